// cmd_viewshed.cpp -- `conetrace viewshed`: which posts an observer sees.
//
//   conetrace viewshed PKG --observer E,N,H [--target-height M] [--radius M]
//                      [--effects LIST] [--earth-radius M] [--margin M]
//                      [--threads T] -o vs.tif [--png vs.png]
//
// The observer stands at map point (E, N), H metres above the surface there
// (as gdal_viewshed's -oz); every post (i, j) within --radius metres
// (horizontally; default: the whole tile) is a target at the post's height
// plus --target-height (default 0, as -tz), and is visible when the flight
// library's ct_los finds nothing of the surface more than --margin (default
// 0.01 m) before it -- the exact line of sight on the bilinear surface.
// --effects curvature,refraction bends it as geolocation does (k 0.13): on
// a UTM package the true Earth (the line of sight straight in Earth-fixed
// space; a ct_earth_map fitted once around the observer), elsewhere or with
// --earth-radius M the sphere of that radius (default 6371 km).
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

namespace {

// A proof that the line of sight to post (i, j) is blocked, from a point q
// (grid x, y) where a neighbour's line of sight was: the segment from the
// observer A to the target, at its point P closest (horizontally) to q, runs
// at least kSafety below the surface there (bilinear between the four posts;
// in the sphere model's lowered frame, terrain and target lowered by
// c rho^2 / 2R as ct_los lowers them), and P lies far enough before the
// target that ct_los's first hit -- at or before P, since A is above the
// surface (else ct_los says CT_BELOW: hidden too) -- is more than the margin
// before it.  kSafety (0.25 m) is far above this double arithmetic's error
// and the library's prepared segment's distance from the exact one (within
// a millimetre, docs/library.md), so a post proved hidden is one ct_los calls
// hidden; test_cli checks every post of a viewshed against ct_los.
class Shortcut {
public:
    static constexpr double kSafety = 0.25;  // metres

    // true_earth: ct_los follows the true Earth; the proof then uses the
    // sphere of 6371 km with room for the difference (below)
    Shortcut(const ct_package &p, const Terrain &t, const int64_t A[3], const ct_effects &fx, bool true_earth,
             double margin, double target_height)
        : t_(t), margin_(margin), th_(target_height)
    {
        int64_t x, y, z;
        on_ = ct_map_to_grid(&p, A[0], A[1], A[2], &x, &y, &z) == CT_OK;
        ax_ = x / 65536.0, ay_ = y / 65536.0, ha_ = A[2] * 1e-9;
        pe_ = p.posting_e_nm * 1e-9;
        const double k = (fx.flags & CT_EFFECT_REFRACTION) ? fx.refraction_k_q16 / 65536.0 : 0.0;
        const double c = ((fx.flags & CT_EFFECT_CURVATURE) ? 1.0 : 0.0) - k;
        if (c < 0) on_ = false;  // ct_los refuses these effects: it decides (refuses) every post
        const double R = true_earth ? CT_EARTH_RADIUS_NM * 1e-9 : (fx.earth_radius_nm ? fx.earth_radius_nm : CT_EARTH_RADIUS_NM) * 1e-9;
        lower_ = c > 0 ? c * pe_ * pe_ / (2.0 * R) : 0.0;
        // The true Earth against that sphere: the radii of curvature of
        // WGS84 (6,335-6,400 km) within 0.6 % of 6,371 km, UTM's scale
        // (0.9996-1.001 in a zone) within 0.2 % on rho^2, the terms of
        // higher order within rho / R: 2 % + rho / R of the drop, twice
        // over, is the room the proof leaves
        rel_ = true_earth ? 0.02 : 0.0;
        per_cell_ = true_earth ? pe_ / R : 0.0;
    }

