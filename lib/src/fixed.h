/*
 * fixed.h -- integer arithmetic helpers of the flight library.
 *
 * ct_i128 is a signed 128-bit integer held as two 64-bit halves (two's
 * complement).  Hosts with __int128 use it; others (Cortex-M) use the
 * portable code below.  Both are exact, so every result is bit-identical;
 * tests/test_fixed.c runs both against each other (CT_PORTABLE_INT128).
 * Scaling and overflow: callers keep |values| < 2^126 (the largest product
 * formed is < 2^123, see trace.c), so no operation here ever wraps.
 */
#ifndef CT_FIXED_H
#define CT_FIXED_H

#include <stdint.h>
#include <stddef.h>

#ifndef CT_ASSERT
#define CT_ASSERT(cond) ((void)0)
#endif

/* Keeps a rarely taken path with a large frame (the bent rays' 128-bit cell
 * test) out of its caller, so the common path's stack stays small; only a
 * hint, so compilers without it lose nothing but stack.                    */
#if defined(__GNUC__)
#define CT_NOINLINE __attribute__((noinline))
#else
#define CT_NOINLINE
#endif

/* Inlines a small helper shared by a few hot loops even under -Os, where
 * a call would cost more than the helper (a hint, as CT_NOINLINE).       */
#if defined(__GNUC__)
#define CT_ALWAYS_INLINE __attribute__((always_inline))
#else
#define CT_ALWAYS_INLINE
#endif

/* CT_ALWAYS_INLINE when optimising only: the coverage build (-O0) keeps
 * such a helper one function, with one set of branches.                  */
#if defined(__GNUC__) && defined(__OPTIMIZE__)
#define CT_OPT_INLINE __attribute__((always_inline))
#else
#define CT_OPT_INLINE
#endif

/* CT_OPT_INLINE for the 64 x 64 -> 128-bit product's four 32 x 32 -> 64-bit
 * ones, except on ARMv6-M (Cortex-M0), which has no such multiply: there
 * each is a library call and an inlined copy only adds flash.             */
#if defined(__ARM_ARCH_6M__)
#define CT_MUL_INLINE
#else
#define CT_MUL_INLINE CT_OPT_INLINE
#endif

/* A hint to start loading a cache line, on hosts with caches (GCC and clang
 * on x86-64 and AArch64); nothing on the flight MCUs, which have none (the
 * code around it is compiled out there: CT_HAVE_PREFETCH 0).               */
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__aarch64__))
#define CT_PREFETCH(a) __builtin_prefetch((a))
#define CT_HAVE_PREFETCH 1
#else
#define CT_PREFETCH(a) ((void)0)
#define CT_HAVE_PREFETCH 0
#endif

typedef struct {
    uint64_t hi;
    uint64_t lo;
} ct_i128;

extern const int64_t ct_cot_q32[256];
extern const uint32_t ct_crc32_table[4][256];
extern const uint32_t ct_isqrt_top8[192];

/* floor(a / b) for b > 0. */
static inline int64_t ct_floor_div(int64_t a, int64_t b)
{
    int64_t q = a / b;
    if ((a % b) != 0 && a < 0) {
        q -= 1;
    }
    return q;
}

/* floor(a / 2^n), n < 63, without relying on the implementation-defined
 * right shift of negative values (|a| < 2^63 - 2^n).  Inlined: the cone
 * walk's hot loop uses it (a call there costs Cortex-M4 5-10 % of a ray). */
CT_OPT_INLINE static inline int64_t ct_floor_shr(int64_t a, unsigned n)
{
    return a >= 0 ? a >> n : -(int64_t)(((uint64_t)(-a) + (((uint64_t)1 << n) - 1u)) >> n);
}

/* ceil(a / b) for b > 0. */
static inline int64_t ct_ceil_div(int64_t a, int64_t b)
{
    return -ct_floor_div(-a, b);
}

/* |a|, saturated: INT64_MIN (whose negation overflows) gives INT64_MAX, so
 * a range check |a| <= limit written with it refuses INT64_MIN.            */
