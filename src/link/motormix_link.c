#include "motormix_link.h"

enum { kWaitSync0 = 0, kWaitSync1 = 1, kWaitLength = 2, kBody = 3 };

/* After a bad frame, not once a byte: kept out of the byte's path, whose
 * every call would otherwise save and restore the registers it needs (on
 * the chip 12 cycles of a byte's 130). (decode() stays inline: out of line
 * too, it saves as much again, but moves the firmware's code enough that a
 * pulse edge's interrupt meets a 4-cycle instruction: 0.25 us on a servo
 * pulse in the firmware's tests, 0.125 us with it inline.) */
#if defined(__GNUC__)
#define MM_LINK_COLD __attribute__((noinline))
#else
#define MM_LINK_COLD
#endif

/* CRC-32 (reflected polynomial 0xEDB88320). */
#ifdef __AVR__
/* On the chip a byte-wide table in flash: a quarter of the cycles
 * of the nibble table for each byte (flash has room, RAM has not), which
 * the firmware's busiest loop (bidirectional DShot) needs. */
#include <avr/pgmspace.h>
static const uint32_t kCrcByte[256] PROGMEM = {
    0x00000000u, 0x77073096u, 0xEE0E612Cu, 0x990951BAu, 0x076DC419u, 0x706AF48Fu, 0xE963A535u,
    0x9E6495A3u, 0x0EDB8832u, 0x79DCB8A4u, 0xE0D5E91Eu, 0x97D2D988u, 0x09B64C2Bu, 0x7EB17CBDu,
    0xE7B82D07u, 0x90BF1D91u, 0x1DB71064u, 0x6AB020F2u, 0xF3B97148u, 0x84BE41DEu, 0x1ADAD47Du,
    0x6DDDE4EBu, 0xF4D4B551u, 0x83D385C7u, 0x136C9856u, 0x646BA8C0u, 0xFD62F97Au, 0x8A65C9ECu,
    0x14015C4Fu, 0x63066CD9u, 0xFA0F3D63u, 0x8D080DF5u, 0x3B6E20C8u, 0x4C69105Eu, 0xD56041E4u,
    0xA2677172u, 0x3C03E4D1u, 0x4B04D447u, 0xD20D85FDu, 0xA50AB56Bu, 0x35B5A8FAu, 0x42B2986Cu,
    0xDBBBC9D6u, 0xACBCF940u, 0x32D86CE3u, 0x45DF5C75u, 0xDCD60DCFu, 0xABD13D59u, 0x26D930ACu,
    0x51DE003Au, 0xC8D75180u, 0xBFD06116u, 0x21B4F4B5u, 0x56B3C423u, 0xCFBA9599u, 0xB8BDA50Fu,
    0x2802B89Eu, 0x5F058808u, 0xC60CD9B2u, 0xB10BE924u, 0x2F6F7C87u, 0x58684C11u, 0xC1611DABu,
    0xB6662D3Du, 0x76DC4190u, 0x01DB7106u, 0x98D220BCu, 0xEFD5102Au, 0x71B18589u, 0x06B6B51Fu,
    0x9FBFE4A5u, 0xE8B8D433u, 0x7807C9A2u, 0x0F00F934u, 0x9609A88Eu, 0xE10E9818u, 0x7F6A0DBBu,
    0x086D3D2Du, 0x91646C97u, 0xE6635C01u, 0x6B6B51F4u, 0x1C6C6162u, 0x856530D8u, 0xF262004Eu,
    0x6C0695EDu, 0x1B01A57Bu, 0x8208F4C1u, 0xF50FC457u, 0x65B0D9C6u, 0x12B7E950u, 0x8BBEB8EAu,
    0xFCB9887Cu, 0x62DD1DDFu, 0x15DA2D49u, 0x8CD37CF3u, 0xFBD44C65u, 0x4DB26158u, 0x3AB551CEu,
    0xA3BC0074u, 0xD4BB30E2u, 0x4ADFA541u, 0x3DD895D7u, 0xA4D1C46Du, 0xD3D6F4FBu, 0x4369E96Au,
    0x346ED9FCu, 0xAD678846u, 0xDA60B8D0u, 0x44042D73u, 0x33031DE5u, 0xAA0A4C5Fu, 0xDD0D7CC9u,
    0x5005713Cu, 0x270241AAu, 0xBE0B1010u, 0xC90C2086u, 0x5768B525u, 0x206F85B3u, 0xB966D409u,
    0xCE61E49Fu, 0x5EDEF90Eu, 0x29D9C998u, 0xB0D09822u, 0xC7D7A8B4u, 0x59B33D17u, 0x2EB40D81u,
    0xB7BD5C3Bu, 0xC0BA6CADu, 0xEDB88320u, 0x9ABFB3B6u, 0x03B6E20Cu, 0x74B1D29Au, 0xEAD54739u,
    0x9DD277AFu, 0x04DB2615u, 0x73DC1683u, 0xE3630B12u, 0x94643B84u, 0x0D6D6A3Eu, 0x7A6A5AA8u,
    0xE40ECF0Bu, 0x9309FF9Du, 0x0A00AE27u, 0x7D079EB1u, 0xF00F9344u, 0x8708A3D2u, 0x1E01F268u,
    0x6906C2FEu, 0xF762575Du, 0x806567CBu, 0x196C3671u, 0x6E6B06E7u, 0xFED41B76u, 0x89D32BE0u,
    0x10DA7A5Au, 0x67DD4ACCu, 0xF9B9DF6Fu, 0x8EBEEFF9u, 0x17B7BE43u, 0x60B08ED5u, 0xD6D6A3E8u,
    0xA1D1937Eu, 0x38D8C2C4u, 0x4FDFF252u, 0xD1BB67F1u, 0xA6BC5767u, 0x3FB506DDu, 0x48B2364Bu,
    0xD80D2BDAu, 0xAF0A1B4Cu, 0x36034AF6u, 0x41047A60u, 0xDF60EFC3u, 0xA867DF55u, 0x316E8EEFu,
    0x4669BE79u, 0xCB61B38Cu, 0xBC66831Au, 0x256FD2A0u, 0x5268E236u, 0xCC0C7795u, 0xBB0B4703u,
    0x220216B9u, 0x5505262Fu, 0xC5BA3BBEu, 0xB2BD0B28u, 0x2BB45A92u, 0x5CB36A04u, 0xC2D7FFA7u,
    0xB5D0CF31u, 0x2CD99E8Bu, 0x5BDEAE1Du, 0x9B64C2B0u, 0xEC63F226u, 0x756AA39Cu, 0x026D930Au,
    0x9C0906A9u, 0xEB0E363Fu, 0x72076785u, 0x05005713u, 0x95BF4A82u, 0xE2B87A14u, 0x7BB12BAEu,
    0x0CB61B38u, 0x92D28E9Bu, 0xE5D5BE0Du, 0x7CDCEFB7u, 0x0BDBDF21u, 0x86D3D2D4u, 0xF1D4E242u,
    0x68DDB3F8u, 0x1FDA836Eu, 0x81BE16CDu, 0xF6B9265Bu, 0x6FB077E1u, 0x18B74777u, 0x88085AE6u,
    0xFF0F6A70u, 0x66063BCAu, 0x11010B5Cu, 0x8F659EFFu, 0xF862AE69u, 0x616BFFD3u, 0x166CCF45u,
    0xA00AE278u, 0xD70DD2EEu, 0x4E048354u, 0x3903B3C2u, 0xA7672661u, 0xD06016F7u, 0x4969474Du,
    0x3E6E77DBu, 0xAED16A4Au, 0xD9D65ADCu, 0x40DF0B66u, 0x37D83BF0u, 0xA9BCAE53u, 0xDEBB9EC5u,
    0x47B2CF7Fu, 0x30B5FFE9u, 0xBDBDF21Cu, 0xCABAC28Au, 0x53B39330u, 0x24B4A3A6u, 0xBAD03605u,
    0xCDD70693u, 0x54DE5729u, 0x23D967BFu, 0xB3667A2Eu, 0xC4614AB8u, 0x5D681B02u, 0x2A6F2B94u,
    0xB40BBE37u, 0xC30C8EA1u, 0x5A05DF1Bu, 0x2D02EF8Du,
};

