// earth_reference.hpp -- independent reference for geolocation with the
// earth's curvature (tests only; header-only C++17, long double, PROJ).
//
// The line of sight is a straight line in Earth-fixed coordinates
// (EPSG:4978), optionally bent down by refraction:
//     P(t) = C + t d - k t^2 / (2 R) w,   t >= 0 metres, R = 6371 km,
// C the camera centre, d the unit direction, w = u - (u.d) d, u the
// ellipsoid normal at C: perpendicular to d in the vertical plane through
// d, pointing up, of length cos(elevation) -- the textbook ray curvature
// k cos(elev) / R of a layered atmosphere, whose vertical drop
// k t^2 cos^2(elev) / 2R is the parabola model's k rho^2 / 2R (w = 0 for a
// vertical ray).  The terrain is the package's bilinear surface over its
// posts in the map frame (UTM E, N; h = height_offset + code * scale,
// taken as WGS84 ellipsoidal heights): post (i, j) at
//     E = origin_e + (i + 1/2) posting_e,  N = origin_n + (j + 1/2) posting_n.
// The hit is the first point of the path (smallest t) at or below the
// surface, inside the tile's post box: a path that enters the box from
// outside below the surface hits the box's side there (Result::wall), a
// camera inside the box below the surface is BELOW.
//
// How: the path is sampled in t (step <= posting / 8 of horizontal range)
// and every sample is mapped through PROJ (EPSG:4978 -> EPSG:4979 for lat,
// lon, h; EPSG:4326 -> EPSG:326zz/327zz for E, N).  Between two samples the
// mapped path is a straight segment to within ~0.3 um (its height is
// quadratic in t with curvature 1/R; its sideways bend is ~1e-8 m over a
// step), and that segment is intersected exactly with the bilinear patch
// of every cell it touches (a quadratic per cell).  The first root is then
// refined by bisection on the true path F(t) = h(P(t)) - S(E(t), N(t))
// to < 0.1 um in t.  Where the path is certainly clear of the terrain (above
// the tile's highest post by > 1 m, or farther outside the tile's box than
// the next step) it is sampled coarsely (every 64 m of t).
//
// The result also reports the smallest clearance (path height minus
// surface, vertical) at a local minimum of the clearance before the hit
// (for a miss: anywhere over the tile) -- near-grazing rays, where a
// different but valid tracer may legitimately touch a sliver of terrain
// the other one passes, can be skipped by the caller.
//
// Camera: either the library's ct_pose (the spec of the library's exact
// mode: C = the pose's (E, N) through the UTM inverse with the pose's h;
// d = R_map_cam ray turned from grid north to true north by the meridian
// convergence gamma at C, then local ENU -> ECEF), or a WGS84 position and
// a NED attitude quaternion (independent of the library's pose code: no
// convergence involved at all).  The convergence is measured numerically
// from PROJ's projection (the grid azimuth of the meridian through C, by
// central differences), so its sign is PROJ's by construction: gamma =
// bearing of grid north clockwise from true north, true azimuth = grid
// azimuth + gamma.
#pragma once

#include <proj.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

#include "conetrace.h"
#include "proj_pair.hpp"

namespace earth_ref {

typedef long double ld;

const ld kWgsA = 6378137.0L;
const ld kWgsF = 1.0L / 298.257223563L;
const ld kWgsE2 = kWgsF * (2.0L - kWgsF);
const ld kRefractionRadius = 6371000.0L;  // R of the refraction arc (k t^2 / 2R)
const ld kPi = 3.141592653589793238462643383279502884L;

enum { HIT = CT_HIT, MISS = CT_MISS, BELOW = CT_BELOW };

// ---------------------------------------------------------------------------
// PROJ transformations (lon, lat order after normalisation; degrees, metres)
struct Proj {
    PJ_CONTEXT *ctx = nullptr;
    PJ *ecef_to_geo = nullptr;  // EPSG:4978 -> EPSG:4979
    PJ *geo_to_ecef = nullptr;  // EPSG:4979 -> EPSG:4978
    PJ *geo_to_utm = nullptr;   // EPSG:4326 -> EPSG:epsg
    int epsg = 0;
    long calls = 0;

