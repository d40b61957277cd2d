// test_earth.cpp -- geolocation with the earth's curvature: the library's
// exact mode (ct_effects CT_EFFECT_CURVATURE with earth_radius_nm == 0 on a
// UTM package: a line of sight straight in Earth-fixed coordinates, bent by
// refraction k t^2 / 2R when asked) against the independent PROJ reference
// of tests/kit/earth_reference.hpp.
//
// The fixture jacksboro_fault_dem.tif (EPSG:32617, 30 m posting, ~12 x 10
// km, ~300 km west of zone 17's central meridian: point scale 1.0008,
// convergence -1.6 deg, map-frame lines of sight bent sideways) is built
// into a package in-process; a pinhole camera looks at it from poses made
// by ct_pose_from_wgs84 (nadir from 3 km; oblique 30 and 20 deg from 2.6
// km; grazing 5 and 3 deg from ~1 km over the terrain in several azimuths;
// long: 5 deg from 10 km outside the tile; far: 5 deg down from 200 km
// south, west, north and east of it, 15 km up, half the pixels aimed at
// tile posts).  Seeded random pixels: the
// library's hit (CT_METHOD_DIRECTIONAL) vs the reference, per pose family
// (count, RMS and max 3D distance), with the same hit/miss status except
// near-grazing rays (reference clearance at a local minimum before the hit
// below kSkipClearM, counted and skipped; a ray that enters the tile's side
// below the surface hits that wall in the reference, and the library may
// call it CT_BELOW instead: counted, accepted), and the distance within
// kMaxErrM, the hit within kMaxOffPathM of the reference path and the RMS
// within kMaxRmsM.  The worst ray of each family is printed with where the
// library's hit lies relative to the reference path (off it: a different
// line of sight; on it but under/over the terrain: a different
// intersection).  For the report only: the old sphere-parabola model (the
// same call with earth_radius_nm = CT_EARTH_RADIUS_NM) against the
// reference.  At grazing incidence a vertical error e moves the hit by
// e / tan(incidence) along the ray: the off-path bound is the model's.
//
// Sanity checks of the reference itself (they hold whatever the library's
// exact mode does): the package georeference (post centres, heights) as the
// reference reads it vs the DEM and ct_grid_to_map; the convergence it
// measures from PROJ vs ct_utm_factors, and the line of sight from the
// library's pose (R_map_cam turned by the convergence) vs the one from the
// navigation solution's quaternion directly (no convergence involved);
// a nadir ray hits straight below the camera at the surface height; on a
// flat package the hit matches a closed-form intersection of the Earth-fixed
// line (or refracted curve) with the surface h = H, and differs from the
// parabola model by about rho^2 tan(depression) / R along track.
#include <proj.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "bend.h"
#include "conetrace.h"
#include "dem_io.hpp"
#include "earth_reference.hpp"
#include "harness.h"
#include "terrain.hpp"
#include "tiles.h"

using namespace ct_host;
using earth_ref::ld;

namespace {

// ---- tolerances -------------------------------------------------------------
// The exact mode's promise: the traced line of sight stays within the chord
// tolerance (ct_effects.chord_nm, default 1 mm) of the true one, plus the
// Q16 rounding of its vertices (up to 2 units: 0.92 mm at 30 m posting).
// So the library's hit lies within kMaxOffPathM of the reference path; its
// distance from the reference hit is that times 1 / tan(incidence) along the
// ray (3.6 cm at 3 deg), bounded here by kMaxErrM, and in RMS by kMaxRmsM.
const double kMaxOffPathM = 0.001 + 2 * 30.0 / 65536;
const double kMaxErrM = 0.04;       // library exact mode vs reference, 3D distance (m): the off-path
                                    // bound over sin(3 deg), the shallowest incidence the poses make
const double kMaxRmsM = 0.005;      // the same, RMS over every family
const double kFitMaxM = 2e-5;       // fitted map vs the reference ECEF -> UTM over its cube (m):
                                    // measured 1.4e-5 at 2^47 nm, degree 6; <= 1.7e-6 below
const double kExactImageM = 2e-6;   // the exact image (Q24, 1.8 um at 30 m) vs the same reference (m)
const double kSkipClearM = 0.05;    // skip rays passing this close (m) over terrain before the hit
const double kRefCheckM = 5e-5;     // reference vs closed form on a flat package (m)
const double kNadirM = 1e-3;        // nadir hit vs the point below the camera (m)
const double kDirAgreeRad = 2e-8;   // line of sight from the pose vs from the quaternion
const int kPixelsPerPose = 50;

const std::string kDem = std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif";
const ld kPi = earth_ref::kPi;

int64_t q61(ld deg) { return (int64_t)std::llround(deg * kPi / 180 * std::ldexp(1.0L, 61)); }
ld deg_of_q61(int64_t v) { return (ld)v / std::ldexp(1.0L, 61) * 180 / kPi; }
// A unit grid direction (east, north, up) in Q39, ct_trace_earth_set's:
// yaw clockwise from grid north, pitch up from the horizontal (degrees).
void grid_dir_q39(ld yaw_deg, ld pitch_deg, int64_t dg[3])
{
    const ld y = yaw_deg * kPi / 180, p = pitch_deg * kPi / 180, one = std::ldexp(1.0L, 39);
    dg[0] = std::llround(std::sin(y) * std::cos(p) * one);
    dg[1] = std::llround(std::cos(y) * std::cos(p) * one);
    dg[2] = std::llround(std::sin(p) * one);
}

struct Cam {
    ct_camera cam;
    ld fx = 1400, fy = 1400, cx = 511.5, cy = 383.5;
    int w = 1024, h = 768;
};

Cam make_camera()
{
    Cam c;
    ct_lens lens;
    std::memset(&lens, 0, sizeof lens);
    lens.model = CT_LENS_PINHOLE;
    lens.width = (uint32_t)c.w;
    lens.height = (uint32_t)c.h;
    lens.fx_q32 = std::llround(c.fx * std::ldexp(1.0L, 32));
    lens.fy_q32 = std::llround(c.fy * std::ldexp(1.0L, 32));
    lens.cx_q32 = std::llround(c.cx * std::ldexp(1.0L, 32));
    lens.cy_q32 = std::llround(c.cy * std::ldexp(1.0L, 32));
    if (ct_camera_init(&c.cam, &lens) != CT_OK) std::abort();
    return c;
}

struct World {
    std::vector<uint8_t> bytes;
    ct_package p;
    earth_ref::Surface sf;
    DemRaster dem;
    Terrain t;
};

World *jacksboro()
{
    static World *w = nullptr;
    if (w) return w;
    w = new World;
    w->dem = read_dem(kDem);
    w->t = terrain_from_heights(w->dem.width, w->dem.height, w->dem.h, w->dem.valid, w->dem.geo, 0.015625);
    BuildOptions o;
    o.sectors = 8;
    w->bytes = build_package(w->t, o);
    if (ct_package_open(&w->p, w->bytes.data(), w->bytes.size()) != CT_OK) std::abort();
    w->sf = earth_ref::Surface::from_package(w->p);
    return w;
}

// A flat package (constant height) with the fixture's origin, posting and
// EPSG, 801 x 801 posts (24 km).
World *flat()
{
    static World *w = nullptr;
    if (w) return w;
    w = new World;
    Georef g = jacksboro()->dem.geo;
    const int n = 801;
    std::vector<double> h((size_t)n * n, 400.0);
    std::vector<uint8_t> valid((size_t)n * n, 1);
    w->t = terrain_from_heights(n, n, h, valid, g, 0.015625);
    BuildOptions o;
    o.sectors = 4;
    o.reduce = 8;
    w->bytes = build_package(w->t, o);
    if (ct_package_open(&w->p, w->bytes.data(), w->bytes.size()) != CT_OK) std::abort();
    w->sf = earth_ref::Surface::from_package(w->p);
    return w;
}

earth_ref::Proj &proj()
{
    static earth_ref::Proj *p = new earth_ref::Proj(32617);
    return *p;
}

// A pose: a map-frame place (E, N), height above the terrain there (or an
// ellipsoidal height), yaw and pitch (deg).
struct PoseDef {
    const char *family;
    ld e, n;         // map position (m)
    ld above;        // metres above the surface under the camera (or the tile's mean outside)
    ld yaw, pitch;   // deg
};

struct Pose {
    PoseDef def;
    ld lat, lon, h;  // as given to ct_pose_from_wgs84 (Q61 values converted back)
    int32_t q[4];
    ct_pose pose;
};

bool make_pose(const earth_ref::Surface &sf, const PoseDef &d, Pose *out)
{
    earth_ref::Proj &pj = proj();
    ld lat, lon;
    pj.utm_inverse(d.e, d.n, &lat, &lon);
    out->def = d;
    const int64_t la = q61(lat), lo = q61(lon);
    const int64_t h_nm = std::llround((sf.ground_under(d.e, d.n) + d.above) * 1e9L);
    out->lat = deg_of_q61(la);
    out->lon = deg_of_q61(lo);
    out->h = (ld)h_nm * 1e-9L;
    ct_utm z = {17, 0};
    const ld yaw = d.yaw > 180 ? d.yaw - 360 : d.yaw;  // ct_quat_from_ypr: |angle| <= pi
    if (ct_quat_from_ypr(q61(yaw), q61(d.pitch), 0, out->q) != CT_OK) return false;
    return ct_pose_from_wgs84(&out->pose, &z, la, lo, h_nm, out->q) == CT_OK;
}

ld dist3(ld e0, ld n0, ld h0, ld e1, ld n1, ld h1)
{
    return std::sqrt((e0 - e1) * (e0 - e1) + (n0 - n1) * (n0 - n1) + (h0 - h1) * (h0 - h1));
}

// ---------------------------------------------------------------------------
// Sanity: the reference's reading of the package georeference.
void test_reference_georef()
{
    World *w = jacksboro();
    const earth_ref::Surface &sf = w->sf;
    TEST_ASSERT_EQUAL_INT(w->dem.width, sf.w);
    TEST_ASSERT_EQUAL_INT(w->dem.height, sf.h);
    TEST_ASSERT_EQUAL_INT(32617, sf.epsg);
    double worst_xy = 0, worst_h = 0, worst_lib = 0;
    for (int j = 0; j < sf.h; j += 7)
        for (int i = 0; i < sf.w; i += 5) {
            ld E, N;
            sf.map_of(i, j, &E, &N);
            // GDAL: pixel (i, j)'s centre
            const ld ge = w->dem.geo.origin_e + (i + 0.5L) * w->dem.geo.posting_e;
            const ld gn = w->dem.geo.origin_n + (j + 0.5L) * w->dem.geo.posting_n;
            worst_xy = std::max(worst_xy, (double)std::max(std::fabs(E - ge), std::fabs(N - gn)));
            worst_h = std::max(worst_h, (double)std::fabs(sf.at(i, j) - (ld)w->dem.h[(size_t)j * sf.w + i]));
            int64_t e_nm, n_nm, h_nm;
            const uint32_t code = w->t.at(i, j);
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&w->p, (int64_t)i << 16, (int64_t)j << 16, (int64_t)code << 16,
                                                        &e_nm, &n_nm, &h_nm));
            worst_lib = std::max(worst_lib, (double)std::max({std::fabs(E - e_nm * 1e-9L), std::fabs(N - n_nm * 1e-9L),
                                                              std::fabs(sf.at(i, j) - h_nm * 1e-9L)}));
        }
    // the bilinear surface between posts vs the library's (rounded up to 2^-16 LSB)
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 97 + 3);
    double worst_s = 0;
    for (int k = 0; k < 2000; ++k) {
        const int64_t x = ct_rng_range(&rng, 0, (int64_t)(sf.w - 1) << 16), y = ct_rng_range(&rng, 0, (int64_t)(sf.h - 1) << 16);
        int64_t z;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_surface_height(&w->p, x, y, &z));
        const ld lib = ((ld)w->p.height_offset_nm + (ld)z / 65536 * (ld)w->p.height_scale_nm) * 1e-9L;
        worst_s = std::max(worst_s, (double)std::fabs(lib - sf.height((ld)x / 65536, (ld)y / 65536)));
    }
    std::printf("  post centres vs GDAL pixel centres %.3g m, vs ct_grid_to_map %.3g m; heights vs DEM %.3g m; "
                "bilinear surface vs ct_surface_height %.3g m\n",
                worst_xy, worst_lib, worst_h, worst_s);
    TEST_ASSERT(worst_xy < 1e-6);
    TEST_ASSERT(worst_lib < 2e-9);
    TEST_ASSERT(worst_h <= 0.015625 / 2 + 1e-9);
    TEST_ASSERT(worst_s < 1e-6);
}

// Sanity: the convergence the reference measures from PROJ, and the line of
// sight from the library's pose vs from the quaternion.
void test_reference_convergence()
{
    earth_ref::Proj &pj = proj();
    World *w = jacksboro();
    ct_utm z = {17, 0};
    double worst_g = 0, gmin = 1e9, gmax = -1e9;
    const ld pts[][2] = {{195000, 4071000}, {207090, 4060680}, {201045, 4065840}, {185000, 4065840}, {500000, 4065840},
                         {800000, 4065840}};
    for (auto &p : pts) {
        ld lat, lon;
        pj.utm_inverse(p[0], p[1], &lat, &lon);
        int64_t g, k;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_factors(&z, q61(lat), q61(lon), &g, &k));
        const ld mine = pj.convergence(lat, lon), lib = (ld)g / std::ldexp(1.0L, 61);
        worst_g = std::max(worst_g, (double)std::fabs(mine - lib));
        gmin = std::min(gmin, (double)(mine * 180 / kPi));
        gmax = std::max(gmax, (double)(mine * 180 / kPi));
        // PROJ's sign: east of the central meridian (north) grid north is east of true north
        if (p[0] > 500001) TEST_ASSERT(mine > 0);
        if (p[0] < 499999) TEST_ASSERT(mine < 0);
    }
    std::printf("  convergence from PROJ's projection (central differences) vs ct_utm_factors: %.2g rad "
                "(%.3f .. %.3f deg over the points)\n",
                worst_g, gmin, gmax);
    TEST_ASSERT(worst_g < 1e-9);
    // the two lines of sight: pose (R_map_cam + convergence) vs quaternion
    const PoseDef defs[] = {{"a", 201045, 4065840, 3000, 0, -90}, {"b", 195500, 4065840, 1000, 90, -5},
                            {"c", 206600, 4070500, 1000, 225, -3}, {"d", 201045, 4061000, 1000, 0, -5},
                            {"e", 185000, 4065840, 1400, 90, -5}, {"f", 201045, 4061340, 2600, 137, -30}};
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 13 + 5);
    double worst = 0, worst_c = 0;
    for (const PoseDef &d : defs) {
        Pose p;
        TEST_ASSERT_MSG(make_pose(w->sf, d, &p), "pose %s", d.family);
        for (int k = 0; k < 20; ++k) {
            ld ray[3] = {ct_rng_unit(&rng) - 0.5, ct_rng_unit(&rng) - 0.5, 1};
            earth_ref::normalise3(ray);
            ld qd[4];
            earth_ref::quat_of_q30(p.q, qd);
            earth_ref::Los a = earth_ref::los_from_pose(pj, p.pose, ray, nullptr);
            earth_ref::Los b = earth_ref::los_from_wgs84(pj, p.lat, p.lon, p.h, qd, ray, nullptr);
            ld dd[3] = {a.d[0] - b.d[0], a.d[1] - b.d[1], a.d[2] - b.d[2]};
            worst = std::max(worst, (double)std::sqrt(earth_ref::dot3(dd, dd)));
            ld dc[3] = {a.C[0] - b.C[0], a.C[1] - b.C[1], a.C[2] - b.C[2]};
            worst_c = std::max(worst_c, (double)std::sqrt(earth_ref::dot3(dc, dc)));
        }
    }
    std::printf("  line of sight from the library's pose vs from the quaternion: direction %.2g rad, centre %.2g m\n",
                worst, worst_c);
    TEST_ASSERT_MSG(worst < kDirAgreeRad, "directions differ by %.3g rad (convergence sign?)", worst);
    TEST_ASSERT(worst_c < 1e-6);
}

