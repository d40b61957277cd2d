/*
 * fixed.c -- 128-bit integer helpers, integer square roots, integer trig.
 * See fixed.h for the formats and the overflow contract.
 */
#include "fixed.h"

#ifndef CT_NATIVE_INT128
/* One quotient digit of Knuth's algorithm D in base 2^32: the estimate
 * un / vn1, corrected at most twice (Knuth's theorem B) against the next
 * dividend digit un_next and the divisor's second digit vn0. */
static uint64_t knuth_digit(uint64_t un, uint64_t un_next, uint64_t vn1, uint64_t vn0)
{
    const uint64_t b = (uint64_t)1 << 32;
    uint64_t q = un / vn1, rhat = un - q * vn1;
    unsigned k;
    for (k = 0u; k < 2u; ++k) { /* bound: at most two corrections */
        if (q >= b || q * vn0 > ((rhat << 32) | un_next)) {
            q--;
            rhat += vn1;
            if (rhat < b) {
                continue;
            }
        }
        break;
    }
    return q;
}
#endif

/* Unsigned (hi:lo) / d with hi < d; returns the quotient, *rem the rest.
 * Portable: long division in base 2^32 (Knuth's algorithm D, as in Hacker's
 * Delight's divlu): d normalised so its top bit is set, then two quotient
 * digits, each estimated from the top digits (a 64-by-32-bit division) and
 * corrected at most twice (Knuth's theorem B).  The 64-bit intermediates
 * fit: un32 < vn (from hi < d), so q1 <= 2^32 and q1 vn0 < 2^64; un21 and
 * the remainder are < vn. */
static uint64_t udiv128(uint64_t hi, uint64_t lo, uint64_t d, uint64_t *rem)
{
#ifdef CT_NATIVE_INT128
#if defined(__x86_64__) && defined(__GNUC__)
    /* x86-64's DIV divides hi:lo by d in one instruction when the quotient
     * fits (hi < d, as callers keep it; else DIV would trap and the C
     * division below wraps, as the portable path does); the compiler's
     * 128-bit division would call a general library routine instead */
    if (hi < d) {
        uint64_t q, r;
        __asm__("divq %4" : "=a"(q), "=d"(r) : "a"(lo), "d"(hi), "rm"(d) : "cc");
        *rem = r;
        return q;
    }
#endif
    {
        ct_nu128 n = ((ct_nu128)hi << 64) | (ct_nu128)lo;
        *rem = (uint64_t)(n % d);
        return (uint64_t)(n / d);
    }
#else
    const uint64_t m32 = 0xFFFFFFFFu;
    unsigned s = 64u - ct_bitlen64(d); /* leading zeros; d > 0 */
    uint64_t vn = d << s, vn1 = vn >> 32, vn0 = vn & m32;
    uint64_t un32 = s == 0u ? hi : (hi << s) | (lo >> (64u - s));
    uint64_t un10 = lo << s, un1 = un10 >> 32, un0 = un10 & m32;
    uint64_t q1, q0, un21;
    q1 = knuth_digit(un32, un1, vn1, vn0);
    un21 = (un32 << 32) + un1 - q1 * vn; /* mod 2^64; the value is < vn */
    q0 = knuth_digit(un21, un0, vn1, vn0);
    *rem = ((un21 << 32) + un0 - q0 * vn) >> s;
    return (q1 << 32) | q0;
#endif
}

int64_t ct_i128_floor_div(ct_i128 n, int64_t d)
{
    uint64_t rem, q;
    CT_ASSERT(d > 0);
    /* fast path: the numerator fits in 64 bits */
    if (n.hi == ((n.lo >> 63) != 0u ? ~(uint64_t)0 : 0u) && n.lo != ((uint64_t)1 << 63)) {
        return ct_floor_div((int64_t)n.lo, d);
    }
    if (ct_i128_sign(n) >= 0) {
        q = udiv128(n.hi, n.lo, (uint64_t)d, &rem);
        return (int64_t)q;
    } else {
        ct_i128 m = ct_i128_neg(n);
        q = udiv128(m.hi, m.lo, (uint64_t)d, &rem);
        /* floor(-m/d) = -ceil(m/d) */
        return -(int64_t)q - (rem != 0u ? 1 : 0);
    }
}

