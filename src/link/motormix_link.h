/* The serial link between `motormix output` and the microcontroller that
 * makes the ESC pulses (the firmware to come). One C99 file for both ends: no heap, no
 * I/O, fixed-size buffers, so the ATmega328P and the host parse the same
 * bytes the same way.
 *
 * Frame: 0xA5 0x5A, length (of type + sequence + payload), type, sequence,
 * payload, CRC-32 (IEEE 802.3, little-endian) over length..payload.
 * CRC-32 rather than a 16-bit CRC: the firmware must not change a pulse on
 * 10^5 corrupted frames, and a 16-bit check lets one random frame in 65536
 * through.
 *
 * Host -> MCU, MM_LINK_PULSES: armed (0/1), count (1..MM_LINK_MAX_CHANNELS),
 * then count pulse widths in microseconds (u16, little-endian). Not armed:
 * every channel gets its disarmed pulse, whatever the widths say.
 * MCU -> host, MM_LINK_REPORT: frames accepted, CRC errors, malformed
 * frames (u32 each), link timeouts, watchdog resets (u16 each), the last
 * accepted sequence number (u8).
 */
#ifndef MOTORMIX_LINK_H
#define MOTORMIX_LINK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MM_LINK_SYNC0 0xA5u
#define MM_LINK_SYNC1 0x5Au
#define MM_LINK_MAX_CHANNELS 8u
#define MM_LINK_PULSES 0x01u
#define MM_LINK_REPORT 0x02u
/* Largest length field: a pulses frame with every channel. */
#define MM_LINK_MAX_BODY (2u + 2u + 2u * MM_LINK_MAX_CHANNELS)
/* Largest frame on the wire: sync, length, body, CRC. */
#define MM_LINK_MAX_FRAME (2u + 1u + MM_LINK_MAX_BODY + 4u)

uint32_t mm_link_crc32(uint32_t crc, const uint8_t* data, size_t len);

typedef struct {
  uint8_t sequence;
  uint8_t armed;
  uint8_t count;
  uint16_t pulse_us[MM_LINK_MAX_CHANNELS];
} mm_link_pulses;

typedef struct {
  uint32_t frames;
  uint32_t crc_errors;
  uint32_t malformed;
  uint16_t link_timeouts;
  uint16_t watchdog_resets;
  uint8_t last_sequence;
} mm_link_report;

/* Encode into out (at least MM_LINK_MAX_FRAME bytes); the frame's length in
 * bytes, 0 if count is outside 1..MM_LINK_MAX_CHANNELS. */
size_t mm_link_encode_pulses(const mm_link_pulses* p, uint8_t* out);
size_t mm_link_encode_report(const mm_link_report* r, uint8_t sequence, uint8_t* out);

/* A byte-at-a-time parser: it finds the sync, checks the length and the
 * CRC, and after anything wrong searches again from the byte after the
 * failed sync, so a truncated or corrupted frame does not take the next
 * good one with it. */
typedef struct {
  uint8_t state;
  uint8_t length;
  uint8_t have;
  uint8_t body[MM_LINK_MAX_BODY + 4u];
  uint8_t raw[MM_LINK_MAX_FRAME]; /* every byte since the sync being tried */
  uint8_t raw_len;
  uint8_t pending[2u * MM_LINK_MAX_FRAME]; /* bytes to search again */
  uint8_t pending_len;
  uint32_t crc_errors;
  uint32_t malformed; /* a length out of range, an unknown type, a bad payload */
} mm_link_parser;

void mm_link_parser_init(mm_link_parser* p);

/* Feeds one byte. Returns the type of a frame that just completed and
 * passed every check (its decoded content in *pulses or *report, whichever
 * it is; either pointer may be NULL to ignore that type), 0 otherwise. */
uint8_t mm_link_feed(mm_link_parser* p, uint8_t byte, mm_link_pulses* pulses,
                     mm_link_report* report);

#ifdef __cplusplus
}
#endif

#endif /* MOTORMIX_LINK_H */
