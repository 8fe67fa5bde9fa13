#include <math.h>
#include <stdint.h>

#include "core/fixed.h"
#include "harness.h"
#include "modules/pid.h"

#define Q(x) ((int32_t)((x) * 65536.0))

/* Gains in output units per error unit (err_per_si = out_per_si = 1). */
static pid_gains_t gains(float kp, float ki, float kd, float i_limit)
{
    pb_pid_t g = {kp, ki, kd, i_limit};
    pid_gains_t k;
    pid_gains_convert(&k, &g, 1.0f, 1.0f);
    return k;
}

static void proportional_integral_derivative_terms(void)
{
    pid_gains_t g = gains(2.0f, 0.5f, 1.0f, 10.0f);
    pid_state_t s;
    pid_reset(&s);
    int32_t u = pid_update(&s, &g, 1, Q(1000)); /* 2*1 + 0.5*1 + 0 (no previous error) */
    CHECK(u == Q(2.5), "first step %f", u / 65536.0);
    u = pid_update(&s, &g, 3, Q(1000)); /* 6 + 0.5*4 + 1*(3-1) */
    CHECK(u == Q(10.0), "second step %f", u / 65536.0);
}

static void gains_keep_sixteen_significant_bits_over_their_range(void)
{
    /* The defaults of the robot: 2500 permille per m/s on an error in um/s, 0.0004 m/s per permille in mm/s. */
    pb_pid_t speed = {2500.0f, 120.0f, 0.0f, 40.0f};
    pid_gains_t k;
    pid_gains_convert(&k, &speed, 1.0e6f, 1.0f);
    pid_state_t s;
    pid_reset(&s);
    int32_t u = pid_update(&s, &k, 100000, Q(1000)); /* 0.1 m/s: 250 + 12 permille */
    CHECK(fabs(u / 65536.0 - 262.0) < 0.01, "speed PID %f permille", u / 65536.0);
    pb_pid_t line = {0.0004f, 0.0f, 0.002f, 1000.0f};
    pid_gains_convert(&k, &line, 1.0f, 1000.0f);
    pid_reset(&s);
    pid_update(&s, &k, 100, Q(1000));
    u = pid_update(&s, &k, 200, Q(1000)); /* 0.4 * 200 + 2 * 100 mm/s */
    CHECK(fabs(u / 65536.0 - 280.0) < 0.01, "line PD %f mm/s", u / 65536.0);
    for (float x = 1.0e-9f; x < 1.0e9f; x *= 3.7f) {
        fx_gain_t g = fx_gain(x);
        double v = g.m * pow(2.0, -g.s);
        CHECK(fabs(v - x) <= x * 1.6e-5, "gain %g kept as %g", (double)x, v);
    }
}

static void integral_and_output_are_clamped(void)
{
    pid_gains_t g = gains(0.0f, 1.0f, 0.0f, 5.0f);
    pid_state_t s;
    pid_reset(&s);
    for (int i = 0; i < 100; i++)
        pid_update(&s, &g, 1, Q(1000));
    CHECK(s.i == Q(5), "integral %f", s.i / 65536.0);
    int32_t u = pid_update(&s, &g, -1, Q(1000));
    CHECK(u == Q(4), "unwinds at once %f", u / 65536.0);
    pid_gains_t big = gains(100000.0f, 100000.0f, 100000.0f, 1000000.0f);
    pid_reset(&s);
    u = pid_update(&s, &big, 1, Q(1000));
    CHECK(u == Q(1000), "output clamp %f", u / 65536.0);
    u = pid_update(&s, &big, -1, Q(1000));
    CHECK(u == -Q(1000) || u == Q(1000), "clamped %f", u / 65536.0);
}

