/* Several hosts on one robot: one drives, the others watch; take-over, goodbye, the failsafe's guard, the drive
 * across a reconnect, answers to the asking link, framed links. Link 0 is the UART (the test's host drives it
 * after world_reset()), links 1 and 2 the emulator's further links. */
#include <stddef.h>
#include <string.h>

#include "core/data.h"
#include "harness.h"
#include "modules/comm.h"
#include "protocol/pb_frame.h"
#include "world.h"

_Static_assert(COMM_LINKS >= 3, "these tests use three links");

static int driver_on(int link, int n, pb_driver_t *out)
{
    const host_frame_t *f = link == 0 ? host_find(PB_PKT_DRIVER, n) : link_find(link, PB_PKT_DRIVER, n);
    if (f == NULL || f->len != sizeof *out)
        return 0;
    memcpy(out, f->payload, sizeof *out);
    return 1;
}

static int count_on(int link, uint8_t type)
{
    return link == 0 ? host_count(type) : link_count(link, type);
}

static const pb_error_t *error_on(int link, int n)
{
    const host_frame_t *f = link == 0 ? host_find(PB_PKT_ERROR, n) : link_find(link, PB_PKT_ERROR, n);
    return f ? (const pb_error_t *)f->payload : NULL;
}

static void collect_all(void)
{
    host_collect();
    for (int k = 1; k < (int)COMM_LINKS; k++)
        link_collect(k);
}

/* Forgets what every link got so far, what is still on its way included. */
static void clear_all(void)
{
    collect_all();
    host_clear();
    for (int k = 1; k < (int)COMM_LINKS; k++)
        link_clear(k);
}

/* Runs `ms` with a heartbeat from the driver on link 0 every 100 ms (and from `also`, if not 0). */
static void run_with_heartbeats(int ms, int also)
{
    for (int t = 0; t < ms; t += 100) {
        host_send(PB_PKT_HEARTBEAT, 0, NULL, 0);
        if (also)
            link_send(also, PB_PKT_HEARTBEAT, 0, NULL, 0);
        world_run_ms(ms - t < 100 ? ms - t : 100);
    }
}

static void move(int link, uint16_t id, uint8_t seq, float distance)
{
    pb_move_straight_t m = {id, distance, 0.1f};
    if (link == 0)
        host_send(PB_PKT_MOVE_STRAIGHT, seq, &m, sizeof m);
    else
        link_send(link, PB_PKT_MOVE_STRAIGHT, seq, &m, sizeof m);
}

/* The outcome of movement `id` as link `link` heard it, or -1. */
static int outcome_on(int link, uint16_t id)
{
    for (int i = 0; i < 64; i++) {
        const host_frame_t *f = link == 0 ? host_find(PB_PKT_MOVEMENT_DONE, i) : link_find(link, PB_PKT_MOVEMENT_DONE, i);
        if (f == NULL)
            return -1;
        pb_movement_done_t d;
        memcpy(&d, f->payload, sizeof d);
        if (d.id == id)
            return d.outcome;
    }
    return -1;
}

