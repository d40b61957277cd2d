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
 *   mode 1 (package): edits (u16 offset, u8 value) applied to a copy of the
 *                     package, its CRC re-stamped (unless bit 7 of byte 1
 *                     is set), then ct_package_open / ct_package_verify and
 *                     a few rays from the bytes that follow the edits;
 *   mode 2 (geolocation, byte 0 = 2 mod 4): a pinhole camera on an
 *                     arbitrary map pose near the tile (yaw, pitch, roll),
 *                     an arbitrary pixel and effects (curvature, refraction
 *                     k, radius 0 = the true Earth on the UTM package,
 *                     chord) through ct_geolocate with every method: a
 *                     documented status, identical results, hits in the tile;
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
 *                     merged package's, or CT_NO_DATA no later than it.
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
        CHECK(l0 == CT_OK || l0 == CT_HIT || l0 == CT_BELOW || l0 == CT_ERR_RAY || l0 == CT_ERR_EFFECTS);
        for (m = 1; m < CT_METHOD_COUNT; ++m) { /* bound: 4 methods */
            l1 = ct_los(&pkg, A, B, &fx, (e >> 50) & 0xffffff, (ct_method)m, &h1);
            CHECK(l1 == l0);
        }
        l1 = ct_locate_inverse(&pkg, &cam, &pose, &fx, B, 0, &u2, &v2, &vis, &h1);
        CHECK(l1 == CT_OK || l1 == CT_ERR_UNPROJECT || l1 == CT_ERR_RAY || l1 == CT_ERR_EFFECTS || l1 == CT_BELOW);
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
    } else {
        package_mode(vp, (d[1] & 0x80u) == 0u, d + 2, n - 2u);
    }
    return 0;
}
