/*
 * package.c -- terrain package layout, validation, CRC-32 and the derived
 * tables (sector boundaries, cot per angle code).  The layout is defined
 * once here (ct_package_layout) and used by the reader and the writer.
 */
#include "bend.h"
#include "fixed.h"
#include "tiles.h"

/* Sizes are computed in uint64: W, H <= 2^15 so W*H*2 < 2^31 and every
 * section (and the total) fits in uint32; the checks below reject anything
 * larger before a uint32 is formed.                                         */

static uint64_t align8(uint64_t v) { return (v + 7u) & ~(uint64_t)7u; }

static uint32_t levels_for(uint32_t cx, uint32_t cy)
{
    uint32_t l = 0u;
    /* bound: CT_MAX_LEVELS; each level halves the larger side (< 2^15) */
    while ((cx > 1u || cy > 1u) && l < CT_MAX_LEVELS - 1u) {
        cx = (cx + 1u) / 2u;
        cy = (cy + 1u) / 2u;
        l++;
    }
    return l;
}

ct_status ct_package_layout(uint32_t width, uint32_t height, uint32_t reduce,
                            uint32_t sectors, uint32_t with_voids,
                            uint32_t sec_off[CT_SEC_COUNT],
                            uint32_t sec_size[CT_SEC_COUNT], uint32_t *levels,
                            uint32_t *total)
{
    uint64_t sz[CT_SEC_COUNT], off, mip = 0u;
    uint32_t cx, cy, wc, hc, l, lv, mw, mh, planes, k;
    CT_ASSERT(sec_off != NULL && sec_size != NULL && levels != NULL && total != NULL);
    if (sec_off == NULL || sec_size == NULL || levels == NULL || total == NULL) {
        return CT_ERR_ARG;
    }
    if (width < 2u || height < 2u || width > CT_MAX_POSTS || height > CT_MAX_POSTS) {
        return CT_ERR_DIMS;
    }
    if (sectors < 1u || sectors > CT_MAX_SECTORS) {
        return CT_ERR_SECTORS;
    }
    if (reduce < 1u || reduce > CT_MAX_REDUCE) {
        return CT_ERR_REDUCE;
    }
    cx = width - 1u;
    cy = height - 1u;
    wc = (cx + reduce - 1u) / reduce;
    hc = (cy + reduce - 1u) / reduce;
    lv = levels_for(cx, cy);
    mw = cx;
    mh = cy;
    /* bound: lv <= CT_MAX_LEVELS - 1 */
    for (l = 1u; l <= lv; ++l) {
        mw = (mw + 1u) / 2u;
        mh = (mh + 1u) / 2u;
        mip += (uint64_t)mw * mh * 2u;
    }
    planes = sectors == 1u ? 1u : sectors + 1u;
    sz[CT_SEC_HEIGHTS] = (uint64_t)width * height * 2u;
    sz[CT_SEC_MIPMAP] = mip;
    sz[CT_SEC_APEX] = (uint64_t)wc * hc * 2u;
    sz[CT_SEC_ANGLES] = (uint64_t)wc * hc * planes;
    sz[CT_SEC_VOIDS] = with_voids ? ((uint64_t)cx * cy + 7u) / 8u : 0u;
    off = CT_PKG_HEADER_SIZE;
    /* bound: CT_SEC_COUNT sections */
    for (k = 0u; k < CT_SEC_COUNT; ++k) {
        sec_off[k] = (uint32_t)off;
        sec_size[k] = (uint32_t)sz[k];
        off = align8(off + sz[k]);
    }
    if (off > 0xffffffffu) {
        return CT_ERR_SIZE;
    }
    *levels = lv;
    *total = (uint32_t)off;
    return CT_OK;
}

ct_status ct_package_size(uint32_t width, uint32_t height, uint32_t reduce,
                          uint32_t sectors, uint32_t with_voids,
                          uint32_t *out_size)
{
    uint32_t so[CT_SEC_COUNT], ss[CT_SEC_COUNT], lv;
    CT_ASSERT(out_size != NULL);
    if (out_size == NULL) {
        return CT_ERR_ARG;
    }
    *out_size = 0u;
    return ct_package_layout(width, height, reduce, sectors, with_voids, so, ss,
                             &lv, out_size);
}

