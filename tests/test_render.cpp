// test_render.cpp -- `conetrace render` and host_tools/render.*: the pictures
// show what they claim.  Distances are checked pixel by pixel against brute
// force (every feature pixel, the flight library's closed-wedge test), the
// cross-section against the posts, the angle and apex maps against the
// package bytes; the CLI's PNG is read back with OpenImageIO and compared
// with the in-process picture; bad inputs leave no file.
#include <OpenImageIO/imageio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "conetrace.h"
#include "ddt.hpp"
#include "dem_cases.hpp"
#include "harness.h"
#include "render.hpp"
#include "terrain.hpp"

using namespace ct_host;

namespace {

constexpr int64_t INF64 = std::numeric_limits<int64_t>::max();

// brute-force squared distance to the nearest feature in sector s of n (n = 0: any)
std::vector<int64_t> brute_d2(int w, int h, const std::vector<uint8_t> &bits, uint32_t n, uint32_t s)
{
    int32_t bx[CT_MAX_SECTORS + 1], by[CT_MAX_SECTORS + 1];
    if (n > 0)
        for (uint32_t k = 0; k <= n; ++k) ct_sector_boundary(n, k, &bx[k], &by[k]);
    std::vector<int64_t> d((size_t)w * h, INF64);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int qy = 0; qy < h; ++qy)
                for (int qx = 0; qx < w; ++qx) {
                    if (!bits[(size_t)qy * w + qx]) continue;
                    int64_t dx = qx - x, dy = qy - y;
                    if (n > 1 && (dx || dy)) {
                        uint32_t in = 0;
                        ct_in_wedge(bx, by, n, s, dx, dy, &in);
                        if (!in) continue;
                    }
                    d[(size_t)y * w + x] = std::min(d[(size_t)y * w + x], dx * dx + dy * dy);
                }
    return d;
}

bool same(std::array<uint8_t, 3> a, std::array<uint8_t, 3> b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; }

void test_distance_pictures_vs_brute_force()
{
    ct_rng g;
    ct_rng_seed(&g, 4242);
    int checked = 0;
    for (int trial = 0; trial < 60; ++trial) {
        int w = (int)ct_rng_range(&g, 1, 23), h = (int)ct_rng_range(&g, 1, 19);
        int dens = (int)ct_rng_range(&g, 1, 40);
        std::vector<uint8_t> bits((size_t)w * h);
        for (auto &b : bits) b = (uint8_t)(ct_rng_range(&g, 0, 99) < dens);
        ddt::Prepared bm(w, h, bits.data());
        std::vector<ddt::Point> ft;
        uint32_t n = (uint32_t)(trial % 3 == 0 ? 0 : (trial % 3 == 1 ? 8 : 24));
        uint32_t s = n ? (uint32_t)ct_rng_range(&g, 0, (int)n - 1) : 0;
        std::vector<int64_t> d2;
        if (n == 0)
            ddt::unconstrained(bm, ddt::EuclideanSq(), d2, ft);
        else
            ddt::directional(bm, n, s, ddt::EuclideanSq(), d2, ft);
        std::vector<int64_t> ref = brute_d2(w, h, bits, n, s);
        double dmax = std::max(1.0, render::max_distance(ref));
        TEST_ASSERT_MSG(std::fabs(render::max_distance(d2) - render::max_distance(ref)) < 1e-12, "max distance");
        render::Image im = render::distance_image(w, h, d2, dmax);
        TEST_ASSERT_EQUAL_INT(w, im.w);
        TEST_ASSERT_EQUAL_INT(h, im.h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                int64_t r = ref[(size_t)y * w + x];
                std::array<uint8_t, 3> want = r == 0 ? render::FEATURE
                                              : r == INF64 ? render::NO_FEATURE
                                                           : render::ramp(std::sqrt((double)r) / dmax);
                TEST_ASSERT_MSG(same(im.at(x, y), want), "trial %d (%dx%d, N=%u s=%u): pixel (%d,%d) colour differs", trial,
                                w, h, n, s, x, y);
                checked++;
            }
    }
    std::printf("  %d pixels match brute force\n", checked);
    // the ramp is monotone in green from its first stop up (distances readable)
    TEST_ASSERT_MSG(render::ramp(0.0)[1] < render::ramp(0.5)[1] && render::ramp(0.5)[1] < render::ramp(1.0)[1],
                    "ramp not increasing");
}

