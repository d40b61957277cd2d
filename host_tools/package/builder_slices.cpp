// builder_slices.cpp -- the paper's PPT builder (Paglieroni 1997, sec. 2.3):
// directional distance transforms of horizontal cross-sections, processed
// bottom-up one slice at a time, made conservative for the cone promise
// (docs/builders.md).
//
// Grid: coarse cells G (r x r fine cells, height Hc(G) = max over its fine
// cells of the tallest corner).  Levels L_0 < L_1 < ... < L_K (integer height
// codes, L_0 = hmin, L_K = hmax, evenly spaced or given, duplicates removed).  Apex of
// coarse cell F: a = L_k0, the lowest level not below Hc(F).  Slice k is the
// bitmap B_k = { G : Hc(G) > L_k }.
//
// The needed cot C(F, s) (LSB per fine cell) must bound (S(q) - a) / rho_s(q)
// for every terrain point q with S(q) > a, rho_s(q) = min |q - p| over p in
// F's footprint with q - p in the closed wedge W_s (docs/builders.md).  Three parts,
// each a valid bound for the points it covers:
//  near    rho_s(q) <= K_NEAR: the surface's directional slopes (shared with
//          the brute-force builder, builder_common.hpp);
//  window  q in a coarse cell G = F + v with |v|_inf <= Rw: the column bound
//          (Hc(G) - a) / max(K_NEAR, min rho over G in W_s), exact geometry,
//          offsets precomputed per sector; for |v|_inf <= FINE_RING per fine
//          cell instead of per coarse cell, and the largest such terms (up
//          to three per cone) refined best-first over 1/8-cell sub-squares
//          (sub_term: the patch's maximum over a sub-square is at a corner);
//  far     q in G with |v|_inf > Rw.  Let S(q) be in (L_k, L_k+1] (k >= k0);
//          then G is in B_k, and
//            rho_s(q) >= r * (|v| - sqrt2)          (p, q anywhere in F, G)
//            rho_s(q) >= r * Rw                    (|v|_inf >= Rw + 1)
//          and, since q - p in W_s and |r v - (q - p)| <= r sqrt2, v lies
//          within the angle delta = asin(sqrt2 / (Rw + 1)) of W_s: in the
//          widened wedge W'_s = W_s rotated outwards by delta on both sides.
//          With DT_k(F) the exact Euclidean directional DT of B_k at F over
//          W'_s (ddt.hpp: rasterized line traversal), DT_k(F) <= |v|, so
//            (S(q) - a) / rho_s(q) <= (L_k+1 - a) / (r * max(Rw, DT_k - sqrt2)).
//          The radius is held constant across the band (L_k, L_k+1], as the
//          paper prescribes.
// The code stored is the widest angle whose tracer cot covers max(0, near,
// window, far_k for all k >= k0), rounded down (code_for).  Slices are done
// bottom-up with one slice in memory; each slice's sectors run on the worker
// threads (one sector per thread at a time).
//
// DT_k is needed only where a far term could narrow the current code, i.e.
// for cells with X = (L_k+1 - a) / cot > r Rw, and only below the cap
// (X / r + sqrt2)^2: about 10% of the cells per slice and sector on the real
// DEM, with caps of ~30 cells.  So each such cell asks a capped query
// (ddt::CappedQuery: the same canonical frames and exact wedge intervals as
// the line traversal, one bitset lookup per row); a (slice, sector) whose
// queries visit more than full_dt_rows rows per cell finishes with one full
// line-traversal DT (ddt::directional), and so does the same sector of the
// next slice.  Both give the exact DT below the cap: the packages are
// byte-identical whichever runs (test_promise), and identical to computing
// every DT in full (the paper's way), which is 2-3x slower at 2048^2.
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

#include "builder_common.hpp"
#include "builder_slices.hpp"
#include "ddt.hpp"