/* One byte into a CRC register (not inverted at either end). */
static uint32_t crc_step(uint32_t reg, uint8_t byte) {
  return (reg >> 8) ^ pgm_read_dword(&kCrcByte[(uint8_t)(reg ^ byte)]);
}
#else
/* CRC-32 (reflected polynomial 0xEDB88320) a nibble at a time: a 64-byte
 * table rather than the usual 1 KiB one, which would take half of the
 * ATmega328P's RAM; two lookups per byte keep a byte to a few microseconds
 * there. */
static const uint32_t kCrcNibble[16] = {0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu,
                                        0x76DC4190u, 0x6B6B51F4u, 0x4DB26158u, 0x5005713Cu,
                                        0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
                                        0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu};

/* One byte into a CRC register (not inverted at either end). */
static uint32_t crc_step(uint32_t reg, uint8_t byte) {
  reg = (reg >> 4) ^ kCrcNibble[(reg ^ byte) & 0x0Fu];
  reg = (reg >> 4) ^ kCrcNibble[(reg ^ (uint8_t)(byte >> 4)) & 0x0Fu];
  return reg;
}
#endif

uint32_t mm_link_crc32(uint32_t crc, const uint8_t* data, size_t len) {
  uint32_t reg = ~crc;
  for (size_t i = 0; i < len; ++i) reg = crc_step(reg, data[i]);
  return ~reg;
}

