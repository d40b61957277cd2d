/*
 * fuzz_lib.c -- libFuzzer harness for the flight library (ASan + UBSan):
 * packages and rays the fuzzer makes up, checked against the library's own
 * contracts, not only for crashes.
 *
 * Input: byte 0 selects the mode and byte 1 the base package (the two
 * packages of the MCU vectors, built by the project's builder: N = 8, r = 2
 * and N = 24, r = 1, with real cones).
 *   mode 0 (ray, byte 0 = 0 mod 4):     six int64 (x, y, z, dx, dy, dz), then a bend (c Q16,
 *                     R and chord exponents) -- traced straight and bent
 *                     with all four methods on the intact package;
 *   mode 1 (package, byte 0 = 1 mod 8): edits (u16 offset, u8 value) applied to a copy of the
 *                     package, its CRC re-stamped (unless bit 7 of byte 1
 *                     is set), then ct_package_open / ct_package_verify and
 *                     a few rays from the bytes that follow the edits;
 *   mode 2 (geolocation, byte 0 = 2 mod 4): a pinhole camera on an
 *                     arbitrary map pose near the tile (yaw, pitch, roll),
 *                     an arbitrary pixel and effects (curvature, refraction
 *                     k, radius 0 = the true Earth on the UTM package,
 *                     chord) through ct_geolocate with every method: a
 *                     documented status, identical results, hits in the tile;
 *                     and 8 pixels along a row from it through
 *                     ct_geolocate_batch (its runs): each record as
 *                     ct_geolocate's;
 *   mode 3 (geodesy, byte 0 = 3 mod 4): int64 lat, lon, e, n, yaw, pitch,
 *                     roll, h and a zone byte through ct_utm_forward,
 *                     ct_utm_inverse, ct_utm_factors, ct_quat_from_ypr and
 *                     ct_pose_from_wgs84: documented statuses only, and
 *                     where the forward projection succeeds, its inverse
 *                     succeeds and projects back to the same nanometre;
 *                     then lat, lon, h and e, n, yaw as Earth-fixed x, y, z
 *                     through ct_ecef_from_wgs84 / ct_wgs84_from_ecef, raw
 *                     and folded into their domains: the status is the one
 *                     the domain implies, and the round trips (geodetic ->
 *                     Earth-fixed -> geodetic -> Earth-fixed, and Earth-fixed
 *                     -> geodetic -> Earth-fixed) come back within 2 nm.
 *   mode 4 (tile set, byte 0 = 4 mod 8, a share of mode 0's bytes): the
 *                     MCU vectors' 3 x 3 tile set of the first package's
 *                     DEM (same N, r: that package is the merged one);
 *                     byte 1: bit 0 edit tile byte 2 % 9 with the (u16
 *                     offset, u8 value) edits that follow (count byte 3 %
 *                     9), its CRC re-stamped; bit 1 the manifest vouching
 *                     for the edited tile (entry and CRC re-stamped); bit 2
 *                     zero copy; bits 3-4 slots - 1; then up to 4 rays
 *                     traced with every method: documented statuses
 *                     (CT_NO_DATA included), the bound, hits in the box,
 *                     and with no tile accepted edited, each result is the
 *                     merged package's, or CT_NO_DATA no later than it;
 *                     then (24 more bytes) 8 pixels of a row through
 *                     ct_geolocate_batch_tiles (straight or on a small
 *                     sphere), each record as ct_geolocate_tiles' and,
 *                     with no tile accepted edited, the merged package's;
 *   mode 5 (lens, byte 0 = 5 mod 16, taken from mode 1, whose corpus
 *                     inputs have byte 0 = 1; its byte 1 the flags): a
 *                     ct_lens of every model (or a raw model number) with
 *                     raw int64 parameters, any within the documented
 *                     ranges, or a plausible lens -> ct_camera_init: the
 *                     status the ranges imply (always CT_OK for pinholes and
 *                     plausible lenses); pixels through ct_camera_unproject
 *                     (iters <= CT_UNPROJECT_MAX_ITERS, 0 for a pinhole, whose
 *                     ray and refusals beyond x^2 + y^2 = 64 are judged
 *                     exactly; unit rays ahead) that project back within
 *                     the residual CT_UNPROJECT_TOL_Q32 plus the Q30 ray's
 *                     rounding (its effect measured by projecting the ray's
 *                     +-1 neighbours); rays through ct_camera_project
 *                     (refused behind the camera), their pixels unprojected
 *                     again: they re-project, and for lenses without
 *                     tangential terms (injective on the valid field) come
 *                     back parallel within the pixel error times the
 *                     ray's change between neighbouring pixels;
 *   mode 13 (grid, byte 0 = 13 mod 16): ct_camera_init_grid on up to
 *                     16 x 16 nodes (geometry raw or in range; nodes baked
 *                     by ct_camera_unproject from a plausible lens, a
 *                     coherent field from the input with missing nodes, the
 *                     same with raw noise near the 2^-20 unit test, or a
 *                     field in the plane y = 0): the status the geometry and
 *                     nodes imply; pixels on nodes, inside and raw against
 *                     the header's interpolation in double (the 4 x 4 nodes,
 *                     t kept to 2^-20 of a step, Catmull-Rom, refusals for
 *                     a missing node, |V| < 1/2, a node beyond 60 deg; on a
 *                     node line either neighbouring cell): the same status,
 *                     the ray within 2^-24 rad, unit, y = 0 exactly for the
 *                     planar field, and ct_camera_project CT_ERR_LENS.
 * Contracts asserted (abort on violation):
 *   - every status is one the API documents for the call;
 *   - on a package that opens and verifies, the four methods return the same
 *     status and the same hit, bit for bit, straight and bent -- except the
 *     cone methods when an edit changed an angle code or the posting or
 *     height scale the codes are measured in: ct_package_verify
 *     checks the heights, the mipmap and the apexes, but a cone's opening
 *     (which only the builder's whole computation can confirm) is trusted,
 *     as the CRC that guards it; such a package may then lead the cone
 *     walks past terrain, never out of bounds;
 *   - a hit lies in the tile (its cell, and x, y within the tile's box);
 *   - iters never exceed the published bound (CT_WCET_*).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "conetrace.h"
#include "ct_vectors.h"

#define CHECK(c)       \
    do {               \
        if (!(c)) {    \
            abort();   \
        }              \
    } while (0)

static uint8_t g_buf[65536] __attribute__((aligned(8)));

static int64_t rd64(const uint8_t *d, size_t n, size_t *pos)
{
    uint64_t v = 0u;
    unsigned k;
    for (k = 0u; k < 8u; ++k) {
        uint64_t b = *pos < n ? d[*pos] : 0u;
        v |= b << (8u * k);
        (*pos)++;
    }
    return (int64_t)v;
}

/* Six int64 at d[*pos..] as a ray (zero past the end). */
static void read_ray(const uint8_t *d, size_t n, size_t *pos, ct_ray *r)
{
    r->x_q16 = rd64(d, n, pos);
    r->y_q16 = rd64(d, n, pos);
    r->z_q16 = rd64(d, n, pos);
    r->dx = rd64(d, n, pos);
    r->dy = rd64(d, n, pos);
    r->dz = rd64(d, n, pos);
}

static int trace_status_ok(ct_status s)
{
    return s == CT_HIT || s == CT_HIT_VOID || s == CT_MISS || s == CT_BELOW || s == CT_ERR_RAY ||
           s == CT_ERR_RANGE || s == CT_ERR_ARG;
}

static void check_hit(const ct_package *p, ct_status s, const ct_hit *h, uint32_t bound)
{
    CHECK(trace_status_ok(s));
    if (s >= 0) {
        CHECK(h->iters <= bound);
    }
    if (s == CT_HIT || s == CT_HIT_VOID) {
        CHECK(h->cell_x >= 0 && h->cell_y >= 0 && (uint32_t)h->cell_x < p->cells_x &&
              (uint32_t)h->cell_y < p->cells_y);
        CHECK(h->x_q16 >= -2 && h->y_q16 >= -2 && h->x_q16 <= (int64_t)p->cells_x * 65536 + 2 &&
              h->y_q16 <= (int64_t)p->cells_y * 65536 + 2);
    }
}

static int same_hit(ct_status a, const ct_hit *ha, ct_status b, const ct_hit *hb)
{
    if (a != b) {
        return 0;
    }
    if (a != CT_HIT && a != CT_HIT_VOID) {
        return 1;
    }
    return ha->x_q16 == hb->x_q16 && ha->y_q16 == hb->y_q16 && ha->z_q16 == hb->z_q16 &&
           ha->t_q26 == hb->t_q26 && ha->cell_x == hb->cell_x && ha->cell_y == hb->cell_y &&
           ha->e_nm == hb->e_nm && ha->n_nm == hb->n_nm && ha->h_nm == hb->h_nm;
}

/* All methods, straight and (if bd) bent; identical results when `same`
 * (1: all four; 2: incremental and hierarchical only). */
