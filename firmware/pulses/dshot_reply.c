/* Bidirectional DShot replies, read by sampling port D (see dshot_reply.h).
 *
 * The reply: 30 us or so after the frame an ESC pulls its line low for a
 * 21-bit word at 5/4 of the frame's bitrate (1.333 us a bit at DShot600,
 * 2.667 at DShot300), each 1 a change of level and each 0 none; the first
 * bit (the fall) starts it, the other 20 are four 5-bit GCR codes, one per
 * nibble of a 16-bit value: a 12-bit period (3-bit exponent, 9-bit
 * mantissa: period_us = mantissa << exponent) and a 4-bit checksum (the
 * inverted xor of the three nibbles). GCR never holds a level longer than
 * three bits, which is what lets a run of samples be counted in bits.
 *
 * Sampling: every 7 cycles at DShot600, 14 at DShot300 (dshot.S): 3.05
 * samples a reply bit both ways. Each bit is read in its middle and the
 * count goes back in step at every change (GCR changes level at least
 * every three bits), so a bit is read right while its edges are within
 * 1.5 samples of where they were counted: half a sample for where between
 * two samples a change came, 0.2 for three bits of a clock 2 % off, the
 * rest (5 cycles at DShot600) for jitter. Every channel of the port in
 * each sample, so four motors cost one pass of sampling.
 *
 * The window follows the frame at once, interrupts off from the frame's
 * start to the window's end (an interrupt between them would move the
 * window, and replies start some 30 us after the frame): at DShot600 165
 * samples (72 us, replies seen 2..74 us after the frame, one takes 28),
 * short enough for the UART, which holds two bytes (80 us at 250000 baud)
 * after the poll between the frame and the window; at DShot300 a reply
 * takes 56 us: 115 samples (100 us, 2..102 us), the UART read by the
 * sampling loop itself (dshot.S). */
#include "dshot_reply.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#include "motormix_link.h"

void mm_dshot_sample600(uint8_t* buffer, uint8_t n);
uint8_t mm_dshot_sample300(uint8_t* buffer, uint8_t n, uint8_t* uart);

/* At DShot300 the bytes the UART received while sampling go after the
 * samples: one a sample at most, so they can never overrun it. */
#define SAMPLES_300 115u /* 100.6 us */
#define PADDING 8u       /* see find_first_low */
#define BUFFER \
  (SAMPLES_300 * 2u > MM_REPLY_SAMPLES + PADDING ? SAMPLES_300 * 2u : MM_REPLY_SAMPLES + PADDING)
static uint8_t g_samples[BUFFER];
static uint8_t g_count; /* samples in the last capture */
static void find_first_low(uint8_t pins);

#define TICKS_PER_US 2u /* Timer1 at clk/8 */
#define WAIT_US 2u
#define SAMPLES_600 MM_REPLY_SAMPLES /* 72 us */
#define REPLY_BITS 21u

void mm_reply_capture(uint8_t speed, uint8_t pins, void (*poll)(void), void (*take)(uint8_t byte)) {
  /* The frame left the pins high: input with the pull-up on, no glitch. */
  DDRD = (uint8_t)(DDRD & ~pins);
  const uint16_t t0 = TCNT1;
  while ((uint16_t)(TCNT1 - t0) < WAIT_US * TICKS_PER_US) {
  }
  poll();
  if (speed == MM_LINK_PROTOCOL_DSHOT600) {
    g_count = SAMPLES_600;
    mm_dshot_sample600(g_samples, g_count);
  } else {
    uint8_t* const uart = g_samples + SAMPLES_300;
    g_count = SAMPLES_300;
    const uint8_t n = mm_dshot_sample300(g_samples, g_count, uart);
    for (uint8_t k = 0; k < n; ++k) take(uart[k]);
  }
  poll();
  DDRD = (uint8_t)(DDRD | pins); /* PORTD still high there: idle */
  find_first_low(pins);
}

/* GCR code -> nibble; 0xFF: not a code. */
static const uint8_t kGcr[32] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 9,    10,
                                 11,   0xFF, 13,   14,   15,   0xFF, 0xFF, 2,    3,    0xFF, 5,
                                 6,    7,    0xFF, 0,    8,    1,    0xFF, 4,    12,   0xFF};

