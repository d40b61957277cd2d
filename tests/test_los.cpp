// test_los.cpp -- ct_los (intervisibility) against the independent reference
// tracer (tests/kit/reference.hpp, long double, no code shared with lib/).
//
// On the adversarial DEMs (spikes, knife walls, pits, flat, terraces, the
// 16-bit extremes): seeded pairs of an observer A (the surface plus 0..40 %
// of the relief, sometimes below the lowest post's height) and a target B
// (on the surface, or a little above it), straight and with curvature and
// refraction on a small sphere (R = 2^44 nm, so the bend matters on these
// small tiles).  The reference decides "hidden" when its first hit of the
// segment A -> B (bent: z(t) = zA + t dz + kz t^2, kz = c rho_B^2 / 2R)
// lies more than the margin (0.5 m) before B.  Ties -- the line of sight
// passing within 1 cm of the surface before the margin, or the first hit
// within 1 cm of it --
// are counted and reported, not judged: the library traces its prepared
// (quantised) ray, within 1 mm of the caller's.  Zero disagreements
// elsewhere; the blocking point of a hidden pair lies on the reference's
// line of sight (within 2 cm; its distance along it from the reference's
// first hit is reported).  Plus the argument checks.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
#include "harness.h"
#include "reference.hpp"

namespace {

using ref::ld;

struct Tally {
    long pairs = 0, visible = 0, hidden = 0, ties = 0, below = 0, bad = 0;
    double worst_block = 0, along = 0;
};

void run_case(const dem_cases::Case &cs, bool bent, Tally *ty)
{
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    const ref::Dem d = dem_cases::ref_dem(cs.t);
    const ld pe = std::fabs(p.posting_e_nm * 1e-9L), pn = std::fabs(p.posting_n_nm * 1e-9L),
             hs = p.height_scale_nm * 1e-9L;
    const ld R = std::ldexp(1.0L, 44) * 1e-9L;               // m
    const ld c = 1 - (ld)CT_REFRACTION_K_STD_Q16 / 65536;  // curvature and refraction
    const ct_effects fx = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, INT64_C(1) << 44, 0,
                           nullptr};
    const int64_t margin = 500000000;  // 0.5 m: a target's own extent
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 7919 + cs.name.size() * 31 + (bent ? 1 : 0));
    const int lo = *std::min_element(d.z.begin(), d.z.end()), hi = *std::max_element(d.z.begin(), d.z.end());
    const int npairs = std::max(100, (int)std::lround(1500 * ct_test_scale()));
    for (int k = 0; k < npairs; ++k) {
        // A and B as grid points (Q16), then the map points the library is
        // given; the grid points it works with are ct_map_to_grid's
        auto pick = [&](bool observer, int64_t g[3]) {
            const ld x = ct_rng_unit(&rng) * (d.w - 1), y = ct_rng_unit(&rng) * (d.h - 1);
            ld z = ref::surface(d, x, y);
            if (observer) z += ct_rng_unit(&rng) * 0.4 * (hi - lo) + 1;
            else if (ct_rng_range(&rng, 0, 2) == 0) z += ct_rng_unit(&rng) * 0.05 * (hi - lo);
            if (observer && ct_rng_range(&rng, 0, 19) == 0) z = lo - 5;  // below every post
            g[0] = std::llround(x * 65536);
            g[1] = std::llround(y * 65536);
            g[2] = std::llround(z * 65536);
        };
        int64_t ga[3], gb[3], a[3], b[3];
        pick(true, ga);
        pick(false, gb);
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, ga[0], ga[1], ga[2], &a[0], &a[1], &a[2]));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, gb[0], gb[1], gb[2], &b[0], &b[1], &b[2]));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_map_to_grid(&p, a[0], a[1], a[2], &ga[0], &ga[1], &ga[2]));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_map_to_grid(&p, b[0], b[1], b[2], &gb[0], &gb[1], &gb[2]));
        if (ga[0] == gb[0] && ga[1] == gb[1]) continue;
        ct_hit blk;
        const ct_status st = ct_los(&p, a, b, bent ? &fx : nullptr, margin, CT_METHOD_DIRECTIONAL, &blk);
        ty->pairs++;
        // the reference: the segment in the grid frame, bent by kz
        ref::Ray r;
        r.ox = ga[0] / 65536.0L;
        r.oy = ga[1] / 65536.0L;
        r.oz = ga[2] / 65536.0L;
        const ld dx = (gb[0] - ga[0]) / 65536.0L, dy = (gb[1] - ga[1]) / 65536.0L;
        const ld rho = std::hypot(dx * pe, dy * pn);
        r.kz = bent ? c * rho * rho / (2 * R) / hs : 0;
        r.dx = dx;
        r.dy = dy;
        r.dz = (gb[2] - ga[2]) / 65536.0L - r.kz;
        r.tend = 1;
        const ld len = std::sqrt(rho * rho + std::pow((gb[2] - ga[2]) / 65536.0L * hs, 2));  // m
        const ld surfA = ref::surface(d, std::min<ld>(std::max<ld>(r.ox, 0), d.w - 1),
                                      std::min<ld>(std::max<ld>(r.oy, 0), d.h - 1));
        if (r.oz < surfA) {
            // A under the surface
            TEST_ASSERT_MSG(st == CT_BELOW || st == CT_HIT, "%s: A under the surface, status %d", cs.name.c_str(), st);
            ty->below++;
            continue;
        }
        ref::Hit h = ref::trace(d, r);
        const ld tcut = 1 - (ld)margin * 1e-9L / len;
        const ld tie_t = 0.01L / len;  // 1 cm along the segment
        const ld clear = ref::min_clearance(d, r, 0, std::max<ld>(0, tcut)) * hs;  // m
        bool ref_hidden = h.status == ref::HIT && h.t < tcut;
        bool tie = std::fabs(clear) < 0.01L || (h.status == ref::HIT && std::fabs(h.t - tcut) < tie_t);
        if (tie) {
            ty->ties++;
            continue;
        }
        if (st != CT_OK && st != CT_HIT) {
            ty->bad++;
            std::printf("  %s%s: pair %d: status %d\n", cs.name.c_str(), bent ? " (bent)" : "", k, st);
            continue;
        }
        if ((st == CT_HIT) != ref_hidden) {
            ty->bad++;
            if (ty->bad <= 5)
                std::printf("  %s%s: pair %d: library %s, reference %s (t %.6Lf, cut %.6Lf, clearance %.4Lf m)\n",
                            cs.name.c_str(), bent ? " (bent)" : "", k, st == CT_HIT ? "hidden" : "visible",
                            ref_hidden ? "hidden" : "visible", h.t, tcut, clear);
            continue;
        }
        if (st == CT_HIT) {
            ty->hidden++;
            // the blocking point lies on the reference's line of sight (its
            // height at that point's range along it); where the line of sight crosses the surface at a grazing angle
            // a millimetre moves that point metres along it, so the distance
            // to the reference's first hit is reported, not judged
            int64_t x, y, z;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_map_to_grid(&p, blk.e_nm, blk.n_nm, blk.h_nm, &x, &y, &z));
            const ld bx = x / 65536.0L, by = y / 65536.0L, bz = z / 65536.0L;
            const ld tb = ((bx - r.ox) * r.dx * pe * pe + (by - r.oy) * r.dy * pn * pn) /
                          (r.dx * r.dx * pe * pe + r.dy * r.dy * pn * pn);
            const ld off_path = std::hypot((r.ox + tb * r.dx - bx) * pe, (r.oy + tb * r.dy - by) * pn);
            const ld off_height = std::fabs(r.oz + tb * r.dz + r.kz * tb * tb - bz) * hs;
            TEST_ASSERT_MSG(off_path <= 0.02L && off_height <= 0.02L,
                            "%s%s: pair %d: blocking point %.4Lf m beside, %.4Lf m above/below the line of sight",
                            cs.name.c_str(), bent ? " (bent)" : "", k, off_path, off_height);
            ty->worst_block = std::max(ty->worst_block, (double)std::max(off_path, off_height));
            ty->along = std::max(ty->along, (double)(std::fabs(tb - h.t) * len));
        } else {
            ty->visible++;
        }
    }
}

