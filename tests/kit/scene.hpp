// scene.hpp -- geolocation scenes (fixtures/scenes/*.scene, format in
// fixtures/scenes/README.md) and their simulator: ground truth from mrcal
// projection and the independent long-double reference tracer, with exactly
// the effects a scene lists.  Shared by tests/test_scenes.cpp and
// bench/bench_geoloc.cpp.
//
// The simulator (tests only, long double):
//   - a ground point P on the bilinear surface is chosen (below a random
//     pixel, or behind the first hit of one, so occluded points occur);
//   - its line of sight from the camera centre C under the scene's effects
//     is the parabola z(rho) = C_h + sigma rho + c rho^2 / 2R through P
//     (c = [curvature] - k [refraction], rho the horizontal range): it leaves
//     the camera along the direction towards the *apparent* point
//     P' = P - (0, 0, c rho_P^2 / 2R), which mrcal projects (with the
//     scene's lens: distortion only if the scene lists it) to the pixel;
//   - the reference tracer follows that parabola (ref::Ray::kz) from C and
//     reports its first hit: P itself (visible) or an occluder.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

extern "C" {
#include <mrcal/mrcal.h>
}

#include "camera_host.hpp"
#include "conetrace.h"
#include "dem_cases.hpp"
#include "dem_io.hpp"
#include "reference.hpp"

