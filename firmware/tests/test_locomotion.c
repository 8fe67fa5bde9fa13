#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/data.h"
#include "harness.h"
#include "modules/locomotion.h"
#include "world.h"

static uint16_t detail;

static uint8_t straight(uint16_t id, float distance_m, float speed_mps)
{
    pb_move_straight_t c = {id, distance_m, speed_mps};
    return locomotion_straight(&c, &detail);
}

static uint8_t rotate(uint16_t id, float angle_deg, float speed_mps)
{
    pb_move_rotate_t c = {id, angle_deg, speed_mps};
    return locomotion_rotate(&c, &detail);
}

static uint8_t arc(uint16_t id, float radius_m, float angle_deg, float speed_mps)
{
    pb_move_arc_t c = {id, radius_m, angle_deg, speed_mps};
    return locomotion_arc(&c, &detail);
}

static void heartbeat(void)
{
    host_send(PB_PKT_HEARTBEAT, 0, NULL, 0); /* keep the link failsafe quiet */
}

/* Runs until the queue is empty (or the time is up); returns the time it took in ms. */
static int run_until_idle(int max_ms)
{
    for (int t = 0; t < max_ms; t += 10) {
        world_run_ms(10);
        heartbeat();
        if (robot_state.locomotion.mode == PB_LOCO_MODE_IDLE)
            return t + 10;
    }
    return max_ms;
}

/* Runs `ms` with a heartbeat every 10 ms. */
static void run_with_host(int ms)
{
    for (int t = 0; t < ms; t += 10) {
        world_run_ms(10);
        heartbeat();
    }
}

/* The n-th movement_done the host received (0-based), or 0 when there is none. */
static int done_packet(int n, pb_movement_done_t *out)
{
    host_collect();
    const host_frame_t *f = host_find(PB_PKT_MOVEMENT_DONE, n);
    if (f == NULL || f->len != sizeof *out)
        return 0;
    memcpy(out, f->payload, sizeof *out);
    return 1;
}

/* The true distance the robot's centre drove (both wheels' ground travel), m. */
static double true_distance(void)
{
    return (world.pos[0] + world.pos[1]) / 2.0;
}

static void straight_10_cm_within_2_mm(void)
{
    float speeds[] = {0.05f, 0.1f, 0.2f};
    for (unsigned k = 0; k < 3; k++) {
        world_reset(1);
        CHECK(straight(7, 0.10f, speeds[k]) == PB_ERROR_CODE_NONE, "queued");
        int ms = run_until_idle(5000);
        world_run_ms(400); /* let it come to rest */
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
    straight(1, -0.05f, 0.1f);
    run_until_idle(3000);
    world_run_ms(400);
    CHECK(fabs(world.x + 0.05) < 0.002, "ended at %.2f mm", world.x * 1000);
    CHECK(robot_state.encoders.left < 0 && robot_state.encoders.right < 0, "counted backwards");
    pb_movement_done_t d;
    CHECK(done_packet(0, &d) && d.done < -0.048f && d.done > -0.052f, "done %.4f m, signed like the request",
          (double)d.done);
}

static void rotate_90_degrees_within_3(void)
{
    float angles[] = {90.0f, -90.0f, 180.0f};
    for (unsigned k = 0; k < 3; k++) {
        world_reset(1);
        rotate(3, angles[k], 0.05f);
        run_until_idle(5000);
        world_run_ms(400);
        double err = world_heading_deg() - angles[k];
        CHECK(fabs(err) <= 3.0, "rotation %.0f ended %.2f deg off", (double)angles[k], err);
        CHECK(hypot(world.x, world.y) < 0.002, "turned in place: moved %.2f mm", hypot(world.x, world.y) * 1000);
        pb_movement_done_t d;
        CHECK(done_packet(0, &d) && fabs(d.done - world_heading_deg()) < 2.0,
              "done %.2f deg, turned %.2f deg", (double)d.done, world_heading_deg());
    }
}

static void arc_follows_its_circle(void)
{
    world_reset(1);
    arc(4, 0.05f, 90.0f, 0.08f); /* quarter circle to the left: ends at (0.05, 0.05) facing +y */
    run_until_idle(5000);
    world_run_ms(400);
    CHECK(fabs(world_heading_deg() - 90.0) < 4.0, "heading %.2f", world_heading_deg());
    CHECK(fabs(world.x - 0.05) < 0.004 && fabs(world.y - 0.05) < 0.004, "end (%.1f, %.1f) mm", world.x * 1000,
          world.y * 1000);
    pb_movement_done_t d;
    CHECK(done_packet(0, &d) && fabs(d.done - 90.0f) < 4.0f, "done %.2f deg", (double)d.done);
}

static void queue_runs_in_order_and_reports_each_result(void)
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
    run_with_host(400);
    host_collect();
    CHECK(host_count(PB_PKT_MOVEMENT_DONE) == 3, "done packets %d", host_count(PB_PKT_MOVEMENT_DONE));
    const float want[3] = {0.03f, 90.0f, 0.03f};
    const float tolerance[3] = {0.002f, 3.0f, 0.002f};
    for (int i = 0; i < 3; i++) {
        pb_movement_done_t d;
        CHECK(done_packet(i, &d) && d.id == 10 + i && d.outcome == PB_MOVEMENT_OUTCOME_FINISHED &&
                  fabsf(d.done - want[i]) <= tolerance[i],
              "result %d: id %u outcome %u done %.4f", i, d.id, d.outcome, (double)d.done);
    }
    /* An L: 30 mm along x, quarter turn left, 30 mm along y. */
    CHECK(fabs(world.x - 0.03) < 0.003 && fabs(world.y - 0.03) < 0.003, "end (%.1f, %.1f) mm", world.x * 1000,
          world.y * 1000);
}

