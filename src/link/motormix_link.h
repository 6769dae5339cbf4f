/* The serial link between `motormix output` and the pulse firmware on the
 * microcontroller that makes the ESC pulses (firmware/pulses). One C99 file
 * for both ends: no heap, no I/O, fixed-size buffers, so the ATmega328P and
 * the host parse the same bytes the same way.
 *
 * Frame: 0xA5 0x5A, length (of type + sequence + payload), type, sequence,
 * payload, CRC-32 (IEEE 802.3, little-endian) over length..payload.
 * CRC-32 rather than a 16-bit CRC: the firmware must not change a pulse on
 * 10^5 corrupted frames, and a 16-bit check lets one random frame in 65536
 * through. Multi-byte fields are little-endian.
 *
 * Link version 5 (MM_LINK_VERSION, in every REPORT; 3 added the protocol
 * to CONFIG and the COMMAND frame, 4 bidirectional DShot and TELEMETRY, 5
 * the telemetry request in PULSES).
 * Sessions: the chip
 * names a session in its reports, a 32-bit number that never repeats (its
 * EEPROM keeps the highest base used across resets) and that it moves on
 * at every link timeout. CONFIG and PULSES carry the session they are for
 * and a 32-bit sequence number, and the chip takes one only for its
 * current session and with a sequence above the last it took. So a frame
 * recorded before a link timeout, or before a reset, is never taken again,
 * whatever its sequence; within a session only a frame newer than every
 * one taken, i.e. one younger than the link timeout, and at most
 * MM_LINK_MAX_SEQUENCE_STEP beyond it. A host learns the session, and the
 * last sequence taken, from the reports: it sends nothing before it has
 * heard one.
 *
 * Host -> MCU (after type: session u32, sequence u32)
 *   MM_LINK_CONFIG: period (us), link timeout (ms), lowest and highest
 *     armed pulse (us), channel count, protocol (MM_LINK_PROTOCOL_*), then
 *     one disarmed pulse (us) per channel. The firmware makes no pulse at all
 *     until it has one; it takes a new one only while its outputs are
 *     disarmed. With DShot the period is the frame period, an armed width
 *     maps [min, max] onto throttle 48..2047 and a disarmed channel sends
 *     0 (motor stop): the disarmed widths are not used. With
 *     MM_LINK_PROTOCOL_BIDIRECTIONAL the frames are inverted (idle high,
 *     inverted checksum) and every ESC answers each one with its eRPM.
 *   MM_LINK_COMMAND (DShot only): a special command (1..47, the ESC's
 *     numbering), a channel mask and a count of frames to send it in (ESCs
 *     act on a setting only after 6), with the telemetry bit set as ESCs
 *     require. Taken only while every output is disarmed; an armed PULSES
 *     frame ends it.
 *   MM_LINK_PULSES: armed channels (a bit per channel, none beyond the
 *     count), count (must equal the configured count; its low nibble: with
 *     bit 7 set, bits 4..6 name the channel whose ESC is asked for its KISS
 *     telemetry: DShot only, the telemetry bit in that channel's next frame
 *     alone, the frames after it without), then count pulse
 *     widths in half microseconds (the firmware's timer resolution: a width
 *     of 1234.3 us goes as 2469 and comes out as 1234.5). A channel whose
 *     bit is clear gets its disarmed pulse, whatever its width says; an
 *     armed one its width, clamped into [min, max]. One bit alone is a
 *     motor test through `motormix output`.
 * MCU -> host
 *   MM_LINK_REPORT (after type: a report counter u8): frames accepted, CRC
 *     errors, malformed frames (u32 each), link timeouts, watchdog resets,
 *     rejected frames (u16 each: well formed but refused: another session,
 *     out of sequence, before a configuration, wrong count, a configuration
 *     while armed), the last accepted sequence number (u32), state flags
 *     (MM_LINK_FLAG_*), the session (u32) and the link version (u8).
 *   MM_LINK_TELEMETRY (bidirectional DShot; after type: a counter u8): the
 *     frame counter of the first reading (u16), readings, channels (u8
 *     each), then each reading's periods (u16 a channel), oldest first.
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
#define MM_LINK_CONFIG 0x03u
#define MM_LINK_COMMAND 0x04u
#define MM_LINK_TELEMETRY 0x05u
#define MM_LINK_VERSION 5u
/* CONFIG's protocol */
#define MM_LINK_PROTOCOL_PWM 0u
#define MM_LINK_PROTOCOL_DSHOT150 1u
#define MM_LINK_PROTOCOL_DSHOT300 2u
#define MM_LINK_PROTOCOL_DSHOT600 3u
/* DShot: every channel on one port (D2..D7) in one frame; frames up to 4 kHz */
#define MM_LINK_MAX_DSHOT_CHANNELS 6u
#define MM_LINK_MIN_DSHOT_PERIOD_US 250u
#define MM_LINK_DSHOT_MAX_COMMAND 47u
/* Bidirectional DShot: CONFIG's protocol with this bit (DShot300 or 600
 * only); the first MM_LINK_MAX_BIDIR_CHANNELS channels (D2..D5), frames at
 * most 1 kHz: the chip decodes every reply between two frames; with four
 * motors and the host's frames at 400 Hz it holds 1.43 kHz (measured in
 * simavr), where its TELEMETRY frames nearly fill the wire back. */
