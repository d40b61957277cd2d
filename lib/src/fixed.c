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

/* floor(sqrt(n)).  Newton from above, x <- (x + n/x) / 2, which decreases
 * monotonically to floor(sqrt(n)) from any start x0 >= floor(sqrt(n)) and
 * never passes below it; so the first x with x^2 <= n is the answer (a
 * product instead of the confirming division).  The start comes from n's
 * top eight bits: with n = m / 4^e, m in [2^62, 2^64), x0 = ceil(T / 2^e)
 * where T >= floor(sqrt(m)) (ct_isqrt_top8, capped at 2^32 - 1, so x0^2 <
 * 2^64), within 0.8 % of sqrt(n): the relative error after one step is
 * below 2^-14, after two below 2^-30 (under two units for x < 2^32), so at
 * most three divisions (20 million random n, every bit length: 0-3, mostly
 * 1-2).  bound: 8 steps (the error at least squares per step).            */
uint64_t ct_isqrt64(uint64_t n)
{
    uint64_t x;
    unsigned e, k;
    if (n < 2u) {
        return n;
    }
    e = (64u - ct_bitlen64(n)) / 2u; /* m = n << 2e in [2^62, 2^64) */
    x = (uint64_t)ct_isqrt_top8[((n << (2u * e)) >> 56) - 64u];
    x = (x + (((uint64_t)1 << e) - 1u)) >> e;
    for (k = 0u; k < 8u; ++k) {
        if (x * x <= n) {
            break;
        }
        x = (x + n / x) >> 1;
    }
    return x;
}

uint64_t ct_i128_isqrt(ct_i128 n)
{
    uint64_t x, q, rem;
    int k;
    if (ct_i128_sign(n) <= 0) {
        return 0u;
    }
    if (n.hi == 0u) {
        return ct_isqrt64(n.lo);
    }
    /* Newton from above, started from the square root of the top bits:
     * with n' = n >> 2s < 2^62, x0 = (isqrt(n') + 1) << s > sqrt(n), and
     * x <- (x + n/x)/2 decreases monotonically to floor(sqrt(n)) (two or
     * three steps from this start).  bound: 70 iterations.               */
    {
        unsigned bits = 64u + ct_bitlen64(n.hi), s;
        uint64_t top;
        s = (bits - 61u) / 2u + 1u; /* 2s >= bits - 62, 2s < 64 + ... */
        if (2u * s >= 64u) {
            top = n.hi >> (2u * s - 64u);
        } else {
            top = (n.lo >> (2u * s)) | (n.hi << (64u - 2u * s));
        }
        x = (ct_isqrt64(top) + 1u) << s;
    }
    /* One Newton step from x0 lands within a few units of the root: x0 is
     * within 2^s of it (relative 2^-29), so the step's error is at most
     * 2^2s / 2^(30+s) = 2^(s-30) <= 8 (s <= 33), plus 2 for the floors and
     * the +1.  The result is then fixed by exact squares (128-bit products:
     * y < 2^63).  bound: 16 + 16 fix-ups; if they do not suffice (they
     * always do by the argument above), the Newton loop below finishes. */
    if (n.hi < x) {
        uint64_t y = (x >> 1) + (udiv128(n.hi, n.lo, x, &rem) >> 1) + 1u;
        int ok = 0;
        for (k = 0; k < 16; ++k) {
            ct_i128 sq = ct_umul64(y, y);
            if (ct_i128_cmp(sq, n) <= 0) {
                ok = 1;
                break;
            }
            y--;
        }
        if (ok) {
            for (k = 0; k < 16; ++k) {
                ct_i128 sq = ct_umul64(y + 1u, y + 1u);
                if (ct_i128_cmp(sq, n) > 0) {
                    return y;
                }
                y++;
            }
        }
    }
    for (k = 0; k < 70; ++k) {
        uint64_t y;
        if (n.hi >= x) {
            /* n / x does not fit: x far too small, cannot happen from above */
            break;
        }
        q = udiv128(n.hi, n.lo, x, &rem);
        y = (x >> 1) + (q >> 1) + ((x & q) & 1u);
        if (y >= x) {
            break;
        }
        x = y;
    }
    return x;
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
