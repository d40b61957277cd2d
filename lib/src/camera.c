/*
 * camera.c -- lens models (PINHOLE and OpenCV 4/5/8 in mrcal's
 * parameterisation), fixed-point unprojection and projection, and the pose.
 *
 * Model (OpenCV, as mrcal evaluates it), normalised coordinates x = X/Z,
 * y = Y/Z, r2 = x^2 + y^2:
 *   N = 1 + k1 r2 + k2 r2^2 + k3 r2^3,  D = 1 + k4 r2 + k5 r2^2 + k6 r2^3,
 *   R = N / D,
 *   x_d = x R + 2 p1 x y + p2 (r2 + 2 x^2),
 *   y_d = y R + p1 (r2 + 2 y^2) + 2 p2 x y,
 *   u = fx x_d + cx,  v = fy y_d + cy.
 * Jacobian, with R' = dR/dr2 = (N' - R D') / D:
 *   dx_d/dx = R + 2 x^2 R' + 2 p1 y + 6 p2 x
 *   dx_d/dy = dy_d/dx = 2 x y R' + 2 p1 x + 2 p2 y
 *   dy_d/dy = R + 2 y^2 R' + 6 p1 y + 2 p2 x
 *
 * Scaling and overflow (all values Q32 unless marked): |k| <= 2^58 (Q48),
 * |x|, |y| <= 2^35 (8), r2 <= 2^38 (64).  N and D stay below 2^60.2,
 * N' and D' below 2^55.7 (poly, dpoly).  Guards,
 * checked wherever the value is formed (a failed guard is "outside the
 * valid field"): D >= 2^-16, R in [2^-8, 2^8] (<= 2^40), |R'| <= 2^20
 * (<= 2^52).  Then x R < 2^43, p x y < 2^48, p (r2 + 2 x^2) < 2^49.6, so
 * x_d, y_d < 2^50.1; Jacobian entries < 2^59.1; the determinant (Q64) and
 * the Newton numerators (Jacobian x residual, Q64) are 128-bit, < 2^120.
 * Every product is rounded half up (ct_mul_shr); the code is exact integer
 * arithmetic, bit-identical on every target.
 */
#include "bend.h"
#include "fixed.h"

#define ONE32 (INT64_C(1) << 32)
#define CAM_READY 0x314d4143u  /* "CAM1" */
#define POSE_READY 0x31534f50u /* "POS1" */

#define PIX_MAX_Q32 ((int64_t)CT_CAM_MAX_PIXEL << 32)
#define XY_MAX (INT64_C(8) << 32)       /* |x|, |y| <= 8 (r2 <= 64)         */
#define XD_MAX (INT64_C(1) << 48)       /* |x_d|, |y_d| <= 2^16 at entry    */
#define R_MIN (ONE32 >> 8)
#define R_MAX (ONE32 << 8)
#define D_MIN (ONE32 >> 16)
#define RP_MAX (ONE32 << 20)
#define SLOPE_MIN (ONE32 >> 8)          /* d(r R)/dr along a radius         */
#define STEP_MAX (INT64_C(1) << 38)     /* Newton step <= 64 per component  */
#define STOP_Q32 2                      /* iterate until within 2 Q32 units */
#define SCAN_R_MAX (INT64_C(8) << 32)   /* scan radius r in [0, 8]          */
#define BISECT_STEPS 24u

typedef struct {
    int64_t xd, yd;             /* distort(x, y)                           */
    int64_t jxx, jxy, jyy;      /* Jacobian (symmetric off-diagonal)       */
} lens_eval;

static ct_status grid_unproject(const ct_camera *c, int64_t u, int64_t v, int32_t out[3], ct_unproject_memo *memo);

static int has_distortion(const ct_lens *l) { return l->model != CT_LENS_PINHOLE; }

/* -lim <= v <= lim without forming |v| (v may be INT64_MIN) */
static int within(int64_t v, int64_t lim) { return v >= -lim && v <= lim; }

/* round(v / 2^n), half up, |v| < 2^62 */
static int64_t rnd_shr(int64_t v, unsigned n) { return ct_floor_div(v + (INT64_C(1) << (n - 1u)), INT64_C(1) << n); }

/* 1 + c1 r2 + c2 r2^2 + c3 r2^3 (Q32) for c in Q48, |c| <= 2^58, r2 in
 * [0, 2^38] (Q32), by Horner with the partial sums in Q44, Q38, Q32: each
 * stays < 2^60.2 and each rounding error (<= 2^-45, 2^-39, 2^-33) is
 * multiplied by r2^2, r2, 1 afterwards: < 2^-32 in all (a coefficient's
 * own rounding, 2^-49 r2^3, is < 2^-31 at r2 = 64, < 2^-40 at r2 <= 8).   */
static int64_t poly(int64_t c1, int64_t c2, int64_t c3, int64_t r2)
{
    int64_t a1 = rnd_shr(c2, 4u) + ct_mul_shr(c3, r2, 36u);  /* Q44, c3 r2 < 2^96 */
    int64_t a2 = rnd_shr(c1, 10u) + ct_mul_shr(a1, r2, 38u); /* Q38, a1 r2 < 2^98.1 */
    return ONE32 + ct_mul_shr(a2, r2, 38u);                  /* Q32, < 2^60.2 */
}

