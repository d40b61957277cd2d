/*
 * los.c -- intervisibility: is a map point B visible from a map point A?
 *
 * The segment from A to B (both in the grid frame, Q16, as ct_map_to_grid
 * rounds them) is prepared as a segment and traced with the caller's
 * method; with a bend (c > 0: curvature, alone or with refraction, on the
 * sphere of the effects' radius) the line of sight from A through B is the
 * lowered walk of bend.c: the terrain lowered by c rho^2 / 2R from A and
 * the straight segment from A to B lowered the same way.  The first point
 * of the surface the segment meets decides: B is hidden when that point
 * lies more than margin_nm before B (3D distance from A, nm), visible
 * otherwise -- a target on the ground is met at itself.
 */
#include "bend.h"
#include "tiles.h"
#include "fixed.h"

/* |x - y| for points in nm: map points (|.| <= 2^61, checked by the
 * callers: each difference capped at 2^61) or ECEF points (|.| < 2^55: the
 * cap never applies); squares < 2^122, the sum < 2^124. */
static int64_t dist3(const int64_t x[3], const int64_t y[3])
{
    ct_i128 s = ct_i128_from64(0);
    int k;
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        int64_t d = ct_min64(ct_abs64(x[k] - y[k]), INT64_C(1) << 61);
        s = ct_i128_add(s, ct_i128_mul(d, d));
    }
    return (int64_t)ct_i128_isqrt(s);
}

/* A map point to ECEF (nm) on the package's zone. */
static ct_status to_ecef(const ct_utm *zone, const int64_t m[3], int64_t x[3])
{
    int64_t lat, lon;
    ct_status st = ct_utm_inverse(zone, m[0], m[1], &lat, &lon);
    return st == CT_OK ? ct_ecef_from_wgs84(lat, lon, m[2], x) : st;
}

/* The true Earth's aim from A at B (map points, nm): the Earth-fixed line
 * of sight from A to B -- with refraction aimed at B raised by the bent
 * path's drop there, k t^2 / 2R along the direction earth.c bends it -- as
 * a Q39 unit vector dg in the grid frame at A (es: ct_earth_setup's for a
 * pose at A; its frame is all that is read); A and B also in ECEF (A[],
 * B[]).  fx checked by the caller.  CT_ERR_RAY: a point off the zone's
 * projection, or A = B. */
