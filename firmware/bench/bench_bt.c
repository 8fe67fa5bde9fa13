/**
 * \file bench_bt.c
 * The cycle bench's Bluetooth controller (HCI build): it answers the firmware's HCI commands, returns the buffers of
 * the ACL packets the firmware sent (Number_Of_Completed_Packets), and plays a host on it: connection, an RFCOMM
 * data channel with credits given back as a host's stack would, and host packets in UIH frames. Its bytes reach the
 * firmware at the wire's pace (12 per ms, uart_rx_isr()) and it takes the firmware's bytes at the same pace
 * (uart_tx_isr()), outside the timed tasks, so the bench counts the stack's work and none of the controller's.
 */
#include <string.h>

#include "bench.h"
#include "bluetooth/hci.h"
#include "drivers/uart.h"
#include "hal/hal.h"

#define WIRE_BYTES_PER_MS 12u
#define HANDLE 1u
#define PEER_CID 0x0050u

/* Controller to robot: a ring of bytes waiting for the wire. */
static uint8_t out[256];
static uint8_t out_head, out_tail;

/* Robot to controller: the packet being read. */
static uint8_t in_hdr[5];
static uint8_t in_got;
static uint16_t in_need;
static uint8_t in_rfcomm[4]; /* the first payload bytes of an ACL start: L2CAP channel, RFCOMM address */
static uint8_t acl_done;     /* ACL packets received since the last Number_Of_Completed_Packets */
static uint8_t uih_frames;   /* RFCOMM data frames received since credits were last given back */
static uint16_t robot_cid;   /* the robot's RFCOMM channel */

static void put(const uint8_t *p, uint8_t n)
{
    while (n--)
        out[out_head++] = *p++;
}

static void event(uint8_t code, const uint8_t *p, uint8_t n)
{
    uint8_t h[3] = {0x04, code, n};
    put(h, 3);
    put(p, n);
}

static void l2cap(uint16_t cid, const uint8_t *p, uint8_t n)
{
    uint8_t h[9] = {0x02, HANDLE, 0x20, (uint8_t)(n + 4), 0, n, 0, (uint8_t)cid, (uint8_t)(cid >> 8)};
    put(h, 9);
    put(p, n);
}

/* TS 07.10's FCS. */
static uint8_t fcs(const uint8_t *p, uint8_t n)
{
    uint8_t crc = 0xFF;
    while (n--) {
        crc ^= *p++;
        for (uint8_t i = 0; i < 8; i++)
            crc = (uint8_t)(crc & 1 ? (crc >> 1) ^ 0xE0 : crc >> 1);
    }
    return (uint8_t)(0xFF - crc);
}

static void rfcomm(uint8_t dlci, uint8_t ctrl, const uint8_t *info, uint8_t n, uint8_t credits)
{
    uint8_t f[40];
    uint8_t k = 0;
    f[k++] = (uint8_t)(dlci << 2 | 0x03);
    f[k++] = credits ? (uint8_t)(ctrl | 0x10) : ctrl;
    f[k++] = (uint8_t)(n << 1 | 1);
    if (credits)
        f[k++] = credits;
    if (n)
        memcpy(f + k, info, n);
    k = (uint8_t)(k + n);
    f[k] = fcs(f, (ctrl & 0xEF) == 0xEF ? 2 : 3);
    l2cap(robot_cid, f, (uint8_t)(k + 1));
}

/* A command from the robot: answered as a controller with 27-byte ACL buffers, 8 of them, would. */
static void answer(uint16_t op)
{
    uint8_t p[14] = {1, (uint8_t)op, (uint8_t)(op >> 8), 0};
    uint8_t n = 4;
    if (op == 0x1005) { /* Read_Buffer_Size */
        static const uint8_t r[7] = {27, 0, 0, 8, 0, 0, 0};
        memcpy(p + 4, r, 7);
        n = 11;
    } else if (op == 0x1009) { /* Read_BD_ADDR */
        static const uint8_t a[6] = {0x0F, 0x0E, 0x0D, 0x0C, 0x0B, 0x0A};
        memcpy(p + 4, a, 6);
        n = 10;
    } else if ((op >> 10) == 1) { /* link control: Command Status */
        uint8_t s[4] = {0, 1, (uint8_t)op, (uint8_t)(op >> 8)};
        event(0x0F, s, 4);
        return;
    }
    event(0x0E, p, n);
}

