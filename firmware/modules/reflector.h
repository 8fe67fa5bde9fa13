/**
 * \file reflector.h
 * The global robot_state (thesis 6.4) and the state reflector that mirrors it to the host: a `state_full`
 * or `state_reduced` packet every settings.sync.period_ms, by settings.sync.mode.
 */
#ifndef REFLECTOR_H
#define REFLECTOR_H

#include <stdint.h>

#include "pb_protocol.h"

extern pb_robot_state_t robot_state;

void reflector_init(void);
/** Sends the state when its period has passed (a full transmit buffer skips it and counts tx_dropped). */
void reflector_task(void);
/** Handles `set_sync`. \return PB_ERROR_CODE_NONE or PB_ERROR_CODE_BAD_ARGUMENT. */
uint8_t reflector_set_sync(uint8_t mode, uint16_t period_ms);

#endif
