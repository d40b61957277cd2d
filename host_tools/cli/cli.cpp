// cli.cpp -- the `conetrace` command line tool (a thin shell over lib/).
//
//   conetrace build DEM -o OUT.ctp [--sectors N] [--reduce r] [--slices K]
//                   [--height-scale M] [--posting M] [--threads T]
//   conetrace info PKG
//   conetrace trace PKG --rays rays.csv [--method M] -o hits.csv
//   conetrace demo DEM
//
// rays.csv: header, columns E,N,h,dE,dN,dh (map frame, metres).
// hits.csv: header status,E,N,h,t,steps; one row per ray in input order;
//           E,N,h,t are nan when nothing is hit.  t: hit = origin + t*d.
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <atomic>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "conetrace.h"
#include "dem_io.hpp"
#include "emit_c.hpp"
#include "host_io.hpp"
#include "terrain.hpp"
#include "tileset.hpp"
#include "vdatum.hpp"
#include "warp.hpp"

namespace fs = std::filesystem;

using namespace ct_host;

namespace ct_host {
// cmd_demo.cpp: geolocation, the picture and the table of the demo
int demo_main_job(const std::vector<uint8_t> &pkg, const Terrain &t, const std::map<std::string, std::string> &opt);
}  // namespace ct_host

namespace {

// One usage block per command: `conetrace --help` prints them all,
// `conetrace CMD --help` its own (both on stdout, exit 0).
struct UsageBlock {
    const char *cmd, *text;
};
const UsageBlock kUsage[] = {
    {"build",
     "conetrace build DEM -o OUT.ctp [--sectors N] [--reduce r] [--slices K]\n"
     "                [--height-scale M] [--posting M] [--threads T]\n"
     "                [--builder slices|brute] [--window R] [--levels H1,H2,...]\n"
     "                [--emit-c NAME] [--vdatum egm96|ellipsoid|unknown]\n"
     "                [--utm ZONE{N|S}]   (geographic DEMs: resampled onto UTM at --posting M)\n"
     "                [--tile-size P|auto]  (a tile set: -o names a directory of tiles of P posts\n"
     "                and their manifest; auto: tiles of at most 4 MB; a DEM over 32768 posts\n"
     "                per side: a mosaic of tile sets DIR/set_<x>_<y>)\n"},
    {"info", "conetrace info PKG_or_TILESET\n"},
    {"trace", "conetrace trace PKG_or_TILESET --rays rays.csv [--method M] [--threads T] [--cache-tiles K]\n"
              "                -o hits.csv\n"},
    {"demo",
     "conetrace demo DEM --camera C.cameramodel [--tolerance M | --effects LIST] [--step PX]\n"
     "               [--sectors N] [--reduce r] [-o DIR]\n"
     "               (the main job: package the DEM, geolocate a grid of the camera's pixels,\n"
     "               draw DIR/footprint.png and list DIR/pixels.csv; DIR defaults to demo)\n"},
    {"geoloc",
     "conetrace geoloc PKG_or_TILESET --camera C.cameramodel --pixels px.csv [--method M]\n"
     "                 [--pose-wgs84 LAT,LON,H,YAW,PITCH,ROLL | --pose-map E,N,H,YAW,PITCH,ROLL]\n"
     "                 [--effects curvature,refraction] [--refraction-k K]\n"
     "                 [--tolerance M] [--chord M] [--earth-radius M] [--earth-map auto|fitted|exact]\n"
     "                 [--grid-step PX]\n"
     "                 [--threads T] [--cache-tiles K] -o g.csv\n"
     "                 (curvature on a UTM package: the true Earth, its map fitted once per\n"
     "                 chunk of pixels when there are 256 or more (auto); --earth-radius: a sphere)\n"},
    {"viewshed",
     "conetrace viewshed PKG --observer E,N,H [--target-height M] [--radius M] [--effects LIST]\n"
     "                   [--earth-radius M] [--margin M] [--threads T] -o vs.tif [--png vs.png]\n"
     "                   (H above the surface; every post by the library's exact line of sight)\n"},
    {"shadows",
     "conetrace shadows PKG --sun AZ,EL [--lift M] [--method M] [--threads T] -o shadow.tif [--png shadow.png]\n"
     "                  (a ray from every post towards the sun, AZ clockwise from grid north)\n"},
    {"view",
     "conetrace view PKG --camera C.cameramodel [--effects LIST] [--threads T] -o view.png\n"
     "               [--range range.tif]   (every pixel traced: shaded terrain, and its range)\n"},
    {"render",
     "conetrace render DEM_or_PKG --what bitmap|dt|ddt|angles|apex -o OUT.png\n"
     "                 [--slice H | --level k --slices K] [--reduce r] [--sectors N]\n"
     "                 [--sector LIST] [--range LO,HI] [--hillshade] [--zoom Z]\n"
     "                 [--columns C] [--no-legend] [--threads T]\n"},
};

// cmd == nullptr: every command
void print_usage(std::FILE *f, const char *cmd = nullptr)
{
    bool first = true;
    for (const UsageBlock &u : kUsage) {
        if (cmd && std::strcmp(cmd, u.cmd) != 0) continue;
        std::fprintf(f, "%s%s", first ? "usage: " : "       ", u.text);
        first = false;
    }
    if (first) return print_usage(f);  // unknown command: all of them
    std::fprintf(f, "methods: incremental, hierarchical, cone, directional (default)\n"
                    "details: docs/cli.md\n");
}

[[noreturn]] void usage(const std::string &msg)
{
    std::fprintf(stderr, "conetrace: %s\n", msg.c_str());
    print_usage(stderr);
    std::exit(2);
}

bool is_help(const std::string &s) { return s == "-h" || s == "--help" || s == "help"; }

using Args = CmdLine;

Args parse(int argc, char **argv, int first, const std::vector<std::string> &valued)
{
    Args a;
    const std::string err = parse_cmdline(argc, argv, first, valued, {}, false, &a);
    if (!err.empty()) usage(err);
    return a;
}

int to_int(const Args &a, const std::string &k, int def)
{
    auto it = a.opt.find(k);
    if (it == a.opt.end()) return def;
    char *end = nullptr;
    errno = 0;
    long v = std::strtol(it->second.c_str(), &end, 10);
    if (it->second.empty() || !end || *end || errno == ERANGE || v < -1000000 || v > 1000000)
        usage(k + " needs an integer in range, got '" + it->second + "'");
    return (int)v;
}

double to_double(const Args &a, const std::string &k, double def)
{
    auto it = a.opt.find(k);
    if (it == a.opt.end()) return def;
    char *end = nullptr;
    double v = std::strtod(it->second.c_str(), &end);
    if (it->second.empty() || !end || *end || !std::isfinite(v) || v <= 0 || v > 1e6)
        usage(k + " needs a positive number of metres (at most 1e6), got '" + it->second + "'");
    return v;
}

ct_method parse_method(const std::string &m)
{
    try {
        return method_named(m);
    } catch (const Error &e) {
        usage(e.what());
    }
}

Terrain load_terrain(const std::string &path, double posting, double hscale, int vdatum = CT_VDATUM_UNKNOWN,
                     const WarpOptions &utm = WarpOptions(), std::string *resampled = nullptr)
{
    // a DEM on a geographic CRS (with --utm: on any CRS but that zone) is resampled onto UTM
    const bool warp = dem_needs_warp(path, utm);
    WarpOptions w = utm;
    w.posting_m = posting;
    DemRaster r = warp ? warp_dem(path, w) : read_dem(path);
    if (warp && resampled) *resampled = " (" + warp_summary(r) + ")";
    Georef g = r.geo;
    if (!r.has_georef) {
        if (posting <= 0) throw Error(path + ": no georeference in the file; give --posting METRES");
        g = Georef{};
        g.posting_e = posting;
        g.posting_n = -posting;
    } else if (posting > 0 && !warp) {
        g.posting_e = std::copysign(posting, g.posting_e);
        g.posting_n = std::copysign(posting, g.posting_n);
    }
    try {
        GeoidGrid geoid;
        apply_vdatum(r.h, r.valid, r.width, r.height, g, vdatum, geoid);  // heights -> ellipsoidal
        Terrain t = terrain_from_heights(r.width, r.height, r.h, r.valid, g, hscale);
        t.vdatum = vdatum;
        t.geoid = std::move(geoid);
        return t;
    } catch (const Error &e) {
        throw Error(path + ": " + e.what());
    }
}

// `build --tile-size P`: a tile set in directory `out`.
int build_tiles(const Terrain &t, const BuildOptions &o, int P, const std::string &out,
                std::chrono::steady_clock::time_point t0, const std::string &resampled)
{
    const TileGrid g = tile_grid(t.width, t.height, P);
    Progress bar("building " + std::to_string(g.tiles_x * g.tiles_y) + " tiles");
    TileSetBytes sum;
    build_tileset_dir(t, o, P, out, o.threads, [&](size_t d, size_t n) { bar.update(d, n); }, &sum);
    bar.finish();
    size_t bytes = sum.manifest.size(), largest = 0;
    for (const auto &tile : sum.tiles) {
        bytes += tile.size();
        largest = std::max(largest, tile.size());
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s/: %dx%d posts%s in %d x %d tiles of %d posts (edge posts shared), %d sectors, r=%d, "
                "%zu bytes in all (%.2fx the 16-bit DEM), largest tile %zu bytes; %s and tile_<col>_<row>.ctp; "
                "built in %.2f s\n",
                out.c_str(), t.width, t.height, resampled.c_str(), g.tiles_x, g.tiles_y, P, o.sectors, o.reduce, bytes,
                (double)bytes / (2.0 * t.width * t.height), largest, kManifestName, secs);
    return 0;
}

// `build --tile-size P` of a DEM beyond one tile set's frame: a mosaic of
// tile sets, read and built one band of tiles at a time.
int build_mosaic(const std::string &path, DemRows &rows, double posting, double hscale, int vdatum,
                 const BuildOptions &o, int P, const std::string &out, std::chrono::steady_clock::time_point t0)
{
    const DemRaster &hd = rows.header();
    Georef g = hd.geo;
    if (!hd.has_georef) {
        if (posting <= 0) throw Error(path + ": no georeference in the file; give --posting METRES");
        g = Georef{};
        g.posting_e = posting;
        g.posting_n = -posting;
    } else if (posting > 0) {
        g.posting_e = std::copysign(posting, g.posting_e);
        g.posting_n = std::copysign(posting, g.posting_n);
    }
    GeoidGrid geoid;  // over the whole DEM, in every tile, as load_terrain makes it
    try {
        geoid = vdatum_grid(g, hd.width, hd.height, vdatum);
    } catch (const Error &e) {
        throw Error(path + ": " + e.what());
    }
    // read in chunks of whole TIFF tiles or strips, about 4 M posts each
    const int block = std::max(1, hd.block_rows);
    const int chunk = block * std::max(1, (int)std::min<size_t>(1u << 20, (4u << 20) / ((size_t)block * hd.width)));
    const int K = mosaic_set_tiles(P);
    const int tx = (hd.width - 1 + P - 2) / (P - 1), ty = (hd.height - 1 + P - 2) / (P - 1);
    std::unique_ptr<Progress> bar;
    std::string phase;
    StreamedSetSummary sum;
    try {
        build_mosaic_dir(
            hd.width, hd.height, g, hscale, vdatum, geoid,
            [&](int y0, int n, std::vector<double> &h, std::vector<uint8_t> &valid) {
                rows.read(y0, n, h, valid);
                apply_vdatum_rows(h, valid, hd.width, y0, n, g, vdatum, geoid);  // heights -> ellipsoidal
            },
            chunk, o, P, out, o.threads,
            [&](const char *what, size_t d, size_t n) {
                if (phase != what) {
                    if (phase.empty())  // the checks passed: what is built, then the progress
                        std::fprintf(stderr,
                                     "%s: %dx%d posts, more than a tile set's frame holds (%d per side): a mosaic of "
                                     "%d x %d tile sets of up to %d x %d tiles of %d posts, one band of tiles at a "
                                     "time\n",
                                     path.c_str(), hd.width, hd.height, kMaxPackagePosts, (tx + K - 1) / K,
                                     (ty + K - 1) / K, K, K, P);
                    if (bar) bar->finish();
                    phase = what;
                    bar = std::make_unique<Progress>(phase);
                }
                bar->update(d, n);
            },
            &sum);
    } catch (const Error &e) {
        const std::string w = e.what();
        // the reader's errors name the DEM already; the builder's name the output
        if (w.compare(0, path.size(), path) == 0 || w.compare(0, out.size(), out) == 0) throw;
        throw Error(path + ": " + w);
    }
    if (bar) bar->finish();
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s/: %dx%d posts in a mosaic of %d x %d tile sets (set_<x>_<y>/, edge posts shared) of %d x %d tiles "
                "of %d posts in all, %d sectors, r=%d, %zu bytes in all (%.2fx the 16-bit DEM), largest tile %zu bytes; "
                "heights %.4f m + code x %.6g m; built in %.2f s (%.2f s scanning heights), peak resident %.1f MB "
                "(estimate %.1f MB)\n",
                out.c_str(), hd.width, hd.height, sum.sets_x, sum.sets_y, sum.tiles_x, sum.tiles_y, P, o.sectors,
                o.reduce, sum.bytes, (double)sum.bytes / (2.0 * hd.width * hd.height), sum.largest, sum.lo_m,
                sum.scale_m, secs, sum.seconds_scan, proc_status_kib("VmHWM") * 1024.0 / 1e6,
                sum.memory_estimate / 1e6);
    return 0;
}

