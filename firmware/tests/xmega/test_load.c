/**
 * \file test_load.c
 * Interrupts per second in each mode of the robot, on the model with the real configuration: the HAL's own
 * (timers, ADC, TWI, USARTs) and those the world brings (encoder edges at the wheels' speed, host bytes, IR from
 * another robot), as the cycle bench's scenarios have them; "bluetooth" is the USART's load of the HCI build's Bluetooth
 * scenario (the H4 wire busy both ways: the host's packets back to back, full state every 12 ms). Prints `LOAD: <mode> <vector> <per second> <most in a
 * millisecond>` lines: `make bench` weighs them with the ISRs' measured cycles (bench/isr_bench.c).
 */
#include <avr/io.h>
#include <string.h>

#include "core/data.h"
#include "hal/hal.h"
#include "modules/line_follower.h"
#include "modules/locomotion.h"
#include "modules/track.h"
#include "protocol/pb_frame.h"
#include "protocol/slip.h"
#include "robot.h"
#include "xm_tests.h"

#define BAUD 115200u

enum { HOST_NONE, HOST_HEARTBEATS, HOST_WIRE_RATE };

typedef struct {
    const char *name;
    bool moving;
    uint8_t host;
    bool ir;
} mode_t;

/* About 140 mm/s: an edge every 5 ms on each wheel (as the bench). */
static void wheels_turn(uint64_t from, uint64_t to)
{
    for (uint64_t t = from + XM_MS(1); t < to; t += XM_MS(5)) {
        xm_ac_toggle(0, t);
        xm_ac_toggle(1, t + XM_MS(2));
    }
}

/* A heartbeat from the host every millisecond (7 bytes: what 115200 Bd carries besides the replies), or back to
 * back (every byte the wire carries). */
static void host_talks(uint64_t from, uint64_t to, uint8_t how)
{
    uint8_t frame[PB_MAX_FRAME], slip[2 * PB_MAX_FRAME];
    uint16_t n = slip_encode(slip, frame, pb_frame_encode(frame, PB_PKT_HEARTBEAT, 0, NULL, 0));
    for (uint64_t t = from; t < to;) {
        uint64_t end = xm_usart_send(XM_USARTC0, slip, n, BAUD, t);
        t = how == HOST_WIRE_RATE ? end : t + XM_MS(1);
    }
}

/* Another robot's messages on both receivers, back to back as its link allows. */
static void ir_heard(uint64_t from, uint64_t to)
{
    for (uint64_t t = from; t < to; t += ROBOT_IR_FRAME)
        for (uint8_t u = XM_USARTD0; u <= XM_USARTD1; u++)
            xm_usart_rx_at(u, 0x55, t, false); /* no message: noise the receivers must sift */
}

static void load(const mode_t *m, uint32_t *total)
{
    uint64_t t0 = xm_now(), t1 = t0 + XM_MS(1000);
    if (m->moving)
        wheels_turn(t0, t1);
    if (m->host)
        host_talks(t0, t1, m->host);
    if (m->ir)
        ir_heard(t0, t1);
    xm_irq_clear_counts();
    robot_run_until(t1);
    *total = 0;
    for (uint8_t v = 1; v < XM_VECTORS; v++) {
        uint32_t n = xm_irq_count(v);
        if (!n)
            continue;
        *total += n;
        printf("LOAD: %s %u %u %u\n", m->name, v, n, xm_irq_max_per_ms(v));
    }
}

static void interrupts_per_second_in_each_mode(void)
{
    static const mode_t modes[] = {
        {"idle", false, HOST_NONE, false},
        {"movement", true, HOST_NONE, false},
        {"line_following", true, HOST_NONE, false},
        {"teleoperation", true, HOST_HEARTBEATS, true},
        {"track", true, HOST_NONE, true},
        {"bluetooth", true, HOST_WIRE_RATE, false},
    };
    robot_boot();
    settings.link.failsafe_timeout_ms = 0;
    robot_run_us(200000);
    uint16_t detail;
    for (unsigned i = 0; i < sizeof modes / sizeof modes[0]; i++) {
        const mode_t *m = &modes[i];
        if (i == 1) {
            pb_move_straight_t move = {1, 10.0f, 0.15f};
            locomotion_straight(&move, &detail);
        } else if (i == 2) {
            pb_line_follow_t follow = {1, PB_COLOUR_MODE_SEGMENTS, 0.0f};
            line_follower_command(&follow, &detail);
        } else if (i == 3) {
            pb_wheel_speeds_t teleop = {0.1f, -0.1f};
            locomotion_teleop(&teleop, &detail);
            settings.sync.mode = PB_SYNC_MODE_REDUCED;
            settings.sync.period_ms = 5;
        } else if (i == 4) {
            settings.sync.mode = PB_SYNC_MODE_FULL;
            settings.sync.period_ms = 100;
            track_command(PB_TRACK_ACTION_START);
        } else if (i == 5) {
            track_command(PB_TRACK_ACTION_STOP);
            settings.sync.period_ms = 12;
            pb_move_straight_t move = {2, 10.0f, 0.15f};
            locomotion_straight(&move, &detail);
        }
        uint32_t total;
        load(m, &total);
        uint32_t adc = 0;
        for (uint8_t v = ADCB_CH0_vect_num; v <= ADCB_CH3_vect_num; v++)
            adc += xm_irq_count(v);
        for (uint8_t v = ADCA_CH0_vect_num; v <= ADCA_CH3_vect_num; v++)
            adc += xm_irq_count(v);
        /* Budgets: the line sensor's acquisition (5 phases a tick) and the tick's compare, the beacon, the colour
         * sensor once per integration, the links' bytes; no interrupt for an ADC conversion. */
        CHECK(adc == 0, "%s: %u ADC interrupts a second", m->name, adc);
        CHECK(xm_irq_count(TWIC_TWIM_vect_num) <= 1400, "%s: %u TWI interrupts a second", m->name,
              xm_irq_count(TWIC_TWIM_vect_num));
        uint32_t links = m->host == HOST_WIRE_RATE ? 2u * 11520u : m->host ? 12000u + 7000u : 1500u;
        CHECK(total <= 6200u + 1400u + 2 * 480u + links, "%s: %u interrupts a second", m->name, total);
    }
    CHECK(xm_misuse_count() == 0, "the model saw: %s", xm_misuse_last());
}

void suite_xm_load(void)
{
    RUN(interrupts_per_second_in_each_mode);
}
