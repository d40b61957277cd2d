// test_warp.cpp -- geographic DEMs resampled onto UTM (host_tools/warp/warp.hpp)
// and `conetrace build` on them, end to end.
//
// Inputs: the bundled fixture (EPSG:32617, 30 m) warped onto EPSG:4326 by
// the gdalwarp binary, once as int16 (nodata -32768) and once as float32
// (nodata -9999), both with nodata holes punched in afterwards (blocks,
// single posts, a row segment) besides the nodata margin of the rotated
// footprint.  Checks:
//  (a) warp_dem() against `gdalwarp -t_srs EPSG:32616 -tr P P -r bilinear`
//      on the same file: the same grid; equal heights (tolerance kTolEt0) on
//      posts valid in both against gdalwarp with the exact transformation
//      (-et 0, as warp_dem uses), and within kTolDefMax / kTolDefMean of
//      gdalwarp's default approximate one (-et 0.125); voids: every gdalwarp
//      void is a void of ours; ours has more: gdalwarp renormalises the
//      bilinear weights over the valid posts of a footprint that touches
//      nodata, ours makes such a post a void.  Each void and valid post is
//      checked against the source mask at the post's exact source position.
//  (b) `conetrace build` of the geographic files: summary names the
//      resampling, `info` shows the UTM EPSG, the posts and posting.
//  (c) errors: --utm on a DEM without georeference, --utm 61N / 0S / junk:
//      one "conetrace: " line, non-zero exit, no file left behind.
#include "dem_io.hpp"
#include "harness.h"
#include "warp.hpp"

#include <cpl_conv.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#ifndef CT_CLI
#error "CT_CLI must be defined"
#endif
#ifndef CT_GDALWARP
#error "CT_GDALWARP must be defined"
#endif

namespace fs = std::filesystem;

static const double kTolEt0 = 2e-3;      // m: float32 storage of gdalwarp's output (~1e-4 m at 1000 m)
static const double kTolDefMax = 6.0;    // m: gdalwarp's default -et 0.125 moves posts by up to 1/8 pixel
static const double kTolDefMean = 1.5;   // m

static std::string g_root;