static void trace_all(const ct_package *p, const ct_ray *r, const ct_bend *bd, int same)
{
    ct_hit h0, h;
    ct_status s0, s;
    int m;
    uint32_t segs = CT_BEND_MAX_SEGMENTS;
    s0 = ct_trace(p, r, CT_METHOD_INCREMENTAL, &h0);
    check_hit(p, s0, &h0, CT_WCET_CELL_ITERS(p->cells_x, p->cells_y));
    for (m = 1; m < CT_METHOD_COUNT; ++m) {
        s = ct_trace(p, r, (ct_method)m, &h);
        check_hit(p, s, &h,
                  m == CT_METHOD_HIERARCHICAL ? CT_WCET_HIER_ITERS(p->cells_x, p->cells_y, p->levels)
                                              : CT_WCET_CELL_ITERS(p->cells_x, p->cells_y));
        if (same == 1 || (same == 2 && m == CT_METHOD_HIERARCHICAL)) {
            CHECK(same_hit(s0, &h0, s, &h));
        }
    }
    if (bd == NULL) {
        return;
    }
    s0 = ct_trace_bent(p, r, bd, CT_METHOD_INCREMENTAL, &h0);
    CHECK(trace_status_ok(s0));
    if (s0 == CT_HIT || s0 == CT_HIT_VOID) {
        check_hit(p, s0, &h0, CT_WCET_BENT_ITERS(p->cells_x, p->cells_y, segs));
    }
    for (m = 1; m < CT_METHOD_COUNT; ++m) {
        s = ct_trace_bent(p, r, bd, (ct_method)m, &h);
        CHECK(trace_status_ok(s));
        if (same) {
            CHECK(same_hit(s0, &h0, s, &h));
        }
    }
}

static void ray_mode(const ct_vec_package *vp, uint32_t idx, const uint8_t *d, size_t n)
{
    static ct_package pkgs[8]; /* opened once each */
    static int opened[8];
    ct_package *pkg = &pkgs[idx % 8u];
    size_t pos = 0u;
    ct_ray r;
    ct_bend bd;
    if (!opened[idx % 8u]) {
        CHECK(ct_package_open(pkg, vp->bytes, vp->size) == CT_OK);
        opened[idx % 8u] = 1;
    }
    read_ray(d, n, &pos, &r);
    {
        /* a bend: c in [-4, 4] (Q16), R = 2^(40..54) nm, chord 2^(10..50) nm */
        int64_t e = rd64(d, n, &pos);
        bd.coeff_q16 = (int32_t)((e & 0x7ffff) - 0x40000);
        bd.radius_nm = INT64_C(1) << (40 + ((e >> 20) & 0xf) % 15);
        bd.chord_nm = INT64_C(1) << (10 + ((e >> 24) & 0x3f) % 41);
        bd.flags = (uint32_t)((e >> 30) & 1);
    }
    trace_all(pkg, &r, &bd, 1);
}

/* ---- mode 4: tile sets --------------------------------------------------- */

static union {
    uint64_t align;
    uint8_t b[9][CT_VEC_TILE_CAP];
} g_tiles;
static uint32_t g_tile_size[9];
static union {
    uint64_t align;
    uint8_t b[4096];
} g_manifest;
static union {
    uint64_t align;
    uint8_t b[4][CT_VEC_TILE_CAP];
} g_slot_bufs;

static void st32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

/* CRC of a package or manifest with its CRC field (offset 12) zeroed,
 * written into that field. */
static void restamp(uint8_t *b, uint32_t size)
{
    uint32_t c = 0u;
    st32(b + 12, 0u);
    (void)ct_crc32(0u, b, size, &c);
    st32(b + 12, c);
}

static int g_zero_copy;

static ct_status fuzz_loader(void *user, uint32_t col, uint32_t row, uint8_t *buf, size_t cap, const uint8_t **bytes,
                             size_t *len)
{
    uint32_t k = row * 3u + col;
    (void)user;
    if (k >= 9u || g_tile_size[k] > cap) {
        return CT_ERR_ARG;
    }
    if (g_zero_copy) {
        *bytes = g_tiles.b[k];
    } else {
        memcpy(buf, g_tiles.b[k], g_tile_size[k]);
        *bytes = buf;
    }
    *len = g_tile_size[k];
    return CT_OK;
}

static void tileset_mode(const uint8_t *d, size_t n)
{
    static ct_package merged;
    static int opened;
    const ct_vec_tileset *vt;
    ct_tile_slot slots[4];
    ct_tileset ts;
    uint32_t k, nslots, edited = 9u, nedits;
    size_t pos = 3u;
    int r;
    if (ct_vectors.ntilesets == 0u || n < 3u) {
        return;
    }
    vt = &ct_vectors.tilesets[0];
    CHECK(vt->ntiles == 9u && vt->manifest_size <= sizeof g_manifest.b);
    if (!opened) {
        CHECK(ct_package_open(&merged, ct_vectors.packages[0].bytes, ct_vectors.packages[0].size) == CT_OK);
        opened = 1;
    }
    memcpy(g_manifest.b, vt->manifest, vt->manifest_size);
    for (k = 0u; k < 9u; ++k) {
        memcpy(g_tiles.b[k], vt->tiles[k].bytes, vt->tiles[k].size);
        g_tile_size[k] = vt->tiles[k].size;
    }
    if (d[0] & 1u) {
        edited = d[1] % 9u;
        nedits = d[2] % 9u;
        for (k = 0u; k < nedits && pos + 3u <= n; ++k, pos += 3u) {
            uint32_t off = ((uint32_t)d[pos] | (uint32_t)d[pos + 1] << 8) % g_tile_size[edited];
            g_tiles.b[edited][off] = d[pos + 2];
        }
        restamp(g_tiles.b[edited], g_tile_size[edited]);
        if (d[0] & 2u) {
            uint8_t *e = g_manifest.b + CT_SET_HEADER_SIZE + edited * CT_SET_ENTRY_SIZE;
            memcpy(e + 4, g_tiles.b[edited] + 12, 4u);
            restamp(g_manifest.b, vt->manifest_size);
        }
    }
    g_zero_copy = (d[0] >> 2) & 1;
    nslots = 1u + ((d[0] >> 3) & 3u);
    for (k = 0u; k < nslots; ++k) {
        memset(&slots[k], 0, sizeof slots[k]);
        slots[k].buf = g_slot_bufs.b[k];
        slots[k].cap = CT_VEC_TILE_CAP;
    }
    CHECK(ct_tileset_open(&ts, g_manifest.b, vt->manifest_size, slots, nslots, fuzz_loader, NULL) == CT_OK);
    for (r = 0; r < 4 && pos < n; ++r) {
        ct_ray ray;
        int m;
        read_ray(d, n, &pos, &ray);
        if (r & 1) { /* a ray of the merged box's scale, as most real ones */
            ray.x_q16 = (ray.x_q16 & 0x3fffff) - 0x40000;
            ray.y_q16 = (ray.y_q16 & 0x3fffff) - 0x40000;
            ray.z_q16 = ray.z_q16 & 0x3fffffff;
            ray.dx >>= 40;
            ray.dy >>= 40;
            ray.dz >>= 44;
        }
        for (m = 0; m < CT_METHOD_COUNT; ++m) {
            ct_hit hm, hs;
            const ct_status sm = ct_trace(&merged, &ray, (ct_method)m, &hm);
            const ct_status ss = ct_tileset_trace(&ts, &ray, (ct_method)m, &hs);
            const uint32_t tile_bound = m == CT_METHOD_HIERARCHICAL ? CT_WCET_HIER_ITERS(11u, 11u, CT_MAX_LEVELS)
                                                                    : CT_WCET_CELL_ITERS(11u, 11u);
            CHECK(trace_status_ok(ss) || ss == CT_NO_DATA);
            if (ss >= 0) {
                CHECK(hs.iters <= CT_WCET_SET_ITERS(3u, 3u, tile_bound));
            }
            if (ss == CT_HIT || ss == CT_HIT_VOID || ss == CT_NO_DATA) {
                CHECK(hs.cell_x >= 0 && hs.cell_y >= 0 && (uint32_t)hs.cell_x < merged.cells_x &&
                      (uint32_t)hs.cell_y < merged.cells_y);
            }
            if (edited == 9u || (d[0] & 2u) == 0u) {
                /* every accepted tile is intact: the merged package's result,
                 * or no data (the refused tile) no later than it */
                if (ss == CT_NO_DATA) {
                    CHECK(edited != 9u);
                    CHECK(sm == CT_MISS || sm == CT_BELOW || ((sm == CT_HIT || sm == CT_HIT_VOID) && hs.t_q26 <= hm.t_q26));
                } else {
                    CHECK(same_hit(sm, &hm, ss, &hs));
                }
            }
        }
    }
    if (pos + 24u <= n) {
        /* a row of 8 pixels through the set's batch (its runs over the tile
         * the rays start on), straight or on a small sphere (the lowered
         * walk): each record as ct_geolocate_tiles', and with every accepted
         * tile intact as the merged package's (or no data no later) */
        const int64_t a = rd64(d, n, &pos), b = rd64(d, n, &pos), c = rd64(d, n, &pos);
        const int64_t deg = INT64_C(40244552544872904); /* one degree, Q61 */
        ct_lens lens;
        ct_camera cam;
        ct_pose pose;
        ct_effects fx;
        ct_geo gb[8], g, gm;
        int64_t uv[16];
        int32_t q[4];
        memset(&lens, 0, sizeof lens);
        lens.model = CT_LENS_PINHOLE;
        lens.width = lens.height = 1000u;
        lens.fx_q32 = lens.fy_q32 = (int64_t)(200 + (c & 1023)) << 32;
        lens.cx_q32 = lens.cy_q32 = (int64_t)500 << 32;
        CHECK(ct_camera_init(&cam, &lens) == CT_OK);
        memset(&fx, 0, sizeof fx);
        fx.flags = (c >> 10) & 1 ? CT_EFFECT_CURVATURE : 0u;
        fx.earth_radius_nm = INT64_C(1) << (44 + ((c >> 11) & 3));
        /* over the merged box or beside it, looking down 1 .. 64 deg */
        if (ct_quat_from_ypr((int64_t)(int16_t)(c >> 16) * (deg / 180), -(int64_t)(1 + ((c >> 32) & 63)) * deg, 0, q) ==
                CT_OK &&
            ct_pose_from_map(&pose, merged.origin_e_nm + (a % ((int64_t)merged.width * 2)) * merged.posting_e_nm,
                             merged.origin_n_nm + ((a >> 32) % ((int64_t)merged.height * 2)) * merged.posting_n_nm,
                             merged.height_offset_nm + ((int64_t)merged.hmax + (b & 0xffff)) * merged.height_scale_nm,
                             q) == CT_OK) {
            const ct_method bm = (ct_method)((c >> 40) & 3);
            uint32_t k;
            for (k = 0u; k < 8u; ++k) { /* bound: 8 pixels */
                uv[2u * k] = ((b >> 16) & 0x3ffffff) + (int64_t)k * (1 + ((b >> 42) & 0x1ffff));
                uv[2u * k + 1u] = (b >> 20) & 0x3ffffff;
            }
            CHECK(ct_geolocate_batch_tiles(&ts, &cam, &pose, bm, &fx, uv, 8u, gb, 8u) == CT_OK);
            for (k = 0u; k < 8u; ++k) { /* bound: 8 pixels */
                const ct_status s1 = ct_geolocate_tiles(&ts, &cam, &pose, bm, &fx, uv[2u * k], uv[2u * k + 1u], &g);
                CHECK(s1 == gb[k].status);
                CHECK(s1 != CT_NO_DATA || (g.hit.cell_x == gb[k].hit.cell_x && g.hit.cell_y == gb[k].hit.cell_y &&
                                           g.hit.t_q26 == gb[k].hit.t_q26));
                CHECK(same_hit(s1, &g.hit, gb[k].status, &gb[k].hit));
                if (edited == 9u || (d[0] & 2u) == 0u) {
                    const ct_status s2 = ct_geolocate(&merged, &cam, &pose, bm, &fx, uv[2u * k], uv[2u * k + 1u], &gm);
                    CHECK(s1 == CT_NO_DATA ? edited != 9u : same_hit(s2, &gm.hit, s1, &g.hit));
                }
            }
        }
    }
}