static void put16(uint8_t* out, uint16_t v) {
  out[0] = (uint8_t)(v & 0xFFu);
  out[1] = (uint8_t)(v >> 8);
}

static void put32(uint8_t* out, uint32_t v) {
  put16(out, (uint16_t)(v & 0xFFFFu));
  put16(out + 2, (uint16_t)(v >> 16));
}

static uint16_t get16(const uint8_t* in) { return (uint16_t)(in[0] | ((uint16_t)in[1] << 8)); }

static uint32_t get32(const uint8_t* in) {
  return (uint32_t)get16(in) | ((uint32_t)get16(in + 2) << 16);
}

/* Sync, length and CRC around a body already at out + 3. */
static size_t frame(uint8_t* out, uint8_t body_length) {
  out[0] = MM_LINK_SYNC0;
  out[1] = MM_LINK_SYNC1;
  out[2] = body_length;
  put32(out + 3 + body_length, mm_link_crc32(0, out + 2, (size_t)body_length + 1u));
  return (size_t)body_length + 7u;
}

static int pulse_in_range(uint16_t us, uint16_t period_us) {
  return us >= MM_LINK_MIN_PULSE_US && us <= MM_LINK_MAX_PULSE_US &&
         (uint32_t)us + MM_LINK_MIN_LOW_US <= period_us;
}

int mm_link_config_valid(const mm_link_config* c) {
  if (c->count < 1u || c->count > MM_LINK_MAX_CHANNELS) return 0;
  const uint8_t speed = (uint8_t)(c->protocol & MM_LINK_PROTOCOL_SPEED_MASK);
  const int bidir = (c->protocol & MM_LINK_PROTOCOL_BIDIRECTIONAL) != 0u;
  if (speed > MM_LINK_PROTOCOL_DSHOT600) return 0;
  if ((c->protocol & (uint8_t) ~(MM_LINK_PROTOCOL_SPEED_MASK | MM_LINK_PROTOCOL_BIDIRECTIONAL)) !=
      0u)
    return 0;
  const int dshot = speed != MM_LINK_PROTOCOL_PWM;
  if (dshot && c->count > MM_LINK_MAX_DSHOT_CHANNELS) return 0;
  if (bidir && (speed < MM_LINK_PROTOCOL_DSHOT300 || c->count > MM_LINK_MAX_BIDIR_CHANNELS ||
                c->period_us < MM_LINK_MIN_BIDIR_PERIOD_US))
    return 0;
  if (c->period_us < (dshot ? MM_LINK_MIN_DSHOT_PERIOD_US : MM_LINK_MIN_PERIOD_US) ||
      c->period_us > MM_LINK_MAX_PERIOD_US)
    return 0;
  if (c->link_timeout_ms < MM_LINK_MIN_TIMEOUT_MS || c->link_timeout_ms > MM_LINK_MAX_TIMEOUT_MS)
    return 0;
  /* The failsafe counts the timeout less one period: shorter than two, it
   * would wrap. */
  if ((uint32_t)c->link_timeout_ms * 1000UL < (uint32_t)MM_LINK_MIN_TIMEOUT_PERIODS * c->period_us)
    return 0;
  /* DShot: the widths only name the throttle range, no pulse has to fit
   * in the period. */
  const uint16_t room = dshot ? MM_LINK_MAX_PERIOD_US : c->period_us;
  if (!pulse_in_range(c->min_us, room) || !pulse_in_range(c->max_us, room) ||
      c->min_us > c->max_us || (dshot && c->min_us == c->max_us))
    return 0;
  for (uint8_t i = 0; i < c->count; ++i)
    if (!pulse_in_range(c->disarmed_us[i], room)) return 0;
  return 1;
}