// Sanity: nadir rays hit straight below the camera at the surface height.
void test_reference_nadir()
{
    earth_ref::Proj &pj = proj();
    World *w = jacksboro();
    const ld places[][2] = {{201045, 4065840}, {196000, 4070000}, {206000, 4061500}, {198765.4, 4064321.2}};
    double worst = 0;
    for (auto &pl : places)
        for (int refr = 0; refr < 2; ++refr) {
            Pose p;
            TEST_ASSERT(make_pose(w->sf, {"nadir", pl[0], pl[1], 3000, 30, -90}, &p));
            ct_effects fx = {CT_EFFECT_CURVATURE | (refr ? CT_EFFECT_REFRACTION : 0u), CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
            // the camera's optical axis is the local down (pitch -90 in NED): ray (0, 0, 1)
            const ld ray[3] = {0, 0, 1};
            ld qd[4];
            earth_ref::quat_of_q30(p.q, qd);
            // the exact normal (the Q30 quaternion is within 2^-30 of it)
            earth_ref::Los L = earth_ref::los_from_wgs84(pj, p.lat, p.lon, p.h, qd, ray, &fx);
            ld e[3], n[3], u[3];
            earth_ref::enu_axes(p.lat, p.lon, e, n, u);
            for (int k = 0; k < 3; ++k) L.d[k] = -u[k];
            earth_ref::set_effects(L, &fx, u);
            earth_ref::Result r = earth_ref::trace(pj, w->sf, L);
            TEST_ASSERT_EQUAL_INT(CT_HIT, r.status);
            ld E0, N0, x, y;
            pj.utm(p.lat, p.lon, &E0, &N0);
            w->sf.grid(E0, N0, &x, &y);
            const ld d = dist3(r.e, r.n, r.h, E0, N0, w->sf.height(x, y));
            worst = std::max(worst, (double)d);
            TEST_ASSERT_MSG(d < kNadirM, "nadir hit %.4Lf m from the point below the camera", d);
            // and through the pose (Q30 attitude: within 2^-30 rad of the normal)
            earth_ref::Result r2 = earth_ref::geolocate(pj, w->sf, p.pose, ray, &fx);
            TEST_ASSERT_EQUAL_INT(CT_HIT, r2.status);
            TEST_ASSERT(dist3(r2.e, r2.n, r2.h, r.e, r.n, r.h) < 1e-4);
        }
    // a camera under the terrain
    {
        Pose p;
        TEST_ASSERT(make_pose(w->sf, {"under", 201045, 4065840, -5, 0, -30}, &p));
        const ld ray[3] = {0, 0, 1};
        ct_effects fx = {CT_EFFECT_CURVATURE, 0, 0, 0, nullptr};
        TEST_ASSERT_EQUAL_INT(CT_BELOW, earth_ref::geolocate(pj, w->sf, p.pose, ray, &fx).status);
    }
    std::printf("  nadir: hit vs the surface point below the camera within %.3g m\n", worst);
}

// The closed form on a flat surface h = H: Newton on the own long-double
// geodetic height of P(t), then P(t) to the map by PROJ.
bool closed_form_flat(earth_ref::Proj &pj, const earth_ref::Los &L, ld H, ld *E, ld *N, ld *h, ld *t_out)
{
    auto height = [&](ld t) {
        ld P[3], la, lo, hh;
        L.at(t, P);
        earth_ref::geodetic_ld(P, &la, &lo, &hh);
        return hh;
    };
    ld t = 0;
    for (int it = 0; it < 60; ++it) {
        const ld f = height(t) - H, eps = 1e-3L;
        const ld df = (height(t + eps) - height(t - eps)) / (2 * eps);
        if (df >= 0) return false;
        const ld step = f / df;
        t -= step;
        if (std::fabs(step) < 1e-9L) break;
    }
    ld P[3];
    L.at(t, P);
    pj.map(P, E, N, h);
    *t_out = t;
    return std::fabs(*h - H) < 1e-6L;
}

// Sanity: on a flat package the reference hit is the closed-form
// intersection; its difference from the parabola model (the map-frame ray
// of the library's pose with its horizontal scale, rising rho^2 / 2R' with
// R' the ellipsoid's radius of curvature in the ray's azimuth plus the
// camera's height) is about rho^2 tan(depression) / R along track.
void test_reference_flat()
{
    earth_ref::Proj &pj = proj();
    World *w = flat();
    const ld H = w->sf.zmin;
    TEST_ASSERT(w->sf.zmax == H);
    struct Case {
        ld e, n, above, yaw, pitch;
    };
    const Case cases[] = {{201045, 4050000, 1000, 0, -5},  {201045, 4050000, 1000, 0, -10},
                          {201045, 4052000, 2600, 0, -20}, {201045, 4055000, 2600, 0, -45},
                          {196000, 4060000, 1000, 90, -5}, {201045, 4050000, 1500, 20, -5},
                          {216000, 4065000, 1000, 270, -4}, {214000, 4050000, 1200, 315, -6}};
    double worst_cf = 0;
    for (const Case &c : cases)
        for (int refr = 0; refr < 2; ++refr) {
            Pose p;
            TEST_ASSERT(make_pose(w->sf, {"flat", c.e, c.n, c.above, c.yaw, c.pitch}, &p));
            ct_effects fx = {CT_EFFECT_CURVATURE | (refr ? CT_EFFECT_REFRACTION : 0u), CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
            const ld ray[3] = {0, 0, 1};
            earth_ref::Los L = earth_ref::los_from_pose(pj, p.pose, ray, &fx);
            earth_ref::Result r = earth_ref::trace(pj, w->sf, L);
            TEST_ASSERT_EQUAL_INT(CT_HIT, r.status);
            ld E, N, h, t;
            TEST_ASSERT(closed_form_flat(pj, L, H, &E, &N, &h, &t));
            const ld dcf = dist3(r.e, r.n, r.h, E, N, h);
            worst_cf = std::max(worst_cf, (double)dcf);
            TEST_ASSERT_MSG(dcf < kRefCheckM, "flat: reference %.6Lf off the closed form", dcf);
            // the parabola model in the map frame (from the library's pose)
            const int32_t rc[3] = {0, 0, 1 << 30};
            int64_t dq[3];
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_rotate(&p.pose, rc, dq));
            const ld de = dq[0] / std::ldexp(1.0L, 39), dn = dq[1] / std::ldexp(1.0L, 39), dh = dq[2] / std::ldexp(1.0L, 39);
            const ld hor = std::hypot(de, dn), az = std::atan2(de, dn) + L.gamma;  // true azimuth
            const ld la = p.lat * kPi / 180, s2 = std::sin(la) * std::sin(la);
            const ld Nr = earth_ref::kWgsA / std::sqrt(1 - earth_ref::kWgsE2 * s2);
            const ld Mr = earth_ref::kWgsA * (1 - earth_ref::kWgsE2) / std::pow(1 - earth_ref::kWgsE2 * s2, 1.5L);
            const ld Raz = 1 / (std::cos(az) * std::cos(az) / Mr + std::sin(az) * std::sin(az) / Nr);
            const ld Rp = Raz + p.h;
            const ld kk = refr ? CT_REFRACTION_K_STD_Q16 / 65536.0L : 0;
            const ld cc = 1 / (2 * Rp) - kk / (2 * earth_ref::kRefractionRadius);
            // the rise in ground metres: the map range over the pose's
            // horizontal scale k R / (R + h) (in map metres the rise would be
            // 2 (k - 1) too large: ~(k - 1) rho^2 / (R tan) along track)
            const ld hs = p.pose.hscale_q30 / std::ldexp(1.0L, 30), hg = hor / hs;
            // h0 + t dh + cc (t hg)^2 = H: smallest positive root
            const ld A = cc * hg * hg, B = dh, C0 = p.h - H;
            const ld tp = (-B - std::sqrt(B * B - 4 * A * C0)) / (2 * A);
            const ld pe = p.pose.e_nm * 1e-9L + tp * de, pn = p.pose.n_nm * 1e-9L + tp * dn;
            const ld ue = de / hor, un = dn / hor;
            const ld along = (r.e - pe) * ue + (r.n - pn) * un, cross = -(r.e - pe) * un + (r.n - pn) * ue;
            const ld rho = r.range, tdep = -dh / hor;
            // the Earth-fixed line's stretch, and with refraction: the spec
            // bends the path k t^2 cos(dep) / 2R perpendicular to the ray in
            // its vertical plane, the parabola k rho^2 / 2R vertically; at
            // horizontal range s the former has dropped k s^2 / (2 R cos^2
            // dep) (to first order in k: its bend also shortens the range):
            // the hit comes earlier by the excess k s^2 tan^2(dep) / 2R over
            // tan(dep)
            const ld cdep = std::cos(std::atan(tdep));
            // transverse Mercator, x = E - 500 km: the point scale k0 (1 +
            // x^2 / 2R^2) changes along an east-west ray (the map range grows
            // by (x / R^2) ue rho^2 / 2), and a geodesic's image bends
            // sideways by (x / R^2) un rho^2 / 2 (R^2 = M N)
            const ld x = p.pose.e_nm * 1e-9L - 500000, R2 = Mr * Nr;
            const ld pred = rho * rho * tdep / Raz -
                            kk * rho * rho * (1 / (cdep * cdep) - 1) / (2 * earth_ref::kRefractionRadius) / tdep +
                            x / R2 * ue * rho * rho / 2;
            const ld pred_cross = x / R2 * un * rho * rho / 2;
            std::printf("  flat yaw %3.0Lf dep %4.1Lf%s: range %7.1Lf m, ref vs closed form %.2Lg m; vs parabola along "
                        "%+.3Lf m (predicted %+.3Lf), across %+.3Lf m (predicted %+.3Lf)\n",
                        c.yaw, -c.pitch, refr ? " refr" : "     ", rho, dcf, along, pred, cross, pred_cross);
            TEST_ASSERT_MSG(std::fabs(along - pred) <= 0.03L * std::fabs(pred) + 0.03L,
                            "along-track difference %.3Lf m vs predicted %.3Lf m", along, pred);
            TEST_ASSERT_MSG(std::fabs(cross - pred_cross) <= 0.05L * std::fabs(pred_cross) + 0.03L,
                            "cross-track difference %.3Lf m vs predicted %.3Lf m", cross, pred_cross);
        }
    std::printf("  flat: reference vs closed form within %.3g m\n", worst_cf);
}

// ---------------------------------------------------------------------------
// The library's exact mode vs the reference.

struct Stat {
    long n = 0, miss_agree = 0, skipped = 0, mismatch = 0, wall_below = 0;
    double sum2 = 0, max = 0, max_off = 0;
    std::vector<double> all;
    char worst[300] = "";
    void add(double d, const char *what)
    {
        n++;
        sum2 += d * d;
        all.push_back(d);
        if (d > max) std::snprintf(worst, sizeof worst, "%s", what);
        max = std::max(max, d);
    }
    double rms() const { return n ? std::sqrt(sum2 / n) : 0; }
    double median()
    {
        if (all.empty()) return 0;
        std::nth_element(all.begin(), all.begin() + all.size() / 2, all.end());
        return all[all.size() / 2];
    }
};

// Stats summed over the families: the worst errors, RMS and status mismatches.
struct Total {
    double worst = 0, worst_off = 0, sum2 = 0;
    long bad = 0, n = 0;
    void add(const Stat &s)
    {
        worst = std::max(worst, s.max);
        worst_off = std::max(worst_off, s.max_off);
        sum2 += s.sum2;
        n += s.n;
        bad += s.mismatch;
    }
    double rms() const { return n ? std::sqrt(sum2 / (double)n) : 0; }
};

std::vector<PoseDef> pose_defs()
{
    const ld Ec = 201045, Nc = 4065840;
    auto back = [&](ld dist, ld yaw, ld *e, ld *n) {
        *e = Ec - dist * std::sin(yaw * kPi / 180);
        *n = Nc - dist * std::cos(yaw * kPi / 180);
    };
    std::vector<PoseDef> v;
    v.push_back({"nadir", Ec, Nc, 3000, 0, -90});
    v.push_back({"nadir", Ec - 3000, Nc + 2000, 3000, 40, -90});
    for (ld yaw : {0.0L, 135.0L}) {
        ld e, n;
        back(2600 / std::tan(30 * kPi / 180), yaw, &e, &n);
        v.push_back({"oblique30", e, n, 2600, yaw, -30});
    }
    for (ld yaw : {270.0L, 45.0L}) {
        ld e, n;
        back(2600 / std::tan(20 * kPi / 180), yaw, &e, &n);
        v.push_back({"oblique20", e, n, 2600, yaw, -20});
    }
    // grazing: north from the south edge, east from the west edge, south-west from the north-east corner
    v.push_back({"grazing5", Ec, 4061000, 1000, 0, -5});
    v.push_back({"grazing5", 195500, Nc, 1000, 90, -5});
    v.push_back({"grazing5", 206600, 4070500, 1000, 225, -5});
    v.push_back({"grazing3", Ec, 4061000, 1000, 0, -3});
    v.push_back({"grazing3", 195500, Nc, 1000, 90, -3});
    v.push_back({"grazing3", 206600, 4070500, 1000, 225, -3});
    // long: 10 km outside the tile, 5 deg down towards its middle
    v.push_back({"long", 185000, Nc, 1420, 90, -5});
    v.push_back({"long", Ec, 4050680, 1350, 0, -5});
    // far: 200 km south, west, north and east of the tile, 15 km up,
    // looking at it (about 5 deg down, the Earth's drop 3.1 km included): a
    // range beyond 150 km, so the path is interpolated through 6 nodes, and
    // lines of sight that pass over the tile leave it on every side; half
    // the pixels aimed at tile posts (ct_locate_inverse), the others at random
    v.push_back({"far", Ec, Nc - 200000, 15000, 0, -5.1L});
    v.push_back({"far", Ec - 200000, Nc, 15000, 90, -5.1L});
    v.push_back({"far", Ec, Nc + 200000, 15000, 179.9L, -5.1L});  // yaw: within ct_quat_from_ypr's pi
    v.push_back({"far", Ec + 200000, Nc, 15000, 270, -5.1L});
    return v;
}

// compare()'s pose families, in pose_defs()' order.
const char *const kFamilies[] = {"nadir", "oblique30", "oblique20", "grazing5", "grazing3", "long", "far"};
constexpr int kFamilyCount = 7;

// What compare() gathers: per family, each mode's statistics against the
// reference (the exact mode, the old parabola on a 6371 km sphere, the fitted
// map, the kept map) and the reference's hits and their ranges; over every
// family, the fitted map against the exact mode and the ct_los checks.
struct Tally {
    Stat exact[kFamilyCount], old[kFamilyCount], fitted[kFamilyCount], kmap[kFamilyCount];
    ld rng_sum[kFamilyCount] = {0};
    long ref_hits[kFamilyCount] = {0};
    double fit_vs_exact = 0;
    long fit_status_diff = 0, los_checked = 0, los_bad = 0, first_reports = 0;
    long inv_checked = 0;
    double inv_worst_px = 0; // ct_locate_inverse of the reference hits: pixel error
};

// The effects of the four modes.
struct Modes {
    ct_effects exact, old, fit, kept;
};

// The effects of the four modes for the flags; the kept map, one for every
// pose: the tile's centre at 500 m, a cube of 70 km (every pose's range from
// there, with 10 km to spare).
void make_modes(unsigned flags, const ct_package &p, Modes *m)
{
    static ct_earth_map kept;
    m->exact = {flags, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
    m->old = m->fit = m->kept = m->exact;
    m->old.earth_radius_nm = CT_EARTH_RADIUS_NM;
    m->fit.flags |= CT_EFFECT_EARTH_FIT;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_map_init(&p, INT64_C(201045) * 1000000000, INT64_C(4065840) * 1000000000,
                                                   INT64_C(500) * 1000000000, INT64_C(60000) * 1000000000, &kept));
    m->kept.earth_map = &kept;
}

// A pixel, its pose and the reference's result for it.
struct PixelCase {
    const PoseDef *d;
    int64_t u, v;
    const earth_ref::Los *L;
    const earth_ref::Result *r;
};

// One mode's status and hit for a pixel, judged against the reference into
// s; the first 8 status mismatches of the reported modes are printed.
void judge(World *w, const PixelCase &c, Stat &s, int status, const ct_geo &gg, bool report, long *first_reports)
{
    earth_ref::Proj &pj = proj();
    const PoseDef &d = *c.d;
    const earth_ref::Result &r = *c.r;
    const int64_t u = c.u, v = c.v;
    if (r.wall && status == CT_BELOW) {
        // the path enters the tile's side below the surface: the
        // reference hits that wall; the library may call it BELOW
        s.wall_below++;
        return;
    }
    if (status != r.status) {
        s.mismatch++;
        if (report && (*first_reports)++ < 8)
            std::printf("    %s yaw %.0Lf px (%.2f, %.2f): library status %d (%.3f %.3f %.3f), reference %d "
                        "(%.3Lf %.3Lf %.3Lf, range %.0Lf m, clearance %.3Lg m)\n",
                        d.family, d.yaw, u / 65536.0, v / 65536.0, status, gg.hit.e_nm * 1e-9,
                        gg.hit.n_nm * 1e-9, gg.hit.h_nm * 1e-9, r.status, r.e, r.n, r.h, r.range, r.min_clear);
        return;
    }
    if (status != CT_HIT) {
        s.miss_agree++;
        return;
    }
    const ld le = gg.hit.e_nm * 1e-9L, ln = gg.hit.n_nm * 1e-9L, lh = gg.hit.h_nm * 1e-9L;
    char what[300];
    const earth_ref::OffPath op = earth_ref::off_path(pj, w->sf, *c.L, le, ln, lh);
    std::snprintf(what, sizeof what,
                  "yaw %.0Lf px (%.2f, %.2f): reference (%.3Lf, %.3Lf, %.3Lf) range %.0Lf m, library - "
                  "reference (%+.4Lf, %+.4Lf, %+.4Lf) m; the library's hit is %.4Lf m off the path, "
                  "%+.4Lf m along it, the path's clearance there %+.4Lf m",
                  d.yaw, u / 65536.0, v / 65536.0, r.e, r.n, r.h, r.range, le - r.e, ln - r.n, lh - r.h,
                  op.dist, op.t - r.t, op.clearance);
    s.add((double)dist3(le, ln, lh, r.e, r.n, r.h), what);
    s.max_off = std::max(s.max_off, (double)op.dist);
}

// ct_los on the true Earth from the camera centre to the reference's hit r:
// visible (0.5 m margin), and a point 30 m under it hidden -- unless the hit
// lies within 2 m of the tile's edge, where the line to that point may
// enter the tile's side within the margin of it (the side wall then meets
// it at itself: visible, rightly).
void check_los(World *w, const Pose &p, const PoseDef &d, const earth_ref::Result &r, const ct_effects &fx, Tally &T)
{
    const int64_t A[3] = {p.pose.e_nm, p.pose.n_nm, p.pose.h_nm};
    const int64_t B[3] = {std::llround(r.e * 1e9L), std::llround(r.n * 1e9L), std::llround(r.h * 1e9L)};
    const int64_t B2[3] = {B[0], B[1], B[2] - INT64_C(30000000000)};
    ld E0, N0, E1, N1;
    w->sf.map_of(0, 0, &E0, &N0);
    w->sf.map_of(w->sf.w - 1, w->sf.h - 1, &E1, &N1);
    const ld edge = std::min(std::min(std::fabs(r.e - E0), std::fabs(r.e - E1)),
                             std::min(std::fabs(r.n - N0), std::fabs(r.n - N1)));
    ct_hit lb;
    const ct_status v1 = ct_los(&w->p, A, B, &fx, 500000000, CT_METHOD_DIRECTIONAL, &lb);
    const ct_status v2 = edge >= 2 ? ct_los(&w->p, A, B2, &fx, 500000000, CT_METHOD_DIRECTIONAL, &lb) : CT_HIT;
    T.los_checked++;
    if (v1 != CT_OK || v2 != CT_HIT) {
        T.los_bad++;
        if (T.los_bad <= 5)
            std::printf("    ct_los %s yaw %.0Lf: to the reference hit %d (want %d), 30 m under it %d "
                        "(want %d)\n", d.family, d.yaw, v1, CT_OK, v2, CT_HIT);
    }
}

// ct_locate_inverse of the reference's hit for pixel (u, v) (Q16) must give
// that pixel back: the PROJ reference's point lies on the pixel's line of
// sight, so its pixel is (u, v) to the reference's precision (um at 200 km:
// far below 10^-3 px at 1,400 px focal length).
void check_inverse(World *w, const Cam &cam, const Pose &p, const earth_ref::Result &r, const ct_effects &fx,
                   int64_t u, int64_t v, Tally &T)
{
    const int64_t G[3] = {std::llround(r.e * 1e9L), std::llround(r.n * 1e9L), std::llround(r.h * 1e9L)};
    int64_t uu = 0, vv = 0;
    uint32_t vis = 0;
    ct_hit blk;
    const ct_status s = ct_locate_inverse(&w->p, &cam.cam, &p.pose, &fx, G, 500000000, &uu, &vv, &vis, &blk);
    T.inv_checked++;
    const double e = s == CT_OK ? std::hypot((uu - u) / 65536.0, (vv - v) / 65536.0) : 1e9;
    if (e > T.inv_worst_px && T.inv_worst_px <= 0.01 && e > 0.01)
        std::printf("    ct_locate_inverse %s: pixel (%.3f, %.3f) back at (%.4f, %.4f), status %d\n", p.def.family,
                    u / 65536.0, v / 65536.0, uu / 65536.0, vv / 65536.0, s);
    T.inv_worst_px = std::max(T.inv_worst_px, e);
}

// One pose of family f: its pixels uv (u, v pairs, Q16) geolocated in the
// four modes -- the fitted and the kept map as one batch each, the batch's
// first pixel also alone (bit for bit ct_geolocate's) -- and judged against
// the reference; ct_los to each reference hit.
void run_pose(World *w, const Cam &cam, const Pose &p, int f, const std::vector<int64_t> &uv, const Modes &m,
              Tally &T)
{
    earth_ref::Proj &pj = proj();
    const PoseDef &d = p.def;
    const int npix = (int)(uv.size() / 2);
    std::vector<ct_geo> gf((size_t)npix), gk((size_t)npix);
    TEST_ASSERT(ct_geolocate_batch(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &m.fit, uv.data(),
                                   (size_t)npix, gf.data(), gf.size()) == CT_OK);
    TEST_ASSERT(ct_geolocate_batch(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &m.kept, uv.data(),
                                   (size_t)npix, gk.data(), gk.size()) == CT_OK);
    {
        ct_geo g1;
        const ct_status s1 = ct_geolocate(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &m.fit, uv[0], uv[1], &g1);
        TEST_ASSERT(s1 == gf[0].status && g1.hit.e_nm == gf[0].hit.e_nm && g1.hit.n_nm == gf[0].hit.n_nm &&
                    g1.hit.h_nm == gf[0].hit.h_nm && g1.hit.steps == gf[0].hit.steps);
    }
    for (int k = 0; k < npix; ++k) {
        const int64_t u = uv[2 * k], v = uv[2 * k + 1];
        ld ray[3];
        earth_ref::pinhole_ray(cam.fx, cam.fy, cam.cx, cam.cy, (ld)u / 65536, (ld)v / 65536, ray);
        const earth_ref::Los L = earth_ref::los_from_pose(pj, p.pose, ray, &m.exact);
        earth_ref::Result r = earth_ref::trace(pj, w->sf, L);
        ct_geo g, go;
        const ct_status st = ct_geolocate(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &m.exact, u, v, &g);
        const ct_status so = ct_geolocate(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &m.old, u, v, &go);
        const int ls = st == CT_HIT_VOID ? CT_HIT : st, los = so == CT_HIT_VOID ? CT_HIT : so;
        if (r.min_clear < kSkipClearM) {
            T.exact[f].skipped++;
            T.old[f].skipped++;
            T.fitted[f].skipped++;
            T.kmap[f].skipped++;
            continue;
        }
        if (r.status == CT_HIT) {
            T.rng_sum[f] += r.range;
            T.ref_hits[f]++;
        }
        const PixelCase c = {&d, u, v, &L, &r};
        judge(w, c, T.exact[f], ls, g, true, &T.first_reports);
        judge(w, c, T.old[f], los, go, false, &T.first_reports);
        const int lfs = gf[k].status == CT_HIT_VOID ? CT_HIT : gf[k].status;
        judge(w, c, T.fitted[f], lfs, gf[k], true, &T.first_reports);
        judge(w, c, T.kmap[f], gk[k].status == CT_HIT_VOID ? CT_HIT : gk[k].status, gk[k], true, &T.first_reports);
        if (r.status == CT_HIT && !r.wall) check_los(w, p, d, r, m.exact, T);
        if (r.status == CT_HIT) check_inverse(w, cam, p, r, m.exact, u, v, T);
        if (lfs != ls) {
            T.fit_status_diff++;
        } else if (ls == CT_HIT) {
            T.fit_vs_exact = std::max(T.fit_vs_exact, (double)dist3(gf[k].hit.e_nm * 1e-9L, gf[k].hit.n_nm * 1e-9L,
                                                                    gf[k].hit.h_nm * 1e-9L, g.hit.e_nm * 1e-9L,
                                                                    g.hit.n_nm * 1e-9L, g.hit.h_nm * 1e-9L));
        }
    }
}

// The per-family table: the exact mode and the old parabola, then the
// fitted map; ex and fi summed over the families.
void print_families(Tally &T, Total *ex, Total *fi)
{
    std::printf("  hits: both hit (compared); miss: both miss; skip: reference clearance < %.2f m before the hit; "
                "bad: status differs; wall: the reference hits the tile's side (entering below the surface) and the "
                "library says CT_BELOW (accepted)\n",
                kSkipClearM);
    std::printf("  %-10s %5s %5s %5s | %-46s | %-46s\n", "family", "hits", "miss", "skip",
                "exact mode (radius 0): median / RMS / max, bad, wall",
                "old parabola (6371 km): median / RMS / max, bad, wall");
    for (int f = 0; f < kFamilyCount; ++f) {
        Stat &e = T.exact[f], &o = T.old[f];
        std::printf("  %-10s %5ld %5ld %5ld | %8.4f %8.4f %9.4f m %4ld %4ld | %8.4f %8.4f %9.4f m %4ld %4ld  (mean range "
                    "%.0f m)\n",
                    kFamilies[f], e.n, e.miss_agree, e.skipped, e.median(), e.rms(), e.max, e.mismatch, e.wall_below,
                    o.median(), o.rms(), o.max, o.mismatch, o.wall_below,
                    (double)(T.rng_sum[f] / std::max<long>(1, T.ref_hits[f])));
        if (e.n) std::printf("  %-10s   worst (exact mode): %s\n", "", e.worst);
        ex->add(e);
    }
    for (int f = 0; f < kFamilyCount; ++f) {
        Stat &s = T.fitted[f];
        std::printf("  %-10s fitted map (CT_EFFECT_EARTH_FIT): %5ld hits, median / RMS / max %8.4f %8.4f %9.4f m, "
                    "bad %ld, wall %ld\n",
                    kFamilies[f], s.n, s.median(), s.rms(), s.max, s.mismatch, s.wall_below);
        if (s.n) std::printf("  %-10s   worst (fitted map): %s\n", "", s.worst);
        fi->add(s);
    }
}

// The totals against their bounds: ct_los, the kept map, the fitted map,
// the exact mode.
void check_totals(Tally &T, const Total &ex, const Total &fi)
{
    std::printf("  ct_los on the true Earth: %ld reference hits visible from the camera, 30 m under them hidden; "
                "%ld wrong\n", T.los_checked, T.los_bad);
    TEST_ASSERT_MSG(T.los_bad == 0 && T.los_checked > 300, "ct_los: %ld wrong of %ld", T.los_bad, T.los_checked);
    std::printf("  ct_locate_inverse on the true Earth: %ld reference hits, each back at its pixel within %.5f px\n",
                T.inv_checked, T.inv_worst_px);
    TEST_ASSERT_MSG(T.inv_checked > 300 && T.inv_worst_px <= 0.01, "ct_locate_inverse: a pixel %.4f px off (%ld)",
                    T.inv_worst_px, T.inv_checked);
    Total km;
    for (int f = 0; f < kFamilyCount; ++f) km.add(T.kmap[f]);
    const double kworst = km.worst, kworst_off = km.worst_off, krms = km.rms();
    const long kbad = km.bad, kn = km.n;
    std::printf("  kept map (ct_earth_map_init, one for all poses): %ld hits within %.4f m of the reference path, RMS "
                "%.4f m, max %.4f m from the reference hit, %ld statuses differ\n",
                kn, kworst_off, krms, kworst, kbad);
    TEST_ASSERT_MSG(kworst_off <= kMaxOffPathM && krms <= kMaxRmsM && kbad == 0 && kworst <= kMaxErrM,
                    "kept map: off path %.4f, RMS %.4f, %ld bad, max %.4f m", kworst_off, krms, kbad, kworst);
    const double fworst = fi.worst, fworst_off = fi.worst_off, frms = fi.rms();
    const long fbad = fi.bad;
    std::printf("  fitted map: hits within %.4f m of the reference path, RMS %.4f m, max %.4f m from the reference "
                "hit; vs the exact map's hits: up to %.4f m apart, %ld statuses differ\n",
                fworst_off, frms, fworst, T.fit_vs_exact, T.fit_status_diff);
    TEST_ASSERT_MSG(fworst_off <= kMaxOffPathM, "fitted map: a hit %.4f m off the reference path (> %.4f m)",
                    fworst_off, kMaxOffPathM);
    TEST_ASSERT_MSG(frms <= kMaxRmsM, "fitted map: RMS %.4f m (> %.4f m)", frms, kMaxRmsM);
    TEST_ASSERT_MSG(fbad == 0, "fitted map: %ld rays with a status different from the reference's", fbad);
    TEST_ASSERT_MSG(fworst <= kMaxErrM, "fitted map off the reference by up to %.4f m (> %.4f m)", fworst, kMaxErrM);
    const double worst = ex.worst, worst_off = ex.worst_off, rms = ex.rms();
    const long bad = ex.bad;
    std::printf("  exact mode: hits within %.4f m of the reference path (bound %.4f m), RMS %.4f m, max %.4f m from "
                "the reference hit\n", worst_off, kMaxOffPathM, rms, worst);
    TEST_ASSERT_MSG(worst_off <= kMaxOffPathM, "a library hit %.4f m off the reference path (> %.4f m)", worst_off,
                    kMaxOffPathM);
    TEST_ASSERT_MSG(rms <= kMaxRmsM, "RMS %.4f m (> %.4f m)", rms, kMaxRmsM);
    TEST_ASSERT_MSG(bad == 0, "%ld rays with the library's status different from the reference's", bad);
    TEST_ASSERT_MSG(worst <= kMaxErrM, "library exact mode off the reference by up to %.4f m (> %.4f m)", worst, kMaxErrM);
}

// The library's true Earth with these effects against the reference: every
// pose of pose_defs() with kPixelsPerPose seeded pixels, in the four modes.
void compare(unsigned flags)
{
    earth_ref::Proj &pj = proj();
    World *w = jacksboro();
    Cam cam = make_camera();
    const std::vector<PoseDef> defs = pose_defs();
    Tally T;
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 1009 + flags);
    const int npix = std::max(1, (int)std::lround(kPixelsPerPose * ct_test_scale()));
    Modes m;
    make_modes(flags, w->p, &m);
    auto t0 = std::chrono::steady_clock::now();
    for (const PoseDef &d : defs) {
        int f = 0;
        while (std::strcmp(kFamilies[f], d.family) != 0) f++;
        Pose p;
        TEST_ASSERT_MSG(make_pose(w->sf, d, &p), "pose %s", d.family);
        std::vector<int64_t> uv(2 * (size_t)npix);
        for (int k = 0; k < npix; ++k) {
            uv[2 * k] = ct_rng_range(&rng, 0, (int64_t)(cam.w - 1) << 16);
            uv[2 * k + 1] = ct_rng_range(&rng, 0, (int64_t)(cam.h - 1) << 16);
            if (f == 6 && k % 2 == 0) {
                // the tile takes a few pixels of the far poses' view: aim 1 m
                // under a random post (aimed at the post itself, the line of
                // sight would graze the surface there: a tangency, which the
                // library's mm and the reference may settle either way)
                const int i = (int)ct_rng_range(&rng, 0, w->sf.w - 1), j = (int)ct_rng_range(&rng, 0, w->sf.h - 1);
                ld E, N;
                w->sf.map_of(i, j, &E, &N);
                const int64_t g[3] = {std::llround(E * 1e9L), std::llround(N * 1e9L),
                                      std::llround((w->sf.at(i, j) - 1) * 1e9L)};
                int64_t u = 0, v = 0;
                uint32_t vis = 0;
                ct_hit blk;
                if (ct_locate_inverse(&w->p, &cam.cam, &p.pose, &m.exact, g, 0, &u, &v, &vis, &blk) == CT_OK &&
                    u >= 0 && v >= 0 && u <= (int64_t)(cam.w - 1) << 16 && v <= (int64_t)(cam.h - 1) << 16) {
                    uv[2 * k] = u;
                    uv[2 * k + 1] = v;
                }
            }
        }
        run_pose(w, cam, p, f, uv, m, T);
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("  effects %s: %d pixels per pose, %zu poses; reference %.1f s, %ld PROJ samples\n",
                flags & CT_EFFECT_REFRACTION ? "curvature+refraction (k 0.13)" : "curvature", npix, defs.size(), secs,
                pj.calls);
    Total ex, fi;
    print_families(T, &ex, &fi);
    check_totals(T, ex, fi);
}

// The fitted map (CT_EFFECT_EARTH_FIT) against PROJ's ECEF -> UTM over its
// whole cube, for cameras ever farther west of the tile (cubes of 2^44 ..
// 2^47 nm, degrees 4 .. 6): the fit is interpolation, so the error is
// largest between its points and near the cube's corners -- sampled at
// random points, at the corners and on the faces' middles.
// The fitted image g (Q24 grid units) of Earth-fixed offset D against the
// reference: long-double geodetic coordinates (PROJ's own ECEF -> geodetic
// is one Bowring step, off by tens of um 70 km from the ellipsoid), PROJ's
// transverse Mercator; the largest |dE|, |dN|, |dh| (m) so far in err.
// The reference's map point (m) of the Earth-fixed offset D from the camera.
void ref_point(const ct_earth &es, const int64_t D[3], ld *E, ld *N, ld *h)
{
    ld X[3], lat, lon;
    for (int k = 0; k < 3; ++k) X[k] = (ld)(es.c[k] + D[k]) * 1e-9L;
    earth_ref::geodetic_ld(X, &lat, &lon, h);
    proj().utm(lat * 180 / kPi, lon * 180 / kPi, E, N);
}

void fit_error(const ct_package &pk, const ct_earth &es, const int64_t D[3], const int64_t g[3], double err[3])
{
    ld E, N, h;
    ref_point(es, D, &E, &N, &h);
    const ld fe = pk.origin_e_nm * 1e-9L + (ld)(g[0] + (INT64_C(1) << 23)) * (ld)pk.posting_e_nm * 1e-9L / 16777216.0L;
    const ld fn = pk.origin_n_nm * 1e-9L + (ld)(g[1] + (INT64_C(1) << 23)) * (ld)pk.posting_n_nm * 1e-9L / 16777216.0L;
    const ld fh = pk.height_offset_nm * 1e-9L + (ld)g[2] * (ld)pk.height_scale_nm * 1e-9L / 16777216.0L;
    err[0] = std::max(err[0], (double)std::fabs(fe - E));
    err[1] = std::max(err[1], (double)std::fabs(fn - N));
    err[2] = std::max(err[2], (double)std::fabs(fh - h));
}

// The map ct_earth_setup fits for a camera back_km east of the tile (3 km
// up, looking west 10 deg down): its cube's corners, edge and face middles
// and centre and nrand random points against the reference, a point just
// outside refused.  The cube's size joins *seen, its largest error *worst.
void check_fit_for_camera(World *w, ld back_km, ct_rng *rng, int nrand, uint32_t *seen, double *worst)
{
    const ct_package &pk = w->p;
    Pose p;
    TEST_ASSERT(make_pose(w->sf, {"far", 201045 + back_km * 1000, 4065840, 3000, 270, -10}, &p));
    ct_earth es;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&pk, &p.pose, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM,
                                                CT_EFFECTS_CHORD_NM, 0u, 1, nullptr, &es));
    TEST_ASSERT_MSG(es.map == &es.fit && es.fit.deg >= 4 && es.fit.deg <= CT_EARTH_MAP_DEG,
                    "no fit %d km back (range %.1f km)", (int)back_km, es.tmax_nm * 1e-12);
    *seen |= 1u << es.fit.qrho % 32u;
    const int64_t half = INT64_C(1) << es.fit.qrho;
    double err[3] = {0, 0, 0}, err_exact[3] = {0, 0, 0};
    int refused = 0;
    auto check = [&](const int64_t D[3]) {
        int64_t g[3];
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_image24(&pk, &es, D, 1, g));
        fit_error(pk, es, D, g, err);
        // the exact image (what the fit interpolates) against the reference
        // too; refused (CT_ERR_RANGE) only beyond its range, 2^23 grid units
        // from the camera on an axis (it keeps 32 fraction bits below 2^55:
        // 131 km of height at this package's 15.6 mm scale)
        const ct_status st = ct_earth_image24(&pk, &es, D, 0, g);
        if (st == CT_OK) {
            fit_error(pk, es, D, g, err_exact);
        } else {
            ld E, N, h, E0, N0, h0;
            const int64_t zero[3] = {0, 0, 0};
            ref_point(es, D, &E, &N, &h);
            ref_point(es, zero, &E0, &N0, &h0);
            const ld units = std::max(std::max(std::fabs(E - E0) / (pk.posting_e_nm * 1e-9L),
                                               std::fabs(N - N0) / std::fabs(pk.posting_n_nm * 1e-9L)),
                                      std::fabs(h - h0) / (pk.height_scale_nm * 1e-9L));
            TEST_ASSERT_MSG(st == CT_ERR_RANGE && units > 8388608.0L * (1 - 1e-6L),
                            "exact image refused (%d) %.0Lf grid units from the camera", st, units);
            refused++;
        }
    };
    for (int c = 0; c < 27; ++c) {  // corners, edge and face middles, centre
        const int64_t D[3] = {(c % 3 - 1) * half, (c / 3 % 3 - 1) * half, (c / 9 - 1) * half};
        check(D);
    }
    for (int k = 0; k < nrand; ++k) {
        const int64_t D[3] = {ct_rng_range(rng, -half, half), ct_rng_range(rng, -half, half),
                              ct_rng_range(rng, -half, half)};
        check(D);
    }
    // just outside the cube: no fitted image
    const int64_t Dout[3] = {half + 1, 0, 0};
    int64_t gout[3];
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_image24(&pk, &es, Dout, 1, gout));
    // beyond 2^50 nm on any axis: no image at all
    for (int k = 0; k < 3; ++k) {
        int64_t Dfar[3] = {0, 0, 0};
        Dfar[k] = -(INT64_C(1) << 50) - 1;
        TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_image24(&pk, &es, Dfar, 0, gout));
        TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_image24(&pk, &es, Dfar, 1, gout));
    }
    const double ex = std::max(err_exact[0], std::max(err_exact[1], err_exact[2]));
    TEST_ASSERT_MSG(ex <= kExactImageM, "exact image off PROJ by %.3g m (> %.3g m)", ex, kExactImageM);
    const double e = std::max(err[0], std::max(err[1], err[2]));
    std::printf("  camera %3.0Lf km east of the tile: range %.1f km, cube half-width 2^%u nm (%.1f km), degree %d "
                "(%d exact images): fit vs the reference max |dE| %.2g, |dN| %.2g, |dh| %.2g m; the exact image %.2g m "
                "(%d points beyond its range)\n",
                back_km, es.tmax_nm * 1e-12, es.fit.qrho, (double)half * 1e-12, es.fit.deg,
                (es.fit.deg + 1) * (es.fit.deg + 1) * (es.fit.deg + 1), err[0], err[1], err[2], ex, refused);
    *worst = std::max(*worst, e);
}