static void a_result_waits_until_the_wheels_stand_still_unless_the_next_movement_follows(void)
{
    world_reset(1);
    straight(1, 0.05f, 0.2f);
    straight(2, 0.05f, 0.2f);
    int first_at = -1, second_at = -1, second_started = -1, still_at = -1;
    for (int t = 1; t <= 2000 && second_at < 0; t++) {
        world_run_ms(1);
        if (t % 10 == 0)
            heartbeat();
        host_collect();
        if (first_at < 0 && host_count(PB_PKT_MOVEMENT_DONE) >= 1)
            first_at = t;
        if (second_started < 0 && robot_state.locomotion.current_id == 2)
            second_started = t;
        if (still_at < 0 && robot_state.locomotion.mode == PB_LOCO_MODE_IDLE && world.v[0] == 0.0 && world.v[1] == 0.0)
            still_at = t;
        if (host_count(PB_PKT_MOVEMENT_DONE) >= 2)
            second_at = t;
    }
    /* The first is reported at the hand-over, with the robot still moving on into the second (a state packet being
     * encoded at that moment delays the report by up to 4 ticks: comm_offer()). */
    CHECK(first_at > 0 && second_started > 0 && abs(first_at - second_started) <= 6,
          "first reported at %d ms, the second started at %d ms", first_at, second_started);
    /* The last one waits for the wheels to stand still (the firmware sees it a speed timeout after the last
     * pulse), at most LOCOMOTION_SETTLE_MS after the end. */
    CHECK(second_at > 0 && robot_state.wheels.speed_left_mmps == 0 && robot_state.wheels.speed_right_mmps == 0,
          "second reported at %d ms with the wheels at %d and %d mm/s", second_at, robot_state.wheels.speed_left_mmps,
          robot_state.wheels.speed_right_mmps);
    pb_movement_done_t d1, d2;
    CHECK(done_packet(0, &d1) && done_packet(1, &d2), "both reported");
    /* The coasting counts: together they are what the wheels did, to the encoder's resolution (0.7 mm). */
    double sum = (double)d1.done + (double)d2.done;
    CHECK(fabs(sum - true_distance()) < 0.0015, "reported %.2f + %.2f mm, drove %.2f mm", d1.done * 1e3,
          d2.done * 1e3, true_distance() * 1e3);
    CHECK(still_at < 0 || second_at >= still_at - 100, "reported at %d ms, standing at %d ms", second_at, still_at);
}

