/*
 * geodesy.c -- WGS84 geodetic <-> UTM (transverse Mercator) and <->
 * Earth-fixed Cartesian (ECEF) in integers; geodetic poses; the geoid grid;
 * the camera's local frame for the true-Earth walk (earth.c).
 *
 * Krueger's series to order n^6 as in Karney (2011), "Transverse Mercator
 * with an accuracy of a few nanometers": the conformal latitude from
 * tau = tan(phi) by tau' = tau sqrt(1 + sigma^2) - sigma sqrt(1 + tau^2),
 * sigma = sinh(e atanh(e sin(phi))); the spherical transverse Mercator
 * xi' = atan2(tau', cos(lam)), eta' = asinh(sin(lam) / sqrt(tau'^2 +
 * cos^2(lam))); then zeta = zeta' + sum alpha_j sin(2 j zeta') (complex,
 * summed by Clenshaw's recurrence); E = 500 km + k0 A eta, N = FN + k0 A xi.
 * The inverse reverses each step (the beta series; tau from tau' by
 * Newton's method).  The series' own error is a few nm within the zone.
 *
 * Number format: every internal quantity is Q59 (value * 2^59 in int64,
 * |value| < 16, resolution 1.7e-18); products and quotients go through
 * 128 bits and are rounded to nearest.  Angles are radians.  Bounds that
 * keep values below 16: |lat| <= 84.5 deg (tan < 9.7, 1 / cos < 9.8),
 * |lon - lon0| <= CT_UTM_MAX_DLON_DEG = 9 deg (sinh(eta') < 0.16), so
 * every series below converges geometrically with ratio <= 0.04 (term
 * counts chosen for < 2^-60).  Public angles are Q61 radians (|.| <= pi <
 * 2^1.7), map coordinates integer nm.
 */
#include "conetrace.h"
#include "fixed.h"
#include "geodesy_tables.h"
#include "bend.h"

#define QB 59u
#define ONE (INT64_C(1) << QB)
#define HALF_NM_Q8 INT64_C(128)

/* a * b in Q59, rounded: |a b| < 2^63 * 2^59 */
static int64_t qmul(int64_t a, int64_t b)
{
    return ct_i128_round_shr(ct_i128_mul(a, b), QB);
}

/* a / b in Q59 (b != 0, |a / b| < 16), floored: a 2^59 < 2^126 */
static int64_t qdiv(int64_t a, int64_t b)
{
    ct_i128 n = ct_i128_shl(ct_i128_from64(a), QB);
    if (b < 0) {
        n = ct_i128_neg(n);
        b = -b;
    }
    return ct_i128_floor_div(n, b);
}

/* sqrt(1 - a) in Q59 for 0 <= a <= 1 */
static int64_t qsqrt_one_minus(int64_t a)
{
    return (int64_t)ct_i128_isqrt(ct_i128_shl(ct_i128_from64(ONE - a), QB));
}

/* sqrt(a^2 + b^2) in Q59 for |a|, |b| < 16 (the sum of squares < 2^127 is
 * formed in 128 bits; ct_i128_isqrt needs < 2^126: |a|, |b| < 11.3, which
 * the callers' bounds give) */
static int64_t qhypot(int64_t a, int64_t b)
{
    return (int64_t)ct_i128_isqrt(ct_i128_add(ct_i128_mul(a, a), ct_i128_mul(b, b)));
}

/* x * (c[0] + x^2 (c[1] + x^2 (...))), Horner in x^2, n terms */
static int64_t odd_series(int64_t x, const int64_t *c, int n)
{
    int64_t x2 = qmul(x, x), s = c[n - 1];
    int k;
    for (k = n - 2; k >= 0; --k) { /* bound: n */
        s = c[k] + qmul(x2, s);
    }
    return qmul(x, s);
}

/* c[0] + x^2 (c[1] + ...), n terms */
static int64_t even_series(int64_t x, const int64_t *c, int n)
{
    int64_t x2 = qmul(x, x), s = c[n - 1];
    int k;
    for (k = n - 2; k >= 0; --k) { /* bound: n */
        s = c[k] + qmul(x2, s);
    }
    return s;
}

/* Series coefficients (Q59, rounded): 1/(2k+1)! with alternating sign
 * (sin), 1/(2k)! (cos), the same without signs (sinh, cosh), 1/(2k+1)
 * (atanh; alternating: atan), asinh's (-1)^k (2k)! / (4^k k!^2 (2k+1)). */
#define NS 10
static const int64_t c_sin[NS] = {INT64_C(576460752303423488), -INT64_C(96076792050570581), INT64_C(4803839602528529),
                                  -INT64_C(114377133393536),   INT64_C(1588571297132),      -INT64_C(14441557247),
                                  INT64_C(92574085),           -INT64_C(440829),            INT64_C(1621),
                                  -INT64_C(5)};
static const int64_t c_cos[NS] = {INT64_C(576460752303423488), -INT64_C(288230376151711744), INT64_C(24019198012642645),
                                  -INT64_C(800639933754755),   INT64_C(14297141674192),      -INT64_C(158857129713),
                                  INT64_C(1203463104),         -INT64_C(6612437),            INT64_C(27552),
                                  -INT64_C(90)};
static const int64_t c_sinh[NS] = {INT64_C(576460752303423488), INT64_C(96076792050570581), INT64_C(4803839602528529),
                                   INT64_C(114377133393536),    INT64_C(1588571297132),     INT64_C(14441557247),
                                   INT64_C(92574085),           INT64_C(440829),            INT64_C(1621),
                                   INT64_C(5)};
static const int64_t c_cosh[NS] = {INT64_C(576460752303423488), INT64_C(288230376151711744), INT64_C(24019198012642645),
                                   INT64_C(800639933754755),    INT64_C(14297141674192),     INT64_C(158857129713),
                                   INT64_C(1203463104),         INT64_C(6612437),            INT64_C(27552),
                                   INT64_C(90)};

/* sin and cos of |r| <= pi/4 (Q59): Taylor to r^19 / r^18, error < 2^-60 */
static void sincos_small(int64_t r, int64_t *s, int64_t *c)
{
    *s = odd_series(r, c_sin, NS);
    *c = even_series(r, c_cos, NS);
}