/* its derivative c1 + 2 c2 r2 + 3 c3 r2^2 (Q32): partial sum in Q44
 * (< 2^61.7), the product with r2 < 2^99.7, the result < 2^55.7.          */
static int64_t dpoly(int64_t c1, int64_t c2, int64_t c3, int64_t r2)
{
    int64_t b1 = rnd_shr(2 * c2, 4u) + ct_mul_shr(3 * c3, r2, 36u);
    return rnd_shr(c1, 16u) + ct_mul_shr(b1, r2, 44u);
}

/* R = N/D and R' = dR/dr2 at r2 in [0, 2^38] (Q32).  0 where a guard fails. */
static int radial(const ct_lens *l, int64_t r2, int64_t *R, int64_t *Rp)
{
    const int64_t *k = l->dist_q48; /* k1 k2 p1 p2 k3 k4 k5 k6 */
    int64_t N, Np, D, Dp;
    ct_i128 num;
    if (!has_distortion(l)) {
        *R = ONE32;
        *Rp = 0;
        return 1;
    }
    N = poly(k[0], k[1], k[4], r2);
    Np = dpoly(k[0], k[1], k[4], r2);
    if (k[5] == 0 && k[6] == 0 && k[7] == 0) {
        /* no denominator: D = 2^32 and D' = 0 exactly, so the quotients
         * below are N and N' themselves (the same bits, no division) */
        if (ct_abs64(N) > R_MAX || N < R_MIN || ct_abs64(Np) > RP_MAX) {
            return 0;
        }
        *R = N;
        *Rp = Np;
        return 1;
    }
    D = poly(k[5], k[6], k[7], r2);
    Dp = dpoly(k[5], k[6], k[7], r2);
    if (D < D_MIN) {
        return 0;
    }
    /* R = N 2^32 / D: |N 2^32| < 2^92.2; D < 2^60.2 */
    if (!ct_i128_round_div_lim(ct_i128_shl(ct_i128_from64(N), 32u), D, R_MAX, R) || *R < R_MIN) {
        return 0;
    }
    /* R' = (N' 2^32 - R D') / D (Q64 / Q32): |N' 2^32| < 2^87.7,
     * |R D'| < 2^40 2^55.7 = 2^95.7 */
    num = ct_i128_sub(ct_i128_shl(ct_i128_from64(Np), 32u), ct_i128_mul(*R, Dp));
    return ct_i128_round_div_lim(num, D, RP_MAX, Rp);
}

/* distort(x, y) and its Jacobian.  0 outside the valid field. */
static int lens_forward(const ct_camera *c, int64_t x, int64_t y, lens_eval *ev)
{
    const ct_lens *l = &c->lens;
    int64_t x2, y2, xy, r2, R, Rp, p1, p2;
    if (ct_abs64(x) > XY_MAX || ct_abs64(y) > XY_MAX) {
        return 0;
    }
    x2 = ct_mul_shr(x, x, 32u); /* <= 2^38 */
    y2 = ct_mul_shr(y, y, 32u);
    xy = ct_mul_shr(x, y, 32u);
    r2 = x2 + y2;
    if (r2 > c->r2_max_q32 || !radial(l, r2, &R, &Rp)) {
        return 0;
    }
    p1 = l->dist_q48[2]; /* Q48 */
    p2 = l->dist_q48[3];
    /* p (r2 + 2 x^2) < 2^58 2^39.6: Q48 x Q32 >> 48 */
    ev->xd = ct_mul_shr(x, R, 32u) + 2 * ct_mul_shr(p1, xy, 48u) + ct_mul_shr(p2, r2 + 2 * x2, 48u);
    ev->yd = ct_mul_shr(y, R, 32u) + ct_mul_shr(p1, r2 + 2 * y2, 48u) + 2 * ct_mul_shr(p2, xy, 48u);
    /* 2 x^2 R' < 2^39 2^52 / 2^32 = 2^59 */
    ev->jxx = R + ct_mul_shr(2 * x2, Rp, 32u) + 2 * ct_mul_shr(p1, y, 48u) + 6 * ct_mul_shr(p2, x, 48u);
    ev->jxy = ct_mul_shr(2 * xy, Rp, 32u) + 2 * ct_mul_shr(p1, x, 48u) + 2 * ct_mul_shr(p2, y, 48u);
    ev->jyy = R + ct_mul_shr(2 * y2, Rp, 32u) + 6 * ct_mul_shr(p1, y, 48u) + 2 * ct_mul_shr(p2, x, 48u);
    return 1;
}

/* det of the Jacobian, Q64 (128-bit, < 2^119.2). */
static ct_i128 jac_det(const lens_eval *ev)
{
    return ct_i128_sub(ct_i128_mul(ev->jxx, ev->jyy), ct_i128_mul(ev->jxy, ev->jxy));
}

static int det_ok(const lens_eval *ev)
{
    /* det >= CT_UNPROJECT_MIN_DET (Q32) = MIN_DET * 2^32 in Q64 */
    return ct_i128_cmp(jac_det(ev), ct_i128_shl(ct_i128_from64(CT_UNPROJECT_MIN_DET), 32u)) >= 0;
}

