// gen_vectors.cpp -- host generator of the MCU bit-identity vectors.
//
//   gen_vectors <out.c> [rays-per-package]
//
// Builds a small synthetic terrain, turns it into packages (N = 8, r = 2 and
// N = 24, r = 1), traces a few hundred rays per package with every method
// on the HOST build of the library (native __int128) and writes everything
// -- package bytes, rays, prepared rays, every ct_hit field, map-frame
// conversions, fixed-point results, and four cameras over the packages
// (lenses, an unprojection grid, poses, straight and bent rays: every
// ct_geolocate output, which the targets' batch must also reproduce), geoid
// undulations (ct_geoid_at on synthetic grids; a package with a datum
// section on UTM 17N and ct_package_geoid at map points) -- as a
// C99 data file (ct_vectors.h).
// The MCU program re-computes all of it with the Cortex-M build and requires
// bit-identical results.
//
// Package source: ct_host::build_package, with the slice builder when
// CT_GEN_USE_BUILDER is defined (real cones, so cone jumps run on the MCU),
// else (and as the fallback when that build fails) with
// PptBuilder::Degenerate: exact mipmap, apex = tallest corner of each
// coarse cell, every angle code 0 (degenerate cone, always valid).
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
extern "C" {
#include "fixed.h"
}
#include "ct_vectors.h"
#include "le.hpp"
#include "terrain.hpp"
#include "tileset.hpp"

namespace {

const int64_t ONE16 = 65536;

// ------------------------------------------------------------------ rng
struct Rng {
    uint64_t s;
    explicit Rng(uint64_t seed) : s(seed * 0x9E3779B97F4A7C15ull + 0x1234567ull) {}
    uint64_t u64()
    {
        uint64_t x = s;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        s = x;
        return x * 0x2545F4914F6CDD1Dull;
    }
    int64_t range(int64_t lo, int64_t hi) { return lo + (int64_t)(u64() % (uint64_t)(hi - lo + 1)); }
    double unit() { return (double)(u64() >> 11) * (1.0 / 9007199254740992.0); }
    double uni(double lo, double hi) { return lo + (hi - lo) * unit(); }
    bool chance(int pct) { return range(0, 99) < pct; }
};

[[noreturn]] void die(const std::string &m)
{
    std::fprintf(stderr, "gen_vectors: %s\n", m.c_str());
    std::exit(1);
}

// ------------------------------------------------------------------ terrain
const int W = 33, H = 29;  // posts: 32 x 28 fine cells
const double POSTING_M = 30.0, SCALE_M = 0.125, OFFSET_M = -100.0;
const double ORIGIN_E_M = 500000.0, ORIGIN_N_M = 4200000.0;
const int EPSG = 32633;

struct Dem {
    std::vector<uint16_t> codes;  // row-major
    std::vector<uint8_t> void_post;
    uint16_t at(int i, int j) const { return codes[(size_t)j * W + (size_t)i]; }
};

// Varied terrain: rolling hills, a sharp ridge, a pit, a flat plateau (exact
// ties), a one-post spike, a cliff, a saddle, and a small nodata patch.
Dem make_dem()
{
    Dem d;
    d.codes.resize((size_t)W * H);
    d.void_post.assign((size_t)W * H, 0);
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            double h = 220.0 + 45.0 * std::sin(i * 0.31) * std::cos(j * 0.23) + 12.0 * std::sin(i * 1.7 + j * 0.9);
            h += 90.0 * std::exp(-std::pow((i - 2.0 * j / 3.0 - 6.0) / 1.6, 2));  // ridge
            h -= 70.0 * std::exp(-((i - 24.0) * (i - 24.0) + (j - 20.0) * (j - 20.0)) / 10.0);  // pit
            if (i >= 18 && i <= 23 && j >= 3 && j <= 8) {
                h = 300.0;  // plateau: exactly flat
            }
            if (i >= 8 && i <= 12 && j >= 20) {
                h += 80.0;  // cliff block
            }
            h += 0.02 * (i - 16) * (j - 14) * 3.0;  // saddle twist
            if (i == 27 && j == 6) {
                h = 520.0;  // spike
            }
            long c = std::lround((h - OFFSET_M) / SCALE_M);
            if (c < 0 || c > 65535) {
                die("terrain code out of range");
            }
            d.codes[(size_t)j * W + i] = (uint16_t)c;
        }
    }
    // nodata patch: posts (3..4, 24..25); the fill is the floor of the patch
    for (int j = 24; j <= 25; ++j) {
        for (int i = 3; i <= 4; ++i) {
            d.void_post[(size_t)j * W + i] = 1;
            d.codes[(size_t)j * W + i] = d.at(2, 23);
        }
    }
    return d;
}

// ------------------------------------------------------------------ packages
using ct_host::put32;

int64_t nm(double m) { return (int64_t)std::llround(m * 1e9); }

const char *builder_name(ct_host::PptBuilder b)
{
    return b == ct_host::PptBuilder::Degenerate ? "degenerate cones" : "slice builder";
}

ct_host::Terrain dem_terrain(const Dem &d)
{
    ct_host::Terrain t;
    t.width = W;
    t.height = H;
    t.codes = d.codes;
    t.void_post = d.void_post;
    t.geo.origin_e = ORIGIN_E_M;
    t.geo.origin_n = ORIGIN_N_M;
    t.geo.posting_e = POSTING_M;
    t.geo.posting_n = -POSTING_M;
    t.geo.epsg = EPSG;
    t.height_offset_m = OFFSET_M;
    t.height_scale_m = SCALE_M;
    return t;
}

std::vector<uint8_t> build_with_builder(const Dem &d, int n, int r, ct_host::PptBuilder b)
{
    const ct_host::Terrain t = dem_terrain(d);
    ct_host::BuildOptions o;
    o.sectors = n;
    o.reduce = r;
    o.threads = 1;
    o.builder = b;
    ct_host::BuildStats st;
    std::vector<uint8_t> bytes = ct_host::build_package(t, o, &st);
    std::fprintf(stderr, "gen_vectors: build_package (%s) N=%d r=%d: %zu bytes, %zu of %zu cones degenerate\n",
                 builder_name(b), n, r, bytes.size(), st.degenerate_cones, st.cones);
    return bytes;
}

// ------------------------------------------------------------------ vertical datum
// Geoid grids as a datum section stores them (conetrace.h): node (i, j) at
// (lat0 - j step, lon0 + i step), Q61 radians, values in micrometres.
struct GGrid {
    uint32_t w = 0, h = 0;
    int64_t lat0 = 0, lon0 = 0, step = 0;
    std::vector<int32_t> um;              // w * h, row 0 north
    bool null_values = false;             // an invalid grid: values NULL
    std::vector<uint8_t> bytes;           // um, little-endian
    void pack()
    {
        bytes.assign(4 * um.size(), 0);
        for (size_t k = 0; k < um.size(); ++k) put32(bytes, 4 * k, (uint32_t)um[k]);
    }
    ct_geoid_grid view() const
    {
        ct_geoid_grid g{};
        g.w = w;
        g.h = h;
        g.lat0_q61 = lat0;
        g.lon0_q61 = lon0;
        g.step_q61 = step;
        g.values = null_values ? nullptr : bytes.data();
        return g;
    }
};

int64_t q61_deg(long double deg)
{
    return (int64_t)std::llround(deg * 3.14159265358979323846264338L / 180 * std::ldexp(1.0L, 61));
}

// The datum package: a tiny tile on UTM 17N (western North Carolina),
// heights declared EGM96 (so ellipsoidal in the package), resampled from
// EPSG:4326, with a 4 x 4 EGM96-like geoid at 15' around it.
const int DATUM_EPSG = 32617, DATUM_SOURCE_EPSG = 4326, DW = 9, DH = 9;

GGrid datum_geoid()
{
    GGrid g;
    g.w = g.h = 4;
    g.lat0 = q61_deg(36.0L);
    g.lon0 = q61_deg(-82.0L);
    g.step = q61_deg(0.25L);
    g.um = {-31512345, -31204871, -30877210, -30561094, -31873026, -31590412, -31266583, -30938817,
            -32215390, -31943177, -31631409, -31310266, -32547718, -32284935, -31988021, -31671532};
    g.pack();
    return g;
}

std::vector<uint8_t> build_datum_with_builder(const GGrid &gg, double oe, double on, ct_host::PptBuilder b)
{
    ct_host::Terrain t;
    t.width = DW;
    t.height = DH;
    t.codes.resize((size_t)DW * DH);
    for (int j = 0; j < DH; ++j)
        for (int i = 0; i < DW; ++i) {
            double h = 420.0 + 25.0 * std::sin(i * 0.7) * std::cos(j * 0.5) + 3.0 * i;
            t.codes[(size_t)j * DW + i] = (uint16_t)std::lround(h / SCALE_M);
        }
    t.geo.origin_e = oe;
    t.geo.origin_n = on;
    t.geo.posting_e = POSTING_M;
    t.geo.posting_n = -POSTING_M;
    t.geo.epsg = DATUM_EPSG;
    t.geo.source_epsg = DATUM_SOURCE_EPSG;
    t.height_offset_m = 0.0;
    t.height_scale_m = SCALE_M;
    t.vdatum = CT_VDATUM_EGM96;
    t.geoid.w = (int)gg.w;
    t.geoid.h = (int)gg.h;
    t.geoid.lat0_q61 = gg.lat0;
    t.geoid.lon0_q61 = gg.lon0;
    t.geoid.step_q61 = gg.step;
    t.geoid.um = gg.um;
    ct_host::BuildOptions o;
    o.sectors = 8;
    o.reduce = 2;
    o.threads = 1;
    o.builder = b;
    ct_host::BuildStats st;
    std::vector<uint8_t> bytes = ct_host::build_package(t, o, &st);
    std::fprintf(stderr, "gen_vectors: build_package (%s) datum package (EPSG:%d, EGM96): %zu bytes\n",
                 builder_name(b), DATUM_EPSG, bytes.size());
    return bytes;
}

// The synthetic grids of the ct_geoid_at vectors: EGM96-like around
// Munich, one across the antimeridian, one of extreme values and extreme
// extent (north pole, the largest step, (w - 1) step = 2^62), one of the
// smallest step at the equator, and three invalid ones.
std::vector<GGrid> geoid_grids()
{
    std::vector<GGrid> v;
    GGrid g;
    g.w = g.h = 4;
    g.lat0 = q61_deg(48.5L);
    g.lon0 = q61_deg(11.0L);
    g.step = q61_deg(0.25L);
    g.um = {47912345, 48104562, 48296011, 48477236, 47621908, 47815530, 48003377, 48190245,
            47322019, 47507664, 47698212, 47879011, 47015432, 47201188, 47388906, 47570013};
    v.push_back(g);
    g = GGrid();
    g.w = g.h = 4;
    g.lat0 = q61_deg(-16.0L);
    g.lon0 = q61_deg(179.75L);
    g.step = q61_deg(0.25L);
    g.um = {57120334, 57388120, 57650712, 57901446, 56876204, 57140009, 57399512, 57648230,
            56630871, 56890453, 57146287, 57392045, 56381652, 56638117, 56890946, 57133602};
    v.push_back(g);
    g = GGrid();
    g.w = 17;
    g.h = 3;
    g.lat0 = CT_PI_Q61 / 2;
    g.lon0 = -CT_PI_Q61;
    g.step = CT_GEOID_MAX_STEP_Q61;
    for (uint32_t k = 0; k < g.w * g.h; ++k)
        g.um.push_back(k % 3 == 0 ? INT32_MIN : k % 3 == 1 ? INT32_MAX : (k % 2 ? -1 : 1));
    v.push_back(g);
    g = GGrid();
    g.w = g.h = 4;
    g.lat0 = q61_deg(0.001L);
    g.lon0 = q61_deg(-0.001L);
    g.step = CT_GEOID_MIN_STEP_Q61;
    g.um = {17161234, 17161251, 17161270, 17161288, 17161199, 17161217, 17161236, 17161254,
            17161165, 17161183, 17161202, 17161220, 17161131, 17161149, 17161168, 17161186};
    v.push_back(g);
    // invalid: one column; a step below the smallest; no values
    g = v[0];
    g.w = 1;
    g.um.resize(4);
    v.push_back(g);
    g = v[0];
    g.step = CT_GEOID_MIN_STEP_Q61 - 1;
    v.push_back(g);
    g = v[0];
    g.null_values = true;
    v.push_back(g);
    for (GGrid &x : v) x.pack();
    return v;
}

