/*
 * bend.c -- rays bent by earth curvature and atmospheric refraction.
 *
 * The curve: P(s) = O + (s / L) * U + (0, 0, drop(s)), s >= 0 the
 * horizontal range from the observer O in Q16 fine cells, U the caller's
 * direction reduced to |U| <= 2^30 per component, L = floor(sqrt(Ux^2 +
 * Uy^2)) (so the horizontal range is s up to a relative 2^-30), and
 *     drop(s) = c * rho^2 / (2 R)   converted to Q16 height LSB,
 *     rho = s * posting / 2^16      (nm).
 * Vertices at s_k = k * Delta, rounded to Q16; each chord is traced exactly
 * as a segment.  A parabola with second derivative q deviates from its chord
 * over a length Delta by at most q Delta^2 / 8, so Delta = sqrt(8 eps R / |c|)
 * keeps the polyline within eps of the curve (plus vertex rounding).
 *
 * Formats and bounds (all integers):
 *   s, Delta      int64 Q16 cells; |s| < 2^52 nm / posting * 2^16 < 2^63.
 *   rho           int64 nm, checked < 2^52.
 *   drop          c * rho^2 < 2^18 * 2^104 = 2^122 (128-bit), divided by
 *                 2R (< 2^55) and by the height scale, saturated at 2^62.
 *   vertex        O + s * U / L: s * U < 2^63 * 2^30 (128-bit), / L.
 */
#include "bend.h"
#include "tiles.h"
#include "fixed.h"

#define ONE16 INT64_C(65536)
#define RHO_MAX_NM (INT64_C(1) << 52)
/* the polyline's longest segment (1,126 km) */
#define SEG_MAX_NM (INT64_C(1) << 50)
#define DIR_MAX (INT64_C(1) << 30)
/* Largest run of segments culled at once: 2^10 (e.g. 245 km of 240 m
 * segments); the cull's box then reaches the mipmap's top levels. */
#define CT_BEND_MAX_RUN_LOG2 10

typedef struct {
    int64_t x, y, z;
    int64_t line, drop; /* z = line + drop (unless saturated): the straight
                           ray's height and the bend's, Q16 */
} v3;

typedef struct {
    const ct_package *p;
    int64_t ox, oy, oz;    /* observer, Q16 */
    int64_t ux, uy, uz;    /* reduced direction, |.| <= 2^30 */
    int64_t L;             /* floor(|(ux, uy)|) >= 1 */
    int64_t coeff;         /* c, Q16 */
    int64_t radius;        /* nm */
    int64_t posting;       /* |posting|, nm */
} bent;

/* round(s * u / L) for s >= 0, |u| <= 2^30, 1 <= L < 2^31: in 64 bits when
 * s < 2^31 (|s u| < 2^61, so 2 s u + L fits), else through 128 bits.  Both
 * give floor((2 s u + L) / 2L), the same value. */
static int64_t scale_round(int64_t s, int64_t u, int64_t L)
{
    if (s < (INT64_C(1) << 31)) {
        return ct_floor_div(2 * s * u + L, 2 * L);
    }
    return ct_i128_round_div_sat(ct_i128_mul(s, u), L);
}

/* The vertex at range s (Q16 cells, s >= 0).  Returns CT_ERR_RANGE when
 * the range exceeds RHO_MAX_NM. */
static ct_status vertex(const bent *b, int64_t s, v3 *v)
{
    ct_i128 rho2, sp;
    int64_t rho, drop;
    /* rho = floor(s * posting / 2^16): s < 2^63, posting < 2^62, both >= 0:
     * the unsigned 128-bit product shifted right by 16 */
    sp = ct_umul64((uint64_t)s, (uint64_t)b->posting);
    if ((sp.hi >> 16) != 0u) {
        return CT_ERR_RANGE;
    }
    rho = (int64_t)((sp.hi << 48) | (sp.lo >> 16));
    if (rho >= RHO_MAX_NM || rho < 0) {
        return CT_ERR_RANGE;
    }
    /* c * rho^2: |c| <= 2^18, rho^2 < 2^104 -> < 2^122 */
    rho2 = ct_umul64((uint64_t)rho, (uint64_t)rho);
    {
        ct_i128 num = ct_i128_mul128_64(rho2, b->coeff);
        /* drop_q16 = c_q16 / 2^16 * rho^2 / (2R) * 2^16 / scale
         *          = c_q16 * rho^2 / (2 R scale): divide by 2R, then scale */
        int64_t q1 = ct_i128_floor_div_sat(num, 2 * b->radius);
        drop = ct_floor_div(q1, b->p->height_scale_nm);
    }
    /* s * U / L: |s| < 2^63, |U| <= 2^30: 128-bit; quotients < 2^63 / 1 are
     * saturated at 2^62 (far outside the box: the segment clip rejects) */
    v->x = b->ox + scale_round(s, b->ux, b->L);
    v->y = b->oy + scale_round(s, b->uy, b->L);
    v->z = b->oz + scale_round(s, b->uz, b->L);
    v->line = v->z;
    v->drop = drop;
    /* keep z within +-2^62 */
    if (drop > 0 && v->z > (INT64_C(1) << 62) - drop) {
        v->z = INT64_C(1) << 62;
    } else if (drop < 0 && v->z < -(INT64_C(1) << 62) - drop) {
        v->z = -(INT64_C(1) << 62);
    } else {
        v->z += drop;
    }
    return CT_OK;
}

