// terrain.hpp -- host-side terrain model and package building (C++17).
//
// A Terrain is what a package is made from: 16-bit height codes on a square
// grid plus the georeference.  build_package() computes the max-mipmap and
// the directional PPT (apex + N sector angles per coarse cell) and returns
// the package bytes in the format defined by lib/include/conetrace.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace ct_host {

struct Georef {
    // GDAL convention: post (i, j) centre = origin + (i + 1/2, j + 1/2) * posting.
    double origin_e = 0.0, origin_n = 0.0;  // metres, top-left corner of pixel (0,0)
    double posting_e = 30.0, posting_n = -30.0;  // metres; |e| == |n|
    int epsg = 0;                                // 0 = unknown
    int source_epsg = 0;  // the source DEM's CRS when it was resampled onto epsg (0: not resampled)
    // the package header's origin exactly, in nm, instead of origin_e/n
    // rounded (a tile of a tile set: the set's origin plus whole postings)
    bool origin_nm_set = false;
    int64_t origin_e_nm = 0, origin_n_nm = 0;
};

// A geoid grid as a package's datum section stores it (conetrace.h): node
// (i, j) at (lat0 - j step, lon0 + i step), Q61 radians; undulation in
// micrometres.
struct GeoidGrid {
    int w = 0, h = 0;                             // 0: no grid
    int64_t lat0_q61 = 0, lon0_q61 = 0, step_q61 = 0;
    std::vector<int32_t> um;                      // w * h, row 0 north
};

struct Terrain {
    int width = 0, height = 0;           // posts
    std::vector<uint16_t> codes;         // row-major, width * height
    std::vector<uint8_t> void_post;      // empty, or 1 where the post was nodata
    Georef geo;
    double height_offset_m = 0.0;        // h = offset + code * scale
    double height_scale_m = 1.0;         // metres per LSB (> 0)
    int vdatum = 0;                      // CT_VDATUM_* of the source heights; when
                                         // known, the codes are ellipsoidal heights
    GeoidGrid geoid;                     // carried in the datum section

    uint16_t at(int i, int j) const { return codes[(size_t)j * (size_t)width + (size_t)i]; }
};

// Slices: the paper's slice-by-slice directional-DT builder (the default;
// builder_slices.cpp).  Brute: per-cell branch and bound over exact
// geometry (builder_brute.cpp): tighter cones, slower; the test reference.
// Degenerate: no cones -- exact apexes (the coarse cell's tallest post) and
// every angle code 0 (always valid, no cone jumps); a package for tests
// (the MCU vectors without a cone builder).
enum class PptBuilder { Slices, Brute, Degenerate };

struct BuildOptions {
    int sectors = 24;      // N, 1..64
    int reduce = 1;        // r, 1..8
    int slices = 0;        // K > 0: apexes rounded up to K evenly spaced levels;
                           // 0: exact apexes (Brute), DEFAULT_SLICES (Slices)
    int threads = 0;       // 0 = hardware concurrency
    PptBuilder builder = PptBuilder::Slices;
    int window = 12;       // Slices: near window Rw in coarse cells (>= 1)
    // Slices: a (slice, sector) whose capped DT queries visit more than this
    // many rows per coarse cell finishes with one full line-traversal DT
    // (the same values; 0 = always full DTs, a huge value = queries only)
    double full_dt_rows = 12.0;
    std::vector<double> levels_m;  // Slices: given levels (metres) instead of K even ones;
                                   // the DEM's lowest and highest heights are always levels
    static constexpr int DEFAULT_SLICES = 64;
    // progress(done, total) called from the calling thread now and then
    std::function<void(size_t, size_t)> progress;
};