static ct_status earth_aim(const ct_earth *es, const int64_t a_nm[3], const int64_t b_nm[3],
                           const ct_effects *fx, int64_t A[3], int64_t B[3], int64_t dg[3])
{
    int64_t d[3], big = 0;
    int k, j;
    unsigned sh = 0u;
    if (to_ecef(&es->zone, a_nm, A) != CT_OK || to_ecef(&es->zone, b_nm, B) != CT_OK) {
        return CT_ERR_RAY;
    }
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        d[k] = B[k] - A[k]; /* < 2^56 */
    }
    if ((fx->flags & CT_EFFECT_REFRACTION) != 0u) {
        /* earth.c bends the path P(t) = A + t u - (k t^2 / 2R) w, u the
         * unit direction, w = up - (up . u) u with up the camera's vertical
         * (the frame's third column; refraction_axis): aim at B + (k t^2 /
         * 2R) w with t = |that aim|.  u, w and t depend on the aim: from
         * the aim B - A, three rounds (each shrinks the error by about k t
         * / R < 1e-2 at 200 km; aiming along the vertical instead misses B
         * by 1.6 m at 200 km 5 deg down).  t < 2^50 capped, t^2 |k| <
         * 2^117, / 2R saturated at 2^62, / 2^16; |aim| < 2^56 + 2^50. */
        int64_t aim[3], w[3], t, up, dot, na;
        int round;
        for (k = 0; k < 3; ++k) { /* bound: 3 axes */
            aim[k] = d[k];
        }
        for (round = 0; round < 3; ++round) { /* bound: 3 rounds */
            ct_i128 s2 = ct_i128_from64(0);
            for (k = 0; k < 3; ++k) { /* bound: 3 axes */
                s2 = ct_i128_add(s2, ct_i128_mul(aim[k], aim[k]));
            }
            na = (int64_t)ct_i128_isqrt(s2);
            if (na == 0) {
                break; /* A = B: refused below */
            }
            t = ct_min64(na, INT64_C(1) << 50);
            up = ct_floor_div(ct_i128_floor_div_sat(ct_i128_mul128_64(ct_i128_mul(t, t), fx->refraction_k_q16),
                                                    2 * CT_EARTH_RADIUS_NM),
                              65536);
            up = ct_max64(-(INT64_C(1) << 50), ct_min64(INT64_C(1) << 50, up));
            /* w: u in Q30 (|aim| 2^30 < 2^87), up . u, the rest of up */
            dot = 0;
            for (k = 0; k < 3; ++k) { /* bound: 3 axes */
                w[k] = ct_i128_round_div(ct_i128_shl(ct_i128_from64(aim[k]), 30u), na);
                dot += es->frame_q30[3 * k + 2] * w[k]; /* |.| <= 2^60 each */
            }
            dot = ct_floor_div(dot + (INT64_C(1) << 29), INT64_C(1) << 30);
            for (k = 0; k < 3; ++k) { /* bound: 3 axes; |w| <= 2^30 + 2 */
                w[k] = es->frame_q30[3 * k + 2] - ct_floor_div(dot * w[k] + (INT64_C(1) << 29), INT64_C(1) << 30);
                aim[k] = d[k] + ct_mul_shr(up, w[k], 30u);
            }
        }
        for (k = 0; k < 3; ++k) { /* bound: 3 axes */
            d[k] = aim[k];
        }
    }
    /* the direction in the grid frame at A (frame^T d), scaled to a Q39
     * unit vector: |d| < 2^57, shifted below 2^40 first */
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        big = ct_max64(big, ct_abs64(d[k]));
    }
    /* bound: 63 halvings */
    while (sh < 63u && (big >> sh) >= (INT64_C(1) << 40)) {
        sh++;
    }
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        ct_i128 s = ct_i128_from64(0);
        for (j = 0; j < 3; ++j) { /* bound: 3 terms, Q30 x 2^40 */
            s = ct_i128_add(s, ct_i128_mul(es->frame_q30[3 * j + k], ct_floor_div(d[j], INT64_C(1) << sh)));
        }
        dg[k] = ct_i128_round_shr(s, 30u); /* < 2^42 */
    }
    {
        int64_t n = (int64_t)ct_i128_isqrt(ct_i128_add(ct_i128_add(ct_i128_mul(dg[0], dg[0]), ct_i128_mul(dg[1], dg[1])),
                                                        ct_i128_mul(dg[2], dg[2])));
        if (n == 0) {
            return CT_ERR_RAY;
        }
        for (k = 0; k < 3; ++k) { /* bound: 3 axes; |dg| <= n < 2^43: 2^82 / n */
            dg[k] = ct_i128_round_div(ct_i128_shl(ct_i128_from64(dg[k]), 39u), n);
        }
    }
    return CT_OK;
}

/* ct_earth_setup at a pose with fx's refraction (bent on the sphere of
 * CT_EARTH_RADIUS_NM), no bend flags, the map fitted or given as asked:
 * CT_ERR_CRS for a package on no UTM zone (its zone check), CT_ERR_RAY for
 * a point beyond the grid's range, CT_ERR_EFFECTS for any other refusal. */
static ct_status earth_at(const ct_package *p, const ct_pose *pose, const ct_effects *fx, int64_t chord_nm, int fitted,
                          const ct_earth_map *map, ct_earth *es)
{
    ct_status st = ct_earth_setup(p, pose, (fx->flags & CT_EFFECT_REFRACTION) != 0u ? fx->refraction_k_q16 : 0,
                                  CT_EARTH_RADIUS_NM, chord_nm, 0u, fitted, map, es);
    return st == CT_OK || st == CT_ERR_CRS || st == CT_ERR_RAY ? st : CT_ERR_EFFECTS;
}

/* The true Earth (curvature with radius 0 on a UTM package): the Earth-fixed
 * line of sight from A aimed at B (earth_aim), traced by earth.c as
 * geolocation does; hidden when its first hit lies more than the margin
 * (Earth-fixed distance from A) before B.  fx checked and its chord taken
 * by the caller (ct_effects_to_bend).  CT_ERR_CRS: not UTM (earth_at). */
