// cmd_render.cpp -- `conetrace render`: PNG pictures of what the PPT builder
// works with (Paglieroni 1997, Figs. 10-11): a DEM cross-section, its
// distance transforms, and a package's opening-angle and apex maps.
//
//   conetrace render IN --what KIND -o OUT.png [options]
//
// IN is a DEM (anything `build` reads) or a package (.ctp, recognised by its
// magic); KIND is one of
//   bitmap  the cross-section: cells whose top (tallest corner; with
//           --reduce r the max over r x r cells) is at or above the level
//   dt      its unconstrained Euclidean DT (ddt::unconstrained), in cells
//   ddt     directional Euclidean DTs, one panel per sector (--sectors N,
//           --sector LIST); "no feature in the sector" = infinity
//   angles  a package's opening-angle planes, one panel per sector
//           (--sector LIST, "omni" = the omnidirectional plane), degrees
//           from the upward vertical; code 0 (no cone) is marked
//   apex    a package's apex heights, grey (dark = low), metres
// Level (bitmap, dt, ddt): --slice H (metres), or --level k with
// --slices K (level k of K evenly spaced between the lowest and highest
// height code, as `build --slices`; K defaults to the package's slices).
// Options: --reduce r (1..8, bitmap/dt/ddt; packages use their own r),
//   --sectors N (ddt, 1..64, default 8), --sector LIST ("0,2,5", "all";
//   default all), --range LO,HI (colour scale: cells for distances, degrees
//   for angles, metres for apex; default: the data's range over all
//   panels), --hillshade (shade by the DEM's relief, light from the NW),
//   --zoom Z (1..16, pixels per cell), --columns C (panels per row),
//   --no-legend, --threads T.
//
// Picture layout (tests rely on it): panels of w*Z x h*Z pixels (cell
// (x, y) at pixels x*Z.., y*Z.., row 0 = north), laid out C per row, GAP
// pixels apart; sector panels (ddt, angles) have a STRIP-pixel header above
// them with the sector's wedge and number; below everything (unless
// --no-legend) a LEGEND-pixel colour bar with the scale's ends.
// Background white.  Colours: viridis (perceptual, dark = 0) for distances
// and angles, grey for apex; infinity / no cone = kNone (light grey,
// distinct from every palette colour), bitmap features kFeature on white.
//
// Errors print one line (file and reason) and exit non-zero; the PNG is
// written to a temporary file and renamed: never a partial output.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include "conetrace.h"
#include "cells.hpp"
#include "ddt.hpp"
#include "dem_io.hpp"
#include "picture.hpp"
#include "host_io.hpp"
#include "le.hpp"
#include "terrain.hpp"

using namespace ct_host;