int64_t wrap_lon(int64_t lon)
{
    const uint64_t turn = 2u * (uint64_t)CT_PI_Q61;  // 2 pi > INT64_MAX in Q61
    if (lon > CT_PI_Q61) return (int64_t)((uint64_t)lon - turn);
    if (lon < -CT_PI_Q61) return (int64_t)((uint64_t)lon + turn);
    return lon;
}

// Points of one grid: nodes, the last row and column, just outside each
// side, inside, arbitrary int64.
std::vector<ct_vec_geoid> geoid_points(Rng &g, const std::vector<GGrid> &grids)
{
    std::vector<ct_vec_geoid> out;
    for (uint32_t gi = 0; gi < grids.size(); ++gi) {
        const GGrid &G = grids[gi];
        const uint64_t wid = (uint64_t)(G.w > 1 ? G.w - 1 : 1) * (uint64_t)G.step;
        const uint64_t hei = (uint64_t)(G.h - 1) * (uint64_t)G.step;
        const int64_t latS = G.lat0 - (int64_t)hei, lonE = G.lon0 + (int64_t)wid;
        const bool valid = gi < 4;
        const int n = valid ? 12 : 2;
        for (int k = 0; k < n; ++k) {
            ct_vec_geoid v{};
            v.grid = gi;
            int64_t lat = G.lat0 - (int64_t)(g.u64() % (hei + 1)), lon = G.lon0 + (int64_t)(g.u64() % (wid + 1));
            switch (valid ? k : 8 + k) {
            case 0: lat = G.lat0; lon = G.lon0; break;                                  // node (0, 0)
            case 1: lat = latS; lon = lonE; break;                                      // the last corner
            case 2: lat = latS; break;                                                  // the last row
            case 3: lon = lonE; break;                                                  // the last column
            case 4: lat = G.lat0 + 1; break;                                            // just north
            case 5: lat = latS - 1; break;                                              // just south
            case 6: lon = G.lon0 - 1; break;                                            // just west
            case 7: lon = lonE + 1; break;                                              // just east
            case 10:                                                                    // on a node column
                lon = G.lon0 + (int64_t)(g.u64() % G.w) * G.step;
                break;
            case 11: lat = (int64_t)g.u64(); lon = (int64_t)g.u64(); break;             // anything
            default: break;                                                             // inside
            }
            v.lat_q61 = lat;
            v.lon_q61 = k == 11 ? lon : wrap_lon(lon);
            const ct_geoid_grid view = G.view();
            v.status = ct_geoid_at(&view, v.lat_q61, v.lon_q61, &v.n_nm);
            out.push_back(v);
        }
        if (gi == 1) {  // the antimeridian itself, both ways
            for (int s = 0; s < 2; ++s) {
                ct_vec_geoid v{};
                v.grid = gi;
                v.lat_q61 = G.lat0 - (int64_t)(g.u64() % (hei + 1));
                v.lon_q61 = s ? CT_PI_Q61 : -CT_PI_Q61;
                const ct_geoid_grid view = G.view();
                v.status = ct_geoid_at(&view, v.lat_q61, v.lon_q61, &v.n_nm);
                out.push_back(v);
            }
        }
    }
    return out;
}

// ------------------------------------------------------------------ rays
struct Pkg {
    std::string name;
    std::vector<uint8_t> bytes;
    ct_package p;
    uint32_t cone_codes = 0;
    std::vector<ct_vec_case> cases;
    std::vector<ct_vec_point> points;
};

int64_t surface_q16(const ct_package &p, int64_t x, int64_t y)
{
    int64_t z = 0;
    if (ct_surface_height(&p, x, y, &z) != CT_OK) die("ct_surface_height");
    return z;
}

// direction from azimuth (rad, grid frame) and elevation (rad, metric)
void dir_from_angles(const ct_package &p, double az, double el, double scale, ct_ray &r)
{
    double lsb_per_cell = (double)p.posting_e_nm / (double)p.height_scale_nm;
    r.dx = (int64_t)std::llround(std::cos(az) * scale);
    r.dy = (int64_t)std::llround(std::sin(az) * scale);
    r.dz = (int64_t)std::llround(std::tan(el) * lsb_per_cell * scale);
}

// The tile's extent as the ray kinds use it: cells in x and y, and a height
// just above its tallest post (Q16).
struct TileBox {
    int64_t cx, cy, top;
};

const double PI = 3.14159265358979323846;

// kind 0: a camera above the tile looking down
ct_ray ray_looking_down(Rng &g, const ct_package &p, const TileBox &b)
{
    ct_ray r{};
    r.x_q16 = g.range(-5 * ONE16, (b.cx + 5) * ONE16);
    r.y_q16 = g.range(-5 * ONE16, (b.cy + 5) * ONE16);
    r.z_q16 = b.top + g.range(0, 2500 * ONE16);
    dir_from_angles(p, g.uni(0, 2 * PI), -g.uni(2, 85) * PI / 180, g.uni(1e3, 1e9), r);
    return r;
}

// kind 1: grazing from just above the surface
ct_ray ray_grazing(Rng &g, const ct_package &p, const TileBox &b)
{
    ct_ray r{};
    int64_t x = g.range(ONE16, (b.cx - 1) * ONE16), y = g.range(ONE16, (b.cy - 1) * ONE16);
    r.x_q16 = x;
    r.y_q16 = y;
    r.z_q16 = surface_q16(p, x, y) + g.range(1, 64 * ONE16);
    dir_from_angles(p, g.uni(0, 2 * PI), g.uni(-6, 1.5) * PI / 180, g.uni(1e4, 1e8), r);
    return r;
}

// kind 2: from far outside, aimed exactly at a surface point
ct_ray ray_aimed_from_afar(Rng &g, const ct_package &p, const TileBox &b)
{
    ct_ray r{};
    double a = g.uni(0, 2 * PI), dist = g.uni(40, 400);
    int64_t tx = g.range(0, b.cx * ONE16), ty = g.range(0, b.cy * ONE16);
    int64_t tz = surface_q16(p, tx, ty);
    r.x_q16 = tx + (int64_t)std::llround(std::cos(a) * dist * ONE16);
    r.y_q16 = ty + (int64_t)std::llround(std::sin(a) * dist * ONE16);
    r.z_q16 = tz + (int64_t)std::llround(dist * g.uni(0.2, 600.0) * ONE16);
    r.dx = tx - r.x_q16;
    r.dy = ty - r.y_q16;
    r.dz = tz - r.z_q16;
    return r;
}

// kind 3: axis-aligned and exact diagonals, origins on grid lines / posts
ct_ray ray_on_grid_lines(Rng &g, const ct_package &p, const TileBox &b)
{
    ct_ray r{};
    const int64_t cx = b.cx, cy = b.cy;
    int64_t s = g.range(1, 1 << 20);
    int which = (int)g.range(0, 5);
    r.x_q16 = g.range(0, cx) * ONE16 + (g.chance(50) ? 0 : g.range(0, ONE16 - 1));
    r.y_q16 = g.range(0, cy) * ONE16 + (g.chance(50) ? 0 : g.range(0, ONE16 - 1));
    r.z_q16 = surface_q16(p, std::min(r.x_q16, cx * ONE16), std::min(r.y_q16, cy * ONE16)) + g.range(1, 400 * ONE16);
    int64_t sx = g.chance(50) ? 1 : -1, sy = g.chance(50) ? 1 : -1;
    r.dx = which == 0 ? 0 : (which == 1 ? sx * s : sx * s);
    r.dy = which == 0 ? sy * s : (which == 1 ? 0 : sy * s);
    if (which >= 3) {  // off-diagonal small integer slopes
        r.dx = sx * s * g.range(1, 3);
        r.dy = sy * s * g.range(1, 3);
    }
    r.dz = -s * g.range(0, 300);
    return r;
}

// kind 4: vertical, down and up, some on posts and lines
ct_ray ray_vertical(Rng &g, const TileBox &b)
{
    ct_ray r{};
    r.x_q16 = g.chance(40) ? g.range(0, b.cx) * ONE16 : g.range(0, b.cx * ONE16);
    r.y_q16 = g.chance(40) ? g.range(0, b.cy) * ONE16 : g.range(0, b.cy * ONE16);
    r.z_q16 = b.top + g.range(-ONE16, 500 * ONE16);
    r.dz = g.chance(80) ? -g.range(1, INT64_C(1) << 40) : g.range(1, 1000);
    if (g.chance(15)) {  // vertical outside the tile
        r.x_q16 = -g.range(1, 1000);
    }
    return r;
}

// kind 5: starts below / exactly on the surface
ct_ray ray_from_the_surface(Rng &g, const ct_package &p, const TileBox &b)
{
    ct_ray r{};
    int64_t x = g.range(0, b.cx) * ONE16, y = g.range(0, b.cy) * ONE16;
    if (g.chance(50)) {
        x += g.range(0, ONE16 - 1);
        y += g.range(0, ONE16 - 1);
        x = std::min(x, b.cx * ONE16);
        y = std::min(y, b.cy * ONE16);
    }
    int64_t s = surface_q16(p, x, y);
    r.x_q16 = x;
    r.y_q16 = y;
    r.z_q16 = g.chance(50) ? s : s - g.range(1, 50 * ONE16);
    dir_from_angles(p, g.uni(0, 2 * PI), g.uni(-40, 40) * PI / 180, 1e6, r);
    return r;
}

// kind 6: upward and level rays over the tile (misses)
ct_ray ray_upward(Rng &g, const ct_package &p, const TileBox &b)
{
    ct_ray r{};
    r.x_q16 = g.range(-10 * ONE16, (b.cx + 10) * ONE16);
    r.y_q16 = g.range(-10 * ONE16, (b.cy + 10) * ONE16);
    r.z_q16 = b.top + g.range(-50 * ONE16, 50 * ONE16);
    dir_from_angles(p, g.uni(0, 2 * PI), g.uni(0, 30) * PI / 180, 1e7, r);
    return r;
}

