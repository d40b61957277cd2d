// dem_cases.hpp -- test DEMs (generated adversarial ones and the real
// fixture) and ray families, shared by the tests and the benchmark.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "conetrace.h"
#include "harness.h"
#include "reference.hpp"
#include "terrain.hpp"

#ifndef CT_FIXTURES_DIR
#define CT_FIXTURES_DIR "fixtures"
#endif

namespace dem_cases {

struct Case {
    std::string name;
    ct_host::Terrain t;
    ct_host::BuildOptions opt;
    std::vector<uint8_t> pkg;
};

inline ct_host::Terrain make_terrain(int w, int h, const std::vector<uint16_t> &codes, double scale_m = 1.0)
{
    ct_host::Terrain t;
    t.width = w;
    t.height = h;
    t.codes = codes;
    t.geo.origin_e = 500000.0;
    t.geo.origin_n = 4000000.0;
    t.geo.posting_e = 30.0;
    t.geo.posting_n = -30.0;
    t.height_offset_m = 100.0;
    t.height_scale_m = scale_m;
    return t;
}

inline Case make_case(const std::string &name, ct_host::Terrain t, int sectors, int reduce, int slices = 0)
{
    Case c;
    c.name = name;
    c.t = std::move(t);
    c.opt.sectors = sectors;
    c.opt.reduce = reduce;
    c.opt.slices = slices;
    c.pkg = ct_host::build_package(c.t, c.opt);
    return c;
}

// ---- generated adversarial DEMs ------------------------------------------

inline std::vector<uint16_t> smooth(int w, int h, uint64_t seed, double lo, double hi)
{
    ct_rng r;
    ct_rng_seed(&r, seed);
    double ph[6], fx[6], fy[6];
    for (int k = 0; k < 6; ++k) {
        ph[k] = ct_rng_unit(&r) * 6.283;
        fx[k] = (ct_rng_unit(&r) - 0.5) * 0.6;
        fy[k] = (ct_rng_unit(&r) - 0.5) * 0.6;
    }
    std::vector<uint16_t> z((size_t)w * h);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            double s = 0;
            for (int k = 0; k < 6; ++k) s += std::sin(fx[k] * i + fy[k] * j + ph[k]) / (k + 1);
            double v = lo + (hi - lo) * (0.5 + 0.2 * s);
            z[(size_t)j * w + i] = (uint16_t)std::clamp(std::lround(v), 0L, 65535L);
        }
    return z;
}

inline std::vector<Case> adversarial_cases()
{
    std::vector<Case> v;
    ct_rng r;
    ct_rng_seed(&r, 12345);
    {  // single-cell spikes on gentle terrain, at the 16-bit maximum
        int w = 61, h = 53;
        auto z = smooth(w, h, 1, 900, 1100);
        for (int k = 0; k < 60; ++k) z[(size_t)ct_rng_range(&r, 0, h - 1) * w + ct_rng_range(&r, 0, w - 1)] = 65535;
        v.push_back(make_case("spikes", make_terrain(w, h, z, 0.25), 24, 1));
    }
    {  // one-post-thin walls (rows, columns) and diagonal knife ridges
        int w = 64, h = 64;
        std::vector<uint16_t> z((size_t)w * h, 2000);
        for (int i = 0; i < w; ++i) z[(size_t)20 * w + i] = 30000;
        for (int j = 5; j < h - 5; ++j) z[(size_t)j * w + 40] = 42000;
        for (int k = 0; k < 50; ++k) z[(size_t)(k + 7) * w + (k + 3)] = 50000;
        for (int k = 0; k < 40; ++k) z[(size_t)(k + 10) * w + (60 - k)] = 25000;
        v.push_back(make_case("walls_and_knives", make_terrain(w, h, z, 0.1), 8, 2));
    }
    {  // pits: single posts at 0 in high terrain
        int w = 50, h = 50;
        auto z = smooth(w, h, 2, 30000, 36000);
        for (int k = 0; k < 80; ++k) z[(size_t)ct_rng_range(&r, 0, h - 1) * w + ct_rng_range(&r, 0, w - 1)] = 0;
        v.push_back(make_case("pits", make_terrain(w, h, z, 0.05), 4, 3));
    }
    {  // a flat plane
        int w = 40, h = 33;
        std::vector<uint16_t> z((size_t)w * h, 12345);
        v.push_back(make_case("flat", make_terrain(w, h, z, 1.0), 1, 1));
    }
    {  // terraces and cliffs
        int w = 70, h = 45;
        std::vector<uint16_t> z((size_t)w * h);
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i) {
                int step = (i + 2 * j) / 9;
                int v0 = 3000 * (step % 7) + (i > 50 ? 40000 : 0);
                z[(size_t)j * w + i] = (uint16_t)std::min(65535, v0);
            }
        v.push_back(make_case("terraces_cliffs", make_terrain(w, h, z, 0.02), 24, 2, 40));
    }
    {  // samples at the 16-bit extremes: maximal saddles
        int w = 33, h = 37;
        std::vector<uint16_t> z((size_t)w * h);
        for (auto &q : z) q = (ct_rng_u64(&r) & 1) ? 65535 : 0;
        v.push_back(make_case("extremes", make_terrain(w, h, z, 0.01), 64, 1));
    }
    {  // smooth hills, whole range, coarse reduction
        int w = 80, h = 80;
        v.push_back(make_case("smooth_r4", make_terrain(w, h, smooth(w, h, 3, 0, 65535), 0.05), 3, 4));
    }
    {  // white noise
        int w = 45, h = 45;
        std::vector<uint16_t> z((size_t)w * h);
        for (auto &q : z) q = (uint16_t)ct_rng_range(&r, 20000, 24000);
        v.push_back(make_case("noise", make_terrain(w, h, z, 0.1), 32, 1));
    }
    return v;
}

