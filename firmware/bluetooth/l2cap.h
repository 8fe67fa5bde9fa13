/**
 * \file l2cap.h
 * L2CAP in basic mode (Bluetooth Core, Vol 3, Part A) over the links of hci.h: reassembles each link's PDUs from
 * ACL fragments into one buffer of BT_L2CAP_MTU bytes, answers the signalling channel (connection, configuration
 * with the MTU, disconnection, echo, information), and serves three dynamic channels per link, one per service:
 * SDP (PSM 1), RFCOMM (PSM 3) and the robot's framed service (BT_PSM_FRAMED). One data channel per link: the
 * framed service is refused while RFCOMM's data channel is open (l2cap_set_stream()), and RFCOMM refuses its data
 * channel while the framed one is connected. Enhanced retransmission and streaming modes are refused in configuration, which
 * leaves basic mode.
 *
 * A received PDU whose answer finds no room in the transmit ring stays in its buffer and is handled again by
 * l2cap_task(); what arrives for that link meanwhile is dropped and counted (robot_state.errors.bt_dropped).
 * The services implement the hooks at the end of this header.
 */
#ifndef L2CAP_H
#define L2CAP_H

#include <stdbool.h>
#include <stdint.h>

#include "bluetooth/bt_config.h"

#define L2CAP_PSM_SDP 0x0001u
#define L2CAP_PSM_RFCOMM 0x0003u
/** The MTU a peer that names none receives (and so the most the robot sends it). */
#define L2CAP_DEFAULT_MTU 672u

/** The services, one channel each per link. */
enum { L2CAP_SDP = 0, L2CAP_RFCOMM, L2CAP_FRAMED, L2CAP_SERVICES };

void l2cap_init(void);

/** Handles again a PDU whose answer found no room, and sends configuration requests that waited. */
void l2cap_task(void);

/** \return true when `service`'s channel on `link` is open and a PDU with `len` payload bytes can go now (within the
 *  peer's MTU; `data`: leaving room for answers, see hci_acl_can_send()). */
bool l2cap_can_send(uint8_t link, uint8_t service, uint16_t len, bool data);

/** \return true while `service`'s channel on `link` is connected (configuring or open). */
bool l2cap_connected(uint8_t link, uint8_t service);

/** RFCOMM's data channel on `link` opened or closed: the framed service is refused while it is open. */
void l2cap_set_stream(uint8_t link, bool open);

/** \return the most payload bytes one PDU of `service` on `link` may carry (the peer's MTU), 0 when not open. */
uint16_t l2cap_peer_mtu(uint8_t link, uint8_t service);

/** Starts a PDU of `len` payload bytes on `service`'s channel (after l2cap_can_send()): the payload follows with
 *  hci_acl_put*(), then hci_acl_end(). */
void l2cap_begin(uint8_t link, uint8_t service, uint16_t len);

/* ---- hooks implemented by the services ---- */

/** An SDP request. \return false when its answer found no room yet (it is handed over again later). */
bool sdp_on_pdu(uint8_t link, const uint8_t *p, uint16_t n);
/** An RFCOMM frame. \return false when an answer found no room yet. */
bool rfcomm_on_pdu(uint8_t link, const uint8_t *p, uint16_t n);
/** The RFCOMM channel of `link` closed (`lost`: with the link, not by a disconnection request). */
void rfcomm_channel_closed(uint8_t link, bool lost);
/** The framed channel of `link` opened, received one SDU, closed. */
void bt_framed_opened(uint8_t link);
void bt_framed_rx(uint8_t link, const uint8_t *p, uint16_t n);
void bt_framed_closed(uint8_t link, bool lost);

#endif