/* sin, cos of |x| <= pi (Q59): quadrant reduction by pi/2 */
static void qsincos(int64_t x, int64_t *s, int64_t *c)
{
    int64_t k = (x >= 0 ? x + TM_PI_2 / 2 : x - TM_PI_2 / 2) / TM_PI_2; /* nearest, |k| <= 2 */
    int64_t r = x - k * TM_PI_2, sr, cr;
    sincos_small(r, &sr, &cr);
    switch ((int)(k & 3)) {
    case 0:
        *s = sr;
        *c = cr;
        break;
    case 1:
        *s = cr;
        *c = -sr;
        break;
    case 2:
        *s = -sr;
        *c = -cr;
        break;
    default:
        *s = -cr;
        *c = sr;
        break;
    }
}

/* The series' coefficients in Q59, as integer divisions of ONE (constant
 * tables: -Os would otherwise divide them out, 14 64-bit divisions a call):
 * atan (-1)^k / (2k + 1), atanh 1 / (2k + 1), asinh (-1)^k t_k / (2k + 1)
 * with t_0 = ONE, t_(k+1) = floor(t_k / (2k + 2)) (2k + 1). */
static const int64_t atan_c[14] = {
    INT64_C(576460752303423488), -INT64_C(192153584101141162), INT64_C(115292150460684697),
    -INT64_C(82351536043346212), INT64_C(64051194700380387),   -INT64_C(52405522936674862),
    INT64_C(44343134792571037),  -INT64_C(38430716820228232),  INT64_C(33909456017848440),
    -INT64_C(30340039594917025), INT64_C(27450512014448737),   -INT64_C(25063510969714064),
    INT64_C(23058430092136939),  -INT64_C(21350398233460129)};
static const int64_t atanh_c[12] = {
    INT64_C(576460752303423488), INT64_C(192153584101141162), INT64_C(115292150460684697),
    INT64_C(82351536043346212),  INT64_C(64051194700380387),  INT64_C(52405522936674862),
    INT64_C(44343134792571037),  INT64_C(38430716820228232),  INT64_C(33909456017848440),
    INT64_C(30340039594917025),  INT64_C(27450512014448737),  INT64_C(25063510969714064)};
static const int64_t asinh_c[14] = {
    INT64_C(576460752303423488), -INT64_C(96076792050570581), INT64_C(43234556422756761),
    -INT64_C(25734855013545691), INT64_C(17513998550885262),  -INT64_C(12896671660197329),
    INT64_C(10003187633871005),  -INT64_C(8050184333924761),  INT64_C(6659159835048056),
    -INT64_C(5627184772891486),  INT64_C(4836699292890063),   -INT64_C(4215384166333039),
    INT64_C(3716563706650296),   -INT64_C(3308906433983525)};

/* atan(x) for |x| <= 1 (Q59): two halvings x / (1 + sqrt(1 + x^2)) bring
 * it to <= tan(pi/16) < 0.2, then 14 terms of the series (0.04^14 <
 * 2^-64), times 4. */
static int64_t atan_unit(int64_t x)
{
    int k;
    /* bound: 2 halvings */
    for (k = 0; k < 2; ++k) {
        x = qdiv(x, ONE + qhypot(ONE, x));
    }
    return 4 * odd_series(x, atan_c, 14);
}

/* atan2(y, x) in (-pi, pi], |x|, |y| < 16, not both 0 */
static int64_t qatan2(int64_t y, int64_t x)
{
    int64_t ay = ct_abs64(y), ax = ct_abs64(x), a;
    if (ay <= ax) {
        a = atan_unit(qdiv(ay, ax));
    } else {
        a = TM_PI_2 - atan_unit(qdiv(ax, ay));
    }
    if (x < 0) {
        a = TM_PI - a;
    }
    return y < 0 ? -a : a;
}

/* atanh(x) for |x| <= 0.1: 12 terms of x + x^3/3 + ... (0.01^12) */
static int64_t atanh_small(int64_t x)
{
    return odd_series(x, atanh_c, 12);
}

/* asinh(x) for |x| <= 0.17: 14 terms (0.029^14 < 2^-70) */
static int64_t asinh_small(int64_t x)
{
    return odd_series(x, asinh_c, 14); /* t_k ~ (2k)! / (4^k k!^2) */
}

/* sinh and cosh of |x| <= 0.2: 10 terms each (c_sinh, c_cosh: sin's and
 * cos's coefficients without their signs, as atanh_c is atan_c's) */
static void sinhcosh_small(int64_t x, int64_t *sh, int64_t *ch)
{
    *sh = odd_series(x, c_sinh, NS);
    *ch = even_series(x, c_cosh, NS);
}

/* tau' from tau = sin / cos of the latitude (Karney's taupf):
 * sigma = sinh(e atanh(e sin)), tau' = tau sqrt(1 + sigma^2) - sigma / cos. */
static int64_t taup(int64_t sphi, int64_t cphi, int64_t tau)
{
    int64_t sig, ch;
    sinhcosh_small(qmul(TM_E, atanh_small(qmul(TM_E, sphi))), &sig, &ch);
    /* ch = sqrt(1 + sigma^2) */
    return qmul(tau, ch) - qdiv(sig, cphi);
}

/* 1 + sum_j 2 j a_j cos(2 j zeta) = p - i q (the derivative of the series
 * below), by the same recurrence on the coefficients 2 j a_j: the cosine
 * sum is cos(2 zeta) y_1 - y_2. */
static void clenshaw_deriv(const int64_t *a, int64_t s2, int64_t c2, int64_t sh2, int64_t ch2, int64_t *p,
                           int64_t *q)
{
    int64_t ar = 2 * qmul(c2, ch2), ai = -2 * qmul(s2, sh2);
    int64_t yr0 = 0, yi0 = 0, yr1 = 0, yi1 = 0;
    int j;
    for (j = 5; j >= 0; --j) { /* bound: 6 terms */
        int64_t yr = 2 * (j + 1) * a[j] + qmul(ar, yr0) - qmul(ai, yi0) - yr1;
        int64_t yi = qmul(ar, yi0) + qmul(ai, yr0) - yi1;
        yr1 = yr0;
        yi1 = yi0;
        yr0 = yr;
        yi0 = yi;
    }
    {
        /* cos(2 zeta) = c2 ch2 - i s2 sh2 */
        int64_t cr = qmul(c2, ch2), ci = -qmul(s2, sh2);
        *p = ONE + qmul(cr, yr0) - qmul(ci, yi0) - yr1;
        *q = -(qmul(cr, yi0) + qmul(ci, yr0) - yi1);
    }
}

