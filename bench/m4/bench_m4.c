/*
 * bench_m4.c -- instructions per ray on Cortex-M4 (qemu mps2-an386 with
 * -icount): every method on the benchmark's ray families over the fixture
 * package (ct_gen_m4_data), timed with SysTick and converted to executed
 * instructions by a calibration loop of known length, so the figure does
 * not depend on qemu's clock constants.  Each ray's status and steps must
 * equal the host's (bit-identical tracing), else the run fails.
 * Flight software budgets in cycles: on a Cortex-M4 most instructions take
 * one cycle (loads two, taken branches 1-3, divisions 2-12), so cycles are
 * roughly 1.2-1.5x these counts at zero-wait-state memory.
 * C99, freestanding; scripts/bench_m4.sh builds and runs it.
 */
#include <stddef.h>
#include <stdint.h>

#include "bench_m4_data.h"
#include "bend.h"
#include "conetrace.h"
#include "mcu_platform.h"

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)

static char g_buf[160];
static uint32_t g_len;

static void put(const char *s)
{
    while (*s != '\0' && g_len + 1u < sizeof g_buf) { /* bound: buffer */
        g_buf[g_len++] = *s++;
    }
    g_buf[g_len] = '\0';
}

static void put_u(uint64_t v, unsigned width)
{
    char d[24];
    unsigned n = 0u;
    do { /* bound: 20 digits */
        d[n++] = (char)('0' + (int)(v % 10u));
        v /= 10u;
    } while (v != 0u && n < 20u);
    while (width > n) { /* bound: width */
        put(" ");
        width--;
    }
    while (n > 0u) { /* bound: n */
        char c[2];
        c[0] = d[--n];
        c[1] = '\0';
        put(c);
    }
}

static void flush(void)
{
    put("\n");
    ct_plat_puts(g_buf);
    g_len = 0u;
    g_buf[0] = '\0';
}

/* s, then spaces up to width characters. */
static void put_pad(const char *s, uint32_t width)
{
    uint32_t n = 0u;
    put(s);
    while (s[n] != '\0' && n < width) { /* bound: width */
        n++;
    }
    while (n < width) { /* bound: width */
        put(" ");
        n++;
    }
}

/* Baked ray k as a ct_ray. */
static ct_ray ray_at(uint32_t k)
{
    ct_ray r;
    r.x_q16 = m4_rays[k].ray[0];
    r.y_q16 = m4_rays[k].ray[1];
    r.z_q16 = m4_rays[k].ray[2];
    r.dx = m4_rays[k].ray[3];
    r.dy = m4_rays[k].ray[4];
    r.dz = m4_rays[k].ray[5];
    return r;
}

static uint32_t ticks_since(uint32_t start) { return (start - SYST_CVR) & 0xFFFFFFu; }

/* 2 n + 1 instructions (subs; bne per round, the last bne not taken) */
static void spin(uint32_t n)
{
    __asm__ volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
}

