// bench_tiles.cpp -- `make bench`, tile sets: rays and a 1024 x 768 image
// over a 4 x 4 tile set against the merged package of the same DEM (the
// fixture mirror-tiled to 2049 x 2049 posts, N = 24, r = 3; tiles of 513
// posts), one thread, directional method.  Per ray family (20,000 rays)
// and for the image: ns per ray on the merged package and on the set with
// every tile resident (16 slots, warmed), their ratio (the median of
// per-round ratios over 11 rounds; within a round the sides alternate
// every 500 rays -- 1,024 pixels -- in the order ab ba ab ..., so both
// see the same machine; ns per ray: each side's best round), and
// with caches of 4 and 1 slots the ns per ray and tile loads per ray (on
// the first 1,000 rays of each family, every 64th image row); the steps
// per ray of both.  A
// load here is a zero-copy hand-over of the tile's bytes (a memory-mapped
// file or flash) plus ct_package_open's checks, its CRC over the whole
// tile included -- what a flight computer pays per tile switch besides
// reading the tile.  Every result is also compared with the merged
// package's (it must be bit-identical; a difference is reported loudly).
// Target: with every tile it needs resident, a tile set costs <= 1.1x the
// merged package's time.
//
// Options: --quick (5,000 rays per family, every 4th pixel of the image).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
#include "tileset.hpp"

namespace {

using clk = std::chrono::steady_clock;

constexpr int kRounds = 11;

double now_ns()
{
    return (double)std::chrono::duration_cast<std::chrono::nanoseconds>(clk::now().time_since_epoch()).count();
}

const ct_host::TileSetBytes *g_set;

ct_status zero_copy_loader(void *, uint32_t col, uint32_t row, uint8_t *, size_t, const uint8_t **bytes, size_t *len)
{
    const std::vector<uint8_t> &t = g_set->tiles[(size_t)row * g_set->grid.tiles_x + col];
    *bytes = t.data();
    *len = t.size();
    return CT_OK;
}

struct Cache {
    std::vector<ct_tile_slot> slots;
    ct_tileset ts{};
    explicit Cache(int n) : slots((size_t)n)
    {
        for (auto &s : slots) s = ct_tile_slot{};
        if (ct_tileset_open(&ts, g_set->manifest.data(), g_set->manifest.size(), slots.data(), (uint32_t)n,
                            zero_copy_loader, nullptr) != CT_OK)
            std::printf("  ct_tileset_open failed\n");
    }
};

bool same(ct_status a, const ct_hit &x, ct_status b, const ct_hit &y)
{
    return a == b && (a != CT_HIT || (x.x_q16 == y.x_q16 && x.y_q16 == y.y_q16 && x.z_q16 == y.z_q16 &&
                                      x.t_q26 == y.t_q26));
}

// One round of the two sides, interleaved chunk by chunk (a(k0, k1) and
// b(k0, k1) run items [k0, k1)): chunks of `chunk` items, in the order
// a b, b a, a b, ... so that both see the same machine at millisecond
// granularity.  *na, *nb: ns per item of each side over the round.
template <class A, class B> void abba_round(A a, B b, size_t n, size_t chunk, double *na, double *nb)
{
    double ta = 0, tb = 0;
    for (size_t k0 = 0, c = 0; k0 < n; k0 += chunk, ++c) {
        const size_t k1 = std::min(n, k0 + chunk);
        for (int side = 0; side < 2; ++side) {
            const bool first_a = (c & 1) == 0;
            const double t0 = now_ns();
            if ((side == 0) == first_a)
                a(k0, k1);
            else
                b(k0, k1);
            ((side == 0) == first_a ? ta : tb) += now_ns() - t0;
        }
    }
    *na = ta / (double)n;
    *nb = tb / (double)n;
}

double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : v[v.size() / 2];
}

struct Row {
    std::string what;
    size_t n = 0;
    double merged = 0, set = 0, ratio = 0, ns4 = 0, loads4 = 0, ns1 = 0, loads1 = 0, steps_m = 0, steps_s = 0;
    long differ = 0;
};

// Rounds of abba_round: each side's best ns per item, and the median of
// the rounds' ratios b / a.
template <class A, class B> void compare(A a, B b, size_t n, size_t chunk, int rounds, Row *row)
{
    std::vector<double> ratios;
    for (int round = 0; round < rounds; ++round) {
        double na, nb;
        abba_round(a, b, n, chunk, &na, &nb);
        ratios.push_back(nb / na);
        row->merged = round == 0 ? na : std::min(row->merged, na);
        row->set = round == 0 ? nb : std::min(row->set, nb);
    }
    row->ratio = median(ratios);
}