/* Complex Clenshaw: zeta + sum_j a_j sin(2 j zeta), zeta = xi + i eta,
 * from sin/cos of 2 xi and sinh/cosh of 2 eta; sign -1 for the inverse. */
static void clenshaw(const int64_t *a, int sign, int64_t xi, int64_t eta, int64_t s2, int64_t c2, int64_t sh2,
                     int64_t ch2, int64_t *oxi, int64_t *oeta)
{
    /* ar + i ai = 2 cos(2 zeta) = 2 (c2 ch2 - i s2 sh2) */
    int64_t ar = 2 * qmul(c2, ch2), ai = -2 * qmul(s2, sh2);
    int64_t yr0 = 0, yi0 = 0, yr1 = 0, yi1 = 0;
    int j;
    /* bound: 6 terms; y_j = a_j + (ar + i ai) y_{j+1} - y_{j+2} */
    for (j = 5; j >= 0; --j) {
        int64_t yr = a[j] + qmul(ar, yr0) - qmul(ai, yi0) - yr1;
        int64_t yi = qmul(ar, yi0) + qmul(ai, yr0) - yi1;
        yr1 = yr0;
        yi1 = yi0;
        yr0 = yr;
        yi0 = yi;
    }
    {
        /* sin(2 zeta) = s2 ch2 + i c2 sh2; the sum = sin(2 zeta) y_1 */
        int64_t sr = qmul(s2, ch2), si = qmul(c2, sh2);
        int64_t tr = qmul(sr, yr0) - qmul(si, yi0), ti = qmul(sr, yi0) + qmul(si, yr0);
        *oxi = xi + sign * tr;
        *oeta = eta + sign * ti;
    }
}

static int64_t lon0_q59(int32_t zone) { return (int64_t)(6 * zone - 183) * TM_DEG_Q59; }

/* Q61 -> Q59, rounded */
static int64_t q61_to_59(int64_t v) { return v >= 0 ? (v + 2) >> 2 : -((-v + 2) >> 2); }

ct_status ct_utm_zone_of_epsg(int32_t epsg, ct_utm *z)
{
    CT_ASSERT(z != NULL);
    if (z == NULL) {
        return CT_ERR_ARG;
    }
    if (epsg >= 32601 && epsg <= 32660) {
        z->zone = epsg - 32600;
        z->south = 0;
        return CT_OK;
    }
    if (epsg >= 32701 && epsg <= 32760) {
        z->zone = epsg - 32700;
        z->south = 1;
        return CT_OK;
    }
    return CT_ERR_CRS;
}

static ct_status forward(const ct_utm *z, int64_t lat_q61, int64_t lon_q61, int64_t *e_nm, int64_t *n_nm,
                         int64_t *gamma_q61, int64_t *k_q61);

ct_status ct_utm_forward(const ct_utm *z, int64_t lat_q61, int64_t lon_q61, int64_t *e_nm, int64_t *n_nm)
{
    return forward(z, lat_q61, lon_q61, e_nm, n_nm, NULL, NULL);
}

ct_status ct_utm_factors(const ct_utm *z, int64_t lat_q61, int64_t lon_q61, int64_t *gamma_q61, int64_t *k_q61)
{
    int64_t e, n;
    CT_ASSERT(gamma_q61 != NULL && k_q61 != NULL);
    if (gamma_q61 == NULL || k_q61 == NULL) {
        return CT_ERR_ARG;
    }
    return forward(z, lat_q61, lon_q61, &e, &n, gamma_q61, k_q61);
}

/* The forward projection; with gamma_q61 != NULL also the meridian
 * convergence and the point scale (Karney 2011, eqs. 27-28 with the series'
 * derivative p - i q): gamma = atan2(tau' sin lam, sqrt(1 + tau'^2) cos lam)
 * + atan2(q, p); k = k0 (A / a) sqrt(1 - e^2 sin^2 phi) sqrt(1 + tau^2) /
 * sqrt(tau'^2 + cos^2 lam) * sqrt(p^2 + q^2). */
static ct_status forward(const ct_utm *z, int64_t lat_q61, int64_t lon_q61, int64_t *e_nm, int64_t *n_nm,
                         int64_t *gamma_q61, int64_t *k_q61)
{
    int64_t phi, lam, sphi, cphi, slam, clam, tau, tp, r, sxi, cxi, sheta, cheta, xi, eta, s2, c2, sh2, ch2;
    CT_ASSERT(z != NULL && e_nm != NULL && n_nm != NULL);
    if (z == NULL || e_nm == NULL || n_nm == NULL || z->zone < 1 || z->zone > 60) {
        return CT_ERR_ARG;
    }
    if (ct_abs64(lat_q61) > CT_UTM_MAX_LAT_Q61 || ct_abs64(lon_q61) > CT_PI_Q61) {
        return CT_ERR_RANGE;
    }
    phi = q61_to_59(lat_q61);
    lam = q61_to_59(lon_q61) - lon0_q59(z->zone);
    /* wrap into (-pi, pi] */
    if (lam > TM_PI) {
        lam -= 2 * TM_PI;
    } else if (lam <= -TM_PI) {
        lam += 2 * TM_PI;
    }
    if (ct_abs64(lam) > CT_UTM_MAX_DLON_DEG * TM_DEG_Q59) {
        return CT_ERR_RANGE;
    }
    qsincos(phi, &sphi, &cphi);
    qsincos(lam, &slam, &clam);
    tau = qdiv(sphi, cphi);
    tp = taup(sphi, cphi, tau);
    /* xi' = atan2(tau', cos lam), and its sine and cosine; sinh eta' =
     * sin lam / r, cosh eta' = sqrt(1 + tau'^2) / r, r = hypot(tau', cos lam) */
    r = qhypot(tp, clam);
    xi = qatan2(tp, clam);
    sxi = qdiv(tp, r);
    cxi = qdiv(clam, r);
    sheta = qdiv(slam, r);
    cheta = qdiv(qhypot(ONE, tp), r);
    eta = asinh_small(sheta);
    s2 = 2 * qmul(sxi, cxi);
    c2 = qmul(cxi, cxi) - qmul(sxi, sxi);
    sh2 = 2 * qmul(sheta, cheta);
    ch2 = qmul(cheta, cheta) + qmul(sheta, sheta);
    if (gamma_q61 != NULL) {
        int64_t pp, qq, g, kk;
        clenshaw_deriv(tm_alpha, s2, c2, sh2, ch2, &pp, &qq);
        g = qatan2(qmul(tp, slam), qmul(qhypot(ONE, tp), clam)) + qatan2(qq, pp);
        /* k / (k0 A / a): each factor < 10, the product formed step by step */
        kk = qmul(qsqrt_one_minus(qmul(TM_E2, qmul(sphi, sphi))), qdiv(ONE, cphi));
        kk = qmul(qdiv(kk, r), qhypot(pp, qq));
        *gamma_q61 = g * 4;
        *k_q61 = qmul(kk, TM_K0A_OVER_A) * 4;
    }
    clenshaw(tm_alpha, 1, xi, eta, s2, c2, sh2, ch2, &xi, &eta);
    /* k0 A (nm, Q8, < 2^61) times xi, eta (Q59, |.| < 2): Q67 -> nm */
    *e_nm = INT64_C(500000000000000) + ct_i128_round_shr(ct_i128_mul(TM_K0A_NM_Q8, eta), QB + 8u);
    *n_nm = (z->south ? INT64_C(10000000000000000) : 0) + ct_i128_round_shr(ct_i128_mul(TM_K0A_NM_Q8, xi), QB + 8u);
    return CT_OK;
}