namespace {

constexpr int GAP = 8;      // pixels between panels
constexpr int STRIP = 28;   // header above each sector panel
constexpr int LEGEND = 26;  // colour bar below the panels (incl. its gap)

constexpr Rgb kFeature{38, 38, 46};    // bitmap: terrain at/above the level
constexpr Rgb kNone{200, 200, 200};    // infinity, no cone (not in viridis)

// 256-entry palette: index = round(255 * t).
Rgb palette(bool grey, int idx)
{
    if (grey) return Rgb{(uint8_t)idx, (uint8_t)idx, (uint8_t)idx};
    return viridis(idx / 255.0);
}

[[noreturn]] void fail(const std::string &msg) { throw Error("render: " + msg); }

std::string fmt_num(double v)
{
    char b[32];
    if (std::fabs(v) >= 100 || v == std::floor(v))
        std::snprintf(b, sizeof b, "%.0f", v);
    else
        std::snprintf(b, sizeof b, "%.1f", v);
    return b;
}

// ------------------------------------------------------------------ input
struct Input {
    Terrain t;
    bool is_pkg = false;
    std::vector<uint8_t> bytes;  // package bytes (kept: ct_package points into them)
    ct_package pkg{};
};

Input load_input(const std::string &path)
{
    Input in;
    std::vector<uint8_t> head;
    {
        std::FILE *f = std::fopen(path.c_str(), "rb");
        if (!f) throw Error(path + ": " + std::strerror(errno));
        uint8_t m[4] = {0, 0, 0, 0};
        size_t n = std::fread(m, 1, 4, f);
        std::fclose(f);
        in.is_pkg = n == 4 && std::memcmp(m, CT_PKG_MAGIC, 4) == 0;
    }
    if (in.is_pkg) {
        open_package_file(path, &in.bytes, &in.pkg);
        in.t = terrain_from_package(in.pkg);
    } else {
        {
            // the size from the header first, as build's: a DEM beyond one
            // package is refused before its pixels are read (a compressed
            // file's header could promise any size)
            DemRows rows(path);
            const int w = rows.header().width, h = rows.header().height;
            if (w > kMaxPackagePosts || h > kMaxPackagePosts)
                throw Error(path + ": DEM of " + std::to_string(w) + "x" + std::to_string(h) +
                            " posts: render takes at most " + std::to_string(kMaxPackagePosts) + " posts per side");
        }
        DemRaster r = read_dem(path);
        try {
            in.t = terrain_from_heights(r.width, r.height, r.h, r.valid, r.geo, 0.0);
        } catch (const Error &e) {
            throw Error(path + ": " + e.what());
        }
    }
    return in;
}

// ------------------------------------------------------------------ options
struct Opts {
    std::vector<std::string> pos;
    std::map<std::string, std::string> val;
    bool hillshade = false, legend = true;
};

Opts parse_opts(int argc, char **argv)
{
    CmdLine c;
    const std::string err = parse_cmdline(argc, argv, 2,
                                          {"-o", "--what", "--slice", "--level", "--slices", "--reduce", "--sectors",
                                           "--sector", "--range", "--zoom", "--columns", "--threads"},
                                          {"--hillshade", "--no-legend"}, true, &c);
    if (!err.empty()) fail(err);
    Opts o;
    o.pos = std::move(c.pos);
    o.val = std::move(c.opt);
    o.hillshade = c.flag.count("--hillshade") > 0;
    o.legend = c.flag.count("--no-legend") == 0;
    return o;
}

long get_int(const Opts &o, const std::string &k, long def, long lo, long hi)
{
    auto it = o.val.find(k);
    if (it == o.val.end()) return def;
    char *end = nullptr;
    errno = 0;
    long v = std::strtol(it->second.c_str(), &end, 10);
    if (it->second.empty() || *end || errno == ERANGE || v < lo || v > hi)
        fail(k + " needs an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got '" + it->second + "'");
    return v;
}

double parse_real(const std::string &what, const std::string &s)
{
    char *end = nullptr;
    double v = std::strtod(s.c_str(), &end);
    if (s.empty() || *end || !std::isfinite(v)) fail(what + " needs a number, got '" + s + "'");
    return v;
}

// "all", or a comma-separated list of sector indices (and "omni" if allowed).
// Returns plane indices; omni = n.
std::vector<int> parse_sectors(const std::string &s, int n, bool allow_omni)
{
    std::vector<int> v;
    if (s == "all") {
        for (int k = 0; k < n; ++k) v.push_back(k);
        return v;
    }
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) {
        if (item == "omni") {
            if (!allow_omni) fail("--sector omni: only for --what angles of a package with more than one sector");
            v.push_back(n);
            continue;
        }
        char *end = nullptr;
        long k = std::strtol(item.c_str(), &end, 10);
        if (item.empty() || *end || k < 0 || k >= n)
            fail("--sector '" + s + "': '" + item + "' is not a sector in 0.." + std::to_string(n - 1) +
                 (allow_omni ? " or omni" : ""));
        v.push_back((int)k);
    }
    if (v.empty()) fail("--sector '" + s + "': empty list");
    return v;
}

// ------------------------------------------------------------------ panels
// One panel: values per cell (NaN = none/infinity), w x h.
struct Panel {
    int w = 0, h = 0;
    std::vector<double> v;
    int sector = -1;          // header: sector index (N = omni), -1 = no header
    std::vector<uint8_t> fg;  // bitmap panels: 1 = feature
};

void draw_wedge_glyph(Image &im, int cx, int cy, int rad, int n, int s)
{
    // ring, then the sector filled (s == n: whole disc, the omni plane)
    int32_t bx[CT_MAX_SECTORS + 1], by[CT_MAX_SECTORS + 1];
    for (int k = 0; s < n && k <= n; ++k) ct_sector_boundary((uint32_t)n, (uint32_t)k, &bx[k], &by[k]);
    for (int dy = -rad; dy <= rad; ++dy)
        for (int dx = -rad; dx <= rad; ++dx) {
            int d2 = dx * dx + dy * dy;
            if (d2 > rad * rad) continue;
            bool ring = d2 >= (rad - 1) * (rad - 1);
            uint32_t in = 1;
            // the flight library's closed-wedge test (image x = grid x, east;
            // image y = grid y, south)
            if (s < n) ct_in_wedge(bx, by, (uint32_t)n, (uint32_t)s, dx, dy, &in);
            if (ring || in) im.set(cx + dx, cy + dy, ring ? kInk : Rgb{230, 120, 30});
        }
}

