/**
 * \file scheduler.h
 * Four-channel scheduler on one timer (thesis 11.1): one event per channel at a time, callbacks run in
 * interrupt context and must only start short actions. Channel 0 times the main loop at
 * settings.scheduler.main_period_us; the others belong to drivers. On the ground floor (core/): drivers
 * and modules use it, it uses only the HAL and the global data.
 */
#ifndef SCHEDULER_H
#define SCHEDULER_H

#include <stdbool.h>
#include <stdint.h>

enum {
    SCHED_CH_MAIN = 0,      /**< main loop tick (owned by the scheduler) */
    SCHED_CH_LINE = 1,      /**< line sensor acquisition phases */
    SCHED_CH_PROX_TX = 2,   /**< proximity: spacing of the messages of a beacon */
    SCHED_CH_PROX_BEACON = 3 /**< proximity: beacon period */
};

typedef void (*scheduler_cb_t)(void);

/** Starts the main loop channel. */
void scheduler_init(void);

/** Calls `cb` from the timer interrupt `delay_us` from now (any delay; long ones are re-armed).
 *  Replaces what was scheduled on `ch`. */
void scheduler_after(uint8_t ch, uint32_t delay_us, scheduler_cb_t cb);

/** Like scheduler_after() for a delay the timer's compare spans at once (at most HAL_SCHED_MAX_DELAY_US), without
 *  reading the clock here or when it fires: the cheap way for a driver's short steps (the line sensor's phases, five
 *  interrupts a tick). A channel armed this way must not be re-armed by scheduler_again(), which needs the time it
 *  last fired. */
void scheduler_after_short(uint8_t ch, uint16_t delay_us, scheduler_cb_t cb);

/** Like scheduler_after(), relative to the time the channel last fired: drift-free periodic events. */
void scheduler_again(uint8_t ch, uint32_t period_us, scheduler_cb_t cb);

void scheduler_cancel(uint8_t ch);

/** \return true (once per tick) when a main loop tick is due; call scheduler_tick_end() when done. */
bool scheduler_tick_begin(void);

/** \return true when a main loop tick is due (nothing else: the main loop asks before it sleeps). */
bool scheduler_tick_due(void);

/** Ends a tick: measures its duration into robot_state.time.tick_max_us and counts overruns (a tick that
 *  took longer than the period, or a tick that came due while the previous one still ran) in
 *  robot_state.time.overruns and .last_overrun_ms. */
void scheduler_tick_end(void);

/** \return true when overruns happened that scheduler_take_overruns() has not taken yet. */
bool scheduler_overruns_pending(void);

/** Takes the overruns since the last call, for a warning. \param longest_us set to the longest tick among
 *  them (us) \return how many ticks overran */
uint16_t scheduler_take_overruns(uint16_t *longest_us);

/** Period of the main loop in microseconds (settings.scheduler.main_period_us, clamped). */
uint16_t scheduler_period_us(void);

#endif
