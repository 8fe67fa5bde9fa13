#include <string.h>

#include "bluetooth/h4.h"
#include "bluetooth/hci.h"
#include "bluetooth/l2cap.h"
#include "bt_wire.h"
#include "core/data.h"
#include "harness.h"

static const uint8_t phone[6] = {0x01, 0x00, 0x00, 0x00, 0x00, 0xB0};

/* The signalling answer with `code` (the n-th one), copied. */
static int signal(uint8_t code, int n, uint8_t *out)
{
    const uint8_t *q;
    uint16_t len;
    for (int k = 0; (q = wire_find_l2cap(1, 1, k, &len)); k++)
        if (q[0] == code && n-- == 0) {
            memcpy(out, q, len);
            return len;
        }
    return -1;
}

static void up(uint16_t acl_mtu)
{
    wire_bring_up(acl_mtu, 64);
    wire_connect(phone, 1);
    wire_clear();
}

static void a_channel_is_connected_and_configured_both_ways(void)
{
    up(27);
    uint8_t req[8] = {0x02, 5, 4, 0, 0x01, 0x00, 0x40, 0x00}; /* SDP from the peer's 0x0040 */
    wire_l2cap(1, 1, req, sizeof req);
    wire_run_ms(1);
    uint8_t a[64];
    CHECK(signal(0x03, 0, a) == 12 && a[1] == 5, "no connection response");
    uint16_t dcid = (uint16_t)(a[4] | a[5] << 8);
    CHECK(dcid >= 0x40 && a[6] == 0x40 && a[8] == 0 && a[9] == 0, "response: dcid %04x result %u", dcid, a[8]);
    CHECK(signal(0x04, 0, a) == 12 && a[4] == 0x40 && a[8] == 0x01 && (a[10] | a[11] << 8) == BT_L2CAP_MTU,
          "our configuration request");
    uint8_t our_id = a[1];
    CHECK(l2cap_peer_mtu(0, L2CAP_SDP) == 0, "open before configuration");
    uint8_t cfg[12] = {0x04, 6, 8, 0, (uint8_t)dcid, 0, 0, 0, 0x01, 2, 0x30, 0x00}; /* MTU 48 */
    wire_l2cap(1, 1, cfg, sizeof cfg);
    uint8_t rsp[10] = {0x05, our_id, 6, 0, (uint8_t)dcid, 0, 0, 0, 0, 0};
    wire_l2cap(1, 1, rsp, sizeof rsp);
    wire_run_ms(1);
    CHECK(signal(0x05, 0, a) >= 10 && a[4] == 0x40 && a[8] == 0 && a[9] == 0, "configuration response");
    CHECK(l2cap_peer_mtu(0, L2CAP_SDP) == 48, "peer MTU %u", l2cap_peer_mtu(0, L2CAP_SDP));
}

static void an_unknown_psm_is_refused(void)
{
    up(27);
    uint8_t req[8] = {0x02, 5, 4, 0, 0x05, 0x10, 0x40, 0x00};
    wire_l2cap(1, 1, req, sizeof req);
    wire_run_ms(1);
    uint8_t a[64];
    CHECK(signal(0x03, 0, a) == 12 && a[4] == 0 && a[8] == 0x02, "result %u", a[8]);
}

static void only_basic_mode_and_known_options_are_taken(void)
{
    up(27);
    uint16_t cid = wire_open_l2cap(1, BT_PSM_FRAMED, 0x41, 200);
    wire_clear();
    uint8_t ertm[4 + 4 + 11] = {0x04, 7, 15, 0, (uint8_t)cid, 0, 0, 0, 0x04, 9, 0x03};
    wire_l2cap(1, 1, ertm, sizeof ertm);
    uint8_t odd[4 + 4 + 3] = {0x04, 8, 7, 0, (uint8_t)cid, 0, 0, 0, 0x7E, 1, 0};
    wire_l2cap(1, 1, odd, sizeof odd);
    uint8_t hint[4 + 4 + 3] = {0x04, 9, 7, 0, (uint8_t)cid, 0, 0, 0, 0xFE, 1, 0};
    wire_l2cap(1, 1, hint, sizeof hint);
    wire_run_ms(3);
    uint8_t a[64];
    CHECK(signal(0x05, 0, a) == 4 + 6 + 11 && a[8] == 0x01 && a[10] == 0x04 && a[12] == 0, "ERTM not refused");
    CHECK(signal(0x05, 1, a) == 4 + 6 + 1 && a[8] == 0x03 && a[10] == 0x7E, "unknown option not refused");
    CHECK(signal(0x05, 2, a) == 4 + 6 && a[8] == 0, "a hint refused");
}

