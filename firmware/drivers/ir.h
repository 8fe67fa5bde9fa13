/**
 * \file ir.h
 * IR transceiver driver: messages heard by the front and rear receivers are queued by the interrupt and
 * taken by the proximity module; messages are sent through the HAL transmitter.
 */
#ifndef IR_H
#define IR_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal.h"

#define IR_RX_QUEUE 8u

void ir_init(void);
/** Takes the oldest heard message. \return false when none waits. */
bool ir_receive(uint8_t *side, hal_ir_msg_t *msg);
/** Sends a message. \return false if the transmitter is busy. */
bool ir_transmit(const hal_ir_msg_t *msg);

#endif