#define MM_LINK_PROTOCOL_BIDIRECTIONAL 0x80u
#define MM_LINK_PROTOCOL_SPEED_MASK 0x0Fu
#define MM_LINK_MAX_BIDIR_CHANNELS 4u
#define MM_LINK_MIN_BIDIR_PERIOD_US 1000u
/* PULSES' count byte: the telemetry request's flag (its channel in bits 4..6) */
#define MM_LINK_TELEMETRY_REQUEST 0x80u
/* TELEMETRY: up to this many frames' replies in one */
#define MM_LINK_TELEMETRY_MAX_READINGS 5u

/* Limits both ends hold a configuration to (servo-style ESC pulses at
 * 40..500 Hz; a pulse ends at least MM_LINK_MIN_LOW_US before the next
 * period starts). */
#define MM_LINK_MIN_PERIOD_US 2000u
#define MM_LINK_MAX_PERIOD_US 25000u
#define MM_LINK_MIN_PULSE_US 500u
#define MM_LINK_MAX_PULSE_US 2500u
#define MM_LINK_MIN_LOW_US 40u
#define MM_LINK_MIN_TIMEOUT_MS 10u
#define MM_LINK_MAX_TIMEOUT_MS 1000u
/* The link timeout is at least this many periods: the chip calls the link
 * lost one period before the timeout, so that outputs disarm within it. */
#define MM_LINK_MIN_TIMEOUT_PERIODS 2u
/* A frame is taken only when its sequence is above the last one taken in
 * the session by at most this: more frames than a session sees before a
 * link timeout (4 kHz for a second), so a frame with a wild sequence (a
 * host whose counter started wrong) is refused and cannot lock the session
 * out. */
#define MM_LINK_MAX_SEQUENCE_STEP 65536UL

#define MM_LINK_CONFIG_BODY(count) (19u + 2u * (count))
#define MM_LINK_COMMAND_BODY 12u
#define MM_LINK_PULSES_BODY(count) (11u + 2u * (count))
#define MM_LINK_REPORT_BODY 30u
#define MM_LINK_TELEMETRY_BODY(readings, count) (6u + 2u * (readings) * (count))
/* Largest length field: a telemetry frame of every reading. */
#define MM_LINK_MAX_BODY \
  MM_LINK_TELEMETRY_BODY(MM_LINK_TELEMETRY_MAX_READINGS, MM_LINK_MAX_BIDIR_CHANNELS)
/* Largest frame on the wire: sync, length, body, CRC. */
#define MM_LINK_MAX_FRAME (2u + 1u + MM_LINK_MAX_BODY + 4u)

/* Report flags. */
#define MM_LINK_FLAG_CONFIGURED 0x01u /* has a configuration, makes pulses */
#define MM_LINK_FLAG_ARMED 0x02u      /* the pulses now are armed ones */
#define MM_LINK_FLAG_TIMED_OUT 0x04u  /* disarmed by its own link watchdog */

uint32_t mm_link_crc32(uint32_t crc, const uint8_t* data, size_t len);

typedef struct {
  uint32_t session;
  uint32_t sequence;
  uint16_t period_us;
  uint16_t link_timeout_ms;
  uint16_t min_us; /* armed pulses are clamped into [min_us, max_us] */
  uint16_t max_us;
  uint8_t count;
  uint8_t protocol; /* MM_LINK_PROTOCOL_* */
  uint16_t disarmed_us[MM_LINK_MAX_CHANNELS];
} mm_link_config;

typedef struct {
  uint32_t session;
  uint32_t sequence;
  uint8_t command;  /* 1..MM_LINK_DSHOT_MAX_COMMAND */
  uint8_t channels; /* bit i: channel i */
  uint8_t repeat;   /* frames to send it in, 1..255 */
} mm_link_command;

typedef struct {
  uint32_t session;
  uint32_t sequence;
  uint8_t armed; /* bit i: channel i armed */
  uint8_t count;
  uint16_t pulse_hus[MM_LINK_MAX_CHANNELS]; /* half microseconds: 3000 is 1500 us */
  /* 0: no request; c + 1: ask channel c's ESC for its KISS telemetry (the
   * telemetry bit in its next DShot frame; c below count). Zero by default
   * so that a frame built without it asks nothing. */
  uint8_t telemetry;
} mm_link_pulses;

/* The eRPM replies of consecutive DShot frames, as the chip decoded them:
 * each the period of one electrical revolution in microseconds (the reply's
 * mantissa << exponent: 65408, its largest, is a stopped motor), or
 * MM_LINK_NO_REPLY when the reply was missing or broken (no falling edge,
 * a run longer than GCR allows, a bad code or checksum). */
