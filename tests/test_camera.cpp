// test_camera.cpp -- lens models, fixed-point unprojection and the pose,
// against mrcal's own C API (libmrcal 2.2).
//
// Unprojection: for PINHOLE, OPENCV4, OPENCV5, OPENCV8 with realistic and
// strong (wide-angle, corner) distortion, and a lens that folds over inside
// its image, seeded random pixels across the image (plus 10% margin),
// corners, edges and the centre.  For every pixel ct_camera_unproject
// returns a ray, then
//   - mrcal_project(ray) is the input pixel within REPROJ_TOL_PX, and
//   - the angle to mrcal_unproject's ray is <= ANGLE_TOL_RAD;
// or CT_ERR_UNPROJECT, and then mrcal fails too (NaN), or mrcal's ray does
// not re-project to the pixel, or lies outside the camera's valid field
// (beyond the fold, or where the Jacobian's determinant is below the
// library's minimum): never a silently wrong ray, never a refusal of a
// well-posed pixel.  Realistic models must unproject every pixel of the
// image.  Iteration counts are reported (mean, max) beside the cap.
//
// Pose: our Rodrigues (host, long double) vs mrcal_R_from_r on random and
// edge-case vectors (0, tiny, exactly pi: built as angle * axis, never via
// mrcal's r_from_R, which returns near-identity within ~1e-5 rad of pi);
// R_from_r must give back rotations built from their axes (nadir: pi about
// east); the camera centre vs mrcal_transform_point_rt_inverted; the whole
// pixel -> map-direction chain vs mrcal; ct_pose_init's refusals.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

extern "C" {
#include <mrcal/mrcal.h>
}

#include "camera_host.hpp"
#include "conetrace.h"
#include "harness.h"

typedef long double ld;

