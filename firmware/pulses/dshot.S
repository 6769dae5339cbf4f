; DShot frames on port D: every DShot channel (D2..D7) in one frame, by
; writing the whole port three times per bit: all channels high, then the
; channels whose bit is 0 low, then all low. Assembly because DShot is
; timing: each write's cycle is fixed by the instruction count below (the
; bit period and the two high times), with interrupts off for the frame
; (27 us at DShot600, 53 at DShot300, 107 at DShot150, which reads the
; UART itself).
;
; At 16 MHz, cycles per bit, high for a 0, high for a 1 (the protocol:
; 1/rate, 37.5 % and 75 % of it):
;   DShot600: 27 and every third 26 (a frame's mean 26.67, 1.6667 us
;             exact), 10 (0.625 us), 20 (1.25 us)
;   DShot300: 53 and every third 54 (mean 53.33, 3.3333 us exact),
;             20 (1.25 us), 40 (2.5 us)
;   DShot150: 107 (6.6875 us, +0.3 %), 40 (2.5 us), 80 (5.0 us)
; An ESC decides a bit by its high time against half a bit (AM32, Bluejay):
; these are 1.5 (0) and 2.4 (1) tenths of a bit from that threshold.
;
; void mm_dshot_send600(const uint8_t* ports, uint8_t high, uint8_t low);
; (and 300, 150): ports: 16 values of PORTD, the frame's first bit first,
; each with the channels whose bit is 1 high; high: PORTD with every DShot
; channel high; low: with every one low. avr-gcc's convention: ports in
; r25:r24, high in r22, low in r20; r18-r27, r30, r31 are the callee's.
#include <avr/io.h>

; n cycles of nothing (n >= 0): pairs of rjmp .+0 (2 cycles, one word) and
; a nop for an odd count.
.macro DELAY n
  .rept (\n) / 2
  rjmp .+0
  .endr
  .if (\n) % 2
  nop
  .endif
.endm

