#include "servo_pulses.h"

#include <avr/io.h>

#include "firmware_state.h"
#include "pulse_schedule.h"
#include "pulse_timing.h"

/* ---- shared with the pulse interrupt (pulse_isr.S) ---- */
typedef struct {
  uint8_t port_d;
  uint8_t port_b;
  uint16_t next_at; /* the next edge's tick */
  uint8_t flags;
} mm_isr_edge;
mm_isr_edge mm_isr_rise;
mm_isr_edge mm_isr_active[MM_LINK_MAX_CHANNELS];
mm_isr_edge* volatile mm_isr_next;
void mm_isr_period_start(void);

/* ---- the period, owned by the interrupt once it runs ---- */
static uint16_t g_rise_at; /* tick of the rise just written */
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
      e->next_at = (uint16_t)(start + next->at);
      e->flags = next->take_uart ? (uint8_t)(1u << MM_EDGE_NEXT_TAKE)
                 : next->polled  ? (uint8_t)(1u << MM_EDGE_NEXT_POLLED)
                                 : 0u;
    } else {
      e->next_at = (uint16_t)(start + g_period_ticks);
      e->flags = (uint8_t)(1u << MM_EDGE_NEXT_RISE);
    }
  }
  const uint16_t first = (uint16_t)(start + s->fall[0].at);
  OCR1B = first;
  OCR1A = (uint16_t)(first - MM_ENTRY_LEAD_TICKS);
  /* The interrupt wrote the rise's (meaningless) next ticks before calling
   * here; a match of them in between must not fire the first fall early.
   * The first fall is at least 500 us away, so no real match is lost. */
  TIFR1 = _BV(OCF1A) | _BV(OCF1B);
  mm_isr_next = &mm_isr_active[0];
}

void mm_pulses_pins_low(void) {
  uint8_t d, b;
  mm_rise_ports(MM_LINK_MAX_CHANNELS, &d, &b);
  PORTD = (uint8_t)(PORTD & ~d);
  PORTB = (uint8_t)(PORTB & ~b);
}

void mm_pulses_stop(void) {
  TIMSK1 = 0;
  TIFR1 = _BV(OCF1A) | _BV(OCF1B);
  mm_pulses_pins_low();
}

void mm_pulses_forget_armed(void) {
  for (uint8_t k = 0; k < FRAME_BUFFERS; ++k) g_frame_armed[k] = 0;
}

uint8_t mm_pulses_armed_pending(void) { return g_frame_armed[g_ready]; }

void mm_pulses_start(const mm_link_config* c) {
  uint16_t ticks[MM_LINK_MAX_CHANNELS];
  for (uint8_t k = 0; k < c->count; ++k) ticks[k] = (uint16_t)(c->disarmed_us[k] * MM_TICKS_PER_US);
  mm_schedule_build(ticks, c->count, &g_disarmed);
  for (uint8_t k = 0; k < FRAME_BUFFERS; ++k) {
    g_frame[k] = g_disarmed;
    g_frame_armed[k] = 0;
  }
  g_ready = g_current = 0;
  mm_rise_ports(c->count, &mm_isr_rise.port_d, &mm_isr_rise.port_b);
  mm_isr_rise.flags = (uint8_t)(1u << MM_EDGE_RISE);
  /* The rise's next tick is never used: mm_isr_period_start sets the
   * first fall's compares itself. */
  mm_isr_rise.next_at = 0;
  mm_isr_next = &mm_isr_rise;
  /* The first rise a little ahead; the interrupt takes it from there.
   * (The pulse interrupt is off: the timer's registers are this code's.) */
  g_rise_at = (uint16_t)(TCNT1 + 400u - g_period_ticks);
  const uint16_t rise = (uint16_t)(g_rise_at + g_period_ticks);
  OCR1B = rise;
  OCR1A = (uint16_t)(rise - MM_ENTRY_LEAD_TICKS);
  TIFR1 = _BV(OCF1A) | _BV(OCF1B);
  TIMSK1 = _BV(OCIE1A);
}

void mm_pulses_take(const mm_link_pulses* p, uint16_t lo, uint16_t hi) {
  uint16_t ticks[MM_LINK_MAX_CHANNELS];
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
}