static void bad_arguments_name_the_field(void)
{
    world_reset(1);
    for (uint16_t i = 1; i <= LOCOMOTION_QUEUE_SIZE; i++)
        CHECK(straight(i, 0.01f, 0.1f) == PB_ERROR_CODE_NONE, "movement %u", i);
    CHECK(straight(99, 0.01f, 0.1f) == PB_ERROR_CODE_QUEUE_FULL, "17th refused");
    CHECK(straight(0, 0.01f, 0.1f) == PB_ERROR_CODE_BAD_ARGUMENT && detail == offsetof(pb_move_straight_t, id),
          "id 0: detail %u", detail);
    CHECK(straight(5, NAN, 0.1f) == PB_ERROR_CODE_BAD_ARGUMENT && detail == offsetof(pb_move_straight_t, distance_m),
          "NaN distance: detail %u", detail);
    CHECK(straight(5, 0.1f, 0.0f) == PB_ERROR_CODE_BAD_ARGUMENT && detail == offsetof(pb_move_straight_t, speed_mps),
          "zero speed: detail %u", detail);
    CHECK(rotate(5, NAN, 0.1f) == PB_ERROR_CODE_BAD_ARGUMENT && detail == offsetof(pb_move_rotate_t, angle_deg),
          "NaN angle: detail %u", detail);
    CHECK(arc(5, -1.0f, 10.0f, 0.1f) == PB_ERROR_CODE_BAD_ARGUMENT && detail == offsetof(pb_move_arc_t, radius_m),
          "negative radius: detail %u", detail);
    CHECK(arc(5, 90.0f, 36000.0f, 0.1f) == PB_ERROR_CODE_BAD_ARGUMENT && detail == offsetof(pb_move_arc_t, radius_m),
          "a wheel distance over 1000 m names the radius: detail %u", detail);
    CHECK(arc(5, 0.1f, 10.0f, 3.0f) == PB_ERROR_CODE_BAD_ARGUMENT && detail == offsetof(pb_move_arc_t, speed_mps),
          "too fast: detail %u", detail);
}

static void stop_ends_the_running_movement_as_stopped_and_drops_the_queued(void)
{
    for (int immediate = 0; immediate <= 1; immediate++) {
        world_reset(1);
        straight(1, 0.5f, 0.2f);
        straight(2, 0.5f, 0.2f);
        straight(3, 0.5f, 0.2f);
        run_with_host(300);
        pb_stop_t st = {(uint8_t)immediate};
        host_send(PB_PKT_STOP, 5, &st, sizeof st);
        world_run_ms(3);
        if (immediate)
            CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_IDLE && robot_state.locomotion.queue_length == 0 &&
                      robot_state.wheels.pwm_left == 0 && robot_state.wheels.pwm_right == 0, "immediate stop");
        else
            CHECK(robot_state.locomotion.queue_length == 1, "only the braking movement left");
        run_until_idle(2000);
        run_with_host(400);
        CHECK(host_count(PB_PKT_MOVEMENT_DONE) == 3, "three results: %d", host_count(PB_PKT_MOVEMENT_DONE));
        pb_movement_done_t d[3];
        for (int i = 0; i < 3; i++)
            done_packet(i, &d[i]);
        /* In the order they ended: braking ends after the queued ones were dropped. */
        const pb_movement_done_t *stopped = immediate ? &d[0] : &d[2];
        const pb_movement_done_t *dropped = immediate ? &d[1] : &d[0];
        CHECK(stopped->id == 1 && stopped->outcome == PB_MOVEMENT_OUTCOME_STOPPED, "running one: id %u outcome %u",
              stopped->id, stopped->outcome);
        CHECK(fabs(stopped->done - true_distance()) < 0.001, "stopped after %.2f mm, drove %.2f mm",
              stopped->done * 1e3, true_distance() * 1e3);
        CHECK(dropped[0].id == 2 && dropped[1].id == 3 && dropped[0].outcome == PB_MOVEMENT_OUTCOME_DROPPED &&
                  dropped[1].outcome == PB_MOVEMENT_OUTCOME_DROPPED && dropped[0].done == 0.0f && dropped[1].done == 0.0f,
              "queued ones dropped");
        CHECK(robot_state.locomotion.finished_id == 0, "a stopped movement is not reported finished");
    }
    /* Braking at 1 m/s^2 from 0.2 m/s takes about 20 mm. */
    world_reset(1);
    straight(1, 0.5f, 0.2f);
    run_with_host(300);
    double x0 = world.x;
    locomotion_stop(false);
    run_until_idle(2000);
    world_run_ms(100);
    CHECK(world.x - x0 > 0.005 && world.x - x0 < 0.04, "braked over %.1f mm", (world.x - x0) * 1000);
}

