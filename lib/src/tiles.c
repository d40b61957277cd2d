/*
 * tiles.c -- tile sets: a ray traced over many packages as over one.
 *
 * The set's frame (a header-only ct_package of the merged grid) is what the
 * ray is prepared against, so the prepared ray -- origin, direction,
 * zshift, tend -- is the merged package's.  The walk then visits the tiles
 * the ray crosses in order (a grid walk over tiles, with the cells' tie
 * rules), and in each tile runs the method's own walk from the parameter
 * where the ray crosses onto it (trace.c, ct_trace_tile) on the prepared
 * ray shifted by the tile's offset (whole cells: x, y - 2^16 * offset, so
 * every product the walk forms is the merged walk's, bounds included).
 * The cell tests decide the hit exactly from the posts of the cell and
 * the prepared ray, and a tile's posts are the merged DEM's, so the hit is
 * the merged package's bit for bit.  A tile's cones, built from that tile
 * alone, only promise empty space inside its box: a cone step that leaves
 * the box ends the tile's walk (CT_MISS) and the next tile's walk starts
 * at the seam, never where the step landed.
 *
 * Numbers: tile offsets are at most CT_MAX_POSTS cells (the merged grid
 * is a package grid: W, H <= CT_MAX_POSTS), so every coordinate is the
 * merged walk's less a multiple of 2^16 below 2^31 -- the same ranges
 * (trace.c's header) hold in the tile's grid.  Seam parameters are
 * rationals n / d with d = |dx| or |dy| <= 2^26 and n < 2^34, compared as
 * trace.c compares them (products < 2^60).
 */
#include "conetrace.h"
#include "fixed.h"
#include "tiles.h"

#define ONE16 INT64_C(65536)

/* a < b for seam parameters: n < 2^34, d <= 2^26 */
static int t_lt(int64_t an, int64_t ad, int64_t bn, int64_t bd) { return an * bd < bn * ad; }

