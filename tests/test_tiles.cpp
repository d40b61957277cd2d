// test_tiles.cpp -- tile sets (lib/src/tiles.c, host_tools/package/tileset.cpp).
//
//  - seams: seeded rays over DEMs cut into tiles (the fixture mirror-tiled,
//    generated adversarial DEMs), plus rays built to run along seams,
//    through tile corners and grazing across seams: every method's hit over
//    the tile set is the merged package's bit for bit (status, grid and map
//    position, t, cell), the methods agree, and the merged result is judged
//    against the long-double reference (zero wrong-surface results);
//  - caches of 1, 2 and all slots give the same hits, with the loads
//    counted; tiles the ray passes high above are not loaded;
//  - missing and corrupt tiles (no tile, a loader failure, a flipped byte,
//    a truncated tile, a tile of another place or CRS swapped in with its
//    manifest entry): CT_NO_DATA where the ray enters that tile, never a hit
//    beyond it, nothing read after it; rays that stop before it unchanged;
//  - the manifest's checks; geolocation over a set equals the merged
//    package's (straight, on a sphere, on the true Earth with the exact and
//    the fitted map, refraction alone: the polyline); the published
//    iteration bound.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include <malloc.h>
#include <unistd.h>

#include <atomic>
#include <new>

#include "bend.h"
#include "conetrace.h"
#include "dem_cases.hpp"
#include "harness.h"
#include "judge.hpp"
#include "le.hpp"
#include "terrain.hpp"
#include "tiles.h"
#include "tileset.hpp"
#include "vdatum.hpp"

namespace {

using ct_host::TileSetBytes;

// Tiles in memory: the loader the tests hand the library.
struct Mem {
    const TileSetBytes *b = nullptr;
    std::map<size_t, std::vector<uint8_t>> replace;  // tile k served as these bytes
    long fail = -1;                                  // tile the loader refuses
    long no_bytes = -1;                              // tile it says CT_OK for but gives no bytes
    bool copy = true;                                // into the slot (else zero copy)
    std::vector<long> calls;                         // per tile
};

ct_status mem_loader(void *user, uint32_t col, uint32_t row, uint8_t *buf, size_t cap, const uint8_t **bytes,
                     size_t *len)
{
    Mem *m = static_cast<Mem *>(user);
    const size_t k = (size_t)row * m->b->grid.tiles_x + col;
    m->calls[k]++;
    if ((long)k == m->fail) return CT_ERR_ARG;
    if ((long)k == m->no_bytes) {
        *bytes = nullptr;
        *len = 0;
        return CT_OK;
    }
    auto it = m->replace.find(k);
    const std::vector<uint8_t> &v = it != m->replace.end() ? it->second : m->b->tiles[k];
    if (m->copy) {
        if (v.size() > cap) return CT_ERR_ARG;
        std::memcpy(buf, v.data(), v.size());
        *bytes = buf;
    } else {
        *bytes = v.data();
    }
    *len = v.size();
    return CT_OK;
}

// A tile set over Mem with `nslots` slots (their buffers sized for the
// largest tile).
struct Set {
    Mem mem;
    std::vector<ct_tile_slot> slots;
    std::vector<std::vector<uint8_t>> bufs;
    ct_tileset ts{};
    ct_status open(const TileSetBytes &b, int nslots, const std::vector<uint8_t> *manifest = nullptr)
    {
        mem.b = &b;
        mem.calls.assign(b.tiles.size(), 0);
        size_t cap = 0;
        for (const auto &t : b.tiles) cap = std::max(cap, t.size());
        for (const auto &kv : mem.replace) cap = std::max(cap, kv.second.size());
        slots.assign((size_t)nslots, ct_tile_slot{});
        bufs.assign((size_t)nslots, std::vector<uint8_t>(cap));
        for (int k = 0; k < nslots; ++k) {
            slots[k].buf = bufs[k].data();
            slots[k].cap = cap;
        }
        const std::vector<uint8_t> &m = manifest ? *manifest : b.manifest;
        return ct_tileset_open(&ts, m.data(), m.size(), slots.data(), (uint32_t)nslots, mem_loader, &mem);
    }
};

// A pinhole camera of w x h pixels, focal length f pixels, principal point
// (cx2 / 2, cy2 / 2) pixels.
ct_status pinhole(ct_camera *cam, uint32_t w, uint32_t h, int64_t f, int64_t cx2, int64_t cy2)
{
    ct_lens lens{};
    lens.model = CT_LENS_PINHOLE;
    lens.width = w;
    lens.height = h;
    lens.fx_q32 = lens.fy_q32 = f << 32;
    lens.cx_q32 = cx2 << 31;
    lens.cy_q32 = cy2 << 31;
    return ct_camera_init(cam, &lens);
}

bool same_hit(ct_status sa, const ct_hit &a, ct_status sb, const ct_hit &b)
{
    if (sa != sb) return false;
    if (sa != CT_HIT && sa != CT_HIT_VOID) return true;
    return a.x_q16 == b.x_q16 && a.y_q16 == b.y_q16 && a.z_q16 == b.z_q16 && a.t_q26 == b.t_q26 &&
           a.cell_x == b.cell_x && a.cell_y == b.cell_y && a.e_nm == b.e_nm && a.n_nm == b.n_nm && a.h_nm == b.h_nm;
}

// Rays built for the seams of grid g on terrain t: along a seam (exactly on
// a seam line, descending slowly), through a tile corner post, grazing
// across a seam at a random angle.
// (lo, hi: the terrain's lowest and highest codes, dem_cases::minmax)
ct_ray seam_ray(const ct_host::Terrain &t, const ct_host::TileGrid &g, int kind, ct_rng *r, double lo, double hi)
{
    const int sx = g.tiles_x > 1 ? (int)ct_rng_range(r, 1, g.tiles_x - 1) : 0;
    const int sy = g.tiles_y > 1 ? (int)ct_rng_range(r, 1, g.tiles_y - 1) : 0;
    const double seam_x = g.first_col(sx), seam_y = g.first_row(sy);
    double d[3];
    switch (kind) {
    case 0: {  // along a seam line (x or y constant), either way
        const bool along_x = ct_rng_u64(r) & 1;
        const double el = -(ct_rng_unit(r) * 3) * M_PI / 180;
        const int sg = (ct_rng_u64(r) & 1) ? 1 : -1;
        dem_cases::metric_dir(t, along_x ? (sg > 0 ? 0 : M_PI) : (sg > 0 ? M_PI / 2 : -M_PI / 2), el, d);
        double x = ct_rng_unit(r) * (t.width - 1), y = ct_rng_unit(r) * (t.height - 1);
        if (along_x) {
            d[1] = 0;
            y = seam_y;
        } else {
            d[0] = 0;
            x = seam_x;
        }
        const double s = dem_cases::surf(t, x, y);
        return dem_cases::to_ray(x, y, s + ct_rng_unit(r) * (hi + 1 - s), d);
    }
    case 1: {  // exactly through a post on a seam (a tile corner, or one on a seam line), from up to 60 cells back
        const int pick = (int)ct_rng_range(r, 0, 2);
        const int i = pick == 1 ? (int)ct_rng_range(r, 0, t.width - 1) : (int)seam_x;
        const int j = pick == 2 ? (int)ct_rng_range(r, 0, t.height - 1) : (int)seam_y;
        int64_t D[3] = {ct_rng_range(r, -(1 << 20), 1 << 20), ct_rng_range(r, -(1 << 20), 1 << 20),
                        ct_rng_range(r, -(1 << 17), 1 << 8)};
        if (ct_rng_range(r, 0, 2) == 0) D[1] = ct_rng_range(r, 0, 1) ? D[0] : -D[0];  // diagonal
        if (D[0] == 0 && D[1] == 0) D[0] = 1 << 19;
        const int64_t k = ct_rng_range(r, 1, 60);
        const int64_t dz[4] = {0, 1, -1, ct_rng_range(r, 1, 40000)};
        ct_ray ray;
        ray.x_q16 = (int64_t)i * 65536 - k * D[0];
        ray.y_q16 = (int64_t)j * 65536 - k * D[1];
        ray.z_q16 = (int64_t)t.at(i, j) * 65536 + dz[ct_rng_range(r, 0, 3)] - k * D[2];
        ray.dx = D[0];
        ray.dy = D[1];
        ray.dz = D[2];
        return ray;
    }
    default: {  // grazing across a seam: start near one, skim the surface
        const bool vert = ct_rng_u64(r) & 1;
        double x = vert ? seam_x + (ct_rng_unit(r) - 0.5) * 6 : ct_rng_unit(r) * (t.width - 1);
        double y = vert ? ct_rng_unit(r) * (t.height - 1) : seam_y + (ct_rng_unit(r) - 0.5) * 6;
        x = std::clamp(x, 0.0, t.width - 1.0);
        y = std::clamp(y, 0.0, t.height - 1.0);
        const double az = ct_rng_unit(r) * 2 * M_PI;
        dem_cases::metric_dir(t, az, -(0.001 + 0.8 * ct_rng_unit(r)) * M_PI / 180, d);
        const double s = dem_cases::surf(t, x, y);
        return dem_cases::to_ray(x, y, s + 0.01 + ct_rng_unit(r) * 2, d);
    }
    }
}

// Tiles a ray visits before its result: sampled along its path in the box.
int tiles_visited(const ct_host::TileGrid &g, const ct_prepared &pr, ct_status s, const ct_hit &h)
{
    const double tend = (s == CT_HIT || s == CT_HIT_VOID) ? h.t_q26 / 67108864.0 : (double)pr.tend_n / pr.tend_d;
    int last = -1, n = 0;
    for (int k = 0; k <= 400; ++k) {
        const double tt = tend * k / 400.0;
        const double x = (pr.ox + tt * pr.dx) / 65536.0, y = (pr.oy + tt * pr.dy) / 65536.0;
        const int a = std::min(g.tiles_x - 1, std::max(0, (int)(x / (g.P - 1)))),
                  b = std::min(g.tiles_y - 1, std::max(0, (int)(y / (g.P - 1))));
        if (b * g.tiles_x + a != last) {
            last = b * g.tiles_x + a;
            n++;
        }
    }
    return n;
}

struct SeamStats {
    long rays = 0, hits = 0, nodata = 0, wrong = 0, tangent = 0, differ = 0;
    long by_tiles[5] = {0, 0, 0, 0, 0};  // 1, 2, 3, 4, 5+ tiles visited
};

// n rays (families and seam rays) on terrain t cut into tiles of P posts,
// package options o: every method's result over the set (`slots` slots)
// against the merged package's.
void check_seams(const char *name, const ct_host::Terrain &t, const ct_host::BuildOptions &o, int P, long n,
                 int slots, SeamStats *st)
{
    const std::vector<uint8_t> merged = ct_host::build_package(t, o);
    const TileSetBytes tb = ct_host::build_tileset(t, o, P, 0);
    ct_package mp;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&mp, merged.data(), merged.size()));
    Set set;
    TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, slots));
    if (ct_harness_g.current_failed) return;
    // the frame is the merged package's grid
    TEST_ASSERT(set.ts.frame.cells_x == mp.cells_x && set.ts.frame.cells_y == mp.cells_y &&
                set.ts.frame.hmin == mp.hmin && set.ts.frame.hmax == mp.hmax &&
                set.ts.frame.origin_e_nm == mp.origin_e_nm && set.ts.frame.origin_n_nm == mp.origin_n_nm &&
                set.ts.frame.zshift_max == mp.zshift_max);
    const ref::Dem d = dem_cases::ref_dem(t);
    uint32_t levels = 0;
    for (const auto &tile : tb.tiles) {
        ct_package tp;
        if (!tile.empty() && ct_package_open(&tp, tile.data(), tile.size()) == CT_OK) levels = std::max(levels, tp.levels);
    }
    const uint32_t bound_cells = CT_WCET_SET_ITERS(tb.grid.tiles_x, tb.grid.tiles_y, CT_WCET_CELL_ITERS(P - 1, P - 1));
    const uint32_t bound_hier =
        CT_WCET_SET_ITERS(tb.grid.tiles_x, tb.grid.tiles_y, CT_WCET_HIER_ITERS(P - 1, P - 1, levels));
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 104729u + (uint64_t)P * 31u + (uint64_t)t.width);
    int reported = 0;
    double lo, hi;
    dem_cases::minmax(t, &lo, &hi);
    for (long k = 0; k < n; ++k) {
        // two thirds from the ray families, a third built for the seams
        const ct_ray ray = (k % 3 == 2)
                               ? seam_ray(t, tb.grid, (int)((k / 3) % 3), &rng, lo, hi)
                               : dem_cases::make_ray(t, (dem_cases::Family)(k % dem_cases::FAMILY_COUNT), &rng, lo, hi);
        ct_hit hm[4], hs[4];
        ct_status sm[4], ss[4];
        for (int m = 0; m < 4; ++m) {
            sm[m] = ct_trace(&mp, &ray, (ct_method)m, &hm[m]);
            ss[m] = ct_tileset_trace(&set.ts, &ray, (ct_method)m, &hs[m]);
            const bool same = same_hit(sm[m], hm[m], ss[m], hs[m]) && same_hit(sm[m], hm[m], sm[0], hm[0]);
            if (!same) {
                st->differ++;
                if (reported++ < 5)
                    std::printf("  DIFFER %s P=%d ray %ld method %d: merged %d (%lld, %lld, %lld) t %lld cell %d,%d; "
                                "set %d (%lld, %lld, %lld) t %lld cell %d,%d\n",
                                name, P, k, m, sm[m], (long long)hm[m].x_q16, (long long)hm[m].y_q16,
                                (long long)hm[m].z_q16, (long long)hm[m].t_q26, hm[m].cell_x, hm[m].cell_y, ss[m],
                                (long long)hs[m].x_q16, (long long)hs[m].y_q16, (long long)hs[m].z_q16,
                                (long long)hs[m].t_q26, hs[m].cell_x, hs[m].cell_y);
            }
            const uint32_t bound = m == CT_METHOD_HIERARCHICAL ? bound_hier : bound_cells;
            TEST_ASSERT_MSG(hs[m].iters <= bound, "%s: %u iterations above the bound %u", name, hs[m].iters, bound);
        }
        st->rays++;
        if (ss[0] == CT_HIT || ss[0] == CT_HIT_VOID) st->hits++;
        if (ss[0] == CT_NO_DATA) st->nodata++;
        ct_prepared pr;
        if (ct_ray_prepare(&mp, &ray, &pr) == CT_OK) {
            st->by_tiles[std::min(5, tiles_visited(tb.grid, pr, ss[0], hs[0])) - 1]++;
            ref::Hit rh;
            double err = 0;
            const judge::Verdict v = judge::judge(d, pr, ss[3], hs[3], &rh, &err);
            if (v == judge::TANGENT) st->tangent++;
            if (v == judge::WRONG) {
                st->wrong++;
                if (reported++ < 5)
                    std::printf("  WRONG %s P=%d ray %ld: set status %d t %lld; reference %d t %.9Lf\n", name, P, k,
                                ss[3], (long long)hs[3].t_q26, rh.status, rh.t);
            }
        }
    }
}

