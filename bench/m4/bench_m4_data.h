/* bench_m4_data.h -- the data ct_gen_m4_data bakes for bench_m4.c. */
#ifndef CT_BENCH_M4_DATA_H
#define CT_BENCH_M4_DATA_H
#include <stdint.h>

#include "conetrace.h"

typedef struct {
    int64_t ray[6];      /* ct_ray: x, y, z (Q16), dx, dy, dz                */
    int32_t status[4];   /* the host's ct_trace status per method            */
    uint32_t steps[4];   /* the host's steps per method                      */
    int32_t bent_status; /* the host's ct_trace_bent (m4_bend), directional  */
    uint32_t bent_steps;
} m4_ray;

/* The bend of the "bent" lines: curvature and refraction, c = 1 - 0.13, R =
 * 6371 km, the polyline chord 1 mm (unused by the lowered walk).          */
#define M4_BEND_COEFF_Q16 57016
#define M4_BEND_RADIUS_NM INT64_C(6371000000000000)
#define M4_BEND_CHORD_NM INT64_C(1000000)

/* Geolocation per pixel (ct_geolocate, directional) with the effects of
 * M4_GEO_FX: 0 none (straight), 1 curvature + refraction (k = 0.13) on the
 * sphere of CT_EARTH_RADIUS_NM (the map-frame parabola), 2 the same on the
 * true Earth (earth_radius_nm = 0: the Earth-fixed line of sight, earth.c),
 * 3 the true Earth with its map fitted once per call (CT_EFFECT_EARTH_FIT),
 * 4 the true Earth through a map kept across calls (m4_geo_map_init).     */
#define M4_GEO_FX 5
static inline const ct_effects *m4_geo_effects(int k, ct_effects *fx, const ct_earth_map *map)
{
    fx->flags = k == 3 ? CT_EFFECT_ALL | CT_EFFECT_EARTH_FIT : CT_EFFECT_ALL;
    fx->refraction_k_q16 = CT_REFRACTION_K_STD_Q16;
    fx->earth_radius_nm = k == 1 ? CT_EARTH_RADIUS_NM : 0;
    fx->chord_nm = 0;
    fx->earth_map = k == 4 ? map : (const ct_earth_map *)0;
    return k == 0 ? (const ct_effects *)0 : fx;
}
/* The kept map of effect 4: around the tile's centre at its lowest post's
 * height, a 35 km cube (the camera 4.5 km back and its 16 km range).      */
static inline ct_status m4_geo_map_init(const ct_package *p, ct_earth_map *map)
{
    int64_t e = p->origin_e_nm + (int64_t)(p->width / 2u) * p->posting_e_nm;
    int64_t n = p->origin_n_nm + (int64_t)(p->height / 2u) * p->posting_n_nm;
    int64_t h = p->height_offset_nm + (int64_t)p->hmin * p->height_scale_nm;
    return ct_earth_map_init(p, e, n, h, INT64_C(1) << 45, map);
}
typedef struct {
    int64_t uv[2];        /* pixel, Q16                                      */
    int32_t status[M4_GEO_FX];  /* the host's ct_geolocate status per effects */
    uint32_t steps[M4_GEO_FX];
    int64_t enh[M4_GEO_FX][3];  /* the host's hit (E, N, h nm; 0 if no hit)  */
} m4_pixel;

extern const uint32_t m4_pkg_size;
extern const uint8_t m4_pkg[];
extern const uint32_t m4_family_count;
extern const char *const m4_family_name[];
extern const uint32_t m4_family_start[];
extern const m4_ray m4_rays[];
extern const char m4_geo_desc[];   /* the scene, for the report           */
extern const ct_lens m4_geo_lens;
extern const int64_t m4_geo_centre_nm[3]; /* camera centre E, N, h          */
extern const int32_t m4_geo_q30[4];       /* ct_pose_from_map's quaternion  */
extern const uint32_t m4_geo_count;
extern const m4_pixel m4_geo_px[];
/* The same lens baked into an 8 px unprojection grid (nodes from the
 * library's own closed-form unprojection), and the host's straight
 * geolocation of the same pixels through it. */
extern const ct_unproject_grid m4_geo_grid;
typedef struct {
    int32_t status;
    uint32_t steps;
    int64_t enh[3];
} m4_grid_pixel;
extern const m4_grid_pixel m4_geo_grid_px[];
/* 64 pixels in 8 runs of 8 neighbours along a row (ct_geolocate_batch's
 * runs), and the host's ct_geolocate of each with the lens: straight
 * ([0]) and on the sphere ([1], m4_geo_effects(1)). */
extern const int64_t m4_geo_rows_uv[128];
extern const m4_grid_pixel m4_geo_rows_px[2][64];
/* The same 64 pixels through the 8 px grid, straight. */
extern const m4_grid_pixel m4_geo_grid_rows_px[64];
#endif