void test_los_vs_reference()
{
    std::vector<dem_cases::Case> cases = dem_cases::adversarial_cases();
    for (int bent = 0; bent < 2; ++bent) {
        Tally all;
        for (const dem_cases::Case &cs : cases) {
            Tally t;
            run_case(cs, bent != 0, &t);
            std::printf("  %-18s %s: %ld pairs: %ld visible, %ld hidden, %ld A below, %ld ties, %ld disagree; "
                        "blocking point on the reference's line of sight within %.3g m, %.3g m along it "
                        "from the reference's first hit\n",
                        cs.name.c_str(), bent ? "bent (c 0.87, R 17.6 km)" : "straight", t.pairs, t.visible, t.hidden,
                        t.below, t.ties, t.bad, t.worst_block, t.along);
            all.pairs += t.pairs;
            all.ties += t.ties;
            all.bad += t.bad;
            all.hidden += t.hidden;
            all.visible += t.visible;
            all.worst_block = std::max(all.worst_block, t.worst_block);
        }
        TEST_ASSERT_MSG(all.bad == 0, "%ld disagreements with the reference", all.bad);
        TEST_ASSERT_MSG(all.ties * 4 <= all.pairs, "%ld ties of %ld pairs", all.ties, all.pairs);
        TEST_ASSERT(all.hidden > all.pairs / 10 && all.visible > all.pairs / 10);
        TEST_ASSERT(all.worst_block <= 0.02);
    }
}

