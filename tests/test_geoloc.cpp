// test_geoloc.cpp -- pixel to ground (ct_geolocate, ct_geolocate_batch)
// against mrcal's projection and the independent reference tracer.
//
// A package is built from a generated DEM (smooth hills, 30 m posting,
// UTM-like coordinates ~(5e5, 4e6) m) with a high wall across it.  For
// cameras looking at it (nadir, oblique, low oblique over the wall; OpenCV
// lenses, and a splined stereographic lens baked into an unprojection
// grid), seeded random points of the bilinear surface are projected to
// pixels with mrcal (mrcal_transform_point_rt + mrcal_project).  Each
// point's visibility is decided by the reference tracer (tests/kit/reference.hpp)
// on the exact ray from the camera centre to the point, with a clearance
// margin so grazing tangents are not counted either way.  Then:
//   - visible points: ct_geolocate returns CT_HIT within GEO_TOL_M
//     horizontally (and vertically) of the point;
//   - occluded points: the hit is the reference's first hit (in front of
//     the point) within GEO_TOL_M, never the point itself;
//   - ct_geolocate_batch gives bit-identical ct_geo records, and all four
//     methods the same hit;
//   - a camera below the terrain is CT_BELOW, sky pixels are CT_MISS, a pixel
//     in a folded lens region CT_ERR_UNPROJECT, and the argument errors
//     (effects, method, camera centre out of range, short buffer) have their
//     codes.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

extern "C" {
#include <mrcal/mrcal.h>
}

#include "camera_host.hpp"
#include "conetrace.h"
#include "dem_cases.hpp"
#include "harness.h"
#include "reference.hpp"

typedef long double ld;