static void teleoperation_and_line_following_end_a_movement_as_stopped(void)
{
    world_reset(1);
    straight(1, 0.5f, 0.2f);
    straight(2, 0.5f, 0.2f);
    run_with_host(200);
    pb_wheel_speeds_t w = {0.05f, 0.05f};
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    run_with_host(50);
    pb_movement_done_t d;
    CHECK(done_packet(0, &d) && d.id == 1 && d.outcome == PB_MOVEMENT_OUTCOME_STOPPED && d.done > 0.02f,
          "teleoperation stopped 1 after %.1f mm", d.done * 1e3);
    CHECK(done_packet(1, &d) && d.id == 2 && d.outcome == PB_MOVEMENT_OUTCOME_DROPPED, "and dropped 2");
    world_reset(1);
    straight(1, 0.5f, 0.2f);
    run_with_host(200);
    pb_line_follow_t lf = {1, PB_COLOUR_MODE_PLAIN, 0.0f};
    host_send(PB_PKT_LINE_FOLLOW, 3, &lf, sizeof lf);
    run_with_host(50);
    CHECK(done_packet(0, &d) && d.id == 1 && d.outcome == PB_MOVEMENT_OUTCOME_STOPPED, "line following stopped 1");
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
    w.right_mps = INFINITY;
    host_clear();
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(2);
    host_collect();
    const host_frame_t *e = host_find(PB_PKT_ERROR, 0);
    pb_error_t err;
    if (e)
        memcpy(&err, e->payload, sizeof err);
    CHECK(robot_state.errors.rejected == 1 && e && err.code == PB_ERROR_CODE_BAD_ARGUMENT &&
              err.detail == offsetof(pb_wheel_speeds_t, right_mps), "infinite speed refused, detail names it");
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
}

static void the_failsafe_ends_every_movement_with_how_far_it_went(void)
{
    world_reset(1);
    pb_move_straight_t m = {1, 0.3f, 0.1f};
    host_send(PB_PKT_MOVE_STRAIGHT, 1, &m, sizeof m);
    pb_move_rotate_t r = {2, 90.0f, 0.05f};
    host_send(PB_PKT_MOVE_ROTATE, 2, &r, sizeof r);
    world_run_ms(1100); /* the host falls silent: the failsafe ends both at 1000 ms */
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_FAILSAFE && robot_state.locomotion.queue_length == 0,
          "movements stop");
    world_run_ms(400);
    pb_movement_done_t d;
    CHECK(done_packet(0, &d) && d.id == 1 && d.outcome == PB_MOVEMENT_OUTCOME_FAILSAFE, "running one: failsafe");
    CHECK(fabs(d.done - true_distance()) < 0.001 && true_distance() > 0.05, "done %.2f mm, drove %.2f mm",
          d.done * 1e3, true_distance() * 1e3);
    CHECK(done_packet(1, &d) && d.id == 2 && d.outcome == PB_MOVEMENT_OUTCOME_FAILSAFE && d.done == 0.0f,
          "queued one: failsafe, nothing done");
}

static int read_log(uint8_t seq, pb_movement_log_t *out)
{
    host_clear();
    host_send(PB_PKT_READ_MOVEMENTS, seq, NULL, 0);
    world_run_ms(20);
    host_collect();
    const host_frame_t *f = host_find(PB_PKT_MOVEMENT_LOG, 0);
    const host_frame_t *ack = host_find(PB_PKT_ACK, 0);
    if (f == NULL || f->len != sizeof *out || ack == NULL || ack->seq != seq || ack < f)
        return 0;
    memcpy(out, f->payload, sizeof *out);
    return 1;
}

