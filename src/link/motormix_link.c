#include "motormix_link.h"

enum { kWaitSync0 = 0, kWaitSync1 = 1, kWaitLength = 2, kBody = 3 };

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
  if (c->protocol > MM_LINK_PROTOCOL_DSHOT600) return 0;
  const int dshot = c->protocol != MM_LINK_PROTOCOL_PWM;
  if (dshot && c->count > MM_LINK_MAX_DSHOT_CHANNELS) return 0;
  if (c->period_us < (dshot ? MM_LINK_MIN_DSHOT_PERIOD_US : MM_LINK_MIN_PERIOD_US) ||
      c->period_us > MM_LINK_MAX_PERIOD_US)
    return 0;
  if (c->link_timeout_ms < MM_LINK_MIN_TIMEOUT_MS || c->link_timeout_ms > MM_LINK_MAX_TIMEOUT_MS)
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
  b[9] = p->armed;
  b[10] = p->count;
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
    const uint8_t count = b[10];
    if (count < 1u || count > MM_LINK_MAX_CHANNELS || p->length != MM_LINK_PULSES_BODY(count) ||
        (count < 8u && (b[9] >> count) != 0u)) {
      ++p->malformed;
      return 0;
    }
    mm_link_pulses* out = &f->u.pulses;
    out->session = get32(b + 1);
    out->sequence = get32(b + 5);
    out->armed = b[9];
    out->count = count;
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
static void search_again(mm_link_parser* p) {
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

uint8_t mm_link_feed(mm_link_parser* p, uint8_t byte, mm_link_frame* frame) {
  mm_link_push(p, byte);
  while (p->pending_len > 0) {
    const uint8_t type = mm_link_poll(p, frame);
    if (type != 0) return type;
  }
  return 0;
}