/* tau from tau' by Newton's method (Karney's tauf): d tau' / d tau =
 * (1 - e^2) sqrt(1 + tau'^2) sqrt(1 + tau^2) / (1 + (1 - e^2) tau^2), so
 * the step is (tau'(tau) - target) w / ((1 - e^2) sqrt(1 + tau'^2)), w =
 * (1 + (1 - e^2) tau^2) / sqrt(1 + tau^2) (<= sqrt(1 + tau^2) < 10; its
 * numerator formed in Q118, < 2^126).  Start tau' / (1 - e^2); the error
 * squares each step: 5 steps reach the Q59 resolution.  A step of 0 ends
 * it (tau unchanged, every later step would be 0 too: the same result);
 * over the zone 2 or 3 steps (0.05 % take 4; a few points near the
 * domain's limits, in the tests, all 5). */
static int64_t tau_of_taup(int64_t target)
{
    int64_t tau = qdiv(target, TM_1ME2), step = 1;
    int k;
    for (k = 0; k < 5 && step != 0; ++k) { /* bound: 5 Newton steps */
        int64_t sec = qhypot(ONE, tau); /* sqrt(1 + tau^2) = 1 / cos(phi) */
        int64_t cphi = qdiv(ONE, sec), sphi = qdiv(tau, sec);
        int64_t tp = taup(sphi, cphi, tau);
        ct_i128 w2 = ct_i128_add(ct_i128_shl(ct_i128_from64(ONE), QB), ct_i128_mul(qmul(TM_1ME2, tau), tau));
        int64_t w = ct_i128_floor_div(w2, sec);
        int64_t d = qmul(TM_1ME2, qhypot(ONE, tp));
        step = qdiv(qmul(tp - target, w), d);
        tau -= step;
    }
    return tau;
}

ct_status ct_utm_inverse(const ct_utm *z, int64_t e_nm, int64_t n_nm, int64_t *lat_q61, int64_t *lon_q61)
{
    int64_t xi, eta, sh, ch, s2, c2, sh2, ch2, sxi, cxi, sheta, cheta, r, tp, lam, phi, de, dn;
    CT_ASSERT(z != NULL && lat_q61 != NULL && lon_q61 != NULL);
    if (z == NULL || lat_q61 == NULL || lon_q61 == NULL || z->zone < 1 || z->zone > 60) {
        return CT_ERR_ARG;
    }
    if (ct_abs64(e_nm) > (INT64_C(1) << 60) || ct_abs64(n_nm) > (INT64_C(1) << 60)) {
        return CT_ERR_RANGE; /* far off any zone; keeps the differences below in range */
    }
    de = e_nm - INT64_C(500000000000000);
    dn = n_nm - (z->south ? INT64_C(10000000000000000) : 0);
    /* |de| <= 1100 km (eta <= 0.173), |dn| <= 9,500 km (xi < 1.5; lat
     * 84.5 deg is at 9,390 km): d 2^67 < 2^120, quotients < 2^62 */
    if (ct_abs64(de) > INT64_C(1100000000000000) || ct_abs64(dn) > INT64_C(9500000000000000)) {
        return CT_ERR_RANGE;
    }
    xi = ct_i128_floor_div(ct_i128_shl(ct_i128_shl(ct_i128_from64(dn), QB), 8u), TM_K0A_NM_Q8);
    eta = ct_i128_floor_div(ct_i128_shl(ct_i128_shl(ct_i128_from64(de), QB), 8u), TM_K0A_NM_Q8);
    qsincos(2 * xi, &s2, &c2);
    sinhcosh_small(eta, &sh, &ch);
    sh2 = 2 * qmul(sh, ch);
    ch2 = qmul(ch, ch) + qmul(sh, sh);
    clenshaw(tm_beta, -1, xi, eta, s2, c2, sh2, ch2, &xi, &eta);
    qsincos(xi, &sxi, &cxi);
    sinhcosh_small(eta, &sheta, &cheta);
    r = qhypot(sheta, cxi);
    if (r == 0) {
        return CT_ERR_RANGE; /* a pole */
    }
    tp = qdiv(sxi, r);
    lam = qatan2(sheta, cxi);
    /* the forward domain (|lat| <= 84.5 deg: tau' < 10.4; <= 9 deg from the
     * meridian) with a margin, so that every point it maps inverts; tau' <
     * 10.5 keeps qhypot's arguments below 11.3 */
    if (ct_abs64(lam) > CT_UTM_MAX_DLON_DEG * TM_DEG_Q59 + TM_DEG_Q59 / 64 || ct_abs64(tp) > 10 * ONE + ONE / 2) {
        return CT_ERR_RANGE;
    }
    phi = qatan2(tau_of_taup(tp), ONE);
    *lat_q61 = phi * 4;
    lam += lon0_q59(z->zone);
    if (lam > TM_PI) {
        lam -= 2 * TM_PI;
    } else if (lam <= -TM_PI) {
        lam += 2 * TM_PI;
    }
    *lon_q61 = lam * 4;
    return CT_OK;
}