static ct_status los_earth(const ct_package *p, ct_tileset *ts, const int64_t a_nm[3], const int64_t b_nm[3],
                           const ct_effects *fx, int64_t chord_nm, int64_t margin_nm, ct_method m, ct_hit *block)
{
    static const int32_t ident[9] = {1 << 30, 0, 0, 0, 1 << 30, 0, 0, 0, 1 << 30};
    ct_pose pose;
    ct_earth es;
    int64_t A[3], B[3], H[3], dg[3], lim;
    ct_status st;
    if (ct_pose_init(&pose, ident, a_nm[0], a_nm[1], a_nm[2]) != CT_OK) {
        return CT_ERR_RAY;
    }
    st = earth_at(p, &pose, fx, chord_nm, (fx->flags & CT_EFFECT_EARTH_FIT) != 0u, fx->earth_map, &es);
    if (st != CT_OK) {
        return st;
    }
    st = earth_aim(&es, a_nm, b_nm, fx, A, B, dg);
    if (st != CT_OK) {
        return st;
    }
    st = ct_trace_earth_set(p, ts, &es, dg, m, block);
    if (st == CT_BELOW || st == CT_NO_DATA || st < 0) {
        return st;
    }
    if (st != CT_HIT && st != CT_HIT_VOID) {
        return CT_OK;
    }
    {
        const int64_t hm[3] = {block->e_nm, block->n_nm, block->h_nm};
        if (to_ecef(&es.zone, hm, H) != CT_OK) {
            return CT_ERR_RAY;
        }
        lim = dist3(A, B) - margin_nm;
        return dist3(A, H) < lim ? CT_HIT : CT_OK;
    }
}

/* ct_los on one package (ts NULL) or over a tile set (p its frame). */
static ct_status los_impl(const ct_package *p, ct_tileset *ts, const int64_t a_nm[3], const int64_t b_nm[3],
                          const ct_effects *effects, int64_t margin_nm, ct_method m, ct_hit *block)
{
    ct_ray ray;
    ct_prepared pr;
    ct_bend bd;
    ct_lower lw;
    const ct_lower *lwp = NULL;
    int64_t ax, ay, az, bx, by, bz;
    ct_status st;
    int k;
    if (p == NULL || a_nm == NULL || b_nm == NULL || block == NULL || margin_nm < 0) {
        return CT_ERR_ARG;
    }
    if ((uint32_t)m >= (uint32_t)CT_METHOD_COUNT) {
        return CT_ERR_METHOD;
    }
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        if (ct_abs64(a_nm[k]) > (INT64_C(1) << 61) || ct_abs64(b_nm[k]) > (INT64_C(1) << 61)) {
            return CT_ERR_RAY;
        }
    }
    if (ct_map_to_grid(p, a_nm[0], a_nm[1], a_nm[2], &ax, &ay, &az) != CT_OK ||
        ct_map_to_grid(p, b_nm[0], b_nm[1], b_nm[2], &bx, &by, &bz) != CT_OK || ct_abs64(ax) > CT_MAX_ORIGIN_Q16 ||
        ct_abs64(ay) > CT_MAX_ORIGIN_Q16 || ct_abs64(az) > CT_MAX_ORIGIN_Q16 || ct_abs64(bx) > CT_MAX_ORIGIN_Q16 ||
        ct_abs64(by) > CT_MAX_ORIGIN_Q16 || ct_abs64(bz) > CT_MAX_ORIGIN_Q16) {
        return CT_ERR_RAY;
    }
    /* the effects checked as for geolocation (both models below) */
    if (ct_effects_to_bend(p, effects, &bd) != CT_OK) {
        return CT_ERR_EFFECTS;
    }
    if (effects != NULL && (effects->flags & CT_EFFECT_CURVATURE) != 0u && effects->earth_radius_nm == 0) {
        /* the true Earth where the package is on a UTM zone */
        st = los_earth(p, ts, a_nm, b_nm, effects, bd.chord_nm, margin_nm, m, block);
        if (st != CT_ERR_CRS) {
            return st;
        }
    }
    /* the sphere model: c = [curvature] - k [refraction] > 0 as a lowered
     * walk from A; c = 0 is a straight line; c < 0 (k > 1) is not offered
     * (CT_ERR_EFFECTS) */
    if (bd.coeff_q16 < 0) {
        return CT_ERR_EFFECTS;
    }
    if (bd.coeff_q16 > 0) {
        if (ct_lower_setup(p, ax, ay, &bd, &lw) != CT_OK) {
            return CT_ERR_EFFECTS;
        }
        lwp = &lw;
    }
    ray.x_q16 = ax;
    ray.y_q16 = ay;
    ray.z_q16 = az;
    ray.dx = bx - ax; /* |.| <= 2^47 */
    ray.dy = by - ay;
    /* the segment to B lowered by the rise at B: the line of sight from A
     * through B in the lowered frame */
    ray.dz = bz - (lwp != NULL ? ct_lower_at(lwp, bx, by) : 0) - az;
    if (ray.dx == 0 && ray.dy == 0 && ray.dz == 0) {
        return CT_ERR_RAY; /* A and B the same grid point */
    }
    if (ts != NULL) {
        /* over a tile set: the same segment, walked tile by tile */
        int64_t tn, td;
        st = ct_tileset_trace_segment(ts, &ray, lwp, 0, m, block, &tn, &td);
        if (st < 0 || st == CT_NO_DATA || st == CT_BELOW) {
            return st;
        }
    } else {
        st = ct_prepare_lowered_segment(p, &ray, lwp, &pr);
        if (st < 0) {
            return st;
        }
        block->steps = block->iters = 0u;
        if (st == CT_MISS) {
            return CT_OK; /* the segment never meets the tile's box */
        }
        if (st == CT_BELOW) {
            return CT_BELOW; /* A under the surface */
        }
        st = ct_trace_prepared_lowered(p, &pr, lwp, m, block);
        if (st < 0) {
            return st;
        }
    }
    if (st == CT_HIT || st == CT_HIT_VOID) {
        int64_t h[3];
        int64_t dh, db;
        h[0] = block->e_nm;
        h[1] = block->n_nm;
        h[2] = block->h_nm;
        dh = dist3(a_nm, h);
        db = dist3(a_nm, b_nm);
        return dh < db - margin_nm ? CT_HIT : CT_OK;
    }
    return st == CT_BELOW ? CT_BELOW : CT_OK;
}

