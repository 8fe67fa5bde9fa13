#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/data.h"
#include "drivers/line_sensor.h"
#include "harness.h"
#include "modules/line_follower.h"
#include "world.h"

static int16_t position_of(const uint16_t raw[8], uint8_t *seen)
{
    int16_t pos = 12345;
    for (int i = 0; i < 8; i++) /* let a recalibration reach every spot */
        *seen = line_sensor_evaluate(raw, NULL, &pos);
    return pos;
}

static void position_does_not_depend_on_line_width(void)
{
    world_reset(1);
    uint8_t seen;
    uint16_t narrow[8] = {100, 100, 100, 2000, 2000, 100, 100, 100};
    uint16_t wide[8] = {100, 100, 2000, 2000, 2000, 2000, 100, 100};
    int16_t a = position_of(narrow, &seen);
    CHECK(seen && a == 0, "narrow centred line at %d", a);
    int16_t b = position_of(wide, &seen);
    CHECK(seen && b == 0, "wide centred line at %d", b);
    uint16_t right_n[8] = {100, 100, 100, 100, 100, 2000, 100, 100};
    uint16_t right_w[8] = {100, 100, 100, 100, 2000, 2000, 2000, 100};
    CHECK(abs(position_of(right_n, &seen) - position_of(right_w, &seen)) <= 2, "same centre, other widths");
    CHECK(position_of(right_n, &seen) > 300, "right of centre is positive");
    uint16_t far_left[8] = {2000, 100, 100, 100, 100, 100, 100, 100};
    CHECK(position_of(far_left, &seen) == -1000, "far left -1000");
    uint16_t none[8] = {100, 100, 100, 100, 100, 100, 100, 100};
    position_of(none, &seen);
    CHECK(!seen, "white: no line");
}

static void of_two_lines_the_one_nearest_to_the_last_position_counts(void)
{
    world_reset(1);
    uint16_t fork[8] = {100, 2000, 2000, 100, 100, 100, 2000, 2000};
    int16_t pos = -200;
    uint8_t seen = 0;
    for (int i = 0; i < 8; i++) { /* let a recalibration reach every spot */
        pos = -200;
        seen = line_sensor_evaluate(fork, NULL, &pos);
    }
    CHECK(seen && pos < -400, "the left one, near -200: %d", pos);
    pos = 300;
    seen = line_sensor_evaluate(fork, NULL, &pos);
    CHECK(seen && pos > 700, "the right one, near 300: %d", pos);
    /* One wide run is one line, whatever came before. */
    uint16_t wide[8] = {100, 100, 2000, 2000, 2000, 2000, 100, 100};
    pos = 900;
    CHECK(line_sensor_evaluate(wide, NULL, &pos) && pos == 0, "a wide line is centred: %d", pos);
}

static void calibration_maps_each_spot_to_darkness(void)
{
    world_reset(1);
    settings.line_sensor.cal_min[0] = 500;
    settings.line_sensor.cal_max[0] = 1500;
    settings_generation++;
    uint16_t raw[8] = {1000, 4095, 0, 100, 2000, 1050, 3000, 5};
    uint16_t dark[8];
    int16_t pos;
    for (int i = 0; i < 8; i++)
        line_sensor_evaluate(raw, dark, &pos);
    CHECK(dark[0] == 499 || dark[0] == 500, "half way: %u", dark[0]);
    CHECK(dark[1] == 1000 && dark[2] == 0 && dark[3] == 0 && dark[4] == 1000 && dark[7] == 0, "clamped");
    settings.line_sensor.cal_max[2] = 50; /* max below min: uncalibrated, dark above cal_min */
    settings_generation++;
    raw[2] = 200;
    for (int i = 0; i < 8; i++)
        line_sensor_evaluate(raw, dark, &pos);
    CHECK(dark[2] == 1000, "inverted calibration does not divide by zero: %u", dark[2]);
}

static void acquisition_suppresses_ambient_light(void)
{
    world_reset(1);
    world.line_enabled = 1;
    world.line_y = 0.0;
    world_run_ms(20);
    CHECK(world.emitter_masks_seen == ((1 << 0) | (1 << 0x15) | (1 << 0x0A)), "phases: dark, {0,2,4}, {1,3}: %x",
          world.emitter_masks_seen);
    int16_t p1 = robot_state.line.position;
    uint16_t r1 = robot_state.line.raw[3];
    world.ambient = 1500; /* a lamp comes on */
    world_run_ms(5);
    CHECK(robot_state.line.position == p1 && robot_state.line.raw[3] == r1, "ambient light has no effect");
    CHECK(abs(p1) < 100 && (robot_state.line.flags & PB_LINE_FLAG_SEEN), "centred line seen at %d", p1);
    world.line_y = -0.003; /* the line moves to the robot's right */
    world_run_ms(5);
    CHECK(robot_state.line.position > 200, "line to the right at %d", robot_state.line.position);
}

