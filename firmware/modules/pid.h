/**
 * \file pid.h
 * Discrete PID controller (thesis 11.2.1) in fixed point: u = kp*e + ki*sum(e) + kd*(e - e_prev), the sum
 * clamped to +-i_limit and the output to +-out_limit. Errors are integers in the caller's unit (um/s, um,
 * permille); the output is Q16 of the caller's output unit (16 fractional bits). The integral is kept as
 * ki*sum(e) in output units, clamped to ki*i_limit (the same as clamping the sum while ki is constant),
 * so it never needs more range than the output. Every operation saturates: no input makes it wrap.
 */
#ifndef PID_H
#define PID_H

#include <stdint.h>

#include "core/fixed.h"
#include "pb_protocol.h"

/** Largest error magnitude a controller accepts; larger ones are clamped (so e - e_prev cannot overflow). */
#define PID_ERROR_LIMIT ((1L << 30) - 1)
/** Fractional bits of the output. */
#define PID_Q 16

/** Gains converted from the float settings (pid_gains_convert()), in the controller's units. */
typedef struct {
    fx_gain_t kp, ki, kd;
    int32_t i_limit; /**< clamp of the integral term ki*sum(e), output Q16 */
} pid_gains_t;

typedef struct {
    int32_t i;      /**< integral term ki*sum(e), output Q16 */
    int32_t prev;   /**< previous error */
    uint8_t primed; /**< prev is valid */
} pid_state_t;

/**
 * Converts gains from settings (SI units); done when settings change, the only float arithmetic here.
 * \param err_per_si error units per SI unit of the error (1e6 for an error in um/s and gains per m/s)
 * \param out_per_si output units per SI unit of the output (1 for permille, 1000 for mm/s from m/s)
 */
void pid_gains_convert(pid_gains_t *out, const pb_pid_t *g, float err_per_si, float out_per_si);

void pid_reset(pid_state_t *s);

/** One controller step. \param e the error \param out_limit output clamp, Q16 (>= 0)
 *  \return the clamped output, Q16. */
int32_t pid_update(pid_state_t *s, const pid_gains_t *g, int32_t e, int32_t out_limit);

#endif