static void a_second_host_watches_while_the_first_drives(void)
{
    world_reset(1);
    link_open(1);
    link_handshake(1, 0x2222, PB_HOST_ROLE_DRIVE, "panel@lab-pc");
    world_run_ms(5);
    collect_all();
    pb_driver_t d;
    CHECK(link_count(1, PB_PKT_HELLO) == 1 && driver_on(1, 0, &d), "hello and driver on link 1");
    CHECK(d.role == PB_HOST_ROLE_WATCH && d.change == PB_DRIVER_CHANGE_NONE && strcmp(d.label, WORLD_LABEL) == 0,
          "it watches, and is told who drives: role %u change %u '%.16s'", d.role, d.change, d.label);
    const host_frame_t *ack = link_find(1, PB_PKT_ACK, 0);
    CHECK(ack && ack->payload[0] == PB_PKT_SET_ROLE && link_find(1, PB_PKT_DRIVER, 0) < ack, "driver before the ack");
    CHECK(host_count(PB_PKT_HELLO) == 0 && host_count(PB_PKT_DRIVER) == 0, "the driver is not disturbed");

    /* A watcher's command is refused, and it is told again who drives. */
    clear_all();
    move(1, 5, 9, 0.05f);
    pb_wheel_speeds_t w = {0.1f, 0.1f};
    link_send(1, PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(5);
    collect_all();
    const pb_error_t *e = error_on(1, 0);
    CHECK(e && e->code == PB_ERROR_CODE_NOT_DRIVER && e->packet_type == PB_PKT_MOVE_STRAIGHT && e->seq == 9,
          "not_driver for the movement");
    e = error_on(1, 1);
    CHECK(e && e->code == PB_ERROR_CODE_NOT_DRIVER && e->packet_type == PB_PKT_WHEEL_SPEEDS, "and for teleoperation");
    CHECK(robot_state.locomotion.queue_length == 0 && robot_state.locomotion.mode == PB_LOCO_MODE_IDLE, "nothing moves");
    CHECK(driver_on(1, 0, &d) && strcmp(d.label, WORLD_LABEL) == 0, "who drives, with the refusal");
    CHECK(host_count(PB_PKT_ERROR) == 0, "the refusals go to the watcher only");

    /* The driver's commands run; state and debug text reach both; reads are answered to the asker only. */
    clear_all();
    move(0, 6, 3, 0.02f);
    link_send(1, PB_PKT_READ_SETTINGS, 4, NULL, 0);
    run_with_heartbeats(800, 1);
    collect_all();
    CHECK(host_find(PB_PKT_ACK, 0) && host_find(PB_PKT_ACK, 0)->payload[0] == PB_PKT_MOVE_STRAIGHT, "driver's move acked");
    CHECK(count_on(0, PB_PKT_STATE_FULL) >= 2 && count_on(1, PB_PKT_STATE_FULL) >= 2, "state to both: %d %d",
          count_on(0, PB_PKT_STATE_FULL), count_on(1, PB_PKT_STATE_FULL));
    CHECK(outcome_on(0, 6) == PB_MOVEMENT_OUTCOME_FINISHED && outcome_on(1, 6) == PB_MOVEMENT_OUTCOME_FINISHED,
          "movement results to both");
    CHECK(link_count(1, PB_PKT_SETTINGS_DATA) == 3 && host_count(PB_PKT_SETTINGS_DATA) == 0, "settings to the asker");
    CHECK(link_hosts[1].bad == 0 && host_bad_frames == 0, "every frame whole on both links");
}

static void a_take_over_moves_the_drive_and_tells_both(void)
{
    world_reset(1);
    move(0, 1, 1, 0.5f);
    world_run_ms(50);
    link_open(1);
    link_handshake(1, 0x2222, PB_HOST_ROLE_TAKE_OVER, "cli@lab-pc");
    world_run_ms(5);
    collect_all();
    pb_driver_t d;
    CHECK(driver_on(1, 0, &d) && d.role == PB_HOST_ROLE_DRIVE && d.change == PB_DRIVER_CHANGE_TAKEN_OVER &&
              strcmp(d.label, "cli@lab-pc") == 0, "the new driver: role %u change %u", d.role, d.change);
    CHECK(driver_on(0, 0, &d) && d.role == PB_HOST_ROLE_WATCH && d.change == PB_DRIVER_CHANGE_TAKEN_OVER &&
              strcmp(d.label, "cli@lab-pc") == 0, "the old one is told: role %u change %u '%.16s'", d.role, d.change,
          d.label);
    CHECK(comm_driver_link() == 1, "link 1 drives");
    CHECK(robot_state.locomotion.current_id == 1, "what the old driver queued goes on");
    clear_all();
    move(0, 2, 2, 0.05f);
    move(1, 3, 2, 0.05f);
    world_run_ms(5);
    collect_all();
    CHECK(error_on(0, 0) && error_on(0, 0)->code == PB_ERROR_CODE_NOT_DRIVER, "the old driver is refused");
    CHECK(link_find(1, PB_PKT_ACK, 0) && robot_state.locomotion.queue_length == 2, "the new one queues: %u",
          robot_state.locomotion.queue_length);
    /* Asking to drive is not taking over. */
    clear_all();
    host_handshake(WORLD_SESSION, PB_HOST_ROLE_DRIVE, WORLD_LABEL);
    world_run_ms(5);
    collect_all();
    CHECK(comm_driver_link() == 1 && driver_on(0, 0, &d) && d.role == PB_HOST_ROLE_WATCH, "drive waits its turn: %u %d %u",
          comm_driver_link(), driver_on(0, 0, &d), d.role);
    pb_set_role_t r = {7, "x"};
    host_send(PB_PKT_SET_ROLE, 8, &r, sizeof r);
    world_run_ms(5);
    collect_all();
    const pb_error_t *e = error_on(0, 0);
    CHECK(e && e->code == PB_ERROR_CODE_BAD_ARGUMENT && e->detail == offsetof(pb_set_role_t, role), "role 7 refused");
}

static void anyone_may_stop_the_robot(void)
{
    world_reset(1);
    move(0, 1, 1, 0.5f);
    move(0, 2, 2, 0.5f);
    link_open(2);
    link_handshake(2, 0x3333, PB_HOST_ROLE_WATCH, "phone");
    run_with_heartbeats(200, 0);
    pb_stop_t st = {0};
    link_send(2, PB_PKT_STOP, 5, &st, sizeof st);
    run_with_heartbeats(500, 0);
    collect_all();
    CHECK(link_find(2, PB_PKT_ACK, 1) && link_find(2, PB_PKT_ACK, 1)->payload[0] == PB_PKT_STOP, "the watcher's stop acked");
    CHECK(outcome_on(0, 1) == PB_MOVEMENT_OUTCOME_STOPPED && outcome_on(0, 2) == PB_MOVEMENT_OUTCOME_DROPPED,
          "the driver's movements end: %d %d", outcome_on(0, 1), outcome_on(0, 2));
    CHECK(comm_driver_link() == 0, "the drive stays where it was");
}

static void the_failsafe_guards_the_drivers_link_only(void)
{
    world_reset(1);
    link_open(1);
    link_handshake(1, 0x2222, PB_HOST_ROLE_WATCH, "panel");
    move(0, 1, 1, 1.0f);
    /* The driver falls silent; the watcher keeps talking. */
    for (int t = 0; t < 1200; t += 50) {
        link_send(1, PB_PKT_HEARTBEAT, 0, NULL, 0);
        world_run_ms(50);
    }
    world_run_ms(400);
    collect_all();
    CHECK(outcome_on(1, 1) == PB_MOVEMENT_OUTCOME_FAILSAFE, "the failsafe stopped it: %d", outcome_on(1, 1));
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_FAILSAFE, "mode failsafe");
    /* Nobody else asked to drive: the silent driver still has the drive when it speaks again. */
    clear_all();
    move(0, 2, 2, 0.02f);
    world_run_ms(5);
    host_collect();
    CHECK(host_find(PB_PKT_ACK, 0) && robot_state.locomotion.current_id == 2, "back, and still the driver");
}

