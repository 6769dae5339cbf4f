/* motormix pulse firmware for the ATmega328P (Arduino Uno, Nano) at 16 MHz:
 * servo-style ESC pulses on up to eight pins (D2..D9), set by frames from
 * `motormix output` over the serial port (250000 baud, src/link), with a
 * link watchdog of its own and the hardware watchdog.
 *
 * Safe states, in order:
 * - at power-up and after any reset, no pulse at all until the host sends a
 *   configuration (an ESC without a signal does not start);
 * - configured, disarmed pulses until a valid, newer PULSES frame of the
 *   current session says armed (src/link: a frame recorded before a link
 *   timeout or a reset is never taken again);
 * - when no valid PULSES frame has come for the configured link timeout,
 *   disarmed pulses again, the first of them starting within the timeout of
 *   the last frame (the host died, was killed, or the cable came out);
 * - if the main loop or the pulse interrupt stops, the hardware watchdog
 *   resets the chip within 60 ms: no pulse at all, as at power-up.
 * The serial port's receive interrupt fills a ring (serial.h: the chip's
 * receiver holds two bytes and a third in its shift register, far less
 * than this loop's longest turn); the pulse interrupt is entered early
 * enough to let it run and still write each edge on its tick.
 *
 * With DShot (CONFIG's protocol: 150, 300 or 600) the same states hold with
 * DShot frames on D2..D7 instead of pulses: no signal before a
 * configuration, motor stop (0) for a disarmed channel and after the link
 * timeout. The main loop sends the frames (dshot.S, interrupts off for a
 * frame) at the configured rate, and the special commands of a COMMAND
 * frame while every channel is disarmed; no pulse interrupt runs.
 * Bidirectional DShot (CONFIG's protocol bit) inverts the frames (idle
 * high) and reads every ESC's eRPM reply after each one (dshot_reply.c),
 * sent to the host in TELEMETRY frames.
 *
 * Units: servo_pulses.c (the pulses and their interrupt), dshot_out.c
 * (DShot frames, commands, replies), sessions.c (EEPROM: sessions and the
 * watchdog's count), serial.c (the UART); this file takes the host's
 * frames and runs the loop. */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/wdt.h>
#include <stdint.h>
#include <string.h>

#include "dshot_out.h"
#include "firmware_state.h"
#include "motormix_link.h"
#include "pulse_schedule.h"
#include "pulse_timing.h"
#include "serial.h"
#include "servo_pulses.h"
#include "sessions.h"

#if F_CPU != 16000000UL
#error "the pulse timing is for 16 MHz (Timer1 at clk/8: 2 ticks per microsecond)"
#endif
#define REPORT_EVERY_TICKS 100000UL /* 50 ms */

/* ---- shared with the other units (firmware_state.h) ---- */
mm_link_config g_config;
uint8_t g_configured;
mm_link_report g_report;
uint16_t g_period_ticks;
volatile uint8_t g_periods;
volatile uint8_t g_link_ok;
volatile uint8_t g_out_armed;

/* ---- main loop state ---- */
static mm_link_parser g_parser;
static uint32_t g_now_high, g_deadline, g_next_report;
static uint16_t g_last_tcnt;
static uint16_t g_timeout_ticks_high; /* link timeout - one period, in ticks >> 8 */
static uint8_t g_report_seq;

/* Reset cause, saved before anything else runs (the watchdog stays on
 * after a watchdog reset and must be stopped at once). */
static uint8_t g_mcusr __attribute__((section(".noinit")));
void early_init(void) __attribute__((naked, used, section(".init3")));
void early_init(void) {
  g_mcusr = MCUSR;
  MCUSR = 0;
  wdt_disable();
}

/* A 32-bit tick clock from Timer1, extended here: the loop runs far more
 * often than the timer wraps (32.8 ms). */
uint32_t mm_now_ticks(void) {
  /* Interrupts off for the two byte reads: the timer's 16-bit registers
   * share one high-byte latch, and the pulse interrupt's write of OCR1A
   * between them would hand this read its compare's high byte (a clock
   * leap of up to 32.8 ms, a link timeout called early). */
  const uint8_t sreg = SREG;
  cli();
  const uint16_t t = TCNT1;
  SREG = sreg;
  if (t < g_last_tcnt) g_now_high += 0x10000UL;
  g_last_tcnt = t;
  return g_now_high | t;
}

