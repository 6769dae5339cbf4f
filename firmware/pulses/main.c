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
 * The serial port is polled, not interrupt-driven, so nothing but the pulse
 * interrupt can delay an edge (with bidirectional DShot, where no pulse
 * interrupt runs, its receive interrupt fills a ring instead: decoding the
 * replies takes longer than the UART's two bytes last).
 *
 * With DShot (CONFIG's protocol: 150, 300 or 600) the same states hold with
 * DShot frames on D2..D7 instead of pulses: no signal before a
 * configuration, motor stop (0) for a disarmed channel and after the link
 * timeout. The main loop sends the frames (dshot.S, interrupts off for a
 * frame) at the configured rate, and the special commands of a COMMAND
 * frame while every channel is disarmed; no pulse interrupt runs.
 * Bidirectional DShot (CONFIG's protocol bit) inverts the frames (idle
 * high) and reads every ESC's eRPM reply after each one (dshot_reply.c),
 * sent to the host in TELEMETRY frames. */
#include <avr/eeprom.h>
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/wdt.h>
#include <stdint.h>
#include <string.h>

#include "dshot_reply.h"
#include "motormix_link.h"
#include "pulse_schedule.h"
#include "pulse_timing.h"
#include "serial.h"

#if F_CPU != 16000000UL
#error "the pulse timing is for 16 MHz (Timer1 at clk/8: 2 ticks per microsecond)"
#endif
#define REPORT_EVERY_TICKS 100000UL /* 50 ms */

/* ---- shared with the pulse interrupt (pulse_isr.S) ---- */
typedef struct {
  uint8_t port_d;
  uint8_t port_b;
  uint16_t next_compare;
  uint8_t flags;
} mm_isr_edge;
mm_isr_edge mm_isr_rise;
mm_isr_edge mm_isr_active[MM_LINK_MAX_CHANNELS];
mm_isr_edge* volatile mm_isr_next;
void mm_isr_period_start(void);

/* ---- the period, owned by the interrupt once it runs ---- */
static uint16_t g_period_ticks;
static uint16_t g_rise_at; /* tick of the rise just written */
static volatile uint8_t g_periods;
static mm_schedule g_disarmed;
/* Schedules from PULSES frames, triple-buffered: each period starts on the
 * newest complete one (g_ready); the main loop writes into the one that is
 * neither that nor the one the interrupt is using, then names it ready (one
 * byte: atomic). A frame taken while a period starts is in the next one.
 * (With two buffers and a "writing" flag, the interrupt kept the old
 * schedule whenever a period started during a write, and the next frame
 * went into the same buffer again: host frames in step with the period
 * held the pins on one frame for tens of milliseconds.) */
#define FRAME_BUFFERS 3u
static mm_schedule g_frame[FRAME_BUFFERS];
static uint8_t g_frame_armed[FRAME_BUFFERS];
static volatile uint8_t g_ready, g_current;
static volatile uint8_t g_link_ok; /* 0: disarmed pulses, whatever the frames said */
static volatile uint8_t g_out_armed;

/* ---- DShot (CONFIG's protocol), frames sent by the main loop ---- */
void mm_dshot_send600(const uint8_t* ports, uint8_t high, uint8_t low);
void mm_dshot_send300(const uint8_t* ports, uint8_t high, uint8_t low);
void mm_dshot_send150(const uint8_t* ports, uint8_t high, uint8_t low);
#define DSHOT_MIN_THROTTLE 48u
#define DSHOT_THROTTLE_STEPS 1999u /* 48..2047 */
static uint8_t g_dshot;            /* 0: servo pulses; else MM_LINK_PROTOCOL_DSHOT* */
static uint8_t g_bidir;            /* bidirectional: inverted frames, eRPM replies */
static uint16_t g_dshot_throttle[MM_LINK_MAX_DSHOT_CHANNELS];
static uint8_t g_dshot_armed; /* channels armed by the last PULSES frame */
static uint8_t g_dshot_ports[16], g_dshot_high, g_dshot_low;
static uint8_t g_dshot_dirty; /* the frame's port values are to be made again */
static uint8_t g_cmd, g_cmd_channels, g_cmd_left;
/* KISS telemetry: the channel (+1; 0 none) whose next frame asks its ESC,
 * and whether the frame prepared last carries that request (the frames
 * after it are made again without). */
static uint8_t g_tlm_ask, g_tlm_in_frame;
static uint32_t g_next_frame;
static uint8_t g_dshot_pins; /* port D bits of the DShot channels */
/* Replies: the last frame's are yet to be decoded, the readings waiting to
 * go to the host, the frame counter. */
static uint8_t g_replies_waiting;
static mm_link_telemetry g_tlm;
static uint16_t g_frame_count;
static uint8_t g_tlm_send_at, g_tlm_seq;

/* ---- main loop state ---- */
static mm_link_config g_config;
static uint8_t g_configured;
static mm_link_parser g_parser;
static mm_link_report g_report;
/* The session frames must name, and the last sequence taken in it. */
static uint32_t g_session;
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

#define WATCHDOG_COUNT_ADDRESS ((uint16_t*)0)
/* The highest session base used (a multiple of 2^16): each reset starts
 * above it, so no session number ever comes back. */
#define SESSION_BASE_ADDRESS ((uint32_t*)4)
#define SESSION_BASE_STEP 0x10000UL

/* A session above every one used before: the next base, written down
 * before it is used. */
static void start_sessions(void) {
  uint32_t base = eeprom_read_dword(SESSION_BASE_ADDRESS);
  if (base == 0xFFFFFFFFUL) base = 0; /* a fresh EEPROM */
  base += SESSION_BASE_STEP;
  eeprom_update_dword(SESSION_BASE_ADDRESS, base);
  g_session = base + 1u;
}

/* The next session (after a link timeout); past a base's 2^16 numbers the
 * next base is written down first. */
static void next_session(void) {
  ++g_session;
  if ((g_session & (SESSION_BASE_STEP - 1u)) == 0u) {
    eeprom_update_dword(SESSION_BASE_ADDRESS, g_session);
    ++g_session;
  }
  g_report.last_sequence = 0;
}

void mm_isr_period_start(void) {
  g_rise_at = (uint16_t)(g_rise_at + g_period_ticks);
  ++g_periods;
  g_current = g_ready;
  const uint8_t armed_frame = g_link_ok && g_frame_armed[g_current];
  const mm_schedule* s = g_link_ok ? &g_frame[g_current] : &g_disarmed;
  g_out_armed = armed_frame;
  const uint16_t start = g_rise_at;
  for (uint8_t k = 0; k < s->n; ++k) {
    mm_isr_edge* e = &mm_isr_active[k];
    e->port_d = s->fall[k].port_d;
    e->port_b = s->fall[k].port_b;
    if (k + 1u < s->n) {
      const mm_fall* next = &s->fall[k + 1u];
      e->next_compare =
          (uint16_t)(start + next->at - (next->polled ? 0u : (uint16_t)MM_ENTRY_LEAD_TICKS));
      e->flags = next->polled ? (uint8_t)(1u << MM_EDGE_NEXT_POLLED) : 0u;
    } else {
      e->next_compare = (uint16_t)(start + g_period_ticks - MM_ENTRY_LEAD_TICKS);
      e->flags = (uint8_t)(1u << MM_EDGE_NEXT_RISE);
    }
  }
  OCR1A = (uint16_t)(start + s->fall[0].at - MM_ENTRY_LEAD_TICKS);
  /* The interrupt wrote the rise's (meaningless) next compare before
   * calling here; a match of it in between must not fire the first fall
   * early. The first fall is at least 500 us away, so no real match is lost. */
  TIFR1 = _BV(OCF1A);
  mm_isr_next = &mm_isr_active[0];
}

/* A 32-bit tick clock from Timer1, extended here: the loop runs far more
 * often than the timer wraps (32.8 ms). */
static uint32_t now_ticks(void) {
  const uint16_t t = TCNT1;
  if (t < g_last_tcnt) g_now_high += 0x10000UL;
  g_last_tcnt = t;
  return g_now_high | t;
}

static void pins_low(void) {
  uint8_t d, b;
  mm_rise_ports(MM_LINK_MAX_CHANNELS, &d, &b);
  PORTD = (uint8_t)(PORTD & ~d);
  PORTB = (uint8_t)(PORTB & ~b);
}

static void stop_pulses(void) {
  TIMSK1 = 0;
  TIFR1 = _BV(OCF1A);
  pins_low();
}

static void apply_config(const mm_link_config* c) {
  stop_pulses();
  /* Polled unless bidirectional (a frame being sent is finished by the loop). */
  mm_serial_interrupts(0);
  mm_serial_read(&g_parser);
  g_config = *c;
  g_period_ticks = (uint16_t)(c->period_us * MM_TICKS_PER_US);
  /* Disarmed pulses start within the timeout of the last frame: the link
   * is called lost one period before the timeout. */
  const uint32_t timeout_ticks = (uint32_t)c->link_timeout_ms * 1000UL * MM_TICKS_PER_US;
  g_timeout_ticks_high = (uint16_t)((timeout_ticks - g_period_ticks) >> 8);
  g_dshot = (uint8_t)(c->protocol & MM_LINK_PROTOCOL_SPEED_MASK);
  g_bidir = (c->protocol & MM_LINK_PROTOCOL_BIDIRECTIONAL) != 0u;
  if (g_dshot) {
    /* Frames of motor stop from the next one on; no pulse interrupt. */
    g_dshot_armed = 0;
    g_cmd_left = 0;
    g_tlm_ask = 0;
    g_link_ok = 0;
    g_out_armed = 0;
    for (uint8_t k = 0; k < FRAME_BUFFERS; ++k) g_frame_armed[k] = 0;
    g_dshot_dirty = 1;
    g_dshot_pins = 0;
    for (uint8_t k = 0; k < c->count; ++k) {
      uint8_t d, b;
      mm_channel_bits(k, &d, &b);
      g_dshot_pins = (uint8_t)(g_dshot_pins | d);
    }
    /* Bidirectional: the lines idle high, which tells the ESCs to answer;
     * the UART read by its interrupt while the replies are decoded. */
    if (g_bidir) {
      PORTD = (uint8_t)(PORTD | g_dshot_pins);
      mm_serial_interrupts(1);
    }
    g_replies_waiting = 0;
    g_tlm.readings = 0;
    g_tlm.count = c->count;
    /* Replies go in batches of about 3 ms of frames: at 1 kHz a TELEMETRY
     * frame of three readings (37 bytes) every 3 ms fills half the wire and
     * costs the chip less than smaller ones; two more fit while a report
     * (1.6 ms) holds the wire. */
    g_tlm_send_at = (uint8_t)(c->period_us >= 3000u ? 1u : c->period_us >= 1500u ? 2u : 3u);
    g_next_frame = now_ticks();
    g_configured = 1;
    return;
  }
  uint16_t ticks[MM_LINK_MAX_CHANNELS];
  for (uint8_t k = 0; k < c->count; ++k) ticks[k] = (uint16_t)(c->disarmed_us[k] * MM_TICKS_PER_US);
  mm_schedule_build(ticks, c->count, &g_disarmed);
  for (uint8_t k = 0; k < FRAME_BUFFERS; ++k) {
    g_frame[k] = g_disarmed;
    g_frame_armed[k] = 0;
  }
  g_ready = g_current = 0;
  g_link_ok = 0;
  g_out_armed = 0;
  mm_rise_ports(c->count, &mm_isr_rise.port_d, &mm_isr_rise.port_b);
  mm_isr_rise.flags = (uint8_t)(1u << MM_EDGE_RISE);
  /* The rise's next compare is never used: mm_isr_period_start sets the
   * first fall's compare itself. */
  mm_isr_rise.next_compare = 0;
  mm_isr_next = &mm_isr_rise;
  /* The first rise a little ahead; the interrupt takes it from there. */
  g_rise_at = (uint16_t)(TCNT1 + 400u - g_period_ticks);
  OCR1A = (uint16_t)(g_rise_at + g_period_ticks - MM_ENTRY_LEAD_TICKS);
  TIFR1 = _BV(OCF1A);
  TIMSK1 = _BV(OCIE1A);
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

/* A DShot frame's 16 bits: throttle (11), telemetry request, checksum
 * (inverted for bidirectional DShot, which is how an ESC tells the two). */
static uint16_t dshot_packet(uint16_t value, uint8_t telemetry) {
  const uint16_t v = (uint16_t)((value << 1) | telemetry);
  uint16_t sum = (uint16_t)(v ^ (v >> 4) ^ (v >> 8));
  if (g_bidir) sum = (uint16_t)~sum;
  return (uint16_t)((v << 4) | (sum & 0x0Fu));
}

/* The port values of the next frame: the throttle of each armed channel
 * while the link holds, a special command on its channels while one is
 * being sent, motor stop (0) otherwise. */
static void dshot_prepare(void) {
  /* A channel at a time, its packet kept in registers and shifted out a
   * bit at a time into the 16 port values (a 16-bit mask per bit and
   * channel took 2400 cycles a frame, longer than a DShot300 frame). DShot
   * channels are D2.. in channel order. */
  uint8_t* const ports = g_dshot_ports;
  for (uint8_t i = 0; i < 16u; ++i) ports[i] = 0;
  const uint8_t all = g_dshot_pins;
  const uint8_t armed = g_link_ok ? g_dshot_armed : 0u;
  uint8_t pin = 4u; /* D2 */
  /* Taken once the frame is sent (a newer PULSES frame may make this one
   * again first). */
  const uint8_t ask = g_tlm_ask;
  g_tlm_in_frame = ask;
  for (uint8_t k = 0; k < g_config.count; ++k, pin = (uint8_t)(pin << 1)) {
    uint16_t packet;
    const uint8_t asked = (uint8_t)(ask == (uint8_t)(k + 1u));
    if ((armed >> k) & 1u) {
      packet = dshot_packet(g_dshot_throttle[k], asked);
    } else if (g_cmd_left && ((g_cmd_channels >> k) & 1u)) {
      packet = dshot_packet(g_cmd, 1); /* ESCs take commands with the bit set */
    } else {
      packet = dshot_packet(0, asked); /* motor stop; telemetry on the ground too */
    }
    uint8_t* p = ports;
    for (uint8_t i = 16u; i != 0u; --i, ++p, packet = (uint16_t)(packet << 1))
      if (packet & 0x8000u) *p |= pin;
  }
  const uint8_t base = (uint8_t)(PORTD & ~all);
  /* Inverted (bidirectional): a bit is low for its high time. */
  const uint8_t flip = g_bidir ? all : 0u;
  for (uint8_t i = 0; i < 16u; ++i) ports[i] = (uint8_t)(base | (ports[i] ^ flip));
  g_dshot_high = g_bidir ? base : (uint8_t)(base | all);
  g_dshot_low = g_bidir ? (uint8_t)(base | all) : base;
  g_out_armed = armed != 0u;
  g_dshot_dirty = 0;
}

static void dshot_send(void) {
  if (g_bidir) {
    /* The window right after the frame, interrupts off throughout (the
     * sender restores them as they were). The main loop decodes the last
     * frame's replies before it sends another frame, so none is sampled
     * over. */
    const uint8_t sreg = SREG;
    cli();
    if (g_dshot == MM_LINK_PROTOCOL_DSHOT600) {
      mm_dshot_send600(g_dshot_ports, g_dshot_high, g_dshot_low);
    } else {
      mm_dshot_send300(g_dshot_ports, g_dshot_high, g_dshot_low);
    }
    mm_reply_capture(g_dshot, g_dshot_pins, mm_serial_take, mm_serial_put);
    SREG = sreg;
    g_replies_waiting = 1;
  } else if (g_dshot == MM_LINK_PROTOCOL_DSHOT600) {
    mm_dshot_send600(g_dshot_ports, g_dshot_high, g_dshot_low);
  } else if (g_dshot == MM_LINK_PROTOCOL_DSHOT300) {
    mm_dshot_send300(g_dshot_ports, g_dshot_high, g_dshot_low);
  } else {
    mm_dshot_send150(g_dshot_ports, g_dshot_high, g_dshot_low);
  }
  ++g_frame_count;
  ++g_periods; /* the watchdog's sign of life, as a pulse period is */
  if (g_cmd_left && --g_cmd_left == 0u) g_dshot_dirty = 1;
  if (g_tlm_in_frame) { /* asked once: the next frame without */
    g_tlm_ask = 0;
    g_tlm_in_frame = 0;
    g_dshot_dirty = 1;
  }
}

/* Every channel's reply of the last frame, as one reading in the batch for
 * the host (the oldest dropped if the batch is full, which the host sees as
 * a gap in the frame counter). */
static void decode_replies(void) {
  if (g_tlm.readings == MM_LINK_TELEMETRY_MAX_READINGS) {
    for (uint8_t r = 1; r < MM_LINK_TELEMETRY_MAX_READINGS; ++r)
      memcpy(g_tlm.period_us[r - 1u], g_tlm.period_us[r], sizeof g_tlm.period_us[r]);
    --g_tlm.readings;
    ++g_tlm.first;
  }
  if (g_tlm.readings == 0u) g_tlm.first = (uint16_t)(g_frame_count - 1u);
  for (uint8_t ch = 0; ch < g_config.count; ++ch)
    g_tlm.period_us[g_tlm.readings][ch] = mm_reply_decode(ch);
  ++g_tlm.readings;
  g_replies_waiting = 0;
}

/* A PULSES frame's bookkeeping once taken. */
static void taken(uint32_t sequence, uint32_t now) {
  g_report.last_sequence = sequence;
  ++g_report.frames;
  g_deadline = now + ((uint32_t)g_timeout_ticks_high << 8);
  g_link_ok = 1;
}

/* num / span for a quotient below 2048 (a throttle step), by long
 * division on its 11 bits: a third of the cycles of the library's 32-bit
 * division, four times a frame. */
static uint16_t steps(uint32_t num, uint16_t span) {
  uint32_t d = (uint32_t)span << 10;
  uint16_t q = 0;
  for (uint16_t bit = 1u << 10; bit != 0u; bit >>= 1) {
    if (num >= d) {
      num -= d;
      q |= bit;
    }
    d >>= 1;
  }
  return q;
}

static void take_pulses(const mm_link_pulses* p, uint32_t now) {
  if (!current(p->session, p->sequence)) return;
  if (!g_configured || p->count != g_config.count) {
    ++g_report.rejected; /* before a configuration, wrong count */
    return;
  }
  uint16_t ticks[MM_LINK_MAX_CHANNELS];
  const uint16_t lo = (uint16_t)(g_config.min_us * MM_TICKS_PER_US);
  const uint16_t hi = (uint16_t)(g_config.max_us * MM_TICKS_PER_US);
  if (g_dshot) {
    /* [min, max] onto 48..2047, rounded; the width's half microseconds
     * are finer than a throttle step at any range above 500 us. */
    const uint32_t span = (uint32_t)(hi - lo);
    for (uint8_t k = 0; k < p->count; ++k) {
      uint16_t t = p->pulse_hus[k];
      if (t < lo) t = lo;
      if (t > hi) t = hi;
      g_dshot_throttle[k] =
          (uint16_t)(DSHOT_MIN_THROTTLE +
                     steps((uint32_t)(t - lo) * DSHOT_THROTTLE_STEPS + span / 2u, (uint16_t)span));
    }
    g_dshot_armed = p->armed;
    if (p->telemetry != 0u) g_tlm_ask = p->telemetry;
    if (p->armed) g_cmd_left = 0; /* arming ends a special command */
    g_dshot_dirty = 1;
    taken(p->sequence, now);
    return;
  }
  for (uint8_t k = 0; k < p->count; ++k) {
    const uint8_t armed = (uint8_t)(((unsigned)p->armed >> k) & 1u);
    uint16_t t = armed ? p->pulse_hus[k] : (uint16_t)(g_config.disarmed_us[k] * MM_TICKS_PER_US);
    if (armed && t < lo) t = lo;
    if (armed && t > hi) t = hi;
    ticks[k] = t;
  }
  /* Only this loop moves g_ready; the interrupt moves g_current to it at
   * most, so a buffer that is neither stays free until named ready. */
  const uint8_t ready = g_ready;
  const uint8_t in_use = g_current;
  uint8_t w = 0;
  while (w == ready || w == in_use) ++w;
  mm_schedule_build(ticks, p->count, &g_frame[w]);
  g_frame_armed[w] = p->armed != 0u; /* any channel: no configuration meanwhile */
  g_ready = w;
  taken(p->sequence, now);
}

/* A DShot special command: only while every output is disarmed. */
static void take_command(const mm_link_command* c) {
  if (!current(c->session, c->sequence)) return;
  g_report.last_sequence = c->sequence;
  if (!g_configured || !g_dshot || g_out_armed || (g_link_ok && g_dshot_armed) ||
      (c->channels >> g_config.count) != 0u) {
    ++g_report.rejected;
    return;
  }
  g_cmd = c->command;
  g_cmd_channels = c->channels;
  g_cmd_left = c->repeat;
  g_dshot_dirty = 1;
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
    /* Never while the motors may be turning: armed pulses now, or an armed
     * frame taken that the next period will start. */
    if (g_configured &&
        (g_out_armed || (g_link_ok && (g_frame_armed[g_ready] || (g_dshot && g_dshot_armed))))) {
      ++g_report.rejected;
      return;
    }
    apply_config(&f->u.config);
  }
}

/* On a fixed schedule: a frame sent late (the loop was busy: a burst of
 * bytes, the replies) shortens the next gap, so the rate holds on average;
 * only more than four periods behind does the schedule start again from
 * now. True when a frame is to go now (the schedule then moved on). */
static uint8_t frame_due(uint32_t now) {
  if ((int32_t)(now - g_next_frame) < 0) return 0;
  g_next_frame += g_period_ticks;
  if ((int32_t)(now - g_next_frame) >= (int32_t)(4u * (uint32_t)g_period_ticks))
    g_next_frame = now + g_period_ticks;
  return 1;
}

/* Up to `steps` bytes of the search; a frame taken ends it (a PULSES frame
 * is to be prepared). */
static void search(uint32_t now, uint8_t steps) {
  do {
    mm_link_frame frame;
    const uint8_t type = mm_link_poll(&g_parser, &frame);
    if (type) {
      take_frame(type, &frame, now);
      return;
    }
  } while (--steps && mm_link_pending(&g_parser));
}

/* The host's bytes with bidirectional DShot, up to SEARCH_STEPS of them:
 * those to be searched again after a bad frame first, then the ring's,
 * each straight into the parser. A frame taken ends it (a PULSES frame is
 * to be prepared). */
#define SEARCH_STEPS 24u /* some 200 us: a frame due waits no longer */
static void bidir_bytes(uint32_t now) {
  uint8_t steps = SEARCH_STEPS;
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
 * values, then the host's bytes; and one turn of bytes at least between
 * two frames. Bytes last: with the wire full (a byte every 40 us) a byte a
 * turn, before everything else, left no turn for the replies, no frame
 * went, and the hardware watchdog reset the chip. A turn of bytes owed:
 * frames due back to back (a rate the chip cannot hold) would leave none
 * for the host, whose frames would stop and the link time out. */
static uint8_t g_bytes_owed;
static void bidir_turn(uint32_t now) {
  if (!g_dshot_dirty && !g_replies_waiting && !g_bytes_owed && frame_due(now)) {
    dshot_send();
  } else if (g_replies_waiting) {
    decode_replies();
    g_bytes_owed = 1;
  } else if (g_dshot_dirty) {
    dshot_prepare();
  } else {
    bidir_bytes(now);
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
  uint16_t resets = eeprom_read_word(WATCHDOG_COUNT_ADDRESS);
  if (resets == 0xFFFFu) resets = 0; /* a fresh EEPROM */
  if (g_mcusr & _BV(WDRF)) eeprom_update_word(WATCHDOG_COUNT_ADDRESS, ++resets);
  g_report.watchdog_resets = resets;
  start_sessions();

  uint8_t d, b;
  mm_rise_ports(MM_LINK_MAX_CHANNELS, &d, &b);
  pins_low();
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
    const uint32_t now = now_ticks();
    if (g_bidir) {
      bidir_turn(now);
    } else if (mm_serial_waiting()) {
      /* A received byte first, else one step of the search: a step takes a
       * few microseconds, a byte 40, so the UART's two-byte buffer never
       * overruns, even while the parser searches again after a bad frame. */
      mm_serial_read(&g_parser);
    } else if (g_dshot && g_configured && !g_dshot_dirty && frame_due(now)) {
      /* A DShot frame right after a look at the UART: its 27-107 us with
       * interrupts off fit in the three bytes the UART holds. */
      dshot_send();
    } else if (g_dshot && g_dshot_dirty) {
      dshot_prepare();
    } else if (mm_link_pending(&g_parser)) {
      /* Bytes of the search: a step takes some 7 us and a turn of this
       * loop as much; three steps between two looks at the UART (a byte
       * comes every 40 us, the UART holds two): after a bad frame the
       * search goes over its bytes again, and at the wire's full rate one
       * step a turn fell behind. */
      search(now, 3u);
    }
    if (g_link_ok && (int32_t)(now - g_deadline) >= 0) {
      g_link_ok = 0;
      g_dshot_dirty = 1; /* DShot: motor stop from the next frame */
      /* Whatever was sent before this is never taken: a new session, told
       * to the host at once. */
      next_session();
      ++g_report.link_timeouts;
      if (!mm_serial_sending()) g_next_report = now;
    }
    if (mm_serial_sending()) {
      mm_serial_poll_send();
    } else if (g_bidir && g_tlm.readings >= g_tlm_send_at) {
      /* A batch of replies before a report: a batch held behind a report
       * (1.6 ms on the wire) and the next batch would overflow, a report
       * waits a batch at most. */
      mm_serial_send((uint8_t)mm_link_encode_telemetry(&g_tlm, g_tlm_seq++, mm_serial_frame()));
      g_tlm.readings = 0;
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
