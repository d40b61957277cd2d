/*
 * earth.c -- the true Earth: a line of sight straight in Earth-fixed space
 * (WGS84), or refracted, traced over a package on a UTM zone.
 *
 * The path: P(t) = C + t d - (k t^2 / 2R) w  (ECEF, nm; t >= 0 the range
 * from the camera centre C, d the unit direction, w = up - (up . d) d:
 * normal to d in its vertical plane, upwards, of length cos(elevation) --
 * the textbook ray curvature k cos(elev) / R; the last term only with
 * refraction, R the mean radius).  Its image in the package's frame (UTM E, N, the
 * ellipsoidal height: ct_wgs84_from_ecef, ct_utm_forward, ct_map_to_grid)
 * is neither a map-frame line nor a vertical parabola: it stretches along
 * track (rho^2 tan(depression) / R), bends sideways (transverse Mercator:
 * about E' rho^2 / (2 R^2) at E' from the central meridian) and rises with
 * the ellipsoid's radius in its azimuth.  The image is interpolated per
 * ray through exact ones at Chebyshev nodes (below) and traced in pieces
 * [ta, tb] of the range:
 *   - the images A, M, B of the ends and the middle (Q16 grid, and in Q24
 *     for the checks);
 *   - horizontally the chord A -> B shifted sideways towards M by half M's
 *     deviation (chord_shift; the sideways bend is about a parabola, so the
 *     shifted chord's error is half the chord's, at its ends and middle
 *     alike); the camera's own piece over the tile is not shifted;
 *   - vertically the quadratic z(s) = zA + b s + a s^2 in the range s along
 *     the chord through A, M and B: the straight line from A to B lowered
 *     by a s^2 at B, traced against the terrain lowered post by post by
 *     a ((x - xA)^2 + (y - yA)^2) (the lowered walk of trace.c, ct_lower);
 *     a < 0 (a path bending down faster than the Earth: refraction k > 1)
 *     traces the chord itself;
 *   - the model's errors over the piece are bounded from the interpolated
 *     image's derivatives (side_rem, bound_vert: sideways, and in height at
 *     the image's range along the chord), or, for a piece without a
 *     lowered walk or an image without its polynomial, sampled at the
 *     quarter points (model_error): within the chord tolerance the piece is
 *     traced, otherwise shortened by 0.8 sqrt(tol / error) (errors grow as
 *     the length squared) and checked again; the next piece aims at 0.8 of
 *     the tolerance, at most twice as long, up to 30 km;
 *   - a hit beyond the piece's end belongs to the next piece.
 * The pieces start where the interpolated path may first come over the tile
 * and end where it has left it for good (path_span: the polynomial's linear
 * part and a bound of the rest).  Pieces off the tile in between
 * (horizontally, or above the tallest post) are not traced and need no
 * tolerance: they double in length.  The walk ends when the path has left
 * the tile for good, at the span's end, or after EARTH_MAX_PIECES.
 * CT_BELOW means the camera is over the tile and under its surface; a path
 * entering the tile's side below the surface meets the side there.
 *
 * Formats: ECEF nm (|.| < 2^55), directions Q39 (unit = 2^39), t nm
 * (< 2^48: 281 km), grid Q16 as everywhere.
 */
#include "bend.h"
#include "tiles.h"
#include "fixed.h"

#define ONE16 INT64_C(65536)
#define KM_NM (INT64_C(1000) * 1000000000)
#define PIECE_FIRST_NM (4 * KM_NM)
#define PIECE_MAX_NM (30 * KM_NM)
#define PIECE_MIN_NM (INT64_C(20) * 1000000000)
#define TMAX_LIMIT_NM (INT64_C(1) << 48)
#define EARTH_MAX_PIECES 8192u
#define EARTH_MAX_RETRIES 8u

typedef struct {
    int64_t x, y, z;    /* Q16 grid (the walks' units)                       */
    int64_t fx, fy, fz; /* x, y, z with 8 more bits (Q24): the checks' and
                           the node polynomial's precision                  */
} gv;

/* The image is interpolated between n exact images at the Chebyshev-
 * Lobatto nodes of [0, tmax] (a polynomial of degree n - 1; sigma_j =
 * -cos(j pi / (n - 1)), the ends included): node 0 is the camera, whose
 * image is found once per call (ct_earth_setup: cam24), so a ray pays n - 1
 * images; n = 4 up to 35 km, 5 up to 130 km, 6 beyond (to 281 km).  Against
 * the fitted map's images (within 2 um of PROJ's) that stays within 0.02
 * mm (measured, docs/geolocation.md: these nodes' error is about twice the
 * Gauss-Chebyshev nodes' at the same n; the image's k-th derivative scales
 * as R^(1-k)).  The polynomial is kept per ray in powers of sigma = 2 t /
 * tmax - 1 in [-1, 1]: c = V^-1 X, V the nodes' Vandermonde matrix, V^-1
 * in Q40 (|entries| < 8, generated with mpmath at 60 digits); X the nodes'
 * images less node 0's in Q24, required below 2^46 (else every vertex is
 * computed exactly): c < 2^49, V^-1 X formed in 128 bits.  A vertex is
 * then Horner's rule in sigma (Q60): n - 1 products < 2^110 per
 * coordinate.  tau_j = (1 + sigma_j) / 2 in Q60 (tau_0 = 0, tau_(n-1) =
 * 1).  With a map fitted per call the polynomial comes instead from the
 * fit's derivatives at the camera and one or two images (taylor_nodes):
 * degree 4 up to 35 km, 5 up to 130 km, the same representation. */
#define NODES 6
#define NODES_4_NM (35 * KM_NM)
#define NODES_5_NM (130 * KM_NM)
static const int64_t tau_q60[3][NODES] = {
    {INT64_C(0), INT64_C(288230376151711744), INT64_C(864691128455135232), INT64_C(1152921504606846976), INT64_C(0),
     INT64_C(0)},
    {INT64_C(0), INT64_C(168841445261774044), INT64_C(576460752303423488), INT64_C(984080059345072932),
     INT64_C(1152921504606846976), INT64_C(0)},
    {INT64_C(0), INT64_C(110094207099786768), INT64_C(398324583251498512), INT64_C(754596921355348464),
     INT64_C(1042827297507060208), INT64_C(1152921504606846976)}};
static const int64_t vinv4_q40[4][4] = {
    {-INT64_C(183251937963), INT64_C(733007751851), INT64_C(733007751851), -INT64_C(183251937963)},
    {INT64_C(183251937963), -INT64_C(1466015503701), INT64_C(1466015503701), -INT64_C(183251937963)},
    {INT64_C(733007751851), -INT64_C(733007751851), -INT64_C(733007751851), INT64_C(733007751851)},
    {-INT64_C(733007751851), INT64_C(1466015503701), -INT64_C(1466015503701), INT64_C(733007751851)}};
static const int64_t vinv5_q40[5][5] = {
    {INT64_C(0), INT64_C(0), INT64_C(1099511627776), INT64_C(0), INT64_C(0)},
    {INT64_C(549755813888), -INT64_C(1554944255988), INT64_C(0), INT64_C(1554944255988), -INT64_C(549755813888)},
    {-INT64_C(549755813888), INT64_C(2199023255552), -INT64_C(3298534883328), INT64_C(2199023255552),
     -INT64_C(549755813888)},
    {-INT64_C(1099511627776), INT64_C(1554944255988), INT64_C(0), -INT64_C(1554944255988), INT64_C(1099511627776)},
    {INT64_C(1099511627776), -INT64_C(2199023255552), INT64_C(2199023255552), -INT64_C(2199023255552),
     INT64_C(1099511627776)}};
static const int64_t vinv6_q40[6][6] = {
    {INT64_C(109951162778), -INT64_C(271814222797), INT64_C(711618873907), INT64_C(711618873907),
     -INT64_C(271814222797), INT64_C(109951162778)},
    {-INT64_C(109951162778), INT64_C(335980856628), -INT64_C(2302847050035), INT64_C(2302847050035),
     -INT64_C(335980856628), INT64_C(109951162778)},
    {-INT64_C(1319413953331), INT64_C(3118289718424), -INT64_C(1798875765093), -INT64_C(1798875765093),
     INT64_C(3118289718424), -INT64_C(1319413953331)},
    {INT64_C(1319413953331), -INT64_C(3854418065511), INT64_C(5821284258918), -INT64_C(5821284258918),
     INT64_C(3854418065511), -INT64_C(1319413953331)},
    {INT64_C(1759218604442), -INT64_C(2846475495628), INT64_C(1087256891186), INT64_C(1087256891186),
     -INT64_C(2846475495628), INT64_C(1759218604442)},
    {-INT64_C(1759218604442), INT64_C(3518437208883), -INT64_C(3518437208883), INT64_C(3518437208883),
     -INT64_C(3518437208883), INT64_C(1759218604442)}};

static int64_t vinv(int n, int k, int j)
{
    return n == 4 ? vinv4_q40[k][j] : (n == 5 ? vinv5_q40[k][j] : vinv6_q40[k][j]);
}

typedef struct {
    const ct_package *p;
    const ct_earth *es;
    ct_utm zone;
    int64_t d[3];  /* direction, ECEF, Q39 */
    int64_t w[3];  /* refraction's bending direction, Q30 (0: none) */
    int refract;
    int interp;    /* 1: the nodes below are set */
    int alone;     /* 1: the fit's Taylor terms alone, no image (taylor_nodes) */
    int nodes;     /* coefficients: 4, 5 or 6 (Lobatto: the nodes) */
    int64_t tmax;
    int64_t tinv;  /* floor(2^(60 + tsh) / tmax), in (2^60, 2^61]    */
    unsigned tsh;  /* bit length of tmax                              */
    int64_t base[3];      /* image of node 0, Q24 (x, y) and Q24 height   */
    int64_t cf[NODES][3]; /* polynomial in sigma, Q24, lowest power first */
    int64_t b3z;          /* sum of j (j - 1) (j - 2) |c_j| of the height:
                             |z'''(sigma)| <= b3z on [-1, 1] (< 2^57)      */
    int64_t b1h, b2h, b3h; /* the same of x and y together (|c_j,x| +
                             |c_j,y|): |p^(k)(sigma)| <= bkh on [-1, 1] for
                             the horizontal image p (< 2^55, 2^57, 2^58)  */
} path;

/* round(v / 256) */
static int64_t q24_to_16(int64_t v)
{
    return ct_floor_div(v + 128, 256);
}

/* ---- the fitted map (CT_EFFECT_EARTH_FIT, ct_earth_map) -----------------
 * T_a(x_i) = cos(a (2i + 1) pi / 2m) in Q62 for m = deg + 1 points per
 * axis (generated with mpmath at 60 digits); row 1 holds the points x_i. */
static const int64_t cheb5_q62[5][5] = {
    {INT64_C(4611686018427387904), INT64_C(4611686018427387904), INT64_C(4611686018427387904),
     INT64_C(4611686018427387904), INT64_C(4611686018427387904)},
    {INT64_C(4385974038932618941), INT64_C(2710681029835013083), INT64_C(0), -INT64_C(2710681029835013083),
     -INT64_C(4385974038932618941)},
    {INT64_C(3730932361629093763), -INT64_C(1425089352415399811), -INT64_C(4611686018427387904),
     -INT64_C(1425089352415399811), INT64_C(3730932361629093763)},
    {INT64_C(2710681029835013083), -INT64_C(4385974038932618941), INT64_C(0), INT64_C(4385974038932618941),
     -INT64_C(2710681029835013083)},
    {INT64_C(1425089352415399811), -INT64_C(3730932361629093763), INT64_C(4611686018427387904),
     -INT64_C(3730932361629093763), INT64_C(1425089352415399811)}};
static const int64_t cheb6_q62[6][6] = {
    {INT64_C(4611686018427387904), INT64_C(4611686018427387904), INT64_C(4611686018427387904),
     INT64_C(4611686018427387904), INT64_C(4611686018427387904), INT64_C(4611686018427387904)},
    {INT64_C(4454546627935218059), INT64_C(3260954456333195553), INT64_C(1193592171602022505),
     -INT64_C(1193592171602022505), -INT64_C(3260954456333195553), -INT64_C(4454546627935218059)},
    {INT64_C(3993837246235628775), INT64_C(0), -INT64_C(3993837246235628775), -INT64_C(3993837246235628775),
     INT64_C(0), INT64_C(3993837246235628775)},
    {INT64_C(3260954456333195553), -INT64_C(3260954456333195553), -INT64_C(3260954456333195553),
     INT64_C(3260954456333195553), INT64_C(3260954456333195553), -INT64_C(3260954456333195553)},
    {INT64_C(2305843009213693952), -INT64_C(4611686018427387904), INT64_C(2305843009213693952),
     INT64_C(2305843009213693952), -INT64_C(4611686018427387904), INT64_C(2305843009213693952)},
    {INT64_C(1193592171602022505), -INT64_C(3260954456333195553), INT64_C(4454546627935218059),
     -INT64_C(4454546627935218059), INT64_C(3260954456333195553), -INT64_C(1193592171602022505)}};
static const int64_t cheb7_q62[7][7] = {
    {INT64_C(4611686018427387904), INT64_C(4611686018427387904), INT64_C(4611686018427387904),
     INT64_C(4611686018427387904), INT64_C(4611686018427387904), INT64_C(4611686018427387904),
     INT64_C(4611686018427387904)},
    {INT64_C(4496061421583520199), INT64_C(3605561316464170519), INT64_C(2000935573311439104), INT64_C(0),
     -INT64_C(2000935573311439104), -INT64_C(3605561316464170519), -INT64_C(4496061421583520199)},
    {INT64_C(4154985531143938469), INT64_C(1026196679933739317), -INT64_C(2875339201863983833),
     -INT64_C(4611686018427387904), -INT64_C(2875339201863983833), INT64_C(1026196679933739317),
     INT64_C(4154985531143938469)},
    {INT64_C(3605561316464170519), -INT64_C(2000935573311439104), -INT64_C(4496061421583520199), INT64_C(0),
     INT64_C(4496061421583520199), INT64_C(2000935573311439104), -INT64_C(3605561316464170519)},
    {INT64_C(2875339201863983833), -INT64_C(4154985531143938469), -INT64_C(1026196679933739317),
     INT64_C(4611686018427387904), -INT64_C(1026196679933739317), -INT64_C(4154985531143938469),
     INT64_C(2875339201863983833)},
    {INT64_C(2000935573311439104), -INT64_C(4496061421583520199), INT64_C(3605561316464170519), INT64_C(0),
     -INT64_C(3605561316464170519), INT64_C(4496061421583520199), -INT64_C(2000935573311439104)},
    {INT64_C(1026196679933739317), -INT64_C(2875339201863983833), INT64_C(4154985531143938469),
     -INT64_C(4611686018427387904), INT64_C(4154985531143938469), -INT64_C(2875339201863983833),
     INT64_C(1026196679933739317)}};
#define T_ONE_Q62 (INT64_C(1) << 62)

static int64_t cheb_at_node(int deg, int a, int i)
{
    return deg == 4 ? cheb5_q62[a][i] : (deg == 5 ? cheb6_q62[a][i] : cheb7_q62[a][i]);
}

/* f = round((v 2^fb - c) / |s|) with the sign of s folded into v and c,
 * 0 < |s| <= 2^50, |v| < 2^62, fb <= 32, |c| < 2^113: |v 2^fb| < 2^94; 0
 * when the quotient passes 2^55. */
static int rel_q(int64_t v, ct_i128 c, int64_t s, uint32_t fb, int64_t *f)
{
    ct_i128 num = ct_i128_sub(ct_i128_shl(ct_i128_from64(v), fb), c);
    if (s < 0) {
        num = ct_i128_neg(num);
        s = -s;
    }
    return ct_i128_round_div_lim(num, s, INT64_C(1) << 55, f);
}

/* The exact image of the ECEF point P (nm) in the grid frame less the
 * map's grid point g16, with fb[k] fraction bits per axis (26 .. 32): f =
 * (e - e0) 2^fb / pe - (gx 2^(fb - 16) + 2^(fb - 1)) (as ct_map_to_grid
 * with fb - 16 more bits), likewise n, and (h - h0) 2^fb / hs - gz 2^(fb -
 * 16).  CT_ERR_RANGE when |f| > 2^55. */
