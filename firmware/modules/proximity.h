/**
 * \file proximity.h
 * IR proximity (thesis 7): every settings.proximity.beacon_period_ms the robot sends a beacon - one
 * message from each of its four LEDs - carrying its id, the LED and the power; successive beacons cycle
 * the power through 100, 50 and 25 % of settings.proximity.ir_power, so a receiver tells a distance class
 * from the lowest power it still hears. A robot heard is reported per receiver (front, rear) with its id,
 * the LED it was heard from (its orientation) and the distance class, held for settings.proximity.hold_ms;
 * hearing its own id means an obstacle reflects the beacon. A payload from `ir_send` goes out with the
 * next beacon; payloads heard from others are forwarded to the host as `ir_received`, except those a module
 * that talks to other robots (the track behaviour) takes as its own.
 */
#ifndef PROXIMITY_H
#define PROXIMITY_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal.h"

/** The pause between the messages of a beacon: each message takes its time on the IR link (hal_ir_message_us():
 *  23 ms without payload on the robot), then the LEDs rest this long. A beacon that outlasts beacon_period_ms
 *  delays the next one to the following period; a sighting is held at least a cycle of the beacon powers. */
#define PROXIMITY_MSG_GAP_US 1000u

/** Starts the beacons and registers `ir_send` with comm. */
void proximity_init(void);
/** Evaluates heard messages into robot_state.proximity and forwards payloads. */
void proximity_task(void);
/** Queues a payload for the next beacon. \return PB_ERROR_CODE_NONE or _BAD_ARGUMENT (power not 1..100,
 *  more than 8 bytes) or _BUSY (the previous payload is not sent yet). */
uint8_t proximity_send_payload(uint8_t power, const uint8_t *data, uint8_t len);

/** What a module that talks to other robots over IR gets: every payload another robot sent, heard on `side`
 *  (PB_SIDE_*), called from proximity_task(). \return true when the payload is the module's own conversation:
 *  then it is not forwarded to the host as `ir_received` (robots talk to each other several times a second). */
typedef bool (*proximity_payload_cb_t)(uint8_t side, const hal_ir_msg_t *msg);

/** Sets the one payload listener (call after proximity_init(); NULL: none). */
void proximity_on_payload(proximity_payload_cb_t cb);

/** Distance class of a message heard at `power` percent. */
uint8_t proximity_distance_class(uint8_t power);

#endif
