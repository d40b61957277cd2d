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

typedef struct {
    uint64_t hi;
    uint64_t lo;
} ct_i128;

extern const int64_t ct_cot_q32[256];
extern const uint32_t ct_crc32_table[256];

/* floor(a / b) for b > 0. */
static inline int64_t ct_floor_div(int64_t a, int64_t b)
{
    int64_t q = a / b;
    if ((a % b) != 0 && a < 0) {
        q -= 1;
    }
    return q;
}

/* ceil(a / b) for b > 0. */
static inline int64_t ct_ceil_div(int64_t a, int64_t b)
{
    return -ct_floor_div(-a, b);
}

static inline int64_t ct_abs64(int64_t a) { return a < 0 ? -a : a; }
static inline int64_t ct_max64(int64_t a, int64_t b) { return a > b ? a : b; }
static inline int64_t ct_min64(int64_t a, int64_t b) { return a < b ? a : b; }

/* Little-endian loads from byte buffers: portable, alignment- and
 * aliasing-safe; compilers merge them into one load where allowed.         */
static inline uint32_t ct_ld16(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8);
}
static inline uint32_t ct_ld32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}
static inline int64_t ct_ld64s(const uint8_t *p)
{
    uint64_t v = (uint64_t)ct_ld32(p) | ((uint64_t)ct_ld32(p + 4) << 32);
    return (int64_t)v;
}

ct_i128 ct_i128_from64(int64_t a);
ct_i128 ct_i128_mul(int64_t a, int64_t b);
ct_i128 ct_i128_add(ct_i128 a, ct_i128 b);
ct_i128 ct_i128_sub(ct_i128 a, ct_i128 b);
ct_i128 ct_i128_neg(ct_i128 a);
ct_i128 ct_i128_shl(ct_i128 a, unsigned n); /* n < 64, no overflow by caller */
int ct_i128_sign(ct_i128 a);                /* -1, 0, +1 */
int ct_i128_cmp(ct_i128 a, ct_i128 b);      /* -1, 0, +1 */
/* a * b with a 128-bit, b 64-bit; caller guarantees |a * b| < 2^126. */
ct_i128 ct_i128_mul128_64(ct_i128 a, int64_t b);
/* floor(n / d) for d > 0 and |quotient| < 2^63.                             */
int64_t ct_i128_floor_div(ct_i128 n, int64_t d);
/* floor(n / d) for d > 0, saturated to [-2^62, 2^62].                      */
int64_t ct_i128_floor_div_sat(ct_i128 n, int64_t d);
/* floor(sqrt(n)) for 0 <= n < 2^126.                                         */
uint64_t ct_i128_isqrt(ct_i128 n);
/* floor(sqrt(n)) for 64-bit n.                                               */
uint64_t ct_isqrt64(uint64_t n);
/* low 64 bits as a signed value (caller knows it fits).                     */
int64_t ct_i128_to64(ct_i128 a);

/* Integer cos/sin of 2*pi*k/n in units of 2^30 (|error| < 2^-28 of full
 * scale); exact on axes and diagonals and symmetric, deterministic.       */
void ct_dir_of_fraction(uint32_t k, uint32_t n, int32_t *cx, int32_t *sy);

#endif /* CT_FIXED_H */