// The panels of a picture and what its legend and description say.
struct Picture {
    std::vector<Panel> panels;
    int reduce = 1, nsec = 0;
    bool grey = false, distances = false;  // grey scale (apexes); distances from 0
    std::ostringstream desc;
    std::string unit;
    int wc = 0, hc = 0;  // cells per panel
    double level_m = 0.0;
};

// --what bitmap|dt|ddt: the cross-section at the level the options give and
// its DTs.
void cross_section_panels(Opts &o, const Input &in, const std::string &what, int threads, Picture *pic)
{
    const Terrain &t = in.t;
    int &reduce = pic->reduce, &nsec = pic->nsec, &wc = pic->wc, &hc = pic->hc;
    std::vector<Panel> &panels = pic->panels;
    std::ostringstream &desc = pic->desc;
    reduce = (int)get_int(o, "--reduce", 1, 1, 8);
    uint16_t hmin = 65535, hmax = 0;
    for (uint16_t c : t.codes) hmin = std::min(hmin, c), hmax = std::max(hmax, c);
    // level in code units (double): feature iff cell top >= level
    double level;
    if (o.val.count("--slice") && o.val.count("--level")) fail("give --slice H or --level k, not both");
    if (o.val.count("--slice")) {
        if (o.val.count("--slices")) fail("--slices goes with --level, not --slice");
        double hm = parse_real("--slice", o.val["--slice"]);
        level = (hm - t.height_offset_m) / t.height_scale_m;
    } else if (o.val.count("--level")) {
        long kdef = in.is_pkg && in.pkg.slices > 0 ? (long)in.pkg.slices : 0;
        long k = get_int(o, "--slices", kdef, 1, 65535);
        if (k == 0) fail("--level needs --slices K (the number of evenly spaced levels)");
        long l = get_int(o, "--level", 0, 0, k);
        level = slice_level(hmin, hmax, (int)k, (int)l);  // the builder's level, rounded up
    } else {
        fail("--what " + what + " needs a level: --slice H (metres) or --level k --slices K");
    }
    std::vector<uint16_t> top = cell_tops(t, reduce, wc, hc);
    std::vector<uint8_t> bits(top.size());
    size_t nfeat = 0;
    for (size_t k = 0; k < top.size(); ++k) nfeat += bits[k] = top[k] >= level - 1e-9;
    pic->level_m = t.height_offset_m + level * t.height_scale_m;
    desc << "cross-section at " << pic->level_m << " m (cells with top >= level: " << nfeat << " of " << top.size()
         << "), r=" << reduce;
    if (what == "bitmap") {
        Panel p;
        p.w = wc, p.h = hc;
        p.fg = bits;
        p.v.assign(bits.size(), 0.0);
        panels.push_back(std::move(p));
    } else {
        pic->distances = true;
        pic->unit = "cells";
        ddt::Prepared bm(wc, hc, bits.data());
        ddt::Options dopt;
        dopt.threads = threads;
        std::vector<int64_t> dt;
        std::vector<ddt::Point> ft;
        auto to_panel = [&](int sector) {
            Panel p;
            p.w = wc, p.h = hc, p.sector = sector;
            p.v.resize(dt.size());
            for (size_t k = 0; k < dt.size(); ++k)
                p.v[k] = dt[k] == ddt::Inf<int64_t>::value ? NAN : std::sqrt((double)dt[k]);
            panels.push_back(std::move(p));
        };
        if (what == "dt") {
            ddt::unconstrained(bm, ddt::EuclideanSq(), dt, ft, dopt);
            to_panel(-1);
            desc << "; unconstrained Euclidean DT";
        } else {
            nsec = (int)get_int(o, "--sectors", 8, 1, CT_MAX_SECTORS);
            std::vector<int> secs = parse_sectors(o.val.count("--sector") ? o.val["--sector"] : "all", nsec, false);
            for (int s : secs) {
                ddt::directional(bm, (uint32_t)nsec, (uint32_t)s, ddt::EuclideanSq(), dt, ft, dopt);
                to_panel(s);
            }
            desc << "; directional Euclidean DT, " << nsec << " sectors, sectors";
            for (int s : secs) desc << " " << s;
        }
    }
}

