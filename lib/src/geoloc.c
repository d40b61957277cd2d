/*
 * geoloc.c -- pixel to ground: unproject (camera.c), rotate into the map
 * frame (Q39), convert to a grid-frame ray from the camera centre and trace
 * it (trace.c), or, with scene effects (earth curvature, refraction), trace
 * the bent ray (bend.c: the observer is the camera centre).
 *
 * Effects: c = (CURVATURE ? 1 : 0) - (REFRACTION ? k : 0) in Q16, with
 * k in [-2, 2] (Q16): c in [-2, 3] (Q16 |c| <= 3 * 2^16), inside
 * ct_bend's |c| <= 4 * 2^16.  The bend's parameters (R, chord, and the
 * resulting segment length) are checked once per call (ct_bend_segment),
 * so a bad parameter is CT_ERR_EFFECTS for the call, never per pixel.
 *
 * Grid ray: ct_ray_from_map's from the pose centre along the pixel's map
 * direction (ct_geo.dir_map_q39, a Q39 unit vector): the centre converted
 * once per call, the direction per pixel by ct_grid_dir_from_map, so a
 * pixel's ray can be formed again from the pose and ct_geo alone (the pixel
 * soak does) and keeps ct_ray_from_map's precision (each component exact,
 * or within 1/2 of its exact value with the largest above 2^61).
 */
#include "bend.h"
#include "fixed.h"
#include "tiles.h"

typedef struct {
    int64_t ox, oy, oz;   /* camera centre, grid frame, Q16 */
    ct_bend bend;         /* coeff_q16 == 0: straight rays  */
    ct_bent_setup bent;   /* the bend for this observer     */
    int earth;            /* 1: the true Earth (earth.c)    */
    ct_earth es;
} geo_setup;

#define K_MAX_Q16 (2 * 65536)

/* Declared in bend.h (shared with los.c). */
ct_status ct_effects_to_bend(const ct_package *p, const ct_effects *fx, ct_bend *bd)
{
    int64_t delta;
    int32_t c = 0;
    bd->coeff_q16 = 0;
    bd->flags = 0u;
    bd->radius_nm = CT_EARTH_RADIUS_NM;
    bd->chord_nm = CT_EFFECTS_CHORD_NM;
    if (fx == NULL) {
        return CT_OK;
    }
    if ((fx->flags & ~(CT_EFFECT_ALL | CT_EFFECT_EARTH_FIT)) != 0u ||
        (fx->earth_map != NULL && !ct_earth_map_fits(p, fx->earth_map))) {
        return CT_ERR_EFFECTS;
    }
    if ((fx->flags & CT_EFFECT_CURVATURE) != 0u) {
        c = 65536;
    }
    if ((fx->flags & CT_EFFECT_REFRACTION) != 0u) {
        if (fx->refraction_k_q16 < -K_MAX_Q16 || fx->refraction_k_q16 > K_MAX_Q16) {
            return CT_ERR_EFFECTS;
        }
        c -= fx->refraction_k_q16; /* |c| <= 3 * 2^16 */
    }
    if (fx->earth_radius_nm != 0) {
        bd->radius_nm = fx->earth_radius_nm;
    }
    if (fx->chord_nm != 0) {
        bd->chord_nm = fx->chord_nm;
    }
    bd->coeff_q16 = c;
    /* ranges of R and chord, and the segment length (also for c = 0, so a
     * bad parameter is refused whatever k is) */
    {
        ct_bend chk = *bd;
        if (chk.coeff_q16 == 0) {
            chk.coeff_q16 = 65536;
        }
        if (ct_bend_segment(p, &chk, &delta) != CT_OK) {
            return CT_ERR_EFFECTS;
        }
    }
    return CT_OK;
}

