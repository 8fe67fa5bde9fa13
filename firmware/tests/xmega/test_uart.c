/**
 * \file test_uart.c
 * The host link's USART (USARTC0) on the model as a byte source and sink: packets both ways at 115200 Bd, and the
 * receiver's overruns and frame errors counted and survived.
 */
#include <avr/io.h>

#include "core/data.h"
#include "protocol/pb_frame.h"
#include "protocol/slip.h"
#include "robot.h"
#include "xm_tests.h"

#define BAUD 115200u

/* SLIP-encodes a packet into `out`. \return its length */
static uint16_t packet(uint8_t *out, uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    uint8_t frame[PB_MAX_FRAME];
    uint16_t n = pb_frame_encode(frame, type, seq, payload, len);
    return slip_encode(out, frame, n);
}

/* Sends an acked command with `seq`: \return whether its ack came back within 20 ms */
static bool command_acked(uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    uint8_t bytes[2 * PB_MAX_FRAME + 2];
    uint16_t n = packet(bytes, type, seq, payload, len);
    robot_frames_clear();
    robot_run_until(xm_usart_send(XM_USARTC0, bytes, n, BAUD, xm_now()) + XM_MS(20));
    for (uint32_t k = 0; robot_frame(PB_PKT_ACK, k); k++)
        if (robot_frame(PB_PKT_ACK, k)->payload[0] == type)
            return true;
    return false;
}

/* The host takes the drive (set_role), so that its commands are the driver's. */
static bool drives(void)
{
    pb_set_role_t role = {PB_HOST_ROLE_DRIVE, "xmega test"};
    return command_acked(PB_PKT_SET_ROLE, 100, &role, sizeof role);
}

/* Sends set_sync (an acked command, the driver's) with `seq`: \return whether its ack came back */
static bool acked(uint8_t seq)
{
    pb_set_sync_t sync = {PB_SYNC_MODE_FULL, 100};
    return command_acked(PB_PKT_SET_SYNC, seq, &sync, sizeof sync);
}

static void packets_go_both_ways_at_the_baud_rate(void)
{
    robot_boot();
    robot_run_us(20000);
    CHECK(drives(), "the host drives");
    CHECK(acked(1), "set_sync acked");
    robot_run_us(300000); /* full states every 100 ms */
    double bit = xm_usart_bit_cycles(XM_USARTC0);
    CHECK(bit > 0 && XM_HZ / bit > BAUD * 0.999 && XM_HZ / bit < BAUD * 1.001, "%.0f Bd", bit > 0 ? XM_HZ / bit : 0);
    /* The transmitter keeps its shift register busy: frames back to back, 10 bits each. */
    uint32_t n = xm_usart_tx_count(XM_USARTC0), gaps = 0;
    for (uint32_t i = 1; i < n; i++) {
        const xm_frame_t *a = xm_usart_tx_frame(XM_USARTC0, i - 1), *b = xm_usart_tx_frame(XM_USARTC0, i);
        gaps += b->start == a->end ? 0 : 1;
    }
    CHECK(n > 100, "%u bytes sent", n);
    CHECK(gaps <= n / 4, "%u of %u frames began after a pause", gaps, n);
}

static void overruns_and_frame_errors_are_counted_and_survived(void)
{
    robot_boot();
    settings.link.failsafe_timeout_ms = 0;
    robot_run_us(20000);
    CHECK(drives(), "the host drives");
    uint16_t lost = robot_state.errors.rx_overflow;
    /* 30 bytes arrive while interrupts stay masked for 1 ms: the receiver holds three, the rest overrun. */
    uint8_t noise[30];
    for (unsigned i = 0; i < sizeof noise; i++)
        noise[i] = (uint8_t)(0x30 + i);
    xm_usart_send(XM_USARTC0, noise, sizeof noise, BAUD, xm_now());
    xm_busy(XM_MS(1), true);
    robot_run_us(5000);
    CHECK(robot_state.errors.rx_overflow > lost, "the overrun is counted: rx_overflow %u", robot_state.errors.rx_overflow);
    CHECK(acked(2), "the link works on after the overrun");
    lost = robot_state.errors.rx_overflow;
    xm_usart_rx_at(XM_USARTC0, 0x00, xm_now() + XM_US(100), true); /* a break: a byte with a bad stop bit */
    robot_run_us(5000);
    CHECK(robot_state.errors.rx_overflow == lost + 1, "the frame error is counted: rx_overflow %u",
          robot_state.errors.rx_overflow);
    CHECK(acked(3), "and the link works on");
}

void suite_xm_uart(void)
{
    RUN(packets_go_both_ways_at_the_baud_rate);
    RUN(overruns_and_frame_errors_are_counted_and_survived);
}
