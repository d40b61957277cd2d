// bench.cpp -- `make bench`: steps and time per ray, per ray family and
// method, on the bundled real DEM used as a square 30 m grid (and on a
// 2048x2048 mirror-tiled copy), with the incremental method as the baseline
// ratio and (when built with Embree) Embree 3's rtcIntersect1 beside it.
// Everything is measured in one run; nothing here is a pass/fail test.
//
// Options: --quick (fewer rays, no 2048 DEM), --rays N (per family),
//          --no-2048; for profiling: --family NAME, --method 0..3, --r R,
//          --loop S (repeat the timed loop S seconds), --azimuth DEG (all
//          rays in one direction: one sector plane, mostly in cache).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
#include "terrain.hpp"
#include "families.hpp"

#ifdef CT_HAVE_EMBREE
#include "embree_baseline.hpp"
#endif

namespace {

double g_azimuth = -1;  // --azimuth DEG: every ray (nearly) in this direction, one sector's plane

using clk = std::chrono::steady_clock;

struct Result {
    double mean_steps = 0, median_steps = 0, ns = 0;
    long hits = 0;
};

// ns per ray of one pass of m over the rays
double time_pass(const ct_package &p, const std::vector<ct_ray> &rays, ct_method m)
{
    ct_hit h;
    uint64_t sink = 0;
    auto t0 = clk::now();
    for (const ct_ray &ray : rays) {
        ct_trace(&p, &ray, m, &h);
        sink += (uint64_t)h.x_q16;
    }
    double ns = std::chrono::duration<double, std::nano>(clk::now() - t0).count() / std::max<size_t>(1, rays.size());
    if (sink == 42) std::printf(" ");
    return ns;
}

// steps and hits of m over the rays (untimed); ns left to the caller
Result count(const ct_package &p, const std::vector<ct_ray> &rays, ct_method m, std::vector<ct_hit> *out)
{
    Result res;
    std::vector<uint32_t> steps(rays.size());
    out->resize(rays.size());
    for (size_t k = 0; k < rays.size(); ++k) {
        ct_status s = ct_trace(&p, &rays[k], m, &(*out)[k]);
        steps[k] = (*out)[k].steps;
        res.hits += (s == CT_HIT || s == CT_HIT_VOID);
    }
    double sum = 0;
    for (uint32_t s : steps) sum += s;
    res.mean_steps = rays.empty() ? 0 : sum / rays.size();
    std::vector<uint32_t> sorted = steps;
    std::sort(sorted.begin(), sorted.end());
    res.median_steps = sorted.empty() ? 0 : sorted[sorted.size() / 2];
    return res;
}

// one method alone (--method): its steps and its best of 3 passes
Result run(const ct_package &p, const std::vector<ct_ray> &rays, ct_method m, std::vector<ct_hit> *out)
{
    Result res = count(p, rays, m, out);
    res.ns = 1e30;
    for (int rep = 0; rep < 3; ++rep) res.ns = std::min(res.ns, time_pass(p, rays, m));
    return res;
}

#ifdef CT_HAVE_EMBREE
// Embree's rays: the origins and unit directions of ours
std::vector<std::array<double, 6>> embree_rays(const std::vector<ct_ray> &rays)
{
    std::vector<std::array<double, 6>> rr;
    for (const ct_ray &r : rays) {
        double m = std::max(std::fabs((double)r.dx), std::max(std::fabs((double)r.dy), std::fabs((double)r.dz)));
        rr.push_back({r.x_q16 / 65536.0, r.y_q16 / 65536.0, r.z_q16 / 65536.0, r.dx / m, r.dy / m, r.dz / m});
    }
    return rr;
}

double embree_pass(const EmbreeTerrain &e, const std::vector<std::array<double, 6>> &rr, long *hits)
{
    long h = 0;
    double t;
    auto t0 = clk::now();
    for (const auto &q : rr) h += e.intersect(q.data(), q.data() + 3, 1e7, &t);
    *hits = h;
    return std::chrono::duration<double, std::nano>(clk::now() - t0).count() / std::max<size_t>(1, rr.size());
}
#endif

int g_slices = 0, g_window = 12;  // --slices K, --window R (slice builder)
bool g_only_slices = false;
std::string g_family;      // --family NAME: only this ray family
int g_method = -1;         // --method M (0..3): only this method
double g_loop_s = 0;       // --loop S: repeat the timed loop for S seconds (for perf)
std::vector<int> g_reduces; // --r R (repeatable): only these reductions

void bench_dem(const char *title, const ct_host::Terrain &t, int n, const std::vector<int> &reduces,
               const std::vector<ct_host::PptBuilder> &builders)
{
    std::printf("\n=== %s: %dx%d posts, 30 m grid, %.4g m per LSB ===\n", title, t.width, t.height, t.height_scale_m);
    size_t dem_bytes = (size_t)t.width * t.height * 2;
#ifdef CT_HAVE_EMBREE
    EmbreeTerrain emb(t.codes.data(), t.width, t.height, 1.0);
    std::printf("Embree 3 scene: %.1f MB (%.1fx the DEM), built in %.2f s\n", emb.memory_bytes() / 1e6,
                (double)emb.memory_bytes() / dem_bytes, emb.build_seconds());
#endif
    for (ct_host::PptBuilder builder : builders)
    for (int r : reduces) {
        if (!g_reduces.empty() && std::find(g_reduces.begin(), g_reduces.end(), r) == g_reduces.end()) continue;
        ct_host::BuildOptions o;
        o.sectors = 24;
        o.reduce = r;
        o.builder = builder;
        o.slices = g_slices;
        o.window = g_window;
        const char *bname = builder == ct_host::PptBuilder::Brute ? "brute-force builder" : "slice builder";
        ct_host::BuildStats bs;
        std::vector<uint8_t> pkg = ct_host::build_package(t, o, &bs);
        ct_package p;
        if (ct_package_open(&p, pkg.data(), pkg.size()) != CT_OK) {
            std::printf("package did not open\n");
            return;
        }
        std::printf("\npackage N=24 r=%d, %s: %zu bytes = %.2fx the 16-bit DEM (built in %.1f s, %.2f%% degenerate cones)\n", r, bname,
                    pkg.size(), (double)pkg.size() / dem_bytes, bs.seconds,
                    100.0 * bs.degenerate_cones / std::max<size_t>(1, bs.cones));
        auto fams = make_families(t, p, n, 2024, g_azimuth);
        std::printf("%-11s %6s | %-13s %9s %7s %9s %9s %9s\n", "family", "rays", "method", "steps", "median", "ns/ray",
                    "x fewer", "x faster");
        for (const auto &f : fams) {
            if (f.rays.empty() || (!g_family.empty() && f.name != g_family)) continue;
            if (g_method >= 0) {
                std::vector<ct_hit> hv;
                Result one = run(p, f.rays, (ct_method)g_method, &hv);
                auto t0 = clk::now();
                ct_hit h;
                uint64_t sink = 0;
                while (std::chrono::duration<double>(clk::now() - t0).count() < g_loop_s)
                    for (const ct_ray &ray : f.rays) {
                        ct_trace(&p, &ray, (ct_method)g_method, &h);
                        sink += (uint64_t)h.x_q16;
                    }
                std::printf("%-11s %6zu | method %d %9.1f %7.0f %9.0f%s\n", f.name.c_str(), f.rays.size(), g_method,
                            one.mean_steps, one.median_steps, one.ns, sink == 42 ? " " : "");
                continue;
            }
            Result base;
            std::vector<ct_hit> hs[4];
            Result res[4];
            for (int m = 0; m < 4; ++m) res[m] = count(p, f.rays, (ct_method)m, &hs[m]);
            // Timed in alternating rounds, every method (and Embree) once a
            // round, the order reversed every other round, so that all of
            // them see the same machine (its speed drifts by tens of percent
            // within seconds); each side's best of 3 rounds.  In a round a
            // side first takes an untimed pass: the one before it (Embree's
            // 25 MB scene, say) has evicted its data from the caches, which
            // back-to-back passes of one method would find warm.
            int sides = 4;
#ifdef CT_HAVE_EMBREE
            double ens = 1e30;
            long eh = 0;
            std::vector<std::array<double, 6>> rr = embree_rays(f.rays);
            sides = 5;
#endif
            for (int m = 0; m < 4; ++m) res[m].ns = 1e30;
            for (int round = 0; round < 3; ++round)
                for (int q = 0; q < sides; ++q) {
                    int s = round % 2 ? sides - 1 - q : q;
                    if (s < 4) {
                        (void)time_pass(p, f.rays, (ct_method)s);
                        res[s].ns = std::min(res[s].ns, time_pass(p, f.rays, (ct_method)s));
                    }
#ifdef CT_HAVE_EMBREE
                    else {
                        (void)embree_pass(emb, rr, &eh);
                        ens = std::min(ens, embree_pass(emb, rr, &eh));
                    }
#endif
                }
            base = res[0];
            const char *mn[4] = {"incremental", "hierarchical", "cone", "directional"};
            for (int m = 0; m < 4; ++m) {
                std::printf("%-11s %6zu | %-13s %9.1f %7.0f %9.0f %9.2f %9.2f\n", m == 0 ? f.name.c_str() : "",
                            f.rays.size(), mn[m], res[m].mean_steps, res[m].median_steps, res[m].ns,
                            base.mean_steps / std::max(1e-9, res[m].mean_steps), base.ns / res[m].ns);
            }
            std::printf("%-11s %6s   directional vs cone: %.2fx fewer steps\n", "", "",
                        res[2].mean_steps / std::max(1e-9, res[3].mean_steps));
#ifdef CT_HAVE_EMBREE
            std::printf("%-11s %6s   embree %.0f ns/ray (%ld hits vs our %ld): directional/embree time = %.2f\n", "", "", ens,
                        eh, res[3].hits, res[3].ns / ens);
#endif
        }
    }
}

}  // namespace

