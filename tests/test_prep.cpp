// test_prep.cpp -- the ray the tracer is exact for, against the caller's ray.
//
// ct_ray_prepare clips the caller's ray to the tile's box with exact
// rationals, rounds the entry point to Q16 (z to units of 2^zshift Q16) and
// scales the direction (x, y, z / 2^zshift) so its largest component is
// 2^26 - 1 or 2^26.  docs/library.md ("Exactness and the error bound")
// states the resulting bound: a point of the prepared ray at parameter t
// lies within
//     | (u_x (1/2 + c t), u_y (1/2 + c t), u_z ((2^k + 1)/2 + 2^k c t)) |
// metres of the caller's line (u: metres per Q16 unit, k = zshift,
// c = 1/2 + 2^-6: each direction component's rounding), which keeps it within
// 1 mm anywhere in a tile up to 2,048 cells (61 km at 30 m); and a hit is within
// 2 Q16 units (2 z units) of the prepared ray's exact first hit.  This test
// checks both against an independent clip (128-bit rationals written
// separately from lib/) and long double geometry, plus the grid <-> map
// conversions.
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
#include "harness.h"

typedef __int128 i128;
typedef long double ld;

namespace {

struct Rat {
    i128 n, d;  // d > 0
};
bool rat_lt(const Rat &a, const Rat &b) { return a.n * b.d < b.n * a.d; }

struct Fixture {
    dem_cases::Case c;
    ct_package p;
};

Fixture *make_fixture(int w, int h, uint64_t seed, double lo = 200, double hi = 3000, double scale = 0.25)
{
    static std::vector<std::unique_ptr<Fixture>> keep;  // alive until exit, then freed
    keep.push_back(std::make_unique<Fixture>());
    Fixture *f = keep.back().get();
    f->c = dem_cases::make_case("smooth", dem_cases::make_terrain(w, h, dem_cases::smooth(w, h, seed, lo, hi), scale),
                                8, 2);
    if (ct_package_open(&f->p, f->c.pkg.data(), f->c.pkg.size()) != CT_OK) return nullptr;
    return f;
}

int64_t rand_dir(ct_rng *r)
{
    switch (ct_rng_range(r, 0, 5)) {
    case 0: return 0;
    case 1: return ct_rng_range(r, -3, 3);
    case 2: return ct_rng_range(r, -(INT64_C(1) << 20), INT64_C(1) << 20);
    case 3: return ct_rng_range(r, -(INT64_C(1) << 40), INT64_C(1) << 40);
    default: {
        int64_t m = INT64_C(1) << 62;
        return ct_rng_range(r, -m, m);
    }
    }
}

ct_ray random_ray(ct_rng *r, const ct_package &p)
{
    ct_ray ray;
    int64_t W = (int64_t)p.cells_x << 16, H = (int64_t)p.cells_y << 16, Z = ((int64_t)p.hmax + 1) << 16;
    int64_t far = ct_rng_range(r, 0, 3) == 0 ? CT_MAX_ORIGIN_Q16 : 4 * std::max(W, Z);
    ray.x_q16 = ct_rng_range(r, 0, 2) ? ct_rng_range(r, -far, far) : ct_rng_range(r, 0, W);
    ray.y_q16 = ct_rng_range(r, 0, 2) ? ct_rng_range(r, -far, far) : ct_rng_range(r, 0, H);
    ray.z_q16 = ct_rng_range(r, -far, far);
    do {
        ray.dx = rand_dir(r);
        ray.dy = rand_dir(r);
        ray.dz = rand_dir(r);
    } while (ray.dx == 0 && ray.dy == 0 && ray.dz == 0);
    // aim half of them at a point of the tile's upper air so many enter
    if (ct_rng_range(r, 0, 1) == 0) {
        int64_t tx = ct_rng_range(r, 0, W), ty = ct_rng_range(r, 0, H), tz = ct_rng_range(r, Z / 2, Z);
        ray.dx = tx - ray.x_q16;
        ray.dy = ty - ray.y_q16;
        ray.dz = tz - ray.z_q16;
        if (ray.dx == 0 && ray.dy == 0 && ray.dz == 0) ray.dz = -1;
    }
    return ray;
}

// Independent clip: the entry parameter (as a rational in the caller's
// parameter) or false when the ray misses the box [0,W]x[0,H]x(-inf,Z].
bool clip(const ct_package &p, const ct_ray &ray, Rat *tin)
{
    const int64_t O[3] = {ray.x_q16, ray.y_q16, ray.z_q16}, U[3] = {ray.dx, ray.dy, ray.dz};
    const int64_t hi[3] = {(int64_t)p.cells_x << 16, (int64_t)p.cells_y << 16, ((int64_t)p.hmax + 1) << 16};
    Rat lo_t = {0, 1}, hi_t = {1, 0};  // hi_t = +infinity while d == 0
    for (int k = 0; k < 3; ++k) {
        bool has_floor = k < 2;
        if (U[k] == 0) {
            if ((has_floor && O[k] < 0) || O[k] > hi[k]) return false;
            continue;
        }
        Rat a, b;  // parameters at the two faces
        a = {(i128)(0 - O[k]), (i128)U[k]};
        b = {(i128)(hi[k] - O[k]), (i128)U[k]};
        if (U[k] < 0) {
            a.n = -a.n, a.d = -a.d;
            b.n = -b.n, b.d = -b.d;
            std::swap(a, b);  // a: enter (top face), b: leave (floor)
        }
        bool enter_face = U[k] > 0 ? has_floor : true;
        bool leave_face = U[k] > 0 ? true : has_floor;
        if (enter_face && rat_lt(lo_t, a)) lo_t = a;
        if (leave_face && (hi_t.d == 0 || rat_lt(b, hi_t))) hi_t = b;
    }
    if (hi_t.d != 0 && rat_lt(hi_t, lo_t)) return false;
    *tin = lo_t;
    return true;
}

// A point of the prepared ray at parameter t, in Q16 (z scaled back).
void prep_point(const ct_prepared &pr, ld t, ld P[3])
{
    P[0] = (ld)pr.ox + t * pr.dx;
    P[1] = (ld)pr.oy + t * pr.dy;
    P[2] = std::ldexp((ld)pr.oz + t * pr.dz, pr.zshift);
}

// Metres per Q16 unit on each axis.
void units_m(const ct_package &p, ld u[3])
{
    u[0] = std::fabs((ld)p.posting_e_nm) * 1e-9L / 65536;
    u[1] = std::fabs((ld)p.posting_n_nm) * 1e-9L / 65536;
    u[2] = (ld)p.height_scale_nm * 1e-9L / 65536;
}

// Distance in metres from the Q16 point P to the caller's line.
ld dist_to_line_m(const ct_package &p, const ct_ray &ray, const ld P[3])
{
    ld u[3], a[3], d[3];
    units_m(p, u);
    const ld O[3] = {(ld)ray.x_q16, (ld)ray.y_q16, (ld)ray.z_q16}, U[3] = {(ld)ray.dx, (ld)ray.dy, (ld)ray.dz};
    ld um = std::max(std::fabs(U[0]), std::max(std::fabs(U[1]), std::fabs(U[2])));
    for (int k = 0; k < 3; ++k) {
        a[k] = (P[k] - O[k]) * u[k];
        d[k] = U[k] / um * u[k];
    }
    ld c[3] = {a[1] * d[2] - a[2] * d[1], a[2] * d[0] - a[0] * d[2], a[0] * d[1] - a[1] * d[0]};
    return std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

// The stated bound at parameter t (see the top of this file), metres.
ld bound_m(const ct_package &p, const ct_prepared &pr, ld t)
{
    ld u[3];
    units_m(p, u);
    const ld c = 0.5L + 0x1p-6L, zk = std::ldexp(1.0L, pr.zshift);
    ld e[3] = {u[0] * (0.5L + c * t), u[1] * (0.5L + c * t), u[2] * ((zk + 1) / 2 + zk * c * t)};
    return std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) * (1 + 1e-12L) + 1e-15L;
}

void test_clip_entry_and_direction()
{
    Fixture *f = make_fixture(37, 29, 5);
    TEST_ASSERT(f != nullptr);
    ct_rng r;
    ct_rng_seed(&r, ct_test_seed() * 7 + 1);
    long n = (long)(200000 * ct_test_scale()), entered = 0, outside_origin = 0;
    ld worst = 0;
    for (long i = 0; i < n; ++i) {
        ct_ray ray = random_ray(&r, f->p);
        ct_prepared pr;
        ct_status st = ct_ray_prepare(&f->p, &ray, &pr);
        Rat tin;
        bool in = clip(f->p, ray, &tin);
        if (!in) {
            if (st != CT_MISS) TEST_FAIL_MSG("ray %ld: independent clip says miss, prepare says %d", i, (int)st);
            continue;
        }
        if (st == CT_MISS) TEST_FAIL_MSG("ray %ld: prepare says miss, the ray enters the box", i);
        TEST_ASSERT(st == CT_OK || st == CT_BELOW || st == CT_HIT);
        if (st != CT_OK) continue;  // decided at the first point: nothing more to compare
        entered++;
        // entry point: exact O + tin * U, rounded to the nearest Q16 unit
        const int64_t O[3] = {ray.x_q16, ray.y_q16, ray.z_q16}, U[3] = {ray.dx, ray.dy, ray.dz};
        const int64_t got[3] = {pr.ox, pr.oy, pr.oz * (INT64_C(1) << pr.zshift)};
        if (tin.n != 0) outside_origin++;
        for (int k = 0; k < 3; ++k) {
            // |got - (O + n/d * U)| <= e  <=>  |2 (got - O) d - 2 n U| <= 2 e d,
            // e = 1/2 (x, y), (2^k + 1)/2 (z: Q16, then units of 2^k)
            i128 lhs = 2 * ((i128)(got[k] - O[k]) * tin.d - tin.n * (i128)U[k]);
            i128 lim = k < 2 ? (i128)tin.d : (((i128)1 << pr.zshift) + 1) * tin.d;
            if (lhs < 0) lhs = -lhs;
            if (lhs > lim) TEST_FAIL_MSG("ray %ld axis %d: entry point off by more than half a unit", i, k);
        }
        // direction scale, length, sector, z shift
        int64_t m = std::max<int64_t>(std::abs(pr.dx), std::max<int64_t>(std::abs(pr.dy), std::abs(pr.dz)));
        TEST_ASSERT(m >= (INT64_C(1) << 26) - 1 && m <= (INT64_C(1) << 26));
        TEST_ASSERT(pr.zshift >= 0 && (uint32_t)pr.zshift <= f->p.zshift_max);
        if (pr.dx == 0 && pr.dy == 0) TEST_ASSERT_EQUAL_INT(0, pr.zshift);
        int64_t l2 = (int64_t)pr.dx * pr.dx + (int64_t)pr.dy * pr.dy;
        TEST_ASSERT(pr.len_lo * pr.len_lo <= l2 && pr.len_hi * pr.len_hi >= l2 && pr.len_hi - pr.len_lo <= 1);
        if (pr.dx == 0 && pr.dy == 0) {
            TEST_ASSERT_EQUAL_INT(-1, pr.sector);
        } else {
            uint32_t inside = 0;
            TEST_ASSERT(pr.sector >= 0 && (uint32_t)pr.sector < f->p.sectors);
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_in_wedge(f->p.bound_x, f->p.bound_y, f->p.sectors, (uint32_t)pr.sector,
                                                     pr.dx, pr.dy, &inside));
            TEST_ASSERT(inside == 1);
        }
        // the prepared ray stays within the stated bound of the caller's ray
        // up to where it leaves the box
        ld tend = (ld)pr.tend_n / (ld)pr.tend_d;
        for (int s = 0; s <= 4; ++s) {
            ld P[3], t = tend * s / 4;
            prep_point(pr, t, P);
            ld dev = dist_to_line_m(f->p, ray, P), b = bound_m(f->p, pr, t);
            worst = std::max(worst, dev / b);
            if (dev > b) TEST_FAIL_MSG("ray %ld: prepared ray %.4Lg m from the caller's (bound %.4Lg m)", i, dev, b);
        }
    }
    printf("  %ld rays, %ld entered (%ld from outside the box), worst deviation / bound %.3Lf\n", n, entered,
           outside_origin, worst);
    TEST_ASSERT(entered > n / 10 && outside_origin > n / 20);  // n/10: about 1 in 5 enter above the surface  // the sample exercises the clip
}

