// test_geoloc_cli.cpp -- `conetrace geoloc` end to end (runs the real binary).
//
// In a fresh scratch directory (mkdtemp under /tmp): a package built from a
// generated DEM, an mrcal .cameramodel written with full precision (exact
// nadir: r = pi about east, translations at UTM magnitudes) and pixel CSVs.
// Checks: the header u,v,status,E,N,h,steps; one row per pixel in input
// order with the u,v echoed; each hit's E,N,h (nine decimals) equal to the
// library's ct_geolocate on the same camera in-process (bit-identical);
// statuses for pixels beyond the lens's field and off the terrain; column
// order free in the input; --method and --effects ""; and bad inputs
// (missing or unparsable camera, unsupported lens model, bad CSV, missing
// option, unknown method, --effects curvature): non-zero exit, one stderr
// line "conetrace: ..." naming the file or option, no output file, no
// temporary left behind, an existing output untouched.
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "camera_host.hpp"
#include "picture.hpp"
#include "conetrace.h"
#include "dem_cases.hpp"
#include "dem_io.hpp"
#include "reference.hpp"
#include "scene.hpp"
#include "harness.h"
#include "host_io.hpp"
#include "vdatum.hpp"

#ifndef CT_CLI
#error "CT_CLI must be defined (path of the conetrace binary)"
#endif

namespace fs = std::filesystem;

namespace {

std::string g_dir;

std::string slurp(const std::string &path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void spit(const std::string &path, const std::string &text)
{
    std::ofstream o(path, std::ios::binary | std::ios::trunc);
    o << text;
}

std::vector<std::string> lines_of(const std::string &text)
{
    std::vector<std::string> v;
    std::istringstream in(text);
    std::string l;
    while (std::getline(in, l)) v.push_back(l);
    return v;
}

std::vector<std::string> split(const std::string &s)
{
    std::vector<std::string> v;
    std::string cur;
    for (char c : s) {
        if (c == ',') {
            v.push_back(cur);
            cur.clear();
        } else {
            cur += c;
        }
    }
    v.push_back(cur);
    return v;
}

// A geoloc row (fields f, row number `row`) against the library's answer for
// its pixel: the status, and for a hit E, N, h to the nanometre (counted in
// *hits).  `what` prefixes the messages.
// a row against the library's result; h is the package's height less the
// geoid (ct_package_geoid) for an EGM96 package, h_ell the package's height
// when its datum is known, else nan
void check_row(const std::vector<std::string> &f, const std::string &what, size_t row, ct_status want,
               const ct_geo &g, int *hits, const ct_package *pk = nullptr)
{
    TEST_ASSERT_MSG(f.size() == 10, "%srow %zu: %zu fields", what.c_str(), row, f.size());
    TEST_ASSERT_MSG(f[2] == ct_host::status_name(want), "%srow %zu: status %s, library %s", what.c_str(), row,
                    f[2].c_str(), ct_host::status_name(want).c_str());
    if (want == CT_HIT) {
        ++*hits;
        int64_t und = 0;
        if (pk && pk->vdatum == CT_VDATUM_EGM96)
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_geoid(pk, g.hit.e_nm, g.hit.n_nm, &und));
        TEST_ASSERT(f[3] == ct_host::nm_to_decimal(g.hit.e_nm) && f[4] == ct_host::nm_to_decimal(g.hit.n_nm));
        TEST_ASSERT_MSG(f[5] == ct_host::nm_to_decimal(g.hit.h_nm - und), "%srow %zu: h %s, library %s less N %s",
                        what.c_str(), row, f[5].c_str(), ct_host::nm_to_decimal(g.hit.h_nm).c_str(),
                        ct_host::nm_to_decimal(und).c_str());
        const bool known = pk && pk->vdatum != CT_VDATUM_UNKNOWN;
        TEST_ASSERT(f[9] == (known ? ct_host::nm_to_decimal(g.hit.h_nm) : std::string("nan")));
        if (pk && pk->vdatum == CT_VDATUM_EGM96) TEST_ASSERT(und < -20000000000 && und > -40000000000);  // Tennessee: N ~ -30 m
    } else {
        TEST_ASSERT(f[9] == "nan");
    }
}

std::string quote(const std::string &s)
{
    std::string r = "'";
    for (char c : s) r += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return r + "'";
}

struct Run {
    int code = -1;
    std::string out, err;
    std::vector<std::string> err_lines;
};

Run run(const std::vector<std::string> &args)
{
    std::string cmd = "cd " + quote(g_dir) + " && exec " + quote(CT_CLI);
    for (const auto &a : args) cmd += " " + quote(a);
    std::string fo = g_dir + "/../stdout.txt", fe = g_dir + "/../stderr.txt";
    cmd += " </dev/null >" + quote(fo) + " 2>" + quote(fe);
    int st = std::system(cmd.c_str());
    Run r;
    r.code = st == -1 ? -1 : (WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0));
    r.out = slurp(fo);
    r.err = slurp(fe);
    r.err_lines = lines_of(r.err);
    if (getenv("CT_TEST_VERBOSE")) printf("  $ conetrace ... -> %d\n%s", r.code, r.err.c_str());
    return r;
}

std::set<std::string> listing()
{
    std::set<std::string> s;
    for (const auto &e : fs::directory_iterator(g_dir)) s.insert(e.path().filename().string());
    return s;
}

// The camera of the test: exact nadir above the tile, OPENCV4.
const char *kModel =
    "# conetrace test camera: nadir, r = pi about east\n"
    "{\n"
    "    'lensmodel':  'LENSMODEL_OPENCV4',\n"
    "    'intrinsics': [ 3000, 3001.5, 1023.5, 767.5, -0.28, 0.09, 0.0001, -0.0002 ],\n"
    "    'extrinsics': [ 3.141592653589793, 0, 0, %.17g, %.17g, %.17g ],\n"
    "    'imagersize': [ 2048, 1536 ],\n"
    "}\n";

struct Setup {
    dem_cases::Case c;
    ct_package p;
    double centre[3];
    std::string model_text;
};

Setup *setup()
{
    static Setup *s = nullptr;
    if (s) return s;
    s = new Setup;
    const int W = 64, H = 56;
    s->c = dem_cases::make_case("cli", dem_cases::make_terrain(W, H, dem_cases::smooth(W, H, 5, 4000, 6000), 0.25), 8,
                                1);
    if (ct_package_open(&s->p, s->c.pkg.data(), s->c.pkg.size()) != CT_OK) return nullptr;
    // centre above the middle of the tile, 2 km up; nadir R_cam_map =
    // diag(1, -1, -1), so t = -R c = (-cE, cN, ch)
    s->centre[0] = 500000.0 + 31.25 * 30 + 0.123456789;
    s->centre[1] = 4000000.0 - 27.5 * 30 - 0.987654321;
    s->centre[2] = 3500.0;
    char buf[1024];
    std::snprintf(buf, sizeof buf, kModel, -s->centre[0], s->centre[1], s->centre[2]);
    s->model_text = buf;
    spit(g_dir + "/t.ctp", std::string(s->c.pkg.begin(), s->c.pkg.end()));
    spit(g_dir + "/cam.cameramodel", s->model_text);
    return s;
}

// pixels: inside the image, fractional, corners, beyond 2^20 px, far outside
const char *kPixels =
    "u,v\n"
    "1023.5,767.5\n"
    "0,0\n"
    "2047,1535\n"
    "100.25,1400.75\n"
    "1500.125,30.0625\n"
    "5e6,3\n"          // beyond 2^20 px
    "-900000,700\n"    // far outside the image: a ray ~80 deg off axis
    "  512 , 384 \n"
    "\n"
    "1800.5,200.5\n";

// The output's metres: ct_host::nm_to_decimal against printf's digits, at
// the edges (0, +-1 nm, +-1 m, the int64 limits) and at random values.
void test_nm_decimal()
{
    auto ref = [](int64_t nm) {
        uint64_t a = nm < 0 ? (uint64_t)0 - (uint64_t)nm : (uint64_t)nm;
        char b[48];
        std::snprintf(b, sizeof b, "%s%llu.%09llu", nm < 0 ? "-" : "", (unsigned long long)(a / 1000000000u),
                      (unsigned long long)(a % 1000000000u));
        return std::string(b);
    };
    const int64_t edge[] = {0, 1, -1, 999999999, -999999999, 1000000000, -1000000000, 1000000001,
                            INT64_MAX, INT64_MIN, INT64_MIN + 1};
    for (int64_t v : edge) TEST_ASSERT_MSG(ct_host::nm_to_decimal(v) == ref(v), "%lld", (long long)v);
    ct_rng r;
    ct_rng_seed(&r, ct_test_seed() + 5);
    for (int k = 0; k < 100000; ++k) {
        int64_t v = (int64_t)(ct_rng_u64(&r) >> ct_rng_range(&r, 0, 63)) * (ct_rng_range(&r, 0, 1) ? 1 : -1);
        TEST_ASSERT_MSG(ct_host::nm_to_decimal(v) == ref(v), "%lld", (long long)v);
    }
}

