#include "pid.h"

#include <string.h>

/* Software floats are slow on the AVR (a compare costs as much as 40 integer instructions); IEEE 754
 * magnitudes order like their bit patterns, so clamps compare integers. */
static uint32_t magnitude_bits(float v)
{
    uint32_t b;
    memcpy(&b, &v, sizeof b);
    return b & 0x7FFFFFFFul;
}

#define NAN_OR_INF_BITS 0x7F800000ul

void pid_reset(pid_state_t *s)
{
    s->sum = 0.0f;
    s->prev = 0.0f;
    s->primed = 0;
}

float pid_clamp(float v, float limit)
{
    uint32_t m = magnitude_bits(v);
    if (m > NAN_OR_INF_BITS) /* NaN */
        return 0.0f;
    if (m > magnitude_bits(limit))
        return v < 0.0f ? -limit : limit;
    return v;
}

float pid_update(pid_state_t *s, const pb_pid_t *g, float e, float out_limit)
{
    e = pid_clamp(e, PID_ERROR_LIMIT);
    /* settings_write() keeps the gains and i_limit within 0..1e6, so every term stays finite. */
    float u = g->kp * e;
    if (magnitude_bits(g->ki) != 0) {
        s->sum = pid_clamp(s->sum + e, g->i_limit);
        u += g->ki * s->sum;
    }
    if (magnitude_bits(g->kd) != 0 && s->primed)
        u += g->kd * (e - s->prev);
    s->prev = e;
    s->primed = 1;
    return pid_clamp(u, out_limit);
}
