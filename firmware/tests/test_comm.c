#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "modules/comm.h"
#include "modules/reflector.h"
#include "modules/settings.h"
#include "protocol/pb_frame.h"
#include "protocol/slip.h"
#include "world.h"

static const pb_error_t *error_packet(int n)
{
    const host_frame_t *f = host_find(PB_PKT_ERROR, n);
    return f ? (const pb_error_t *)f->payload : NULL;
}

static void hello_at_reset_and_on_request(void)
{
    world_reset(5);
    world_run_ms(2);
    host_collect();
    const host_frame_t *f = host_find(PB_PKT_HELLO, 0);
    CHECK(f != NULL && f->len == PB_HELLO_SIZE, "hello at reset");
    if (f) {
        pb_hello_t h;
        memcpy(&h, f->payload, sizeof h);
        CHECK(h.robot_id == 5 && h.layout_hash == PB_LAYOUT_HASH && h.settings_size == sizeof(pb_settings_t) &&
                  h.state_size == sizeof(pb_robot_state_t) && h.protocol_version == PB_PROTOCOL_VERSION, "fields");
    }
    pb_hello_request_t r = {1};
    host_send(PB_PKT_HELLO_REQUEST, 0, &r, sizeof r);
    world_run_ms(2);
    host_collect();
    CHECK(host_count(PB_PKT_HELLO) == 2, "hello on request");
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
    pb_move_straight_t m = {1, 0.05f, 0.1f};
    host_send(PB_PKT_MOVE_STRAIGHT, 42, &m, sizeof m);
    host_send(PB_PKT_MOVE_STRAIGHT, 42, &m, sizeof m);
    m.id = 2;
    host_send(PB_PKT_MOVE_ROTATE, 42, &m, sizeof m); /* same seq, other type: a new command */
    world_run_ms(2);
    host_collect();
    CHECK(host_count(PB_PKT_ACK) == 3, "acks %d", host_count(PB_PKT_ACK));
    CHECK(robot_state.locomotion.queue_length == 2, "queue %u", robot_state.locomotion.queue_length);
    /* 16 other commands later the seq is forgotten and executes again. */
    for (int i = 0; i < 16; i++) {
        pb_set_sync_t s = {PB_SYNC_MODE_FULL, 100};
        host_send(PB_PKT_SET_SYNC, (uint8_t)(100 + i), &s, sizeof s);
    }
    m.id = 1;
    host_send(PB_PKT_MOVE_STRAIGHT, 42, &m, sizeof m);
    world_run_ms(2);
    host_collect();
    CHECK(robot_state.locomotion.queue_length == 3, "queue %u", robot_state.locomotion.queue_length);
}

static void bad_packets_are_counted_and_answered(void)
{
    world_reset(1);
    uint8_t payload[16] = {0};
    host_send(0x7E, 3, payload, 2); /* unknown type */
    host_send(PB_PKT_HELLO, 4, payload, 0); /* robot-to-host type from the host */
    host_send(PB_PKT_MOVE_STRAIGHT, 5, payload, 4); /* length disagrees with the type */
    host_send(PB_PKT_MOVE_STRAIGHT, 6, payload, 10); /* id 0 */
    world_run_ms(2);
    host_collect();
    CHECK(robot_state.errors.rejected == 4, "rejected %u", robot_state.errors.rejected);
    const pb_error_t *e;
    CHECK((e = error_packet(0)) && e->code == PB_ERROR_CODE_UNKNOWN_TYPE && e->seq == 3 && e->packet_type == 0x7E,
          "unknown");
    CHECK((e = error_packet(1)) && e->code == PB_ERROR_CODE_UNKNOWN_TYPE && e->seq == 4, "direction");
    CHECK((e = error_packet(2)) && e->code == PB_ERROR_CODE_BAD_LENGTH && e->seq == 5 && e->detail == 4, "length");
    CHECK((e = error_packet(3)) && e->code == PB_ERROR_CODE_BAD_ARGUMENT && e->seq == 6, "argument");
    /* A bad CRC: counted, no answer. */
    uint8_t frame[32], slip[70];
    uint16_t n = pb_frame_encode(frame, PB_PKT_HEARTBEAT, 0, NULL, 0);
    frame[n - 1] ^= 1;
    host_clear();
    host_send_raw(slip, slip_encode(slip, frame, n));
    /* Too short, and a broken escape. */
    const uint8_t junk[] = {0xC0, 1, 2, 0xC0, 1, 0xDB, 7, 0xC0};
    host_send_raw(junk, sizeof junk);
    world_run_ms(2);
    host_collect();
    CHECK(robot_state.errors.crc == 1 && robot_state.errors.framing == 2, "crc %u framing %u",
          robot_state.errors.crc, robot_state.errors.framing);
    CHECK(host_count(PB_PKT_ERROR) == 0, "no answers to unreadable frames");
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
    pb_hello_request_t r = {1};
    host_clear();
    host_send(PB_PKT_HELLO_REQUEST, 0, &r, sizeof r);
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
    RUN(bad_packets_are_counted_and_answered);
    RUN(settings_are_written_read_saved_and_reset_over_the_link);
    RUN(garbage_on_the_link_never_hurts);
}
