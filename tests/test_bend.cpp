// test_bend.cpp -- rays bent by earth curvature and refraction
// (ct_trace_bent) against the long-double reference tracing the exact
// parabola z(t) = oz + t dz + kz t^2 cell by cell.
//
// The library traces a polyline within delta of the curve (chord error plus
// vertex rounding), so its hit is checked by a sandwich: the curve lowered by
// delta must hit no later, the curve raised by delta no earlier (lowering a
// ray can only bring its first hit forward).  Statuses must agree with the
// same sandwich, the four methods must agree bit for bit, and the bending
// must matter (hits differ from the straight ray's).
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "bend.h"
#include "conetrace.h"
#include "dem_cases.hpp"
#include "harness.h"
#include "reference.hpp"

namespace {

typedef long double ld;

struct Scene {
    const char *name;
    double coeff;      // c
    double radius_m;   // R
    double chord_m;    // polyline tolerance
    double tol_m = 0;  // the judge's tolerance for the polyline when tighter than chord_m (0: chord_m)
};

struct Counts {
    long rays = 0, hits = 0, miss = 0, below = 0, differ_from_straight = 0, bad = 0, fewer_steps_culled = 0;
    long hit_void = 0;
    long lowered = 0, polyline = 0;  // rays traced by each model
    bool rise_matters = false;       // the largest rise is 1/10 of the relief or more
    ld worst_lead = 0;
};

// Reference hit parameter (t of the caller's ray) of the curve shifted by dz0
// LSB, +inf for a miss, -1 for BELOW.  The reference starts where the path
// enters the tile (re-expanding the parabola there).
ld ref_t(const ref::Dem &d, ld ox, ld oy, ld oz, ld dx, ld dy, ld dz, ld kz, ld dz0)
{
    const ld W = d.w - 1, H = d.h - 1;
    ld lo = 0, hi = INFINITY;
    if (!ref::clip_box(ox, oy, dx, dy, W, H, &lo, &hi)) return INFINITY;
    ref::Ray r;
    // the entry point, kept on the tile against rounding (so the
    // reference's start-point test applies to it)
    r.ox = std::min(W, std::max<ld>(0, ox + lo * dx));
    r.oy = std::min(H, std::max<ld>(0, oy + lo * dy));
    r.oz = oz + dz0 + lo * dz + kz * lo * lo;
    r.dx = dx;
    r.dy = dy;
    r.dz = dz + 2 * kz * lo;
    r.kz = kz;
    r.tend = hi - lo;
    ref::Hit h = ref::trace(d, r);
    if (h.status == ref::BELOW) return -1;
    if (h.status != ref::HIT) return INFINITY;
    return lo + h.t;
}

// One ray judged: the four methods bit for bit, culling changing nothing,
// the status and hit against the reference curve's sandwich (cs's terrain
// as d, the scene's bend), counted into cnt (ray number n for messages).
// The DEM's largest slope (LSB per cell): the horizontal part of the delta
// (every cell's steepest edges, the last row's and column's too).
ld max_slope(const ref::Dem &d)
{
    ld slope = 0;
    for (int j = 0; j + 1 < d.h; ++j)
        for (int i = 0; i + 1 < d.w; ++i) {
            const ld dx = std::max(std::abs(d.at(i + 1, j) - d.at(i, j)), std::abs(d.at(i + 1, j + 1) - d.at(i, j + 1)));
            const ld dy = std::max(std::abs(d.at(i, j + 1) - d.at(i, j)), std::abs(d.at(i + 1, j + 1) - d.at(i + 1, j)));
            slope = std::max(slope, dx + dy);
        }
    return slope;
}

void judge_ray(const ct_package &p, const ref::Dem &d, ld slope, const dem_cases::Case &cs, const Scene &sc,
               const ct_ray &ray, long n, Counts *cnt)
{
    const ld posting = (ld)std::fabs(cs.t.geo.posting_e), scale = (ld)cs.t.height_scale_m;
    ct_bend bd{};
    bd.coeff_q16 = (int32_t)std::lround(sc.coeff * 65536);
    bd.radius_nm = (int64_t)std::llround(sc.radius_m * 1e9);
    bd.chord_nm = (int64_t)std::llround(sc.chord_m * 1e9);
    const ld c = (ld)bd.coeff_q16 / 65536, R = (ld)bd.radius_nm * 1e-9L;
    // the polyline's tolerance: its chord plus the vertices' and the prepared
    // segments' rounding; the lowered model's (c > 0, ct_lower): the rise's
    // bilinear interpolation between posts, c posting^2 / (4R), plus the
    // prepared ray's rounding
    const ld rounding = (3 + 3 * slope) / 65536.0L + 1e-6L;
    const ld delta_poly = (sc.tol_m > 0 ? sc.tol_m : sc.chord_m) / scale * 1.001L + rounding;
    const ld delta_low = c * posting * posting / (4 * R) / scale * 1.001L + rounding;
    ct_lower lw;
    const bool lowered = ct_lower_setup(&p, ray.x_q16, ray.y_q16, &bd, &lw) == CT_OK;
    const ld delta = lowered ? delta_low : delta_poly;
    (lowered ? cnt->lowered : cnt->polyline)++;
    ct_hit h[4];
    ct_status st[4];
    for (int m = 0; m < 4; ++m) st[m] = ct_trace_bent(&p, &ray, &bd, (ct_method)m, &h[m]);
    cnt->rays++;
    for (int m = 1; m < 4; ++m)
        if (st[m] != st[0] || ((st[0] == CT_HIT || st[0] == CT_HIT_VOID) &&
                               (h[m].x_q16 != h[0].x_q16 || h[m].y_q16 != h[0].y_q16 || h[m].z_q16 != h[0].z_q16)))
            TEST_FAIL_MSG("%s/%s ray %ld: method %d disagrees with incremental", cs.name.c_str(), sc.name, n, m);
    TEST_ASSERT(st[0] >= 0);
    {
        // culling (runs of segments skipped over the max-mipmap) changes
        // no result: the same walk tracing every segment, bit for bit
        ct_bend nc = bd;
        nc.flags = CT_BEND_NO_CULL;
        ct_hit hn;
        ct_status sn = ct_trace_bent(&p, &ray, &nc, CT_METHOD_DIRECTIONAL, &hn);
        if (sn != st[3] || ((sn == CT_HIT || sn == CT_HIT_VOID) &&
                            (hn.x_q16 != h[3].x_q16 || hn.y_q16 != h[3].y_q16 || hn.z_q16 != h[3].z_q16 ||
                             hn.t_q26 != h[3].t_q26 || hn.cell_x != h[3].cell_x || hn.cell_y != h[3].cell_y)))
            TEST_FAIL_MSG("%s/%s ray %ld: culling changed the result (%d vs %d)", cs.name.c_str(), sc.name, n,
                          (int)st[3], (int)sn);
        if (hn.steps > h[3].steps) cnt->fewer_steps_culled++;
    }
    // the reference curve, in the caller's parameter
    ld ox = (ld)ray.x_q16 / 65536, oy = (ld)ray.y_q16 / 65536, oz = (ld)ray.z_q16 / 65536;
    ld dx = (ld)ray.dx / 65536, dy = (ld)ray.dy / 65536, dz = (ld)ray.dz / 65536;
    ld hm = std::sqrt(dx * dx + dy * dy) * posting;  // metres per unit t
    ld kz = c * hm * hm / (2 * R) / scale;
    ld t_dn = ref_t(d, ox, oy, oz, dx, dy, dz, kz, -delta);
    ld t_up = ref_t(d, ox, oy, oz, dx, dy, dz, kz, +delta);
    ld slack = 3.0L / 65536 / std::sqrt(dx * dx + dy * dy);
    bool ok = true;
    if (st[0] == CT_HIT || st[0] == CT_HIT_VOID) {
        cnt->hits++;
        cnt->hit_void += st[0] == CT_HIT_VOID;
        ld hx = (ld)h[0].x_q16 / 65536, hy = (ld)h[0].y_q16 / 65536;
        ld tl = ((hx - ox) * dx + (hy - oy) * dy) / (dx * dx + dy * dy);
        // the lowered curve hits no later (or starts below); the raised
        // one hits no earlier
        ok = (t_dn == -1 || t_dn <= tl + slack) && (t_up == INFINITY || t_up >= tl - slack);
        // the hit lies on the curve within delta (vertically)
        ld zc = oz + tl * dz + kz * tl * tl, zl = (ld)h[0].z_q16 / 65536;
        ld lead = std::fabs(zl - zc);
        cnt->worst_lead = std::max(cnt->worst_lead, lead);
        if (lead > delta + std::fabs(dz) * slack) ok = false;
        ct_hit hs;
        ct_status ss = ct_trace(&p, &ray, CT_METHOD_DIRECTIONAL, &hs);
        if (ss != st[0] || std::llabs(hs.x_q16 - h[0].x_q16) + std::llabs(hs.y_q16 - h[0].y_q16) > 65536)
            cnt->differ_from_straight++;
    } else if (st[0] == CT_MISS) {
        cnt->miss++;
        ok = t_up == INFINITY;  // the raised curve must miss too
    } else if (st[0] == CT_BELOW) {
        cnt->below++;
        ok = t_dn == -1;  // the lowered curve starts below as well
    }
    if (!ok) {
        cnt->bad++;
        if (cnt->bad <= 5)
            printf("  BAD %s/%s ray %ld: status %d (hit %.6Lf %.6Lf %.6Lf), ref t(down) %.6Lg t(up) %.6Lg (ray %lld %lld "
                   "%lld / %lld %lld %lld)\n",
                   cs.name.c_str(), sc.name, n, (int)st[0], (ld)h[0].x_q16 / 65536, (ld)h[0].y_q16 / 65536,
                   (ld)h[0].z_q16 / 65536, t_dn, t_up, (long long)ray.x_q16, (long long)ray.y_q16, (long long)ray.z_q16,
                   (long long)ray.dx, (long long)ray.dy, (long long)ray.dz);
    }
}

void run_scene(const dem_cases::Case &cs, const Scene &sc, long nrays, Counts *cnt)
{
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    const ref::Dem d = dem_cases::ref_dem(cs.t);
    double lo, hi;
    dem_cases::minmax(cs.t, &lo, &hi);
    const ld posting = (ld)std::fabs(cs.t.geo.posting_e), scale = (ld)cs.t.height_scale_m;
    const ld c = (ld)std::lround(sc.coeff * 65536) / 65536, R = (ld)std::llround(sc.radius_m * 1e9) * 1e-9L;
    const double cw = cs.t.width - 1, ch = cs.t.height - 1;
    const ld cw_ = cw, ch_ = ch;
    const ld slope = max_slope(d);
    // the largest rise over the scene's lines of sight (2.5 tile widths), in LSB
    const ld rise = std::fabs(c) * std::pow(2.5L * std::max(cw_, ch_) * posting, 2) / (2 * R) / scale;
    cnt->rise_matters = rise > 0.1L * (hi - lo);
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 31 + (uint64_t)(sc.radius_m / 1000) + (uint64_t)cs.t.width);
    for (long n = 0; n < nrays; ++n) {
        // a target near the terrain, an observer up to 1.5 tile widths back
        // along a line of sight at elevation angle el; a few rising rays
        // from just above the ground
        double tx = ct_rng_unit(&rng) * cw, ty = ct_rng_unit(&rng) * ch;
        double tz = dem_cases::surf(cs.t, tx, ty) + ct_rng_unit(&rng) * 0.5 * (hi - lo);
        double el = (0.1 + 20 * std::pow(ct_rng_unit(&rng), 2)) * M_PI / 180;
        double az = ct_rng_unit(&rng) * 2 * M_PI, D = ct_rng_unit(&rng) * 1.5 * std::max(cw, ch);
        double x = tx - D * std::cos(az), y = ty - D * std::sin(az);
        double zm = tz + D * std::fabs(cs.t.geo.posting_e) * std::tan(el) / cs.t.height_scale_m;
        if (n % 7 == 0) {
            x = tx;
            y = ty;
            zm = dem_cases::surf(cs.t, tx, ty) + 5 / cs.t.height_scale_m;
            el = -0.005 * ct_rng_unit(&rng);
        }
        double dv[3];
        dem_cases::metric_dir(cs.t, az, -el, dv);
        judge_ray(p, d, slope, cs, sc, dem_cases::to_ray(x, y, zm, dv), n, cnt);
    }
}

