// soak.cpp -- `make soak`: many seeded rays and pixels on freshly generated terrain,
// every result judged against the long-double reference (judge.hpp), the
// four methods compared with each other and the iteration bounds checked.
// Time-boxed; not part of `make test`.
//
// Each terrain is new: a smooth field, the same with isolated spikes, the
// same cut into terraces (cliffs), or one of the adversarial DEMs, of a
// random size (9..160 posts a side) and height range (1..60,000 codes),
// built with a random N in {1, 3, 8, 24} and r in {1, 2, 3}; 4,000 rays of
// every family per terrain, and 4,000 pixels of a camera posed over it
// (soak_pixels), and rows of neighbouring pixels through ct_geolocate_batch
// (its runs) against ct_geolocate, and through ct_geolocate_batch_tiles on
// the terrain cut into a tile set (random tile size, cache slots, a tile
// left out now and then) against ct_geolocate_tiles.
//
// Usage: ct_soak [--rays N] [--seconds S] [--threads T] [--seed K]
// (defaults: 10^7 rays, 1,800 s, all cores, seed 1).  Exit 1 when any
// result is wrong, the methods differ, or a bound is exceeded.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
#include "judge.hpp"
#include "reference.hpp"
#include "tileset.hpp"

namespace {

struct Counts {
    long terrains = 0, rays = 0, hits = 0, misses = 0, below = 0, tangent = 0, wrong = 0, differ = 0, bound = 0,
         errors = 0;
    // pixels: geolocated with each method; their grid ray formed again from
    // the pose and ct_geo (ct_ray_from_map) and traced must give the same hit
    long pixels = 0, pixel_hits = 0, pixel_unprojected = 0, pixel_retrace_differ = 0;
    // the batch's runs: rows of neighbouring pixels through ct_geolocate_batch
    // against ct_geolocate, pixel by pixel
    long batch_pixels = 0, batch_differ = 0, batch_shortened = 0;
    // ... and over a tile set against ct_geolocate_tiles
    long set_pixels = 0, set_differ = 0, set_shortened = 0, set_nodata = 0;
    long set_calls = 0, set_more_loads = 0, set_fewer_loads = 0;  // batch calls; loads against the single calls
    long tangent_by[dem_cases::FAMILY_COUNT] = {};
    long tangent_both_hit = 0; // both hit, positions apart by more than judge::POS_TOL_Q16
    double worst_xy = 0, worst_z = 0; // the largest such distances (Q16)
    void add(const Counts &o)
    {
        for (int f = 0; f < dem_cases::FAMILY_COUNT; ++f) tangent_by[f] += o.tangent_by[f];
        tangent_both_hit += o.tangent_both_hit;
        worst_xy = std::max(worst_xy, o.worst_xy);
        worst_z = std::max(worst_z, o.worst_z);
        terrains += o.terrains;
        rays += o.rays;
        hits += o.hits;
        misses += o.misses;
        below += o.below;
        tangent += o.tangent;
        wrong += o.wrong;
        differ += o.differ;
        bound += o.bound;
        errors += o.errors;
        pixels += o.pixels;
        pixel_hits += o.pixel_hits;
        pixel_unprojected += o.pixel_unprojected;
        pixel_retrace_differ += o.pixel_retrace_differ;
        batch_pixels += o.batch_pixels;
        batch_differ += o.batch_differ;
        batch_shortened += o.batch_shortened;
        set_pixels += o.set_pixels;
        set_differ += o.set_differ;
        set_shortened += o.set_shortened;
        set_nodata += o.set_nodata;
        set_calls += o.set_calls;
        set_more_loads += o.set_more_loads;
        set_fewer_loads += o.set_fewer_loads;
    }
};

std::mutex g_print;

bool same(ct_status a, const ct_hit &x, ct_status b, const ct_hit &y)
{
    if (a != b) return false;
    if (a != CT_HIT && a != CT_HIT_VOID) return true;
    return x.x_q16 == y.x_q16 && x.y_q16 == y.y_q16 && x.z_q16 == y.z_q16 && x.t_q26 == y.t_q26 &&
           x.cell_x == y.cell_x && x.cell_y == y.cell_y;
}

// Terrain number k of this seed: its codes, size and build options.
dem_cases::Case make_terrain(uint64_t seed, const std::vector<dem_cases::Case> &adv)
{
    ct_rng r;
    ct_rng_seed(&r, seed);
    const int kind = (int)ct_rng_range(&r, 0, 3);
    const int sectors[] = {1, 3, 8, 24};
    const int N = sectors[ct_rng_range(&r, 0, 3)], R = (int)ct_rng_range(&r, 1, 3);
    if (kind == 3 && !adv.empty()) {
        const dem_cases::Case &c = adv[(size_t)ct_rng_range(&r, 0, (int64_t)adv.size() - 1)];
        return dem_cases::make_case(c.name, c.t, N, R);
    }
    const int w = (int)ct_rng_range(&r, 9, 160), h = (int)ct_rng_range(&r, 9, 160);
    const double lo = (double)ct_rng_range(&r, 0, 2000), span = (double)ct_rng_range(&r, 1, 60000);
    std::vector<uint16_t> z = dem_cases::smooth(w, h, ct_rng_u64(&r), lo, std::min(65535.0, lo + span));
    if (kind == 1) {  // isolated spikes
        const int n = (int)ct_rng_range(&r, 1, 12);
        for (int k = 0; k < n; ++k)
            z[(size_t)ct_rng_range(&r, 0, (int64_t)z.size() - 1)] = (uint16_t)std::min(65535.0, lo + span);
    } else if (kind == 2) {  // terraces: cliffs between flat steps
        const uint16_t step = (uint16_t)std::max<int64_t>(1, ct_rng_range(&r, 1, (int64_t)span / 3 + 1));
        for (auto &v : z) v = (uint16_t)(v / step * step);
    }
    const char *names[] = {"smooth", "spikes", "terraces"};
    return dem_cases::make_case(names[kind], dem_cases::make_terrain(w, h, z, 0.5), N, R);
}

// One traced result judged against the reference: counts, and a line for
// a wrong one.  f == FAMILY_COUNT: a pixel's ray.
void judge_one(const dem_cases::Case &cs, const ref::Dem &d, uint64_t seed, const char *what, int f, const ct_ray &ray,
               const ct_prepared &pr, ct_status s0, const ct_hit &h0, Counts *c)
{
    ref::Hit rh;
    double err = 0;
    const judge::Verdict v = judge::judge(d, pr, s0, h0, &rh, &err);
    c->hits += s0 == CT_HIT || s0 == CT_HIT_VOID;
    c->misses += s0 == CT_MISS;
    c->below += s0 == CT_BELOW;
    if (v == judge::TANGENT) {
        c->tangent++;
        if (f < dem_cases::FAMILY_COUNT) c->tangent_by[f]++;
        if ((s0 == CT_HIT || s0 == CT_HIT_VOID) && rh.status == ref::HIT) {
            c->tangent_both_hit++;
            c->worst_xy = std::max({c->worst_xy, std::fabs((double)(h0.x_q16 - rh.x * 65536)),
                                    std::fabs((double)(h0.y_q16 - rh.y * 65536))});
            c->worst_z = std::max(c->worst_z, std::fabs((double)(h0.z_q16 - rh.z * 65536)));
        }
    }
    if (v == judge::WRONG) {
        c->wrong++;
        std::lock_guard<std::mutex> g(g_print);
        std::printf("  WRONG: terrain %s (seed %llu, %d x %d, N %d, r %d), %s, ray (%lld, %lld, %lld) "
                    "(%lld, %lld, %lld): status %d, reference %d\n",
                    cs.name.c_str(), (unsigned long long)seed, cs.t.width, cs.t.height, cs.opt.sectors, cs.opt.reduce,
                    what, (long long)ray.x_q16, (long long)ray.y_q16, (long long)ray.z_q16, (long long)ray.dx,
                    (long long)ray.dy, (long long)ray.dz, s0, (int)rh.status);
    }
}

// A generated terrain opened once for its rays and its pixels: the package,
// the reference's DEM and the height range.
struct Soaked {
    const dem_cases::Case &cs;
    ct_package p;
    ref::Dem d;
    double lo = 0, hi = 0;
    explicit Soaked(const dem_cases::Case &c) : cs(c), d(dem_cases::ref_dem(c.t)) { dem_cases::minmax(c.t, &lo, &hi); }
};

void soak_terrain(const Soaked &sk, uint64_t seed, long nrays, Counts *c)
{
    const dem_cases::Case &cs = sk.cs;
    const ct_package &p = sk.p;
    const ref::Dem &d = sk.d;
    const double lo = sk.lo, hi = sk.hi;
    const uint32_t bound_cells = CT_WCET_CELL_ITERS(p.cells_x, p.cells_y);
    const uint32_t bound_hier = CT_WCET_HIER_ITERS(p.cells_x, p.cells_y, p.levels);
    ct_rng rng;
    ct_rng_seed(&rng, seed * 2654435761u + 17u);
    c->terrains++;
    for (long k = 0; k < nrays; ++k) {
        const dem_cases::Family f = (dem_cases::Family)(k % dem_cases::FAMILY_COUNT);
        const ct_ray ray = dem_cases::make_ray(cs.t, f, &rng, lo, hi);
        ct_prepared pr;
        const ct_status ps = ct_ray_prepare(&p, &ray, &pr);
        c->rays++;
        if (ps < 0) {
            c->errors++;
            continue;
        }
        if (ps == CT_MISS) {
            c->misses++;
            if (dem_cases::ray_crosses_box(cs.t, ray)) c->wrong++;
            continue;
        }
        ct_hit h[4];
        ct_status s[4];
        for (int m = 0; m < 4; ++m) {
            s[m] = ct_trace_prepared(&p, &pr, (ct_method)m, &h[m]);
            if (s[m] < 0) c->errors++;
            if (h[m].iters > (m == CT_METHOD_HIERARCHICAL ? bound_hier : bound_cells)) c->bound++;
        }
        for (int m = 1; m < 4; ++m) c->differ += !same(s[m], h[m], s[0], h[0]);
        judge_one(cs, d, seed, dem_cases::family_name(f), f, ray, pr, s[0], h[0], c);
    }
}

// Pixels: a pinhole camera (640 x 480, focal length 150..1500 px) at a
// random point above or beside the terrain (up to 5 km above its top)
// looking at a random point of its surface (roll -30..30 deg), npx random
// pixels geolocated (straight lines of sight) with each method: the four
// identical; the pixel's grid ray formed again from the pose centre and
// ct_geo's map direction by ct_ray_from_map and traced gives the same hit,
// bit for bit; and that ray judged against the reference as the rays are.
void soak_pixels(const Soaked &sk, uint64_t seed, long npx, Counts *c)
{
    const dem_cases::Case &cs = sk.cs;
    const ct_package &p = sk.p;
    const ref::Dem &d = sk.d;
    const double hi = sk.hi;
    ct_rng rng;
    ct_rng_seed(&rng, seed * 40503u + 99u);
    const ct_lens lens = dem_cases::centred_pinhole(640, 480, ct_rng_range(&rng, 150, 1500));
    ct_camera cam;
    if (ct_camera_init(&cam, &lens) != CT_OK) {
        c->errors++;
        return;
    }
    // the centre: anywhere over the tile or up to half its size beside it,
    // looking at a random point of the surface (so most pixels see terrain)
    const double gx = (ct_rng_unit(&rng) * 2 - 0.5) * (cs.t.width - 1), gy = (ct_rng_unit(&rng) * 2 - 0.5) * (cs.t.height - 1);
    const double tx = ct_rng_unit(&rng) * (cs.t.width - 1), ty = ct_rng_unit(&rng) * (cs.t.height - 1);
    const double up_m = 1 + ct_rng_unit(&rng) * 5000;
    int64_t e, n, h, te, tn, th;
    if (ct_grid_to_map(&p, std::llround(gx * 65536), std::llround(gy * 65536), std::llround(hi * 65536), &e, &n, &h) !=
            CT_OK ||
        ct_grid_to_map(&p, std::llround(tx * 65536), std::llround(ty * 65536),
                       std::llround(dem_cases::surf(cs.t, tx, ty) * 65536), &te, &tn, &th) != CT_OK) {
        c->errors++;
        return;
    }
    h += std::llround(up_m * 1e9);
    const double de = (te - e) * 1e-9, dn = (tn - n) * 1e-9, dh = (th - h) * 1e-9;
    const double yaw = std::atan2(de, dn) * 180 / M_PI, pitch = std::atan2(dh, std::hypot(de, dn)) * 180 / M_PI;
    int32_t q[4];
    ct_pose pose;
    if (ct_quat_from_ypr(dem_cases::deg_q61(yaw), dem_cases::deg_q61(pitch), dem_cases::deg_q61(ct_rng_unit(&rng) * 60 - 30),
                         q) != CT_OK ||
        ct_pose_from_map(&pose, e, n, h, q) != CT_OK) {
        c->errors++;
        return;
    }
    for (long k = 0; k < npx; ++k) {
        const int64_t u = ct_rng_range(&rng, 0, 639 << 16), v = ct_rng_range(&rng, 0, 479 << 16);
        ct_geo g[4];
        ct_status s[4];
        for (int m = 0; m < 4; ++m) s[m] = ct_geolocate(&p, &cam, &pose, (ct_method)m, nullptr, u, v, &g[m]);
        c->pixels++;
        for (int m = 1; m < 4; ++m) c->differ += !same(s[m], g[m].hit, s[0], g[0].hit);
        if (s[0] == CT_ERR_RAY || s[0] == CT_ERR_LENS) continue;  // outside the lens's field: nothing to trace
        if (s[0] < 0) {
            c->errors++;
            continue;
        }
        c->pixel_unprojected++;
        ct_ray ray;
        if (ct_ray_from_map(&p, pose.e_nm, pose.n_nm, pose.h_nm, g[0].dir_map_q39[0], g[0].dir_map_q39[1],
                            g[0].dir_map_q39[2], &ray) != CT_OK) {
            c->errors++;
            continue;
        }
        ct_hit rh;
        const ct_status rs = ct_trace(&p, &ray, CT_METHOD_DIRECTIONAL, &rh);
        c->pixel_retrace_differ += !same(rs, rh, s[0], g[0].hit);
        c->pixel_hits += s[0] == CT_HIT || s[0] == CT_HIT_VOID;
        ct_prepared pr;
        const ct_status ps = ct_ray_prepare(&p, &ray, &pr);
        if (ps < 0) {
            c->errors++;
            continue;
        }
        if (ps == CT_MISS) {
            if (dem_cases::ray_crosses_box(cs.t, ray)) c->wrong++;
            continue;
        }
        judge_one(cs, d, seed, "pixel", dem_cases::FAMILY_COUNT, ray, pr, s[0], g[0].hit, c);
    }
    // the batch's runs: rows of 16 pixels 1/4 to 2 px apart, straight and on
    // a small sphere (the lowered walk), every method
    const ct_effects sphere = {CT_EFFECT_CURVATURE, 0, INT64_C(1) << 50, 0, nullptr};
    std::vector<int64_t> uv;
    for (long r = 0; r < std::max(1L, npx / 64); ++r) {
        const int64_t u0 = ct_rng_range(&rng, 0, 600 << 16), v = ct_rng_range(&rng, 0, 479 << 16);
        const int64_t du = ct_rng_range(&rng, 16384, 131072);
        for (int k = 0; k < 16; ++k) {
            uv.push_back(u0 + k * du);
            uv.push_back(v);
        }
    }
    const size_t nb = uv.size() / 2;
    std::vector<ct_geo> batch(nb);
    for (const ct_effects *fx : {(const ct_effects *)nullptr, &sphere})
        for (int m = 0; m < 4; ++m) {
            if (ct_geolocate_batch(&p, &cam, &pose, (ct_method)m, fx, uv.data(), nb, batch.data(), nb) != CT_OK) {
                c->errors++;
                continue;
            }
            for (size_t k = 0; k < nb; ++k) {
                ct_geo g;
                const ct_status st = ct_geolocate(&p, &cam, &pose, (ct_method)m, fx, uv[2 * k], uv[2 * k + 1], &g);
                c->batch_pixels++;
                c->batch_differ += !same(st, g.hit, batch[k].status, batch[k].hit);
                c->batch_shortened += batch[k].hit.steps < g.hit.steps;
            }
        }
    // the same rows over the terrain cut into a tile set: tiles of 3 posts
    // up to the whole, 1 to 4 slots or one per tile, a tile left out in a
    // quarter of the sets (CT_NO_DATA where a line of sight reaches it,
    // the same point from the batch and the single call)
    const int side = std::max(cs.t.width, cs.t.height);  // at most 64 tiles a side
    const int P = (int)ct_rng_range(&rng, std::max(3, (side - 2) / 64 + 2), side);
    const bool hole = ct_rng_range(&rng, 0, 3) == 0;
    const int64_t hc = ct_rng_range(&rng, 0, 63), hr = ct_rng_range(&rng, 0, 63);
    const ct_host::TileSetBytes tb = ct_host::build_tileset(cs.t, cs.opt, P, 1, [&](int col, int row) {
        return hole && col == hc % ((cs.t.width - 2) / (P - 1) + 1) && row == hr % ((cs.t.height - 2) / (P - 1) + 1);
    });
    const int ntiles = (int)tb.tiles.size();
    const int nslots = ct_rng_range(&rng, 0, 1) ? ntiles : (int)ct_rng_range(&rng, 1, 4);
    struct Loader {
        static ct_status load(void *user, uint32_t col, uint32_t row, uint8_t *, size_t, const uint8_t **bytes,
                              size_t *len)
        {
            const ct_host::TileSetBytes *b = static_cast<const ct_host::TileSetBytes *>(user);
            const std::vector<uint8_t> &v = b->tiles[(size_t)row * b->grid.tiles_x + col];
            if (v.empty()) return CT_ERR_ARG;
            *bytes = v.data();
            *len = v.size();
            return CT_OK;
        }
    };
    for (const ct_effects *fx : {(const ct_effects *)nullptr, &sphere})
        for (int m = 0; m < 4; ++m) {
            std::vector<ct_tile_slot> sa((size_t)std::min(nslots, (int)CT_SET_MAX_SLOTS)), sb(sa.size());
            ct_tileset ta, tsb;
            if (ct_tileset_open(&ta, tb.manifest.data(), tb.manifest.size(), sa.data(), (uint32_t)sa.size(),
                                Loader::load, (void *)&tb) != CT_OK ||
                ct_tileset_open(&tsb, tb.manifest.data(), tb.manifest.size(), sb.data(), (uint32_t)sb.size(),
                                Loader::load, (void *)&tb) != CT_OK ||
                ct_geolocate_batch_tiles(&ta, &cam, &pose, (ct_method)m, fx, uv.data(), nb, batch.data(), nb) !=
                    CT_OK) {
                c->errors++;
                continue;
            }
            for (size_t k = 0; k < nb; ++k) {
                ct_geo g;
                const ct_status st = ct_geolocate_tiles(&tsb, &cam, &pose, (ct_method)m, fx, uv[2 * k], uv[2 * k + 1], &g);
                const ct_hit &x = batch[k].hit, &y = g.hit;
                const bool placed = st == CT_HIT || st == CT_HIT_VOID || st == CT_NO_DATA;
                c->set_pixels++;
                const bool dif = batch[k].status != st ||
                                 (placed && (x.x_q16 != y.x_q16 || x.y_q16 != y.y_q16 || x.z_q16 != y.z_q16 ||
                                             x.t_q26 != y.t_q26 || x.cell_x != y.cell_x || x.cell_y != y.cell_y ||
                                             x.e_nm != y.e_nm || x.n_nm != y.n_nm || x.h_nm != y.h_nm));
                c->set_differ += dif;
                if (dif) {
                    std::lock_guard<std::mutex> lk(g_print);
                    std::printf("  SET DIFFERS: terrain %s (seed %llu, %d x %d, N %d, r %d), tiles of %d posts, %d slots, "
                                "hole %d, effects %d, method %d, pixel %zu: batch %d (cell %d,%d t %lld) vs single %d "
                                "(cell %d,%d t %lld)\n",
                                cs.name.c_str(), (unsigned long long)seed, cs.t.width, cs.t.height, cs.opt.sectors,
                                cs.opt.reduce, P, nslots, (int)hole, fx != nullptr, m, k, batch[k].status, x.cell_x,
                                x.cell_y, (long long)x.t_q26, st, y.cell_x, y.cell_y, (long long)y.t_q26);
                }
                c->set_shortened += x.steps < y.steps;
                c->set_nodata += st == CT_NO_DATA;
            }
            // a run fetches only the tile its rays' walks would, and a ray it
            // shows clear through that tile skips it: with one slot (a load
            // per change of tile) or a slot per tile the batch never loads
            // more than the single calls; with a few slots the skipped
            // visits change which tile the LRU slot drops, either way
            c->set_calls++;
            if (ta.loads > tsb.loads) {
                c->set_more_loads++;
                if (sa.size() == 1 || sa.size() >= tb.tiles.size()) {
                    c->set_differ++;
                    std::lock_guard<std::mutex> lk(g_print);
                    std::printf("  SET LOADS MORE: terrain %s (seed %llu, %d x %d), tiles of %d posts, %zu slots, "
                                "hole %d, effects %d, method %d: batch %u, single %u\n",
                                cs.name.c_str(), (unsigned long long)seed, cs.t.width, cs.t.height, P, sa.size(),
                                (int)hole, fx != nullptr, m, (unsigned)ta.loads, (unsigned)tsb.loads);
                }
            }
            c->set_fewer_loads += ta.loads < tsb.loads;
        }
}

}  // namespace

