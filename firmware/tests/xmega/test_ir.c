/**
 * \file test_ir.c
 * The IR link on the model: the robot's messages frame by frame (which LED, what carrier, how long a burst), the
 * beacons' pace, and messages from other robots heard on both receivers.
 */
#include <avr/io.h>
#include <string.h>

#include "core/data.h"
#include "hal/hal.h"
#include "robot.h"
#include "xm_tests.h"

#define SYNC 0xA5u
/* Carrier cycles a common IR receiver accepts in one burst before its gain control takes it for noise. */
#define RECEIVER_MAX_BURST_CYCLES 70.0
#define CARRIER_HZ 38000.0

/* The line code as hal_xmega.c describes it, for the other robots' side: a byte as it is when its frame has no
 * burst of more than 4 bit times, else rotated left, masked with 0x29 and flagged in the 9th bit. */
static unsigned longest_burst_bits(uint16_t data, uint8_t bits)
{
    unsigned run = 1, longest = 1; /* the start bit */
    for (uint8_t i = 0; i < bits; i++) {
        run = (data & (1u << i)) ? 0 : run + 1;
        if (run > longest)
            longest = run;
    }
    return longest;
}

static uint16_t line_code(uint8_t b)
{
    if (longest_burst_bits(b, 9) <= 4)
        return b;
    return (uint16_t)(0x100u | (uint8_t)(((b << 1) | (b >> 7)) ^ 0x29u));
}

static uint8_t line_decode(uint16_t f)
{
    if (!(f & 0x100u))
        return (uint8_t)f;
    uint8_t r = (uint8_t)(f ^ 0x29u);
    return (uint8_t)((r >> 1) | (r << 7));
}

static uint8_t crc8(const uint8_t *p, uint8_t n)
{
    uint8_t c = 0;
    while (n--) {
        c ^= *p++;
        for (uint8_t i = 0; i < 8; i++)
            c = (uint8_t)((c & 0x80u) ? (unsigned)(c << 1) ^ 0x07u : (unsigned)(c << 1));
    }
    return c;
}

/* ---- what the robot transmitted ---- */

typedef struct {
    uint8_t bytes[13], n;
    uint32_t first; /* its first frame in the USARTD0 log */
} message_t;

/* Splits the transmitted frames into messages. \return how many */
static int messages(message_t *out, int max)
{
    int k = 0;
    uint32_t n = xm_usart_tx_count(XM_USARTD0);
    for (uint32_t i = 0; i < n && k < max;) {
        message_t *m = &out[k];
        m->first = i;
        m->n = 0;
        while (i < n && m->n < 13) {
            m->bytes[m->n++] = line_decode(xm_usart_tx_frame(XM_USARTD0, i++)->data);
            if (m->n >= 4 && m->n == 5u + (m->bytes[2] & 0x0Fu))
                break;
        }
        k++;
    }
    return k;
}