    static PJ *make(PJ_CONTEXT *c, const char *a, const char *b) { return proj_normalized(c, a, b); }
    explicit Proj(int epsg_code) : epsg(epsg_code)
    {
        if (!((epsg >= 32601 && epsg <= 32660) || (epsg >= 32701 && epsg <= 32760)))
            throw std::runtime_error("earth_ref::Proj: not a UTM zone EPSG code");
        ctx = proj_context_create();
        char dst[32];
        std::snprintf(dst, sizeof dst, "EPSG:%d", epsg);
        ecef_to_geo = make(ctx, "EPSG:4978", "EPSG:4979");
        geo_to_ecef = make(ctx, "EPSG:4979", "EPSG:4978");
        geo_to_utm = make(ctx, "EPSG:4326", dst);
        if (!ecef_to_geo || !geo_to_ecef || !geo_to_utm) throw std::runtime_error("earth_ref::Proj: PROJ cannot make the transformations");
    }
    ~Proj()
    {
        if (ecef_to_geo) proj_destroy(ecef_to_geo);
        if (geo_to_ecef) proj_destroy(geo_to_ecef);
        if (geo_to_utm) proj_destroy(geo_to_utm);
        proj_context_destroy(ctx);
    }
    Proj(const Proj &) = delete;
    Proj &operator=(const Proj &) = delete;

    // ECEF (m) -> E, N (m), h (m, ellipsoidal)
    void map(const ld X[3], ld *E, ld *N, ld *h)
    {
        calls++;
        PJ_COORD g = proj_trans(ecef_to_geo, PJ_FWD, proj_coord((double)X[0], (double)X[1], (double)X[2], 0));
        PJ_COORD m = proj_trans(geo_to_utm, PJ_FWD, proj_coord(g.lpz.lam, g.lpz.phi, 0, 0));
        *E = m.xy.x;
        *N = m.xy.y;
        *h = g.lpz.z;
    }
    // geodetic (deg, deg, m) -> ECEF (m)
    void ecef(ld lat_deg, ld lon_deg, ld h, ld X[3])
    {
        PJ_COORD c = proj_trans(geo_to_ecef, PJ_FWD, proj_coord((double)lon_deg, (double)lat_deg, (double)h, 0));
        X[0] = c.xyz.x;
        X[1] = c.xyz.y;
        X[2] = c.xyz.z;
    }
    void utm(ld lat_deg, ld lon_deg, ld *E, ld *N)
    {
        PJ_COORD m = proj_trans(geo_to_utm, PJ_FWD, proj_coord((double)lon_deg, (double)lat_deg, 0, 0));
        *E = m.xy.x;
        *N = m.xy.y;
    }
    void utm_inverse(ld E, ld N, ld *lat_deg, ld *lon_deg)
    {
        PJ_COORD g = proj_trans(geo_to_utm, PJ_INV, proj_coord((double)E, (double)N, 0, 0));
        *lon_deg = g.lp.lam;
        *lat_deg = g.lp.phi;
    }
    // meridian convergence (radians, PROJ's sign: the bearing of grid north
    // clockwise from true north) from the image of the meridian through the
    // point: true north's grid azimuth is atan2(dE, dN) = -gamma.
    ld convergence(ld lat_deg, ld lon_deg)
    {
        const ld dl = 1e-4L;  // ~11 m; central differences
        ld e1, n1, e2, n2;
        utm(lat_deg + dl, lon_deg, &e1, &n1);
        utm(lat_deg - dl, lon_deg, &e2, &n2);
        return -std::atan2(e1 - e2, n1 - n2);
    }
};

// ---------------------------------------------------------------------------
// The terrain: bilinear surface over the posts, map frame, metres.
struct Surface {
    int w = 0, h = 0;               // posts
    ld oe = 0, on = 0, pe = 0, pn = 0;  // corner origin and posting (m)
    std::vector<ld> z;              // post heights (m), row-major
    ld zmin = 0, zmax = 0;
    int epsg = 0;

