#include <math.h>
#include <string.h>

#include "core/data.h"
#include "harness.h"
#include "modules/track.h"
#include "world.h"

/* An IR message heard on `side` (0 front, 1 rear); a track message is {kind, to, hop}. */
static void heard(int side, int sender, int led, int power)
{
    sim_ir_rx(side, sender, led, power, 0, 0, 0);
}

static void heard_msg(int side, int sender, uint8_t kind, uint8_t to, uint8_t hop)
{
    sim_ir_rx(side, sender, 2, 100, TRACK_MSG_LEN, (int32_t)(kind | (uint32_t)to << 8 | (uint32_t)hop << 16), 0);
}

/* The last track message the robot sent, as kind | to << 8 | hop << 16; 0 if none since the last call (of those the
 * world kept: 64 IR messages, about 300 ms). */
static uint32_t sent_msg(void)
{
    uint32_t last = 0;
    for (int i = 0; i < world.ir_count; i++)
        if (world.ir[i].len == TRACK_MSG_LEN)
            last = world.ir[i].lo & 0xFFFFFFu;
    world.ir_count = 0;
    return last;
}

static uint32_t msg(uint8_t kind, uint8_t to, uint8_t hop)
{
    return kind | (uint32_t)to << 8 | (uint32_t)hop << 16;
}

/* How many times the robot sent track message `m` (from all four LEDs: counted once) since the last call, which
 * forgets them all; call it at least every 200 ms (the world keeps 64 IR messages). */
static int times_sent(uint32_t m)
{
    int n = 0;
    for (int i = 0; i < world.ir_count; i++)
        n += world.ir[i].len == TRACK_MSG_LEN && world.ir[i].led == 0 && (world.ir[i].lo & 0xFFFFFFu) == m;
    world.ir_count = 0;
    return n;
}

/* A robot on a straight line along x, the behaviour started by the host. */
static void start_on_line(int32_t id)
{
    world_reset(id);
    world.line_enabled = 1;
    world.line_y = 0.0;
    uint8_t start = PB_TRACK_ACTION_START;
    host_send(PB_PKT_TRACK, 1, &start, 1);
    world_run_ms(2);
    world.ir_count = 0;
}

static double speed(void)
{
    return (world.v[0] + world.v[1]) / 2;
}

static void the_command_starts_stops_and_refuses_unknown_actions(void)
{
    start_on_line(2);
    host_collect();
    CHECK(host_find(PB_PKT_ACK, 0) != NULL, "start acknowledged");
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_TRACK, "track mode: %u", robot_state.locomotion.mode);
    world_run_ms(1000);
    CHECK(robot_state.track.status == PB_TRACK_STATUS_FOLLOWING, "following: %u", robot_state.track.status);
    CHECK(fabs(speed() - settings.track.speed_mps) < 0.02, "at the track speed: %.3f m/s", speed());
    CHECK(fabs(world.y) < 0.002, "on the line: %.1f mm off", world.y * 1000);
    CHECK(robot_state.track.token == 0, "robot 2 does not create the token");
    uint8_t bad = 3;
    host_send(PB_PKT_TRACK, 2, &bad, 1);
    world_run_ms(2);
    host_collect();
    const host_frame_t *e = host_find(PB_PKT_ERROR, 0);
    CHECK(e && e->payload[0] == PB_ERROR_CODE_BAD_ARGUMENT, "action 3 refused as bad_argument");
    uint8_t stop = PB_TRACK_ACTION_STOP;
    host_send(PB_PKT_TRACK, 3, &stop, 1);
    world_run_ms(300);
    CHECK(robot_state.track.status == PB_TRACK_STATUS_OFF && robot_state.locomotion.mode == PB_LOCO_MODE_IDLE,
          "stopped: status %u mode %u", robot_state.track.status, robot_state.locomotion.mode);
    CHECK(speed() < 0.01, "motors off: %.3f m/s", speed());
}

static void the_origin_creates_the_token_and_shows_it(void)
{
    start_on_line(1); /* settings.track.token_origin_id is 1 */
    world_run_ms(10);
    CHECK(robot_state.track.token == 1, "robot 1 holds the token");
    CHECK(robot_state.indicators.led & PB_LED_FLAG_TOKEN, "the token LED is on: %x", robot_state.indicators.led);
    CHECK(robot_state.track.token_visits == 0, "creating it is no visit");
    world_run_ms(500);
    CHECK(speed() > 1.8 * settings.track.speed_mps, "the holder hurries: %.3f m/s", speed());
}

