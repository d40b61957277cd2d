// cmd_shadows.cpp -- `conetrace shadows`: which posts are in the sun's shadow.
//
//   conetrace shadows PKG --sun AZ,EL [--lift M] [--method M] [--threads T]
//                     -o shadow.tif [--png shadow.png]
//
// For the sun at azimuth AZ (degrees clockwise from grid north) and
// elevation EL (degrees above the horizon, (0, 90]), every post casts a ray
// from the surface there (lifted by --lift metres, default 0.01, so a post
// on a slope facing the sun does not shadow itself) towards the sun; the
// flight library's ct_trace decides: a hit is shadow, a miss is sun.  With
// the default --method directional this is the paper's horizon-angle view:
// the walk's first step compares the sun with the cone of the post's coarse
// cell in the sun's sector (a post at or above the cone's apex with the sun
// above the cone is lit at once: "lit in one step" in the summary, which
// also counts a first cell step that leaves the tile), then
// jumps from cone to cone and tests cells exactly only where no cone
// decides.  --method incremental is the exact ray cell by cell (the same
// map, bit for bit; make bench compares the two per N).
// shadow.tif: a GeoTIFF on the package's grid and CRS, 1 lit, 0 shadow.
// --png: the picture over the hillshade (shadow darkened and blue; in the
// top-left corner the sun's marker and a line the way shadows fall).  Errors print one line and exit non-zero; outputs are
// written atomically.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "conetrace.h"
#include "dem_io.hpp"
#include "host_io.hpp"
#include "picture.hpp"
#include "terrain.hpp"

using namespace ct_host;

int cmd_shadows(int argc, char **argv)
{
    CmdLine args;
    const std::string err =
        parse_cmdline(argc, argv, 2, {"--sun", "--lift", "--method", "--threads", "-o", "--png"}, {}, false, &args);
    if (!err.empty()) throw Error("shadows: " + err);
    std::map<std::string, std::string> &opt = args.opt;
    if (args.pos.size() != 1) throw Error("shadows needs exactly one package file");
    if (!opt.count("--sun")) throw Error("shadows needs --sun AZ,EL (degrees)");
    if (!opt.count("-o")) throw Error("shadows needs -o shadow.tif");
    std::vector<double> sun;
    {
        std::stringstream ss(opt["--sun"]);
        std::string tok;
        while (std::getline(ss, tok, ',')) {
            char *end = nullptr;
            const double v = std::strtod(tok.c_str(), &end);
            if (tok.empty() || *end || !std::isfinite(v)) throw Error("--sun '" + opt["--sun"] + "': '" + tok + "' is not a number");
            sun.push_back(v);
        }
    }
    if (sun.size() != 2) throw Error("--sun needs two numbers AZ,EL (degrees)");
    if (!(sun[1] > 0 && sun[1] <= 90)) throw Error("--sun: the sun is below the horizon (elevation must be in (0, 90] degrees)");
    const double lift =
        opt.count("--lift") ? number_in("--lift", opt["--lift"], 0, 1000, "a height in metres in [0, 1000]") : 0.01;
    const int threads = opt.count("--threads") ? threads_option(opt["--threads"], "shadows") : 0;
    const ct_method method = opt.count("--method") ? method_named(opt["--method"]) : CT_METHOD_DIRECTIONAL;
    const std::string &path = args.pos[0];
    std::vector<uint8_t> bytes;
    ct_package p;
    open_package_file(path, &bytes, &p);
    const Terrain t = terrain_from_package(p);
    const int W = t.width, H = t.height;
    const double az = sun[0] * M_PI / 180, el = sun[1] * M_PI / 180;
    // the direction towards the sun, map frame (E, N, up), scaled to 2^40
    const double s = std::ldexp(1.0, 40);
    const int64_t de = std::llround(std::sin(az) * std::cos(el) * s), dn = std::llround(std::cos(az) * std::cos(el) * s),
                  dh = std::llround(std::sin(el) * s);
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<uint8_t> lit((size_t)W * H, 0);
    std::vector<long> bad((size_t)H, 0), steps((size_t)H, 0), at_once((size_t)H, 0);
    parallel_chunks((size_t)H, threads, 8, [&](size_t b, size_t e) {
        for (size_t j = b; j < e; ++j)
            for (int i = 0; i < W; ++i) {
                int64_t pe, pn, ph;
                (void)ct_grid_to_map(&p, (int64_t)i << 16, (int64_t)j << 16, (int64_t)t.at(i, (int)j) << 16, &pe, &pn, &ph);
                ct_ray r;
                ct_hit h;
                ct_status s2 = ct_ray_from_map(&p, pe, pn, ph + std::llround(lift * 1e9), de, dn, dh, &r);
                if (s2 == CT_OK) s2 = ct_trace(&p, &r, method, &h);
                if (s2 == CT_MISS) lit[j * W + i] = 1, at_once[j] += h.steps == 1;
                else if (s2 != CT_HIT && s2 != CT_HIT_VOID && s2 != CT_BELOW) bad[j]++;
                if (s2 >= 0) steps[j] += h.steps;
            }
    });
    long errors = 0, nlit = 0, nsteps = 0, nonce = 0;
    for (int j = 0; j < H; ++j) errors += bad[j], nsteps += steps[j], nonce += at_once[j];
    for (uint8_t v : lit) nlit += v;
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (errors) throw Error("shadows: " + std::to_string(errors) + " posts could not be decided");
    write_geotiff(opt["-o"], W, H, std::vector<double>(lit.begin(), lit.end()), SampleType::UInt16, t.geo);
    std::fprintf(stderr, "shadows: sun at azimuth %.2f, elevation %.2f deg: %ld posts lit (%ld in one step), %ld in "
                         "shadow; %.1f steps per post; %.3f s\n",
                 sun[0], sun[1], nlit, nonce, (long)W * H - nlit, (double)nsteps / ((double)W * H), secs);
    if (opt.count("--png")) {
        const int zoom = std::max(1, (int)std::lround(900.0 / std::max(W, H)));
        Image im(W * zoom, H * zoom);
        paint_posts(im, t, 0, 0, W - 1, H - 1, zoom, [&](int i, int j, double sh) {
            const bool on = lit[(size_t)j * W + i] != 0;
            const uint8_t gg = (uint8_t)std::lround(255 * (on ? 0.3 + 0.65 * sh : (0.3 + 0.65 * sh) * 0.35));
            return on ? Rgb{gg, gg, (uint8_t)std::lround(gg * 0.85)} : Rgb{gg, gg, (uint8_t)std::min(255.0, gg * 1.4)};
        });
        // the sun's direction from the picture's corner
        const int cx = 40, cy = 40;
        im.disc(cx, cy, 6, Rgb{255, 200, 40});
        im.line(cx, cy, cx - (int)std::lround(30 * std::sin(az)), cy + (int)std::lround(30 * std::cos(az)), kInk);
        write_png_atomic(opt["--png"], im, "conetrace shadows: the sun at " + opt["--sun"], "conetrace shadows");
    }
    return 0;
}
