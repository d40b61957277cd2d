// test_promise.cpp -- the cone promise (docs/builders.md) checked directly.
//
// For every coarse cell F, sector s and fine cell Q of small DEMs, and every
// point q of Q reachable from F in the closed wedge W_s, the package as the
// tracer reads it (apex a from the package, cot = cot_q16[code] / 2^16 from
// the library's table) must satisfy
//        S(q) <= a + rho_s(q) * cot,   rho_s(q) = min |q - p|, p in F, q - p in W_s.
// Independent of the builder: distances come from Sutherland-Hodgman
// clipping in long double (the builder uses slab tests and closest points),
// and every point counts, including those on cell and wedge boundaries.
// Q is subdivided adaptively: a sub-rectangle R is safe when
// max_R S - a - cot * rho_lo(R) <= 0 (bilinear max at R's corners); a
// violation is a sample point with S - a - cot * rho > TOL.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
#include "harness.h"
#include "terrain.hpp"
#include "tileset.hpp"

namespace {

typedef long double ld;
constexpr ld TOL = 1e-7L;  // LSB
constexpr int MAX_DEPTH = 12;

struct P2 {
    ld x, y;
};
typedef std::vector<P2> Poly;

// keep the side n.x*x + n.y*y >= 0 (closed half-plane through the origin)
Poly clip(const Poly &in, ld nx, ld ny)
{
    Poly out;
    size_t n = in.size();
    for (size_t k = 0; k < n; ++k) {
        P2 a = in[k], b = in[(k + 1) % n];
        ld da = nx * a.x + ny * a.y, db = nx * b.x + ny * b.y;
        if (da >= 0) out.push_back(a);
        if ((da >= 0) != (db >= 0)) {
            ld t = da / (da - db);
            out.push_back(P2{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)});
        }
    }
    return out;
}

struct Wedge {
    int n;
    std::vector<ld> bx, by;
};

// keep the side of the directed line o -> o + e that is on its left
Poly clip_line(const Poly &in, P2 o, P2 e)
{
    Poly out;
    size_t n = in.size();
    auto side = [&](P2 v) { return e.x * (v.y - o.y) - e.y * (v.x - o.x); };
    for (size_t k = 0; k < n; ++k) {
        P2 a = in[k], b = in[(k + 1) % n];
        ld da = side(a), db = side(b);
        if (da >= 0) out.push_back(a);
        if ((da >= 0) != (db >= 0)) {
            ld t = da / (da - db);
            out.push_back(P2{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)});
        }
    }
    return out;
}

// convex hull (counter-clockwise), Andrew's monotone chain
Poly hull(std::vector<P2> pts)
{
    std::sort(pts.begin(), pts.end(), [](P2 a, P2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    Poly h(2 * pts.size());
    size_t k = 0;
    auto cross = [](P2 o, P2 a, P2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); };
    for (size_t i = 0; i < pts.size(); ++i) {
        while (k >= 2 && cross(h[k - 2], h[k - 1], pts[i]) <= 0) k--;
        h[k++] = pts[i];
    }
    for (size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross(h[k - 2], h[k - 1], pts[i]) <= 0) k--;
        h[k++] = pts[i];
    }
    h.resize(k > 1 ? k - 1 : k);
    return h;
}

// (rect x0..x1, y0..y1) intersected with the closed wedge (as a polygon)
Poly rect_in_wedge(const Wedge &w, int s, ld x0, ld x1, ld y0, ld y1)
{
    Poly p = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    if (w.n == 1) return p;
    // inside: cross(b_s, v) >= 0 and cross(v, b_{s+1}) >= 0
    p = clip(p, -w.by[s], w.bx[s]);
    if (p.empty()) return p;
    return clip(p, w.by[s + 1], -w.bx[s + 1]);
}

ld seg_dist(P2 a, P2 b)  // distance from the origin to segment ab
{
    ld dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy;
    ld t = l2 > 0 ? -(a.x * dx + a.y * dy) / l2 : 0;
    t = std::max<ld>(0, std::min<ld>(1, t));
    return std::hypot(a.x + t * dx, a.y + t * dy);
}