/* Robot 7 behind hands the token to robot 2 as hop 5, every message heard: 2 holds it at hop 5 then. */
static void given_the_token_by_7(void)
{
    heard_msg(1, 7, TRACK_MSG_OFFER, 2, 5);
    world_run_ms(100);
    heard_msg(1, 7, TRACK_MSG_GIVE, 2, 5);
    world_run_ms(100);
    sent_msg();
}

/* Robot `id` heard ahead at mid distance (its rear LED at 100 and 50 %) for `ms`. */
static void ahead_mid(int id, int ms)
{
    for (int i = 0; i < ms / 40; i++) {
        heard(0, id, 2, 100);
        heard(0, id, 2, 50);
        world_run_ms(40);
    }
}

static void an_offer_is_accepted_and_the_token_taken_only_from_the_give(void)
{
    start_on_line(2);
    heard_msg(1, 7, TRACK_MSG_OFFER, 2, 5); /* robot 7 behind offers it as hop 5 */
    world_run_ms(100);
    CHECK(sent_msg() == msg(TRACK_MSG_ACCEPT, 7, 5), "accepted hop 5 from robot 7");
    CHECK(robot_state.track.token == 0 && robot_state.track.token_visits == 0, "not taken on the offer: 7 still holds it");
    heard_msg(1, 7, TRACK_MSG_OFFER, 2, 5); /* the ACCEPT was lost: the same offer again */
    world_run_ms(100);
    CHECK(sent_msg() == msg(TRACK_MSG_ACCEPT, 7, 5), "accepted again");
    CHECK(robot_state.track.token == 0, "still not taken");
    heard_msg(1, 7, TRACK_MSG_GIVE, 2, 5); /* 7 heard an ACCEPT and let go */
    world_run_ms(100);
    CHECK(robot_state.track.token == 1 && robot_state.track.token_visits == 1, "taken: token %u visits %u",
          robot_state.track.token, robot_state.track.token_visits);
    CHECK(robot_state.indicators.led & PB_LED_FLAG_TOKEN, "token LED on");
    CHECK(sent_msg() == msg(TRACK_MSG_TAKEN, 7, 5), "answered TAKEN to 7, hop 5");
    heard_msg(1, 7, TRACK_MSG_GIVE, 2, 5); /* the TAKEN was lost: 7 gives again */
    world_run_ms(100);
    CHECK(robot_state.track.token == 1 && robot_state.track.token_visits == 1, "kept, no second visit: token %u visits %u",
          robot_state.track.token, robot_state.track.token_visits);
    CHECK(sent_msg() == msg(TRACK_MSG_TAKEN, 7, 5), "answered TAKEN again");
    heard_msg(1, 7, TRACK_MSG_OFFER, 2, 5); /* an old offer heard late: we hold it, nothing to accept */
    world_run_ms(100);
    CHECK(sent_msg() == 0, "no answer to an offer while holding the token");
    host_collect();
    CHECK(host_count(PB_PKT_IR_RECEIVED) == 0, "the robots' conversation is not forwarded to the host");
}

static void messages_for_other_robots_and_gives_never_accepted_are_not_taken(void)
{
    start_on_line(2);
    heard_msg(1, 7, TRACK_MSG_OFFER, 3, 5); /* an offer to robot 3, heard by us too */
    heard_msg(1, 7, TRACK_MSG_GIVE, 3, 5);
    world_run_ms(100);
    CHECK(sent_msg() == 0 && robot_state.track.token == 0, "robot 3's hand-over is none of ours");
    heard_msg(1, 7, TRACK_MSG_OFFER, 2, 5);
    world_run_ms(100);
    CHECK(sent_msg() == msg(TRACK_MSG_ACCEPT, 7, 5), "accepted hop 5 from 7");
    heard_msg(1, 8, TRACK_MSG_GIVE, 2, 5); /* robot 8 never offered it to us */
    heard_msg(1, 7, TRACK_MSG_GIVE, 2, 4);
    world_run_ms(100);
    CHECK(robot_state.track.token == 0 && robot_state.track.token_visits == 0, "a GIVE that is no offer we accepted is not taken");
}