/* Newton step J^-1 e (Q32), shortened (direction kept) to <= STEP_MAX per
 * component.  0 if det < CT_UNPROJECT_MIN_DET (folded or singular). */
static int newton_step(const lens_eval *ev, int64_t ex, int64_t ey, int64_t *dx, int64_t *dy)
{
    ct_i128 det = jac_det(ev), nx, ny;
    unsigned b, h;
    int64_t ds;
    if (!det_ok(ev)) {
        return 0;
    }
    /* |J| < 2^59.1, |e| < 2^50.2: numerators < 2^110.3 */
    nx = ct_i128_sub(ct_i128_mul(ev->jyy, ex), ct_i128_mul(ev->jxy, ey));
    ny = ct_i128_sub(ct_i128_mul(ev->jxx, ey), ct_i128_mul(ev->jxy, ex));
    /* bring det below 2^61 (relative precision of the step >= 2^-60 unless
     * det < 2^61 already, >= 2^48 by det_ok): shift all three alike */
    b = ct_i128_bits(det);
    if (b > 61u) {
        det = ct_i128_sar(det, b - 61u);
        nx = ct_i128_sar(nx, b - 61u);
        ny = ct_i128_sar(ny, b - 61u);
    }
    ds = ct_i128_to64(det);
    /* shorten: |n| <= 2^6 det  <=>  |step| <= 64.  bound: |n| < 2^111,
     * det >= 2^48: at most 58 halvings */
    for (h = 0u; h < 64u; ++h) {
        ct_i128 lim = ct_i128_shl(ct_i128_from64(ds), 6u);
        if (ct_i128_cmp(ct_i128_abs(nx), lim) <= 0 && ct_i128_cmp(ct_i128_abs(ny), lim) <= 0) {
            break;
        }
        nx = ct_i128_sar(nx, 1u);
        ny = ct_i128_sar(ny, 1u);
    }
    /* step = n 2^32 / det: |n 2^32| <= 2^99 */
    return ct_i128_round_div_lim(ct_i128_shl(nx, 32u), ds, STEP_MAX, dx) &&
           ct_i128_round_div_lim(ct_i128_shl(ny, 32u), ds, STEP_MAX, dy);
}

static int64_t max_abs2(int64_t a, int64_t b) { return ct_max64(ct_abs64(a), ct_abs64(b)); }

/* Solve distort(x, y) = (xt, yt).  CT_OK or CT_ERR_UNPROJECT. */
static ct_status undistort(const ct_camera *c, int64_t xt, int64_t yt, int64_t *xo, int64_t *yo,
                           uint32_t *iters)
{
    lens_eval ev;
    int64_t x = xt, y = yt, ex, ey, en;
    uint32_t it, h;
    int ok = 0;
    *iters = 0u;
    /* start at (x_d, y_d), halved into the valid field.  bound: |x_d| <=
     * 2^48, and (0, 0) is always valid: at most 49 halvings */
    for (h = 0u; h < 64u; ++h) {
        if (lens_forward(c, x, y, &ev)) {
            ok = 1;
            break;
        }
        x /= 2;
        y /= 2;
    }
    if (!ok) {
        return CT_ERR_UNPROJECT;
    }
    ex = xt - ev.xd; /* |xt| <= 2^48, |xd| < 2^50.1 */
    ey = yt - ev.yd;
    en = max_abs2(ex, ey);
    /* bound: CT_UNPROJECT_MAX_ITERS Newton steps */
    for (it = 0u; it < CT_UNPROJECT_MAX_ITERS && en > STOP_Q32; ++it) {
        int64_t dx, dy;
        int accepted = 0;
        if (!newton_step(&ev, ex, ey, &dx, &dy)) {
            break;
        }
        /* backtracking: accept the first step (halving it each time) that
         * reduces the residual.  bound: CT_UNPROJECT_MAX_HALVINGS */
        for (h = 0u; h < CT_UNPROJECT_MAX_HALVINGS && (dx != 0 || dy != 0); ++h) {
            lens_eval e2;
            if (lens_forward(c, x + dx, y + dy, &e2)) {
                int64_t nx = xt - e2.xd, ny = yt - e2.yd, nn = max_abs2(nx, ny);
                if (nn < en) {
                    x += dx;
                    y += dy;
                    ev = e2;
                    ex = nx;
                    ey = ny;
                    en = nn;
                    accepted = 1;
                    break;
                }
            }
            dx /= 2;
            dy /= 2;
        }
        if (!accepted) {
            break; /* stalled: at the noise floor, or no descent */
        }
        *iters = it + 1u;
    }
    if (en > CT_UNPROJECT_TOL_Q32 || !det_ok(&ev)) {
        return CT_ERR_UNPROJECT;
    }
    *xo = x;
    *yo = y;
    return CT_OK;
}

