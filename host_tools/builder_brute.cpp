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
    prepare_codes(c);

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
            const auto &lv = c.pyr.lv[l];  // level 0 (fine cells) is not stored
            for (uint16_t v : lv) {
                put16(b, off, v);
                off += 2;
            }
        }
    }
    // apexes and angles
    int wc = (c.cx + c.r - 1) / c.r, hc = (c.cy + c.r - 1) / c.r;
    size_t plane = (size_t)wc * hc;
    int nthreads = opt.threads > 0 ? opt.threads : (int)std::max(1u, std::thread::hardware_concurrency());
    std::vector<uint16_t> apex(plane);  // height codes
    // the angle planes, written in place in the package (sector-major, then
    // the omnidirectional plane when N > 1)
    uint8_t *codes = &b[so[CT_SEC_ANGLES]];
    int slices_header = opt.slices;
    for (int cj = 0; cj < hc; ++cj)
        for (int ci = 0; ci < wc; ++ci) {
            int m = 0;
            for (int j = cj * c.r; j < std::min(c.cy, (cj + 1) * c.r); ++j)
                for (int i = ci * c.r; i < std::min(c.cx, (ci + 1) * c.r); ++i) m = std::max<int>(m, c.fm[(size_t)j * c.cx + i]);
            apex[(size_t)cj * wc + ci] = (uint16_t)m;
        }
    if (opt.builder == PptBuilder::Slices) {
        int K = opt.slices > 0 ? opt.slices : BuildOptions::DEFAULT_SLICES;
        slices_header = K;
        // levels L_k = ceil(hmin + k (hmax - hmin) / K), duplicates removed
        std::vector<int> lv;
        if (!opt.levels_m.empty()) {
            // given levels in metres -> codes (rounded up: a level is only a
            // height at which a slice is cut), plus the extremes
            lv.push_back(hmin);
            lv.push_back(hmax);
            for (double m : opt.levels_m) {
                if (!std::isfinite(m)) throw Error("slice level is not a number");
                double code = std::ceil((m - t.height_offset_m) / t.height_scale_m - 1e-9);
                if (code > hmin && code < hmax) lv.push_back((int)code);
            }
            std::sort(lv.begin(), lv.end());
            lv.erase(std::unique(lv.begin(), lv.end()), lv.end());
            slices_header = (int)lv.size() - 1;
        } else {
            for (int k = 0; k <= K; ++k) {
                int l = (int)std::ceil(hmin + (double)k * (hmax - hmin) / K - 1e-9);
                l = std::clamp<int>(l, hmin, hmax);
                if (k == K) l = hmax;
                if (lv.empty() || l > lv.back()) lv.push_back(l);
            }
        }
        std::vector<uint16_t> k0(plane);  // < lv.size() <= 65536
        for (size_t f = 0; f < plane; ++f) {
            // the paper's apex: the lowest level not below the cell's top
            // (measured: 7% fewer steps than exact apexes with K = 64)
            k0[f] = (uint16_t)(std::lower_bound(lv.begin(), lv.end(), (int)apex[f]) - lv.begin());
            apex[f] = (uint16_t)lv[(size_t)k0[f]];
        }
        bld::SliceInput in;
        in.levels = &lv;
        in.apex_level = &k0;
        in.apex = &apex;
        in.window = opt.window;
        in.full_dt_rows = opt.full_dt_rows;
        in.threads = nthreads;
        in.progress = opt.progress;
        bld::SliceStats sst;
        bld::slice_angles(c, in, codes, &sst);
        if (stats) {
            stats->slices = (int)lv.size() - 1;
            stats->slices_transformed = sst.slices;
            stats->seconds_local = sst.seconds_local;
            stats->far_narrowed = sst.far_narrowed;
            stats->dts_skipped = sst.dts_skipped;
            stats->dt_queries = sst.queries;
            stats->dt_query_rows = sst.query_rows;
            stats->full_dts = sst.full_dts;
            stats->seconds_dt = sst.seconds_dt;
        }
    } else {
        if (opt.slices > 0 && hmax > hmin) {
            for (uint16_t &am : apex) {
                int m = am;
                // smallest level hmin + k*(hmax-hmin)/K >= m, as an integer code
                double step = (double)(hmax - hmin) / opt.slices;
                int k = (int)std::ceil((m - hmin) / step - 1e-12);
                int lvl = (int)std::ceil(hmin + k * step - 1e-9);
                am = (uint16_t)std::min<int>(hmax, std::max(m, lvl));
            }
        }
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
        if (opt.progress) {
            while (rows_done.load() < (size_t)hc) {
                opt.progress(rows_done.load(), (size_t)hc);
                std::this_thread::sleep_for(std::chrono::milliseconds(100));
            }
        }
        for (auto &th : pool) th.join();
        if (opt.progress) opt.progress((size_t)hc, (size_t)hc);
    }
    for (size_t f = 0; f < plane; ++f) put16(b, so[CT_SEC_APEX] + 2 * f, (uint32_t)apex[f]);

    if (stats) {
        stats->cones = plane * (size_t)c.n;
    }
    size_t degenerate = 0;
    for (size_t k = 0; k < plane * (size_t)c.n; ++k) degenerate += codes[k] == 0;
    if (c.n > 1) {
        for (size_t k = 0; k < plane; ++k) {
            uint8_t m = 255;
            for (int s = 0; s < c.n; ++s) m = std::min(m, codes[(size_t)s * plane + k]);
            codes[(size_t)c.n * plane + k] = m;
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
    put32(b, 28, (uint32_t)slices_header);
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
    }
    return b;
}

}  // namespace ct_host