static void package_mode(const ct_vec_package *vp, int stamp_crc, const uint8_t *d, size_t n)
{
    static ct_package pkg;
    size_t pos = 0u, k;
    size_t edits = n > 0u ? d[0] : 0u;
    ct_status st;
    int verified, angles_edited = 0;
    static ct_package base;
    size_t a0, a1;
    memcpy(g_buf, vp->bytes, vp->size);
    /* the angle section of the intact package: [a0, a1) */
    CHECK(ct_package_open(&base, vp->bytes, vp->size) == CT_OK);
    a0 = (size_t)(base.angles - base.base);
    a1 = a0 + (size_t)base.planes * base.coarse_x * base.coarse_y;
    pos = 1u;
    for (k = 0u; k < edits && pos + 3u <= n; ++k, pos += 3u) {
        size_t off = ((size_t)d[pos] | ((size_t)d[pos + 1u] << 8)) % vp->size;
        /* an angle code, or the posting or the height scale its opening is
         * measured in (header bytes 48..63, 72..79): the cone's promise */
        if (((off >= a0 && off < a1) || (off >= 48u && off < 64u) || (off >= 72u && off < 80u)) &&
            g_buf[off] != d[pos + 2u]) {
            angles_edited = 1;
        }
        g_buf[off] = d[pos + 2u];
    }
    if (stamp_crc) {
        restamp(g_buf, vp->size);
    }
    st = ct_package_open(&pkg, g_buf, vp->size);
    CHECK(st == CT_OK || (st <= CT_ERR_ARG && st >= CT_ERR_FLAGS));
    if (st != CT_OK) {
        return;
    }
    st = ct_package_verify(&pkg);
    CHECK(st == CT_OK || st == CT_ERR_VERIFY);
    verified = st == CT_OK;
    /* rays from the remaining bytes: a start over the tile and a direction */
    for (k = 0u; k < 4u && pos < n; ++k) {
        ct_ray r;
        int64_t a = rd64(d, n, &pos), b = rd64(d, n, &pos);
        r.x_q16 = (int64_t)((uint64_t)a % ((uint64_t)pkg.cells_x * 65536u + 1u));
        r.y_q16 = (int64_t)((uint64_t)(a >> 32) % ((uint64_t)pkg.cells_y * 65536u + 1u));
        r.z_q16 = ((int64_t)pkg.hmax + 1 + (int64_t)(b & 0x3ff)) * 65536;
        r.dx = (int16_t)(b >> 16);
        r.dy = (int16_t)(b >> 32);
        r.dz = -(int64_t)(1 + ((uint64_t)b >> 48));
        /* on unverified content the methods may disagree (their
         * acceleration data is not what the builder wrote), never crash */
        trace_all(&pkg, &r, NULL, verified ? (angles_edited ? 2 : 1) : 0);
    }
}

/* ct_ecef_from_wgs84 / ct_wgs84_from_ecef: the documented domains give
 * the status exactly; inside, the round trips within 2 nm per axis. */
#define ECEF_HMIN (-(INT64_C(1) << 52))
#define ECEF_HMAX (INT64_C(1) << 54)
#define ECEF_MAX (INT64_C(1) << 55)

static int64_t fold(int64_t v, int64_t lo, int64_t hi) /* into [lo, hi] */
{
    uint64_t span = (uint64_t)hi - (uint64_t)lo + 1u;
    return (int64_t)((uint64_t)lo + (uint64_t)v % span);
}

static int64_t dist(int64_t a, int64_t b) { return a > b ? a - b : b - a; }

/* the inverse of xyz; its status as the domain implies (the 2^50 nm sphere
 * judged in double with a margin), the forward back within 2 nm */
static void ecef_inverse(const int64_t xyz[3])
{
    int64_t la, lo, h, back[3];
    int i, inside = 1;
    double r2 = 0.0, s = 1125899906842624.0; /* 2^50 */
    ct_status st;
    for (i = 0; i < 3; ++i) { /* bound: 3 axes */
        if (xyz[i] > ECEF_MAX || xyz[i] < -ECEF_MAX) {
            inside = 0;
        }
        r2 += (double)xyz[i] * (double)xyz[i];
    }
    st = ct_wgs84_from_ecef(xyz, &la, &lo, &h);
    CHECK(st == CT_OK || st == CT_ERR_RANGE);
    if (!inside) {
        CHECK(st == CT_ERR_RANGE);
        return;
    }
    if (r2 > s * s * (1.0 + 1e-9)) {
        CHECK(st == CT_OK);
    } else if (r2 < s * s * (1.0 - 1e-9)) {
        CHECK(st == CT_ERR_RANGE);
    }
    if (st != CT_OK) {
        return;
    }
    CHECK(la <= CT_PI_Q61 / 2 && la >= -(CT_PI_Q61 / 2) && lo <= CT_PI_Q61 && lo >= -CT_PI_Q61);
    CHECK(h >= -(INT64_C(6400000) * INT64_C(1000000000)) && h < INT64_C(3) * ECEF_MAX);
    st = ct_ecef_from_wgs84(la, lo, h, back);
    if (h >= ECEF_HMIN && h <= ECEF_HMAX) {
        CHECK(st == CT_OK);
        for (i = 0; i < 3; ++i) { /* bound: 3 axes */
            CHECK(dist(back[i], xyz[i]) <= 2);
        }
    } else {
        CHECK(st == CT_ERR_RANGE);
    }
}

