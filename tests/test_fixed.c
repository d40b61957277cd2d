/*
 * test_fixed.c -- fixed-point helpers against independent references:
 * 128-bit arithmetic against the compiler's __int128 (the library is built
 * twice, native and CT_PORTABLE_INT128, and this test is compiled and
 * linked with each: fixed.h's inline operations too), integer
 * square roots against long double, the cot table against long double cot,
 * sector boundary vectors against cos/sin (exact on axes and diagonals),
 * CRC-32 against the standard check value, sector selection against the
 * closed-wedge test.  Hard-value tables plus seeded random cases.
 */
#include <math.h>

#include "conetrace.h"
#include "fixed.h"
#include "harness.h"

__extension__ typedef __int128 i128;

static i128 to_n(ct_i128 a) { return (i128)(((unsigned __int128)a.hi << 64) | a.lo); }

static ct_rng rng;

static int64_t rand_bits(int bits)
{
    uint64_t v = ct_rng_u64(&rng);
    int64_t x;
    if (bits >= 63) {
        x = (int64_t)(v >> 1);
    } else {
        x = (int64_t)(v & (((uint64_t)1 << bits) - 1));
    }
    return (ct_rng_u64(&rng) & 1) ? -x : x;
}

static void test_i128_hard_values(void)
{
    const int64_t hard[] = {0, 1, -1, 2, -2, INT64_MAX, INT64_MIN + 1, (int64_t)1 << 62, -((int64_t)1 << 62),
                            ((int64_t)1 << 32) - 1, (int64_t)1 << 32, -((int64_t)1 << 32), 0x7fffffffll, -0x80000000ll,
                            INT64_MIN, -((int64_t)1 << 32) + 1, ((int64_t)1 << 32) + 1, -0x1ffffffffll, INT64_MIN + 0xffffffffll};
    size_t n = sizeof hard / sizeof hard[0], a, b;
    for (a = 0; a < n; ++a) {
        for (b = 0; b < n; ++b) {
            ct_i128 p = ct_i128_mul(hard[a], hard[b]);
            i128 e = (i128)hard[a] * hard[b];
            TEST_ASSERT_MSG(to_n(p) == e, "mul %lld * %lld", (long long)hard[a], (long long)hard[b]);
            TEST_ASSERT(to_n(ct_i128_add(ct_i128_from64(hard[a]), ct_i128_from64(hard[b]))) == (i128)hard[a] + hard[b]);
            TEST_ASSERT(to_n(ct_i128_sub(ct_i128_from64(hard[a]), ct_i128_from64(hard[b]))) == (i128)hard[a] - hard[b]);
            TEST_ASSERT(ct_i128_cmp(ct_i128_from64(hard[a]), ct_i128_from64(hard[b])) ==
                        (hard[a] < hard[b] ? -1 : hard[a] > hard[b]));
            if (hard[b] > 0) {
                /* floor division, including negative numerators */
                i128 q = (i128)hard[a] / hard[b];
                if ((i128)hard[a] % hard[b] != 0 && hard[a] < 0) q -= 1;
                TEST_ASSERT(ct_i128_floor_div(ct_i128_from64(hard[a]), hard[b]) == (int64_t)q);
                TEST_ASSERT(ct_floor_div(hard[a], hard[b]) == (int64_t)q);
            }
        }
    }
    TEST_ASSERT(ct_i128_sign(ct_i128_from64(0)) == 0);
    TEST_ASSERT(ct_i128_sign(ct_i128_from64(-5)) == -1);
    TEST_ASSERT(ct_i128_sign(ct_i128_shl(ct_i128_from64(1), 63)) == 1);
}