/* ------------------------------------------------------------------------ */
/* Earth-centred, Earth-fixed coordinates (EPSG:4978)                        */
/*
 * Lengths here are nm scaled by 2^8 (forward) or 2^6 (inverse), so that
 * rounding inside stays far below the nm of the results while every value
 * keeps below 2^63; the factors that multiply them are Q59 (|.| <= 1 + a
 * few units), their products formed in 128 bits (< 2^123) and rounded.
 * Constants (WGS84: a = 6378137 m, f = 1 / 298.257223563, e^2 = f (2 - f),
 * b = a (1 - f), e'^2 = e^2 / (1 - e^2)), rounded to the nearest unit.    */
#define ECEF_A_Q8 INT64_C(1632803072000000000)  /* a, nm * 2^8 (exact, < 2^61)   */
#define ECEF_A_Q6 INT64_C(408200768000000000)   /* a, nm * 2^6 (exact, < 2^59)   */
#define ECEF_1MF INT64_C(574527988545292214)    /* b / a = 1 - f, Q59            */
#define ECEF_E2A_Q6 INT64_C(2732651053259518)   /* e^2 a, nm * 2^6 (< 2^52)      */
#define ECEF_EP2B_Q6 INT64_C(2741843936852069)  /* e'^2 b = e^2 a / (1 - f), same */
#define ECEF_MAX_NM (INT64_C(1) << 55)          /* |x|, |y|, |z| of the inverse  */

/* X = (N + h) cos(phi) cos(lam), Y = (N + h) cos(phi) sin(lam), Z = (N (1 -
 * e^2) + h) sin(phi), N = a / sqrt(1 - e^2 sin^2 phi).                     */
ct_status ct_ecef_from_wgs84(int64_t lat_q61, int64_t lon_q61, int64_t h_nm, int64_t xyz_nm[3])
{
    int64_t sphi, cphi, slam, clam, w, n8, nh8, nz8;
    CT_ASSERT(xyz_nm != NULL);
    if (xyz_nm == NULL) {
        return CT_ERR_ARG;
    }
    if (ct_abs64(lat_q61) > CT_PI_Q61 / 2 || ct_abs64(lon_q61) > CT_PI_Q61 || h_nm < -(INT64_C(1) << 52) ||
        h_nm > (INT64_C(1) << 54)) {
        return CT_ERR_RANGE;
    }
    qsincos(q61_to_59(lat_q61), &sphi, &cphi);
    qsincos(q61_to_59(lon_q61), &slam, &clam);
    /* w = sqrt(1 - e^2 sin^2 phi) in [0.9966, 1] (Q59); N = a / w, nm * 2^8:
     * the dividend a 2^8 2^59 < 2^120, the quotient < 1.0034 a 2^8 < 2^61 */
    w = qsqrt_one_minus(qmul(TM_E2, qmul(sphi, sphi)));
    n8 = ct_i128_floor_div(ct_i128_shl(ct_i128_from64(ECEF_A_Q8), QB), w);
    /* N + h and N (1 - e^2) + h, nm * 2^8: h 2^8 in [-2^60, 2^62], N 2^8 <
     * 2^60.6, so both lie in (0, 2^62.5) (N >= a > 2^52 >= -h) */
    nh8 = n8 + h_nm * 256;
    nz8 = ct_i128_round_shr(ct_i128_mul(n8, TM_1ME2), QB) + h_nm * 256;
    /* (< 2^62.5) times a Q59 factor (<= 1): < 2^122, rounded to nm (< 2^55) */
    xyz_nm[0] = ct_i128_round_shr(ct_i128_mul(nh8, qmul(cphi, clam)), QB + 8u);
    xyz_nm[1] = ct_i128_round_shr(ct_i128_mul(nh8, qmul(cphi, slam)), QB + 8u);
    xyz_nm[2] = ct_i128_round_shr(ct_i128_mul(nz8, sphi), QB + 8u);
    return CT_OK;
}

/* lon = atan2(Y, X); the latitude by Bowring's iteration (1976) on the
 * reduced latitude beta (tan beta = (1 - f) tan phi), from tan beta0 = a Z
 * / (b p), p = hypot(X, Y):
 *   tan phi = (Z + e'^2 b sin^3 beta) / (p - e^2 a cos^3 beta),
 *   tan beta = (1 - f) tan phi,
 * carried as (cos, sin) pairs, so no trigonometric function inside.  The
 * error of phi after the k-th evaluation (measured in 45-digit arithmetic
 * over latitudes 0..90 deg and radii 2^50 nm .. 63,000 km; worst at the
 * domain's deepest point, 2^50 nm from the centre): k = 1: 7e-6, k = 2:
 * 1.4e-12 (< 1e-19 from 6,300 km outwards), k = 3: 6e-26 rad (< 3e-30 from
 * 2,000 km outwards) -- three evaluations reach the Q59 resolution
 * everywhere; the plain iteration phi <- atan2(Z + e^2 N sin phi, p)
 * contracts by only e^2 N / (N + h) per step (0.04 at 2^50 nm) and needs
 * a sine, a cosine and an arctangent each time (3x slower at 6 steps).
 * Then h = p cos(phi) + Z sin(phi) - a sqrt(1 - e^2 sin^2 phi), which is
 * stationary in phi (no loss near the poles).  By symmetry the iteration
 * runs on |Z| and the sign is put back at the end.                        */
