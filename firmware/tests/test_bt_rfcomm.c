#include <string.h>

#include "bluetooth/rfcomm.h"
#include "bt_wire.h"
#include "core/data.h"
#include "harness.h"

static const uint8_t phone[6] = {0x01, 0x00, 0x00, 0x00, 0x00, 0xB0};

static uint16_t cid;

static void up(uint8_t credits)
{
    wire_bring_up(27, 64);
    wire_connect(phone, 1);
    cid = wire_open_rfcomm(1, credits, 200);
}

/* The n-th RFCOMM frame the robot sent, copied; \return its length or -1. */
static int frame(int n, uint8_t *out)
{
    uint16_t len;
    const uint8_t *q = wire_find_rfcomm(1, n, &len);
    if (!q)
        return -1;
    memcpy(out, q, len);
    return len;
}

/* The n-th multiplexer message (UIH on DLCI 0) of `type` (with EA and C/R), copied from its type byte. */
static int mcc(uint8_t type, int n, uint8_t *out)
{
    uint8_t f[300];
    int len;
    for (int k = 0; (len = frame(k, f)) >= 0; k++)
        if (f[0] >> 2 == 0 && (f[1] & 0xEF) == 0xEF && f[3] == type && n-- == 0) {
            memcpy(out, f + 3, (size_t)(len - 4));
            return len - 4;
        }
    return -1;
}

static void the_multiplexer_and_data_channel_open_with_credits(void)
{
    up(3);
    uint8_t f[300], m[64];
    CHECK(frame(0, f) == 4 && f[0] == 0x03 && f[1] == 0x73 && f[3] == wire_fcs(f, 3), "UA on DLCI 0");
    CHECK(mcc(0x81, 0, m) == 10 && m[2] == 2 && m[3] == 0xE0 && (m[6] | m[7] << 8) == 121 && m[9] == 7,
          "PN response: CL %02x N1 %u credits %u", m[3], m[6] | m[7] << 8, m[9]);
    CHECK(frame(2, f) == 4 && f[0] == 0x0B && f[1] == 0x73, "UA on DLCI 2");
    CHECK(mcc(0xE3, 0, m) == 4 && m[2] == 0x0B && m[3] == 0x8D, "our modem status");
    CHECK(wire_up.stream_opened[0] == 1, "stream not opened");
    uint8_t msc[4] = {0xE3, 0x05, 0x0B, 0x8D};
    wire_rfcomm(1, cid, 0, 0xEF, msc, 4, 0);
    wire_run_ms(1);
    CHECK(mcc(0xE1, 0, m) == 4 && m[2] == 0x0B, "the peer's modem status not answered");
}

static void data_in_is_handed_up_and_credits_come_back(void)
{
    up(3);
    uint8_t d[100];
    for (int i = 0; i < 100; i++)
        d[i] = (uint8_t)i;
    for (int k = 0; k < 5; k++) {
        wire_rfcomm(1, cid, 2, 0xEF, d + 20 * k, 20, 0);
        wire_run_ms(1);
    }
    CHECK(wire_up.stream_rx_len[0] == 100 && memcmp(wire_up.stream_rx[0], d, 100) == 0, "%d bytes up",
          wire_up.stream_rx_len[0]);
    uint8_t f[300];
    int given = 0;
    for (int k = 0, len; (len = frame(k, f)) >= 0; k++)
        if (f[0] == 0x09 && f[1] == 0xFF)
            given += f[3];
    CHECK(given >= 4, "credits given back: %d", given);
}

