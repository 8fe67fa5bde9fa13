#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "modules/locomotion.h"
#include "modules/reflector.h"
#include "modules/settings.h"
#include "world.h"

/* Runs until the queue is empty (or the time is up); returns the time it took in ms. */
static int run_until_idle(int max_ms)
{
    for (int t = 0; t < max_ms; t += 10) {
        world_run_ms(10);
        pb_heartbeat_t hb;
        host_send(PB_PKT_HEARTBEAT, 0, &hb, 0); /* keep the link failsafe quiet */
        if (robot_state.locomotion.mode == PB_LOCO_MODE_IDLE)
            return t + 10;
    }
    return max_ms;
}

static void straight_10_cm_within_2_mm(void)
{
    float speeds[] = {0.05f, 0.1f, 0.2f};
    for (unsigned k = 0; k < 3; k++) {
        world_reset(1);
        CHECK(locomotion_straight(7, 0.10f, speeds[k]) == PB_ERROR_CODE_NONE, "queued");
        int ms = run_until_idle(5000);
        world_run_ms(200); /* let it come to rest */
        host_collect();
        double err_mm = (world.x - 0.10) * 1000.0;
        CHECK(fabs(err_mm) <= 2.0, "at %.2f m/s: ended %.2f mm off", (double)speeds[k], err_mm);
        CHECK(fabs(world.y) < 0.002 && fabs(world_heading_deg()) < 3.0, "straight: y %.2f mm heading %.2f deg",
              world.y * 1000, world_heading_deg());
        CHECK(robot_state.locomotion.finished_id == 7 && host_count(PB_PKT_MOVEMENT_DONE) == 1, "reported");
        CHECK(ms < 3000, "took %d ms", ms);
    }
}

static void backwards_straight(void)
{
    world_reset(1);
    locomotion_straight(1, -0.05f, 0.1f);
    run_until_idle(3000);
    world_run_ms(200);
    CHECK(fabs(world.x + 0.05) < 0.002, "ended at %.2f mm", world.x * 1000);
    CHECK(robot_state.encoders.left < 0 && robot_state.encoders.right < 0, "counted backwards");
}

static void rotate_90_degrees_within_3(void)
{
    float angles[] = {90.0f, -90.0f, 180.0f};
    for (unsigned k = 0; k < 3; k++) {
        world_reset(1);
        locomotion_rotate(3, angles[k], 0.05f);
        run_until_idle(5000);
        world_run_ms(200);
        double err = world_heading_deg() - angles[k];
        CHECK(fabs(err) <= 3.0, "rotation %.0f ended %.2f deg off", (double)angles[k], err);
        CHECK(hypot(world.x, world.y) < 0.002, "turned in place: moved %.2f mm", hypot(world.x, world.y) * 1000);
    }
}

static void arc_follows_its_circle(void)
{
    world_reset(1);
    locomotion_arc(4, 0.05f, 90.0f, 0.08f); /* quarter circle to the left: ends at (0.05, 0.05) facing +y */
    run_until_idle(5000);
    world_run_ms(200);
    CHECK(fabs(world_heading_deg() - 90.0) < 4.0, "heading %.2f", world_heading_deg());
    CHECK(fabs(world.x - 0.05) < 0.004 && fabs(world.y - 0.05) < 0.004, "end (%.1f, %.1f) mm", world.x * 1000,
          world.y * 1000);
}

static void queue_runs_in_order_and_reports_each_id(void)
{
    world_reset(1);
    pb_move_straight_t s = {10, 0.03f, 0.1f};
    pb_move_rotate_t r = {11, 90.0f, 0.05f};
    host_send(PB_PKT_MOVE_STRAIGHT, 1, &s, sizeof s);
    host_send(PB_PKT_MOVE_ROTATE, 2, &r, sizeof r);
    s.id = 12;
    host_send(PB_PKT_MOVE_STRAIGHT, 3, &s, sizeof s);
    world_run_ms(5);
    CHECK(robot_state.locomotion.queue_length == 3 && robot_state.locomotion.current_id == 10, "queued");
    run_until_idle(5000);
    host_collect();
    CHECK(host_count(PB_PKT_MOVEMENT_DONE) == 3, "done packets %d", host_count(PB_PKT_MOVEMENT_DONE));
    for (int i = 0; i < 3; i++) {
        const host_frame_t *f = host_find(PB_PKT_MOVEMENT_DONE, i);
        CHECK(f && f->payload[0] == 10 + i, "order %d", i);
    }
    /* An L: 30 mm along x, quarter turn left, 30 mm along y. */
    CHECK(fabs(world.x - 0.03) < 0.003 && fabs(world.y - 0.03) < 0.003, "end (%.1f, %.1f) mm", world.x * 1000,
          world.y * 1000);
}

