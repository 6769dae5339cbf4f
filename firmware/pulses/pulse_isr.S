; The pulse interrupt (Timer1 compare A): writes one edge of every channel's
; pulse per call, or several when they are too close together to leave and
; re-enter between them. Assembly because an edge's time is the number of
; cycles from its compare flag to its port write: each edge is waited for
; here, on compare B set to its tick (a 3-cycle poll), after an entry by
; compare A MM_ENTRY_LEAD_TICKS earlier: a receive interrupt running at
; compare A delays the entry, not the edge. Everything between edges that
; can wait runs in C (mm_isr_period_start).
;
; In a chain of edges waited for here, a byte of the UART is taken before
; an edge far enough from the one before (MM_EDGE_NEXT_TAKE): the receive
; interrupt is held off by the whole chain, which can last over 100 us with
; eight channels, longer than the chip's receiver holds bytes.
;
; An edge in the table: port D value, port B value, the next edge's tick
; (low byte first), flags (pulse_timing.h).
#include <avr/io.h>
#include "pulse_timing.h"
#include "serial.h"

  .section .text
  .global TIMER1_COMPA_vect
TIMER1_COMPA_vect:
  push r0
  in r0, _SFR_IO_ADDR(SREG)
  push r0
  push r1
  clr r1
  push r18
  push r19
  push r20
  push r21
  push r22
  push r23
  push r24
  push r25
  push r26
  push r27
  push r30
  push r31
  lds r30, mm_isr_next
  lds r31, mm_isr_next+1
  ldi r23, (1 << OCF1A) | (1 << OCF1B)
  ld r18, Z+
  ld r19, Z+
  ld r20, Z+
  ld r21, Z+
  ld r22, Z+
wait:
  sbis _SFR_IO_ADDR(TIFR1), OCF1B
  rjmp wait
  out _SFR_IO_ADDR(PORTD), r18
  out _SFR_IO_ADDR(PORTB), r19
  out _SFR_IO_ADDR(TIFR1), r23
  sts OCR1BH, r21
  sts OCR1BL, r20
  sbrs r22, MM_EDGE_NEXT_POLLED
  rjmp not_polled
load_next:
  ld r18, Z+
  ld r19, Z+
  ld r20, Z+
  ld r21, Z+
  ld r22, Z+
  rjmp wait
not_polled:
  sbrc r22, MM_EDGE_NEXT_TAKE
  rjmp take
  ; Leaving: back in at the next edge's tick less the lead.
  movw r24, r20
  subi r24, MM_ENTRY_LEAD_TICKS
  sbci r25, 0
  sts OCR1AH, r25
  sts OCR1AL, r24
  sbrc r22, MM_EDGE_RISE
  rjmp rise
  sbrs r22, MM_EDGE_NEXT_RISE
  rjmp save
  ldi r30, lo8(mm_isr_rise)
  ldi r31, hi8(mm_isr_rise)
save:
  sts mm_isr_next, r30
  sts mm_isr_next+1, r31
  rjmp done
take:
  ; A byte the UART holds into the ring (serial.c's ring_put; its error
  ; flags are not looked at: the link's CRC-32 finds a bad byte). About 25
  ; cycles; an edge with this flag is at least MM_TAKE_GAP_TICKS after the
  ; one before.
  lds r24, UCSR0A
  sbrs r24, RXC0
  rjmp taken
  lds r25, UDR0
  lds r26, mm_serial_rx_head
  mov r24, r26
  inc r24
  andi r24, MM_SERIAL_RX_RING - 1
  lds r27, mm_serial_rx_tail
  cp r24, r27
  breq full
  clr r27
  subi r26, lo8(-(mm_serial_rx))
  sbci r27, hi8(-(mm_serial_rx))
  st X, r25
  sts mm_serial_rx_head, r24
  rjmp taken
full:
  lds r24, mm_serial_rx_lost
  inc r24
  sts mm_serial_rx_lost, r24
taken:
  rjmp load_next
rise:
  call mm_isr_period_start
done:
  pop r31
  pop r30
  pop r27
  pop r26
  pop r25
  pop r24
  pop r23
  pop r22
  pop r21
  pop r20
  pop r19
  pop r18
  pop r1
  pop r0
  out _SFR_IO_ADDR(SREG), r0
  pop r0
  reti