// kind 7: extreme scales and invalid rays
ct_ray ray_extreme(Rng &g, const TileBox &b)
{
    ct_ray r{};
    int v = (int)g.range(0, 5);
    r.x_q16 = g.range(0, b.cx * ONE16);
    r.y_q16 = g.range(0, b.cy * ONE16);
    r.z_q16 = b.top + g.range(0, 100 * ONE16);
    if (v == 0) {  // huge direction
        r.dx = g.range(-(INT64_C(1) << 62), INT64_C(1) << 62);
        r.dy = g.range(-(INT64_C(1) << 62), INT64_C(1) << 62);
        r.dz = -(INT64_C(1) << 62) + g.range(0, 1000);
    } else if (v == 1) {  // tiny direction
        r.dx = g.range(-1, 1);
        r.dy = g.range(-1, 1);
        r.dz = -1;
    } else if (v == 2) {  // origin far away, near the limit
        r.x_q16 = CT_MAX_ORIGIN_Q16 - g.range(0, 1000);
        r.y_q16 = -CT_MAX_ORIGIN_Q16 + g.range(0, 1000);
        r.z_q16 = CT_MAX_ORIGIN_Q16 / 2;
        r.dx = -(INT64_C(1) << 50);
        r.dy = INT64_C(1) << 50;
        r.dz = -(INT64_C(1) << 46);
    } else if (v == 3) {  // origin beyond the limit
        r.x_q16 = CT_MAX_ORIGIN_Q16 + 1;
        r.dx = -1;
        r.dz = -1;
    } else if (v == 4) {  // zero direction
        r.dx = r.dy = r.dz = 0;
    } else {  // direction beyond 2^62
        r.dx = INT64_MAX;
        r.dz = -1;
    }
    return r;
}

// kind 8: aimed exactly at posts, edge midpoints, plateau points
ct_ray ray_aimed_at_posts(Rng &g, const ct_package &p, const TileBox &b)
{
    ct_ray r{};
    int64_t tx = g.range(0, b.cx) * ONE16, ty = g.range(0, b.cy) * ONE16;
    if (g.chance(30)) tx += ONE16 / 2;
    if (g.chance(30)) ty += ONE16 / 2;
    if (g.chance(25)) {  // the plateau (flat, exact ties)
        tx = g.range(18, 23) * ONE16 + g.range(0, 5) * (ONE16 / 4);
        ty = g.range(3, 8) * ONE16;
    }
    tx = std::min(tx, b.cx * ONE16);
    ty = std::min(ty, b.cy * ONE16);
    int64_t tz = surface_q16(p, tx, ty);
    int64_t ddx = g.range(-20, 20) * ONE16 / 4, ddy = g.range(-20, 20) * ONE16 / 4;
    int64_t ddz = g.range(g.chance(20) ? 0 : 1, 3000) * ONE16;
    r.x_q16 = tx - ddx;
    r.y_q16 = ty - ddy;
    r.z_q16 = tz + ddz;
    r.dx = ddx;
    r.dy = ddy;
    r.dz = -ddz;
    if (r.dx == 0 && r.dy == 0 && r.dz == 0) r.dz = -1;
    return r;
}

// kind 9: long low rays across the whole tile
ct_ray ray_long_low(Rng &g, const ct_package &p, const TileBox &b)
{
    ct_ray r{};
    bool alongx = g.chance(50);
    r.x_q16 = alongx ? -g.range(0, 3 * ONE16) : g.range(0, b.cx * ONE16);
    r.y_q16 = alongx ? g.range(0, b.cy * ONE16) : (b.cy * ONE16 + g.range(0, 3 * ONE16));
    r.z_q16 = ((int64_t)p.hmin + (p.hmax - p.hmin) / 2) * ONE16 + g.range(0, (p.hmax - p.hmin) / 2 * ONE16);
    dir_from_angles(p, alongx ? g.uni(-0.6, 0.6) : g.uni(-PI / 2 - 0.6, -PI / 2 + 0.6), g.uni(-2, 0.2) * PI / 180,
                    g.uni(1e5, 1e9), r);
    return r;
}

// A ray of the given kind (0..9, pick_kind's shares) over package p.
ct_ray make_ray(Rng &g, const ct_package &p, int kind)
{
    const TileBox b = {p.cells_x, p.cells_y, ((int64_t)p.hmax + 1) * ONE16};
    switch (kind) {
    case 0: return ray_looking_down(g, p, b);
    case 1: return ray_grazing(g, p, b);
    case 2: return ray_aimed_from_afar(g, p, b);
    case 3: return ray_on_grid_lines(g, p, b);
    case 4: return ray_vertical(g, b);
    case 5: return ray_from_the_surface(g, p, b);
    case 6: return ray_upward(g, p, b);
    case 7: return ray_extreme(g, b);
    case 8: return ray_aimed_at_posts(g, p, b);
    default: return ray_long_low(g, p, b);
    }
}

const int KIND_PCT[10] = {24, 14, 10, 10, 5, 6, 5, 6, 12, 8};  // sums to 100

int pick_kind(Rng &g)
{
    int v = (int)g.range(0, 99), k = 0;
    while (k < 9 && v >= KIND_PCT[k]) v -= KIND_PCT[k++];
    return k;
}

ct_vec_case trace_case(const ct_package &p, const ct_ray &ray)
{
    ct_vec_case c;
    std::memset(&c, 0, sizeof c);
    c.ray = ray;
    c.prep_status = ct_ray_prepare(&p, &ray, &c.prep);
    for (int m = 0; m < CT_METHOD_COUNT; ++m) {
        c.status[m] = ct_trace(&p, &ray, (ct_method)m, &c.hit[m]);
        if (c.prep_status >= 0) {  // the prepared path must agree on the host already
            ct_hit h2;
            std::memset(&h2, 0, sizeof h2);
            ct_status s2 = ct_trace_prepared(&p, &c.prep, (ct_method)m, &h2);
            if (s2 != c.status[m] || h2.t_q26 != c.hit[m].t_q26 || h2.steps != c.hit[m].steps) {
                die("host: ct_trace and ct_trace_prepared disagree");
            }
        }
    }
    return c;
}

ct_vec_point make_point(Rng &g, const ct_package &p, int k)
{
    ct_vec_point q;
    std::memset(&q, 0, sizeof q);
    const int64_t cx = p.cells_x, cy = p.cells_y;
    if (k < 6) {  // posts and corners
        q.x = (k & 1) ? cx * ONE16 : g.range(0, cx) * ONE16;
        q.y = (k & 2) ? cy * ONE16 : g.range(0, cy) * ONE16;
    } else if (k < 30) {
        q.x = g.range(0, cx * ONE16);
        q.y = g.range(0, cy * ONE16);
    } else {  // outside the tile / far away
        q.x = g.range(-(INT64_C(1) << 40), INT64_C(1) << 40);
        q.y = g.range(-(INT64_C(1) << 40), INT64_C(1) << 40);
    }
    q.z = g.range(-(INT64_C(1) << 30), INT64_C(1) << 34);
    q.g2m_status = ct_grid_to_map(&p, q.x, q.y, q.z, &q.e, &q.n, &q.h);
    q.m2g_status = ct_map_to_grid(&p, q.e, q.n, q.h, &q.x2, &q.y2, &q.z2);
    q.surf_status = ct_surface_height(&p, q.x, q.y, &q.surf_z);
    q.de = g.range(-(INT64_C(1) << 40), INT64_C(1) << 40);
    q.dn = g.range(-(INT64_C(1) << 40), INT64_C(1) << 40);
    q.dh = -g.range(0, INT64_C(1) << 40);
    if (k % 7 == 3) q.de = q.dn = 0;
    if (k % 11 == 5) q.de = q.dn = q.dh = 0;  // invalid
    q.rfm_status = ct_ray_from_map(&p, q.e, q.n, q.h, q.de, q.dn, q.dh, &q.rfm);
    return q;
}

// ------------------------------------------------------------------ output
std::string i64(int64_t v)
{
    char b[48];
    if (v == INT64_MIN) return "(-INT64_C(9223372036854775807) - 1)";
    std::snprintf(b, sizeof b, "INT64_C(%" PRId64 ")", v);
    return b;
}
std::string u64(uint64_t v)
{
    char b[48];
    std::snprintf(b, sizeof b, "UINT64_C(0x%016" PRIx64 ")", v);
    return b;
}
std::string i32(int32_t v)
{
    char b[32];
    if (v == INT32_MIN) return "(-2147483647 - 1)";
    std::snprintf(b, sizeof b, "%" PRId32, v);
    return b;
}
std::string u32(uint32_t v)
{
    char b[32];
    std::snprintf(b, sizeof b, "%" PRIu32 "u", v);
    return b;
}

std::string ray_init(const ct_ray &r)
{
    return "{" + i64(r.x_q16) + ", " + i64(r.y_q16) + ", " + i64(r.z_q16) + ", " + i64(r.dx) + ", " + i64(r.dy) + ", " +
           i64(r.dz) + "}";
}

std::string hit_init(const ct_hit &h)
{
    return "{.x_q16 = " + i64(h.x_q16) + ", .y_q16 = " + i64(h.y_q16) + ", .z_q16 = " + i64(h.z_q16) +
           ", .e_nm = " + i64(h.e_nm) + ", .n_nm = " + i64(h.n_nm) + ", .h_nm = " + i64(h.h_nm) +
           ",\n     .t_q26 = " + i64(h.t_q26) + ", .cell_x = " + i32(h.cell_x) + ", .cell_y = " + i32(h.cell_y) +
           ", .steps = " + u32(h.steps) + ", .iters = " + u32(h.iters) + "}";
}

void emit_case(FILE *f, const ct_vec_case &c)
{
    const ct_prepared &p = c.prep;
    std::fprintf(f, "  {.ray = %s,\n   .prep_status = %s,\n", ray_init(c.ray).c_str(), i32(c.prep_status).c_str());
    std::fprintf(f,
                 "   .prep = {.ox = %s, .oy = %s, .oz = %s, .dx = %s, .dy = %s, .dz = %s, .sector = %s, .zshift = %s,\n"
                 "            .len_lo = %s, .len_hi = %s, .tend_n = %s, .tend_d = %s, .start = %s},\n",
                 i64(p.ox).c_str(), i64(p.oy).c_str(), i64(p.oz).c_str(), i32(p.dx).c_str(), i32(p.dy).c_str(),
                 i32(p.dz).c_str(), i32(p.sector).c_str(), i32(p.zshift).c_str(), i64(p.len_lo).c_str(), i64(p.len_hi).c_str(),
                 i64(p.tend_n).c_str(), i64(p.tend_d).c_str(), i32(p.start).c_str());
    std::fprintf(f, "   .status = {%s, %s, %s, %s},\n   .hit = {\n", i32(c.status[0]).c_str(), i32(c.status[1]).c_str(),
                 i32(c.status[2]).c_str(), i32(c.status[3]).c_str());
    for (int m = 0; m < CT_METHOD_COUNT; ++m) std::fprintf(f, "    %s,\n", hit_init(c.hit[m]).c_str());
    std::fprintf(f, "  }},\n");
}

void emit_point(FILE *f, const ct_vec_point &q)
{
    std::fprintf(f,
                 "  {%s, %s, %s,\n   %s, %s, %s, %s,\n   %s, %s, %s, %s,\n   %s, %s,\n   %s, %s, %s,\n   %s, %s},\n",
                 i64(q.x).c_str(), i64(q.y).c_str(), i64(q.z).c_str(), i32(q.g2m_status).c_str(), i64(q.e).c_str(),
                 i64(q.n).c_str(), i64(q.h).c_str(), i32(q.m2g_status).c_str(), i64(q.x2).c_str(), i64(q.y2).c_str(),
                 i64(q.z2).c_str(), i32(q.surf_status).c_str(), i64(q.surf_z).c_str(), i64(q.de).c_str(),
                 i64(q.dn).c_str(), i64(q.dh).c_str(), i32(q.rfm_status).c_str(), ray_init(q.rfm).c_str());
}

