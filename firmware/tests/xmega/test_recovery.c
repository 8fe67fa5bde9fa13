/**
 * \file test_recovery.c
 * What brings the robot back on the model: the watchdog after a hang, a reset after a stray interrupt, a main loop
 * that does not sleep through an interrupt, and the clock's DFLL started after its reference.
 */
#include <avr/io.h>

#include "app.h"
#include "core/data.h"
#include "modules/locomotion.h"
#include "robot.h"
#include "xm_tests.h"

#define TCE0_BASE 0x0A00u
#define TCC1_BASE 0x0840u

static void a_hung_main_loop_is_reset_by_the_watchdog_and_the_motors_stop(void)
{
    robot_boot();
    settings.link.failsafe_timeout_ms = 0;
    uint16_t detail;
    pb_wheel_speeds_t teleop = {0.2f, 0.2f};
    locomotion_teleop(&teleop, &detail); /* the wheels stand (no encoder edges): the controllers drive them harder */
    robot_run_us(200000);
    CHECK(xm_tc_duty(TCE0_BASE, 0) > 20.0 && xm_tc_duty(TCE0_BASE, 2) > 20.0, "motors driven: %.0f %% %.0f %%",
          xm_tc_duty(TCE0_BASE, 0), xm_tc_duty(TCE0_BASE, 2));
    uint64_t hang = xm_now();
    xm_busy(XM_MS(500), false); /* the main loop stuck in a loop: interrupts go on, no tick ends */
    CHECK(xm_restarts(XM_RESTART_WATCHDOG) == 1, "the watchdog reset the MCU %u times", xm_restarts(XM_RESTART_WATCHDOG));
    double after_ms = (double)(xm_last_restart_at() - hang) / XM_MS(1);
    CHECK(xm_restarts(XM_RESTART_WATCHDOG) == 0 || after_ms <= 140.0, "reset %.0f ms into the hang", after_ms);
    CHECK(xm_tc_duty(TCE0_BASE, 0) == 0.0 && xm_tc_duty(TCE0_BASE, 2) == 0.0, "the motors' PWM stops: %.0f %% %.0f %%",
          xm_tc_duty(TCE0_BASE, 0), xm_tc_duty(TCE0_BASE, 2));
    robot_restart();
    uint32_t ticks = robot_ticks();
    robot_run_us(50000);
    CHECK(robot_ticks() - ticks >= 45, "running again after the reset: %u ticks in 50 ms", robot_ticks() - ticks);
    CHECK(RST.STATUS & RST_WDRF_bm, "the reset cause says watchdog: 0x%02x", RST.STATUS);
}

static void a_stray_interrupt_resets_the_mcu_instead_of_blocking_its_level(void)
{
    robot_boot();
    settings.link.failsafe_timeout_ms = 0;
    robot_run_us(20000);
    /* A peripheral's interrupt enabled with no handler in the program (TCC1's overflow, LO level). */
    xm_write8(TCC1_BASE + 0x06, TC_OVFINTLVL_LO_gc);
    xm_write8(TCC1_BASE + 0x00, TC_CLKSEL_DIV1_gc);
    uint8_t why = robot_run_us(5000);
    CHECK(why == XM_RESTART_SOFTWARE, "restarted by a reset (%u), not by a jump to 0 (%u): %u", XM_RESTART_SOFTWARE,
          XM_RESTART_JUMP_TO_0, why);
    robot_restart();
    uint32_t ir_frames = xm_usart_tx_count(XM_USARTD0);
    robot_run_us(300000);
    CHECK(PMIC.STATUS == 0, "no interrupt level left active: PMIC.STATUS 0x%02x", PMIC.STATUS);
    CHECK(xm_usart_tx_count(XM_USARTD0) - ir_frames >= 40, "LO-level interrupts run: %u IR frames sent in 300 ms",
          xm_usart_tx_count(XM_USARTD0) - ir_frames);
}

static uint64_t compare_at;

/* At the CPU's write to SLEEP.CTRL on its way to sleep: time runs to the next main loop tick's compare match. */
static void compare_matches_now(void)
{
    uint16_t cca = (uint16_t)(TCC0.CCAL | TCC0.CCAH << 8);
    compare_at = xm_tc_next_count_time(0x0800, cca);
    xm_busy(compare_at - xm_now(), false);
}

static void an_interrupt_while_the_main_loop_goes_to_sleep_is_not_slept_through(void)
{
    robot_boot();
    settings.link.failsafe_timeout_ms = 0;
    robot_run_us(20000);
    uint16_t overruns = robot_state.time.overruns;
    for (int k = 0; k < 5; k++) {
        compare_at = 0;
        xm_after_write(0x0048, compare_matches_now); /* SLEEP.CTRL */
        uint32_t ticks = robot_ticks();
        robot_run_us(3000);
        uint64_t next = 0;
        for (uint32_t n = ticks; n < robot_ticks() && !next; n++)
            if (robot_tick_time(n) >= compare_at)
                next = robot_tick_time(n);
        CHECK(compare_at && next && next - compare_at <= XM_US(50), "the tick due at %.3f ms ran %.0f us later",
              (double)compare_at / XM_MS(1), next ? (double)(next - compare_at) / XM_US(1) : -1.0);
    }
    CHECK(robot_state.time.overruns == overruns, "%u ticks overran", robot_state.time.overruns - overruns);
}

static void the_dfll_starts_after_its_reference(void)
{
    robot_boot();
    CHECK(!xm_dfll_enabled_early(), "the DFLL was enabled before its 32.768 kHz reference was ready");
    CHECK(xm_sysclk() == CLK_SCLKSEL_RC32M_gc && (DFLLRC32M.CTRL & DFLL_ENABLE_bm), "32 MHz RC, trimmed by its DFLL");
}

void suite_xm_recovery(void)
{
    RUN(a_hung_main_loop_is_reset_by_the_watchdog_and_the_motors_stop);
    RUN(a_stray_interrupt_resets_the_mcu_instead_of_blocking_its_level);
    RUN(an_interrupt_while_the_main_loop_goes_to_sleep_is_not_slept_through);
    RUN(the_dfll_starts_after_its_reference);
}