int64_t ct_i128_floor_div_sat(ct_i128 n, int64_t d)
{
    const int64_t lim = INT64_C(1) << 62;
    ct_i128 cap = ct_i128_mul(lim, d);
    CT_ASSERT(d > 0);
    if (ct_i128_cmp(n, cap) >= 0) {
        return lim;
    }
    if (ct_i128_cmp(n, ct_i128_neg(cap)) <= 0) {
        return -lim;
    }
    return ct_i128_floor_div(n, d);
}

/* Integer square roots without a 64-bit division (a library call on
 * Cortex-M0/M4, about 50 instructions on M4): floor(sqrt(a)) of a 32-bit a by one
 * Newton step from a table with a 32-bit division, then each doubling of
 * the width by one Newton step from below; each step's error is at most
 * one unit.
 *
 * isqrt32_norm: floor(sqrt(a)) for a in [2^30, 2^32).  The start is the
 * table's T (ct_isqrt_top8, by a's top eight bits: T >= floor(sqrt(m)) for
 * every 64-bit m with those top bits, so x0 = ceil(T / 2^16) >=
 * floor(sqrt(a)), and within 0.8 % of it, <= 2^16).  One Newton step from
 * above, x1 = (x0 + a / x0) / 2 floored, never goes below floor(sqrt(a))
 * and exceeds sqrt(a) by at most (x0 - sqrt(a))^2 / (2 x0) <= 256^2 /
 * (2 * 33024) < 1 (the first segment's, the widest): so x1 is the
 * root or one more, decided by its square (a throwaway exhaustive run over
 * every a: 11 % take the decrement; test_fixed checks each table segment's
 * ends at every scale). */
static uint32_t isqrt32_norm(uint32_t a)
{
    uint32_t t = ct_isqrt_top8[(a >> 24) - 64u];
    uint32_t x = (t >> 16) + ((t & 0xffffu) != 0u ? 1u : 0u); /* <= 2^16 */
    x = (x + a / x) >> 1; /* x >= 2^15: a / x < 2^17 */
    return (uint64_t)x * x > a ? x - 1u : x;
}

/* floor(sqrt(m)) for m in [2^62, 2^64).  s1 = floor(sqrt(m_hi)) (m_hi = m /
 * 2^32 floored, in [2^30, 2^32)) puts the root in [x0, x0 + 2^16), x0 = s1
 * 2^16 >= 2^31.  One Newton step from below, x1 = x0 + r / (2 x0) with r =
 * m - x0^2 (< (2 s1 + 1) 2^32 < 2^49), lands in [sqrt(m), sqrt(m) + 1]
 * (its error (sqrt(m) - x0)^2 / (2 x0) < 2^32 / 2^32), so floor(x1) =
 * x0 + floor(floor(r / 2^17) / s1) (a 32-bit division: r / 2^17 < 2^32) is
 * the root or one more; capped at 2^32 - 1 (the root is below 2^32) and
 * checked by its square. */
static uint64_t isqrt64_norm(uint64_t m)
{
    uint32_t s1 = isqrt32_norm((uint32_t)(m >> 32));
    uint64_t r = m - (((uint64_t)s1 * s1) << 32);
    uint64_t y = ((uint64_t)s1 << 16) + (uint32_t)(r >> 17) / s1; /* <= 2^32 */
    if (y > 0xffffffffu) {
        y = 0xffffffffu;
    }
    return y * y > m ? y - 1u : y;
}

/* floor(sqrt(n)): n scaled by 4^e into [2^62, 2^64) (n >= 2), whose root
 * floored and divided by 2^e (floored) is n's. */
uint64_t ct_isqrt64(uint64_t n)
{
    unsigned e;
    if (n < 2u) {
        return n;
    }
    e = (64u - ct_bitlen64(n)) / 2u;
    return isqrt64_norm(n << (2u * e)) >> e;
}

/* floor(sqrt(n)) of a 128-bit n (0 for n <= 0): n >= 2^64 scaled by 4^e
 * into N in [2^126, 2^128) (2e <= 62), S1 = floor(sqrt(N_hi)) in [2^31,
 * 2^32) puts N's root in [X0, X0 + 2^32), X0 = S1 2^32 >= 2^63, and
 * one Newton step from below, X0 + floor(R / (2 X0)) with R = N - X0^2 <
 * (2 S1 + 1) 2^64 < 2^97, is the root or one more (as isqrt64_norm's):
 * floor(floor(R / 2^33) / S1), R / 2^33 < 2^64, one 64-bit division;
 * capped at 2^64 - 1, checked by its 128-bit square, then divided by 2^e. */
