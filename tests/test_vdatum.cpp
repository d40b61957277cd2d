// test_vdatum.cpp -- the vertical datum: a DEM's EGM96 heights turned into
// WGS84 ellipsoidal heights by the builder, and the package's geoid grid
// read by the library (ct_geoid_at), both against PROJ by an independent
// route (EPSG:326zz+5773 "UTM + EGM96 height" -> EPSG:4979 "WGS 84 3D"
// through PROJ's database, not the builder's vgridshift pipeline); the
// datum section's evil variants, each with its own status.
#include <proj.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "conetrace.h"
#include "dem_io.hpp"
#include "harness.h"
#include "proj_pair.hpp"
#include "le.hpp"
#include "terrain.hpp"
#include "vdatum.hpp"

using namespace ct_host;

namespace {

const std::string kDem = std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif";

// N (metres) at UTM (E, N) by PROJ: (E, N, 0 m above EGM96) -> WGS84 3D
struct ProjGeoid : ProjPair {
    explicit ProjGeoid(int epsg) : ProjPair(("EPSG:" + std::to_string(epsg) + "+5773").c_str(), "EPSG:4979") {}
    double at(double e, double n) const
    {
        PJ_COORD c = proj_trans(pj, PJ_FWD, proj_coord(e, n, 0.0, 0.0));
        return c.xyz.z;
    }
};

struct Built {
    DemRaster dem;
    Terrain t;
    std::vector<uint8_t> pkg;
};

Built build(int vdatum)
{
    Built b;
    b.dem = read_dem(kDem);
    std::vector<double> h = b.dem.h;
    GeoidGrid g;
    apply_vdatum(h, b.dem.valid, b.dem.width, b.dem.height, b.dem.geo, vdatum, g);
    b.t = terrain_from_heights(b.dem.width, b.dem.height, h, b.dem.valid, b.dem.geo, 0.015625);
    b.t.vdatum = vdatum;
    b.t.geoid = g;
    BuildOptions o;
    o.sectors = 4;
    b.pkg = build_package(b.t, o);
    return b;
}

void recrc(std::vector<uint8_t> &p)
{
    std::memset(&p[12], 0, 4);
    uint32_t c = 0;
    ct_crc32(0u, p.data(), p.size(), &c);
    put32(p, 12, c);
}

// the geoid the package carries, at seeded points of the tile, against PROJ
void test_geoid_vs_proj()
{
    Built b = build(CT_VDATUM_EGM96);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, b.pkg.data(), b.pkg.size()));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_verify(&p));
    TEST_ASSERT_EQUAL_INT(CT_VDATUM_EGM96, (int)p.vdatum);
    TEST_ASSERT(p.geoid.w >= 2 && p.geoid.h >= 2);
    ProjGeoid pg(32617);
    TEST_ASSERT_MSG(pg.pj != nullptr, "PROJ cannot make EPSG:32617+5773 -> EPSG:4979");
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 31 + 7);
    const double w = (p.width - 1) * 30.0, h = (p.height - 1) * 30.0;
    double worst = 0, mean = 0, nmin = 1e9, nmax = -1e9;
    const int npts = 4000;
    for (int k = 0; k < npts; ++k) {
        const double e = p.origin_e_nm * 1e-9 + 15 + ct_rng_unit(&rng) * w;
        const double n = p.origin_n_nm * 1e-9 - 15 - ct_rng_unit(&rng) * h;
        int64_t nn = 0;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_geoid(&p, (int64_t)std::llround(e * 1e9), (int64_t)std::llround(n * 1e9), &nn));
        const double ref = pg.at(e, n);
        TEST_ASSERT_MSG(std::isfinite(ref), "PROJ gave no undulation at %.3f %.3f", e, n);
        const double d = std::fabs(nn * 1e-9 - ref);
        worst = std::max(worst, d);
        mean += d / npts;
        nmin = std::min(nmin, ref);
        nmax = std::max(nmax, ref);
    }
    std::printf("  geoid grid %ux%u: N %.3f..%.3f m; |library - PROJ| mean %.4f mm, max %.4f mm (%d points)\n",
                p.geoid.w, p.geoid.h, nmin, nmax, mean * 1e3, worst * 1e3, npts);
    TEST_ASSERT_MSG(worst <= 0.0001, "geoid grid off PROJ by %.4f mm", worst * 1e3);
}

