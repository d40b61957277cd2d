// test_embree_baseline.cpp -- checks the Embree 3 benchmark baseline
// (bench/embree_baseline.*) against analytic answers.
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "embree_baseline.hpp"
#include "harness.h"

namespace {

std::vector<uint16_t> flat_dem(int w, int h, uint16_t code) {
  return std::vector<uint16_t>(static_cast<size_t>(w) * static_cast<size_t>(h), code);
}

// z = 2x + 3y, exactly representable with z_scale 1.
constexpr int kPlaneW = 64;
constexpr int kPlaneH = 48;
std::vector<uint16_t> plane_dem() {
  std::vector<uint16_t> c(static_cast<size_t>(kPlaneW) * kPlaneH);
  size_t k = 0;
  for (int j = 0; j < kPlaneH; ++j)
    for (int i = 0; i < kPlaneW; ++i) c[k++] = static_cast<uint16_t>(2 * i + 3 * j);
  return c;
}

void test_flat_nadir_hits_at_400(void) {
  const int w = 40, h = 30;
  const auto codes = flat_dem(w, h, 100);
  EmbreeTerrain t(codes.data(), w, h, 1.0);
  ct_rng rng;
  ct_rng_seed(&rng, ct_test_seed());
  const double dir[3] = {0.0, 0.0, -1.0};
  // Random points strictly inside the footprint.
  for (int k = 0; k < 500; ++k) {
    const double org[3] = {0.01 + ct_rng_unit(&rng) * (w - 1 - 0.02), 0.01 + ct_rng_unit(&rng) * (h - 1 - 0.02),
                           500.0};
    double th = -1.0;
    const bool hit = t.intersect(org, dir, 1e9, &th);
    TEST_ASSERT_MSG(hit, "nadir ray at (%g, %g) missed", org[0], org[1]);
    TEST_ASSERT_DOUBLE_WITHIN(1e-3, 400.0, th);
  }
  // Cell centres and cell-edge midpoints (shared edges between triangles).
  for (int j = 0; j + 1 < h; ++j) {
    for (int i = 0; i + 1 < w; ++i) {
      const double pts[3][2] = {{i + 0.5, j + 0.5}, {i + 0.5, j + 0.0}, {i + 0.25, j + 0.25}};
      for (const auto& p : pts) {
        const double org[3] = {p[0], p[1], 500.0};
        double th = -1.0;
        TEST_ASSERT_MSG(t.intersect(org, dir, 1e9, &th), "nadir ray at (%g, %g) missed", p[0], p[1]);
        TEST_ASSERT_DOUBLE_WITHIN(1e-3, 400.0, th);
      }
    }
  }
}

void test_tmax_limits_hit(void) {
  const auto codes = flat_dem(8, 8, 100);
  EmbreeTerrain t(codes.data(), 8, 8, 1.0);
  const double org[3] = {3.3, 4.6, 500.0};
  const double dir[3] = {0.0, 0.0, -1.0};
  double th = -1.0;
  TEST_ASSERT_FALSE(t.intersect(org, dir, 399.0, &th));
  TEST_ASSERT_TRUE(t.intersect(org, dir, 401.0, &th));
  TEST_ASSERT_DOUBLE_WITHIN(1e-3, 400.0, th);
  // dir need not be unit length: t is in units of |dir|.
  const double dir2[3] = {0.0, 0.0, -4.0};
  TEST_ASSERT_TRUE(t.intersect(org, dir2, 1e9, &th));
  TEST_ASSERT_DOUBLE_WITHIN(1e-3, 100.0, th);
}

void test_inclined_plane_random_rays(void) {
  const auto codes = plane_dem();
  EmbreeTerrain t(codes.data(), kPlaneW, kPlaneH, 1.0);
  ct_rng rng;
  ct_rng_seed(&rng, ct_test_seed() + 17);
  const double inv_norm = 1.0 / std::sqrt(14.0);  // |(-2,-3,1)|
  const int want = static_cast<int>(400 * ct_test_scale());
  int done = 0, tries = 0;
  while (done < want) {
    TEST_ASSERT_MSG(++tries < 100 * want, "could not generate enough rays (%d of %d)", done, want);
    // Random unit direction with a downward component.
    double d[3] = {2.0 * ct_rng_unit(&rng) - 1.0, 2.0 * ct_rng_unit(&rng) - 1.0, -(0.2 + ct_rng_unit(&rng))};
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (double& c : d) c /= len;
    // Target point strictly inside the footprint; origin t0 back along the ray.
    const double px = 0.5 + ct_rng_unit(&rng) * (kPlaneW - 2);
    const double py = 0.5 + ct_rng_unit(&rng) * (kPlaneH - 2);
    const double t0 = 5.0 + ct_rng_unit(&rng) * 300.0;
    const double o[3] = {px - t0 * d[0], py - t0 * d[1], 2.0 * px + 3.0 * py - t0 * d[2]};
    // Analytic intersection of o + t d with z = 2x + 3y.
    const double denom = d[2] - 2.0 * d[0] - 3.0 * d[1];
    if (-denom * inv_norm < 0.2) continue;  // origin below the plane, or grazing
    const double t_exp = (2.0 * o[0] + 3.0 * o[1] - o[2]) / denom;
    double th = -1.0;
    const bool hit = t.intersect(o, d, 1e9, &th);
    TEST_ASSERT_MSG(hit, "ray %d (org %g %g %g, dir %g %g %g) missed; expected t=%g", done, o[0], o[1], o[2], d[0],
                    d[1], d[2], t_exp);
    TEST_ASSERT_DOUBLE_WITHIN(1e-3, t_exp, th);
    ++done;
  }
}

void test_diagonal_split(void) {
  // 2x2 posts, only (1,1) raised.  Split along (0,0)-(1,1): for x > y the
  // surface is z = 10y, for x < y it is z = 10x.  (The other diagonal would
  // give z = 0 at both probe points.)
  const uint16_t codes[4] = {0, 0, 0, 10};
  EmbreeTerrain t(codes, 2, 2, 1.0);
  const double dir[3] = {0.0, 0.0, -1.0};
  double th = -1.0;
  const double a[3] = {0.75, 0.25, 20.0};
  TEST_ASSERT_TRUE(t.intersect(a, dir, 1e9, &th));
  TEST_ASSERT_DOUBLE_WITHIN(1e-3, 20.0 - 2.5, th);
  const double b[3] = {0.2, 0.6, 20.0};
  TEST_ASSERT_TRUE(t.intersect(b, dir, 1e9, &th));
  TEST_ASSERT_DOUBLE_WITHIN(1e-3, 20.0 - 2.0, th);
  // x is the column index i, y the row index j: z_scale applies.
  EmbreeTerrain t2(codes, 2, 2, 0.5);
  TEST_ASSERT_TRUE(t2.intersect(a, dir, 1e9, &th));
  TEST_ASSERT_DOUBLE_WITHIN(1e-3, 20.0 - 1.25, th);
}

void test_upward_rays_miss(void) {
  const auto codes = flat_dem(32, 32, 100);
  EmbreeTerrain flat(codes.data(), 32, 32, 1.0);
  const auto pcodes = plane_dem();
  EmbreeTerrain plane(pcodes.data(), kPlaneW, kPlaneH, 1.0);
  ct_rng rng;
  ct_rng_seed(&rng, ct_test_seed() + 5);
  for (int k = 0; k < 300; ++k) {
    double d[3] = {2.0 * ct_rng_unit(&rng) - 1.0, 2.0 * ct_rng_unit(&rng) - 1.0, 0.05 + ct_rng_unit(&rng)};
    const double ox = ct_rng_unit(&rng) * 31.0, oy = ct_rng_unit(&rng) * 31.0;
    const double o[3] = {ox, oy, 100.5 + 50.0 * ct_rng_unit(&rng)};
    double th = -1.0;
    TEST_ASSERT_MSG(!flat.intersect(o, d, 1e9, &th), "upward ray %d hit flat DEM at t=%g", k, th);
    // Start above the highest post of z = 2x+3y: a climbing ray cannot hit.
    const double o2[3] = {ox, oy, 2.0 * (kPlaneW - 1) + 3.0 * (kPlaneH - 1) + 1.0};
    d[2] = 0.05 + ct_rng_unit(&rng);
    const double up[3] = {d[0], d[1], d[2]};
    TEST_ASSERT_MSG(!plane.intersect(o2, up, 1e9, &th), "upward ray %d hit plane DEM at t=%g", k, th);
  }
}

void test_outside_footprint_misses(void) {
  const auto codes = flat_dem(16, 12, 100);
  EmbreeTerrain t(codes.data(), 16, 12, 1.0);
  const double down[3] = {0.0, 0.0, -1.0};
  const double outside[][3] = {{-10.0, -10.0, 500.0}, {-0.5, 5.0, 500.0}, {15.5, 5.0, 500.0},
                               {7.0, 11.5, 500.0},   {7.0, -3.0, 500.0}, {100.0, 100.0, 500.0}};
  double th = -1.0;
  for (const auto& o : outside) {
    TEST_ASSERT_MSG(!t.intersect(o, down, 1e9, &th), "ray at (%g, %g) outside the footprint hit at t=%g", o[0], o[1],
                    th);
  }
  // Slanted ray that passes beside the DEM without crossing it.
  const double o[3] = {-5.0, -5.0, 200.0};
  const double d[3] = {-1.0, 0.3, -1.0};
  TEST_ASSERT_FALSE(t.intersect(o, d, 1e9, &th));
}

void test_memory_and_build_time(void) {
  const int w = 100, h = 70;
  std::vector<uint16_t> codes(static_cast<size_t>(w) * h);
  ct_rng rng;
  ct_rng_seed(&rng, ct_test_seed() + 3);
  for (auto& c : codes) c = static_cast<uint16_t>(ct_rng_range(&rng, 0, 4000));
  EmbreeTerrain t(codes.data(), w, h, 0.1);
  const size_t our_buffers = (3 * static_cast<size_t>(w) * h + 1) * sizeof(float) +
                             6 * static_cast<size_t>(w - 1) * (h - 1) * sizeof(unsigned int);
  TEST_ASSERT(t.memory_bytes() > 0);
  TEST_ASSERT_MSG(t.memory_bytes() > our_buffers, "memory_bytes %zu does not exceed our buffers %zu (monitor silent?)",
                  t.memory_bytes(), our_buffers);
  TEST_ASSERT(t.peak_build_bytes() >= t.memory_bytes());
  TEST_ASSERT(t.build_seconds() >= 0.0);
  TEST_ASSERT_EQUAL_INT(2 * (w - 1) * (h - 1), t.triangle_count());
}

void test_bad_arguments_throw(void) {
  const uint16_t codes[4] = {0, 0, 0, 0};
  bool threw = false;
  try {
    EmbreeTerrain t(codes, 1, 4, 1.0);
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  TEST_ASSERT_TRUE(threw);
  threw = false;
  try {
    EmbreeTerrain t(nullptr, 2, 2, 1.0);
  } catch (const std::invalid_argument&) {
    threw = true;
  }
  TEST_ASSERT_TRUE(threw);
}

}  // namespace

int main(void) {
  TEST_BEGIN("test_embree_baseline");
  RUN_TEST(test_flat_nadir_hits_at_400);
  RUN_TEST(test_tmax_limits_hit);
  RUN_TEST(test_inclined_plane_random_rays);
  RUN_TEST(test_diagonal_split);
  RUN_TEST(test_upward_rays_miss);
  RUN_TEST(test_outside_footprint_misses);
  RUN_TEST(test_memory_and_build_time);
  RUN_TEST(test_bad_arguments_throw);
  return TEST_END();
}
