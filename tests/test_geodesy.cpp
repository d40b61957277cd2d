// test_geodesy.cpp -- the library's integer UTM (ct_utm_forward/inverse,
// lib/src/geodesy.c) against PROJ (libproj: EPSG:4326 -> EPSG:326zz/327zz,
// PROJ's own Krueger-series transverse Mercator in double precision), on
// seeded points across zones, both hemispheres, latitudes -80..84 and the
// whole width of a zone (+-4 deg of the central meridian, and out to the
// library's +-9 deg limit); the inverse against PROJ's inverse; the round
// trip; and the statuses for input outside the domain.
#include <proj.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "conetrace.h"
#include "harness.h"
#include "proj_pair.hpp"

namespace {

typedef long double ld;

int64_t q61(ld deg) { return (int64_t)std::llround(deg * M_PIl / 180 * std::ldexp(1.0L, 61)); }
ld deg_of(int64_t q) { return (ld)q / std::ldexp(1.0L, 61) * 180 / M_PIl; }

// EPSG:4326 (lon, lat) -> EPSG:epsg
struct Proj : ProjPair {
    explicit Proj(int epsg) : ProjPair("EPSG:4326", ("EPSG:" + std::to_string(epsg)).c_str()) {}
};

struct Stats {
    long n = 0;
    double fwd = 0, inv = 0;  // worst metres
    long rt_nm = 0;           // worst round-trip difference, nm
};

// One zone: nrays points, lat in [lat0, lat1], lon within dlon of the CM.
void run_zone(int zone, bool south, double lat0, double lat1, double dlon, long npts, Stats *st)
{
    ct_utm z = {zone, south ? 1 : 0};
    Proj pr((south ? 32700 : 32600) + zone);
    TEST_ASSERT_MSG(pr.pj != nullptr, "PROJ cannot create EPSG:%d", (south ? 32700 : 32600) + zone);
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 977 + (uint64_t)zone * 2 + (south ? 1 : 0));
    const double cm = 6.0 * zone - 183;
    for (long k = 0; k < npts; ++k) {
        double lat = lat0 + (lat1 - lat0) * ct_rng_unit(&rng);
        double lon = cm + dlon * (2 * ct_rng_unit(&rng) - 1);
        if (lon > 180) lon -= 360;
        if (lon <= -180) lon += 360;
        int64_t la = q61(lat), lo = q61(lon), e, n;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_forward(&z, la, lo, &e, &n));
        PJ_COORD c = proj_trans(pr.pj, PJ_FWD, proj_coord(deg_of(lo), deg_of(la), 0, 0));
        double d = std::hypot((double)e * 1e-9 - c.xy.x, (double)n * 1e-9 - c.xy.y);
        st->fwd = std::max(st->fwd, d);
        // the inverse at PROJ's point, against the exact input (metres on
        // the ground: 1 rad of latitude ~ 6.37e6 m, of longitude times cos)
        int64_t la2, lo2;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_inverse(&z, e, n, &la2, &lo2));
        PJ_COORD g = proj_trans(pr.pj, PJ_INV, proj_coord((double)e * 1e-9, (double)n * 1e-9, 0, 0));
        ld dlat = (deg_of(la2) - (ld)g.lp.phi) * M_PIl / 180, dl = (deg_of(lo2) - (ld)g.lp.lam) * M_PIl / 180;
        double di = (double)(6.371e6L * std::sqrt(dlat * dlat + dl * dl * std::pow(std::cos(lat * M_PI / 180), 2)));
        st->inv = std::max(st->inv, di);
        // round trip: map -> geodetic -> map gives the same nanometres
        int64_t e2, n2;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_forward(&z, la2, lo2, &e2, &n2));
        st->rt_nm = std::max(st->rt_nm, (long)(std::llabs(e2 - e) + std::llabs(n2 - n)));
        st->n++;
    }
}

void test_utm_vs_proj()
{
    long per = (long)(400 * ct_test_scale());
    Stats zone_w, edge;
    const int zones[] = {1, 17, 31, 33, 60};
    for (int zone : zones)
        for (int south = 0; south < 2; ++south) {
            // across the zone (+-4 deg), UTM's latitudes
            run_zone(zone, south != 0, south ? -80 : 0, south ? 0 : 84, 4.0, per, &zone_w);
            // out to the library's limit (+-9 deg) at mid latitudes
            run_zone(zone, south != 0, south ? -60 : 20, south ? -20 : 60, 9.0, per / 4, &edge);
        }
    std::printf("  %ld points across zones 1, 17, 31, 33, 60 (north and south, +-4 deg): forward %.2f nm, inverse "
                "%.2f nm from PROJ, round trip %ld nm\n",
                zone_w.n, zone_w.fwd * 1e9, zone_w.inv * 1e9, zone_w.rt_nm);
    std::printf("  %ld points out to +-9 deg: forward %.2f nm, inverse %.2f nm, round trip %ld nm\n", edge.n,
                edge.fwd * 1e9, edge.inv * 1e9, edge.rt_nm);
    // the issue asks <= 1 mm against PROJ across a zone; measured a few nm
    // (PROJ's double-precision rounding at 10^7 m is ~1 nm)
    TEST_ASSERT(zone_w.fwd < 1e-6 && zone_w.inv < 1e-6);
    TEST_ASSERT(edge.fwd < 1e-5 && edge.inv < 1e-5);
    TEST_ASSERT(zone_w.rt_nm <= 1 && edge.rt_nm <= 1);
}