void test_cross_section_and_package_maps()
{
    Terrain t = dem_cases::real_terrain();
    if (t.width == 0) TEST_SKIP("real fixture not available");
    render::Cells c = render::cells_from_terrain(t);
    TEST_ASSERT_EQUAL_INT(t.width - 1, c.w);
    double level = t.height_offset_m + 9000 * t.height_scale_m;
    std::vector<uint8_t> bits = render::cross_section(c, level);
    size_t ones = 0;
    for (int j = 0; j < c.h; ++j)
        for (int i = 0; i < c.w; ++i) {
            bool any = false;  // a post of the cell at or above the level
            for (int dj = 0; dj < 2; ++dj)
                for (int di = 0; di < 2; ++di)
                    any = any || t.height_offset_m + t.at(i + di, j + dj) * t.height_scale_m >= level;
            TEST_ASSERT_MSG(any == (bits[(size_t)j * c.w + i] != 0), "cross-section wrong at cell (%d,%d)", i, j);
            ones += any;
        }
    TEST_ASSERT_MSG(ones > 0 && ones < bits.size(), "degenerate cross-section (%zu of %zu)", ones, bits.size());
    render::Image bi = render::bitmap_image(c, bits);
    for (int j = 0; j < c.h; j += 7)
        for (int i = 0; i < c.w; i += 5) {
            auto p = bi.at(i, j);
            bool brown = p[0] > p[1] && p[1] > p[2], grey = p[0] == p[1] && p[1] == p[2];
            TEST_ASSERT_MSG(bits[(size_t)j * c.w + i] ? brown : grey, "bitmap pixel (%d,%d) colour", i, j);
        }

    BuildOptions o;
    o.sectors = 8;
    o.reduce = 3;
    std::vector<uint8_t> b = build_package(t, o);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, b.data(), b.size()));
    render::Cells pc = render::cells_from_package(p);
    TEST_ASSERT_EQUAL_INT(c.w, pc.w);
    for (size_t k = 0; k < c.top_m.size(); ++k)
        TEST_ASSERT_MSG(std::fabs(c.top_m[k] - pc.top_m[k]) < 1e-6, "package cell heights differ at %zu", k);
    for (uint32_t plane = 0; plane < p.planes; plane += 3) {
        render::Image ai = render::angle_image(p, plane);
        TEST_ASSERT_EQUAL_INT((int)p.coarse_x, ai.w);
        for (uint32_t j = 0; j < p.coarse_y; ++j)
            for (uint32_t i = 0; i < p.coarse_x; ++i) {
                uint8_t code = p.angles[(size_t)plane * p.coarse_x * p.coarse_y + (size_t)j * p.coarse_x + i];
                auto want = (code == 0 || !p.cot_ok[code]) ? render::DEGENERATE : render::ramp(code / 128.0);
                TEST_ASSERT_MSG(same(ai.at((int)i, (int)j), want), "angle pixel (%u,%u) plane %u", i, j, plane);
            }
    }
    render::Image ap = render::apex_image(p);
    // grey levels ordered like the apexes
    for (uint32_t k = 1; k < p.coarse_x * p.coarse_y; k += 17) {
        int a0 = p.apex[0] | (p.apex[1] << 8), a1 = p.apex[2 * k] | (p.apex[2 * k + 1] << 8);
        int g0 = ap.at(0, 0)[0], g1 = ap.at((int)(k % p.coarse_x), (int)(k / p.coarse_x))[0];
        TEST_ASSERT_MSG((a0 < a1) ? g0 <= g1 : (a0 > a1 ? g0 >= g1 : g0 == g1), "apex grey order at %u", k);
    }
}

std::string tmpdir()
{
    char tmpl[] = "/tmp/ct_test_render_XXXXXX";
    const char *d = mkdtemp(tmpl);
    return d ? d : "/tmp";
}