namespace ct_host {
namespace bld {
namespace {

struct WinOffset {
    int dx, dy;      // coarse cells
    double rho;      // max(K_NEAR, min rho over the offset's rectangle in W_s), fine cells
};

// Offsets of the window (|v|_inf <= rw, v != 0) whose rectangle of q - p
// meets W_s with positive area, per sector.  Coarse offsets with |v|_inf <=
// FINE_RING go to `fine` as the fine cells they hold (offsets from F's
// top-left fine cell; the column bound per fine cell is far tighter than
// per coarse cell next to F), the rest to `coarse`.
constexpr int FINE_RING = 2;

// `near`: the fine cells of near_term() (builder_common.hpp) for a whole
// footprint, as offsets from F's top-left fine cell (a superset of a partial
// edge cell's: distances to a subset of F are no shorter).
void window_offsets(const Ctx &c, int rw, std::vector<std::vector<WinOffset>> *fine,
                    std::vector<std::vector<WinOffset>> *coarse, std::vector<std::vector<WinOffset>> *nearl)
{
    fine->assign((size_t)c.n, {});
    coarse->assign((size_t)c.n, {});
    nearl->assign((size_t)c.n, {});
    const int64_t r = c.r;
    for (int s = 0; s < c.n; ++s) {
        for (int dy = -rw; dy <= rw; ++dy)
            for (int dx = -rw; dx <= rw; ++dx) {
                if (std::max(std::abs(dx), std::abs(dy)) <= FINE_RING) continue;
                Rect rr{r * dx - r, r * dx + r, r * dy - r, r * dy + r};
                if (!overlaps(c.wedge, s, rr)) continue;
                double d = dist_min(c.wedge, s, rr);
                if (d == INF) continue;
                (*coarse)[(size_t)s].push_back(WinOffset{dx, dy, std::max(K_NEAR, d)});
            }
        for (int oy = -2; oy < r + 2; ++oy)
            for (int ox = -2; ox < r + 2; ++ox) {
                if (ox >= 0 && ox < r && oy >= 0 && oy < r) continue;
                Rect rr{ox - r, ox + 1, oy - r, oy + 1};
                if (!overlaps(c.wedge, s, rr)) continue;
                if (dist_min(c.wedge, s, rr) > K_NEAR) continue;
                (*nearl)[(size_t)s].push_back(WinOffset{ox, oy, 0.0});
            }
        const int lo = -FINE_RING * (int)r, hi = (FINE_RING + 1) * (int)r;
        for (int oy = lo; oy < hi; ++oy)
            for (int ox = lo; ox < hi; ++ox) {
                if (ox >= 0 && ox < r && oy >= 0 && oy < r) continue;  // F's own cells: below a
                Rect rr{ox - r, ox + 1, oy - r, oy + 1};
                if (!overlaps(c.wedge, s, rr)) continue;
                double d = dist_min(c.wedge, s, rr);
                if (d == INF) continue;
                (*fine)[(size_t)s].push_back(WinOffset{ox, oy, std::max(K_NEAR, d)});
            }
    }
}

// The widened wedge W'_s as pieces of at most 90 degrees (closed, sharing
// their inner boundaries exactly), or an empty list for "every direction".
std::vector<ddt::Wedge> widened_pieces(const Ctx &c, int s, double delta)
{
    std::vector<ddt::Wedge> out;
    if (c.n == 1) return out;
    constexpr double PI = 3.14159265358979323846;
    double t0 = std::atan2((double)c.wedge.by[s], (double)c.wedge.bx[s]);
    double t1 = std::atan2((double)c.wedge.by[s + 1], (double)c.wedge.bx[s + 1]);
    double open = t1 - t0;
    while (open <= 0.0) open += 2.0 * PI;
    double a0 = t0 - delta, span = open + 2.0 * delta;
    if (span >= 2.0 * PI - 1e-6) return out;
    int m = (int)std::ceil(span / (PI / 2.0) - 1e-12);
    auto vec = [](double t, int64_t *x, int64_t *y) {
        *x = (int64_t)std::llround(std::cos(t) * 1073741824.0);
        *y = (int64_t)std::llround(std::sin(t) * 1073741824.0);
    };
    int64_t px, py;
    vec(a0, &px, &py);
    for (int k = 1; k <= m; ++k) {
        int64_t qx, qy;
        vec(a0 + span * k / m, &qx, &qy);
        ddt::Wedge w;
        w.b1x = px;
        w.b1y = py;
        w.b2x = qx;
        w.b2y = qy;
        out.push_back(w);
        px = qx;
        py = qy;
    }
    return out;
}

// ---- the near and window terms ------------------------------------------

// The per-sector offset lists merged: each offset is visited once per cell
// (one height load and compare), then credited to its sectors.
struct Merged {
    int dx, dy;
    size_t first, count;  // into secs / rhos
};
struct MergedList {
    std::vector<Merged> offs;
    std::vector<int> secs;
    std::vector<double> rhos;
};

MergedList merge_offsets(const Ctx &c, const std::vector<std::vector<WinOffset>> &per)
{
    std::map<std::pair<int, int>, std::vector<std::pair<int, double>>> m;
    for (int s = 0; s < c.n; ++s)
        for (const WinOffset &o : per[(size_t)s]) m[{o.dy, o.dx}].push_back({s, o.rho});
    MergedList out;
    for (const auto &kv : m) {
        out.offs.push_back(Merged{kv.first.second, kv.first.first, out.secs.size(), kv.second.size()});
        for (const auto &e : kv.second) {
            out.secs.push_back(e.first);
            out.rhos.push_back(e.second);
        }
    }
    return out;
}

// The fine window's three largest terms of a sector (value, fine cell), and
// the largest of the rest, for the sub-square refinement.
struct Top {
    double v[3];
    int qi[3], qj[3];
    double rest;
    void reset() { v[0] = v[1] = v[2] = rest = -INF; }
    void add(double x, int i, int j)
    {
        if (x <= v[2]) {
            rest = std::max(rest, x);
            return;
        }
        rest = std::max(rest, v[2]);
        int k = 2;
        while (k > 0 && x > v[k - 1]) {
            v[k] = v[k - 1], qi[k] = qi[k - 1], qj[k] = qj[k - 1];
            --k;
        }
        v[k] = x, qi[k] = i, qj[k] = j;
    }
};

// A coarse-window offset of one sector with 1 / rho: a product instead of a
// division per term (within an ulp of the quotient, far inside code_for's
// margin).
struct SecOffset {
    int dx, dy;
    double inv_rho;
};

constexpr int RING_SIDE = 2 * FINE_RING + 1, RING_GROUPS = RING_SIDE * RING_SIDE;

// Consecutive fine-ring offsets (in mfine's order) in one coarse cell of the
// ring and one row: a cell skips a run whose coarse cell does not rise above
// its apex with one test instead of one per offset, and tests the tile's
// edges once per run when the whole run lies inside (near and window terms
// of a 4097^2 tile at r = 8: 0.68 -> 0.46 s; at r = 3, runs of 3, no
// change).  The offsets keep their order: the same terms in the same
// sequence, the same codes.
struct FineRun {
    size_t first, last;    // offsets [first, last) of mfine.offs
    int group;             // the coarse cell, an index into alive[]
    int dy, dx0, dx1;      // their row, first and last column (increasing)
    double min_rho;        // the least rho of their terms
    size_t sfirst, scount;  // the sectors of their terms: run_secs[sfirst, sfirst + scount)
};

// What the near and window terms read, shared by the workers.
struct LocalTables {
    MergedList mnear, mfine, mcoarse;
    std::vector<FineRun> fine_runs;                 // mfine.offs cut where the coarse cell or the row changes
    std::vector<int> run_secs;                      // each run's sectors, once each
    std::vector<std::vector<SecOffset>> by_sector;  // the coarse window per sector, by increasing rho
};

LocalTables local_tables(const Ctx &c, int rw)
{
    std::vector<std::vector<WinOffset>> win, wfine, wnear;
    window_offsets(c, std::max(rw, FINE_RING), &wfine, &win, &wnear);
    LocalTables t;
    t.mnear = merge_offsets(c, wnear);
    t.mfine = merge_offsets(c, wfine);
    t.mcoarse = merge_offsets(c, win);
    const int r = c.r;
    for (size_t m = 0; m < t.mfine.offs.size(); ++m) {
        auto fdiv = [r](int v) { return v >= 0 ? v / r : -((-v + r - 1) / r); };
        const Merged &o = t.mfine.offs[m];
        int gx = fdiv(o.dx) + FINE_RING, gy = fdiv(o.dy) + FINE_RING;
        if (gx < 0 || gy < 0 || gx >= RING_SIDE || gy >= RING_SIDE) throw Error("slice builder: fine ring offset");
        const int g = gy * RING_SIDE + gx;
        FineRun *b = t.fine_runs.empty() ? nullptr : &t.fine_runs.back();
        if (b && b->group == g && b->dy == o.dy && b->dx1 < o.dx) {
            b->last = m + 1;
            b->dx1 = o.dx;
        } else {
            t.fine_runs.push_back(FineRun{m, m + 1, g, o.dy, o.dx, o.dx, 0.0, 0, 0});
        }
    }
    for (FineRun &run : t.fine_runs) {
        run.min_rho = INF;
        run.sfirst = t.run_secs.size();
        for (size_t m = run.first; m < run.last; ++m) {
            const Merged &o = t.mfine.offs[m];
            for (size_t e = o.first; e < o.first + o.count; ++e) {
                run.min_rho = std::min(run.min_rho, t.mfine.rhos[e]);
                const int s = t.mfine.secs[e];
                if (std::find(t.run_secs.begin() + (long)run.sfirst, t.run_secs.end(), s) == t.run_secs.end())
                    t.run_secs.push_back(s);
            }
        }
        run.scount = t.run_secs.size() - run.sfirst;
    }
    t.by_sector.assign((size_t)c.n, {});
    for (const Merged &o : t.mcoarse.offs)
        for (size_t e = o.first; e < o.first + o.count; ++e)
            t.by_sector[(size_t)t.mcoarse.secs[e]].push_back(SecOffset{o.dx, o.dy, 1.0 / t.mcoarse.rhos[e]});
    for (auto &l : t.by_sector)
        std::stable_sort(l.begin(), l.end(), [](const SecOffset &x, const SecOffset &y) { return x.inv_rho > y.inv_rho; });
    return t;
}

struct Sub {
    int k;
    int64_t i, j;
};

// The cot sector s of a cell needs from its near and window terms: the
// largest fine-window terms refined to 1/8-cell sub-squares (the column
// bound at the cell's tallest corner and nearest point over-estimates most
// next to F) while one of them is the maximum, at most 3; `other` is the
// largest of the rest.  Best-first over the quadtree of sub-squares: a
// sub-square's bound covers its children, so only those above every other
// term are split; the result is exact where it matters (above `other`).
double refined_need(const Ctx &c, int s, double a, Top &tp, double other, int fx0, int fx1, int fy0, int fy1,
                    std::vector<Sub> &stack)
{
    bool done[3] = {false, false, false};
    for (int it = 0; it < 3; ++it) {
        int m = 0;
        for (int q = 1; q < 3; ++q)
            if (tp.v[q] > tp.v[m]) m = q;
        if (tp.v[m] <= other || done[m]) break;
        const double floor = other;
        double vr = -INF;
        stack.clear();
        stack.push_back(Sub{0, tp.qi[m], tp.qj[m]});
        while (!stack.empty()) {
            Sub sq = stack.back();
            stack.pop_back();
            for (int d = 0; d < 4; ++d) {
                int64_t ci2 = sq.i * 2 + (d & 1), cj2 = sq.j * 2 + (d >> 1);
                double b = sub_term(c, s, a, sq.k + 1, ci2, cj2, fx0, fx1, fy0, fy1);
                if (b <= std::max(floor, vr)) continue;
                if (sq.k + 1 == SUB_DEPTH)
                    vr = b;
                else
                    stack.push_back(Sub{sq.k + 1, ci2, cj2});
            }
        }
        // vr = -INF: nothing of the cell rises above floor
        tp.v[m] = std::min(tp.v[m], std::max(vr, floor));
        done[m] = true;
    }
    return std::max(other, std::max(tp.v[0], std::max(tp.v[1], tp.v[2])));
}

// One worker's scratch for the near and window terms.
struct LocalScratch {
    std::vector<uint16_t> colmax, winmax;  // per coarse column of the row: the window's max height
    bool alive[RING_GROUPS];               // the fine ring's coarse cells that rise above the apex
    double rise[RING_GROUPS];              // and by how much (when alive)
    std::vector<double> need;              // per sector
    std::vector<Top> top;                  // per sector
    std::vector<Sub> stack;
};

// What a row of the near and window terms reads.
struct LocalInput {
    const Ctx *c;
    const LocalTables *t;
    const std::vector<uint16_t> *hcm;  // coarse heights
    const std::vector<double> *lvd;    // levels
    const std::vector<uint16_t> *k0;   // apex level per coarse cell
    int rw, wc, hc;
    size_t plane;
};

// The codes of every cell of coarse row cj from its near and window terms.
void local_row(const LocalInput &L, int cj, LocalScratch &sc, uint8_t *codes)
{
    const Ctx &c = *L.c;
    const LocalTables &T = *L.t;
    const std::vector<uint16_t> &hcm = *L.hcm;
    const int r = c.r, wc = L.wc, hc = L.hc;
    if (r > 1) {  // the window's max height around each cell of the row
        const int rww = std::max(L.rw, FINE_RING);
        std::fill(sc.colmax.begin(), sc.colmax.end(), (uint16_t)0);
        for (int gj = std::max(0, cj - rww); gj <= std::min(hc - 1, cj + rww); ++gj)
            for (int gi = 0; gi < wc; ++gi)
                sc.colmax[(size_t)gi] = std::max(sc.colmax[(size_t)gi], hcm[(size_t)gj * wc + gi]);
        for (int ci = 0; ci < wc; ++ci) {
            uint16_t m = 0;
            for (int gi = std::max(0, ci - rww); gi <= std::min(wc - 1, ci + rww); ++gi)
                m = std::max(m, sc.colmax[(size_t)gi]);
            sc.winmax[(size_t)ci] = m;
        }
    }
    for (int ci = 0; ci < wc; ++ci) {
        size_t f = (size_t)cj * wc + ci;
        double a = (*L.lvd)[(*L.k0)[f]];  // the cell's apex: its level
        int fx0 = ci * r, fy0 = cj * r;
        // the coarse cells of the fine ring that rise above a
        for (int g = 0; g < RING_GROUPS; ++g) {
            int gi = ci + g % RING_SIDE - FINE_RING, gj = cj + g / RING_SIDE - FINE_RING;
            sc.alive[g] = gi >= 0 && gj >= 0 && gi < wc && gj < hc && hcm[(size_t)gj * wc + gi] > a;
            if (sc.alive[g]) sc.rise[g] = hcm[(size_t)gj * wc + gi] - a;
        }
        std::fill(sc.need.begin(), sc.need.end(), 0.0);
        for (Top &tp : sc.top) tp.reset();
        for (const Merged &o : T.mnear.offs) {
            int qi = fx0 + o.dx, qj = fy0 + o.dy;
            if (qi < 0 || qj < 0 || qi >= c.cx || qj >= c.cy) continue;
            const PatchGrad g = patch_grad(*c.t, qi, qj);
            for (size_t e = o.first; e < o.first + o.count; ++e) {
                int s = T.mnear.secs[e];
                sc.need[(size_t)s] = std::max(sc.need[(size_t)s], max_slope(c, s, g));
            }
        }
        for (const FineRun &run : T.fine_runs) {
            if (!sc.alive[run.group]) continue;  // its coarse cell is not above a
            {
                // no term of the run exceeds its coarse cell's rise over its
                // least rho (a fine cell is no taller than its coarse cell,
                // and a quotient of doubles is monotone in both): when that
                // bound neither enters a sector's top three nor raises its
                // rest, the run's terms change nothing (the same codes)
                const double bound = sc.rise[run.group] / run.min_rho;
                bool passed = true;
                for (size_t q = run.sfirst; q < run.sfirst + run.scount && passed; ++q) {
                    const Top &tp = sc.top[(size_t)T.run_secs[q]];
                    passed = bound <= tp.v[2] && bound <= tp.rest;
                }
                if (passed) continue;
            }
            const int qj = fy0 + run.dy;
            if (qj < 0 || qj >= c.cy) continue;
            const bool inside = fx0 + run.dx0 >= 0 && fx0 + run.dx1 < c.cx;
            for (size_t m = run.first; m < run.last; ++m) {
                const Merged &o = T.mfine.offs[m];
                int qi = fx0 + o.dx;
                if (!inside && (qi < 0 || qi >= c.cx)) continue;
                double rise = fine_max(*c.t, qi, qj) - a;
                if (rise <= 0.0) continue;
                for (size_t e = o.first; e < o.first + o.count; ++e)
                    sc.top[(size_t)T.mfine.secs[e]].add(rise / T.mfine.rhos[e], qi, qj);
            }
        }
        if (r == 1) {  // a coarse cell is a fine cell: refinable too
            for (const Merged &o : T.mcoarse.offs) {
                int gi = ci + o.dx, gj = cj + o.dy;
                if (gi < 0 || gj < 0 || gi >= wc || gj >= hc) continue;
                double rise = hcm[(size_t)gj * wc + gi] - a;
                if (rise <= 0.0) continue;
                for (size_t e = o.first; e < o.first + o.count; ++e)
                    sc.top[(size_t)T.mcoarse.secs[e]].add(rise / T.mcoarse.rhos[e], gi, gj);
            }
        } else if (sc.winmax[(size_t)ci] > a) {
            // per sector, nearest offsets first; no term beyond rho can
            // exceed (window max - a) / rho, so stop once that is no more
            // than what the sector needs already
            const double hw = sc.winmax[(size_t)ci] - a;
            for (int s = 0; s < c.n; ++s) {
                double nd = sc.need[(size_t)s];
                for (const SecOffset &o : T.by_sector[(size_t)s]) {
                    if (hw * o.inv_rho <= nd) break;
                    int gi = ci + o.dx, gj = cj + o.dy;
                    if (gi < 0 || gj < 0 || gi >= wc || gj >= hc) continue;
                    double rise = hcm[(size_t)gj * wc + gi] - a;
                    if (rise > 0.0) nd = std::max(nd, rise * o.inv_rho);
                }
                sc.need[(size_t)s] = nd;
            }
        }
        const int fx1 = std::min(fx0 + r, c.cx), fy1 = std::min(fy0 + r, c.cy);
        for (int s = 0; s < c.n; ++s) {
            Top &tp = sc.top[(size_t)s];
            const double other = std::max(sc.need[(size_t)s], tp.rest);
            const double nd = refined_need(c, s, a, tp, other, fx0, fx1, fy0, fy1, sc.stack);
            codes[(size_t)s * L.plane + f] = code_for(c, std::max(0.0, nd));
        }
    }
}

// The near and window terms of every cell (local_row), threads taking rows
// of coarse cells in turn.
void local_terms(const LocalInput &L, int nthreads, uint8_t *codes)
{
    std::atomic<int> next{0};
    auto worker = [&]() {
        LocalScratch sc;
        sc.colmax.resize((size_t)L.wc);
        sc.winmax.resize((size_t)L.wc);
        sc.need.resize((size_t)L.c->n);
        sc.top.resize((size_t)L.c->n);
        for (;;) {
            int cj = next.fetch_add(1);
            if (cj >= L.hc) break;
            local_row(L, cj, sc, codes);
        }
    };
    std::vector<std::thread> pool;
    for (int t = 0; t < nthreads; ++t) pool.emplace_back(worker);
    for (auto &th : pool) th.join();
}

// ---- the far terms, slice by slice ---------------------------------------

constexpr double SQRT2 = 1.41421356237309515;  // rounded up

// A worker's counts and the arrays of its full DTs (allocated on first use).
struct FarWorker {
    size_t narrowed = 0, queries = 0, full = 0;
    uint64_t rows = 0;
    std::vector<int64_t> dt, dmin;
    std::vector<ddt::Point> ft;
};

// What one slice's sectors read.
struct FarSlice {
    const Ctx *c;
    int k, rw, wc, hc;
    size_t plane;
    double top;                                       // L_k+1
    const ddt::BitLines *bl;                          // B_k
    const std::vector<uint16_t> *k0;                  // apex level per coarse cell
    const std::vector<double> *lvd;                   // levels
    const std::vector<uint8_t> *thr;                  // per cell: codes at or below it cannot narrow
    const double *cot_of, *skip_rise;                 // per code
    const std::vector<std::vector<ddt::Wedge>> *pieces;  // W'_s per sector
    double row_budget;                                // query rows before a full DT
    std::once_flag *prepared_once;                    // the line-traversal tables, built on first need
    std::unique_ptr<ddt::Prepared> *prepared;
};

// Slice k's far terms for sector s: every cell whose code a far term could
// narrow asks its capped DT (or reads the full DT once the queries cost
// more than one); went_full: the sector's previous slice switched to a full
// DT (then this one starts with it; it is updated).
void far_sector(const FarSlice &F, int s, uint8_t *went_full, FarWorker &w, uint8_t *codes)
{
    const Ctx &c = *F.c;
    const int r = c.r;
    const std::vector<uint16_t> &k0 = *F.k0;
    const ddt::CappedQuery<ddt::EuclideanSq> q(*F.bl, (*F.pieces)[(size_t)s], ddt::EuclideanSq());
    uint8_t *cs = &codes[(size_t)s * F.plane];
    size_t nq = 0;
    const int64_t *dtf = nullptr;  // the full DT, once switched to it
    for (size_t f = 0; f < F.plane; ++f) {
        if (cs[f] <= (*F.thr)[f]) continue;
        const uint16_t kf = k0[f];
        if (kf > F.k) continue;
        const uint8_t code = cs[f];
        const double rise = F.top - (*F.lvd)[kf];
        if (rise <= 0.0 || rise < F.skip_rise[code]) continue;
        const double cot = F.cot_of[code];
        // term = (top - a) / (r max(Rw, sqrt(D2) - sqrt2)) > cot needs X =
        // (top - a) / cot > r Rw and D2 < (X / r + sqrt2)^2: only distances
        // below that cap are asked for (exactly)
        int64_t cap = ddt::Inf<int64_t>::value;
        if (cot > 0.0) {
            const double x = rise / cot;
            if (x <= r * (double)F.rw) continue;
            const double lim = x / r + SQRT2, l2 = lim * lim * (1.0 + 1e-12) + 1.0;
            if (l2 < 4.0e18) cap = (int64_t)l2 + 1;
        }
        if (!dtf && (*went_full || F.row_budget <= 0.0 || (double)q.rows_visited() > F.row_budget)) {
            // the queries cost more than a full transform would: finish
            // this slice and sector with one (the same values)
            std::call_once(*F.prepared_once, [&] {
                std::vector<uint8_t> bits(F.plane);
                for (size_t g = 0; g < F.plane; ++g) bits[g] = k0[g] > F.k;
                F.prepared->reset(new ddt::Prepared(F.wc, F.hc, bits.data()));
            });
            ddt::Options opt;
            opt.feature_transform = false;
            const auto &ps = (*F.pieces)[(size_t)s];
            if (ps.empty()) {
                ddt::unconstrained(**F.prepared, ddt::EuclideanSq(), w.dmin, w.ft, opt);
            } else {
                for (size_t p = 0; p < ps.size(); ++p) {
                    ddt::directional(**F.prepared, ps[p], ddt::EuclideanSq(), p == 0 ? w.dmin : w.dt, w.ft, opt);
                    if (p > 0)
                        for (size_t g = 0; g < F.plane; ++g) w.dmin[g] = std::min(w.dmin[g], w.dt[g]);
                }
            }
            dtf = w.dmin.data();
            w.full++;
        }
        int64_t d2;
        if (dtf) {
            d2 = dtf[f];
        } else {
            ++nq;
            d2 = q.query((int)(f % (size_t)F.wc), (int)(f / (size_t)F.wc), cap);
        }
        if (d2 >= cap) continue;
        const double d = std::sqrt((double)d2) * (1.0 - 1e-15) - SQRT2;
        const double term = rise / (r * std::max((double)F.rw, d));
        if (term > cot) {
            const uint8_t nc = code_for(c, term);
            if (nc < cs[f]) {
                cs[f] = nc;
                w.narrowed++;
            }
        }
    }
    *went_full = dtf != nullptr;
    w.queries += nq;
    w.rows += q.rows_visited();
}

// Per code: cot as a double lower bound, for the monotone update (stricter
// than code_for); -INF for a code that is not valid.
void code_cots(const Ctx &c, double cot_of[256])
{
    for (int k = 0; k < 256; ++k) cot_of[k] = c.cot_ok[k] ? ((double)c.cot_q16[k] * (1.0 - 1e-9) - 3.0) / 65536.0 : -INF;
}

// A far term is at most (top - a) / (r Rw): it cannot narrow code k unless
// top - a > r Rw cot(k) (checked exactly in far_sector; a hair lower here).
// Code 0 (degenerate) cannot narrow at all.
void skip_rises(int r, int rw, const double cot_of[256], double skip_rise[256])
{
    for (int k = 0; k < 256; ++k)
        skip_rise[k] = k == 0 ? INF : cot_of[k] > 0.0 ? r * (double)rw * cot_of[k] * (1.0 - 1e-12) : -INF;
}

// Slice k (top L_k+1 = top, K levels): a cell can be narrowed only if its
// code is one whose skip test passes: rise >= skip_rise[code], rise = top -
// its apex level, the same for every sector.  Per cell, (the least such
// code) - 1, 255 when none: every cell the tests accept has a code above
// it, so the sectors' loops first compare one byte (same result; most
// cells stop there; the slice phase at 2048^2, r = 3 measured 5-10% faster).
std::vector<uint8_t> narrow_thresholds(int K, int k, double top, const std::vector<double> &lvd,
                                       const double skip_rise[256], const std::vector<uint16_t> &k0, size_t plane)
{
    std::vector<uint8_t> thr_of_level((size_t)K + 1);
    for (int kf = 0; kf <= K; ++kf) {
        int t = 255;
        const double rise = top - lvd[(size_t)kf];
        if (kf <= k && rise > 0.0)
            for (int code = 1; code < 256; ++code)
                if (!(rise < skip_rise[code])) {
                    t = code - 1;
                    break;
                }
        thr_of_level[(size_t)kf] = (uint8_t)t;
    }
    std::vector<uint8_t> thr(plane);
    for (size_t f = 0; f < plane; ++f) thr[f] = thr_of_level[k0[f]];
    return thr;
}

// Slice F.k's far terms in every sector (far_sector), threads taking
// sectors in turn; went_full per sector, workers per thread.
void far_terms(const FarSlice &F, int nthreads, std::vector<uint8_t> &went_full, std::vector<FarWorker> &workers,
               uint8_t *codes)
{
    const int n = F.c->n;
    std::atomic<int> next{0};
    auto worker = [&](int tid) {
        for (;;) {
            int s = next.fetch_add(1);
            if (s >= n) break;
            far_sector(F, s, &went_full[(size_t)s], workers[(size_t)tid], codes);
        }
    };
    std::vector<std::thread> pool;
    for (int t = 0; t < std::min(nthreads, n); ++t) pool.emplace_back(worker, t);
    for (auto &th : pool) th.join();
}

}  // namespace

void slice_angles(const Ctx &c, const SliceInput &in, uint8_t *codes, SliceStats *st)
{
    const int r = c.r, wc = (c.cx + r - 1) / r, hc = (c.cy + r - 1) / r;
    const size_t plane = (size_t)wc * hc;
    const int rw = in.window;
    if (rw < 1) throw Error("slice builder window must be >= 1 coarse cell");
    const int nthreads = std::max(1, in.threads);
    std::fill(codes, codes + plane * (size_t)c.n, (uint8_t)0);

    // coarse heights (taken over: freed after the window terms)
    std::vector<uint16_t> hcm;
    hcm.swap(*in.coarse_max);
    if (hcm.size() != plane) throw Error("slice builder: coarse heights missing");
    const std::vector<int> &lv = *in.levels;
    const std::vector<uint16_t> &k0 = *in.apex_level;
    // apex of a cell: its level (one table, no per-cell array)
    const std::vector<double> lvd(lv.begin(), lv.end());
    const int K = (int)lv.size() - 1;

    double cot_of[256];
    code_cots(c, cot_of);

    auto t_start = std::chrono::steady_clock::now();
    // ---- near + window terms
    {
        const LocalTables tables = local_tables(c, rw);
        local_terms(LocalInput{&c, &tables, &hcm, &lvd, &k0, rw, wc, hc, plane}, nthreads, codes);
    }

    auto t_local = std::chrono::steady_clock::now();
    hcm = std::vector<uint16_t>();  // not needed below: B_k comes from the apex levels
    // ---- far terms, slice by slice, bottom-up
    const double delta = std::asin(std::min(1.0, SQRT2 / (rw + 1))) + 1e-7;
    std::vector<std::vector<ddt::Wedge>> pieces((size_t)c.n);
    for (int s = 0; s < c.n; ++s) pieces[(size_t)s] = widened_pieces(c, s, delta);
    int kmin = K;
    for (uint16_t v : k0) kmin = std::min(kmin, (int)v);
    std::vector<FarWorker> workers((size_t)nthreads);
    // per sector: did the previous slice switch to a full DT?  Then this one
    // starts with it (the needed cells change slowly from slice to slice).
    std::vector<uint8_t> went_full((size_t)c.n, 0);
    double skip_rise[256];
    skip_rises(r, rw, cot_of, skip_rise);
    // a query row costs ~2 ns, a full DT ~10-20 ns per cell (measured)
    const double row_budget = in.full_dt_rows * (double)plane;
    for (int k = kmin; k < K; ++k) {
        // slice k: B_k = { G : Hc(G) > L_k } = { G : k0(G) > k } (levels increase)
        size_t nfeat = 0;
        const ddt::BitLines bl = ddt::BitLines::from(wc, hc, [&](int x, int y) {
            bool b = k0[(size_t)y * wc + x] > k;
            nfeat += b;
            return b;
        });
        if (in.progress) in.progress((size_t)(k - kmin), (size_t)(K - kmin));
        if (nfeat == 0) break;  // and every higher slice is empty too
        if (st) st->slices++;
        const double top = lv[(size_t)k + 1];
        const std::vector<uint8_t> thr = narrow_thresholds(K, k, top, lvd, skip_rise, k0, plane);
        std::once_flag prepared_once;
        std::unique_ptr<ddt::Prepared> prepared;
        const FarSlice F{&c,  k,      rw,        wc,      hc,         plane,          top,           &bl,
                         &k0, &lvd,   &thr,      cot_of,  skip_rise,  &pieces,        row_budget,    &prepared_once,
                         &prepared};
        far_terms(F, nthreads, went_full, workers, codes);
    }
    if (in.progress) in.progress((size_t)(K - kmin), (size_t)(K - kmin));
    if (st) {
        auto t_end = std::chrono::steady_clock::now();
        for (const FarWorker &w : workers) {
            st->far_narrowed += w.narrowed;
            st->queries += w.queries;
            st->full_dts += w.full;
            st->query_rows += w.rows;
        }
        st->seconds_local = std::chrono::duration<double>(t_local - t_start).count();
        st->seconds_dt = std::chrono::duration<double>(t_end - t_local).count();
    }
}

}  // namespace bld
}  // namespace ct_host