void test_geoloc_end_to_end()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    spit(g_dir + "/px.csv", kPixels);
    Run r = run({"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "-o", "g.csv"});
    TEST_ASSERT_MSG(r.code == 0, "exit %d: %s", r.code, r.err.c_str());
    TEST_ASSERT_MSG(r.err.empty(), "stderr: %s", r.err.c_str());
    std::vector<std::string> rows = lines_of(slurp(g_dir + "/g.csv"));
    TEST_ASSERT_EQUAL_INT(10, rows.size());
    TEST_ASSERT_MSG(rows[0] == "u,v,status,E,N,h,steps,lat,lon,h_ell", "header '%s'", rows[0].c_str());
    // the library on the same camera, in-process
    ct_host::CameraModel cm = ct_host::read_cameramodel(g_dir + "/cam.cameramodel");
    ct_host::LibCamera lc = ct_host::lib_camera(cm, "cam");
    std::vector<ct_host::PixelRow> px = ct_host::read_pixels_csv(g_dir + "/px.csv");
    TEST_ASSERT_EQUAL_INT(9, px.size());
    const char *echo[9][2] = {{"1023.5", "767.5"}, {"0", "0"}, {"2047", "1535"}, {"100.25", "1400.75"},
                              {"1500.125", "30.0625"}, {"5e6", "3"}, {"-900000", "700"}, {"512", "384"},
                              {"1800.5", "200.5"}};
    int hits = 0;
    for (size_t k = 0; k < px.size(); ++k) {
        std::vector<std::string> f = split(rows[k + 1]);
        TEST_ASSERT_MSG(f.size() == 10, "row %zu: '%s'", k + 1, rows[k + 1].c_str());
        // the package has no EPSG code and no datum: no geodetic columns
        TEST_ASSERT(f[7] == "nan" && f[8] == "nan" && f[9] == "nan");
        TEST_ASSERT_MSG(f[0] == echo[k][0] && f[1] == echo[k][1], "row %zu echoes '%s,%s'", k + 1, f[0].c_str(),
                        f[1].c_str());
        int64_t uq, vq;
        ct_status want = CT_ERR_UNPROJECT;
        ct_geo g;
        if (ct_host::pixel_to_q16(px[k].u, px[k].v, &uq, &vq))
            want = ct_geolocate(&s->p, &lc.cam, &lc.pose, CT_METHOD_DIRECTIONAL, nullptr, uq, vq, &g);
        TEST_ASSERT_MSG(f[2] == ct_host::status_name(want), "row %zu: status %s, library %s", k + 1, f[2].c_str(),
                        ct_host::status_name(want).c_str());
        if (want == CT_HIT) {
            ++hits;
            TEST_ASSERT(f[3] == ct_host::nm_to_decimal(g.hit.e_nm));
            TEST_ASSERT(f[4] == ct_host::nm_to_decimal(g.hit.n_nm));
            TEST_ASSERT(f[5] == ct_host::nm_to_decimal(g.hit.h_nm));
            TEST_ASSERT(f[6] == std::to_string(g.hit.steps));
            // nine decimals, UTM magnitudes: "4000xxx.xxxxxxxxx"
            TEST_ASSERT_MSG(f[4].size() == 17 && f[4][7] == '.', "northing '%s'", f[4].c_str());
        } else {
            TEST_ASSERT(f[3] == "nan" && f[4] == "nan" && f[5] == "nan");
        }
    }
    TEST_ASSERT_MSG(hits >= 6, "only %d hits", hits);
    TEST_ASSERT(split(rows[6])[2] == "err_unproject");
    TEST_ASSERT(split(rows[7])[2] == "miss");  // ~80 deg off axis: over the horizon
    // the centre pixel of an exact nadir camera lands below its centre (the
    // camera's optical axis is vertical): within a millimetre
    std::vector<std::string> f = split(rows[1]);
    TEST_ASSERT_MSG(std::fabs(std::stod(f[3]) - s->centre[0]) < 1e-3 && std::fabs(std::stod(f[4]) - s->centre[1]) < 1e-3,
                    "nadir centre pixel at %s, %s", f[3].c_str(), f[4].c_str());
    // column order is free; other columns are ignored; --method, --effects ""
    spit(g_dir + "/px2.csv", "id,v,u\na,767.5,1023.5\nb,1400.75,100.25\n");
    r = run({"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px2.csv", "--method", "incremental",
             "--effects", "", "-o", "g2.csv"});
    TEST_ASSERT_MSG(r.code == 0, "exit %d: %s", r.code, r.err.c_str());
    std::vector<std::string> rows2 = lines_of(slurp(g_dir + "/g2.csv"));
    TEST_ASSERT_EQUAL_INT(3, rows2.size());
    std::vector<std::string> a = split(rows2[1]), b = split(rows[1]), c2 = split(rows2[2]), d = split(rows[4]);
    for (int k = 0; k < 6; ++k) {
        TEST_ASSERT(a[k] == b[k]);
        TEST_ASSERT(c2[k] == d[k]);
    }
    // the same pixels with CRLF line ends, blank lines of blanks, a column
    // before them and no newline after the last: the same file, byte for byte
    std::string crlf = "id,u,v\r\n";
    for (size_t k = 1; k < 10; ++k) {
        crlf += "x," + rows[k].substr(0, rows[k].find(',', rows[k].find(',') + 1));
        crlf += k == 3 ? "\r\n \t\r\n" : (k < 9 ? "\r\n" : "");  // a blank line; nothing after the last
    }
    spit(g_dir + "/px3.csv", crlf);
    r = run({"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px3.csv", "-o", "g3.csv"});
    TEST_ASSERT_MSG(r.code == 0, "exit %d: %s", r.code, r.err.c_str());
    TEST_ASSERT_MSG(slurp(g_dir + "/g3.csv") == slurp(g_dir + "/g.csv"), "CRLF pixels: another output");
    fs::remove(g_dir + "/g.csv");
    fs::remove(g_dir + "/g2.csv");
    fs::remove(g_dir + "/g3.csv");
    fs::remove(g_dir + "/px2.csv");
    fs::remove(g_dir + "/px3.csv");
}

// --threads: 5,000 pixels (five chunks) give the same file, byte for byte,
// on 1, 2 and 3 threads and by default, in input order; spot rows are the
// library's ct_geolocate.
void test_geoloc_threads()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    std::string px = "u,v\n";
    ct_rng rng;
    ct_rng_seed(&rng, 77);
    std::vector<std::pair<double, double>> uv;
    for (int k = 0; k < 5000; ++k) {
        double u = -100 + 2200 * ct_rng_unit(&rng), v = -100 + 1700 * ct_rng_unit(&rng);
        uv.push_back({u, v});
        char line[64];
        std::snprintf(line, sizeof line, "%.17g,%.17g\n", u, v);
        px += line;
    }
    spit(g_dir + "/pxt.csv", px);
    std::string first;
    for (const char *t : {"1", "2", "3", ""}) {
        std::vector<std::string> args = {"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "pxt.csv",
                                         "--effects", "curvature,refraction", "-o", "gt.csv"};
        if (*t) {
            args.push_back("--threads");
            args.push_back(t);
        }
        Run r = run(args);
        TEST_ASSERT_MSG(r.code == 0, "--threads %s: exit %d: %s", t, r.code, r.err.c_str());
        std::string got = slurp(g_dir + "/gt.csv");
        if (first.empty()) first = got;
        TEST_ASSERT_MSG(got == first, "--threads %s: output differs from one thread", t);
    }
    std::vector<std::string> rows = lines_of(first);
    TEST_ASSERT_EQUAL_INT(5001, rows.size());
    ct_host::CameraModel cm = ct_host::read_cameramodel(g_dir + "/cam.cameramodel");
    ct_host::LibCamera lc = ct_host::lib_camera(cm, "cam");
    ct_effects fx = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
    int hits = 0;
    for (size_t k = 0; k < uv.size(); k += 97) {
        std::vector<std::string> f = split(rows[k + 1]);
        int64_t uq, vq;
        TEST_ASSERT(ct_host::pixel_to_q16(uv[k].first, uv[k].second, &uq, &vq));
        ct_geo g;
        ct_status want = ct_geolocate(&s->p, &lc.cam, &lc.pose, CT_METHOD_DIRECTIONAL, &fx, uq, vq, &g);
        check_row(f, "", k + 1, want, g, &hits);
    }
    TEST_ASSERT_MSG(hits > 20, "only %d hits", hits);
    fs::remove(g_dir + "/gt.csv");
    fs::remove(g_dir + "/pxt.csv");
}

