// reference.hpp -- independent reference tracer in long double (tests only).
//
// It shares no code with lib/src/trace.c: a "thick" grid walk (every cell
// whose closed footprint the ray's 2D path touches, found by walking the
// cells of the path and testing their 3x3 neighbourhoods), and per cell the
// quadratic f(t) = z(t) - S(x(t), y(t)) in world coordinates solved for its
// first root on the cell's closed t-interval.  Inputs are the prepared ray's
// integers converted to long double exactly.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace ref {

typedef long double ld;

struct Dem {
    int w = 0, h = 0;            // posts
    std::vector<int32_t> z;      // codes
    int32_t at(int i, int j) const { return z[(size_t)j * w + i]; }
};

// Narrows [*lo, *hi] to the t where (ox, oy) + t (dx, dy) lies in the box
// [0, W] x [0, H]; false when the line misses the box (or *hi < *lo).
inline bool clip_box(ld ox, ld oy, ld dx, ld dy, ld W, ld H, ld *lo, ld *hi)
{
    auto axis = [&](ld o, ld u, ld top) {
        if (u == 0) return o >= 0 && o <= top;
        ld a = (0 - o) / u, b = (top - o) / u;
        if (a > b) std::swap(a, b);
        *lo = std::max(*lo, a);
        *hi = std::min(*hi, b);
        return true;
    };
    return axis(ox, dx, W) && axis(oy, dy, H) && *hi >= *lo;
}

struct Ray {
    ld ox, oy, oz;  // cells, cells, LSB
    ld dx, dy, dz;  // per unit t
    ld tend;        // the ray ends here (tile box exit)
    ld kz = 0;      // bent rays: z(t) = oz + t dz + kz t^2 (LSB per t^2)
};

enum { MISS = 0, HIT = 1, BELOW = 2 };

struct Hit {
    int status = MISS;
    ld t = 0, x = 0, y = 0, z = 0;
    int ci = -1, cj = -1;
    long cells = 0;
};

// f at t within cell (i, j) (S extended bilinearly)
inline ld f_cell(const Dem &d, int i, int j, const Ray &r, ld t)
{
    ld u = r.ox + t * r.dx - i, v = r.oy + t * r.dy - j;
    ld h00 = d.at(i, j), h10 = d.at(i + 1, j), h01 = d.at(i, j + 1), h11 = d.at(i + 1, j + 1);
    ld s = h00 + (h10 - h00) * u + (h01 - h00) * v + (h11 - h10 - h01 + h00) * u * v;
    return r.oz + t * r.dz + r.kz * t * t - s;
}

// Surface height at (x, y) inside the tile.
inline ld surface(const Dem &d, ld x, ld y)
{
    int i = std::min(d.w - 2, std::max(0, (int)std::floor(x)));
    int j = std::min(d.h - 2, std::max(0, (int)std::floor(y)));
    ld u = x - i, v = y - j;
    ld h00 = d.at(i, j), h10 = d.at(i + 1, j), h01 = d.at(i, j + 1), h11 = d.at(i + 1, j + 1);
    return h00 + (h10 - h00) * u + (h01 - h00) * v + (h11 - h10 - h01 + h00) * u * v;
}

// t-interval of the ray inside the closed cell footprint, clipped to [0, tend]
inline bool cell_interval(const Ray &r, int i, int j, ld *t0, ld *t1)
{
    ld lo = 0, hi = r.tend;
    auto axis = [&](ld o, ld dd, ld a, ld b) {
        if (dd == 0) return o >= a && o <= b;
        ld ta = (a - o) / dd, tb = (b - o) / dd;
        if (ta > tb) std::swap(ta, tb);
        lo = std::max(lo, ta);
        hi = std::min(hi, tb);
        return true;
    };
    if (!axis(r.ox, r.dx, i, i + 1) || !axis(r.oy, r.dy, j, j + 1)) return false;
    *t0 = lo;
    *t1 = hi;
    return lo <= hi;
}

// First t in [t0, t1] with f <= 0 (touch counts), or -1.
inline ld first_root(const Dem &d, int i, int j, const Ray &r, ld t0, ld t1)
{
    ld h00 = d.at(i, j), h10 = d.at(i + 1, j), h01 = d.at(i, j + 1), h11 = d.at(i + 1, j + 1);
    ld a = h10 - h00, b = h01 - h00, c = h11 - h10 - h01 + h00;
    ld u0 = r.ox - i, v0 = r.oy - j;
    // f(t) = A t^2 + B t + C
    ld A = -c * r.dx * r.dy + r.kz;
    ld B = r.dz - a * r.dx - b * r.dy - c * (u0 * r.dy + v0 * r.dx);
    ld C = r.oz - h00 - a * u0 - b * v0 - c * u0 * v0;
    auto f = [&](ld t) { return (A * t + B) * t + C; };
    if (f(t0) <= 0) return t0;
    // candidate roots
    ld roots[2];
    int nr = 0;
    if (A == 0) {
        if (B != 0) roots[nr++] = -C / B;
    } else {
        ld D = B * B - 4 * A * C;
        if (D >= 0) {
            ld sq = std::sqrt(D);
            ld q = -0.5L * (B + (B >= 0 ? sq : -sq));
            if (q != 0) {
                roots[nr++] = q / A;
                roots[nr++] = C / q;
            } else {
                roots[nr++] = -B / (2 * A);
            }
        }
    }
    ld best = -1;
    for (int k = 0; k < nr; ++k) {
        ld t = roots[k];
        if (t >= t0 && t <= t1 && (best < 0 || t < best)) best = t;
    }
    if (best < 0 && f(t1) <= 0) best = t1;  // rounding at the far end
    return best;
}

