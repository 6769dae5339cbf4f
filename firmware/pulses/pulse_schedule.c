#include "pulse_schedule.h"

void mm_channel_bits(uint8_t channel, uint8_t* port_d_bit, uint8_t* port_b_bit) {
  *port_d_bit = (uint8_t)(channel < 6u ? 1u << (channel + 2u) : 0u);
  *port_b_bit = (uint8_t)((channel >= 6u && channel < 8u) ? 1u << (channel - 6u) : 0u);
}

void mm_rise_ports(uint8_t count, uint8_t* port_d, uint8_t* port_b) {
  uint8_t d = 0, b = 0;
  for (uint8_t k = 0; k < count; ++k) {
    uint8_t bd, bb;
    mm_channel_bits(k, &bd, &bb);
    d |= bd;
    b |= bb;
  }
  *port_d = d;
  *port_b = b;
}

void mm_schedule_build(const uint16_t* width_ticks, uint8_t count, mm_schedule* out) {
  uint8_t order[MM_LINK_MAX_CHANNELS];
  if (count > MM_LINK_MAX_CHANNELS) count = MM_LINK_MAX_CHANNELS;
  for (uint8_t k = 0; k < count; ++k) {
    /* Insertion sort by width: at most eight. */
    uint8_t j = k;
    while (j > 0 && width_ticks[order[j - 1u]] > width_ticks[k]) {
      order[j] = order[j - 1u];
      --j;
    }
    order[j] = k;
  }
  uint8_t d, b;
  mm_rise_ports(count, &d, &b);
  out->n = 0;
  uint16_t last_at = 0;
  uint8_t i = 0;
  while (i < count) {
    const uint16_t first = width_ticks[order[i]];
    uint16_t last = first;
    while (i < count && width_ticks[order[i]] <= first + 2u) {
      last = width_ticks[order[i]];
      uint8_t bd, bb;
      mm_channel_bits(order[i], &bd, &bb);
      d = (uint8_t)(d & ~bd);
      b = (uint8_t)(b & ~bb);
      ++i;
    }
    /* The middle (the later tick of two), or MM_MIN_GAP_TICKS after the
     * group before: the group before fell at most one tick after its
     * shortest, which is at least 3 ticks before this one's, so either way
     * every width here is within one tick. */
    uint16_t at = (uint16_t)(first + (last - first + 1u) / 2u);
    if (out->n > 0 && at < last_at + MM_MIN_GAP_TICKS) at = (uint16_t)(last_at + MM_MIN_GAP_TICKS);
    mm_fall* f = &out->fall[out->n++];
    f->at = at;
    f->port_d = d;
    f->port_b = b;
    const uint16_t gap = (uint16_t)(at - last_at);
    f->polled = (uint8_t)(out->n > 1u && gap < MM_POLL_GAP_TICKS);
    f->take_uart = (uint8_t)(f->polled && gap >= MM_TAKE_GAP_TICKS);
    last_at = at;
  }
}