// The bundled real DEM (fixtures/jacksboro_fault_dem.tif), read through the
// host reader.  Defined in dem_cases_real.cpp (needs dem_io).
std::vector<Case> real_cases();
ct_host::Terrain real_terrain();

// grid <-> map in long double, from a package's exact nm georeference
struct Geo {
    long double e0, n0, pe, pn, off, sc;
    explicit Geo(const ct_package &p)
        : e0(p.origin_e_nm * 1e-9L), n0(p.origin_n_nm * 1e-9L), pe(p.posting_e_nm * 1e-9L),
          pn(p.posting_n_nm * 1e-9L), off(p.height_offset_nm * 1e-9L), sc(p.height_scale_nm * 1e-9L)
    {
    }
    void to_map(long double x, long double y, long double z, long double m[3]) const
    {
        m[0] = e0 + (x + 0.5L) * pe;
        m[1] = n0 + (y + 0.5L) * pn;
        m[2] = off + z * sc;
    }
    void to_grid(const long double m[3], long double g[3]) const
    {
        g[0] = (m[0] - e0) / pe - 0.5L;
        g[1] = (m[1] - n0) / pn - 0.5L;
        g[2] = (m[2] - off) / sc;
    }
};

// Polyline segments that start just under the surface after the polyline
// entered (a bend of c = -4, R = 2^40 nm and a 0.1 mm chord): 1 mm height
// codes on 30 m posts, and five rays found by a search (test_bend on a
// package, test_tiles over a set).
inline ct_host::Terrain below_after_entered_terrain()
{
    return make_terrain(40, 40, smooth(40, 40, 5, 1000, 30000), 0.001);
}
const ct_ray kBelowAfterEnteredRays[5] = {
    {1463966, 1863104, 824113802, -11723337624, -8935396427, -1099511627776},
    {1094272, 1384564, 487285953, -2179200295, -1912324554, -1099511627776},
    {895832, 844974, 639287769, -1769281208, 4330961408, -1099511627776},
    {1032338, 2035326, 661998285, 10652333117, 8898833412, -1099511627776},
    {524396, 1695986, 818069374, 3617659896, -126108301, -1099511627776},
};

// t mirror-tiled to w x h posts (every other copy flipped, so heights stay
// continuous across the seams); the voids are dropped.
inline ct_host::Terrain mirror_tiled(const ct_host::Terrain &t, int w, int h)
{
    ct_host::Terrain b = t;
    b.width = w;
    b.height = h;
    b.codes.resize((size_t)w * h);
    b.void_post.clear();
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            int pi = i % (2 * t.width), pj = j % (2 * t.height);
            if (pi >= t.width) pi = 2 * t.width - 1 - pi;
            if (pj >= t.height) pj = 2 * t.height - 1 - pj;
            b.codes[(size_t)j * w + i] = t.at(pi, pj);
        }
    return b;
}

