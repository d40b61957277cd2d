/* profile_m4.c -- a Cortex-M4 instruction profile of ct_geolocate under
 * qemu (scripts/profile_m4.sh): the baked geolocation scene of bench_m4
 * (bench_m4_data.h), effects PROFILE_FX (0 straight, 1 sphere, 2 the true
 * Earth exact, 3 fitted per call, 4 a kept map; 5 straight through the 8 px
 * unprojection grid over bench_m4's rows of 8 px), PROFILE_PIXELS pixels one
 * by one, or in one batch with PROFILE_BATCH.  The script runs it
 * single-stepped with qemu's exec log and counts instructions per
 * function; the package's open (its CRC) and the kept map's fit are done
 * before the marker `profile_begin` and left out. */
#include <stdint.h>

#include "bench_m4_data.h"
#include "conetrace.h"
#include "mcu_platform.h"

#ifndef PROFILE_FX
#define PROFILE_FX 2
#endif
#ifndef PROFILE_PIXELS
#define PROFILE_PIXELS 4
#endif
#ifndef PROFILE_BATCH
#define PROFILE_BATCH 0
#endif

static ct_earth_map g_map;
static ct_geo g_geo[64];
static int64_t g_uv[2 * 64];

/* Its first instruction starts the profile, its return ends it. */
__attribute__((noinline)) void profile_begin(void);
__attribute__((noinline)) void profile_begin(void)
{
    __asm__ volatile("" ::: "memory");
}

int main(void)
{
    ct_package p;
    ct_camera cam;
    ct_pose pose;
    ct_effects fxs;
    const ct_effects *fx;
    uint32_t k, n = PROFILE_PIXELS < 64 ? PROFILE_PIXELS : 64;
    if (ct_package_open(&p, m4_pkg, m4_pkg_size) != CT_OK ||
        (PROFILE_FX == 5 ? ct_camera_init_grid(&cam, &m4_geo_grid) : ct_camera_init(&cam, &m4_geo_lens)) != CT_OK ||
        ct_pose_from_map(&pose, m4_geo_centre_nm[0], m4_geo_centre_nm[1], m4_geo_centre_nm[2], m4_geo_q30) != CT_OK ||
        (PROFILE_FX == 4 && m4_geo_map_init(&p, &g_map) != CT_OK)) {
        ct_plat_puts("profile_m4: FAIL: set-up\n");
        ct_plat_exit(0);
    }
    fx = m4_geo_effects(PROFILE_FX == 5 ? 0 : PROFILE_FX, &fxs, &g_map);
    for (k = 0u; k < n; ++k) { /* bound: 64 pixels */
        g_uv[2u * k] = PROFILE_FX == 5 ? m4_geo_rows_uv[2u * k] : m4_geo_px[k].uv[0];
        g_uv[2u * k + 1u] = PROFILE_FX == 5 ? m4_geo_rows_uv[2u * k + 1u] : m4_geo_px[k].uv[1];
    }
    profile_begin();
    if (PROFILE_BATCH) {
        (void)ct_geolocate_batch(&p, &cam, &pose, CT_METHOD_DIRECTIONAL, fx, g_uv, n, g_geo, 64u);
    } else {
        for (k = 0u; k < n; ++k) { /* bound: 64 pixels */
            (void)ct_geolocate(&p, &cam, &pose, CT_METHOD_DIRECTIONAL, fx, g_uv[2u * k], g_uv[2u * k + 1u], &g_geo[k]);
        }
    }
    profile_begin();
    ct_plat_puts("profile_m4: done\n");
    ct_plat_exit(1);
    return 0;
}