const Scene kScenes[] = {
    {"earth k=0.13", 0.87, 6371000.0, 0.001},
    {"earth curvature only", 1.0, 6371000.0, 0.005},
    {"exaggerated R=40km", 1.0, 40000.0, 0.001},
    {"exaggerated refraction only", -0.5, 40000.0, 0.002},
};

void test_bent_vs_reference()
{
    std::vector<dem_cases::Case> cases;
    cases.push_back(dem_cases::make_case("jacksboro r3", dem_cases::real_terrain(), 24, 3));
    {
        int w = 97, h = 83;
        cases.push_back(dem_cases::make_case("smooth", dem_cases::make_terrain(w, h, dem_cases::smooth(w, h, 17, 100, 9000), 0.125), 16, 2));
    }
    long per = (long)(2000 * ct_test_scale());
    for (const auto &cs : cases)
        for (const Scene &sc : kScenes) {
            Counts cnt;
            run_scene(cs, sc, per, &cnt);
            printf("  %-13s %-28s %ld rays (%ld lowered, %ld polyline): %ld hit, %ld miss, %ld below; %ld differ "
                   "from the straight ray; worst |z - curve| %.4Lf LSB; bad %ld; culling saved steps on %ld\n",
                   cs.name.c_str(), sc.name, cnt.rays, cnt.lowered, cnt.polyline, cnt.hits, cnt.miss, cnt.below,
                   cnt.differ_from_straight, cnt.worst_lead, cnt.bad, cnt.fewer_steps_culled);
            // culling happens where the rise is large against the relief
            // (lowered: bounds of the lowering ahead; polyline: runs of
            // segments above the mipmap)
            if (cnt.rise_matters || cnt.polyline > 0) TEST_ASSERT(cnt.fewer_steps_culled > cnt.rays / 20);
            // both models are exercised where they apply
            if (sc.coeff > 0) TEST_ASSERT(cnt.lowered > cnt.rays / 2);
            if (sc.coeff < 0) TEST_ASSERT(cnt.polyline == cnt.rays);
            TEST_ASSERT(cnt.bad == 0);
            TEST_ASSERT(cnt.hits > cnt.rays / (sc.radius_m < 1e6 ? 10 : 3));  // strong bending lifts many over the tile
            if (sc.radius_m < 1e6) TEST_ASSERT(cnt.differ_from_straight > cnt.hits / 4);  // the effect is real
        }
}

