/* Numbers the pulse interrupt (pulse_isr.S) and its C side share. Measured
 * in simavr by test/avr (the widths of edges written on interrupt entry and
 * of edges waited for inside the interrupt agree to within 0.2 us). */
#ifndef MOTORMIX_PULSE_TIMING_H
#define MOTORMIX_PULSE_TIMING_H

/* Flags of an edge in the interrupt's table. */
#define MM_EDGE_NEXT_POLLED 0 /* the next edge is waited for inside the interrupt */
#define MM_EDGE_NEXT_RISE 1   /* the next edge is the next period's rise */
#define MM_EDGE_RISE 7        /* this edge is the period's rise */

/* An edge written on interrupt entry is compared this many ticks early:
 * entering the interrupt (saving registers, loading the edge) takes that
 * long, and MM_ENTRY_DELAY_CYCLES more make it as late, after its tick, as
 * an edge the waiting loop writes. */
#define MM_ENTRY_LEAD_TICKS 7
#define MM_ENTRY_DELAY_CYCLES 7

#endif /* MOTORMIX_PULSE_TIMING_H */
