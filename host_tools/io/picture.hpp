// picture.hpp -- small RGB pictures for `conetrace render`, `demo`, `view`,
// `viewshed` and `shadows`: a package's terrain, an image buffer with points,
// lines and 3x5-pixel digits, the viridis colour map, a hillshade of a
// terrain painted post by post, and an atomic PNG writer (libpng).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "conetrace.h"
#include "terrain.hpp"

namespace ct_host {

// An opened package's terrain: its height codes, georeference (origin,
// posting, EPSG) and height coding, for pictures of a package.
Terrain terrain_from_package(const ct_package &p);

struct Rgb {
    uint8_t r, g, b;
};
constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kInk{20, 20, 20};

// Viridis (matplotlib's), 11 anchors at t = 0, 0.1, ..., 1, linear between;
// t is clamped to [0, 1].
Rgb viridis(double t);

// a + f (b - a) per channel, rounded.
Rgb mix(Rgb a, Rgb b, double f);

struct Image {
    int w = 0, h = 0;
    std::vector<uint8_t> px;  // RGB, rows top to bottom
    Image(int w_, int h_) : w(w_), h(h_), px((size_t)w_ * h_ * 3, 255) {}
    void set(int x, int y, Rgb c)  // ignored outside the image
    {
        if (x < 0 || y < 0 || x >= w || y >= h) return;
        uint8_t *p = &px[((size_t)y * w + x) * 3];
        p[0] = c.r, p[1] = c.g, p[2] = c.b;
    }
    Rgb get(int x, int y) const
    {
        const uint8_t *p = &px[((size_t)y * w + x) * 3];
        return Rgb{p[0], p[1], p[2]};
    }
    // a segment (Bresenham), a filled disc and a ring of radius r
    void line(int x0, int y0, int x1, int y1, Rgb c);
    void disc(int cx, int cy, int r, Rgb c);
};

// Digits, '.', '-', 'o' (3 x 5 glyphs, each pixel scale x scale) in ink.
void draw_text(Image &im, int x, int y, const std::string &s, int scale);

// Hillshade in [0, 1] per coarse cell of r x r cells (mean over its fine
// cells; wc x hc coarse cells), light from the NW, 45 deg up.
std::vector<double> hillshade(const Terrain &t, int r, int wc, int hc);

// Posts i0..i1 x j0..j1 of t as zoom x zoom blocks (post (i, j) at pixel
// ((i - i0) zoom, (j - j0) zoom)), each coloured by colour(i, j, s) with s
// the hillshade (r = 1) of the cell at (min(i, width - 2), min(j, height - 2)).
void paint_posts(Image &im, const Terrain &t, int i0, int j0, int i1, int j1, int zoom,
                 const std::function<Rgb(int i, int j, double s)> &colour);

// Write a PNG (description and software in its text chunks) through a
// temporary file renamed into place: never a partial file.  Throws Error
// naming the path and the reason.
void write_png_atomic(const std::string &path, const Image &im, const std::string &desc,
                      const std::string &software);

}  // namespace ct_host