namespace {

// Bounds stated in docs/geolocation.md, "Measured accuracy" (measured values
// printed below).
const double ANGLE_TOL_RAD = 2.5e-9;   // ours vs mrcal_unproject (well conditioned)
const double REPROJ_TOL_PX = 3e-5;     // mrcal_project(our ray) vs pixel
const double PROJECT_TOL_PX = 2e-5;    // ct_camera_project vs mrcal_project

struct Model {
    const char *name;   // test name
    const char *lens;   // mrcal name
    std::vector<double> in;
    unsigned w, h;
    bool realistic;     // every pixel of the image must unproject
};

std::vector<Model> models()
{
    return {
        {"pinhole", "LENSMODEL_PINHOLE", {1200, 1210, 959.5, 539.5}, 1920, 1080, true},
        {"pinhole_wide", "LENSMODEL_PINHOLE", {300, 300, 1000.2, 750.7}, 2000, 1500, true},
        {"opencv4", "LENSMODEL_OPENCV4", {1400, 1401.5, 1023.5, 767.5, -0.28, 0.09, 1e-4, -2e-4}, 2048, 1536,
         true},
        {"opencv5", "LENSMODEL_OPENCV5", {2200.3, 2200.1, 1511.2, 1003.9, -0.31, 0.12, 3e-4, 2e-4, -0.021}, 3000,
         2000, true},
        {"opencv5_pincushion", "LENSMODEL_OPENCV5", {1800, 1800, 960, 540, 0.25, 0.05, -1e-3, 5e-4, 0.01}, 1920,
         1080, true},
        // a wide-angle rational model like mrcal's tour (OPENCV8, ~160 deg diagonal)
        {"opencv8_wide", "LENSMODEL_OPENCV8",
         {1761.2, 1761.9, 2999.3, 1687.6, 2.82, 1.13, -1.1e-4, -5.3e-5, 0.061, 3.11, 2.21, 0.24}, 6000, 3376, true},
        {"opencv8", "LENSMODEL_OPENCV8",
         {1500, 1500, 1279.5, 959.5, 0.9, -0.05, 2e-4, -1e-4, 0.01, 1.2, 0.1, 0.003}, 2560, 1920, true},
        // strong barrel that folds over inside the image: r_d = r (1 - 0.5 r^2)
        // peaks at r = 0.816 (r_d = 0.544); the corners (r_d ~ 1) have no ray
        {"opencv4_fold", "LENSMODEL_OPENCV4", {1000, 1000, 799.5, 599.5, -0.5, 0.0, 0.0, 0.0}, 1600, 1200, false},
        // strong rational barrel with tangential terms, folding near the corners
        {"opencv8_fold", "LENSMODEL_OPENCV8",
         {900, 905, 1000, 700, -0.6, 0.3, 0.004, -0.003, -0.1, 0.4, 0.05, 0.01}, 2000, 1400, false},
    };
}

bool make_camera(const Model &m, ct_camera *cam)
{
    ct_lens l = ct_host::lens_from_intrinsics(m.lens, m.in, m.w, m.h);
    return ct_camera_init(cam, &l) == CT_OK;
}

mrcal_lensmodel_t mrcal_model(const char *name)
{
    mrcal_lensmodel_t lm;
    mrcal_lensmodel_from_name(&lm, name);
    return lm;
}

ld angle_between(const ld a[3], const ld b[3])
{
    ld c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    ld cn = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    ld d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    return std::atan2(cn, d);
}

// Independent long-double forward model (normalised coordinates) and the
// Jacobian determinant, for judging refusals.
void distort_ld(const Model &m, ld x, ld y, ld *xd, ld *yd, ld *det, ld *smin = nullptr)
{
    ld k[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (size_t i = 4; i < m.in.size(); ++i) k[i - 4] = m.in[i];
    auto f = [&](ld a, ld b, ld *oa, ld *ob) {
        ld r2 = a * a + b * b;
        ld N = 1 + r2 * (k[0] + r2 * (k[1] + r2 * k[4]));
        ld D = 1 + r2 * (k[5] + r2 * (k[6] + r2 * k[7]));
        ld R = N / D;
        *oa = a * R + 2 * k[2] * a * b + k[3] * (r2 + 2 * a * a);
        *ob = b * R + k[2] * (r2 + 2 * b * b) + 2 * k[3] * a * b;
    };
    f(x, y, xd, yd);
    ld e = 1e-7L, ax, ay, bx, by, cx, cy, dx, dy;
    f(x + e, y, &ax, &ay);
    f(x - e, y, &bx, &by);
    f(x, y + e, &cx, &cy);
    f(x, y - e, &dx, &dy);
    ld jxx = (ax - bx) / (2 * e), jyx = (ay - by) / (2 * e), jxy = (cx - dx) / (2 * e), jyy = (cy - dy) / (2 * e);
    *det = jxx * jyy - jxy * jyx;
    if (smin) {
        ld f2 = jxx * jxx + jxy * jxy + jyx * jyx + jyy * jyy;
        *smin = std::sqrt(std::max<ld>(0, (f2 - std::sqrt(std::max<ld>(0, f2 * f2 - 4 * *det * *det))) / 2));
    }
}

// The radial slope d(r R)/dr of the model at radius r (long double).
ld radial_slope(const Model &m, ld r)
{
    ld k[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (size_t i = 4; i < m.in.size(); ++i) k[i - 4] = m.in[i];
    auto g = [&](ld s) {
        ld r2 = s * s;
        return s * (1 + r2 * (k[0] + r2 * (k[1] + r2 * k[4]))) / (1 + r2 * (k[5] + r2 * (k[6] + r2 * k[7])));
    };
    ld e = 1e-7L;
    return (g(r + e) - g(r - e)) / (2 * e);
}

void ray_ld(const int32_t q[3], ld out[3])
{
    for (int k = 0; k < 3; ++k) out[k] = (ld)q[k] / 1073741824.0L;
}

struct Stats {
    long n = 0, ok = 0, refused = 0, refused_in_image = 0, mrcal_nan = 0;
    long iters_sum = 0;
    double ns = 0;
    uint32_t iters_max = 0;
    double max_angle = 0, max_angle_ill = 0, max_reproj = 0;
};

// One pixel: returns "" or a failure description.
std::string check_pixel(const Model &m, const ct_camera &cam, const mrcal_lensmodel_t &lm, int64_t uq, int64_t vq,
                        Stats *st)
{
    const double u = (double)uq / 65536.0, v = (double)vq / 65536.0;
    int32_t ray[3];
    uint32_t it = 0;
    auto t0 = std::chrono::steady_clock::now();
    ct_status s = ct_camera_unproject(&cam, uq, vq, ray, &it);
    st->ns += std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
    mrcal_point2_t q = {{u, v}};
    mrcal_point3_t mv;
    mrcal_unproject(&mv, &q, 1, &lm, m.in.data());
    bool mrcal_ok = std::isfinite(mv.x) && std::isfinite(mv.y) && std::isfinite(mv.z);
    st->n++;
    st->mrcal_nan += !mrcal_ok;
    char buf[512];
    bool in_image = u >= -0.5 && v >= -0.5 && u <= m.w - 0.5 && v <= m.h - 0.5;
    if (s == CT_OK) {
        st->ok++;
        st->iters_sum += it;
        st->iters_max = std::max(st->iters_max, it);
        ld r[3];
        ray_ld(ray, r);
        ld n = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if (std::fabs(n - 1) > 4e-9L || r[2] <= 0) {
            std::snprintf(buf, sizeof buf, "pixel (%.6f, %.6f): ray not unit or behind (|r| = %.12Lf)", u, v, n);
            return buf;
        }
        mrcal_point3_t p = {{(double)r[0], (double)r[1], (double)r[2]}};
        mrcal_point2_t qq;
        mrcal_project(&qq, NULL, NULL, &p, 1, &lm, m.in.data());
        double e = std::hypot(qq.x - u, qq.y - v);
        st->max_reproj = std::max(st->max_reproj, e);
        if (!(e <= REPROJ_TOL_PX)) {
            std::snprintf(buf, sizeof buf, "pixel (%.6f, %.6f): our ray re-projects %.3g px away (mrcal_project)", u,
                          v, e);
            return buf;
        }
        if (mrcal_ok) {
            ld mm[3] = {mv.x, mv.y, mv.z};
            // mrcal's own ray must re-project too for the comparison to mean anything
            mrcal_point2_t q2;
            mrcal_project(&q2, NULL, NULL, &mv, 1, &lm, m.in.data());
            if (std::hypot(q2.x - u, q2.y - v) < 1e-6) {
                // the bound: ANGLE_TOL_RAD where the lens is well conditioned
                // (smallest singular value of the distortion's Jacobian >=
                // 1/4, every realistic pixel); near a fold the Newton
                // residual (<= 2^-31) is divided by that singular value
                double a = (double)angle_between(r, mm);
                ld xd, yd, det, smin;
                distort_ld(m, r[0] / r[2], r[1] / r[2], &xd, &yd, &det, &smin);
                double tol = ANGLE_TOL_RAD + (smin < 0.25L ? (double)(0.5e-9L / smin) : 0.0);
                if (smin >= 0.25L)
                    st->max_angle = std::max(st->max_angle, a);
                else
                    st->max_angle_ill = std::max(st->max_angle_ill, a);
                if (!(a <= tol)) {
                    std::snprintf(buf, sizeof buf,
                                  "pixel (%.6f, %.6f): %.3g rad from mrcal_unproject's ray (tolerance %.3g, "
                                  "sigma_min %.3Lg)",
                                  u, v, a, tol, smin);
                    return buf;
                }
            }
        }
        return "";
    }
    if (s != CT_ERR_UNPROJECT) {
        std::snprintf(buf, sizeof buf, "pixel (%.6f, %.6f): status %d", u, v, (int)s);
        return buf;
    }
    st->refused++;
    st->refused_in_image += in_image;
    if (m.realistic && in_image) {
        std::snprintf(buf, sizeof buf, "pixel (%.6f, %.6f) of a realistic model refused", u, v);
        return buf;
    }
    if (!mrcal_ok) return "";
    // mrcal has a ray: it must be one the library may refuse
    mrcal_point2_t q2;
    mrcal_project(&q2, NULL, NULL, &mv, 1, &lm, m.in.data());
    if (std::hypot(q2.x - u, q2.y - v) > 1e-6) return "";  // mrcal's ray is not a solution
    ld x = (ld)mv.x / mv.z, y = (ld)mv.y / mv.z, xd, yd, det;
    distort_ld(m, x, y, &xd, &yd, &det);
    ld r = std::sqrt(x * x + y * y);
    ld rmax = std::sqrt((ld)cam.r2_max_q32 / 4294967296.0L);
    if (mv.z <= 0 || r >= rmax * (1 - 1e-6L) || det <= 2.0L / 65536 || radial_slope(m, r) <= 1.0L / 128)
        return "";  // beyond the valid field, folded, or ill-conditioned
    std::snprintf(buf, sizeof buf,
                  "pixel (%.6f, %.6f) refused, but mrcal's ray (r = %.6Lf < r_max = %.6Lf, det %.3Lg) is well posed", u,
                  v, r, rmax, det);
    return buf;
}

void test_unproject_vs_mrcal()
{
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 7 + 1);
    const int n_random = (int)(20000 * ct_test_scale());
    for (const Model &m : models()) {
        ct_camera cam;
        TEST_ASSERT_MSG(make_camera(m, &cam), "%s: ct_camera_init refused", m.name);
        mrcal_lensmodel_t lm = mrcal_model(m.lens);
        Stats st;
        std::vector<std::pair<double, double>> px;
        // centre, corners, edge midpoints, and pixel-centre corners
        px.push_back({m.in[2], m.in[3]});
        for (double fu : {-0.5, 0.0, 0.5, 1.0, 1.5})
            for (double fv : {-0.5, 0.0, 0.5, 1.0, 1.5}) px.push_back({fu * (m.w - 1), fv * (m.h - 1)});
        for (int k = 0; k < n_random; ++k) {
            double mu = 0.1 * m.w, mv = 0.1 * m.h;
            px.push_back({-mu + ct_rng_unit(&rng) * (m.w + 2 * mu), -mv + ct_rng_unit(&rng) * (m.h + 2 * mv)});
        }
        for (auto &p : px) {
            int64_t uq = std::llround(p.first * 65536), vq = std::llround(p.second * 65536);
            std::string why = check_pixel(m, cam, lm, uq, vq, &st);
            TEST_ASSERT_MSG(why.empty(), "%s: %s", m.name, why.c_str());
        }
        printf("  %-18s r_max %.4f: %ld pixels, %ld unprojected (%ld refused, %ld of them in the image; mrcal "
               "NaN %ld); iterations mean %.2f max %u (cap %u); max angle vs mrcal %.2e rad (%.2e near a fold); "
               "max re-projection %.2e px; %.0f ns per pixel\n",
               m.name, std::sqrt((double)cam.r2_max_q32 / 4294967296.0), st.n, st.ok, st.refused,
               st.refused_in_image, st.mrcal_nan, st.ok ? (double)st.iters_sum / st.ok : 0.0, st.iters_max,
               CT_UNPROJECT_MAX_ITERS, st.max_angle, st.max_angle_ill, st.max_reproj, st.ns / std::max(1L, st.n));
        if (!m.realistic) TEST_ASSERT_MSG(st.refused_in_image > 0, "%s: the fold was never detected", m.name);
    }
}

void test_unproject_hard_values()
{
    Model m = models()[2];  // opencv4
    ct_camera cam;
    TEST_ASSERT(make_camera(m, &cam));
    int32_t ray[3];
    uint32_t it = 99;
    // the principal point: exactly the optical axis
    int64_t cxq = std::llround(m.in[2] * 65536), cyq = std::llround(m.in[3] * 65536);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_unproject(&cam, cxq, cyq, ray, &it));
    TEST_ASSERT_EQUAL_INT(0, ray[0]);
    TEST_ASSERT_EQUAL_INT(0, ray[1]);
    TEST_ASSERT_EQUAL_INT(1 << 30, ray[2]);
    TEST_ASSERT_EQUAL_INT(0, it);
    // pinhole: pixel cx + fx (fx = 1200 exactly) is 45 degrees off axis
    Model ph = models()[0];
    TEST_ASSERT(make_camera(ph, &cam));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_unproject(&cam, std::llround((959.5 + 1200) * 65536), std::llround(539.5 * 65536), ray, &it));
    TEST_ASSERT(std::abs(ray[0] - 759250125) <= 1);  // 2^30 / sqrt(2)
    TEST_ASSERT(std::abs(ray[2] - 759250125) <= 1);
    TEST_ASSERT_EQUAL_INT(0, ray[1]);
    // beyond 82.9 deg (r^2 > 64) a pinhole refuses
    TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, ct_camera_unproject(&cam, std::llround((959.5 + 1200 * 8.1) * 65536), std::llround(539.5 * 65536), ray, &it));
    // pixels beyond +-2^20
    TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, ct_camera_unproject(&cam, (int64_t)(CT_CAM_MAX_PIXEL + 1) << 16, 0, ray, &it));
    TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, ct_camera_unproject(&cam, 0, INT64_MIN, ray, &it));
    // iters may be NULL
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_unproject(&cam, cxq, cyq, ray, nullptr));
}