void test_hit_is_near_callers_ray()
{
    Fixture *f = make_fixture(41, 33, 9);
    TEST_ASSERT(f != nullptr);
    ct_rng r;
    ct_rng_seed(&r, ct_test_seed() * 11 + 3);
    long n = (long)(100000 * ct_test_scale()), hits = 0;
    ld worst = 0;
    for (long i = 0; i < n; ++i) {
        ct_ray ray = random_ray(&r, f->p);
        ct_prepared pr;
        if (ct_ray_prepare(&f->p, &ray, &pr) != CT_OK) continue;
        ct_hit h;
        ct_status st = ct_trace_prepared(&f->p, &pr, CT_METHOD_DIRECTIONAL, &h);
        if (st != CT_HIT) continue;
        hits++;
        // the reported point is the prepared ray's at t_q26 (floored to Q16,
        // z scaled to Q16 from units of 2^k), and so within the bound of the
        // caller's line plus one Q16 unit per axis
        ld t = (ld)h.t_q26 / (ld)(1 << 26), P[3], u[3];
        prep_point(pr, t, P);
        units_m(f->p, u);
        const ld Hq[3] = {(ld)h.x_q16, (ld)h.y_q16, (ld)h.z_q16};
        for (int k = 0; k < 3; ++k)
            if (std::fabs(Hq[k] - P[k]) > 1 + 1e-9L)  // floored (a vertical hit: its surface height, rounded up)
                TEST_FAIL_MSG("ray %ld axis %d: hit %.3Lf, prepared ray at t_q26 %.3Lf", i, k, Hq[k], P[k]);
        ld e = dist_to_line_m(f->p, ray, Hq), b = bound_m(f->p, pr, t) + std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        worst = std::max(worst, e / b);
        if (e > b)
            TEST_FAIL_MSG("ray %ld: hit %.4Lg m from the caller's ray, bound %.4Lg (ray %lld %lld %lld / %lld %lld %lld; prep %lld %lld %lld / %d %d %d k %d; hit %lld %lld %lld t %lld)", i, e, b,
                          (long long)ray.x_q16, (long long)ray.y_q16, (long long)ray.z_q16, (long long)ray.dx, (long long)ray.dy, (long long)ray.dz,
                          (long long)pr.ox, (long long)pr.oy, (long long)pr.oz, pr.dx, pr.dy, pr.dz, pr.zshift, (long long)h.x_q16, (long long)h.y_q16, (long long)h.z_q16, (long long)h.t_q26);
    }
    printf("  %ld hits, worst distance from the caller's ray / bound %.3Lf\n", hits, worst);
    TEST_ASSERT(hits > n / 10);
}

