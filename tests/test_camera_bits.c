/*
 * test_camera_bits.c -- the camera code gives bit-identical results with the
 * native and the portable (Cortex-M) 128-bit arithmetic.
 *
 * Built twice (against conetrace and conetrace_portable); each prints a
 * digest (FNV-1a) over the statuses, iteration counts, rays, pixels and
 * rotated directions of seeded unprojections, projections and grid
 * unprojections for several lenses; CTest compares the two lines.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "conetrace.h"
#include "harness.h"

static uint64_t g_h = 1469598103934665603ull;
static unsigned long g_n;

static void mix(int64_t v)
{
    int k;
    for (k = 0; k < 8; ++k) {
        g_h ^= (uint64_t)((v >> (8 * k)) & 0xff);
        g_h *= 1099511628211ull;
    }
    g_n++;
}

static int64_t q(double v, int bits) { return (int64_t)llround(v * ldexp(1.0, bits)); }

int main(void)
{
    static const double lenses[][13] = {
        /* model, fx, fy, cx, cy, k1 k2 p1 p2 k3 k4 k5 k6 */
        {0, 1200, 1210, 959.5, 539.5, 0, 0, 0, 0, 0, 0, 0, 0},
        {1, 1400, 1401.5, 1023.5, 767.5, -0.28, 0.09, 1e-4, -2e-4, 0, 0, 0, 0},
        {2, 2200.3, 2200.1, 1511.2, 1003.9, -0.31, 0.12, 3e-4, 2e-4, -0.021, 0, 0, 0},
        {3, 1761.2, 1761.9, 2999.3, 1687.6, 2.82, 1.13, -1.1e-4, -5.3e-5, 0.061, 3.11, 2.21, 0.24},
        {1, 1000, 1000, 799.5, 599.5, -0.5, 0, 0, 0, 0, 0, 0, 0},
        {3, 900, 905, 1000, 700, -0.6, 0.3, 0.004, -0.003, -0.1, 0.4, 0.05, 0.01},
    };
    static int32_t table[3 * 40 * 30];
    const int32_t R[9] = {1 << 30, 0, 0, 0, -(1 << 30), 0, 0, 0, -(1 << 30)};
    ct_pose pose;
    ct_rng rng;
    size_t m;
    int k;
    ct_rng_seed(&rng, 4242);
    if (ct_pose_init(&pose, R, INT64_C(500000) * 1000000000, INT64_C(4000000) * 1000000000, 0) != CT_OK) {
        printf("pose refused\n");
        return 1;
    }
    for (m = 0; m < sizeof lenses / sizeof lenses[0]; ++m) {
        const double *L = lenses[m];
        ct_lens l;
        ct_camera cam;
        int i;
        memset(&l, 0, sizeof l);
        l.model = (uint32_t)L[0];
        l.fx_q32 = q(L[1], 32);
        l.fy_q32 = q(L[2], 32);
        l.cx_q32 = q(L[3], 32);
        l.cy_q32 = q(L[4], 32);
        for (i = 0; i < 8; ++i) l.dist_q48[i] = q(L[5 + i], 48);
        mix(ct_camera_init(&cam, &l));
        mix(cam.r2_max_q32);
        for (k = 0; k < 3000; ++k) {
            int64_t u = ct_rng_range(&rng, -(INT64_C(400) << 16), INT64_C(6400) << 16);
            int64_t v = ct_rng_range(&rng, -(INT64_C(400) << 16), INT64_C(3800) << 16);
            int32_t ray[3];
            int64_t d[3], pu = 0, pv = 0;
            uint32_t it = 0;
            ct_status s = ct_camera_unproject(&cam, u, v, ray, &it);
            mix(s);
            mix(it);
            if (s == CT_OK) {
                mix(ray[0]);
                mix(ray[1]);
                mix(ray[2]);
                mix(ct_camera_project(&cam, ray, &pu, &pv));
                mix(pu);
                mix(pv);
                mix(ct_pose_rotate(&pose, ray, d));
                mix(d[0]);
                mix(d[1]);
                mix(d[2]);
            }
        }
    }
    {
        /* a grid: rays of a stereographic-like lens (double, same on both) */
        ct_unproject_grid g;
        ct_camera cam;
        int i, j;
        for (j = 0; j < 30; ++j)
            for (i = 0; i < 40; ++i) {
                double x = (i - 19.3) * 0.045, y = (j - 14.6) * 0.05, r2 = x * x + y * y;
                double d[3] = {x, y, 1 - r2 / 4}, n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                int c;
                for (c = 0; c < 3; ++c) table[3 * (j * 40 + i) + c] = (int32_t)llround(d[c] / n * 1073741824.0);
            }
        g.nu = 40;
        g.nv = 30;
        g.u0_q16 = -(INT64_C(33) << 15);
        g.v0_q16 = -(INT64_C(33) << 15);
        g.step_q16 = INT64_C(32) << 16;
        g.rays_q30 = table;
        g.rays_len = sizeof table / sizeof table[0];
        mix(ct_camera_init_grid(&cam, &g));
        for (k = 0; k < 5000; ++k) {
            int32_t ray[3];
            ct_status s = ct_camera_unproject(&cam, ct_rng_range(&rng, -(INT64_C(40) << 16), INT64_C(1300) << 16),
                                              ct_rng_range(&rng, -(INT64_C(40) << 16), INT64_C(980) << 16), ray, NULL);
            mix(s);
            if (s == CT_OK) {
                mix(ray[0]);
                mix(ray[1]);
                mix(ray[2]);
            }
        }
    }
    printf("camera digest %016llx over %lu values\n", (unsigned long long)g_h, g_n);
    return 0;
}