static void the_holder_lets_go_only_when_its_offer_is_accepted(void)
{
    start_on_line(2);
    given_the_token_by_7();
    ahead_mid(9, 240);
    CHECK(sent_msg() == msg(TRACK_MSG_OFFER, 9, 6), "offered to robot 9 as hop 6");
    CHECK(robot_state.track.token == 1, "kept until robot 9 accepts");
    heard_msg(0, 9, TRACK_MSG_ACCEPT, 2, 5);
    heard_msg(0, 8, TRACK_MSG_ACCEPT, 2, 6);
    ahead_mid(9, 40);
    CHECK(robot_state.track.token == 1, "an answer for another hop or from another robot does not count");
    heard_msg(0, 9, TRACK_MSG_ACCEPT, 2, 6);
    ahead_mid(9, 80);
    CHECK(robot_state.track.token == 0, "let go on robot 9's ACCEPT");
    CHECK(!(robot_state.indicators.led & PB_LED_FLAG_TOKEN), "token LED off");
    CHECK(sent_msg() == msg(TRACK_MSG_GIVE, 9, 6), "gives it to robot 9");
    heard_msg(0, 9, TRACK_MSG_ACCEPT, 2, 6); /* robot 9 heard the offer once more */
    ahead_mid(9, 80);
    CHECK(robot_state.track.token == 0 && sent_msg() == msg(TRACK_MSG_GIVE, 9, 6), "still giving, not holding");
}

static void an_offer_stays_with_its_robot_until_it_times_out(void)
{
    start_on_line(2);
    given_the_token_by_7();
    ahead_mid(9, 160);
    CHECK(sent_msg() == msg(TRACK_MSG_OFFER, 9, 6), "offered to robot 9");
    for (int i = 0; i < 3; i++) { /* robot 8 comes between, nearer: robot 9 may have accepted all the same */
        heard(0, 8, 2, 25);
        world_run_ms(40);
    }
    uint32_t m = sent_msg();
    CHECK(m == msg(TRACK_MSG_OFFER, 9, 6), "still offered to robot 9: %06x", (unsigned)m);
    heard_msg(0, 8, TRACK_MSG_ACCEPT, 2, 6);
    world_run_ms(40);
    CHECK(robot_state.track.token == 1, "robot 8's accept of an offer to robot 9 does not count");
    for (int i = 0; i < 10; i++) { /* no answer from robot 9: the offer times out, robot 8 is ahead now */
        heard(0, 8, 2, 25);
        world_run_ms(40);
        uint32_t last = sent_msg();
        m = last ? last : m;
    }
    CHECK(robot_state.track.token == 1, "a withdrawn offer leaves the token with us");
    CHECK(m == msg(TRACK_MSG_OFFER, 8, 6), "offered to robot 8 after the timeout: %06x", (unsigned)m);
    heard_msg(0, 8, TRACK_MSG_ACCEPT, 2, 6);
    world_run_ms(80);
    CHECK(robot_state.track.token == 0 && sent_msg() == msg(TRACK_MSG_GIVE, 8, 6), "given to robot 8");
}

static void a_give_is_repeated_until_taken_even_after_a_stop(void)
{
    start_on_line(2);
    given_the_token_by_7();
    ahead_mid(9, 120);
    heard_msg(0, 9, TRACK_MSG_ACCEPT, 2, 6);
    world_run_ms(200); /* robot 9 out of hearing now, its TAKENs lost */
    sent_msg();
    uint8_t stop = PB_TRACK_ACTION_STOP;
    host_send(PB_PKT_TRACK, 2, &stop, 1);
    int gives = 0;
    for (int i = 0; i < 5; i++) {
        world_run_ms(100);
        gives += times_sent(msg(TRACK_MSG_GIVE, 9, 6));
    }
    CHECK(robot_state.track.status == PB_TRACK_STATUS_OFF, "stopped");
    CHECK(gives >= 12, "gave on at every beacon, stopped or not: %d GIVEs in 500 ms", gives);
    heard_msg(0, 9, TRACK_MSG_TAKEN, 2, 5);
    heard_msg(0, 8, TRACK_MSG_TAKEN, 2, 6);
    world_run_ms(100);
    CHECK(sent_msg() == msg(TRACK_MSG_GIVE, 9, 6), "a TAKEN of another hop or robot does not end it");
    heard_msg(0, 9, TRACK_MSG_TAKEN, 2, 6);
    world_run_ms(100);
    sent_msg();
    world_run_ms(200);
    CHECK(sent_msg() == 0, "robot 9 has it: no more GIVEs");
    CHECK(robot_state.track.token == 0 && robot_state.track.token_visits == 1, "token %u visits %u",
          robot_state.track.token, robot_state.track.token_visits);
}

