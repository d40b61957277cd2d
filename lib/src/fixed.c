/*
 * fixed.c -- 128-bit integer helpers, integer square roots, integer trig.
 * See fixed.h for the formats and the overflow contract.
 */
#include "fixed.h"

#if defined(__SIZEOF_INT128__) && !defined(CT_PORTABLE_INT128)
#define CT_NATIVE_INT128 1
__extension__ typedef __int128 ct_n128;
__extension__ typedef unsigned __int128 ct_nu128;

static ct_n128 to_n(ct_i128 a)
{
    ct_nu128 u = ((ct_nu128)a.hi << 64) | (ct_nu128)a.lo;
    return (ct_n128)u;
}
static ct_i128 from_n(ct_n128 v)
{
    ct_i128 r;
    ct_nu128 u = (ct_nu128)v;
    r.hi = (uint64_t)(u >> 64);
    r.lo = (uint64_t)u;
    return r;
}
#endif

ct_i128 ct_i128_from64(int64_t a)
{
    ct_i128 r;
    r.lo = (uint64_t)a;
    r.hi = a < 0 ? ~(uint64_t)0 : 0u;
    return r;
}

int64_t ct_i128_to64(ct_i128 a) { return (int64_t)a.lo; }

ct_i128 ct_i128_add(ct_i128 a, ct_i128 b)
{
    ct_i128 r;
    r.lo = a.lo + b.lo;
    r.hi = a.hi + b.hi + (r.lo < a.lo ? 1u : 0u);
    return r;
}

ct_i128 ct_i128_neg(ct_i128 a)
{
    ct_i128 r;
    r.lo = ~a.lo + 1u;
    r.hi = ~a.hi + (r.lo == 0u ? 1u : 0u);
    return r;
}

ct_i128 ct_i128_sub(ct_i128 a, ct_i128 b) { return ct_i128_add(a, ct_i128_neg(b)); }

ct_i128 ct_i128_shl(ct_i128 a, unsigned n)
{
    ct_i128 r;
    if (n == 0u) {
        return a;
    }
    r.hi = (a.hi << n) | (a.lo >> (64u - n));
    r.lo = a.lo << n;
    return r;
}

int ct_i128_sign(ct_i128 a)
{
    if ((a.hi >> 63) != 0u) {
        return -1;
    }
    return (a.hi | a.lo) != 0u ? 1 : 0;
}

int ct_i128_cmp(ct_i128 a, ct_i128 b) { return ct_i128_sign(ct_i128_sub(a, b)); }

/* Unsigned 64 x 64 -> 128 from 32-bit halves. */
static ct_i128 umul64(uint64_t a, uint64_t b)
{
    ct_i128 r;
#ifdef CT_NATIVE_INT128
    ct_nu128 p = (ct_nu128)a * (ct_nu128)b;
    r.hi = (uint64_t)(p >> 64);
    r.lo = (uint64_t)p;
#else
    uint64_t a0 = a & 0xffffffffu, a1 = a >> 32;
    uint64_t b0 = b & 0xffffffffu, b1 = b >> 32;
    uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    uint64_t mid = (p00 >> 32) + (p01 & 0xffffffffu) + (p10 & 0xffffffffu);
    r.lo = (p00 & 0xffffffffu) | (mid << 32);
    r.hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
#endif
    return r;
}

static uint64_t uabs64(int64_t a) { return a < 0 ? (uint64_t)0 - (uint64_t)a : (uint64_t)a; }

ct_i128 ct_i128_mul(int64_t a, int64_t b)
{
    ct_i128 p = umul64(uabs64(a), uabs64(b));
    return ((a < 0) != (b < 0)) ? ct_i128_neg(p) : p;
}

ct_i128 ct_i128_mul128_64(ct_i128 a, int64_t b)
{
#ifdef CT_NATIVE_INT128
    return from_n(to_n(a) * (ct_n128)b);
#else
    int neg = 0;
    ct_i128 ua = a, r, lo, hi;
    uint64_t ub;
    if (ct_i128_sign(a) < 0) {
        ua = ct_i128_neg(a);
        neg = 1;
    }
    if (b < 0) {
        neg = !neg;
    }
    ub = uabs64(b);
    lo = umul64(ua.lo, ub);
    hi = umul64(ua.hi, ub); /* caller: |a*b| < 2^126, so hi.hi == 0 */
    r.lo = lo.lo;
    r.hi = lo.hi + hi.lo;
    return neg ? ct_i128_neg(r) : r;
#endif
}

/* Unsigned (hi:lo) / d with hi < d; returns the quotient, *rem the rest. */
static uint64_t udiv128(uint64_t hi, uint64_t lo, uint64_t d, uint64_t *rem)
{
#ifdef CT_NATIVE_INT128
    ct_nu128 n = ((ct_nu128)hi << 64) | (ct_nu128)lo;
    *rem = (uint64_t)(n % d);
    return (uint64_t)(n / d);
#else
    uint64_t q = 0u, r = hi;
    int i;
    /* bound: 64 iterations, one quotient bit each */
    for (i = 63; i >= 0; --i) {
        uint64_t carry = r >> 63;
        r = (r << 1) | ((lo >> (unsigned)i) & 1u);
        if (carry != 0u || r >= d) {
            r -= d;
            q |= (uint64_t)1 << (unsigned)i;
        }
    }
    *rem = r;
    return q;
#endif
}

int64_t ct_i128_floor_div(ct_i128 n, int64_t d)
{
    uint64_t rem, q;
    CT_ASSERT(d > 0);
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

uint64_t ct_isqrt64(uint64_t n)
{
    uint64_t res = 0u, bit = (uint64_t)1 << 62;
    /* bound: 32 iterations (one result bit each) */
    while (bit > n) {
        bit >>= 2;
    }
    while (bit != 0u) {
        if (n >= res + bit) {
            n -= res + bit;
            res = (res >> 1) + bit;
        } else {
            res >>= 1;
        }
        bit >>= 2;
    }
    return res;
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
    /* Newton from above: x0 = 2^ceil(bits/2) >= sqrt(n); x <- (x + n/x)/2
     * decreases monotonically to floor(sqrt(n)).  bound: 70 iterations
     * (quadratic convergence needs < 10 from this start). */
    {
        unsigned bits = 64u;
        uint64_t h = n.hi;
        while (h != 0u) {
            h >>= 1;
            bits++;
        }
        x = (bits + 1u) / 2u >= 64u ? ~(uint64_t)0 : ((uint64_t)1 << ((bits + 1u) / 2u));
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