static void ecef_mode(const int64_t *v)
{
    int64_t xyz[3], la, lo, h;
    ct_status st;
    int i, j;
    for (i = 0; i < 2; ++i) { /* bound: 2 passes: raw, folded into the domains */
        int64_t lat = i == 0 ? v[0] : fold(v[0], -(CT_PI_Q61 / 2), CT_PI_Q61 / 2);
        int64_t lon = i == 0 ? v[1] : fold(v[1], -CT_PI_Q61, CT_PI_Q61);
        int64_t hh = i == 0 ? v[7] : fold(v[7], ECEF_HMIN, ECEF_HMAX);
        int inside = lat >= -(CT_PI_Q61 / 2) && lat <= CT_PI_Q61 / 2 && lon >= -CT_PI_Q61 && lon <= CT_PI_Q61 &&
                     hh >= ECEF_HMIN && hh <= ECEF_HMAX;
        st = ct_ecef_from_wgs84(lat, lon, hh, xyz);
        CHECK(st == (inside ? CT_OK : CT_ERR_RANGE));
        if (st == CT_OK) {
            /* the forward's image lies in the inverse's domain (|.| <= N +
             * h < 2^54.5, >= b - 2^52 > 2^50 from the centre) */
            for (j = 0; j < 3; ++j) { /* bound: 3 axes */
                CHECK(xyz[j] <= ECEF_MAX && xyz[j] >= -ECEF_MAX);
            }
            CHECK(ct_wgs84_from_ecef(xyz, &la, &lo, &h) == CT_OK);
            CHECK(dist(h, hh) <= 2);
            ecef_inverse(xyz);
        }
        for (j = 0; j < 3; ++j) { /* bound: 3 axes */
            xyz[j] = i == 0 ? v[2 + j] : fold(v[2 + j], -ECEF_MAX, ECEF_MAX) / (INT64_C(1) << (v[5] & 7));
        }
        ecef_inverse(xyz);
    }
    CHECK(ct_ecef_from_wgs84(0, 0, 0, NULL) == CT_ERR_ARG);
    CHECK(ct_wgs84_from_ecef(xyz, NULL, &lo, &h) == CT_ERR_ARG);
}

static int geo_status_ok(ct_status s)
{
    return s == CT_HIT || s == CT_HIT_VOID || s == CT_MISS || s == CT_BELOW || s == CT_ERR_RAY ||
           s == CT_ERR_RANGE || s == CT_ERR_UNPROJECT || s == CT_ERR_EFFECTS || s == CT_ERR_POSE ||
           s == CT_ERR_ARG || s == CT_ERR_CRS;
}

/* Geolocation with arbitrary poses, pixels and effects on an intact
 * package (the true Earth on the UTM one, the sphere elsewhere or with a
 * radius): a documented status, the same status and hit from every method,
 * a hit inside the tile. */
static void geoloc_mode(const ct_vec_package *vp, const uint8_t *d, size_t n)
{
    static ct_package pkg;
    ct_camera cam;
    ct_lens lens;
    ct_pose pose;
    ct_effects fx;
    ct_geo g0, g;
    int32_t q[4];
    size_t pos = 0u;
    int64_t a = rd64(d, n, &pos), b = rd64(d, n, &pos), c = rd64(d, n, &pos), e = rd64(d, n, &pos);
    int64_t pix = rd64(d, n, &pos);
    const int64_t deg = INT64_C(40244552544872904); /* one degree, Q61 */
    int m;
    ct_status s0, s;
    CHECK(ct_package_open(&pkg, vp->bytes, vp->size) == CT_OK);
    memset(&lens, 0, sizeof lens);
    lens.model = CT_LENS_PINHOLE;
    lens.width = 1000u;
    lens.height = 1000u;
    lens.fx_q32 = lens.fy_q32 = (int64_t)1000 << 32;
    lens.cx_q32 = lens.cy_q32 = (int64_t)500 << 32;
    CHECK(ct_camera_init(&cam, &lens) == CT_OK);
    /* the camera within ~35 km of the tile's corner, -1 .. 15 km up */
    if (ct_quat_from_ypr((int64_t)(int16_t)(c >> 0) * (deg / 180), (int64_t)(int16_t)(c >> 16) * (deg / 360),
                         (int64_t)(int16_t)(c >> 32) * (deg / 180), q) != CT_OK) {
        return;
    }
    s = ct_pose_from_map(&pose, pkg.origin_e_nm + (int64_t)(int32_t)a * 16384, pkg.origin_n_nm + (int64_t)(int32_t)(a >> 32) * 16384,
                         (int64_t)(b % INT64_C(16000000000000)) - INT64_C(1000000000000), q);
    CHECK(s == CT_OK);
    fx.flags = (uint32_t)(e & 3);
    /* the fitted map: per call (1 input in 16: 125-343 exact conversions
     * each), or kept across calls (fitted once around the tile's centre) */
    if (((e >> 41) & 15) == 0) {
        fx.flags |= CT_EFFECT_EARTH_FIT;
    }
    fx.earth_map = NULL;
    if ((e >> 40) & 1) {
        /* one map per package (fitted the first time it is asked for); a
         * map of another package now and then (refused: CT_ERR_EFFECTS) */
        static ct_earth_map maps[4];
        static const ct_vec_package *made_for[4];
        static int state[4]; /* 1 fitted, 2 refused (not UTM) */
        size_t slot = (size_t)(((uintptr_t)vp >> 4) % 4u);
        if (made_for[slot] != vp) {
            made_for[slot] = vp;
            state[slot] = ct_earth_map_init(&pkg, pkg.origin_e_nm + (int64_t)(pkg.width / 2u) * pkg.posting_e_nm,
                                            pkg.origin_n_nm + (int64_t)(pkg.height / 2u) * pkg.posting_n_nm, 0,
                                            INT64_C(1) << 46, &maps[slot]) == CT_OK ? 1 : 2;
        }
        fx.earth_map = state[slot] == 1 ? &maps[((e >> 42) & 7) == 0 ? (slot + 1u) % 4u : slot] : NULL;
    }
    fx.refraction_k_q16 = (int32_t)((int16_t)(e >> 8)) * 4;
    fx.earth_radius_nm = ((e >> 24) & 1) ? 0 : INT64_C(1) << (40 + ((e >> 25) & 0xf) % 15);
    fx.chord_nm = ((e >> 29) & 1) ? 0 : INT64_C(1) << (10 + ((e >> 30) & 0x3f) % 41);
    {
        /* line of sight between arbitrary points near the tile (the pose's
         * centre and a point from the pixel word): a documented status, every
         * method alike; and the inverse location of that point */
        int64_t A[3], B[3], u2, v2;
        uint32_t vis;
        ct_hit h0, h1;
        ct_status l0, l1;
        A[0] = pose.e_nm;
        A[1] = pose.n_nm;
        A[2] = pose.h_nm;
        B[0] = pkg.origin_e_nm + (int64_t)(int32_t)pix * 4096;
        B[1] = pkg.origin_n_nm + (int64_t)(int32_t)(pix >> 32) * 4096;
        B[2] = (int64_t)(b % INT64_C(4000000000000));
        l0 = ct_los(&pkg, A, B, &fx, (e >> 50) & 0xffffff, CT_METHOD_INCREMENTAL, &h0);
        CHECK(l0 == CT_OK || l0 == CT_HIT || l0 == CT_BELOW || l0 == CT_ERR_RAY || l0 == CT_ERR_EFFECTS ||
              l0 == CT_ERR_RANGE);
        for (m = 1; m < CT_METHOD_COUNT; ++m) { /* bound: 4 methods */
            l1 = ct_los(&pkg, A, B, &fx, (e >> 50) & 0xffffff, (ct_method)m, &h1);
            CHECK(l1 == l0);
        }
        l1 = ct_locate_inverse(&pkg, &cam, &pose, &fx, B, 0, &u2, &v2, &vis, &h1);
        CHECK(l1 == CT_OK || l1 == CT_ERR_UNPROJECT || l1 == CT_ERR_RAY || l1 == CT_ERR_EFFECTS || l1 == CT_BELOW ||
              l1 == CT_ERR_RANGE);
        CHECK(vis <= 1u);
    }
    {
        /* effects for an arbitrary tolerance, k and radius: a documented
         * status, and when CT_OK a choice within its ranges */
        ct_effects_choice ch;
        const int64_t tol = (b >> 3) ^ e;
        s = ct_effects_for_tolerance(&pkg, &cam, &pose, fx.refraction_k_q16, fx.earth_radius_nm, tol, &ch);
        CHECK(s == CT_OK || s == CT_ERR_EFFECTS || s == CT_ERR_UNPROJECT);
        if (s == CT_OK) {
            CHECK(ch.flags <= CT_EFFECT_ALL && ch.chord_nm >= (INT64_C(1) << 10) && ch.chord_nm <= (INT64_C(1) << 50));
            CHECK(ch.bound_nm[0] >= 0 && ch.bound_nm[1] >= 0 && ch.bound_nm[2] >= 0 && ch.bound_nm[3] == 0);
            CHECK(ch.samples >= 1u && ch.samples <= 421u && ch.range_nm >= 0);
            CHECK(ch.flags == CT_EFFECT_ALL || ch.bound_nm[ch.flags == 0u ? 0 : (ch.flags == CT_EFFECT_CURVATURE ? 1 : 2)] <= tol);
        }
    }
    {
        const int64_t u = (int64_t)(int32_t)pix % (INT64_C(1500) << 16), v = (int64_t)(int32_t)(pix >> 32) % (INT64_C(1500) << 16);
        s0 = ct_geolocate(&pkg, &cam, &pose, CT_METHOD_INCREMENTAL, &fx, u, v, &g0);
        CHECK(geo_status_ok(s0) && s0 == g0.status);
        if (s0 == CT_HIT || s0 == CT_HIT_VOID) {
            check_hit(&pkg, s0, &g0.hit, UINT32_MAX);
        }
        for (m = 1; m < CT_METHOD_COUNT; ++m) { /* bound: 4 methods */
            s = ct_geolocate(&pkg, &cam, &pose, (ct_method)m, &fx, u, v, &g);
            CHECK(s == s0 && same_hit(s0, &g0.hit, s, &g.hit));
        }
        {
            /* the batch's runs: 8 pixels along a row from (u, v), 1/64 to
             * 4 px apart, with a method from the bytes: each record as
             * ct_geolocate's (status and hit; the steps may differ) */
            int64_t uv[16];
            ct_geo gb[8];
            const int64_t du = 1024 + (int64_t)((pix >> 20) & 0x3ffff);
            const ct_method bm = (ct_method)((e >> 60) & 3);
            uint32_t k;
            for (k = 0u; k < 8u; ++k) { /* bound: 8 pixels */
                uv[2u * k] = u + (int64_t)k * du;
                uv[2u * k + 1u] = v;
            }
            s = ct_geolocate_batch(&pkg, &cam, &pose, bm, &fx, uv, 8u, gb, 8u);
            CHECK(s == CT_OK || s == s0);
            for (k = 0u; k < 8u && s == CT_OK; ++k) { /* bound: 8 pixels */
                const ct_status s1 = ct_geolocate(&pkg, &cam, &pose, bm, &fx, uv[2u * k], uv[2u * k + 1u], &g);
                CHECK(s1 == gb[k].status && same_hit(s1, &g.hit, gb[k].status, &gb[k].hit));
            }
        }
    }
}