/* At the edges of int32: a wrap anywhere (product, integral, derivative, sum) would flip a sign. */
static void extreme_inputs_saturate_instead_of_wrapping(void)
{
    pid_gains_t big = gains(100000.0f, 100000.0f, 100000.0f, 1000000.0f);
    pid_state_t s;
    pid_reset(&s);
    const int32_t lim = FX_MAX;
    int32_t u = pid_update(&s, &big, INT32_MAX, lim);
    CHECK(u == FX_MAX, "largest error gives the largest output, not %d", u);
    u = pid_update(&s, &big, INT32_MIN, lim);
    CHECK(u == -FX_MAX, "most negative error gives the most negative output, not %d", u);
    CHECK(s.i <= FX_MAX && s.i >= -FX_MAX, "integral within range");
    /* The integral saturates at its clamp over many large steps, never wraps to the other sign. */
    pid_gains_t integ = gains(0.0f, 100000.0f, 0.0f, 1000000.0f);
    pid_reset(&s);
    for (int i = 0; i < 50; i++) {
        u = pid_update(&s, &integ, PID_ERROR_LIMIT, lim);
        CHECK(u > 0 && s.i > 0, "step %d: integral %d output %d stay positive", i, s.i, u);
    }
    /* The derivative of a full swing: e - e_prev = 2^31 would overflow without the error clamp. */
    pid_gains_t deriv = gains(0.0f, 0.0f, 1.0f, 0.0f);
    pid_reset(&s);
    pid_update(&s, &deriv, INT32_MIN, lim);
    u = pid_update(&s, &deriv, INT32_MAX, lim);
    CHECK(u == FX_MAX, "full positive swing %d", u);
    u = pid_update(&s, &deriv, INT32_MIN, lim);
    CHECK(u == -FX_MAX, "full negative swing %d", u);
}

/* fx_mul() against the exact product, floored and saturated, for every exponent a gain can have. */
static void products_are_exact_for_every_exponent(void)
{
    uint32_t x = 1;
    for (int e = -70; e <= 40; e++) {
        for (int j = 0; j < 40; j++) {
            x = x * 1103515245u + 12345u;
            fx_gain_t g = fx_gain(ldexpf(1.0f + (float)(x >> 9) / 8388608.0f, e));
            for (int i = 0; i < 60; i++) {
                x = x * 1103515245u + 12345u;
                int32_t a = (int32_t)(x ^ (x << 13)) >> (i % 31);
                if (i == 0)
                    a = INT32_MIN;
                unsigned __int128 p = (unsigned __int128)(a < 0 ? -(int64_t)a : a) * g.m;
                unsigned __int128 q = g.s >= 0 ? p >> g.s : p << -g.s;
                int64_t exact = q > FX_MAX ? FX_MAX : (int64_t)q;
                int32_t r = fx_mul(a, &g);
                if (r != (a < 0 ? -exact : exact)) {
                    CHECK(0, "%d * %u / 2^%d = %d, exact %lld", a, g.m, g.s, r, (long long)(a < 0 ? -exact : exact));
                    return;
                }
            }
        }
    }
}

static void divisions_are_exact(void)
{
    uint32_t x = 7;
    for (int i = 0; i < 200000; i++) {
        x = x * 1103515245u + 12345u;
        uint32_t n = x ^ (x << 7), d = (x >> (i % 32)) | 1u;
        if (i % 7 == 0)
            n = 0xFFFFFFFFu >> (i % 5);
        if (fx_udiv(n, d) != n / d) {
            CHECK(0, "%u / %u = %u, fx_udiv says %u", n, d, n / d, fx_udiv(n, d));
            return;
        }
    }
    CHECK(fx_udiv(0xFFFFFFFFu, 1) == 0xFFFFFFFFu && fx_udiv(5, 0xFFFFFFFFu) == 0 && fx_udiv(0x80000000u, 0x80000000u) == 1,
          "edges");
}