static ct_status setup(const ct_package *p, const ct_camera *cam, const ct_pose *pose, ct_method m,
                       const ct_effects *effects, geo_setup *s)
{
    if (p == NULL || cam == NULL || pose == NULL || cam->ready == 0u || pose->ready == 0u) {
        return CT_ERR_ARG;
    }
    if ((unsigned)m >= (unsigned)CT_METHOD_COUNT) {
        return CT_ERR_METHOD;
    }
    if (ct_effects_to_bend(p, effects, &s->bend) != CT_OK) {
        return CT_ERR_EFFECTS;
    }
    if (ct_map_to_grid(p, pose->e_nm, pose->n_nm, pose->h_nm, &s->ox, &s->oy, &s->oz) != CT_OK ||
        ct_abs64(s->ox) > CT_MAX_ORIGIN_Q16 || ct_abs64(s->oy) > CT_MAX_ORIGIN_Q16 ||
        ct_abs64(s->oz) > CT_MAX_ORIGIN_Q16) {
        return CT_ERR_RAY;
    }
    s->earth = 0;
    if (effects != NULL && (effects->flags & CT_EFFECT_CURVATURE) != 0u && effects->earth_radius_nm == 0) {
        /* the true Earth on a package on a UTM zone (CT_ERR_CRS: another
         * CRS, which keeps the sphere of CT_EARTH_RADIUS_NM) */
        ct_status st = ct_earth_setup(p, pose,
                                      (effects->flags & CT_EFFECT_REFRACTION) != 0u ? effects->refraction_k_q16 : 0,
                                      CT_EARTH_RADIUS_NM, s->bend.chord_nm, s->bend.flags,
                                      (effects->flags & CT_EFFECT_EARTH_FIT) != 0u, effects->earth_map, &s->es);
        if (st == CT_OK) {
            s->earth = 1;
            return CT_OK;
        }
        if (st != CT_ERR_CRS) {
            return st == CT_ERR_RAY ? CT_ERR_RAY : CT_ERR_POSE;
        }
    }
    if (s->bend.coeff_q16 != 0 && ct_bent_prepare(p, &s->bend, s->ox, s->oy, &s->bent) != CT_OK) {
        return CT_ERR_EFFECTS; /* checked by ct_effects_to_bend already */
    }
    return CT_OK;
}

/* The pixel's record cleared, its ray unprojected and rotated into the
 * map frame (out->ray_cam_q30, out->dir_map_q39); memo: a batch's (NULL
 * for one pixel). */
static ct_status pixel_dir(const ct_camera *cam, const ct_pose *pose, int64_t u, int64_t v, ct_unproject_memo *memo,
                           ct_geo *out)
{
    ct_status st;
    uint32_t k;
    /* bound: 3 components */
    for (k = 0u; k < 3u; ++k) {
        out->ray_cam_q30[k] = 0;
        out->dir_map_q39[k] = 0;
    }
    out->hit.x_q16 = out->hit.y_q16 = out->hit.z_q16 = 0;
    out->hit.e_nm = out->hit.n_nm = out->hit.h_nm = 0;
    out->hit.t_q26 = 0;
    out->hit.cell_x = out->hit.cell_y = -1;
    out->hit.steps = out->hit.iters = 0u;
    st = ct_camera_unproject_memo(cam, u, v, out->ray_cam_q30, &out->unproject_iters, memo);
    if (st == CT_OK) {
        st = ct_pose_rotate(pose, out->ray_cam_q30, out->dir_map_q39);
    }
    return st;
}

/* ct_ray_from_map's ray from the pose centre along dir_map_q39 (|.| <=
 * 2^39, a unit vector: never all 0). */
static void pixel_ray(const ct_package *p, const geo_setup *s, const ct_geo *g, ct_ray *ray)
{
    int64_t d[3];
    ct_grid_dir_from_map(p, g->dir_map_q39[0], g->dir_map_q39[1], g->dir_map_q39[2], d);
    ray->x_q16 = s->ox;
    ray->y_q16 = s->oy;
    ray->z_q16 = s->oz;
    ray->dx = d[0];
    ray->dy = d[1];
    ray->dz = d[2];
}

