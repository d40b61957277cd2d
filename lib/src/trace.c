/*
 * trace.c -- exact first hit of a prepared ray on the bilinear surface, by
 * four methods that all share one exact cell test (cell.c; so all four
 * return bit-identical hits):
 *   INCREMENTAL   grid walk over every fine cell (Musgrave)
 *   HIERARCHICAL  max-mipmap block skipping
 *   CONE          one omnidirectional cone per coarse cell
 *   DIRECTIONAL   one cone per sector per coarse cell (Paglieroni 1997)
 *
 * Number formats (see conetrace.h):
 *   positions  x, y Q16 in int64; z in units of 2^k Q16 LSB (k = the
 *              prepared ray's zshift, 0..16; a height h is h * zone,
 *              zone = 2^(16-k)).  Inside the tile box x, y < 2^31, z in
 *              [(hmin-1)*zone, (hmax+1)*zone] so |z| < 2^33 (and
 *              |z * 2^k| < 2^33 too: bounds written for z hold for both).
 *   direction  int32, max component in [2^25, 2^26].
 *   t          rational n/d, d in {1, |dx|, |dy|, |dz|, 2^26} <= 2^26;
 *              the ray is inside the box for t <= tend < 2^8 (the dominant
 *              axis moves >= 2^25 per unit t across a box of <= 2^33), so
 *              0 <= n < 2^34.
 * Every product below is annotated with its bound; all stay < 2^62 in
 * int64 except the few marked "128-bit".
 * Where z meets a horizontal quantity (the cell's exit sign, the quadratic)
 * it is scaled back to Q16 by zmul = 2^k.  Such a product is d * z_q16 at a
 * point of the cell being tested, physically bounded: the ray is in the box
 * at the cell's entry tin (< tend), |z_q16| < 2^33 there, and within one
 * cell it moves at most 2^16 |dz| / max(|dx|, |dy|) prepared z units, so
 * d * |z_q16 - z_q16(tin)| <= 2^16 |dz| 2^k <= 2^58 for d <= max(|dx|,|dy|).
 *
 * Exactness: whether the ray meets the surface in a cell is decided with
 * exact integer arithmetic (the sign of f = z_ray - S at cell faces in
 * 64-bit; the interior minimum of the quadratic f in 128-bit).  Only the
 * reported hit position is rounded: the root is computed to 2^-60 of the
 * cell (W_BITS) and the position reported at t_q26 = floor(t * 2^26).
 */
#include "tiles.h"
#include "walk.h"

static const rt T_ZERO = {0, 1};

/* Cell index for a Q26 t (den 2^42): shifts instead of divisions. */
static int32_t axis_cell_q26(int64_t num, int32_t s, int32_t ncell)
{
    return cell_rule(floor_shr(num, 16u + CT_T_FRAC_BITS), (num & ((INT64_C(1) << (16 + CT_T_FRAC_BITS)) - 1)) == 0, s,
                     ncell);
}

/* The cell index on one axis (origin o, direction d of sign s, n cells)
 * holding the ray at t.  o*d < 2^31 * 2^26, n*d < 2^60. */
static int32_t locate_axis(int64_t o, int32_t d, int32_t s, int32_t n, rt t)
{
    if (t.d == T_ONE) {
        return axis_cell_q26(o * T_ONE + t.n * (int64_t)d, s, n);
    }
    return axis_cell(o * t.d + t.n * (int64_t)d, t.d * ONE16, s, n);
}

/* Cell holding the ray at t. */
static void locate(const ctx *c, rt t, int32_t *i, int32_t *j)
{
    *i = locate_axis(c->r->ox, c->r->dx, c->sx, c->cx, t);
    *j = locate_axis(c->r->oy, c->r->dy, c->sy, c->cy, t);
}

static int inside(const ctx *c, int32_t i, int32_t j)
{
    return i >= 0 && j >= 0 && i < c->cx && j < c->cy;
}

/* Where the ray leaves a rectangle of cells whose far faces (those it
 * moves towards) are x = xf and y = yf: *face FACE_X, FACE_Y or FACE_XY
 * (through the corner), and the parameter n / d there, d = |dx| or |dy|.
 * Faces and origins lie in the tile, so |face 2^16 - o| < 2^31 and the
 * face test is two 32 x 32-bit products (< 2^57). */
CT_ALWAYS_INLINE static inline void rect_exit(const ctx *c, int32_t xf, int32_t yf, int *face, rt *t)
{
    int64_t nx = 0, ny = 0;
    if (c->sx > 0) {
        nx = (int64_t)xf * ONE16 - c->r->ox;
    } else if (c->sx < 0) {
        nx = c->r->ox - (int64_t)xf * ONE16;
    }
    if (c->sy > 0) {
        ny = (int64_t)yf * ONE16 - c->r->oy;
    } else if (c->sy < 0) {
        ny = c->r->oy - (int64_t)yf * ONE16;
    }
    if (c->sy == 0) {
        *face = FACE_X;
    } else if (c->sx == 0) {
        *face = FACE_Y;
    } else {
        int64_t lx = ct_smul32(nx, c->ady), ly = ct_smul32(ny, c->adx);
        *face = lx < ly ? FACE_X : (ly < lx ? FACE_Y : FACE_XY);
    }
    if (*face == FACE_Y) {
        t->n = ny;
        t->d = c->ady;
    } else {
        t->n = nx;
        t->d = c->adx;
    }
}

/* Exit of fine cell (i, j). */
static void cell_exit(const ctx *c, int32_t i, int32_t j, cexit *e)
{
    e->xf = i + (c->sx > 0 ? 1 : 0);
    e->yf = j + (c->sy > 0 ? 1 : 0);
    rect_exit(c, e->xf, e->yf, &e->face, &e->t);
}

/* Canonical entry parameter of cell (i, j): the later of its entry faces,
 * or 0 when the origin lies in it. */
static rt cell_entry(const ctx *c, int32_t i, int32_t j)
{
    rt t = {0, 1};
    if (c->sx != 0) {
        int64_t xe = (int64_t)i + (c->sx < 0 ? 1 : 0);
        rt tx;
        tx.n = (xe * ONE16 - c->r->ox) * c->sx;
        tx.d = c->adx;
        if (rt_lt(t, tx)) {
            t = tx;
        }
    }
    if (c->sy != 0) {
        int64_t ye = (int64_t)j + (c->sy < 0 ? 1 : 0);
        rt ty;
        ty.n = (ye * ONE16 - c->r->oy) * c->sy;
        ty.d = c->ady;
        if (rt_lt(t, ty)) {
            t = ty;
        }
    }
    return t;
}

/* ------------------------------------------------------------------------ */
/* Walkers.                                                                  */

static void next_cell(const ctx *c, const cexit *e, int32_t *i, int32_t *j)
{
    if (e->face & FACE_X) {
        *i += c->sx;
    }
    if (e->face & FACE_Y) {
        *j += c->sy;
    }
}