void test_los_arguments()
{
    std::vector<dem_cases::Case> cases = dem_cases::adversarial_cases();
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cases[0].pkg.data(), cases[0].pkg.size()));
    int64_t a[3], b[3];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, 5 << 16, 5 << 16, INT64_C(70000) << 16, &a[0], &a[1], &a[2]));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, 20 << 16, 30 << 16, INT64_C(900) << 16, &b[0], &b[1], &b[2]));
    ct_hit h;
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_los(nullptr, a, b, nullptr, 0, CT_METHOD_DIRECTIONAL, &h));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_los(&p, a, b, nullptr, -1, CT_METHOD_DIRECTIONAL, &h));
    TEST_ASSERT_EQUAL_INT(CT_ERR_METHOD, ct_los(&p, a, b, nullptr, 0, (ct_method)7, &h));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_los(&p, a, a, nullptr, 0, CT_METHOD_DIRECTIONAL, &h));
    const int64_t far[3] = {INT64_C(1) << 62, 0, 0};
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_los(&p, far, b, nullptr, 0, CT_METHOD_DIRECTIONAL, &h));
    ct_effects neg = {CT_EFFECT_REFRACTION, 2 * 65536, 0, 0, nullptr};  // c = -2
    TEST_ASSERT_EQUAL_INT(CT_ERR_EFFECTS, ct_los(&p, a, b, &neg, 0, CT_METHOD_DIRECTIONAL, &h));
    // every method decides alike
    ct_status s0 = ct_los(&p, a, b, nullptr, 0, CT_METHOD_INCREMENTAL, &h);
    for (int m = 1; m < CT_METHOD_COUNT; ++m) TEST_ASSERT_EQUAL_INT(s0, ct_los(&p, a, b, nullptr, 0, (ct_method)m, &h));
}