ct_status ct_wgs84_from_ecef(const int64_t xyz_nm[3], int64_t *lat_q61, int64_t *lon_q61, int64_t *h_nm)
{
    int64_t x, y, p, az, u, v, num = 0, den = 0, r, s, c, lat, lon;
    ct_i128 r2, acc;
    int k;
    CT_ASSERT(xyz_nm != NULL && lat_q61 != NULL && lon_q61 != NULL && h_nm != NULL);
    if (xyz_nm == NULL || lat_q61 == NULL || lon_q61 == NULL || h_nm == NULL) {
        return CT_ERR_ARG;
    }
    x = xyz_nm[0];
    y = xyz_nm[1];
    if (ct_abs64(x) > ECEF_MAX_NM || ct_abs64(y) > ECEF_MAX_NM || ct_abs64(xyz_nm[2]) > ECEF_MAX_NM) {
        return CT_ERR_RANGE;
    }
    /* |.| <= 2^55: squares <= 2^110, their sum < 2^112; at least 2^50 nm
     * from the centre (outside the evolute of the meridian ellipse, 43 km,
     * by far: the iteration's contraction stays small) */
    r2 = ct_i128_add(ct_i128_add(ct_i128_mul(x, x), ct_i128_mul(y, y)), ct_i128_mul(xyz_nm[2], xyz_nm[2]));
    if (ct_i128_cmp(r2, ct_i128_shl(ct_i128_from64(INT64_C(1) << 50), 50u)) < 0) { /* shl: n < 64 */
        return CT_ERR_RANGE;
    }
    /* qatan2 uses only y / x (|.| < 2^63: y 2^59 < 2^122) */
    lon = (x == 0 && y == 0) ? 0 : qatan2(y, x);
    /* lengths in nm * 2^6 (<= 2^61): p <= 2^61.5 (squares summed < 2^123) */
    p = (int64_t)ct_i128_isqrt(ct_i128_add(ct_i128_mul(64 * x, 64 * x), ct_i128_mul(64 * y, 64 * y)));
    az = 64 * ct_abs64(xyz_nm[2]);
    /* (cos beta, sin beta) ~ (u, v) = ((1 - f) p, Z); later (den, (1 - f)
     * num): den <= p, num <= az + e'^2 b < 2^61 + 2^52, so qhypot's sum of
     * squares stays below 2^125 (it needs < 2^126); r >= (1 - f) 2^56 > 0
     * since the point is at least 2^50 nm from the centre. */
    u = qmul(ECEF_1MF, p);
    v = az;
    for (k = 0; k < 3; ++k) { /* bound: 3 evaluations (see above) */
        int64_t sb, cb;
        if (k > 0) {
            u = den;
            v = qmul(ECEF_1MF, num);
        }
        r = qhypot(u, v);
        cb = qdiv(u, r);
        sb = qdiv(v, r);
        /* e'^2 b sin^3, e^2 a cos^3: a length (< 2^52) times Q59 (<= 1) */
        num = az + qmul(ECEF_EP2B_Q6, qmul(qmul(sb, sb), sb));
        den = p - qmul(ECEF_E2A_Q6, qmul(qmul(cb, cb), cb));
    }
    /* den >= 0 outside the evolute; phi in [0, pi/2] */
    lat = qatan2(num, den);
    r = qhypot(den, num);
    c = qdiv(den, r);
    s = qdiv(num, r);
    /* h 2^6 2^59 = p c + |Z| s - a sqrt(1 - e^2 s^2): each product < 2^121,
     * the sum < 2^123; rounded to nm */
    acc = ct_i128_add(ct_i128_mul(p, c), ct_i128_mul(az, s));
    acc = ct_i128_sub(acc, ct_i128_mul(ECEF_A_Q6, qsqrt_one_minus(qmul(TM_E2, qmul(s, s)))));
    *h_nm = ct_i128_round_shr(acc, QB + 6u);
    /* Q59 -> Q61; 4 pi (Q59) exceeds CT_PI_Q61 by 2 units: clamped */
    lat = ct_min64(4 * lat, CT_PI_Q61 / 2);
    *lat_q61 = xyz_nm[2] < 0 ? -lat : lat;
    *lon_q61 = ct_max64(ct_min64(4 * lon, CT_PI_Q61), -CT_PI_Q61);
    return CT_OK;
}

/* ------------------------------------------------------------------------ */
/* Poses from the navigation solution.                                       */

/* round(v / 2^30) without the implementation-defined shift of negatives */
static int64_t shr30(int64_t v)
{
    const int64_t h = INT64_C(1) << 29;
    return v >= 0 ? (v + h) >> 30 : -((-v + h) >> 30);
}

/* Hamilton product a b (Q30 in, Q30 out, rounded; |components| <= 2^30:
 * products <= 2^60, sums of four < 2^62) */
static void quat_mul(const int64_t a[4], const int64_t b[4], int64_t r[4])
{
    r[0] = shr30(a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3]);
    r[1] = shr30(a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2]);
    r[2] = shr30(a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1]);
    r[3] = shr30(a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]);
}

/* Q59 -> Q30, rounded (|v| <= 2^59) */
static int64_t q59_to_30(int64_t v) { return v >= 0 ? (v + (INT64_C(1) << 28)) >> 29 : -((-v + (INT64_C(1) << 28)) >> 29); }

ct_status ct_quat_from_ypr(int64_t yaw_q61, int64_t pitch_q61, int64_t roll_q61, int32_t q[4])
{
    /* q = q_z(yaw) q_y(pitch) q_x(roll) q_P, q_P = (1, 1, 1, 1) / 2 the
     * camera-to-body turn (x -> y, y -> z, z -> x: 120 deg about (1,1,1)),
     * each axis quaternion (cos a/2, sin a/2 along the axis).  Products of
     * Q30 values (< 2^60, sums of four < 2^62) rounded to Q30. */
    int64_t a[3], qz[4], qy[4], qx[4], t1[4], t2[4], r[4];
    const int64_t qp[4] = {INT64_C(1) << 29, INT64_C(1) << 29, INT64_C(1) << 29, INT64_C(1) << 29};
    int64_t sv, cv;
    int k;
    CT_ASSERT(q != NULL);
    if (q == NULL) {
        return CT_ERR_ARG;
    }
    a[0] = yaw_q61;
    a[1] = pitch_q61;
    a[2] = roll_q61;
    for (k = 0; k < 3; ++k) { /* bound: 3 angles */
        if (ct_abs64(a[k]) > CT_PI_Q61) {
            return CT_ERR_RANGE;
        }
    }
    qsincos(q61_to_59(yaw_q61) / 2, &sv, &cv);
    qz[0] = q59_to_30(cv);
    qz[1] = 0;
    qz[2] = 0;
    qz[3] = q59_to_30(sv);
    qsincos(q61_to_59(pitch_q61) / 2, &sv, &cv);
    qy[0] = q59_to_30(cv);
    qy[1] = 0;
    qy[2] = q59_to_30(sv);
    qy[3] = 0;
    qsincos(q61_to_59(roll_q61) / 2, &sv, &cv);
    qx[0] = q59_to_30(cv);
    qx[1] = q59_to_30(sv);
    qx[2] = 0;
    qx[3] = 0;
    quat_mul(qz, qy, t1);
    quat_mul(t1, qx, t2);
    quat_mul(t2, qp, r);
    for (k = 0; k < 4; ++k) { /* bound: 4 components, |r| <= 2^30 + 4 */
        q[k] = (int32_t)ct_max64(ct_min64(r[k], INT64_C(1) << 30), -(INT64_C(1) << 30));
    }
    return CT_OK;
}