ct_status ct_crc32(uint32_t crc, const uint8_t *data, size_t len, uint32_t *out_crc)
{
    const uint32_t *t0 = ct_crc32_table[0], *t1 = ct_crc32_table[1], *t2 = ct_crc32_table[2],
                   *t3 = ct_crc32_table[3];
    size_t i;
    uint32_t c = ~crc;
    CT_ASSERT(out_crc != NULL && (data != NULL || len == 0u));
    if (out_crc == NULL || (data == NULL && len != 0u)) {
        return CT_ERR_ARG;
    }
    /* four bytes at a time (slicing by 4): the word, little-endian, folded
     * into the register, then each of its bytes advanced by the table for
     * the bytes still to come after it.  bound: len / 4 words */
    for (i = 0u; len - i >= 4u; i += 4u) {
        c ^= ct_ld32(data + i);
        c = t3[c & 0xffu] ^ t2[(c >> 8) & 0xffu] ^ t1[(c >> 16) & 0xffu] ^ t0[c >> 24];
    }
    /* bound: the last len % 4 bytes */
    for (; i < len; ++i) {
        c = t0[(c ^ data[i]) & 0xffu] ^ (c >> 8);
    }
    *out_crc = ~c;
    return CT_OK;
}

ct_status ct_sector_boundary(uint32_t sectors, uint32_t k, int32_t *bx, int32_t *by)
{
    CT_ASSERT(bx != NULL && by != NULL);
    if (bx == NULL || by == NULL) {
        return CT_ERR_ARG;
    }
    if (sectors < 1u || sectors > CT_MAX_SECTORS || k > sectors) {
        return CT_ERR_SECTORS;
    }
    ct_dir_of_fraction(k, sectors, bx, by);
    return CT_OK;
}

ct_status ct_cot_table(int64_t posting_nm, int64_t height_scale_nm,
                       int64_t out_q16[256], uint8_t ok[256])
{
    uint32_t k;
    int64_t den;
    CT_ASSERT(out_q16 != NULL && ok != NULL);
    if (out_q16 == NULL || ok == NULL) {
        return CT_ERR_ARG;
    }
    posting_nm = ct_abs64(posting_nm);
    if (posting_nm <= 0 || height_scale_nm <= 0 ||
        posting_nm > (INT64_C(1) << 50) || height_scale_nm > (INT64_C(1) << 46)) {
        return CT_ERR_GEOREF;
    }
    /* cot_grid (LSB per cell) = cot_metric * posting / scale.
     * Q16 = ceil(cot_q32 * posting / (scale * 2^16)).
     * |cot_q32| < 2^39, posting <= 2^50: product < 2^89 (128-bit);
     * den = scale * 2^16 <= 2^62.  Quotients beyond CT_COT_MAX are capped. */
    den = height_scale_nm * 65536;
    out_q16[0] = CT_COT_MAX_Q16;
    ok[0] = 0u;
    /* bound: 255 codes */
    for (k = 1u; k < 256u; ++k) {
        ct_i128 num = ct_i128_mul(ct_cot_q32[k], posting_nm);
        ct_i128 cap = ct_i128_mul(CT_COT_MAX_Q16, den);
        int64_t v;
        if (ct_i128_cmp(num, cap) > 0) {
            out_q16[k] = CT_COT_MAX_Q16;
            ok[k] = 0u; /* too narrow to step with: degenerate */
            continue;
        }
        if (ct_i128_cmp(num, ct_i128_neg(cap)) < 0) {
            out_q16[k] = -CT_COT_MAX_Q16; /* raising the cone is conservative */
            ok[k] = 1u;
            continue;
        }
        v = -ct_i128_floor_div(ct_i128_neg(num), den); /* ceil */
        out_q16[k] = v;
        ok[k] = 1u;
    }
    return CT_OK;
}