static ct_status walk_incremental(const ctx *c, ct_hit *h)
{
    int32_t i, j;
    uint32_t it, steps = h->steps, bound = CT_WCET_CELL_ITERS(c->cx, c->cy);
    ct_status st = CT_ERR_INTERNAL;
    rt tin = c->t0;
    cexit e;
    i = c->i0;
    j = c->j0;
    /* bound: each iteration leaves one fine cell */
    for (it = 0u; it < bound; ++it) {
        if (!inside(c, i, j)) {
            st = CT_MISS;
            break;
        }
        cell_exit(c, i, j, &e);
        steps++;
        if (ct_cell_test(c, i, j, tin, &e, -1, h)) {
            st = ct_hit_status(c->p, i, j);
            it++;
            break;
        }
        if (!rt_lt(e.t, c->tend)) {
            st = CT_MISS;
            it++;
            break;
        }
        next_cell(c, &e, &i, &j);
        tin = e.t;
    }
    h->steps = steps;
    h->iters = it; /* == bound with CT_ERR_INTERNAL */
    return st;
}

static ct_status walk_hierarchical(const ctx *c, ct_hit *h)
{
    const ct_package *p = c->p;
    int32_t i, j;
    uint32_t lvl = p->levels, it, bound = CT_WCET_HIER_ITERS(c->cx, c->cy, p->levels);
    int32_t lbi = -2, lbj = -2; /* the cell lb was formed for */
    int64_t lb = 0;
    rt t = c->t0;
    cexit e;
    i = c->i0;
    j = c->j0;
    /* bound: per fine cell left, at most levels descents + one advance */
    for (it = 0u; it < bound; ++it) {
        if (!inside(c, i, j)) {
            h->iters = it;
            return CT_MISS;
        }
        if (lvl == 0u) {
            cell_exit(c, i, j, &e);
            h->steps++;
            if (ct_cell_test(c, i, j, t, &e, -1, h)) {
                h->iters = it + 1u;
                return ct_hit_status(p, i, j);
            }
            if (!rt_lt(e.t, c->tend)) {
                h->iters = it + 1u;
                return CT_MISS;
            }
            next_cell(c, &e, &i, &j);
            t = e.t;
            lvl = p->levels > 0u ? 1u : 0u;
        } else {
            int32_t bi = i >> lvl, bj = j >> lvl, xf, yf;
            int64_t bmax = (int64_t)ct_mip_at(p, lvl, (uint32_t)bi, (uint32_t)bj);
            rt tx;
            int face;
            /* the block's exit faces (cells), clamped to the tile */
            xf = c->sx > 0 ? ((bi + 1) << lvl) : (bi << lvl);
            yf = c->sy > 0 ? ((bj + 1) << lvl) : (bj << lvl);
            if (xf > c->cx) {
                xf = c->cx;
            }
            if (yf > c->cy) {
                yf = c->cy;
            }
            rect_exit(c, xf, yf, &face, &tx);
            {
                rt tl = c->r->dz <= 0 ? tx : t;
                int64_t zlo = c->r->oz * tl.d + tl.n * (int64_t)c->r->dz, zb = zh(c, (uint32_t)bmax);
                if (c->lw != NULL && zlo <= zb * tl.d) {
                    /* a bent ray: the block's max less the lowering's
                     * bound ahead (the same range as zh, see cell_test) */
                    if (lbi != i || lbj != j) {
                        lb = lower_ahead(c, i, j);
                        lbi = i;
                        lbj = j;
                    }
                    zb -= lb;
                }
                if (zlo > zb * tl.d) {
                    /* skip the block: the ray is above its max all along */
                    h->steps++;
                    if (!rt_lt(tx, c->tend)) {
                        h->iters = it + 1u;
                        return CT_MISS;
                    }
                    if (face & FACE_X) {
                        i = c->sx > 0 ? xf : xf - 1;
                    } else {
                        i = axis_cell(c->r->ox * tx.d + tx.n * (int64_t)c->r->dx, tx.d * ONE16, c->sx, c->cx);
                    }
                    if (face & FACE_Y) {
                        j = c->sy > 0 ? yf : yf - 1;
                    } else {
                        j = axis_cell(c->r->oy * tx.d + tx.n * (int64_t)c->r->dy, tx.d * ONE16, c->sy, c->cy);
                    }
                    t = tx;
                    if (lvl < p->levels) {
                        lvl++;
                    }
                } else {
                    lvl--;
                }
            }
        }
    }
    return CT_ERR_INTERNAL;
}

/* floor(t 2^26) for the walk's t >= 0 (t.n 2^26 < 2^60): unsigned, a
 * cheaper division on the MCUs. */
static inline int64_t floor_q26(rt t)
{
    return t.d == T_ONE ? t.n : (int64_t)((uint64_t)(t.n * T_ONE) / (uint64_t)t.d);
}

/* Where the ray leaves the footprint of coarse cell (ci, cj) (the ray in
 * it; r x r fine cells, clamped to the tile), as rect_exit: t_X = n / d
 * with 0 <= n < 2^31 and d <= 2^26; for a rising
 * ray tend when that comes first (n < 2^34).  (A level or descending ray
 * is stepped from t_X only when above the apex there, which is above the
 * box's floor, and no higher than at t: in the box, so t_X <= tend.) */
static rt footprint_exit(const ctx *c, uint32_t ci, uint32_t cj)
{
    const ct_package *p = c->p;
    int face;
    int32_t xf = (int32_t)(c->sx > 0 ? ct_min64((int64_t)(ci + 1u) * p->reduce, c->cx) : (int64_t)ci * p->reduce);
    int32_t yf = (int32_t)(c->sy > 0 ? ct_min64((int64_t)(cj + 1u) * p->reduce, c->cy) : (int64_t)cj * p->reduce);
    rt tx;
    rect_exit(c, xf, yf, &face, &tx);
    return c->r->dz > 0 && rt_lt(c->tend, tx) ? c->tend : tx;
}

/* The cone walk.  fine, a constant: 1 for a package at r = 1, whose coarse
 * cells are its fine cells (no multiplier for the coarse cell, no step from
 * a footprint's exit) -- an instance of its own on hosts (walk_cones
 * below); the MCUs compile one instance, fine = 0, for code size. */
