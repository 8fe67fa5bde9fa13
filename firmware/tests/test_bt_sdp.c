#include <string.h>

#include "bluetooth/bt_config.h"
#include "bluetooth/h4.h"
#include "bt_trace.h"
#include "bt_wire.h"
#include "core/data.h"
#include "harness.h"

static const uint8_t phone[6] = {0x01, 0x00, 0x00, 0x00, 0x00, 0xB0};

/* ---- the recorded session ---- */

/* The L2CAP PDUs (length-prefixed, concatenated) on `cid` of the H4 packets in `pkts` (length-prefixed). */
static int l2cap_pdus(const uint8_t *pkts, int count, uint16_t cid, uint8_t *out, int max)
{
    static uint8_t pdu[1024];
    int got = 0, len = 0;
    for (int i = 0; i < count; i++) {
        int n = pkts[0] | pkts[1] << 8;
        const uint8_t *p = pkts + 2;
        pkts += 2 + n;
        if (p[0] != H4_ACL)
            continue;
        if (((p[2] >> 4) & 3) != 1)
            got = 0;
        memcpy(pdu + got, p + 5, (size_t)(n - 5));
        got += n - 5;
        if (got < 4 || got < 4 + (pdu[0] | pdu[1] << 8))
            continue;
        int total = 4 + (pdu[0] | pdu[1] << 8);
        got = 0;
        if ((pdu[2] | pdu[3] << 8) != cid || len + 2 + total - 4 > max)
            continue;
        out[len++] = (uint8_t)(total - 4);
        out[len++] = (uint8_t)((total - 4) >> 8);
        memcpy(out + len, pdu + 4, (size_t)(total - 4));
        len += total - 4;
    }
    return len;
}

/* The same of what the robot sent in this run. */
static int l2cap_pdus_now(uint16_t cid, uint8_t *out, int max)
{
    static uint8_t pkts[80000];
    int len = 0;
    wire_collect();
    for (int i = 0; i < wire_out_count; i++) {
        const wire_packet_t *w = &wire_out[i];
        if (w->type != H4_ACL)
            continue;
        int n = 5 + w->len;
        pkts[len] = (uint8_t)n;
        pkts[len + 1] = (uint8_t)(n >> 8);
        pkts[len + 2] = H4_ACL;
        pkts[len + 3] = (uint8_t)w->handle;
        pkts[len + 4] = (uint8_t)(w->handle >> 8);
        pkts[len + 5] = (uint8_t)w->len;
        pkts[len + 6] = (uint8_t)(w->len >> 8);
        memcpy(pkts + len + 7, w->data, w->len);
        len += 2 + n;
    }
    int count = 0;
    for (int i = 0; i < wire_out_count; i++)
        count += wire_out[i].type == H4_ACL;
    return l2cap_pdus(pkts, count, cid, out, max);
}

static void replays_a_recorded_bumble_session_with_the_same_answers(void)
{
    wire_reset();
    wire_echo = true;
    wire_uart_bytes_per_ms = 12; /* as --live sends */
    const uint8_t *p = bt_trace_in;
    for (int i = 0; i < BT_TRACE_IN_COUNT; i++) { /* each packet when the controller sent it */
        uint32_t at = (uint32_t)(p[0] | p[1] << 8);
        int n = p[2] | p[3] << 8;
        while (robot_state.time.time_ms < at)
            wire_run_ms(1);
        wire_feed(p + 4, (uint16_t)n);
        p += 4 + n;
    }
    wire_run_ms(20);
    wire_echo = false;
    static uint8_t want[8192], got[8192];
    /* The peer's channels: signalling; 0x0040 for SDP, then for RFCOMM; 0x0041 for the framed service. Each gets
     * what it got in the recording, byte for byte: the same answers, the same echoes in the same frames. */
    static const uint16_t cids[] = {0x0001, 0x0040, 0x0041};
    for (unsigned k = 0; k < 3; k++) {
        int w = l2cap_pdus(bt_trace_out, BT_TRACE_OUT_COUNT, cids[k], want, sizeof want);
        int g = l2cap_pdus_now(cids[k], got, sizeof got);
        CHECK(w > 100 && w == g && memcmp(want, got, (size_t)w) == 0, "channel %04x: %d recorded bytes, %d now",
              cids[k], w, g);
    }
    CHECK(robot_state.errors.bt_dropped == 0 && robot_state.errors.bt_resets == 0, "dropped %u resets %u",
          robot_state.errors.bt_dropped, robot_state.errors.bt_resets);
}

