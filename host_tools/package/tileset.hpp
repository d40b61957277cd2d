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
// The same into s, reusing its buffers (a worker's tiles one after another).
void tile_terrain(const Terrain &t, const TileGrid &g, int col, int row, Terrain &s);

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

// A DEM wider or taller than a tile set's merged frame holds (CT_MAX_POSTS
// = 32,768 posts per side; ct_tileset_open refuses more) is built into a
// *mosaic*: a directory of tile sets set_<bx>_<by>/, each an ordinary tile
// set of at most 32,768 posts and 64 x 64 tiles per side, neighbours
// sharing their edge posts, all cut from one global tile grid (tile
// (col, row) of the DEM is tile (col - bx K, row - by K) of set (bx, by),
// K tiles per set side) and with the whole DEM's height coding.
constexpr const char *kMosaicFirstSet = "set_0_0";
std::string mosaic_set_name(int bx, int by);
// The tile sets of a mosaic per side: K tiles of P posts, K = min(64,
// 32767 / (P - 1)).
int mosaic_set_tiles(int P);

// One row of the DEM's rows y0 .. y0 + n - 1 (metres as stored) and valid
// flags (1 valid, 0 nodata), n <= the reader's wish.
using RowReader = std::function<void(int y0, int n, std::vector<double> &h, std::vector<uint8_t> &valid)>;

struct StreamedSetSummary {
    int sets_x = 0, sets_y = 0;      // tile sets of the mosaic
    int tiles_x = 0, tiles_y = 0;    // the DEM's tile grid
    size_t bytes = 0, largest = 0;   // tiles and manifests; largest tile
    double lo_m = 0.0, scale_m = 0.0;
    double seconds_scan = 0.0, seconds_build = 0.0;
    size_t memory_estimate = 0;      // bytes, checked before the build
};

// The bytes a streamed build of a W x H DEM in tiles of P posts holds at
// once (a band of P rows of codes and voids, a chunk of read rows, and
// `threads` tiles being built), by the estimate checked before it starts.
size_t streamed_memory_estimate(int width, int height, int P, int chunk_rows, int threads, int reduce, int sectors);
// Its part per tile being built: a P x P tile's terrain, package and the
// builder's working memory at reduction r with N sectors (test_tiles
// checks it against a build's measured peak).
size_t tile_build_memory(int P, int reduce, int sectors);

// Build a W x H DEM (W or H beyond kMaxPackagePosts, at most
// kMaxTileSetDemPosts; vdatum and geoid as the whole DEM's Terrain has
// them, `read` giving heights already in that datum) read by `read` in
// chunks of `chunk_rows` rows into a
// mosaic of tile sets at `dir`, holding one band of tiles (P rows) at a
// time: a first pass finds the heights' range (the height coding,
// choose_height_scale(lo, hi, scale_m)), the second reads each band,
// quantises it and builds its tiles `threads` at a time (each tile copied
// out of the band first, so the next band is read while a band's last
// tiles are built), writing each to
// "<dir>.tmp.<pid>" as it is made; renamed into place on success (an
// existing tile set or mosaic at dir replaced, anything else refused).
// Refuses with Error when the memory estimate exceeds what the machine has
// available.  progress(phase, done, total) from the calling thread.
void build_mosaic_dir(int width, int height, const Georef &geo, double scale_m, int vdatum, const GeoidGrid &geoid,
                      const RowReader &read,
                      int chunk_rows, const BuildOptions &opt, int P, const std::string &dir, int threads,
                      const std::function<void(const char *phase, size_t, size_t)> &progress,
                      StreamedSetSummary *summary);

// True when `path` is a tile set: a directory holding manifest.ctm, or a
// file starting with the manifest's magic.  Throws Error for a mosaic of
// tile sets (is_mosaic_path), which no command but `info` reads whole.
bool is_tileset_path(const std::string &path);
// True when `path` is a directory holding a mosaic of tile sets
// (set_0_0/manifest.ctm and no manifest.ctm of its own); *sets_x, *sets_y
// (optional): how many sets per side it holds.
bool is_mosaic_path(const std::string &path, int *sets_x = nullptr, int *sets_y = nullptr);

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