namespace scene {

typedef long double ld;

enum { FX_DISTORTION = 1, FX_CURVATURE = 2, FX_REFRACTION = 4 };

struct Scene {
    std::string name, dir, path;
    std::string dem;                 // path relative to the scene file
    int tile_x = 1, tile_y = 1;      // mirror tiling
    int sectors = 24, reduce = 1;    // package
    std::string camera;              // .cameramodel, relative
    std::string lens_model;
    std::vector<double> intrinsics;
    unsigned width = 0, height = 0;
    double pose[6] = {0, 0, 0, 0, 0, 0};  // E N h (m), azimuth, depression, roll (deg)
    unsigned effects = 0;            // FX_*
    double k = 0.13, radius_m = 6371000.0;
};

inline std::string fx_names(unsigned fx)
{
    std::string s;
    if (fx & FX_DISTORTION) s += "distortion ";
    if (fx & FX_CURVATURE) s += "curvature ";
    if (fx & FX_REFRACTION) s += "refraction ";
    if (s.empty()) return "none";
    s.pop_back();
    return s;
}

// Throws ct_host::Error("<path>:<line>: reason").
inline Scene read_scene(const std::string &path)
{
    Scene s;
    s.path = path;
    size_t slash = path.find_last_of('/');
    s.dir = slash == std::string::npos ? "." : path.substr(0, slash);
    std::ifstream in(path);
    if (!in) throw ct_host::Error(path + ": cannot open");
    std::string line;
    int ln = 0;
    bool have[6] = {false, false, false, false, false, false};
    while (std::getline(in, line)) {
        ++ln;
        size_t hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        std::istringstream is(line);
        std::string key;
        if (!(is >> key)) continue;
        auto bad = [&](std::string why) {
            for (char &c : why)  // the file's text quoted: no control characters
                if ((unsigned char)c < 0x20 || c == 0x7f) c = '?';
            throw ct_host::Error(path + ":" + std::to_string(ln) + ": " + why.substr(0, 200));
        };
        auto nums = [&](size_t n) {
            std::vector<double> v;
            double x;
            while (is >> x) v.push_back(x);
            if (!is.eof() || (n && v.size() != n)) bad("'" + key + "' needs " + std::to_string(n) + " numbers");
            return v;
        };
        // a whole number in [lo, hi] (checked before a cast: a double beyond an
        // int's range is undefined behaviour)
        auto whole = [&](double x, double lo, double hi) {
            if (!(x >= lo && x <= hi && x == std::floor(x)))
                bad("'" + key + "' needs whole numbers in " + std::to_string((long)lo) + ".." + std::to_string((long)hi));
            return x;
        };
        if (key == "name") {
            if (!(is >> s.name)) bad("name needs a value");
        } else if (key == "dem") {
            if (!(is >> s.dem)) bad("dem needs a path");
            have[0] = true;
        } else if (key == "tile") {
            auto v = nums(2);
            if (!(v[0] >= 1 && v[0] <= 8 && v[1] >= 1 && v[1] <= 8 && v[0] == std::floor(v[0]) && v[1] == std::floor(v[1])))
                bad("tile needs 1..8 1..8");
            s.tile_x = (int)v[0], s.tile_y = (int)v[1];
        } else if (key == "package") {
            auto v = nums(2);
            s.sectors = (int)whole(v[0], 1, 1 << 20), s.reduce = (int)whole(v[1], 1, 1 << 20);
        } else if (key == "camera") {
            if (!(is >> s.camera)) bad("camera needs a path");
            have[1] = true;
        } else if (key == "lens") {
            if (!(is >> s.lens_model)) bad("lens needs a model name");
            s.intrinsics = nums(0);
            have[2] = true;
        } else if (key == "imager") {
            auto v = nums(2);
            s.width = (unsigned)whole(v[0], 1, 1 << 30), s.height = (unsigned)whole(v[1], 1, 1 << 30);
            have[3] = true;
        } else if (key == "pose") {
            auto v = nums(6);
            std::copy(v.begin(), v.end(), s.pose);
            have[4] = true;
        } else if (key == "effects") {
            std::string e;
            while (is >> e) {
                if (e == "distortion") s.effects |= FX_DISTORTION;
                else if (e == "curvature") s.effects |= FX_CURVATURE;
                else if (e == "refraction") s.effects |= FX_REFRACTION;
                else if (e != "none") bad("unknown effect '" + e + "'");
            }
            have[5] = true;
        } else if (key == "refraction_k") {
            s.k = nums(1)[0];
        } else if (key == "earth_radius") {
            s.radius_m = nums(1)[0];
        } else {
            bad("unknown key '" + key + "'");
        }
    }
    const char *names[6] = {"dem", "camera", "lens", "imager", "pose", "effects"};
    for (int k = 0; k < 6; ++k)
        if (!have[k]) throw ct_host::Error(path + ": missing '" + names[k] + "'");
    if (s.name.empty()) s.name = path.substr(slash == std::string::npos ? 0 : slash + 1);
    // the lens must agree with the distortion effect
    bool distorted = false;
    for (size_t k = 4; k < s.intrinsics.size(); ++k) distorted = distorted || s.intrinsics[k] != 0;
    if (distorted != ((s.effects & FX_DISTORTION) != 0))
        throw ct_host::Error(path + ": the lens " + (distorted ? "has" : "has no") +
                             " distortion but 'effects' says otherwise");
    return s;
}

// ---- pose: (E, N, h, azimuth, depression, roll) <-> rt_cam_ref ---------

struct Quat {
    ld w, x, y, z;
};
inline Quat q_axis(ld ax, ld ay, ld az, ld angle)
{
    ld n = std::sqrt(ax * ax + ay * ay + az * az), s = std::sin(angle / 2) / n;
    return {std::cos(angle / 2), ax * s, ay * s, az * s};
}
inline Quat q_mul(const Quat &a, const Quat &b)
{
    return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
            a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

// rt_cam_ref (map frame = reference) of a camera at (E, N, h) looking along
// azimuth az (clockwise from north) with depression dep below horizontal and
// roll about its optical axis; image top towards the azimuth.  Rotations
// are composed as quaternions and turned into the Rodrigues vector with
// atan2 (well conditioned at pi; no r_from_R).
inline void rt_from_pose(const double pose[6], double rt[6])
{
    const ld d2r = (ld)M_PI / 180;
    Quat q0 = q_axis(1, 0, 0, -(ld)M_PI / 2);  // level camera looking north
    Quat roll = q_axis(0, 0, 1, pose[5] * d2r);  // about the camera's z
    Quat tilt = q_axis(1, 0, 0, -pose[4] * d2r);
    Quat turn = q_axis(0, 0, 1, -pose[3] * d2r);
    Quat q = q_mul(turn, q_mul(tilt, q_mul(q0, roll)));  // map <- cam
    if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
    ld s = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z), th = 2 * std::atan2(s, q.w), f = s > 0 ? th / s : 2;
    ld r_cam_map[3] = {-q.x * f, -q.y * f, -q.z * f}, R[9];
    ct_host::rotation_from_r(r_cam_map, R);
    for (int k = 0; k < 3; ++k) rt[k] = (double)r_cam_map[k];
    for (int i = 0; i < 3; ++i)
        rt[3 + i] = (double)-(R[3 * i] * pose[0] + R[3 * i + 1] * pose[1] + R[3 * i + 2] * pose[2]);
}

inline ct_host::CameraModel model_of(const Scene &s)
{
    ct_host::CameraModel m;
    m.model = s.lens_model;
    m.intrinsics = s.intrinsics;
    m.width = s.width;
    m.height = s.height;
    rt_from_pose(s.pose, m.rt_cam_ref);
    return m;
}

// ---- the world: DEM (mirror-tiled), package, cameras ------------------

inline ct_host::Terrain load_terrain(const Scene &s)
{
    std::string p = s.dem[0] == '/' ? s.dem : s.dir + "/" + s.dem;
    ct_host::DemRaster r = ct_host::read_dem(p);
    ct_host::Terrain t = ct_host::terrain_from_heights(r.width, r.height, r.h, r.valid, r.geo, 0.0);
    if (s.tile_x == 1 && s.tile_y == 1) return t;
    return dem_cases::mirror_tiled(t, t.width * s.tile_x, t.height * s.tile_y);
}

using dem_cases::Geo;

struct World {
    Scene s;
    ct_host::Terrain t;
    std::vector<uint8_t> bytes;
    ct_package p;
    ref::Dem d;
    ct_host::CameraModel file_model;   // as read from the .cameramodel
    ct_host::LibCamera cam;            // the library's camera (the file's lens)
    ct_host::LibCamera pinhole;        // the same without distortion
    mrcal_lensmodel_t lm;
    double build_s = 0;
};

// Loads everything; throws ct_host::Error.
inline World *load_world(const std::string &scene_path)
{
    World *w = new World;
    w->s = read_scene(scene_path);
    w->t = load_terrain(w->s);
    ct_host::BuildOptions o;
    o.sectors = w->s.sectors;
    o.reduce = w->s.reduce;
    ct_host::BuildStats st;
    w->bytes = ct_host::build_package(w->t, o, &st);
    w->build_s = st.seconds;
    if (ct_package_open(&w->p, w->bytes.data(), w->bytes.size()) != CT_OK)
        throw ct_host::Error(scene_path + ": package does not open");
    w->d.w = w->t.width;
    w->d.h = w->t.height;
    w->d.z.assign(w->t.codes.begin(), w->t.codes.end());
    std::string cpath = w->s.dir + "/" + w->s.camera;
    w->file_model = ct_host::read_cameramodel(cpath);
    w->cam = ct_host::lib_camera(w->file_model, cpath);
    ct_host::CameraModel pm = w->file_model;
    pm.model = "LENSMODEL_PINHOLE";
    pm.intrinsics.resize(4);
    w->pinhole = ct_host::lib_camera(pm, cpath + " (pinhole)");
    if (!mrcal_lensmodel_from_name(&w->lm, w->file_model.model.c_str()))
        throw ct_host::Error(cpath + ": mrcal does not know " + w->file_model.model);
    return w;
}

inline ct_effects lib_effects(const Scene &s, unsigned fx)
{
    ct_effects e = {0u, (int32_t)std::lround(s.k * 65536), (int64_t)std::llround(s.radius_m * 1e9), 0, nullptr};
    if (fx & FX_CURVATURE) e.flags |= CT_EFFECT_CURVATURE;
    if (fx & FX_REFRACTION) e.flags |= CT_EFFECT_REFRACTION;
    return e;
}

// c of the model, as the library rounds it (k in Q16)
inline ld bend_coeff(const Scene &s, unsigned fx)
{
    return ((fx & FX_CURVATURE) ? 1.0L : 0.0L) - ((fx & FX_REFRACTION) ? std::lround(s.k * 65536) / 65536.0L : 0.0L);
}

// ---- the simulator ----------------------------------------------------

struct Sample {
    ld P[3];           // chosen ground point, map metres
    ld first[3];       // the reference's first hit along P's line of sight
    bool visible;      // first == P
    int64_t uq, vq;    // pixel (mrcal), Q16
    double u, v;
    ld dep_deg;        // depression of the line of sight at the first hit
    ld inc_deg;        // angle between the line of sight and the surface there
    ld range_m;        // horizontal range of the first hit
};

// The reference parabola in the grid frame from the camera centre C through
// map point A (t = 1 at A), bending c / 2R; re-expanded at the tile entry.
// Returns false when it never enters the tile.
inline bool ref_ray(const World &w, const Geo &g, const ld C[3], const ld A[3], ld c, ld *t_entry, ref::Ray *out)
{
    ld cg[3], ag[3];
    g.to_grid(C, cg);
    g.to_grid(A, ag);
    ld dx = ag[0] - cg[0], dy = ag[1] - cg[1];
    ld hm = std::hypot(dx * g.pe, dy * g.pn);
    ld kz = c * hm * hm / (2 * (ld)w.s.radius_m) / g.sc;
    ld dz = ag[2] - cg[2] - kz;
    const ld W = w.d.w - 1, H = w.d.h - 1;
    ld lo = 0, hi = 4;
    if (!ref::clip_box(cg[0], cg[1], dx, dy, W, H, &lo, &hi)) return false;
    ref::Ray r;
    r.ox = std::min(W, std::max<ld>(0, cg[0] + lo * dx));
    r.oy = std::min(H, std::max<ld>(0, cg[1] + lo * dy));
    r.oz = cg[2] + lo * dz + kz * lo * lo;
    r.dx = dx;
    r.dy = dy;
    r.dz = dz + 2 * kz * lo;
    r.kz = kz;
    r.tend = hi - lo;
    *t_entry = lo;
    *out = r;
    return true;
}

// Smallest clearance (LSB) of the ray above the surface over [0, tb]:
// a walk over the cells of the path (with their 3x3 neighbourhoods),
// analytic per cell as ref::min_clearance.
inline ld path_clearance(const ref::Dem &d, const ref::Ray &r, ld tb)
{
    int cw = d.w - 1, chh = d.h - 1;
    ld m = INFINITY;
    tb = std::min(tb, r.tend);
    std::vector<std::pair<int, int>> seen;
    auto cell = [&](int i, int j) {
        if (i < 0 || j < 0 || i >= cw || j >= chh) return;
        for (auto &q : seen)
            if (q.first == i && q.second == j) return;
        seen.push_back({i, j});
        if (seen.size() > 64) seen.erase(seen.begin(), seen.begin() + 32);
        ld t0, t1;
        if (!ref::cell_interval(r, i, j, &t0, &t1)) return;
        t1 = std::min(t1, tb);
        if (t1 < t0) return;
        m = std::min(m, ref::f_cell(d, i, j, r, t0));
        m = std::min(m, ref::f_cell(d, i, j, r, t1));
        ld h00 = d.at(i, j), h10 = d.at(i + 1, j), h01 = d.at(i, j + 1), h11 = d.at(i + 1, j + 1);
        ld c = h11 - h10 - h01 + h00, A = -c * r.dx * r.dy + r.kz;
        if (A > 0) {
            ld a = h10 - h00, b = h01 - h00, u0 = r.ox - i, v0 = r.oy - j;
            ld B = r.dz - a * r.dx - b * r.dy - c * (u0 * r.dy + v0 * r.dx);
            ld tv = -B / (2 * A);
            if (tv > t0 && tv < t1) m = std::min(m, ref::f_cell(d, i, j, r, tv));
        }
    };
    ld t = 0;
    int guard = 4 * (cw + chh) + 16;
    while (t <= tb && guard-- > 0) {
        ld x = r.ox + t * r.dx, y = r.oy + t * r.dy;
        int i = (int)std::floor(x), j = (int)std::floor(y);
        for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) cell(i + di, j + dj);
        ld tn = INFINITY;
        if (r.dx != 0) tn = std::min(tn, ((r.dx > 0 ? std::floor(x) + 1 : std::ceil(x) - 1) - r.ox) / r.dx);
        if (r.dy != 0) tn = std::min(tn, ((r.dy > 0 ? std::floor(y) + 1 : std::ceil(y) - 1) - r.oy) / r.dy);
        if (!(tn > t)) tn = t + 1e-12L;
        t = tn;
    }
    return m;
}

