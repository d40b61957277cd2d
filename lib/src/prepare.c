/*
 * prepare.c -- ray preparation: the caller's ray (or segment) clipped to
 * the tile's box, its direction normalised to int32 with the dominant
 * component in [2^25, 2^26] and z scaled by 2^-k (the zshift), its first
 * point located, the sector found, and the start decided (below the
 * surface, or the first cell); the formats and bounds are trace.c's
 * (number formats at its top) and conetrace.h's (ct_prepared).
 */
#include "tiles.h"
#include "trace_core.h"

/* A ray parameter n / d of the caller's ray: |n| < 2^48 (a distance to a
 * face of the box, or 0 or 1), 0 < d <= 2^62 (a component of the caller's
 * direction); compared in 128 bits. */
typedef struct {
    int64_t n;
    int64_t d; /* > 0 */
} bigrt;

/* a < b: products |n| d < 2^110 */
static int bigrt_lt(const bigrt *a, const bigrt *b)
{
    return ct_i128_cmp(ct_i128_mul(a->n, b->d), ct_i128_mul(b->n, a->d)) < 0;
}

/* Round o + t*D to nearest on one axis: o + round(n*D / d), the product
 * 128-bit (|n D| < 2^48 2^62), the quotient q < 2^48 (so o + q fits).  The
 * remainder n D - q d lies in [0, d) with d <= 2^62, so its low 64 bits
 * (wrapping products) are the remainder itself. */
static int64_t round_axis(int64_t o, int64_t D, const bigrt *t)
{
    ct_i128 num = ct_i128_mul(t->n, D);
    int64_t q = ct_i128_floor_div(num, t->d);
    uint64_t rem = num.lo - (uint64_t)q * (uint64_t)t->d; /* 0 <= rem < d */
    if (rem >= (uint64_t)t->d - rem) {
        q += 1;
    }
    return o + q;
}

/* a * 2^e for a <= 2^62 and a result known to be <= 2^32, rounded to
 * nearest (halves away from zero) when e < 0. */
static uint64_t scale_pow2(uint64_t a, int e)
{
    if (e >= 0) {
        return a << (unsigned)e;
    }
    if (e <= -64) {
        return 0u;
    }
    /* a + 2^(-e-1) <= 2^62 + 2^62: fits uint64 */
    return (a + ((uint64_t)1 << (unsigned)(-e - 1))) >> (unsigned)(-e);
}

/* A direction's magnitudes: the larger horizontal component h = max(|Ux|,
 * |Uy|), az = |Uz|, and their bit lengths. */
typedef struct {
    uint64_t h, az;
    unsigned bh, bz;
} dir_mag;

static dir_mag dir_magnitudes(const int64_t U[3])
{
    dir_mag g;
    g.h = (uint64_t)ct_max64(ct_abs64(U[0]), ct_abs64(U[1]));
    g.az = (uint64_t)ct_abs64(U[2]);
    g.bh = ct_bitlen64(g.h);
    g.bz = ct_bitlen64(g.az);
    return g;
}

/* z shift of a direction: the smallest k <= kmax with |Uz| / 2^k <= h (so
 * that z, in units of 2^k Q16, no longer dominates a steep ray); 0 for a
 * vertical ray.  With k0 = bitlen(|Uz|) - bitlen(h), |Uz| >> k0 <
 * 2^bitlen(h) <= 2h, so k is k0 or k0 + 1. */
static unsigned dir_zshift(const dir_mag *g, uint32_t kmax)
{
    uint64_t h = g->h, az = g->az;
    unsigned bh = g->bh, bz = g->bz, k;
    if (h == 0u || bz < bh) {
        return 0u;
    }
    k = bz - bh;
    k += (az >> k) > h ? 1u : 0u;
    return k < kmax ? k : kmax;
}

/* The direction (Ux, Uy, Uz / 2^zs) scaled so that its largest component is
 * 2^26 - 1 or 2^26.  |U| <= 2^62.  V = (Ux 2^zs, Uy 2^zs, Uz) is first
 * brought by a common power of two to a largest component m' in
 * [2^31, 2^32] (rounding error <= 1/2 in 2^31: relative 2^-32), then
 * multiplied by f / 2^32 with f = floor(2^58 / m') in [2^26, 2^27] and
 * rounded: each component is within 1/2 + 2^-5 of the exact (common)
 * scaling, whose largest component is in (2^26 - 1, 2^26].  Products
 * V' f <= 2^32 2^27 = 2^59.                                               */
