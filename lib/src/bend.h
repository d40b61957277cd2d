/*
 * bend.h -- tracer helpers shared by trace.c, prepare.c, frames.c, bend.c
 * and geoloc.c (private):
 * bent rays, the lowered terrain, the grid direction of a map direction.
 */
#ifndef CT_BEND_H
#define CT_BEND_H

#include "conetrace.h"
#include "fixed.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The max-mipmap's value (the tallest post under it) of block (bi, bj) at
 * level l in [1, levels], the block inside that level's grid (the walks'
 * and the culling's one read of it). */
static inline uint32_t ct_mip_at(const ct_package *p, uint32_t l, uint32_t bi, uint32_t bj)
{
    return ct_ld16(p->mip[l] + 2u * ((size_t)bj * p->mip_w[l] + (size_t)bi));
}

/* The grid direction of a map direction (|.| <= 2^40, not all 0), as
 * ct_ray_from_map forms it (frames.c); geolocation uses it so that a pixel's
 * grid ray is ct_ray_from_map's of the pose centre and ct_geo.dir_map_q39. */
void ct_grid_dir_from_map(const ct_package *p, int64_t de, int64_t dn, int64_t dh, int64_t d[3]);

/* Check *bd's ranges (ct_bend) and compute the polyline's segment length
 * Delta = sqrt(8 chord R / |c|) in Q16 fine cells of pkg (0 when c = 0).
 * CT_OK, or CT_ERR_ARG for a parameter out of range or Delta < 1/64 cell. */
ct_status ct_bend_segment(const ct_package *pkg, const ct_bend *bd, int64_t *delta_q16);

/* The caller's effects as a bend (geoloc.c): c = [curvature] - k
 * [refraction] in Q16 (0 = straight; fx == NULL: none), the radius and
 * chord with their defaults, bd->flags 0.  CT_ERR_EFFECTS for an unknown
 * flag, |k| > 2, an earth_map not fitted for pkg, or a radius or chord out
 * of ct_bend_segment's ranges (checked whatever c is).                    */
ct_status ct_effects_to_bend(const ct_package *pkg, const ct_effects *fx, ct_bend *bd);

/* Lowered terrain (trace.c): a bent ray with c > 0 is traced as its straight
 * tangent at the observer against the terrain lowered, post by post, by the
 * bend's rise at that post's horizontal range from the observer:
 *     D(post) = floor(Q * kf / 2^kshift)  Q16 height LSB,
 *     Q = (x_post - obx)^2 + (y_post - oby)^2  (Q16 cells, squared),
 * so z_tangent(t) <= S - D  <=>  z_tangent + rise <= S  at every post.  In a
 * cell the surface is the bilinear patch of the lowered posts; the rise is
 * a quadratic in (x, y) whose bilinear interpolation exceeds it by at most
 * c posting^2 / (4 R) (0.035 mm for 30 m cells), the model's only error
 * besides kf's rounding (relative < 2^-29).  Bounds set up by bend.c: every
 * tile corner within 2^31 Q16 of the observer on each axis (Q < 2^63),
 * kf < 2^32 (Q kf < 2^95), dmax = D at the farthest corner < 2^32.        */
typedef struct {
    int64_t obx, oby;  /* observer, Q16 cells                               */
    uint64_t kf;       /* rise per squared Q16 cell, times 2^kshift          */
    uint32_t kshift;   /* < 128                                             */
    int64_t dmax;      /* largest D over the tile, Q16 LSB, < 2^32           */
    int64_t kc;        /* the walks' lower bounds: D per squared whole cell,
                          Q16 (floor(kf 2^48 / 2^kshift), at most 2^33)   */
    int32_t cull;      /* 1: the walks use lower bounds of D ahead (culling) */
} ct_lower;