struct SimOptions {
    unsigned effects = 0;         // the effects simulated (FX_*)
    ld clearance_m = 0.05;        // line of sight must clear the surface by this before its first hit
    ld min_incidence_deg = 0.25;  // and meet it at least this steeply
    int n = 300;
    uint64_t seed = 1;
};

struct SimStats {
    long tries = 0, tangent = 0, shallow = 0, off_image = 0, no_hit = 0;
};

// The first hit of P's line of sight and its geometry.  False when the
// sample is unusable (tangent, entering the tile below its edge, ...).
inline bool judge(const World &w, const Geo &g, const ld C[3], const SimOptions &o, Sample *s, SimStats *st)
{
    ld c = bend_coeff(w.s, o.effects), te;
    ref::Ray r;
    if (!ref_ray(w, g, C, s->P, c, &te, &r)) return false;
    // entering the tile below its edge: terrain the package does not hold
    if (r.oz - ref::surface(w.d, r.ox, r.oy) < 2) return false;
    ref::Hit h = ref::trace(w.d, r);
    if (h.status != ref::HIT) {
        st->no_hit++;
        return false;
    }
    ld t1 = 1 - te;  // P
    s->visible = std::fabs(h.t - t1) < 1e-7L * std::max<ld>(1, t1);
    if (path_clearance(w.d, r, h.t - std::max<ld>(0.005L * h.t, 1e-4L)) < o.clearance_m / g.sc) {
        st->tangent++;
        return false;
    }
    // geometry at the hit: tangent of the line of sight, surface normal
    int i = std::min(w.d.w - 2, std::max(0, (int)std::floor(h.x)));
    int j = std::min(w.d.h - 2, std::max(0, (int)std::floor(h.y)));
    ld u = h.x - i, v = h.y - j;
    ld h00 = w.d.at(i, j), h10 = w.d.at(i + 1, j), h01 = w.d.at(i, j + 1), h11 = w.d.at(i + 1, j + 1);
    ld cc = h11 - h10 - h01 + h00;
    ld sx = ((h10 - h00) + cc * v) * g.sc / std::fabs(g.pe), sy = ((h01 - h00) + cc * u) * g.sc / std::fabs(g.pn);
    ld n[3] = {-sx, -sy, 1};
    ld dv[3] = {r.dx * std::fabs(g.pe), r.dy * std::fabs(g.pn), (r.dz + 2 * r.kz * h.t) * g.sc};
    ld nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + 1), dn = std::sqrt(dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2]);
    s->inc_deg = std::asin(std::fabs(n[0] * dv[0] + n[1] * dv[1] + n[2] * dv[2]) / (nn * dn)) * 180 / (ld)M_PI;
    s->dep_deg = std::atan2(-dv[2], std::hypot(dv[0], dv[1])) * 180 / (ld)M_PI;
    if (s->inc_deg < o.min_incidence_deg) {
        st->shallow++;
        return false;
    }
    g.to_map(h.x, h.y, h.z, s->first);
    s->range_m = std::hypot(s->first[0] - C[0], s->first[1] - C[1]);
    return true;
}

