/**
 * \file fixed.h
 * Fixed-point arithmetic for the control loops. Software floats cost hundreds of cycles per operation on
 * the AVR; these helpers build every product from 16 x 16 -> 32 bit multiplications (one MUL sequence each
 * there) and saturate instead of wrapping. Gains and other factors converted from float settings are
 * `fx_gain_t` (a 16-bit mantissa and a binary exponent), so gains from 1e-12 to 1e12 keep 16 significant
 * bits; the conversion is done once, when settings change.
 */
#ifndef FIXED_H
#define FIXED_H

#include <stdint.h>

#define FX_MAX INT32_MAX /**< saturation limit; results stay within +-FX_MAX (never INT32_MIN) */

/* -Os would make calls of the small helpers, and a call costs as much as their work on the AVR. */
#define FX_INLINE static inline __attribute__((always_inline))

/** A non-negative factor m * 2^-s, m in [2^15, 2^16) or 0. */
typedef struct {
    uint16_t m;    /**< mantissa, 0 for a zero factor */
    int8_t s;      /**< binary exponent: the value is m / 2^s */
    uint32_t hmax; /**< for s < 16: the largest (|a| * m) >> 16 whose product does not saturate */
} fx_gain_t;

/** \return `x` (finite, >= 0; negative or NaN give 0) as a factor; values below 2^-47 become 0, those of
 *  2^31 and above 65535 * 2^15 (any product of 2 or more saturates). Exact to 16 significant bits.
 *  No float arithmetic. */
fx_gain_t fx_gain(float x);

/** \return a + b saturated to +-FX_MAX. */
FX_INLINE int32_t fx_add(int32_t a, int32_t b)
{
    int32_t r = (int32_t)((uint32_t)a + (uint32_t)b);
    if (((a ^ r) & (b ^ r)) < 0) /* a and b have the same sign and r the other: overflow */
        return a < 0 ? -FX_MAX : FX_MAX;
    return r == INT32_MIN ? -FX_MAX : r;
}

/** \return v clamped to +-limit (limit >= 0). */
FX_INLINE int32_t fx_clamp(int32_t v, int32_t limit)
{
    return v > limit ? limit : v < -limit ? -limit : v;
}

/** \return a * b (16 x 16 -> 32 bits). On the AVR the four MUL instructions inline: the compiler loses the
 *  operands' width once they come out of shifts and calls its 32 x 32 bit routine otherwise. */
FX_INLINE uint32_t fx_umul16(uint16_t a, uint16_t b)
{
#if defined(__AVR__) && defined(__AVR_HAVE_MUL__)
    uint32_t r;
    uint8_t zero;
    __asm__("clr  %[z]"           "\n\t"
            "mul  %A[a], %A[b]"   "\n\t"
            "movw %A[r], r0"      "\n\t"
            "mul  %B[a], %B[b]"   "\n\t"
            "movw %C[r], r0"      "\n\t"
            "mul  %B[a], %A[b]"   "\n\t"
            "add  %B[r], r0"      "\n\t"
            "adc  %C[r], r1"      "\n\t"
            "adc  %D[r], %[z]"    "\n\t"
            "mul  %A[a], %B[b]"   "\n\t"
            "add  %B[r], r0"      "\n\t"
            "adc  %C[r], r1"      "\n\t"
            "adc  %D[r], %[z]"    "\n\t"
            "clr  __zero_reg__"
            : [r] "=&r"(r), [z] "=&r"(zero)
            : [a] "r"(a), [b] "r"(b));
    return r;
#else
    return (uint32_t)a * b;
#endif
}

/** \return x >> k for k < 32: whole bytes by moves, then at most 7 single-bit steps. */
FX_INLINE uint32_t fx_shr(uint32_t x, uint8_t k)
{
    if (k & 16u)
        x >>= 16;
    if (k & 8u)
        x >>= 8;
    return x >> (k & 7u);
}

/** \return x << k for k < 32 (the caller knows it does not overflow). */
FX_INLINE uint32_t fx_shl(uint32_t x, uint8_t k)
{
    if (k & 16u)
        x <<= 16;
    if (k & 8u)
        x <<= 8;
    return x << (k & 7u);
}

/** Fractions in Q14: 1.0 = FX_ONE. */
#define FX_ONE 16384
#define FX_FRAC_MAX (1L << 30) /**< fx_frac() takes |a| up to this */