void test_bent_arguments()
{
    auto cs = dem_cases::make_case("flat", dem_cases::make_terrain(9, 9, std::vector<uint16_t>(81, 100)), 4, 1);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    ct_ray ray = {0, 0, 200 << 16, 1 << 20, 1 << 20, -(250 << 16)};
    ct_bend bd = {57016, INT64_C(6371000000000000), 1000000, 0u};
    ct_hit h;
    TEST_ASSERT(ct_trace_bent(&p, &ray, &bd, CT_METHOD_DIRECTIONAL, &h) == CT_HIT);
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_trace_bent(nullptr, &ray, &bd, CT_METHOD_DIRECTIONAL, &h));
    ct_bend b2 = bd;
    b2.radius_nm = 1000;
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_trace_bent(&p, &ray, &b2, CT_METHOD_DIRECTIONAL, &h));
    b2 = bd;
    b2.chord_nm = 0;
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_trace_bent(&p, &ray, &b2, CT_METHOD_DIRECTIONAL, &h));
    b2 = bd;
    b2.coeff_q16 = 5 << 16;
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_trace_bent(&p, &ray, &b2, CT_METHOD_DIRECTIONAL, &h));
    TEST_ASSERT_EQUAL_INT(CT_ERR_METHOD, ct_trace_bent(&p, &ray, &bd, (ct_method)7, &h));
    // the ray's ranges (checked here first for a bent ray): each alone
    for (int k = 0; k < 6; ++k) {
        ct_ray bad = ray;
        int64_t *f[6] = {&bad.x_q16, &bad.y_q16, &bad.z_q16, &bad.dx, &bad.dy, &bad.dz};
        *f[k] = k < 3 ? CT_MAX_ORIGIN_Q16 + 1 : -(INT64_C(1) << 62) - 1;
        TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_bent(&p, &bad, &bd, CT_METHOD_DIRECTIONAL, &h));
    }
    // c = 0 and vertical rays are the straight trace
    b2 = bd;
    b2.coeff_q16 = 0;
    ct_hit hs;
    TEST_ASSERT_EQUAL_INT(ct_trace(&p, &ray, CT_METHOD_CONE, &hs), ct_trace_bent(&p, &ray, &b2, CT_METHOD_CONE, &h));
    TEST_ASSERT(h.x_q16 == hs.x_q16 && h.z_q16 == hs.z_q16);
    ct_ray v = {3 << 16, 3 << 16, 500 << 16, 0, 0, -1};
    TEST_ASSERT_EQUAL_INT(ct_trace(&p, &v, CT_METHOD_CONE, &hs), ct_trace_bent(&p, &v, &bd, CT_METHOD_CONE, &h));
    TEST_ASSERT(h.z_q16 == hs.z_q16);
}

// The polyline (c < 0) where the curve does not matter or cannot be traced:
// a ray whose horizontal part vanishes once reduced (the straight trace, bit
// for bit), horizontal paths that never cross the tile -- along an axis
// beside it, or past a corner -- (CT_MISS, as straight), a start far under
// the tile's floor (CT_BELOW, as straight), an observer beyond 2^52 nm, a
// tile straddling 2^52 nm from the observer, and a path needing more than
// CT_BEND_MAX_SEGMENTS segments (CT_ERR_RANGE, as documented).
void test_bent_polyline_edges()
{
    auto cs = dem_cases::make_case("hills", dem_cases::make_terrain(40, 36, dem_cases::smooth(40, 36, 4, 1000, 9000)), 8, 2);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    const ct_bend up = {-2 * 65536, INT64_C(6371000000000000), 1000000, 0u};  // k = 3: bends upwards
    const int64_t W = (int64_t)p.cells_x << 16, H = (int64_t)p.cells_y << 16, top = ((int64_t)p.hmax + 5) << 16;
    struct Ray {
        const char *name;
        ct_ray ray;
        ct_status want;  // also the straight trace's
    };
    const Ray rays[] = {
        {"nearly vertical", {W / 2, H / 3, top, 1, 0, -(INT64_C(1) << 62)}, CT_HIT},
        {"along x, beside the tile (y < 0)", {-W, -(5 << 16), top, 1 << 20, 0, -(1 << 10)}, CT_MISS},
        {"along x, beside the tile (y > top)", {-W, H + (5 << 16), top, 1 << 20, 0, -(1 << 10)}, CT_MISS},
        {"along y, beside the tile (x < 0)", {-(5 << 16), -H, top, 0, 1 << 20, -(1 << 10)}, CT_MISS},
        {"along y, beside the tile (x > top)", {W + (5 << 16), -H, top, 0, 1 << 20, -(1 << 10)}, CT_MISS},
        {"past the corner", {-(5 << 16), H + (5 << 16), top, 1 << 20, 1 << 20, -(1 << 10)}, CT_MISS},
        {"far under the floor", {-(100 << 16), H / 2, -(INT64_C(1) << 46) + (1 << 20), 1 << 16, 0, -(1 << 20)}, CT_BELOW},
    };
    for (const Ray &r : rays) {
        ct_hit hb, hs;
        const ct_status sb = ct_trace_bent(&p, &r.ray, &up, CT_METHOD_DIRECTIONAL, &hb);
        const ct_status ss = ct_trace(&p, &r.ray, CT_METHOD_DIRECTIONAL, &hs);
        TEST_ASSERT_MSG(sb == r.want && ss == r.want, "%s: bent %d, straight %d, expected %d", r.name, sb, ss, r.want);
        if (sb == CT_HIT) TEST_ASSERT(hb.x_q16 == hs.x_q16 && hb.y_q16 == hs.y_q16 && hb.z_q16 == hs.z_q16);
    }
    // an observer 4,600 km west of the tile (beyond RHO_MAX, 2^52 nm), one
    // 2^45.5 Q16 cells west (its range times the posting passes 2^80) and
    // one 3e13 Q16 cells west (range times posting in [2^79, 2^80): the
    // range in nm passes 2^63): CT_ERR_RANGE, "the observer beyond 2^52 nm
    // of the tile"
    for (int64_t x0 : {-(INT64_C(153333) << 16), -(INT64_C(46000000000000)), -(INT64_C(30000000000000))}) {
        const ct_ray far = {x0, H / 2, top, 1 << 20, 0, 0};
        ct_hit hf;
        TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_trace_bent(&p, &far, &up, CT_METHOD_DIRECTIONAL, &hf));
    }
    // a tile straddling 2^52 nm from the observer (150,000 .. 150,400
    // cells of 30 m west of it), the path 1 km over its flat ground there
    // (refraction k = 0.13 drops it 207 km on the way): the polyline's
    // vertices past 2^52 nm cannot be formed -- CT_ERR_RANGE (the observer
    // must be within 2^52 nm of every point of the tile), culled or not
    {
        auto strip = dem_cases::make_case("strip", dem_cases::make_terrain(401, 3, std::vector<uint16_t>(1203, 100)), 1, 1);
        ct_package q;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&q, strip.pkg.data(), strip.pkg.size()));
        const ct_bend refr = {-8520, INT64_C(6371000000000000), 1000000, 0u};
        const int64_t x0 = -(INT64_C(150000) << 16);
        const long double drop = 0.13L * std::pow(150200 * 30.0L, 2) / (2 * 6371000.0L);  // m, to the straddle
        const ct_ray ray = {x0, 1 << 16, (int64_t)std::llround((100 + 1000 + drop) * 65536), 1 << 20, 0, 0};
        for (uint32_t flags : {0u, (uint32_t)CT_BEND_NO_CULL}) {
            ct_bend b = refr;
            b.flags = flags;
            for (int m = 0; m < 4; ++m) {
                ct_hit hr;
                TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_trace_bent(&q, &ray, &b, (ct_method)m, &hr));
            }
        }
    }
    // 2000 x 3 posts of 30 m and a chord that makes the segment just over
    // 1/64 cell: about 120,000 segments across the tile
    auto wide = dem_cases::make_case("wide", dem_cases::make_terrain(2000, 3, std::vector<uint16_t>(6000, 100)), 1, 1);
    ct_package q;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&q, wide.pkg.data(), wide.pkg.size()));
    const ct_bend fine = {-4 * 65536, INT64_C(1) << 40, 120000, 0u};
    const ct_ray across = {0, 1 << 16, 200 << 16, 1 << 20, 0, 0};
    ct_hit h;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_trace_bent(&q, &across, &fine, CT_METHOD_DIRECTIONAL, &h));
}