static void a_robot_that_handed_the_token_on_still_answers_the_old_give(void)
{
    start_on_line(2);
    given_the_token_by_7(); /* robot 7 missed our TAKENs: it will go on giving hop 5 */
    ahead_mid(9, 120);
    heard_msg(0, 9, TRACK_MSG_ACCEPT, 2, 6);
    world_run_ms(80);
    heard_msg(0, 9, TRACK_MSG_TAKEN, 2, 6);
    world_run_ms(80);
    sent_msg();
    CHECK(robot_state.track.token == 0, "handed on to robot 9");
    heard_msg(1, 7, TRACK_MSG_GIVE, 2, 5); /* robot 7's old hand-over */
    world_run_ms(100);
    CHECK(sent_msg() == msg(TRACK_MSG_TAKEN, 7, 5), "answered TAKEN, so that robot 7 can stop");
    CHECK(robot_state.track.token == 0 && robot_state.track.token_visits == 1, "not taken again: token %u visits %u",
          robot_state.track.token, robot_state.track.token_visits);
}

static void a_robot_still_giving_that_gets_the_token_back_stops_giving(void)
{
    start_on_line(2);
    given_the_token_by_7();
    ahead_mid(9, 120);
    heard_msg(0, 9, TRACK_MSG_ACCEPT, 2, 6);
    world_run_ms(200); /* giving hop 6 to robot 9, no TAKEN heard */
    sent_msg();
    heard_msg(1, 3, TRACK_MSG_OFFER, 2, 8); /* meanwhile 9 handed it on, and robot 3 brings it back as hop 8 */
    world_run_ms(100);
    int accepts = times_sent(msg(TRACK_MSG_ACCEPT, 3, 8));
    CHECK(accepts == 1, "accepted from robot 3 while still giving: %d ACCEPTs", accepts);
    heard_msg(1, 3, TRACK_MSG_GIVE, 2, 8);
    world_run_ms(100);
    CHECK(robot_state.track.token == 1 && robot_state.track.token_visits == 2, "taken: token %u visits %u",
          robot_state.track.token, robot_state.track.token_visits);
    sent_msg();
    world_run_ms(200);
    CHECK(times_sent(msg(TRACK_MSG_GIVE, 9, 6)) == 0, "the old hand-over is over");
}

static void robots_close_by_are_greeted_and_a_greeting_names_the_robot_met(void)
{
    start_on_line(2);
    heard(1, 8, 0, 50); /* robot 8 behind, facing us, mid */
    world_run_ms(100);
    CHECK(sent_msg() == msg(TRACK_MSG_GREET, 8, 0), "greeted robot 8");
    heard(1, 8, 0, 50);
    world_run_ms(100);
    CHECK(sent_msg() == 0, "once while it stays in hearing");
    heard_msg(1, 8, TRACK_MSG_GREET, 2, 0);
    world_run_ms(5);
    CHECK(robot_state.track.met_id == 8, "met robot 8: %u", robot_state.track.met_id);
}