static void normalize_dir(const int64_t U[3], const dir_mag *g, unsigned zs, int32_t out[3])
{
    uint64_t a[3], v[3], m = 0u, f;
    int e[3], top, k;
    /* bound: 3 components */
    for (k = 0; k < 3; ++k) {
        a[k] = (uint64_t)ct_abs64(U[k]);
    }
    top = (int)(g->bh + zs) > (int)g->bz ? (int)(g->bh + zs) : (int)g->bz;
    for (k = 0; k < 3; ++k) { /* bound: 3 components */
        /* V_k / 2^(top - 32), V_k = a_k 2^(zs for x, y) */
        e[k] = (k < 2 ? (int)zs : 0) - (top - 32);
        v[k] = scale_pow2(a[k], e[k]);
        m = v[k] > m ? v[k] : m;
    }
    f = ((uint64_t)1 << 58) / m; /* m >= 2^31 */
    for (k = 0; k < 3; ++k) { /* bound: 3 components */
        int64_t q = (int64_t)((v[k] * f + ((uint64_t)1 << 31)) >> 32);
        out[k] = (int32_t)(U[k] < 0 ? -q : q);
    }
}


/* The caller's ray clipped to the box [lo, hi] (no floor: z has only hi),
 * in exact 128-bit rationals of its unnormalised direction: *tin, *tout
 * and the entry face's axis *kin (-1: the origin is inside) and coordinate
 * *kin_at.  seg != 0: the ray also ends at t = 1.  Returns CT_OK, or
 * CT_MISS when the ray never enters the box.  |bound - o| < 2^47, |U| <=
 * 2^62: the rationals' products < 2^110. */
static ct_status clip_to_box(const int64_t O[3], const int64_t U[3], const int64_t lo[3], const int64_t hi[3], int seg,
                             bigrt *tin, bigrt *tout, int *kin, int64_t *kin_at)
{
    int k, has_out = 0;
    tin->n = 0;
    tin->d = 1;
    *tout = *tin;
    *kin = -1;
    *kin_at = 0;
    /* A segment that starts and ends inside the box (the bent walk's usual
     * case) needs no clipping: tin = 0, and every box exit is at t >= 1.
     * |O| <= 2^46, |U| <= 2^62: O + U fits in int64. */
    k = 0;
    if (seg) {
        int in = 1;
        for (k = 0; k < 3; ++k) { /* bound: 3 axes */
            int64_t e = O[k] + U[k];
            if ((k < 2 && (O[k] < lo[k] || e < lo[k])) || O[k] > hi[k] || e > hi[k]) {
                in = 0;
            }
        }
        if (in) {
            has_out = 1;
            tout->n = 1;
            k = 3; /* skip the clip below */
        } else {
            k = 0;
        }
    }
    /* bound: 3 axes */
    for (; k < 3; ++k) {
        bigrt a, b;
        int floorless = (k == 2);
        if (U[k] == 0) {
            if ((!floorless && O[k] < lo[k]) || O[k] > hi[k]) {
                return CT_MISS;
            }
            continue;
        }
        a.d = b.d = ct_abs64(U[k]);
        /* |bound - o| < 2^47 */
        if (U[k] > 0) {
            a.n = lo[k] - O[k];
            b.n = hi[k] - O[k];
            /* tin >= 0: an entry at a.n <= 0 (behind the origin) is never later */
            if (!floorless && a.n > 0 && bigrt_lt(tin, &a)) {
                *tin = a;
                *kin = k;
                *kin_at = lo[k];
            }
            if (!has_out || bigrt_lt(&b, tout)) {
                *tout = b;
                has_out = 1;
            }
        } else {
            a.n = O[k] - hi[k];
            b.n = O[k] - lo[k];
            if (a.n > 0 && bigrt_lt(tin, &a)) {
                *tin = a;
                *kin = k;
                *kin_at = hi[k];
            }
            if (!floorless && (!has_out || bigrt_lt(&b, tout))) {
                *tout = b;
                has_out = 1;
            }
        }
    }
    if (seg) {
        bigrt one;
        one.n = 1;
        one.d = 1;
        if (!has_out || bigrt_lt(&one, tout)) {
            *tout = one;
            has_out = 1;
        }
    }
    /* tin = 0 (the origin inside): a miss when tout < 0, by its sign */
    return has_out && (tin->n == 0 ? tout->n < 0 : bigrt_lt(tout, tin)) ? CT_MISS : CT_OK;
}