int main(void)
{
    static const char *const mname[4] = {"incremental", "hierarchical", "cone", "directional"};
    ct_package p;
    uint32_t f, m, k, t0, cal_ticks, empty;
    uint64_t ipt_q16; /* instructions per tick, Q16 */
    int ok = 1;
    SYST_RVR = 0xFFFFFFu;
    SYST_CVR = 0u;
    SYST_CSR = 5u; /* enable, processor clock, no interrupt */
    t0 = SYST_CVR;
    empty = ticks_since(t0);
    t0 = SYST_CVR;
    spin(200000u);
    cal_ticks = ticks_since(t0) - empty;
    if (cal_ticks == 0u) {
        ct_plat_puts("bench_m4: FAIL: SysTick does not count\n");
        ct_plat_exit(0);
    }
    ipt_q16 = ((uint64_t)400001u << 16) / cal_ticks;
    if (ct_package_open(&p, m4_pkg, m4_pkg_size) != CT_OK) {
        ct_plat_puts("bench_m4: FAIL: the package does not open\n");
        ct_plat_exit(0);
    }
    put("cortex-m4 (qemu -icount): fixture N=24 r=3, ");
    put_u(m4_pkg_size, 0u);
    put(" bytes; instructions per tick ");
    put_u(ipt_q16 >> 16, 0u);
    put(".");
    put_u(((ipt_q16 & 0xFFFFu) * 100u) >> 16, 0u);
    flush();
    put("family        rays | method         steps  instructions/ray (directional: of which ct_ray_prepare)");
    flush();
    /* bound: families x methods x rays (baked arrays) */
    for (f = 0u; f < m4_family_count; ++f) {
        uint32_t a = m4_family_start[f], b = m4_family_start[f + 1u];
        for (m = 0u; m < 4u; ++m) {
            uint64_t ticks = 0u, steps = 0u;
            for (k = a; k < b; ++k) {
                ct_ray r = ray_at(k);
                ct_hit h;
                ct_status st;
                uint32_t dt;
                t0 = SYST_CVR;
                st = ct_trace(&p, &r, (ct_method)m, &h);
                dt = ticks_since(t0);
                ticks += dt > empty ? dt - empty : 0u;
                steps += h.steps;
                if ((int32_t)st != m4_rays[k].status[m] || h.steps != m4_rays[k].steps[m]) {
                    ok = 0;
                }
            }
            put_pad(m == 0u ? m4_family_name[f] : "", 12u);
            put_u(b - a, 6u);
            put(" | ");
            put_pad(mname[m], 13u);
            put_u(b > a ? (steps * 10u / (b - a)) / 10u : 0u, 6u);
            put(".");
            put_u(b > a ? (steps * 10u / (b - a)) % 10u : 0u, 0u);
            put_u(b > a ? ((ticks * ipt_q16) >> 16) / (b - a) : 0u, 18u);
            if (m == 3u) {
                /* of which the preparation (ct_ray_prepare alone) */
                uint64_t pt = 0u;
                for (k = a; k < b; ++k) {
                    ct_ray r = ray_at(k);
                    ct_prepared pr;
                    uint32_t dt;
                    t0 = SYST_CVR;
                    (void)ct_ray_prepare(&p, &r, &pr);
                    dt = ticks_since(t0);
                    pt += dt > empty ? dt - empty : 0u;
                }
                put("  (prepare ");
                put_u(b > a ? ((pt * ipt_q16) >> 16) / (b - a) : 0u, 0u);
                put(")");
            }
            flush();
        }
        {
            /* the same rays bent by curvature and refraction (M4_BEND_*),
             * directional: the lowered walk for these observers */
            const ct_bend bd = {M4_BEND_COEFF_Q16, M4_BEND_RADIUS_NM, M4_BEND_CHORD_NM, 0u};
            uint64_t ticks = 0u, steps = 0u;
            for (k = a; k < b; ++k) {
                ct_ray r = ray_at(k);
                ct_hit h;
                ct_status st;
                uint32_t dt;
                t0 = SYST_CVR;
                st = ct_trace_bent(&p, &r, &bd, CT_METHOD_DIRECTIONAL, &h);
                dt = ticks_since(t0);
                ticks += dt > empty ? dt - empty : 0u;
                steps += h.steps;
                if ((int32_t)st != m4_rays[k].bent_status || h.steps != m4_rays[k].bent_steps) {
                    ok = 0;
                }
            }
            put_pad("", 12u);
            put_u(b - a, 6u);
            put(" | ");
            put_pad("dir., bent", 13u);
            put_u(b > a ? (steps * 10u / (b - a)) / 10u : 0u, 6u);
            put(".");
            put_u(b > a ? (steps * 10u / (b - a)) % 10u : 0u, 0u);
            put_u(b > a ? ((ticks * ipt_q16) >> 16) / (b - a) : 0u, 18u);
            {
                /* of which the bend's set-up for the ray's observer
                 * (ct_bent_prepare: formed once per call by
                 * ct_geolocate_batch for all of a camera's pixels) */
                uint64_t pt = 0u;
                for (k = a; k < b; ++k) {
                    ct_bent_setup bs;
                    uint32_t dt;
                    t0 = SYST_CVR;
                    (void)ct_bent_prepare(&p, &bd, m4_rays[k].ray[0], m4_rays[k].ray[1], &bs);
                    dt = ticks_since(t0);
                    pt += dt > empty ? dt - empty : 0u;
                }
                put("  (set-up ");
                put_u(b > a ? ((pt * ipt_q16) >> 16) / (b - a) : 0u, 0u);
                put(")");
            }
            flush();
        }
    }
    ct_plat_puts(ok ? "bench_m4: every status and step count equals the host's\n"
                    : "bench_m4: FAIL: a status or step count differs from the host's\n");
    ct_plat_exit(ok);
    return 0;
}