int main(int argc, char **argv)
{
    long total = 10000000;
    double seconds = 1800;
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    uint64_t seed = 1;
    for (int a = 1; a + 1 < argc; a += 2) {
        if (!std::strcmp(argv[a], "--rays")) total = std::atol(argv[a + 1]);
        else if (!std::strcmp(argv[a], "--seconds")) seconds = std::atof(argv[a + 1]);
        else if (!std::strcmp(argv[a], "--threads")) threads = (unsigned)std::max(1, std::atoi(argv[a + 1]));
        else if (!std::strcmp(argv[a], "--seed")) seed = (uint64_t)std::atoll(argv[a + 1]);
        else {
            std::fprintf(stderr, "ct_soak: unknown option %s\n", argv[a]);
            return 2;
        }
    }
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    const auto t0 = std::chrono::steady_clock::now();
    auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    const std::vector<dem_cases::Case> adv = dem_cases::adversarial_cases();
    const long per_terrain = 4000;
    std::atomic<long> next{0}, done{0};
    std::vector<Counts> counts(threads);
    std::vector<std::thread> pool;
    for (unsigned w = 0; w < threads; ++w)
        pool.emplace_back([&, w] {
            while (done.load() < total && elapsed() < seconds) {
                const uint64_t k = (uint64_t)next++;
                const dem_cases::Case cs = make_terrain(seed * 1000003u + k, adv);
                Soaked sk(cs);
                if (ct_package_open(&sk.p, cs.pkg.data(), cs.pkg.size()) != CT_OK) {
                    counts[w].errors++;
                } else {
                    soak_terrain(sk, seed * 1000003u + k, per_terrain, &counts[w]);
                    soak_pixels(sk, seed * 1000003u + k, per_terrain, &counts[w]);
                }
                const long d = (done += per_terrain);
                if (d / 200000 != (d - per_terrain) / 200000) {
                    std::lock_guard<std::mutex> g(g_print);
                    std::printf("  %ld rays and as many pixels, %.0f s\n", d, elapsed());
                }
            }
        });
    for (auto &t : pool) t.join();
    Counts c;
    for (const Counts &x : counts) c.add(x);
    std::printf("soak: %ld rays and %ld pixels x 4 methods on %ld generated terrains in %.0f s (%u threads, seed "
                "%llu): %ld hits, %ld misses, %ld below; against the reference %ld wrong, methods differing %ld, bounds "
                "exceeded %ld, errors %ld\n",
                c.rays, c.pixels, c.terrains, elapsed(), threads, (unsigned long long)seed, c.hits, c.misses, c.below,
                c.wrong, c.differ, c.bound, c.errors);
    std::printf("  pixels (one camera per terrain): %ld unprojected, %ld hit; the pixel's ray formed again from the "
                "pose and ct_geo by ct_ray_from_map and traced: %ld differ from ct_geolocate's hit\n",
                c.pixel_unprojected, c.pixel_hits, c.pixel_retrace_differ);
    std::printf("  the batch's runs (rows of 16 neighbouring pixels, straight and on a 2^50 nm sphere, 4 methods): %ld "
                "pixels, %ld differ from ct_geolocate's, %ld walks shortened\n",
                c.batch_pixels, c.batch_differ, c.batch_shortened);
    std::printf("  the same rows over the terrain cut into a tile set (random tiles and slots, a tile missing in a "
                "quarter of the sets): %ld pixels, %ld differ from ct_geolocate_tiles' (or loaded more with 1 slot or "
                "one per tile), %ld CT_NO_DATA, %ld walks shortened; of %ld batch calls %ld loaded fewer tiles than the "
                "single calls, %ld more (2-4 slots: LRU)\n",
                c.set_pixels, c.set_differ, c.set_nodata, c.set_shortened, c.set_calls, c.set_fewer_loads,
                c.set_more_loads);
    std::printf("  disputes the judge settles as tangent (the reference's ray within 1e-6 LSB of the surface there): "
                "%ld, of them %ld where both hit -- x and y at most %.1f Q16 apart (the stated bound: 2), z up to "
                "%.1f (steep cells: 2 Q16 across a cliff is many codes up); by family:",
                c.tangent, c.tangent_both_hit, c.worst_xy, c.worst_z);
    for (int f = 0; f < dem_cases::FAMILY_COUNT; ++f)
        std::printf(" %s %ld", dem_cases::family_name((dem_cases::Family)f), c.tangent_by[f]);
    std::printf("\n");
    return (c.wrong || c.differ || c.bound || c.errors || c.pixel_retrace_differ || c.batch_differ ||
            c.set_differ) ? 1 : 0;
}
