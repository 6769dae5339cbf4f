/* The firmware's serial port (250000 baud, 8N1): bytes in to the link's
 * parser, frames out.
 *
 * Reception is always by the receive interrupt into a ring: the chip's
 * receiver holds two bytes and a third in its shift register, so a byte
 * must be read within two byte times (80 us) of its arrival while the host
 * sends back to back, and the main loop has turns far longer than that
 * (building a pulse schedule, taking a configuration: 145-180 us). What
 * may hold the interrupt off is bounded instead: the pulse interrupt,
 * which also takes a byte inside its long chains of edges (pulse_isr.S),
 * and a DShot frame or reply window, which read the UART themselves where
 * they are long (dshot.S). The pulse interrupt is entered early enough to
 * wait out a receive interrupt before its edge (pulse_timing.h).
 *
 * Sending is by the loop while pulses run, by the data-register interrupt
 * with bidirectional DShot. */
#ifndef MOTORMIX_SERIAL_H
#define MOTORMIX_SERIAL_H

/* The ring: the receive interrupt (and the pulse interrupt, pulse_isr.S)
 * write the head, the main loop the tail, one byte each. A power of two. */
#define MM_SERIAL_RX_RING 64 /* 2.6 ms of the wire: a search after a bad frame */

#ifndef __ASSEMBLER__
#include <avr/io.h>
#include <stdint.h>

#include "motormix_link.h"

/* The port, its receive interrupt on. */
void mm_serial_init(void);
/* Frames sent by the data-register interrupt (1) or by the loop (0). */
void mm_serial_send_interrupt(uint8_t on);

extern uint8_t mm_serial_rx[MM_SERIAL_RX_RING];
extern volatile uint8_t mm_serial_rx_head, mm_serial_rx_tail;
/* Bytes lost (ring full) or broken (framing, overrun) since the last read. */
extern volatile uint8_t mm_serial_rx_lost;
static inline uint8_t mm_serial_waiting(void) { return mm_serial_rx_head != mm_serial_rx_tail; }
/* With a byte waiting: the oldest byte of the ring. The bytes lost
 * meanwhile go to the parser's malformed count. */
uint8_t mm_serial_next(mm_link_parser* parser);
/* With interrupts off (a frame and its window): the bytes the UART holds,
 * if any, into the ring; a byte read elsewhere into the ring (interrupts
 * off too: the ring's head is the receive interrupt's). */
void mm_serial_take(void);
void mm_serial_put(uint8_t byte);

/* The frame being sent: idle when everything was; a new one is written into
 * mm_serial_frame() (MM_LINK_MAX_FRAME bytes) and started with its length. */
uint8_t mm_serial_sending(void);
uint8_t* mm_serial_frame(void);
void mm_serial_send(uint8_t length);
/* A byte of the frame when the UART has room (the main loop's turn). */
void mm_serial_poll_send(void);

#endif /* __ASSEMBLER__ */
#endif /* MOTORMIX_SERIAL_H */
