/**
 * \file failsafe.h
 * Link failsafe: when no sound frame arrived from the driving host (comm_host_seen_ms()) for
 * settings.link.failsafe_timeout_ms while the host drives the robot (movements, teleoperation), the motors
 * stop, every movement ends as failsafe and the mode becomes failsafe. Line following goes on if
 * settings.line_follow.autonomous says so.
 *
 * A driver that leaves on purpose says `goodbye` instead (registered here): the robot finishes or drops its
 * queue, as the driver chose, and stops what only a present host may drive (teleoperation; line following unless
 * autonomous); the failsafe guards no more until a host drives again.
 */
#ifndef FAILSAFE_H
#define FAILSAFE_H

/** Registers `goodbye` with comm. */
void failsafe_init(void);
void failsafe_task(void);

#endif