/* Unit vector (x, y, 1) / |(x, y, 1)| in Q30, |x|, |y| <= 2^35 (Q32). */
static void unit_ray(int64_t x, int64_t y, int32_t out[3])
{
    ct_i128 l2 = ct_i128_add(ct_i128_mul(x, x), ct_i128_mul(y, y)); /* < 2^71 */
    int64_t L, q = 0;
    l2.hi += 1u;                                 /* + 1.0 in Q64       */
    L = (int64_t)ct_i128_isqrt(l2);              /* Q32, [2^32, 2^36)  */
    /* |x 2^30| < 2^65; quotients <= 2^30 */
    (void)ct_i128_round_div_lim(ct_i128_shl(ct_i128_from64(x), 30u), L, INT64_C(1) << 30, &q);
    out[0] = (int32_t)q;
    (void)ct_i128_round_div_lim(ct_i128_shl(ct_i128_from64(y), 30u), L, INT64_C(1) << 30, &q);
    out[1] = (int32_t)q;
    (void)ct_i128_round_div_lim(ct_i128_shl(ct_i128_from64(1), 62u), L, INT64_C(1) << 30, &q);
    out[2] = (int32_t)q;
}

/* Slope of the distorted radius r R(r^2) along a radius: R + 2 r2 R'. */
static int radial_ok(const ct_lens *l, int64_t r)
{
    int64_t r2 = ct_mul_shr(r, r, 32u), R, Rp;
    if (!radial(l, r2, &R, &Rp)) {
        return 0;
    }
    /* 2 r2 R' < 2^59 */
    return R + 2 * ct_mul_shr(r2, Rp, 32u) >= SLOPE_MIN;
}

static ct_status lens_check(const ct_lens *l)
{
    uint32_t k, used;
    if (l->model >= (uint32_t)CT_LENS_COUNT) {
        return CT_ERR_LENS;
    }
    if (l->fx_q32 < ONE32 || l->fy_q32 < ONE32 || l->fx_q32 > PIX_MAX_Q32 || l->fy_q32 > PIX_MAX_Q32 ||
        !within(l->cx_q32, PIX_MAX_Q32) || !within(l->cy_q32, PIX_MAX_Q32)) {
        return CT_ERR_LENS;
    }
    used = l->model == CT_LENS_PINHOLE ? 0u : (l->model == CT_LENS_OPENCV4 ? 4u : (l->model == CT_LENS_OPENCV5 ? 5u : 8u));
    /* bound: 8 coefficients */
    for (k = 0u; k < 8u; ++k) {
        if (!within(l->dist_q48[k], CT_CAM_MAX_DIST) || (k >= used && l->dist_q48[k] != 0)) {
            return CT_ERR_LENS;
        }
    }
    return CT_OK;
}

ct_status ct_camera_init(ct_camera *cam, const ct_lens *lens)
{
    ct_status st;
    uint32_t k;
    int64_t good = 0, bad = -1;
    CT_ASSERT(cam != NULL && lens != NULL);
    if (cam == NULL || lens == NULL) {
        return CT_ERR_ARG;
    }
    cam->ready = 0u;
    cam->grid_smooth = 0u; /* no grid */
    st = lens_check(lens);
    if (st != CT_OK) {
        return st;
    }
    cam->lens = *lens;
    /* The valid field: the first radius r in (0, 8] where the radial guards
     * or the slope of r R fail; scanned in CT_CAM_SCAN_STEPS steps of 8/256
     * and refined by bisection to 2^-21.  bound: CT_CAM_SCAN_STEPS */
    for (k = 1u; k <= CT_CAM_SCAN_STEPS; ++k) {
        int64_t r = SCAN_R_MAX / CT_CAM_SCAN_STEPS * (int64_t)k;
        if (!radial_ok(lens, r)) {
            bad = r;
            break;
        }
        good = r;
    }
    if (bad > 0) {
        /* bound: BISECT_STEPS halvings of a 2^27 (Q32) interval */
        for (k = 0u; k < BISECT_STEPS && bad - good > 1; ++k) {
            int64_t mid = good + (bad - good) / 2;
            if (radial_ok(lens, mid)) {
                good = mid;
            } else {
                bad = mid;
            }
        }
    }
    if (good <= 0) {
        return CT_ERR_LENS; /* no valid field */
    }
    cam->r2_max_q32 = ct_min64(ct_mul_shr(good, good, 32u), (int64_t)CT_CAM_MAX_R2 << 32);
    cam->ready = CAM_READY;
    return CT_OK;
}

ct_status ct_camera_unproject(const ct_camera *cam, int64_t u, int64_t v, int32_t ray[3], uint32_t *iters)
{
    return ct_camera_unproject_memo(cam, u, v, ray, iters, NULL);
}

