// dem_pixels.cpp -- the pixels of a DEM raster through OpenImageIO, in the
// file's native sample type, never rescaled (read_dem's first half; the
// georeference is dem_io.cpp's).  The only file of the DEM reader that needs
// OpenImageIO: the `conetrace` binary reaches it through the plugin
// (heavy_door.hpp), so commands that read no DEM do not load OpenImageIO.
#include "dem_io.hpp"

#include <OpenImageIO/imageio.h>

#include <sys/stat.h>

#include <algorithm>
#include <cstring>
#include <memory>

namespace ct_host {
namespace {

template <typename T>
void convert_samples(const std::vector<unsigned char> &buf, size_t n, std::vector<double> &out)
{
    out.resize(n);
    for (size_t k = 0; k < n; k++) {
        T v;
        std::memcpy(&v, buf.data() + k * sizeof(T), sizeof(T));
        out[k] = (double)v;
    }
}


// Open `path` and check what read_dem needs of it (one channel, a plain
// sample type at its full bit depth); r's size and sample type set.
std::unique_ptr<OIIO::ImageInput> open_checked(const std::string &path, DemRaster &r, bool &is_tiff)
{
    auto fail = [&](const std::string &why) { return Error(path + ": " + why); };

    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        std::string e = clipped(one_line(OIIO::geterror()));
        throw fail("cannot read image" + (e.empty() ? std::string() : ": " + e));
    }
    const OIIO::ImageSpec spec = in->spec();
    is_tiff = std::strcmp(in->format_name(), "tiff") == 0;

    if (spec.nchannels != 1)
        throw fail("has " + std::to_string(spec.nchannels) +
                   " channels; a single-channel (single-band) raster is required");
    if (spec.depth > 1) throw fail("volume images are not supported");
    if (spec.width <= 0 || spec.height <= 0) throw fail("empty image");

    const OIIO::TypeDesc fmt = spec.format;
    const char *name = nullptr;
    switch (fmt.basetype) {
    case OIIO::TypeDesc::INT8: name = "int8"; break;
    case OIIO::TypeDesc::UINT8: name = "uint8"; break;
    case OIIO::TypeDesc::INT16: name = "int16"; break;
    case OIIO::TypeDesc::UINT16: name = "uint16"; break;
    case OIIO::TypeDesc::INT32: name = "int32"; break;
    case OIIO::TypeDesc::UINT32: name = "uint32"; break;
    case OIIO::TypeDesc::FLOAT: name = "float32"; break;
    case OIIO::TypeDesc::DOUBLE: name = "float64"; break;
    default: break;
    }
    if (!name || fmt.aggregate != OIIO::TypeDesc::SCALAR || fmt.arraylen != 0)
        throw fail(std::string("unsupported sample format '") + fmt.c_str() + "'");
    // Sub-byte or odd bit depths (1/2/4/10/12-bit) are widened *and rescaled*
    // by OIIO, which would corrupt heights.
    int bits = spec.get_int_attribute("oiio:BitsPerSample", 0);
    if (bits != 0 && bits != (int)(fmt.size() * 8))
        throw fail("unsupported bit depth " + std::to_string(bits) + " (stored as " +
                   fmt.c_str() + ")");
    if (spec.tile_width > 0 && spec.tile_height > 0) {
        // OpenImageIO reads a tile whole, into a buffer of the tile's size:
        // a header whose tiles hold far more posts than the image (a 8 x 8
        // image in tiles of 28944 x 65521, 7.6 GB each) is refused before
        // that is allocated
        const double tile = (double)spec.tile_width * (double)spec.tile_height * (double)std::max(1, spec.tile_depth);
        if (tile > std::max(4.0 * (double)spec.width * (double)spec.height, 16777216.0))
            throw fail("tiles of " + std::to_string(spec.tile_width) + " x " + std::to_string(spec.tile_height) +
                       " posts for a " + std::to_string(spec.width) + " x " + std::to_string(spec.height) +
                       " image");
    }
    const size_t n = (size_t)spec.width * (size_t)spec.height;
    {
        // uncompressed pixels must be in the file: a header that promises
        // more is refused before the buffer is allocated
        struct stat st;
        const std::string comp = spec.get_string_attribute("compression", "none");
        if ((comp == "none" || comp.empty()) && ::stat(path.c_str(), &st) == 0 &&
            (unsigned long long)st.st_size < (unsigned long long)(n * fmt.size()))
            throw fail("the header promises " + std::to_string(spec.width) + " x " + std::to_string(spec.height) +
                       " uncompressed posts (" + std::to_string(n * fmt.size()) + " bytes) but the file has " +
                       std::to_string((unsigned long long)st.st_size));
    }
    r.width = spec.width;
    r.height = spec.height;
    r.sample_type = name;
    return in;
}

void convert_any(OIIO::TypeDesc fmt, const std::vector<unsigned char> &buf, size_t n, std::vector<double> &out)
{
    switch (fmt.basetype) {
    case OIIO::TypeDesc::INT8: convert_samples<int8_t>(buf, n, out); break;
    case OIIO::TypeDesc::UINT8: convert_samples<uint8_t>(buf, n, out); break;
    case OIIO::TypeDesc::INT16: convert_samples<int16_t>(buf, n, out); break;
    case OIIO::TypeDesc::UINT16: convert_samples<uint16_t>(buf, n, out); break;
    case OIIO::TypeDesc::INT32: convert_samples<int32_t>(buf, n, out); break;
    case OIIO::TypeDesc::UINT32: convert_samples<uint32_t>(buf, n, out); break;
    case OIIO::TypeDesc::FLOAT: convert_samples<float>(buf, n, out); break;
    default: convert_samples<double>(buf, n, out); break;
    }
}

struct RowInput {
    std::string path;
    std::unique_ptr<OIIO::ImageInput> in;
    std::vector<unsigned char> buf;
    std::vector<unsigned char> tile;  // one tile of a tiled file
};

}  // namespace

