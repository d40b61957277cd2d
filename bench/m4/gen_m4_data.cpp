// gen_m4_data.cpp -- bakes the data of the Cortex-M4 instruction count
// (bench/m4/bench_m4.c, scripts/bench_m4.sh) into one C file: the fixture
// package (N = 24, r = 3, slice builder: the 2.83x-the-DEM package that fits
// a flight computer's flash) as a const array, the benchmark's ray families
// (families.hpp, the same generator and seed as ct_bench), and the host's
// results (status and steps of every ray and method), which the target must
// reproduce exactly.  Also a geolocation scene on the same package: the
// OPENCV5 lens of fixtures/scenes/oblique30 on a map-frame pose 2.6 km
// above the tile's mid height, 30 deg down, looking north at the tile's
// centre, and an 8 x 8 grid of pixels over its image with the host's
// ct_geolocate results for each of M4_GEO_FX effects.
//
//   ct_gen_m4_data OUT.c [RAYS_PER_FAMILY]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_m4_data.h"
#include "conetrace.h"
#include "families.hpp"

namespace {

// One m4_grid_pixel initialiser: the host's ct_geolocate (directional) of
// pixel (u, v) -- status, steps and the hit (0 without one).
void put_grid_pixel(FILE *f, const ct_package &p, const ct_camera &cam, const ct_pose &pose, const ct_effects *fx,
                    int64_t u, int64_t v)
{
    ct_geo x;
    ct_geolocate(&p, &cam, &pose, CT_METHOD_DIRECTIONAL, fx, u, v, &x);
    const bool hit = x.status == CT_HIT || x.status == CT_HIT_VOID;
    std::fprintf(f, "  {%d, %uu, {INT64_C(%lld), INT64_C(%lld), INT64_C(%lld)}},\n", (int)x.status, x.hit.steps,
                 hit ? (long long)x.hit.e_nm : 0LL, hit ? (long long)x.hit.n_nm : 0LL, hit ? (long long)x.hit.h_nm : 0LL);
}

// The geolocation scene (see the head comment); false on a library error.
bool geo_data(FILE *f, const ct_package &p)
{
    // fixtures/scenes/oblique30's lens: OPENCV5, 1024 x 768
    const long double in[9] = {2400, 2400, 511.5L, 383.5L, -0.21L, 0.11L, 3e-4L, 2e-4L, -0.02L};
    ct_lens lens = {};
    lens.model = CT_LENS_OPENCV5;
    lens.width = 1024;
    lens.height = 768;
    lens.fx_q32 = std::llround(in[0] * 4294967296.0L);
    lens.fy_q32 = std::llround(in[1] * 4294967296.0L);
    lens.cx_q32 = std::llround(in[2] * 4294967296.0L);
    lens.cy_q32 = std::llround(in[3] * 4294967296.0L);
    for (int k = 0; k < 5; ++k) lens.dist_q48[k] = std::llround(in[4 + k] * 281474976710656.0L);
    ct_camera cam;
    if (ct_camera_init(&cam, &lens) != CT_OK) {
        std::fprintf(stderr, "ct_gen_m4_data: ct_camera_init failed\n");
        return false;
    }
    ct_utm zone;
    if (ct_utm_zone_of_epsg((int32_t)p.epsg, &zone) != CT_OK) {
        std::fprintf(stderr, "ct_gen_m4_data: the package is not on a UTM zone (EPSG %u)\n", p.epsg);
        return false;
    }
    // the tile's centre and mid height; the camera 2.6 km above that, back
    // south by 2.6 km / tan 30 deg, pitched 30 deg down, yaw 0 (north)
    const int64_t ec = p.origin_e_nm + p.posting_e_nm * (int64_t)p.width / 2;
    const int64_t nc = p.origin_n_nm + p.posting_n_nm * (int64_t)p.height / 2;
    const int64_t hmid = p.height_offset_nm + (int64_t)(p.hmin + p.hmax) / 2 * p.height_scale_nm;
    const int64_t up = INT64_C(2600000000000);
    const int64_t centre[3] = {ec, nc - std::llround(2600e9L / std::tan(30 * 3.14159265358979323846L / 180)),
                               hmid + up};
    const int64_t deg = INT64_C(40244552544872904);  // one degree, Q61
    int32_t q[4];
    ct_pose pose;
    if (ct_quat_from_ypr(0, -30 * deg, 0, q) != CT_OK ||
        ct_pose_from_map(&pose, centre[0], centre[1], centre[2], q) != CT_OK) {
        std::fprintf(stderr, "ct_gen_m4_data: the pose fails\n");
        return false;
    }
    std::vector<int64_t> uv;
    for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
            uv.push_back(((int64_t)(64 + 128 * i) << 16) + 12345 * (i + 1));  // off the pixel centres
            uv.push_back(((int64_t)(48 + 96 * j) << 16) + 23456 * (j + 1));
        }
    const size_t n = uv.size() / 2;
    std::vector<ct_geo> g[M4_GEO_FX];
    static ct_earth_map map;
    if (m4_geo_map_init(&p, &map) != CT_OK) {
        std::fprintf(stderr, "ct_gen_m4_data: the kept Earth map fails\n");
        return false;
    }
    for (int e = 0; e < M4_GEO_FX; ++e) {
        ct_effects fx;
        const ct_effects *pf = m4_geo_effects(e, &fx, &map);
        g[e].resize(n);
        std::vector<ct_geo> b(n);
        if (ct_geolocate_batch(&p, &cam, &pose, CT_METHOD_DIRECTIONAL, pf, uv.data(), n, b.data(), n) != CT_OK) {
            std::fprintf(stderr, "ct_gen_m4_data: ct_geolocate_batch failed (effects %d)\n", e);
            return false;
        }
        for (size_t k = 0; k < n; ++k) {
            ct_geo &x = g[e][k];
            ct_geolocate(&p, &cam, &pose, CT_METHOD_DIRECTIONAL, pf, uv[2 * k], uv[2 * k + 1], &x);
            // (not the steps: the batch's runs may shorten a pixel's walk)
            if (x.status != b[k].status ||
                ((x.status == CT_HIT || x.status == CT_HIT_VOID) &&
                 (x.hit.e_nm != b[k].hit.e_nm || x.hit.n_nm != b[k].hit.n_nm || x.hit.h_nm != b[k].hit.h_nm))) {
                std::fprintf(stderr, "ct_gen_m4_data: batch and ct_geolocate differ (effects %d, pixel %zu)\n", e, k);
                return false;
            }
        }
    }
    std::fprintf(f, "const char m4_geo_desc[] = \"oblique30's OPENCV5 lens (1024x768), E %.0f N %.0f, %.0f m above "
                    "the tile's mid height, 30 deg down, north; EPSG %u\";\n",
                 (double)centre[0] * 1e-9, (double)centre[1] * 1e-9, (double)up * 1e-9, p.epsg);
    std::fprintf(f, "const ct_lens m4_geo_lens = {%u, %u, %u, INT64_C(%lld), INT64_C(%lld), INT64_C(%lld), INT64_C(%lld), {",
                 lens.model, lens.width, lens.height, (long long)lens.fx_q32, (long long)lens.fy_q32,
                 (long long)lens.cx_q32, (long long)lens.cy_q32);
    for (int k = 0; k < 8; ++k) std::fprintf(f, "INT64_C(%lld)%s", (long long)lens.dist_q48[k], k < 7 ? ", " : "}};\n");
    std::fprintf(f, "const int64_t m4_geo_centre_nm[3] = {INT64_C(%lld), INT64_C(%lld), INT64_C(%lld)};\n",
                 (long long)centre[0], (long long)centre[1], (long long)centre[2]);
    std::fprintf(f, "const int32_t m4_geo_q30[4] = {%d, %d, %d, %d};\n", q[0], q[1], q[2], q[3]);
    std::fprintf(f, "const uint32_t m4_geo_count = %zuu;\nconst m4_pixel m4_geo_px[%zu] = {\n", n, n);
    for (size_t k = 0; k < n; ++k) {
        std::fprintf(f, "  {{%lld, %lld}, {", (long long)uv[2 * k], (long long)uv[2 * k + 1]);
        for (int e = 0; e < M4_GEO_FX; ++e) std::fprintf(f, "%d%s", (int)g[e][k].status, e + 1 < M4_GEO_FX ? ", " : "}, {");
        for (int e = 0; e < M4_GEO_FX; ++e) std::fprintf(f, "%uu%s", g[e][k].hit.steps, e + 1 < M4_GEO_FX ? ", " : "}, {");
        for (int e = 0; e < M4_GEO_FX; ++e) {
            const ct_geo &x = g[e][k];
            const bool hit = x.status == CT_HIT || x.status == CT_HIT_VOID;
            std::fprintf(f, "{INT64_C(%lld), INT64_C(%lld), INT64_C(%lld)}%s", hit ? (long long)x.hit.e_nm : 0LL,
                         hit ? (long long)x.hit.n_nm : 0LL, hit ? (long long)x.hit.h_nm : 0LL,
                         e + 1 < M4_GEO_FX ? ", " : "}},\n");
        }
    }
    std::fprintf(f, "};\n");
    // the lens as an 8 px unprojection grid: nodes at (-0.5 - 8 + 8 i, ...)
    // from ct_camera_unproject (a node it refuses stays (0, 0, 0))
    const int64_t step = INT64_C(8) << 16, u0 = -(INT64_C(17) << 15), v0 = u0;
    const uint32_t nu = (uint32_t)((((int64_t)lens.width << 16) - u0) / step) + 3u,
                   nv = (uint32_t)((((int64_t)lens.height << 16) - v0) / step) + 3u;
    std::vector<int32_t> nodes;
    const ct_unproject_grid grid = dem_cases::grid_from_camera(cam, u0, v0, step, nu, nv, &nodes);
    ct_camera gcam;
    if (ct_camera_init_grid(&gcam, &grid) != CT_OK) {
        std::fprintf(stderr, "ct_gen_m4_data: the unprojection grid is refused\n");
        return false;
    }
    std::fprintf(f, "static const int32_t m4_grid_nodes[%zu] = {", nodes.size());
    for (size_t k = 0; k < nodes.size(); ++k) std::fprintf(f, "%s%d,", k % 12 == 0 ? "\n" : "", nodes[k]);
    std::fprintf(f, "\n};\nconst ct_unproject_grid m4_geo_grid = {%uu, %uu, INT64_C(%lld), INT64_C(%lld), INT64_C(%lld), "
                    "m4_grid_nodes, %zuu};\n",
                 nu, nv, (long long)u0, (long long)v0, (long long)step, nodes.size());
    std::fprintf(f, "const m4_grid_pixel m4_geo_grid_px[%zu] = {\n", n);
    for (size_t k = 0; k < n; ++k) {
        put_grid_pixel(f, p, gcam, pose, nullptr, uv[2 * k], uv[2 * k + 1]);
    }
    std::fprintf(f, "};\n");
    // 8 runs of 8 neighbouring pixels of a row (the batch's runs)
    std::vector<int64_t> ruv;
    for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
            ruv.push_back(((int64_t)(64 + 116 * j + i) << 16) + 12345);
            ruv.push_back(((int64_t)(48 + 96 * j) << 16) + 23456);
        }
    std::fprintf(f, "const int64_t m4_geo_rows_uv[128] = {");
    for (size_t k = 0; k < ruv.size(); ++k) std::fprintf(f, "%sINT64_C(%lld),", k % 4 == 0 ? "\n  " : " ", (long long)ruv[k]);
    std::fprintf(f, "\n};\nconst m4_grid_pixel m4_geo_rows_px[2][64] = {\n");
    for (int e = 0; e < 2; ++e) {
        ct_effects fx;
        const ct_effects *pf = m4_geo_effects(e, &fx, &map);
        std::fprintf(f, " {\n");
        for (size_t k = 0; k < 64; ++k) put_grid_pixel(f, p, cam, pose, pf, ruv[2 * k], ruv[2 * k + 1]);
        std::fprintf(f, " },\n");
    }
    std::fprintf(f, "};\n");
    // the same rows through the 8 px grid, straight
    std::fprintf(f, "const m4_grid_pixel m4_geo_grid_rows_px[64] = {\n");
    for (size_t k = 0; k < 64; ++k) put_grid_pixel(f, p, gcam, pose, nullptr, ruv[2 * k], ruv[2 * k + 1]);
    std::fprintf(f, "};\n");
    return true;
}

}  // namespace

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: ct_gen_m4_data OUT.c [RAYS_PER_FAMILY]\n");
        return 2;
    }
    const int n = argc > 2 ? std::atoi(argv[2]) : 100;
    ct_host::Terrain t = dem_cases::real_terrain();
    ct_host::BuildOptions o;
    o.sectors = 24;
    o.reduce = 3;
    std::vector<uint8_t> pkg = ct_host::build_package(t, o, nullptr);
    ct_package p;
    if (ct_package_open(&p, pkg.data(), pkg.size()) != CT_OK) {
        std::fprintf(stderr, "ct_gen_m4_data: the package does not open\n");
        return 1;
    }
    auto fams = make_families(t, p, n, 2024);
    std::string tmp = std::string(argv[1]) + ".tmp";
    FILE *f = std::fopen(tmp.c_str(), "w");
    if (!f) {
        std::perror(argv[1]);
        return 1;
    }
    std::fprintf(f, "/* generated by ct_gen_m4_data: do not edit */\n#include \"bench_m4_data.h\"\n\n");
    std::fprintf(f, "const uint32_t m4_pkg_size = %zuu;\n", pkg.size());
    std::fprintf(f, "const uint8_t m4_pkg[%zu] __attribute__((aligned(8))) = {", pkg.size());
    for (size_t k = 0; k < pkg.size(); ++k) std::fprintf(f, "%s%u,", k % 32 == 0 ? "\n" : "", pkg[k]);
    std::fprintf(f, "\n};\n\n");
    size_t total = 0;
    for (const auto &fr : fams) total += fr.rays.size();
    std::fprintf(f, "const uint32_t m4_family_count = %zuu;\n", fams.size());
    std::fprintf(f, "const char *const m4_family_name[%zu] = {", fams.size());
    for (const auto &fr : fams) std::fprintf(f, "\"%s\", ", fr.name.c_str());
    std::fprintf(f, "};\nconst uint32_t m4_family_start[%zu] = {", fams.size() + 1);
    size_t at = 0;
    for (const auto &fr : fams) {
        std::fprintf(f, "%zuu, ", at);
        at += fr.rays.size();
    }
    std::fprintf(f, "%zuu};\n", at);
    std::fprintf(f, "const m4_ray m4_rays[%zu] = {\n", total);
    for (const auto &fr : fams)
        for (const ct_ray &r : fr.rays) {
            ct_hit h[4];
            ct_status st[4];
            for (int m = 0; m < 4; ++m) st[m] = ct_trace(&p, &r, (ct_method)m, &h[m]);
            const ct_bend bd = {M4_BEND_COEFF_Q16, M4_BEND_RADIUS_NM, M4_BEND_CHORD_NM, 0u};
            ct_hit hb;
            ct_status sb = ct_trace_bent(&p, &r, &bd, CT_METHOD_DIRECTIONAL, &hb);
            std::fprintf(f, "  {{%lld, %lld, %lld, %lld, %lld, %lld}, {%d, %d, %d, %d}, {%u, %u, %u, %u}, %d, %u},\n",
                         (long long)r.x_q16, (long long)r.y_q16, (long long)r.z_q16, (long long)r.dx, (long long)r.dy,
                         (long long)r.dz, (int)st[0], (int)st[1], (int)st[2], (int)st[3], h[0].steps, h[1].steps,
                         h[2].steps, h[3].steps, (int)sb, hb.steps);
        }
    std::fprintf(f, "};\n\n");
    if (!geo_data(f, p)) {
        std::fclose(f);
        std::remove(tmp.c_str());
        return 1;
    }
    if (std::fclose(f) != 0 || std::rename(tmp.c_str(), argv[1]) != 0) {
        std::perror(argv[1]);
        std::remove(tmp.c_str());
        return 1;
    }
    return 0;
}