static int command_valid(const mm_link_command* c) {
  return c->command >= 1u && c->command <= MM_LINK_DSHOT_MAX_COMMAND && c->channels != 0u &&
         c->repeat >= 1u;
}

size_t mm_link_encode_config(const mm_link_config* c, uint8_t* out) {
  if (!mm_link_config_valid(c)) return 0;
  uint8_t* b = out + 3;
  b[0] = MM_LINK_CONFIG;
  put32(b + 1, c->session);
  put32(b + 5, c->sequence);
  put16(b + 9, c->period_us);
  put16(b + 11, c->link_timeout_ms);
  put16(b + 13, c->min_us);
  put16(b + 15, c->max_us);
  b[17] = c->count;
  b[18] = c->protocol;
  for (uint8_t i = 0; i < c->count; ++i) put16(b + 19 + 2 * i, c->disarmed_us[i]);
  return frame(out, (uint8_t)MM_LINK_CONFIG_BODY(c->count));
}

size_t mm_link_encode_command(const mm_link_command* c, uint8_t* out) {
  if (!command_valid(c)) return 0;
  uint8_t* b = out + 3;
  b[0] = MM_LINK_COMMAND;
  put32(b + 1, c->session);
  put32(b + 5, c->sequence);
  b[9] = c->command;
  b[10] = c->channels;
  b[11] = c->repeat;
  return frame(out, (uint8_t)MM_LINK_COMMAND_BODY);
}

size_t mm_link_encode_pulses(const mm_link_pulses* p, uint8_t* out) {
  if (p->count < 1u || p->count > MM_LINK_MAX_CHANNELS) return 0;
  uint8_t* b = out + 3;
  b[0] = MM_LINK_PULSES;
  put32(b + 1, p->session);
  put32(b + 5, p->sequence);
  if ((p->armed >> p->count) != 0u) return 0; /* a channel beyond the count */
  if (p->telemetry > p->count) return 0;      /* a request beyond the count */
  b[9] = p->armed;
  b[10] = p->telemetry != 0u
              ? (uint8_t)(p->count | MM_LINK_TELEMETRY_REQUEST | ((p->telemetry - 1u) << 4))
              : p->count;
  for (uint8_t i = 0; i < p->count; ++i) put16(b + 11 + 2 * i, p->pulse_hus[i]);
  return frame(out, (uint8_t)MM_LINK_PULSES_BODY(p->count));
}

size_t mm_link_encode_report(const mm_link_report* r, uint8_t sequence, uint8_t* out) {
  uint8_t* b = out + 3;
  b[0] = MM_LINK_REPORT;
  b[1] = sequence;
  put32(b + 2, r->frames);
  put32(b + 6, r->crc_errors);
  put32(b + 10, r->malformed);
  put16(b + 14, r->link_timeouts);
  put16(b + 16, r->watchdog_resets);
  put16(b + 18, r->rejected);
  put32(b + 20, r->last_sequence);
  b[24] = r->flags;
  put32(b + 25, r->session);
  b[29] = r->version;
  return frame(out, (uint8_t)MM_LINK_REPORT_BODY);
}

size_t mm_link_encode_telemetry(const mm_link_telemetry* t, uint8_t sequence, uint8_t* out) {
  if (t->readings < 1u || t->readings > MM_LINK_TELEMETRY_MAX_READINGS || t->count < 1u ||
      t->count > MM_LINK_MAX_BIDIR_CHANNELS)
    return 0;
  uint8_t* b = out + 3;
  b[0] = MM_LINK_TELEMETRY;
  b[1] = sequence;
  put16(b + 2, t->first);
  b[4] = t->readings;
  b[5] = t->count;
  uint8_t* v = b + 6;
  for (uint8_t r = 0; r < t->readings; ++r)
    for (uint8_t c = 0; c < t->count; ++c, v += 2) put16(v, t->period_us[r][c]);
  return frame(out, (uint8_t)MM_LINK_TELEMETRY_BODY(t->readings, t->count));
}