// ------------------------------------------------------------------ cameras
struct Cam {
    std::string name;
    uint32_t package = 0;
    ct_lens lens{};
    std::vector<int32_t> grid_rays;  // nodes of a grid camera
    ct_unproject_grid grid{};
    ct_status init_status = CT_ERR_ARG;
    int64_t r2_max_q32 = 0;
    int32_t R[9] = {0};
    int64_t e_nm = 0, n_nm = 0, h_nm = 0;
    ct_status pose_status = CT_ERR_ARG;
    ct_effects effects{};
    uint32_t batch_method = 0;
    std::vector<ct_vec_pixel> px;
    std::vector<ct_geo> batch;  // the host's ct_geolocate_batch over px
    int64_t tol_nm = 0;
    ct_status tol_status = CT_ERR_ARG;
    ct_effects_choice tol{};
};

ct_lens make_lens(uint32_t model, double f, double cx, double cy, std::vector<double> dist)
{
    ct_lens L;
    std::memset(&L, 0, sizeof L);
    L.model = model;
    L.width = 640;
    L.height = 480;
    L.fx_q32 = (int64_t)std::llround(f * 4294967296.0);
    L.fy_q32 = (int64_t)std::llround(f * 1.002 * 4294967296.0);  // fx != fy: both paths used
    L.cx_q32 = (int64_t)std::llround(cx * 4294967296.0);
    L.cy_q32 = (int64_t)std::llround(cy * 4294967296.0);
    for (size_t i = 0; i < dist.size() && i < 8; ++i) L.dist_q48[i] = (int64_t)std::llround(dist[i] * 281474976710656.0);
    return L;
}

// R_map_cam for a camera looking towards azimuth az (deg from north,
// clockwise) pitched down by pitch (deg): columns right, down, forward.
void look(double az_deg, double pitch_deg, int32_t R[9])
{
    const double a = az_deg * 3.14159265358979323846 / 180, p = pitch_deg * 3.14159265358979323846 / 180;
    const double f[3] = {std::sin(a) * std::cos(p), std::cos(a) * std::cos(p), -std::sin(p)};
    const double r[3] = {std::cos(a), -std::sin(a), 0.0};
    const double d[3] = {f[1] * r[2] - f[2] * r[1], f[2] * r[0] - f[0] * r[2], f[0] * r[1] - f[1] * r[0]};
    for (int i = 0; i < 3; ++i) {
        R[i * 3 + 0] = (int32_t)std::lround(r[i] * 1073741824.0);
        R[i * 3 + 1] = (int32_t)std::lround(d[i] * 1073741824.0);
        R[i * 3 + 2] = (int32_t)std::lround(f[i] * 1073741824.0);
    }
}

// Camera c's lens (or grid) and pose set up on the host: *init and
// *pose_st their statuses.
void camera_setup(const Cam &c, ct_camera *cam, ct_pose *pose, ct_status *init, ct_status *pose_st)
{
    std::memset(cam, 0, sizeof *cam);
    std::memset(pose, 0, sizeof *pose);
    *init = c.grid.nu ? ct_camera_init_grid(cam, &c.grid) : ct_camera_init(cam, &c.lens);
    *pose_st = ct_pose_init(pose, c.R, c.e_nm, c.n_nm, c.h_nm);
}

// Camera c's pixels as the batch takes them (u, v pairs, Q16).
std::vector<int64_t> camera_uv(const Cam &c)
{
    std::vector<int64_t> uv;
    for (const ct_vec_pixel &q : c.px) {
        uv.push_back(q.u_q16);
        uv.push_back(q.v_q16);
    }
    return uv;
}

// Unprojection, projection back and geolocation (every method) of a
// camera's pixels on the host.  The batch is compared with these on the
// targets (and test_geoloc checks it on the host).
void run_camera(Rng &g, Cam &c, const ct_package &pkg)
{
    ct_camera cam;
    ct_pose pose;
    camera_setup(c, &cam, &pose, &c.init_status, &c.pose_status);
    c.r2_max_q32 = cam.r2_max_q32;
    if (c.init_status != CT_OK || c.pose_status != CT_OK) die("camera " + c.name + ": init failed on the host");
    const int64_t U = INT64_C(1) << 16;
    const int64_t fixed_px[][2] = {{0, 0}, {639 * U, 0}, {0, 479 * U}, {639 * U, 479 * U}, {319 * U + U / 2, 239 * U + U / 2},
                                   {-3000 * U, 240 * U}, {320 * U, 9000 * U}, {(INT64_C(1) << 20) * U + 1, 0}};
    for (int k = 0; k < 40; ++k) {
        ct_vec_pixel q;
        std::memset(&q, 0, sizeof q);
        if (k < 8) {
            q.u_q16 = fixed_px[k][0];
            q.v_q16 = fixed_px[k][1];
        } else if (k >= 24) {
            // two runs of 8 neighbouring pixels of a row (the batch's runs)
            if (k % 8 == 0) {
                q.u_q16 = g.range(0, 600 * U);
                q.v_q16 = g.range(0, 479 * U);
            } else {
                q.u_q16 = c.px.back().u_q16 + U;
                q.v_q16 = c.px.back().v_q16;
            }
        } else {
            q.u_q16 = g.range(-20 * U, 660 * U);
            q.v_q16 = g.range(-20 * U, 500 * U);
        }
        q.unp_status = ct_camera_unproject(&cam, q.u_q16, q.v_q16, q.ray_q30, &q.unp_iters);
        if (q.unp_status == CT_OK) q.proj_status = ct_camera_project(&cam, q.ray_q30, &q.pu_q16, &q.pv_q16);
        for (int m = 0; m < CT_METHOD_COUNT; ++m)
            ct_geolocate(&pkg, &cam, &pose, (ct_method)m, &c.effects, q.u_q16, q.v_q16, &q.geo[m]);
        c.px.push_back(q);
    }
    // the batch: every record as the single call's but for the runs' steps
    {
        const std::vector<int64_t> uv = camera_uv(c);
        c.batch.assign(c.px.size(), ct_geo{});
        if (ct_geolocate_batch(&pkg, &cam, &pose, (ct_method)c.batch_method, &c.effects, uv.data(), c.px.size(),
                               c.batch.data(), c.batch.size()) != CT_OK)
            die("camera " + c.name + ": batch failed on the host");
        for (size_t k = 0; k < c.px.size(); ++k) {
            const ct_geo &a = c.batch[k], &b = c.px[k].geo[c.batch_method];
            ct_hit ha = a.hit, hb = b.hit;
            ha.steps = hb.steps = ha.iters = hb.iters = 0;
            if (a.status != b.status || a.unproject_iters != b.unproject_iters ||
                std::memcmp(a.ray_cam_q30, b.ray_cam_q30, sizeof a.ray_cam_q30) != 0 ||
                std::memcmp(a.dir_map_q39, b.dir_map_q39, sizeof a.dir_map_q39) != 0 ||
                std::memcmp(&ha, &hb, sizeof ha) != 0)
                die("camera " + c.name + ": a batch record differs from the single call's");
        }
    }
    // the effects a tolerance calls for (a different tolerance per camera)
    c.tol_nm = INT64_C(10000000) << (3 * (c.name.size() % 4));
    c.tol_status = ct_effects_for_tolerance(&pkg, &cam, &pose, c.effects.refraction_k_q16, c.effects.earth_radius_nm,
                                            c.tol_nm, &c.tol);
    int hits = 0, miss = 0, errors = 0, shortened = 0;
    for (size_t k = 0; k < c.px.size(); ++k) shortened += c.batch[k].hit.steps < c.px[k].geo[c.batch_method].hit.steps;
    for (const ct_vec_pixel &q : c.px) {
        const ct_status st = q.geo[0].status;
        hits += st == CT_HIT || st == CT_HIT_VOID;
        miss += st == CT_MISS;
        errors += st < 0;
    }
    std::fprintf(stderr, "gen_vectors: camera %s: %zu pixels: %d hit, %d miss, %d errors; %d walks shortened by the batch's runs\n",
                 c.name.c_str(), c.px.size(), hits, miss, errors, shortened);
}

std::vector<Cam> make_cameras(Rng &g, const std::vector<const ct_package *> &pk)
{
    std::vector<Cam> cams(4);
    const double E0 = ORIGIN_E_M, N0 = ORIGIN_N_M;
    {  // distorted lens looking north over the tile, curvature + refraction
        Cam &c = cams[0];
        c.name = "opencv8_oblique_bent";
        c.package = 1;
        c.lens = make_lens(CT_LENS_OPENCV8, 900, 319.5, 239.5,
                           {-0.28, 0.09, 0.0007, -0.0004, -0.01, 0.02, 0.003, 0.001});
        look(0, 40, c.R);
        c.e_nm = nm(E0 + 480);
        c.n_nm = nm(N0 - 1500);
        c.h_nm = nm(900);
        c.effects.flags = CT_EFFECT_ALL;
        c.effects.refraction_k_q16 = CT_REFRACTION_K_STD_Q16;
        c.batch_method = CT_METHOD_DIRECTIONAL;
    }
    {  // pinhole, nearly nadir, straight rays
        Cam &c = cams[1];
        c.name = "pinhole_nadir";
        c.package = 0;
        c.lens = make_lens(CT_LENS_PINHOLE, 1500, 320, 240, {});
        look(30, 89, c.R);
        c.e_nm = nm(E0 + 480);
        c.n_nm = nm(N0 - 420);
        c.h_nm = nm(2000);
        c.batch_method = CT_METHOD_CONE;
    }
    {  // grazing from the west on a small planet: strongly bent polylines
        Cam &c = cams[2];
        c.name = "opencv4_grazing_small_earth";
        c.package = 0;
        c.lens = make_lens(CT_LENS_OPENCV4, 900, 330, 250, {-0.1, 0.01, 0.0001, 0.0001});
        look(90, 20, c.R);
        c.e_nm = nm(E0 - 100);
        c.n_nm = nm(N0 - 400);
        c.h_nm = nm(600);
        c.effects.flags = CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION;
        c.effects.refraction_k_q16 = 8520;
        c.effects.earth_radius_nm = INT64_C(1) << 44;
        c.effects.chord_nm = INT64_C(1) << 20;
        c.batch_method = CT_METHOD_DIRECTIONAL;
    }
    {  // unprojection grid baked from the first lens, curvature only (the
       // true Earth, its map fitted per call)
        Cam &c = cams[3];
        c.name = "grid_from_opencv8";
        c.package = 1;
        ct_camera src;
        std::memset(&src, 0, sizeof src);
        if (ct_camera_init(&src, &cams[0].lens) != CT_OK) die("grid source lens");
        c.grid = dem_cases::grid_from_camera(src, INT64_C(-64) << 16, INT64_C(-64) << 16, INT64_C(64) << 16, 13u, 10u,
                                             &c.grid_rays);
        look(20, 40, c.R);
        c.e_nm = nm(E0 + 300);
        c.n_nm = nm(N0 - 1300);
        c.h_nm = nm(800);
        c.effects.flags = CT_EFFECT_CURVATURE | CT_EFFECT_EARTH_FIT;
        c.batch_method = CT_METHOD_HIERARCHICAL;
    }
    for (Cam &c : cams) run_camera(g, c, *pk[c.package]);
    return cams;
}

std::string geo_init(const ct_geo &o)
{
    return "{.status = " + i32(o.status) + ", .unproject_iters = " + u32(o.unproject_iters) + ", .ray_cam_q30 = {" +
           i32(o.ray_cam_q30[0]) + ", " + i32(o.ray_cam_q30[1]) + ", " + i32(o.ray_cam_q30[2]) + "},\n      .dir_map_q39 = {" +
           i64(o.dir_map_q39[0]) + ", " + i64(o.dir_map_q39[1]) + ", " + i64(o.dir_map_q39[2]) + "},\n      .hit = " +
           hit_init(o.hit) + "}";
}

