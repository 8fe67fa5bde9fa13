/**
 * \file failsafe.h
 * Link failsafe: when no sound frame arrived from the host (comm_host_seen_ms()) for
 * settings.link.failsafe_timeout_ms while the host drives the robot (movements, teleoperation), the motors
 * stop, every movement ends as failsafe and the mode becomes failsafe. Line following goes on if
 * settings.line_follow.autonomous says so.
 */
#ifndef FAILSAFE_H
#define FAILSAFE_H

void failsafe_init(void);
void failsafe_task(void);

#endif