int cmd_build(int argc, char **argv)
{
    Args a = parse(argc, argv, 2,
                   {"-o", "--sectors", "--reduce", "--slices", "--height-scale", "--posting", "--threads", "--emit-c", "--builder", "--window", "--levels", "--vdatum", "--utm", "--tile-size"});
    if (a.pos.size() != 1) usage("build needs exactly one DEM file");
    if (!a.opt.count("-o")) usage("build needs -o OUT.ctp");
    BuildOptions o;
    o.sectors = to_int(a, "--sectors", 24);
    o.reduce = to_int(a, "--reduce", 3);
    o.slices = to_int(a, "--slices", 0);
    o.threads = to_int(a, "--threads", 0);
    o.window = to_int(a, "--window", o.window);
    if (a.opt.count("--builder")) {
        const std::string &b = a.opt["--builder"];
        if (b == "slices") o.builder = PptBuilder::Slices;
        else if (b == "brute") o.builder = PptBuilder::Brute;
        else usage("--builder " + b + ": expected slices or brute");
    }
    if (o.window < 1 || o.window > 64) usage("--window must be in 1..64");
    if (a.opt.count("--levels")) {
        if (o.builder != PptBuilder::Slices) usage("--levels needs the slice builder");
        if (a.opt.count("--slices")) usage("--levels and --slices exclude each other");
        std::stringstream ls(a.opt["--levels"]);
        std::string item;
        while (std::getline(ls, item, ',')) {
            char *end = nullptr;
            double v = std::strtod(item.c_str(), &end);
            if (item.empty() || *end != '\0' || !std::isfinite(v)) usage("--levels: '" + item + "' is not a height in metres");
            o.levels_m.push_back(v);
        }
        if (o.levels_m.empty()) usage("--levels needs at least one height");
    }
    if (o.sectors < 1 || o.sectors > 64) usage("--sectors must be in 1..64");
    if (o.reduce < 1 || o.reduce > 8) usage("--reduce must be in 1..8");
    if (o.slices < 0) usage("--slices must be >= 0");
    const std::string out = a.opt["-o"];
    if (a.opt.count("--emit-c") && !is_c_identifier(a.opt["--emit-c"]))
        usage("--emit-c " + a.opt["--emit-c"] + ": not a C identifier (letters, digits, _; at most 31)");
    auto t0 = std::chrono::steady_clock::now();
    int vdatum = CT_VDATUM_UNKNOWN;
    if (a.opt.count("--vdatum")) {
        try {
            vdatum = parse_vdatum(a.opt["--vdatum"]);
        } catch (const Error &e) {
            usage(std::string("--vdatum: ") + e.what());
        }
    }
    WarpOptions utm;
    if (a.opt.count("--utm")) {
        try {
            parse_utm_zone(a.opt["--utm"], &utm);
        } catch (const Error &e) {
            throw Error(std::string("--utm: ") + e.what());
        }
    }
    int tile_posts = 0;
    if (a.opt.count("--tile-size")) {
        if (a.opt.count("--emit-c")) usage("--emit-c and --tile-size exclude each other (emit a tile's package instead)");
        tile_posts = a.opt["--tile-size"] == "auto" ? default_tile_posts(o.reduce, o.sectors)
                                                    : to_int(a, "--tile-size", 0);
        if (tile_posts < 2 || tile_posts > CT_MAX_POSTS) usage("--tile-size must be auto or 2..32768 posts");
    }
    std::string resampled;
    {
        // the size from the header first: a DEM beyond one package is refused
        // (or streamed into a mosaic of tile sets) before its pixels are read
        const bool warp = dem_needs_warp(a.pos[0], utm);
        std::unique_ptr<DemRows> rows;
        try {
            rows = std::make_unique<DemRows>(a.pos[0]);
        } catch (const Error &) {
            if (!warp) throw;  // GDAL may read what OpenImageIO does not: the warper says
        }
        const int w = rows ? rows->header().width : 0, h = rows ? rows->header().height : 0;
        if (w > kMaxPackagePosts || h > kMaxPackagePosts) {
            if (warp)
                throw Error(a.pos[0] + ": DEM of " + std::to_string(w) + "x" + std::to_string(h) +
                            " posts: resampling onto UTM holds the whole DEM and takes at most " +
                            std::to_string(kMaxPackagePosts) + " posts per side (resample it in pieces, e.g. gdalwarp)");
            if (tile_posts == 0) throw Error(a.pos[0] + ": " + too_wide_for_package(w, h));
            return build_mosaic(a.pos[0], *rows, to_double(a, "--posting", 0), to_double(a, "--height-scale", 0),
                                vdatum, o, tile_posts, out, t0);
        }
    }
    Terrain t = load_terrain(a.pos[0], to_double(a, "--posting", 0), to_double(a, "--height-scale", 0), vdatum, utm,
                             &resampled);
    if (tile_posts > 0) return build_tiles(t, o, tile_posts, out, t0, resampled);
    Progress bar("building cones");
    o.progress = [&](size_t d, size_t n) { bar.update(d, n); };
    BuildStats st;
    // working memory of the build: the peak resident size while the
    // package is built and written (streamed to the file) above the
    // resident size before it (the DEM and the libraries)
    double rss0 = proc_status_kib("VmRSS") * 1024.0;
    reset_peak_rss();
    build_package_file(t, o, out, &st);
    double work = std::max(0.0, proc_status_kib("VmHWM") * 1024.0 - rss0);
    bar.finish();
    if (a.opt.count("--emit-c")) {
        RemovedIfInterrupted all_or_none(out);  // the package goes if the C array is interrupted
        try {
            emit_c_array(out, a.opt["--emit-c"]);
        } catch (...) {
            std::remove(out.c_str());  // all outputs or none
            throw;
        }
    }
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    size_t dem_bytes = (size_t)t.width * t.height * 2;
    std::string how = "brute-force builder";
    if (o.builder == PptBuilder::Slices) {
        char buf[300];
        std::snprintf(buf, sizeof buf,
                      "slice builder: %d levels, %d slices x %d sectors, %.2f DT queries per cell and slice-sector "
                      "(%.1f rows each), %zu full DTs; %.2f s near, %.2f s slices",
                      st.slices, st.slices_transformed, o.sectors,
                      (double)st.dt_queries / std::max(1.0, (double)st.slices_transformed * (double)st.cones),
                      (double)st.dt_query_rows / std::max<double>(1.0, (double)st.dt_queries), st.full_dts, st.seconds_local,
                      st.seconds_dt);
        how = buf;
    }
    std::printf("%s: %dx%d posts%s, %d sectors, r=%d, package %zu bytes (%.2fx the 16-bit DEM), "
                "%.1f%% degenerate cones, built in %.2f s (%s), working memory %.1f MB (%.2fx the DEM)\n",
                out.c_str(), t.width, t.height, resampled.c_str(), o.sectors, o.reduce, st.bytes, (double)st.bytes / dem_bytes,
                100.0 * st.degenerate_cones / std::max<size_t>(1, st.cones), secs, how.c_str(), work / 1e6,
                work / dem_bytes);
    return 0;
}