// min |v| over a convex polygon (0 if it holds the origin)
ld poly_min(const Poly &p)
{
    if (p.empty()) return INFINITY;
    if (p.size() == 1) return std::hypot(p[0].x, p[0].y);
    // the origin is inside a polygon of positive area when every edge has
    // it on the same side; degenerate polygons (segments, points) only have
    // edge distances
    bool pos = true, neg = true;
    ld m = INFINITY, area = 0;
    for (size_t k = 0; k < p.size(); ++k) {
        P2 a = p[k], b = p[(k + 1) % p.size()];
        ld c = a.x * b.y - a.y * b.x;
        area += c;
        ld ex = b.x - a.x, ey = b.y - a.y;
        ld side = ex * (-a.y) - ey * (-a.x);  // origin relative to edge a->b
        pos = pos && side >= 0;
        neg = neg && side <= 0;
        m = std::min(m, seg_dist(a, b));
    }
    if (area != 0 && (pos || neg)) return 0;
    return m;
}

ld poly_max(const Poly &p)
{
    ld m = 0;
    for (auto &v : p) m = std::max(m, std::hypot(v.x, v.y));
    return m;
}

struct Checker {
    const ct_host::Terrain *t;
    const ct_package *p;
    Wedge w;
    long violations = 0, undecided = 0, regions = 0, cones = 0, degenerate = 0;
    bool quiet = false;  // no VIOLATION lines (the checker's own test)
    ld worst = -INFINITY;

    ld S(ld x, ld y) const
    {
        int i = std::min(t->width - 2, std::max(0, (int)std::floor(x)));
        int j = std::min(t->height - 2, std::max(0, (int)std::floor(y)));
        ld u = x - i, v = y - j;
        ld h00 = t->at(i, j), h10 = t->at(i + 1, j), h01 = t->at(i, j + 1), h11 = t->at(i + 1, j + 1);
        return h00 + (h10 - h00) * u + (h01 - h00) * v + (h11 - h10 - h01 + h00) * u * v;
    }

    // Max over unit u in the closed wedge W_s of grad S . u, over all points
    // of the box [x0,x1] x [y0,y1] (clipped to the tile).  grad S is affine
    // on each cell, so its extremes over a sub-box are at the sub-box corners.
    ld max_slope(int s, ld x0, ld x1, ld y0, ld y1) const
    {
        int cx = t->width - 1, cy = t->height - 1;
        x0 = std::max<ld>(0, x0);
        y0 = std::max<ld>(0, y0);
        x1 = std::min<ld>(cx, x1);
        y1 = std::min<ld>(cy, y1);
        ld best = -INFINITY;
        for (int j = std::max(0, (int)std::floor(y0)); j < cy && j <= (int)std::floor(y1); ++j)
            for (int i = std::max(0, (int)std::floor(x0)); i < cx && i <= (int)std::floor(x1); ++i) {
                ld h00 = t->at(i, j), h10 = t->at(i + 1, j), h01 = t->at(i, j + 1), h11 = t->at(i + 1, j + 1);
                ld a = h10 - h00, b = h01 - h00, c = h11 - h10 - h01 + h00;
                ld us[2] = {std::max<ld>(0, x0 - i), std::min<ld>(1, x1 - i)};
                ld vs[2] = {std::max<ld>(0, y0 - j), std::min<ld>(1, y1 - j)};
                for (ld u : us)
                    for (ld v : vs) {
                        ld gx = a + c * v, gy = b + c * u, g = std::hypot(gx, gy), m;
                        bool in = w.n == 1 || ((w.bx[s] * gy - w.by[s] * gx) >= 0 && (gx * w.by[s + 1] - gy * w.bx[s + 1]) >= 0);
                        if (in) {
                            m = g;
                        } else {
                            ld l0 = std::hypot(w.bx[s], w.by[s]), l1 = std::hypot(w.bx[s + 1], w.by[s + 1]);
                            m = std::max((gx * w.bx[s] + gy * w.by[s]) / l0, (gx * w.bx[s + 1] + gy * w.by[s + 1]) / l1);
                        }
                        best = std::max(best, m);
                    }
            }
        return best;
    }

    // rho at a point q (INF when q is not reachable from F in W_s)
    ld rho_at(int s, ld qx, ld qy, ld fx0, ld fx1, ld fy0, ld fy1) const
    {
        return poly_min(rect_in_wedge(w, s, qx - fx1, qx - fx0, qy - fy1, qy - fy0));
    }

