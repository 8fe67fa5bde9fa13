#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "core/data.h"
#include "harness.h"
#include "modules/comm.h"
#include "modules/settings.h"
#include "protocol/pb_frame.h"
#include "protocol/slip.h"
#include "world.h"

static const pb_error_t *error_packet(int n)
{
    const host_frame_t *f = host_find(PB_PKT_ERROR, n);
    return f ? (const pb_error_t *)f->payload : NULL;
}

static int hello_packet(int n, pb_hello_t *out)
{
    const host_frame_t *f = host_find(PB_PKT_HELLO, n);
    if (f == NULL || f->len != sizeof *out)
        return 0;
    memcpy(out, f->payload, sizeof *out);
    return 1;
}

static void hello_request(uint32_t session)
{
    pb_hello_request_t r = {PB_PROTOCOL_VERSION, session};
    host_send(PB_PKT_HELLO_REQUEST, 0, &r, sizeof r);
}

static void hello_at_reset_and_on_request(void)
{
    world_power_on(5);
    world_run_ms(2);
    host_collect();
    pb_hello_t h;
    CHECK(hello_packet(0, &h), "hello at reset");
    CHECK(h.robot_id == 5 && h.layout_hash == PB_LAYOUT_HASH && h.settings_size == sizeof(pb_settings_t) &&
              h.state_size == sizeof(pb_robot_state_t) && h.protocol_version == PB_PROTOCOL_VERSION &&
              h.session_resumed == 0, "fields");
    CHECK(h.settings_crc == pb_crc16(0xFFFF, (const uint8_t *)&settings, sizeof settings), "settings CRC");
    hello_request(0x1234);
    world_run_ms(2);
    host_collect();
    CHECK(host_count(PB_PKT_HELLO) == 2 && hello_packet(1, &h) && h.session_resumed == 0, "a new session");
    hello_request(0x1234);
    world_run_ms(2);
    host_collect();
    CHECK(hello_packet(2, &h) && h.session_resumed == 1, "the same session again: resumed");
    hello_request(0);
    hello_request(0);
    world_run_ms(2);
    host_collect();
    CHECK(hello_packet(3, &h) && h.session_resumed == 0 && hello_packet(4, &h) && h.session_resumed == 0,
          "session 0 is never resumed");
    /* The CRC follows the settings. */
    settings.line_follow.speed_mps = 0.2f;
    hello_request(0x99);
    world_run_ms(2);
    host_collect();
    CHECK(hello_packet(5, &h) && h.settings_crc == pb_crc16(0xFFFF, (const uint8_t *)&settings, sizeof settings),
          "CRC of the settings as they are now");
}

static void state_is_reflected_at_the_configured_mode_and_period(void)
{
    world_reset(1);
    world_run_ms(1000);
    int full = host_count(PB_PKT_STATE_FULL);
    CHECK(full >= 9 && full <= 11, "full state every 100 ms: %d", full);
    pb_set_sync_t s = {PB_SYNC_MODE_REDUCED, 5};
    host_send(PB_PKT_SET_SYNC, 9, &s, sizeof s);
    host_clear();
    world_run_ms(100);
    const host_frame_t *ack = host_find(PB_PKT_ACK, 0);
    CHECK(ack && ack->seq == 9 && ack->payload[0] == PB_PKT_SET_SYNC, "set_sync acked");
    int red = host_count(PB_PKT_STATE_REDUCED);
    CHECK(red >= 18 && red <= 21 && host_count(PB_PKT_STATE_FULL) <= 1, "reduced every 5 ms: %d", red);
    s.mode = 3;
    host_send(PB_PKT_SET_SYNC, 10, &s, sizeof s);
    world_run_ms(2);
    host_collect();
    CHECK(error_packet(0) && error_packet(0)->code == PB_ERROR_CODE_BAD_ARGUMENT && error_packet(0)->seq == 10,
          "bad mode refused");
    s.mode = PB_SYNC_MODE_NONE;
    s.period_ms = 1;
    host_send(PB_PKT_SET_SYNC, 11, &s, sizeof s);
    world_run_ms(2);
    host_collect();
    host_clear();
    world_run_ms(100);
    CHECK(host_count(PB_PKT_STATE_REDUCED) + host_count(PB_PKT_STATE_FULL) == 0, "mode none sends nothing");
}

