// cmd_demo.cpp -- `conetrace demo`: the main job on a DEM in one command.
//
//   conetrace demo DEM --camera C.cameramodel [--tolerance M | --effects LIST]
//                      [--step PX] [--sectors N] [--reduce r] [-o DIR]
//
// Packages the DEM in memory (the slice builder, N = 24, r = 3 by default),
// geolocates a grid of the camera's pixels (every --step pixels, default
// 32, and the image's border every 4 pixels) with the flight library's
// ct_geolocate_batch -- directional and, for comparison, incremental: the
// same hits --, prints a few pixels' ground points with their steps, and
// the time per pixel; then draws DIR/footprint.png (default DIR: demo):
// the DEM's hillshade around the footprint and the camera, north up; the ground the camera sees tinted warm and
// the ground inside its view but hidden behind terrain shaded blue (each
// post projected into the image with ct_camera_project and geolocated back:
// visible when the hit lies within 1.5 postings of it); the footprint's
// outline (the border pixels' hits, red); the grid's hits as dots coloured
// by range (viridis, the colour bar below with the nearest and farthest
// range in metres); the camera's position (white dot) and heading (the
// optical axis's horizontal direction, a black line).  DIR/pixels.csv
// lists the grid pixels: u,v,status,E,N,h,range,steps,px,py (px, py the
// dot's centre in the picture: px = floor(((E - E0) / posting_e - i0) *
// zoom), likewise py; posts i0..i1 x j0..j1 around the footprint and the
// camera drawn with zoom pixels each, as the PNG's description says).
// --tolerance M (default 0.1): the effects and chord ct_effects_for_tolerance
// picks for the camera (said in the output); --effects LIST forces a set
// instead.  On a UTM package curvature is the true Earth, its map fitted
// once per batch.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "camera_host.hpp"
#include "conetrace.h"
#include "host_io.hpp"
#include "picture.hpp"
#include "terrain.hpp"

