// cmd_render.cpp -- `conetrace render`: pictures a person would look at.
//
//   conetrace render IN --what bitmap|dt|ddt|angles|apex -o OUT.png
//                    [--level H] [--sectors N] [--sector S1,S2,...] [--scale K]
//
// IN is a DEM (anything `build` reads) or a terrain package (.ctp); angles
// and apex need a package.  bitmap: the cross-section at --level H metres
// (default: halfway between the lowest and highest cell) over a hillshade;
// dt: its unconstrained Euclidean distance transform; ddt: its directional
// DTs for the --sector list of --sectors N (default N = 8, every sector),
// side by side (the paper's Fig. 11); angles: the package's opening angles
// for the --sector list (N = the omnidirectional plane; default 0); apex: the
// package's apex heights.  --scale K enlarges K times (nearest neighbour).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "conetrace.h"
#include "ddt.hpp"
#include "dem_io.hpp"
#include "host_io.hpp"
#include "render.hpp"
#include "terrain.hpp"

using namespace ct_host;

namespace {

[[noreturn]] void render_usage(const std::string &msg)
{
    std::fprintf(stderr, "conetrace: %s\n", msg.c_str());
    std::fprintf(stderr,
                 "usage: conetrace render IN --what bitmap|dt|ddt|angles|apex -o OUT.png\n"
                 "                        [--level H] [--sectors N] [--sector S1,S2,...] [--scale K]\n"
                 "IN: a DEM or a package (.ctp); angles and apex need a package\n");
    std::exit(2);
}

long parse_long(const std::string &opt, const std::string &v, long lo, long hi)
{
    char *end = nullptr;
    long x = std::strtol(v.c_str(), &end, 10);
    if (v.empty() || *end != '\0' || x < lo || x > hi)
        render_usage(opt + " needs an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got '" + v + "'");
    return x;
}

std::vector<long> parse_list(const std::string &opt, const std::string &v, long lo, long hi)
{
    std::vector<long> out;
    std::stringstream ss(v);
    std::string item;
    while (std::getline(ss, item, ',')) out.push_back(parse_long(opt, item, lo, hi));
    if (out.empty()) render_usage(opt + " needs at least one number");
    return out;
}

}  // namespace