static void a_full_transmit_buffer_skips_and_counts(void)
{
    world_reset(1);
    pb_set_sync_t s = {PB_SYNC_MODE_FULL, 1};
    host_send(PB_PKT_SET_SYNC, 1, &s, sizeof s);
    /* Nobody drains the link for 50 ms: the 256-byte buffer holds two state packets at most. */
    for (int i = 1; i <= 50; i++)
        sim_advance((int64_t)i * 32000);
    CHECK(robot_state.errors.tx_dropped >= 40, "dropped %u", robot_state.errors.tx_dropped);
    host_collect();
    CHECK(host_bad_frames == 0, "what was queued is whole: %d bad", host_bad_frames);
}

static void retransmitted_command_is_acked_but_not_executed_twice(void)
{
    world_reset(1);
    host_handshake(0xABCD, PB_HOST_ROLE_TAKE_OVER, "other@host");
    world_run_ms(1);
    host_collect();
    host_clear();
    pb_move_straight_t m = {1, 0.05f, 0.1f};
    host_send(PB_PKT_MOVE_STRAIGHT, 42, &m, sizeof m);
    host_send(PB_PKT_MOVE_STRAIGHT, 42, &m, sizeof m); /* identical: a retransmission */
    m.id = 2;
    host_send(PB_PKT_MOVE_ROTATE, 42, &m, sizeof m); /* same seq, other type: a new command */
    m.distance_m = 0.06f;
    host_send(PB_PKT_MOVE_STRAIGHT, 42, &m, sizeof m); /* same seq and type, other payload: a new command */
    world_run_ms(2);
    host_collect();
    CHECK(host_count(PB_PKT_ACK) == 4, "acks %d", host_count(PB_PKT_ACK));
    CHECK(robot_state.locomotion.queue_length == 3, "queue %u", robot_state.locomotion.queue_length);
    /* 16 other commands later the first is forgotten and executes again. */
    for (int i = 0; i < 16; i++) {
        pb_set_sync_t s = {PB_SYNC_MODE_FULL, (uint16_t)(100 + i)};
        host_send(PB_PKT_SET_SYNC, (uint8_t)(100 + i), &s, sizeof s);
    }
    m.id = 1;
    m.distance_m = 0.05f;
    host_send(PB_PKT_MOVE_STRAIGHT, 42, &m, sizeof m);
    world_run_ms(2);
    CHECK(robot_state.locomotion.queue_length == 4, "queue %u", robot_state.locomotion.queue_length);
    /* The same session resumed (a reconnect) keeps the history: a retransmission is still recognised. */
    hello_request(0xABCD);
    host_send(PB_PKT_MOVE_STRAIGHT, 42, &m, sizeof m);
    world_run_ms(2);
    CHECK(robot_state.locomotion.queue_length == 4, "resumed session: not executed twice (%u)",
          robot_state.locomotion.queue_length);
}

static void two_hosts_in_turn_get_every_command_executed(void)
{
    world_reset(1);
    /* Host A, then host B with the same sequence numbers and the same (identical!) frames: each is a new
     * session, so nothing B sends is taken for A's. */
    for (int host = 0; host < 2; host++) {
        host_handshake(host == 0 ? 0x1111u : 0x2222u, PB_HOST_ROLE_TAKE_OVER, "host");
        for (uint8_t seq = 1; seq <= 5; seq++) {
            pb_move_straight_t m = {seq, 0.01f, 0.1f};
            host_send(PB_PKT_MOVE_STRAIGHT, seq, &m, sizeof m);
        }
        world_run_ms(2);
    }
    CHECK(robot_state.locomotion.queue_length == 10 ||
              robot_state.locomotion.queue_length + host_count(PB_PKT_MOVEMENT_DONE) == 10,
          "all 10 executed: queue %u", robot_state.locomotion.queue_length);
    /* A host without a session (0) clears the history too. */
    pb_move_straight_t m = {6, 0.01f, 0.1f};
    host_send(PB_PKT_MOVE_STRAIGHT, 9, &m, sizeof m);
    host_handshake(0, PB_HOST_ROLE_TAKE_OVER, "anonymous");
    host_send(PB_PKT_MOVE_STRAIGHT, 9, &m, sizeof m);
    world_run_ms(2);
    CHECK(robot_state.locomotion.queue_length == 12, "queue %u", robot_state.locomotion.queue_length);
}