static void staged_bytes_go_out_within_credits(void)
{
    up(2);
    wire_clear();
    uint8_t d[60];
    memset(d, 0x5A, sizeof d);
    CHECK(rfcomm_tx_room(0) == RFCOMM_TX_SIZE - 1u, "room %u", rfcomm_tx_room(0));
    wire_uart_bytes_per_ms = 12;
    rfcomm_write(0, d, 60);
    wire_run_ms(10);
    rfcomm_write(0, d, 60);
    wire_run_ms(10);
    rfcomm_write(0, d, 60); /* no credit left for this one */
    wire_run_ms(10);
    uint8_t f[300];
    int frames = 0, bytes = 0;
    for (int k = 0, len; (len = frame(k, f)) >= 0; k++)
        if (f[0] == 0x09 && (f[2] >> 1) > 0) {
            frames++;
            bytes += f[2] >> 1;
        }
    CHECK(frames == 2 && bytes == 120, "%d frames, %d bytes without credits", frames, bytes);
    wire_rfcomm(1, cid, 2, 0xEF, NULL, 0, 5); /* credits */
    wire_run_ms(10);
    frames = bytes = 0;
    for (int k = 0, len; (len = frame(k, f)) >= 0; k++)
        if (f[0] == 0x09 && (f[2] >> 1) > 0) {
            frames++;
            bytes += f[2] >> 1;
        }
    CHECK(frames == 3 && bytes == 180, "%d frames, %d bytes with credits", frames, bytes);
}

static void bytes_staged_while_the_uart_is_busy_grow_into_one_frame(void)
{
    up(7);
    wire_clear();
    wire_uart_bytes_per_ms = 12;
    uint8_t d[12];
    memset(d, 1, sizeof d);
    rfcomm_write(0, d, 12); /* goes at once: the UART is idle */
    wire_run_ms(1);
    uint8_t big[60] = {0};
    rfcomm_write(0, big, 60); /* a frame the UART needs a while for */
    wire_run_ms(1);
    for (int k = 0; k < 5; k++) { /* while it sends: 12 bytes per ms */
        rfcomm_write(0, d, 12);
        wire_run_ms(1);
    }
    wire_run_ms(20);
    uint8_t f[300];
    int sizes[8], n = 0;
    for (int k = 0, len; (len = frame(k, f)) >= 0 && n < 8; k++)
        if (f[0] == 0x09 && (f[2] >> 1) > 0)
            sizes[n++] = f[2] >> 1;
    CHECK(n == 3 && sizes[0] == 12 && sizes[1] == 60 && sizes[2] >= 48, "%d frames: %d %d %d", n, sizes[0],
          n > 1 ? sizes[1] : 0, n > 2 ? sizes[2] : 0);
}

/* Data bytes of the n-th UIH data frame the robot sent on `handle` (DLCI 2), -1 when there is none. */
static int data_frame(uint16_t handle, int n)
{
    uint16_t len;
    for (int k = 0;; k++) {
        const uint8_t *f = wire_find_rfcomm(handle, k, &len);
        if (!f)
            return -1;
        if (f[0] == 0x09 && (f[1] & 0xEF) == 0xEF && (f[2] >> 1) > 0 && n-- == 0)
            return f[2] >> 1;
    }
}

/* Two hosts send at once and the stack echoes on both links (as bt_e2e.py's peers): each gets every byte back, the
 * links taking turns frame by frame. */
static void two_links_are_served_in_turn(void)
{
    static const uint8_t computer[6] = {0x02, 0x00, 0x00, 0x00, 0x00, 0xB0};
    wire_bring_up(27, 64);
    wire_connect(phone, 1);
    uint16_t c1 = wire_open_rfcomm(1, 7, 121);
    wire_connect(computer, 2);
    uint16_t c2 = wire_open_rfcomm(2, 7, 121);
    wire_clear();
    wire_uart_bytes_per_ms = 12; /* the wire's pace, as --live sends */
    wire_echo = true;
    uint8_t d[20];
    for (int round = 0; round < 6; round++) {
        memset(d, round + 1, sizeof d);
        wire_rfcomm(1, c1, 2, 0xEF, d, sizeof d, 0);
        wire_rfcomm(2, c2, 2, 0xEF, d, sizeof d, 0);
        wire_run_ms(2);
    }
    wire_run_ms(100);
    wire_echo = false;
    int echoed[2] = {0, 0};
    for (int h = 0; h < 2; h++)
        for (int k = 0, n; (n = data_frame((uint16_t)(h + 1), k)) > 0; k++)
            echoed[h] += n;
    CHECK(echoed[0] == 120 && echoed[1] == 120, "echoed %d bytes to the phone, %d to the computer", echoed[0],
          echoed[1]);
}