static ct_status image_rel(const ct_package *p, const ct_utm *zone, const ct_earth_map *mp, const int64_t P[3],
                           int64_t f[3])
{
    int64_t lat, lon, h, e, n;
    ct_status st = ct_wgs84_from_ecef(P, &lat, &lon, &h);
    if (st == CT_OK) {
        st = ct_utm_forward(zone, lat, lon, &e, &n);
    }
    if (st != CT_OK) {
        return st;
    }
    if (ct_abs64(e) > (INT64_C(1) << 60) || ct_abs64(n) > (INT64_C(1) << 60) || ct_abs64(h) > (INT64_C(1) << 60)) {
        return CT_ERR_RANGE;
    }
    /* the origin and offset are the package's (|.| <= 2^61, checked at
     * open), so the differences stay below 2^62; |g16| <= 2^46 (set-up):
     * (g 2^(fb - 16) + 2^(fb - 1)) |pe| < 2^63 2^50 */
    if (!rel_q(e - p->origin_e_nm,
               ct_i128_mul(mp->g16[0] * (INT64_C(1) << (mp->fb[0] - 16u)) + (INT64_C(1) << (mp->fb[0] - 1u)),
                           p->posting_e_nm),
               p->posting_e_nm, mp->fb[0], &f[0]) ||
        !rel_q(n - p->origin_n_nm,
               ct_i128_mul(mp->g16[1] * (INT64_C(1) << (mp->fb[1] - 16u)) + (INT64_C(1) << (mp->fb[1] - 1u)),
                           p->posting_n_nm),
               p->posting_n_nm, mp->fb[1], &f[1]) ||
        !rel_q(h - p->height_offset_nm, ct_i128_mul(mp->g16[2] * (INT64_C(1) << (mp->fb[2] - 16u)), p->height_scale_nm),
               p->height_scale_nm, mp->fb[2], &f[2])) {
        return CT_ERR_RANGE;
    }
    return CT_OK;
}

/* round(v / 2^n) = floor((v + 2^(n-1)) / 2^n), 1 <= n <= 62, |v| < 2^62
 * (the sum cannot wrap): by unsigned shifts of the sum and of its
 * complement when negative (floor(x / m) = -floor((-x - 1) / m) - 1), as
 * ct_i128_round_shr -- no division, no shift of a negative value. */
static int64_t rshr64(int64_t v, unsigned n)
{
    uint64_t u = (uint64_t)v + ((uint64_t)1 << (n - 1u));
    uint64_t neg = (u >> 63) != 0u ? ~(uint64_t)0 : 0u;
    return (int64_t)(((u ^ neg) >> n) ^ neg);
}

/* round(x y / 2^62) for |x|, |y| <= 2^62 + 2^8, skipping the product when
 * a factor is exactly one (T_0, or T_n(s) = 1): the same value, no
 * multiplication. */
static int64_t mul62(int64_t x, int64_t y)
{
    return x == T_ONE_Q62 ? y : (y == T_ONE_Q62 ? x : ct_mul_shr(x, y, 62u));
}

/* The map's terms T_a(s_x) T_b(s_y) T_c(s_z), a + b + c <= deg, in the order
 * the coefficients are stored: by total degree, then a, then b (the first
 * n(deg) = (deg + 1)(deg + 2)(deg + 3) / 6 entries are those of degree <=
 * deg: 35, 56, 84 for deg 4, 5, 6).  deg_start[k]: the first term of
 * degree k. */
static const uint8_t term_abc[CT_EARTH_MAP_TERMS][3] = {
    {0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1, 0, 0}, {0, 0, 2}, {0, 1, 1}, {0, 2, 0}, {1, 0, 1}, {1, 1, 0}, {2, 0, 0},
    {0, 0, 3}, {0, 1, 2}, {0, 2, 1}, {0, 3, 0}, {1, 0, 2}, {1, 1, 1}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}, {3, 0, 0},
    {0, 0, 4}, {0, 1, 3}, {0, 2, 2}, {0, 3, 1}, {0, 4, 0}, {1, 0, 3}, {1, 1, 2}, {1, 2, 1}, {1, 3, 0}, {2, 0, 2},
    {2, 1, 1}, {2, 2, 0}, {3, 0, 1}, {3, 1, 0}, {4, 0, 0}, {0, 0, 5}, {0, 1, 4}, {0, 2, 3}, {0, 3, 2}, {0, 4, 1},
    {0, 5, 0}, {1, 0, 4}, {1, 1, 3}, {1, 2, 2}, {1, 3, 1}, {1, 4, 0}, {2, 0, 3}, {2, 1, 2}, {2, 2, 1}, {2, 3, 0},
    {3, 0, 2}, {3, 1, 1}, {3, 2, 0}, {4, 0, 1}, {4, 1, 0}, {5, 0, 0}, {0, 0, 6}, {0, 1, 5}, {0, 2, 4}, {0, 3, 3},
    {0, 4, 2}, {0, 5, 1}, {0, 6, 0}, {1, 0, 5}, {1, 1, 4}, {1, 2, 3}, {1, 3, 2}, {1, 4, 1}, {1, 5, 0}, {2, 0, 4},
    {2, 1, 3}, {2, 2, 2}, {2, 3, 1}, {2, 4, 0}, {3, 0, 3}, {3, 1, 2}, {3, 2, 1}, {3, 3, 0}, {4, 0, 2}, {4, 1, 1},
    {4, 2, 0}, {5, 0, 1}, {5, 1, 0}, {6, 0, 0}};
static const uint8_t deg_start[CT_EARTH_MAP_DEG + 2] = {0, 1, 4, 10, 20, 35, 56, 84};

/* The fitted image of c + D (|D| <= 2^qrho per axis, checked by the
 * caller), Q24: the base plus the sum of cf T_a(s_x) T_b(s_y) T_c(s_z), s
 * = D / 2^qrho.
 *   - Terms of total degree <= 2 (the large ones: up to 2^56 for the
 *     linear, rho^2 / R for the quadratic): T in Q62 (T_2 = 2 s^2 - 1), a
 *     product of three < 2^62, times cf (< 2^56): < 2^118, in 128 bits.
 *   - Degree k >= 3 (at most rho^3 / R^2, 69 m at 141 km): cf stored as
 *     cf' = round(cf / 2^sh[k]) with |cf'| <= 2^27 (fit_map), T in Q30 by
 *     the recurrence T_(n+1) = 2 s T_n - T_(n-1) (|T| <= 1 + 2^-26), each
 *     term cf' T T T < 2^57.1 in 64 bits; a degree's <= 28 terms sum below
 *     2^62, then times 2^(32 + sh[k]) (sh <= 29: < 2^123) into the 128-bit
 *     sum.
 *   The sum (Q(fb + 60), < 2^125) is rounded once to Q24.  The rounding of
 *   cf' (2^(sh - 1) per term) costs under 2 um at 141 km (fit_map).  The
 *   terms run in their stored order (term_abc), one flat loop per degree.
 * Out of line: its 0.9 KB frame (M0) would otherwise join vertex_exact's
 * on the true Earth's deepest path. */
CT_NOINLINE static void fit_eval(const ct_earth_map *mp, const int64_t D[3], int64_t g[3])
{
    int64_t T[3][3], U[3][CT_EARTH_MAP_DEG + 1], V[CT_EARTH_MAP_DEG + 1][CT_EARTH_MAP_DEG + 1];
    ct_i128 acc[3];
    int k, o, t, deg = mp->deg;
    unsigned q = mp->qrho;
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        int n;
        T[k][0] = T_ONE_Q62;
        T[k][1] = D[k] * (INT64_C(1) << (62u - q)); /* |D| <= 2^qrho */
        T[k][2] = ct_mul_shr(T[k][1], T[k][1], 61u) - T_ONE_Q62;
        U[k][0] = INT64_C(1) << 30;
        U[k][1] = rshr64(D[k], q - 30u); /* |.| <= 2^30 */
        for (n = 1; n < deg; ++n) { /* bound: CT_EARTH_MAP_DEG - 1; |2 U_1 U_n| < 2^62 */
            U[k][n + 1] = rshr64(2 * U[k][1] * U[k][n], 30u) - U[k][n - 1];
        }
        acc[k] = ct_i128_from64(0);
    }
    for (t = 0; t < deg_start[3]; ++t) { /* bound: 10 terms of degree <= 2 */
        const uint8_t *e = term_abc[t];
        int64_t ttt = mul62(mul62(T[0][e[0]], T[1][e[1]]), T[2][e[2]]);
        acc[0] = ct_i128_add(acc[0], ct_i128_mul(mp->cf[t][0], ttt));
        acc[1] = ct_i128_add(acc[1], ct_i128_mul(mp->cf[t][1], ttt));
        acc[2] = ct_i128_add(acc[2], ct_i128_mul(mp->cf[t][2], ttt));
    }
    /* V[a][b] = round(U_a(s_x) U_b(s_y) / 2^30) for a + b <= deg (|U| <=
     * 2^30 + 2^8: products < 2^61, |V| <= 2^30 + 2^9).  U, V, the terms
     * (<= 2^30 + 2^10) and cf' (<= 2^27) all fit 32 bits: their products
     * are 32 x 32 -> 64-bit ones (ct_smul32) */
    for (t = 0; t <= deg; ++t) {         /* bound: CT_EARTH_MAP_DEG + 1 */
        for (k = 0; t + k <= deg; ++k) { /* bound: CT_EARTH_MAP_DEG + 1 */
            V[t][k] = rshr64(ct_smul32(U[0][t], U[1][k]), 30u);
        }
    }
    for (k = 3; k <= deg; ++k) { /* bound: CT_EARTH_MAP_DEG - 2 */
        int64_t s0 = 0, s1 = 0, s2 = 0;
        const int64_t(*cf)[3] = &mp->cf[deg_start[k]];
        int ea, eb;
        /* term_abc's order within a degree: a, then b (c = k - a - b) */
        for (ea = 0; ea <= k; ++ea) {          /* bound: CT_EARTH_MAP_DEG + 1 */
            for (eb = 0; ea + eb <= k; ++eb) { /* bound: CT_EARTH_MAP_DEG + 1 */
                int64_t ttt = rshr64(ct_smul32(V[ea][eb], U[2][k - ea - eb]), 30u);
                s0 += ct_smul32(cf[0][0], ttt);
                s1 += ct_smul32(cf[0][1], ttt);
                s2 += ct_smul32(cf[0][2], ttt);
                cf++;
            }
        }
        acc[0] = ct_i128_add(acc[0], ct_i128_shl(ct_i128_from64(s0), 32u + mp->sh[k][0]));
        acc[1] = ct_i128_add(acc[1], ct_i128_shl(ct_i128_from64(s1), 32u + mp->sh[k][1]));
        acc[2] = ct_i128_add(acc[2], ct_i128_shl(ct_i128_from64(s2), 32u + mp->sh[k][2]));
    }
    for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
        g[o] = mp->g16[o] * 256 + ct_i128_round_shr(acc[o], 36u + mp->fb[o]);
    }
}

/* The fit through the exact images at the (deg + 1)^3 Chebyshev points of
 * the cube: c_abc = (2/m)^3 g_a g_b g_c sum_ijk f_ijk T_a(x_i) T_b(x_j)
 * T_c(x_k), m = deg + 1, g_0 = 1/2 and 1 otherwise, f the images less the
 * centre's grid point g16 with fb fraction bits (|f| <= 2^55, else no fit:
 * image_rel).  Each term f T T T / 2^64 (Q(fb - 2)) < 2^53, the sum over
 * <= 343 points < 2^61.5, kept in the coefficient array itself; then times
 * 8 g_a g_b g_c / m^3 (in 128 bits): |c| <= 8 max|f| / 4 < 2^56.  The
 * samples' rounding (2^-33 of a cell or height unit) reaches the fit
 * amplified by the interpolation's Lebesgue constant (< 12 for degree 6):
 * far below a micrometre.  Leaves deg = 0 when a point is outside the
 * projection's domain or too far. */
static void fit_map(const ct_package *p, const ct_utm *zone, ct_earth_map *mp, uint32_t qrho)
{
    int deg = qrho <= 44u ? 4 : (qrho <= 46u ? 5 : 6); /* 1.7, 1.0, 13 and 14 um off PROJ (test_earth) */
    int m = deg + 1, nt = deg_start[deg + 1], i, j, k, t, o;
    mp->ready = 0u;
    mp->deg = 0;
    mp->qrho = qrho;
    /* fraction bits: the images lie within 2^(qrho + 1) nm of the centre's
     * (the cube's half-diagonal sqrt(3) 2^qrho, stretched by at most 1 %
     * by the projection), so |f| <= 2^(qrho + 1 + fb) / scale <= 2^55 for
     * fb = 54 - qrho + floor(log2 scale), at most 32; below 26 no fit */
    for (o = 0; o < 3; ++o) { /* bound: 3 axes */
        int64_t sc = ct_abs64(o == 0 ? p->posting_e_nm : (o == 1 ? p->posting_n_nm : p->height_scale_nm));
        int fb = 54 - (int)qrho + (int)ct_bitlen64((uint64_t)sc) - 1;
        if (fb < 26) {
            return;
        }
        mp->fb[o] = fb > 32 ? 32u : (uint32_t)fb;
    }
    for (t = 0; t < CT_EARTH_MAP_TERMS; ++t) { /* bound: CT_EARTH_MAP_TERMS */
        mp->cf[t][0] = mp->cf[t][1] = mp->cf[t][2] = 0;
    }
    for (i = 0; i < m; ++i) {             /* bound: CT_EARTH_MAP_DEG + 1 */
        for (j = 0; j < m; ++j) {         /* bound: CT_EARTH_MAP_DEG + 1 */
            /* T_a(x_i) T_b(x_j), a + b <= deg, once per (i, j) */
            int64_t tab[CT_EARTH_MAP_DEG + 1][CT_EARTH_MAP_DEG + 1];
            int a, b;
            for (a = 0; a <= deg; ++a) {         /* bound: CT_EARTH_MAP_DEG + 1 */
                for (b = 0; a + b <= deg; ++b) { /* bound: CT_EARTH_MAP_DEG + 1 */
                    tab[a][b] = ct_mul_shr(cheb_at_node(deg, a, i), cheb_at_node(deg, b, j), 62u);
                }
            }
            for (k = 0; k < m; ++k) {     /* bound: CT_EARTH_MAP_DEG + 1 */
                int64_t P[3], f[3];
                /* the point: c + 2^qrho x (|x| <= 2^62 in Q62) */
                P[0] = mp->c[0] + ct_mul_shr(cheb_at_node(deg, 1, i), INT64_C(1) << qrho, 62u);
                P[1] = mp->c[1] + ct_mul_shr(cheb_at_node(deg, 1, j), INT64_C(1) << qrho, 62u);
                P[2] = mp->c[2] + ct_mul_shr(cheb_at_node(deg, 1, k), INT64_C(1) << qrho, 62u);
                if (image_rel(p, zone, mp, P, f) != CT_OK) {
                    return;
                }
                for (t = 0; t < nt; ++t) { /* bound: CT_EARTH_MAP_TERMS */
                    const uint8_t *e = term_abc[t];
                    int64_t ttt = ct_mul_shr(tab[e[0]][e[1]], cheb_at_node(deg, e[2], k), 62u);
                    for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
                        mp->cf[t][o] += ct_i128_round_shr(ct_i128_mul(f[o], ttt), 64u);
                    }
                }
            }
        }
    }
    for (t = 0; t < nt; ++t) { /* bound: CT_EARTH_MAP_TERMS */
        /* 8 g_a g_b g_c = 2^(3 - zeros) */
        const uint8_t *e = term_abc[t];
        unsigned sh = 3u - (unsigned)((e[0] == 0u) + (e[1] == 0u) + (e[2] == 0u));
        for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
            mp->cf[t][o] = ct_i128_round_div(ct_i128_shl(ct_i128_from64(mp->cf[t][o]), sh), (int64_t)(m * m * m));
        }
    }
    /* degrees >= 3: cf' = round(cf / 2^sh) with sh the least making every
     * |cf'| < 2^27 (per degree and coordinate; sh <= 29 as |cf| < 2^56) */
    for (k = 3; k <= deg; ++k) { /* bound: CT_EARTH_MAP_DEG - 2 */
        for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
            int64_t mx = 0;
            unsigned sh = 0u;
            for (t = deg_start[k]; t < deg_start[k + 1]; ++t) { /* bound: 28 terms of degree k */
                mx = ct_max64(mx, ct_abs64(mp->cf[t][o]));
            }
            /* bound: 30 halvings */
            while ((mx >> sh) >= (INT64_C(1) << 27)) {
                sh++;
            }
            mp->sh[k][o] = sh;
            for (t = deg_start[k]; t < deg_start[k + 1] && sh > 0u; ++t) { /* bound: 28 terms of degree k */
                mp->cf[t][o] = rshr64(mp->cf[t][o], sh);
            }
        }
    }
    for (o = 0; o < 3; ++o) { /* bound: 3 coordinates (degrees < 3 unscaled) */
        mp->sh[0][o] = mp->sh[1][o] = mp->sh[2][o] = 0u;
    }
    mp->georef[0] = p->origin_e_nm;
    mp->georef[1] = p->origin_n_nm;
    mp->georef[2] = p->posting_e_nm;
    mp->georef[3] = p->posting_n_nm;
    mp->georef[4] = p->height_offset_nm;
    mp->georef[5] = p->height_scale_nm;
    mp->georef[6] = (int64_t)p->epsg;
    mp->deg = deg;
    mp->ready = CT_EARTH_MAP_READY;
}