    bool hides(int i, int j, double qx, double qy) const
    {
        if (!on_) return false;
        const double dx = i - ax_, dy = j - ay_, l2 = dx * dx + dy * dy;
        const double tt = ((qx - ax_) * dx + (qy - ay_) * dy) / l2;
        if (!(tt > 0 && tt < 1)) return false;
        const double px = ax_ + tt * dx, py = ay_ + tt * dy;
        const int ci = std::min(t_.width - 2, std::max(0, (int)std::floor(px)));
        const int cj = std::min(t_.height - 2, std::max(0, (int)std::floor(py)));
        const double fx = px - ci, fy = py - cj;
        const double s = (1 - fy) * ((1 - fx) * post(ci, cj) + fx * post(ci + 1, cj)) +
                         fy * ((1 - fx) * post(ci, cj + 1) + fx * post(ci + 1, cj + 1));
        const double drop_b = lower_ * l2, hb = post(i, j) + th_;
        const double room = kSafety + 2 * drop_b * (rel_ + per_cell_ * std::sqrt(l2));
        const double seg = ha_ + tt * (hb - drop_b - ha_);
        if (s - lower_ * tt * tt * l2 - seg < room) return false;
        // the first hit lies within tt |AB| + drop_b / 4 of A (the bent
        // segment sags below the chord by at most a quarter of drop_b)
        const double ab = std::sqrt(l2 * pe_ * pe_ + (hb - ha_) * (hb - ha_));
        return tt * ab + drop_b / 4 + room < ab - margin_;
    }

private:
    double post(int i, int j) const { return t_.height_offset_m + t_.at(i, j) * t_.height_scale_m; }
    const Terrain &t_;
    double margin_, th_;
    bool on_ = false;
    double ax_ = 0, ay_ = 0, ha_ = 0, pe_ = 0, lower_ = 0, rel_ = 0, per_cell_ = 0;
};

// What a sweep found: posts seen, hidden (proved so without ct_los), and
// not decided (ct_los's error statuses).
struct Tally {
    long seen = 0, hidden = 0, proved = 0, errors = 0;
};

// Every post of t within `radius` metres (0: all) of the observer A as a
// target th metres above it: (*out)[j W + i] = 1 seen, 0 hidden, 255
// beyond the radius.  A hidden post is proved so by sc from a neighbour's
// blocking point where it can be, else decided by ct_los; rows in chunks
// over `threads` threads.
Tally sweep_posts(const ct_package &p, const Terrain &t, const int64_t A[3], const ct_effects &fx, const Shortcut &sc,
                  double th, double radius, double margin, int threads, std::vector<uint8_t> *out)
{
    const int W = t.width, H = t.height;
    std::vector<uint8_t> &vis = *out;
    vis.assign((size_t)W * H, 255);
    std::vector<long> cnt((size_t)H * 4, 0);
    int64_t ox, oy, oz;
    (void)ct_map_to_grid(&p, A[0], A[1], A[2], &ox, &oy, &oz);
    const double oi = ox / 65536.0, oj = oy / 65536.0;
    const int orow = std::min(H - 1, std::max(0, (int)std::lround(oj)));
    const int ocol = std::min(W - 1, std::max(0, (int)std::lround(oi)));
    parallel_chunks((size_t)H, threads, 8, [&](size_t b, size_t e) {
        // rows from the observer's row outward, each row from its column
        // outward: the neighbour toward the observer comes first, and its
        // blocking point (grid x, y; NaN: none) is the candidate proof
        std::vector<double> prev((size_t)W * 2, NAN), cur((size_t)W * 2, NAN);
        // (a chunk holding the observer's row runs south from its first row;
        // its rows north of the observer then see the wrong neighbour first:
        // fewer proofs, never a wrong one)
        const bool up = (int)e - 1 <= orow;  // the chunk lies at or north of the observer's row
        for (size_t s = 0; s < e - b; ++s) {
            const int j = up ? (int)(e - 1 - s) : (int)(b + s);
            for (int half = 0; half < 2; ++half)
                for (int i = half ? ocol - 1 : ocol; half ? i >= 0 : i < W; i += half ? -1 : 1) {
                    double *blk = &cur[2 * (size_t)i];
                    blk[0] = blk[1] = NAN;
                    int64_t pt[3];
                    (void)ct_grid_to_map(&p, (int64_t)i << 16, (int64_t)j << 16, (int64_t)t.at(i, j) << 16, &pt[0],
                                         &pt[1], &pt[2]);
                    pt[2] += std::llround(th * 1e9);
                    if (radius > 0 && std::hypot((pt[0] - A[0]) * 1e-9, (pt[1] - A[1]) * 1e-9) > radius) continue;
                    long *c = &cnt[4 * (size_t)j];
                    if (pt[0] == A[0] && pt[1] == A[1]) {
                        vis[(size_t)j * W + i] = 1;
                        c[0]++;
                        continue;
                    }
                    const int in = i + (i >= ocol ? -1 : 1);  // the row neighbour toward the observer
                    const bool row_n = in >= 0 && in < W, col_n = s > 0 && j != orow;
                    const double *cand[3] = {row_n ? &cur[2 * (size_t)in] : nullptr,
                                             col_n ? &prev[2 * (size_t)i] : nullptr,
                                             row_n && col_n ? &prev[2 * (size_t)in] : nullptr};
                    bool done = false;
                    for (const double *q : cand)
                        if (q && !std::isnan(q[0]) && sc.hides(i, j, q[0], q[1])) {
                            vis[(size_t)j * W + i] = 0;
                            blk[0] = q[0], blk[1] = q[1];
                            c[1]++, c[3]++;
                            done = true;
                            break;
                        }
                    if (done) continue;
                    ct_hit h;
                    const ct_status st = ct_los(&p, A, pt, &fx, std::llround(margin * 1e9), CT_METHOD_DIRECTIONAL, &h);
                    if (st == CT_OK) {
                        vis[(size_t)j * W + i] = 1;
                        c[0]++;
                    } else if (st == CT_HIT || st == CT_BELOW) {
                        vis[(size_t)j * W + i] = 0;
                        c[1]++;
                        if (st == CT_HIT) {
                            // the candidate for the next posts: a cell past the first
                            // hit (at most half way to the target), where the segment
                            // runs deeper under the surface than at the hit itself
                            // (on the fixture 98 % of the hidden posts are proved
                            // from there, 59 % from the hit itself)
                            const double hx = h.x_q16 / 65536.0, hy = h.y_q16 / 65536.0;
                            const double rx = i - hx, ry = j - hy, rl = std::hypot(rx, ry);
                            const double step = std::min(1.0, 0.5 * rl) / std::max(rl, 1e-9);
                            blk[0] = hx + step * rx, blk[1] = hy + step * ry;
                        }
                    } else {
                        c[2]++;
                    }
                }
            std::swap(prev, cur);
        }
    });
    Tally n;
    for (int j = 0; j < H; ++j)
        n.seen += cnt[4 * j], n.hidden += cnt[4 * j + 1], n.errors += cnt[4 * j + 2], n.proved += cnt[4 * j + 3];
    return n;
}

// The command line, checked.
struct Options {
    std::string package, out, png, observer_text;
    double ob[3] = {0, 0, 0};  // E, N (map metres), H (metres above the surface)
    double th = 0, radius = 0, margin = 0.01;
    ct_effects fx = {0u, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};  // radius 0: the true Earth on UTM packages
    int threads = 0;
};

Options parse_options(int argc, char **argv)
{
    CmdLine args;
    const std::string err = parse_cmdline(argc, argv, 2,
                                          {"--observer", "--target-height", "--radius", "--effects", "--earth-radius",
                                           "--margin", "--threads", "-o", "--png"},
                                          {}, false, &args);
    if (!err.empty()) throw Error("viewshed: " + err);
    std::map<std::string, std::string> &opt = args.opt;
    if (args.pos.size() != 1) throw Error("viewshed needs exactly one package file");
    if (!opt.count("--observer")) throw Error("viewshed needs --observer E,N,H");
    if (!opt.count("-o")) throw Error("viewshed needs -o vs.tif");
    Options o;
    o.package = args.pos[0];
    o.out = opt["-o"];
    if (opt.count("--png")) o.png = opt["--png"];
    o.observer_text = opt["--observer"];
    {
        std::stringstream ss(o.observer_text);
        std::string tok;
        int k = 0;
        while (std::getline(ss, tok, ',')) {
            const double v = number_in("--observer", tok, -1e9, 1e9, "three numbers E,N,H");
            if (k < 3) o.ob[k] = v;
            k++;
        }
        if (k != 3) throw Error("--observer needs three numbers E,N,H (metres; H above the surface)");
    }
    if (opt.count("--target-height"))
        o.th = number_in("--target-height", opt["--target-height"], 0, 1e5, "a height in metres in [0, 1e5]");
    if (opt.count("--radius")) o.radius = number_in("--radius", opt["--radius"], 1e-3, 1e7, "a radius in metres in (0, 1e7]");
    if (opt.count("--margin")) o.margin = number_in("--margin", opt["--margin"], 0, 1e4, "a length in metres in [0, 1e4]");
    if (opt.count("--effects")) o.fx.flags = effects_from_list(opt["--effects"]);
    if (opt.count("--earth-radius")) {
        if (!o.fx.flags) throw Error("--earth-radius needs --effects curvature and/or refraction");
        o.fx.earth_radius_nm = std::llround(number_in("--earth-radius", opt["--earth-radius"], 1100, 1.8e7,
                                                   "a radius in metres in [1100, 1.8e7]") * 1e9);
    }
    if (opt.count("--threads")) o.threads = threads_option(opt["--threads"], "viewshed");
    return o;
}

// The observer A (map nm): H above the surface at (E, N), which must be
// over the tile.
void place_observer(const ct_package &p, const Options &o, int64_t A[3])
{
    int64_t ox, oy, oz, gz, ge, gn, gh;
    const int64_t oe = std::llround(o.ob[0] * 1e9), on = std::llround(o.ob[1] * 1e9);
    if (ct_map_to_grid(&p, oe, on, 0, &ox, &oy, &oz) != CT_OK || ox < 0 || oy < 0 ||
        ox > (int64_t)p.cells_x << 16 || oy > (int64_t)p.cells_y << 16 || ct_surface_height(&p, ox, oy, &gz) != CT_OK)
        throw Error("--observer: (" + o.observer_text + ") is not over the tile");
    (void)ct_grid_to_map(&p, ox, oy, gz, &ge, &gn, &gh);
    A[0] = oe, A[1] = on, A[2] = gh + std::llround(o.ob[2] * 1e9);
}

// The picture over the hillshade: warm seen, blue hidden, the observer white.
void write_picture(const std::string &path, const ct_package &p, const Terrain &t, const std::vector<uint8_t> &vis,
                   const int64_t A[3])
{
    const int W = t.width, H = t.height;
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
    const double cx = (double)(A[0] - p.origin_e_nm) / (double)p.posting_e_nm * zoom,
                 cy = (double)(A[1] - p.origin_n_nm) / (double)p.posting_n_nm * zoom;
    im.disc((int)cx, (int)cy, 6, kInk);
    im.disc((int)cx, (int)cy, 4, kWhite);
    write_png_atomic(path, im, "conetrace viewshed: warm seen, blue hidden", "conetrace viewshed");
}

}  // namespace