/* Culling.  1 when nothing at or below zmin (Q16) stands under the
 * horizontal box [x0, x1] x [y0, y1] (Q16): zmin is above the max-mipmap's
 * maximum over the fine cells the box touches.  *over_tile says whether the
 * box meets the tile at all.  At most four mipmap reads: the level is the
 * first whose blocks are at least as wide as the box (the box top hmax when
 * none is). */
static int box_above_terrain(const ct_package *p, int64_t x0, int64_t x1, int64_t y0, int64_t y1, int64_t zmin,
                             int *over_tile)
{
    int64_t i0, i1, j0, j1, top, bi, bj;
    uint32_t l = 1u;
    *over_tile = !(x1 < 0 || y1 < 0 || x0 > (int64_t)p->cells_x * ONE16 || y0 > (int64_t)p->cells_y * ONE16);
    if (!*over_tile) {
        return 1;
    }
    /* cells touched, clamped to the tile (x0 < 0 -> cell 0) */
    i0 = ct_min64(ct_max64(x0, 0) >> 16, (int64_t)p->cells_x - 1);
    j0 = ct_min64(ct_max64(y0, 0) >> 16, (int64_t)p->cells_y - 1);
    i1 = ct_min64(x1 >> 16, (int64_t)p->cells_x - 1);
    j1 = ct_min64(y1 >> 16, (int64_t)p->cells_y - 1);
    /* bound: CT_MAX_LEVELS levels */
    while (l < p->levels && (((i1 >> l) - (i0 >> l)) > 1 || ((j1 >> l) - (j0 >> l)) > 1)) {
        l++;
    }
    if (p->levels == 0u || ((i1 >> l) - (i0 >> l)) > 1 || ((j1 >> l) - (j0 >> l)) > 1) {
        top = p->hmax;
    } else {
        top = 0;
        /* bound: at most 2 x 2 blocks */
        for (bj = j0 >> l; bj <= (j1 >> l); ++bj) {
            for (bi = i0 >> l; bi <= (i1 >> l); ++bi) {
                top = ct_max64(top, (int64_t)ct_mip_at(p, l, (uint32_t)bi, (uint32_t)bj));
            }
        }
    }
    return zmin > top * ONE16;
}

/* Culling a run of polyline segments from vertex a to vertex b (one segment
 * or 2^q consecutive ones).  Their vertices lie between a and b
 * horizontally (monotone along the ray), and every point of the polyline
 * over the run is at least
 *     min(line_a, line_b) + min(drop_a, drop_b) - chord - 2
 * (the straight part is linear, the bend's drop monotone in range for
 * either sign of c, the chords within `chord` of the curve, vertices
 * rounded by < 2 units); for a single segment (run = 0) the chord itself is
 * used: min(z_a, z_b).  The slack, 2 + max|b - a| / 2^24 Q16 units, also
 * covers each prepared segment's own rounding (entry 1/2 unit, direction
 * ~2^-26 of the distance, see ct_prepared), and vertically 2^zshift_max
 * more for the entry's z rounded to the segment's z unit (2^k Q16, k <=
 * zshift_max), so no ray the walk would trace over the run can meet the
 * surface when this returns 1: skipping the run changes no result. */
static uint64_t absdiff64(int64_t a, int64_t b)
{
    return a > b ? (uint64_t)a - (uint64_t)b : (uint64_t)b - (uint64_t)a;
}

/* A lower bound of the polyline over the run (Q16), kept within +-2^61:
 * |line| <= 2^62 + 2^46 and |drop| <= 2^62 (vertex's saturations), so each
 * is clamped to +-2^60 first (only ever lowering a bound that high, far
 * above any tile) and the sum and the chord's 2^60 at most stay in range. */
static int64_t run_floor(const v3 *a, const v3 *b, int run, int64_t chord_q16)
{
    const int64_t lim = INT64_C(1) << 60;
    if (run) {
        int64_t l = ct_min64(ct_max64(ct_min64(a->line, b->line), -lim), lim);
        int64_t d = ct_min64(ct_max64(ct_min64(a->drop, b->drop), -lim), lim);
        return l + d - ct_min64(chord_q16, lim) - 2;
    }
    return ct_min64(a->z, b->z);
}

