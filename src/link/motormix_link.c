#include "motormix_link.h"

enum { kWaitSync0 = 0, kWaitSync1 = 1, kWaitLength = 2, kBody = 3 };

uint32_t mm_link_crc32(uint32_t crc, const uint8_t* data, size_t len) {
  /* Bitwise, reflected polynomial 0xEDB88320: no 1 KiB table in the
   * ATmega328P's 2 KiB of RAM. */
  crc = ~crc;
  for (size_t i = 0; i < len; ++i) {
    crc ^= data[i];
    for (int b = 0; b < 8; ++b) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
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

size_t mm_link_encode_pulses(const mm_link_pulses* p, uint8_t* out) {
  if (p->count < 1u || p->count > MM_LINK_MAX_CHANNELS) return 0;
  uint8_t* b = out + 3;
  b[0] = MM_LINK_PULSES;
  b[1] = p->sequence;
  b[2] = p->armed ? 1u : 0u;
  b[3] = p->count;
  for (uint8_t i = 0; i < p->count; ++i) put16(b + 4 + 2 * i, p->pulse_us[i]);
  return frame(out, (uint8_t)(4u + 2u * p->count));
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
  b[18] = r->last_sequence;
  return frame(out, 19u);
}

void mm_link_parser_init(mm_link_parser* p) {
  p->state = kWaitSync0;
  p->length = 0;
  p->have = 0;
  p->raw_len = 0;
  p->pending_len = 0;
  p->crc_errors = 0;
  p->malformed = 0;
}

/* The body's content, once its CRC held: 0 if it is not a valid frame. */
static uint8_t decode(mm_link_parser* p, mm_link_pulses* pulses, mm_link_report* report) {
  const uint8_t* b = p->body;
  const uint8_t type = b[0];
  if (type == MM_LINK_PULSES) {
    const uint8_t count = b[3];
    if (count < 1u || count > MM_LINK_MAX_CHANNELS || p->length != 4u + 2u * count || b[2] > 1u) {
      ++p->malformed;
      return 0;
    }
    if (pulses) {
      pulses->sequence = b[1];
      pulses->armed = b[2];
      pulses->count = count;
      for (uint8_t i = 0; i < count; ++i) pulses->pulse_us[i] = get16(b + 4 + 2 * i);
    }
    return type;
  }
  if (type == MM_LINK_REPORT && p->length == 19u) {
    if (report) {
      report->frames = get32(b + 2);
      report->crc_errors = get32(b + 6);
      report->malformed = get32(b + 10);
      report->link_timeouts = get16(b + 14);
      report->watchdog_resets = get16(b + 16);
      report->last_sequence = b[18];
    }
    return type;
  }
  ++p->malformed;
  return 0;
}

/* The bytes tried since the failed sync, but that sync, go back to be
 * searched again, ahead of whatever is still pending. */
static void search_again(mm_link_parser* p) {
  const uint8_t again = p->raw_len > 0u ? (uint8_t)(p->raw_len - 1u) : 0u;
  uint8_t keep = p->pending_len;
  if ((unsigned)again + keep > sizeof p->pending) keep = (uint8_t)(sizeof p->pending - again);
  for (uint8_t i = keep; i > 0; --i) p->pending[again + i - 1u] = p->pending[i - 1u];
  for (uint8_t i = 0; i < again; ++i) p->pending[i] = p->raw[1u + i];
  p->pending_len = (uint8_t)(again + keep);
  p->raw_len = 0;
  p->state = kWaitSync0;
}

/* One byte through the state machine; a completed, valid frame's type or 0. */
static uint8_t step(mm_link_parser* p, uint8_t byte, mm_link_pulses* pulses,
                    mm_link_report* report) {
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
      p->state = kBody;
      return 0;
    default:
      break;
  }
  p->raw[p->raw_len++] = byte;
  p->body[p->have++] = byte;
  if (p->have < p->length + 4u) return 0;
  const uint32_t crc = mm_link_crc32(mm_link_crc32(0, &p->length, 1u), p->body, p->length);
  if (crc != get32(p->body + p->length)) {
    ++p->crc_errors;
    search_again(p);
    return 0;
  }
  p->state = kWaitSync0;
  p->raw_len = 0;
  return decode(p, pulses, report);
}

uint8_t mm_link_feed(mm_link_parser* p, uint8_t byte, mm_link_pulses* pulses,
                     mm_link_report* report) {
  if (p->pending_len < sizeof p->pending) {
    p->pending[p->pending_len++] = byte;
  } else {
    ++p->malformed; /* cannot happen: each search takes a byte off */
  }
  while (p->pending_len > 0) {
    const uint8_t next = p->pending[0];
    for (uint8_t i = 1; i < p->pending_len; ++i) p->pending[i - 1u] = p->pending[i];
    --p->pending_len;
    const uint8_t type = step(p, next, pulses, report);
    if (type != 0) return type;
  }
  return 0;
}