// --pose-map and --pose-wgs84: the rows are the library's ct_geolocate with
// ct_pose_from_map / ct_pose_from_wgs84 of the same numbers (the model's
// extrinsics ignored), bit for bit; lat,lon are ct_utm_inverse of E,N on a
// UTM package (checked against the hit's forward projection); bad poses are
// one-line errors.
// --pose-map against the equivalent .cameramodel: rt_cam_ref written from
// the very rotation ct_pose_from_map makes (its Q30 matrix, made orthonormal
// in long double, as a rotation vector with 17 digits) and t = -R_cam_map C.
// The CLI's model route then rebuilds the Q30 matrix and the centre: where
// both routes round to the same Q30 matrix (always for multiples of 90 deg,
// usually otherwise) the rows are identical, byte for byte; where a matrix
// entry rounds the other way (a few Q30 units: the library's quaternion route
// is not exactly orthonormal) the statuses agree and the hits within 1 mm.
void test_geoloc_pose_map_vs_model()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    spit(g_dir + "/pxm.csv", kPixels);
    auto q61 = [](double deg) { return (int64_t)std::llround((long double)deg * M_PIl / 180 * std::ldexp(1.0L, 61)); };
    const double E0 = 500000 + 30 * 30 + 0.25, N0 = 4000000 - 26 * 30 - 0.5, H0 = 2750;
    const double att[][3] = {{0, -90, 0}, {90, -90, 0}, {-90, 0, 0}, {-40, -75, 3}, {25, -60, -2}, {135, -45, 10}};
    int identical = 0;
    for (const auto &a : att) {
        int32_t q[4];
        ct_pose pose;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(q61(a[0]), q61(a[1]), q61(a[2]), q));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&pose, std::llround(E0 * 1e9), std::llround(N0 * 1e9),
                                                      std::llround(H0 * 1e9), q));
        // R (map <- cam) from the pose, orthonormalised by one Newton step of
        // the polar decomposition R <- (R + R^-T) / 2
        long double R[9], Ri[9], det;
        for (int k = 0; k < 9; ++k) R[k] = (long double)pose.R_map_cam_q30[k] / 1073741824.0L;
        for (int it = 0; it < 3; ++it) {
            det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) + R[2] * (R[3] * R[7] - R[4] * R[6]);
            // inverse transpose = cofactor matrix / det
            Ri[0] = (R[4] * R[8] - R[5] * R[7]) / det;
            Ri[1] = -(R[3] * R[8] - R[5] * R[6]) / det;
            Ri[2] = (R[3] * R[7] - R[4] * R[6]) / det;
            Ri[3] = -(R[1] * R[8] - R[2] * R[7]) / det;
            Ri[4] = (R[0] * R[8] - R[2] * R[6]) / det;
            Ri[5] = -(R[0] * R[7] - R[1] * R[6]) / det;
            Ri[6] = (R[1] * R[5] - R[2] * R[4]) / det;
            Ri[7] = -(R[0] * R[5] - R[2] * R[3]) / det;
            Ri[8] = (R[0] * R[4] - R[1] * R[3]) / det;
            for (int k = 0; k < 9; ++k) R[k] = (R[k] + Ri[k]) / 2;
        }
        // R_cam_map = R^T; its rotation vector via the quaternion (robust at 180 deg)
        long double C[9];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) C[3 * i + j] = R[3 * j + i];
        long double qw, qx, qy, qz, tr = C[0] + C[4] + C[8];
        if (tr > 0) {
            long double t = std::sqrt(tr + 1) * 2;
            qw = t / 4; qx = (C[7] - C[5]) / t; qy = (C[2] - C[6]) / t; qz = (C[3] - C[1]) / t;
        } else if (C[0] >= C[4] && C[0] >= C[8]) {
            long double t = std::sqrt(1 + C[0] - C[4] - C[8]) * 2;
            qw = (C[7] - C[5]) / t; qx = t / 4; qy = (C[1] + C[3]) / t; qz = (C[2] + C[6]) / t;
        } else if (C[4] >= C[8]) {
            long double t = std::sqrt(1 + C[4] - C[0] - C[8]) * 2;
            qw = (C[2] - C[6]) / t; qx = (C[1] + C[3]) / t; qy = t / 4; qz = (C[5] + C[7]) / t;
        } else {
            long double t = std::sqrt(1 + C[8] - C[0] - C[4]) * 2;
            qw = (C[3] - C[1]) / t; qx = (C[2] + C[6]) / t; qy = (C[5] + C[7]) / t; qz = t / 4;
        }
        if (qw < 0) { qw = -qw; qx = -qx; qy = -qy; qz = -qz; }
        const long double vn = std::sqrt(qx * qx + qy * qy + qz * qz), ang = 2 * std::atan2(vn, qw);
        const long double rv[3] = {vn > 0 ? qx / vn * ang : 0, vn > 0 ? qy / vn * ang : 0, vn > 0 ? qz / vn * ang : 0};
        const long double cen[3] = {(long double)pose.e_nm * 1e-9L, (long double)pose.n_nm * 1e-9L,
                                    (long double)pose.h_nm * 1e-9L};
        long double t3[3];
        for (int i = 0; i < 3; ++i) t3[i] = -(C[3 * i] * cen[0] + C[3 * i + 1] * cen[1] + C[3 * i + 2] * cen[2]);
        char model[1024];
        std::snprintf(model, sizeof model,
                      "{\n    'lensmodel':  'LENSMODEL_OPENCV4',\n"
                      "    'intrinsics': [ 3000, 3001.5, 1023.5, 767.5, -0.28, 0.09, 0.0001, -0.0002 ],\n"
                      "    'extrinsics': [ %.21Lg, %.21Lg, %.21Lg, %.21Lg, %.21Lg, %.21Lg ],\n"
                      "    'imagersize': [ 2048, 1536 ],\n}\n",
                      rv[0], rv[1], rv[2], t3[0], t3[1], t3[2]);
        spit(g_dir + "/eq.cameramodel", model);
        // the model route's pose, as the CLI builds it
        ct_host::CameraModel cm = ct_host::read_cameramodel(g_dir + "/eq.cameramodel");
        ct_host::LibCamera lc = ct_host::lib_camera(cm, "eq");
        long dr = 0, dc = std::max(std::llabs(lc.pose.e_nm - pose.e_nm),
                                   std::max(std::llabs(lc.pose.n_nm - pose.n_nm), std::llabs(lc.pose.h_nm - pose.h_nm)));
        for (int k = 0; k < 9; ++k) dr = std::max(dr, (long)std::labs((long)lc.pose.R_map_cam_q30[k] - pose.R_map_cam_q30[k]));
        std::printf("  yaw %g pitch %g roll %g: model route vs ct_pose_from_map: R within %ld Q30 units, centre within %ld nm\n",
                    a[0], a[1], a[2], dr, dc);
        TEST_ASSERT_MSG(dr <= 4 && dc <= 2, "yaw %g pitch %g roll %g: the model's pose is %ld Q30 / %ld nm off", a[0],
                        a[1], a[2], dr, dc);
        const bool same_pose = dr == 0 && dc == 0;
        char arg[160];
        std::snprintf(arg, sizeof arg, "%.9f,%.9f,%.9f,%g,%g,%g", E0, N0, H0, a[0], a[1], a[2]);
        Run r1 = run({"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "pxm.csv", "--pose-map", arg, "-o",
                      "gm1.csv"});
        Run r2 = run({"geoloc", "t.ctp", "--camera", "eq.cameramodel", "--pixels", "pxm.csv", "-o", "gm2.csv"});
        TEST_ASSERT_MSG(r1.code == 0 && r2.code == 0, "exit %d / %d: %s %s", r1.code, r2.code, r1.err.c_str(),
                        r2.err.c_str());
        const std::string g1 = slurp(g_dir + "/gm1.csv"), g2 = slurp(g_dir + "/gm2.csv");
        if (same_pose) {
            TEST_ASSERT_MSG(g1 == g2, "yaw %g pitch %g roll %g: --pose-map and the equivalent model differ", a[0],
                            a[1], a[2]);
            identical += g1 == g2 && lines_of(g1).size() > 2;
        } else {
            // a few Q30 units apart (the two routes round the same rotation):
            // the same statuses, hits within 1 mm
            std::vector<std::string> l1 = lines_of(g1), l2 = lines_of(g2);
            TEST_ASSERT_EQUAL_INT(l1.size(), l2.size());
            for (size_t k = 1; k < l1.size() && k < l2.size(); ++k) {
                std::vector<std::string> f1 = split(l1[k]), f2 = split(l2[k]);
                TEST_ASSERT(f1[2] == f2[2]);
                if (f1[2] == "hit")
                    for (int c = 3; c <= 5; ++c)
                        TEST_ASSERT_MSG(std::fabs(std::stod(f1[c]) - std::stod(f2[c])) < 1e-3, "row %zu col %d: %s vs %s", k,
                                        c, f1[c].c_str(), f2[c].c_str());
            }
        }
    }
    // the exact attitudes (multiples of 90 deg) and most general ones agree to the bit
    TEST_ASSERT_MSG(identical >= 4, "only %d of the attitudes gave identical rows", identical);
}

void test_geoloc_poses()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    // the same terrain as a UTM zone 17N package
    ct_host::Terrain t = s->c.t;
    t.geo.epsg = 32617;
    auto cu = dem_cases::make_case("cli-utm", t, 8, 1);
    spit(g_dir + "/tu.ctp", std::string(cu.pkg.begin(), cu.pkg.end()));
    ct_package pu;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&pu, cu.pkg.data(), cu.pkg.size()));
    // and with a datum: its heights taken as ellipsoidal ones converted from
    // EGM96, the geoid grid over it from PROJ
    ct_host::Terrain tv = t;
    tv.vdatum = CT_VDATUM_EGM96;
    {
        ct_host::Egm96 egm;
        tv.geoid = ct_host::make_geoid_grid(egm, tv.geo, tv.width, tv.height);
    }
    auto cv = dem_cases::make_case("cli-utm-egm96", tv, 8, 1);
    spit(g_dir + "/tv.ctp", std::string(cv.pkg.begin(), cv.pkg.end()));
    ct_package pv;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&pv, cv.pkg.data(), cv.pkg.size()));
    TEST_ASSERT_EQUAL_INT(CT_VDATUM_EGM96, (int)pv.vdatum);
    spit(g_dir + "/pxp.csv", kPixels);
    std::vector<ct_host::PixelRow> px = ct_host::read_pixels_csv(g_dir + "/pxp.csv");
    ct_host::CameraModel cm = ct_host::read_cameramodel(g_dir + "/cam.cameramodel");
    ct_host::LibCamera lc = ct_host::lib_camera(cm, "cam");
    auto q61 = [](double deg) { return (int64_t)std::llround((long double)deg * M_PIl / 180 * std::ldexp(1.0L, 61)); };
    // looking 75 deg below the horizon towards the north-west, from above
    // the tile's middle: centre (E, N) of the tile, 2.5 km up
    const double E0 = 500000 + 32 * 30, N0 = 4000000 - 28 * 30, H0 = 2500;
    const double yaw = -40, pitch = -75, roll = 3;
    int32_t q[4];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(q61(yaw), q61(pitch), q61(roll), q));
    for (int mode = 0; mode < 3; ++mode) {
        ct_pose pose;
        char arg[160];
        std::string pkgname = mode == 0 ? "t.ctp" : mode == 1 ? "tu.ctp" : "tv.ctp";
        const ct_package *pk = mode == 0 ? &s->p : mode == 1 ? &pu : &pv;
        ct_utm z = {17, 0};
        if (mode == 0) {
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&pose, std::llround(E0 * 1e9), std::llround(N0 * 1e9),
                                                          std::llround(H0 * 1e9), q));
            std::snprintf(arg, sizeof arg, "%.9f,%.9f,%.9f,%g,%g,%g", E0, N0, H0, yaw, pitch, roll);
        } else {
            // the geodetic point of the tile's middle (the library's inverse)
            int64_t la, lo;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_inverse(&z, std::llround(E0 * 1e9), std::llround(N0 * 1e9), &la, &lo));
            long double lat = (long double)la / std::ldexp(1.0L, 61) * 180 / M_PIl;
            long double lon = (long double)lo / std::ldexp(1.0L, 61) * 180 / M_PIl;
            std::snprintf(arg, sizeof arg, "%.12Lf,%.12Lf,%.9f,%g,%g,%g", lat, lon, H0, yaw, pitch, roll);
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_wgs84(&pose, &z, q61((double)lat), q61((double)lon),
                                                           std::llround(H0 * 1e9), q));
        }
        Run r = run({"geoloc", pkgname, "--camera", "cam.cameramodel", "--pixels", "pxp.csv",
                     mode == 0 ? "--pose-map" : "--pose-wgs84", arg, "-o", "gp.csv"});
        TEST_ASSERT_MSG(r.code == 0, "exit %d: %s", r.code, r.err.c_str());
        std::vector<std::string> rows = lines_of(slurp(g_dir + "/gp.csv"));
        TEST_ASSERT_EQUAL_INT(px.size() + 1, rows.size());
        int hits = 0;
        for (size_t k = 0; k < px.size(); ++k) {
            std::vector<std::string> f = split(rows[k + 1]);
            int64_t uq, vq;
            ct_geo g;
            ct_status want = CT_ERR_UNPROJECT;
            if (ct_host::pixel_to_q16(px[k].u, px[k].v, &uq, &vq))
                want = ct_geolocate(pk, &lc.cam, &pose, CT_METHOD_DIRECTIONAL, nullptr, uq, vq, &g);
            check_row(f, mode == 0 ? "--pose-map " : "--pose-wgs84 ", k + 1, want, g, &hits, pk);
            if (want == CT_HIT && mode >= 1) {
                // lat,lon: forward-projected back onto the hit's E,N
                long double la = std::stold(f[7]), lo = std::stold(f[8]);
                int64_t e, n;
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_forward(&z, q61((double)la), q61((double)lo), &e, &n));
                TEST_ASSERT_MSG(std::llabs(e - g.hit.e_nm) < 200000 && std::llabs(n - g.hit.n_nm) < 200000,
                                "row %zu: lat,lon %s,%s are %lld / %lld nm from the hit", k + 1, f[7].c_str(),
                                f[8].c_str(), (long long)(e - g.hit.e_nm), (long long)(n - g.hit.n_nm));
            } else if (mode == 0) {
                TEST_ASSERT(f[7] == "nan" && f[8] == "nan");
            }
        }
        TEST_ASSERT_MSG(hits >= 3, "%s: only %d hits", mode == 0 ? "--pose-map" : "--pose-wgs84", hits);
    }
    // bad poses: one line each, non-zero exit, no output
    const std::vector<std::vector<std::string>> bad = {
        {"tu.ctp", "--pose-wgs84", "36.1,-60,2500,0,0,0"},   // off zone 17
        {"tu.ctp", "--pose-wgs84", "95,-81,2500,0,0,0"},     // latitude beyond 90
        {"tu.ctp", "--pose-wgs84", "36,-81,2500,0,0"},       // five numbers
        {"tu.ctp", "--pose-wgs84", "36,-81,2500,0,x,0"},     // not a number
        {"tu.ctp", "--pose-wgs84", "36,-81,2500,0,0,270"},   // angle beyond 180
        {"t.ctp", "--pose-wgs84", "36,-81,2500,0,0,0"},      // not a UTM package
    };
    for (const auto &b : bad) {
        fs::remove(g_dir + "/gb.csv");
        Run r = run({"geoloc", b[0], "--camera", "cam.cameramodel", "--pixels", "pxp.csv", b[1], b[2], "-o", "gb.csv"});
        TEST_ASSERT_MSG(r.code != 0 && r.err_lines.size() == 1, "%s %s: exit %d, stderr '%s'", b[1].c_str(),
                        b[2].c_str(), r.code, r.err.c_str());
        TEST_ASSERT(!fs::exists(g_dir + "/gb.csv"));
    }
    Run r2 = run({"geoloc", "tu.ctp", "--camera", "cam.cameramodel", "--pixels", "pxp.csv", "--pose-map",
                  "1,2,3,0,0,0", "--pose-wgs84", "36,-81,2500,0,0,0", "-o", "gb.csv"});
    TEST_ASSERT(r2.code != 0 && r2.err_lines.size() == 1);
    fs::remove(g_dir + "/gp.csv");
    fs::remove(g_dir + "/tu.ctp");
}