    static Surface from_package(const ct_package &p)
    {
        Surface s;
        s.w = (int)p.width;
        s.h = (int)p.height;
        s.oe = (ld)p.origin_e_nm * 1e-9L;
        s.on = (ld)p.origin_n_nm * 1e-9L;
        s.pe = (ld)p.posting_e_nm * 1e-9L;
        s.pn = (ld)p.posting_n_nm * 1e-9L;
        s.epsg = (int)p.epsg;
        s.z.resize((size_t)s.w * s.h);
        s.zmin = std::numeric_limits<ld>::infinity();
        s.zmax = -s.zmin;
        for (size_t k = 0; k < s.z.size(); ++k) {
            const uint32_t code = (uint32_t)p.heights[2 * k] | (uint32_t)p.heights[2 * k + 1] << 8;
            s.z[k] = ((ld)p.height_offset_nm + (ld)code * (ld)p.height_scale_nm) * 1e-9L;
            s.zmin = std::min(s.zmin, s.z[k]);
            s.zmax = std::max(s.zmax, s.z[k]);
        }
        return s;
    }
    ld at(int i, int j) const { return z[(size_t)j * w + i]; }
    // grid (post units, post (i, j) at (i, j)) of a map point
    void grid(ld E, ld N, ld *x, ld *y) const
    {
        *x = (E - oe) / pe - 0.5L;
        *y = (N - on) / pn - 0.5L;
    }
    void map_of(ld x, ld y, ld *E, ld *N) const
    {
        *E = oe + (x + 0.5L) * pe;
        *N = on + (y + 0.5L) * pn;
    }
    bool inside(ld x, ld y) const { return x >= 0 && y >= 0 && x <= w - 1 && y <= h - 1; }
    // distance (in posts, max norm) outside the box, 0 inside
    ld outside_by(ld x, ld y) const
    {
        ld dx = std::max<ld>(0, std::max(-x, x - (w - 1)));
        ld dy = std::max<ld>(0, std::max(-y, y - (h - 1)));
        return std::max(dx, dy);
    }
    ld height(ld x, ld y) const  // inside the box
    {
        int i = std::min(w - 2, std::max(0, (int)std::floor(x)));
        int j = std::min(h - 2, std::max(0, (int)std::floor(y)));
        ld u = x - i, v = y - j;
        ld h00 = at(i, j), h10 = at(i + 1, j), h01 = at(i, j + 1), h11 = at(i + 1, j + 1);
        return h00 + (h10 - h00) * u + (h01 - h00) * v + (h11 - h10 - h01 + h00) * u * v;
    }
    // the surface under a map point, or the mean height off the tile (where
    // test poses put a camera a given height above the ground)
    ld ground_under(ld E, ld N) const
    {
        ld x, y;
        grid(E, N, &x, &y);
        if (inside(x, y)) return height(x, y);
        ld s = 0;
        for (ld v : z) s += v;
        return s / z.size();
    }
};

// ---------------------------------------------------------------------------
// Small vector helpers
inline ld dot3(const ld a[3], const ld b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline void normalise3(ld a[3])
{
    ld n = std::sqrt(dot3(a, a));
    for (int k = 0; k < 3; ++k) a[k] /= n;
}
// local east, north, up unit vectors (ECEF) at geodetic lat, lon (deg)
inline void enu_axes(ld lat_deg, ld lon_deg, ld e[3], ld n[3], ld u[3])
{
    ld la = lat_deg * kPi / 180, lo = lon_deg * kPi / 180;
    e[0] = -std::sin(lo);
    e[1] = std::cos(lo);
    e[2] = 0;
    n[0] = -std::sin(la) * std::cos(lo);
    n[1] = -std::sin(la) * std::sin(lo);
    n[2] = std::cos(la);
    u[0] = std::cos(la) * std::cos(lo);
    u[1] = std::cos(la) * std::sin(lo);
    u[2] = std::sin(la);
}

// Geodetic height of an ECEF point in long double (own iteration, used
// only by tests' closed-form checks, not by the tracer).
inline void geodetic_ld(const ld X[3], ld *lat_rad, ld *lon_rad, ld *h)
{
    ld p = std::sqrt(X[0] * X[0] + X[1] * X[1]);
    ld lat = std::atan2(X[2], p * (1 - kWgsE2)), hh = 0;
    for (int it = 0; it < 12; ++it) {
        ld s = std::sin(lat), c = std::cos(lat);
        ld Nr = kWgsA / std::sqrt(1 - kWgsE2 * s * s);
        hh = std::fabs(c) > 0.5L ? p / c - Nr : X[2] / s - Nr * (1 - kWgsE2);
        lat = std::atan2(X[2], p * (1 - kWgsE2 * Nr / (Nr + hh)));
    }
    *lat_rad = lat;
    *lon_rad = std::atan2(X[1], X[0]);
    *h = hh;
}

// ---------------------------------------------------------------------------
// The line of sight
struct Los {
    ld C[3] = {0, 0, 0};  // ECEF camera centre (m)
    ld d[3] = {0, 0, 0};  // ECEF unit direction
    ld w[3] = {0, 0, 0};  // ECEF "up" made perpendicular to d: length cos(elevation), 0 for a vertical d
    ld kr = 0;            // refraction: P(t) = C + t d - kr t^2 w, kr = k / (2R)
    ld lat = 0, lon = 0, h = 0;  // camera centre, geodetic (deg, deg, m)
    ld gamma = 0;         // convergence at C used (radians; from_pose only)
    void at(ld t, ld P[3]) const
    {
        for (int k = 0; k < 3; ++k) P[k] = C[k] + t * d[k] - kr * t * t * w[k];
    }
    ld depression_deg() const  // below the local horizontal at C
    {
        ld e[3], n[3], u[3];
        enu_axes(lat, lon, e, n, u);
        return -std::asin(std::max<ld>(-1, std::min<ld>(1, dot3(d, u)))) * 180 / kPi;
    }
};

// Effects: only CT_EFFECT_CURVATURE (a straight Earth-fixed line) and
// CT_EFFECT_REFRACTION (k from refraction_k_q16) are read.
inline void set_effects(Los &L, const ct_effects *fx, const ld u[3])
{
    L.kr = 0;
    for (int k = 0; k < 3; ++k) L.w[k] = 0;
    if (fx == nullptr || (fx->flags & CT_EFFECT_REFRACTION) == 0u) return;
    const ld kk = (ld)fx->refraction_k_q16 / 65536.0L;
    ld ud = dot3(u, L.d);
    for (int k = 0; k < 3; ++k) L.w[k] = u[k] - ud * L.d[k];  // |w| = cos(elevation)
    L.kr = kk / (2 * kRefractionRadius);
}

// The camera-frame ray (x right, y down, z forward) of a pinhole pixel
inline void pinhole_ray(ld fx, ld fy, ld cx, ld cy, ld u, ld v, ld r[3])
{
    r[0] = (u - cx) / fx;
    r[1] = (v - cy) / fy;
    r[2] = 1;
    normalise3(r);
}

// The library's exact mode, as specified: from a ct_pose.
inline Los los_from_pose(Proj &pj, const ct_pose &pose, const ld ray_cam[3], const ct_effects *fx)
{
    Los L;
    const ld E = (ld)pose.e_nm * 1e-9L, N = (ld)pose.n_nm * 1e-9L;
    pj.utm_inverse(E, N, &L.lat, &L.lon);
    L.h = (ld)pose.h_nm * 1e-9L;
    pj.ecef(L.lat, L.lon, L.h, L.C);
    ld m[3];  // grid east, grid north, up
    for (int r = 0; r < 3; ++r) {
        m[r] = 0;
        for (int c = 0; c < 3; ++c) m[r] += (ld)pose.R_map_cam_q30[3 * r + c] / 1073741824.0L * ray_cam[c];
    }
    L.gamma = pj.convergence(L.lat, L.lon);
    const ld cg = std::cos(L.gamma), sg = std::sin(L.gamma);
    // true azimuth = grid azimuth + gamma: grid north (0, 1) -> (sin g, cos g)
    const ld te = m[0] * cg + m[1] * sg, tn = -m[0] * sg + m[1] * cg, tu = m[2];
    ld e[3], n[3], u[3];
    enu_axes(L.lat, L.lon, e, n, u);
    for (int k = 0; k < 3; ++k) L.d[k] = te * e[k] + tn * n[k] + tu * u[k];
    normalise3(L.d);
    set_effects(L, fx, u);
    return L;
}

// The same from the navigation solution directly: WGS84 lat, lon (deg),
// ellipsoidal h (m), and a unit quaternion q = (w, x, y, z) rotating
// camera-frame vectors into local north-east-down.
inline Los los_from_wgs84(Proj &pj, ld lat_deg, ld lon_deg, ld h, const ld q_in[4], const ld ray_cam[3],
                          const ct_effects *fx)
{
    Los L;
    L.lat = lat_deg;
    L.lon = lon_deg;
    L.h = h;
    pj.ecef(lat_deg, lon_deg, h, L.C);
    ld qn = std::sqrt(q_in[0] * q_in[0] + q_in[1] * q_in[1] + q_in[2] * q_in[2] + q_in[3] * q_in[3]);
    const ld w = q_in[0] / qn, x = q_in[1] / qn, y = q_in[2] / qn, z = q_in[3] / qn;
    const ld R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                        {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                        {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    ld ned[3];
    for (int r = 0; r < 3; ++r) ned[r] = R[r][0] * ray_cam[0] + R[r][1] * ray_cam[1] + R[r][2] * ray_cam[2];
    ld e[3], n[3], u[3];
    enu_axes(lat_deg, lon_deg, e, n, u);
    for (int k = 0; k < 3; ++k) L.d[k] = ned[0] * n[k] + ned[1] * e[k] - ned[2] * u[k];
    normalise3(L.d);
    set_effects(L, fx, u);
    return L;
}

// Q30 quaternion (as ct_quat_from_ypr makes it) to long double
inline void quat_of_q30(const int32_t q[4], ld out[4])
{
    for (int k = 0; k < 4; ++k) out[k] = (ld)q[k] / 1073741824.0L;
}

// ---------------------------------------------------------------------------
// The trace
struct Result {
    int status = MISS;
    ld e = 0, n = 0, h = 0;   // hit, map frame (m)
    ld t = 0;                 // path parameter at the hit (m)
    ld range = 0;             // map-frame horizontal distance camera -> hit (m)
    ld min_clear = std::numeric_limits<ld>::infinity();  // smallest clearance at a local
                              // minimum before the hit (miss: over the tile), m
    long samples = 0;         // PROJ-mapped samples
    bool wall = false;        // HIT where the path enters the tile's box below the
                              // surface (from outside): the hit is on the box's side
};

namespace detail {

struct Sample {
    ld t, E, N, h, x, y;
};

// the mapped sample at t
inline Sample sample(Proj &pj, const Surface &s, const Los &L, ld t)
{
    Sample o;
    ld P[3];
    L.at(t, P);
    o.t = t;
    pj.map(P, &o.E, &o.N, &o.h);
    s.grid(o.E, o.N, &o.x, &o.y);
    return o;
}

// F(t) = path height - surface (+inf outside the tile)
inline ld clearance(Proj &pj, const Surface &s, const Los &L, ld t)
{
    Sample o = sample(pj, s, L, t);
    if (!s.inside(o.x, o.y)) return std::numeric_limits<ld>::infinity();
    return o.h - s.height(o.x, o.y);
}

// On the straight segment a -> b (s in [0, 1]): the first s where the
// segment is at or below the surface (-1: none); *entry_below when that
// is the segment's first point in the tile and it is below; clearance
// minima appended to `mins` as (s, f) at local minima (interior vertices
// of a cell's quadratic, and cell-boundary points).
struct SegOut {
    ld s = -1;
    bool at_entry = false;  // the root is the first in-tile point of the segment
    ld f_entry = 0;
};

inline SegOut segment_root(const Surface &sf, const Sample &a, const Sample &b, std::vector<std::pair<ld, ld>> &pts)
{
    SegOut out;
    const ld dx = b.x - a.x, dy = b.y - a.y, dz = b.h - a.h;
    int i0 = (int)std::floor(std::min(a.x, b.x)), i1 = (int)std::floor(std::max(a.x, b.x));
    int j0 = (int)std::floor(std::min(a.y, b.y)), j1 = (int)std::floor(std::max(a.y, b.y));
    i0 = std::max(i0, 0);
    j0 = std::max(j0, 0);
    i1 = std::min(i1, sf.w - 2);
    j1 = std::min(j1, sf.h - 2);
    ld best = -1, entry = std::numeric_limits<ld>::infinity();
    ld best_f0 = 0;
    struct Piece {
        ld s0, s1;
        int i, j;
    };
    std::vector<Piece> pieces;
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
            ld lo = 0, hi = 1;
            auto axis = [&](ld o, ld dd, ld c0, ld c1) {
                if (dd == 0) return o >= c0 && o <= c1;
                ld ta = (c0 - o) / dd, tb = (c1 - o) / dd;
                if (ta > tb) std::swap(ta, tb);
                lo = std::max(lo, ta);
                hi = std::min(hi, tb);
                return true;
            };
            if (!axis(a.x, dx, i, i + 1) || !axis(a.y, dy, j, j + 1) || lo > hi) continue;
            pieces.push_back({lo, hi, i, j});
            entry = std::min(entry, lo);
        }
    for (const Piece &pc : pieces) {
        const int i = pc.i, j = pc.j;
        const ld h00 = sf.at(i, j), h10 = sf.at(i + 1, j), h01 = sf.at(i, j + 1), h11 = sf.at(i + 1, j + 1);
        const ld ca = h10 - h00, cb = h01 - h00, cc = h11 - h10 - h01 + h00;
        const ld u0 = a.x - i, v0 = a.y - j;
        const ld A = -cc * dx * dy;
        const ld B = dz - ca * dx - cb * dy - cc * (u0 * dy + v0 * dx);
        const ld C0 = a.h - h00 - ca * u0 - cb * v0 - cc * u0 * v0;
        auto f = [&](ld s) { return (A * s + B) * s + C0; };
        const ld s0 = pc.s0, s1 = pc.s1;
        ld root = -1;
        if (f(s0) <= 0) {
            root = s0;
        } else {
            ld r[2];
            int nr = 0;
            if (A == 0) {
                if (B != 0) r[nr++] = -C0 / B;
            } else {
                ld D = B * B - 4 * A * C0;
                if (D >= 0) {
                    ld sq = std::sqrt(D);
                    ld q = -0.5L * (B + (B >= 0 ? sq : -sq));
                    if (q != 0) {
                        r[nr++] = q / A;
                        r[nr++] = C0 / q;
                    } else {
                        r[nr++] = -B / (2 * A);
                    }
                }
            }
            for (int k = 0; k < nr; ++k)
                if (r[k] >= s0 && r[k] <= s1 && (root < 0 || r[k] < root)) root = r[k];
            if (root < 0 && f(s1) <= 0) root = s1;
        }
        // clearance samples of this piece: ends and an interior minimum
        pts.push_back({s0, f(s0)});
        if (A > 0) {
            ld sv = -B / (2 * A);
            if (sv > s0 && sv < s1) pts.push_back({sv, f(sv)});
        }
        pts.push_back({s1, f(s1)});
        if (root >= 0 && (best < 0 || root < best)) {
            best = root;
            best_f0 = f(s0);
        }
    }
    out.s = best;
    if (best >= 0 && best == entry) {
        out.at_entry = true;
        out.f_entry = best_f0;
    }
    return out;
}

// The trace's steps in t (m) and the height above which the path is clear
// of the terrain.  The horizontal fraction of the direction is taken at C
// (the path's horizontal speed changes little over a tile: the fine step
// is kept below posting / 8 with a 10 % margin).
struct Steps {
    ld post = 0;       // the posting (m)
    ld dt_fine = 0;    // step where the path may meet the terrain
    ld dt_coarse = 0;  // step where it certainly does not
    ld clear_h = 0;    // the tile's highest post + 1 m
};

inline Steps steps_of(const Surface &sf, const Los &L)
{
    Steps st;
    st.post = std::fabs(sf.pe);
    ld e[3], n[3], u[3];
    enu_axes(L.lat, L.lon, e, n, u);
    const ld horiz = std::sqrt(std::max<ld>(0, 1 - dot3(L.d, u) * dot3(L.d, u)));
    st.dt_fine = std::min(st.post / 8 / std::max(horiz, 1e-6L) / 1.1L, 4 * st.post);
    st.dt_coarse = std::max(st.dt_fine, (ld)64);
    st.clear_h = sf.zmax + 1;
    return st;
}

// res (the trace so far) completed as a hit at t on the path; cam is the
// sample at t = 0.
inline Result hit_at(Proj &pj, const Surface &sf, const Los &L, const Sample &cam, ld t, Result res)
{
    Sample hs = sample(pj, sf, L, t);
    res.status = HIT;
    res.e = hs.E;
    res.n = hs.N;
    res.h = hs.h;
    res.t = t;
    res.range = std::hypot(hs.E - cam.E, hs.N - cam.N);
    return res;
}

// The march along the path from the sample prev (the camera's; entered:
// the camera is over the tile) to the first segment that meets the
// terrain (hit_t, its first root on the mapped segment; wall: the path
// enters the tile's box there at or below the surface), or to a permanent
// miss (hit_t = -1).  The clearances along the path over the tile are
// appended to pts as (t, clearance), the samples taken added to *samples.
struct March {
    ld hit_t = -1;
    bool wall = false;
};

inline March march(Proj &pj, const Surface &sf, const Los &L, const Steps &st, Sample prev, bool entered,
                   std::vector<std::pair<ld, ld>> &pts, long *samples)
{
    const ld t_max = 300000;  // 300 km
    March out;
    int fine_left = 0;
    while (prev.t < t_max) {
        // permanent misses: outside the box and moving away; above every
        // post and rising (the height along the path is convex in t)
        Sample next;
        bool coarse_ok = false;
        if (fine_left <= 0) {
            next = sample(pj, sf, L, prev.t + st.dt_coarse);
            (*samples)++;
            const ld out_prev = sf.outside_by(prev.x, prev.y) * st.post;
            if (out_prev > 1.2L * st.dt_coarse + 2 * st.post ||
                (prev.h > st.clear_h && next.h > st.clear_h)) {
                coarse_ok = true;
            } else {
                fine_left = (int)std::ceil(st.dt_coarse / st.dt_fine) + 1;
            }
        }
        if (!coarse_ok) {
            next = sample(pj, sf, L, prev.t + st.dt_fine);
            (*samples)++;
            fine_left--;
            std::vector<std::pair<ld, ld>> sp;
            SegOut so = segment_root(sf, prev, next, sp);
            for (auto &q : sp) pts.push_back({prev.t + q.first * (next.t - prev.t), q.second});
            if (so.s >= 0) {
                out.hit_t = prev.t + so.s * (next.t - prev.t);
                // the path enters the tile's box at or below the surface:
                // that entry point (on the box's side) is the path's first
                // point at or below the terrain -- a hit on the wall
                out.wall = so.at_entry && !entered && so.f_entry <= 0;
                return out;
            }
            if (!sp.empty()) entered = true;
        }
        const bool out_now = !sf.inside(next.x, next.y);
        if (out_now && sf.outside_by(next.x, next.y) > sf.outside_by(prev.x, prev.y) && entered) break;
        if (out_now && !entered && sf.outside_by(next.x, next.y) > sf.outside_by(prev.x, prev.y)) break;
        if (next.h > st.clear_h && next.h > prev.h) break;
        prev = next;
    }
    return out;
}

// The smallest clearance at a local minimum before the hit at hit_t (a
// miss, hit_t < 0: anywhere) among the clearances pts (sorted here): the
// final descent into the hit is dropped, everything before it kept.
inline ld min_clear_before(std::vector<std::pair<ld, ld>> &pts, ld hit_t)
{
    ld min_clear = std::numeric_limits<ld>::infinity();
    std::sort(pts.begin(), pts.end());
    if (hit_t >= 0) {
        size_t k = pts.size();
        while (k > 0 && pts[k - 1].first > hit_t) --k;
        // walk back over the descent (clearance increasing backwards)
        while (k > 1 && pts[k - 2].second >= pts[k - 1].second) --k;
        for (size_t m = 0; m + 1 < k; ++m) min_clear = std::min(min_clear, pts[m].second);
    } else {
        for (auto &q : pts) min_clear = std::min(min_clear, q.second);
    }
    return min_clear;
}

// The root hit_t of the mapped segment refined on the true path by
// bisection to < 0.1 um, once it is bracketed (F(a) > 0 >= F(b)); hit_t
// itself when it cannot be.  The samples taken are added to *samples.
inline ld refine(Proj &pj, const Surface &sf, const Los &L, ld hit_t, ld dt_fine, long *samples)
{
    ld a = hit_t, b = hit_t, fa = 0, fb = 0;
    for (ld del = 1e-4L;; del *= 4) {
        a = std::max<ld>(0, hit_t - del);
        fa = clearance(pj, sf, L, a);
        (*samples)++;
        if (fa > 0 || a == 0) break;
    }
    for (ld del = 1e-4L; del < 4 * dt_fine; del *= 4) {
        b = hit_t + del;
        fb = clearance(pj, sf, L, b);
        (*samples)++;
        if (fb <= 0) break;
    }
    if (fa > 0 && fb <= 0) {
        while (b - a > 1e-7L) {
            ld m = 0.5L * (a + b);
            ld fm = clearance(pj, sf, L, m);
            (*samples)++;
            if (fm > 0)
                a = m;
            else
                b = m;
        }
        return b;
    }
    return hit_t;
}

}  // namespace detail

// The reference first hit of the line of sight L on the surface: the camera
// at or below the surface over the tile, else the march to the first
// segment that meets the terrain, the smallest clearance before it, the
// hit refined on the true path.
inline Result trace(Proj &pj, const Surface &sf, const Los &L)
{
    using detail::Sample;
    Result res;
    const detail::Steps st = detail::steps_of(sf, L);
    const Sample cam = detail::sample(pj, sf, L, 0);
    res.samples = 1;
    bool entered = false;
    if (sf.inside(cam.x, cam.y)) {
        entered = true;
        const ld f0 = cam.h - sf.height(cam.x, cam.y);
        if (f0 <= 0) {
            res.status = f0 < 0 ? BELOW : HIT;
            res.e = cam.E;
            res.n = cam.N;
            res.h = cam.h;
            res.t = 0;
            return res;
        }
    }
    std::vector<std::pair<ld, ld>> pts;  // (t, clearance) along the path over the tile
    const detail::March mr = detail::march(pj, sf, L, st, cam, entered, pts, &res.samples);
    if (mr.wall) {
        res.wall = true;
        return detail::hit_at(pj, sf, L, cam, mr.hit_t, res);
    }
    res.min_clear = detail::min_clear_before(pts, mr.hit_t);
    if (mr.hit_t < 0) {
        res.status = MISS;
        return res;
    }
    return detail::hit_at(pj, sf, L, cam, detail::refine(pj, sf, L, mr.hit_t, st.dt_fine, &res.samples), res);
}

// Where a map point (E, N, h) -- e.g. another tracer's hit -- lies relative
// to the path: its distance from the path (m), the path parameter of the
// nearest point, and the path's clearance over the terrain there (+inf
// outside the tile).  Tells a wrong line of sight (off the path) from a
// wrong intersection (on the path, clearance != 0).
struct OffPath {
    ld dist = 0, t = 0, clearance = 0;
};
inline OffPath off_path(Proj &pj, const Surface &sf, const Los &L, ld E, ld N, ld h)
{
    ld lat, lon, X[3];
    pj.utm_inverse(E, N, &lat, &lon);
    pj.ecef(lat, lon, h, X);
    OffPath o;
    ld t = 0;
    for (int k = 0; k < 3; ++k) t += (X[k] - L.C[k]) * L.d[k];
    for (int it = 0; it < 4; ++it) {  // the tangent at t: d - 2 kr t w
        ld P[3], T[3], r = 0, tt = 0;
        L.at(t, P);
        for (int k = 0; k < 3; ++k) T[k] = L.d[k] - 2 * L.kr * t * L.w[k];
        for (int k = 0; k < 3; ++k) {
            r += (X[k] - P[k]) * T[k];
            tt += T[k] * T[k];
        }
        t += r / tt;
    }
    ld P[3];
    L.at(t, P);
    ld dd[3] = {X[0] - P[0], X[1] - P[1], X[2] - P[2]};
    o.dist = std::sqrt(dot3(dd, dd));
    o.t = t;
    o.clearance = detail::clearance(pj, sf, L, t);
    return o;
}

// Convenience: package + pose + camera-frame unit ray + effects -> hit.
inline Result geolocate(Proj &pj, const Surface &sf, const ct_pose &pose, const ld ray_cam[3], const ct_effects *fx)
{
    return trace(pj, sf, los_from_pose(pj, pose, ray_cam, fx));
}
inline Result geolocate_wgs84(Proj &pj, const Surface &sf, ld lat_deg, ld lon_deg, ld h, const int32_t q_q30[4],
                              const ld ray_cam[3], const ct_effects *fx)
{
    ld q[4];
    quat_of_q30(q_q30, q);
    return trace(pj, sf, los_from_wgs84(pj, lat_deg, lon_deg, h, q, ray_cam, fx));
}

}  // namespace earth_ref