int run(const std::string &cmd)
{
    int rc = std::system((cmd + " >/dev/null 2>&1").c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

bool exists(const std::string &p)
{
    struct stat st;
    return stat(p.c_str(), &st) == 0;
}

void test_cli_png_round_trip()
{
    std::string d = tmpdir(), dem = std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif";
    std::string out = d + "/ddt.png";
    std::string cmd = std::string(CT_CLI) + " render " + dem + " --what ddt --level 560 --sectors 8 --sector 0,5 --scale 2 -o " + out;
    TEST_ASSERT_MSG(run(cmd) == 0, "render failed: %s", cmd.c_str());
    auto in = OIIO::ImageInput::open(out);
    TEST_ASSERT_MSG(in != nullptr, "cannot read %s back", out.c_str());
    const OIIO::ImageSpec &spec = in->spec();
    std::vector<uint8_t> px((size_t)spec.width * spec.height * 3);
    TEST_ASSERT_MSG(spec.nchannels == 3 && in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data()), "read_image");
    in->close();
    // the same picture in process
    Terrain t = dem_cases::real_terrain();
    render::Cells c = render::cells_from_terrain(t);
    std::vector<uint8_t> bits = render::cross_section(c, 560.0);
    ddt::Prepared bm(c.w, c.h, bits.data());
    std::vector<ddt::Point> ft;
    std::vector<int64_t> a, b;
    ddt::directional(bm, 8, 0, ddt::EuclideanSq(), a, ft);
    ddt::directional(bm, 8, 5, ddt::EuclideanSq(), b, ft);
    double dmax = std::max(1.0, std::max(render::max_distance(a), render::max_distance(b)));
    render::Image want = render::enlarge(
        render::side_by_side({render::distance_image(c.w, c.h, a, dmax), render::distance_image(c.w, c.h, b, dmax)}, 4), 2);
    TEST_ASSERT_EQUAL_INT(want.w, spec.width);
    TEST_ASSERT_EQUAL_INT(want.h, spec.height);
    TEST_ASSERT_MSG(px == want.rgb, "the PNG differs from the in-process picture");

    // bad inputs: one line, non-zero exit, no output left behind
    std::string pkgless = d + "/angles.png";
    TEST_ASSERT_MSG(run(std::string(CT_CLI) + " render " + dem + " --what angles -o " + pkgless) != 0, "angles of a DEM");
    TEST_ASSERT_MSG(!exists(pkgless), "output left after a refused render");
    TEST_ASSERT_MSG(run(std::string(CT_CLI) + " render " + dem + " --what dt -o " + d + "/x.jpg") != 0, "non-png output");
    TEST_ASSERT_MSG(run(std::string(CT_CLI) + " render " + dem + " --what bogus -o " + d + "/y.png") != 0, "bad --what");
    TEST_ASSERT_MSG(run(std::string(CT_CLI) + " render " + d + "/missing.tif --what dt -o " + d + "/z.png") != 0, "missing input");
    TEST_ASSERT_MSG(run(std::string(CT_CLI) + " render " + dem + " --what dt -o " + d + "/nodir/z.png") != 0, "unwritable output");
    TEST_ASSERT_MSG(!exists(d + "/y.png") && !exists(d + "/z.png") && !exists(d + "/x.jpg"), "partial outputs left");
    // only ddt.png remains in the directory (no temporaries)
    int files = 0;
    for (const char *f : {"/ddt.png"}) files += exists(d + f);
    TEST_ASSERT_EQUAL_INT(1, files);
    std::string ls = "test $(ls " + d + " | wc -l) -eq 1";
    TEST_ASSERT_MSG(std::system(ls.c_str()) == 0, "temporary files left in %s", d.c_str());
}

}  // namespace

int main()
{
    TEST_BEGIN("test_render");
    RUN_TEST(test_distance_pictures_vs_brute_force);
    RUN_TEST(test_cross_section_and_package_maps);
    RUN_TEST(test_cli_png_round_trip);
    return TEST_END();
}