#define MM_LINK_NO_REPLY 0u
typedef struct {
  uint16_t first;   /* the DShot frame counter of the first reading (mod 2^16) */
  uint8_t readings; /* 1..MM_LINK_TELEMETRY_MAX_READINGS */
  uint8_t count;    /* channels, 1..MM_LINK_MAX_BIDIR_CHANNELS */
  uint16_t period_us[MM_LINK_TELEMETRY_MAX_READINGS][MM_LINK_MAX_BIDIR_CHANNELS];
} mm_link_telemetry;

typedef struct {
  uint32_t frames;
  uint32_t crc_errors;
  uint32_t malformed;
  uint16_t link_timeouts;
  uint16_t watchdog_resets;
  uint16_t rejected;
  uint32_t last_sequence;
  uint8_t flags;
  uint32_t session; /* the one frames must be for now */
  uint8_t version;  /* MM_LINK_VERSION of the firmware that sent it */
} mm_link_report;

/* 1 if every field is within the limits above (pulses shorter than the
 * period by MM_LINK_MIN_LOW_US, min <= max, disarmed pulses in range, the
 * link timeout at least MM_LINK_MIN_TIMEOUT_PERIODS periods). */
int mm_link_config_valid(const mm_link_config* c);

/* Encode into out (at least MM_LINK_MAX_FRAME bytes); the frame's length in
 * bytes, 0 if the content cannot be sent (a count outside
 * 1..MM_LINK_MAX_CHANNELS, an invalid configuration). */
size_t mm_link_encode_config(const mm_link_config* c, uint8_t* out);
size_t mm_link_encode_pulses(const mm_link_pulses* p, uint8_t* out);
size_t mm_link_encode_command(const mm_link_command* c, uint8_t* out);
size_t mm_link_encode_report(const mm_link_report* r, uint8_t sequence, uint8_t* out);
size_t mm_link_encode_telemetry(const mm_link_telemetry* t, uint8_t sequence, uint8_t* out);

/* What a completed frame held: its type says which member is valid. */
typedef struct {
  uint8_t type;
  union {
    mm_link_config config;
    mm_link_pulses pulses;
    mm_link_report report;
    mm_link_command command;
    mm_link_telemetry telemetry;
  } u;
} mm_link_frame;

/* A byte-at-a-time parser: it finds the sync, checks the length and the
 * CRC (computed as the bytes arrive), and after anything wrong searches
 * again from the byte after the failed sync, so a truncated or corrupted
 * frame does not take the next good one with it. The bytes to search again
 * wait in a ring, and each mm_link_poll takes one of them: the firmware
 * polls between reads of its UART, so no search after a failure makes it
 * miss an incoming byte. */
#define MM_LINK_PENDING 128u /* a power of two, at least 2 * MM_LINK_MAX_FRAME */
typedef struct {
  /* The fields every byte touches first, near the start: on the chip they
   * are reached in one instruction from the parser's address (within 63
   * bytes of it), the arrays after them. */
  uint8_t state;
  uint8_t length;
  uint8_t have;
  uint8_t raw_len;
  uint8_t pending_head;
  uint8_t pending_len;
  uint32_t crc; /* running CRC over length..body */
  uint32_t crc_errors;
  uint32_t malformed; /* a length out of range, an unknown type, a bad payload, a byte
                         dropped because the ring was full */
  uint8_t body[MM_LINK_MAX_BODY + 4u];
  uint8_t raw[MM_LINK_MAX_FRAME];   /* every byte since the sync being tried */
  uint8_t pending[MM_LINK_PENDING]; /* a ring of bytes to search */
} mm_link_parser;

void mm_link_parser_init(mm_link_parser* p);

/* Queues one received byte (dropped and counted as malformed if the ring is
 * full). */
void mm_link_push(mm_link_parser* p, uint8_t byte);
/* Searches one queued byte. Returns the type of a frame that just completed
 * and passed every check (its decoded content in *frame), 0 otherwise. */
uint8_t mm_link_poll(mm_link_parser* p, mm_link_frame* frame);
static inline uint8_t mm_link_pending(const mm_link_parser* p) { return p->pending_len; }
/* One received byte, searched at once when nothing waits to be searched
 * (else queued behind what does, and one queued byte searched): what
 * mm_link_push and mm_link_poll do, without the trip through the ring in
 * the common case. Returns as mm_link_poll. */
uint8_t mm_link_step(mm_link_parser* p, uint8_t byte, mm_link_frame* frame);

/* Push, then poll until a frame completes or nothing is queued: the host's
 * way, where no byte can be missed. */
uint8_t mm_link_feed(mm_link_parser* p, uint8_t byte, mm_link_frame* frame);

#ifdef __cplusplus
}
#endif

#endif /* MOTORMIX_LINK_H */