int ct_segment_above_terrain(const ct_package *p, int64_t ax, int64_t ay, int64_t az, int64_t bx, int64_t by,
                             int64_t bz, int64_t zfloor, int *over_tile)
{
    /* |b - a| as unsigned differences (vertices lie within +-(2^62 + 2^46),
     * so a difference may not fit an int64); the slack <= 2 + 2^40 */
    uint64_t m = absdiff64(ax, bx);
    int64_t slack;
    m = absdiff64(ay, by) > m ? absdiff64(ay, by) : m;
    m = absdiff64(az, bz) > m ? absdiff64(az, bz) : m;
    slack = 2 + (int64_t)(m >> 24);
    return box_above_terrain(p, ct_min64(ax, bx) - slack, ct_max64(ax, bx) + slack, ct_min64(ay, by) - slack,
                                ct_max64(ay, by) + slack, zfloor - slack - ((int64_t)1 << p->zshift_max), over_tile);
}

static int run_above_terrain(const ct_package *p, const v3 *a, const v3 *b, int run, int64_t chord_q16,
                             int *over_tile)
{
    return ct_segment_above_terrain(p, a->x, a->y, a->z, b->x, b->y, b->z, run_floor(a, b, run, chord_q16),
                                    over_tile);
}

/* Both ends of the run inside the tile's closed box (so the polyline over
 * it is too: straight horizontally; vertically ct_ray_prepare_segment clips
 * any part above the top and starts at or above the surface). */
static int run_inside(const ct_package *p, const v3 *a, const v3 *b, int64_t ztop)
{
    int64_t wq = (int64_t)p->cells_x * ONE16, hq = (int64_t)p->cells_y * ONE16;
    return a->x >= 0 && a->y >= 0 && b->x >= 0 && b->y >= 0 && a->x <= wq && b->x <= wq && a->y <= hq &&
           b->y <= hq && a->z <= ztop && b->z <= ztop;
}

/* Range interval [s0, s1] (Q16 cells) where the horizontal path is inside
 * the tile's closed box; 0 when it never is.  Along x: ox + s ux / L in
 * [0, W]: s in [(0 - ox) L / ux, (W - ox) L / ux] (sorted).  Floors and
 * ceilings widen the interval (more segments, never a missed piece). */
static int range_in_box(const bent *b, int64_t *s0, int64_t *s1)
{
    int64_t lo = 0, hi = INT64_C(1) << 62;
    const int64_t o[2] = {b->ox, b->oy}, u[2] = {b->ux, b->uy};
    const int64_t top[2] = {(int64_t)b->p->cells_x * ONE16, (int64_t)b->p->cells_y * ONE16};
    int k;
    for (k = 0; k < 2; ++k) { /* bound: 2 axes */
        if (u[k] == 0) {
            if (o[k] < 0 || o[k] > top[k]) {
                return 0;
            }
            continue;
        }
        {
            /* (edge - o) * L: |edge - o| < 2^48, L < 2^31: < 2^79 */
            int64_t a = u[k] > 0 ? 0 : top[k], e = u[k] > 0 ? top[k] : 0;
            int64_t au = ct_abs64(u[k]);
            ct_i128 na = ct_i128_mul((a - o[k]) * (u[k] > 0 ? 1 : -1), b->L);
            ct_i128 ne = ct_i128_mul((e - o[k]) * (u[k] > 0 ? 1 : -1), b->L);
            int64_t sa = ct_i128_floor_div_sat(na, au);
            int64_t se = -ct_i128_floor_div_sat(ct_i128_neg(ne), au);
            lo = ct_max64(lo, sa);
            hi = ct_min64(hi, se);
        }
    }
    if (hi < lo) {
        return 0;
    }
    *s0 = lo;
    *s1 = hi;
    return 1;
}

/* floor(n / d) of a non-negative 128-bit n by 1 <= d < 2^32, as a 128-bit
 * value: the high word, then the low word in two 32-bit halves (each
 * partial dividend (r << 32) | half < 2^64 since r < d < 2^32). */
static ct_i128 udiv128_small(ct_i128 n, uint64_t d)
{
    ct_i128 q;
    uint64_t r, x;
    q.hi = n.hi / d;
    r = n.hi % d;
    x = (r << 32) | (n.lo >> 32);
    q.lo = (x / d) << 32;
    r = x % d;
    x = (r << 32) | (n.lo & 0xFFFFFFFFu);
    q.lo |= x / d;
    return q;
}

