#include <math.h>
#include <stdlib.h>

#include "drivers/encoder.h"
#include "harness.h"
#include "hal/hal.h"
#include "modules/reflector.h"
#include "modules/settings.h"
#include "modules/speed.h"
#include "world.h"

static void speed_from_one_and_two_periods(void)
{
    float p = 0.001f;                    /* 1 mm pulses */
    uint32_t ms10 = HAL_CAPTURE_HZ / 100; /* 10 ms */
    CHECK(fabsf(speed_from_periods(p, ms10, 0, 10 * ms10) - 0.1f) < 1e-6f, "one period: 1 mm / 10 ms");
    /* Unequal stripes: 8 ms and 12 ms average to 10 ms. */
    float v = speed_from_periods(p, ms10 * 8 / 10, ms10 * 12 / 10, 10 * ms10);
    CHECK(fabsf(v - 0.1f) < 1e-6f, "average of two periods %f", (double)v);
    CHECK(speed_from_periods(p, 11 * ms10, ms10, 10 * ms10) == 0.0f, "a period beyond the timeout is standstill");
    CHECK(speed_from_periods(p, 0, 0, 10 * ms10) == 0.0f, "no period, no speed");
    CHECK(speed_from_periods(p, 1, 1, 10 * ms10) > 0.0f && isfinite(speed_from_periods(p, 1, 1, 10 * ms10)),
          "shortest period finite");
}

static void measured_speed_is_smooth_over_unequal_stripes_and_times_out(void)
{
    world_reset(1);
    world.stripe_ratio = 1.3; /* stripes 30 % unequal */
    pb_wheel_speeds_t w = {0.10f, 0.10f};
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(400);
    int lo = 10000, hi = -10000;
    for (int i = 0; i < 50; i++) {
        world_run_ms(1);
        int v = robot_state.wheels.speed_left_mmps;
        lo = v < lo ? v : lo;
        hi = v > hi ? v : hi;
    }
    CHECK(hi - lo <= 8 && abs(lo - 100) < 10, "speed %d..%d mm/s with unequal stripes", lo, hi);
    /* Stop: the speed falls to zero within the timeout after the last pulse. */
    pb_stop_t st = {1};
    host_send(PB_PKT_STOP, 1, &st, sizeof st);
    world_run_ms(200 + settings.encoder.speed_timeout_ms);
    CHECK(robot_state.wheels.speed_left_mmps == 0 && robot_state.wheels.speed_right_mmps == 0, "zero after stop");
}

static void counts_are_signed_by_the_motor_direction(void)
{
    world_reset(1);
    pb_wheel_speeds_t w = {-0.10f, 0.10f};
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(300);
    CHECK(robot_state.encoders.left < -10 && robot_state.encoders.right > 10, "counts %d %d",
          robot_state.encoders.left, robot_state.encoders.right);
    CHECK(robot_state.wheels.speed_left_mmps < -80 && robot_state.wheels.speed_right_mmps > 80, "speeds %d %d",
          robot_state.wheels.speed_left_mmps, robot_state.wheels.speed_right_mmps);
    /* Counts match the truth to a pulse. */
    double pulse = M_PI * 0.009 / 40;
    CHECK(fabs(robot_state.encoders.right - world.pos[1] / pulse) <= 1.0, "right %d vs %.1f", robot_state.encoders.right,
          world.pos[1] / pulse);
}

static void distance_is_extrapolated_within_a_pulse(void)
{
    world_reset(1);
    pb_wheel_speeds_t w = {0.05f, 0.05f};
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(500);
    double worst = 0;
    for (int i = 0; i < 40; i++) {
        world_run_ms(1);
        double err = fabs(speed_distance_m(0) - world.pos[0]);
        worst = err > worst ? err : worst;
    }
    CHECK(worst < 0.0005, "extrapolation error %.3f mm (a pulse is 0.707 mm)", worst * 1000);
}

void suite_speed(void)
{
    RUN(speed_from_one_and_two_periods);
    RUN(measured_speed_is_smooth_over_unequal_stripes_and_times_out);
    RUN(counts_are_signed_by_the_motor_direction);
    RUN(distance_is_extrapolated_within_a_pulse);
}