// ct_locate_inverse (the pixel where a map point appears, and whether it
// is visible) as the inverse of ct_geolocate: from a map pose and from a
// geodetic pose (map metres per ground metre undone), with no effects and
// with an effects record of no flags (the same answer), a point below the
// surface (hidden), the camera centre itself (CT_ERR_RAY), a point behind
// the camera (CT_ERR_UNPROJECT), a point 3,000 km away straight ahead in
// azimuth (its direction scaled down first: the centre column), and a
// camera under the surface (CT_BELOW, as ct_los).
void test_locate_inverse_cases()
{
    ct_host::Terrain t = dem_cases::make_terrain(64, 64, dem_cases::smooth(64, 64, 5, 1000, 4000), 0.25);
    t.geo.epsg = 32617;
    const dem_cases::Case cs = dem_cases::make_case("inverse", t, 8, 2);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    const ct_lens lens = dem_cases::centred_pinhole(640, 480, 500);
    ct_camera cam;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init(&cam, &lens));
    int64_t e, n, h;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, 32 << 16, 40 << 16, (int64_t)p.hmax << 16, &e, &n, &h));
    int32_t q[4];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(0, dem_cases::deg_q61(-60), 0, q));
    ct_pose poses[2];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&poses[0], e, n, h + 1000000000000, q));
    {
        const ct_utm zone = {17, 0};
        int64_t lat, lon;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_inverse(&zone, e, n, &lat, &lon));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_wgs84(&poses[1], &zone, lat, lon, h + 1000000000000, q));
        TEST_ASSERT(poses[1].hscale_q30 != (1 << 30));
    }
    const ct_effects none = {0u, 0, 0, 0, nullptr};
    for (int pk = 0; pk < 2; ++pk) {
        const ct_pose &pose = poses[pk];
        int hits = 0;
        for (int64_t u : {100, 320, 555})
            for (int64_t v : {60, 240, 420}) {
                ct_geo g;
                if (ct_geolocate(&p, &cam, &pose, CT_METHOD_DIRECTIONAL, nullptr, u << 16, v << 16, &g) != CT_HIT) continue;
                hits++;
                const int64_t gp[3] = {g.hit.e_nm, g.hit.n_nm, g.hit.h_nm};
                for (const ct_effects *fx : {(const ct_effects *)nullptr, &none}) {
                    int64_t uu, vv;
                    uint32_t vis = 7;
                    ct_hit b;
                    TEST_ASSERT_EQUAL_INT(CT_OK, ct_locate_inverse(&p, &cam, &pose, fx, gp, 500000000, &uu, &vv, &vis, &b));
                    TEST_ASSERT_MSG(vis == 1u, "pose %d pixel (%lld, %lld): the hit not visible", pk, (long long)u,
                                    (long long)v);
                    // the hit is within 2 mm of the pixel's ray: 1 km away,
                    // a few thousandths of a pixel
                    TEST_ASSERT_MSG(std::llabs(uu - (u << 16)) < 656 && std::llabs(vv - (v << 16)) < 656,
                                    "pose %d pixel (%lld, %lld): back at (%.4f, %.4f)", pk, (long long)u, (long long)v,
                                    uu / 65536.0, vv / 65536.0);
                }
                // 50 m below the surface there: hidden (the surface is met first)
                const int64_t under[3] = {gp[0], gp[1], gp[2] - 50000000000};
                int64_t uu, vv;
                uint32_t vis = 7;
                ct_hit b;
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_locate_inverse(&p, &cam, &pose, nullptr, under, 500000000, &uu, &vv, &vis, &b));
                TEST_ASSERT_EQUAL_INT(0, (int)vis);
            }
        TEST_ASSERT(hits >= 5);
        int64_t uu, vv;
        uint32_t vis;
        ct_hit b;
        const int64_t centre[3] = {pose.e_nm, pose.n_nm, pose.h_nm};
        TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_locate_inverse(&p, &cam, &pose, nullptr, centre, 0, &uu, &vv, &vis, &b));
        const int64_t behind[3] = {pose.e_nm, pose.n_nm - 1000000000000, pose.h_nm};
        TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, ct_locate_inverse(&p, &cam, &pose, nullptr, behind, 0, &uu, &vv, &vis, &b));
        const int64_t ahead[3] = {pose.e_nm, pose.n_nm + INT64_C(3000000000000000), pose.h_nm};
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_locate_inverse(&p, &cam, &pose, nullptr, ahead, 0, &uu, &vv, &vis, &b));
        TEST_ASSERT_MSG(std::llabs(uu - (INT64_C(639) << 15)) < 65536, "ahead: u %.3f", uu / 65536.0);
        TEST_ASSERT(vv < 0);  // above the image's top: 60 deg up from its axis
    }
    // a camera under the surface: ct_los's CT_BELOW, and not visible
    {
        ct_pose under;
        int64_t zs, uu, vv, gx, gy, gz;
        uint32_t vis = 7;
        ct_hit b;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_surface_height(&p, 32 << 16, 40 << 16, &zs));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, 32 << 16, 40 << 16, zs - (200 << 16), &gx, &gy, &gz));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&under, gx, gy, gz, q));
        const int64_t ahead[3] = {gx, gy + 300000000000, gz - 200000000000};
        TEST_ASSERT_EQUAL_INT(CT_BELOW, ct_locate_inverse(&p, &cam, &under, nullptr, ahead, 0, &uu, &vv, &vis, &b));
        TEST_ASSERT_EQUAL_INT(0, (int)vis);
    }
}

