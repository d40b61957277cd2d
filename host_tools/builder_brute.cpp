// builder_brute.cpp -- the reference ("brute force") PPT builder and the
// package writer.
//
// For every coarse cell F (closed footprint of r x r fine cells), apex a =
// the tallest corner over F (rounded up to a slice level when K > 0), and
// every sector s, the opening angle must satisfy DESIGN.md's promise:
//   S(q) <= a + rho_s(q) * cot(omega)   for every terrain point q,
// rho_s(q) = min |q - p| over p in F with q - p in the closed wedge W_s.
// We bound sup_q (S(q) - a) / rho_s(q) from above (all in grid units: LSB
// per fine cell) by three valid pieces:
//  near   for q with rho <= K_NEAR: S(q) - a <= S(q) - S(p*) <= rho * (max
//         directional slope of the bilinear patches met on the segment
//         p* -> q, all of which lie in cells within K_NEAR of F in W_s and
//         outside F: p* being the point of F nearest to q, no point of the
//         segment lies in F's interior);
//  far    for q with rho > K_NEAR in a cell Q higher than a:
//         (hmax(Q) - a) / max(K_NEAR, dist_s(F, Q)), and where that bound
//         could be the maximum, the same over Q's sub-squares down to 1/8
//         cell (the patch's maximum over a square is at a corner), which
//         shrinks the column over-estimate from ~1/d to ~1/(8d);
//  below  for cells not higher than a: (hmax(Q) - a) / far_s(F, Q) <= 0.
// Cells whose intersection with F (+) W_s has zero area are skipped: their
// points in the region are limits of points of neighbouring cells that do
// count (DESIGN.md pitfall: "a neighbour that only shares an edge or a
// corner ... must not count").  The far/below maxima are found by
// best-first branch and bound over a max pyramid.  The angle code is then
// the widest whose tracer cot (lib's ct_cot_table, rounded up) is >= the
// bound plus a margin for double rounding.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <queue>
#include <sstream>
#include <thread>

#include "conetrace.h"
#include "terrain.hpp"