ct_status ct_los(const ct_package *p, const int64_t a_nm[3], const int64_t b_nm[3], const ct_effects *effects,
                 int64_t margin_nm, ct_method m, ct_hit *block)
{
    /* a frame (base NULL: a tile set's, no sections) as a NULL package */
    return los_impl(p != NULL && p->base == NULL ? NULL : p, NULL, a_nm, b_nm, effects, margin_nm, m, block);
}

ct_status ct_los_tiles(ct_tileset *ts, const int64_t a_nm[3], const int64_t b_nm[3], const ct_effects *effects,
                       int64_t margin_nm, ct_method m, ct_hit *block)
{
    if (ts == NULL || ts->ready != CT_SET_READY) {
        return CT_ERR_ARG;
    }
    return los_impl(&ts->frame, ts, a_nm, b_nm, effects, margin_nm, m, block);
}

/* ct_locate_inverse's direction on the true Earth: the line of sight from
 * the camera centre to G as ct_los's (earth_aim), in the grid frame at the
 * camera (Q39) -- the frame ct_geolocate's true Earth turns a camera ray
 * into (ct_pose_rotate_grid: no horizontal scale).  CT_ERR_CRS: not a UTM
 * package (the sphere then, as geolocation). */
static ct_status inverse_earth(const ct_package *p, const ct_pose *pose, const ct_effects *fx, int64_t chord_nm,
                               const int64_t g_nm[3], int64_t dg[3])
{
    ct_earth es;
    int64_t c[3], A[3], B[3];
    /* only the frame at the camera is read: no map fitted */
    ct_status st = earth_at(p, pose, fx, chord_nm, 0, NULL, &es);
    if (st != CT_OK) {
        return st;
    }
    c[0] = pose->e_nm;
    c[1] = pose->n_nm;
    c[2] = pose->h_nm;
    return earth_aim(&es, c, g_nm, fx, A, B, dg);
}

