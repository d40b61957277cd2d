// render.cpp -- see render.hpp.
#include "render.hpp"

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace ct_host {
namespace render {

std::array<uint8_t, 3> ramp(double t)
{
    // viridis-like stops
    static const double stops[6][3] = {{68, 1, 84},   {65, 68, 135},  {42, 120, 142},
                                       {34, 168, 132}, {122, 209, 81}, {253, 231, 37}};
    if (!(t > 0.0)) t = 0.0;
    if (t > 1.0) t = 1.0;
    double x = t * 5.0;
    int i = std::min(4, (int)x);
    double f = x - i;
    std::array<uint8_t, 3> c;
    for (int k = 0; k < 3; ++k) c[(size_t)k] = (uint8_t)std::lround(stops[i][k] * (1.0 - f) + stops[i + 1][k] * f);
    return c;
}

Cells cells_from_terrain(const Terrain &t)
{
    Cells c;
    c.w = t.width - 1;
    c.h = t.height - 1;
    c.top_m.resize((size_t)c.w * c.h);
    for (int j = 0; j < c.h; ++j)
        for (int i = 0; i < c.w; ++i) {
            int m = std::max(std::max(t.at(i, j), t.at(i + 1, j)), std::max(t.at(i, j + 1), t.at(i + 1, j + 1)));
            c.top_m[(size_t)j * c.w + i] = t.height_offset_m + m * t.height_scale_m;
        }
    return c;
}

Cells cells_from_package(const ct_package &p)
{
    Cells c;
    c.w = (int)p.cells_x;
    c.h = (int)p.cells_y;
    c.top_m.resize((size_t)c.w * c.h);
    auto at = [&](uint32_t i, uint32_t j) {
        size_t k = 2 * ((size_t)j * p.width + i);
        return (int)(p.heights[k] | (p.heights[k + 1] << 8));
    };
    for (uint32_t j = 0; j < p.cells_y; ++j)
        for (uint32_t i = 0; i < p.cells_x; ++i) {
            int m = std::max(std::max(at(i, j), at(i + 1, j)), std::max(at(i, j + 1), at(i + 1, j + 1)));
            c.top_m[(size_t)j * c.w + i] = (p.height_offset_nm + m * (double)p.height_scale_nm) * 1e-9;
        }
    return c;
}

std::vector<uint8_t> cross_section(const Cells &c, double level_m)
{
    std::vector<uint8_t> b(c.top_m.size());
    for (size_t k = 0; k < b.size(); ++k) b[k] = c.top_m[k] >= level_m;
    return b;
}

Image bitmap_image(const Cells &c, const std::vector<uint8_t> &bits)
{
    Image im(c.w, c.h);
    double lo = *std::min_element(c.top_m.begin(), c.top_m.end());
    double hi = *std::max_element(c.top_m.begin(), c.top_m.end());
    double span = std::max(1e-9, hi - lo);
    for (int j = 0; j < c.h; ++j)
        for (int i = 0; i < c.w; ++i) {
            auto z = [&](int x, int y) {
                x = std::clamp(x, 0, c.w - 1);
                y = std::clamp(y, 0, c.h - 1);
                return c.top_m[(size_t)y * c.w + x];
            };
            // slope towards the light (north-west), exaggerated to the range
            double gx = (z(i + 1, j) - z(i - 1, j)) / span * 40.0, gy = (z(i, j + 1) - z(i, j - 1)) / span * 40.0;
            double shade = std::clamp(0.78 + 0.22 * (gx + gy) / std::sqrt(1.0 + gx * gx + gy * gy), 0.0, 1.0);
            if (bits[(size_t)j * c.w + i]) {
                im.set(i, j, {(uint8_t)std::lround(110 * shade), (uint8_t)std::lround(62 * shade),
                              (uint8_t)std::lround(30 * shade)});
            } else {
                uint8_t g = (uint8_t)std::lround(255 * shade);
                im.set(i, j, {g, g, g});
            }
        }
    return im;
}

double max_distance(const std::vector<int64_t> &d2)
{
    int64_t m = 0;
    for (int64_t v : d2)
        if (v != std::numeric_limits<int64_t>::max()) m = std::max(m, v);
    return std::sqrt((double)m);
}

Image distance_image(int w, int h, const std::vector<int64_t> &d2, double dmax)
{
    Image im(w, h);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            int64_t v = d2[(size_t)j * w + i];
            if (v == 0)
                im.set(i, j, FEATURE);
            else if (v == std::numeric_limits<int64_t>::max())
                im.set(i, j, NO_FEATURE);
            else
                im.set(i, j, ramp(std::sqrt((double)v) / dmax));
        }
    return im;
}

Image angle_image(const ct_package &p, uint32_t plane)
{
    if (plane >= p.planes) throw Error("angle plane " + std::to_string(plane) + " outside 0.." + std::to_string(p.planes - 1));
    Image im((int)p.coarse_x, (int)p.coarse_y);
    const uint8_t *a = p.angles + (size_t)plane * p.coarse_x * p.coarse_y;
    for (uint32_t j = 0; j < p.coarse_y; ++j)
        for (uint32_t i = 0; i < p.coarse_x; ++i) {
            uint8_t code = a[(size_t)j * p.coarse_x + i];
            im.set((int)i, (int)j, p.cot_ok[code] && code != 0 ? ramp(code / 128.0) : DEGENERATE);  // 0..90 deg, wider clamped
        }
    return im;
}

Image apex_image(const ct_package &p)
{
    Image im((int)p.coarse_x, (int)p.coarse_y);
    double lo = p.hmin, span = std::max(1, p.hmax - p.hmin);
    for (uint32_t j = 0; j < p.coarse_y; ++j)
        for (uint32_t i = 0; i < p.coarse_x; ++i) {
            size_t k = 2 * ((size_t)j * p.coarse_x + i);
            int code = p.apex[k] | (p.apex[k + 1] << 8);
            uint8_t g = (uint8_t)std::lround(std::clamp((code - lo) / span, 0.0, 1.0) * 255.0);
            im.set((int)i, (int)j, {g, g, g});
        }
    return im;
}

Image side_by_side(const std::vector<Image> &panels, int gap)
{
    int w = 0, h = 0;
    for (size_t k = 0; k < panels.size(); ++k) {
        w += panels[k].w + (k ? gap : 0);
        h = std::max(h, panels[k].h);
    }
    Image out(w, h);
    int x0 = 0;
    for (const Image &p : panels) {
        for (int j = 0; j < p.h; ++j)
            for (int i = 0; i < p.w; ++i) out.set(x0 + i, j, p.at(i, j));
        x0 += p.w + gap;
    }
    return out;
}

Image enlarge(const Image &im, int k)
{
    if (k <= 1) return im;
    Image out(im.w * k, im.h * k);
    for (int j = 0; j < out.h; ++j)
        for (int i = 0; i < out.w; ++i) out.set(i, j, im.at(i / k, j / k));
    return out;
}

void write_png(const std::string &path, const Image &im)
{
    if (path.size() < 5 || path.compare(path.size() - 4, 4, ".png") != 0)
        throw Error(path + ": the output must be a .png file");
    // the temporary keeps the .png extension: OpenImageIO picks the format by it
    std::string tmp = path.substr(0, path.size() - 4) + ".tmp." + std::to_string((long)getpid()) + ".png";
    auto out = OIIO::ImageOutput::create(tmp);
    if (!out) throw Error(path + ": cannot create a PNG writer (" + OIIO::geterror() + ")");
    OIIO::ImageSpec spec(im.w, im.h, 3, OIIO::TypeDesc::UINT8);
    bool ok = out->open(tmp, spec) && out->write_image(OIIO::TypeDesc::UINT8, im.rgb.data());
    std::string err = ok ? "" : out->geterror();
    ok = out->close() && ok;
    if (!ok) {
        std::remove(tmp.c_str());
        throw Error(path + ": cannot write (" + (err.empty() ? std::string("unknown error") : err) + ")");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        std::remove(tmp.c_str());
        throw Error(path + ": cannot rename the temporary file into place");
    }
}

}  // namespace render
}  // namespace ct_host