static void geodesy_mode(const uint8_t *d, size_t n)
{
    size_t pos = 0u;
    int64_t v[8], e, nn, la, lo, g, k;
    int32_t q[4];
    ct_utm z;
    ct_pose pose;
    ct_status s;
    int i;
    for (i = 0; i < 8; ++i) { /* bound: 8 values */
        v[i] = rd64(d, n, &pos);
    }
    z.zone = pos < n ? (int32_t)(d[pos] % 64u) : 17;
    z.south = pos + 1u < n ? (int32_t)(d[pos + 1u] & 1u) : 0;
    /* arbitrary values, and values scaled into the domain (most arbitrary
     * int64 angles are out of range) */
    for (i = 0; i < 2; ++i) { /* bound: 2 passes */
        int64_t lat = i == 0 ? v[0] : v[0] % CT_UTM_MAX_LAT_Q61;
        int64_t lon = i == 0 ? v[1] : (int64_t)(6 * z.zone - 183) * INT64_C(40244552544872904) + v[1] % (INT64_C(40244552544872904) * 10);
        s = ct_utm_forward(&z, lat, lon, &e, &nn);
        CHECK(s == CT_OK || s == CT_ERR_RANGE || s == CT_ERR_ARG);
        if (s == CT_OK) {
            /* the round trip, away from the domain's edge (within 2^-40 rad
             * of it the inverse may come back a few Q59 units outside) */
            const int64_t deg = INT64_C(40244552544872904), edge = INT64_C(1) << 21;
            /* lon - the central meridian, in half units (the difference of
             * two angles up to pi each may reach 2 pi: beyond int64 in Q61) */
            int64_t dl = lon / 2 - (int64_t)(6 * z.zone - 183) * (deg / 2);
            int64_t e2, n2;
            while (dl > 90 * deg) { /* bound: |lon| <= pi after the forward's check */
                dl -= 180 * deg;
            }
            while (dl < -90 * deg) { /* bound: as above */
                dl += 180 * deg;
            }
            dl *= 2;
            s = ct_utm_inverse(&z, e, nn, &la, &lo);
            CHECK(s == CT_OK);
            s = ct_utm_forward(&z, la, lo, &e2, &n2);
            if ((dl < 0 ? -dl : dl) < CT_UTM_MAX_DLON_DEG * deg - edge &&
                (lat < 0 ? -lat : lat) < CT_UTM_MAX_LAT_Q61 - edge) {
                CHECK(s == CT_OK);
                CHECK(e2 - e <= 1 && e - e2 <= 1 && n2 - nn <= 1 && nn - n2 <= 1);
            } else {
                CHECK(s == CT_OK || s == CT_ERR_RANGE);
            }
            CHECK(ct_utm_factors(&z, lat, lon, &g, &k) == CT_OK);
            CHECK(k > INT64_C(2300000000000000000) && k < INT64_C(2340000000000000000)); /* 0.9975..1.015 */
        }
        s = ct_utm_inverse(&z, v[2], v[3], &la, &lo);
        CHECK(s == CT_OK || s == CT_ERR_RANGE || s == CT_ERR_ARG);
        s = ct_quat_from_ypr(v[4] % (i == 0 ? INT64_MAX : CT_PI_Q61), v[5] % (i == 0 ? INT64_MAX : CT_PI_Q61),
                             v[6] % (i == 0 ? INT64_MAX : CT_PI_Q61), q);
        CHECK(s == CT_OK || s == CT_ERR_RANGE);
        if (s == CT_OK) {
            s = ct_pose_from_wgs84(&pose, &z, lat, lon, v[7], q);
            CHECK(s == CT_OK || s == CT_ERR_RANGE || s == CT_ERR_ARG || s == CT_ERR_POSE);
        }
    }
    ecef_mode(v);
}

/* ---- modes 5 and 13: lenses and unprojection grids ----------------------- */

/* sqrt for the harness's judgements (no libm: replay links the library only) */
static double dsqrt(double x)
{
    double g = x > 1.0 ? x : 1.0;
    int k;
    if (x <= 0.0) {
        return 0.0;
    }
    for (k = 0; k < 200; ++k) { /* bound: Newton from above, |x| < 2^130 */
        double h = 0.5 * (g + x / g);
        if (h >= g) {
            break;
        }
        g = h;
    }
    return g;
}

/* the angle between a and b at most tol (rad; both non-zero): |a x b|^2 <=
 * tol^2 |a|^2 |b|^2, and a . b > 0 */
static int parallel(const double a[3], const double b[3], double tol)
{
    double c0 = a[1] * b[2] - a[2] * b[1], c1 = a[2] * b[0] - a[0] * b[2], c2 = a[0] * b[1] - a[1] * b[0];
    double aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2], bb = b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] > 0.0 && c0 * c0 + c1 * c1 + c2 * c2 <= tol * tol * aa * bb;
}

static void to_d3(const int32_t r[3], double o[3])
{
    o[0] = (double)r[0];
    o[1] = (double)r[1];
    o[2] = (double)r[2];
}

/* |ray| = 1 within 2^-29 (the ray_cam format): 2 Q30 units */
static int unit_q30(const int32_t r[3])
{
    const double l = dsqrt((double)r[0] * r[0] + (double)r[1] * r[1] + (double)r[2] * r[2]);
    return l >= 1073741824.0 - 2.0 && l <= 1073741824.0 + 2.0;
}

#define PIX_LIM_Q16 ((int64_t)CT_CAM_MAX_PIXEL << 16)
#define Q32F 4294967296.0

/* Lens parameters from the input: how 0 raw int64 (unused coefficients
 * zeroed unless keep), 1 anywhere in the documented ranges (coefficients
 * also scaled down by 0..63 bits), 2 a plausible lens (f 200..4000 px,
 * |k| <= 0.5, |p| <= 0.005 or none). */
static void lens_from(const uint8_t *d, size_t n, size_t *pos, uint32_t model, int how, int keep, ct_lens *l)
{
    static const int64_t kmax[8] = {INT64_C(1) << 47, INT64_C(3) << 46, INT64_C(1) << 40, INT64_C(1) << 40,
                                    INT64_C(1) << 46, INT64_C(1) << 47, INT64_C(3) << 46, INT64_C(1) << 46};
    int64_t v[12];
    uint32_t k, used;
    for (k = 0u; k < 12u; ++k) { /* bound: 12 parameters */
        v[k] = rd64(d, n, pos);
    }
    memset(l, 0, sizeof *l);
    l->model = model;
    l->width = 1000u;
    l->height = 1000u;
    used = model == CT_LENS_PINHOLE ? 0u : (model == CT_LENS_OPENCV4 ? 4u : (model == CT_LENS_OPENCV5 ? 5u : 8u));
    if (how == 0) {
        l->fx_q32 = v[0];
        l->fy_q32 = v[1];
        l->cx_q32 = v[2];
        l->cy_q32 = v[3];
        for (k = 0u; k < 8u; ++k) { /* bound: 8 coefficients */
            l->dist_q48[k] = (k < used || keep) ? v[4 + k] : 0;
        }
    } else if (how == 1) {
        l->fx_q32 = fold(v[0], INT64_C(1) << 32, PIX_LIM_Q16 << 16);
        l->fy_q32 = fold(v[1], INT64_C(1) << 32, PIX_LIM_Q16 << 16);
        l->cx_q32 = fold(v[2], -(PIX_LIM_Q16 << 16), PIX_LIM_Q16 << 16);
        l->cy_q32 = fold(v[3], -(PIX_LIM_Q16 << 16), PIX_LIM_Q16 << 16);
        for (k = 0u; k < 8u; ++k) { /* bound: 8 coefficients */
            l->dist_q48[k] = k < used ? fold(v[4 + k], -CT_CAM_MAX_DIST, CT_CAM_MAX_DIST) >> ((uint64_t)v[4 + k] >> 58) : 0;
        }
    } else {
        l->fx_q32 = fold(v[0], INT64_C(200) << 32, INT64_C(4000) << 32);
        l->fy_q32 = l->fx_q32 + fold(v[1], -(l->fx_q32 >> 6), l->fx_q32 >> 6);
        l->cx_q32 = fold(v[2], 0, INT64_C(2000) << 32);
        l->cy_q32 = fold(v[3], 0, INT64_C(2000) << 32);
        for (k = 0u; k < 8u; ++k) { /* bound: 8 coefficients */
            l->dist_q48[k] = k < used ? fold(v[4 + k], -kmax[k], kmax[k]) : 0;
        }
        if ((v[6] >> 62) & 1) { /* radial only */
            l->dist_q48[2] = l->dist_q48[3] = 0;
        }
    }
}