// ct_los's rarer paths: a vertical line of sight (A straight above B on the
// surface: visible; B under the surface: hidden; straight, on the true
// Earth and on the sphere's lowered walk), A = B under the true
// Earth (CT_ERR_RAY, as straight), B off the zone's projection (CT_ERR_RAY),
// and the true Earth asked of a package on no UTM zone: the sphere of
// CT_EARTH_RADIUS_NM, the same answer and block as asking for it.
void test_los_cases()
{
    ct_host::Terrain t = dem_cases::make_terrain(48, 40, dem_cases::smooth(48, 40, 9, 1000, 30000), 0.25);
    t.geo.epsg = 32617;
    const dem_cases::Case utm = dem_cases::make_case("utm", t, 8, 2);
    t.geo.epsg = 0;
    const dem_cases::Case plain = dem_cases::make_case("no crs", t, 8, 2);
    ct_package p, q;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, utm.pkg.data(), utm.pkg.size()));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&q, plain.pkg.data(), plain.pkg.size()));
    int64_t zs, g[3], a[3];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_surface_height(&p, (20 << 16) + 999, (17 << 16) + 4321, &zs));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, (20 << 16) + 999, (17 << 16) + 4321, zs, &g[0], &g[1], &g[2]));
    a[0] = g[0], a[1] = g[1], a[2] = g[2] + 800000000000;  // 800 m above
    const ct_effects earth = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
    const ct_effects ball = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM, 0,
                             nullptr};
    ct_hit h;
    for (const ct_effects *fx : {(const ct_effects *)nullptr, &earth, &ball}) {
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_los(&p, a, g, fx, 1000000, CT_METHOD_DIRECTIONAL, &h));
        const int64_t under[3] = {g[0], g[1], g[2] - 5000000000};
        TEST_ASSERT_EQUAL_INT(CT_HIT, ct_los(&p, a, under, fx, 1000000, CT_METHOD_DIRECTIONAL, &h));
        TEST_ASSERT(std::llabs(h.h_nm - g[2]) < 2000000);  // blocked at the surface, within 2 mm
        TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_los(&p, a, a, fx, 0, CT_METHOD_DIRECTIONAL, &h));
    }
    const int64_t off_zone[3] = {a[0] + INT64_C(2000000000000000), a[1], a[2]};
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_los(&p, a, off_zone, &earth, 0, CT_METHOD_DIRECTIONAL, &h));
    // no CRS: the true Earth is the sphere of 6371 km
    const ct_effects sphere = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM,
                               0, nullptr};
    ct_rng rng;
    ct_rng_seed(&rng, 77);
    int hidden = 0;
    for (int k = 0; k < 200; ++k) {
        int64_t b[3], zb;
        const int64_t xb = ct_rng_range(&rng, 0, 47 << 16), yb = ct_rng_range(&rng, 0, 39 << 16);
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_surface_height(&q, xb, yb, &zb));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&q, xb, yb, zb, &b[0], &b[1], &b[2]));
        ct_hit h1, h2;
        const ct_status s1 = ct_los(&q, a, b, &earth, 500000000, CT_METHOD_DIRECTIONAL, &h1);
        const ct_status s2 = ct_los(&q, a, b, &sphere, 500000000, CT_METHOD_DIRECTIONAL, &h2);
        TEST_ASSERT_EQUAL_INT(s2, s1);
        if (s1 == CT_HIT) {
            hidden++;
            TEST_ASSERT(h1.x_q16 == h2.x_q16 && h1.y_q16 == h2.y_q16 && h1.z_q16 == h2.z_q16 && h1.e_nm == h2.e_nm);
        }
        if (ct_harness_g.current_failed) return;
    }
    TEST_ASSERT(hidden > 0);
    // ct_locate_inverse likewise: on the package with no CRS the true Earth
    // is the sphere (the same pixel and visibility as asking for it); on
    // the UTM package a camera far off the zone (its frame cannot be
    // formed) and one beyond the grid's range give ct_los's own statuses
    // for the same line of sight
    const ct_lens lens = dem_cases::centred_pinhole(640, 480, 500);
    ct_camera cam;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init(&cam, &lens));
    int32_t qd[4];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(0, dem_cases::deg_q61(-60), 0, qd));
    ct_pose pose;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&pose, a[0] - 300000000000, a[1] - 300000000000, a[2], qd));
    {
        int64_t u1, v1, u2, v2;
        uint32_t vis1 = 7, vis2 = 7;
        ct_hit b1, b2;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_locate_inverse(&q, &cam, &pose, &earth, g, 500000000, &u1, &v1, &vis1, &b1));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_locate_inverse(&q, &cam, &pose, &sphere, g, 500000000, &u2, &v2, &vis2, &b2));
        TEST_ASSERT(u1 == u2 && v1 == v2 && vis1 == vis2);
    }
    for (int far = 0; far < 2; ++far) {
        // 3,000 km east: off the zone's projection; 2^61 nm north: beyond
        // the grid's range
        ct_pose fp;
        const int64_t fe = far ? a[0] : a[0] + INT64_C(3000000000000000), fn = far ? (INT64_C(1) << 61) : a[1];
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&fp, fe, fn, a[2], qd));
        const int64_t fa[3] = {fe, fn, a[2]};
        int64_t uu, vv;
        uint32_t vis = 7;
        ct_hit b1, b2;
        const ct_status sl = ct_los(&p, fa, g, &earth, 500000000, CT_METHOD_DIRECTIONAL, &b1);
        const ct_status si = ct_locate_inverse(&p, &cam, &fp, &earth, g, 500000000, &uu, &vv, &vis, &b2);
        TEST_ASSERT_MSG(sl < 0 && si == sl, "camera %s: ct_los %d, ct_locate_inverse %d", far ? "beyond the grid" : "off the zone",
                        (int)sl, (int)si);
        TEST_ASSERT_EQUAL_INT(0, (int)vis);
    }
}