/* The entry point O + tin U (tin > 0), rounded to Q16 and kept in the box;
 * CT_BELOW when it lies below -2^46 (every surface is >= 0; its z would not
 * fit the rounding).  The box has no floor: a ray may enter through a side
 * face far below the terrain (z unbounded below).  (oz + 2^46) d + n U_z <
 * 0 with |oz + 2^46| <= 2^47, d <= 2^62, n < 2^48: 128-bit. */
static ct_status entry_point(int64_t O[3], const int64_t U[3], const bigrt *tin, int kin, int64_t kin_at,
                             const int64_t lo[3], const int64_t hi[3])
{
    int k;
    ct_i128 zq = ct_i128_add(ct_i128_mul(O[2] + CT_MAX_ORIGIN_Q16, tin->d), ct_i128_mul(tin->n, U[2]));
    if (ct_i128_sign(zq) < 0) {
        return CT_BELOW;
    }
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        /* on the entry face's axis the point is the face itself, exactly
         * (o + (bound - o)/U U): no division */
        O[k] = k == kin ? kin_at : round_axis(O[k], U[k], tin);
    }
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        if (O[k] > hi[k]) {
            O[k] = hi[k];
        }
        if (k < 2 && O[k] < lo[k]) {
            O[k] = lo[k];
        }
    }
    return CT_OK;
}

/* The quantised ray from the (entry) point O and the caller's direction U:
 * the per-axis scaling (z in units of 2^zs Q16, see ct_prepared), the
 * direction normalised, the origin's z rounded to those units (O[2] <=
 * hi[2], a multiple of 2^16, stays in the box; |O[2]| <= 2^46), the
 * horizontal length's bounds and the sector.  Returns CT_OK or
 * ct_sector_of's error. */
static ct_status quantise(const ct_package *p, const int64_t O[3], const int64_t U[3], ct_prepared *out)
{
    int32_t D[3];
    dir_mag mag = dir_magnitudes(U);
    unsigned zs = dir_zshift(&mag, p->zshift_max);
    int64_t oz = O[2];
    normalize_dir(U, &mag, zs, D);
    if (zs > 0u && D[0] == 0 && D[1] == 0) {
        /* horizontal components too small to survive: a vertical ray,
         * which the tracer handles in Q16 */
        zs = 0u;
        normalize_dir(U, &mag, zs, D);
    }
    if (zs > 0u) {
        oz = floor_shr(oz + (INT64_C(1) << (zs - 1u)), zs);
    }
    out->ox = O[0];
    out->oy = O[1];
    out->oz = oz;
    out->dx = D[0];
    out->dy = D[1];
    out->dz = D[2];
    out->zshift = (int32_t)zs;
    {
        /* dx^2 + dy^2 <= 2^53 */
        uint64_t l2 = (uint64_t)((int64_t)D[0] * D[0] + (int64_t)D[1] * D[1]);
        uint64_t l = ct_isqrt64(l2);
        out->len_lo = (int64_t)l;
        out->len_hi = (int64_t)l + (l * l != l2 ? 1 : 0);
    }
    if (D[0] != 0 || D[1] != 0) {
        uint32_t s;
        ct_status st = ct_sector_of(p, D[0], D[1], &s);
        if (st != CT_OK) {
            return st;
        }
        out->sector = (int32_t)s;
    } else {
        out->sector = -1;
    }
    return CT_OK;
}

/* Preparation in two parts.  prep_geom clips the ray to p's box and
 * quantises it (origin, direction, zshift, length, sector): geometry only,
 * no heights read, so a tile set prepares against its whole extent (a
 * header-only package).  prep_finish decides the first point against the
 * surface of sp -- the package holding it; in a tile set the tile, whose
 * grid is p's shifted by (offx, offy) Q16, whole cells -- and forms tend
 * in p's box.  seg != 0: the ray ends at origin + direction (t <= 1 in the
 * caller's parameter) as well as at the box.  prep_geom returns CT_OK
 * (then out->start is not yet set), or CT_MISS / CT_BELOW (out->start set)
 * or an error. */