// Maps a kept map's users refuse: another package's, one never fitted, bad
// arguments to ct_earth_map_init (km fitted for pk, p a pose over it).
void check_kept_map_refusals(const ct_package &pk, const Pose &p, ct_earth_map *km)
{
    ct_effects fx = {CT_EFFECT_CURVATURE, 0, 0, 0, km};
    ct_geo g;
    Cam cam = make_camera();
    TEST_ASSERT(ct_geolocate(&pk, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &fx, 100 << 16, 100 << 16, &g) >= 0);
    ct_package other = pk;
    other.origin_e_nm += 1;
    TEST_ASSERT_EQUAL_INT(CT_ERR_EFFECTS,
                          ct_geolocate(&other, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &fx, 100 << 16, 100 << 16, &g));
    // ct_los refuses the same maps (its effects checked as ct_geolocate's)
    const int64_t la[3] = {p.pose.e_nm, p.pose.n_nm, p.pose.h_nm};
    const int64_t lb[3] = {201045000000000, 4065840000000000, 300000000000};
    ct_hit lh;
    TEST_ASSERT(ct_los(&pk, la, lb, &fx, 0, CT_METHOD_DIRECTIONAL, &lh) >= 0);
    TEST_ASSERT_EQUAL_INT(CT_ERR_EFFECTS, ct_los(&other, la, lb, &fx, 0, CT_METHOD_DIRECTIONAL, &lh));
    static ct_earth_map blank;
    fx.earth_map = &blank;
    TEST_ASSERT_EQUAL_INT(CT_ERR_EFFECTS,
                          ct_geolocate(&pk, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &fx, 100 << 16, 100 << 16, &g));
    TEST_ASSERT_EQUAL_INT(CT_ERR_EFFECTS, ct_los(&pk, la, lb, &fx, 0, CT_METHOD_DIRECTIONAL, &lh));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_map_init(&pk, 201045000000000, 4065840000000000, 0, 0, &blank));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_map_init(&pk, 201045000000000, 4065840000000000, 0,
                                                          (INT64_C(1) << 47) + 1, &blank));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_map_init(&pk, 201045000000000, 4065840000000000,
                                                          (INT64_C(1) << 50) + 1, INT64_C(1) << 44, &blank));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_map_init(&pk, 201045000000000, 4065840000000000,
                                                          -(INT64_C(1) << 50) - 1, INT64_C(1) << 44, &blank));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_map_init(&pk, 0, 0, 0, 1, nullptr));
    other = pk;
    other.epsg = 0;
    TEST_ASSERT_EQUAL_INT(CT_ERR_CRS, ct_earth_map_init(&other, 201045000000000, 4065840000000000, 0,
                                                        INT64_C(1) << 44, &blank));
    TEST_ASSERT(blank.ready != CT_EARTH_MAP_READY);
    // a georeference ct_package_frame accepts (heights offset -2^60 nm in
    // 1 um codes) whose grid cannot hold a point the projection takes: 500
    // m is (500 m + 2^60 nm) / 1 um codes from the offset, beyond
    // ct_map_to_grid's 2^62 Q16 (long double below): CT_ERR_RANGE
    {
        ct_package fr;
        const int64_t gr[6] = {pk.origin_e_nm, pk.origin_n_nm, pk.posting_e_nm, pk.posting_n_nm, -(INT64_C(1) << 60),
                               1000};
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_frame(&fr, pk.width, pk.height, 3u, 8u, 0, 100, gr, pk.epsg));
        TEST_ASSERT((500e9L + std::ldexp(1.0L, 60)) / 1000 * 65536 >= std::ldexp(1.0L, 62));
        TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_map_init(&fr, 201045000000000, 4065840000000000, 500000000000,
                                                              INT64_C(1) << 44, &blank));
        TEST_ASSERT(blank.ready != CT_EARTH_MAP_READY);
    }
}