// Regression: the segment length Delta = sqrt(8 chord R / |c|) was formed
// through a 64-bit quotient saturated at 2^62 nm^2, so for a real earth
// (8 chord R ~ 5e22 nm^2 at 1 mm) Delta came out ~2 m instead of ~240 m:
// exact still, but ~100x more segments (and time) per ray.
void test_bent_segment_length_regression()
{
    auto cs = dem_cases::make_case("flat", dem_cases::make_terrain(9, 9, std::vector<uint16_t>(81, 100)), 4, 1);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    struct {
        int32_t c;
        int64_t r_nm, chord_nm;
    } cases[] = {{57016, INT64_C(6371000000000000), 1000000},   {65536, INT64_C(6371000000000000), 5000000},
                 {-8520, INT64_C(6371000000000000), 1000000},   {65536, INT64_C(1) << 54, INT64_C(1) << 50},
                 {1, INT64_C(6371000000000000), 1000000},       {4 * 65536, INT64_C(1) << 40, 1 << 20}};
    for (const auto &k : cases) {
        ct_bend bd = {k.c, k.r_nm, k.chord_nm, 0u};
        int64_t delta = 0;
        ct_status st = ct_bend_segment(&p, &bd, &delta);
        long double want = std::sqrt(8.0L * k.chord_nm * k.r_nm * 65536 / std::fabs((long double)k.c)) * 65536 /
                           (long double)std::llabs(p.posting_e_nm);
        if (want < 1024) {
            TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, st);
            continue;
        }
        TEST_ASSERT_EQUAL_INT(CT_OK, st);
        // segments of at most 2^50 nm
        want = std::min(want, std::ldexp(1.0L, 50) * 65536 / (long double)std::llabs(p.posting_e_nm));
        want = std::min(want, std::ldexp(1.0L, 62));
        // floor of the exact value (the polyline never deviates more than chord)
        TEST_ASSERT_MSG(delta <= want && delta >= want - 2 - want * 1e-15L,
                        "c %d R %lld chord %lld: Delta %lld Q16 cells, want %.3Lf", (int)k.c, (long long)k.r_nm,
                        (long long)k.chord_nm, (long long)delta, want);
    }
}

// A bend whose tolerance allows segments longer than 2^50 nm (a tiny |c|
// with a large chord and radius: c = -1/65536, R = 2^54 nm, chord 2^50 nm
// would give 2^53.5 nm) is traced with segments of 2^50 nm, not refused:
// the polyline's last vertex, a segment past the box, stayed beyond the
// vertices' range (CT_ERR_RANGE for every ray, an observer beside the tile
// included).  Judged against the reference curve within the capped
// segment's sagitta |c| Delta^2 / 8R (2^27 nm, 0.13 m).
void test_bent_capped_segment()
{
    std::vector<dem_cases::Case> cases;
    {
        int w = 97, h = 83;
        cases.push_back(
            dem_cases::make_case("smooth", dem_cases::make_terrain(w, h, dem_cases::smooth(w, h, 17, 100, 9000), 0.125), 16, 2));
    }
    Scene sc{"tiny c, 2^50 nm chord", -1.0 / 65536, std::ldexp(1.0, 54) * 1e-9, std::ldexp(1.0, 50) * 1e-9,
             std::ldexp(1.0, 27) * 1e-9};
    Counts cnt;
    run_scene(cases[0], sc, (long)(400 * ct_test_scale()), &cnt);
    printf("  %s: %ld rays (%ld polyline): %ld hit, %ld miss, %ld below; bad %ld\n", sc.name, cnt.rays, cnt.polyline,
           cnt.hits, cnt.miss, cnt.below, cnt.bad);
    TEST_ASSERT(cnt.bad == 0 && cnt.polyline == cnt.rays && cnt.hits > cnt.rays / 3);
}

// ct_trace_bent refuses a chord whose polyline segment would be under 1/64
// cell (CT_ERR_ARG) whichever model then traces the ray; the lowered model's
// set-up checks it without the segment's square root.  Around the threshold
// (for R = 2^40 nm, c = 4, 30 m cells: chord ~ 1e5 nm) both must agree.
void test_bent_chord_check_agrees()
{
    auto cs = dem_cases::make_case("flat", dem_cases::make_terrain(9, 9, std::vector<uint16_t>(81, 100)), 4, 1);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    ct_ray ray = {0, 0, 200 << 16, 1 << 20, 1 << 20, -(250 << 16)};
    long refused = 0, accepted = 0;
    const int32_t cs_[] = {4 * 65536, 3 * 65536 + 12345, 65536, -65536};
    for (int32_t c : cs_) {
        // the threshold chord for this c, then +-3000 nm around it
        long double post = (long double)std::llabs(p.posting_e_nm);
        long double t = std::pow(std::ceil(post / 64), 2) * std::fabs((long double)c) / (std::ldexp(1.0L, 40 + 19));
        for (int64_t chord = (int64_t)t - 3000; chord <= (int64_t)t + 3000; chord += 13) {
            ct_bend bd = {c, INT64_C(1) << 40, chord, 0u};
            int64_t delta;
            ct_hit h;
            ct_status want = ct_bend_segment(&p, &bd, &delta) == CT_OK ? CT_OK : CT_ERR_ARG;
            ct_status got = ct_trace_bent(&p, &ray, &bd, CT_METHOD_DIRECTIONAL, &h);
            if (want == CT_ERR_ARG) {
                TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, got);
                refused++;
            } else {
                TEST_ASSERT(got >= 0);
                accepted++;
            }
        }
    }
    TEST_ASSERT(refused > 100 && accepted > 100);
}