/* ts != NULL: trace over the tile set (p is its frame). */
static ct_status one_pixel(const ct_package *p, ct_tileset *ts, const ct_camera *cam, const ct_pose *pose, ct_method m,
                           const geo_setup *s, int64_t u, int64_t v, ct_unproject_memo *memo, ct_geo *out)
{
    ct_ray ray;
    ct_status st = pixel_dir(cam, pose, u, v, memo, out);
    if (st == CT_OK && s->earth) {
        /* the map-frame direction without the pose's horizontal scale */
        int64_t dg[3];
        ct_pose_rotate_grid(pose, out->ray_cam_q30, dg);
        st = ct_trace_earth_set(p, ts, &s->es, dg, m, &out->hit);
    } else if (st == CT_OK) {
        pixel_ray(p, s, out, &ray);
        if (ts != NULL) {
            st = s->bend.coeff_q16 == 0 ? ct_tileset_trace(ts, &ray, m, &out->hit)
                                        : ct_trace_bent_set_ts(p, ts, &ray, &s->bent, m, &out->hit);
        } else {
            st = s->bend.coeff_q16 == 0 ? ct_trace(p, &ray, m, &out->hit)
                                        : ct_trace_bent_set(p, &ray, &s->bent, m, &out->hit);
        }
    }
    out->status = st;
    return st;
}

/* A batch with straight rays or the lowered model on one package (ts
 * NULL) or over a tile set (p its frame; memo: the batch's, cleared), in
 * runs of up to CT_RUN_MAX
 * consecutive pixels traced together (ct_trace_run, ct_tileset_trace_run):
 * each record as one_pixel's but for hit.steps and hit.iters (the pixel's
 * own walk).  A pixel whose ray does not take that walk (an unprojection
 * or preparation error, a vertical ray of a bent trace) is done as
 * one_pixel does it. */
CT_NOINLINE static void run_pixels(const ct_package *p, ct_tileset *ts, const ct_camera *cam, const ct_pose *pose,
                                   ct_method m, const geo_setup *s, const int64_t *uv_q16, size_t count,
                                   ct_unproject_memo *memo, ct_geo *out)
{
    union {
        ct_prepared r[CT_RUN_MAX]; /* one package: the prepared rays */
        ct_ray ray[CT_RUN_MAX];    /* a tile set: the rays */
    } u;
    ct_hit *hp[CT_RUN_MAX];
    ct_status st[CT_RUN_MAX];
    size_t idx[CT_RUN_MAX];
    const ct_lower *lw = s->bend.coeff_q16 != 0 ? &s->bent.lw : NULL;
    size_t k = 0u;
    uint32_t n, i;
    /* bound: count pixels, at least one per pass */
    while (k < count) {
        /* bound: CT_RUN_MAX pixels per run */
        for (n = 0u; k < count && n < CT_RUN_MAX; ++k) {
            ct_geo *g = &out[k];
            ct_ray ray;
            ct_status sp = pixel_dir(cam, pose, uv_q16[2u * k], uv_q16[2u * k + 1u], memo, g);
            g->status = sp;
            if (sp != CT_OK) {
                continue;
            }
            pixel_ray(p, s, g, &ray);
            if (lw != NULL && (ray.dx | ray.dy) == 0) {
                /* a vertical ray of a bent trace is traced straight; every
                 * other takes ct_trace_bent_set's lowered walk (its origin
                 * the observer, within range: setup; |d| <= 2^62:
                 * ct_grid_dir_from_map) */
                g->status = ct_trace_bent_set_ts(p, ts, &ray, &s->bent, m, &g->hit);
                continue;
            }
            if (ts != NULL) {
                u.ray[n] = ray;
            } else {
                sp = ct_prepare_lowered(p, &ray, 0, lw, &u.r[n]);
                if (sp < 0) {
                    g->status = sp;
                    continue;
                }
            }
            hp[n] = &g->hit;
            idx[n] = k;
            n++;
        }
        if (ts != NULL) {
            (void)ct_tileset_trace_run(ts, u.ray, n, lw, m, hp, st);
        } else {
            (void)ct_trace_run(p, u.r, n, lw, m, hp, st);
        }
        /* bound: n <= CT_RUN_MAX */
        for (i = 0u; i < n; ++i) {
            out[idx[i]].status = st[i];
        }
    }
}