namespace ct_host {
namespace {

constexpr double K_NEAR = 1.0;          // cells          // cells
constexpr double INF = std::numeric_limits<double>::infinity();
constexpr size_t BELOW_POP_CAP = 4096;  // effort cap for negative cones
constexpr double GEOM_EPS = 1e-9;       // cells: slab expansion

struct Wedge {
    int n = 1;
    std::vector<int64_t> bx, by;  // n + 1 integer boundary vectors (|b| ~ 2^30)
    std::vector<double> ux, uy;   // the same, unit length
};

Wedge make_wedge(int n)
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

// exact closed / open wedge tests for integer vectors (|v| <= 2^20)
bool in_closed(const Wedge &w, int s, int64_t x, int64_t y)
{
    if (w.n == 1) return true;
    int64_t c0 = w.bx[s] * y - w.by[s] * x;
    int64_t c1 = x * w.by[s + 1] - y * w.bx[s + 1];
    return c0 >= 0 && c1 >= 0;
}
bool in_open(const Wedge &w, int s, int64_t x, int64_t y)
{
    if (w.n == 1) return x != 0 || y != 0;
    int64_t c0 = w.bx[s] * y - w.by[s] * x;
    int64_t c1 = x * w.by[s + 1] - y * w.bx[s + 1];
    return c0 > 0 && c1 > 0;
}

// Rational p/q with q >= 0 (q == 0: +infinity).
struct Frac {
    int64_t p, q;
};
bool frac_lt(Frac a, Frac b)
{
    if (a.q == 0) return false;
    if (b.q == 0) return true;
    return a.p * b.q < b.p * a.q;  // |p| <= 2^18, q <= 2^30
}

// Does {l * b : l > 0} meet the open rectangle (x0,x1) x (y0,y1)?  Exact.
bool ray_meets_open_rect(int64_t bx, int64_t by, int64_t x0, int64_t x1, int64_t y0, int64_t y1)
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
bool overlaps(const Wedge &w, int s, const Rect &r)
{
    if (w.n == 1) return true;
    if (r.x0 < 0 && 0 < r.x1 && r.y0 < 0 && 0 < r.y1) return true;
    if (in_open(w, s, r.x0 + r.x1, r.y0 + r.y1)) return true;
    return ray_meets_open_rect(w.bx[s], w.by[s], r.x0, r.x1, r.y0, r.y1) ||
           ray_meets_open_rect(w.bx[s + 1], w.by[s + 1], r.x0, r.x1, r.y0, r.y1);
}

// Slab interval of the unit ray (ux, uy) through R expanded by GEOM_EPS.
bool slab(double ux, double uy, const Rect &r, double *tlo, double *thi)
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
double dist_min(const Wedge &w, int s, const Rect &r)
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
double dist_max(const Wedge &w, int s, const Rect &r)
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
struct Pyramid {
    std::vector<std::vector<uint16_t>> lv;
    std::vector<int> w, h;
    uint16_t at(int l, int i, int j) const { return lv[l][(size_t)j * w[l] + i]; }
};

Pyramid make_pyramid(const std::vector<uint16_t> &fm, int cx, int cy)
{
    Pyramid p;
    p.lv.push_back(fm);
    p.w.push_back(cx);
    p.h.push_back(cy);
    while (p.w.back() > 1 || p.h.back() > 1) {
        int pw = p.w.back(), ph = p.h.back(), nw = (pw + 1) / 2, nh = (ph + 1) / 2;
        std::vector<uint16_t> nx((size_t)nw * nh, 0);
        const auto &pr = p.lv.back();
        for (int j = 0; j < ph; ++j)
            for (int i = 0; i < pw; ++i) {
                uint16_t &d = nx[(size_t)(j / 2) * nw + i / 2];
                d = std::max(d, pr[(size_t)j * pw + i]);
            }
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
    std::vector<uint16_t> fm;          // fine-cell tallest corner
    Pyramid pyr;
    int64_t cot_q16[256];
    uint8_t cot_ok[256];
};

// Max over u in W_s of the directional derivative of cell (i, j)'s patch
// (LSB per cell); gradient extremes are at the corners.
double max_slope(const Ctx &c, int s, int i, int j)
{
    const Terrain &t = *c.t;
    double h00 = t.at(i, j), h10 = t.at(i + 1, j), h01 = t.at(i, j + 1), h11 = t.at(i + 1, j + 1);
    double a = h10 - h00, b = h01 - h00, cc = h11 - h10 - h01 + h00;
    double best = -INF;
    for (int v = 0; v < 2; ++v)
        for (int u = 0; u < 2; ++u) {
            double gx = a + cc * v, gy = b + cc * u, m;
            double g = std::hypot(gx, gy);
            bool inside = c.wedge.n == 1;
            if (!inside) {
                double c0 = c.wedge.ux[s] * gy - c.wedge.uy[s] * gx;
                double c1 = gx * c.wedge.uy[s + 1] - gy * c.wedge.ux[s + 1];
                inside = c0 >= -1e-12 * g && c1 >= -1e-12 * g;
            }
            if (inside) {
                m = g;
            } else {
                m = std::max(gx * c.wedge.ux[s] + gy * c.wedge.uy[s], gx * c.wedge.ux[s + 1] + gy * c.wedge.uy[s + 1]);
            }
            best = std::max(best, m + 1e-9 * (g + 1.0));
        }
    return best;
}

struct Node {
    double bound;
    int l, i, j;
    bool operator<(const Node &o) const { return bound < o.bound; }
};

Rect block_rect(const Ctx &c, int l, int bi, int bj, int fx0, int fx1, int fy0, int fy1)
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
double sub_term(const Ctx &c, int s, double a, int k, int64_t i, int64_t j, int fx0, int fx1, int fy0, int fy1)
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

// Needed cot (LSB per fine cell) for coarse cell (ci, cj), sector s, apex a.
// seed: a fine cell index likely to be the maximiser (or -1); updated.
double needed_cot(const Ctx &c, int ci, int cj, int s, int a, long *seed)
{
    int fx0 = ci * c.r, fy0 = cj * c.r, fx1 = std::min(fx0 + c.r, c.cx), fy1 = std::min(fy0 + c.r, c.cy);
    double best = -INF;
    // near term
    for (int j = std::max(0, fy0 - 2); j < std::min(c.cy, fy1 + 2); ++j)
        for (int i = std::max(0, fx0 - 2); i < std::min(c.cx, fx1 + 2); ++i) {
            // F's own cells: a segment from the nearest point p* of F to a
            // point q outside F never runs through F's interior (a point of
            // F nearer to q would lie on it), so F's slopes do not count.
            if (i >= fx0 && i < fx1 && j >= fy0 && j < fy1) continue;
            Rect rr = block_rect(c, 0, i, j, fx0, fx1, fy0, fy1);
            if (!overlaps(c.wedge, s, rr)) continue;
            if (dist_min(c.wedge, s, rr) > K_NEAR) continue;
            best = std::max(best, max_slope(c, s, i, j));
        }
    auto leaf_term = [&](int i, int j, bool *ok) {
        Rect rr = block_rect(c, 0, i, j, fx0, fx1, fy0, fy1);
        *ok = false;
        if (!overlaps(c.wedge, s, rr)) return -INF;
        double hm = c.fm[(size_t)j * c.cx + i];
        if (hm > a) {
            double d = dist_min(c.wedge, s, rr);
            if (d == INF) return -INF;
            *ok = true;
            return (hm - a) / std::max(K_NEAR, d);
        }
        double d = dist_max(c.wedge, s, rr);
        if (d <= 0.0) return -INF;
        *ok = true;
        return (hm - a) / d;
    };
    // seed with the previous maximiser (an exact term is a valid lower bound)
    if (*seed >= 0) {
        bool ok;
        int si = (int)(*seed % c.cx), sj = (int)(*seed / c.cx);
        double v = leaf_term(si, sj, &ok);
        if (ok && v > 0.0) {
            // the seed cell's refined far term: every sub-square at full depth
            double vr = -INF;
            const int n = 1 << SUB_DEPTH;
            for (int b = 0; b < n; ++b)
                for (int q = 0; q < n; ++q)
                    vr = std::max(vr, sub_term(c, s, a, SUB_DEPTH, ((int64_t)si << SUB_DEPTH) + q,
                                               ((int64_t)sj << SUB_DEPTH) + b, fx0, fx1, fy0, fy1));
            v = vr;
        }
        if (ok) best = std::max(best, v);
    }
    // phase 1: cells higher than the apex
    int top = (int)c.pyr.lv.size() - 1;
    std::priority_queue<Node> pq;
    pq.push(Node{INF, top, 0, 0});
    while (!pq.empty()) {
        Node nd = pq.top();
        if (nd.bound <= best) break;
        pq.pop();
        if (nd.l <= 0) {
            // a fine cell (l = 0) or a sub-square at depth -l: refine
            int k = -nd.l;
            if (k == SUB_DEPTH) {
                best = nd.bound;
                *seed = (long)(nd.j >> k) * c.cx + (nd.i >> k);
                continue;
            }
            for (int dj = 0; dj < 2; ++dj)
                for (int di = 0; di < 2; ++di) {
                    int64_t si = (int64_t)nd.i * 2 + di, sj = (int64_t)nd.j * 2 + dj;
                    double bound = sub_term(c, s, a, k + 1, si, sj, fx0, fx1, fy0, fy1);
                    if (bound > best) pq.push(Node{bound, -(k + 1), (int)si, (int)sj});
                }
            continue;
        }
        int l = nd.l - 1;
        for (int dj = 0; dj < 2; ++dj)
            for (int di = 0; di < 2; ++di) {
                int bi = nd.i * 2 + di, bj = nd.j * 2 + dj;
                if (bi >= c.pyr.w[l] || bj >= c.pyr.h[l]) continue;
                double hm = c.pyr.at(l, bi, bj);
                if (hm <= a) continue;
                Rect rr = block_rect(c, l, bi, bj, fx0, fx1, fy0, fy1);
                if (!overlaps(c.wedge, s, rr)) continue;
                double d = dist_min(c.wedge, s, rr);
                if (d == INF) continue;
                double bound = (hm - a) / std::max(K_NEAR, d);
                if (bound > best) pq.push(Node{bound, l, bi, bj});
            }
    }
    if (best >= 0.0) return best;
    // phase 2: nothing in the sector rises above the apex; look for the
    // gentlest descent (negative cot), with an effort cap (0 is always valid).
    std::priority_queue<Node> pq2;
    pq2.push(Node{INF, top, 0, 0});
    size_t pops = 0;
    while (!pq2.empty()) {
        Node nd = pq2.top();
        if (nd.bound <= best) break;
        pq2.pop();
        if (++pops > BELOW_POP_CAP) return std::max(best, 0.0);
        if (nd.l == 0) {
            best = std::max(best, nd.bound);
            continue;
        }
        int l = nd.l - 1;
        for (int dj = 0; dj < 2; ++dj)
            for (int di = 0; di < 2; ++di) {
                int bi = nd.i * 2 + di, bj = nd.j * 2 + dj;
                if (bi >= c.pyr.w[l] || bj >= c.pyr.h[l]) continue;
                double hm = c.pyr.at(l, bi, bj);
                Rect rr = block_rect(c, l, bi, bj, fx0, fx1, fy0, fy1);
                if (!overlaps(c.wedge, s, rr)) continue;
                double bound;
                if (l == 0) {
                    bool ok;
                    bound = leaf_term(bi, bj, &ok);
                    if (!ok) continue;
                } else if (hm > a) {
                    bound = INF; // holds cells above a, outside the wedge: descend
                } else {
                    double d = dist_max(c.wedge, s, rr);
                    if (d <= 0.0) continue;
                    bound = (hm - a) / d;
                }
                if (bound > best) pq2.push(Node{bound, l, bi, bj});
            }
    }
    return best;  // -INF: no terrain at all in this sector within the tile
}

// Widest code whose tracer cot covers `need` (LSB per cell).
uint8_t code_for(const Ctx &c, double need)
{
    if (need == -INF) return 255;
    double q = need * 65536.0;
    q = q + std::fabs(q) * 1e-9 + 2.0;  // margin for double rounding
    if (q > 9.0e18) return 0;
    int64_t need_q = (int64_t)std::ceil(q);
    int lo = 0;  // largest k with cot_ok[k] && cot_q16[k] >= need_q; 0 if none
    for (int k = 1; k < 256; ++k) {
        if (c.cot_ok[k] && c.cot_q16[k] >= need_q) lo = k;
    }
    return (uint8_t)lo;
}

void put16(std::vector<uint8_t> &b, size_t off, uint32_t v)
{
    b[off] = (uint8_t)v;
    b[off + 1] = (uint8_t)(v >> 8);
}
void put32(std::vector<uint8_t> &b, size_t off, uint32_t v)
{
    for (int k = 0; k < 4; ++k) b[off + k] = (uint8_t)(v >> (8 * k));
}
void put64(std::vector<uint8_t> &b, size_t off, int64_t v)
{
    for (int k = 0; k < 8; ++k) b[off + k] = (uint8_t)((uint64_t)v >> (8 * k));
}

}  // namespace

std::vector<uint8_t> build_package(const Terrain &t, const BuildOptions &opt, BuildStats *stats)
{
    auto t0 = std::chrono::steady_clock::now();
    if (opt.sectors < 1 || opt.sectors > CT_MAX_SECTORS) throw Error("sectors must be in 1..64");
    if (opt.reduce < 1 || opt.reduce > CT_MAX_REDUCE) throw Error("reduce must be in 1..8");
    if (opt.slices < 0) throw Error("slices must be >= 0");
    if (t.width < 2 || t.height < 2 || t.width > CT_MAX_POSTS || t.height > CT_MAX_POSTS)
        throw Error("DEM dimensions outside 2..32768 posts");
    if ((size_t)t.width * t.height != t.codes.size()) throw Error("terrain codes size mismatch");

    Ctx c;
    c.t = &t;
    c.cx = t.width - 1;
    c.cy = t.height - 1;
    c.r = opt.reduce;
    c.n = opt.sectors;
    c.wedge = make_wedge(opt.sectors);
    c.fm.resize((size_t)c.cx * c.cy);
    for (int j = 0; j < c.cy; ++j)
        for (int i = 0; i < c.cx; ++i)
            c.fm[(size_t)j * c.cx + i] =
                std::max(std::max(t.at(i, j), t.at(i + 1, j)), std::max(t.at(i, j + 1), t.at(i + 1, j + 1)));
    c.pyr = make_pyramid(c.fm, c.cx, c.cy);

    // georeference as stored
    int64_t pe = metres_to_nm(t.geo.posting_e), pn = metres_to_nm(t.geo.posting_n);
    int64_t sc = metres_to_nm(t.height_scale_m);
    if (pe == 0 || pn == 0 || std::llabs(pe) != std::llabs(pn)) {
        std::ostringstream os;
        os << "non-square posting (" << t.geo.posting_e << " x " << t.geo.posting_n << " m)";
        throw Error(os.str());
    }
    if (sc <= 0) throw Error("height scale must be positive");
    if (ct_cot_table(pe, sc, c.cot_q16, c.cot_ok) != CT_OK) throw Error("posting or height scale out of range");

    bool voids = !t.void_post.empty();
    uint32_t so[CT_SEC_COUNT], ss[CT_SEC_COUNT], levels, total;
    if (ct_package_layout((uint32_t)t.width, (uint32_t)t.height, (uint32_t)c.r, (uint32_t)c.n, voids ? 1u : 0u, so, ss,
                          &levels, &total) != CT_OK)
        throw Error("package layout failed (size limits)");
    std::vector<uint8_t> b(total, 0);

    uint16_t hmin = 65535, hmax = 0;
    for (size_t k = 0; k < t.codes.size(); ++k) {
        put16(b, so[CT_SEC_HEIGHTS] + 2 * k, t.codes[k]);
        hmin = std::min(hmin, t.codes[k]);
        hmax = std::max(hmax, t.codes[k]);
    }
    {
        size_t off = so[CT_SEC_MIPMAP];
        for (uint32_t l = 1; l <= levels; ++l) {
            const auto &lv = c.pyr.lv[l];
            for (uint16_t v : lv) {
                put16(b, off, v);
                off += 2;
            }
        }
    }
    // apexes
    int wc = (c.cx + c.r - 1) / c.r, hc = (c.cy + c.r - 1) / c.r;
    std::vector<int> apex((size_t)wc * hc);
    for (int cj = 0; cj < hc; ++cj)
        for (int ci = 0; ci < wc; ++ci) {
            int m = 0;
            for (int j = cj * c.r; j < std::min(c.cy, (cj + 1) * c.r); ++j)
                for (int i = ci * c.r; i < std::min(c.cx, (ci + 1) * c.r); ++i) m = std::max<int>(m, c.fm[(size_t)j * c.cx + i]);
            if (opt.slices > 0 && hmax > hmin) {
                // smallest level hmin + k*(hmax-hmin)/K >= m, as an integer code
                double step = (double)(hmax - hmin) / opt.slices;
                int k = (int)std::ceil((m - hmin) / step - 1e-12);
                int lvl = (int)std::ceil(hmin + k * step - 1e-9);
                m = std::min<int>(hmax, std::max(m, lvl));
            }
            apex[(size_t)cj * wc + ci] = m;
            put16(b, so[CT_SEC_APEX] + 2 * ((size_t)cj * wc + ci), (uint32_t)m);
        }
    // angles
    size_t plane = (size_t)wc * hc;
    std::vector<uint8_t> codes(plane * (size_t)c.n);
    std::atomic<int> next_row{0};
    std::atomic<size_t> rows_done{0};
    int nthreads = opt.threads > 0 ? opt.threads : (int)std::max(1u, std::thread::hardware_concurrency());
    auto worker = [&]() {
        std::vector<long> seed(c.n, -1);
        for (;;) {
            int cj = next_row.fetch_add(1);
            if (cj >= hc) break;
            std::fill(seed.begin(), seed.end(), -1);
            for (int ci = 0; ci < wc; ++ci) {
                int a = apex[(size_t)cj * wc + ci];
                for (int s = 0; s < c.n; ++s) {
                    double need = needed_cot(c, ci, cj, s, a, &seed[s]);
                    codes[(size_t)s * plane + (size_t)cj * wc + ci] = code_for(c, need);
                }
            }
            rows_done.fetch_add(1);
        }
    };
    std::vector<std::thread> pool;
    for (int k = 0; k < nthreads; ++k) pool.emplace_back(worker);
    if (opt.progress) {
        while (rows_done.load() < (size_t)hc) {
            opt.progress(rows_done.load(), (size_t)hc);
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    }
    for (auto &th : pool) th.join();
    if (opt.progress) opt.progress((size_t)hc, (size_t)hc);

    size_t degenerate = 0;
    for (size_t k = 0; k < codes.size(); ++k) {
        b[so[CT_SEC_ANGLES] + k] = codes[k];
        degenerate += codes[k] == 0;
    }
    if (c.n > 1) {
        for (size_t k = 0; k < plane; ++k) {
            uint8_t m = 255;
            for (int s = 0; s < c.n; ++s) m = std::min(m, codes[(size_t)s * plane + k]);
            b[so[CT_SEC_ANGLES] + (size_t)c.n * plane + k] = m;
        }
    }
    if (voids) {
        for (int j = 0; j < c.cy; ++j)
            for (int i = 0; i < c.cx; ++i) {
                size_t p00 = (size_t)j * t.width + i;
                bool v = t.void_post[p00] || t.void_post[p00 + 1] || t.void_post[p00 + t.width] ||
                         t.void_post[p00 + t.width + 1];
                size_t k = (size_t)j * c.cx + i;
                if (v) b[so[CT_SEC_VOIDS] + k / 8] |= (uint8_t)(1u << (k % 8));
            }
    }
    // header
    std::memcpy(&b[0], CT_PKG_MAGIC, 4);
    put16(b, 4, CT_PKG_VERSION);
    put16(b, 6, CT_PKG_HEADER_SIZE);
    put32(b, 8, total);
    put16(b, 16, (uint32_t)t.width);
    put16(b, 18, (uint32_t)t.height);
    b[20] = (uint8_t)c.r;
    b[21] = (uint8_t)c.n;
    b[22] = (uint8_t)levels;
    b[23] = voids ? CT_PKG_FLAG_VOIDS : 0;
    put16(b, 24, hmin);
    put16(b, 26, hmax);
    put32(b, 28, (uint32_t)opt.slices);
    put64(b, 32, metres_to_nm(t.geo.origin_e));
    put64(b, 40, metres_to_nm(t.geo.origin_n));
    put64(b, 48, pe);
    put64(b, 56, pn);
    put64(b, 64, metres_to_nm(t.height_offset_m));
    put64(b, 72, sc);
    put32(b, 80, (uint32_t)std::max(0, t.geo.epsg));
    for (int k = 0; k < CT_SEC_COUNT; ++k) {
        put32(b, CT_HDR_SECTION_TABLE + 8 * k, so[k]);
        put32(b, CT_HDR_SECTION_TABLE + 8 * k + 4, ss[k]);
    }
    uint32_t crc = 0;
    ct_crc32(0, b.data(), b.size(), &crc);  // CRC field is still zero
    put32(b, 12, crc);
    if (stats) {
        stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        stats->degenerate_cones = degenerate;
        stats->cones = codes.size();
    }
    return b;
}

}  // namespace ct_host