static void a_pdu_in_fragments_is_reassembled(void)
{
    up(27);
    uint16_t cid = wire_open_l2cap(1, BT_PSM_FRAMED, 0x41, 200);
    CHECK(wire_up.framed_opened[0] == 1, "framed channel not open");
    uint8_t pdu[4 + 125];
    pdu[0] = 125;
    pdu[1] = 0;
    pdu[2] = (uint8_t)cid;
    pdu[3] = 0;
    for (int i = 0; i < 125; i++)
        pdu[4 + i] = (uint8_t)(i * 3);
    wire_acl(1, 2, pdu, 30);
    wire_run_ms(1);
    wire_acl(1, 1, pdu + 30, 50);
    wire_acl(1, 1, pdu + 80, 49);
    wire_run_ms(3);
    CHECK(wire_up.framed_sdus[0] == 1 && wire_up.framed_rx_len[0] == 125 &&
              memcmp(wire_up.framed_rx[0], pdu + 4, 125) == 0,
          "SDUs %d, %d bytes", wire_up.framed_sdus[0], wire_up.framed_rx_len[0]);
    CHECK(robot_state.errors.bt_dropped == 0, "dropped %u", robot_state.errors.bt_dropped);
}

static void a_pdu_longer_than_the_mtu_is_dropped_whole(void)
{
    up(27);
    uint16_t cid = wire_open_l2cap(1, BT_PSM_FRAMED, 0x41, 200);
    uint8_t big[4 + 40] = {200, 0, (uint8_t)cid, 0};
    wire_acl(1, 2, big, sizeof big);
    uint8_t rest[40] = {0};
    for (int i = 0; i < 4; i++)
        wire_acl(1, 1, rest, 40);
    uint8_t ok[4 + 5] = {5, 0, (uint8_t)cid, 0, 1, 2, 3, 4, 5};
    wire_acl(1, 2, ok, sizeof ok);
    wire_run_ms(6);
    CHECK(robot_state.errors.bt_dropped == 1, "dropped %u", robot_state.errors.bt_dropped);
    CHECK(wire_up.framed_sdus[0] == 1 && wire_up.framed_rx_len[0] == 5, "the next SDU lost");
}

static void fragments_out_of_order_are_dropped(void)
{
    up(27);
    uint16_t cid = wire_open_l2cap(1, BT_PSM_FRAMED, 0x41, 200);
    uint8_t orphan[10] = {0};
    wire_acl(1, 1, orphan, sizeof orphan); /* a continuation without a start */
    uint8_t half[4 + 6] = {20, 0, (uint8_t)cid, 0};
    wire_acl(1, 2, half, sizeof half); /* a start, then another start */
    uint8_t whole[4 + 3] = {3, 0, (uint8_t)cid, 0, 7, 8, 9};
    wire_acl(1, 2, whole, sizeof whole);
    wire_run_ms(1);
    CHECK(robot_state.errors.bt_dropped == 1, "dropped %u", robot_state.errors.bt_dropped);
    CHECK(wire_up.framed_sdus[0] == 1 && wire_up.framed_rx[0][0] == 7, "the whole SDU lost");
}

static void an_sdu_out_is_fragmented_to_the_controller_buffers(void)
{
    up(27);
    wire_open_l2cap(1, BT_PSM_FRAMED, 0x41, 200);
    wire_clear();
    uint8_t sdu[125];
    for (int i = 0; i < 125; i++)
        sdu[i] = (uint8_t)i;
    CHECK(l2cap_can_send(0, L2CAP_FRAMED, 125, true), "no room");
    l2cap_begin(0, L2CAP_FRAMED, 125);
    hci_acl_put(sdu, 125);
    hci_acl_end();
    wire_collect();
    int frags = 0, starts = 0;
    for (int i = 0; i < wire_out_count; i++)
        if (wire_out[i].type == H4_ACL) {
            frags++;
            starts += ((wire_out[i].handle >> 12) & 3) == 2;
            CHECK(wire_out[i].len <= 27, "fragment of %u bytes", wire_out[i].len);
        }
    CHECK(frags == 5 && starts == 1, "%d fragments, %d starts", frags, starts);
    uint16_t n;
    const uint8_t *q = wire_find_l2cap(1, 0x41, 0, &n);
    CHECK(q && n == 125 && memcmp(q, sdu, 125) == 0, "SDU differs");
}

