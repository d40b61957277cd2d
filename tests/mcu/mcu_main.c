/*
 * mcu_main.c -- bit-identity check of the flight library on a target.
 *
 * Re-computes every host-generated vector (ct_vectors.h) with the library
 * build linked into this image: package open/verify and derived tables,
 * CRC-32, ray preparation, all four tracing methods through ct_trace and
 * ct_trace_prepared, map-frame conversions, surface heights, the
 * fixed-point core, and cameras: lens and grid set-up, unprojection,
 * projection, ct_geolocate with every method (straight and bent rays) and
 * ct_geolocate_batch, and the vertical datum (ct_geoid_at on synthetic
 * grids, a package's datum section, ct_package_geoid).  Every field must be
 * bit-identical.  Prints a summary and stops with pass/fail through the
 * platform layer (semihosting on qemu).  C99, freestanding, no stdio, no
 * float.
 */
#include <stddef.h>
#include <stdint.h>

#include "conetrace.h"
#include "ct_vectors.h"
#include "fixed.h"
#include "mcu_platform.h"

#ifndef CT_MCU_NAME
#define CT_MCU_NAME "host"
#endif

#define MAX_REPORTS 12u

static uint32_t g_checks, g_fail, g_reported;
static const char *g_where = "";
static uint32_t g_idx, g_method;

/* ---- tiny formatting (no stdio) ----------------------------------------- */

static char g_line[160];
static uint32_t g_len;

static void put_str(const char *s)
{
    while (*s != '\0' && g_len + 1u < sizeof g_line) {
        g_line[g_len++] = *s++;
    }
    g_line[g_len] = '\0';
}

static void put_u64(uint64_t v)
{
    char buf[24];
    uint32_t n = 0u;
    do {
        buf[n++] = (char)('0' + (int)(v % 10u));
        v /= 10u;
    } while (v != 0u && n < sizeof buf);
    while (n > 0u && g_len + 1u < sizeof g_line) {
        g_line[g_len++] = buf[--n];
    }
    g_line[g_len] = '\0';
}

static void put_i64(int64_t v)
{
    if (v < 0) {
        put_str("-");
        put_u64((uint64_t)0 - (uint64_t)v);
    } else {
        put_u64((uint64_t)v);
    }
}

static void flush_line(void)
{
    put_str("\n");
    ct_plat_puts(g_line);
    g_len = 0u;
    g_line[0] = '\0';
}

/* ---- comparisons ---------------------------------------------------------- */

static void mismatch(const char *field, int64_t want, int64_t got)
{
    g_fail++;
    if (g_reported < MAX_REPORTS) {
        g_reported++;
        put_str("MISMATCH ");
        put_str(g_where);
        put_str(" #");
        put_u64(g_idx);
        put_str(" method ");
        put_u64(g_method);
        put_str(" ");
        put_str(field);
        put_str(": host ");
        put_i64(want);
        put_str(" target ");
        put_i64(got);
        flush_line();
    }
}

static void eq_i64(const char *field, int64_t want, int64_t got)
{
    g_checks++;
    if (want != got) {
        mismatch(field, want, got);
    }
}

static void eq_u64(const char *field, uint64_t want, uint64_t got)
{
    g_checks++;
    if (want != got) {
        mismatch(field, (int64_t)want, (int64_t)got);
    }
}

static void zero_bytes(void *p, size_t n)
{
    uint8_t *b = (uint8_t *)p;
    size_t i;
    for (i = 0u; i < n; ++i) {
        b[i] = 0u;
    }
}

static void eq_hit(const ct_hit *w, const ct_hit *g)
{
    eq_i64("x_q16", w->x_q16, g->x_q16);
    eq_i64("y_q16", w->y_q16, g->y_q16);
    eq_i64("z_q16", w->z_q16, g->z_q16);
    eq_i64("e_nm", w->e_nm, g->e_nm);
    eq_i64("n_nm", w->n_nm, g->n_nm);
    eq_i64("h_nm", w->h_nm, g->h_nm);
    eq_i64("t_q26", w->t_q26, g->t_q26);
    eq_i64("cell_x", w->cell_x, g->cell_x);
    eq_i64("cell_y", w->cell_y, g->cell_y);
    eq_u64("steps", w->steps, g->steps);
    eq_u64("iters", w->iters, g->iters);
}

static void eq_ray(const ct_ray *w, const ct_ray *g)
{
    eq_i64("ray.x_q16", w->x_q16, g->x_q16);
    eq_i64("ray.y_q16", w->y_q16, g->y_q16);
    eq_i64("ray.z_q16", w->z_q16, g->z_q16);
    eq_i64("ray.dx", w->dx, g->dx);
    eq_i64("ray.dy", w->dy, g->dy);
    eq_i64("ray.dz", w->dz, g->dz);
}

static void eq_prep(const ct_prepared *w, const ct_prepared *g)
{
    eq_i64("prep.ox", w->ox, g->ox);
    eq_i64("prep.oy", w->oy, g->oy);
    eq_i64("prep.oz", w->oz, g->oz);
    eq_i64("prep.dx", w->dx, g->dx);
    eq_i64("prep.dy", w->dy, g->dy);
    eq_i64("prep.dz", w->dz, g->dz);
    eq_i64("prep.sector", w->sector, g->sector);
    eq_i64("prep.zshift", w->zshift, g->zshift);
    eq_i64("prep.len_lo", w->len_lo, g->len_lo);
    eq_i64("prep.len_hi", w->len_hi, g->len_hi);
    eq_i64("prep.tend_n", w->tend_n, g->tend_n);
    eq_i64("prep.tend_d", w->tend_d, g->tend_d);
    eq_i64("prep.start", w->start, g->start);
}

