#include "dshot_out.h"

#include <avr/interrupt.h>
#include <avr/io.h>
#include <string.h>

#include "dshot_reply.h"
#include "firmware_state.h"
#include "pulse_schedule.h"
#include "serial.h"

void mm_dshot_send600(const uint8_t* ports, uint8_t high, uint8_t low);
void mm_dshot_send300(const uint8_t* ports, uint8_t high, uint8_t low);
uint8_t mm_dshot_send150(const uint8_t* ports, uint8_t high, uint8_t low, uint8_t* uart);
#define DSHOT_MIN_THROTTLE 48u
#define DSHOT_THROTTLE_STEPS 1999u /* 48..2047 */

uint8_t g_dshot;
uint8_t g_bidir;
uint8_t g_dshot_dirty;
uint8_t g_replies_waiting;
static uint16_t g_dshot_throttle[MM_LINK_MAX_DSHOT_CHANNELS];
static uint8_t g_dshot_armed; /* channels armed by the last PULSES frame */
static uint8_t g_dshot_ports[16], g_dshot_high, g_dshot_low;
static uint8_t g_cmd, g_cmd_channels, g_cmd_left;
/* KISS telemetry: the channel (+1; 0 none) whose next frame asks its ESC,
 * and whether the frame prepared last carries that request (the frames
 * after it are made again without). */
static uint8_t g_tlm_ask, g_tlm_in_frame;
static uint32_t g_next_frame;
static uint8_t g_dshot_pins; /* port D bits of the DShot channels */
/* Replies waiting to go to the host, the frame counter. */
static mm_link_telemetry g_tlm;
static uint16_t g_frame_count;
static uint8_t g_tlm_send_at, g_tlm_seq;

uint8_t mm_dshot_armed(void) { return g_dshot_armed; }

void mm_dshot_start(const mm_link_config* c) {
  g_dshot_armed = 0;
  g_cmd_left = 0;
  g_tlm_ask = 0;
  g_dshot_dirty = 1;
  g_dshot_pins = 0;
  for (uint8_t k = 0; k < c->count; ++k) {
    uint8_t d, b;
    mm_channel_bits(k, &d, &b);
    g_dshot_pins = (uint8_t)(g_dshot_pins | d);
  }
  /* Bidirectional: the lines idle high, which tells the ESCs to answer;
   * frames to the host sent by the UART's interrupt while the replies are
   * decoded. */
  if (g_bidir) {
    PORTD = (uint8_t)(PORTD | g_dshot_pins);
    mm_serial_send_interrupt(1);
  }
  g_replies_waiting = 0;
  g_tlm.readings = 0;
  g_tlm.count = c->count;
  /* Replies go in batches of about 3 ms of frames: at 1 kHz a TELEMETRY
   * frame of three readings (37 bytes) every 3 ms fills half the wire and
   * costs the chip less than smaller ones; two more fit while a report
   * (1.6 ms) holds the wire. */
  g_tlm_send_at = (uint8_t)(c->period_us >= 3000u ? 1u : c->period_us >= 1500u ? 2u : 3u);
  g_next_frame = mm_now_ticks();
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

void mm_dshot_take(const mm_link_pulses* p, uint16_t lo, uint16_t hi) {
  /* [min, max] onto 48..2047, rounded; the width's half microseconds are
   * finer than a throttle step at any range above 500 us. */
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
}

uint8_t mm_dshot_take_command(const mm_link_command* c) {
  if (!g_configured || !g_dshot || g_out_armed || (g_link_ok && g_dshot_armed) ||
      (c->channels >> g_config.count) != 0u)
    return 0;
  g_cmd = c->command;
  g_cmd_channels = c->channels;
  g_cmd_left = c->repeat;
  g_dshot_dirty = 1;
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
void mm_dshot_prepare(void) {
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

void mm_dshot_send(void) {
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
    /* The bytes the UART received during the frame, read by the sender,
     * go into the ring before the receive interrupt may put a later one
     * there (and the ring's head is the interrupt's otherwise). */
    uint8_t uart[4];
    const uint8_t sreg = SREG;
    cli();
    const uint8_t n = mm_dshot_send150(g_dshot_ports, g_dshot_high, g_dshot_low, uart);
    for (uint8_t k = 0; k < n; ++k) mm_serial_put(uart[k]);
    SREG = sreg;
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
void mm_dshot_decode_replies(void) {
  if (g_tlm.readings == MM_LINK_TELEMETRY_MAX_READINGS) {
    for (uint8_t r = 1; r < MM_LINK_TELEMETRY_MAX_READINGS; ++r)
      memcpy(g_tlm.period_us[r - 1u], g_tlm.period_us[r], sizeof g_tlm.period_us[r]);
    --g_tlm.readings;
    ++g_tlm.first;
  }
  if (g_tlm.readings == 0u) g_tlm.first = (uint16_t)(g_frame_count - 1u);
  mm_reply_find_starts();
  for (uint8_t ch = 0; ch < g_config.count; ++ch)
    g_tlm.period_us[g_tlm.readings][ch] = mm_reply_decode(ch);
  ++g_tlm.readings;
  g_replies_waiting = 0;
}

uint8_t mm_dshot_batch_ready(void) { return g_tlm.readings >= g_tlm_send_at; }

void mm_dshot_send_batch(void) {
  mm_serial_send((uint8_t)mm_link_encode_telemetry(&g_tlm, g_tlm_seq++, mm_serial_frame()));
  g_tlm.readings = 0;
}

/* On a fixed schedule: a frame sent late (the loop was busy: a burst of
 * bytes, the replies) shortens the next gap, so the rate holds on average;
 * only more than four periods behind does the schedule start again from
 * now. */
uint8_t mm_dshot_frame_due(uint32_t now) {
  if ((int32_t)(now - g_next_frame) < 0) return 0;
  g_next_frame += g_period_ticks;
  if ((int32_t)(now - g_next_frame) >= (int32_t)(4u * (uint32_t)g_period_ticks))
    g_next_frame = now + g_period_ticks;
  return 1;
}
