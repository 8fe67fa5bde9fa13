#include <math.h>
#include <stdlib.h>

#include "core/data.h"
#include "drivers/encoder.h"
#include "hal/hal.h"
#include "harness.h"
#include "modules/speed.h"
#include "world.h"

static void speed_from_one_and_two_periods(void)
{
    world_reset(1);
    double pulse_um = M_PI * 9000.0 / 40.0; /* the default geometry: 0.707 mm pulses */
    uint32_t ms10 = HAL_CAPTURE_HZ / 100;   /* 10 ms */
    double expect = pulse_um / 0.010;       /* um/s */
    CHECK(fabs(speed_from_periods(ms10, 0, 10 * ms10) - expect) < 2.0, "one period: a pulse in 10 ms, %d um/s",
          speed_from_periods(ms10, 0, 10 * ms10));
    /* Unequal stripes: 8 ms and 12 ms average to 10 ms. */
    int32_t v = speed_from_periods(ms10 * 8 / 10, ms10 * 12 / 10, 10 * ms10);
    CHECK(fabs(v - expect) < 2.0, "average of two periods %d um/s", v);
    CHECK(speed_from_periods(11 * ms10, ms10, 10 * ms10) == 0, "a period beyond the timeout is standstill");
    CHECK(speed_from_periods(0, 0, 10 * ms10) == 0, "no period, no speed");
    v = speed_from_periods(1, 1, 10 * ms10);
    CHECK(v > 3900000 && v <= 4000000, "shortest period saturates at 4 m/s: %d", v);
    v = speed_from_periods(HAL_CAPTURE_HZ / 1000, HAL_CAPTURE_HZ / 1000, 10 * ms10); /* 2 m/s rounds to 1 um/s */
    CHECK(fabs(v - pulse_um / 0.001) < 4.0, "fast: %d um/s", v);
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
        double err = fabs(speed_position_um(0) * 1e-6 - world.pos[0]);
        worst = err > worst ? err : worst;
    }
    CHECK(worst < 0.0005, "extrapolation error %.3f mm (a pulse is 0.707 mm)", worst * 1000);
}

/* A wheel that stopped just past a stripe edge and creeps back over it as it is driven the other way: its first
 * edge in the new direction is the same edge again, a fraction of a pulse later. That is no speed. */
static void a_wheel_that_crosses_back_over_its_last_edge_reads_no_speed(void)
{
    world_reset(1);
    pb_wheel_speeds_t back = {-0.10f, -0.10f}, rest = {0.0f, 0.0f}, on = {0.10f, 0.10f};
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &back, sizeof back);
    world_run_ms(400);
    host_send(PB_PKT_WHEEL_SPEEDS, 1, &rest, sizeof rest);
    world_run_ms(300);
    CHECK(robot_state.wheels.speed_left_mmps == 0, "at rest: %d mm/s", robot_state.wheels.speed_left_mmps);
    /* The left wheel still creeps backwards, 0.1 um from the edge behind it. */
    world.v[0] = -0.0005;
    world.pos[0] = world.prev_edge[0] + 1e-7;
    int32_t count = robot_state.encoders.left;
    world_run_ms(1);
    CHECK(robot_state.encoders.left == count - 1, "crossed the edge backwards: %d from %d", robot_state.encoders.left, count);
    double l0 = world.pos[0], r0 = world.pos[1];
    host_send(PB_PKT_WHEEL_SPEEDS, 2, &on, sizeof on);
    int fastest = 0;
    for (int i = 0; i < 60; i++) {
        world_run_ms(1);
        if (robot_state.wheels.speed_left_mmps > fastest)
            fastest = robot_state.wheels.speed_left_mmps;
    }
    CHECK(fastest < 130, "the left wheel never read faster than it can have turned: %d mm/s", fastest);
    world_run_ms(140);
    double dl = world.pos[0] - l0, dr = world.pos[1] - r0;
    CHECK(fabs(dl - dr) < 0.002, "both wheels drove on together: left %.1f mm, right %.1f mm", dl * 1000, dr * 1000);
}

void suite_speed(void)
{
    RUN(speed_from_one_and_two_periods);
    RUN(measured_speed_is_smooth_over_unequal_stripes_and_times_out);
    RUN(counts_are_signed_by_the_motor_direction);
    RUN(distance_is_extrapolated_within_a_pulse);
    RUN(a_wheel_that_crosses_back_over_its_last_edge_reads_no_speed);
}