// --earth-map on a UTM package with curvature (the true Earth): auto picks
// the fitted map for 256 pixels or more (byte-identical to --earth-map
// fitted), the rows are the library's with CT_EFFECT_EARTH_FIT for any
// --threads; the exact map (per-pixel conversions) finds the same statuses
// and hits within a few millimetres (the two paths' images differ by
// micrometres; a grazing ray turns that into millimetres along itself).
void test_geoloc_earth_map()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    ct_host::Terrain t = s->c.t;
    t.geo.epsg = 32617;
    auto cu = dem_cases::make_case("cli-utm", t, 8, 1);
    spit(g_dir + "/tm.ctp", std::string(cu.pkg.begin(), cu.pkg.end()));
    ct_package pu;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&pu, cu.pkg.data(), cu.pkg.size()));
    std::string px = "u,v\n";
    ct_rng rng;
    ct_rng_seed(&rng, 91);
    std::vector<std::pair<double, double>> uv;
    for (int k = 0; k < 1500; ++k) {
        double u = -50 + 2100 * ct_rng_unit(&rng), v = -50 + 1600 * ct_rng_unit(&rng);
        uv.push_back({u, v});
        char line[64];
        std::snprintf(line, sizeof line, "%.17g,%.17g\n", u, v);
        px += line;
    }
    spit(g_dir + "/pxe.csv", px);
    auto q61 = [](double deg) { return (int64_t)std::llround((long double)deg * M_PIl / 180 * std::ldexp(1.0L, 61)); };
    // 40 deg below the horizon, towards the north-west, from 1.5 km above
    // the tile's south-east corner (lat, lon from the library's inverse)
    const double E0 = 500000 + 60 * 30, N0 = 4000000 - 60 * 30, H0 = 1500;
    ct_utm z = {17, 0};
    int64_t la, lo;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_utm_inverse(&z, std::llround(E0 * 1e9), std::llround(N0 * 1e9), &la, &lo));
    const long double lat = (long double)la / std::ldexp(1.0L, 61) * 180 / M_PIl;
    const long double lon = (long double)lo / std::ldexp(1.0L, 61) * 180 / M_PIl;
    char arg[160], slat[40], slon[40];
    std::snprintf(slat, sizeof slat, "%.12Lf", lat);
    std::snprintf(slon, sizeof slon, "%.12Lf", lon);
    std::snprintf(arg, sizeof arg, "%s,%s,%.9f,-45,-40,0", slat, slon, H0);
    int32_t q[4];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(q61(-45), q61(-40), 0, q));
    ct_host::CameraModel cm = ct_host::read_cameramodel(g_dir + "/cam.cameramodel");
    ct_host::LibCamera lc = ct_host::lib_camera(cm, "cam");
    // the pose the command makes of the text it is given (its latitude
    // and longitude to 12 decimals, read back as doubles): the rows are
    // then the library's own answers to the bit (a pose 10^-7 m away moves
    // an unlucky hit by a Q16 unit)
    ct_pose pose;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_wgs84(&pose, &z, q61(std::strtod(slat, nullptr)),
                                                   q61(std::strtod(slon, nullptr)), std::llround(H0 * 1e9), q));
    auto geoloc = [&](const char *map, const char *threads) -> std::string {
        std::vector<std::string> args = {"geoloc", "tm.ctp", "--camera", "cam.cameramodel", "--pixels", "pxe.csv",
                                         "--pose-wgs84", arg, "--effects", "curvature,refraction", "-o", "ge.csv"};
        if (*map) {
            args.push_back("--earth-map");
            args.push_back(map);
        }
        if (*threads) {
            args.push_back("--threads");
            args.push_back(threads);
        }
        Run r = run(args);
        if (r.code != 0) return "failed: --earth-map " + std::string(map) + ": " + r.err;
        return slurp(g_dir + "/ge.csv");
    };
    const std::string fitted = geoloc("fitted", "1");
    TEST_ASSERT_MSG(fitted.compare(0, 7, "failed:") != 0, "%s", fitted.c_str());
    TEST_ASSERT_MSG(geoloc("", "") == fitted, "auto differs from fitted");
    TEST_ASSERT_MSG(geoloc("fitted", "2") == fitted, "fitted: two threads differ from one");
    const std::string exact = geoloc("exact", "");
    TEST_ASSERT_MSG(exact.compare(0, 7, "failed:") != 0, "%s", exact.c_str());
    std::vector<std::string> rf = lines_of(fitted), rx = lines_of(exact);
    TEST_ASSERT_EQUAL_INT(uv.size() + 1, rf.size());
    TEST_ASSERT_EQUAL_INT(uv.size() + 1, rx.size());
    ct_effects fx = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION | CT_EFFECT_EARTH_FIT, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
    int hits = 0, both = 0;
    double apart = 0;
    for (size_t k = 0; k < uv.size(); ++k) {
        std::vector<std::string> f = split(rf[k + 1]), x = split(rx[k + 1]);
        TEST_ASSERT_MSG(f[2] == x[2], "row %zu: fitted %s, exact %s", k + 1, f[2].c_str(), x[2].c_str());
        if (f[2] == "hit") {
            both++;
            double d2 = 0;
            for (int c = 3; c <= 5; ++c) d2 += std::pow(std::stod(f[c]) - std::stod(x[c]), 2);
            apart = std::max(apart, std::sqrt(d2));
        }
        if (k % 37 == 0) {
            int64_t uq, vq;
            TEST_ASSERT(ct_host::pixel_to_q16(uv[k].first, uv[k].second, &uq, &vq));
            ct_geo g;
            ct_status want = ct_geolocate(&pu, &lc.cam, &pose, CT_METHOD_DIRECTIONAL, &fx, uq, vq, &g);
            check_row(f, "fitted ", k + 1, want, g, &hits, &pu);
        }
    }
    std::printf("  --earth-map: %d rows hit; fitted vs exact hits up to %.2g m apart\n", both, apart);
    TEST_ASSERT_MSG(hits >= 10 && both >= 300, "only %d / %d hits", hits, both);
    TEST_ASSERT_MSG(apart <= 0.01, "fitted and exact hits %.3g m apart", apart);
    Run bad = run({"geoloc", "tm.ctp", "--camera", "cam.cameramodel", "--pixels", "pxe.csv", "--pose-wgs84", arg,
                   "--effects", "curvature", "--earth-map", "sometimes", "-o", "ge.csv"});
    TEST_ASSERT(bad.code != 0 && bad.err.find("--earth-map needs auto, fitted or exact") != std::string::npos);
    fs::remove(g_dir + "/ge.csv");
    fs::remove(g_dir + "/pxe.csv");
}

// --tolerance M: the effects ct_effects_for_tolerance picks, said on stderr,
// and the rows are those of --effects with that set; with --effects it is
// refused, as is a negative tolerance.
void test_geoloc_tolerance()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    spit(g_dir + "/pxt.csv", kPixels);
    ct_host::LibCamera lc = ct_host::lib_camera(ct_host::read_cameramodel(g_dir + "/cam.cameramodel"), "cam");
    std::set<std::string> chosen;
    for (const char *tol : {"0", "0.00001", "0.001", "1000"}) {
        Run r = run({"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "pxt.csv", "--tolerance", tol, "-o",
                     "gt.csv"});
        TEST_ASSERT_MSG(r.code == 0, "--tolerance %s: exit %d: %s", tol, r.code, r.err.c_str());
        const size_t at = r.err.find("-> chord ");
        TEST_ASSERT_MSG(at != std::string::npos, "--tolerance %s: stderr '%s'", tol, r.err.c_str());
        const size_t eff = r.err.find(" m, effects: ", at);
        TEST_ASSERT(eff != std::string::npos);
        const std::string chord = r.err.substr(at + 9, eff - (at + 9));
        std::string set = r.err.substr(eff + 13);
        set = set.substr(0, set.find('\n'));
        chosen.insert(set);
        // the library's choice, and the rows of --effects with it
        ct_effects_choice ch;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_effects_for_tolerance(&s->p, &lc.cam, &lc.pose, CT_REFRACTION_K_STD_Q16, 0,
                                                              std::llround(std::stod(tol) * 1e9), &ch));
        const char *names[4] = {"none", "curvature", "refraction", "curvature, refraction"};
        TEST_ASSERT_MSG(set == names[ch.flags & 3u], "--tolerance %s: said '%s', the library chose %u", tol,
                        set.c_str(), ch.flags);
        TEST_ASSERT_MSG(std::llabs(std::llround(std::stod(chord) * 1e9) - ch.chord_nm) <= ch.chord_nm / 100000,
                        "--tolerance %s: chord %s m, library %lld nm", tol, chord.c_str(), (long long)ch.chord_nm);
        const std::string got = slurp(g_dir + "/gt.csv");
        // the same set with the chord as printed: the rows are the same
        // where the chord is not used (every effect here but refraction
        // alone, c < 0) or prints exactly
        char cbuf[64];
        std::snprintf(cbuf, sizeof cbuf, "%.9f", ch.chord_nm * 1e-9);
        Run e = run({"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "pxt.csv", "--effects",
                     set == "none" ? "" : set, "--chord", cbuf, "-o", "ge.csv"});
        TEST_ASSERT_MSG(e.code == 0, "--effects %s: %s", set.c_str(), e.err.c_str());
        TEST_ASSERT_MSG(got == slurp(g_dir + "/ge.csv"), "--tolerance %s: rows differ from --effects %s", tol,
                        set.c_str());
    }
    TEST_ASSERT_MSG(chosen.count("curvature, refraction") && chosen.count("none"), "choices: %zu", chosen.size());
    Run both = run({"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "pxt.csv", "--tolerance", "1",
                    "--effects", "curvature", "-o", "gt.csv"});
    TEST_ASSERT(both.code != 0 && both.err.find("give --effects or --tolerance, not both") != std::string::npos);
    Run neg = run({"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "pxt.csv", "--tolerance", "-1", "-o",
                   "gt.csv"});
    TEST_ASSERT(neg.code != 0 && neg.err.find("--tolerance needs") != std::string::npos);
    fs::remove(g_dir + "/gt.csv");
    fs::remove(g_dir + "/ge.csv");
    fs::remove(g_dir + "/pxt.csv");
}

