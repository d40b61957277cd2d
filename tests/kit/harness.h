/*
 * harness.h -- a small Unity-style test harness (C99 and C++).
 *
 *   static void test_something(void) { TEST_ASSERT_EQUAL_INT(3, f()); }
 *   int main(void) { TEST_BEGIN("name"); RUN_TEST(test_something); return TEST_END(); }
 *
 * A failing assertion prints file:line and the values, marks the current
 * test failed and returns from it.  TEST_END prints one summary line
 * ("name: N tests, F failures") and returns the process exit code.
 * Environment: CT_TEST_SEED (default 1) and CT_TEST_SCALE (default 1.0)
 * for heavy sweeps; CT_TEST_FILTER runs only tests whose name contains it.
 */
#ifndef CT_TEST_HARNESS_H
#define CT_TEST_HARNESS_H

#include <inttypes.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifdef __cplusplus
#define CT_HARNESS_INLINE inline
#else
#define CT_HARNESS_INLINE static inline
#endif

typedef struct {
    const char *suite;
    int tests, failures, current_failed, skipped;
} ct_harness_state;

#ifdef __cplusplus
inline ct_harness_state ct_harness_g;
#else
static ct_harness_state ct_harness_g;
#endif

CT_HARNESS_INLINE uint64_t ct_test_seed(void)
{
    const char *s = getenv("CT_TEST_SEED");
    return s ? (uint64_t)strtoull(s, NULL, 10) : 1u;
}

CT_HARNESS_INLINE double ct_test_scale(void)
{
    const char *s = getenv("CT_TEST_SCALE");
    double v = s ? atof(s) : 1.0;
    return v > 0 ? v : 1.0;
}

/* xorshift64* -- deterministic, seedable */
typedef struct {
    uint64_t s;
} ct_rng;
CT_HARNESS_INLINE void ct_rng_seed(ct_rng *r, uint64_t seed) { r->s = seed * 0x9E3779B97F4A7C15ull + 0x1234567ull; if (!r->s) r->s = 1; }
CT_HARNESS_INLINE uint64_t ct_rng_u64(ct_rng *r)
{
    uint64_t x = r->s;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    r->s = x;
    return x * 0x2545F4914F6CDD1Dull;
}
/* uniform in [0, 1) */
CT_HARNESS_INLINE double ct_rng_unit(ct_rng *r) { return (double)(ct_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0); }
/* uniform integer in [lo, hi] */
CT_HARNESS_INLINE int64_t ct_rng_range(ct_rng *r, int64_t lo, int64_t hi)
{
    /* in unsigned arithmetic (hi - lo may not fit an int64); the same values
     * as lo + u % (hi - lo + 1) wherever that fits */
    uint64_t span = (uint64_t)hi - (uint64_t)lo + 1u, u = ct_rng_u64(r);
    return (int64_t)((uint64_t)lo + (span == 0u ? u : u % span));
}

#define TEST_BEGIN(name)                                  \
    do {                                                  \
        memset(&ct_harness_g, 0, sizeof ct_harness_g);    \
        ct_harness_g.suite = (name);                      \
        setvbuf(stdout, NULL, _IOLBF, 0);                 \
    } while (0)

#define RUN_TEST(fn)                                                                  \
    do {                                                                              \
        const char *flt_ = getenv("CT_TEST_FILTER");                                  \
        if (flt_ && !strstr(#fn, flt_)) break;                                        \
        clock_t t0_ = clock();                                                        \
        ct_harness_g.current_failed = 0;                                              \
        ct_harness_g.tests++;                                                         \
        fn();                                                                         \
        if (ct_harness_g.current_failed) ct_harness_g.failures++;                     \
        printf("%-4s %s (%.2f s)\n", ct_harness_g.current_failed ? "FAIL" : "ok", #fn, \
               (double)(clock() - t0_) / CLOCKS_PER_SEC);                             \
    } while (0)

#define TEST_END()                                                                         \
    (printf("%s: %d tests, %d failures%s\n", ct_harness_g.suite, ct_harness_g.tests,       \
            ct_harness_g.failures, ct_harness_g.skipped ? " (some skipped)" : ""),         \
     ct_harness_g.failures ? 1 : 0)

#define TEST_FAIL_MSG(...)                                      \
    do {                                                        \
        printf("  %s:%d: ", __FILE__, __LINE__);                \
        printf(__VA_ARGS__);                                    \
        printf("\n");                                           \
        ct_harness_g.current_failed = 1;                        \
        return;                                                 \
    } while (0)

#define TEST_SKIP(...)                          \
    do {                                        \
        printf("  skipped: ");                  \
        printf(__VA_ARGS__);                    \
        printf("\n");                           \
        ct_harness_g.skipped = 1;               \
        return;                                 \
    } while (0)

#define TEST_ASSERT(cond) \
    do { if (!(cond)) TEST_FAIL_MSG("assertion failed: %s", #cond); } while (0)

#define TEST_ASSERT_MSG(cond, ...) \
    do { if (!(cond)) TEST_FAIL_MSG(__VA_ARGS__); } while (0)

#define TEST_ASSERT_TRUE(cond) TEST_ASSERT(cond)
#define TEST_ASSERT_FALSE(cond) TEST_ASSERT(!(cond))

#define TEST_ASSERT_EQUAL_INT(exp, act)                                                  \
    do {                                                                                 \
        long long e_ = (long long)(exp), a_ = (long long)(act);                          \
        if (e_ != a_) TEST_FAIL_MSG("expected %s == %lld, got %lld", #act, e_, a_);      \
    } while (0)

#define TEST_ASSERT_EQUAL_UINT64(exp, act)                                                        \
    do {                                                                                          \
        unsigned long long e_ = (unsigned long long)(exp), a_ = (unsigned long long)(act);        \
        if (e_ != a_) TEST_FAIL_MSG("expected %s == %llu, got %llu", #act, e_, a_);               \
    } while (0)

#define TEST_ASSERT_DOUBLE_WITHIN(tol, exp, act)                                              \
    do {                                                                                      \
        double e_ = (double)(exp), a_ = (double)(act), t_ = (double)(tol);                    \
        if (!(e_ - a_ <= t_ && a_ - e_ <= t_))                                                \
            TEST_FAIL_MSG("expected %s within %g of %.17g, got %.17g", #act, t_, e_, a_);     \
    } while (0)

#endif /* CT_TEST_HARNESS_H */
