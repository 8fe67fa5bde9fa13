/**
 * \file h4.h
 * The H4 UART transport of HCI (Bluetooth Core, Vol 4, Part A): a packet type byte, then a command, ACL or event
 * packet. The reader takes the bytes the USART interrupt put into the driver's receive ring and runs a
 * type/header/payload state machine over them; the writer puts whole packets into the transmit ring and publishes
 * each to the interrupt when it is complete.
 *
 * H4 cannot resynchronise: a packet type that is neither event nor ACL, an ACL packet longer than the robot said it
 * takes (Host_Buffer_Size), or a packet that stops in the middle is an error the layer above answers by resetting
 * the controller (hci.c).
 */
#ifndef H4_H
#define H4_H

#include <stdbool.h>
#include <stdint.h>

#include "bluetooth/bt_config.h"
#include "hal/hal.h"

#define H4_COMMAND 0x01u
#define H4_ACL 0x02u
#define H4_EVENT 0x04u

/** Event parameter bytes kept: every event the stack reads fits; longer ones are read to their end, flagged. */
#define H4_EVENT_MAX 40u
/** A packet whose next byte is this late (ms) was cut off on the wire. */
#define H4_PACKET_TIMEOUT_MS 20u

typedef enum {
    H4_NONE = 0,   /**< the receive ring is empty, or the byte budget is spent */
    H4_EVENT_READY, /**< a whole event is in h4_event */
    H4_ACL_HEADER, /**< an ACL header was read (h4_acl): call h4_acl_into() before reading on */
    H4_ACL_READY,  /**< the payload of that ACL packet is complete */
    H4_ERROR       /**< bad packet type or ACL length: the wire is out of step (h4_flush() before going on) */
} h4_result_t;

/** The last event read. */
typedef struct {
    uint8_t code;
    uint8_t len;       /**< parameter bytes kept in params (at most H4_EVENT_MAX) */
    uint8_t truncated; /**< 1 if the event had more parameters than were kept */
    uint8_t params[H4_EVENT_MAX];
} h4_event_t;
extern h4_event_t h4_event;

/** The header of the ACL packet being read. */
typedef struct {
    uint16_t handle; /**< connection handle, 12 bits */
    uint8_t pb;      /**< packet boundary flag: 2 (or 0) starts an L2CAP PDU, 1 continues one */
    uint16_t len;    /**< payload bytes */
} h4_acl_t;
extern h4_acl_t h4_acl;

/** Forgets any packet in progress (the bytes still in the receive ring stay there). */
void h4_init(void);

/**
 * Reads received bytes until something is complete or `*budget` bytes were read (it counts down).
 * \return what was read; H4_NONE when the ring is empty or the budget spent
 */
h4_result_t h4_read(uint8_t *budget);

/** Where the payload of the ACL packet just announced (H4_ACL_HEADER) goes: `dst` has room for h4_acl.len
 *  bytes, or is NULL to skip them. */
void h4_acl_into(uint8_t *dst);

/** \return true when a packet started more than H4_PACKET_TIMEOUT_MS ago has stopped arriving (a lost byte). */
bool h4_stalled(uint32_t now_ms);

/** Drops every received byte waiting and any packet in progress. \return true if there were bytes to drop. */
bool h4_flush(void);

/* ---- writer ---- */

/** \return bytes that can be written into the transmit ring now. */
uint16_t h4_tx_room(void);
/** \return bytes written and published but not yet sent by the USART. */
uint8_t h4_tx_backlog(void);

/** Starts writing; the caller checked h4_tx_room() for everything it will write before h4_tx_end(). */
void h4_tx_begin(void);
void h4_tx_byte(uint8_t b);
void h4_tx_bytes(const uint8_t *p, uint16_t n);
void h4_tx_zeros(uint16_t n);
/** Publishes what was written to the USART interrupt (at packet boundaries) and starts it; the write may go on. */
void h4_tx_end(void);
/** \return true while received bytes wait in the ring or a packet is being read. */
bool h4_rx_busy(void);

/** Writes an HCI command packet (h4_tx_begin() .. h4_tx_end()); the caller checked the room for 4 + len. */
void h4_command(uint16_t opcode, const uint8_t *params, uint8_t len);

#endif