int ct_earth_map_fits(const ct_package *p, const ct_earth_map *mp)
{
    return p != NULL && mp != NULL && mp->ready == CT_EARTH_MAP_READY && mp->deg >= 4 &&
           mp->deg <= CT_EARTH_MAP_DEG && mp->qrho >= 44u && mp->qrho <= 47u && mp->georef[0] == p->origin_e_nm &&
           mp->georef[1] == p->origin_n_nm && mp->georef[2] == p->posting_e_nm && mp->georef[3] == p->posting_n_nm &&
           mp->georef[4] == p->height_offset_nm && mp->georef[5] == p->height_scale_nm &&
           mp->georef[6] == (int64_t)p->epsg;
}

/* The coefficient of s^k in T_n (n, k <= 6). */
static const int8_t cheb_pow[CT_EARTH_MAP_DEG + 1][CT_EARTH_MAP_DEG + 1] = {
    {1, 0, 0, 0, 0, 0, 0},  {0, 1, 0, 0, 0, 0, 0},   {-1, 0, 2, 0, 0, 0, 0},   {0, -3, 0, 4, 0, 0, 0},
    {1, 0, -8, 0, 8, 0, 0}, {0, 5, 0, -20, 0, 16, 0}, {-1, 0, 18, 0, -48, 0, 32}};

/* For the quartic terms 20..34 of term_abc: the product of the leading
 * power coefficients 2^(n - 1) of their Chebyshev factors T_n (n >= 1,
 * cheb_pow[n][n]), as a power of 2: the degree less the nonzero exponents.
 * Only a fit's own terms of degree 4 have quartic monomials, so its quartic
 * power coefficients are these times cf 2^sh (map_taylor, taylor_quartic). */
static const uint8_t quart_lead[15] = {3, 2, 2, 2, 3, 2, 1, 1, 2, 2, 1, 2, 2, 2, 3};

/* The fit's Taylor terms of degrees 1..3 at the cube's centre (s = 0), and
 * of degree 4 for a fit of degree 4 (taylor_alone): for each such term
 * s^alpha (term_abc 1..19, 20..34), the sum over the fit's terms of cf 2^sh
 * C_a C_b C_c, C the power coefficients of its Chebyshev factors (exact integers: |cf 2^sh| < 2^56, |C C C| <= 48^3 <
 * 2^17, <= 56 terms: < 2^80 in 128 bits), kept in cf[tay_row(t)]: rows
 * TAY0 .. for degrees 1..3 (a fit of degree <= 5 uses cf[0 .. 55] only: no
 * stack for them), TAY4 .. for degree 4 (a degree-4 fit uses cf[0 .. 34]).
 * 0 for degree 6, or when one reaches 2^58 (taylor_nodes' range). */
#define TAY0 56
#define TAY4 35 /* a degree-4 fit's terms of degree 4 (term_abc 20..34) */
#define TAY_S 50 /* then taylor_alone's magnitudes and range flag (3 rows) */
static int tay_row(int t)
{
    return t < 20 ? TAY0 + t - 1 : TAY4 + t - 20;
}

static int map_taylor(ct_earth_map *mp)
{
    int t, u, o, nt = deg_start[mp->deg + 1];
    if (mp->deg > 5) {
        return 0;
    }
    for (t = 1; t < 20; ++t) { /* bound: 19 terms */
        const uint8_t *e = term_abc[t];
        for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
            ct_i128 acc = ct_i128_from64(0);
            for (u = 0; u < nt; ++u) { /* bound: CT_EARTH_MAP_TERMS */
                const uint8_t *f = term_abc[u];
                int64_t cc = (int64_t)cheb_pow[f[0]][e[0]] * cheb_pow[f[1]][e[1]] * cheb_pow[f[2]][e[2]];
                int k = f[0] + f[1] + f[2];
                if (cc != 0) {
                    /* cc 2^sh < 2^46 */
                    acc = ct_i128_add(acc, ct_i128_mul(mp->cf[u][o], k >= 3 ? cc * (INT64_C(1) << mp->sh[k][o]) : cc));
                }
            }
            if (ct_i128_cmp(ct_i128_abs(acc), ct_i128_from64(INT64_C(1) << 58)) >= 0) {
                return 0;
            }
            mp->cf[tay_row(t)][o] = ct_i128_to64(acc);
        }
    }
    if (mp->deg == 4) {
        /* its terms of degree 4 (in cf[TAY4 ..], which it leaves unused: nt
         * = 35): only its own Chebyshev term of degree 4 has a monomial of
         * that degree, so each is cf 2^sh times the leading power
         * coefficients 2^(n - 1) of its factors T_n (n >= 1): |cf 2^sh| <
         * 2^56, times at most 2^3 */
        int big = 0;
        for (t = 20; t < 35; ++t) { /* bound: 15 terms */
            for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
                int64_t v = mp->cf[t][o] * (INT64_C(1) << (quart_lead[t - 20] + mp->sh[4][o]));
                if (ct_abs64(v) >= (INT64_C(1) << 58)) {
                    return 0;
                }
                mp->cf[tay_row(t)][o] = v;
            }
        }
        /* taylor_alone's bound: per coordinate S4 = sum |G_4's terms| in
         * cf[TAY_S][o] (< 15 2^58), ceil((S2 + 4 S3) / 2) in cf[TAY_S +
         * 1][o] (S2 < 6 2^58, S3 < 10 2^58: the sum < 2^63.4, half < 2^63).
         * Its 64-bit sums take quartic terms below 2^27 and cubic ones below
         * 2^35: cf[TAY_S + 2][0] is 1 when a term exceeds that (the image
         * then), else 0.  The quartic terms are about (rho / R)^3 of the
         * image's extent, which fit_map keeps below 2^55 in these units, so
         * that takes postings below about 0.5 mm */
        for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
            uint64_t s2 = 0u, s3 = 0u, s4 = 0u;
            for (t = 4; t < 35; ++t) { /* bound: 31 terms of degrees 2..4 */
                uint64_t v = (uint64_t)ct_abs64(mp->cf[tay_row(t)][o]);
                if (t < 10) {
                    s2 += v;
                } else if (t < 20) {
                    s3 += v;
                    big |= v >= (UINT64_C(1) << 35);
                } else {
                    s4 += v;
                    big |= v >= (UINT64_C(1) << 27);
                }
            }
            mp->cf[TAY_S][o] = (int64_t)s4;
            mp->cf[TAY_S + 1][o] = (int64_t)((s2 + 4u * s3 + 1u) >> 1);
        }
        mp->cf[TAY_S + 2][0] = big;
    }
    return 1;
}

/* the least q in [44, 47] with 2^q >= need; 48 when none */
static uint32_t cube_q(int64_t need)
{
    uint32_t q = 44u;
    /* bound: 4 sizes */
    while (q < 48u && (INT64_C(1) << q) < need) {
        q++;
    }
    return q;
}

ct_status ct_earth_map_init(const ct_package *p, int64_t e_nm, int64_t n_nm, int64_t h_nm, int64_t radius_nm,
                            ct_earth_map *mp)
{
    ct_utm zone;
    int64_t lat, lon;
    int32_t frame[9];
    uint32_t q;
    ct_status st;
    if (p == NULL || mp == NULL) {
        return CT_ERR_ARG;
    }
    mp->ready = 0u;
    mp->deg = 0;
    if (ct_package_zone(p, &zone) != CT_OK) {
        return CT_ERR_CRS;
    }
    q = cube_q(radius_nm);
    if (radius_nm <= 0 || q > 47u || ct_abs64(h_nm) > (INT64_C(1) << 50)) {
        return CT_ERR_RANGE;
    }
    st = ct_grid_frame_ecef(&zone, e_nm, n_nm, &lat, &lon, frame);
    if (st == CT_OK) {
        st = ct_ecef_from_wgs84(lat, lon, h_nm, mp->c);
    }
    if (st != CT_OK || ct_map_to_grid(p, e_nm, n_nm, h_nm, &mp->g16[0], &mp->g16[1], &mp->g16[2]) != CT_OK ||
        ct_abs64(mp->g16[0]) > CT_MAX_ORIGIN_Q16 || ct_abs64(mp->g16[1]) > CT_MAX_ORIGIN_Q16 ||
        ct_abs64(mp->g16[2]) > CT_MAX_ORIGIN_Q16) {
        return CT_ERR_RANGE;
    }
    fit_map(p, &zone, mp, q);
    return mp->deg > 0 ? CT_OK : CT_ERR_RANGE;
}

#if CT_TEST_HOOKS
ct_status ct_earth_image24(const ct_package *p, const ct_earth *es, const int64_t D[3], int fitted, int64_t g[3])
{
    int64_t P[3], f[3], Dm[3];
    int k, in = fitted && es->map != NULL;
    ct_status st;
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        if (ct_abs64(D[k]) > (INT64_C(1) << 50)) {
            return CT_ERR_RANGE;
        }
        P[k] = es->c[k] + D[k];
        Dm[k] = D[k] + es->moff[k]; /* |moff| <= 2^50 (set-up) */
        in = in && ct_abs64(Dm[k]) <= (INT64_C(1) << es->map->qrho);
    }
    if (in) {
        fit_eval(es->map, Dm, g);
        return CT_OK;
    }
    if (fitted) {
        return CT_ERR_RANGE;
    }
    {
        /* exact, relative to the camera's grid point with 32 fraction bits
         * (image_rel reads g16 and fb only) */
        ct_earth_map rel;
        rel.g16[0] = es->ox;
        rel.g16[1] = es->oy;
        rel.g16[2] = es->oz;
        rel.fb[0] = rel.fb[1] = rel.fb[2] = 32u;
        st = image_rel(p, &es->zone, &rel, P, f);
        for (k = 0; k < 3 && st == CT_OK; ++k) { /* bound: 3 axes */
            g[k] = rel.g16[k] * 256 + ct_i128_round_shr(ct_i128_from64(f[k]), 8u);
        }
    }
    return st;
}
#endif

/* The bend of refraction at range t, nm: k t^2 / 2R (t < 2^48, t^2 <
 * 2^96, |k| <= 2^17: < 2^113; / 2R (>= 2^41) leaves < 2^72 -- saturated
 * at 2^62, then / 2^16). */
static int64_t bend_at(const ct_earth *es, int64_t t)
{
    ct_i128 num = ct_i128_mul128_64(ct_umul64((uint64_t)t, (uint64_t)t), es->refr_k_q16);
    return ct_floor_div(ct_i128_floor_div_sat(num, 2 * es->radius_nm), ONE16);
}

/* The image of P(t) in the grid frame: exact, or by the fitted map when
 * there is one and P is in its cube. */
static ct_status vertex_exact(const path *pa, int64_t t, gv *v)
{
    int64_t D[3], Dm[3], g[3], bend = 0;
    int k, in = pa->es->map != NULL;
    ct_status st;
    if (pa->refract) {
        bend = bend_at(pa->es, t);
    }
    /* bound: 3 axes.  t d: < 2^48 2^40 = 2^88 (128-bit) / 2^39; bend w:
     * < 2^46 2^31 / 2^30 */
    for (k = 0; k < 3; ++k) {
        D[k] = ct_mul_shr(t, pa->d[k], 39u);
        if (pa->refract) {
            D[k] -= ct_mul_shr(bend, pa->w[k], 30u);
        }
        Dm[k] = D[k] + pa->es->moff[k]; /* |D| < 2^49, |moff| <= 2^50 */
        in = in && ct_abs64(Dm[k]) <= (INT64_C(1) << pa->es->map->qrho);
    }
    if (in) {
        fit_eval(pa->es->map, Dm, g);
        v->fx = g[0];
        v->fy = g[1];
        v->fz = g[2];
        v->x = q24_to_16(g[0]);
        v->y = q24_to_16(g[1]);
        v->z = q24_to_16(g[2]);
        return CT_OK;
    }
    {
        int64_t P[3], lat, lon, h, e, n;
        for (k = 0; k < 3; ++k) { /* bound: 3 axes */
            P[k] = pa->es->c[k] + D[k];
        }
        st = ct_wgs84_from_ecef(P, &lat, &lon, &h);
        if (st == CT_OK) {
            st = ct_utm_forward(&pa->zone, lat, lon, &e, &n);
        }
        if (st == CT_OK) {
            st = ct_map_to_grid(pa->p, e, n, h, &v->x, &v->y, &v->z);
        }
    }
    /* |x|, |y| < 2^55 (ct_map_to_grid's range) */
    v->fx = v->x * 256;
    v->fy = v->y * 256;
    v->fz = v->z * 256;
    return st;
}

/* A node's image for the path's polynomial: P(t)'s less the camera's (the
 * polynomial's base), Q24, in X; 0 when it cannot be found or passes
 * 2^46 (the polynomial's range: its coefficients then stay below 2^49). */
static int node_image(const path *pa, int64_t t, int64_t X[3])
{
    gv v;
    int k;
    if (vertex_exact(pa, t, &v) != CT_OK) {
        return 0;
    }
    X[0] = v.fx - pa->es->cam24[0];
    X[1] = v.fy - pa->es->cam24[1];
    X[2] = v.fz - pa->es->cam24[2];
    for (k = 0; k < 3; ++k) { /* bound: 3 coordinates */
        if (ct_abs64(X[k]) >= (INT64_C(1) << 46)) {
            return 0;
        }
    }
    return 1;
}

/* The image of P(t), 0 <= t <= tmax: interpolated when the nodes are set. */
CT_NOINLINE static ct_status vertex(const path *pa, int64_t t, gv *v)
{
    int64_t sig, r[3];
    int j, k;
    if (!pa->interp) {
        return vertex_exact(pa, t, v);
    }
    /* sigma = (2t - tmax) 2^60 / tmax (within 2 units): |2t - tmax| <=
     * tmax < 2^49, times tinv <= 2^61: < 2^110 */
    sig = ct_i128_to64(ct_i128_sar(ct_i128_mul(2 * t - pa->tmax, pa->tinv), pa->tsh));
    for (k = 0; k < 3; ++k) { /* bound: 3 coordinates */
        int64_t acc = pa->cf[pa->nodes - 1][k];
        for (j = pa->nodes - 2; j >= 0; --j) { /* bound: NODES - 1 */
            acc = pa->cf[j][k] + ct_mul_shr(sig, acc, 60u);
        }
        r[k] = pa->base[k] + acc;
    }
    v->fx = r[0];
    v->fy = r[1];
    v->fz = r[2];
    v->x = q24_to_16(r[0]);
    v->y = q24_to_16(r[1]);
    v->z = q24_to_16(r[2]);
    return CT_OK;
}

/* The bounds of the path's derivatives from its polynomial (|c| < 2^49,
 * k (k-1) (k-2) <= 60). */
static void path_bounds(path *pa)
{
    int k;
    pa->b3z = pa->b1h = pa->b2h = pa->b3h = 0;
    for (k = 1; k < pa->nodes; ++k) { /* bound: NODES - 1 */
        int64_t ch = ct_abs64(pa->cf[k][0]) + ct_abs64(pa->cf[k][1]);
        pa->b1h += (int64_t)k * ch;
        pa->b2h += (int64_t)(k * (k - 1)) * ch;
        pa->b3h += (int64_t)(k * (k - 1) * (k - 2)) * ch;
        pa->b3z += (int64_t)(k * (k - 1) * (k - 2)) * ct_abs64(pa->cf[k][2]);
    }
}

/* For the terms 4..19 of term_abc (degrees 2 and 3): the term whose
 * monomial times s along tay_axis is this one's (for a quadratic term e_i +
 * e_j, i = tay_axis, the parent is e_j, term 3 - j). */
static const uint8_t tay_parent[20] = {0, 0, 0, 0, 1, 1, 2, 1, 2, 3, 4, 4, 5, 6, 4, 5, 6, 7, 8, 9};
static const uint8_t tay_axis[20] = {0, 0, 0, 0, 2, 1, 1, 0, 0, 0, 2, 1, 1, 1, 0, 0, 0, 0, 0, 0};

/* binom(k, j) for k <= 5 */
static const uint8_t binom5[6][6] = {{1, 0, 0, 0, 0, 0},  {1, 1, 0, 0, 0, 0},  {1, 2, 1, 0, 0, 0},
                                     {1, 3, 3, 1, 0, 0},  {1, 4, 6, 4, 1, 0},  {1, 5, 10, 10, 5, 1}};