// ---- ray families ---------------------------------------------------------

enum Family {
    NADIR, OBLIQUE, GRAZING, HORIZONTAL, RISING, VERTICAL, GRIDLINE, DIAGONAL, THROUGH_POST, BELOW_START,
    OUTSIDE, FAMILY_COUNT
};

inline const char *family_name(Family f)
{
    static const char *n[] = {"nadir", "oblique", "grazing", "horizontal", "rising", "vertical",
                              "gridline", "diagonal", "through_post", "below", "outside"};
    return n[f];
}

inline double surf(const ct_host::Terrain &t, double x, double y)
{
    int i = std::min(t.width - 2, std::max(0, (int)std::floor(x)));
    int j = std::min(t.height - 2, std::max(0, (int)std::floor(y)));
    double u = x - i, v = y - j;
    double h00 = t.at(i, j), h10 = t.at(i + 1, j), h01 = t.at(i, j + 1), h11 = t.at(i + 1, j + 1);
    return h00 + (h10 - h00) * u + (h01 - h00) * v + (h11 - h10 - h01 + h00) * u * v;
}

// metric direction (azimuth in the grid frame, elevation angle) -> grid units
inline void metric_dir(const ct_host::Terrain &t, double az, double elev, double out[3])
{
    double post = std::fabs(t.geo.posting_e);
    out[0] = std::cos(az) * std::cos(elev) / post;
    out[1] = std::sin(az) * std::cos(elev) / post;
    out[2] = std::sin(elev) / t.height_scale_m;
}

inline ct_ray to_ray(double x, double y, double z, const double d[3])
{
    ct_ray r;
    r.x_q16 = std::llround(x * 65536.0);
    r.y_q16 = std::llround(y * 65536.0);
    r.z_q16 = std::llround(z * 65536.0);
    double m = std::max(std::fabs(d[0]), std::max(std::fabs(d[1]), std::fabs(d[2])));
    double s = 1099511627776.0 / m;  // 2^40
    r.dx = std::llround(d[0] * s);
    r.dy = std::llround(d[1] * s);
    r.dz = std::llround(d[2] * s);
    return r;
}

// The terrain's codes as the reference tracer's height field.
inline ref::Dem ref_dem(const ct_host::Terrain &t)
{
    ref::Dem d;
    d.w = t.width;
    d.h = t.height;
    d.z.assign(t.codes.begin(), t.codes.end());
    return d;
}

inline void minmax(const ct_host::Terrain &t, double *lo, double *hi)
{
    auto mm = std::minmax_element(t.codes.begin(), t.codes.end());
    *lo = *mm.first;
    *hi = *mm.second;
}

