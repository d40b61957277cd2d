/*
 * bench_m4.c -- instructions per ray on Cortex-M4 (qemu mps2-an386 with
 * -icount): every method on the benchmark's ray families over the fixture
 * package (ct_gen_m4_data), timed with SysTick and converted to executed
 * instructions by a calibration loop of known length, so the figure does
 * not depend on qemu's clock constants.  Each ray's status and steps must
 * equal the host's (bit-identical tracing), else the run fails.
 * Then geolocation per pixel (geo_bench): ct_geolocate, directional, on a
 * camera over the same package, straight and with curvature + refraction on
 * the sphere and on the true Earth; each pixel's status, steps and hit must
 * equal the host's, and ct_geolocate_batch over the same pixels gives the
 * per-call set-up; last, straight again with the lens baked into an 8 px
 * unprojection grid (pixel_row as the others), then runs of 8 neighbouring
 * pixels of a row with the lens, on the sphere and through the grid.
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

/* g's status, steps (when steps != 0; a batch's runs may shorten a
 * pixel's walk) and (for a hit) map position equal the host's. */
static int same_geo(const ct_geo *g, const m4_grid_pixel *w, int steps)
{
    if ((int32_t)g->status != w->status || (steps && g->hit.steps != w->steps)) {
        return 0;
    }
    return (g->status != CT_HIT && g->status != CT_HIT_VOID) ||
           (g->hit.e_nm == w->enh[0] && g->hit.n_nm == w->enh[1] && g->hit.h_nm == w->enh[2]);
}

static ct_geo g_geo[64];
static m4_grid_pixel g_want[64]; /* the host's results for the row at hand */

/* One row of the geolocation table: the n pixels one by one (mean, min-max
 * instructions) and in one batch (per pixel; the per-call set-up as the
 * difference when setup != 0), each status, step count (the singles) and hit checked
 * against g_want.  0 on a mismatch or a batch that failed or may have
 * wrapped SysTick (2^24 ticks). */
static int pixel_row(const char *name, const ct_package *p, const ct_camera *cam, const ct_pose *pose,
                     const ct_effects *fx, const int64_t *uv, uint32_t n, int setup, uint32_t empty,
                     uint64_t ipt_q16)
{
    uint64_t sum = 0u, steps = 0u, batch;
    uint32_t lo = 0xFFFFFFFFu, hi = 0u, hits = 0u, k, t0, dt, in;
    int ok = 1;
    /* bound: n <= 64 pixels */
    for (k = 0u; k < n; ++k) {
        ct_geo g;
        ct_status st;
        t0 = SYST_CVR;
        st = ct_geolocate(p, cam, pose, CT_METHOD_DIRECTIONAL, fx, uv[2u * k], uv[2u * k + 1u], &g);
        dt = ticks_since(t0);
        dt = dt > empty ? dt - empty : 0u;
        in = (uint32_t)(((uint64_t)dt * ipt_q16) >> 16);
        sum += dt;
        lo = in < lo ? in : lo;
        hi = in > hi ? in : hi;
        steps += g.hit.steps;
        hits += (st == CT_HIT || st == CT_HIT_VOID) ? 1u : 0u;
        g.status = st;
        ok = ok && same_geo(&g, &g_want[k], 1);
    }
    t0 = SYST_CVR;
    if (ct_geolocate_batch(p, cam, pose, CT_METHOD_DIRECTIONAL, fx, uv, n, g_geo, 64u) != CT_OK || sum >= 0xF00000u) {
        ct_plat_puts("bench_m4: FAIL: the batch failed or may have wrapped SysTick\n");
        ok = 0;
    }
    dt = ticks_since(t0);
    batch = dt > empty ? dt - empty : 0u;
    /* bound: n <= 64 pixels */
    for (k = 0u; k < n; ++k) {
        ok = ok && same_geo(&g_geo[k], &g_want[k], 0);
    }
    put_pad(name, 26u);
    put_u(n, 7u);
    put_u(hits, 5u);
    put_u(n > 0u ? (steps * 10u / n) / 10u : 0u, 4u);
    put(".");
    put_u(n > 0u ? (steps * 10u / n) % 10u : 0u, 0u);
    put(" | ");
    put_u(n > 0u ? ((sum * ipt_q16) >> 16) / n : 0u, 24u);
    put("  ");
    put_u(lo, 8u);
    put("-");
    put_u(hi, 0u);
    put_u(n > 0u ? ((batch * ipt_q16) >> 16) / n : 0u, 14u);
    /* n per-pixel calls form the set-up n times, the batch once */
    if (setup && n > 1u && sum > batch) {
        put_u((((sum - batch) * ipt_q16) >> 16) / (n - 1u), 13u);
    } else if (setup) {
        put("            -");
    }
    flush();
    return ok;
}

/* Geolocation per pixel (see the head comment); 0 on a mismatch with the
 * host or a set-up failure. */
