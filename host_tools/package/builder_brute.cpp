// builder_brute.cpp -- the reference ("brute force") PPT builder (the
// package is written by package_build.cpp).
//
// For every coarse cell F (closed footprint of r x r fine cells), apex a =
// the tallest corner over F (rounded up to a slice level when K > 0), and
// every sector s, the opening angle must satisfy the cone promise
// (docs/builders.md):
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
// count (docs/builders.md, the cone promise: "a neighbour that only shares
// an edge or a corner ... must not count").  The far/below maxima are found by
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
#include "builder_common.hpp"
#include "builder_slices.hpp"
#include "terrain.hpp"

namespace ct_host {
namespace {
using namespace bld;

struct Node {
    double bound;
    int l, i, j;
    bool operator<(const Node &o) const { return bound < o.bound; }
};


// Needed cot (LSB per fine cell) for coarse cell (ci, cj), sector s, apex a.
// seed: a fine cell index likely to be the maximiser (or -1); updated.
double needed_cot(const Ctx &c, int ci, int cj, int s, int a, long *seed)
{
    int fx0 = ci * c.r, fy0 = cj * c.r, fx1 = std::min(fx0 + c.r, c.cx), fy1 = std::min(fy0 + c.r, c.cy);
    double best = near_term(c, s, fx0, fx1, fy0, fy1);
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


}  // namespace

namespace bld {

void brute_angles(const Ctx &c, const std::vector<uint16_t> &apex, uint8_t *codes, int nthreads,
                  const std::function<void(size_t, size_t)> &progress)
{
    int wc = (c.cx + c.r - 1) / c.r, hc = (c.cy + c.r - 1) / c.r;
    size_t plane = (size_t)wc * hc;
    std::atomic<int> next_row{0};
    std::atomic<size_t> rows_done{0};
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
    if (progress) {
        while (rows_done.load() < (size_t)hc) {
            progress(rows_done.load(), (size_t)hc);
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    }
    for (auto &th : pool) th.join();
    if (progress) progress((size_t)hc, (size_t)hc);
}

}  // namespace bld
}  // namespace ct_host