/* *bd's ranges (CT_ERR_ARG when one is out), and for c != 0 the square of
 * the polyline's segment length, q = 8 eps R / |c| in nm^2 (eps the chord,
 * R the radius, c = coeff_q16 / 2^16; *q = 0 for c = 0): eps R 2^19 <
 * 2^123 over |coeff_q16| >= 1, divided as a 128-bit value (udiv128_small;
 * the quotient must not be saturated to 64 bits: 8 eps R alone is ~2^75
 * nm^2 for 1 mm and 6371 km). */
static ct_status bend_q(const ct_bend *bd, ct_i128 *q)
{
    if (bd->coeff_q16 < -(4 * 65536) || bd->coeff_q16 > 4 * 65536 || bd->radius_nm < (INT64_C(1) << 40) ||
        bd->radius_nm > (INT64_C(1) << 54) || bd->chord_nm < (INT64_C(1) << 10) ||
        bd->chord_nm > (INT64_C(1) << 50) || (bd->flags & ~CT_BEND_NO_CULL) != 0u) {
        return CT_ERR_ARG;
    }
    *q = ct_i128_from64(0);
    if (bd->coeff_q16 != 0) {
        ct_i128 num = ct_i128_shl(ct_umul64((uint64_t)bd->chord_nm, (uint64_t)bd->radius_nm), 19);
        *q = udiv128_small(num, (uint64_t)ct_abs64((int64_t)bd->coeff_q16));
    }
    return CT_OK;
}

/* *bd's ranges, and (c != 0) whether the polyline's segment would be at
 * least 1024 Q16 units (1/64 cell) -- ct_bend_segment's checks without its
 * square root: floor(isqrt(q) 2^16 / posting) >= 1024 iff isqrt(q) >=
 * ceil(posting / 64) iff q >= ceil(posting / 64)^2 (ceil(posting / 64) <
 * 2^57, its square 128-bit). */
static ct_status bend_check(const ct_package *p, const ct_bend *bd)
{
    ct_i128 q;
    ct_status st = bend_q(bd, &q);
    if (st == CT_OK && bd->coeff_q16 != 0) {
        uint64_t m = ((uint64_t)ct_abs64(p->posting_e_nm) + 63u) / 64u;
        if (ct_i128_cmp(q, ct_umul64(m, m)) < 0) {
            return CT_ERR_ARG;
        }
    }
    return st;
}

ct_status ct_bend_segment(const ct_package *p, const ct_bend *bd, int64_t *delta)
{
    ct_i128 q;
    if (bend_q(bd, &q) != CT_OK) {
        return CT_ERR_ARG;
    }
    *delta = 0;
    if (bd->coeff_q16 != 0) {
        /* Delta in nm: sqrt(q); then Q16 cells: Delta_nm < 2^62, * 2^16 /
         * posting (saturated). */
        uint64_t dn = ct_i128_isqrt(q);
        /* at most SEG_MAX_NM: a segment shorter than the tolerance allows
         * is as good, and the polyline's last vertex, a segment past the
         * far side of the box, must stay within RHO_MAX_NM (a tiny |c| with
         * a large chord and R would give segments of 2^53.5 nm, and
         * CT_ERR_RANGE for every ray) */
        if (dn > (uint64_t)SEG_MAX_NM) {
            dn = (uint64_t)SEG_MAX_NM;
        }
        *delta = ct_i128_floor_div_sat(ct_i128_shl(ct_i128_from64((int64_t)dn), 16), ct_abs64(p->posting_e_nm));
        if (*delta < 1024) {
            return CT_ERR_ARG; /* chord too small for this posting */
        }
    }
    return CT_OK;
}

/* q = floor(n 2^s / d) with s chosen so that q is in [2^61, 2^63): n > 0
 * (< 2^126), 0 < d < 2^63.  Returns q; *s may be negative (n shifted right
 * first, floored).  n 2^s < 2^(62 + bitlen(d)) <= 2^125. */
static uint64_t norm_div(ct_i128 n, int64_t d, int *s)
{
    int e = 62 - ((int)ct_i128_bits(n) - (int)ct_bitlen64((uint64_t)d));
    if (e >= 0) {
        /* e <= 62 + 63 - 1: in two shifts of < 64 */
        n = ct_i128_shl(n, (unsigned)(e > 63 ? 63 : e));
        if (e > 63) {
            n = ct_i128_shl(n, (unsigned)(e - 63));
        }
    } else {
        unsigned r = (unsigned)(-e);
        n.lo = r >= 64u ? n.hi >> (r - 64u) : (n.lo >> r) | (r == 0u ? 0u : n.hi << (64u - r));
        n.hi = r >= 64u ? 0u : n.hi >> r;
    }
    *s = e;
    return (uint64_t)ct_i128_floor_div(n, d);
}