static int geo_bench(const ct_package *p, uint32_t empty, uint64_t ipt_q16)
{
    static const char *const fxname[M4_GEO_FX] = {"straight", "sphere c+r", "true Earth c+r",
                                                            "true Earth c+r, fitted", "true Earth c+r, kept map"};
    static ct_earth_map map;
    static int64_t uv[2 * 64];
    ct_camera cam, gcam;
    ct_pose pose;
    uint32_t n = m4_geo_count, k, t0, dt;
    int e, ok = 1;
    if (n > 64u || ct_camera_init(&cam, &m4_geo_lens) != CT_OK || ct_camera_init_grid(&gcam, &m4_geo_grid) != CT_OK ||
        ct_pose_from_map(&pose, m4_geo_centre_nm[0], m4_geo_centre_nm[1], m4_geo_centre_nm[2], m4_geo_q30) != CT_OK) {
        ct_plat_puts("bench_m4: FAIL: the geolocation camera, grid or pose fails\n");
        return 0;
    }
    for (k = 0u; k < n; ++k) { /* bound: 64 pixels */
        uv[2u * k] = m4_geo_px[k].uv[0];
        uv[2u * k + 1u] = m4_geo_px[k].uv[1];
    }
    t0 = SYST_CVR;
    if (m4_geo_map_init(p, &map) != CT_OK) {
        ct_plat_puts("bench_m4: FAIL: the kept Earth map fails\n");
        return 0;
    }
    dt = ticks_since(t0);
    put("the kept Earth map (ct_earth_map_init, once): ");
    put_u((uint32_t)(((uint64_t)(dt > empty ? dt - empty : 0u) * ipt_q16) >> 16), 0u);
    put(" instructions");
    flush();
    ct_plat_puts("geolocation: ");
    ct_plat_puts(m4_geo_desc);
    ct_plat_puts("\n");
    put("ct_geolocate, directional  pixels hits steps | instructions/pixel: mean    min-max         ");
    put("batch/pixel  set-up/call");
    flush();
    /* bound: effects x pixels (baked arrays) */
    for (e = 0; e < M4_GEO_FX; ++e) {
        ct_effects fxs;
        const ct_effects *fx = m4_geo_effects(e, &fxs, &map);
        for (k = 0u; k < n; ++k) { /* bound: n <= 64 pixels */
            g_want[k].status = m4_geo_px[k].status[e];
            g_want[k].steps = m4_geo_px[k].steps[e];
            g_want[k].enh[0] = m4_geo_px[k].enh[e][0];
            g_want[k].enh[1] = m4_geo_px[k].enh[e][1];
            g_want[k].enh[2] = m4_geo_px[k].enh[e][2];
        }
        ok = pixel_row(fxname[e], p, &cam, &pose, fx, uv, n, 1, empty, ipt_q16) && ok;
    }
    /* straight again with the lens baked into the 8 px grid.  bound: n */
    for (k = 0u; k < n; ++k) {
        g_want[k] = m4_geo_grid_px[k];
    }
    ok = pixel_row("straight, 8 px grid", p, &gcam, &pose, (const ct_effects *)0, uv, n, 0, empty, ipt_q16) && ok;
    /* runs of 8 neighbouring pixels (the batch's runs), straight and on
     * the sphere; no set-up column (the batch's gain is more than the
     * set-up here).  bound: 2 effects x 64 pixels */
    for (e = 0; e < 2; ++e) {
        ct_effects fxs;
        const ct_effects *fx = m4_geo_effects(e, &fxs, &map);
        for (k = 0u; k < 64u; ++k) {
            g_want[k] = m4_geo_rows_px[e][k];
        }
        ok = pixel_row(e == 0 ? "straight, rows of 8 px" : "sphere c+r, rows of 8 px", p, &cam, &pose, fx,
                       m4_geo_rows_uv, 64u, 0, empty, ipt_q16) && ok;
    }
    /* the same runs through the 8 px grid (a batch keeps a row's column
     * sums within a node column).  bound: 64 pixels */
    for (k = 0u; k < 64u; ++k) {
        g_want[k] = m4_geo_grid_rows_px[k];
    }
    ok = pixel_row("straight, 8 px grid, rows", p, &gcam, &pose, (const ct_effects *)0, m4_geo_rows_uv, 64u, 0, empty,
                   ipt_q16) && ok;
    return ok;
}

int main(void)
{
    static const char *const mname[4] = {"incremental", "hierarchical", "cone", "directional"};
    ct_package p;
    uint32_t f, m, k, t0, cal_ticks, empty, open_ticks;
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
    t0 = SYST_CVR;
    if (ct_package_open(&p, m4_pkg, m4_pkg_size) != CT_OK) {
        ct_plat_puts("bench_m4: FAIL: the package does not open\n");
        ct_plat_exit(0);
    }
    open_ticks = ticks_since(t0) - empty;
    put("cortex-m4 (qemu -icount): fixture N=24 r=3, ");
    put_u(m4_pkg_size, 0u);
    put(" bytes; instructions per tick ");
    put_u(ipt_q16 >> 16, 0u);
    put(".");
    put_u(((ipt_q16 & 0xFFFFu) * 100u) >> 16, 0u);
    flush();
    /* the open verifies the CRC of every byte: most of its time */
    put("ct_package_open: ");
    put_u((uint32_t)(((uint64_t)open_ticks * ipt_q16) >> 16), 0u);
    put(" instructions, ");
    {
        const uint64_t c100 = (((uint64_t)open_ticks * ipt_q16) >> 16) * 100u / m4_pkg_size;
        put_u(c100 / 100u, 0u);
        put(c100 % 100u < 10u ? ".0" : ".");
        put_u(c100 % 100u, 0u);
    }
    put(" per byte");
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
    if (!geo_bench(&p, empty, ipt_q16)) {
        ok = 0;
    }
    ct_plat_puts(ok ? "bench_m4: every status and step count (and geolocation hit) equals the host's\n"
                    : "bench_m4: FAIL: a status, step count or geolocation hit differs from the host's\n");
    ct_plat_exit(ok);
    return 0;
}
