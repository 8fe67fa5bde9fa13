#include "pid.h"

#define Q_SCALE 65536.0f /* 2^PID_Q */

void pid_gains_convert(pid_gains_t *out, const pb_pid_t *g, float err_per_si, float out_per_si)
{
    float scale = out_per_si * Q_SCALE;
    float per_err = scale / err_per_si;
    out->kp = fx_gain(g->kp * per_err);
    out->ki = fx_gain(g->ki * per_err);
    out->kd = fx_gain(g->kd * per_err);
    /* ki * i_limit is in output units whatever the error unit; saturates like the output would. */
    float lim = g->ki * g->i_limit * scale;
    out->i_limit = !(lim > 0.0f) ? 0 : lim < 2147483520.0f ? (int32_t)(lim + 0.5f) : FX_MAX;
}

void pid_reset(pid_state_t *s)
{
    s->i = 0;
    s->prev = 0;
    s->primed = 0;
}

/* Out of line: inlined into each of its four callers it took 5 kB of flash, for about 150 cycles a call saved. */
int32_t pid_update(pid_state_t *s, const pid_gains_t *g, int32_t e, int32_t out_limit)
{
    e = fx_clamp(e, PID_ERROR_LIMIT);
    int32_t u = fx_mul(e, &g->kp);
    if (g->ki.m) {
        s->i = fx_clamp(fx_add(s->i, fx_mul(e, &g->ki)), g->i_limit);
        u = fx_add(u, s->i);
    }
    if (g->kd.m && s->primed)
        u = fx_add(u, fx_mul(e - s->prev, &g->kd)); /* both within +-2^30: no overflow */
    s->prev = e;
    s->primed = 1;
    return fx_clamp(u, out_limit);
}

