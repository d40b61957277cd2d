// render.hpp -- pictures of cross-sections, distance transforms and PPTs
// (`conetrace render`; host side, C++17).
//
// Everything works on cells (posts - 1 per side), like the builders: a
// cell's height is its tallest corner, a cross-section at level H is the
// bitmap "cell height >= H" (1 = feature = terrain reaches the slice).
// Colours: distances on a perceptual ramp (dark blue -> green -> yellow,
// viridis-like) scaled to the largest finite distance shown; feature pixels
// (distance 0) black; "no feature in the sector" (infinite distance) pale
// pink; opening angles on the same ramp from 0 to 90 degrees (wider ones
// at the top colour) with
// degenerate cones red; apex heights grey from the lowest to the highest.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "conetrace.h"
#include "terrain.hpp"

namespace ct_host {
namespace render {

struct Image {
    int w = 0, h = 0;
    std::vector<uint8_t> rgb;  // row-major, 3 bytes per pixel
    Image() = default;
    Image(int w_, int h_, uint8_t grey = 255) : w(w_), h(h_), rgb((size_t)w_ * h_ * 3, grey) {}
    void set(int x, int y, std::array<uint8_t, 3> c)
    {
        uint8_t *p = &rgb[((size_t)y * w + x) * 3];
        p[0] = c[0], p[1] = c[1], p[2] = c[2];
    }
    std::array<uint8_t, 3> at(int x, int y) const
    {
        const uint8_t *p = &rgb[((size_t)y * w + x) * 3];
        return {p[0], p[1], p[2]};
    }
};

constexpr std::array<uint8_t, 3> FEATURE{0, 0, 0};
constexpr std::array<uint8_t, 3> NO_FEATURE{250, 214, 236};
constexpr std::array<uint8_t, 3> DEGENERATE{220, 30, 30};

// The ramp at t in [0, 1] (clamped).
std::array<uint8_t, 3> ramp(double t);

// Cell heights (tallest corner) in metres.
struct Cells {
    int w = 0, h = 0;
    std::vector<double> top_m;
};
Cells cells_from_terrain(const Terrain &t);
Cells cells_from_package(const ct_package &p);

// Cross-section: 1 where the cell's height >= level_m.
std::vector<uint8_t> cross_section(const Cells &c, double level_m);

// Hillshade of the cells (light from the north-west) with the bitmap's
// features drawn dark brown on it.
Image bitmap_image(const Cells &c, const std::vector<uint8_t> &bits);

// Squared Euclidean distances (INT64_MAX = none) as a picture; dmax > 0 is
// the distance shown as the ramp's top.
Image distance_image(int w, int h, const std::vector<int64_t> &d2, double dmax);
// Largest finite sqrt(d2) (0 if none).
double max_distance(const std::vector<int64_t> &d2);

// The package's opening angles of plane `plane` (0..planes-1; N is the
// omnidirectional plane) and its apex heights, one pixel per coarse cell.
Image angle_image(const ct_package &p, uint32_t plane);
Image apex_image(const ct_package &p);

// Panels side by side with `gap` white columns between them.
Image side_by_side(const std::vector<Image> &panels, int gap);
// Nearest-neighbour enlargement by an integer factor k >= 1.
Image enlarge(const Image &im, int k);

// Write a PNG through OpenImageIO, atomically (temporary file + rename).
// Throws ct_host::Error("<path>: <reason>").
void write_png(const std::string &path, const Image &im);

}  // namespace render
}  // namespace ct_host
