/**
 * \file speed.h
 * Wheel speed by fixed delta-s (thesis 11.5): the period of each encoder pulse from input-capture
 * timestamps, averaged over the two latest pulses (the stripes are unequal), and zero after
 * settings.encoder.speed_timeout_ms without a pulse. Also the distance each wheel travelled, extrapolated
 * inside the current pulse from the speed (finer than one pulse, for stopping precisely).
 * Fixed point: speeds in um/s, distances in um; one integer division per encoder edge.
 */
#ifndef SPEED_H
#define SPEED_H

#include <stdint.h>

void speed_init(void);
/** Updates speeds, counts and robot_state.encoders / wheels.speed_*; call once per main loop tick. */
void speed_task(void);
/** \return the measured speed of `wheel` in um/s (signed). */
int32_t speed_umps(uint8_t wheel);
/** \return the distance `wheel` travelled since reset in um (signed), extrapolated within a pulse. */
int32_t speed_position_um(uint8_t wheel);
/** Both wheels' speed_position_um() at the same instant (the cheaper: both computed in one call). */
void speed_positions_um(int32_t *left, int32_t *right);

/**
 * The fixed delta-s formula with the pulse length of the current settings, exposed for tests.
 * \param p0,p1 the two latest periods (capture ticks), p1 = 0 if unknown
 * \param timeout_ticks periods longer than this mean standstill \return speed magnitude in um/s
 */
int32_t speed_from_periods(uint32_t p0, uint32_t p1, uint32_t timeout_ticks);

#endif