static void test_i128_random(void)
{
    int k;
    ct_rng_seed(&rng, ct_test_seed());
    /* bound: fixed count */
    for (k = 0; k < 200000; ++k) {
        int64_t a = rand_bits((int)ct_rng_range(&rng, 1, 63)), b = rand_bits((int)ct_rng_range(&rng, 1, 63));
        int64_t c = rand_bits((int)ct_rng_range(&rng, 1, 62));
        ct_i128 p = ct_i128_mul(a, b);
        i128 e = (i128)a * b;
        unsigned sh = (unsigned)ct_rng_range(&rng, 0, 40);
        TEST_ASSERT_MSG(to_n(p) == e, "mul %lld %lld", (long long)a, (long long)b);
        TEST_ASSERT(to_n(ct_i128_neg(p)) == -e);
        /* shl within range: a < 2^62 * 2^-sh */
        {
            int64_t s = a >> (sh + 1);
            TEST_ASSERT(to_n(ct_i128_shl(ct_i128_from64(s), sh)) == (i128)s * ((i128)1 << sh));
        }
        /* mul128_64 with |a*b*c| < 2^126 */
        {
            int64_t a2 = a >> 32, b2 = b >> 2, c2 = c >> 2;
            ct_i128 q = ct_i128_mul128_64(ct_i128_mul(a2, b2), c2);
            TEST_ASSERT(to_n(q) == (i128)a2 * b2 * c2);
        }
        if (c > 0) {
            /* floor(p / c) when it fits in 63 bits */
            i128 q = e / c;
            if (e % c != 0 && e < 0) q -= 1;
            if (q < ((i128)1 << 62) && q > -((i128)1 << 62)) {
                TEST_ASSERT_MSG(ct_i128_floor_div(p, c) == (int64_t)q, "floor_div");
                TEST_ASSERT(ct_i128_floor_div_sat(p, c) == (int64_t)q);
            } else {
                TEST_ASSERT(ct_i128_floor_div_sat(p, c) == (q > 0 ? ((int64_t)1 << 62) : -((int64_t)1 << 62)));
            }
        }
    }
}

/* The 128-by-64-bit division's digit paths (fixed.c udiv128: on targets
 * without a 128-bit type, Knuth's algorithm D in base 2^32, each digit
 * estimated from the top digits and corrected at most twice): divisors,
 * quotients and remainders built from the digits where the estimates need
 * correcting -- top divisor digits just above 2^31 and at 2^32 - 1 after
 * normalisation, second digits 0, 1 and all ones, quotient digits 0, 1,
 * 2^31 and all ones, remainders 0, 1 and d - 1 -- each n = q d + r (and
 * -n) against the native quotient; plus random ones whose remainders run
 * high (partial remainders with a top digit equal to the divisor's). */