void emit_cameras(FILE *f, const std::vector<Cam> &cams)
{
    for (size_t k = 0; k < cams.size(); ++k) {
        const Cam &c = cams[k];
        if (!c.grid_rays.empty()) {
            std::fprintf(f, "static const int32_t cam%zu_grid[%zu] = {", k, c.grid_rays.size());
            for (size_t i = 0; i < c.grid_rays.size(); ++i)
                std::fprintf(f, "%s%s,", (i % 6) ? " " : "\n  ", i32(c.grid_rays[i]).c_str());
            std::fprintf(f, "\n};\n\n");
        }
        std::fprintf(f, "static const ct_vec_pixel cam%zu_pixels[%zu] = {\n", k, c.px.size());
        for (const ct_vec_pixel &q : c.px) {
            std::fprintf(f, "  {%s, %s, %s, %s, {%s, %s, %s}, %s, %s, %s,\n   {", i64(q.u_q16).c_str(), i64(q.v_q16).c_str(),
                         i32(q.unp_status).c_str(), u32(q.unp_iters).c_str(), i32(q.ray_q30[0]).c_str(),
                         i32(q.ray_q30[1]).c_str(), i32(q.ray_q30[2]).c_str(), i32(q.proj_status).c_str(),
                         i64(q.pu_q16).c_str(), i64(q.pv_q16).c_str());
            for (int m = 0; m < CT_METHOD_COUNT; ++m) std::fprintf(f, "%s%s", m ? ",\n    " : "", geo_init(q.geo[m]).c_str());
            std::fprintf(f, "}},\n");
        }
        std::fprintf(f, "};\n\n");
        std::fprintf(f, "static const ct_geo cam%zu_batch[%zu] = {\n", k, c.batch.size());
        for (const ct_geo &o : c.batch) std::fprintf(f, "  %s,\n", geo_init(o).c_str());
        std::fprintf(f, "};\n\n");
    }
    std::fprintf(f, "static const ct_vec_camera cameras[%zu] = {\n", cams.size());
    for (size_t k = 0; k < cams.size(); ++k) {
        const Cam &c = cams[k];
        const ct_lens &L = c.lens;
        std::fprintf(f, "  {.name = \"%s\", .package = %uu,\n   .lens = {.model = %uu, .width = %uu, .height = %uu, ",
                     c.name.c_str(), c.package, L.model, L.width, L.height);
        std::fprintf(f, ".fx_q32 = %s, .fy_q32 = %s, .cx_q32 = %s, .cy_q32 = %s,\n            .dist_q48 = {",
                     i64(L.fx_q32).c_str(), i64(L.fy_q32).c_str(), i64(L.cx_q32).c_str(), i64(L.cy_q32).c_str());
        for (int i = 0; i < 8; ++i) std::fprintf(f, "%s%s", i ? ", " : "", i64(L.dist_q48[i]).c_str());
        std::fprintf(f, "}},\n");
        if (!c.grid_rays.empty())
            std::fprintf(f,
                         "   .grid = {.nu = %uu, .nv = %uu, .u0_q16 = %s, .v0_q16 = %s, .step_q16 = %s, .rays_q30 = "
                         "cam%zu_grid, .rays_len = %zuu},\n",
                         c.grid.nu, c.grid.nv, i64(c.grid.u0_q16).c_str(), i64(c.grid.v0_q16).c_str(),
                         i64(c.grid.step_q16).c_str(), k, c.grid_rays.size());
        std::fprintf(f, "   .init_status = %s, .r2_max_q32 = %s,\n   .R_q30 = {", i32(c.init_status).c_str(),
                     i64(c.r2_max_q32).c_str());
        for (int i = 0; i < 9; ++i) std::fprintf(f, "%s%s", i ? ", " : "", i32(c.R[i]).c_str());
        std::fprintf(f, "},\n   .e_nm = %s, .n_nm = %s, .h_nm = %s, .pose_status = %s,\n", i64(c.e_nm).c_str(),
                     i64(c.n_nm).c_str(), i64(c.h_nm).c_str(), i32(c.pose_status).c_str());
        std::fprintf(f, "   .effects = {.flags = %uu, .refraction_k_q16 = %s, .earth_radius_nm = %s, .chord_nm = %s},\n",
                     c.effects.flags, i32(c.effects.refraction_k_q16).c_str(), i64(c.effects.earth_radius_nm).c_str(),
                     i64(c.effects.chord_nm).c_str());
        std::fprintf(f, "   .batch_method = %uu, .pixels = cam%zu_pixels, .npixels = %zuu, .batch = cam%zu_batch,\n",
                     c.batch_method, k, c.px.size(), k);
        std::fprintf(f, "   .tol_nm = %s, .tol_status = %s, .tol_choice = {.flags = %uu, .chord_nm = %s, .bound_nm = {%s, %s, "
                        "%s, %s}, .range_nm = %s, .tan_min_q30 = %s, .samples = %uu}},\n",
                     i64(c.tol_nm).c_str(), i32(c.tol_status).c_str(), c.tol.flags, i64(c.tol.chord_nm).c_str(),
                     i64(c.tol.bound_nm[0]).c_str(), i64(c.tol.bound_nm[1]).c_str(), i64(c.tol.bound_nm[2]).c_str(),
                     i64(c.tol.bound_nm[3]).c_str(), i64(c.tol.range_nm).c_str(), i64(c.tol.tan_min_q30).c_str(),
                     c.tol.samples);
    }
    std::fprintf(f, "};\n\n");
}

}  // namespace

// ------------------------------------------------------------------ tile sets
// The DEM cut into 3 x 3 tiles; traced on the host through the same slots
// and loader the target uses (a copy from the const tiles into RAM slots;
// `missing` refused), so results, steps and loads must match bit for bit.
struct TSet {
    std::string name;
    ct_host::TileSetBytes b;
    uint32_t nslots = 2, missing = 0;  // missing == tiles: none
    std::vector<ct_vec_case> cases;
    uint32_t loads = 0;
    uint32_t camera = 0;        // the camera whose pixels go through the set's batch
    std::vector<ct_geo> batch;  // ct_geolocate_batch_tiles over them, after the cases
    uint32_t batch_loads = 0;
};

struct TLoad {
    const TSet *s;
};

ct_status tset_loader(void *user, uint32_t col, uint32_t row, uint8_t *buf, size_t cap, const uint8_t **bytes,
                      size_t *len)
{
    const TSet *s = static_cast<TLoad *>(user)->s;
    const uint32_t k = row * (uint32_t)s->b.grid.tiles_x + col;
    const std::vector<uint8_t> &v = s->b.tiles[k];
    if (k == s->missing || v.size() > cap) return CT_ERR_ARG;
    std::memcpy(buf, v.data(), v.size());
    *bytes = buf;
    *len = v.size();
    return CT_OK;
}

void run_tileset(Rng &g, TSet &s, const ct_package &merged, int nrays, const std::vector<Cam> &cams)
{
    std::vector<ct_tile_slot> slots(s.nslots);
    std::vector<std::vector<uint8_t>> bufs(s.nslots, std::vector<uint8_t>(CT_VEC_TILE_CAP));
    for (uint32_t k = 0; k < s.nslots; ++k) {
        slots[k] = ct_tile_slot{};
        slots[k].buf = bufs[k].data();
        slots[k].cap = bufs[k].size();
    }
    TLoad tl{&s};
    ct_tileset ts;
    if (ct_tileset_open(&ts, s.b.manifest.data(), s.b.manifest.size(), slots.data(), s.nslots, tset_loader, &tl) != CT_OK)
        die("host: ct_tileset_open failed");
    int nodata = 0;
    for (int k = 0; k < nrays; ++k) {
        ct_vec_case c;
        std::memset(&c, 0, sizeof c);
        c.ray = make_ray(g, merged, pick_kind(g));
        for (int m = 0; m < CT_METHOD_COUNT; ++m) {
            c.status[m] = ct_tileset_trace(&ts, &c.ray, (ct_method)m, &c.hit[m]);
            nodata += c.status[m] == CT_NO_DATA;
            if (s.missing >= s.b.tiles.size()) {
                ct_hit h;
                std::memset(&h, 0, sizeof h);
                const ct_status sm = ct_trace(&merged, &c.ray, (ct_method)m, &h);
                if (sm != c.status[m] || h.t_q26 != c.hit[m].t_q26 || h.x_q16 != c.hit[m].x_q16)
                    die("host: a tile set differs from the merged package");
            }
        }
        s.cases.push_back(c);
    }
    s.loads = ts.loads;
    // a camera over the merged package: its pixels through the set's batch
    // (the runs over the tile its rays start on), each record as the merged
    // batch's where the set has every tile
    const Cam &c = cams[s.camera];
    if (c.package != 0) die("the tile sets' camera must be over the first package");
    ct_camera cam;
    ct_pose pose;
    ct_status init, pst;
    camera_setup(c, &cam, &pose, &init, &pst);
    if (init != CT_OK || pst != CT_OK) die("tile set " + s.name + ": camera set-up failed on the host");
    const std::vector<int64_t> uv = camera_uv(c);
    s.batch.assign(c.px.size(), ct_geo{});
    if (ct_geolocate_batch_tiles(&ts, &cam, &pose, (ct_method)c.batch_method, &c.effects, uv.data(), c.px.size(),
                                 s.batch.data(), s.batch.size()) != CT_OK)
        die("tile set " + s.name + ": batch failed on the host");
    int differ = 0, set_nodata = 0;
    for (size_t k = 0; k < c.px.size(); ++k) {
        const ct_geo &a = s.batch[k], &b = c.batch[k];
        set_nodata += a.status == CT_NO_DATA;
        if (s.missing >= s.b.tiles.size())
            differ += a.status != b.status || a.hit.t_q26 != b.hit.t_q26 || a.hit.x_q16 != b.hit.x_q16 ||
                      a.hit.y_q16 != b.hit.y_q16 || a.hit.z_q16 != b.hit.z_q16;
    }
    if (differ) die("tile set " + s.name + ": the batch differs from the merged package's");
    s.batch_loads = ts.loads;
    std::fprintf(stderr, "gen_vectors: tile set %s: %zu tiles, %u slots, %d rays x 4 methods, %u loads, %d no_data; "
                 "camera %s's %zu pixels through its batch: %d no_data, %u loads in all\n",
                 s.name.c_str(), s.b.tiles.size(), s.nslots, nrays, s.loads, nodata, c.name.c_str(), c.px.size(),
                 set_nodata, s.batch_loads);
}