static void goodbye_lets_the_queue_finish_or_drops_it(void)
{
    world_reset(1);
    move(0, 1, 1, 0.1f);
    move(0, 2, 2, 0.1f);
    world_run_ms(20);
    pb_goodbye_t g = {PB_LEAVE_QUEUE_FINISH};
    host_send(PB_PKT_GOODBYE, 3, &g, sizeof g);
    world_run_ms(5);
    host_collect();
    const host_frame_t *ack = host_find(PB_PKT_ACK, 2);
    CHECK(ack && ack->payload[0] == PB_PKT_GOODBYE && ack->seq == 3, "goodbye acked");
    CHECK(comm_driver_link() == COMM_NO_LINK, "nobody drives");
    world_run_ms(4000); /* no host packet: far past the failsafe */
    host_collect();
    CHECK(outcome_on(0, 1) == PB_MOVEMENT_OUTCOME_FINISHED && outcome_on(0, 2) == PB_MOVEMENT_OUTCOME_FINISHED,
          "both finished: %d %d", outcome_on(0, 1), outcome_on(0, 2));
    CHECK(world.x > 0.19 && world.x < 0.21, "0.2 m driven: %.3f", world.x);

    /* A driver that asks to watch leaves its queue to the robot as a goodbye would: no failsafe. */
    host_clear();
    host_handshake(WORLD_SESSION, PB_HOST_ROLE_DRIVE, WORLD_LABEL);
    move(0, 9, 9, 0.1f);
    world_run_ms(20);
    host_handshake(WORLD_SESSION, PB_HOST_ROLE_WATCH, WORLD_LABEL);
    world_run_ms(3000);
    host_collect();
    CHECK(outcome_on(0, 9) == PB_MOVEMENT_OUTCOME_FINISHED, "finished: %d", outcome_on(0, 9));

    /* Teleoperation ends with its host; a dropped queue is a stop. */
    host_clear();
    host_handshake(WORLD_SESSION, PB_HOST_ROLE_DRIVE, WORLD_LABEL);
    move(0, 3, 4, 0.3f);
    move(0, 4, 5, 0.3f);
    world_run_ms(100);
    g.queue = PB_LEAVE_QUEUE_DROP;
    host_send(PB_PKT_GOODBYE, 6, &g, sizeof g);
    world_run_ms(600);
    host_collect();
    CHECK(outcome_on(0, 3) == PB_MOVEMENT_OUTCOME_STOPPED && outcome_on(0, 4) == PB_MOVEMENT_OUTCOME_DROPPED,
          "dropped: %d %d", outcome_on(0, 3), outcome_on(0, 4));
    host_handshake(WORLD_SESSION, PB_HOST_ROLE_DRIVE, WORLD_LABEL);
    pb_wheel_speeds_t w = {0.1f, 0.1f};
    host_send(PB_PKT_WHEEL_SPEEDS, 0, &w, sizeof w);
    world_run_ms(50);
    g.queue = PB_LEAVE_QUEUE_FINISH;
    host_send(PB_PKT_GOODBYE, 7, &g, sizeof g);
    world_run_ms(5);
    CHECK(robot_state.locomotion.mode == PB_LOCO_MODE_IDLE, "teleoperation ended: mode %u", robot_state.locomotion.mode);

    /* A watcher's goodbye changes nothing. */
    host_handshake(WORLD_SESSION, PB_HOST_ROLE_DRIVE, WORLD_LABEL);
    move(0, 5, 8, 0.3f);
    link_open(1);
    link_handshake(1, 0x2222, PB_HOST_ROLE_WATCH, "watcher");
    pb_goodbye_t drop = {PB_LEAVE_QUEUE_DROP};
    link_send(1, PB_PKT_GOODBYE, 9, &drop, sizeof drop);
    world_run_ms(20);
    link_collect(1);
    CHECK(link_find(1, PB_PKT_ACK, 1) && link_find(1, PB_PKT_ACK, 1)->payload[0] == PB_PKT_GOODBYE, "acked");
    CHECK(robot_state.locomotion.current_id == 5 && comm_driver_link() == 0, "still moving, still driven");
    g.queue = 2;
    host_send(PB_PKT_GOODBYE, 10, &g, sizeof g);
    world_run_ms(5);
    host_clear();
    host_collect();
    CHECK(comm_driver_link() == 0, "a bad goodbye is refused and leaves nothing");
}