void mm_link_parser_init(mm_link_parser* p) {
  p->state = kWaitSync0;
  p->length = 0;
  p->have = 0;
  p->crc = 0;
  p->raw_len = 0;
  p->pending_head = 0;
  p->pending_len = 0;
  p->crc_errors = 0;
  p->malformed = 0;
}

/* The body's content, once its CRC held: 0 if it is not a valid frame. */
static uint8_t decode(mm_link_parser* p, mm_link_frame* f) {
  const uint8_t* b = p->body;
  const uint8_t type = b[0];
  if (type == MM_LINK_PULSES) {
    const uint8_t count = (uint8_t)(b[10] & 0x0Fu);
    const uint8_t asked = (uint8_t)((b[10] >> 4) & 0x07u);
    const uint8_t request = (b[10] & MM_LINK_TELEMETRY_REQUEST) != 0u ? (uint8_t)(asked + 1u) : 0u;
    if (count < 1u || count > MM_LINK_MAX_CHANNELS || p->length != MM_LINK_PULSES_BODY(count) ||
        (count < 8u && (b[9] >> count) != 0u) || request > count ||
        (request == 0u && asked != 0u)) {
      ++p->malformed;
      return 0;
    }
    mm_link_pulses* out = &f->u.pulses;
    out->session = get32(b + 1);
    out->sequence = get32(b + 5);
    out->armed = b[9];
    out->count = count;
    out->telemetry = request;
    for (uint8_t i = 0; i < count; ++i) out->pulse_hus[i] = get16(b + 11 + 2 * i);
  } else if (type == MM_LINK_CONFIG) {
    const uint8_t count = b[17];
    mm_link_config* out = &f->u.config;
    if (count < 1u || count > MM_LINK_MAX_CHANNELS || p->length != MM_LINK_CONFIG_BODY(count)) {
      ++p->malformed;
      return 0;
    }
    out->session = get32(b + 1);
    out->sequence = get32(b + 5);
    out->period_us = get16(b + 9);
    out->link_timeout_ms = get16(b + 11);
    out->min_us = get16(b + 13);
    out->max_us = get16(b + 15);
    out->count = count;
    out->protocol = b[18];
    for (uint8_t i = 0; i < count; ++i) out->disarmed_us[i] = get16(b + 19 + 2 * i);
    if (!mm_link_config_valid(out)) {
      ++p->malformed;
      return 0;
    }
  } else if (type == MM_LINK_COMMAND && p->length == MM_LINK_COMMAND_BODY) {
    mm_link_command* out = &f->u.command;
    out->session = get32(b + 1);
    out->sequence = get32(b + 5);
    out->command = b[9];
    out->channels = b[10];
    out->repeat = b[11];
    if (!command_valid(out)) {
      ++p->malformed;
      return 0;
    }
  } else if (type == MM_LINK_REPORT && p->length == MM_LINK_REPORT_BODY) {
    mm_link_report* out = &f->u.report;
    out->frames = get32(b + 2);
    out->crc_errors = get32(b + 6);
    out->malformed = get32(b + 10);
    out->link_timeouts = get16(b + 14);
    out->watchdog_resets = get16(b + 16);
    out->rejected = get16(b + 18);
    out->last_sequence = get32(b + 20);
    out->flags = b[24];
    out->session = get32(b + 25);
    out->version = b[29];
  } else if (type == MM_LINK_TELEMETRY && p->length >= MM_LINK_TELEMETRY_BODY(1u, 1u)) {
    mm_link_telemetry* out = &f->u.telemetry;
    out->first = get16(b + 2);
    out->readings = b[4];
    out->count = b[5];
    if (out->readings < 1u || out->readings > MM_LINK_TELEMETRY_MAX_READINGS || out->count < 1u ||
        out->count > MM_LINK_MAX_BIDIR_CHANNELS ||
        p->length != MM_LINK_TELEMETRY_BODY(out->readings, out->count)) {
      ++p->malformed;
      return 0;
    }
    const uint8_t* v = b + 6;
    for (uint8_t r = 0; r < out->readings; ++r)
      for (uint8_t c = 0; c < out->count; ++c, v += 2) out->period_us[r][c] = get16(v);
  } else {
    ++p->malformed;
    return 0;
  }
  f->type = type;
  return type;
}

