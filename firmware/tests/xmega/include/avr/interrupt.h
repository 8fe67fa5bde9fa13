/** \file interrupt.h  <avr/interrupt.h> for the host model: interrupt vectors are functions the model calls. */
#ifndef XM_AVR_INTERRUPT_H
#define XM_AVR_INTERRUPT_H

#include "avr/io.h"

/* A vector is a plain function named as avr-libc names it (__vector_N); the model's interrupt controller
 * calls it, with the PMIC's levels and priorities. */
#define ISR(vector, ...) void vector(void); void vector(void)
/* avr-libc routes every vector without a handler to __vector_default when one is defined. */
#define BADISR_vect __vector_default
#define sei() xm_sei()
#define cli() xm_cli()

#endif