// A lens whose tangential term alone folds it: OPENCV4 with p1 = 0.1 and no
// radial terms (the valid field, found along radii, is the whole r <= 8).
// The Jacobian's determinant (1 + 2 p1 y)(1 + 6 p1 y) - 4 p1^2 x^2 vanishes
// near y = -1 / (6 p1) = -1.67.  Pixels imaged from points ever closer to
// that fold (the long-double forward model): each unprojects to a ray that
// re-projects onto its pixel (on either side of the fold), or is refused
// (CT_ERR_UNPROJECT) -- and only near the fold, where the determinant at
// the point is under 1e-3 (conetrace.h: a solution must have a determinant
// of at least CT_UNPROJECT_MIN_DET, 2^-16, and Newton stops after
// CT_UNPROJECT_MAX_ITERS steps).
void test_tangential_fold()
{
    const Model m = {"opencv4_tangential_fold", "LENSMODEL_OPENCV4", {1000, 1000, 1000, 1000, 0, 0, 0.1, 0}, 2000,
                     2000, false};
    ct_camera cam;
    TEST_ASSERT(make_camera(m, &cam));
    long ok = 0, refused = 0, n = 0;
    uint32_t most = 0, most_refused = 0;
    ld worst = 0;
    for (int k = 0; k < 4000; ++k) {
        // y from the fold at -1/(6 p1) outwards by 2^-k/40 .. on both sides, x in [-0.5, 0.5]
        const ld side = (k % 2 == 0) ? 1 : -1;
        const ld y = -1.0L / 0.6L + side * std::ldexp(1.0L, -(k / 2) % 40);
        const ld x = -0.5L + (ld)((k * 37) % 101) / 100;
        ld xd, yd, det;
        distort_ld(m, x, y, &xd, &yd, &det);
        const int64_t uq = std::llround((1000 * xd + 1000) * 65536), vq = std::llround((1000 * yd + 1000) * 65536);
        int32_t ray[3];
        uint32_t it = 0;
        const ct_status st = ct_camera_unproject(&cam, uq, vq, ray, &it);
        n++;
        if (st == CT_OK) {
            ok++;
            most = std::max(most, it);
            // the ray re-projects onto the pixel (the forward model at its x, y)
            ld rx = (ld)ray[0] / ray[2], ry = (ld)ray[1] / ray[2], qx, qy, qd;
            distort_ld(m, rx, ry, &qx, &qy, &qd);
            const ld e = std::hypot(1000 * qx + 1000 - (ld)uq / 65536, 1000 * qy + 1000 - (ld)vq / 65536);
            worst = std::max(worst, e);
            TEST_ASSERT_MSG(e < 1e-3L, "point (%.6Lf, %.9Lf): its ray re-projects %.3Lg px away", x, y, e);
        } else {
            refused++;
            most_refused = std::max(most_refused, it);
            TEST_ASSERT_MSG(st == CT_ERR_UNPROJECT && std::fabs(det) < 1e-3L,
                            "point (%.6Lf, %.9Lf), det %.3Lg: status %d", x, y, det, st);
        }
        if (ct_harness_g.current_failed) return;
    }
    std::printf("  tangential fold: %ld pixels, %ld unprojected (within %.2Lg px, up to %u iterations), %ld refused near "
                "the fold (after up to %u iterations)\n", n, ok, worst, most, refused, most_refused);
    TEST_ASSERT(ok > n / 2 && refused > 0);
}

void test_lens_evil()
{
    ct_camera cam;
    Model m = models()[6];  // opencv8
    ct_lens good = ct_host::lens_from_intrinsics(m.lens, m.in, m.w, m.h), l;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init(&cam, &good));
    struct Case {
        const char *what;
        void (*mutate)(ct_lens *);
    };
    const Case cases[] = {
        {"unknown model", [](ct_lens *x) { x->model = CT_LENS_COUNT; }},
        {"fx = 0", [](ct_lens *x) { x->fx_q32 = 0; }},
        {"fy < 1 px", [](ct_lens *x) { x->fy_q32 = (INT64_C(1) << 32) - 1; }},
        {"fx > 2^20 px", [](ct_lens *x) { x->fx_q32 = ((int64_t)CT_CAM_MAX_PIXEL << 32) + 1; }},
        {"cx beyond 2^20 px", [](ct_lens *x) { x->cx_q32 = -((int64_t)CT_CAM_MAX_PIXEL << 32) - 1; }},
        {"k1 > 1024", [](ct_lens *x) { x->dist_q48[0] = CT_CAM_MAX_DIST + 1; }},
        {"k6 < -1024", [](ct_lens *x) { x->dist_q48[7] = -CT_CAM_MAX_DIST - 1; }},
        {"OPENCV4 with k3 set", [](ct_lens *x) { x->model = CT_LENS_OPENCV4; }},
        {"OPENCV5 with k4 set", [](ct_lens *x) { x->model = CT_LENS_OPENCV5; }},
        {"PINHOLE with k1 set", [](ct_lens *x) { x->model = CT_LENS_PINHOLE; }},
    };
    for (const Case &c : cases) {
        l = good;
        c.mutate(&l);
        ct_status s = ct_camera_init(&cam, &l);
        TEST_ASSERT_MSG(s == CT_ERR_LENS, "%s: expected CT_ERR_LENS, got %d", c.what, (int)s);
        int32_t ray[3];
        // a failed init leaves the camera unusable
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_camera_unproject(&cam, 0, 0, ray, nullptr));
    }
    // host-side conversion refusals
    bool threw = false;
    try {
        ct_host::lens_from_intrinsics("LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=100", {1, 2}, 10, 10);
    } catch (const ct_host::Error &) {
        threw = true;
    }
    TEST_ASSERT(threw);
    threw = false;
    try {
        ct_host::lens_from_intrinsics("LENSMODEL_OPENCV4", {1000, 1000, 10, 10, 0.1}, 10, 10);
    } catch (const ct_host::Error &) {
        threw = true;
    }
    TEST_ASSERT(threw);
    // k1 = -1000, k4 = 1000: the lens folds at r ~ 0.02: a tiny valid field
    l = good;
    l.dist_q48[0] = -(INT64_C(1000) << 48);
    l.dist_q48[5] = INT64_C(1000) << 48;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init(&cam, &l));
    TEST_ASSERT_MSG((double)cam.r2_max_q32 / 4294967296.0 < 0.001, "r2_max %.6f", (double)cam.r2_max_q32 / 4294967296.0);
    // a radial factor whose denominator vanishes: the valid field stops short
    l = good;
    l.dist_q48[0] = 0;
    l.dist_q48[1] = 0;
    l.dist_q48[4] = 0;
    l.dist_q48[5] = -(INT64_C(2) << 48);  // D = 1 - 2 r^2
    l.dist_q48[6] = 0;
    l.dist_q48[7] = 0;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init(&cam, &l));
    TEST_ASSERT_MSG((double)cam.r2_max_q32 / 4294967296.0 < 0.5, "r2_max %.6f", (double)cam.r2_max_q32 / 4294967296.0);
}

