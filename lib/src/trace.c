/*
 * trace.c -- exact first hit of a prepared ray on the bilinear surface, by
 * four methods that all share one exact cell test (so all four return
 * bit-identical hits):
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
#include "bend.h"
#include "conetrace.h"
#include "fixed.h"
#include "tiles.h"
#include "trace_core.h"

enum { FACE_X = 1, FACE_Y = 2, FACE_XY = 3 };

static const rt T_ZERO = {0, 1};

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
static int64_t zh(const ctx *c, uint32_t h)
{
    return (int64_t)((uint64_t)h * c->zone);
}

static int sgn64(int64_t v) { return (v > 0) - (v < 0); }

/* ------------------------------------------------------------------------ */
/* Lowered terrain (bent rays, see ct_lower in bend.h).                      */

/* floor(v / 2^n) of a non-negative 128-bit v, n < 128. */
static uint64_t ushr128(ct_i128 v, uint32_t n)
{
    if (n >= 64u) {
        return v.hi >> (n - 64u);
    }
    if (n == 0u) {
        return v.lo;
    }
    return (v.hi << (64u - n)) | (v.lo >> n);
}

/* D for a squared Q16 distance q < 2^63: q kf < 2^95, result < 2^33 for
 * any point of the tile (<= dmax < 2^32 by set-up) */
static int64_t lower_of(const ct_lower *lw, uint64_t q)
{
    return (int64_t)ushr128(ct_umul64(q, lw->kf), lw->kshift);
}

int64_t ct_lower_at(const ct_lower *lw, int64_t x, int64_t y)
{
    /* |x - obx|, |y - oby| < 2^31 inside the tile (set-up): squares < 2^62 */
    int64_t ex = x - lw->obx, ey = y - lw->oby;
    return lower_of(lw, (uint64_t)(ex * ex) + (uint64_t)(ey * ey));
}

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
static int64_t lower_ahead(const ctx *c, int32_t i, int32_t j)
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

/* Exit of fine cell (i, j).  (face*2^16 - o) < 2^31, times |d| <= 2^26:
 * < 2^57. */
