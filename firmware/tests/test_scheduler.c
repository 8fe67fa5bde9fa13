#include "harness.h"
#include "hal/hal.h"
#include "modules/reflector.h"
#include "modules/scheduler.h"
#include "modules/settings.h"
#include "world.h"

static int fired;
static uint32_t fired_at;
static void mark(void)
{
    fired++;
    fired_at = hal_micros();
}

static void main_loop_runs_at_the_configured_period(void)
{
    world_reset(1);
    uint32_t t0 = robot_state.time.time_ms;
    world_run_ms(1000);
    CHECK(robot_state.time.time_ms - t0 >= 999 && robot_state.time.time_ms - t0 <= 1001, "time %u ms",
          robot_state.time.time_ms - t0);
    /* Count ticks through the state packets' tick_max and the clock: 500 us ticks. */
    settings.scheduler.main_period_us = 500;
    pb_set_sync_t s = {PB_SYNC_MODE_REDUCED, 1};
    host_send(PB_PKT_SET_SYNC, 1, &s, sizeof s);
    world.link_bytes_per_ms = 1000;
    world_run_ms(5);
    host_collect();
    host_clear();
    world_run_ms(100);
    int n = host_count(PB_PKT_STATE_REDUCED);
    CHECK(n >= 98 && n <= 101, "a state per ms at 500 us ticks: %d", n);
    CHECK(robot_state.time.overruns == 0, "no overruns: %u", robot_state.time.overruns);
}

static void channels_fire_once_at_their_time_even_after_long_delays(void)
{
    world_reset(1);
    settings.proximity.ir_power = 0; /* keep the proximity driver off its channel */
    world_run_ms(settings.proximity.beacon_period_ms + 1);
    fired = 0;
    uint32_t start = hal_micros();
    scheduler_after(SCHED_CH_PROX_TX, 150000, mark); /* longer than one hardware compare can wait */
    world_run_ms(149);
    CHECK(fired == 0, "not early");
    world_run_ms(3);
    CHECK(fired == 1 && fired_at - start >= 150000 && fired_at - start < 150200, "fired once at %u us",
          fired_at - start);
    scheduler_after(SCHED_CH_PROX_TX, 1000, mark);
    scheduler_cancel(SCHED_CH_PROX_TX);
    world_run_ms(5);
    CHECK(fired == 1, "cancelled");
}

static void tick_health_is_reported_and_reset_with_each_state_packet(void)
{
    world_reset(1);
    robot_state.time.tick_max_us = 777;
    world_run_ms(settings.sync.period_ms + 2);
    /* In the emulator code takes no time, so a sent state packet resets the maximum to 0. */
    CHECK(robot_state.time.tick_max_us == 0, "tick_max_us %u", robot_state.time.tick_max_us);
    CHECK(robot_state.time.overruns == 0, "overruns %u", robot_state.time.overruns);
}

void suite_scheduler(void)
{
    RUN(main_loop_runs_at_the_configured_period);
    RUN(channels_fire_once_at_their_time_even_after_long_delays);
    RUN(tick_health_is_reported_and_reset_with_each_state_packet);
}
