// tileset.cpp -- tile sets on the host (tileset.hpp).
#include "tileset.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
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

Terrain tile_terrain(const Terrain &t, const TileGrid &g, int col, int row)
{
    const int x0 = g.first_col(col), y0 = g.first_row(row);
    const int w = std::min(g.P, t.width - x0), h = std::min(g.P, t.height - y0);
    Terrain s;
    s.width = w;
    s.height = h;
    s.codes.resize((size_t)w * h);
    for (int j = 0; j < h; ++j)
        std::copy_n(&t.codes[(size_t)(y0 + j) * t.width + x0], w, &s.codes[(size_t)j * w]);
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
    s.geo = t.geo;
    s.geo.origin_e = t.geo.origin_e + x0 * t.geo.posting_e;
    s.geo.origin_n = t.geo.origin_n + y0 * t.geo.posting_n;
    s.geo.origin_nm_set = true;
    const int64_t oe = t.geo.origin_nm_set ? t.geo.origin_e_nm : metres_to_nm(t.geo.origin_e);
    const int64_t on = t.geo.origin_nm_set ? t.geo.origin_n_nm : metres_to_nm(t.geo.origin_n);
    s.geo.origin_e_nm = oe + (int64_t)x0 * metres_to_nm(t.geo.posting_e);
    s.geo.origin_n_nm = on + (int64_t)y0 * metres_to_nm(t.geo.posting_n);
    s.height_offset_m = t.height_offset_m;
    s.height_scale_m = t.height_scale_m;
    s.vdatum = t.vdatum;
    s.geoid = t.geoid;
    return s;
}

std::vector<uint8_t> make_manifest(const Terrain &t, const TileGrid &g, int reduce, int sectors,
                                   const std::vector<std::vector<uint8_t>> &tiles)
{
    const size_t n = (size_t)g.tiles_x * g.tiles_y;
    if (tiles.size() != n) throw Error("manifest: tile count mismatch");
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
    uint16_t lo = 65535, hi = 0;
    for (uint16_t v : t.codes) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
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
        const std::vector<uint8_t> &p = tiles[k];
        uint8_t *e = &m[CT_SET_HEADER_SIZE + k * CT_SET_ENTRY_SIZE];
        if (p.empty()) continue;  // no tile: present = 0
        if (p.size() < CT_PKG_HEADER_SIZE) throw Error("manifest: a tile is shorter than a header");
        put32(e, (uint32_t)p.size());
        put32(e + 4, get32(p, CT_HDR_CRC));
        put16(e + 8, get16(&p[CT_HDR_HMIN]));
        put16(e + 10, get16(&p[CT_HDR_HMAX]));
        e[12] = 1;
    }
    uint32_t crc = 0;
    ct_crc32(0u, m.data(), m.size(), &crc);  // the CRC field is still 0
    put32(m, CT_HDR_CRC, crc);
    return m;
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
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) throw Error(dir + ": exists and is not a directory");
    if (fs::is_directory(dir, ec) && !fs::is_empty(dir, ec) && !fs::exists(fs::path(dir) / kManifestName, ec))
        throw Error(dir + ": a non-empty directory that is not a tile set (refusing to replace it)");
    TileSetBytes b = build_tileset(t, opt, P, threads, nullptr, progress);
    fs::remove_all(tmp, ec);
    if (!fs::create_directories(tmp, ec)) throw Error(tmp + ": cannot create (" + ec.message() + ")");
    try {
        for (int row = 0; row < b.grid.tiles_y; ++row)
            for (int col = 0; col < b.grid.tiles_x; ++col)
                write_file_atomic((fs::path(tmp) / tile_file_name(col, row)).string(),
                                  b.tiles[(size_t)row * b.grid.tiles_x + col]);
        write_file_atomic((fs::path(tmp) / kManifestName).string(), b.manifest);
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
        throw;
    }
    fs::remove_all(old, ec);
    if (summary) {
        summary->grid = b.grid;
        summary->manifest = b.manifest;
        summary->tiles = std::move(b.tiles);
    }
}

bool is_tileset_path(const std::string &path)
{
    std::error_code ec;
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
