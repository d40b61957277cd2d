// test_api_args.cpp -- every public entry point of the flight library with
// each pointer argument NULL, an object never set up, or a value outside its
// documented range: a table of named cases, each with the status conetrace.h
// documents for it (littlefs's test_evil style).  The other arguments are
// valid (a small UTM package, a pinhole camera, a pose over the tile), so
// the case's status is the answer to its one fault.  CT_TEST_VERBOSE=1
// prints every case.
#include <cstdlib>
#include <cstring>
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
#include "harness.h"

namespace {

struct World {
    dem_cases::Case c;
    ct_package p{};
    ct_camera cam{};
    ct_pose pose{};
    ct_ray ray{};
    ct_prepared pr{};
    int64_t a[3] = {0, 0, 0}, b[3] = {0, 0, 0};  // two map points over the tile
    // the same heights on a 1 um grid with 1 um height codes (a legal
    // georeference whose grid range a point a few km away already passes),
    // and on a grid whose axes run west and north (posting_e < 0 < posting_n)
    dem_cases::Case fine_c, west_c;
    ct_package fine{}, west{};
    int64_t fa[3] = {0, 0, 0};  // a map point over the fine tile
    // and with a height scale of 2^24 nm (16.777216 mm)
    dem_cases::Case pow2_c;
    ct_package pow2{};
    int64_t pa[3] = {0, 0, 0};  // a map point over it
};

World *world()
{
    static World *w = nullptr;
    if (w) return w;
    w = new World;
    ct_host::Terrain t = dem_cases::make_terrain(24, 20, dem_cases::smooth(24, 20, 3, 1000, 3000), 0.25);
    t.geo.epsg = 32617;
    w->c = dem_cases::make_case("args", t, 8, 2);
    if (ct_package_open(&w->p, w->c.pkg.data(), w->c.pkg.size()) != CT_OK) return nullptr;
    const ct_lens lens = dem_cases::centred_pinhole(64, 48, 60);
    if (ct_camera_init(&w->cam, &lens) != CT_OK) return nullptr;
    int64_t e, n, h;
    (void)ct_grid_to_map(&w->p, 12 << 16, 10 << 16, (int64_t)w->p.hmax << 16, &e, &n, &h);
    int32_t q[4];
    if (ct_quat_from_ypr(0, dem_cases::deg_q61(-60), 0, q) != CT_OK ||
        ct_pose_from_map(&w->pose, e, n, h + 500000000000, q) != CT_OK)
        return nullptr;
    w->a[0] = e, w->a[1] = n, w->a[2] = h + 100000000000;
    (void)ct_grid_to_map(&w->p, 3 << 16, 4 << 16, (int64_t)w->p.hmin << 16, &w->b[0], &w->b[1], &w->b[2]);
    if (ct_ray_from_map(&w->p, e, n, h + 100000000000, 1 << 20, 1 << 19, -(1 << 20), &w->ray) != CT_OK) return nullptr;
    if (ct_ray_prepare(&w->p, &w->ray, &w->pr) != CT_OK) return nullptr;
    ct_host::Terrain tf = t;
    tf.geo.posting_e = 1e-6;
    tf.geo.posting_n = -1e-6;
    tf.height_scale_m = 1e-6;
    w->fine_c = dem_cases::make_case("fine", tf, 8, 2);
    if (ct_package_open(&w->fine, w->fine_c.pkg.data(), w->fine_c.pkg.size()) != CT_OK) return nullptr;
    (void)ct_grid_to_map(&w->fine, 12 << 16, 10 << 16, (int64_t)w->fine.hmax << 16, &w->fa[0], &w->fa[1], &w->fa[2]);
    ct_host::Terrain tw = t;
    tw.geo.posting_e = -30.0;
    tw.geo.posting_n = 30.0;
    w->west_c = dem_cases::make_case("west", tw, 8, 2);
    if (ct_package_open(&w->west, w->west_c.pkg.data(), w->west_c.pkg.size()) != CT_OK) return nullptr;
    ct_host::Terrain t2 = t;
    t2.height_scale_m = 0.016777216;
    w->pow2_c = dem_cases::make_case("pow2", t2, 8, 2);
    if (ct_package_open(&w->pow2, w->pow2_c.pkg.data(), w->pow2_c.pkg.size()) != CT_OK ||
        w->pow2.height_scale_nm != (INT64_C(1) << 24))
        return nullptr;
    (void)ct_grid_to_map(&w->pow2, 12 << 16, 10 << 16, (int64_t)w->pow2.hmax << 16, &w->pa[0], &w->pa[1], &w->pa[2]);
    return w;
}

struct Case {
    const char *name;
    ct_status want;
    std::function<ct_status(World &)> call;
};

const ct_method kBadMethod = (ct_method)CT_METHOD_COUNT;

std::vector<Case> cases()
{
    std::vector<Case> v;
    auto add = [&](const char *name, ct_status want, std::function<ct_status(World &)> f) {
        v.push_back(Case{name, want, std::move(f)});
    };
    // ---- packages
    add("package_open: pkg NULL", CT_ERR_ARG, [](World &w) { return ct_package_open(nullptr, w.c.pkg.data(), w.c.pkg.size()); });
    add("package_open: bytes NULL", CT_ERR_ARG, [](World &w) {
        ct_package q;
        return ct_package_open(&q, nullptr, w.c.pkg.size());
    });
    add("package_open: 0 bytes", CT_ERR_TRUNCATED, [](World &w) {
        ct_package q;
        return ct_package_open(&q, w.c.pkg.data(), 0);
    });
    add("package_verify: NULL", CT_ERR_ARG, [](World &) { return ct_package_verify(nullptr); });
    add("package_size: out NULL", CT_ERR_ARG, [](World &) { return ct_package_size(16, 16, 1, 8, 0, nullptr); });
    add("package_size: width 1", CT_ERR_DIMS, [](World &) {
        uint32_t s;
        return ct_package_size(1, 16, 1, 8, 0, &s);
    });
    add("package_size: 0 sectors", CT_ERR_SECTORS, [](World &) {
        uint32_t s;
        return ct_package_size(16, 16, 1, 0, 0, &s);
    });
    add("package_size: r 0", CT_ERR_REDUCE, [](World &) {
        uint32_t s;
        return ct_package_size(16, 16, 0, 8, 0, &s);
    });
    add("package_layout: levels NULL", CT_ERR_ARG, [](World &) {
        uint32_t off[CT_SEC_COUNT], size[CT_SEC_COUNT], total;
        return ct_package_layout(16, 16, 1, 8, 0, off, size, nullptr, &total);
    });
    add("package_layout: sec_off NULL", CT_ERR_ARG, [](World &) {
        uint32_t size[CT_SEC_COUNT], levels, total;
        return ct_package_layout(16, 16, 1, 8, 0, nullptr, size, &levels, &total);
    });
    add("crc32: out NULL", CT_ERR_ARG, [](World &w) { return ct_crc32(0, w.c.pkg.data(), 4, nullptr); });
    add("crc32: data NULL, len 4", CT_ERR_ARG, [](World &) {
        uint32_t c;
        return ct_crc32(0, nullptr, 4, &c);
    });
    add("sector_boundary: bx NULL", CT_ERR_ARG, [](World &) {
        int32_t y;
        return ct_sector_boundary(8, 0, nullptr, &y);
    });
    add("sector_boundary: k > N", CT_ERR_SECTORS, [](World &) {
        int32_t x, y;
        return ct_sector_boundary(8, 9, &x, &y);
    });
    add("sector_boundary: N 0", CT_ERR_SECTORS, [](World &) {
        int32_t x, y;
        return ct_sector_boundary(0, 0, &x, &y);
    });
    add("sector_of: pkg NULL", CT_ERR_ARG, [](World &) {
        uint32_t s;
        return ct_sector_of(nullptr, 1, 0, &s);
    });
    add("sector_of: out NULL", CT_ERR_ARG, [](World &w) { return ct_sector_of(&w.p, 1, 0, nullptr); });
    add("sector_of: direction 0", CT_ERR_ARG, [](World &w) {
        uint32_t s;
        return ct_sector_of(&w.p, 0, 0, &s);
    });
    add("in_wedge: bounds NULL", CT_ERR_ARG, [](World &w) {
        uint32_t in;
        return ct_in_wedge(nullptr, w.p.bound_y, 8, 0, 1, 0, &in);
    });
    add("in_wedge: s = N", CT_ERR_SECTORS, [](World &w) {
        uint32_t in;
        return ct_in_wedge(w.p.bound_x, w.p.bound_y, 8, 8, 1, 0, &in);
    });
    add("in_wedge: direction beyond 2^30", CT_ERR_ARG, [](World &w) {
        uint32_t in;
        return ct_in_wedge(w.p.bound_x, w.p.bound_y, 8, 0, (INT64_C(1) << 30) + 1, 0, &in);
    });
    add("cot_table: out NULL", CT_ERR_ARG, [](World &) {
        uint8_t ok[256];
        return ct_cot_table(30000000000, 62500000, nullptr, ok);
    });
    add("cot_table: posting 0", CT_ERR_GEOREF, [](World &) {
        int64_t c[256];
        uint8_t ok[256];
        return ct_cot_table(0, 62500000, c, ok);
    });
    // ---- rays
    add("ray_prepare: pkg NULL", CT_ERR_ARG, [](World &w) {
        ct_prepared q;
        return ct_ray_prepare(nullptr, &w.ray, &q);
    });
    add("ray_prepare: ray NULL", CT_ERR_ARG, [](World &w) {
        ct_prepared q;
        return ct_ray_prepare(&w.p, nullptr, &q);
    });
    add("ray_prepare: out NULL", CT_ERR_ARG, [](World &w) { return ct_ray_prepare(&w.p, &w.ray, nullptr); });
    add("ray_prepare: zero direction", CT_ERR_RAY, [](World &w) {
        ct_ray r = w.ray;
        r.dx = r.dy = r.dz = 0;
        ct_prepared q;
        return ct_ray_prepare(&w.p, &r, &q);
    });
    add("ray_prepare: origin beyond CT_MAX_ORIGIN_Q16", CT_ERR_RAY, [](World &w) {
        ct_ray r = w.ray;
        r.x_q16 = CT_MAX_ORIGIN_Q16 + 1;
        ct_prepared q;
        return ct_ray_prepare(&w.p, &r, &q);
    });
    add("ray_prepare_segment: out NULL", CT_ERR_ARG, [](World &w) { return ct_ray_prepare_segment(&w.p, &w.ray, nullptr); });
    add("trace_prepared: hit NULL", CT_ERR_ARG, [](World &w) {
        return ct_trace_prepared(&w.p, &w.pr, CT_METHOD_DIRECTIONAL, nullptr);
    });
    add("trace_prepared: ray NULL", CT_ERR_ARG, [](World &w) {
        ct_hit h;
        return ct_trace_prepared(&w.p, nullptr, CT_METHOD_DIRECTIONAL, &h);
    });
    // a prepared ray with one field edited out of its documented range or
    // out of agreement with the others: CT_ERR_RAY (ct_trace_prepared
    // checks every field of the caller's object); the unedited ray traces
    struct PrepEdit {
        const char *name;
        ct_status want;
        void (*edit)(ct_prepared &, const ct_package &);
    };
    static const PrepEdit prep_edits[] = {
        {"trace_prepared: as prepared", CT_OK, [](ct_prepared &, const ct_package &) {}},
        {"trace_prepared: |d| beyond 2^26", CT_ERR_RAY, [](ct_prepared &r, const ct_package &) { r.dz = (1 << 26) + 1; }},
        {"trace_prepared: |d| below 2^25", CT_ERR_RAY, [](ct_prepared &r, const ct_package &) { r.dx = r.dy = r.dz = 1; }},
        {"trace_prepared: ox < 0", CT_ERR_RAY, [](ct_prepared &r, const ct_package &) { r.ox = -1; }},
        {"trace_prepared: oy < 0", CT_ERR_RAY, [](ct_prepared &r, const ct_package &) { r.oy = -1; }},
        {"trace_prepared: ox past the tile", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &p) { r.ox = (int64_t)p.cells_x * 65536 + 1; }},
        {"trace_prepared: oy past the tile", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &p) { r.oy = (int64_t)p.cells_y * 65536 + 1; }},
        {"trace_prepared: oz above the box", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &p) { r.oz = ((int64_t)p.hmax + 2) * (65536 >> r.zshift); }},
        {"trace_prepared: oz below -2^(46 - zshift)", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &) { r.oz = -(INT64_C(1) << (46 - r.zshift)) - 1; }},
        {"trace_prepared: oz on the floor, start ok", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &p) { r.oz = ((int64_t)p.hmin - 1) * (65536 >> r.zshift); }},
        {"trace_prepared: len_lo < 0", CT_ERR_RAY, [](ct_prepared &r, const ct_package &) { r.len_lo = -1; }},
        {"trace_prepared: len_hi < len_lo", CT_ERR_RAY, [](ct_prepared &r, const ct_package &) { r.len_hi = r.len_lo - 1; }},
        {"trace_prepared: len_hi > len_lo + 1", CT_ERR_RAY, [](ct_prepared &r, const ct_package &) { r.len_hi = r.len_lo + 2; }},
        {"trace_prepared: len_lo above the length", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &) { r.len_lo = r.len_hi = r.len_hi + 1; }},
        {"trace_prepared: len_hi below the length", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &) { r.len_hi = r.len_lo = r.len_lo - 1; }},
        {"trace_prepared: tend_d 0", CT_ERR_RAY, [](ct_prepared &r, const ct_package &) { r.tend_d = 0; }},
        {"trace_prepared: tend_d beyond 2^26", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &) { r.tend_d = (INT64_C(1) << 26) + 1; }},
        {"trace_prepared: tend_n < 0", CT_ERR_RAY, [](ct_prepared &r, const ct_package &) { r.tend_n = -1; }},
        {"trace_prepared: tend_n beyond 2^34", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &) { r.tend_n = (INT64_C(1) << 34) + 1; }},
        {"trace_prepared: tend past the box exit", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &) { r.tend_n = INT64_C(1) << 34, r.tend_d = 1; }},
        {"trace_prepared: start CT_HIT_VOID (no preparation's outcome)", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &) { r.start = CT_HIT_VOID; }},
        {"trace_prepared: sector -1 for a slanted ray", CT_ERR_RAY, [](ct_prepared &r, const ct_package &) { r.sector = -1; }},
        {"trace_prepared: sector N", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &p) { r.sector = (int32_t)p.sectors; }},
        {"trace_prepared: the opposite sector", CT_ERR_RAY,
         [](ct_prepared &r, const ct_package &p) { r.sector = (int32_t)((r.sector + p.sectors / 2) % p.sectors); }},
    };
    for (const PrepEdit &e : prep_edits) {
        const PrepEdit *ep = &e;
        add(e.name, e.want, [ep](World &w) -> ct_status {
            ct_prepared r = w.pr;
            ep->edit(r, w.p);
            ct_hit h;
            const ct_status st = ct_trace_prepared(&w.p, &r, CT_METHOD_DIRECTIONAL, &h);
            return st >= 0 ? CT_OK : st;
        });
    }
    add("trace_prepared: a vertical ray with a sector", CT_ERR_RAY, [](World &w) -> ct_status {
        ct_ray ray = w.ray;
        ray.dx = ray.dy = 0;
        ct_prepared r;
        if (ct_ray_prepare(&w.p, &ray, &r) != CT_OK || r.sector != -1) return CT_ERR_INTERNAL;
        ct_hit h;
        if (ct_trace_prepared(&w.p, &r, CT_METHOD_DIRECTIONAL, &h) < 0) return CT_ERR_INTERNAL;
        r.sector = 0;
        return ct_trace_prepared(&w.p, &r, CT_METHOD_DIRECTIONAL, &h);
    });
    add("surface_height: x < 0", CT_ERR_RANGE, [](World &w) {
        int64_t z;
        return ct_surface_height(&w.p, -1, 0, &z);
    });
    add("surface_height: y < 0", CT_ERR_RANGE, [](World &w) {
        int64_t z;
        return ct_surface_height(&w.p, 0, -1, &z);
    });
    add("surface_height: x past the tile", CT_ERR_RANGE, [](World &w) {
        int64_t z;
        return ct_surface_height(&w.p, (int64_t)w.p.cells_x * 65536 + 1, 0, &z);
    });
    add("surface_height: y past the tile", CT_ERR_RANGE, [](World &w) {
        int64_t z;
        return ct_surface_height(&w.p, 0, (int64_t)w.p.cells_y * 65536 + 1, &z);
    });
    add("trace_prepared: unknown method", CT_ERR_METHOD, [](World &w) {
        ct_hit h;
        return ct_trace_prepared(&w.p, &w.pr, kBadMethod, &h);
    });
    add("trace: pkg NULL", CT_ERR_ARG, [](World &w) {
        ct_hit h;
        return ct_trace(nullptr, &w.ray, CT_METHOD_DIRECTIONAL, &h);
    });
    add("trace: unknown method", CT_ERR_METHOD, [](World &w) {
        ct_hit h;
        return ct_trace(&w.p, &w.ray, kBadMethod, &h);
    });
    add("trace_bent: bend NULL", CT_ERR_ARG, [](World &w) {
        ct_hit h;
        return ct_trace_bent(&w.p, &w.ray, nullptr, CT_METHOD_DIRECTIONAL, &h);
    });
    add("trace_bent: radius below 2^40", CT_ERR_ARG, [](World &w) {
        const ct_bend bd = {57016, INT64_C(1) << 39, CT_EFFECTS_CHORD_NM, 0u};
        ct_hit h;
        return ct_trace_bent(&w.p, &w.ray, &bd, CT_METHOD_DIRECTIONAL, &h);
    });
    add("grid_to_map: e NULL", CT_ERR_ARG, [](World &w) {
        int64_t n, h;
        return ct_grid_to_map(&w.p, 0, 0, 0, nullptr, &n, &h);
    });
    add("map_to_grid: pkg NULL", CT_ERR_ARG, [](World &) {
        int64_t x, y, z;
        return ct_map_to_grid(nullptr, 0, 0, 0, &x, &y, &z);
    });
    add("ray_from_map: out NULL", CT_ERR_ARG, [](World &w) { return ct_ray_from_map(&w.p, w.a[0], w.a[1], w.a[2], 1, 0, 0, nullptr); });
    add("ray_from_map: direction beyond 2^40", CT_ERR_RAY, [](World &w) {
        ct_ray r;
        return ct_ray_from_map(&w.p, w.a[0], w.a[1], w.a[2], (INT64_C(1) << 40) + 1, 0, 0, &r);
    });
    add("ray_from_map: zero direction", CT_ERR_RAY, [](World &w) {
        ct_ray r;
        return ct_ray_from_map(&w.p, w.a[0], w.a[1], w.a[2], 0, 0, 0, &r);
    });
    // the direction (de scale, dn scale, dh |posting|) divided by the least
    // power of two that brings it within 2^62: on a package whose height
    // scale is 2^24 nm, de = +-2^40 makes exactly 2^64 -- divided by 4, to
    // exactly +-2^62 (not by 8); dh's part rounded half away from zero
    add("ray_from_map: largest component exactly 2^64", CT_OK, [](World &w) -> ct_status {
        for (int64_t sign : {INT64_C(1), INT64_C(-1)}) {
            ct_ray r;
            const ct_status st = ct_ray_from_map(&w.pow2, w.pa[0], w.pa[1], w.pa[2], sign * (INT64_C(1) << 40), 0, 3, &r);
            const int64_t dz = (3 * w.pow2.posting_e_nm + 2) / 4;
            if (st != CT_OK) return st;
            if (r.dx != sign * (INT64_C(1) << 62) || r.dy != 0 || r.dz != dz) return CT_ERR_INTERNAL;
        }
        return CT_OK;
    });
    add("surface_height: out NULL", CT_ERR_ARG, [](World &w) { return ct_surface_height(&w.p, 0, 0, nullptr); });
    add("surface_height: off the tile", CT_ERR_RANGE, [](World &w) {
        int64_t z;
        return ct_surface_height(&w.p, -1, 0, &z);
    });
    add("status_name: out NULL", CT_ERR_ARG, [](World &) { return ct_status_name(CT_OK, nullptr); });
    add("status_name: unknown status", CT_ERR_ARG, [](World &) {
        const char *s;
        return ct_status_name((ct_status)-999, &s);
    });
    // ---- cameras and poses
    add("camera_init: cam NULL", CT_ERR_ARG, [](World &) {
        const ct_lens lens = dem_cases::centred_pinhole(64, 48, 60);
        return ct_camera_init(nullptr, &lens);
    });
    add("camera_init: lens NULL", CT_ERR_ARG, [](World &) {
        ct_camera c;
        return ct_camera_init(&c, nullptr);
    });
    add("camera_init: focal length 0", CT_ERR_LENS, [](World &) {
        ct_lens lens = dem_cases::centred_pinhole(64, 48, 60);
        lens.fx_q32 = 0;
        ct_camera c;
        return ct_camera_init(&c, &lens);
    });
    // each of the lens's ranges alone
    struct LensEdit {
        const char *name;
        void (*edit)(ct_lens &);
    };
    static const LensEdit lens_edits[] = {
        {"camera_init: fy beyond 2^20 px", [](ct_lens &l) { l.fy_q32 = ((int64_t)CT_CAM_MAX_PIXEL << 32) + 1; }},
        {"camera_init: fx beyond 2^20 px", [](ct_lens &l) { l.fx_q32 = ((int64_t)CT_CAM_MAX_PIXEL << 32) + 1; }},
        {"camera_init: fy below 1 px", [](ct_lens &l) { l.fy_q32 = (INT64_C(1) << 32) - 1; }},
        {"camera_init: cx beyond 2^20 px", [](ct_lens &l) { l.cx_q32 = ((int64_t)CT_CAM_MAX_PIXEL << 32) + 1; }},
        {"camera_init: cx below -2^20 px", [](ct_lens &l) { l.cx_q32 = -((int64_t)CT_CAM_MAX_PIXEL << 32) - 1; }},
        {"camera_init: cy beyond 2^20 px", [](ct_lens &l) { l.cy_q32 = ((int64_t)CT_CAM_MAX_PIXEL << 32) + 1; }},
        {"camera_init: cy below -2^20 px", [](ct_lens &l) { l.cy_q32 = -((int64_t)CT_CAM_MAX_PIXEL << 32) - 1; }},
    };
    for (const LensEdit &e : lens_edits) {
        const LensEdit *ep = &e;
        add(e.name, CT_ERR_LENS, [ep](World &) {
            ct_lens lens = dem_cases::centred_pinhole(64, 48, 60);
            ep->edit(lens);
            ct_camera c;
            return ct_camera_init(&c, &lens);
        });
    }
    // a pixel whose normalised coordinate passes 2^16 (|u - cx| / fx): a
    // 1 px focal length and the centre at the far edge of the range
    add("camera_unproject: (u - cx) / fx beyond 2^16", CT_ERR_UNPROJECT, [](World &) -> ct_status {
        ct_lens lens = dem_cases::centred_pinhole(64, 48, 1);
        lens.cx_q32 = -((int64_t)CT_CAM_MAX_PIXEL << 32);
        ct_camera c;
        int32_t r[3];
        if (ct_camera_init(&c, &lens) != CT_OK) return CT_ERR_INTERNAL;
        return ct_camera_unproject(&c, (int64_t)CT_CAM_MAX_PIXEL << 16, 0, r, nullptr);
    });
    add("camera_unproject: (v - cy) / fy beyond 2^16", CT_ERR_UNPROJECT, [](World &) -> ct_status {
        ct_lens lens = dem_cases::centred_pinhole(64, 48, 1);
        lens.cy_q32 = (int64_t)CT_CAM_MAX_PIXEL << 32;
        ct_camera c;
        int32_t r[3];
        if (ct_camera_init(&c, &lens) != CT_OK) return CT_ERR_INTERNAL;
        return ct_camera_unproject(&c, 0, -((int64_t)CT_CAM_MAX_PIXEL << 16), r, nullptr);
    });
    // rational lenses with one denominator coefficient (k4, k5 or k6)
    // alone: the pixel unprojected and projected back lands within 1e-3 px
    for (int kk = 5; kk <= 7; ++kk) {
        static const char *const names[] = {"camera_init: OPENCV8 with k4 alone, round trip",
                                            "camera_init: OPENCV8 with k5 alone, round trip",
                                            "camera_init: OPENCV8 with k6 alone, round trip"};
        add(names[kk - 5], CT_OK, [kk](World &) -> ct_status {
            ct_lens lens = dem_cases::centred_pinhole(640, 480, 500);
            lens.model = CT_LENS_OPENCV8;
            lens.dist_q48[0] = -(INT64_C(1) << 46);  // k1 -0.25
            lens.dist_q48[kk] = INT64_C(1) << 45;    // 0.125
            ct_camera c;
            const ct_status st = ct_camera_init(&c, &lens);
            if (st != CT_OK) return st;
            for (int64_t u : {INT64_C(150), INT64_C(320), INT64_C(450)}) {
                const int64_t uq = u << 16, vq = (u / 2 + 90) << 16;
                int32_t r[3];
                int64_t u2, v2;
                if (ct_camera_unproject(&c, uq, vq, r, nullptr) != CT_OK ||
                    ct_camera_project(&c, r, &u2, &v2) != CT_OK)
                    return CT_ERR_INTERNAL;
                if (std::llabs(u2 - uq) > 66 || std::llabs(v2 - vq) > 66) return CT_ERR_INTERNAL;
            }
            return CT_OK;
        });
    }
    // unprojection grids: a 4 x 4 grid of the optical axis (0, 0, 1), one
    // field out of range or one node edited
    struct GridEdit {
        const char *name;
        ct_status want;
        void (*edit)(ct_unproject_grid &, int32_t *rays);
    };
    static const GridEdit grid_edits[] = {
        {"camera_init_grid: the axis everywhere (ok)", CT_OK, [](ct_unproject_grid &, int32_t *) {}},
        {"camera_init_grid: nv 3", CT_ERR_LENS, [](ct_unproject_grid &g, int32_t *) { g.nv = 3; }},
        {"camera_init_grid: nu beyond CT_GRID_MAX_NODES", CT_ERR_LENS,
         [](ct_unproject_grid &g, int32_t *) { g.nu = CT_GRID_MAX_NODES + 1u; }},
        {"camera_init_grid: nv beyond CT_GRID_MAX_NODES", CT_ERR_LENS,
         [](ct_unproject_grid &g, int32_t *) { g.nv = CT_GRID_MAX_NODES + 1u; }},
        {"camera_init_grid: step below 1 px", CT_ERR_LENS, [](ct_unproject_grid &g, int32_t *) { g.step_q16 = 65535; }},
        {"camera_init_grid: step beyond 4096 px", CT_ERR_LENS,
         [](ct_unproject_grid &g, int32_t *) { g.step_q16 = (INT64_C(4096) << 16) + 1; }},
        {"camera_init_grid: u0 beyond 2^20 px", CT_ERR_LENS,
         [](ct_unproject_grid &g, int32_t *) { g.u0_q16 = ((int64_t)CT_CAM_MAX_PIXEL << 16) + 1; }},
        {"camera_init_grid: v0 beyond 2^20 px", CT_ERR_LENS,
         [](ct_unproject_grid &g, int32_t *) { g.v0_q16 = -((int64_t)CT_CAM_MAX_PIXEL << 16) - 1; }},
        {"camera_init_grid: fewer rays than nodes", CT_ERR_LENS, [](ct_unproject_grid &g, int32_t *) { g.rays_len = 47; }},
        {"camera_init_grid: a node (0, 1, 0) (ok)", CT_OK,
         [](ct_unproject_grid &, int32_t *r) { r[3 * 5 + 1] = 1 << 30, r[3 * 5 + 2] = 0; }},
        {"camera_init_grid: a node (0, 0, 0) (no ray, ok)", CT_OK, [](ct_unproject_grid &, int32_t *r) { r[3 * 5 + 2] = 0; }},
        {"camera_init_grid: x beyond 1", CT_ERR_LENS, [](ct_unproject_grid &, int32_t *r) { r[3 * 5] = (1 << 30) + (1 << 13); }},
        {"camera_init_grid: x below -1", CT_ERR_LENS, [](ct_unproject_grid &, int32_t *r) { r[3 * 5] = -(1 << 30) - (1 << 13); }},
        {"camera_init_grid: y beyond 1", CT_ERR_LENS, [](ct_unproject_grid &, int32_t *r) { r[3 * 5 + 1] = (1 << 30) + (1 << 13); }},
        {"camera_init_grid: y below -1", CT_ERR_LENS,
         [](ct_unproject_grid &, int32_t *r) { r[3 * 5 + 1] = -(1 << 30) - (1 << 13); }},
        {"camera_init_grid: z beyond 1", CT_ERR_LENS, [](ct_unproject_grid &, int32_t *r) { r[3 * 5 + 2] = (1 << 30) + (1 << 13); }},
        {"camera_init_grid: z below -1", CT_ERR_LENS,
         [](ct_unproject_grid &, int32_t *r) { r[3 * 5 + 2] = -(1 << 30) - (1 << 13); }},
        {"camera_init_grid: a node not of unit length", CT_ERR_LENS, [](ct_unproject_grid &, int32_t *r) { r[3 * 5 + 2] = 1 << 29; }},
    };
    for (const GridEdit &e : grid_edits) {
        const GridEdit *ep = &e;
        add(e.name, e.want, [ep](World &) {
            static int32_t rays[48];
            for (int k = 0; k < 16; ++k) rays[3 * k] = rays[3 * k + 1] = 0, rays[3 * k + 2] = 1 << 30;
            ct_unproject_grid g{4u, 4u, 0, 0, INT64_C(16) << 16, rays, 48};
            ep->edit(g, rays);
            ct_camera c;
            return ct_camera_init_grid(&c, &g);
        });
    }
    // unprojecting through a grid: the centre cell of the 4 x 4 grid
    // (pixels 16..32) is the one cell with a node on every side
    struct GridPixel {
        const char *name;
        ct_status want;
        void (*edit)(int32_t *rays);
    };
    static const GridPixel grid_pixels[] = {
        {"camera_unproject (grid): the axis (ok)", CT_OK, [](int32_t *) {}},
        {"camera_unproject (grid): a node without a ray (x, y, z all 0)", CT_ERR_UNPROJECT,
         [](int32_t *r) { r[3 * 5 + 2] = 0; }},
        {"camera_unproject (grid): a node (0, 1, 0), 90 deg from its neighbours", CT_ERR_UNPROJECT,
         [](int32_t *r) { r[3 * 5 + 1] = 1 << 30, r[3 * 5 + 2] = 0; }},
        {"camera_unproject (grid): rows of opposite rays (they cancel)", CT_ERR_UNPROJECT,
         [](int32_t *r) {
             for (int k = 8; k < 16; ++k) r[3 * k + 2] = -(1 << 30);
         }},
    };
    for (const GridPixel &e : grid_pixels) {
        const GridPixel *ep = &e;
        add(e.name, e.want, [ep](World &) -> ct_status {
            static int32_t rays[48];
            for (int k = 0; k < 16; ++k) rays[3 * k] = rays[3 * k + 1] = 0, rays[3 * k + 2] = 1 << 30;
            ep->edit(rays);
            const ct_unproject_grid g{4u, 4u, 0, 0, INT64_C(16) << 16, rays, 48};
            ct_camera c;
            if (ct_camera_init_grid(&c, &g) != CT_OK) return CT_ERR_INTERNAL;
            int32_t r[3] = {0, 0, 0};
            const ct_status st = ct_camera_unproject(&c, INT64_C(20) << 16, INT64_C(21) << 16, r, nullptr);
            if (st == CT_OK && (r[0] != 0 || r[1] != 0 || r[2] != 1 << 30)) return CT_ERR_INTERNAL;  // the axis
            return st;
        });
    }
    add("pose_init: east beyond 2^61 nm", CT_ERR_POSE, [](World &) {
        const int32_t R[9] = {1 << 30, 0, 0, 0, 1 << 30, 0, 0, 0, 1 << 30};
        ct_pose q;
        return ct_pose_init(&q, R, (INT64_C(1) << 61) + 1, 0, 0);
    });
    add("pose_init: north beyond 2^61 nm", CT_ERR_POSE, [](World &) {
        const int32_t R[9] = {1 << 30, 0, 0, 0, 1 << 30, 0, 0, 0, 1 << 30};
        ct_pose q;
        return ct_pose_init(&q, R, 0, -(INT64_C(1) << 61) - 1, 0);
    });
    add("pose_init: height beyond 2^61 nm", CT_ERR_POSE, [](World &) {
        const int32_t R[9] = {1 << 30, 0, 0, 0, 1 << 30, 0, 0, 0, 1 << 30};
        ct_pose q;
        return ct_pose_init(&q, R, 0, 0, (INT64_C(1) << 61) + 1);
    });
    add("pose_init: an entry of the second column beyond 1", CT_ERR_POSE, [](World &) {
        const int32_t R[9] = {1 << 30, (1 << 30) + (1 << 13), 0, 0, 1 << 30, 0, 0, 0, 1 << 30};
        ct_pose q;
        return ct_pose_init(&q, R, 0, 0, 0);
    });
    add("camera_init_grid: grid NULL", CT_ERR_ARG, [](World &) {
        ct_camera c;
        return ct_camera_init_grid(&c, nullptr);
    });
    add("camera_unproject: ray NULL", CT_ERR_ARG, [](World &w) {
        uint32_t it;
        return ct_camera_unproject(&w.cam, 0, 0, nullptr, &it);
    });
    add("camera_unproject: camera never set up", CT_ERR_ARG, [](World &) {
        ct_camera c;
        std::memset(&c, 0, sizeof c);
        int32_t r[3];
        uint32_t it;
        return ct_camera_unproject(&c, 0, 0, r, &it);
    });
    add("camera_project: u NULL", CT_ERR_ARG, [](World &w) {
        const int32_t r[3] = {0, 0, 1 << 30};
        int64_t vv;
        return ct_camera_project(&w.cam, r, nullptr, &vv);
    });
    add("pose_init: R NULL", CT_ERR_ARG, [](World &) {
        ct_pose q;
        return ct_pose_init(&q, nullptr, 0, 0, 0);
    });
    add("pose_init: not a rotation", CT_ERR_POSE, [](World &) {
        const int32_t R[9] = {1 << 30, 0, 0, 0, 1 << 30, 0, 0, 0, -(1 << 30)};  // det -1
        ct_pose q;
        return ct_pose_init(&q, R, 0, 0, 0);
    });
    add("pose_rotate: out NULL", CT_ERR_ARG, [](World &w) {
        const int32_t r[3] = {0, 0, 1 << 30};
        return ct_pose_rotate(&w.pose, r, nullptr);
    });
    add("pose_from_map: quaternion NULL", CT_ERR_ARG, [](World &) {
        ct_pose q;
        return ct_pose_from_map(&q, 0, 0, 0, nullptr);
    });
    add("pose_from_map: quaternion far from unit", CT_ERR_POSE, [](World &) {
        const int32_t qq[4] = {1 << 29, 0, 0, 0};
        ct_pose q;
        return ct_pose_from_map(&q, 0, 0, 0, qq);
    });
    add("quat_from_ypr: out NULL", CT_ERR_ARG, [](World &) { return ct_quat_from_ypr(0, 0, 0, nullptr); });
    add("quat_from_ypr: yaw beyond pi", CT_ERR_RANGE, [](World &) {
        int32_t q[4];
        return ct_quat_from_ypr(CT_PI_Q61 + 1, 0, 0, q);
    });
    // ---- geolocation
    add("geolocate: out NULL", CT_ERR_ARG, [](World &w) {
        return ct_geolocate(&w.p, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, nullptr, 32 << 16, 24 << 16, nullptr);
    });
    add("geolocate: camera NULL", CT_ERR_ARG, [](World &w) {
        ct_geo g;
        return ct_geolocate(&w.p, nullptr, &w.pose, CT_METHOD_DIRECTIONAL, nullptr, 32 << 16, 24 << 16, &g);
    });
    add("geolocate: pose never set up", CT_ERR_ARG, [](World &w) {
        ct_pose q;
        std::memset(&q, 0, sizeof q);
        ct_geo g;
        return ct_geolocate(&w.p, &w.cam, &q, CT_METHOD_DIRECTIONAL, nullptr, 32 << 16, 24 << 16, &g);
    });
    add("geolocate: unknown method", CT_ERR_METHOD, [](World &w) {
        ct_geo g;
        return ct_geolocate(&w.p, &w.cam, &w.pose, kBadMethod, nullptr, 32 << 16, 24 << 16, &g);
    });
    add("geolocate: unknown effect flag", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {0x80u, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
        ct_geo g;
        return ct_geolocate(&w.p, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, &fx, 32 << 16, 24 << 16, &g);
    });
    add("geolocate: refraction k beyond 2", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {CT_EFFECT_REFRACTION | CT_EFFECT_CURVATURE, 3 * 65536, 0, 0, nullptr};
        ct_geo g;
        return ct_geolocate(&w.p, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, &fx, 32 << 16, 24 << 16, &g);
    });
    add("geolocate: an earth map never fitted", CT_ERR_EFFECTS, [](World &w) {
        ct_earth_map m;
        std::memset(&m, 0, sizeof m);
        const ct_effects fx = {CT_EFFECT_CURVATURE, 0, 0, 0, &m};
        ct_geo g;
        return ct_geolocate(&w.p, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, &fx, 32 << 16, 24 << 16, &g);
    });
    // a map fitted for w.p, used with a package whose georeference differs
    // in one field, or with one of its own fields out of range: "a map
    // fitted for this package, else CT_ERR_EFFECTS"; the map as fitted gives
    // the status of the exact conversions
    static ct_earth_map fitted;
    static ct_status fitted_st = CT_ERR_INTERNAL;
    auto with_map = [](World &w, void (*edit)(ct_package &, ct_earth_map &)) -> ct_status {
        if (fitted_st == CT_ERR_INTERNAL) fitted_st = ct_earth_map_init(&w.p, w.a[0], w.a[1], w.a[2], INT64_C(10000000000000), &fitted);
        if (fitted_st != CT_OK) return fitted_st;
        ct_package q = w.p;
        ct_earth_map m = fitted;
        edit(q, m);
        const ct_effects fx = {CT_EFFECT_CURVATURE, 0, 0, 0, &m};
        ct_geo g;
        const ct_status st = ct_geolocate(&q, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, &fx, 32 << 16, 24 << 16, &g);
        if (st < 0) return st;
        // accepted: the status of the exact conversions (no map)
        const ct_effects exact = {CT_EFFECT_CURVATURE, 0, 0, 0, nullptr};
        ct_geo g2;
        return ct_geolocate(&q, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, &exact, 32 << 16, 24 << 16, &g2) == st ? CT_OK : CT_ERR_INTERNAL;
    };
    struct MapEdit {
        const char *name;
        ct_status want;
        void (*edit)(ct_package &, ct_earth_map &);
    };
    static const MapEdit map_edits[] = {
        {"geolocate: the earth map as fitted (the exact status)", CT_OK, [](ct_package &, ct_earth_map &) {}},
        {"geolocate: earth map of degree 3", CT_ERR_EFFECTS, [](ct_package &, ct_earth_map &m) { m.deg = 3; }},
        {"geolocate: earth map of degree 7", CT_ERR_EFFECTS, [](ct_package &, ct_earth_map &m) { m.deg = CT_EARTH_MAP_DEG + 1; }},
        {"geolocate: earth map cube 2^43 nm", CT_ERR_EFFECTS, [](ct_package &, ct_earth_map &m) { m.qrho = 43u; }},
        {"geolocate: earth map cube 2^48 nm", CT_ERR_EFFECTS, [](ct_package &, ct_earth_map &m) { m.qrho = 48u; }},
        {"geolocate: earth map of another origin (east)", CT_ERR_EFFECTS, [](ct_package &q, ct_earth_map &) { q.origin_e_nm += 1; }},
        {"geolocate: earth map of another origin (north)", CT_ERR_EFFECTS, [](ct_package &q, ct_earth_map &) { q.origin_n_nm += 1; }},
        {"geolocate: earth map of another posting (east)", CT_ERR_EFFECTS, [](ct_package &q, ct_earth_map &) { q.posting_e_nm += 1; }},
        {"geolocate: earth map of another posting (north)", CT_ERR_EFFECTS, [](ct_package &q, ct_earth_map &) { q.posting_n_nm -= 1; }},
        {"geolocate: earth map of another height offset", CT_ERR_EFFECTS, [](ct_package &q, ct_earth_map &) { q.height_offset_nm += 1; }},
        {"geolocate: earth map of another height scale", CT_ERR_EFFECTS, [](ct_package &q, ct_earth_map &) { q.height_scale_nm += 1; }},
        {"geolocate: earth map of another zone", CT_ERR_EFFECTS, [](ct_package &q, ct_earth_map &) { q.epsg = 32618u; }},
    };
    for (const MapEdit &e : map_edits) {
        const MapEdit *ep = &e;
        add(e.name, e.want, [with_map, ep](World &w) { return with_map(w, ep->edit); });
    }
    // the true Earth with the camera 2,000 km east of the package's zone
    // (still inside the grid's range): its projection cannot take the pose
    add("geolocate: true Earth, camera 2,000 km east of the zone", CT_ERR_POSE, [](World &w) {
        const ct_effects fx = {CT_EFFECT_CURVATURE, 0, 0, 0, nullptr};
        ct_pose pose = w.pose;
        pose.e_nm += INT64_C(2000000000000000);
        ct_geo g;
        return ct_geolocate(&w.p, &w.cam, &pose, CT_METHOD_DIRECTIONAL, &fx, 32 << 16, 24 << 16, &g);
    });
    // a package whose EPSG code is beyond INT32_MAX (the header field is 32
    // bits unsigned): no UTM zone, so the true Earth falls back to the
    // sphere of 6371 km (the same hit as asking for it), and no earth map
    add("geolocate: true Earth, EPSG beyond INT32_MAX: the sphere's hit", CT_OK, [](World &w) -> ct_status {
        ct_package q = w.p;
        q.epsg = 0x80000000u + 32617u;
        const ct_effects earth = {CT_EFFECT_CURVATURE, 0, 0, 0, nullptr};
        const ct_effects sphere = {CT_EFFECT_CURVATURE, 0, CT_EARTH_RADIUS_NM, 0, nullptr};
        ct_geo g1, g2;
        const ct_status s1 = ct_geolocate(&q, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, &earth, 32 << 16, 24 << 16, &g1);
        const ct_status s2 = ct_geolocate(&q, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, &sphere, 32 << 16, 24 << 16, &g2);
        if (s1 != s2 || s1 < 0) return CT_ERR_INTERNAL;
        return s1 != CT_HIT || (g1.hit.e_nm == g2.hit.e_nm && g1.hit.n_nm == g2.hit.n_nm && g1.hit.h_nm == g2.hit.h_nm)
                   ? CT_OK
                   : CT_ERR_INTERNAL;
    });
    add("los: true Earth, EPSG beyond INT32_MAX: the sphere's answer", CT_OK, [](World &w) -> ct_status {
        ct_package q = w.p;
        q.epsg = 0x80000000u + 32617u;
        const ct_effects earth = {CT_EFFECT_CURVATURE, 0, 0, 0, nullptr};
        const ct_effects sphere = {CT_EFFECT_CURVATURE, 0, CT_EARTH_RADIUS_NM, 0, nullptr};
        ct_hit h1, h2;
        const ct_status s1 = ct_los(&q, w.a, w.b, &earth, 0, CT_METHOD_DIRECTIONAL, &h1);
        const ct_status s2 = ct_los(&q, w.a, w.b, &sphere, 0, CT_METHOD_DIRECTIONAL, &h2);
        return s1 == s2 && s1 >= 0 ? CT_OK : CT_ERR_INTERNAL;
    });
    add("locate_inverse: true Earth, EPSG beyond INT32_MAX: the sphere's pixel", CT_OK, [](World &w) -> ct_status {
        ct_package q = w.p;
        q.epsg = 0x80000000u + 32617u;
        const ct_effects earth = {CT_EFFECT_CURVATURE, 0, 0, 0, nullptr};
        const ct_effects sphere = {CT_EFFECT_CURVATURE, 0, CT_EARTH_RADIUS_NM, 0, nullptr};
        int64_t u1, v1, u2, v2;
        uint32_t vis1, vis2;
        ct_hit h1, h2;
        const ct_status s1 = ct_locate_inverse(&q, &w.cam, &w.pose, &earth, w.b, 0, &u1, &v1, &vis1, &h1);
        const ct_status s2 = ct_locate_inverse(&q, &w.cam, &w.pose, &sphere, w.b, 0, &u2, &v2, &vis2, &h2);
        return s1 == s2 && s1 >= 0 && u1 == u2 && v1 == v2 && vis1 == vis2 ? CT_OK : CT_ERR_INTERNAL;
    });
    add("earth_map_init: centre 2,000 km east of the zone's meridian", CT_ERR_RANGE, [](World &w) {
        static ct_earth_map m;
        return ct_earth_map_init(&w.p, w.a[0] + INT64_C(2000000000000000), w.a[1], w.a[2], INT64_C(10000000000000), &m);
    });
    add("earth_map_init: EPSG beyond INT32_MAX", CT_ERR_CRS, [](World &w) {
        ct_package q = w.p;
        q.epsg = 0x80000000u + 32617u;
        static ct_earth_map m;
        return ct_earth_map_init(&q, w.a[0], w.a[1], w.a[2], INT64_C(10000000000000), &m);
    });
    // heights in 0.1 mm codes: a cube of 2^47 nm leaves too few fraction
    // bits for the fit (CT_ERR_RANGE), one of 2^44 nm fits; the per-call fit
    // of CT_EFFECT_EARTH_FIT falls back to the exact conversions there (the
    // same hit as without it, bit for bit)
    static dem_cases::Case fine_h;
    static ct_package pfh;
    auto fine_heights = [](World &w) -> const ct_package * {
        if (fine_h.pkg.empty()) {
            ct_host::Terrain t = w.c.t;
            t.height_scale_m = 1e-4;
            fine_h = dem_cases::make_case("0.1 mm codes", t, 8, 2);
            if (ct_package_open(&pfh, fine_h.pkg.data(), fine_h.pkg.size()) != CT_OK) return nullptr;
        }
        return &pfh;
    };
    add("earth_map_init (0.1 mm height codes): a cube of 2^47 nm", CT_ERR_RANGE, [fine_heights](World &w) -> ct_status {
        const ct_package *q = fine_heights(w);
        if (q == nullptr) return CT_ERR_INTERNAL;
        static ct_earth_map m;
        if (ct_earth_map_init(q, w.a[0], w.a[1], w.a[2], INT64_C(1) << 44, &m) != CT_OK) return CT_ERR_INTERNAL;
        return ct_earth_map_init(q, w.a[0], w.a[1], w.a[2], INT64_C(1) << 47, &m);
    });
    add("geolocate (0.1 mm height codes): EARTH_FIT from 50 km up falls back to exact", CT_HIT, [fine_heights](World &w) -> ct_status {
        const ct_package *q = fine_heights(w);
        if (q == nullptr) return CT_ERR_INTERNAL;
        int32_t qq[4];
        ct_pose pose;
        if (ct_quat_from_ypr(0, dem_cases::deg_q61(-90), 0, qq) != CT_OK ||
            ct_pose_from_map(&pose, w.a[0], w.a[1], w.a[2] + INT64_C(50000000000000), qq) != CT_OK)
            return CT_ERR_INTERNAL;
        const ct_effects fit = {CT_EFFECT_CURVATURE | CT_EFFECT_EARTH_FIT, 0, 0, 0, nullptr};
        const ct_effects exact = {CT_EFFECT_CURVATURE, 0, 0, 0, nullptr};
        ct_geo g1, g2;
        // the principal point (63/2, 47/2) px: straight down
        const ct_status s1 = ct_geolocate(q, &w.cam, &pose, CT_METHOD_DIRECTIONAL, &fit, 63 << 15, 47 << 15, &g1);
        const ct_status s2 = ct_geolocate(q, &w.cam, &pose, CT_METHOD_DIRECTIONAL, &exact, 63 << 15, 47 << 15, &g2);
        if (s1 != s2 || s1 < 0) return CT_ERR_INTERNAL;
        return s1 != CT_HIT || (g1.hit.x_q16 == g2.hit.x_q16 && g1.hit.y_q16 == g2.hit.y_q16 && g1.hit.z_q16 == g2.hit.z_q16)
                   ? s1
                   : CT_ERR_INTERNAL;
    });
    add("geolocate: chord beyond 2^50 nm", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {CT_EFFECT_CURVATURE, 0, 0, (INT64_C(1) << 50) + 1, nullptr};
        ct_geo g;
        return ct_geolocate(&w.p, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, &fx, 32 << 16, 24 << 16, &g);
    });
    add("geolocate_batch: pixels NULL, count 1", CT_ERR_ARG, [](World &w) {
        ct_geo g;
        return ct_geolocate_batch(&w.p, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, nullptr, nullptr, 1, &g, 1);
    });
    add("geolocate_batch: out shorter than count", CT_ERR_ARG, [](World &w) {
        const int64_t uv[4] = {0, 0, 1 << 16, 1 << 16};
        ct_geo g[2];
        return ct_geolocate_batch(&w.p, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, nullptr, uv, 2, g, 1);
    });
    add("effects_for_tolerance: out NULL", CT_ERR_ARG, [](World &w) {
        return ct_effects_for_tolerance(&w.p, &w.cam, &w.pose, CT_REFRACTION_K_STD_Q16, 0, 1000000, nullptr);
    });
    add("los: block NULL", CT_ERR_ARG, [](World &w) {
        return ct_los(&w.p, w.a, w.b, nullptr, 0, CT_METHOD_DIRECTIONAL, nullptr);
    });
    add("los: negative margin", CT_ERR_ARG, [](World &w) {
        ct_hit h;
        return ct_los(&w.p, w.a, w.b, nullptr, -1, CT_METHOD_DIRECTIONAL, &h);
    });
    add("los: unknown method", CT_ERR_METHOD, [](World &w) {
        ct_hit h;
        return ct_los(&w.p, w.a, w.b, nullptr, 0, kBadMethod, &h);
    });
    add("los: A = B", CT_ERR_RAY, [](World &w) {
        ct_hit h;
        return ct_los(&w.p, w.a, w.a, nullptr, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    add("los: a point beyond 2^61 nm", CT_ERR_RAY, [](World &w) {
        int64_t far[3] = {w.b[0], w.b[1], (INT64_C(1) << 61) + 1};
        ct_hit h;
        return ct_los(&w.p, w.a, far, nullptr, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    add("locate_inverse: u NULL", CT_ERR_ARG, [](World &w) {
        int64_t vv;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(&w.p, &w.cam, &w.pose, nullptr, w.b, 0, nullptr, &vv, &vis, &h);
    });
    add("earth_map_init: map NULL", CT_ERR_ARG, [](World &w) {
        return ct_earth_map_init(&w.p, w.a[0], w.a[1], w.a[2], 10000000000000, nullptr);
    });
    add("earth_map_init: radius 0", CT_ERR_RANGE, [](World &w) {
        static ct_earth_map m;
        return ct_earth_map_init(&w.p, w.a[0], w.a[1], w.a[2], 0, &m);
    });
    // ---- geodesy
    add("utm_zone_of_epsg: zone NULL", CT_ERR_ARG, [](World &) { return ct_utm_zone_of_epsg(32617, nullptr); });
    add("utm_zone_of_epsg: not UTM", CT_ERR_CRS, [](World &) {
        ct_utm z;
        return ct_utm_zone_of_epsg(4326, &z);
    });
    add("utm_forward: e NULL", CT_ERR_ARG, [](World &) {
        const ct_utm z = {17, 0};
        int64_t n;
        return ct_utm_forward(&z, 0, 0, nullptr, &n);
    });
    add("utm_forward: zone 61", CT_ERR_ARG, [](World &) {
        const ct_utm z = {61, 0};
        int64_t e, n;
        return ct_utm_forward(&z, 0, 0, &e, &n);
    });
    add("utm_factors: gamma NULL", CT_ERR_ARG, [](World &) {
        const ct_utm z = {17, 0};
        int64_t k;
        return ct_utm_factors(&z, 0, 0, nullptr, &k);
    });
    add("utm_inverse: lat NULL", CT_ERR_ARG, [](World &) {
        const ct_utm z = {17, 0};
        int64_t lon;
        return ct_utm_inverse(&z, 500000000000000, 0, nullptr, &lon);
    });
    add("pose_from_wgs84: zone NULL", CT_ERR_ARG, [](World &) {
        const int32_t q[4] = {1 << 30, 0, 0, 0};
        ct_pose p;
        return ct_pose_from_wgs84(&p, nullptr, 0, 0, 0, q);
    });
    add("geoid_at: out NULL", CT_ERR_ARG, [](World &) {
        const ct_geoid_grid g = {0, 0, 0, 0, 0, nullptr};
        return ct_geoid_at(&g, 0, 0, nullptr);
    });
    add("package_geoid: out NULL", CT_ERR_ARG, [](World &w) { return ct_package_geoid(&w.p, w.a[0], w.a[1], nullptr); });
    add("ecef_from_wgs84: out NULL", CT_ERR_ARG, [](World &) { return ct_ecef_from_wgs84(0, 0, 0, nullptr); });
    add("ecef_from_wgs84: latitude beyond pi/2", CT_ERR_RANGE, [](World &) {
        int64_t x[3];
        return ct_ecef_from_wgs84(CT_PI_Q61 / 2 + 1, 0, 0, x);
    });
    add("wgs84_from_ecef: point NULL", CT_ERR_ARG, [](World &) {
        int64_t lat, lon, h;
        return ct_wgs84_from_ecef(nullptr, &lat, &lon, &h);
    });
    add("wgs84_from_ecef: the Earth's centre", CT_ERR_RANGE, [](World &) {
        const int64_t x[3] = {0, 0, 0};
        int64_t lat, lon, h;
        return ct_wgs84_from_ecef(x, &lat, &lon, &h);
    });
    // ---- tile sets
    add("tileset_open: ts NULL", CT_ERR_ARG, [](World &w) {
        ct_tile_slot s[1];
        return ct_tileset_open(nullptr, w.c.pkg.data(), w.c.pkg.size(), s, 1, nullptr, nullptr);
    });
    add("tileset_trace: ts NULL", CT_ERR_ARG, [](World &w) {
        ct_hit h;
        return ct_tileset_trace(nullptr, &w.ray, CT_METHOD_DIRECTIONAL, &h);
    });
    add("tileset_trace: ray NULL", CT_ERR_ARG, [](World &) {
        static ct_tileset ts{};
        ct_hit h;
        return ct_tileset_trace(&ts, nullptr, CT_METHOD_DIRECTIONAL, &h);
    });
    add("tileset_trace: hit NULL", CT_ERR_ARG, [](World &w) {
        static ct_tileset ts{};
        return ct_tileset_trace(&ts, &w.ray, CT_METHOD_DIRECTIONAL, nullptr);
    });
    add("tileset_trace: unknown method", CT_ERR_METHOD, [](World &w) {
        static ct_tileset ts{};
        ts.ready = CT_SET_READY;  // past the ready check: the method is checked before the set is used
        ct_hit h;
        return ct_tileset_trace(&ts, &w.ray, kBadMethod, &h);
    });
    add("geolocate_tiles: ts NULL", CT_ERR_ARG, [](World &w) {
        ct_geo g;
        return ct_geolocate_tiles(nullptr, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, nullptr, 0, 0, &g);
    });
    add("geolocate_batch_tiles: ts NULL", CT_ERR_ARG, [](World &w) {
        ct_geo g;
        const int64_t uv[2] = {0, 0};
        return ct_geolocate_batch_tiles(nullptr, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, nullptr, uv, 1, &g, 1);
    });
    add("los_tiles: ts NULL", CT_ERR_ARG, [](World &w) {
        ct_hit h;
        return ct_los_tiles(nullptr, w.a, w.b, nullptr, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    // ---- each part of a range check of several parts on its own (the
    // other parts in range), so that every part is seen to refuse
    add("package_size: height 1", CT_ERR_DIMS, [](World &) {
        uint32_t s;
        return ct_package_size(16, 1, 1, 8, 0, &s);
    });
    add("package_size: width CT_MAX_POSTS + 1", CT_ERR_DIMS, [](World &) {
        uint32_t s;
        return ct_package_size(CT_MAX_POSTS + 1u, 16, 1, 8, 0, &s);
    });
    add("package_size: height CT_MAX_POSTS + 1", CT_ERR_DIMS, [](World &) {
        uint32_t s;
        return ct_package_size(16, CT_MAX_POSTS + 1u, 1, 8, 0, &s);
    });
    add("package_size: CT_MAX_SECTORS + 1 sectors", CT_ERR_SECTORS, [](World &) {
        uint32_t s;
        return ct_package_size(16, 16, 1, CT_MAX_SECTORS + 1u, 0, &s);
    });
    add("package_size: r CT_MAX_REDUCE + 1", CT_ERR_REDUCE, [](World &) {
        uint32_t s;
        return ct_package_size(16, 16, CT_MAX_REDUCE + 1u, 8, 0, &s);
    });
    // the largest grid, r = 1, 64 sectors: 32767^2 cells x 65 angle planes
    // alone are 2^36 bytes, beyond a 32-bit package size
    add("package_size: CT_MAX_POSTS^2, r 1, 64 sectors (over 4 GB)", CT_ERR_SIZE, [](World &) {
        uint32_t s;
        return ct_package_size(CT_MAX_POSTS, CT_MAX_POSTS, 1, CT_MAX_SECTORS, 1, &s);
    });
    add("crc32: data NULL, len 0 (nothing to read)", CT_OK, [](World &) {
        uint32_t c = 1;
        const ct_status st = ct_crc32(0, nullptr, 0, &c);
        return st == CT_OK && c == 0u ? CT_OK : CT_ERR_INTERNAL;  // the CRC of no bytes from 0 is 0
    });
    add("package_verify: a package never opened (no bytes)", CT_ERR_ARG, [](World &) {
        static const ct_package q{};
        return ct_package_verify(&q);
    });
    add("cot_table: height scale 0", CT_ERR_GEOREF, [](World &) {
        static int64_t out[256];
        static uint8_t ok[256];
        return ct_cot_table(30000000000, 0, out, ok);
    });
    add("cot_table: posting beyond 2^50", CT_ERR_GEOREF, [](World &) {
        static int64_t out[256];
        static uint8_t ok[256];
        return ct_cot_table((INT64_C(1) << 50) + 1, 62500000, out, ok);
    });
    add("cot_table: height scale beyond 2^46", CT_ERR_GEOREF, [](World &) {
        static int64_t out[256];
        static uint8_t ok[256];
        return ct_cot_table(30000000000, (INT64_C(1) << 46) + 1, out, ok);
    });
    add("in_wedge: 0 sectors", CT_ERR_SECTORS, [](World &w) {
        uint32_t in;
        return ct_in_wedge(w.p.bound_x, w.p.bound_y, 0, 0, 1, 0, &in);
    });
    add("in_wedge: CT_MAX_SECTORS + 1 sectors", CT_ERR_SECTORS, [](World &w) {
        uint32_t in;
        return ct_in_wedge(w.p.bound_x, w.p.bound_y, CT_MAX_SECTORS + 1u, 0, 1, 0, &in);
    });
    add("in_wedge: dy beyond 2^30", CT_ERR_ARG, [](World &w) {
        uint32_t in;
        return ct_in_wedge(w.p.bound_x, w.p.bound_y, 8, 0, 1, -(INT64_C(1) << 30) - 1, &in);
    });
    add("sector_of: dx beyond 2^30", CT_ERR_ARG, [](World &w) {
        uint32_t s;
        return ct_sector_of(&w.p, -(INT64_C(1) << 30) - 1, 0, &s);
    });
    add("sector_of: dy beyond 2^30", CT_ERR_ARG, [](World &w) {
        uint32_t s;
        return ct_sector_of(&w.p, 0, (INT64_C(1) << 30) + 1, &s);
    });
    add("status_name: one past CT_NO_DATA", CT_ERR_ARG, [](World &) {
        const char *n = nullptr;
        return ct_status_name((ct_status)(CT_NO_DATA + 1), &n);
    });
    add("status_name: one below CT_ERR_CRS", CT_ERR_ARG, [](World &) {
        const char *n = nullptr;
        return ct_status_name((ct_status)(CT_ERR_CRS - 1), &n);
    });
    add("utm_zone_of_epsg: 32761 (one past the southern zones)", CT_ERR_CRS, [](World &) {
        ct_utm z;
        return ct_utm_zone_of_epsg(32761, &z);
    });
    add("utm_inverse: zone 0", CT_ERR_ARG, [](World &) {
        const ct_utm z = {0, 0};
        int64_t lat, lon;
        return ct_utm_inverse(&z, 500000000000000, 0, &lat, &lon);
    });
    add("utm_inverse: zone 61", CT_ERR_ARG, [](World &) {
        const ct_utm z = {61, 0};
        int64_t lat, lon;
        return ct_utm_inverse(&z, 500000000000000, 0, &lat, &lon);
    });
    add("utm_inverse: northing beyond 2^60 nm", CT_ERR_RANGE, [](World &) {
        const ct_utm z = {17, 0};
        int64_t lat, lon;
        return ct_utm_inverse(&z, 500000000000000, (INT64_C(1) << 60) + 1, &lat, &lon);
    });
    add("utm_inverse: 9,600 km north of the equator (beyond 84.5 deg)", CT_ERR_RANGE, [](World &) {
        const ct_utm z = {17, 0};
        int64_t lat, lon;
        return ct_utm_inverse(&z, 500000000000000, 9600000000000000, &lat, &lon);
    });
    // 1,000 km east of the meridian at 6,600 km north (about 59 deg): some
    // 17 deg of longitude away, beyond the zone's 9 deg
    add("utm_inverse: 17 deg from the central meridian", CT_ERR_RANGE, [](World &) {
        const ct_utm z = {17, 0};
        int64_t lat, lon;
        return ct_utm_inverse(&z, 1500000000000000, 6600000000000000, &lat, &lon);
    });
    add("package_geoid: a package on no UTM zone (EPSG 0)", CT_ERR_CRS, [](World &w) {
        ct_package q = w.p;
        int64_t n;
        q.epsg = 0;
        return ct_package_geoid(&q, w.a[0], w.a[1], &n);
    });
    add("package_geoid: an EPSG code beyond INT32_MAX", CT_ERR_CRS, [](World &w) {
        ct_package q = w.p;
        int64_t n;
        q.epsg = 0x80000000u + 32617u;
        return ct_package_geoid(&q, w.a[0], w.a[1], &n);
    });
    add("package_geoid: a point far off the zone", CT_ERR_RANGE, [](World &w) {
        int64_t n;
        return ct_package_geoid(&w.p, INT64_C(1) << 61, w.a[1], &n);
    });
    // a 2 x 2 geoid grid with its north-west node at 0.5 rad, 0.1 rad
    // apart, but one dimension or the point out of range
    static const uint8_t geoid_vals[16 * 4097] = {0};
    auto geoid = [](uint32_t gw, uint32_t gh) {
        return ct_geoid_grid{gw, gh, CT_PI_Q61 / 6, 0, CT_PI_Q61 / 31, geoid_vals};
    };
    add("geoid_at: a grid of one row", CT_ERR_RANGE, [geoid](World &) {
        const ct_geoid_grid g = geoid(2, 1);
        int64_t n;
        return ct_geoid_at(&g, CT_PI_Q61 / 7, CT_PI_Q61 / 64, &n);
    });
    add("geoid_at: a grid of CT_GEOID_MAX_NODES + 1 rows", CT_ERR_RANGE, [geoid](World &) {
        const ct_geoid_grid g = geoid(2, CT_GEOID_MAX_NODES + 1u);
        int64_t n;
        return ct_geoid_at(&g, CT_PI_Q61 / 7, CT_PI_Q61 / 64, &n);
    });
    add("geoid_at: a point north of the grid's first row", CT_ERR_RANGE, [geoid](World &) {
        const ct_geoid_grid g = geoid(2, 2);
        int64_t n;
        return ct_geoid_at(&g, CT_PI_Q61 / 5, CT_PI_Q61 / 64, &n);
    });
    add("geoid_at: the same grid, a point inside it", CT_OK, [geoid](World &) {
        const ct_geoid_grid g = geoid(2, 2);
        int64_t n = 1;
        const ct_status st = ct_geoid_at(&g, CT_PI_Q61 / 6 - CT_PI_Q61 / 64, CT_PI_Q61 / 64, &n);
        return st == CT_OK && n == 0 ? CT_OK : CT_ERR_INTERNAL;  // all nodes 0
    });
    // ---- the grid's range: on the 1 um grid a point 10 km away is beyond
    // CT_MAX_ORIGIN_Q16 (2^46 Q16) and one 2^57 nm away beyond what
    // ct_map_to_grid can express (2^62)
    const int64_t km10 = INT64_C(10000000000000), far57 = INT64_C(1) << 57;
    add("map_to_grid (1 um grid): 2^57 nm east", CT_ERR_RANGE, [far57](World &w) {
        int64_t x, y, z;
        return ct_map_to_grid(&w.fine, w.fa[0] + far57, w.fa[1], w.fa[2], &x, &y, &z);
    });
    add("map_to_grid (1 um grid): 2^57 nm north", CT_ERR_RANGE, [far57](World &w) {
        int64_t x, y, z;
        return ct_map_to_grid(&w.fine, w.fa[0], w.fa[1] - far57, w.fa[2], &x, &y, &z);
    });
    add("map_to_grid (1 um grid): 2^57 nm up", CT_ERR_RANGE, [far57](World &w) {
        int64_t x, y, z;
        return ct_map_to_grid(&w.fine, w.fa[0], w.fa[1], w.fa[2] + far57, &x, &y, &z);
    });
    // a camera looking down 60 deg at (de, dn, dh) from the fine tile's point
    auto fine_geo = [](World &w, int64_t de, int64_t dn, int64_t dh, const ct_effects *fx) -> ct_status {
        int32_t q[4];
        ct_pose pose;
        if (ct_quat_from_ypr(0, dem_cases::deg_q61(-60), 0, q) != CT_OK ||
            ct_pose_from_map(&pose, w.fa[0] + de, w.fa[1] + dn, w.fa[2] + dh, q) != CT_OK)
            return CT_ERR_INTERNAL;
        ct_geo g;
        return ct_geolocate(&w.fine, &w.cam, &pose, CT_METHOD_DIRECTIONAL, fx, 32 << 16, 24 << 16, &g);
    };
    static const ct_effects earth = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
    static const ct_effects sphere = {CT_EFFECT_CURVATURE, 0, CT_EARTH_RADIUS_NM, 0, nullptr};
    for (const ct_effects *fx : {(const ct_effects *)nullptr, &earth, &sphere}) {
        const std::string tag = fx == nullptr ? "" : (fx == &earth ? ", true Earth" : ", sphere");
        static std::deque<std::string> names;  // push_back keeps earlier elements in place
        auto name = [&](const char *what) {
            names.push_back(std::string("geolocate (1 um grid): camera ") + what + tag);
            return names.back().c_str();
        };
        add(name("10 km east"), CT_ERR_RAY, [fine_geo, fx, km10](World &w) { return fine_geo(w, km10, 0, 0, fx); });
        add(name("10 km south"), CT_ERR_RAY, [fine_geo, fx, km10](World &w) { return fine_geo(w, 0, -km10, 0, fx); });
        add(name("10 km up"), CT_ERR_RAY, [fine_geo, fx, km10](World &w) { return fine_geo(w, 0, 0, km10, fx); });
        add(name("2^57 nm west"), CT_ERR_RAY, [fine_geo, fx, far57](World &w) { return fine_geo(w, -far57, 0, 0, fx); });
    }
    // inverse location on the true Earth with the camera 10 km east on the
    // 1 um grid: beyond the grid's range (ct_los's status for that camera)
    add("locate_inverse (1 um grid): camera 10 km east, true Earth", CT_ERR_RAY, [km10](World &w) -> ct_status {
        int32_t q[4];
        ct_pose pose;
        if (ct_quat_from_ypr(0, dem_cases::deg_q61(-60), 0, q) != CT_OK ||
            ct_pose_from_map(&pose, w.fa[0] + km10, w.fa[1], w.fa[2], q) != CT_OK)
            return CT_ERR_INTERNAL;
        int64_t u, vv;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(&w.fine, &w.cam, &pose, &earth, w.fa, 0, &u, &vv, &vis, &h);
    });
    // line of sight with one end beyond the grid's range on one axis
    struct LosEnd {
        const char *name;
        int end, axis;
        int64_t d;
    };
    static const LosEnd los_ends[] = {
        {"los (1 um grid): A 10 km east", 0, 0, INT64_C(10000000000000)},
        {"los (1 um grid): A 10 km north", 0, 1, INT64_C(10000000000000)},
        {"los (1 um grid): A 10 km up", 0, 2, INT64_C(10000000000000)},
        {"los (1 um grid): B 10 km west", 1, 0, -INT64_C(10000000000000)},
        {"los (1 um grid): B 10 km south", 1, 1, -INT64_C(10000000000000)},
        {"los (1 um grid): B 10 km up", 1, 2, INT64_C(10000000000000)},
        {"los (1 um grid): A 2^57 nm east", 0, 0, INT64_C(1) << 57},
        {"los (1 um grid): B 2^57 nm north", 1, 1, INT64_C(1) << 57},
    };
    for (const LosEnd &e : los_ends) {
        const LosEnd *ep = &e;
        add(e.name, CT_ERR_RAY, [ep](World &w) {
            int64_t a[3] = {w.fa[0], w.fa[1], w.fa[2]}, b[3] = {w.fa[0] + 3000, w.fa[1] - 4000, w.fa[2] - 1000};
            (ep->end == 0 ? a : b)[ep->axis] += ep->d;
            ct_hit h;
            return ct_los(&w.fine, a, b, nullptr, 0, CT_METHOD_DIRECTIONAL, &h);
        });
    }
    // the sphere on the 1 um grid (its lowering's constants from the far
    // end of their normalisation): over 23 um the bend is far below a
    // height code, so the answer is the straight line's
    add("los (1 um grid): the sphere, as straight", CT_OK, [](World &w) -> ct_status {
        const ct_effects fx = {CT_EFFECT_CURVATURE, 0, CT_EARTH_RADIUS_NM, 0, nullptr};
        ct_hit h;
        for (int64_t dz : {INT64_C(-1000), INT64_C(-100000), INT64_C(-3000000)}) {
            const int64_t b[3] = {w.fa[0] + 3000, w.fa[1] - 4000, w.fa[2] + dz};
            const ct_status s1 = ct_los(&w.fine, w.fa, b, &fx, 0, CT_METHOD_DIRECTIONAL, &h);
            if (s1 < 0 || s1 != ct_los(&w.fine, w.fa, b, nullptr, 0, CT_METHOD_DIRECTIONAL, &h)) return CT_ERR_INTERNAL;
        }
        return CT_OK;
    });
    add("earth_map_init (1 um grid): centre 10 km east", CT_ERR_RANGE, [km10](World &w) {
        static ct_earth_map m;
        return ct_earth_map_init(&w.fine, w.fa[0] + km10, w.fa[1], w.fa[2], INT64_C(10000000000000), &m);
    });
    add("earth_map_init (1 um grid): centre 10 km north", CT_ERR_RANGE, [km10](World &w) {
        static ct_earth_map m;
        return ct_earth_map_init(&w.fine, w.fa[0], w.fa[1] + km10, w.fa[2], INT64_C(10000000000000), &m);
    });
    add("earth_map_init (1 um grid): centre 10 km up", CT_ERR_RANGE, [km10](World &w) {
        static ct_earth_map m;
        return ct_earth_map_init(&w.fine, w.fa[0], w.fa[1], w.fa[2] + km10, INT64_C(10000000000000), &m);
    });
    // ---- a grid whose axes run west and north: ct_map_to_grid is
    // ct_grid_to_map's inverse, x grows westwards and y northwards, and a
    // camera straight above a point sees that point
    add("map_to_grid (axes west and north): inverse of grid_to_map, x west, y north", CT_OK, [](World &w) -> ct_status {
        int64_t e, n, h, x, y, z, x2, y2, z2;
        if (ct_grid_to_map(&w.west, 7 << 16, 5 << 16, 1000 << 16, &e, &n, &h) != CT_OK ||
            ct_map_to_grid(&w.west, e, n, h, &x, &y, &z) != CT_OK ||
            ct_map_to_grid(&w.west, e - 30000000000, n + 30000000000, h, &x2, &y2, &z2) != CT_OK)
            return CT_ERR_INTERNAL;
        return x == 7 << 16 && y == 5 << 16 && z == 1000 << 16 && x2 == x + 65536 && y2 == y + 65536 && z2 == z
                   ? CT_OK
                   : CT_ERR_INTERNAL;
    });
    add("geolocate (axes west and north): nadir pixel hits below the camera", CT_HIT, [](World &w) -> ct_status {
        int64_t e, n, h;
        int32_t q[4];
        ct_pose pose;
        if (ct_grid_to_map(&w.west, (11 << 16) + 12345, (9 << 16) + 23456, (int64_t)w.west.hmax << 16, &e, &n, &h) != CT_OK ||
            ct_quat_from_ypr(0, dem_cases::deg_q61(-90), 0, q) != CT_OK ||
            ct_pose_from_map(&pose, e, n, h + 200000000000, q) != CT_OK)
            return CT_ERR_INTERNAL;
        ct_geo g;
        // the centred pinhole's principal point: (63/2, 47/2) px
        const ct_status st = ct_geolocate(&w.west, &w.cam, &pose, CT_METHOD_DIRECTIONAL, nullptr, 63 << 15, 47 << 15, &g);
        if (st == CT_HIT && (std::llabs(g.hit.e_nm - e) > 1000000 || std::llabs(g.hit.n_nm - n) > 1000000)) return CT_ERR_INTERNAL;
        return st;
    });
    // ---- every other pointer argument NULL: CT_ERR_ARG, the rule of the header
    auto null_arg = [&](const char *name, std::function<ct_status(World &)> f) { add(name, CT_ERR_ARG, std::move(f)); };
    null_arg("package_layout: sec_size NULL", [](World &) {
        uint32_t off[CT_SEC_COUNT], levels, total;
        return ct_package_layout(16, 16, 1, 8, 0, off, nullptr, &levels, &total);
    });
    null_arg("package_layout: total NULL", [](World &) {
        uint32_t off[CT_SEC_COUNT], size[CT_SEC_COUNT], levels;
        return ct_package_layout(16, 16, 1, 8, 0, off, size, &levels, nullptr);
    });
    null_arg("sector_boundary: by NULL", [](World &) {
        int32_t x;
        return ct_sector_boundary(8, 0, &x, nullptr);
    });
    null_arg("in_wedge: bound_y NULL", [](World &w) {
        uint32_t in;
        return ct_in_wedge(w.p.bound_x, nullptr, 8, 0, 1, 0, &in);
    });
    null_arg("in_wedge: out NULL", [](World &w) { return ct_in_wedge(w.p.bound_x, w.p.bound_y, 8, 0, 1, 0, nullptr); });
    null_arg("cot_table: ok NULL", [](World &) {
        int64_t c[256];
        return ct_cot_table(30000000000, 62500000, c, nullptr);
    });
    null_arg("ray_prepare_segment: pkg NULL", [](World &w) {
        ct_prepared q;
        return ct_ray_prepare_segment(nullptr, &w.ray, &q);
    });
    null_arg("ray_prepare_segment: ray NULL", [](World &w) {
        ct_prepared q;
        return ct_ray_prepare_segment(&w.p, nullptr, &q);
    });
    null_arg("trace_prepared: pkg NULL", [](World &w) {
        ct_hit h;
        return ct_trace_prepared(nullptr, &w.pr, CT_METHOD_DIRECTIONAL, &h);
    });
    null_arg("trace: ray NULL", [](World &w) {
        ct_hit h;
        return ct_trace(&w.p, nullptr, CT_METHOD_DIRECTIONAL, &h);
    });
    null_arg("trace: hit NULL", [](World &w) { return ct_trace(&w.p, &w.ray, CT_METHOD_DIRECTIONAL, nullptr); });
    null_arg("trace_bent: pkg NULL", [](World &w) {
        const ct_bend bd = {57016, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u};
        ct_hit h;
        return ct_trace_bent(nullptr, &w.ray, &bd, CT_METHOD_DIRECTIONAL, &h);
    });
    null_arg("trace_bent: ray NULL", [](World &w) {
        const ct_bend bd = {57016, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u};
        ct_hit h;
        return ct_trace_bent(&w.p, nullptr, &bd, CT_METHOD_DIRECTIONAL, &h);
    });
    null_arg("trace_bent: hit NULL", [](World &w) {
        const ct_bend bd = {57016, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u};
        return ct_trace_bent(&w.p, &w.ray, &bd, CT_METHOD_DIRECTIONAL, nullptr);
    });
    add("trace_bent: unknown method", CT_ERR_METHOD, [](World &w) {
        const ct_bend bd = {57016, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u};
        ct_hit h;
        return ct_trace_bent(&w.p, &w.ray, &bd, kBadMethod, &h);
    });
    null_arg("grid_to_map: pkg NULL", [](World &) {
        int64_t e, n, h;
        return ct_grid_to_map(nullptr, 0, 0, 0, &e, &n, &h);
    });
    null_arg("grid_to_map: n NULL", [](World &w) {
        int64_t e, h;
        return ct_grid_to_map(&w.p, 0, 0, 0, &e, nullptr, &h);
    });
    null_arg("grid_to_map: h NULL", [](World &w) {
        int64_t e, n;
        return ct_grid_to_map(&w.p, 0, 0, 0, &e, &n, nullptr);
    });
    null_arg("map_to_grid: x NULL", [](World &w) {
        int64_t y, z;
        return ct_map_to_grid(&w.p, w.a[0], w.a[1], w.a[2], nullptr, &y, &z);
    });
    null_arg("map_to_grid: y NULL", [](World &w) {
        int64_t x, z;
        return ct_map_to_grid(&w.p, w.a[0], w.a[1], w.a[2], &x, nullptr, &z);
    });
    null_arg("map_to_grid: z NULL", [](World &w) {
        int64_t x, y;
        return ct_map_to_grid(&w.p, w.a[0], w.a[1], w.a[2], &x, &y, nullptr);
    });
    null_arg("ray_from_map: pkg NULL", [](World &w) {
        ct_ray r;
        return ct_ray_from_map(nullptr, w.a[0], w.a[1], w.a[2], 1, 0, 0, &r);
    });
    null_arg("surface_height: pkg NULL", [](World &) {
        int64_t z;
        return ct_surface_height(nullptr, 0, 0, &z);
    });
    null_arg("camera_init_grid: cam NULL", [](World &) {
        ct_unproject_grid g{};
        return ct_camera_init_grid(nullptr, &g);
    });
    null_arg("camera_unproject: cam NULL", [](World &) {
        int32_t r[3];
        uint32_t it;
        return ct_camera_unproject(nullptr, 0, 0, r, &it);
    });
    null_arg("camera_project: cam NULL", [](World &) {
        const int32_t r[3] = {0, 0, 1 << 30};
        int64_t u, vv;
        return ct_camera_project(nullptr, r, &u, &vv);
    });
    null_arg("camera_project: ray NULL", [](World &w) {
        int64_t u, vv;
        return ct_camera_project(&w.cam, nullptr, &u, &vv);
    });
    null_arg("camera_project: v NULL", [](World &w) {
        const int32_t r[3] = {0, 0, 1 << 30};
        int64_t u;
        return ct_camera_project(&w.cam, r, &u, nullptr);
    });
    null_arg("camera_project: camera never set up", [](World &) {
        ct_camera c;
        std::memset(&c, 0, sizeof c);
        const int32_t r[3] = {0, 0, 1 << 30};
        int64_t u, vv;
        return ct_camera_project(&c, r, &u, &vv);
    });
    null_arg("pose_init: pose NULL", [](World &) {
        const int32_t R[9] = {1 << 30, 0, 0, 0, 1 << 30, 0, 0, 0, 1 << 30};
        return ct_pose_init(nullptr, R, 0, 0, 0);
    });
    null_arg("pose_rotate: pose NULL", [](World &) {
        const int32_t r[3] = {0, 0, 1 << 30};
        int64_t d[3];
        return ct_pose_rotate(nullptr, r, d);
    });
    null_arg("pose_rotate: ray NULL", [](World &w) {
        int64_t d[3];
        return ct_pose_rotate(&w.pose, nullptr, d);
    });
    null_arg("pose_rotate: pose never set up", [](World &) {
        ct_pose q;
        std::memset(&q, 0, sizeof q);
        const int32_t r[3] = {0, 0, 1 << 30};
        int64_t d[3];
        return ct_pose_rotate(&q, r, d);
    });
    null_arg("pose_from_map: pose NULL", [](World &) {
        const int32_t q[4] = {1 << 30, 0, 0, 0};
        return ct_pose_from_map(nullptr, 0, 0, 0, q);
    });
    null_arg("pose_from_wgs84: pose NULL", [](World &) {
        const ct_utm z = {17, 0};
        const int32_t q[4] = {1 << 30, 0, 0, 0};
        return ct_pose_from_wgs84(nullptr, &z, 0, 0, 0, q);
    });
    null_arg("pose_from_wgs84: quaternion NULL", [](World &) {
        const ct_utm z = {17, 0};
        ct_pose p;
        return ct_pose_from_wgs84(&p, &z, 0, 0, 0, nullptr);
    });
    null_arg("geolocate: pkg NULL", [](World &w) {
        ct_geo g;
        return ct_geolocate(nullptr, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, nullptr, 0, 0, &g);
    });
    null_arg("geolocate: pose NULL", [](World &w) {
        ct_geo g;
        return ct_geolocate(&w.p, &w.cam, nullptr, CT_METHOD_DIRECTIONAL, nullptr, 0, 0, &g);
    });
    null_arg("geolocate: camera never set up", [](World &w) {
        ct_camera c;
        std::memset(&c, 0, sizeof c);
        ct_geo g;
        return ct_geolocate(&w.p, &c, &w.pose, CT_METHOD_DIRECTIONAL, nullptr, 0, 0, &g);
    });
    null_arg("geolocate_batch: pkg NULL", [](World &w) {
        const int64_t uv[2] = {0, 0};
        ct_geo g;
        return ct_geolocate_batch(nullptr, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, nullptr, uv, 1, &g, 1);
    });
    null_arg("geolocate_batch: out NULL, count 1", [](World &w) {
        const int64_t uv[2] = {0, 0};
        return ct_geolocate_batch(&w.p, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, nullptr, uv, 1, nullptr, 1);
    });
    null_arg("effects_for_tolerance: pkg NULL", [](World &w) {
        ct_effects_choice ch;
        return ct_effects_for_tolerance(nullptr, &w.cam, &w.pose, CT_REFRACTION_K_STD_Q16, 0, 1000000, &ch);
    });
    null_arg("effects_for_tolerance: camera NULL", [](World &w) {
        ct_effects_choice ch;
        return ct_effects_for_tolerance(&w.p, nullptr, &w.pose, CT_REFRACTION_K_STD_Q16, 0, 1000000, &ch);
    });
    null_arg("effects_for_tolerance: pose NULL", [](World &w) {
        ct_effects_choice ch;
        return ct_effects_for_tolerance(&w.p, &w.cam, nullptr, CT_REFRACTION_K_STD_Q16, 0, 1000000, &ch);
    });
    null_arg("los: pkg NULL", [](World &w) {
        ct_hit h;
        return ct_los(nullptr, w.a, w.b, nullptr, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    null_arg("los: A NULL", [](World &w) {
        ct_hit h;
        return ct_los(&w.p, nullptr, w.b, nullptr, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    null_arg("los: B NULL", [](World &w) {
        ct_hit h;
        return ct_los(&w.p, w.a, nullptr, nullptr, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    null_arg("locate_inverse: pkg NULL", [](World &w) {
        int64_t u, vv;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(nullptr, &w.cam, &w.pose, nullptr, w.b, 0, &u, &vv, &vis, &h);
    });
    null_arg("locate_inverse: camera NULL", [](World &w) {
        int64_t u, vv;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(&w.p, nullptr, &w.pose, nullptr, w.b, 0, &u, &vv, &vis, &h);
    });
    null_arg("locate_inverse: pose NULL", [](World &w) {
        int64_t u, vv;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(&w.p, &w.cam, nullptr, nullptr, w.b, 0, &u, &vv, &vis, &h);
    });
    null_arg("locate_inverse: point NULL", [](World &w) {
        int64_t u, vv;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(&w.p, &w.cam, &w.pose, nullptr, nullptr, 0, &u, &vv, &vis, &h);
    });
    null_arg("locate_inverse: v NULL", [](World &w) {
        int64_t u;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(&w.p, &w.cam, &w.pose, nullptr, w.b, 0, &u, nullptr, &vis, &h);
    });
    null_arg("locate_inverse: visible NULL", [](World &w) {
        int64_t u, vv;
        ct_hit h;
        return ct_locate_inverse(&w.p, &w.cam, &w.pose, nullptr, w.b, 0, &u, &vv, nullptr, &h);
    });
    null_arg("locate_inverse: block NULL", [](World &w) {
        int64_t u, vv;
        uint32_t vis;
        return ct_locate_inverse(&w.p, &w.cam, &w.pose, nullptr, w.b, 0, &u, &vv, &vis, nullptr);
    });
    null_arg("locate_inverse: camera never set up", [](World &w) {
        ct_camera c;
        std::memset(&c, 0, sizeof c);
        int64_t u, vv;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(&w.p, &c, &w.pose, nullptr, w.b, 0, &u, &vv, &vis, &h);
    });
    null_arg("locate_inverse: pose never set up", [](World &w) {
        ct_pose q;
        std::memset(&q, 0, sizeof q);
        int64_t u, vv;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(&w.p, &w.cam, &q, nullptr, w.b, 0, &u, &vv, &vis, &h);
    });
    add("locate_inverse: a point beyond 2^61 nm", CT_ERR_RAY, [](World &w) {
        const int64_t far[3] = {w.b[0], (INT64_C(1) << 61) + 1, w.b[2]};
        int64_t u, vv;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(&w.p, &w.cam, &w.pose, nullptr, far, 0, &u, &vv, &vis, &h);
    });
    null_arg("earth_map_init: pkg NULL", [](World &w) {
        static ct_earth_map m;
        return ct_earth_map_init(nullptr, w.a[0], w.a[1], w.a[2], 10000000000000, &m);
    });
    null_arg("utm_forward: zone NULL", [](World &) {
        int64_t e, n;
        return ct_utm_forward(nullptr, 0, 0, &e, &n);
    });
    null_arg("utm_forward: n NULL", [](World &) {
        const ct_utm z = {17, 0};
        int64_t e;
        return ct_utm_forward(&z, 0, 0, &e, nullptr);
    });
    null_arg("utm_factors: zone NULL", [](World &) {
        int64_t g, k;
        return ct_utm_factors(nullptr, 0, 0, &g, &k);
    });
    null_arg("utm_factors: k NULL", [](World &) {
        const ct_utm z = {17, 0};
        int64_t g;
        return ct_utm_factors(&z, 0, 0, &g, nullptr);
    });
    null_arg("utm_inverse: zone NULL", [](World &) {
        int64_t lat, lon;
        return ct_utm_inverse(nullptr, 500000000000000, 0, &lat, &lon);
    });
    null_arg("utm_inverse: lon NULL", [](World &) {
        const ct_utm z = {17, 0};
        int64_t lat;
        return ct_utm_inverse(&z, 500000000000000, 0, &lat, nullptr);
    });
    null_arg("geoid_at: grid NULL", [](World &) {
        int64_t n;
        return ct_geoid_at(nullptr, 0, 0, &n);
    });
    null_arg("package_geoid: pkg NULL", [](World &w) {
        int64_t n;
        return ct_package_geoid(nullptr, w.a[0], w.a[1], &n);
    });
    null_arg("wgs84_from_ecef: lat NULL", [](World &) {
        const int64_t x[3] = {INT64_C(6378137000000000), 0, 0};
        int64_t lon, h;
        return ct_wgs84_from_ecef(x, nullptr, &lon, &h);
    });
    null_arg("wgs84_from_ecef: lon NULL", [](World &) {
        const int64_t x[3] = {INT64_C(6378137000000000), 0, 0};
        int64_t lat, h;
        return ct_wgs84_from_ecef(x, &lat, nullptr, &h);
    });
    null_arg("wgs84_from_ecef: h NULL", [](World &) {
        const int64_t x[3] = {INT64_C(6378137000000000), 0, 0};
        int64_t lat, lon;
        return ct_wgs84_from_ecef(x, &lat, &lon, nullptr);
    });
    null_arg("tileset_open: manifest NULL", [](World &) {
        ct_tileset ts;
        ct_tile_slot s[1];
        return ct_tileset_open(&ts, nullptr, 64, s, 1, nullptr, nullptr);
    });
    // ---- ranges of geolocation's inputs
    add("geolocate: refraction k below -2", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {CT_EFFECT_REFRACTION | CT_EFFECT_CURVATURE, -3 * 65536, 0, 0, nullptr};
        ct_geo g;
        return ct_geolocate(&w.p, &w.cam, &w.pose, CT_METHOD_DIRECTIONAL, &fx, 32 << 16, 24 << 16, &g);
    });
    // (east and north cannot leave the grid's range on a 30 m grid: 2^61 nm
    // is 2^42 Q16 cells there, inside CT_MAX_ORIGIN_Q16; such a camera's
    // rays miss)
    add("geolocate: camera 2^61 nm up", CT_ERR_RAY, [](World &w) -> ct_status {
        int32_t q[4];
        ct_pose far;
        if (ct_quat_from_ypr(0, dem_cases::deg_q61(-60), 0, q) != CT_OK ||
            ct_pose_from_map(&far, w.pose.e_nm, w.pose.n_nm, INT64_C(1) << 61, q) != CT_OK)
            return CT_ERR_INTERNAL;  // not the case under test: fails it
        ct_geo g;
        return ct_geolocate(&w.p, &w.cam, &far, CT_METHOD_DIRECTIONAL, nullptr, 32 << 16, 24 << 16, &g);
    });
    struct Tol {
        const char *name;
        int32_t k;
        int64_t radius, tol;
    };
    for (const Tol &t : {Tol{"effects_for_tolerance: k beyond 2", 3 * 65536, 0, 1000000},
                         Tol{"effects_for_tolerance: k below -2", -3 * 65536, 0, 1000000},
                         Tol{"effects_for_tolerance: radius below 2^40 nm", CT_REFRACTION_K_STD_Q16, 1000, 1000000},
                         Tol{"effects_for_tolerance: radius beyond 2^54 nm", CT_REFRACTION_K_STD_Q16,
                             (INT64_C(1) << 54) + 1, 1000000},
                         Tol{"effects_for_tolerance: negative tolerance", CT_REFRACTION_K_STD_Q16, 0, -1}})
        add(t.name, CT_ERR_EFFECTS, [t](World &w) {
            ct_effects_choice ch;
            return ct_effects_for_tolerance(&w.p, &w.cam, &w.pose, t.k, t.radius, t.tol, &ch);
        });
    add("effects_for_tolerance: camera never set up", CT_ERR_ARG, [](World &w) {
        ct_camera c;
        std::memset(&c, 0, sizeof c);
        ct_effects_choice ch;
        return ct_effects_for_tolerance(&w.p, &c, &w.pose, CT_REFRACTION_K_STD_Q16, 0, 1000000, &ch);
    });
    add("effects_for_tolerance: pose never set up", CT_ERR_ARG, [](World &w) {
        ct_pose q;
        std::memset(&q, 0, sizeof q);
        ct_effects_choice ch;
        return ct_effects_for_tolerance(&w.p, &w.cam, &q, CT_REFRACTION_K_STD_Q16, 0, 1000000, &ch);
    });
    // the chord for the true Earth (curvature chosen, radius 0, a UTM
    // package) is never below the default, whose pieces it proves; the
    // sphere's (a radius given, or a package beyond the UTM codes) may be
    // finer: at tolerance 0 nothing is left for it (2^10 nm)
    add("effects_for_tolerance: the true Earth's chord at least 1 mm, the sphere's finer", CT_OK,
        [](World &w) -> ct_status {
            ct_package q = w.p;
            q.epsg = 0x80000000u + 32617u;
            int floored = 0;
            for (int64_t tol : {INT64_C(0), INT64_C(1000000), INT64_C(100000000)}) {
                ct_effects_choice te, sp, off;
                if (ct_effects_for_tolerance(&w.p, &w.cam, &w.pose, CT_REFRACTION_K_STD_Q16, 0, tol, &te) != CT_OK ||
                    ct_effects_for_tolerance(&w.p, &w.cam, &w.pose, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM, tol,
                                             &sp) != CT_OK ||
                    ct_effects_for_tolerance(&q, &w.cam, &w.pose, CT_REFRACTION_K_STD_Q16, 0, tol, &off) != CT_OK)
                    return CT_ERR_INTERNAL;
                const int64_t want = (te.flags & CT_EFFECT_CURVATURE) != 0u
                                         ? std::max<int64_t>(sp.chord_nm, CT_EFFECTS_CHORD_NM)
                                         : sp.chord_nm;
                if (te.flags != sp.flags || off.chord_nm != sp.chord_nm || te.chord_nm != want)
                    return CT_ERR_INTERNAL;
                floored += te.chord_nm != sp.chord_nm;
            }
            return floored > 0 ? CT_OK : CT_ERR_INTERNAL;
        });
    // ---- a bend's ranges (ct_bend): each alone
    struct Bend {
        const char *name;
        ct_bend bd;
    };
    for (const Bend &b : {Bend{"trace_bent: coefficient below -4", {-4 * 65536 - 1, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u}},
                          Bend{"trace_bent: coefficient beyond 4", {4 * 65536 + 1, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u}},
                          Bend{"trace_bent: radius beyond 2^54", {57016, (INT64_C(1) << 54) + 1, CT_EFFECTS_CHORD_NM, 0u}},
                          Bend{"trace_bent: chord below 2^10", {57016, CT_EARTH_RADIUS_NM, (INT64_C(1) << 10) - 1, 0u}},
                          Bend{"trace_bent: chord beyond 2^50", {57016, CT_EARTH_RADIUS_NM, (INT64_C(1) << 50) + 1, 0u}},
                          Bend{"trace_bent: unknown flag", {57016, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 2u}}})
        add(b.name, CT_ERR_ARG, [b](World &w) {
            ct_hit h;
            return ct_trace_bent(&w.p, &w.ray, &b.bd, CT_METHOD_DIRECTIONAL, &h);
        });
    add("trace_bent: origin beyond CT_MAX_ORIGIN_Q16", CT_ERR_RAY, [](World &w) {
        const ct_bend bd = {57016, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u};
        ct_ray r = w.ray;
        r.z_q16 = CT_MAX_ORIGIN_Q16 + 1;
        ct_hit h;
        return ct_trace_bent(&w.p, &r, &bd, CT_METHOD_DIRECTIONAL, &h);
    });
    // ---- the frames' ranges, one axis at a time
    struct Pt {
        const char *name;
        ct_status want;
        int64_t v[3];
        bool to_map;
    };
    const int64_t big60 = (INT64_C(1) << 60) + 1, at60 = INT64_C(1) << 60, big61 = (INT64_C(1) << 61) + 1;
    for (const Pt &q : {Pt{"grid_to_map: x beyond 2^60", CT_ERR_RANGE, {big60, 0, 0}, true},
                        Pt{"grid_to_map: y beyond 2^60", CT_ERR_RANGE, {0, big60, 0}, true},
                        Pt{"grid_to_map: z beyond 2^60", CT_ERR_RANGE, {0, 0, big60}, true},
                        Pt{"grid_to_map: x 2^60, e beyond 2^62 nm", CT_ERR_RANGE, {at60, 0, 0}, true},
                        Pt{"grid_to_map: y 2^60, n beyond 2^62 nm", CT_ERR_RANGE, {0, at60, 0}, true},
                        Pt{"grid_to_map: z 2^60, h beyond 2^62 nm", CT_ERR_RANGE, {0, 0, at60}, true},
                        Pt{"map_to_grid: e beyond 2^61", CT_ERR_RANGE, {big61, 0, 0}, false},
                        Pt{"map_to_grid: n beyond 2^61", CT_ERR_RANGE, {0, big61, 0}, false},
                        Pt{"map_to_grid: h beyond 2^61", CT_ERR_RANGE, {0, 0, big61}, false}})
        add(q.name, q.want, [q](World &w) {
            int64_t o[3];
            return q.to_map ? ct_grid_to_map(&w.p, q.v[0], q.v[1], q.v[2], &o[0], &o[1], &o[2])
                            : ct_map_to_grid(&w.p, q.v[0], q.v[1], q.v[2], &o[0], &o[1], &o[2]);
        });
    add("ray_from_map: dn beyond 2^40", CT_ERR_RAY, [](World &w) {
        ct_ray r;
        return ct_ray_from_map(&w.p, w.a[0], w.a[1], w.a[2], 0, (INT64_C(1) << 40) + 1, 0, &r);
    });
    add("ray_from_map: dh beyond 2^40", CT_ERR_RAY, [](World &w) {
        ct_ray r;
        return ct_ray_from_map(&w.p, w.a[0], w.a[1], w.a[2], 0, 0, (INT64_C(1) << 40) + 1, &r);
    });
    add("ray_from_map: origin beyond 2^61 nm", CT_ERR_RAY, [](World &w) {
        ct_ray r;
        return ct_ray_from_map(&w.p, (INT64_C(1) << 61) + 1, w.a[1], w.a[2], 1, 0, 0, &r);
    });
    // ---- lines of sight: effects and ranges
    add("los: refraction alone (c < 0: not offered)", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM, 0, nullptr};
        ct_hit h;
        return ct_los(&w.p, w.a, w.b, &fx, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    add("los: unknown effect flag", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {0x80u, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
        ct_hit h;
        return ct_los(&w.p, w.a, w.b, &fx, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    add("los: B beyond the grid's height range", CT_ERR_RAY, [](World &w) {
        const int64_t hb[3] = {w.b[0], w.b[1], (INT64_C(1) << 61) - 1};
        ct_hit h;
        return ct_los(&w.p, w.a, hb, nullptr, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    add("los: A beyond the grid's height range", CT_ERR_RAY, [](World &w) {
        const int64_t ha[3] = {w.a[0], w.a[1], (INT64_C(1) << 61) - 1};
        ct_hit h;
        return ct_los(&w.p, ha, w.b, nullptr, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    add("los: the sphere from 2,000 km beside the tile (no lowered model)", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {CT_EFFECT_CURVATURE, 0, CT_EARTH_RADIUS_NM, 0, nullptr};
        const int64_t far[3] = {w.a[0] + INT64_C(2000000000000000), w.a[1], w.a[2]};
        ct_hit h;
        return ct_los(&w.p, far, w.b, &fx, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    add("los: the sphere from 2,000 km north of the tile (no lowered model)", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {CT_EFFECT_CURVATURE, 0, CT_EARTH_RADIUS_NM, 0, nullptr};
        const int64_t far[3] = {w.a[0], w.a[1] + INT64_C(2000000000000000), w.a[2]};
        ct_hit h;
        return ct_los(&w.p, far, w.b, &fx, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    add("los: the sphere from 2,000 km south of the tile (no lowered model)", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {CT_EFFECT_CURVATURE, 0, CT_EARTH_RADIUS_NM, 0, nullptr};
        const int64_t far[3] = {w.a[0], w.a[1] - INT64_C(2000000000000000), w.a[2]};
        ct_hit h;
        return ct_los(&w.p, far, w.b, &fx, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    // posts 2 km apart (2^40 nm and more): beyond the lowered model's range
    add("los: the sphere over 2 km posts (no lowered model)", CT_ERR_EFFECTS, [](World &w) -> ct_status {
        static dem_cases::Case coarse;
        static ct_package q;
        if (coarse.pkg.empty()) {
            ct_host::Terrain t = w.c.t;
            t.geo.posting_e = 2000.0;
            t.geo.posting_n = -2000.0;
            coarse = dem_cases::make_case("coarse", t, 8, 2);
            if (ct_package_open(&q, coarse.pkg.data(), coarse.pkg.size()) != CT_OK) return CT_ERR_INTERNAL;
        }
        int64_t a[3], b[3];
        (void)ct_grid_to_map(&q, 12 << 16, 10 << 16, ((int64_t)q.hmax + 100) << 16, &a[0], &a[1], &a[2]);
        (void)ct_grid_to_map(&q, 3 << 16, 4 << 16, (int64_t)q.hmin << 16, &b[0], &b[1], &b[2]);
        const ct_effects fx = {CT_EFFECT_CURVATURE, 0, CT_EARTH_RADIUS_NM, 0, nullptr};
        ct_hit h;
        if (ct_los(&q, a, b, nullptr, 0, CT_METHOD_DIRECTIONAL, &h) < 0) return CT_ERR_INTERNAL;  // straight: fine
        return ct_los(&q, a, b, &fx, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    add("los: the true Earth from beyond the zone", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {CT_EFFECT_CURVATURE, 0, 0, 0, nullptr};
        const int64_t far[3] = {w.a[0] + INT64_C(3000000000000000), w.a[1], w.a[2]};
        ct_hit h;
        return ct_los(&w.p, far, w.b, &fx, 0, CT_METHOD_DIRECTIONAL, &h);
    });
    add("locate_inverse: unknown effect flag", CT_ERR_EFFECTS, [](World &w) {
        const ct_effects fx = {CT_EFFECT_CURVATURE | 0x80u, 0, 0, 0, nullptr};
        int64_t u, vv;
        uint32_t vis;
        ct_hit h;
        return ct_locate_inverse(&w.p, &w.cam, &w.pose, &fx, w.b, 0, &u, &vv, &vis, &h);
    });
    return v;
}

void test_table()
{
    World *w = world();
    TEST_ASSERT(w != nullptr);
    int bad = 0;
    const std::vector<Case> cs = cases();
    for (const Case &c : cs) {
        const ct_status got = c.call(*w);
        const char *gn = "?", *wn = "?";
        (void)ct_status_name(got, &gn);
        (void)ct_status_name(c.want, &wn);
        if (got != c.want) {
            std::printf("  %-48s got %s (%d), want %s (%d)\n", c.name, gn, (int)got, wn, (int)c.want);
            bad++;
        } else if (std::getenv("CT_TEST_VERBOSE")) {
            std::printf("  %-48s %s\n", c.name, gn);
        }
    }
    std::printf("  %zu named cases, %d with another status\n", cs.size(), bad);
    TEST_ASSERT_EQUAL_INT(0, bad);
}

}  // namespace

int main()
{
    TEST_BEGIN("test_api_args");
    RUN_TEST(test_table);
    return TEST_END();
}