/* ct_geolocate on one package (ts NULL) or over a tile set (pkg its frame). */
static ct_status geolocate_one(const ct_package *pkg, ct_tileset *ts, const ct_camera *cam, const ct_pose *pose,
                               ct_method method, const ct_effects *effects, int64_t u_q16, int64_t v_q16, ct_geo *out)
{
    geo_setup s;
    ct_status st;
    if (out == NULL) {
        return CT_ERR_ARG;
    }
    st = setup(pkg, cam, pose, method, effects, &s); /* NULL pkg: CT_ERR_ARG */
    if (st != CT_OK) {
        out->status = st;
        return st;
    }
    return one_pixel(pkg, ts, cam, pose, method, &s, u_q16, v_q16, NULL, out);
}

/* ct_geolocate_batch likewise. */
static ct_status geolocate_many(const ct_package *pkg, ct_tileset *ts, const ct_camera *cam, const ct_pose *pose,
                                ct_method method, const ct_effects *effects, const int64_t *uv_q16, size_t count,
                                ct_geo *out, size_t out_len)
{
    geo_setup s;
    ct_unproject_memo memo;
    ct_status st;
    size_t k;
    memo.valid = 0u;
    if (count > 0u && (uv_q16 == NULL || out == NULL || out_len < count)) {
        return CT_ERR_ARG;
    }
    st = setup(pkg, cam, pose, method, effects, &s); /* NULL pkg: CT_ERR_ARG */
    if (st != CT_OK) {
        return st;
    }
    if (!s.earth && (s.bend.coeff_q16 == 0 || s.bent.lowered) && method != CT_METHOD_INCREMENTAL) {
        /* runs (the incremental method stays the plain cell-by-cell walk,
         * the reference, in a batch too) */
        run_pixels(pkg, ts, cam, pose, method, &s, uv_q16, count, &memo, out);
        return CT_OK;
    }
    /* bound: count pixels (caller's buffers) */
    for (k = 0u; k < count; ++k) {
        (void)one_pixel(pkg, ts, cam, pose, method, &s, uv_q16[2u * k], uv_q16[2u * k + 1u], &memo, &out[k]);
    }
    return CT_OK;
}

ct_status ct_geolocate(const ct_package *pkg, const ct_camera *cam, const ct_pose *pose, ct_method method,
                       const ct_effects *effects, int64_t u_q16, int64_t v_q16, ct_geo *out)
{
    CT_ASSERT(pkg != NULL && cam != NULL && pose != NULL && out != NULL);
    /* a frame (base NULL: a tile set's, no sections) as a NULL package */
    return geolocate_one(pkg != NULL && pkg->base == NULL ? NULL : pkg, NULL, cam, pose, method, effects, u_q16,
                         v_q16, out);
}

ct_status ct_geolocate_batch(const ct_package *pkg, const ct_camera *cam, const ct_pose *pose, ct_method method,
                             const ct_effects *effects, const int64_t *uv_q16, size_t count, ct_geo *out,
                             size_t out_len)
{
    CT_ASSERT(pkg != NULL && cam != NULL && pose != NULL && (count == 0u || (uv_q16 != NULL && out != NULL)));
    /* a frame (base NULL: a tile set's, no sections) as a NULL package */
    return geolocate_many(pkg != NULL && pkg->base == NULL ? NULL : pkg, NULL, cam, pose, method, effects, uv_q16,
                          count, out, out_len);
}

ct_status ct_geolocate_tiles(ct_tileset *ts, const ct_camera *cam, const ct_pose *pose, ct_method method,
                             const ct_effects *effects, int64_t u_q16, int64_t v_q16, ct_geo *out)
{
    CT_ASSERT(ts != NULL && cam != NULL && pose != NULL && out != NULL);
    /* a set not ready as a NULL package: CT_ERR_ARG */
    return geolocate_one(ts != NULL && ts->ready == CT_SET_READY ? &ts->frame : NULL, ts, cam, pose, method, effects,
                         u_q16, v_q16, out);
}

