// picture.cpp -- see picture.hpp.
#include "picture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <png.h>

#include "host_io.hpp"
#include "le.hpp"

namespace ct_host {

Terrain terrain_from_package(const ct_package &p)
{
    Terrain t;
    t.width = (int)p.width;
    t.height = (int)p.height;
    t.codes.resize((size_t)p.width * p.height);
    for (size_t k = 0; k < t.codes.size(); ++k) t.codes[k] = get16(p.heights + 2 * k);
    t.geo.origin_e = p.origin_e_nm * 1e-9;
    t.geo.origin_n = p.origin_n_nm * 1e-9;
    t.geo.posting_e = p.posting_e_nm * 1e-9;
    t.geo.posting_n = p.posting_n_nm * 1e-9;
    t.geo.epsg = (int)p.epsg;
    t.height_offset_m = p.height_offset_nm * 1e-9;
    t.height_scale_m = p.height_scale_nm * 1e-9;
    return t;
}

// Viridis (matplotlib's), 11 anchors at t = 0, 0.1, ..., 1, linear between.
Rgb viridis(double t)
{
    static const uint8_t a[11][3] = {{68, 1, 84},    {72, 36, 117},  {65, 68, 135},  {53, 95, 141},
                                     {42, 120, 142}, {33, 145, 140}, {34, 168, 132}, {68, 191, 112},
                                     {122, 209, 81}, {189, 223, 38}, {253, 231, 37}};
    t = std::min(1.0, std::max(0.0, t)) * 10.0;
    int k = std::min(9, (int)t);
    double f = t - k;
    auto mix = [&](int c) { return (uint8_t)std::lround(a[k][c] + f * (a[k + 1][c] - a[k][c])); };
    return Rgb{mix(0), mix(1), mix(2)};
}

Rgb mix(Rgb a, Rgb b, double f)
{
    auto m = [&](uint8_t x, uint8_t y) { return (uint8_t)std::lround(x + f * (y - x)); };
    return Rgb{m(a.r, b.r), m(a.g, b.g), m(a.b, b.b)};
}

void Image::line(int x0, int y0, int x1, int y1, Rgb c)
{
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0), sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    for (;;) {  // at most dx - dy + 1 points
        set(x0, y0, c);
        if (x0 == x1 && y0 == y1) break;
        const int e2 = 2 * err;
        if (e2 >= dy) {
            err += dy;
            x0 += sx;
        }
        if (e2 <= dx) {
            err += dx;
            y0 += sy;
        }
    }
}

void Image::disc(int cx, int cy, int r, Rgb c)
{
    for (int y = -r; y <= r; ++y)
        for (int x = -r; x <= r; ++x)
            if (x * x + y * y <= r * r + r) set(cx + x, cy + y, c);
}

// 3 x 5 digits and a few signs, bit 14 = top-left.
void draw_text(Image &im, int x, int y, const std::string &s, int scale)
{
    auto glyph = [](char ch) -> unsigned {
        switch (ch) {
        case '0': return 075557;
        case '1': return 026227;
        case '2': return 071747;
        case '3': return 071717;
        case '4': return 055711;
        case '5': return 074717;
        case '6': return 074757;
        case '7': return 071111;
        case '8': return 075757;
        case '9': return 075717;
        case '.': return 000002;
        case '-': return 000700;
        case 'o': return 000757;  // "omni"
        default: return 0;
        }
    };
    for (char ch : s) {
        unsigned g = glyph(ch);
        for (int r = 0; r < 5; ++r)
            for (int c = 0; c < 3; ++c)
                if (g & (1u << (14 - (r * 3 + c))))
                    for (int a = 0; a < scale; ++a)
                        for (int b = 0; b < scale; ++b) im.set(x + c * scale + b, y + r * scale + a, kInk);
        x += 4 * scale;
    }
}