void test_seams()
{
    const long per = (long)(12000 * ct_test_scale());
    SeamStats st;
    {
        // the fixture mirror-tiled to 600 x 520 posts, 4 x 4 and 10 x 9 tiles
        const ct_host::Terrain t = dem_cases::mirror_tiled(dem_cases::real_terrain(), 600, 520);
        ct_host::BuildOptions o;
        o.sectors = 24;
        o.reduce = 3;
        check_seams("fixture", t, o, 151, 2 * per, 16, &st);
        o.sectors = 8;
        o.reduce = 1;
        check_seams("fixture", t, o, 61, per, 4, &st);
    }
    const auto cases = dem_cases::adversarial_cases();
    for (const auto &cs : cases) {
        // tiles of about a quarter of the DEM (2 x 2 .. 4 x 4 tiles)
        const int P = std::max(5, std::min(cs.t.width, cs.t.height) / 3);
        check_seams(cs.name.c_str(), cs.t, cs.opt, P, per, 3, &st);
        if (ct_harness_g.current_failed) return;
    }
    {
        // the smallest tiles: 2 and 3 posts a side (a seam at every cell or
        // every other one), 16 slots for hundreds of tiles
        const ct_host::Terrain t = dem_cases::mirror_tiled(dem_cases::real_terrain(), 41, 37);
        ct_host::BuildOptions o;
        o.sectors = 8;
        o.reduce = 1;
        check_seams("fixture, P = 2", t, o, 2, per / 4, 16, &st);
        check_seams("fixture, P = 3", t, o, 3, per / 4, 16, &st);
        if (ct_harness_g.current_failed) return;
    }
    std::printf("  seams: %ld rays x 4 methods, %ld hits, %ld tangencies; tiles visited 1/2/3/4/5+: %ld/%ld/%ld/%ld/%ld; "
                "differ from the merged package %ld, wrong %ld, no data %ld\n",
                st.rays, st.hits, st.tangent, st.by_tiles[0], st.by_tiles[1], st.by_tiles[2], st.by_tiles[3],
                st.by_tiles[4], st.differ, st.wrong, st.nodata);
    TEST_ASSERT(st.rays >= (long)(100000 * ct_test_scale()));
    TEST_ASSERT_MSG(st.differ == 0, "%ld results differ from the merged package's", st.differ);
    TEST_ASSERT_MSG(st.wrong == 0, "%ld wrong-surface results", st.wrong);
    TEST_ASSERT(st.nodata == 0);
    TEST_ASSERT(st.by_tiles[0] > 0 && st.by_tiles[1] > 0 && st.by_tiles[3] + st.by_tiles[4] > 0);
}

// Rays that touch the surface exactly on a seam (f = 0 at the seam point,
// above the surface everywhere before it).  Every method, over the set,
// reports the merged package's hit, and that hit is the touch point itself
// (exact: the ray's point at t = 1 is a lattice point of Q16, at code 50).
// The touch is found by the tile the ray leaves: its last cell's test
// includes the exit face, a cone jump or a mipmap skip ends strictly above
// the surface, and a tile passed over is one the ray stays strictly above;
// the next tile's own sign test decides only where tiles disagree on their
// seam posts (test_seam_disagree).
//  - terrain 0: flat at code 50; rays descending one code over 8 cells from
//    code 51 reach it on the seam line x = 10 or y = 10, from either side,
//    along x, along y, obliquely, and diagonally through the tile corner;
//  - terrain 1: code 10, except code 50 for x >= 10 or y >= 10 (a step up
//    exactly on the seams), the same rays;
//  - terrain 2: code 10, except the seam line x = 10 and the post row y = 5
//    at code 50; a horizontal ray at code 50 along y = 5.5 meets the
//    surface at one point only, (10, 5.5) on the seam, from either side.
void test_seam_touch()
{
    const int W = 21;
    const int64_t C = 65536;
    // (start x, start y, dx, dy): 8 cells of run to the seam point at t = 1
    const int64_t rays[][4] = {
        {2 * C, 5 * C + C / 2, 1 << 19, 0},        // along x, west to east onto x = 10
        {5 * C + C / 3, 2 * C, 0, 1 << 19},        // along y, south to north onto y = 10
        {2 * C, 2 * C, 1 << 19, 1 << 19},          // diagonal onto the tile corner (10, 10)
        {18 * C, 5 * C + C / 2, -(1 << 19), 0},    // east to west onto x = 10
        {2 * C, 7 * C + C / 4, 1 << 19, 3 << 16},  // oblique onto x = 10, across y = 10 before it
    };
    long touches = 0;
    for (int terrain = 0; terrain < 3; ++terrain) {
        std::vector<uint16_t> codes((size_t)W * W);
        for (int j = 0; j < W; ++j)
            for (int i = 0; i < W; ++i) {
                const bool high = terrain == 0   ? true
                                  : terrain == 1 ? (i >= 10 || j >= 10)
                                                 : (i == 10 || j == 5);
                codes[(size_t)j * W + (size_t)i] = (uint16_t)(high ? 50 : 10);
            }
        const ct_host::Terrain t = dem_cases::make_terrain(W, W, codes);
        for (int sectors : {1, 8, 24}) {
            ct_host::BuildOptions o;
            o.sectors = sectors;
            o.reduce = 1;
            const std::vector<uint8_t> merged = ct_host::build_package(t, o);
            const TileSetBytes tb = ct_host::build_tileset(t, o, 11, 0);
            TEST_ASSERT(tb.grid.tiles_x == 2 && tb.grid.tiles_y == 2);
            ct_package mp;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&mp, merged.data(), merged.size()));
            Set set;
            TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 4));
            if (ct_harness_g.current_failed) return;
            for (int k = 0; k < 5; ++k) {
                const int64_t *rr = rays[k];
                if (terrain == 2 && k != 0 && k != 3) continue;  // the others meet the row y = 5 first
                ct_ray ray;
                ray.x_q16 = rr[0];
                ray.y_q16 = rr[1];
                ray.z_q16 = (terrain == 2 ? 50 : 51) * C;
                ray.dx = rr[2];
                ray.dy = rr[3];
                ray.dz = terrain == 2 ? 0 : -C;
                const int64_t tx = rr[0] + rr[2], ty = rr[1] + rr[3];
                TEST_ASSERT(tx == 10 * C || ty == 10 * C);
                for (int m = 0; m < 4; ++m) {
                    ct_hit hm, hs;
                    const ct_status sm = ct_trace(&mp, &ray, (ct_method)m, &hm);
                    const ct_status ss = ct_tileset_trace(&set.ts, &ray, (ct_method)m, &hs);
                    TEST_ASSERT_MSG(sm == CT_HIT && ss == CT_HIT, "terrain %d N=%d ray %d method %d: merged %d, set %d",
                                    terrain, sectors, k, m, sm, ss);
                    TEST_ASSERT_MSG(same_hit(sm, hm, ss, hs),
                                    "terrain %d N=%d ray %d method %d: set (%lld, %lld, %lld) cell %d,%d, merged "
                                    "(%lld, %lld, %lld) cell %d,%d",
                                    terrain, sectors, k, m, (long long)hs.x_q16, (long long)hs.y_q16,
                                    (long long)hs.z_q16, hs.cell_x, hs.cell_y, (long long)hm.x_q16,
                                    (long long)hm.y_q16, (long long)hm.z_q16, hm.cell_x, hm.cell_y);
                    TEST_ASSERT_MSG(hs.x_q16 == tx && hs.y_q16 == ty && hs.z_q16 == 50 * C,
                                    "terrain %d N=%d ray %d method %d: hit (%lld, %lld, %lld), the touch is (%lld, "
                                    "%lld, %lld)",
                                    terrain, sectors, k, m, (long long)hs.x_q16, (long long)hs.y_q16,
                                    (long long)hs.z_q16, (long long)tx, (long long)ty, (long long)(50 * C));
                    if (ct_harness_g.current_failed) return;
                    touches++;
                }
            }
        }
    }
    TEST_ASSERT(touches == (5 + 5 + 2) * 3 * 4);
}

