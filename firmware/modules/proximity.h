/**
 * \file proximity.h
 * IR proximity (thesis 7): every settings.proximity.beacon_period_ms the robot sends a beacon - one
 * message from each of its four LEDs - carrying its id, the LED and the power; successive beacons cycle
 * the power through 100, 50 and 25 % of settings.proximity.ir_power, so a receiver tells a distance class
 * from the lowest power it still hears. A robot heard is reported per receiver (front, rear) with its id,
 * the LED it was heard from (its orientation) and the distance class, held for settings.proximity.hold_ms;
 * hearing its own id means an obstacle reflects the beacon. A payload from `ir_send` goes out with the
 * next beacon; payloads heard from others are forwarded to the host as `ir_received`.
 */
#ifndef PROXIMITY_H
#define PROXIMITY_H

#include <stdint.h>

/** Time between the messages of one beacon (the transmitter's message length on the robot). */
#define PROXIMITY_MSG_SPACING_US 2000u
#define PROXIMITY_FLAG_OBSTACLE 0x01u
#define PROXIMITY_FLAG_ROBOT 0x02u

void proximity_init(void);
/** Evaluates heard messages into robot_state.proximity and forwards payloads. */
void proximity_task(void);
/** Queues a payload for the next beacon. \return PB_ERROR_CODE_NONE or _BAD_ARGUMENT (power not 1..100,
 *  more than 8 bytes) or _BUSY (the previous payload is not sent yet). */
uint8_t proximity_send_payload(uint8_t power, const uint8_t *data, uint8_t len);

/** Distance class of a message heard at `power` percent. */
uint8_t proximity_distance_class(uint8_t power);

#endif