ct_status ct_in_wedge(const int32_t *bound_x, const int32_t *bound_y,
                      uint32_t sectors, uint32_t s, int64_t dx, int64_t dy,
                      uint32_t *out_inside)
{
    int64_t c0, c1;
    CT_ASSERT(bound_x != NULL && bound_y != NULL && out_inside != NULL);
    if (bound_x == NULL || bound_y == NULL || out_inside == NULL) {
        return CT_ERR_ARG;
    }
    if (sectors < 1u || sectors > CT_MAX_SECTORS || s >= sectors) {
        return CT_ERR_SECTORS;
    }
    if (ct_abs64(dx) > (INT64_C(1) << 30) || ct_abs64(dy) > (INT64_C(1) << 30)) {
        return CT_ERR_ARG;
    }
    if (sectors == 1u) {
        *out_inside = 1u;
        return CT_OK;
    }
    /* |b| <= 2^30, |d| <= 2^30: each product < 2^60, difference < 2^61 */
    c0 = (int64_t)bound_x[s] * dy - (int64_t)bound_y[s] * dx;
    c1 = dx * (int64_t)bound_y[s + 1u] - dy * (int64_t)bound_x[s + 1u];
    *out_inside = (c0 >= 0 && c1 >= 0) ? 1u : 0u;
    return CT_OK;
}

/* half(v): 0 for angles in [0, 180), 1 for [180, 360).  angle(b) <=
 * angle(d), an exact total order on [0, 360), is half(b) < half(d), or the
 * same half and b x d >= 0. */
static int half_of(int64_t x, int64_t y) { return (y < 0 || (y == 0 && x < 0)) ? 1 : 0; }