// Tiles that disagree on their shared seam posts (a set assembled from two
// builds, each tile vouched for by the manifest): tile (0, 0) has code 10
// everywhere, its seam column included; tile (1, 0) has code 50 on that
// column and beyond.  A horizontal ray at code 30 crosses tile (0, 0) above
// its surface and meets tile (1, 0)'s surface on the seam itself, where its
// own posts stand at 50 (f < 0 on the entry face): every method reports the
// hit there, on the seam point, in tile (1, 0)'s first cell -- each tile's
// terrain is its own, and the ray is first at or below one on the seam.
void test_seam_disagree()
{
    const int W = 21;
    const int64_t C = 65536;
    std::vector<uint16_t> low((size_t)W * W, 10), high((size_t)W * W, 10);
    for (int j = 0; j < W; ++j)
        for (int i = 10; i < W; ++i) high[(size_t)j * W + (size_t)i] = 50;
    const ct_host::Terrain ta = dem_cases::make_terrain(W, W, low), tb_ = dem_cases::make_terrain(W, W, high);
    for (int sectors : {1, 8, 24}) {
        ct_host::BuildOptions o;
        o.sectors = sectors;
        o.reduce = 1;
        TileSetBytes tb = ct_host::build_tileset(ta, o, 11, 0);
        TEST_ASSERT(tb.grid.tiles_x == 2 && tb.grid.tiles_y == 2);
        tb.tiles[1] = ct_host::build_package(ct_host::tile_terrain(tb_, tb.grid, 1, 0), o);  // tile (1, 0)
        tb.manifest = ct_host::make_manifest(tb_, tb.grid, o.reduce, o.sectors, tb.tiles);
        Set set;
        TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 4));
        if (ct_harness_g.current_failed) return;
        // along x from three starts, slightly north, two other lengths of
        // direction, and steeply north (y dominant: the seam's parameter is
        // no multiple of 2^-26)
        for (int k = 0; k < 6; ++k) {
            ct_ray ray;
            ray.x_q16 = k == 5 ? 9 * C : 2 * C + (k % 3) * (C / 4);
            ray.y_q16 = k == 5 ? C / 2 : 5 * C + C / 2 + k * 4099;
            ray.z_q16 = 30 * C;
            ray.dx = k == 3 ? 1 << 26 : k == 4 ? 3 << 24 : 1 << 19;
            ray.dy = k == 2 ? 1 << 14 : k == 5 ? 1 << 20 : 0;
            ray.dz = 0;
            // where the ray is on the seam line x = 10 (exact: dx divides the run)
            const int64_t run = 10 * C - ray.x_q16;
            TEST_ASSERT(run * ray.dy % ray.dx == 0);
            const int64_t sy = ray.y_q16 + run * ray.dy / ray.dx;
            for (int m = 0; m < 4; ++m) {
                ct_hit h;
                const ct_status st = ct_tileset_trace(&set.ts, &ray, (ct_method)m, &h);
                TEST_ASSERT_MSG(st == CT_HIT && h.x_q16 == 10 * C && h.y_q16 == sy && h.z_q16 == 30 * C &&
                                    h.cell_x == 10 && h.cell_y == (int32_t)(sy >> 16),
                                "N=%d ray %d method %d: status %d at (%lld, %lld, %lld) cell %d,%d; the seam point is "
                                "(%lld, %lld, %lld)",
                                sectors, k, m, st, (long long)h.x_q16, (long long)h.y_q16, (long long)h.z_q16,
                                h.cell_x, h.cell_y, (long long)(10 * C), (long long)sy, (long long)(30 * C));
                if (ct_harness_g.current_failed) return;
            }
        }
    }
}

// The same hits with 1, 2 and all slots, zero copy or not; loads counted.
void test_cache_sizes()
{
    const ct_host::Terrain t = dem_cases::mirror_tiled(dem_cases::real_terrain(), 400, 400);
    ct_host::BuildOptions o;
    o.sectors = 16;
    o.reduce = 2;
    const TileSetBytes tb = ct_host::build_tileset(t, o, 101, 0);
    TEST_ASSERT_EQUAL_INT(16, (int)tb.tiles.size());
    const std::vector<uint8_t> merged = ct_host::build_package(t, o);
    ct_package mp;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&mp, merged.data(), merged.size()));
    ct_rng rng;
    ct_rng_seed(&rng, 77);
    std::vector<ct_ray> rays;
    double lo, hi;
    dem_cases::minmax(t, &lo, &hi);
    for (int k = 0; k < 3000; ++k)
        rays.push_back(dem_cases::make_ray(t, (k & 1) ? dem_cases::GRAZING : dem_cases::OUTSIDE, &rng, lo, hi));
    uint32_t loads[3] = {0, 0, 0};
    const int nslots[3] = {1, 2, 16};
    for (int c = 0; c < 3; ++c) {
        Set set;
        set.mem.copy = c != 1;
        TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, nslots[c]));
        long differ = 0;
        for (const ct_ray &ray : rays) {
            ct_hit a, b;
            const ct_status sa = ct_trace(&mp, &ray, CT_METHOD_DIRECTIONAL, &a);
            const ct_status sb = ct_tileset_trace(&set.ts, &ray, CT_METHOD_DIRECTIONAL, &b);
            differ += !same_hit(sa, a, sb, b);
        }
        loads[c] = set.ts.loads;
        long calls = 0;
        for (long v : set.mem.calls) calls += v;
        std::printf("  cache %2d slots%s: %u loads for %zu rays (%.2f per ray), %u refused\n", nslots[c],
                    set.mem.copy ? "" : " (zero copy)", set.ts.loads, rays.size(), (double)set.ts.loads / rays.size(),
                    set.ts.refused);
        TEST_ASSERT_EQUAL_INT(0, (int)differ);
        TEST_ASSERT_EQUAL_INT((int)calls, (int)set.ts.loads);
        TEST_ASSERT_EQUAL_INT(0, (int)set.ts.refused);
    }
    TEST_ASSERT(loads[2] <= 16u);  // every tile at most once
    TEST_ASSERT(loads[0] >= loads[1] && loads[1] >= loads[2]);
    TEST_ASSERT(loads[0] > loads[2]);
}

// A ray far above the terrain crosses tiles without loading them.
void test_skips_tiles_above()
{
    const ct_host::Terrain t = dem_cases::adversarial_cases()[0].t;  // spikes 61 x 53
    ct_host::BuildOptions o;
    const TileSetBytes tb = ct_host::build_tileset(t, o, 16, 0);
    Set set;
    TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 2));
    // horizontal, just above the highest post: crosses every tile column
    double lo, hi, d[3];
    dem_cases::minmax(t, &lo, &hi);
    dem_cases::metric_dir(t, 0.0, 0.0, d);
    d[2] = 0;
    const ct_ray ray = dem_cases::to_ray(0.0, 20.5, hi + 0.5, d);
    ct_hit h;
    TEST_ASSERT_EQUAL_INT(CT_MISS, ct_tileset_trace(&set.ts, &ray, CT_METHOD_DIRECTIONAL, &h));
    TEST_ASSERT_EQUAL_INT(0, (int)set.ts.loads);
}

// Missing and corrupt tiles.
void test_missing_and_corrupt()
{
    const auto cases = dem_cases::adversarial_cases();
    const ct_host::Terrain &t = cases[1].t;  // walls and knives, 64 x 64
    ct_host::BuildOptions o = cases[1].opt;
    const int P = 22;                        // 3 x 3 tiles
    const TileSetBytes full = ct_host::build_tileset(t, o, P, 0);
    const std::vector<uint8_t> merged = ct_host::build_package(t, o);
    ct_package mp;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&mp, merged.data(), merged.size()));
    const size_t centre_tile = 4;  // tile (1, 1): the bad tile but in variant 17
    const ct_host::TileGrid &g = full.grid;
    // variants: 0 absent from the manifest, 1 the loader fails, 2 a flipped
    // byte, 3 truncated, 4 tile (0, 0) swapped in with its entry, 5 another
    // CRS, 6 another posting, 7 the origin one post north, 8 another r, 9
    // another N, 10 the posting north negated, 11 another height offset, 12
    // another height scale, 13 one post narrower, 14 one post shorter (each
    // vouched for by its entry: one field of the tile's place or values
    // differs from the set's), 15 tile (0, 0) served in its place (the
    // manifest unchanged: another CRC), 16 its entry's lowest code raised
    // by one, 17 the tallest code of the first tile's entry below the set's
    // tallest post raised by one, 18 the origin one post east, 19 the
    // loader says CT_OK but gives no bytes
    for (int variant = 0; variant < 20; ++variant) {
        TileSetBytes tb = full;
        Set set;
        size_t centre = centre_tile;
        if (variant == 17) {
            // the first tile below the set's tallest post (raising the
            // tallest entry would change the set's frame)
            const std::vector<uint8_t> &m = full.manifest;
            auto code = [&m](size_t at) { return (unsigned)(m[at] | m[at + 1] << 8); };
            for (centre = 0; centre + 1 < full.tiles.size() &&
                             code(CT_SET_HEADER_SIZE + centre * CT_SET_ENTRY_SIZE + 10) >= code(CT_SET_HDR_HMAX);
                 ++centre) {
            }
            TEST_ASSERT(code(CT_SET_HEADER_SIZE + centre * CT_SET_ENTRY_SIZE + 10) < code(CT_SET_HDR_HMAX));
        }
        if (variant == 0) {
            tb = ct_host::build_tileset(t, o, P, 0, [](int c, int r) { return c == 1 && r == 1; });
        } else if (variant == 1) {
            set.mem.fail = (long)centre;
        } else if (variant == 2) {
            std::vector<uint8_t> bad = full.tiles[centre];
            bad[bad.size() / 2] ^= 0x10;
            set.mem.replace[centre] = bad;
        } else if (variant == 3) {
            std::vector<uint8_t> bad = full.tiles[centre];
            bad.resize(bad.size() - 64);
            set.mem.replace[centre] = bad;
        } else if (variant == 19) {
            set.mem.no_bytes = (long)centre;
        } else if (variant == 15) {
            set.mem.replace[centre] = full.tiles[0];
        } else if (variant == 16 || variant == 17) {
            std::vector<uint8_t> &m = tb.manifest;
            const size_t e = CT_SET_HEADER_SIZE + centre * CT_SET_ENTRY_SIZE + (variant == 16 ? 8 : 10);
            const uint16_t code = (uint16_t)(m[e] | m[e + 1] << 8);
            ct_host::put16(m, e, code + 1);
            ct_host::put32(m, CT_HDR_CRC, 0);
            uint32_t crc = 0;
            ct_crc32(0, m.data(), m.size(), &crc);
            ct_host::put32(m, CT_HDR_CRC, crc);
        } else {
            // a valid package with the manifest rewritten to vouch for it
            std::vector<uint8_t> other;
            if (variant == 4) {
                other = full.tiles[0];
            } else {
                ct_host::Terrain tt = ct_host::tile_terrain(t, g, 1, 1);
                ct_host::BuildOptions oo = o;
                if (variant == 5) {
                    tt.geo.epsg = 32616;
                } else if (variant == 6) {
                    tt.geo.posting_e = 20.0;
                    tt.geo.posting_n = -20.0;
                } else if (variant == 7) {
                    tt.geo.origin_n_nm += (int64_t)(tt.geo.posting_n * 1e9);  // one post north
                    tt.geo.origin_n += tt.geo.posting_n;
                } else if (variant == 18) {
                    tt.geo.origin_e_nm += (int64_t)(tt.geo.posting_e * 1e9);  // one post east
                    tt.geo.origin_e += tt.geo.posting_e;
                } else if (variant == 8) {
                    oo.reduce = o.reduce == 1 ? 2 : 1;
                } else if (variant == 9) {
                    oo.sectors = o.sectors == 8 ? 4 : 8;
                } else if (variant == 10) {
                    tt.geo.posting_n = -tt.geo.posting_n;
                } else if (variant == 11) {
                    tt.height_offset_m += 1.0;
                } else if (variant == 12) {
                    tt.height_scale_m *= 2.0;
                } else {
                    // drop the last column (13) or row (14)
                    const int w = tt.width - (variant == 13), h = tt.height - (variant == 14);
                    std::vector<uint16_t> codes;
                    for (int j = 0; j < h; ++j)
                        for (int i = 0; i < w; ++i) codes.push_back(tt.at(i, j));
                    tt.codes = codes;
                    tt.width = w;
                    tt.height = h;
                    tt.void_post.clear();
                }
                other = ct_host::build_package(tt, oo);
            }
            set.mem.replace[centre] = other;
            std::vector<std::vector<uint8_t>> tiles = full.tiles;
            tiles[centre] = other;
            tb.manifest = ct_host::make_manifest(t, g, o.reduce, o.sectors, tiles);
        }
        TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 2));
        ct_rng rng;
        ct_rng_seed(&rng, 500 + variant);
        long nodata = 0, same = 0, inside = 0;
        const int col = (int)(centre % (size_t)g.tiles_x), row = (int)(centre / (size_t)g.tiles_x);
        const double x0 = g.first_col(col), x1 = g.first_col(col + 1), y0 = g.first_row(row), y1 = g.first_row(row + 1);
        double lo, hi;
        dem_cases::minmax(t, &lo, &hi);
        for (int k = 0; k < 4000; ++k) {
            const ct_ray ray = dem_cases::make_ray(t, (dem_cases::Family)(k % dem_cases::FAMILY_COUNT), &rng, lo, hi);
            ct_hit hm, hs;
            const ct_status sm = ct_trace(&mp, &ray, CT_METHOD_DIRECTIONAL, &hm);
            std::fill(set.mem.calls.begin(), set.mem.calls.end(), 0);
            const uint32_t refused0 = set.ts.refused;
            const ct_status ss = ct_tileset_trace(&set.ts, &ray, CT_METHOD_DIRECTIONAL, &hs);
            const bool hit_inside = (sm == CT_HIT || sm == CT_HIT_VOID) && hm.cell_x >= x0 && hm.cell_x < x1 &&
                                    hm.cell_y >= y0 && hm.cell_y < y1;
            inside += hit_inside;
            if (ss == CT_NO_DATA) {
                nodata++;
                // where it entered the bad tile: on or in its box, no later
                // than the merged hit, which is not before the tile
                const double hx = hs.x_q16 / 65536.0, hy = hs.y_q16 / 65536.0;
                TEST_ASSERT_MSG(hx >= x0 - 1e-4 && hx <= x1 + 1e-4 && hy >= y0 - 1e-4 && hy <= y1 + 1e-4,
                                "variant %d: no data reported at (%.4f, %.4f), off the tile", variant, hx, hy);
                TEST_ASSERT(hs.cell_x >= x0 && hs.cell_x < x1 && hs.cell_y >= y0 && hs.cell_y < y1);
                if (sm == CT_HIT || sm == CT_HIT_VOID) TEST_ASSERT(hs.t_q26 <= hm.t_q26);
                // nothing read after the bad tile: it was the last one asked for
                if (variant > 0) TEST_ASSERT_EQUAL_INT((int)refused0 + 1, (int)set.ts.refused);
            } else {
                TEST_ASSERT_MSG(same_hit(sm, hm, ss, hs), "variant %d ray %d: %d vs merged %d", variant, k, ss, sm);
                TEST_ASSERT_MSG(!hit_inside, "variant %d: a hit on the missing tile", variant);
                same++;
            }
            if (ct_harness_g.current_failed) return;
        }
        if (variant == 0) TEST_ASSERT_EQUAL_INT(0, (int)set.mem.calls[centre]);
        std::printf("  bad tile variant %d: %ld no data, %ld as merged (%ld merged hits on that tile, all no data)\n",
                    variant, nodata, same, inside);
        TEST_ASSERT(nodata >= inside && inside > 0);
    }
}