/* The lowered model's constants (ct_lower, bend.h) for an observer at the
 * ray's origin; CT_ERR_RANGE when it does not apply (c <= 0, the observer
 * too far from the tile, the rise over the tile beyond 2^16 LSB), and the
 * polyline is traced instead.
 *   D = c Q posting^2 / (2^33 R scale)  (Q16 LSB per squared Q16 cell):
 * rho_nm^2 = Q posting^2 / 2^32, rise = c rho^2 / (2R) nm, / scale * 2^16.
 * kf = floor(K 2^kshift) in [2^30, 2^32): K's relative error < 2^-29.    */
ct_status ct_lower_setup(const ct_package *p, int64_t ox, int64_t oy, const ct_bend *bd, ct_lower *lw)
{
    int64_t post = ct_abs64(p->posting_e_nm);
    int s1, s2, e;
    uint64_t q1, q2;
    if (bd->coeff_q16 <= 0 || post >= (INT64_C(1) << 40) || p->height_scale_nm <= 0) {
        return CT_ERR_RANGE;
    }
    /* c posting^2 < 2^18 2^80; / R (< 2^55); / scale (< 2^63) */
    q1 = norm_div(ct_i128_mul128_64(ct_umul64((uint64_t)post, (uint64_t)post), bd->coeff_q16), bd->radius_nm, &s1);
    q2 = norm_div(ct_i128_from64((int64_t)(q1 >> 1)), p->height_scale_nm, &s2);
    /* K = q1 2^-s1 / (2^33 scale) = (q1/2) 2^(1-s1) / 2^33 / scale
     *   = q2 2^-(s1 + s2 + 32); kf = q2 / 2^31 */
    e = s1 + s2 + 32 - 31;
    if (e < 0 || e > 127) {
        return CT_ERR_RANGE;
    }
    return ct_lower_setup_k(p, ox, oy, q2 >> 31, (uint32_t)e, (bd->flags & CT_BEND_NO_CULL) == 0u, lw);
}

ct_status ct_lower_setup_k(const ct_package *p, int64_t ox, int64_t oy, uint64_t kf, uint32_t kshift, int32_t cull,
                           ct_lower *lw)
{
    int64_t W = (int64_t)p->cells_x * ONE16, H = (int64_t)p->cells_y * ONE16;
    uint32_t e = kshift;
    int k;
    if (kf >= ((uint64_t)1 << 32) || kshift > 127u) {
        return CT_ERR_RANGE;
    }
    lw->obx = ox;
    lw->oby = oy;
    /* every corner within 2^31 on each axis: |o| <= 2^46, so no overflow */
    if (lw->obx <= W - (INT64_C(1) << 31) || lw->obx >= (INT64_C(1) << 31) ||
        lw->oby <= H - (INT64_C(1) << 31) || lw->oby >= (INT64_C(1) << 31)) {
        return CT_ERR_RANGE;
    }
    lw->kf = kf;
    lw->kshift = e;
    /* kc = floor(kf 2^48 / 2^e), at most 2^33 (a smaller kc only weakens
     * the walks' lower bounds) */
    lw->kc = e >= 48 ? (int64_t)(lw->kf >> (e - 48)) : INT64_C(1) << 33;
    if (e < 48 && e >= 15 && (lw->kf >> (e - 15)) == 0u) {
        lw->kc = (int64_t)(lw->kf << (48 - e)); /* kf 2^(48-e) < 2^33 */
    }
    lw->kc = ct_min64(lw->kc, INT64_C(1) << 33);
    lw->dmax = 0;
    /* the largest rise is at a corner: bound 4 corners */
    for (k = 0; k < 4; ++k) {
        uint64_t ex = (uint64_t)ct_abs64(((k & 1) ? W : 0) - lw->obx);
        uint64_t ey = (uint64_t)ct_abs64(((k & 2) ? H : 0) - lw->oby);
        ct_i128 d = ct_umul64(ex * ex + ey * ey, lw->kf); /* < 2^63 * 2^32 */
        if (ct_i128_bits(d) > 32u + lw->kshift) {
            return CT_ERR_RANGE; /* D >= 2^32 */
        }
        lw->dmax = ct_max64(lw->dmax, ct_lower_at(lw, (k & 1) ? W : 0, (k & 2) ? H : 0));
    }
    lw->cull = cull;
    return CT_OK;
}

ct_status ct_bent_prepare(const ct_package *p, const ct_bend *bd, int64_t ox, int64_t oy, ct_bent_setup *bs)
{
    ct_status st;
    CT_ASSERT(p != NULL && bd != NULL && bs != NULL);
    if (p == NULL || bd == NULL || bs == NULL) {
        return CT_ERR_ARG;
    }
    st = bend_check(p, bd);
    if (st != CT_OK) {
        return st;
    }
    bs->bend = *bd;
    bs->delta = 0;
    bs->lowered = bd->coeff_q16 != 0 && ct_lower_setup(p, ox, oy, bd, &bs->lw) == CT_OK;
    /* the polyline's segment length only where the polyline is traced */
    return bs->lowered ? CT_OK : ct_bend_segment(p, bd, &bs->delta);
}