static void test_div_digits(void)
{
    static const uint64_t top[] = {0x80000000u, 0x80000001u, 0xC0000000u, 0xFFFFFFFEu, 0xFFFFFFFFu};
    static const uint64_t low[] = {0u, 1u, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFEu, 0xFFFFFFFFu};
    static const uint64_t qd[] = {0u, 1u, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFFu};
    long n_cases = 0;
    unsigned a, b, c, e, f, sh;
    for (sh = 1u; sh <= 33u; sh += 4u) {                          /* the normalisation shift */
        for (a = 0u; a < sizeof top / sizeof top[0]; ++a) {
            for (b = 0u; b < sizeof low / sizeof low[0]; ++b) {
                uint64_t d = ((top[a] << 32) | low[b]) >> sh; /* < 2^63 */
                if (d == 0u) continue;
                for (c = 0u; c < sizeof qd / sizeof qd[0]; ++c) {
                    for (e = 0u; e < sizeof qd / sizeof qd[0]; ++e) {
                        uint64_t q = ((qd[c] << 32) | qd[e]) >> 2; /* < 2^62 */
                        for (f = 0u; f < 3u; ++f) {
                            uint64_t r = f == 0u ? 0u : (f == 1u ? 1u % d : d - 1u);
                            i128 n = (i128)q * (i128)d + (i128)r;
                            ct_i128 nn = ct_i128_from64(0);
                            nn.hi = (uint64_t)(n >> 64);
                            nn.lo = (uint64_t)n;
                            TEST_ASSERT_MSG(ct_i128_floor_div(nn, (int64_t)d) == (int64_t)q,
                                            "floor_div(q %llx d %llx r %llx)", (unsigned long long)q,
                                            (unsigned long long)d, (unsigned long long)r);
                            TEST_ASSERT(ct_i128_floor_div(ct_i128_neg(nn), (int64_t)d) ==
                                        -(int64_t)q - (r != 0u ? 1 : 0));
                            n_cases++;
                        }
                    }
                }
            }
        }
    }
    /* random: q's digits and d's digits random, r = d - 1 - small, so the
     * partial remainders run high */
    ct_rng_seed(&rng, ct_test_seed() * 31 + 7);
    for (a = 0u; a < 200000u; ++a) {
        uint64_t d = (ct_rng_u64(&rng) >> (unsigned)ct_rng_range(&rng, 1, 31)) | ((uint64_t)1 << 32);
        uint64_t q = ct_rng_u64(&rng) >> 2;
        uint64_t r = d - 1u - (uint64_t)ct_rng_range(&rng, 0, 3) % d;
        i128 n = (i128)q * (i128)d + (i128)r;
        ct_i128 nn = ct_i128_from64(0);
        nn.hi = (uint64_t)(n >> 64);
        nn.lo = (uint64_t)n;
        TEST_ASSERT_MSG(ct_i128_floor_div(nn, (int64_t)d) == (int64_t)q, "floor_div(q %llx d %llx r %llx)",
                        (unsigned long long)q, (unsigned long long)d, (unsigned long long)r);
        n_cases++;
    }
    printf("  %ld divisions\n", n_cases);
}

/* ct_bitlen64 against counting bits one at a time: every power of two and
 * its neighbours, and random values of every length. */
static unsigned bitlen_ref(uint64_t v)
{
    unsigned n = 0u;
    while (v != 0u) {
        v >>= 1;
        n++;
    }
    return n;
}

static void test_bitlen(void)
{
    ct_rng r;
    unsigned k;
    long i;
    TEST_ASSERT_EQUAL_INT(0, (int)ct_bitlen64(0u));
    for (k = 0u; k < 64u; ++k) {
        uint64_t p = (uint64_t)1 << k;
        TEST_ASSERT_EQUAL_INT((int)bitlen_ref(p), (int)ct_bitlen64(p));
        TEST_ASSERT_EQUAL_INT((int)bitlen_ref(p - 1u), (int)ct_bitlen64(p - 1u));
        TEST_ASSERT_EQUAL_INT((int)bitlen_ref(p + 1u), (int)ct_bitlen64(p + 1u));
        TEST_ASSERT_EQUAL_INT((int)bitlen_ref(p), (int)ct_bitlen64_portable(p));
        TEST_ASSERT_EQUAL_INT((int)bitlen_ref(p - 1u), (int)ct_bitlen64_portable(p - 1u));
        TEST_ASSERT_EQUAL_INT((int)bitlen_ref(p + 1u), (int)ct_bitlen64_portable(p + 1u));
    }
    TEST_ASSERT_EQUAL_INT(0, (int)ct_bitlen64_portable(0u));
    TEST_ASSERT_EQUAL_INT(64, (int)ct_bitlen64(~(uint64_t)0));
    ct_rng_seed(&r, ct_test_seed() + 41u);
    for (i = 0; i < 100000; ++i) {
        uint64_t v = ct_rng_u64(&r) >> ct_rng_range(&r, 0, 63);
        TEST_ASSERT_EQUAL_INT((int)bitlen_ref(v), (int)ct_bitlen64(v));
        TEST_ASSERT_EQUAL_INT((int)bitlen_ref(v), (int)ct_bitlen64_portable(v));
    }
}