void test_utm_fixed_points()
{
    // the central meridian maps to E = 500 km exactly, the equator to N = 0
    // (north) or 10,000 km (south); symmetric about both
    ct_utm n17 = {17, 0}, s17 = {17, 1};
    int64_t e, n, e2, n2;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_forward(&n17, 0, q61(-81), &e, &n));
    TEST_ASSERT(e == INT64_C(500000000000000) && n == 0);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_forward(&s17, 0, q61(-81), &e, &n));
    TEST_ASSERT(e == INT64_C(500000000000000) && n == INT64_C(10000000000000000));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_forward(&n17, q61(37.5), q61(-81 + 2.25), &e, &n));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_forward(&n17, q61(-37.5), q61(-81 - 2.25), &e2, &n2));
    TEST_ASSERT(std::llabs((e - INT64_C(500000000000000)) + (e2 - INT64_C(500000000000000))) <= 1);
    TEST_ASSERT(std::llabs(n + n2) <= 1);
    // on the central meridian N is k0 times the meridian arc, integrated
    // here independently (Simpson, long double): M = a (1 - e^2) int_0^phi
    // (1 - e^2 sin^2)^(-3/2)
    const ld a = 6378137, f = 1 / 298.257223563L, es = f * (2 - f);
    const double lats[] = {1, 30, 60, 84};
    for (double lat : lats) {
        const int steps = 20000;
        ld phi = lat * M_PIl / 180, h = phi / steps, sum = 0;
        for (int k = 0; k <= steps; ++k) {
            ld s = std::sin(k * h), w = (k == 0 || k == steps) ? 1 : (k % 2 ? 4 : 2);
            sum += w / std::pow(1 - es * s * s, 1.5L);
        }
        ld m = a * (1 - es) * sum * h / 3 * 0.9996L;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_forward(&n17, q61(lat), q61(-81), &e, &n));
        TEST_ASSERT(e == INT64_C(500000000000000));
        TEST_ASSERT_MSG(std::fabs((double)((ld)n * 1e-9L - m)) < 1e-6, "lat %g: N %lld nm, arc %.9Lf m", lat,
                        (long long)n, m);
    }
}

void test_utm_bad_input()
{
    ct_utm z = {17, 0}, bad0 = {0, 0}, bad61 = {61, 0};
    int64_t e, n, la, lo;
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_utm_forward(&bad0, 0, q61(-81), &e, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_utm_forward(&bad61, 0, q61(-81), &e, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_utm_forward(nullptr, 0, 0, &e, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_utm_inverse(&z, 0, 0, nullptr, &lo));
    // latitude beyond 84.5 deg (and beyond the pole), longitude off the zone
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_utm_forward(&z, q61(84.6), q61(-81), &e, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_utm_forward(&z, q61(-90.5), q61(-81), &e, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_utm_forward(&z, q61(45), q61(-81 + 9.1), &e, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_utm_forward(&z, q61(45), q61(99), &e, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_utm_forward(&z, q61(45), INT64_MAX, &e, &n));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_forward(&z, q61(45), q61(-81 + 8.9), &e, &n));
    // map points far off the zone
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_utm_inverse(&z, INT64_C(2000000000000000), 0, &la, &lo));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_utm_inverse(&z, INT64_C(500000000000000), INT64_C(9500000000000000), &la, &lo));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_utm_inverse(&z, INT64_MIN, INT64_MAX, &la, &lo));
    // EPSG codes
    ct_utm u;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_zone_of_epsg(32617, &u));
    TEST_ASSERT(u.zone == 17 && u.south == 0);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_zone_of_epsg(32760, &u));
    TEST_ASSERT(u.zone == 60 && u.south == 1);
    TEST_ASSERT_EQUAL_INT(CT_ERR_CRS, ct_utm_zone_of_epsg(4326, &u));
    TEST_ASSERT_EQUAL_INT(CT_ERR_CRS, ct_utm_zone_of_epsg(32600, &u));
    TEST_ASSERT_EQUAL_INT(CT_ERR_CRS, ct_utm_zone_of_epsg(32661, &u));
    const char *name = nullptr;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_status_name(CT_ERR_CRS, &name));
    TEST_ASSERT(std::string(name) == "err_crs");
}