int main(int argc, char **argv)
{
    bool quick = false, big = true, brute_big = false;
    int n = 20000;
    for (int k = 1; k < argc; ++k) {
        if (!std::strcmp(argv[k], "--quick")) {
            quick = true;
            n = 2000;
            big = false;
        } else if (!std::strcmp(argv[k], "--rays") && k + 1 < argc) {
            n = std::atoi(argv[++k]);
        } else if (!std::strcmp(argv[k], "--slices") && k + 1 < argc) {
            g_slices = std::atoi(argv[++k]);
        } else if (!std::strcmp(argv[k], "--window") && k + 1 < argc) {
            g_window = std::atoi(argv[++k]);
        } else if (!std::strcmp(argv[k], "--only-slices")) {
            g_only_slices = true;
        } else if (!std::strcmp(argv[k], "--azimuth") && k + 1 < argc) {
            g_azimuth = std::atof(argv[++k]);
        } else if (!std::strcmp(argv[k], "--family") && k + 1 < argc) {
            g_family = argv[++k];
        } else if (!std::strcmp(argv[k], "--method") && k + 1 < argc) {
            g_method = std::atoi(argv[++k]);
        } else if (!std::strcmp(argv[k], "--loop") && k + 1 < argc) {
            g_loop_s = std::atof(argv[++k]);
        } else if (!std::strcmp(argv[k], "--r") && k + 1 < argc) {
            g_reduces.push_back(std::atoi(argv[++k]));
        } else if (!std::strcmp(argv[k], "--no-2048")) {
            big = false;
        } else if (!std::strcmp(argv[k], "--brute-2048")) {
            brute_big = true;  // the brute-force builder takes minutes at 2048^2
        }
    }
    ct_host::Terrain t = dem_cases::real_terrain();
    using B = ct_host::PptBuilder;
    if (g_only_slices)
        bench_dem("jacksboro_fault_dem (fixture)", t, n, {1, 3}, {B::Slices});
    else
        bench_dem("jacksboro_fault_dem (fixture)", t, n, {1, 3}, {B::Slices, B::Brute});
    if (big && !quick) {
        const ct_host::Terrain b = dem_cases::mirror_tiled(t, 2048, 2048);
        if (brute_big)
            bench_dem("jacksboro mirror-tiled", b, n, {3}, {B::Slices, B::Brute});
        else
            bench_dem("jacksboro mirror-tiled", b, n, {3}, {B::Slices});
    }
    return 0;
}