static void test_isqrt(void)
{
    const uint64_t hard[] = {0, 1, 2, 3, 4, 15, 16, 17, 0xffffffffull, 0x100000000ull, 0xfffffffe00000001ull,
                             0xffffffffffffffffull, (uint64_t)1 << 62, ((uint64_t)1 << 62) - 1};
    size_t k;
    for (k = 0; k < sizeof hard / sizeof hard[0]; ++k) {
        uint64_t r = ct_isqrt64(hard[k]);
        TEST_ASSERT_MSG((unsigned __int128)r * r <= hard[k] && (unsigned __int128)(r + 1) * (r + 1) > hard[k],
                        "isqrt64(%llu) = %llu", (unsigned long long)hard[k], (unsigned long long)r);
    }
    ct_rng_seed(&rng, ct_test_seed() + 1);
    /* 64-bit, every bit length, with perfect squares and their neighbours
     * (the table-started Newton iteration must land exactly on each) */
    for (k = 0; k < 300000; ++k) {
        unsigned bits = (unsigned)ct_rng_range(&rng, 1, 64);
        uint64_t n = bits == 64 ? ct_rng_u64(&rng) : ct_rng_u64(&rng) & (((uint64_t)1 << bits) - 1u);
        uint64_t r;
        if (k % 3 == 0) {
            uint64_t s = n >> (bits / 2u);
            s &= 0xffffffffu;
            n = s * s + (uint64_t)(int64_t)ct_rng_range(&rng, -1, 1);
        }
        r = ct_isqrt64(n);
        TEST_ASSERT_MSG((unsigned __int128)r * r <= n && (unsigned __int128)(r + 1) * (r + 1) > n,
                        "isqrt64(%llu) = %llu", (unsigned long long)n, (unsigned long long)r);
    }
    /* each start-table segment's ends (its top eight bits k = 64..255),
     * where the table's start is farthest from the root, at every scale,
     * and the 128-bit values with those top bits (N_hi's root) */
    for (k = 64; k < 256; ++k) {
        unsigned e;
        for (e = 0; e < 32; ++e) {
            uint64_t lo = ((uint64_t)k << 56) >> (2u * e), hi = (((uint64_t)(k + 1) << 56) - 1u) >> (2u * e);
            uint64_t r0 = ct_isqrt64(lo), r1 = ct_isqrt64(hi);
            ct_i128 v;
            uint64_t r;
            unsigned __int128 n;
            TEST_ASSERT_MSG((unsigned __int128)r0 * r0 <= lo && (unsigned __int128)(r0 + 1) * (r0 + 1) > lo,
                            "isqrt64 segment %d start", (int)k);
            TEST_ASSERT_MSG((unsigned __int128)r1 * r1 <= hi && (unsigned __int128)(r1 + 1) * (r1 + 1) > hi,
                            "isqrt64 segment %d end", (int)k);
            /* 2^126 .. 2^127 - 1 and below: positive 128-bit values */
            n = ((unsigned __int128)(k < 128 ? hi : hi >> 1) << 64 | ~(uint64_t)0) >> (2u * e);
            v.hi = (uint64_t)(n >> 64);
            v.lo = (uint64_t)n;
            r = ct_i128_isqrt(v);
            TEST_ASSERT_MSG((unsigned __int128)r * r <= n && ((unsigned __int128)r + 1) * ((unsigned __int128)r + 1) > n,
                            "isqrt128 segment %d scale %d", (int)k, (int)e);
        }
    }
    {
        /* the largest 128-bit value and squares at the top of the range */
        const uint64_t roots[] = {((uint64_t)1 << 63) - 1, (uint64_t)3037000499u * 4294967296u, (uint64_t)1 << 62,
                                  ((uint64_t)1 << 62) + 1, ((uint64_t)1 << 32) + 1, 0xb504f333f9de6484ull};
        unsigned __int128 n = ((unsigned __int128)1 << 127) - 1;
        ct_i128 v;
        uint64_t r;
        v.hi = (uint64_t)(n >> 64);
        v.lo = (uint64_t)n;
        r = ct_i128_isqrt(v);
        TEST_ASSERT_MSG(r == 0xb504f333f9de6484ull, "isqrt128(2^127 - 1) = %llu", (unsigned long long)r);
        /* all ones of an even length: the root 2^j - 1, where the Newton
         * step from below reaches 2^j (caps at 2^32 and 2^64) */
        for (k = 1; k <= 63; ++k) {
            n = ((unsigned __int128)1 << (2u * k)) - 1u;
            v.hi = (uint64_t)(n >> 64);
            v.lo = (uint64_t)n;
            r = ct_i128_isqrt(v);
            TEST_ASSERT_MSG(r == ((uint64_t)1 << k) - 1u, "isqrt128(2^%d - 1) = %llu", (int)(2u * k), (unsigned long long)r);
            if (k <= 32) {
                r = ct_isqrt64(v.lo);
                TEST_ASSERT_MSG(r == ((uint64_t)1 << k) - 1u, "isqrt64(2^%d - 1)", (int)(2u * k));
            }
        }
        for (k = 0; k < sizeof roots / sizeof roots[0]; ++k) {
            int d;
            for (d = -1; d <= 1; ++d) {
                n = (unsigned __int128)roots[k] * roots[k] + (unsigned __int128)(__int128)d;
                if (n >> 127) {
                    continue;
                }
                v.hi = (uint64_t)(n >> 64);
                v.lo = (uint64_t)n;
                r = ct_i128_isqrt(v);
                TEST_ASSERT_MSG(r == roots[k] - (d < 0 ? 1u : 0u), "isqrt128 of %llu^2 %+d", (unsigned long long)roots[k],
                                d);
            }
        }
    }
    for (k = 0; k < 100000; ++k) {
        /* 128-bit: n < 2^127, including perfect squares and their neighbours */
        unsigned bits = (unsigned)ct_rng_range(&rng, 1, 127);
        unsigned __int128 n = ((unsigned __int128)ct_rng_u64(&rng) << 64) | ct_rng_u64(&rng);
        uint64_t r;
        ct_i128 v;
        n &= (((unsigned __int128)1) << bits) - 1;
        if (k % 3 == 0) {
            uint64_t s = (uint64_t)(n >> (bits / 2 + 1)) & (((uint64_t)1 << 62) - 1);
            n = (unsigned __int128)s * s + (unsigned __int128)(int)ct_rng_range(&rng, -1, 1);
            if (n >> 127) continue;
        }
        v.hi = (uint64_t)(n >> 64);
        v.lo = (uint64_t)n;
        r = ct_i128_isqrt(v);
        TEST_ASSERT_MSG((unsigned __int128)r * r <= n && ((unsigned __int128)r + 1) * ((unsigned __int128)r + 1) > n,
                        "isqrt128 wrong at k=%d", (int)k);
    }
}