    // The reachable region F (+) W_s, cut to F (+) (W_s within 1e4 cells):
    // the hull of F's corners and the corners moved by the wedge's far points.
    Poly shadow_hull(int s, ld fx0, ld fx1, ld fy0, ld fy1) const
    {
        const ld L = 1e4L;
        std::vector<P2> far = {{0, 0}};
        if (w.n == 1) {
            far = {{L, L}, {-L, L}, {-L, -L}, {L, -L}};
        } else {
            ld l0 = std::hypot(w.bx[s], w.by[s]), l1 = std::hypot(w.bx[s + 1], w.by[s + 1]);
            P2 u0{w.bx[s] / l0, w.by[s] / l0}, u1{w.bx[s + 1] / l1, w.by[s + 1] / l1};
            far.push_back(P2{L * u0.x, L * u0.y});
            far.push_back(P2{L * u1.x, L * u1.y});
            P2 m{-u0.y, u0.x};  // the middle direction (needed for 180 degrees)
            if (u0.x * u1.y - u0.y * u1.x > 1e-12L) m = P2{u0.x + u1.x, u0.y + u1.y};
            ld ml = std::hypot(m.x, m.y);
            far.push_back(P2{L * m.x / ml, L * m.y / ml});
        }
        std::vector<P2> pts;
        const ld fxs[2] = {fx0, fx1}, fys[2] = {fy0, fy1};
        for (ld fx : fxs)
            for (ld fy : fys)
                for (P2 f : far) pts.push_back(P2{fx + f.x, fy + f.y});
        return hull(pts);
    }

    static Poly clip_to(Poly r, const Poly &h)
    {
        for (size_t k = 0; k < h.size() && !r.empty(); ++k) {
            P2 a = h[k], b = h[(k + 1) % h.size()];
            r = clip_line(r, a, P2{b.x - a.x, b.y - a.y});
        }
        return r;
    }

    static ld area(const Poly &p)
    {
        ld A = 0;
        for (size_t k = 0; k < p.size(); ++k) A += p[k].x * p[(k + 1) % p.size()].y - p[k].y * p[(k + 1) % p.size()].x;
        return std::fabs(A) / 2;
    }

    // max of the bilinear patch of cell (i, j) over [x0, x1] x [y0, y1]
    // inside it: at a corner (the patch is linear along each axis)
    ld s_max_rect(int i, int j, ld x0, ld x1, ld y0, ld y1) const
    {
        ld h00 = t->at(i, j), h10 = t->at(i + 1, j), h01 = t->at(i, j + 1), h11 = t->at(i + 1, j + 1);
        ld a = h10 - h00, b = h01 - h00, c = h11 - h10 - h01 + h00;
        ld m = -INFINITY;
        for (ld x : {x0, x1})
            for (ld y : {y0, y1}) {
                ld u = x - i, v = y - j;
                m = std::max(m, h00 + a * u + b * v + c * u * v);
            }
        return m;
    }

    // max of the bilinear patch of cell (i, j) over a convex polygon inside
    // it: on the boundary (no interior maximum), at a vertex or where an
    // edge's quadratic peaks
    ld s_max_poly(const Poly &p, int i, int j) const
    {
        ld h00 = t->at(i, j), h10 = t->at(i + 1, j), h01 = t->at(i, j + 1), h11 = t->at(i + 1, j + 1);
        ld a = h10 - h00, b = h01 - h00, c = h11 - h10 - h01 + h00;
        auto S = [&](ld u, ld v) { return h00 + a * u + b * v + c * u * v; };
        ld m = -INFINITY;
        for (size_t k = 0; k < p.size(); ++k) {
            P2 A = p[k], B = p[(k + 1) % p.size()];
            ld ua = A.x - i, va = A.y - j, du = B.x - A.x, dv = B.y - A.y;
            m = std::max(m, S(ua, va));
            ld q2 = c * du * dv, q1 = a * du + b * dv + c * (ua * dv + va * du);
            if (q2 < 0) {
                ld l = -q1 / (2 * q2);
                if (l > 0 && l < 1) m = std::max(m, S(ua + l * du, va + l * dv));
            }
        }
        return m;
    }

