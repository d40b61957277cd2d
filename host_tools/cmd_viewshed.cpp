// cmd_viewshed.cpp -- `conetrace viewshed`: which posts an observer sees.
//
//   conetrace viewshed PKG --observer E,N,H [--target-height M] [--radius M]
//                      [--effects LIST] [--margin M] [--threads T]
//                      -o vs.tif [--png vs.png]
//
// The observer stands at map point (E, N), H metres above the surface there
// (as gdal_viewshed's -oz); every post (i, j) within --radius metres
// (horizontally; default: the whole tile) is a target at the post's height
// plus --target-height (default 0, as -tz), and is visible when the flight
// library's ct_los finds nothing of the surface more than --margin (default
// 0.01 m) before it -- the exact line of sight on the bilinear surface, with
// --effects curvature,refraction as the sphere model (R 6371 km, k 0.13).
// vs.tif: a GeoTIFF on the package's grid and CRS, 1 visible, 0 hidden, 255
// (nodata) beyond the radius.  --png: the picture over the hillshade (warm:
// seen, blue: hidden, grey: out of range; the observer a white dot).
// Errors print one line and exit non-zero; outputs are written atomically.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "camera_host.hpp"
#include "conetrace.h"
#include "dem_io.hpp"
#include "host_io.hpp"
#include "picture.hpp"
#include "terrain.hpp"

using namespace ct_host;