static void the_distance_to_the_robot_ahead_is_kept(void)
{
    start_on_line(2);
    world_run_ms(600);
    double cruise = speed();
    for (int i = 0; i < 10; i++) {
        heard(0, 9, 2, 50);
        world_run_ms(40);
    }
    CHECK(speed() < 0.6 * cruise && speed() > 0.3 * cruise, "mid: half speed, %.3f of %.3f m/s", speed(), cruise);
    CHECK(robot_state.track.status == PB_TRACK_STATUS_KEEPING_DISTANCE, "keeping distance");
    for (int i = 0; i < 10; i++) {
        heard(0, 9, 2, 25);
        world_run_ms(40);
    }
    CHECK(speed() < 0.005, "near: waits, %.3f m/s", speed());
    world_run_ms(settings.proximity.hold_ms + 1000);
    CHECK(speed() < 0.005, "gone from the beam: still waits, it may only have turned away, %.3f m/s", speed());
    world_run_ms(1500);
    CHECK(speed() > 0.8 * cruise && robot_state.track.status == PB_TRACK_STATUS_FOLLOWING, "way clear: on again, %.3f m/s, status %u", speed(), robot_state.track.status);
    for (int i = 0; i < 10; i++) {
        heard(0, 9, 2, 100);
        world_run_ms(40);
    }
    CHECK(robot_state.track.status == PB_TRACK_STATUS_FOLLOWING, "far: full speed, status %u", robot_state.track.status);
    world_run_ms(settings.proximity.hold_ms + 1000);
    CHECK(robot_state.track.status == PB_TRACK_STATUS_KEEPING_DISTANCE && speed() < 0.6 * cruise && speed() > 0.3 * cruise, "gone from the beam far ahead: half speed a while, %.3f of %.3f m/s", speed(), cruise);
    world_run_ms(1500);
    CHECK(speed() > 0.8 * cruise && robot_state.track.status == PB_TRACK_STATUS_FOLLOWING, "way clear: on again, %.3f m/s, status %u", speed(), robot_state.track.status);
}

static void an_obstacle_ahead_starts_a_detour_off_the_line(void)
{
    start_on_line(2);
    world_run_ms(300);
    for (int i = 0; i < 5; i++) {
        heard(0, 2, 0, 100); /* our own beacon reflected */
        world_run_ms(40);
    }
    CHECK(robot_state.track.status == PB_TRACK_STATUS_DETOUR, "detour: %u", robot_state.track.status);
    world_run_ms(1500);
    CHECK(world.y < -0.02, "left the line to the right: y %.1f mm", world.y * 1000);
}

static void the_link_failsafe_leaves_the_behaviour_running(void)
{
    start_on_line(2);
    settings.link.failsafe_timeout_ms = 300;
    world_run_ms(2000); /* not a byte from the host */
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_TRACK, "still track mode: %u", robot_state.locomotion.mode);
    CHECK(speed() > 0.8 * settings.track.speed_mps, "still driving: %.3f m/s", speed());
}

static void another_command_ends_the_behaviour(void)
{
    start_on_line(2);
    world_run_ms(200);
    pb_line_follow_t c = {1, PB_COLOUR_MODE_PLAIN, 0.0f};
    host_send(PB_PKT_LINE_FOLLOW, 2, &c, sizeof c);
    world_run_ms(5);
    CHECK(robot_state.track.status == PB_TRACK_STATUS_OFF, "off after line_follow: %u", robot_state.track.status);
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_LINE_FOLLOW, "line following has the motors");
}

static void reverse_turns_round_and_follows_the_line_the_other_way(void)
{
    start_on_line(2);
    world_run_ms(500);
    double x0 = world.x;
    uint8_t reverse = PB_TRACK_ACTION_REVERSE;
    host_send(PB_PKT_TRACK, 2, &reverse, 1);
    world_run_ms(5);
    CHECK(robot_state.track.status == PB_TRACK_STATUS_TURNING, "turning: %u", robot_state.track.status);
    world_run_ms(3000);
    double h = fmod(fabs(world_heading_deg()), 360.0);
    CHECK(fabs(h - 180.0) < 15.0, "heading %.0f deg", world_heading_deg());
    CHECK(robot_state.track.status == PB_TRACK_STATUS_FOLLOWING, "following again: %u", robot_state.track.status);
    CHECK(world.x < x0 - 0.05, "driving back: x %.0f mm from %.0f", world.x * 1000, x0 * 1000);
    CHECK(fabs(world.y) < 0.003, "on the line: %.1f mm off", world.y * 1000);
}

/* Put down beside the line (x along it), facing +x turned by `deg`, `mm` to its left: the sensor does not see it. */
static void moved_off_the_line(double mm, double deg)
{
    world.y = mm / 1000.0;
    world.theta = deg * M_PI / 180.0;
}

