// tileset.cpp -- tile sets on the host (tileset.hpp).
#include "tileset.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

#include <unistd.h>

#include "host_io.hpp"
#include "le.hpp"

namespace fs = std::filesystem;

namespace ct_host {

std::string tile_file_name(int col, int row)
{
    return "tile_" + std::to_string(col) + "_" + std::to_string(row) + ".ctp";
}

int default_tile_posts(int reduce, int sectors, size_t max_bytes)
{
    int best = 17;
    for (int k = 4; k <= 15; ++k) {
        const uint32_t P = (1u << k) + 1u;
        uint32_t size = 0;
        if (P > CT_MAX_POSTS ||
            ct_package_size(P, P, (uint32_t)reduce, (uint32_t)sectors, 0u, &size) != CT_OK || size > max_bytes)
            break;
        best = (int)P;
    }
    return best;
}

TileGrid tile_grid(int width, int height, int P)
{
    if (P < 2 || P > CT_MAX_POSTS) throw Error("tile size must be in 2..32768 posts");
    TileGrid g;
    g.P = P;
    g.tiles_x = (width - 1 + P - 2) / (P - 1);
    g.tiles_y = (height - 1 + P - 2) / (P - 1);
    if ((size_t)g.tiles_x * (size_t)g.tiles_y > CT_SET_MAX_TILES)
        throw Error("tile size " + std::to_string(P) + " makes " + std::to_string(g.tiles_x) + " x " +
                    std::to_string(g.tiles_y) + " tiles (at most " + std::to_string(CT_SET_MAX_TILES) + ")");
    return g;
}

namespace {

// geo moved by (x0, y0) posts: the origin in metres and, exactly, in nm.
Georef shifted_georef(const Georef &geo, int x0, int y0)
{
    Georef s = geo;
    const int64_t oe = geo.origin_nm_set ? geo.origin_e_nm : metres_to_nm(geo.origin_e);
    const int64_t on = geo.origin_nm_set ? geo.origin_n_nm : metres_to_nm(geo.origin_n);
    s.origin_e = geo.origin_e + x0 * geo.posting_e;
    s.origin_n = geo.origin_n + y0 * geo.posting_n;
    s.origin_nm_set = true;
    s.origin_e_nm = oe + (int64_t)x0 * metres_to_nm(geo.posting_e);
    s.origin_n_nm = on + (int64_t)y0 * metres_to_nm(geo.posting_n);
    return s;
}

}  // namespace

Terrain tile_terrain(const Terrain &t, const TileGrid &g, int col, int row)
{
    Terrain s;
    tile_terrain(t, g, col, row, s);
    return s;
}

void tile_terrain(const Terrain &t, const TileGrid &g, int col, int row, Terrain &s)
{
    const int x0 = g.first_col(col), y0 = g.first_row(row);
    const int w = std::min(g.P, t.width - x0), h = std::min(g.P, t.height - y0);
    s.width = w;
    s.height = h;
    s.codes.resize((size_t)w * h);  // every element is written below
    for (int j = 0; j < h; ++j)
        std::copy_n(&t.codes[(size_t)(y0 + j) * t.width + x0], w, &s.codes[(size_t)j * w]);
    s.void_post.clear();
    if (!t.void_post.empty()) {
        s.void_post.resize((size_t)w * h);
        bool any = false;
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i) {
                const uint8_t v = t.void_post[(size_t)(y0 + j) * t.width + x0 + i];
                s.void_post[(size_t)j * w + i] = v;
                any = any || v;
            }
        if (!any) s.void_post.clear();
    }
    s.geo = shifted_georef(t.geo, x0, y0);
    s.height_offset_m = t.height_offset_m;
    s.height_scale_m = t.height_scale_m;
    s.vdatum = t.vdatum;
    s.geoid = t.geoid;
}