static void test_cot_table(void)
{
    int k;
    int64_t q16[256];
    uint8_t ok[256];
    for (k = 1; k < 256; ++k) {
        long double ang = (long double)k * 3.14159265358979323846264338327950288L / 256.0L;
        long double c = cosl(ang) / sinl(ang) * 4294967296.0L;
        /* rounded up: entry >= exact, entry - exact < 1 (allow 1e-6 for long double) */
        TEST_ASSERT_MSG((long double)ct_cot_q32[k] >= c - 1e-3L && (long double)ct_cot_q32[k] - c < 1.0L + 1e-3L,
                        "cot_q32[%d] = %lld vs %.3Lf", k, (long long)ct_cot_q32[k], c);
        if (k > 1) TEST_ASSERT(ct_cot_q32[k] < ct_cot_q32[k - 1]);
    }
    TEST_ASSERT(ct_cot_q32[128] == 0);
    /* derived per-package table: 30 m posting, 0.0625 m per LSB */
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_cot_table(30000000000ll, 62500000ll, q16, ok));
    TEST_ASSERT(!ok[0]);
    for (k = 1; k < 256; ++k) {
        long double ang = (long double)k * 3.14159265358979323846264338327950288L / 256.0L;
        long double c = cosl(ang) / sinl(ang) * 30.0L / 0.0625L * 65536.0L;
        if (!ok[k]) {
            TEST_ASSERT(c > (long double)CT_COT_MAX_Q16 - 2);
            continue;
        }
        TEST_ASSERT_MSG((long double)q16[k] >= c - 1e-2L && (long double)q16[k] - c < 2.0L, "cot_q16[%d]", k);
        if (k > 1 && ok[k - 1]) TEST_ASSERT(q16[k] <= q16[k - 1]);
    }
    TEST_ASSERT_EQUAL_INT(CT_ERR_GEOREF, ct_cot_table(0, 1, q16, ok));
    TEST_ASSERT_EQUAL_INT(CT_ERR_GEOREF, ct_cot_table(1, 0, q16, ok));
}

