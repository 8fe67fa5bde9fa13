/**
 * \file line_follower.h
 * Line following (thesis 11.2): a PD controller (Ki available) on the line position gives the difference
 * of the wheel speeds; the per-wheel speed PIDs of locomotion hold them. With colour segments, red tape
 * slows down and blue tape speeds up. A line lost for settings.line_follow.lost_timeout_ms stops the robot
 * (status lost) until the line is seen again.
 */
#ifndef LINE_FOLLOWER_H
#define LINE_FOLLOWER_H

#include <stdint.h>

#include "pb_protocol.h"

/** Registers `line_follow` with comm. */
void line_follower_init(void);
void line_follower_task(void);
/** The `line_follow` command. \return PB_ERROR_CODE_NONE or PB_ERROR_CODE_BAD_ARGUMENT (detail: the payload
 *  offset of the refused field). */
uint8_t line_follower_command(const pb_line_follow_t *c, uint16_t *detail);
/** Stops following (the caller decides what the motors do). */
void line_follower_stop(void);

/** One step of the line PD at cruise speed `v_umps` (um/s): sets the wheel set points. For a module that
 *  follows the line its own way (the track behaviour); call line_follower_steer_reset() when it starts. */
void line_follower_steer(int32_t v_umps);
void line_follower_steer_reset(void);

#endif