namespace {

const double GEO_TOL_M = 0.02;     // hit vs chosen ground point (30 m posting; measured <= 1.4 cm, the
                                   // splined grid's 2e-7 rad ray error at 3 km; the prepared ray is within 1 mm)
const double RAY_TOL_RAD = 1e-8;   // ray handed to the tracer vs the exact ray
const double GRID_RAY_TOL_RAD = 3e-7;  // the same through a 16 px unprojection grid

struct World {
    dem_cases::Case c;
    ct_package p;
    ref::Dem d;
    int wall_row = 0;
};

World *world()
{
    static World *w = nullptr;
    if (w) return w;
    w = new World;
    const int W = 128, H = 112;
    std::vector<uint16_t> z = dem_cases::smooth(W, H, 42, 4000, 6400);  // 0.25 m LSB: 1000..1600 m
    // a wall 3 posts thick along row 60, 700 m above the hills, columns 10..117
    w->wall_row = 60;
    for (int j = 59; j <= 61; ++j)
        for (int i = 10; i <= 117; ++i) z[(size_t)j * W + i] = (uint16_t)std::min(65535, z[(size_t)j * W + i] + 2800);
    w->c = dem_cases::make_case("geoloc_hills", dem_cases::make_terrain(W, H, z, 0.25), 24, 1);
    if (ct_package_open(&w->p, w->c.pkg.data(), w->c.pkg.size()) != CT_OK) return nullptr;
    w->d.w = W;
    w->d.h = H;
    w->d.z.assign(z.begin(), z.end());
    return w;
}

using dem_cases::Geo;

// quaternion (w, x, y, z) helpers: rotations are composed here and turned
// into Rodrigues vectors directly (atan2, well conditioned at pi), never by
// mrcal's r_from_R
struct Quat {
    ld w, x, y, z;
};
Quat q_axis(ld ax, ld ay, ld az, ld angle)
{
    ld n = std::sqrt(ax * ax + ay * ay + az * az), s = std::sin(angle / 2) / n;
    return {std::cos(angle / 2), ax * s, ay * s, az * s};
}
Quat q_mul(const Quat &a, const Quat &b)
{
    return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
            a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
void q_to_r(Quat q, ld r[3])
{
    if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
    ld s = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
    ld th = 2 * std::atan2(s, q.w);
    ld k = s > 0 ? th / s : 2;
    r[0] = q.x * k, r[1] = q.y * k, r[2] = q.z * k;
}

struct Cam {
    const char *name;
    std::string lens;
    std::vector<double> in;
    unsigned w, h;
    double rt[6];      // rt_cam_ref (map frame = reference)
    ld centre[3];      // map, metres
    ct_host::LibCamera lib;
};

// A camera at `centre` (map metres) looking along azimuth `az` (radians
// clockwise from north) with depression `dep` (radians below horizontal;
// pi/2 = nadir), image top towards the azimuth.
Cam make_cam(const char *name, const std::string &lens, const std::vector<double> &in, unsigned w, unsigned h,
             const ld centre[3], ld az, ld dep)
{
    Cam c;
    c.name = name;
    c.lens = lens;
    c.in = in;
    c.w = w;
    c.h = h;
    for (int k = 0; k < 3; ++k) c.centre[k] = centre[k];
    // R_map_cam: start from a camera looking north horizontally (x east,
    // y down, z north) = rotation by -pi/2 about east; tilt down by dep
    // about east, then turn by az clockwise about up (= -az about +h)
    Quat q0 = q_axis(1, 0, 0, -M_PI / 2);  // camera -> map for the level camera
    Quat tilt = q_axis(1, 0, 0, -dep);
    Quat turn = q_axis(0, 0, 1, -az);
    Quat q_map_cam = q_mul(turn, q_mul(tilt, q0));
    ld r_map_cam[3];
    q_to_r(q_map_cam, r_map_cam);
    ld r_cam_map[3] = {-r_map_cam[0], -r_map_cam[1], -r_map_cam[2]}, R[9];
    ct_host::rotation_from_r(r_cam_map, R);
    for (int k = 0; k < 3; ++k) c.rt[k] = (double)r_cam_map[k];
    for (int i = 0; i < 3; ++i) c.rt[3 + i] = (double)-(R[3 * i] * centre[0] + R[3 * i + 1] * centre[1] + R[3 * i + 2] * centre[2]);
    ct_host::CameraModel m;
    m.model = lens;
    m.intrinsics = in;
    std::memcpy(m.rt_cam_ref, c.rt, sizeof c.rt);
    m.width = w;
    m.height = h;
    c.lib = ct_host::lib_camera(m, name);
    return c;
}

std::vector<Cam> cameras(const World &wd)
{
    Geo g(wd.p);
    ld mid[3];
    g.to_map(63.5, 55.5, 0, mid);
    std::vector<Cam> v;
    const std::vector<double> cv8 = {1500, 1500, 1279.5, 959.5, 0.9, -0.05, 2e-4, -1e-4, 0.01, 1.2, 0.1, 0.003};
    const std::vector<double> cv4 = {2400, 2401, 1023.5, 767.5, -0.28, 0.09, 1e-4, -2e-4};
    const std::vector<double> cv5 = {1800, 1800, 959.5, 539.5, -0.31, 0.12, 3e-4, 2e-4, -0.021};
    {
        // exact nadir (pi about east) 1600 m above the highest hills
        ld c[3] = {mid[0] + 7.3L, mid[1] - 11.9L, 3300};
        v.push_back(make_cam("nadir", "LENSMODEL_OPENCV8", cv8, 2560, 1920, c, 0, M_PI / 2));
    }
    {
        // 45 deg oblique from south of the tile, looking north-north-east
        ld c[3] = {mid[0] - 300, mid[1] - 2600, 3000};
        v.push_back(make_cam("oblique45", "LENSMODEL_OPENCV4", cv4, 2048, 1536, c, 0.2L, M_PI / 4));
    }
    {
        // low oblique (12 deg) from the south, over the wall
        ld c[3] = {mid[0] + 200, mid[1] - 2900, 1900};
        v.push_back(make_cam("low_oblique", "LENSMODEL_OPENCV5", cv5, 1920, 1080, c, -0.05L, 12 * M_PI / 180));
    }
    {
        // a 120 deg splined stereographic lens (baked into an unprojection
        // grid, 16 px step), 55 deg down from the south-east
        std::vector<double> spl = {866.0, 867.5, 999.3, 751.2};
        for (int j = 0; j < 12; ++j)
            for (int i = 0; i < 16; ++i) {
                double a = (i - 7.5) / 7.5, b = (j - 5.5) / 5.5;
                spl.push_back(0.004 * a * b + 0.003 * std::sin(2.1 * a + 0.7 * b));
                spl.push_back(-0.003 * a * a + 0.002 * std::cos(1.3 * b - 0.4 * a));
            }
        ld c[3] = {mid[0] + 900, mid[1] - 1500, 3400};
        v.push_back(make_cam("splined_grid", "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=120", spl,
                             2000, 1500, c, -0.5L, 55 * M_PI / 180));
    }
    return v;
}

// Bilinear surface (codes) at grid (x, y)
ld surface(const World &wd, ld x, ld y) { return ref::surface(wd.d, x, y); }

struct Sample {
    ld P[3];          // chosen ground point, map metres
    int64_t uq, vq;   // its pixel (mrcal), Q16
    bool visible;
    ld first[3];      // the reference's first hit along the exact ray (map)
};

// Reference first hit on the exact ray from the camera centre through P
// (t = 1 at P).  Returns false when the geometry is too close to a tangent
// (clearance below `margin` LSB before the hit) to be judged.
bool reference_first_hit(const World &wd, const Geo &g, const ld C[3], const ld P[3], bool *visible, ld first[3])
{
    ld cg[3], pg[3];
    g.to_grid(C, cg);
    g.to_grid(P, pg);
    ref::Ray r;
    r.ox = cg[0], r.oy = cg[1], r.oz = cg[2];
    r.dx = pg[0] - cg[0], r.dy = pg[1] - cg[1], r.dz = pg[2] - cg[2];
    r.tend = 1.5L;
    ref::Hit h = ref::trace(wd.d, r);
    if (h.status != ref::HIT) return false;
    // a ray that enters the tile below its edge meets terrain the package
    // does not hold (the library says CT_BELOW): not a usable sample
    {
        ld te = 0;
        for (int k = 0; k < 2; ++k) {
            ld o = k ? r.oy : r.ox, dd = k ? r.dy : r.dx, hi = (k ? wd.d.h : wd.d.w) - 1;
            if (o < 0 && dd > 0) te = std::max(te, -o / dd);
            if (o > hi && dd < 0) te = std::max(te, (hi - o) / dd);
        }
        ld ex = std::min<ld>(std::max<ld>(r.ox + te * r.dx, 0), wd.d.w - 1);
        ld ey = std::min<ld>(std::max<ld>(r.oy + te * r.dy, 0), wd.d.h - 1);
        if (r.oz + te * r.dz - ref::surface(wd.d, ex, ey) < 2) return false;
    }
    *visible = std::fabs(h.t - 1) < 1e-7L;
    // clearance: the ray must stay >= 2 LSB (0.5 m) above the surface until
    // 0.5 % of the distance before its first hit
    ld m = ref::min_clearance(wd.d, r, 0, h.t * 0.995L);
    if (m < 2) return false;
    // and it must not graze the surface where it hits (incidence >= 1 deg:
    // at a tangent the hit moves along the ray by the lateral error / sin)
    {
        int i = std::min(wd.d.w - 2, std::max(0, (int)std::floor(h.x)));
        int j = std::min(wd.d.h - 2, std::max(0, (int)std::floor(h.y)));
        ld u = h.x - i, v = h.y - j;
        ld h00 = wd.d.at(i, j), h10 = wd.d.at(i + 1, j), h01 = wd.d.at(i, j + 1), h11 = wd.d.at(i + 1, j + 1);
        ld c = h11 - h10 - h01 + h00;
        // metric slopes (m per m) along E (x) and N (y is south: sign folded below)
        ld sx = ((h10 - h00) + c * v) * g.sc / std::fabs(g.pe), sy = ((h01 - h00) + c * u) * g.sc / std::fabs(g.pn);
        ld n[3] = {-sx, -sy, 1}, d[3] = {r.dx * std::fabs(g.pe), r.dy * std::fabs(g.pn), r.dz * g.sc};
        ld nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + 1), dn = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (std::fabs(n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / (nn * dn) < 0.0175L) return false;
    }
    g.to_map(h.x, h.y, h.z, first);
    return true;
}

void test_geolocate_vs_mrcal()
{
    World *wd = world();
    TEST_ASSERT(wd != nullptr);
    Geo g(wd->p);
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 23 + 7);
    const int want = (int)(600 * ct_test_scale());
    for (Cam &c : cameras(*wd)) {
        mrcal_lensmodel_t lm;
        mrcal_lensmodel_from_name(&lm, c.lens.c_str());
        std::vector<Sample> smp;
        int tries = 0;
        while ((int)smp.size() < want && tries < 200 * want) {
            ++tries;
            ld x = 0.5L + ct_rng_unit(&rng) * (wd->d.w - 2), y = 0.5L + ct_rng_unit(&rng) * (wd->d.h - 2);
            Sample s;
            g.to_map(x, y, surface(*wd, x, y), s.P);
            double Pd[3] = {(double)s.P[0], (double)s.P[1], (double)s.P[2]}, pc[3];
            mrcal_transform_point_rt(pc, NULL, NULL, c.rt, Pd);
            if (!(pc[2] > 0)) continue;
            mrcal_point3_t p3 = {{pc[0], pc[1], pc[2]}};
            mrcal_point2_t q;
            mrcal_project(&q, NULL, NULL, &p3, 1, &lm, c.in.data());
            if (!(q.x >= 0 && q.y >= 0 && q.x <= c.w - 1 && q.y <= c.h - 1)) continue;
            if (!reference_first_hit(*wd, g, c.centre, s.P, &s.visible, s.first)) continue;
            s.uq = std::llround(q.x * 65536);
            s.vq = std::llround(q.y * 65536);
            smp.push_back(s);
        }
        TEST_ASSERT_MSG((int)smp.size() == want, "%s: only %zu usable points", c.name, smp.size());
        std::vector<int64_t> uv;
        std::vector<ct_geo> single(smp.size());
        double worst_h = 0, worst_v = 0, worst_occ = 0, worst_ang = 0;
        long vis = 0, occ = 0, steps = 0;
        for (size_t k = 0; k < smp.size(); ++k) {
            const Sample &s = smp[k];
            uv.push_back(s.uq);
            uv.push_back(s.vq);
            ct_geo &o = single[k];
            ct_status st = ct_geolocate(&wd->p, &c.lib.cam, &c.lib.pose, CT_METHOD_DIRECTIONAL, nullptr, s.uq, s.vq, &o);
            TEST_ASSERT_MSG(st == CT_HIT && o.status == CT_HIT, "%s: point %zu: status %d", c.name, k, (int)st);
            ld hit[3] = {o.hit.e_nm * 1e-9L, o.hit.n_nm * 1e-9L, o.hit.h_nm * 1e-9L};
            const ld *want_p = s.visible ? s.P : s.first;
            double dh = (double)std::hypot(hit[0] - want_p[0], hit[1] - want_p[1]);
            double dv = (double)std::fabs(hit[2] - want_p[2]);
            {
                // the ray handed to the tracer vs the exact ray to the point:
                // pixel rounding (2^-17 px / f), unprojection, pose
                ld pd[3] = {want_p[0] - c.centre[0], want_p[1] - c.centre[1], want_p[2] - c.centre[2]};
                ld dm[3] = {(ld)o.dir_map_q39[0], (ld)o.dir_map_q39[1], (ld)o.dir_map_q39[2]};
                ld cr[3] = {pd[1] * dm[2] - pd[2] * dm[1], pd[2] * dm[0] - pd[0] * dm[2], pd[0] * dm[1] - pd[1] * dm[0]};
                ld ang = std::sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]) /
                         (std::sqrt(pd[0] * pd[0] + pd[1] * pd[1] + pd[2] * pd[2]) *
                          std::sqrt(dm[0] * dm[0] + dm[1] * dm[1] + dm[2] * dm[2]));
                if (s.visible) {
                    worst_ang = std::max(worst_ang, (double)ang);
                    double tol = c.lib.cam.lens.model == CT_LENS_GRID ? GRID_RAY_TOL_RAD : RAY_TOL_RAD;
                    TEST_ASSERT_MSG(ang <= tol, "%s: point %zu: ray %.3Lg rad from the exact ray", c.name, k, ang);
                }
            }
            if (s.visible) {
                ++vis;
                worst_h = std::max(worst_h, dh);
                worst_v = std::max(worst_v, dv);
            } else {
                ++occ;
                worst_occ = std::max(worst_occ, std::max(dh, dv));
                // in front of the chosen point, not on it (when the occluder
                // is not within a couple of metres of it)
                ld dp = std::hypot(hit[0] - s.P[0], hit[1] - s.P[1]);
                ld df = std::hypot(s.first[0] - s.P[0], s.first[1] - s.P[1]);
                TEST_ASSERT_MSG(df < 2 || dp > 1.0L, "%s: occluded point %zu reported at the point itself", c.name, k);
            }
            TEST_ASSERT_MSG(dh <= GEO_TOL_M && dv <= GEO_TOL_M,
                            "%s: point %zu (%s): hit %.4f m horizontally, %.4f m vertically from the expected point",
                            c.name, k, s.visible ? "visible" : "occluded", dh, dv);
            steps += o.hit.steps;
            // all four methods agree
            for (int m = 0; m < CT_METHOD_COUNT; ++m) {
                ct_geo o2;
                TEST_ASSERT_EQUAL_INT(CT_HIT, ct_geolocate(&wd->p, &c.lib.cam, &c.lib.pose, (ct_method)m, nullptr, s.uq, s.vq, &o2));
                TEST_ASSERT(o2.hit.e_nm == o.hit.e_nm && o2.hit.n_nm == o.hit.n_nm && o2.hit.h_nm == o.hit.h_nm);
            }
        }
        // the batch form: bit-identical records
        std::vector<ct_geo> batch(smp.size() + 3);
        std::memset(batch.data(), 0x5a, batch.size() * sizeof(ct_geo));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&wd->p, &c.lib.cam, &c.lib.pose, CT_METHOD_DIRECTIONAL, nullptr,
                                                        uv.data(), smp.size(), batch.data(), batch.size()));
        for (size_t k = 0; k < smp.size(); ++k) {
            TEST_ASSERT_MSG(batch[k].status == single[k].status && batch[k].unproject_iters == single[k].unproject_iters &&
                                std::memcmp(batch[k].ray_cam_q30, single[k].ray_cam_q30, sizeof batch[k].ray_cam_q30) == 0 &&
                                std::memcmp(batch[k].dir_map_q39, single[k].dir_map_q39, sizeof batch[k].dir_map_q39) == 0 &&
                                std::memcmp(&batch[k].hit, &single[k].hit, sizeof batch[k].hit) == 0,
                            "%s: batch record %zu differs from ct_geolocate's", c.name, k);
        }
        // nothing written past count
        const unsigned char *tail = (const unsigned char *)&batch[smp.size()];
        for (size_t b = 0; b < 3 * sizeof(ct_geo); ++b) TEST_ASSERT(tail[b] == 0x5a);
        printf("  %-12s %ld visible points: ray within %.2e rad of the exact one, hit within %.2e m horizontally, "
               "%.2e m vertically; %ld occluded: first hit within %.2e m of the reference's; %.1f steps per pixel\n",
               c.name, vis, worst_ang, worst_h, worst_v, occ, worst_occ, (double)steps / std::max<size_t>(1, smp.size()));
        if (std::string(c.name) == "low_oblique") TEST_ASSERT_MSG(occ > 0, "no occluded point behind the wall");
    }
}

