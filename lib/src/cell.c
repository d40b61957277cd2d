/*
 * cell.c -- the exact cell test shared by the four walks (trace.c): the sign
 * of f = z_ray - S at a cell's exit, the bilinear surface's quadratic along
 * the ray and its interior minimum, the root at a hit, and their versions
 * against a bent ray's lowered terrain; the hit's position and status; the
 * surface height.  Number formats and the exactness argument: trace.c's
 * header.
 */
#include "walk.h"

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

/* What make_quad and make_quad_low share: the primary axis p (x when |dx|
 * >= |dy|), the posts h00..h11 (LSB, or the lowered posts' units) put in
 * (p, q) order and mirrored along p when the ray runs towards -p (w = 1 -
 * the cell coordinate), so that w grows along the ray from the cell's entry
 * line L; Q->p, Q->d = |D_p|, Q->dps = s (L - o_p) (|L - o_p| < 2^31), the
 * bilinear coefficients a, b, cc in the (p, q) frame, g00, D_q, and
 * V0 = d (o_q - k_q 2^16) + dps D_q (2^26 2^31 + 2^31 2^26). */
typedef struct {
    int64_t a, b, cc, g00, Dq, V0;
} qframe;

static void quad_frame(const ctx *c, int32_t i, int32_t j, int64_t h00, int64_t h10, int64_t h01, int64_t h11,
                       quad *Q, qframe *F)
{
    int64_t op, oq, Dp, kq, L, g00, g10, g01, g11, s;
    int32_t kp;
    Q->p = (c->adx >= c->ady) ? 0 : 1;
    if (Q->p == 0) {
        op = c->r->ox;
        oq = c->r->oy;
        Dp = c->r->dx;
        F->Dq = c->r->dy;
        kp = i;
        kq = j;
        g10 = h10;
        g01 = h01;
    } else {
        op = c->r->oy;
        oq = c->r->ox;
        Dp = c->r->dy;
        F->Dq = c->r->dx;
        kp = j;
        kq = i;
        g10 = h01;
        g01 = h10;
    }
    g00 = h00;
    g11 = h11;
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
    F->a = g10 - g00;
    F->b = g01 - g00;
    F->cc = g11 - g10 - g01 + g00;
    F->g00 = g00;
    Q->d = ct_abs64(Dp);
    Q->dps = s * (L - op);
    F->V0 = Q->d * (oq - kq * ONE16) + Q->dps * F->Dq;
}

static void make_quad(const ctx *c, int32_t i, int32_t j, const posts4 *q, quad *Q)
{
    qframe F;
    int64_t Z0;
    quad_frame(c, i, j, q->h00, q->h10, q->h01, q->h11, Q, &F);
    /* Z0 = d * 2^16 * (z(L) - g00) with z(L) in LSB: the bracket is d times
     * z(L) - g00 in prepared z units (d*(o_z - g00*zone): 2^26 * 2^33;
     * s*(L - o_p)*D_z: 2^31 * 2^26), times 2^k it is d * (z_q16(L) -
     * g00 2^16) < 2^59 + 2^58 (the header's argument: L is the cell's
     * entry line, within one cell of tin). */
    Z0 = (int64_t)c->zmul * (Q->d * (c->r->oz - zh(c, (uint32_t)F.g00)) + Q->dps * (int64_t)c->r->dz);
    Q->C = Z0 - F.b * F.V0;
    Q->B = ONE16 * (c->dzf - F.a * Q->d - F.b * F.Dq) - F.cc * F.V0;
    Q->A = -F.cc * ONE16 * F.Dq;
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
        /* not for a decided hit on a builder's package (f(tin) > 0, f(exit)
         * <= 0); a package whose angle codes were edited (CRC re-stamped)
         * can let a cone walk pass terrain and decide a cell entered below
         * it (tests/fuzz/corpus/pkg-angle-edit-*) */
        D = ct_i128_from64(0);
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
        w = 0; /* f not decreasing: as for D < 0 above */
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

void ct_fill_hit(const ctx *c, int64_t tq, int32_t i, int32_t j, ct_hit *h)
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
    qframe F;
    int64_t Z0;
    quad *Q = &W->q;
    quad_frame(c, i, j, L->g00, L->g10, L->g01, L->g11, Q, &F);
    /* d z_q16(L) (< 2^59 + 2^58, the header's argument) - d g00 (< 2^59) */
    Z0 = (int64_t)c->zmul * (Q->d * c->r->oz + Q->dps * (int64_t)c->r->dz) - Q->d * F.g00;
    W->C = ct_i128_sub(ct_i128_shl(ct_i128_from64(Z0), 16), ct_i128_mul(F.b, F.V0));
    /* a d, b D_q < 2^60 each */
    W->B = ct_i128_sub(ct_i128_sub(ct_i128_shl(ct_i128_from64(c->dzf), 32),
                                   ct_i128_shl(ct_i128_from64(F.a * Q->d + F.b * F.Dq), 16)),
                       ct_i128_mul(F.cc, F.V0));
    W->A = ct_i128_neg(ct_i128_shl(ct_i128_mul(F.cc, F.Dq), 16)); /* cc D_q < 2^61 */
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
    ct_fill_hit(c, root_low(c, &W, tin, e->t), i, j, h);
    return 1;
}

/* The exact cell test on [tin, exit]; f(tin) > 0 is known by the caller.
 * lb: for a bent ray, lower_ahead(c, i, j) if the caller has it, else -1.
 * Returns 1 and fills *h on a hit. */
int ct_cell_test(const ctx *c, int32_t i, int32_t j, rt tin, const cexit *e, int64_t lb, ct_hit *h)
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
        ct_fill_hit(c, root_t_q26(c, &Q, tin, e->t), i, j, h);
        return 1;
    }
    {
        quad Q;
        make_quad(c, i, j, &q, &Q);
        ct_fill_hit(c, root_t_q26(c, &Q, tin, e->t), i, j, h);
    }
    return 1;
}

/* The sign of f = z_ray - S at t0 > 0, a point on an entry face of cell
 * (i, j) (a tile set's seam): exact, as at a cell's exit. */
int ct_entry_sign(const ctx *c, int32_t i, int32_t j, rt t0)
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
    if (p == NULL || z == NULL || p->base == NULL) {
        return CT_ERR_ARG; /* base NULL: a frame, which has no sections */
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