// where the geoid is steep and curved (the Puerto Rico trench: N falls by
// tens of metres over a 61 km tile, zone 19N), the grid the builder makes
// against PROJ
void test_geoid_steep()
{
    struct Place {
        int epsg;
        double e0, n0;
    };
    const Place places[] = {{32619, 150000.0, 2150000.0}, {32745, 300000.0, 9200000.0}, {32645, 400000.0, 3200000.0}};
    for (const Place &pl : places) {
        Georef g;
        g.epsg = pl.epsg;
        g.origin_e = pl.e0;
        g.origin_n = pl.n0;
        const int w = 2049, h = 2049;
        Egm96 egm;
        GeoidGrid grid = make_geoid_grid(egm, g, w, h);
        ProjGeoid pg(g.epsg);
        TEST_ASSERT(pg.pj != nullptr);
        ct_rng rng;
        ct_rng_seed(&rng, ct_test_seed() * 131 + (uint64_t)pl.epsg);
        double worst = 0, nmin = 1e9, nmax = -1e9;
        for (int k = 0; k < 4000; ++k) {
            const double e = g.origin_e + 15 + ct_rng_unit(&rng) * (w - 1) * 30.0;
            const double n = g.origin_n - 15 - ct_rng_unit(&rng) * (h - 1) * 30.0;
            const double ref = pg.at(e, n), got = geoid_at(grid, g.epsg, e, n);
            TEST_ASSERT(std::isfinite(ref) && std::isfinite(got));
            worst = std::max(worst, std::fabs(got - ref));
            nmin = std::min(nmin, ref);
            nmax = std::max(nmax, ref);
        }
        std::printf("  EPSG:%d, 61 km tile: N %.2f..%.2f m, grid %dx%d; |library - PROJ| max %.4f mm\n", pl.epsg, nmin,
                    nmax, grid.w, grid.h, worst * 1e3);
        TEST_ASSERT_MSG(worst <= 0.0001, "EPSG:%d: geoid grid off PROJ by %.3f mm", pl.epsg, worst * 1e3);
    }
}

// the stored heights: source + N (PROJ) within the quantisation; and the
// library's h - N gives the source height back
void test_heights_converted()
{
    Built b = build(CT_VDATUM_EGM96);
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, b.pkg.data(), b.pkg.size()));
    ProjGeoid pg(32617);
    TEST_ASSERT(pg.pj != nullptr);
    const double q = p.height_scale_nm * 1e-9;
    double worst_proj = 0, worst_back = 0;
    for (uint32_t j = 0; j < p.height; j += 7)
        for (uint32_t i = 0; i < p.width; i += 5) {
            const double e = (p.origin_e_nm + (2 * (int64_t)i + 1) * p.posting_e_nm / 2) * 1e-9;
            const double n = (p.origin_n_nm + (2 * (int64_t)j + 1) * p.posting_n_nm / 2) * 1e-9;
            const uint32_t code = (uint32_t)p.heights[2 * ((size_t)j * p.width + i)] |
                                  (uint32_t)p.heights[2 * ((size_t)j * p.width + i) + 1] << 8;
            const double h_pkg = (p.height_offset_nm + (int64_t)code * p.height_scale_nm) * 1e-9;
            const double h_src = b.dem.h[(size_t)j * p.width + i];
            int64_t nn = 0;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_geoid(&p, (int64_t)std::llround(e * 1e9), (int64_t)std::llround(n * 1e9), &nn));
            worst_back = std::max(worst_back, std::fabs(h_pkg - nn * 1e-9 - h_src));
            worst_proj = std::max(worst_proj, std::fabs(h_pkg - (h_src + pg.at(e, n))));
        }
    std::printf("  heights: |stored - (source + N_PROJ)| max %.2f mm, |stored - N_grid - source| max %.2f mm "
                "(quantum %.1f mm)\n", worst_proj * 1e3, worst_back * 1e3, q * 1e3);
    TEST_ASSERT(worst_back <= q / 2 + 1e-6);
    TEST_ASSERT(worst_proj <= q / 2 + 0.002);
}