static void robot_byte(uint8_t b)
{
    if (in_got == 0 || in_got < (in_hdr[0] == 0x01 ? 4u : 5u)) { /* a command's header is 4 bytes, ACL's 5 */
        in_hdr[in_got++] = b;
        if (in_got < (in_hdr[0] == 0x01 ? 4u : 5u))
            return;
        in_need = in_hdr[0] == 0x01 ? in_hdr[3] : (uint16_t)(in_hdr[3] | in_hdr[4] << 8);
    } else {
        uint16_t at = (uint16_t)(in_got - 5u);
        if (in_hdr[0] == 0x02 && ((in_hdr[2] >> 4) & 3) == 2 && at >= 2 && at < 6)
            in_rfcomm[at - 2] = b; /* channel id, RFCOMM address and control */
        if (in_got < 255)
            in_got++;
        in_need--;
    }
    if (in_need)
        return;
    if (in_hdr[0] == 0x01) {
        answer((uint16_t)(in_hdr[1] | in_hdr[2] << 8));
    } else {
        acl_done++;
        uint16_t cid = (uint16_t)(in_rfcomm[0] | in_rfcomm[1] << 8);
        if (((in_hdr[2] >> 4) & 3) == 2 && cid == PEER_CID && in_rfcomm[2] == 0x09 && (in_rfcomm[3] & 0xEF) == 0xEF)
            uih_frames++;
    }
    in_got = 0;
}

void bench_bt_wire(void)
{
    for (uint8_t i = 0; i < WIRE_BYTES_PER_MS; i++) {
        int16_t b = uart_tx_isr();
        if (b < 0)
            break;
        robot_byte((uint8_t)b);
    }
    if (acl_done) {
        uint8_t p[5] = {1, HANDLE, 0, acl_done, 0};
        event(0x13, p, 5);
        acl_done = 0;
    }
    if (uih_frames >= 4 && robot_cid) { /* credits back, as a host's stack gives them */
        rfcomm(2, 0xEF, NULL, 0, uih_frames);
        uih_frames = 0;
    }
    for (uint8_t i = 0; i < WIRE_BYTES_PER_MS && out_tail != out_head; i++)
        uart_rx_isr(out[out_tail++]);
}

bool bench_bt_idle(void)
{
    return out_tail == out_head;
}

void bench_bt_connect(void)
{
    static const uint8_t addr[6] = {0x01, 0, 0, 0, 0, 0xB0};
    uint8_t req[10] = {0};
    memcpy(req, addr, 6);
    req[9] = 1;
    event(0x04, req, 10);
    bench_bt_run(10);
    uint8_t done[11] = {0, HANDLE, 0};
    memcpy(done + 3, addr, 6);
    done[9] = 1;
    event(0x03, done, 11);
    bench_bt_run(10);
    uint8_t conn[8] = {0x02, 1, 4, 0, 0x03, 0, (uint8_t)PEER_CID, 0};
    l2cap(1, conn, 8);
    bench_bt_run(10);
    robot_cid = 0x0040u + 1u; /* the robot's channel for RFCOMM on its first link */
    uint8_t cfg[12] = {0x04, 2, 8, 0, (uint8_t)robot_cid, 0, 0, 0, 1, 2, 0xF5, 0x03};
    l2cap(1, cfg, 12);
    uint8_t rsp[10] = {0x05, 1, 6, 0, (uint8_t)robot_cid, 0, 0, 0, 0, 0};
    l2cap(1, rsp, 10);
    bench_bt_run(10);
    rfcomm(0, 0x2F, NULL, 0, 0); /* SABM */
    bench_bt_run(10);
    static const uint8_t pn[10] = {0x83, 0x11, 2, 0xF0, 0, 0, 121, 0, 0, 7};
    rfcomm(0, 0xEF, pn, 10, 0);
    bench_bt_run(10);
    rfcomm(2, 0x2F, NULL, 0, 0);
    bench_bt_run(10);
    static const uint8_t msc[4] = {0xE3, 0x05, 0x0B, 0x8D};
    rfcomm(0, 0xEF, msc, 4, 0);
    bench_bt_run(20);
}

void bench_bt_host_packet(const uint8_t *slip, uint8_t n)
{
    rfcomm(2, 0xEF, slip, n, 0);
}
