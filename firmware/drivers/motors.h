/**
 * \file motors.h
 * Motor driver: duties in permille, limited by settings.motors.pwm_limit, mirrored in robot_state.wheels;
 * tells the encoder driver the direction of each wheel.
 */
#ifndef MOTORS_H
#define MOTORS_H

#include <stdint.h>

void motors_init(void);
/** Sets both duties (permille, clamped to +-settings.motors.pwm_limit). */
void motors_set(int16_t left, int16_t right);

#endif
