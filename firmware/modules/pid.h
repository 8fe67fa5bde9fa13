/**
 * \file pid.h
 * Discrete PID controller (thesis 11.2.1): u = kp*e + ki*sum(e) + kd*(e - e_prev), the sum clamped to
 * +-i_limit and the output to +-out_limit. Non-finite or absurd inputs cannot make the output non-finite.
 */
#ifndef PID_H
#define PID_H

#include <stdint.h>

#include "pb_protocol.h"

/** Largest error magnitude a controller accepts; larger ones are clamped (keeps every term finite). */
#define PID_ERROR_LIMIT 1.0e6f

typedef struct {
    float sum;
    float prev;
    uint8_t primed; /**< prev is valid */
} pid_state_t;

void pid_reset(pid_state_t *s);

/** One controller step. \param gains from settings \param e the error \param out_limit output clamp
 *  \return the clamped output */
float pid_update(pid_state_t *s, const pb_pid_t *gains, float e, float out_limit);

/** \return `v` clamped to +-limit; NaN gives 0. */
float pid_clamp(float v, float limit);

#endif
