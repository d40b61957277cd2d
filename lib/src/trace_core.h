/*
 * trace_core.h -- what the tracer (trace.c) and ray preparation
 * (prepare.c) share (private): Q16 constants, rational parameters, the
 * cell index rule, a cell's posts and the bilinear surface.  Small static
 * functions, inlined into both.
 */
#ifndef CT_TRACE_CORE_H
#define CT_TRACE_CORE_H

#include "bend.h"
#include "conetrace.h"
#include "fixed.h"

#define ONE16 INT64_C(65536)
#define T_ONE (INT64_C(1) << CT_T_FRAC_BITS)


typedef struct {
    int64_t n, d; /* t = n / d, d > 0 */
} rt;


/* floor(a / 2^n) (fixed.h's ct_floor_shr, under the tracer's short name). */
CT_OPT_INLINE static inline int64_t floor_shr(int64_t a, unsigned n) { return ct_floor_shr(a, n); }

/* a < b for rationals: n <= 2^34, d <= 2^26 -> products < 2^60 */
static inline int rt_lt(rt a, rt b) { return a.n * b.d < b.n * a.d; }


/* The tie rule and the clamp of a cell index k = floor(coordinate): on a
 * grid line (exact) the cell the ray moves into, with no motion along the
 * axis the cell on its + side; clamped to -1 .. ncell. */
static inline int32_t cell_rule(int64_t k, int exact, int32_t s, int32_t ncell)
{
    if (exact) {
        if (s < 0) {
            k -= 1;
        } else if (s == 0 && k == ncell) {
            k -= 1;
        }
    }
    if (k < -1) {
        k = -1;
    }
    if (k > ncell) {
        k = ncell;
    }
    return (int32_t)k;
}

/* Fine-cell index along one axis at o + t*d (Q16), with the tie rule: a
 * point exactly on a grid line belongs to the cell the ray moves into; with
 * no motion along the axis, to the cell on its + side, clamped to the tile.
 * num = o*den + n*d: o < 2^31 (or 2^47 at prep) ... callers bound it.      */
static inline int32_t axis_cell(int64_t num, int64_t den16, int32_t s, int32_t ncell)
{
    /* den16 = 2^16 (a Q16 coordinate itself, t = 0 / 1): a shift */
    int64_t k = den16 == ONE16 ? floor_shr(num, 16u) : ct_floor_div(num, den16);
    return cell_rule(k, k * den16 == num, s, ncell);
}

/* The coarse row or column of fine row or column i (0 <= i < 2^16): i / r
 * by the multiplier (exact for i < 2^16, see ct_package.reduce_mul). */
static inline uint32_t ct_coarse_of(const ct_package *p, int32_t i)
{
    return (uint32_t)(((uint64_t)(uint32_t)i * p->reduce_mul) >> 32);
}

/* Coarse cell index of fine cell (i, j) (0 <= i, j < 2^16). */
static inline size_t ct_coarse_index(const ct_package *p, int32_t i, int32_t j)
{
    return (size_t)ct_coarse_of(p, j) * p->coarse_x + ct_coarse_of(p, i);
}

typedef struct {
    int32_t h00, h10, h01, h11, hmax;
} posts4;

static inline void load_posts(const ct_package *p, int32_t i, int32_t j, posts4 *q)
{
    const uint8_t *r0 = p->heights + 2u * ((size_t)(uint32_t)j * p->width + (uint32_t)i);
    const uint8_t *r1 = r0 + 2u * p->width;
    int32_t m;
    q->h00 = (int32_t)ct_ld16(r0);
    q->h10 = (int32_t)ct_ld16(r0 + 2);
    q->h01 = (int32_t)ct_ld16(r1);
    q->h11 = (int32_t)ct_ld16(r1 + 2);
    m = q->h00 > q->h10 ? q->h00 : q->h10;
    m = m > q->h01 ? m : q->h01;
    q->hmax = m > q->h11 ? m : q->h11;
}

/* The tallest post of cell (i, j). */
static inline int32_t cell_hmax(const ct_package *p, int32_t i, int32_t j)
{
    posts4 q;
    load_posts(p, i, j, &q);
    return q.hmax;
}

/* Surface height at a Q16 point of cell (i, j), times 2^32 (exact):
 * h00*2^32 + a*U*2^16 + b*V*2^16 + c*U*V with U, V in [0, 2^16]: < 2^50. */
static inline int64_t surface_q32(const ct_package *p, int32_t i, int32_t j, int64_t x, int64_t y)
{
    posts4 q;
    int64_t U = x - (int64_t)i * ONE16, V = y - (int64_t)j * ONE16;
    int64_t a, b, cc;
    load_posts(p, i, j, &q);
    a = (int64_t)q.h10 - q.h00;
    b = (int64_t)q.h01 - q.h00;
    cc = (int64_t)q.h11 - q.h10 - q.h01 + q.h00;
    return (int64_t)q.h00 * (ONE16 * ONE16) + a * U * ONE16 + b * V * ONE16 + cc * U * V;
}


/* Where the ray o + t D (o in the box: x, y Q16, z in units of 2^16/zone
 * Q16) leaves the tile's box: horizontally, through the top (rising) or
 * below hmin - 1 (descending; never reached without a hit), the floor
 * lowered by zlow (a bent ray's largest lowering in its z units, < 2^32;
 * 0 for a straight ray): |zbot| < 2^33.  Candidates
 * have n < 2^34 and d <= 2^26, so rt_lt cannot overflow; with no candidate
 * (cannot happen: some axis moves) te stays 2^34. */
static inline rt box_exit(const ct_package *p, const int64_t O[3], const int32_t D[3], int64_t zone, int64_t zlow)
{
    rt te = {INT64_C(1) << 34, 1}, c;
    int64_t ztop = ((int64_t)p->hmax + 1) * zone, zbot = ((int64_t)p->hmin - 1) * zone - zlow;
    int have = 0, k;
    /* bound: 3 axes */
    for (k = 0; k < 3; ++k) {
        if (D[k] == 0) {
            continue;
        }
        c.d = ct_abs64(D[k]);
        if (k < 2) {
            c.n = D[k] > 0 ? (int64_t)(k == 0 ? p->cells_x : p->cells_y) * ONE16 - O[k] : O[k];
        } else if (D[k] > 0) {
            c.n = ct_max64(ztop - O[2], 0);
        } else {
            if (O[2] <= zbot) {
                continue;
            }
            c.n = O[2] - zbot;
        }
        if (!have || rt_lt(c, te)) {
            te = c;
            have = 1;
        }
    }
    return te;
}

/* The lowered surface (bent rays) at a Q16 point of cell (i, j), in Q16
 * LSB times 2^32, exact (trace.c). */
ct_i128 ct_surface_low_q48(const ct_package *p, const ct_lower *lw, int32_t i, int32_t j, int64_t x, int64_t y);

#endif /* CT_TRACE_CORE_H */