    // Max over unit u in the closed wedge W_s of grad S . u, over the cells
    // that meet (box intersected with the reachable region) with positive
    // area (a segment p*-q running along an edge has the same derivative on
    // both sides).  grad S is affine per cell: extremes at sub-box corners.
    // Largest slope in the wedge's directions over the cells meeting the
    // window and the reach, except F's own cells [fx0,fx1) x [fy0,fy1).
    ld max_slope(int s, const Poly &reach, ld x0, ld x1, ld y0, ld y1, int fx0, int fx1, int fy0, int fy1) const
    {
        int cx = t->width - 1, cy = t->height - 1;
        x0 = std::max<ld>(0, x0);
        y0 = std::max<ld>(0, y0);
        x1 = std::min<ld>(cx, x1);
        y1 = std::min<ld>(cy, y1);
        ld best = -INFINITY;
        for (int j = std::max(0, (int)std::floor(y0)); j < cy && j <= (int)std::floor(y1); ++j)
            for (int i = std::max(0, (int)std::floor(x0)); i < cx && i <= (int)std::floor(x1); ++i) {
                if (i >= fx0 && i < fx1 && j >= fy0 && j < fy1) continue;
                ld bx0 = std::max<ld>(x0, i), bx1 = std::min<ld>(x1, i + 1), by0 = std::max<ld>(y0, j),
                   by1 = std::min<ld>(y1, j + 1);
                if (bx1 <= bx0 || by1 <= by0) continue;
                Poly cell = {{bx0, by0}, {bx1, by0}, {bx1, by1}, {bx0, by1}};
                if (area(clip_to(cell, reach)) <= 0) continue;
                ld h00 = t->at(i, j), h10 = t->at(i + 1, j), h01 = t->at(i, j + 1), h11 = t->at(i + 1, j + 1);
                ld a = h10 - h00, b = h01 - h00, c = h11 - h10 - h01 + h00;
                ld us[2] = {bx0 - i, bx1 - i}, vs[2] = {by0 - j, by1 - j};
                for (ld u : us)
                    for (ld v : vs) {
                        ld gx = a + c * v, gy = b + c * u, g = std::hypot(gx, gy), m;
                        bool in = w.n == 1 || ((w.bx[s] * gy - w.by[s] * gx) >= 0 && (gx * w.by[s + 1] - gy * w.bx[s + 1]) >= 0);
                        if (in) {
                            m = g;
                        } else {
                            ld l0 = std::hypot(w.bx[s], w.by[s]), l1 = std::hypot(w.bx[s + 1], w.by[s + 1]);
                            m = std::max((gx * w.bx[s] + gy * w.by[s]) / l0, (gx * w.bx[s + 1] + gy * w.by[s + 1]) / l1);
                        }
                        best = std::max(best, m);
                    }
            }
        return best;
    }

