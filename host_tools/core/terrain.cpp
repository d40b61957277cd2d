// terrain.cpp -- quantising metres to 16-bit codes.
#include "terrain.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace ct_host {

int64_t metres_to_nm(double m)
{
    if (!(std::fabs(m) < 4.0e9)) {
        throw Error("value out of range for nanometre storage");
    }
    return (int64_t)std::llround(m * 1e9);
}

double choose_height_scale(double lo, double hi, double scale_m)
{
    const double range = hi - lo;
    if (scale_m <= 0.0) {
        // finest power-of-two LSB (at most 1/16 m) that keeps the range
        // within 60000 codes
        scale_m = 1.0 / 16.0;
        while (range / scale_m > 60000.0) {
            scale_m *= 2.0;
        }
    }
    if (range / scale_m > 65535.0) {
        std::ostringstream os;
        os << "height range " << range << " m does not fit 16 bits at " << scale_m << " m per LSB";
        throw Error(os.str());
    }
    return scale_m;
}

std::string too_wide_for_package(int width, int height)
{
    std::ostringstream os;
    os << "DEM of " << width << "x" << height << " posts exceeds the package limit of " << kMaxPackagePosts
       << " per side (a tile set, build --tile-size P|auto, holds up to " << kMaxTileSetDemPosts << ")";
    return os.str();
}

Terrain terrain_from_heights(int width, int height, const std::vector<double> &h_m,
                             const std::vector<uint8_t> &valid, const Georef &geo, double scale_m)
{
    if (width < 2 || height < 2) {
        throw Error("DEM must have at least 2x2 posts");
    }
    if (width > kMaxPackagePosts || height > kMaxPackagePosts) throw Error(too_wide_for_package(width, height));
    size_t n = (size_t)width * (size_t)height;
    if (h_m.size() != n || (!valid.empty() && valid.size() != n)) {
        throw Error("height array size does not match the dimensions");
    }
    HeightRange r;
    for (size_t k = 0; k < n; ++k) r.add(h_m[k], valid.empty() || valid[k]);
    const size_t nvalid = r.nvalid;
    const double lo = r.lo, hi = r.hi;
    if (nvalid == 0) {
        throw Error("every sample is nodata");
    }
    scale_m = choose_height_scale(lo, hi, scale_m);
    Terrain t;
    t.width = width;
    t.height = height;
    t.geo = geo;
    t.height_offset_m = lo;
    t.height_scale_m = scale_m;
    t.codes.resize(n);
    if (nvalid != n) {
        t.void_post.assign(n, 0);
    }
    for (size_t k = 0; k < n; ++k) {
        bool ok = (valid.empty() || valid[k]) && std::isfinite(h_m[k]);
        if (!ok) {
            t.codes[k] = 0; // voids are filled with the lowest height
            t.void_post[k] = 1;
            continue;
        }
        t.codes[k] = height_code(h_m[k], lo, scale_m);
    }
    return t;
}

}  // namespace ct_host