ct_status ct_tileset_open(ct_tileset *ts, const uint8_t *b, size_t len, ct_tile_slot *slots, uint32_t nslots,
                          ct_tile_loader load, void *user)
{
    uint32_t total, tx, ty, P, w, h, r, n, k, ntiles;
    int32_t hmin, hmax;
    int64_t g[6];
    ct_status st;
    CT_ASSERT(ts != NULL && b != NULL && slots != NULL && load != NULL);
    if (ts == NULL || b == NULL || slots == NULL || load == NULL || nslots == 0u || nslots > CT_SET_MAX_SLOTS) {
        return CT_ERR_ARG;
    }
    ts->ready = 0u; /* until every check has passed */
    st = ct_check_stamped(b, len, CT_SET_MAGIC, CT_SET_VERSION, CT_SET_HEADER_SIZE, &total);
    if (st != CT_OK) {
        return st;
    }
    tx = ct_ld16(b + CT_SET_HDR_TILES_X);
    ty = ct_ld16(b + CT_SET_HDR_TILES_Y);
    P = ct_ld16(b + CT_SET_HDR_TILE_POSTS);
    w = ct_ld16(b + CT_SET_HDR_WIDTH);
    h = ct_ld16(b + CT_SET_HDR_HEIGHT);
    r = b[CT_SET_HDR_REDUCE];
    n = b[CT_SET_HDR_SECTORS];
    /* the tile grid covers W x H exactly: (tiles - 1) (P - 1) < W - 1 <=
     * tiles (P - 1), so every tile has at least 2 posts per side */
    if (w < 2u || h < 2u || w > CT_MAX_POSTS || h > CT_MAX_POSTS || P < 2u || P > CT_MAX_POSTS || tx == 0u ||
        ty == 0u || tx * ty > CT_SET_MAX_TILES || (tx - 1u) * (P - 1u) >= w - 1u || tx * (P - 1u) < w - 1u ||
        (ty - 1u) * (P - 1u) >= h - 1u || ty * (P - 1u) < h - 1u) {
        return CT_ERR_DIMS;
    }
    ntiles = tx * ty;
    if ((uint64_t)total != (uint64_t)CT_SET_HEADER_SIZE + (uint64_t)ntiles * CT_SET_ENTRY_SIZE) {
        return CT_ERR_SIZE;
    }
    if (n < 1u || n > CT_MAX_SECTORS) {
        return CT_ERR_SECTORS;
    }
    if (r < 1u || r > CT_MAX_REDUCE) {
        return CT_ERR_REDUCE;
    }
    if (ct_ld32(b + CT_SET_HDR_FLAGS) != 0u || ct_ld16(b + CT_SET_HDR_VDATUM) >= CT_VDATUM_COUNT) {
        return CT_ERR_FLAGS;
    }
    hmin = (int32_t)ct_ld16(b + CT_SET_HDR_HMIN);
    hmax = (int32_t)ct_ld16(b + CT_SET_HDR_HMAX);
    /* bound: ntiles <= CT_SET_MAX_TILES entries */
    for (k = 0u; k < ntiles; ++k) {
        const uint8_t *e = b + CT_SET_HEADER_SIZE + (size_t)k * CT_SET_ENTRY_SIZE;
        if (e[12] > 1u) {
            return CT_ERR_FLAGS;
        }
        if (e[12] == 1u && ((int32_t)ct_ld16(e + 8) > (int32_t)ct_ld16(e + 10) || (int32_t)ct_ld16(e + 8) < hmin ||
                            (int32_t)ct_ld16(e + 10) > hmax)) {
            return CT_ERR_RANGE;
        }
    }
    /* bound: six georeference values */
    for (k = 0u; k < 6u; ++k) {
        g[k] = ct_ld64s(b + CT_SET_HDR_GEOREF + 8u * k);
    }
    st = ct_package_frame(&ts->frame, w, h, r, n, hmin, hmax, g, ct_ld32(b + CT_SET_HDR_EPSG));
    if (st != CT_OK) {
        return st;
    }
    ts->frame.vdatum = ct_ld16(b + CT_SET_HDR_VDATUM);
    ts->frame.source_epsg = 0u;
    ts->frame.geoid.w = ts->frame.geoid.h = 0u;
    ts->frame.geoid.lat0_q61 = ts->frame.geoid.lon0_q61 = ts->frame.geoid.step_q61 = 0;
    ts->frame.geoid.values = NULL;
    /* a tile's map coordinates are the frame's plus its offset times the
     * posting: the corner's stays within the package range (2^61 nm) */
    if (ct_abs64(g[0]) + (int64_t)w * ct_abs64(g[2]) > (INT64_C(1) << 61) ||
        ct_abs64(g[1]) + (int64_t)h * ct_abs64(g[3]) > (INT64_C(1) << 61)) {
        return CT_ERR_GEOREF;
    }
    ts->tiles_x = tx;
    ts->tiles_y = ty;
    ts->tile_posts = P;
    ts->tile_recip = P == 2u ? 0u : (uint32_t)((UINT64_C(1) << 32) / (P - 1u) + 1u); /* <= 2^31 + 1 */
    ts->entries = b + CT_SET_HEADER_SIZE;
    ts->slots = slots;
    ts->nslots = nslots;
    ts->load = load;
    ts->user = user;
    ts->clock = 0u;
    ts->loads = 0u;
    ts->refused = 0u;
    /* bound: CT_SET_MAX_SLOTS */
    for (k = 0u; k < CT_SET_MAX_SLOTS; ++k) {
        ts->held[k] = -1;
        ts->used[k] = 0u;
    }
    /* bound: CT_SET_HINTS */
    for (k = 0u; k < CT_SET_HINTS; ++k) {
        ts->hint[k] = 0u;
    }
    ts->ready = CT_SET_READY;
    return CT_OK;
}

/* First post of tile col (or row) a, and its posts: min(P, W - first). */
static uint32_t tile_first(const ct_tileset *ts, uint32_t a) { return a * (ts->tile_posts - 1u); }

static uint32_t tile_posts_at(const ct_tileset *ts, uint32_t a, uint32_t total)
{
    uint32_t f = tile_first(ts, a);
    return total - f < ts->tile_posts ? total - f : ts->tile_posts;
}