/* ct_camera_init's status as documented: CT_ERR_LENS for an unknown model,
 * f outside [1, 2^20] px, |c| > 2^20 px, a coefficient beyond 2^10 or set
 * but unused; otherwise CT_OK or CT_ERR_LENS (no valid field). */
static int lens_legal(const ct_lens *l)
{
    uint32_t k, used;
    const int64_t fmax = PIX_LIM_Q16 << 16;
    if (l->model >= (uint32_t)CT_LENS_COUNT || l->fx_q32 < (INT64_C(1) << 32) || l->fy_q32 < (INT64_C(1) << 32) ||
        l->fx_q32 > fmax || l->fy_q32 > fmax || l->cx_q32 < -fmax || l->cx_q32 > fmax || l->cy_q32 < -fmax ||
        l->cy_q32 > fmax) {
        return 0;
    }
    used = l->model == CT_LENS_PINHOLE ? 0u : (l->model == CT_LENS_OPENCV4 ? 4u : (l->model == CT_LENS_OPENCV5 ? 5u : 8u));
    for (k = 0u; k < 8u; ++k) { /* bound: 8 coefficients */
        if (l->dist_q48[k] < -CT_CAM_MAX_DIST || l->dist_q48[k] > CT_CAM_MAX_DIST || (k >= used && l->dist_q48[k] != 0)) {
            return 0;
        }
    }
    return 1;
}

static int64_t imax64(int64_t a, int64_t b) { return a > b ? a : b; }

/* |v| <= 2^20 px (Q16), the pixels' and grid origins' documented range */
static int in_pix(int64_t v) { return v >= -PIX_LIM_Q16 && v <= PIX_LIM_Q16; }

/* |a - b| for values within 2^62 of each other */
static int64_t dist64(int64_t a, int64_t b) { return a > b ? (int64_t)((uint64_t)a - (uint64_t)b) : (int64_t)((uint64_t)b - (uint64_t)a); }

/* The pixel moves (Q16, summed over the components) when each component
 * of the ray moves by +-1 (Q30 units): the projection's sensitivity to the
 * ray's rounding.  -1 where one of those projections fails. */
static int64_t proj_sens(const ct_camera *cam, const int32_t r[3], int64_t pu, int64_t pv)
{
    int64_t sum = 0;
    int k, s;
    for (k = 0; k < 3; ++k) { /* bound: 3 components */
        if (r[k] >= INT32_MAX - 1 || r[k] <= INT32_MIN + 1) {
            return -1;
        }
    }
    for (k = 0; k < 3; ++k) { /* bound: 3 components */
        int64_t m = 0;
        for (s = -1; s <= 1; s += 2) { /* bound: 2 signs */
            int32_t q[3];
            int64_t u2, v2;
            q[0] = r[0];
            q[1] = r[1];
            q[2] = r[2];
            q[k] += s;
            if (ct_camera_project(cam, q, &u2, &v2) != CT_OK) {
                return -1;
            }
            m = imax64(m, imax64(dist64(u2, pu), dist64(v2, pv)));
        }
        sum += m;
    }
    return sum;
}

/* The pixel (Q16) where a lens ray came from, within what the residual
 * (CT_UNPROJECT_TOL_Q32 in normalised units, i.e. f 2^-26 px, twice for the
 * evaluation's rounding) and the ray's rounding to Q30 (its effect measured
 * by proj_sens, three times) allow. */
static void check_reproject(const ct_camera *cam, const int32_t ray[3], int64_t u, int64_t v)
{
    int64_t pu, pv, sens;
    double f = (double)imax64(cam->lens.fx_q32, cam->lens.fy_q32) / Q32F, tol;
    const ct_status s = ct_camera_project(cam, ray, &pu, &pv);
    CHECK(s == CT_OK || s == CT_ERR_UNPROJECT);
    if (s != CT_OK) {
        /* only at the valid field's edge: a neighbour of the ray is refused too */
        CHECK(proj_sens(cam, ray, 0, 0) < 0 || (double)ray[0] * ray[0] + (double)ray[1] * ray[1] >=
                                                 (double)cam->r2_max_q32 / Q32F * (double)ray[2] * ray[2] * 0.999999);
        return;
    }
    sens = proj_sens(cam, ray, pu, pv);
    if (sens < 0) {
        return; /* at the edge: no sensitivity to judge by */
    }
    tol = 3.0 * (double)sens + 2.0 * f * 65536.0 * (double)CT_UNPROJECT_TOL_Q32 / Q32F + 4.0;
    CHECK((double)dist64(pu, u) <= tol && (double)dist64(pv, v) <= tol);
}

static int lens_model_radial(const ct_lens *l) { return l->dist_q48[2] == 0 && l->dist_q48[3] == 0; }

/* A ray through ct_camera_project, and its pixel back through
 * ct_camera_unproject: the pixel re-projects (check_reproject); for a lens
 * without tangential terms (injective on its valid field) the ray comes
 * back parallel within what the pixel's error (its rounding, the residual,
 * the projection's rounding) turns into at that pixel, measured by
 * unprojecting its neighbours. */
static void check_ray(const ct_camera *cam, const int32_t r[3])
{
    int64_t pu, pv, sens, h;
    int32_t back[3], nb[3];
    uint32_t it;
    double f = (double)imax64(cam->lens.fx_q32, cam->lens.fy_q32) / Q32F, e, worst = 0.0, a[3], b[3];
    ct_status s = ct_camera_project(cam, r, &pu, &pv);
    int k;
    CHECK(s == CT_OK || s == CT_ERR_UNPROJECT);
    if (r[2] <= 0) {
        CHECK(s == CT_ERR_UNPROJECT);
    }
    if (s != CT_OK || !in_pix(pu) || !in_pix(pv)) {
        return;
    }
    s = ct_camera_unproject(cam, pu, pv, back, &it);
    CHECK((s == CT_OK || s == CT_ERR_UNPROJECT) && it <= CT_UNPROJECT_MAX_ITERS);
    if (s != CT_OK) {
        return;
    }
    CHECK(unit_q30(back) && back[2] > 0);
    check_reproject(cam, back, pu, pv);
    sens = proj_sens(cam, r, pu, pv);
    if (!lens_model_radial(&cam->lens) || sens < 0) {
        return;
    }
    e = (double)sens + 2.0 * f * 65536.0 * (double)CT_UNPROJECT_TOL_Q32 / Q32F + 2.0; /* pixel error, Q16 */
    h = (int64_t)e + 1;
    to_d3(back, b);
    for (k = 0; k < 4; ++k) { /* bound: 4 neighbours */
        const int64_t du = k == 0 ? h : (k == 1 ? -h : 0), dv = k == 2 ? h : (k == 3 ? -h : 0);
        double c[3], c0, c1, c2, s2;
        if (ct_camera_unproject(cam, pu + du, pv + dv, nb, NULL) != CT_OK) {
            return;
        }
        to_d3(nb, c);
        c0 = b[1] * c[2] - b[2] * c[1];
        c1 = b[2] * c[0] - b[0] * c[2];
        c2 = b[0] * c[1] - b[1] * c[0];
        s2 = (c0 * c0 + c1 * c1 + c2 * c2) / ((b[0] * b[0] + b[1] * b[1] + b[2] * b[2]) * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]));
        if (s2 > worst) {
            worst = s2;
        }
    }
    to_d3(r, a);
    CHECK(parallel(a, b, 3.0 * dsqrt(worst) * e / (double)h + 4.0 / 1073741824.0));
}

/* mode 5: a lens from the input through ct_camera_init, pixels through
 * ct_camera_unproject and rays through ct_camera_project. */
