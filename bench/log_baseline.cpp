// The floor for `motormix replay`: LCM's own C log API reading a log and
// writing the same number of events the replay writes (every input event,
// plus `extra` events of `size` bytes, spread evenly between them), with
// nothing computed. EVENTS is the number of events in IN (to spread the
// extra ones evenly without reading the log twice). Prints the wall time in
// milliseconds.
//
//   log_baseline IN.lcmlog OUT.lcmlog EVENTS EXTRA SIZE

#include <lcm/lcm.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: log_baseline IN.lcmlog OUT.lcmlog EVENTS EXTRA SIZE\n");
    return 2;
  }
  const long inputs = std::max(1L, std::atol(argv[3]));
  const long extra = std::atol(argv[4]);
  std::vector<std::uint8_t> payload(static_cast<std::size_t>(std::atol(argv[5])), 0x5A);
  const auto t0 = std::chrono::steady_clock::now();
  lcm_eventlog_t* in = lcm_eventlog_create(argv[1], "r");
  lcm_eventlog_t* out = lcm_eventlog_create(argv[2], "w");
  if (in == nullptr || out == nullptr) {
    std::fprintf(stderr, "log_baseline: cannot open the logs\n");
    return 1;
  }
  char channel[] = "MOTOR_PWM";
  long written_extra = 0;
  long k = 0;
  while (lcm_eventlog_event_t* ev = lcm_eventlog_read_next_event(in)) {
    lcm_eventlog_write_event(out, ev);
    ++k;
    while (written_extra * inputs < extra * k) {
      lcm_eventlog_event_t e{};
      e.timestamp = ev->timestamp;
      e.channellen = sizeof channel - 1;
      e.datalen = static_cast<int32_t>(payload.size());
      e.channel = channel;
      e.data = payload.data();
      lcm_eventlog_write_event(out, &e);
      ++written_extra;
    }
    lcm_eventlog_free_event(ev);
  }
  lcm_eventlog_destroy(in);
  lcm_eventlog_destroy(out);
  const auto t1 = std::chrono::steady_clock::now();
  std::printf("%.3f\n", std::chrono::duration<double, std::milli>(t1 - t0).count());
  return 0;
}