static ct_status prep_geom(const ct_package *p, const ct_ray *ray, int seg, ct_prepared *out)
{
    int64_t O[3], U[3], lo[3], hi[3];
    bigrt tin, tout;
    int k, kin;
    int64_t kin_at; /* the entry face's coordinate on axis kin */
    ct_status st;
    CT_ASSERT(p != NULL && ray != NULL && out != NULL);
    if (p == NULL || ray == NULL || out == NULL) {
        return CT_ERR_ARG;
    }
    O[0] = ray->x_q16;
    O[1] = ray->y_q16;
    O[2] = ray->z_q16;
    U[0] = ray->dx;
    U[1] = ray->dy;
    U[2] = ray->dz;
    /* bound: 3 axes */
    for (k = 0; k < 3; ++k) {
        if (ct_abs64(O[k]) > CT_MAX_ORIGIN_Q16 || ct_abs64(U[k]) > (INT64_C(1) << 62)) {
            return CT_ERR_RAY;
        }
    }
    if (U[0] == 0 && U[1] == 0 && U[2] == 0) {
        return CT_ERR_RAY;
    }
    lo[0] = 0;
    hi[0] = (int64_t)p->cells_x * ONE16;
    lo[1] = 0;
    hi[1] = (int64_t)p->cells_y * ONE16;
    lo[2] = 0; /* unused: the box has no floor (a ray entering below the
                  surface is BELOW) */
    hi[2] = ((int64_t)p->hmax + 1) * ONE16;
    st = clip_to_box(O, U, lo, hi, seg, &tin, &tout, &kin, &kin_at);
    if (st == CT_OK && tin.n > 0) {
        st = entry_point(O, U, &tin, kin, kin_at, lo, hi);
    }
    if (st != CT_OK) {
        out->start = st;
        return st;
    }
    return quantise(p, O, U, out);
}

void ct_prepared_first_cell(const ct_package *p, const ct_prepared *r, int32_t *i, int32_t *j)
{
    /* the cell holding the first point (as the walk's locate at t = 0:
     * -1 .. cells on an axis) */
    *i = axis_cell(r->ox, ONE16, r->dx > 0 ? 1 : (r->dx < 0 ? -1 : 0), (int32_t)p->cells_x);
    *j = axis_cell(r->oy, ONE16, r->dy > 0 ? 1 : (r->dy < 0 ? -1 : 0), (int32_t)p->cells_y);
}

/* (fi, fj): the first point's cell of p (ct_prepared_first_cell). */
static ct_status prep_finish(const ct_package *p, const ct_package *sp, int64_t offx, int64_t offy, int32_t fi,
                             int32_t fj, const ct_ray *ray, int seg, const ct_lower *lw, ct_prepared *out)
{
    int64_t O[3];
    int32_t D[3];
    unsigned zs = (unsigned)out->zshift;
    int64_t zone = ONE16 >> zs;
    ct_status start;
    int k;
    O[0] = out->ox;
    O[1] = out->oy;
    O[2] = out->oz;
    D[0] = out->dx;
    D[1] = out->dy;
    D[2] = out->dz;
    /* the first point: below, on, or above the surface (exact); decided
     * first, so that tend below is formed only for a point at or above the
     * surface (z >= 0: every candidate < 2^34) */
    {
        /* in sp's grid (a tile set's tile: shifted by whole cells) */
        int32_t i = fi - (int32_t)(offx >> 16), j = fj - (int32_t)(offy >> 16);
        int64_t s, f, lx = O[0] - offx, ly = O[1] - offy;
        if (O[2] < -(INT64_C(1) << (46u - zs))) {
            start = CT_BELOW;
        } else if (sp == NULL) {
            start = CT_OK; /* a tile set's caller: above every post of the tile */
        } else if (lw != NULL && O[2] * (INT64_C(1) << zs) > (int64_t)cell_hmax(sp, i, j) * ONE16) {
            start = CT_OK; /* above the cell's tallest post (|O[2] 2^zs| <= 2^46) */
        } else if (lw != NULL) {
            /* the lowered surface, Q16 2^32: z_q16 2^32 < 2^78 */
            int sg = ct_i128_cmp(ct_i128_shl(ct_i128_from64(O[2] * (INT64_C(1) << zs)), 32),
                                 ct_surface_low_q48(sp, lw, i, j, lx, ly));
            start = sg < 0 ? CT_BELOW : (sg == 0 ? CT_HIT : CT_OK);
        } else {
            s = surface_q32(sp, i, j, lx, ly);
            f = O[2] * (INT64_C(1) << zs) * ONE16 - s; /* |oz 2^zs| <= 2^46: < 2^62 */
            start = f < 0 ? CT_BELOW : (f == 0 ? CT_HIT : CT_OK);
        }
    }
    if (start == CT_BELOW) {
        /* decided before tend: below the surface, z may be far under the
         * box, where tend's rationals would not fit */
        out->tend_n = 0;
        out->tend_d = 1;
        out->start = CT_BELOW;
        return CT_BELOW;
    }
    /* tend: leaving the box horizontally, through the top (rising) or
     * below hmin - 1 (descending; never reached without a hit).          */
    {
        rt te = box_exit(p, O, D, zone, lw != NULL ? lw->dmax >> zs : 0), c;
        if (seg) {
            /* the segment's end: where the prepared ray reaches the end
             * point's coordinate on its dominant axis m.  The end is
             * origin + U: |origin| <= 2^46, |U| <= 2^62, so the sum fits;
             * the entry |O[m]| <= 2^47, so the difference fits.  Beyond
             * 2^34 the box exit above is nearer anyway (box < 2^34).    */
            int m = 0;
            int64_t e, num;
            for (k = 1; k < 3; ++k) { /* bound: 2 axes */
                if (ct_abs64(D[k]) > ct_abs64(D[m])) {
                    m = k;
                }
            }
            e = m == 0 ? ray->x_q16 + ray->dx : (m == 1 ? ray->y_q16 + ray->dy : ray->z_q16 + ray->dz);
            num = (e - (m == 2 ? O[2] * (INT64_C(1) << zs) : O[m])) * (D[m] > 0 ? 1 : -1);
            if (num < 0) {
                num = 0;
            }
            if (m == 2) {
                /* in prepared z units, rounded up */
                num = (num >> zs) + ((num & ((INT64_C(1) << zs) - 1)) != 0 ? 1 : 0);
            }
            if (num < (INT64_C(1) << 34)) {
                c.n = num;
                c.d = ct_abs64(D[m]);
                if (rt_lt(c, te)) {
                    te = c;
                }
            }
        }
        out->tend_n = te.n;
        out->tend_d = te.d;
    }
    out->start = start;
    return start;
}

