/**
 * \file comm.h
 * The protocol module (thesis 6.2): it serves up to COMM_LINKS host links at once (a phone and a computer, the
 * emulator's hosts), each with its own receive decoder, host session and duplicate history, through a link
 * driver that moves its bytes. Frames are checked and handed to the handler a module registered for their type
 * (as Crazyflie's crtp.c does: comm knows frames, not modules); the answer (ack or error) goes back on the
 * command's link. Packets to the host are framed and queued whole or not at all: state and debug text to every
 * link, answers to the link that asked.
 *
 *     static uint8_t on_stop(const pb_frame_t *cmd, uint16_t *detail);
 *     void locomotion_init(void) { ...; comm_register(PB_PKT_STOP, on_stop); }
 *
 * One host drives the robot, the others watch (docs/protocol.md, "One driver, watchers"): the rule lives here,
 * once, for every transport. A host packet that is not `watcher_ok` in the schema is refused (`not_driver`) unless
 * it comes from the driver's link; `set_role` asks to drive, watch or take over; every link is told who drives
 * when that changes (`driver`). The driver keeps the drive across a lost link for link.failsafe_timeout_ms (its
 * `hello_request` names its session on whichever link it returns); `goodbye` gives it up and ends the failsafe's
 * guard (the robot finishes or drops the queue, as the driver chose).
 *
 * Dependencies run one way: modules include comm.h, comm includes no module.
 */
#ifndef COMM_H
#define COMM_H

#include <stdbool.h>
#include <stdint.h>

#include "pb_protocol.h"
#include "protocol/pb_frame.h"

/** Host links served at once: a phone, a computer and a script, say. Each costs about 210 bytes of RAM. */
#ifndef COMM_LINKS
#define COMM_LINKS 3u
#endif
/** No link (comm_driver_link() when no host drives, or the driver's link is lost). */
#define COMM_NO_LINK 0xFFu
/** Accepted acked commands remembered per link (seq and frame CRC) to recognise retransmissions. */
#define COMM_SEQ_HISTORY 16u
/** Frame bytes a streamed packet encodes per comm_task(): more than the UART sends in a 1 ms tick. */
#define COMM_STREAM_CHUNK 12u
/** At most one `error` answer per this many ms to frames that cannot be read (bad CRC, framing). */
#define COMM_LINK_ERROR_INTERVAL_MS 100u
/** How long a driver whose link went silent keeps the drive while the failsafe is off (else: its timeout). */
#define COMM_DRIVER_HOLD_MS 1000u

/** What a handler returns instead of an error code when it will call comm_ack() itself, once its answer
 *  (several packets, or one that waits for something) is out. */
#define COMM_ANSWER_LATER 0xFFu

/** Why a link closed (comm_link_close()). Both keep the drive for a driver that may come back on another link:
 *  only its `goodbye` gives it up (a host that crashed closes its link cleanly too). */
#define COMM_LINK_CLOSED 0u
#define COMM_LINK_LOST 1u

/**
 * The driver of one kind of host link: how comm hands it bytes. A stream link (a UART, an RFCOMM channel, the
 * emulator's serial links) carries SLIP bytes; a framed link (an L2CAP channel) one frame per SDU, no SLIP.
 * Called from comm in the main loop only.
 */
typedef struct {
    bool framed;                                                  /**< one frame per write and per received unit */
    uint16_t (*tx_room)(uint8_t link);                            /**< bytes (framed: the largest whole frame) that fit now */
    void (*tx_write)(uint8_t link, const uint8_t *p, uint16_t n); /**< stream bytes, or exactly one frame; fits */
    /** Optional: copies up to `max` received stream bytes into `p` and returns how many, for comm_task() to take
     *  in every tick; NULL when the link's provider hands them over itself with comm_link_rx(). */
    uint8_t (*rx_take)(uint8_t link, uint8_t *p, uint8_t max);
    /** Optional (NULL: every byte goes through tx_write): the stream link's transmit ring of 256 bytes, indexed by
     *  one byte, into which comm SLIP-encodes a frame for this link alone without a copy, once tx_room said it fits.
     *  Returns the ring and sets `*pos` to where the next byte goes; tx_commit() publishes the bytes up to `pos`. */
    uint8_t *(*tx_ring)(uint8_t link, uint8_t *pos);
    void (*tx_commit)(uint8_t link, uint8_t pos);
} comm_link_driver_t;

/** The UART (a serial cable-replacement module, the emulator's first link) as a stream link. */
extern const comm_link_driver_t comm_uart_link;