static void lens_mode(const uint8_t *d, size_t n)
{
    ct_lens lens;
    ct_camera cam;
    size_t pos = 1u;
    const uint32_t fl = n > 0u ? d[0] : 0u;
    const int how = (int)((fl >> 3) & 3u) >= 2 ? 2 : (int)((fl >> 3) & 3u);
    uint32_t model = fl & 3u;
    ct_status st;
    int k;
    if (how == 0 && (fl & 4u)) {
        model = (uint32_t)rd64(d, n, &pos);
    }
    lens_from(d, n, &pos, model, how, (fl & 0x80u) != 0u, &lens);
    st = ct_camera_init(&cam, &lens);
    CHECK(st == CT_OK || st == CT_ERR_LENS);
    if (!lens_legal(&lens)) {
        CHECK(st == CT_ERR_LENS);
        return;
    }
    if (lens.model == CT_LENS_PINHOLE || how == 2) {
        CHECK(st == CT_OK); /* a valid field around the axis (R = 1, slope 1 there) */
    }
    if (st != CT_OK) {
        return;
    }
    CHECK(cam.r2_max_q32 > 0 && cam.r2_max_q32 <= ((int64_t)CT_CAM_MAX_R2 << 32));
    {
        int64_t u, v;
        CHECK(ct_camera_project(&cam, NULL, &u, &v) == CT_ERR_ARG);
    }
    for (k = 0; k < 4 && pos < n; ++k) { /* bound: 4 pixels */
        int64_t u = rd64(d, n, &pos), v = rd64(d, n, &pos);
        int32_t ray[3];
        uint32_t it = 99u;
        if (k >= 1) { /* within 2^20 px; then near the principal point (+-3 f) */
            u = fold(u, -PIX_LIM_Q16, PIX_LIM_Q16);
            v = fold(v, -PIX_LIM_Q16, PIX_LIM_Q16);
        }
        if (k >= 2) {
            u = (lens.cx_q32 >> 16) + u % ((lens.fx_q32 >> 16) * 3 + 1);
            v = (lens.cy_q32 >> 16) + v % ((lens.fy_q32 >> 16) * 3 + 1);
        }
        st = ct_camera_unproject(&cam, u, v, ray, &it);
        CHECK(st == CT_OK || st == CT_ERR_UNPROJECT);
        CHECK(it <= CT_UNPROJECT_MAX_ITERS);
        if (lens.model == CT_LENS_PINHOLE) {
            /* no iteration; the ray ((u - cx) / fx, (v - cy) / fy, 1), refused
             * exactly beyond x^2 + y^2 = 64 */
            const double x = ((double)u * 65536.0 - (double)lens.cx_q32) / (double)lens.fx_q32;
            const double y = ((double)v * 65536.0 - (double)lens.cy_q32) / (double)lens.fy_q32;
            const double r2 = x * x + y * y;
            CHECK(it == 0u);
            if (!in_pix(u) || !in_pix(v) || r2 > 64.000001) {
                CHECK(st == CT_ERR_UNPROJECT);
            } else if (r2 < 63.999999) {
                double a[3], b[3];
                CHECK(st == CT_OK);
                a[0] = x;
                a[1] = y;
                a[2] = 1.0;
                to_d3(ray, b);
                CHECK(parallel(a, b, 4.0 / 1073741824.0));
            }
        }
        if (!in_pix(u) || !in_pix(v)) {
            CHECK(st == CT_ERR_UNPROJECT);
        }
        if (st == CT_OK) {
            CHECK(unit_q30(ray) && ray[2] > 0);
            check_reproject(&cam, ray, u, v);
        }
    }
    for (k = 0; k < 4 && pos < n; ++k) { /* bound: 4 rays */
        int64_t a = rd64(d, n, &pos), b = rd64(d, n, &pos);
        int32_t r[3];
        r[0] = (int32_t)a;
        r[1] = (int32_t)(a >> 32);
        r[2] = (int32_t)b;
        if (k >= 1) { /* ahead of the camera, within ~83 deg of the axis mostly */
            r[2] = (int32_t)(1 + ((uint32_t)b & 0x3fffffffu));
            r[0] = (int32_t)(((int64_t)r[0] * (int64_t)((b >> 32) & 0xffff)) >> 16) % (8 * (r[2] / 8 + 1));
            r[1] = (int32_t)(((int64_t)r[1] * (int64_t)((b >> 48) & 0xffff)) >> 16) % (8 * (r[2] / 8 + 1));
        }
        check_ray(&cam, r);
    }
}

/* ---- grids ---- */

static int32_t g_grid_rays[3u * 256u];

/* Catmull-Rom weights at t in [0, 1] */
static void cr_ref(double t, double w[4])
{
    w[0] = 0.5 * (-t * t * t + 2.0 * t * t - t);
    w[1] = 0.5 * (3.0 * t * t * t - 5.0 * t * t + 2.0);
    w[2] = 0.5 * (-3.0 * t * t * t + 4.0 * t * t + t);
    w[3] = 0.5 * (t * t * t - t * t);
}

/* The grid's documented unprojection, in double: the 4 x 4 nodes around
 * the pixel (cell i, fraction t kept to 2^-20 of a step; at a node either
 * neighbouring cell), Catmull-Rom, renormalised; refused if a node is
 * missing or (0, 0, 0), |V| < 1/2 or a node more than 60 deg from the
 * result.  Returns 1 (unprojects), 0 (refused), -1 (within 1e-6 of a
 * threshold: either); V the interpolated vector. */
static int grid_ref_at(const ct_unproject_grid *g, int64_t iu, double tu, int64_t iv, double tv, double V[3])
{
    double wu[4], wv[4], l, worst = 2.0;
    int a, b, k;
    if (iu < 1 || iu > (int64_t)g->nu - 3 || iv < 1 || iv > (int64_t)g->nv - 3) {
        return 0;
    }
    cr_ref(tu, wu);
    cr_ref(tv, wv);
    V[0] = V[1] = V[2] = 0.0;
    for (b = 0; b < 4; ++b) { /* bound: 4 x 4 nodes */
        for (a = 0; a < 4; ++a) {
            const int32_t *r = g->rays_q30 + 3 * ((iv + b - 1) * (int64_t)g->nu + iu + a - 1);
            if (r[0] == 0 && r[1] == 0 && r[2] == 0) {
                return 0;
            }
            for (k = 0; k < 3; ++k) { /* bound: 3 components */
                V[k] += wv[b] * wu[a] * (double)r[k] / 1073741824.0;
            }
        }
    }
    l = dsqrt(V[0] * V[0] + V[1] * V[1] + V[2] * V[2]);
    if (l < 0.5 * (1.0 - 1e-6)) {
        return 0;
    }
    for (b = 0; b < 4; ++b) { /* bound: 4 x 4 nodes */
        for (a = 0; a < 4; ++a) {
            const int32_t *r = g->rays_q30 + 3 * ((iv + b - 1) * (int64_t)g->nu + iu + a - 1);
            const double c = ((double)r[0] * V[0] + (double)r[1] * V[1] + (double)r[2] * V[2]) / (l * 1073741824.0);
            if (c < worst) {
                worst = c;
            }
        }
    }
    if (worst < 0.5 - 1e-6) {
        return 0;
    }
    return l < 0.5 * (1.0 + 1e-6) || worst < 0.5 + 1e-6 ? -1 : 1;
}

/* cell and fraction along one axis; *alt set where the pixel is on a node
 * (the cell before it, t = 1, is as good a reading) */
static void grid_ref_axis(int64_t p, int64_t p0, int64_t step, int64_t *i, double *t, int *alt)
{
    int64_t dd = p - p0, k = dd / step, rem;
    if (dd % step < 0) {
        k -= 1;
    }
    rem = dd - k * step;
    *i = k;
    *t = (double)((rem << 20) / step) / 1048576.0;
    *alt = rem == 0;
}

static int grid_ref(const ct_unproject_grid *g, int64_t u, int64_t v, double V[3])
{
    int64_t iu, iv;
    double tu, tv, W[3];
    int au, av, r, r0, r2;
    if (!in_pix(u) || !in_pix(v)) {
        return 0;
    }
    grid_ref_axis(u, g->u0_q16, g->step_q16, &iu, &tu, &au);
    grid_ref_axis(v, g->v0_q16, g->step_q16, &iv, &tv, &av);
    r0 = grid_ref_at(g, iu, tu, iv, tv, V);
    r = r0;
    if (au || av) { /* on a node line: the other readings may decide otherwise */
        int m;
        for (m = 1; m < 4; ++m) { /* bound: 3 other readings */
            if (((m & 1) && !au) || ((m & 2) && !av)) {
                continue;
            }
            r2 = grid_ref_at(g, (m & 1) ? iu - 1 : iu, (m & 1) ? 1.0 : tu, (m & 2) ? iv - 1 : iv, (m & 2) ? 1.0 : tv, W);
            if (r2 != r0) {
                if (r0 == 0 && r2 != 0) { /* V: a reading that interpolated */
                    V[0] = W[0];
                    V[1] = W[1];
                    V[2] = W[2];
                }
                r = -1;
            }
        }
    }
    return r;
}

/* mode 13: ct_camera_init_grid on a small grid from the input (its geometry
 * raw or in range; nodes baked from a plausible lens, a coherent field from
 * the input, such a field with raw noise near the unit test's 2^-20, or a
 * field in the plane y = 0), then pixels (on nodes, inside, raw) through
 * ct_camera_unproject against the documented interpolation. */