// The promise: the prepared ray within 1 mm of the caller's ray
// anywhere in the tile, for every direction.  A 2048-cell-long tile at 30 m
// (61 km) with 4,000 m of relief at 1/16 m LSB (the anisotropy of real
// packages: 480 LSB per cell), rays from up to 12 km above it and from far
// outside, steep, oblique, grazing and rising, in every azimuth.  (Scaled
// as one vector, a steep ray kept ~16 bits in dx and dy: centimetres here.)
void test_within_1mm_on_a_long_tile()
{
    const int W = 2049, H = 9;
    Fixture *f = make_fixture(W, H, 21, 0, 64000, 1.0 / 16);
    TEST_ASSERT(f != nullptr);
    const ct_package &p = f->p;
    TEST_ASSERT_EQUAL_INT(8, (int)p.zshift_max);  // 2^8 / 16 m = 16 m <= 30 m < 32 m
    ct_rng r;
    ct_rng_seed(&r, ct_test_seed() * 19 + 11);
    long n = (long)(60000 * ct_test_scale()), traced = 0, steep = 0;
    ld worst = 0, worst_b = 0;
    for (long i = 0; i < n; ++i) {
        double az = ct_rng_unit(&r) * 6.283185307179586, elev;
        switch (ct_rng_range(&r, 0, 3)) {
        case 0: elev = -(60 + 29.99 * ct_rng_unit(&r)) * 0.017453292519943295; break;  // steep
        case 1: elev = -(10 + 50 * ct_rng_unit(&r)) * 0.017453292519943295; break;     // oblique
        case 2: elev = -(0.01 + 10 * ct_rng_unit(&r)) * 0.017453292519943295; break;   // grazing
        default: elev = (ct_rng_unit(&r) * 20 - 10) * 0.017453292519943295; break;     // level, rising
        }
        double d[3];
        dem_cases::metric_dir(f->c.t, az, elev, d);
        // aim at a random point of the tile's air and start up to 40 km back
        double tx = ct_rng_unit(&r) * (W - 1), ty = ct_rng_unit(&r) * (H - 1), tz = 64000 * ct_rng_unit(&r);
        double back = ct_rng_unit(&r) * 40000.0;  // metres along the ray
        double dm = std::sqrt(std::pow(d[0] * 30, 2) + std::pow(d[1] * 30, 2) + std::pow(d[2] / 16, 2));
        double o[3] = {tx - d[0] * back / dm, ty - d[1] * back / dm, tz - d[2] * back / dm};
        if (o[2] > 64000 + 12000 * 16) continue;
        ct_ray ray = dem_cases::to_ray(o[0], o[1], o[2], d);
        ct_prepared pr;
        if (ct_ray_prepare(&p, &ray, &pr) != CT_OK) continue;
        traced++;
        if (pr.zshift > 0) steep++;
        ld tend = (ld)pr.tend_n / (ld)pr.tend_d;
        for (int s2 = 0; s2 <= 16; ++s2) {
            ld P[3], t = tend * s2 / 16;
            prep_point(pr, t, P);
            ld dev = dist_to_line_m(p, ray, P);
            worst = std::max(worst, dev);
            worst_b = std::max(worst_b, bound_m(p, pr, t));
            if (dev > 1e-3L)
                TEST_FAIL_MSG("ray %ld (elevation %.2f deg, zshift %d): prepared ray %.3Lf mm from the caller's at t = %.3Lf",
                              i, elev * 57.29577951308232, pr.zshift, dev * 1000, t);
        }
    }
    printf("  %ld rays traced (%ld with z in coarser units), worst distance from the caller's ray %.3Lf mm "
           "(the bound's worst %.3Lf mm)\n", traced, steep, worst * 1000, worst_b * 1000);
    TEST_ASSERT(traced > n / 4 && steep > traced / 8);
    TEST_ASSERT_MSG(worst_b <= 1e-3L, "the stated bound reaches %.3Lf mm on this tile", worst_b * 1000);
}