/* Does the opened package pk have exactly tile (a, b)'s place and values? */
static int tile_matches(const ct_tileset *ts, const ct_package *pk, const uint8_t *e, uint32_t a, uint32_t bb)
{
    const ct_package *F = &ts->frame;
    int64_t x0 = (int64_t)tile_first(ts, a), y0 = (int64_t)tile_first(ts, bb);
    return pk->size == ct_ld32(e) && ct_ld32(pk->base + CT_HDR_CRC) == ct_ld32(e + 4) &&
           pk->hmin == (int32_t)ct_ld16(e + 8) && pk->hmax == (int32_t)ct_ld16(e + 10) &&
           pk->width == tile_posts_at(ts, a, F->width) && pk->height == tile_posts_at(ts, bb, F->height) &&
           pk->reduce == F->reduce && pk->sectors == F->sectors && pk->posting_e_nm == F->posting_e_nm &&
           pk->posting_n_nm == F->posting_n_nm && pk->height_offset_nm == F->height_offset_nm &&
           pk->height_scale_nm == F->height_scale_nm && pk->epsg == F->epsg &&
           pk->origin_e_nm == F->origin_e_nm + x0 * F->posting_e_nm &&
           pk->origin_n_nm == F->origin_n_nm + y0 * F->posting_n_nm;
}

/* Tile (a, b) in a slot, loading it into the least recently used one if
 * needed; NULL when the set has no such tile or it cannot be loaded. */
static const ct_package *tile_get(ct_tileset *ts, uint32_t a, uint32_t bb)
{
    uint32_t k = bb * ts->tiles_x + a, s, victim = 0u;
    const uint8_t *e = ts->entries + (size_t)k * CT_SET_ENTRY_SIZE;
    const uint8_t *bytes = NULL;
    size_t len = 0u;
    ct_tile_slot *sl;
    if (e[12] == 0u) {
        return NULL;
    }
    ts->clock++;
    s = ts->hint[k % CT_SET_HINTS];
    if (ts->held[s] == (int16_t)k) {
        /* where the tile was found last: the usual case (s < nslots: a
         * hint only names a slot that held a tile) */
        ts->used[s] = ts->clock;
        return &ts->slots[s].pkg;
    }
    /* bound: nslots <= CT_SET_MAX_SLOTS */
    for (s = 0u; s < ts->nslots; ++s) {
        if (ts->held[s] == (int16_t)k) {
            ts->used[s] = ts->clock;
            ts->hint[k % CT_SET_HINTS] = (uint8_t)s;
            return &ts->slots[s].pkg;
        }
    }
    /* not held: the first empty slot, else the least recently used.
     * bound: nslots */
    for (s = 1u; s < ts->nslots && ts->held[victim] >= 0; ++s) {
        if (ts->held[s] < 0 || ts->used[s] < ts->used[victim]) {
            victim = s;
        }
    }
    sl = &ts->slots[victim];
    ts->held[victim] = -1;
    if (ts->load(ts->user, a, bb, sl->buf, sl->cap, &bytes, &len) != CT_OK || bytes == NULL ||
        ct_package_open(&sl->pkg, bytes, len) != CT_OK || !tile_matches(ts, &sl->pkg, e, a, bb)) {
        ts->refused++;
        return NULL;
    }
    ts->held[victim] = (int16_t)k;
    ts->used[victim] = ts->clock;
    ts->hint[k % CT_SET_HINTS] = (uint8_t)victim;
    ts->loads++;
    return &sl->pkg;
}

/* The tile column (or row) holding frame cell i (0 <= i < cells). */
static uint32_t tile_of(const ct_tileset *ts, int32_t i, uint32_t ntiles)
{
    /* i / d without a division: d = P - 1 in [2, 2^15), m = tile_recip =
     * (2^32 + e) / d with 0 < e <= d; for i = a d + b (b < d), i m / 2^32
     * = a + b / d + i e / (d 2^32), and b / d <= 1 - 1 / d while the last
     * term is < 1 / d (i e <= i d < 2^30): the floor is a.  d = 1: i. */
    uint32_t a = ts->tile_posts == 2u ? (uint32_t)i : (uint32_t)(((uint64_t)(uint32_t)i * ts->tile_recip) >> 32);
    return a < ntiles ? a : ntiles - 1u;
}

