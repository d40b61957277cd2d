// test_trace.cpp -- the tracer against an independent long-double reference
// on many seeded rays per DEM, over ray families; all four methods must
// return bit-identical results.
//
// Per DEM: CT_TEST_RAYS rays (default 100000) x 4 methods, scaled by
// CT_TEST_SCALE; seed CT_TEST_SEED.  A result is "wrong" unless
//  - status and position agree with the reference (position within
//    POS_TOL_Q16 per axis), or
//  - the disagreement is a tangency: the ray comes within EPS_LSB of the
//    surface where the two disagree (the reference's own rounding), checked
//    analytically by ref::min_clearance.
// Wrong results must be zero.
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
#include "harness.h"
#include "judge.hpp"
#include "reference.hpp"
#include "terrain.hpp"

namespace {


struct Stats {
    long rays = 0, hits = 0, misses = 0, below = 0, tangent = 0, wrong = 0, prep_miss = 0;
    double max_err_q16 = 0;
    long steps[4] = {0, 0, 0, 0};
    long iters[4] = {0, 0, 0, 0};
    long rising_hits = 0; // hits of rays with dz > 0
};

// A ray generator: the k-th ray and its family's name.
using RayGen = std::function<ct_ray(long k, ct_rng *rng, const char **family)>;

void check_case(const dem_cases::Case &cs, long nrays, Stats *st, std::map<std::string, Stats> *fam,
                const RayGen &gen = RayGen())
{
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, cs.pkg.data(), cs.pkg.size()));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_verify(&p));
    const ref::Dem d = dem_cases::ref_dem(cs.t);
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 7919u + (uint64_t)cs.name.size() * 131u + cs.t.width);
    int reported = 0;
    double lo, hi;  // the families' heights, once (not per ray: O(posts) each)
    dem_cases::minmax(cs.t, &lo, &hi);
    for (long k = 0; k < nrays; ++k) {
        const char *fname;
        ct_ray ray;
        if (gen) {
            ray = gen(k, &rng, &fname);
        } else {
            dem_cases::Family f = (dem_cases::Family)(k % dem_cases::FAMILY_COUNT);
            ray = dem_cases::make_ray(cs.t, f, &rng, lo, hi);
            fname = dem_cases::family_name(f);
        }
        ct_prepared pr;
        ct_status ps = ct_ray_prepare(&p, &ray, &pr);
        Stats &fs = (*fam)[fname];
        st->rays++;
        fs.rays++;
        if (ps < 0) {
            TEST_FAIL_MSG("%s: prepare failed %d for family %s", cs.name.c_str(), ps, fname);
        }
        if (ps == CT_MISS) {
            st->prep_miss++;
            fs.prep_miss++;
            TEST_ASSERT_MSG(!dem_cases::ray_crosses_box(cs.t, ray),
                            "%s: prepare says MISS but the ray crosses the tile box (family %s, ray %ld: o=(%lld,%lld,%lld) "
                            "d=(%lld,%lld,%lld))",
                            cs.name.c_str(), fname, k, (long long)ray.x_q16, (long long)ray.y_q16,
                            (long long)ray.z_q16, (long long)ray.dx, (long long)ray.dy, (long long)ray.dz);
            continue;
        }
        ct_hit h[4];
        ct_status s[4];
        for (int m = 0; m < 4; ++m) {
            s[m] = ct_trace_prepared(&p, &pr, (ct_method)m, &h[m]);
            TEST_ASSERT_MSG(s[m] >= 0, "%s: trace error %d (method %d, family %s, ray %ld)", cs.name.c_str(), s[m], m,
                            fname, k);
            st->steps[m] += h[m].steps;
            st->iters[m] += h[m].iters;
            fs.steps[m] += h[m].steps;
            fs.iters[m] += h[m].iters;
        }
        for (int m = 1; m < 4; ++m) {
            bool same = s[m] == s[0];
            if (same && (s[0] == CT_HIT || s[0] == CT_HIT_VOID))
                same = h[m].x_q16 == h[0].x_q16 && h[m].y_q16 == h[0].y_q16 && h[m].z_q16 == h[0].z_q16 &&
                       h[m].t_q26 == h[0].t_q26 && h[m].cell_x == h[0].cell_x && h[m].cell_y == h[0].cell_y;
            TEST_ASSERT_MSG(same,
                            "%s: method %d differs from incremental (family %s, ray %ld): status %d vs %d, "
                            "x %lld vs %lld, y %lld vs %lld, z %lld vs %lld",
                            cs.name.c_str(), m, fname, k, s[m], s[0], (long long)h[m].x_q16,
                            (long long)h[0].x_q16, (long long)h[m].y_q16, (long long)h[0].y_q16, (long long)h[m].z_q16,
                            (long long)h[0].z_q16);
        }
        ref::Hit rh;
        double err = 0;
        const judge::Verdict v = judge::judge(d, pr, s[0], h[0], &rh, &err);
        bool lhit = s[0] == CT_HIT || s[0] == CT_HIT_VOID;
        if (v == judge::AGREE && lhit) st->max_err_q16 = std::max(st->max_err_q16, err);
        if (lhit) st->hits++;
        if (lhit && pr.dz > 0) st->rising_hits++;
        if (s[0] == CT_MISS) st->misses++;
        if (s[0] == CT_BELOW) st->below++;
        if (v == judge::AGREE) continue;
        if (v == judge::TANGENT) {
            st->tangent++;
            fs.tangent++;
            continue;
        }
        st->wrong++;
        fs.wrong++;
        if (reported++ < 5) {
            std::printf("  WRONG %s family %s ray %ld: lib status %d (%.6f, %.6f, %.6f) t=%.9f cell %d,%d; ref status %d "
                        "(%.6Lf, %.6Lf, %.6Lf) t=%.9Lf cell %d,%d\n"
                        "    prepared o=(%lld,%lld,%lld) d=(%d,%d,%d) tend=%lld/%lld\n",
                        cs.name.c_str(), fname, k, s[0], h[0].x_q16 / 65536.0, h[0].y_q16 / 65536.0,
                        h[0].z_q16 / 65536.0, h[0].t_q26 / 67108864.0, h[0].cell_x, h[0].cell_y, rh.status, rh.x, rh.y,
                        rh.z, rh.t, rh.ci, rh.cj, (long long)pr.ox, (long long)pr.oy, (long long)pr.oz, pr.dx, pr.dy,
                        pr.dz, (long long)pr.tend_n, (long long)pr.tend_d);
        }
    }
}

