/*
 * ct_vectors.h -- layout of the host-generated test vectors that the MCU
 * images (and the host replay) re-check bit for bit.
 *
 * The data file (ct_vectors.c in the build tree) is written at build time
 * by tests/mcu/gen_vectors.cpp from the HOST build of the library (native
 * __int128); the MCU program links the Cortex-M build (portable 128-bit
 * code) and must reproduce every value exactly.  C99, no float.
 */
#ifndef CT_VECTORS_H
#define CT_VECTORS_H

#include <stdint.h>
#include "conetrace.h"

/* One ray, its preparation and its result under every method. */
typedef struct {
    ct_ray ray;
    ct_status prep_status;
    ct_prepared prep;                     /* zero-initialised before the call */
    ct_status status[CT_METHOD_COUNT];
    ct_hit hit[CT_METHOD_COUNT];          /* zero-initialised before the call */
} ct_vec_case;

/* Map-frame conversions of one grid point. */
typedef struct {
    int64_t x, y, z;                      /* grid input (Q16)                 */
    ct_status g2m_status;
    int64_t e, n, h;                      /* ct_grid_to_map                   */
    ct_status m2g_status;
    int64_t x2, y2, z2;                   /* ct_map_to_grid(e, n, h)          */
    ct_status surf_status;
    int64_t surf_z;                       /* ct_surface_height(x, y)          */
    int64_t de, dn, dh;                   /* map direction                    */
    ct_status rfm_status;
    ct_ray rfm;                           /* ct_ray_from_map(e, n, h, de, dn, dh),
                                             zero-initialised before the call */
} ct_vec_point;

typedef struct {
    const char *name;
    const uint8_t *bytes;                 /* 8-byte aligned package           */
    uint32_t size;
    uint32_t crc;                         /* CRC field of the header          */
    uint32_t sectors, reduce, levels;
    uint32_t cone_codes;                  /* non-zero angle codes (0 = none)  */
    int64_t cot_q16[256];
    uint8_t cot_ok[256];
    int32_t bound_x[CT_MAX_SECTORS + 1], bound_y[CT_MAX_SECTORS + 1];
    const ct_vec_case *cases;
    uint32_t ncases;
    const ct_vec_point *points;
    uint32_t npoints;
} ct_vec_package;

/* Fixed-point (lib/src/fixed.h) checks: host native __int128 results. */
typedef struct {
    int64_t a, b;
    uint64_t mul_hi, mul_lo;              /* ct_i128_mul(a, b)                */
    int64_t div_d;                        /* divisor > 0                      */
    int64_t div_q;                        /* ct_i128_floor_div(mul(a,b), d)   */
    uint64_t isqrt;                       /* ct_i128_isqrt(|mul(a, b)|)       */
    uint64_t isqrt64;                     /* ct_isqrt64((uint64_t)a)          */
    int64_t m64;                          /* |m64| < 2^46                     */
    uint64_t m_hi, m_lo;                  /* ct_i128_mul128_64(ct_i128_mul(
                                             a / 2^24, b / 2^24), m64)        */
} ct_vec_fixed;

typedef struct {
    uint32_t k, n;
    int32_t cx, sy;                       /* ct_dir_of_fraction(k, n)         */
} ct_vec_dir;

/* One pixel of a camera: unprojection, projection back, and geolocation
 * with every method (ct_geolocate; outputs zero-initialised before each
 * call). */
typedef struct {
    int64_t u_q16, v_q16;
    ct_status unp_status;
    uint32_t unp_iters;
    int32_t ray_q30[3];                   /* ct_camera_unproject              */
    ct_status proj_status;                /* ct_camera_project(ray_q30), when
                                             unp_status == CT_OK              */
    int64_t pu_q16, pv_q16;
    ct_geo geo[CT_METHOD_COUNT];
} ct_vec_pixel;

/* A camera over one of the packages: lens (or unprojection grid), pose,
 * effects, and its pixels; ct_geolocate_batch over all of them with
 * batch_method must give the host's batch records (batch; equal to the
 * per-pixel results but for the runs' steps and iters, checked by the
 * generator). */
typedef struct {
    const char *name;
    uint32_t package;                     /* index into ct_vec_set.packages  */
    ct_lens lens;                         /* used when grid.nu == 0          */
    ct_unproject_grid grid;               /* nu > 0: ct_camera_init_grid     */
    ct_status init_status;
    int64_t r2_max_q32;                   /* the camera's valid field        */
    int32_t R_q30[9];
    int64_t e_nm, n_nm, h_nm;
    ct_status pose_status;
    ct_effects effects;
    uint32_t batch_method;
    const ct_vec_pixel *pixels;
    uint32_t npixels;
    const ct_geo *batch;                  /* the host's batch, npixels      */
    int64_t tol_nm;                       /* ct_effects_for_tolerance with the
                                             effects' k and radius           */
    ct_status tol_status;
    ct_effects_choice tol_choice;
} ct_vec_camera;