void print_row(const Row &r)
{
    std::printf("%-14s %7zu | %8.0f %8.0f %6.3f | %6.1f %6.1f | %9.0f %7.3f | %9.0f %7.3f%s\n", r.what.c_str(), r.n,
                r.merged, r.set, r.ratio, r.steps_m, r.steps_s, r.ns4, r.loads4, r.ns1, r.loads1,
                r.differ ? "  DIFFERS FROM THE MERGED PACKAGE" : "");
}

}  // namespace

int main(int argc, char **argv)
{
    std::setvbuf(stdout, nullptr, _IOLBF, 0);  // rows as they come
    const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
    const size_t nrays = quick ? 5000 : 20000;
    const ct_host::Terrain t = dem_cases::mirror_tiled(dem_cases::real_terrain(), 2049, 2049);
    ct_host::BuildOptions o;
    o.sectors = 24;
    o.reduce = 3;
    double t0 = now_ns();
    const std::vector<uint8_t> merged = ct_host::build_package(t, o);
    const double build_merged = (now_ns() - t0) * 1e-9;
    t0 = now_ns();
    const ct_host::TileSetBytes set = ct_host::build_tileset(t, o, 513, 0);
    const double build_set = (now_ns() - t0) * 1e-9;
    g_set = &set;
    ct_package mp;
    if (ct_package_open(&mp, merged.data(), merged.size()) != CT_OK) {
        std::printf("bench_tiles: the merged package does not open\n");
        return 1;
    }
    size_t bytes = set.manifest.size();
    for (const auto &tile : set.tiles) bytes += tile.size();
    std::printf("tile sets: 2049 x 2049 posts (the fixture mirror-tiled), N = 24, r = 3: merged package %.1f MB "
                "(built in %.1f s), 4 x 4 tiles of 513 posts %.1f MB in all (built in %.1f s); one thread, "
                "directional; ns per ray (the best round; ratio: the median of 11 rounds' ratios, the sides alternating every 500 rays)\n",
                merged.size() / 1e6, build_merged, bytes / 1e6, build_set);
    std::printf("%-14s %7s | %8s %8s %6s | %6s %6s | %9s %7s | %9s %7s\n", "family", "rays", "merged", "set/16",
                "ratio", "steps", "steps", "set/4", "loads", "set/1", "loads");
    std::printf("%-14s %7s | %8s %8s %6s | %6s %6s | %9s %7s | %9s %7s\n", "", "", "ns/ray", "ns/ray", "", "merged",
                "set", "ns/ray", "/ray", "ns/ray", "/ray");
    std::vector<Row> rows;
    const dem_cases::Family fams[] = {dem_cases::OBLIQUE, dem_cases::GRAZING, dem_cases::HORIZONTAL,
                                      dem_cases::OUTSIDE};
    double worst = 0, lo, hi;
    dem_cases::minmax(t, &lo, &hi);
    for (dem_cases::Family f : fams) {
        ct_rng rng;
        ct_rng_seed(&rng, 1234u + (uint64_t)f);
        std::vector<ct_ray> rays(nrays);
        for (auto &r : rays) r = dem_cases::make_ray(t, f, &rng, lo, hi);
        std::vector<ct_hit> hm(nrays), hs(nrays);
        std::vector<ct_status> sm(nrays), ss(nrays);
        Cache all(16);
        auto run_merged = [&](size_t k0, size_t k1) {
            for (size_t k = k0; k < k1; ++k) sm[k] = ct_trace(&mp, &rays[k], CT_METHOD_DIRECTIONAL, &hm[k]);
        };
        auto run_set = [&](size_t k0, size_t k1) {
            for (size_t k = k0; k < k1; ++k)
                ss[k] = ct_tileset_trace(&all.ts, &rays[k], CT_METHOD_DIRECTIONAL, &hs[k]);
        };
        run_set(0, nrays);  // warm: every tile resident
        Row row;
        row.what = dem_cases::family_name(f);
        row.n = nrays;
        compare(run_merged, run_set, nrays, 500, kRounds, &row);
        for (size_t k = 0; k < nrays; ++k) {
            row.differ += !same(sm[k], hm[k], ss[k], hs[k]);
            row.steps_m += hm[k].steps / (double)nrays;
            row.steps_s += hs[k].steps / (double)nrays;
        }
        // small caches: every load checks the whole tile (its CRC), so on
        // the first 1,000 rays only
        const size_t nl = std::min<size_t>(nrays, 1000);
        for (int slots : {4, 1}) {
            Cache c(slots);
            const double t1 = now_ns();
            for (size_t k = 0; k < nl; ++k) ss[k] = ct_tileset_trace(&c.ts, &rays[k], CT_METHOD_DIRECTIONAL, &hs[k]);
            const double ns = (now_ns() - t1) / (double)nl;
            for (size_t k = 0; k < nl; ++k) row.differ += !same(sm[k], hm[k], ss[k], hs[k]);
            (slots == 4 ? row.ns4 : row.ns1) = ns;
            (slots == 4 ? row.loads4 : row.loads1) = (double)c.ts.loads / (double)nl;
        }
        worst = std::max(worst, row.ratio);
        print_row(row);
        rows.push_back(row);
    }
    // a 1024 x 768 pinhole image, 30 deg down from 3 km over the set's
    // north-west quarter, looking south-east across the seams
    {
        const ct_lens lens = dem_cases::centred_pinhole(1024, 768, 900);
        ct_camera cam;
        int32_t q[4];
        ct_pose pose;
        ct_camera_init(&cam, &lens);
        ct_quat_from_ypr(dem_cases::deg_q61(135), dem_cases::deg_q61(-30), 0, q);
        ct_pose_from_map(&pose, mp.origin_e_nm + 500 * mp.posting_e_nm, mp.origin_n_nm + 500 * mp.posting_n_nm,
                         (int64_t)3000 * 1000000000, q);
        const unsigned step = quick ? 4 : 1;
        const std::vector<int64_t> uv = dem_cases::pixel_grid(1024, 768, step);
        const size_t np = uv.size() / 2;
        std::vector<ct_geo> gm(np), gs(np);
        Cache all(16);
        auto run_merged = [&](size_t k0, size_t k1) {
            ct_geolocate_batch(&mp, &cam, &pose, CT_METHOD_DIRECTIONAL, nullptr, uv.data() + 2 * k0, k1 - k0,
                               gm.data() + k0, k1 - k0);
        };
        auto run_set = [&](size_t k0, size_t k1) {
            ct_geolocate_batch_tiles(&all.ts, &cam, &pose, CT_METHOD_DIRECTIONAL, nullptr, uv.data() + 2 * k0,
                                     k1 - k0, gs.data() + k0, k1 - k0);
        };
        run_set(0, np);
        Row row;
        row.what = "image 1024x768";
        row.n = np;
        compare(run_merged, run_set, np, 1024, kRounds, &row);
        auto diff = [&] {
            long d = 0;
            for (size_t k = 0; k < np; ++k) d += !same(gm[k].status, gm[k].hit, gs[k].status, gs[k].hit);
            return d;
        };
        row.differ = diff();
        for (size_t k = 0; k < np; ++k) {
            row.steps_m += gm[k].hit.steps / (double)np;
            row.steps_s += gs[k].hit.steps / (double)np;
        }
        // small caches: every 64th image row, 12 in all, in order (each
        // load checks a whole tile's CRC)
        const size_t per_row = 1024 / step, nq = 12 * per_row;
        std::vector<int64_t> uvq;
        std::vector<size_t> at;
        for (size_t v = 0; v < 12; ++v)
            for (size_t u = 0; u < per_row; ++u) {
                const size_t k = v * (64 / step) * per_row + u;
                at.push_back(k);
                uvq.push_back(uv[2 * k]);
                uvq.push_back(uv[2 * k + 1]);
            }
        std::vector<ct_geo> gq(nq);
        for (int slots : {4, 1}) {
            Cache c(slots);
            const double t1 = now_ns();
            ct_geolocate_batch_tiles(&c.ts, &cam, &pose, CT_METHOD_DIRECTIONAL, nullptr, uvq.data(), nq, gq.data(), nq);
            (slots == 4 ? row.ns4 : row.ns1) = (now_ns() - t1) / (double)nq;
            (slots == 4 ? row.loads4 : row.loads1) = (double)c.ts.loads / (double)nq;
            for (size_t k = 0; k < nq; ++k)
                row.differ += !same(gm[at[k]].status, gm[at[k]].hit, gq[k].status, gq[k].hit);
        }
        long hits = 0;
        for (const ct_geo &g : gm) hits += g.status == CT_HIT;
        worst = std::max(worst, row.ratio);
        print_row(row);
        std::printf("  (image: %ld of %zu pixels hit; ns per pixel include the unprojection)\n", hits, np);
    }
    std::printf("tile set / merged package, every tile resident: worst %.3fx (target <= 1.10x: %s)\n", worst,
                worst <= 1.10 ? "met" : "NOT met");
    return 0;
}