// A DEM with a patch of voids: ct_los decides as its definition says -- the
// segment A -> B (as ct_map_to_grid rounds them) prepared and traced, hidden
// when the first hit, void or not, lies more than the margin before B, the
// block that hit bit for bit -- straight and on the true Earth (blocked by a
// void cell there as well).
void test_los_voids()
{
    ct_host::Terrain t = dem_cases::make_terrain(40, 40, dem_cases::smooth(40, 40, 13, 1000, 20000), 0.25);
    t.geo.epsg = 32617;
    t.void_post.assign(1600, 0);
    for (int j = 12; j < 28; ++j)
        for (int i = 14; i < 26; ++i) t.void_post[(size_t)j * 40 + i] = 1;
    const dem_cases::Case cs = dem_cases::make_case("voids", t, 8, 2);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    ct_rng rng;
    ct_rng_seed(&rng, 4242);
    const int64_t margin = 500000000;
    long void_blocks = 0, checked = 0;
    for (int k = 0; k < 400; ++k) {
        int64_t a[3], b[3], za, zb;
        const int64_t xa = ct_rng_range(&rng, 0, 39 << 16), ya = ct_rng_range(&rng, 0, 39 << 16);
        const int64_t xb = ct_rng_range(&rng, 15 << 16, 25 << 16), yb = ct_rng_range(&rng, 13 << 16, 27 << 16);
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_surface_height(&p, xa, ya, &za));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_surface_height(&p, xb, yb, &zb));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, xa, ya, za + ct_rng_range(&rng, 1 << 16, 4000 << 16), &a[0], &a[1], &a[2]));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, xb, yb, zb - (2000 << 16), &b[0], &b[1], &b[2]));  // 500 m under
        // the definition: the segment in the grid, prepared and traced
        int64_t g[6];
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_map_to_grid(&p, a[0], a[1], a[2], &g[0], &g[1], &g[2]));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_map_to_grid(&p, b[0], b[1], b[2], &g[3], &g[4], &g[5]));
        const ct_ray seg = {g[0], g[1], g[2], g[3] - g[0], g[4] - g[1], g[5] - g[2]};
        ct_prepared pr;
        ct_hit ht, hl;
        ct_status st = ct_ray_prepare_segment(&p, &seg, &pr);
        if (st == CT_OK || st == CT_HIT) st = ct_trace_prepared(&p, &pr, CT_METHOD_DIRECTIONAL, &ht);
        const ct_status sl = ct_los(&p, a, b, nullptr, margin, CT_METHOD_DIRECTIONAL, &hl);
        TEST_ASSERT(st == CT_HIT || st == CT_HIT_VOID || st == CT_BELOW);  // B is under the surface
        if (st == CT_BELOW) {
            TEST_ASSERT_EQUAL_INT(CT_BELOW, sl);
            continue;
        }
        checked++;
        void_blocks += st == CT_HIT_VOID;
        TEST_ASSERT_EQUAL_INT(CT_HIT, sl);  // met 500 m or more before B
        TEST_ASSERT(hl.x_q16 == ht.x_q16 && hl.y_q16 == ht.y_q16 && hl.z_q16 == ht.z_q16 && hl.e_nm == ht.e_nm);
        // the true Earth: hidden as well (B is 500 m under the surface)
        const ct_effects earth = {CT_EFFECT_CURVATURE, 0, 0, 0, nullptr};
        TEST_ASSERT_EQUAL_INT(CT_HIT, ct_los(&p, a, b, &earth, margin, CT_METHOD_DIRECTIONAL, &hl));
        if (ct_harness_g.current_failed) return;
    }
    std::printf("  voids: %ld pairs blocked, %ld of them in a void cell\n", checked, void_blocks);
    TEST_ASSERT(void_blocks > 0 && checked > void_blocks);
}