ct_status ct_geolocate_batch_tiles(ct_tileset *ts, const ct_camera *cam, const ct_pose *pose, ct_method method,
                                   const ct_effects *effects, const int64_t *uv_q16, size_t count, ct_geo *out,
                                   size_t out_len)
{
    CT_ASSERT(ts != NULL && cam != NULL && pose != NULL && (count == 0u || (uv_q16 != NULL && out != NULL)));
    /* a set not ready as a NULL package: CT_ERR_ARG */
    return geolocate_many(ts != NULL && ts->ready == CT_SET_READY ? &ts->frame : NULL, ts, cam, pose, method, effects,
                          uv_q16, count, out, out_len);
}

/* ---- effects for a tolerance ------------------------------------------ */

#define UNBOUNDED (INT64_C(1) << 62)

/* The bound for one map-frame direction d (Q39) and the coefficients' |c|
 * (Q16) in cq[3]: H the camera's height above the lowest post (nm, > 0),
 * top: the camera is below the tallest post, far: the horizontal distance
 * to the tile's farthest corner (nm, <= 2^50), R (nm). */
static void ray_bounds(const int64_t d[3], int64_t H, int top, int64_t far, int64_t R, const int64_t cq[3],
                       int64_t e[3], int64_t *rho, int64_t *tan_q30)
{
    int k;
    /* L = |(dx, dy)| < 2^40.1 */
    int64_t L = (int64_t)ct_i128_isqrt(ct_i128_add(ct_i128_mul(d[0], d[0]), ct_i128_mul(d[1], d[1])));
    int64_t dn = -d[2], r, q;
    *rho = 0;
    *tan_q30 = UNBOUNDED;
    if (dn <= 0) {
        /* level or rising: it reaches terrain only from below the top */
        for (k = 0; k < 3; ++k) { /* bound: 3 coefficients */
            e[k] = top && cq[k] != 0 ? UNBOUNDED : 0;
        }
        *rho = top ? far : 0;
        *tan_q30 = top ? 0 : UNBOUNDED;
        return;
    }
    /* rho = min(far, H L / dn): H < 2^62, L < 2^41: in 128 bits */
    r = ct_min64(far, ct_i128_floor_div_sat(ct_i128_mul(H, L), dn));
    *rho = r;
    *tan_q30 = L == 0 ? UNBOUNDED : ct_i128_floor_div_sat(ct_i128_shl(ct_i128_from64(dn), 30u), L);
    /* rho^2 / 2R: rho <= 2^50, rho^2 < 2^100, / 2^41 at least: < 2^59 */
    q = ct_i128_floor_div_sat(ct_i128_mul(r, r), 2 * R);
    for (k = 0; k < 3; ++k) { /* bound: 3 coefficients */
        /* q |c| L / (dn 2^16): q |c| < 2^59 2^18, times L < 2^41: < 2^118 */
        ct_i128 num = ct_i128_mul128_64(ct_i128_mul(q, cq[k]), L);
        ct_i128 den = ct_i128_mul(dn, 65536);
        /* den < 2^56: a 64-bit divisor */
        e[k] = ct_i128_floor_div_sat(num, ct_i128_to64(den));
    }
}

