// test_flight_scene.cpp -- the end-to-end flight scene (issue 15's
// acceptance test): a geographic DEM with EGM96 heights, geodetic poses,
// the true Earth.
//
// Input: the fixture jacksboro_fault_dem.tif (EPSG:32617, 30 m) warped onto
// EPSG:4326 (bilinear, float32) by the gdalwarp binary, its heights declared
// EGM96 (they are orthometric metres).  The package is built the way
// `conetrace build geo.tif --vdatum egm96` does it (warp_dem onto the
// automatic UTM zone, 16N here; apply_vdatum EGM96 -> WGS84 ellipsoidal
// heights and the geoid grid; terrain_from_heights; build_package, N = 24),
// and the real CLI's package on the same file must be byte-identical.
//
// Cameras: mrcal LENSMODEL_OPENCV8 with the wide_opencv8 scene's strong
// distortion, and a pinhole.  Geodetic poses (lat, lon, h_ellipsoid from the
// tile's geometry, yaw / pitch / roll through ct_quat_from_ypr, the pose by
// ct_pose_from_wgs84 on zone 16): nadir from 3 km, oblique 30 deg, grazing
// 5 deg, long (10 km outside the tile, 5 deg down).
//
// Ground truth, two independent routes:
//   (a) mrcal: seeded points P on the package's bilinear surface (map E, N,
//       h_ell; near the reference's hit below a random pixel, or behind it
//       so that occluded points occur by design), the true line of sight
//       C -> P straight in Earth-fixed space (PROJ EPSG:4979 -> 4978), its
//       direction rotated into the camera frame by the inverse of the
//       navigation attitude (local NED at C from the quaternion: no
//       convergence involved), projected by mrcal_project with the model's
//       intrinsics.  Pixels outside the image are dropped; the reference
//       traced from the (unrounded) pixel's mrcal-unprojected ray must hit P
//       within kVisibleM, else P is occluded (counted, not used for (a));
//   (b) the PROJ reference (tests/kit/earth_reference.hpp) from the ray of the
//       pixel the library is given (Q16), for every pixel of (a) -- occluded
//       ones included -- and some random pixels (misses, sky).
// The library (ct_geolocate, CT_METHOD_DIRECTIONAL) geolocates every pixel:
//   true Earth (CT_EFFECT_CURVATURE, radius 0) vs (a) and (b); true Earth
//   with refraction vs (b) only ((a) assumes a straight line); and, to show
//   what the true Earth fixes, the straight map-frame line (effects NULL)
//   and the old sphere parabola (radius CT_EARTH_RADIUS_NM) vs both.
// Asserted for the true Earth: RMS <= kMaxRmsM against (a), (b) and (b) with
// refraction per pose family (both cameras), over the hits met at incidence
// >= kMinIncidenceDeg (shallower ones -- a sub-millimetre line-of-sight
// error moves them by cm along the path -- are counted, reported in RMS_all,
// and, like every hit, must lie within kMaxOffPath of the reference path:
// the library's chord tolerance plus 2 Q16 units); every visible (a) point
// hit; zero status mismatches (near-grazing rays, reference clearance
// < kSkipClearM before the hit, skipped; a ray entering the tile's side below
// the surface: the reference hits the wall, the library may say CT_BELOW);
// the hit's geodetic coordinates from the library (ct_utm_inverse of E, N;
// h_ell = h, the package being ellipsoidal) vs PROJ's conversion of the same
// map point within kConvM, and the geodetic distance to the reference hit
// equal to the map-frame one within kConvM (the conversion adds nothing);
// the height in the EGM96 datum (h - ct_package_geoid) vs PROJ's EPSG:4979
// -> EPSG:4326+5773 within kConvM.  The straight line and the old parabola
// must fail the RMS bound (the test discriminates).  Everything is printed
// per pose and camera, per family and in total.
#include <proj.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" {
#include <mrcal/mrcal.h>
}

#include "camera_host.hpp"
#include "conetrace.h"
#include "dem_io.hpp"
#include "earth_reference.hpp"
#include "harness.h"
#include "proj_pair.hpp"
#include "terrain.hpp"
#include "vdatum.hpp"
#include "warp.hpp"

#ifndef CT_CLI
#error "CT_CLI must be defined"
#endif
#ifndef CT_GDALWARP
#error "CT_GDALWARP must be defined"
#endif

using namespace ct_host;
using earth_ref::ld;

