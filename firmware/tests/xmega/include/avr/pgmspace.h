/** \file pgmspace.h  <avr/pgmspace.h> for the host model: LPM reads the production signature row while
 *  NVM.CMD is READ_CALIB_ROW (flash contents are not modelled: program data lives in host memory). */
#ifndef XM_AVR_PGMSPACE_H
#define XM_AVR_PGMSPACE_H

#include "avr/io.h"

#define pgm_read_byte(addr) xm_lpm((uint16_t)(uintptr_t)(addr))

#endif