static void a_waiting_host_drives_when_the_driver_leaves_or_falls_silent(void)
{
    world_reset(1);
    link_open(1);
    link_handshake(1, 0x2222, PB_HOST_ROLE_DRIVE, "panel");
    world_run_ms(5);
    pb_goodbye_t g = {PB_LEAVE_QUEUE_FINISH};
    host_send(PB_PKT_GOODBYE, 3, &g, sizeof g);
    world_run_ms(5);
    collect_all();
    pb_driver_t d;
    CHECK(comm_driver_link() == 1, "the waiting host drives");
    CHECK(driver_on(1, 1, &d) && d.role == PB_HOST_ROLE_DRIVE && d.change == PB_DRIVER_CHANGE_LEFT &&
              strcmp(d.label, "panel") == 0, "and is told: role %u change %u", d.role, d.change);
    CHECK(driver_on(0, 0, &d) && d.role == PB_HOST_ROLE_WATCH && strcmp(d.label, "panel") == 0, "so is the leaver");

    /* The new driver moves, then falls silent while a third host waits to drive. */
    move(1, 7, 1, 1.0f);
    link_open(2);
    link_handshake(2, 0x3333, PB_HOST_ROLE_DRIVE, "phone");
    int handed_at = -1;
    for (int t = 0; t < 1500 && handed_at < 0; t += 10) {
        link_send(2, PB_PKT_HEARTBEAT, 0, NULL, 0);
        world_run_ms(10);
        if (comm_driver_link() == 2)
            handed_at = t;
    }
    world_run_ms(400);
    collect_all();
    CHECK(handed_at >= 990 && handed_at <= 1020, "handed over after the failsafe timeout: %d ms", handed_at);
    CHECK(outcome_on(2, 7) == PB_MOVEMENT_OUTCOME_FAILSAFE, "after the failsafe stopped the silent driver's movement");
    CHECK(driver_on(2, 1, &d) && d.role == PB_HOST_ROLE_DRIVE && d.change == PB_DRIVER_CHANGE_LOST, "told why: %u",
          d.change);
    clear_all();
    move(1, 8, 2, 0.05f);
    world_run_ms(5);
    link_collect(1);
    CHECK(error_on(1, 0) && error_on(1, 0)->code == PB_ERROR_CODE_NOT_DRIVER, "the silent one lost the drive");
}