// One viewshed of test_viewshed: the observer 5 m above post (oi, oj), the
// map point (e, n) of that post; bent: 0 straight, 1 curvature and
// refraction on the sphere, 2 on the true Earth (the UTM copy); the run
// and its GeoTIFF.
struct Viewshed {
    int bent = 0, oi = 0, oj = 0;
    int64_t e = 0, n = 0;
    Run r;
    ct_host::DemRaster vs;
};

const char *const kViewshedLabel[3] = {"", " (curvature, refraction: the sphere)",
                                       " (curvature, refraction: the true Earth)"};

// `conetrace viewshed` of the package p (tu.ctp when v->bent == 2, else
// t.ctp) from v's observer, targets 1.75 m up, into v->r and v->vs: d's
// posts, p's georeference, a PNG written too.
void run_viewshed(const ct_package &p, const ref::Dem &d, Viewshed *v)
{
    int64_t h;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, (int64_t)v->oi << 16, (int64_t)v->oj << 16, 0, &v->e, &v->n, &h));
    char obs[96];
    std::snprintf(obs, sizeof obs, "%.9f,%.9f,5", v->e * 1e-9, v->n * 1e-9);
    std::vector<std::string> args = {"viewshed", v->bent == 2 ? "tu.ctp" : "t.ctp", "--observer", obs,
                                     "--target-height", "1.75", "-o", "vs.tif", "--png", "vs.png"};
    if (v->bent) {
        args.push_back("--effects");
        args.push_back("curvature,refraction");
    }
    v->r = run(args);
    TEST_ASSERT_MSG(v->r.code == 0, "viewshed: exit %d: %s", v->r.code, v->r.err.c_str());
    v->vs = ct_host::read_dem(g_dir + "/vs.tif");
    TEST_ASSERT_EQUAL_INT(d.w, v->vs.width);
    TEST_ASSERT_EQUAL_INT(d.h, v->vs.height);
    TEST_ASSERT(std::fabs(v->vs.geo.origin_e - p.origin_e_nm * 1e-9) < 1e-6 && v->vs.geo.epsg == (int)p.epsg);
    TEST_ASSERT(fs::exists(g_dir + "/vs.png"));
}

// The true Earth's map as the command fits it, into *emap: once around the
// observer A (map, nm) of p (d its posts), out to the tile's farthest
// corner, its relief, the observer's height and a kilometre.
void fit_viewshed_map(const ct_package &p, const ref::Dem &d, const int64_t A[3], ct_earth_map *emap)
{
    const double qe = p.posting_e_nm * 1e-9, qn = p.posting_n_nm * 1e-9;
    double far = 0;
    for (int c = 0; c < 4; ++c)
        far = std::max(far, std::hypot(p.origin_e_nm * 1e-9 + (c & 1 ? d.w : 0) * qe - A[0] * 1e-9,
                                       p.origin_n_nm * 1e-9 + (c & 2 ? d.h : 0) * qn - A[1] * 1e-9));
    const double reach = far + (p.hmax - p.hmin) * p.height_scale_nm * 1e-9 + 5 + 1000;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_earth_map_init(&p, A[0], A[1], A[2], std::llround(reach * 1e9), emap));
}

// Every post of the viewshed v of p (d its posts) as ct_lib's ct_los
// decides it, bit for bit: the posts the command proved hidden from a
// neighbour's blocking point (Shortcut, cmd_viewshed.cpp) without calling
// it included.
void check_viewshed_los(const ct_package &p, const ref::Dem &d, const Viewshed &v)
{
    int64_t gx, gy, gz0, gz, ge, gn, gh;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_map_to_grid(&p, v.e, v.n, 0, &gx, &gy, &gz0));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_surface_height(&p, gx, gy, &gz));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, gx, gy, gz, &ge, &gn, &gh));
    const int64_t A[3] = {v.e, v.n, gh + 5000000000};
    ct_effects fx = {v.bent ? CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION : 0u, CT_REFRACTION_K_STD_Q16,
                     v.bent == 2 ? 0 : CT_EARTH_RADIUS_NM, 0, nullptr};
    ct_earth_map emap;
    if (v.bent == 2) {
        fit_viewshed_map(p, d, A, &emap);
        if (ct_harness_g.current_failed) return;
        fx.earth_map = &emap;
        TEST_ASSERT(v.r.err.find("viewshed: the true Earth, its map fitted once;") != std::string::npos);
    }
    long differ = 0;
    for (int j = 0; j < d.h; ++j)
        for (int i = 0; i < d.w; ++i) {
            int64_t pt[3];
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, (int64_t)i << 16, (int64_t)j << 16,
                                                        (int64_t)d.at(i, j) << 16, &pt[0], &pt[1], &pt[2]));
            pt[2] += 1750000000;
            if (pt[0] == A[0] && pt[1] == A[1]) continue;
            ct_hit hh;
            const ct_status st = ct_los(&p, A, pt, &fx, 10000000, CT_METHOD_DIRECTIONAL, &hh);
            TEST_ASSERT(st == CT_OK || st == CT_HIT || st == CT_BELOW);
            differ += (v.vs.h[(size_t)j * d.w + i] == 1) != (st == CT_OK);
        }
    long proved = -1;
    const size_t at = v.r.err.find(" hidden (");
    TEST_ASSERT(at != std::string::npos && std::sscanf(v.r.err.c_str() + at, " hidden (%ld", &proved) == 1);
    std::printf("  viewshed%s from post (%d, %d): %ld posts proved hidden without ct_los, %ld differ from "
                "ct_los\n", kViewshedLabel[v.bent], v.oi, v.oj, proved, differ);
    TEST_ASSERT_EQUAL_INT(0, differ);
    TEST_ASSERT(proved > 0);
}

// Every post of the viewshed v (d its posts, posting pe x pn m, height
// scale hs m) against the reference's exact segment to the target 1.75 m
// above it (bent: on the sphere): hidden when the first hit lies more than
// the margin (1 cm) before the post; ties (the segment within 1 cm of the
// surface before the margin, or the first hit within 1 cm of it) counted.
void check_viewshed_reference(const ref::Dem &d, ref::ld pe, ref::ld pn, ref::ld hs, const Viewshed &v)
{
    const ref::ld ox = v.oi, oy = v.oj, oz = d.at(v.oi, v.oj) + 5 / hs;
    const ref::ld c = v.bent ? 1 - (ref::ld)CT_REFRACTION_K_STD_Q16 / 65536 : 0, R = 6371000.0L;
    long ties = 0, bad = 0, seen = 0;
    for (int j = 0; j < d.h; ++j)
        for (int i = 0; i < d.w; ++i) {
            const double got = v.vs.h[(size_t)j * d.w + i];
            if (i == v.oi && j == v.oj) {
                TEST_ASSERT(got == 1);
                continue;
            }
            ref::Ray ry;
            ry.ox = ox;
            ry.oy = oy;
            ry.oz = oz;
            ry.dx = i - ox;
            ry.dy = j - oy;
            const ref::ld rho = std::hypot(ry.dx * pe, ry.dy * pn);
            ry.kz = c * rho * rho / (2 * R) / hs;
            const ref::ld tz = d.at(i, j) + 1.75L / hs;
            ry.dz = tz - oz - ry.kz;
            ry.tend = 1;
            const ref::ld len = std::sqrt(rho * rho + std::pow((tz - oz) * hs, 2));
            const ref::ld tcut = 1 - 0.01L / len, tie_t = 0.01L / len;
            ref::Hit hh = ref::trace(d, ry);
            const ref::ld clear = ref::min_clearance(d, ry, 0, std::max<ref::ld>(0, tcut - tie_t)) * hs;
            if (std::fabs(clear) < 0.01L || (hh.status == ref::HIT && std::fabs(hh.t - tcut) < tie_t)) {
                ties++;
                continue;
            }
            const bool ref_seen = !(hh.status == ref::HIT && hh.t < tcut);
            if ((got == 1) != ref_seen) bad++;
            seen += ref_seen;
        }
    std::printf("  viewshed%s from post (%d, %d), 5 m up, targets 1.75 m: %ld posts seen by the reference, %ld "
                "ties, %ld disagree\n", kViewshedLabel[v.bent], v.oi, v.oj, seen, ties, bad);
    TEST_ASSERT_EQUAL_INT(0, bad);
    TEST_ASSERT(ties * 10 < d.w * d.h && seen > 50);
}

// viewshed's errors: an observer off the tile, a bad radius, an Earth
// radius without --effects, no observer.
void check_viewshed_errors()
{
    Run off = run({"viewshed", "t.ctp", "--observer", "1,2,3", "-o", "vs.tif"});
    TEST_ASSERT(off.code != 0 && off.err.find("is not over the tile") != std::string::npos);
    Run rad = run({"viewshed", "t.ctp", "--observer", "500000,4000000,3", "--radius", "0", "-o", "vs.tif"});
    TEST_ASSERT(rad.code != 0 && rad.err.find("--radius needs") != std::string::npos);
    Run radius = run({"viewshed", "t.ctp", "--observer", "500000,4000000,3", "--earth-radius", "6e6", "-o", "vs.tif"});
    TEST_ASSERT(radius.code != 0 && radius.err.find("--earth-radius needs --effects") != std::string::npos);
    Run noobs = run({"viewshed", "t.ctp", "-o", "vs.tif"});
    TEST_ASSERT(noobs.code != 0 && noobs.err.find("needs --observer") != std::string::npos);
}