void emit_tilesets(FILE *f, const std::vector<TSet> &sets)
{
    for (size_t k = 0; k < sets.size(); ++k) {
        const TSet &s = sets[k];
        std::fprintf(f, "static const union {\n    uint64_t align;\n    uint8_t b[%zu];\n} tset%zu_manifest = {.b = {",
                     s.b.manifest.size(), k);
        for (size_t i = 0; i < s.b.manifest.size(); ++i)
            std::fprintf(f, "%s0x%02x,", (i % 16) ? " " : "\n    ", s.b.manifest[i]);
        std::fprintf(f, "\n}};\n\n");
        for (size_t t = 0; t < s.b.tiles.size(); ++t) {
            const std::vector<uint8_t> &v = s.b.tiles[t];
            std::fprintf(f, "static const union {\n    uint64_t align;\n    uint8_t b[%zu];\n} tset%zu_tile%zu = {.b = {",
                         v.size(), k, t);
            for (size_t i = 0; i < v.size(); ++i) std::fprintf(f, "%s0x%02x,", (i % 16) ? " " : "\n    ", v[i]);
            std::fprintf(f, "\n}};\n\n");
        }
        std::fprintf(f, "static const ct_vec_tile tset%zu_tiles[%zu] = {\n", k, s.b.tiles.size());
        for (size_t t = 0; t < s.b.tiles.size(); ++t)
            std::fprintf(f, "  {tset%zu_tile%zu.b, %zuu},\n", k, t, s.b.tiles[t].size());
        std::fprintf(f, "};\n\nstatic const ct_vec_case tset%zu_cases[%zu] = {\n", k, s.cases.size());
        for (const ct_vec_case &c : s.cases) emit_case(f, c);
        std::fprintf(f, "};\n\nstatic const ct_geo tset%zu_batch[%zu] = {\n", k, s.batch.size());
        for (const ct_geo &o : s.batch) std::fprintf(f, "  %s,\n", geo_init(o).c_str());
        std::fprintf(f, "};\n\n");
    }
    std::fprintf(f, "static const ct_vec_tileset tilesets[%zu] = {\n", sets.size());
    for (size_t k = 0; k < sets.size(); ++k) {
        const TSet &s = sets[k];
        std::fprintf(f,
                     "  {.name = \"%s\", .manifest = tset%zu_manifest.b, .manifest_size = %zuu, .tiles = tset%zu_tiles,\n"
                     "   .ntiles = %zuu, .nslots = %uu, .missing = %uu, .cases = tset%zu_cases, .ncases = %zuu, .loads = %uu,\n"
                     "   .camera = %uu, .batch = tset%zu_batch, .batch_loads = %uu},\n",
                     s.name.c_str(), k, s.b.manifest.size(), k, s.b.tiles.size(), s.nslots, s.missing, k,
                     s.cases.size(), s.loads, s.camera, k, s.batch_loads);
    }
    std::fprintf(f, "};\n\n");
}

// The two packages (N = 8, r = 2 and N = 24, r = 1) by the project's
// builder (or the degenerate one when it fails: *generator says so), each
// with nrays traced cases and 40 surface points.
std::vector<Pkg> make_packages(const Dem &dem, int nrays, std::string *generator)
{
    struct Spec {
        uint32_t n, r;
    };
    const Spec specs[] = {{8, 2}, {24, 1}};
    std::vector<Pkg> pkgs;
    Rng g(20240601u);
    for (const Spec &s : specs) {
        Pkg P;
        char nm_[64];
        ct_status st = CT_ERR_ARG;
#ifdef CT_GEN_USE_BUILDER
        // A builder that throws or writes a package the library rejects must
        // not break the whole build: fall back to the degenerate package and
        // say so in the vectors (mcu_vectors_host then fails, loudly).
        try {
            P.bytes = build_with_builder(dem, (int)s.n, (int)s.r, ct_host::PptBuilder::Slices);
            st = ct_package_open(&P.p, P.bytes.data(), P.bytes.size());
            if (st == CT_OK) st = ct_package_verify(&P.p);
            if (st != CT_OK) {
                std::fprintf(stderr, "gen_vectors: WARNING: build_package N=%u r=%u: package rejected (%d)\n", s.n,
                             s.r, (int)st);
            }
        } catch (const std::exception &e) {
            std::fprintf(stderr, "gen_vectors: WARNING: build_package N=%u r=%u threw: %s\n", s.n, s.r, e.what());
        }
        if (st != CT_OK) {
            *generator = "degenerate (FALLBACK: build_package failed)";
        }
        std::snprintf(nm_, sizeof nm_, "N%u_r%u_%s", s.n, s.r, st == CT_OK ? "build_package" : "degenerate_fallback");
#else
        std::snprintf(nm_, sizeof nm_, "N%u_r%u_degenerate", s.n, s.r);
#endif
        P.name = nm_;
        if (st != CT_OK) {
            try {
                P.bytes = build_with_builder(dem, (int)s.n, (int)s.r, ct_host::PptBuilder::Degenerate);
            } catch (const std::exception &e) {
                die(std::string("build_package (degenerate) threw: ") + e.what());
            }
            st = ct_package_open(&P.p, P.bytes.data(), P.bytes.size());
            if (st != CT_OK) die("host ct_package_open failed: " + std::to_string(st));
            st = ct_package_verify(&P.p);
            if (st != CT_OK) die("host ct_package_verify failed: " + std::to_string(st));
        }
        {
            const uint8_t *a = P.p.angles;
            size_t na = (size_t)P.p.planes * P.p.coarse_x * P.p.coarse_y;
            for (size_t k = 0; k < na; ++k) P.cone_codes += a[k] != 0;
        }
        int counts[8] = {0}, fewer_cone = 0, fewer_dir = 0;
        for (int k = 0; k < nrays; ++k) {
            ct_ray r = make_ray(g, P.p, pick_kind(g));
            ct_vec_case c = trace_case(P.p, r);
            P.cases.push_back(c);
            int s0 = c.status[0];
            counts[s0 < 0 ? 5 : (s0 > 4 ? 6 : s0)]++;
            fewer_cone += c.hit[CT_METHOD_CONE].steps < c.hit[CT_METHOD_INCREMENTAL].steps;
            fewer_dir += c.hit[CT_METHOD_DIRECTIONAL].steps < c.hit[CT_METHOD_INCREMENTAL].steps;
            for (int m = 1; m < CT_METHOD_COUNT; ++m) {
                if (c.status[m] != c.status[0] || c.hit[m].t_q26 != c.hit[0].t_q26) {
                    std::fprintf(stderr, "gen_vectors: note: %s ray %d: method %d differs from incremental on host\n",
                                 P.name.c_str(), k, m);
                }
            }
        }
        for (int k = 0; k < 40; ++k) P.points.push_back(make_point(g, P.p, k));
        std::fprintf(stderr, "gen_vectors: %s: %zu bytes, %u non-zero angle codes, rays: %d hit, %d miss, %d below, "
                     "%d hit_void, %d errors; cone jumps shortened %d (CONE) / %d (DIRECTIONAL) rays\n",
                     P.name.c_str(), P.bytes.size(), P.cone_codes, counts[CT_HIT], counts[CT_MISS], counts[CT_BELOW],
                     counts[CT_HIT_VOID], counts[5], fewer_cone, fewer_dir);
        pkgs.push_back(std::move(P));
    }

    return pkgs;
}

// Tile sets: the DEM in 3 x 3 tiles (N = 8, r = 2, the first package's
// builder), all tiles in 2 slots, and tile (1, 1) refused with 1 slot.
std::vector<TSet> make_tilesets(const Dem &dem, const Pkg &first, const std::vector<Cam> &cams)
{
    std::vector<TSet> tsets;
    {
        ct_host::BuildOptions o;
        o.sectors = 8;
        o.reduce = 2;
        o.threads = 1;
        o.builder = first.cone_codes > 0 ? ct_host::PptBuilder::Slices : ct_host::PptBuilder::Degenerate;
        const ct_host::TileSetBytes b = ct_host::build_tileset(dem_terrain(dem), o, 12, 1);
        for (const auto &t : b.tiles)
            if (t.size() > CT_VEC_TILE_CAP) die("a tile is larger than CT_VEC_TILE_CAP");
        Rng gt(16u);
        for (int v = 0; v < 2; ++v) {
            TSet s;
            s.name = v == 0 ? "3x3_tiles_2_slots" : "3x3_tiles_1_slot_centre_missing";
            s.b = b;
            s.nslots = v == 0 ? 2u : 1u;
            s.missing = v == 0 ? (uint32_t)b.tiles.size() : 4u;
            // the grazing camera over a small earth (the lowered walk): runs
            for (size_t k = 0; k < cams.size(); ++k)
                if (cams[k].name == "opencv4_grazing_small_earth") s.camera = (uint32_t)k;
            run_tileset(gt, s, first.p, 120, cams);
            tsets.push_back(std::move(s));
        }
    }

    return tsets;
}

// Fixed-point vectors (native __int128 on the host) and sector boundaries.
void make_fixed(std::vector<ct_vec_fixed> *out_fx, std::vector<ct_vec_dir> *out_dirs)
{
    std::vector<ct_vec_fixed> &fx = *out_fx;
    std::vector<ct_vec_dir> &dirs = *out_dirs;
    {
        Rng h(77u);
        for (int k = 0; k < 120; ++k) {
            ct_vec_fixed v;
            std::memset(&v, 0, sizeof v);
            int ba = (int)h.range(0, 62), bb = (int)h.range(0, 62);
            v.a = (int64_t)(h.u64() >> (63 - ba)) * (h.chance(50) ? -1 : 1);
            v.b = (int64_t)(h.u64() >> (63 - bb)) * (h.chance(50) ? -1 : 1);
            if (k == 0) { v.a = INT64_MAX; v.b = INT64_MAX; }
            if (k == 1) { v.a = INT64_MAX; v.b = -INT64_MAX; }
            if (k == 2) { v.a = 0; v.b = -5; }
            if (k == 3) { v.a = -1; v.b = 1; }
            // the two's complement corrections of the product's high word
            // (fixed.h: every sign, the most negative word, carries through
            // all four partial products)
            if (k == 5) { v.a = INT64_MIN; v.b = INT64_MIN; }
            if (k == 6) { v.a = INT64_MIN; v.b = -1; }
            if (k == 7) { v.a = INT64_MIN; v.b = INT64_MAX; }
            if (k == 8) { v.a = -1; v.b = -1; }
            if (k == 10) { v.a = -(INT64_C(1) << 32) + 1; v.b = (INT64_C(1) << 32) - 1; }
            if (k == 11) { v.a = -(INT64_C(0xffffffff)); v.b = -(INT64_C(0x100000001)); }
            ct_i128 p = ct_i128_mul(v.a, v.b);
            v.mul_hi = p.hi;
            v.mul_lo = p.lo;
            // divisor with |quotient| < 2^62
            __int128 pn = (__int128)(((unsigned __int128)p.hi << 64) | p.lo);
            __int128 ap = pn < 0 ? -pn : pn;
            // contract: d > 0 and |quotient| < 2^63
            __int128 dmin = (ap >> 62) + 1;
            if (dmin > (__int128)(INT64_C(1) << 62)) {
                v.div_d = INT64_MAX;  // |p| < 2^126: quotient < 2^63
            } else {
                v.div_d = (int64_t)dmin + (int64_t)(h.u64() >> (1 + h.range(1, 62)));
                if (k % 9 == 4) v.div_d = (int64_t)dmin;  // smallest allowed divisor
            }
            v.div_q = ct_i128_floor_div(p, v.div_d);
            v.isqrt = ct_i128_isqrt(ct_i128_sign(p) < 0 ? ct_i128_neg(p) : p);
            v.isqrt64 = ct_isqrt64((uint64_t)v.a);
            v.m64 = h.range(-(INT64_C(1) << 46) + 1, (INT64_C(1) << 46) - 1);
            ct_i128 m = ct_i128_mul128_64(ct_i128_mul(v.a / 16777216, v.b / 16777216), v.m64);
            v.m_hi = m.hi;
            v.m_lo = m.lo;
            fx.push_back(v);
        }
        for (uint32_t n = 1; n <= CT_MAX_SECTORS; ++n) {
            for (uint32_t k = 0; k <= n; k += (n > 16 ? 3 : 1)) {
                ct_vec_dir d{k, n, 0, 0};
                ct_dir_of_fraction(k, n, &d.cx, &d.sy);
                dirs.push_back(d);
            }
        }
    }
}