static void test_sector_boundaries(void)
{
    uint32_t n, k;
    for (n = 1; n <= CT_MAX_SECTORS; ++n) {
        for (k = 0; k <= n; ++k) {
            int32_t x, y;
            long double a = 2.0L * 3.14159265358979323846264338327950288L * k / n;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_sector_boundary(n, k, &x, &y));
            TEST_ASSERT_MSG(fabsl(x - cosl(a) * 1073741824.0L) < 4 && fabsl(y - sinl(a) * 1073741824.0L) < 4,
                            "boundary %u/%u = (%d, %d)", k, n, x, y);
            if ((8 * k) % n == 0) {
                /* axes and diagonals: exact */
                uint32_t o = (8 * k / n) % 8;
                int32_t ax[8] = {1, 1, 0, -1, -1, -1, 0, 1}, ay[8] = {0, 1, 1, 1, 0, -1, -1, -1};
                if (o % 2 == 0) {
                    TEST_ASSERT(x == ax[o] * (1 << 30) && y == ay[o] * (1 << 30));
                } else {
                    TEST_ASSERT(x == ax[o] * 759250125 && y == ay[o] * 759250125);
                }
            }
        }
    }
    {
        int32_t bx, by;
        TEST_ASSERT_EQUAL_INT(CT_ERR_SECTORS, ct_sector_boundary(0, 0, &bx, &by));
        TEST_ASSERT_EQUAL_INT(CT_ERR_SECTORS, ct_sector_boundary(65, 0, &bx, &by));
        TEST_ASSERT_EQUAL_INT(CT_ERR_SECTORS, ct_sector_boundary(8, 9, &bx, &by));
    }
}

/* CRC-32 (IEEE) one bit at a time from the reflected polynomial: no tables */
static uint32_t crc32_bitwise(uint32_t crc, const uint8_t *p, size_t n)
{
    uint32_t c = ~crc;
    size_t i;
    int b;
    for (i = 0; i < n; ++i) {
        c ^= p[i];
        for (b = 0; b < 8; ++b) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return ~c;
}

static void test_crc32(void)
{
    uint32_t c;
    const uint8_t msg[] = "123456789";
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_crc32(0, msg, 9, &c));
    TEST_ASSERT_EQUAL_UINT64(0xCBF43926u, c);
    /* incremental == one shot */
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_crc32(0, msg, 4, &c));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_crc32(c, msg + 4, 5, &c));
    TEST_ASSERT_EQUAL_UINT64(0xCBF43926u, c);
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_crc32(0, NULL, 3, &c));
    {
        /* the sliced tables and word loads against the polynomial bit by bit:
         * every length 0..70 at every start modulo 8 (unaligned words, the
         * tail of 0..3 bytes), chained at every split, and 100,003 bytes */
        static uint8_t buf[100011];
        size_t k, off, len, cut;
        ct_rng_seed(&rng, ct_test_seed() + 5u);
        for (k = 0; k < sizeof buf; ++k) buf[k] = (uint8_t)ct_rng_u64(&rng);
        for (off = 0; off < 8u; ++off)
            for (len = 0; len <= 70u; ++len) {
                uint32_t want = crc32_bitwise(0u, buf + off, len), got = 0u;
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_crc32(0u, buf + off, len, &got));
                TEST_ASSERT_EQUAL_UINT64(want, got);
                for (cut = 0; cut <= len; ++cut) {
                    TEST_ASSERT_EQUAL_INT(CT_OK, ct_crc32(0u, buf + off, cut, &got));
                    TEST_ASSERT_EQUAL_INT(CT_OK, ct_crc32(got, buf + off + cut, len - cut, &got));
                    TEST_ASSERT_EQUAL_UINT64(want, got);
                }
            }
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_crc32(0u, buf + 3, 100003u, &c));
        TEST_ASSERT_EQUAL_UINT64(crc32_bitwise(0u, buf + 3, 100003u), c);
    }
}

