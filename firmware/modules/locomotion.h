/**
 * \file locomotion.h
 * Locomotion (thesis 6.5, 11.4): a queue of movements (straight, rotate, arc) executed in order by two
 * chained controllers - a robot speed PID producing PWM and a wheel balance controller keeping the
 * left:right distance ratio - along a three-segment speed profile (accelerate, cruise, brake). Also the
 * per-wheel speed PIDs that hold wheel speed set points for teleoperation and line following. Commands
 * return at once; they take the wire's structs and floats, converted once when queued; the control step is
 * fixed point (um, um/s, Q14 shares, PWM in Q16 permille).
 *
 * Every queued movement ends with an outcome (finished, stopped, failsafe, dropped) and how much it did,
 * recorded in the movement log (modules/movement_log.h); a movement after which the robot comes to rest is
 * recorded once the wheels stand still (at most LOCOMOTION_SETTLE_MS), so that its coasting counts.
 * Registers move_straight, move_rotate, move_arc, stop and wheel_speeds with comm.
 */
#ifndef LOCOMOTION_H
#define LOCOMOTION_H

#include <stdbool.h>
#include <stdint.h>

#include "pb_protocol.h"

#define LOCOMOTION_QUEUE_SIZE 16u
/** Fastest speed a command may ask for, m/s. */
#define LOCOMOTION_MAX_SPEED 2.0f
/** Longest wait for the wheels to stand still before a movement's result is recorded, ms. */
#define LOCOMOTION_SETTLE_MS 300u

void locomotion_init(void);
/** One control step; call once per main loop tick. */
void locomotion_task(void);

/** Queue movements. \param detail on refusal with PB_ERROR_CODE_BAD_ARGUMENT: the payload offset of the first
 *  refused field (id 0; speed not in (0, LOCOMOTION_MAX_SPEED]; a non-finite or absurd distance, angle or
 *  radius: over 100 m, 36000 degrees; an arc with a wheel distance over 1000 m: the radius)
 *  \return PB_ERROR_CODE_NONE, _QUEUE_FULL or _BAD_ARGUMENT */
uint8_t locomotion_straight(const pb_move_straight_t *c, uint16_t *detail);
uint8_t locomotion_rotate(const pb_move_rotate_t *c, uint16_t *detail);
uint8_t locomotion_arc(const pb_move_arc_t *c, uint16_t *detail);

/** Stops: the running movement brakes along the profile (at once when `immediate`) and ends as stopped;
 *  queued ones are dropped. Ends teleoperation and line following (their set points). */
void locomotion_stop(bool immediate);

/** Teleoperation: holds these wheel speeds (ends a running movement as stopped, drops queued ones).
 *  \return PB_ERROR_CODE_NONE or _BAD_ARGUMENT (detail: offset of the refused speed). */
uint8_t locomotion_teleop(const pb_wheel_speeds_t *c, uint16_t *detail);

/** Line following takes the motors: line follow mode, set points 0 (ends a running movement as stopped,
 *  drops queued ones). */
void locomotion_line_follow_begin(void);

/** The track behaviour takes the motors: track mode, set points 0 (ends a running movement as stopped, drops
 *  queued ones). The link failsafe leaves this mode alone: the behaviour is the robot's own. */
void locomotion_track_begin(void);

/** The wheel speed set points the per-wheel PIDs hold in teleoperation, line following and track mode, um/s. */
void locomotion_wheel_setpoints(int32_t left_umps, int32_t right_umps);

/** \return the coasting time learnt so far, s: movements cut the motors when the remaining distance is
 *  within speed x this time. */
float locomotion_coast_s(void);

/** The link failsafe: motors off, the running movement and every queued one end as failsafe, mode failsafe. */
void locomotion_failsafe(void);

#endif