    // Region R = [x0,x1] x [y0,y1] inside fine cell (i, j); F = [fx0,fx1] x
    // [fy0,fy1]; reach = F (+) W_s.
    void check(int s, ld a, ld cot, ld fx0, ld fx1, ld fy0, ld fy1, const Poly &reach, int i, int j, ld x0, ld x1,
               ld y0, ld y1, int depth)
    {
        Poly d = rect_in_wedge(w, s, x0 - fx1, x1 - fx0, y0 - fy1, y1 - fy0);
        if (d.empty()) return;
        ld rho = cot >= 0 ? poly_min(d) : poly_max(d);
        // first the whole of R: the bilinear patch's max over R (at its
        // corners) bounds its max over R's reachable part, so R is safe
        // when even that is under the cone -- before R is cut to the reach
        if (s_max_rect(i, j, x0, x1, y0, y1) - a - cot * rho <= 0) return;
        Poly pr = clip_to(Poly{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}, reach);
        if (pr.empty()) return;
        regions++;
        ld smax = s_max_poly(pr, i, j);
        ld ub = smax - a - cot * rho;
        if (ub <= 0) return;
        // Mean value bound: with p* in F the nearest wedge point of q,
        // S(q) - a <= S(q) - S(p*) <= rho(q) * G, G the largest slope in the
        // wedge's directions where the segment p*-q runs: within
        // max_q rho(q) of R (rho is convex, so its max is at a vertex of pr),
        // and outside F: p* is the point of F nearest to q in the wedge, so
        // no other point of the segment lies in F (it would be nearer).
        ld rh = 0;
        bool rh_ok = true;
        for (P2 v : pr) {
            ld rv = rho_at(s, v.x, v.y, fx0 - 1e-12L, fx1 + 1e-12L, fy0 - 1e-12L, fy1 + 1e-12L);
            if (rv == INFINITY) rh_ok = false;
            rh = std::max(rh, rv);
        }
        if (rh_ok) {
            rh = rh * (1 + 1e-12L) + 1e-12L;
            if (max_slope(s, reach, x0 - rh, x1 + rh, y0 - rh, y1 + rh, (int)fx0, (int)fx1, (int)fy0, (int)fy1) <= cot)
                return;
        }
        // samples: the reachable polygon's vertices and R's centre
        std::vector<P2> samples(pr.begin(), pr.end());
        samples.push_back(P2{(x0 + x1) / 2, (y0 + y1) / 2});
        for (P2 q : samples) {
            ld rq = rho_at(s, q.x, q.y, fx0, fx1, fy0, fy1);
            if (rq == INFINITY) continue;
            ld v = S(q.x, q.y) - a - cot * rq;
            worst = std::max(worst, v);
            if (v > TOL) {
                if (violations++ < 5 && !quiet)
                    std::printf("    VIOLATION sector %d F=[%Lg,%Lg]x[%Lg,%Lg] q=(%.9Lf, %.9Lf): S=%.6Lf a=%.0Lf "
                                "cot=%.6Lf rho=%.9Lf excess %.3Lg LSB\n",
                                s, fx0, fx1, fy0, fy1, q.x, q.y, S(q.x, q.y), a, cot, rq, v);
                return;
            }
        }
        if (depth >= MAX_DEPTH) {
            if (ub > TOL) {
                if (undecided++ < 3 && getenv("CT_PROMISE_VERBOSE"))
                    std::printf("    undecided sector %d F=[%Lg,%Lg]x[%Lg,%Lg] R=[%.6Lf,%.6Lf]x[%.6Lf,%.6Lf] ub=%.3Lg "
                                "a=%.0Lf cot=%.3Lf rho_lo=%.6Lf smax=%.3Lf\n",
                                s, fx0, fx1, fy0, fy1, x0, x1, y0, y1, ub, a, cot, rho, smax);
            }
            return;
        }
        ld mx = (x0 + x1) / 2, my = (y0 + y1) / 2;
        check(s, a, cot, fx0, fx1, fy0, fy1, reach, i, j, x0, mx, y0, my, depth + 1);
        check(s, a, cot, fx0, fx1, fy0, fy1, reach, i, j, mx, x1, y0, my, depth + 1);
        check(s, a, cot, fx0, fx1, fy0, fy1, reach, i, j, x0, mx, my, y1, depth + 1);
        check(s, a, cot, fx0, fx1, fy0, fy1, reach, i, j, mx, x1, my, y1, depth + 1);
    }
};

