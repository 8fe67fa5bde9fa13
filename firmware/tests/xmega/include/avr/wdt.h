/** \file wdt.h  The WDR instruction for the host model (the HAL configures WDT.CTRL itself). */
#ifndef XM_AVR_WDT_H
#define XM_AVR_WDT_H

#include "avr/io.h"

#define wdt_reset() xm_wdr()

#endif
