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
/** The oldest heard message, left in the queue (no copy). \return NULL when none waits. */
const hal_ir_msg_t *ir_peek(uint8_t *side);
/** Drops the message ir_peek() returned. */
void ir_pop(void);
/** Sends a message. \return false if the transmitter is busy. */
bool ir_transmit(const hal_ir_msg_t *msg);

#endif
