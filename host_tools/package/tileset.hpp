// tileset.hpp -- tile sets on the host: cutting a DEM into tiles that share
// their edge posts, building their packages and the manifest
// (lib/include/conetrace.h, "Tile sets"), and reading a tile set back from
// disk through the library's loader callback.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "conetrace.h"
#include "terrain.hpp"

namespace ct_host {

// The manifest's file name inside a tile set directory, and a tile's.
constexpr const char *kManifestName = "manifest.ctm";
std::string tile_file_name(int col, int row);

// Posts per side for tiles of at most `max_bytes` each (r, N as given):
// the largest 2^k + 1 (k >= 4) whose full-size package fits.
int default_tile_posts(int reduce, int sectors, size_t max_bytes = 4u << 20);

// The tile grid of a W x H post DEM cut into tiles of P posts per side.
struct TileGrid {
    int P = 0, tiles_x = 0, tiles_y = 0;
    int first_col(int c) const { return c * (P - 1); }
    int first_row(int r) const { return r * (P - 1); }
};
TileGrid tile_grid(int width, int height, int P);  // throws Error for P < 2

// Tile (col, row) of t: its posts (edge posts shared with its neighbours),
// voids, and the set's height coding; its origin exactly the set's plus
// whole postings (Georef::origin_nm_set).
Terrain tile_terrain(const Terrain &t, const TileGrid &g, int col, int row);

// A whole tile set in memory: the manifest and every tile's package
// (row-major; an empty vector where the set has no tile).
struct TileSetBytes {
    TileGrid grid;
    std::vector<uint8_t> manifest;
    std::vector<std::vector<uint8_t>> tiles;
};

// Build every tile (`threads` tiles at a time, each tile's builder on one
// thread; 0 = all cores) and the manifest.  `drop` (optional) names tiles
// to leave out (present = 0 in the manifest: no data there).  progress(done,
// total) counts tiles, from the calling thread.
TileSetBytes build_tileset(const Terrain &t, const BuildOptions &opt, int P, int threads = 0,
                           const std::function<bool(int col, int row)> &drop = nullptr,
                           const std::function<void(size_t, size_t)> &progress = nullptr);

// The same written to directory `dir`: built in "<dir>.tmp.<pid>" and
// renamed into place, so a failed build leaves no partial tile set (an
// existing tile set at dir is replaced only on success).  Throws Error.
void build_tileset_dir(const Terrain &t, const BuildOptions &opt, int P, const std::string &dir, int threads,
                       const std::function<void(size_t, size_t)> &progress, TileSetBytes *summary);

// The manifest for tiles already built (sizes, CRCs and code ranges taken
// from their headers).
std::vector<uint8_t> make_manifest(const Terrain &t, const TileGrid &g, int reduce, int sectors,
                                   const std::vector<std::vector<uint8_t>> &tiles);

// True when `path` is a tile set: a directory holding manifest.ctm, or a
// file starting with the manifest's magic.
bool is_tileset_path(const std::string &path);

// A tile set on disk, read on demand.  loader() is a ct_tile_loader (user:
// this object): it reads tile_<col>_<row>.ctp into the slot's buffer.
// Thread-safe (each call opens its own file); counts the files read.
class TileSetFiles {
public:
    explicit TileSetFiles(const std::string &path);  // directory or manifest file; throws Error
    const std::vector<uint8_t> &manifest() const { return manifest_; }
    const std::string &dir() const { return dir_; }
    uint32_t tiles_x() const, tiles_y() const;
    size_t largest_tile() const;  // bytes, from the manifest
    static ct_status loader(void *user, uint32_t col, uint32_t row, uint8_t *buf, size_t cap, const uint8_t **bytes,
                            size_t *len);
    std::atomic<uint64_t> files_read{0};

private:
    std::string dir_;
    std::vector<uint8_t> manifest_;
};

// One thread's view of a tile set: K slots with their buffers.
class TileCache {
public:
    TileCache(TileSetFiles &files, int slots);  // throws Error for a bad manifest
    ct_tileset *set() { return &ts_; }
    size_t slot_bytes() const;  // memory the slots hold (buffers + views)

private:
    ct_tileset ts_{};
    std::vector<ct_tile_slot> slots_;
    std::vector<std::vector<uint8_t>> bufs_;
};

}  // namespace ct_host