static void a_driver_that_returns_on_another_link_keeps_its_drive_and_its_history(void)
{
    world_reset(1);
    link_open(1);
    link_handshake(1, 0xBEEF, PB_HOST_ROLE_TAKE_OVER, "panel");
    move(1, 1, 7, 0.02f);
    world_run_ms(5);
    link_close(1);
    world_run_ms(300); /* an outage shorter than the failsafe */
    link_open(2);
    link_clear(2);
    pb_hello_request_t h = {PB_PROTOCOL_VERSION, 0xBEEF};
    link_send(2, PB_PKT_HELLO_REQUEST, 1, &h, sizeof h);
    move(2, 1, 7, 0.02f); /* the retransmission of the command in flight */
    world_run_ms(5);
    link_collect(2);
    const host_frame_t *f = link_find(2, PB_PKT_HELLO, 0);
    CHECK(f && ((const pb_hello_t *)f->payload)->session_resumed == 1, "the session resumed on another link");
    CHECK(link_find(2, PB_PKT_ACK, 0) && robot_state.locomotion.queue_length <= 1, "acked, not queued twice: %u",
          robot_state.locomotion.queue_length);
    CHECK(comm_driver_link() == 2, "it still drives");
    move(2, 2, 8, 0.02f);
    world_run_ms(5);
    CHECK(robot_state.locomotion.queue_length >= 1 && robot_state.locomotion.current_id != 0, "and moves");
    CHECK(link_hosts[2].bad == 0, "link 2's frames whole");
}

