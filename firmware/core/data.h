/**
 * \file data.h
 * The ground floor of the firmware: the two global structs every layer may read and write (thesis 6.3, 6.4).
 * `settings` holds every module's settings as the host mirrors them; `robot_state` every sensor and status
 * the state reflector mirrors to the host. Their layout is the wire's (pb_protocol.h). Drivers, modules
 * and the HAL glue include this header, not the modules that manage the structs (modules/settings.h loads,
 * saves and checks writes; modules/reflector.h sends the state).
 */
#ifndef DATA_H
#define DATA_H

#include <stdint.h>

#include "pb_protocol.h"

extern pb_settings_t settings;

/** Incremented whenever settings change; modules cache values derived from settings against it. */
extern uint8_t settings_generation;

extern pb_robot_state_t robot_state;

#endif
