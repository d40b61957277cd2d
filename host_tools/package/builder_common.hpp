// builder_common.hpp -- geometry shared by the PPT builders (host, C++17):
// exact sector (wedge) tests on integer vectors, distances from a coarse
// cell's footprint to a rectangle within a wedge, the max pyramid, the
// bilinear patches' directional slopes (the "near" term of the cone
// promise, docs/builders.md) and the angle-code choice.  Units: fine cells horizontally, height
// LSB vertically.  Internal to host_tools (builder_brute.cpp,
// builder_slices.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "cells.hpp"
#include "conetrace.h"
#include "terrain.hpp"

namespace ct_host {
namespace bld {

constexpr double K_NEAR = 1.0;          // cells          // cells
constexpr double INF = std::numeric_limits<double>::infinity();
constexpr size_t BELOW_POP_CAP = 4096;  // effort cap for negative cones
constexpr double GEOM_EPS = 1e-9;       // cells: slab expansion

struct Wedge {
    int n = 1;
    std::vector<int32_t> bx, by;  // n + 1 boundary vectors (|b| ~ 2^30), ct_sector_boundary's
    std::vector<double> ux, uy;   // the same, unit length
};

inline Wedge make_wedge(int n)
{
    Wedge w;
    w.n = n;
    for (int k = 0; k <= n; ++k) {
        int32_t x, y;
        if (ct_sector_boundary((uint32_t)n, (uint32_t)k, &x, &y) != CT_OK) {
            throw Error("bad sector count");
        }
        w.bx.push_back(x);
        w.by.push_back(y);
        double l = std::hypot((double)x, (double)y);
        w.ux.push_back(x / l);
        w.uy.push_back(y / l);
    }
    return w;
}

// The closed wedge W_s: the flight library's test (ct_in_wedge, the one the
// tracer uses), kept inline here because the builders call it in their hot
// loops (calling ct_in_wedge costs the brute builder 9%, the slice builder
// 3%); test_package proves it equal to ct_in_wedge on seeded vectors.
// Integer vectors with |v| <= 2^30.
inline bool in_closed(const Wedge &w, int s, int64_t x, int64_t y)
{
    if (w.n == 1) return true;
    int64_t c0 = (int64_t)w.bx[s] * y - (int64_t)w.by[s] * x;
    int64_t c1 = x * w.by[s + 1] - y * w.bx[s + 1];
    return c0 >= 0 && c1 >= 0;
}
// The open wedge (W_s without its boundary rays; ct_in_wedge has no such test).
inline bool in_open(const Wedge &w, int s, int64_t x, int64_t y)
{
    if (w.n == 1) return x != 0 || y != 0;
    int64_t c0 = (int64_t)w.bx[s] * y - (int64_t)w.by[s] * x;
    int64_t c1 = x * w.by[s + 1] - y * w.bx[s + 1];
    return c0 > 0 && c1 > 0;
}

// Rational p/q with q >= 0 (q == 0: +infinity).
struct Frac {
    int64_t p, q;
};
inline bool frac_lt(Frac a, Frac b)
{
    if (a.q == 0) return false;
    if (b.q == 0) return true;
    return a.p * b.q < b.p * a.q;  // |p| <= 2^18, q <= 2^30
}

// Does {l * b : l > 0} meet the open rectangle (x0,x1) x (y0,y1)?  Exact.
inline bool ray_meets_open_rect(int64_t bx, int64_t by, int64_t x0, int64_t x1, int64_t y0, int64_t y1)
{
    Frac lo{0, 1}, hi{1, 0};
    auto axis = [&](int64_t b, int64_t a0, int64_t a1) {
        if (b == 0) return a0 < 0 && 0 < a1;
        Frac l = b > 0 ? Frac{a0, b} : Frac{-a1, -b};
        Frac h = b > 0 ? Frac{a1, b} : Frac{-a0, -b};
        if (frac_lt(lo, l)) lo = l;
        if (frac_lt(h, hi)) hi = h;
        return true;
    };
    if (!axis(bx, x0, x1) || !axis(by, y0, y1)) return false;
    return frac_lt(lo, hi);
}

// R = B (-) F as integer rectangle [x0,x1] x [y0,y1] (cells).
struct Rect {
    int64_t x0, x1, y0, y1;
};

// Does R intersect W_s with positive area?  Exact.
inline bool overlaps(const Wedge &w, int s, const Rect &r)
{
    if (w.n == 1) return true;
    if (r.x0 < 0 && 0 < r.x1 && r.y0 < 0 && 0 < r.y1) return true;
    if (in_open(w, s, r.x0 + r.x1, r.y0 + r.y1)) return true;
    return ray_meets_open_rect(w.bx[s], w.by[s], r.x0, r.x1, r.y0, r.y1) ||
           ray_meets_open_rect(w.bx[s + 1], w.by[s + 1], r.x0, r.x1, r.y0, r.y1);
}

// Slab interval of the unit ray (ux, uy) through R expanded by GEOM_EPS.
inline bool slab(double ux, double uy, const Rect &r, double *tlo, double *thi)
{
    double lo = 0.0, hi = INF;
    auto axis = [&](double u, double a0, double a1) {
        a0 -= GEOM_EPS;
        a1 += GEOM_EPS;
        if (u == 0.0) return a0 <= 0.0 && 0.0 <= a1;
        double t0 = a0 / u, t1 = a1 / u;
        if (t0 > t1) std::swap(t0, t1);
        lo = std::max(lo, t0);
        hi = std::min(hi, t1);
        return true;
    };
    if (!axis(ux, (double)r.x0, (double)r.x1) || !axis(uy, (double)r.y0, (double)r.y1)) return false;
    *tlo = lo;
    *thi = hi;
    return lo <= hi;
}

// min |v| over v in R intersected with closed W_s (a lower bound), INF if empty.
inline double dist_min(const Wedge &w, int s, const Rect &r)
{
    int64_t cx = std::clamp<int64_t>(0, r.x0, r.x1), cy = std::clamp<int64_t>(0, r.y0, r.y1);
    if (in_closed(w, s, cx, cy)) return std::hypot((double)cx, (double)cy) * (1.0 - 1e-12);
    double best = INF;
    for (int k = s; k <= s + 1; ++k) {
        double lo, hi;
        if (slab(w.ux[k], w.uy[k], r, &lo, &hi)) best = std::min(best, lo);
    }
    return best * (1.0 - 1e-12);
}

// max |v| over v in R intersected with closed W_s (an upper bound).
inline double dist_max(const Wedge &w, int s, const Rect &r)
{
    double best = 0.0;
    const int64_t xs[2] = {r.x0, r.x1}, ys[2] = {r.y0, r.y1};
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            if (in_closed(w, s, xs[a], ys[b])) best = std::max(best, std::hypot((double)xs[a], (double)ys[b]));
    if (w.n > 1) {
        for (int k = s; k <= s + 1; ++k) {
            double lo, hi;
            if (slab(w.ux[k], w.uy[k], r, &lo, &hi)) best = std::max(best, hi);
        }
    }
    return best * (1.0 + 1e-12) + 1e-12;
}

// Max pyramid of fine-cell maxima: level 0 = fine cells.
// Max pyramid: level 0 is the fine-cell maxima themselves (not copied: the
// pyramid must not outlive `fm`), levels 1.. are 2x2 maxima.
struct Pyramid {
    const std::vector<uint16_t> *base = nullptr;
    std::vector<std::vector<uint16_t>> lv;  // lv[0] empty
    std::vector<int> w, h;
    uint16_t at(int l, int i, int j) const { return (l == 0 ? *base : lv[l])[(size_t)j * w[l] + i]; }
};

inline Pyramid make_pyramid(const std::vector<uint16_t> &fm, int cx, int cy)
{
    Pyramid p;
    p.base = &fm;
    p.lv.emplace_back();
    p.w.push_back(cx);
    p.h.push_back(cy);
    while (p.w.back() > 1 || p.h.back() > 1) {
        int pw = p.w.back(), ph = p.h.back(), nw = (pw + 1) / 2, nh = (ph + 1) / 2;
        const auto &pr = p.lv.size() == 1 ? fm : p.lv.back();
        std::vector<uint16_t> nx = max_pyramid_step(pw, ph, [&](int i, int j) { return pr[(size_t)j * pw + i]; });
        p.lv.push_back(std::move(nx));
        p.w.push_back(nw);
        p.h.push_back(nh);
    }
    return p;
}

struct Ctx {
    const Terrain *t;
    int cx, cy, r, n;
    Wedge wedge;
    std::vector<uint16_t> fm;          // fine-cell tallest corner (brute-force builder only)
    Pyramid pyr;                       // its max pyramid (brute-force builder only)
    int64_t cot_q16[256];
    uint8_t cot_ok[256];
    // code_for's search: the usable codes 1..255 by cot, descending, with the
    // largest code among each prefix (set by prepare_codes)
    std::vector<int64_t> by_cot;
    std::vector<uint8_t> prefix_max_code;
};

// Fill c.by_cot / c.prefix_max_code from c.cot_q16 / c.cot_ok.
inline void prepare_codes(Ctx &c)
{
    std::vector<std::pair<int64_t, int>> v;
    for (int k = 1; k < 256; ++k)
        if (c.cot_ok[k]) v.push_back({c.cot_q16[k], k});
    std::sort(v.begin(), v.end(), [](const std::pair<int64_t, int> &x, const std::pair<int64_t, int> &y) {
        return x.first > y.first;
    });
    c.by_cot.clear();
    c.prefix_max_code.clear();
    int m = 0;
    for (const auto &e : v) {
        m = std::max(m, e.second);
        c.by_cot.push_back(e.first);
        c.prefix_max_code.push_back((uint8_t)m);
    }
}

// The bilinear patch of cell (i, j): its gradient at the four corners
// (gradient extremes of a bilinear patch are at the corners).  gx, gy:
// integers below 2^18, exact; g1 = |gx| + |gy| >= |g| widens the
// tolerances below (conservative: "inside" takes |g|).
struct PatchGrad {
    double gx[4], gy[4], g1[4], norm[4];
};
inline PatchGrad patch_grad(const Terrain &t, int i, int j)
{
    double h00 = t.at(i, j), h10 = t.at(i + 1, j), h01 = t.at(i, j + 1), h11 = t.at(i + 1, j + 1);
    double a = h10 - h00, b = h01 - h00, cc = h11 - h10 - h01 + h00;
    PatchGrad g;
    for (int v = 0; v < 2; ++v)
        for (int u = 0; u < 2; ++u) {
            const int k = 2 * v + u;
            g.gx[k] = a + cc * v;
            g.gy[k] = b + cc * u;
            g.g1[k] = std::fabs(g.gx[k]) + std::fabs(g.gy[k]);
            g.norm[k] = std::sqrt(g.gx[k] * g.gx[k] + g.gy[k] * g.gy[k]);
        }
    return g;
}

// Max over u in W_s of the directional derivative of a patch (LSB per cell).
inline double max_slope(const Ctx &c, int s, const PatchGrad &g)
{
    double best = -INF;
    for (int k = 0; k < 4; ++k) {
        const double gx = g.gx[k], gy = g.gy[k], g1 = g.g1[k];
        double m;
        bool inside = c.wedge.n == 1;
        if (!inside) {
            double c0 = c.wedge.ux[s] * gy - c.wedge.uy[s] * gx;
            double c1 = gx * c.wedge.uy[s + 1] - gy * c.wedge.ux[s + 1];
            inside = c0 >= -1e-12 * g1 && c1 >= -1e-12 * g1;
        }
        if (inside) {
            m = g.norm[k];
        } else {
            m = std::max(gx * c.wedge.ux[s] + gy * c.wedge.uy[s], gx * c.wedge.ux[s + 1] + gy * c.wedge.uy[s + 1]);
        }
        best = std::max(best, m + 1e-9 * (g1 + 1.0));
    }
    return best;
}
inline double max_slope(const Ctx &c, int s, int i, int j) { return max_slope(c, s, patch_grad(*c.t, i, j)); }


inline Rect block_rect(const Ctx &c, int l, int bi, int bj, int fx0, int fx1, int fy0, int fy1)
{
    int64_t bx0 = (int64_t)bi << l, by0 = (int64_t)bj << l;
    int64_t bx1 = std::min<int64_t>((int64_t)(bi + 1) << l, c.cx), by1 = std::min<int64_t>((int64_t)(bj + 1) << l, c.cy);
    return Rect{bx0 - fx1, bx1 - fx0, by0 - fy1, by1 - fy0};
}

// Far term of a sub-square at depth k >= 1: fine cell (i >> k, j >> k),
// the square [i, i+1] x [j, j+1] / 2^k in fine-cell units.  The bilinear
// patch is linear along each axis, so its maximum over the square is the
// largest of the patch at the square's four corners (dyadic: exact in
// double).  Distances in units of 2^-k cells, exact wedge tests.
constexpr int SUB_DEPTH = 3;  // refine far cells down to 1/8 cell
inline double sub_term(const Ctx &c, int s, double a, int k, int64_t i, int64_t j, int fx0, int fx1, int fy0, int fy1)
{
    const Terrain &t = *c.t;
    int ci = (int)(i >> k), cj = (int)(j >> k);
    double h00 = t.at(ci, cj), h10 = t.at(ci + 1, cj), h01 = t.at(ci, cj + 1), h11 = t.at(ci + 1, cj + 1);
    double sc = 1.0 / (double)(1 << k), hm = -INF;
    double u0 = (double)(i - ((int64_t)ci << k)) * sc, v0 = (double)(j - ((int64_t)cj << k)) * sc;
    for (int dv = 0; dv < 2; ++dv)
        for (int du = 0; du < 2; ++du) {
            double u = u0 + du * sc, v = v0 + dv * sc;
            hm = std::max(hm, h00 * (1 - u) * (1 - v) + h10 * u * (1 - v) + h01 * (1 - u) * v + h11 * u * v);
        }
    if (hm <= a) return -INF;
    Rect rr{i - ((int64_t)fx1 << k), i + 1 - ((int64_t)fx0 << k), j - ((int64_t)fy1 << k), j + 1 - ((int64_t)fy0 << k)};
    if (!overlaps(c.wedge, s, rr)) return -INF;
    double d = dist_min(c.wedge, s, rr) * sc;
    if (d == INF) return -INF;
    return (hm - a) / std::max(K_NEAR, d);
}

// The near term: for terrain points q with rho_s(q) <= K_NEAR, S(q) - a <=
// rho * (max directional slope, over W_s, of the patches met on the segment
// from the nearest point p* of F to q).  Those patches lie in fine cells
// within K_NEAR of F in W_s.  F's own cells do not count: a segment from the
// nearest point p* of F to a point q outside F never runs through F's
// interior (a point of F nearer to q would lie on it).  -INF if none.
inline double near_term(const Ctx &c, int s, int fx0, int fx1, int fy0, int fy1)
{
    double best = -INF;
    for (int j = std::max(0, fy0 - 2); j < std::min(c.cy, fy1 + 2); ++j)
        for (int i = std::max(0, fx0 - 2); i < std::min(c.cx, fx1 + 2); ++i) {
            if (i >= fx0 && i < fx1 && j >= fy0 && j < fy1) continue;
            Rect rr = block_rect(c, 0, i, j, fx0, fx1, fy0, fy1);
            if (!overlaps(c.wedge, s, rr)) continue;
            if (dist_min(c.wedge, s, rr) > K_NEAR) continue;
            best = std::max(best, max_slope(c, s, i, j));
        }
    return best;
}

// Widest code whose tracer cot covers `need` (LSB per cell).
inline uint8_t code_for(const Ctx &c, double need)
{
    if (need == -INF) return 255;
    double q = need * 65536.0;
    q = q + std::fabs(q) * 1e-9 + 2.0;  // margin for double rounding
    if (q > 9.0e18) return 0;
    int64_t need_q = (int64_t)std::ceil(q);
    // largest k with cot_ok[k] && cot_q16[k] >= need_q; 0 if none: the
    // entries with cot >= need_q are a prefix of by_cot
    size_t n = (size_t)(std::upper_bound(c.by_cot.begin(), c.by_cot.end(), need_q, std::greater<int64_t>()) -
                        c.by_cot.begin());
    return n == 0 ? (uint8_t)0 : c.prefix_max_code[n - 1];
}

}  // namespace bld
}  // namespace ct_host