static void acked_commands_need_a_sequence_number(void)
{
    world_reset(1);
    pb_move_straight_t m = {1, 0.05f, 0.1f};
    host_send(PB_PKT_MOVE_STRAIGHT, 0, &m, sizeof m);
    world_run_ms(2);
    host_collect();
    const pb_error_t *e = error_packet(0);
    CHECK(e && e->code == PB_ERROR_CODE_BAD_SEQUENCE && e->packet_type == PB_PKT_MOVE_STRAIGHT && e->seq == 0,
          "seq 0 refused");
    CHECK(robot_state.locomotion.queue_length == 0 && robot_state.errors.rejected == 1, "not executed, counted");
}

static void bad_packets_are_counted_and_answered(void)
{
    world_reset(1);
    uint8_t payload[16] = {0};
    host_send(0x7E, 3, payload, 2); /* unknown type */
    host_send(PB_PKT_HELLO, 4, payload, 0); /* robot-to-host type from the host */
    host_send(PB_PKT_MOVE_STRAIGHT, 5, payload, 4); /* length disagrees with the type */
    host_send(PB_PKT_MOVE_STRAIGHT, 6, payload, 10); /* id 0 */
    pb_set_sync_t s = {PB_SYNC_MODE_FULL, 0};
    host_send(PB_PKT_SET_SYNC, 7, &s, sizeof s); /* period 0 */
    pb_update_settings_t u = {0, 0, {0}};
    host_send(PB_PKT_UPDATE_SETTINGS, 8, &u, PB_UPDATE_SETTINGS_HEAD_SIZE); /* no data */
    world_run_ms(2);
    host_collect();
    CHECK(robot_state.errors.rejected == 6, "rejected %u", robot_state.errors.rejected);
    const pb_error_t *e;
    CHECK((e = error_packet(0)) && e->code == PB_ERROR_CODE_UNKNOWN_TYPE && e->seq == 3 && e->packet_type == 0x7E,
          "unknown");
    CHECK((e = error_packet(1)) && e->code == PB_ERROR_CODE_UNKNOWN_TYPE && e->seq == 4, "direction");
    CHECK((e = error_packet(2)) && e->code == PB_ERROR_CODE_BAD_LENGTH && e->seq == 5 && e->detail == 4, "length");
    CHECK((e = error_packet(3)) && e->code == PB_ERROR_CODE_BAD_ARGUMENT && e->seq == 6 &&
              e->detail == offsetof(pb_move_straight_t, id), "argument");
    CHECK((e = error_packet(4)) && e->code == PB_ERROR_CODE_BAD_ARGUMENT && e->seq == 7 &&
              e->detail == offsetof(pb_set_sync_t, period_ms), "argument offset %u", e ? e->detail : 0);
    CHECK((e = error_packet(5)) && e->code == PB_ERROR_CODE_BAD_LENGTH && e->seq == 8 &&
              e->detail == PB_UPDATE_SETTINGS_HEAD_SIZE, "an update without data is refused by its size");

    /* A sound CRC around a header length that disagrees with the frame: refused, not framing. */
    uint8_t frame[PB_MAX_FRAME + 8], slip[2 * sizeof frame];
    uint16_t n = pb_frame_encode(frame, PB_PKT_HEARTBEAT, 0, payload, 2);
    frame[2] = 1;
    uint16_t crc = pb_crc16(0xFFFF, frame, (uint16_t)(n - 2));
    frame[n - 2] = (uint8_t)crc;
    frame[n - 1] = (uint8_t)(crc >> 8);
    host_clear();
    host_send_raw(slip, slip_encode(slip, frame, n));
    world_run_ms(2);
    host_collect();
    CHECK(robot_state.errors.rejected == 7 && robot_state.errors.framing == 0, "rejected %u framing %u",
          robot_state.errors.rejected, robot_state.errors.framing);
    CHECK((e = error_packet(0)) && e->code == PB_ERROR_CODE_BAD_LENGTH && e->packet_type == PB_PKT_HEARTBEAT,
          "answered with the frame's type");
}