uint64_t ct_i128_isqrt(ct_i128 n)
{
    unsigned e;
    uint64_t s1, dh, q, hi, y;
    ct_i128 N, sq;
    if (ct_i128_sign(n) <= 0) {
        return 0u;
    }
    if (n.hi == 0u) {
        return ct_isqrt64(n.lo);
    }
    /* n < 2^127: bitlen(hi) in [1, 63], e in [0, 31] */
    e = (64u - ct_bitlen64(n.hi)) / 2u;
    N = ct_i128_shl(n, 2u * e); /* 2e <= 62 (0: n itself) */
    s1 = isqrt64_norm(N.hi);
    /* N_hi - S1^2 <= 2 S1 < 2^33: R / 2^33 = (N_hi - S1^2) 2^31 + N_lo / 2^33 */
    dh = N.hi - s1 * s1;
    q = ((dh << 31) | (N.lo >> 33)) / s1; /* <= 2^32 */
    hi = s1 << 32;
    y = q > ~hi ? ~(uint64_t)0 : hi + q;
    sq = ct_umul64(y, y);
    if (sq.hi > N.hi || (sq.hi == N.hi && sq.lo > N.lo)) {
        y--;
    }
    return y >> e;
}

/* ------------------------------------------------------------------------ */
/* Integer trig for sector boundaries.                                       */

#define CT_PI4_Q62 INT64_C(3622009729038561421) /* pi/4 * 2^62 */
#define CT_ONE_Q30 INT64_C(1073741824)
#define CT_C45_Q30 INT32_C(759250125)           /* 2^30 / sqrt(2), rounded */

static int64_t mul_q30(int64_t a, int64_t b)
{
    int64_t p = a * b; /* |a|,|b| <= 2^30.1: |p| < 2^61 */
    return (p >= 0) ? (p + (INT64_C(1) << 29)) >> 30 : -((-p + (INT64_C(1) << 29)) >> 30);
}

/* cos and sin of theta (Q30, 0 < theta <= pi/4) by Taylor series. */
static void cos_sin_q30(int64_t th, int64_t *c, int64_t *s)
{
    int64_t th2 = mul_q30(th, th);
    int64_t ts = th, tc = CT_ONE_Q30, ss = th, cc = CT_ONE_Q30;
    int64_t n;
    /* bound: 9 terms; theta^19/19! < 2^-60 for theta <= pi/4 */
    for (n = 1; n <= 9; ++n) {
        ts = -mul_q30(ts, th2) / ((2 * n) * (2 * n + 1));
        tc = -mul_q30(tc, th2) / ((2 * n - 1) * (2 * n));
        ss += ts;
        cc += tc;
    }
    *c = cc;
    *s = ss;
}

void ct_dir_of_fraction(uint32_t k, uint32_t n, int32_t *cx, int32_t *sy)
{
    uint32_t e, o, r;
    int64_t x, y, t;
    unsigned rot, q;
    CT_ASSERT(n > 0u);
    k %= n;
    e = 8u * k; /* k < 64 * ... : n <= 64 in practice, 8k < 2^32 */
    o = e / n;
    r = e % n;
    if (r == 0u) {
        if ((o & 1u) == 0u) {
            x = CT_ONE_Q30;
            y = 0;
        } else {
            x = CT_C45_Q30;
            y = CT_C45_Q30;
        }
        rot = o / 2u;
    } else if ((o & 1u) == 0u) {
        int64_t th = ((CT_PI4_Q62 / (int64_t)n) * (int64_t)r + (INT64_C(1) << 31)) >> 32;
        cos_sin_q30(th, &x, &y);
        rot = o / 2u;
    } else {
        int64_t th = ((CT_PI4_Q62 / (int64_t)n) * (int64_t)(n - r) + (INT64_C(1) << 31)) >> 32;
        int64_t c, s;
        cos_sin_q30(th, &c, &s);
        /* angle = (o+1)*45 - th: (cos th, -sin th) rotated by (o+1)/2 quarters */
        x = c;
        y = -s;
        rot = (o + 1u) / 2u;
    }
    /* bound: at most 3 quarter turns */
    for (q = 0u; q < (rot & 3u); ++q) {
        t = x;
        x = -y;
        y = t;
    }
    *cx = (int32_t)x;
    *sy = (int32_t)y;
}
