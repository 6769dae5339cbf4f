; The pulse interrupt (Timer1 compare A): writes one edge of every channel's
; pulse per call, or several when they are too close together to leave and
; re-enter between them. Assembly because an edge's time is the number of
; cycles from the compare match to its port write: entered here, it is a
; fixed count; waited for in the loop, it is the compare flag's 3-cycle poll.
; Everything between edges that can wait runs in C (mm_isr_period_start).
;
; An edge in the table: port D value, port B value, the compare for the edge
; after it (absolute, low byte first), flags (pulse_timing.h).
#include <avr/io.h>
#include "pulse_timing.h"

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
  ldi r23, (1 << OCF1A)
  ld r18, Z+
  ld r19, Z+
  ld r20, Z+
  ld r21, Z+
  ld r22, Z+
  .rept MM_ENTRY_DELAY_CYCLES
  nop
  .endr
  rjmp edge
wait:
  sbis _SFR_IO_ADDR(TIFR1), OCF1A
  rjmp wait
edge:
  out _SFR_IO_ADDR(PORTD), r18
  out _SFR_IO_ADDR(PORTB), r19
  out _SFR_IO_ADDR(TIFR1), r23
  sts OCR1AH, r21
  sts OCR1AL, r20
  sbrs r22, MM_EDGE_NEXT_POLLED
  rjmp not_polled
  ld r18, Z+
  ld r19, Z+
  ld r20, Z+
  ld r21, Z+
  ld r22, Z+
  rjmp wait
not_polled:
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
