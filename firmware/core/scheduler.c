#include "scheduler.h"

#include "core/data.h"
#include "hal/hal.h"

typedef struct {
    scheduler_cb_t cb;
    uint32_t target; /* when the callback is due */
    uint32_t fired;  /* when it last fired (basis of scheduler_again) */
    uint8_t active;
    uint8_t short_delay; /* armed by scheduler_after_short(): target and fired are not kept */
} channel_t;

static channel_t channels[HAL_SCHED_CHANNELS];
static volatile uint8_t ticks_pending;
static volatile uint8_t late_ticks;
static uint32_t tick_start;
/* Overruns not yet taken by scheduler_take_overruns(). */
static uint16_t unreported;
static uint16_t unreported_longest_us;

/* Arms the channel for its target, `now` being hal_micros() as the caller read it (reading it costs: once per
 * interrupt is enough). */
static void arm(uint8_t ch, uint32_t now)
{
    int32_t left = (int32_t)(channels[ch].target - now);
    hal_sched_arm(ch, left <= 0 ? 0u : left > (int32_t)HAL_SCHED_MAX_DELAY_US ? HAL_SCHED_MAX_DELAY_US : (uint32_t)left);
}

uint16_t scheduler_period_us(void)
{
    uint16_t p = settings.scheduler.main_period_us;
    return p < 500u ? 500u : p > 20000u ? 20000u : p;
}

static void main_tick(void)
{
    if (ticks_pending)
        late_ticks++; /* the previous tick has not finished: an overrun */
    else
        ticks_pending = 1;
    scheduler_again(SCHED_CH_MAIN, scheduler_period_us(), main_tick);
}

void scheduler_init(void)
{
    for (uint8_t i = 0; i < HAL_SCHED_CHANNELS; i++) {
        channels[i].active = 0;
        hal_sched_disarm(i);
    }
    ticks_pending = 0;
    late_ticks = 0;
    unreported = 0;
    unreported_longest_us = 0;
    channels[SCHED_CH_MAIN].fired = hal_micros();
    scheduler_again(SCHED_CH_MAIN, scheduler_period_us(), main_tick);
}

void scheduler_after(uint8_t ch, uint32_t delay_us, scheduler_cb_t cb)
{
    uint8_t s = hal_irq_save();
    channel_t *c = &channels[ch];
    c->cb = cb;
    c->target = hal_micros() + delay_us;
    c->active = 1;
    c->short_delay = 0;
    hal_sched_arm(ch, delay_us > HAL_SCHED_MAX_DELAY_US ? HAL_SCHED_MAX_DELAY_US : delay_us);
    hal_irq_restore(s);
}

void scheduler_after_short(uint8_t ch, uint16_t delay_us, scheduler_cb_t cb)
{
    uint8_t s = hal_irq_save();
    channel_t *c = &channels[ch];
    c->cb = cb;
    c->active = 1;
    c->short_delay = 1;
    hal_sched_arm(ch, delay_us);
    hal_irq_restore(s);
}

void scheduler_again(uint8_t ch, uint32_t period_us, scheduler_cb_t cb)
{
    uint8_t s = hal_irq_save();
    channel_t *c = &channels[ch];
    uint32_t now = hal_micros();
    c->cb = cb;
    c->target = c->fired + period_us;
    c->short_delay = 0;
    /* After a long stall, restart from now rather than firing a burst of stale events. */
    if ((int32_t)(c->target - now) < -(int32_t)period_us)
        c->target = now + period_us;
    c->active = 1;
    arm(ch, now);
    hal_irq_restore(s);
}

void scheduler_cancel(uint8_t ch)
{
    uint8_t s = hal_irq_save();
    channels[ch].active = 0;
    hal_sched_disarm(ch);
    hal_irq_restore(s);
}

/* A long delay's interrupt: due (its time kept for scheduler_again()), or an intermediate wake-up, re-armed. Apart
 * from scheduler_isr(): the registers it needs were saved in every interrupt of a short delay too. */
static __attribute__((noinline)) bool long_delay_due(channel_t *c, uint8_t ch)
{
    uint32_t now = hal_micros();
    if ((int32_t)(c->target - now) > 0) {
        arm(ch, now);
        return false;
    }
    c->fired = c->target;
    return true;
}

void scheduler_isr(uint8_t ch)
{
    if (ch >= HAL_SCHED_CHANNELS)
        return;
    channel_t *c = &channels[ch];
    if (!c->active)
        return;
    if (!c->short_delay && !long_delay_due(c, ch))
        return;
    c->active = 0;
    c->cb();
}

bool scheduler_tick_begin(void)
{
    if (!ticks_pending)
        return false;
    tick_start = hal_micros();
    return true;
}

bool scheduler_tick_due(void)
{
    return ticks_pending != 0;
}

void scheduler_tick_end(void)
{
    uint32_t took = hal_micros() - tick_start;
    uint8_t s = hal_irq_save();
    ticks_pending = 0;
    uint8_t late = late_ticks;
    late_ticks = 0;
    hal_irq_restore(s);
    if (took > scheduler_period_us())
        late = late ? late : 1;
    if (took > 0xFFFFu)
        took = 0xFFFFu;
    if (late) {
        robot_state.time.overruns = (uint16_t)(robot_state.time.overruns + late);
        /* 0 means "never": an overrun in the very first millisecond is dated 1 ms. */
        robot_state.time.last_overrun_ms = robot_state.time.time_ms ? robot_state.time.time_ms : 1u;
        unreported = (uint16_t)(unreported + late);
        if (took > unreported_longest_us)
            unreported_longest_us = (uint16_t)took;
    }
    if (took > robot_state.time.tick_max_us)
        robot_state.time.tick_max_us = (uint16_t)took;
}

bool scheduler_overruns_pending(void)
{
    return unreported != 0;
}

uint16_t scheduler_take_overruns(uint16_t *longest_us)
{
    uint16_t n = unreported;
    *longest_us = unreported_longest_us;
    unreported = 0;
    unreported_longest_us = 0;
    return n;
}