// The same checks (four methods, culling, the reference's sandwich) on the
// packages the scenes above do not make: a DEM with a patch of voids (the
// polyline's and the lowered walk's hits on void cells: CT_HIT_VOID where
// the reference hits the same place), a package of one cell (no mipmap
// levels) and one of 4 x 4 cells, both of 1 km cells (runs of segments
// wider than the mipmap's blocks); a polyline 1 km over one 100 km cell
// (more than 2^11 segments culled in a row); a polyline from an observer
// 35,000 cells (35 km) from a tile of 1 m posts (ranges past 2^31 Q16).
void test_bent_edge_packages()
{
    std::vector<dem_cases::Case> cases;
    {
        ct_host::Terrain t = dem_cases::make_terrain(60, 50, dem_cases::smooth(60, 50, 23, 100, 9000), 0.125);
        t.void_post.assign(60 * 50, 0);
        for (int j = 15; j < 35; ++j)
            for (int i = 20; i < 45; ++i) t.void_post[(size_t)j * 60 + i] = 1;
        cases.push_back(dem_cases::make_case("voids", t, 16, 2));
    }
    for (int n : {2, 5}) {
        ct_host::Terrain t = dem_cases::make_terrain(n, n, dem_cases::smooth(n, n, 5, 100, 3000), 0.125);
        t.geo.posting_e = 1000.0;
        t.geo.posting_n = -1000.0;
        cases.push_back(dem_cases::make_case(n == 2 ? "one 1 km cell" : "4 x 4 cells of 1 km", t, 8, 1));
    }
    const long per = std::max(50L, (long)(400 * ct_test_scale()));
    for (const auto &cs : cases)
        for (const Scene &sc : kScenes) {
            Counts cnt;
            run_scene(cs, sc, per, &cnt);
            printf("  %-20s %-28s %ld rays (%ld lowered, %ld polyline): %ld hit (%ld void), %ld miss, %ld below; bad %ld\n",
                   cs.name.c_str(), sc.name, cnt.rays, cnt.lowered, cnt.polyline, cnt.hits, cnt.hit_void, cnt.miss,
                   cnt.below, cnt.bad);
            TEST_ASSERT(cnt.bad == 0);
            TEST_ASSERT(cnt.hits > 0);
            if (cs.name == "voids") TEST_ASSERT(cnt.hit_void > 0);
        }
    // observers 40,000 cells (1,200 km) west of a 30 x 30 tile on a sphere
    // of 2^40 nm bent with c = -4 and c = 4 (beyond the lowered walk's
    // 2^15 cells: the polyline): over the tile the path lies over 2^46 Q16
    // below the terrain (CT_BELOW, before the polyline entered) or above it
    // (vertices out of range, skipped: CT_MISS), as the reference's
    {
        const dem_cases::Case cs =
            dem_cases::make_case("30 x 30", dem_cases::make_terrain(31, 31, dem_cases::smooth(31, 31, 3, 100, 3000), 0.25),
                                 8, 1);
        ct_package p;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
        const ref::Dem d = dem_cases::ref_dem(cs.t);
        for (double c : {-4.0, 4.0}) {
            const Scene sc = {c < 0 ? "c = -4, R = 2^40 nm" : "c = 4, R = 2^40 nm", c, (double)(INT64_C(1) << 40) * 1e-9,
                              0.001};
            Counts cnt;
            for (int k = 0; k < 6; ++k) {
                const ct_ray ray = {-(INT64_C(40000) << 16), (int64_t)(5 + 4 * k) << 16, (int64_t)2000 << 16, 1 << 16,
                                    k * 7, -(k << 8)};
                judge_ray(p, d, max_slope(d), cs, sc, ray, k, &cnt);
            }
            printf("  %-20s %-28s %ld rays (%ld polyline): %ld hit, %ld miss, %ld below; bad %ld\n", cs.name.c_str(),
                   sc.name, cnt.rays, cnt.polyline, cnt.hits, cnt.miss, cnt.below, cnt.bad);
            TEST_ASSERT(cnt.bad == 0 && cnt.polyline == cnt.rays);
            TEST_ASSERT(c < 0 ? cnt.below > 0 : cnt.miss > 0);
        }
        // nearly vertical lines of sight upwards (2^28 up per cell across),
        // bent down by k = 1.5 on a 40 km sphere: from beside the tile and
        // from just over its surface, the vertices over the tile lie beyond
        // 2^46 Q16 above it (skipped, before and after the polyline
        // entered): a miss, as the reference's
        const Scene up = {"steeply up, k 1.5 R 40 km", -0.5, 40000.0, 0.002};
        Counts cnt;
        for (int k = 0; k < 4; ++k) {
            const int64_t x0 = k % 2 == 0 ? -(5 << 16) : (int64_t)(10 + k) << 16, y0 = (int64_t)(8 + 3 * k) << 16;
            int64_t z0 = (int64_t)4000 << 16;
            if (k % 2 == 1) {
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_surface_height(&p, x0, y0, &z0));
                z0 += 5 << 16;
            }
            const ct_ray ray = {x0, y0, z0, 1 << 16, k << 10, INT64_C(1) << 44};
            judge_ray(p, d, max_slope(d), cs, up, ray, k, &cnt);
        }
        printf("  %-20s %-28s %ld rays (%ld polyline): %ld hit, %ld miss, %ld below; bad %ld\n", cs.name.c_str(), up.name,
               cnt.rays, cnt.polyline, cnt.hits, cnt.miss, cnt.below, cnt.bad);
        TEST_ASSERT(cnt.bad == 0 && cnt.miss == cnt.rays);
    }
    // 1 nm posts with 2^30 nm (1.07 m) height codes on a sphere of 2^54 nm:
    // the lowering's constant K = c posting^2 / (2^33 R scale) is below
    // 2^-127 (ct_lower_setup refuses it), so the polyline traces the rays
    {
        ct_host::Terrain t = dem_cases::make_terrain(30, 30, dem_cases::smooth(30, 30, 11, 100, 3000), 1.073741824);
        t.geo.posting_e = 1e-9;
        t.geo.posting_n = -1e-9;
        const dem_cases::Case cs = dem_cases::make_case("1 nm posts", t, 8, 1);
        ct_package p;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
        TEST_ASSERT(p.posting_e_nm == 1 && p.height_scale_nm == (INT64_C(1) << 30));
        const Scene sc = {"sphere of 2^54 nm", 1.0, (double)(INT64_C(1) << 54) * 1e-9, 0.001};
        Counts cnt;
        run_scene(cs, sc, 200, &cnt);
        printf("  %-20s %-28s %ld rays (%ld lowered, %ld polyline): %ld hit, %ld miss, %ld below; bad %ld\n",
               cs.name.c_str(), sc.name, cnt.rays, cnt.lowered, cnt.polyline, cnt.hits, cnt.miss, cnt.below, cnt.bad);
        TEST_ASSERT(cnt.bad == 0 && cnt.polyline == cnt.rays && cnt.hits > 0);
    }
    // 69 x 2 flat cells of 30 m with a 2.5 km spike at the far corner;
    // polylines 1 km over them along x (inside the terrain's box), bent up
    // (k = 1.5 on a sphere of 2^40 nm) in segments of 0.59 m (just over
    // 1/64 cell): 3,500 segments over the tile, thousands culled in a row
    {
        std::vector<uint16_t> z(210, 400);
        z[2 * 70 + 69] = 20400;
        const dem_cases::Case cs = dem_cases::make_case("69 x 2 cells, a spike", dem_cases::make_terrain(70, 3, z, 0.125), 4, 1);
        ct_package p;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
        const ref::Dem d = dem_cases::ref_dem(cs.t);
        const Scene sc = {"k 1.5, R 2^40 nm", -0.5, (double)(INT64_C(1) << 40) * 1e-9, 2e-5};
        Counts cnt;
        for (int k = 0; k < 10; ++k) {
            const ct_ray ray = {-(1 << 12), (1 << 16) + k * 3000, (400 + 8000) << 16, 1 << 16, k * 100,
                                -(int64_t)k << 14};
            judge_ray(p, d, max_slope(d), cs, sc, ray, k, &cnt);
        }
        printf("  %-20s %-28s %ld rays: %ld hit, %ld miss, %ld below; bad %ld; culling saved steps on %ld\n",
               cs.name.c_str(), sc.name, cnt.rays, cnt.hits, cnt.miss, cnt.below, cnt.bad, cnt.fewer_steps_culled);
        TEST_ASSERT(cnt.bad == 0 && cnt.fewer_steps_culled == cnt.rays);
    }
    // 40 x 40 posts of 1 m; observers 35 km west, aimed (through the
    // polyline's curve, refraction k = 0.13 on the Earth) at points just
    // over the terrain
    {
        ct_host::Terrain t = dem_cases::make_terrain(40, 40, dem_cases::smooth(40, 40, 9, 100, 4000), 0.125);
        t.geo.posting_e = 1.0;
        t.geo.posting_n = -1.0;
        const dem_cases::Case cs = dem_cases::make_case("1 m posts", t, 8, 1);
        ct_package p;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
        const ref::Dem d = dem_cases::ref_dem(cs.t);
        const Scene sc = {"refraction only, Earth", -0.13, 6371000.0, 0.001};
        const ld c = (ld)std::lround(sc.coeff * 65536) / 65536, R = (ld)std::llround(sc.radius_m * 1e9) * 1e-9L;
        const ld D = 35000;  // cells (m) back along x
        Counts cnt;
        ct_rng rng;
        ct_rng_seed(&rng, 35);
        for (int k = 0; k < 20; ++k) {
            const ld tx = 5 + 30 * ct_rng_unit(&rng), ty = 5 + 30 * ct_rng_unit(&rng);
            const ld tz = dem_cases::surf(cs.t, (double)tx, (double)ty) + 2 + 40 * ct_rng_unit(&rng);  // LSB
            const ld el = 0.002L + 0.01L * ct_rng_unit(&rng);  // rad down
            const ld dz = -std::tan(el) * 1.0L / 0.125L;       // LSB per cell
            const ld kz = c * 1.0L / (2 * R) / 0.125L;         // the curve's t^2 term, LSB per cell^2
            const ld oz = tz - D * dz - kz * D * D;
            const ct_ray ray = {(int64_t)std::llround((tx - D) * 65536), (int64_t)std::llround(ty * 65536),
                                (int64_t)std::llround(oz * 65536), 1 << 16, 0, (int64_t)std::llround(dz * 65536)};
            judge_ray(p, d, max_slope(d), cs, sc, ray, k, &cnt);
        }
        printf("  %-20s %-28s %ld rays: %ld hit, %ld miss, %ld below; bad %ld\n", cs.name.c_str(), sc.name, cnt.rays,
               cnt.hits, cnt.miss, cnt.below, cnt.bad);
        TEST_ASSERT(cnt.bad == 0 && cnt.hits > 0);
    }
}