/* Declared in bend.h (geoloc.c's batches pass a memo). */
ct_status ct_camera_unproject_memo(const ct_camera *cam, int64_t u, int64_t v, int32_t ray[3], uint32_t *iters,
                                   ct_unproject_memo *memo)
{
    const ct_lens *l;
    int64_t xt = 0, yt = 0, x, y;
    uint32_t it = 0u;
    ct_status st;
    CT_ASSERT(cam != NULL && ray != NULL);
    if (iters != NULL) {
        *iters = 0u;
    }
    if (cam == NULL || ray == NULL || cam->ready != CAM_READY) {
        return CT_ERR_ARG;
    }
    l = &cam->lens;
    if (!within(u, (int64_t)CT_CAM_MAX_PIXEL << 16) || !within(v, (int64_t)CT_CAM_MAX_PIXEL << 16)) {
        return CT_ERR_UNPROJECT;
    }
    if (l->model == CT_LENS_GRID) {
        return grid_unproject(cam, u, v, ray, memo);
    }
    /* x_d = (u 2^16 - cx) 2^32 / fx (all Q32): |u 2^16 - cx| <= 2^53, so
     * the numerator < 2^85; fx <= 2^52 */
    if (!ct_i128_round_div_lim(ct_i128_shl(ct_i128_from64(u * 65536 - l->cx_q32), 32u), l->fx_q32, XD_MAX, &xt) ||
        !ct_i128_round_div_lim(ct_i128_shl(ct_i128_from64(v * 65536 - l->cy_q32), 32u), l->fy_q32, XD_MAX, &yt)) {
        return CT_ERR_UNPROJECT;
    }
    if (!has_distortion(l)) {
        lens_eval ev;
        if (!lens_forward(cam, xt, yt, &ev)) {
            return CT_ERR_UNPROJECT; /* beyond 82.9 deg off axis */
        }
        x = xt;
        y = yt;
    } else {
        st = undistort(cam, xt, yt, &x, &y, &it);
        if (iters != NULL) {
            *iters = it;
        }
        if (st != CT_OK) {
            return st;
        }
    }
    unit_ray(x, y, ray);
    return CT_OK;
}

ct_status ct_camera_project(const ct_camera *cam, const int32_t ray[3], int64_t *u, int64_t *v)
{
    const ct_lens *l;
    int64_t x = 0, y = 0;
    lens_eval ev;
    CT_ASSERT(cam != NULL && ray != NULL && u != NULL && v != NULL);
    if (cam == NULL || ray == NULL || u == NULL || v == NULL || cam->ready != CAM_READY) {
        return CT_ERR_ARG;
    }
    l = &cam->lens;
    if (l->model == CT_LENS_GRID) {
        return CT_ERR_LENS;
    }
    if (ray[2] <= 0) {
        return CT_ERR_UNPROJECT; /* behind the camera (or at 90 deg) */
    }
    /* x = X 2^32 / Z, |x| <= 8: |X 2^32| < 2^63 */
    if (!ct_i128_round_div_lim(ct_i128_shl(ct_i128_from64(ray[0]), 32u), ray[2], XY_MAX, &x) ||
        !ct_i128_round_div_lim(ct_i128_shl(ct_i128_from64(ray[1]), 32u), ray[2], XY_MAX, &y) ||
        !lens_forward(cam, x, y, &ev)) {
        return CT_ERR_UNPROJECT;
    }
    /* u = (fx x_d + cx) in Q16: fx x_d < 2^52 2^50.1 = 2^102.1 (Q64),
     * cx 2^32 < 2^84 (Q64); the sum / 2^48 < 2^54.1 */
    *u = ct_i128_round_shr(ct_i128_add(ct_i128_mul(l->fx_q32, ev.xd), ct_i128_shl(ct_i128_from64(l->cx_q32), 32u)),
                           48u);
    *v = ct_i128_round_shr(ct_i128_add(ct_i128_mul(l->fy_q32, ev.yd), ct_i128_shl(ct_i128_from64(l->cy_q32), 32u)),
                           48u);
    return CT_OK;
}

/* ------------------------------------------------------------------------ */
/* Unprojection grid.                                                        */

#define GRID_T_BITS 20u
#define GRID_STEP_MAX (INT64_C(4096) << 16)

/* cos 5 deg in Q60, rounded up */
#define GRID_COS5_Q60 INT64_C(1148534290205298930)

/* 1 when every node is a ray and each lies within 5 deg of its right and
 * lower neighbours (Q60 dot products of nodes of length 1 +- 2^-20, each
 * < 2^60.0001: |dot| < 2^61.1 in 64 bits; such a dot >= cos 5 deg means
 * an angle below 5.001 deg).  Then grid_unproject's per-pixel checks
 * cannot fail, and it skips them: the 4 x 4 nodes around a pixel are
 * within 4 hops, so within alpha = 20.004 deg of its node (i, j), c.  The
 * Catmull-Rom weights of one axis sum to 1 with negative ones of at most
 * t (1 - t) / 2 <= 1/8 in all; the 16 products w_a w_b sum to 1 with
 * S = sum |w| <= (1 + 1/4)^2 = 1.5625, so their positive part P <= 1.2813
 * and negative part N <= 0.2813.  V = sum w r has V.c >= P cos alpha - N
 * >= 0.9225 (a unit r has r.c in [cos alpha, 1]) and a part across c of at
 * most S sin alpha <= 0.5346, so V is within atan(0.5346 / 0.9225) = 30.1
 * deg of c and 50.1 deg of each node: the 60 deg check holds with 9 deg to
 * spare (the rounding of weights, rows and the result is below 2^-28 rad),
 * and |V| > 0.92, far from the half unit the length check asks.
 * bound: nu nv nodes. */
