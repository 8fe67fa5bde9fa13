/**
 * \file track.h
 * Multiple robots on a track (thesis A.3), decentralized: the behaviour runs here, in every robot, and needs no
 * host once started. Each robot follows the line at settings.track.speed_mps and keeps its distance from the
 * robot ahead by IR proximity (the front receiver's robot and distance class: mid slows down to half speed,
 * near waits; one that drops out of hearing may only have turned away, and is taken to be there for a while).
 * Robots that come close identify each other by their beacons and greet each other with an IR
 * message (robot_state.track.met_id says whom). One robot holds a token (created by
 * settings.track.token_origin_id at its first start); the holder shows it (robot_state.track.token, LED
 * `token`: the thesis's orange light) and drives settings.track.token_boost_percent faster until it has
 * caught up with the robot ahead and handed the token on. An obstacle on the line (the front receiver hears
 * its own reflection, no robot close) is driven round on the right: turn out, pass it, turn back, find the
 * line, line up with it. A robot that has lost the line (it drifted off, or a detour or a turn did not find it)
 * searches for it (status lost): it sweeps 45 degrees either side turning on the spot and backs up 40 mm (unless
 * something is close behind), four rounds at most, then stands still until the line is under its sensor again.
 *
 * IR messages (payloads of proximity's beacons, 3 bytes: kind, addressee id, hop): GREET ("I see you", hop 0),
 * and the token's two-phase hand-over OFFER, ACCEPT, GIVE, TAKEN (hop = the token's hand-overs so far + 1), which
 * lets at most one robot hold the token at any instant and never loses it: see track.c.
 *
 * The host starts, stops and reverses the behaviour with the `track` command (reverse = turn round on the
 * spot and find the line again) and sets the speed in settings.track. It runs in locomotion's track mode: any
 * other motion command (stop, line_follow, wheel_speeds, a movement) ends it. The link failsafe does not: the
 * behaviour is the robot's own, not host-driven, and goes on without a host (as line following does with
 * line_follow.autonomous = 1). Registers `track` with comm and listens to proximity's payloads.
 */
#ifndef TRACK_H
#define TRACK_H

#include <stdint.h>

#define TRACK_MSG_GREET 0xA1u
#define TRACK_MSG_OFFER 0xA2u
#define TRACK_MSG_ACCEPT 0xA3u
#define TRACK_MSG_GIVE 0xA4u
#define TRACK_MSG_TAKEN 0xA5u
#define TRACK_MSG_LEN 3u

/** Call after proximity_init(): registers the `track` command and the payload listener. */
void track_init(void);
/** One step of the behaviour; call once per main loop tick, after proximity_task(). */
void track_task(void);
/** The `track` command. \param action PB_TRACK_ACTION_* \return PB_ERROR_CODE_NONE or _BAD_ARGUMENT */
uint8_t track_command(uint8_t action);

#endif