// The meridian convergence and the point scale against PROJ's
// proj_factors (numerical derivatives of its projection, ~1e-10 deg and
// ~1e-10 relative: the tolerance is set by them, not by the library).
void test_utm_factors_vs_proj()
{
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 31337);
    double worst_g = 0, worst_k = 0;
    long n = 0;
    const int zones[] = {5, 17, 33};
    for (int zone : zones)
        for (int south = 0; south < 2; ++south) {
            char def[64];
            std::snprintf(def, sizeof def, "+proj=utm +zone=%d %s+ellps=WGS84", zone, south ? "+south " : "");
            PJ_CONTEXT *ctx = proj_context_create();
            PJ *pj = proj_create(ctx, def);
            TEST_ASSERT(pj != nullptr);
            ct_utm z = {zone, south};
            for (int k = 0; k < (int)(200 * ct_test_scale()); ++k) {
                double lat = south ? -80 * ct_rng_unit(&rng) : 84 * ct_rng_unit(&rng);
                double lon = 6.0 * zone - 183 + 4 * (2 * ct_rng_unit(&rng) - 1);
                int64_t g, kk;
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_factors(&z, q61(lat), q61(lon), &g, &kk));
                PJ_FACTORS f = proj_factors(pj, proj_coord(proj_torad(deg_of(q61(lon))), proj_torad(deg_of(q61(lat))), 0, 0));
                worst_g = std::max(worst_g, std::fabs((double)deg_of(g) - proj_todeg(f.meridian_convergence)));
                worst_k = std::max(worst_k, std::fabs((double)((ld)kk / std::ldexp(1.0L, 61)) - f.parallel_scale));
                n++;
            }
            proj_destroy(pj);
            proj_context_destroy(ctx);
        }
    std::printf("  %ld points: convergence within %.2g deg, point scale within %.2g of PROJ's proj_factors\n", n,
                worst_g, worst_k);
    TEST_ASSERT(worst_g < 1e-8 && worst_k < 1e-9);
    int64_t g, kk;
    ct_utm z = {17, 0};
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_utm_factors(&z, q61(45), q61(-60), &g, &kk));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_utm_factors(&z, q61(45), q61(-81), nullptr, &kk));
    // on the central meridian: no convergence, scale k0 = 0.9996 exactly
    // up to the series' rounding
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_factors(&z, q61(45), q61(-81), &g, &kk));
    TEST_ASSERT(std::llabs(g) < 64);
    TEST_ASSERT(std::fabs((double)((ld)kk / std::ldexp(1.0L, 61) - 0.9996L)) < 1e-15);
}