// info's heights, origin, posting and EPSG lines (a package, or a set's frame)
void print_heights_georef(const ct_package &p)
{
    std::printf("heights       codes %d..%d = %.4f..%.4f m (%.6g m per LSB)\n", p.hmin, p.hmax,
                (p.height_offset_nm + p.hmin * p.height_scale_nm) * 1e-9,
                (p.height_offset_nm + p.hmax * p.height_scale_nm) * 1e-9, p.height_scale_nm * 1e-9);
    std::printf("origin        E %.9f N %.9f (corner of pixel 0,0)\n", p.origin_e_nm * 1e-9, p.origin_n_nm * 1e-9);
    std::printf("posting       %.9f x %.9f m\n", p.posting_e_nm * 1e-9, p.posting_n_nm * 1e-9);
    std::printf("epsg          %u\n", p.epsg);
}

// `info` on a tile set: the grid, its coverage and sizes, every tile checked
// by loading it as the library would (CRC, the manifest's size and CRC, its
// place).
int info_tiles(const std::string &path)
{
    TileSetFiles files(path);
    TileCache cache(files, 1);
    ct_tileset *ts = cache.set();
    const ct_package &f = ts->frame;
    const size_t n = (size_t)ts->tiles_x * ts->tiles_y;
    size_t present = 0, bytes = files.manifest().size(), largest = 0, bad = 0;
    std::vector<std::string> problems;
    for (uint32_t row = 0; row < ts->tiles_y; ++row)
        for (uint32_t col = 0; col < ts->tiles_x; ++col) {
            const uint8_t *e = ts->entries + (size_t)(row * ts->tiles_x + col) * CT_SET_ENTRY_SIZE;
            if (!e[12]) continue;
            present++;
            const uint32_t sz = (uint32_t)e[0] | (uint32_t)e[1] << 8 | (uint32_t)e[2] << 16 | (uint32_t)e[3] << 24;
            bytes += sz;
            largest = std::max<size_t>(largest, sz);
            // one ray straight down through the tile's first cell loads it
            ct_ray r{};
            r.x_q16 = ((int64_t)col * (ts->tile_posts - 1) << 16) + 32768;
            r.y_q16 = ((int64_t)row * (ts->tile_posts - 1) << 16) + 32768;
            r.z_q16 = ((int64_t)f.hmax + 1) << 16;
            r.dz = -1;
            ct_hit h;
            if (ct_tileset_trace(ts, &r, CT_METHOD_INCREMENTAL, &h) == CT_NO_DATA) {
                bad++;
                if (problems.size() < 8) problems.push_back(files.dir() + "/" + tile_file_name((int)col, (int)row));
            }
        }
    std::printf("tile set      %s (manifest %s)\n", files.dir().c_str(), kManifestName);
    std::printf("tiles         %u x %u of %u posts (edge posts shared), %zu of %zu present (%.1f%% coverage)\n",
                ts->tiles_x, ts->tiles_y, ts->tile_posts, present, n, 100.0 * present / std::max<size_t>(1, n));
    std::printf("posts         %u x %u (cells %u x %u), merged\n", f.width, f.height, f.cells_x, f.cells_y);
    std::printf("sectors       %u\nreduce        %u\n", f.sectors, f.reduce);
    print_heights_georef(f);
    std::printf("size          %zu bytes in all (%.2fx the 16-bit DEM), largest tile %zu bytes\n", bytes,
                (double)bytes / (2.0 * f.width * f.height), largest);
    std::printf("verify        %s\n", bad == 0 ? "ok (every tile loads and matches the manifest)" : "FAILED");
    for (const std::string &pth : problems) std::printf("  bad tile    %s\n", pth.c_str());
    return bad == 0 ? 0 : 1;
}

