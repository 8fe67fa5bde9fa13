/**
 * \file test_encoder.c
 * The encoders on the model: comparator edges through the event system into TCD0's captures, stamped in 32 bits
 * (4 MHz) by the HAL, counted by the encoder driver.
 */
#include <avr/io.h>

#include "drivers/encoder.h"
#include "hal/hal.h"
#include "robot.h"
#include "xm_tests.h"

#define TCD0_BASE 0x0900u
#define CYCLES_PER_COUNT 8u /* TCD0 at clk/8: 4 MHz */

static void captures_are_stamped_right_at_every_phase_of_the_wrap(void)
{
    static const uint32_t late_us[] = {0, 2, 10, 200}; /* how long the capture's interrupt waits (interrupts masked) */
    robot_boot();
    robot_run_us(10000);
    int wrong = 0, total = 0;
    for (unsigned l = 0; l < sizeof late_us / sizeof late_us[0]; l++)
        for (int k = -24; k <= 24; k += 2) { /* the edge k counts before (< 0) or after the count wraps */
            uint64_t wrap = xm_tc_next_count_time(TCD0_BASE, 0);
            if (wrap < xm_now() + XM_US(400))
                wrap += 0x10000ull * CYCLES_PER_COUNT;
            uint64_t edge = wrap + (uint64_t)((int64_t)k * CYCLES_PER_COUNT);
            robot_run_until(edge - XM_US(200));
            uint32_t before = hal_capture_now(); /* 800 counts before the edge: same high half unless k >= 0 */
            uint32_t expected = (before & 0xFFFF0000ul) + (k >= 0 ? 0x10000ul : 0) + (uint16_t)k;
            xm_ac_toggle(0, edge);
            if (late_us[l]) {
                robot_run_until(edge - XM_US(1));
                xm_busy(XM_US(1 + late_us[l]), true); /* a critical section (or another HI interrupt) meanwhile */
            }
            robot_run_us(300);
            encoder_snapshot_t e;
            encoder_snapshot(ENCODER_LEFT, &e);
            total++;
            if (e.last != expected && wrong++ < 3)
                printf("  edge %d counts from the wrap, its interrupt %u us late: stamped %lu, was %lu (%+ld)\n", k,
                       late_us[l], (unsigned long)e.last, (unsigned long)expected, (long)(e.last - expected));
        }
    CHECK(wrong == 0, "%d of %d captures stamped wrong", wrong, total);
    CHECK(xm_misuse_count() == 0, "the model saw: %s", xm_misuse_last());
}

static void chatter_below_the_physical_minimum_is_not_counted(void)
{
    robot_boot();
    robot_run_us(5000);
    encoder_snapshot_t a, b;
    encoder_snapshot(ENCODER_LEFT, &a);
    uint64_t t = xm_now() + XM_US(500);
    for (int i = 0; i < 20; i++, t += XM_MS(2)) {
        xm_ac_toggle(0, t);            /* a stripe edge, */
        xm_ac_toggle(0, t + XM_US(4)); /* and the comparator chattering on it: back and forth */
        xm_ac_toggle(0, t + XM_US(9));
    }
    robot_run_until(t + XM_MS(1));
    encoder_snapshot(ENCODER_LEFT, &b);
    CHECK(b.count - a.count == 20, "20 stripe edges counted as %ld", (long)(b.count - a.count));
    CHECK(b.periods == 2 && b.period[0] == 2000u * 4u && b.period[1] == 2000u * 4u,
          "periods %lu and %lu capture ticks (2 ms each)", (unsigned long)b.period[0], (unsigned long)b.period[1]);
}

void suite_xm_encoder(void)
{
    RUN(captures_are_stamped_right_at_every_phase_of_the_wrap);
    RUN(chatter_below_the_physical_minimum_is_not_counted);
}