static inline int64_t ct_abs64(int64_t a) { return a < 0 ? (a == INT64_MIN ? INT64_MAX : -a) : a; }
static inline int64_t ct_max64(int64_t a, int64_t b) { return a > b ? a : b; }
static inline int64_t ct_min64(int64_t a, int64_t b) { return a < b ? a : b; }

/* Number of significant bits of v (0 for 0): the count-leading-zeros
 * instruction where there is one (GCC and clang on x86-64, AArch64 and
 * Cortex-M3/M4/M7: LZCNT/BSR, CLZ), else ct_bitlen64_portable (Cortex-M0).
 * test_fixed checks both.                                                  */
static inline unsigned ct_bitlen64_portable(uint64_t v);
static inline unsigned ct_bitlen64(uint64_t v)
{
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__aarch64__) || defined(__ARM_FEATURE_CLZ)) && \
    !defined(CT_PORTABLE_BITLEN)
    return v == 0u ? 0u : 64u - (unsigned)__builtin_clzll(v);
#else
    return ct_bitlen64_portable(v);
#endif
}

/* The same by halving: six tests, no loop (compilers turn them into
 * conditional moves).                                                      */
static inline unsigned ct_bitlen64_portable(uint64_t v)
{
    unsigned n = 0u;
    if ((v >> 32) != 0u) { n += 32u; v >>= 32; }
    if ((v >> 16) != 0u) { n += 16u; v >>= 16; }
    if ((v >> 8) != 0u) { n += 8u; v >>= 8; }
    if ((v >> 4) != 0u) { n += 4u; v >>= 4; }
    if ((v >> 2) != 0u) { n += 2u; v >>= 2; }
    if ((v >> 1) != 0u) { n += 1u; v >>= 1; }
    return n + (unsigned)v;
}

/* Little-endian loads from byte buffers: alignment- and aliasing-safe.
 * ct_ld32 is one unaligned word load where gcc or clang target a
 * little-endian core that has them (x86, Cortex-M3/M4: GCC at -Os does not
 * merge the four byte loads there; the CRC's words, 8.15 -> 4.40
 * instructions per byte on Cortex-M4), four byte loads elsewhere
 * (Cortex-M0 faults on an unaligned word).                                 */
static inline uint32_t ct_ld16(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8);
}
static inline uint32_t ct_ld32(const uint8_t *p)
{
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__ &&                               \
    (defined(__x86_64__) || defined(__i386__) || defined(__ARM_FEATURE_UNALIGNED))
    uint32_t w;
    __builtin_memcpy(&w, p, 4u);
    return w;
#else
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
#endif
}
static inline int64_t ct_ld64s(const uint8_t *p)
{
    uint64_t v = (uint64_t)ct_ld32(p) | ((uint64_t)ct_ld32(p + 4) << 32);
    return (int64_t)v;
}

#if defined(__SIZEOF_INT128__) && !defined(CT_PORTABLE_INT128)
#define CT_NATIVE_INT128 1
__extension__ typedef __int128 ct_n128;
__extension__ typedef unsigned __int128 ct_nu128;
#endif

/* Core 128-bit operations, inline: from64, to64 (caller knows it fits),
 * add, neg, sub, shl (n < 64, no overflow by caller), sign and cmp (-1, 0,
 * +1), mul (64 x 64), mul128_64 (caller guarantees |a * b| < 2^126).     */
#ifdef CT_NATIVE_INT128

static inline ct_n128 ct_to_n(ct_i128 a)
{
    ct_nu128 u = ((ct_nu128)a.hi << 64) | (ct_nu128)a.lo;
    return (ct_n128)u;
}
static inline ct_i128 ct_from_n(ct_n128 v)
{
    ct_i128 r;
    ct_nu128 u = (ct_nu128)v;
    r.hi = (uint64_t)(u >> 64);
    r.lo = (uint64_t)u;
    return r;
}
#endif

static inline ct_i128 ct_i128_from64(int64_t a)
{
    ct_i128 r;
    r.lo = (uint64_t)a;
    r.hi = a < 0 ? ~(uint64_t)0 : 0u;
    return r;
}