// The wall in front of a chosen point: the first hit is the wall.
void test_occluded_by_wall()
{
    World *wd = world();
    TEST_ASSERT(wd != nullptr);
    Geo g(wd->p);
    std::vector<Cam> cams = cameras(*wd);
    // 25 cells south of the wall, 100 m above its top, looking north 30 deg down
    ld top = 0;
    for (int i = 0; i < wd->d.w; ++i) top = std::max(top, (ld)wd->d.at(i, wd->wall_row));
    ld centre[3];
    g.to_map(63.5L, wd->wall_row + 25, top, centre);
    centre[2] += 100;
    Cam c = make_cam("wall_view", cams[2].lens, cams[2].in, cams[2].w, cams[2].h, centre, 0, 30 * M_PI / 180);
    mrcal_lensmodel_t lm;
    mrcal_lensmodel_from_name(&lm, c.lens.c_str());
    int found = 0;
    // points north of the wall (rows < 59: north is -y) in the view whose
    // reference first hit is the wall
    for (int k = 0; k < 4000 && found < 20; ++k) {
        ld x = 12 + (k % 400) * 0.26L, y = 57 - (k / 400) * 1.3L;
        ld P[3];
        g.to_map(x, y, surface(*wd, x, y), P);
        double Pd[3] = {(double)P[0], (double)P[1], (double)P[2]}, pc[3];
        mrcal_transform_point_rt(pc, NULL, NULL, c.rt, Pd);
        mrcal_point3_t p3 = {{pc[0], pc[1], pc[2]}};
        mrcal_point2_t q;
        mrcal_project(&q, NULL, NULL, &p3, 1, &lm, c.in.data());
        if (!(pc[2] > 0 && q.x >= 0 && q.y >= 0 && q.x <= c.w - 1 && q.y <= c.h - 1)) continue;
        bool visible;
        ld first[3], fg[3];
        if (!reference_first_hit(*wd, g, c.centre, P, &visible, first) || visible) continue;
        g.to_grid(first, fg);
        if (fg[1] < wd->wall_row - 1.5L || fg[1] > wd->wall_row + 1.5L) continue;  // hidden by a hill
        ct_geo o;
        TEST_ASSERT_EQUAL_INT(CT_HIT, ct_geolocate(&wd->p, &c.lib.cam, &c.lib.pose, CT_METHOD_DIRECTIONAL, nullptr,
                                                   std::llround(q.x * 65536), std::llround(q.y * 65536), &o));
        // on the wall (cells of rows 58..61 touch it), well in front of P
        TEST_ASSERT_MSG(o.hit.cell_y >= wd->wall_row - 2 && o.hit.cell_y <= wd->wall_row + 1,
                        "hit in row %d, not on the wall", o.hit.cell_y);
        ld dist_hit = std::hypot(o.hit.e_nm * 1e-9L - c.centre[0], o.hit.n_nm * 1e-9L - c.centre[1]);
        ld dist_p = std::hypot(P[0] - c.centre[0], P[1] - c.centre[1]);
        TEST_ASSERT(dist_hit < dist_p - 60);
        TEST_ASSERT(std::hypot(o.hit.e_nm * 1e-9L - first[0], o.hit.n_nm * 1e-9L - first[1]) <= GEO_TOL_M);
        ++found;
    }
    TEST_ASSERT_MSG(found >= 10, "only %d points hidden by the wall", found);
}