/* For the terms 20..34 of term_abc (degree 4): the degree-3 term whose
 * monomial times s along quart_axis is this one's; for the terms 10..19
 * (degree 3): per axis i the degree-2 term alpha - e_i (0: alpha_i = 0). */
static const uint8_t quart_parent[15] = {10, 10, 11, 12, 13, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19};
static const uint8_t quart_axis[15] = {2, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
static const uint8_t cub_less[10][3] = {{0, 0, 4}, {0, 4, 5}, {0, 5, 6}, {0, 6, 0}, {4, 0, 7},
                                        {5, 7, 8}, {6, 8, 0}, {7, 0, 9}, {8, 9, 0}, {9, 0, 0}};

/* The quartic monomial a^alpha of term 20 + t (Q30) from its cubic parent
 * in am (Q62) and a in Q30 (aq): |.| <= 2^30 + 2. */
CT_OPT_INLINE static inline int64_t quart_mono(const int64_t am[20], const int64_t aq[3], int t)
{
    /* both factors <= 2^30 + 2: ct_smul32 */
    return rshr64(ct_smul32(rshr64(am[quart_parent[t]], 32u), aq[quart_axis[t]]), 30u);
}

/* The quartic Taylor term of a degree-4 fit along x(tau) = tau a - tau^2 b
 * (taylor_nodes, which gives a, b and am, the monomials a^alpha of degrees
 * 1..3, Q62; |b| <= 2^53 per axis, else 0): p4 = G_4(a) - E_31 into p[4]
 * (Q30; the sums Q(fb + 60)).  What it leaves out, E_22 = G_2(b) in tau^4
 * and the terms of degree 5 and more in tau (E_4l, l >= 1, and E_3l, l >=
 * 2), is with every |a^alpha| <= 1 at most |b|^2 S2 + |b| (4 + 6 |b| + 4
 * |b|^2 + |b|^3) S4 + |b|^2 (3 + |b|) S3 <= |b|^2 (S2 + 4 S3) + 5 |b| S4
 * (|b| <= 2^-9), S_k the sum of |G_k|'s coefficients; 0 (the images then)
 * when that could reach 2 um (2^11 nm) for a coordinate -- the path with an
 * image is within 5.4 um of the fit's images (taylor_nodes) -- or when the
 * terms exceed its 64-bit sums' range (map_taylor).  Out of line: its
 * monomials are not on the stack while the images are found. */
CT_NOINLINE static int taylor_alone(const ct_package *pk, const ct_earth_map *mp, const int64_t a[3], const int64_t b[3],
                                    const int64_t am[20], int64_t p[6][3])
{
    /* In 64 bits, as fit_eval's terms of degree >= 3: the monomials in Q30
     * (|.| <= 2^30 + 2), E_31's factors in Q30 (|b| / 2^32 <= 2^21: |.| <=
     * 3 2^21 + 3), the quartic coefficients below 2^27 and the cubic ones
     * below 2^35 (map_taylor): each coordinate's sums below 2^61 (15 terms <
     * 2^57.1, 10 terms < 2^57.6), which is the Q(fb + 60) sum over 2^32.
     * The monomials' rounding is 2^-30 of the terms: nanometres. */
    int64_t aq[3], bq[3], a4[15], d1[10];
    int64_t bx = ct_max64(ct_abs64(b[0]), ct_max64(ct_abs64(b[1]), ct_abs64(b[2]))), bx2;
    int t, i, o, bent = bx != 0; /* a straight line (b = 0) leaves nothing out */
    if (mp->cf[TAY_S + 2][0] != 0) {
        return 0; /* terms beyond the 64-bit sums' range */
    }
    if (bx > (INT64_C(1) << 53)) {
        return 0; /* |b| <= 2^-9: its products' range, and the bound's */
    }
    bx2 = ct_mul_shr(bx, bx, 62u);
    /* what is left out, per coordinate: 5 |b| S4 + |b|^2 (S2 + 4 S3)
     * (map_taylor's sums: S4 < 2^62, half the other < 2^63; 5 |b| <= 5
     * 2^53, 2 |b|^2 <= 2^45: the bound < 2^119).  In nm: lim / 2^(fb + 36)
     * Q24 units of the axis' unit (a posting, or a height LSB: < 2^50 nm),
     * below 2^11 nm */
    for (o = 0; bent && o < 3; ++o) { /* bound: 3 coordinates */
        int64_t unit = o == 0 ? pk->posting_e_nm : (o == 1 ? pk->posting_n_nm : pk->height_scale_nm);
        ct_i128 lim = ct_i128_add(ct_i128_mul(mp->cf[TAY_S][o], 5 * bx), ct_i128_mul(mp->cf[TAY_S + 1][o], 2 * bx2));
        if (ct_i128_bits(lim) + ct_bitlen64((uint64_t)ct_abs64(unit)) > mp->fb[o] + 36u + 24u + 11u) {
            return 0;
        }
    }
    for (i = 0; i < 3; ++i) { /* bound: 3 axes */
        aq[i] = rshr64(a[i], 32u);
        bq[i] = rshr64(b[i], 32u);
    }
    for (t = 0; t < 15; ++t) { /* bound: 15 terms of degree 4 */
        a4[t] = quart_mono(am, aq, t);
    }
    /* E_31's factor per cubic monomial, sum e_i b_i a^(alpha - e_i) */
    for (t = 0; bent && t < 10; ++t) { /* bound: 10 terms of degree 3 */
        const uint8_t *e = term_abc[10 + t];
        d1[t] = 0;
        for (i = 0; i < 3; ++i) { /* bound: 3 axes */
            if (e[i] > 0) {
                d1[t] += (int64_t)e[i] * rshr64(ct_smul32(bq[i], rshr64(am[cub_less[t][i]], 32u)), 30u);
            }
        }
    }
    for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
        int64_t u = 0;
        for (t = 0; t < 15; ++t) { /* bound: 15 terms: G_4(a) */
            u += ct_smul32(mp->cf[tay_row(20 + t)][o], a4[t]); /* < 2^27, <= 2^30 + 2 */
        }
        for (t = 0; bent && t < 10; ++t) { /* bound: 10 terms: - E_31 */
            u -= mp->cf[tay_row(10 + t)][o] * d1[t];
        }
        /* |u| < 2^62: Q30 by a shift of fb - 2 >= 24 (fb >= 26, fit_map) */
        p[4][o] = ct_i128_round_shr(ct_i128_from64(u), mp->fb[o] - 2u);
    }
    return 1;
}

/* The quartic Taylor term of a fit of degree 5 along x(tau) = tau a - tau^2
 * b (taylor_nodes: a, b, am and db in Q62; |a_i| <= 1, |b_i| <= 2^-9 else
 * 0): p4 = E_40 - E_31 + E_22 (Q30), for a path of degree 5 through one
 * image, at its far end.  Its quartic power coefficients need no rows: only
 * the fit's own Chebyshev terms of degree 4 have quartic monomials (T_n has
 * n's parity), so each is cf' 2^(sh[4] + quart_lead).
 * Ranges, in Q30 (rshr64 of 64-bit products, as fit_eval's terms of degree
 * >= 3: the roundings, 2^-31 of a term each, are nanometres): the
 * monomials (<= 2^30), b (<= 2^21), E_31's factors (<= 3 2^21: sums of two
 * products < 2^53), b^beta (<= 2^12).  G_2's and G_3's coefficients (<
 * 2^58) times those in 128 bits: 16 products, < 2^85 (Q(fb + 28)).  The
 * quartic terms in 64 bits: cf' (<= 2^27) times the monomial times
 * 2^quart_lead in Q26, whose sum over the 15 terms is at most 66 2^26 for
 * |a_i| <= 1: < 2^59.1, then times 2^(sh + 4) (sh <= 29): < 2^93.
 * 0 (two images then) when |b| > 2^-9 or p4 reaches 2^53. */
CT_NOINLINE static int taylor_quartic(const ct_earth_map *mp, const int64_t a[3], const int64_t b[3],
                                      const int64_t am[20], const int64_t db[6], int64_t p4[3])
{
    int64_t aq[3], bq[3], s4[3] = {0, 0, 0};
    ct_i128 u4[3];
    int64_t bx = ct_max64(ct_abs64(b[0]), ct_max64(ct_abs64(b[1]), ct_abs64(b[2])));
    int t, i, o, bent = bx != 0; /* a straight line: no E_31, E_22 */
    if (bx > (INT64_C(1) << 53)) {
        return 0;
    }
    for (i = 0; i < 3; ++i) { /* bound: 3 axes */
        aq[i] = rshr64(a[i], 32u);
        bq[i] = rshr64(b[i], 32u);
        u4[i] = ct_i128_from64(0);
    }
    /* + E_22 = G_2(b) */
    for (t = 4; bent && t < 10; ++t) { /* bound: 6 terms of degree 2 */
        int64_t bb = rshr64(bq[3 - tay_parent[t]] * bq[tay_axis[t]], 30u);
        for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
            u4[o] = ct_i128_add(u4[o], ct_i128_mul(mp->cf[TAY0 + t - 1][o], bb));
        }
    }
    /* - E_31: a cubic alpha = beta + e_i has the eps term a^beta b_i +
     * db_beta a_i */
    for (t = 10; bent && t < 20; ++t) { /* bound: 10 terms of degree 3 */
        int pt = tay_parent[t];
        int64_t d1;
        i = tay_axis[t];
        d1 = rshr64(rshr64(am[pt], 32u) * bq[i] + rshr64(db[pt - 4], 32u) * aq[i], 30u);
        for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
            u4[o] = ct_i128_sub(u4[o], ct_i128_mul(mp->cf[TAY0 + t - 1][o], d1));
        }
    }
    /* + E_40 = G_4(a) */
    for (t = 0; t < 15; ++t) { /* bound: 15 terms of degree 4 */
        int64_t mq = rshr64(quart_mono(am, aq, t) * (INT64_C(1) << quart_lead[t]), 4u);
        for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
            s4[o] += mp->cf[20 + t][o] * mq;
        }
    }
    for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
        ct_i128 v = ct_i128_add(u4[o], ct_i128_mul(s4[o], INT64_C(1) << (mp->sh[4][o] + 4u)));
        /* v / 2^(fb + 51) by two shifts of at most 63 (fb >= 26); |v| <
         * 2^93, so its low word holds it */
        int64_t h = ct_i128_to64(ct_i128_sar(ct_i128_sar(v, 63u), mp->fb[o] - 12u));
        if (h != 0 && h != -1) {
            return 0;
        }
        p4[o] = ct_i128_round_shr(v, mp->fb[o] - 2u);
    }
    return 1;
}

/* Taylor-Lobatto nodes (a fit per call, es->tay_ok: tmax < 70 km):
 * the path's polynomial in tau = t / tmax through the camera's image with
 * the fit's own first three derivatives there, and the fit's image at
 * tau = 1 (up to 35 km: degree 4), or beyond 35 km (a fit of degree 5) the
 * fourth derivative too (taylor_quartic) and the image at tau = 1, or
 * where that is not formed the images at tau = 3/4 and 1 (degree 5) -- one
 * or two images a line of sight instead of the Lobatto nodes' three or
 * four.  Along the line x(tau) = tau a - tau^2 b (x = (P - c) / 2^q, a =
 * tmax d / 2^q, b = bend(tmax) w / 2^q: refraction's bend is k t^2 / 2R
 * exactly, vertex_exact's within a nanometre) the fit G = sum G_k (G_k its
 * terms of degree k) has the Taylor terms p_m = sum over k + l = m of
 * (-1)^l E_kl, E_kl the coefficient of eps^l in G_k(a + eps b): p1 = G_1 a,
 * p2 = G_2(a) - G_1 b, p3 = G_3(a) - G_2'(a) b: exact for the fit along a
 * straight line up to the degree, and otherwise off by its terms of
 * degree 5 (6) times at most max |tau^4 (tau - 1)| = 0.082 (max |tau^4
 * (tau - 3/4) (tau - 1)| = 0.0099; with p4 = E_40 - E_31 + E_22 and one
 * image, by at most the sum of its terms of degree 6 and more, which only
 * refraction makes: |E_51| is 0.02 um at 52 km with k = 0.13): within
 * 0.0054 mm of the fit's images (test_earth test_taylor_path; the Lobatto
 * nodes' 0.0125 mm).
 * A fit of degree 4 (cubes of 2^44 nm) takes its Taylor terms alone, no
 * image: also p4 = E_40 - E_31 (E_31 = sum over i of alpha_i b_i a^(alpha
 * - e_i) per cubic monomial a^alpha), which along a straight line (b = 0)
 * is the fit exactly (degree 4 in tau); with refraction what it leaves
 * out (G_2(b) and the terms of degree 5 and more in tau) is bounded by
 * taylor_alone, which takes the image instead when that could reach 2 um
 * (with k = 0.13 the bound is about 1 um at 10 km).
 * Units: a, b and their products Q62, the terms' sums Q(fb + 60) in 128
 * bits (|tay| < 2^58: <= 31 products < 2^121 each, < 2^126), rounded to Q30
 * (below 2^54, else none); the images X in Q24 less the camera's, |X| <
 * 2^46.
 * Returns 0 (the Lobatto nodes then) when an image is missing or too far,
 * or a coefficient reaches 2^49. */
static int taylor_nodes(path *pa, int64_t tmax)
{
    const ct_earth *es = pa->es;
    const ct_earth_map *mp = es->map;
    int64_t a[3], b[3], am[20], db[6], p[6][3], X[2][3];
    int deg = tmax <= NODES_4_NM ? 4 : 5, nf, alone = 0, quart = 0, i, j, k, t, o;
    unsigned q = mp->qrho;
    int64_t bmax = pa->refract ? es->tay_bend_nm : 0;
    /* a: tmax |d| < 2^48 2^40 over 2^(q - 23) (q >= 44): |a| <= 2^62 as
     * tmax < 2^q; b: |bend| < 2^47 (the cube holds it), |w| <= 2^30 + 2,
     * over 2^(q - 32): |b| < 2^62 */
    for (i = 0; i < 3; ++i) { /* bound: 3 axes */
        a[i] = ct_i128_round_shr(ct_i128_mul(tmax, pa->d[i]), q - 23u);
        b[i] = ct_i128_round_shr(ct_i128_mul(bmax, pa->w[i]), q - 32u);
    }
    /* a^alpha for the terms of degrees 1..3 (Q62): a term's monomial is
     * its parent's (tay_parent) times a along tay_axis; and each quadratic
     * one's derivative along b, e_i b_i a^(alpha - e_i) (|.| < 2^63) */
    am[0] = T_ONE_Q62;
    am[1] = a[2];
    am[2] = a[1];
    am[3] = a[0];
    for (t = 4; t < 20; ++t) { /* bound: 16 terms */
        am[t] = ct_mul_shr(am[tay_parent[t]], a[tay_axis[t]], 62u);
    }
    for (t = 4; t < 10; ++t) { /* bound: 6 terms: alpha = e_i + e_j, parent e_j */
        int ax = tay_axis[t], ox = 3 - (int)tay_parent[t]; /* term 3 - i is e_i's */
        db[t - 4] = ct_mul_shr(b[ax], a[ox], 62u) + ct_mul_shr(b[ox], a[ax], 62u);
    }
    /* a degree-4 fit: its Taylor terms alone when taylor_alone bounds what
     * they leave out */
    if (mp->deg == 4 && taylor_alone(pa->p, mp, a, b, am, p)) {
        alone = 1; /* deg is 4: tmax < 2^44 nm, below NODES_4_NM */
    } else if (deg == 5 && taylor_quartic(mp, a, b, am, db, p[4])) {
        /* beyond 35 km (the fit's degree is 5: its cube holds over 35 km):
         * the quartic term too, and one image */
        quart = 1;
    }
    nf = alone ? 0 : (quart ? 1 : deg - 3);
    for (j = 0; j < nf; ++j) { /* bound: 2 far nodes: tau = 3/4 (3 tmax < 2^50) and 1 */
        if (!node_image(pa, j == nf - 1 ? tmax : (3 * tmax) >> 2, X[j])) {
            return 0;
        }
    }
    for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
        ct_i128 s1 = ct_i128_from64(0), s2 = ct_i128_from64(0), s3 = ct_i128_from64(0);
        for (t = 1; t < 4; ++t) { /* bound: 3 terms: G_1 a; - G_1 b */
            s1 = ct_i128_add(s1, ct_i128_mul(mp->cf[TAY0 + t - 1][o], am[t]));
            s2 = ct_i128_sub(s2, ct_i128_mul(mp->cf[TAY0 + t - 1][o], b[3 - t]));
        }
        for (t = 4; t < 10; ++t) { /* bound: 6 terms: G_2(a); - G_2'(a) b */
            s2 = ct_i128_add(s2, ct_i128_mul(mp->cf[TAY0 + t - 1][o], am[t]));
            s3 = ct_i128_sub(s3, ct_i128_mul(mp->cf[TAY0 + t - 1][o], db[t - 4]));
        }
        for (t = 10; t < 20; ++t) { /* bound: 10 terms: G_3(a) */
            s3 = ct_i128_add(s3, ct_i128_mul(mp->cf[TAY0 + t - 1][o], am[t]));
        }
        /* Q(fb + 60) -> Q30, each below 2^54 (p1 is about 64 X, < 2^52):
         * the sums below stay within 64 bits */
        if (ct_i128_bits(ct_i128_abs(s1)) > mp->fb[o] + 83u || ct_i128_bits(ct_i128_abs(s2)) > mp->fb[o] + 83u ||
            ct_i128_bits(ct_i128_abs(s3)) > mp->fb[o] + 83u) {
            return 0;
        }
        p[0][o] = 0;
        p[1][o] = ct_i128_round_shr(s1, mp->fb[o] + 30u);
        p[2][o] = ct_i128_round_shr(s2, mp->fb[o] + 30u);
        p[3][o] = ct_i128_round_shr(s3, mp->fb[o] + 30u);
        if (alone) {
            continue; /* p4: taylor_alone's */
        }
        if (deg == 4) {
            p[4][o] = X[0][o] * 64 - p[1][o] - p[2][o] - p[3][o];
        } else if (quart) {
            /* through the image at tau = 1: |p4| < 2^53, |64 X| < 2^52 */
            p[5][o] = X[0][o] * 64 - p[1][o] - p[2][o] - p[3][o] - p[4][o];
        } else {
            /* r0 + r1 tau through tau = 3/4 and 1 of (X - p1 tau - p2 tau^2
             * - p3 tau^3) / tau^4: R1 at 1 (< 2^56); at 3/4 its 64-fold M
             * (< 2^58 + 111 2^54 < 2^61) and V = r0 + 3 r1 / 4 = 4 M / 81
             * rounded (8 M in 128 bits; |V| < 2^57); r1 = 4 (R1 - V) < 2^60 */
            int64_t r1s = X[1][o] * 64 - p[1][o] - p[2][o] - p[3][o];
            int64_t m64 = X[0][o] * 4096 - (48 * p[1][o] + 36 * p[2][o] + 27 * p[3][o]);
            int64_t vq = ct_i128_floor_div(ct_i128_add(ct_i128_mul(m64, 8), ct_i128_from64(81)), 162);
            p[5][o] = 4 * (r1s - vq);
            p[4][o] = r1s - p[5][o];
        }
    }
    pa->nodes = deg + 1;
    pa->alone = alone;
    /* in powers of sigma = 2 tau - 1: c_j = sum_k p_k binom(k, j) / 2^k
     * (Q30 -> Q24: / 2^(deg + 6)) */
    for (j = 0; j <= deg; ++j) { /* bound: NODES */
        for (o = 0; o < 3; ++o) { /* bound: 3 coordinates */
            ct_i128 s = ct_i128_from64(0);
            for (k = j; k <= deg; ++k) { /* bound: NODES */
                s = ct_i128_add(s, ct_i128_mul(p[k][o], (int64_t)binom5[k][j] << (deg - k)));
            }
            pa->cf[j][o] = ct_i128_round_shr(s, (unsigned)deg + 6u);
            if (ct_abs64(pa->cf[j][o]) >= (INT64_C(1) << 49)) {
                return 0;
            }
        }
    }
    return 1;
}