static inline int64_t ct_i128_to64(ct_i128 a) { return (int64_t)a.lo; }

static inline ct_i128 ct_i128_add(ct_i128 a, ct_i128 b)
{
    ct_i128 r;
    r.lo = a.lo + b.lo;
    r.hi = a.hi + b.hi + (r.lo < a.lo ? 1u : 0u);
    return r;
}

static inline ct_i128 ct_i128_neg(ct_i128 a)
{
    ct_i128 r;
    r.lo = ~a.lo + 1u;
    r.hi = ~a.hi + (r.lo == 0u ? 1u : 0u);
    return r;
}

static inline ct_i128 ct_i128_sub(ct_i128 a, ct_i128 b) { return ct_i128_add(a, ct_i128_neg(b)); }

CT_OPT_INLINE static inline ct_i128 ct_i128_shl(ct_i128 a, unsigned n)
{
    ct_i128 r;
    if (n == 0u) {
        return a;
    }
    r.hi = (a.hi << n) | (a.lo >> (64u - n));
    r.lo = a.lo << n;
    return r;
}

static inline int ct_i128_sign(ct_i128 a)
{
    if ((a.hi >> 63) != 0u) {
        return -1;
    }
    return (a.hi | a.lo) != 0u ? 1 : 0;
}

static inline int ct_i128_cmp(ct_i128 a, ct_i128 b)
{
#ifdef CT_NATIVE_INT128
    ct_n128 x = ct_to_n(a), y = ct_to_n(b);
    return (x > y) - (x < y);
#else
    return ct_i128_sign(ct_i128_sub(a, b));
#endif
}

/* Unsigned 64 x 64 -> 128 from 32-bit halves: each partial sum is a 32 x
 * 32-bit product plus at most two 32-bit words, < 2^64 ((2^32 - 1)^2 + 2
 * (2^32 - 1) = 2^64 - 1).  On cores with the DSP extension (Cortex-M4,
 * M7, M33) the same four partial sums are one UMULL and three UMAAL (a x b
 * + c + d for 32-bit words, one instruction and one cycle each; GCC 12
 * does not emit UMAAL itself): 6 instructions for the product against
 * GCC's 12 for the C below.  The same bits (mcu_qemu_m4 and bench_m4
 * compare every result with the host's, test_fixed_portable the C below
 * with __int128). */
CT_MUL_INLINE static inline ct_i128 ct_umul64(uint64_t a, uint64_t b)
{
    ct_i128 r;
#ifdef CT_NATIVE_INT128
    ct_nu128 p = (ct_nu128)a * (ct_nu128)b;
    r.hi = (uint64_t)(p >> 64);
    r.lo = (uint64_t)p;
#elif defined(__ARM_FEATURE_DSP) && defined(__thumb2__)
    /* w1:w0 = a0 b0; w2:w1 = a1 b0 + w1; w3:w1 = a0 b1 + w1 (+ 0);
     * w3:w2 = a1 b1 + w2 + w3 */
    uint32_t a0 = (uint32_t)a, a1 = (uint32_t)(a >> 32), b0 = (uint32_t)b, b1 = (uint32_t)(b >> 32);
    uint32_t w0, w1, w2, w3;
    __asm__("umull %0, %1, %4, %6\n\t"
            "movs %2, #0\n\t"
            "umaal %1, %2, %5, %6\n\t"
            "movs %3, #0\n\t"
            "umaal %1, %3, %4, %7\n\t"
            "umaal %2, %3, %5, %7"
            : "=&r"(w0), "=&r"(w1), "=&r"(w2), "=&r"(w3)
            : "r"(a0), "r"(a1), "r"(b0), "r"(b1)
            : "cc");
    r.lo = ((uint64_t)w1 << 32) | w0;
    r.hi = ((uint64_t)w3 << 32) | w2;
#else
    uint32_t a0 = (uint32_t)a, a1 = (uint32_t)(a >> 32), b0 = (uint32_t)b, b1 = (uint32_t)(b >> 32);
    uint64_t p00 = (uint64_t)a0 * b0;
    uint64_t p10 = (uint64_t)a1 * b0 + (p00 >> 32);
    uint64_t p01 = (uint64_t)a0 * b1 + (p10 & 0xffffffffu);
    r.lo = (p01 << 32) | (p00 & 0xffffffffu);
    r.hi = (uint64_t)a1 * b1 + (p10 >> 32) + (p01 >> 32);
#endif
    return r;
}