namespace {

// A tile's manifest entry (package size, its CRC field, its codes' range).
struct TileEntry {
    bool present = false;
    uint32_t size = 0, crc = 0;
    uint16_t hmin = 0, hmax = 0;
};

// The entry of a package of `size` bytes whose header (CRC field set) is h.
TileEntry entry_of_header(const std::vector<uint8_t> &h, size_t size)
{
    TileEntry e;
    if (size == 0) return e;  // no tile: present = 0
    if (size < CT_PKG_HEADER_SIZE || h.size() < CT_PKG_HEADER_SIZE)
        throw Error("manifest: a tile is shorter than a header");
    e.present = true;
    e.size = (uint32_t)size;
    e.crc = get32(h, CT_HDR_CRC);
    e.hmin = get16(&h[CT_HDR_HMIN]);
    e.hmax = get16(&h[CT_HDR_HMAX]);
    return e;
}

TileEntry entry_of(const std::vector<uint8_t> &p) { return entry_of_header(p, p.size()); }

// A package streamed into its file (AtomicFile: committed by the caller),
// keeping its header and size for the manifest's entry: a mosaic's tile is
// never held whole in memory.
class TileFileSink : public PackageSink {
public:
    explicit TileFileSink(AtomicFile &f) : f_(f) {}
    void write(const uint8_t *p, size_t n) override
    {
        f_.write(p, n);
        if (head_.size() < CT_PKG_HEADER_SIZE)
            head_.insert(head_.end(), p, p + std::min(n, CT_PKG_HEADER_SIZE - head_.size()));
        size_ += n;
    }
    void patch(size_t off, const uint8_t *p, size_t n) override
    {
        f_.patch(off, p, n);
        for (size_t k = 0; k < n && off + k < head_.size(); ++k) head_[off + k] = p[k];
    }
    TileEntry entry() const { return entry_of_header(head_, size_); }

private:
    AtomicFile &f_;
    std::vector<uint8_t> head_;
    size_t size_ = 0;
};

// The manifest of a set whose merged grid is t's (size, georeference,
// height coding, datum; t's codes are not used): codes lo..hi, the entries.
std::vector<uint8_t> manifest_bytes(const Terrain &t, uint16_t lo, uint16_t hi, const TileGrid &g, int reduce,
                                    int sectors, const std::vector<TileEntry> &entries)
{
    const size_t n = (size_t)g.tiles_x * g.tiles_y;
    if (entries.size() != n) throw Error("manifest: tile count mismatch");
    std::vector<uint8_t> m(CT_SET_HEADER_SIZE + n * CT_SET_ENTRY_SIZE, 0);
    std::memcpy(&m[0], CT_SET_MAGIC, 4);
    put16(m, CT_HDR_VERSION, CT_SET_VERSION);
    put16(m, CT_HDR_HEADER_SIZE, CT_SET_HEADER_SIZE);
    put32(m, CT_HDR_TOTAL, (uint32_t)m.size());
    put16(m, CT_SET_HDR_TILES_X, (uint32_t)g.tiles_x);
    put16(m, CT_SET_HDR_TILES_Y, (uint32_t)g.tiles_y);
    put16(m, CT_SET_HDR_TILE_POSTS, (uint32_t)g.P);
    m[CT_SET_HDR_REDUCE] = (uint8_t)reduce;
    m[CT_SET_HDR_SECTORS] = (uint8_t)sectors;
    put16(m, CT_SET_HDR_WIDTH, (uint32_t)t.width);
    put16(m, CT_SET_HDR_HEIGHT, (uint32_t)t.height);
    put16(m, CT_SET_HDR_HMIN, lo);
    put16(m, CT_SET_HDR_HMAX, hi);
    const int64_t geo[6] = {t.geo.origin_nm_set ? t.geo.origin_e_nm : metres_to_nm(t.geo.origin_e),
                            t.geo.origin_nm_set ? t.geo.origin_n_nm : metres_to_nm(t.geo.origin_n),
                            metres_to_nm(t.geo.posting_e),
                            metres_to_nm(t.geo.posting_n),
                            metres_to_nm(t.height_offset_m),
                            metres_to_nm(t.height_scale_m)};
    for (int k = 0; k < 6; ++k) put64(m, CT_SET_HDR_GEOREF + 8 * k, geo[k]);
    put32(m, CT_SET_HDR_EPSG, (uint32_t)std::max(0, t.geo.epsg));
    put16(m, CT_SET_HDR_VDATUM, (uint32_t)t.vdatum);
    for (size_t k = 0; k < n; ++k) {
        const TileEntry &te = entries[k];
        uint8_t *e = &m[CT_SET_HEADER_SIZE + k * CT_SET_ENTRY_SIZE];
        if (!te.present) continue;  // no tile: present = 0
        put32(e, te.size);
        put32(e + 4, te.crc);
        put16(e + 8, te.hmin);
        put16(e + 10, te.hmax);
        e[12] = 1;
    }
    uint32_t crc = 0;
    ct_crc32(0u, m.data(), m.size(), &crc);  // the CRC field is still 0
    put32(m, CT_HDR_CRC, crc);
    return m;
}

// A directory that `build --tile-size` may replace: missing, empty, a tile
// set or a mosaic of them.
void check_replaceable(const std::string &dir)
{
    std::error_code ec;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) throw Error(dir + ": exists and is not a directory");
    if (fs::is_directory(dir, ec) && !fs::is_empty(dir, ec) && !fs::exists(fs::path(dir) / kManifestName, ec) &&
        !is_mosaic_path(dir))
        throw Error(dir + ": a non-empty directory that is not a tile set (refusing to replace it)");
}

