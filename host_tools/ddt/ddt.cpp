// ddt.cpp -- directional distance transforms by line traversal; the
// algorithm and its exactness argument are in ddt.hpp.
#include "ddt.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <thread>
#include <type_traits>

#include "conetrace.h"
#include "terrain.hpp"  // ct_host::Error

namespace ct_host {
namespace ddt {

void Stats::add(const Stats &o)
{
    pixels += o.pixels;
    lines += o.lines;
    candidates += o.candidates;
    never_valid += o.never_valid;
    activated += o.activated;
    dominated += o.dominated;
    pruned += o.pruned;
    comparisons += o.comparisons;
    walk_steps += o.walk_steps;
}

namespace {

using i128 = __int128;

// |.| of each operand < 2^32: each product < 2^64, exact in 128 bits.
i128 cross(int64_t ux, int64_t uy, int64_t vx, int64_t vy) { return (i128)ux * vy - (i128)uy * vx; }

constexpr int64_t kMaxSide = INT64_C(1) << 20;  // pixels per side (keys stay < 2^53)
constexpr int kLineChunk = 64;                   // lines per work unit
constexpr int kPrefetchRows = 16;                // pass 2 prefetches this many rows ahead

bool int32_range(int64_t v) { return v >= INT32_MIN && v <= INT32_MAX; }

// A piece: wedge of at most 90 degrees inside one closed quadrant.
struct Piece {
    int64_t b1x, b1y, b2x, b2y;
};

// Split the ccw wedge b1 -> b2 (0 < opening <= 180) at the axis directions
// strictly inside it.
std::vector<Piece> split_wedge(const Wedge &w)
{
    if (!int32_range(w.b1x) || !int32_range(w.b1y) || !int32_range(w.b2x) || !int32_range(w.b2y))
        throw Error("ddt: sector boundary outside the int32 range");
    if ((w.b1x == 0 && w.b1y == 0) || (w.b2x == 0 && w.b2y == 0))
        throw Error("ddt: zero sector boundary vector");
    const i128 c = cross(w.b1x, w.b1y, w.b2x, w.b2y);
    const i128 dot = (i128)w.b1x * w.b2x + (i128)w.b1y * w.b2y;
    if (c < 0 || (c == 0 && dot >= 0))
        throw Error("ddt: sector must open counterclockwise from b1 to b2 by more than 0 and at most 180 degrees");
    static const int64_t ax[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    std::vector<std::array<int64_t, 2>> cuts;
    for (const auto &e : ax)
        if (cross(w.b1x, w.b1y, e[0], e[1]) > 0 && cross(e[0], e[1], w.b2x, w.b2y) > 0)
            cuts.push_back({e[0], e[1]});
    // at most two cuts (180 degrees); order them counterclockwise from b1
    if (cuts.size() == 2 && cross(cuts[0][0], cuts[0][1], cuts[1][0], cuts[1][1]) < 0)
        std::swap(cuts[0], cuts[1]);
    std::vector<Piece> out;
    int64_t px = w.b1x, py = w.b1y;
    for (const auto &e : cuts) {
        out.push_back({px, py, e[0], e[1]});
        px = e[0];
        py = e[1];
    }
    out.push_back({px, py, w.b2x, w.b2y});
    return out;
}

// The canonical frame of a piece (see ddt.hpp).  Original -> canonical:
// flip x if fx, flip y if fy, then swap x and y if transpose.
struct Frame {
    int W = 0, H = 0;      // original size
    int Wc = 0, Hc = 0;    // canonical size
    bool fx = false, fy = false, transpose = false;
    int64_t base = 0, stepx = 0, stepy = 0;  // original index of canonical (x', y')
    int dir = 0;                             // pass-1 table for canonical +x'
    int64_t a1 = 1, c1 = 0, a2 = 0, c2 = 1;  // canonical boundaries
};

Frame make_frame(int W, int H, const Piece &p, int force)
{
    Frame f;
    f.W = W;
    f.H = H;
    // a direction strictly inside the piece decides the quadrant
    const int64_t mx = p.b1x + p.b2x, my = p.b1y + p.b2y;
    f.fx = mx < 0;
    f.fy = my < 0;
    const int64_t sx = f.fx ? -1 : 1, sy = f.fy ? -1 : 1;
    int64_t ux = sx * p.b1x, uy = sy * p.b1y, vx = sx * p.b2x, vy = sy * p.b2y;
    if (sx * sy < 0) {  // a reflection reverses the orientation
        std::swap(ux, vx);
        std::swap(uy, vy);
    }
    if (ux < 0 || uy < 0 || vx < 0 || vy < 0 || cross(ux, uy, vx, vy) <= 0)
        throw Error("ddt: internal error: piece not in one quadrant");
    // frame A: as is; frame B: transposed (u' = T v, v' = T u)
    const double inf = std::numeric_limits<double>::infinity();
    const double t1a = uy == 0 ? inf : (double)ux / (double)uy, t2a = (double)vx / (double)vy;
    const double t1b = vx == 0 ? inf : (double)vy / (double)vx, t2b = (double)uy / (double)ux;
    // Frame choice.  Lines with t2 > 1 skip columns; in a transposed frame
    // they also skip memory rows (a measured 2x slowdown at 2048^2), so a
    // transposed frame is only taken with t2 <= 1 or when it is the only one
    // with t2 <= max(1, W'/8).  Among those, a frame whose lines have an
    // integer slope t2 comes first: psi is then constant along a line, so no
    // feature pixel needs a secondary candidate (measured 1.4-1.9x faster on
    // dense cross-sections).  Of two frames with non-integer slopes, the
    // smaller t2 (fewer columns skipped per row: 10-20% fewer instructions on
    // mid and sparse cross-sections, the same on dense ones).  Otherwise the
    // larger t1 - t2 (shorter walks).
    const bool oka = t2a <= std::max(1.0, W / 8.0), okb = t2b <= std::max(1.0, H / 8.0);
    const bool inta = vx % vy == 0, intb = uy % ux == 0 && t2b <= 1.0;
    bool useb;
    if (oka != okb)
        useb = okb;
    else if (oka && inta != intb)
        useb = intb;
    else if (!oka)
        useb = t2b < t2a;
    else if (t2b > 1.0)
        useb = false;
    else if (!inta && !intb)
        useb = t2b < t2a;
    else if ((t1b - t2b) == (t1a - t2a))  // both infinite: a quadrant; rows
        useb = true;                        // of memory as lines (measured faster)
    else
        useb = (t1b - t2b) > (t1a - t2a);
    if (force == 1 || force == 2)
        useb = force == 2;
    f.transpose = useb;
    if (!useb) {
        f.a1 = ux;
        f.c1 = uy;
        f.a2 = vx;
        f.c2 = vy;
    } else {
        f.a1 = vy;
        f.c1 = vx;
        f.a2 = uy;
        f.c2 = ux;
    }
    f.Wc = useb ? H : W;
    f.Hc = useb ? W : H;
    const int64_t x0 = f.fx ? W - 1 : 0, y0 = f.fy ? H - 1 : 0;
    f.base = y0 * (int64_t)W + x0;
    const int64_t ix = f.fx ? -1 : 1, iy = f.fy ? -(int64_t)W : (int64_t)W;
    f.stepx = useb ? iy : ix;
    f.stepy = useb ? ix : iy;
    f.dir = useb ? (f.fy ? 3 : 2) : (f.fx ? 1 : 0);
    return f;
}

// D in canonical coordinates (the transpose swaps the arguments).
template <class D, bool kT>
struct CanonDist {
    const D &d;
    typename D::value_type operator()(int64_t ax, int64_t ay) const { return kT ? d(ay, ax) : d(ax, ay); }
};

// A list entry: a feature of row r at column col with its keys (V1 - c1*k
// and V2 - c2*k, see ddt.hpp).  A feature pixel on the line itself (q0) also
// carries its row's secondary, the first feature after it (column scol, key1
// skey1; kNoKey: none or not needed): the row's candidate for the pixels
// where q0 lies left of the wedge (key2 < psi(Y)); a secondary is always on
// the valid side of the left boundary.
constexpr int64_t kNoKey = std::numeric_limits<int64_t>::max();
struct Cand {
    int32_t r, col, scol;
    int64_t key1, key2, skey1;
};
struct Node {
    Cand c;
    int32_t next;
};

// kCount: keep operation counts (off when no Stats were asked for).
template <class D, bool kT, bool kCount>
class Kernel {
public:
    using V = typename D::value_type;

    // first: the first piece writes every pixel (dt, ft need no prior fill);
    // later pieces keep the minimum.
    Kernel(const Prepared &bm, const Frame &f, const D &dist, V *dt, Point *ft, const Options &opt, bool first)
        : f_(f), dist_{dist}, dt_(dt), ft_(ft), next_(bm.next(f.dir)), rule1_(opt.rule1), rule2_(opt.rule2),
          euclid_(opt.rule2 && opt.euclid), first_(first)
    {
        const int Hc = f.Hc;
        rows_.resize(Hc);
        lb_.resize(Hc);
        // Y*a2 < 2^20 * 2^32; c1*L <= a1*Y + c1 (theta1 < theta2): all < 2^53.
        for (int Y = 0; Y < Hc; ++Y) {
            Row &w = rows_[(size_t)Y];
            w.L = (Y * f.a2 + f.c2 - 1) / f.c2;
            w.off = w.L * f.stepx + (int64_t)Y * f.stepy;
            w.phi = f.c1 * w.L - f.a1 * Y;
            w.psi = f.c2 * w.L - f.a2 * Y;
            w.phimin = Y ? std::min(rows_[(size_t)Y - 1].phimin, w.phi) : w.phi;
            w.psimax = Y ? std::max(rows_[(size_t)Y - 1].psimax, w.psi) : w.psi;
            lb_[(size_t)Y] = w.L < f.Wc ? dist_(w.L, Y) : Inf<V>::value;
        }
        const i128 x12 = (i128)f.a1 * f.c2 - (i128)f.c1 * f.a2;
        tau_ = (double)f.c1 * (double)f.c2 / (double)x12;
        kmax_ = f.Wc - 1;
        kmin_ = -rows_[(size_t)Hc - 1].L;
        sec_ = f.a2 % f.c2 != 0;  // else psi = c2*L(Y) - a2*Y = 0 on every row
    }

    int64_t line_count() const { return kmax_ - kmin_ + 1; }

    // Lines kmax - chunk*kLineChunk ... for chunks tid, tid + nth, ...
    void run(int tid, int nth, Stats &st)
    {
        head_.assign(f_.Hc, -1);
        pool_.resize(2 * (size_t)f_.Hc + 2);
        list_.resize(2 * (size_t)f_.Hc + 2);
        const int64_t nchunks = (line_count() + kLineChunk - 1) / kLineChunk;
        for (int64_t ch = tid; ch < nchunks; ch += nth) {
            const int64_t hi = kmax_ - ch * kLineChunk;
            const int64_t lo = std::max(kmin_, hi - kLineChunk + 1);
            for (int64_t k = hi; k >= lo; --k) {
                if (sec_)
                    line<true>(k, st);
                else
                    line<false>(k, st);
            }
        }
    }

private:
    // Per canonical row Y: L(Y), the memory offset of (L(Y), Y) from the
    // canonical origin, phi(Y), psi(Y), and min phi / max psi over rows
    // 0..Y (the rows still to come on a line, for rule 2).
    struct Row {
        int64_t L, off, phi, psi, phimin, psimax;
    };
    const Frame f_;
    CanonDist<D, kT> dist_;
    V *dt_;
    Point *ft_;
    const int32_t *next_;
    const bool rule1_, rule2_, euclid_, first_;
    std::vector<Row> rows_;
    std::vector<V> lb_;  // lb_[dy] = D(L(dy), dy): no candidate dy rows deeper is nearer (rule 1)
    double tau_ = 0.0;
    int64_t kmax_ = 0, kmin_ = 0;
    bool sec_ = false;  // psi varies along a line (non-integer slope a2/c2): secondaries exist
    // per-thread scratch (one Kernel per thread); a line creates at most two
    // candidates per pixel, so pool and list never exceed 2 * Hc entries
    std::vector<int32_t> head_;
    std::vector<Node> pool_;
    std::vector<Cand> list_;

    static void count(uint64_t &c)
    {
        if (kCount)
            ++c;
    }

    Point to_orig(int64_t cx, int64_t cy) const
    {
        const int64_t xf = f_.transpose ? cy : cx, yf = f_.transpose ? cx : cy;
        Point p;
        p.x = (int32_t)(f_.fx ? f_.W - 1 - xf : xf);
        p.y = (int32_t)(f_.fy ? f_.H - 1 - yf : yf);
        return p;
    }

    // One rasterized line k, bottom to top.  The hot state lives in locals
    // (the list, the pool, the current row's rule-2 thresholds) so that the
    // compiler keeps it in registers across the list's stores.
    template <bool kSec>
    void line(int64_t k, Stats &st)
    {
        const int Wc = f_.Wc, Hc = f_.Hc;
        // the line's rows: 0 <= k + L(Y) <= Wc - 1 (L nondecreasing)
        const auto L_below = [](const Row &w, int64_t v) { return w.L < v; };
        const auto below_L = [](int64_t v, const Row &w) { return v < w.L; };
        const int Ytop = (int)(std::lower_bound(rows_.begin(), rows_.end(), -k, L_below) - rows_.begin());
        const int Ybot =
            (int)(std::upper_bound(rows_.begin(), rows_.end(), (int64_t)(Wc - 1) - k, below_L) - rows_.begin()) - 1;
        if (Ytop > Ybot || Ytop >= Hc)
            return;
        count(st.lines);
        const Row *const rows = rows_.data();
        const V *const lb = lb_.data();
        const int32_t *const nx = next_;
        Cand *const list = list_.data();
        Node *const pool = pool_.data();
        int32_t *const head = head_.data();
        V *const dt = dt_;
        Point *const ft = ft_;
        const bool rule1 = rule1_, rule2 = rule2_, first = first_;
        const int64_t c1 = f_.c1, c2 = f_.c2, stepx = f_.stepx, base = f_.base + k * f_.stepx;
        const double tau = tau_;
        const bool prune = std::is_same<D, EuclideanSq>::value && euclid_;
        const int64_t xtop = k + rows[Ytop].L, a2 = f_.a2;
        size_t ln = 0, pn = 0;  // used entries of list and pool
        int64_t pmn = 0, psx = 0;  // phimin, psimax of the current row

        // Rule 2.  E covers one part of an older entry A (column ca, keys ka,
        // kb; kb = kNoKey for a secondary) when, at every row still to come
        // where that part is A's candidate and valid, E's candidate is valid
        // and no farther right: E.col <= ca, E.key1 <= max(ka, pmn) (so E is
        // valid on the right wherever the part is), and either E.key2 >=
        // min(kb, psx) (E stays valid on the left there) or E's secondary
        // qualifies too (it takes over where E's q0 falls out on the left).
        // The rows still to come are <= Y: pmn <= phi and psx >= psi there.
        auto covers_part = [&](const Cand &e, int64_t ca, int64_t ka, int64_t kb) __attribute__((always_inline)) {
            const int64_t t1 = std::max(ka, pmn);
            return e.col <= ca && e.key1 <= t1 &&
                   (e.key2 >= std::min(kb, psx) || (kSec && e.scol <= ca && e.skey1 <= t1));
        };
        auto covers = [&](const Cand &e, const Cand &a) __attribute__((always_inline)) {
            return covers_part(e, a.col, a.key1, a.key2) &&
                   (!kSec || a.skey1 == kNoKey || covers_part(e, a.scol, a.skey1, kNoKey));
        };
        // Whether (ca, ra) is no farther than (cb, rb) from every pixel
        // (x, Y') still to come on the line, Ytop <= Y' <= Y (the squared
        // distances differ by a function linear in Y', see ddt.hpp).
        auto le_rest = [&](int64_t Y, int64_t ca, int64_t ra, int64_t cb, int64_t rb) __attribute__((always_inline)) {
            if (!kSec)
                return dist_(ca - xtop, ra - Ytop) <= dist_(cb - xtop, rb - Ytop);
            const int64_t gc = ca - cb, gr = ra - rb;
            const int64_t sc = c2 * (ca + cb) - 2 * (gc < 0 ? c2 : 0), sr = ra + rb;  // < 2^53
            const auto at = [&](int64_t y) __attribute__((always_inline)) {
                return (i128)gc * (sc - 2 * (c2 * k + y * a2)) + (i128)(c2 * gr) * (sr - 2 * y) <= 0;
            };
            return at(Y) && at(Ytop);
        };
        // The Euclidean pruning (ddt.hpp): entry a is valid at every row
        // still to come (key1 <= pmn) with q0 as its candidate there (key2 >=
        // psx), its candidate is no farther than b's at P_Y (da <= db), and
        // no farther than b's q0 (or primary; b's secondary, in the same row
        // further right, is farther still) at every pixel still to come.
        auto beats = [&](int64_t Y, const Cand &a, const Cand &b, V da, V db) __attribute__((always_inline)) {
            if (!(da <= db) || a.key1 > pmn || (kSec && a.key2 < psx))
                return false;
            return le_rest(Y, a.col, a.r, b.col, b.r);
        };
        // The run of entries just below position i that a covers (rule 2):
        // returns where it starts.
        auto covered_run = [&](const Cand &a, size_t i) __attribute__((always_inline)) {
            size_t j = i;
            while (rule2 && j > 0) {
                count(st.comparisons);
                if (!covers(a, list[j - 1]))
                    break;
                --j;
                count(st.dominated);
            }
            return j;
        };
        // Insert a into the row-sorted list (top = back = newest row), rule 2.
        auto insert = [&](const Cand &a) __attribute__((always_inline)) {
            size_t i = ln;
            if (rule2) {
                while (i > 0 && list[i - 1].r <= a.r) {  // newer (or same row): may dominate a
                    count(st.comparisons);
                    if (covers(list[i - 1], a)) {
                        count(st.dominated);
                        return;
                    }
                    --i;
                }
            } else {
                while (i > 0 && list[i - 1].r < a.r)
                    --i;
            }
            count(st.activated);
            const size_t j = covered_run(a, i);  // older entries a dominates
            if (i == ln) {  // the usual case: a is the newest
                list[j] = a;
                ln = j + 1;
            } else if (j < i) {  // replace the dominated run [j, i) by a
                list[j] = a;
                std::copy(list + i, list + ln, list + j + 1);
                ln = ln - (i - j) + 1;
            } else {
                std::copy_backward(list + i, list + ln, list + ln + 1);
                list[i] = a;
                ++ln;
            }
        };

        // A candidate of row Y (its own row) at column col, h = col - col(Y).
        auto create = [&](int Y, const Row &w, int64_t col, int64_t h) __attribute__((always_inline)) {
            const Cand c{Y, (int32_t)col, (int32_t)col, w.phi + c1 * h, w.psi + c2 * h, kNoKey};
            count(st.candidates);
            // h <= 1 (the feature next to the line): inserting it at once,
            // before it is valid, is exact too (the scan checks validity) and
            // measured cheaper than a walk and an activation for these.
            if (!rule1 || h <= 1) {
                insert(c);
                return;
            }
            // Activation row Y1: the first row going up where key1 <= phi.  Valid
            // at Y' implies Y - Y' > (h - 1) * tau (ddt.hpp), so the walk starts
            // from Y - floor((h - 1) * tau), safe for rounding errors below 1.
            // (Activating at that bound without the walk is also exact -- queries
            // check validity -- but measured no faster: more invalid entries.)
            int64_t Y1 = Y;
            if (c1 != 0) {
                const double est = (double)(h - 1) * tau;  // >= 0: truncation is floor
                if (est > (double)(Y - Ytop) + 1.0) {
                    count(st.never_valid);
                    return;
                }
                Y1 = Y - (int64_t)est;
                while (Y1 >= Ytop && c.key1 > rows[Y1].phi) {
                    --Y1;
                    count(st.walk_steps);
                }
            }
            if (Y1 < Ytop) {
                count(st.never_valid);
                return;
            }
            if (Y1 == Y) {
                insert(c);
                return;
            }
            pool[pn] = Node{c, head[Y1]};
            head[Y1] = (int32_t)pn++;
        };

        for (int Y = Ybot; Y >= Ytop; --Y) {
            const Row &w = rows[Y];
            pmn = w.phimin;
            psx = w.psimax;
            const int64_t col = k + w.L;
            const int64_t idx = base + w.off;
            // a line steps through memory by a row per pixel: ask for the
            // pixel kPrefetchRows further up now (measured at 2048^2: 15 -> 12
            // ns per pixel on dense cross-sections; no change at 403 x 344)
            if (Y - kPrefetchRows >= Ytop) {
                const int64_t ahead = base + rows[Y - kPrefetchRows].off;
                __builtin_prefetch(nx + ahead);
                __builtin_prefetch(dt + ahead, 1);
                if (ft)
                    __builtin_prefetch(ft + ahead, 1);
            }
            const int32_t d0 = nx[idx];
            const bool feat = d0 == 0;
            count(st.pixels);
            // candidates of row Y
            if (feat) {
                // q0 = (Y, col(Y)) and its row's secondary, one entry.  It is
                // newer than every entry (their rows are > Y) and no farther
                // right (their columns are >= col(r) >= col(Y)), so only the
                // older run it covers goes.  The secondary is not needed when
                // q0 stays on the left side for all rows to come (then the
                // left start of row Y is col(Y) for every pixel above).
                count(st.candidates);
                count(st.activated);
                Cand q{Y, (int32_t)col, (int32_t)col, w.phi, w.psi, kNoKey};
                if (kSec && col + 1 < Wc && !(rule2 && w.psi >= w.psimax)) {
                    const int32_t d1 = nx[idx + stepx];
                    if (d1 < Prepared::kNone) {
                        count(st.candidates);
                        q.scol = (int32_t)(col + 1 + d1);
                        q.skey1 = w.phi + c1 * (1 + d1);
                    }
                }
                const size_t j = covered_run(q, ln);
                list[j] = q;
                ln = j + 1;
            } else if (d0 < Prepared::kNone) {
                create(Y, w, col + d0, d0);
            }
            // activations due at this row
            for (int32_t n = head[Y]; n >= 0; n = pool[(size_t)n].next)
                insert(pool[(size_t)n].c);
            head[Y] = -1;
            // answer P_Y
            V best = first ? Inf<V>::value : dt[idx];
            int64_t bc = -1, br = -1;
            if (feat) {
                const V d = dist_(0, 0);
                if (d < best) {
                    best = d;
                    bc = col;
                    br = Y;
                }
            } else {
                const int64_t phiY = w.phi, psiY = w.psi;
                size_t jb = 0, jdel = ln;  // the best entry; the lowest entry marked for removal
                for (size_t j = ln; j-- > 0;) {
                    Cand &e = list[j];
                    const int dy = e.r - Y;
                    if (rule1 && !(lb[dy] < best))
                        break;
                    count(st.comparisons);
                    // q0 where it is on the valid side of the left boundary,
                    // else the secondary (if any); either valid on the right
                    const bool left = !kSec || e.key2 >= psiY;
                    const bool valid = (left ? e.key1 : e.skey1) <= phiY;
                    if (!valid && !(prune && bc >= 0))
                        continue;
                    const int64_t cc = left ? e.col : e.scol;
                    const V d = dist_(cc - col, dy);
                    if (valid && d < best) {
                        if (prune && bc >= 0 && beats(Y, e, list[jb], d, best)) {
                            list[jb].r = -1;  // the former best: e is nearer for the rest of the line
                            jdel = std::min(jdel, jb);
                            count(st.pruned);
                        }
                        best = d;
                        bc = cc;
                        br = e.r;
                        jb = j;
                    } else if (prune && bc >= 0 && beats(Y, list[jb], e, best, d)) {
                        e.r = -1;
                        jdel = j;
                        count(st.pruned);
                    }
                }
                if (prune && jdel < ln) {
                    size_t o = jdel;
                    for (size_t j = jdel; j < ln; ++j)
                        if (list[j].r >= 0) list[o++] = list[j];
                    ln = o;
                }
            }
            if (bc >= 0) {
                dt[idx] = best;
                if (ft) ft[idx] = to_orig(bc, br);
            } else if (first) {
                dt[idx] = Inf<V>::value;
                if (ft) ft[idx] = Point();
            }
        }
    }
};

int thread_count(const Options &opt)
{
    int n = opt.threads > 0 ? opt.threads : (int)std::max(1u, std::thread::hardware_concurrency());
    return std::min(n, 64);
}

template <class D, bool kT, bool kCount>
void run_frame(const Prepared &bm, const Frame &f, const D &dist, typename D::value_type *dt, Point *ft,
               const Options &opt, bool first, Stats *stats)
{
    // one heap object per thread: no false sharing of scratch or counters
    const int nth = thread_count(opt);
    std::vector<std::unique_ptr<Kernel<D, kT, kCount>>> ks;
    std::vector<std::unique_ptr<Stats>> st;
    ks.emplace_back(new Kernel<D, kT, kCount>(bm, f, dist, dt, ft, opt, first));
    st.emplace_back(new Stats());
    const int64_t nchunks = (ks[0]->line_count() + kLineChunk - 1) / kLineChunk;
    const int used = (int)std::min<int64_t>(nth, nchunks);
    for (int t = 1; t < used; ++t) {
        ks.emplace_back(new Kernel<D, kT, kCount>(bm, f, dist, dt, ft, opt, first));
        st.emplace_back(new Stats());
    }
    if (used <= 1) {
        ks[0]->run(0, 1, *st[0]);
    } else {
        std::vector<std::thread> pool;
        for (int t = 1; t < used; ++t)
            pool.emplace_back([&, t] { ks[(size_t)t]->run(t, used, *st[(size_t)t]); });
        ks[0]->run(0, used, *st[0]);
        for (auto &th : pool)
            th.join();
    }
    if (stats)
        for (const auto &s : st)
            stats->add(*s);
}

// The kernel for frame f: a transposed one only when D is not symmetric
// (a symmetric D's transposed frame computes the same values untransposed).
template <class D, bool kCount>
void run_frame_for(const Prepared &bm, const Frame &f, const D &dist, typename D::value_type *dt, Point *ft,
                   const Options &opt, bool first, Stats *stats)
{
    if constexpr (!D::symmetric) {
        if (f.transpose) {
            run_frame<D, true, kCount>(bm, f, dist, dt, ft, opt, first, stats);
            return;
        }
    }
    run_frame<D, false, kCount>(bm, f, dist, dt, ft, opt, first, stats);
}

template <class D>
void run_pieces(const Prepared &bm, const std::vector<Piece> &pieces, const D &dist,
                std::vector<typename D::value_type> &dt, std::vector<Point> &ft, const Options &opt,
                Stats *stats)
{
    if (opt.frame < 0 || opt.frame > 2)
        throw Error("ddt: Options::frame must be 0 (automatic), 1 or 2");
    const size_t n = (size_t)bm.width() * (size_t)bm.height();
    dt.resize(n);  // the first piece writes every pixel
    Point *ftp = nullptr;
    if (opt.feature_transform) {
        ft.resize(n);
        ftp = ft.data();
    } else {
        ft.clear();
    }
    bool first = true;
    for (const Piece &p : pieces) {
        const Frame f = make_frame(bm.width(), bm.height(), p, opt.frame);
        if (stats)
            run_frame_for<D, true>(bm, f, dist, dt.data(), ftp, opt, first, stats);
        else
            run_frame_for<D, false>(bm, f, dist, dt.data(), ftp, opt, first, stats);
        first = false;
    }
}

}  // namespace

Wedge sector_wedge(uint32_t sectors, uint32_t s)
{
    if (sectors < 1u || sectors > CT_MAX_SECTORS || s >= sectors)
        throw Error("ddt: sector " + std::to_string(s) + " of " + std::to_string(sectors) + " out of range");
    int32_t x0, y0, x1, y1;
    if (ct_sector_boundary(sectors, s, &x0, &y0) != CT_OK || ct_sector_boundary(sectors, s + 1u, &x1, &y1) != CT_OK)
        throw Error("ddt: ct_sector_boundary failed");
    Wedge w;
    w.b1x = x0;
    w.b1y = y0;
    w.b2x = x1;
    w.b2y = y1;
    return w;
}

Prepared::Prepared(int width, int height, const uint8_t *bits) : w_(width), h_(height)
{
    if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide ||
        (int64_t)width * height >= (INT64_C(1) << 31) || bits == nullptr)
        throw Error("ddt: bitmap size out of range");
    const size_t W = (size_t)width, H = (size_t)height;
    for (auto &v : next_)
        v.resize(W * H);
    for (size_t y = 0; y < H; ++y) {
        const uint8_t *row = bits + y * W;
        int32_t *r0 = next_[0].data() + y * W, *r1 = next_[1].data() + y * W;
        int32_t n = kNone;
        for (size_t x = W; x-- > 0;) {
            n = row[x] ? 0 : (n < kNone ? n + 1 : kNone);
            r0[x] = n;
        }
        n = kNone;
        for (size_t x = 0; x < W; ++x) {
            n = row[x] ? 0 : (n < kNone ? n + 1 : kNone);
            r1[x] = n;
        }
    }
    for (size_t y = H; y-- > 0;) {  // +y: from the bottom row up
        const uint8_t *row = bits + y * W;
        int32_t *r = next_[2].data() + y * W;
        const int32_t *below = y + 1 < H ? r + W : nullptr;
        for (size_t x = 0; x < W; ++x)
            r[x] = row[x] ? 0 : (below && below[x] < kNone ? below[x] + 1 : kNone);
    }
    for (size_t y = 0; y < H; ++y) {  // -y: from the top row down
        const uint8_t *row = bits + y * W;
        int32_t *r = next_[3].data() + y * W;
        const int32_t *above = y > 0 ? r - W : nullptr;
        for (size_t x = 0; x < W; ++x)
            r[x] = row[x] ? 0 : (above && above[x] < kNone ? above[x] + 1 : kNone);
    }
}

template <class D>
void directional(const Prepared &bm, const Wedge &w, const D &dist, std::vector<typename D::value_type> &dt,
                 std::vector<Point> &ft, const Options &opt, Stats *stats)
{
    run_pieces(bm, split_wedge(w), dist, dt, ft, opt, stats);
}

template <class D>
void directional(const Prepared &bm, uint32_t sectors, uint32_t s, const D &dist,
                 std::vector<typename D::value_type> &dt, std::vector<Point> &ft, const Options &opt,
                 Stats *stats)
{
    const Wedge w = sector_wedge(sectors, s);
    if (sectors == 1u)  // the whole plane (ct_in_wedge: always inside)
        unconstrained(bm, dist, dt, ft, opt, stats);
    else
        directional(bm, w, dist, dt, ft, opt, stats);
}

template <class D>
void unconstrained(const Prepared &bm, const D &dist, std::vector<typename D::value_type> &dt,
                   std::vector<Point> &ft, const Options &opt, Stats *stats)
{
    const std::vector<Piece> quadrants = {{1, 0, 0, 1}, {0, 1, -1, 0}, {-1, 0, 0, -1}, {0, -1, 1, 0}};
    run_pieces(bm, quadrants, dist, dt, ft, opt, stats);
}

// ------------------------------------------------------------ capped queries

void BitLines::alloc(int width, int height)
{
    if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
        throw Error("ddt: bitmap size out of range");
    w_ = width;
    h_ = height;
    const int64_t len[2] = {width, height}, nl[2] = {height, width};
    for (int o = 0; o < 2; ++o) {
        Lines &L = l_[o];
        L.len = len[o];
        L.wpl = (len[o] + 63) / 64;
        L.w.assign((size_t)(nl[o] * L.wpl), 0);
    }
}

void BitLines::set(int x, int y)
{
    l_[0].w[(size_t)(y * l_[0].wpl + (x >> 6))] |= UINT64_C(1) << (x & 63);
    l_[1].w[(size_t)(x * l_[1].wpl + (y >> 6))] |= UINT64_C(1) << (y & 63);
}

void BitLines::finish()
{
    for (Lines &L : l_) {
        const size_t n = L.w.size(), wpl = (size_t)L.wpl;
        L.nz_up.assign(n, -1);
        L.nz_down.assign(n, -1);
        for (size_t base = 0; base < n; base += wpl) {
            int32_t last = -1;
            for (size_t k = wpl; k-- > 0;) {
                if (L.w[base + k]) last = (int32_t)k;
                L.nz_up[base + k] = last;
            }
            last = -1;
            for (size_t k = 0; k < wpl; ++k) {
                if (L.w[base + k]) last = (int32_t)k;
                L.nz_down[base + k] = last;
            }
        }
    }
}

BitLines::BitLines(int width, int height, const uint8_t *bits)
{
    if (bits == nullptr) throw Error("ddt: null bitmap");
    alloc(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            if (bits[(size_t)y * (size_t)width + (size_t)x]) set(x, y);
    finish();
}

int64_t BitLines::next(int o, int64_t l, int64_t p, bool fwd) const
{
    const Lines &L = l_[o];
    const size_t base = (size_t)(l * L.wpl);
    const uint64_t *row = &L.w[base];
    const int64_t w = p >> 6;
    const int b = (int)(p & 63);
    if (fwd) {
        const uint64_t m = row[w] & (~UINT64_C(0) << b);
        if (m) return (w << 6) + __builtin_ctzll(m);
        if (w + 1 >= L.wpl) return -1;
        const int32_t w2 = L.nz_up[base + (size_t)w + 1];
        return w2 < 0 ? -1 : ((int64_t)w2 << 6) + __builtin_ctzll(row[w2]);
    }
    const uint64_t m = row[w] & (~UINT64_C(0) >> (63 - b));
    if (m) return (w << 6) + 63 - __builtin_clzll(m);
    if (w == 0) return -1;
    const int32_t w2 = L.nz_down[base + (size_t)w - 1];
    return w2 < 0 ? -1 : ((int64_t)w2 << 6) + 63 - __builtin_clzll(row[w2]);
}

template <class D>
CappedQuery<D>::CappedQuery(const BitLines &bl, const std::vector<Wedge> &wedges, const D &dist)
    : bl_(bl), dist_(dist)
{
    std::vector<Piece> pieces;
    if (wedges.empty()) {
        static const Piece quadrants[4] = {{1, 0, 0, 1}, {0, 1, -1, 0}, {-1, 0, 0, -1}, {0, -1, 1, 0}};
        for (const Piece &p : quadrants) pieces.push_back(p);
    } else {
        for (const Wedge &w : wedges)
            for (const Piece &p : split_wedge(w)) pieces.push_back(p);
    }
    const int W = bl.width(), H = bl.height();
    for (const Piece &p : pieces) {
        // canonical first-quadrant boundaries u (near +x), v (near +y), as
        // in make_frame; then the frame whose far boundary is nearer the
        // scan axis (larger t2 = a2 / c2: fewer rows before rule 1 stops)
        const int64_t mx = p.b1x + p.b2x, my = p.b1y + p.b2y;
        QFrame q;
        q.fx = mx < 0;
        q.fy = my < 0;
        const int64_t sx = q.fx ? -1 : 1, sy = q.fy ? -1 : 1;
        int64_t ux = sx * p.b1x, uy = sy * p.b1y, vx = sx * p.b2x, vy = sy * p.b2y;
        if (sx * sy < 0) {
            std::swap(ux, vx);
            std::swap(uy, vy);
        }
        if (ux < 0 || uy < 0 || vx < 0 || vy < 0 || cross(ux, uy, vx, vy) <= 0)
            throw Error("ddt: internal error: piece not in one quadrant");
        // frame A: a2/c2 = vx/vy; frame B (transposed): uy/ux
        q.transpose = (i128)uy * vy > (i128)vx * ux;
        int64_t a1, c1, a2, c2;
        if (!q.transpose) {
            a1 = ux, c1 = uy, a2 = vx, c2 = vy;
        } else {
            a1 = vy, c1 = vx, a2 = uy, c2 = ux;
        }
        const int64_t Wc = q.transpose ? H : W, Hc = q.transpose ? W : H;
        for (int64_t j = 0; j < Hc; ++j) {
            const int64_t L = (j * a2 + c2 - 1) / c2;  // < 2^20 * 2^31
            if (L >= Wc) break;                          // and every deeper row
            q.L.push_back(L);
            q.R.push_back(c1 == 0 ? INT64_MAX : j * a1 / c1);
            q.lb.push_back(q.transpose ? dist_(j, L) : dist_(L, j));
        }
        frames_.push_back(std::move(q));
    }
}

template <class D>
typename D::value_type CappedQuery<D>::query(int x, int y, V cap) const
{
    const int64_t W = bl_.width(), H = bl_.height();
    V best = cap;
    uint64_t rows = 0;
    for (const QFrame &q : frames_) {
        const int64_t xf = q.fx ? W - 1 - x : x, yf = q.fy ? H - 1 - y : y;
        const int64_t xc = q.transpose ? yf : xf, yc = q.transpose ? xf : yf;
        const int64_t Wc = q.transpose ? H : W, Hc = q.transpose ? W : H;
        const int64_t jmax = std::min<int64_t>((int64_t)q.L.size(), Hc - yc);
        // the line for canonical row yc + j, positions in canonical x
        const int o = q.transpose ? 1 : 0;
        const bool flip_pos = q.transpose ? q.fy : q.fx, flip_line = q.transpose ? q.fx : q.fy;
        const int64_t lenl = q.transpose ? W : H, lenp = Wc;
        for (int64_t j = 0; j < jmax; ++j) {
            if (!(q.lb[(size_t)j] < best)) break;
            const int64_t lo = xc + q.L[(size_t)j];
            if (lo >= Wc) break;  // L nondecreasing: no deeper row either
            ++rows;
            const int64_t hi = q.R[(size_t)j] == INT64_MAX ? Wc - 1 : std::min(Wc - 1, xc + q.R[(size_t)j]);
            const int64_t line = flip_line ? lenl - 1 - (yc + j) : yc + j;
            const int64_t f = bl_.next(o, line, flip_pos ? lenp - 1 - lo : lo, !flip_pos);
            if (f < 0) continue;
            const int64_t pc = flip_pos ? lenp - 1 - f : f;
            if (pc > hi) continue;
            const V d = q.transpose ? dist_(j, pc - xc) : dist_(pc - xc, j);
            if (d < best) best = d;
        }
    }
    rows_ += rows;
    return best;
}

#define CT_DDT_INSTANTIATE(D)                                                                              \
    template void directional<D>(const Prepared &, const Wedge &, const D &,                              \
                                 std::vector<D::value_type> &, std::vector<Point> &, const Options &,     \
                                 Stats *);                                                                 \
    template void directional<D>(const Prepared &, uint32_t, uint32_t, const D &,                         \
                                 std::vector<D::value_type> &, std::vector<Point> &, const Options &,     \
                                 Stats *);                                                                 \
    template void unconstrained<D>(const Prepared &, const D &, std::vector<D::value_type> &,             \
                                   std::vector<Point> &, const Options &, Stats *);              \
    template class CappedQuery<D>;
CT_DDT_INSTANTIATE(EuclideanSq)
CT_DDT_INSTANTIATE(CityBlock)
CT_DDT_INSTANTIATE(Chessboard)
CT_DDT_INSTANTIATE(ChamferInt)
CT_DDT_INSTANTIATE(ChamferReal)
CT_DDT_INSTANTIATE(TableDistance)
#undef CT_DDT_INSTANTIATE

}  // namespace ddt
}  // namespace ct_host