// Vertices beyond +-2^62 Q16: 30 m posts with 1 nm height codes (the
// terrain 3 um tall) on a sphere of 2^40 nm bent with c = -4 and c = 4, and
// a chord of 2^46 nm: the drop at the first vertex after the observer is
// 4 chord / scale = 2^48 LSB (2^64 Q16), so it is kept at +-2^62 (vertex's
// saturation) and the first segment, from an observer over the terrain,
// descends (c = -4) by more than 2^62 -- ct_ray_prepare_segment's limit.
// The polyline must still be traced (the documented statuses, never an
// error for a ray and a bend in their ranges), and judged by the
// reference's sandwich (its tolerance, chord / scale, is 2^46 LSB) --
// observers over the tile and beside it, above the terrain and (c = 4)
// under its floor.
void test_bent_saturated_vertices()
{
    const dem_cases::Case cs =
        dem_cases::make_case("1 nm codes", dem_cases::make_terrain(31, 31, dem_cases::smooth(31, 31, 7, 100, 3000), 1e-9), 8, 1);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    TEST_ASSERT(p.height_scale_nm == 1);
    const ref::Dem d = dem_cases::ref_dem(cs.t);
    const ld slope = max_slope(d);
    const ld chord_nm = std::ldexp(1.0L, 46), R_nm = std::ldexp(1.0L, 40);
    for (double c : {-4.0, 4.0}) {
        const Scene sc = {c < 0 ? "c = -4, 2^62 Q16 drops" : "c = 4, 2^62 Q16 rises", c, (double)(R_nm * 1e-9L),
                          (double)(chord_nm * 1e-9L)};
        // the first vertex's bend is beyond 2^62 Q16 (saturated)
        {
            const ct_bend bd = {(int32_t)std::lround(c * 65536), INT64_C(1) << 40, INT64_C(1) << 46, 0u};
            int64_t delta = 0;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_bend_segment(&p, &bd, &delta));
            const ld rho = (ld)delta * (ld)p.posting_e_nm / 65536;  // nm
            TEST_ASSERT(std::fabs(c) * rho * rho / (2 * R_nm) * 65536 > std::ldexp(1.0L, 62));
        }
        Counts cnt;
        long n = 0;
        for (int k = 0; k < 8; ++k) {
            // over the tile (k even) or 1/8 cell beside its west edge (odd),
            // 50 LSB over the terrain there, aimed along az, level or down
            const double az = 0.3 + 0.7 * k, y = 4.0 + 3.0 * k;
            const double x = k % 2 == 0 ? 3.0 + 2.5 * k : -0.125;
            const double zs = dem_cases::surf(cs.t, std::max(0.0, x), y);
            double dv[3];
            dem_cases::metric_dir(cs.t, k % 2 == 0 ? az : 0.2 * (k - 4), -1e-7 * k, dv);
            judge_ray(p, d, slope, cs, sc, dem_cases::to_ray(x, y, zs + 50, dv), n++, &cnt);
            if (c > 0) {
                // from under the tile's floor, beside it, rising: the curve
                // enters the tile below the surface or above the box
                const ct_ray under = {-(1 << 13), (int64_t)(4 + 3 * k) << 16, -(INT64_C(200) << 16), 1 << 20, k << 16,
                                      (int64_t)k << 10};
                judge_ray(p, d, slope, cs, sc, under, n++, &cnt);
            }
        }
        printf("  %-20s %-28s %ld rays (%ld polyline): %ld hit, %ld miss, %ld below; bad %ld\n", cs.name.c_str(),
               sc.name, cnt.rays, cnt.polyline, cnt.hits, cnt.miss, cnt.below, cnt.bad);
        TEST_ASSERT(cnt.bad == 0 && cnt.polyline == cnt.rays);
        // c = -4: from over the tile the curve falls onto the terrain at
        // once (25 mm in 1/8 cell); from beside it, it enters the tile
        // that far under the 3 um terrain: BELOW
        if (c < 0) TEST_ASSERT(cnt.hits == 4 && cnt.below == 4);
    }
}

