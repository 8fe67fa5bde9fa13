/**
 * \file pb_frame.h
 * Frames of the PocketBot protocol: type, seq, payload length, payload, CRC-16/CCITT-FALSE (little-endian)
 * over header and payload.
 */
#ifndef PB_FRAME_H
#define PB_FRAME_H

#include <stdint.h>

#include "pb_protocol.h"

/** A checked frame; `payload` points into the buffer that was checked. */
typedef struct {
    uint8_t type;
    uint8_t seq;
    uint8_t len;
    const uint8_t *payload;
} pb_frame_t;

extern const PB_FLASH uint16_t pb_crc_table[256];

/** One byte of CRC-16/CCITT-FALSE. */
static inline uint16_t pb_crc16_byte(uint16_t crc, uint8_t b)
{
    return (uint16_t)((crc << 8) ^ pb_crc_table[(uint8_t)((crc >> 8) ^ b)]);
}

/** CRC-16/CCITT-FALSE of `len` bytes, continuing from `crc` (start with 0xFFFF). */
uint16_t pb_crc16(uint16_t crc, const uint8_t *data, uint16_t len);

/**
 * Checks the integrity of a raw (unSLIPped) frame.
 * \param buf the frame bytes \param n their number \param out filled when the frame is sound
 * \return PB_ERROR_CODE_NONE, _TOO_SHORT, _TOO_LONG, _BAD_CRC or _BAD_LENGTH (header length field
 *         disagrees with the frame size). The type is not judged here.
 */
uint8_t pb_frame_check(const uint8_t *buf, uint16_t n, pb_frame_t *out);

/**
 * Builds a frame into `out` (room for PB_MAX_FRAME bytes).
 * \return the frame size, or 0 when `len` exceeds PB_MAX_PAYLOAD.
 */
uint16_t pb_frame_encode(uint8_t *out, uint8_t type, uint8_t seq, const void *payload, uint8_t len);

/** Builds the index pb_packet_lookup() uses (else its first call does). */
void pb_packet_lookup_init(void);

/** pb_packet_index() of an unknown type. */
#define PB_PACKET_NONE 0xFFu

/** \return the index of `type` in pb_packet_info, or PB_PACKET_NONE if the type is unknown. */
uint8_t pb_packet_index(uint8_t type);

/** \return the packet table entry of `type`, or NULL if the type is unknown. */
const PB_FLASH pb_packet_info_t *pb_packet_lookup(uint8_t type);

#endif
