/*
 * main.c -- conetrace in a firmware-style program: a terrain package linked
 * in as a const array (`conetrace build DEM -o X.ctp --emit-c
 * ct_example_pkg`), a pinhole camera 2 km above the tile's highest post
 * looking north 45 degrees down, and a few pixels geolocated straight and
 * with earth curvature and refraction.  No heap, no stdio, no floating
 * point: the one service the program needs from its platform is
 * example_print() (platform_host.c: stdout; platform_mps2.c: semihosting
 * under qemu).  It prints one line per pixel and "example: ok" when every
 * pixel hit the terrain and every hit lies on the surface; main returns 0
 * then.
 */
#include <stddef.h>
#include <stdint.h>

#include "conetrace.h"
#include "ct_example_pkg.h"

void example_print(const char *s);

/* Decimal of v (with sign) into buf (>= 24 bytes); returns buf. */
static char *fmt_i64(int64_t v, char *buf)
{
    char tmp[24];
    uint64_t a = v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
    size_t n = 0u, k = 0u;
    do { /* bound: 20 digits */
        tmp[n++] = (char)('0' + (int)(a % 10u));
        a /= 10u;
    } while (a != 0u && n < sizeof tmp);
    if (v < 0) {
        buf[k++] = '-';
    }
    while (n > 0u) { /* bound: n */
        buf[k++] = tmp[--n];
    }
    buf[k] = '\0';
    return buf;
}

/* Millimetres of a nanometre value, as "<sign>metres.mmm". */
static void print_mm(int64_t nm)
{
    char b[24], f[4];
    int64_t mm = (nm >= 0 ? nm + 500000 : nm - 500000) / 1000000;
    int64_t am = mm < 0 ? -mm : mm;
    f[0] = (char)('0' + (int)(am / 100 % 10));
    f[1] = (char)('0' + (int)(am / 10 % 10));
    f[2] = (char)('0' + (int)(am % 10));
    f[3] = '\0';
    if (mm < 0) {
        example_print("-");
    }
    example_print(fmt_i64(am / 1000, b));
    example_print(".");
    example_print(f);
}

static ct_package g_pkg; /* ~2.6 KB: static, not on the stack */

int main(void)
{
    static const int64_t px[5][2] = {{320, 240}, {0, 0}, {639, 0}, {0, 479}, {639, 479}};
    /* camera axes in (E, N, h), columns of R_map_cam (Q30, row-major): x
     * right = east, y down = (0, -sin 45, -cos 45), z forward = (0, cos 45,
     * -sin 45): looking north, 45 degrees down */
    const int32_t s45 = 759250125; /* sin 45 deg = cos 45 deg in Q30 */
    const int32_t R[9] = {1073741824, 0, 0, 0, -s45, s45, 0, -s45, -s45};
    ct_lens lens = {CT_LENS_PINHOLE, 640u, 480u, (int64_t)800 << 32, (int64_t)800 << 32,
                    ((int64_t)639 << 31), ((int64_t)479 << 31), {0, 0, 0, 0, 0, 0, 0, 0}};
    ct_effects fx = {CT_EFFECT_CURVATURE | CT_EFFECT_REFRACTION, CT_REFRACTION_K_STD_Q16, 0, 0, NULL};
    ct_camera cam;
    ct_pose pose;
    int64_t e, n, h;
    int ok = 1;
    size_t k;
    int pass;
    char b[24];
    if (ct_package_open(&g_pkg, ct_example_pkg, ct_example_pkg_SIZE) != CT_OK) {
        example_print("example: the package does not open\n");
        return 1;
    }
    /* 2 km above the tile's highest post, halfway across, 1/4 from the south */
    e = g_pkg.origin_e_nm + (int64_t)(g_pkg.cells_x / 2u) * g_pkg.posting_e_nm;
    n = g_pkg.origin_n_nm + (int64_t)(g_pkg.cells_y * 3u / 4u) * g_pkg.posting_n_nm;
    h = g_pkg.height_offset_nm + (int64_t)g_pkg.hmax * g_pkg.height_scale_nm + INT64_C(2000000000000);
    if (ct_camera_init(&cam, &lens) != CT_OK || ct_pose_init(&pose, R, e, n, h) != CT_OK) {
        example_print("example: camera or pose refused\n");
        return 1;
    }
    for (pass = 0; pass < 2; ++pass) { /* bound: straight, then bent */
        for (k = 0u; k < 5u; ++k) { /* bound: 5 pixels */
            ct_geo g;
            ct_status st = ct_geolocate(&g_pkg, &cam, &pose, CT_METHOD_DIRECTIONAL, pass ? &fx : NULL,
                                        px[k][0] << 16, px[k][1] << 16, &g);
            const char *name = "?";
            (void)ct_status_name(st, &name);
            example_print(pass ? "bent     " : "straight ");
            example_print(fmt_i64(px[k][0], b));
            example_print(",");
            example_print(fmt_i64(px[k][1], b));
            example_print(" ");
            example_print(name);
            if (st == CT_HIT) {
                int64_t zs;
                example_print(" E ");
                print_mm(g.hit.e_nm);
                example_print(" N ");
                print_mm(g.hit.n_nm);
                example_print(" h ");
                print_mm(g.hit.h_nm);
                example_print(" steps ");
                example_print(fmt_i64(g.hit.steps, b));
                /* the hit lies on the bilinear surface: within 1 mm of
                 * height (tol in Q16 LSB; the reported point is rounded to
                 * Q16, so on a slope the surface under it differs by the
                 * slope times that rounding) */
                int64_t tol = (INT64_C(1000000) << 16) / g_pkg.height_scale_nm;
                if (ct_surface_height(&g_pkg, g.hit.x_q16, g.hit.y_q16, &zs) != CT_OK ||
                    zs - g.hit.z_q16 > tol || g.hit.z_q16 - zs > tol) {
                    example_print(" OFF THE SURFACE");
                    ok = 0;
                }
            } else {
                ok = 0;
            }
            example_print("\n");
        }
    }
    example_print(ok ? "example: ok\n" : "example: FAILED\n");
    return ok ? 0 : 1;
}
