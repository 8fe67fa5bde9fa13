/**
 * \file debug.h
 * Debug text with per-module verbosity levels (thesis 6.2.3), sent to the host as `debug_text` packets.
 *
 *     DEBUG_PRINT(LOCOMOTION, 2, "movement %u done", id);
 *
 * A message is sent when its level is at most the module's compile-time ceiling DEBUG_MAX_<MODULE> and at
 * most settings.debug.level (run time). Building with -DNDEBUG_TEXT removes every message and its text.
 * Format strings stay in flash on AVR. The formatter knows %d %i %u %x %c %s %% and the l modifier
 * (%ld %lu %lx); no floats. Not for interrupt context.
 */
#ifndef DEBUG_H
#define DEBUG_H

#include <stdarg.h>
#include <stdint.h>

#include "core/data.h"
#include "hal/hal.h"
#include "pb_protocol.h"

#ifndef DEBUG_MAX_MAIN
#define DEBUG_MAX_MAIN 4
#endif
#ifndef DEBUG_MAX_PROTOCOL
#define DEBUG_MAX_PROTOCOL 4
#endif
#ifndef DEBUG_MAX_LOCOMOTION
#define DEBUG_MAX_LOCOMOTION 4
#endif
#ifndef DEBUG_MAX_LINE
#define DEBUG_MAX_LINE 4
#endif
#ifndef DEBUG_MAX_PROXIMITY
#define DEBUG_MAX_PROXIMITY 4
#endif
#ifndef DEBUG_MAX_SENSORS
#define DEBUG_MAX_SENSORS 4
#endif
#ifndef DEBUG_MAX_SETTINGS
#define DEBUG_MAX_SETTINGS 4
#endif
#ifndef DEBUG_MAX_SCHEDULER
#define DEBUG_MAX_SCHEDULER 4
#endif
#ifndef DEBUG_MAX_TRACK
#define DEBUG_MAX_TRACK 4
#endif

#ifdef __AVR__
#define DEBUG_STR(s) (__extension__({ static const __flash char debug_fmt_[] = (s); &debug_fmt_[0]; }))
#else
#define DEBUG_STR(s) (s)
#endif

#ifdef NDEBUG_TEXT
#define DEBUG_PRINT(mod_, lvl_, fmt_, ...)                                                            \
    do {                                                                                                \
        if (0)                                                                                          \
            debug_printf(0, 0, "", ##__VA_ARGS__);                                                      \
    } while (0)
#else
#define DEBUG_PRINT(mod_, lvl_, fmt_, ...)                                                            \
    do {                                                                                                \
        if ((lvl_) <= DEBUG_MAX_##mod_ && (lvl_) <= settings.debug.level)                             \
            debug_printf(PB_DEBUG_MODULE_##mod_, (lvl_), DEBUG_STR(fmt_), ##__VA_ARGS__);               \
    } while (0)
#endif

/** Formats a message and queues it as a `debug_text` packet (dropped and counted if the link is full). */
void debug_printf(uint8_t module, uint8_t level, const HAL_FLASH char *fmt, ...);

/**
 * The formatter behind debug_printf, exposed for tests.
 * \return the number of characters written to out (at most `size`, never terminated).
 */
uint8_t debug_format(char *out, uint8_t size, const HAL_FLASH char *fmt, va_list ap);

#endif
