/* Numbers the pulse interrupt (pulse_isr.S) and its C side share. */
#ifndef MOTORMIX_PULSE_TIMING_H
#define MOTORMIX_PULSE_TIMING_H

/* Flags of an edge in the interrupt's table. */
#define MM_EDGE_NEXT_POLLED 0 /* the next edge is waited for inside the interrupt */
#define MM_EDGE_NEXT_RISE 1   /* the next edge is the next period's rise */
#define MM_EDGE_NEXT_TAKE 2   /* waited for too, a byte of the UART taken first */
#define MM_EDGE_RISE 7        /* this edge is the period's rise */

/* Every edge is written when compare B (set to its tick) matches, waited
 * for inside the interrupt: the same few cycles after its tick for each.
 * The interrupt is entered by compare A this many ticks earlier, enough for
 * a receive interrupt that holds it off (about 70 cycles), the main loop's
 * short sections with interrupts off and its own entry (about 60 cycles):
 * 160 cycles. */
#define MM_ENTRY_LEAD_TICKS 20

#endif /* MOTORMIX_PULSE_TIMING_H */