int cmd_info(int argc, char **argv)
{
    Args a = parse(argc, argv, 2, {});
    if (a.pos.size() != 1) usage("info needs exactly one package file");
    int sets_x = 0, sets_y = 0;
    if (is_mosaic_path(a.pos[0], &sets_x, &sets_y)) {
        // a mosaic: each of its tile sets as `info` on it would show it
        std::printf("mosaic        %s: %d x %d tile sets set_<x>_<y>/ (edge posts shared)\n", a.pos[0].c_str(), sets_x,
                    sets_y);
        int rc = 0;
        for (int by = 0; by < sets_y; ++by)
            for (int bx = 0; bx < sets_x; ++bx) {
                std::printf("\n");
                std::fflush(stdout);
                rc = std::max(rc, info_tiles((fs::path(a.pos[0]) / mosaic_set_name(bx, by)).string()));
            }
        return rc;
    }
    if (is_tileset_path(a.pos[0])) return info_tiles(a.pos[0]);
    std::vector<uint8_t> bytes;
    ct_package p;
    open_package_file(a.pos[0], &bytes, &p);
    size_t deg = 0, cones = (size_t)p.coarse_x * p.coarse_y * p.sectors;
    for (size_t k = 0; k < cones; ++k) deg += p.angles[k] == 0;
    std::printf("file          %s\n", a.pos[0].c_str());
    std::printf("size          %u bytes (%.2fx the 16-bit DEM)\n", p.size, (double)p.size / (2.0 * p.width * p.height));
    std::printf("posts         %u x %u (cells %u x %u)\n", p.width, p.height, p.cells_x, p.cells_y);
    std::printf("sectors       %u\nreduce        %u (coarse %u x %u)\n", p.sectors, p.reduce, p.coarse_x, p.coarse_y);
    std::printf("slices        %u\nmip levels    %u\n", p.slices, p.levels);
    print_heights_georef(p);
    std::printf("voids         %s\n", p.voids ? "yes" : "no");
    if (p.source_epsg != 0) std::printf("resampled     from EPSG:%u\n", p.source_epsg);
    if (p.vdatum == CT_VDATUM_UNKNOWN)
        std::printf("vertical      unknown datum (heights as in the DEM)\n");
    else
        std::printf("vertical      WGS84 ellipsoidal heights (the DEM's were %s)\n",
                    p.vdatum == CT_VDATUM_EGM96 ? "above the EGM96 geoid" : "ellipsoidal");
    if (p.geoid.w > 0)
        std::printf("geoid         EGM96, %u x %u nodes every %.4g deg\n", p.geoid.w, p.geoid.h, (double)p.geoid.step_q61 / 2305843009213693952.0 * 180 / M_PI);
    std::printf("degenerate    %.2f%% of %zu sector cones\n", 100.0 * deg / std::max<size_t>(1, cones), cones);
    std::printf("verify        %s\n", ct_package_verify(&p) == CT_OK ? "ok" : "FAILED");
    return 0;
}