// A map kept across calls (ct_earth_map_init): centred on the tile at 500 m,
// 70 km cube; checked through a camera 3 km up at the centre at nrand
// random points (its largest error joins *worst), then what refuses it.
void check_kept_map(World *w, ct_rng *rng, int nrand, double *worst)
{
    const ct_package &pk = w->p;
    static ct_earth_map km;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_map_init(&pk, INT64_C(201045) * 1000000000, INT64_C(4065840) * 1000000000,
                                                   INT64_C(500) * 1000000000, INT64_C(60000) * 1000000000, &km));
    TEST_ASSERT_EQUAL_INT(46, (int)km.qrho);
    TEST_ASSERT_EQUAL_INT(5, km.deg);
    Pose p;
    TEST_ASSERT(make_pose(w->sf, {"kept", 201045, 4065840, 3000, 0, -30}, &p));
    ct_earth es;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&pk, &p.pose, 0, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u, 0,
                                                &km, &es));
    TEST_ASSERT(es.map == &km);
    const int64_t half = INT64_C(1) << km.qrho;
    double err[3] = {0, 0, 0};
    for (int k = 0; k < nrand; ++k) {
        int64_t D[3], g[3];
        for (int a = 0; a < 3; ++a) D[a] = ct_rng_range(rng, -half, half) - es.moff[a];
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_image24(&pk, &es, D, 1, g));
        fit_error(pk, es, D, g, err);
    }
    std::printf("  kept map (ct_earth_map_init, centre of the tile, 2^%u nm, degree %d): fit vs the reference max "
                "|dE| %.2g, |dN| %.2g, |dh| %.2g m\n", km.qrho, km.deg, err[0], err[1], err[2]);
    *worst = std::max(*worst, std::max(err[0], std::max(err[1], err[2])));
    check_kept_map_refusals(pk, p, &km);
}

void test_fitted_map()
{
    World *w = jacksboro();
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 31 + 7);
    const int nrand = std::max(200, (int)std::lround(3000 * ct_test_scale()));
    uint32_t seen = 0;
    double worst = 0;
    for (ld back_km : {0.0L, 12.0L, 40.0L, 100.0L}) check_fit_for_camera(w, back_km, &rng, nrand, &seen, &worst);
    check_kept_map(w, &rng, nrand, &worst);
    TEST_ASSERT_MSG(seen == (1u << 44 % 32) + (1u << 45 % 32) + (1u << 46 % 32) + (1u << 47 % 32),
                    "the poses did not make every cube size (mask %x)", seen);
    TEST_ASSERT_MSG(worst <= kFitMaxM, "fitted map off PROJ by %.3g m (> %.3g m)", worst, kFitMaxM);
    // a camera too far for a fit keeps the exact map
    Pose far;
    TEST_ASSERT(make_pose(w->sf, {"far", 201045 + 130000, 4065840, 3000, 270, -10}, &far));
    ct_earth es;
    const ct_status st = ct_earth_setup(&w->p, &far.pose, 0, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u, 1, nullptr, &es);
    TEST_ASSERT(st != CT_OK || es.map == nullptr);
    if (st == CT_OK) {
        const int64_t D0[3] = {0, 0, 0};
        int64_t g0[3];
        TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_image24(&w->p, &es, D0, 1, g0));  // no fit to use
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_image24(&w->p, &es, D0, 0, g0));
    }
    // a kept map 1,600 km from the camera (over 2^50 nm on the polar axis:
    // its cube is of no use there): set aside, the exact conversions instead
    // -- the exact mode's results, bit for bit (the range capped at 2^48 nm,
    // 281 km: the tile is below the horizon, every pixel a miss)
    {
        static ct_earth_map km;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_map_init(&w->p, INT64_C(201045) * 1000000000,
                                                       INT64_C(4065840) * 1000000000, INT64_C(500) * 1000000000,
                                                       INT64_C(60000) * 1000000000, &km));
        Pose p;
        TEST_ASSERT(make_pose(w->sf, {"far", 201045, 4065840 - 1600000, 3000, 0, -10}, &p));
        ct_earth ek;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&w->p, &p.pose, 0, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u, 0,
                                                    &km, &ek));
        TEST_ASSERT(ek.map == nullptr);
        Cam cam = make_camera();
        ct_effects exact = {CT_EFFECT_CURVATURE, 0, 0, 0, nullptr}, kept = exact;
        kept.earth_map = &km;
        for (int k = 0; k < 8; ++k) {
            ct_geo a, b;
            const int64_t u = (int64_t)(64 + 128 * k) << 16, v = (int64_t)(100 + 80 * k) << 16;
            const ct_status sa = ct_geolocate(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &exact, u, v, &a);
            const ct_status sb = ct_geolocate(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &kept, u, v, &b);
            TEST_ASSERT_MSG(sa == CT_MISS && sa == sb && a.hit.e_nm == b.hit.e_nm && a.hit.n_nm == b.hit.n_nm &&
                                a.hit.h_nm == b.hit.h_nm && a.hit.steps == b.hit.steps,
                            "pixel %d: kept map far away %d, exact %d", k, sb, sa);
        }
    }
}