/* The nodes' exact images and the polynomial through them; pa->interp = 0
 * when one is outside the projection's domain (the vertices are then
 * computed exactly). */
CT_NOINLINE static void set_nodes(path *pa, int64_t tmax)
{
    int j, k;
    int64_t X[NODES][3];
    pa->interp = 0;
    pa->alone = 0;
    pa->tmax = tmax;
    /* tmax >= 1 km (set-up): tsh in [40, 49], 60 + tsh < 128 */
    pa->tsh = ct_bitlen64((uint64_t)tmax);
    pa->tinv = ct_i128_floor_div(ct_i128_shl(ct_i128_shl(ct_i128_from64(1), 60u), pa->tsh), tmax);
    /* every path's base: node 0, the camera's image (the call's) */
    pa->base[0] = pa->es->cam24[0];
    pa->base[1] = pa->es->cam24[1];
    pa->base[2] = pa->es->cam24[2];
    /* (tay_ok: a fit of degree <= 5, whose cube of at most 2^46 nm holds
     * the range: tmax < 70 km, so within the Taylor terms' two regimes) */
    if (pa->es->tay_ok && taylor_nodes(pa, tmax)) {
        path_bounds(pa);
        pa->interp = 1;
        return;
    }
    pa->nodes = tmax <= NODES_4_NM ? 4 : (tmax <= NODES_5_NM ? 5 : 6);
    X[0][0] = X[0][1] = X[0][2] = 0;
    for (j = 1; j < pa->nodes; ++j) { /* bound: NODES */
        /* t_j = tmax tau_j: < 2^48 2^60 in 128 bits */
        if (!node_image(pa, ct_mul_shr(tmax, tau_q60[pa->nodes - 4][j], 60u), X[j])) {
            return;
        }
    }
    for (k = 0; k < pa->nodes; ++k) { /* bound: NODES */
        for (j = 0; j < 3; ++j) { /* bound: 3 coordinates */
            ct_i128 acc = ct_i128_from64(0);
            int i;
            for (i = 0; i < pa->nodes; ++i) { /* bound: NODES; < 2^43 2^46 each */
                acc = ct_i128_add(acc, ct_i128_mul(vinv(pa->nodes, k, i), X[i][j]));
            }
            pa->cf[k][j] = ct_i128_round_shr(acc, 40u);
        }
    }
    path_bounds(pa);
    pa->interp = 1;
}

/* The chord's length in Q24 (|differences| < 2^44: squares in 128 bits). */
static int64_t chord24(const gv *A, const gv *B)
{
    int64_t ux = B->fx - A->fx, uy = B->fy - A->fy;
    return (int64_t)ct_i128_isqrt(ct_i128_add(ct_i128_mul(ux, ux), ct_i128_mul(uy, uy)));
}

/* The sideways distance (Q24) of Q from the chord A -> B of Q24 length l24,
 * signed: positive to the left of A -> B (from A, and positive, when the
 * chord is vertical). */
static int64_t side24(const gv *A, const gv *B, int64_t l24, const gv *Q)
{
    int64_t ux = B->fx - A->fx, uy = B->fy - A->fy, qx = Q->fx - A->fx, qy = Q->fy - A->fy, d;
    ct_i128 cross;
    if (l24 < 256) {
        /* shorter than a Q16 unit: as good as vertical */
        return (int64_t)ct_i128_isqrt(ct_i128_add(ct_i128_mul(qx, qx), ct_i128_mul(qy, qy)));
    }
    cross = ct_i128_sub(ct_i128_mul(ux, qy), ct_i128_mul(uy, qx));
    d = ct_i128_floor_div_sat(ct_i128_sign(cross) < 0 ? ct_i128_neg(cross) : cross, l24);
    return ct_i128_sign(cross) < 0 ? -d : d;
}

/* Its magnitude. */
static int64_t lateral24(const gv *A, const gv *B, int64_t l24, const gv *Q)
{
    return ct_abs64(side24(A, B, l24, Q));
}

/* The piece A -> B (middle M): chord length l, the middle's sideways
 * deviation, its range along the chord, and the vertical quadratic's
 * coefficient a = num / den (den > 0; den = 0: no quadratic). */
typedef struct {
    int64_t ux, uy, l, sm;
    int64_t l24; /* the chord's length, Q24 */
    int64_t sdev, dev; /* the middle's sideways deviation, Q24: signed (side24), its magnitude */
    ct_i128 num, den;
    int64_t dip; /* |a| l^2 / 4, Q16 height units (saturated) */
} fit;

/* The Q16 chord A -> B: u and its length l (pieces are at most 30 km: |u|
 * < 2^42 Q16 at 1 cm posting or more; squares in 128 bits). */
static void fit_u(const gv *A, const gv *B, fit *f)
{
    f->ux = B->x - A->x;
    f->uy = B->y - A->y;
    f->l = (int64_t)ct_i128_isqrt(ct_i128_add(ct_i128_mul(f->ux, f->ux), ct_i128_mul(f->uy, f->uy)));
}

/* The chord's part of the fit: u, l, l24. */
static void fit_chord(const gv *A, const gv *B, fit *f)
{
    fit_u(A, B, f);
    f->l24 = chord24(A, B);
}

/* The middle's part of the fit (u, l and l24 set by fit_chord: a chord
 * shifted sideways keeps them). */
CT_NOINLINE static void fit_middle(const gv *A, const gv *B, const gv *M, fit *f)
{
    int64_t mx = M->x - A->x, my = M->y - A->y;
    ct_i128 dot;
    /* |m| < 2^42 as |u|: products in 128 bits */
    dot = ct_i128_add(ct_i128_mul(f->ux, mx), ct_i128_mul(f->uy, my));
    f->sm = f->l == 0 ? 0 : ct_i128_floor_div_sat(dot, f->l);
    f->sdev = side24(A, B, f->l24, M);
    f->dev = ct_abs64(f->sdev);
    f->den = ct_i128_from64(0);
    f->num = ct_i128_from64(0);
    f->dip = 0;
    /* the quadratic z = b s + a s^2 through (0, 0), (sm, zm'), (l, zb'):
     *   a = (zb' sm - zm' l) / (sm l (l - sm)),
     * only for a chord of a cell or more with the middle well inside */
    if (f->l >= (INT64_C(1) << 40) || ct_abs64(M->z - A->z) >= (INT64_C(1) << 48) ||
        ct_abs64(B->z - A->z) >= (INT64_C(1) << 48)) {
        f->dip = INT64_C(1) << 62; /* beyond the fit's range: shorten */
    } else if (f->l >= ONE16 && f->sm > f->l / 4 && f->sm < f->l - f->l / 4) {
        int64_t zm = M->z - A->z, zb = B->z - A->z, q1;
        /* |z'| < 2^48, l < 2^40: products < 2^88, den < 2^120 */
        f->num = ct_i128_sub(ct_i128_mul(zb, f->sm), ct_i128_mul(zm, f->l));
        f->den = ct_i128_mul128_64(ct_i128_mul(f->sm, f->l), f->l - f->sm);
        /* dip = |num| l / (4 sm (l - sm)): |num| l < 2^128 is not assured,
         * so |num| / sm first (sm > l / 4: the quotient < 2^50), then l /
         * (4 (l - sm)) < 1 */
        q1 = ct_i128_floor_div_sat(ct_i128_sign(f->num) < 0 ? ct_i128_neg(f->num) : f->num, f->sm);
        f->dip = ct_i128_floor_div_sat(ct_i128_mul(q1, f->l), 4 * (f->l - f->sm));
    }
}

/* The shift (Q24, horizontal) that moves the chord A -> B towards its
 * middle M by half M's sideways deviation: the image bends sideways about
 * as a parabola (the transverse Mercator's bend, nearly constant along a
 * piece), so the shifted line lies within half the middle's deviation of
 * it at the ends and the middle alike -- a piece may be sqrt(2) times as
 * long for the same tolerance.  The signed deviation dv (side24, Q24,
 * |dv| <= |M - A| < 2^46) along the unit normal (-uy, ux) / l24, halved:
 * |dv u| < 2^92 in 128 bits, over 2 l24.  0 (no shift) for a chord
 * shorter than a Q16 unit or a shift that rounds to nothing. */
static int chord_shift(const gv *A, const gv *B, int64_t dv, int64_t l24, int64_t *sx, int64_t *sy)
{
    int64_t ux = B->fx - A->fx, uy = B->fy - A->fy;
    if (l24 < 256) {
        return 0;
    }
    *sx = ct_i128_floor_div_sat(ct_i128_mul(-dv, uy), 2 * l24);
    *sy = ct_i128_floor_div_sat(ct_i128_mul(dv, ux), 2 * l24);
    return *sx != 0 || *sy != 0;
}

/* v moved sideways by (sx, sy) Q24 cells, its Q16 point the nearest to
 * that (as a vertex's: q24_to_16). */
static void gv_shift(gv *v, int64_t sx, int64_t sy)
{
    v->fx += sx;
    v->fy += sy;
    v->x = q24_to_16(v->fx);
    v->y = q24_to_16(v->fy);
}

/* The model's distance from the exact image Q (a quarter point): its
 * sideways distance from the chord (Q24 cells) and, in the chord's
 * vertical plane, the height difference at Q's range along the chord (Q16
 * height units: the chord's height there plus the lowering (lw) or the
 * straight chord (lw = NULL)) -- for a chord steeper than 45 degrees (in
 * metres: its rise dzc, in Q16 cells, above its length l) the range
 * difference at Q's height instead, which is the height difference times
 * l / dzc: the smaller of the two, both at least Q's distance from the
 * model across it (the height difference times the cosine of the chord's
 * elevation), and neither growing without bound as the chord steepens.
 * Ranges and heights at Q24 (a Q16 range along a steep chord would put
 * its rounding times the slope into the height). */
static void model_error(const gv *A, const gv *B, const gv *Q, const fit *f, const ct_lower *lw, int64_t dB,
                        int64_t dzc, int64_t *lat, int64_t *vert)
{
    int64_t ux = B->fx - A->fx, uy = B->fy - A->fy, qx = Q->fx - A->fx, qy = Q->fy - A->fy, sq, zl, v;
    ct_i128 dot;
    *lat = lateral24(A, B, f->l24, Q);
    if (f->l == 0) {
        /* a vertical chord: the sideways distance only (l24 > 0 with l > 0:
         * the Q16 ends are the Q24 ones rounded) */
        *vert = 0;
        return;
    }
    /* |u|, |q| < 2^50 (pieces <= 30 km): the dot product < 2^101 */
    dot = ct_i128_add(ct_i128_mul(ux, qx), ct_i128_mul(uy, qy));
    /* sq: Q's range along the chord, Q24 (within the piece: |sq| <= 2 l24) */
    sq = ct_i128_floor_div_sat(dot, f->l24);
    sq = ct_max64(-2 * f->l24, ct_min64(2 * f->l24, sq));
    /* the line's height at sq, Q24: 256 (B.z - dB - A.z) sq / l24, |dz sq|
     * < 2^57 2^47, times 2^8 < 2^113 */
    zl = A->z * 256 +
         ct_i128_floor_div_sat(ct_i128_mul128_64(ct_i128_mul(B->z - dB - A->z, sq), 256), f->l24);
    if (lw != NULL) {
        zl += ct_lower_at(lw, Q->x, Q->y) * 256;
    }
    v = ct_min64(ct_abs64(Q->fz - zl), INT64_C(1) << 60);
    if (dzc > f->l) {
        /* times l / dzc (l < 2^40; dzc capped at 2^52 by the caller) */
        v = ct_i128_floor_div_sat(ct_i128_mul(v, f->l), dzc);
    }
    *vert = (v + 255) / 256;
}

/* kf, kshift with kf 2^-kshift = num / den (num, den > 0), kf in
 * [2^30, 2^32); 0 when the quotient is beyond the lowered walk's range. */
CT_NOINLINE static int rise_coeff(ct_i128 num, ct_i128 den, uint64_t *kf, uint32_t *kshift)
{
    unsigned nb, db, r = 0u;
    int e;
    int64_t d64, q;
    nb = num.hi != 0u ? 64u + ct_bitlen64(num.hi) : ct_bitlen64(num.lo);
    db = den.hi != 0u ? 64u + ct_bitlen64(den.hi) : ct_bitlen64(den.lo);
    if (db > 62u) {
        r = db - 62u;
        den = r >= 64u ? ct_i128_from64((int64_t)(den.hi >> (r - 64u)))
                       : ct_i128_from64((int64_t)((den.lo >> r) | (den.hi << (64u - r))));
        db = 62u;
    }
    d64 = (int64_t)den.lo;
    /* num 2^e / d64 in [2^30, 2^32): e = 31 - (nb - db), and num 2^e <
     * 2^(nb + e) = 2^(31 + db) <= 2^93 */
    e = 31 - ((int)nb - (int)db);
    if (e < 0 || d64 <= 0) {
        return 0;
    }
    /* ct_i128_shl shifts by less than 64 */
    num = e >= 64 ? ct_i128_shl(ct_i128_shl(num, 63u), (unsigned)e - 63u) : ct_i128_shl(num, (unsigned)e);
    q = ct_i128_floor_div(num, d64);
    /* bound: 2 halvings */
    while (q >= (INT64_C(1) << 32)) {
        q >>= 1;
        e--;
    }
    if (e + (int)r > 127 || e < 0) {
        return 0;
    }
    *kf = (uint64_t)q;
    *kshift = (uint32_t)(e + (int)r);
    return 1;
}