/* The pose for attitude quaternion q (Q30, NED) with grid north at
 * convergence (sin, cos: Q30) from true north, the centre (e, n, h). */
static ct_status pose_from_q(ct_pose *pose, const int32_t qin[4], int64_t sg, int64_t cg, int64_t e, int64_t n,
                             int64_t h_nm)
{
    int64_t w = qin[0], x = qin[1], y = qin[2], zq = qin[3];
    int64_t ned[9]; /* R_ned_cam, Q30 */
    int32_t R[9];
    int i;
    /* |q|^2 = 2^60 within 2^40 (components <= 2^31: squares < 2^62,
     * their sum < 2^64 -- formed unsigned) */
    {
        uint64_t s2 = (uint64_t)(w * w) + (uint64_t)(x * x) + (uint64_t)(y * y) + (uint64_t)(zq * zq);
        uint64_t one = (uint64_t)1 << 60;
        if ((s2 > one ? s2 - one : one - s2) > ((uint64_t)1 << 40)) {
            pose->ready = 0u;
            return CT_ERR_POSE;
        }
    }
    /* R_ned_cam from q (rotating camera vectors into NED), Q30; products
     * < 2^62 */
    ned[0] = (INT64_C(1) << 30) - shr30(2 * (y * y + zq * zq));
    ned[1] = shr30(2 * (x * y - w * zq));
    ned[2] = shr30(2 * (x * zq + w * y));
    ned[3] = shr30(2 * (x * y + w * zq));
    ned[4] = (INT64_C(1) << 30) - shr30(2 * (x * x + zq * zq));
    ned[5] = shr30(2 * (y * zq - w * x));
    ned[6] = shr30(2 * (x * zq - w * y));
    ned[7] = shr30(2 * (y * zq + w * x));
    ned[8] = (INT64_C(1) << 30) - shr30(2 * (x * x + y * y));
    /* map = (grid east, grid north, up): east' = E cos g - N sin g,
     * north' = E sin g + N cos g (true north lies at grid azimuth -g), up =
     * -down; E = ned row 1, N = ned row 0 */
    for (i = 0; i < 3; ++i) { /* bound: 3 columns (camera axes) */
        int64_t nn = ned[i], ee = ned[3 + i], dd = ned[6 + i];
        R[i] = (int32_t)shr30(ee * cg - nn * sg);
        R[3 + i] = (int32_t)shr30(ee * sg + nn * cg);
        R[6 + i] = (int32_t)(-dd);
    }
    return ct_pose_init(pose, R, e, n, h_nm);
}

ct_status ct_pose_from_map(ct_pose *pose, int64_t e_nm, int64_t n_nm, int64_t h_nm, const int32_t q[4])
{
    CT_ASSERT(pose != NULL && q != NULL);
    if (pose == NULL || q == NULL) {
        return CT_ERR_ARG;
    }
    return pose_from_q(pose, q, 0, INT64_C(1) << 30, e_nm, n_nm, h_nm);
}

ct_status ct_pose_from_wgs84(ct_pose *pose, const ct_utm *zone, int64_t lat_q61, int64_t lon_q61, int64_t h_nm,
                             const int32_t qin[4])
{
    int64_t e, n, g, k, n2, sg, cg, sphi, cphi, hs;
    ct_status st;
    CT_ASSERT(pose != NULL && zone != NULL && qin != NULL);
    if (pose == NULL || zone == NULL || qin == NULL) {
        return CT_ERR_ARG;
    }
    pose->ready = 0u;
    st = forward(zone, lat_q61, lon_q61, &e, &n, &g, &k);
    if (st != CT_OK) {
        return st;
    }
    qsincos(q61_to_59(g), &sg, &cg);
    st = pose_from_q(pose, qin, q59_to_30(sg), q59_to_30(cg), e, n, h_nm);
    if (st != CT_OK) {
        return st;
    }
    /* hscale = k R / (R + h), R = sqrt(M N) = a sqrt(1 - e^2) / (1 - e^2
     * sin^2 phi) the Gaussian mean radius (nm: < 2^53): k (Q61 -> Q59)
     * times R / (R + h) (Q59, |h| < R / 2 required) -> Q30 */
    qsincos(q61_to_59(lat_q61), &sphi, &cphi);
    (void)cphi;
    n2 = ONE - qmul(TM_E2, qmul(sphi, sphi));
    {
        int64_t rr = ct_i128_round_shr(ct_i128_mul(INT64_C(6378137000000000), qdiv(qsqrt_one_minus(TM_E2), n2)), QB);
        int64_t ratio;
        if (ct_abs64(h_nm) > rr / 2) {
            pose->ready = 0u;
            return CT_ERR_POSE;
        }
        ratio = qdiv(rr, rr + h_nm); /* < 2 */
        hs = qmul(q61_to_59(k), ratio);
    }
    pose->hscale_q30 = (int32_t)q59_to_30(hs);
    return CT_OK;
}

/* ------------------------------------------------------------------------ */
/* The geoid grid (conetrace.h: ct_geoid_grid, the datum section)           */

#define GEOID_FRAC_BITS 19u
#define TWO_PI_Q61_U ((uint64_t)CT_PI_Q61 * 2u)

/* the node index and the Q19 fraction of an offset d (>= 0) along an axis
 * of n nodes, the last node included; 0 if outside.  d and (n - 1) step
 * are below 2^64 (open: (n - 1) step <= 2^62).                            */