// `conetrace viewshed` against a brute-force exact line of sight per post by
// the independent reference tracer (tests/kit/reference.hpp): the observer 5 m
// above a post of the test DEM, every post a target 1.75 m above it; hidden
// when the reference's first hit of the segment lies more than the margin
// (1 cm) before the post.  Identical except ties (the segment within 1 cm
// of the surface before the margin, or the first hit within 1 cm of it:
// counted); straight and with curvature and refraction (the sphere, as the
// reference's bent segment; and on a UTM copy of the DEM the true Earth,
// which differs from the sphere by far less than the ties over this 2 km
// tile); every post also exactly as ct_los decides it (the posts the
// command proves hidden from a neighbour's blocking point included); plus
// the GeoTIFF's georeference and the errors.
void test_viewshed()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    const ref::Dem d = dem_cases::ref_dem(s->c.t);
    const ref::ld pe = std::fabs(s->p.posting_e_nm * 1e-9L), pn = std::fabs(s->p.posting_n_nm * 1e-9L),
                  hs = s->p.height_scale_nm * 1e-9L;
    // the same terrain on UTM zone 17N: --effects is the true Earth there
    ct_host::Terrain tu = s->c.t;
    tu.geo.epsg = 32617;
    const dem_cases::Case cu = dem_cases::make_case("cli-utm", tu, 8, 1);
    spit(g_dir + "/tu.ctp", std::string(cu.pkg.begin(), cu.pkg.end()));
    ct_package pu;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&pu, cu.pkg.data(), cu.pkg.size()));
    for (int bent = 0; bent < 3; ++bent)  // straight, the sphere, the true Earth
        for (int oi : {20, 41}) {
            const ct_package &p = bent == 2 ? pu : s->p;
            Viewshed v;
            v.bent = bent;
            v.oi = oi;
            v.oj = oi == 20 ? 30 : 12;
            run_viewshed(p, d, &v);
            if (ct_harness_g.current_failed) return;
            check_viewshed_los(p, d, v);
            if (ct_harness_g.current_failed) return;
            check_viewshed_reference(d, pe, pn, hs, v);
            if (ct_harness_g.current_failed) return;
        }
    check_viewshed_errors();
    if (ct_harness_g.current_failed) return;
    fs::remove(g_dir + "/vs.tif");
    fs::remove(g_dir + "/vs.png");
}

// `conetrace shadows` against a ray to the sun per post by the independent
// reference tracer (the same grid ray, from ct_ray_from_map, 0.1 m above
// each post): lit exactly where the reference finds no hit, except ties
// (the ray passing within 1 cm of the surface: counted); --method
// incremental gives the same map; the sun below the horizon and an unknown
// method are errors.
void test_shadows()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    const ct_package &p = s->p;
    const ref::Dem d = dem_cases::ref_dem(s->c.t);
    const ref::ld hs = p.height_scale_nm * 1e-9L;
    for (const char *sun : {"135,20", "300,6", "10,60"}) {
        Run r = run({"shadows", "t.ctp", "--sun", sun, "--lift", "0.1", "-o", "sh.tif", "--png", "sh.png"});
        TEST_ASSERT_MSG(r.code == 0, "shadows: exit %d: %s", r.code, r.err.c_str());
        ct_host::DemRaster sh = ct_host::read_dem(g_dir + "/sh.tif");
        TEST_ASSERT(sh.width == d.w && sh.height == d.h && fs::exists(g_dir + "/sh.png"));
        double az, el;
        TEST_ASSERT(std::sscanf(sun, "%lf,%lf", &az, &el) == 2);
        const double sc = std::ldexp(1.0, 40);
        const int64_t de = std::llround(std::sin(az * M_PI / 180) * std::cos(el * M_PI / 180) * sc),
                      dn = std::llround(std::cos(az * M_PI / 180) * std::cos(el * M_PI / 180) * sc),
                      dh = std::llround(std::sin(el * M_PI / 180) * sc);
        long lit = 0, ties = 0, bad = 0;
        for (int j = 0; j < d.h; ++j)
            for (int i = 0; i < d.w; ++i) {
                int64_t e, n, h;
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, (int64_t)i << 16, (int64_t)j << 16,
                                                            (int64_t)d.at(i, j) << 16, &e, &n, &h));
                ct_ray cr;
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_ray_from_map(&p, e, n, h + 100000000, de, dn, dh, &cr));
                ref::Ray ry;
                ry.ox = cr.x_q16 / 65536.0L;
                ry.oy = cr.y_q16 / 65536.0L;
                ry.oz = cr.z_q16 / 65536.0L;
                const ref::ld m = std::max({std::fabs((ref::ld)cr.dx), std::fabs((ref::ld)cr.dy), std::fabs((ref::ld)cr.dz)});
                ry.dx = cr.dx / m;
                ry.dy = cr.dy / m;
                ry.dz = cr.dz / m;
                ref::ld lo = 0, hi = 1e12L;
                ref::clip_box(ry.ox, ry.oy, ry.dx, ry.dy, d.w - 1, d.h - 1, &lo, &hi);
                ry.tend = std::max<ref::ld>(0, hi);
                ref::Hit rh = ref::trace(d, ry);
                const ref::ld clear = ref::min_clearance(d, ry, 1e-9L, ry.tend) * hs;
                if (std::fabs(clear) < 0.01L) {
                    ties++;
                    continue;
                }
                const bool ref_lit = rh.status != ref::HIT;
                const bool got = sh.h[(size_t)j * d.w + i] == 1;
                if (got != ref_lit) bad++;
                lit += ref_lit;
            }
        // the exact ray cell by cell gives the same map, bit for bit
        Run inc = run({"shadows", "t.ctp", "--sun", sun, "--lift", "0.1", "--method", "incremental", "-o", "shi.tif"});
        TEST_ASSERT_MSG(inc.code == 0, "shadows --method incremental: exit %d: %s", inc.code, inc.err.c_str());
        const ct_host::DemRaster shi = ct_host::read_dem(g_dir + "/shi.tif");
        TEST_ASSERT(shi.h == sh.h);
        long own = -1;
        const size_t at = r.err.find(" lit (");
        TEST_ASSERT(at != std::string::npos && std::sscanf(r.err.c_str() + at, " lit (%ld in one step", &own) == 1);
        std::printf("  shadows, sun %s: %ld posts lit by the reference (%ld of them in one step), "
                    "%ld ties, %ld disagree; incremental: the same map\n",
                    sun, lit, own, ties, bad);
        TEST_ASSERT_EQUAL_INT(0, bad);
        TEST_ASSERT(ties * 10 < d.w * d.h && lit > 0);
    }
    Run below = run({"shadows", "t.ctp", "--sun", "90,-3", "-o", "sh.tif"});
    TEST_ASSERT(below.code != 0 && below.err.find("below the horizon") != std::string::npos);
    Run nosun = run({"shadows", "t.ctp", "-o", "sh.tif"});
    TEST_ASSERT(nosun.code != 0 && nosun.err.find("needs --sun") != std::string::npos);
    Run meth = run({"shadows", "t.ctp", "--sun", "90,30", "--method", "fastest", "-o", "sh.tif"});
    TEST_ASSERT(meth.code != 0 && meth.err.find("unknown method 'fastest'") != std::string::npos);
    fs::remove(g_dir + "/sh.tif");
    fs::remove(g_dir + "/shi.tif");
    fs::remove(g_dir + "/sh.png");
}

// `conetrace view`: the oblique30 scene's camera over its package, no
// effects; its range image against surface points projected by mrcal
// (tests/kit/scene.hpp: visible points, their pixel by mrcal_project, their
// range from the reference tracer's first hit): each point's range lies
// between its four neighbouring pixel centres' rendered ranges (0.1 % to
// spare), where those four agree within 2 % (not across an occluding edge).
void test_view()
{
    scene::World *w = scene::load_world(std::string(CT_SCENES_DIR) + "/oblique30.scene");
    spit(g_dir + "/view.ctp", std::string(w->bytes.begin(), w->bytes.end()));
    const std::string model = std::string(CT_SCENES_DIR) + "/oblique30.cameramodel";
    Run r = run({"view", "view.ctp", "--camera", model, "-o", "view.png", "--range", "range.tif"});
    TEST_ASSERT_MSG(r.code == 0, "view: exit %d: %s", r.code, r.err.c_str());
    auto png = OIIO::ImageInput::open(g_dir + "/view.png");
    TEST_ASSERT(png != nullptr && png->spec().width == (int)w->s.width && png->spec().height == (int)w->s.height);
    png->close();
    auto in = OIIO::ImageInput::open(g_dir + "/range.tif");
    TEST_ASSERT(in != nullptr);
    const int W = in->spec().width, H = in->spec().height;
    TEST_ASSERT(W == (int)w->s.width && H == (int)w->s.height && in->spec().nchannels == 1);
    std::vector<float> rg((size_t)W * H);
    TEST_ASSERT(in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, rg.data()));
    in->close();
    scene::SimOptions o;
    o.effects = w->s.effects & scene::FX_DISTORTION;  // the view is traced without bending
    o.n = 400;
    o.seed = 99;
    scene::SimStats ss;
    std::vector<scene::Sample> smp = scene::simulate(*w, o, &ss);
    const scene::ld *C = w->cam.host_pose.centre_m;
    long checked = 0, edges = 0;
    double worst = 0;
    for (const scene::Sample &sm : smp) {
        if (!sm.visible) continue;
        const int i = (int)std::floor(sm.u), j = (int)std::floor(sm.v);
        if (i < 0 || j < 0 || i + 1 >= W || j + 1 >= H) continue;
        const float q[4] = {rg[(size_t)j * W + i], rg[(size_t)j * W + i + 1], rg[(size_t)(j + 1) * W + i],
                            rg[(size_t)(j + 1) * W + i + 1]};
        const double lo = *std::min_element(q, q + 4), hi = *std::max_element(q, q + 4);
        TEST_ASSERT(std::isfinite(lo) && std::isfinite(hi));
        if (hi > 1.02 * lo) {
            edges++;
            continue;
        }
        const double range = (double)std::sqrt(std::pow(sm.first[0] - C[0], 2) + std::pow(sm.first[1] - C[1], 2) +
                                               std::pow(sm.first[2] - C[2], 2));
        const double out = std::max(0.0, std::max(lo - range, range - hi)) / range;
        worst = std::max(worst, out);
        checked++;
    }
    std::printf("  view: %ld points between their neighbours' rendered ranges (worst outside by %.2g of the range), "
                "%ld at occluding edges left out\n", checked, worst, edges);
    TEST_ASSERT_MSG(worst <= 1e-3, "a point's range %.3g outside its neighbours'", worst);
    TEST_ASSERT(checked >= 200);
    Run bad = run({"view", "view.ctp", "-o", "v.png"});
    TEST_ASSERT(bad.code != 0 && bad.err.find("needs --camera") != std::string::npos);
    fs::remove(g_dir + "/view.ctp");
    fs::remove(g_dir + "/view.png");
    fs::remove(g_dir + "/range.tif");
    delete w;
}