// A pose from WGS84 and a yaw-pitch-roll attitude: every camera axis, turned
// by ct_pose_from_wgs84 and ct_pose_rotate into the map frame, against an
// independent reference -- the attitude as the product of the three axis
// rotations in long double, the direction stepped 1 m in Earth-fixed
// coordinates (PROJ: EPSG:4979 <-> 4978, then to UTM), the map-frame
// displacement per metre.  The library turns NED by the meridian
// convergence and scales horizontal lengths by k R / (R + h) with R the
// Gaussian mean radius; the radius of curvature in the ray's own azimuth
// differs from it by up to e^2 (0.7 %), so the scale is good to about
// 0.0068 h / R (3e-6 at 2.6 km above the ellipsoid), plus the 1 m step's
// own curvature (1e-7).
void test_pose_from_wgs84_vs_proj()
{
    PJ_CONTEXT *ctx = proj_context_create();
    PJ *to_ecef = proj_create_crs_to_crs(ctx, "EPSG:4979", "EPSG:4978", nullptr);
    PJ *geo3 = to_ecef ? proj_normalize_for_visualization(ctx, to_ecef) : nullptr;
    TEST_ASSERT(geo3 != nullptr);
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 4979);
    double worst = 0, worst_rel = 0;
    long n = 0;
    const int zones[] = {17, 33};
    for (int zone : zones)
        for (int south = 0; south < 2; ++south) {
            Proj utm((south ? 32700 : 32600) + zone);
            ct_utm z = {zone, south};
            for (int k = 0; k < (int)(50 * ct_test_scale()); ++k) {
                double lat = (south ? -1 : 1) * (70 * ct_rng_unit(&rng)), lon = 6.0 * zone - 183 + 6 * (ct_rng_unit(&rng) - 0.5);
                double h = 10000 * ct_rng_unit(&rng);
                double yaw = 360 * ct_rng_unit(&rng) - 180, pitch = 180 * ct_rng_unit(&rng) - 90,
                       roll = 360 * ct_rng_unit(&rng) - 180;
                int32_t q[4];
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(q61(yaw), q61(pitch), q61(roll), q));
                ct_pose pose;
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_wgs84(&pose, &z, q61(lat), q61(lon), std::llround(h * 1e9), q));
                // reference attitude: R_ned_cam = Rz(yaw) Ry(pitch) Rx(roll) P
                ld cy = std::cos(yaw * M_PIl / 180), sy = std::sin(yaw * M_PIl / 180);
                ld cp = std::cos(pitch * M_PIl / 180), sp = std::sin(pitch * M_PIl / 180);
                ld cr = std::cos(roll * M_PIl / 180), sr = std::sin(roll * M_PIl / 180);
                ld Rb[3][3] = {{cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr},
                               {sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr},
                               {-sp, cp * sr, cp * cr}};
                // P: camera x -> body y, y -> body z, z -> body x
                PJ_COORD c0 = proj_trans(geo3, PJ_FWD, proj_coord(lon, lat, h, 0));
                ld la = lat * M_PIl / 180, lo = lon * M_PIl / 180;
                ld N[3] = {-std::sin(la) * std::cos(lo), -std::sin(la) * std::sin(lo), std::cos(la)};
                ld E[3] = {-std::sin(lo), std::cos(lo), 0};
                ld D[3] = {-std::cos(la) * std::cos(lo), -std::cos(la) * std::sin(lo), -std::sin(la)};
                int64_t e0, n0;
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_forward(&z, q61(lat), q61(lon), &e0, &n0));
                for (int axis = 0; axis < 3; ++axis) {
                    const int body = axis == 0 ? 1 : (axis == 1 ? 2 : 0);
                    ld dn = Rb[0][body], de = Rb[1][body], dd = Rb[2][body];
                    ld X = c0.xyz.x + dn * N[0] + de * E[0] + dd * D[0];
                    ld Y = c0.xyz.y + dn * N[1] + de * E[1] + dd * D[1];
                    ld Z = c0.xyz.z + dn * N[2] + de * E[2] + dd * D[2];
                    PJ_COORD g = proj_trans(geo3, PJ_INV, proj_coord((double)X, (double)Y, (double)Z, 0));
                    PJ_COORD m = proj_trans(utm.pj, PJ_FWD, proj_coord(g.lpz.lam, g.lpz.phi, 0, 0));
                    PJ_COORD m0 = proj_trans(utm.pj, PJ_FWD, proj_coord(lon, lat, 0, 0));
                    ld want[3] = {(ld)m.xy.x - m0.xy.x, (ld)m.xy.y - m0.xy.y, (ld)g.lpz.z - h};
                    int32_t ray[3] = {0, 0, 0};
                    ray[axis] = 1 << 30;
                    int64_t got[3];
                    TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_rotate(&pose, ray, got));
                    ld err = 0;
                    for (int c = 0; c < 3; ++c) err = std::max(err, std::fabs((ld)got[c] / std::ldexp(1.0L, 39) - want[c]));
                    worst = std::max(worst, (double)err);
                    double tol = 2e-7 + 0.0068 * h / 6.37e6;
                    worst_rel = std::max(worst_rel, (double)err / tol);
                    TEST_ASSERT_MSG(err <= tol, "lat %g lon %g h %g axis %d: |map dir - PROJ| %.3Lg > %.3g", lat, lon, h,
                                    axis, err, tol);
                }
                TEST_ASSERT(pose.e_nm == e0 && pose.h_nm == std::llround(h * 1e9));
                n++;
            }
        }
    std::printf("  %ld poses x 3 camera axes: map-frame directions within %.2g of PROJ's Earth-fixed step (worst "
                "%.0f %% of the bound)\n",
                n, worst, 100 * worst_rel);
    proj_destroy(geo3);
    proj_destroy(to_ecef);
    proj_context_destroy(ctx);
    // bad input
    ct_utm z = {17, 0};
    ct_pose pose;
    int32_t q[4] = {1 << 30, 0, 0, 0}, qbad[4] = {1 << 29, 0, 0, 0};
    TEST_ASSERT_EQUAL_INT(CT_ERR_POSE, ct_pose_from_wgs84(&pose, &z, q61(45), q61(-81), 0, qbad));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_pose_from_wgs84(&pose, &z, q61(45), q61(-60), 0, q));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_pose_from_wgs84(&pose, &z, q61(89), q61(-81), 0, q));
    TEST_ASSERT_EQUAL_INT(CT_ERR_POSE, ct_pose_from_wgs84(&pose, &z, q61(45), q61(-81), INT64_C(4000000000000000), q));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_pose_from_wgs84(nullptr, &z, q61(45), q61(-81), 0, q));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_quat_from_ypr(q61(181), 0, 0, q));
}

// ---- Earth-centred, Earth-fixed (ct_ecef_from_wgs84 / ct_wgs84_from_ecef) --

