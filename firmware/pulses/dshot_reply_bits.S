; The loops of reading bidirectional DShot replies (dshot_reply.c says how
; a reply is read), in assembly because they are most of the chip's work
; with replies on (four channels every frame).
;
; void mm_reply_falls(const uint8_t* samples, uint8_t pins, uint8_t* falls);
; samples (r25:r24), ending in a sample with every line low; pins (r22):
; the channels' bits of port D (D2..D5); falls (r21:r20): for each channel
; in pins, the index of its first low sample. One pass for all channels,
; 6 cycles a sample (the search per channel took 7 a sample, each).
  .section .text.mm_reply_falls,"ax",@progbits
  .global mm_reply_falls
mm_reply_falls:
  movw r26, r24        ; X: the next sample
  movw r30, r20        ; Z: falls
  movw r18, r24        ; the first sample, for the index
1:
  ld r24, X+
  com r24              ; the lines low
  and r24, r22         ; of the channels not yet found
  breq 1b
  mov r25, r26         ; the index of this sample (low bytes: below 256)
  sub r25, r18
  dec r25
  eor r22, r24         ; found now
  sbrc r24, 2
  std Z+0, r25
  sbrc r24, 3
  std Z+1, r25
  sbrc r24, 4
  std Z+2, r25
  sbrc r24, 5
  std Z+3, r25
  tst r22
  brne 1b
  ret

; The bit loop of a reply: each of the 20 bits after the start bit read in its
; middle, a change of level since the bit before a 1, back in step at every
; change: 12 cycles a bit without a change, about 25 with one, against
; some 26 and 45 for the same steps compiled from C.
;
; void mm_reply_codes(const uint8_t* fall, uint8_t pin, uint8_t* codes);
; fall (r25:r24): the sample where the start bit's fall was first seen;
; pin (r22): the channel's bit of port D; codes (r21:r20): the four 5-bit
; GCR codes, first sent first. The position is a pointer to the whole
; sample (Z) and an 8-bit fraction (r18): a bit is 3 + 12/256 samples; the
; middle of the first bit after a change seen at sample e is e + 1 +
; 134/256 (the constants of dshot_reply.c).
;
; Registers (all the caller's to lose, avr-gcc's convention): Z the
; position, X the codes, r0 the fraction of a bit, r18 the fraction,
; r19 the level, r20 the code being read, r21 the codes left, r22 the
; pin, r23 the samples since the last bit's middle, r24 a sample, r25 the
; last bit's middle (low byte: distances are below 256).
#include <avr/io.h>

#define BIT_WHOLE 3
#define BIT_FRACTION 12
#define FIRST_MID_FRACTION 134

; One bit into r20.
.macro REPLY_BIT
  add r18, r0          ; the fraction, then the whole samples
  brcc 1f
  adiw r30, 1
1:
  adiw r30, BIT_WHOLE
  ld r24, Z
  and r24, r22
  lsl r20
  cp r24, r19
  breq 4f
  ; A change: a 1, and back in step at the first sample of the new level
  ; since the last bit's middle (3 or 4 samples before this one).
  ori r20, 1
  mov r19, r24
  mov r23, r30
  sub r23, r25
  mov r25, r30
  ld r24, -Z           ; one before
  and r24, r22
  cp r24, r19
  brne 2f
  ld r24, -Z           ; two before
  and r24, r22
  cp r24, r19
  brne 2f
  cpi r23, 4           ; three before only if the last middle was further
  brlo 3f
  ld r24, -Z
  and r24, r22
  cp r24, r19
  brne 2f
  rjmp 3f
2:
  adiw r30, 1          ; Z was at the last sample of the old level
3:
  adiw r30, 1          ; the first of the new one + 1: this bit's middle
  ldi r18, FIRST_MID_FRACTION
  rjmp 5f
4:
  mov r25, r30
5:
.endm

  .section .text.mm_reply_codes,"ax",@progbits
  .global mm_reply_codes
mm_reply_codes:
  movw r30, r24
  mov r25, r30         ; the start bit's fall is the last change seen
  adiw r30, 1
  movw r26, r20
  ldi r18, FIRST_MID_FRACTION
  clr r19              ; low: the start bit
  ldi r24, BIT_FRACTION
  mov r0, r24
  ldi r21, 4
6:
  clr r20
  REPLY_BIT
  REPLY_BIT
  REPLY_BIT
  REPLY_BIT
  REPLY_BIT
  st X+, r20
  dec r21
  breq 7f
  rjmp 6b
7:
  ret