ct_status ct_locate_inverse(const ct_package *p, const ct_camera *cam, const ct_pose *pose, const ct_effects *effects,
                            const int64_t g_nm[3], int64_t margin_nm, int64_t *u_q16, int64_t *v_q16,
                            uint32_t *visible, ct_hit *block)
{
    int64_t d[3], c[3], big = 0, rise = 0;
    int32_t ray[3];
    int k, j, sh = 0, earth = 0;
    ct_status st;
    if (p == NULL || cam == NULL || pose == NULL || g_nm == NULL || u_q16 == NULL || v_q16 == NULL ||
        visible == NULL || block == NULL || cam->ready == 0u || pose->ready == 0u || p->base == NULL) {
        return CT_ERR_ARG; /* base NULL: a frame, which has no sections */
    }
    *visible = 0u;
    /* the camera centre and the ground point: |.| <= 2^61 each, the
     * difference capped at 2^62 */
    c[0] = pose->e_nm;
    c[1] = pose->n_nm;
    c[2] = pose->h_nm;
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        if (ct_abs64(g_nm[k]) > (INT64_C(1) << 61)) {
            return CT_ERR_RAY;
        }
        d[k] = g_nm[k] - c[k];
    }
    if (effects != NULL && (effects->flags & CT_EFFECT_ALL) != 0u) {
        /* the apparent point: the line of sight rises c rho^2 / 2R on its
         * way, so the camera sees the point along the tangent to the point
         * lowered by that rise (the sphere of the effects' radius); on the
         * true Earth, the Earth-fixed line of sight's own direction */
        ct_bend bd;
        if (ct_effects_to_bend(p, effects, &bd) != CT_OK) {
            return CT_ERR_EFFECTS;
        }
        if ((effects->flags & CT_EFFECT_CURVATURE) != 0u && effects->earth_radius_nm == 0) {
            st = inverse_earth(p, pose, effects, bd.chord_nm, g_nm, d);
            if (st == CT_OK) {
                earth = 1;
            } else if (st != CT_ERR_CRS) {
                return st;
            }
        }
        if (!earth) {
            /* rho^2 / 2R with rho <= 2^50 (capped): < 2^100 / 2^41 */
            int64_t de = ct_min64(ct_abs64(d[0]), INT64_C(1) << 50), dn = ct_min64(ct_abs64(d[1]), INT64_C(1) << 50);
            int64_t rho2h =
                ct_i128_floor_div_sat(ct_i128_add(ct_i128_mul(de, de), ct_i128_mul(dn, dn)), 2 * bd.radius_nm);
            /* |c| <= 3 2^16: the rise, capped at 2^60 (|d| <= 2^62: no wrap) */
            rise = ct_i128_floor_div_sat(ct_i128_mul(rho2h, bd.coeff_q16), 65536);
            rise = ct_max64(-(INT64_C(1) << 60), ct_min64(INT64_C(1) << 60, rise));
            d[2] -= rise;
        }
    }
    /* the camera frame: R^T d, with a geodetic pose's horizontal scale
     * undone first (map metres per ground metre, Q30); d scaled into 2^40
     * so the Q30 products stay within 128 bits and the result within int32 */
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        big = ct_max64(big, ct_abs64(d[k]));
    }
    /* bound: 63 halvings */
    while (sh < 63 && (big >> sh) >= (INT64_C(1) << 40)) {
        sh++;
    }
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        d[k] = ct_floor_div(d[k], INT64_C(1) << sh);
    }
    if (!earth && pose->hscale_q30 != ((int32_t)1 << 30)) {
        /* (the true Earth's direction is in the grid frame already) */
        for (k = 0; k < 2; ++k) { /* bound: 2 horizontal axes; |d| < 2^40, hscale >= 2^29 */
            d[k] = ct_i128_floor_div(ct_i128_shl(ct_i128_from64(d[k]), 30u), pose->hscale_q30);
        }
    }
    {
        int64_t r[3];
        int64_t m = 0;
        for (k = 0; k < 3; ++k) { /* bound: 3 components */
            ct_i128 s = ct_i128_from64(0);
            for (j = 0; j < 3; ++j) { /* bound: 3 terms; Q30 x 2^41 */
                s = ct_i128_add(s, ct_i128_mul(pose->R_map_cam_q30[3 * j + k], d[j]));
            }
            r[k] = ct_i128_round_shr(s, 30u); /* < 2^43 */
            m = ct_max64(m, ct_abs64(r[k]));
        }
        if (m == 0) {
            return CT_ERR_RAY; /* the point is the camera centre */
        }
        /* to int32 (|.| < 2^30): the direction is all projection needs */
        sh = 0;
        /* bound: 14 halvings */
        while ((m >> sh) >= (INT64_C(1) << 30)) {
            sh++;
        }
        for (k = 0; k < 3; ++k) { /* bound: 3 components */
            ray[k] = (int32_t)ct_floor_div(r[k], INT64_C(1) << sh);
        }
    }
    st = ct_camera_project(cam, ray, u_q16, v_q16);
    if (st != CT_OK) {
        return st;
    }
    {
        int64_t a[3];
        a[0] = pose->e_nm;
        a[1] = pose->n_nm;
        a[2] = pose->h_nm;
        st = ct_los(p, a, g_nm, effects, margin_nm, CT_METHOD_DIRECTIONAL, block);
    }
    if (st == CT_OK) {
        *visible = 1u;
        return CT_OK;
    }
    return st == CT_HIT ? CT_OK : st;
}