// ellipsoidal sources pass through; unknown datums carry nothing
void test_pass_through()
{
    Built e = build(CT_VDATUM_WGS84), u = build(CT_VDATUM_UNKNOWN);
    ct_package pe, pu;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&pe, e.pkg.data(), e.pkg.size()));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&pu, u.pkg.data(), u.pkg.size()));
    TEST_ASSERT_EQUAL_INT(CT_VDATUM_WGS84, (int)pe.vdatum);
    TEST_ASSERT_EQUAL_INT(CT_VDATUM_UNKNOWN, (int)pu.vdatum);
    TEST_ASSERT(pe.geoid.w >= 2);
    TEST_ASSERT_EQUAL_INT(0, (int)pu.geoid.w);
    TEST_ASSERT_EQUAL_INT(0, (int)(pu.flags & CT_PKG_FLAG_DATUM));
    TEST_ASSERT(e.t.codes == u.t.codes);
    TEST_ASSERT_EQUAL_INT(0, std::memcmp(pe.heights, pu.heights, 2u * pe.width * pe.height));
    int64_t nn = 0;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_package_geoid(&pu, pu.origin_e_nm, pu.origin_n_nm, &nn));
    // a datum needs a UTM CRS
    Georef g = e.dem.geo;
    g.epsg = 4326;
    std::vector<double> h = e.dem.h;
    GeoidGrid gg;
    bool threw = false;
    try {
        apply_vdatum(h, e.dem.valid, e.dem.width, e.dem.height, g, CT_VDATUM_EGM96, gg);
    } catch (const Error &) {
        threw = true;
    }
    TEST_ASSERT(threw);
}

// bilinear interpolation at and between nodes, edges inclusive
void test_geoid_at_grid()
{
    const int32_t um[6] = {1000, 3000, -5000, 2000, 4000, 2147483647};
    uint8_t le[24];
    for (int k = 0; k < 6; ++k) put32(le + 4 * k, (uint32_t)um[k]);
    const int64_t s = INT64_C(1) << 53;  // about 0.22 deg
    const int64_t lat0 = INT64_C(1) << 60, lon0 = -(INT64_C(1) << 61);
    ct_geoid_grid g = {3u, 2u, lat0, lon0, s, le};
    int64_t n = 0;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_geoid_at(&g, lat0, lon0, &n));
    TEST_ASSERT_MSG(n == INT64_C(1000000), "node %lld", (long long)n);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_geoid_at(&g, lat0 - s, lon0 + 2 * s, &n));  // last node, inclusive
    TEST_ASSERT_MSG(n == INT64_C(2147483647000), "last node %lld", (long long)n);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_geoid_at(&g, lat0 - s / 2, lon0 + s / 2, &n));
    TEST_ASSERT_MSG(n == INT64_C(2500000), "centre %lld", (long long)n);  // (1 + 3 + 2 + 4) mm / 4
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_geoid_at(&g, lat0, lon0 - 1, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_geoid_at(&g, lat0, lon0 + 2 * s + 1, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_geoid_at(&g, lat0 + 1, lon0, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_geoid_at(&g, lat0 - s - 1, lon0, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_geoid_at(&g, INT64_MIN, INT64_MAX, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_geoid_at(&g, lat0, CT_PI_Q61 + 1, &n));      // longitude beyond pi
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_geoid_at(&g, -CT_PI_Q61 / 2 - 1, lon0, &n)); // latitude beyond -pi/2
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_geoid_at(nullptr, 0, 0, &n));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_geoid_at(&g, 0, 0, nullptr));
    ct_geoid_grid bad = g;
    bad.step_q61 = CT_GEOID_MAX_STEP_Q61 + 1;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RANGE, ct_geoid_at(&bad, lat0, lon0, &n));
    // across the antimeridian: nodes at 180 - s, 180, 180 + s (= -180 + s)
    ct_geoid_grid am = {3u, 2u, lat0, CT_PI_Q61 - s, s, le};
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_geoid_at(&am, lat0, -CT_PI_Q61 + s / 2, &n));
    TEST_ASSERT_MSG(std::llabs(n - INT64_C(-1000000)) <= 1, "across 180 deg %lld", (long long)n);  // 3 mm .. -5 mm halfway
    // monotone along a row between two nodes (1 -> 3 mm)
    int64_t prev = INT64_MIN;
    for (int k = 0; k <= 64; ++k) {
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_geoid_at(&g, lat0, lon0 + s / 64 * k, &n));
        TEST_ASSERT(n >= prev && std::llabs(n - (1000000 + 2000000 * k / 64)) <= 4);
        prev = n;
    }
}