ct_status ct_earth_setup(const ct_package *p, const ct_pose *pose, int32_t refr_k_q16, int64_t radius_nm,
                         int64_t chord_nm, uint32_t bend_flags, int fitted, const ct_earth_map *map, ct_earth *es)
{
    int64_t lat, lon, post, far2x, far2y, dz;
    ct_status st;
    if (p == NULL || pose == NULL || es == NULL) {
        return CT_ERR_ARG;
    }
    if (ct_package_zone(p, &es->zone) != CT_OK) {
        return CT_ERR_CRS;
    }
    st = ct_grid_frame_ecef(&es->zone, pose->e_nm, pose->n_nm, &lat, &lon, es->frame_q30);
    if (st == CT_OK) {
        st = ct_ecef_from_wgs84(lat, lon, pose->h_nm, es->c);
    }
    if (st != CT_OK) {
        return st;
    }
    if (ct_map_to_grid(p, pose->e_nm, pose->n_nm, pose->h_nm, &es->ox, &es->oy, &es->oz) != CT_OK ||
        ct_abs64(es->ox) > CT_MAX_ORIGIN_Q16 || ct_abs64(es->oy) > CT_MAX_ORIGIN_Q16 ||
        ct_abs64(es->oz) > CT_MAX_ORIGIN_Q16) {
        return CT_ERR_RAY;
    }
    es->refr_k_q16 = refr_k_q16;
    es->radius_nm = radius_nm;
    post = ct_abs64(p->posting_e_nm);
    /* chord (<= 2^50) 2^16 < 2^66: 128-bit */
    /* the checks aim at 3/4 of the chord: they see the model at its middle
     * and quarter points only, and the vertices are rounded to Q16 */
    chord_nm -= chord_nm / 4;
    es->tol_q24 = ct_max64(2, ct_i128_floor_div_sat(ct_i128_shl(ct_i128_from64(chord_nm), 24), post));
    es->tolz_q16 = ct_max64(2, ct_i128_floor_div_sat(ct_i128_shl(ct_i128_from64(chord_nm), 16), p->height_scale_nm));
    es->cull = (bend_flags & CT_BEND_NO_CULL) == 0u;
    /* no terrain beyond the farthest tile corner: the range to it (map
     * metres are ground metres within 0.1 %) plus the height down to the
     * lowest post, with 10 % and 1 km to spare */
    far2x = ct_max64(ct_abs64(es->ox), ct_abs64(es->ox - (int64_t)p->cells_x * ONE16));
    far2y = ct_max64(ct_abs64(es->oy), ct_abs64(es->oy - (int64_t)p->cells_y * ONE16));
    dz = ct_abs64(es->oz - (int64_t)p->hmin * ONE16);
    {
        /* Q16 -> nm (saturated; each capped at 2^48: squares < 2^98) */
        int64_t hx = ct_i128_floor_div_sat(ct_i128_mul(far2x, post), ONE16);
        int64_t hy = ct_i128_floor_div_sat(ct_i128_mul(far2y, post), ONE16);
        int64_t hz = ct_i128_floor_div_sat(ct_i128_mul(dz, p->height_scale_nm), ONE16);
        hx = ct_min64(hx, TMAX_LIMIT_NM);
        hy = ct_min64(hy, TMAX_LIMIT_NM);
        hz = ct_min64(hz, TMAX_LIMIT_NM);
        ct_i128 s2 = ct_i128_add(ct_i128_add(ct_i128_mul(hx, hx), ct_i128_mul(hy, hy)), ct_i128_mul(hz, hz));
        int64_t dist = (int64_t)ct_i128_isqrt(s2);
        if (dist > TMAX_LIMIT_NM) {
            dist = TMAX_LIMIT_NM;
        }
        es->tmax_nm = ct_min64(TMAX_LIMIT_NM, dist + dist / 10 + KM_NM);
    }
    es->map = NULL;
    es->moff[0] = es->moff[1] = es->moff[2] = 0;
    es->fit.ready = 0u;
    es->fit.deg = 0;
    es->tay_ok = 0;
    es->tay_bend_nm = 0;
    if (map != NULL) {
        es->map = map;
    } else if (fitted) {
        /* the cube holds every node C + t d - bend w, t <= tmax: its
         * half-width 2^q >= tmax + the bend at tmax (as vertex_exact: |k|
         * tmax^2 / 2R, < 2^62 saturated) + 1 km */
        int64_t bend;
        uint32_t q;
        ct_i128 num = ct_i128_mul128_64(ct_umul64((uint64_t)es->tmax_nm, (uint64_t)es->tmax_nm),
                                        refr_k_q16 < 0 ? -(int64_t)refr_k_q16 : (int64_t)refr_k_q16);
        bend = ct_floor_div(ct_i128_floor_div_sat(num, 2 * radius_nm), ONE16);
        q = cube_q(es->tmax_nm + bend + KM_NM); /* < 2^48 + 2^46 + 2^40 */
        if (q <= 47u) {
            int k;
            for (k = 0; k < 3; ++k) { /* bound: 3 axes */
                es->fit.c[k] = es->c[k];
            }
            es->fit.g16[0] = es->ox;
            es->fit.g16[1] = es->oy;
            es->fit.g16[2] = es->oz;
            fit_map(p, &es->zone, &es->fit, q);
            if (es->fit.deg > 0) {
                es->map = &es->fit;
                es->tay_ok = map_taylor(&es->fit);
                es->tay_bend_nm = bend_at(es, es->tmax_nm);
            }
        }
    }
    if (es->map != NULL) {
        int k;
        for (k = 0; k < 3; ++k) { /* bound: 3 axes */
            es->moff[k] = es->c[k] - es->map->c[k];
            if (ct_abs64(es->moff[k]) > (INT64_C(1) << 50)) {
                es->map = NULL; /* the camera is 1,100 km from the map's cube: exact */
                es->tay_ok = 0;
                break;
            }
        }
    }
    {
        /* every path's first node: the camera's image (t = 0: no direction
         * and no bend), as vertex_exact finds it -- the camera's map point
         * through ECEF and back, so it fails only for a camera on the
         * projection domain's very edge (as the pose's own point is
         * checked above): CT_ERR_RANGE */
        path pa;
        gv v;
        pa.p = p;
        pa.es = es;
        pa.zone = es->zone;
        pa.d[0] = pa.d[1] = pa.d[2] = 0;
        pa.w[0] = pa.w[1] = pa.w[2] = 0;
        pa.refract = 0;
        pa.interp = 0;
        st = vertex_exact(&pa, 0, &v);
        if (st != CT_OK) {
            return st;
        }
        es->cam24[0] = v.fx;
        es->cam24[1] = v.fy;
        es->cam24[2] = v.fz;
    }
    return CT_OK;
}

/* e 526 / 2^16 rounded up (526 / 2^16 > 1 / (72 sqrt 3), the remainder
 * of quadratic interpolation at three equally spaced points), for 0 <= e
 * < 2^61: (e >> 8) 526 < 2^62. */
static int64_t rem3(int64_t e)
{
    return ((((e >> 8) + 1) * 526) >> 8) + 1;
}

/* The piece [ta, ta + Lc] in sigma: h = 2 Lc / tmax in Q30, rounded up
 * (Lc <= tmax: h <= 2^31; 2 Lc 2^30 < 2^80). */
static int64_t piece_hq(const path *pa, int64_t Lc)
{
    return -ct_i128_floor_div_sat(ct_i128_neg(ct_i128_shl(ct_i128_from64(2 * Lc), 30u)), pa->tmax);
}

/* b (hq / 2^30)^k rounded up, k <= 3, for 0 <= b < 2^58 and hq <= 2^31:
 * each product < 2^90 in 128 bits, each step at most doubles (< 2^61). */
static int64_t pow_h(int64_t b, int64_t hq, int k)
{
    int i;
    for (i = 0; i < k; ++i) { /* bound: 3 */
        b = -ct_i128_to64(ct_i128_sar(ct_i128_neg(ct_i128_mul(b, hq)), 30u));
    }
    return b;
}

/* A bound (Q16 height units) of how far the path's height over a piece of
 * length Lc may fall below the quadratic in sigma through its ends and
 * middle: |z'''| h^3 / (72 sqrt 3), h = 2 Lc / tmax the piece in sigma
 * (the error of interpolation at three equally spaced points), rounded
 * up: hq = h 2^30 <= 2^31, b3z hq < 2^88 in 128 bits, each product
 * shifted back; 526 / 2^16 > 1 / (72 sqrt 3); 2 units for the rounding of
 * the vertices' heights to Q16.  Without the polynomial
 * (the exact vertices), pieces up to PIECE_FIRST_NM bend by far less than
 * the tolerance the callers subtract as well (the image's third derivative
 * scales as 1 / R^2: 0.03 mm at 4 km), longer ones are never off. */
static int64_t cubic_drop(const path *pa, int64_t Lc)
{
    int64_t e;
    if (!pa->interp) {
        return Lc <= PIECE_FIRST_NM ? 0 : INT64_C(1) << 60;
    }
    e = pow_h(pa->b3z, piece_hq(pa, Lc), 3);
    /* e <= b3z (hq / 2^30)^3 < 2^60, the remainder in Q24 (rem3), then Q16 */
    return ((rem3(e) - 1) >> 8) + 2;
}

/* 1 when nothing of the piece can touch terrain: off the tile
 * horizontally (the box of A, B, M widened by the deviation and 2 cells:
 * the sideways bend beyond the middle's deviation is far smaller) or, by
 * the tolerance, above the tallest post -- its lowest point bounded from
 * the quadratic in sigma through A, M, B (at least min(zA, zB) less (zA +
 * zB - 2 zM) / 2, rounded up, when convex) less the path's distance from it (cubic_drop;
 * unchecked pieces may be up to 30 km long) and as the model sees it (the
 * quadratic along the chord, less its dip). */
static int piece_off(const ct_package *p, const path *pa, const gv *A, const gv *B, const gv *M, const fit *f,
                     int64_t Lc, int64_t tolz)
{
    int64_t m = f->dev / 256 + 2 * ONE16;
    int64_t x0 = ct_min64(A->x, ct_min64(B->x, M->x)) - m, x1 = ct_max64(A->x, ct_max64(B->x, M->x)) + m;
    int64_t y0 = ct_min64(A->y, ct_min64(B->y, M->y)) - m, y1 = ct_max64(A->y, ct_max64(B->y, M->y)) + m;
    /* |z| < 2^56 (ct_map_to_grid's range, and the interpolation's 2^49):
     * sums < 2^58; the tolerance and the dip (saturated at 2^62) capped at
     * 2^60, still far below any tile; cubic_drop <= 2^60 + 2^44 */
    int64_t tz = ct_min64(tolz, INT64_C(1) << 60), top = ((int64_t)p->hmax + 1) * ONE16;
    if (x1 < 0 || y1 < 0 || x0 > (int64_t)p->cells_x * ONE16 || y0 > (int64_t)p->cells_y * ONE16) {
        return 1;
    }
    /* both bounds above the top (the path's, with its 128-bit cubic_drop,
     * only for a piece the model's already puts there) */
    return ct_min64(A->z, ct_min64(B->z, M->z)) - ct_min64(f->dip, INT64_C(1) << 60) - tz > top &&
           ct_min64(A->z, B->z) - ct_max64(0, (A->z + B->z - 2 * M->z + 1) / 2) - cubic_drop(pa, Lc) - tz > top;
}

/* 1 when the piece's walk cannot meet the surface (CT_BEND_NO_CULL turns
 * this off): its straight line, from A to B less the lowering dB (the walk
 * traces it against the terrain lowered by a >= 0, so below the terrain),
 * culled as the polyline's segments are (ct_segment_above_terrain). */
static int piece_culled(const ct_package *p, const gv *A, const gv *B, int64_t dB)
{
    int64_t zb = B->z - dB;
    int over;
    return ct_segment_above_terrain(p, A->x, A->y, A->z, B->x, B->y, zb, ct_min64(A->z, zb), &over);
}

/* 1 when the path never comes back over the tile: beyond an edge and
 * moving away on that axis faster than 1/1024 of its horizontal progress
 * (its heading turns by far less over 281 km: refraction_axis), or above the tallest post
 * and rising on a convex piece. */
static int gone(const ct_package *p, const gv *A, const gv *B, const gv *M, const fit *f)
{
    int64_t W = (int64_t)p->cells_x * ONE16, H = (int64_t)p->cells_y * ONE16, away = f->l / 1024 + 1;
    if ((B->x < 0 && A->x - B->x > away) || (B->x > W && B->x - A->x > away) || (B->y < 0 && A->y - B->y > away) ||
        (B->y > H && B->y - A->y > away)) {
        return 1;
    }
    return ct_i128_sign(f->num) >= 0 && B->z > ((int64_t)p->hmax + 1) * ONE16 && B->z >= M->z && M->z >= A->z;
}

/* The model's largest errors at the piece's quarter points (out of line:
 * its vertices are not on the walk's stack). */
CT_NOINLINE static ct_status quarter_errors(const path *pa, int64_t ta, int64_t Lc, const gv *A, const gv *B,
                                            const fit *f, const ct_lower *lw, int64_t dB, int64_t *elat,
                                            int64_t *evert)
{
    gv Q1, Q3;
    int64_t l1, v1, l3, v3, dzc;
    if (vertex(pa, ta + Lc / 4, &Q1) != CT_OK || vertex(pa, ta + Lc - Lc / 4, &Q3) != CT_OK) {
        return CT_ERR_RANGE;
    }
    /* the chord's rise in Q16 cells (rounded down: the smaller, the larger
     * the error; |dz| < 2^57, height scale < 2^50 nm: < 2^107) */
    dzc = ct_min64(ct_i128_floor_div_sat(ct_i128_mul(ct_abs64(B->z - dB - A->z), pa->p->height_scale_nm),
                                         ct_abs64(pa->p->posting_e_nm)),
                   INT64_C(1) << 52);
    model_error(A, B, &Q1, f, lw, dB, dzc, &l1, &v1);
    model_error(A, B, &Q3, f, lw, dB, dzc, &l3, &v3);
    *elat = ct_max64(*elat, ct_max64(l1, l3));
    *evert = ct_max64(v1, v3);
    return CT_OK;
}

/* One piece traced: the line from A to B less the lowering at B, against
 * the terrain lowered by lw (NULL: the chord against the terrain).  CT_MISS
 * when the path goes on to the next piece; a hit (in *h, with the steps and
 * iterations so far), CT_BELOW (first: the camera's own piece, the camera
 * over the tile, starting below the surface) or an error otherwise.  Out
 * of line: the prepared ray and the piece's hit are on the stack only while
 * it runs. */
CT_NOINLINE static ct_status trace_piece(const ct_package *p, ct_tileset *ts, const gv *A, const gv *B,
                                         const fit *f, const ct_lower *lw, int64_t dB, int first, ct_method m,
                                         ct_hit *h, uint32_t *steps, uint32_t *iters)
{
    ct_ray ray;
    ct_prepared pr;
    ct_hit sh;
    ct_status st;
    int64_t tend_n, tend_d;
    ray.x_q16 = A->x;
    ray.y_q16 = A->y;
    ray.z_q16 = A->z;
    ray.dx = f->ux;
    ray.dy = f->uy;
    ray.dz = B->z - dB - A->z;
    if (ray.dx == 0 && ray.dy == 0 && ray.dz == 0) {
        return CT_MISS;
    }
    if (ts != NULL) {
        /* a tile set: the same segment, walked tile by tile (below the
         * surface at A after the first piece: a hit there, as below) */
        st = ct_tileset_trace_segment(ts, &ray, lw, !first, m, &sh, &tend_n, &tend_d);
        if (st < 0 || st == CT_NO_DATA) {
            if (st == CT_NO_DATA) {
                *h = sh;
                h->steps = *steps + sh.steps;
                h->iters = *iters + sh.iters;
            }
            return st;
        }
        if (st == CT_BELOW) {
            h->steps = *steps;
            h->iters = *iters;
            return CT_BELOW;
        }
    } else {
        st = ct_prepare_lowered_segment(p, &ray, lw, &pr);
        if (st < 0) {
            return st;
        }
        if (st == CT_BELOW && first) {
            h->steps = *steps;
            h->iters = *iters;
            return CT_BELOW;
        }
        if (st == CT_MISS) {
            return CT_MISS;
        }
        if (st == CT_BELOW) {
            /* the previous piece ended above the surface: the path met it
             * within the models' tolerance at A */
            pr.start = CT_HIT;
        }
        st = ct_trace_prepared_lowered(p, &pr, lw, m, &sh);
        if (st < 0) {
            return st;
        }
        tend_n = pr.tend_n;
        tend_d = pr.tend_d;
    }
    *steps += sh.steps;
    *iters += sh.iters;
    /* t_q26 < 2^35, tend_d <= 2^26: < 2^61; tend_n < 2^34 */
    if ((st == CT_HIT || st == CT_HIT_VOID) && sh.t_q26 * tend_d <= tend_n * (INT64_C(1) << CT_T_FRAC_BITS)) {
        *h = sh;
        h->steps = *steps;
        h->iters = *iters;
        return st;
    }
    return CT_MISS;
}