// Regressions from issue 19's first fuzzing run (run under ASan + UBSan as
// test_prep_san): an origin inside the tile horizontally but far below it
// (within the documented 2^46) made the box exit's rationals overflow before
// the ray was found to start below the surface; a direction component of
// INT64_MIN (outside the documented 2^62) overflowed |.| and was traced.
void test_fuzz_regressions()
{
    Fixture *f = make_fixture(9, 7, 13);
    TEST_ASSERT(f != nullptr);
    const ct_package &p = f->p;
    ct_prepared pr;
    ct_hit h;
    ct_ray deep = {5 * 65536, 4 * 65536, -INT64_C(1098567909376), INT64_C(107784773119), 1048576, 2146435072};
    TEST_ASSERT_EQUAL_INT(CT_BELOW, ct_ray_prepare(&p, &deep, &pr));
    TEST_ASSERT_EQUAL_INT(CT_BELOW, ct_trace(&p, &deep, CT_METHOD_DIRECTIONAL, &h));
    for (int k = 0; k < 3; ++k) {  // the lowest documented origin, in every direction
        ct_ray r = {3 * 65536, 2 * 65536, -CT_MAX_ORIGIN_Q16, 0, 0, 0};
        int64_t *d = k == 0 ? &r.dx : k == 1 ? &r.dy : &r.dz;
        for (int64_t mag : {INT64_C(1), INT64_C(1) << 31, INT64_C(1) << 62}) {
            *d = mag;
            r.dz = k == 2 ? mag : 1;
            TEST_ASSERT_EQUAL_INT(CT_BELOW, ct_ray_prepare(&p, &r, &pr));
        }
    }
    const int64_t bad[][6] = {
        {0, 0, 0, INT64_C(1369094286723776512), INT64_MIN, -2097152},
        {0, 0, 0, INT64_MIN, 1, 1},
        {0, 0, 0, 1, 1, INT64_MIN},
        {INT64_MIN, 0, 0, 1, 1, 1},
        {0, 0, INT64_MIN, 1, 1, -1},
    };
    ct_bend bd = {65536, INT64_C(6371000000000000), INT64_C(1000000), 0};
    for (const auto &b : bad) {
        ct_ray r = {b[0], b[1], b[2], b[3], b[4], b[5]};
        TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_ray_prepare(&p, &r, &pr));
        TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace(&p, &r, CT_METHOD_DIRECTIONAL, &h));
        TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_bent(&p, &r, &bd, CT_METHOD_HIERARCHICAL, &h));
    }
    ct_ray out;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_ray_from_map(&p, p.origin_e_nm, p.origin_n_nm, 0, INT64_MIN, 1, 1, &out));
    int64_t e, n, z;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_map_to_grid(&p, INT64_MIN, 0, 0, &e, &n, &z));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_grid_to_map(&p, 0, INT64_MIN, 0, &e, &n, &z));
}