/* ---- stack measurement ---------------------------------------------------- */

enum {
    ST_OPEN,
    ST_PREPARE,
    ST_TRACE,
    ST_TRACE_PREP,
    ST_UNPROJECT,
    ST_PROJECT,
    ST_GEOLOCATE,
    ST_BATCH,
    ST_TILESET,
    ST_BATCH_TILES,
    ST_COUNT
};
static const char *const st_names[ST_COUNT] = {"ct_package_open",     "ct_ray_prepare",      "ct_trace",
                                               "ct_trace_prepared",   "ct_camera_unproject", "ct_camera_project",
                                               "ct_geolocate",        "ct_geolocate_batch",  "ct_tileset_trace",
                                               "ct_geolocate_batch_tiles"};
static unsigned st_max[ST_COUNT];

static void st_note(int k)
{
    unsigned u = ct_plat_stack_used();
    if (u > st_max[k]) {
        st_max[k] = u;
    }
}

/* ---- the checks ------------------------------------------------------------ */

static ct_package g_pkg;                 /* ~2.6 KB: static, not on the stack */
static union {
    uint64_t align;
    uint8_t b[128u * 1024u];
} g_copy;                                /* RAM copy for corruption tests      */

static uint32_t ld32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void check_crc(void)
{
    static const uint8_t digits[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    uint32_t c = 0u, c2 = 0u;
    g_where = "crc";
    g_idx = 0u;
    g_method = 0u;
    eq_i64("crc status", CT_OK, ct_crc32(0u, digits, sizeof digits, &c));
    eq_u64("crc(123456789)", 0xCBF43926u, c);
    /* continuation: crc(a || b) == crc(crc(a), b) */
    (void)ct_crc32(0u, digits, 4u, &c2);
    (void)ct_crc32(c2, digits + 4, 5u, &c2);
    eq_u64("crc chained", c, c2);
    eq_i64("crc null", CT_ERR_ARG, ct_crc32(0u, NULL, 1u, &c));
}

/* The package's stored CRC: the IEEE CRC of the package with its CRC field
 * zeroed, and the same value in the header. */
static void check_package_crc(const ct_vec_package *vp)
{
    uint32_t crc = 0u;
    static const uint8_t zero4[4] = {0u, 0u, 0u, 0u};
    (void)ct_crc32(0u, vp->bytes, 12u, &crc);
    (void)ct_crc32(crc, zero4, 4u, &crc);
    (void)ct_crc32(crc, vp->bytes + 16, vp->size - 16u, &crc);
    eq_u64("package crc", vp->crc, crc);
    eq_u64("header crc field", vp->crc, ld32(vp->bytes + 12));
}

/* Opens the package into g_pkg (stack measured).  Open: verifies it, checks
 * its header fields, its size and its derived tables (cotangents, sector
 * bounds) against the host's.  Returns the open status. */
static ct_status open_package(const ct_vec_package *vp)
{
    ct_status st;
    uint32_t k, size = 0u;
    ct_plat_stack_paint();
    st = ct_package_open(&g_pkg, vp->bytes, vp->size);
    st_note(ST_OPEN);
    eq_i64("open", CT_OK, st);
    if (st != CT_OK) {
        return st;
    }
    eq_i64("verify", CT_OK, ct_package_verify(&g_pkg));
    eq_u64("sectors", vp->sectors, g_pkg.sectors);
    eq_u64("reduce", vp->reduce, g_pkg.reduce);
    eq_u64("levels", vp->levels, g_pkg.levels);
    eq_i64("size status", CT_OK,
           ct_package_size(g_pkg.width, g_pkg.height, g_pkg.reduce, g_pkg.sectors,
                           g_pkg.voids != NULL ? 1u : 0u, &size));
    eq_u64("package size", vp->size, size);
    for (k = 0u; k < 256u; ++k) { /* bound: 256 cotangents */
        g_idx = k;
        eq_i64("cot_q16", vp->cot_q16[k], g_pkg.cot_q16[k]);
        eq_u64("cot_ok", vp->cot_ok[k], g_pkg.cot_ok[k]);
    }
    for (k = 0u; k <= CT_MAX_SECTORS; ++k) { /* bound: CT_MAX_SECTORS + 1 */
        g_idx = k;
        eq_i64("bound_x", vp->bound_x[k], g_pkg.bound_x[k]);
        eq_i64("bound_y", vp->bound_y[k], g_pkg.bound_y[k]);
    }
    return st;
}

/* One ray of g_pkg (g_idx set): its preparation, then every method through
 * ct_trace and, for a ray that prepares, ct_trace_prepared from the host's
 * prepared ray (stacks measured).  Adds the methods that matched in full
 * to *traces, the host's hits to *hits. */
static void check_case(const ct_vec_case *c, uint32_t *traces, uint32_t *hits)
{
    ct_status st;
    ct_prepared prep;
    uint32_t m;
    g_method = 0u;
    zero_bytes(&prep, sizeof prep);
    ct_plat_stack_paint();
    st = ct_ray_prepare(&g_pkg, &c->ray, &prep);
    st_note(ST_PREPARE);
    eq_i64("prep_status", c->prep_status, st);
    eq_prep(&c->prep, &prep);
    for (m = 0u; m < (uint32_t)CT_METHOD_COUNT; ++m) { /* bound: CT_METHOD_COUNT */
        ct_hit h;
        uint32_t before = g_fail;
        g_method = m;
        zero_bytes(&h, sizeof h);
        ct_plat_stack_paint();
        st = ct_trace(&g_pkg, &c->ray, (ct_method)m, &h);
        st_note(ST_TRACE);
        eq_i64("status", c->status[m], st);
        eq_hit(&c->hit[m], &h);
        if (c->prep_status >= 0) {
            /* the same trace from the host's prepared ray */
            zero_bytes(&h, sizeof h);
            ct_plat_stack_paint();
            st = ct_trace_prepared(&g_pkg, &c->prep, (ct_method)m, &h);
            st_note(ST_TRACE_PREP);
            eq_i64("prepared status", c->status[m], st);
            eq_hit(&c->hit[m], &h);
        }
        if (g_fail == before) {
            (*traces)++;
        }
        if (c->status[m] == CT_HIT || c->status[m] == CT_HIT_VOID) {
            (*hits)++;
        }
    }
}

/* One map point of g_pkg (g_idx set): grid -> map and back, the surface
 * height, the ray from the map. */
static void check_point(const ct_vec_point *q)
{
    int64_t a = 0, b = 0, c = 0;
    ct_ray r;
    eq_i64("g2m status", q->g2m_status, ct_grid_to_map(&g_pkg, q->x, q->y, q->z, &a, &b, &c));
    if (q->g2m_status == CT_OK) {
        eq_i64("e", q->e, a);
        eq_i64("n", q->n, b);
        eq_i64("h", q->h, c);
    }
    a = b = c = 0;
    eq_i64("m2g status", q->m2g_status, ct_map_to_grid(&g_pkg, q->e, q->n, q->h, &a, &b, &c));
    if (q->m2g_status == CT_OK) {
        eq_i64("x2", q->x2, a);
        eq_i64("y2", q->y2, b);
        eq_i64("z2", q->z2, c);
    }
    a = 0;
    eq_i64("surface status", q->surf_status, ct_surface_height(&g_pkg, q->x, q->y, &a));
    if (q->surf_status == CT_OK) {
        eq_i64("surface z", q->surf_z, a);
    }
    zero_bytes(&r, sizeof r);
    eq_i64("rfm status", q->rfm_status, ct_ray_from_map(&g_pkg, q->e, q->n, q->h, q->de, q->dn, q->dh, &r));
    eq_ray(&q->rfm, &r);
}

/* Corruption: a RAM copy of the package opens, with one flipped byte it
 * must fail its CRC, a short buffer must be reported truncated. */
static void check_corruption(const ct_vec_package *vp)
{
    uint32_t k;
    ct_package tmp;
    if (vp->size > sizeof g_copy.b) {
        return;
    }
    for (k = 0u; k < vp->size; ++k) { /* bound: the package's size */
        g_copy.b[k] = vp->bytes[k];
    }
    eq_i64("copy opens", CT_OK, ct_package_open(&tmp, g_copy.b, vp->size));
    g_copy.b[vp->size / 2u] ^= 0x10u;
    eq_i64("corrupt", CT_ERR_CRC, ct_package_open(&tmp, g_copy.b, vp->size));
    eq_i64("truncated", CT_ERR_TRUNCATED, ct_package_open(&tmp, g_copy.b, vp->size - 8u));
}

/* One package: its CRC, open and tables, its rays x methods, its map
 * points, corrupted copies.  Adds the methods that matched in full to
 * *traces, the host's hits to *hits. */
static void check_package(const ct_vec_package *vp, uint32_t *traces, uint32_t *hits)
{
    uint32_t k;
    g_where = vp->name;
    g_idx = 0u;
    g_method = 0u;
    check_package_crc(vp);
    if (open_package(vp) != CT_OK) {
        return;
    }
    for (k = 0u; k < vp->ncases; ++k) { /* bound: the package's rays */
        g_idx = k;
        check_case(&vp->cases[k], traces, hits);
    }
    g_method = 0u;
    for (k = 0u; k < vp->npoints; ++k) { /* bound: the package's map points */
        g_idx = k;
        check_point(&vp->points[k]);
    }
    g_idx = 0u;
    check_corruption(vp);
}

static void eq_geo(const ct_geo *w, const ct_geo *g)
{
    uint32_t i;
    eq_i64("geo.status", w->status, g->status);
    eq_u64("geo.unproject_iters", w->unproject_iters, g->unproject_iters);
    for (i = 0u; i < 3u; ++i) {
        eq_i64("geo.ray_cam_q30", w->ray_cam_q30[i], g->ray_cam_q30[i]);
        eq_i64("geo.dir_map_q39", w->dir_map_q39[i], g->dir_map_q39[i]);
    }
    eq_hit(&w->hit, &g->hit);
}

#define CAM_MAX_PIXELS 64u
static ct_package g_cpkg;
static ct_camera g_cam;
static ct_pose g_pose;
static int64_t g_uv[2u * CAM_MAX_PIXELS];
static ct_geo g_batch[CAM_MAX_PIXELS];

/* Camera vc's lens (or grid) and pose into g_cam and g_pose: the two
 * statuses in *init and *pose. */
static void camera_setup(const ct_vec_camera *vc, ct_status *init, ct_status *pose)
{
    zero_bytes(&g_cam, sizeof g_cam);
    zero_bytes(&g_pose, sizeof g_pose);
    *init = vc->grid.nu > 0u ? ct_camera_init_grid(&g_cam, &vc->grid) : ct_camera_init(&g_cam, &vc->lens);
    *pose = ct_pose_init(&g_pose, vc->R_q30, vc->e_nm, vc->n_nm, vc->h_nm);
}

/* Cameras: lens (or grid) and pose set-up, unprojection, projection back,
 * geolocation with every method and the batch, each bit-identical to the
 * host's.  Returns the number of geolocations that matched in full. */
static uint32_t check_camera(const ct_vec_set *vs, const ct_vec_camera *vc, uint32_t *total)
{
    ct_status st, pst;
    uint32_t k, m, ok = 0u, before;
    g_where = vc->name;
    g_idx = 0u;
    g_method = 0u;
    *total += vc->npixels * (uint32_t)CT_METHOD_COUNT;
    if (vc->package >= vs->npackages || vc->npixels > CAM_MAX_PIXELS ||
        vc->batch_method >= (uint32_t)CT_METHOD_COUNT) {
        eq_i64("camera vector shape", 0, 1);
        return 0u;
    }
    st = ct_package_open(&g_cpkg, vs->packages[vc->package].bytes, vs->packages[vc->package].size);
    eq_i64("camera package open", CT_OK, st);
    if (st != CT_OK) {
        return 0u;
    }
    camera_setup(vc, &st, &pst);
    eq_i64("camera init", vc->init_status, st);
    eq_i64("r2_max_q32", vc->r2_max_q32, g_cam.r2_max_q32);
    eq_i64("pose init", vc->pose_status, pst);
    if (vc->init_status != CT_OK || vc->pose_status != CT_OK) {
        return 0u;
    }
    {
        /* the effects for a tolerance: every field of the choice */
        ct_effects_choice ch;
        zero_bytes(&ch, sizeof ch);
        eq_i64("tolerance status", vc->tol_status,
               ct_effects_for_tolerance(&g_cpkg, &g_cam, &g_pose, vc->effects.refraction_k_q16,
                                        vc->effects.earth_radius_nm, vc->tol_nm, &ch));
        eq_i64("tolerance flags", vc->tol_choice.flags, ch.flags);
        eq_i64("tolerance chord", vc->tol_choice.chord_nm, ch.chord_nm);
        for (k = 0u; k < 4u; ++k) { /* bound: 4 bounds */
            eq_i64("tolerance bound", vc->tol_choice.bound_nm[k], ch.bound_nm[k]);
        }
        eq_i64("tolerance range", vc->tol_choice.range_nm, ch.range_nm);
        eq_i64("tolerance tan", vc->tol_choice.tan_min_q30, ch.tan_min_q30);
        eq_i64("tolerance samples", vc->tol_choice.samples, ch.samples);
    }
    for (k = 0u; k < vc->npixels; ++k) {
        const ct_vec_pixel *q = &vc->pixels[k];
        int32_t ray[3] = {0, 0, 0};
        uint32_t iters = 0u;
        g_idx = k;
        g_method = 0u;
        ct_plat_stack_paint();
        st = ct_camera_unproject(&g_cam, q->u_q16, q->v_q16, ray, &iters);
        st_note(ST_UNPROJECT);
        eq_i64("unproject status", q->unp_status, st);
        if (q->unp_status == CT_OK) {
            int64_t u = 0, v = 0;
            eq_u64("unproject iters", q->unp_iters, iters);
            eq_i64("ray x", q->ray_q30[0], ray[0]);
            eq_i64("ray y", q->ray_q30[1], ray[1]);
            eq_i64("ray z", q->ray_q30[2], ray[2]);
            ct_plat_stack_paint();
            st = ct_camera_project(&g_cam, q->ray_q30, &u, &v);
            st_note(ST_PROJECT);
            eq_i64("project status", q->proj_status, st);
            eq_i64("project u", q->pu_q16, u);
            eq_i64("project v", q->pv_q16, v);
        }
        for (m = 0u; m < (uint32_t)CT_METHOD_COUNT; ++m) {
            ct_geo o;
            g_method = m;
            before = g_fail;
            zero_bytes(&o, sizeof o);
            ct_plat_stack_paint();
            st = ct_geolocate(&g_cpkg, &g_cam, &g_pose, (ct_method)m, &vc->effects, q->u_q16, q->v_q16, &o);
            st_note(ST_GEOLOCATE);
            eq_i64("geolocate status", q->geo[m].status, st);
            eq_geo(&q->geo[m], &o);
            if (g_fail == before) {
                ok++;
            }
        }
        g_uv[2u * k] = q->u_q16;
        g_uv[2u * k + 1u] = q->v_q16;
    }
    /* the batch: the same pixels, bit-identical to the host's batch (whose
     * records the generator checked against the single calls) */
    g_method = vc->batch_method;
    zero_bytes(g_batch, sizeof g_batch);
    ct_plat_stack_paint();
    st = ct_geolocate_batch(&g_cpkg, &g_cam, &g_pose, (ct_method)vc->batch_method, &vc->effects, g_uv, vc->npixels,
                            g_batch, CAM_MAX_PIXELS);
    st_note(ST_BATCH);
    eq_i64("batch status", CT_OK, st);
    for (k = 0u; k < vc->npixels; ++k) {
        g_idx = k;
        eq_geo(&vc->batch[k], &g_batch[k]);
    }
    return ok;
}

static void check_fixed(const ct_vec_set *vs)
{
    uint32_t k;
    g_where = "fixed";
    g_method = 0u;
    for (k = 0u; k < vs->nfixed; ++k) {
        const ct_vec_fixed *v = &vs->fixed[k];
        ct_i128 p = ct_i128_mul(v->a, v->b), m;
        g_idx = k;
        eq_u64("mul.hi", v->mul_hi, p.hi);
        eq_u64("mul.lo", v->mul_lo, p.lo);
        eq_i64("floor_div", v->div_q, ct_i128_floor_div(p, v->div_d));
        eq_u64("isqrt128", v->isqrt, ct_i128_isqrt(ct_i128_sign(p) < 0 ? ct_i128_neg(p) : p));
        eq_u64("isqrt64", v->isqrt64, ct_isqrt64((uint64_t)v->a));
        m = ct_i128_mul128_64(ct_i128_mul(v->a / 16777216, v->b / 16777216), v->m64);
        eq_u64("mul128_64.hi", v->m_hi, m.hi);
        eq_u64("mul128_64.lo", v->m_lo, m.lo);
        /* algebra on the target itself: (p + p) - p == p, cmp, sign */
        eq_i64("add/sub", 0, ct_i128_cmp(ct_i128_sub(ct_i128_add(p, p), p), p));
        eq_i64("neg sign", -ct_i128_sign(p), ct_i128_sign(ct_i128_neg(p)));
    }
    g_where = "dir";
    for (k = 0u; k < vs->ndirs; ++k) {
        const ct_vec_dir *d = &vs->dirs[k];
        int32_t cx = 0, sy = 0;
        g_idx = k;
        ct_dir_of_fraction(d->k, d->n, &cx, &sy);
        eq_i64("cos", d->cx, cx);
        eq_i64("sin", d->sy, sy);
        cx = sy = 0;
        eq_i64("boundary status", CT_OK, ct_sector_boundary(d->n, d->k, &cx, &sy));
        eq_i64("boundary x", d->cx, cx);
        eq_i64("boundary y", d->sy, sy);
    }
    g_where = "utm";
    for (k = 0u; k < vs->ngeo; ++k) {
        const ct_vec_geo *v = &vs->geo[k];
        int64_t e = 0, n = 0, la = 0, lo = 0;
        g_idx = k;
        eq_i64("utm forward status", v->fwd_status, ct_utm_forward(&v->zone, v->lat_q61, v->lon_q61, &e, &n));
        if (v->fwd_status == CT_OK) {
            eq_i64("utm e", v->e_nm, e);
            eq_i64("utm n", v->n_nm, n);
        }
        eq_i64("utm inverse status", v->inv_status, ct_utm_inverse(&v->zone, v->e_nm, v->n_nm, &la, &lo));
        if (v->inv_status == CT_OK) {
            eq_i64("utm lat", v->lat2_q61, la);
            eq_i64("utm lon", v->lon2_q61, lo);
        }
        la = lo = 0;
        eq_i64("utm factors status", v->fac_status, ct_utm_factors(&v->zone, v->lat_q61, v->lon_q61, &la, &lo));
        if (v->fac_status == CT_OK) {
            eq_i64("utm gamma", v->gamma_q61, la);
            eq_i64("utm k", v->k_q61, lo);
        }
        {
            int32_t q[4] = {0, 0, 0, 0};
            ct_pose pose;
            uint32_t a;
            eq_i64("quat status", v->quat_status, ct_quat_from_ypr(v->ypr_q61[0], v->ypr_q61[1], v->ypr_q61[2], q));
            for (a = 0u; a < 4u; ++a) { /* bound: 4 */
                eq_i64("quat", v->q_q30[a], q[a]);
            }
            eq_i64("pose status", v->pose_status, ct_pose_from_wgs84(&pose, &v->zone, v->lat_q61, v->lon_q61, v->h_nm, v->q_q30));
            if (v->pose_status == CT_OK) {
                for (a = 0u; a < 9u; ++a) { /* bound: 9 */
                    eq_i64("pose R", v->R_q30[a], pose.R_map_cam_q30[a]);
                }
                eq_i64("pose hscale", v->hscale_q30, pose.hscale_q30);
            }
        }
    }
    g_where = "ecef";
    for (k = 0u; k < vs->necef; ++k) {
        const ct_vec_ecef *v = &vs->ecef[k];
        int64_t xyz[3] = {0, 0, 0}, la = 0, lo = 0, h = 0;
        uint32_t a;
        g_idx = k;
        eq_i64("ecef forward status", v->fwd_status, ct_ecef_from_wgs84(v->lat_q61, v->lon_q61, v->h_nm, xyz));
        if (v->fwd_status == CT_OK) {
            for (a = 0u; a < 3u; ++a) { /* bound: 3 */
                eq_i64("ecef xyz", v->xyz_nm[a], xyz[a]);
            }
        }
        eq_i64("ecef inverse status", v->inv_status, ct_wgs84_from_ecef(v->in_nm, &la, &lo, &h));
        if (v->inv_status == CT_OK) {
            eq_i64("ecef lat", v->lat2_q61, la);
            eq_i64("ecef lon", v->lon2_q61, lo);
            eq_i64("ecef h", v->h2_nm, h);
        }
    }
    g_where = "status names";
    for (k = 0u; k < 32u; ++k) {
        const char *name = NULL;
        ct_status s = (ct_status)k - 25;
        ct_status want = (s >= CT_ERR_CRS && s <= CT_NO_DATA) ? CT_OK : CT_ERR_ARG;
        g_idx = k;
        eq_i64("status_name", want, ct_status_name(s, &name));
        eq_i64("status_name set", 1, name != NULL);
    }
}

/* The vertical datum: ct_geoid_at on the synthetic grids, and the datum
 * package (open, its datum fields, ct_package_geoid at map points, a
 * corrupted copy).  Returns the number of geoid values checked. */
static uint32_t check_datum(const ct_vec_set *vs)
{
    uint32_t k, p, n = 0u;
    int64_t v = 0;
    g_where = "geoid";
    g_method = 0u;
    for (k = 0u; k < vs->ngeoid; ++k) {
        const ct_vec_geoid *q = &vs->geoid[k];
        g_idx = k;
        if (q->grid >= vs->ngeoid_grids) {
            eq_i64("geoid vector shape", 0, 1);
            continue;
        }
        v = 0;
        eq_i64("geoid status", q->status, ct_geoid_at(&vs->geoid_grids[q->grid], q->lat_q61, q->lon_q61, &v));
        if (q->status == CT_OK) {
            eq_i64("geoid N", q->n_nm, v);
        }
        n++;
    }
    g_idx = 0u;
    eq_i64("geoid null grid", CT_ERR_ARG, ct_geoid_at(NULL, 0, 0, &v));
    if (vs->ngeoid_grids > 0u) {
        eq_i64("geoid null out", CT_ERR_ARG, ct_geoid_at(&vs->geoid_grids[0], 0, 0, NULL));
    }
    for (p = 0u; p < vs->ndatum; ++p) {
        const ct_vec_datum_package *vd = &vs->datum[p];
        ct_status st;
        g_where = vd->name;
        g_idx = 0u;
        st = ct_package_open(&g_pkg, vd->bytes, vd->size);
        eq_i64("datum open", vd->open_status, st);
        if (st != CT_OK) {
            continue;
        }
        eq_i64("datum verify", vd->verify_status, ct_package_verify(&g_pkg));
        eq_u64("datum flags", vd->flags, g_pkg.flags);
        eq_u64("datum epsg", vd->epsg, g_pkg.epsg);
        eq_u64("vdatum", vd->vdatum, g_pkg.vdatum);
        eq_u64("source_epsg", vd->source_epsg, g_pkg.source_epsg);
        eq_u64("geoid w", vd->geoid_w, g_pkg.geoid.w);
        eq_u64("geoid h", vd->geoid_h, g_pkg.geoid.h);
        eq_i64("geoid lat0", vd->geoid_lat0_q61, g_pkg.geoid.lat0_q61);
        eq_i64("geoid lon0", vd->geoid_lon0_q61, g_pkg.geoid.lon0_q61);
        eq_i64("geoid step", vd->geoid_step_q61, g_pkg.geoid.step_q61);
        eq_i64("geoid values", 1, g_pkg.geoid.values == vd->bytes + vd->geoid_values_off);
        for (k = 0u; k < vd->npoints; ++k) {
            const ct_vec_map_geoid *q = &vd->points[k];
            g_idx = k;
            v = 0;
            eq_i64("package geoid status", q->status, ct_package_geoid(&g_pkg, q->e_nm, q->n_nm, &v));
            if (q->status == CT_OK) {
                eq_i64("package geoid N", q->n_geoid_nm, v);
            }
            n++;
        }
        g_idx = 0u;
        eq_i64("package geoid null", CT_ERR_ARG, ct_package_geoid(NULL, 0, 0, &v));
        /* one flipped byte in the geoid values: the CRC catches it */
        if (vd->size <= sizeof g_copy.b && vd->geoid_values_off < vd->size) {
            for (k = 0u; k < vd->size; ++k) {
                g_copy.b[k] = vd->bytes[k];
            }
            g_copy.b[vd->geoid_values_off] ^= 0x01u;
            eq_i64("datum corrupt", CT_ERR_CRC, ct_package_open(&g_pkg, g_copy.b, vd->size));
        }
    }
    return n;
}

/* The start of a summary line: "<what><name>: N rays x 4 methods: ok/4N
 * identical (H hits, " (the caller ends it). */
static void put_rays_line(const char *what, const char *name, uint32_t ncases, uint32_t ok, uint32_t hits)
{
    put_str(what);
    put_str(name);
    put_str(": ");
    put_u64(ncases);
    put_str(" rays x 4 methods: ");
    put_u64(ok);
    put_str("/");
    put_u64(ncases * (uint64_t)CT_METHOD_COUNT);
    put_str(" identical (");
    put_u64(hits);
    put_str(" hits, ");
}

/* ---- tile sets: tiles copied from flash into a few RAM slots --------------- */

#define TS_MAX_SLOTS 4u
static ct_tile_slot g_slots[TS_MAX_SLOTS];
static union {
    uint64_t align;
    uint8_t b[TS_MAX_SLOTS][CT_VEC_TILE_CAP];
} g_slot_mem;
static ct_tileset g_ts;

static ct_status vec_loader(void *user, uint32_t col, uint32_t row, uint8_t *buf, size_t cap, const uint8_t **bytes,
                            size_t *len)
{
    const ct_vec_tileset *vt = (const ct_vec_tileset *)user;
    uint32_t k = row * ct_ld16(vt->manifest + CT_SET_HDR_TILES_X) + col, i;
    if (k >= vt->ntiles || k == vt->missing || vt->tiles[k].size > cap) {
        return CT_ERR_ARG;
    }
    /* bound: the tile's bytes */
    for (i = 0u; i < vt->tiles[k].size; ++i) {
        buf[i] = vt->tiles[k].bytes[i];
    }
    *bytes = buf;
    *len = vt->tiles[k].size;
    return CT_OK;
}

static uint32_t check_tileset(const ct_vec_set *vs, const ct_vec_tileset *vt, uint32_t *hits)
{
    uint32_t k, m, s, ok = 0u;
    ct_status st;
    g_where = vt->name;
    g_idx = 0u;
    g_method = 0u;
    if (vt->nslots > TS_MAX_SLOTS) {
        eq_u64("slots", TS_MAX_SLOTS, vt->nslots);
        return 0u;
    }
    /* bound: TS_MAX_SLOTS */
    for (s = 0u; s < vt->nslots; ++s) {
        zero_bytes(&g_slots[s], sizeof g_slots[s]);
        g_slots[s].buf = g_slot_mem.b[s];
        g_slots[s].cap = CT_VEC_TILE_CAP;
    }
    st = ct_tileset_open(&g_ts, vt->manifest, vt->manifest_size, g_slots, vt->nslots, vec_loader, (void *)(uintptr_t)vt);
    eq_i64("tileset open", CT_OK, st);
    if (st != CT_OK) {
        return 0u;
    }
    /* bound: the vectors' cases and methods */
    for (k = 0u; k < vt->ncases; ++k) {
        const ct_vec_case *c = &vt->cases[k];
        g_idx = k;
        for (m = 0u; m < (uint32_t)CT_METHOD_COUNT; ++m) {
            ct_hit h;
            uint32_t before = g_fail;
            g_method = m;
            zero_bytes(&h, sizeof h);
            ct_plat_stack_paint();
            st = ct_tileset_trace(&g_ts, &c->ray, (ct_method)m, &h);
            st_note(ST_TILESET);
            eq_i64("tileset status", c->status[m], st);
            eq_hit(&c->hit[m], &h);
            ok += g_fail == before;
            *hits += st == CT_HIT || st == CT_HIT_VOID;
        }
    }
    eq_u64("tileset loads", vt->loads, g_ts.loads);
    /* the camera's pixels through the set's batch (its runs), then */
    if (vt->camera >= vs->ncameras || vs->cameras[vt->camera].npixels > CAM_MAX_PIXELS) {
        eq_i64("tileset camera", 0, 1);
        return ok;
    }
    {
        const ct_vec_camera *vc = &vs->cameras[vt->camera];
        ct_status pst;
        camera_setup(vc, &st, &pst);
        eq_i64("tileset camera init", CT_OK, st);
        eq_i64("tileset pose init", CT_OK, pst);
        /* bound: the camera's pixels */
        for (k = 0u; k < vc->npixels; ++k) {
            g_uv[2u * k] = vc->pixels[k].u_q16;
            g_uv[2u * k + 1u] = vc->pixels[k].v_q16;
        }
        g_method = vc->batch_method;
        zero_bytes(g_batch, sizeof g_batch);
        ct_plat_stack_paint();
        st = ct_geolocate_batch_tiles(&g_ts, &g_cam, &g_pose, (ct_method)vc->batch_method, &vc->effects, g_uv,
                                      vc->npixels, g_batch, CAM_MAX_PIXELS);
        st_note(ST_BATCH_TILES);
        eq_i64("tileset batch status", CT_OK, st);
        /* bound: the camera's pixels */
        for (k = 0u; k < vc->npixels; ++k) {
            g_idx = k;
            eq_geo(&vt->batch[k], &g_batch[k]);
        }
        eq_u64("tileset loads after the batch", vt->batch_loads, g_ts.loads);
    }
    return ok;
}

/* Ends a summary line: " N mismatching fields" since `before` failures. */
static void end_line_mismatches(uint32_t before)
{
    put_u64(g_fail - before);
    put_str(" mismatching fields");
    flush_line();
}

/* The fixed-point core, directions, UTM and Earth-fixed conversions, and
 * their summary line. */
static void report_fixed(const ct_vec_set *vs)
{
    uint32_t before = g_fail;
    check_fixed(vs);
    put_str("  fixed point, directions, UTM (");
    put_u64(vs->ngeo);
    put_str(" points: forward, inverse, factors, geodetic poses), Earth-fixed (");
    put_u64(vs->necef);
    put_str(" points: forward, inverse): ");
    end_line_mismatches(before);
}

/* The vertical datum and its summary line. */
static void report_datum(const ct_vec_set *vs)
{
    uint32_t before = g_fail, n = check_datum(vs);
    put_str("  vertical datum: ct_geoid_at (");
    put_u64(vs->ngeoid_grids);
    put_str(" grids, ");
    put_u64(vs->ngeoid);
    put_str(" points), ");
    put_u64(vs->ndatum);
    put_str(" datum package (open, fields, ");
    put_u64(vs->ndatum > 0u ? vs->datum[0].npoints : 0u);
    put_str(" map points): ");
    put_u64(n);
    put_str(" geoids, ");
    end_line_mismatches(before);
}

/* Every package, a summary line each.  Adds the traces that matched in
 * full to *traces, the traces checked to *total. */
static void report_packages(const ct_vec_set *vs, uint32_t *traces, uint32_t *total)
{
    uint32_t p;
    for (p = 0u; p < vs->npackages; ++p) { /* bound: the vectors' packages */
        const ct_vec_package *vp = &vs->packages[p];
        uint32_t t = 0u, h = 0u, before = g_fail;
        check_package(vp, &t, &h);
        *total += vp->ncases * (uint32_t)CT_METHOD_COUNT;
        *traces += t;
        put_rays_line("  package ", vp->name, vp->ncases, t, h);
        put_u64(vp->cone_codes);
        put_str(" cone codes), ");
        end_line_mismatches(before);
    }
}

/* Every camera, a summary line each.  Adds the geolocations that matched
 * in full to *traces, those checked to *total. */
static void report_cameras(const ct_vec_set *vs, uint32_t *traces, uint32_t *total)
{
    uint32_t p;
    for (p = 0u; p < vs->ncameras; ++p) { /* bound: the vectors' cameras */
        const ct_vec_camera *vc = &vs->cameras[p];
        uint32_t n = 0u, before = g_fail;
        const uint32_t ok = check_camera(vs, vc, &n);
        *total += n;
        *traces += ok;
        put_str("  camera ");
        put_str(vc->name);
        put_str(": ");
        put_u64(vc->npixels);
        put_str(" pixels x 4 methods: ");
        put_u64(ok);
        put_str("/");
        put_u64(n);
        put_str(" geolocations identical (batch checked too), ");
        end_line_mismatches(before);
    }
}

/* Every tile set, a summary line each.  Adds the traces that matched in
 * full to *traces, the traces checked to *total. */
static void report_tilesets(const ct_vec_set *vs, uint32_t *traces, uint32_t *total)
{
    uint32_t p;
    for (p = 0u; p < vs->ntilesets; ++p) { /* bound: the vectors' tile sets */
        const ct_vec_tileset *vt = &vs->tilesets[p];
        uint32_t h = 0u, before = g_fail;
        const uint32_t ok = check_tileset(vs, vt, &h);
        *total += vt->ncases * (uint32_t)CT_METHOD_COUNT;
        *traces += ok;
        put_rays_line("  tile set ", vt->name, vt->ncases, ok, h);
        put_u64(vt->loads);
        put_str(" tile loads into ");
        put_u64(vt->nslots);
        put_str(" slots), ");
        end_line_mismatches(before);
    }
}

/* On a target: the largest stack each measured entry point used. */
static void report_stack(void)
{
#ifdef CT_MCU_TARGET
    uint32_t p;
    for (p = 0u; p < (uint32_t)ST_COUNT; ++p) { /* bound: ST_COUNT */
        put_str("  measured stack ");
        put_str(st_names[p]);
        put_str(": ");
        put_u64(st_max[p]);
        put_str(" bytes");
        flush_line();
    }
#else
    (void)st_names;
#endif
}

/* With CT_MCU_EXPECT_BUILDER: the vectors must come from
 * ct_host::build_package (real cones); a failure otherwise. */
static void check_generator(const ct_vec_set *vs)
{
#ifdef CT_MCU_EXPECT_BUILDER
    const char *a = vs->generator, *b = "build_package";
    while (*a != '\0' && *a == *b) { /* bound: the shorter string */
        ++a;
        ++b;
    }
    if (*a != '\0' || *b != '\0') {
        put_str("FAIL: vectors were not made by build_package: ");
        put_str(vs->generator);
        flush_line();
        g_fail++;
    }
#else
    (void)vs;
#endif
}

int main(void)
{
    const ct_vec_set *vs = &ct_vectors;
    uint32_t traces = 0u, total = 0u;
    int pass;

    put_str("mcu_vectors[" CT_MCU_NAME "]: generator ");
    put_str(vs->generator);
    flush_line();
    check_crc();
    report_fixed(vs);
    report_datum(vs);
    report_packages(vs, &traces, &total);
    report_cameras(vs, &traces, &total);
    report_tilesets(vs, &traces, &total);
    report_stack();
    check_generator(vs);
    pass = g_fail == 0u && traces == total && total > 0u;
    put_str("mcu_vectors[" CT_MCU_NAME "]: ");
    put_str(pass ? "PASS " : "FAIL ");
    put_u64(traces);
    put_str("/");
    put_u64(total);
    put_str(" traces and geolocations bit-identical, ");
    put_u64(g_checks);
    put_str(" values checked, ");
    put_u64(g_fail);
    put_str(" mismatches");
    flush_line();
    return pass ? 0 : 1;
}