static void read_movements_returns_the_last_16_results_oldest_first(void)
{
    world_reset(1);
    pb_movement_log_t log;
    CHECK(read_log(9, &log) && log.count == 0 && log.current_id == 0, "empty after reset");
    for (uint16_t i = 1; i <= LOCOMOTION_QUEUE_SIZE; i++)
        straight(i, 0.5f, 0.1f);
    run_with_host(100);
    locomotion_failsafe(); /* a full queue ends at once */
    run_with_host(400);
    CHECK(read_log(10, &log), "answered with the log, then ack");
    CHECK(log.count == 16 && log.queue_length == 0 && log.current_id == 0, "count %u", log.count);
    for (int i = 0; i < 16; i++)
        CHECK(log.ids[i] == i + 1 && log.outcomes[i] == PB_MOVEMENT_OUTCOME_FAILSAFE, "entry %d: id %u outcome %u", i,
              log.ids[i], log.outcomes[i]);
    CHECK(log.done[0] > 0.005f && log.done[1] == 0.0f, "the running one moved, the queued ones not");

    /* Three more: the oldest three fall out; a new host session keeps the log. */
    for (uint16_t i = 17; i <= 19; i++)
        straight(i, 0.01f, 0.1f);
    run_until_idle(3000);
    run_with_host(400);
    pb_hello_request_t hr = {PB_PROTOCOL_VERSION, 0xC0FFEEu};
    host_send(PB_PKT_HELLO_REQUEST, 0, &hr, sizeof hr);
    straight(20, 0.5f, 0.1f);
    run_with_host(50);
    CHECK(read_log(11, &log), "read again");
    CHECK(log.count == 16 && log.ids[0] == 4 && log.ids[15] == 19 && log.outcomes[15] == PB_MOVEMENT_OUTCOME_FINISHED,
          "last 16: %u..%u", log.ids[0], log.ids[15]);
    CHECK(log.current_id == 20 && log.queue_length == 1, "and the queue now: %u, %u", log.current_id,
          log.queue_length);
    /* Asked again at once, it answers again (a read is never a retransmission). */
    CHECK(read_log(11, &log) && log.count == 16, "the same request answered twice");
}

/* Least-squares slope of v over t. */
static double slope(const double *t, const double *v, int n)
{
    double st = 0, sv = 0, stt = 0, stv = 0;
    for (int i = 0; i < n; i++) {
        st += t[i];
        sv += v[i];
        stt += t[i] * t[i];
        stv += t[i] * v[i];
    }
    return (n * stv - st * sv) / (n * stt - st * st);
}

static void profile_accelerates_cruises_and_brakes_at_the_set_slopes(void)
{
    const float accel[2] = {0.5f, 1.0f};
    for (int k = 0; k < 2; k++) {
        world_reset(1);
        settings.profile.accel_mps2 = accel[k];
        settings.profile.decel_mps2 = accel[k];
        settings_generation++;
        straight(1, 0.4f, 0.2f);
        double t[1000], v[1000];
        int n = 0;
        for (int ms = 0; ms < 4000 && robot_state.locomotion.mode == PB_LOCO_MODE_MOVEMENT && n < 1000; ms += 5) {
            world_run_ms(5);
            if (ms % 50 == 0)
                heartbeat();
            t[n] = (ms + 5) / 1000.0;
            v[n] = (world.v[0] + world.v[1]) / 2.0;
            n++;
        }
        double vmax = 0;
        int peak = 0;
        for (int i = 0; i < n; i++)
            if (v[i] > vmax) {
                vmax = v[i];
                peak = i;
            }
        /* Rising side: from 20 % to 80 % of the cruise speed, a straight line of the set slope (a step profile
         * would rise at the motor's own pace, several m/s^2). */
        int a = 0, b = 0;
        while (a < n && v[a] < 0.04)
            a++;
        b = a;
        while (b < n && v[b] < 0.16)
            b++;
        double up = b - a >= 4 ? slope(t + a, v + a, b - a) : 1e9;
        CHECK(fabs(up - accel[k]) < 0.2 * accel[k], "accelerates at %.2f m/s^2 (set %.2f)", up, (double)accel[k]);
        /* Cruise: at the commanded speed for a while. */
        int cruising = 0;
        for (int i = 0; i < n; i++)
            cruising += fabs(v[i] - 0.2) < 0.01;
        CHECK(vmax < 0.215 && cruising * 5 > 600, "cruises at 0.2 m/s for %d ms (peak %.3f m/s)", cruising * 5, vmax);
        /* Falling side, from 80 % down to 20 %. */
        int c = peak;
        while (c < n && v[c] > 0.16)
            c++;
        int e = c;
        while (e < n && v[e] > 0.04)
            e++;
        double down = e - c >= 4 ? slope(t + c, v + c, e - c) : -1e9;
        CHECK(fabs(-down - accel[k]) < 0.25 * accel[k], "brakes at %.2f m/s^2 (set %.2f)", -down, (double)accel[k]);
    }
}