ct_status ct_trace_bent(const ct_package *p, const ct_ray *ray, const ct_bend *bd, ct_method m,
                        ct_hit *h)
{
    ct_bent_setup bs;
    ct_status st;
    CT_ASSERT(p != NULL && ray != NULL && bd != NULL && h != NULL);
    if (p == NULL || ray == NULL || bd == NULL || h == NULL || p->base == NULL) {
        return CT_ERR_ARG; /* base NULL: a frame, which has no sections */
    }
    st = ct_bent_prepare(p, bd, ray->x_q16, ray->y_q16, &bs);
    if (st != CT_OK) {
        return st;
    }
    return ct_trace_bent_set(p, ray, &bs, m, h);
}

static ct_status trace_polyline(const ct_package *p, ct_tileset *ts, const ct_ray *ray, const ct_bent_setup *bs,
                                ct_method m, ct_hit *h);

ct_status ct_trace_bent_set(const ct_package *p, const ct_ray *ray, const ct_bent_setup *bs, ct_method m,
                            ct_hit *h)
{
    return ct_trace_bent_set_ts(p, NULL, ray, bs, m, h);
}

ct_status ct_trace_bent_set_ts(const ct_package *p, ct_tileset *ts, const ct_ray *ray, const ct_bent_setup *bs,
                               ct_method m, ct_hit *h)
{
    CT_ASSERT(p != NULL && ray != NULL && bs != NULL && h != NULL);
    if (p == NULL || ray == NULL || bs == NULL || h == NULL) {
        return CT_ERR_ARG;
    }
    if (bs->bend.coeff_q16 == 0 || (ray->dx == 0 && ray->dy == 0)) {
        return ts != NULL ? ct_tileset_trace(ts, ray, m, h) : ct_trace(p, ray, m, h);
    }
    if ((uint32_t)m >= (uint32_t)CT_METHOD_COUNT) {
        return CT_ERR_METHOD;
    }
    if (ct_abs64(ray->x_q16) > CT_MAX_ORIGIN_Q16 || ct_abs64(ray->y_q16) > CT_MAX_ORIGIN_Q16 ||
        ct_abs64(ray->z_q16) > CT_MAX_ORIGIN_Q16 || ct_abs64(ray->dx) > (INT64_C(1) << 62) ||
        ct_abs64(ray->dy) > (INT64_C(1) << 62) || ct_abs64(ray->dz) > (INT64_C(1) << 62)) {
        return CT_ERR_RAY;
    }
    if (bs->lowered) {
        if (ray->x_q16 != bs->lw.obx || ray->y_q16 != bs->lw.oby) {
            return CT_ERR_ARG; /* set up for another observer */
        }
        /* one straight walk against the lowered terrain */
        return ts != NULL ? ct_tileset_trace_lowered(ts, ray, &bs->lw, m, h) : ct_trace_lowered(p, ray, &bs->lw, m, h);
    }
    return trace_polyline(p, ts, ray, bs, m, h);
}

/* The polyline's parameters from the caller's ray (the observer and the
 * tangent): its direction reduced to |U| <= 2^30, rounding.  Returns 0 when
 * the horizontal part vanishes there (below 2^-31 of the ray: no bending
 * over the tile). */
static int bent_init(bent *b, const ct_package *p, const ct_ray *ray, const ct_bend *bd)
{
    int64_t mx;
    unsigned sh = 0u;
    b->p = p;
    b->ox = ray->x_q16;
    b->oy = ray->y_q16;
    b->oz = ray->z_q16;
    b->ux = ray->dx;
    b->uy = ray->dy;
    b->uz = ray->dz;
    mx = ct_max64(ct_abs64(b->ux), ct_max64(ct_abs64(b->uy), ct_abs64(b->uz)));
    while ((mx >> sh) > DIR_MAX) { /* bound: 32 halvings (|U| <= 2^62) */
        sh++;
    }
    if (sh > 0u) {
        int64_t half = INT64_C(1) << (sh - 1u);
        b->ux = b->ux >= 0 ? (b->ux + half) >> sh : -((-b->ux + half) >> sh);
        b->uy = b->uy >= 0 ? (b->uy + half) >> sh : -((-b->uy + half) >> sh);
        b->uz = b->uz >= 0 ? (b->uz + half) >> sh : -((-b->uz + half) >> sh);
    }
    if (b->ux == 0 && b->uy == 0) {
        return 0;
    }
    /* ux^2 + uy^2 <= 2^61 */
    b->L = (int64_t)ct_isqrt64((uint64_t)(b->ux * b->ux + b->uy * b->uy));
    b->coeff = bd->coeff_q16;
    b->radius = bd->radius_nm;
    b->posting = ct_abs64(p->posting_e_nm);
    return 1;
}