// ct_geolocate_batch over the pixels uv (Q16 pairs) with every method,
// straight and on a sphere: every record as ct_geolocate's (status, rays,
// hit), the steps aside (the batch's runs); check(batch) on each batch.
// *errors: the number of CT_ERR_UNPROJECT records.
template <class F>
void batch_as_single(World *wd, const Cam &c, const std::vector<int64_t> &uv, F check, int *errors)
{
    const size_t n = uv.size() / 2;
    ct_effects sphere = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, CT_EARTH_RADIUS_NM, 0,
                         nullptr};
    *errors = 0;
    for (const ct_effects *fx : {(const ct_effects *)nullptr, (const ct_effects *)&sphere}) {
        for (int m = 0; m < CT_METHOD_COUNT; ++m) {
            std::vector<ct_geo> batch(n);
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&wd->p, &c.lib.cam, &c.lib.pose, (ct_method)m, fx,
                                                            uv.data(), n, batch.data(), n));
            check(batch);
            for (size_t k = 0; k < n; ++k) {
                ct_geo g;
                ct_geolocate(&wd->p, &c.lib.cam, &c.lib.pose, (ct_method)m, fx, uv[2 * k], uv[2 * k + 1], &g);
                ct_hit a = g.hit, b = batch[k].hit;
                a.steps = b.steps = a.iters = b.iters = 0;
                TEST_ASSERT_MSG(g.status == batch[k].status && std::memcmp(&a, &b, sizeof a) == 0 &&
                                    std::memcmp(g.ray_cam_q30, batch[k].ray_cam_q30, sizeof g.ray_cam_q30) == 0 &&
                                    std::memcmp(g.dir_map_q39, batch[k].dir_map_q39, sizeof g.dir_map_q39) == 0,
                                "%s, %s, method %d, pixel %zu: the batch's record differs", c.name,
                                fx ? "sphere" : "straight", m, k);
                *errors += g.status == CT_ERR_UNPROJECT ? 1 : 0;
            }
        }
    }
}

