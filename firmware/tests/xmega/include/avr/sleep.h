/** \file sleep.h  <avr/sleep.h> for the host model: the SLEEP instruction lets simulated time run to the next
 *  interrupt (sleep mode idle: every peripheral keeps running). */
#ifndef XM_AVR_SLEEP_H
#define XM_AVR_SLEEP_H

#include "avr/io.h"

#define sleep_cpu() xm_sleep()
#define sleep_enable() (SLEEP.CTRL |= SLEEP_SEN_bm)
#define sleep_disable() (SLEEP.CTRL &= (uint8_t)~SLEEP_SEN_bm)
#define set_sleep_mode(mode) (SLEEP.CTRL = (uint8_t)((SLEEP.CTRL & ~SLEEP_SMODE_gm) | (mode)))

#endif