// Polyline segments starting just under the surface after the polyline
// entered the tile: 30 m posts, 1 mm height codes (prepared z units up to
// 2^14 Q16), refraction c = -4 on a sphere of 2^40 nm with a chord of
// 0.1 mm (segments of 0.06 cells).  A segment's prepared ray starts at its
// vertex rounded to its z unit, so where a vertex lies below the surface by
// less than that rounding, the previous segment may end above it: the
// next segment starts under the surface, and that is the polyline's hit
// (the surface crossed within the vertex rounding), not CT_BELOW.  Rays
// found by a search (steep in Q16: 600 LSB per cell), judged as every
// other: the four methods, culling, the reference's sandwich.
void test_bent_start_below_after_entered()
{
    const dem_cases::Case cs = dem_cases::make_case("1 mm codes", dem_cases::below_after_entered_terrain(), 8, 1);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    TEST_ASSERT(p.zshift_max >= 12);
    const ref::Dem d = dem_cases::ref_dem(cs.t);
    const Scene sc = {"c = -4, R 2^40 nm, 0.1 mm", -4.0, (double)(INT64_C(1) << 40) * 1e-9, 1e-4};
    Counts cnt;
    long n = 0;
    for (const ct_ray &ray : dem_cases::kBelowAfterEnteredRays) judge_ray(p, d, max_slope(d), cs, sc, ray, n++, &cnt);
    printf("  %-20s %-28s %ld rays: %ld hit, %ld miss, %ld below; bad %ld\n", cs.name.c_str(), sc.name, cnt.rays,
           cnt.hits, cnt.miss, cnt.below, cnt.bad);
    TEST_ASSERT(cnt.bad == 0 && cnt.polyline == cnt.rays && cnt.hits == cnt.rays);
}

}  // namespace

// An exact tangency of a ray with the lowered surface (issue 19: the
// lowered cell test's B^2 = 4AC to the last bit, and the root of the
// coefficients root_low scales down).  One cell, posts 0 0 0 H (H at (1,
// 1)), and horizontal rays along the anti-diagonal x + y = 1 from points
// (a, 1 - a), a <= 31000 / 2^16 (H from 3 to 65535: coefficients that are
// not powers of two): along it (x = 1/2 + s, y = 1/2 - s) the surface is
// H (1/4 - s^2),
// so the ray at z = H/4 touches it at the cell's centre and nowhere else
// (f = H s^2, exact rational arithmetic).  The lowered walk (ct_lower_setup_k
// with kf 2^-64 per squared Q16 cell: D = 0 at every post, the lowered posts
// are the terrain's) must report that point (every method); the ray one Q16
// unit higher misses (f >= 2^-16 > 0); one unit lower it crosses twice and
// hits at the first root s = -sqrt(2^-16 / H) (within 2 Q16 units).
void test_lowered_tangency()
{
    for (int H : {4, 64, 1024, 40000, 3, 777, 65535}) {
      for (int64_t ox : {8192, 1, 5001, 12345, 30001, 31000}) {
        ct_host::Terrain t = dem_cases::make_terrain(2, 2, {0, 0, 0, (uint16_t)H}, 0.01);
        const dem_cases::Case cs = dem_cases::make_case("tangent", t, 8, 1);
        ct_package p;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
        const int64_t oy = 65536 - ox, z = (int64_t)H * 16384;  // H/4 in Q16
        ct_lower lw;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_lower_setup_k(&p, ox, oy, 1u, 64u, 0, &lw));
        for (int m = 0; m < CT_METHOD_COUNT; ++m) {
            for (int dz = -1; dz <= 1; ++dz) {
                const ct_ray ray = {ox, oy, z + dz, 1 << 20, -(1 << 20), 0};
                ct_hit h;
                const ct_status st = ct_trace_lowered(&p, &ray, &lw, (ct_method)m, &h);
                if (dz > 0) {
                    TEST_ASSERT_MSG(st == CT_MISS, "H %d method %d: 1 unit above the tangent: status %d", H, m, st);
                    continue;
                }
                TEST_ASSERT_MSG(st == CT_HIT, "H %d ox %lld method %d dz %d: status %d", H, (long long)ox, m, dz, st);
                const ld s = dz == 0 ? 0 : -std::sqrt(1.0L / 65536 / H);
                const ld xe = (0.5L + s) * 65536, ye = (0.5L - s) * 65536;
                TEST_ASSERT_MSG(std::fabs(h.x_q16 - xe) <= 2 && std::fabs(h.y_q16 - ye) <= 2 && h.cell_x == 0 &&
                                    h.cell_y == 0,
                                "H %d method %d dz %d: hit (%lld, %lld), exact (%.2Lf, %.2Lf)", H, m, dz,
                                (long long)h.x_q16, (long long)h.y_q16, xe, ye);
            }
        }
      }
    }
}

