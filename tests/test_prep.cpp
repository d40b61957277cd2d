// test_prep.cpp -- the ray the tracer is exact for, against the caller's ray.
//
// ct_ray_prepare clips the caller's ray to the tile's box with exact
// rationals, rounds the entry point to Q16 and scales the direction so its
// largest component is in [2^25, 2^26].  The README states the resulting
// bound: every coordinate of the prepared ray stays within
//     1 + 2^-25 * (distance travelled along the dominant axis)   Q16 units
// of the caller's ray (compared at the same dominant-axis coordinate), and a returned hit is within 2 Q16 units of the
// prepared ray's exact first hit.  This test checks both against an
// independent clip (128-bit rationals written separately from lib/) and long
// double geometry, plus the grid <-> map conversions.
#include <cmath>
#include <cstdint>
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

Fixture *make_fixture(int w, int h, uint64_t seed)
{
    static std::vector<Fixture *> keep;
    Fixture *f = new Fixture;
    f->c = dem_cases::make_case("smooth", dem_cases::make_terrain(w, h, dem_cases::smooth(w, h, seed, 200, 3000), 0.25),
                                8, 2);
    if (ct_package_open(&f->p, f->c.pkg.data(), f->c.pkg.size()) != CT_OK) return nullptr;
    keep.push_back(f);
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

// Deviation of the prepared ray at parameter t from the caller's ray, per
// coordinate, measured at the same coordinate along the prepared ray's
// dominant axis m; also returns the distance travelled along m.
void deviation(const ct_ray &ray, const ct_prepared &pr, ld t, ld dev[3], ld *travel)
{
    const ld P[3] = {(ld)pr.ox + t * pr.dx, (ld)pr.oy + t * pr.dy, (ld)pr.oz + t * pr.dz};
    const int32_t D[3] = {pr.dx, pr.dy, pr.dz};
    const ld O[3] = {(ld)ray.x_q16, (ld)ray.y_q16, (ld)ray.z_q16}, U[3] = {(ld)ray.dx, (ld)ray.dy, (ld)ray.dz};
    int m = 0;
    for (int k = 1; k < 3; ++k)
        if (std::abs(D[k]) > std::abs(D[m])) m = k;
    ld u = (P[m] - O[m]) / U[m];  // caller's parameter at the same m-coordinate
    for (int k = 0; k < 3; ++k) dev[k] = std::fabs(P[k] - (O[k] + u * U[k]));
    *travel = std::fabs(t * D[m]);
}

// Entry rounding moves each coordinate by <= 1/2 and the direction's
// rounding moves the dominant-axis coordinate by <= 1/2 more per 2^25 units
// travelled; comparing at the same dominant coordinate can double both.
ld bound_at(ld travel) { return 1.0L + travel * std::ldexp(1.0L, -25) + 1e-6L; }

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
        const int64_t got[3] = {pr.ox, pr.oy, pr.oz};
        if (tin.n != 0) outside_origin++;
        for (int k = 0; k < 3; ++k) {
            // |got - (O + n/d * U)| <= 1/2  <=>  |2 (got - O) d - 2 n U| <= d
            i128 lhs = 2 * ((i128)(got[k] - O[k]) * tin.d - tin.n * (i128)U[k]);
            if (lhs < 0) lhs = -lhs;
            if (lhs > tin.d) TEST_FAIL_MSG("ray %ld axis %d: entry point off by more than half a unit", i, k);
        }
        // direction scale, length, sector
        int64_t m = std::max<int64_t>(std::abs(pr.dx), std::max<int64_t>(std::abs(pr.dy), std::abs(pr.dz)));
        TEST_ASSERT(m >= (INT64_C(1) << 25) && m <= (INT64_C(1) << 26));
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
            ld dev[3], travel;
            deviation(ray, pr, tend * s / 4, dev, &travel);
            for (int k = 0; k < 3; ++k) {
                worst = std::max(worst, dev[k]);
                if (dev[k] > bound_at(travel))
                    TEST_FAIL_MSG("ray %ld axis %d: prepared ray %.6Lf units from the caller's (bound %.6Lf)", i, k,
                                  dev[k], bound_at(travel));
            }
        }
    }
    printf("  %ld rays, %ld entered (%ld from outside the box), worst deviation %.4Lf Q16 units\n", n, entered,
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
        // the hit lies within 2 units of the prepared ray at t_q26, and so
        // within 2 + bound of the caller's ray
        ld t = (ld)h.t_q26 / (ld)(1 << 26);
        ld dev[3], travel;
        deviation(ray, pr, t, dev, &travel);
        const ld P[3] = {(ld)pr.ox + t * pr.dx, (ld)pr.oy + t * pr.dy, (ld)pr.oz + t * pr.dz};
        const ld Hq[3] = {(ld)h.x_q16, (ld)h.y_q16, (ld)h.z_q16};
        for (int k = 0; k < 3; ++k) {
            ld e = std::fabs(Hq[k] - P[k]) + dev[k];
            worst = std::max(worst, e);
            if (e > 2.0L + bound_at(travel) + std::fabs((ld)(k == 0 ? pr.dx : k == 1 ? pr.dy : pr.dz)) * 0x1p-26L)
                TEST_FAIL_MSG("ray %ld axis %d: hit %.4Lf units from the caller's ray (ray %lld %lld %lld / %lld %lld %lld; prep %lld %lld %lld / %d %d %d; hit %lld %lld %lld t %lld)", i, k, e,
                              (long long)ray.x_q16, (long long)ray.y_q16, (long long)ray.z_q16, (long long)ray.dx, (long long)ray.dy, (long long)ray.dz,
                              (long long)pr.ox, (long long)pr.oy, (long long)pr.oz, pr.dx, pr.dy, pr.dz, (long long)h.x_q16, (long long)h.y_q16, (long long)h.z_q16, (long long)h.t_q26);
        }
    }
    printf("  %ld hits, worst distance from the caller's ray %.4Lf Q16 units\n", hits, worst);
    TEST_ASSERT(hits > n / 10);
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
    RUN_TEST(test_grid_map_round_trip);
    RUN_TEST(test_ray_from_map);
    return TEST_END();
}
