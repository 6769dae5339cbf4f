/* Bidirectional DShot on the chip: after each (inverted) frame the DShot
 * pins are released to the ESCs, port D is sampled for every motor's eRPM
 * reply at once, and the replies are decoded one channel at a time from
 * the main loop. Numbers and their reasons in dshot_reply.c. */
#ifndef MOTORMIX_DSHOT_REPLY_H
#define MOTORMIX_DSHOT_REPLY_H

#include <stdint.h>

/* Samples of port D a capture holds. */
#define MM_REPLY_SAMPLES 165u

/* Releases `pins` (port D bits, idle high) to the ESCs right after a
 * frame, waits for the replies to start, samples port D for the window
 * (speed: MM_LINK_PROTOCOL_DSHOT300 or 600) and drives the pins high
 * again, then finds where each channel's line changed (the costly part,
 * about 100 us for all of them). drain() is called while waiting and after
 * the window; take() with each byte the UART received during a window that
 * read it (DShot300). */
void mm_reply_capture(uint8_t speed, uint8_t pins, void (*drain)(void), void (*take)(uint8_t byte));

/* The reply of a channel (0..3: D2..D5) in the last capture: the eRPM
 * period in microseconds (mantissa << exponent), or MM_LINK_NO_REPLY. */
uint16_t mm_reply_decode(uint8_t channel);

#endif /* MOTORMIX_DSHOT_REPLY_H */
