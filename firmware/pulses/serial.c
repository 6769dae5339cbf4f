#include "serial.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#define BAUD 250000UL

/* Received bytes (interrupt-driven): the interrupt writes the head, the
 * main loop the tail, one byte each. */
#define RX_RING 64u /* 2.6 ms of the wire: a search after a bad frame */
static uint8_t g_rx[RX_RING];
volatile uint8_t mm_serial_rx_head, mm_serial_rx_tail;
static volatile uint8_t g_rx_lost;

static uint8_t g_tx[MM_LINK_MAX_FRAME];
static uint8_t g_tx_len;
static volatile uint8_t g_tx_at;

void mm_serial_init(void) {
  /* Double speed before the rate: simavr takes the byte time from the
   * rate's write, with the U2X0 it finds then (the chip does not care). */
  UCSR0A = _BV(U2X0);
  UBRR0 = (uint16_t)(F_CPU / (8UL * BAUD) - 1UL);
  UCSR0B = _BV(RXEN0) | _BV(TXEN0);
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
}

static uint8_t interrupt_driven(void) { return (UCSR0B & _BV(RXCIE0)) != 0u; }

void mm_serial_interrupts(uint8_t on) {
  if (on) {
    UCSR0B = (uint8_t)(UCSR0B | _BV(RXCIE0));
  } else {
    /* A frame being sent is finished by the loop. */
    UCSR0B = (uint8_t)(UCSR0B & ~(_BV(RXCIE0) | _BV(UDRIE0)));
  }
}

/* Inlined into the receive interrupt, which then saves only the registers
 * they use: calling a function from it saved every register a call may
 * change, 60 of the 100 cycles a byte cost. */
static inline __attribute__((always_inline)) void ring_put(uint8_t byte) {
  const uint8_t head = mm_serial_rx_head;
  const uint8_t next = (uint8_t)((head + 1u) & (RX_RING - 1u));
  if (next == mm_serial_rx_tail) {
    ++g_rx_lost;
    return;
  }
  g_rx[head] = byte;
  mm_serial_rx_head = next;
}

static inline __attribute__((always_inline)) void take_uart(void) {
  const uint8_t status = UCSR0A;
  if (!(status & _BV(RXC0))) return;
  const uint8_t byte = UDR0;
  if (status & (_BV(FE0) | _BV(DOR0))) ++g_rx_lost; /* a broken or lost byte */
  ring_put(byte);
}

void mm_serial_put(uint8_t byte) { ring_put(byte); }

void mm_serial_take(void) { take_uart(); }

ISR(USART_RX_vect) { take_uart(); }

void mm_serial_read(mm_link_parser* parser) {
  if (!interrupt_driven()) {
    while (UCSR0A & _BV(RXC0)) {
      const uint8_t status = UCSR0A;
      const uint8_t byte = UDR0;
      if (status & (_BV(FE0) | _BV(DOR0))) ++parser->malformed; /* a broken or lost byte */
      mm_link_push(parser, byte);
    }
  }
  uint8_t tail = mm_serial_rx_tail;
  while (tail != mm_serial_rx_head) {
    mm_link_push(parser, g_rx[tail]);
    tail = (uint8_t)((tail + 1u) & (RX_RING - 1u));
    mm_serial_rx_tail = tail;
  }
  if (g_rx_lost) {
    const uint8_t sreg = SREG;
    cli();
    parser->malformed += g_rx_lost;
    g_rx_lost = 0;
    SREG = sreg;
  }
}

uint8_t mm_serial_next(mm_link_parser* parser) {
  const uint8_t tail = mm_serial_rx_tail;
  const uint8_t byte = g_rx[tail];
  mm_serial_rx_tail = (uint8_t)((tail + 1u) & (RX_RING - 1u));
  if (g_rx_lost) {
    const uint8_t sreg = SREG;
    cli();
    parser->malformed += g_rx_lost;
    g_rx_lost = 0;
    SREG = sreg;
  }
  return byte;
}

ISR(USART_UDRE_vect) {
  UDR0 = g_tx[g_tx_at++];
  if (g_tx_at >= g_tx_len) UCSR0B = (uint8_t)(UCSR0B & ~_BV(UDRIE0));
}

uint8_t mm_serial_sending(void) { return g_tx_at < g_tx_len; }

uint8_t* mm_serial_frame(void) { return g_tx; }

void mm_serial_send(uint8_t length) {
  g_tx_len = length;
  g_tx_at = 0;
  if (interrupt_driven()) UCSR0B = (uint8_t)(UCSR0B | _BV(UDRIE0));
}

void mm_serial_poll_send(void) {
  if (UCSR0B & _BV(UDRIE0)) {
    /* The interrupt sends, and the loop helps where it may not have come
     * for a byte while interrupts were off (a frame and its window). */
    const uint8_t sreg = SREG;
    cli();
    if ((UCSR0A & _BV(UDRE0)) && g_tx_at < g_tx_len) {
      UDR0 = g_tx[g_tx_at++];
      if (g_tx_at >= g_tx_len) UCSR0B = (uint8_t)(UCSR0B & ~_BV(UDRIE0));
    }
    SREG = sreg;
  } else if ((UCSR0A & _BV(UDRE0)) && g_tx_at < g_tx_len) {
    /* With pulses the loop alone: no interrupt is touched. */
    UDR0 = g_tx[g_tx_at++];
  }
}