/* CT_NO_DATA: where the ray entered tile (a, b), at t = tn / td. */
static ct_status no_data(const ct_tileset *ts, const ct_prepared *r, const ct_lower *lw, uint32_t a, uint32_t bb,
                         int64_t tn, int64_t td, ct_hit *h)
{
    int64_t tq = td == (INT64_C(1) << CT_T_FRAC_BITS) ? tn : ct_floor_div(tn * (INT64_C(1) << CT_T_FRAC_BITS), td);
    int64_t x0 = (int64_t)tile_first(ts, a), y0 = (int64_t)tile_first(ts, bb);
    int64_t x1 = x0 + (int64_t)tile_posts_at(ts, a, ts->frame.width) - 2;
    int64_t y1 = y0 + (int64_t)tile_posts_at(ts, bb, ts->frame.height) - 2;
    ct_fill_point(&ts->frame, r, lw, tq, h);
    h->cell_x = (int32_t)ct_min64(ct_max64(ct_floor_div(h->x_q16, ONE16), x0), x1);
    h->cell_y = (int32_t)ct_min64(ct_max64(ct_floor_div(h->y_q16, ONE16), y0), y1);
    return CT_NO_DATA;
}

/* The lowered model (lw) moved into tile grid coordinates: the frame's
 * grid shifted by (ox, oy) Q16. */
static void lower_shifted(const ct_lower *lw, int64_t ox, int64_t oy, ct_lower *ll)
{
    *ll = *lw;
    ll->obx -= ox;
    ll->oby -= oy;
}

/* Where a set's trace starts: the prepared ray's first point decided
 * against tile (a, bb) -- loaded unless the point is above its tallest post
 * (the manifest says) -- and (i, j) moved into the tile's grid.  *tp: the
 * tile when it was loaded (else NULL).  Returns prep_finish's status, or
 * CT_NO_DATA (*h filled) when the tile is not available. */
static ct_status set_start(ct_tileset *ts, const ct_ray *ray, int seg, const ct_lower *lw, uint32_t a, uint32_t bb,
                           int32_t ci, int32_t cj, ct_prepared *r, const ct_package **tp, int32_t *i, int32_t *j,
                           int64_t tend[2], ct_hit *h)
{
    const ct_package *F = &ts->frame;
    const uint8_t *e0 = ts->entries + (size_t)(bb * ts->tiles_x + a) * CT_SET_ENTRY_SIZE;
    int64_t ox = (int64_t)tile_first(ts, a) * ONE16, oy = (int64_t)tile_first(ts, bb) * ONE16;
    ct_lower ll;
    ct_status st;
    *tp = NULL;
    /* |oz 2^zs| <= 2^46 */
    if (e0[12] != 0u && r->oz * (INT64_C(1) << r->zshift) > (int64_t)ct_ld16(e0 + 10) * ONE16) {
        st = ct_tile_prep_finish(F, NULL, 0, 0, ci, cj, ray, seg, lw, r);
    } else {
        *tp = tile_get(ts, a, bb);
        if (*tp == NULL) {
            r->tend_n = 0;
            r->tend_d = 1;
            r->start = CT_OK;
            if (tend != NULL) { /* in the box, stopped at its first point */
                tend[0] = 0;
                tend[1] = 1;
            }
            return no_data(ts, r, lw, a, bb, 0, 1, h);
        }
        if (lw != NULL) {
            lower_shifted(lw, ox, oy, &ll);
        }
        st = ct_tile_prep_finish(F, *tp, ox, oy, ci, cj, ray, seg, lw != NULL ? &ll : NULL, r);
    }
    *i -= (int32_t)(ox >> 16);
    *j -= (int32_t)(oy >> 16);
    return st;
}

/* Where the ray leaves tile (a, bb) (as trace.c's cell exit): the face (1
 * x, 2 y, 3 a corner) and the parameter en / ed; a vertical ray stays in
 * its tile (tend). */
