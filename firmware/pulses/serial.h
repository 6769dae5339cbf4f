/* The firmware's serial port (250000 baud, 8N1): bytes in to the link's
 * parser, frames out. Polled while pulses run (nothing but the pulse
 * interrupt may delay an edge); with bidirectional DShot, where no pulse
 * interrupt runs and decoding the replies takes longer than the UART holds
 * bytes (two, 80 us), its receive interrupt fills a ring and its
 * data-register interrupt sends. */
#ifndef MOTORMIX_SERIAL_H
#define MOTORMIX_SERIAL_H

#include <avr/io.h>
#include <stdint.h>

#include "motormix_link.h"

void mm_serial_init(void);
/* Interrupt-driven (1) or polled (0); bytes already in the ring stay. */
void mm_serial_interrupts(uint8_t on);

/* A byte waits to go to the parser. Inline: the main loop asks each turn,
 * and with pulses a turn must stay short enough for the UART's bytes. */
extern volatile uint8_t mm_serial_rx_head, mm_serial_rx_tail;
static inline uint8_t mm_serial_waiting(void) {
  return (UCSR0B & _BV(RXCIE0)) ? mm_serial_rx_head != mm_serial_rx_tail
                                : (UCSR0A & _BV(RXC0)) != 0u;
}
/* Every byte received into the parser (a byte lost or broken counted as
 * malformed there). */
void mm_serial_read(mm_link_parser* parser);
/* Interrupt-driven only, with a byte waiting: the oldest byte of the ring.
 * The bytes the ring lost meanwhile go to the parser's malformed count. */
uint8_t mm_serial_next(mm_link_parser* parser);
/* With interrupts off (a frame and its window): the byte the UART holds,
 * if any, into the ring; a byte read elsewhere into the ring. */
void mm_serial_take(void);
void mm_serial_put(uint8_t byte);

/* The frame being sent: idle when everything was; a new one is written into
 * mm_serial_frame() (MM_LINK_MAX_FRAME bytes) and started with its length. */
uint8_t mm_serial_sending(void);
uint8_t* mm_serial_frame(void);
void mm_serial_send(uint8_t length);
/* A byte of the frame when the UART has room (the main loop's turn). */
void mm_serial_poll_send(void);

#endif /* MOTORMIX_SERIAL_H */