// The finished directory tmp moved to dir (an existing one replaced only
// now); tmp removed on failure.
void install_dir(const std::string &tmp, const std::string &dir, const std::string &old)
{
    std::error_code ec;
    {
        InterruptLock lock;  // renamed and (un)registered at once: an interrupt waits
        try {
            if (fs::exists(dir, ec)) {
                fs::rename(dir, old, ec);
                if (ec) throw Error(dir + ": cannot replace (" + ec.message() + ")");
            }
            fs::rename(tmp, dir, ec);
            if (ec) {
                std::error_code ec2;
                if (fs::exists(old, ec2)) fs::rename(old, dir, ec2);
                throw Error(dir + ": cannot create (" + ec.message() + ")");
            }
        } catch (...) {
            fs::remove_all(tmp, ec);
            unregister_temporary(tmp);
            throw;
        }
        unregister_temporary(tmp);
        register_temporary(old, old, true);  // the replaced set: removed now, or by an interrupt
    }
    fs::remove_all(old, ec);
    unregister_temporary(old);
}

}  // namespace

std::vector<uint8_t> make_manifest(const Terrain &t, const TileGrid &g, int reduce, int sectors,
                                   const std::vector<std::vector<uint8_t>> &tiles)
{
    uint16_t lo = 65535, hi = 0;
    for (uint16_t v : t.codes) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    std::vector<TileEntry> entries;
    entries.reserve(tiles.size());
    for (const std::vector<uint8_t> &p : tiles) entries.push_back(entry_of(p));
    return manifest_bytes(t, lo, hi, g, reduce, sectors, entries);
}

