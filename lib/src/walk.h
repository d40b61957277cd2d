/*
 * walk.h -- what the walks (trace.c) and the exact cell solver (cell.c)
 * share (private): the walk's context, a cell's exit, the lowering's bound
 * ahead (small static functions, inlined into both), and the solver's entry
 * points.  Number formats: trace.c's header.
 */
#ifndef CT_WALK_H
#define CT_WALK_H

#include "trace_core.h"

enum { FACE_X = 1, FACE_Y = 2, FACE_XY = 3 };

typedef struct {
    rt t;      /* parameter at the exit point */
    int face;  /* FACE_X, FACE_Y or FACE_XY (through a post) */
    int32_t xf, yf; /* face coordinates (cells) */
} cexit;

typedef struct {
    const ct_package *p;
    const ct_prepared *r;
    int32_t sx, sy;   /* signs of dx, dy */
    int64_t adx, ady; /* |dx|, |dy| */
    int32_t cx, cy;   /* fine cells */
    rt tend;
    unsigned zs;      /* the ray's zshift k */
    uint32_t zone;    /* one height LSB in prepared z units: 2^(16-k) */
    uint32_t zmul;    /* 2^k: prepared z units to Q16 */
    int64_t dzf;      /* dz * 2^k: the z direction in Q16 units (<= 2^42) */
    const ct_lower *lw; /* bent ray: the lowered terrain (NULL: straight)  */
    int64_t ratio_q30;  /* lowered culling: floor(2^30 len_lo / |D_p|), in
                           [2^30, 2^30.5]; 0 when culling is off            */
    rt t0;              /* where the walk starts: 0, or (a tile set) the
                           canonical entry of the tile's first cell         */
    int32_t i0, j0;     /* the cell holding the ray at t0 (located, or the
                           tile set's)                                      */
    int prefetch;       /* hosts: ask for the next cone's code early (the
                           angle planes, or a tile set's, are large)        */
} ctx;

/* Height code h >= 0 (< 2^17) in the ray's z units: one 32x32 product. */
static inline int64_t zh(const ctx *c, uint32_t h)
{
    return (int64_t)((uint64_t)h * c->zone);
}

static inline int sgn64(int64_t v) { return (v > 0) - (v < 0); }

/* A lower bound of D over every post of every cell the ray visits from
 * fine cell (i, j) on, in the ray's z units (0 for a straight ray or with
 * culling off).  The ray's horizontal path runs away from the observer, so
 * a visited point q has range rho(q) >= rho at the current cell's back face
 * along the primary axis p, = dp len / |D_p| for points on the ray (dp =
 * that face's distance from the observer along p; the prepared ray passes
 * within 1 mm of the observer's line, far inside the slack); a post of a
 * visited cell is within sqrt(2) cells of such a point: 2 cells of slack.
 * In whole cells, floored: r = floor(dp ratio / 2^46) - 2 (dp < 2^32,
 * ratio < 2^30.5: < 2^62.5), clamped to 2^15 (r^2 <= 2^30), and D >=
 * r^2 kc / 2^16 (kc <= 2^33, ct_lower: < 2^63), clamped to dmax. */
static inline int64_t lower_ahead(const ctx *c, int32_t i, int32_t j)
{
    int64_t dp, r;
    if (c->ratio_q30 == 0) {
        return 0;
    }
    if (c->adx >= c->ady) {
        dp = c->sx > 0 ? (int64_t)i * ONE16 - c->lw->obx : c->lw->obx - ((int64_t)i + 1) * ONE16;
    } else {
        dp = c->sy > 0 ? (int64_t)j * ONE16 - c->lw->oby : c->lw->oby - ((int64_t)j + 1) * ONE16;
    }
    if (dp <= 0) {
        return 0;
    }
    r = (int64_t)(((uint64_t)dp * (uint64_t)c->ratio_q30) >> 46) - 2;
    if (r <= 0) {
        return 0;
    }
    r = ct_min64(r, INT64_C(1) << 15);
    return ct_min64((r * r * c->lw->kc) >> 16, c->lw->dmax) >> c->zs;
}

/* The exact cell test on [tin, exit] of cell (i, j); f(tin) > 0 is known
 * by the caller.  lb: for a bent ray, lower_ahead(c, i, j) if the caller
 * has it, else -1.  Returns 1 and fills *h on a hit (cell.c). */
int ct_cell_test(const ctx *c, int32_t i, int32_t j, rt tin, const cexit *e, int64_t lb, ct_hit *h);

/* The hit at t = tq / 2^26 in cell (i, j): grid and map position. */
void ct_fill_hit(const ctx *c, int64_t tq, int32_t i, int32_t j, ct_hit *h);

/* CT_HIT, or CT_HIT_VOID in a cell the builder marked void. */
static inline ct_status ct_hit_status(const ct_package *p, int32_t i, int32_t j)
{
    if (p->voids != NULL) {
        uint32_t k = (uint32_t)j * p->cells_x + (uint32_t)i;
        if (((uint32_t)p->voids[k >> 3] >> (k & 7u)) & 1u) {
            return CT_HIT_VOID;
        }
    }
    return CT_HIT;
}

/* The sign of f = z_ray - S at t0 > 0 on an entry face of cell (i, j). */
int ct_entry_sign(const ctx *c, int32_t i, int32_t j, rt t0);

#endif /* CT_WALK_H */