// A ray of family f over terrain t whose lowest and highest codes are lo
// and hi (minmax: pass them when drawing many rays over a large DEM).
inline ct_ray make_ray(const ct_host::Terrain &t, Family f, ct_rng *r, double lo, double hi)
{
    double cw = t.width - 1, ch = t.height - 1;
    double x = ct_rng_unit(r) * cw, y = ct_rng_unit(r) * ch, az = ct_rng_unit(r) * 6.283185307179586;
    double d[3];
    double span = std::max(1.0, hi - lo);
    switch (f) {
    case NADIR: {
        double tilt = (ct_rng_u64(r) & 1) ? 0.0 : ct_rng_unit(r) * 5.0 * M_PI / 180;
        metric_dir(t, az, -M_PI / 2 + tilt, d);
        if (tilt == 0) d[0] = d[1] = 0;
        return to_ray(x, y, hi + 1 + ct_rng_unit(r) * span, d);
    }
    case OBLIQUE: {
        metric_dir(t, az, -(20 + 40 * ct_rng_unit(r)) * M_PI / 180, d);
        return to_ray(x, y, hi + ct_rng_unit(r) * span, d);
    }
    case GRAZING: {
        metric_dir(t, az, -(0.001 + 1.999 * ct_rng_unit(r)) * M_PI / 180, d);
        double s = surf(t, x, y);
        return to_ray(x, y, s + ct_rng_unit(r) * (hi + 1 - s), d);
    }
    case HORIZONTAL: {
        metric_dir(t, az, 0.0, d);
        d[2] = 0;
        double s = surf(t, x, y);
        return to_ray(x, y, s + ct_rng_unit(r) * (hi + 1 - s), d);
    }
    case RISING: {
        metric_dir(t, az, (0.01 + 30 * ct_rng_unit(r)) * M_PI / 180, d);
        double s = surf(t, x, y);
        return to_ray(x, y, s + ct_rng_unit(r) * 0.01 * span, d);
    }
    case VERTICAL: {
        d[0] = d[1] = 0;
        d[2] = (ct_rng_u64(r) & 1) ? 1 : -1;
        return to_ray(x, y, lo - 2 + ct_rng_unit(r) * (span + 4), d);
    }
    case GRIDLINE: {
        // exactly along a grid line, through posts
        double el = -(ct_rng_unit(r) * 10) * M_PI / 180;
        int axis = (int)(ct_rng_u64(r) & 1), sg = (ct_rng_u64(r) & 1) ? 1 : -1;
        metric_dir(t, axis ? M_PI / 2 * sg : (sg > 0 ? 0 : M_PI), el, d);
        if (axis) { d[0] = 0; x = std::floor(x); } else { d[1] = 0; y = std::floor(y); }
        double s = surf(t, x, y);
        return to_ray(x, y, s + ct_rng_unit(r) * (hi + 1 - s), d);
    }
    case DIAGONAL: {
        double el = -(ct_rng_unit(r) * 10) * M_PI / 180;
        int q = (int)(ct_rng_u64(r) & 3);
        metric_dir(t, M_PI / 4 + q * M_PI / 2, el, d);
        double m = std::fabs(d[0]);
        d[0] = std::copysign(m, d[0]);
        d[1] = std::copysign(m, d[1]);
        if (ct_rng_u64(r) & 1) { x = std::floor(x); y = std::floor(y); }
        double s = surf(t, x, y);
        return to_ray(x, y, s + ct_rng_unit(r) * (hi + 1 - s), d);
    }
    case THROUGH_POST: {
        // exactly through post (i, j) at its height + delta, delta in {0, +-1 q16, small}
        int i = (int)ct_rng_range(r, 0, t.width - 1), j = (int)ct_rng_range(r, 0, t.height - 1);
        int64_t pz = (int64_t)t.at(i, j) * 65536;
        int64_t dd[5] = {0, 0, 1, -1, (int64_t)ct_rng_range(r, -5000, 5000)};
        pz += dd[ct_rng_range(r, 0, 4)];
        int64_t D[3] = {ct_rng_range(r, -(1 << 20), 1 << 20), ct_rng_range(r, -(1 << 20), 1 << 20),
                        ct_rng_range(r, -(1 << 18), 1 << 10)};
        if (ct_rng_range(r, 0, 3) == 0) D[1] = 0;
        if (ct_rng_range(r, 0, 3) == 0) D[0] = D[1] == 0 ? 1 << 19 : D[1];
        if (D[0] == 0 && D[1] == 0) D[0] = 1 << 19;
        int64_t k = ct_rng_range(r, 1, 40);  // origin k*D back: up to 40 * 2^20 q16 = 640 cells
        ct_ray ray;
        ray.x_q16 = (int64_t)i * 65536 - k * D[0];
        ray.y_q16 = (int64_t)j * 65536 - k * D[1];
        ray.z_q16 = pz - k * D[2];
        ray.dx = D[0];
        ray.dy = D[1];
        ray.dz = D[2];
        return ray;
    }
    case BELOW_START: {
        double el = (ct_rng_unit(r) - 0.5) * M_PI;
        metric_dir(t, az, el, d);
        double s = surf(t, x, y);
        return to_ray(x, y, s - 1e-4 - ct_rng_unit(r) * 0.05 * span, d);
    }
    case OUTSIDE:
    default: {
        // from outside the tile's box towards a random point in it
        double tx = x, ty = y, tz = lo + ct_rng_unit(r) * (span + 2);
        double dist = (1 + ct_rng_unit(r)) * std::max(cw, ch);
        double el = (ct_rng_unit(r) * 0.3) * (ct_rng_u64(r) % 3 == 0 ? 3 : 1);
        double ox = tx + dist * std::cos(az), oy = ty + dist * std::sin(az);
        double post = std::fabs(t.geo.posting_e);
        double oz = tz + dist * post * std::tan(el) / t.height_scale_m;
        double dv[3] = {tx - ox, ty - oy, tz - oz};
        return to_ray(ox, oy, oz, dv);
    }
    }
}