// Independent long double references (64-bit mantissa: 5e-20 relative,
// 1e-12 m at 2.4e7 m): the closed forward formula, and the inverse by the
// plain fixed-point iteration phi <- atan2(Z + e^2 N sin phi, p) (a
// different method from the library's Bowring iteration), 80 steps
// (contraction <= 0.04 within the domain).
const ld kA = 6378137, kF = 1 / 298.257223563L, kE2 = kF * (2 - kF);

void ecef_ref(ld lat, ld lon, ld h, ld out[3])
{
    ld s = std::sin(lat), c = std::cos(lat), n = kA / std::sqrt(1 - kE2 * s * s);
    out[0] = (n + h) * c * std::cos(lon);
    out[1] = (n + h) * c * std::sin(lon);
    out[2] = (n * (1 - kE2) + h) * s;
}

void geo_ref(ld x, ld y, ld z, ld *lat, ld *lon, ld *h)
{
    ld p = std::hypot(x, y), phi = std::atan2(z, p * (1 - kE2));
    for (int k = 0; k < 80; ++k) {
        ld s = std::sin(phi);
        phi = std::atan2(z + kE2 * kA / std::sqrt(1 - kE2 * s * s) * s, p);
    }
    ld s = std::sin(phi), c = std::cos(phi);
    *lat = phi;
    *lon = (x == 0 && y == 0) ? 0 : std::atan2(y, x);
    *h = p * c + z * s - kA * std::sqrt(1 - kE2 * s * s);
}

ld rad_of(int64_t q) { return (ld)q / std::ldexp(1.0L, 61); }

// EPSG:4979 (lon, lat deg, h m) <-> EPSG:4978 (m)
struct Proj3 : ProjPair {
    Proj3() : ProjPair("EPSG:4979", "EPSG:4978") {}
};

// a seeded geodetic point: every latitude (poles and the equator exactly
// now and then), longitudes incl. +-180, heights by class: 0 near the
// surface (-1 km .. 10 km), 1 up to 2,000 km, 2 up to hmax_km, 3 deep
// (down to -4,500 km, the forward domain's floor)
void seeded_geo(ct_rng *rng, int cls, double hmax_km, int64_t *la, int64_t *lo, int64_t *h)
{
    const int64_t half_pi = CT_PI_Q61 / 2;
    uint64_t pick = ct_rng_u64(rng) % 16u;
    *la = pick == 0 ? half_pi : pick == 1 ? -half_pi : pick == 2 ? 0 : ct_rng_range(rng, -half_pi, half_pi);
    pick = ct_rng_u64(rng) % 16u;
    *lo = pick == 0 ? CT_PI_Q61 : pick == 1 ? -CT_PI_Q61 : ct_rng_range(rng, -CT_PI_Q61, CT_PI_Q61);
    double hm = cls == 0 ? -1e3 + 11e3 * ct_rng_unit(rng)
              : cls == 1 ? 2e6 * ct_rng_unit(rng)
              : cls == 2 ? hmax_km * 1e3 * ct_rng_unit(rng)
                         : -4.5e6 * ct_rng_unit(rng);
    *h = std::llround(hm * 1e9);
}