#if CT_HAVE_PREFETCH
CT_OPT_INLINE static inline ct_status walk_cones_r(const ctx *c, uint32_t plane, ct_hit *h, const int fine)
{
#else
static ct_status walk_cones_r(const ctx *c, uint32_t plane, ct_hit *h)
{
    const int fine = 0;
#endif
    const ct_package *p = c->p;
    const ct_prepared *r = c->r;
    const uint8_t *ang = p->angles + (size_t)plane * p->coarse_x * p->coarse_y;
    /* the ray's constants in locals: h's counters may alias them */
    const int64_t ox = r->ox, oy = r->oy, oz = r->oz;
    const int32_t dx = r->dx, dy = r->dy, dz = r->dz;
    int32_t i, j;
    uint32_t it, steps = h->steps, bound = CT_WCET_CELL_ITERS(c->cx, c->cy);
    /* Cone steps from the coarse footprint's exit (below) at r > 1; at
     * r = 1 the footprint is the fine cell, and the exit's division costs
     * more than the one cell it adds to a step. */
    const int from_exit = fine ? 0 : p->reduce > 1u;
    rt t = c->t0;   /* current point */
    rt tin = c->t0; /* canonical entry of the current cell */
    int tin_ok = 1;
    int64_t lb;      /* lower_ahead at (i, j), -1 when not formed */
    size_t below_k = (size_t)-1; /* the coarse cell whose apex the ray was
                                    found below; none yet: SIZE_MAX, which
                                    no coarse index (< 2^30) equals      */
    ct_status st = CT_ERR_INTERNAL;
    cexit e;
    i = c->i0;
    j = c->j0;
    /* bound: each iteration leaves at least one fine cell */
    for (it = 0u; it < bound; ++it) {
        uint32_t code, ci, cj;
        size_t k;
        if (!inside(c, i, j)) {
            st = CT_MISS;
            break;
        }
        steps++;
        ci = fine ? (uint32_t)i : ct_coarse_of(p, i);
        cj = fine ? (uint32_t)j : ct_coarse_of(p, j);
        k = (size_t)cj * p->coarse_x + ci;
        lb = -1;
        /* Below the apex of coarse cell k at an earlier fine cell of it (the
         * ray leaves a coarse cell once: it is a rectangle): the exact step
         * without consulting the cone again, which seldom jumps there (any
         * step here is exact, so this changes the steps, never the hit).
         * Code 0 (a closed cone) is never stepped with (ct_cot_table). */
        code = k != below_k ? ang[k] : 0u;
        if (p->cot_ok[code]) {
            /* a bent ray: the apex less the lowering's bound ahead (the
             * cone of the lowered terrain; |a16| < 2^33) */
            int64_t a16 = zh(c, ct_ld16(p->apex + 2u * k));
            int64_t T = 0, Tz, num = 0;
            int go = 0;      /* a cone step from T */
            int to_apex = 0; /* ... at most to the apex's height */
            int above_x = 0; /* above the apex at t_X */
            rt tx = T_ZERO;  /* t_X, the footprint's exit (r > 1) */
            if (c->lw != NULL) {
                lb = lower_ahead(c, i, j);
                a16 -= lb;
            }
            if (from_exit) {
                /* The cone holds from every point of the coarse cell's
                 * footprint (the promise): on its way to the footprint's
                 * exit t_X the ray is in the empty region while above the
                 * apex, and the cone's step counts from t_X.  The sign of
                 * z(t_X) - apex, exact: tx.d (z(t_X) - a16) with |oz - a16|
                 * < 2^34, so |(oz - a16) tx.d| < 2^60, |tx.n dz| < 2^60. */
                tx = footprint_exit(c, ci, cj);
                above_x = (oz - a16) * tx.d + tx.n * (int64_t)dz > 0;
            }
            if (above_x) {
                /* above the apex at the exit, and so from t on unless the
                 * ray rises: then z at floor(t 2^26) <= t must be above it
                 * too */
                go = dz <= 0 || oz + floor_shr(floor_q26(t) * (int64_t)dz, CT_T_FRAC_BITS) - a16 > 0;
                /* the step from t_X: T = floor(t_X 2^26) (t_X.n 2^26 <
                 * 2^60; t_X <= tend, see footprint_exit), and a lower bound
                 * of z(t_X) - apex from a Q26 point (z at T for a rising
                 * ray, at T + 1 for a descending one unless t_X is exactly
                 * T / 2^26), at least 0 (< 2^34) */
                {
                    /* one division: quotient and remainder */
                    uint64_t N = (uint64_t)tx.n << CT_T_FRAC_BITS;
                    T = (int64_t)(N / (uint64_t)tx.d);
                    Tz = (dz < 0 && N % (uint64_t)tx.d != 0u) ? T + 1 : T;
                }
                num = ct_max64(oz + floor_shr(Tz * (int64_t)dz, CT_T_FRAC_BITS) - a16, 0);
            } else if (!from_exit || dz < 0) {
                /* From t, with T = floor(t 2^26) and a lower bound of z(t)
                 * from a Q26 point as above: at r = 1, or descending to
                 * the apex inside the footprint, then up to the apex's
                 * height (at or before t_X) unless the cone reaches
                 * farther (cot < 0).  (A ray not descending is at or
                 * below the apex at t as at t_X.) */
                T = floor_q26(t);
                Tz = (t.d != T_ONE && dz < 0) ? T + 1 : T;
                num = oz + floor_shr(Tz * (int64_t)dz, CT_T_FRAC_BITS) - a16; /* < 2^34 */
                go = num > 0;
                to_apex = from_exit;
            }
            if (!go) {
                /* at or below the apex: exact steps in this coarse cell */
                below_k = k;
            } else {
                int64_t cot = p->cot_q16[code];
                int64_t len = cot >= 0 ? r->len_hi : r->len_lo;
                /* in Q16 z units: len <= 2^26.5, |cot| <= 2^35: < 2^61.5,
                 * ceil by 2^16 (cot is Q16 LSB per cell), minus dz 2^k (<=
                 * 2^42).  den <= 0 iff the ray's rise per unit t reaches
                 * the cone's, as in prepared z units; to the apex's height
                 * (cot 0): -dz 2^k. */
                int64_t den = -floor_shr(-(len * cot), 16u) - c->dzf;
                int64_t dt, tn;
                if (to_apex && den > -c->dzf) {
                    den = -c->dzf;
                }
                if (den <= 0) {
                    /* the ray never leaves the empty region: no hit ahead */
                    st = CT_MISS;
                    it++;
                    break;
                }
                num = (int64_t)((uint64_t)num * c->zmul);
                /* num*2^26 < 2^60 and den > 0: unsigned (a cheaper division
                 * on the MCUs, whose 64-bit division is a library call) */
                dt = (int64_t)((uint64_t)(num * T_ONE) / (uint64_t)den);
                if (dt > (INT64_C(1) << 35)) {
                    dt = INT64_C(1) << 35;
                }
                /* T + dt - 1 < 2^26 times where the ray leaves the empty
                 * region (the cone from T's point, t or t_X, or the apex's
                 * height), so the ray on [t, tn] lies in it.  The jump is taken
                 * when it leaves the fine cell (the point at tn lies in
                 * another cell, or on the exit face, which belongs to the
                 * next cell); otherwise the exact cell step below.  The cell
                 * at tn as locate's for a Q26 t: o 2^26 < 2^57 and tn |d| <
                 * (2^34 + 2^35) 2^26 < 2^61.6 (T < 2^34, dt <= 2^35). */
                tn = T + dt - 1;
                if (tn > T) {
                    int32_t ni = axis_cell_q26(ox * T_ONE + tn * (int64_t)dx, c->sx, c->cx);
                    int32_t nj = axis_cell_q26(oy * T_ONE + tn * (int64_t)dy, c->sy, c->cy);
                    if (ni != i || nj != j) {
                        rt tj;
#if CT_HAVE_PREFETCH
                        if (c->prefetch) {
                            /* a hint only: T2 = tn + dt < 2^36, times |d| <=
                             * 2^26; a cell off the tile is not asked for */
                            int64_t T2 = tn + dt;
                            int64_t px = floor_shr(ox + floor_shr(T2 * (int64_t)dx, CT_T_FRAC_BITS), 16u);
                            int64_t py = floor_shr(oy + floor_shr(T2 * (int64_t)dy, CT_T_FRAC_BITS), 16u);
                            if (px >= 0 && py >= 0 && px < c->cx && py < c->cy) {
                                size_t k2 = fine ? (size_t)py * p->coarse_x + (size_t)px
                                                 : ct_coarse_index(p, (int32_t)px, (int32_t)py);
                                CT_PREFETCH(ang + k2);
                                CT_PREFETCH(p->apex + 2u * k2);
                            }
                        }
#endif
                        tj.n = tn;
                        tj.d = T_ONE;
                        if (!rt_lt(tj, c->tend)) {
                            st = CT_MISS;
                            it++;
                            break;
                        }
                        t = tj;
                        i = ni;
                        j = nj;
                        tin_ok = 0;
                        continue;
                    }
                }
            }
        }
        /* exact cell step */
        cell_exit(c, i, j, &e);
        if (!tin_ok) {
            tin = cell_entry(c, i, j);
        }
        if (ct_cell_test(c, i, j, tin, &e, lb, h)) {
            st = ct_hit_status(p, i, j);
            it++;
            break;
        }
        if (!rt_lt(e.t, c->tend)) {
            st = CT_MISS;
            it++;
            break;
        }
        next_cell(c, &e, &i, &j);
        t = e.t;
        tin = e.t;
        tin_ok = 1;
    }
    h->steps = steps;
    h->iters = it; /* == bound with CT_ERR_INTERNAL */
    return st;
}

#if CT_HAVE_PREFETCH
/* hosts: the two instances, each a function of its own (one function
 * holding both cost the r > 1 walk 2-3 %) */
CT_NOINLINE static ct_status walk_cones_fine(const ctx *c, uint32_t plane, ct_hit *h)
{
    return walk_cones_r(c, plane, h, 1);
}

CT_NOINLINE static ct_status walk_cones_coarse(const ctx *c, uint32_t plane, ct_hit *h)
{
    return walk_cones_r(c, plane, h, 0);
}
#endif

static ct_status walk_cones(const ctx *c, uint32_t plane, ct_hit *h)
{
#if CT_HAVE_PREFETCH
    /* hosts: packages at r = 1 take their own instance (their planes are
     * large, and a step's chain from one angle code's load to the next is
     * what limits it); the MCUs keep one instance (code size) */
    return c->p->reduce == 1u ? walk_cones_fine(c, plane, h) : walk_cones_coarse(c, plane, h);
#else
    return walk_cones_r(c, plane, h);
#endif
}

/* A seam start's cheap proof of f(t0) > 0, as the cone walk's first test
 * (the apex as walk_cones' takes it, kept out of that loop: one shared
 * helper cost the walk 11 % more instructions per horizontal ray):
 * the ray at t0 above the apex of its cell's cone in plane (exactly), the
 * apex being at or above every post under it (for a bent ray, less the
 * lowering's bound ahead).  0: not shown (test the sign). */
static int above_apex(const ctx *c, uint32_t plane, int32_t i, int32_t j)
{
    const ct_package *p = c->p;
    const ct_prepared *r = c->r;
    size_t k = ct_coarse_index(p, i, j);
    uint32_t code = p->angles[(size_t)plane * p->coarse_x * p->coarse_y + k];
    int64_t a16;
    if (!p->cot_ok[code]) {
        return 0;
    }
    a16 = zh(c, ct_ld16(p->apex + 2u * k));
    if (c->lw != NULL) {
        a16 -= lower_ahead(c, i, j);
    }
    /* the sign of z(t0) - apex, exact: t0.d (z(t0) - a16) with |oz - a16|
     * < 2^34, t0.d <= 2^26 and t0.n < 2^34: products < 2^60 */
    return (r->oz - a16) * c->t0.d + c->t0.n * (int64_t)r->dz > 0;
}

/* ------------------------------------------------------------------------ */
/* ------------------------------------------------------------------------ */

static ct_status check_prepared(const ct_package *p, const ct_prepared *r)
{
    int64_t m = ct_max64(ct_abs64(r->dx), ct_max64(ct_abs64(r->dy), ct_abs64(r->dz)));
    int64_t l2 = (int64_t)r->dx * r->dx + (int64_t)r->dy * r->dy;
    if (m > (INT64_C(1) << CT_DIR_BITS) || m < (INT64_C(1) << (CT_DIR_BITS - 1))) {
        return CT_ERR_RAY;
    }
    if (r->zshift < 0 || r->zshift > CT_ZSHIFT_MAX || (r->zshift != 0 && r->dx == 0 && r->dy == 0)) {
        return CT_ERR_RAY;
    }
    if (r->ox < 0 || r->oy < 0 || r->ox > (int64_t)p->cells_x * ONE16 ||
        r->oy > (int64_t)p->cells_y * ONE16 || r->oz > ((int64_t)p->hmax + 1) * (ONE16 >> r->zshift) ||
        r->oz < -(INT64_C(1) << (46 - r->zshift))) {
        return CT_ERR_RAY;
    }
    if (r->len_lo < 0 || r->len_hi - r->len_lo < 0 || r->len_hi - r->len_lo > 1 ||
        r->len_lo * r->len_lo > l2 || r->len_hi * r->len_hi < l2) {
        return CT_ERR_RAY;
    }
    if (r->tend_d <= 0 || r->tend_d > (INT64_C(1) << CT_DIR_BITS) || r->tend_n < 0 ||
        r->tend_n > (INT64_C(1) << 34)) {
        return CT_ERR_RAY;
    }
    {
        /* the walk's bounds assume the ray is in the box up to tend, and a
         * traceable ray (start CT_OK) starts above the terrain's floor */
        const int64_t O[3] = {r->ox, r->oy, r->oz};
        const int32_t D[3] = {r->dx, r->dy, r->dz};
        int64_t zone = ONE16 >> r->zshift;
        rt te = box_exit(p, O, D, zone, 0), tr;
        tr.n = r->tend_n;
        tr.d = r->tend_d;
        if (rt_lt(te, tr) || (r->start == CT_OK && r->oz <= ((int64_t)p->hmin - 1) * zone)) {
            return CT_ERR_RAY;
        }
    }
    if (r->dx == 0 && r->dy == 0) {
        if (r->sector != -1) {
            return CT_ERR_RAY;
        }
    } else {
        uint32_t in = 0u;
        if (r->sector < 0 || (uint32_t)r->sector >= p->sectors ||
            ct_in_wedge(p->bound_x, p->bound_y, p->sectors, (uint32_t)r->sector, r->dx, r->dy, &in) != CT_OK ||
            !in) {
            return CT_ERR_RAY;
        }
    }
    return CT_OK;
}

void ct_hit_clear(ct_hit *h)
{
    h->steps = 0u;
    h->iters = 0u;
    h->x_q16 = h->y_q16 = h->z_q16 = 0;
    h->e_nm = h->n_nm = h->h_nm = 0;
    h->t_q26 = 0;
    h->cell_x = h->cell_y = -1;
}

/* Where a tile's walk starts (ct_trace_tile): at t0 = 0 in cell (i, j),
 * or at t0 > 0 on the tile's entry face(s) (face bit 1: x, i given; bit
 * 2: y, j given; the other axis located). */
typedef struct {
    rt t0;
    int face;
    int32_t i, j;
} wstart;

/* The walk's context for prepared ray r on p (lw: a bent ray's lowered
 * terrain, or NULL; ws: a tile set's start, or NULL). */
static void set_ctx(ctx *c, const ct_package *p, const ct_prepared *r, const ct_lower *lw, const wstart *ws)
{
    c->p = p;
    c->r = r;
    c->sx = sgn64(r->dx);
    c->sy = sgn64(r->dy);
    c->adx = ct_abs64(r->dx);
    c->ady = ct_abs64(r->dy);
    c->cx = (int32_t)p->cells_x;
    c->cy = (int32_t)p->cells_y;
    c->zs = (unsigned)r->zshift;
    c->zone = (uint32_t)1 << (16u - c->zs);
    c->zmul = (uint32_t)1 << c->zs;
    c->dzf = (int64_t)r->dz * (int64_t)c->zmul;
    c->tend.n = r->tend_n;
    c->tend.d = r->tend_d;
    c->lw = lw;
    c->ratio_q30 = 0;
    c->t0 = ws != NULL ? ws->t0 : T_ZERO;
    /* angle planes far beyond a host's L2 cache (over 1 MB), or a tile of a
     * set (its tiles' planes together): a cone step's code is a miss, so
     * walk_cones asks for the next one early (hosts only) */
    c->prefetch = CT_HAVE_PREFETCH &&
                 (ws != NULL || (uint64_t)p->coarse_x * p->coarse_y * p->sectors > (UINT64_C(1) << 20));
    if (lw != NULL && lw->cull && (r->dx != 0 || r->dy != 0)) {
        /* len_lo 2^30 < 2^56.5; the quotient in [2^30, 2^30.5] */
        c->ratio_q30 = (r->len_lo << 30) / (c->adx >= c->ady ? c->adx : c->ady);
    }
}

/* A walk that starts at t0 > 0 on a tile's entry face (ws).  Returns 1
 * with the trace's result in *st when the seam point decides it, else 0
 * with the walk's first cell in c->i0, c->j0. */
static int seam_start(ctx *c, ct_method m, const wstart *ws, ct_hit *h, ct_status *st)
{
    /* a tile set's later tile: the walk starts on the seam, where the
     * previous tile's walk left the ray above its surface (a cell test
     * found f > 0 there, or a cone promised no point strictly below the
     * surface).  f = 0 -- the ray touching the surface on the seam
     * after a cone jump -- is a hit there.  The cone walks see f > 0
     * from the cone above the seam point where there is one; the sign
     * is tested from the posts otherwise. */
    int32_t i, j;
    const ct_package *p = c->p;
    const ct_prepared *r = c->r;
    if (r->start != CT_OK || (r->dx == 0 && r->dy == 0)) {
        *st = CT_ERR_RAY;
        return 1;
    }
    /* on the entry face the cell is known; the other axis located */
    i = (ws->face & 1) ? ws->i : locate_axis(r->ox, r->dx, c->sx, c->cx, c->t0);
    j = (ws->face & 2) ? ws->j : locate_axis(r->oy, r->dy, c->sy, c->cy, c->t0);
    if (!inside(c, i, j)) {
        *st = CT_MISS;
        return 1;
    }
    if (m == CT_METHOD_INCREMENTAL || m == CT_METHOD_HIERARCHICAL ||
        !above_apex(c, m == CT_METHOD_CONE ? (p->sectors == 1u ? 0u : p->sectors) : (uint32_t)r->sector, i,
                    j)) {
        if (ct_entry_sign(c, i, j, c->t0) <= 0) {
            ct_fill_hit(c, floor_q26(c->t0), i, j, h);
            h->steps = 1u;
            h->iters = 1u;
            *st = ct_hit_status(p, i, j);
            return 1;
        }
    }
    c->i0 = i;
    c->j0 = j;
    return 0;
}

/* A vertical ray (f(0) > 0 was established at preparation): its hit
 * below the first point, or a miss when it rises. */
static ct_status vertical_trace(const ctx *c, ct_hit *h)
{
    const ct_package *p = c->p;
    const ct_prepared *r = c->r;
    const ct_lower *lw = c->lw;
    int32_t i, j;
    int64_t s, tq;
    h->steps = 1u;
    h->iters = 1u;
    if (r->dz > 0) {
        return CT_MISS;
    }
    locate(c, T_ZERO, &i, &j);
    if (lw != NULL) {
        /* the lowered surface rounded up to Q16 2^16 (a hit at or
         * above it); |s| < 2^50 as below */
        ct_i128 sl = ct_surface_low_q48(p, lw, i, j, r->ox, r->oy);
        s = -ct_i128_floor_div(ct_i128_neg(sl), ONE16);
    } else {
        s = surface_q32(p, i, j, r->ox, r->oy);
    }
    /* t = (oz*2^16 - s) / (2^16 * |dz|) ; in Q26, floored:
     * (oz*2^16 - s) < 2^50, * 2^26 / 2^16 = * 2^10: < 2^60 */
    tq = ct_floor_div((r->oz * ONE16 - s) * 1024, -(int64_t)r->dz);
    ct_fill_hit(c, tq, i, j, h);
    /* report the exact surface height at a vertical hit (for a bent
     * ray: the lowered surface's, plus the rise there) */
    h->z_q16 = -ct_floor_div(-s, ONE16) + (lw != NULL ? ct_lower_at(lw, h->x_q16, h->y_q16) : 0);
    (void)ct_grid_to_map(p, h->x_q16, h->y_q16, h->z_q16, &h->e_nm, &h->n_nm, &h->h_nm);
    return ct_hit_status(p, i, j);
}

/* ws: where the walk starts (a tile set's tile); NULL: t = 0, located. */
static ct_status trace_impl(const ct_package *p, const ct_prepared *r, ct_method m, int checked,
                            const ct_lower *lw, const wstart *ws, ct_hit *h)
{
    ctx c;
    ct_status st;
    CT_ASSERT(p != NULL && r != NULL && h != NULL);
    if (p == NULL || r == NULL || h == NULL || p->base == NULL) {
        return CT_ERR_ARG; /* base NULL: a frame, which has no sections */
    }
    if ((unsigned)m >= (unsigned)CT_METHOD_COUNT) {
        return CT_ERR_METHOD;
    }
    ct_hit_clear(h);
    if (r->start == CT_MISS || r->start == CT_BELOW) {
        return r->start;
    }
    /* a ray prepared by this library needs no re-check (ct_trace, the bent
     * walk); one handed in by a caller does */
    st = checked ? CT_OK : check_prepared(p, r);
    if (st != CT_OK) {
        return st;
    }
    set_ctx(&c, p, r, lw, ws);
    if (c.t0.n > 0) {
        if (seam_start(&c, m, ws, h, &st)) {
            return st;
        }
    } else if (r->start == CT_HIT) {
        int32_t i, j;
        locate(&c, T_ZERO, &i, &j);
        i = i < 0 ? 0 : (i >= c.cx ? c.cx - 1 : i);
        j = j < 0 ? 0 : (j >= c.cy ? c.cy - 1 : j);
        ct_fill_hit(&c, 0, i, j, h);
        h->steps = 1u;
        h->iters = 1u;
        return ct_hit_status(p, i, j);
    } else if (r->start != CT_OK) {
        return CT_ERR_RAY;
    } else if (r->dx == 0 && r->dy == 0) {
        return vertical_trace(&c, h);
    }
    if (ws != NULL && ws->face == 0) {
        c.i0 = ws->i; /* the first point's cell, from the set */
        c.j0 = ws->j;
    } else if (c.t0.n == 0) {
        locate(&c, T_ZERO, &c.i0, &c.j0);
    }
    switch (m) {
    case CT_METHOD_INCREMENTAL:
        return walk_incremental(&c, h);
    case CT_METHOD_HIERARCHICAL:
        return walk_hierarchical(&c, h);
    case CT_METHOD_CONE:
        return walk_cones(&c, p->sectors == 1u ? 0u : p->sectors, h);
    case CT_METHOD_DIRECTIONAL:
    default:
        return walk_cones(&c, (uint32_t)r->sector, h);
    }
}

ct_status ct_trace(const ct_package *p, const ct_ray *ray, ct_method m, ct_hit *h)
{
    ct_prepared r;
    ct_status st;
    CT_ASSERT(p != NULL && ray != NULL && h != NULL);
    if (p == NULL || ray == NULL || h == NULL) {
        return CT_ERR_ARG;
    }
    st = ct_ray_prepare(p, ray, &r);
    if (st < 0) {
        return st;
    }
    return trace_impl(p, &r, m, 1, NULL, NULL, h);
}

ct_status ct_trace_tile(const ct_package *tile, const ct_prepared *r, int64_t t0_n, int64_t t0_d, int face,
                        int32_t i0, int32_t j0, const ct_lower *lw, ct_method m, ct_hit *h)
{
    wstart ws;
    ws.t0.n = t0_n;
    ws.t0.d = t0_d;
    ws.face = face;
    ws.i = i0;
    ws.j = j0;
    return trace_impl(tile, r, m, 1, lw, &ws, h);
}

void ct_fill_point(const ct_package *p, const ct_prepared *r, const ct_lower *lw, int64_t t_q26, ct_hit *h)
{
    ctx c;
    c.p = p;
    c.r = r;
    c.zs = (unsigned)r->zshift;
    c.zmul = (uint32_t)1 << c.zs;
    c.lw = lw;
    ct_fill_hit(&c, t_q26, h->cell_x, h->cell_y, h);
}

ct_status ct_trace_prepared(const ct_package *p, const ct_prepared *r, ct_method m, ct_hit *h)
{
    return trace_impl(p, r, m, 0, NULL, NULL, h);
}

ct_status ct_trace_prepared_own(const ct_package *p, const ct_prepared *r, ct_method m, ct_hit *h)
{
    return trace_impl(p, r, m, 1, NULL, NULL, h);
}

ct_status ct_trace_prepared_lowered(const ct_package *p, const ct_prepared *r, const ct_lower *lw, ct_method m,
                                    ct_hit *h)
{
    return trace_impl(p, r, m, 1, lw, NULL, h);
}

ct_status ct_trace_lowered(const ct_package *p, const ct_ray *ray, const ct_lower *lw, ct_method m, ct_hit *h)
{
    ct_prepared r;
    ct_status st = ct_prepare_lowered(p, ray, 0, lw, &r);
    if (st < 0) {
        return st;
    }
    return trace_impl(p, &r, m, 1, lw, NULL, h);
}

/* ---- runs: rays from one observer traced together --------------------- */
/* A run's common bounds (ct_trace_run).  The rays' primary axis a (0: x,
 * 1: y) has sign s for every ray, |d_a| >= |d_other| and |d_a| >= 2^19.
 * u = s * (the a coordinate), Q16; u-cell cu holds u in [cu, cu + 1)
 * 2^16, i.e. the a-axis cell i = cu (s > 0) or -1 - cu (s < 0).  On u-face
 * fa + m (m in [0, w]) every ray's other coordinate lies in [QL(m), QH(m)]
 * and its height (Q16 LSB) at or above ZL(m):
 *     QL(m) = ql + floor(m sql / 2^16),  QH(m) = qh + ceil(m sqh / 2^16),
 *     ZL(m) = zl + floor(m szl / 2^16)
 * (below run_bounds).  Ranges: |u| < 2^31 on the tile, |q| < 2^33 on the
 * faces (a ray's line runs on past the tile's sides), |ZL| < 2^57. */
#ifndef RUN_MIN_CELLS
#define RUN_MIN_CELLS 16
#endif
#ifndef RUN_SPREAD
#define RUN_SPREAD 8
#endif
#ifndef RUN_SPAN
#define RUN_SPAN 512
#endif
#ifndef RUN_WIDTH
#define RUN_WIDTH 4
#endif
typedef struct {
    int a;
    int32_t s;
    int64_t fa, w;        /* first u-face, faces fa .. fa + w (the tile's end) */
    int64_t ql, qh, zl;   /* at fa */
    int64_t sql, sqh, szl; /* per u-cell, Q16 */
} runb;

/* Ray r's direction on axis a (0: x, 1: y), and its origin's u there. */
static int32_t run_d(const ct_prepared *r, int a)
{
    return a == 0 ? r->dx : r->dy;
}

static int64_t run_u(const ct_prepared *r, int a, int32_t s)
{
    int64_t o = a == 0 ? r->ox : r->oy;
    return s > 0 ? o : -o;
}

/* The other coordinate and the height of prepared ray r on u-face U
 * (Q16): *qlo, *qhi its floor and ceiling, *zlo a lower bound (Q16 LSB).
 * e = U - u_origin, |e| < 2^32: e dq < 2^58, e dz < 2^58, quotients by
 * du >= 2^19 below 2^39, times 2^zshift <= 2^16: < 2^55; |oz 2^zs| <=
 * 2^46 (ct_prepared). */
static void run_at(const ct_prepared *r, int a, int32_t s, int64_t U, int64_t *qlo, int64_t *qhi, int64_t *zlo)
{
    int64_t du = ct_abs64(run_d(r, a)), dq = run_d(r, 1 - a);
    int64_t oq = a == 0 ? r->oy : r->ox, e = U - run_u(r, a, s);
    *qlo = oq + ct_floor_div(e * dq, du);
    *qhi = oq - ct_floor_div(-(e * dq), du);
    *zlo = r->oz * (INT64_C(1) << r->zshift) + ct_floor_div(e * (int64_t)r->dz, du) * (INT64_C(1) << r->zshift);
}

/* The run's bounds over rays use[] of r (1: in the run).  Returns 1, or 0
 * when they cannot be formed (fewer than two rays, primary axes differ, a
 * ray too steep), or 2 when the rays part too fast for a shared walk to
 * pay.
 * Each ray's coordinates are linear in u, so on every face between fa and
 * fa + w they are at or above (below) the chord through the smallest
 * (largest) values at the two ends; the slopes are rounded down (up) and
 * m >= 0, so the bounds hold.  Ranges: |QL_end - QL_start| < 2^34 (q on
 * the faces within 2^31 + 2^32), times 2^16 < 2^50, and m sql <= (2^50 +
 * w) m / w < 2^51 for m <= w.  Heights: each ray changes by at most
 * (hmax - hmin) 2^16 / 16 Q16 LSB per u-cell (the relief test below), so
 * over w < 2^15 cells by < 2^43 (and its floor by 2^16 more), and the
 * lowest at either end differ by less than that: m szl < 2^59 + 2^15. */
static int run_bounds(const ct_package *p, const ct_prepared *const *r, const uint8_t *use, uint32_t n, runb *b)
{
    uint32_t k, cnt = 0u;
    int64_t cu0 = 0, lo, hi, ql1 = 0, qh1 = 0, zl1 = 0, gq = 0, gu = 1, gc = 0, gw = 0, ncell = 0;
    int a = -1;
    int32_t s = 0;
    b->a = 0;
    b->s = 1;
    b->fa = b->w = b->ql = b->qh = b->zl = b->sql = b->sqh = b->szl = 0;
    /* bound: n <= CT_RUN_MAX rays */
    for (k = 0u; k < n; ++k) {
        int64_t du, cu;
        int ka;
        if (!use[k]) {
            continue;
        }
        ka = ct_abs64(r[k]->dx) >= ct_abs64(r[k]->dy) ? 0 : 1;
        du = ct_abs64(run_d(r[k], ka));
        if (a < 0) {
            a = ka;
            s = run_d(r[k], ka) > 0 ? 1 : -1;
            ncell = (int64_t)(a == 0 ? p->cells_x : p->cells_y);
        }
        if (ka != a || (run_d(r[k], a) > 0 ? 1 : -1) != s || du < (INT64_C(1) << 19)) {
            return 0;
        }
        /* a steep ray crosses the tile's relief within RUN_MIN_CELLS
         * cells: its own walk is short, a run would not pay.  Across the
         * relief it moves (hmax - hmin) du / (|dz| 2^zshift) cells:
         * (hmax - hmin) du < 2^42, RUN_MIN_CELLS |dz| 2^zshift < 2^46 */
        if ((int64_t)(p->hmax - p->hmin) * du < RUN_MIN_CELLS * ct_abs64(r[k]->dz) * (INT64_C(1) << r[k]->zshift)) {
            return 0;
        }
        /* Pixels far apart would stop the shared walk at once: 2, before
         * any division, for rays that part from the first one by more than
         * RUN_SPREAD cells over RUN_SPAN cells (or the tile's width if
         * less), or lie more than RUN_WIDTH cells from it across the first
         * one's origin cell (the walk starts with single cells, at most four
         * across).  Slopes dq / du to 8 bits less and positions in whole
         * cells (a choice, not a bound): |q du0 - q0 du| < 2^37, times
         * <= 2^9 cells; the other coordinates' difference (< 2^16 cells)
         * times us gu < 2^36, and the u distance (< 2^16) times qs gu <
         * 2^36: < 2^53; RUN_SPREAD (RUN_WIDTH) us gu < 2^40. */
        cu = floor_shr(run_u(r[k], a, s), 16u);
        {
            int64_t qs = run_d(r[k], 1 - a) / 256, us = du / 256;
            int64_t oq = floor_shr(a == 0 ? r[k]->oy : r[k]->ox, 16u);
            if (cnt == 0u) {
                gq = qs;
                gu = us;
                gc = cu;
                gw = oq;
            } else if (ct_abs64(qs * gu - gq * us) * ct_min64(ncell, RUN_SPAN) > RUN_SPREAD * us * gu ||
                       ct_abs64((oq - gw) * us * gu + (gc - cu) * qs * gu) > RUN_WIDTH * us * gu) {
                return 2;
            }
        }
        cu0 = cnt == 0u ? cu : ct_min64(cu0, cu);
        cnt++;
    }
    if (cnt < 2u) {
        return 0;
    }
    /* u-cells on the tile: [0, N) (s > 0) or [-N, 0) */
    lo = s > 0 ? 0 : -ncell;
    hi = lo + ncell;
    b->a = a;
    b->s = s;
    b->fa = ct_min64(cu0, hi - 1); /* cu0 >= lo: every origin is in the box */
    b->w = hi - b->fa;
    cnt = 0u;
    /* bound: n <= CT_RUN_MAX rays */
    for (k = 0u; k < n; ++k) {
        int64_t q0, q1, z0, qa, qb, za;
        if (!use[k]) {
            continue;
        }
        run_at(r[k], a, s, b->fa * ONE16, &q0, &q1, &z0);
        run_at(r[k], a, s, hi * ONE16, &qa, &qb, &za);
        if (cnt == 0u) {
            b->ql = q0;
            b->qh = q1;
            b->zl = z0;
            ql1 = qa;
            qh1 = qb;
            zl1 = za;
        } else {
            b->ql = ct_min64(b->ql, q0);
            b->qh = ct_max64(b->qh, q1);
            b->zl = ct_min64(b->zl, z0);
            ql1 = ct_min64(ql1, qa);
            qh1 = ct_max64(qh1, qb);
            zl1 = ct_min64(zl1, za);
        }
        cnt++;
    }
    b->sql = ct_floor_div((ql1 - b->ql) * ONE16, b->w);
    b->sqh = -ct_floor_div(-((qh1 - b->qh) * ONE16), b->w);
    b->szl = ct_floor_div((zl1 - b->zl) * ONE16, b->w);
    return 1;
}

/* 1 when no ray of the run can meet the surface in u-cells [cu, cu + 2^l)
 * (clamped to the tile's end), the level-l block of the max-mipmap (l = 0:
 * the fine cells), between the run's bounds there: their lowest height is
 * above the tallest post of every cell their other coordinate's range
 * touches (a point on a cell's edge is bounded by that edge's posts, which
 * the cell on either side holds), less (lw) the lowering at the nearest
 * of those cells' posts to the observer: on the block's near face (the
 * observer is behind it), across the axis at the observer's coordinate
 * clamped to the posts' range -- every post of those cells is at least as
 * far from the observer, and D grows with the range (a bilinear cell of
 * lowered posts is no higher than its tallest lowered post).  At most
 * four blocks across; otherwise 0.  Outside the tile there is no surface. */
static int run_clear(const ct_package *p, const ct_lower *lw, const runb *b, int64_t cu, uint32_t l)
{
    int64_t m0 = cu - b->fa, m1 = ct_min64(cu + ((int64_t)1 << l), b->fa + b->w) - b->fa;
    int64_t qlo = ct_min64(b->ql + floor_shr(m0 * b->sql, 16u), b->ql + floor_shr(m1 * b->sql, 16u));
    int64_t qhi = ct_max64(b->qh - floor_shr(-(m0 * b->sqh), 16u), b->qh - floor_shr(-(m1 * b->sqh), 16u));
    int64_t z = ct_min64(b->zl + floor_shr(m0 * b->szl, 16u), b->zl + floor_shr(m1 * b->szl, 16u));
    int32_t nq = (int32_t)(b->a == 0 ? p->cells_y : p->cells_x), i, j0, j1, bj;
    int64_t hb = 0, D = 0;
    if (qhi < 0 || qlo > (int64_t)nq * ONE16) {
        return 1;
    }
    j0 = (int32_t)ct_max64(ct_min64(floor_shr(qlo, 16u), nq - 1), 0);
    j1 = (int32_t)ct_max64(ct_min64(floor_shr(qhi, 16u), nq - 1), 0);
    if ((j1 >> l) - (j0 >> l) > 3) {
        return 0;
    }
    i = (int32_t)(b->s > 0 ? cu : -1 - cu);
    /* bound: four blocks */
    for (bj = j0 >> l; bj <= (j1 >> l); ++bj) {
        int64_t v;
        if (l == 0u) {
            v = b->a == 0 ? cell_hmax(p, i, bj) : cell_hmax(p, bj, i);
        } else {
            uint32_t bu = (uint32_t)(i >> l), bq = (uint32_t)bj;
            v = b->a == 0 ? ct_mip_at(p, l, bu, bq) : ct_mip_at(p, l, bq, bu);
        }
        hb = ct_max64(hb, v);
    }
    if (lw == NULL || z > hb * ONE16) {
        /* straight, or above the tallest post: clear whatever the
         * lowering (D >= 0) */
        return z > hb * ONE16;
    }
    {
        /* lowered: the near face, in the a coordinate: s * cu 2^16;
         * across the axis the posts of cells j0 .. j1, q in [j0, j1 + 1]
         * cells (in the tile, as ct_lower_at asks) */
        int64_t f = b->s * cu * ONE16, o = b->a == 0 ? lw->obx : lw->oby, oq = b->a == 0 ? lw->oby : lw->obx;
        if ((b->s > 0 && f > o) || (b->s < 0 && f < o)) {
            int64_t q = ct_max64(ct_min64(oq, ((int64_t)j1 + 1) * ONE16), (int64_t)j0 * ONE16);
            D = b->a == 0 ? ct_lower_at(lw, f, q) : ct_lower_at(lw, q, f);
        }
    }
    return z > hb * ONE16 - D;
}

/* The first u-cell the run's walk could not show free of the surface
 * (fa + w: none).  The max-mipmap walk of the hierarchical method over
 * the run's bounds: up one level after a block shown free (when aligned),
 * down one after one not.  bound: every u-cell left at most once per
 * advance, and a descent per advance plus the levels: 2 w + levels + 2. */
static int64_t run_walk(const ct_package *p, const ct_lower *lw, const runb *b)
{
    int64_t cu = b->fa, end = b->fa + b->w;
    uint32_t l = 0u, it, bound = 2u * (uint32_t)b->w + p->levels + 2u;
    for (it = 0u; it < bound && cu < end; ++it) {
        if (run_clear(p, lw, b, cu, l)) {
            cu = ct_min64(cu + ((int64_t)1 << l), end);
            if (l < p->levels && ((uint64_t)cu & ((UINT64_C(2) << l) - 1u)) == 0u) {
                l++;
            }
        } else if (l > 0u) {
            l--;
        } else {
            return cu;
        }
    }
    return ct_min64(cu, end);
}

ct_status ct_run_starts(const ct_package *p, const ct_prepared *const *r, uint32_t n, const ct_lower *lw,
                        ct_run_start *out)
{
    /* grp: 0 its own walk; 1 the run's; 2, 3 a half's */
    uint8_t use[CT_RUN_MAX] = {0u}, grp[CT_RUN_MAX] = {0u};
    runb b[3];
    int64_t cs[3] = {0, 0, 0};
    uint32_t k, g;
    int wide;
    if (p == NULL || r == NULL || out == NULL || n > CT_RUN_MAX) {
        return CT_ERR_ARG;
    }
    /* bound: n <= CT_RUN_MAX rays */
    for (k = 0u; k < n; ++k) {
        use[k] = (uint8_t)(r[k]->start == CT_OK && (r[k]->dx != 0 || r[k]->dy != 0));
        out[k].how = CT_RUN_OWN;
        out[k].face = 0u;
        out[k].cell = 0;
        out[k].t0_n = 0;
        out[k].t0_d = 1;
    }
    /* 1: bounds formed; 2: too wide, or the walk showed nothing free */
    wide = run_bounds(p, r, use, n, &b[0]);
    if (wide == 1) {
        cs[0] = run_walk(p, lw, &b[0]);
        wide = cs[0] > b[0].fa ? 1 : 2;
    }
    if (wide == 1) {
        /* bound: n rays */
        for (k = 0u; k < n; ++k) {
            grp[k] = use[k];
        }
    } else if (wide == 2 && n >= 4u) {
        /* the two halves apart (bound: two halves) */
        for (g = 1u; g <= 2u; ++g) {
            uint8_t half[CT_RUN_MAX];
            /* bound: n rays */
            for (k = 0u; k < n; ++k) {
                half[k] = (uint8_t)(use[k] && (k < n / 2u) == (g == 1u));
            }
            if (run_bounds(p, r, half, n, &b[g]) == 1) {
                cs[g] = run_walk(p, lw, &b[g]);
                /* bound: n rays */
                for (k = 0u; k < n; ++k) {
                    grp[k] = half[k] != 0u ? (uint8_t)(g + 1u) : grp[k];
                }
            }
        }
    }
    /* bound: n <= CT_RUN_MAX rays */
    for (k = 0u; k < n; ++k) {
        int64_t c;
        const runb *q;
        rt t0, tend;
        if (grp[k] == 0u) {
            continue;
        }
        q = &b[grp[k] - 1u];
        c = cs[grp[k] - 1u];
        t0.n = c * ONE16 - run_u(r[k], q->a, q->s); /* < 2^32 */
        t0.d = ct_abs64(run_d(r[k], q->a));
        tend.n = r[k]->tend_n;
        tend.d = r[k]->tend_d;
        if (t0.n <= 0) {
            /* the ray starts in or after the first u-cell not shown free */
            continue;
        }
        if (c == q->fa + q->w || !rt_lt(t0, tend)) {
            /* free until it leaves the tile's box */
            out[k].how = CT_RUN_CLEAR;
            continue;
        }
        /* its walk from the face of u-cell c, as a tile set's seam */
        out[k].how = CT_RUN_FACE;
        out[k].face = q->a == 0 ? 1u : 2u;
        out[k].cell = (int32_t)(q->s > 0 ? c : -1 - c);
        out[k].t0_n = t0.n;
        out[k].t0_d = t0.d;
    }
    return CT_OK;
}

ct_status ct_trace_run(const ct_package *p, const ct_prepared *r, uint32_t n, const ct_lower *lw, ct_method m,
                       ct_hit *const *h, ct_status *st)
{
    const ct_prepared *rp[CT_RUN_MAX] = {NULL};
    ct_run_start rs[CT_RUN_MAX];
    uint32_t k;
    if (p == NULL || r == NULL || h == NULL || st == NULL || n > CT_RUN_MAX) {
        return CT_ERR_ARG;
    }
    /* bound: n <= CT_RUN_MAX rays */
    for (k = 0u; k < n; ++k) {
        rp[k] = &r[k];
    }
    (void)ct_run_starts(p, rp, n, lw, rs);
    /* bound: n <= CT_RUN_MAX rays */
    for (k = 0u; k < n; ++k) {
        if (rs[k].how == CT_RUN_CLEAR) {
            /* no hit, as its walk */
            ct_hit_clear(h[k]);
            st[k] = CT_MISS;
        } else if (rs[k].how == CT_RUN_FACE) {
            wstart ws;
            ws.t0.n = rs[k].t0_n;
            ws.t0.d = rs[k].t0_d;
            ws.face = (int)rs[k].face;
            ws.i = ws.j = rs[k].cell;
            st[k] = trace_impl(p, &r[k], m, 1, lw, &ws, h[k]);
        } else {
            st[k] = trace_impl(p, &r[k], m, 1, lw, NULL, h[k]);
        }
    }
    return CT_OK;
}