namespace {

// ---- tolerances -------------------------------------------------------------
const double kMaxRmsM = 0.01;    // true Earth vs (a) and vs (b): RMS per pose family
const double kConvM = 0.001;     // geodetic / EGM96 conversions of a hit
const double kVisibleM = 0.001;  // the reference's hit from P's pixel is P: visible
const double kSkipClearM = 0.05; // near-grazing: reference clearance before the hit (as test_earth)
// The RMS bound is on hits met at an incidence of at least kMinIncidenceDeg:
// the library's promise is a line of sight within its chord tolerance (1 mm)
// plus 2 Q16 units of the true one (kMaxOffPath, asserted for every hit);
// along a path meeting the terrain at incidence alpha that is 1 / tan(alpha)
// times as much along it (0.36 deg: 16 cm), so a single shallow hit would
// decide the RMS of a pose.  Shallow hits are counted and in RMS_all.
const double kMinIncidenceDeg = 2.0;
const int kVisiblePerPose = 24;  // (a) samples wanted per pose and camera
const int kRandomPerPose = 16;   // extra random pixels for (b)

const std::string kDem = std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif";
const ld kPi = earth_ref::kPi;

int64_t q61(ld deg) { return (int64_t)std::llround(deg * kPi / 180 * std::ldexp(1.0L, 61)); }
ld deg_of_q61(int64_t v) { return (ld)v / std::ldexp(1.0L, 61) * 180 / kPi; }

std::string quote(const std::string &s)
{
    std::string r = "'";
    for (char c : s) r += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return r + "'";
}

int sh(const std::string &cmd, const std::string &log)
{
    const int st = std::system((cmd + " </dev/null >" + quote(log) + " 2>&1").c_str());
    return st == -1 ? -1 : WIFEXITED(st) ? WEXITSTATUS(st) : 128;
}

std::string slurp(const std::string &path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// ---- the world ----------------------------------------------------------------
struct World {
    std::string dir, geo_tif, cli_pkg;
    Terrain t;
    std::vector<uint8_t> bytes, cli_bytes;
    ct_package p;
    earth_ref::Surface sf;
    ct_utm zone = {0, 0};
    earth_ref::Proj *pj = nullptr;
    double build_s = 0, cli_s = 0;
    std::string cli_log;
    bool ok = false;
};

World *g_world = nullptr;
World *world_made() { return g_world; }

World *world()
{
    World *&w = g_world;
    if (w) return w;
    w = new World;
    char tmpl[] = "/tmp/ct_flight_XXXXXX";
    if (!mkdtemp(tmpl)) return w;
    w->dir = tmpl;
    w->geo_tif = w->dir + "/geo.tif";
    w->cli_pkg = w->dir + "/pkg.ctp";
    // the geographic input: EPSG:4326, bilinear, float32 metres (EGM96 heights)
    if (sh(quote(CT_GDALWARP) + " -q -t_srs EPSG:4326 -r bilinear -ot Float32 -dstnodata -9999 " + quote(kDem) + " " +
               quote(w->geo_tif),
           w->dir + "/gdalwarp.log") != 0) {
        std::printf("  gdalwarp to EPSG:4326 failed: %s\n", slurp(w->dir + "/gdalwarp.log").c_str());
        return w;
    }
    // in-process, as `conetrace build geo.tif --vdatum egm96` (cli.cpp load_terrain, cmd_build)
    auto t0 = std::chrono::steady_clock::now();
    WarpOptions wo;  // automatic zone, source posting
    if (!dem_needs_warp(w->geo_tif, wo)) {
        std::printf("  dem_needs_warp is false on the EPSG:4326 file\n");
        return w;
    }
    DemRaster r = warp_dem(w->geo_tif, wo);
    GeoidGrid geoid;
    apply_vdatum(r.h, r.valid, r.width, r.height, r.geo, CT_VDATUM_EGM96, geoid);
    w->t = terrain_from_heights(r.width, r.height, r.h, r.valid, r.geo, 0.0);
    w->t.vdatum = CT_VDATUM_EGM96;
    w->t.geoid = std::move(geoid);
    BuildOptions o;
    o.sectors = 24;
    o.reduce = 3;  // the CLI's defaults
    w->bytes = build_package(w->t, o);
    w->build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (ct_package_open(&w->p, w->bytes.data(), w->bytes.size()) != CT_OK) {
        std::printf("  the in-process package does not open\n");
        return w;
    }
    // the real CLI on the same file
    t0 = std::chrono::steady_clock::now();
    const int rc = sh(quote(CT_CLI) + " build " + quote(w->geo_tif) + " -o " + quote(w->cli_pkg) + " --vdatum egm96",
                      w->dir + "/cli.log");
    w->cli_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    w->cli_log = slurp(w->dir + "/cli.log");
    if (rc != 0) {
        std::printf("  conetrace build failed (%d): %s\n", rc, w->cli_log.c_str());
        return w;
    }
    std::string cb = slurp(w->cli_pkg);
    w->cli_bytes.assign(cb.begin(), cb.end());
    w->sf = earth_ref::Surface::from_package(w->p);
    if (ct_utm_zone_of_epsg((int32_t)w->p.epsg, &w->zone) != CT_OK) {
        std::printf("  package EPSG %u is not UTM\n", (unsigned)w->p.epsg);
        return w;
    }
    w->pj = new earth_ref::Proj((int)w->p.epsg);
    w->ok = true;
    return w;
}

// a cell (i, j) is measured terrain when none of its four posts is void
bool cell_valid(const World &w, ld x, ld y)
{
    const int i = std::min(w.sf.w - 2, std::max(0, (int)std::floor(x)));
    const int j = std::min(w.sf.h - 2, std::max(0, (int)std::floor(y)));
    if (w.t.void_post.empty()) return true;
    const size_t k = (size_t)j * w.t.width + i;
    return !w.t.void_post[k] && !w.t.void_post[k + 1] && !w.t.void_post[k + w.t.width] &&
           !w.t.void_post[k + w.t.width + 1];
}

// ---- PROJ: orthometric (EGM96) height of a WGS84 3D point -------------------
struct ProjEgm96 : ProjPair {
    ProjEgm96() : ProjPair("EPSG:4979", "EPSG:4326+5773") {}
    ld height(ld lat_deg, ld lon_deg, ld h_ell) const
    {
        PJ_COORD c = proj_trans(pj, PJ_FWD, proj_coord((double)lon_deg, (double)lat_deg, (double)h_ell, 0));
        return c.xyz.z;
    }
};

// ---- cameras --------------------------------------------------------------------
struct Camera {
    const char *name;
    CameraModel model;
    LibCamera lib;
    mrcal_lensmodel_t lm;
};

std::vector<Camera> *cameras()
{
    static std::vector<Camera> *v = nullptr;
    if (v) return v;
    v = new std::vector<Camera>;
    struct Def {
        const char *name, *model;
        std::vector<double> intr;
    };
    const Def defs[] = {
        // the wide_opencv8 scene's lens: ~100 deg across, strong rational distortion
        {"opencv8", "LENSMODEL_OPENCV8", {600, 600, 511.5, 383.5, 0.9, -0.05, 2e-4, -1e-4, 0.01, 1.2, 0.1, 0.003}},
        {"pinhole", "LENSMODEL_PINHOLE", {1400, 1400, 511.5, 383.5}}};
    for (const Def &d : defs) {
        Camera c;
        c.name = d.name;
        c.model.model = d.model;
        c.model.intrinsics = d.intr;
        c.model.width = 1024;
        c.model.height = 768;
        c.lib = lib_camera(c.model, d.name);  // the lens; the pose comes from ct_pose_from_wgs84
        if (!mrcal_lensmodel_from_name(&c.lm, d.model)) throw Error(std::string("mrcal does not know ") + d.model);
        v->push_back(c);
    }
    return v;
}

// ---- geodetic poses ---------------------------------------------------------------
struct PoseDef {
    const char *name;
    ld e, n;             // where (map, zone of the package; turned into lat / lon)
    ld above;            // metres above the surface under the camera (outside: above the tile's mean)
    ld yaw, pitch, roll; // deg (ct_quat_from_ypr)
};

struct Pose {
    PoseDef def;
    ld lat, lon, h;      // as given to ct_pose_from_wgs84 (Q61 / nm values converted back)
    int32_t q[4];
    ld qd[4];            // the Q30 quaternion, long double
    ct_pose pose;
    ld C[3];             // camera centre, ECEF (PROJ)
};

bool make_pose(World &w, const PoseDef &d, Pose *out)
{
    ld lat, lon;
    w.pj->utm_inverse(d.e, d.n, &lat, &lon);
    out->def = d;
    const int64_t la = q61(lat), lo = q61(lon);
    const int64_t h_nm = std::llround((w.sf.ground_under(d.e, d.n) + d.above) * 1e9L);
    out->lat = deg_of_q61(la);
    out->lon = deg_of_q61(lo);
    out->h = (ld)h_nm * 1e-9L;
    const ld yaw = d.yaw > 180 ? d.yaw - 360 : d.yaw;
    if (ct_quat_from_ypr(q61(yaw), q61(d.pitch), q61(d.roll), out->q) != CT_OK) return false;
    earth_ref::quat_of_q30(out->q, out->qd);
    w.pj->ecef(out->lat, out->lon, out->h, out->C);
    return ct_pose_from_wgs84(&out->pose, &w.zone, la, lo, h_nm, out->q) == CT_OK;
}

std::vector<PoseDef> pose_defs(const World &w)
{
    const earth_ref::Surface &sf = w.sf;
    ld e0, n0, e1, n1;
    sf.map_of(0, 0, &e0, &n0);
    sf.map_of(sf.w - 1, sf.h - 1, &e1, &n1);
    const ld Ec = (e0 + e1) / 2, Nc = (n0 + n1) / 2;
    const ld W = std::min(e0, e1), S = std::min(n0, n1), E = std::max(e0, e1), N = std::max(n0, n1);
    auto back = [&](ld dist, ld yaw, ld *e, ld *n) {
        *e = Ec - dist * std::sin(yaw * kPi / 180);
        *n = Nc - dist * std::cos(yaw * kPi / 180);
    };
    std::vector<PoseDef> v;
    v.push_back({"nadir", Ec, Nc, 3000, 0, -90, 0});
    v.push_back({"nadir", Ec - 3000, Nc + 2000, 3000, 40, -90, 3});
    for (ld yaw : {0.0L, 135.0L}) {
        ld e, n;
        back(2600 / std::tan(30 * kPi / 180), yaw, &e, &n);
        v.push_back({"oblique30", e, n, 2600, yaw, -30, yaw == 0 ? 0.0L : -4.0L});
    }
    // grazing: north from the south part, east from the west part, south-west from the north-east
    v.push_back({"grazing5", Ec, S + 1500, 1000, 0, -5, 0});
    v.push_back({"grazing5", W + 1500, Nc, 1000, 90, -5, 2});
    v.push_back({"grazing5", E - 1500, N - 1500, 1000, 225, -5, 0});
    // long: 10 km outside the tile, 5 deg down towards its middle
    const ld dw = Ec - (W - 10000), ds = Nc - (S - 10000);
    v.push_back({"long", W - 10000, Nc, dw * std::tan(5 * kPi / 180), 90, -5, 0});
    v.push_back({"long", Ec, S - 10000, ds * std::tan(5 * kPi / 180), 0, -5, 0});
    return v;
}

// ---- helpers ----------------------------------------------------------------------
ld dist3(ld e0, ld n0, ld h0, ld e1, ld n1, ld h1)
{
    return std::sqrt((e0 - e1) * (e0 - e1) + (n0 - n1) * (n0 - n1) + (h0 - h1) * (h0 - h1));
}

// camera-frame direction of the ECEF vector v (inverse of the attitude: ECEF
// -> local NED at the camera -> camera frame by R(q)^T)
void cam_of_ecef(const Pose &p, const ld v[3], ld out[3])
{
    ld e[3], n[3], u[3];
    earth_ref::enu_axes(p.lat, p.lon, e, n, u);
    const ld ned[3] = {earth_ref::dot3(v, n), earth_ref::dot3(v, e), -earth_ref::dot3(v, u)};
    const ld w = p.qd[0], x = p.qd[1], y = p.qd[2], z = p.qd[3];
    const ld R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                        {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                        {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    for (int c = 0; c < 3; ++c) out[c] = R[0][c] * ned[0] + R[1][c] * ned[1] + R[2][c] * ned[2];
    earth_ref::normalise3(out);
}

bool mrcal_ray(const Camera &c, double u, double v, ld ray[3])
{
    mrcal_point2_t q = {{u, v}};
    mrcal_point3_t r;
    if (!mrcal_unproject(&r, &q, 1, &c.lm, c.model.intrinsics.data()) || !(r.z > 0)) return false;
    ray[0] = r.x;
    ray[1] = r.y;
    ray[2] = r.z;
    earth_ref::normalise3(ray);
    return true;
}

bool mrcal_pixel(const Camera &c, const ld ray[3], double *u, double *v)
{
    mrcal_point3_t p = {{(double)ray[0], (double)ray[1], (double)ray[2]}};
    mrcal_point2_t q;
    if (!mrcal_project(&q, nullptr, nullptr, &p, 1, &c.lm, c.model.intrinsics.data())) return false;
    *u = q.x;
    *v = q.y;
    return std::isfinite(q.x) && std::isfinite(q.y);
}

struct Stat {
    long n = 0, shallow = 0, bad = 0, skip = 0, wall = 0, miss = 0;
    double sum2 = 0, max = 0;          // hits met at incidence >= kMinIncidenceDeg
    double sum2_all = 0, max_all = 0;  // every hit
    void add(double d, bool steep)
    {
        if (steep) {
            n++;
            sum2 += d * d;
            max = std::max(max, d);
        } else {
            shallow++;
        }
        sum2_all += d * d;
        max_all = std::max(max_all, d);
    }
    void merge(const Stat &o)
    {
        n += o.n, shallow += o.shallow, bad += o.bad, skip += o.skip, wall += o.wall, miss += o.miss;
        sum2 += o.sum2;
        max = std::max(max, o.max);
        sum2_all += o.sum2_all;
        max_all = std::max(max_all, o.max_all);
    }
    double rms() const { return n ? std::sqrt(sum2 / n) : 0; }
    double rms_all() const { return n + shallow ? std::sqrt(sum2_all / (n + shallow)) : 0; }
};

// The angle (deg) at which the path L meets the bilinear surface at the
// reference hit r: the path's map-frame direction just before the hit vs the
// surface's normal there.
ld incidence_deg(earth_ref::Proj &pj, const earth_ref::Surface &sf, const earth_ref::Los &L, const earth_ref::Result &r)
{
    ld P[3], E, N, h;
    L.at(r.t - 0.5L, P);
    pj.map(P, &E, &N, &h);
    const ld d[3] = {r.e - E, r.n - N, r.h - h};
    ld x, y;
    sf.grid(r.e, r.n, &x, &y);
    const ld eps = 1e-3L;  // posts
    x = std::min<ld>(sf.w - 1 - eps, std::max(eps, x));
    y = std::min<ld>(sf.h - 1 - eps, std::max(eps, y));
    const ld gx = (sf.height(x + eps, y) - sf.height(x - eps, y)) / (2 * eps * sf.pe);
    const ld gy = (sf.height(x, y + eps) - sf.height(x, y - eps)) / (2 * eps * sf.pn);
    const ld n[3] = {-gx, -gy, 1};
    const ld c = std::fabs(earth_ref::dot3(n, d)) / std::sqrt(earth_ref::dot3(n, n) * earth_ref::dot3(d, d));
    return std::asin(std::min<ld>(1, c)) * 180 / kPi;
}

// the library's modes
enum { M_EXACT, M_EXACT_REFR, M_STRAIGHT, M_PARABOLA, M_PARABOLA_REFR, NM };

struct Row {
    std::string pose, cam;
    long tries = 0, occluded = 0, off_image = 0, grazing_a = 0, unproject = 0, pixels = 0;
    Stat a[NM], b[NM];     // vs (a), vs (b) (refraction modes: vs (b) with refraction)
    double geo_conv = 0;   // max |library geodetic - PROJ's conversion of the same map point| (m)
    double geo_vs_map = 0; // max |geodetic distance to the reference hit - map distance| (m)
    double egm = 0;        // max |library EGM96 height - PROJ's| (m)
    double egm_ref = 0;    // max |library EGM96 height - PROJ's of the reference hit| (m)
    Stat routes;           // (a)'s P vs (b)'s reference hit on the same visible pixels (Q16 rounding)
    double max_off = 0;    // true Earth: the library's hit off the reference path (m)
    ld min_inc = 90;       // smallest incidence of a compared hit (deg)
    char worst[2][480] = {"", ""};  // the true Earth's worst hit vs (b), without / with refraction
};

// The sampled pixels of one pose and camera.
struct Px {
    int64_t uq, vq;
    bool truth;   // (a): P is visible from this pixel
    ld P[3];      // (a)'s ground point (map E, N, h_ell)
    ld inc;       // (a): the incidence there (deg)
};

// A candidate for (a) from a random pixel: its first hit (a straight
// Earth-fixed line), a surface point near it (visible, mostly) or behind it
// (occluded, often), that point's pixel through mrcal, and whether the
// reference from that pixel comes back to the point (s.truth).  false: no
// sample (no hit, off the tile, a void cell, off the image).
bool sample_point(World &w, const Camera &cam, const Pose &p, ct_rng *rng, Row *row, Px *out)
{
    earth_ref::Proj &pj = *w.pj;
    const earth_ref::Surface &sf = w.sf;
    const double W = cam.model.width, H = cam.model.height;
    // a random pixel's first hit (straight Earth-fixed line)
    ld ray[3];
    if (!mrcal_ray(cam, ct_rng_unit(rng) * (W - 1), ct_rng_unit(rng) * (H - 1), ray)) return false;
    const earth_ref::Los L0 = earth_ref::los_from_wgs84(pj, p.lat, p.lon, p.h, p.qd, ray, nullptr);
    const earth_ref::Result r0 = earth_ref::trace(pj, sf, L0);
    if (r0.status != CT_HIT || r0.wall) return false;
    // a surface point near it (visible, mostly) or behind it (occluded, often)
    ld e, n;
    if (row->tries % 2) {
        e = r0.e + (ct_rng_unit(rng) * 2 - 1) * sf.pe;
        n = r0.n + (ct_rng_unit(rng) * 2 - 1) * sf.pe;
    } else {
        const ld Ce = (ld)p.pose.e_nm * 1e-9L, Cn = (ld)p.pose.n_nm * 1e-9L, f = 1 + 0.6L * ct_rng_unit(rng);
        e = Ce + (r0.e - Ce) * f;
        n = Cn + (r0.n - Cn) * f;
    }
    ld x, y;
    sf.grid(e, n, &x, &y);
    if (!sf.inside(x, y) || !cell_valid(w, x, y)) return false;
    Px s;
    s.P[0] = e;
    s.P[1] = n;
    s.P[2] = sf.height(x, y);
    // the true line of sight C -> P, Earth-fixed, into the camera frame, projected by mrcal
    ld lat, lon, X[3], v[3], rc[3];
    pj.utm_inverse(e, n, &lat, &lon);
    pj.ecef(lat, lon, s.P[2], X);
    for (int k = 0; k < 3; ++k) v[k] = X[k] - p.C[k];
    cam_of_ecef(p, v, rc);
    double u, vv;
    if (!(rc[2] > 0) || !mrcal_pixel(cam, rc, &u, &vv) || !(u >= 0 && vv >= 0 && u <= W - 1 && vv <= H - 1)) {
        row->off_image++;
        return false;
    }
    s.uq = std::llround(u * 65536);
    s.vq = std::llround(vv * 65536);
    // occluded?  the reference from the pixel's ray must come back to P
    ld ray_p[3];
    s.truth = false;
    if (mrcal_ray(cam, u, vv, ray_p)) {
        const earth_ref::Los Lp = earth_ref::los_from_wgs84(pj, p.lat, p.lon, p.h, p.qd, ray_p, nullptr);
        const earth_ref::Result rp = earth_ref::trace(pj, sf, Lp);
        s.inc = incidence_deg(pj, sf, Lp, rp);
        if (rp.status == CT_HIT && dist3(rp.e, rp.n, rp.h, s.P[0], s.P[1], s.P[2]) <= kVisibleM) {
            if (rp.min_clear < kSkipClearM) {
                row->grazing_a++;
            } else {
                s.truth = true;
            }
        } else {
            row->occluded++;
        }
    }
    *out = s;
    return true;
}

// The pixels of one pose and camera: candidates for (a) until
// kVisiblePerPose of them are visible (or 200 tries per one wanted), then
// kRandomPerPose random pixels for (b); both counts scaled.
std::vector<Px> sample_pixels(World &w, const Camera &cam, const Pose &p, uint64_t seed, Row *row)
{
    const double W = cam.model.width, H = cam.model.height;
    ct_rng rng;
    ct_rng_seed(&rng, seed);
    std::vector<Px> px;
    const int want = std::max(1, (int)std::lround(kVisiblePerPose * ct_test_scale()));
    const int nrand = std::max(1, (int)std::lround(kRandomPerPose * ct_test_scale()));
    int visible = 0;
    while (visible < want && row->tries < 200L * want) {
        row->tries++;
        Px s;
        if (!sample_point(w, cam, p, &rng, row, &s)) continue;
        if (s.truth) visible++;
        px.push_back(s);
    }
    for (int k = 0; k < nrand; ++k) {
        Px s;
        s.uq = ct_rng_range(&rng, 0, (int64_t)(W - 1) << 16);
        s.vq = ct_rng_range(&rng, 0, (int64_t)(H - 1) << 16);
        s.truth = false;
        px.push_back(s);
    }
    row->pixels = (long)px.size();
    return px;
}

// The library's modes' effects; which of them refract.
void mode_effects(ct_effects fx[NM])
{
    fx[M_EXACT] = {CT_EFFECT_CURVATURE, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
    fx[M_EXACT_REFR] = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
    fx[M_STRAIGHT] = {0, 0, 0, 0, nullptr};
    fx[M_PARABOLA] = {CT_EFFECT_CURVATURE, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM, 0, nullptr};
    fx[M_PARABOLA_REFR] = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM, 0, nullptr};
}
const bool kRefracts[NM] = {false, true, false, false, true};

// A pixel's reference paths and hits without (0) and with (1) refraction,
// and the incidence at each hit (90: none).
struct PxRefs {
    earth_ref::Los los[2];
    earth_ref::Result ref[2];
    ld inc[2] = {90, 90};
};

// The exact mode's hit g in geodetic coordinates: the library's
// (ct_utm_inverse; h_ell = h) vs PROJ's conversion of the same map point and
// of the reference hit r, and its height in the EGM96 datum vs PROJ's.
void check_geodetic(World &w, const ct_geo &g, const earth_ref::Result &r, Row *row, ProjEgm96 &egm)
{
    earth_ref::Proj &pj = *w.pj;
    const ld le = g.hit.e_nm * 1e-9L, ln = g.hit.n_nm * 1e-9L, lh = g.hit.h_nm * 1e-9L;
    int64_t la_q, lo_q, N_nm;
    if (ct_utm_inverse(&w.zone, g.hit.e_nm, g.hit.n_nm, &la_q, &lo_q) != CT_OK ||
        ct_package_geoid(&w.p, g.hit.e_nm, g.hit.n_nm, &N_nm) != CT_OK) {
        row->geo_conv = INFINITY;
        return;
    }
    const ld lat_l = deg_of_q61(la_q), lon_l = deg_of_q61(lo_q);
    ld lat_p, lon_p, Xl[3], Xp[3], Xr[3], lat_r, lon_r;
    pj.utm_inverse(le, ln, &lat_p, &lon_p);
    pj.ecef(lat_l, lon_l, lh, Xl);
    pj.ecef(lat_p, lon_p, lh, Xp);
    pj.utm_inverse(r.e, r.n, &lat_r, &lon_r);
    pj.ecef(lat_r, lon_r, r.h, Xr);
    auto d3 = [](const ld a3[3], const ld b3[3]) {
        return std::sqrt((a3[0] - b3[0]) * (a3[0] - b3[0]) + (a3[1] - b3[1]) * (a3[1] - b3[1]) +
                         (a3[2] - b3[2]) * (a3[2] - b3[2]));
    };
    row->geo_conv = std::max(row->geo_conv, (double)d3(Xl, Xp));
    row->geo_vs_map = std::max(row->geo_vs_map, (double)std::fabs(d3(Xl, Xr) - dist3(le, ln, lh, r.e, r.n, r.h)));
    // the height in the EGM96 datum
    const ld H_lib = lh - N_nm * 1e-9L, H_proj = egm.height(lat_p, lon_p, lh);
    const ld H_ref = egm.height(lat_r, lon_r, r.h);
    row->egm = std::max(row->egm, (double)std::fabs(H_lib - H_proj));
    row->egm_ref = std::max(row->egm_ref, (double)std::fabs(H_lib - H_ref));
    if (!(std::fabs(H_proj - lh) > 10)) row->egm = INFINITY;  // PROJ must apply the geoid (N ~ -31 m)
}

// Mode m's geolocation of pixel s, judged against (a) the point s was
// sampled for, when visible (straight Earth-fixed lines only), and (b) the
// reference hit with the mode's refraction; the exact mode's hit also in
// geodetic coordinates.
void judge_mode(World &w, const Camera &cam, const Pose &p, const Px &s, const PxRefs &R, int m,
                const ct_effects fx[NM], Row *row, ProjEgm96 &egm)
{
    ct_geo g;
    const ct_status st = ct_geolocate(&w.p, &cam.lib.cam, &p.pose, CT_METHOD_DIRECTIONAL,
                                      m == M_STRAIGHT ? nullptr : &fx[m], s.uq, s.vq, &g);
    if (st == CT_ERR_UNPROJECT) {
        if (m == 0) row->unproject++;
        return;
    }
    const int ls = st == CT_HIT_VOID ? CT_HIT : st;
    const ld le = g.hit.e_nm * 1e-9L, ln = g.hit.n_nm * 1e-9L, lh = g.hit.h_nm * 1e-9L;
    // (a): straight Earth-fixed lines only
    if (s.truth && !kRefracts[m]) {
        if (ls != CT_HIT)
            row->a[m].bad++;
        else
            row->a[m].add((double)dist3(le, ln, lh, s.P[0], s.P[1], s.P[2]), s.inc >= kMinIncidenceDeg);
    }
    // (b)
    const int k = kRefracts[m] ? 1 : 0;
    const earth_ref::Result &r = R.ref[k];
    if (m == M_EXACT && s.truth && r.status == CT_HIT)
        row->routes.add((double)dist3(r.e, r.n, r.h, s.P[0], s.P[1], s.P[2]), true);
    Stat &b = row->b[m];
    if (r.min_clear < kSkipClearM) {
        b.skip++;
        return;
    }
    if (r.wall && ls == CT_BELOW) {
        b.wall++;
        return;
    }
    if (ls != r.status) {
        b.bad++;
        if (m == M_EXACT || m == M_EXACT_REFR)
            std::printf("    %s %s mode %d px (%.3f, %.3f): library status %d (%.3Lf %.3Lf %.3Lf), reference %d "
                        "(%.3Lf %.3Lf %.3Lf, clearance %.3Lg m)\n",
                        p.def.name, cam.name, m, s.uq / 65536.0, s.vq / 65536.0, (int)st, le, ln, lh, r.status,
                        r.e, r.n, r.h, r.min_clear);
        return;
    }
    if (ls != CT_HIT) {
        b.miss++;
        return;
    }
    const double err = (double)dist3(le, ln, lh, r.e, r.n, r.h);
    if (m == M_EXACT || m == M_EXACT_REFR) {
        // where the library's hit lies relative to the reference path
        const earth_ref::OffPath op = earth_ref::off_path(*w.pj, w.sf, R.los[k], le, ln, lh);
        row->max_off = std::max(row->max_off, (double)op.dist);
        row->min_inc = std::min(row->min_inc, R.inc[k]);
        if (err > b.max_all && err > 0.005)
            std::snprintf(row->worst[k], sizeof row->worst[k],
                          "px (%.2f, %.2f): reference (%.3Lf, %.3Lf, %.3Lf) range %.0Lf m, incidence %.2Lf deg, "
                          "clearance before %.3Lg m; library - reference (%+.4Lf, %+.4Lf, %+.4Lf) m; the "
                          "library's hit %.4Lf m off the path, %+.4Lf m along it, the path's clearance there "
                          "%+.4Lf m",
                          s.uq / 65536.0, s.vq / 65536.0, r.e, r.n, r.h, r.range, R.inc[k], r.min_clear, le - r.e,
                          ln - r.n, lh - r.h, op.dist, op.t - r.t, op.clearance);
    }
    b.add(err, R.inc[k] >= kMinIncidenceDeg);
    if (m == M_EXACT) check_geodetic(w, g, r, row, egm);
}

// One pose and camera: the sampled pixels, their reference paths, and every
// mode's geolocation of them judged (judge_mode), into row.
void run_pose(World &w, const Camera &cam, const Pose &p, uint64_t seed, Row *row, ProjEgm96 &egm)
{
    earth_ref::Proj &pj = *w.pj;
    const std::vector<Px> px = sample_pixels(w, cam, p, seed, row);
    ct_effects fx[NM];
    mode_effects(fx);
    for (const Px &s : px) {
        ld ray[3];
        if (!mrcal_ray(cam, s.uq / 65536.0, s.vq / 65536.0, ray)) continue;
        PxRefs R;
        for (int k = 0; k < 2; ++k) {
            R.los[k] = earth_ref::los_from_wgs84(pj, p.lat, p.lon, p.h, p.qd, ray, &fx[k ? M_EXACT_REFR : M_EXACT]);
            R.ref[k] = earth_ref::trace(pj, w.sf, R.los[k]);
            if (R.ref[k].status == CT_HIT) R.inc[k] = incidence_deg(pj, w.sf, R.los[k], R.ref[k]);
        }
        for (int m = 0; m < NM; ++m) judge_mode(w, cam, p, s, R, m, fx, row, egm);
    }
}

// ---------------------------------------------------------------------------
// The package: in-process as `conetrace build --vdatum egm96` does, and the CLI's
void test_package()
{
    World *w = world();
    TEST_ASSERT_MSG(w->ok, "the world could not be made");
    TEST_ASSERT_EQUAL_INT(32616, (int)w->p.epsg);  // the automatic zone of the fixture's centre
    TEST_ASSERT_EQUAL_INT(4326, (int)w->p.source_epsg);
    TEST_ASSERT_EQUAL_INT(CT_VDATUM_EGM96, (int)w->p.vdatum);
    TEST_ASSERT(w->p.geoid.w >= 2 && w->p.geoid.h >= 2);
    TEST_ASSERT_EQUAL_INT(24, (int)w->p.sectors);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_verify(&w->p));
    size_t ndiff = 0, first = 0;
    if (w->cli_bytes.size() == w->bytes.size())
        for (size_t k = 0; k < w->bytes.size(); ++k)
            if (w->bytes[k] != w->cli_bytes[k] && ndiff++ == 0) first = k;
    std::printf("  geo.tif (EPSG:4326, float32) -> %ux%u posts at %.0f m on EPSG:%u, %s; in-process %.2f s, CLI %.2f s; "
                "packages %zu and %zu bytes, %zu bytes differ\n",
                (unsigned)w->p.width, (unsigned)w->p.height, w->p.posting_e_nm * 1e-9, (unsigned)w->p.epsg,
                w->t.void_post.empty() ? "no voids" : "with voids", w->build_s, w->cli_s, w->bytes.size(),
                w->cli_bytes.size(), ndiff);
    if (ndiff) std::printf("  first difference at byte %zu\n", first);
    TEST_ASSERT_MSG(w->cli_bytes.size() == w->bytes.size() && ndiff == 0,
                    "the CLI's package (%zu bytes) is not the in-process one (%zu bytes, %zu differ)", w->cli_bytes.size(),
                    w->bytes.size(), ndiff);
    TEST_ASSERT_MSG(w->cli_log.find("resampled from EPSG:4326 onto EPSG:32616") != std::string::npos, "CLI said: %s",
                    w->cli_log.c_str());
}

// The flight scene
void print_row(const char *pose, const char *cam, const Row &r)
{
    const Stat &a = r.a[M_EXACT], &b = r.b[M_EXACT], &br = r.b[M_EXACT_REFR];
    std::printf("  %-10s %-7s | %4ld %3ld %4ld %4ld %5.2f %6.2f %5.2f | %4ld %3ld %4ld %3ld %3ld %5.2f %6.2f %5.2f %3ld | "
                "%4ld %3ld %5.2f %6.2f %5.2f %3ld | %4.2f %4.2f | %7.1e %7.1e %7.1e\n",
                pose, cam, a.n, a.shallow, r.occluded, r.grazing_a, a.rms() * 1e3, a.max * 1e3, a.rms_all() * 1e3, b.n,
                b.shallow, b.miss, b.skip, b.wall, b.rms() * 1e3, b.max * 1e3, b.rms_all() * 1e3, b.bad, br.n, br.shallow,
                br.rms() * 1e3, br.max * 1e3, br.rms_all() * 1e3, br.bad, r.max_off * 1e3, (double)r.min_inc,
                r.geo_conv * 1e3, r.geo_vs_map * 1e3, r.egm * 1e3);
}

void merge_row(Row &t, const Row &r)
{
    for (int m = 0; m < NM; ++m) {
        t.a[m].merge(r.a[m]);
        t.b[m].merge(r.b[m]);
    }
    t.occluded += r.occluded;
    t.grazing_a += r.grazing_a;
    t.unproject += r.unproject;
    t.tries += r.tries;
    t.off_image += r.off_image;
    t.pixels += r.pixels;
    t.routes.merge(r.routes);
    t.max_off = std::max(t.max_off, r.max_off);
    t.min_inc = std::min(t.min_inc, r.min_inc);
    t.geo_conv = std::max(t.geo_conv, r.geo_conv);
    t.geo_vs_map = std::max(t.geo_vs_map, r.geo_vs_map);
    t.egm = std::max(t.egm, r.egm);
    t.egm_ref = std::max(t.egm_ref, r.egm_ref);
}

void test_flight()
{
    World *w = world();
    TEST_ASSERT_MSG(w->ok, "the world could not be made");
    std::vector<Camera> &cams = *cameras();
    ProjEgm96 egm;
    TEST_ASSERT_MSG(egm.pj != nullptr, "PROJ cannot make EPSG:4979 -> EPSG:4326+5773");
    const double max_off_path = 0.001 + 2 * std::fabs((double)w->sf.pe) / 65536;  // kMaxOffPath: chord + 2 Q16 units
    const std::vector<PoseDef> defs = pose_defs(*w);
    std::vector<Row> rows;
    auto t0 = std::chrono::steady_clock::now();
    std::printf("  poses (ct_pose_from_wgs84 on zone %d%c; h ellipsoidal):\n", (int)w->zone.zone, w->zone.south ? 'S' : 'N');
    uint64_t seed = ct_test_seed() * 7919 + 11;
    for (size_t k = 0; k < defs.size(); ++k) {
        Pose p;
        TEST_ASSERT_MSG(make_pose(*w, defs[k], &p), "pose %zu (%s)", k, defs[k].name);
        std::printf("    %-10s lat %.6Lf lon %.6Lf h %7.1Lf m  yaw %5.1Lf pitch %5.1Lf roll %4.1Lf\n", p.def.name, p.lat,
                    p.lon, p.h, p.def.yaw, p.def.pitch, p.def.roll);
        for (const Camera &c : cams) {
            Row r;
            r.pose = defs[k].name;
            r.cam = c.name;
            run_pose(*w, c, p, seed++, &r, egm);
            rows.push_back(r);
        }
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("  %zu poses x %zu cameras in %.1f s (%ld PROJ samples)\n", defs.size(), cams.size(), secs, w->pj->calls);
    std::printf("  a: (a) mrcal truth, visible points compared (shal: of them met at incidence < %.0f deg, outside RMS; "
                "occl: occluded by design; graz: near-grazing, not used); b: (b) PROJ reference from the pixel's ray, "
                "both hit (miss: both miss; skip: reference clearance < %.2f m before the hit; wall: reference on the "
                "tile's side, library CT_BELOW; bad: status differs); b+rf: the same with refraction (k 0.13); RMS / max "
                "over incidence >= %.0f deg, all: RMS over every hit; off: the library's hit off the reference path; "
                "inc: smallest incidence; geo: library lat/lon/h_ell vs PROJ's conversion of the same map point (ECEF); "
                "geo-map: |geodetic - map-frame distance| to the reference hit; egm96: h - ct_package_geoid vs PROJ "
                "EPSG:4979 -> 4326+5773\n",
                kMinIncidenceDeg, kSkipClearM, kMinIncidenceDeg);
    std::printf("  true Earth (CT_EFFECT_CURVATURE, radius 0); mm, inc in deg:\n");
    std::printf("  %-10s %-7s | %4s %3s %4s %4s %5s %6s %5s | %4s %3s %4s %3s %3s %5s %6s %5s %3s | %4s %3s %5s %6s %5s %3s | "
                "%4s %4s | %7s %7s %7s\n",
                "pose", "camera", "a", "shal", "occl", "graz", "RMS", "max", "all", "b", "shl", "miss", "skp", "wal", "RMS",
                "max", "all", "bad", "b+rf", "shl", "RMS", "max", "all", "bad", "off", "inc", "geo", "geo-map", "egm96");
    Row tot;
    for (const Row &r : rows) {
        print_row(r.pose.c_str(), r.cam.c_str(), r);
        merge_row(tot, r);
    }
    std::vector<std::string> fams;
    for (const Row &r : rows)
        if (std::find(fams.begin(), fams.end(), r.pose) == fams.end()) fams.push_back(r.pose);
    std::vector<Row> fam(fams.size());
    for (const Row &r : rows) merge_row(fam[std::find(fams.begin(), fams.end(), r.pose) - fams.begin()], r);
    for (size_t f = 0; f < fams.size(); ++f) print_row(fams[f].c_str(), "(both)", fam[f]);
    print_row("all", "", tot);
    for (const Row &r : rows)
        for (int k = 0; k < 2; ++k)
            if (r.worst[k][0])
                std::printf("  worst %s %s%s: %s\n", r.pose.c_str(), r.cam.c_str(), k ? " (refraction)" : "", r.worst[k]);
    std::printf("  sampling: %ld tries (a random pixel's first hit, a surface point near or behind it) -> %ld pixels "
                "(random ones included; %ld points off the image), %ld visible (a) points, %ld occluded, %ld near-grazing; "
                "%ld library CT_ERR_UNPROJECT\n",
                tot.tries, tot.pixels, tot.off_image, tot.a[0].n + tot.a[0].shallow + tot.a[0].bad, tot.occluded,
                tot.grazing_a, tot.unproject);
    std::printf("  the two routes on the same visible pixels ((a)'s P vs (b)'s hit from the Q16 pixel): %ld, RMS %.3f mm, "
                "max %.3f mm; EGM96 height vs PROJ's of the reference hit: max %.2f mm\n",
                tot.routes.n, tot.routes.rms() * 1e3, tot.routes.max * 1e3, tot.egm_ref * 1e3);
    std::printf("  what the true Earth fixes (same pixels, every hit; errors in m; bad = status mismatches):\n");
    std::printf("  %-10s %-7s | %-32s | %-32s | %-15s\n", "pose", "camera", "straight map line: a RMS max bad, b RMS max",
                "old parabola: a RMS max bad, b RMS max", "parab+refr: b");
    rows.push_back(tot);
    rows.back().pose = "all";
    rows.back().cam = "";
    for (const Row &r : rows) {
        const Stat &sa = r.a[M_STRAIGHT], &sb = r.b[M_STRAIGHT], &pa = r.a[M_PARABOLA], &pb = r.b[M_PARABOLA],
                   &qb = r.b[M_PARABOLA_REFR];
        std::printf("  %-10s %-7s | %7.3f %8.3f %2ld %7.3f %8.3f %2ld | %6.3f %7.3f %2ld %6.3f %7.3f %2ld | %6.3f %7.3f %2ld\n",
                    r.pose.c_str(), r.cam.c_str(), sa.rms_all(), sa.max_all, sa.bad, sb.rms_all(), sb.max_all, sb.bad,
                    pa.rms_all(), pa.max_all, pa.bad, pb.rms_all(), pb.max_all, pb.bad, qb.rms_all(), qb.max_all, qb.bad);
    }
    rows.pop_back();

    // ---- assertions
    TEST_ASSERT_MSG(tot.unproject == 0, "%ld pixels inside the image the library cannot unproject", tot.unproject);
    TEST_ASSERT_MSG(tot.occluded > 0, "no occluded point: the sampling does not make any");
    for (const Row &r : rows) {
        const Stat &a = r.a[M_EXACT], &b = r.b[M_EXACT], &br = r.b[M_EXACT_REFR];
        TEST_ASSERT_MSG(a.n + a.shallow >= 12 && b.n + b.shallow >= 12, "%s %s: only %ld (a) and %ld (b) hits compared",
                        r.pose.c_str(), r.cam.c_str(), a.n + a.shallow, b.n + b.shallow);
        TEST_ASSERT_MSG(a.bad == 0, "%s %s: %ld visible points the true-Earth mode does not hit", r.pose.c_str(),
                        r.cam.c_str(), a.bad);
        TEST_ASSERT_MSG(b.bad == 0 && br.bad == 0, "%s %s: %ld (+ %ld with refraction) status mismatches vs the reference",
                        r.pose.c_str(), r.cam.c_str(), b.bad, br.bad);
    }
    for (size_t f = 0; f < fams.size(); ++f) {
        const Stat &a = fam[f].a[M_EXACT], &b = fam[f].b[M_EXACT], &br = fam[f].b[M_EXACT_REFR];
        TEST_ASSERT_MSG(a.rms() <= kMaxRmsM, "%s: RMS vs (a) mrcal truth %.4f m > %.3f m", fams[f].c_str(), a.rms(),
                        kMaxRmsM);
        TEST_ASSERT_MSG(b.rms() <= kMaxRmsM, "%s: RMS vs (b) the reference %.4f m > %.3f m", fams[f].c_str(), b.rms(),
                        kMaxRmsM);
        TEST_ASSERT_MSG(br.rms() <= kMaxRmsM, "%s: RMS vs (b) the reference with refraction %.4f m > %.3f m",
                        fams[f].c_str(), br.rms(), kMaxRmsM);
    }
    TEST_ASSERT_MSG(tot.max_off <= max_off_path, "a library hit %.4f m off the reference path (> %.4f m)", tot.max_off,
                    max_off_path);
    TEST_ASSERT_MSG(tot.geo_conv <= kConvM, "library geodetic hit off PROJ's conversion by %.4f mm", tot.geo_conv * 1e3);
    TEST_ASSERT_MSG(tot.geo_vs_map <= kConvM, "geodetic error differs from the map-frame error by %.4f mm",
                    tot.geo_vs_map * 1e3);
    TEST_ASSERT_MSG(tot.egm <= kConvM, "EGM96 height off PROJ's by %.4f mm", tot.egm * 1e3);
    // the test discriminates: the models the true Earth replaces fail it
    TEST_ASSERT_MSG(tot.a[M_STRAIGHT].rms() > kMaxRmsM && tot.b[M_STRAIGHT].rms() > kMaxRmsM,
                    "the straight map-frame line passes (%.4f / %.4f m)", tot.a[M_STRAIGHT].rms(), tot.b[M_STRAIGHT].rms());
    TEST_ASSERT_MSG(tot.a[M_PARABOLA].rms() > kMaxRmsM && tot.b[M_PARABOLA].rms() > kMaxRmsM,
                    "the old parabola passes (%.4f / %.4f m)", tot.a[M_PARABOLA].rms(), tot.b[M_PARABOLA].rms());
}

// the temporary directory goes whatever ran (CT_TEST_FILTER, a failure)
bool cleanup()
{
    World *w = world_made();
    if (!w || w->dir.empty()) return true;
    for (const char *f : {"/geo.tif", "/pkg.ctp", "/gdalwarp.log", "/cli.log"}) std::remove((w->dir + f).c_str());
    if (rmdir(w->dir.c_str()) == 0) return true;
    std::printf("  cannot remove %s (not empty?)\n", w->dir.c_str());
    return false;
}

}  // namespace

int main()
{
    TEST_BEGIN("test_flight_scene");
    int rc = 1;
    try {
        RUN_TEST(test_package);
        RUN_TEST(test_flight);
        rc = TEST_END();
    } catch (const std::exception &e) {
        std::printf("  exception: %s\n", e.what());
    }
    return cleanup() ? rc : 1;
}