static void apply_config(const mm_link_config* c) {
  mm_pulses_stop();
  /* Sent by the loop unless bidirectional (which turns the interrupt on). */
  mm_serial_send_interrupt(0);
  g_config = *c;
  g_period_ticks = (uint16_t)(c->period_us * MM_TICKS_PER_US);
  /* Disarmed outputs start within the timeout of the last frame: the link
   * is called lost one period before the timeout. */
  const uint32_t timeout_ticks = (uint32_t)c->link_timeout_ms * 1000UL * MM_TICKS_PER_US;
  g_timeout_ticks_high = (uint16_t)((timeout_ticks - g_period_ticks) >> 8);
  g_dshot = (uint8_t)(c->protocol & MM_LINK_PROTOCOL_SPEED_MASK);
  g_bidir = (c->protocol & MM_LINK_PROTOCOL_BIDIRECTIONAL) != 0u;
  g_link_ok = 0;
  g_out_armed = 0;
  if (g_dshot) {
    /* Frames of motor stop from the next one on; no pulse interrupt. */
    mm_pulses_forget_armed();
    mm_dshot_start(c);
  } else {
    mm_pulses_start(c);
  }
  g_configured = 1;
}

static uint8_t same_config(const mm_link_config* a, const mm_link_config* b) {
  if (a->period_us != b->period_us || a->link_timeout_ms != b->link_timeout_ms ||
      a->min_us != b->min_us || a->max_us != b->max_us || a->count != b->count ||
      a->protocol != b->protocol)
    return 0;
  return memcmp(a->disarmed_us, b->disarmed_us, sizeof a->disarmed_us[0] * a->count) == 0;
}

/* For this session, newer than every frame taken in it and at most
 * MM_LINK_MAX_SEQUENCE_STEP beyond the last; else counted. */
static uint8_t current(uint32_t session, uint32_t sequence) {
  const uint32_t step = sequence - g_report.last_sequence; /* 0 or wrapped: not newer */
  if (session != g_session || step == 0u || step > MM_LINK_MAX_SEQUENCE_STEP) {
    ++g_report.rejected;
    return 0;
  }
  return 1;
}

static void take_pulses(const mm_link_pulses* p, uint32_t now) {
  if (!current(p->session, p->sequence)) return;
  if (!g_configured || p->count != g_config.count) {
    ++g_report.rejected; /* before a configuration, wrong count */
    return;
  }
  const uint16_t lo = (uint16_t)(g_config.min_us * MM_TICKS_PER_US);
  const uint16_t hi = (uint16_t)(g_config.max_us * MM_TICKS_PER_US);
  if (g_dshot) {
    mm_dshot_take(p, lo, hi);
  } else {
    mm_pulses_take(p, lo, hi);
  }
  /* Taken: the link holds until the timeout from now. */
  g_report.last_sequence = p->sequence;
  ++g_report.frames;
  g_deadline = now + ((uint32_t)g_timeout_ticks_high << 8);
  g_link_ok = 1;
}

/* A DShot special command: only while every output is disarmed. */
static void take_command(const mm_link_command* c) {
  if (!current(c->session, c->sequence)) return;
  g_report.last_sequence = c->sequence;
  if (!mm_dshot_take_command(c)) ++g_report.rejected;
}

static void take_frame(uint8_t type, const mm_link_frame* f, uint32_t now) {
  if (type == MM_LINK_PULSES) {
    take_pulses(&f->u.pulses, now);
  } else if (type == MM_LINK_COMMAND) {
    take_command(&f->u.command);
  } else if (type == MM_LINK_CONFIG) {
    if (!current(f->u.config.session, f->u.config.sequence)) return;
    g_report.last_sequence = f->u.config.sequence;
    if (g_configured && same_config(&f->u.config, &g_config)) return;
    /* Never while the motors may be turning: armed outputs now, or an armed
     * frame taken that the next period will start. */
    if (g_configured && (g_out_armed || (g_link_ok && (mm_pulses_armed_pending() ||
                                                       (g_dshot && mm_dshot_armed()))))) {
      ++g_report.rejected;
      return;
    }
    apply_config(&f->u.config);
  }
}

/* The host's bytes, up to `steps` of them: those to be searched again after
 * a bad frame first, then the ring's, each straight into the parser. A
 * frame taken ends it (a PULSES frame is to be prepared). */
static void host_bytes(uint32_t now, uint8_t steps) {
  do {
    mm_link_frame frame;
    uint8_t type;
    if (mm_link_pending(&g_parser)) {
      type = mm_link_poll(&g_parser, &frame);
    } else if (mm_serial_waiting()) {
      type = mm_link_step(&g_parser, mm_serial_next(&g_parser), &frame);
    } else {
      return;
    }
    if (type) {
      take_frame(type, &frame, now);
      return;
    }
  } while (--steps);
}

