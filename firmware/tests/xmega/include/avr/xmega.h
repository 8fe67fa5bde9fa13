/** \file xmega.h  _PROTECTED_WRITE for the host model: the CCP signature, then the protected register. */
#ifndef XM_AVR_XMEGA_H
#define XM_AVR_XMEGA_H

#include "avr/io.h"

#define _PROTECTED_WRITE(reg, value)                                                                        \
    do {                                                                                                    \
        CCP = CCP_IOREG_gc;                                                                                 \
        (reg) = (uint8_t)(value);                                                                           \
    } while (0)

#endif