/**
 * Executes a command whose type, direction, length, sequence number and sender (the driver, or a watcher for a
 * `watcher_ok` packet) are sound.
 * \param cmd the frame (payload: cmd->len bytes, within the type's size bounds; copy before casting)
 * \param detail set on refusal: what `error.detail` says (for PB_ERROR_CODE_BAD_ARGUMENT the payload offset of
 *        the first refused field)
 * \return PB_ERROR_CODE_NONE (comm acks acked commands), an error code (comm answers `error`), or
 *         COMM_ANSWER_LATER
 */
typedef uint8_t (*comm_handler_t)(const pb_frame_t *cmd, uint16_t *detail);

/** Forgets every handler, link, session and driver; call before the modules' inits, which register theirs. */
void comm_init(void);

/** The handler of host packets of `type` (one per type; a later call replaces it). The handler of `goodbye`
 *  runs for the driver's goodbye only (it decides what becomes of the queue); a watcher's changes nothing. */
void comm_register(uint8_t type, comm_handler_t handler);

/** A host connected on `link` (0 .. COMM_LINKS-1): it watches until its `set_role`. Opening an open link starts
 *  its receive decoder afresh. */
void comm_link_open(uint8_t link, const comm_link_driver_t *drv);

/** The host of `link` is gone (COMM_LINK_CLOSED or COMM_LINK_LOST): nothing more is sent to it. */
void comm_link_close(uint8_t link, uint8_t why);

/** Received on `link`: stream bytes, or one whole frame on a framed link. */
void comm_link_rx(uint8_t link, const uint8_t *p, uint16_t n);

/** Takes what the links received, dispatches complete frames, continues a streamed packet and the answers,
 *  tells links who drives, and frees the drive of a driver silent for too long. */
void comm_task(void);

/** Checks and dispatches one unSLIPped frame received on `link` (what comm_link_rx() does with each frame;
 *  exposed for the fuzzer). */
void comm_handle_frame(uint8_t link, const uint8_t *frame, uint16_t n);

/** Queues a packet to every link with the robot's own rolling sequence number.
 *  \return false (and counts robot_state.errors.tx_dropped per link) when no link had room. */
bool comm_send(uint8_t type, const void *payload, uint8_t len);

/** Queues a packet to every link that is encoded over the next ticks: its payload is copied now (one instant),
 *  then the CRC and SLIP encoding go out COMM_STREAM_CHUNK bytes per comm_task() (the UART needs about 8 ms for
 *  a full state anyway). Payloads up to sizeof(pb_robot_state_t); a link without room for the worst case is
 *  skipped (and counted in tx_dropped). \return false if no link took it. */
bool comm_send_streamed(uint8_t type, const void *payload, uint8_t len);

/** Queues a packet with the robot's rolling sequence number if it fits now and no streamed packet is being
 *  encoded (after a few refusals it completes that one first): to the link being answered (inside a handler or an
 *  answer step), else to every link, of which the driver's must have room.
 *  \return false when not queued: nothing is counted, the caller offers it again in a later tick (answers that
 *  must not be lost: settings chunks, movement results, IR payloads heard). */
bool comm_offer(uint8_t type, const void *payload, uint8_t len);

/** Continues an answer of several packets (or one that waits): comm_task() calls `step` once per tick until it
 *  returns true (the answer and its comm_ack() are out), with the asking link as the one being answered. A
 *  handler that starts one returns COMM_ANSWER_LATER. One answer per `step` function: starting it again while it
 *  runs for the same link just keeps it running; another link's request for it waits until it is done (that
 *  host asks again after its ack timeout). */
typedef bool (*comm_answer_step_t)(void);
void comm_answer_later(comm_answer_step_t step);

/** Acknowledges a command whose handler returned COMM_ANSWER_LATER, as comm_offer() queues, on the link
 *  being answered. \return false when not queued (nothing counted: call again in a later tick). */
bool comm_ack(uint8_t type, uint8_t seq);

/** Sends `hello` to every link (at reset: session_resumed 0, sequence number 0). */
void comm_send_hello(void);

/** \return robot time (ms) of the driver's last frame with a sound CRC (the link failsafe's clock); the time now
 *  while nothing is guarded: before any host drove, and after the driver's `goodbye`. */
uint32_t comm_host_seen_ms(void);

/** \return the link of the host that drives, or COMM_NO_LINK (nobody drives, or the driver's link is lost). */
uint8_t comm_driver_link(void);

#endif