static std::string fixture() { return std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif"; }

static std::string quote(const std::string &s)
{
    std::string r = "'";
    for (char c : s) r += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return r + "'";
}

static std::string slurp(const std::string &path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

struct Run {
    int code = -1;
    std::string out, err;
    int err_lines = 0;
};

// `prog args...` in `dir`; captures in g_root (never in `dir`).
static Run run(const std::string &dir, const std::string &prog, const std::vector<std::string> &args)
{
    std::string cmd = "cd " + quote(dir) + " && exec " + quote(prog);
    for (const auto &a : args) cmd += " " + quote(a);
    cmd += " </dev/null >" + quote(g_root + "/stdout") + " 2>" + quote(g_root + "/stderr");
    Run r;
    int st = std::system(cmd.c_str());
    r.code = st == -1 ? -1 : WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
    r.out = slurp(g_root + "/stdout");
    r.err = slurp(g_root + "/stderr");
    r.err_lines = (int)std::count(r.err.begin(), r.err.end(), '\n');
    if (getenv("CT_TEST_VERBOSE")) printf("  $ %s -> %d\n%s%s", cmd.c_str(), r.code, r.out.c_str(), r.err.c_str());
    return r;
}

static std::set<std::string> listing(const std::string &dir)
{
    std::set<std::string> s;
    for (const auto &e : fs::directory_iterator(dir)) s.insert(e.path().filename().string());
    return s;
}

static bool contains(const std::string &s, const std::string &p) { return s.find(p) != std::string::npos; }

static std::string info_value(const std::string &text, const std::string &key)
{
    std::istringstream in(text);
    std::string l;
    while (std::getline(in, l))
        if (l.compare(0, key.size(), key) == 0 && l.size() > key.size() && l[key.size()] == ' ')
            return l.substr(l.find_first_not_of(' ', key.size()));
    return "";
}

// ---------------------------------------------------------------------------
// rasters read with GDAL

struct Grid {
    int w = 0, h = 0;
    double gt[6] = {0, 1, 0, 0, 0, 1};
    std::vector<double> v;
    std::vector<uint8_t> ok;  // 1 = valid
    bool good = false;
};

static Grid read_grid(const std::string &path)
{
    Grid g;
    GDALDatasetH ds = GDALOpen(path.c_str(), GA_ReadOnly);
    if (!ds) return g;
    g.w = GDALGetRasterXSize(ds);
    g.h = GDALGetRasterYSize(ds);
    GDALGetGeoTransform(ds, g.gt);
    GDALRasterBandH b = GDALGetRasterBand(ds, 1);
    g.v.resize((size_t)g.w * g.h);
    g.ok.resize(g.v.size());
    int has = 0;
    double nd = GDALGetRasterNoDataValue(b, &has);
    bool io = GDALRasterIO(b, GF_Read, 0, 0, g.w, g.h, g.v.data(), g.w, g.h, GDT_Float64, 0, 0) == CE_None;
    const bool f32 = GDALGetRasterDataType(b) == GDT_Float32;
    for (size_t k = 0; k < g.v.size(); ++k)
        g.ok[k] = !std::isnan(g.v[k]) && !(has && (f32 ? (float)g.v[k] == (float)nd : g.v[k] == nd));
    GDALClose(ds);
    g.good = io;
    return g;
}

// Punch nodata holes into a GeoTIFF (in place): two blocks, a row segment,
// a sparse lattice of single posts.  Returns the number of posts changed.
static long punch_holes(const std::string &path)
{
    GDALDatasetH ds = GDALOpen(path.c_str(), GA_Update);
    if (!ds) return -1;
    GDALRasterBandH b = GDALGetRasterBand(ds, 1);
    int has = 0;
    const double nd = GDALGetRasterNoDataValue(b, &has);
    const int W = GDALGetRasterXSize(ds), H = GDALGetRasterYSize(ds);
    std::vector<double> v((size_t)W * H);
    long n = 0;
    if (has && GDALRasterIO(b, GF_Read, 0, 0, W, H, v.data(), W, H, GDT_Float64, 0, 0) == CE_None) {
        auto hole = [&](int i, int j) {
            if (i >= 0 && j >= 0 && i < W && j < H && v[(size_t)j * W + i] != nd) {
                v[(size_t)j * W + i] = nd;
                n++;
            }
        };
        for (int j = 80; j < 100; ++j)
            for (int i = 100; i < 125; ++i) hole(i, j);
        for (int j = 200; j < 205; ++j)
            for (int i = 300; i < 305; ++i) hole(i, j);
        for (int i = 150; i < 260; ++i) hole(i, 240);
        for (int j = 40; j < H - 40; j += 23)
            for (int i = 40; i < W - 40; i += 29) hole(i, j);
        if (GDALRasterIO(b, GF_Write, 0, 0, W, H, v.data(), W, H, GDT_Float64, 0, 0) != CE_None) n = -1;
    } else {
        n = -1;
    }
    GDALClose(ds);
    return n;
}

static std::string g_geo[2];  // int16, float32 EPSG:4326 inputs
static long g_holes[2];
static bool g_inputs_ok = false;

static bool make_inputs()
{
    if (g_inputs_ok) return true;
    const char *type[2] = {"Int16", "Float32"}, *nd[2] = {"-32768", "-9999"};
    for (int k = 0; k < 2; ++k) {
        g_geo[k] = g_root + "/geo_" + std::string(type[k]) + ".tif";
        Run r = run(g_root, CT_GDALWARP, {"-q", "-t_srs", "EPSG:4326", "-r", "bilinear", "-ot", type[k], "-dstnodata",
                                          nd[k], fixture(), g_geo[k]});
        if (r.code != 0) {
            printf("  gdalwarp to EPSG:4326 failed: %s", r.err.c_str());
            return false;
        }
        g_holes[k] = punch_holes(g_geo[k]);
        if (g_holes[k] < 500) {
            printf("  punching holes into %s: %ld posts\n", g_geo[k].c_str(), g_holes[k]);
            return false;
        }
    }
    return g_inputs_ok = true;
}

// The UTM posting (m) of the source grid at its centre, from the ellipsoid's
// radii of curvature (the UTM scale factor, ~1.0005 here, is ignored).
static double expected_posting(const Grid &src)
{
    const double a = 6378137.0, f = 1 / 298.257223563, e2 = f * (2 - f);
    const double lat = (src.gt[3] + 0.5 * src.h * src.gt[5]) * M_PI / 180;
    const double w = 1 - e2 * std::sin(lat) * std::sin(lat);
    const double M = a * (1 - e2) / std::pow(w, 1.5), N = a / std::sqrt(w);
    const double dn = std::fabs(src.gt[5]) * M_PI / 180 * M, de = std::fabs(src.gt[1]) * M_PI / 180 * N * std::cos(lat);
    return std::sqrt(dn * de);
}

// ---------------------------------------------------------------------------
// (a) warp_dem vs gdalwarp

// warp_dem on input k (0 int16, 1 float32) and the source grid: the UTM zone
// of the centre (84.35 W -> zone 16; the fixture itself is on 17N), the
// source EPSG, a georeference, a round posting near the source's.
static void warp_input(int k, ct_host::DemRaster *r, Grid *src)
{
    TEST_ASSERT_MSG(make_inputs(), "could not make the EPSG:4326 inputs");
    const std::string &in = g_geo[k];
    TEST_ASSERT_MSG(ct_host::dem_needs_warp(in), "%s: dem_needs_warp false on EPSG:4326", in.c_str());
    try {
        *r = ct_host::warp_dem(in);
    } catch (const std::exception &e) {
        TEST_FAIL_MSG("warp_dem(%s): %s", in.c_str(), e.what());
    }
    *src = read_grid(in);
    TEST_ASSERT(src->good);
    TEST_ASSERT_EQUAL_INT(32616, r->geo.epsg);
    TEST_ASSERT_EQUAL_INT(4326, r->geo.source_epsg);
    TEST_ASSERT(r->has_georef);
    const double P = r->geo.posting_e;
    const double pexp = expected_posting(*src);
    TEST_ASSERT_MSG(P == std::round(P) && std::fabs(P - pexp) <= 0.51 && P == -r->geo.posting_n,
                    "posting %.9g x %.9g m, expected the round of %.4f m", P, r->geo.posting_n, pexp);
}

// gdalwarp of `in` onto EPSG:32616 at posting P, bilinear, float32: *a with
// the exact transformation (-et 0), *d with the default approximate one.
static void gdalwarp_refs(const std::string &in, double P, Grid *a, Grid *d)
{
    const std::string tr = std::to_string((int)P);
    const std::string ref0 = in + ".et0.tif", refd = in + ".default.tif";
    Run g0 = run(g_root, CT_GDALWARP, {"-q", "-overwrite", "-t_srs", "EPSG:32616", "-tr", tr, tr, "-r", "bilinear",
                                      "-et", "0", "-ot", "Float32", "-dstnodata", "-9999", in, ref0});
    Run gd = run(g_root, CT_GDALWARP, {"-q", "-overwrite", "-t_srs", "EPSG:32616", "-tr", tr, tr, "-r", "bilinear",
                                      "-ot", "Float32", "-dstnodata", "-9999", in, refd});
    TEST_ASSERT_MSG(g0.code == 0 && gd.code == 0, "gdalwarp onto UTM failed: %s%s", g0.err.c_str(), gd.err.c_str());
    *a = read_grid(ref0);
    *d = read_grid(refd);
    TEST_ASSERT(a->good && d->good);
}

// Ours (r), gdalwarp -et 0 (a) and default gdalwarp (d) on the same grid.
static void check_same_grid(const ct_host::DemRaster &r, const Grid &a, const Grid &d)
{
    TEST_ASSERT_MSG(r.width == a.w && r.height == a.h, "grid %dx%d, gdalwarp %dx%d", r.width, r.height, a.w, a.h);
    TEST_ASSERT_MSG(std::fabs(r.geo.origin_e - a.gt[0]) < 1e-6 && std::fabs(r.geo.origin_n - a.gt[3]) < 1e-6 &&
                        r.geo.posting_e == a.gt[1] && r.geo.posting_n == a.gt[5] && a.gt[2] == 0 && a.gt[4] == 0,
                    "origin %.6f %.6f posting %g %g; gdalwarp %.6f %.6f %g %g", r.geo.origin_e, r.geo.origin_n,
                    r.geo.posting_e, r.geo.posting_n, a.gt[0], a.gt[3], a.gt[1], a.gt[5]);
    TEST_ASSERT(d.w == a.w && d.h == a.h && d.gt[0] == a.gt[0] && d.gt[3] == a.gt[3]);
}

// The heights of ours (r, input k, posting P) against gdalwarp -et 0 (a,
// within kTolEt0) and default gdalwarp (d, kTolDefMax / kTolDefMean) on
// the posts valid in both, and the voids: every gdalwarp void is ours,
// ours has more (the footprints gdalwarp renormalises).  Prints a line.
static void check_heights(int k, const ct_host::DemRaster &r, const Grid &a, const Grid &d, double P)
{
    const size_t n = (size_t)r.width * r.height;
    double max0 = 0, maxd = 0, sumd = 0;
    size_t both = 0, bothd = 0, ref_void_ours_valid = 0, ours_void_ref_valid = 0, voids = 0;
    for (size_t q = 0; q < n; ++q) {
        voids += !r.valid[q];
        if (r.valid[q] && !std::isfinite(r.h[q])) TEST_FAIL_MSG("post %zu valid but %g", q, r.h[q]);
        if (!a.ok[q] && r.valid[q]) ref_void_ours_valid++;
        if (a.ok[q] && !r.valid[q]) ours_void_ref_valid++;
        if (a.ok[q] && r.valid[q]) {
            max0 = std::max(max0, std::fabs(r.h[q] - a.v[q]));
            both++;
        }
        if (d.ok[q] && r.valid[q]) {
            const double e = std::fabs(r.h[q] - d.v[q]);
            maxd = std::max(maxd, e);
            sumd += e;
            bothd++;
        }
    }
    const double meand = sumd / std::max<size_t>(1, bothd);
    printf("  %s: %dx%d posts at %g m (EPSG:32616), %zu voids; vs gdalwarp -et 0: %zu common valid posts, "
           "max |dh| %.2e m; vs default gdalwarp: max %.3f m, mean %.3f m; voids only here: %zu, "
           "only in gdalwarp: %zu\n",
           k ? "float32" : "int16", r.width, r.height, P, voids, both, max0, maxd, meand, ours_void_ref_valid,
           ref_void_ours_valid);
    TEST_ASSERT_MSG(both > n / 2, "only %zu of %zu posts valid in both", both, n);
    TEST_ASSERT_MSG(max0 <= kTolEt0, "max |ours - gdalwarp -et 0| = %g m > %g", max0, kTolEt0);
    TEST_ASSERT_MSG(maxd <= kTolDefMax && meand <= kTolDefMean, "vs default gdalwarp: max %g m, mean %g m", maxd,
                    meand);
    TEST_ASSERT_MSG(ref_void_ours_valid == 0, "%zu gdalwarp voids are valid here", ref_void_ours_valid);
    // the holes make footprints that gdalwarp renormalises and we void
    TEST_ASSERT_MSG(ours_void_ref_valid > 200, "only %zu posts are voids here and valid in gdalwarp",
                    ours_void_ref_valid);
}

// Whether an invalid source post of src lies within rad (source posts, max
// norm, strictly) of source pixel position (x, y) (centre of pixel (c, l)
// at (c + 0.5, l + 0.5)); posts off the source do not count (GDAL drops
// their weights).
static bool source_void_near(const Grid &src, double x, double y, double rad)
{
    for (int l = (int)std::floor(y - 0.5 - rad); l <= (int)std::ceil(y - 0.5 + rad); ++l)
        for (int c = (int)std::floor(x - 0.5 - rad); c <= (int)std::ceil(x - 0.5 + rad); ++c) {
            if (std::fabs(c + 0.5 - x) >= rad || std::fabs(l + 0.5 - y) >= rad) continue;
            if (c < 0 || l < 0 || c >= src.w || l >= src.h) continue;  // GDAL drops those weights
            if (!src.ok[(size_t)l * src.w + c]) return true;
        }
    return false;
}

// Every post of ours (r, posting P) against the source mask at its exact
// source position: valid => the four posts of its bilinear cell are valid
// (they always have non-zero weight); void => an invalid (or missing)
// source post within the kernel radius (1 source post, up to 1.12 where
// GDAL widens the kernel for downsampling east-west here).
static void check_voids_against_source(const ct_host::DemRaster &r, const Grid &src, double P)
{
    OGRSpatialReferenceH u = OSRNewSpatialReference(nullptr), g = OSRNewSpatialReference(nullptr);
    OSRImportFromEPSG(u, 32616);
    OSRImportFromEPSG(g, 4326);
    OSRSetAxisMappingStrategy(u, OAMS_TRADITIONAL_GIS_ORDER);
    OSRSetAxisMappingStrategy(g, OAMS_TRADITIONAL_GIS_ORDER);
    OGRCoordinateTransformationH ct = OCTNewCoordinateTransformation(u, g);
    size_t bad_valid = 0, bad_void = 0;
    std::string example;
    for (int j = 0; j < r.height; ++j) {
        std::vector<double> xs(r.width), ys(r.width);
        for (int i = 0; i < r.width; ++i) {
            xs[i] = r.geo.origin_e + (i + 0.5) * P;
            ys[i] = r.geo.origin_n - (j + 0.5) * P;
        }
        OCTTransform(ct, r.width, xs.data(), ys.data(), nullptr);
        for (int i = 0; i < r.width; ++i) {
            // source pixel coordinates; centre of pixel (c, l) at (c + 0.5, l + 0.5)
            const double x = (xs[i] - src.gt[0]) / src.gt[1], y = (ys[i] - src.gt[3]) / src.gt[5];
            const bool inside = x >= 0 && y >= 0 && x <= src.w && y <= src.h;
            const bool v = r.valid[(size_t)j * r.width + i];
            if (v && (!inside || source_void_near(src, x, y, 0.999))) {
                if (!bad_valid++) example = "valid post " + std::to_string(i) + "," + std::to_string(j);
            }
            if (!v && inside && !source_void_near(src, x, y, 1.15)) {
                if (!bad_void++) example += " void post " + std::to_string(i) + "," + std::to_string(j);
            }
        }
    }
    OCTDestroyCoordinateTransformation(ct);
    OSRDestroySpatialReference(u);
    OSRDestroySpatialReference(g);
    TEST_ASSERT_MSG(bad_valid == 0 && bad_void == 0,
                    "%zu valid posts touch nodata, %zu voids touch none (e.g. %s)", bad_valid, bad_void,
                    example.c_str());
}

// (a) warp_dem of input k against gdalwarp on the same file: the grid, the
// heights and voids, every post against the source mask.
static void check_against_gdalwarp(int k)
{
    ct_host::DemRaster r;
    Grid src, a, d;
    warp_input(k, &r, &src);
    if (ct_harness_g.current_failed) return;
    const double P = r.geo.posting_e;
    gdalwarp_refs(g_geo[k], P, &a, &d);
    if (ct_harness_g.current_failed) return;
    check_same_grid(r, a, d);
    if (ct_harness_g.current_failed) return;
    check_heights(k, r, a, d, P);
    if (ct_harness_g.current_failed) return;
    check_voids_against_source(r, src, P);
}

static void test_warp_int16_vs_gdalwarp(void) { check_against_gdalwarp(0); }
static void test_warp_float32_vs_gdalwarp(void) { check_against_gdalwarp(1); }

static void test_predicate_and_options(void)
{
    TEST_ASSERT(make_inputs());
    // the fixture is on a WGS84 UTM zone: no warping
    TEST_ASSERT(!ct_host::dem_needs_warp(fixture()));
    ct_host::WarpOptions o;
    ct_host::parse_utm_zone("17N", &o);
    TEST_ASSERT(o.utm_zone == 17 && !o.south);
    TEST_ASSERT(!ct_host::dem_needs_warp(fixture(), o));  // already there
    ct_host::parse_utm_zone("16s", &o);
    TEST_ASSERT(o.utm_zone == 16 && o.south);
    TEST_ASSERT(ct_host::dem_needs_warp(fixture(), o));
    for (const char *bad : {"61N", "0S", "17", "N", "17X", "-5N", "017NN", "", "1 7N"}) {
        bool threw = false;
        try {
            ct_host::parse_utm_zone(bad, &o);
        } catch (const ct_host::Error &) {
            threw = true;
        }
        TEST_ASSERT_MSG(threw, "parse_utm_zone('%s') accepted", bad);
    }
    // another projected CRS (web mercator) needs warping; forced zone + posting
    const std::string merc = g_root + "/merc.tif";
    Run m = run(g_root, CT_GDALWARP, {"-q", "-t_srs", "EPSG:3857", "-r", "bilinear", fixture(), merc});
    TEST_ASSERT_MSG(m.code == 0, "gdalwarp to 3857: %s", m.err.c_str());
    TEST_ASSERT(ct_host::dem_needs_warp(merc));
    o = ct_host::WarpOptions();
    o.utm_zone = 17;
    o.posting_m = 45;
    ct_host::DemRaster r = ct_host::warp_dem(merc, o);
    TEST_ASSERT_EQUAL_INT(32617, r.geo.epsg);
    TEST_ASSERT_EQUAL_INT(3857, r.geo.source_epsg);
    TEST_ASSERT(r.geo.posting_e == 45 && r.geo.posting_n == -45);
    TEST_ASSERT_MSG(ct_host::warp_summary(r) == "resampled from EPSG:3857 onto EPSG:32617 at 45 m, bilinear", "'%s'",
                    ct_host::warp_summary(r).c_str());
    // back on 17N the heights are the fixture's, up to two bilinear passes
    // (the fixture read independently at the same map positions)
    ct_host::DemRaster f = ct_host::read_dem(fixture());
    size_t cmp = 0;
    double sum = 0;
    for (int j = 0; j < r.height; ++j)
        for (int i = 0; i < r.width; ++i) {
            if (!r.valid[(size_t)j * r.width + i]) continue;
            const double e = r.geo.origin_e + (i + 0.5) * 45, nn = r.geo.origin_n - (j + 0.5) * 45;
            const int fi = (int)std::floor((e - f.geo.origin_e) / 30), fj = (int)std::floor((f.geo.origin_n - nn) / 30);
            if (fi < 1 || fj < 1 || fi >= f.width - 1 || fj >= f.height - 1) continue;
            sum += std::fabs(r.h[(size_t)j * r.width + i] - f.h[(size_t)fj * f.width + fi]);
            cmp++;
        }
    TEST_ASSERT_MSG(cmp > 1000 && sum / cmp < 8.0, "%zu posts, mean |dh| vs the fixture %g m", cmp,
                    sum / std::max<size_t>(1, cmp));
    // errors name the file
    try {
        ct_host::warp_dem(g_root + "/missing.tif");
        TEST_FAIL_MSG("warp_dem on a missing file did not throw");
    } catch (const ct_host::Error &e) {
        TEST_ASSERT_MSG(contains(e.what(), "missing.tif"), "'%s'", e.what());
    }
}

// ---------------------------------------------------------------------------
// (b) `conetrace build` / `info` on the geographic files

static void test_cli_build_geographic(void)
{
    TEST_ASSERT(make_inputs());
    const std::string dir = g_root + "/cli";
    fs::create_directories(dir);
    struct Case {
        int input;
        std::vector<std::string> extra;
        std::string epsg, summary;
        double posting;
    } cases[] = {
        {0, {}, "32616", "(resampled from EPSG:4326 onto EPSG:32616 at 31 m, bilinear)", 31},
        {1, {"--utm", "17N"}, "32617", "(resampled from EPSG:4326 onto EPSG:32617 at 31 m, bilinear)", 31},
        {1, {"--utm", "16n", "--posting", "60"}, "32616", "(resampled from EPSG:4326 onto EPSG:32616 at 60 m, bilinear)",
         60},
    };
    int k = 0;
    for (const Case &c : cases) {
        const std::string out = "g" + std::to_string(k++) + ".ctp";
        std::vector<std::string> args = {"build", g_geo[c.input], "-o", out, "--sectors", "8", "--reduce", "4"};
        args.insert(args.end(), c.extra.begin(), c.extra.end());
        Run b = run(dir, CT_CLI, args);
        TEST_ASSERT_MSG(b.code == 0, "build %s: exit %d: %s", g_geo[c.input].c_str(), b.code, b.err.c_str());
        TEST_ASSERT_MSG(contains(b.out, c.summary), "summary lacks '%s': %s", c.summary.c_str(), b.out.c_str());
        Run i = run(dir, CT_CLI, {"info", out});
        TEST_ASSERT_MSG(i.code == 0, "info: %s", i.err.c_str());
        TEST_ASSERT_MSG(info_value(i.out, "epsg") == c.epsg, "info epsg '%s', expected %s",
                        info_value(i.out, "epsg").c_str(), c.epsg.c_str());
        TEST_ASSERT_MSG(info_value(i.out, "voids") == "yes", "info voids '%s'", info_value(i.out, "voids").c_str());
        double pe = 0, pn = 0;
        TEST_ASSERT(std::sscanf(info_value(i.out, "posting").c_str(), "%lf x %lf", &pe, &pn) == 2);
        TEST_ASSERT_MSG(pe == c.posting && pn == -c.posting, "posting %g x %g", pe, pn);
        // the package's posts are warp_dem's grid
        ct_host::WarpOptions o;
        if (c.extra.size() >= 2) ct_host::parse_utm_zone(c.extra[1], &o);
        o.posting_m = c.extra.size() >= 4 ? 60 : 0;
        ct_host::DemRaster r = ct_host::warp_dem(g_geo[c.input], o);
        char posts[64];
        std::snprintf(posts, sizeof posts, "%d x %d ", r.width, r.height);
        TEST_ASSERT_MSG(info_value(i.out, "posts").compare(0, std::strlen(posts), posts) == 0, "posts '%s', expected %s",
                        info_value(i.out, "posts").c_str(), posts);
    }
    // a UTM input is not resampled (and --utm of its own zone changes nothing)
    Run f = run(dir, CT_CLI, {"build", fixture(), "-o", "f.ctp", "--sectors", "8", "--reduce", "4", "--utm", "17N"});
    TEST_ASSERT_MSG(f.code == 0 && !contains(f.out, "resampled"), "fixture build: %d %s%s", f.code, f.out.c_str(),
                    f.err.c_str());
}

// ---------------------------------------------------------------------------
// (c) bad input

static void test_cli_errors(void)
{
    TEST_ASSERT(make_inputs());
    const std::string dir = g_root + "/errors";
    fs::create_directories(dir);
    // a DEM without georeference (plain GeoTIFF-less TIFF)
    const std::string plain = dir + "/plain.tif";
    {
        GDALDriverH drv = GDALGetDriverByName("GTiff");
        char opt0[] = "PROFILE=BASELINE";
        char *opts[] = {opt0, nullptr};
        GDALDatasetH ds = GDALCreate(drv, plain.c_str(), 40, 30, 1, GDT_Int16, opts);
        TEST_ASSERT(ds);
        std::vector<int16_t> v(40 * 30);
        for (size_t q = 0; q < v.size(); ++q) v[q] = (int16_t)(100 + q % 40 + q / 40);
        TEST_ASSERT(GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, 40, 30, v.data(), 40, 30, GDT_Int16, 0, 0) ==
                    CE_None);
        GDALClose(ds);
    }
    // without --utm it builds as before (--posting labels it)
    Run ok = run(dir, CT_CLI, {"build", "plain.tif", "-o", "plain.ctp", "--posting", "30", "--sectors", "4"});
    TEST_ASSERT_MSG(ok.code == 0 && !contains(ok.out, "resampled"), "plain build: %d %s", ok.code, ok.err.c_str());
    fs::remove(dir + "/plain.ctp");
    struct Bad {
        std::vector<std::string> args;
        std::string needle;
    } bad[] = {
        {{"build", "plain.tif", "-o", "X.ctp", "--utm", "17N"}, "plain.tif"},
        {{"build", "plain.tif", "-o", "X.ctp", "--utm", "17N", "--posting", "30"}, "plain.tif"},
        {{"build", g_geo[0], "-o", "X.ctp", "--utm", "61N"}, "61N"},
        {{"build", g_geo[0], "-o", "X.ctp", "--utm", "0S"}, "0S"},
        {{"build", g_geo[1], "-o", "X.ctp", "--utm", "seventeen"}, "seventeen"},
        {{"build", g_geo[1], "-o", "X.ctp", "--utm", "17"}, "17"},
        {{"build", g_geo[1], "-o", "X.ctp", "--posting", "0.05"}, "geo_Float32.tif"},  // over 32768 posts a side
    };
    for (const Bad &b : bad) {
        const std::set<std::string> before = listing(dir);
        Run r = run(dir, CT_CLI, b.args);
        std::string cmd;
        for (const auto &a : b.args) cmd += " " + a;
        TEST_ASSERT_MSG(r.code != 0 && r.code < 128, "`conetrace%s`: exit %d", cmd.c_str(), r.code);
        TEST_ASSERT_MSG(r.out.empty(), "`conetrace%s`: stdout '%s'", cmd.c_str(), r.out.c_str());
        TEST_ASSERT_MSG(r.err_lines == 1 && r.err.compare(0, 11, "conetrace: ") == 0 && contains(r.err, b.needle),
                        "`conetrace%s`: stderr should be one 'conetrace: ...%s...' line, was: %s", cmd.c_str(),
                        b.needle.c_str(), r.err.c_str());
        TEST_ASSERT_MSG(listing(dir) == before, "`conetrace%s` left files behind", cmd.c_str());
    }
}

int main(void)
{
    char tmpl[] = "/tmp/ct_test_warp.XXXXXX";
    if (!mkdtemp(tmpl)) {
        perror("mkdtemp");
        return 1;
    }
    g_root = tmpl;
    GDALAllRegister();
    CPLSetConfigOption("GDAL_PAM_ENABLED", "NO");  // no .aux.xml next to the inputs
    TEST_BEGIN("test_warp");
    RUN_TEST(test_warp_int16_vs_gdalwarp);
    RUN_TEST(test_warp_float32_vs_gdalwarp);
    RUN_TEST(test_predicate_and_options);
    RUN_TEST(test_cli_build_geographic);
    RUN_TEST(test_cli_errors);
    if (!getenv("CT_TEST_KEEP")) fs::remove_all(g_root);
    return TEST_END();
}
