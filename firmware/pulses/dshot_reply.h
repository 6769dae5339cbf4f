/* Bidirectional DShot on the chip: after each (inverted) frame the DShot
 * pins are released to the ESCs, port D is sampled for every motor's eRPM
 * reply at once, and the replies are decoded one channel at a time from
 * the main loop. Numbers and their reasons in dshot_reply.c. */
#ifndef MOTORMIX_DSHOT_REPLY_H
#define MOTORMIX_DSHOT_REPLY_H

#include <stdint.h>

/* Samples of port D a capture holds. */
#define MM_REPLY_SAMPLES 165u

/* Right after a frame, with interrupts still off: releases `pins` (port
 * D bits, idle high) to the ESCs, samples port D for the replies (speed:
 * MM_LINK_PROTOCOL_DSHOT300 or 600) and drives the pins high again. poll()
 * takes the bytes the UART holds (before and after the window); take()
 * each byte the window itself read (DShot300). */
void mm_reply_capture(uint8_t speed, uint8_t pins, void (*poll)(void), void (*take)(uint8_t byte));

/* Where each reply of the last capture starts, with interrupts on (a pass
 * over every sample: too long to hold the UART's interrupt off). Once per
 * capture, before mm_reply_decode. */
void mm_reply_find_starts(void);

/* The reply of a channel (0..3: D2..D5) in the last capture: the eRPM
 * period in microseconds (mantissa << exponent), or MM_LINK_NO_REPLY. */
uint16_t mm_reply_decode(uint8_t channel);

#endif /* MOTORMIX_DSHOT_REPLY_H */
