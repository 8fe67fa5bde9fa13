/**
 * \file bt_config.h
 * What a host needs to know of the robot's Bluetooth stack, in one place (firmware/README.md lists them for the
 * host side): the services it offers, how it presents itself, and the sizes that bound its memory.
 */
#ifndef BT_CONFIG_H
#define BT_CONFIG_H

/** ACL links served at once (a phone and a computer). */
#define BT_LINKS 2u

/** The robot's framed service: one PocketBot frame per L2CAP SDU (dynamic PSM, odd, >= 0x1001). */
#define BT_PSM_FRAMED 0x1001u
/** The Serial Port Profile's RFCOMM server channel (SLIP frames, as on any stream). */
#define BT_RFCOMM_CHANNEL 1u
/** 128-bit service class UUID of the framed service in its SDP record: 6e2a6f10-5b1e-4c3a-9a4e-70b0c4e7b001. */
#define BT_FRAMED_UUID 0x6Eu, 0x2Au, 0x6Fu, 0x10u, 0x5Bu, 0x1Eu, 0x4Cu, 0x3Au, \
                       0x9Au, 0x4Eu, 0x70u, 0xB0u, 0xC4u, 0xE7u, 0xB0u, 0x01u
/** SDP service record handles: the Serial Port record and the framed service's. */
#define BT_SDP_HANDLE_SPP 0x00010001ul
#define BT_SDP_HANDLE_FRAMED 0x00010002ul

/** Local name: this prefix and settings.identity.robot_id in decimal ("PocketBot-7"). */
#define BT_NAME_PREFIX "PocketBot-"
/** Class of device: major class Toy (0x08), minor class Robot (0x01). */
#define BT_CLASS_OF_DEVICE 0x000804ul

/** L2CAP MTU the robot receives on every channel: one PocketBot frame (125 bytes) fits. */
#define BT_L2CAP_MTU 128u
/** Largest RFCOMM information field the robot receives (N1): an RFCOMM header and FCS beside it fit the MTU. */
#define BT_RFCOMM_N1 121u
/** Largest ACL data packet the controller may send the robot (told by Host_Buffer_Size): one whole L2CAP PDU. */
#define BT_ACL_RX_MAX (BT_L2CAP_MTU + 4u)

#endif
