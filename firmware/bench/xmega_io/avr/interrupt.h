/** \file interrupt.h  ISRs as functions the cycle bench calls (signal handlers: they save what they use and RETI). */
#ifndef BENCH_XMEGA_INTERRUPT_H
#define BENCH_XMEGA_INTERRUPT_H

#include "avr/io.h"

#define ISR(vector, ...) void vector(void) __attribute__((signal, used, externally_visible)); void vector(void)
#define BADISR_vect __vector_default
#define sei() __asm__ __volatile__("sei" ::: "memory")
#define cli() __asm__ __volatile__("cli" ::: "memory")

#endif