static void a_robot_beside_the_line_sweeps_for_it_and_follows_it_again(void)
{
    start_on_line(2);
    world_run_ms(500);
    moved_off_the_line(20, 0);
    double x0 = world.x;
    world_run_ms(400);
    CHECK(robot_state.track.status == PB_TRACK_STATUS_LOST, "searching: %u", robot_state.track.status);
    world_run_ms(3000);
    CHECK(robot_state.track.status == PB_TRACK_STATUS_FOLLOWING, "following again: %u", robot_state.track.status);
    CHECK(fabs(world.y) < 0.003, "on the line: %.1f mm off", world.y * 1000);
    CHECK(fabs(world_heading_deg()) < 20.0 && world.x > x0 + 0.05, "on the way it went: heading %.0f deg, x %.0f mm from %.0f",
          world_heading_deg(), world.x * 1000, x0 * 1000);
}

static void a_robot_further_off_backs_up_to_where_the_line_was(void)
{
    start_on_line(2);
    world_run_ms(500);
    moved_off_the_line(30, 30); /* drove off it to the left: out of a sweep's reach */
    double x0 = world.x;
    world_run_ms(6000);
    CHECK(world.x < x0 || robot_state.track.status == PB_TRACK_STATUS_FOLLOWING, "backed up: x %.0f mm from %.0f", world.x * 1000, x0 * 1000);
    CHECK(robot_state.track.status == PB_TRACK_STATUS_FOLLOWING, "following again: %u", robot_state.track.status);
    CHECK(fabs(world.y) < 0.003 && fabs(world_heading_deg()) < 20.0, "on the line: %.1f mm off, heading %.0f deg", world.y * 1000, world_heading_deg());
}

static void a_search_that_finds_no_line_stops_and_reverse_still_works(void)
{
    start_on_line(2);
    world_run_ms(500);
    world.line_enabled = 0;
    double x0 = world.x;
    world_run_ms(15000);
    CHECK(robot_state.track.status == PB_TRACK_STATUS_LOST && robot_state.locomotion.mode == PB_LOCO_MODE_TRACK,
          "lost, still in track mode: status %u mode %u", robot_state.track.status, robot_state.locomotion.mode);
    CHECK(speed() < 0.005 && fabs(world.v[0] - world.v[1]) < 0.005, "given up: standing still, %.3f m/s", speed());
    CHECK(fabs(world.x - x0) < 0.2, "bounded: %.0f mm from where it lost the line", (world.x - x0) * 1000);
    uint8_t reverse = PB_TRACK_ACTION_REVERSE;
    host_send(PB_PKT_TRACK, 2, &reverse, 1);
    world_run_ms(5);
    world.line_enabled = 1;
    CHECK(robot_state.track.status == PB_TRACK_STATUS_TURNING, "turning: %u", robot_state.track.status);
    double x1 = world.x;
    world_run_ms(3000);
    CHECK(fabs(fmod(fabs(world_heading_deg()), 360.0) - 180.0) < 20.0, "heading %.0f deg", world_heading_deg());
    CHECK(robot_state.track.status == PB_TRACK_STATUS_FOLLOWING && world.x < x1 - 0.05, "following back: status %u, x %.0f mm from %.0f",
          robot_state.track.status, world.x * 1000, x1 * 1000);
}

void suite_track(void)
{
    RUN(the_command_starts_stops_and_refuses_unknown_actions);
    RUN(the_origin_creates_the_token_and_shows_it);
    RUN(an_offer_is_accepted_and_the_token_taken_only_from_the_give);
    RUN(messages_for_other_robots_and_gives_never_accepted_are_not_taken);
    RUN(the_holder_lets_go_only_when_its_offer_is_accepted);
    RUN(an_offer_stays_with_its_robot_until_it_times_out);
    RUN(a_give_is_repeated_until_taken_even_after_a_stop);
    RUN(a_robot_that_handed_the_token_on_still_answers_the_old_give);
    RUN(a_robot_still_giving_that_gets_the_token_back_stops_giving);
    RUN(robots_close_by_are_greeted_and_a_greeting_names_the_robot_met);
    RUN(the_distance_to_the_robot_ahead_is_kept);
    RUN(an_obstacle_ahead_starts_a_detour_off_the_line);
    RUN(the_link_failsafe_leaves_the_behaviour_running);
    RUN(another_command_ends_the_behaviour);
    RUN(reverse_turns_round_and_follows_the_line_the_other_way);
    RUN(a_robot_beside_the_line_sweeps_for_it_and_follows_it_again);
    RUN(a_robot_further_off_backs_up_to_where_the_line_was);
    RUN(a_search_that_finds_no_line_stops_and_reverse_still_works);
}