/* Whether the run of segments va .. vb (run: more than one segment) may be
 * skipped untraced: the max-mipmap shows it above all terrain under it, and
 * ct_ray_prepare_segment's answer for each segment is known without it --
 * off the tile or above the box (CT_MISS), or inside the box above the
 * surface (CT_OK: the polyline has entered; *entered set). */
static int run_culled(const ct_package *p, const ct_bend *bd, const ct_tileset *ts, const v3 *va, const v3 *vb, int run,
                      int64_t chord_q16, int64_t ztop, int *entered)
{
    int over = 0, inside;
    if (ts != NULL || (bd->flags & CT_BEND_NO_CULL) != 0u || !run_above_terrain(p, va, vb, run, chord_q16, &over)) {
        return 0;
    }
    inside = run_inside(p, va, vb, ztop);
    if (!over || run_floor(va, vb, run, chord_q16) > ztop || inside) {
        if (inside) {
            *entered = 1;
        }
        return 1;
    }
    return 0;
}

typedef enum { SEG_SKIP, SEG_BELOW, SEG_TRACED } seg_outcome;

/* One segment of the polyline traced exactly, over the set (ts) or p:
 * SEG_SKIP when it never enters the box; SEG_BELOW when it starts below the
 * surface before the polyline entered the box (the whole trace is then
 * CT_BELOW); else SEG_TRACED with its status returned, *sh its trace and
 * tn / td where the segment ends on its prepared ray.  A start below the
 * surface after the polyline entered is a hit there: the polyline crossed
 * the surface within the vertex rounding between the previous segment's
 * end and this start.  Errors (< 0) are returned as they come. */
static ct_status trace_segment(const ct_package *p, ct_tileset *ts, const ct_ray *seg, int entered, ct_method m,
                               seg_outcome *oc, ct_hit *sh, int64_t *tn, int64_t *td)
{
    ct_prepared pr;
    ct_status st;
    *oc = SEG_SKIP;
    if (ts != NULL) {
        st = ct_tileset_trace_segment(ts, seg, NULL, entered, m, sh, tn, td);
        /* td 0: decided by the set's preparation, before any tile (tend
         * unset): a segment off the box (CT_MISS), or one entering a side
         * face over 2^46 under the terrain (CT_BELOW, as
         * ct_ray_prepare_segment's below the box: before the polyline
         * entered, the whole trace is CT_BELOW; once entered, every
         * segment starts in the footprint, so it cannot enter a side
         * face).  Every other outcome sets tend (td >= 1), CT_NO_DATA at
         * the first point too; errors are returned as they come. */
        if (*td != 0) {
            *oc = SEG_TRACED;
        } else if (st == CT_BELOW) {
            *oc = SEG_BELOW;
        }
        return st;
    }
    st = ct_ray_prepare_segment(p, seg, &pr);
    if (st < 0 || st == CT_MISS) {
        return st;
    }
    if (st == CT_BELOW) {
        if (!entered) {
            *oc = SEG_BELOW;
            return st;
        }
        pr.start = CT_HIT;
    }
    st = ct_trace_prepared_own(p, &pr, m, sh);
    *tn = pr.tend_n;
    *td = pr.tend_d;
    *oc = SEG_TRACED;
    return st;
}

/* The polyline (c < 0, or the lowered model out of range); its own
 * function, kept out of line, so that its large frame is not on the
 * lowered walk's stack.  The ray is checked by the caller.  ts != NULL: a
 * tile set (p its frame): each segment walked tile by tile, without the
 * mipmap culling (the frame has no mipmap; culling changes no result). */