int cmd_viewshed(int argc, char **argv)
{
    Options o = parse_options(argc, argv);
    std::vector<uint8_t> bytes;
    ct_package p;
    open_package_file(o.package, &bytes, &p);
    const Terrain t = terrain_from_package(p);
    const int W = t.width, H = t.height;
    int64_t A[3];
    place_observer(p, o, A);
    // the true Earth: its map fitted once around the observer, out to the
    // tile's farthest corner, its relief, the observer's height and a km
    ct_effects &fx = o.fx;
    ct_utm zone;
    const bool true_earth = (fx.flags & CT_EFFECT_CURVATURE) && fx.earth_radius_nm == 0 &&
                            ct_utm_zone_of_epsg((int32_t)p.epsg, &zone) == CT_OK;
    ct_earth_map emap;
    if (true_earth) {
        const double pe = p.posting_e_nm * 1e-9, pn = p.posting_n_nm * 1e-9;
        double far = 0;
        for (int c = 0; c < 4; ++c)
            far = std::max(far, std::hypot((p.origin_e_nm - A[0]) * 1e-9 + (c & 1 ? W : 0) * pe,
                                           (p.origin_n_nm - A[1]) * 1e-9 + (c & 2 ? H : 0) * pn));
        const double reach = far + (p.hmax - p.hmin) * p.height_scale_nm * 1e-9 + o.ob[2] + 1000;
        if (ct_earth_map_init(&p, A[0], A[1], A[2], std::llround(reach * 1e9), &emap) == CT_OK) fx.earth_map = &emap;
    }
    // every post: hidden by a neighbour's blocking point when that proves it
    // (Shortcut), else decided by ct_los
    const Shortcut sc(p, t, A, fx, true_earth, o.margin, o.th);
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<uint8_t> vis;
    const Tally n = sweep_posts(p, t, A, fx, sc, o.th, o.radius, o.margin, o.threads, &vis);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (n.errors) throw Error("viewshed: " + std::to_string(n.errors) + " posts could not be decided");
    write_geotiff(o.out, W, H, std::vector<double>(vis.begin(), vis.end()), SampleType::UInt16, t.geo, true, 255);
    const double R_m = (fx.earth_radius_nm ? fx.earth_radius_nm : CT_EARTH_RADIUS_NM) * 1e-9;
    const std::string model = !(fx.flags & CT_EFFECT_CURVATURE) && !(fx.flags & CT_EFFECT_REFRACTION) ? "straight"
                              : true_earth ? std::string("the true Earth") + (fx.earth_map ? ", its map fitted once" : "")
                                           : "the sphere of " + std::to_string((long)std::lround(R_m / 1000)) + " km";
    std::fprintf(stderr, "viewshed: %s; ", model.c_str());
    std::fprintf(stderr, "observer (%.3f, %.3f) %.3f m above the surface (h %.3f m); %ld posts seen, %ld "
                         "hidden (%ld by a neighbour's blocking point), %ld out of range; %.2f s\n",
                 o.ob[0], o.ob[1], o.ob[2], A[2] * 1e-9, n.seen, n.hidden, n.proved, (long)W * H - n.seen - n.hidden,
                 secs);
    if (!o.png.empty()) write_picture(o.png, p, t, vis, A);
    return 0;
}