/* The lowered model's constants for an observer at ray's origin (bend.c):
 * CT_OK, or CT_ERR_RANGE where it does not apply (c <= 0, the observer
 * 2^31 Q16 or more from a tile corner on an axis, a rise of 2^16 LSB or
 * more over the tile); ct_trace_bent then traces the polyline.  *bd's
 * ranges are checked by the caller (ct_bend_segment).                      */
ct_status ct_lower_setup(const ct_package *pkg, int64_t ox_q16, int64_t oy_q16, const ct_bend *bd, ct_lower *lw);

/* Everything ct_trace_bent derives from the package, the bend and the
 * observer's horizontal position, formed once for many rays from one
 * observer (geoloc.c: every pixel of a camera).                            */
typedef struct {
    ct_bend bend;
    int64_t delta;   /* the polyline's segment length (ct_bend_segment)   */
    int32_t lowered; /* 1: lw applies (c > 0, ct_lower_setup succeeded)   */
    ct_lower lw;
} ct_bent_setup;

/* ct_bend_segment's checks, then the set-up for an observer at (ox, oy). */
ct_status ct_bent_prepare(const ct_package *pkg, const ct_bend *bd, int64_t ox_q16, int64_t oy_q16,
                          ct_bent_setup *bs);

/* ct_trace_bent with a set-up from ct_bent_prepare; the ray's origin must
 * be the observer it was made for (CT_ERR_ARG otherwise, when lowered).    */
ct_status ct_trace_bent_set(const ct_package *pkg, const ct_ray *ray, const ct_bent_setup *bs, ct_method method,
                            ct_hit *hit);

/* D at a Q16 point (x, y) of the tile (exact, the formula above). */
int64_t ct_lower_at(const ct_lower *lw, int64_t x, int64_t y);

/* ct_trace for the lowered model (ray's origin = the observer). */
ct_status ct_trace_lowered(const ct_package *pkg, const ct_ray *ray, const ct_lower *lw, ct_method method,
                           ct_hit *hit);

/* Ray preparation (prepare.c) for a straight ray or segment (seg) or, with
 * lw, a bent ray's tangent against the lowered terrain. */
ct_status ct_prepare_lowered(const ct_package *p, const ct_ray *ray, int seg, const ct_lower *lw, ct_prepared *out);

/* Rays from one observer traced together (geoloc.c's batch): n <=
 * CT_RUN_MAX prepared rays r[k] (lw: the lowered terrain of all, or NULL:
 * straight), each one's status in st[k] and hit in *h[k], the same as
 * its own trace from t = 0 (ct_trace_prepared_own / _lowered) in every
 * field but steps and iters, which count only the ray's own walk.  Where
 * the rays' paths share a primary axis and direction (each crossing the
 * relief over 16 cells or more, none parting from the first by more than
 * 8 cells over 512 cells or the tile's width, nor more than 4 cells from
 * it across its origin's cell), one walk of the max-mipmap over their common
 * bounds shows a first stretch free of the surface for all of them (at
 * most 2 w + levels + 2 iterations, w the tile's cells along that axis;
 * when it shows nothing, or the rays part too fast, the same for each
 * half of a run of 4 or more); each ray's walk then starts on the face
 * where that stretch ends, as a tile set's walk starts on a seam.
 * CT_ERR_ARG for a NULL argument or n > CT_RUN_MAX, else CT_OK.          */
#define CT_RUN_MAX 8u
ct_status ct_trace_run(const ct_package *pkg, const ct_prepared *r, uint32_t n, const ct_lower *lw, ct_method method,
                       ct_hit *const *h, ct_status *st);

/* Where each ray of a run starts its own walk on pkg (ct_run_starts, the
 * first half of ct_trace_run; a tile set's run on one tile, tiles.c):
 * CT_RUN_OWN from its first point as alone; CT_RUN_FACE on the face of
 * cell column (face 1) or row (face 2) `cell` of pkg's grid at t = t0_n /
 * t0_d (t0_d = |dx| or |dy|), as a tile set's walk starts on a seam, the
 * ray's way there holding no point of pkg's surface; CT_RUN_CLEAR: none
 * on its whole way through pkg's box.                                     */