/* WGS84 <-> UTM (lib/src/geodesy.c): the host's results. */
typedef struct {
    ct_utm zone;
    int64_t lat_q61, lon_q61;
    ct_status fwd_status;
    int64_t e_nm, n_nm;                   /* ct_utm_forward                  */
    ct_status inv_status;
    int64_t lat2_q61, lon2_q61;           /* ct_utm_inverse(e_nm, n_nm)      */
    ct_status fac_status;
    int64_t gamma_q61, k_q61;             /* ct_utm_factors(lat, lon)        */
    int64_t ypr_q61[3], h_nm;
    ct_status quat_status;
    int32_t q_q30[4];                     /* ct_quat_from_ypr(ypr)           */
    ct_status pose_status;
    int32_t R_q30[9];                     /* ct_pose_from_wgs84(lat, lon, h, q) */
    int32_t hscale_q30;
} ct_vec_geo;

/* WGS84 geodetic <-> Earth-fixed (lib/src/geodesy.c): the host's results. */
typedef struct {
    int64_t lat_q61, lon_q61, h_nm;
    ct_status fwd_status;
    int64_t xyz_nm[3];                    /* ct_ecef_from_wgs84               */
    int64_t in_nm[3];                     /* the inverse's input: xyz_nm when
                                             fwd_status == CT_OK, else made up */
    ct_status inv_status;
    int64_t lat2_q61, lon2_q61, h2_nm;    /* ct_wgs84_from_ecef(in_nm)        */
} ct_vec_ecef;

/* The vertical datum (lib/src/geodesy.c): ct_geoid_at at one point of one
 * of the synthetic grids (ct_vec_set.geoid_grids). */
typedef struct {
    uint32_t grid;                        /* index into ct_vec_set.geoid_grids */
    int64_t lat_q61, lon_q61;
    ct_status status;
    int64_t n_nm;                         /* ct_geoid_at, when CT_OK          */
} ct_vec_geoid;

/* ct_package_geoid at one map point of the datum package. */
typedef struct {
    int64_t e_nm, n_nm;
    ct_status status;
    int64_t n_geoid_nm;                   /* when CT_OK                       */
} ct_vec_map_geoid;

/* A package with a datum section (CT_PKG_FLAG_DATUM): what ct_package_open
 * makes of it, and the geoid at map points. */
typedef struct {
    const char *name;
    const uint8_t *bytes;                 /* 8-byte aligned package           */
    uint32_t size;
    ct_status open_status, verify_status;
    uint32_t flags, epsg, vdatum, source_epsg;
    uint32_t geoid_w, geoid_h;
    int64_t geoid_lat0_q61, geoid_lon0_q61, geoid_step_q61;
    uint32_t geoid_values_off;            /* pkg.geoid.values - bytes         */
    const ct_vec_map_geoid *points;
    uint32_t npoints;
} ct_vec_datum_package;

/* A tile set (conetrace.h, "Tile sets"): the manifest and its tiles as
 * const arrays; the target loads them into nslots RAM slots of
 * CT_VEC_TILE_CAP bytes (tile `missing` refused; ntiles: none) and traces
 * the cases' rays with every method in order: the statuses, hits and the
 * final load count are the host's (prep fields unused).  Then, with the
 * same set, camera `camera`'s pixels through ct_geolocate_batch_tiles
 * (its lens or grid, pose, effects and batch method): every record and
 * the load count after it (batch_loads) the host's. */
#define CT_VEC_TILE_CAP 4096u
typedef struct {
    const uint8_t *bytes;
    uint32_t size;
} ct_vec_tile;

typedef struct {
    const char *name;
    const uint8_t *manifest;
    uint32_t manifest_size;
    const ct_vec_tile *tiles;             /* row-major                        */
    uint32_t ntiles;
    uint32_t nslots, missing;
    const ct_vec_case *cases;
    uint32_t ncases;
    uint32_t loads;                       /* ct_tileset.loads after the cases */
    uint32_t camera;                      /* index into ct_vec_set.cameras   */
    const ct_geo *batch;                  /* the camera's npixels records    */
    uint32_t batch_loads;                 /* ct_tileset.loads after them     */
} ct_vec_tileset;

typedef struct {
    const ct_vec_package *packages;
    uint32_t npackages;
    const ct_vec_fixed *fixed;
    uint32_t nfixed;
    const ct_vec_dir *dirs;
    uint32_t ndirs;
    const char *generator;                /* "build_package" or "degenerate"  */
    const ct_vec_camera *cameras;
    uint32_t ncameras;
    const ct_vec_geo *geo;
    uint32_t ngeo;
    const ct_vec_ecef *ecef;
    uint32_t necef;
    const ct_geoid_grid *geoid_grids;     /* some invalid (statuses)          */
    uint32_t ngeoid_grids;
    const ct_vec_geoid *geoid;
    uint32_t ngeoid;
    const ct_vec_datum_package *datum;
    uint32_t ndatum;
    const ct_vec_tileset *tilesets;
    uint32_t ntilesets;
} ct_vec_set;

extern const ct_vec_set ct_vectors;

#endif /* CT_VECTORS_H */
