/*
 * tiles.h -- what tiles.c needs from the tracer (private; trace.c and
 * prepare.c).
 *
 * A tile set traces a ray prepared against the whole set (a header-only
 * package, the "frame": the merged grid's extent, heights and
 * georeference) and walks it tile by tile, each tile's grid being the
 * frame's shifted by whole cells (offx, offy: Q16, multiples of 2^16).
 */
#ifndef CT_TILES_H
#define CT_TILES_H

#include "bend.h"
#include "conetrace.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ct_ray_prepare's (seg: ct_ray_prepare_segment's) clipping and
 * quantisation against frame's box (no heights read): CT_OK (out->start
 * not yet decided), CT_MISS / CT_BELOW, or an error.                      */
ct_status ct_tile_prep_geom(const ct_package *frame, const ct_ray *ray, int seg, ct_prepared *out);

/* The cell of frame holding a prepared ray's first point, as the walk
 * locates it (-1 .. cells on an axis: clamp with ct_clamp_cell for the
 * cell the point is on). */
void ct_prepared_first_cell(const ct_package *frame, const ct_prepared *r, int32_t *i, int32_t *j);

/* i clamped to 0 .. cells - 1. */
static inline int32_t ct_clamp_cell(int32_t i, uint32_t cells)
{
    return i < 0 ? 0 : (i >= (int32_t)cells ? (int32_t)cells - 1 : i);
}

/* The rest of ct_ray_prepare: the first point -- in frame's cell (fi, fj),
 * from ct_prepared_first_cell -- decided against tile (whose grid is
 * frame's shifted by offx, offy; lw, if any, in tile's grid), tend in
 * frame's box.  tile NULL: the caller knows the first point is above every
 * post of its tile (start CT_OK, nothing read).  Returns out->start.      */
ct_status ct_tile_prep_finish(const ct_package *frame, const ct_package *tile, int64_t offx, int64_t offy, int32_t fi,
                              int32_t fj, const ct_ray *ray, int seg, const ct_lower *lw, ct_prepared *out);

/* The walk of r (a frame-prepared ray shifted into tile's grid) in tile
 * from t0 = t0_n / t0_d: 0 for the first tile (as ct_trace_prepared; face
 * 0, (i0, j0) the first point's cell in tile's grid, unclamped), else the
 * parameter where the ray crosses onto the tile (d <= 2^26) through its
 * entry face(s): face bit 1 the x face (i0 its column), bit 2 the y face
 * (j0 its row); the other axis is located.  CT_MISS when it leaves the
 * tile (or, by a cone, shows the rest of the ray in the tile is above its
 * surface) without a hit.                                                  */
ct_status ct_trace_tile(const ct_package *tile, const ct_prepared *r, int64_t t0_n, int64_t t0_d, int face,
                        int32_t i0, int32_t j0, const ct_lower *lw, ct_method method, ct_hit *hit);

/* hit's position at t_q26 on r (x, y, z Q16 and map nm in p's frame; for a
 * bent ray, on the curve); hit->cell_x, cell_y are kept.                   */
void ct_fill_point(const ct_package *p, const ct_prepared *r, const ct_lower *lw, int64_t t_q26, ct_hit *hit);

/* ct_tileset_trace for the lowered model (lw in the frame's grid, its
 * observer the ray's origin): geoloc.c.                                   */
ct_status ct_tileset_trace_lowered(ct_tileset *ts, const ct_ray *ray, const ct_lower *lw, ct_method method,
                                   ct_hit *hit);

/* A segment over the set (origin to origin + direction, as
 * ct_prepare_lowered_segment + ct_trace_prepared_lowered on one package;
 * lw NULL: the terrain itself).  below_hit: a first point below the surface
 * is a hit there (a later piece of a path whose previous piece ended above
 * it; one package's caller sets pr.start = CT_HIT).  *tend_n / *tend_d: the
 * prepared segment's end (a hit beyond it is the caller's to discard);
 * *tend_d 0 when the segment never enters the set's box (CT_MISS, as
 * ct_ray_prepare_segment's).                                               */
ct_status ct_tileset_trace_segment(ct_tileset *ts, const ct_ray *ray, const ct_lower *lw, int below_hit,
                                   ct_method method, ct_hit *hit, int64_t *tend_n, int64_t *tend_d);

/* ct_trace_run over a tile set (geoloc.c's batch): n <= CT_RUN_MAX rays
 * from one observer (lw: the lowered model in the frame's grid, or NULL:
 * straight), each one's status in st[k] and hit in *h[k] as
 * ct_tileset_trace's (_lowered's) but for steps and iters (its own
 * walks).  When every ray starts on one tile, that tile's walks start
 * where the run's shared walk over it (ct_run_starts) leaves them; the
 * later tiles are walked ray by ray.  CT_ERR_ARG for a NULL argument, a
 * set not ready or n > CT_RUN_MAX, else CT_OK.                            */
ct_status ct_tileset_trace_run(ct_tileset *ts, const ct_ray *rays, uint32_t n, const ct_lower *lw, ct_method method,
                               ct_hit *const *h, ct_status *st);
/* ct_trace_bent_set over a tile set (p: its frame; ts NULL: one package). */
ct_status ct_trace_bent_set_ts(const ct_package *p, ct_tileset *ts, const ct_ray *ray, const ct_bent_setup *bs,
                               ct_method method, ct_hit *hit);

/* The first hit of the line of sight of a unit map-frame direction (grid
 * east, grid north, up at the camera; Q39, without the pose's horizontal
 * scale), over a tile set (p: its frame) or, ts NULL, on one package p.
 * hit.steps / iters add up over the pieces.                               */
ct_status ct_trace_earth_set(const ct_package *p, ct_tileset *ts, const ct_earth *es, const int64_t dir_grid_q39[3],
                             ct_method method, ct_hit *hit);

/* A result with nothing in it: steps, iters, t 0, positions 0, cell -1. */
void ct_hit_clear(ct_hit *hit);

/* The checks every stamped file of the format shares (a package, a
 * manifest): length, magic, version, header size, total size (<= len,
 * into *total), CRC-32 over the whole with its field zero.  CT_OK or
 * CT_ERR_TRUNCATED / _MAGIC / _VERSION / _HEADER / _CRC (package.c). */
ct_status ct_check_stamped(const uint8_t *bytes, size_t len, const char *magic, uint32_t version,
                           uint32_t header_size, uint32_t *total);

/* Fill the derived fields of a package view from header values (package.c;
 * ct_package_open's second half): sections NULL, levels 0.  CT_OK or the
 * georeference's error.                                                    */
ct_status ct_package_frame(ct_package *pkg, uint32_t width, uint32_t height, uint32_t reduce, uint32_t sectors,
                           int32_t hmin, int32_t hmax, const int64_t georef_nm[6], uint32_t epsg);

#ifdef __cplusplus
}
#endif

#endif /* CT_TILES_H */