CT_NOINLINE static ct_status trace_polyline(const ct_package *p, ct_tileset *ts, const ct_ray *ray,
                                            const ct_bent_setup *bs, ct_method m, ct_hit *h)
{
    const ct_bend *bd = &bs->bend;
    bent b;
    int64_t s0, s1, delta = bs->delta, k0, k1, k, chord_q16;
    int64_t ztop;
    int q;
    int entered = 0;
    uint32_t steps = 0u, iters = 0u;
    v3 va, vb;
    ct_status st;
    if (!bent_init(&b, p, ray, bd)) {
        return ts != NULL ? ct_tileset_trace(ts, ray, m, h) : ct_trace(p, ray, m, h);
    }
    h->steps = h->iters = 0u;
    if (!range_in_box(&b, &s0, &s1)) {
        h->x_q16 = h->y_q16 = h->z_q16 = 0;
        h->cell_x = h->cell_y = -1;
        return CT_MISS;
    }
    k0 = s0 / delta;
    k1 = s1 / delta + 1;
    if (k1 - k0 > (int64_t)CT_BEND_MAX_SEGMENTS) {
        return CT_ERR_RANGE;
    }
    st = vertex(&b, k0 * delta, &va);
    if (st != CT_OK) {
        return st;
    }
    ztop = ((int64_t)p->hmax + 1) * ONE16;
    /* the chord tolerance in Q16 height units, rounded up (run culling) */
    chord_q16 = ct_i128_floor_div_sat(ct_i128_shl(ct_i128_from64(bd->chord_nm), 16), p->height_scale_nm) + 1;
    /* Runs of 2^q segments are culled at once where the polyline is high
     * above the terrain (q grows by one after each success, shrinks by one
     * after each failure, as the hierarchical walk's level); q = 0 is one
     * segment, culled or traced.  bound: every iteration advances k or
     * lowers q, and q rises only with an advance, so at most
     * 2 (k1 - k0) + CT_BEND_MAX_RUN_LOG2 + 1 iterations. */
    q = 0;
    for (k = k0; k < k1;) { /* bound: see above */
        ct_ray seg;
        ct_hit sh;
        int64_t tn = 0, td = 0;
        seg_outcome oc;
        int run;
        int64_t kn = k + ((int64_t)1 << q);
        if (q > 0 && kn > k1) {
            q--;
            continue;
        }
        st = vertex(&b, kn * delta, &vb);
        if (st != CT_OK) {
            return st;
        }
        run = q > 0;
        /* one convex segment above the box and rising: the polyline never
         * comes back (not for a run: a convex curve may dip between) */
        if (!run && b.coeff > 0 && va.z > ztop && vb.z >= va.z) {
            break;
        }
        if (run_culled(p, bd, ts, &va, &vb, run, chord_q16, ztop, &entered)) {
            steps++;
            iters++;
            va = vb;
            k = kn;
            if (q < CT_BEND_MAX_RUN_LOG2) {
                q++;
            }
            continue;
        }
        if (run) {
            q--;
            continue;
        }
        /* one segment, traced exactly */
        seg.x_q16 = va.x;
        seg.y_q16 = va.y;
        seg.z_q16 = va.z;
        if (ct_abs64(seg.x_q16) > CT_MAX_ORIGIN_Q16 || ct_abs64(seg.y_q16) > CT_MAX_ORIGIN_Q16 ||
            ct_abs64(seg.z_q16) > CT_MAX_ORIGIN_Q16) {
            /* a vertex beyond the library's origin range: only possible
             * far above or below the tile */
            va = vb;
            k = kn;
            if (seg.z_q16 < 0 && entered == 0) {
                return CT_BELOW;
            }
            continue;
        }
        /* |va| <= 2^46 (just checked) and |vb| <= 2^62 + 2^46 (vertex's
         * saturation): the differences fit in int64.  dz is kept within
         * ct_ray's +-2^62: beyond it the end vertex lies over 2^62 - 2^46
         * from the datum (saturated, or nearly), far outside every tile,
         * and is moved towards the start vertically as vertex's saturation
         * does (else ct_ray_prepare_segment would refuse it: CT_ERR_RAY). */
        seg.dx = vb.x - va.x;
        seg.dy = vb.y - va.y;
        seg.dz = ct_min64(ct_max64(vb.z - va.z, -(INT64_C(1) << 62)), INT64_C(1) << 62);
        va = vb;
        k = kn;
        if (seg.dx == 0 && seg.dy == 0 && seg.dz == 0) {
            continue;
        }
        st = trace_segment(p, ts, &seg, entered, m, &oc, &sh, &tn, &td);
        if (st < 0) {
            return st;
        }
        if (oc == SEG_SKIP) {
            continue;
        }
        if (oc == SEG_BELOW) {
            h->steps = steps;
            h->iters = iters;
            return CT_BELOW;
        }
        entered = 1;
        steps += sh.steps;
        iters += sh.iters;
        /* a hit in the last cell beyond the segment's end belongs to the
         * extension of the chord, not to the polyline.  t_q26 < 2^35,
         * tend_d <= 2^26: < 2^61; tend_n < 2^34: 2^60 */
        if (st == CT_NO_DATA ||
            ((st == CT_HIT || st == CT_HIT_VOID) && sh.t_q26 * td <= tn * (INT64_C(1) << CT_T_FRAC_BITS))) {
            *h = sh;
            h->steps = steps;
            h->iters = iters;
            return st;
        }
        if (st == CT_BELOW) {
            h->steps = steps;
            h->iters = iters;
            return CT_BELOW;
        }
    }
    h->steps = steps;
    h->iters = iters;
    h->x_q16 = h->y_q16 = h->z_q16 = 0;
    h->cell_x = h->cell_y = -1;
    return CT_MISS;
}