// A DEM with a patch of voids cut into 3 x 3 tiles: every ray's result as
// the merged package's, CT_HIT_VOID included (walked in a later tile too).
void test_voids()
{
    ct_host::Terrain t = dem_cases::make_terrain(43, 43, dem_cases::smooth(43, 43, 21, 1000, 20000), 0.25);
    t.void_post.assign(43 * 43, 0);
    for (int j = 10; j < 33; ++j)
        for (int i = 10; i < 33; ++i) t.void_post[(size_t)j * 43 + i] = (i + j) % 5 != 0;
    ct_host::BuildOptions o;
    o.sectors = 8;
    o.reduce = 2;
    const TileSetBytes tb = ct_host::build_tileset(t, o, 15, 0);
    const std::vector<uint8_t> merged = ct_host::build_package(t, o);
    ct_package mp;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&mp, merged.data(), merged.size()));
    Set set;
    TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 2));
    ct_rng rng;
    ct_rng_seed(&rng, 99);
    double lo, hi;
    dem_cases::minmax(t, &lo, &hi);
    long voids = 0;
    for (int k = 0; k < 6000; ++k) {
        const ct_ray ray = dem_cases::make_ray(t, (dem_cases::Family)(k % dem_cases::FAMILY_COUNT), &rng, lo, hi);
        for (int m = 0; m < CT_METHOD_COUNT; ++m) {
            ct_hit hm, hs;
            const ct_status sm = ct_trace(&mp, &ray, (ct_method)m, &hm);
            const ct_status ss = ct_tileset_trace(&set.ts, &ray, (ct_method)m, &hs);
            TEST_ASSERT_MSG(same_hit(sm, hm, ss, hs), "ray %d method %d: %d vs merged %d", k, m, ss, sm);
            voids += m == 0 && sm == CT_HIT_VOID;
        }
        if (ct_harness_g.current_failed) return;
    }
    std::printf("  voids: %ld of 6000 rays hit a void cell, as merged\n", voids);
    TEST_ASSERT(voids > 0);
}

void test_manifest_checks()
{
    const ct_host::Terrain t = dem_cases::adversarial_cases()[3].t;  // flat 40 x 33
    ct_host::BuildOptions o;
    o.sectors = 4;
    const TileSetBytes tb = ct_host::build_tileset(t, o, 12, 0);
    Set set;
    TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 1));
    auto restamp = [](std::vector<uint8_t> m) {
        ct_host::put32(m, CT_HDR_CRC, 0);
        uint32_t crc = 0;
        ct_crc32(0, m.data(), m.size(), &crc);
        ct_host::put32(m, CT_HDR_CRC, crc);
        return m;
    };
    struct Bad {
        const char *what;
        ct_status want;
        std::function<void(std::vector<uint8_t> &)> edit;
        bool restamp;
    };
    const std::vector<Bad> bads = {
        {"short", CT_ERR_TRUNCATED, [](std::vector<uint8_t> &m) { m.resize(40); }, false},
        {"magic", CT_ERR_MAGIC, [](std::vector<uint8_t> &m) { m[3] = 'K'; }, false},
        {"version", CT_ERR_VERSION, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_HDR_VERSION, 2); }, true},
        {"crc", CT_ERR_CRC, [](std::vector<uint8_t> &m) { m[CT_SET_HEADER_SIZE + 1] ^= 1; }, false},
        {"tiles_x", CT_ERR_DIMS, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_TILES_X, 5); }, true},
        {"tile posts", CT_ERR_DIMS, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_TILE_POSTS, 40); }, true},
        {"sectors", CT_ERR_SECTORS, [](std::vector<uint8_t> &m) { m[CT_SET_HDR_SECTORS] = 65; }, true},
        {"reduce", CT_ERR_REDUCE, [](std::vector<uint8_t> &m) { m[CT_SET_HDR_REDUCE] = 9; }, true},
        {"flags", CT_ERR_FLAGS, [](std::vector<uint8_t> &m) { ct_host::put32(m, CT_SET_HDR_FLAGS, 1); }, true},
        {"entry range", CT_ERR_RANGE,
         [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HEADER_SIZE + 10, 60000); }, true},
        {"posting", CT_ERR_GEOREF, [](std::vector<uint8_t> &m) { ct_host::put64(m, CT_SET_HDR_GEOREF + 16, 0); }, true},
        // each of the grid's checks alone (40 x 33 posts, tiles of 12: 4 x 3)
        {"header size", CT_ERR_HEADER, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_HDR_HEADER_SIZE, 64); }, true},
        {"total beyond the bytes", CT_ERR_TRUNCATED,
         [](std::vector<uint8_t> &m) { ct_host::put32(m, CT_HDR_TOTAL, (uint32_t)m.size() + 1); }, true},
        {"width 1", CT_ERR_DIMS, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_WIDTH, 1); }, true},
        {"height 1", CT_ERR_DIMS, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_HEIGHT, 1); }, true},
        {"width beyond CT_MAX_POSTS", CT_ERR_DIMS,
         [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_WIDTH, CT_MAX_POSTS + 1); }, true},
        {"height beyond CT_MAX_POSTS", CT_ERR_DIMS,
         [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_HEIGHT, CT_MAX_POSTS + 1); }, true},
        {"tile posts 1", CT_ERR_DIMS, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_TILE_POSTS, 1); }, true},
        {"tile posts beyond CT_MAX_POSTS", CT_ERR_DIMS,
         [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_TILE_POSTS, CT_MAX_POSTS + 1); }, true},
        {"tiles_x 0", CT_ERR_DIMS, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_TILES_X, 0); }, true},
        {"tiles_y 0", CT_ERR_DIMS, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_TILES_Y, 0); }, true},
        {"more tiles than CT_SET_MAX_TILES", CT_ERR_DIMS,
         [](std::vector<uint8_t> &m) {
             ct_host::put16(m, CT_SET_HDR_TILES_X, 60000);
             ct_host::put16(m, CT_SET_HDR_TILES_Y, 60000);
         },
         true},
        {"tiles_x too few", CT_ERR_DIMS, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_TILES_X, 3); }, true},
        {"tiles_y too many", CT_ERR_DIMS, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_TILES_Y, 4); }, true},
        {"tiles_y too few", CT_ERR_DIMS, [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_TILES_Y, 2); }, true},
        {"an entry too many", CT_ERR_SIZE,
         [](std::vector<uint8_t> &m) {
             m.resize(m.size() + CT_SET_ENTRY_SIZE, 0);
             ct_host::put32(m, CT_HDR_TOTAL, (uint32_t)m.size());
         },
         true},
        {"sectors 0", CT_ERR_SECTORS, [](std::vector<uint8_t> &m) { m[CT_SET_HDR_SECTORS] = 0; }, true},
        {"reduce 0", CT_ERR_REDUCE, [](std::vector<uint8_t> &m) { m[CT_SET_HDR_REDUCE] = 0; }, true},
        {"vertical datum unknown to the library", CT_ERR_FLAGS,
         [](std::vector<uint8_t> &m) { ct_host::put16(m, CT_SET_HDR_VDATUM, CT_VDATUM_COUNT); }, true},
        {"entry flag 2", CT_ERR_FLAGS, [](std::vector<uint8_t> &m) { m[CT_SET_HEADER_SIZE + 12] = 2; }, true},
        {"entry hmin above its hmax", CT_ERR_RANGE,
         [](std::vector<uint8_t> &m) {
             m[CT_SET_HEADER_SIZE + 12] = 1;
             ct_host::put16(m, CT_SET_HEADER_SIZE + 8, 5);
             ct_host::put16(m, CT_SET_HEADER_SIZE + 10, 4);
         },
         true},
        {"entry hmin below the set's", CT_ERR_RANGE,
         [](std::vector<uint8_t> &m) {
             m[CT_SET_HEADER_SIZE + 12] = 1;
             ct_host::put16(m, CT_SET_HDR_HMIN, 3);
             ct_host::put16(m, CT_SET_HDR_HMAX, 60000);
             ct_host::put16(m, CT_SET_HEADER_SIZE + 8, 2);
             ct_host::put16(m, CT_SET_HEADER_SIZE + 10, 4);
         },
         true},
        {"a corner beyond 2^61 nm east", CT_ERR_GEOREF,
         [](std::vector<uint8_t> &m) { ct_host::put64(m, CT_SET_HDR_GEOREF, (INT64_C(1) << 61) - 1000); }, true},
        {"a corner beyond 2^61 nm north", CT_ERR_GEOREF,
         [](std::vector<uint8_t> &m) { ct_host::put64(m, CT_SET_HDR_GEOREF + 8, (INT64_C(1) << 61) - 1000); }, true},
    };
    for (const Bad &b : bads) {
        std::vector<uint8_t> m = tb.manifest;
        b.edit(m);
        if (b.restamp) m = restamp(m);
        Set s2;
        const ct_status st = s2.open(tb, 1, &m);
        TEST_ASSERT_MSG(st == b.want, "manifest %s: %d, expected %d", b.what, st, b.want);
    }
    ct_tileset ts;
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_tileset_open(&ts, tb.manifest.data(), tb.manifest.size(), set.slots.data(), 0,
                                                      mem_loader, &set.mem));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_tileset_open(&ts, tb.manifest.data(), tb.manifest.size(), set.slots.data(),
                                                      CT_SET_MAX_SLOTS + 1, mem_loader, &set.mem));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_tileset_open(&ts, tb.manifest.data(), tb.manifest.size(), nullptr, 1,
                                                      mem_loader, &set.mem));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_tileset_open(&ts, tb.manifest.data(), tb.manifest.size(), set.slots.data(), 1,
                                                      nullptr, &set.mem));
}

