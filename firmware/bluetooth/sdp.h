/**
 * \file sdp.h
 * The SDP server (Bluetooth Core, Vol 3, Part B): two service records in flash, the Serial Port Profile (UUID
 * 0x1101, RFCOMM channel BT_RFCOMM_CHANNEL) and the robot's framed service (BT_FRAMED_UUID, L2CAP PSM
 * BT_PSM_FRAMED), both in the public browse group. It answers ServiceSearch, ServiceAttribute and
 * ServiceSearchAttribute requests; answers longer than the client's byte count, its MTU or SDP_CHUNK_MAX go out in
 * parts with a continuation state (the offset into the answer). It keeps no state between requests.
 */
#ifndef SDP_H
#define SDP_H

#include <stdbool.h>
#include <stdint.h>

/** Most attribute bytes per response PDU (keeps each answer small in the transmit ring). */
#define SDP_CHUNK_MAX 64u

/* sdp_on_pdu() is the L2CAP hook (l2cap.h). */

#endif