void test_ecef_forward_vs_proj()
{
    Proj3 pr;
    TEST_ASSERT_MSG(pr.pj != nullptr, "PROJ cannot create EPSG:4979 -> EPSG:4978");
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 4978 + 1);
    double worst_proj[4] = {0, 0, 0, 0}, worst_ref[4] = {0, 0, 0, 0};
    long n = 0;
    const long per = (long)(2000 * ct_test_scale());
    for (int cls = 0; cls < 4; ++cls)
        for (long k = 0; k < per; ++k) {
            int64_t la, lo, h, xyz[3];
            seeded_geo(&rng, cls, 18000, &la, &lo, &h);
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_ecef_from_wgs84(la, lo, h, xyz));
            PJ_COORD c = proj_trans(pr.pj, PJ_FWD, proj_coord((double)deg_of(lo), (double)deg_of(la), (double)h * 1e-9, 0));
            ld ref[3];
            ecef_ref(rad_of(la), rad_of(lo), (ld)h * 1e-9L, ref);
            double dp = std::sqrt(std::pow((double)xyz[0] * 1e-9 - c.xyz.x, 2) + std::pow((double)xyz[1] * 1e-9 - c.xyz.y, 2) +
                                  std::pow((double)xyz[2] * 1e-9 - c.xyz.z, 2));
            double dr = (double)std::sqrt(std::pow((ld)xyz[0] * 1e-9L - ref[0], 2) + std::pow((ld)xyz[1] * 1e-9L - ref[1], 2) +
                                          std::pow((ld)xyz[2] * 1e-9L - ref[2], 2));
            worst_proj[cls] = std::max(worst_proj[cls], dp);
            worst_ref[cls] = std::max(worst_ref[cls], dr);
            n++;
        }
    std::printf("  forward, %ld points (-1..10 km / ..2,000 km / ..18,000 km / -4,500..0 km): from PROJ %.2f / %.2f / "
                "%.2f / %.2f nm, from the long double formula %.2f / %.2f / %.2f / %.2f nm\n",
                n, worst_proj[0] * 1e9, worst_proj[1] * 1e9, worst_proj[2] * 1e9, worst_proj[3] * 1e9, worst_ref[0] * 1e9,
                worst_ref[1] * 1e9, worst_ref[2] * 1e9, worst_ref[3] * 1e9);
    // PROJ works in double: its input angles in degrees (ulp 1.4e-14 deg at
    // 90: 6 nm at 2.4e7 m) and its output (ulp 3.7 nm at 2.4e7 m) carry a
    // few nm themselves (measured up to 13 nm at 10x the points)
    for (int cls = 0; cls < 4; ++cls) {
        TEST_ASSERT(worst_proj[cls] < 30e-9);
        TEST_ASSERT(worst_ref[cls] < 1.5e-9);  // the nm rounding plus the Q59 factors
    }
    // poles: on the axis exactly; the equator at lon 0: (a + h, 0, 0)
    int64_t xyz[3];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_ecef_from_wgs84(CT_PI_Q61 / 2, q61(37), 0, xyz));
    TEST_ASSERT(xyz[0] == 0 && xyz[1] == 0 && xyz[2] == INT64_C(6356752314245179));  // b = 6356752.314245179 m
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_ecef_from_wgs84(0, 0, INT64_C(1000000000), xyz));
    TEST_ASSERT(xyz[0] == INT64_C(6378138000000000) && xyz[1] == 0 && xyz[2] == 0);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_ecef_from_wgs84(0, CT_PI_Q61, 0, xyz));
    TEST_ASSERT(xyz[0] == -INT64_C(6378137000000000) && std::llabs(xyz[1]) <= 1 && xyz[2] == 0);
}

struct InvStats {
    long n = 0, rt_n = 0;
    double lat_proj = 0, lon_proj = 0, h_proj = 0;  // rad, rad (times cos lat), m
    double lat_ref = 0, lon_ref = 0, h_ref = 0;
    double proj_lat_ref = 0, proj_h_ref = 0;  // PROJ's own inverse vs the reference
    double resid = 0;  // PROJ's forward of the library's result vs the input, m
    long rt_nm = 0;  // ECEF -> geodetic -> ECEF, worst |dx| + |dy| + |dz|
};

void check_inverse(const Proj3 &pr, const int64_t xyz[3], InvStats *st)
{
    int64_t la, lo, h;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_wgs84_from_ecef(xyz, &la, &lo, &h));
    TEST_ASSERT(std::llabs(la) <= CT_PI_Q61 / 2 && std::llabs(lo) <= CT_PI_Q61);
    ld rla, rlo, rh;
    geo_ref((ld)xyz[0] * 1e-9L, (ld)xyz[1] * 1e-9L, (ld)xyz[2] * 1e-9L, &rla, &rlo, &rh);
    PJ_COORD g = proj_trans(pr.pj, PJ_INV, proj_coord((double)xyz[0] * 1e-9, (double)xyz[1] * 1e-9, (double)xyz[2] * 1e-9, 0));
    const ld cl = std::cos(rad_of(la));
    // longitude differences wrapped (+-pi are one meridian), weighted by
    // cos(lat) (at the poles any longitude is right)
    auto dlon = [](ld a, ld b) {
        ld d = std::fabs(a - b);
        return std::min(d, 2 * M_PIl - d);
    };
    st->lat_ref = std::max(st->lat_ref, (double)std::fabs(rad_of(la) - rla));
    st->lon_ref = std::max(st->lon_ref, (double)(dlon(rad_of(lo), rlo) * cl));
    st->h_ref = std::max(st->h_ref, (double)std::fabs((ld)h * 1e-9L - rh));
    st->lat_proj = std::max(st->lat_proj, (double)std::fabs(rad_of(la) - (ld)g.lpz.phi * M_PIl / 180));
    st->lon_proj = std::max(st->lon_proj, (double)(dlon(rad_of(lo), (ld)g.lpz.lam * M_PIl / 180) * cl));
    st->h_proj = std::max(st->h_proj, std::fabs((double)h * 1e-9 - g.lpz.z));
    st->proj_lat_ref = std::max(st->proj_lat_ref, (double)std::fabs((ld)g.lpz.phi * M_PIl / 180 - rla));
    st->proj_h_ref = std::max(st->proj_h_ref, (double)std::fabs((ld)g.lpz.z - rh));
    PJ_COORD f = proj_trans(pr.pj, PJ_FWD, proj_coord((double)deg_of(lo), (double)deg_of(la), (double)h * 1e-9, 0));
    st->resid = std::max(st->resid, std::sqrt(std::pow(f.xyz.x - (double)xyz[0] * 1e-9, 2) + std::pow(f.xyz.y - (double)xyz[1] * 1e-9, 2) +
                                              std::pow(f.xyz.z - (double)xyz[2] * 1e-9, 2)));
    st->n++;
    int64_t back[3];
    if (ct_ecef_from_wgs84(la, lo, h, back) == CT_OK) {
        st->rt_nm = std::max(st->rt_nm, (long)(std::llabs(back[0] - xyz[0]) + std::llabs(back[1] - xyz[1]) +
                                                std::llabs(back[2] - xyz[2])));
        st->rt_n++;
    }
}