namespace ct_host {

namespace {

using clk = std::chrono::steady_clock;

double seconds_since(clk::time_point t0) { return std::chrono::duration<double>(clk::now() - t0).count(); }

struct Px {
    double u, v;
    int64_t uq, vq;
};

double range_m(const ct_pose &pose, const ct_geo &g)
{
    const double de = (g.hit.e_nm - pose.e_nm) * 1e-9, dn = (g.hit.n_nm - pose.n_nm) * 1e-9,
                 dh = (g.hit.h_nm - pose.h_nm) * 1e-9;
    return std::sqrt(de * de + dn * dn + dh * dh);
}

bool is_hit(ct_status s) { return s == CT_HIT || s == CT_HIT_VOID; }

// The demo's effects: --effects as given, else those a --tolerance (default
// 0.1 m) calls for (ct_effects_for_tolerance); *why says which and why.
ct_effects demo_effects(const ct_package &p, const LibCamera &cam, const std::map<std::string, std::string> &opt,
                        const std::string &cpath, std::string *whyp)
{
    std::string &why = *whyp;
    ct_effects fx = {0u, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
    if (opt.count("--effects")) {
        if (opt.count("--tolerance")) throw Error("demo: give --effects or --tolerance, not both");
        fx.flags = effects_from_list(opt.at("--effects"));
        why = "as given";
    } else {
        // the effects (and chord) the camera needs for a tolerance
        const std::string ts = opt.count("--tolerance") ? opt.at("--tolerance") : "0.1";
        const double tol = number_in("--tolerance", ts, 0, 1e6, "a tolerance in metres in [0, 1e6]");
        ct_effects_choice ch;
        if (ct_effects_for_tolerance(&p, &cam.cam, &cam.pose, fx.refraction_k_q16, 0, std::llround(tol * 1e9), &ch) !=
            CT_OK)
            throw Error(cpath + ": cannot bound the effects for this camera");
        fx.flags = ch.flags;
        fx.chord_nm = ch.chord_nm;
        char b[256];
        auto m = [](int64_t nm) {
            char buf[32];
            std::snprintf(buf, sizeof buf, "%.3g m", nm * 1e-9);
            return nm >= (INT64_C(1) << 62) ? std::string("unbounded") : std::string(buf);
        };
        std::snprintf(b, sizeof b, "chosen for a %g m tolerance: simulating nothing would be off by up to %s, curvature "
                      "only %s, refraction only %s (flat ground, rays to %.1f km); chord %.3g m", tol,
                      m(ch.bound_nm[0]).c_str(), m(ch.bound_nm[1]).c_str(), m(ch.bound_nm[2]).c_str(),
                      ch.range_nm * 1e-12, ch.chord_nm * 1e-9);
        why = b;
    }
    return fx;
}

// The posts inside the camera's image: each post's centre projected (double
// rotation, the library's lens), as pixels (*seen) and post indices.
void posts_in_view(const ct_package &p, const Terrain &t, const LibCamera &cam, unsigned W, unsigned H,
                   std::vector<Px> *seenp, std::vector<size_t> *postp)
{
    std::vector<Px> &seen = *seenp;
    std::vector<size_t> &seen_post = *postp;
    const double pe = p.posting_e_nm * 1e-9, pn = p.posting_n_nm * 1e-9;
    const double E0 = p.origin_e_nm * 1e-9, N0 = p.origin_n_nm * 1e-9;
    const double C[3] = {cam.pose.e_nm * 1e-9, cam.pose.n_nm * 1e-9, cam.pose.h_nm * 1e-9};
    double R[9];
    for (int k = 0; k < 9; ++k) R[k] = cam.pose.R_map_cam_q30[k] / 1073741824.0;
    for (int j = 0; j < t.height; ++j)
        for (int i = 0; i < t.width; ++i) {
            const double P[3] = {E0 + (i + 0.5) * pe - C[0], N0 + (j + 0.5) * pn - C[1],
                                 t.height_offset_m + t.at(i, j) * t.height_scale_m - C[2]};
            double d[3];
            for (int r = 0; r < 3; ++r) d[r] = R[r] * P[0] + R[3 + r] * P[1] + R[6 + r] * P[2];  // R^T P
            if (d[2] <= 0) continue;
            const double m = std::max(std::fabs(d[0]), std::max(std::fabs(d[1]), d[2]));
            const int32_t ray[3] = {(int32_t)std::lround(d[0] / m * 1e9), (int32_t)std::lround(d[1] / m * 1e9),
                                    (int32_t)std::lround(d[2] / m * 1e9)};
            int64_t uq, vq;
            if (ct_camera_project(&cam.cam, ray, &uq, &vq) != CT_OK) continue;
            const double u = uq / 65536.0, v = vq / 65536.0;
            if (u < -0.5 || v < -0.5 || u > W - 0.5 || v > H - 0.5) continue;
            seen.push_back(Px{u, v, uq, vq});
            seen_post.push_back((size_t)j * t.width + i);
        }
}

}  // namespace

namespace {

// What the demo's parts share: the package, the camera, the effects and the
// grid's and border's results.
struct Demo {
    ct_package p;
    std::string cpath;
    LibCamera cam;
    unsigned W = 0, H = 0;
    ct_effects fx;
    std::string why;  // why these effects
    bool utm = false;
    ct_utm zone;
    int step = 32;
    std::vector<Px> grid, border;  // the pixels: a grid, and the image's border (the footprint's outline)
    std::vector<ct_geo> gd, gb;    // their results, directional
    double rmin = 1e300, rmax = 0;  // the grid's hits' range, m
};

Px px_of(double u, double v)
{
    Px q{u, v, 0, 0};
    pixel_to_q16(u, v, &q.uq, &q.vq);
    return q;
}

// ct_geolocate_batch over px: its seconds.
double geolocate_px(const Demo &d, const std::vector<Px> &px, ct_method m, std::vector<ct_geo> *out)
{
    std::vector<int64_t> uv(2 * px.size());
    for (size_t k = 0; k < px.size(); ++k) {
        uv[2 * k] = px[k].uq;
        uv[2 * k + 1] = px[k].vq;
    }
    out->assign(px.size(), ct_geo{});
    const clk::time_point t0 = clk::now();
    const ct_status st = ct_geolocate_batch(&d.p, &d.cam.cam, &d.cam.pose, m, &d.fx, uv.data(), px.size(), out->data(),
                                            out->size());
    const double s = seconds_since(t0);
    if (st != CT_OK) throw Error(d.cpath + ": cannot geolocate from this camera (" + status_name(st) + ")");
    return s;
}

// The grid and the border geolocated (the grid with both methods, compared);
// the summary printed.
void geolocate_grid(Demo &d)
{
    for (unsigned v = 0; v < d.H; v += (unsigned)d.step)
        for (unsigned u = 0; u < d.W; u += (unsigned)d.step) d.grid.push_back(px_of(u, v));
    for (unsigned u = 0; u + 1 < d.W; u += 4) d.border.push_back(px_of(u, 0));
    for (unsigned v = 0; v + 1 < d.H; v += 4) d.border.push_back(px_of(d.W - 1, v));
    for (unsigned u = d.W - 1; u > 0; u -= std::min(u, 4u)) d.border.push_back(px_of(u, d.H - 1));
    for (unsigned v = d.H - 1; v > 0; v -= std::min(v, 4u)) d.border.push_back(px_of(0, v));
    // each method's time: the best of five rounds that alternate between
    // them (a batch of a few hundred pixels takes a millisecond or two, less
    // than this machine's hiccups; the results are the same every round)
    std::vector<ct_geo> gi;
    double sd = 1e30, si = 1e30;
    for (int round = 0; round < 5; ++round) {
        sd = std::min(sd, geolocate_px(d, d.grid, CT_METHOD_DIRECTIONAL, &d.gd));
        si = std::min(si, geolocate_px(d, d.grid, CT_METHOD_INCREMENTAL, &gi));
    }
    geolocate_px(d, d.border, CT_METHOD_DIRECTIONAL, &d.gb);
    long hits = 0, differ = 0;
    double steps_d = 0, steps_i = 0;
    for (size_t k = 0; k < d.grid.size(); ++k) {
        const ct_geo &a = d.gd[k], &b = gi[k];
        differ += a.status != b.status || a.hit.e_nm != b.hit.e_nm || a.hit.n_nm != b.hit.n_nm || a.hit.h_nm != b.hit.h_nm;
        steps_d += a.hit.steps;
        steps_i += b.hit.steps;
        if (!is_hit(a.status)) continue;
        hits++;
        d.rmin = std::min(d.rmin, range_m(d.cam.pose, a));
        d.rmax = std::max(d.rmax, range_m(d.cam.pose, a));
    }
    const double n = (double)std::max<size_t>(1, d.grid.size());
    const uint32_t fl = d.fx.flags;
    std::printf("camera %s: %ux%u pixels, centre E %.1f N %.1f h %.1f m; effects: %s%s (%s)\n", d.cpath.c_str(), d.W,
                d.H, d.cam.pose.e_nm * 1e-9, d.cam.pose.n_nm * 1e-9, d.cam.pose.h_nm * 1e-9,
                (fl & CT_EFFECT_ALL) == 0u ? "none (straight lines of sight)"
                : (fl & CT_EFFECT_ALL) == CT_EFFECT_ALL ? "curvature, refraction (k 0.13)"
                : (fl & CT_EFFECT_CURVATURE) ? "curvature" : "refraction (k 0.13)",
                (fl & CT_EFFECT_CURVATURE) && d.utm ? " -- the true Earth (WGS84, map fitted per batch)" : "",
                d.why.c_str());
    std::printf("geolocated %zu pixels (every %d px): %ld hit; directional %.2f us and %.1f steps per pixel, "
                "incremental %.2f us and %.1f steps (the same hits%s)\n\n",
                d.grid.size(), d.step, hits, sd * 1e6 / n, steps_d / n, si * 1e6 / n, steps_i / n,
                differ ? ": NO, they differ" : ", bit for bit");
}

// A few pixels' ground points: the corners, the centre and the middles of
// two edges.
void print_sample_pixels(const Demo &d)
{
    std::printf("%9s %9s  %-9s %13s %14s %9s %10s %13s %13s %6s\n", "u", "v", "status", "E (m)", "N (m)", "h (m)",
                "range (m)", "lat (deg)", "lon (deg)", "steps");
    const double W = d.W, H = d.H;
    const double show[][2] = {{0, 0}, {W - 1.0, 0}, {(W - 1) / 2.0, (H - 1) / 2.0}, {0, H - 1.0},
                              {W - 1.0, H - 1.0}, {(W - 1) / 2.0, 0}, {(W - 1) / 2.0, H - 1.0}};
    for (const auto &s : show) {
        const Px q = px_of(s[0], s[1]);
        ct_geo g;
        const ct_status st = ct_geolocate(&d.p, &d.cam.cam, &d.cam.pose, CT_METHOD_DIRECTIONAL, &d.fx, q.uq, q.vq, &g);
        if (is_hit(st)) {
            int64_t la = 0, lo = 0;
            const bool ll = d.utm && ct_utm_inverse(&d.zone, g.hit.e_nm, g.hit.n_nm, &la, &lo) == CT_OK;
            const double k = 180 / M_PI / std::ldexp(1.0, 61);
            std::printf("%9.1f %9.1f  %-9s %13.3f %14.3f %9.3f %10.1f %13.7f %13.7f %6u\n", s[0], s[1],
                        status_name(st).c_str(), g.hit.e_nm * 1e-9, g.hit.n_nm * 1e-9, g.hit.h_nm * 1e-9,
                        range_m(d.cam.pose, g), ll ? la * k : NAN, ll ? lo * k : NAN, g.hit.steps);
        } else {
            std::printf("%9.1f %9.1f  %-9s %13s %14s %9s %10s %13s %13s %6u\n", s[0], s[1], status_name(st).c_str(),
                        "-", "-", "-", "-", "-", "-", g.hit.steps);
        }
    }
}

// What the camera sees: every post projected into the image and geolocated
// back; per post 1 (seen), 2 (in the view but hidden) or 0.
std::vector<uint8_t> posts_seen(const Demo &d, const Terrain &t)
{
    const clk::time_point tv = clk::now();
    const double pe = d.p.posting_e_nm * 1e-9, pn = d.p.posting_n_nm * 1e-9;
    const double E0 = d.p.origin_e_nm * 1e-9, N0 = d.p.origin_n_nm * 1e-9;
    std::vector<Px> seen;
    std::vector<size_t> seen_post;
    posts_in_view(d.p, t, d.cam, d.W, d.H, &seen, &seen_post);
    std::vector<ct_geo> gs;
    geolocate_px(d, seen, CT_METHOD_DIRECTIONAL, &gs);
    std::vector<uint8_t> state((size_t)t.width * t.height, 0);
    long visible = 0;
    for (size_t k = 0; k < seen.size(); ++k) {
        const size_t post = seen_post[k];
        const double e = E0 + ((double)(post % t.width) + 0.5) * pe, nn = N0 + ((double)(post / t.width) + 0.5) * pn;
        const bool vis = is_hit(gs[k].status) &&
                         std::hypot(gs[k].hit.e_nm * 1e-9 - e, gs[k].hit.n_nm * 1e-9 - nn) <= 1.5 * std::fabs(pe);
        state[post] = vis ? 1 : 2;
        visible += vis;
    }
    std::printf("\n%zu of %d posts inside the camera's view: %ld seen, %ld hidden behind terrain (%.2f s)\n",
                seen.size(), t.width * t.height, visible, (long)seen.size() - visible, seconds_since(tv));
    return state;
}

// The picture (DIR/footprint.png) and the grid's table (DIR/pixels.csv):
// the posts around the footprint and the camera (a fifth of their extent
// to spare), about 900 pixels on its longer side.
void draw_footprint(const Demo &d, const Terrain &t, const std::vector<uint8_t> &state, const std::string &dir)
{
    const double pe = d.p.posting_e_nm * 1e-9, pn = d.p.posting_n_nm * 1e-9;
    const double E0 = d.p.origin_e_nm * 1e-9, N0 = d.p.origin_n_nm * 1e-9;
    const ct_pose &pose = d.cam.pose;
    double x0 = (pose.e_nm * 1e-9 - E0) / pe, x1 = x0, y0 = (pose.n_nm * 1e-9 - N0) / pn, y1 = y0;
    for (const std::vector<ct_geo> *v : {&d.gd, &d.gb})
        for (const ct_geo &g : *v) {
            if (!is_hit(g.status)) continue;
            const double x = (g.hit.e_nm * 1e-9 - E0) / pe, y = (g.hit.n_nm * 1e-9 - N0) / pn;
            x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        }
    const double mx = 0.2 * (x1 - x0) + 10, my = 0.2 * (y1 - y0) + 10;
    const int i0 = std::max(0, (int)std::floor(x0 - mx)), i1 = std::min(t.width - 1, (int)std::ceil(x1 + mx));
    const int j0 = std::max(0, (int)std::floor(y0 - my)), j1 = std::min(t.height - 1, (int)std::ceil(y1 + my));
    const int cw = i1 - i0 + 1, ch = j1 - j0 + 1;
    const int zoom = std::max(1, (int)std::lround(900.0 / std::max(cw, ch)));
    const int pw = cw * zoom, ph = ch * zoom, LEG = 40;
    Image im(std::max(pw, 300), ph + LEG);
    paint_posts(im, t, i0, j0, i1, j1, zoom, [&](int i, int j, double sh) {
        const uint8_t g = (uint8_t)std::lround(255 * (0.25 + 0.7 * sh));
        Rgb c{g, g, g};
        const uint8_t st = state[(size_t)j * t.width + i];
        if (st == 1) c = mix(c, Rgb{255, 214, 120}, 0.35);
        if (st == 2) c = mix(c, Rgb{20, 40, 140}, 0.6);
        return c;
    });
    // a map point's place in the picture: post (i, j) covers [i, i + 1) x
    // [j, j + 1) in units of zoom pixels, its centre at (i + 1/2, j + 1/2)
    auto pic = [&](int64_t e_nm, int64_t n_nm, double *x, double *y) {
        *x = ((e_nm * 1e-9 - E0) / pe - i0) * zoom;
        *y = ((n_nm * 1e-9 - N0) / pn - j0) * zoom;
    };
    // the footprint's outline: consecutive border hits joined
    for (size_t k = 0; k < d.gb.size(); ++k) {
        const ct_geo &a = d.gb[k], &b = d.gb[(k + 1) % d.gb.size()];
        if (!is_hit(a.status) || !is_hit(b.status)) continue;
        double bx0, by0, bx1, by1;
        pic(a.hit.e_nm, a.hit.n_nm, &bx0, &by0);
        pic(b.hit.e_nm, b.hit.n_nm, &bx1, &by1);
        if (std::hypot(bx1 - bx0, by1 - by0) > 6.0 * zoom) continue;  // a jump across hidden ground
        im.line((int)std::floor(bx0), (int)std::floor(by0), (int)std::floor(bx1), (int)std::floor(by1),
                Rgb{220, 30, 30});
    }
    // the grid's hits, coloured by range; the table beside the picture
    const double span = std::max(1.0, d.rmax - d.rmin);
    std::string csv = "u,v,status,E,N,h,range,steps,px,py\n";
    for (size_t k = 0; k < d.grid.size(); ++k) {
        const ct_geo &g = d.gd[k];
        char line[256];
        if (!is_hit(g.status)) {
            std::snprintf(line, sizeof line, "%.1f,%.1f,%s,nan,nan,nan,nan,%u,nan,nan\n", d.grid[k].u, d.grid[k].v,
                          status_name(g.status).c_str(), g.hit.steps);
            csv += line;
            continue;
        }
        double x, y;
        pic(g.hit.e_nm, g.hit.n_nm, &x, &y);
        const double r = range_m(pose, g);
        im.disc((int)std::floor(x), (int)std::floor(y), 2, viridis((r - d.rmin) / span));
        std::snprintf(line, sizeof line, "%.1f,%.1f,%s,%s,%s,%s,%.3f,%u,%d,%d\n", d.grid[k].u, d.grid[k].v,
                      status_name(g.status).c_str(), nm_to_decimal(g.hit.e_nm).c_str(),
                      nm_to_decimal(g.hit.n_nm).c_str(), nm_to_decimal(g.hit.h_nm).c_str(), r, g.hit.steps,
                      (int)std::floor(x), (int)std::floor(y));
        csv += line;
    }
    // the camera and its heading (the optical axis in the map frame: the
    // third column of R_map_cam, its E and N)
    {
        double cx, cy;
        pic(pose.e_nm, pose.n_nm, &cx, &cy);
        const double ax = pose.R_map_cam_q30[2] / 1073741824.0, ay = pose.R_map_cam_q30[5] / 1073741824.0;
        const double al = std::hypot(ax, ay);
        if (al > 1e-6) {
            const double dx = ax / al * 60, dy = -ay / al * 60 * (pn < 0 ? 1 : -1);
            for (int o = -1; o <= 1; ++o)
                for (int q = -1; q <= 1; ++q)
                    im.line((int)cx + o, (int)cy + q, (int)std::lround(cx + dx) + o, (int)std::lround(cy + dy) + q, kInk);
        }
        im.disc((int)cx, (int)cy, 7, kInk);
        im.disc((int)cx, (int)cy, 5, kWhite);
    }
    // colour bar: nearest .. farthest range (m)
    const int bx = 10, by = ph + 8, bw = std::min(256, im.w - 20);
    for (int x = 0; x < bw; ++x)
        for (int y = 0; y < 12; ++y) im.set(bx + x, by + y, viridis((double)x / std::max(1, bw - 1)));
    draw_text(im, bx, by + 16, std::to_string((long)std::lround(d.rmin)), 2);
    const std::string far = std::to_string((long)std::lround(d.rmax));
    draw_text(im, bx + bw - 8 * (int)far.size(), by + 16, far, 2);
    const std::string png = dir + "/footprint.png", csvp = dir + "/pixels.csv";
    char desc[256];
    std::snprintf(desc, sizeof desc,
                  "conetrace demo: %s; posts %d..%d x %d..%d of the DEM, %d picture pixels per post, range %.0f..%.0f m",
                  d.cpath.c_str(), i0, i1, j0, j1, zoom, d.rmin, d.rmax);
    write_png_atomic(png, im, desc, "conetrace demo");
    write_file_atomic(csvp, std::vector<uint8_t>(csv.begin(), csv.end()));
    std::printf("\npicture: %s (%dx%d: hillshade of posts %d..%d x %d..%d, north up, %d pixels per post; warm: ground "
                "the camera sees; blue: in its view but hidden; red: the footprint's outline; dots: the grid's hits "
                "by range, %.0f..%.0f m; white: the camera, black line: its heading)\npixels:  %s\n",
                png.c_str(), im.w, im.h, i0, i1, j0, j1, zoom, d.rmin, d.rmax, csvp.c_str());
}

}  // namespace

int demo_main_job(const std::vector<uint8_t> &bytes, const Terrain &t, const std::map<std::string, std::string> &opt)
{
    Demo d;
    if (ct_package_open(&d.p, bytes.data(), bytes.size()) != CT_OK) throw Error("demo: the package did not open");
    d.cpath = opt.at("--camera");
    const CameraModel cm = read_cameramodel(d.cpath);
    d.cam = lib_camera(cm, d.cpath);
    d.W = cm.width;
    d.H = cm.height;
    if (d.W == 0 || d.H == 0) throw Error(d.cpath + ": no image size");
    d.fx = demo_effects(d.p, d.cam, opt, d.cpath, &d.why);
    d.fx.flags |= CT_EFFECT_EARTH_FIT;  // batches only; ignored without the true Earth
    d.utm = ct_utm_zone_of_epsg((int32_t)d.p.epsg, &d.zone) == CT_OK;
    if (opt.count("--step")) {
        d.step = std::atoi(opt.at("--step").c_str());
        if (d.step < 1 || d.step > 4096) throw Error("--step needs a number of pixels in [1, 4096]");
    }
    const std::string dir = opt.count("-o") ? opt.at("-o") : "demo";
    {
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        if (ec) throw Error(dir + ": cannot create the directory (" + ec.message() + ")");
    }
    geolocate_grid(d);
    print_sample_pixels(d);
    const std::vector<uint8_t> state = posts_seen(d, t);
    draw_footprint(d, t, state, dir);
    return 0;
}

}  // namespace ct_host