/* The first sample where any channel's line is low: no reply starts
 * earlier, so each channel's search starts there. */
static uint8_t g_first;

static void find_first_low(uint8_t pins) {
  /* After the window: a sentinel (every line low) that ends each search,
   * and idle (high) lines that a late reply's resync may read into. */
  g_samples[g_count] = 0;
  for (uint8_t k = 1; k < PADDING; ++k) g_samples[g_count + k] = 0xFFu;
  uint8_t i = 0;
  while ((g_samples[i] & pins) == pins) ++i;
  g_first = i;
}

/* A reply bit in samples, 8.8 fixed point: 3.048 both ways (21.333 cycles
 * over 7 at DShot600, 42.667 over 14 at DShot300). A bit is read in its
 * middle: from a change first seen at sample e (it came half a sample
 * earlier on average), the middle of that bit is e + 1.024; positions carry
 * half a sample more so that the whole part is the nearest sample. */
#define BIT_Q8 780u
#define FIRST_MID_Q8 390u /* (1.024 + 0.5) * 256 */
#define LAST_MID 62u      /* the 21st bit's, from the start's fall */

uint16_t mm_reply_decode(uint8_t channel) {
  const uint8_t pin = (uint8_t)(4u << channel); /* D2.. */
  const uint8_t* const s = g_samples;
  uint8_t i = g_first;
  while (s[i] & pin) ++i; /* the start bit's fall (the sentinel ends it) */
  /* Low from the window's first sample: a reply that started before it
   * (or a line held low), not to be read from the middle; and a reply whose
   * last bit's middle (with a slow ESC's clock) is past the window. */
  if (i == 0u || (uint16_t)i + LAST_MID + 2u >= g_count) return MM_LINK_NO_REPLY;
  /* Each bit read in its middle, as a UART reads, counted from the last
   * change seen; a 1 is a change of level since the bit before; each five
   * bits a GCR code. Within the padding after the window at worst. */
  uint16_t mid = (uint16_t)(((uint16_t)i << 8) + FIRST_MID_Q8);
  uint8_t level = 0, before = i, code = 0, left = 5, value_ok = 1;
  uint16_t value = 0;
  for (uint8_t bit = 1; bit < REPLY_BITS; ++bit) {
    mid = (uint16_t)(mid + BIT_Q8);
    const uint8_t at = (uint8_t)(mid >> 8);
    const uint8_t l = (uint8_t)(s[at] & pin);
    code = (uint8_t)(code << 1);
    if (l != level) {
      code |= 1u;
      /* Back in step: the first sample of the new level since the last
       * bit's middle, which is 3 or 4 samples before this one. */
      const uint8_t* q = s + at;
      uint8_t e = at;
      if ((uint8_t)(q[-1] & pin) == l) {
        --e;
        if ((uint8_t)(q[-2] & pin) == l) {
          --e;
          if ((uint8_t)(at - before) > 3u && (uint8_t)(q[-3] & pin) == l) --e;
        }
      }
      mid = (uint16_t)(((uint16_t)e << 8) + FIRST_MID_Q8);
      level = l;
    }
    before = at;
    if (--left == 0u) {
      const uint8_t nibble = kGcr[code & 0x1Fu];
      if (nibble == 0xFFu) value_ok = 0;
      value = (uint16_t)((value << 4) | (nibble & 0x0Fu));
      code = 0;
      left = 5;
    }
  }
  if (!value_ok) return MM_LINK_NO_REPLY;
  uint16_t sum = (uint16_t)(value ^ (value >> 8));
  sum = (uint16_t)(sum ^ (sum >> 4));
  if ((sum & 0x0Fu) != 0x0Fu) return MM_LINK_NO_REPLY;
  const uint16_t period = (uint16_t)(value >> 4);
  const uint16_t mantissa = (uint16_t)(period & 0x1FFu);
  if (mantissa == 0u) return MM_LINK_NO_REPLY;
  return (uint16_t)(mantissa << (period >> 9));
}