ct_status ct_effects_for_tolerance(const ct_package *p, const ct_camera *cam, const ct_pose *pose,
                                   int32_t refraction_k_q16, int64_t radius_nm, int64_t tol_nm,
                                   ct_effects_choice *out)
{
    int64_t R = radius_nm == 0 ? CT_EARTH_RADIUS_NM : radius_nm;
    int64_t k = refraction_k_q16, H, far = 0, cq[3], u_lo, u_hi, v_lo, v_hi;
    int64_t lo_nm, hi_nm;
    uint32_t i, j, n;
    int top;
    ct_utm zone;
    if (p == NULL || cam == NULL || pose == NULL || out == NULL || cam->ready == 0u || pose->ready == 0u) {
        return CT_ERR_ARG;
    }
    if (k < -K_MAX_Q16 || k > K_MAX_Q16 || R < (INT64_C(1) << 40) || R > (INT64_C(1) << 54) || tol_nm < 0) {
        return CT_ERR_EFFECTS;
    }
    /* residual coefficients: nothing simulated 1 - k, curvature only k,
     * refraction only 1 (Q16, |.| <= 3 2^16) */
    cq[0] = ct_abs64(65536 - k);
    cq[1] = ct_abs64(k);
    cq[2] = 65536;
    /* heights: |offset| <= 2^61, codes < 2^16 times scale <= 2^46 */
    lo_nm = p->height_offset_nm + (int64_t)p->hmin * p->height_scale_nm;
    hi_nm = p->height_offset_nm + (int64_t)(p->hmax + 1) * p->height_scale_nm;
    H = pose->h_nm - lo_nm; /* |h| <= 2^61 (ct_pose_init) */
    top = pose->h_nm <= hi_nm;
    /* the farthest tile corner, horizontally: origin + size posting - the
     * camera in 128 bits (|origin|, |e| <= 2^61, size < 2^32 times |posting|
     * <= 2^50), each offset capped at 2^49 */
    for (i = 0u; i < 4u; ++i) { /* bound: 4 corners */
        ct_i128 ce = ct_i128_from64(p->origin_e_nm - pose->e_nm);
        ct_i128 cn = ct_i128_from64(p->origin_n_nm - pose->n_nm);
        int64_t de, dn;
        if ((i & 1u) != 0u) {
            ce = ct_i128_add(ce, ct_i128_mul((int64_t)p->width, p->posting_e_nm));
        }
        if ((i & 2u) != 0u) {
            cn = ct_i128_add(cn, ct_i128_mul((int64_t)p->height, p->posting_n_nm));
        }
        ce = ct_i128_abs(ce);
        cn = ct_i128_abs(cn);
        de = ct_i128_cmp(ce, ct_i128_from64(INT64_C(1) << 49)) > 0 ? INT64_C(1) << 49 : ct_i128_to64(ce);
        dn = ct_i128_cmp(cn, ct_i128_from64(INT64_C(1) << 49)) > 0 ? INT64_C(1) << 49 : ct_i128_to64(cn);
        far = ct_max64(far, (int64_t)ct_i128_isqrt(ct_i128_add(ct_i128_mul(de, de), ct_i128_mul(dn, dn))));
    }
    /* the image: the lens's size, or the grid's supported extent */
    if (cam->lens.model == CT_LENS_GRID) {
        u_lo = cam->grid.u0_q16 + cam->grid.step_q16;
        v_lo = cam->grid.v0_q16 + cam->grid.step_q16;
        u_hi = cam->grid.u0_q16 + (int64_t)(cam->grid.nu - 2u) * cam->grid.step_q16;
        v_hi = cam->grid.v0_q16 + (int64_t)(cam->grid.nv - 2u) * cam->grid.step_q16;
    } else {
        u_lo = -32768; /* -0.5 px */
        v_lo = -32768;
        u_hi = ((int64_t)cam->lens.width << 16) - 32768;
        v_hi = ((int64_t)cam->lens.height << 16) - 32768;
    }
    out->flags = 0u;
    out->chord_nm = INT64_C(1) << 10;
    out->bound_nm[0] = out->bound_nm[1] = out->bound_nm[2] = out->bound_nm[3] = 0;
    out->range_nm = 0;
    out->tan_min_q30 = UNBOUNDED;
    out->samples = 0u;
    /* 4 edges x 64 points, then a 15 x 11 grid: 421 pixels */
    n = 4u * 64u + 15u * 11u;
    for (i = 0u; i < n; ++i) { /* bound: 421 pixels */
        int64_t u, v, d[3], e[3], rho, tq;
        int32_t ray[3];
        uint32_t it;
        if (i < 256u) {
            /* edge i / 64: top, right, bottom, left; 64 steps along it */
            int64_t f = (int64_t)(i % 64u), side = (int64_t)(i / 64u);
            int64_t du = (u_hi - u_lo) / 64, dv = (v_hi - v_lo) / 64;
            u = side == 0 ? u_lo + f * du : (side == 1 ? u_hi : (side == 2 ? u_hi - f * du : u_lo));
            v = side == 0 ? v_lo : (side == 1 ? v_lo + f * dv : (side == 2 ? v_hi : v_hi - f * dv));
        } else {
            j = i - 256u;
            u = u_lo + (u_hi - u_lo) * (int64_t)(j % 15u + 1u) / 16;
            v = v_lo + (v_hi - v_lo) * (int64_t)(j / 15u + 1u) / 12;
        }
        if (ct_camera_unproject(cam, u, v, ray, &it) != CT_OK || ct_pose_rotate(pose, ray, d) != CT_OK) {
            continue;
        }
        out->samples++;
        if (H <= 0) {
            e[0] = e[1] = e[2] = UNBOUNDED; /* the camera below every post */
            rho = far;
            tq = 0;
        } else {
            ray_bounds(d, H, top, far, R, cq, e, &rho, &tq);
        }
        for (j = 0u; j < 3u; ++j) { /* bound: 3 coefficients */
            out->bound_nm[j] = ct_max64(out->bound_nm[j], e[j]);
        }
        out->range_nm = ct_max64(out->range_nm, rho);
        if (rho > 0) {
            out->tan_min_q30 = ct_min64(out->tan_min_q30, tq);
        }
    }
    if (out->samples == 0u) {
        return CT_ERR_UNPROJECT;
    }
    out->flags = out->bound_nm[0] <= tol_nm   ? 0u
                 : out->bound_nm[1] <= tol_nm ? CT_EFFECT_CURVATURE
                 : out->bound_nm[2] <= tol_nm ? CT_EFFECT_REFRACTION
                                              : CT_EFFECT_ALL;
    {
        /* the chord: (tol - bound) min(tan_min, 1), the rest of the
         * tolerance on the most grazing ray (tan_min Q30; none reaching:
         * the coarsest) -- a chord's height error moves a hit on flat
         * ground by chord / tan(depression), its sideways or along-track
         * error (the true Earth's pieces) by up to the chord itself */
        int64_t used = out->flags == CT_EFFECT_ALL ? 0
                       : out->bound_nm[out->flags == 0u ? 0 : (out->flags == CT_EFFECT_CURVATURE ? 1 : 2)];
        int64_t rest = tol_nm - used;
        int64_t ch = out->tan_min_q30 >= UNBOUNDED
                         ? INT64_C(1) << 50
                         : ct_i128_floor_div_sat(ct_i128_mul(ct_max64(rest, 0), ct_min64(out->tan_min_q30, INT64_C(1) << 30)),
                                                 INT64_C(1) << 30);
        out->chord_nm = ct_max64(INT64_C(1) << 10, ct_min64(INT64_C(1) << 50, ch));
        if ((out->flags & CT_EFFECT_CURVATURE) != 0u && radius_nm == 0 && ct_package_zone(p, &zone) == CT_OK) {
            /* the true Earth: its pieces' bounds keep terms that do not
             * shrink with a piece (the camera's Q16 grid point on its own
             * piece, the vertices' rounding), so a finer chord than the
             * default is refused pixel by pixel where those exceed it
             * (up to 0.5 mm looking down at 30 m posts): never below it */
            out->chord_nm = ct_max64(out->chord_nm, CT_EFFECTS_CHORD_NM);
        }
        if (out->tan_min_q30 == 0) {
            /* a level or rising ray can reach the tile: no flat-ground
             * bound at all, the default chord */
            out->chord_nm = CT_EFFECTS_CHORD_NM;
        }
    }
    return CT_OK;
}