// Geolocation over a set: the merged package's results, straight and on a
// sphere (the lowered walk), single calls and the batch.
void test_geolocation()
{
    const ct_host::Terrain t = dem_cases::mirror_tiled(dem_cases::real_terrain(), 500, 500);
    ct_host::BuildOptions o;
    o.sectors = 24;
    o.reduce = 3;
    const TileSetBytes tb = ct_host::build_tileset(t, o, 129, 0);
    const std::vector<uint8_t> merged = ct_host::build_package(t, o);
    ct_package mp;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&mp, merged.data(), merged.size()));
    Set set;
    TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 4));
    ct_camera cam;  // principal point (159.5, 119.5): off centre
    TEST_ASSERT_EQUAL_INT(CT_OK, pinhole(&cam, 640, 480, 500, 319, 239));
    // over the set's centre, 2 km up, looking 20 deg down to the north-east
    int32_t q[4];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(dem_cases::deg_q61(45), dem_cases::deg_q61(-20), 0, q));
    ct_pose pose;
    const int64_t e = mp.origin_e_nm + 120 * mp.posting_e_nm, n = mp.origin_n_nm + 380 * mp.posting_n_nm;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&pose, e, n, (int64_t)2000 * 1000000000, q));
    const std::vector<int64_t> uv = dem_cases::pixel_grid(640, 480, 24);
    const size_t np = uv.size() / 2;
    ct_effects sphere = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16,
                         (int64_t)6371000 * 1000000000, 0, NULL};
    // the true Earth (the fixture is on UTM 17N): exact conversions, and
    // the map fitted once per batch
    ct_effects earth = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, 0, 0, NULL};
    ct_effects earth_fit = earth;
    earth_fit.flags |= CT_EFFECT_EARTH_FIT;
    const ct_effects *fxs[4] = {nullptr, &sphere, &earth, &earth_fit};
    const char *names[4] = {"straight", "on a sphere (lowered walk)", "the true Earth", "the true Earth, fitted map"};
    for (int f = 0; f < 4; ++f)
        for (int m = 0; m < 4; ++m) {
            if (f >= 2 && (m == 1 || m == 2)) continue;  // the true Earth: incremental and directional suffice
            std::vector<ct_geo> a(np), b(np);
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&mp, &cam, &pose, (ct_method)m, fxs[f], uv.data(), np,
                                                            a.data(), np));
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch_tiles(&set.ts, &cam, &pose, (ct_method)m, fxs[f],
                                                                  uv.data(), np, b.data(), np));
            long hits = 0, differ = 0;
            for (size_t k = 0; k < np; ++k) {
                hits += a[k].status == CT_HIT;
                differ += !same_hit(a[k].status, a[k].hit, b[k].status, b[k].hit);
            }
            ct_geo one;
            ct_geolocate_tiles(&set.ts, &cam, &pose, (ct_method)m, fxs[f], uv[np], uv[np + 1], &one);
            ct_geo ref1;
            ct_geolocate(&mp, &cam, &pose, (ct_method)m, fxs[f], uv[np], uv[np + 1], &ref1);
            TEST_ASSERT(same_hit(ref1.status, ref1.hit, one.status, one.hit));
            if (m == 3)
                std::printf("  geolocation %s: %zu pixels, %ld hits, %ld differ from the merged package\n", names[f],
                            np, hits, differ);
            TEST_ASSERT_EQUAL_INT(0, (int)differ);
            TEST_ASSERT(hits > (long)np / 2);
        }
    // refraction alone on a sphere (c < 0: the polyline, each segment walked
    // tile by tile): the merged package's results too
    ct_effects refr = {CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, (int64_t)6371000 * 1000000000, 0, NULL};
    // a camera 5 m under the surface, every effect model (the straight
    // walk, the lowered walk, the polyline, the true Earth's pieces, exact
    // and fitted): CT_BELOW for every pixel from the merged package and the
    // set alike (ct_geolocate's documented status)
    {
        const int ci = 300, cj = 200;
        const int64_t be = mp.origin_e_nm + (int64_t)std::llround((ci + 0.5) * mp.posting_e_nm);
        const int64_t bn = mp.origin_n_nm + (int64_t)std::llround((cj + 0.5) * mp.posting_n_nm);
        const int64_t bh = mp.height_offset_nm + (int64_t)t.codes[(size_t)cj * t.width + ci] * mp.height_scale_nm -
                           (int64_t)5 * 1000000000;
        ct_pose under;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&under, be, bn, bh, q));
        const ct_effects *all[5] = {nullptr, &sphere, &refr, &earth, &earth_fit};
        for (int f = 0; f < 5; ++f)
            for (int m : {0, 3}) {
                std::vector<ct_geo> a(np), b(np);
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&mp, &cam, &under, (ct_method)m, all[f], uv.data(), np,
                                                                a.data(), np));
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch_tiles(&set.ts, &cam, &under, (ct_method)m, all[f],
                                                                      uv.data(), np, b.data(), np));
                long below = 0;
                for (size_t k = 0; k < np; ++k) {
                    below += a[k].status == CT_BELOW && b[k].status == CT_BELOW;
                    if (a[k].status != CT_BELOW || b[k].status != CT_BELOW) {
                        TEST_ASSERT_MSG(false, "under the surface, effects %d method %d pixel %zu: merged %d, set %d", f,
                                        m, k, a[k].status, b[k].status);
                        break;
                    }
                }
                TEST_ASSERT_EQUAL_INT((int)np, (int)below);
            }
    }
    // a vertical line of sight (a nadir pose with an exact rotation, the
    // principal point): no effect bends it -- the straight trace's hit,
    // bit for bit, from the merged package and the set, with every effect
    {
        const int32_t nadir[9] = {1 << 30, 0, 0, 0, -(1 << 30), 0, 0, 0, -(1 << 30)};
        ct_pose down;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_init(&down, nadir, e, n, (int64_t)2000 * 1000000000));
        const int64_t pu = (int64_t)319 << 15, pv = (int64_t)239 << 15;  // (159.5, 119.5)
        ct_geo ref;
        TEST_ASSERT_EQUAL_INT(CT_HIT, ct_geolocate(&mp, &cam, &down, CT_METHOD_INCREMENTAL, nullptr, pu, pv, &ref));
        TEST_ASSERT(ref.dir_map_q39[0] == 0 && ref.dir_map_q39[1] == 0);
        const ct_effects *all[3] = {&sphere, &refr, nullptr};
        for (int f = 0; f < 3; ++f)
            for (int m = 0; m < 4; ++m) {
                ct_geo a, b;
                ct_geolocate(&mp, &cam, &down, (ct_method)m, all[f], pu, pv, &a);
                ct_geolocate_tiles(&set.ts, &cam, &down, (ct_method)m, all[f], pu, pv, &b);
                TEST_ASSERT_MSG(same_hit(ref.status, ref.hit, a.status, a.hit) &&
                                    same_hit(ref.status, ref.hit, b.status, b.hit),
                                "nadir, effects %d method %d: merged %d, set %d", f, m, a.status, b.status);
            }
    }
    // the bent walk's own entry (tiles.h) with a line of sight whose
    // horizontal part vanishes once reduced (1 against 2^40 down): not
    // bent, the straight trace's hit -- the polyline's (c < 0) and the
    // lowered walk's set-ups, over the set and on the merged package
    {
        const ct_ray steep = {(int64_t)250 << 16, (int64_t)190 << 16, ((int64_t)mp.hmax + 100) << 16, 1, 0,
                              -(INT64_C(1) << 40)};
        ct_hit hs, hb;
        const ct_status ss = ct_trace(&mp, &steep, CT_METHOD_DIRECTIONAL, &hs);
        TEST_ASSERT_EQUAL_INT(CT_HIT, ss);
        for (int32_t c : {-8520, 57016}) {
            const ct_bend bd = {c, (int64_t)6371000 * 1000000000, 1000000, 0u};
            ct_bent_setup bs, bm;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_bent_prepare(&set.ts.frame, &bd, steep.x_q16, steep.y_q16, &bs));
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_bent_prepare(&mp, &bd, steep.x_q16, steep.y_q16, &bm));
            for (int m = 0; m < 4; ++m) {
                TEST_ASSERT(same_hit(ss, hs, ct_trace_bent_set_ts(&set.ts.frame, &set.ts, &steep, &bs, (ct_method)m, &hb),
                                     hb));
                TEST_ASSERT(same_hit(ss, hs, ct_trace_bent_set(&mp, &steep, &bm, (ct_method)m, &hb), hb));
            }
        }
    }
    // a tile missing, with every effect: the merged result or CT_NO_DATA,
    // never a hit on the missing tile
    {
        const int mc = 2, mr = 2;  // a tile the camera sees
        const TileSetBytes holed = ct_host::build_tileset(t, o, 129, 0, [&](int c, int r) { return c == mc && r == mr; });
        Set hs;
        TEST_ASSERT_EQUAL_INT(CT_OK, hs.open(holed, 4));
        const ct_effects *all[5] = {nullptr, &sphere, &earth, &earth_fit, &refr};
        const int x0 = holed.grid.first_col(mc), y0 = holed.grid.first_row(mr);
        for (int f = 0; f < 5; ++f) {
            std::vector<ct_geo> a(np), b(np);
            ct_geolocate_batch(&mp, &cam, &pose, CT_METHOD_DIRECTIONAL, all[f], uv.data(), np, a.data(), np);
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch_tiles(&hs.ts, &cam, &pose, CT_METHOD_DIRECTIONAL, all[f],
                                                                  uv.data(), np, b.data(), np));
            long nodata = 0, on_hole = 0;
            for (size_t k = 0; k < np; ++k) {
                const bool hole = a[k].status == CT_HIT && a[k].hit.cell_x >= x0 && a[k].hit.cell_x < x0 + 128 &&
                                  a[k].hit.cell_y >= y0 && a[k].hit.cell_y < y0 + 128;
                on_hole += hole;
                if (b[k].status == CT_NO_DATA) {
                    nodata++;
                    TEST_ASSERT(b[k].hit.cell_x >= x0 && b[k].hit.cell_x < x0 + 128 && b[k].hit.cell_y >= y0 &&
                                b[k].hit.cell_y < y0 + 128);
                } else {
                    TEST_ASSERT_MSG(!hole && same_hit(a[k].status, a[k].hit, b[k].status, b[k].hit),
                                    "effects %d pixel %zu: %d vs merged %d", f, k, b[k].status, a[k].status);
                }
            }
            std::printf("  a missing tile, effects %d: %ld pixels no_data (%ld merged hits on it)\n", f, nodata, on_hole);
            TEST_ASSERT(nodata >= on_hole && on_hole > 0);
        }
        // the camera 20 m over the missing tile, inside the terrain's box:
        // every line of sight starts there -- CT_NO_DATA at its first
        // point, with every effect model
        ct_pose over;
        const int oi = x0 + 64, oj = y0 + 64;
        const int64_t oe = mp.origin_e_nm + (int64_t)std::llround((oi + 0.5) * mp.posting_e_nm);
        const int64_t on = mp.origin_n_nm + (int64_t)std::llround((oj + 0.5) * mp.posting_n_nm);
        const int64_t oh = mp.height_offset_nm + (int64_t)t.codes[(size_t)oj * t.width + oi] * mp.height_scale_nm +
                           (int64_t)20 * 1000000000;
        TEST_ASSERT((oh - mp.height_offset_nm) / mp.height_scale_nm < (int64_t)mp.hmax);
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&over, oe, on, oh, q));
        for (int f = 0; f < 5; ++f) {
            std::vector<ct_geo> b(np);
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch_tiles(&hs.ts, &cam, &over, CT_METHOD_DIRECTIONAL, all[f],
                                                                  uv.data(), np, b.data(), np));
            long nodata = 0;
            for (size_t k = 0; k < np; ++k)
                nodata += b[k].status == CT_NO_DATA && b[k].hit.cell_x >= x0 && b[k].hit.cell_x < x0 + 128 &&
                          b[k].hit.cell_y >= y0 && b[k].hit.cell_y < y0 + 128;
            TEST_ASSERT_MSG(nodata == (long)np, "camera over the missing tile, effects %d: %ld of %zu no_data on it "
                            "(pixel 0: status %d cell %d,%d)", f, nodata, np, b[0].status, b[0].hit.cell_x, b[0].hit.cell_y);
        }
    }
    for (int m : {0, 3}) {
        std::vector<ct_geo> a(np), b(np);
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&mp, &cam, &pose, (ct_method)m, &refr, uv.data(), np, a.data(), np));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch_tiles(&set.ts, &cam, &pose, (ct_method)m, &refr, uv.data(), np,
                                                              b.data(), np));
        long hits = 0, differ = 0;
        for (size_t k = 0; k < np; ++k) {
            hits += a[k].status == CT_HIT;
            differ += !same_hit(a[k].status, a[k].hit, b[k].status, b[k].hit);
        }
        if (m == 3)
            std::printf("  geolocation refraction alone (the polyline): %zu pixels, %ld hits, %ld differ\n", np, hits,
                        differ);
        TEST_ASSERT_EQUAL_INT(0, (int)differ);
        TEST_ASSERT(hits > (long)np / 2);
    }
}

