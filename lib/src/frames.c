/*
 * frames.c -- the map frame and the grid frame (conetrace.h, "Frames"):
 * map points (nm) to grid points (Q16 cells and height LSB) and back, a
 * map-frame ray as a grid-frame ct_ray, and the grid direction of a map
 * direction (shared with geolocation).  Exact integer scalings with one
 * rounding each; the ranges are argued beside each function.
 */
#include "bend.h"
#include "conetrace.h"
#include "fixed.h"

/* round(num / den) for den > 0, checking the quotient fits in |q| < 2^62. */
static ct_status round_div(ct_i128 num, int64_t den, int64_t *q)
{
    ct_i128 lim = ct_i128_mul(INT64_C(1) << 62, den);
    if (ct_i128_cmp(num, lim) >= 0 || ct_i128_cmp(num, ct_i128_neg(lim)) <= 0) {
        return CT_ERR_RANGE;
    }
    /* den <= 2^51 and |num| < 2^113: ct_i128_round_div's ranges */
    *q = ct_i128_round_div(num, den);
    return CT_OK;
}

/* round(v / 2^16) for a 128-bit v, checking |result| < 2^62. */
static ct_status round_shr16(ct_i128 v, int64_t *q)
{
    ct_i128 r = ct_i128_add(v, ct_i128_from64(32768));
    int64_t hi = (int64_t)r.hi;
    /* r >> 16 fits in 62 bits iff the top 66 bits of r are all equal */
    if (hi >= (INT64_C(1) << 13) || hi < -(INT64_C(1) << 13)) {
        return CT_ERR_RANGE;
    }
    *q = (int64_t)((r.hi << 48) | (r.lo >> 16));
    return CT_OK;
}

ct_status ct_grid_to_map(const ct_package *p, int64_t x, int64_t y, int64_t z,
                         int64_t *e, int64_t *n, int64_t *hh)
{
    int64_t de, dn, dh;
    CT_ASSERT(p != NULL && e != NULL && n != NULL && hh != NULL);
    if (p == NULL || e == NULL || n == NULL || hh == NULL) {
        return CT_ERR_ARG;
    }
    if (ct_abs64(x) > (INT64_C(1) << 60) || ct_abs64(y) > (INT64_C(1) << 60) ||
        ct_abs64(z) > (INT64_C(1) << 60)) {
        return CT_ERR_RANGE;
    }
    /* (x + 2^15) * posting / 2^16 rounded: < 2^61 * 2^50, 128-bit */
    if (round_shr16(ct_i128_mul(x + 32768, p->posting_e_nm), &de) != CT_OK ||
        round_shr16(ct_i128_mul(y + 32768, p->posting_n_nm), &dn) != CT_OK ||
        round_shr16(ct_i128_mul(z, p->height_scale_nm), &dh) != CT_OK) {
        return CT_ERR_RANGE;
    }
    /* |origin| <= 2^61 and |delta| < 2^62: sums fit */
    *e = p->origin_e_nm + de;
    *n = p->origin_n_nm + dn;
    *hh = p->height_offset_nm + dh;
    return CT_OK;
}

ct_status ct_map_to_grid(const ct_package *p, int64_t e, int64_t n, int64_t hh,
                         int64_t *x, int64_t *y, int64_t *z)
{
    ct_status st;
    int64_t pe, pn;
    ct_i128 ne, nn;
    CT_ASSERT(p != NULL && x != NULL && y != NULL && z != NULL);
    if (p == NULL || x == NULL || y == NULL || z == NULL) {
        return CT_ERR_ARG;
    }
    if (ct_abs64(e) > (INT64_C(1) << 61) || ct_abs64(n) > (INT64_C(1) << 61) ||
        ct_abs64(hh) > (INT64_C(1) << 61)) {
        return CT_ERR_RANGE;
    }
    /* x = (e - e0) * 2^16 / pe - 2^15: |e - e0| < 2^62, * 2^16: 128-bit */
    ne = ct_i128_shl(ct_i128_from64(e - p->origin_e_nm), 16);
    nn = ct_i128_shl(ct_i128_from64(n - p->origin_n_nm), 16);
    pe = p->posting_e_nm;
    pn = p->posting_n_nm;
    if (pe < 0) {
        ne = ct_i128_neg(ne);
        pe = -pe;
    }
    if (pn < 0) {
        nn = ct_i128_neg(nn);
        pn = -pn;
    }
    st = round_div(ct_i128_sub(ne, ct_i128_mul(32768, pe)), pe, x);
    if (st != CT_OK) {
        return st;
    }
    st = round_div(ct_i128_sub(nn, ct_i128_mul(32768, pn)), pn, y);
    if (st != CT_OK) {
        return st;
    }
    return round_div(ct_i128_shl(ct_i128_from64(hh - p->height_offset_nm), 16), p->height_scale_nm, z);
}