// Project map point P (its apparent position under `effects`) with mrcal.
inline bool project(const World &w, const double rt[6], const ld C[3], const ld P[3], ld c, double *u, double *v)
{
    ld rho = std::hypot(P[0] - C[0], P[1] - C[1]);
    double Pa[3] = {(double)P[0], (double)P[1], (double)(P[2] - c * rho * rho / (2 * (ld)w.s.radius_m))}, pc[3];
    mrcal_transform_point_rt(pc, NULL, NULL, rt, Pa);
    if (!(pc[2] > 0)) return false;
    mrcal_point3_t p3 = {{pc[0], pc[1], pc[2]}};
    mrcal_point2_t q;
    if (!mrcal_project(&q, NULL, NULL, &p3, 1, &w.lm, w.file_model.intrinsics.data())) return false;
    *u = q.x, *v = q.y;
    return std::isfinite(q.x) && std::isfinite(q.y);
}

// Samples of the scene with `o.effects` simulated.  Half are the first hit
// below a random pixel's line of sight (visible), half a surface point
// behind it (often occluded).
inline std::vector<Sample> simulate(const World &w, const SimOptions &o, SimStats *st)
{
    Geo g(w.p);
    const double *rt = w.file_model.rt_cam_ref;
    const ld *C = w.cam.host_pose.centre_m;
    const ld *R = w.cam.host_pose.R_map_cam;
    ld c = bend_coeff(w.s, o.effects);
    ct_rng rng;
    ct_rng_seed(&rng, o.seed);
    std::vector<Sample> out;
    const double Wd = w.s.width, Hd = w.s.height;
    while ((int)out.size() < o.n && st->tries < 100L * o.n + 1000) {
        st->tries++;
        double u = ct_rng_unit(&rng) * (Wd - 1), v = ct_rng_unit(&rng) * (Hd - 1);
        mrcal_point2_t q = {{u, v}};
        mrcal_point3_t ray;
        if (!mrcal_unproject(&ray, &q, 1, &w.lm, w.file_model.intrinsics.data()) || !(ray.z > 0)) continue;
        ld dm[3];
        for (int i = 0; i < 3; ++i) dm[i] = R[3 * i] * ray.x + R[3 * i + 1] * ray.y + R[3 * i + 2] * ray.z;
        // a far point A along the pixel's line of sight (apparent): the
        // parabola through A's true position starts along dm
        ld hn = std::hypot(dm[0], dm[1]);
        ld reach = 4 * std::hypot((w.d.w - 1) * g.pe, (w.d.h - 1) * g.pn);
        ld sc = hn > 1e-9L ? reach / hn : reach;
        ld A[3] = {C[0] + sc * dm[0], C[1] + sc * dm[1], C[2] + sc * dm[2]};
        ld rhoA = std::hypot(A[0] - C[0], A[1] - C[1]);
        A[2] += c * rhoA * rhoA / (2 * (ld)w.s.radius_m);
        ld te;
        ref::Ray r;
        if (!ref_ray(w, g, C, A, c, &te, &r)) continue;
        if (r.oz - ref::surface(w.d, r.ox, r.oy) < 2) continue;
        ref::Hit h = ref::trace(w.d, r);
        if (h.status != ref::HIT) continue;
        Sample s;
        ld tt = h.t;
        if (out.size() % 2 == 1) tt *= 1 + 0.6L * ct_rng_unit(&rng);  // behind the first hit
        ld x = r.ox + tt * r.dx, y = r.oy + tt * r.dy;
        if (!(x >= 0 && y >= 0 && x <= w.d.w - 1 && y <= w.d.h - 1)) continue;
        g.to_map(x, y, ref::surface(w.d, x, y), s.P);
        if (!project(w, rt, C, s.P, c, &s.u, &s.v) || !(s.u >= 0 && s.v >= 0 && s.u <= Wd - 1 && s.v <= Hd - 1)) {
            st->off_image++;
            continue;
        }
        if (!judge(w, g, C, o, &s, st)) continue;
        s.uq = std::llround(s.u * 65536);
        s.vq = std::llround(s.v * 65536);
        out.push_back(s);
    }
    return out;
}

}  // namespace scene