// the datum section's evil variants
void test_datum_section_evil()
{
    Built b = build(CT_VDATUM_EGM96);
    const size_t off = get32(b.pkg, CT_HDR_DATUM);
    TEST_ASSERT(off > 0 && off % 8 == 0);
    struct Case {
        const char *name;
        void (*mutate)(std::vector<uint8_t> &, size_t);
        ct_status expect;
    };
    const Case cases[] = {
        {"flag without offset", [](std::vector<uint8_t> &p, size_t) { put32(p, CT_HDR_DATUM, 0); }, CT_ERR_OFFSET},
        {"offset without flag", [](std::vector<uint8_t> &p, size_t) { p[23] &= (uint8_t)~CT_PKG_FLAG_DATUM; }, CT_ERR_FLAGS},
        {"offset misaligned", [](std::vector<uint8_t> &p, size_t o) { put32(p, CT_HDR_DATUM, (uint32_t)o + 4); }, CT_ERR_OFFSET},
        {"offset inside the angles", [](std::vector<uint8_t> &p, size_t) { put32(p, CT_HDR_DATUM, get32(p, CT_HDR_SECTION_TABLE + 8 * CT_SEC_ANGLES)); }, CT_ERR_OFFSET},
        {"offset past the end", [](std::vector<uint8_t> &p, size_t) { put32(p, CT_HDR_DATUM, (get32(p, 8) - 32) & ~7u); }, CT_ERR_OFFSET},
        {"unknown datum code", [](std::vector<uint8_t> &p, size_t o) { p[o] = CT_VDATUM_COUNT; }, CT_ERR_RANGE},
        {"reserved word set", [](std::vector<uint8_t> &p, size_t o) { p[o + 12] = 1; }, CT_ERR_RANGE},
        {"reserved half-word set", [](std::vector<uint8_t> &p, size_t o) { p[o + 6] = 1; }, CT_ERR_RANGE},
        {"one node per row", [](std::vector<uint8_t> &p, size_t o) { p[o + 2] = 1; p[o + 3] = 0; }, CT_ERR_DIMS},
        {"rows without a row width", [](std::vector<uint8_t> &p, size_t o) { p[o + 2] = 0; p[o + 3] = 0; }, CT_ERR_DIMS},
        {"grid beyond the package", [](std::vector<uint8_t> &p, size_t o) { p[o + 4] = 200; p[o + 5] = 0; }, CT_ERR_SIZE},
        {"zero step", [](std::vector<uint8_t> &p, size_t o) { std::memset(&p[o + 32], 0, 8); }, CT_ERR_GEOREF},
        {"latitude beyond 90 deg", [](std::vector<uint8_t> &p, size_t o) { p[o + 23] = 0x7f; }, CT_ERR_GEOREF},
        {"longitude beyond 180 deg", [](std::vector<uint8_t> &p, size_t o) { p[o + 31] = 0x70; }, CT_ERR_GEOREF},
        {"extent beyond 2^62", [](std::vector<uint8_t> &p, size_t o) { std::memset(&p[o + 32], 0, 8); p[o + 39] = 1; p[o + 2] = 66; p[o + 3] = 0; }, CT_ERR_GEOREF},
    };
    for (const Case &c : cases) {
        std::vector<uint8_t> p = b.pkg;
        c.mutate(p, off);
        recrc(p);
        ct_package pk;
        const ct_status st = ct_package_open(&pk, p.data(), p.size());
        TEST_ASSERT_MSG(st == c.expect, "%s: status %d, expected %d", c.name, (int)st, (int)c.expect);
    }
    // a grid-less section (heights ellipsoidal, no geoid) opens
    std::vector<uint8_t> p = b.pkg;
    std::memset(&p[off + 2], 0, 4);
    recrc(p);
    ct_package pk;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&pk, p.data(), p.size()));
    TEST_ASSERT_EQUAL_INT(0, (int)pk.geoid.w);
}