/* Refraction's bending vector w = up - (up . d) d (Q30), up the frame's
 * third column, d the unit direction: of length cos(elevation), so that the
 * path P(t) = C + t d - (k t^2 / 2R) w bends with the textbook ray
 * curvature k cos(elev) / R of a horizontally layered atmosphere -- its
 * vertical drop k t^2 cos^2(elev) / 2R = k rho^2 / 2R is the sphere
 * model's (the lowered walk's), and a steep path's horizontal speed
 * cos(elev) shrinks by at most t k / R cos(elev) |sin(elev)|, so it never
 * turns back within R / k >= 3,185 km (gone() relies on its heading).  A
 * vertical path (w = 0) is not bent: pa->refract stays 0. */
static void refraction_axis(path *pa, const ct_earth *es)
{
    int64_t up[3], dq[3], dot = 0;
    int k;
    for (k = 0; k < 3; ++k) { /* bound: 3 */
        up[k] = es->frame_q30[3 * k + 2];
        dq[k] = ct_floor_div(pa->d[k] + (INT64_C(1) << 8), INT64_C(1) << 9); /* Q30 */
        dot += up[k] * dq[k];                                               /* < 2^62 */
    }
    dot = ct_floor_div(dot + (INT64_C(1) << 29), INT64_C(1) << 30);
    for (k = 0; k < 3; ++k) { /* bound: 3; |w| <= 2^30 + 2 */
        pa->w[k] = up[k] - ct_floor_div(dot * dq[k] + (INT64_C(1) << 29), INT64_C(1) << 30);
        if (pa->w[k] != 0) {
            pa->refract = 1;
        }
    }
}

/* The path of the line of sight with grid direction dg (Q39): its
 * direction in Earth-fixed axes, refraction's bending direction, and the
 * interpolation nodes over [0, tmax].  Out of line: inlined, its frame and
 * set_nodes' would sit under earth_walk's on the deepest path (M0 +40 B). */
CT_NOINLINE static void path_init(path *pa, const ct_package *p, const ct_earth *es, const int64_t dg[3])
{
    int k;
    pa->p = p;
    pa->es = es;
    pa->zone = es->zone;
    /* d = frame dg: |frame| <= 2^30, |dg| <= 2^40: products < 2^70 */
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        ct_i128 s = ct_i128_from64(0);
        int j;
        for (j = 0; j < 3; ++j) { /* bound: 3 terms */
            s = ct_i128_add(s, ct_i128_mul(es->frame_q30[3 * k + j], dg[j]));
        }
        pa->d[k] = ct_i128_round_shr(s, 30u);
        pa->w[k] = 0;
    }
    pa->refract = 0;
    if (es->refr_k_q16 != 0) {
        refraction_axis(pa, es);
    }
    pa->interp = 0;
    set_nodes(pa, es->tmax_nm);
}

/* One piece of the path, from A (at ta) to B (at ta + Lc) through its
 * middle M: the model's ends As, Bs (A and B shifted sideways towards M,
 * chord_shift) and the chord and quadratic fitted through As, M, Bs (f), 1 when it
 * is off the tile (nothing to trace), the lowering it is traced against
 * (lwp: &lw or NULL) and its value at B (dB), the model's largest errors
 * sideways and vertically (elat, Q24; evert, Q16 height units).  Not to be
 * copied: lwp points into it. */
typedef struct {
    gv B, M;
    gv As, Bs; /* the model's ends: A and B, shifted sideways (chord_shift) */
    fit f;
    int64_t Lc, elat, evert, dB;
    int off;
    ct_lower lw;
    const ct_lower *lwp;
} piece;

/* The errors' excess over the tolerances, the larger of the two, in
 * 1/1024 (each error capped at 2^40): both < 2^62. */
static int64_t excess_1024(const ct_earth *es, int64_t elat, int64_t evert)
{
    return ct_max64(ct_min64(elat, INT64_C(1) << 40) * 1024 / ct_max64(es->tol_q24, 1),
                    ct_min64(evert, INT64_C(1) << 40) * 1024 / ct_max64(es->tolz_q16, 1));
}

#define BOUND_CAP (INT64_C(1) << 60)

/* ceil(v / 2^n) for 0 <= v < 2^126 and n < 128, saturated at BOUND_CAP. */
static int64_t shr_up_sat(ct_i128 v, unsigned n)
{
    unsigned b = ct_i128_bits(v);
    if (b > n + 60u) {
        return BOUND_CAP;
    }
    if (b <= n) {
        return b == 0u ? 0 : 1;
    }
    /* n < b <= n + 60: ceil(v / 2^n) = floor((v - 1) / 2^n) + 1 < 2^60 */
    v = ct_i128_sub(v, ct_i128_from64(1));
    /* bound: 2 shifts of 63 */
    while (n >= 63u) {
        v = ct_i128_sar(v, 63u);
        n -= 63u;
    }
    if (n > 0u) {
        v = ct_i128_sar(v, n);
    }
    return ct_i128_to64(v) + 1;
}

/* The model's largest errors over a piece of the interpolated path,
 * bounded from the path polynomial's derivatives (not sampled): q, the
 * quadratic in sigma through the path's images A, M, B, differs from the
 * path by at most rem3 of |f'''| h^3 per coordinate.
 *   - Sideways (here; check_piece adds it to the larger of the ends' and
 *     M's distances from the shifted chord): q's distance from the chord A
 *     -> B is 4 s (1 - s) times M's (s in [0, 1] along the piece), so from
 *     the shifted chord, parallel to it, at most the larger of the ends'
 *     and M's; the path is within the remainder of q (Q24 cells; |x'''| +
 *     |y'''| <= b3h).  8 units for the polynomial's roundings.  (The first
 *     piece from the camera starts at the camera's grid point, not at the
 *     path's image cam24: check_piece takes the largest distance of the
 *     quadratic through cam24, M and B instead, quad_max.)
 *   - In height: bound_vert. */
static int64_t side_rem(const path *pa, int64_t hq, int64_t l24)
{
    /* a chord shorter than a Q16 unit: distances from A, not from the
     * line, which q may pass by B's (< 2^8; Lagrange weights in [-1/8, 1]) */
    return rem3(pow_h(pa->b3h, hq, 3)) + 8 + (l24 < 256 ? 256 : 0);
}

/* The largest |g(s)| over s in [0, 1] of the quadratic with g(0) = y0,
 * g(1/2) = ym, g(1) = y1 (|y| < 2^47), rounded up: g = y0 + b s + c s^2,
 * b = 4 ym - 3 y0 - y1, c = 2 (y0 + y1 - 2 ym); at the ends, or y0 - b^2
 * / 4c where -b / 2c lies inside (b^2 < 2^100, 4 |c| < 2^51). */
static int64_t quad_max(int64_t y0, int64_t ym, int64_t y1)
{
    int64_t b = 4 * ym - 3 * y0 - y1, c = 2 * (y0 + y1 - 2 * ym);
    int64_t m = ct_max64(ct_abs64(y0), ct_abs64(y1));
    if (c != 0 && (b < 0) == (c > 0) && b != 0 && ct_abs64(b) < 2 * ct_abs64(c)) {
        int64_t q = ct_i128_floor_div_sat(ct_i128_mul(b, b), 4 * ct_abs64(c));
        m = ct_max64(m, ct_abs64(c > 0 ? y0 - q : y0 + q) + 1);
    }
    return m;
}

/* The height part (Q16 height units) for a piece traced as a lowered walk
 * (pc->lwp set; rh = side_rem, pc->elat the sideways bound):
 *   - at the path's range s(sigma) along the chord, the walk's
 *     model Z(s) = zA + b s + a s^2 (b the walk line's slope dz / l, a =
 *     kf / 2^kshift the lowering's rise) meets the path at A, M and B up to
 *     the vertices' Q16 rounding (which the tolerance's quarter is for), so
 *     g = z - Z(s(sigma)) has three equally spaced zeros and is within
 *     rem3 of |g'''| h^3, where |g'''| <= |z'''| + |Z'(s)| |s'''| + 6 a |s'|
 *     |s''|, |s^(k)| <= b_kh, |Z'| <= |b| + 2 a S (S = l + rh / 256 + 3,
 *     Q16: the farthest range along the chord).  The last term, 6 rem3(1) a (b1h h)
 *     (b2h h^2) < a L1 L2 / 16 (in Q24: a / 256 per Q24 cell squared).  A
 *     point of the path off the walk line by lambda <= elat is lowered by a
 *     lambda^2 more.  3 Q16 units for the lowering's floors, and dip / 2^28
 *     for kf's truncation (relative 2^-30 of a).
 * Each term saturates at BOUND_CAP (the piece then fails its check). */
static int64_t bound_vert(const path *pa, const ct_earth *es, int64_t ta, int64_t hq, int64_t rh, const gv *A,
                          const piece *pc)
{
    const ct_lower *lw = &pc->lw;
    int64_t l = pc->f.l, rhc = ct_min64(rh, BOUND_CAP), lam, S, L1, L2, sum, t;
    int64_t adz = ct_abs64(pc->Bs.z - pc->dB - A->z); /* |z| < 2^56 */
    /* height: z''' (and the camera's grid point's height on the first piece) */
    sum = rem3(pow_h(pa->b3z, hq, 3)) + 8 + (ta == 0 ? ct_abs64(es->cam24[2] - A->fz) : 0);
    /* |b| rh = |dz| rh / l (l >= 2^16 with a lowering; < 2^56 2^60) */
    t = ct_i128_floor_div_sat(ct_i128_add(ct_i128_mul(adz, rhc), ct_i128_from64(l - 1)), l);
    sum += ct_min64(t, BOUND_CAP);
    /* 2 a S rh: kf < 2^32, S < 2^44, rh < 2^40: < 2^117 */
    S = l + rhc / 256 + 3;
    t = BOUND_CAP;
    if (rhc < (INT64_C(1) << 40) && S < (INT64_C(1) << 44)) {
        t = shr_up_sat(ct_i128_mul128_64(ct_i128_mul((int64_t)lw->kf, S), 2 * rhc), lw->kshift);
    }
    sum += t;
    /* a L1 L2 / 16, in Q24 a further / 256: L1, L2 < 2^44, kf < 2^32 */
    L1 = pow_h(pa->b1h, hq, 1);
    L2 = pow_h(pa->b2h, hq, 2);
    t = BOUND_CAP;
    if (L1 < (INT64_C(1) << 44) && L2 < (INT64_C(1) << 44)) {
        t = shr_up_sat(ct_i128_mul128_64(ct_i128_mul(L1, L2), (int64_t)lw->kf), lw->kshift + 12u);
    }
    sum += t; /* four terms each <= 2^60 + 8 */
    /* a lambda^2, lambda <= elat (Q16, rounded up; < 2^40: < 2^112) */
    lam = pc->elat / 256 + 1;
    t = BOUND_CAP;
    if (lam < (INT64_C(1) << 40)) {
        t = shr_up_sat(ct_i128_mul128_64(ct_i128_mul(lam, lam), (int64_t)lw->kf), lw->kshift);
    }
    return (sum + 255) / 256 + 3 + (ct_min64(pc->f.dip, BOUND_CAP) >> 28) + 1 + t;
}

/* The model of the piece from A with its B and M set, checked against the
 * exact image: 1 when it is within the tolerances or off the tile, 0 when
 * it must be shorter, -1 when a quarter point is beyond the projection's
 * domain.  Sets As, Bs, f, off, lwp (and lw), dB (0 without a lowering), elat,
 * evert. */
static int check_piece(const ct_package *p, const path *pa, const ct_earth *es, const gv *A, int64_t ta, int shift,
                       piece *pc)
{
    int ok;
    int64_t sx, sy, hq = 0, rh = 0;
    fit_chord(A, &pc->B, &pc->f);
    pc->As = *A;
    pc->Bs = pc->B;
    pc->elat = 0;
    if (shift && chord_shift(A, &pc->B, side24(A, &pc->B, pc->f.l24, &pc->M), pc->f.l24, &sx, &sy)) {
        /* |s| <= |dv| / 2 + 1 < 2^45: the ends stay within the walks'
         * range where A and B are (ct_map_to_grid's 2^55) */
        gv_shift(&pc->As, sx, sy);
        gv_shift(&pc->Bs, sx, sy);
        /* the walk's chord between the shifted Q16 ends, when their
         * rounding changed it (the Q24 one is parallel to A -> B, of the
         * same l24) */
        if (pc->Bs.x - pc->As.x != pc->f.ux || pc->Bs.y - pc->As.y != pc->f.uy) {
            fit_u(&pc->As, &pc->Bs, &pc->f);
        }
        /* the ends' own distance from the shifted line (the same at both) */
        pc->elat = lateral24(&pc->As, &pc->Bs, pc->f.l24, A);
    }
    fit_middle(&pc->As, &pc->Bs, &pc->M, &pc->f);
    pc->off = piece_off(p, pa, A, &pc->B, &pc->M, &pc->f, pc->Lc, es->tolz_q16);
    pc->lwp = NULL;
    pc->dB = 0; /* with lwp: a try that fails before the quarter points
                   must not keep an earlier, longer try's lowering */
    pc->elat = ct_max64(pc->elat, pc->f.dev);
    pc->evert = 0;
    if (pa->interp) {
        /* the sideways bound (side_rem) */
        hq = piece_hq(pa, pc->Lc);
        rh = ct_min64(side_rem(pa, hq, pc->f.l24), BOUND_CAP);
        if (ta == 0 && pc->f.l24 >= 256) {
            /* the first piece from the camera: its A is the camera's grid
             * point, within a Q16 unit of the path's own start cam24 --
             * the quadratic through cam24, M and B (signed distances from
             * the chord, < 2^47 as |M - A|) */
            gv C = *A;
            C.fx = es->cam24[0];
            C.fy = es->cam24[1];
            pc->elat = ct_max64(pc->elat, quad_max(side24(&pc->As, &pc->Bs, pc->f.l24, &C), pc->f.sdev,
                                                   side24(&pc->As, &pc->Bs, pc->f.l24, &pc->B)));
        } else if (ta == 0) {
            /* (distances from A: cam24 within 2^8 + 2 of it) */
            pc->elat += ct_abs64(es->cam24[0] - A->fx) + ct_abs64(es->cam24[1] - A->fy);
        }
        pc->elat = ct_min64(pc->elat, BOUND_CAP) + rh;
    }
    ok = pc->off || pc->elat <= es->tol_q24;
    if (ok && !pc->off) {
        uint64_t kf;
        uint32_t ks;
        if (ct_i128_sign(pc->f.num) > 0 && ct_i128_sign(pc->f.den) > 0 && rise_coeff(pc->f.num, pc->f.den, &kf, &ks) &&
            ct_lower_setup_k(p, pc->As.x, pc->As.y, kf, ks, es->cull, &pc->lw) == CT_OK) {
            pc->lwp = &pc->lw;
        }
        pc->dB = pc->lwp != NULL ? ct_lower_at(pc->lwp, pc->Bs.x, pc->Bs.y) : 0;
        if (pa->interp && pc->lwp != NULL) {
            /* the interpolated path and a lowered walk: the errors bounded */
            pc->evert = bound_vert(pa, es, ta, hq, rh, A, pc);
        } else if (quarter_errors(pa, ta, pc->Lc, &pc->As, &pc->Bs, &pc->f, pc->lwp, pc->dB, &pc->elat,
                                  &pc->evert) != CT_OK) {
            /* otherwise the model against the image at the quarter points */
            return -1;
        }
        ok = pc->elat <= es->tol_q24 && pc->evert <= es->tolz_q16;
    }
    return ok;
}

/* The next piece from A (at ta): *L long at most (and not beyond tend),
 * shortened until its model is within the tolerances
 * or it is PIECE_MIN_NM long; *L is left at the length of the last try.
 * A piece with a point beyond the projection's domain (its end, middle or
 * quarter points) is shortened to 1/8 too: the tile lies inside the
 * domain, so the path may still meet it before leaving (a tile near the
 * zone's edge).  CT_MISS when even PIECE_MIN_NM reaches beyond the domain
 * (or the tries run out on such a piece); CT_ERR_EFFECTS when the last try
 * is still not within the tolerances (a chord finer than the pieces' own
 * rounding allows: such a piece is never used); else CT_OK. */