// Every cone of package p (built from t with n sectors at reduction r)
// against the terrain; wider: each cone's cot taken down by that fraction
// of its size (0: the package's cones; > 0: wider cones than built, which
// must fail).
Checker check_promise(const ct_host::Terrain &t, const ct_package &p, int n, int r, ld wider = 0)
{
    Checker c;
    c.quiet = wider > 0;
    c.t = &t;
    c.p = &p;
    c.w.n = n;
    for (int k = 0; k <= n; ++k) {
        c.w.bx.push_back(p.bound_x[k]);
        c.w.by.push_back(p.bound_y[k]);
    }
    int cx = t.width - 1, cy = t.height - 1;
    for (uint32_t cj = 0; cj < p.coarse_y; ++cj)
        for (uint32_t ci = 0; ci < p.coarse_x; ++ci) {
            size_t k = (size_t)cj * p.coarse_x + ci;
            ld a = (ld)(p.apex[2 * k] | (p.apex[2 * k + 1] << 8));
            ld fx0 = ci * r, fy0 = cj * r, fx1 = std::min<int>((ci + 1) * r, cx), fy1 = std::min<int>((cj + 1) * r, cy);
            for (uint32_t s = 0; s < p.planes; ++s) {
                uint8_t code = p.angles[(size_t)s * p.coarse_x * p.coarse_y + k];
                c.cones++;
                if (!p.cot_ok[code]) {
                    c.degenerate++;
                    continue;  // no promise for a degenerate cone
                }
                ld cot = (ld)p.cot_q16[code] / 65536.0L;
                cot -= wider * std::fabs(cot);
                // the omni plane (s == N) must hold for every sector's wedge
                int s0 = (int)s, s1 = (int)s;
                if (s == (uint32_t)n) {
                    s0 = 0;
                    s1 = n - 1;
                }
                for (int ss = s0; ss <= s1; ++ss) {
                    Poly reach = c.shadow_hull(ss, fx0, fx1, fy0, fy1);
                    for (int j = 0; j < cy; ++j)
                        for (int i = 0; i < cx; ++i)
                            c.check(ss, a, cot, fx0, fx1, fy0, fy1, reach, i, j, i, i + 1, j, j + 1, 0);
                }
            }
        }
    return c;
}

// builder: the default (the slice builder), or the one given; window: the
// slice builder's near window Rw (small windows send most terrain through
// the slice DTs).  *stats_out: the build's stats.
void check_package(const char *name, const ct_host::Terrain &t, int n, int r, int slices = 0,
                   ct_host::PptBuilder builder = ct_host::BuildOptions().builder, int window = ct_host::BuildOptions().window,
                   ct_host::BuildStats *stats_out = nullptr, const std::vector<double> *levels_m = nullptr)
{
    ct_host::BuildOptions o;
    o.sectors = n;
    o.reduce = r;
    o.slices = slices;
    o.builder = builder;
    o.window = window;
    if (levels_m) o.levels_m = *levels_m;
    ct_host::BuildStats bst;
    std::vector<uint8_t> b = ct_host::build_package(t, o, &bst);
    if (stats_out) *stats_out = bst;
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, b.data(), b.size()));
    if (ct_harness_g.current_failed) return;
    const Checker c = check_promise(t, p, n, r);
    std::printf("  %-5s %-16s N=%-2d r=%d K=%-2d W=%-2d: %ld cones (%ld degenerate), %ld regions; worst excess %.3Lg LSB; "
                "violations %ld, undecided %ld\n",
                builder == ct_host::PptBuilder::Brute ? "brute" : "slice", name, n, r, slices, window, c.cones, c.degenerate, c.regions, c.worst, c.violations, c.undecided);
    TEST_ASSERT_MSG(c.violations == 0, "%s N=%d r=%d: %ld promise violations", name, n, r, c.violations);
    TEST_ASSERT_MSG(c.undecided == 0, "%s N=%d r=%d: %ld undecided regions", name, n, r, c.undecided);
}

ct_host::Terrain small(int kind, int w, int h)
{
    ct_rng r;
    ct_rng_seed(&r, 100 + kind);
    std::vector<uint16_t> z((size_t)w * h);
    switch (kind) {
    case 0:  // noise
        for (auto &q : z) q = (uint16_t)ct_rng_range(&r, 1000, 1400);
        return dem_cases::make_terrain(w, h, z, 0.25);
    case 1:  // spikes and a wall on a slope
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i) z[(size_t)j * w + i] = (uint16_t)(2000 + 40 * i + 15 * j);
        for (int k = 0; k < 5; ++k) z[(size_t)ct_rng_range(&r, 0, h - 1) * w + ct_rng_range(&r, 0, w - 1)] = 9000;
        for (int j = 2; j < h - 2; ++j) z[(size_t)j * w + w / 2] = 7000;
        return dem_cases::make_terrain(w, h, z, 0.1);
    case 2:  // smooth
        return dem_cases::make_terrain(w, h, dem_cases::smooth(w, h, 9, 0, 20000), 0.5);
    default:  // extremes
        for (auto &q : z) q = (ct_rng_u64(&r) & 1) ? 65535 : 0;
        return dem_cases::make_terrain(w, h, z, 0.01);
    }
}

using B = ct_host::PptBuilder;