// *err: the largest distance (m, per axis) between a line of sight's
// interpolated path and the images it interpolates (the map's, or exact),
// every 1/1000 of its range, over azimuths az0, az0 + step, ... <= az1 and
// depressions 1, 4 and 12 deg; *nodes the last path's coefficient count.
void path_vs_images(const ct_package &pk, const ct_earth &es, int az0, int az1, int step, int32_t *nodes,
                    double *err)
{
    *err = 0;
    for (int az = az0; az <= az1; az += step) {
        for (int dep : {1, 4, 12}) {
            int64_t dg[3];
            grid_dir_q39(az, -dep, dg);
            for (int i = 0; i <= 1000; ++i) {
                const int64_t t = (int64_t)((ld)es.tmax_nm * i / 1000);
                int64_t gi[3], ge[3];
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_path_image24(&pk, &es, dg, t, 1, gi, nodes));
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_path_image24(&pk, &es, dg, t, 0, ge, nodes));
                const double ex = std::fabs((double)(gi[0] - ge[0])) * (double)pk.posting_e_nm * 1e-9 / 16777216.0;
                const double ey =
                    std::fabs((double)(gi[1] - ge[1])) * std::fabs((double)pk.posting_n_nm) * 1e-9 / 16777216.0;
                const double ez = std::fabs((double)(gi[2] - ge[2])) * (double)pk.height_scale_nm * 1e-9 / 16777216.0;
                *err = std::max(*err, std::max(ex, std::max(ey, ez)));
            }
        }
    }
}

// The interpolated path (earth.c: the image of a line of sight through its
// 4, 5 or 6 Chebyshev-Lobatto nodes, the camera's image node 0) against its
// images found as the nodes are, every 1/1000 of the range: cameras 0 to
// 120 km east of the tile (ranges of 10 to 140 km: every node count, and
// near the longest range of 4 and of 5 nodes, 35 and 130 km), lines of
// sight 1 to 12 deg down in azimuths from 200 to 340 deg,
// with refraction; a map kept for each camera (a 2^47 nm cube, degree 6,
// half-way to the tile: within 14 um of PROJ) so that both sides' images
// carry Q24 precision.  The promise (earth.c, docs/geolocation.md): within
// 0.02 mm.
void test_path_interpolation()
{
    World *w = jacksboro();
    const ct_package &pk = w->p;
    const double kInterpM = 2e-5;
    double worst = 0;
    uint32_t counts = 0;
    for (ld back_km : {0.0L, 24.0L, 40.0L, 111.0L, 120.0L}) {
        Pose p;
        TEST_ASSERT(make_pose(w->sf, {"far", 201045 + back_km * 1000, 4065840, 3000, 270, -10}, &p));
        static ct_earth_map km;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_map_init(&pk, std::llround((201045 + back_km * 500) * 1e9L),
                                                       INT64_C(4065840) * 1000000000, INT64_C(500) * 1000000000,
                                                       INT64_C(1) << 47, &km));
        ct_earth es;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&pk, &p.pose, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM,
                                                    CT_EFFECTS_CHORD_NM, 0u, 0, &km, &es));
        TEST_ASSERT(es.map == &km);
        int32_t nodes = 0;
        double err = 0;
        path_vs_images(pk, es, 200, 340, 35, &nodes, &err);
        counts |= 1u << nodes;
        std::printf("  camera %3.0Lf km east of the tile: range %.1f km, %d nodes: interpolated vs node images max %.4f "
                    "mm\n",
                    back_km, es.tmax_nm * 1e-12, (int)nodes, err * 1e3);
        worst = std::max(worst, err);
    }
    TEST_ASSERT_MSG(counts == (1u << 4) + (1u << 5) + (1u << 6), "the cameras did not make every node count (%x)",
                    counts);
    // the hook's refusals: each argument missing, t outside [0, tmax]
    {
        Pose p;
        TEST_ASSERT(make_pose(w->sf, {"far", 201045, 4065840, 3000, 270, -10}, &p));
        ct_earth es;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&pk, &p.pose, 0, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u, 1,
                                                    nullptr, &es));
        const int64_t dg[3] = {INT64_C(1) << 39, 0, 0};
        int64_t g[3];
        int32_t n;
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_path_image24(nullptr, &es, dg, 0, 1, g, &n));
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_path_image24(&pk, nullptr, dg, 0, 1, g, &n));
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_path_image24(&pk, &es, nullptr, 0, 1, g, &n));
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_path_image24(&pk, &es, dg, 0, 1, nullptr, &n));
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_path_image24(&pk, &es, dg, 0, 1, g, nullptr));
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_path_image24(&pk, &es, dg, -1, 1, g, &n));
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_path_image24(&pk, &es, dg, es.tmax_nm + 1, 1, g, &n));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_path_image24(&pk, &es, dg, es.tmax_nm, 1, g, &n));
    }
    TEST_ASSERT_MSG(worst <= kInterpM, "interpolated path off its node images by %.3g m (> %.3g m)", worst, kInterpM);
}

// A map fitted per call (CT_EFFECT_EARTH_FIT) gives the path's polynomial
// from the fit's own Taylor terms at the camera plus one image at the far
// end (up to 35 km) or two (to 130 km) -- earth.c taylor_nodes -- instead
// of the Lobatto nodes' three or four, when the fit's degree is 5 or less
// (its unused coefficients hold the terms); a fit of degree 4 (cubes of
// 2^44 nm) from its Taylor terms alone, up to the fourth power of the
// range, no image, where the bound of what that leaves out allows.  The
// same cameras as above (ranges 10-135 km), a fit per call each, with and
// without refraction, lines of sight in every direction the cameras see,
// against the fit's own images every 1/1000 of the range
// (ct_earth_path_image24 with interp = 0: the fit evaluated at the exact
// point C + t d - bend w): within 0.02 mm (the Lobatto nodes, which the
// degree-6 fits of the farthest cameras take, within 0.04 mm), and each
// regime taken (the Taylor terms alone and with one image: 5 coefficients
// up to 35 km; 6 beyond; the Lobatto nodes); a line whose image passes the
// polynomial's range has none (exact vertices).  Breaking a Taylor term (a
// cubic monomial's axis in taylor_nodes, or a quartic one's) fails it.
void test_taylor_path()
{
    World *w = jacksboro();
    const ct_package &pk = w->p;
    const double kInterpM = 2e-5, kLobattoM = 4e-5, kAloneM = 4.5e-6, kFarM = 6.3e-6;
    double worst = 0, worst_lobatto = 0, worst_alone = 0, worst_far = 0;
    uint32_t counts = 0;
    for (ld back_km : {0.0L, 24.0L, 40.0L, 111.0L, 116.0L}) {
        Pose p;
        TEST_ASSERT(make_pose(w->sf, {"far", 201045 + back_km * 1000, 4065840, 3000, 270, -10}, &p));
        for (int32_t k : {0, CT_REFRACTION_K_STD_Q16, -2 * CT_REFRACTION_K_STD_Q16, 16 * CT_REFRACTION_K_STD_Q16,
                          64 * CT_REFRACTION_K_STD_Q16}) {
            // k = 2.08 and 8.32 on the nearest camera: the Taylor terms
            // alone take the image there, at 2.08 as their bound of what
            // they leave out could reach 2 um, at 8.32 as refraction bends
            // the line more than 2^-9 of the cube's half-width; at 8.32 on
            // the camera 40 km east too, where the quartic term is then
            // not formed (two images)
            const bool strong = k >= 16 * CT_REFRACTION_K_STD_Q16;
            if (strong && back_km > 0 && !(back_km == 40 && k == 64 * CT_REFRACTION_K_STD_Q16)) continue;
            ct_earth es;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&pk, &p.pose, k, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u,
                                                        1, nullptr, &es));
            TEST_ASSERT(es.map == &es.fit);
            int32_t nodes = 0;
            double err = 0;
            path_vs_images(pk, es, 0, 315, 45, &nodes, &err);
            // the Taylor terms (a fit of degree <= 5, to 130 km): 5 or 6
            // coefficients, alone (+8: a fit of degree 4) where their bound
            // allows; else the Lobatto nodes: 4, 5 or 6
            const int64_t km = 1000000000000;
            const bool near = es.tmax_nm <= 35 * km, mid = es.tmax_nm <= 130 * km;
            const bool taylor = es.tay_ok != 0 && mid, alone = taylor && es.fit.deg == 4 && !strong;
            const int want = (taylor ? (near ? 5 : 6) : (near ? 4 : (mid ? 5 : 6))) + (alone ? 8 : 0);
            TEST_ASSERT_MSG(es.tay_ok == (es.fit.deg <= 5), "range %.1f km: Taylor terms %d, the fit's degree %d",
                            es.tmax_nm * 1e-12, (int)es.tay_ok, (int)es.fit.deg);
            TEST_ASSERT_MSG(nodes == want, "range %.1f km, k = %.2f: %d coefficients (+8: alone), not %d",
                            es.tmax_nm * 1e-12, k / 65536.0, (int)nodes, want);
            const int regime = alone ? 4 : (taylor ? want : 7);
            counts |= 1u << regime;
            std::printf("  camera %3.0Lf km east, k = %+.2f: range %.1f km, fit of degree %d, %d coefficients (%s): "
                        "path vs the fit's images max %.4f mm\n",
                        back_km, k / 65536.0, es.tmax_nm * 1e-12, (int)es.fit.deg, (int)nodes % 8,
                        alone ? "Taylor terms alone" : (taylor ? "Taylor terms and images" : "Lobatto nodes"),
                        err * 1e3);
            if (back_km > 100 && k == 0) {
                // a line 40 deg down over 130 km: its image passes 2^46 Q24
                // units (100 km horizontally at 30 m posts), beyond the
                // polynomial's range -- no polynomial (neither the Taylor
                // terms' nor the Lobatto nodes'), every vertex found as a
                // node is
                int64_t dg[3], g[3];
                grid_dir_q39(0, -40, dg);
                TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_path_image24(&pk, &es, dg, es.tmax_nm, 1, g, &nodes));
                TEST_ASSERT_EQUAL_INT(0, nodes);
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_path_image24(&pk, &es, dg, es.tmax_nm, 0, g, &nodes));
            }
            if (alone)
                worst_alone = std::max(worst_alone, err);
            else if (taylor && !near && !strong)
                worst_far = std::max(worst_far, err);
            else if (taylor)
                worst = std::max(worst, err);
            else
                worst_lobatto = std::max(worst_lobatto, err);
        }
    }
    TEST_ASSERT_MSG(counts == (1u << 4) + (1u << 5) + (1u << 6) + (1u << 7), "the cameras did not take every regime (%x)",
                    counts);
    TEST_ASSERT_MSG(worst <= kInterpM, "path off the fit's images by %.3g m (> %.3g m)", worst, kInterpM);
    // beyond 35 km (a fit of degree 5) the Taylor terms to the quartic and
    // one image: the fit along a straight line exactly (degree 5), with
    // refraction within nanometres, so at the images' rounding (3 Q24
    // units, 0.0054 mm); leaving out refraction's E_22 (0.0089 mm) or
    // E_31, or a quartic monomial's wrong axis or leading coefficient, fails
    TEST_ASSERT_MSG(worst_far <= kFarM, "path (Taylor terms to the quartic, one image) off the fit's images by %.3g m "
                    "(> %.3g m)", worst_far, kFarM);
    // the Taylor terms alone (a degree-4 fit) are the fit's restriction to
    // the path but for the rounding of the images compared (2 Q24 units,
    // 0.0036 mm) and what they leave out (nanometres at these k): leaving
    // out refraction's E_31 in the quartic term (0.0054 mm with k = -0.26)
    // or taking a quartic monomial's wrong axis (0.0125 mm) fails
    TEST_ASSERT_MSG(worst_alone <= kAloneM, "path (Taylor terms alone) off the fit's images by %.3g m (> %.3g m)",
                    worst_alone, kAloneM);
    // the Lobatto nodes at 130 km with k = -0.26 (refraction bending the
    // line up twice the standard amount) reach 0.03 mm
    TEST_ASSERT_MSG(worst_lobatto <= kLobattoM, "Lobatto path off the fit's images by %.3g m (> %.3g m)",
                    worst_lobatto, kLobattoM);
}

