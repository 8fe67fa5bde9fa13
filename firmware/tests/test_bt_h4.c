#include <string.h>

#include "bluetooth/h4.h"
#include "bt_wire.h"
#include "core/data.h"
#include "harness.h"

static h4_result_t read_all(uint8_t budget)
{
    return h4_read(&budget);
}

static void an_event_split_byte_by_byte_is_read_whole(void)
{
    wire_reset();
    h4_init();
    const uint8_t ev[] = {H4_EVENT, 0x0E, 4, 1, 0x03, 0x0C, 0};
    h4_result_t r = H4_NONE;
    for (unsigned i = 0; i < sizeof ev; i++) {
        CHECK(r == H4_NONE, "early result %d at byte %u", r, i);
        wire_feed(ev + i, 1);
        r = read_all(48);
    }
    CHECK(r == H4_EVENT_READY, "result %d", r);
    CHECK(h4_event.code == 0x0E && h4_event.len == 4 && h4_event.params[1] == 0x03, "code %02x len %u",
          h4_event.code, h4_event.len);
}

static void a_bad_packet_type_is_an_error(void)
{
    wire_reset();
    h4_init();
    const uint8_t b[] = {0x03, 0x00};
    wire_feed(b, 2);
    CHECK(read_all(48) == H4_ERROR, "SCO type not refused");
    h4_flush();
    wire_feed((const uint8_t[]){H4_COMMAND}, 1);
    CHECK(read_all(48) == H4_ERROR, "a command from the controller not refused");
}

static void an_acl_longer_than_announced_is_an_error(void)
{
    wire_reset();
    h4_init();
    const uint8_t ok[] = {H4_ACL, 0x01, 0x20, (uint8_t)BT_ACL_RX_MAX, 0};
    wire_feed(ok, sizeof ok);
    CHECK(read_all(48) == H4_ACL_HEADER && h4_acl.len == BT_ACL_RX_MAX, "the longest ACL refused");
    h4_init();
    h4_flush();
    const uint8_t bad[] = {H4_ACL, 0x01, 0x20, (uint8_t)(BT_ACL_RX_MAX + 1), 0};
    wire_feed(bad, sizeof bad);
    CHECK(read_all(48) == H4_ERROR, "an ACL of %u bytes taken", BT_ACL_RX_MAX + 1);
}

static void acl_payload_goes_where_it_is_told_or_is_skipped(void)
{
    wire_reset();
    h4_init();
    const uint8_t pkt[] = {H4_ACL, 0x05, 0x20, 3, 0, 0xAA, 0xBB, 0xCC, H4_ACL, 0x05, 0x10, 2, 0, 0x11, 0x22};
    wire_feed(pkt, sizeof pkt);
    uint8_t dst[8] = {0};
    CHECK(read_all(48) == H4_ACL_HEADER && h4_acl.handle == 5 && h4_acl.pb == 2 && h4_acl.len == 3, "first header");
    h4_acl_into(dst);
    CHECK(read_all(48) == H4_ACL_READY && dst[0] == 0xAA && dst[2] == 0xCC, "payload %02x %02x", dst[0], dst[2]);
    CHECK(read_all(48) == H4_ACL_HEADER && h4_acl.pb == 1, "continuation header");
    h4_acl_into(NULL);
    CHECK(read_all(48) == H4_ACL_READY && dst[3] == 0, "skipped payload written");
    CHECK(read_all(48) == H4_NONE, "more than was sent");
}

static void a_long_event_is_kept_in_part_and_the_next_packet_read(void)
{
    wire_reset();
    h4_init();
    uint8_t ev[3 + 200];
    ev[0] = H4_EVENT;
    ev[1] = 0x2F; /* Extended_Inquiry_Result: longer than the stack keeps */
    ev[2] = 200;
    for (int i = 0; i < 200; i++)
        ev[3 + i] = (uint8_t)i;
    wire_feed(ev, sizeof ev);
    const uint8_t next[] = {H4_EVENT, 0x13, 1, 0};
    wire_feed(next, sizeof next);
    h4_result_t r;
    int guard = 0;
    while ((r = read_all(48)) == H4_NONE && guard++ < 10) {
    }
    CHECK(r == H4_EVENT_READY && h4_event.code == 0x2F && h4_event.truncated && h4_event.len == H4_EVENT_MAX &&
              h4_event.params[H4_EVENT_MAX - 1] == H4_EVENT_MAX - 1,
          "long event: result %d truncated %u len %u", r, h4_event.truncated, h4_event.len);
    CHECK(read_all(48) == H4_EVENT_READY && h4_event.code == 0x13 && !h4_event.truncated, "next event %02x",
          h4_event.code);
}

static void reading_stops_at_its_budget(void)
{
    wire_reset();
    h4_init();
    uint8_t acl[5 + 100] = {H4_ACL, 0x01, 0x20, 100, 0};
    wire_feed(acl, sizeof acl);
    uint8_t budget = 20, dst[100];
    CHECK(h4_read(&budget) == H4_ACL_HEADER && budget == 15, "header: budget left %u", budget);
    h4_acl_into(dst);
    CHECK(h4_read(&budget) == H4_NONE && budget == 0, "payload: budget left %u", budget);
    budget = 200;
    CHECK(h4_read(&budget) == H4_ACL_READY && budget == 200 - 85, "rest: budget left %u", budget);
}

static void a_packet_that_stops_arriving_is_stalled(void)
{
    wire_reset();
    h4_init();
    const uint8_t part[] = {H4_EVENT, 0x0E, 4, 1};
    wire_feed(part, sizeof part);
    read_all(48);
    CHECK(!h4_stalled(robot_state.time.time_ms + H4_PACKET_TIMEOUT_MS), "stalled too early");
    CHECK(h4_stalled(robot_state.time.time_ms + H4_PACKET_TIMEOUT_MS + 1), "not stalled");
    h4_flush();
    CHECK(!h4_stalled(robot_state.time.time_ms + 1000), "stalled between packets");
}

void suite_bt_h4(void)
{
    RUN(an_event_split_byte_by_byte_is_read_whole);
    RUN(a_bad_packet_type_is_an_error);
    RUN(an_acl_longer_than_announced_is_an_error);
    RUN(acl_payload_goes_where_it_is_told_or_is_skipped);
    RUN(a_long_event_is_kept_in_part_and_the_next_packet_read);
    RUN(reading_stops_at_its_budget);
    RUN(a_packet_that_stops_arriving_is_stalled);
}