#define RING_MASK (MM_LINK_PENDING - 1u)

/* The bytes tried since the failed sync, but that sync, go back to the
 * front of the ring, to be searched again before what is queued; if the
 * ring cannot hold them all, the newest queued bytes make room. */
MM_LINK_COLD static void search_again(mm_link_parser* p) {
  const uint8_t again = p->raw_len > 0u ? (uint8_t)(p->raw_len - 1u) : 0u;
  if ((unsigned)again + p->pending_len > MM_LINK_PENDING) {
    p->malformed += (uint32_t)(again + p->pending_len - MM_LINK_PENDING);
    p->pending_len = (uint8_t)(MM_LINK_PENDING - again);
  }
  for (uint8_t i = again; i > 0; --i) {
    p->pending_head = (uint8_t)((p->pending_head - 1u) & RING_MASK);
    p->pending[p->pending_head] = p->raw[i];
  }
  p->pending_len = (uint8_t)(p->pending_len + again);
  p->raw_len = 0;
  p->state = kWaitSync0;
}

/* One byte through the state machine; a completed, valid frame's type or 0. */
static uint8_t step(mm_link_parser* p, uint8_t byte, mm_link_frame* f) {
  switch (p->state) {
    case kWaitSync0:
      if (byte == MM_LINK_SYNC0) {
        p->state = kWaitSync1;
        p->raw[0] = byte;
        p->raw_len = 1;
      }
      return 0;
    case kWaitSync1:
      if (byte == MM_LINK_SYNC1) {
        p->state = kWaitLength;
        p->raw[p->raw_len++] = byte;
      } else if (byte == MM_LINK_SYNC0) {
        p->raw_len = 1; /* this one may be the sync */
      } else {
        p->state = kWaitSync0;
        p->raw_len = 0;
      }
      return 0;
    case kWaitLength:
      p->raw[p->raw_len++] = byte;
      if (byte < 2u || byte > MM_LINK_MAX_BODY) {
        ++p->malformed;
        search_again(p);
        return 0;
      }
      p->length = byte;
      p->have = 0;
      p->crc = crc_step(0xFFFFFFFFu, byte);
      p->state = kBody;
      return 0;
    default:
      break;
  }
  p->raw[p->raw_len++] = byte;
  p->body[p->have++] = byte;
  if (p->have <= p->length) {
    p->crc = crc_step(p->crc, byte);
    return 0;
  }
  if (p->have < p->length + 4u) return 0;
  if (~p->crc != get32(p->body + p->length)) {
    ++p->crc_errors;
    search_again(p);
    return 0;
  }
  p->state = kWaitSync0;
  p->raw_len = 0;
  return decode(p, f);
}

void mm_link_push(mm_link_parser* p, uint8_t byte) {
  if (p->pending_len >= MM_LINK_PENDING) {
    ++p->malformed;
    return;
  }
  p->pending[(uint8_t)((p->pending_head + p->pending_len) & RING_MASK)] = byte;
  ++p->pending_len;
}

uint8_t mm_link_poll(mm_link_parser* p, mm_link_frame* frame) {
  if (p->pending_len == 0) return 0;
  const uint8_t next = p->pending[p->pending_head];
  p->pending_head = (uint8_t)((p->pending_head + 1u) & RING_MASK);
  --p->pending_len;
  return step(p, next, frame);
}

uint8_t mm_link_step(mm_link_parser* p, uint8_t byte, mm_link_frame* frame) {
  if (p->pending_len == 0u) return step(p, byte, frame);
  mm_link_push(p, byte);
  return mm_link_poll(p, frame);
}

uint8_t mm_link_feed(mm_link_parser* p, uint8_t byte, mm_link_frame* frame) {
  mm_link_push(p, byte);
  while (p->pending_len > 0) {
    const uint8_t type = mm_link_poll(p, frame);
    if (type != 0) return type;
  }
  return 0;
}