static void a_read_asked_on_two_links_is_answered_on_each(void)
{
    world_reset(1);
    link_open(1);
    link_handshake(1, 0x2222, PB_HOST_ROLE_WATCH, "panel");
    world_run_ms(5);
    clear_all();
    /* Link 1's host reads nothing for a while: its answer waits for room, and link 0's request for the same waits
     * meanwhile. */
    world.stuck_links = 1 << 1;
    world_run_ms(250);
    link_send(1, PB_PKT_READ_SETTINGS, 12, NULL, 0);
    world_run_ms(20);
    host_send(PB_PKT_READ_SETTINGS, 11, NULL, 0);
    world_run_ms(20);
    host_collect();
    CHECK(host_count(PB_PKT_SETTINGS_DATA) == 0 && host_count(PB_PKT_ACK) == 0, "link 0 waits");
    world.stuck_links = 0;
    world_run_ms(100);
    host_send(PB_PKT_READ_SETTINGS, 11, NULL, 0); /* asked again, as the host does after its ack timeout */
    world_run_ms(100);
    collect_all();
    CHECK(link_count(1, PB_PKT_SETTINGS_DATA) == 3 && link_find(1, PB_PKT_ACK, 0) &&
              link_find(1, PB_PKT_ACK, 0)->seq == 12, "link 1 answered");
    CHECK(host_count(PB_PKT_SETTINGS_DATA) == 3 && host_find(PB_PKT_ACK, 0) && host_find(PB_PKT_ACK, 0)->seq == 11,
          "link 0 answered once");
    CHECK(link_hosts[1].bad == 0 && host_bad_frames == 0, "whole");
}

static void a_link_that_stops_reading_does_not_stall_the_others(void)
{
    world_reset(1);
    link_open(1);
    link_handshake(1, 0x2222, PB_HOST_ROLE_WATCH, "stuck");
    world_run_ms(5);
    uint16_t dropped = robot_state.errors.tx_dropped;
    clear_all();
    move(0, 1, 1, 0.2f);
    world.stuck_links = 1 << 1;
    run_with_heartbeats(3000, 0);
    host_collect();
    CHECK(outcome_on(0, 1) == PB_MOVEMENT_OUTCOME_FINISHED, "the driver got its result: %d", outcome_on(0, 1));
    CHECK(host_count(PB_PKT_STATE_FULL) >= 29, "and its states: %d", host_count(PB_PKT_STATE_FULL));
    CHECK(robot_state.errors.tx_dropped > dropped, "what link 1 had no room for is counted");
    link_collect(1);
    CHECK(link_hosts[1].bad == 0, "what link 1 got is whole");
}

static void closed_links_get_nothing_and_bytes_for_them_are_ignored(void)
{
    world_reset(1);
    link_open(1);
    link_handshake(1, 0x2222, PB_HOST_ROLE_WATCH, "panel");
    world_run_ms(5);
    link_close(1);
    link_collect(1);
    link_clear(1);
    move(1, 1, 3, 0.05f);
    world_run_ms(300);
    link_collect(1);
    CHECK(link_hosts[1].count == 0, "nothing sent to a closed link: %d", link_hosts[1].count);
    CHECK(robot_state.locomotion.queue_length == 0 && robot_state.errors.rejected == 0, "its bytes are not read");
    /* A link past the last, and an open without a driver, change nothing. */
    comm_link_open(COMM_LINKS, &comm_uart_link);
    comm_link_open(1, NULL);
    comm_link_close(COMM_LINKS, COMM_LINK_LOST);
    comm_link_rx(COMM_LINKS, (const uint8_t *)"x", 1);
    world_run_ms(5);
    CHECK(comm_driver_link() == 0, "untouched");
}

/* ---- a framed link (an L2CAP channel): one frame per unit, no SLIP ---- */

static struct {
    uint8_t frames[32][PB_MAX_FRAME];
    uint16_t sizes[32];
    int count;
    uint16_t room;
} framed;

static uint16_t framed_room(uint8_t link)
{
    (void)link;
    return framed.room;
}

static void framed_write(uint8_t link, const uint8_t *p, uint16_t n)
{
    (void)link;
    if (framed.count < 32 && n <= PB_MAX_FRAME) {
        memcpy(framed.frames[framed.count], p, n);
        framed.sizes[framed.count++] = n;
    }
}