int cmd_trace(int argc, char **argv)
{
    Args a = parse(argc, argv, 2, {"--rays", "--method", "--threads", "--cache-tiles", "-o"});
    if (a.pos.size() != 1) usage("trace needs exactly one package file or tile set");
    if (!a.opt.count("--rays")) usage("trace needs --rays rays.csv");
    if (!a.opt.count("-o")) usage("trace needs -o hits.csv");
    ct_method m = parse_method(a.opt.count("--method") ? a.opt["--method"] : "directional");
    const int threads = a.opt.count("--threads") ? threads_option(a.opt["--threads"], "trace") : 0;
    // a package, or a tile set read through per-thread caches of K tiles
    std::vector<uint8_t> bytes;
    ct_package p;
    std::unique_ptr<TileSetFiles> tiles;
    const int cache_tiles = to_int(a, "--cache-tiles", 16);
    if (is_tileset_path(a.pos[0])) {
        if (cache_tiles < 1) usage("--cache-tiles must be at least 1");
        tiles = std::make_unique<TileSetFiles>(a.pos[0]);
        TileCache probe(*tiles, 1);
        p = probe.set()->frame;
    } else {
        if (a.opt.count("--cache-tiles")) usage("--cache-tiles needs a tile set");
        open_package_file(a.pos[0], &bytes, &p);
    }
    std::vector<MapRay> rays = read_rays_csv(a.opt["--rays"]);
    // rows formatted by the threads into their chunk's part, written in
    // input order
    const size_t chunk = tiles ? 8192 : 1024;
    std::vector<std::string> parts((rays.size() + chunk - 1) / chunk);
    std::atomic<uint64_t> loads{0}, nodata{0};
    std::atomic<size_t> caches{0}, cache_bytes{0};
    parallel_chunks(rays.size(), threads, chunk, [&](size_t b, size_t e) {
        std::string &o = parts[b / chunk];
        o.reserve((e - b) * 64);
        std::unique_ptr<TileCache> cache;
        if (tiles) {
            cache = std::make_unique<TileCache>(*tiles, cache_tiles);
            caches++;
            cache_bytes = std::max(cache_bytes.load(), cache->slot_bytes());
        }
        char line[256];
        for (size_t k = b; k < e; ++k) {
            const MapRay &r = rays[k];
            ct_ray gr;
            ct_hit h;
            ct_status s = map_ray_to_grid(p, r, &gr);
            if (s == CT_OK) s = cache ? ct_tileset_trace(cache->set(), &gr, m, &h) : ct_trace(&p, &gr, m, &h);
            if (s == CT_HIT || s == CT_HIT_VOID || s == CT_NO_DATA) {
                // no_data: where the ray reached terrain the set does not hold
                double e_m = h.e_nm * 1e-9, n_m = h.n_nm * 1e-9, hh = h.h_nm * 1e-9;
                double d2 = r.de * r.de + r.dn * r.dn + r.dh * r.dh;
                double t = ((e_m - r.e) * r.de + (n_m - r.n) * r.dn + (hh - r.h) * r.dh) / d2;
                std::snprintf(line, sizeof line, "%s,%.6f,%.6f,%.6f,%.9g,%u\n", status_name(s).c_str(), e_m, n_m, hh, t,
                              h.steps);
                if (s == CT_NO_DATA) nodata++;
            } else if (s >= 0) {
                std::snprintf(line, sizeof line, "%s,nan,nan,nan,nan,%u\n", status_name(s).c_str(),
                              s == CT_MISS || s == CT_BELOW ? h.steps : 0u);
            } else {
                std::snprintf(line, sizeof line, "%s,nan,nan,nan,nan,0\n", status_name(s).c_str());
            }
            o += line;
        }
        if (cache) loads += cache->set()->loads;
    });
    write_file_atomic(a.opt["-o"], "status,E,N,h,t,steps\n", parts);
    if (tiles)
        std::fprintf(stderr,
                     "trace: %zu rays over %u x %u tiles: %llu tile loads (%zu caches of %d slots, one per chunk of "
                     "8192 rays), %.1f MB of tiles in memory per cache, %llu files read, %llu rays reached missing "
                     "or bad tiles (no_data)\n",
                     rays.size(), tiles->tiles_x(), tiles->tiles_y(), (unsigned long long)loads.load(), caches.load(),
                     cache_tiles, cache_bytes.load() / 1e6, (unsigned long long)tiles->files_read.load(),
                     (unsigned long long)nodata.load());
    return 0;
}

