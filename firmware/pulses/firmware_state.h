/* What the pulse firmware's units share (main.c owns it): the host's
 * configuration, the link's report and state, the output period, and the
 * 32-bit tick clock. */
#ifndef MOTORMIX_FIRMWARE_STATE_H
#define MOTORMIX_FIRMWARE_STATE_H

#include <stdint.h>

#include "motormix_link.h"

extern mm_link_config g_config;
extern uint8_t g_configured;
extern mm_link_report g_report;
/* The output period, in Timer1 ticks. */
extern uint16_t g_period_ticks;
/* Periods (or DShot frames) begun: the watchdog's sign of life. */
extern volatile uint8_t g_periods;
/* 0: disarmed outputs, whatever the frames said. */
extern volatile uint8_t g_link_ok;
extern volatile uint8_t g_out_armed;

/* Timer1 extended to 32 bits (the loop runs far more often than it wraps). */
uint32_t mm_now_ticks(void);

#endif /* MOTORMIX_FIRMWARE_STATE_H */
