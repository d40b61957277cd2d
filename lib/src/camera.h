/*
 * camera.h -- integer helpers shared by camera.c and geoloc.c (private).
 *
 * mul_shr: round(a * b / 2^q) through a 64 x 64 -> 128-bit product.  The
 * caller states, at each use, that the rounded result fits in int64.
 */
#ifndef CT_CAMERA_H
#define CT_CAMERA_H

#include "conetrace.h"
#include "fixed.h"

/* round(a * b / 2^q) (half up), 1 <= q <= 63; |a * b| < 2^126 always holds
 * for int64 operands; the result must fit in int64 (caller's bound).       */
static inline int64_t ct_mul_shr(int64_t a, int64_t b, unsigned q)
{
    ct_i128 p = ct_i128_add(ct_i128_mul(a, b), ct_i128_from64(INT64_C(1) << (q - 1u)));
    /* the low 64 bits of floor(p / 2^q), two's complement */
    return (int64_t)((p.hi << (64u - q)) | (p.lo >> q));
}

/* floor(a / 2^n) of a 128-bit value, 1 <= n <= 63 (arithmetic shift
 * written with unsigned operations only).                                  */
static inline ct_i128 ct_i128_sar(ct_i128 a, unsigned n)
{
    ct_i128 r;
    r.lo = (a.lo >> n) | (a.hi << (64u - n));
    r.hi = (a.hi >> n) | (((a.hi >> 63) != 0u) ? ~(~(uint64_t)0 >> n) : 0u);
    return r;
}

static inline ct_i128 ct_i128_abs(ct_i128 a) { return ct_i128_sign(a) < 0 ? ct_i128_neg(a) : a; }

/* Number of significant bits of a non-negative 128-bit value (0 for 0).    */
static inline unsigned ct_i128_bits(ct_i128 a)
{
    return a.hi != 0u ? ct_bitlen64(a.hi) + 64u : ct_bitlen64(a.lo);
}

/* round(num / d) for d in (0, 2^61]: returns 0 (and leaves *q alone) when
 * |num| > lim * d, lim in [0, 2^61], i.e. when |num / d| would exceed lim;
 * then |num| <= 2^122 and the quotient fits.                                */
static inline int ct_div_round(ct_i128 num, int64_t d, int64_t lim, int64_t *q)
{
    if (ct_i128_cmp(ct_i128_abs(num), ct_i128_mul(lim, d)) > 0) {
        return 0;
    }
    /* floor((2 num + d) / (2 d)) */
    *q = ct_i128_floor_div(ct_i128_add(ct_i128_shl(num, 1u), ct_i128_from64(d)), 2 * d);
    return 1;
}

#endif /* CT_CAMERA_H */