static uint32_t grid_is_smooth(const ct_unproject_grid *g)
{
    uint32_t i, j;
    for (j = 0u; j < g->nv; ++j) {
        for (i = 0u; i < g->nu; ++i) {
            /* node k = j nu + i < nu nv <= 2^28, its neighbours' indices
             * formed only where they exist */
            const int32_t *r = g->rays_q30 + 3u * (j * g->nu + i);
            if (r[0] == 0 && r[1] == 0 && r[2] == 0) {
                return 0u;
            }
            if (i + 1u < g->nu) {
                const int32_t *e = g->rays_q30 + 3u * (j * g->nu + i + 1u);
                if ((int64_t)r[0] * e[0] + (int64_t)r[1] * e[1] + (int64_t)r[2] * e[2] < GRID_COS5_Q60) {
                    return 0u;
                }
            }
            if (j + 1u < g->nv) {
                const int32_t *s = g->rays_q30 + 3u * ((j + 1u) * g->nu + i);
                if ((int64_t)r[0] * s[0] + (int64_t)r[1] * s[1] + (int64_t)r[2] * s[2] < GRID_COS5_Q60) {
                    return 0u;
                }
            }
        }
    }
    return 1u;
}

ct_status ct_camera_init_grid(ct_camera *cam, const ct_unproject_grid *g)
{
    uint32_t k, n;
    const int32_t lim = (INT32_C(1) << 30) + (INT32_C(1) << 12);
    CT_ASSERT(cam != NULL && g != NULL);
    if (cam == NULL || g == NULL) {
        return CT_ERR_ARG;
    }
    cam->ready = 0u;
    if (g->rays_q30 == NULL || g->nu < 4u || g->nv < 4u || g->nu > CT_GRID_MAX_NODES ||
        g->nv > CT_GRID_MAX_NODES || g->step_q16 < 65536 || g->step_q16 > GRID_STEP_MAX ||
        !within(g->u0_q16, (int64_t)CT_CAM_MAX_PIXEL << 16) || !within(g->v0_q16, (int64_t)CT_CAM_MAX_PIXEL << 16)) {
        return CT_ERR_LENS;
    }
    n = g->nu * g->nv; /* <= 2^28: 3 n < 2^30 fits size_t and uint32 */
    if (g->rays_len / 3u < (size_t)n) {
        return CT_ERR_LENS;
    }
    /* every node a unit vector within 2^-20, or (0, 0, 0).  bound: nu nv */
    for (k = 0u; k < n; ++k) {
        const int32_t *r = g->rays_q30 + 3u * k;
        int64_t l2;
        if (r[0] == 0 && r[1] == 0 && r[2] == 0) {
            continue;
        }
        if (r[0] > lim || r[0] < -lim || r[1] > lim || r[1] < -lim || r[2] > lim || r[2] < -lim) {
            return CT_ERR_LENS;
        }
        /* each square <= 2^60.0001: the sum < 2^62 */
        l2 = (int64_t)r[0] * r[0] + (int64_t)r[1] * r[1] + (int64_t)r[2] * r[2];
        if (ct_abs64(l2 - (INT64_C(1) << 60)) > (INT64_C(1) << 41)) {
            return CT_ERR_LENS;
        }
    }
    cam->grid_smooth = grid_is_smooth(g);
    cam->lens.model = CT_LENS_GRID;
    cam->lens.width = cam->lens.height = 0u;
    cam->lens.fx_q32 = cam->lens.fy_q32 = cam->lens.cx_q32 = cam->lens.cy_q32 = 0;
    /* bound: 8 coefficients */
    for (k = 0u; k < 8u; ++k) {
        cam->lens.dist_q48[k] = 0;
    }
    cam->r2_max_q32 = 0;
    cam->grid = *g;
    cam->ready = CAM_READY;
    return CT_OK;
}

/* Catmull-Rom weights, doubled, for t in [0, 1) given in Q20: Q30.  The
 * polynomials are formed in Q60 (each term < 5 * 2^60 < 2^63) and rounded to
 * Q30: the weights sum to 2^31 (within 2 LSB) and sum |w| < 2.6 * 2^30. */
static void cr_weights(int64_t t, int64_t w[4])
{
    int64_t t2 = t * t << GRID_T_BITS; /* t^2, Q60 */
    int64_t t3 = t * t * t;            /* t^3, Q60 */
    int64_t t1 = t << 40;              /* t, Q60   */
    const int64_t half = INT64_C(1) << 29;
    w[0] = ct_floor_shr(-t3 + 2 * t2 - t1 + half, 30u);
    w[1] = ct_floor_shr(3 * t3 - 5 * t2 + (INT64_C(2) << 60) + half, 30u);
    w[2] = ct_floor_shr(-3 * t3 + 4 * t2 + t1 + half, 30u);
    w[3] = ct_floor_shr(t3 - t2 + half, 30u);
}

/* Node index and fraction (Q20) along one axis: the pixel lies in
 * [node i, node i + 1) with 1 <= i <= n - 3 (so i - 1 .. i + 2 exist). */