static void line_lost_after_timeout(void)
{
    world_reset(1);
    world.line_enabled = 0;
    world_run_ms(settings.line_follow.lost_timeout_ms - 20);
    CHECK(!(robot_state.line.flags & PB_LINE_FLAG_LOST), "not lost yet");
    world_run_ms(40);
    CHECK(robot_state.line.flags == PB_LINE_FLAG_LOST, "lost: flags %x", robot_state.line.flags);
    world.line_enabled = 1;
    world_run_ms(5);
    CHECK(robot_state.line.flags == PB_LINE_FLAG_SEEN, "found again: flags %x", robot_state.line.flags);
}

static void follower_converges_onto_the_line(void)
{
    world_reset(1);
    settings.link.failsafe_timeout_ms = 0;
    world.line_enabled = 1;
    world.line_y = -0.004; /* 4 mm to the right of the robot */
    pb_line_follow_t c = {1, PB_COLOUR_MODE_PLAIN, 0.0f};
    host_send(PB_PKT_LINE_FOLLOW, 1, &c, sizeof c);
    world_run_ms(1500);
    CHECK(robot_state.line_follow.status == PB_LINE_FOLLOW_STATUS_FOLLOWING, "following");
    CHECK(world.x > 0.1, "moved forward %.0f mm", world.x * 1000);
    CHECK(fabs(world.y - world.line_y) < 0.0015, "on the line: %.2f mm off", (world.y - world.line_y) * 1000);
    CHECK(fabs(world_heading_deg()) < 5.0, "heading %.1f deg", world_heading_deg());
}

static void colour_segments_change_speed(void)
{
    world_reset(1);
    settings.link.failsafe_timeout_ms = 0;
    world.line_enabled = 1;
    pb_line_follow_t c = {1, PB_COLOUR_MODE_SEGMENTS, 0.0f};
    host_send(PB_PKT_LINE_FOLLOW, 1, &c, sizeof c);
    world.colour[0] = 20; world.colour[1] = 20; world.colour[2] = 25; world.colour[3] = 20; /* black tape */
    world_run_ms(600);
    double v_black = (world.v[0] + world.v[1]) / 2;
    world.colour[0] = 200; world.colour[1] = 30; world.colour[2] = 30; world.colour[3] = 90; /* red */
    world_run_ms(600);
    double v_red = (world.v[0] + world.v[1]) / 2;
    CHECK(robot_state.line_follow.segment == PB_COLOUR_RED, "segment %u", robot_state.line_follow.segment);
    world.colour[0] = 30; world.colour[1] = 40; world.colour[2] = 200; world.colour[3] = 90; /* blue */
    world_run_ms(600);
    double v_blue = (world.v[0] + world.v[1]) / 2;
    CHECK(fabs(v_black - settings.line_follow.speed_mps) < 0.02 && fabs(v_red - settings.line_follow.red_speed_mps) < 0.02 &&
              fabs(v_blue - settings.line_follow.blue_speed_mps) < 0.03,
          "black %.3f red %.3f blue %.3f m/s", v_black, v_red, v_blue);
}

static void lost_line_stops_and_link_loss_respects_autonomy(void)
{
    world_reset(1);
    world.line_enabled = 1;
    pb_line_follow_t c = {1, PB_COLOUR_MODE_PLAIN, 0.1f};
    host_send(PB_PKT_LINE_FOLLOW, 1, &c, sizeof c);
    world_run_ms(1500); /* no host packets: autonomous line following goes on */
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_LINE_FOLLOW && world.v[0] > 0.05, "autonomous");
    world.line_enabled = 0;
    world_run_ms(settings.line_follow.lost_timeout_ms + 150);
    CHECK(robot_state.line_follow.status == PB_LINE_FOLLOW_STATUS_LOST && fabs(world.v[0]) < 0.01, "stopped: lost");

    world_reset(1);
    settings.line_follow.autonomous = 0;
    world.line_enabled = 1;
    host_send(PB_PKT_LINE_FOLLOW, 1, &c, sizeof c);
    world_run_ms(1100);
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_FAILSAFE &&
              robot_state.line_follow.status == PB_LINE_FOLLOW_STATUS_OFF, "not autonomous: failsafe");
}

void suite_line(void)
{
    RUN(position_does_not_depend_on_line_width);
    RUN(of_two_lines_the_one_nearest_to_the_last_position_counts);
    RUN(calibration_maps_each_spot_to_darkness);
    RUN(acquisition_suppresses_ambient_light);
    RUN(line_lost_after_timeout);
    RUN(follower_converges_onto_the_line);
    RUN(colour_segments_change_speed);
    RUN(lost_line_stops_and_link_loss_respects_autonomy);
}
