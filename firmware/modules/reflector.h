/**
 * \file reflector.h
 * The state reflector (thesis 6.4): mirrors the global robot_state (core/data.h) to the host, a `state_full`
 * or `state_reduced` packet every settings.sync.period_ms by settings.sync.mode, and handles `set_sync`.
 */
#ifndef REFLECTOR_H
#define REFLECTOR_H

#include <stdint.h>

/** Starts the period and registers `set_sync`. */
void reflector_init(void);
/** Sends the state when its period has passed (a full transmit buffer skips it and counts tx_dropped). */
void reflector_task(void);
/** Sets the mode and period. \return PB_ERROR_CODE_NONE or PB_ERROR_CODE_BAD_ARGUMENT. */
uint8_t reflector_set_sync(uint8_t mode, uint16_t period_ms);

#endif
