/**
 * \file comm.h
 * The protocol module: SLIP frames from the host link are checked, dispatched to the modules and answered
 * (ack or error); packets to the host are framed and queued whole or not at all.
 */
#ifndef COMM_H
#define COMM_H

#include <stdbool.h>
#include <stdint.h>

#include "pb_protocol.h"

/** Number of recent (type, seq) pairs of accepted commands remembered to recognise retransmissions. */
#define COMM_SEQ_HISTORY 16u
/** Frame bytes a streamed packet encodes per comm_task(): more than the UART sends in a 1 ms tick. */
#define COMM_STREAM_CHUNK 12u

void comm_init(void);

/** Reads what the link received, dispatches complete frames, and continues multi-packet answers. */
void comm_task(void);

/** Feeds one received byte (what comm_task() does with each byte; exposed for tests and the fuzzer). */
void comm_rx_byte(uint8_t byte);

/** Checks and dispatches one unSLIPped frame. */
void comm_handle_frame(const uint8_t *frame, uint16_t n);

/** Queues a packet with the robot's own rolling sequence number.
 *  \return false (and counts robot_state.errors.tx_dropped) when the transmit buffer lacks room. */
bool comm_send(uint8_t type, const void *payload, uint8_t len);

/** Queues a packet that is encoded over the next ticks: its payload is copied now (one instant), then the
 *  CRC and SLIP encoding go into the transmit buffer COMM_STREAM_CHUNK bytes per comm_task() (the UART needs
 *  about 8 ms for a full state anyway). Payloads up to sizeof(pb_robot_state_t); without room for the
 *  worst case it is sent at once like comm_send(). \return false (and counts tx_dropped) if not queued. */
bool comm_send_streamed(uint8_t type, const void *payload, uint8_t len);

/** Queues a packet with a given sequence number (acks and errors carry the command's). */
bool comm_send_seq(uint8_t type, uint8_t seq, const void *payload, uint8_t len);

/** Sends `hello`. */
void comm_send_hello(void);

/** Sends an `error` packet. */
void comm_send_error(uint8_t code, uint8_t type, uint8_t seq, uint16_t detail);

#endif
