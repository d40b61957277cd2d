// cmd_geoloc.cpp -- `conetrace geoloc`: pixels of a camera to map points.
//
//   conetrace geoloc PKG --camera C.cameramodel --pixels px.csv [--method M]
//                        [--pose-wgs84 LAT,LON,H,YAW,PITCH,ROLL | --pose-map E,N,H,YAW,PITCH,ROLL]
//                        [--effects LIST] [--refraction-k K] [--earth-radius M]
//                        [--grid-step PX] [--threads T] -o g.csv
//
// C.cameramodel: an mrcal camera model (read by libmrcal's C reader); its
//   extrinsics are rt_cam_ref with the package's map frame (metres) as the
//   reference.  Lens models: LENSMODEL_PINHOLE, LENSMODEL_OPENCV4/5/8 in
//   closed form; any other model mrcal can unproject (e.g.
//   LENSMODEL_SPLINED_STEREOGRAPHIC_...) is baked into an unprojection grid
//   with --grid-step PX (default 16) between nodes.
// px.csv: header naming u and v, one pixel per line (mrcal convention:
//   (0,0) is the centre of the top-left pixel).
// --pose-wgs84 LAT,LON,H,YAW,PITCH,ROLL: the camera centre in WGS84 (degrees;
//   H metres above the ellipsoid on a package whose datum is known, else in
//   the DEM's heights) and its attitude w.r.t. local
//   north-east-down, aerospace yaw-pitch-roll in degrees (at zero the
//   camera's x, y, z point east, down, north); the model's extrinsics are
//   ignored.  Needs a UTM package (EPSG 326zz/327zz): ct_pose_from_wgs84.
// --pose-map E,N,H,YAW,PITCH,ROLL: the same in the package's map frame
//   (metres; the attitude w.r.t. grid north, grid east, down):
//   ct_pose_from_map.
// g.csv: header u,v,status,E,N,h,steps,lat,lon,h_ell; one row per pixel, in
//   input order; u,v echoed as given; E,N,h in metres with all nine decimals
//   of the library's nanometres (nan when nothing is hit), h in the DEM's own
//   vertical datum (above EGM96 for an EGM96 DEM: the package's ellipsoidal
//   height less ct_package_geoid); steps as in `trace`; lat,lon the hit in
//   WGS84 degrees with 9 decimals (ct_utm_inverse; nan unless the package is
//   UTM and something is hit); h_ell the WGS84 ellipsoidal height (nan when
//   the package's vertical datum is unknown).
// --effects LIST: scene effects, comma-separated: curvature, refraction
//   (empty: a straight line of sight).  The library's model (ct_effects):
//   the line of sight's height above the datum gains c rho^2 / 2R at
//   horizontal range rho, c = [curvature] - k [refraction].
//   --refraction-k K (default 0.13, in [-2, 2]; needs refraction) and
//   --earth-radius M (metres, default 6371000; needs an effect).
// --tolerance M: instead of --effects, the least set of curvature and
//   refraction whose omission stays within M metres horizontally over the
//   image, and the largest chord within the rest (ct_effects_for_tolerance:
//   flat-ground bounds from each ray's range and depression); the bounds
//   and the choice are printed on stderr.
// --chord M: the polyline's / the true Earth's piece tolerance (default
//   0.001 m; ct_effects.chord_nm).
// --earth-map auto|fitted|exact: with curvature on a UTM package (the true
//   Earth), map the line of sight into the package's frame through a
//   polynomial fitted once per chunk of pixels (CT_EFFECT_EARTH_FIT: 125-343
//   exact conversions, then ~2x faster per pixel; within 0.02 mm of the
//   exact map) or by exact conversions per pixel.  auto (default): fitted
//   for 256 pixels or more.
// --threads T: threads (default 0: all cores); each runs ct_geolocate_batch
//   on chunks of pixels, the rows stay in input order and are the same for
//   any T.
// The work is the flight library's: ct_camera_init, ct_pose_init,
// ct_geolocate_batch.  Errors print one line and exit non-zero; the output
// is written atomically (never a partial file).
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <atomic>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "camera_host.hpp"
#include "conetrace.h"
#include "host_io.hpp"
#include "terrain.hpp"
#include "tileset.hpp"

using namespace ct_host;