static void unreadable_frames_are_counted_and_reported_at_a_limited_rate(void)
{
    world_reset(1);
    world_run_ms(200);
    host_collect();
    host_clear();
    /* A bad CRC. */
    uint8_t frame[PB_MAX_FRAME + 8], slip[2 * sizeof frame + 2];
    uint16_t n = pb_frame_encode(frame, PB_PKT_HEARTBEAT, 0, NULL, 0);
    frame[n - 1] ^= 1;
    host_send_raw(slip, slip_encode(slip, frame, n));
    world_run_ms(150);
    /* Too short. */
    const uint8_t shorty[] = {0xC0, 1, 2, 0xC0};
    host_send_raw(shorty, sizeof shorty);
    world_run_ms(150);
    /* Too long: 130 bytes between the ENDs. */
    uint8_t longy[132];
    memset(longy, 0x11, sizeof longy);
    longy[0] = longy[131] = 0xC0;
    host_send_raw(longy, sizeof longy);
    world_run_ms(150);
    /* A broken escape. */
    const uint8_t broken[] = {0xC0, 1, 0xDB, 7, 2, 0xC0};
    host_send_raw(broken, sizeof broken);
    world_run_ms(150);
    host_collect();
    CHECK(robot_state.errors.crc == 1 && robot_state.errors.framing == 3 && robot_state.errors.rejected == 0,
          "crc %u framing %u rejected %u", robot_state.errors.crc, robot_state.errors.framing,
          robot_state.errors.rejected);
    const uint8_t codes[4] = {PB_ERROR_CODE_BAD_CRC, PB_ERROR_CODE_TOO_SHORT, PB_ERROR_CODE_TOO_LONG,
                              PB_ERROR_CODE_FRAMING};
    const uint16_t lengths[4] = {5, 2, 130, 3};
    CHECK(host_count(PB_PKT_ERROR) == 4, "one answer each: %d", host_count(PB_PKT_ERROR));
    for (int i = 0; i < 4; i++) {
        const pb_error_t *e = error_packet(i);
        CHECK(e && e->code == codes[i] && e->packet_type == 0 && e->seq == 0 && e->detail == lengths[i],
              "answer %d: code %u type %u seq %u detail %u", i, e ? e->code : 0, e ? e->packet_type : 0,
              e ? e->seq : 0, e ? e->detail : 0);
    }
    /* A burst of garbage: every frame counted, at most one answer per 100 ms. */
    host_clear();
    for (int k = 0; k < 50; k++) {
        host_send_raw(slip, slip_encode(slip, frame, n));
        world_run_ms(2);
    }
    world_run_ms(10);
    host_collect();
    CHECK(robot_state.errors.crc == 51, "counted %u", robot_state.errors.crc);
    CHECK(host_count(PB_PKT_ERROR) >= 1 && host_count(PB_PKT_ERROR) <= 2, "answers in 110 ms: %d",
          host_count(PB_PKT_ERROR));
}