struct BuildStats {
    double seconds = 0.0;
    size_t bytes = 0;              // package size
    size_t degenerate_cones = 0;   // (cell, sector) pairs with code 0
    size_t cones = 0;              // (cell, sector) pairs
    int slices = 0;                // Slices: levels K used / slices transformed
    int slices_transformed = 0;
    size_t far_narrowed = 0;       // Slices: codes narrowed by a far (DT) term
    size_t dt_queries = 0;         // Slices: capped directional DT queries (cell, slice, sector)
    uint64_t dt_query_rows = 0;    // Slices: rows those queries visited
    size_t full_dts = 0;           // Slices: (slice, sector) pairs finished with a full DT
    double seconds_local = 0.0;    // Slices: near + window terms
    double seconds_dt = 0.0;       // Slices: slice DTs and far terms
};

struct Error : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Posts per side: of one package (CT_MAX_POSTS; also the most a tile set's
// merged frame holds, ct_tileset_open), and of a DEM that `build
// --tile-size` takes (beyond kMaxPackagePosts: a mosaic of tile sets).
constexpr int kMaxPackagePosts = 32768;
constexpr int kMaxTileSetDemPosts = 1 << 20;
// "DEM of WxH posts exceeds the package limit ..." (and what holds it).
std::string too_wide_for_package(int width, int height);

// The height scale (metres per LSB) for heights lo..hi: scale_m <= 0
// chooses the finest power-of-two fraction of a metre (at most 1/16 m) that
// keeps the range within 60000 codes; throws Error when the range does not
// fit 16 bits at the scale.  Codes are lround((h - lo) / scale) clamped to
// 0..65535, voids 0.
double choose_height_scale(double lo, double hi, double scale_m);

// The range of the valid, finite heights seen so far (nvalid of them).
struct HeightRange {
    double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
    size_t nvalid = 0;
    // h counts when valid and finite; returns whether it did
    bool add(double h, bool valid)
    {
        if (!valid || !std::isfinite(h)) return false;
        lo = std::min(lo, h);
        hi = std::max(hi, h);
        nvalid++;
        return true;
    }
    // another part's heights counted too (min, max and count: any order)
    void merge(const HeightRange &o)
    {
        lo = std::min(lo, o.lo);
        hi = std::max(hi, o.hi);
        nvalid += o.nvalid;
    }
};

// A height's code: lround((h - lo) / scale) clamped to 0..65535.
inline uint16_t height_code(double h_m, double lo, double scale_m)
{
    const long c = std::lround((h_m - lo) / scale_m);
    return (uint16_t)std::min(65535L, std::max(0L, c));
}

// Quantise metres to codes.  scale_m <= 0 chooses the finest power-of-two
// fraction of a metre that fits the range (at most 1/16 m ... up to 2^k m).
// NaN / nodata entries (valid[k] == 0) become void posts.
Terrain terrain_from_heights(int width, int height, const std::vector<double> &h_m,
                             const std::vector<uint8_t> &valid, const Georef &geo,
                             double scale_m = 0.0);

// Where a package goes: its bytes in file order, then one patch (the CRC).
class PackageSink {
public:
    virtual ~PackageSink() = default;
    virtual void write(const uint8_t *p, size_t n) = 0;
    virtual void patch(size_t offset, const uint8_t *p, size_t n) = 0;
    // the package's size, told before the first write (a buffer reserves it)
    virtual void size_hint(size_t) {}
};

// The package (header, heights, mipmap, apex, angles, voids, CRC), streamed
// to `sink` (package_build.cpp); only the angle planes are held whole.
void build_package_to(const Terrain &t, const BuildOptions &opt, PackageSink &sink,
                      BuildStats *stats = nullptr);
// The same into memory.
std::vector<uint8_t> build_package(const Terrain &t, const BuildOptions &opt,
                                   BuildStats *stats = nullptr);
// The same into a file, atomically (host_io.hpp's AtomicFile: a temporary
// file beside it, synced and renamed): no partial file is left on any error.  Throws Error("<path>: ...").
void build_package_file(const Terrain &t, const BuildOptions &opt, const std::string &path,
                        BuildStats *stats = nullptr);

// Georeference as the package stores it (integer nanometres).
int64_t metres_to_nm(double m);

}  // namespace ct_host