// The batch's runs around the exact nadir camera's principal point, whose
// ray is exactly vertical: with a bent trace (the sphere) that pixel takes
// ct_trace_bent_set's straight vertical trace, its neighbours the runs
// (straight and bent, every method): every record as ct_geolocate's but
// for the steps.
void test_batch_vertical_pixel()
{
    World *wd = world();
    TEST_ASSERT(wd != nullptr);
    std::vector<Cam> cams = cameras(*wd);
    const Cam &nadir = cams[0];
    const int64_t cu = std::llround(nadir.in[2] * 65536), cv = std::llround(nadir.in[3] * 65536);
    std::vector<int64_t> uv;
    for (int k = -5; k <= 6; ++k) {
        uv.push_back(cu + k * 65536);
        uv.push_back(cv);
    }
    int errors;
    batch_as_single(
        wd, nadir, uv,
        [](const std::vector<ct_geo> &batch) {
            TEST_ASSERT_MSG(batch[5].dir_map_q39[0] == 0 && batch[5].dir_map_q39[1] == 0,
                            "the principal point's ray is not vertical (%lld, %lld)",
                            (long long)batch[5].dir_map_q39[0], (long long)batch[5].dir_map_q39[1]);
        },
        &errors);
    TEST_ASSERT_EQUAL_INT(0, errors);
}

// A grid camera's pixels in a batch, which keeps the grid's column sums
// for consecutive pixels of one row in one node column: rows crossing node
// columns both ways, rows a Q16 unit apart (the same node row, another
// fraction), a row across a node row's boundary, a pixel repeated, and a
// pixel outside the grid between pixels of one row.  Every method, straight
// and sphere-bent: every record as ct_geolocate's (the steps aside: the
// batch's runs).
void test_batch_grid_rows()
{
    World *wd = world();
    TEST_ASSERT(wd != nullptr);
    std::vector<Cam> cams = cameras(*wd);
    const Cam &gc = cams[3];
    TEST_ASSERT(gc.lib.cam.lens.model == CT_LENS_GRID);
    std::vector<int64_t> uv;
    auto px = [&](double u, int64_t vq) {
        uv.push_back(std::llround(u * 65536));
        uv.push_back(vq);
    };
    const int64_t v0 = std::llround(700.3 * 65536);
    for (double u = 900; u <= 1000; u += 3.7) px(u, v0);         // across node columns
    for (double u = 1000; u >= 900; u -= 5.3) px(u, v0);         // and back
    for (double u = 900; u <= 1000; u += 3.7) px(u, v0 + 1);     // a Q16 unit down
    px(950, v0 + 1);
    px(950, v0 + 1);                                             // repeated
    px(-500, v0 + 1);                                            // outside the grid
    px(951, v0 + 1);
    for (int k = 0; k < 40; ++k) px(930 + 0.9 * k, std::llround((707 + 0.5 * k) * 65536));  // down across a node row
    int errors;
    batch_as_single(wd, gc, uv, [](const std::vector<ct_geo> &) {}, &errors);
    TEST_ASSERT_EQUAL_INT(2 * CT_METHOD_COUNT, errors);  // the one pixel outside the grid, every time
}