/* a b for |a|, |b| < 2^31 (the caller's bound): a 32 x 32 -> 64-bit
 * product, one SMULL or SMLAL on Cortex-M4, where a 64-bit one is three
 * multiplies. */
static inline int64_t ct_smul32(int64_t a, int64_t b) { return (int64_t)(int32_t)a * (int32_t)b; }

static inline uint64_t ct_uabs64(int64_t a) { return a < 0 ? (uint64_t)0 - (uint64_t)a : (uint64_t)a; }

/* a b, 64 x 64 -> 128 bits, always inlined when optimising, except on
 * Cortex-M0 (CT_MUL_INLINE), where each 32 x 32-bit product is a library
 * call.  On Cortex-M4 the UMAAL product (ct_umul64) and the sign
 * corrections are ~16 instructions in line against a call that returns
 * the 16-byte result through memory: 5-6 % fewer instructions per pixel
 * and ray for 6.7 KB more flash (bench_m4; docs/benchmarks.md).          */
CT_MUL_INLINE static inline ct_i128 ct_i128_mul(int64_t a, int64_t b)
{
#ifdef CT_NATIVE_INT128
    return ct_from_n((ct_n128)a * (ct_n128)b);
#else
    /* the unsigned product of the two's complement words, less 2^64 b for
     * a < 0 and 2^64 a for b < 0 (mod 2^128: a = a_u - 2^64 [a < 0]) */
    ct_i128 p = ct_umul64((uint64_t)a, (uint64_t)b);
    p.hi -= ((uint64_t)b & ((uint64_t)0 - (uint64_t)(a < 0))) + ((uint64_t)a & ((uint64_t)0 - (uint64_t)(b < 0)));
    return p;
#endif
}

static inline ct_i128 ct_i128_mul128_64(ct_i128 a, int64_t b)
{
#ifdef CT_NATIVE_INT128
    return ct_from_n(ct_to_n(a) * (ct_n128)b);
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
    ub = ct_uabs64(b);
    lo = ct_umul64(ua.lo, ub);
    hi = ct_umul64(ua.hi, ub); /* caller: |a*b| < 2^126, so hi.hi == 0 */
    r.lo = lo.lo;
    r.hi = lo.hi + hi.lo;
    return neg ? ct_i128_neg(r) : r;
#endif
}


/* |a| for a > -2^127.                                                       */
CT_OPT_INLINE static inline ct_i128 ct_i128_abs(ct_i128 a) { return ct_i128_sign(a) < 0 ? ct_i128_neg(a) : a; }

/* Number of significant bits of a non-negative 128-bit value (0 for 0).    */
static inline unsigned ct_i128_bits(ct_i128 a)
{
    return a.hi != 0u ? ct_bitlen64(a.hi) + 64u : ct_bitlen64(a.lo);
}

/* floor(a / 2^n) of a 128-bit value, 1 <= n <= 63 (arithmetic shift
 * written with unsigned operations only); never overflows.                 */
static inline ct_i128 ct_i128_sar(ct_i128 a, unsigned n)
{
    ct_i128 r;
    r.lo = (a.lo >> n) | (a.hi << (64u - n));
    r.hi = (a.hi >> n) | (((a.hi >> 63) != 0u) ? ~(~(uint64_t)0 >> n) : 0u);
    return r;
}

/* Rounded shifts and divisions of 128-bit values, all half up (ties toward
 * +infinity): round(x) = floor(x + 1/2).  The one family every file uses.  */