// Culling (earth.c piece_culled: a piece whose walk line is above the
// max-mipmap under it is not walked) changes no result: every pose of
// pose_defs(), 30 seeded lines of sight each with the exact map and 30 with
// a fitted one (the pose's own direction turned by up to 20 deg, with
// refraction), every method, traced with the culling and without it
// (CT_BEND_NO_CULL): the same status and hit, bit for bit; and some traces
// took fewer steps (a piece's walk culled), so the comparison means
// something.
void test_piece_culling()
{
    World *w = jacksboro();
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 71 + 3);
    long rays = 0, culled = 0, hits = 0;
    for (const PoseDef &d : pose_defs()) {
        Pose p;
        TEST_ASSERT_MSG(make_pose(w->sf, d, &p), "pose %s", d.family);
        for (int fitted = 0; fitted < 2; ++fitted) {
            ct_earth es[2];
            bool ok = true;
            for (int nc = 0; nc < 2; ++nc) {
                ok = ok && ct_earth_setup(&w->p, &p.pose, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM,
                                          CT_EFFECTS_CHORD_NM, nc ? CT_BEND_NO_CULL : 0u, fitted, nullptr,
                                          &es[nc]) == CT_OK;
            }
            TEST_ASSERT_MSG(ok, "pose %s: no set-up", d.family);
            for (int k = 0; k < 30; ++k) {
                const ld yaw = d.yaw + ct_rng_range(&rng, -20000, 20000) * 1e-3L;
                const ld pitch = std::max(-89.0L, d.pitch + ct_rng_range(&rng, -20000, 20000) * 1e-3L);
                int64_t dg[3];
                grid_dir_q39(yaw, pitch, dg);
                for (int m = 0; m < 4; ++m) {
                    ct_hit h[2];
                    ct_status st[2];
                    for (int nc = 0; nc < 2; ++nc) {
                        std::memset(&h[nc], 0, sizeof h[nc]);
                        st[nc] = ct_trace_earth_set(&w->p, nullptr, &es[nc], dg, (ct_method)m, &h[nc]);
                    }
                    const bool hit = st[0] == CT_HIT || st[0] == CT_HIT_VOID;
                    TEST_ASSERT_MSG(st[0] == st[1] && (!hit || (h[0].x_q16 == h[1].x_q16 && h[0].y_q16 == h[1].y_q16 &&
                                                                 h[0].z_q16 == h[1].z_q16 && h[0].t_q26 == h[1].t_q26 &&
                                                                 h[0].cell_x == h[1].cell_x &&
                                                                 h[0].cell_y == h[1].cell_y)),
                                    "pose %s, line %d, method %d: culled %d, not culled %d", d.family, k, m, (int)st[0],
                                    (int)st[1]);
                    rays++;
                    hits += hit;
                    culled += h[0].steps < h[1].steps;
                }
            }
        }
    }
    // lines of sight along each of the tile's four edges, a cell outside it
    // (the east-west ones drift 9 m south over the tile: the transverse
    // Mercator's image of a great circle), level 1 m over its lowest post:
    // pieces within 2 cells of the tile and below its tallest post (so not
    // off), whose own boxes miss it -- culled as such
    {
        const ct_package &pk = w->p;
        const ld pe = pk.posting_e_nm * 1e-9L, pn = pk.posting_n_nm * 1e-9L;
        const ld e0 = pk.origin_e_nm * 1e-9L, n0 = pk.origin_n_nm * 1e-9L;
        const ld e1 = e0 + pe * pk.cells_x, n1 = n0 + pn * pk.cells_y;
        const ld west = std::min(e0, e1) - 30, east = std::max(e0, e1) + 30;
        const ld south = std::min(n0, n1) - 30, north = std::max(n0, n1) + 30;
        const ld h = (pk.height_offset_nm + (int64_t)pk.hmin * pk.height_scale_nm) * 1e-9L + 1;
        const struct {
            ld e, n;
            int yaw;
        } edge[4] = {{west, south - 300, 0}, {east, south - 300, 0}, {west - 300, south, 90}, {west - 300, north, 90}};
        for (const auto &ed : edge) {
            int32_t q[4];
            ct_pose pose;
            TEST_ASSERT(ct_quat_from_ypr(q61(ed.yaw), 0, 0, q) == CT_OK);
            TEST_ASSERT(ct_pose_from_map(&pose, std::llround(ed.e * 1e9L), std::llround(ed.n * 1e9L),
                                         std::llround(h * 1e9L), q) == CT_OK);
            ct_earth es[2];
            for (int nc = 0; nc < 2; ++nc) {
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&pk, &pose, 0, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM,
                                                            nc ? CT_BEND_NO_CULL : 0u, 1, nullptr, &es[nc]));
            }
            int64_t dg[3];
            grid_dir_q39(ed.yaw, 0, dg);
            ct_hit h2[2];
            ct_status st[2];
            for (int nc = 0; nc < 2; ++nc) {
                st[nc] = ct_trace_earth_set(&pk, nullptr, &es[nc], dg, CT_METHOD_DIRECTIONAL, &h2[nc]);
            }
            TEST_ASSERT_MSG(st[0] == CT_MISS && st[1] == CT_MISS, "along an edge (yaw %d): %d, %d", ed.yaw, (int)st[0],
                            (int)st[1]);
            culled += h2[0].steps < h2[1].steps;
        }
    }
    std::printf("  %ld traces (%ld hits): the same with and without culling; %ld took fewer steps with it\n", rays, hits,
                culled);
    TEST_ASSERT_MSG(culled > rays / 20, "culling skipped too little to test (%ld of %ld traces)", culled, rays);
}

// The pieces' error bounds (earth.c side_rem, bound_vert) hold: for every
// pose of pose_defs() and a camera 5 m over the tile, with the exact and
// the fitted map, with and without refraction, 12 seeded lines of sight
// and one straight down, every piece whose errors were bounded (not
// sampled) is compared with the interpolated path at 49 points along it,
// in long double: the path's sideways distance from the shifted chord
// (Q24) within the piece's sideways bound, and its height less the walk's
// model there (the walk line's height at the point's range along it, plus
// the lowering at the point) within the height bound plus 1.25 times the
// largest of that difference at the piece's ends and middle (the bound
// leaves out the vertices' Q16 rounding: its interpolation at three
// equally spaced points is within 1.25 times its largest value).  And the
// sideways bound is tight (some piece's path comes within 10 % of it).
void test_piece_bounds()
{
    World *w = jacksboro();
    const ct_package &pk = w->p;
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 29 + 11);
    static ct_earth_piece pcs[2048];
    long lines = 0, pieces = 0, bounded = 0, sampled = 0, points = 0, over_tol = 0;
    double tight = 0, vratio = 0, worst_lat = 0, worst_v = 0;
    // and a camera 5 m over the middle of the tile, below its tallest post,
    // whose first piece starts at the camera however steep
    std::vector<PoseDef> defs = pose_defs();
    defs.push_back({"low", 201045, 4065840, 5, 0, -90});
    for (const PoseDef &d : defs) {
        Pose p;
        TEST_ASSERT_MSG(make_pose(w->sf, d, &p), "pose %s", d.family);
        for (int mode = 0; mode < 4; ++mode) {
            const int fitted = mode & 1;
            const int32_t k = (mode & 2) ? CT_REFRACTION_K_STD_Q16 : 0;
            ct_earth es;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&pk, &p.pose, k, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u,
                                                        fitted, nullptr, &es));
            for (int r = 0; r < 13; ++r) {
                const ld yaw = d.yaw + ct_rng_range(&rng, -20000, 20000) * 1e-3L;
                const ld pitch = std::max(-89.0L, std::min(-0.2L, d.pitch + ct_rng_range(&rng, -3000, 3000) * 1e-3L));
                int64_t dg[3];
                grid_dir_q39(yaw, pitch, dg);
                if (r == 12) {
                    // straight down the ellipsoid's normal: the camera's
                    // piece less than a Q16 unit long horizontally
                    dg[0] = dg[1] = 0;
                    dg[2] = -(INT64_C(1) << 39);
                }
                uint32_t n = 0;
                (void)ct_earth_pieces(&pk, &es, dg, pcs, 2048u, &n);
                lines++;
                TEST_ASSERT_MSG(n < 2048u, "pose %s: the log of pieces is full (%u)", d.family, n);
                for (uint32_t i = 0; i < n; ++i) {
                    const ct_earth_piece &e = pcs[i];
                    pieces++;
                    sampled += !e.off && !e.bounded;
                    if (e.off || !e.bounded) {
                        continue;
                    }
                    bounded++;
                    over_tol += e.elat_q24 > es.tol_q24 || e.evert_q16 > es.tolz_q16;
                    // the shifted chord in Q24: A's and B's images moved by the walk's shift
                    const ld ax = (ld)(e.a24[0] + e.shift_q24[0]), ay = (ld)(e.a24[1] + e.shift_q24[1]);
                    const ld ux = (ld)(e.b24[0] - e.a24[0]), uy = (ld)(e.b24[1] - e.a24[1]);
                    // the walk's ends within half a Q16 unit of the shifted chord's
                    TEST_ASSERT(std::fabs(e.walk_q16[0] * 256.0L - ax) <= 128 &&
                                std::fabs(e.walk_q16[1] * 256.0L - ay) <= 128 &&
                                std::fabs(e.walk_q16[3] * 256.0L - (e.b24[0] + e.shift_q24[0])) <= 128 &&
                                std::fabs(e.walk_q16[4] * 256.0L - (e.b24[1] + e.shift_q24[1])) <= 128);
                    const ld l24 = std::sqrt(ux * ux + uy * uy);
                    // the walk's model (Q16)
                    const ld wx = (ld)e.walk_q16[0], wy = (ld)e.walk_q16[1], wz = (ld)e.walk_q16[2];
                    const ld vx = (ld)e.walk_q16[3] - wx, vy = (ld)e.walk_q16[4] - wy, vz = (ld)e.walk_q16[5] - wz;
                    const ld l16 = std::sqrt(vx * vx + vy * vy);
                    const ld a = std::ldexp((ld)e.kf, -(int)e.kshift);
                    ld lat[49], dz[49];
                    for (int q = 0; q <= 48; ++q) {
                        const int64_t t = e.ta_nm + (int64_t)((ld)e.lc_nm * q / 48);
                        int64_t g[3];
                        int32_t nodes = 0;
                        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_path_image24(&pk, &es, dg, t, 1, g, &nodes));
                        lat[q] = std::fabs(ux * (g[1] - ay) - uy * (g[0] - ax)) / l24;
                        const ld px = g[0] / 256.0L, py = g[1] / 256.0L;
                        const ld sq = (vx * (px - wx) + vy * (py - wy)) / l16;
                        const ld zl = wz + vz * sq / l16 + a * ((px - wx) * (px - wx) + (py - wy) * (py - wy));
                        dz[q] = g[2] / 256.0L - zl;
                        points++;
                    }
                    const ld node = std::max(std::fabs(dz[0]), std::max(std::fabs(dz[24]), std::fabs(dz[48])));
                    ld mlat = 0, mv = 0;
                    for (int q = 0; q <= 48; ++q) {
                        mlat = std::max(mlat, lat[q]);
                        mv = std::max(mv, std::fabs(dz[q]) - 1.25L * node);
                        TEST_ASSERT_MSG(lat[q] <= e.elat_q24 + 2,
                                        "pose %s, piece %u at %d/48: %.1Lf Q24 sideways, bound %lld", d.family, i, q,
                                        lat[q], (long long)e.elat_q24);
                        TEST_ASSERT_MSG(std::fabs(dz[q]) <= e.evert_q16 + 1.25L * node + 1,
                                        "pose %s, piece %u at %d/48: %.2Lf Q16 in height (vertices %.2Lf), bound %lld",
                                        d.family, i, q, dz[q], node, (long long)e.evert_q16);
                    }
                    tight = std::max(tight, (double)(mlat / (ld)e.elat_q24));
                    vratio = std::max(vratio, (double)(mv / (ld)e.evert_q16));
                    worst_lat = std::max(worst_lat, (double)(mlat * pk.posting_e_nm * 1e-9L / 16777216.0L));
                    worst_v = std::max(worst_v, (double)(mv * pk.height_scale_nm * 1e-9L / 65536.0L));
                }
            }
        }
    }
    std::printf("  %ld lines of sight, %ld pieces (off the tile but %ld), %ld with bounded errors (%ld over the "
                "tolerance), %ld points: sideways up to %.4f mm (%.3f of its bound at most), in height beyond "
                "1.25 x the vertices' rounding up to %.4f mm (%.3f of its bound)\n",
                lines, pieces, bounded + sampled, bounded, over_tol, points, worst_lat * 1e3, tight, worst_v * 1e3,
                vratio);
    TEST_ASSERT_MSG(bounded > 500, "too few bounded pieces (%ld)", bounded);
    TEST_ASSERT_MSG(over_tol == 0, "%ld pieces over their tolerance were logged (never traced)", over_tol);
    // the hook's refusals, and its cap: the first pieces only, the walk's status
    {
        Pose p;
        TEST_ASSERT(make_pose(w->sf, pose_defs()[0], &p));
        ct_earth es;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&pk, &p.pose, 0, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u, 1,
                                                    nullptr, &es));
        int64_t dg[3];
        grid_dir_q39(30, -45, dg);
        uint32_t n = 0, n1 = 0;
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_pieces(nullptr, &es, dg, pcs, 2048u, &n));
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_pieces(&pk, nullptr, dg, pcs, 2048u, &n));
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_pieces(&pk, &es, nullptr, pcs, 2048u, &n));
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_pieces(&pk, &es, dg, nullptr, 2048u, &n));
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_earth_pieces(&pk, &es, dg, pcs, 2048u, nullptr));
        const ct_status st = ct_earth_pieces(&pk, &es, dg, pcs, 2048u, &n);
        const ct_earth_piece first = pcs[0];
        TEST_ASSERT_EQUAL_INT(st, ct_earth_pieces(&pk, &es, dg, pcs, 1u, &n1));
        TEST_ASSERT_MSG(n > 1 && n1 == 1 && pcs[0].lc_nm == first.lc_nm && pcs[0].elat_q24 == first.elat_q24,
                        "capped log: %u of %u pieces (status %d)", n1, n, (int)st);
    }
    TEST_ASSERT_MSG(tight > 0.9, "the sideways bound is loose: the path came within %.3f of it at most", tight);
}

// Regression: a 3 x 3 km tile (gentle hills) whose west edge lies 1 km
// inside the projection's domain (9 deg west of zone 17's meridian),
// cameras 0.5, 3 and 17 km east of it looking west 3 deg down: the lines of
// sight leave the domain soon after the tile (within tmax).  Every pixel's
// status and hit agree with the PROJ reference (which has no such domain):
// curvature, with refraction, and with the map fitted (its cube crosses
// the edge: the exact map instead).  A piece reaching past the edge was a
// miss, though the tile lay on it: 276 hits of 3,199 pixels were missed.
// The easting of zone 17's western edge (longitude -90 deg) at northing
// 4,064.5 km, by bisection through PROJ's inverse.
ld zone17_west_edge(earth_ref::Proj &pj)
{
    ld lo = -400000, hi = -200000, lat, lon;
    for (int k = 0; k < 60; ++k) {
        const ld mid = (lo + hi) / 2;
        pj.utm_inverse(mid, 4064500, &lat, &lon);
        (lon < -90 ? lo : hi) = mid;
    }
    return lo;
}

void test_zone_edge()
{
    earth_ref::Proj &pj = proj();
    const ld Eedge = zone17_west_edge(pj);
    static World *w = nullptr;
    if (!w) {
        w = new World;
        Georef g = jacksboro()->dem.geo;
        g.origin_e = std::floor(Eedge) + 1000;
        g.origin_n = 4066000;
        const int n = 101;
        std::vector<double> h((size_t)n * n);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) h[(size_t)j * n + i] = 400.0 + 30 * std::sin(i * 0.2) * std::cos(j * 0.15);
        std::vector<uint8_t> valid((size_t)n * n, 1);
        w->t = terrain_from_heights(n, n, h, valid, g, 0.015625);
        BuildOptions o;
        o.sectors = 8;
        o.reduce = 2;
        w->bytes = build_package(w->t, o);
        TEST_ASSERT(ct_package_open(&w->p, w->bytes.data(), w->bytes.size()) == CT_OK);
        w->sf = earth_ref::Surface::from_package(w->p);
    }
    Cam cam = make_camera();
    const ld E0 = w->p.origin_e_nm * 1e-9L, N0 = w->p.origin_n_nm * 1e-9L;
    long n = 0, agree = 0, hits = 0;
    double worst = 0;
    // a kept map over the tile: its cube (17.6 km) reaches past the edge,
    // where the projection cannot take it: CT_ERR_RANGE (conetrace.h)
    static ct_earth_map km;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_map_init(&w->p, w->p.origin_e_nm + INT64_C(1500000000000),
                                                          w->p.origin_n_nm - INT64_C(1500000000000),
                                                          INT64_C(400000000000), INT64_C(1) << 44, &km));
    for (ld back : {17000.0L, 3000.0L, 500.0L})
        for (int mode = 0; mode < 3; ++mode) {  // curvature; with refraction; with refraction, the map fitted
            Pose p;
            TEST_ASSERT(make_pose(w->sf, {"edge", E0 + 3000 + back, N0 - 1500, 600, 270, -3.0L}, &p));
            ct_effects fx = {CT_EFFECT_CURVATURE | (mode ? CT_EFFECT_REFRACTION : 0u) | (mode == 2 ? CT_EFFECT_EARTH_FIT : 0u),
                             CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
            for (int iv = 300; iv < 500; iv += 3)
                for (int iu = 0; iu < 1024; iu += 128) {
                    const int64_t u = (int64_t)iu << 16, v = (int64_t)iv << 16;
                    ld ray[3];
                    earth_ref::pinhole_ray(cam.fx, cam.fy, cam.cx, cam.cy, (ld)u / 65536, (ld)v / 65536, ray);
                    const earth_ref::Los L = earth_ref::los_from_pose(pj, p.pose, ray, &fx);
                    earth_ref::Result r = earth_ref::trace(pj, w->sf, L);
                    if (r.min_clear < kSkipClearM) continue;
                    ct_geo g;
                    const ct_status st = ct_geolocate(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &fx, u, v, &g);
                    n++;
                    const int ls = st == CT_HIT_VOID ? CT_HIT : st;
                    if (ls != r.status) {
                        if (n - agree < 5)
                            std::printf("    zone edge: %.0Lf m back, px (%d, %d): library %d, reference %d (E %.1Lf, %.1Lf m "
                                        "inside the domain)\n", back, iu, iv, st, r.status, r.e, r.e - Eedge);
                        continue;
                    }
                    agree++;
                    if (ls == CT_HIT) {
                        hits++;
                        worst = std::max(worst, (double)dist3(g.hit.e_nm * 1e-9L, g.hit.n_nm * 1e-9L, g.hit.h_nm * 1e-9L,
                                                              r.e, r.n, r.h));
                    }
                }
        }
    std::printf("  zone edge (tile 1 km inside 9 deg): %ld pixels, %ld agree with the reference (%ld hits, within %.4f m)\n",
                n, agree, hits, worst);
    TEST_ASSERT(agree == n && hits > 100 && worst <= kMaxErrM);
}