static int grid_axis(int64_t p, int64_t p0, int64_t step, uint32_t n, uint32_t *i, int64_t *t)
{
    int64_t d = p - p0, k, rem; /* |p - p0| <= 2^37 */
    k = ct_floor_div(d, step);
    if (k < 1 || k > (int64_t)n - 3) {
        return 0;
    }
    rem = d - k * step;                            /* [0, step), step <= 2^28 */
    *t = ct_floor_div(rem << GRID_T_BITS, step);   /* < 2^20 */
    *i = (uint32_t)k;
    return 1;
}

/* Bicubic (Catmull-Rom) interpolation of the 4 x 4 nodes around the pixel,
 * then normalised; all in 64 bits.  Scaling and overflow: nodes |r| <=
 * 2^30 + 2^12 (checked at init), weights Q30 with sum |w| < 2.6 * 2^30, so
 * a column's sum sum_b w_b r_b < 2.6 * 2^60.01 < 2^62 (Q60, doubled),
 * rounded to Q30 (< 2^31.4); the row's sum sum_a w_a col_a < 2.6 * 2^31.4 *
 * 2^30 < 2^62.8 (Q60, four times the interpolated vector: coherent unit
 * rays give |V| ~ 2^62).  V >> 32 (rounded) leaves |V'_k| < 2^30.8 and
 * |V'|^2 < 3 * 2^61.6 < 2^64 (unsigned).  |V'| shorter than 2^29 means the
 * 16 rays disagree.  The unit result is |V'_k| f / 2^32 with f = floor(2^62
 * / L), L = |V'| rounded, >= 2^29: f <= 2^33, products < 2^63.8
 * (unsigned).  The columns (along v) depend on v and i only: with a memo
 * for this row and node column they are taken from it. */
static ct_status grid_unproject(const ct_camera *c, int64_t u, int64_t v, int32_t out[3], ct_unproject_memo *memo)
{
    const ct_unproject_grid *g = &c->grid;
    uint32_t i, j, a, b, k;
    int64_t tu, tv, wu[4], V[3];
    int64_t own[4][3];
    int64_t (*col)[3] = memo != NULL ? memo->col : own;
    uint64_t l2 = 0u, L, f;
    if (!grid_axis(u, g->u0_q16, g->step_q16, g->nu, &i, &tu) ||
        !grid_axis(v, g->v0_q16, g->step_q16, g->nv, &j, &tv)) {
        return CT_ERR_UNPROJECT;
    }
    cr_weights(tu, wu);
    if (memo == NULL || memo->valid == 0u || memo->v != v || memo->i != i) {
        const size_t stride = 3u * (size_t)g->nu; /* one node row */
        int64_t wv[4];
        cr_weights(tv, wv);
        /* along v for columns i-1 .. i+2 (nodes j-1 .. j+2 of each).
         * bound: 4 x 4 x 3 */
        for (a = 0u; a < 4u; ++a) {
            const int32_t *top = g->rays_q30 + 3u * ((j - 1u) * g->nu + (i - 1u + a));
            int64_t acc[3] = {0, 0, 0};
            for (b = 0u; b < 4u; ++b) {
                const int32_t *r = top + b * stride;
                acc[0] += wv[b] * r[0];
                acc[1] += wv[b] * r[1];
                acc[2] += wv[b] * r[2];
            }
            for (k = 0u; k < 3u; ++k) {
                col[a][k] = ct_floor_shr(acc[k] + (INT64_C(1) << 29), 30u);
            }
        }
        if (memo != NULL) {
            memo->v = v;
            memo->i = i;
            memo->valid = 1u;
        }
    }
    /* along u, then V' = V / 2^32 rounded.  bound: 3 x 4 */
    for (k = 0u; k < 3u; ++k) {
        int64_t acc = 0;
        for (a = 0u; a < 4u; ++a) {
            acc += wu[a] * col[a][k];
        }
        V[k] = ct_floor_shr(acc + (INT64_C(1) << 31), 32u);
        l2 += (uint64_t)(V[k] * V[k]);
    }
    L = ct_isqrt64(l2);
    if (L < (UINT64_C(1) << 29)) {
        return CT_ERR_UNPROJECT;
    }
    /* L rounded to the nearest (|V'| >= L + 1/2 <=> l2 - L^2 > L): with
     * the floor, |V'| / L reached 1 + 2^-29 and the rounded components
     * |ray| = 1 + 2^-28.6 beyond the ray_cam format's 2^-29 (found by
     * fuzzing, corpus grid-unit-length); rounded, 1 +- 2^-30 and the
     * components' rounding keep it within 2^-29.  l2 - L^2 <= 2 L < 2^33 */
    if (l2 - L * L > L) {
        L += 1u;
    }
    f = (UINT64_C(1) << 62) / L;
    /* bound: 3 components.  |V'_k| is an integer <= |V'|, so <= L, and
     * L f <= 2^62: the quotient is at most 2^30 */
    for (k = 0u; k < 3u; ++k) {
        int32_t m = (int32_t)(((uint64_t)ct_abs64(V[k]) * f + (UINT64_C(1) << 31)) >> 32);
        out[k] = V[k] < 0 ? -m : m;
    }
    /* the result must lie within 60 deg of each of its 16 nodes (cos >=
     * 1/2: dot >= 2^59 in Q60; products < 2^61, sums < 2^63), which also
     * refuses a node without a ray (dot 0); on a smooth grid it does
     * (grid_is_smooth).  bound: 4 x 4 nodes */
    if (!c->grid_smooth) {
        for (b = 0u; b < 4u; ++b) {
            for (a = 0u; a < 4u; ++a) {
                const int32_t *r = g->rays_q30 + 3u * ((j + b - 1u) * g->nu + (i - 1u + a));
                int64_t dot = (int64_t)r[0] * out[0] + (int64_t)r[1] * out[1] + (int64_t)r[2] * out[2];
                if (dot < (INT64_C(1) << 59)) {
                    return CT_ERR_UNPROJECT;
                }
            }
        }
    }
    return CT_OK;
}