int cmd_demo(int argc, char **argv)
{
    Args a = parse(argc, argv, 2, {"--camera", "--effects", "--tolerance", "--step", "--sectors", "--reduce", "-o"});
    if (a.pos.size() != 1) usage("demo needs a DEM file");
    if (!a.opt.count("--camera")) usage("demo needs --camera C.cameramodel");
    Terrain t = load_terrain(a.pos[0], 0, 0);
    BuildOptions o;
    o.sectors = to_int(a, "--sectors", 24);
    o.reduce = to_int(a, "--reduce", 3);
    Progress bar("building cones");
    o.progress = [&](size_t d, size_t n) { bar.update(d, n); };
    BuildStats bs;
    std::vector<uint8_t> pkg = build_package(t, o, &bs);
    bar.finish();
    std::printf("DEM %s: %dx%d posts, %.0f m posting, EPSG:%d; package %zu bytes (%.2fx the DEM), %d sectors, r=%d, "
                "built in %.2f s\n",
                a.pos[0].c_str(), t.width, t.height, std::fabs(t.geo.posting_e), t.geo.epsg, pkg.size(),
                pkg.size() / (2.0 * t.width * t.height), o.sectors, o.reduce, bs.seconds);
    return demo_main_job(pkg, t, a.opt);
}

}  // namespace

