/**
 * \file robot.h
 * The robot's firmware on the XMEGA model: power it on and run its main loop in simulated time, as main.c does.
 */
#ifndef ROBOT_H
#define ROBOT_H

#include <stdint.h>

#include "pb_protocol.h"
#include "xmega_model.h"

/** Powers the model on with a robot's surroundings (battery, accelerometer at rest, a white floor under the
 *  colour sensor, 25 C), then boots the firmware (app_init()). */
void robot_boot(void);
/** Starts the firmware again after the CPU restarted (app_init() on the model as the restart left it). */
void robot_restart(void);
/** Runs the main loop (app_poll(), then app_idle() when nothing is due, as main.c) until `t`.
 *  \return XM_RESTART_NONE, or what restarted the CPU: the run ends there */
uint8_t robot_run_until(uint64_t t);
uint8_t robot_run_us(uint64_t us);
/** Main loop ticks run since boot. */
uint32_t robot_ticks(void);
/** When the n-th tick (0-based, one of the last ROBOT_TICK_TIMES) ended (cycles), else 0. */
#define ROBOT_TICK_TIMES 64u
uint64_t robot_tick_time(uint32_t n);

/** Packets the robot sent on the host link (USARTC0) since the last robot_frames_clear(): how many of a type,
 *  and the first ROBOT_FRAMES_KEPT of them. */
uint32_t robot_frames_of_type(uint8_t type);
#define ROBOT_FRAMES_KEPT 256u
typedef struct {
    uint8_t type, len;
    uint8_t payload[PB_MAX_PAYLOAD];
} robot_frame_t;
/** \return the n-th (0-based) kept packet of `type`, or NULL */
const robot_frame_t *robot_frame(uint8_t type, uint32_t n);
void robot_frames_clear(void);

/** A byte's frame on the robots' IR link (cycles): 11 bits (start bit, 8 data bits, the line code's bit, stop bit)
 *  at 2400 Bd, as another robot sends them. */
#define ROBOT_IR_FRAME ((uint64_t)(11.0 * (double)XM_HZ / 2400.0))

#endif