static void cell_exit(const ctx *c, int32_t i, int32_t j, cexit *e)
{
    int64_t nx = 0, ny = 0;
    e->xf = i + (c->sx > 0 ? 1 : 0);
    e->yf = j + (c->sy > 0 ? 1 : 0);
    if (c->sx != 0) {
        nx = ((int64_t)e->xf * ONE16 - c->r->ox) * c->sx;
    }
    if (c->sy != 0) {
        ny = ((int64_t)e->yf * ONE16 - c->r->oy) * c->sy;
    }
    if (c->sy == 0) {
        e->face = FACE_X;
    } else if (c->sx == 0) {
        e->face = FACE_Y;
    } else {
        int64_t lx = nx * c->ady, ly = ny * c->adx;
        e->face = lx < ly ? FACE_X : (ly < lx ? FACE_Y : FACE_XY);
    }
    if (e->face == FACE_Y) {
        e->t.n = ny;
        e->t.d = c->ady;
    } else {
        e->t.n = nx;
        e->t.d = c->adx;
    }
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

/* Sign of f = z_ray - S at the exit point, exact.  With d = e->t.d and
 * n = e->t.n:  d*Z = oz*d + n*dz (< 2^58 + 2^60) in prepared z units; at a
 * face, d*Z*2^k = d*z_q16 < 2^59 (the header's argument: d*|z_q16(tin)|
 * < 2^59... 2^26 * 2^33, plus <= 2^58 within the cell); h*2^16*d < 2^58;
 * d*2^16*v in [0, 2^42] times |dh| < 2^16: < 2^58.  Sum < 2^61.        */
static int exit_sign(const ctx *c, int32_t i, int32_t j, const cexit *e, const posts4 *q)
{
    int64_t d = e->t.d, n = e->t.n;
    int64_t dz = c->r->oz * d + n * (int64_t)c->r->dz;
    int64_t ha, hb, dw, val;
    if (e->face == FACE_XY) {
        int32_t h = (e->xf == i) ? (e->yf == j ? q->h00 : q->h01) : (e->yf == j ? q->h10 : q->h11);
        return sgn64(dz - zh(c, (uint32_t)h) * d);
    }
    dz *= (int64_t)c->zmul;
    if (e->face == FACE_X) {
        ha = (e->xf == i) ? q->h00 : q->h10;
        hb = (e->xf == i) ? q->h01 : q->h11;
        dw = c->r->oy * d + n * (int64_t)c->r->dy - (int64_t)j * ONE16 * d;
    } else {
        ha = (e->yf == j) ? q->h00 : q->h01;
        hb = (e->yf == j) ? q->h10 : q->h11;
        dw = c->r->ox * d + n * (int64_t)c->r->dx - (int64_t)i * ONE16 * d;
    }
    val = (dz - ha * ONE16 * d) - (hb - ha) * dw;
    return sgn64(val);
}

/* ------------------------------------------------------------------------ */
/* The quadratic along the cell.  The primary axis p is the one with the
 * larger |D| (x for |dx| >= |dy|); w in [0, 1] is the cell coordinate along
 * p measured in the ray's direction (w = u for dx > 0, w = 1 - u for
 * dx < 0), so w grows with t.  Posts are relabelled g[ip][iq] (ip along p,
 * mirrored when the ray moves to -p), and the surface is
 *     S = g00 + a w + b v + c w v      (v: cell coordinate across p).
 * With d = |D_p|, L = the cell's w = 0 line, dps = d * t(L) = s*(L - o_p):
 *     V0 = d*2^16 * v(L) = d*(o_q - k_q*2^16) + dps_q, dps_q = s*(L-o_p)*D_q
 *     Z0 = d*2^16 * (z(L) - g00) = d*(o_z - g00*2^16) + s*(L-o_p)*D_z
 *     d*2^16 * f(w) = A w^2 + B w + C,
 *     C = Z0 - b*V0,  B = 2^16*(D_z - a*d - b*D_q) - c*V0,  A = -c*2^16*D_q
 * In the ray's prepared z units D_z is 2^k times smaller and z values are
 * 2^k times coarser; the formulas use D_z * 2^k and z * 2^k (Q16).
 * Bounds (|D_q| <= |D_p| so v(L) in [-1, 2]; |a|,|b| < 2^16, |c| < 2^17;
 * |D_z| 2^k <= 2^42): |V0| <= 2^43, |Z0| < 2^59.6, |C| < 2^60.6,
 * |B| < 2^61, |A| < 2^59; B^2 - 4AC < 2^123 (128-bit).                    */
typedef struct {
    int64_t A, B, C;
    int p;       /* 0: x-major, 1: y-major */
    int64_t d;   /* |D_p| */
    int64_t dps; /* s * (L - o_p): d times t at the w = 0 line */
} quad;

static void make_quad(const ctx *c, int32_t i, int32_t j, const posts4 *q, quad *Q)
{
    int64_t op, oq, Dp, Dq, kq, L, g00, g10, g01, g11, a, b, cc, V0, Z0, s;
    int32_t kp;
    Q->p = (c->adx >= c->ady) ? 0 : 1;
    if (Q->p == 0) {
        op = c->r->ox;
        oq = c->r->oy;
        Dp = c->r->dx;
        Dq = c->r->dy;
        kp = i;
        kq = j;
        g00 = q->h00;
        g10 = q->h10;
        g01 = q->h01;
        g11 = q->h11;
    } else {
        op = c->r->oy;
        oq = c->r->ox;
        Dp = c->r->dy;
        Dq = c->r->dx;
        kp = j;
        kq = i;
        g00 = q->h00;
        g10 = q->h01;
        g01 = q->h10;
        g11 = q->h11;
    }
    s = Dp > 0 ? 1 : -1;
    if (s < 0) {
        /* mirror along p: w = 1 - (cell coordinate) */
        int64_t t0 = g00, t1 = g01;
        g00 = g10;
        g01 = g11;
        g10 = t0;
        g11 = t1;
        L = ((int64_t)kp + 1) * ONE16;
    } else {
        L = (int64_t)kp * ONE16;
    }
    a = g10 - g00;
    b = g01 - g00;
    cc = g11 - g10 - g01 + g00;
    Q->d = ct_abs64(Dp);
    Q->dps = s * (L - op); /* |L - o_p| < 2^31 */
    /* d*(o_q - k_q 2^16): 2^26 * 2^31; s*(L - o_p)*D_q: 2^31 * 2^26 */
    V0 = Q->d * (oq - kq * ONE16) + Q->dps * Dq;
    /* Z0 = d * 2^16 * (z(L) - g00) with z(L) in LSB: the bracket is d times
     * z(L) - g00 in prepared z units (d*(o_z - g00*zone): 2^26 * 2^33;
     * s*(L - o_p)*D_z: 2^31 * 2^26), times 2^k it is d * (z_q16(L) -
     * g00 2^16) < 2^59 + 2^58 (the header's argument: L is the cell's
     * entry line, within one cell of tin). */
    Z0 = (int64_t)c->zmul * (Q->d * (c->r->oz - zh(c, (uint32_t)g00)) + Q->dps * (int64_t)c->r->dz);
    Q->C = Z0 - b * V0;
    Q->B = ONE16 * (c->dzf - a * Q->d - b * Dq) - cc * V0;
    Q->A = -cc * ONE16 * Dq;
}

/* w at parameter t as pn / pd (pd > 0): d*t - dps over 2^16:
 * pn = n*d - e*dps (< 2^60 + 2^57), pd = e * 2^16 <= 2^42. */
static void p_at(const ctx *c, const quad *Q, rt t, int64_t *pn, int64_t *pd)
{
    (void)c;
    *pn = t.n * Q->d - t.d * Q->dps;
    *pd = t.d * ONE16;
}

/* sign of dQ/dw at w = pn/pd: sign(B*pd + 2A*pn), 128-bit (< 2^104). */
static int dq_sign(const quad *Q, int64_t pn, int64_t pd)
{
    ct_i128 v = ct_i128_add(ct_i128_mul(Q->B, pd), ct_i128_mul(2 * Q->A, pn));
    return ct_i128_sign(v);
}

static ct_i128 disc(const quad *Q)
{
    /* B^2 < 2^122; 4AC < 2^121 */
    return ct_i128_sub(ct_i128_mul(Q->B, Q->B), ct_i128_mul128_64(ct_i128_mul(Q->A, Q->C), 4));
}

/* Interior test: f > 0 at both ends of [tin, tout]; is there an interior
 * minimum <= 0?  Needs A > 0, the vertex strictly inside, and B^2 >= 4AC. */
static int interior_hit(const ctx *c, const quad *Q, rt tin, rt tout)
{
    int64_t pn, pd;
    if (Q->A <= 0) {
        return 0;
    }
    p_at(c, Q, tin, &pn, &pd);
    if (dq_sign(Q, pn, pd) >= 0) {
        return 0;
    }
    p_at(c, Q, tout, &pn, &pd);
    if (dq_sign(Q, pn, pd) <= 0) {
        return 0;
    }
    return ct_i128_sign(disc(Q)) >= 0;
}

/* First down-crossing root of the quadratic in [w(tin), w(tout)] and its
 * t in Q26 (floored: the reported point never passes the true hit by more
 * than one Q26 step).  Root w = (-B - sqrt(D)) / 2A = 2C / (-B + sqrt(D)),
 * each form used where it does not cancel.  w is computed in Q60 (W_BITS):
 * t = (dps + w 2^16) / d, so a steep ray (tiny d) still gets t to 2^-44.
 * Scaling: |2C| 2^60 < 2^121 and |B + sd| 2^60 < 2^123 (128-bit), divisors
 * -B + sd < 2^62.3 and 2|A| < 2^60; quotients saturate at +-2^62.        */
#define W_BITS 60u

static int64_t root_t_q26(const ctx *c, const quad *Q, rt tin, rt tout)
{
    ct_i128 D = disc(Q);
    int64_t sd, w, pn, pd;
    ct_i128 num;
    (void)c;
    if (ct_i128_sign(D) < 0) {
        D = ct_i128_from64(0); /* cannot happen for a decided hit */
    }
    sd = (int64_t)ct_i128_isqrt(D); /* < 2^61.5 */
    if (Q->B < 0) {
        w = ct_i128_floor_div_sat(ct_i128_shl(ct_i128_from64(2 * Q->C), W_BITS), -Q->B + sd);
    } else if (Q->A != 0) {
        /* (-B - sd) / 2A with A < 0 here: (B + sd) / (2|A|) */
        ct_i128 nn = ct_i128_shl(ct_i128_from64(Q->B + sd), W_BITS);
        int64_t den = -2 * Q->A;
        if (den < 0) {
            nn = ct_i128_neg(nn);
            den = -den;
        }
        w = ct_i128_floor_div_sat(nn, den);
    } else {
        w = 0; /* f not decreasing: cannot happen for a decided hit */
    }
    /* clamp to the segment: w >= lo = ceil(w(tin) 2^60) and w <= hi =
     * floor(w(tout) 2^60), w(t) = pn / pd.  For an integer w, w < lo iff
     * w pd < pn 2^60 and w > hi iff w pd > pn 2^60, so the quotients are
     * formed only when a clamp applies.  |pn| < 2^61: pn 2^60 < 2^121;
     * |w| <= 2^62, pd <= 2^42: w pd < 2^104. */
    p_at(c, Q, tin, &pn, &pd);
    num = ct_i128_shl(ct_i128_from64(pn), W_BITS);
    if (ct_i128_cmp(ct_i128_mul(w, pd), num) < 0) {
        w = -ct_i128_floor_div_sat(ct_i128_neg(num), pd);
    }
    p_at(c, Q, tout, &pn, &pd);
    num = ct_i128_shl(ct_i128_from64(pn), W_BITS);
    if (ct_i128_cmp(ct_i128_mul(w, pd), num) > 0) {
        w = ct_i128_floor_div_sat(num, pd);
    }
    /* d*t = dps + w*2^16, so t_q26 = floor((dps 2^60 + w 2^16) / (d 2^34))
     * = floor((dps 2^44 + w) / (d 2^18)).  In 64 bits: dps 2^26 = q1 d + r1
     * (0 <= r1 < d), so t_q26 = q1 + floor((r1 2^18 + w) / (d 2^18)).
     * |dps| < 2^31: dps 2^26 < 2^57; r1 2^18 < 2^44 and |w| <= 2^62: the
     * sum < 2^63; d 2^18 <= 2^44. */
    {
        int64_t q1 = ct_floor_div(Q->dps * T_ONE, Q->d);
        int64_t r1 = Q->dps * T_ONE - q1 * Q->d;
        int64_t t = q1 + ct_floor_div(r1 * (INT64_C(1) << (W_BITS - 16u - CT_T_FRAC_BITS)) + w,
                                      Q->d << (W_BITS - 16u - CT_T_FRAC_BITS));
        return t < 0 ? 0 : t;
    }
}

/* ------------------------------------------------------------------------ */

static void fill_hit(const ctx *c, int64_t tq, int32_t i, int32_t j, ct_hit *h)
{
    const ct_prepared *r = c->r;
    /* tq < 2^35, |d| <= 2^26: < 2^61; z in Q16: oz 2^k + tq dz 2^k / 2^26 */
    h->t_q26 = tq;
    h->x_q16 = r->ox + ct_floor_div(tq * (int64_t)r->dx, T_ONE);
    h->y_q16 = r->oy + ct_floor_div(tq * (int64_t)r->dy, T_ONE);
    h->z_q16 = r->oz * (int64_t)c->zmul + floor_shr(tq * (int64_t)r->dz, CT_T_FRAC_BITS - c->zs);
    if (c->lw != NULL) {
        /* a bent ray: the curve is the tangent plus the rise at the hit */
        h->z_q16 += ct_lower_at(c->lw, h->x_q16, h->y_q16);
    }
    h->cell_x = i;
    h->cell_y = j;
    (void)ct_grid_to_map(c->p, h->x_q16, h->y_q16, h->z_q16, &h->e_nm, &h->n_nm, &h->h_nm);
}

static ct_status hit_status(const ct_package *p, int32_t i, int32_t j)
{
    if (p->voids != NULL) {
        uint32_t k = (uint32_t)j * p->cells_x + (uint32_t)i;
        if (((uint32_t)p->voids[k >> 3] >> (k & 7u)) & 1u) {
            return CT_HIT_VOID;
        }
    }
    return CT_HIT;
}

/* ------------------------------------------------------------------------ */
/* The cell test on the lowered terrain (bent rays).  Posts G = h 2^16 - D
 * in Q16 LSB, |G| < 2^33 (D <= dmax < 2^32).  Everything is as for the
 * straight test with heights 2^16 finer, so the products grow by 16 bits:
 * 128-bit where marked, and the interior minimum's discriminant compared
 * in 256 bits.                                                             */

typedef struct {
    int64_t g00, g10, g01, g11;
} lposts;

static void lower_posts(const ctx *c, int32_t i, int32_t j, const posts4 *q, lposts *L)
{
    int64_t x0 = (int64_t)i * ONE16, y0 = (int64_t)j * ONE16;
    L->g00 = (int64_t)q->h00 * ONE16 - ct_lower_at(c->lw, x0, y0);
    L->g10 = (int64_t)q->h10 * ONE16 - ct_lower_at(c->lw, x0 + ONE16, y0);
    L->g01 = (int64_t)q->h01 * ONE16 - ct_lower_at(c->lw, x0, y0 + ONE16);
    L->g11 = (int64_t)q->h11 * ONE16 - ct_lower_at(c->lw, x0 + ONE16, y0 + ONE16);
}

/* Sign of f at the exit point.  dq = d * z_q16 (< 2^61, the header's
 * argument); G d < 2^59.  At a face: 2^16 (dq - Ga d) < 2^78 and
 * (Gb - Ga) dw < 2^34 * 2^42 (128-bit). */
static int exit_sign_low(const ctx *c, int32_t i, int32_t j, const cexit *e, const lposts *L)
{
    int64_t d = e->t.d, n = e->t.n;
    int64_t dq = (c->r->oz * d + n * (int64_t)c->r->dz) * (int64_t)c->zmul;
    int64_t ga, gb, dw;
    if (e->face == FACE_XY) {
        int64_t g = (e->xf == i) ? (e->yf == j ? L->g00 : L->g01) : (e->yf == j ? L->g10 : L->g11);
        return sgn64(dq - g * d);
    }
    if (e->face == FACE_X) {
        ga = (e->xf == i) ? L->g00 : L->g10;
        gb = (e->xf == i) ? L->g01 : L->g11;
        dw = c->r->oy * d + n * (int64_t)c->r->dy - (int64_t)j * ONE16 * d;
    } else {
        ga = (e->yf == j) ? L->g00 : L->g01;
        gb = (e->yf == j) ? L->g10 : L->g11;
        dw = c->r->ox * d + n * (int64_t)c->r->dx - (int64_t)i * ONE16 * d;
    }
    return ct_i128_sign(ct_i128_sub(ct_i128_shl(ct_i128_from64(dq - ga * d), 16), ct_i128_mul(gb - ga, dw)));
}

/* d 2^16 f_q16(w) = A w^2 + B w + C (make_quad's derivation with posts in
 * Q16): C = 2^16 Z0 - b V0, B = 2^32 D_z 2^k - 2^16 (a d + b D_q) - c V0,
 * A = -c 2^16 D_q.  |a|, |b| < 2^34, |c| < 2^35, |V0| <= 2^43, |Z0| <
 * 2^60.6: |C| < 2^78, |B| < 2^80, |A| < 2^77 (128-bit). */
typedef struct {
    ct_i128 A, B, C;
    quad q; /* p, d, dps as make_quad; its A, B, C: the above scaled down */
} wquad;

static void make_quad_low(const ctx *c, int32_t i, int32_t j, const lposts *L, wquad *W)
{
    int64_t op, oq, Dp, Dq, kq, Lp, g00, g10, g01, g11, a, b, cc, V0, Z0, s;
    int32_t kp;
    quad *Q = &W->q;
    Q->p = (c->adx >= c->ady) ? 0 : 1;
    if (Q->p == 0) {
        op = c->r->ox;
        oq = c->r->oy;
        Dp = c->r->dx;
        Dq = c->r->dy;
        kp = i;
        kq = j;
        g00 = L->g00;
        g10 = L->g10;
        g01 = L->g01;
        g11 = L->g11;
    } else {
        op = c->r->oy;
        oq = c->r->ox;
        Dp = c->r->dy;
        Dq = c->r->dx;
        kp = j;
        kq = i;
        g00 = L->g00;
        g10 = L->g01;
        g01 = L->g10;
        g11 = L->g11;
    }
    s = Dp > 0 ? 1 : -1;
    if (s < 0) {
        int64_t t0 = g00, t1 = g01;
        g00 = g10;
        g01 = g11;
        g10 = t0;
        g11 = t1;
        Lp = ((int64_t)kp + 1) * ONE16;
    } else {
        Lp = (int64_t)kp * ONE16;
    }
    a = g10 - g00;
    b = g01 - g00;
    cc = g11 - g10 - g01 + g00;
    Q->d = ct_abs64(Dp);
    Q->dps = s * (Lp - op);
    V0 = Q->d * (oq - kq * ONE16) + Q->dps * Dq;
    /* d z_q16(L) (< 2^59 + 2^58, the header's argument) - d g00 (< 2^59) */
    Z0 = (int64_t)c->zmul * (Q->d * c->r->oz + Q->dps * (int64_t)c->r->dz) - Q->d * g00;
    W->C = ct_i128_sub(ct_i128_shl(ct_i128_from64(Z0), 16), ct_i128_mul(b, V0));
    /* a d, b D_q < 2^60 each */
    W->B = ct_i128_sub(ct_i128_sub(ct_i128_shl(ct_i128_from64(c->dzf), 32),
                                   ct_i128_shl(ct_i128_from64(a * Q->d + b * Dq), 16)),
                       ct_i128_mul(cc, V0));
    W->A = ct_i128_neg(ct_i128_shl(ct_i128_mul(cc, Dq), 16)); /* cc D_q < 2^61 */
}

/* Unsigned 128 x 128 -> 256-bit product (a, b < 2^127), limbs low first. */
static void umul128x128(ct_i128 a, ct_i128 b, uint64_t r[4])
{
    ct_i128 p00 = ct_umul64(a.lo, b.lo), p01 = ct_umul64(a.lo, b.hi);
    ct_i128 p10 = ct_umul64(a.hi, b.lo), p11 = ct_umul64(a.hi, b.hi);
    uint64_t c1, c2, t;
    r[0] = p00.lo;
    t = p00.hi + p01.lo;
    c1 = t < p00.hi ? 1u : 0u;
    r[1] = t + p10.lo;
    c1 += r[1] < t ? 1u : 0u;
    t = p11.lo + p01.hi;
    c2 = t < p11.lo ? 1u : 0u;
    t += p10.hi;
    c2 += t < p10.hi ? 1u : 0u;
    r[2] = t + c1;
    c2 += r[2] < t ? 1u : 0u;
    r[3] = p11.hi + c2;
}

/* B^2 >= 4AC for A > 0 (exact; 4|A| < 2^79, |B|, |C| < 2^80). */
static int disc_nonneg_low(const wquad *W)
{
    uint64_t l[4], r[4];
    int k;
    if (ct_i128_sign(W->C) <= 0) {
        return 1;
    }
    umul128x128(ct_i128_abs(W->B), ct_i128_abs(W->B), l);
    umul128x128(ct_i128_shl(W->A, 2), W->C, r);
    for (k = 3; k >= 0; --k) { /* bound: 4 limbs */
        if (l[k] != r[k]) {
            return l[k] > r[k];
        }
    }
    return 1;
}

/* sign of dQ/dw at w = pn/pd: B pd + 2A pn.  pd <= 2^42 and, for t in the
 * cell, |pn| <= pd (w in [0, 1]): < 2^122 + 2^120 (128-bit). */
static int dq_sign_low(const wquad *W, int64_t pn, int64_t pd)
{
    return ct_i128_sign(ct_i128_add(ct_i128_mul128_64(W->B, pd), ct_i128_mul128_64(ct_i128_shl(W->A, 1), pn)));
}

static int interior_hit_low(const ctx *c, const wquad *W, rt tin, rt tout)
{
    int64_t pn, pd;
    if (ct_i128_sign(W->A) <= 0) {
        return 0;
    }
    p_at(c, &W->q, tin, &pn, &pd);
    if (dq_sign_low(W, pn, pd) >= 0) {
        return 0;
    }
    p_at(c, &W->q, tout, &pn, &pd);
    if (dq_sign_low(W, pn, pd) <= 0) {
        return 0;
    }
    return disc_nonneg_low(W);
}

/* The hit's position only (the decision above is exact): the coefficients
 * scaled by one power of two into make_quad's ranges (|A|, |B|, |C| <
 * 2^59), which moves the root by far less than the reported position's
 * resolution (t_q26, Q16 cells) except where the ray is tangent to the
 * surface; root_t_q26 clamps it to [tin, tout] exactly either way. */
static int64_t root_low(const ctx *c, wquad *W, rt tin, rt tout)
{
    ct_i128 m = ct_i128_abs(W->A);
    uint64_t top;
    unsigned n;
    if (ct_i128_cmp(ct_i128_abs(W->B), m) > 0) {
        m = ct_i128_abs(W->B);
    }
    if (ct_i128_cmp(ct_i128_abs(W->C), m) > 0) {
        m = ct_i128_abs(W->C);
    }
    top = m.hi != 0u ? m.hi : 0u;
    n = top != 0u ? 64u + ct_bitlen64(top) : ct_bitlen64(m.lo);
    n = n > 59u ? n - 59u : 0u;
    if (n > 0u) {
        W->A = ct_i128_sar(W->A, n);
        W->B = ct_i128_sar(W->B, n);
        W->C = ct_i128_sar(W->C, n);
    }
    W->q.A = ct_i128_to64(W->A);
    W->q.B = ct_i128_to64(W->B);
    W->q.C = ct_i128_to64(W->C);
    return root_t_q26(c, &W->q, tin, tout);
}

CT_NOINLINE static int cell_test_low(const ctx *c, int32_t i, int32_t j, rt tin, const cexit *e, const posts4 *q,
                                     ct_hit *h)
{
    lposts L;
    wquad W;
    lower_posts(c, i, j, q, &L);
    if (exit_sign_low(c, i, j, e, &L) > 0) {
        int64_t cc = L.g11 - L.g10 - L.g01 + L.g00;
        if (cc == 0 || (cc > 0) == ((c->sx * c->sy) > 0) || c->sx == 0 || c->sy == 0) {
            return 0;
        }
        make_quad_low(c, i, j, &L, &W);
        if (!interior_hit_low(c, &W, tin, e->t)) {
            return 0;
        }
    } else {
        make_quad_low(c, i, j, &L, &W);
    }
    fill_hit(c, root_low(c, &W, tin, e->t), i, j, h);
    return 1;
}

/* The exact cell test on [tin, exit]; f(tin) > 0 is known by the caller.
 * lb: for a bent ray, lower_ahead(c, i, j) if the caller has it, else -1.
 * Returns 1 and fills *h on a hit. */
static int cell_test(const ctx *c, int32_t i, int32_t j, rt tin, const cexit *e, int64_t lb, ct_hit *h)
{
    posts4 q;
    int64_t zlo, zmax;
    rt tlo;
    load_posts(c->p, i, j, &q);
    /* cheap reject: lowest ray point above the tallest corner (for a bent
     * ray, less the lowering's bound ahead, < 2^32 >> k, when needed).
     * d*Z < 2^60 (see exit_sign), hmax*2^16*d < 2^58. */
    tlo = c->r->dz <= 0 ? e->t : tin;
    zlo = c->r->oz * tlo.d + tlo.n * (int64_t)c->r->dz;
    zmax = zh(c, (uint32_t)q.hmax);
    if (zlo > zmax * tlo.d) {
        return 0;
    }
    if (c->lw != NULL) {
        if (lb < 0) {
            lb = lower_ahead(c, i, j);
        }
        if (zlo > (zmax - lb) * tlo.d) {
            return 0;
        }
        return cell_test_low(c, i, j, tin, e, &q, h);
    }
    if (exit_sign(c, i, j, e, &q) > 0) {
        int64_t cc = (int64_t)q.h11 - q.h10 - q.h01 + q.h00;
        quad Q;
        /* an interior minimum needs f convex: -c*dx*dy > 0 */
        if (cc == 0 || (cc > 0) == ((c->sx * c->sy) > 0) || c->sx == 0 || c->sy == 0) {
            return 0;
        }
        make_quad(c, i, j, &q, &Q);
        if (!interior_hit(c, &Q, tin, e->t)) {
            return 0;
        }
        fill_hit(c, root_t_q26(c, &Q, tin, e->t), i, j, h);
        return 1;
    }
    {
        quad Q;
        make_quad(c, i, j, &q, &Q);
        fill_hit(c, root_t_q26(c, &Q, tin, e->t), i, j, h);
    }
    return 1;
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
    uint32_t it, bound = CT_WCET_CELL_ITERS(c->cx, c->cy);
    rt tin = c->t0;
    cexit e;
    i = c->i0;
    j = c->j0;
    /* bound: each iteration leaves one fine cell */
    for (it = 0u; it < bound; ++it) {
        if (!inside(c, i, j)) {
            h->iters = it;
            return CT_MISS;
        }
        cell_exit(c, i, j, &e);
        h->steps++;
        if (cell_test(c, i, j, tin, &e, -1, h)) {
            h->iters = it + 1u;
            return hit_status(c->p, i, j);
        }
        if (!rt_lt(e.t, c->tend)) {
            h->iters = it + 1u;
            return CT_MISS;
        }
        next_cell(c, &e, &i, &j);
        tin = e.t;
    }
    return CT_ERR_INTERNAL;
}

static uint32_t mip_at(const ct_package *p, uint32_t l, int32_t bi, int32_t bj)
{
    return ct_ld16(p->mip[l] + 2u * ((size_t)(uint32_t)bj * p->mip_w[l] + (uint32_t)bi));
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
            if (cell_test(c, i, j, t, &e, -1, h)) {
                h->iters = it + 1u;
                return hit_status(p, i, j);
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
            int64_t bmax = (int64_t)mip_at(p, lvl, bi, bj), nx = 0, ny = 0;
            rt tx;
            int face;
            /* block exit faces (cells); |face*2^16 - o| < 2^31 */
            xf = c->sx > 0 ? ((bi + 1) << lvl) : (bi << lvl);
            yf = c->sy > 0 ? ((bj + 1) << lvl) : (bj << lvl);
            if (xf > c->cx) {
                xf = c->cx;
            }
            if (yf > c->cy) {
                yf = c->cy;
            }
            if (c->sx != 0) {
                nx = ((int64_t)xf * ONE16 - c->r->ox) * c->sx;
            }
            if (c->sy != 0) {
                ny = ((int64_t)yf * ONE16 - c->r->oy) * c->sy;
            }
            if (c->sy == 0) {
                face = FACE_X;
            } else if (c->sx == 0) {
                face = FACE_Y;
            } else {
                int64_t lx = nx * c->ady, ly = ny * c->adx;
                face = lx < ly ? FACE_X : (ly < lx ? FACE_Y : FACE_XY);
            }
            if (face == FACE_Y) {
                tx.n = ny;
                tx.d = c->ady;
            } else {
                tx.n = nx;
                tx.d = c->adx;
            }
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

/* Coarse cell index of fine cell (i, j): i / r by the multiplier (exact for
 * i < 2^16, see ct_package.reduce_mul). */
static size_t coarse_index(const ct_package *p, int32_t i, int32_t j)
{
    uint32_t ci = (uint32_t)(((uint64_t)(uint32_t)i * p->reduce_mul) >> 32);
    uint32_t cj = (uint32_t)(((uint64_t)(uint32_t)j * p->reduce_mul) >> 32);
    return (size_t)cj * p->coarse_x + ci;
}

static ct_status walk_cones(const ctx *c, uint32_t plane, ct_hit *h)
{
    const ct_package *p = c->p;
    const ct_prepared *r = c->r;
    const uint8_t *ang = p->angles + (size_t)plane * p->coarse_x * p->coarse_y;
    int32_t i, j;
    uint32_t it, bound = CT_WCET_CELL_ITERS(c->cx, c->cy);
    rt t = c->t0;   /* current point */
    rt tin = c->t0; /* canonical entry of the current cell */
    int tin_ok = 1;
    int64_t lb;      /* lower_ahead at (i, j), -1 when not formed */
    cexit e;
    i = c->i0;
    j = c->j0;
    /* bound: each iteration leaves at least one fine cell */
    for (it = 0u; it < bound; ++it) {
        uint32_t code;
        size_t k;
        if (!inside(c, i, j)) {
            h->iters = it;
            return CT_MISS;
        }
        h->steps++;
        k = coarse_index(p, i, j);
        code = ang[k];
        lb = -1;
        if (p->cot_ok[code]) {
            /* a bent ray: the apex less the lowering's bound ahead (the
             * cone of the lowered terrain; |a16| < 2^33) */
            int64_t a16 = zh(c, ct_ld16(p->apex + 2u * k));
            if (c->lw != NULL) {
                lb = lower_ahead(c, i, j);
                a16 -= lb;
            }
            /* T = floor(t 2^26), and a lower bound of z(t) from a Q26 point
             * (z at T for a rising ray, at T + 1 for a descending one unless
             * t is exactly T / 2^26): t.n 2^26 < 2^60. */
            int64_t T = t.d == T_ONE ? t.n : ct_floor_div(t.n * T_ONE, t.d);
            int64_t Tz = (t.d != T_ONE && r->dz < 0) ? T + 1 : T;
            int64_t num = r->oz + floor_shr(Tz * (int64_t)r->dz, CT_T_FRAC_BITS) - a16; /* < 2^34 */
            if (num > 0) {
                int64_t cot = p->cot_q16[code];
                int64_t len = cot >= 0 ? r->len_hi : r->len_lo;
                /* in Q16 z units: num 2^k < 2^34 (a lower bound of the
                 * height above the apex); len <= 2^26.5, |cot| <= 2^35:
                 * < 2^61.5, ceil by 2^16 (cot is Q16 LSB per cell), minus
                 * dz 2^k (<= 2^42).  den <= 0 iff the ray's rise per unit t
                 * reaches the cone's, as in prepared z units. */
                int64_t den = -floor_shr(-(len * cot), 16u) - c->dzf;
                int64_t dt, tn;
                if (den <= 0) {
                    /* the ray never leaves the empty region: no hit ahead */
                    h->iters = it + 1u;
                    return CT_MISS;
                }
                num = (int64_t)((uint64_t)num * c->zmul);
                dt = (num * T_ONE) / den; /* num*2^26 < 2^60 */
                if (dt > (INT64_C(1) << 35)) {
                    dt = INT64_C(1) << 35;
                }
                /* T + dt - 1 < 2^26 times the exact exit of the cone, so the
                 * ray on [t, tn] lies in the empty region.  The jump is taken
                 * when it leaves the fine cell (the point at tn lies in
                 * another cell, or on the exit face, which belongs to the
                 * next cell); otherwise the exact cell step below. */
                tn = T + dt - 1;
                if (tn > T) {
                    rt tj;
                    int32_t ni, nj;
                    tj.n = tn;
                    tj.d = T_ONE;
                    locate(c, tj, &ni, &nj);
                    if (ni != i || nj != j) {
#if CT_HAVE_PREFETCH
                        if (c->prefetch) {
                            /* a hint only: T2 = tn + dt < 2^36, times |d| <=
                             * 2^26; a cell off the tile is not asked for */
                            int64_t T2 = tn + dt;
                            int64_t px = floor_shr(r->ox + floor_shr(T2 * (int64_t)r->dx, CT_T_FRAC_BITS), 16u);
                            int64_t py = floor_shr(r->oy + floor_shr(T2 * (int64_t)r->dy, CT_T_FRAC_BITS), 16u);
                            if (px >= 0 && py >= 0 && px < c->cx && py < c->cy) {
                                size_t k2 = coarse_index(p, (int32_t)px, (int32_t)py);
                                CT_PREFETCH(ang + k2);
                                CT_PREFETCH(p->apex + 2u * k2);
                            }
                        }
#endif
                        if (!rt_lt(tj, c->tend)) {
                            h->iters = it + 1u;
                            return CT_MISS;
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
        if (cell_test(c, i, j, tin, &e, lb, h)) {
            h->iters = it + 1u;
            return hit_status(p, i, j);
        }
        if (!rt_lt(e.t, c->tend)) {
            h->iters = it + 1u;
            return CT_MISS;
        }
        next_cell(c, &e, &i, &j);
        t = e.t;
        tin = e.t;
        tin_ok = 1;
    }
    return CT_ERR_INTERNAL;
}

/* A seam start's cheap proof of f(t0) > 0, as the cone walk's first test
 * (the same apex formula as walk_cones', kept out of that loop: one shared
 * helper cost the walk 11 % more instructions per horizontal ray):
 * the ray at t0 (a lower bound of its z) above the apex of its cell's cone
 * in plane, the apex being at or above every post under it (for a bent
 * ray, less the lowering's bound ahead).  0: not shown (test the sign). */
static int above_apex(const ctx *c, uint32_t plane, int32_t i, int32_t j)
{
    const ct_package *p = c->p;
    const ct_prepared *r = c->r;
    size_t k = coarse_index(p, i, j);
    uint32_t code = p->angles[(size_t)plane * p->coarse_x * p->coarse_y + k];
    int64_t a16, T, Tz;
    if (!p->cot_ok[code]) {
        return 0;
    }
    a16 = zh(c, ct_ld16(p->apex + 2u * k));
    if (c->lw != NULL) {
        a16 -= lower_ahead(c, i, j);
    }
    /* as walk_cones: t.n 2^26 < 2^60, the sum < 2^34 */
    T = c->t0.d == T_ONE ? c->t0.n : ct_floor_div(c->t0.n * T_ONE, c->t0.d);
    Tz = (c->t0.d != T_ONE && r->dz < 0) ? T + 1 : T;
    return r->oz + floor_shr(Tz * (int64_t)r->dz, CT_T_FRAC_BITS) - a16 > 0;
}

/* ------------------------------------------------------------------------ */

/* The lowered surface (bent rays) at a Q16 point of cell (i, j), in Q16
 * LSB times 2^32, exact: posts G < 2^33 in Q16 LSB, a, b < 2^34, c < 2^35,
 * U, V in [0, 2^16]: G00 2^32 + (a U + b V) 2^16 + c U V < 2^68 (128-bit). */
CT_NOINLINE ct_i128 ct_surface_low_q48(const ct_package *p, const ct_lower *lw, int32_t i, int32_t j, int64_t x,
                                       int64_t y)
{
    posts4 q;
    int64_t U = x - (int64_t)i * ONE16, V = y - (int64_t)j * ONE16, x0 = (int64_t)i * ONE16,
            y0 = (int64_t)j * ONE16;
    int64_t g00, g10, g01, g11;
    load_posts(p, i, j, &q);
    g00 = (int64_t)q.h00 * ONE16 - ct_lower_at(lw, x0, y0);
    g10 = (int64_t)q.h10 * ONE16 - ct_lower_at(lw, x0 + ONE16, y0);
    g01 = (int64_t)q.h01 * ONE16 - ct_lower_at(lw, x0, y0 + ONE16);
    g11 = (int64_t)q.h11 * ONE16 - ct_lower_at(lw, x0 + ONE16, y0 + ONE16);
    return ct_i128_add(ct_i128_add(ct_i128_shl(ct_i128_from64(g00), 32),
                                   ct_i128_shl(ct_i128_add(ct_i128_mul(g10 - g00, U), ct_i128_mul(g01 - g00, V)), 16)),
                       ct_i128_mul((g11 - g10 - g01 + g00) * U, V));
}

ct_status ct_surface_height(const ct_package *p, int64_t x, int64_t y, int64_t *z)
{
    int32_t i, j;
    int64_t s;
    CT_ASSERT(p != NULL && z != NULL);
    if (p == NULL || z == NULL) {
        return CT_ERR_ARG;
    }
    if (x < 0 || y < 0 || x > (int64_t)p->cells_x * ONE16 || y > (int64_t)p->cells_y * ONE16) {
        return CT_ERR_RANGE;
    }
    i = axis_cell(x, ONE16, 0, (int32_t)p->cells_x);
    j = axis_cell(y, ONE16, 0, (int32_t)p->cells_y);
    s = surface_q32(p, i, j, x, y);
    *z = -ct_floor_div(-s, ONE16); /* ceil */
    return CT_OK;
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

/* The sign of f = z_ray - S at t0 > 0, a point on an entry face of cell
 * (i, j) (a tile set's seam): exact, as at a cell's exit. */
static int entry_sign(const ctx *c, int32_t i, int32_t j, rt t0)
{
    cexit e;
    posts4 q;
    int onx, ony;
    e.t = t0;
    e.xf = i + (c->sx < 0 ? 1 : 0);
    e.yf = j + (c->sy < 0 ? 1 : 0);
    /* on the x entry face: (xf 2^16 - ox) sx d == n |dx| (< 2^57 each) */
    onx = c->sx != 0 && ((int64_t)e.xf * ONE16 - c->r->ox) * c->sx * t0.d == t0.n * c->adx;
    ony = c->sy != 0 && ((int64_t)e.yf * ONE16 - c->r->oy) * c->sy * t0.d == t0.n * c->ady;
    e.face = onx ? (ony ? FACE_XY : FACE_X) : FACE_Y;
    load_posts(c->p, i, j, &q);
    if (c->lw != NULL) {
        lposts L;
        lower_posts(c, i, j, &q, &L);
        return exit_sign_low(c, i, j, &e, &L);
    }
    return exit_sign(c, i, j, &e, &q);
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
        if (entry_sign(c, i, j, c->t0) <= 0) {
            fill_hit(c, c->t0.d == T_ONE ? c->t0.n : ct_floor_div(c->t0.n * T_ONE, c->t0.d), i, j, h);
            h->steps = 1u;
            h->iters = 1u;
            *st = hit_status(p, i, j);
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
    fill_hit(c, tq, i, j, h);
    /* report the exact surface height at a vertical hit (for a bent
     * ray: the lowered surface's, plus the rise there) */
    h->z_q16 = -ct_floor_div(-s, ONE16) + (lw != NULL ? ct_lower_at(lw, h->x_q16, h->y_q16) : 0);
    (void)ct_grid_to_map(p, h->x_q16, h->y_q16, h->z_q16, &h->e_nm, &h->n_nm, &h->h_nm);
    return hit_status(p, i, j);
}

/* ws: where the walk starts (a tile set's tile); NULL: t = 0, located. */
static ct_status trace_impl(const ct_package *p, const ct_prepared *r, ct_method m, int checked,
                            const ct_lower *lw, const wstart *ws, ct_hit *h)
{
    ctx c;
    ct_status st;
    CT_ASSERT(p != NULL && r != NULL && h != NULL);
    if (p == NULL || r == NULL || h == NULL) {
        return CT_ERR_ARG;
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
        fill_hit(&c, 0, i, j, h);
        h->steps = 1u;
        h->iters = 1u;
        return hit_status(p, i, j);
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
    fill_hit(&c, t_q26, h->cell_x, h->cell_y, h);
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