/* round(v / 2^n), 1 <= n <= 126: floor((v + 2^(n-1)) / 2^n) by an
 * arithmetic shift of the two words.  Caller: v + 2^(n-1) does not wrap
 * (|v| <= 2^126 ensures it) and the result fits in int64 (only its low 64
 * bits are returned).                                                            */
CT_OPT_INLINE static inline int64_t ct_i128_round_shr(ct_i128 v, unsigned n)
{
    ct_i128 h = ct_i128_from64(1);
    ct_i128 r;
    uint64_t neg;
    h = n - 1u >= 64u ? ct_i128_shl(ct_i128_shl(h, 63u), n - 64u) : ct_i128_shl(h, n - 1u);
    r = ct_i128_add(v, h);
    neg = (r.hi >> 63) != 0u ? ~(uint64_t)0 : 0u;
    if (n >= 64u) {
        /* (hi >> (n - 64)) with the sign's bits shifted in */
        return (int64_t)(((r.hi ^ neg) >> (n - 64u)) ^ neg);
    }
    return (int64_t)((r.lo >> n) | (r.hi << (64u - n)));
}

/* round(a * b / 2^q), 1 <= q <= 63, through the 64 x 64 -> 128-bit
 * product (|a * b| <= 2^126 for any int64 operands, so the sum cannot
 * wrap); the result must fit in int64 (caller's bound at each use).        */
CT_OPT_INLINE static inline int64_t ct_mul_shr(int64_t a, int64_t b, unsigned q)
{
    return ct_i128_round_shr(ct_i128_mul(a, b), q);
}

/* floor(n / d) for d > 0 and |quotient| < 2^63.                             */
int64_t ct_i128_floor_div(ct_i128 n, int64_t d);
/* floor(n / d) for d > 0, saturated to [-2^62, 2^62].                      */
int64_t ct_i128_floor_div_sat(ct_i128 n, int64_t d);

/* round(n / d) = floor((2 n + d) / (2 d)) for 0 < d < 2^62 (2 d fits) and
 * |n| < 2^125 (2 n + d fits); the quotient must satisfy |q| < 2^63 -- the
 * caller checks it (ct_i128_round_div_lim, or its own test) or bounds it. */
static inline int64_t ct_i128_round_div(ct_i128 n, int64_t d)
{
    return ct_i128_floor_div(ct_i128_add(ct_i128_shl(n, 1u), ct_i128_from64(d)), 2 * d);
}

/* round(n / d) as above, saturated to [-2^62, 2^62] (no bound on the
 * quotient; 0 < d < 2^62, |n| < 2^125).                                     */
static inline int64_t ct_i128_round_div_sat(ct_i128 n, int64_t d)
{
    return ct_i128_floor_div_sat(ct_i128_add(ct_i128_shl(n, 1u), ct_i128_from64(d)), 2 * d);
}

/* round(n / d) for d in (0, 2^61], checked: returns 0 (and leaves *q
 * alone) when |n| > lim * d, lim in [0, 2^61], i.e. when |n / d| would
 * exceed lim; otherwise |n| <= 2^122, the quotient fits, returns 1.       */
static inline int ct_i128_round_div_lim(ct_i128 n, int64_t d, int64_t lim, int64_t *q)
{
    if (ct_i128_cmp(ct_i128_abs(n), ct_i128_mul(lim, d)) > 0) {
        return 0;
    }
    *q = ct_i128_round_div(n, d);
    return 1;
}
/* floor(sqrt(n)) for n < 2^127 (0 for n <= 0); no 64-bit division.          */
uint64_t ct_i128_isqrt(ct_i128 n);
/* floor(sqrt(n)) for 64-bit n; only 32-bit divisions.                       */
uint64_t ct_isqrt64(uint64_t n);

/* Integer cos/sin of 2*pi*k/n in units of 2^30 (|error| < 2^-28 of full
 * scale); exact on axes and diagonals and symmetric, deterministic.       */
void ct_dir_of_fraction(uint32_t k, uint32_t n, int32_t *cx, int32_t *sy);

#endif /* CT_FIXED_H */