void test_project_vs_mrcal()
{
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 11 + 3);
    double worst = 0, worst_rel = 0;
    for (const Model &m : models()) {
        ct_camera cam;
        TEST_ASSERT(make_camera(m, &cam));
        mrcal_lensmodel_t lm = mrcal_model(m.lens);
        ld rmax = std::sqrt((ld)cam.r2_max_q32 / 4294967296.0L);
        for (int k = 0; k < 4000; ++k) {
            ld v[3];
            bool far = k % 2 == 1;
            if (!far) {
                // the ray of a pixel in the image (+10%), by mrcal
                mrcal_point2_t q = {{(-0.1 + 1.2 * (double)ct_rng_unit(&rng)) * m.w,
                                     (-0.1 + 1.2 * (double)ct_rng_unit(&rng)) * m.h}};
                mrcal_point3_t mv;
                mrcal_unproject(&mv, &q, 1, &lm, m.in.data());
                if (!std::isfinite(mv.x) || !std::isfinite(mv.y) || !(mv.z > 0)) continue;
                ld r = std::hypot((ld)mv.x, (ld)mv.y) / mv.z;
                if (r >= rmax * 0.999L) continue;
                v[0] = mv.x, v[1] = mv.y, v[2] = mv.z;
            } else {
                // anywhere in the valid field (pixels far outside the image)
                ld r = rmax * std::sqrt(ct_rng_unit(&rng)) * 0.999L, a = ct_rng_unit(&rng) * 2 * M_PI;
                v[0] = r * std::cos(a), v[1] = r * std::sin(a), v[2] = 1;
            }
            ld nn = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            int32_t q[3];
            for (int i = 0; i < 3; ++i) q[i] = (int32_t)std::llround(v[i] / nn * 1073741824.0L);
            int64_t u, vv;
            ct_status s = ct_camera_project(&cam, q, &u, &vv);
            if (s != CT_OK && far) continue;  // rounding to Q30 may step outside
            TEST_ASSERT_MSG(s == CT_OK, "%s: project refused a ray of the image", m.name);
            mrcal_point3_t p = {{(double)q[0], (double)q[1], (double)q[2]}};
            mrcal_point2_t mq;
            mrcal_project(&mq, NULL, NULL, &p, 1, &lm, m.in.data());
            double e = std::hypot(u / 65536.0 - mq.x, vv / 65536.0 - mq.y);
            if (!far) {
                worst = std::max(worst, e);
                TEST_ASSERT_MSG(e <= PROJECT_TOL_PX, "%s: project %.3g px from mrcal at (%.3f, %.3f)", m.name, e,
                                mq.x, mq.y);
            } else {
                // far out, pixels reach ~1e7: a relative bound
                double dist = std::hypot(mq.x - m.in[2], mq.y - m.in[3]), rel = e / std::max(1.0, dist);
                if (dist > 1e4) worst_rel = std::max(worst_rel, rel);
                TEST_ASSERT_MSG(rel <= 5e-10 || e <= PROJECT_TOL_PX, "%s: project %.3g px (%.3g relative) from mrcal at (%.6g, %.6g)",
                                m.name, e, rel, mq.x, mq.y);
            }
        }
        // behind the camera and outside the field
        int32_t back[3] = {0, 0, -(1 << 30)}, side[3] = {1 << 30, 0, 0};
        int64_t u, vv;
        TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, ct_camera_project(&cam, back, &u, &vv));
        TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, ct_camera_project(&cam, side, &u, &vv));
    }
    printf("  ct_camera_project vs mrcal_project: max %.2e px for rays of the image (+10%%), %.2e relative "
           "for pixels beyond 1e4 px of the centre\n",
           worst, worst_rel);
}

// ---- the valid field's guards (issue 19: branches of camera.c) ------------

// A lens from its intrinsics, fx = fy = 1000 px, centre (0, 0), exact Q48
// distortion coefficients (dyadic values).
struct GuardLens {
    Model m;
    ct_lens l;
};

GuardLens guard_lens(const char *name, const char *lens, std::vector<double> k)
{
    GuardLens g;
    std::vector<double> in = {1000, 1000, 0, 0};
    in.insert(in.end(), k.begin(), k.end());
    g.m = {name, lens, in, 2000, 2000, false};
    g.l = ct_host::lens_from_intrinsics(lens, in, 2000, 2000);
    return g;
}

// The documented guards of the valid field (conetrace.h) in long double at
// r2 = s: R = N/D in [2^-8, 2^8], D >= 2^-16, |R'| <= 2^20, and the slope
// of r R, R + 2 s R', >= 2^-8.
bool guards_ld(const Model &m, ld s, ld *R_out = nullptr, ld *D_out = nullptr)
{
    ld k[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (size_t i = 4; i < m.in.size(); ++i) k[i - 4] = m.in[i];
    const ld N = 1 + s * (k[0] + s * (k[1] + s * k[4])), Np = k[0] + s * (2 * k[1] + 3 * s * k[4]);
    const ld D = 1 + s * (k[5] + s * (k[6] + s * k[7])), Dp = k[5] + s * (2 * k[6] + 3 * s * k[7]);
    const ld R = N / D, Rp = (Np - R * Dp) / D;
    if (R_out) *R_out = R;
    if (D_out) *D_out = D;
    const ld lo = 1.0L / 256;
    return D >= 1.0L / 65536 && R >= lo && R <= 256 && std::fabs(Rp) <= 1048576.0L &&
           R + 2 * s * Rp >= lo;
}

// The first radius where the guards fail, from 0 outwards (steps of 1e-5,
// then bisection), long double.
ld first_failure_ld(const Model &m, ld rmax)
{
    ld good = 0, bad = -1;
    for (ld r = 1e-5L; r <= rmax; r += 1e-5L) {
        if (!guards_ld(m, r * r)) {
            bad = r;
            break;
        }
        good = r;
    }
    if (bad < 0) return rmax;
    for (int i = 0; i < 80; ++i) {
        ld mid = (good + bad) / 2;
        (guards_ld(m, mid * mid) ? good : bad) = mid;
    }
    return good;
}

int32_t q30(ld v) { return (int32_t)std::llroundl(v * 1073741824.0L); }

// ct_camera_project of the ray (x, y, 1): the status, and for CT_OK in *err
// its distance from mrcal_project's pixel in units of the bound
// test_project_vs_mrcal uses: PROJECT_TOL_PX, or far out (beyond 4e4 px)
// 5e-10 of the distance from the centre (*err <= 1: within the bound).
ct_status project_vs_mrcal(const GuardLens &g, const ct_camera &cam, ld x, ld y, double *err)
{
    ld n = std::sqrt(x * x + y * y + 1);
    int32_t q[3] = {q30(x / n), q30(y / n), q30(1 / n)};
    int64_t u = 0, v = 0;
    ct_status s = ct_camera_project(&cam, q, &u, &v);
    if (s != CT_OK) return s;
    mrcal_lensmodel_t lm = mrcal_model(g.m.lens);
    mrcal_point3_t p = {{(double)q[0], (double)q[1], (double)q[2]}};
    mrcal_point2_t mq;
    mrcal_project(&mq, NULL, NULL, &p, 1, &lm, g.m.in.data());
    const double e = std::hypot(u / 65536.0 - mq.x, v / 65536.0 - mq.y), dist = std::hypot(mq.x, mq.y);
    *err = std::min(e / PROJECT_TOL_PX, e / (5e-10 * dist));
    return CT_OK;
}

// Lenses whose radial factor N/D is already below 2^-8 at the valid-field
// scan's first sample (r = 8/256, r^2 = 2^-10): k1 = -1024 makes N = 1 +
// k1 r^2 exactly 0 there (ct_camera_init's scan stops on the R guard, for a
// polynomial lens and, with a denominator, for a rational one), while the
// lens is well behaved nearer the axis.  The valid field is then found by
// bisection: it must end where the long-double model's guards first fail
// (the slope 1 - 3 * 1024 r^2 reaching 2^-8, r = 0.018), rays inside
// project as mrcal projects them, rays beyond are refused.
void test_valid_field_first_sample()
{
    const GuardLens lenses[] = {
        guard_lens("poly_k1_-1024", "LENSMODEL_OPENCV4", {-1024, 0, 0, 0}),
        guard_lens("rational_k1_-1024", "LENSMODEL_OPENCV8", {-1024, 0, 0, 0, 0, 1, 0, 0}),
    };
    for (const GuardLens &g : lenses) {
        ct_camera cam;
        ld R;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init(&cam, &g.l));
        // the reference: the first sample fails on R (not on the slope)
        TEST_ASSERT(!guards_ld(g.m, 1.0L / 1024, &R) && R < 1.0L / 256);
        const ld rref = first_failure_ld(g.m, 8), rmax = std::sqrt((ld)cam.r2_max_q32 / 4294967296.0L);
        TEST_ASSERT_MSG(rref > 0.015L && rref < 0.02L && std::fabs(rmax - rref) < 1e-7L,
                        "%s: valid field r <= %.9Lf, the model's guards fail from %.9Lf", g.m.name, rmax, rref);
        double worst = 0;
        for (int k = 0; k < 16; ++k) {
            const ld a = k * (ld)M_PI / 8, r = rref * (k % 2 ? 0.98L : 0.5L);
            double e = 1e9;
            TEST_ASSERT_EQUAL_INT(CT_OK, project_vs_mrcal(g, cam, r * std::cos(a), r * std::sin(a), &e));
            TEST_ASSERT_MSG(e <= 1, "%s: %.3g x the bound from mrcal", g.m.name, e);
            worst = std::max(worst, e);
            TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT,
                                  project_vs_mrcal(g, cam, 1.02L * rref * std::cos(a), 1.02L * rref * std::sin(a), &e));
            TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT,
                                  project_vs_mrcal(g, cam, std::cos(a) / 32, std::sin(a) / 32, &e));
        }
        std::printf("  %s: valid field r <= %.9Lf (model %.9Lf), projections within %.2g of the bound from mrcal\n", g.m.name,
                    rmax, rref, worst);
    }
}