int cmd_viewshed(int argc, char **argv)
{
    CmdLine args;
    const std::string err = parse_cmdline(argc, argv, 2,
                                          {"--observer", "--target-height", "--radius", "--effects", "--margin",
                                           "--threads", "-o", "--png"},
                                          {}, false, &args);
    if (!err.empty()) throw Error("viewshed: " + err);
    std::map<std::string, std::string> &opt = args.opt;
    if (args.pos.size() != 1) throw Error("viewshed needs exactly one package file");
    if (!opt.count("--observer")) throw Error("viewshed needs --observer E,N,H");
    if (!opt.count("-o")) throw Error("viewshed needs -o vs.tif");
    auto number = [&](const std::string &name, const std::string &text, double lo, double hi, const char *what) {
        char *end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || !end || *end || !(v >= lo && v <= hi))
            throw Error(name + " needs " + what + ", got '" + text + "'");
        return v;
    };
    std::vector<double> ob;
    {
        std::stringstream ss(opt["--observer"]);
        std::string tok;
        while (std::getline(ss, tok, ',')) ob.push_back(number("--observer", tok, -1e9, 1e9, "three numbers E,N,H"));
        if (ob.size() != 3) throw Error("--observer needs three numbers E,N,H (metres; H above the surface)");
    }
    const double th = opt.count("--target-height") ? number("--target-height", opt["--target-height"], 0, 1e5,
                                                            "a height in metres in [0, 1e5]")
                                                     : 0.0;
    const double radius = opt.count("--radius") ? number("--radius", opt["--radius"], 1e-3, 1e7,
                                                         "a radius in metres in (0, 1e7]")
                                                : 0.0;
    const double margin = opt.count("--margin") ? number("--margin", opt["--margin"], 0, 1e4,
                                                         "a length in metres in [0, 1e4]")
                                                : 0.01;
    ct_effects fx = {0u, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM, 0, nullptr};
    if (opt.count("--effects")) fx.flags = effects_from_list(opt["--effects"]);
    const int threads = opt.count("--threads") ? threads_option(opt["--threads"], "viewshed") : 0;

    const std::string &path = args.pos[0];
    std::vector<uint8_t> bytes;
    ct_package p;
    open_package_file(path, &bytes, &p);
    const Terrain t = terrain_from_package(p);
    const int W = t.width, H = t.height;
    const double pe = p.posting_e_nm * 1e-9, pn = p.posting_n_nm * 1e-9;
    const double E0 = p.origin_e_nm * 1e-9, N0 = p.origin_n_nm * 1e-9;
    // the observer: on the tile, H above the surface
    int64_t ox, oy, oz, gz;
    const int64_t oe = std::llround(ob[0] * 1e9), on = std::llround(ob[1] * 1e9);
    if (ct_map_to_grid(&p, oe, on, 0, &ox, &oy, &oz) != CT_OK || ox < 0 || oy < 0 ||
        ox > (int64_t)(W - 1) << 16 || oy > (int64_t)(H - 1) << 16 || ct_surface_height(&p, ox, oy, &gz) != CT_OK)
        throw Error("--observer: (" + opt["--observer"] + ") is not over the tile");
    int64_t ge, gn, gh;
    (void)ct_grid_to_map(&p, ox, oy, gz, &ge, &gn, &gh);
    const int64_t A[3] = {oe, on, gh + std::llround(ob[2] * 1e9)};
    // every post
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<uint8_t> vis((size_t)W * H, 255);
    long seen = 0, hidden = 0, errors = 0;
    std::vector<long> cnt((size_t)H * 3, 0);
    parallel_chunks((size_t)H, threads, 8, [&](size_t b, size_t e) {
        for (size_t j = b; j < e; ++j)
            for (int i = 0; i < W; ++i) {
                int64_t pt[3];
                (void)ct_grid_to_map(&p, (int64_t)i << 16, (int64_t)j << 16, (int64_t)t.at(i, (int)j) << 16, &pt[0], &pt[1],
                                     &pt[2]);
                pt[2] += std::llround(th * 1e9);
                if (radius > 0 && std::hypot((pt[0] - A[0]) * 1e-9, (pt[1] - A[1]) * 1e-9) > radius) continue;
                if (pt[0] == A[0] && pt[1] == A[1]) {
                    vis[j * W + i] = 1;
                    cnt[3 * j]++;
                    continue;
                }
                ct_hit h;
                const ct_status s = ct_los(&p, A, pt, &fx, std::llround(margin * 1e9), CT_METHOD_DIRECTIONAL, &h);
                if (s == CT_OK) {
                    vis[j * W + i] = 1;
                    cnt[3 * j]++;
                } else if (s == CT_HIT || s == CT_BELOW) {
                    vis[j * W + i] = 0;
                    cnt[3 * j + 1]++;
                } else {
                    cnt[3 * j + 2]++;
                }
            }
    });
    for (int j = 0; j < H; ++j) seen += cnt[3 * j], hidden += cnt[3 * j + 1], errors += cnt[3 * j + 2];
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (errors) throw Error("viewshed: " + std::to_string(errors) + " posts could not be decided");
    write_geotiff(opt["-o"], W, H, std::vector<double>(vis.begin(), vis.end()), SampleType::UInt16, t.geo, true, 255);
    std::fprintf(stderr, "viewshed: observer (%.3f, %.3f) %.3f m above the surface (h %.3f m); %ld posts seen, %ld "
                         "hidden, %ld out of range; %.2f s\n",
                 ob[0], ob[1], ob[2], A[2] * 1e-9, seen, hidden, (long)W * H - seen - hidden, secs);
    if (opt.count("--png")) {
        const int zoom = std::max(1, (int)std::lround(900.0 / std::max(W, H)));
        Image im(W * zoom, H * zoom);
        paint_posts(im, t, 0, 0, W - 1, H - 1, zoom, [&](int i, int j, double s) {
            const uint8_t gg = (uint8_t)std::lround(255 * (0.25 + 0.7 * s));
            Rgb c{gg, gg, gg};
            const uint8_t v = vis[(size_t)j * W + i];
            if (v == 1) c = mix(c, Rgb{255, 214, 120}, 0.45);
            if (v == 0) c = mix(c, Rgb{20, 40, 140}, 0.55);
            return c;
        });
        const double cx = (ob[0] - E0) / pe * zoom, cy = (ob[1] - N0) / pn * zoom;
        im.disc((int)cx, (int)cy, 6, kInk);
        im.disc((int)cx, (int)cy, 4, kWhite);
        write_png_atomic(opt["--png"], im, "conetrace viewshed: warm seen, blue hidden", "conetrace viewshed");
    }
    return 0;
}