/* ---- requests of our own ---- */

static uint16_t sdp_cid;

static void sdp_up(void)
{
    wire_bring_up(27, 64);
    wire_connect(phone, 1);
    sdp_cid = wire_open_l2cap(1, 1, 0x0060, 672);
    wire_clear();
}

/* Sends an SDP request, returns the answer's parameters (after pdu id, tid, length) and its pdu id. */
static int ask(uint8_t pdu, const uint8_t *params, int n, uint8_t *answer, uint8_t *answer_pdu)
{
    static uint16_t tid = 0x100;
    uint8_t req[300] = {pdu, (uint8_t)(++tid >> 8), (uint8_t)tid, (uint8_t)(n >> 8), (uint8_t)n};
    memcpy(req + 5, params, (size_t)n);
    wire_clear();
    wire_l2cap(1, sdp_cid, req, (uint16_t)(5 + n));
    wire_run_ms(4);
    uint16_t len;
    const uint8_t *q = wire_find_l2cap(1, 0x0060, 0, &len);
    if (!q || len < 5 || (q[1] << 8 | q[2]) != tid)
        return -1;
    *answer_pdu = q[0];
    memcpy(answer, q + 5, len - 5u);
    return len - 5;
}

static int search(const uint8_t *uuid_de, int n, uint8_t *answer)
{
    uint8_t req[40] = {0x35, (uint8_t)n};
    memcpy(req + 2, uuid_de, (size_t)n);
    req[2 + n] = 0;
    req[3 + n] = 10; /* at most 10 records */
    req[4 + n] = 0;  /* no continuation */
    uint8_t pdu = 0;
    int len = ask(0x02, req, 5 + n, answer, &pdu);
    return pdu == 0x03 ? len : -1;
}

static void services_are_found_by_any_of_their_uuids(void)
{
    sdp_up();
    uint8_t a[64];
    static const uint8_t spp16[] = {0x19, 0x11, 0x01};
    CHECK(search(spp16, 3, a) == 9 && a[3] == 1 && a[5] == 0x01 && a[7] == 0x01, "SPP by its 16-bit UUID");
    static const uint8_t spp32[] = {0x1A, 0x00, 0x00, 0x11, 0x01};
    CHECK(search(spp32, 5, a) == 9 && a[3] == 1 && a[7] == 0x01, "SPP by its 32-bit UUID");
    static const uint8_t spp128[] = {0x1C, 0x00, 0x00, 0x11, 0x01, 0x00, 0x00, 0x10, 0x00,
                                     0x80, 0x00, 0x00, 0x80, 0x5F, 0x9B, 0x34, 0xFB};
    CHECK(search(spp128, 17, a) == 9 && a[3] == 1, "SPP by its 128-bit UUID");
    static const uint8_t framed[] = {0x1C, BT_FRAMED_UUID};
    CHECK(search(framed, 17, a) == 9 && a[3] == 1 && a[7] == 0x02, "the framed service");
    static const uint8_t l2cap[] = {0x19, 0x01, 0x00};
    CHECK(search(l2cap, 3, a) == 13 && a[3] == 2, "both over L2CAP");
    static const uint8_t both[] = {0x19, 0x01, 0x00, 0x19, 0x00, 0x03};
    CHECK(search(both, 6, a) == 9 && a[3] == 1, "L2CAP and RFCOMM: SPP only");
    static const uint8_t other[] = {0x19, 0x11, 0x0A};
    CHECK(search(other, 3, a) == 5 && a[3] == 0, "a service the robot has not");
}