// `conetrace demo` (make demo's main job) on the bundled DEM and the
// oblique30 scene's camera: every geolocated pixel of pixels.csv is the
// library's (the same package built by `conetrace build --reduce 3`, the same
// effects), its dot lies where its map point falls in the picture (the
// test's own georeference arithmetic from the crop and zoom the PNG states),
// and the picture there has the dot's range colour (not a golden image).
void test_demo()
{
    const std::string dem = std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif";
    const std::string model = std::string(CT_FIXTURES_DIR) + "/scenes/oblique30.cameramodel";
    Run r = run({"demo", dem, "--camera", model, "--step", "64", "-o", "demo_out"});
    TEST_ASSERT_MSG(r.code == 0, "demo: exit %d: %s", r.code, r.err.c_str());
    TEST_ASSERT(r.out.find("picture: demo_out/footprint.png") != std::string::npos);
    TEST_ASSERT(r.out.find("(the same hits, bit for bit)") != std::string::npos);
    Run b = run({"build", dem, "--reduce", "3", "-o", "demo_pkg.ctp"});
    TEST_ASSERT_MSG(b.code == 0, "build: %s", b.err.c_str());
    const std::string bytes = slurp(g_dir + "/demo_pkg.ctp");
    ct_package pk;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&pk, (const uint8_t *)bytes.data(), bytes.size()));
    ct_host::LibCamera lc = ct_host::lib_camera(ct_host::read_cameramodel(model), model);
    // the picture and what it says of itself
    auto in = OIIO::ImageInput::open(g_dir + "/demo_out/footprint.png");
    TEST_ASSERT(in != nullptr);
    const OIIO::ImageSpec spec = in->spec();
    TEST_ASSERT_EQUAL_INT(3, spec.nchannels);
    std::vector<uint8_t> px((size_t)spec.width * spec.height * 3);
    TEST_ASSERT(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data()));
    in->close();
    const std::string desc = spec.get_string_attribute("ImageDescription");
    int i0, i1, j0, j1, zoom;
    const size_t at = desc.find("posts ");
    TEST_ASSERT_MSG(at != std::string::npos && std::sscanf(desc.c_str() + at, "posts %d..%d x %d..%d of the DEM, %d",
                                                           &i0, &i1, &j0, &j1, &zoom) == 5,
                    "description '%s'", desc.c_str());
    TEST_ASSERT_EQUAL_INT(std::max(300, (i1 - i0 + 1) * zoom), spec.width);
    TEST_ASSERT_EQUAL_INT((j1 - j0 + 1) * zoom + 40, spec.height);
    // the rows
    std::vector<std::string> rows = lines_of(slurp(g_dir + "/demo_out/pixels.csv"));
    TEST_ASSERT(rows.size() > 1 && rows[0] == "u,v,status,E,N,h,range,steps,px,py");
    TEST_ASSERT_EQUAL_INT(16 * 12 + 1, rows.size());  // every 64th pixel of 1024 x 768
    // the demo's effects: those a 10 cm tolerance calls for (its default)
    TEST_ASSERT(r.out.find("chosen for a 0.1 m tolerance") != std::string::npos);
    ct_effects_choice ch;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_effects_for_tolerance(&pk, &lc.cam, &lc.pose, CT_REFRACTION_K_STD_Q16, 0,
                                                          100000000, &ch));
    ct_effects fx = {ch.flags | CT_EFFECT_EARTH_FIT, CT_REFRACTION_K_STD_Q16, 0, ch.chord_nm, nullptr};
    struct Dot {
        int x, y;
        double range;
    };
    std::vector<Dot> dots;
    double rmin = 1e300, rmax = 0;
    const double pe = pk.posting_e_nm * 1e-9, pn = pk.posting_n_nm * 1e-9;
    for (size_t k = 1; k < rows.size(); ++k) {
        std::vector<std::string> f = split(rows[k]);
        TEST_ASSERT_EQUAL_INT(10, f.size());
        int64_t uq, vq;
        TEST_ASSERT(ct_host::pixel_to_q16(std::stod(f[0]), std::stod(f[1]), &uq, &vq));
        ct_geo g;
        const ct_status want = ct_geolocate(&pk, &lc.cam, &lc.pose, CT_METHOD_DIRECTIONAL, &fx, uq, vq, &g);
        TEST_ASSERT_MSG(f[2] == ct_host::status_name(want), "row %zu: %s, library %s", k, f[2].c_str(),
                        ct_host::status_name(want).c_str());
        if (want != CT_HIT && want != CT_HIT_VOID) continue;
        TEST_ASSERT_MSG(f[3] == ct_host::nm_to_decimal(g.hit.e_nm) && f[4] == ct_host::nm_to_decimal(g.hit.n_nm) &&
                            f[5] == ct_host::nm_to_decimal(g.hit.h_nm),
                        "row %zu: the hit is not the library's", k);
        const double x = ((g.hit.e_nm - pk.origin_e_nm) * 1e-9 / pe - i0) * zoom;
        const double y = ((g.hit.n_nm - pk.origin_n_nm) * 1e-9 / pn - j0) * zoom;
        TEST_ASSERT_MSG(std::stoi(f[8]) == (int)std::floor(x) && std::stoi(f[9]) == (int)std::floor(y),
                        "row %zu: dot at (%s, %s), the georeference puts it at (%.2f, %.2f)", k, f[8].c_str(),
                        f[9].c_str(), x, y);
        TEST_ASSERT(x >= 0 && y >= 0 && x < (i1 - i0 + 1) * zoom && y < (j1 - j0 + 1) * zoom);
        const double rg = std::stod(f[6]);
        dots.push_back({(int)std::floor(x), (int)std::floor(y), rg});
        rmin = std::min(rmin, rg);
        rmax = std::max(rmax, rg);
    }
    TEST_ASSERT_MSG(dots.size() >= 150, "only %zu hits", dots.size());
    // each dot's centre has its colour, or a neighbour's whose dot (radius
    // 2) covers it; the camera's mark (radius 7, heading 60 px) is drawn last
    const double cx = ((lc.pose.e_nm - pk.origin_e_nm) * 1e-9 / pe - i0) * zoom;
    const double cy = ((lc.pose.n_nm - pk.origin_n_nm) * 1e-9 / pn - j0) * zoom;
    int checked = 0;
    for (const Dot &d : dots) {
        if (std::hypot(d.x - cx, d.y - cy) < 70) continue;
        const uint8_t *c = &px[((size_t)d.y * spec.width + d.x) * 3];
        bool ok = false;
        for (const Dot &e : dots) {
            if (std::abs(e.x - d.x) > 2 || std::abs(e.y - d.y) > 2) continue;
            const ct_host::Rgb v = ct_host::viridis((e.range - rmin) / std::max(1.0, rmax - rmin));
            ok = ok || (c[0] == v.r && c[1] == v.g && c[2] == v.b);
        }
        TEST_ASSERT_MSG(ok, "the picture at (%d, %d) is (%d, %d, %d), no dot's colour", d.x, d.y, c[0], c[1], c[2]);
        checked++;
    }
    std::printf("  demo: %zu hits of %zu pixels, %d dots checked in the %dx%d picture (posts %d..%d x %d..%d, zoom %d)\n",
                dots.size(), rows.size() - 1, checked, spec.width, spec.height, i0, i1, j0, j1, zoom);
    TEST_ASSERT(checked >= 100);
    Run bad = run({"demo", dem, "-o", "demo_out"});
    TEST_ASSERT(bad.code != 0 && bad.err.find("demo needs --camera") != std::string::npos);
    fs::remove_all(g_dir + "/demo_out");
    fs::remove(g_dir + "/demo_pkg.ctp");
}

// --effects curvature,refraction with --refraction-k and --earth-radius:
// the rows are the library's ct_geolocate with the same ct_effects, bit for
// bit, and (with an exaggerated 30 km earth) differ from the straight rays.
void test_geoloc_effects()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    spit(g_dir + "/px.csv", kPixels);
    Run r0 = run({"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "-o", "g0.csv"});
    TEST_ASSERT_MSG(r0.code == 0, "exit %d: %s", r0.code, r0.err.c_str());
    struct Opt {
        std::vector<std::string> extra;
        ct_effects fx;
    };
    const Opt opts[] = {
        {{"--effects", "curvature, refraction", "--refraction-k", "0.25", "--earth-radius", "30000"},
         {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, 16384, INT64_C(30000000000000), 0, nullptr}},
        {{"--effects", "refraction", "--earth-radius", "20000"},
         {CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, INT64_C(20000000000000), 0, nullptr}},
        {{"--effects", "curvature"}, {CT_EFFECT_CURVATURE, 0, CT_EARTH_RADIUS_NM, 0, nullptr}},
    };
    std::vector<std::string> rows0 = lines_of(slurp(g_dir + "/g0.csv"));
    ct_host::LibCamera lc = ct_host::lib_camera(ct_host::read_cameramodel(g_dir + "/cam.cameramodel"), "cam");
    std::vector<ct_host::PixelRow> px = ct_host::read_pixels_csv(g_dir + "/px.csv");
    for (const Opt &o : opts) {
        std::vector<std::string> args = {"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv"};
        args.insert(args.end(), o.extra.begin(), o.extra.end());
        args.push_back("-o");
        args.push_back("g1.csv");
        Run r = run(args);
        TEST_ASSERT_MSG(r.code == 0, "%s: exit %d: %s", o.extra[1].c_str(), r.code, r.err.c_str());
        std::vector<std::string> rows = lines_of(slurp(g_dir + "/g1.csv"));
        TEST_ASSERT_EQUAL_INT(rows0.size(), rows.size());
        int hits = 0, differ = 0;
        for (size_t k = 0; k < px.size(); ++k) {
            std::vector<std::string> f = split(rows[k + 1]);
            int64_t uq, vq;
            ct_status want = CT_ERR_UNPROJECT;
            ct_geo g;
            if (ct_host::pixel_to_q16(px[k].u, px[k].v, &uq, &vq))
                want = ct_geolocate(&s->p, &lc.cam, &lc.pose, CT_METHOD_DIRECTIONAL, &o.fx, uq, vq, &g);
            check_row(f, o.extra[1] + " ", k + 1, want, g, &hits);
            if (want == CT_HIT) {
                TEST_ASSERT(f[6] == std::to_string(g.hit.steps));
                differ += rows[k + 1] != rows0[k + 1];
            }
        }
        TEST_ASSERT(hits >= 6);
        // every off-centre hit moves (a nadir camera: the centre pixel's
        // ray is vertical and does not bend)
        TEST_ASSERT_MSG(differ >= hits - 1, "%s: only %d of %d hits differ from the straight rays",
                        o.extra[1].c_str(), differ, hits);
    }
    fs::remove(g_dir + "/g0.csv");
    fs::remove(g_dir + "/g1.csv");
}

// A lens model without a closed form in the library (mrcal's splined
// stereographic) is baked into an unprojection grid: the command's rows
// equal the library's on the same baked grid, for the default and an
// explicit --grid-step.
void test_geoloc_splined_grid()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    std::string txt = "{\n    'lensmodel':  'LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=32',\n"
                      "    'intrinsics': [ 3800, 3801, 1023.5, 767.5";
    for (int j = 0; j < 12; ++j)
        for (int i = 0; i < 16; ++i) {
            char b[64];
            std::snprintf(b, sizeof b, ", %.6f, %.6f", 0.002 * std::sin(0.4 * i + 0.3 * j),
                          -0.0015 * std::cos(0.2 * i - 0.5 * j));
            txt += b;
        }
    char tail[256];
    std::snprintf(tail, sizeof tail,
                  " ],\n    'extrinsics': [ 3.141592653589793, 0, 0, %.17g, %.17g, %.17g ],\n"
                  "    'imagersize': [ 2048, 1536 ],\n}\n",
                  -s->centre[0], s->centre[1], s->centre[2]);
    txt += tail;
    spit(g_dir + "/spl.cameramodel", txt);
    spit(g_dir + "/px.csv", kPixels);
    for (double step : {ct_host::kDefaultGridStepPx, 8.0}) {
        std::vector<std::string> args = {"geoloc", "t.ctp", "--camera", "spl.cameramodel", "--pixels", "px.csv",
                                         "-o", "gs.csv"};
        if (step != ct_host::kDefaultGridStepPx) {
            args.push_back("--grid-step");
            args.push_back("8");
        }
        Run r = run(args);
        TEST_ASSERT_MSG(r.code == 0, "exit %d: %s", r.code, r.err.c_str());
        std::vector<std::string> rows = lines_of(slurp(g_dir + "/gs.csv"));
        TEST_ASSERT_EQUAL_INT(10, rows.size());
        ct_host::LibCamera lc = ct_host::lib_camera(ct_host::read_cameramodel(g_dir + "/spl.cameramodel"), "spl", step);
        TEST_ASSERT_EQUAL_INT(CT_LENS_GRID, lc.cam.lens.model);
        std::vector<ct_host::PixelRow> px = ct_host::read_pixels_csv(g_dir + "/px.csv");
        int hits = 0;
        for (size_t k = 0; k < px.size(); ++k) {
            std::vector<std::string> f = split(rows[k + 1]);
            int64_t uq, vq;
            ct_status want = CT_ERR_UNPROJECT;
            ct_geo g;
            if (ct_host::pixel_to_q16(px[k].u, px[k].v, &uq, &vq))
                want = ct_geolocate(&s->p, &lc.cam, &lc.pose, CT_METHOD_DIRECTIONAL, nullptr, uq, vq, &g);
            check_row(f, "", k + 1, want, g, &hits);
        }
        // pixels of the image hit; the two beyond it are outside the grid
        TEST_ASSERT_MSG(hits == 7, "%d hits", hits);
        TEST_ASSERT(split(rows[6])[2] == "err_unproject" && split(rows[7])[2] == "err_unproject");
        fs::remove(g_dir + "/gs.csv");
    }
    fs::remove(g_dir + "/spl.cameramodel");
}