// ct_surface_height: the bilinear surface at a Q16 point, rounded up,
// against long double; outside the tile CT_ERR_RANGE, NULL CT_ERR_ARG.
void test_surface_height()
{
    Fixture *f = make_fixture(23, 17, 8);
    TEST_ASSERT(f != nullptr);
    const ct_package &p = f->p;
    ct_rng r;
    ct_rng_seed(&r, ct_test_seed() * 23 + 9);
    for (int k = 0; k < 100000; ++k) {
        int64_t x = ct_rng_range(&r, 0, (int64_t)p.cells_x << 16), y = ct_rng_range(&r, 0, (int64_t)p.cells_y << 16), z;
        if (k < 4) x = k & 1 ? (int64_t)p.cells_x << 16 : 0, y = k & 2 ? (int64_t)p.cells_y << 16 : 0;  // corners
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_surface_height(&p, x, y, &z));
        ld ref = (ld)dem_cases::surf(f->c.t, (double)x / 65536, (double)y / 65536) * 65536;
        if (!((ld)z >= ref - 1e-6L && (ld)z < ref + 1 + 1e-6L))
            TEST_FAIL_MSG("surface at (%lld, %lld): %lld, long double %.4Lf", (long long)x, (long long)y, (long long)z, ref);
    }
    int64_t z;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_surface_height(&p, -1, 0, &z));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_surface_height(&p, 0, ((int64_t)p.cells_y << 16) + 1, &z));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_surface_height(&p, 0, 0, nullptr));
}