// ---------------------------------------------------------------------------
// The projection's domain and extreme packages.

// A synthetic package on EPSG epsg: nx x ny posts `post` m apart from the
// corner (oe, on) (north-west, rows southwards), heights h(i, j) (m) coded
// in `scale` m.
template <class F>
World *synthetic(int epsg, ld oe, ld on, double post, int nx, int ny, F h, double scale)
{
    World *w = new World;
    Georef g;
    g.origin_e = (double)oe;
    g.origin_n = (double)on;
    g.posting_e = post;
    g.posting_n = -post;
    g.epsg = epsg;
    std::vector<double> hv((size_t)nx * ny);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) hv[(size_t)j * nx + i] = h(i, j);
    std::vector<uint8_t> valid((size_t)nx * ny, 1);
    w->t = terrain_from_heights(nx, ny, hv, valid, g, scale);
    BuildOptions o;
    o.sectors = 8;
    o.reduce = 2;
    w->bytes = build_package(w->t, o);
    if (ct_package_open(&w->p, w->bytes.data(), w->bytes.size()) != CT_OK) std::abort();
    w->sf = earth_ref::Surface::from_package(w->p);
    return w;
}

// A pose at map point (E, N) of zone z, ellipsoidal height h (m), yaw and
// pitch (deg) w.r.t. north-east-down.
bool pose_at(earth_ref::Proj &pj, const ct_utm &z, ld E, ld N, ld h, ld yaw, ld pitch, Pose *out)
{
    ld lat, lon;
    pj.utm_inverse(E, N, &lat, &lon);
    out->def = {"domain", E, N, 0, yaw, pitch};
    const int64_t la = q61(lat), lo = q61(lon), h_nm = std::llround(h * 1e9L);
    out->lat = deg_of_q61(la);
    out->lon = deg_of_q61(lo);
    out->h = (ld)h_nm * 1e-9L;
    if (ct_quat_from_ypr(q61(yaw > 180 ? yaw - 360 : yaw), q61(pitch), 0, out->q) != CT_OK) return false;
    return ct_pose_from_wgs84(&out->pose, &z, la, lo, h_nm, out->q) == CT_OK;
}

// The first range t (m) in [0, t_end] where the reference path is outside
// the projection's domain (|lat| > 84.5 deg, or more than 9 deg from the
// zone's meridian lon0): sampled every `step` m, then bisected to 1 mm;
// +inf when every sample is inside.
ld domain_exit(const earth_ref::Los &L, ld lon0_deg, ld t_end, ld step)
{
    auto outside = [&](ld t) {
        ld P[3], la, lo, hh;
        L.at(t, P);
        earth_ref::geodetic_ld(P, &la, &lo, &hh);
        ld dl = lo * 180 / kPi - lon0_deg;
        dl -= 360 * std::floor((dl + 180) / 360);
        return std::fabs(la * 180 / kPi) > 84.5L || std::fabs(dl) > 9;
    };
    for (ld t = 0; t <= t_end + step; t += step) {
        if (!outside(t)) continue;
        ld a = std::max<ld>(0, t - step), b = t;
        while (b - a > 1e-3L) (outside((a + b) / 2) ? b : a) = (a + b) / 2;
        return b;
    }
    return std::numeric_limits<ld>::infinity();
}

// Pixels judged against the reference where lines of sight leave the
// projection's domain: a library hit must be the reference's; a library
// miss where the reference hits only when the reference path left the
// domain before its hit, or within 25 m after (the pieces stop up to 20 m
// short of the edge: next_piece, docs/geolocation.md).
struct DomainTally {
    long n = 0, hits = 0, misses = 0, domain_miss = 0, bad = 0;
    double worst = 0;
};

void judge_domain(World *w, earth_ref::Proj &pj, ld lon0, const Cam &cam, const Pose &p, const ct_effects &fx,
                  int64_t u, int64_t v, DomainTally &T, ld skip_clear = kSkipClearM)
{
    ld ray[3];
    earth_ref::pinhole_ray(cam.fx, cam.fy, cam.cx, cam.cy, (ld)u / 65536, (ld)v / 65536, ray);
    const earth_ref::Los L = earth_ref::los_from_pose(pj, p.pose, ray, &fx);
    const earth_ref::Result r = earth_ref::trace(pj, w->sf, L);
    if (r.min_clear < skip_clear) return;
    ct_geo g;
    const ct_status st = ct_geolocate(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &fx, u, v, &g);
    const int ls = st == CT_HIT_VOID ? CT_HIT : st;
    T.n++;
    const char *why = nullptr;
    if (ls == CT_HIT && r.status == CT_HIT) {
        const double d = (double)dist3(g.hit.e_nm * 1e-9L, g.hit.n_nm * 1e-9L, g.hit.h_nm * 1e-9L, r.e, r.n, r.h);
        T.worst = std::max(T.worst, d);
        T.hits++;
        if (d > kMaxErrM) why = "hit off the reference's";
    } else if (ls == CT_MISS && r.status == CT_MISS) {
        T.misses++;
    } else if (ls == CT_MISS && r.status == CT_HIT) {
        if (domain_exit(L, lon0, r.t + 25, 0.5L) <= r.t + 25) {
            T.domain_miss++;
        } else {
            why = "a miss inside the domain";
        }
    } else if (!(r.wall && ls == CT_BELOW)) {
        why = "status differs";
    }
    if (why) {
        T.bad++;
        if (T.bad <= 5)
            std::printf("    px (%.3f, %.3f): %s: library %d (%.3f %.3f %.3f), reference %d (%.3Lf %.3Lf %.3Lf, t %.1Lf m)\n",
                        u / 65536.0, v / 65536.0, why, st, g.hit.e_nm * 1e-9, g.hit.n_nm * 1e-9, g.hit.h_nm * 1e-9,
                        r.status, r.e, r.n, r.h, r.t);
    }
}

// A 3 x 3 km tile (gentle hills) reaching 1 km past the projection's 9 deg
// edge (zone 17, west), cameras 0.5, 3 and 17 km east of it looking west
// 3 deg down: lines of sight pass over the tile into the region the
// projection cannot take (PROJ, the reference, can): the pieces shrink to
// 20 m at the edge and the path is a miss there (next_piece), every hit
// before it as the reference's.
void test_zone_edge_straddle()
{
    earth_ref::Proj &pj = proj();
    const ld lo = zone17_west_edge(pj);
    static World *w = nullptr;
    if (!w)
        w = synthetic(32617, std::floor(lo) - 1000, 4066000, 30.0, 101, 101,
                      [](int i, int j) { return 400.0 + 30 * std::sin(i * 0.2) * std::cos(j * 0.15); }, 0.015625);
    Cam cam = make_camera();
    const ct_utm z = {17, 0};
    const ld E0 = w->p.origin_e_nm * 1e-9L, N0 = w->p.origin_n_nm * 1e-9L;
    DomainTally T;
    for (ld back : {17000.0L, 3000.0L, 500.0L})
        for (int mode = 0; mode < 2; ++mode) {
            Pose p;
            TEST_ASSERT(pose_at(pj, z, E0 + 3000 + back, N0 - 1500, 1000, 270, -3.0L, &p));
            ct_effects fx = {CT_EFFECT_CURVATURE | (mode ? CT_EFFECT_REFRACTION : 0u), CT_REFRACTION_K_STD_Q16, 0, 0,
                             nullptr};
            for (int iv = 300; iv < 560; iv += 5)
                for (int iu = 0; iu < 1024; iu += 128)
                    judge_domain(w, pj, -81, cam, p, fx, (int64_t)iu << 16, (int64_t)iv << 16, T);
        }
    std::printf("  tile across the zone's 9 deg edge: %ld pixels, %ld hits as the reference's (within %.4f m), %ld "
                "misses as its, %ld misses where the path leaves the domain before its hit; %ld wrong\n",
                T.n, T.hits, T.worst, T.misses, T.domain_miss, T.bad);
    TEST_ASSERT(T.bad == 0 && T.hits > 100 && T.domain_miss > 50);
}

// A 3 x 3 km tile across the 84.5 deg limit of latitude (zone 33, on its
// meridian), cameras west of it looking east along the limit and south of
// it looking north, 60 m over the terrain.  In the map the limit is a
// circle around the pole (611 km), so an eastward line of sight cuts a
// chord of it: its ends inside the domain, its middle or quarter points
// beyond (next_piece, check_piece).  Every library hit is the reference's,
// every miss either the reference's or one past the limit.
void test_latitude_limit()
{
    static earth_ref::Proj *pjp = new earth_ref::Proj(32633);
    earth_ref::Proj &pj = *pjp;
    ld El, Nl;
    pj.utm(84.5L, 15, &El, &Nl);
    static World *w = nullptr;
    if (!w)
        w = synthetic(32633, 500000 - 1500, std::floor(Nl) + 1500, 30.0, 101, 101,
                      [](int i, int j) { return 400.0 + 20 * std::sin(i * 0.3) * std::cos(j * 0.2); }, 0.015625);
    Cam cam = make_camera();
    const ct_utm z = {33, 0};
    DomainTally T;
    for (int mode = 0; mode < 2; ++mode) {
        ct_effects fx = {CT_EFFECT_CURVATURE | (mode ? CT_EFFECT_REFRACTION : 0u), CT_REFRACTION_K_STD_Q16, 0, 0,
                         nullptr};
        // east, beta north of grid east from (E, Nl + dn): the northing
        // Nl + dn + beta (x - x0) (x = E - 500 km) against the limit's Nl +
        // x^2 / 2 rho (rho = 611 km) peaks at xp = beta rho, by dn - beta x0
        // + rho beta^2 / 2: a chord of the polar cap centred at xp, about
        // sqrt(2 rho excess) either side, somewhere along the first pieces
        const ld rho = 611000, x0 = -5000;
        for (int kb = 0; kb <= 80; ++kb) {
            const ld xp = -3000 + 50 * kb, beta = xp / rho, excess = kb % 2 ? 0.1L : 0.4L;
            const ld dn = excess + beta * x0 - rho * beta * beta / 2;
            ld la, lo;
            pj.utm_inverse(500000 + x0, Nl + dn, &la, &lo);
            const ld yaw = 90 - std::atan(beta) * 180 / kPi + pj.convergence(la, lo) * 180 / kPi;
            Pose p;
            TEST_ASSERT(pose_at(pj, z, 500000 + x0, Nl + dn, 480, yaw, -0.5L, &p));
            for (int iv = 364; iv < 404; iv += 8)
                judge_domain(w, pj, 15, cam, p, fx, (int64_t)1023 << 15, (int64_t)iv << 16, T);
        }
        Pose p;
        TEST_ASSERT(pose_at(pj, z, 500000, Nl - 5000, 480, 0, -0.5L, &p));
        for (int iv = 370; iv < 400; iv += 3)
            for (int iu = 0; iu < 1024; iu += 64) judge_domain(w, pj, 15, cam, p, fx, (int64_t)iu << 16, (int64_t)iv << 16, T);
    }
    std::printf("  tile across the 84.5 deg limit: %ld pixels, %ld hits as the reference's (within %.4f m), %ld "
                "misses as its, %ld misses where the path leaves the domain before its hit; %ld wrong\n",
                T.n, T.hits, T.worst, T.misses, T.domain_miss, T.bad);
    TEST_ASSERT(T.bad == 0 && T.hits > 100 && T.domain_miss > 50);
}

// A pose looking (yaw, pitch) from h (m) whose centre pixel's reference
// path meets height hz at map point (Et, Nt): the camera's place moved by
// the miss, three times.
Pose aim_at(earth_ref::Proj &pj, const ct_utm &z, const ct_effects &fx, ld Et, ld Nt, ld hz, ld back_e, ld back_n,
            ld h, ld yaw, ld pitch)
{
    ld ce = Et - back_e, cn = Nt - back_n;
    Pose p;
    for (int it = 0; it < 3; ++it) {
        if (!pose_at(pj, z, ce, cn, h, yaw, pitch, &p)) std::abort();
        const ld ray[3] = {0, 0, 1};
        const earth_ref::Los L = earth_ref::los_from_pose(pj, p.pose, ray, &fx);
        ld a = 0, b = 2 * (h - hz) + 2 * std::hypot(back_e, back_n);
        for (int k = 0; k < 100; ++k) {
            ld P[3], la, lo, hh;
            L.at((a + b) / 2, P);
            earth_ref::geodetic_ld(P, &la, &lo, &hh);
            (hh > hz ? a : b) = (a + b) / 2;
        }
        ld P[3], E, N, hh;
        L.at(a, P);
        pj.map(P, &E, &N, &hh);
        ce += Et - E;
        cn += Nt - N;
    }
    return p;
}

// A 20 x 20 cm tile of 1 mm posts (201 x 201, a plane rising 4 and 2 cm across it) in zone
// 17: cameras 60 km west and south of it, 60 km up, looking at it 45 deg
// down: the path's interpolation nodes lie over 2^22 cells apart (the
// vertices are then exact: set_nodes) and the pieces off the tile grow
// past 2^24 cells (beyond the vertical fit's range: fit_piece); and a
// wavy tile of 1 mm posts (1 cm waves) seen by a camera 5 km over it
// looking 1.5 mrad off the vertical with the strongest refraction, k = 2:
// under the textbook curvature k cos(elev) / R the path's horizontal image
// keeps going (a constant curvature k / R would turn it back 4.8 km along
// the line, where earth.c's gone() takes a path off the tile and moving
// away as gone for good).  Every status and hit as the reference's.
void test_tiny_posting()
{
    earth_ref::Proj &pj = proj();
    static World *w = nullptr;
    if (!w)
        w = synthetic(32617, 201045, 4065840, 0.001, 201, 201,
                      [](int i, int j) { return 400.0 + 0.0002 * i + 0.0001 * j; }, 0.0009765625);
    Cam cam = make_camera();
    const ct_utm z = {17, 0};
    const ld Ec = 201045.1L, Nc = 4065840 - 0.1L;
    const int64_t u0 = (int64_t)1023 << 15, v0 = (int64_t)767 << 15;
    DomainTally T;
    // (and with the map fitted per call from 20 km: a cube of 35 km, whose
    // fit has the Taylor terms, but the lines' images pass the path
    // polynomial's range, 2^46 Q24 units, at 1 mm posts -- neither the
    // Taylor terms nor the Lobatto nodes, every vertex by the fit; and from
    // 10 km: a cube of 17.6 km, whose degree-4 fit's quartic and cubic
    // terms are, at 1 mm posts, within a factor 2 of taylor_alone's 64-bit
    // range)
    for (int fit = 0; fit < 3; ++fit)
        for (int side = 0; side < 2; ++side) {
            const int mode = side;  // west: curvature; south: with refraction
            const ct_effects fx = {CT_EFFECT_CURVATURE | (mode ? CT_EFFECT_REFRACTION : 0u) |
                                       (fit ? CT_EFFECT_EARTH_FIT : 0u),
                                   CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
            const ld d = fit == 2 ? 10000 : (fit ? 20000 : 60000);
            const Pose p = aim_at(pj, z, fx, Ec, Nc, 400, side ? 0 : d, side ? d : 0, d + 400, side ? 0 : 90, -45);
            for (int iv = -1; iv <= 1; ++iv)
                for (int iu = -1; iu <= 1; ++iu) judge_domain(w, pj, -81, cam, p, fx, u0 + iu * 40, v0 + iv * 40, T, 0);
        }
    std::printf("  1 mm posts, cameras 60 km away (exact map), 20 km and 10 km (fitted): %ld pixels, %ld hits as the "
                "reference's (within %.5f m), %ld misses as its; %ld wrong\n",
                T.n, T.hits, T.worst, T.misses, T.bad);
    TEST_ASSERT(T.bad == 0 && T.domain_miss == 0 && T.hits >= 36 && T.n == 54);
    static World *wavy = nullptr;
    if (!wavy)
        wavy = synthetic(32617, 201045, 4065840, 0.001, 201, 201,
                         [](int i, int j) { return 400.0 + 0.01 * std::sin(0.02 * i) * std::cos(0.015 * j); },
                         0.0009765625);
    const ct_effects k2 = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, 2 * 65536, 0, 0, nullptr};
    // 1.5 mrad off the vertical, north: 7.5 m south of the tile's centre
    const Pose ps = aim_at(pj, z, k2, Ec, Nc, 400, 0, 7.5L, 5400, 0, -(90 - 0.0859436693L));
    DomainTally S;
    // the tile is 0.056 px wide from 5 km: offsets of 1/328 px around the centre
    for (int iv = -10; iv < 10; ++iv)
        for (int iu = -10; iu < 11; ++iu) judge_domain(wavy, pj, -81, cam, ps, k2, u0 + iu * 200, v0 + iv * 200, S, 0);
    std::printf("  1 mm posts, 5 km below a camera 1.5 mrad off the vertical, k = 2: %ld pixels, %ld hits as the "
                "reference's (within %.5f m), %ld misses as its; %ld wrong\n",
                S.n, S.hits, S.worst, S.misses, S.bad);
    TEST_ASSERT(S.bad == 0 && S.domain_miss == 0 && S.hits >= 300 && S.n == 420);
}

