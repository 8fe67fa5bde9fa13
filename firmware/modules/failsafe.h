/**
 * \file failsafe.h
 * Link failsafe: when no packet arrived from the host for settings.link.failsafe_timeout_ms while the host
 * drives the robot (movements, teleoperation), the motors stop and the mode becomes failsafe. Line
 * following goes on if settings.line_follow.autonomous says so.
 */
#ifndef FAILSAFE_H
#define FAILSAFE_H

void failsafe_init(void);
void failsafe_task(void);
/** A sound packet arrived from the host. */
void failsafe_host_seen(void);

#endif