static const comm_link_driver_t framed_driver = {true, framed_room, framed_write, NULL, NULL, NULL};

static void framed_send(uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    uint8_t frame[PB_MAX_FRAME];
    uint16_t n = pb_frame_encode(frame, type, seq, payload, len);
    comm_link_rx(2, frame, n);
}

/* The n-th frame of `type` written to the framed link, checked whole. */
static int framed_find(uint8_t type, int n, pb_frame_t *out)
{
    for (int i = 0; i < framed.count; i++)
        if (pb_frame_check(framed.frames[i], framed.sizes[i], out) == PB_ERROR_CODE_NONE && out->type == type &&
            n-- == 0)
            return 1;
    return 0;
}

static void a_framed_link_carries_whole_frames(void)
{
    world_reset(1);
    memset(&framed, 0, sizeof framed);
    framed.room = 512;
    comm_link_open(2, &framed_driver);
    pb_hello_request_t h = {PB_PROTOCOL_VERSION, 0x4444};
    framed_send(PB_PKT_HELLO_REQUEST, 1, &h, sizeof h);
    pb_set_role_t r = {PB_HOST_ROLE_TAKE_OVER, "l2cap"};
    framed_send(PB_PKT_SET_ROLE, 2, &r, sizeof r);
    pb_move_straight_t m = {9, 0.02f, 0.1f};
    framed_send(PB_PKT_MOVE_STRAIGHT, 3, &m, sizeof m);
    world_run_ms(250);
    pb_frame_t f;
    CHECK(framed_find(PB_PKT_HELLO, 0, &f) && f.seq == 1, "hello as one frame");
    CHECK(framed_find(PB_PKT_DRIVER, 0, &f) && ((const pb_driver_t *)f.payload)->role == PB_HOST_ROLE_DRIVE, "drives");
    CHECK(framed_find(PB_PKT_ACK, 1, &f) && f.seq == 3, "the movement acked");
    CHECK(framed_find(PB_PKT_STATE_FULL, 1, &f) && f.len == sizeof(pb_robot_state_t), "streamed state whole");
    int whole = 1;
    for (int i = 0; i < framed.count; i++)
        whole &= pb_frame_check(framed.frames[i], framed.sizes[i], &f) == PB_ERROR_CODE_NONE;
    CHECK(whole, "every unit one sound frame");
    /* A corrupted unit is counted and answered; a full link misses packets, counted. */
    uint8_t frame[PB_MAX_FRAME];
    uint16_t n = pb_frame_encode(frame, PB_PKT_HEARTBEAT, 0, NULL, 0);
    frame[n - 1] ^= 0x55;
    uint16_t crc_errors = robot_state.errors.crc;
    comm_link_rx(2, frame, n);
    framed.room = 10;
    uint16_t dropped = robot_state.errors.tx_dropped;
    world_run_ms(200);
    CHECK(robot_state.errors.crc == crc_errors + 1, "bad CRC counted");
    CHECK(robot_state.errors.tx_dropped > dropped, "no room: counted");
    comm_link_close(2, COMM_LINK_LOST);
}

void suite_links(void)
{
    RUN(a_second_host_watches_while_the_first_drives);
    RUN(a_take_over_moves_the_drive_and_tells_both);
    RUN(anyone_may_stop_the_robot);
    RUN(the_failsafe_guards_the_drivers_link_only);
    RUN(goodbye_lets_the_queue_finish_or_drops_it);
    RUN(a_waiting_host_drives_when_the_driver_leaves_or_falls_silent);
    RUN(a_driver_that_returns_on_another_link_keeps_its_drive_and_its_history);
    RUN(a_read_asked_on_two_links_is_answered_on_each);
    RUN(a_link_that_stops_reading_does_not_stall_the_others);
    RUN(closed_links_get_nothing_and_bytes_for_them_are_ignored);
    RUN(a_framed_link_carries_whole_frames);
}