static void echo_information_and_unknown_commands_are_answered(void)
{
    up(27);
    uint8_t echo[4 + 3] = {0x08, 3, 3, 0, 'a', 'b', 'c'};
    wire_l2cap(1, 1, echo, sizeof echo);
    uint8_t info[6] = {0x0A, 4, 2, 0, 0x02, 0};
    wire_l2cap(1, 1, info, sizeof info);
    uint8_t fixed[6] = {0x0A, 5, 2, 0, 0x03, 0};
    wire_l2cap(1, 1, fixed, sizeof fixed);
    uint8_t odd[4] = {0x2A, 6, 0, 0};
    wire_l2cap(1, 1, odd, sizeof odd);
    wire_run_ms(2);
    uint8_t a[64];
    CHECK(signal(0x09, 0, a) == 4 && a[1] == 3, "echo");
    CHECK(signal(0x0B, 0, a) == 12 && a[4] == 2 && a[6] == 0 && a[8] == 0, "extended features");
    CHECK(signal(0x0B, 1, a) == 8 && a[4] == 3 && a[6] == 1, "fixed channels not unsupported");
    CHECK(signal(0x01, 0, a) == 6 && a[1] == 6 && a[4] == 0, "unknown command not rejected");
}

static void a_disconnection_request_closes_cleanly_and_a_lost_link_not(void)
{
    up(27);
    uint16_t cid = wire_open_l2cap(1, BT_PSM_FRAMED, 0x41, 200);
    uint8_t disc[8] = {0x06, 9, 4, 0, (uint8_t)cid, 0, 0x41, 0};
    wire_l2cap(1, 1, disc, sizeof disc);
    wire_run_ms(1);
    uint8_t a[64];
    CHECK(signal(0x07, 0, a) == 8 && a[4] == cid && a[6] == 0x41, "no disconnection response");
    CHECK(wire_up.framed_closed[0] == 1 && wire_up.framed_lost[0] == 0, "closed %d lost %d",
          wire_up.framed_closed[0], wire_up.framed_lost[0]);
    wire_open_l2cap(1, BT_PSM_FRAMED, 0x42, 200);
    uint8_t gone[4] = {0, 1, 0, 0x08};
    wire_event(0x05, gone, 4);
    wire_run_ms(1);
    CHECK(wire_up.framed_closed[0] == 2 && wire_up.framed_lost[0] == 1, "lost link: closed %d lost %d",
          wire_up.framed_closed[0], wire_up.framed_lost[0]);
}

static void one_data_channel_per_link(void)
{
    up(27);
    wire_open_rfcomm(1, 7, 121);
    CHECK(wire_up.stream_opened[0] == 1, "RFCOMM not open");
    CHECK(wire_open_l2cap(1, BT_PSM_FRAMED, 0x41, 200) == 0, "framed channel taken beside RFCOMM");
    up(27);
    wire_open_l2cap(1, BT_PSM_FRAMED, 0x41, 200);
    wire_open_rfcomm(1, 7, 121);
    CHECK(wire_up.stream_opened[0] == 0, "RFCOMM taken beside the framed channel");
}

static void an_answer_without_room_waits_and_is_not_lost(void)
{
    up(27);
    /* Fill the transmit ring so that no answer fits. */
    uint16_t fill = 0;
    h4_tx_begin();
    while (h4_tx_room() > 4 && fill < 250) {
        h4_tx_byte(0);
        fill++;
    }
    h4_tx_end();
    uint8_t echo[4] = {0x08, 3, 0, 0};
    wire_l2cap(1, 1, echo, sizeof echo);
    wire_run_ms(2);
    uint8_t a[64];
    int before = signal(0x09, 0, a);
    CHECK(before < 0, "answered without room");
    wire_clear(); /* the UART sends */
    wire_run_ms(1);
    CHECK(signal(0x09, 0, a) == 4, "the waiting answer was lost");
    CHECK(robot_state.errors.bt_dropped == 0, "dropped %u", robot_state.errors.bt_dropped);
}

void suite_bt_l2cap(void)
{
    RUN(a_channel_is_connected_and_configured_both_ways);
    RUN(an_unknown_psm_is_refused);
    RUN(only_basic_mode_and_known_options_are_taken);
    RUN(a_pdu_in_fragments_is_reassembled);
    RUN(a_pdu_longer_than_the_mtu_is_dropped_whole);
    RUN(fragments_out_of_order_are_dropped);
    RUN(an_sdu_out_is_fragmented_to_the_controller_buffers);
    RUN(echo_information_and_unknown_commands_are_answered);
    RUN(a_disconnection_request_closes_cleanly_and_a_lost_link_not);
    RUN(one_data_channel_per_link);
    RUN(an_answer_without_room_waits_and_is_not_lost);
}