enum { CT_RUN_OWN = 0, CT_RUN_FACE = 1, CT_RUN_CLEAR = 2 };
typedef struct {
    int64_t t0_n, t0_d;
    int32_t cell;
    uint8_t face, how;
} ct_run_start;
/* *r[k] (k < n <= CT_RUN_MAX, none NULL) prepared rays in pkg's grid (lw:
 * the lowered terrain of all, or NULL), out[k] each one's start.
 * CT_ERR_ARG for a NULL argument or n > CT_RUN_MAX, else CT_OK.           */
ct_status ct_run_starts(const ct_package *pkg, const ct_prepared *const *r, uint32_t n, const ct_lower *lw,
                        ct_run_start *out);

/* A segment (origin to origin + direction) of a lowered ray: prepared as
 * ct_ray_prepare_segment, traced against the lowered terrain (lw = NULL:
 * the terrain itself).  A hit in the last cell beyond the segment's end
 * (t beyond tend) belongs to the chord's extension: the caller discards it. */
ct_status ct_prepare_lowered_segment(const ct_package *pkg, const ct_ray *ray, const ct_lower *lw,
                                     ct_prepared *out);
ct_status ct_trace_prepared_lowered(const ct_package *pkg, const ct_prepared *ray, const ct_lower *lw,
                                    ct_method method, ct_hit *hit);

/* ct_lower_setup for a given rise coefficient: D = floor(Q kf / 2^kshift)
 * with kf < 2^32, kshift < 128; the same range checks.                     */
ct_status ct_lower_setup_k(const ct_package *pkg, int64_t ox_q16, int64_t oy_q16, uint64_t kf, uint32_t kshift,
                           int32_t cull, ct_lower *lw);

/* The true Earth (earth.c): a line of sight straight in Earth-fixed space
 * (WGS84; with refraction bent by k t^2 / 2R in its vertical plane) from a
 * camera over a package on a UTM zone, traced in pieces whose map-frame
 * image is a straight chord (sideways within the chord tolerance of the
 * exact image at its middle) and, vertically, the quadratic through the
 * exact images of its ends and middle -- each piece one lowered walk.     */
typedef struct {
    ct_utm zone;
    int64_t c[3];          /* camera centre, ECEF nm                          */
    int64_t ox, oy, oz;    /* the same, grid frame Q16 (the pose's point)     */
    int32_t frame_q30[9];  /* ECEF of grid east, grid north, up at the camera:
                              columns, Q30                                   */
    int32_t refr_k_q16;    /* refraction coefficient (0: none), Q16           */
    int64_t radius_nm;     /* radius for refraction's bending                 */
    int64_t tol_q24;       /* chord tolerance, Q24 cells (>= 2)               */
    int64_t tolz_q16;      /* the same in Q16 height units (>= 2)             */
    int64_t tmax_nm;       /* no terrain beyond this range                    */
    int32_t cull;
    /* The fitted map (earth.c): the image of ECEF points P in the cube |P
     * - map->c| <= 2^qrho nm as a sum of Chebyshev products T_a(s_x)
     * T_b(s_y) T_c(s_z), s = (P - map->c) / 2^qrho, a + b + c <= deg,
     * interpolated through the exact images at the tensor grid of (deg +
     * 1)^3 Chebyshev points.  map: NULL (exact), &fit (CT_EFFECT_EARTH_FIT:
     * fitted per call around the camera) or the caller's.                 */
    const ct_earth_map *map;
    int64_t moff[3];       /* c - map->c, ECEF nm                            */
    int64_t cam24[3];      /* the camera's image, Q24 (every path's node 0)  */
    ct_earth_map fit;
    /* 1: the fit (per call, centred at the camera: moff = 0) holds its
     * Taylor terms of degrees 1..3 there in the tail of its coefficients,
     * which a fit of degree <= 5 leaves unused (earth.c map_taylor); 0:
     * none (a kept map, no fit, degree 6, or a term out of range), the
     * path then takes Lobatto nodes only.                               */
    int32_t tay_ok;
    int64_t tay_bend_nm;   /* with tay_ok: refraction's bend at tmax_nm (nm) */
} ct_earth;