int cmd_render(int argc, char **argv)
{
    std::string in, out, what;
    std::map<std::string, std::string> opt;
    for (int k = 2; k < argc; ++k) {
        std::string a = argv[k];
        if (a == "-o" || a == "--what" || a == "--level" || a == "--sectors" || a == "--sector" || a == "--scale") {
            if (k + 1 >= argc) render_usage(a + " needs a value");
            opt[a] = argv[++k];
        } else if (!a.empty() && a[0] == '-') {
            render_usage("render: unknown option " + a);
        } else if (in.empty()) {
            in = a;
        } else {
            render_usage("render takes one input file");
        }
    }
    if (in.empty()) render_usage("render needs an input DEM or package");
    if (!opt.count("-o")) render_usage("render needs -o OUT.png");
    if (!opt.count("--what")) render_usage("render needs --what bitmap|dt|ddt|angles|apex");
    out = opt["-o"];
    what = opt["--what"];
    if (what != "bitmap" && what != "dt" && what != "ddt" && what != "angles" && what != "apex")
        render_usage("--what " + what + ": expected bitmap, dt, ddt, angles or apex");
    if (out.size() < 5 || out.compare(out.size() - 4, 4, ".png") != 0) render_usage("-o " + out + ": must end in .png");
    int scale = (int)(opt.count("--scale") ? parse_long("--scale", opt["--scale"], 1, 16) : 1);

    // input: a package (magic) or a DEM
    std::vector<uint8_t> bytes;
    ct_package pkg;
    bool is_pkg = false;
    {
        FILE *f = std::fopen(in.c_str(), "rb");
        char magic[4] = {0, 0, 0, 0};
        if (f) {
            size_t got = std::fread(magic, 1, 4, f);
            std::fclose(f);
            is_pkg = got == 4 && std::string(magic, 4) == CT_PKG_MAGIC;
        }
    }
    if (is_pkg) {
        bytes = read_file(in);
        ct_status st = ct_package_open(&pkg, bytes.data(), bytes.size());
        if (st != CT_OK) throw Error(in + ": not a valid package (" + status_name(st) + ")");
    } else if (what == "angles" || what == "apex") {
        throw Error(in + ": --what " + what + " needs a terrain package (.ctp), not a DEM");
    }

    render::Image im;
    std::string detail;
    if (what == "angles") {
        std::vector<long> ss = opt.count("--sector") ? parse_list("--sector", opt["--sector"], 0, (long)pkg.planes - 1)
                                                     : std::vector<long>{0};
        std::vector<render::Image> panels;
        for (long s : ss) panels.push_back(render::angle_image(pkg, (uint32_t)s));
        im = render::side_by_side(panels, 4);
        detail = "opening angles, " + std::to_string(pkg.sectors) + " sectors, planes " + opt["--sector"];
    } else if (what == "apex") {
        im = render::apex_image(pkg);
        detail = "apex heights";
    } else {
        render::Cells cells;
        if (is_pkg) {
            cells = render::cells_from_package(pkg);
        } else {
            DemRaster r = read_dem(in);
            Georef g = r.has_georef ? r.geo : Georef{};
            try {
                cells = render::cells_from_terrain(terrain_from_heights(r.width, r.height, r.h, r.valid, g));
            } catch (const Error &e) {
                throw Error(in + ": " + e.what());
            }
        }
        if (cells.w < 1 || cells.h < 1) throw Error(in + ": too small to render");
        double lo = cells.top_m[0], hi = lo;
        for (double v : cells.top_m) lo = std::min(lo, v), hi = std::max(hi, v);
        double level = (lo + hi) / 2;
        if (opt.count("--level")) {
            char *end = nullptr;
            level = std::strtod(opt["--level"].c_str(), &end);
            if (opt["--level"].empty() || *end != '\0' || !std::isfinite(level))
                render_usage("--level needs a height in metres, got '" + opt["--level"] + "'");
        }
        std::vector<uint8_t> bits = render::cross_section(cells, level);
        char lv[64];
        std::snprintf(lv, sizeof lv, "level %.2f m", level);
        if (what == "bitmap") {
            im = render::bitmap_image(cells, bits);
            detail = std::string("cross-section at ") + lv;
        } else {
            ddt::Prepared bm(cells.w, cells.h, bits.data());
            std::vector<ddt::Point> ft;
            ddt::Options o;
            o.threads = 0;
            if (what == "dt") {
                std::vector<int64_t> d2;
                ddt::unconstrained(bm, ddt::EuclideanSq(), d2, ft, o);
                im = render::distance_image(cells.w, cells.h, d2, std::max(1.0, render::max_distance(d2)));
                detail = std::string("Euclidean DT of the cross-section at ") + lv;
            } else {
                long n = opt.count("--sectors") ? parse_long("--sectors", opt["--sectors"], 1, CT_MAX_SECTORS) : 8;
                std::vector<long> ss;
                if (opt.count("--sector")) {
                    ss = parse_list("--sector", opt["--sector"], 0, n - 1);
                } else {
                    for (long s = 0; s < n; ++s) ss.push_back(s);
                }
                std::vector<std::vector<int64_t>> d2s(ss.size());
                double dmax = 1.0;
                for (size_t k = 0; k < ss.size(); ++k) {
                    ddt::directional(bm, (uint32_t)n, (uint32_t)ss[k], ddt::EuclideanSq(), d2s[k], ft, o);
                    dmax = std::max(dmax, render::max_distance(d2s[k]));
                }
                std::vector<render::Image> panels;
                for (const auto &d2 : d2s) panels.push_back(render::distance_image(cells.w, cells.h, d2, dmax));
                im = render::side_by_side(panels, 4);
                detail = "directional DTs, " + std::to_string(n) + " sectors, of the cross-section at " + lv;
            }
        }
    }
    im = render::enlarge(im, scale);
    render::write_png(out, im);
    std::printf("%s: %dx%d, %s\n", out.c_str(), im.w, im.h, detail.c_str());
    return 0;
}