void test_statuses_and_errors()
{
    World *wd = world();
    TEST_ASSERT(wd != nullptr);
    Geo g(wd->p);
    std::vector<Cam> cams = cameras(*wd);
    const Cam &obl = cams[1];
    ct_geo o;
    int64_t cu = std::llround(obl.in[2] * 65536), cv = std::llround(obl.in[3] * 65536);
    TEST_ASSERT_EQUAL_INT(CT_HIT, ct_geolocate(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, nullptr, cu, cv, &o));
    // sky: a camera 2000 m above the tile looking 20 deg up
    {
        ld c[3];
        g.to_map(63.5, 55.5, 0, c);
        c[2] = 4000;
        Cam sky = make_cam("sky", cams[1].lens, cams[1].in, cams[1].w, cams[1].h, c, 1.0L, -20 * M_PI / 180);
        TEST_ASSERT_EQUAL_INT(CT_MISS, ct_geolocate(&wd->p, &sky.lib.cam, &sky.lib.pose, CT_METHOD_DIRECTIONAL, nullptr,
                                                    cu, cv, &o));
        TEST_ASSERT_EQUAL_INT(CT_MISS, o.status);
    }
    // effects: parameters out of range are CT_ERR_EFFECTS for the call
    {
        const ct_effects good = {CT_EFFECT_ALL, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
        std::vector<ct_effects> bad(7, good);
        bad[0].flags = 8u;  // the first unknown flag (4 is CT_EFFECT_EARTH_FIT)
        bad[1].flags = 0x80000000u | CT_EFFECT_CURVATURE;
        bad[2].refraction_k_q16 = 2 * 65536 + 1;
        bad[3].earth_radius_nm = 1000;                     // below 2^40 nm
        bad[4].earth_radius_nm = (INT64_C(1) << 54) + 1;
        bad[5].chord_nm = 1;                               // below 2^10 nm
        bad[6].chord_nm = 1 << 12;                         // segment < 1/64 cell at R = 6371 km
        bad[6].earth_radius_nm = INT64_C(1) << 40;
        {
            // CT_EFFECT_EARTH_FIT without the true Earth is ignored: the
            // straight ray, and the sphere parabola with a radius
            ct_effects fit = {CT_EFFECT_EARTH_FIT, 0, 0, 0, nullptr}, fit_sphere = good, sphere = good;
            fit_sphere.flags |= CT_EFFECT_EARTH_FIT;
            fit_sphere.earth_radius_nm = sphere.earth_radius_nm = CT_EARTH_RADIUS_NM;
            ct_geo a, b;
            TEST_ASSERT_EQUAL_INT(ct_geolocate(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, nullptr, cu, cv, &a),
                                  ct_geolocate(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, &fit, cu, cv, &b));
            TEST_ASSERT(a.hit.e_nm == b.hit.e_nm && a.hit.n_nm == b.hit.n_nm && a.hit.h_nm == b.hit.h_nm);
            TEST_ASSERT_EQUAL_INT(ct_geolocate(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, &sphere, cu, cv, &a),
                                  ct_geolocate(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, &fit_sphere, cu, cv, &b));
            TEST_ASSERT(a.hit.e_nm == b.hit.e_nm && a.hit.n_nm == b.hit.n_nm && a.hit.h_nm == b.hit.h_nm);
        }
        for (const ct_effects &fx : bad) {
            TEST_ASSERT_EQUAL_INT(CT_ERR_EFFECTS, ct_geolocate(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, &fx, cu, cv, &o));
            TEST_ASSERT_EQUAL_INT(CT_ERR_EFFECTS, o.status);
            int64_t uv1[2] = {cu, cv};
            TEST_ASSERT_EQUAL_INT(CT_ERR_EFFECTS, ct_geolocate_batch(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, &fx, uv1, 1, &o, 1));
        }
        TEST_ASSERT_EQUAL_INT(CT_HIT, ct_geolocate(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, &good, cu, cv, &o));
        // k outside [-2, 2] is refused only when refraction is on
        ct_effects curv = good;
        curv.flags = CT_EFFECT_CURVATURE;
        curv.refraction_k_q16 = 9 << 16;
        TEST_ASSERT_EQUAL_INT(CT_HIT, ct_geolocate(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, &curv, cu, cv, &o));
    }
    TEST_ASSERT_EQUAL_INT(CT_ERR_METHOD, ct_geolocate(&wd->p, &obl.lib.cam, &obl.lib.pose, (ct_method)7, nullptr, cu, cv, &o));
    int64_t uv[4] = {cu, cv, cu, cv};
    ct_geo two[2];
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_geolocate_batch(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, nullptr, uv, 2, two, 1));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_geolocate_batch(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, nullptr, nullptr, 2, two, 2));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&wd->p, &obl.lib.cam, &obl.lib.pose, CT_METHOD_DIRECTIONAL, nullptr, nullptr, 0, nullptr, 0));
    ct_camera blank;
    std::memset(&blank, 0, sizeof blank);
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_geolocate(&wd->p, &blank, &obl.lib.pose, CT_METHOD_DIRECTIONAL, nullptr, cu, cv, &o));
    // a camera centre beyond 2^30 cells of the tile
    ct_pose far = obl.lib.pose;
    // (2^60 nm up = 4.6e9 height LSB of 0.25 m > 2^30)
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_init(&far, obl.lib.pose.R_map_cam_q30, obl.lib.pose.e_nm,
                                              obl.lib.pose.n_nm, obl.lib.pose.h_nm + (INT64_C(1) << 60)));
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_geolocate(&wd->p, &obl.lib.cam, &far, CT_METHOD_DIRECTIONAL, nullptr, cu, cv, &o));
    // a camera below the terrain
    ct_pose under = obl.lib.pose;
    ld mid[3];
    g.to_map(63.5, 30.5, 0, mid);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_init(&under, obl.lib.pose.R_map_cam_q30, (int64_t)std::llround(mid[0] * 1e9L),
                                              (int64_t)std::llround(mid[1] * 1e9L), wd->p.height_offset_nm + 1000000000));
    TEST_ASSERT_EQUAL_INT(CT_BELOW, ct_geolocate(&wd->p, &obl.lib.cam, &under, CT_METHOD_DIRECTIONAL, nullptr, cu, cv, &o));
    // a folded lens: pixels beyond the fold are CT_ERR_UNPROJECT, per pixel in a batch
    ct_lens fold = ct_host::lens_from_intrinsics("LENSMODEL_OPENCV4", {1000, 1000, 799.5, 599.5, -0.5, 0, 0, 0}, 1600, 1200);
    ct_camera fc;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init(&fc, &fold));
    int64_t px[4] = {std::llround(799.5 * 65536), std::llround(599.5 * 65536), 0, 0};
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_geolocate_batch(&wd->p, &fc, &cams[0].lib.pose, CT_METHOD_DIRECTIONAL, nullptr, px, 2, two, 2));
    TEST_ASSERT_EQUAL_INT(CT_HIT, two[0].status);
    TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, two[1].status);
    TEST_ASSERT_EQUAL_INT(0, two[1].hit.steps);
}