namespace {

using Opts = std::map<std::string, std::string>;

// The value of option `name`, a number in [lo, hi].
double option_number(Opts &opt, const char *name, double lo, double hi, const char *what)
{
    return number_in(name, opt[name], lo, hi, what);
}

// --effects, --refraction-k, --chord, --earth-radius (with --tolerance the
// flags and the chord are chosen later).
ct_effects parse_effects(Opts &opt, bool by_tolerance)
{
    // radius 0: the true Earth on UTM packages (the sphere of 6371 km on others)
    ct_effects fx = {0u, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
    if (opt.count("--effects")) fx.flags = effects_from_list(opt["--effects"]);
    if (by_tolerance && opt.count("--effects")) throw Error("geoloc: give --effects or --tolerance, not both");
    if (opt.count("--refraction-k")) {
        if (!(fx.flags & CT_EFFECT_REFRACTION) && !by_tolerance)
            throw Error("--refraction-k needs --effects refraction (or --tolerance)");
        fx.refraction_k_q16 =
            (int32_t)std::lround(option_number(opt, "--refraction-k", -2, 2, "a coefficient in [-2, 2]") * 65536);
    }
    if (opt.count("--chord")) {
        if (by_tolerance) throw Error("geoloc: --tolerance chooses the chord; give one or the other");
        fx.chord_nm = (int64_t)std::llround(
            option_number(opt, "--chord", 1.024e-6, 1.1e6, "a length in metres in [1.024e-6, 1.1e6]") * 1e9);
    }
    if (opt.count("--earth-radius")) {
        if (!fx.flags && !by_tolerance)
            throw Error("--earth-radius needs --effects curvature and/or refraction (or --tolerance)");
        fx.earth_radius_nm = (int64_t)std::llround(
            option_number(opt, "--earth-radius", 1100, 1.8e7, "a radius in metres in [1100, 1.8e7]") * 1e9);
    }
    return fx;
}

// What the pixels are geolocated over: a package, or a tile set read through
// per-chunk caches of cache_tiles tiles (then p is the set's frame, and gp a
// tile for the geoid).
struct Target {
    std::vector<uint8_t> bytes, gbytes;
    ct_package p, gp;
    std::unique_ptr<TileSetFiles> tiles;
    int cache_tiles = 16;
};

void open_target(const std::string &path, Opts &opt, Target *t)
{
    ct_package &p = t->p, &gp = t->gp;
    if (opt.count("--cache-tiles")) {
        char *end = nullptr;
        const long k = std::strtol(opt["--cache-tiles"].c_str(), &end, 10);
        if (opt["--cache-tiles"].empty() || *end || k < 1 || k > 4096)
            throw Error("--cache-tiles needs a number of tiles in [1, 4096], got '" + opt["--cache-tiles"] + "'");
        t->cache_tiles = (int)k;
    }
    if (is_tileset_path(path)) {
        t->tiles = std::make_unique<TileSetFiles>(path);
        TileSetFiles &tiles = *t->tiles;
        TileCache probe(tiles, 1);
        p = probe.set()->frame;
        gp = p;
        for (uint32_t k = 0; k < tiles.tiles_x() * tiles.tiles_y() && p.vdatum == CT_VDATUM_EGM96; ++k) {
            const std::string tp = tiles.dir() + "/" + tile_file_name((int)(k % tiles.tiles_x()), (int)(k / tiles.tiles_x()));
            try {
                t->gbytes = read_file(tp);
            } catch (const Error &) {
                continue;
            }
            if (ct_package_open(&gp, t->gbytes.data(), t->gbytes.size()) == CT_OK) break;
            gp = p;
        }
    } else {
        if (opt.count("--cache-tiles")) throw Error("--cache-tiles needs a tile set");
        open_package_file(path, &t->bytes, &p);
        gp = p;
    }
}

// --pose-wgs84 / --pose-map into cam->pose (else the camera model's
// extrinsics stay).
void parse_pose(Opts &opt, const ct_package &p, const std::string &path, LibCamera *camp)
{
    LibCamera &cam = *camp;
    ct_utm zone = {0, 0};
    const bool utm = ct_utm_zone_of_epsg((int32_t)p.epsg, &zone) == CT_OK;
    ct_status st = CT_OK;
    if (opt.count("--pose-wgs84") && opt.count("--pose-map"))
        throw Error("geoloc: give --pose-wgs84 or --pose-map, not both");
    for (const char *flag : {"--pose-wgs84", "--pose-map"}) {
        if (!opt.count(flag)) continue;
        std::vector<double> v;
        std::stringstream ss(opt[flag]);
        std::string tok;
        while (std::getline(ss, tok, ',')) {
            char *end = nullptr;
            double x = std::strtod(tok.c_str(), &end);
            if (tok.empty() || *end != '\0' || !std::isfinite(x))
                throw Error(std::string(flag) + " '" + opt[flag] + "': '" + tok + "' is not a number");
            v.push_back(x);
        }
        if (v.size() != 6)
            throw Error(std::string(flag) + " '" + opt[flag] + "': needs six numbers (" +
                        (flag[7] == 'w' ? "LAT,LON,H" : "E,N,H") + ",YAW,PITCH,ROLL)");
        for (int k = 3; k < 6; ++k)
            if (std::fabs(v[k]) > 180) throw Error(std::string(flag) + ": angles are degrees in [-180, 180]");
        auto rad_q61 = [](double deg) { return (int64_t)std::llround((long double)deg * M_PIl / 180 * 2305843009213693952.0L); };
        int32_t q[4];
        if (ct_quat_from_ypr(rad_q61(v[3]), rad_q61(v[4]), rad_q61(v[5]), q) != CT_OK)
            throw Error(std::string(flag) + ": angles out of range");
        if (std::fabs(v[2]) > 1e7) throw Error(std::string(flag) + ": height beyond 10,000 km");
        const int64_t h_nm = std::llround(v[2] * 1e9);
        if (flag[7] == 'w') {
            if (!utm)
                throw Error(path + ": --pose-wgs84 needs a UTM package (EPSG 326zz/327zz); this one is EPSG:" +
                            std::to_string(p.epsg));
            if (std::fabs(v[0]) > 90 || std::fabs(v[1]) > 180)
                throw Error("--pose-wgs84: latitude must be in [-90, 90] and longitude in [-180, 180] degrees");
            st = ct_pose_from_wgs84(&cam.pose, &zone, rad_q61(v[0]), rad_q61(v[1]), h_nm, q);
            if (st == CT_ERR_RANGE)
                throw Error("--pose-wgs84: the position is off UTM zone " + std::to_string(zone.zone) +
                            (zone.south ? "S" : "N") + " (more than 9 degrees from its central meridian, or beyond 84.5 degrees)");
        } else {
            if (std::fabs(v[0]) > 1e9 || std::fabs(v[1]) > 1e9) throw Error("--pose-map: E, N beyond 10^9 m");
            st = ct_pose_from_map(&cam.pose, std::llround(v[0] * 1e9), std::llround(v[1] * 1e9), h_nm, q);
        }
        if (st != CT_OK) throw Error(std::string(flag) + ": not a valid pose (" + status_name(st) + ")");
    }
}

// --tolerance: the least effects (and the largest chord) within it, with
// the bounds on stderr.
void choose_effects(Opts &opt, const ct_package &p, const LibCamera &cam, ct_effects *fxp)
{
    ct_effects &fx = *fxp;
    const double tol = option_number(opt, "--tolerance", 0, 1e6, "a tolerance in metres in [0, 1e6]");
    ct_effects_choice ch;
    const ct_status st = ct_effects_for_tolerance(&p, &cam.cam, &cam.pose, fx.refraction_k_q16, fx.earth_radius_nm,
                                                  std::llround(tol * 1e9), &ch);
    if (st != CT_OK) throw Error("--tolerance: cannot bound the effects for this camera (" + status_name(st) + ")");
    fx.flags = ch.flags;
    fx.chord_nm = ch.chord_nm;
    auto metres = [](int64_t nm) {
        char b[32];
        if (nm >= (INT64_C(1) << 62)) return std::string("unbounded");
        std::snprintf(b, sizeof b, "%.4g m", nm * 1e-9);
        return std::string(b);
    };
    const char *names[4] = {"none", "curvature", "refraction", "curvature, refraction"};
    std::fprintf(stderr,
                 "geoloc --tolerance %g m: horizontal error bounds over the image on flat ground (rays to %.1f "
                 "km, depression down to %.2f deg; k %.3g, R %.0f km): simulating nothing %s, curvature only %s, "
                 "refraction only %s, both 0 -> chord %.6g m, effects: %s\n",
                 tol, ch.range_nm * 1e-12,
                 ch.tan_min_q30 >= (INT64_C(1) << 62) ? 90.0 : std::atan(ch.tan_min_q30 / 1073741824.0) * 180 / M_PI,
                 fx.refraction_k_q16 / 65536.0, (fx.earth_radius_nm ? fx.earth_radius_nm : CT_EARTH_RADIUS_NM) * 1e-12,
                 metres(ch.bound_nm[0]).c_str(), metres(ch.bound_nm[1]).c_str(), metres(ch.bound_nm[2]).c_str(),
                 ch.chord_nm * 1e-9, names[ch.flags & 3u]);
}

// Degrees with nine decimals of an angle in Q61 radians (as %.9f would
// print it, rounded to the nearest 1e-9 degree in long double: no printf
// per value).
void append_deg9(std::string &o, int64_t q61)
{
    static const long double k = 180e9L / M_PIl / 2305843009213693952.0L;
    append_nm_decimal(o, std::llroundl((long double)q61 * k));  // an integer of 1e-9 units
}

// The rows of pixels px[0..n) with their records g[0..n), appended to o.
void append_rows(std::string &o, const PixelRow *px, const uint8_t *in_range, const ct_geo *g, size_t n,
                 const ct_package &p, const ct_package &gp, const ct_utm *zone)
{
    o.reserve(o.size() + n * 96);
    for (size_t k = 0; k < n; ++k) {
        ct_status s = in_range[k] ? g[k].status : CT_ERR_UNPROJECT;
        o += px[k].u_text;
        o += ',';
        o += px[k].v_text;
        o += ',';
        o += status_name(s);
        o += ',';
        if (s == CT_HIT || s == CT_HIT_VOID) {
            append_nm_decimal(o, g[k].hit.e_nm);
            o += ',';
            append_nm_decimal(o, g[k].hit.n_nm);
            o += ',';
            // h in the DEM's own datum: the package's (ellipsoidal when
            // the datum is known) less the geoid for EGM96 DEMs
            int64_t und = 0;
            const bool geoid_ok = p.vdatum == CT_VDATUM_EGM96 &&
                                  ct_package_geoid(&gp, g[k].hit.e_nm, g[k].hit.n_nm, &und) == CT_OK;
            if (p.vdatum == CT_VDATUM_EGM96 && !geoid_ok)
                o += "nan";
            else
                append_nm_decimal(o, g[k].hit.h_nm - und);
            o += ',';
            o += std::to_string(g[k].hit.steps);
            int64_t la, lo;
            if (zone != nullptr && ct_utm_inverse(zone, g[k].hit.e_nm, g[k].hit.n_nm, &la, &lo) == CT_OK) {
                o += ',';
                append_deg9(o, la);
                o += ',';
                append_deg9(o, lo);
            } else {
                o += ",nan,nan";
            }
            o += ',';
            if (p.vdatum != CT_VDATUM_UNKNOWN)
                append_nm_decimal(o, g[k].hit.h_nm);
            else
                o += "nan";
        } else {
            o += "nan,nan,nan,";
            o += std::to_string(s >= 0 ? g[k].hit.steps : 0u);
            o += ",nan,nan,nan";
        }
        o += '\n';
    }
}

}  // namespace

int cmd_geoloc(int argc, char **argv)
{
    CmdLine args;
    const std::string err = parse_cmdline(argc, argv, 2,
                                          {"--camera", "--pixels", "--method", "--effects", "--grid-step",
                                           "--refraction-k", "--earth-radius", "--threads", "--pose-wgs84",
                                           "--pose-map", "--earth-map", "--tolerance", "--chord", "--cache-tiles", "-o"},
                                          {}, false, &args);
    if (!err.empty()) throw Error("geoloc: " + err);
    const std::vector<std::string> &pos = args.pos;
    std::map<std::string, std::string> &opt = args.opt;
    if (pos.size() != 1) throw Error("geoloc needs exactly one package file or tile set");
    if (!opt.count("--camera")) throw Error("geoloc needs --camera C.cameramodel");
    if (!opt.count("--pixels")) throw Error("geoloc needs --pixels pixels.csv");
    if (!opt.count("-o")) throw Error("geoloc needs -o out.csv");
    const bool by_tolerance = opt.count("--tolerance") > 0;
    ct_effects fx = parse_effects(opt, by_tolerance);
    const ct_method m = opt.count("--method") ? method_named(opt["--method"]) : CT_METHOD_DIRECTIONAL;

    const double grid_step = opt.count("--grid-step") ? option_number(opt, "--grid-step", 1, 4096,
                                                                      "a number of pixels in [1, 4096]")
                                                        : kDefaultGridStepPx;

    const int threads = opt.count("--threads") ? threads_option(opt["--threads"], "geoloc") : 0;

    Target tg;
    open_target(pos[0], opt, &tg);
    const ct_package &p = tg.p;
    const std::unique_ptr<TileSetFiles> &tiles = tg.tiles;
    const int cache_tiles = tg.cache_tiles;
    const std::string &cpath = opt["--camera"];
    LibCamera cam = lib_camera(read_cameramodel(cpath), cpath, grid_step);
    parse_pose(opt, p, pos[0], &cam);
    if (by_tolerance) choose_effects(opt, p, cam, &fx);
    std::vector<PixelRow> px = read_pixels_csv(opt["--pixels"]);

    std::vector<int64_t> uv(2 * px.size());
    std::vector<uint8_t> in_range(px.size());
    for (size_t k = 0; k < px.size(); ++k) {
        in_range[k] = pixel_to_q16(px[k].u, px[k].v, &uv[2 * k], &uv[2 * k + 1]);
        if (!in_range[k]) uv[2 * k] = uv[2 * k + 1] = 0;
    }
    std::string earth_map = opt.count("--earth-map") ? opt["--earth-map"] : "auto";
    if (earth_map != "auto" && earth_map != "fitted" && earth_map != "exact")
        throw Error("--earth-map needs auto, fitted or exact, got '" + earth_map + "'");
    if (earth_map == "fitted" || (earth_map == "auto" && px.size() >= 256)) fx.flags |= CT_EFFECT_EARTH_FIT;
    // a fitted map is set up once per chunk: few large chunks then
    const size_t chunk =
        (fx.flags & CT_EFFECT_EARTH_FIT) != 0u ? std::max<size_t>(1024, px.size() / 8 + 1) : (size_t)1024;
    // the set-up's status (the same for every chunk; an empty input still
    // checks the camera and the effects)
    std::atomic<uint64_t> loads{0}, nodata{0};
    std::atomic<size_t> caches{0};
    ct_status st;
    ct_geo none;
    if (tiles) {
        TileCache probe(*tiles, 1);
        st = ct_geolocate_batch_tiles(probe.set(), &cam.cam, &cam.pose, m, &fx, uv.data(), 0, &none, 0);
    } else {
        st = ct_geolocate_batch(&p, &cam.cam, &cam.pose, m, &fx, uv.data(), 0, &none, 0);
    }
    // each chunk geolocated into its own records and formatted at once into
    // its part of the output (input order: part b / chunk)
    ct_utm zone = {0, 0};
    const bool utm = ct_utm_zone_of_epsg((int32_t)p.epsg, &zone) == CT_OK;
    std::vector<std::string> parts((px.size() + chunk - 1) / chunk);
    if (st == CT_OK)
        parallel_chunks(px.size(), threads, chunk, [&](size_t b, size_t e) {
            std::vector<ct_geo> g(e - b);
            if (!tiles) {
                (void)ct_geolocate_batch(&p, &cam.cam, &cam.pose, m, &fx, uv.data() + 2 * b, e - b, g.data(), e - b);
            } else {
                TileCache cache(*tiles, cache_tiles);
                caches++;
                (void)ct_geolocate_batch_tiles(cache.set(), &cam.cam, &cam.pose, m, &fx, uv.data() + 2 * b, e - b,
                                               g.data(), e - b);
                loads += cache.set()->loads;
                for (const ct_geo &x : g) nodata += x.status == CT_NO_DATA;
            }
            append_rows(parts[b / chunk], px.data() + b, in_range.data() + b, g.data(), e - b, p, tg.gp,
                        utm ? &zone : nullptr);
        });
    if (st == CT_ERR_EFFECTS)
        throw Error("--effects: the effect parameters are out of range for this package (" + status_name(st) + ")");
    if (st != CT_OK) throw Error(cpath + ": cannot geolocate from this camera (" + status_name(st) + ")");

    write_file_atomic(opt["-o"], "u,v,status,E,N,h,steps,lat,lon,h_ell\n", parts);
    if (tiles)
        std::fprintf(stderr,
                     "geoloc: %zu pixels over %u x %u tiles: %llu tile loads (%zu caches of %d slots, one per chunk), "
                     "%.1f MB of tiles in memory per cache, %llu pixels reached missing or bad tiles (no_data)\n",
                     px.size(), tiles->tiles_x(), tiles->tiles_y(), (unsigned long long)loads.load(), caches.load(),
                     cache_tiles, (double)cache_tiles * (double)tiles->largest_tile() / 1e6,
                     (unsigned long long)nodata.load());
    return 0;
}