/* ------------------------------------------------------------------------ */
/* Pose.                                                                     */

ct_status ct_pose_init(ct_pose *pose, const int32_t R[9], int64_t e, int64_t n, int64_t h)
{
    uint32_t i, j, k;
    ct_i128 det;
    CT_ASSERT(pose != NULL && R != NULL);
    if (pose == NULL || R == NULL) {
        return CT_ERR_ARG;
    }
    pose->ready = 0u;
    /* R^T R = I within 2^-20: entries |R| < 2^31, products < 2^62 each;
     * the check on the diagonal first bounds |R| <= 2^30 (1 + 2^-21), so
     * sums of three stay < 2^62.  bound: 3 x 3 x 3 */
    for (i = 0u; i < 3u; ++i) {
        for (j = i; j < 3u; ++j) {
            int64_t s = 0, want = i == j ? (INT64_C(1) << 60) : 0;
            for (k = 0u; k < 3u; ++k) {
                int64_t a = R[3u * k + i], b = R[3u * k + j];
                if (ct_abs64(a) > (INT64_C(1) << 30) + (INT64_C(1) << 12) ||
                    ct_abs64(b) > (INT64_C(1) << 30) + (INT64_C(1) << 12)) {
                    return CT_ERR_POSE;
                }
                s += a * b;
            }
            if (ct_abs64(s - want) > (INT64_C(1) << 40)) {
                return CT_ERR_POSE;
            }
        }
    }
    /* det by cofactors: minors < 2^61.1 (int64), times an entry: 128-bit */
    det = ct_i128_mul(R[0], (int64_t)R[4] * R[8] - (int64_t)R[5] * R[7]);
    det = ct_i128_sub(det, ct_i128_mul(R[1], (int64_t)R[3] * R[8] - (int64_t)R[5] * R[6]));
    det = ct_i128_add(det, ct_i128_mul(R[2], (int64_t)R[3] * R[7] - (int64_t)R[4] * R[6]));
    if (ct_i128_sign(det) <= 0) {
        return CT_ERR_POSE;
    }
    if (!within(e, INT64_C(1) << 61) || !within(n, INT64_C(1) << 61) || !within(h, INT64_C(1) << 61)) {
        return CT_ERR_POSE;
    }
    /* bound: 9 entries */
    for (k = 0u; k < 9u; ++k) {
        pose->R_map_cam_q30[k] = R[k];
    }
    pose->e_nm = e;
    pose->n_nm = n;
    pose->h_nm = h;
    pose->hscale_q30 = (int32_t)1 << 30;
    pose->ready = POSE_READY;
    return CT_OK;
}

void ct_pose_rotate_grid(const ct_pose *pose, const int32_t ray[3], int64_t out[3])
{
    uint32_t i;
    /* bound: 3 rows.  |R| <= 2^30 + 2^12 (ct_pose_init), |ray| < 2^31:
     * each product < 2^61.1, the sum of three < 2^62.7; Q60 -> Q39 */
    for (i = 0u; i < 3u; ++i) {
        const int32_t *row = pose->R_map_cam_q30 + 3u * i;
        int64_t s = (int64_t)row[0] * ray[0] + (int64_t)row[1] * ray[1] + (int64_t)row[2] * ray[2];
        out[i] = ct_floor_div(s + (INT64_C(1) << 20), INT64_C(1) << 21);
    }
}

ct_status ct_pose_rotate(const ct_pose *pose, const int32_t ray[3], int64_t out[3])
{
    uint32_t i;
    CT_ASSERT(pose != NULL && ray != NULL && out != NULL);
    if (pose == NULL || ray == NULL || out == NULL || pose->ready != POSE_READY) {
        return CT_ERR_ARG;
    }
    ct_pose_rotate_grid(pose, ray, out);
    if (pose->hscale_q30 != ((int32_t)1 << 30)) {
        /* a geodetic pose: horizontal map metres per ground metre (|out| <=
         * 2^39.1, hscale in [2^29, 2^31): products < 2^70.1, 128-bit; the
         * results stay < 2^40) */
        for (i = 0u; i < 2u; ++i) {
            ct_i128 m = ct_i128_add(ct_i128_mul(out[i], pose->hscale_q30), ct_i128_from64(INT64_C(1) << 29));
            out[i] = ct_i128_floor_div(m, INT64_C(1) << 30);
        }
    }
    return CT_OK;
}
