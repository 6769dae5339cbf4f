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
#define PADDING 8u       /* see mm_reply_find_starts */
#define BUFFER \
  (SAMPLES_300 * 2u > MM_REPLY_SAMPLES + PADDING ? SAMPLES_300 * 2u : MM_REPLY_SAMPLES + PADDING)
static uint8_t g_samples[BUFFER];
static uint8_t g_count; /* samples in the last capture */
static uint8_t g_pins;  /* the channels sampled */

#define TICKS_PER_US 2u /* Timer1 at clk/8 */
#define WAIT_US 2u
#define SAMPLES_600 MM_REPLY_SAMPLES /* 72 us */

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
  g_pins = pins;
}

/* GCR code -> nibble; 0xFF: not a code. */
static const uint8_t kGcr[32] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 9,    10,
                                 11,   0xFF, 13,   14,   15,   0xFF, 0xFF, 2,    3,    0xFF, 5,
                                 6,    7,    0xFF, 0,    8,    1,    0xFF, 4,    12,   0xFF};

/* Each channel's first low sample, the start of its reply (D2.. first),
 * found for all of them in one pass (dshot_reply_bits.S). */
static uint8_t g_fall[MM_LINK_MAX_BIDIR_CHANNELS];
void mm_reply_falls(const uint8_t* samples, uint8_t pins, uint8_t* falls);

void mm_reply_find_starts(void) {
  /* After the window: a sentinel (every line low) that ends the search,
   * and idle (high) lines that a late reply's resync may read into. */
  g_samples[g_count] = 0;
  for (uint8_t k = 1; k < PADDING; ++k) g_samples[g_count + k] = 0xFFu;
  mm_reply_falls(g_samples, g_pins, g_fall);
}

/* A reply bit in samples: 3.048 both ways (21.333 cycles over 7 at
 * DShot600, 42.667 over 14 at DShot300). A bit is read in its middle: from
 * a change first seen at sample e (it came half a sample earlier on
 * average), the middle of that bit is e + 1.024; positions carry half a
 * sample more so that the whole part is the nearest sample. The bit loop
 * (dshot_reply_bits.S) keeps them as a pointer and an 8-bit fraction of
 * 1/256 sample: 3 + 12/256 a bit, e + 1 + 134/256 after a change. */
#define LAST_MID 62u /* the 21st bit's, from the start's fall */
#define CODES 4u
void mm_reply_codes(const uint8_t* fall, uint8_t pin, uint8_t* codes);

uint16_t mm_reply_decode(uint8_t channel) {
  const uint8_t pin = (uint8_t)(4u << channel); /* D2.. */
  const uint8_t i = g_fall[channel];            /* the start bit's fall (or the sentinel) */
  const uint8_t* const q = g_samples + i;
  /* Low from the window's first sample: a reply that started before it
   * (or a line held low), not to be read from the middle; and a reply whose
   * last bit's middle (with a slow ESC's clock) is past the window. */
  if (i == 0u || (uint16_t)i + LAST_MID + 2u >= g_count) return MM_LINK_NO_REPLY;
  /* Within the padding after the window at worst. */
  uint8_t code[CODES];
  mm_reply_codes(q, pin, code);
  uint8_t nibble[CODES], bad = 0;
  for (uint8_t n = 0; n < CODES; ++n) {
    nibble[n] = kGcr[code[n]];
    bad |= nibble[n];
  }
  /* 0xFF (not a code) is the only entry above 15. */
  if (bad & 0xF0u) return MM_LINK_NO_REPLY;
  /* The checksum: the inverted xor of the three nibbles before it. */
  if ((uint8_t)(nibble[0] ^ nibble[1] ^ nibble[2] ^ nibble[3]) != 0x0Fu) return MM_LINK_NO_REPLY;
  /* 3-bit exponent, 9-bit mantissa. */
  const uint16_t mantissa =
      (uint16_t)(((uint16_t)(nibble[0] & 1u) << 8) | (uint8_t)(nibble[1] << 4) | nibble[2]);
  if (mantissa == 0u) return MM_LINK_NO_REPLY;
  return (uint16_t)(mantissa << (nibble[0] >> 1));
}