TileSetBytes build_tileset(const Terrain &t, const BuildOptions &opt, int P, int threads,
                           const std::function<bool(int, int)> &drop,
                           const std::function<void(size_t, size_t)> &progress)
{
    TileSetBytes out;
    out.grid = tile_grid(t.width, t.height, P);
    const TileGrid &g = out.grid;
    const size_t n = (size_t)g.tiles_x * g.tiles_y;
    out.tiles.assign(n, {});
    BuildOptions o = opt;
    o.threads = 1;
    o.progress = nullptr;
    const int nthreads = threads > 0 ? threads : (int)std::max(1u, std::thread::hardware_concurrency());
    std::atomic<size_t> next{0}, done{0};
    std::atomic<bool> failed{false};
    std::mutex err_mu;
    std::string err;
    auto work = [&]() {
        for (;;) {
            const size_t k = next++;
            if (k >= n) return;
            const int col = (int)(k % (size_t)g.tiles_x), row = (int)(k / (size_t)g.tiles_x);
            try {
                if (!drop || !drop(col, row)) out.tiles[k] = build_package(tile_terrain(t, g, col, row), o);
            } catch (const std::exception &e) {
                std::lock_guard<std::mutex> lk(err_mu);
                if (err.empty()) err = "tile " + std::to_string(col) + "," + std::to_string(row) + ": " + e.what();
                failed = true;
                next = n;  // stop the others
            }
            done++;
        }
    };
    std::vector<std::thread> pool;
    const int nw = std::max(1, std::min<int>(nthreads, (int)n));
    for (int k = 0; k < nw; ++k) pool.emplace_back(work);
    // the calling thread reports progress until the workers are through
    while (progress && done.load() < n && !failed.load()) {
        progress(done.load(), n);
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    for (std::thread &th : pool) th.join();
    if (!err.empty()) throw Error(err);
    if (progress) progress(n, n);
    out.manifest = make_manifest(t, g, opt.reduce, opt.sectors, out.tiles);
    return out;
}

void build_tileset_dir(const Terrain &t, const BuildOptions &opt, int P, const std::string &dir, int threads,
                       const std::function<void(size_t, size_t)> &progress, TileSetBytes *summary)
{
    const std::string pid = std::to_string((long)getpid());
    const std::string tmp = dir + ".tmp." + pid, old = dir + ".old." + pid;
    std::error_code ec;
    check_replaceable(dir);
    TileSetBytes b = build_tileset(t, opt, P, threads, nullptr, progress);
    fs::remove_all(tmp, ec);
    create_registered_dir(tmp, dir);  // removed by an interrupt from now on
    try {
        for (int row = 0; row < b.grid.tiles_y; ++row)
            for (int col = 0; col < b.grid.tiles_x; ++col)
                write_file_atomic((fs::path(tmp) / tile_file_name(col, row)).string(),
                                  b.tiles[(size_t)row * b.grid.tiles_x + col]);
        write_file_atomic((fs::path(tmp) / kManifestName).string(), b.manifest);
    } catch (...) {
        fs::remove_all(tmp, ec);
        unregister_temporary(tmp);
        throw;
    }
    install_dir(tmp, dir, old);
    if (summary) {
        summary->grid = b.grid;
        summary->manifest = b.manifest;
        summary->tiles = std::move(b.tiles);
    }
}

std::string mosaic_set_name(int bx, int by) { return "set_" + std::to_string(bx) + "_" + std::to_string(by); }

int mosaic_set_tiles(int P)
{
    if (P < 2 || P > CT_MAX_POSTS) throw Error("tile size must be in 2..32768 posts");
    return std::min(64, (CT_MAX_POSTS - 1) / (P - 1));  // K^2 <= CT_SET_MAX_TILES, K (P - 1) + 1 <= CT_MAX_POSTS
}

size_t tile_build_memory(int P, int reduce, int sectors)
{
    uint32_t pkg = 0;
    if (ct_package_size((uint32_t)P, (uint32_t)P, (uint32_t)reduce, (uint32_t)sectors, 0u, &pkg) != CT_OK)
        pkg = (uint32_t)((size_t)P * P * 4);
    const size_t r = (size_t)std::max(1, reduce), cells = ((size_t)P - 1 + r - 1) / r;
    // the tile's codes and voids (3 B/post) and small arrays per post (4 B);
    // as much again as the package (the package is streamed into its file,
    // but its angle planes and apexes are held while they are made); and
    // the slice builder's arrays per coarse cell, its DTs above all (full
    // DTs' distances, minima and line tables): 23-29 B measured at r = 1
    // (257 to 1025 posts, N = 8 and 24), 40 B counted (test_tiles)
    return (size_t)P * P * 7 + pkg + cells * cells * 40;
}

size_t streamed_memory_estimate(int width, int height, int P, int chunk_rows, int threads, int reduce, int sectors)
{
    (void)height;
    const size_t band = (size_t)width * (size_t)P * 3;                     // codes and void flags
    const size_t chunk = (size_t)width * (size_t)chunk_rows * (8 + 1 + 8);  // doubles, flags, raw samples
    return band + chunk + (size_t)std::max(1, threads) * tile_build_memory(P, reduce, sectors) + (64u << 20);
}

namespace {

// MemAvailable from /proc/meminfo, bytes (0: unknown).
size_t memory_available()
{
    std::ifstream f("/proc/meminfo");
    std::string key;
    size_t kib = 0;
    std::string unit;
    while (f >> key >> kib) {
        std::getline(f, unit);
        if (key == "MemAvailable:") return kib * 1024;
    }
    return 0;
}

std::string gib(size_t b)
{
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f GB", (double)b / 1e9);
    return buf;
}

// n items in one share per thread: the chunk for parallel_chunks.
size_t share(size_t n, int threads) { return (n + (size_t)threads - 1) / (size_t)threads; }

// Rows src .. src + n - 1 of a read chunk (h, valid: whole rows of
// band.width) quantised into the band's rows dst .. dst + n - 1, each row
// alone on one of `threads` threads; voids get the lowest height.
void quantise_rows(const std::vector<double> &h, const std::vector<uint8_t> &valid, int src, int dst, int n, double lo,
                   double scale_m, int threads, Terrain &band)
{
    const size_t w = (size_t)band.width;
    parallel_chunks((size_t)n, threads, share((size_t)n, threads), [&](size_t rb, size_t re) {
        for (size_t q = rb; q < re; ++q) {
            const size_t from = ((size_t)src + q) * w, to = ((size_t)dst + q) * w;
            for (size_t i = 0; i < w; ++i) {
                const double v = h[from + i];
                const bool ok = valid[from + i] && std::isfinite(v);
                band.codes[to + i] = ok ? height_code(v, lo, scale_m) : 0;
                band.void_post[to + i] = ok ? 0 : 1;
            }
        }
    });
}

}  // namespace

void build_mosaic_dir(int width, int height, const Georef &geo, double scale_m, int vdatum, const GeoidGrid &geoid,
                      const RowReader &read,
                      int chunk_rows, const BuildOptions &opt, int P, const std::string &dir, int threads,
                      const std::function<void(const char *, size_t, size_t)> &progress,
                      StreamedSetSummary *summary)
{
    if (width < 2 || height < 2) throw Error("DEM must have at least 2x2 posts");
    if (width > kMaxTileSetDemPosts || height > kMaxTileSetDemPosts)
        throw Error("DEM of " + std::to_string(width) + "x" + std::to_string(height) +
                    " posts exceeds the tile-set limit of " + std::to_string(kMaxTileSetDemPosts) + " per side");
    const int K = mosaic_set_tiles(P);
    TileGrid g;  // the DEM's global tile grid
    g.P = P;
    g.tiles_x = (width - 1 + P - 2) / (P - 1);
    g.tiles_y = (height - 1 + P - 2) / (P - 1);
    const int sets_x = (g.tiles_x + K - 1) / K, sets_y = (g.tiles_y + K - 1) / K;
    const int nthreads = threads > 0 ? threads : (int)std::max(1u, std::thread::hardware_concurrency());
    chunk_rows = std::max(1, std::min(chunk_rows, height));
    StreamedSetSummary sum;
    sum.sets_x = sets_x;
    sum.sets_y = sets_y;
    sum.tiles_x = g.tiles_x;
    sum.tiles_y = g.tiles_y;
    sum.memory_estimate = streamed_memory_estimate(width, height, P, chunk_rows, nthreads, opt.reduce, opt.sectors);
    const size_t avail = memory_available();
    if (avail != 0 && sum.memory_estimate > avail)
        throw Error("building tiles of " + std::to_string(P) + " posts from a " + std::to_string(width) + "x" +
                    std::to_string(height) + " DEM needs about " + gib(sum.memory_estimate) + " (a band of " +
                    std::to_string(P) + " rows, " + std::to_string(nthreads) + " tiles at once) but " + gib(avail) +
                    " are available: use a smaller --tile-size or fewer --threads");
    check_replaceable(dir);
    std::error_code ec;
    {
        // the tiles' bytes (without voids and geoid, a lower bound) against
        // the free space where they are written
        uint64_t need = 0;
        for (int r = 0; r < g.tiles_y; ++r)
            for (int c = 0; c < g.tiles_x; ++c) {
                uint32_t b = 0;
                ct_package_size((uint32_t)std::min(P, width - g.first_col(c)),
                                (uint32_t)std::min(P, height - g.first_row(r)), (uint32_t)opt.reduce,
                                (uint32_t)opt.sectors, 0u, &b);
                need += b;
            }
        fs::path parent = fs::absolute(fs::path(dir), ec).parent_path();
        const fs::space_info sp = fs::space(parent, ec);
        if (!ec && sp.available < need)
            throw Error(dir + ": the tiles need about " + gib(need) + " but " + parent.string() + " has " +
                        gib(sp.available) + " free");
    }

    // pass 1: the heights' range
    auto t0 = std::chrono::steady_clock::now();
    std::vector<double> h;
    std::vector<uint8_t> valid;
    HeightRange range;
    for (int y = 0; y < height; y += chunk_rows) {
        const int n = std::min(chunk_rows, height - y);
        read(y, n, h, valid);
        // the chunk's range in one part per thread, then merged
        const size_t per = share(h.size(), nthreads);
        std::vector<HeightRange> parts((size_t)nthreads);
        parallel_chunks(h.size(), nthreads, per, [&](size_t b, size_t e) {
            HeightRange part;  // a local (the parts share cache lines)
            for (size_t k = b; k < e; ++k) part.add(h[k], valid[k] != 0);
            parts[b / per] = part;
        });
        for (const HeightRange &part : parts) range.merge(part);
        if (progress) progress("scanning heights", (size_t)(y + n), (size_t)height);
    }
    if (range.nvalid == 0) throw Error("every sample is nodata");
    const double lo = range.lo;
    scale_m = choose_height_scale(lo, range.hi, scale_m);
    sum.lo_m = lo;
    sum.scale_m = scale_m;
    auto t1 = std::chrono::steady_clock::now();
    sum.seconds_scan = std::chrono::duration<double>(t1 - t0).count();

    // pass 2: band by band (tile row by tile row), each tile written as made
    const std::string pid = std::to_string((long)getpid());
    const std::string tmp = dir + ".tmp." + pid, old = dir + ".old." + pid;
    fs::remove_all(tmp, ec);
    create_registered_dir(tmp, dir);  // removed by an interrupt from now on
    std::vector<TileEntry> entries((size_t)g.tiles_x * g.tiles_y);
    try {
        for (int by = 0; by < sets_y; ++by)
            for (int bx = 0; bx < sets_x; ++bx)
                if (!fs::create_directory(fs::path(tmp) / mosaic_set_name(bx, by), ec))
                    throw Error(tmp + ": cannot create (" + ec.message() + ")");
        BuildOptions o = opt;
        o.threads = 1;
        o.progress = nullptr;
        // the band: a row of tiles, P rows of the DEM at most (tile_terrain
        // cuts its tiles as from a whole DEM: row 0 of the grid)
        Terrain band;
        band.width = width;
        band.codes.resize((size_t)width * P);
        band.void_post.resize((size_t)width * P);
        band.height_offset_m = lo;
        band.height_scale_m = scale_m;
        band.vdatum = vdatum;
        band.geoid = geoid;
        int have = 0;        // rows of the band already filled (the shared edge row)
        int next_row = 0;    // the next DEM row to read
        int chunk_y = 0;     // rows chunk_y .. chunk_y + chunk_n - 1 are in h / valid
        int chunk_n = 0;
        const size_t ntiles = entries.size();
        std::atomic<size_t> done{0};
        // The workers take the tiles in order over the whole grid.  A tile's
        // terrain is copied out of the band before it is built, so the band
        // is free once every tile of its row has been copied: the next band
        // is read and quantised while this row's last tiles are still being
        // built (no core waits for the reading, nor for a row's last tile).
        std::mutex mu;
        std::condition_variable cv;
        int band_row = -1;  // the row of tiles the band holds (under mu)
        int copied = 0;     // tiles of band_row copied out of it (under mu)
        bool failed = false;
        std::string err;
        std::atomic<size_t> next_tile{0};
        auto fail = [&](const std::string &what) {
            std::lock_guard<std::mutex> lk(mu);
            if (err.empty()) err = what;
            failed = true;
            next_tile = ntiles;  // stop the others
            cv.notify_all();
        };
        auto is_failed = [&] {
            std::lock_guard<std::mutex> lk(mu);
            return failed;
        };
        auto work = [&](Terrain &tile) {
            for (;;) {
                const size_t k = next_tile++;
                if (k >= ntiles) return;
                const int row = (int)(k / (size_t)g.tiles_x), col = (int)(k % (size_t)g.tiles_x);
                try {
                    {
                        std::unique_lock<std::mutex> lk(mu);
                        cv.wait(lk, [&] { return failed || band_row == row; });
                        if (failed) return;
                    }
                    tile_terrain(band, g, col, 0, tile);
                    {
                        std::lock_guard<std::mutex> lk(mu);
                        if (++copied == g.tiles_x) cv.notify_all();
                    }
                    const int bx = col / K, by = row / K;
                    AtomicFile f((fs::path(tmp) / mosaic_set_name(bx, by) / tile_file_name(col - bx * K, row - by * K))
                                     .string());
                    TileFileSink sink(f);
                    build_package_to(tile, o, sink);
                    f.commit();
                    entries[k] = sink.entry();
                } catch (const std::exception &e) {
                    fail("tile " + std::to_string(col) + "," + std::to_string(row) + ": " + e.what());
                    return;
                }
                done++;
            }
        };
        // each worker's tile, its buffers reused from tile to tile (fresh
        // ones per tile were page faults and memsets: ~7% of the build)
        const int nw = (int)std::max<size_t>(1, std::min<size_t>((size_t)nthreads, ntiles));
        std::vector<Terrain> tiles((size_t)nw);
        std::vector<std::thread> pool;
        for (int k = 0; k < nw; ++k) pool.emplace_back(work, std::ref(tiles[(size_t)k]));
        try {
            for (int row = 0; row < g.tiles_y; ++row) {
                const int y0 = g.first_row(row), rows = std::min(P, height - y0);
                // the band's rows: the previous band's last row is this one's first
                for (int j = have; j < rows;) {
                    const int y = y0 + j;
                    if (y >= chunk_y + chunk_n) {
                        chunk_y = next_row;
                        chunk_n = std::min(chunk_rows, height - chunk_y);
                        read(chunk_y, chunk_n, h, valid);
                        next_row = chunk_y + chunk_n;
                    }
                    // the band's rows j .. jend - 1 held by this chunk
                    const int jend = std::min(rows, chunk_y + chunk_n - y0);
                    quantise_rows(h, valid, y - chunk_y, j, jend - j, lo, scale_m, nthreads, band);
                    j = jend;
                }
                band.height = rows;
                band.geo = shifted_georef(geo, 0, y0);
                // the band to the workers; back once its tiles are copied out
                std::unique_lock<std::mutex> lk(mu);
                band_row = row;
                copied = 0;
                cv.notify_all();
                while (!failed && copied < g.tiles_x) {
                    cv.wait_for(lk, std::chrono::milliseconds(100));
                    if (progress) {
                        lk.unlock();
                        progress("building tiles", done.load(), ntiles);
                        lk.lock();
                    }
                }
                if (failed) break;
                lk.unlock();
                // the band's last row is the next band's first
                if (row + 1 < g.tiles_y) {
                    std::copy_n(&band.codes[(size_t)(rows - 1) * width], width, &band.codes[0]);
                    std::copy_n(&band.void_post[(size_t)(rows - 1) * width], width, &band.void_post[0]);
                    have = 1;
                }
            }
            while (progress && done.load() < ntiles && !is_failed()) {
                progress("building tiles", done.load(), ntiles);
                std::this_thread::sleep_for(std::chrono::milliseconds(100));
            }
        } catch (...) {
            fail("the DEM's reading failed");  // the workers stop; the reader's error is thrown again
            for (std::thread &th : pool) th.join();
            throw;
        }
        for (std::thread &th : pool) th.join();
        if (!err.empty()) throw Error(err);
        if (progress) progress("building tiles", done.load(), ntiles);
        // each set's manifest: its grid, origin and codes' range
        for (int by = 0; by < sets_y; ++by)
            for (int bx = 0; bx < sets_x; ++bx) {
                const int c0 = bx * K, r0 = by * K;
                TileGrid sg;
                sg.P = P;
                sg.tiles_x = std::min(K, g.tiles_x - c0);
                sg.tiles_y = std::min(K, g.tiles_y - r0);
                const int x0 = g.first_col(c0), y0 = g.first_row(r0);
                Terrain f;
                f.width = std::min(sg.tiles_x * (P - 1) + 1, width - x0);
                f.height = std::min(sg.tiles_y * (P - 1) + 1, height - y0);
                f.geo = shifted_georef(geo, x0, y0);
                f.height_offset_m = lo;
                f.height_scale_m = scale_m;
                f.vdatum = vdatum;
                std::vector<TileEntry> se;
                uint16_t clo = 65535, chi = 0;
                for (int r = 0; r < sg.tiles_y; ++r)
                    for (int c = 0; c < sg.tiles_x; ++c) {
                        const TileEntry &e = entries[(size_t)(r0 + r) * g.tiles_x + c0 + c];
                        se.push_back(e);
                        clo = std::min(clo, e.hmin);
                        chi = std::max(chi, e.hmax);
                        sum.bytes += e.size;
                        sum.largest = std::max<size_t>(sum.largest, e.size);
                    }
                const std::vector<uint8_t> m = manifest_bytes(f, clo, chi, sg, opt.reduce, opt.sectors, se);
                write_file_atomic((fs::path(tmp) / mosaic_set_name(bx, by) / kManifestName).string(), m);
                sum.bytes += m.size();
            }
    } catch (...) {
        fs::remove_all(tmp, ec);
        unregister_temporary(tmp);
        throw;
    }
    install_dir(tmp, dir, old);
    sum.seconds_build = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    if (summary) *summary = sum;
}

bool is_mosaic_path(const std::string &path, int *sets_x, int *sets_y)
{
    std::error_code ec;
    if (!fs::is_directory(path, ec) || fs::exists(fs::path(path) / kManifestName, ec) ||
        !fs::exists(fs::path(path) / kMosaicFirstSet / kManifestName, ec))
        return false;
    int nx = 1, ny = 1;
    while (fs::is_directory(fs::path(path) / mosaic_set_name(nx, 0), ec)) nx++;
    while (fs::is_directory(fs::path(path) / mosaic_set_name(0, ny), ec)) ny++;
    if (sets_x) *sets_x = nx;
    if (sets_y) *sets_y = ny;
    return true;
}

bool is_tileset_path(const std::string &path)
{
    std::error_code ec;
    int sx = 0, sy = 0;
    if (is_mosaic_path(path, &sx, &sy))
        throw Error(path + ": a mosaic of " + std::to_string(sx) + " x " + std::to_string(sy) +
                    " tile sets (one set's frame holds at most " + std::to_string(kMaxPackagePosts) +
                    " posts per side): give one of them, e.g. " + (fs::path(path) / kMosaicFirstSet).string());
    if (fs::is_directory(path, ec)) return fs::exists(fs::path(path) / kManifestName, ec);
    std::ifstream f(path, std::ios::binary);
    char m[4] = {0, 0, 0, 0};
    return f && f.read(m, 4) && std::memcmp(m, CT_SET_MAGIC, 4) == 0;
}

TileSetFiles::TileSetFiles(const std::string &path)
{
    std::error_code ec;
    std::string mpath = path;
    if (fs::is_directory(path, ec)) {
        dir_ = path;
        mpath = (fs::path(path) / kManifestName).string();
    } else {
        dir_ = fs::path(path).parent_path().string();
        if (dir_.empty()) dir_ = ".";
    }
    manifest_ = read_file(mpath);
    if (manifest_.size() < CT_SET_HEADER_SIZE || std::memcmp(manifest_.data(), CT_SET_MAGIC, 4) != 0)
        throw Error(mpath + ": not a tile set manifest");
}

uint32_t TileSetFiles::tiles_x() const { return get16(&manifest_[CT_SET_HDR_TILES_X]); }
uint32_t TileSetFiles::tiles_y() const { return get16(&manifest_[CT_SET_HDR_TILES_Y]); }

size_t TileSetFiles::largest_tile() const
{
    size_t m = 0;
    const size_t n = (size_t)tiles_x() * tiles_y();
    for (size_t k = 0; k < n && CT_SET_HEADER_SIZE + (k + 1) * CT_SET_ENTRY_SIZE <= manifest_.size(); ++k)
        m = std::max<size_t>(m, get32(manifest_, CT_SET_HEADER_SIZE + k * CT_SET_ENTRY_SIZE));
    return m;
}

ct_status TileSetFiles::loader(void *user, uint32_t col, uint32_t row, uint8_t *buf, size_t cap,
                               const uint8_t **bytes, size_t *len)
{
    TileSetFiles *self = static_cast<TileSetFiles *>(user);
    const std::string p = (fs::path(self->dir_) / tile_file_name((int)col, (int)row)).string();
    std::FILE *f = std::fopen(p.c_str(), "rb");
    if (!f) return CT_ERR_ARG;
    const size_t got = std::fread(buf, 1, cap, f);
    std::fclose(f);
    self->files_read++;
    *bytes = buf;
    *len = got;
    return CT_OK;
}

TileCache::TileCache(TileSetFiles &files, int slots)
{
    if (slots < 1) throw Error("--cache-tiles must be at least 1");
    slots_.resize((size_t)slots);
    bufs_.resize((size_t)slots);
    const size_t cap = files.largest_tile();
    for (size_t k = 0; k < slots_.size(); ++k) {
        bufs_[k].resize(cap);
        slots_[k].buf = bufs_[k].data();
        slots_[k].cap = cap;
    }
    const ct_status st = ct_tileset_open(&ts_, files.manifest().data(), files.manifest().size(), slots_.data(),
                                         (uint32_t)slots_.size(), &TileSetFiles::loader, &files);
    if (st != CT_OK) throw Error(files.dir() + "/" + kManifestName + ": not a valid tile set (" + status_name(st) + ")");
}

size_t TileCache::slot_bytes() const
{
    size_t b = slots_.size() * sizeof(ct_tile_slot);
    for (const auto &v : bufs_) b += v.size();
    return b;
}

}  // namespace ct_host
