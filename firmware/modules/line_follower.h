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

void line_follower_init(void);
void line_follower_task(void);
/** Handles the `line_follow` command. \return PB_ERROR_CODE_NONE or PB_ERROR_CODE_BAD_ARGUMENT. */
uint8_t line_follower_command(uint8_t run, uint8_t colour_mode, float speed_mps);
/** Stops following (the caller decides what the motors do). */
void line_follower_stop(void);

#endif