/* ct_sector_of picks a sector whose closed wedge holds the direction, and
 * the lowest such sector. */
static void test_sector_of(void)
{
    static ct_package p; /* only sectors and boundaries are used */
    uint32_t n, s, in, s2;
    int k;
    ct_rng_seed(&rng, ct_test_seed() + 2);
    for (n = 1; n <= CT_MAX_SECTORS; ++n) {
        p.sectors = n;
        for (k = 0; k <= (int)n; ++k) ct_sector_boundary(n, (uint32_t)k, &p.bound_x[k], &p.bound_y[k]);
        for (k = 0; k < 3000; ++k) {
            int64_t dx, dy;
            int kind = k % 4;
            if (kind == 0) {
                /* exactly on a boundary vector (scaled down exactly when possible) */
                uint32_t b = (uint32_t)ct_rng_range(&rng, 0, n);
                dx = p.bound_x[b];
                dy = p.bound_y[b];
            } else if (kind == 1) {
                int64_t ax[8] = {1, 1, 0, -1, -1, -1, 0, 1}, ay[8] = {0, 1, 1, 1, 0, -1, -1, -1};
                int o = (int)ct_rng_range(&rng, 0, 7);
                int64_t m = ct_rng_range(&rng, 1, 1 << 26);
                dx = ax[o] * m;
                dy = ay[o] * m;
            } else {
                dx = ct_rng_range(&rng, -(1 << 26), 1 << 26);
                dy = ct_rng_range(&rng, -(1 << 26), 1 << 26);
                if (dx == 0 && dy == 0) dx = 1;
            }
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_sector_of(&p, dx, dy, &s));
            TEST_ASSERT(s < n);
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_in_wedge(p.bound_x, p.bound_y, n, s, dx, dy, &in));
            TEST_ASSERT_MSG(in, "direction (%lld, %lld) not in its sector %u of %u", (long long)dx, (long long)dy, s, n);
            /* no lower sector holds it -- except sector N-1 wrapping to 0 */
            for (s2 = 0; s2 < s; ++s2) {
                ct_in_wedge(p.bound_x, p.bound_y, n, s2, dx, dy, &in);
                TEST_ASSERT_MSG(!in || (s2 == 0 && s == n - 1) || s2 + 1 == s,
                                "lower sector %u of %u also holds (%lld,%lld), chosen %u", s2, n, (long long)dx,
                                (long long)dy, s);
            }
        }
    }
}

int main(void)
{
    TEST_BEGIN("test_fixed");
    RUN_TEST(test_i128_hard_values);
    RUN_TEST(test_i128_random);
    RUN_TEST(test_bitlen);
    RUN_TEST(test_div_digits);
    RUN_TEST(test_isqrt);
    RUN_TEST(test_cot_table);
    RUN_TEST(test_sector_boundaries);
    RUN_TEST(test_crc32);
    RUN_TEST(test_sector_of);
    return TEST_END();
}