// A hole in the valid field between the scan's samples: a rational lens
// whose numerator and denominator share the double root r^2 = 1/2,
// D = (1 - 2 r^2)^2, N = D (1 + r^2 / 8): R = 1 + r^2 / 8 wherever D != 0,
// and every sample r = k/32 passes (the nearest, k = 22, 23, lie 17/1024
// from the root), so ct_camera_init takes the whole r <= 8.  D < 2^-16
// (the documented guard) only for |r^2 - 1/2| < 2^-9: rays there must be
// refused (lens_forward re-checks the guards at every point); rays with
// |r^2 - 1/2| >= 0.1 project as mrcal projects them (nearer the root the
// Q32 quotient N/D loses 2^-32 / D relative: 2.7e-5 px at D = 0.006).
void test_valid_field_hole()
{
    const GuardLens g = guard_lens("shared_root", "LENSMODEL_OPENCV8",
                                   {-3.875, 3.5, 0, 0, 0.5, -4, 4, 0});
    ct_camera cam;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init(&cam, &g.l));
    TEST_ASSERT(cam.r2_max_q32 == (int64_t)64 << 32);
    // the reference: the guards hold at every scan sample, and fail in the hole
    for (int k = 1; k <= 256; ++k) TEST_ASSERT(guards_ld(g.m, (ld)k * k / 1024));
    long refused = 0, projected = 0;
    double worst = 0;
    for (int k = 0; k < 400; ++k) {
        const ld a = k * 0.0157L, s = 0.5L + (k % 2 ? 1 : -1) * std::ldexp(1.0L, -10 - (k / 2) % 12);
        ld R, D;
        TEST_ASSERT(!guards_ld(g.m, s, &R, &D) && D < 1.0L / 65536);
        double e;
        TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT,
                              project_vs_mrcal(g, cam, std::sqrt(s) * std::cos(a), std::sqrt(s) * std::sin(a), &e));
        refused++;
        // off the hole, from r = 0.05 to 7.9
        const ld r = 0.05L + 7.85L * k / 399;
        if (std::fabs(r * r - 0.5L) < 0.1L) continue;
        TEST_ASSERT(guards_ld(g.m, r * r));
        e = 1e9;
        TEST_ASSERT_EQUAL_INT(CT_OK, project_vs_mrcal(g, cam, r * std::cos(a), r * std::sin(a), &e));
        TEST_ASSERT_MSG(e <= 1, "r %.4Lf: %.3g x the bound from mrcal", r, e);
        worst = std::max(worst, e);
        projected++;
    }
    std::printf("  hole at r^2 = 1/2: %ld rays in it refused, %ld others within %.2g of the bound from mrcal\n",
                refused, projected, worst);
}

// Newton's full CT_UNPROJECT_MAX_ITERS steps: a pincushion lens (OPENCV4,
// k1 = 2^-8) whose valid field is the whole r <= 8, and pixels imaged (by
// mrcal_project) from points just beyond that edge, r = 8 + 2^-e (e = 14
// .. 24; from 2^-12 out a step may land nearer and save one): each
// Newton step overshoots the edge and is halved back into the field, so
// the iterate halves its distance to the edge per step and the loop ends
// by its count.  The documented answer is CT_ERR_UNPROJECT: the solution
// lies outside the valid field, and the field's closest point, r = 8,
// images 1.75 * 2^-e > 2^-26 (CT_UNPROJECT_TOL_Q32) away.  Pixels from
// r = 8 - 2^-e inside unproject to mrcal's ray.
void test_unproject_max_iters()
{
    const GuardLens g = guard_lens("pincushion_edge", "LENSMODEL_OPENCV4", {1.0 / 256, 0, 0, 0});
    ct_camera cam;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init(&cam, &g.l));
    TEST_ASSERT(cam.r2_max_q32 == (int64_t)64 << 32);
    mrcal_lensmodel_t lm = mrcal_model(g.m.lens);
    for (int e = 14; e <= 24; ++e) {
        for (int side = -1; side <= 1; side += 2) {
            const ld r = 8 + side * std::ldexp(1.0L, -e);
            mrcal_point3_t p = {{(double)r, 0.0, 1.0}};
            mrcal_point2_t q;
            mrcal_project(&q, NULL, NULL, &p, 1, &lm, g.m.in.data());
            const int64_t uq = std::llround(q.x * 65536), vq = std::llround(q.y * 65536);
            int32_t ray[3];
            uint32_t it = 0;
            const ct_status s = ct_camera_unproject(&cam, uq, vq, ray, &it);
            if (side > 0) {
                TEST_ASSERT_MSG(s == CT_ERR_UNPROJECT && it == CT_UNPROJECT_MAX_ITERS,
                                "r = 8 + 2^-%d: status %d after %u iterations", e, (int)s, it);
            } else {
                TEST_ASSERT_MSG(s == CT_OK, "r = 8 - 2^-%d: status %d", e, (int)s);
                mrcal_point2_t qq = {{uq / 65536.0, vq / 65536.0}};
                mrcal_point3_t mv;
                mrcal_unproject(&mv, &qq, 1, &lm, g.m.in.data());
                ld a[3], b[3] = {mv.x, mv.y, mv.z};
                ray_ld(ray, a);
                TEST_ASSERT_MSG(angle_between(a, b) < 2e-9L, "r = 8 - 2^-%d: %.3Lg rad from mrcal", e,
                                angle_between(a, b));
            }
        }
    }
}

// ---- unprojection grids ----------------------------------------------------

// A splined stereographic lens (mrcal's richest model) with a smooth
// distortion of a few pixels on top of the stereographic projection.
ct_host::CameraModel splined_model()
{
    ct_host::CameraModel m;
    const int nx = 16, ny = 12;
    m.model = "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=120";
    m.width = 2000;
    m.height = 1500;
    m.intrinsics = {866.0, 867.5, 999.3, 751.2};
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            double a = (i - 7.5) / 7.5, b = (j - 5.5) / 5.5;
            m.intrinsics.push_back(0.004 * a * b + 0.003 * std::sin(2.1 * a + 0.7 * b));
            m.intrinsics.push_back(-0.003 * a * a + 0.002 * std::cos(1.3 * b - 0.4 * a));
        }
    return m;
}

ct_host::CameraModel opencv8_wide_model()
{
    ct_host::CameraModel m;
    const std::vector<Model> ms = models();
    const Model &w = ms[5];
    m.model = w.lens;
    m.intrinsics = w.in;
    m.width = w.w;
    m.height = w.h;
    return m;
}

// Accuracy vs grid step against mrcal_unproject, over random pixels of the
// image.  Returns the largest angle (rad); counts refusals.
double grid_error(const ct_host::CameraModel &m, double step, int n, long *refused, double *mean)
{
    ct_host::BakedGrid b = ct_host::bake_grid(m, step);
    ct_camera cam;
    if (ct_camera_init_grid(&cam, &b.grid) != CT_OK) return 1e9;
    mrcal_lensmodel_t lm = mrcal_model(m.model.c_str());
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 29 + (uint64_t)step);
    double worst = 0, sum = 0;
    long cnt = 0;
    *refused = 0;
    for (int k = 0; k < n; ++k) {
        double u = -0.5 + ct_rng_unit(&rng) * m.width, v = -0.5 + ct_rng_unit(&rng) * m.height;
        int64_t uq = std::llround(u * 65536), vq = std::llround(v * 65536);
        int32_t ray[3];
        if (ct_camera_unproject(&cam, uq, vq, ray, nullptr) != CT_OK) {
            ++*refused;
            continue;
        }
        mrcal_point2_t q = {{uq / 65536.0, vq / 65536.0}};
        mrcal_point3_t mv;
        mrcal_unproject(&mv, &q, 1, &lm, m.intrinsics.data());
        ld r[3], mm[3] = {mv.x, mv.y, mv.z};
        ray_ld(ray, r);
        double a = (double)angle_between(r, mm);
        worst = std::max(worst, a);
        sum += a;
        ++cnt;
    }
    *mean = cnt ? sum / cnt : 0;
    return worst;
}

