/* Servo-style pulses on D2..D9 (CONFIG's protocol 0): every channel rises
 * at the period start and falls at its width, edges written by the pulse
 * interrupt (pulse_isr.S) from schedules the main loop builds. */
#ifndef MOTORMIX_SERVO_PULSES_H
#define MOTORMIX_SERVO_PULSES_H

#include <stdint.h>

#include "motormix_link.h"

/* Every output pin low, the pulse interrupt off. */
void mm_pulses_pins_low(void);
void mm_pulses_stop(void);
/* Disarmed pulses of configuration c from the next period on, the pulse
 * interrupt running (after mm_pulses_stop). */
void mm_pulses_start(const mm_link_config* c);
/* A PULSES frame's widths (half microseconds; disarmed channels at their
 * disarmed width, armed ones within [lo, hi] ticks) from the next period. */
void mm_pulses_take(const mm_link_pulses* p, uint16_t lo, uint16_t hi);
/* Whether an armed frame was taken that the next period will start. */
uint8_t mm_pulses_armed_pending(void);
/* No frame taken counts as armed (DShot configured instead). */
void mm_pulses_forget_armed(void);

#endif /* MOTORMIX_SERVO_PULSES_H */
