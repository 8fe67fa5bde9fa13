/**
 * \file bt.h
 * The robot's Bluetooth host stack (thesis chapter 10), its own floor between the UART driver and comm:
 *
 *     comm           host links 0..BT_LINKS-1: one per ACL link, stream (RFCOMM) or framed (L2CAP)
 *     bt             this module: the stack's task and comm's link drivers
 *     rfcomm  sdp    RFCOMM server channel BT_RFCOMM_CHANNEL; the SDP server and its records in flash
 *     l2cap          basic mode: signalling, configuration, fragmentation and reassembly; the framed service
 *     hci            reset and init, connections, Secure Simple Pairing with link keys in EEPROM, flow control
 *     h4             the H4 UART transport over drivers/uart's rings (USARTC0, 115200 Bd)
 *
 * Built into the robot's default firmware (LINK=hci); the serial-module build (LINK=serial) leaves it out and
 * serves host link 0 on the UART instead. A host that opens RFCOMM's data channel or the framed channel on a link
 * becomes comm's host on that link; its closing (or losing) the channel, its link or the controller (reset after a
 * wire failure) closes comm's link, so the failsafe and the session rules work as on any link.
 */
#ifndef BT_H
#define BT_H

/** Starts the stack: the controller is reset and initialised over the next ticks. */
void bt_init(void);

/** One main loop tick of the stack: the wire (a bounded slice of received bytes), answers and staged data. */
void bt_task(void);

#endif
