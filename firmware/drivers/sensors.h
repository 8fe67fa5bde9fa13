/**
 * \file sensors.h
 * Slow sensors: battery voltage, current, MCU temperature, accelerometer and the colour sensor, read in
 * turn (one group per tick) into robot_state; the colour is classified for line following segments.
 */
#ifndef SENSORS_H
#define SENSORS_H

#include <stdint.h>

void sensors_init(void);
void sensors_task(void);

/** Classifies a colour reading (channels 0..255) as PB_COLOUR_*: achromatic readings are white or black
 *  by brightness, chromatic ones by their dominant channel. */
uint8_t sensors_classify(uint8_t r, uint8_t g, uint8_t b, uint8_t clear);

#endif
