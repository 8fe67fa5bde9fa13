#include "slip.h"

void slip_decoder_init(slip_decoder_t *d)
{
    d->len = 0;
    d->escaped = 0;
    d->broken = 0;
    d->overflow = 0;
    d->ended = 0;
    d->dropped = 0;
}

slip_result_t slip_decode(slip_decoder_t *d, uint8_t byte)
{
    if (d->ended) { /* what the END completed stayed readable until now */
        d->ended = 0;
        d->len = 0;
        d->dropped = 0;
        d->overflow = 0;
    }
    if (byte == SLIP_END) {
        slip_result_t r = SLIP_NONE;
        if (d->broken || d->escaped)
            r = SLIP_ERROR;
        else if (d->len)
            r = SLIP_FRAME;
        d->escaped = 0;
        d->broken = 0;
        d->ended = 1;
        return r;
    }
    if (d->escaped) {
        d->escaped = 0;
        if (byte == SLIP_ESC_END)
            byte = SLIP_END;
        else if (byte == SLIP_ESC_ESC)
            byte = SLIP_ESC;
        else
            d->broken = 1;
    } else if (byte == SLIP_ESC) {
        d->escaped = 1; /* counted with the byte it escapes */
        return SLIP_NONE;
    }
    if (d->broken || d->len >= sizeof d->buf) { /* counted for the error's detail, not kept */
        d->overflow |= !d->broken;
        d->broken = 1;
        if (d->dropped < 0xFFFFu - sizeof d->buf)
            d->dropped++;
        return SLIP_NONE;
    }
    d->buf[d->len++] = byte;
    return SLIP_NONE;
}

uint16_t slip_decode_plain(slip_decoder_t *d, const uint8_t *p, uint16_t n)
{
    if (d->ended || d->escaped || d->broken)
        return 0;
    uint8_t room = (uint8_t)(sizeof d->buf - d->len);
    uint8_t *dst = d->buf + d->len;
    uint16_t k = 0;
    while (k < n && k < room) {
        uint8_t b = p[k];
        if (b == SLIP_END || b == SLIP_ESC)
            break;
        dst[k++] = b;
    }
    d->len = (uint8_t)(d->len + k);
    return k;
}

uint16_t slip_encoded_size(const uint8_t *frame, uint16_t n)
{
    uint16_t size = (uint16_t)(n + 2u);
    for (uint16_t i = 0; i < n; i++)
        if (frame[i] == SLIP_END || frame[i] == SLIP_ESC)
            size++;
    return size;
}

uint16_t slip_encode(uint8_t *out, const uint8_t *frame, uint16_t n)
{
    uint16_t k = 0;
    out[k++] = SLIP_END;
    for (uint16_t i = 0; i < n; i++) {
        uint8_t b = frame[i];
        if (b == SLIP_END) {
            out[k++] = SLIP_ESC;
            out[k++] = SLIP_ESC_END;
        } else if (b == SLIP_ESC) {
            out[k++] = SLIP_ESC;
            out[k++] = SLIP_ESC_ESC;
        } else {
            out[k++] = b;
        }
    }
    out[k++] = SLIP_END;
    return k;
}