static int tile_exit(const ct_tileset *ts, const ct_prepared *r, uint32_t a, uint32_t bb, int64_t *en, int64_t *ed)
{
    const ct_package *F = &ts->frame;
    int32_t sx = r->dx > 0 ? 1 : (r->dx < 0 ? -1 : 0), sy = r->dy > 0 ? 1 : (r->dy < 0 ? -1 : 0);
    int64_t adx = ct_abs64(r->dx), ady = ct_abs64(r->dy);
    int64_t x0 = (int64_t)tile_first(ts, a), y0 = (int64_t)tile_first(ts, bb);
    int64_t x1 = x0 + (int64_t)tile_posts_at(ts, a, F->width) - 1;
    int64_t y1 = y0 + (int64_t)tile_posts_at(ts, bb, F->height) - 1;
    int64_t nx = 0, ny = 0;
    int face;
    if (sx != 0) {
        nx = ((sx > 0 ? x1 : x0) * ONE16 - r->ox) * sx;
    }
    if (sy != 0) {
        ny = ((sy > 0 ? y1 : y0) * ONE16 - r->oy) * sy;
    }
    if (sy == 0) {
        face = 1;
    } else if (sx == 0) {
        face = 2;
    } else {
        int64_t lx = nx * ady, ly = ny * adx;
        face = lx < ly ? 1 : (ly < lx ? 2 : 3);
    }
    *en = face == 2 ? ny : nx;
    *ed = face == 2 ? ady : adx;
    if (sx == 0 && sy == 0) {
        *en = r->tend_n;
        *ed = r->tend_d;
    }
    return face;
}

/* Whether the ray may meet tile entry e's terrain between tn / td and its
 * exit en / ed: its lowest point there (at the exit, or tend if earlier,
 * for a descending ray; else at the entry) at or below the tile's tallest
 * post, or the manifest does not say.  Lowered terrain is lower still.
 * z d = oz d + n dz < 2^61 (trace.c's exit_sign), hmax 2^16 d < 2^59. */
static int tile_may_hit(const uint8_t *e, const ct_prepared *r, int64_t tn, int64_t td, int64_t en, int64_t ed)
{
    int64_t ln = tn, ld = td;
    if (r->dz < 0) {
        ln = en;
        ld = ed;
        if (t_lt(r->tend_n, r->tend_d, ln, ld)) {
            ln = r->tend_n;
            ld = r->tend_d;
        }
    }
    return e[12] == 0u || r->oz * ld + ln * (int64_t)r->dz <= (int64_t)ct_ld16(e + 10) * (ONE16 >> r->zshift) * ld;
}

/* The walk over tile tp from tn / td (entry face(s) eface, cell (i, j) of
 * the tile's grid): the ray (and the observer) shifted into the tile's grid
 * in place and back -- no copies on the walk's stack -- and a hit moved
 * back into the frame's.  Its steps and iterations add to *h's. */
static ct_status walk_tile(const ct_package *tp, ct_prepared *r, int64_t x0, int64_t y0, int64_t tn, int64_t td,
                           int eface, int32_t i, int32_t j, const ct_lower *lw, ct_method m, ct_hit *h)
{
    const uint32_t steps = h->steps, iters = h->iters;
    ct_lower ll;
    ct_status st;
    r->ox -= x0 * ONE16;
    r->oy -= y0 * ONE16;
    if (lw != NULL) {
        lower_shifted(lw, x0 * ONE16, y0 * ONE16, &ll);
    }
    st = ct_trace_tile(tp, r, tn, td, eface, i, j, lw != NULL ? &ll : NULL, m, h);
    r->ox += x0 * ONE16;
    r->oy += y0 * ONE16;
    h->steps += steps;
    h->iters += iters;
    if (st == CT_HIT || st == CT_HIT_VOID) {
        /* the tile's map position is the frame's: its origin is the
         * frame's plus x0 postings exactly, so ct_grid_to_map rounded the
         * same product (less x0 2^16 posting) */
        h->x_q16 += x0 * ONE16;
        h->y_q16 += y0 * ONE16;
        h->cell_x += (int32_t)x0;
        h->cell_y += (int32_t)y0;
    }
    return st;
}