void *open_dem_pixel_rows(const std::string &path, DemRaster &r, bool &is_tiff)
{
    auto ri = std::make_unique<RowInput>();
    ri->path = path;
    ri->in = open_checked(path, r, is_tiff);
    return ri.release();
}

void read_dem_pixel_rows(void *handle, int y0, int n, std::vector<double> &h)
{
    RowInput &ri = *static_cast<RowInput *>(handle);
    const OIIO::ImageSpec &spec = ri.in->spec();
    if (y0 < 0 || n < 1 || y0 + n > spec.height) throw Error(ri.path + ": rows out of range");
    const size_t count = (size_t)spec.width * (size_t)n, px = spec.format.size();
    bool ok;
    if (spec.tile_width > 0 && spec.tile_height > 0) {
        // a tiled file: whole rows of tiles (read_scanlines is not for
        // tiled files in OpenImageIO 2.4), the rows wanted copied out
        const int th = spec.tile_height, t0 = y0 / th * th, t1 = std::min(spec.height, (y0 + n + th - 1) / th * th);
        ri.buf.resize((size_t)spec.width * (size_t)(t1 - t0) * px);
        // tile by tile through one buffer of our own (volumes are refused
        // at open): the samples are already in the format asked for, and
        // read_tiles zeroes and pages in a fresh buffer of the whole request
        // on every call (OpenImageIO 2.4; a third of a mosaic's reading)
        const int tw = spec.tile_width;
        const size_t tile_row = (size_t)tw * px;
        ri.tile.resize(tile_row * (size_t)th);
        ok = true;
        for (int ty = t0; ty < t1 && ok; ty += th)
            for (int tx = 0; tx < spec.width && ok; tx += tw) {
                ok = ri.in->read_native_tile(0, 0, spec.x + tx, spec.y + ty, spec.z, ri.tile.data());
                const size_t w = (size_t)std::min(tw, spec.width - tx) * px;
                for (int r = 0; ok && r < std::min(th, spec.height - ty); ++r)
                    std::memcpy(ri.buf.data() + ((size_t)(ty - t0 + r) * spec.width + tx) * px,
                                ri.tile.data() + (size_t)r * tile_row, w);
            }
        if (t0 != y0)
            std::memmove(ri.buf.data(), ri.buf.data() + (size_t)(y0 - t0) * spec.width * px, count * px);
    } else {
        // the native reader: read_scanlines would stage each call through
        // a 64 MB buffer of its own (OpenImageIO 2.4), for samples that are
        // already in the format asked for
        ri.buf.resize(count * px);
        ok = ri.in->read_native_scanlines(0, 0, spec.y + y0, spec.y + y0 + n, spec.z, 0, 1, ri.buf.data());
    }
    if (!ok || ri.in->has_error()) {
        std::string e = clipped(one_line(ri.in->geterror()));
        throw Error(ri.path + ": cannot read rows " + std::to_string(y0) + ".." + std::to_string(y0 + n - 1) +
                    (e.empty() ? std::string() : ": " + e));
    }
    convert_any(spec.format, ri.buf, count, h);
}

void close_dem_pixel_rows(void *handle)
{
    RowInput *ri = static_cast<RowInput *>(handle);
    if (ri && ri->in) ri->in->close();
    delete ri;
}

void read_dem_pixels(const std::string &path, DemRaster &r, bool &is_tiff)
{
    auto fail = [&](const std::string &why) { return Error(path + ": " + why); };
    auto in = open_checked(path, r, is_tiff);
    const OIIO::ImageSpec spec = in->spec();
    const OIIO::TypeDesc fmt = spec.format;

    const size_t n = (size_t)spec.width * (size_t)spec.height;
    if (n / (size_t)spec.width != (size_t)spec.height || n > ((size_t)1 << 34))
        throw fail("image too large");
    std::vector<unsigned char> buf(n * fmt.size());
    // OIIO 2.4 can return true from read_image() although a strip failed to
    // decode (the error is only recorded), so check has_error() as well.
    const bool read_ok = in->read_image(0, 0, 0, 1, fmt, buf.data());
    if (!read_ok || in->has_error()) {
        std::string e = clipped(one_line(in->geterror()));
        throw fail("cannot read pixels" + (e.empty() ? std::string() : ": " + e));
    }
    in->close();

    convert_any(fmt, buf, n, r.h);
}

}  // namespace ct_host