// Height codes of 100 nm (a tile of 1 m posts with 2 mm of relief, the
// camera 1 m over it, within CT_MAX_ORIGIN_Q16 = 2^30 codes of the offset):
// the lines of sight below the horizon hit the ground metres away, those
// above it miss; with a chord tolerance of 100 m (pieces as long as the
// path's 1.1 km) the ones rising over 23 deg climb 2^32 codes (430 m)
// within their first piece, over 60 deg by its middle, beyond the
// vertical fit's range (fit_piece shortens the piece).  Every status and hit as the reference's.
void test_tiny_height_scale()
{
    earth_ref::Proj &pj = proj();
    static World *w = nullptr;
    if (!w)
        w = synthetic(32617, 201045, 4065840, 1.0, 101, 101,
                      [](int i, int j) { return 400.0 + 0.002 * std::sin(0.3 * i) * std::cos(0.2 * j); }, 1e-7);
    TEST_ASSERT(w->p.height_scale_nm == 100);
    Cam cam = make_camera();
    const ct_utm z = {17, 0};
    DomainTally T;
    for (int refr = 0; refr < 2; ++refr) {
        const ct_effects fx = {CT_EFFECT_CURVATURE | (refr ? CT_EFFECT_REFRACTION : 0u), CT_REFRACTION_K_STD_Q16, 0,
                               0, nullptr};
        Pose p;
        TEST_ASSERT(pose_at(pj, z, 201045 + 50.3L, 4065840 - 50.7L, 401, 45 + 90 * refr, 0, &p));
        for (int iv = 0; iv < 768; iv += 48)
            for (int iu = 0; iu < 1024; iu += 128)
                judge_domain(w, pj, -81, cam, p, fx, (int64_t)iu << 16, (int64_t)iv << 16, T, 0);
        // the path ends 1.1 km out (tmax: the farthest tile corner, plus
        // 10 % and 1 km): looking 50 deg up, rows rising 35-65 deg (over
        // 60 deg the piece's middle, too, is 430 m up)
        ct_effects loose = fx;
        loose.chord_nm = INT64_C(100000000000);  // 100 m
        Pose up;
        TEST_ASSERT(pose_at(pj, z, 201045 + 50.3L, 4065840 - 50.7L, 401, 45 + 90 * refr, 50, &up));
        for (int iv = 0; iv < 768; iv += 64)
            for (int iu = 0; iu < 1024; iu += 256)
                judge_domain(w, pj, -81, cam, up, loose, (int64_t)iu << 16, (int64_t)iv << 16, T, 0);
    }
    std::printf("  100 nm height codes, a camera 1 m up: %ld pixels, %ld hits as the reference's (within %.5f m), %ld "
                "misses as its; %ld wrong\n", T.n, T.hits, T.worst, T.misses, T.bad);
    TEST_ASSERT(T.bad == 0 && T.domain_miss == 0 && T.hits >= 50 && T.misses >= 50);
}

// A line of sight whose 16 km piece's fitted vertical quadratic rises by
// less than 2^-96 Q16 height units per squared Q16 cell: earth.c's
// rise_coeff refuses it (check_piece) and the piece is traced as its
// straight chord.  A 1 x 1 m tile of 5 mm posts (201 x 201) in zone 17 at
// 36.7 deg N, 13.9 km west of the central meridian, flat but for a step of
// one height code (0.65536 m: a Q16 height unit of 10 um) over its eastern
// half; a map pose 26 km west of the tile's centre (every input an
// integer), 0.3 m over the lower half, looking grid east, level, with
// refraction k = 65381 / 65536: the path bends with the 6371 km sphere
// widened by 1 / k to 6386.1 km, about the ellipsoid's radius in that
// azimuth (the prime vertical's, 6385.8 km; k found by a search: the
// rounded heights along the piece then stay within a unit of a straight
// line).  The path's image spans 27 km of x between its first and last
// interpolation nodes (tmax 29.6 km), over 2^22 cells: its vertices are
// computed exactly (set_nodes) and -- path_span trims only interpolated
// paths -- its pieces start from the camera and double off the tile: 4 km,
// 8 km, then 12 .. 28 km over the tile: l = 2^37.6 Q16, den = sm l (l - sm)
// = 2^110.8.  (An interpolated path cannot take the branch: its nodes lie
// within 2^22 cells of each other on each axis, and a level line of
// sight's higher terms are a few 10^-5 of that -- E = 83 cells measured 300
// km from the meridian, 18 km out --, so its pieces, within the tile
// widened by 2 cells and E, span under 2^15.1 cells an axis: den < 2^93,
// where a refusal needs 2^97.)  The middle lies 11 .. 24 Q16 units beyond
// the chord's half (2 sm - l = 22 .. 47): along the refracted path the
// parameter's speed grows as t / R^2, which alone would put it 206,000
// units short for this piece, and the point scale's fall towards the
// meridian takes that back (the piece's middle 20 km west of it; 2 sm - l
// about 21 units less per metre east).  The rows 4 .. 20 units (of 1/65536 px) above the centre
// climb 9 height units more each to the piece's middle; for 10 of the 17
// the rounded heights rise by exactly zm and 2 zm to the middle and the
// end (zm = 13 .. 152), so num = zb sm - zm l = zm (2 sm - l) = 312 ..
// 7,144 (measured with a probe in earth.c) and num / den < 2^-96 (for the
// others zb - 2 zm = +-1: a rise rise_coeff takes, or a negative one).
// Every row hits the step's face (2.3 mm east of the tile's centre, 0.3 m
// up) where the reference does.
void test_level_rise_refused()
{
    earth_ref::Proj &pj = proj();
    static World *w = nullptr;
    if (!w)
        w = synthetic(32617, 486103 - 0.5025L, 4068000 + 0.5025L, 0.005, 201, 201,
                      [](int i, int) { return i > 100 ? 400.65536 : 400.0; }, 0.65536);
    TEST_ASSERT(w->p.height_scale_nm == 655360000 && w->p.posting_e_nm == 5000000 && w->p.hmax == 1);
    Cam cam = make_camera();
    Pose p;
    p.def = {"level", 460103, 4068000, 0, 90, 0};
    const int64_t yaw90_q61 = INT64_C(3622009729038561421);  // 90 deg
    TEST_ASSERT(ct_quat_from_ypr(yaw90_q61, 0, 0, p.q) == CT_OK);
    TEST_ASSERT(ct_pose_from_map(&p.pose, INT64_C(460103000000000), INT64_C(4068000000000000), INT64_C(400300000000),
                                 p.q) == CT_OK);
    const ct_effects fx = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, 65381, 0, 0, nullptr};
    const int64_t u0 = (int64_t)1023 << 15, v0 = (int64_t)767 << 15;
    // the premise: the path is not interpolated (its nodes span over 2^22
    // cells), so its pieces start at the camera: 4, 8, then 16 km
    {
        ct_earth es;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&w->p, &p.pose, fx.refraction_k_q16, CT_EARTH_RADIUS_NM,
                                                    CT_EFFECTS_CHORD_NM, 0u, 0, nullptr, &es));
        const int64_t east[3] = {INT64_C(1) << 39, 0, 0};
        int64_t g[3];
        int32_t nodes = -1;
        TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_earth_path_image24(&w->p, &es, east, 0, 1, g, &nodes));
        TEST_ASSERT_EQUAL_INT(0, nodes);
        TEST_ASSERT(es.tmax_nm >= INT64_C(28000) * 1000000000);  // the third piece whole: 12 .. 28 km
    }
    DomainTally T;
    for (int dv = -20; dv <= -4; ++dv) judge_domain(w, pj, -81, cam, p, fx, u0, v0 + dv, T, 0);
    std::printf("  a level line of sight (k = 0.9977) 26 km from a tile of 5 mm posts, its 16 km piece's rise below "
                "2^-96: %ld pixels, %ld hits as the reference's (within %.5f m); %ld wrong\n", T.n, T.hits, T.worst,
                T.bad);
    TEST_ASSERT(T.bad == 0 && T.n == 17 && T.hits == 17 && T.worst <= 0.001);
}

// A chord finer than the pieces can prove is refused pixel by pixel, never
// traced with pieces outside their tolerance.  A piece's bound holds terms
// that do not shrink with its length -- on the camera's own piece (a camera
// over the tile) the camera's rounding to its Q16 grid point, up to 258 Q24
// units, 0.46 mm at 30 m posts: chords below about 0.62 mm (of which the
// checks aim at 3/4) may not be proven there, where that rounding is at
// its largest, and none of 2^10 nm, the finest ct_effects accepts,
// anywhere.  At 2^10 nm every pixel that hits at
// the default (1 mm) is CT_ERR_EFFECTS and none hits; the piece log ends
// with that status and holds no piece over its tolerance; at 0.8 mm every
// pixel's status is the default's (a hit within 5 mm of its hit: two
// chords' bounds and the walk's rounding on slopes); at 0.1 mm a pixel is
// refused (the nadir poses: a piece whose bound stays just above the
// tolerance through all its shortenings) or as at 1 mm (a hit within 1 cm:
// 5.1 mm on a steep slope under a nadir pose).
void test_chord_too_fine()
{
    World *w = jacksboro();
    Cam cam = make_camera();
    long pixels = 0, hits = 0, refused = 0, wrong = 0, agree = 0, fine_refused = 0, fine_bad = 0;
    static ct_earth_piece pcs[2048];
    for (const PoseDef &d : pose_defs()) {
        Pose p;
        TEST_ASSERT_MSG(make_pose(w->sf, d, &p), "pose %s", d.family);
        std::vector<int64_t> uv;
        for (int iv = 0; iv < cam.h; iv += 96)
            for (int iu = 0; iu < cam.w; iu += 128) {
                uv.push_back((int64_t)iu << 16);
                uv.push_back((int64_t)iv << 16);
            }
        const size_t n = uv.size() / 2;
        std::vector<ct_geo> g1(n), gf(n), g08(n), g01(n);
        ct_effects fx = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &fx,
                                                        uv.data(), n, g1.data(), n));
        fx.chord_nm = INT64_C(1) << 10;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &fx,
                                                        uv.data(), n, gf.data(), n));
        fx.chord_nm = 800000;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &fx,
                                                        uv.data(), n, g08.data(), n));
        fx.chord_nm = 100000;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&w->p, &cam.cam, &p.pose, CT_METHOD_DIRECTIONAL, &fx,
                                                        uv.data(), n, g01.data(), n));
        for (size_t k = 0; k < n; ++k) {
            pixels++;
            const bool hit1 = g1[k].status == CT_HIT || g1[k].status == CT_HIT_VOID;
            hits += hit1;
            refused += gf[k].status == CT_ERR_EFFECTS;
            wrong += gf[k].status == CT_HIT || gf[k].status == CT_HIT_VOID || (hit1 && gf[k].status != CT_ERR_EFFECTS);
            const ld de = (ld)(g08[k].hit.e_nm - g1[k].hit.e_nm), dn = (ld)(g08[k].hit.n_nm - g1[k].hit.n_nm),
                     dh = (ld)(g08[k].hit.h_nm - g1[k].hit.h_nm);
            agree += g08[k].status == g1[k].status && (!hit1 || std::sqrt(de * de + dn * dn + dh * dh) <= 5e6L);
            // at 0.1 mm: refused, or as at 1 mm
            const ld fe = (ld)(g01[k].hit.e_nm - g1[k].hit.e_nm), fn = (ld)(g01[k].hit.n_nm - g1[k].hit.n_nm),
                     fh = (ld)(g01[k].hit.h_nm - g1[k].hit.h_nm);
            fine_refused += g01[k].status == CT_ERR_EFFECTS;
            fine_bad += g01[k].status != CT_ERR_EFFECTS &&
                        (g01[k].status != g1[k].status || (hit1 && std::sqrt(fe * fe + fn * fn + fh * fh) > 1e7L));
        }
        // the piece log of a line of sight through the image's middle
        ct_earth es;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_setup(&w->p, &p.pose, 0, CT_EARTH_RADIUS_NM, INT64_C(1) << 10, 0u, 0,
                                                    nullptr, &es));
        int64_t dg[3];
        grid_dir_q39(d.yaw, std::max(-89.0L, d.pitch), dg);
        uint32_t np = 0;
        const ct_status st = ct_earth_pieces(&w->p, &es, dg, pcs, 2048u, &np);
        for (uint32_t i = 0; i < np; ++i)
            TEST_ASSERT_MSG(pcs[i].off || (pcs[i].elat_q24 <= es.tol_q24 && pcs[i].evert_q16 <= es.tolz_q16),
                            "pose %s: piece %u of %u over its tolerance (status %d)", d.family, i, np, (int)st);
        TEST_ASSERT_MSG(st == CT_ERR_EFFECTS || st == CT_MISS, "pose %s: piece log status %d", d.family, (int)st);
    }
    std::printf("  chord 2^10 nm on the true Earth: %ld pixels, %ld hit at 1 mm, %ld refused (CT_ERR_EFFECTS), %ld "
                "wrong; at 0.8 mm %ld of %ld as at 1 mm; at 0.1 mm %ld refused, the others as at 1 mm but %ld\n",
                pixels, hits, refused, wrong, agree, pixels, fine_refused, fine_bad);
    TEST_ASSERT(wrong == 0 && hits > 100 && refused >= hits && agree == pixels && fine_bad == 0);
}

void test_exact_curvature() { compare(CT_EFFECT_CURVATURE); }
void test_exact_curvature_refraction() { compare(CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION); }

}  // namespace

int main()
{
    TEST_BEGIN("test_earth");
    RUN_TEST(test_reference_georef);
    RUN_TEST(test_reference_convergence);
    RUN_TEST(test_reference_nadir);
    RUN_TEST(test_reference_flat);
    RUN_TEST(test_fitted_map);
    RUN_TEST(test_path_interpolation);
    RUN_TEST(test_taylor_path);
    RUN_TEST(test_piece_culling);
    RUN_TEST(test_piece_bounds);
    RUN_TEST(test_exact_curvature);
    RUN_TEST(test_exact_curvature_refraction);
    RUN_TEST(test_zone_edge);
    RUN_TEST(test_zone_edge_straddle);
    RUN_TEST(test_latitude_limit);
    RUN_TEST(test_tiny_posting);
    RUN_TEST(test_tiny_height_scale);
    RUN_TEST(test_level_rise_refused);
    RUN_TEST(test_chord_too_fine);
    return TEST_END();
}