/* A ray's walk over the set: the prepared ray (frame's grid), the tile
 * (a, bb) it is in and where its walk there starts -- t = tn / td, entry
 * face(s) eface (0: the first point), cell (i, j) of the tile's grid --
 * the tile when already fetched, and skip: a run showed the ray's way
 * through that tile clear of its surface (no walk there). */
typedef struct {
    ct_prepared r;
    const ct_package *tp;
    int64_t tn, td;
    int32_t i, j, ci, cj;
    uint32_t a, bb;
    int eface, skip;
} set_walker;

/* The ray prepared against the frame (no heights read) and the tile its
 * first point is on: CT_OK, or the trace's status (an error, CT_MISS). */
static ct_status set_geom(ct_tileset *ts, const ct_ray *ray, int seg, ct_method m, set_walker *w)
{
    const ct_package *F = &ts->frame;
    ct_status st;
    if ((unsigned)m >= (unsigned)CT_METHOD_COUNT) {
        return CT_ERR_METHOD;
    }
    st = ct_tile_prep_geom(F, ray, seg, &w->r);
    if (st != CT_OK) {
        return st;
    }
    /* (i, j): the cell the walk starts in (in tile (a, bb)'s grid after
     * set_begin); (ci, cj): the cell the first point is on */
    ct_prepared_first_cell(F, &w->r, &w->i, &w->j);
    w->ci = ct_clamp_cell(w->i, F->cells_x);
    w->cj = ct_clamp_cell(w->j, F->cells_y);
    w->a = tile_of(ts, w->ci, ts->tiles_x);
    w->bb = tile_of(ts, w->cj, ts->tiles_y);
    w->tp = NULL;
    w->tn = 0;
    w->td = 1;
    w->eface = 0;
    w->skip = 0;
    return CT_OK;
}

/* The first point decided against its tile (set_start); seg, below_hit,
 * tend: set_trace's.  1 when the walk goes on (*st CT_OK, or CT_HIT at the
 * first point), else 0 with the trace's status in *st. */
static int set_begin(ct_tileset *ts, const ct_ray *ray, int seg, const ct_lower *lw, int below_hit, ct_hit *h,
                     int64_t tend[2], set_walker *w, ct_status *st)
{
    *st = set_start(ts, ray, seg, lw, w->a, w->bb, w->ci, w->cj, &w->r, &w->tp, &w->i, &w->j, tend, h);
    if (*st == CT_NO_DATA) {
        return 0;
    }
    if (*st == CT_BELOW && below_hit) {
        w->r.start = CT_HIT; /* tend stays 0: the hit is at the first point */
        *st = CT_HIT;
    }
    if (tend != NULL) {
        tend[0] = w->r.tend_n;
        tend[1] = w->r.tend_d;
    }
    return *st == CT_OK || *st == CT_HIT; /* else CT_BELOW */
}

/* The walk over the tiles the ray crosses, from w's. */
static ct_status set_walk(ct_tileset *ts, set_walker *w, const ct_lower *lw, ct_method m, ct_hit *h)
{
    const ct_package *F = &ts->frame;
    const ct_prepared *r = &w->r;
    int32_t sx = r->dx > 0 ? 1 : (r->dx < 0 ? -1 : 0), sy = r->dy > 0 ? 1 : (r->dy < 0 ? -1 : 0);
    uint32_t it;
    ct_status st;
    /* bound: a ray crosses at most tiles_x + tiles_y - 1 tiles */
    for (it = 0u; it < ts->tiles_x + ts->tiles_y; ++it) {
        const uint8_t *e = ts->entries + (size_t)(w->bb * ts->tiles_x + w->a) * CT_SET_ENTRY_SIZE;
        int64_t en, ed;
        const int face = tile_exit(ts, r, w->a, w->bb, &en, &ed);
        if (!w->skip && tile_may_hit(e, r, w->tn, w->td, en, ed)) {
            if (w->tp == NULL) {
                w->tp = tile_get(ts, w->a, w->bb);
                if (w->tp == NULL) {
                    return no_data(ts, r, lw, w->a, w->bb, w->tn, w->td, h);
                }
            }
            st = walk_tile(w->tp, &w->r, (int64_t)tile_first(ts, w->a), (int64_t)tile_first(ts, w->bb), w->tn, w->td,
                           w->eface, w->i, w->j, lw, m, h);
            if (st != CT_MISS) {
                return st;
            }
        }
        if (!t_lt(en, ed, r->tend_n, r->tend_d)) {
            return CT_MISS;
        }
        /* onto the next tile (through a corner: the diagonal one), in the
         * cell column (row) on its entry face */
        if (face & 1) {
            if ((sx < 0 && w->a == 0u) || (sx > 0 && w->a + 1u >= ts->tiles_x)) {
                return CT_MISS;
            }
            w->a = sx > 0 ? w->a + 1u : w->a - 1u;
            w->i = sx > 0 ? 0 : (int32_t)tile_posts_at(ts, w->a, F->width) - 2;
        }
        if (face & 2) {
            if ((sy < 0 && w->bb == 0u) || (sy > 0 && w->bb + 1u >= ts->tiles_y)) {
                return CT_MISS;
            }
            w->bb = sy > 0 ? w->bb + 1u : w->bb - 1u;
            w->j = sy > 0 ? 0 : (int32_t)tile_posts_at(ts, w->bb, F->height) - 2;
        }
        w->eface = face;
        w->skip = 0;
        w->tp = NULL;
        w->tn = en;
        w->td = ed;
    }
    return CT_ERR_INTERNAL;
}