static void grid_mode(const uint8_t *d, size_t n)
{
    ct_unproject_grid g;
    ct_camera cam;
    size_t pos = 1u;
    const uint32_t fl = n > 0u ? d[0] : 0u, src = fl & 3u;
    int64_t a = rd64(d, n, &pos), b = rd64(d, n, &pos), c = rd64(d, n, &pos), e = rd64(d, n, &pos);
    int64_t pix[12], base[3];
    uint32_t k, nodes, valid = 1u;
    ct_status st;
    int p;
    memset(&g, 0, sizeof g);
    if (fl & 4u) { /* raw geometry */
        g.nu = (uint32_t)a;
        g.nv = (uint32_t)(a >> 32);
        g.step_q16 = b;
        g.u0_q16 = c;
        g.v0_q16 = e;
        if (fl & 0x40u) {
            g.nu = 4u + g.nu % 29u; /* around the table's 256 nodes */
            g.nv = 4u + g.nv % 29u;
        }
        g.rays_len = sizeof g_grid_rays / sizeof g_grid_rays[0];
    } else {
        g.nu = 4u + (uint32_t)(a & 0xff) % 13u;
        g.nv = 4u + (uint32_t)((a >> 8) & 0xff) % 13u;
        g.step_q16 = 65536 + (fold(b, 0, INT64_C(4095) << 16) >> ((a >> 16) & 31));
        g.u0_q16 = fold(c, -PIX_LIM_Q16, PIX_LIM_Q16) >> ((a >> 24) & 31);
        g.v0_q16 = fold(e, -PIX_LIM_Q16, PIX_LIM_Q16) >> ((a >> 32) & 31);
        g.rays_len = 3u * g.nu * g.nv - ((fl & 0x80u) ? 1u : 0u);
    }
    g.rays_q30 = g_grid_rays;
    for (p = 0; p < 12; ++p) { /* bound: 6 pixels */
        pix[p] = rd64(d, n, &pos);
    }
    for (k = 0u; k < 3u; ++k) { /* bound: 3 components */
        base[k] = (int16_t)(pos + 1u < n ? (uint32_t)d[pos] | (uint32_t)d[pos + 1u] << 8 : 0u);
        pos += 2u;
    }
    if (base[0] == 0 && base[1] == 0 && base[2] == 0) {
        base[2] = 1;
    }
    /* the nodes: node k is (i, j) = (k % nu, k / nu) */
    nodes = g.nu >= 1u ? 256u : 0u;
    memset(g_grid_rays, 0, sizeof g_grid_rays);
    if (src == 0u && g.nu >= 1u) {
        ct_lens lens;
        ct_camera lc;
        lens_from(d, n, &pos, (fl >> 4) & 3u, 2, 0, &lens);
        CHECK(ct_camera_init(&lc, &lens) == CT_OK);
        for (k = 0u; k < nodes; ++k) { /* bound: 256 nodes */
            const int64_t u = (int64_t)((uint64_t)g.u0_q16 + (uint64_t)(k % g.nu) * ((uint64_t)g.step_q16 & 0xfffffffu));
            const int64_t v = (int64_t)((uint64_t)g.v0_q16 + (uint64_t)(k / g.nu) * ((uint64_t)g.step_q16 & 0xfffffffu));
            uint32_t it;
            if (!in_pix(u) || !in_pix(v) ||
                ct_camera_unproject(&lc, u, v, g_grid_rays + 3u * k, &it) != CT_OK) {
                g_grid_rays[3u * k] = g_grid_rays[3u * k + 1u] = g_grid_rays[3u * k + 2u] = 0;
            }
        }
    } else {
        const unsigned sh = (fl >> 4) & 7u;
        for (k = 0u; k < nodes; ++k) { /* bound: 256 nodes */
            int32_t q[3];
            double w[3], l;
            uint32_t m;
            const int32_t n0 = pos < n ? (int8_t)d[pos] : 0;
            const int32_t n1 = pos + 1u < n ? (int8_t)d[pos + 1u] : 0;
            const int32_t n2 = pos + 2u < n ? (int8_t)d[pos + 2u] : 0;
            pos += 3u;
            if (n0 == -128) {
                continue; /* a node without a ray */
            }
            w[0] = (double)(base[0] * 256 + (int64_t)n0 * (INT64_C(1) << sh));
            w[1] = src == 3u ? 0.0 : (double)(base[1] * 256 + (int64_t)n1 * (INT64_C(1) << sh));
            w[2] = (double)(base[2] * 256 + (int64_t)n2 * (INT64_C(1) << sh));
            l = dsqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            if (l == 0.0) {
                continue;
            }
            for (m = 0u; m < 3u; ++m) { /* bound: 3 components */
                double x = w[m] / l * 1073741824.0;
                q[m] = (int32_t)(x < 0.0 ? x - 0.5 : x + 0.5);
            }
            if (src == 2u) { /* raw noise of up to 2^(3..10) Q30 units: the unit test's edge */
                q[0] += n1 * (INT32_C(1) << (3u + (uint32_t)(e & 7)));
                q[1] += n2 * (INT32_C(1) << (3u + (uint32_t)((e >> 3) & 7)));
                q[2] += n0 * (INT32_C(1) << (3u + (uint32_t)((e >> 6) & 7)));
            }
            g_grid_rays[3u * k] = q[0];
            g_grid_rays[3u * k + 1u] = q[1];
            g_grid_rays[3u * k + 2u] = q[2];
        }
    }
    /* the documented geometry and node checks */
    if (g.nu < 4u || g.nv < 4u || g.nu > CT_GRID_MAX_NODES || g.nv > CT_GRID_MAX_NODES || g.step_q16 < 65536 ||
        g.step_q16 > (INT64_C(4096) << 16) || !in_pix(g.u0_q16) || !in_pix(g.v0_q16) ||
        g.rays_len < 3u * (size_t)g.nu * g.nv) {
        valid = 0u;
    } else {
        for (k = 0u; k < g.nu * g.nv; ++k) { /* bound: <= 256 nodes (rays_len) */
            const int32_t *r = g_grid_rays + 3u * k;
            double l;
            if (r[0] == 0 && r[1] == 0 && r[2] == 0) {
                continue;
            }
            l = dsqrt((double)r[0] * r[0] + (double)r[1] * r[1] + (double)r[2] * r[2]) / 1073741824.0 - 1.0;
            if (l > 1.01 / 1048576.0 || l < -1.01 / 1048576.0) {
                valid = 0u;
            } else if ((l > 0.99 / 1048576.0 || l < -0.99 / 1048576.0) && valid == 1u) {
                valid = 2u; /* at the edge: either */
            }
        }
    }
    st = ct_camera_init_grid(&cam, &g);
    CHECK(st == CT_OK || st == CT_ERR_LENS);
    CHECK(valid == 2u || st == (valid ? CT_OK : CT_ERR_LENS));
    if (st != CT_OK) {
        return;
    }
    for (p = 0; p < 6; ++p) { /* bound: 6 pixels */
        int64_t u = pix[2 * p], v = pix[2 * p + 1];
        int32_t ray[3];
        uint32_t it = 99u;
        double V[3], o[3];
        int want;
        const int sel = (int)(((uint64_t)u >> 60) & 3u);
        if (sel == 0) { /* on a node (or just off the table) */
            u = g.u0_q16 + ((int64_t)((uint64_t)u % (g.nu + 2u)) - 1) * g.step_q16;
            v = g.v0_q16 + ((int64_t)((uint64_t)v % (g.nv + 2u)) - 1) * g.step_q16;
        } else if (sel != 3) { /* within the table's span (and a step beyond) */
            u = g.u0_q16 + fold(u, -g.step_q16, (int64_t)g.nu * g.step_q16);
            v = g.v0_q16 + fold(v, -g.step_q16, (int64_t)g.nv * g.step_q16);
        }
        st = ct_camera_unproject(&cam, u, v, ray, &it);
        CHECK(st == CT_OK || st == CT_ERR_UNPROJECT);
        CHECK(it <= CT_UNPROJECT_MAX_ITERS);
        want = grid_ref(&g, u, v, V);
        if (want >= 0) {
            CHECK(st == (want ? CT_OK : CT_ERR_UNPROJECT));
        }
        if (st != CT_OK) {
            continue;
        }
        CHECK(unit_q30(ray));
        to_d3(ray, o);
        CHECK(parallel(o, V, 1.0 / 16777216.0)); /* 2^-24 rad */
        if (src == 3u) {
            CHECK(ray[1] == 0); /* nodes in the plane y = 0 */
        }
        {
            /* grid cameras have no projection */
            int64_t pu, pv;
            CHECK(ct_camera_project(&cam, ray, &pu, &pv) == CT_ERR_LENS);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);
int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n)
{
    const ct_vec_package *vp;
    uint32_t idx;
    if (n < 2u || ct_vectors.npackages == 0u) {
        return 0;
    }
    idx = (d[1] & 0x7fu) % ct_vectors.npackages;
    vp = &ct_vectors.packages[idx];
    if (vp->size > sizeof g_buf) {
        return 0;
    }
    if ((d[0] & 3u) == 3u) {
        geodesy_mode(d + 2, n - 2u);
    } else if ((d[0] & 3u) == 2u) {
        geoloc_mode(vp, d + 2, n - 2u);
    } else if ((d[0] & 7u) == 4u) {
        tileset_mode(d + 1, n - 1u);
    } else if ((d[0] & 1u) == 0u) {
        ray_mode(vp, idx, d + 2, n - 2u);
    } else if ((d[0] & 7u) == 5u) {
        /* byte 0 = 5 mod 16 lenses, 13 mod 16 grids (taken from the
         * package mode, whose corpus inputs all have byte 0 = 1) */
        if (d[0] & 8u) {
            grid_mode(d + 1, n - 1u);
        } else {
            lens_mode(d + 1, n - 1u);
        }
    } else {
        package_mode(vp, (d[1] & 0x80u) == 0u, d + 2, n - 2u);
    }
    return 0;
}
