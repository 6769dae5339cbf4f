/* Reads an LCM log with decoders lcm-gen generated for C, as an existing C
 * consumer of motormix's messages would: prints, per event on the team
 * quad's channels, how many bytes the decoder read and the fields that say
 * which message it was. Run on a log and on the same log signed, the two
 * printouts must be equal: the decoders never read the signature trailer.
 *   decode_log LOG */
#include <lcm/lcm.h>

#include "motormix_mixer_status_t.h"
#include "motormix_motor_pwm_t.h"
#include "motormix_pid_t.h"
#include "motormix_setpoint_t.h"

#include <stdio.h>
#include <string.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: decode_log LOG\n");
    return 2;
  }
  lcm_eventlog_t* log = lcm_eventlog_create(argv[1], "r");
  if (!log) {
    fprintf(stderr, "decode_log: cannot read %s\n", argv[1]);
    return 1;
  }
  long events = 0;
  int failed = 0;
  lcm_eventlog_event_t* ev;
  while ((ev = lcm_eventlog_read_next_event(log)) != NULL) {
    int n = -1;
    if (strcmp(ev->channel, "pos_deseada") == 0) {
      motormix_setpoint_t m;
      n = motormix_setpoint_t_decode(ev->data, 0, (int)ev->datalen, &m);
      if (n >= 0) printf("setpoint %d %lld %d %.6f\n", n, (long long)m.utime, m.armed, m.throttle);
    } else if (strcmp(ev->channel, "pid") == 0) {
      motormix_pid_t m;
      n = motormix_pid_t_decode(ev->data, 0, (int)ev->datalen, &m);
      if (n >= 0) printf("pid %d %lld %.6f %.6f\n", n, (long long)m.utime, m.roll, m.pitch);
    } else if (strcmp(ev->channel, "motor_pwm") == 0) {
      motormix_motor_pwm_t m;
      n = motormix_motor_pwm_t_decode(ev->data, 0, (int)ev->datalen, &m);
      if (n >= 0) {
        printf("motor_pwm %d %lld %d", n, (long long)m.utime, m.armed);
        for (int i = 0; i < m.num_motors; ++i) printf(" %.3f", m.pwm[i]);
        printf("\n");
        motormix_motor_pwm_t_decode_cleanup(&m);
      }
    } else if (strcmp(ev->channel, "MIXER_STATUS") == 0) {
      motormix_mixer_status_t m;
      n = motormix_mixer_status_t_decode(ev->data, 0, (int)ev->datalen, &m);
      if (n >= 0)
        printf("status %d %lld %d %lld\n", n, (long long)m.utime, m.state, (long long)m.cycles);
    } else {
      lcm_eventlog_free_event(ev);
      continue;
    }
    ++events;
    if (n < 0) {
      fprintf(stderr, "decode_log: event %lld on %s does not decode\n", (long long)ev->eventnum,
              ev->channel);
      failed = 1;
    }
    lcm_eventlog_free_event(ev);
  }
  lcm_eventlog_destroy(log);
  fprintf(stderr, "decode_log: %ld events decoded\n", events);
  return failed || events == 0;
}
