#include "serial.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#define BAUD 250000UL

uint8_t mm_serial_rx[MM_SERIAL_RX_RING];
volatile uint8_t mm_serial_rx_head, mm_serial_rx_tail;
volatile uint8_t mm_serial_rx_lost;
static uint8_t g_tx_by_interrupt;

static uint8_t g_tx[MM_LINK_MAX_FRAME];
static uint8_t g_tx_len;
static volatile uint8_t g_tx_at;

void mm_serial_init(void) {
  /* Double speed before the rate: simavr takes the byte time from the
   * rate's write, with the U2X0 it finds then (the chip does not care). */
  UCSR0A = _BV(U2X0);
  UBRR0 = (uint16_t)(F_CPU / (8UL * BAUD) - 1UL);
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
  UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);
}

void mm_serial_send_interrupt(uint8_t on) {
  g_tx_by_interrupt = on;
  /* Off: a frame being sent is finished by the loop. */
  if (!on) UCSR0B = (uint8_t)(UCSR0B & ~_BV(UDRIE0));
}

/* Inlined into the receive interrupt, which then saves only the registers
 * they use: calling a function from it saved every register a call may
 * change, 60 of the 100 cycles a byte cost. */
static inline __attribute__((always_inline)) void ring_put(uint8_t byte) {
  const uint8_t head = mm_serial_rx_head;
  const uint8_t next = (uint8_t)((head + 1u) & (MM_SERIAL_RX_RING - 1u));
  if (next == mm_serial_rx_tail) {
    ++mm_serial_rx_lost;
    return;
  }
  mm_serial_rx[head] = byte;
  mm_serial_rx_head = next;
}

static inline __attribute__((always_inline)) void take_uart(void) {
  const uint8_t status = UCSR0A;
  if (!(status & _BV(RXC0))) return;
  const uint8_t byte = UDR0;
  if (status & (_BV(FE0) | _BV(DOR0))) ++mm_serial_rx_lost; /* a broken or lost byte */
  ring_put(byte);
}

void mm_serial_put(uint8_t byte) { ring_put(byte); }

void mm_serial_take(void) {
  /* Everything the receiver holds (two bytes and one being shifted in). */
  for (uint8_t k = 0; k < 3u; ++k) take_uart();
}

ISR(USART_RX_vect) { take_uart(); }

uint8_t mm_serial_next(mm_link_parser* parser) {
  const uint8_t tail = mm_serial_rx_tail;
  const uint8_t byte = mm_serial_rx[tail];
  mm_serial_rx_tail = (uint8_t)((tail + 1u) & (MM_SERIAL_RX_RING - 1u));
  if (mm_serial_rx_lost) {
    const uint8_t sreg = SREG;
    cli();
    parser->malformed += mm_serial_rx_lost;
    mm_serial_rx_lost = 0;
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
  if (g_tx_by_interrupt) UCSR0B = (uint8_t)(UCSR0B | _BV(UDRIE0));
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
    /* With pulses the loop alone. */
    UDR0 = g_tx[g_tx_at++];
  }
}