; One bit of a frame: rise, the 0s' fall at t0h, every fall at t1h, then
; low until `len` cycles after the rise (the next bit's rise; none after the
; last bit, whose low part is the caller's). Per bit: out (1), ld (2),
; DELAY n1, out (1), DELAY n2, out (1), DELAY n3.
.macro DSHOT_BIT t0h, t1h, len, last
  out _SFR_IO_ADDR(PORTD), r22   ; t = 0: every channel high
  ld r19, X+
  DELAY (\t0h - 3)
  out _SFR_IO_ADDR(PORTD), r19   ; t = t0h: the channels sending 0 fall
  DELAY (\t1h - \t0h - 1)
  out _SFR_IO_ADDR(PORTD), r20   ; t = t1h: every channel low
  .if \last == 0
  DELAY (\len - \t1h - 1)
  .endif
.endm

; One sender, its 16 bits unrolled: t0h and t1h the cycles from the rise to
; the falls of a 0 and a 1, `bit` the cycles of most bits and `third` those
; of every third (bits 2, 5, 8, 11, 14): 16 MHz has no whole number of
; cycles within 0.5 % of a DShot600 or DShot300 bit (26.67, 53.33), so ten
; bits of one count and five of the next make the 15 rise-to-rise spans of
; a frame exactly the protocol's (400 and 800 cycles), each bit within one
; cycle of it.
.macro DSHOT_SENDER name, t0h, t1h, bit, third
  .global \name
\name:
  movw r26, r24          ; X: the port values
  in r21, _SFR_IO_ADDR(SREG)
  cli
  .set i, 0
  .rept 15
  .if (i % 3) == 2
  DSHOT_BIT \t0h, \t1h, \third, 0
  .else
  DSHOT_BIT \t0h, \t1h, \bit, 0
  .endif
  .set i, i + 1
  .endr
  DSHOT_BIT \t0h, \t1h, \bit, 1
  out _SFR_IO_ADDR(SREG), r21
  ret
.endm

  .section .text
  DSHOT_SENDER mm_dshot_send600, 10, 20, 27, 26
  DSHOT_SENDER mm_dshot_send300, 20, 40, 53, 54

; uint8_t mm_dshot_send150(const uint8_t* ports, uint8_t high, uint8_t low,
;                          uint8_t* uart);
; A DShot150 frame (107 us) is longer than the chip's receiver holds bytes
; back to back (two byte times, 80 us), so it reads the UART itself once a
; bit, in the same 10 cycles whether a byte came or not, into uart (three
; at most); returns their number in r24. Per bit as the others, with the
; read in the low part:
;   byte:    lds 2, sbrs 2 (skips), lds 2, st 2, rjmp 2
;   no byte: lds 2, sbrs 1, rjmp 2, DELAY 5
; Its error flags are not looked at: the link's CRC-32 finds a bad byte.
  .global mm_dshot_send150
mm_dshot_send150:
  push r28
  push r29
  movw r26, r24          ; X: the port values
  movw r28, r18          ; Y: where the UART's bytes go
  mov r25, r18           ; its start (low byte): the count at the end
  ldi r18, 16
  in r21, _SFR_IO_ADDR(SREG)
  cli
1:
  out _SFR_IO_ADDR(PORTD), r22   ; t = 0: every channel high
  ld r19, X+
  DELAY (40 - 3)
  out _SFR_IO_ADDR(PORTD), r19   ; t = 40: the channels sending 0 fall
  DELAY (80 - 40 - 1)
  out _SFR_IO_ADDR(PORTD), r20   ; t = 80: every channel low
  lds r23, UCSR0A
  sbrs r23, RXC0
  rjmp 2f
  lds r23, UDR0
  st Y+, r23
  rjmp 3f
2:
  DELAY 5
3:
  DELAY (107 - 80 - 4 - 10)
  dec r18
  brne 1b
  out _SFR_IO_ADDR(SREG), r21
  mov r24, r28
  sub r24, r25
  pop r29
  pop r28
  ret

; Port D sampled for bidirectional DShot replies (dshot_reply.c), n
; samples into buffer, interrupts off, as for a frame.
;
; uint8_t mm_dshot_sample600(uint8_t* buffer, uint8_t n);
; buffer in r25:r24, n in r22: one sample every 7 cycles, in (1), st (2),
; DELAY 1, dec (1), brne (2). The window is short enough (72 us) for the
; UART's two bytes.
  .global mm_dshot_sample600
mm_dshot_sample600:
  movw r26, r24
  in r21, _SFR_IO_ADDR(SREG)
  cli
1:
  in r18, _SFR_IO_ADDR(PIND)
  st X+, r18
  DELAY 1
  dec r22
  brne 1b
  out _SFR_IO_ADDR(SREG), r21
  ret

; uint8_t mm_dshot_sample300(uint8_t* buffer, uint8_t n, uint8_t* uart);
; buffer in r25:r24, n in r22, uart in r21:r20; returns in r24 the bytes
; the UART received meanwhile, stored at uart. One sample every 14 cycles,
; the UART read in the same 14 cycles whether a byte came or not, so its
; window (100 us, longer than the UART's two bytes) costs no sample:
;   byte:    in 1, st 2, lds 2, sbrs 2 (skips), lds 2, st 2, dec 1, brne 2
;   no byte: in 1, st 2, lds 2, sbrs 1, rjmp 2, DELAY 3, dec 1, brne 2
; Its error flags are not looked at: the link's CRC-32 finds a bad byte.
  .global mm_dshot_sample300
mm_dshot_sample300:
  push r28
  push r29
  movw r26, r24
  movw r28, r20
  in r23, _SFR_IO_ADDR(SREG)
  cli
1:
  in r18, _SFR_IO_ADDR(PIND)
  st X+, r18
  lds r19, UCSR0A
  sbrs r19, RXC0
  rjmp 2f
  lds r19, UDR0
  st Y+, r19
  dec r22
  brne 1b
  rjmp 3f
2:
  DELAY 3
  dec r22
  brne 1b
3:
  out _SFR_IO_ADDR(SREG), r23
  mov r24, r28
  sub r24, r20
  pop r29
  pop r28
  ret