ct_status ct_tile_prep_geom(const ct_package *frame, const ct_ray *ray, int seg, ct_prepared *out)
{
    return prep_geom(frame, ray, seg, out);
}

ct_status ct_tile_prep_finish(const ct_package *frame, const ct_package *tile, int64_t offx, int64_t offy, int32_t fi,
                              int32_t fj, const ct_ray *ray, int seg, const ct_lower *lw, ct_prepared *out)
{
    return prep_finish(frame, tile, offx, offy, fi, fj, ray, seg, lw, out);
}

ct_status ct_prepare_lowered(const ct_package *p, const ct_ray *ray, int seg, const ct_lower *lw, ct_prepared *out)
{
    int32_t i, j;
    ct_status st;
    if (p != NULL && p->base == NULL) {
        return CT_ERR_ARG; /* a frame (a tile set's): no sections to trace */
    }
    st = prep_geom(p, ray, seg, out);
    if (st != CT_OK) {
        return st;
    }
    /* the first point is on the tile: the cell it is in, clamped */
    ct_prepared_first_cell(p, out, &i, &j);
    i = ct_clamp_cell(i, p->cells_x);
    j = ct_clamp_cell(j, p->cells_y);
#if CT_HAVE_PREFETCH
    if (out->sector >= 0 && (uint64_t)p->coarse_x * p->coarse_y * p->sectors > (UINT64_C(1) << 20)) {
        /* hosts, angle planes beyond L2 (as trace.c's set_ctx): start
         * loading the first cone's code and apex (directional) while the
         * first point is decided (a package opened whole, as prep_finish
         * reads its posts: its planes are there) */
        size_t k = ct_coarse_index(p, i, j);
        CT_PREFETCH(p->angles + (size_t)(uint32_t)out->sector * p->coarse_x * p->coarse_y + k);
        CT_PREFETCH(p->apex + 2u * k);
    }
#endif
    return prep_finish(p, p, 0, 0, i, j, ray, seg, lw, out);
}

ct_status ct_ray_prepare(const ct_package *p, const ct_ray *ray, ct_prepared *out)
{
    return ct_prepare_lowered(p, ray, 0, NULL, out);
}

ct_status ct_ray_prepare_segment(const ct_package *p, const ct_ray *ray, ct_prepared *out)
{
    return ct_prepare_lowered(p, ray, 1, NULL, out);
}


ct_status ct_prepare_lowered_segment(const ct_package *p, const ct_ray *ray, const ct_lower *lw, ct_prepared *out)
{
    return ct_prepare_lowered(p, ray, 1, lw, out);
}