CT_NOINLINE static ct_status next_piece(const ct_package *p, const path *pa, const ct_earth *es, const gv *A,
                                        int64_t ta, int64_t tend, int shift, int64_t *L, piece *pc)
{
    uint32_t r;
    int ok = -1;
    pc->dB = 0;
    /* bound: EARTH_MAX_RETRIES + 1 tries */
    for (r = 0u; r <= EARTH_MAX_RETRIES; ++r) {
        pc->Lc = ct_min64(*L, tend - ta);
        ok = -1;
        if (vertex(pa, ta + pc->Lc, &pc->B) == CT_OK && vertex(pa, ta + pc->Lc / 2, &pc->M) == CT_OK) {
            ok = check_piece(p, pa, es, A, ta, shift, pc);
        }
        if (ok < 0) {
            /* beyond the domain: a shorter piece, down to PIECE_MIN_NM */
            if (pc->Lc <= PIECE_MIN_NM) {
                return CT_MISS;
            }
            *L = ct_max64(PIECE_MIN_NM, pc->Lc / 8);
            continue;
        }
        if (ok || pc->Lc <= PIECE_MIN_NM) {
            break;
        }
        {
            /* shorten by sqrt(tol / excess) * 0.8 (at least 1/8): excess >= tol */
            int64_t fr = (int64_t)ct_isqrt64(
                (uint64_t)((INT64_C(1) << 40) / ct_max64(excess_1024(es, pc->elat, pc->evert), 1024))); /* Q15 */
            *L = ct_max64(PIECE_MIN_NM, ct_max64(pc->Lc / 8, ct_mul_shr(pc->Lc, fr * 4 / 5, 15u)));
        }
    }
    return ok < 0 ? CT_MISS : (ok ? CT_OK : CT_ERR_EFFECTS);
}

/* The length to try for the piece after pc: longer where pc was well
 * within the tolerances or off the tile. */
static int64_t next_length(const ct_earth *es, const piece *pc)
{
    int64_t fr;
    if (pc->off) {
        return ct_min64(PIECE_MAX_NM, 2 * pc->Lc);
    }
    /* the errors grow as the square of the length: aim at 0.8 of the
     * tolerance ((29/32)^2 = 0.82: the sideways bend, which sets most
     * pieces' lengths, changes little from one piece to the next), by a
     * factor in [1/2, 2] */
    fr = (int64_t)ct_isqrt64(
        (uint64_t)((INT64_C(1) << 40) / ct_max64(excess_1024(es, pc->elat, pc->evert), 64))); /* Q15 */
    fr = ct_min64(INT64_C(2) << 15, ct_max64(INT64_C(1) << 14, fr * 29 / 32));
    return ct_min64(PIECE_MAX_NM, ct_max64(PIECE_MIN_NM, ct_mul_shr(pc->Lc, fr, 15u)));
}

/* sigma's bounds (Q30) from one axis of the interpolated image: where its
 * linear part b + c1 sigma (c1 != 0) lies in [lo, hi] (lo_open: no lower
 * bound), the ends rounded outwards.  |b| < 2^64 (base < 2^63 plus c_0 <
 * 2^49), |lo|, |hi| < 2^62: differences times 2^30 < 2^95. */
static void span_axis(ct_i128 b, int64_t c1, int64_t lo, int lo_open, int64_t hi, int64_t *s0, int64_t *s1)
{
    ct_i128 up = ct_i128_shl(ct_i128_sub(ct_i128_from64(hi), b), 30u);
    ct_i128 dn = ct_i128_shl(ct_i128_sub(ct_i128_from64(lo), b), 30u);
    if (c1 > 0) {
        /* s in [(lo - b) / c1, (hi - b) / c1] */
        *s1 = ct_min64(*s1, -ct_i128_floor_div_sat(ct_i128_neg(up), c1));
        if (!lo_open) {
            *s0 = ct_max64(*s0, ct_i128_floor_div_sat(dn, c1));
        }
    } else {
        /* s in [(b - hi) / |c1|, (b - lo) / |c1|] */
        *s0 = ct_max64(*s0, ct_i128_floor_div_sat(ct_i128_neg(up), -c1));
        if (!lo_open) {
            *s1 = ct_min64(*s1, -ct_i128_floor_div_sat(dn, -c1));
        }
    }
}

/* The part [*t0, *t1] of [0, tmax] outside which the interpolated path is
 * off the tile as piece_off sees it (beyond 2 cells of an edge, or above
 * the tallest post by the height tolerance): per axis the polynomial is its
 * linear part b + c_1 sigma within E = the sum of |c_j|, j >= 2 (|sigma| <=
 * 1; < 2^52), plus one unit per Horner rounding and one for c_1 = 0 taken
 * as 1.  0 when it is off everywhere.  Pieces then start at t0 (no off
 * pieces before it, each two vertices and a fit) and end by t1. */
static int path_span(const path *pa, const ct_package *p, const ct_earth *es, int64_t *t0, int64_t *t1)
{
    int64_t s0 = -(INT64_C(1) << 30), s1 = INT64_C(1) << 30;
    int j, k;
    for (k = 0; k < 3; ++k) { /* bound: 3 coordinates */
        int64_t e = NODES + 1, lo, hi;
        for (j = 2; j < pa->nodes; ++j) { /* bound: NODES - 2; |c_j| < 2^49 */
            e += ct_abs64(pa->cf[j][k]);
        }
        if (k < 2) {
            /* cells <= 2^31: < 2^56 */
            lo = -2 * ONE16 * 256 - e;
            hi = ((int64_t)(k == 0 ? p->cells_x : p->cells_y) + 2) * ONE16 * 256 + e;
        } else {
            /* hmax < 2^16; the tolerance capped at 2^36 Q16 units (2^20
             * height units) */
            lo = 0;
            hi = (((int64_t)p->hmax + 1) * ONE16 + ct_min64(es->tolz_q16, INT64_C(1) << 36)) * 256 + e;
        }
        span_axis(ct_i128_add(ct_i128_from64(pa->base[k]), ct_i128_from64(pa->cf[0][k])),
                  pa->cf[1][k] + (pa->cf[1][k] == 0), lo, k == 2, hi, &s0, &s1);
    }
    /* s0 only rose from -2^30 and s1 only fell from 2^30 */
    if (s0 > s1) {
        return 0;
    }
    /* t = tmax (sigma + 1) / 2, t0 rounded down and t1 up: tmax < 2^49,
     * sigma + 2^30 in [0, 2^31]: 0 <= t0 <= t1 <= tmax */
    *t0 = ct_i128_to64(ct_i128_sar(ct_i128_mul(pa->tmax, s0 + (INT64_C(1) << 30)), 31u));
    *t1 = -ct_i128_to64(ct_i128_sar(ct_i128_neg(ct_i128_mul(pa->tmax, s1 + (INT64_C(1) << 30))), 31u));
    return 1;
}

#if CT_TEST_HOOKS
ct_status ct_earth_path_image24(const ct_package *p, const ct_earth *es, const int64_t dg[3], int64_t t, int interp,
                                int64_t g[3], int32_t *nodes)
{
    path pa;
    gv v = {0, 0, 0, 0, 0, 0};
    ct_status st;
    if (p == NULL || es == NULL || dg == NULL || g == NULL || nodes == NULL || t < 0 || t > es->tmax_nm) {
        return CT_ERR_ARG;
    }
    path_init(&pa, p, es, dg);
    *nodes = pa.nodes * pa.interp + 8 * pa.alone;
    if (interp && !pa.interp) {
        return CT_ERR_RANGE;
    }
    st = interp ? vertex(&pa, t, &v) : vertex_exact(&pa, t, &v);
    g[0] = v.fx;
    g[1] = v.fy;
    g[2] = v.fz;
    return st;
}
#endif

/* 1 for the camera's own piece over the tile: it starts at the camera (its
 * CT_BELOW is the camera's) and is not shifted sideways. */
static int camera_piece(int64_t ta, int over)
{
    return ta == 0 && over;
}

/* The first piece's length to try: where the path's sideways bend, as its
 * polynomial's second-degree term shows it (k = 2 |c1 x c2| / |c1|, the
 * sideways second derivative in sigma at its middle; x, y of |c| < 2^49:
 * the cross product < 2^99 in 128 bits, k < 2^51), puts the chord at 0.8
 * of the tolerance: k h^2 / 16 (shifted: half the deviation; else / 8) =
 * 0.8 tol, h = 2 L / tmax the piece in sigma.  A guess (next_piece checks
 * the piece): PIECE_FIRST_NM without a bend, and within [PIECE_MIN_NM,
 * PIECE_FIRST_NM] (longer pieces grow from there). */
CT_NOINLINE static int64_t first_length(const path *pa, const ct_earth *es, int shift)
{
    ct_i128 cross = ct_i128_sub(ct_i128_mul(pa->cf[1][0], pa->cf[2][1]), ct_i128_mul(pa->cf[1][1], pa->cf[2][0]));
    int64_t n1 = (int64_t)ct_i128_isqrt(
        ct_i128_add(ct_i128_mul(pa->cf[1][0], pa->cf[1][0]), ct_i128_mul(pa->cf[1][1], pa->cf[1][1])));
    int64_t k, h2, L;
    if (n1 == 0) {
        return PIECE_FIRST_NM;
    }
    k = ct_i128_floor_div_sat(ct_i128_shl(ct_i128_abs(cross), 1u), n1);
    if (k <= 0) {
        return PIECE_FIRST_NM;
    }
    /* h^2 in Q60 = (12.8 or 6.4) tol 2^60 / k: tol capped at 2^48, 13 tol
     * 2^60 < 2^112; saturated at 2^62 (h = 2, the whole path), so h in Q30
     * <= 2^31 and h tmax < 2^80 */
    h2 = ct_i128_floor_div_sat(
        ct_i128_shl(ct_i128_from64(ct_min64(es->tol_q24, INT64_C(1) << 48) * (shift ? 64 : 32) / 5), 60u), k);
    L = ct_i128_to64(ct_i128_sar(ct_i128_mul((int64_t)ct_isqrt64((uint64_t)h2), pa->tmax), 31u));
    return ct_min64(PIECE_FIRST_NM, ct_max64(PIECE_MIN_NM, L));
}

/* The pieces' record for ct_earth_pieces (a test hook, compiled with
 * CT_TEST_HOOKS only): NULL when tracing, and always in a flight build. */
typedef struct {
    ct_earth_piece *out;
    uint32_t cap, n;
} piece_log;

static void log_piece(piece_log *lg, const path *pa, const gv *A, int64_t ta, const piece *pc)
{
    ct_earth_piece *e;
    if (lg->n >= lg->cap) {
        return;
    }
    e = &lg->out[lg->n++];
    e->ta_nm = ta;
    e->lc_nm = pc->Lc;
    e->a24[0] = A->fx;
    e->a24[1] = A->fy;
    e->a24[2] = A->fz;
    e->m24[0] = pc->M.fx;
    e->m24[1] = pc->M.fy;
    e->m24[2] = pc->M.fz;
    e->b24[0] = pc->B.fx;
    e->b24[1] = pc->B.fy;
    e->b24[2] = pc->B.fz;
    e->walk_q16[0] = pc->As.x;
    e->walk_q16[1] = pc->As.y;
    e->walk_q16[2] = pc->As.z;
    e->walk_q16[3] = pc->Bs.x;
    e->walk_q16[4] = pc->Bs.y;
    e->walk_q16[5] = pc->Bs.z - pc->dB;
    e->shift_q24[0] = pc->As.fx - A->fx;
    e->shift_q24[1] = pc->As.fy - A->fy;
    e->lowered = pc->lwp != NULL;
    e->kf = pc->lwp != NULL ? pc->lw.kf : 0u;
    e->kshift = pc->lwp != NULL ? pc->lw.kshift : 0u;
    e->elat_q24 = pc->elat;
    e->evert_q16 = pc->evert;
    e->off = pc->off;
    e->bounded = (int32_t)((pa->interp != 0) & (pc->lwp != NULL)); /* check_piece bounds these */
}

/* The line of sight as pieces of lowered walks from the camera: each piece
 * chosen (next_piece), traced unless off the tile (trace_piece), until a
 * hit, an error, the path's end or a path gone from the tile.  With lg,
 * every piece is logged and none traced. */
static ct_status earth_walk(const ct_package *p, ct_tileset *ts, const ct_earth *es, const int64_t dg[3], ct_method m,
                            ct_hit *h, piece_log *lg)
{
    path pa;
    gv A;
    piece pc;
    int64_t ta = 0, tend, L = PIECE_FIRST_NM;
    uint32_t n, steps = 0u, iters = 0u;
    int over;
    ct_status st;
    path_init(&pa, p, es, dg);
    A.x = es->ox;
    A.y = es->oy;
    A.z = es->oz;
    A.fx = es->ox * 256; /* |ox| <= 2^46 */
    A.fy = es->oy * 256;
    A.fz = es->oz * 256;
    /* CT_BELOW: the camera over the tile and under its surface; a path
     * entering the tile's side below the surface meets the side there */
    over = (uint64_t)es->ox <= (uint64_t)p->cells_x * (uint64_t)ONE16 &&
           (uint64_t)es->oy <= (uint64_t)p->cells_y * (uint64_t)ONE16; /* negative: huge */
    tend = es->tmax_nm;
    if (pa.interp) {
        int64_t t0, t1;
        if (path_span(&pa, p, es, &t0, &t1)) {
            tend = t1;
            ta = t0;
        } else {
            ta = tend; /* off everywhere: no piece */
        }
        if (ta > 0) {
            /* the first piece's start, off the tile (an interpolated vertex
             * is always CT_OK); at 0 the camera's own grid point */
            (void)vertex(&pa, ta, &A);
        }
        L = first_length(&pa, es, !camera_piece(ta, over));
    }
    /* bound: EARTH_MAX_PIECES pieces (each with at most EARTH_MAX_RETRIES
     * + 1 tries in next_piece) */
    for (n = 0u; n < EARTH_MAX_PIECES && ta < tend; ++n) {
        int first = camera_piece(ta, over);
        st = next_piece(p, &pa, es, &A, ta, tend, !first, &L, &pc);
        if (st != CT_OK) {
            h->steps = steps;
            h->iters = iters;
            return st; /* CT_MISS: beyond the projection's domain */
        }
        if (CT_TEST_HOOKS && lg != NULL) { /* a flight build has no log: the compiler drops it */
            log_piece(lg, &pa, &A, ta, &pc);
        } else if (!pc.off && !(es->cull && piece_culled(p, &pc.As, &pc.Bs, pc.dB))) {
            st = trace_piece(p, ts, &pc.As, &pc.Bs, &pc.f, pc.lwp, pc.dB, first, m, h, &steps, &iters);
            if (st != CT_MISS) {
                return st; /* a hit, the camera below the surface, or an error */
            }
        }
        steps++;
        iters++;
        if (gone(p, &A, &pc.B, &pc.M, &pc.f)) {
            break;
        }
        L = next_length(es, &pc);
        A = pc.B;
        ta += pc.Lc;
    }
    h->steps = steps;
    h->iters = iters;
    h->x_q16 = h->y_q16 = h->z_q16 = 0;
    h->e_nm = h->n_nm = h->h_nm = 0;
    h->cell_x = h->cell_y = -1;
    /* EARTH_MAX_PIECES pieces while the path goes on over the tile (not
     * gone, which breaks out before n reaches the bound): not a miss (a
     * chord too fine for the path's length) */
    return n == EARTH_MAX_PIECES && ta < tend ? CT_ERR_RANGE : CT_MISS;
}

ct_status ct_trace_earth_set(const ct_package *p, ct_tileset *ts, const ct_earth *es, const int64_t dg[3], ct_method m,
                             ct_hit *h)
{
    if (p == NULL || es == NULL || dg == NULL || h == NULL) {
        return CT_ERR_ARG;
    }
    if ((uint32_t)m >= (uint32_t)CT_METHOD_COUNT) {
        return CT_ERR_METHOD;
    }
    return earth_walk(p, ts, es, dg, m, h, NULL);
}

#if CT_TEST_HOOKS
ct_status ct_earth_pieces(const ct_package *p, const ct_earth *es, const int64_t dg[3], ct_earth_piece *out,
                          uint32_t cap, uint32_t *n)
{
    piece_log lg;
    ct_hit h;
    ct_status st;
    if (p == NULL || es == NULL || dg == NULL || out == NULL || n == NULL) {
        return CT_ERR_ARG;
    }
    lg.out = out;
    lg.cap = cap;
    lg.n = 0u;
    st = earth_walk(p, NULL, es, dg, CT_METHOD_INCREMENTAL, &h, &lg);
    *n = lg.n;
    return st;
}
#endif
