#define _GNU_SOURCE
#include <string.h>

#include "core/data.h"
#include "core/scheduler.h"
#include "hal/hal.h"
#include "harness.h"
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
    world_run_ms(150);
    host_collect();
    host_clear();
    CHECK(robot_state.time.tick_max_us == 0, "code takes no time here: %u", robot_state.time.tick_max_us);
    sim_host_stretch_tick_us(300);
    world_run_ms(1);
    CHECK(robot_state.time.tick_max_us == 300 && robot_state.time.overruns == 0, "a 300 us tick: max %u, overruns %u",
          robot_state.time.tick_max_us, robot_state.time.overruns);
    world_run_ms(settings.sync.period_ms + 10);
    host_collect();
    const host_frame_t *f = host_find(PB_PKT_STATE_FULL, 0);
    pb_robot_state_t s;
    if (f)
        memcpy(&s, f->payload, sizeof s);
    CHECK(f && s.time.tick_max_us == 300, "the next state packet tells it: %u", f ? s.time.tick_max_us : 0);
    CHECK(robot_state.time.tick_max_us == 0, "and the maximum starts again: %u", robot_state.time.tick_max_us);
}

static int overrun_warnings(void)
{
    host_collect();
    int n = 0;
    for (int i = 0; i < host_count(PB_PKT_DEBUG_TEXT); i++) {
        const host_frame_t *f = host_find(PB_PKT_DEBUG_TEXT, i);
        n += f->payload[0] == PB_DEBUG_MODULE_SCHEDULER && f->payload[1] == 1;
    }
    return n;
}

static void an_overrun_is_counted_dated_and_reported_at_most_once_a_second(void)
{
    world_reset(1);
    world_run_ms(500);
    host_collect();
    host_clear();
    sim_host_stretch_tick_us(1500); /* one and a half periods: the next tick came due while it ran */
    world_run_ms(3);
    uint32_t when = robot_state.time.time_ms;
    CHECK(robot_state.time.overruns == 1, "overruns %u", robot_state.time.overruns);
    CHECK(robot_state.time.last_overrun_ms >= when - 3 && robot_state.time.last_overrun_ms <= when, "dated %u (now %u)",
          robot_state.time.last_overrun_ms, when);
    world_run_ms(5);
    CHECK(overrun_warnings() == 1, "warned once: %d", overrun_warnings());
    const host_frame_t *f = host_find(PB_PKT_DEBUG_TEXT, 0);
    CHECK(f && f->len > 2 && memmem(f->payload + 2, f->len - 2u, "overran 1 times", 15) != NULL,
          "the warning says how often");
    /* More within the second: counted, no more warnings yet; then one warning for all of them. */
    for (int k = 0; k < 3; k++) {
        sim_host_stretch_tick_us(2500);
        world_run_ms(100);
    }
    CHECK(robot_state.time.overruns >= 4, "overruns %u", robot_state.time.overruns);
    CHECK(overrun_warnings() == 1, "still one warning: %d", overrun_warnings());
    world_run_ms(1000);
    CHECK(overrun_warnings() == 2, "the next second warns again: %d", overrun_warnings());
}

void suite_scheduler(void)
{
    RUN(main_loop_runs_at_the_configured_period);
    RUN(channels_fire_once_at_their_time_even_after_long_delays);
    RUN(tick_health_is_reported_and_reset_with_each_state_packet);
    RUN(an_overrun_is_counted_dated_and_reported_at_most_once_a_second);
}