// The fixture mirror-tiled to 500 x 500 posts (N sectors, r = 3) cut into
// 4 x 4 tiles of 129 posts, the same set with tile (hc, hr) left out, and
// the package built from the merged DEM (opened in mp).
struct Mirror500 {
    ct_host::Terrain t;
    ct_host::BuildOptions o;
    TileSetBytes tb, holed;
    std::vector<uint8_t> merged;
    ct_package mp{}; // opened over merged: not to be copied
    Mirror500(const Mirror500 &) = delete;
    Mirror500 &operator=(const Mirror500 &) = delete;
    Mirror500(int sectors, int hc, int hr) : t(dem_cases::mirror_tiled(dem_cases::real_terrain(), 500, 500))
    {
        o.sectors = sectors;
        o.reduce = 3;
        tb = ct_host::build_tileset(t, o, 129, 0);
        holed = ct_host::build_tileset(t, o, 129, 0, [&](int c, int r) { return c == hc && r == hr; });
        merged = ct_host::build_package(t, o);
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&mp, merged.data(), merged.size()));
    }
};

// The batch's runs over a set (ct_tileset_trace_run): whole image rows of
// neighbouring pixels, every record (status, hit position, cell; a missing
// tile's CT_NO_DATA point too) as the same pixel's ct_geolocate_tiles and,
// where the set has every tile, as the merged package's; straight and on a
// sphere, every method; a slot per tile and a single slot (the run fetches
// only the tile its rays' walks would, and a ray it shows clear through it
// skips it: with these caches the batch's loads are at most the single
// calls'; with a few LRU slots the skipped visits may change which tile a
// slot drops, ct_soak counts it); cameras high, low and grazing, and one
// outside the set.  The runs must take part: some walks shortened.
void test_batch_runs()
{
    const Mirror500 w(24, 2, 1);
    const ct_host::Terrain &t = w.t;
    const TileSetBytes &tb = w.tb, &holed = w.holed;
    const ct_package &mp = w.mp;
    ct_camera cam;
    TEST_ASSERT_EQUAL_INT(CT_OK, pinhole(&cam, 640, 480, 500, 639, 479));
    std::vector<int64_t> uv;
    for (int row : {0, 100, 239, 380, 479})
        for (int col = 0; col < 640; ++col) {
            uv.push_back(((int64_t)col << 16) + (1 << 15));
            uv.push_back(((int64_t)row << 16) + (1 << 15));
        }
    const size_t np = uv.size() / 2;
    struct View {
        const char *what;
        int ci, cj;
        double up_m, yaw, pitch;
    };
    const View views[] = {
        {"2 km up, 20 deg down", 120, 380, 2000, 45, -20},
        {"300 m over the top, 4 deg down", 60, 60, 300, 30, -4},
        {"400 m up, 12 deg down, looking west", 470, 250, 400, 175, -12},
        {"outside the set, 1 km up, 8 deg down", -40, 200, 1000, 5, -8},
    };
    ct_effects sphere = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16,
                         (int64_t)6371000 * 1000000000, 0, NULL};
    const ct_effects *fxs[2] = {nullptr, &sphere};
    long shortened = 0, compared = 0, nodata = 0;
    for (const View &v : views) {
        int32_t q[4];
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(dem_cases::deg_q61(v.yaw), dem_cases::deg_q61(v.pitch), 0, q));
        const int64_t e = mp.origin_e_nm + (int64_t)v.ci * mp.posting_e_nm;
        const int64_t n = mp.origin_n_nm + (int64_t)v.cj * mp.posting_n_nm;
        const int64_t h = mp.height_offset_nm + (int64_t)mp.hmax * mp.height_scale_nm + (int64_t)(v.up_m * 1e9);
        ct_pose pose;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&pose, e, n, h, q));
        for (int f = 0; f < 2; ++f)
            for (int m = 0; m < 4; ++m)
                for (int which = 0; which < 2; ++which)
                    for (int slots : {16, 1}) {
                        const TileSetBytes &sb = which == 0 ? tb : holed;
                        Set a, b;
                        TEST_ASSERT_EQUAL_INT(CT_OK, a.open(sb, slots));
                        TEST_ASSERT_EQUAL_INT(CT_OK, b.open(sb, slots));
                        std::vector<ct_geo> gb(np), gm(np);
                        TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch_tiles(&a.ts, &cam, &pose, (ct_method)m, fxs[f],
                                                                              uv.data(), np, gb.data(), np));
                        if (which == 0)
                            TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&mp, &cam, &pose, (ct_method)m, fxs[f],
                                                                            uv.data(), np, gm.data(), np));
                        for (size_t k = 0; k < np; ++k) {
                            ct_geo one;
                            ct_geolocate_tiles(&b.ts, &cam, &pose, (ct_method)m, fxs[f], uv[2 * k], uv[2 * k + 1], &one);
                            const ct_hit &x = gb[k].hit, &y = one.hit;
                            const bool placed = one.status == CT_HIT || one.status == CT_HIT_VOID ||
                                                one.status == CT_NO_DATA;
                            const bool same = gb[k].status == one.status &&
                                              (!placed || (x.x_q16 == y.x_q16 && x.y_q16 == y.y_q16 &&
                                                           x.z_q16 == y.z_q16 && x.t_q26 == y.t_q26 &&
                                                           x.cell_x == y.cell_x && x.cell_y == y.cell_y &&
                                                           x.e_nm == y.e_nm && x.n_nm == y.n_nm && x.h_nm == y.h_nm));
                            TEST_ASSERT_MSG(same, "%s, effects %d, method %d, %s set, %d slots, pixel %zu: batch %d "
                                            "(cell %d,%d) vs single %d (cell %d,%d)", v.what, f, m,
                                            which == 0 ? "whole" : "holed", slots, k, gb[k].status, x.cell_x, x.cell_y,
                                            one.status, y.cell_x, y.cell_y);
                            if (which == 0)
                                TEST_ASSERT_MSG(same_hit(gm[k].status, gm[k].hit, gb[k].status, gb[k].hit),
                                                "%s, effects %d, method %d, pixel %zu: set %d vs merged %d", v.what, f,
                                                m, k, gb[k].status, gm[k].status);
                            shortened += gb[k].hit.steps < one.hit.steps;
                            nodata += gb[k].status == CT_NO_DATA;
                            compared++;
                            if (!same) break;
                        }
                        TEST_ASSERT_MSG(a.ts.loads <= b.ts.loads, "%s, effects %d, method %d, %d slots: the batch "
                                        "loaded %u tiles, the single calls %u", v.what, f, m, slots,
                                        (unsigned)a.ts.loads, (unsigned)b.ts.loads);
                    }
    }
    // rays the runs leave to their own walks: a nadir camera's (an exact
    // rotation) principal point and the pixels around it (vertical rays, rays
    // in a vertical grid plane), and a camera exactly on a post (every ray a
    // hit at its first point)
    {
        const int32_t nadir[9] = {1 << 30, 0, 0, 0, -(1 << 30), 0, 0, 0, -(1 << 30)};
        const int pi = 200, pj = 260;
        const int64_t pe = mp.origin_e_nm + (int64_t)pi * mp.posting_e_nm, pn = mp.origin_n_nm + (int64_t)pj * mp.posting_n_nm;
        ct_pose down, on_post;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_init(&down, nadir, pe, pn, mp.height_offset_nm +
                                                      ((int64_t)mp.hmax + 30000) * mp.height_scale_nm));
        ct_geo below;  // the surface under the post: the vertical ray's hit
        TEST_ASSERT_EQUAL_INT(CT_HIT, ct_geolocate(&mp, &cam, &down, CT_METHOD_INCREMENTAL, nullptr,
                                                   ((int64_t)319 << 16) + (1 << 15), ((int64_t)239 << 16) + (1 << 15),
                                                   &below));
        const int64_t post_h = below.hit.h_nm;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_init(&on_post, nadir, pe, pn, post_h));
        std::vector<int64_t> px;
        for (int dv = -1; dv <= 1; ++dv)
            for (int du = -1; du <= 1; ++du) {
                px.push_back(((int64_t)(319 + du) << 16) + (1 << 15));
                px.push_back(((int64_t)(239 + dv) << 16) + (1 << 15));
            }
        const size_t n9 = px.size() / 2;
        long vertical = 0, at_camera = 0;
        for (const ct_pose *ps : {&down, &on_post})
            for (int m = 0; m < 4; ++m) {
                Set a, b;
                TEST_ASSERT_EQUAL_INT(CT_OK, a.open(tb, 4));
                TEST_ASSERT_EQUAL_INT(CT_OK, b.open(tb, 4));
                std::vector<ct_geo> gb(n9);
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch_tiles(&a.ts, &cam, ps, (ct_method)m, nullptr, px.data(),
                                                                      n9, gb.data(), n9));
                for (size_t k = 0; k < n9; ++k) {
                    ct_geo one;
                    ct_geolocate_tiles(&b.ts, &cam, ps, (ct_method)m, nullptr, px[2 * k], px[2 * k + 1], &one);
                    TEST_ASSERT_MSG(same_hit(one.status, one.hit, gb[k].status, gb[k].hit),
                                    "%s, method %d, pixel %zu: batch %d vs single %d",
                                    ps == &down ? "nadir" : "on a post", m, k, gb[k].status, one.status);
                    vertical += ps == &down && gb[k].dir_map_q39[0] == 0 && gb[k].dir_map_q39[1] == 0;
                    at_camera += ps == &on_post && gb[k].status == CT_HIT && gb[k].hit.h_nm == post_h;
                }
            }
        TEST_ASSERT(vertical > 0 && at_camera > 0);
    }
    std::printf("  batch runs over a set: %ld records as the single calls' (%ld CT_NO_DATA), %ld walks shortened\n",
                compared, nodata, shortened);
    TEST_ASSERT(nodata > 0);
    TEST_ASSERT(shortened > compared / 10);
}