/* A turn with bidirectional DShot, where the UART's interrupt fills a ring
 * and a turn may take long: the frame first when it is due (once the last
 * frame's replies are decoded: they would be sampled over, and once a new
 * throttle is in the port values), then those replies, then the port
 * values, then the host's bytes (some 200 us of them at most: a frame due
 * waits no longer); and one turn of bytes at least between two frames.
 * Bytes last: with the wire full (a byte every 40 us) a byte a turn, before
 * everything else, left no turn for the replies, no frame went, and the
 * hardware watchdog reset the chip. A turn of bytes owed: frames due back
 * to back (a rate the chip cannot hold) would leave none for the host,
 * whose frames would stop and the link time out. */
#define SEARCH_STEPS 24u
static uint8_t g_bytes_owed;
static void bidir_turn(uint32_t now) {
  if (!g_dshot_dirty && !g_replies_waiting && !g_bytes_owed && mm_dshot_frame_due(now)) {
    mm_dshot_send();
  } else if (g_replies_waiting) {
    mm_dshot_decode_replies();
    g_bytes_owed = 1;
  } else if (g_dshot_dirty) {
    mm_dshot_prepare();
  } else {
    host_bytes(now, SEARCH_STEPS);
    g_bytes_owed = 0;
  }
}

static void queue_report(void) {
  g_report.crc_errors = g_parser.crc_errors;
  g_report.malformed = g_parser.malformed;
  g_report.flags = (uint8_t)((g_configured ? MM_LINK_FLAG_CONFIGURED : 0u) |
                             (g_out_armed ? MM_LINK_FLAG_ARMED : 0u) |
                             (g_configured && !g_link_ok ? MM_LINK_FLAG_TIMED_OUT : 0u));
  g_report.session = g_session;
  g_report.version = MM_LINK_VERSION;
  mm_serial_send((uint8_t)mm_link_encode_report(&g_report, g_report_seq++, mm_serial_frame()));
}

int main(void) {
  g_report.watchdog_resets = mm_count_resets((g_mcusr & _BV(WDRF)) != 0u);
  mm_sessions_start();

  uint8_t d, b;
  mm_rise_ports(MM_LINK_MAX_CHANNELS, &d, &b);
  mm_pulses_pins_low();
  DDRD |= d;
  DDRB |= b;

  mm_serial_init();

  TCCR1A = 0;
  TCCR1B = _BV(CS11); /* clk/8, normal mode: free-running, compare A drives the edges */
  mm_link_parser_init(&g_parser);
  wdt_enable(WDTO_60MS);
  sei();

  uint8_t seen_periods = g_periods;
  for (;;) {
    const uint32_t now = mm_now_ticks();
    if (g_bidir) {
      bidir_turn(now);
    } else if (g_dshot && g_configured && !g_dshot_dirty && mm_dshot_frame_due(now)) {
      mm_dshot_send();
    } else if (g_dshot && g_dshot_dirty) {
      mm_dshot_prepare();
    } else if (mm_link_pending(&g_parser) || mm_serial_waiting()) {
      /* A few steps of the parser (some 7 us each) a turn, so that a frame
       * due is never held long: a byte comes every 40 us at most. */
      host_bytes(now, 3u);
    }
    if (g_link_ok && (int32_t)(now - g_deadline) >= 0) {
      g_link_ok = 0;
      g_dshot_dirty = 1; /* DShot: motor stop from the next frame */
      /* Whatever was sent before this is never taken: a new session, told
       * to the host at once. */
      mm_sessions_next();
      ++g_report.link_timeouts;
      if (!mm_serial_sending()) g_next_report = now;
    }
    if (mm_serial_sending()) {
      mm_serial_poll_send();
    } else if (g_bidir && mm_dshot_batch_ready()) {
      /* A batch of replies before a report: a batch held behind a report
       * (1.6 ms on the wire) and the next batch would overflow, a report
       * waits a batch at most. */
      mm_dshot_send_batch();
    } else if ((int32_t)(now - g_next_report) >= 0) {
      g_next_report = now + REPORT_EVERY_TICKS;
      queue_report();
    }
    /* The watchdog is fed only while the pulse interrupt is alive too. */
    const uint8_t periods = g_periods;
    if (!g_configured || periods != seen_periods) {
      seen_periods = periods;
      wdt_reset();
    }
  }
}