// Segments that end just after entering the tile's box: shallow lines of
// sight from far outside, ending a fraction of a Q16 unit under the box's
// top (hmax + 1 LSB) over low ground, and ending a fraction of a unit past
// the box's west face: the part inside is shorter than the entry point's
// rounding, and nothing can be met there -- ct_ray_prepare_segment enters
// (CT_OK) and the trace misses, or hits beyond the segment's end in its
// last cell (as documented); every method alike.
void test_los_short_entry()
{
    std::vector<uint16_t> z(40 * 40, 1000);
    z[40 * 40 - 1] = 20000;  // the box's top far above the rest (the far corner's post)
    const dem_cases::Case cs = dem_cases::make_case("low", dem_cases::make_terrain(40, 40, z, 0.25), 8, 2);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    const int64_t top = ((int64_t)p.hmax + 1) << 16;
    ct_rng rng;
    ct_rng_seed(&rng, 907);
    long entered = 0, beyond = 0;
    for (int k = 0; k < 4000; ++k) {
        ct_ray seg;
        if (k % 3 == 2) {
            // steep (z dominant past the package's zshift, 2^6 here) and
            // ending on the west face, or up to 3 units inside it: the
            // entry's z rounded to 64 units may pass the end
            const int64_t xe = ct_rng_range(&rng, 0, 3), ye = ct_rng_range(&rng, 10 << 16, 30 << 16);
            const int64_t ze = ct_rng_range(&rng, (int64_t)1200 << 16, (int64_t)15000 << 16);
            const int64_t dx = ct_rng_range(&rng, 1, 1 << 8), dy = ct_rng_range(&rng, -(1 << 8), 1 << 8);
            const int64_t dz = -dx * ct_rng_range(&rng, 1 << 10, 1 << 14);
            seg = {xe - dx, ye - dy, ze - dz, dx, dy, dz};
        } else if (k % 2 == 0) {
            // through the top: 1 unit down per 1000 along x, ending 0..3 units under the top
            const int64_t xe = ct_rng_range(&rng, 10 << 16, 30 << 16), ye = ct_rng_range(&rng, 10 << 16, 30 << 16);
            const int64_t ze = top - ct_rng_range(&rng, 0, 3);
            const int64_t dx = ct_rng_range(&rng, 1000 << 16, 2000 << 16), dy = ct_rng_range(&rng, -(5 << 16), 5 << 16);
            const int64_t dz = -(dx / 1000) - ct_rng_range(&rng, 0, 7);
            seg = {xe - dx, ye - dy, ze - dz, dx, dy, dz};
        } else {
            // through the west face: ending 0..3 units east of x = 0, 100-1000 times faster in y
            const int64_t xe = ct_rng_range(&rng, 0, 3), ye = ct_rng_range(&rng, 10 << 16, 30 << 16);
            const int64_t dx = ct_rng_range(&rng, 1 << 10, 1 << 16), dy = dx * ct_rng_range(&rng, 100, 1000);
            seg = {xe - dx, ye - dy, (int64_t)1500 << 16, dx, dy, -ct_rng_range(&rng, 0, 1 << 16)};
        }
        ct_prepared pr;
        const ct_status sp = ct_ray_prepare_segment(&p, &seg, &pr);
        TEST_ASSERT_MSG(sp == CT_OK || sp == CT_MISS, "segment %d: prepare %d", k, sp);
        if (sp != CT_OK) continue;
        entered++;
        for (int m = 0; m < 4; ++m) {
            // a miss, or a hit beyond the segment's end in its last cell
            // (which ct_ray_prepare_segment documents; the callers discard it)
            ct_hit h;
            const ct_status st = ct_trace_prepared(&p, &pr, (ct_method)m, &h);
            TEST_ASSERT_MSG(st == CT_MISS || (st == CT_HIT && h.t_q26 * pr.tend_d > pr.tend_n * (INT64_C(1) << CT_T_FRAC_BITS)),
                            "segment %d method %d: %d, t %lld against the end %lld / %lld", k, m, st, (long long)h.t_q26,
                            (long long)pr.tend_n, (long long)pr.tend_d);
            beyond += st == CT_HIT;
        }
        if (ct_harness_g.current_failed) return;
    }
    std::printf("  short entries: %ld of 4000 segments enter the box, none meets the surface before its end (%ld hits "
                "beyond it, in the last cell)\n", entered, beyond);
    TEST_ASSERT(entered > 1000);
}

}  // namespace

int main()
{
    TEST_BEGIN("test_los");
    RUN_TEST(test_los_vs_reference);
    RUN_TEST(test_los_arguments);
    RUN_TEST(test_locate_inverse_cases);
    RUN_TEST(test_los_cases);
    RUN_TEST(test_los_voids);
    RUN_TEST(test_los_short_entry);
    return TEST_END();
}