ct_status ct_sector_of(const ct_package *pkg, int64_t dx, int64_t dy,
                       uint32_t *out_sector)
{
    uint32_t lo, hi, n;
    int hd;
    CT_ASSERT(pkg != NULL && out_sector != NULL);
    if (pkg == NULL || out_sector == NULL) {
        return CT_ERR_ARG;
    }
    if ((dx == 0 && dy == 0) || ct_abs64(dx) > (INT64_C(1) << 30) ||
        ct_abs64(dy) > (INT64_C(1) << 30)) {
        return CT_ERR_ARG;
    }
    n = pkg->sectors;
    if (n == 1u) {
        *out_sector = 0u;
        return CT_OK;
    }
    /* Largest k in [0, n) with angle(b_k) <= angle(d) (d's half formed
     * once): b_0 is +x (angle 0), so k exists.  The boundaries are
     * ct_sector_boundary's (ct_package_open), in increasing angle, so the
     * search ends with angle(b_lo) <= angle(d) < angle(b_lo+1): d lies in
     * the closed wedge lo, ct_in_wedge's test, which the builder uses
     * (test_fixed's test_sector_of checks both for every N); on b_lo
     * exactly it is in wedge lo - 1 as well, and either is valid.
     * bound: log2(64) + 1 halvings.                                        */
    hd = half_of(dx, dy);
    lo = 0u;
    hi = n; /* invariant: angle(b_lo) <= angle(d), and b_hi > d or hi == n */
    while (hi - lo > 1u) {
        uint32_t mid = (lo + hi) / 2u;
        int64_t bx = pkg->bound_x[mid], by = pkg->bound_y[mid];
        int hb = half_of(bx, by);
        /* |b|, |d| <= 2^30: each product < 2^60 */
        if (hb != hd ? hb < hd : bx * dy - by * dx >= 0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    *out_sector = lo;
    return CT_OK;
}

/* ------------------------------------------------------------------------ */

/* The datum section (conetrace.h): its fields into pkg, or the status of
 * the first thing wrong.  `end` is where the last fixed section ends.     */
static ct_status open_datum(ct_package *pkg, const uint8_t *b, uint32_t total,
                            uint64_t end, int present)
{
    uint32_t off = ct_ld32(b + CT_HDR_DATUM), vd, gw, gh;
    const uint8_t *d;
    pkg->vdatum = CT_VDATUM_UNKNOWN;
    pkg->source_epsg = 0u;
    pkg->geoid.w = 0u;
    pkg->geoid.h = 0u;
    pkg->geoid.lat0_q61 = 0;
    pkg->geoid.lon0_q61 = 0;
    pkg->geoid.step_q61 = 0;
    pkg->geoid.values = NULL;
    if (!present) {
        return off == 0u ? CT_OK : CT_ERR_FLAGS;
    }
    if ((off % CT_PKG_ALIGN) != 0u || (uint64_t)off < end ||
        (uint64_t)off + CT_DATUM_HEADER_SIZE > (uint64_t)total) {
        return CT_ERR_OFFSET;
    }
    d = b + off;
    vd = ct_ld16(d);
    gw = ct_ld16(d + 2);
    gh = ct_ld16(d + 4);
    if (vd >= (uint32_t)CT_VDATUM_COUNT || ct_ld16(d + 6) != 0u || ct_ld32(d + 12) != 0u) {
        return CT_ERR_RANGE;
    }
    if (gw != 0u || gh != 0u) {
        ct_geoid_grid g;
        ct_status st;
        g.w = gw;
        g.h = gh;
        g.lat0_q61 = ct_ld64s(d + 16);
        g.lon0_q61 = ct_ld64s(d + 24);
        g.step_q61 = ct_ld64s(d + 32);
        g.values = d + CT_DATUM_HEADER_SIZE;
        st = ct_geoid_grid_check(&g);
        if (st != CT_OK) {
            return st;
        }
        /* 4 gw gh <= 2^26: no overflow in 64 bits */
        if ((uint64_t)off + CT_DATUM_HEADER_SIZE + 4u * (uint64_t)gw * gh > (uint64_t)total) {
            return CT_ERR_SIZE;
        }
        pkg->geoid = g;
    }
    pkg->vdatum = vd;
    pkg->source_epsg = ct_ld32(d + 8);
    return CT_OK;
}

ct_status ct_check_stamped(const uint8_t *b, size_t len, const char *magic, uint32_t version, uint32_t header_size,
                           uint32_t *total)
{
    static const uint8_t zero4[4] = {0u, 0u, 0u, 0u};
    uint32_t crc;
    if (len < header_size) {
        return CT_ERR_TRUNCATED;
    }
    if (b[0] != (uint8_t)magic[0] || b[1] != (uint8_t)magic[1] || b[2] != (uint8_t)magic[2] ||
        b[3] != (uint8_t)magic[3]) {
        return CT_ERR_MAGIC;
    }
    if (ct_ld16(b + CT_HDR_VERSION) != version) {
        return CT_ERR_VERSION;
    }
    if (ct_ld16(b + CT_HDR_HEADER_SIZE) != header_size) {
        return CT_ERR_HEADER;
    }
    *total = ct_ld32(b + CT_HDR_TOTAL);
    if (*total < header_size || (uint64_t)*total > (uint64_t)len) {
        return CT_ERR_TRUNCATED;
    }
    (void)ct_crc32(0u, b, CT_HDR_CRC, &crc);
    (void)ct_crc32(crc, zero4, 4u, &crc);
    (void)ct_crc32(crc, b + CT_HDR_CRC + 4u, (size_t)*total - (CT_HDR_CRC + 4u), &crc);
    return crc == ct_ld32(b + CT_HDR_CRC) ? CT_OK : CT_ERR_CRC;
}

ct_status ct_package_frame(ct_package *pkg, uint32_t w, uint32_t h, uint32_t r, uint32_t n, int32_t hmin, int32_t hmax,
                           const int64_t g[6], uint32_t epsg)
{
    int64_t pe = g[2], pn = g[3];
    uint32_t k;
    if (hmin > hmax) {
        return CT_ERR_RANGE;
    }
    if (pe == 0 || pn == 0 || ct_abs64(pe) != ct_abs64(pn) || g[5] <= 0 || ct_abs64(pe) > (INT64_C(1) << 50) ||
        g[5] > (INT64_C(1) << 46) || ct_abs64(g[0]) > (INT64_C(1) << 61) || ct_abs64(g[1]) > (INT64_C(1) << 61) ||
        ct_abs64(g[4]) > (INT64_C(1) << 61)) {
        return CT_ERR_GEOREF;
    }
    pkg->hmin = hmin;
    pkg->hmax = hmax;
    pkg->origin_e_nm = g[0];
    pkg->origin_n_nm = g[1];
    pkg->posting_e_nm = pe;
    pkg->posting_n_nm = pn;
    pkg->height_offset_nm = g[4];
    pkg->height_scale_nm = g[5];
    pkg->base = NULL;
    pkg->size = 0u;
    pkg->width = w;
    pkg->height = h;
    pkg->cells_x = w - 1u;
    pkg->cells_y = h - 1u;
    pkg->reduce = r;
    {
        /* the coarsest prepared z unit, 2^k Q16 LSB, that is still no larger
         * in nm than a Q16 cell unit: 2^k * scale <= |posting|, i.e.
         * scale <= floor(|posting| / 2^k).  bound: 16 doublings */
        uint32_t zk = 0u;
        while (zk < (uint32_t)CT_ZSHIFT_MAX && pkg->height_scale_nm <= (ct_abs64(pe) >> (zk + 1u))) {
            zk++;
        }
        pkg->zshift_max = zk;
    }
    pkg->reduce_mul = (((uint64_t)1 << 32) + r - 1u) / r;
    pkg->sectors = n;
    pkg->coarse_x = (pkg->cells_x + r - 1u) / r;
    pkg->coarse_y = (pkg->cells_y + r - 1u) / r;
    pkg->levels = 0u;
    pkg->planes = n == 1u ? 1u : n + 1u;
    pkg->flags = 0u;
    pkg->slices = 0u;
    pkg->epsg = epsg;
    pkg->heights = NULL;
    pkg->apex = NULL;
    pkg->angles = NULL;
    pkg->voids = NULL;
    /* bound: CT_MAX_LEVELS levels */
    for (k = 0u; k < CT_MAX_LEVELS; ++k) {
        pkg->mip[k] = NULL;
        pkg->mip_w[k] = 0u;
        pkg->mip_h[k] = 0u;
    }
    /* bound: N + 1 boundaries */
    for (k = 0u; k <= CT_MAX_SECTORS; ++k) {
        if (k <= n) {
            ct_dir_of_fraction(k, n, &pkg->bound_x[k], &pkg->bound_y[k]);
        } else {
            pkg->bound_x[k] = 0;
            pkg->bound_y[k] = 0;
        }
    }
    return ct_cot_table(pe, pkg->height_scale_nm, pkg->cot_q16, pkg->cot_ok);
}

ct_status ct_package_open(ct_package *pkg, const uint8_t *b, size_t len)
{
    uint32_t total, w, h, r, n, lv, flags, k;
    uint32_t so[CT_SEC_COUNT], ss[CT_SEC_COUNT], lv_expect, total_expect;
    uint64_t prev_end = CT_PKG_HEADER_SIZE;
    ct_status st;

    CT_ASSERT(pkg != NULL && b != NULL);
    if (pkg == NULL || b == NULL) {
        return CT_ERR_ARG;
    }
    st = ct_check_stamped(b, len, CT_PKG_MAGIC, CT_PKG_VERSION, CT_PKG_HEADER_SIZE, &total);
    if (st != CT_OK) {
        return st;
    }
    w = ct_ld16(b + CT_HDR_WIDTH);
    h = ct_ld16(b + CT_HDR_HEIGHT);
    r = b[CT_HDR_REDUCE];
    n = b[CT_HDR_SECTORS];
    lv = b[CT_HDR_LEVELS];
    flags = b[CT_HDR_FLAGS];
    if (w < 2u || h < 2u || w > CT_MAX_POSTS || h > CT_MAX_POSTS) {
        return CT_ERR_DIMS;
    }
    if (n < 1u || n > CT_MAX_SECTORS) {
        return CT_ERR_SECTORS;
    }
    if (r < 1u || r > CT_MAX_REDUCE) {
        return CT_ERR_REDUCE;
    }
    if ((flags & ~(CT_PKG_FLAG_VOIDS | CT_PKG_FLAG_DATUM)) != 0u) {
        return CT_ERR_FLAGS;
    }
    st = ct_package_layout(w, h, r, n, flags & CT_PKG_FLAG_VOIDS, so, ss,
                           &lv_expect, &total_expect);
    if (st != CT_OK) {
        return st;
    }
    if (lv != lv_expect) {
        return CT_ERR_LEVELS;
    }
    /* Section table: sizes must be exactly the implied ones; offsets
     * aligned, after the header, in order, and inside the package.        */
    {
        /* bound: CT_SEC_COUNT sections */
        for (k = 0u; k < CT_SEC_COUNT; ++k) {
            uint32_t off = ct_ld32(b + CT_HDR_SECTION_TABLE + 8u * k);
            uint32_t sz = ct_ld32(b + CT_HDR_SECTION_TABLE + 8u * k + 4u);
            if (sz != ss[k]) {
                return CT_ERR_SIZE;
            }
            if ((off % CT_PKG_ALIGN) != 0u || (uint64_t)off < prev_end ||
                (uint64_t)off + sz > (uint64_t)total) {
                return CT_ERR_OFFSET;
            }
            so[k] = off;
            prev_end = (uint64_t)off + sz;
        }
    }
    st = open_datum(pkg, b, total, prev_end, (flags & CT_PKG_FLAG_DATUM) != 0u);
    if (st != CT_OK) {
        return st;
    }
    {
        int64_t g[6];
        g[0] = ct_ld64s(b + CT_HDR_ORIGIN_E);
        g[1] = ct_ld64s(b + CT_HDR_ORIGIN_N);
        g[2] = ct_ld64s(b + CT_HDR_POSTING_E);
        g[3] = ct_ld64s(b + CT_HDR_POSTING_N);
        g[4] = ct_ld64s(b + CT_HDR_HEIGHT_OFFSET);
        g[5] = ct_ld64s(b + CT_HDR_HEIGHT_SCALE);
        st = ct_package_frame(pkg, w, h, r, n, (int32_t)ct_ld16(b + CT_HDR_HMIN), (int32_t)ct_ld16(b + CT_HDR_HMAX), g,
                              ct_ld32(b + CT_HDR_EPSG));
        if (st != CT_OK) {
            return st;
        }
    }
    pkg->base = b;
    pkg->size = total;
    pkg->levels = lv;
    pkg->flags = flags;
    pkg->slices = ct_ld32(b + CT_HDR_SLICES);
    pkg->heights = b + so[CT_SEC_HEIGHTS];
    pkg->apex = b + so[CT_SEC_APEX];
    pkg->angles = b + so[CT_SEC_ANGLES];
    pkg->voids = (flags & CT_PKG_FLAG_VOIDS) ? b + so[CT_SEC_VOIDS] : NULL;
    {
        uint32_t mw = pkg->cells_x, mh = pkg->cells_y, off = so[CT_SEC_MIPMAP];
        pkg->mip[0] = NULL;
        pkg->mip_w[0] = mw;
        pkg->mip_h[0] = mh;
        /* bound: lv < CT_MAX_LEVELS */
        for (k = 1u; k < CT_MAX_LEVELS; ++k) {
            if (k <= lv) {
                mw = (mw + 1u) / 2u;
                mh = (mh + 1u) / 2u;
                pkg->mip[k] = b + off;
                pkg->mip_w[k] = mw;
                pkg->mip_h[k] = mh;
                off += mw * mh * 2u;
            } else {
                pkg->mip[k] = NULL;
                pkg->mip_w[k] = 0u;
                pkg->mip_h[k] = 0u;
            }
        }
    }
    return CT_OK;
}

static uint32_t cell_max(const ct_package *p, uint32_t i, uint32_t j)
{
    const uint8_t *r0 = p->heights + 2u * ((size_t)j * p->width + i);
    const uint8_t *r1 = r0 + 2u * p->width;
    uint32_t a = ct_ld16(r0), b2 = ct_ld16(r0 + 2), c = ct_ld16(r1), d = ct_ld16(r1 + 2);
    uint32_t m = a > b2 ? a : b2;
    m = m > c ? m : c;
    return m > d ? m : d;
}

ct_status ct_package_verify(const ct_package *p)
{
    uint32_t i, j, l, lo = 0xffffu, hi = 0u;
    CT_ASSERT(p != NULL);
    if (p == NULL || p->base == NULL) {
        return CT_ERR_ARG;
    }
    /* bound: W*H samples */
    for (j = 0u; j < p->height; ++j) {
        for (i = 0u; i < p->width; ++i) {
            uint32_t v = ct_ld16(p->heights + 2u * ((size_t)j * p->width + i));
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    }
    if ((int32_t)lo != p->hmin || (int32_t)hi != p->hmax) {
        return CT_ERR_VERIFY;
    }
    /* bound: levels x cells of each level */
    for (l = 1u; l <= p->levels; ++l) {
        for (j = 0u; j < p->mip_h[l]; ++j) {
            for (i = 0u; i < p->mip_w[l]; ++i) {
                uint32_t m = 0u, di, dj;
                for (dj = 0u; dj < 2u; ++dj) {
                    for (di = 0u; di < 2u; ++di) {
                        uint32_t ci = 2u * i + di, cj = 2u * j + dj, v;
                        if (ci >= p->mip_w[l - 1u] || cj >= p->mip_h[l - 1u]) {
                            continue;
                        }
                        v = (l == 1u) ? cell_max(p, ci, cj)
                                      : ct_ld16(p->mip[l - 1u] + 2u * ((size_t)cj * p->mip_w[l - 1u] + ci));
                        m = v > m ? v : m;
                    }
                }
                if (ct_ld16(p->mip[l] + 2u * ((size_t)j * p->mip_w[l] + i)) != m) {
                    return CT_ERR_VERIFY;
                }
            }
        }
    }
    /* bound: coarse cells x r^2 */
    for (j = 0u; j < p->coarse_y; ++j) {
        for (i = 0u; i < p->coarse_x; ++i) {
            uint32_t a = ct_ld16(p->apex + 2u * ((size_t)j * p->coarse_x + i)), m = 0u, fi, fj;
            for (fj = j * p->reduce; fj < (j + 1u) * p->reduce && fj < p->cells_y; ++fj) {
                for (fi = i * p->reduce; fi < (i + 1u) * p->reduce && fi < p->cells_x; ++fi) {
                    uint32_t v = cell_max(p, fi, fj);
                    m = v > m ? v : m;
                }
            }
            if (a < m) {
                return CT_ERR_VERIFY;
            }
        }
    }
    return CT_OK;
}

ct_status ct_status_name(ct_status s, const char **out)
{
    static const char *const names[] = {
        "ok", "hit", "miss", "below", "hit_void", "no_data"};
    static const char *const errs[] = {
        "err_arg", "err_truncated", "err_magic", "err_version", "err_header",
        "err_crc", "err_dims", "err_sectors", "err_reduce", "err_levels",
        "err_size", "err_offset", "err_range", "err_georef", "err_flags",
        "err_ray", "err_method", "err_internal", "err_verify",
        /* camera and geolocation */
        "err_lens", "err_unproject", "err_pose", "err_effects",
        /* geodesy */
        "err_crs"};
    CT_ASSERT(out != NULL);
    if (out == NULL) {
        return CT_ERR_ARG;
    }
    if (s >= 0 && s <= CT_NO_DATA) {
        *out = names[s];
        return CT_OK;
    }
    if (s < 0 && s >= CT_ERR_CRS) {
        *out = errs[-s - 1];
        return CT_OK;
    }
    *out = "unknown";
    return CT_ERR_ARG;
}
