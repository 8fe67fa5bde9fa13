/**
 * \file test_time.c
 * Time and the scheduler's timer (TCC0) on the model: hours of uptime across both wraps of the time base.
 */
#include <avr/io.h>

#include "app.h"
#include "core/data.h"
#include "hal/hal.h"
#include "robot.h"
#include "xm_tests.h"

/* hal_micros() wraps after 2^32 us (71.6 min); TCC0's 32-bit count at 500 kHz after twice that (143.2 min). */
#define MICROS_WRAP_S 4294.967296
#define TICKS_WRAP_S (2.0 * MICROS_WRAP_S)

static uint64_t at_seconds(double s)
{
    return (uint64_t)(s * (double)XM_HZ);
}

/* Two seconds of running from `t`: how many scheduler compare interrupts and main loop ticks a second. */
static void two_seconds_at(double s, const char *where)
{
    uint64_t t = at_seconds(s);
    if (t > xm_now())
        xm_fast_forward(t - xm_now());
    robot_run_us(20000); /* what piled up while skipping is served */
    xm_irq_clear_counts();
    uint32_t ticks0 = robot_ticks(), ms0 = robot_state.time.time_ms;
    robot_frames_clear();
    robot_run_us(2000000);
    uint32_t compares = xm_irq_count(TCC0_CCA_vect_num) + xm_irq_count(TCC0_CCB_vect_num) +
                        xm_irq_count(TCC0_CCC_vect_num) + xm_irq_count(TCC0_CCD_vect_num);
    uint32_t ticks = robot_ticks() - ticks0, ms = robot_state.time.time_ms - ms0;
    /* A tick a millisecond, a line sensor acquisition's 5 phases in each, the beacons' timer and messages. */
    CHECK(compares <= 2 * (1000 + 5000 + 200), "%s: %u scheduler interrupts in 2 s", where, compares);
    CHECK(ticks >= 1990 && ticks <= 2010, "%s: %u main loop ticks in 2 s", where, ticks);
    CHECK(ms >= 1995 && ms <= 2005, "%s: the robot's clock moved %u ms in 2 s", where, ms);
    uint32_t states = robot_frames_of_type(PB_PKT_STATE_FULL);
    CHECK(states >= 19 && states <= 21, "%s: %u full states on the host link in 2 s", where, states);
}

static void scheduler_keeps_time_across_both_wraps(void)
{
    robot_boot();
    settings.link.failsafe_timeout_ms = 0;
    robot_run_us(1000000);
    /* Steps of at most 25 minutes: the firmware compares times as signed 32-bit microsecond differences. */
    two_seconds_at(1500.0, "25 min");
    two_seconds_at(3000.0, "50 min");
    two_seconds_at(MICROS_WRAP_S - 1.0, "across 71.6 min (hal_micros wraps)");
    two_seconds_at(MICROS_WRAP_S + 1200.0, "91.6 min");
    two_seconds_at(MICROS_WRAP_S + 2400.0, "111.6 min");
    two_seconds_at(TICKS_WRAP_S - 1.0, "across 143.2 min (the timer's count wraps)");
    two_seconds_at(TICKS_WRAP_S + 600.0, "153.2 min");
    CHECK(xm_misuse_count() == 0, "the model saw: %s", xm_misuse_last());
}

/* The HAL is compiled without optimisation here (as a debug build would be): a call to itself would not be
 * dropped by the compiler. */
static void disarming_a_channel_returns_and_keeps_it_quiet(void)
{
    robot_boot();
    robot_run_us(5000);
    uint32_t before = xm_irq_count(TCC0_CCD_vect_num);
    hal_sched_arm(3, 1000);
    hal_sched_disarm(3);
    robot_run_us(3000);
    CHECK(xm_irq_count(TCC0_CCD_vect_num) == before, "channel 3 fired after it was disarmed");
    CHECK((TCC0.INTCTRLB & TC0_CCDINTLVL_gm) == 0, "its interrupt level is off: 0x%02x", TCC0.INTCTRLB);
}

void suite_xm_time(void)
{
    RUN(scheduler_keeps_time_across_both_wraps);
    RUN(disarming_a_channel_returns_and_keeps_it_quiet);
}