void test_grid_map_round_trip()
{
    Fixture *f = make_fixture(19, 23, 3);
    TEST_ASSERT(f != nullptr);
    const ct_package &p = f->p;
    ct_rng r;
    ct_rng_seed(&r, ct_test_seed() * 13 + 5);
    const ld pe = (ld)p.posting_e_nm, pn = (ld)p.posting_n_nm, sc = (ld)p.height_scale_nm;
    for (int i = 0; i < 100000; ++i) {
        int64_t x = ct_rng_range(&r, -(INT64_C(1) << 40), INT64_C(1) << 40);
        int64_t y = ct_rng_range(&r, -(INT64_C(1) << 40), INT64_C(1) << 40);
        int64_t z = ct_rng_range(&r, -(INT64_C(1) << 40), INT64_C(1) << 40);
        int64_t e, nn, h, x2, y2, z2;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, x, y, z, &e, &nn, &h));
        // against long double: posts at pixel centres, e = e0 + (x/2^16 + 1/2) * pe
        ld ee = (ld)p.origin_e_nm + ((ld)x / 65536 + 0.5L) * pe, en = (ld)p.origin_n_nm + ((ld)y / 65536 + 0.5L) * pn;
        ld eh = (ld)p.height_offset_nm + (ld)z / 65536 * sc;
        if (std::fabs((ld)e - ee) > 0.5001L || std::fabs((ld)nn - en) > 0.5001L || std::fabs((ld)h - eh) > 0.5001L)
            TEST_FAIL_MSG("grid->map (%lld,%lld,%lld) off by more than 1/2 nm", (long long)x, (long long)y,
                          (long long)z);
        // one Q16 unit is far more than a nanometre: the round trip is exact
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_map_to_grid(&p, e, nn, h, &x2, &y2, &z2));
        if (x2 != x || y2 != y || z2 != z) TEST_FAIL_MSG("grid->map->grid not exact at sample %d", i);
    }
}