/* Every attribute of every record, in one answer or in parts of `max` bytes. */
static int all_attributes(uint16_t max, uint8_t *out, int *parts)
{
    int len = 0;
    uint16_t offset = 0;
    bool more = true;
    *parts = 0;
    while (more && *parts < 50) {
        uint8_t req[32] = {0x35, 3, 0x19, 0x10, 0x02, (uint8_t)(max >> 8), (uint8_t)max, 0x35, 5, 0x0A, 0, 0, 0xFF,
                           0xFF};
        int n = 14;
        if (offset) {
            req[n++] = 2;
            req[n++] = (uint8_t)(offset >> 8);
            req[n++] = (uint8_t)offset;
        } else {
            req[n++] = 0;
        }
        uint8_t a[300], pdu = 0;
        int k = ask(0x06, req, n, a, &pdu);
        if (pdu != 0x07 || k < 3)
            return -1;
        int count = a[0] << 8 | a[1];
        memcpy(out + len, a + 2, (size_t)count);
        len += count;
        (*parts)++;
        more = a[2 + count] == 2;
        if (more)
            offset = (uint16_t)(a[3 + count] << 8 | a[4 + count]);
    }
    return len;
}

static void a_long_answer_comes_in_parts_that_make_the_whole(void)
{
    sdp_up();
    static uint8_t whole[1024], parts[1024];
    int n1 = 0, n2 = 0;
    int a = all_attributes(1000, whole, &n1);
    int b = all_attributes(16, parts, &n2);
    CHECK(a > 100 && a == b && memcmp(whole, parts, (size_t)a) == 0, "%d bytes in %d parts, %d in %d", a, n1, b, n2);
    CHECK(n2 >= a / 16, "only %d parts of 16 bytes for %d", n2, a);
    CHECK(whole[0] == 0x35 && whole[2] == 0x35, "not a sequence of attribute lists");
}

static void malformed_requests_are_answered_with_errors(void)
{
    sdp_up();
    uint8_t a[64], pdu;
    static const uint8_t bad_handle[] = {0x00, 0x01, 0x00, 0x07, 0x00, 0x40, 0x35, 3, 0x09, 0x00, 0x01, 0};
    CHECK(ask(0x04, bad_handle, sizeof bad_handle, a, &pdu) == 2 && pdu == 0x01 && a[1] == 0x02, "bad handle");
    static const uint8_t good[] = {0x00, 0x01, 0x00, 0x01, 0x00, 0x40, 0x35, 3, 0x09, 0x00, 0x04, 0};
    CHECK(ask(0x04, good, sizeof good, a, &pdu) > 2 && pdu == 0x05, "a sound attribute request refused");
    static const uint8_t not_uuids[] = {0x35, 2, 0x08, 0x01, 0x00, 0x0A, 0};
    CHECK(ask(0x02, not_uuids, sizeof not_uuids, a, &pdu) == 2 && pdu == 0x01 && a[1] == 0x03, "not UUIDs");
    static const uint8_t overrun[] = {0x35, 40, 0x19, 0x11};
    CHECK(ask(0x02, overrun, sizeof overrun, a, &pdu) == 2 && pdu == 0x01 && a[1] == 0x03, "overrun");
    static const uint8_t bad_cont[] = {0x35, 3, 0x19, 0x10, 0x02, 0x00, 0x40, 0x35, 3, 0x09, 0x00, 0x01, 3, 1, 2, 3};
    CHECK(ask(0x06, bad_cont, sizeof bad_cont, a, &pdu) == 2 && pdu == 0x01 && a[1] == 0x05, "bad continuation");
    static const uint8_t far_cont[] = {0x35, 3, 0x19, 0x10, 0x02, 0x00, 0x40, 0x35, 3, 0x09, 0x00, 0x01, 2, 0x7F,
                                       0xFF};
    CHECK(ask(0x06, far_cont, sizeof far_cont, a, &pdu) == 2 && pdu == 0x01 && a[1] == 0x05, "continuation past the end");
    static const uint8_t none[] = {0};
    CHECK(ask(0x09, none, 1, a, &pdu) == 2 && pdu == 0x01, "unknown PDU");
    CHECK(robot_state.errors.bt_resets == 0, "reset");
}

void suite_bt_sdp(void)
{
    RUN(replays_a_recorded_bumble_session_with_the_same_answers);
    RUN(services_are_found_by_any_of_their_uuids);
    RUN(a_long_answer_comes_in_parts_that_make_the_whole);
    RUN(malformed_requests_are_answered_with_errors);
}
