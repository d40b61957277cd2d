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
#include "fixed.h"

/* |P - A| for map points in nm (each difference < 2^63 by the callers'
 * ranges, capped at 2^61: squares < 2^123, the sum < 2^125). */
static int64_t dist_nm(int64_t ae, int64_t an, int64_t ah, int64_t pe, int64_t pn, int64_t ph)
{
    int64_t d[3];
    ct_i128 s = ct_i128_from64(0);
    int k;
    d[0] = ct_min64(ct_abs64(pe - ae), INT64_C(1) << 61);
    d[1] = ct_min64(ct_abs64(pn - an), INT64_C(1) << 61);
    d[2] = ct_min64(ct_abs64(ph - ah), INT64_C(1) << 61);
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        s = ct_i128_add(s, ct_i128_mul(d[k], d[k]));
    }
    return (int64_t)ct_i128_isqrt(s);
}

ct_status ct_los(const ct_package *p, const int64_t a_nm[3], const int64_t b_nm[3], const ct_effects *effects,
                 int64_t margin_nm, ct_method m, ct_hit *block)
{
    ct_ray ray;
    ct_prepared pr;
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
    if (effects != NULL && (effects->flags & CT_EFFECT_ALL) != 0u) {
        /* the sphere model: c = [curvature] - k [refraction] > 0 as a
         * lowered walk from A; c = 0 is a straight line; c < 0 (k > 1) is
         * not offered (CT_ERR_EFFECTS) */
        ct_bend bd;
        int32_t c = 0;
        if ((effects->flags & ~(CT_EFFECT_ALL | CT_EFFECT_EARTH_FIT)) != 0u || effects->refraction_k_q16 < -131072 ||
            effects->refraction_k_q16 > 131072) {
            return CT_ERR_EFFECTS;
        }
        if ((effects->flags & CT_EFFECT_CURVATURE) != 0u) {
            c = 65536;
        }
        if ((effects->flags & CT_EFFECT_REFRACTION) != 0u) {
            c -= effects->refraction_k_q16;
        }
        if (c < 0) {
            return CT_ERR_EFFECTS;
        }
        if (c > 0) {
            bd.coeff_q16 = c;
            bd.radius_nm = effects->earth_radius_nm == 0 ? CT_EARTH_RADIUS_NM : effects->earth_radius_nm;
            bd.chord_nm = CT_EFFECTS_CHORD_NM;
            bd.flags = 0u;
            if (bd.radius_nm < (INT64_C(1) << 40) || bd.radius_nm > (INT64_C(1) << 54) ||
                ct_lower_setup(p, ax, ay, &bd, &lw) != CT_OK) {
                return CT_ERR_EFFECTS;
            }
            lwp = &lw;
        }
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
    if (st == CT_HIT || st == CT_HIT_VOID) {
        int64_t dh = dist_nm(a_nm[0], a_nm[1], a_nm[2], block->e_nm, block->n_nm, block->h_nm);
        int64_t db = dist_nm(a_nm[0], a_nm[1], a_nm[2], b_nm[0], b_nm[1], b_nm[2]);
        return dh < db - margin_nm ? CT_HIT : CT_OK;
    }
    return st == CT_BELOW ? CT_BELOW : CT_OK;
}