void test_promise_sectors()
{
    ct_host::Terrain t0 = small(0, 12, 10), t1 = small(1, 13, 11), t2 = small(2, 12, 12), t3 = small(3, 9, 8);
    const int ns[] = {1, 2, 3, 4, 8, 24};
    for (B b : {B::Brute, B::Slices})
        for (int n : ns) {
            check_package("noise", t0, n, 1, 0, b);
            check_package("spikes_wall", t1, n, 2, 0, b);
            check_package("smooth", t2, n, 3, 0, b);
            check_package("extremes", t3, n, 1, 0, b);
            if (ct_harness_g.current_failed) return;
        }
}

void test_promise_reduce_and_slices()
{
    ct_host::Terrain t1 = small(1, 14, 12), t2 = small(2, 13, 11);
    for (B b : {B::Brute, B::Slices}) {
        for (int r = 1; r <= 4; ++r) {
            check_package("spikes_wall", t1, 7, r, 0, b);
            check_package("smooth+slices", t2, 16, r, 12, b);
            if (ct_harness_g.current_failed) return;
        }
        check_package("smooth", t2, 64, 1, 0, b);
    }
}

// The slice builder (the default) for N in {1, 4, 8, 16, 24, 32, 64} and r in
// 1..4.  Windows of 1 and 2 coarse cells send nearly all terrain through the
// slice DTs and their widened sectors; the DEMs are large enough (in coarse
// cells) that far terms narrow many cones, which is asserted so that the
// far path is known to be exercised.
void test_promise_slice_builder()
{
    ct_host::Terrain ts[3] = {small(1, 19, 17), small(2, 18, 18), small(0, 17, 15)};
    const char *names[3] = {"spikes_wall", "smooth", "noise"};
    const int ns[] = {1, 4, 8, 16, 24, 32, 64};
    size_t narrowed[5] = {0, 0, 0, 0, 0};
    int k = 0;
    for (int n : ns)
        for (int r = 1; r <= 4; ++r, ++k) {
            int which = k % 3, window = 1 + (k / 3) % 2, slices = (k % 2) ? 0 : 5 + 7 * (k % 5);
            ct_host::BuildStats st;
            check_package(names[which], ts[which], n, r, slices, B::Slices, window, &st);
            narrowed[r] += st.far_narrowed;
            if (ct_harness_g.current_failed) return;
        }
    // given (uneven) levels, in metres: h = 100 m + code * scale
    const std::vector<double> lv = {100.0 + 0.5 * 5000, 100.0 + 0.5 * 9000, 100.0 + 0.5 * 9500, 100.0 + 0.5 * 14000};
    ct_host::BuildStats st;
    check_package("smooth+levels", ts[1], 24, 2, 0, B::Slices, 1, &st, &lv);
    TEST_ASSERT_MSG(st.slices == 4 || st.slices == 5, "given levels: %d slices", st.slices);
    for (int r = 1; r <= 4; ++r) {
        std::printf("  r=%d: %zu cones narrowing events by far (slice DT) terms\n", r, narrowed[r]);
        TEST_ASSERT_MSG(narrowed[r] > 0, "r=%d: the slice DTs never narrowed a cone", r);
    }
}

// The checker itself: cones wider than built (each cot taken down by a
// tenth of its size) break the promise on rough DEMs (noise, spikes and a
// wall: the cones nearly touch them; a smooth DEM's have slack), and it
// must say so; the same packages as built hold.
void test_checker_finds_wider_cones()
{
    const ct_host::Terrain ts[2] = {small(1, 13, 11), small(2, 12, 12)};
    for (int k = 0; k < 2; ++k)
        for (int r = 1; r <= 2; ++r) {
            ct_host::BuildOptions o;
            o.sectors = 8;
            o.reduce = r;
            std::vector<uint8_t> b = ct_host::build_package(ts[k], o);
            ct_package p;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, b.data(), b.size()));
            const Checker as_built = check_promise(ts[k], p, 8, r), wider = check_promise(ts[k], p, 8, r, 0.1L);
            std::printf("  DEM %d r=%d: as built %ld violations, cot 10 %% less %ld\n", k, r,
                        as_built.violations, wider.violations);
            TEST_ASSERT_MSG(as_built.violations == 0 && as_built.undecided == 0, "DEM %d r=%d as built: %ld violations",
                            k, r, as_built.violations);
            TEST_ASSERT_MSG(wider.violations > 0, "DEM %d r=%d: wider cones not found", k, r);
        }
}

