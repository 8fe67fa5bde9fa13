/**
 * \file hci.h
 * The Host Controller Interface over H4 (Bluetooth Core, Vol 4, Part E): resets and initialises the controller
 * (buffer sizes, address, local name `PocketBot-<id>`, class of device, Secure Simple Pairing, page and inquiry
 * scan), accepts incoming connections up to BT_LINKS, pairs "just works" with the link keys kept in EEPROM, sends
 * commands within the controller's command credits and ACL data within its buffer count
 * (Number_Of_Completed_Packets), and supervises the wire: an H4 error, a packet cut off, a command unanswered (or no
 * command credit) for HCI_COMMAND_TIMEOUT_MS or a hardware error event drop every link and reset the controller
 * (robot_state.errors.bt_*). A keep-alive command every HCI_KEEPALIVE_MS (Read_Scan_Enable) finds a controller
 * that went quiet, and one power-cycled behind the stack's back (its scans are off): that one is reset too.
 *
 * Links are numbered 0..BT_LINKS-1; the layer above (L2CAP) implements the hooks at the end of this header.
 */
#ifndef HCI_H
#define HCI_H

#include <stdbool.h>
#include <stdint.h>

#include "bluetooth/bt_config.h"
#include "hal/hal.h"

#define HCI_COMMAND_TIMEOUT_MS 1000u
#define HCI_KEEPALIVE_MS 2000u
/** Received bytes read per hci_task(): the wire brings under 12 per ms, and the ring holds 256. */
#define HCI_RX_BUDGET 16u
/** Transmit ring bytes and controller buffers that data (hci_acl_can_send(..., true)) leaves for answers. */
#define HCI_TX_RESERVE 48u

/** Link keys remembered, in EEPROM from HCI_KEYS_EEPROM_ADDR (one 32-byte page each; the settings image is
 *  below). The oldest is replaced when all are used. */
#define HCI_KEYS 8u
#define HCI_KEYS_EEPROM_ADDR 0x0400u

/** Disconnection reasons (HCI error codes) the stack reports upwards. */
#define HCI_REASON_TIMEOUT 0x08u      /**< supervision timeout: the link was lost */
#define HCI_REASON_REMOTE_USER 0x13u  /**< the peer closed the link */
#define HCI_REASON_RESET 0x1Fu        /**< the controller was reset (unspecified error) */

/** Starts the controller's reset and initialisation. */
void hci_init(void);

/** Reads the wire (at most HCI_RX_BUDGET bytes), answers the controller, continues the initialisation, sends
 *  queued commands, checks timeouts. */
void hci_task(void);

/** \return true once the controller is initialised and connectable. */
bool hci_ready(void);

/** \return the controller's address (little-endian, as on the wire), all zero before it was read. */
const uint8_t *hci_bd_addr(void);

/** \return the peer address of a connected link, or NULL. */
const uint8_t *hci_link_addr(uint8_t link);

/* ---- ACL data out: one L2CAP PDU, fragmented to the controller's buffer size ---- */

/**
 * \return true when a PDU of `len` bytes (L2CAP header included) can be written now: no other PDU is being written,
 *         room in the transmit ring for it and its fragments' headers, and a controller buffer for each fragment.
 *         Data (`data` true) also leaves HCI_TX_RESERVE bytes and one buffer for answers.
 */
bool hci_acl_can_send(uint16_t len, bool data);
/** Starts a PDU of `len` bytes on `link` (after hci_acl_can_send()); then exactly `len` bytes of hci_acl_put*(),
 *  which may come over several ticks (each fragment goes to the UART when it is complete), then hci_acl_end().
 *  Meanwhile nothing else is written: commands and other PDUs wait. */
void hci_acl_begin(uint8_t link, uint16_t len);
void hci_acl_put(const uint8_t *p, uint16_t n);
void hci_acl_put_byte(uint8_t b);
void hci_acl_put_u16(uint16_t v);
/** Publishes the PDU to the UART. */
void hci_acl_end(void);
/** Gives up the PDU being written (its link went away): what was not published yet is never sent. */
void hci_acl_abort(void);

/* ---- hooks implemented by the layer above (l2cap.c) ---- */

/** A link is connected. */
void l2cap_link_up(uint8_t link);
/** A link is gone (`reason`: an HCI error code, HCI_REASON_RESET when the controller was reset). */
void l2cap_link_down(uint8_t link, uint8_t reason);
/** \return where the `len` payload bytes of an ACL fragment of `link` go (`start`: it starts a PDU), or NULL to
 *  drop them (L2CAP counts what it drops). */
uint8_t *l2cap_rx_fragment(uint8_t link, bool start, uint16_t len);
/** The fragment announced last is in place. */
void l2cap_rx_fragment_done(uint8_t link);

#endif