// --what angles|apex: a package's planes.
void package_panels(Opts &o, const Input &in, const std::string &what, Picture *pic)
{
    const Terrain &t = in.t;
    int &reduce = pic->reduce, &nsec = pic->nsec, &wc = pic->wc, &hc = pic->hc;
    std::vector<Panel> &panels = pic->panels;
    std::ostringstream &desc = pic->desc;
    const ct_package &p = in.pkg;
    wc = (int)p.coarse_x, hc = (int)p.coarse_y;
    reduce = (int)p.reduce;
    const size_t plane = (size_t)wc * hc;
    if (what == "apex") {
        pic->grey = true;
        pic->unit = "m";
        Panel pn;
        pn.w = wc, pn.h = hc;
        pn.v.resize(plane);
        for (size_t k = 0; k < plane; ++k) pn.v[k] = t.height_offset_m + get16(p.apex + 2 * k) * t.height_scale_m;
        panels.push_back(std::move(pn));
        desc << "apex heights (m), " << wc << "x" << hc << " coarse cells, r=" << reduce;
    } else {
        pic->unit = "deg";
        nsec = (int)p.sectors;
        std::vector<int> secs =
            parse_sectors(o.val.count("--sector") ? o.val["--sector"] : "all", nsec, p.planes > p.sectors);
        for (int s : secs) {
            Panel pn;
            pn.w = wc, pn.h = hc, pn.sector = s;
            pn.v.resize(plane);
            const uint8_t *a = p.angles + (size_t)s * plane;
            for (size_t k = 0; k < plane; ++k) pn.v[k] = a[k] == 0 ? NAN : a[k] * 180.0 / 256.0;
            panels.push_back(std::move(pn));
        }
        desc << "opening angles (deg from the upward vertical; no cone = grey), " << nsec << " sectors, r="
             << reduce << ", planes";
        for (int s : secs) desc << " " << (s == nsec ? std::string("omni") : std::to_string(s));
    }
}

// The legend below the panels: the level's swatch (bitmaps), else the colour
// bar from lo to hi and the "none" swatch.
void draw_legend(Image &im, const std::string &what, const Picture &pic, double lo, double hi)
{
    const bool grey = pic.grey;
    const int y0 = im.h - LEGEND + 8;  // 8 px gap above the bar
    if (what == "bitmap") {
        for (int a = 0; a < 12; ++a)
            for (int b = 0; b < 12; ++b) im.set(2 + b, y0 + a, kFeature);
        draw_text(im, 18, y0 + 1, fmt_num(pic.level_m), 2);  // the level, metres
    } else {
        const int bw = std::min(256, im.w - 120);
        std::string ls = fmt_num(lo), hs = fmt_num(hi);
        int x = 2;
        draw_text(im, x, y0 + 1, ls, 2);
        x += (int)ls.size() * 8 + 4;
        for (int b = 0; b < bw; ++b)
            for (int a = 0; a < 12; ++a) im.set(x + b, y0 + a, palette(grey, (int)std::lround(b * 255.0 / (bw - 1))));
        x += bw + 4;
        draw_text(im, x, y0 + 1, hs, 2);
        x += (int)hs.size() * 8 + 12;
        if (!grey)  // the "none" swatch: infinity / no cone
            for (int a = 0; a < 12; ++a)
                for (int b = 0; b < 12; ++b) im.set(x + b, y0 + a, kNone);
    }
}

}  // namespace