void test_grid_accuracy_vs_step()
{
    const double GRID16_TOL_RAD = 3e-7;  // at a 16 px step (docs/geolocation.md)
    for (const ct_host::CameraModel &m : {opencv8_wide_model(), splined_model()}) {
        double prev = 0;
        for (double step : {64.0, 32.0, 16.0, 8.0, 4.0}) {
            long refused = 0;
            double mean = 0, e = grid_error(m, step, (int)(4000 * ct_test_scale()), &refused, &mean);
            ct_host::BakedGrid b = ct_host::bake_grid(m, step);
            printf("  grid %-60.60s step %2.0f px (%4u x %4u nodes, %7.1f KB): max %.2e rad, mean %.2e rad, "
                   "%ld refused\n",
                   m.model.c_str(), step, b.grid.nu, b.grid.nv, b.rays->size() * 4 / 1024.0, e, mean, refused);
            TEST_ASSERT_MSG(refused == 0, "%s step %g: %ld pixels of the image refused", m.model.c_str(), step, refused);
            if (step == 16.0) TEST_ASSERT_MSG(e <= GRID16_TOL_RAD, "%s: %.3g rad at 16 px", m.model.c_str(), e);
            // cubic convergence until the Q30 floor
            if (prev > 1e-8) TEST_ASSERT_MSG(e < prev, "%s: error did not shrink with the step", m.model.c_str());
            prev = e;
        }
    }
}

void test_grid_evil()
{
    ct_host::CameraModel m = splined_model();
    ct_host::BakedGrid b = ct_host::bake_grid(m, 32);
    ct_camera cam;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init_grid(&cam, &b.grid));
    int32_t ray[3];
    int64_t u, v;
    // the principal point unprojects; projection is not available
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_unproject(&cam, std::llround(999.3 * 65536), std::llround(751.2 * 65536), ray, nullptr));
    TEST_ASSERT_MSG(ray[2] > 1073000000 && std::abs(ray[0]) < 10000000 && std::abs(ray[1]) < 10000000, "axis %d %d %d",
                    ray[0], ray[1], ray[2]);
    TEST_ASSERT_EQUAL_INT(CT_ERR_LENS, ct_camera_project(&cam, ray, &u, &v));
    // outside the grid's support
    TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, ct_camera_unproject(&cam, -40 * 65536, 700 * 65536, ray, nullptr));
    TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, ct_camera_unproject(&cam, 700 * 65536, 1600 * 65536, ray, nullptr));
    // a node without a ray: the 4 x 4 pixels around it refuse, others do not
    std::vector<int32_t> t = *b.rays;
    ct_unproject_grid g = b.grid;
    g.rays_q30 = t.data();
    size_t node = (size_t)10 * g.nu + 12;
    t[3 * node] = t[3 * node + 1] = t[3 * node + 2] = 0;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init_grid(&cam, &g));
    double nu_px = g.u0_q16 / 65536.0 + 12 * 32, nv_px = g.v0_q16 / 65536.0 + 10 * 32;
    TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, ct_camera_unproject(&cam, std::llround((nu_px + 5) * 65536), std::llround((nv_px - 40) * 65536), ray, nullptr));
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_unproject(&cam, std::llround((nu_px + 70) * 65536), std::llround((nv_px - 40) * 65536), ray, nullptr));
    // rays that disagree (a node flipped): refused, never averaged into nonsense
    t = *b.rays;
    for (int k = 0; k < 3; ++k) t[3 * node + k] = -t[3 * node + k];
    for (int k = 0; k < 3; ++k) t[3 * (node + 1) + k] = -t[3 * (node + 1) + k];
    for (int k = 0; k < 3; ++k) t[3 * (node + g.nu) + k] = -t[3 * (node + g.nu) + k];
    for (int k = 0; k < 3; ++k) t[3 * (node + g.nu + 1) + k] = -t[3 * (node + g.nu + 1) + k];
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init_grid(&cam, &g));
    TEST_ASSERT_EQUAL_INT(CT_ERR_UNPROJECT, ct_camera_unproject(&cam, std::llround((nu_px + 16) * 65536), std::llround((nv_px + 16) * 65536), ray, nullptr));
    // bad geometry and bad nodes
    struct Case {
        const char *what;
        void (*mutate)(ct_unproject_grid *, std::vector<int32_t> *);
    };
    const Case cases[] = {
        {"nu < 4", [](ct_unproject_grid *x, std::vector<int32_t> *) { x->nu = 3; }},
        {"nv > max", [](ct_unproject_grid *x, std::vector<int32_t> *) { x->nv = CT_GRID_MAX_NODES + 1; }},
        {"step 0", [](ct_unproject_grid *x, std::vector<int32_t> *) { x->step_q16 = 0; }},
        {"step < 1 px", [](ct_unproject_grid *x, std::vector<int32_t> *) { x->step_q16 = 65535; }},
        {"step > 4096 px", [](ct_unproject_grid *x, std::vector<int32_t> *) { x->step_q16 = (INT64_C(4096) << 16) + 1; }},
        {"u0 beyond 2^20 px", [](ct_unproject_grid *x, std::vector<int32_t> *) { x->u0_q16 = INT64_MIN; }},
        {"table too short", [](ct_unproject_grid *x, std::vector<int32_t> *) { x->rays_len = 3 * x->nu * x->nv - 1; }},
        {"no table", [](ct_unproject_grid *x, std::vector<int32_t> *) { x->rays_q30 = nullptr; }},
        {"node not unit", [](ct_unproject_grid *, std::vector<int32_t> *tt) { (*tt)[3 * 57 + 2] += 1 << 12; }},
        {"node component too big", [](ct_unproject_grid *, std::vector<int32_t> *tt) { (*tt)[3 * 5] = INT32_MIN; }},
    };
    for (const Case &c : cases) {
        t = *b.rays;
        g = b.grid;
        g.rays_q30 = t.data();
        c.mutate(&g, &t);
        ct_status st = ct_camera_init_grid(&cam, &g);
        TEST_ASSERT_MSG(st == CT_ERR_LENS, "%s: expected CT_ERR_LENS, got %d", c.what, (int)st);
        TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_camera_unproject(&cam, 0, 0, ray, nullptr));
    }
    // ct_camera_init refuses the grid model (it needs its table)
    ct_lens l;
    std::memset(&l, 0, sizeof l);
    l.model = CT_LENS_GRID;
    l.fx_q32 = l.fy_q32 = INT64_C(1000) << 32;
    TEST_ASSERT_EQUAL_INT(CT_ERR_LENS, ct_camera_init(&cam, &l));
}

// A grid of nu x nv nodes whose rays turn by step_deg per node along u and
// step_v_deg along v (about two axes), plus a zig-zag of zig_deg by the
// parity of i + j.
static std::vector<int32_t> turning_grid(uint32_t nu, uint32_t nv, double step_deg, double step_v_deg, double zig_deg)
{
    std::vector<int32_t> t(3 * (size_t)nu * nv);
    const double d2r = 3.14159265358979323846 / 180;
    for (uint32_t j = 0; j < nv; ++j)
        for (uint32_t i = 0; i < nu; ++i) {
            const double a = ((double)i - nu / 2.0) * step_deg * d2r + ((i + j) % 2 ? zig_deg : -zig_deg) * d2r / 2;
            const double b = ((double)j - nv / 2.0) * step_v_deg * d2r;
            const double r[3] = {std::sin(a) * std::cos(b), std::sin(b), std::cos(a) * std::cos(b)};
            for (int k = 0; k < 3; ++k) t[3 * ((size_t)j * nu + i) + k] = (int32_t)std::llround(r[k] * 1073741824.0);
        }
    return t;
}