inline ct_ray make_ray(const ct_host::Terrain &t, Family f, ct_rng *r)
{
    double lo, hi;
    minmax(t, &lo, &hi);
    return make_ray(t, f, r, lo, hi);
}

// ---- cameras --------------------------------------------------------------

// A pinhole lens of w x h pixels, focal length f pixels, centred ((w - 1) / 2,
// (h - 1) / 2).
inline ct_lens centred_pinhole(uint32_t w, uint32_t h, int64_t f)
{
    ct_lens lens{};
    lens.model = CT_LENS_PINHOLE;
    lens.width = w;
    lens.height = h;
    lens.fx_q32 = lens.fy_q32 = f << 32;
    lens.cx_q32 = (int64_t)(w - 1) << 31;
    lens.cy_q32 = (int64_t)(h - 1) << 31;
    return lens;
}

// A camera's own unprojection (ct_camera_unproject) at nu x nv nodes from
// pixel (u0, v0), step apart (all Q16), as an unprojection grid; a node it
// refuses stays (0, 0, 0).  *nodes holds the rays and must outlive the grid.
inline ct_unproject_grid grid_from_camera(const ct_camera &cam, int64_t u0_q16, int64_t v0_q16, int64_t step_q16,
                                          uint32_t nu, uint32_t nv, std::vector<int32_t> *nodes)
{
    nodes->assign(3u * (size_t)nu * nv, 0);
    for (uint32_t j = 0; j < nv; ++j)
        for (uint32_t i = 0; i < nu; ++i) {
            int32_t r[3];
            if (ct_camera_unproject(&cam, u0_q16 + (int64_t)i * step_q16, v0_q16 + (int64_t)j * step_q16, r,
                                    nullptr) == CT_OK)
                for (uint32_t c = 0; c < 3u; ++c) (*nodes)[3u * ((size_t)j * nu + i) + c] = r[c];
        }
    ct_unproject_grid g;
    g.nu = nu;
    g.nv = nv;
    g.u0_q16 = u0_q16;
    g.v0_q16 = v0_q16;
    g.step_q16 = step_q16;
    g.rays_q30 = nodes->data();
    g.rays_len = nodes->size();
    return g;
}

// Every step-th pixel of a w x h image, row by row, as (u, v) Q16 pairs.
inline std::vector<int64_t> pixel_grid(unsigned w, unsigned h, unsigned step)
{
    std::vector<int64_t> uv;
    for (unsigned v = 0; v < h; v += step)
        for (unsigned u = 0; u < w; u += step) {
            uv.push_back((int64_t)u << 16);
            uv.push_back((int64_t)v << 16);
        }
    return uv;
}

// An angle in degrees as ct_quat_from_ypr takes it (radians, Q61).
inline int64_t deg_q61(double deg) { return std::llround(deg * (M_PI / 180) * 2305843009213693952.0); }

// Does the ray cross the interior of the tile's box (long double slab test)?
inline bool ray_crosses_box(const ct_host::Terrain &t, const ct_ray &r)
{
    long double lo = 0, hi = 1e30L;
    long double o[3] = {(long double)r.x_q16, (long double)r.y_q16, (long double)r.z_q16};
    long double d[3] = {(long double)r.dx, (long double)r.dy, (long double)r.dz};
    double zl, zh;
    minmax(t, &zl, &zh);
    long double b0[3] = {0, 0, -1e30L}, b1[3] = {(t.width - 1) * 65536.0L, (t.height - 1) * 65536.0L, (zh + 1) * 65536.0L};
    for (int k = 0; k < 3; ++k) {
        if (d[k] == 0) {
            if (!(o[k] > b0[k] && o[k] < b1[k])) return false;
            continue;
        }
        long double a = (b0[k] - o[k]) / d[k], b = (b1[k] - o[k]) / d[k];
        if (a > b) std::swap(a, b);
        lo = std::max(lo, a);
        hi = std::min(hi, b);
    }
    return hi - lo > 1e-12L * std::max((long double)1, hi);
}

}  // namespace dem_cases