// Hillshade in [0, 1] per coarse cell (mean over its fine cells), light from
// azimuth 315 deg (NW), 45 deg up; gradients from the cell's four posts.
std::vector<double> hillshade(const Terrain &t, int r, int wc, int hc)
{
    const int cx = t.width - 1, cy = t.height - 1;
    const double post = std::fabs(t.geo.posting_e) > 0 ? std::fabs(t.geo.posting_e) : 1.0;
    const double alt = M_PI / 4, az = 7 * M_PI / 4;  // from north, clockwise
    // light vector in (east, south, up)
    const double lx = std::cos(alt) * std::sin(az), ly = -std::cos(alt) * std::cos(az), lz = std::sin(alt);
    std::vector<double> sum((size_t)wc * hc, 0.0);
    std::vector<int> cnt((size_t)wc * hc, 0);
    for (int j = 0; j < cy; ++j)
        for (int i = 0; i < cx; ++i) {
            double z00 = t.at(i, j), z10 = t.at(i + 1, j), z01 = t.at(i, j + 1), z11 = t.at(i + 1, j + 1);
            double s = t.height_scale_m / post;
            double gx = 0.5 * ((z10 + z11) - (z00 + z01)) * s, gy = 0.5 * ((z01 + z11) - (z00 + z10)) * s;
            double nrm = std::sqrt(gx * gx + gy * gy + 1.0);
            double sh = std::max(0.0, (-gx * lx - gy * ly + lz) / nrm);
            size_t k = (size_t)(j / r) * wc + i / r;
            sum[k] += sh;
            cnt[k] += 1;
        }
    for (size_t k = 0; k < sum.size(); ++k) sum[k] = cnt[k] ? sum[k] / cnt[k] : 1.0;
    return sum;
}

void paint_posts(Image &im, const Terrain &t, int i0, int j0, int i1, int j1, int zoom,
                 const std::function<Rgb(int i, int j, double s)> &colour)
{
    const std::vector<double> shade = hillshade(t, 1, t.width - 1, t.height - 1);
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
            const double s = shade[(size_t)std::min(j, t.height - 2) * (t.width - 1) + std::min(i, t.width - 2)];
            const Rgb c = colour(i, j, s);
            for (int y = 0; y < zoom; ++y)
                for (int x = 0; x < zoom; ++x) im.set((i - i0) * zoom + x, (j - j0) * zoom + y, c);
        }
}

namespace {

struct PngError {
    char text[200];
};

void png_fail(png_structp png, png_const_charp msg)
{
    PngError *e = static_cast<PngError *>(png_get_error_ptr(png));
    std::snprintf(e->text, sizeof e->text, "%s", msg ? msg : "libpng error");
    png_longjmp(png, 1);
}

void png_warn(png_structp, png_const_charp) {}

// libpng's output callback: append to the std::vector<uint8_t> behind the
// io pointer (an allocation failure becomes a libpng error, never an
// exception through libpng's C frames).
void png_append(png_structp png, png_bytep data, size_t n)
{
    auto *out = static_cast<std::vector<uint8_t> *>(png_get_io_ptr(png));
    try {
        out->insert(out->end(), data, data + n);
    } catch (...) {
        png_error(png, "out of memory");
    }
}

void png_flush_none(png_structp) {}

// The RGB rows of an image as PNG bytes appended to *out, with Description
// and Software text chunks (the keys OpenImageIO reads as ImageDescription
// and Software).  libpng reports errors by longjmp to this frame, so it
// holds only plain C objects; false with err->text set on failure.
bool png_to_bytes(std::vector<uint8_t> *out, int w, int h, const uint8_t *px, const char *desc, const char *software,
                  PngError *err)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, err, png_fail, png_warn);
    if (!png) {
        std::snprintf(err->text, sizeof err->text, "out of memory");
        return false;
    }
    png_infop info = png_create_info_struct(png);
    if (!info || setjmp(png_jmpbuf(png))) {
        if (!info) std::snprintf(err->text, sizeof err->text, "out of memory");
        png_destroy_write_struct(&png, info ? &info : nullptr);
        return false;
    }
    png_set_write_fn(png, out, png_append, png_flush_none);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_text text[2];
    std::memset(text, 0, sizeof text);
    text[0].compression = PNG_TEXT_COMPRESSION_NONE;
    text[0].key = const_cast<char *>("Description");
    text[0].text = const_cast<char *>(desc);
    text[1].compression = PNG_TEXT_COMPRESSION_NONE;
    text[1].key = const_cast<char *>("Software");
    text[1].text = const_cast<char *>(software);
    png_set_text(png, info, text, 2);
    png_write_info(png, info);
    for (int y = 0; y < h; ++y) png_write_row(png, px + (size_t)y * (size_t)w * 3);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return true;
}

}  // namespace

void write_png_atomic(const std::string &path, const Image &im, const std::string &desc,
                      const std::string &software)
{
    std::vector<uint8_t> bytes;
    PngError err{};
    if (!png_to_bytes(&bytes, im.w, im.h, im.px.data(), desc.c_str(), software.c_str(), &err))
        throw Error(path + ": cannot write (" + std::string(err.text) + ")");
    write_file_atomic(path, bytes);  // temporary file, renamed: "<path>: cannot write (<reason>)"
}

}  // namespace ct_host