// Intervisibility over a set: ct_los_tiles = ct_los on the merged package
// (straight, a sphere, the true Earth), and with a tile missing the merged
// answer or CT_NO_DATA, never "visible" through or "blocked" on that tile.
void test_los()
{
    const Mirror500 w(16, 1, 2);
    const ct_host::Terrain &t = w.t;
    const TileSetBytes &tb = w.tb, &holed = w.holed;
    const ct_package &mp = w.mp;
    Set set, hs;
    TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 3));
    TEST_ASSERT_EQUAL_INT(CT_OK, hs.open(holed, 3));
    ct_effects sphere = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16,
                         (int64_t)6371000 * 1000000000, 0, NULL};
    ct_effects earth = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, 0, 0, NULL};
    const ct_effects *fxs[3] = {nullptr, &sphere, &earth};
    ct_rng rng;
    ct_rng_seed(&rng, 4242);
    long counts[3] = {0, 0, 0}, nodata = 0, hidden = 0;
    const int hx0 = holed.grid.first_col(1), hy0 = holed.grid.first_row(2);
    for (int k = 0; k < 1500; ++k) {
        // A 2-300 m above a post, B on or above the surface elsewhere
        auto point = [&](double lift) {
            const double i = ct_rng_unit(&rng) * 498, j = ct_rng_unit(&rng) * 498;
            std::array<int64_t, 3> q;
            q[0] = mp.origin_e_nm + (int64_t)std::llround((i + 0.5) * mp.posting_e_nm);
            q[1] = mp.origin_n_nm + (int64_t)std::llround((j + 0.5) * mp.posting_n_nm);
            q[2] = mp.height_offset_nm + (int64_t)std::llround(dem_cases::surf(t, i, j) * mp.height_scale_nm) +
                   (int64_t)std::llround(lift * 1e9);
            return q;
        };
        // one pair in ten with A 5 m under the surface: CT_BELOW (ct_los's documented status)
        const bool under = k % 10 == 9;
        const auto A = point(under ? -5 : 2 + 300 * ct_rng_unit(&rng)), B = point(ct_rng_unit(&rng) < 0.5 ? 0.5 : 30);
        const ct_effects *fx = fxs[k % 3];
        ct_hit hm, hs1, hh;
        const ct_status sm = ct_los(&mp, A.data(), B.data(), fx, 1000000, CT_METHOD_DIRECTIONAL, &hm);
        const ct_status ss = ct_los_tiles(&set.ts, A.data(), B.data(), fx, 1000000, CT_METHOD_DIRECTIONAL, &hs1);
        const ct_status sh = ct_los_tiles(&hs.ts, A.data(), B.data(), fx, 1000000, CT_METHOD_DIRECTIONAL, &hh);
        TEST_ASSERT_MSG(sm >= 0, "ct_los %d", sm);
        TEST_ASSERT_MSG(under == (sm == CT_BELOW), "pair %d effects %d: A %s the surface, ct_los %d", k, k % 3,
                        under ? "under" : "over", sm);
        TEST_ASSERT_MSG(same_hit(sm, hm, ss, hs1), "pair %d effects %d: set %d vs merged %d", k, k % 3, ss, sm);
        counts[sm == CT_OK ? 0 : (sm == CT_HIT ? 1 : 2)]++;
        const bool on_hole = sm == CT_HIT && hm.cell_x >= hx0 && hm.cell_x < hx0 + 128 && hm.cell_y >= hy0 &&
                             hm.cell_y < hy0 + 128;
        hidden += on_hole;
        if (sh == CT_NO_DATA) {
            nodata++;
        } else {
            TEST_ASSERT_MSG(!on_hole && same_hit(sm, hm, sh, hh), "holed pair %d: %d vs merged %d", k, sh, sm);
        }
        if (ct_harness_g.current_failed) return;
    }
    std::printf("  line of sight: 1500 pairs (straight, sphere, true Earth): %ld visible, %ld blocked, %ld below; "
                "with a tile missing %ld no_data (%ld blocked on it)\n",
                counts[0], counts[1], counts[2], nodata, hidden);
    TEST_ASSERT(counts[0] > 100 && counts[1] > 100 && counts[2] == 150 && nodata >= hidden && hidden > 0);
}

// A set's frame (ts.frame: a ct_package with no sections, base NULL, for
// the georeference) handed to what reads terrain: CT_ERR_ARG from each, not
// a NULL dereference; the same calls on the merged package succeed.  And a
// set that is not ready (never opened, or its open failed): CT_ERR_ARG.
// The polyline over a set where its vertices saturate (test_bend's
// test_bent_saturated_vertices: 1 nm height codes, a sphere of 2^40 nm,
// c = -4 and 4, a chord of 2^46 nm, one segment of ~400 cells over the
// 30 x 30 cells): over the set (tiles of 11 posts) every method's result is
// the merged package's bit for bit -- hits from over the terrain (c = -4),
// CT_BELOW from beside the tile (the first segment enters the west face
// over 2^46 Q16 under the terrain: decided at its preparation), misses
// (c = 4).  Before, the set's segment trace returned that CT_BELOW with
// no end (td 0) and the polyline took it for a segment off the box: a
// miss where the merged package says CT_BELOW.
void test_bent_saturated()
{
    const ct_host::Terrain t =
        dem_cases::make_terrain(31, 31, dem_cases::smooth(31, 31, 7, 100, 3000), 1e-9);
    ct_host::BuildOptions o;
    o.sectors = 8;
    o.reduce = 1;
    const TileSetBytes tb = ct_host::build_tileset(t, o, 11, 0);
    const std::vector<uint8_t> merged = ct_host::build_package(t, o);
    ct_package mp;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&mp, merged.data(), merged.size()));
    TEST_ASSERT(mp.height_scale_nm == 1);
    Set set;
    TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 2));
    long hits = 0, below = 0, miss = 0;
    for (int32_t c : {-4 * 65536, 4 * 65536}) {
        const ct_bend bd = {c, INT64_C(1) << 40, INT64_C(1) << 46, 0u};
        for (int k = 0; k < 8; ++k) {
            const double az = 0.3 + 0.7 * k, y = 4.0 + 3.0 * k;
            const double x = k % 2 == 0 ? 3.0 + 2.5 * k : -0.125;
            double dv[3];
            dem_cases::metric_dir(t, k % 2 == 0 ? az : 0.2 * (k - 4), -1e-7 * k, dv);
            const ct_ray ray = dem_cases::to_ray(x, y, dem_cases::surf(t, std::max(0.0, x), y) + 50, dv);
            ct_bent_setup bs, bm;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_bent_prepare(&set.ts.frame, &bd, ray.x_q16, ray.y_q16, &bs));
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_bent_prepare(&mp, &bd, ray.x_q16, ray.y_q16, &bm));
            TEST_ASSERT(!bs.lowered && !bm.lowered);
            for (int m = 0; m < 4; ++m) {
                ct_hit hm, hs;
                const ct_status sm = ct_trace_bent_set(&mp, &ray, &bm, (ct_method)m, &hm);
                const ct_status ss = ct_trace_bent_set_ts(&set.ts.frame, &set.ts, &ray, &bs, (ct_method)m, &hs);
                TEST_ASSERT_MSG(same_hit(sm, hm, ss, hs), "c %d ray %d method %d: set %d, merged %d", (int)c, k, m,
                                (int)ss, (int)sm);
                if (m == 0) {
                    hits += sm == CT_HIT;
                    below += sm == CT_BELOW;
                    miss += sm == CT_MISS;
                }
            }
        }
    }
    std::printf("  saturated polyline: %ld hit, %ld below, %ld miss, as merged\n", hits, below, miss);
    TEST_ASSERT(hits == 4 && below == 4 && miss == 8);
}

// Polyline segments starting just under the surface after the polyline
// entered (test_bend's test_bent_start_below_after_entered: 1 mm codes on
// 30 m posts, c = -4, R = 2^40 nm, a chord of 0.1 mm; its rays): over a set
// of 13-post tiles the set's segment trace takes that start as the hit
// (below_hit), and every method's result is the merged package's bit for
// bit.
void test_bent_start_below_after_entered()
{
    const ct_host::Terrain t = dem_cases::below_after_entered_terrain();
    ct_host::BuildOptions o;
    o.sectors = 8;
    o.reduce = 1;
    const TileSetBytes tb = ct_host::build_tileset(t, o, 13, 0);
    const std::vector<uint8_t> merged = ct_host::build_package(t, o);
    ct_package mp;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&mp, merged.data(), merged.size()));
    Set set;
    TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 2));
    const ct_bend bd = {-4 * 65536, INT64_C(1) << 40, 100000, 0u};
    long hits = 0;
    for (const ct_ray &ray : dem_cases::kBelowAfterEnteredRays) {
        ct_bent_setup bs, bm;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_bent_prepare(&set.ts.frame, &bd, ray.x_q16, ray.y_q16, &bs));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_bent_prepare(&mp, &bd, ray.x_q16, ray.y_q16, &bm));
        for (int m = 0; m < 4; ++m) {
            ct_hit hm, hs;
            const ct_status sm = ct_trace_bent_set(&mp, &ray, &bm, (ct_method)m, &hm);
            const ct_status ss = ct_trace_bent_set_ts(&set.ts.frame, &set.ts, &ray, &bs, (ct_method)m, &hs);
            TEST_ASSERT_MSG(same_hit(sm, hm, ss, hs), "ray %lld method %d: set %d, merged %d", (long long)ray.x_q16, m,
                            (int)ss, (int)sm);
            hits += m == 0 && sm == CT_HIT;
        }
    }
    TEST_ASSERT(hits == 5);
}