long rays_per_dem()
{
    const char *s = getenv("CT_TEST_RAYS");
    long n = s ? atol(s) : 100000;
    return (long)(n * ct_test_scale());
}

// Every case's rays (the families, or gen_of's per case), judged; the hits
// of rising rays over all cases added to *rising_hits when given.
void run_cases(const std::vector<dem_cases::Case> &cases,
               const std::function<RayGen(const dem_cases::Case &)> &gen_of = nullptr, long *rising_hits = nullptr)
{
    long n = rays_per_dem();
    for (const auto &cs : cases) {
        Stats st;
        std::map<std::string, Stats> fam;
        check_case(cs, n, &st, &fam, gen_of ? gen_of(cs) : RayGen());
        if (rising_hits != nullptr) *rising_hits += st.rising_hits;
        if (ct_harness_g.current_failed) return;
        std::printf("  %-22s N=%-2d r=%d: %ld rays, %ld hit, %ld miss, %ld below, %ld never enter; "
                    "tangencies %ld, wrong %ld, max |err| %.2f q16; mean steps inc %.1f hier %.1f cone %.1f dir %.1f\n",
                    cs.name.c_str(), cs.opt.sectors, cs.opt.reduce, st.rays, st.hits, st.misses, st.below, st.prep_miss,
                    st.tangent, st.wrong, st.max_err_q16, (double)st.steps[0] / st.rays, (double)st.steps[1] / st.rays,
                    (double)st.steps[2] / st.rays, (double)st.steps[3] / st.rays);
        if (st.wrong) {
            for (auto &kv : fam)
                if (kv.second.wrong)
                    std::printf("    family %-12s wrong %ld of %ld\n", kv.first.c_str(), kv.second.wrong, kv.second.rays);
        }
        TEST_ASSERT_MSG(st.wrong == 0, "%s: %ld wrong-surface results", cs.name.c_str(), st.wrong);
        TEST_ASSERT_MSG(st.max_err_q16 <= judge::POS_TOL_Q16, "position error above bound");
    }
}

void test_adversarial_dems() { run_cases(dem_cases::adversarial_cases()); }

// The default (slice) builder over the whole grid of sector counts and
// reductions the builder issue names, windows of 2 coarse cells so that far
// terrain goes through the slice DTs, and the brute-force builder on two of
// them: every method against the reference.
void test_builder_grid()
{
    std::vector<dem_cases::Case> cases;
    const int ns[] = {1, 4, 8, 16, 24, 32, 64};
    int k = 0;
    for (int n : ns)
        for (int r = 1; r <= 4; ++r, ++k) {
            int w = 41 + 3 * (k % 5), h = 37 + 2 * (k % 3);
            std::vector<uint16_t> z = dem_cases::smooth(w, h, 700 + k, 0, 30000);
            ct_rng g;
            ct_rng_seed(&g, 900 + k);
            for (int q = 0; q < 6; ++q)  // spikes and a short wall on the smooth hills
                z[(size_t)ct_rng_range(&g, 0, h - 1) * w + ct_rng_range(&g, 0, w - 1)] = 52000;
            for (int j = h / 4; j < h / 2; ++j) z[(size_t)j * w + w / 3] = 45000;
            dem_cases::Case c;
            c.name = "grid_k" + std::to_string(k);
            c.t = dem_cases::make_terrain(w, h, z, 0.05);
            c.opt.sectors = n;
            c.opt.reduce = r;
            c.opt.window = 2;
            c.opt.slices = (k % 2) ? 0 : 24;
            if (k == 13 || k == 22) {
                c.opt.builder = ct_host::PptBuilder::Brute;
                c.name += "_brute";
            }
            c.pkg = ct_host::build_package(c.t, c.opt);
            cases.push_back(std::move(c));
        }
    // a twentieth of the per-DEM rays each (28 DEMs)
    const char *env = getenv("CT_TEST_RAYS");
    char buf[32];
    std::snprintf(buf, sizeof buf, "%ld", std::max(1000L, rays_per_dem() / 20));
    std::string old = env ? env : "";
    setenv("CT_TEST_RAYS", buf, 1);
    run_cases(cases);
    if (env) setenv("CT_TEST_RAYS", old.c_str(), 1);
    else unsetenv("CT_TEST_RAYS");
}

