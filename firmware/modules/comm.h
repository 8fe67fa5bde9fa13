/**
 * \file comm.h
 * The protocol module (thesis 6.2): SLIP frames from the host link are checked and handed to the handler a
 * module registered for their type (as Crazyflie's crtp.c does: comm knows frames, not modules); the
 * answer (ack or error) goes back here. Host sessions and the duplicate history live here too. Packets to
 * the host are framed and queued whole or not at all.
 *
 *     static uint8_t on_stop(const pb_frame_t *cmd, uint16_t *detail);
 *     void locomotion_init(void) { ...; comm_register(PB_PKT_STOP, on_stop); }
 *
 * Dependencies run one way: modules include comm.h, comm includes no module.
 */
#ifndef COMM_H
#define COMM_H

#include <stdbool.h>
#include <stdint.h>

#include "pb_protocol.h"
#include "protocol/pb_frame.h"

/** Accepted acked commands remembered (seq and frame CRC) to recognise retransmissions. */
#define COMM_SEQ_HISTORY 16u
/** Frame bytes a streamed packet encodes per comm_task(): more than the UART sends in a 1 ms tick. */
#define COMM_STREAM_CHUNK 12u
/** At most one `error` answer per this many ms to frames that cannot be read (bad CRC, framing). */
#define COMM_LINK_ERROR_INTERVAL_MS 100u

/** What a handler returns instead of an error code when it will call comm_ack() itself, once its answer
 *  (several packets, or one that waits for something) is out. */
#define COMM_ANSWER_LATER 0xFFu

/**
 * Executes a command whose type, direction, length and sequence number are sound.
 * \param cmd the frame (payload: cmd->len bytes, within the type's size bounds; copy before casting)
 * \param detail set on refusal: what `error.detail` says (for PB_ERROR_CODE_BAD_ARGUMENT the payload offset of
 *        the first refused field)
 * \return PB_ERROR_CODE_NONE (comm acks acked commands), an error code (comm answers `error`), or
 *         COMM_ANSWER_LATER
 */
typedef uint8_t (*comm_handler_t)(const pb_frame_t *cmd, uint16_t *detail);

/** Forgets every handler and the session; call before the modules' inits, which register theirs. */
void comm_init(void);

/** The handler of host packets of `type` (one per type; a later call replaces it). */
void comm_register(uint8_t type, comm_handler_t handler);

/** Reads what the link received, dispatches complete frames, and continues a streamed packet. */
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

/** Queues a packet with the robot's rolling sequence number if the transmit buffer has room for it now and
 *  no streamed packet is being encoded (after a few refusals it completes that one first).
 *  \return false when not queued: nothing is counted, the caller offers it again in a later tick (answers that
 *  must not be lost: settings chunks, movement results, IR payloads heard). */
bool comm_offer(uint8_t type, const void *payload, uint8_t len);

/** Continues an answer of several packets (or one that waits): comm_task() calls `step` once per tick until it
 *  returns true (the answer and its comm_ack() are out). A handler that starts one returns COMM_ANSWER_LATER.
 *  One answer per `step` function: starting it again while it runs just keeps it running. */
typedef bool (*comm_answer_step_t)(void);
void comm_answer_later(comm_answer_step_t step);

/** Acknowledges a command whose handler returned COMM_ANSWER_LATER, as comm_offer() queues.
 *  \return false when not queued (nothing counted: call again in a later tick). */
bool comm_ack(uint8_t type, uint8_t seq);

/** Sends `hello` (session_resumed 0 unless in answer to a hello_request of the session served). */
void comm_send_hello(void);

/** Sends an `error` packet. */
void comm_send_error(uint8_t code, uint8_t type, uint8_t seq, uint16_t detail);

/** \return robot time (ms) of the last frame with a sound CRC from the host (the link failsafe's clock). */
uint32_t comm_host_seen_ms(void);

#endif
