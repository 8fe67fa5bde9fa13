/**
 * \file speed.h
 * Wheel speed by fixed delta-s (thesis 11.5): the period of each encoder pulse from input-capture
 * timestamps, averaged over the two latest pulses (the stripes are unequal), and zero after
 * settings.encoder.speed_timeout_ms without a pulse. Also the distance each wheel travelled, extrapolated
 * inside the current pulse from the speed (finer than one pulse, for stopping precisely).
 */
#ifndef SPEED_H
#define SPEED_H

#include <stdint.h>

void speed_init(void);
/** Updates speeds, counts and robot_state.encoders / wheels.speed_*; call once per main loop tick. */
void speed_task(void);
/** \return the measured speed of `wheel` in m/s (signed). */
float speed_mps(uint8_t wheel);
/** \return the distance `wheel` travelled since reset in metres (signed), extrapolated within a pulse. */
float speed_distance_m(uint8_t wheel);
/** \return the length of one encoder pulse in metres: pi * wheel diameter / pulses per revolution. */
float speed_pulse_m(void);

/**
 * The fixed delta-s formula, exposed for tests.
 * \param pulse_m pulse length \param p0,p1 the two latest periods (capture ticks), p1 = 0 if unknown
 * \param timeout_ticks periods longer than this mean standstill \return speed magnitude in m/s
 */
float speed_from_periods(float pulse_m, uint32_t p0, uint32_t p1, uint32_t timeout_ticks);

#endif