static void a_bad_fcs_is_dropped(void)
{
    up(7);
    uint8_t f[8] = {0x0B, 0xEF, 0x05, 'a', 'b', 0x00};
    wire_l2cap(1, cid, f, 6);
    wire_run_ms(1);
    CHECK(wire_up.stream_rx_len[0] == 0 && robot_state.errors.bt_dropped == 1, "taken: %d bytes, dropped %u",
          wire_up.stream_rx_len[0], robot_state.errors.bt_dropped);
}

static void port_line_test_and_unknown_messages_are_answered(void)
{
    up(7);
    wire_clear();
    uint8_t rpn[3] = {0x93, 0x03, 0x0B};
    wire_rfcomm(1, cid, 0, 0xEF, rpn, 3, 0);
    uint8_t test[5] = {0x23, 0x07, 'p', 'n', 'g'};
    wire_rfcomm(1, cid, 0, 0xEF, test, 5, 0);
    uint8_t odd[2] = {0xFF, 0x01};
    wire_rfcomm(1, cid, 0, 0xEF, odd, 2, 0);
    wire_run_ms(2);
    uint8_t m[64];
    CHECK(mcc(0x91, 0, m) == 10 && m[2] == 0x0B, "remote port negotiation");
    CHECK(mcc(0x21, 0, m) == 5 && memcmp(m + 2, "png", 3) == 0, "test not echoed");
    CHECK(mcc(0x11, 0, m) == 3 && m[2] == 0xFF, "unknown type not answered NSC");
}

static void disconnecting_closes_cleanly_and_a_lost_link_not(void)
{
    up(7);
    wire_rfcomm(1, cid, 2, 0x53, NULL, 0, 0); /* DISC, P */
    wire_run_ms(1);
    CHECK(wire_up.stream_closed[0] == 1 && wire_up.stream_lost[0] == 0, "closed %d lost %d",
          wire_up.stream_closed[0], wire_up.stream_lost[0]);
    CHECK(rfcomm_tx_room(0) == 0, "room on a closed channel");
    wire_rfcomm(1, cid, 2, 0x3F, NULL, 0, 0); /* SABM again */
    wire_run_ms(1);
    CHECK(wire_up.stream_opened[0] == 2, "not opened again");
    uint8_t gone[4] = {0, 1, 0, 0x08};
    wire_event(0x05, gone, 4);
    wire_run_ms(1);
    CHECK(wire_up.stream_closed[0] == 2 && wire_up.stream_lost[0] == 1, "lost: closed %d lost %d",
          wire_up.stream_closed[0], wire_up.stream_lost[0]);
}

static void another_server_channel_is_refused(void)
{
    up(7);
    wire_clear();
    wire_rfcomm(1, cid, 4, 0x3F, NULL, 0, 0); /* SABM on channel 2 */
    wire_run_ms(1);
    uint8_t f[16];
    CHECK(frame(0, f) == 4 && f[0] == 0x13 && f[1] == 0x1F, "no DM for channel 2");
}

void suite_bt_rfcomm(void)
{
    RUN(the_multiplexer_and_data_channel_open_with_credits);
    RUN(data_in_is_handed_up_and_credits_come_back);
    RUN(staged_bytes_go_out_within_credits);
    RUN(bytes_staged_while_the_uart_is_busy_grow_into_one_frame);
    RUN(two_links_are_served_in_turn);
    RUN(a_bad_fcs_is_dropped);
    RUN(port_line_test_and_unknown_messages_are_answered);
    RUN(disconnecting_closes_cleanly_and_a_lost_link_not);
    RUN(another_server_channel_is_refused);
}