void test_ecef_inverse_vs_proj()
{
    Proj3 pr;
    TEST_ASSERT(pr.pj != nullptr);
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 4978 + 2);
    const long per = (long)(2000 * ct_test_scale());
    InvStats st[5];
    // classes 0-3: geodetic points (heights as the forward test, up to
    // 29,000 km: every coordinate stays below 2^55 nm), through PROJ's
    // forward, rounded to nm
    for (int cls = 0; cls < 4; ++cls)
        for (long k = 0; k < per; ++k) {
            int64_t la, lo, h;
            seeded_geo(&rng, cls, 29000, &la, &lo, &h);
            PJ_COORD c = proj_trans(pr.pj, PJ_FWD, proj_coord((double)deg_of(lo), (double)deg_of(la), (double)h * 1e-9, 0));
            int64_t xyz[3] = {std::llround(c.xyz.x * 1e9), std::llround(c.xyz.y * 1e9), std::llround(c.xyz.z * 1e9)};
            check_inverse(pr, xyz, &st[cls]);
        }
    // class 4: anywhere in the inverse's domain: uniform in the cube
    // |.| <= 2^55 nm, at least 2^50 nm from the centre
    for (long k = 0; k < per; ++k) {
        const int64_t m = INT64_C(1) << 55;
        int64_t xyz[3];
        long double r2;
        do {
            for (int i = 0; i < 3; ++i) xyz[i] = ct_rng_range(&rng, -m, m) >> (ct_rng_u64(&rng) % 6u);
            r2 = (ld)xyz[0] * xyz[0] + (ld)xyz[1] * xyz[1] + (ld)xyz[2] * xyz[2];
        } while (r2 < std::ldexp(1.0L, 100));
        check_inverse(pr, xyz, &st[4]);
    }
    const char *names[5] = {"-1..10 km", "..2,000 km", "..29,000 km", "-4,500..0 km", "the whole cube"};
    for (int cls = 0; cls < 5; ++cls)
        std::printf("  inverse, %ld points %s: from the long double iteration lat %.2g, lon %.2g rad, h %.2f nm; "
                    "PROJ's forward of the result %.2f nm from the input; round trip (%ld) %ld nm; from PROJ's "
                    "inverse lat %.2g, lon %.2g rad, h %.3g nm (PROJ's own from the reference: lat %.2g rad, h %.3g nm)\n",
                    st[cls].n, names[cls], st[cls].lat_ref, st[cls].lon_ref, st[cls].h_ref * 1e9, st[cls].resid * 1e9,
                    st[cls].rt_n, st[cls].rt_nm, st[cls].lat_proj, st[cls].lon_proj, st[cls].h_proj * 1e9,
                    st[cls].proj_lat_ref, st[cls].proj_h_ref * 1e9);
    for (int cls = 0; cls < 5; ++cls) {
        // lon weighted by cos(lat); 1e-17 rad is 0.06 nm on the ground
        TEST_ASSERT(st[cls].lat_ref < 5e-17 && st[cls].lon_ref < 5e-17 && st[cls].h_ref < 1e-9);
        // PROJ's double input (1.4e-14 deg: 15 nm at the cube's corners,
        // 6.2e7 m) and output (7.5 nm there) limit this (measured 21 nm)
        TEST_ASSERT(st[cls].resid < 50e-9);
        TEST_ASSERT(st[cls].rt_nm <= 3);
        // longitude is atan2 in both
        TEST_ASSERT(st[cls].lon_proj < 1e-15);
    }
    // PROJ's own inverse (cart.cpp: one Bowring step, h = p / cos(lat) - N)
    // is the coarser one: ~1e-13 rad and ~1 um (near the poles) at the
    // surface, ~1e-8 rad and ~0.3 m at satellite heights, more deep inside
    // (measured, printed above); the library agrees with it that far
    TEST_ASSERT(st[0].lat_proj < 1e-12 && st[0].h_proj < 1e-5);
    for (int cls = 0; cls < 5; ++cls)
        TEST_ASSERT(st[cls].lat_proj <= st[cls].proj_lat_ref + 1e-16 && st[cls].h_proj <= st[cls].proj_h_ref + 2e-9);
}

