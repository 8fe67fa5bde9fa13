/**
 * \file rfcomm.h
 * RFCOMM (Bluetooth RFCOMM specification over TS 07.10) on the RFCOMM channel of each link: the multiplexer on
 * DLCI 0, parameter negotiation (PN) with credit-based flow control, modem status (MSC), remote port and line
 * status, test; one data channel per link, server channel BT_RFCOMM_CHANNEL, carrying a byte stream (SLIP frames,
 * as on any stream).
 *
 * Bytes to send are staged per link (RFCOMM_TX_SIZE) and go out as UIH frames of up to N1 bytes: at once when a
 * frame is full, else when the UART is about to run dry, so frames grow while the wire is busy; a frame is written
 * RFCOMM_SLICE bytes per tick. Credits are given back as received frames are handled (comm handles each at once),
 * with data or on a frame of their own.
 */
#ifndef RFCOMM_H
#define RFCOMM_H

#include <stdbool.h>
#include <stdint.h>

/** Bytes staged per link for sending: a full state packet SLIP-encoded at its worst (comm's room check). */
#define RFCOMM_TX_SIZE 256u
/** Credits the robot grants the peer (frames it may send before more are given). */
#define RFCOMM_RX_CREDITS 7u
/** A partial frame goes out when fewer bytes than this wait for the UART (it is about to run dry). */
#define RFCOMM_IDLE_BACKLOG 16u
/** Information bytes of a frame written into the transmit ring per tick: a long frame takes a few ticks (the wire
 *  needs 10 ms for it anyway), so no tick pays for all of it. */
#define RFCOMM_SLICE 16u

void rfcomm_init(void);

/** Sends staged bytes, credits and modem status due, on every link. */
void rfcomm_task(void);

/** \return bytes that can be staged on `link` now (0 while its data channel is not open). */
uint16_t rfcomm_tx_room(uint8_t link);
/** Stages `n` bytes (at most rfcomm_tx_room()). */
void rfcomm_write(uint8_t link, const uint8_t *p, uint16_t n);
/** The staging ring of `link` (RFCOMM_TX_SIZE bytes, one-byte indices), `*pos` set to where the next byte goes: a
 *  writer that stores its bytes there itself (at most rfcomm_tx_room()) stages them with rfcomm_tx_commit(). */
uint8_t *rfcomm_tx_ring(uint8_t link, uint8_t *pos);
/** Stages the ring's bytes up to `pos`. */
void rfcomm_tx_commit(uint8_t link, uint8_t pos);

/* rfcomm_on_pdu() and rfcomm_channel_closed() are L2CAP hooks (l2cap.h). */

/* ---- hooks implemented by the layer above (bt.c) ---- */

/** The data channel of `link` opened, received bytes, closed (`lost`: with its link, not by a disconnection). */
void bt_stream_opened(uint8_t link);
void bt_stream_rx(uint8_t link, const uint8_t *p, uint16_t n);
void bt_stream_closed(uint8_t link, bool lost);

#endif
