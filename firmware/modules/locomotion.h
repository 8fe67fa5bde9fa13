/**
 * \file locomotion.h
 * Locomotion (thesis 6.5, 11.4): a queue of movements (straight, rotate, arc) executed in order by two
 * chained controllers - a robot speed PID producing PWM and a wheel balance controller keeping the
 * left:right distance ratio - along a three-segment speed profile (accelerate, cruise, brake). Also
 * teleoperation and line following set points through per-wheel speed PIDs. Commands return at once.
 * Commands take floats (as on the wire) and are converted once when queued; the control step is fixed
 * point (um, um/s, Q14 shares, PWM in Q16 permille).
 */
#ifndef LOCOMOTION_H
#define LOCOMOTION_H

#include <stdbool.h>
#include <stdint.h>

#define LOCOMOTION_QUEUE_SIZE 16u
/** Fastest speed a command may ask for, m/s. */
#define LOCOMOTION_MAX_SPEED 2.0f

void locomotion_init(void);
/** One control step; call once per main loop tick. */
void locomotion_task(void);

/** Queue movements. \return PB_ERROR_CODE_NONE, _QUEUE_FULL or _BAD_ARGUMENT (id 0, speed not in
 *  (0, LOCOMOTION_MAX_SPEED], non-finite or absurd distance, angle or radius: over 100 m, 36000 degrees,
 *  or an arc with a wheel distance over 1000 m). */
uint8_t locomotion_straight(uint16_t id, float distance_m, float speed_mps);
uint8_t locomotion_rotate(uint16_t id, float angle_deg, float speed_mps);
uint8_t locomotion_arc(uint16_t id, float radius_m, float angle_deg, float speed_mps);

/** Clears the queue and stops: at once, or braking along the profile. Ends teleoperation and line following. */
void locomotion_stop(bool immediate);

/** Teleoperation: holds these wheel speeds. \return PB_ERROR_CODE_NONE or _BAD_ARGUMENT. */
uint8_t locomotion_teleop(float left_mps, float right_mps);

/** Line following: enters line follow mode (clears the queue). */
void locomotion_line_follow_begin(void);
/** Line following: the wheel speed set points of this tick, um/s. */
void locomotion_line_follow_set(int32_t left_umps, int32_t right_umps);

/** \return the coasting time learnt so far, s: movements cut the motors when the remaining distance is
 *  within speed x this time. */
float locomotion_coast_s(void);

/** The link failsafe: motors off, queue cleared, mode failsafe. */
void locomotion_failsafe(void);

#endif