static void settings_are_written_read_saved_and_reset_over_the_link(void)
{
    world_reset(1);
    pb_update_settings_t u;
    u.offset = offsetof(pb_settings_t, line_follow.speed_mps);
    u.length = 4;
    float v = 0.2f;
    memcpy(u.data, &v, 4);
    host_send(PB_PKT_UPDATE_SETTINGS, 7, &u, 7);
    world_run_ms(2);
    host_collect();
    CHECK(settings.line_follow.speed_mps == 0.2f && host_find(PB_PKT_ACK, 0), "applied and acked");
    v = 5.0f;
    memcpy(u.data, &v, 4);
    host_send(PB_PKT_UPDATE_SETTINGS, 8, &u, 7);
    u.length = 5; /* length field disagrees with the payload */
    host_send(PB_PKT_UPDATE_SETTINGS, 9, &u, 7);
    u.length = 4;
    u.offset = 1000;
    host_send(PB_PKT_UPDATE_SETTINGS, 10, &u, 7);
    world_run_ms(2);
    host_collect();
    const pb_error_t *e;
    CHECK((e = error_packet(0)) && e->code == PB_ERROR_CODE_SETTINGS_VALUE && e->seq == 8 &&
              e->detail == offsetof(pb_settings_t, line_follow.speed_mps), "value");
    CHECK((e = error_packet(1)) && e->code == PB_ERROR_CODE_BAD_LENGTH && e->seq == 9, "length field");
    CHECK((e = error_packet(2)) && e->code == PB_ERROR_CODE_SETTINGS_RANGE && e->seq == 10 && e->detail == 1000,
          "range");
    CHECK(settings.line_follow.speed_mps == 0.2f, "unchanged by refusals");

    host_clear();
    host_send(PB_PKT_READ_SETTINGS, 11, NULL, 0);
    world_run_ms(20);
    host_collect();
    uint8_t image[sizeof(pb_settings_t)];
    memset(image, 0xEE, sizeof image);
    int chunks = host_count(PB_PKT_SETTINGS_DATA);
    for (int i = 0; i < chunks; i++) {
        const host_frame_t *f = host_find(PB_PKT_SETTINGS_DATA, i);
        pb_settings_data_t d;
        memcpy(&d, f->payload, f->len);
        CHECK(d.length == f->len - 3 && d.offset + d.length <= sizeof image, "chunk %d", i);
        memcpy(image + d.offset, d.data, d.length);
    }
    CHECK(chunks == 3 && memcmp(image, &settings, sizeof image) == 0, "chunks %d reassemble the settings", chunks);
    const host_frame_t *ack = host_find(PB_PKT_ACK, 0);
    CHECK(ack && ack->seq == 11 && ack > host_find(PB_PKT_SETTINGS_DATA, chunks - 1), "ack after the data");

    host_send(PB_PKT_SAVE_SETTINGS, 12, NULL, 0);
    host_send(PB_PKT_LOAD_DEFAULTS, 13, NULL, 0);
    world_run_ms(20);
    host_collect();
    CHECK(settings.line_follow.speed_mps == pb_settings_defaults.line_follow.speed_mps, "defaults");
    CHECK(settings_load() && settings.line_follow.speed_mps == 0.2f, "saved copy in EEPROM");
}

static void garbage_on_the_link_never_hurts(void)
{
    world_reset(1);
    srand(1234);
    uint8_t buf[4096];
    for (int round = 0; round < 50; round++) {
        for (unsigned i = 0; i < sizeof buf; i++) {
            int r = rand();
            buf[i] = (uint8_t)((r & 0x700) == 0 ? 0xC0 : (r & 0x3800) == 0 ? 0xDB : r);
        }
        host_send_raw(buf, sizeof buf);
        world_run_ms(20);
    host_collect();
    }
    CHECK(robot_state.errors.rx_overflow > 0, "overflow counted");
    /* Still alive and answering. */
    host_clear();
    hello_request(7);
    world_run_ms(5);
    host_collect();
    CHECK(host_count(PB_PKT_HELLO) == 1, "answers after the garbage");
}

void suite_comm(void)
{
    RUN(hello_at_reset_and_on_request);
    RUN(state_is_reflected_at_the_configured_mode_and_period);
    RUN(a_full_transmit_buffer_skips_and_counts);
    RUN(retransmitted_command_is_acked_but_not_executed_twice);
    RUN(two_hosts_in_turn_get_every_command_executed);
    RUN(acked_commands_need_a_sequence_number);
    RUN(bad_packets_are_counted_and_answered);
    RUN(unreadable_frames_are_counted_and_reported_at_a_limited_rate);
    RUN(settings_are_written_read_saved_and_reset_over_the_link);
    RUN(garbage_on_the_link_never_hurts);
}