/* Straight and arc with a weak left motor: the balance controller keeps the wheels' distances in their ratio;
 * without it (gains 0) the same disturbance bends the path. */
static double worst_ratio_error_mm(float balance_kp, float balance_ki, int use_arc)
{
    world_reset(1);
    world.gain[0] = 0.7;
    settings.wheel_balance.kp = balance_kp;
    settings.wheel_balance.ki = balance_ki;
    settings_generation++;
    /* Arc of radius 0.05 m to the left: the left wheel is the inner one, ratio (r - b/2) / (r + b/2). */
    double ratio = use_arc ? (0.05 - 0.013) / (0.05 + 0.013) : 1.0;
    if (use_arc)
        arc(1, 0.05f, 120.0f, 0.1f);
    else
        straight(1, 0.3f, 0.15f);
    double worst = 0;
    for (int ms = 0; ms < 5000 && robot_state.locomotion.mode == PB_LOCO_MODE_MOVEMENT; ms++) {
        world_run_ms(1);
        if (ms % 10 == 0)
            heartbeat();
        double err = fabs(world.pos[0] - ratio * world.pos[1]) * 1000.0;
        if (err > worst)
            worst = err;
    }
    return worst;
}

static void wheel_balance_keeps_the_ratio_under_a_disturbance(void)
{
    float kp = pb_settings_defaults.wheel_balance.kp, ki = pb_settings_defaults.wheel_balance.ki;
    for (int use_arc = 0; use_arc <= 1; use_arc++) {
        double with = worst_ratio_error_mm(kp, ki, use_arc);
        double without = worst_ratio_error_mm(0.0f, 0.0f, use_arc);
        CHECK(with < 2.0, "%s: ratio kept within %.2f mm", use_arc ? "arc" : "straight", with);
        CHECK(without > 4.0 * with && without > 5.0, "%s: without balance the error grows to %.2f mm (with %.2f mm)",
              use_arc ? "arc" : "straight", without, with);
    }
}

static void coasting_of_a_sluggish_drive_is_learnt(void)
{
    world_reset(1);
    world.tau = 0.08; /* a drive that rolls on for long after the motors are cut */
    double first = 0, last = 0;
    for (int k = 0; k < 3; k++) {
        double x0 = world.x;
        straight((uint16_t)(k + 1), 0.10f, 0.1f);
        run_until_idle(4000);
        run_with_host(400);
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
    RUN(queue_runs_in_order_and_reports_each_result);
    RUN(a_result_waits_until_the_wheels_stand_still_unless_the_next_movement_follows);
    RUN(bad_arguments_name_the_field);
    RUN(stop_ends_the_running_movement_as_stopped_and_drops_the_queued);
    RUN(teleoperation_and_line_following_end_a_movement_as_stopped);
    RUN(teleoperation_holds_wheel_speeds);
    RUN(link_failsafe_stops_host_driven_motion);
    RUN(the_failsafe_ends_every_movement_with_how_far_it_went);
    RUN(read_movements_returns_the_last_16_results_oldest_first);
    RUN(profile_accelerates_cruises_and_brakes_at_the_set_slopes);
    RUN(wheel_balance_keeps_the_ratio_under_a_disturbance);
}