static void fixed_point_helpers_saturate(void)
{
    fx_gain_t huge = fx_gain(1.0e30f), one = fx_gain(1.0f), tiny = fx_gain(1.0e-30f);
    CHECK(fx_mul(INT32_MAX, &huge) == FX_MAX && fx_mul(INT32_MIN, &huge) == -FX_MAX, "products saturate");
    CHECK(fx_mul(2, &huge) == FX_MAX && fx_mul(-2, &huge) == -FX_MAX && fx_mul(1, &huge) > 2147000000,
          "a huge gain saturates any error");
    for (int s = -20; s < 20; s++) { /* around the boundary of every shift: saturate, never wrap */
        fx_gain_t g = fx_gain(ldexpf(65535.0f, -s));
        for (int32_t a = 1; a > 0 && a < (1 << 30); a = a * 3 + 1) {
            double exact = (double)a * g.m * pow(2.0, -g.s);
            int32_t r = fx_mul(a, &g);
            CHECK(exact >= FX_MAX ? r >= FX_MAX - (1 << 16) : fabs(r - exact) <= 1.0 && r >= 0,
                  "%d * %u / 2^%d = %d, exact %.0f", a, g.m, g.s, r, exact);
            CHECK(fx_mul(-a, &g) == -r, "symmetric");
        }
    }
    CHECK(fx_mul(INT32_MAX, &one) == INT32_MAX && fx_mul(-123456789, &one) == -123456789, "unity gain exact");
    CHECK(fx_mul(INT32_MAX, &tiny) == 0, "tiny gain");
    fx_gain_t quarter_pct = fx_gain(0.0025f);
    CHECK(fx_mul(1000, &quarter_pct) == 2, "truncates towards zero");
    CHECK(fx_mul(-1000, &quarter_pct) == -2, "symmetric");
    CHECK(fx_gain(-1.0f).m == 0 && fx_gain(NAN).m == 0 && fx_gain(INFINITY).m != 0, "negative and NaN give 0");
    CHECK(fx_add(FX_MAX, 1) == FX_MAX && fx_add(-FX_MAX, -1) == -FX_MAX && fx_add(INT32_MIN, -1) == -FX_MAX,
          "sums saturate");
    CHECK(fx_add(FX_MAX, -FX_MAX) == 0, "no false saturation");
    CHECK(fx_frac(INT32_MAX, FX_ONE) == FX_FRAC_MAX && fx_frac(INT32_MIN, -FX_ONE) == FX_FRAC_MAX,
          "fractions clamp their input");
    CHECK(fx_frac(1000000, FX_ONE / 2) == 500000 && fx_frac(-1000000, FX_ONE / 4) == -250000 &&
              fx_frac(1000000, -FX_ONE) == -1000000,
          "fractions");
    CHECK(fx_mulhi(0xFFFFFFFFu, 0xFFFFFFFFu) == 0xFFFFFFFEu && fx_mulhi(1u << 31, 4) == 2, "mulhi");
    for (uint32_t a = 1; a < 0xF0000000u; a = a * 7 + 3)
        for (uint32_t b = 1; b < 0x10000u; b = b * 5 + 1) {
            uint32_t exact = (uint32_t)(((uint64_t)a * b) >> 32);
            CHECK(fx_mulhi(a, b) == exact && fx_mulhi16(a, (uint16_t)b) == exact, "mulhi %u * %u", a, b);
        }
    CHECK(fx_mulhi16(0xFFFFFFFFu, 0xFFFF) == 0xFFFEu, "mulhi16 at the top");
    CHECK(fx_frac(-999999, FX_ONE / 2) == -499999 && fx_frac(999999, -FX_ONE / 2) == -499999, "halves");
    CHECK(fx_isqrt(0xFFFFFFFFu) == 65535 && fx_isqrt(99) == 9 && fx_isqrt(100) == 10, "isqrt");
}

void suite_pid(void)
{
    RUN(proportional_integral_derivative_terms);
    RUN(gains_keep_sixteen_significant_bits_over_their_range);
    RUN(integral_and_output_are_clamped);
    RUN(extreme_inputs_saturate_instead_of_wrapping);
    RUN(fixed_point_helpers_saturate);
    RUN(products_are_exact_for_every_exponent);
    RUN(divisions_are_exact);
}
