#include "fixed.h"

#include <string.h>

fx_gain_t fx_gain(float x)
{
    fx_gain_t g = {0, 0, 0};
    uint32_t b;
    memcpy(&b, &x, sizeof b);
    if (b & 0x80000000ul) /* negative (or -0, -NaN) */
        return g;
    uint8_t e = (uint8_t)(b >> 23);
    if (e == 0) /* zero or subnormal: below any useful gain */
        return g;
    if (e == 0xFF) { /* infinity or NaN */
        if (b & 0x7FFFFFul)
            return g;
        e = 0xFE;
        b |= 0x7FFFFFul;
    }
    /* x = mant * 2^(e - 150) with a 24-bit mant; keep 16 bits: x = m * 2^(e - 142). */
    uint32_t mant = (b & 0x7FFFFFul) | 0x800000ul;
    uint32_t m = (mant + 0x80u) >> 8;
    int16_t s = (int16_t)(142 - e);
    if (m > 0xFFFFu) { /* rounding carried into a 17th bit */
        m >>= 1;
        s--;
    }
    if (s > 62) /* below 2^-47: every product of a 32-bit value truncates to 0 */
        return g;
    if (s < -15) { /* 2^31 and above: held at 65535 * 2^15, so every product of 2 or more saturates */
        s = -15;
        m = 0xFFFFu;
    }
    g.m = (uint16_t)m;
    g.s = (int8_t)s;
    /* fx_mul() for s < 16: (h << (16 - s)) + (l >> s, or l << -s) <= FX_MAX while h <= hmax */
    if (s < 16) {
        uint32_t low_max = s >= 0 ? 0xFFFFul >> s : 0xFFFFul << -s; /* -s <= 15 */
        g.hmax = ((uint32_t)FX_MAX - low_max) >> (16 - s);          /* 16 - s <= 31 */
    }
    return g;
}

uint32_t fx_udiv(uint32_t n, uint32_t d)
{
    if (d > n)
        return 0;
    /* Align d under n's top: whole bytes first (moves on the AVR), then bits. */
    uint8_t k = 0;
    while (d <= (n >> 8)) {
        d <<= 8;
        k = (uint8_t)(k + 8u);
    }
    while (d <= (n >> 1)) {
        d <<= 1;
        k++;
    }
    uint32_t q = 0;
    for (;;) {
        if (n >= d) {
            n -= d;
            q |= 1u;
        }
        if (k-- == 0)
            return q;
        q <<= 1;
        d >>= 1;
    }
}

uint16_t fx_isqrt(uint32_t v)
{
    uint32_t root = 0;
    uint32_t bit = 1ul << 30;
    while (bit > v)
        bit >>= 2;
    while (bit) {
        if (v >= root + bit) {
            v -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    return (uint16_t)root;
}