static void a_full_queue_refuses_the_seventeenth(void)
{
    world_reset(1);
    for (uint16_t i = 1; i <= LOCOMOTION_QUEUE_SIZE; i++)
        CHECK(locomotion_straight(i, 0.01f, 0.1f) == PB_ERROR_CODE_NONE, "movement %u", i);
    CHECK(locomotion_straight(99, 0.01f, 0.1f) == PB_ERROR_CODE_QUEUE_FULL, "17th refused");
    CHECK(locomotion_straight(0, 0.01f, 0.1f) == PB_ERROR_CODE_BAD_ARGUMENT, "id 0");
    CHECK(locomotion_rotate(5, NAN, 0.1f) == PB_ERROR_CODE_BAD_ARGUMENT, "NaN angle");
    CHECK(locomotion_arc(5, -1.0f, 10.0f, 0.1f) == PB_ERROR_CODE_BAD_ARGUMENT, "negative radius");
    CHECK(locomotion_straight(5, 0.1f, 0.0f) == PB_ERROR_CODE_BAD_ARGUMENT, "zero speed");
}

static void stop_clears_the_queue(void)
{
    world_reset(1);
    locomotion_straight(1, 0.5f, 0.2f);
    locomotion_straight(2, 0.5f, 0.2f);
    world_run_ms(300);
    pb_stop_t st = {1};
    host_send(PB_PKT_STOP, 5, &st, sizeof st);
    world_run_ms(3);
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_IDLE && robot_state.locomotion.queue_length == 0 &&
              robot_state.wheels.pwm_left == 0 && robot_state.wheels.pwm_right == 0, "immediate stop");
    world_reset(1);
    locomotion_straight(1, 0.5f, 0.2f);
    locomotion_straight(2, 0.5f, 0.2f);
    world_run_ms(300);
    double x0 = world.x;
    locomotion_stop(false);
    CHECK(robot_state.locomotion.queue_length == 1, "only the braking movement left");
    run_until_idle(2000);
    world_run_ms(100);
    /* Braking at 1 m/s^2 from 0.2 m/s takes about 20 mm. */
    CHECK(world.x - x0 > 0.005 && world.x - x0 < 0.04, "braked over %.1f mm", (world.x - x0) * 1000);
    CHECK(robot_state.locomotion.finished_id == 0, "a stopped movement is not reported finished");
}

static void teleoperation_holds_wheel_speeds(void)
{
    world_reset(1);
    pb_wheel_speeds_t w = {0.10f, 0.15f};
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(300);
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_TELEOP, "mode %u", robot_state.locomotion.mode);
    CHECK(fabs(world.v[0] - 0.10) < 0.01 && fabs(world.v[1] - 0.15) < 0.01, "speeds %.3f %.3f", world.v[0],
          world.v[1]);
    CHECK(abs(robot_state.wheels.speed_left_mmps - 100) < 10 && abs(robot_state.wheels.speed_right_mmps - 150) < 10,
          "measured %d %d", robot_state.wheels.speed_left_mmps, robot_state.wheels.speed_right_mmps);
    w.left_mps = -0.10f; /* reverse one wheel */
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(300);
    CHECK(fabs(world.v[0] + 0.10) < 0.01 && robot_state.wheels.speed_left_mmps < -90, "reversed: %.3f m/s, %d mm/s",
          world.v[0], robot_state.wheels.speed_left_mmps);
    w.left_mps = INFINITY;
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(2);
    CHECK(robot_state.errors.rejected == 1, "infinite speed refused");
}

static void link_failsafe_stops_host_driven_motion(void)
{
    world_reset(1);
    pb_wheel_speeds_t w = {0.10f, 0.10f};
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(900);
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_TELEOP, "still driving at 900 ms");
    world_run_ms(200);
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_FAILSAFE && robot_state.wheels.pwm_left == 0, "failsafe");
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(5);
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_TELEOP, "a new command resumes");

    world_reset(1);
    pb_move_straight_t m = {1, 1.0f, 0.1f};
    host_send(PB_PKT_MOVE_STRAIGHT, 1, &m, sizeof m);
    world_run_ms(1100);
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_FAILSAFE && robot_state.locomotion.queue_length == 0,
          "movements stop too");
}

static void coasting_of_a_sluggish_drive_is_learnt(void)
{
    world_reset(1);
    world.tau = 0.08; /* a drive that rolls on for long after the motors are cut */
    double first = 0, last = 0;
    for (int k = 0; k < 3; k++) {
        double x0 = world.x;
        locomotion_straight((uint16_t)(k + 1), 0.10f, 0.1f);
        run_until_idle(4000);
        world_run_ms(400);
        double err = (world.x - x0 - 0.10) * 1000.0;
        if (k == 0)
            first = err;
        last = err;
    }
    CHECK(locomotion_coast_s() > 0.04f && locomotion_coast_s() < 0.12f, "learnt %.0f ms",
          (double)locomotion_coast_s() * 1000);
    CHECK(fabs(last) < 2.0 && fabs(last) < fabs(first), "first %.2f mm, third %.2f mm off", first, last);
}

void suite_locomotion(void)
{
    RUN(coasting_of_a_sluggish_drive_is_learnt);
    RUN(straight_10_cm_within_2_mm);
    RUN(backwards_straight);
    RUN(rotate_90_degrees_within_3);
    RUN(arc_follows_its_circle);
    RUN(queue_runs_in_order_and_reports_each_id);
    RUN(a_full_queue_refuses_the_seventeenth);
    RUN(stop_clears_the_queue);
    RUN(teleoperation_holds_wheel_speeds);
    RUN(link_failsafe_stops_host_driven_motion);
}