void test_frame_refused()
{
    const ct_host::Terrain t = dem_cases::mirror_tiled(dem_cases::real_terrain(), 200, 200);
    ct_host::BuildOptions o;
    o.sectors = 8;
    o.reduce = 2;
    const TileSetBytes tb = ct_host::build_tileset(t, o, 65, 0);
    const std::vector<uint8_t> merged = ct_host::build_package(t, o);
    ct_package mp;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&mp, merged.data(), merged.size()));
    Set set;
    TEST_ASSERT_EQUAL_INT(CT_OK, set.open(tb, 2));
    const ct_package *f = &set.ts.frame;
    TEST_ASSERT(f->base == nullptr && f->heights == nullptr);
    ct_camera cam;
    TEST_ASSERT_EQUAL_INT(CT_OK, pinhole(&cam, 64, 48, 50, 63, 47));
    int32_t q[4];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(0, dem_cases::deg_q61(-60), 0, q));
    ct_pose pose;
    const int64_t e = mp.origin_e_nm + 100 * mp.posting_e_nm, n = mp.origin_n_nm + 100 * mp.posting_n_nm;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&pose, e, n, (int64_t)1500 * 1000000000, q));
    ct_effects sphere = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16,
                         (int64_t)6371000 * 1000000000, 0, NULL};
    // from 2,000 LSB above the highest post, 256 LSB down per cell: a hit
    const ct_ray ray = {(int64_t)100 << 16, (int64_t)100 << 16, ((int64_t)mp.hmax + 2000) << 16, 1 << 16, 1 << 15,
                        -(1 << 24)};
    const ct_bend bd = {57016, CT_EARTH_RADIUS_NM, CT_EFFECTS_CHORD_NM, 0u};  // c = 0.87, as the effects
    const int64_t uv[2] = {(int64_t)32 << 16, (int64_t)24 << 16};
    const int64_t a[3] = {e, n, (int64_t)1500 * 1000000000}, b[3] = {e + 50 * mp.posting_e_nm, n, 0};
    for (int side = 0; side < 2; ++side) {
        const ct_package *p = side == 0 ? &mp : f;
        const char *who = side == 0 ? "the merged package" : "the frame";
        auto ok = [&](ct_status s) { return side == 0 ? s >= 0 : s == CT_ERR_ARG; };
        ct_hit h;
        ct_prepared pr;
        int64_t z = 0, u = 0, v = 0;
        uint32_t visible = 0;
        ct_geo g, gb[1];
        TEST_ASSERT_MSG(ok(ct_trace(p, &ray, CT_METHOD_DIRECTIONAL, &h)), "%s: ct_trace", who);
        TEST_ASSERT_MSG(ok(ct_ray_prepare(p, &ray, &pr)), "%s: ct_ray_prepare", who);
        TEST_ASSERT_MSG(ok(ct_ray_prepare_segment(p, &ray, &pr)), "%s: ct_ray_prepare_segment", who);
        TEST_ASSERT_MSG(ok(ct_trace_bent(p, &ray, &bd, CT_METHOD_DIRECTIONAL, &h)), "%s: ct_trace_bent", who);
        TEST_ASSERT_MSG(ok(ct_surface_height(p, 5 << 16, 5 << 16, &z)), "%s: ct_surface_height", who);
        TEST_ASSERT_MSG(ok(ct_package_verify(p)), "%s: ct_package_verify", who);
        TEST_ASSERT_MSG(ok(ct_los(p, a, b, &sphere, 0, CT_METHOD_DIRECTIONAL, &h)), "%s: ct_los", who);
        TEST_ASSERT_MSG(ok(ct_locate_inverse(p, &cam, &pose, NULL, b, 0, &u, &v, &visible, &h)),
                        "%s: ct_locate_inverse", who);
        TEST_ASSERT_MSG(ok(ct_geolocate(p, &cam, &pose, CT_METHOD_DIRECTIONAL, &sphere, uv[0], uv[1], &g)) &&
                            ok(g.status),
                        "%s: ct_geolocate", who);
        TEST_ASSERT_MSG(ok(ct_geolocate_batch(p, &cam, &pose, CT_METHOD_DIRECTIONAL, NULL, uv, 1, gb, 1)),
                        "%s: ct_geolocate_batch", who);
        if (side == 0) {
            // a ray prepared on the package, traced on the frame
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_ray_prepare(&mp, &ray, &pr));
            TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_trace_prepared(f, &pr, CT_METHOD_DIRECTIONAL, &h));
        }
    }
    // A set ct_tileset_open did not make ready -- never opened (zeroed), or
    // its last open failed (a truncated manifest over a set that was open)
    // -- refused by every _tiles function; the open set answers.
    Set failed;
    TEST_ASSERT_EQUAL_INT(CT_OK, failed.open(tb, 2));
    TEST_ASSERT_EQUAL_INT(CT_SET_READY, failed.ts.ready);
    const std::vector<uint8_t> cut(tb.manifest.begin(), tb.manifest.end() - 1);
    TEST_ASSERT(failed.open(tb, 2, &cut) < 0);
    ct_tileset zeroed{};
    for (int which = 0; which < 3; ++which) {
        ct_tileset *ts = which == 0 ? &set.ts : (which == 1 ? &zeroed : &failed.ts);
        auto ok = [&](ct_status st) { return which == 0 ? st >= 0 : st == CT_ERR_ARG; };
        const ct_package *frame = &set.ts.frame;  // the open set's georeference for the rays
        ct_ray gr;
        ct_hit h;
        ct_geo g, gb[1];
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_ray_from_map(frame, e, n, (int64_t)1500 * 1000000000, 1, 0, -1, &gr));
        TEST_ASSERT_MSG(ok(ct_tileset_trace(ts, &gr, CT_METHOD_DIRECTIONAL, &h)), "set %d: ct_tileset_trace", which);
        TEST_ASSERT_MSG(ok(ct_los_tiles(ts, a, b, &sphere, 0, CT_METHOD_DIRECTIONAL, &h)), "set %d: ct_los_tiles",
                        which);
        TEST_ASSERT_MSG(ok(ct_geolocate_tiles(ts, &cam, &pose, CT_METHOD_DIRECTIONAL, &sphere, uv[0], uv[1], &g)) &&
                            ok(g.status),
                        "set %d: ct_geolocate_tiles", which);
        TEST_ASSERT_MSG(ok(ct_geolocate_batch_tiles(ts, &cam, &pose, CT_METHOD_DIRECTIONAL, NULL, uv, 1, gb, 1)),
                        "set %d: ct_geolocate_batch_tiles", which);
    }
}

}  // namespace

// ---------------------------------------------------------------------------
// The streamed build (build_mosaic_dir: a band of tiles at a time, the rows
// read in chunks) makes the very files the whole-DEM build makes: a DEM
// that fits one set becomes set_0_0/ of its mosaic, byte for byte -- voids,
// the narrower last tiles, chunks that straddle bands, the height coding.

static std::vector<uint8_t> file_bytes(const std::string &p)
{
    std::vector<uint8_t> b;
    FILE *f = fopen(p.c_str(), "rb");
    if (!f) return b;
    int c;
    while ((c = fgetc(f)) != EOF) b.push_back((uint8_t)c);
    fclose(f);
    return b;
}

// The heap this process holds, and its peak since reset (the global
// operator new and delete below count every C++ allocation by its usable
// size): a build's working memory, whatever the allocator keeps resident.
static std::atomic<size_t> g_heap_now{0}, g_heap_peak{0};

void *operator new(size_t n)
{
    void *p = std::malloc(n ? n : 1);
    if (p == nullptr) throw std::bad_alloc();
    const size_t now = g_heap_now += malloc_usable_size(p);
    size_t peak = g_heap_peak.load();
    while (now > peak && !g_heap_peak.compare_exchange_weak(peak, now)) {
    }
    return p;
}
void operator delete(void *p) noexcept
{
    if (p == nullptr) return;
    g_heap_now -= malloc_usable_size(p);
    std::free(p);
}
void operator delete(void *p, size_t) noexcept { operator delete(p); }

// A mosaic's memory check (streamed_memory_estimate) counts, per tile being
// built, tile_build_memory: a tile's build streamed to a sink (as a mosaic's
// tiles are to their files) must stay within it, its terrain included, on
// one thread, at r = 1 (the builder's DT arrays per cell dominate: on this
// terrain, whose slices take full DTs, an estimate without them was 35-50 %
// of the heap) and r = 3.
static void test_tile_build_memory(void)
{
    struct Discard : ct_host::PackageSink {
        size_t n = 0;
        void write(const uint8_t *, size_t k) override { n += k; }
        void patch(size_t, const uint8_t *, size_t) override {}
    };
    const int P = 257;
    std::vector<uint16_t> z((size_t)P * P);
    for (int j = 0; j < P; ++j)
        for (int i = 0; i < P; ++i)
            z[(size_t)j * P + i] = (uint16_t)(std::lround(100 + 50 * std::sin(i / 37.0) * std::cos(j / 23.0) + 20 * std::sin((i + 2 * j) / 11.0)) - 30);
    const ct_host::Terrain t = dem_cases::make_terrain(P, P, z, 1.0);
    for (const auto rn : {std::array<int, 2>{1, 24}, std::array<int, 2>{1, 8}, std::array<int, 2>{3, 24}}) {
        ct_host::BuildOptions o;
        o.reduce = rn[0];
        o.sectors = rn[1];
        o.threads = 1;
        Discard sink;
        const size_t before = g_heap_now.load();
        g_heap_peak = before;
        ct_host::build_package_to(t, o, sink);
        const double work = (double)(g_heap_peak.load() - before) + 3.0 * P * P;
        const double est = (double)ct_host::tile_build_memory(P, o.reduce, o.sectors);
        std::printf("  P=%d r=%d N=%d: package %zu B, heap at most %.2f MB with the tile, estimate %.2f MB\n", P,
                    o.reduce, o.sectors, sink.n, work / 1e6, est / 1e6);
        TEST_ASSERT_MSG(work <= est, "r=%d N=%d: %.2f MB of heap above the estimate %.2f MB", o.reduce, o.sectors,
                        work / 1e6, est / 1e6);
    }
}

static void test_streamed_build(void)
{
    const int W = 203, H = 150;
    std::vector<double> h((size_t)W * H);
    std::vector<uint8_t> valid((size_t)W * H, 1);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const size_t k = (size_t)j * W + i;
            h[k] = 250.0 + 80.0 * std::sin(i * 0.07) * std::cos(j * 0.05) + 0.37 * ((i * 7 + j * 13) % 11);
            if ((i - 60) * (i - 60) + (j - 70) * (j - 70) < 30) valid[k] = 0;  // a void
        }
    ct_host::Georef g;
    g.origin_e = 500000.0;
    g.origin_n = 4000000.0;
    g.posting_e = 30.0;
    g.posting_n = -30.0;
    g.epsg = 32617;
    ct_host::BuildOptions o;
    o.sectors = 8;
    o.reduce = 3;
    char tmpl[] = "/tmp/ct_test_tiles_XXXXXX";
    TEST_ASSERT(mkdtemp(tmpl) != nullptr);
    const std::string root = tmpl;
    // P = 17 and 64; P = 33 with heights above EGM96 (turned ellipsoidal
    // band by band, the whole DEM's geoid grid in every tile)
    for (int P : {17, 64, 33}) {
        const int vd = P == 33 ? CT_VDATUM_EGM96 : CT_VDATUM_UNKNOWN;
        std::vector<double> hw = h;
        ct_host::GeoidGrid gw;
        ct_host::apply_vdatum(hw, valid, W, H, g, vd, gw);
        ct_host::Terrain t = ct_host::terrain_from_heights(W, H, hw, valid, g, 0.0);
        t.vdatum = vd;
        t.geoid = gw;
        const std::string whole = root + "/whole" + std::to_string(P), mosaic = root + "/mosaic" + std::to_string(P);
        ct_host::build_tileset_dir(t, o, P, whole, 2, nullptr, nullptr);
        int reads = 0;
        const ct_host::GeoidGrid gs = ct_host::vdatum_grid(g, W, H, vd);
        TEST_ASSERT(gs.w == gw.w && gs.h == gw.h && gs.um == gw.um && (vd == CT_VDATUM_UNKNOWN || gs.w > 1));
        ct_host::RowReader read = [&](int y0, int n, std::vector<double> &hh, std::vector<uint8_t> &vv) {
            TEST_ASSERT(y0 >= 0 && n >= 1 && y0 + n <= H);
            hh.assign(h.begin() + (ptrdiff_t)y0 * W, h.begin() + (ptrdiff_t)(y0 + n) * W);
            vv.assign(valid.begin() + (ptrdiff_t)y0 * W, valid.begin() + (ptrdiff_t)(y0 + n) * W);
            ct_host::apply_vdatum_rows(hh, vv, W, y0, n, g, vd, gs);
            reads++;
        };
        ct_host::StreamedSetSummary sum;
        ct_host::build_mosaic_dir(W, H, g, 0.0, vd, gs, read, 7, o, P, mosaic, 2, nullptr, &sum);
        TEST_ASSERT_EQUAL_INT(1, sum.sets_x * sum.sets_y);
        TEST_ASSERT_MSG(reads == 2 * ((H + 6) / 7), "P %d: %d chunks read (two passes of %d)", P, reads, (H + 6) / 7);
        const ct_host::TileGrid tg = ct_host::tile_grid(W, H, P);
        for (int r = 0; r < tg.tiles_y; ++r)
            for (int c = 0; c < tg.tiles_x; ++c) {
                const std::string n = ct_host::tile_file_name(c, r);
                const std::vector<uint8_t> a = file_bytes(whole + "/" + n), b = file_bytes(mosaic + "/set_0_0/" + n);
                TEST_ASSERT_MSG(!a.empty() && a == b, "P %d: %s differs (%zu vs %zu bytes)", P, n.c_str(), a.size(),
                                b.size());
            }
        TEST_ASSERT_MSG(file_bytes(whole + "/manifest.ctm") == file_bytes(mosaic + "/set_0_0/manifest.ctm"),
                        "P %d: the manifests differ", P);
    }
    std::string cmd = "rm -rf '" + root + "'";
    TEST_ASSERT(system(cmd.c_str()) == 0);
}

int main()
{
    TEST_BEGIN("test_tiles");
    RUN_TEST(test_seams);
    RUN_TEST(test_seam_touch);
    RUN_TEST(test_seam_disagree);
    RUN_TEST(test_cache_sizes);
    RUN_TEST(test_skips_tiles_above);
    RUN_TEST(test_missing_and_corrupt);
    RUN_TEST(test_manifest_checks);
    RUN_TEST(test_voids);
    RUN_TEST(test_geolocation);
    RUN_TEST(test_batch_runs);
    RUN_TEST(test_los);
    RUN_TEST(test_bent_saturated);
    RUN_TEST(test_bent_start_below_after_entered);
    RUN_TEST(test_frame_refused);
    RUN_TEST(test_streamed_build);
    RUN_TEST(test_tile_build_memory);
    return TEST_END();
}