void emit_packages(FILE *f, const std::vector<Pkg> &pkgs)
{
    for (size_t k = 0; k < pkgs.size(); ++k) {
        const Pkg &P = pkgs[k];
        std::fprintf(f, "static const union {\n    uint64_t align;\n    uint8_t b[%zu];\n} pkg%zu_bytes = {.b = {", P.bytes.size(), k);
        for (size_t i = 0; i < P.bytes.size(); ++i) {
            std::fprintf(f, "%s0x%02x,", (i % 16) ? " " : "\n    ", P.bytes[i]);
        }
        std::fprintf(f, "\n}};\n\nstatic const ct_vec_case pkg%zu_cases[%zu] = {\n", k, P.cases.size());
        for (const ct_vec_case &c : P.cases) emit_case(f, c);
        std::fprintf(f, "};\n\nstatic const ct_vec_point pkg%zu_points[%zu] = {\n", k, P.points.size());
        for (const ct_vec_point &q : P.points) emit_point(f, q);
        std::fprintf(f, "};\n\n");
    }
    std::fprintf(f, "static const ct_vec_package packages[%zu] = {\n", pkgs.size());
    for (size_t k = 0; k < pkgs.size(); ++k) {
        const Pkg &P = pkgs[k];
        uint32_t crc = (uint32_t)P.bytes[12] | (uint32_t)P.bytes[13] << 8 | (uint32_t)P.bytes[14] << 16 |
                       (uint32_t)P.bytes[15] << 24;
        std::fprintf(f, "  {.name = \"%s\", .bytes = pkg%zu_bytes.b, .size = %zuu, .crc = 0x%08xu,\n", P.name.c_str(), k,
                     P.bytes.size(), crc);
        std::fprintf(f, "   .sectors = %uu, .reduce = %uu, .levels = %uu, .cone_codes = %uu,\n   .cot_q16 = {",
                     P.p.sectors, P.p.reduce, P.p.levels, P.cone_codes);
        for (int i = 0; i < 256; ++i) std::fprintf(f, "%s%s,", (i % 4) ? " " : "\n     ", i64(P.p.cot_q16[i]).c_str());
        std::fprintf(f, "},\n   .cot_ok = {");
        for (int i = 0; i < 256; ++i) std::fprintf(f, "%s%u,", (i % 32) ? "" : "\n     ", P.p.cot_ok[i]);
        std::fprintf(f, "},\n   .bound_x = {");
        for (int i = 0; i <= CT_MAX_SECTORS; ++i) std::fprintf(f, "%s%s,", (i % 8) ? " " : "\n     ", i32(P.p.bound_x[i]).c_str());
        std::fprintf(f, "},\n   .bound_y = {");
        for (int i = 0; i <= CT_MAX_SECTORS; ++i) std::fprintf(f, "%s%s,", (i % 8) ? " " : "\n     ", i32(P.p.bound_y[i]).c_str());
        std::fprintf(f, "},\n   .cases = pkg%zu_cases, .ncases = %zuu, .points = pkg%zu_points, .npoints = %zuu},\n", k,
                     P.cases.size(), k, P.points.size());
    }
}

void emit_fixed(FILE *f, const std::vector<ct_vec_fixed> &fx, const std::vector<ct_vec_dir> &dirs)
{
    std::fprintf(f, "};\n\nstatic const ct_vec_fixed fixed[%zu] = {\n", fx.size());
    for (const ct_vec_fixed &v : fx) {
        std::fprintf(f, "  {%s, %s, %s, %s,\n   %s, %s, %s, %s,\n   %s, %s, %s},\n", i64(v.a).c_str(), i64(v.b).c_str(),
                     u64(v.mul_hi).c_str(), u64(v.mul_lo).c_str(), i64(v.div_d).c_str(), i64(v.div_q).c_str(),
                     u64(v.isqrt).c_str(), u64(v.isqrt64).c_str(), i64(v.m64).c_str(), u64(v.m_hi).c_str(),
                     u64(v.m_lo).c_str());
    }
    std::fprintf(f, "};\n\nstatic const ct_vec_dir dirs[%zu] = {", dirs.size());
    for (size_t i = 0; i < dirs.size(); ++i) {
        std::fprintf(f, "%s{%uu, %uu, %s, %s},", (i % 3) ? " " : "\n  ", dirs[i].k, dirs[i].n, i32(dirs[i].cx).c_str(),
                     i32(dirs[i].sy).c_str());
    }
    std::fprintf(f, "\n};\n\n");
}

// Geodesy: points across zones and hemispheres, some out of range.
size_t emit_geodesy(FILE *f)
{
    std::vector<ct_vec_geo> geo;
    {
        Rng gg(4326u);
        for (int k = 0; k < 64; ++k) {
            ct_vec_geo v{};
            v.zone.zone = 1 + (int32_t)(gg.u64() % 60u);
            v.zone.south = (int32_t)(gg.u64() % 2u);
            long double lat = (v.zone.south ? -81.0L : -1.0L) + (long double)(gg.u64() % 860000u) * 1e-4L;
            long double dl = ((long double)(gg.u64() % 200001u) - 100000.0L) * 1e-4L;  // +-10 deg
            long double lon = 6.0L * v.zone.zone - 183 + dl;
            if (lon > 180) lon -= 360;
            v.lat_q61 = (int64_t)std::llround(lat * 3.14159265358979323846264338L / 180 * std::ldexp(1.0L, 61));
            v.lon_q61 = (int64_t)std::llround(lon * 3.14159265358979323846264338L / 180 * std::ldexp(1.0L, 61));
            v.fwd_status = ct_utm_forward(&v.zone, v.lat_q61, v.lon_q61, &v.e_nm, &v.n_nm);
            if (v.fwd_status != CT_OK) {
                // an inverse of a map point off the zone as well
                v.e_nm = INT64_C(500000000000000) + (int64_t)(gg.u64() % 2000000u) * INT64_C(1000000000);
                v.n_nm = (int64_t)(gg.u64() % 10000000u) * INT64_C(1000000000);
            }
            v.inv_status = ct_utm_inverse(&v.zone, v.e_nm, v.n_nm, &v.lat2_q61, &v.lon2_q61);
            v.fac_status = ct_utm_factors(&v.zone, v.lat_q61, v.lon_q61, &v.gamma_q61, &v.k_q61);
            for (int a = 0; a < 3; ++a)
                v.ypr_q61[a] = (int64_t)((long double)((int64_t)(gg.u64() % 2000001u) - 1000000) * 1e-6L *
                                         3.14159265358979323846264338L * std::ldexp(1.0L, 61));
            v.h_nm = (int64_t)(gg.u64() % 20000000u) * INT64_C(1000000) - INT64_C(1000000000000);
            v.quat_status = ct_quat_from_ypr(v.ypr_q61[0], v.ypr_q61[1], v.ypr_q61[2], v.q_q30);
            {
                ct_pose pose{};
                v.pose_status = ct_pose_from_wgs84(&pose, &v.zone, v.lat_q61, v.lon_q61, v.h_nm, v.q_q30);
                if (v.pose_status == CT_OK) {
                    for (int a = 0; a < 9; ++a) v.R_q30[a] = pose.R_map_cam_q30[a];
                    v.hscale_q30 = pose.hscale_q30;
                }
            }
            geo.push_back(v);
        }
    }
    std::fprintf(f, "static const ct_vec_geo geo[%zu] = {\n", geo.size());
    for (const ct_vec_geo &v : geo)
    {
        std::fprintf(f, "  {{%d, %d}, %s, %s, %d, %s, %s, %d, %s, %s, %d, %s, %s,\n   {%s, %s, %s}, %s, %d, {", (int)v.zone.zone,
                     (int)v.zone.south, i64(v.lat_q61).c_str(), i64(v.lon_q61).c_str(), (int)v.fwd_status,
                     i64(v.e_nm).c_str(), i64(v.n_nm).c_str(), (int)v.inv_status, i64(v.lat2_q61).c_str(),
                     i64(v.lon2_q61).c_str(), (int)v.fac_status, i64(v.gamma_q61).c_str(), i64(v.k_q61).c_str(),
                     i64(v.ypr_q61[0]).c_str(), i64(v.ypr_q61[1]).c_str(), i64(v.ypr_q61[2]).c_str(),
                     i64(v.h_nm).c_str(), (int)v.quat_status);
        for (int a = 0; a < 4; ++a) std::fprintf(f, "%s, ", i32(v.q_q30[a]).c_str());
        std::fprintf(f, "}, %d, {", (int)v.pose_status);
        for (int a = 0; a < 9; ++a) std::fprintf(f, "%s, ", i32(v.R_q30[a]).c_str());
        std::fprintf(f, "}, %s},\n", i32(v.hscale_q30).c_str());
    }
    std::fprintf(f, "};\n\n");
    return geo.size();
}

size_t emit_ecef(FILE *f)
{
    // geodetic <-> Earth-fixed: every latitude (the poles exactly), every
    // longitude (+-180 exactly), heights -5,000 .. 22,000 km (some beyond
    // the forward's domain), the forward's result inverted; where the
    // forward refuses, a made-up point of the cube |.| <= 2^55.3 (some
    // outside the inverse's domain, or within 2^50 nm of the centre)
    std::vector<ct_vec_ecef> ecef;
    {
        Rng gg(4978u);
        for (int k = 0; k < 48; ++k) {
            ct_vec_ecef v{};
            const uint64_t pi = (uint64_t)CT_PI_Q61;
            uint64_t pick = gg.u64() % 12u;
            v.lat_q61 = pick == 0 ? CT_PI_Q61 / 2 : pick == 1 ? -(CT_PI_Q61 / 2) : (int64_t)(gg.u64() % (pi + 1u)) - CT_PI_Q61 / 2;
            pick = gg.u64() % 12u;
            v.lon_q61 = pick == 0 ? CT_PI_Q61 : pick == 1 ? -CT_PI_Q61 : (int64_t)(gg.u64() % (2u * pi + 1u)) - CT_PI_Q61;
            v.h_nm = (int64_t)(gg.u64() % 27000000u) * INT64_C(1000000000) - INT64_C(5000000000000000) +
                     (int64_t)(gg.u64() % 1000000000u);
            v.fwd_status = ct_ecef_from_wgs84(v.lat_q61, v.lon_q61, v.h_nm, v.xyz_nm);
            for (int a = 0; a < 3; ++a)
                v.in_nm[a] = v.fwd_status == CT_OK ? v.xyz_nm[a]
                                                   : (int64_t)(gg.u64() % (UINT64_C(5) << 54)) - (INT64_C(5) << 53);
            if (k % 16 == 15) {  // near the centre: 2^49.5 .. 2^50.5 on one axis
                v.in_nm[0] = v.in_nm[1] = 0;
                v.in_nm[2] = (INT64_C(3) << 48) + (int64_t)(gg.u64() % (UINT64_C(3) << 48));
            }
            v.inv_status = ct_wgs84_from_ecef(v.in_nm, &v.lat2_q61, &v.lon2_q61, &v.h2_nm);
            ecef.push_back(v);
        }
    }
    std::fprintf(f, "static const ct_vec_ecef ecef[%zu] = {\n", ecef.size());
    for (const ct_vec_ecef &v : ecef)
        std::fprintf(f, "  {%s, %s, %s, %d, {%s, %s, %s},\n   {%s, %s, %s}, %d, %s, %s, %s},\n", i64(v.lat_q61).c_str(),
                     i64(v.lon_q61).c_str(), i64(v.h_nm).c_str(), (int)v.fwd_status, i64(v.xyz_nm[0]).c_str(),
                     i64(v.xyz_nm[1]).c_str(), i64(v.xyz_nm[2]).c_str(), i64(v.in_nm[0]).c_str(), i64(v.in_nm[1]).c_str(),
                     i64(v.in_nm[2]).c_str(), (int)v.inv_status, i64(v.lat2_q61).c_str(), i64(v.lon2_q61).c_str(),
                     i64(v.h2_nm).c_str());
    std::fprintf(f, "};\n\n");
    return ecef.size();
}