// Tile sets (conetrace.h, "Tile sets"): each tile's cones are built from the
// tile alone and promise empty space only inside the tile's box -- all a walk
// over the set uses (a tile's walk ends at its seam; the next tile's starts
// there: test_tiles).  So the promise to check is each tile's, against the
// merged DEM inside that box, which is the tile's own terrain: for several
// N and r, every tile of a DEM cut into 2 x 2 tiles (edge posts shared).
void test_promise_tiles()
{
    const ct_host::Terrain merged[2] = {small(1, 23, 21), small(2, 21, 23)};
    const char *names[2] = {"spikes_wall tile", "smooth tile"};
    for (int which = 0; which < 2; ++which) {
        const ct_host::TileGrid g = ct_host::tile_grid(merged[which].width, merged[which].height, 12);
        TEST_ASSERT(g.tiles_x == 2 && g.tiles_y == 2);
        for (int n : {3, 8, 24})
            for (int r = 1; r <= 3; ++r)
                for (int row = 0; row < g.tiles_y; ++row)
                    for (int col = 0; col < g.tiles_x; ++col) {
                        check_package(names[which], ct_host::tile_terrain(merged[which], g, col, row), n, r);
                        if (ct_harness_g.current_failed) return;
                    }
    }
}

// The slice builder's far terms come from capped directional DT queries, or,
// where those would visit too many rows, from full line-traversal DTs: two
// independent implementations that must give byte-identical packages.  Run
// both ways on every (N, r) of the slice-builder grid and on the real DEM.
void test_slice_dt_paths_agree()
{
    struct Case {
        const char *name;
        ct_host::Terrain t;
        int n, r, window;
    };
    std::vector<Case> cases;
    ct_host::Terrain ts[3] = {small(1, 19, 17), small(2, 18, 18), small(0, 17, 15)};
    int k = 0;
    for (int n : {1, 2, 4, 8, 16, 24, 32, 64})
        for (int r = 1; r <= 4; ++r, ++k) cases.push_back({"small", ts[k % 3], n, r, 1 + k % 2});
    cases.push_back({"jacksboro", dem_cases::real_terrain(), 24, 3, 12});
    cases.push_back({"jacksboro", dem_cases::real_terrain(), 8, 2, 4});
    size_t queried = 0, full = 0;
    for (const Case &c : cases) {
        ct_host::BuildOptions o;
        o.sectors = c.n;
        o.reduce = c.r;
        o.window = c.window;
        ct_host::BuildStats sq, sf;
        o.full_dt_rows = 1e30;  // queries only
        const std::vector<uint8_t> a = ct_host::build_package(c.t, o, &sq);
        o.full_dt_rows = 0.0;  // full DTs only
        const std::vector<uint8_t> b = ct_host::build_package(c.t, o, &sf);
        TEST_ASSERT_MSG(a == b, "%s N=%d r=%d window %d: capped queries and full DTs give different packages", c.name,
                        c.n, c.r, c.window);
        TEST_ASSERT_MSG(sq.full_dts == 0 && sf.dt_queries == 0, "%s N=%d r=%d: paths not separated (%zu full, %zu "
                        "queries)", c.name, c.n, c.r, sq.full_dts, sf.dt_queries);
        queried += sq.dt_queries;
        full += sf.full_dts;
        if (ct_harness_g.current_failed) return;
    }
    std::printf("  %zu capped queries and %zu full DTs gave the same packages in %zu builds\n", queried, full,
                cases.size());
    TEST_ASSERT_MSG(queried > 1000 && full > 100, "too little exercised: %zu queries, %zu full DTs", queried, full);
}

}  // namespace

int main()
{
    TEST_BEGIN("test_promise");
    RUN_TEST(test_checker_finds_wider_cones);
    RUN_TEST(test_promise_sectors);
    RUN_TEST(test_promise_reduce_and_slices);
    RUN_TEST(test_promise_slice_builder);
    RUN_TEST(test_slice_dt_paths_agree);
    RUN_TEST(test_promise_tiles);
    return TEST_END();
}