static int geoid_axis(uint64_t d, int64_t step, uint32_t n, uint32_t *idx, int64_t *frac)
{
    uint64_t i = d / (uint64_t)step, r = d - i * (uint64_t)step;
    if (i > (uint64_t)n - 1u || (i == (uint64_t)n - 1u && r != 0u)) {
        return 0;
    }
    if (i == (uint64_t)n - 1u) {
        i--;
        r = (uint64_t)step;
    }
    *idx = (uint32_t)i;
    /* r <= step <= 2^58: shifted in 128 bits */
    *frac = ct_i128_floor_div(ct_i128_shl(ct_i128_from64((int64_t)r), GEOID_FRAC_BITS), step);
    return 1;
}

static int64_t geoid_node_nm(const ct_geoid_grid *g, uint32_t i, uint32_t j)
{
    uint32_t u = ct_ld32(g->values + 4u * ((size_t)j * g->w + i));
    return (int64_t)(int32_t)u * 1000;
}

ct_status ct_geoid_grid_check(const ct_geoid_grid *g)
{
    uint32_t most = g->w > g->h ? g->w : g->h;
    if (g->w < 2u || g->h < 2u || most > CT_GEOID_MAX_NODES) {
        return CT_ERR_DIMS;
    }
    if (g->step_q61 < CT_GEOID_MIN_STEP_Q61 || g->step_q61 > CT_GEOID_MAX_STEP_Q61 ||
        (uint64_t)(most - 1u) > ((uint64_t)1 << 62) / (uint64_t)g->step_q61 ||
        ct_abs64(g->lat0_q61) > CT_PI_Q61 / 2 || ct_abs64(g->lon0_q61) > CT_PI_Q61) {
        return CT_ERR_GEOREF;
    }
    return CT_OK;
}

ct_status ct_geoid_at(const ct_geoid_grid *g, int64_t lat_q61, int64_t lon_q61, int64_t *n_geoid_nm)
{
    const int64_t one = INT64_C(1) << GEOID_FRAC_BITS, half = one / 2;
    uint32_t i, j;
    int64_t fx, fy, a, c;
    uint64_t dlon;
    if (g == NULL || n_geoid_nm == NULL) {
        return CT_ERR_ARG;
    }
    if (g->values == NULL || ct_geoid_grid_check(g) != CT_OK) {
        return CT_ERR_RANGE;
    }
    if (ct_abs64(lat_q61) > CT_PI_Q61 / 2 || ct_abs64(lon_q61) > CT_PI_Q61 || g->lat0_q61 < lat_q61) {
        return CT_ERR_RANGE;
    }
    /* lon - lon0 in [0, 2 pi): modulo 2^64, then one turn added when
     * negative (2 pi < 2^64 in Q61) */
    dlon = (uint64_t)lon_q61 - (uint64_t)g->lon0_q61;
    if (lon_q61 < g->lon0_q61) {
        dlon += TWO_PI_Q61_U;
    }
    if (!geoid_axis(dlon, g->step_q61, g->w, &i, &fx) ||
        !geoid_axis((uint64_t)(g->lat0_q61 - lat_q61), g->step_q61, g->h, &j, &fy)) {
        return CT_ERR_RANGE;
    }
    /* along the row, rounded to nm: |N| < 2^41 nm, times <= 2^19 */
    a = ct_floor_div(geoid_node_nm(g, i, j) * (one - fx) + geoid_node_nm(g, i + 1u, j) * fx + half, one);
    c = ct_floor_div(geoid_node_nm(g, i, j + 1u) * (one - fx) + geoid_node_nm(g, i + 1u, j + 1u) * fx + half, one);
    *n_geoid_nm = ct_floor_div(a * (one - fy) + c * fy + half, one);
    return CT_OK;
}

ct_status ct_package_geoid(const ct_package *pkg, int64_t e_nm, int64_t n_nm, int64_t *n_geoid_nm)
{
    ct_utm z;
    int64_t lat, lon;
    ct_status st;
    if (pkg == NULL || n_geoid_nm == NULL) {
        return CT_ERR_ARG;
    }
    if (ct_package_zone(pkg, &z) != CT_OK) {
        return CT_ERR_CRS;
    }
    st = ct_utm_inverse(&z, e_nm, n_nm, &lat, &lon);
    if (st != CT_OK) {
        return st;
    }
    return ct_geoid_at(&pkg->geoid, lat, lon, n_geoid_nm);
}

/* ------------------------------------------------------------------------ */
/* The camera's local frame for the true-Earth walk (bend.h, earth.c)        */

ct_status ct_grid_frame_ecef(const ct_utm *z, int64_t e_nm, int64_t n_nm, int64_t *lat_q61, int64_t *lon_q61,
                             int32_t f[9])
{
    int64_t lat, lon, e, n, g, k, sp, cp, sl, cl, sg, cg, east[3], north[3], up[3];
    ct_status st;
    int i;
    if (z == NULL || lat_q61 == NULL || lon_q61 == NULL || f == NULL) {
        return CT_ERR_ARG;
    }
    st = ct_utm_inverse(z, e_nm, n_nm, &lat, &lon);
    if (st == CT_OK) {
        st = forward(z, lat, lon, &e, &n, &g, &k);
    }
    if (st != CT_OK) {
        return st;
    }
    qsincos(q61_to_59(lat), &sp, &cp);
    qsincos(q61_to_59(lon), &sl, &cl);
    qsincos(q61_to_59(g), &sg, &cg);
    /* ENU in ECEF: east (-sin lon, cos lon, 0), north (-sin lat cos lon,
     * -sin lat sin lon, cos lat), up (cos lat cos lon, cos lat sin lon,
     * sin lat); grid east = cos g east - sin g north, grid north = sin g
     * east + cos g north (pose_from_q's relation, inverted).  Q59 -> Q30 */
    east[0] = -sl;
    east[1] = cl;
    east[2] = 0;
    north[0] = -qmul(sp, cl);
    north[1] = -qmul(sp, sl);
    north[2] = cp;
    up[0] = qmul(cp, cl);
    up[1] = qmul(cp, sl);
    up[2] = sp;
    for (i = 0; i < 3; ++i) { /* bound: 3 ECEF axes */
        f[3 * i] = (int32_t)q59_to_30(qmul(cg, east[i]) - qmul(sg, north[i]));
        f[3 * i + 1] = (int32_t)q59_to_30(qmul(sg, east[i]) + qmul(cg, north[i]));
        f[3 * i + 2] = (int32_t)q59_to_30(up[i]);
    }
    *lat_q61 = lat;
    *lon_q61 = lon;
    return CT_OK;
}
