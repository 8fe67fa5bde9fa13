/**
 * \file slip.h
 * SLIP (RFC 1055) framing of the serial link: END 0xC0 before and after every frame, ESC 0xDB,
 * ESC_END 0xDC, ESC_ESC 0xDD.
 */
#ifndef SLIP_H
#define SLIP_H

#include <stdbool.h>
#include <stdint.h>

#include "pb_protocol.h"

#define SLIP_END 0xC0u
#define SLIP_ESC 0xDBu
#define SLIP_ESC_END 0xDCu
#define SLIP_ESC_ESC 0xDDu

/** Result of feeding one byte to the decoder. */
typedef enum {
    SLIP_NONE = 0,     /**< nothing complete yet */
    SLIP_FRAME,        /**< a frame is complete in buf[0..len) */
    SLIP_ERROR         /**< a frame was dropped: bad escape, or longer than the buffer (`overflow`) */
} slip_result_t;

/** Decoder state; the buffer holds the largest protocol frame. */
typedef struct {
    uint8_t buf[PB_MAX_FRAME];
    uint8_t len;
    uint8_t escaped;   /**< the previous byte was ESC */
    uint8_t broken;    /**< the frame is dropped at the next END */
    uint8_t overflow;  /**< it is dropped for being longer than buf */
    uint8_t ended;     /**< an END completed a frame or an error; the next byte starts a new one */
    uint16_t dropped;  /**< decoded bytes not kept in buf once the frame broke (saturating) */
} slip_decoder_t;

/** Decoded bytes of the current (or just ended) frame, those past the buffer or a broken escape included. */
static inline uint16_t slip_seen(const slip_decoder_t *d)
{
    return (uint16_t)(d->len + d->dropped);
}

void slip_decoder_init(slip_decoder_t *d);

/** Feeds one received byte. Empty frames (END END) are ignored.
 *  \return SLIP_FRAME when END completes a frame (buf, len valid until the next call), SLIP_ERROR when it
 *  completes a broken one (slip_seen() and `overflow` tell how long it was and why, until the next call). */
slip_result_t slip_decode(slip_decoder_t *d, uint8_t byte);

/** Takes `byte` when slip_decode() would only append it to the frame (a plain byte inside a sound frame), without
 *  the call. \return true if it did; else the byte is slip_decode()'s */
static inline bool slip_take_plain(slip_decoder_t *d, uint8_t byte)
{
    if (byte == SLIP_END || byte == SLIP_ESC || d->ended || d->escaped || d->broken || d->len >= sizeof d->buf)
        return false;
    d->buf[d->len++] = byte;
    return true;
}

/** Takes the bytes of `p` that slip_decode() would only append to the frame (plain bytes inside a sound frame), in
 *  one loop instead of a call each; stops at the first byte that needs slip_decode(). \return how many it took */
uint16_t slip_decode_plain(slip_decoder_t *d, const uint8_t *p, uint16_t n);

/** \return the size of `frame` once SLIP-encoded, both ENDs included. */
uint16_t slip_encoded_size(const uint8_t *frame, uint16_t n);

/** SLIP-encodes `frame` into `out` (room for slip_encoded_size() bytes). \return bytes written. */
uint16_t slip_encode(uint8_t *out, const uint8_t *frame, uint16_t n);

#endif