/* The trace over the set; lw: the lowered model in the frame's grid
 * (NULL: straight); seg, below_hit: ct_tileset_trace_segment's; *tend:
 * the prepared ray's end (NULL: not wanted). */
static ct_status set_trace(ct_tileset *ts, const ct_ray *ray, int seg, const ct_lower *lw, int below_hit,
                           ct_method m, ct_hit *h, int64_t tend[2])
{
    set_walker w;
    ct_status st;
    ct_hit_clear(h);
    st = set_geom(ts, ray, seg, m, &w);
    if (st != CT_OK || !set_begin(ts, ray, seg, lw, below_hit, h, tend, &w, &st)) {
        return st;
    }
    return set_walk(ts, &w, lw, m, h);
}

/* A run on tile (a, bb), where every ray of w[] with go[k] starts: when
 * each one the run can take (start CT_OK, not vertical) may meet that
 * tile's terrain (so that its own walk would fetch the tile) and the tile
 * is at hand, the shared walk over it (ct_run_starts, the rays shifted
 * into its grid in place and back) sets where each one's walk there
 * starts, or that it has none there. */
CT_NOINLINE static void set_run(ct_tileset *ts, set_walker *w, const uint8_t *go, uint32_t n, const ct_lower *lw,
                                uint32_t a, uint32_t bb)
{
    const uint8_t *e = ts->entries + (size_t)(bb * ts->tiles_x + a) * CT_SET_ENTRY_SIZE;
    const int64_t x0 = (int64_t)tile_first(ts, a) * ONE16, y0 = (int64_t)tile_first(ts, bb) * ONE16;
    const ct_prepared *rp[CT_RUN_MAX] = {NULL};
    ct_run_start rs[CT_RUN_MAX];
    uint32_t idx[CT_RUN_MAX];
    const ct_package *tp;
    ct_lower ll;
    uint32_t k, cnt = 0u, used = 0u;
    /* bound: n <= CT_RUN_MAX rays */
    for (k = 0u; k < n; ++k) {
        const ct_prepared *r = &w[k].r;
        if (!go[k]) {
            continue;
        }
        if (r->start == CT_OK && (r->dx != 0 || r->dy != 0)) {
            int64_t en, ed;
            (void)tile_exit(ts, r, a, bb, &en, &ed);
            if (!tile_may_hit(e, r, 0, 1, en, ed)) {
                return;
            }
            used++;
        }
        rp[cnt] = r;
        idx[cnt++] = k;
    }
    tp = used >= 2u ? tile_get(ts, a, bb) : NULL;
    if (tp == NULL) {
        return; /* each ray's own walk reports a tile it cannot have */
    }
    if (lw != NULL) {
        lower_shifted(lw, x0, y0, &ll);
    }
    /* bound: cnt <= CT_RUN_MAX rays */
    for (k = 0u; k < cnt; ++k) {
        w[idx[k]].r.ox -= x0;
        w[idx[k]].r.oy -= y0;
    }
    (void)ct_run_starts(tp, rp, cnt, lw != NULL ? &ll : NULL, rs);
    /* bound: cnt <= CT_RUN_MAX rays */
    for (k = 0u; k < cnt; ++k) {
        set_walker *v = &w[idx[k]];
        v->r.ox += x0;
        v->r.oy += y0;
        if (rs[k].how == CT_RUN_CLEAR) {
            v->skip = 1;
        } else if (rs[k].how == CT_RUN_FACE) {
            v->tn = rs[k].t0_n;
            v->td = rs[k].t0_d;
            v->eface = (int)rs[k].face;
            v->i = v->j = rs[k].cell;
        }
    }
}