void test_geoloc_bad_inputs()
{
    Setup *s = setup();
    TEST_ASSERT(s != nullptr);
    spit(g_dir + "/px.csv", kPixels);
    spit(g_dir + "/garbage.cameramodel", "{ 'lensmodel': 'LENSMODEL_OPENCV4', 'intrinsics': [ 1, 2,\n");
    // CAHVORE: mrcal itself cannot unproject it, so it cannot be baked
    std::string cah = s->model_text;
    cah.replace(cah.find("LENSMODEL_OPENCV4"), 17, "LENSMODEL_CAHVORE_linearity=1.00");
    const std::string intr = "[ 3000, 3001.5, 1023.5, 767.5, -0.28, 0.09, 0.0001, -0.0002 ]";
    cah.replace(cah.find(intr), intr.size(), "[ 3000, 3001.5, 1023.5, 767.5, 0, 0, 0, 0, 0, 0, 0, 0 ]");
    spit(g_dir + "/cahvore.cameramodel", cah);
    // libmrcal 2.2 read past the end of these (found by fuzz_host): refused first
    spit(g_dir + "/unclosed.cameramodel", "{ 'lensmodel': 'LENSMODEL_OPENCV4, 'intrinsics' [ 1, 2 ]\n");
    static const char nul_model[] = "{ 'lensmodel':\0 'LENSMODEL_OPENCV4' }\n";
    spit(g_dir + "/nul.cameramodel", std::string(nul_model, sizeof nul_model - 1));
    // mrcal's message quotes the file's carriage returns: blanked
    spit(g_dir + "/cr.cameramodel", "{\r\n 'lensmodel\r\r': 'LENSMODEL_OPENCV4' 3,\r\n");
    // a NUL ended the number's text: '4\0junk' was read as 4
    static const char nul_csv[] = "u,v\n1,2\n3,4\0junk\n";
    spit(g_dir + "/nul.csv", std::string(nul_csv, sizeof nul_csv - 1));
    spit(g_dir + "/badnum.csv", "u,v\n1,2\n3,x4\n");
    spit(g_dir + "/nocol.csv", "u,w\n1,2\n");
    spit(g_dir + "/empty.csv", "");
    spit(g_dir + "/bad.ctp", "not a package");
    struct Case {
        std::vector<std::string> args;
        std::string needle;
    };
    const std::vector<std::string> base = {"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv"};
    auto with = [&](const std::string &key, const std::string &val) {
        std::vector<std::string> v = base;
        for (size_t k = 0; k + 1 < v.size(); ++k)
            if (v[k] == key) v[k + 1] = val;
        v.push_back("-o");
        v.push_back("out.csv");
        return v;
    };
    std::vector<Case> cases = {
        {with("--camera", "missing.cameramodel"), "missing.cameramodel"},
        {with("--camera", "garbage.cameramodel"), "garbage.cameramodel"},
        {with("--camera", "cahvore.cameramodel"), "CAHVORE"},
        {with("--camera", "unclosed.cameramodel"),
         "unclosed.cameramodel: not a valid mrcal .cameramodel (a string not closed"},
        {with("--camera", "nul.cameramodel"), "nul.cameramodel: not a valid mrcal .cameramodel (a NUL byte"},
        {with("--camera", "cr.cameramodel"), "cr.cameramodel: not a valid mrcal .cameramodel ("},
        {with("--pixels", "nul.csv"), "nul.csv:3: bad number '4?junk' in column v"},
        {with("--pixels", "missing.csv"), "missing.csv"},
        {with("--pixels", "badnum.csv"), "badnum.csv:3"},
        {with("--pixels", "nocol.csv"), "nocol.csv:1"},
        {with("--pixels", "empty.csv"), "empty.csv"},
        {with("t.ctp", "bad.ctp"), "bad.ctp"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "-o", "out.csv"}, "--pixels"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv"}, "-o"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "--method", "bogus", "-o", "out.csv"},
         "bogus"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "--effects", "curvature,fog", "-o",
          "out.csv"},
         "fog"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "--effects", "curvature",
          "--refraction-k", "0.1", "-o", "out.csv"},
         "--refraction-k"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "--effects", "refraction",
          "--refraction-k", "2.5", "-o", "out.csv"},
         "--refraction-k"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "--effects", "curvature",
          "--earth-radius", "5", "-o", "out.csv"},
         "--earth-radius"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "--earth-radius", "6e6", "-o",
          "out.csv"},
         "--earth-radius"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "--bogus", "1", "-o", "out.csv"},
         "--bogus"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "--grid-step", "0.5", "-o",
          "out.csv"},
         "--grid-step"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "--threads", "-1", "-o", "out.csv"},
         "--threads"},
        {{"geoloc", "t.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "--threads", "two", "-o",
          "out.csv"},
         "--threads"},
    };
    // pixels 'bad.ctp' swap: the package is the second argument
    cases[11].args = {"geoloc", "bad.ctp", "--camera", "cam.cameramodel", "--pixels", "px.csv", "-o", "out.csv"};
    for (const Case &c : cases) {
        std::set<std::string> before = listing();
        Run r = run(c.args);
        std::string all;
        for (const auto &a : c.args) all += a + " ";
        TEST_ASSERT_MSG(r.code != 0 && r.code < 128, "%s: exit %d", all.c_str(), r.code);
        TEST_ASSERT_MSG(r.out.empty(), "%s: stdout '%s'", all.c_str(), r.out.c_str());
        TEST_ASSERT_MSG(r.err_lines.size() == 1, "%s: %zu stderr lines:\n%s", all.c_str(), r.err_lines.size(),
                        r.err.c_str());
        TEST_ASSERT_MSG(r.err_lines[0].rfind("conetrace: ", 0) == 0 && r.err_lines[0].find(c.needle) != std::string::npos,
                        "%s: stderr '%s' lacks '%s'", all.c_str(), r.err_lines[0].c_str(), c.needle.c_str());
        for (char ch : r.err_lines[0])
            TEST_ASSERT_MSG((unsigned char)ch >= 0x20 && ch != 0x7f, "%s: a control character in '%s'", all.c_str(),
                            r.err_lines[0].c_str());
        TEST_ASSERT_MSG(listing() == before, "%s: the directory changed (partial output or temporary left)",
                        all.c_str());
    }
    // a last comment line without a newline (libmrcal 2.2 read on past the
    // file for the comment's newline): the model as without it
    spit(g_dir + "/comment.cameramodel", s->model_text + "\n# no newline after this comment");
    ct_host::CameraModel a = ct_host::read_cameramodel(g_dir + "/cam.cameramodel");
    ct_host::CameraModel b = ct_host::read_cameramodel(g_dir + "/comment.cameramodel");
    TEST_ASSERT(a.model == b.model && a.intrinsics == b.intrinsics && a.width == b.width && a.height == b.height);
    // an existing output survives a failed run
    spit(g_dir + "/out.csv", "keep me\n");
    Run r = run(with("--pixels", "badnum.csv"));
    TEST_ASSERT(r.code != 0);
    TEST_ASSERT(slurp(g_dir + "/out.csv") == "keep me\n");
}

}  // namespace

int main()
{
    TEST_BEGIN("test_geoloc_cli");
    char tmpl[] = "/tmp/ct_geoloc_cli_XXXXXX";
    if (!mkdtemp(tmpl)) {
        printf("cannot create a scratch directory\n");
        return 1;
    }
    fs::create_directory(std::string(tmpl) + "/work");
    g_dir = std::string(tmpl) + "/work";
    RUN_TEST(test_nm_decimal);
    RUN_TEST(test_geoloc_end_to_end);
    RUN_TEST(test_geoloc_effects);
    RUN_TEST(test_geoloc_poses);
    RUN_TEST(test_geoloc_pose_map_vs_model);
    RUN_TEST(test_geoloc_threads);
    RUN_TEST(test_geoloc_earth_map);
    RUN_TEST(test_geoloc_tolerance);
    RUN_TEST(test_demo);
    RUN_TEST(test_viewshed);
    RUN_TEST(test_shadows);
    RUN_TEST(test_view);
    RUN_TEST(test_geoloc_splined_grid);
    RUN_TEST(test_geoloc_bad_inputs);
    int rc = TEST_END();
    if (!getenv("CT_TEST_KEEP")) fs::remove_all(tmpl);
    return rc;
}
