#include <float.h>
#include <math.h>

#include "harness.h"
#include "modules/pid.h"

static void proportional_integral_derivative_terms(void)
{
    pb_pid_t g = {2.0f, 0.5f, 1.0f, 10.0f};
    pid_state_t s;
    pid_reset(&s);
    float u = pid_update(&s, &g, 1.0f, 1000.0f); /* 2*1 + 0.5*1 + 0 (no previous error) */
    CHECK(fabsf(u - 2.5f) < 1e-6f, "first step %f", u);
    u = pid_update(&s, &g, 3.0f, 1000.0f); /* 6 + 0.5*4 + 1*(3-1) */
    CHECK(fabsf(u - 10.0f) < 1e-6f, "second step %f", u);
}

static void integral_and_output_are_clamped(void)
{
    pb_pid_t g = {0.0f, 1.0f, 0.0f, 5.0f};
    pid_state_t s;
    pid_reset(&s);
    for (int i = 0; i < 100; i++)
        pid_update(&s, &g, 1.0f, 1000.0f);
    CHECK(s.sum == 5.0f, "sum %f", s.sum);
    float u = pid_update(&s, &g, -1.0f, 1000.0f);
    CHECK(u == 4.0f, "unwinds at once %f", u);
    pb_pid_t big = {100000.0f, 100000.0f, 100000.0f, 1000000.0f};
    pid_reset(&s);
    u = pid_update(&s, &big, 1.0f, 1000.0f);
    CHECK(u == 1000.0f, "output clamp %f", u);
    u = pid_update(&s, &big, -1.0f, 1000.0f);
    CHECK(u == -1000.0f || u == 1000.0f, "clamped %f", u);
}

static void extreme_inputs_stay_finite(void)
{
    pb_pid_t big = {100000.0f, 100000.0f, 100000.0f, 1000000.0f};
    pid_state_t s;
    pid_reset(&s);
    float inputs[] = {FLT_MAX, -FLT_MAX, INFINITY, -INFINITY, NAN, 1e-45f, -0.0f, 3e38f, -3e38f};
    for (unsigned i = 0; i < sizeof inputs / sizeof inputs[0]; i++) {
        float u = pid_update(&s, &big, inputs[i], 1000.0f);
        CHECK(isfinite(u) && fabsf(u) <= 1000.0f, "input %u gives %f", i, u);
        CHECK(isfinite(s.sum) && isfinite(s.prev), "state finite after input %u", i);
    }
    CHECK(pid_clamp(NAN, 5.0f) == 0.0f, "NaN clamps to 0");
}

void suite_pid(void)
{
    RUN(proportional_integral_derivative_terms);
    RUN(integral_and_output_are_clamped);
    RUN(extreme_inputs_stay_finite);
}