static void beacons_leave_byte_by_byte_through_their_own_led(void)
{
    robot_boot();
    settings.link.failsafe_timeout_ms = 0;
    robot_run_us(1200000);
    message_t msg[64];
    int n = messages(msg, 64);
    /* A beacon takes 96 ms on the link: at the 40 ms period one goes every 80 or 120 ms. */
    CHECK(n >= 36 && n <= 64, "%d beacon messages in 1.2 s", n);
    if (n == 0)
        return;
    if (msg[n - 1].n < 5)
        n--; /* the last one was still going out */
    int bad_led = 0, bad_power = 0, bad = 0;
    for (int k = 0; k < n; k++) {
        const message_t *m = &msg[k];
        if (m->n < 5 || m->bytes[0] != SYNC || m->bytes[m->n - 1] != crc8(m->bytes + 1, (uint8_t)(m->n - 2))) {
            bad++;
            continue;
        }
        uint8_t led = m->bytes[2] >> 4, power = m->bytes[3];
        for (uint32_t i = m->first; i < m->first + m->n; i++) {
            const xm_frame_t *f = xm_usart_tx_frame(XM_USARTD0, i);
            if (XM_IR_LEDS(f->aux_start) != (1u << led) || XM_IR_LEDS(f->aux_end) != (1u << led)) {
                if (!bad_led++)
                    printf("  message %d (LED %u) byte %u: LEDs 0x%x at its start, 0x%x at its end\n", k, led,
                           i - m->first, XM_IR_LEDS(f->aux_start), XM_IR_LEDS(f->aux_end));
            }
            int duty = (int)XM_IR_DUTY(f->aux_start);
            if (duty < power - 1 || duty > power + 1 || XM_IR_DUTY(f->aux_end) != XM_IR_DUTY(f->aux_start)) {
                if (!bad_power++)
                    printf("  message %d (power %u) byte %u: carrier %u %% at its start, %u %% at its end\n", k, power,
                           i - m->first, XM_IR_DUTY(f->aux_start), XM_IR_DUTY(f->aux_end));
            }
        }
    }
    CHECK(bad == 0, "%d messages were not whole", bad);
    CHECK(bad_led == 0, "%d bytes left through another LED than their message's", bad_led);
    CHECK(bad_power == 0, "%d bytes left with another carrier power than their message's", bad_power);
    /* One message after another, each taking its time on the link: never two on the air. */
    for (int k = 1; k < n; k++) {
        const xm_frame_t *last = xm_usart_tx_frame(XM_USARTD0, msg[k].first - 1);
        const xm_frame_t *next = xm_usart_tx_frame(XM_USARTD0, msg[k].first);
        CHECK(next->start >= last->end, "message %d starts before message %d ended", k, k - 1);
    }
    uint64_t airtime = XM_US(hal_ir_message_us(0));
    const xm_frame_t *a = xm_usart_tx_frame(XM_USARTD0, msg[0].first);
    const xm_frame_t *b = xm_usart_tx_frame(XM_USARTD0, msg[0].first + msg[0].n - 1);
    CHECK(b->end - a->start <= airtime && b->end - a->start > airtime * 9 / 10,
          "a beacon message takes %.1f ms on the link, hal_ir_message_us() says %.1f ms",
          (double)(b->end - a->start) / XM_MS(1), (double)airtime / XM_MS(1));
    CHECK(xm_misuse_count() == 0, "the model saw: %s", xm_misuse_last());
}

static void no_carrier_burst_is_longer_than_a_receiver_takes(void)
{
    robot_boot();
    settings.proximity.ir_power = 0; /* no beacons: only the messages sent here */
    robot_run_us(10000);
    for (unsigned v = 0; v < 256; v += 8) {
        hal_ir_msg_t m = {.sender_id = (uint8_t)v, .led = (uint8_t)(v & 3u), .power = 100, .len = 8};
        for (uint8_t i = 0; i < 8; i++)
            m.data[i] = (uint8_t)(v + i);
        int waited = 0;
        while (!hal_ir_send(&m) && waited++ < 200)
            robot_run_us(1000);
        CHECK(waited <= 200, "the transmitter stays busy");
        if (waited > 200)
            return;
    }
    robot_run_us(100000);
    uint32_t n = xm_usart_tx_count(XM_USARTD0);
    double bit = xm_usart_bit_cycles(XM_USARTD0), cycles_per_carrier = (double)XM_HZ / CARRIER_HZ;
    double longest = 0;
    uint16_t worst = 0;
    for (uint32_t i = 0; i < n; i++) {
        const xm_frame_t *f = xm_usart_tx_frame(XM_USARTD0, i);
        double burst = longest_burst_bits(f->data, f->bits) * bit / cycles_per_carrier;
        if (burst > longest) {
            longest = burst;
            worst = f->data;
        }
    }
    CHECK(n >= 32 * 13, "%u frames sent", n);
    CHECK(longest <= RECEIVER_MAX_BURST_CYCLES, "a frame (0x%03x) carries a burst of %.0f carrier cycles (%.2f ms)",
          worst, longest, longest / CARRIER_HZ * 1000.0);
}