// `conetrace build --vdatum`: the package says what was done; bad values
// and CRSs without a geoid are one-line errors with no output left behind
int sh(const std::string &cmd) { return std::system((cmd + " >/dev/null 2>&1").c_str()); }

void test_cli_vdatum()
{
    char tmpl[] = "/tmp/ct_vdatum_XXXXXX";
    TEST_ASSERT(mkdtemp(tmpl) != nullptr);
    const std::string d = tmpl, cli = CT_CLI;
    TEST_ASSERT_EQUAL_INT(0, sh(cli + " build " + kDem + " -o " + d + "/v.ctp --sectors 4 --vdatum egm96"));
    TEST_ASSERT_EQUAL_INT(0, std::system((cli + " info " + d + "/v.ctp > " + d + "/info.txt").c_str()));
    std::FILE *f = std::fopen((d + "/info.txt").c_str(), "r");
    TEST_ASSERT(f != nullptr);
    char buf[4096];
    size_t n = std::fread(buf, 1, sizeof buf - 1, f);
    std::fclose(f);
    buf[n] = 0;
    TEST_ASSERT_MSG(std::strstr(buf, "vertical      WGS84 ellipsoidal heights (the DEM's were above the EGM96 geoid)") &&
                        std::strstr(buf, "geoid         EGM96, 4 x 4 nodes every 0.25 deg"), "info:\n%s", buf);
    // bad value: usage error, nothing written
    TEST_ASSERT(sh(cli + " build " + kDem + " -o " + d + "/b.ctp --vdatum egm2008") != 0);
    TEST_ASSERT(access((d + "/b.ctp").c_str(), F_OK) != 0);
    // a DEM without a CRS: one line naming the file
    DemRaster r = read_dem(kDem);
    Georef g = r.geo;
    g.epsg = 0;  // georeferenced, but on no known CRS
    write_geotiff(d + "/merc.tif", r.width, r.height, r.h, SampleType::Int16, g);
    TEST_ASSERT(std::system((cli + " build " + d + "/merc.tif -o " + d + "/m.ctp --vdatum egm96 2>" + d + "/err.txt >/dev/null").c_str()) != 0);
    TEST_ASSERT(access((d + "/m.ctp").c_str(), F_OK) != 0);
    f = std::fopen((d + "/err.txt").c_str(), "r");
    TEST_ASSERT(f != nullptr);
    n = std::fread(buf, 1, sizeof buf - 1, f);
    std::fclose(f);
    buf[n] = 0;
    TEST_ASSERT_MSG(std::strstr(buf, "merc.tif: a vertical datum needs a UTM CRS") && std::strchr(buf, '\n') == buf + n - 1,
                    "stderr: %s", buf);
    sh("rm -rf " + d);
}

}  // namespace

int main()
{
    TEST_BEGIN("test_vdatum");
    RUN_TEST(test_geoid_at_grid);
    RUN_TEST(test_geoid_vs_proj);
    RUN_TEST(test_geoid_steep);
    RUN_TEST(test_heights_converted);
    RUN_TEST(test_pass_through);
    RUN_TEST(test_datum_section_evil);
    RUN_TEST(test_cli_vdatum);
    return TEST_END();
}
