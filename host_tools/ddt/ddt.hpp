// ddt.hpp -- directional distance transforms of bitmaps (host side, C++17).
//
// Paglieroni 1997, "Directional Distance Transforms and Height Field
// Preprocessing for Efficient Ray Tracing" (GMIP 59(4)), section 3: the
// distance from every pixel to the nearest feature pixel that lies inside a
// sector (a wedge of directions) emanating from the pixel, computed by two
// passes of line traversal.  The rules below are our own design in the
// paper's spirit (we did not have the paper's text at hand); they are exact,
// and the argument is written out at the end of this comment.
//
// ---------------------------------------------------------------- definitions
// Bitmap: W x H, row-major, nonzero = feature pixel.  Pixel (x, y): x is the
// column (east), y the row (south).  Offsets d = q - p = (dx, dy).
//
// Sector (Wedge): two integer boundary vectors b1 = (a1, c1), b2 = (a2, c2)
// (int32, e.g. |b| ~ 2^30 from ct_sector_boundary).  The sector is the
// closed wedge swept counterclockwise in (x, y) coordinates from b1 to b2,
// i.e. by increasing grid azimuth from +x towards +y (clockwise on a
// north-up map), and
//     d is in the sector  <=>  cross(b1, d) >= 0  and  cross(d, b2) >= 0,
// cross(u, v) = u.x * v.y - u.y * v.x, evaluated exactly (128-bit where two
// boundary components meet, 64-bit with |d| < 2^31 otherwise).  This is the
// flight library's convention: sector s of N is the closed wedge between
// b_s = ct_sector_boundary(N, s) and b_{s+1} (ct_in_wedge).  The offset
// (0, 0) -- the feature pixel itself -- is in every sector.
// Openings: 0 < angle <= 180 degrees for an explicit Wedge; a wedge is split
// internally at the axis directions strictly inside it into pieces of at most
// 90 degrees lying in one closed quadrant, and the result is the minimum over
// the pieces (the closed pieces cover the closed wedge exactly).  For
// sector_wedge(N, s) with N >= 4 every sector is <= 90 degrees; N = 2 and 3
// give 180 and 120 degree sectors (unions of pieces); N = 1 is the whole
// plane and equals unconstrained().
//
// Directional DT at p: min over feature pixels q with q - p in the sector of
// D(q - p); directional FT: one such q achieving the minimum (which one, on
// ties, is unspecified).  No feature in the sector: DT = Inf<V>::value
// (int64 max or +infinity) and FT = (-1, -1).
//
// Distances D(|dx|, |dy|): any function nondecreasing in |dx| and in |dy|
// (such a D depends on |dx| and |dy| only).  Provided functors:
//   EuclideanSq    dx^2 + dy^2 (int64, exact; the Euclidean DT is its root)
//   CityBlock      |dx| + |dy|
//   Chessboard     max(|dx|, |dy|)
//   ChamferInt     w_max * max + w_min * min, int64 weights >= 0
//   ChamferReal    the same with double weights >= 0 (e.g. 1, sqrt(2) - 1)
//   TableDistance  an arbitrary monotone table D[|dy|][|dx|] (tests)
// Chamfer is defined as w_max * max(|dx|,|dy|) + w_min * min(|dx|,|dy|).
// The classic local-step form a * (max - min) + b * min (a = axial step,
// b = diagonal step, "3-4" chamfer: a = 3, b = 4) is chamfer_from_steps(a, b)
// = {w_max = a, w_min = b - a}; (1, sqrt 2) gives {1, sqrt(2) - 1}.
// Values are compared exactly: the traversal calls the same functor on the
// same (|dx|, |dy|) as any brute force would, so doubles are bitwise equal
// (fl(w0*M) + fl(w1*m) is monotone in M and m for w0, w1 >= 0).
//
// ---------------------------------------------------------------- algorithm
// Per piece (<= 90 degrees, one closed quadrant) the bitmap is viewed in a
// canonical frame -- a flip of x and/or y and optionally a transpose, all
// lattice symmetries that keep |dx|, |dy| (the transpose swaps D's
// arguments) -- in which the wedge lies in the closed first quadrant:
//   b1 = (a1, c1) nearer +x, b2 = (a2, c2) nearer +y, a1 > 0, c2 > 0,
//   X12 = a1*c2 - c1*a2 > 0;  t1 = a1/c1 (inf if c1 = 0) > t2 = a2/c2 >= 0.
// Of the two frames (with and without transpose), a transposed frame must
// have t2 <= 1 (lines stepping over several memory rows per pixel ran 2x
// slower at 2048^2), and a frame t2 <= max(1, W'/8) (not too many short
// lines).  Among those, one whose t2 is an integer comes first: psi below is
// then constant along a line and no feature needs a secondary candidate (16
// of the 24 sectors of N = 24; measured about twice as fast as the other 8
// on dense cross-sections); of two non-integer slopes, the smaller t2 (10-20%
// fewer instructions on mid and sparse cross-sections); otherwise the larger
// t1 - t2 (shorter activation walks).
// At depth j >= 0 (row y + j) the wedge of p = (x, y) is the row interval
//   x + L(j) <= col <= x + R(j),  L(j) = ceil(j*a2/c2), R(j) = floor(j*a1/c1),
// and in exact integers: left  V2(q) = c2*col - a2*row >= V2(p),
//                        right V1(q) = c1*col - a1*row <= V1(p).
//
// Pass 1 runs along the lattice rows of the canonical frame (the lattice
// direction bounding the quadrant next to b1 -- our "nearest rational
// direction" for theta1: exact, no rasterization error): for every pixel the
// first feature at or after it along +x (one shared table per bitmap and
// direction; the four directions serve all sectors).  The first-pass rule:
// along a row only the first feature ahead is carried; a feature found on
// the row is propagated backwards until the next feature, which is nearer
// for every pixel further along (D is nondecreasing in |dx|).
//
// Pass 2 runs along every rasterized line at orientation theta2 (the digital
// line col(Y) = k + L(Y), one pixel per row, line index k = x - L(y); every
// pixel lies on exactly one line), bottom to top.  On line k,
//   V1(P_Y) = c1*k + phi(Y),  phi(Y) = c1*L(Y) - a1*Y,
//   V2(P_Y) = c2*k + psi(Y),  psi(Y) = c2*L(Y) - a2*Y in [0, c2),
// so the exact left start of p's wedge on any row r is col(r) or col(r) + 1:
// it is col(r) iff psi(r) >= psi(y).  Row r therefore offers p at most two
// possible nearest features: the first feature at or after col(r) (primary;
// called q0 when col(r) itself is a feature) and, when col(r) is a feature,
// the first one after it (secondary).  With keys
//   key1 = phi(r) + c1*h,  key2 = psi(r) + c2*h   (h = col - col(r)),
// a feature is in the sector of P_Y iff key1 <= phi(Y) and key2 >= psi(Y);
// candidates with h >= 1 have key2 >= c2 > psi(Y): always valid on the left.
// A primary with h >= 1 becomes a list entry of its own; q0 and its row's
// secondary share one entry, whose candidate for P_Y is q0 where key2(q0) >=
// psi(Y) and the secondary elsewhere -- exactly the row's left start.
// phi drifts up by X12/c2 per row with a jitter below c1; a candidate becomes
// valid (enters through the theta1 side) at its activation row: the first
// row going up where key1 <= phi, found by a short walk (at most 2*tau + 2
// rows, tau = c1*c2/X12 = 1/(t1 - t2)) from a bound.  Entries are kept in a
// list sorted by row, newest on top.  At each pixel the list is scanned from
// the top; every entry's candidate is checked for validity (the jitter can
// move one back out) and the nearest valid one wins.
//
// Rule 1 (propagation): a primary with h >= 2 waits until its activation row
//   and is dropped if that row lies above the line's top (it can never be in
//   the sector of a pixel further along the line); a primary with h = 1
//   (next to the line) and the (q0, secondary) entries enter at once, which
//   measured cheaper than walking for them (the scan checks validity anyway).  The scan stops at the first depth dy with
//   D(L(dy), dy) >= best (no deeper candidate can be nearer).
// Rule 2 (dominance): an entry B is dropped once a newer entry A (row(A) <=
//   row(B)) covers it: at every pixel further along the line where B's
//   candidate is valid, A's is valid and lies in a column no greater.  For
//   single candidates: col(A) <= col(B), key1(A) <= max(key1(B), pmn) and
//   key2(A) >= min(key2(B), psx), where pmn = min of phi and psx = max of
//   psi over the rows still to come.  With pairs, each part of B (q0, and its
//   secondary with key2 taken as infinite -- it is used only where q0 falls
//   out on the left) must be covered so by A's q0, or, where A's q0 may fall
//   out on the left (key2(A) < min(key2(part), psx)), by A's secondary as well.
// Euclidean pruning (EuclideanSq only, with rule 2; Options::euclid): rule 2
//   keeps B while A's column is greater, although for the Euclidean distance
//   A may stay nearer for the whole rest of the line.  During the scan at
//   P_Y, with A the best entry so far and B another one met (either order):
//   B is dropped when A is valid at every row still to come with q0 as its
//   candidate (key1(A) <= pmn, and key2(A) >= psx if psi varies), A's
//   candidate is no farther than B's at P_Y, and A's q0 is no farther than
//   B's q0 (or primary) from every pixel (x, Y') still to come on the line,
//   Ytop <= Y' <= Y.  B's secondary, used where B's q0 falls out on the left,
//   lies in the same row further right, so it is farther still.  The squared
//   distances differ by  gc*(cA + cB - 2x) + gr*(rA + rB - 2Y')  (gc = cA -
//   cB, gr = rA - rB): linear in Y' when x = k + L(Y') is (integer slope
//   t2), so the ends Y and Ytop decide; otherwise c2*x lies in [c2*k + Y'*a2,
//   c2*k + Y'*a2 + c2) and the difference times c2 is bounded above by a
//   function linear in Y', again checked at both ends (128-bit).  On sparse
//   cross-sections at 2048^2 it removes half the comparisons (3.2 -> 1.7 per
//   pixel per sector on p90) and 10-17% of the time; on dense ones it is
//   neutral.
// Without the rules (Options::rule1/rule2 = false) every candidate enters the
// list at once, stays, and the scan visits all of them: still exact, slower.
//
// ---------------------------------------------------------------- exactness
// A feature pixel P_Y gets D(0, 0), the least value of any monotone D.
// Otherwise fix P_Y on line k and a row r >= Y.  The features of row r in P_Y's wedge
// form the interval [start, end] with start in {col(r), col(r)+1}; D is
// nondecreasing in |dx| with dx >= 0 there, so the first feature at or after
// start (m_r, if <= end) is the row's nearest, and m_r is row r's entry's
// candidate at Y: the primary, or for a feature at col(r) q0 when start =
// col(r) and the secondary otherwise (the secondary is skipped only when q0
// stays on the left side for all rows to come, i.e. start = col(r), or when
// psi is constant).  The nearest in-sector feature of P_Y is the best m_r
// over r.  m_r is valid at Y, so its entry entered the list before P_Y was
// answered (a waiting primary's activation row is >= Y: the walk starts from
// a proven upper bound).  An entry leaves the list only by rule 2, in favour
// of one whose candidate is valid at every later pixel where its own is and
// no farther in |dx| and |dy| there; by induction over removals some list
// entry's candidate valid at Y is no farther than m_r (the Euclidean pruning
// removes B only for an A valid at every later pixel and, at each of them,
// no farther than B's candidate there; these relations compose, so the
// induction holds with both removals).  Every valid
// candidate is a feature in the sector, so the minimum over them is the DT.  Rule 1's scan stop is safe since every valid member at depth dy
// has dx >= L(dy).  Only comparisons of exact integers (and of one D functor
// on equal arguments) are involved.
//
// Work: pass 1 is O(W*H) per bitmap.  Pass 2 creates at most two candidates
// per pixel, each activated once and removed at most once; a walk costs
// O(tau).  The scan visits the Pareto staircase of candidates above the
// stopping depth -- any D-oblivious exact method must evaluate D on each
// Pareto-minimal in-sector feature, since any of them can be the unique
// nearest for some monotone D.  Measured on cross-sections of the real DEM
// (bench/bench_ddt.cpp, N = 24): 0.5 - 2.0 comparisons (0.9 - 3.8 without
// the Euclidean pruning), 0.3 - 1.3 candidates and 0.25 - 1.8 walk steps per
// pixel per sector; distances only, one thread, on the machine of 2026-11-25:
// 7.7 - 13.5 ns per pixel per sector at 403 x 344 and 11.6 - 20.3 ns at
// 2048^2 (two threads at 2048^2: 6.3 - 10.6 ns); OpenCV's exact
// unconstrained EDT in the same runs: 5.8 - 8.7 and 29 - 33 ns per pixel.
// Unconstrained: the minimum over the four closed quadrants [0,90], [90,180],
// [180,270], [270,360] degrees (every offset lies in one), same traversal.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace ct_host {
namespace ddt {

// ------------------------------------------------------------------ values
template <class V>
struct Inf;
template <>
struct Inf<int64_t> {
    static constexpr int64_t value = std::numeric_limits<int64_t>::max();
};
template <>
struct Inf<double> {
    static constexpr double value = std::numeric_limits<double>::infinity();
};

struct Point {
    int32_t x = -1, y = -1;  // pixel; (-1, -1) = no feature in the sector
};

// ---------------------------------------------------------------- distances
// Each takes |dx|, |dy| (pixels, >= 0, < 2^31).  symmetric: D(a, b) ==
// D(b, a) for all arguments, so a transposed frame runs the plain kernel
// (the same values; half the kernels to compile).
struct EuclideanSq {
    using value_type = int64_t;
    static constexpr bool symmetric = true;
    int64_t operator()(int64_t ax, int64_t ay) const { return ax * ax + ay * ay; }
};
struct CityBlock {
    using value_type = int64_t;
    static constexpr bool symmetric = true;
    int64_t operator()(int64_t ax, int64_t ay) const { return ax + ay; }
};
struct Chessboard {
    using value_type = int64_t;
    static constexpr bool symmetric = true;
    int64_t operator()(int64_t ax, int64_t ay) const { return ax > ay ? ax : ay; }
};
struct ChamferInt {  // w_max * max + w_min * min, weights in [0, 2^40]
    using value_type = int64_t;
    static constexpr bool symmetric = true;
    int64_t w_max = 1, w_min = 0;
    int64_t operator()(int64_t ax, int64_t ay) const
    {
        return ax > ay ? w_max * ax + w_min * ay : w_max * ay + w_min * ax;
    }
};
struct ChamferReal {  // same, double weights >= 0
    using value_type = double;
    static constexpr bool symmetric = true;
    double w_max = 1.0, w_min = 0.0;
    double operator()(int64_t ax, int64_t ay) const
    {
        return ax > ay ? w_max * (double)ax + w_min * (double)ay
                       : w_max * (double)ay + w_min * (double)ax;
    }
};
// a * (max - min) + b * min  ==  a * max + (b - a) * min   (b >= a >= 0)
inline ChamferInt chamfer_from_steps(int64_t a, int64_t b) { return ChamferInt{a, b - a}; }
inline ChamferReal chamfer_from_steps(double a, double b) { return ChamferReal{a, b - a}; }
// D(|dx|, |dy|) = table[|dy| * cols + |dx|]; the caller guarantees a
// nondecreasing table covering |dx| < cols, |dy| < rows (not copied).
struct TableDistance {
    using value_type = int64_t;
    static constexpr bool symmetric = false;  // any nondecreasing table
    const int64_t *table = nullptr;
    int64_t cols = 0, rows = 0;
    int64_t operator()(int64_t ax, int64_t ay) const { return table[ay * cols + ax]; }
};

// ------------------------------------------------------------------ sectors
struct Wedge {
    int64_t b1x = 1, b1y = 0;  // int32 range
    int64_t b2x = 0, b2y = 1;
};
// Sector s (0 <= s < N, 1 <= N <= CT_MAX_SECTORS) with boundaries from
// ct_sector_boundary(N, s) and (N, s + 1).  Throws ct_host::Error.
Wedge sector_wedge(uint32_t sectors, uint32_t s);

// ------------------------------------------------------------------ options
struct Options {
    int threads = 1;    // lines are independent; 0 = hardware concurrency
    bool rule1 = true;  // propagation rule (see above)
    bool rule2 = true;  // dominance rule
    bool euclid = true; // the Euclidean pruning (EuclideanSq only; needs rule2)
    bool feature_transform = true;  // false: the DT only, ft left empty
    // Canonical frame per piece: 0 = the measured-fastest choice (above);
    // 1 = never transposed, 2 = always transposed.  Every frame is exact (the
    // tests sweep all three); only speed differs.
    int frame = 0;
};
// Operation counts, summed over pieces and threads.
struct Stats {
    uint64_t pixels = 0;       // pixels answered (once per piece)
    uint64_t lines = 0;        // rasterized lines traversed in pass 2
    uint64_t candidates = 0;   // candidates created
    uint64_t never_valid = 0;  // dropped by rule 1 at creation
    uint64_t activated = 0;    // entered the list
    uint64_t dominated = 0;    // removed or refused by rule 2
    uint64_t pruned = 0;       // removed by the Euclidean pruning
    uint64_t comparisons = 0;  // candidate comparisons: scan visits + rule-2 tests
    uint64_t walk_steps = 0;   // activation-row walk steps
    void add(const Stats &o);
};

// Pass-1 tables for one bitmap (distance to the first feature at or after
// each pixel in each of the four axis directions), shared by all sectors.
// Sizes: 1 <= W, H and W * H < 2^31.  Throws ct_host::Error.
class Prepared {
public:
    Prepared(int width, int height, const uint8_t *bits);  // bits: W*H bytes
    int width() const { return w_; }
    int height() const { return h_; }
    bool feature(int x, int y) const { return next_[0][(std::size_t)y * (std::size_t)w_ + (std::size_t)x] == 0; }
    const int32_t *next(int dir) const { return next_[dir].data(); }  // 0:+x 1:-x 2:+y 3:-y
    static constexpr int32_t kNone = std::numeric_limits<int32_t>::max() / 2;

private:
    int w_, h_;
    std::vector<int32_t> next_[4];
};

// Directional DT/FT of one sector into dt and ft (resized to W*H, row-major).
template <class D>
void directional(const Prepared &bm, const Wedge &w, const D &dist,
                 std::vector<typename D::value_type> &dt, std::vector<Point> &ft,
                 const Options &opt = Options(), Stats *stats = nullptr);
template <class D>
void directional(const Prepared &bm, uint32_t sectors, uint32_t s, const D &dist,
                 std::vector<typename D::value_type> &dt, std::vector<Point> &ft,
                 const Options &opt = Options(), Stats *stats = nullptr);
// Unconstrained DT/FT: min over the four closed quadrants.
template <class D>
void unconstrained(const Prepared &bm, const D &dist,
                   std::vector<typename D::value_type> &dt, std::vector<Point> &ft,
                   const Options &opt = Options(), Stats *stats = nullptr);

// ------------------------------------------------------- capped queries
// The PPT builder (builder_slices.cpp) needs a slice's directional DT only at
// some pixels (measured: about 10% of them per slice and sector on the real
// DEM) and only where it is below a per-pixel cap (a radius of ~30 pixels on
// average).  A full transform computes every pixel; a capped query computes
// one pixel by walking the rows of the same canonical frame as the traversal
// (depth j = 0, 1, ... away from p; ddt.hpp's L(j), R(j) give row j's exact
// wedge interval), with the same exactness argument as pass 2: the nearest
// in-sector feature of row j is the first feature at or after x + L(j) when
// it is <= x + R(j) (D nondecreasing in |dx|), and rows stop at the first
// depth j with D(L(j), j) >= min(best, cap) (rule 1's bound).  Each row costs
// one "first set bit at or after" on 64-bit words with a skip table over
// empty words, O(1).  Per piece, the frame with the fewer rows to visit is
// taken: rows ~ distance * sin(angle between the piece's far boundary and the
// scan axis).
//
// BitLines: a bitmap's rows and columns as bitsets (2 bits per pixel plus
// 1/16 for the skip tables), built once per bitmap, shared by every sector
// and thread.
class BitLines {
public:
    // bits: W*H bytes, nonzero = feature; 1 <= W, H <= 2^20.  Throws.
    BitLines(int width, int height, const uint8_t *bits);
    // The same from a predicate feature(x, y) evaluated once per pixel.
    template <class F>
    static BitLines from(int width, int height, const F &feature);
    int width() const { return w_; }
    int height() const { return h_; }
    // First feature at or after position p (0 <= p < len) along line l of
    // orientation o (0: rows, position = x; 1: columns, position = y) in
    // increasing (fwd) or decreasing (!fwd) position; -1 if none.
    int64_t next(int o, int64_t l, int64_t p, bool fwd) const;

private:
    BitLines() = default;
    void alloc(int width, int height);
    void set(int x, int y);
    void finish();
    struct Lines {
        int64_t len = 0, wpl = 0;        // line length, 64-bit words per line
        std::vector<uint64_t> w;          // lines x wpl
        std::vector<int32_t> nz_up, nz_down;  // next nonzero word at or after / at or before (-1: none)
    };
    int w_ = 0, h_ = 0;
    Lines l_[2];
};

template <class F>
BitLines BitLines::from(int width, int height, const F &feature)
{
    BitLines b;
    b.alloc(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            if (feature(x, y)) b.set(x, y);
    b.finish();
    return b;
}

// Capped directional DT queries for one wedge (a union of closed pieces)
// over one BitLines.  The wedges: each 0 < opening <= 180 degrees (ddt.hpp's
// convention), their union the sector; an empty list = every direction.
template <class D>
class CappedQuery {
public:
    using V = typename D::value_type;
    CappedQuery(const BitLines &bl, const std::vector<Wedge> &wedges, const D &dist);
    // min(cap, the directional DT at (x, y)): exact when the DT is below cap.
    V query(int x, int y, V cap) const;
    uint64_t rows_visited() const { return rows_; }  // statistics, summed over queries

private:
    struct QFrame {
        bool fx, fy, transpose;
        std::vector<int64_t> L, R;  // per depth j: wedge interval (R: INT64_MAX = unbounded)
        std::vector<V> lb;          // D(L(j), j) in the original orientation
    };
    const BitLines &bl_;
    D dist_;
    std::vector<QFrame> frames_;
    mutable uint64_t rows_ = 0;
};

}  // namespace ddt
}  // namespace ct_host