/* Library-internal helpers shared between files.                          */

/* R_map_cam ray (Q30 x Q30 -> Q39) without the pose's horizontal scale:
 * the local grid frame (camera.c; ct_pose_rotate applies hscale to it).
 * The pose and the ray are the caller's, checked.                          */
void ct_pose_rotate_grid(const ct_pose *pose, const int32_t ray_q30[3], int64_t out_q39[3]);

/* A batch's memo of an unprojection grid's column sums (camera.c): the
 * four columns' Catmull-Rom interpolation along v (Q30, |.| < 2^31.4) for
 * one pixel row v (Q16) and one node column i.  Consecutive pixels of a row
 * in one grid cell share them, so they are formed once; the result is the
 * same integer as without the memo.  valid = 0 before the first pixel.     */
typedef struct {
    int64_t v;
    uint32_t i, valid;
    int64_t col[4][3];
} ct_unproject_memo;

/* ct_camera_unproject with a memo (NULL: none); for other lenses than the
 * grid the memo is not used.                                               */
ct_status ct_camera_unproject_memo(const ct_camera *cam, int64_t u, int64_t v, int32_t ray[3], uint32_t *iters,
                                   ct_unproject_memo *memo);

/* A geoid grid's ranges (conetrace.h, the datum section): CT_OK,
 * CT_ERR_DIMS (nodes) or CT_ERR_GEOREF (step, extent, corner); the values
 * pointer is not looked at (geodesy.c).                                     */
ct_status ct_geoid_grid_check(const ct_geoid_grid *grid);

/* The camera's local frame from its map point (E, N) on a zone: lat, lon
 * (Q61) and the ECEF columns of grid east, grid north and up (Q30); the
 * grid axes are the true ones turned by the meridian convergence
 * (geodesy.c).                                                             */
ct_status ct_grid_frame_ecef(const ct_utm *zone, int64_t e_nm, int64_t n_nm, int64_t *lat_q61, int64_t *lon_q61,
                             int32_t frame_q30[9]);

/* Set-up for a pose over a UTM package: CT_ERR_CRS when the package is not
 * on a UTM zone, CT_ERR_RANGE / CT_ERR_RAY for a camera outside the
 * projection's or the tracer's domain.  fitted != 0: fit the map (above)
 * when the cube needed is at most 2^47 nm (else the exact map is kept);
 * map != NULL (checked by the caller: ct_earth_map_fits): use it instead. */
ct_status ct_earth_setup(const ct_package *pkg, const ct_pose *pose, int32_t refr_k_q16, int64_t radius_nm,
                         int64_t chord_nm, uint32_t bend_flags, int fitted, const ct_earth_map *map, ct_earth *es);

/* The UTM zone of a package's EPSG code (a 32-bit unsigned header field):
 * CT_OK, or CT_ERR_CRS for any other CRS, codes beyond INT32_MAX too.    */
static inline ct_status ct_package_zone(const ct_package *pkg, ct_utm *z)
{
    if (pkg->epsg > 0x7fffffffu || ct_utm_zone_of_epsg((int32_t)pkg->epsg, z) != CT_OK) {
        return CT_ERR_CRS;
    }
    return CT_OK;
}

/* 1 when `map` is a fitted map for this package's georeference.          */
int ct_earth_map_fits(const ct_package *pkg, const ct_earth_map *map);

/* Test hooks (earth.c): compiled only with CT_TEST_HOOKS, which the host
 * build of the whole project defines for the tests; a flight build (the
 * standalone library, the Cortex-M builds) has none of them
 * (tests/mcu/check_symbols.py refuses their symbols there).               */
