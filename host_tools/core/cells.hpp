// cells.hpp -- cell heights as every host tool computes them (the builder,
// the mipmap writer, `conetrace render`): a fine cell's height, the coarse
// cells' tops, one 2x2 step of a max pyramid and the slice levels.  One copy
// each, so the package, the builders and the pictures agree.  Units: height
// codes (uint16), fine cells.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "terrain.hpp"

namespace ct_host {

// A fine cell's height: the tallest of its four posts.
inline uint16_t fine_max(const Terrain &t, int i, int j)
{
    const size_t k = (size_t)j * (size_t)t.width + (size_t)i, w = (size_t)t.width;
    return std::max(std::max(t.codes[k], t.codes[k + 1]), std::max(t.codes[k + w], t.codes[k + w + 1]));
}

// Coarse cell tops for reduction r: the tallest fine cell of each r x r block;
// wc x hc = ceil((width - 1) / r) x ceil((height - 1) / r), row-major.
inline std::vector<uint16_t> cell_tops(const Terrain &t, int r, int &wc, int &hc)
{
    const int cx = t.width - 1, cy = t.height - 1;
    wc = (cx + r - 1) / r;
    hc = (cy + r - 1) / r;
    std::vector<uint16_t> top((size_t)wc * hc, 0);
    for (int j = 0; j < cy; ++j)
        for (int i = 0; i < cx; ++i) {
            uint16_t &d = top[(size_t)(j / r) * wc + i / r];
            d = std::max(d, fine_max(t, i, j));
        }
    return top;
}

// One level of a max pyramid: from a pw x ph level (values at(i, j)) to the
// next, (pw + 1) / 2 x (ph + 1) / 2, each the max of its (up to) 2x2 children.
template <class At>
std::vector<uint16_t> max_pyramid_step(int pw, int ph, At at)
{
    const int nw = (pw + 1) / 2, nh = (ph + 1) / 2;
    std::vector<uint16_t> next((size_t)nw * nh, 0);
    for (int j = 0; j < ph; ++j)
        for (int i = 0; i < pw; ++i) {
            uint16_t &d = next[(size_t)(j / 2) * nw + i / 2];
            d = std::max(d, (uint16_t)at(i, j));
        }
    return next;
}

// Slice level k of K evenly spaced between the DEM's lowest and highest codes
// (0 <= k <= K, K >= 1): L_k = ceil(hmin + k (hmax - hmin) / K), rounded up
// (a level is a height at which a slice is cut), within [hmin, hmax], L_K = hmax.
inline int slice_level(int hmin, int hmax, int K, int k)
{
    if (k >= K) return hmax;
    const int l = (int)std::ceil(hmin + (double)k * (hmax - hmin) / K - 1e-9);
    return std::clamp<int>(l, hmin, hmax);
}

}  // namespace ct_host
