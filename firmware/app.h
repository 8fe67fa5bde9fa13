/**
 * \file app.h
 * The firmware core, the same on every target: app_init() starts every module, app_poll() runs a main
 * loop tick when the scheduler says one is due. main.c (robot) and hal/sim (emulator) call them.
 */
#ifndef APP_H
#define APP_H

#include <stdbool.h>

/** Initializes the HAL and every driver and module, sends `hello`, enables interrupts. */
void app_init(void);

/** Runs one main loop tick if one is due. \return true if it ran one. */
bool app_poll(void);

/** Sleeps until an interrupt, unless a tick is due: an interrupt that makes one due while it goes to sleep wakes it
 *  at once. The main loop is `for (;;) if (!app_poll()) app_idle();`. */
void app_idle(void);

/** Every task of one tick, in order (app_poll() brackets it with the scheduler's tick accounting). */
void app_tick(void);

#endif