// A smooth grid (every node a ray, neighbours within 5 deg: grid_smooth)
// skips the per-pixel checks, which it cannot fail: on grids turning by
// nearly 5 deg per node, and zig-zagging, every pixel's ray equals the one
// the checks pass (the same camera with grid_smooth cleared) and lies
// within 60 deg of its 16 nodes; just beyond 5 deg, or with a node
// without a ray, the grid is not smooth.
void test_grid_smooth()
{
    struct G {
        double step, step_v, zig;
        int smooth;
    };
    const G gs[] = {{4.99, 4.99, 0.0, 1}, {0.0, 0.0, 4.99, 1}, {2.4, 2.4, 2.4, 1}, {0.5, 0.5, 0.0, 1},
                    {5.02, 5.02, 0.0, 0}, {0.0, 0.0, 5.02, 0}, {1.0, 5.02, 0.0, 0}, {20.0, 20.0, 0.0, 0},
                    {0.0, 0.0, 40.0, 0}};
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 41 + 3);
    for (const G &gd : gs) {
        const uint32_t nu = 12, nv = 9;
        std::vector<int32_t> t = turning_grid(nu, nv, gd.step, gd.step_v, gd.zig);
        ct_unproject_grid g;
        g.nu = nu;
        g.nv = nv;
        g.u0_q16 = -(INT64_C(16) << 16);
        g.v0_q16 = INT64_C(5) << 16;
        g.step_q16 = INT64_C(16) << 16;
        g.rays_q30 = t.data();
        g.rays_len = t.size();
        ct_camera cam, checked;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init_grid(&cam, &g));
        TEST_ASSERT_MSG((int)cam.grid_smooth == gd.smooth, "turning %.2f, zig-zag %.2f deg: grid_smooth %u", gd.step,
                        gd.zig, cam.grid_smooth);
        checked = cam;
        checked.grid_smooth = 0u;
        long ok = 0;
        for (int k = 0; k < 4000; ++k) {
            // pixels over the grid's whole support and a little beyond
            const int64_t u = g.u0_q16 + (int64_t)((ct_rng_unit(&rng) * (nu + 1) - 1) * g.step_q16);
            const int64_t v = g.v0_q16 + (int64_t)((ct_rng_unit(&rng) * (nv + 1) - 1) * g.step_q16);
            int32_t r1[3], r2[3];
            const ct_status s1 = ct_camera_unproject(&cam, u, v, r1, nullptr);
            const ct_status s2 = ct_camera_unproject(&checked, u, v, r2, nullptr);
            TEST_ASSERT_MSG(s1 == s2 && (s1 != CT_OK || (r1[0] == r2[0] && r1[1] == r2[1] && r1[2] == r2[2])),
                            "pixel (%lld, %lld): %d (%d %d %d) against the checked %d (%d %d %d)", (long long)u,
                            (long long)v, (int)s1, r1[0], r1[1], r1[2], (int)s2, r2[0], r2[1], r2[2]);
            if (s1 != CT_OK) continue;
            ++ok;
            // within 60 deg of the 16 nodes around it (by the double-precision dot)
            const int64_t i = (u - g.u0_q16) / g.step_q16, j = (v - g.v0_q16) / g.step_q16;
            double worst = 1;
            for (int64_t b = j - 1; b <= j + 2; ++b)
                for (int64_t a = i - 1; a <= i + 2; ++a) {
                    const int32_t *n = &t[3 * (size_t)(b * nu + a)];
                    double dot = 0;
                    for (int c = 0; c < 3; ++c) dot += (double)n[c] * r1[c] / 1073741824.0 / 1073741824.0;
                    worst = std::min(worst, dot);
                }
            TEST_ASSERT_MSG(worst > 0.5, "pixel (%lld, %lld): %.1f deg from a node", (long long)u, (long long)v,
                            std::acos(worst) * 180 / 3.14159265358979323846);
        }
        // the support (cells 1 .. n - 3) is 9/13 x 6/10 of the pixels drawn
        TEST_ASSERT_MSG(ok > 1400, "turning %.2f deg: only %ld of 4000 pixels unprojected", gd.step, ok);
    }
    // the baked lenses are smooth; a node without a ray makes a grid not
    ct_host::BakedGrid b = ct_host::bake_grid(splined_model(), 32);
    ct_camera cam;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init_grid(&cam, &b.grid));
    TEST_ASSERT_EQUAL_INT(1, (int)cam.grid_smooth);
    std::vector<int32_t> t = *b.rays;
    ct_unproject_grid g = b.grid;
    g.rays_q30 = t.data();
    t[3 * 40] = t[3 * 40 + 1] = t[3 * 40 + 2] = 0;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_init_grid(&cam, &g));
    TEST_ASSERT_EQUAL_INT(0, (int)cam.grid_smooth);
}

// ---- pose ---------------------------------------------------------------

void mat_mrcal(const ld r[3], double R[9])
{
    double rd[3] = {(double)r[0], (double)r[1], (double)r[2]};
    mrcal_R_from_r(R, NULL, rd);
}

void test_rodrigues_vs_mrcal()
{
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 13 + 5);
    double worst = 0;
    for (int k = 0; k < 20000; ++k) {
        // axis * angle, angles over [0, pi] with extra weight at 0 and pi
        ld ax[3] = {ct_rng_unit(&rng) - 0.5L, ct_rng_unit(&rng) - 0.5L, ct_rng_unit(&rng) - 0.5L};
        ld an = std::sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
        if (k % 5 == 0) ax[0] = 1, ax[1] = ax[2] = 0, an = 1;
        ld th;
        switch (k % 4) {
        case 0: th = ct_rng_unit(&rng) * M_PI; break;
        case 1: th = M_PI - std::pow(10.0L, -ct_rng_unit(&rng) * 12); break;
        case 2: th = std::pow(10.0L, -ct_rng_unit(&rng) * 12); break;
        default: th = (k % 8 == 3) ? M_PI : 0; break;
        }
        ld r[3] = {ax[0] / an * th, ax[1] / an * th, ax[2] / an * th};
        ld R[9];
        double M[9];
        ct_host::rotation_from_r(r, R);
        mat_mrcal(r, M);
        for (int i = 0; i < 9; ++i) worst = std::max(worst, (double)std::fabs(R[i] - M[i]));
    }
    printf("  rotation_from_r vs mrcal_R_from_r: max |dR| %.2e\n", worst);
    TEST_ASSERT_MSG(worst <= 4e-15, "max |dR| = %.3g", worst);
}

// Rotations built from the camera's axes; R_from_r must give them back.
void test_rotations_from_axes()
{
    struct Case {
        const char *what;
        ld r[3];          // r_cam_map = angle * axis
        ld cols[3][3];    // camera x, y, z axes in the map frame (E, N, h)
    };
    const ld s = std::sqrt(0.5L);
    const Case cases[] = {
        // nadir: x east, y south (image top = north), z down: pi about east
        {"nadir", {M_PI, 0, 0}, {{1, 0, 0}, {0, -1, 0}, {0, 0, -1}}},
        // nadir, x north, y east (image top = west), z down: pi about (1, 1, 0)/sqrt2
        {"nadir_rot", {M_PI * s, M_PI * s, 0}, {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}}},
        // horizontal camera looking north: x east, y down, z north: -pi/2 about east
        // (r_cam_map maps map to camera: the inverse rotation)
        {"north_horizontal", {M_PI / 2, 0, 0}, {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}}},
        {"identity", {0, 0, 0}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
    };
    for (const Case &c : cases) {
        // R_cam_map rows are the camera axes in the map frame
        double M[9];
        ld R[9];
        mat_mrcal(c.r, M);
        ct_host::rotation_from_r(c.r, R);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                TEST_ASSERT_MSG(std::fabs(M[3 * i + j] - (double)c.cols[i][j]) < 1e-15, "%s: mrcal R[%d][%d] = %.17g",
                                c.what, i, j, M[3 * i + j]);
                TEST_ASSERT_MSG(std::fabs(R[3 * i + j] - c.cols[i][j]) < 1e-15L, "%s: our R[%d][%d]", c.what, i, j);
            }
        // and the library accepts the pose (R_map_cam = transpose, Q30)
        double rt[6] = {(double)c.r[0], (double)c.r[1], (double)c.r[2], 12.5, -4000000.25, 300};
        ct_host::HostPose hp = ct_host::pose_from_rt_cam_ref(rt);
        ct_pose pose;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_init(&pose, hp.R_map_cam_q30, hp.centre_nm[0], hp.centre_nm[1], hp.centre_nm[2]));
        // the camera's z axis in the map frame is column 2 of R_map_cam
        int32_t z[3] = {0, 0, 1 << 30};
        int64_t d[3];
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_rotate(&pose, z, d));
        for (int i = 0; i < 3; ++i)
            TEST_ASSERT_MSG(std::fabs((ld)d[i] / 549755813888.0L - c.cols[2][i]) < 1e-9L, "%s: z axis %d", c.what, i);
    }
}