void test_ray_from_map()
{
    Fixture *f = make_fixture(19, 23, 4);
    TEST_ASSERT(f != nullptr);
    const ct_package &p = f->p;
    ct_rng r;
    ct_rng_seed(&r, ct_test_seed() * 17 + 7);
    const ld pe = (ld)p.posting_e_nm, pn = (ld)p.posting_n_nm, sc = (ld)p.height_scale_nm;
    for (int i = 0; i < 100000; ++i) {
        int64_t e = p.origin_e_nm + ct_rng_range(&r, -INT64_C(100000000000000), INT64_C(100000000000000));
        int64_t nn = p.origin_n_nm + ct_rng_range(&r, -INT64_C(100000000000000), INT64_C(100000000000000));
        int64_t h = ct_rng_range(&r, -INT64_C(10000000000000), INT64_C(10000000000000));
        int64_t lim = INT64_C(1) << ct_rng_range(&r, 1, 40);
        int64_t de = ct_rng_range(&r, -lim, lim), dn = ct_rng_range(&r, -lim, lim), dh = ct_rng_range(&r, -lim, lim);
        if (de == 0 && dn == 0 && dh == 0) dh = -1;
        ct_ray ray;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_ray_from_map(&p, e, nn, h, de, dn, dh, &ray));
        int64_t x, y, z;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_map_to_grid(&p, e, nn, h, &x, &y, &z));
        TEST_ASSERT(ray.x_q16 == x && ray.y_q16 == y && ray.z_q16 == z);
        // direction parallel to (de/pe, dn/pn, dh/sc) within 2^-60 relative
        ld g[3] = {(ld)de / pe, (ld)dn / pn, (ld)dh / sc};
        ld d[3] = {(ld)ray.dx, (ld)ray.dy, (ld)ray.dz};
        ld gm = std::max(std::fabs(g[0]), std::max(std::fabs(g[1]), std::fabs(g[2])));
        ld dm = std::max(std::fabs(d[0]), std::max(std::fabs(d[1]), std::fabs(d[2])));
        for (int k = 0; k < 3; ++k) {
            ld rel = std::fabs(g[k] / gm - d[k] / dm);
            if (rel > 0x1p-50L)
                TEST_FAIL_MSG("ray_from_map sample %d axis %d: direction off by %.3Le relative", i, k, rel);
            if ((g[k] == 0) != (d[k] == 0)) TEST_FAIL_MSG("sample %d: zero component not kept", i);
        }
    }
    ct_ray ray;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_ray_from_map(&p, p.origin_e_nm, p.origin_n_nm, 0, 0, 0, 0, &ray));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_ray_from_map(&p, p.origin_e_nm, p.origin_n_nm, 0, INT64_C(1) << 41, 0, 0, &ray));
}

}  // namespace

int main()
{
    TEST_BEGIN("test_prep");
    RUN_TEST(test_clip_entry_and_direction);
    RUN_TEST(test_hit_is_near_callers_ray);
    RUN_TEST(test_within_1mm_on_a_long_tile);
    RUN_TEST(test_fuzz_regressions);
    RUN_TEST(test_surface_height);
    RUN_TEST(test_grid_map_round_trip);
    RUN_TEST(test_ray_from_map);
    return TEST_END();
}