// The reference first hit.
inline Hit trace(const Dem &d, const Ray &r)
{
    Hit h;
    int cw = d.w - 1, chh = d.h - 1;
    // start point
    {
        ld x = r.ox, y = r.oy;
        if (x >= 0 && y >= 0 && x <= cw && y <= chh) {
            ld f0 = r.oz - surface(d, x, y);
            if (f0 < 0) {
                h.status = BELOW;
                return h;
            }
            if (f0 == 0) {
                h.status = HIT;
                h.t = 0;
                h.x = x;
                h.y = y;
                h.z = r.oz;
                h.ci = std::min(cw - 1, (int)std::floor(x));
                h.cj = std::min(chh - 1, (int)std::floor(y));
                return h;
            }
        }
    }
    // walk the cells of the 2D path (long double DDA), testing 3x3 blocks
    std::vector<uint32_t> stamp;  // tested cells (small local set)
    std::vector<std::pair<int, int>> tested;
    ld best = -1;
    int bi = -1, bj = -1;
    auto test = [&](int i, int j) {
        if (i < 0 || j < 0 || i >= cw || j >= chh) return;
        for (auto &p : tested)
            if (p.first == i && p.second == j) return;
        tested.push_back({i, j});
        if (tested.size() > 64) tested.erase(tested.begin(), tested.begin() + 32);
        ld t0, t1;
        if (!cell_interval(r, i, j, &t0, &t1)) return;
        h.cells++;
        ld t = first_root(d, i, j, r, t0, t1);
        if (t >= 0 && (best < 0 || t < best || (t == best && (j < bj || (j == bj && i < bi))))) {
            best = t;
            bi = i;
            bj = j;
        }
    };
    if (r.dx == 0 && r.dy == 0) {
        int i = std::min(cw - 1, std::max(0, (int)std::floor(r.ox)));
        int j = std::min(chh - 1, std::max(0, (int)std::floor(r.oy)));
        for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) test(i + di, j + dj);
    } else {
        ld t = 0;
        int guard = 4 * (cw + chh) + 16;
        while (t <= r.tend && guard-- > 0) {
            ld x = r.ox + t * r.dx, y = r.oy + t * r.dy;
            int i = (int)std::floor(x), j = (int)std::floor(y);
            for (int dj = -1; dj <= 1; ++dj)
                for (int di = -1; di <= 1; ++di) test(i + di, j + dj);
            if (best >= 0 && best < t) break;
            // next grid line crossing after t
            ld tn = std::numeric_limits<ld>::infinity();
            if (r.dx != 0) {
                ld nx = r.dx > 0 ? std::floor(x) + 1 : std::ceil(x) - 1;
                tn = std::min(tn, (nx - r.ox) / r.dx);
            }
            if (r.dy != 0) {
                ld ny = r.dy > 0 ? std::floor(y) + 1 : std::ceil(y) - 1;
                tn = std::min(tn, (ny - r.oy) / r.dy);
            }
            if (!(tn > t)) tn = t + 1e-12L;
            t = tn;
        }
    }
    if (best >= 0) {
        h.status = HIT;
        h.t = best;
        h.x = r.ox + best * r.dx;
        h.y = r.oy + best * r.dy;
        h.z = r.oz + best * r.dz + r.kz * best * best;
        h.ci = bi;
        h.cj = bj;
    }
    return h;
}

// Minimum of f along the ray over [ta, tb] (analytic per cell).
inline ld min_clearance(const Dem &d, const Ray &r, ld ta, ld tb)
{
    int cw = d.w - 1, chh = d.h - 1;
    ld m = std::numeric_limits<ld>::infinity();
    ta = std::max<ld>(0, ta);
    tb = std::min(r.tend, tb);
    if (tb < ta) return m;
    int ia = (int)std::floor(std::min(r.ox + ta * r.dx, r.ox + tb * r.dx)) - 1;
    int ib = (int)std::floor(std::max(r.ox + ta * r.dx, r.ox + tb * r.dx)) + 1;
    int ja = (int)std::floor(std::min(r.oy + ta * r.dy, r.oy + tb * r.dy)) - 1;
    int jb = (int)std::floor(std::max(r.oy + ta * r.dy, r.oy + tb * r.dy)) + 1;
    ia = std::max(0, ia);
    ja = std::max(0, ja);
    ib = std::min(cw - 1, ib);
    jb = std::min(chh - 1, jb);
    if ((long)(ib - ia + 1) * (jb - ja + 1) > 4000000L) return -std::numeric_limits<ld>::infinity();
    for (int j = ja; j <= jb; ++j)
        for (int i = ia; i <= ib; ++i) {
            ld t0, t1;
            if (!cell_interval(r, i, j, &t0, &t1)) continue;
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
            if (t1 < t0) continue;
            m = std::min(m, f_cell(d, i, j, r, t0));
            m = std::min(m, f_cell(d, i, j, r, t1));
            ld h00 = d.at(i, j), h10 = d.at(i + 1, j), h01 = d.at(i, j + 1), h11 = d.at(i + 1, j + 1);
            ld c = h11 - h10 - h01 + h00;
            ld A = -c * r.dx * r.dy + r.kz;
            if (A > 0) {
                ld a = h10 - h00, b = h01 - h00, u0 = r.ox - i, v0 = r.oy - j;
                ld B = r.dz - a * r.dx - b * r.dy - c * (u0 * r.dy + v0 * r.dx);
                ld tv = -B / (2 * A);
                if (tv > t0 && tv < t1) m = std::min(m, f_cell(d, i, j, r, tv));
            }
        }
    return m;
}

}  // namespace ref