void test_pose_vs_mrcal()
{
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 17 + 9);
    double worst_c = 0, worst_a = 0;
    for (int k = 0; k < 5000; ++k) {
        ld ax[3] = {ct_rng_unit(&rng) - 0.5L, ct_rng_unit(&rng) - 0.5L, ct_rng_unit(&rng) - 0.5L};
        ld an = std::sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
        ld th = (k % 3 == 0) ? M_PI : ct_rng_unit(&rng) * M_PI;
        double rt[6] = {(double)(ax[0] / an * th), (double)(ax[1] / an * th), (double)(ax[2] / an * th), 0, 0, 0};
        // a camera centre at UTM-like coordinates, then t = -R c (mrcal)
        double c[3] = {300000 + 400000 * (double)ct_rng_unit(&rng), 3000000 + 2000000 * (double)ct_rng_unit(&rng),
                       -100 + 9000 * (double)ct_rng_unit(&rng)};
        double Rc[3];
        mrcal_rotate_point_r(Rc, NULL, NULL, rt, c);
        for (int i = 0; i < 3; ++i) rt[3 + i] = -Rc[i];
        ct_host::HostPose hp = ct_host::pose_from_rt_cam_ref(rt);
        // mrcal: the camera centre is the camera-frame origin mapped to the reference
        double zero[3] = {0, 0, 0}, cm[3];
        mrcal_transform_point_rt_inverted(cm, NULL, NULL, rt, zero);
        for (int i = 0; i < 3; ++i) worst_c = std::max(worst_c, std::fabs(hp.centre_nm[i] * 1e-9 - cm[i]));
        ct_pose pose;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_init(&pose, hp.R_map_cam_q30, hp.centre_nm[0], hp.centre_nm[1], hp.centre_nm[2]));
        // a random camera-frame unit ray into the map frame vs mrcal
        ld v[3] = {ct_rng_unit(&rng) - 0.5L, ct_rng_unit(&rng) - 0.5L, ct_rng_unit(&rng)};
        ld vn = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        int32_t q[3];
        for (int i = 0; i < 3; ++i) q[i] = (int32_t)std::llround(v[i] / vn * 1073741824.0L);
        int64_t d[3];
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_rotate(&pose, q, d));
        double vc[3] = {q[0] / 1073741824.0, q[1] / 1073741824.0, q[2] / 1073741824.0}, vm[3];
        mrcal_rotate_point_r_inverted(vm, NULL, NULL, rt, vc);
        ld a[3] = {(ld)d[0], (ld)d[1], (ld)d[2]}, b[3] = {vm[0], vm[1], vm[2]};
        worst_a = std::max(worst_a, (double)angle_between(a, b));
    }
    printf("  camera centre vs mrcal_transform_point_rt_inverted: max %.2e m; R_map_cam ray vs mrcal: max %.2e rad\n",
           worst_c, worst_a);
    // mrcal's double arithmetic at ~5e6 m carries ~1e-9 m of its own error
    TEST_ASSERT_MSG(worst_c <= 5e-9, "centre %.3g m", worst_c);
    TEST_ASSERT_MSG(worst_a <= 5e-9, "rotation %.3g rad", worst_a);
}

void test_pixel_to_map_chain_vs_mrcal()
{
    // pixel -> ray_cam -> R_map_cam: against mrcal_unproject + the inverse transform
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed() * 19 + 1);
    double worst = 0;
    for (const Model &m : models()) {
        if (!m.realistic) continue;
        ct_camera cam;
        TEST_ASSERT(make_camera(m, &cam));
        mrcal_lensmodel_t lm = mrcal_model(m.lens);
        for (int k = 0; k < 500; ++k) {
            double rt[6] = {(double)(ct_rng_unit(&rng) * 4 - 2), (double)(ct_rng_unit(&rng) * 4 - 2),
                            (double)(ct_rng_unit(&rng) * 4 - 2), 1e5, -4e6, 2e3};
            ct_host::HostPose hp = ct_host::pose_from_rt_cam_ref(rt);
            ct_pose pose;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_init(&pose, hp.R_map_cam_q30, hp.centre_nm[0], hp.centre_nm[1], hp.centre_nm[2]));
            int64_t uq = std::llround(ct_rng_unit(&rng) * (m.w - 1) * 65536), vq = std::llround(ct_rng_unit(&rng) * (m.h - 1) * 65536);
            int32_t ray[3];
            int64_t d[3];
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_camera_unproject(&cam, uq, vq, ray, nullptr));
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_rotate(&pose, ray, d));
            mrcal_point2_t q = {{uq / 65536.0, vq / 65536.0}};
            mrcal_point3_t v;
            mrcal_unproject(&v, &q, 1, &lm, m.in.data());
            double vm[3];
            mrcal_rotate_point_r_inverted(vm, NULL, NULL, rt, v.xyz);
            ld a[3] = {(ld)d[0], (ld)d[1], (ld)d[2]}, b[3] = {vm[0], vm[1], vm[2]};
            worst = std::max(worst, (double)angle_between(a, b));
        }
    }
    printf("  pixel -> map direction vs mrcal (unproject, rotate): max %.2e rad\n", worst);
    TEST_ASSERT_MSG(worst <= 2 * ANGLE_TOL_RAD, "%.3g rad", worst);
}

void test_pose_evil()
{
    ct_pose pose;
    int32_t I[9] = {1 << 30, 0, 0, 0, 1 << 30, 0, 0, 0, 1 << 30};
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_init(&pose, I, 0, 0, 0));
    int32_t R[9];
    std::memcpy(R, I, sizeof R);
    R[8] = -(1 << 30);  // a reflection: det -1
    TEST_ASSERT_EQUAL_INT(CT_ERR_POSE, ct_pose_init(&pose, R, 0, 0, 0));
    std::memcpy(R, I, sizeof R);
    R[1] = 1 << 12;  // not orthogonal (2^-18)
    TEST_ASSERT_EQUAL_INT(CT_ERR_POSE, ct_pose_init(&pose, R, 0, 0, 0));
    std::memcpy(R, I, sizeof R);
    R[0] = (1 << 30) + (1 << 11);  // not unit (2^-19)
    TEST_ASSERT_EQUAL_INT(CT_ERR_POSE, ct_pose_init(&pose, R, 0, 0, 0));
    std::memcpy(R, I, sizeof R);
    R[0] = INT32_MAX;
    TEST_ASSERT_EQUAL_INT(CT_ERR_POSE, ct_pose_init(&pose, R, 0, 0, 0));
    std::memset(R, 0, sizeof R);
    TEST_ASSERT_EQUAL_INT(CT_ERR_POSE, ct_pose_init(&pose, R, 0, 0, 0));
    TEST_ASSERT_EQUAL_INT(CT_ERR_POSE, ct_pose_init(&pose, I, (INT64_C(1) << 61) + 1, 0, 0));
    TEST_ASSERT_EQUAL_INT(CT_ERR_POSE, ct_pose_init(&pose, I, 0, 0, INT64_MIN));
    int32_t ray[3] = {0, 0, 1 << 30};
    int64_t d[3];
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_pose_rotate(&pose, ray, d));  // the failed init cleared it
    // rounding: a Q30 rotation from a random r stays acceptable
    ct_rng rng;
    ct_rng_seed(&rng, 99);
    for (int k = 0; k < 1000; ++k) {
        double rt[6] = {(double)(ct_rng_unit(&rng) * 6 - 3), (double)(ct_rng_unit(&rng) * 6 - 3),
                        (double)(ct_rng_unit(&rng) * 6 - 3), 0, 0, 0};
        ct_host::HostPose hp = ct_host::pose_from_rt_cam_ref(rt);
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_pose_init(&pose, hp.R_map_cam_q30, 0, 0, 0));
    }
    const char *name = nullptr;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_status_name(CT_ERR_UNPROJECT, &name));
    TEST_ASSERT(std::strcmp(name, "err_unproject") == 0);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_status_name(CT_ERR_LENS, &name));
    TEST_ASSERT(std::strcmp(name, "err_lens") == 0);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_status_name(CT_ERR_POSE, &name));
    TEST_ASSERT(std::strcmp(name, "err_pose") == 0);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_status_name(CT_ERR_EFFECTS, &name));
    TEST_ASSERT(std::strcmp(name, "err_effects") == 0);
}

}  // namespace

int main()
{
    TEST_BEGIN("test_camera");
    RUN_TEST(test_unproject_vs_mrcal);
    RUN_TEST(test_unproject_hard_values);
    RUN_TEST(test_lens_evil);
    RUN_TEST(test_tangential_fold);
    RUN_TEST(test_project_vs_mrcal);
    RUN_TEST(test_valid_field_first_sample);
    RUN_TEST(test_valid_field_hole);
    RUN_TEST(test_unproject_max_iters);
    RUN_TEST(test_grid_accuracy_vs_step);
    RUN_TEST(test_grid_evil);
    RUN_TEST(test_grid_smooth);
    RUN_TEST(test_rodrigues_vs_mrcal);
    RUN_TEST(test_rotations_from_axes);
    RUN_TEST(test_pose_vs_mrcal);
    RUN_TEST(test_pixel_to_map_chain_vs_mrcal);
    RUN_TEST(test_pose_evil);
    return TEST_END();
}
