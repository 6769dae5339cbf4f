/* DShot on D2..D7 (CONFIG's protocol: 150, 300 or 600): frames sent by the
 * main loop (dshot.S, interrupts off for a frame) at the configured rate,
 * the throttle of each armed channel while the link holds, motor stop (0)
 * otherwise, special commands while every channel is disarmed, and a
 * channel's telemetry request when the host asks. Bidirectional DShot
 * inverts the frames (idle high) and reads every ESC's eRPM reply after
 * each one (dshot_reply.c), batched for the host's TELEMETRY frames. */
#ifndef MOTORMIX_DSHOT_OUT_H
#define MOTORMIX_DSHOT_OUT_H

#include <stdint.h>

#include "motormix_link.h"

extern uint8_t g_dshot;       /* 0: servo pulses; else MM_LINK_PROTOCOL_DSHOT* */
extern uint8_t g_bidir;       /* bidirectional: inverted frames, eRPM replies */
extern uint8_t g_dshot_dirty; /* the next frame's port values are to be made again */
/* The last frame's replies are yet to be decoded. */
extern uint8_t g_replies_waiting;

/* Frames of motor stop from the next one on (the configuration c taken). */
void mm_dshot_start(const mm_link_config* c);
/* A PULSES frame's widths (half microseconds, [lo, hi] ticks) as throttles. */
void mm_dshot_take(const mm_link_pulses* p, uint16_t lo, uint16_t hi);
/* A COMMAND frame, while every channel is disarmed; 0 if refused. */
uint8_t mm_dshot_take_command(const mm_link_command* c);
/* Channels armed by the last PULSES frame. */
uint8_t mm_dshot_armed(void);

/* True when a frame is due now (the schedule then moved on). */
uint8_t mm_dshot_frame_due(uint32_t now);
void mm_dshot_prepare(void);
void mm_dshot_send(void);
void mm_dshot_decode_replies(void);
/* A batch of replies is ready for the host; send it. */
uint8_t mm_dshot_batch_ready(void);
void mm_dshot_send_batch(void);

#endif /* MOTORMIX_DSHOT_OUT_H */