/* Sends a message to the robot's receiver `u` as another robot would, starting at `at`. \return when it ends */
static uint64_t hear(uint8_t u, uint8_t sender, uint8_t led, uint8_t power, const uint8_t *data, uint8_t len,
                     uint64_t at)
{
    uint8_t raw[13] = {SYNC, sender, (uint8_t)(led << 4 | len), power};
    if (len)
        memcpy(raw + 4, data, len);
    raw[4 + len] = crc8(raw + 1, (uint8_t)(3 + len));
    for (uint8_t i = 0; i < 5 + len; i++) {
        at += ROBOT_IR_FRAME;
        xm_usart_rx_at(u, line_code(raw[i]), at, false);
    }
    return at;
}

static void other_robots_are_heard_on_each_side_and_reflections_are_obstacles(void)
{
    robot_boot();
    settings.link.failsafe_timeout_ms = 0;
    robot_run_us(50000);
    uint64_t t = xm_now();
    for (int beacon = 0; beacon < 3; beacon++) {
        hear(XM_USARTD0, 9, 2, 25, NULL, 0, t);     /* robot 9 ahead, near: its rear LED */
        t = hear(XM_USARTD1, 12, 0, 100, NULL, 0, t); /* robot 12 behind, far: its front LED */
        t += XM_MS(80);
    }
    robot_run_until(t);
    robot_run_us(5000);
    pb_proximity_side_t f = robot_state.proximity.front, r = robot_state.proximity.rear;
    CHECK(f.robot_id == 9 && f.robot_led == 2 && f.distance == PB_DISTANCE_CLASS_NEAR && (f.flags & PB_PROXIMITY_FLAG_ROBOT),
          "front: robot %u, LED %u, distance %u, flags 0x%x", f.robot_id, f.robot_led, f.distance, f.flags);
    CHECK(r.robot_id == 12 && r.robot_led == 0 && r.distance == PB_DISTANCE_CLASS_FAR,
          "rear: robot %u, LED %u, distance %u", r.robot_id, r.robot_led, r.distance);
    CHECK(!(f.flags & PB_PROXIMITY_FLAG_OBSTACLE), "no obstacle yet: 0x%x", f.flags);
    xm_usart_echo(XM_USARTD0, XM_USARTD0, true); /* something in front reflects the robot's own beacons */
    robot_run_us(300000);
    CHECK(robot_state.proximity.front.flags & PB_PROXIMITY_FLAG_OBSTACLE, "the reflection is an obstacle: 0x%x",
          robot_state.proximity.front.flags);
}

static void payloads_from_another_robot_reach_the_host_byte_for_byte(void)
{
    robot_boot();
    settings.link.failsafe_timeout_ms = 0;
    robot_run_us(50000);
    robot_frames_clear();
    for (unsigned v = 0; v < 256; v += 8) {
        uint8_t data[8];
        for (uint8_t i = 0; i < 8; i++)
            data[i] = (uint8_t)(v + i);
        uint64_t end = hear(XM_USARTD1, 7, 1, 50, data, 8, xm_now());
        robot_run_until(end + XM_MS(5));
    }
    robot_run_us(20000);
    int wrong = 0, got = 0;
    for (unsigned v = 0; v < 256; v += 8) {
        const robot_frame_t *f = robot_frame(PB_PKT_IR_RECEIVED, v / 8u);
        if (!f)
            break;
        got++;
        const pb_ir_received_t *p = (const pb_ir_received_t *)f->payload;
        for (uint8_t i = 0; i < 8; i++)
            wrong += p->data[i] != (uint8_t)(v + i) || p->sender_id != 7 || p->side != 1;
    }
    CHECK(got == 32 && wrong == 0, "%d of 32 payloads forwarded, %d bytes wrong", got, wrong);
}

void suite_xm_ir(void)
{
    RUN(beacons_leave_byte_by_byte_through_their_own_led);
    RUN(no_carrier_burst_is_longer_than_a_receiver_takes);
    RUN(other_robots_are_heard_on_each_side_and_reflections_are_obstacles);
    RUN(payloads_from_another_robot_reach_the_host_byte_for_byte);
}