// The vertical datum: ct_geoid_at on the synthetic grids; *npoints the
// points emitted.
size_t emit_geoid(FILE *f, size_t *npoints)
{
    const std::vector<GGrid> ggrids = geoid_grids();
    std::vector<ct_vec_geoid> gpts;
    {
        Rng gg(5773u);
        gpts = geoid_points(gg, ggrids);
    }
    for (size_t k = 0; k < ggrids.size(); ++k) {
        const GGrid &G = ggrids[k];
        if (G.null_values) continue;
        std::fprintf(f, "static const uint8_t geoid_grid%zu_values[%zu] = {", k, G.bytes.size());
        for (size_t i = 0; i < G.bytes.size(); ++i) std::fprintf(f, "%s0x%02x,", (i % 16) ? " " : "\n    ", G.bytes[i]);
        std::fprintf(f, "\n};\n\n");
    }
    std::fprintf(f, "static const ct_geoid_grid geoid_grids[%zu] = {\n", ggrids.size());
    for (size_t k = 0; k < ggrids.size(); ++k) {
        const GGrid &G = ggrids[k];
        char vals[64];
        if (G.null_values)
            std::snprintf(vals, sizeof vals, "(const uint8_t *)0");
        else
            std::snprintf(vals, sizeof vals, "geoid_grid%zu_values", k);
        std::fprintf(f, "  {.w = %uu, .h = %uu, .lat0_q61 = %s, .lon0_q61 = %s, .step_q61 = %s, .values = %s},\n", G.w, G.h,
                     i64(G.lat0).c_str(), i64(G.lon0).c_str(), i64(G.step).c_str(), vals);
    }
    std::fprintf(f, "};\n\nstatic const ct_vec_geoid geoid[%zu] = {\n", gpts.size());
    for (const ct_vec_geoid &v : gpts)
        std::fprintf(f, "  {%uu, %s, %s, %d, %s},\n", v.grid, i64(v.lat_q61).c_str(), i64(v.lon_q61).c_str(), (int)v.status,
                     i64(v.n_nm).c_str());
    std::fprintf(f, "};\n\n");
    {
        int counts[2] = {0, 0};
        for (const ct_vec_geoid &v : gpts) counts[v.status == CT_OK ? 0 : 1]++;
        std::fprintf(stderr, "gen_vectors: geoid: %zu grids, %zu points: %d inside, %d refused\n", ggrids.size(),
                     gpts.size(), counts[0], counts[1]);
    }
    *npoints = gpts.size();
    return ggrids.size();
}

// The datum package: a tile on zone 17N with a datum section, and map
// points' undulations (*generator says so if the builder failed).
void emit_datum(FILE *f, std::string *generator)
{
    const GGrid dg = datum_geoid();
    ct_utm z17{};
    int64_t ce = 0, cn = 0;
    if (ct_utm_zone_of_epsg(DATUM_EPSG, &z17) != CT_OK ||
        ct_utm_forward(&z17, q61_deg(35.6L), q61_deg(-81.6L), &ce, &cn) != CT_OK)
        die("datum package: UTM 17N");
    const double oe = std::floor((double)ce / 30e9) * 30.0, on = std::floor((double)cn / 30e9) * 30.0;
    std::vector<uint8_t> bytes;
    std::string dname = "datum_egm96_degenerate";
    ct_package dp;
    ct_vec_datum_package dv{};
#ifdef CT_GEN_USE_BUILDER
    dname = "datum_egm96_build_package";
    try {
        bytes = build_datum_with_builder(dg, oe, on, ct_host::PptBuilder::Slices);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "gen_vectors: WARNING: build_package (datum package) threw: %s\n", e.what());
    }
    dv.open_status = bytes.empty() ? CT_ERR_ARG : ct_package_open(&dp, bytes.data(), bytes.size());
    if (dv.open_status != CT_OK || (dp.flags & CT_PKG_FLAG_DATUM) == 0u) {
        std::fprintf(stderr, "gen_vectors: WARNING: datum package rejected (%d)\n", (int)dv.open_status);
        *generator = "degenerate (FALLBACK: build_package failed)";
        bytes.clear();
    }
#endif
    if (bytes.empty()) {
        dname = "datum_egm96_degenerate";
        try {
            bytes = build_datum_with_builder(dg, oe, on, ct_host::PptBuilder::Degenerate);
        } catch (const std::exception &e) {
            die(std::string("build_package (degenerate datum package) threw: ") + e.what());
        }
    }
    dv.open_status = ct_package_open(&dp, bytes.data(), bytes.size());
    if (dv.open_status != CT_OK) die("host ct_package_open (datum package): " + std::to_string(dv.open_status));
    dv.verify_status = ct_package_verify(&dp);
    dv.flags = dp.flags;
    dv.epsg = dp.epsg;
    dv.vdatum = dp.vdatum;
    dv.source_epsg = dp.source_epsg;
    dv.geoid_w = dp.geoid.w;
    dv.geoid_h = dp.geoid.h;
    dv.geoid_lat0_q61 = dp.geoid.lat0_q61;
    dv.geoid_lon0_q61 = dp.geoid.lon0_q61;
    dv.geoid_step_q61 = dp.geoid.step_q61;
    dv.geoid_values_off = (uint32_t)(dp.geoid.values - bytes.data());
    if (dv.vdatum != CT_VDATUM_EGM96 || dv.geoid_w != dg.w || dv.source_epsg != (uint32_t)DATUM_SOURCE_EPSG)
        die("datum package: datum section not as built");
    // map points: in the tile (corners too), around it within the
    // geoid, 100 km off (outside the geoid), off the zone, anything
    std::vector<ct_vec_map_geoid> mp;
    Rng gm(32617u);
    const int64_t span = (int64_t)(DW - 1) * nm(POSTING_M);
    for (int k = 0; k < 24; ++k) {
        ct_vec_map_geoid v{};
        v.e_nm = dp.origin_e_nm + gm.range(0, span);
        v.n_nm = dp.origin_n_nm - gm.range(0, span);
        if (k == 0) {
            v.e_nm = dp.origin_e_nm;
            v.n_nm = dp.origin_n_nm;
        } else if (k == 1) {
            v.e_nm = dp.origin_e_nm + span;
            v.n_nm = dp.origin_n_nm - span;
        } else if (k >= 12 && k < 18) {
            v.e_nm += gm.range(-INT64_C(20000000000000), INT64_C(20000000000000));
            v.n_nm += gm.range(-INT64_C(20000000000000), INT64_C(20000000000000));
        } else if (k >= 18 && k < 21) {
            v.e_nm += k == 20 ? -INT64_C(100000000000000) : 0;
            v.n_nm += k == 18 ? INT64_C(100000000000000) : k == 19 ? -INT64_C(100000000000000) : 0;
        } else if (k == 21) {
            v.e_nm = INT64_C(5000000000000000);
        } else if (k >= 22) {
            v.e_nm = (int64_t)gm.u64();
            v.n_nm = (int64_t)gm.u64();
        }
        v.status = ct_package_geoid(&dp, v.e_nm, v.n_nm, &v.n_geoid_nm);
        mp.push_back(v);
    }
    int ok = 0;
    for (const ct_vec_map_geoid &v : mp) ok += v.status == CT_OK;
    std::fprintf(stderr, "gen_vectors: %s: %zu bytes, %zu map points: %d with a geoid, %zu refused\n", dname.c_str(),
                 bytes.size(), mp.size(), ok, mp.size() - (size_t)ok);
    std::fprintf(f, "static const union {\n    uint64_t align;\n    uint8_t b[%zu];\n} datum_pkg_bytes = {.b = {",
                 bytes.size());
    for (size_t i = 0; i < bytes.size(); ++i) std::fprintf(f, "%s0x%02x,", (i % 16) ? " " : "\n    ", bytes[i]);
    std::fprintf(f, "\n}};\n\nstatic const ct_vec_map_geoid datum_points[%zu] = {\n", mp.size());
    for (const ct_vec_map_geoid &v : mp)
        std::fprintf(f, "  {%s, %s, %d, %s},\n", i64(v.e_nm).c_str(), i64(v.n_nm).c_str(), (int)v.status,
                     i64(v.n_geoid_nm).c_str());
    std::fprintf(f, "};\n\nstatic const ct_vec_datum_package datum[1] = {\n");
    std::fprintf(f, "  {.name = \"%s\", .bytes = datum_pkg_bytes.b, .size = %zuu, .open_status = %d, .verify_status = %d,\n",
                 dname.c_str(), bytes.size(), (int)dv.open_status, (int)dv.verify_status);
    std::fprintf(f, "   .flags = %uu, .epsg = %uu, .vdatum = %uu, .source_epsg = %uu, .geoid_w = %uu, .geoid_h = %uu,\n",
                 dv.flags, dv.epsg, dv.vdatum, dv.source_epsg, dv.geoid_w, dv.geoid_h);
    std::fprintf(f, "   .geoid_lat0_q61 = %s, .geoid_lon0_q61 = %s, .geoid_step_q61 = %s, .geoid_values_off = %uu,\n",
                 i64(dv.geoid_lat0_q61).c_str(), i64(dv.geoid_lon0_q61).c_str(), i64(dv.geoid_step_q61).c_str(),
                 dv.geoid_values_off);
    std::fprintf(f, "   .points = datum_points, .npoints = %zuu},\n};\n\n", mp.size());
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: gen_vectors <out.c> [rays-per-package]\n");
        return 2;
    }
    const int nrays = argc > 2 ? std::atoi(argv[2]) : 300;
    const Dem dem = make_dem();
#ifdef CT_GEN_USE_BUILDER
    std::string generator = "build_package";
#else
    std::string generator = "degenerate";
#endif
    const std::vector<Pkg> pkgs = make_packages(dem, nrays, &generator);
    std::vector<ct_vec_fixed> fx;
    std::vector<ct_vec_dir> dirs;
    make_fixed(&fx, &dirs);
    std::vector<const ct_package *> pk;
    for (const Pkg &P : pkgs) pk.push_back(&P.p);
    Rng gc(20251125u);
    const std::vector<Cam> cams = make_cameras(gc, pk);
    const std::vector<TSet> tsets = make_tilesets(dem, pkgs[0], cams);

    FILE *f = std::fopen(argv[1], "w");
    if (!f) die(std::string("cannot write ") + argv[1]);
    std::fprintf(f, "/* Generated by tests/mcu/gen_vectors.cpp -- do not edit. */\n#include \"ct_vectors.h\"\n\n");
    emit_packages(f, pkgs);
    emit_fixed(f, fx, dirs);
    emit_cameras(f, cams);
    emit_tilesets(f, tsets);
    const size_t ngeo = emit_geodesy(f);
    const size_t necef = emit_ecef(f);
    size_t ngpts = 0;
    const size_t ngrids = emit_geoid(f, &ngpts);
    emit_datum(f, &generator);
    std::fprintf(f,
                 "const ct_vec_set ct_vectors = {packages, %zuu, fixed, %zuu, dirs, %zuu, \"%s\", cameras, %zuu, geo, "
                 "%zuu, ecef, %zuu,\n    geoid_grids, %zuu, geoid, %zuu, datum, 1u, tilesets, %zuu};\n",
                 pkgs.size(), fx.size(), dirs.size(), generator.c_str(), cams.size(), ngeo, necef, ngrids, ngpts,
                 tsets.size());
    if (std::fclose(f) != 0) die("write error");
    return 0;
}