/** \return a * f / FX_ONE (f a Q14 fraction, |f| <= FX_ONE, so |result| <= |a|), truncated towards zero;
 *  a is clamped to +-FX_FRAC_MAX first. */
FX_INLINE int32_t fx_frac(int32_t a, int16_t f)
{
    a = fx_clamp(a, FX_FRAC_MAX);
    uint8_t negative = (a < 0) != (f < 0);
    uint32_t ua = a < 0 ? (uint32_t)-a : (uint32_t)a;
    uint16_t uf = (uint16_t)(f < 0 ? -f : f);
    uint32_t r;
    if (uf >= FX_ONE) {
        r = ua;
    } else if (uf == FX_ONE / 2) { /* straight movements and rotations: halves */
        r = ua >> 1;
    } else {
        /* a * f / 2^14 = a * (4 f) / 2^16: whole bytes, no bit shifts; 4 f < 2^16 */
        uf = (uint16_t)(uf << 2);
        r = fx_umul16((uint16_t)(ua >> 16), uf) + (fx_umul16((uint16_t)ua, uf) >> 16);
    }
    return negative ? -(int32_t)r : (int32_t)r;
}

/** \return (a * b) >> 32 for b < 2^16, exact (floor). */
FX_INLINE uint32_t fx_mulhi16(uint32_t a, uint16_t b)
{
    return (fx_umul16((uint16_t)(a >> 16), b) + (fx_umul16((uint16_t)a, b) >> 16)) >> 16;
}

/** \return (a * b) >> 32, exact (floor). */
FX_INLINE uint32_t fx_mulhi(uint32_t a, uint32_t b)
{
    uint16_t ah = (uint16_t)(a >> 16), al = (uint16_t)a, bh = (uint16_t)(b >> 16), bl = (uint16_t)b;
    uint32_t hh = fx_umul16(ah, bh), hl = fx_umul16(ah, bl), lh = fx_umul16(al, bh), ll = fx_umul16(al, bl);
    uint32_t mid = (ll >> 16) + (uint16_t)hl + (uint16_t)lh;
    return hh + (hl >> 16) + (lh >> 16) + (mid >> 16);
}

/** \return a * g, truncated towards zero, saturated to +-FX_MAX. */
FX_INLINE int32_t fx_mul(int32_t a, const fx_gain_t *gp)
{
    /* Each field read where it is needed: a copy of the struct took registers that were spilled. */
    uint16_t m = gp->m;
    if (a == 0 || m == 0)
        return 0;
    uint32_t ua = a < 0 ? 0u - (uint32_t)a : (uint32_t)a; /* |INT32_MIN| = 2^31 fits */
    /* |a| * m = h * 2^16 + l, from two 16 x 16 bit products; h < 2^31 + 2^16. */
    uint32_t t = fx_umul16((uint16_t)ua, m);
    uint32_t h = fx_umul16((uint16_t)(ua >> 16), m) + (t >> 16);
    uint32_t r;
    if (gp->s >= 16) {
        uint8_t k = (uint8_t)(gp->s - 16);
        r = k >= 32u ? 0 : fx_shr(h, k);
        if (r > FX_MAX)
            r = FX_MAX;
    } else if (h > gp->hmax) {
        r = FX_MAX;
    } else {
        /* (h * 2^16 + l) / 2^s = h << (16 - s) + l / 2^s, within FX_MAX by hmax */
        uint16_t l = (uint16_t)t;
        uint8_t k = (uint8_t)(16 - gp->s);
        uint16_t low = (uint16_t)((gp->s & 8 ? (uint16_t)(l >> 8) : l) >> (gp->s & 7)); /* 16-bit shifts; s < 16 */
        r = fx_shl(h, k) + (gp->s >= 0 ? (uint32_t)low : fx_shl(l, (uint8_t)-gp->s));
    }
    return a < 0 ? -(int32_t)r : (int32_t)r;
}

/** \return n / d (d > 0): shift and subtract over the quotient's bits only, so a quotient of k bits takes k steps
 *  (the library's 32-bit division takes 32, about 600 cycles on the AVR). */
uint32_t fx_udiv(uint32_t n, uint32_t d);

/** \return floor(sqrt(v)). */
uint16_t fx_isqrt(uint32_t v);

/** \return v in Q16 rounded to an integer, halves away from zero (|v| < 2^30). */
FX_INLINE int32_t fx_round_q16(int32_t v)
{
    return v >= 0 ? (v + 0x8000) >> 16 : -((-v + 0x8000) >> 16);
}

#endif