int cmd_geoloc(int argc, char **argv);  // cmd_geoloc.cpp
int cmd_render(int argc, char **argv);  // cmd_render.cpp
int cmd_viewshed(int argc, char **argv);  // cmd_viewshed.cpp
int cmd_shadows(int argc, char **argv);   // cmd_shadows.cpp
int cmd_view(int argc, char **argv);      // cmd_view.cpp

int main(int argc, char **argv)
{
    if (argc < 2) usage("missing command");
    std::string cmd = argv[1];
    // `conetrace --help` and `conetrace CMD --help`: the usage on stdout, exit 0
    if (is_help(cmd)) {
        print_usage(stdout);
        return 0;
    }
    for (int k = 2; k < argc; ++k) {
        if (std::strcmp(argv[k], "-h") == 0 || std::strcmp(argv[k], "--help") == 0) {
            print_usage(stdout, cmd.c_str());
            return 0;
        }
    }
    // Ctrl-C, SIGTERM, SIGHUP: the temporaries in progress removed, one line
    // naming the output (-o), the process ended by the signal (temp_output.hpp)
    std::string output;
    for (int k = 2; k + 1 < argc; ++k)
        if (std::strcmp(argv[k], "-o") == 0) output = argv[k + 1];
    remove_temporaries_on_interrupt("conetrace", output);
    try {
        if (cmd == "build") return cmd_build(argc, argv);
        if (cmd == "info") return cmd_info(argc, argv);
        if (cmd == "trace") return cmd_trace(argc, argv);
        if (cmd == "demo") return cmd_demo(argc, argv);
        if (cmd == "geoloc") return cmd_geoloc(argc, argv);
        if (cmd == "render") return cmd_render(argc, argv);
        if (cmd == "viewshed") return cmd_viewshed(argc, argv);
        if (cmd == "shadows") return cmd_shadows(argc, argv);
        if (cmd == "view") return cmd_view(argc, argv);
        usage("unknown command '" + cmd + "'");
    } catch (const std::exception &e) {
        std::fprintf(stderr, "conetrace: %s\n", e.what());
        return 1;
    }
}