/* The grid direction of a map direction (|.| <= 2^40), shared by
 * ct_ray_from_map and geolocation (geoloc.c): (de, dn, dh) scaled by
 * (scale sgn(pe), scale sgn(pn), |pe|) -- proportional to (de/pe, dn/pn,
 * dh/scale), < 2^40 * 2^50 in 128 bits -- then divided by the least 2^s
 * (s <= 60) that brings every component to |.| <= 2^62, rounded half away
 * from zero. */
void ct_grid_dir_from_map(const ct_package *p, int64_t de, int64_t dn, int64_t dh, int64_t d[3])
{
    ct_i128 v[3];
    ct_i128 top = ct_i128_from64(0);
    unsigned s = 0u, len;
    int k;
    v[0] = ct_i128_mul(de, p->posting_e_nm < 0 ? -p->height_scale_nm : p->height_scale_nm);
    v[1] = ct_i128_mul(dn, p->posting_n_nm < 0 ? -p->height_scale_nm : p->height_scale_nm);
    v[2] = ct_i128_mul(dh, ct_abs64(p->posting_e_nm));
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        ct_i128 a = ct_i128_abs(v[k]);
        if (ct_i128_cmp(a, top) > 0) {
            top = a;
        }
    }
    /* top < 2^len: s = len - 63 unless top exceeds 2^(62 + s), then one more */
    len = ct_i128_bits(top);
    if (len > 62u) {
        s = len > 63u ? len - 63u : 0u;
        if (ct_i128_cmp(top, ct_i128_shl(ct_i128_from64(INT64_C(1) << 62), s)) > 0) {
            s++;
        }
        s = s > 60u ? 60u : s;
    }
    for (k = 0; k < 3; ++k) { /* bound: 3 axes */
        if (s == 0u) {
            d[k] = ct_i128_to64(v[k]);
        } else {
            /* |v| + 2^(s-1) >= 0: floor division by 2^s is a shift */
            ct_i128 a = ct_i128_abs(v[k]);
            int64_t q = ct_i128_to64(ct_i128_sar(ct_i128_add(a, ct_i128_shl(ct_i128_from64(1), s - 1u)), s));
            d[k] = ct_i128_sign(v[k]) < 0 ? -q : q;
        }
    }
}

ct_status ct_ray_from_map(const ct_package *p, int64_t e, int64_t n, int64_t hh,
                          int64_t de, int64_t dn, int64_t dh, ct_ray *out)
{
    int64_t d[3];
    CT_ASSERT(p != NULL && out != NULL);
    if (p == NULL || out == NULL) {
        return CT_ERR_ARG;
    }
    if (ct_abs64(de) > (INT64_C(1) << 40) || ct_abs64(dn) > (INT64_C(1) << 40) ||
        ct_abs64(dh) > (INT64_C(1) << 40) || (de == 0 && dn == 0 && dh == 0)) {
        return CT_ERR_RAY;
    }
    if (ct_map_to_grid(p, e, n, hh, &out->x_q16, &out->y_q16, &out->z_q16) != CT_OK) {
        return CT_ERR_RAY;
    }
    ct_grid_dir_from_map(p, de, dn, dh, d);
    out->dx = d[0];
    out->dy = d[1];
    out->dz = d[2];
    return CT_OK;
}
