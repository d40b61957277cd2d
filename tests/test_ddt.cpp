// test_ddt.cpp -- directional distance transforms (host_tools/ddt/ddt.hpp) against
// a brute force that scans every feature with the flight library's closed
// wedge test (ct_in_wedge) or, for explicit wedges, an independent 128-bit
// cross-product test.  Every DT value must be equal (doubles bitwise); every
// FT must be a feature in the sector at exactly that distance.
//
// Environment: CT_DDT_SEED (default 1), CT_DDT_CASES (bitmaps per sweep,
// default 800: about 8000 bitmaps in all, ~10 s), plus CT_TEST_FILTER.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "conetrace.h"
#include "ddt.hpp"
#include "harness.h"

using namespace ct_host::ddt;

namespace {

uint64_t env_u64(const char *name, uint64_t dflt)
{
    const char *s = getenv(name);
    return s ? (uint64_t)strtoull(s, nullptr, 10) : dflt;
}
uint64_t g_seed = 1;
int g_cases = 800;

// ----------------------------------------------------------------- bitmaps
struct Bits {
    int w = 0, h = 0;
    std::vector<uint8_t> b;
    uint8_t at(int x, int y) const { return b[(size_t)y * (size_t)w + (size_t)x]; }
};

// Varied sizes and contents: 1 x n, n x 1, empty, full, 1 %, 50 %, random
// density, and digital lines at random slopes (features along a sector
// boundary are where the rasterized-line jitter matters).
Bits random_bits(ct_rng *r, int maxside)
{
    Bits m;
    const int shape = (int)ct_rng_range(r, 0, 9);
    if (shape == 0) {
        m.w = 1;
        m.h = (int)ct_rng_range(r, 1, maxside);
    } else if (shape == 1) {
        m.w = (int)ct_rng_range(r, 1, maxside);
        m.h = 1;
    } else {
        m.w = (int)ct_rng_range(r, 1, maxside);
        m.h = (int)ct_rng_range(r, 1, maxside);
    }
    m.b.assign((size_t)m.w * (size_t)m.h, 0);
    const int kind = (int)ct_rng_range(r, 0, 7);
    double p = 0.0;
    switch (kind) {
    case 0: p = 0.0; break;
    case 1: p = 1.0; break;
    case 2: p = 0.01; break;
    case 3: p = 0.5; break;
    case 4: p = 0.1; break;
    default: p = ct_rng_unit(r); break;
    }
    for (auto &v : m.b)
        v = ct_rng_unit(r) < p ? 1 : 0;
    if (kind >= 6) {  // add a few digital lines
        const int nl = (int)ct_rng_range(r, 1, 3);
        for (int l = 0; l < nl; ++l) {
            const double ang = ct_rng_unit(r) * 6.283185307179586;
            const double x0 = ct_rng_unit(r) * m.w, y0 = ct_rng_unit(r) * m.h;
            for (int t = -2 * (m.w + m.h); t <= 2 * (m.w + m.h); ++t) {
                const int x = (int)std::floor(x0 + t * 0.5 * std::cos(ang));
                const int y = (int)std::floor(y0 + t * 0.5 * std::sin(ang));
                if (x >= 0 && y >= 0 && x < m.w && y < m.h)
                    m.b[(size_t)y * (size_t)m.w + (size_t)x] = 1;
            }
        }
    }
    return m;
}

// ------------------------------------------------------- sector predicates
struct NSector {  // the flight library's own test
    int32_t bx[CT_MAX_SECTORS + 1], by[CT_MAX_SECTORS + 1];
    uint32_t n, s;
    NSector(uint32_t n_, uint32_t s_) : n(n_), s(s_)
    {
        for (uint32_t k = 0; k <= n; ++k)
            ct_sector_boundary(n, k, &bx[k], &by[k]);
    }
    bool operator()(int64_t dx, int64_t dy) const
    {
        uint32_t in = 0;
        ct_in_wedge(bx, by, n, s, dx, dy, &in);
        return in != 0;
    }
};
struct XSector {  // explicit wedge, independent 128-bit test; open = strict
    Wedge w;
    bool open = false;
    bool operator()(int64_t dx, int64_t dy) const
    {
        const __int128 c0 = (__int128)w.b1x * dy - (__int128)w.b1y * dx;
        const __int128 c1 = (__int128)dx * w.b2y - (__int128)dy * w.b2x;
        if (open && (dx != 0 || dy != 0))
            return c0 > 0 && c1 > 0;
        return c0 >= 0 && c1 >= 0;
    }
};
struct AllDirections {
    bool operator()(int64_t, int64_t) const { return true; }
};

// --------------------------------------------------------------- distances
struct Metrics {
    EuclideanSq e;
    CityBlock c;
    Chessboard k;
    ChamferInt ci = chamfer_from_steps((int64_t)3, (int64_t)4);  // {3, 1}
    ChamferReal cr = ChamferReal{1.0, std::sqrt(2.0) - 1.0};
    std::vector<int64_t> table;
    TableDistance t;
    // a random monotone, asymmetric table (catches swapped arguments)
    Metrics(ct_rng *r, int cols, int rows)
    {
        table.assign((size_t)cols * (size_t)rows, 0);
        for (int y = 0; y < rows; ++y)
            for (int x = 0; x < cols; ++x) {
                int64_t v = ct_rng_range(r, 0, 3) * (1 + (x > 2 * y ? 3 : 0)) + (x == 0 && y == 0 ? 0 : 1);
                if (x > 0)
                    v = std::max(v, table[(size_t)y * cols + x - 1] + ct_rng_range(r, 0, 2));
                if (y > 0)
                    v = std::max(v, table[(size_t)(y - 1) * cols + x] + ct_rng_range(r, 0, 1));
                table[(size_t)y * cols + x] = v;
            }
        t = TableDistance{table.data(), cols, rows};
    }
};

// ------------------------------------------------------------------ checks
struct Mismatch {
    bool any = false;
    std::string what;
};

template <class V>
std::string vstr(V v)
{
    if (v == Inf<V>::value)
        return "inf";
    char buf[64];
    snprintf(buf, sizeof buf, "%.17g", (double)v);
    return buf;
}

// Brute-force DT by scanning all features; compare; check FTs.
template <class D, class In>
bool check_one(const Bits &m, const std::vector<std::array<int, 2>> &feats, const In &in, const D &d,
               const std::vector<typename D::value_type> &dt, const std::vector<Point> &ft, Mismatch *mm,
               const char *label)
{
    using V = typename D::value_type;
    for (int y = 0; y < m.h; ++y)
        for (int x = 0; x < m.w; ++x) {
            V best = Inf<V>::value;
            for (const auto &q : feats) {
                const int64_t dx = q[0] - x, dy = q[1] - y;
                if (!in(dx, dy))
                    continue;
                const V v = d(dx < 0 ? -dx : dx, dy < 0 ? -dy : dy);
                if (v < best)
                    best = v;
            }
            const size_t i = (size_t)y * (size_t)m.w + (size_t)x;
            char buf[256];
            if (!(dt[i] == best)) {
                if (!mm->any)
                    snprintf(buf, sizeof buf, "%s: %dx%d pixel (%d,%d): dt %s, brute force %s", label, m.w, m.h, x,
                             y, vstr(dt[i]).c_str(), vstr(best).c_str()),
                        mm->what = buf;
                mm->any = true;
                return false;
            }
            const Point f = ft[i];
            bool ok;
            if (best == Inf<V>::value) {
                ok = f.x == -1 && f.y == -1;
            } else {
                const int64_t dx = f.x - x, dy = f.y - y;
                ok = f.x >= 0 && f.y >= 0 && f.x < m.w && f.y < m.h && m.at(f.x, f.y) && in(dx, dy) &&
                     d(dx < 0 ? -dx : dx, dy < 0 ? -dy : dy) == best;
            }
            if (!ok) {
                if (!mm->any)
                    snprintf(buf, sizeof buf, "%s: %dx%d pixel (%d,%d): bad ft (%d,%d) for dt %s", label, m.w, m.h,
                             x, y, f.x, f.y, vstr(best).c_str()),
                        mm->what = buf;
                mm->any = true;
                return false;
            }
        }
    return true;
}

std::vector<std::array<int, 2>> features(const Bits &m)
{
    std::vector<std::array<int, 2>> f;
    for (int y = 0; y < m.h; ++y)
        for (int x = 0; x < m.w; ++x)
            if (m.at(x, y))
                f.push_back({x, y});
    return f;
}

// Run every metric through `run(dist, dt, ft)` and compare with predicate in.
template <class Run, class In>
bool check_all_metrics(const Bits &m, const Metrics &me, const In &in, const Run &run, Mismatch *mm,
                       const char *label)
{
    const auto feats = features(m);
    std::vector<int64_t> di;
    std::vector<double> dd;
    std::vector<Point> ft;
    bool ok = true;
    run(me.e, di, ft);
    ok = ok && check_one(m, feats, in, me.e, di, ft, mm, (std::string(label) + " euclid").c_str());
    run(me.c, di, ft);
    ok = ok && check_one(m, feats, in, me.c, di, ft, mm, (std::string(label) + " cityblock").c_str());
    run(me.k, di, ft);
    ok = ok && check_one(m, feats, in, me.k, di, ft, mm, (std::string(label) + " chessboard").c_str());
    run(me.ci, di, ft);
    ok = ok && check_one(m, feats, in, me.ci, di, ft, mm, (std::string(label) + " chamfer34").c_str());
    run(me.cr, dd, ft);
    ok = ok && check_one(m, feats, in, me.cr, dd, ft, mm, (std::string(label) + " chamfer_real").c_str());
    run(me.t, di, ft);
    ok = ok && check_one(m, feats, in, me.t, di, ft, mm, (std::string(label) + " table").c_str());
    return ok;
}

Options opts_for(ct_rng *r)
{
    Options o;
    o.threads = ct_rng_range(r, 0, 3) == 0 ? 2 : 1;
    o.frame = (int)ct_rng_range(r, 0, 2);  // the automatic frame, or either one forced
    return o;
}

// One N-sector family over g_cases random bitmaps; `subset` > 0 tests that
// many random sectors per bitmap instead of all N.
void sweep_n(uint32_t n, int subset, uint64_t salt, int maxside)
{
    ct_rng r;
    ct_rng_seed(&r, g_seed * 1000003u + salt);
    for (int c = 0; c < g_cases; ++c) {
        const Bits m = random_bits(&r, maxside);
        const Prepared bm(m.w, m.h, m.b.data());
        const Metrics me(&r, m.w, m.h);
        const Options o = opts_for(&r);
        const uint32_t count = subset > 0 ? (uint32_t)subset : n;
        for (uint32_t i = 0; i < count; ++i) {
            const uint32_t s = subset > 0 ? (uint32_t)ct_rng_range(&r, 0, n - 1) : i;
            Mismatch mm;
            char label[64];
            snprintf(label, sizeof label, "case %d N=%u s=%u", c, n, s);
            auto run = [&](const auto &d, auto &dt, std::vector<Point> &ft) { directional(bm, n, s, d, dt, ft, o); };
            if (!check_all_metrics(m, me, NSector(n, s), run, &mm, label))
                TEST_FAIL_MSG("%s", mm.what.c_str());
        }
    }
}

void test_octants_n8(void) { sweep_n(8, 0, 8, 24); }
void test_sectors_n24(void) { sweep_n(24, 0, 24, 16); }
void test_quadrants_n4(void) { sweep_n(4, 0, 4, 24); }
void test_sectors_n64(void) { sweep_n(64, 12, 64, 20); }
// N < 4: sectors wider than 90 degrees are unions of pieces; N = 1 is all.
void test_wide_sectors_n123(void)
{
    sweep_n(1, 0, 1, 20);
    sweep_n(2, 0, 2, 20);
    sweep_n(3, 0, 3, 20);
}

// Random boundary vectors: huge (|b| ~ 2^20..2^31) or tiny (|.| <= 6, so the
// boundaries pass through many lattice points); openings up to 90 degrees,
// and every tenth case up to 180 (split internally at the axes).
Wedge random_wedge(ct_rng *r)
{
    for (;;) {
        Wedge w;
        const bool wide = ct_rng_range(r, 0, 9) == 0;
        if (ct_rng_range(r, 0, 2) == 0) {
            w.b1x = ct_rng_range(r, -6, 6);
            w.b1y = ct_rng_range(r, -6, 6);
            w.b2x = ct_rng_range(r, -6, 6);
            w.b2y = ct_rng_range(r, -6, 6);
        } else {
            const double th = ct_rng_unit(r) * 6.283185307179586;
            const double om = (wide ? 3.141592653589793 : 1.5707963267948966) *
                              (ct_rng_range(r, 0, 4) == 0 ? ct_rng_unit(r) * 0.05 : ct_rng_unit(r));
            const double m1 = std::ldexp(1.0, (int)ct_rng_range(r, 20, 30)) * (1.0 + ct_rng_unit(r));
            const double m2 = std::ldexp(1.0, (int)ct_rng_range(r, 20, 30)) * (1.0 + ct_rng_unit(r));
            w.b1x = (int64_t)std::llround(m1 * std::cos(th));
            w.b1y = (int64_t)std::llround(m1 * std::sin(th));
            w.b2x = (int64_t)std::llround(m2 * std::cos(th + om));
            w.b2y = (int64_t)std::llround(m2 * std::sin(th + om));
            if (ct_rng_range(r, 0, 19) == 0) {  // exactly 180 degrees
                w.b2x = -w.b1x;
                w.b2y = -w.b1y;
            }
        }
        auto clamp32 = [](int64_t v) { return std::max<int64_t>(INT32_MIN + 1, std::min<int64_t>(INT32_MAX, v)); };
        w.b1x = clamp32(w.b1x);
        w.b1y = clamp32(w.b1y);
        w.b2x = clamp32(w.b2x);
        w.b2y = clamp32(w.b2y);
        const __int128 c = (__int128)w.b1x * w.b2y - (__int128)w.b1y * w.b2x;
        const __int128 d = (__int128)w.b1x * w.b2x + (__int128)w.b1y * w.b2y;
        if ((w.b1x == 0 && w.b1y == 0) || (w.b2x == 0 && w.b2y == 0))
            continue;
        if (c > 0 && (wide || d >= 0))
            return w;
        if (c == 0 && d < 0 && wide)
            return w;
    }
}

void test_random_sector_pairs(void)
{
    ct_rng r;
    ct_rng_seed(&r, g_seed * 1000003u + 77);
    int wide = 0;
    for (int c = 0; c < g_cases; ++c) {
        const Bits m = random_bits(&r, 24);
        const Prepared bm(m.w, m.h, m.b.data());
        const Metrics me(&r, m.w, m.h);
        const Options o = opts_for(&r);
        for (int i = 0; i < 8; ++i) {
            const Wedge w = random_wedge(&r);
            wide += (w.b1x * w.b2x + w.b1y * w.b2y < 0) ? 1 : 0;
            Mismatch mm;
            char label[160];
            snprintf(label, sizeof label, "case %d wedge (%lld,%lld)-(%lld,%lld)", c, (long long)w.b1x,
                     (long long)w.b1y, (long long)w.b2x, (long long)w.b2y);
            auto run = [&](const auto &d, auto &dt, std::vector<Point> &ft) { directional(bm, w, d, dt, ft, o); };
            if (!check_all_metrics(m, me, XSector{w, false}, run, &mm, label))
                TEST_FAIL_MSG("%s", mm.what.c_str());
        }
    }
    TEST_ASSERT_MSG(wide > 0, "no wedge wider than 90 degrees was drawn");
}

void test_unconstrained(void)
{
    ct_rng r;
    ct_rng_seed(&r, g_seed * 1000003u + 99);
    for (int c = 0; c < g_cases; ++c) {
        const Bits m = random_bits(&r, c % 10 == 0 ? 48 : 24);
        const Prepared bm(m.w, m.h, m.b.data());
        const Metrics me(&r, m.w, m.h);
        const Options o = opts_for(&r);
        Mismatch mm;
        char label[64];
        snprintf(label, sizeof label, "case %d unconstrained", c);
        auto run = [&](const auto &d, auto &dt, std::vector<Point> &ft) { unconstrained(bm, d, dt, ft, o); };
        if (!check_all_metrics(m, me, AllDirections(), run, &mm, label))
            TEST_FAIL_MSG("%s", mm.what.c_str());
    }
}

// A few bitmaps up to 64 x 64 for the 24-sector family and random wedges.
void test_large_bitmaps(void)
{
    ct_rng r;
    ct_rng_seed(&r, g_seed * 1000003u + 64);
    const int n = std::max(2, g_cases / 50);
    for (int c = 0; c < n; ++c) {
        Bits m = random_bits(&r, 64);
        if (c == 0) {  // one full-size case for sure
            m.w = m.h = 64;
            m.b.assign(64 * 64, 0);
            for (auto &v : m.b)
                v = ct_rng_unit(&r) < 0.03 ? 1 : 0;
        }
        const Prepared bm(m.w, m.h, m.b.data());
        const Metrics me(&r, m.w, m.h);
        const Options o = opts_for(&r);
        for (int i = 0; i < 6; ++i) {
            Mismatch mm;
            char label[96];
            bool ok;
            if (i < 4) {
                const uint32_t s = (uint32_t)ct_rng_range(&r, 0, 23);
                snprintf(label, sizeof label, "large %d N=24 s=%u", c, s);
                auto run = [&](const auto &d, auto &dt, std::vector<Point> &ft) { directional(bm, 24, s, d, dt, ft, o); };
                ok = check_all_metrics(m, me, NSector(24, s), run, &mm, label);
            } else {
                const Wedge w = random_wedge(&r);
                snprintf(label, sizeof label, "large %d random wedge", c);
                auto run = [&](const auto &d, auto &dt, std::vector<Point> &ft) { directional(bm, w, d, dt, ft, o); };
                ok = check_all_metrics(m, me, XSector{w, false}, run, &mm, label);
            }
            if (!ok)
                TEST_FAIL_MSG("%s", mm.what.c_str());
        }
    }
}

// Clustered, sparse bitmaps with long lines, like the real cross-sections
// (features in blobs: a sum of random bumps above a level), where the
// Euclidean pruning removes many entries: squared Euclidean DT and FT for all
// 24 sectors and random wedges against a brute force that walks rows of
// features outwards from the pixel (bucketed by row, stopping at dy^2 >=
// best), with the pruning on and off.  It must fire, and cut comparisons.
void test_euclidean_pruning(void)
{
    ct_rng r;
    ct_rng_seed(&r, g_seed * 1000003u + 77);
    const int n = std::max(3, g_cases / 100);
    Stats on, off;
    for (int c = 0; c < n; ++c) {
        Bits m;
        const int shape = c % 3;  // square, wide, tall: lines long in either frame
        m.w = shape == 2 ? (int)ct_rng_range(&r, 20, 60) : (int)ct_rng_range(&r, 120, 200);
        m.h = shape == 1 ? (int)ct_rng_range(&r, 20, 60) : (int)ct_rng_range(&r, 120, 200);
        const int bumps = (int)ct_rng_range(&r, 5, 40);
        std::vector<std::array<double, 4>> bp;
        for (int i = 0; i < bumps; ++i)
            bp.push_back({ct_rng_unit(&r) * m.w, ct_rng_unit(&r) * m.h, 2.0 + ct_rng_unit(&r) * 20.0,
                          ct_rng_unit(&r) < 0.2 ? -0.5 : 1.0});
        std::vector<double> v((size_t)m.w * (size_t)m.h);
        for (int y = 0; y < m.h; ++y)
            for (int x = 0; x < m.w; ++x) {
                double s = 0.0;
                for (const auto &b : bp) {
                    const double dx = x - b[0], dy = y - b[1];
                    s += b[3] * std::exp(-(dx * dx + dy * dy) / (b[2] * b[2]));
                }
                v[(size_t)y * (size_t)m.w + (size_t)x] = s + 0.05 * ct_rng_unit(&r);
            }
        std::vector<double> sorted = v;
        std::sort(sorted.begin(), sorted.end());
        const double density = 0.01 + 0.2 * ct_rng_unit(&r);
        const double level = sorted[(size_t)((double)(sorted.size() - 1) * (1.0 - density))];
        m.b.resize(v.size());
        for (size_t i = 0; i < v.size(); ++i)
            m.b[i] = v[i] >= level ? 1 : 0;
        const Prepared bm(m.w, m.h, m.b.data());
        std::vector<std::vector<int>> rows((size_t)m.h);  // feature columns per row
        for (int y = 0; y < m.h; ++y)
            for (int x = 0; x < m.w; ++x)
                if (m.at(x, y)) rows[(size_t)y].push_back(x);
        for (int i = 0; i < 26; ++i) {
            Wedge w;
            char label[96];
            if (i < 24) {
                w = sector_wedge(24, (uint32_t)i);
                snprintf(label, sizeof label, "clustered %d (%dx%d) N=24 s=%d", c, m.w, m.h, i);
            } else {
                w = random_wedge(&r);
                snprintf(label, sizeof label, "clustered %d (%dx%d) random wedge", c, m.w, m.h);
            }
            const XSector in{w, false};
            Options o = opts_for(&r);
            std::vector<int64_t> dt, dt0;
            std::vector<Point> ft, ft0;
            directional(bm, w, EuclideanSq(), dt, ft, o, &on);
            o.euclid = false;
            directional(bm, w, EuclideanSq(), dt0, ft0, o, &off);
            for (int y = 0; y < m.h; ++y)
                for (int x = 0; x < m.w; ++x) {
                    int64_t best = Inf<int64_t>::value;
                    for (int dy = 0; dy < m.h && (int64_t)dy * dy < best; ++dy)
                        for (int sgn = -1; sgn <= 1; sgn += 2) {
                            const int yy = y + sgn * dy;
                            if ((dy == 0 && sgn > 0) || yy < 0 || yy >= m.h)
                                continue;
                            for (int xx : rows[(size_t)yy])
                                if (in(xx - x, yy - y))
                                    best = std::min(best, (int64_t)(xx - x) * (xx - x) + (int64_t)dy * dy);
                        }
                    const size_t k = (size_t)y * (size_t)m.w + (size_t)x;
                    if (dt[k] != best || dt0[k] != best)
                        TEST_FAIL_MSG("%s: pixel (%d,%d): dt %s, without the pruning %s, brute force %s", label, x, y,
                                      vstr(dt[k]).c_str(), vstr(dt0[k]).c_str(), vstr(best).c_str());
                    const Point f = ft[k];
                    const bool ok = best == Inf<int64_t>::value
                                        ? f.x == -1 && f.y == -1
                                        : f.x >= 0 && f.y >= 0 && f.x < m.w && f.y < m.h && m.at(f.x, f.y) &&
                                              in(f.x - x, f.y - y) &&
                                              (int64_t)(f.x - x) * (f.x - x) + (int64_t)(f.y - y) * (f.y - y) == best;
                    if (!ok)
                        TEST_FAIL_MSG("%s: pixel (%d,%d): bad ft (%d,%d)", label, x, y, f.x, f.y);
                }
        }
    }
    TEST_ASSERT_MSG(on.pruned > 0 && off.pruned == 0, "pruned %llu / %llu", (unsigned long long)on.pruned,
                    (unsigned long long)off.pruned);
    TEST_ASSERT_MSG(on.comparisons < off.comparisons, "comparisons %llu with the pruning, %llu without",
                    (unsigned long long)on.comparisons, (unsigned long long)off.comparisons);
    printf("  Euclidean pruning: %.2f comparisons per pixel and wedge with it, %.2f without\n",
           (double)on.comparisons / (double)on.pixels, (double)off.comparisons / (double)off.pixels);
}

// Without the pruning rules the result must be the same (exact either way).
void test_rules_off_same_result(void)
{
    ct_rng r;
    ct_rng_seed(&r, g_seed * 1000003u + 5);
    Stats on, off;
    for (int c = 0; c < g_cases / 3; ++c) {
        const Bits m = random_bits(&r, 24);
        const Prepared bm(m.w, m.h, m.b.data());
        const Metrics me(&r, m.w, m.h);
        for (int mode = 0; mode < 3; ++mode) {
            Options o;
            o.rule1 = mode != 1 && mode != 0;
            o.rule2 = mode != 2 && mode != 0;
            if (mode == 0)
                o.rule1 = o.rule2 = false;
            const uint32_t s = (uint32_t)ct_rng_range(&r, 0, 23);
            Mismatch mm;
            char label[64];
            snprintf(label, sizeof label, "case %d rules %d%d s=%u", c, (int)o.rule1, (int)o.rule2, s);
            Stats *st = mode == 0 ? &off : nullptr;
            auto run = [&](const auto &d, auto &dt, std::vector<Point> &ft) { directional(bm, 24, s, d, dt, ft, o, st); };
            if (!check_all_metrics(m, me, NSector(24, s), run, &mm, label))
                TEST_FAIL_MSG("%s", mm.what.c_str());
            Options all;
            std::vector<int64_t> dt;
            std::vector<Point> ft;
            directional(bm, 24, s, me.e, dt, ft, all, &on);
        }
    }
    // the rules must actually prune something
    TEST_ASSERT_MSG(off.comparisons > on.comparisons, "rules did not reduce comparisons (%llu vs %llu)",
                    (unsigned long long)on.comparisons, (unsigned long long)off.comparisons);
}

// Options::feature_transform = false (the PPT builder's mode): the same
// distances, no feature array.
void test_distances_only(void)
{
    ct_rng r;
    ct_rng_seed(&r, g_seed * 1000003u + 11);
    for (int c = 0; c < g_cases / 4; ++c) {
        const Bits m = random_bits(&r, 24);
        const Prepared bm(m.w, m.h, m.b.data());
        const uint32_t n = (uint32_t)ct_rng_range(&r, 1, 32), s = (uint32_t)ct_rng_range(&r, 0, (int)n - 1);
        Options full, lean;
        lean.feature_transform = false;
        std::vector<int64_t> a, b;
        std::vector<Point> fa, fb(3);
        directional(bm, n, s, EuclideanSq(), a, fa, full);
        directional(bm, n, s, EuclideanSq(), b, fb, lean);
        TEST_ASSERT_MSG(a == b, "case %d (N=%u s=%u): distances differ without the feature transform", c, n, s);
        TEST_ASSERT_MSG(fb.empty() && fa.size() == a.size(), "case %d: feature array sizes %zu / %zu", c, fa.size(),
                        fb.size());
    }
}

// Capped queries (the PPT builder's mode): min(cap, DT) at every pixel equals
// the brute force's, for unions of random wedges (or all directions), every
// metric, caps from 0 through the exact DT values to infinity, on bitmaps
// wide enough to span several 64-bit words per row and column.
template <class D>
bool check_capped(ct_rng *r, const Bits &m, const BitLines &bl, const std::vector<Wedge> &ws, const D &d,
                  const char *label, std::string *what)
{
    using V = typename D::value_type;
    CappedQuery<D> q(bl, ws, d);
    std::vector<std::array<int, 2>> feats;
    for (int y = 0; y < m.h; ++y)
        for (int x = 0; x < m.w; ++x)
            if (m.at(x, y)) feats.push_back({x, y});
    for (int y = 0; y < m.h; ++y)
        for (int x = 0; x < m.w; ++x) {
            V best = Inf<V>::value;
            for (const auto &f : feats) {
                const int64_t dx = f[0] - x, dy = f[1] - y;
                bool in = ws.empty();
                for (const Wedge &w : ws) in = in || XSector{w, false}(dx, dy);
                if (!in) continue;
                const V v = d(dx < 0 ? -dx : dx, dy < 0 ? -dy : dy);
                if (v < best) best = v;
            }
            V caps[4] = {Inf<V>::value, best, (V)0, (V)ct_rng_range(r, 0, 40)};
            if (best != Inf<V>::value) caps[2] = best + (V)1;
            for (V cap : caps) {
                const V got = q.query(x, y, cap), want = best < cap ? best : cap;
                if (!(got == want)) {
                    char buf[256];
                    snprintf(buf, sizeof buf, "%s: %dx%d pixel (%d,%d) cap %s: query %s, brute force %s", label, m.w,
                             m.h, x, y, vstr(cap).c_str(), vstr(got).c_str(), vstr(want).c_str());
                    *what = buf;
                    return false;
                }
            }
        }
    return true;
}

void test_capped_queries(void)
{
    ct_rng r;
    ct_rng_seed(&r, g_seed * 1000003u + 313);
    int unions = 0, alldir = 0;
    uint64_t rows = 0;
    for (int c = 0; c < g_cases / 4; ++c) {
        const Bits m = random_bits(&r, c % 16 == 0 ? 130 : 40);
        const BitLines bl(m.w, m.h, m.b.data());
        std::vector<Wedge> ws;
        const int kind = (int)ct_rng_range(&r, 0, 9);
        if (kind == 0) {
            alldir++;
        } else if (kind <= 3) {
            const uint32_t n = (uint32_t)ct_rng_range(&r, 2, 64);
            ws.push_back(sector_wedge(n, (uint32_t)ct_rng_range(&r, 0, (int)n - 1)));
        } else {
            const int nw = (int)ct_rng_range(&r, 1, 3);
            for (int k = 0; k < nw; ++k) ws.push_back(random_wedge(&r));
            unions += nw > 1;
        }
        char label[64];
        snprintf(label, sizeof label, "case %d (%zu wedges)", c, ws.size());
        const Metrics me(&r, m.w, m.h);
        std::string what;
        bool ok = check_capped(&r, m, bl, ws, me.e, label, &what) && check_capped(&r, m, bl, ws, me.c, label, &what) &&
                  check_capped(&r, m, bl, ws, me.k, label, &what) && check_capped(&r, m, bl, ws, me.cr, label, &what) &&
                  check_capped(&r, m, bl, ws, me.t, label, &what);
        if (!ok) TEST_FAIL_MSG("%s", what.c_str());
        // the same bitmap from a predicate gives the same bitsets' answers
        const BitLines bp = BitLines::from(m.w, m.h, [&](int x, int y) { return m.at(x, y) != 0; });
        CappedQuery<EuclideanSq> q1(bl, ws, EuclideanSq()), q2(bp, ws, EuclideanSq());
        for (int y = 0; y < m.h; ++y)
            for (int x = 0; x < m.w; ++x)
                TEST_ASSERT_MSG(q1.query(x, y, Inf<int64_t>::value) == q2.query(x, y, Inf<int64_t>::value),
                                "case %d: BitLines::from differs at (%d,%d)", c, x, y);
        rows += q1.rows_visited();
    }
    // a few features on wide bitmaps: nearest features many rows and words away
    for (int c = 0; c < 24; ++c) {
        Bits m;
        m.w = (int)ct_rng_range(&r, 1, 300);
        m.h = (int)ct_rng_range(&r, 1, 300);
        m.b.assign((size_t)m.w * (size_t)m.h, 0);
        for (int k = (int)ct_rng_range(&r, 1, 6); k-- > 0;)
            m.b[(size_t)ct_rng_range(&r, 0, m.w * m.h - 1)] = 1;
        const BitLines bl(m.w, m.h, m.b.data());
        std::vector<Wedge> ws;
        if (c % 6 != 0) ws.push_back(c % 2 ? random_wedge(&r) : sector_wedge(24, (uint32_t)(c % 24)));
        char label[64];
        snprintf(label, sizeof label, "sparse case %d", c);
        std::string what;
        if (!check_capped(&r, m, bl, ws, EuclideanSq(), label, &what) ||
            !check_capped(&r, m, bl, ws, Chessboard(), label, &what))
            TEST_FAIL_MSG("%s", what.c_str());
    }
    TEST_ASSERT_MSG(unions > 0 && alldir > 0, "no union of wedges (%d) or all-directions case (%d) drawn", unions,
                    alldir);
    TEST_ASSERT(rows > 0);
}

// Self-tests of the comparison: a wrong sector, an open wedge and a wrong FT
// must each be caught on some case.
void test_checker_catches_errors(void)
{
    ct_rng r;
    ct_rng_seed(&r, g_seed * 1000003u + 11);
    int wrong_sector = 0, open_wedge = 0, bad_ft = 0, tried = 0;
    for (int c = 0; c < 60; ++c) {
        const Bits m = random_bits(&r, 16);
        const Prepared bm(m.w, m.h, m.b.data());
        const Metrics me(&r, m.w, m.h);
        const auto feats = features(m);
        const uint32_t s = (uint32_t)ct_rng_range(&r, 0, 23);
        std::vector<int64_t> dt;
        std::vector<Point> ft;
        directional(bm, 24, s, me.e, dt, ft);
        Mismatch a, b, f;
        if (!check_one(m, feats, NSector(24, (s + 1) % 24), me.e, dt, ft, &a, "wrong sector"))
            ++wrong_sector;
        if (!check_one(m, feats, XSector{sector_wedge(24, s), true}, me.e, dt, ft, &b, "open wedge"))
            ++open_wedge;
        // move one FT to another feature (or off a feature)
        for (size_t i = 0; i < ft.size(); ++i)
            if (ft[i].x >= 0 && feats.size() > 1) {
                ++tried;
                ft[i].x = (ft[i].x + 1) % m.w;
                if (!check_one(m, feats, NSector(24, s), me.e, dt, ft, &f, "bad ft"))
                    ++bad_ft;
                break;
            }
    }
    TEST_ASSERT_MSG(wrong_sector > 0, "a wrong sector was never detected");
    TEST_ASSERT_MSG(open_wedge > 0, "an open wedge was never detected (closed boundaries untested)");
    TEST_ASSERT_MSG(tried == 0 || bad_ft > 0, "a corrupted FT was never detected");
}

// A hand-checked 9 x 9 case (we could not reproduce the paper's Fig. 2 from
// memory, so this is our own): features A = (7,4), B = (2,8), C = (5,1);
// sector 0 of N = 8 is 0 <= dy <= dx (x right, y down).  By hand:
//   A is in p's sector iff y <= 4 and x <= y + 3;
//   B iff x <= y - 6;   C iff y <= 1 and x <= y + 4.
// Spot checks: (0,0): A 49+16 = 65, C 25+1 = 26 -> 26.  (4,0): only C ->
// 1+1 = 2.  (6,1): none -> inf.  (0,6): B 4+4 = 8.  (1,6): none.  (3,4): A
// 16.  (8,4): none.  '.' = no feature in the sector.
void test_hand_checked_9x9(void)
{
    static const char *expect[9] = {
        // x = 0    1    2    3    4    5    6    7    8
        "26   17   10   5    2    .    .    .    .",
        "25   16   9    4    1    0    .    .    .",   // row 1 holds C at x = 5
        "53   40   29   20   13   8    .    .    .",
        "50   37   26   17   10   5    2    .    .",
        "49   36   25   16   9    4    1    0    .",
        ".    .    .    .    .    .    .    .    .",
        "8    .    .    .    .    .    .    .    .",
        "5    2    .    .    .    .    .    .    .",
        "4    1    0    .    .    .    .    .    .",
    };
    Bits m;
    m.w = m.h = 9;
    m.b.assign(81, 0);
    m.b[4 * 9 + 7] = m.b[8 * 9 + 2] = m.b[1 * 9 + 5] = 1;
    // the expected table, parsed
    int64_t want[9][9];
    for (int y = 0; y < 9; ++y) {
        const char *p = expect[y];
        for (int x = 0; x < 9; ++x) {
            while (*p == ' ')
                ++p;
            if (*p == '.') {
                want[y][x] = Inf<int64_t>::value;
                ++p;
            } else {
                want[y][x] = strtoll(p, const_cast<char **>(&p), 10);
            }
        }
    }
    const Prepared bm(9, 9, m.b.data());
    std::vector<int64_t> dt;
    std::vector<Point> ft;
    directional(bm, 8, 0, EuclideanSq(), dt, ft);
    for (int y = 0; y < 9; ++y)
        for (int x = 0; x < 9; ++x)
            TEST_ASSERT_MSG(dt[(size_t)y * 9 + x] == want[y][x], "(%d,%d): got %s want %s", x, y,
                            vstr(dt[(size_t)y * 9 + x]).c_str(), vstr(want[y][x]).c_str());
    // a few FTs
    TEST_ASSERT(ft[0].x == 5 && ft[0].y == 1);
    TEST_ASSERT(ft[6 * 9].x == 2 && ft[6 * 9].y == 8);
    TEST_ASSERT(ft[4 * 9 + 3].x == 7 && ft[4 * 9 + 3].y == 4);
    TEST_ASSERT(ft[4 * 9 + 8].x == -1 && ft[4 * 9 + 8].y == -1);
    // unconstrained at (8,0): nearest of A (1,4)->17, C (3,1)->10
    unconstrained(bm, EuclideanSq(), dt, ft);
    TEST_ASSERT_EQUAL_INT(10, dt[8]);
}

void test_bad_arguments(void)
{
    const uint8_t one = 1;
    const Prepared bm(1, 1, &one);
    std::vector<int64_t> dt;
    std::vector<Point> ft;
    int thrown = 0;
    const Wedge bad[] = {{1, 0, 1, 0}, {0, 1, 1, 0}, {0, 0, 1, 1}, {1, 0, (int64_t)INT32_MAX + 1, 1}};
    for (const Wedge &w : bad) {
        try {
            directional(bm, w, EuclideanSq(), dt, ft);
        } catch (const std::exception &) {
            ++thrown;
        }
    }
    TEST_ASSERT_EQUAL_INT(4, thrown);
    thrown = 0;
    try {
        directional(bm, 24, 24, EuclideanSq(), dt, ft);
    } catch (const std::exception &) {
        ++thrown;
    }
    try {
        Prepared z(0, 5, &one);
    } catch (const std::exception &) {
        ++thrown;
    }
    TEST_ASSERT_EQUAL_INT(2, thrown);
}

}  // namespace

int main(void)
{
    g_seed = env_u64("CT_DDT_SEED", 1);
    g_cases = (int)env_u64("CT_DDT_CASES", 800);
    TEST_BEGIN("test_ddt");
    RUN_TEST(test_hand_checked_9x9);
    RUN_TEST(test_checker_catches_errors);
    RUN_TEST(test_bad_arguments);
    RUN_TEST(test_octants_n8);
    RUN_TEST(test_sectors_n24);
    RUN_TEST(test_quadrants_n4);
    RUN_TEST(test_sectors_n64);
    RUN_TEST(test_wide_sectors_n123);
    RUN_TEST(test_random_sector_pairs);
    RUN_TEST(test_unconstrained);
    RUN_TEST(test_large_bitmaps);
    RUN_TEST(test_euclidean_pruning);
    RUN_TEST(test_rules_off_same_result);
    RUN_TEST(test_distances_only);
    RUN_TEST(test_capped_queries);
    return TEST_END();
}