int cmd_render(int argc, char **argv)
{
    Opts o = parse_opts(argc, argv);
    if (o.pos.size() != 1) fail("needs exactly one input (a DEM or a .ctp package)");
    if (!o.val.count("--what")) fail("needs --what bitmap|dt|ddt|angles|apex");
    if (!o.val.count("-o")) fail("needs -o OUT.png");
    const std::string what = o.val["--what"], out = o.val["-o"], inpath = o.pos[0];
    if (what != "bitmap" && what != "dt" && what != "ddt" && what != "angles" && what != "apex")
        fail("--what '" + what + "': expected bitmap, dt, ddt, angles or apex");
    if (out.size() < 5 || (out.compare(out.size() - 4, 4, ".png") != 0 && out.compare(out.size() - 4, 4, ".PNG") != 0))
        fail(out + ": the output must be a .png file");
    const bool sliced = what == "bitmap" || what == "dt" || what == "ddt";
    // options that do not apply are refused (no silent ignoring)
    auto refuse = [&](const char *opt, bool applies) {
        if (!applies && o.val.count(opt)) fail(std::string(opt) + " does not apply to --what " + what);
    };
    refuse("--slice", sliced);
    refuse("--level", sliced);
    refuse("--slices", sliced);
    refuse("--reduce", sliced);
    refuse("--sectors", what == "ddt");
    refuse("--sector", what == "ddt" || what == "angles");
    refuse("--range", what != "bitmap");
    const int zoom = (int)get_int(o, "--zoom", 1, 1, 16);
    const int threads = (int)get_int(o, "--threads", 0, 0, 256);

    Input in = load_input(inpath);
    const Terrain &t = in.t;
    if (!sliced && !in.is_pkg)
        fail(inpath + ": --what " + what + " needs a package (.ctp; make one with conetrace build)");

    Picture pic;
    if (sliced)
        cross_section_panels(o, in, what, threads, &pic);
    else
        package_panels(o, in, what, &pic);
    const std::vector<Panel> &panels = pic.panels;
    const int reduce = pic.reduce, nsec = pic.nsec, wc = pic.wc, hc = pic.hc;
    const bool grey = pic.grey;
    std::ostringstream &desc = pic.desc;

    // colour scale
    double lo = INFINITY, hi = -INFINITY;
    for (const Panel &p : panels)
        for (double v : p.v)
            if (!std::isnan(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    if (pic.distances) lo = 0.0;
    if (o.val.count("--range")) {
        const std::string &r = o.val["--range"];
        size_t c = r.find(',');
        if (c == std::string::npos) fail("--range needs LO,HI, got '" + r + "'");
        lo = parse_real("--range", r.substr(0, c));
        hi = parse_real("--range", r.substr(c + 1));
        if (!(hi > lo)) fail("--range '" + r + "': HI must exceed LO");
    }
    if (!std::isfinite(lo)) lo = 0.0, hi = 1.0;  // nothing finite: all "none"
    if (!(hi > lo)) hi = lo + 1.0;
    auto colour = [&](double v) {
        if (std::isnan(v)) return kNone;
        double f = (v - lo) / (hi - lo);
        int idx = (int)std::lround(std::min(1.0, std::max(0.0, f)) * 255.0);
        return palette(grey, idx);
    };

    std::vector<double> shade;
    if (o.hillshade) shade = hillshade(t, reduce, wc, hc);

    // layout
    const int n = (int)panels.size();
    const int cols = (int)get_int(o, "--columns", std::min(n, 6), 1, 64);
    const int rows = (n + cols - 1) / cols;
    const bool headers = panels[0].sector >= 0;
    const int strip = headers ? STRIP : 0;
    const int pw = wc * zoom, ph = hc * zoom;
    const long W = (long)cols * pw + (long)(cols - 1) * GAP;
    const long H = (long)rows * (strip + ph) + (long)(rows - 1) * GAP + (o.legend ? LEGEND : 0);
    if (W * H > (1L << 28)) fail("the picture would be " + std::to_string(W) + "x" + std::to_string(H) + " pixels; use a smaller --zoom");
    Image im((int)std::max<long>(W, o.legend ? 200 : 1), (int)H);
    for (int k = 0; k < n; ++k) {
        const Panel &p = panels[(size_t)k];
        const int x0 = (k % cols) * (pw + GAP), y0 = (k / cols) * (strip + ph + GAP) + strip;
        if (headers) {
            draw_wedge_glyph(im, x0 + 12, y0 - strip + 13, 11, nsec, p.sector);
            draw_text(im, x0 + 30, y0 - strip + 8, p.sector == nsec && what == "angles" ? "o" : std::to_string(p.sector), 2);
        }
        for (int y = 0; y < p.h; ++y)
            for (int x = 0; x < p.w; ++x) {
                size_t c = (size_t)y * p.w + x;
                Rgb col = !p.fg.empty() ? (p.fg[c] ? kFeature : kWhite) : colour(p.v[c]);
                if (!shade.empty()) {
                    double f = 0.45 + 0.55 * shade[c];
                    col = Rgb{(uint8_t)std::lround(col.r * f), (uint8_t)std::lround(col.g * f),
                              (uint8_t)std::lround(col.b * f)};
                }
                for (int a = 0; a < zoom; ++a)
                    for (int b = 0; b < zoom; ++b) im.set(x0 + x * zoom + b, y0 + y * zoom + a, col);
            }
    }
    if (o.legend) draw_legend(im, what, pic, lo, hi);
    if (what != "bitmap") desc << "; scale " << lo << ".." << hi << " " << pic.unit;
    write_png_atomic(out, im, desc.str(), "conetrace render");
    std::printf("%s: %dx%d px, %d panel%s of %dx%d cells; %s\n", out.c_str(), im.w, im.h, n, n == 1 ? "" : "s", wc, hc,
                desc.str().c_str());
    return 0;
}
