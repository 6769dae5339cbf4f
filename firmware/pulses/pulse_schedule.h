/* Where each channel's pulse falls, as the pulse interrupt needs it: the
 * falling edges of one period in time order, channels that fall together
 * in one edge, each edge with the two port values it writes. Pure C99 (no
 * AVR header), so the host's tests build the same schedules.
 *
 * Every channel rises at the period start; channel k is on Arduino pin
 * D(2+k): PD2..PD7, then PB0 and PB1. Time is Timer1 at clk/8: two ticks per
 * microsecond at 16 MHz.
 *
 * Edges the interrupt cannot leave and re-enter between are waited for
 * inside it (polled). Its waiting loop writes edges at least
 * MM_MIN_GAP_TICKS apart, so widths closer than that are grouped: a group
 * holds the widths within 2 ticks of its shortest, falls at their middle,
 * and comes at least MM_MIN_GAP_TICKS after the group before. No channel
 * then falls more than one tick (0.5 us) from its width. */
#ifndef MOTORMIX_PULSE_SCHEDULE_H
#define MOTORMIX_PULSE_SCHEDULE_H

#include <stdint.h>

#include "motormix_link.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MM_TICKS_PER_US 2u
/* The shortest time between two edges the interrupt's waiting loop writes
 * one after the other (its loop takes 22 cycles: 3 ticks are 24). */
#define MM_MIN_GAP_TICKS 3u
/* Edges closer than this to the one before are waited for inside the
 * interrupt rather than by leaving it and being called again (leaving and
 * entering again, MM_ENTRY_LEAD_TICKS before the edge, with a receive
 * interrupt in between: about 12 us). */
#define MM_POLL_GAP_TICKS 32u
/* An edge waited for inside the interrupt this far from the one before has
 * the UART looked at first (a byte into the ring, some 30 cycles with the
 * way there): a chain of edges then holds the UART unread for at most
 * seven gaps shorter than this (28 us), not for the whole chain. */
#define MM_TAKE_GAP_TICKS 8u

typedef struct {
  uint16_t at;    /* ticks after the period start */
  uint8_t port_d; /* PORTD and PORTB once this edge is written */
  uint8_t port_b;
  uint8_t polled;    /* 1: waited for inside the interrupt */
  uint8_t take_uart; /* polled, and a UART byte taken before it */
} mm_fall;

typedef struct {
  uint8_t n;
  mm_fall fall[MM_LINK_MAX_CHANNELS];
} mm_schedule;

/* The port bits of channels 0..count-1 (both 0 for a channel past 7). */
void mm_channel_bits(uint8_t channel, uint8_t* port_d_bit, uint8_t* port_b_bit);
void mm_rise_ports(uint8_t count, uint8_t* port_d, uint8_t* port_b);

/* The falls for widths in ticks (count 1..MM_LINK_MAX_CHANNELS). */
void mm_schedule_build(const uint16_t* width_ticks, uint8_t count, mm_schedule* out);

#ifdef __cplusplus
}
#endif

#endif /* MOTORMIX_PULSE_SCHEDULE_H */