void test_ecef_domain()
{
    const int64_t half_pi = CT_PI_Q61 / 2, lo_h = -(INT64_C(1) << 52), hi_h = INT64_C(1) << 54;
    int64_t xyz[3], la, lo, h;
    // forward: the edges themselves, and one unit beyond
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_ecef_from_wgs84(half_pi, CT_PI_Q61, hi_h, xyz));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_ecef_from_wgs84(-half_pi, -CT_PI_Q61, lo_h, xyz));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_ecef_from_wgs84(half_pi + 1, 0, 0, xyz));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_ecef_from_wgs84(-half_pi - 1, 0, 0, xyz));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_ecef_from_wgs84(0, CT_PI_Q61 + 1, 0, xyz));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_ecef_from_wgs84(0, -CT_PI_Q61 - 1, 0, xyz));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_ecef_from_wgs84(0, 0, hi_h + 1, xyz));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_ecef_from_wgs84(0, 0, lo_h - 1, xyz));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_ecef_from_wgs84(INT64_MIN, INT64_MIN, INT64_MIN, xyz));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_ecef_from_wgs84(0, 0, INT64_MAX, xyz));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_ecef_from_wgs84(0, 0, 0, nullptr));
    // inverse: |x|, |y|, |z| <= 2^55, at least 2^50 from the centre
    const int64_t m = INT64_C(1) << 55, r0 = INT64_C(1) << 50;
    for (int i = 0; i < 3; ++i) {
        int64_t p[3] = {0, 0, 0};
        p[i] = m;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_wgs84_from_ecef(p, &la, &lo, &h));
        p[i] = -m - 1;
        TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_wgs84_from_ecef(p, &la, &lo, &h));
        p[i] = r0;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_wgs84_from_ecef(p, &la, &lo, &h));
        p[i] = -(r0 - 1);
        TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_wgs84_from_ecef(p, &la, &lo, &h));
        p[i] = INT64_MIN;
        TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_wgs84_from_ecef(p, &la, &lo, &h));
    }
    const int64_t corner[3] = {m, -m, m}, origin[3] = {0, 0, 0};
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_wgs84_from_ecef(corner, &la, &lo, &h));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_wgs84_from_ecef(origin, &la, &lo, &h));
    // off the axes, either side of the 2^50 sphere: 2^44 (37, 37, 37) has
    // r = 1.0014 2^50, 2^44 (36, 36, 36) r = 0.974 2^50
    const int64_t out_r[3] = {INT64_C(37) << 44, INT64_C(37) << 44, -(INT64_C(37) << 44)};
    const int64_t in_r[3] = {INT64_C(36) << 44, INT64_C(36) << 44, -(INT64_C(36) << 44)};
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_wgs84_from_ecef(out_r, &la, &lo, &h));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_wgs84_from_ecef(in_r, &la, &lo, &h));
    // the poles: lon 0 on the axis, lat +-90 deg, h = |z| - b
    const int64_t np[3] = {0, 0, INT64_C(6356752314245179) + 5}, sp[3] = {0, 0, -INT64_C(6356752314245179) - 5};
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_wgs84_from_ecef(np, &la, &lo, &h));
    TEST_ASSERT(lo == 0 && std::llabs(la - half_pi) <= 4 && std::llabs(h - 5) <= 1);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_wgs84_from_ecef(sp, &la, &lo, &h));
    TEST_ASSERT(lo == 0 && std::llabs(la + half_pi) <= 4 && std::llabs(h - 5) <= 1);
    // the antimeridian: +pi (y = 0 and x < 0)
    const int64_t am[3] = {-INT64_C(6378137000000000), 0, 0};
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_wgs84_from_ecef(am, &la, &lo, &h));
    TEST_ASSERT(lo == CT_PI_Q61 && la == 0 && h == 0);
    // NULL pointers
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_wgs84_from_ecef(nullptr, &la, &lo, &h));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_wgs84_from_ecef(am, nullptr, &lo, &h));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_wgs84_from_ecef(am, &la, nullptr, &h));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_wgs84_from_ecef(am, &la, &lo, nullptr));
}

}  // namespace

int main()
{
    TEST_BEGIN("test_geodesy");
    RUN_TEST(test_utm_fixed_points);
    RUN_TEST(test_utm_bad_input);
    RUN_TEST(test_utm_vs_proj);
    RUN_TEST(test_utm_factors_vs_proj);
    RUN_TEST(test_pose_from_wgs84_vs_proj);
    RUN_TEST(test_ecef_domain);
    RUN_TEST(test_ecef_forward_vs_proj);
    RUN_TEST(test_ecef_inverse_vs_proj);
    return TEST_END();
}