// ct_trace_run (the runs of ct_geolocate_batch) against each ray's own
// trace, on rays aimed at spikes' tops.  Smooth terrain with single-post
// spikes 50-150 m tall; an observer inside the tile or up to 50 cells
// outside, high above the terrain or level with the spike's top (within
// 30 m: a nearly level ray, whose height changes little across a cell or
// a block, so the bounds' margin is small); runs of 8 rays aimed at the
// spike's top (the lowered top with curvature) raised by a common offset
// within +-1 m, 10 cm, 1 cm or 1 mm plus each ray's own jitter of a tenth
// of that, and as far sideways as the spike's flank falls by about that
// much.  The runs' shared walk must stop short of the spike exactly when a
// ray of the run would meet it: a bound too loose by 8 mm fails this test.
// Straight rays and the lowered model (spheres of 2^50 and 2^48 nm, the
// lowering 5.7x and 23x the Earth's), the four methods: every status and
// hit equal to the ray's own trace but for steps and iters, and the runs
// engage (a run's rays take fewer steps in total than their own walks in
// most runs).
void test_runs_vs_own_trace()
{
    const int w = 300, h = 260;
    std::vector<uint16_t> z = dem_cases::smooth(w, h, 31, 100, 2000);
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 7 + 3);
    std::vector<std::pair<int, int>> spikes;
    for (int k = 0; k < 120; ++k) {
        const int i = (int)ct_rng_range(&rng, 2, w - 3), j = (int)ct_rng_range(&rng, 2, h - 3);
        z[(size_t)j * w + i] = (uint16_t)(z[(size_t)j * w + i] + ct_rng_range(&rng, 400, 1200));
        spikes.push_back({i, j});
    }
    const dem_cases::Case cs = dem_cases::make_case("spikes", dem_cases::make_terrain(w, h, z, 0.125), 16, 3);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    long runs = 0, rays = 0, engaged = 0, hits = 0, differ = 0, lowered_runs = 0;
    const long trials = (long)(400 * ct_test_scale());
    for (long tr = 0; tr < trials; ++tr) {
        const int64_t ox = ct_rng_range(&rng, -50, w + 50) * 65536 + ct_rng_range(&rng, 0, 65535);
        const int64_t oy = ct_rng_range(&rng, -50, h + 50) * 65536 + ct_rng_range(&rng, 0, 65535);
        const auto sp = spikes[(size_t)ct_rng_range(&rng, 0, (int64_t)spikes.size() - 1)];
        const int64_t tx = (int64_t)sp.first * 65536, ty = (int64_t)sp.second * 65536;
        const int64_t top = (int64_t)z[(size_t)sp.second * w + sp.first] * 65536;
        const int64_t oz = tr % 2 ? (int64_t)(p.hmax + ct_rng_range(&rng, 50, 4000)) * 65536
                                  : top + ct_rng_range(&rng, 0, 240) * 65536;
        static const int64_t scales[4] = {8 * 65536, 52429, 5243, 524};  // 1 m, 10 cm, 1 cm, 1 mm in Q16 LSB (1/8 m)
        const int64_t sc = scales[(tr / 2) % 4];
        const int64_t base = ct_rng_range(&rng, -sc, sc);
        for (int fx = 0; fx < 3; ++fx) {
            ct_lower lw;
            const ct_lower *plw = nullptr;
            int64_t drop = 0;
            if (fx > 0) {
                ct_bend bd;
                bd.coeff_q16 = 65536;
                bd.radius_nm = INT64_C(1) << (fx == 1 ? 50 : 48);
                bd.chord_nm = CT_EFFECTS_CHORD_NM;
                bd.flags = 0u;
                if (ct_lower_setup(&p, ox, oy, &bd, &lw) != CT_OK) continue;
                plw = &lw;
                drop = ct_lower_at(&lw, tx, ty);
                lowered_runs++;
            }
            ct_prepared r[CT_RUN_MAX];
            uint32_t n = 0;
            // every 7th trial in turn: a vertical ray in the run (its own
            // walk); three rays at spikes far apart (too wide, no halves);
            // level rays above every post (free to the tile's end); a fan
            // 3.5 cells wide across the tile's edge (rays that leave the
            // tile sideways before the shared stretch ends); rays with dx
            // exactly 0
            const int kind = (int)(tr % 7);
            const uint32_t nr = kind == 2 ? 3u : CT_RUN_MAX;
            for (uint32_t k = 0; k < nr; ++k) {
                int64_t ex = tx + ct_rng_range(&rng, -sc / 64, sc / 64), ey = ty + ct_rng_range(&rng, -sc / 64, sc / 64);
                int64_t ez = top - drop + base + ct_rng_range(&rng, -sc / 10, sc / 10), rz = oz;
                if (kind == 1 && k == 0) {
                    ex = ox;
                    ey = oy;
                } else if (kind == 2) {
                    const auto q = spikes[(size_t)ct_rng_range(&rng, 0, (int64_t)spikes.size() - 1)];
                    ex = (int64_t)q.first * 65536;
                    ey = (int64_t)q.second * 65536;
                } else if (kind == 3) {
                    rz = (int64_t)(p.hmax + 40) * 65536;
                    ez = rz - ct_rng_range(&rng, 0, 65536);
                    ex = ox + (tx - ox) * 4;
                    ey = oy + (ty - oy) * 4;
                } else if (kind == 5) {
                    // a fan half a cell apart across the tile's edge on the
                    // side axis (the low edge and the high one in turn)
                    const bool along_x = std::llabs(tx - ox) >= std::llabs(ty - oy);
                    const int64_t edge = (tr / 7) % 2 ? (int64_t)(along_x ? h - 1 : w - 1) * 65536 : 0;
                    const int64_t side = edge + (int64_t)k * 32768 - 7 * 16384;
                    if (along_x) ey = side; else ex = side;
                } else if (kind == 6) {
                    ex = ox;  // dx = 0 exactly: the run's axis is y
                }
                if (kind == 4 && tr % 14 == 4) {
                    // from 1.5 cells inside the low y edge, +x, rays parting
                    // by 0.7 cells each over 240 cells down to 80 m under
                    // the ground there: those bound for y < 0 leave the tile
                    // sideways before the others near the ground
                    rz = (int64_t)(p.hmax + 160) * 65536;
                    const int64_t bx = std::llabs(ox) % (30 * 65536) + 20 * 65536, by = 98304;
                    ex = bx + 240 * 65536;
                    ey = by + ((int64_t)k * 2 - 7) * 22938;
                    ez = (int64_t)z[(size_t)w + (size_t)(ex >> 16)] * 65536 - 80 * 65536;
                    const ct_ray ray = {bx, by, rz, ex - bx, ey - by, ez - rz};
                    if (ct_prepare_lowered(&p, &ray, 0, plw, &r[n]) == CT_OK) n++;
                    continue;
                }
                const ct_ray ray = {ox, oy, rz, ex - ox, ey - oy, ez - rz};
                if (ct_prepare_lowered(&p, &ray, 0, plw, &r[n]) == CT_OK) n++;
            }
            if (n == 0) continue;
            for (int m = 0; m < CT_METHOD_COUNT; ++m) {
                ct_hit own[CT_RUN_MAX], run[CT_RUN_MAX];
                ct_hit *hp[CT_RUN_MAX];
                ct_status so[CT_RUN_MAX], sr[CT_RUN_MAX];
                long steps_own = 0, steps_run = 0;
                for (uint32_t k = 0; k < n; ++k) {
                    so[k] = ct_trace_prepared_lowered(&p, &r[k], plw, (ct_method)m, &own[k]);
                    hp[k] = &run[k];
                    steps_own += own[k].steps;
                }
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_trace_run(&p, r, n, plw, (ct_method)m, hp, sr));
                for (uint32_t k = 0; k < n; ++k) {
                    ct_hit a = own[k], b = run[k];
                    a.steps = b.steps = a.iters = b.iters = 0;
                    const bool same = so[k] == sr[k] && std::memcmp(&a, &b, sizeof a) == 0;
                    differ += !same;
                    TEST_ASSERT_MSG(same, "trial %ld effects %d method %d ray %u: run status %d (%lld, %lld), own %d "
                                    "(%lld, %lld)", tr, fx, m, k, sr[k], (long long)run[k].x_q16,
                                    (long long)run[k].y_q16, so[k], (long long)own[k].x_q16, (long long)own[k].y_q16);
                    hits += so[k] == CT_HIT;
                    steps_run += run[k].steps;
                }
                runs++;
                rays += n;
                engaged += steps_run < steps_own;
            }
        }
    }
    printf("  %ld runs (%ld lowered), %ld rays, %ld hits; the run shortened the walks in %ld runs\n", runs,
           lowered_runs, rays, hits, engaged);
    TEST_ASSERT_EQUAL_INT(0, differ);
    TEST_ASSERT(lowered_runs > trials);
    TEST_ASSERT_MSG(2 * engaged > runs, "runs engaged in only %ld of %ld", engaged, runs);
}

int main()
{
    TEST_BEGIN("test_bend");
    RUN_TEST(test_bent_arguments);
    RUN_TEST(test_bent_polyline_edges);
    RUN_TEST(test_bent_segment_length_regression);
    RUN_TEST(test_bent_capped_segment);
    RUN_TEST(test_bent_chord_check_agrees);
    RUN_TEST(test_bent_vs_reference);
    RUN_TEST(test_bent_edge_packages);
    RUN_TEST(test_lowered_tangency);
    RUN_TEST(test_runs_vs_own_trace);
    RUN_TEST(test_bent_saturated_vertices);
    RUN_TEST(test_bent_start_below_after_entered);
    return TEST_END();
}