// ct_effects_for_tolerance's cases (conetrace.h): a camera below every
// post is unbounded, a level ray from below the tallest post reaches the
// tile with no flat-ground bound (the default chord), rays rising from
// above the tile bound nothing (the coarsest chord), a grid camera samples
// its supported extent, a camera that unprojects nothing is
// CT_ERR_UNPROJECT; and the choice is the smallest set whose bound is within
// the tolerance (each bound just met, or just missed, by tol).
void test_effects_choice()
{
    World *wd = world();
    TEST_ASSERT(wd != nullptr);
    const ct_package &p = wd->p;
    const int64_t lo = p.height_offset_nm + (int64_t)p.hmin * p.height_scale_nm;
    const int64_t hi = p.height_offset_nm + (int64_t)(p.hmax + 1) * p.height_scale_nm;
    int64_t e, n, h;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_grid_to_map(&p, 64 << 16, 56 << 16, 0, &e, &n, &h));
    ct_camera pin;
    const ct_lens lens = dem_cases::centred_pinhole(640, 480, 500);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init(&pin, &lens));
    static int32_t axis[48], none[48];
    for (int k = 0; k < 16; ++k) axis[3 * k] = axis[3 * k + 1] = 0, axis[3 * k + 2] = 1 << 30;
    ct_camera grid, empty;
    const ct_unproject_grid ga{4u, 4u, 0, 0, INT64_C(16) << 16, axis, 48}, gn{4u, 4u, 0, 0, INT64_C(16) << 16, none, 48};
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init_grid(&grid, &ga));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init_grid(&empty, &gn));
    const int64_t UNB = INT64_C(1) << 62;
    struct Case {
        const char *name;
        const ct_camera *cam;
        int64_t h_nm, pitch_deg;
        int32_t k_q16;
        ct_status want;
        void (*check)(const ct_effects_choice &);
    };
    const Case cases[] = {
        {"below every post", &pin, lo - 1000000000, -30, CT_REFRACTION_K_STD_Q16, CT_OK,
         [](const ct_effects_choice &c) {
             for (int k = 0; k < 3; ++k) TEST_ASSERT(c.bound_nm[k] == INT64_C(1) << 62);
             TEST_ASSERT_EQUAL_INT(CT_EFFECT_ALL, (int)c.flags);
         }},
        {"level, below the tallest post", &pin, (lo + hi) / 2, 0, CT_REFRACTION_K_STD_Q16, CT_OK,
         [](const ct_effects_choice &c) {
             TEST_ASSERT(c.tan_min_q30 == 0);
             TEST_ASSERT(c.chord_nm == CT_EFFECTS_CHORD_NM);
             TEST_ASSERT(c.bound_nm[0] == INT64_C(1) << 62);
         }},
        {"level, below the tallest post, k = 0", &pin, (lo + hi) / 2, 0, 0, CT_OK,
         [](const ct_effects_choice &c) {
             TEST_ASSERT(c.bound_nm[0] == INT64_C(1) << 62 && c.bound_nm[2] == INT64_C(1) << 62);
             TEST_ASSERT(c.bound_nm[1] == 0);  // curvature alone is exact with no refraction
             TEST_ASSERT_EQUAL_INT(CT_EFFECT_CURVATURE, (int)c.flags);
         }},
        {"rising, above the tile", &pin, hi + 1000000000000, 60, CT_REFRACTION_K_STD_Q16, CT_OK,
         [](const ct_effects_choice &c) {
             TEST_ASSERT(c.bound_nm[0] == 0 && c.bound_nm[1] == 0 && c.bound_nm[2] == 0);
             TEST_ASSERT(c.range_nm == 0 && c.tan_min_q30 == INT64_C(1) << 62);
             TEST_ASSERT_EQUAL_INT(0, (int)c.flags);
             TEST_ASSERT(c.chord_nm == INT64_C(1) << 50);
         }},
        {"a grid camera, the axis 30 deg down", &grid, hi + 1000000000000, -30, CT_REFRACTION_K_STD_Q16, CT_OK,
         [](const ct_effects_choice &c) { TEST_ASSERT(c.samples > 0u && c.bound_nm[0] > 0); }},
        {"a grid camera with no rays", &empty, hi + 1000000000000, -30, CT_REFRACTION_K_STD_Q16, CT_ERR_UNPROJECT,
         nullptr},
        {"k = -2, 30 deg down", &pin, hi + 1000000000000, -30, -2 * 65536, CT_OK, nullptr},
        {"k = 0.13, 5 deg down", &pin, hi + 1000000000000, -5, CT_REFRACTION_K_STD_Q16, CT_OK, nullptr},
        {"k = 0.13, looking down", &pin, hi + 1000000000000, -90, CT_REFRACTION_K_STD_Q16, CT_OK,
         [](const ct_effects_choice &c) { TEST_ASSERT(c.tan_min_q30 > INT64_C(1) << 30); }},
    };
    int capped = 0;
    for (const Case &c : cases) {
        int32_t q[4];
        ct_pose pose;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(0, dem_cases::deg_q61((double)c.pitch_deg), 0, q));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&pose, e, n, c.h_nm, q));
        ct_effects_choice ch;
        const ct_status st = ct_effects_for_tolerance(&p, c.cam, &pose, c.k_q16, 0, 0, &ch);
        TEST_ASSERT_MSG(st == c.want, "%s: %d, expected %d", c.name, st, c.want);
        if (st != CT_OK) continue;
        if (c.check) c.check(ch);
        // the choice against each bound: a tolerance equal to a bound
        // admits it, one nm less does not (the sets in the header's order)
        for (int b = 0; b < 3; ++b) {
            if (ch.bound_nm[b] >= UNB) continue;
            for (int64_t tol : {ch.bound_nm[b], ch.bound_nm[b] - 1}) {
                if (tol < 0) continue;
                ct_effects_choice c2;
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_effects_for_tolerance(&p, c.cam, &pose, c.k_q16, 0, tol, &c2));
                const uint32_t want = ch.bound_nm[0] <= tol   ? 0u
                                      : ch.bound_nm[1] <= tol ? (uint32_t)CT_EFFECT_CURVATURE
                                      : ch.bound_nm[2] <= tol ? (uint32_t)CT_EFFECT_REFRACTION
                                                              : (uint32_t)CT_EFFECT_ALL;
                TEST_ASSERT_MSG(c2.flags == want, "%s, tol %lld: flags %u, expected %u", c.name, (long long)tol,
                                c2.flags, want);
                if (b == 2 && tol == ch.bound_nm[2] && c.k_q16 == -2 * 65536)
                    TEST_ASSERT_EQUAL_INT(CT_EFFECT_REFRACTION, (int)c2.flags);  // |1 - k| = 3 > |k| = 2 > 1
                // the chord: at least 2^10 nm, at most 2^50; between, the
                // largest whose effect on flat ground, chord / tan(dep) in
                // height and the chord itself sideways, fits in what the
                // set's bound leaves of the tolerance
                TEST_ASSERT(c2.chord_nm >= 1024 && c2.chord_nm <= INT64_C(1) << 50);
                if (c2.tan_min_q30 > 0 && c2.tan_min_q30 < UNB && c2.chord_nm > 1024 &&
                    c2.chord_nm < INT64_C(1) << 50) {
                    const int64_t used =
                        c2.flags == CT_EFFECT_ALL
                            ? 0
                            : c2.bound_nm[c2.flags == 0u ? 0 : (c2.flags == CT_EFFECT_CURVATURE ? 1 : 2)];
                    const long double f = std::max(1.0L, std::ldexp(1.0L, 30) / (long double)c2.tan_min_q30);
                    TEST_ASSERT_MSG((long double)c2.chord_nm * f <= (long double)(tol - used) + 1 &&
                                        (long double)(c2.chord_nm + 2) * f > (long double)(tol - used),
                                    "%s, tol %lld: chord %lld nm, tan %lld, rest %lld", c.name, (long long)tol,
                                    (long long)c2.chord_nm, (long long)c2.tan_min_q30, (long long)(tol - used));
                    capped += f == 1.0L;
                }
            }
        }
    }
    TEST_ASSERT_MSG(capped > 0, "no choice had tan(dep) > 1 (the sideways bound untested)");
    // a camera 2^50 nm (1,126 km) east of the tile: each corner's offset
    // capped at 2^49 nm, so the range is at most 2^49.5 nm
    {
        int32_t q[4];
        ct_pose pose;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_quat_from_ypr(0, dem_cases::deg_q61(-30), 0, q));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_from_map(&pose, e + (INT64_C(1) << 50), n - (INT64_C(1) << 50), hi + 1000000000000, q));
        ct_effects_choice ch;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_effects_for_tolerance(&p, &pin, &pose, CT_REFRACTION_K_STD_Q16, 0, 1000000, &ch));
        TEST_ASSERT(ch.range_nm <= (int64_t)(std::sqrt(2.0) * (double)(INT64_C(1) << 49)) + 1);
    }
}

}  // namespace

int main()
{
    TEST_BEGIN("test_geoloc");
    RUN_TEST(test_geolocate_vs_mrcal);
    RUN_TEST(test_occluded_by_wall);
    RUN_TEST(test_statuses_and_errors);
    RUN_TEST(test_batch_vertical_pixel);
    RUN_TEST(test_batch_grid_rows);
    RUN_TEST(test_effects_choice);
    return TEST_END();
}