#ifndef CT_TEST_HOOKS
#define CT_TEST_HOOKS 0
#endif

#if CT_TEST_HOOKS
/* The image of the ECEF point c + D (|D| <= 2^50 nm per axis) in the grid
 * frame, Q24: fitted (CT_ERR_RANGE when there is no fit or D is outside
 * its cube) or exact (for tests of the fit).                              */
ct_status ct_earth_image24(const ct_package *pkg, const ct_earth *es, const int64_t D[3], int fitted, int64_t g[3]);
#endif

/* Culling (bend.c): 1 when no prepared segment from a to b (Q16, z in Q16
 * height units) whose lowest point is zfloor can meet the surface: zfloor,
 * less the segment's rounding slack (2 + max|b - a| / 2^24 units, and
 * 2^zshift_max more vertically), is above the max-mipmap's maximum under
 * the box of a and b widened by the slack (at most four reads), or that
 * box misses the tile (*over_tile 0).  The walk would find no hit there,
 * so skipping it changes no result.                                       */
int ct_segment_above_terrain(const ct_package *p, int64_t ax, int64_t ay, int64_t az, int64_t bx, int64_t by,
                             int64_t bz, int64_t zfloor, int *over_tile);

#if CT_TEST_HOOKS
/* The image (Q24) of the line of sight with grid direction dg (Q39, as
 * ct_trace_earth_set's) at range t (0 <= t <= es->tmax_nm): interpolated
 * between its nodes (interp != 0; CT_ERR_RANGE when they could not be
 * set) or found as a node is (the map, or the exact conversions); *nodes
 * the number of the path polynomial's coefficients (0: none): the Lobatto
 * nodes' count, or with a fit per call 5 or 6 (earth.c taylor_nodes), plus
 * 8 when they are the fit's Taylor terms alone (no image).
 * For tests of the interpolation.                                        */
ct_status ct_earth_path_image24(const ct_package *pkg, const ct_earth *es, const int64_t dg[3], int64_t t, int interp,
                                int64_t g[3], int32_t *nodes);
#endif

/* One piece of a true-Earth line of sight as ct_trace_earth_set chooses it
 * (earth.c), for tests of its error bounds.                               */
typedef struct {
    int64_t ta_nm, lc_nm;      /* its range along the line of sight          */
    int64_t a24[3], m24[3], b24[3]; /* the path's images at its start (the
                                  camera's grid point on the first piece from
                                  the camera), middle and end, Q24          */
    int64_t shift_q24[2];      /* the chord's sideways shift, Q24           */
    int64_t walk_q16[6];       /* the walk line: from (x, y, z) to (x, y, z),
                                  Q16, against the terrain lowered by kf    */
    uint64_t kf;               /* the lowering's rise (ct_lower), when lowered */
    uint32_t kshift;
    int32_t lowered;           /* 1: the walk is lowered                     */
    int64_t elat_q24;          /* the sideways error it was accepted with     */
    int64_t evert_q16;         /* the height error it was accepted with       */
    int32_t off;               /* 1: off the tile, neither checked nor traced */
    int32_t bounded;           /* 1: errors bounded, 0: sampled at quarters   */
} ct_earth_piece;

/* The pieces of the line of sight with grid direction dg (as
 * ct_trace_earth_set's, without tracing them: every piece to the path's
 * end, the first cap in out), *n of them; the walk's status.              */
#if CT_TEST_HOOKS
ct_status ct_earth_pieces(const ct_package *pkg, const ct_earth *es, const int64_t dg[3], ct_earth_piece *out,
                          uint32_t cap, uint32_t *n);
#endif

/* ct_trace_prepared for a ray this library prepared itself (skips the
 * re-validation of the caller-visible struct). */
ct_status ct_trace_prepared_own(const ct_package *pkg, const ct_prepared *ray, ct_method method, ct_hit *hit);

#ifdef __cplusplus
}
#endif

#endif /* CT_BEND_H */