ct_status ct_tileset_trace_run(ct_tileset *ts, const ct_ray *rays, uint32_t n, const ct_lower *lw, ct_method m,
                               ct_hit *const *h, ct_status *st)
{
    set_walker w[CT_RUN_MAX];
    uint8_t go[CT_RUN_MAX] = {0u};
    uint32_t k, cnt = 0u, a = 0u, bb = 0u;
    int one = 1; /* every ray starts on one tile */
    if (ts == NULL || rays == NULL || h == NULL || st == NULL || n > CT_RUN_MAX || ts->ready != CT_SET_READY) {
        return CT_ERR_ARG;
    }
    /* bound: n <= CT_RUN_MAX rays */
    for (k = 0u; k < n; ++k) {
        ct_hit_clear(h[k]);
        st[k] = set_geom(ts, &rays[k], 0, m, &w[k]);
        go[k] = (uint8_t)(st[k] == CT_OK);
        if (go[k] && cnt++ == 0u) {
            a = w[k].a;
            bb = w[k].bb;
        } else if (go[k] && (w[k].a != a || w[k].bb != bb)) {
            one = 0;
        }
    }
    if (cnt >= 2u && one) {
        /* the first points decided on that tile (which only it may
         * load), then one shared walk over it */
        /* bound: n rays */
        for (k = 0u; k < n; ++k) {
            go[k] = (uint8_t)(go[k] && set_begin(ts, &rays[k], 0, lw, 0, h[k], NULL, &w[k], &st[k]));
        }
        set_run(ts, w, go, n, lw, a, bb);
        /* bound: n rays */
        for (k = 0u; k < n; ++k) {
            if (go[k]) {
                w[k].tp = NULL; /* another ray's walk may have moved it */
                st[k] = set_walk(ts, &w[k], lw, m, h[k]);
            }
        }
        return CT_OK;
    }
    /* bound: n rays */
    for (k = 0u; k < n; ++k) {
        if (go[k] && set_begin(ts, &rays[k], 0, lw, 0, h[k], NULL, &w[k], &st[k])) {
            st[k] = set_walk(ts, &w[k], lw, m, h[k]);
        }
    }
    return CT_OK;
}

ct_status ct_tileset_trace(ct_tileset *ts, const ct_ray *ray, ct_method m, ct_hit *h)
{
    CT_ASSERT(ts != NULL && ray != NULL && h != NULL);
    if (ts == NULL || ray == NULL || h == NULL || ts->ready != CT_SET_READY) {
        return CT_ERR_ARG;
    }
    return set_trace(ts, ray, 0, NULL, 0, m, h, NULL);
}

ct_status ct_tileset_trace_lowered(ct_tileset *ts, const ct_ray *ray, const ct_lower *lw, ct_method m, ct_hit *h)
{
    return set_trace(ts, ray, 0, lw, 0, m, h, NULL);
}

ct_status ct_tileset_trace_segment(ct_tileset *ts, const ct_ray *ray, const ct_lower *lw, int below_hit, ct_method m,
                                   ct_hit *h, int64_t *tend_n, int64_t *tend_d)
{
    int64_t te[2] = {0, 0}; /* d 0: the segment never entered the box */
    ct_status st = set_trace(ts, ray, 1, lw, below_hit, m, h, te);
    *tend_n = te[0];
    *tend_d = te[1];
    return st;
}