// Rays aimed at spikes from a few cells before them, from between the
// ground and the spike's top (every other one from just below the top),
// most of them rising.  A cone holds from every point of its coarse cell,
// so at r > 1 the cone walk steps from the coarse cell's exit when the ray
// is above the apex there -- and a rising ray must then be above it where
// it is too: one that starts below the apex and leaves the cell above it
// may meet a spike's flank in between.  Spikes of every height on low
// hills at r = 2, 3, 4, with apexes at the coarse cells' tops, make those
// cases common; every method against the reference, and enough rising
// hits that the case is exercised.
void test_footprint_exits()
{
    std::vector<dem_cases::Case> cases;
    std::vector<std::vector<std::pair<int, int>>> spikes;
    const int w = 47, h = 43;
    for (int r = 2; r <= 4; ++r)
        for (int n : {8, 24}) {
            std::vector<uint16_t> z = dem_cases::smooth(w, h, 40 + r * 7 + n, 0, 12000);
            ct_rng g;
            ct_rng_seed(&g, 500 + r * 31 + n);
            std::vector<std::pair<int, int>> sp;
            for (int q = 0; q < 60; ++q) {
                int i = (int)ct_rng_range(&g, 1, w - 2), j = (int)ct_rng_range(&g, 1, h - 2);
                z[(size_t)j * w + i] = (uint16_t)(14000 + ct_rng_range(&g, 0, 50000));
                sp.emplace_back(i, j);
            }
            // the brute-force builder: apexes at the coarse cells' tops
            // (the slice builder rounds them up to its levels)
            dem_cases::Case c;
            c.name = "spike_aim_N" + std::to_string(n) + "_r" + std::to_string(r);
            c.t = dem_cases::make_terrain(w, h, z, 0.05);
            c.opt.sectors = n;
            c.opt.reduce = r;
            c.opt.builder = ct_host::PptBuilder::Brute;
            c.pkg = ct_host::build_package(c.t, c.opt);
            cases.push_back(std::move(c));
            spikes.push_back(sp);
        }
    size_t which = 0;
    long rising = 0;
    run_cases(cases, [&](const dem_cases::Case &cs) -> RayGen {
        const std::vector<std::pair<int, int>> sp = spikes[which++];
        const ct_host::Terrain *t = &cs.t;
        return [sp, t](long k, ct_rng *g, const char **family) {
            const std::pair<int, int> s = sp[(size_t)ct_rng_range(g, 0, (int64_t)sp.size() - 1)];
            double az = ct_rng_unit(g) * 6.283185307179586, u = 0.3 + 3.7 * ct_rng_unit(g);
            double x = std::clamp(s.first - u * std::cos(az), 0.0, t->width - 1.0);
            double y = std::clamp(s.second - u * std::sin(az), 0.0, t->height - 1.0);
            double ground = dem_cases::surf(*t, x, y), top = t->at(s.first, s.second);
            // every other ray starts just below the spike's top (the apex)
            double f = (k % 2) ? ct_rng_unit(g) : 1.0 - 0.02 * ct_rng_unit(g);
            double z0 = ground + 0.5 + f * std::max(0.0, top - ground);
            double el = (-10.0 + 55.0 * ct_rng_unit(g)) * M_PI / 180, d[3];
            dem_cases::metric_dir(*t, az, el, d);
            *family = el > 0 ? "aimed_rising" : "aimed_level_or_down";
            return dem_cases::to_ray(x, y, z0, d);
        };
    }, &rising);
    if (ct_harness_g.current_failed) return;
    std::printf("  rising rays' hits: %ld\n", rising);
    TEST_ASSERT_MSG(rising > (long)cases.size() * rays_per_dem() / 20, "too few rising hits (%ld) to test the case",
                    rising);
}

void test_real_dem()
{
    std::vector<dem_cases::Case> cs = dem_cases::real_cases();
    if (cs.empty()) TEST_SKIP("real fixture not available");
    run_cases(cs);
}

}  // namespace

int main()
{
    TEST_BEGIN("test_trace");
    RUN_TEST(test_adversarial_dems);
    RUN_TEST(test_builder_grid);
    RUN_TEST(test_footprint_exits);
    RUN_TEST(test_real_dem);
    return TEST_END();
}
