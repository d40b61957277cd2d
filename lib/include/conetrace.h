/*
 * conetrace.h -- the one public header of the conetrace flight library.
 *
 * Exact first hit of a ray on the bilinear surface of a terrain package
 * (a DEM plus a directional parameter plane transform, Paglieroni 1997).
 * C99, freestanding, integer-only, no heap, no recursion, every loop bounded.
 *
 * Frames and units (see docs/library.md, "Frames and fixed-point formats"):
 *   grid frame   x = column, y = row, in fine cells; post (i, j) sits at
 *                (x, y) = (i, j); z is in height LSB (package code units).
 *   map frame    the DEM's projected CRS in nanometres (int64): E east,
 *                N north, h up.  Post (i, j) is at
 *                E = origin_e + (i + 1/2) * posting_e,
 *                N = origin_n + (j + 1/2) * posting_n  (GDAL convention),
 *                h = height_offset + code * height_scale.
 *
 * Fixed-point formats (Q notation: Qm.n has n fractional bits):
 *   ct_q16    int64 with 16 fractional bits.  Grid positions x, y (cells)
 *             and z (LSB).  Inside a tile |x|,|y| < 2^15 cells and
 *             z in [-2^16, 2^16] LSB, so values stay below 2^33; ray
 *             origins may lie outside the tile up to CT_MAX_ORIGIN_Q16.
 *   t (Q26)   the parameter of a *prepared* ray; position = o + t * d with
 *             d normalised so that max(|dx|,|dy|,|dz|) is in
 *             [2^25, 2^26].  Inside a tile t < 2^8, so t_q26 < 2^34.
 * Overflow arguments for every product are written beside the code that
 * forms it (lib/src/trace.c, lib/src/fixed.h).
 *
 * Status codes: every public function returns ct_status.  Negative values
 * are errors (bad data or bad arguments); non-negative values are results.
 * Programmer misuse (NULL pointers) also trips CT_ASSERT, which a build may
 * override (define CT_ASSERT before including, or at compile time).
 */
#ifndef CONETRACE_H
#define CONETRACE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------ */
/* Status codes                                                              */

typedef int32_t ct_status;

enum {
    /* results (>= 0) */
    CT_OK = 0,
    CT_HIT = 1,       /* first intersection found (hit fields valid)          */
    CT_MISS = 2,      /* the ray leaves the tile (or never enters it)         */
    CT_BELOW = 3,     /* the ray's first point in the tile is below the surface */
    CT_HIT_VOID = 4,  /* first hit lies in a void (nodata) cell: position is on
                         the filled floor, not on measured terrain             */

    /* errors (< 0) */
    CT_ERR_ARG = -1,        /* NULL pointer, bad enum, zero-length buffer       */
    CT_ERR_TRUNCATED = -2,  /* buffer shorter than the header or total size     */
    CT_ERR_MAGIC = -3,      /* not a conetrace package                          */
    CT_ERR_VERSION = -4,    /* unsupported format version                       */
    CT_ERR_HEADER = -5,     /* header size field wrong                          */
    CT_ERR_CRC = -6,        /* CRC-32 mismatch                                  */
    CT_ERR_DIMS = -7,       /* width/height outside [2, CT_MAX_POSTS]           */
    CT_ERR_SECTORS = -8,    /* sector count outside [1, CT_MAX_SECTORS]         */
    CT_ERR_REDUCE = -9,     /* reduction factor outside [1, CT_MAX_REDUCE]      */
    CT_ERR_LEVELS = -10,    /* mipmap level count inconsistent with the size    */
    CT_ERR_SIZE = -11,      /* a section size differs from the one implied      */
    CT_ERR_OFFSET = -12,    /* a section lies outside the package, overlaps,
                               or is not 8-byte aligned                         */
    CT_ERR_RANGE = -13,     /* impossible value (hmin > hmax, codes outside)    */
    CT_ERR_GEOREF = -14,    /* zero/non-square posting, non-positive scale      */
    CT_ERR_FLAGS = -15,     /* unknown flag bits                                */
    CT_ERR_RAY = -16,       /* zero direction or origin beyond CT_MAX_ORIGIN_Q16 */
    CT_ERR_METHOD = -17,    /* unknown tracing method                           */
    CT_ERR_INTERNAL = -18,  /* a loop reached its bound: a library bug          */
    CT_ERR_VERIFY = -19     /* ct_package_verify: content breaks an invariant   */
};

/* ------------------------------------------------------------------------ */
/* Limits                                                                    */

#define CT_MAX_POSTS 32768        /* posts per side: x_q16 < 2^31            */
#define CT_MAX_SECTORS 64
#define CT_MAX_REDUCE 8
#define CT_MAX_LEVELS 16          /* mipmap levels 1..15 stored               */
#define CT_MAX_ORIGIN_Q16 ((int64_t)1 << 46) /* |origin| in q16, 2^30 cells   */
#define CT_DIR_BITS 26            /* prepared direction: max |d| in [2^25, 2^26] */
#define CT_ZSHIFT_MAX 16          /* prepared z unit: at most 2^16 Q16 units  */
#define CT_T_FRAC_BITS 26         /* t_q26                                    */

/* Worst-case loop iterations, published per method (docs/library.md,
 * "Methods"; the cone step: docs/builders.md): every INCREMENTAL, CONE
 * and DIRECTIONAL iteration leaves at least one fine cell, so iterations
 * <= cells_x + cells_y + 1; HIERARCHICAL needs at most (levels + 2)
 * iterations per fine cell left.  Exceeding a bound returns
 * CT_ERR_INTERNAL.                                                          */
#define CT_WCET_CELL_ITERS(cx, cy) ((uint32_t)(cx) + (uint32_t)(cy) + 2u)
#define CT_WCET_HIER_ITERS(cx, cy, levels) \
    (CT_WCET_CELL_ITERS(cx, cy) * ((uint32_t)(levels) + 2u))

/* ------------------------------------------------------------------------ */
/* Package format (little-endian; defined once here, written by host_tools) */

#define CT_PKG_MAGIC "CTPK"
#define CT_PKG_VERSION 1u
#define CT_PKG_HEADER_SIZE 128u
#define CT_PKG_ALIGN 8u
#define CT_PKG_FLAG_VOIDS 1u     /* a void (nodata) cell bitmap is present   */
#define CT_PKG_FLAG_DATUM 2u     /* a datum section is present (header word 84
                                    holds its offset)                        */

/* Section indices in the header's section table.                           */
enum {
    CT_SEC_HEIGHTS = 0, /* W*H uint16 codes, row-major (row 0 first)          */
    CT_SEC_MIPMAP = 1,  /* levels 1..L of max-mipmap, uint16, level by level  */
    CT_SEC_APEX = 2,    /* Wc*Hc uint16 apex codes of the coarse cells        */
    CT_SEC_ANGLES = 3,  /* P planes of Wc*Hc uint8 opening-angle codes;
                           P = N for N == 1, else N + 1 (plane N = omni cone) */
    CT_SEC_VOIDS = 4,   /* ceil(cx*cy/8) bytes, bit k = fine cell k is void   */
    CT_SEC_COUNT = 5
};

/* Header byte offsets.  All multi-byte fields little-endian.
 *   0  char[4] magic "CTPK"          4  u16 version        6  u16 header size
 *   8  u32 total size (bytes)       12  u32 CRC-32 (IEEE, over the whole
 *                                       package with these 4 bytes zero)
 *  16  u16 width W (posts)          18  u16 height H (posts)
 *  20  u8  reduce r                 21  u8  sectors N
 *  22  u8  mipmap levels L          23  u8  flags
 *  24  u16 hmin code                26  u16 hmax code
 *  28  u32 slices K (informational, 0 = exact apexes)
 *  32  i64 origin_e_nm              40  i64 origin_n_nm   (GDAL top-left corner)
 *  48  i64 posting_e_nm             56  i64 posting_n_nm  (|e| == |n|)
 *  64  i64 height_offset_nm         72  i64 height_scale_nm (> 0, per LSB)
 *  80  u32 EPSG code (0 = unknown)  84  u32 datum section offset (flag
 *                                       CT_PKG_FLAG_DATUM; else 0)
 *  88  5 x { u32 offset, u32 size } section table (bytes from package start)
 */
#define CT_HDR_MAGIC 0u
#define CT_HDR_VERSION 4u
#define CT_HDR_HEADER_SIZE 6u
#define CT_HDR_TOTAL 8u
#define CT_HDR_CRC 12u
#define CT_HDR_WIDTH 16u
#define CT_HDR_HEIGHT 18u
#define CT_HDR_REDUCE 20u
#define CT_HDR_SECTORS 21u
#define CT_HDR_LEVELS 22u
#define CT_HDR_FLAGS 23u
#define CT_HDR_HMIN 24u
#define CT_HDR_HMAX 26u
#define CT_HDR_SLICES 28u
#define CT_HDR_ORIGIN_E 32u
#define CT_HDR_ORIGIN_N 40u
#define CT_HDR_POSTING_E 48u
#define CT_HDR_POSTING_N 56u
#define CT_HDR_HEIGHT_OFFSET 64u
#define CT_HDR_HEIGHT_SCALE 72u
#define CT_HDR_EPSG 80u
#define CT_HDR_DATUM 84u
#define CT_HDR_SECTION_TABLE 88u

/* The datum section (optional; flag CT_PKG_FLAG_DATUM): where the heights
 * and the grid came from, and the geoid over the tile.  8-aligned, after
 * the other sections, inside the package (so under the CRC):
 *   0  u16 source vertical datum (CT_VDATUM_*)   2  u16 geoid nodes per row gw
 *   4  u16 geoid rows gh                         6  u16 reserved (0)
 *   8  u32 source EPSG: the CRS the DEM was resampled from (0 = not resampled)
 *  12  u32 reserved (0)
 *  16  i64 lat0_q61  24  i64 lon0_q61   geoid node (0, 0), WGS84, Q61 radians
 *  32  i64 step_q61  node (i, j) lies at (lat0 - j step, lon0 + i step)
 *  40  gw * gh i32   geoid undulation N at the nodes, micrometres, row-major,
 *                    row 0 north (h_ellipsoid = h_geoid + N)
 * The nodes are the geoid model's own (EGM96: every 15'), so bilinear
 * interpolation between them is the model's interpolation (PROJ's).
 * gw = gh = 0: no geoid grid.  Otherwise 2 <= gw, gh <= CT_GEOID_MAX_NODES,
 * step in [CT_GEOID_MIN_STEP_Q61, CT_GEOID_MAX_STEP_Q61], (max(gw, gh) - 1)
 * step <= 2^62, |lat0| <= pi / 2 and |lon0| <= pi.
 * When the source vertical datum is known (not CT_VDATUM_UNKNOWN) the
 * package's heights are ellipsoidal (WGS84): the builder converted them.  */
#define CT_DATUM_HEADER_SIZE 40u
#define CT_GEOID_MAX_NODES 4096u
#define CT_GEOID_MIN_STEP_Q61 (INT64_C(1) << 40)  /* 2^-21 rad: 3 m          */
#define CT_GEOID_MAX_STEP_Q61 (INT64_C(1) << 58)  /* 1/8 rad: 7.2 deg        */
enum {
    CT_VDATUM_UNKNOWN = 0, /* heights in the DEM's own, unstated datum       */
    CT_VDATUM_WGS84 = 1,   /* the DEM's heights were ellipsoidal (WGS84)     */
    CT_VDATUM_EGM96 = 2,   /* the DEM's heights were above the EGM96 geoid;
                              the builder added N (PROJ's egm96_15 grid)     */
    CT_VDATUM_COUNT = 3
};

/* Sector convention: sector s covers the closed wedge of horizontal grid
 * directions between boundary vectors b_s and b_{s+1}, b_k at grid azimuth
 * 360 deg * k / N measured from +x (column, east) towards +y (row, south);
 * on a north-up map that is clockwise from east.  b_k are integer vectors
 * (|b| ~ 2^30) from ct_sector_boundary(); axes and diagonals are exact.
 * The builder and the tracer use the very same integer wedge test.          */

/* Opening angle codes: omega = code * 180 deg / 256 from the upward vertical,
 * measured in the metric frame (height in metres vs distance in metres).
 * Code 0 means "no cone" (degenerate).  The tracer uses
 * cot_q16[code] = ceil(cot(omega) * posting / height_scale * 2^16), LSB per
 * cell in Q16, rounded towards +infinity so the promised empty region only
 * ever shrinks; |cot_q16| is limited to CT_COT_MAX_Q16 (larger positive
 * values are treated as degenerate, larger negative ones clamped).          */
#define CT_COT_MAX_Q16 ((int64_t)1 << 35)

/* ------------------------------------------------------------------------ */
/* Types                                                                     */

typedef enum {
    CT_METHOD_INCREMENTAL = 0, /* exact grid walk (Musgrave)                 */
    CT_METHOD_HIERARCHICAL = 1,/* max-mipmap                                 */
    CT_METHOD_CONE = 2,        /* one omnidirectional cone per coarse cell   */
    CT_METHOD_DIRECTIONAL = 3, /* N sector cones per coarse cell             */
    CT_METHOD_COUNT = 4
} ct_method;

/* A geoid-undulation grid on geodetic nodes: bilinear between them
 * (ct_geoid_at).  A view of little-endian bytes, as in a package's datum
 * section.                                                                 */
typedef struct {
    uint32_t w, h;           /* nodes per row, rows; 0 = no grid             */
    int64_t lat0_q61;        /* node (0, 0): the north-west node, Q61 rad    */
    int64_t lon0_q61;
    int64_t step_q61;        /* node spacing in latitude and longitude       */
    const uint8_t *values;   /* w * h int32 LE, micrometres, row 0 north     */
} ct_geoid_grid;

/* An opened package: a zero-copy view of caller bytes plus derived tables.
 * Transparent so it can live in static memory; fill it with ct_package_open.
 * About 2.6 KB.                                                             */
typedef struct {
    const uint8_t *base;    /* the package bytes (not copied)                 */
    uint32_t size;          /* total size in bytes                            */
    uint32_t width, height; /* posts                                          */
    uint32_t cells_x, cells_y;   /* fine cells = posts - 1                     */
    uint32_t reduce, sectors;    /* r, N                                       */
    uint32_t zshift_max;         /* largest k <= 16 with 2^k * height_scale <=
                                    min |posting|: the coarsest z unit
                                    (2^k Q16 LSB) a prepared ray may use,
                                    still no coarser than a Q16 cell unit  */
    uint64_t reduce_mul;         /* ceil(2^32 / r): i / r = (i * it) >> 32 for
                                    i < 2^16 (error i * (1/r)' < 2^-16 < 1/r) */
    uint32_t coarse_x, coarse_y; /* ceil(cells / r)                            */
    uint32_t levels;             /* stored mipmap levels (1..L)                */
    uint32_t planes;             /* angle planes (N or N + 1)                  */
    uint32_t flags;
    uint32_t slices;
    uint32_t epsg;
    int32_t hmin, hmax;          /* height code range                          */
    int64_t origin_e_nm, origin_n_nm, posting_e_nm, posting_n_nm;
    int64_t height_offset_nm, height_scale_nm;
    const uint8_t *heights;      /* section pointers into base                 */
    const uint8_t *mip[CT_MAX_LEVELS]; /* mip[l] for l = 1..levels             */
    uint32_t mip_w[CT_MAX_LEVELS], mip_h[CT_MAX_LEVELS];
    const uint8_t *apex;
    const uint8_t *angles;
    const uint8_t *voids;        /* NULL when no voids                         */
    int32_t bound_x[CT_MAX_SECTORS + 1]; /* sector boundary vectors            */
    int32_t bound_y[CT_MAX_SECTORS + 1];
    int64_t cot_q16[256];        /* per angle code; see CT_COT_MAX_Q16         */
    uint8_t cot_ok[256];         /* 0: code is degenerate for this package     */
    uint32_t vdatum;             /* source vertical datum, CT_VDATUM_*; when not
                                    UNKNOWN the heights are WGS84 ellipsoidal */
    uint32_t source_epsg;        /* CRS the DEM was resampled from (0: none)   */
    ct_geoid_grid geoid;         /* geoid over the tile (w = 0: none)          */
} ct_package;

/* A ray as the caller gives it, grid frame.                                 */
typedef struct {
    int64_t x_q16, y_q16, z_q16; /* origin; |.| <= CT_MAX_ORIGIN_Q16           */
    int64_t dx, dy, dz;          /* direction in the same units (cells, cells,
                                    LSB), any common scale, not all zero,
                                    |.| <= 2^62                                */
} ct_ray;

/* A ray clipped to the tile and quantised: the object the tracer is exact
 * for.  Transparent so tests can trace the same ray independently.
 * Position(t) = o + t * d, t >= 0; o lies in the tile's box.
 * Per-axis scaling: x and y are Q16 cells, but z is counted in units of
 * 2^zshift Q16 LSB (z_q16 = oz * 2^zshift + t * dz * 2^zshift).  The grid
 * frame is anisotropic (a 30 m cell is 480 LSB of 1/16 m), so a steep ray
 * scaled as one vector would keep only ~16 bits in dx and dy; with z in
 * coarser units (never coarser than a Q16 cell unit in metres, see
 * ct_package.zshift_max) every component keeps ~26 bits and the prepared
 * ray stays within 1 mm of the caller's (docs/library.md, "Exactness").    */
typedef struct {
    int64_t ox, oy, oz;    /* origin (the entry point): x, y Q16; z in units
                              of 2^zshift Q16                                 */
    int32_t dx, dy, dz;    /* the same units per unit t; max |.| in
                              [2^25, 2^26] (preparation makes it 2^26 - 1
                              or 2^26)                                        */
    int32_t sector;        /* sector of (dx, dy); -1 for vertical rays        */
    int32_t zshift;        /* 0..CT_ZSHIFT_MAX; 0 for vertical rays           */
    int64_t len_lo, len_hi;/* floor/ceil of sqrt(dx^2 + dy^2)                 */
    int64_t tend_n, tend_d;/* t where the ray leaves the tile's box (> 0 den) */
    ct_status start;       /* CT_OK, or CT_MISS/CT_BELOW/CT_HIT decided at prep */
} ct_prepared;

/* Result of a trace.                                                        */
typedef struct {
    int64_t x_q16, y_q16, z_q16; /* hit, grid frame (valid for CT_HIT*)        */
    int64_t e_nm, n_nm, h_nm;    /* hit, map frame (valid for CT_HIT*)         */
    int64_t t_q26;               /* parameter of the prepared ray at the hit   */
    int32_t cell_x, cell_y;      /* fine cell holding the hit                  */
    uint32_t steps;              /* advances (cells, blocks or cones)           */
    uint32_t iters;              /* loop iterations (<= the WCET bound)         */
} ct_hit;

/* ------------------------------------------------------------------------ */
/* Functions                                                                 */

/* Validate bytes[0..len) as a package and fill *pkg (zero copy: bytes must
 * outlive pkg).  Checks, in order: header, magic, version, header size,
 * total size, CRC, dimensions, sectors, reduction, levels, flags, ranges,
 * georeference, every section's offset, size and alignment.  A package that
 * opens can never make any function read outside bytes[0..total).
 *   [out] pkg    the opened package: a view of bytes plus derived tables
 *                (cot table, sector boundaries, section pointers).
 *   [in]  bytes  the package as built (little-endian, package-format.md).
 *   [in]  len    bytes available, >= the header's total size.
 * Returns CT_OK, or the status of the first check that fails: CT_ERR_ARG
 * for NULL, one of CT_ERR_TRUNCATED .. CT_ERR_FLAGS (-2 .. -15) else.
 * Scaling and overflow: sizes are 32-bit and every offset + size is summed
 * in 64 bits before it is compared with total; postings, offsets and scales
 * are checked against the ranges the conversions below rely on.            */
ct_status ct_package_open(ct_package *pkg, const uint8_t *bytes, size_t len);

/* Deep content check, O(cells): mipmap levels are the max of their children,
 * every apex is at least its coarse cell's tallest corner, hmin/hmax match
 * the samples.  The cones' opening angles are not checked (only the
 * builder's whole computation could confirm them): the CRC guards them, and
 * a package whose angle codes were altered with the CRC re-stamped may make
 * the cone methods pass terrain (never read out of bounds).
 *   [in]  pkg  a package ct_package_open accepted.
 * Returns CT_OK, CT_ERR_VERIFY (a mismatch), CT_ERR_ARG (NULL, or no bytes
 * behind pkg).
 * Scaling and overflow: heights and maxima are 16-bit codes compared as
 * uint32; indices are size_t products of dimensions <= CT_MAX_POSTS.      */
ct_status ct_package_verify(const ct_package *pkg);

/* Size in bytes of a package with these parameters (the builder's and a
 * loader's buffer size).
 *   [in]  width, height  posts, [2, CT_MAX_POSTS].
 *   [in]  reduce         r, [1, CT_MAX_REDUCE].
 *   [in]  sectors        N, [1, CT_MAX_SECTORS].
 *   [in]  with_voids     nonzero: the package carries a void mask.
 *   [out] out_size       the total size; 0 on any error.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_DIMS, CT_ERR_REDUCE, CT_ERR_SECTORS,
 * CT_ERR_SIZE (the total would not fit 32 bits).
 * Scaling and overflow: section sizes are summed in 64 bits, each start
 * aligned to 8 bytes, and the total compared with 2^32 - 1.               */
ct_status ct_package_size(uint32_t width, uint32_t height, uint32_t reduce,
                          uint32_t sectors, uint32_t with_voids,
                          uint32_t *out_size);

/* Section layout (offset, size in bytes) for a package with these
 * parameters; the writer and the reader share it (package-format.md).
 *   [in]  width .. with_voids  as ct_package_size.
 *   [out] sec_off, sec_size    per section CT_SEC_*: byte offset (a multiple
 *                              of 8) and size; an absent section has size 0.
 *   [out] levels               mipmap levels above the fine cells.
 *   [out] total                the package's size in bytes.
 * Errors and scaling: as ct_package_size.                                  */
ct_status ct_package_layout(uint32_t width, uint32_t height, uint32_t reduce,
                            uint32_t sectors, uint32_t with_voids,
                            uint32_t sec_off[CT_SEC_COUNT],
                            uint32_t sec_size[CT_SEC_COUNT],
                            uint32_t *levels, uint32_t *total);

/* CRC-32 (IEEE 802.3, reflected 0xEDB88320) of data[0..len), continuing
 * from crc: start with 0, pass the previous result to go on across pieces.
 *   [in]  crc      0, or the CRC of the bytes before data.
 *   [in]  data     len bytes (may be NULL when len is 0).
 *   [out] out_crc  the CRC of everything so far.
 * Errors: CT_ERR_ARG (out_crc NULL, or data NULL with len > 0).           */
ct_status ct_crc32(uint32_t crc, const uint8_t *data, size_t len,
                   uint32_t *out_crc);

/* Sector boundary vector k of N sectors: the direction k 360/N degrees
 * from +x (grid frame), as integers computed the same way on every platform
 * and shared by the builder and the tracer (b_0 = b_N = +x).
 *   [in]  sectors  N, [1, CT_MAX_SECTORS].
 *   [in]  k        0 .. N.
 *   [out] bx, by   the vector, |.| about 2^30 (an integer approximation of
 *                  2^30 (cos, sin): multiples of 45 degrees from
 *                  constants, the rest from a Q30 Taylor series).
 * Errors: CT_ERR_ARG (NULL), CT_ERR_SECTORS (N outside [1, CT_MAX_SECTORS]
 * or k > N).                                                               */
ct_status ct_sector_boundary(uint32_t sectors, uint32_t k, int32_t *bx,
                             int32_t *by);

/* Sector holding a grid direction: the s with angle(b_s) <= angle(d) <
 * angle(b_{s+1}) by an exact integer order, confirmed with the closed-wedge
 * test ct_in_wedge (the builder's test).
 *   [in]  pkg         an opened package (its N and boundaries).
 *   [in]  dx, dy      the direction, |.| <= 2^30, not both zero.
 *   [out] out_sector  s in [0, N); 0 when N = 1.
 * Errors: CT_ERR_ARG (NULL, a zero or too long direction), CT_ERR_INTERNAL
 * (the wedge test disagrees with the order: cannot happen).
 * Scaling and overflow: cross products of 2^30-bounded vectors, < 2^61.  */
ct_status ct_sector_of(const ct_package *pkg, int64_t dx, int64_t dy,
                       uint32_t *out_sector);

/* Whether a direction lies in the closed wedge of sector s of an explicit
 * boundary set (the builder's test; ct_sector_of confirms with it).
 *   [in]  bound_x, bound_y  N + 1 boundary vectors (ct_sector_boundary).
 *   [in]  sectors, s        N in [1, CT_MAX_SECTORS], s in [0, N).
 *   [in]  dx, dy            the direction, |.| <= 2^30.
 *   [out] out_inside        1 when b_s x d >= 0 and d x b_{s+1} >= 0 (both
 *                           boundaries included), else 0; 1 when N = 1.
 * Errors: CT_ERR_ARG (NULL, |dx| or |dy| beyond 2^30), CT_ERR_SECTORS.
 * Scaling and overflow: |b|, |d| <= 2^30: each cross product < 2^61.      */
ct_status ct_in_wedge(const int32_t *bound_x, const int32_t *bound_y,
                      uint32_t sectors, uint32_t s, int64_t dx, int64_t dy,
                      uint32_t *out_inside);

/* The cones' slopes in the grid frame: for each angle code (half-angle
 * omega = code 180/256 degrees from the upward vertical, in metres), the
 * cone's rise cot(omega) in height LSB per fine cell, Q16, rounded up (so
 * a cone is never wider than the builder's).
 *   [in]  posting_nm       the cell size, nm (its sign is ignored), <= 2^50.
 *   [in]  height_scale_nm  one height LSB, nm, (0, 2^46].
 *   [out] out_q16          per code, Q16 LSB per cell; capped at
 *                          +-CT_COT_MAX_Q16.
 *   [out] ok               per code, 0 where the cone is too narrow to step
 *                          with (code 0, or cot beyond the cap), else 1.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_GEOREF (posting or scale out of range).
 * Scaling and overflow: cot_q32 (< 2^39) times posting (<= 2^50) in 128
 * bits over scale 2^16 (<= 2^62), capped before the quotient is formed.   */
ct_status ct_cot_table(int64_t posting_nm, int64_t height_scale_nm,
                       int64_t out_q16[256], uint8_t ok[256]);

/* Clip and quantise a ray.  Returns CT_OK (traceable), CT_MISS (never enters
 * the tile), CT_BELOW / CT_HIT (decided at its first point), or an error.
 *   [in]  pkg  an opened package.
 *   [in]  ray  grid frame: origin Q16 (x, y cells; z height LSB), |.| <=
 *              CT_MAX_ORIGIN_Q16; direction in any common scale, |.| <=
 *              2^62, not all zero.
 *   [out] out  the prepared ray (ct_prepared: the object the tracer is exact
 *              for), filled for every non-error status.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_RAY (origin or direction out of range,
 * zero direction).
 * Scaling and overflow: the clip is done in 128-bit rationals (origin <
 * 2^47, direction < 2^63: products < 2^110); the direction is rounded to
 * int32 with its largest component in [2^25, 2^26] and z in units of
 * 2^zshift Q16, which keeps the prepared ray within 1 mm of the caller's on
 * a tile up to 2,048 cells across (docs/library.md, "Exactness").          */
ct_status ct_ray_prepare(const ct_package *pkg, const ct_ray *ray,
                         ct_prepared *out);

/* Trace a prepared ray.  Returns CT_HIT, CT_HIT_VOID, CT_MISS, CT_BELOW or an
 * error; *hit is filled for every non-error result (steps, iters).  A ray
 * that ct_ray_prepare could not have made is CT_ERR_RAY: direction scale,
 * zshift, sector, length, an origin outside the box (or, for start CT_OK,
 * at or below its floor hmin - 1), a tend beyond where it leaves the box.
 *   [in]  pkg     the package the ray was prepared for.
 *   [in]  ray     from ct_ray_prepare (or an equal one: it is re-validated).
 *   [in]  method  CT_METHOD_*; all four give bit-identical hits.
 *   [out] hit     the first hit: grid (Q16) and map (nm) position, t_q26,
 *                 cell, steps and iterations (<= CT_WCET_* for the method).
 * Errors: CT_ERR_ARG (NULL), CT_ERR_METHOD, CT_ERR_RAY (above),
 * CT_ERR_INTERNAL (a loop bound reached: a library bug).
 * Scaling and overflow: positions inside the box are < 2^31 Q16 (x, y) and
 * < 2^33 (z); t is a rational with denominator <= 2^26 and numerator < 2^34;
 * every product is bounded beside the code (trace.c), 64-bit except the
 * interior minimum's discriminant and the root (128-bit).                  */
ct_status ct_trace_prepared(const ct_package *pkg, const ct_prepared *ray,
                            ct_method method, ct_hit *hit);

/* ct_ray_prepare + ct_trace_prepared: [in] pkg, [in] ray (ct_ray_prepare's
 * ranges), [in] method, [out] hit.  The statuses of both (CT_MISS and
 * CT_BELOW decided at preparation come back with *hit's steps 0).          */
ct_status ct_trace(const ct_package *pkg, const ct_ray *ray, ct_method method,
                   ct_hit *hit);

/* Grid (Q16) to map (nm) and back, exact integer scaling, rounded to
 * nearest.  Map coordinates of the tile must stay within +-2^62 nm.
 *   grid frame: x = column, y = row (Q16 fine cells, post (i, j) at
 *   (i 2^16, j 2^16)); z = height code (Q16 LSB).  Map frame: E, N at the
 *   post's pixel centre (GDAL's pixel-is-area), h = offset + code * scale;
 *   all in nm.
 * ct_grid_to_map: [in] x_q16, y_q16, z_q16 (|.| <= 2^60), [out] e_nm, n_nm,
 * h_nm.  ct_map_to_grid: [in] e_nm, n_nm, h_nm (|.| <= 2^61), [out] x_q16,
 * y_q16, z_q16.  Errors: CT_ERR_ARG (NULL), CT_ERR_RANGE (an input beyond
 * its bound, or a result beyond 2^62).
 * Scaling and overflow: each axis is one 128-bit product or quotient
 * ((x + 2^15) posting / 2^16; (e - e0) 2^16 / posting - 2^15) rounded half
 * up, its result checked against 2^62 before it is stored.                 */
ct_status ct_grid_to_map(const ct_package *pkg, int64_t x_q16, int64_t y_q16,
                         int64_t z_q16, int64_t *e_nm, int64_t *n_nm,
                         int64_t *h_nm);
ct_status ct_map_to_grid(const ct_package *pkg, int64_t e_nm, int64_t n_nm,
                         int64_t h_nm, int64_t *x_q16, int64_t *y_q16,
                         int64_t *z_q16);

/* A map-frame ray (origin in nm, direction in any common unit with
 * |.| <= 2^40) as a grid-frame ct_ray.
 *   [in]  e_nm, n_nm, h_nm  origin, map frame, nm (|.| <= 2^61).
 *   [in]  de, dn, dh        direction, any common unit, |.| <= 2^40, not
 *                           all zero.
 *   [out] out               the grid ray: origin as ct_map_to_grid rounds
 *                           it; direction (de/posting_e, dn/posting_n,
 *                           dh/scale) times |posting_e| scale, divided by
 *                           the least power of two that brings it within
 *                           2^62 (rounded half away from zero).
 * Errors: CT_ERR_ARG (NULL), CT_ERR_RAY (direction out of range or zero,
 * an origin ct_map_to_grid refuses).
 * Scaling and overflow: direction products < 2^40 2^50 in 128 bits.        */
ct_status ct_ray_from_map(const ct_package *pkg, int64_t e_nm, int64_t n_nm,
                          int64_t h_nm, int64_t de, int64_t dn, int64_t dh,
                          ct_ray *out);

/* Height of the bilinear surface at a grid point inside the tile, Q16,
 * rounded up.
 *   [in]  x_q16, y_q16  grid point, 0 <= . <= cells 2^16.
 *   [out] z_q16         the surface's height code there, Q16 LSB.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_RANGE (off the tile).
 * Scaling and overflow: the patch times 2^32 is exact in 64 bits (< 2^50).  */
ct_status ct_surface_height(const ct_package *pkg, int64_t x_q16,
                            int64_t y_q16, int64_t *z_q16);

/* Like ct_ray_prepare, but the ray is the segment from its origin to
 * origin + direction (t <= 1 in the caller's parameter): the prepared ray's
 * tend is also at most the segment's end.  A walk may still report a hit in
 * the segment's last cell beyond tend; ct_trace_bent discards those.
 *   [in]  pkg, ray  as ct_ray_prepare (origin + direction must fit int64:
 *                   it does within the documented ranges).
 *   [out] out       the prepared segment.
 * Statuses, errors and scaling: as ct_ray_prepare; a segment inside the box
 * at both ends is not clipped.                                             */
ct_status ct_ray_prepare_segment(const ct_package *pkg, const ct_ray *ray,
                                 ct_prepared *out);

/* ------------------------------------------------------------------------ */
/* Bent rays: earth curvature and atmospheric refraction (lib/src/bend.c).   */

/* Model: over a projected-grid DEM, a ray from an observer gains height
 * above the datum of  c * rho^2 / (2 R)  at horizontal range rho from its
 * origin, c = (curvature ? 1 : 0) - (refraction ? k : 0), k the refraction
 * coefficient (~0.13), R the earth radius.
 * c > 0: the caller's (straight) ray is traced once against the terrain
 * with each post lowered by the rise at its range from the observer
 * (exact integers; inside a cell the bilinear patch of the lowered posts,
 * within c posting^2 / (4 R) of the exact rise: 0.035 mm for 30 m cells),
 * by the method's own walk, bound and exactness; the hit is reported on
 * the curve.  This needs every tile corner within 2^31 Q16 (2^15 cells) of
 * the observer on each axis and the rise over the tile below 2^16 LSB.
 * Otherwise (c < 0, or out of that range) the library traces the polyline
 * with vertices on the curve (rounded to Q16) every Delta of horizontal
 * range, Delta = min(sqrt(8 * chord * R / |c|), 2^50 nm), so the polyline stays within
 * chord_nm (+ 1 Q16 unit of vertex rounding) of the curve; each segment is
 * traced exactly (ct_ray_prepare_segment), so the result is the exact first
 * hit of the polyline.  The observer must be within 2^52 nm (4500 km)
 * horizontally of every point of the tile.                                 */
typedef struct {
    int32_t coeff_q16; /* c in Q16, |c| <= 4 * 2^16; 0 = straight ray       */
    int64_t radius_nm; /* R in nm, [2^40, 2^54] (1.1 km .. 18,000 km)        */
    int64_t chord_nm;  /* largest polyline deviation, [2^10, 2^50] nm       */
    uint32_t flags;    /* 0, or CT_BEND_NO_CULL                              */
} ct_bend;

/* The walks lower the mipmap's and cones' bounds by the rise ahead (the
 * lowered walk), the polyline skips runs of segments that the max-mipmap
 * shows to be above all terrain under them (bend.c, "culling"); that
 * changes no result, only the time.  CT_BEND_NO_CULL turns both off (for
 * tests that check it).                                                    */
#define CT_BEND_NO_CULL 1u

#define CT_BEND_MAX_SEGMENTS 65536u
/* Worst-case iterations of a bent trace: the method's straight bound for
 * the lowered walk; for the polyline, every segment's walk leaves a new
 * fine cell per iteration except at most twice per segment (its first and
 * last cell are shared with its neighbours).                               */
#define CT_WCET_BENT_ITERS(cx, cy, segments) \
    (CT_WCET_CELL_ITERS(cx, cy) + 2u * (uint32_t)(segments))

/* Trace ray (its origin is the observer) bent by *bend.  Returns as
 * ct_trace; hit->t_q26 is the parameter on the prepared straight ray (the
 * lowered walk) or on the segment holding the hit (the polyline), whose
 * steps and iters are summed over segments.
 *   [in]  pkg     an opened package.
 *   [in]  ray     the tangent at the observer, grid frame (ct_ray's ranges).
 *   [in]  bend    c (Q16), R and chord (nm), flags: the ranges above.
 *   [in]  method  CT_METHOD_*.
 *   [out] hit     as ct_trace's; its map position on the curve.
 * Errors: CT_ERR_ARG (NULL, a bend out of range), CT_ERR_METHOD, CT_ERR_RAY
 * (the ray's ranges), CT_ERR_RANGE (more than CT_BEND_MAX_SEGMENTS
 * segments, or the observer beyond 2^52 nm of the tile).
 * Scaling and overflow: the lowered terrain D = Q kf / 2^kshift with Q <
 * 2^63 and kf < 2^32 (128-bit, bend.h); the polyline's vertices in 128-bit
 * rationals, each segment prepared with ct_ray_prepare_segment's bounds.  */
ct_status ct_trace_bent(const ct_package *pkg, const ct_ray *ray,
                        const ct_bend *bend, ct_method method, ct_hit *hit);

/* A status's short name ("hit", "err_crc", ...), for logs and the CLI.
 *   [in]  s    any ct_status.
 *   [out] out  a static string; "unknown" for a value that is not one.
 * Errors: CT_ERR_ARG (out NULL, or s not a status: *out is then "unknown"). */
ct_status ct_status_name(ct_status s, const char **out);

/* ======================================================================== */
/* Camera and geolocation (lib/src/camera.c, lib/src/geoloc.c)              */
/*                                                                          */
/* pixel --lens--> unit ray in the camera frame --pose--> map-frame ray     */
/*       --ct_trace--> first hit (E, N, h in nm).                           */
/*                                                                          */
/* Conventions are mrcal's: camera frame x right, y down, z forward (the    */
/* optical axis); pixel (0, 0) is the centre of the top-left pixel; lens    */
/* parameters as mrcal orders them (fx, fy, cx, cy, then OpenCV's k1 k2 p1  */
/* p2 [k3 [k4 k5 k6]]).  A .cameramodel's extrinsics rt_cam_ref map         */
/* reference-frame (here: map-frame) points into the camera frame; the      */
/* library takes the inverse pose, R_map_cam and the camera centre in nm.   */
/* The conversion rt_cam_ref -> (R_map_cam, centre) runs on the host in     */
/* long double (host_tools/camera/camera_host.cpp,                          */
/* ct_host::pose_from_rt_cam_ref) and stored with ct_pose_init; a           */
/* navigation solution gives the pose through ct_pose_from_wgs84 or         */
/* ct_pose_from_map (below).                                                */
/*                                                                          */
/* Fixed-point formats:                                                     */
/*   pixel       u, v: int64 Q16 pixels, |u|, |v| <= CT_CAM_MAX_PIXEL px.   */
/*   focal       fx, fy: int64 Q32 pixels in [1, CT_CAM_MAX_PIXEL] px       */
/*               (Q32, not Q16: a Q16 focal length alone would turn 2^-17 px */
/*               of rounding into ~1e-8 rad at the image edge).             */
/*   centre      cx, cy: int64 Q32 pixels, |.| <= CT_CAM_MAX_PIXEL px.      */
/*   distortion  int64 Q48 (dist_q48[0..7] = k1 k2 p1 p2 k3 k4 k5 k6),      */
/*               |.| <= CT_CAM_MAX_DIST (2^10); unused entries must be 0.   */
/*               (Q48: at the edge of a wide lens, r^2 ~ 40, k3 r^6 turns a */
/*               Q32 coefficient's rounding into 2e-5 px.)                  */
/*   normalised  image-plane coordinates x = X/Z, y = Y/Z (internal): int64 */
/*               Q32 with x^2 + y^2 <= CT_CAM_MAX_R2 (64, i.e. <= 82.9 deg  */
/*               off axis).  Every polynomial value is then < 2^60.2 in Q32:*/
/*               |N|, |D| <= 1 + 2^10 (64 + 64^2 + 64^3) < 2^28.1; products */
/*               are formed 64 x 64 -> 128 bits and rounded back; Horner's */
/*               partial sums are kept in Q44 and Q38 (camera.c).           */
/*   ray_cam     int32 Q30 unit vector in the camera frame, z > 0           */
/*               (|component| <= 2^30; |ray| = 1 within 2^-29).             */
/*   R_map_cam   int32 Q30, row-major; column j is camera axis j in the map */
/*               frame (E, N, h).  Orthonormal within 2^-20, det +1.        */
/*   dir_map     int64 Q39 map-frame direction (|.| < 2^40), the ray handed */
/*               to the tracer (ct_ray_from_map's range).                   */
/*                                                                          */
/* Unprojection (OpenCV models): (x_d, y_d) = ((u - cx)/fx, (v - cy)/fy),   */
/* then Newton's method with the analytic Jacobian and step halving on      */
/* (x, y) |-> distort(x, y) = (x_d, y_d), at most CT_UNPROJECT_MAX_ITERS     */
/* iterations.  A pixel unprojects (CT_OK) only if the distorted point of   */
/* the solution is within CT_UNPROJECT_TOL_Q32 of (x_d, y_d) (max norm,     */
/* normalised units; 2^-26 = 1.5e-8, i.e. 1.5e-5 px at fx = 1000 px), the   */
/* solution lies inside the camera's valid field and the Jacobian's         */
/* determinant there is >= CT_UNPROJECT_MIN_DET.  The valid field is the    */
/* disc r <= r_max where, along every radius, the radial factor R = N/D     */
/* stays in [2^-8, 2^8] and the distorted radius r*R grows with slope       */
/* >= 2^-8 (ct_camera_init finds the first radius where that fails: the     */
/* lens "folds over" there).  Anything else is CT_ERR_UNPROJECT, never a    */
/* silently wrong ray.  PINHOLE needs no iteration.                         */
/* Measured (tests/test_camera.cpp): see docs/geolocation.md.               */

/* Status codes, continued (errors, < 0). */
enum {
    CT_ERR_LENS = -20,      /* bad lens parameters or model (ct_camera_init) */
    CT_ERR_UNPROJECT = -21, /* pixel does not unproject: no convergence,
                               outside the valid field, folded or extreme
                               distortion, or behind the camera           */
    CT_ERR_POSE = -22,      /* rotation not orthonormal with det +1, or the
                               camera centre out of range                 */
    CT_ERR_EFFECTS = -23,   /* unknown scene-effect flags or an effect
                               parameter out of range (ct_effects)        */
    CT_ERR_CRS = -24        /* a coordinate reference system the library
                               does not convert (only UTM north/south on
                               WGS84, EPSG 326xx / 327xx)                 */
};

typedef enum {
    CT_LENS_PINHOLE = 0, /* fx fy cx cy                                     */
    CT_LENS_OPENCV4 = 1, /* + k1 k2 p1 p2                                   */
    CT_LENS_OPENCV5 = 2, /* + k1 k2 p1 p2 k3                                */
    CT_LENS_OPENCV8 = 3, /* + k1 k2 p1 p2 k3 k4 k5 k6 (rational)            */
    CT_LENS_COUNT = 4,   /* parametric models above                         */
    CT_LENS_GRID = 16    /* unprojection grid (ct_camera_init_grid)         */
} ct_lens_model;

#define CT_CAM_MAX_PIXEL 1048576           /* 2^20 px                        */
#define CT_CAM_MAX_DIST (INT64_C(1) << 58) /* 2^10 in Q48                    */
#define CT_CAM_MAX_R2 64                   /* x^2 + y^2, normalised units    */
#define CT_UNPROJECT_MAX_ITERS 24u   /* Newton iterations (each with up to
                                        CT_UNPROJECT_MAX_HALVINGS halvings) */
#define CT_UNPROJECT_MAX_HALVINGS 24u
#define CT_UNPROJECT_TOL_Q32 64      /* 2^-26 normalised units            */
#define CT_UNPROJECT_MIN_DET (INT64_C(1) << 16) /* 2^-16 in Q32           */
#define CT_CAM_SCAN_STEPS 256u       /* valid-field scan samples (init)   */

/* Lens parameters as the caller gives them (see the formats above).        */
typedef struct {
    uint32_t model;            /* ct_lens_model                             */
    uint32_t width, height;    /* imager size in pixels (informational)     */
    int64_t fx_q32, fy_q32;    /* focal lengths, Q32 pixels                 */
    int64_t cx_q32, cy_q32;    /* principal point, Q32 pixels               */
    int64_t dist_q48[8];       /* k1 k2 p1 p2 k3 k4 k5 k6, Q48              */
} ct_lens;

/* Unprojection grid: any lens (e.g. mrcal's LENSMODEL_SPLINED_STEREOGRAPHIC)
 * baked on the host into unit rays at grid pixels
 *   (u, v) = (u0 + i * step, v0 + j * step),  i < nu, j < nv,
 * stored row-major (j outer) as int32 Q30 triples in caller memory (may be
 * const in flash; not copied).  A node without a ray is (0, 0, 0).  The
 * library interpolates with separable Catmull-Rom cubics over the 4 x 4
 * nodes around the pixel (exact for rays that vary cubically with the
 * pixel) and renormalises; the cell position is kept to 2^-20 of a step.
 * A pixel whose 4 x 4 nodes are not all inside the grid and valid, or
 * whose interpolated vector is shorter than half a unit or more than 60 deg
 * from any of those nodes (rays that disagree), is CT_ERR_UNPROJECT.  Rays
 * may point anywhere (fields of view beyond 180 deg).  Accuracy vs step:
 * docs/geolocation.md (1.3e-7 rad at a 16 px step on a 160 deg lens).     */
#define CT_GRID_MAX_NODES 16384u          /* per side                     */
typedef struct {
    uint32_t nu, nv;           /* nodes per row / column, 4..CT_GRID_MAX_NODES */
    int64_t u0_q16, v0_q16;    /* pixel of node (0, 0), Q16, |.| <= 2^20 px */
    int64_t step_q16;          /* node spacing, Q16 px, in [1, 4096] px      */
    const int32_t *rays_q30;   /* 3 * nu * nv int32: unit rays, Q30          */
    size_t rays_len;           /* int32 entries available (>= 3 nu nv)      */
} ct_unproject_grid;

/* A validated lens with its valid field.  Fill with ct_camera_init (or
 * ct_camera_init_grid).                                                    */
typedef struct {
    ct_lens lens;              /* lens.model == CT_LENS_GRID for a grid     */
    int64_t r2_max_q32;        /* valid field: x^2 + y^2 <= r2_max (Q32)     */
    ct_unproject_grid grid;    /* CT_LENS_GRID only                         */
    uint32_t ready;            /* set by ct_camera_init                      */
    uint32_t grid_smooth;      /* set by ct_camera_init_grid: every node a
                                  ray, neighbours within 5 deg (0 for a
                                  closed-form lens)                         */
} ct_camera;

/* Camera pose: centre in the map frame and R_map_cam.                      */
typedef struct {
    int64_t e_nm, n_nm, h_nm;  /* camera centre, map frame, nm              */
    int32_t R_map_cam_q30[9];  /* row-major, Q30                            */
    int32_t hscale_q30;        /* map metres per ground metre horizontally
                                  at the camera, Q30: 2^30 from
                                  ct_pose_init; k R / (R + h) from
                                  ct_pose_from_wgs84                        */
    uint32_t ready;            /* set by ct_pose_init                        */
} ct_pose;

/* Scene effects for ct_geolocate: earth curvature and atmospheric
 * refraction over a projected-grid DEM (whose "vertical" is the map
 * frame's h axis everywhere).  Model: the line of sight leaves the camera
 * along the pixel's ray and its height above the datum gains
 *     c * rho^2 / (2 R),   c = (CURVATURE ? 1 : 0) - (REFRACTION ? k : 0)
 * at horizontal range rho from the camera (the earth falls away below the
 * tangent plane by rho^2/2R; refraction bends the ray down along an arc of
 * radius R/k).  Both: (1 - k) rho^2 / 2R.  The ray is traced by
 * ct_trace_bent (for c > 0 one walk against the terrain lowered by the
 * rise, within c posting^2 / 4R of the parabola; otherwise a polyline
 * within chord_nm of it), so the tracer's exactness and its step bounds
 * hold with effects on.  A zero field means the default where one is
 * given.                                                                   */
#define CT_EFFECT_CURVATURE 1u   /* earth curvature                          */
#define CT_EFFECT_REFRACTION 2u  /* atmospheric refraction, coefficient k    */
#define CT_EFFECT_ALL 3u
/* With the true Earth (CURVATURE, earth_radius_nm 0, a UTM package): map
 * the line of sight into the package's frame through a polynomial fitted
 * once per call (ct_geolocate_batch: once for all its pixels) instead of
 * 4-6 exact ECEF -> geodetic -> UTM conversions per pixel.  The fit
 * interpolates the exact map at the (d + 1)^3 Chebyshev points of a cube
 * of half-width 2^44..2^47 nm (17.6-141 km) around the camera holding
 * every point the pixel's path is converted at, d = 4, 5 or 6 by its size
 * (125-343 exact conversions at set-up); beyond 141 km (a camera more than
 * ~120 km from the tile's far corner) the exact map is kept.  Fitted and
 * exact images differ by under 0.02 mm (docs/geolocation.md); the hit is
 * within the same error bound.  For batches: a single-pixel call pays the
 * whole set-up.  Ignored without the true Earth.                          */
#define CT_EFFECT_EARTH_FIT 4u
#define CT_EARTH_RADIUS_NM INT64_C(6371000000000000) /* 6371 km (mean)     */
#define CT_REFRACTION_K_STD_Q16 8520  /* k = 0.13 (standard atmosphere), Q16 */
#define CT_EFFECTS_CHORD_NM INT64_C(1000000)         /* 1 mm               */
/* A fitted map from Earth-fixed space into a UTM package's grid (the true
 * Earth, earth.c), kept in caller memory across calls: ct_earth_map_init
 * fits it once over a cube around a point (e.g. the tile's centre, large
 * enough for every camera position and its range), then every ct_geolocate
 * / ct_geolocate_batch whose ct_effects.earth_map points to it maps the
 * lines of sight through it where they lie in its cube (exactly
 * elsewhere), with no set-up per call beyond the camera's own.  As
 * CT_EFFECT_EARTH_FIT's per-call map: within 0.02 mm of the exact map.
 * The fields are the library's; about 2.3 KB.                             */
#define CT_EARTH_MAP_DEG 6
#define CT_EARTH_MAP_TERMS 84   /* terms of total degree <= 6 in 3 variables */
typedef struct {
    uint32_t ready;            /* CT_EARTH_MAP_READY once fitted            */
    int32_t deg;               /* 4..CT_EARTH_MAP_DEG; 0: none              */
    uint32_t qrho;             /* the cube's half-width is 2^qrho nm        */
    uint32_t fb[3];            /* the samples' fraction bits per axis       */
    uint32_t sh[CT_EARTH_MAP_DEG + 1][3]; /* per degree: coefficient shift */
    int64_t c[3];              /* the cube's centre, ECEF nm                */
    int64_t g16[3];            /* its grid point, Q16                       */
    int64_t georef[7];         /* the package's georeference it fits        */
    int64_t cf[CT_EARTH_MAP_TERMS][3]; /* Chebyshev coefficients            */
} ct_earth_map;
#define CT_EARTH_MAP_READY 0x4d524145u /* "EARM" */

typedef struct {
    uint32_t flags;            /* CT_EFFECT_* bits; 0 = a straight ray       */
    int32_t refraction_k_q16;  /* k in Q16, [-2, 2] (used with REFRACTION;
                                  0 is k = 0, not a default)                */
    int64_t earth_radius_nm;   /* 0: with CT_EFFECT_CURVATURE on a package
                                  on a UTM zone, the true Earth (earth.c:
                                  the line of sight straight in Earth-fixed
                                  space, WGS84 -- with REFRACTION bent in
                                  its vertical plane with the textbook
                                  curvature k cos(elevation) / R --, traced at most 2^48 nm,
                                  281 km, from the camera: terrain farther
                                  is not seen); else the sphere of
                                  CT_EARTH_RADIUS_NM.  Non-zero: the sphere
                                  of that radius, [2^40, 2^54] nm (1.1 km ..
                                  18,000 km), as a map-frame parabola      */
    int64_t chord_nm;          /* polyline tolerance; 0 = CT_EFFECTS_CHORD_NM;
                                  else [2^10, 2^50] nm, and the polyline's
                                  segment sqrt(8 chord R / |c|) must be at
                                  least 1/64 of a cell (else CT_ERR_EFFECTS).
                                  The true Earth's pieces: a pixel whose
                                  piece cannot be proven within the chord
                                  (its bound's rounding terms exceed it:
                                  chords below about 0.5 mm looking down
                                  at 30 m posts) is CT_ERR_EFFECTS      */
    const ct_earth_map *earth_map; /* NULL, or a map fitted for this package
                                  (ct_earth_map_init; else CT_ERR_EFFECTS),
                                  used with the true Earth (else ignored)   */
} ct_effects;

/* Effects for a tolerance: which of curvature and refraction a camera over
 * a package needs for a horizontal geolocation error under tol_nm, from a
 * bound per pixel over the image (its border every 1/64 and a 15 x 11
 * grid): leaving out a bend of coefficient c moves the line of sight by c
 * rho^2 / 2R vertically at horizontal range rho, which moves its meeting
 * with flat ground by that over tan(depression).  rho is where the ray
 * reaches the tile's lowest post, at most the tile's farthest corner; a ray
 * level or rising while the camera is below the tallest post, or a camera
 * below the lowest post, is unbounded (2^62).  Bounds are for flat ground:
 * where the ground falls away from the ray (incidence below the
 * depression) the error grows as 1 / sin(incidence).  The chord (the
 * polyline's and the true Earth's pieces' tolerance) moves a hit on flat
 * ground by at most chord / tan(depression) in height and by the chord
 * itself sideways or along the track (the true Earth's pieces): the
 * largest chord whose larger effect is within what the chosen set's bound
 * leaves of the tolerance.                                                */
typedef struct {
    uint32_t flags;            /* the least set: 0, CURVATURE, REFRACTION or
                                  both (the first, in that order, whose bound
                                  is within the tolerance; both otherwise)  */
    int64_t chord_nm;          /* the largest chord with chord max(1,
                                  1 / tan(dep)) <= tol - the set's bound,
                                  in [2^10, 2^50] nm
                                  (2^10 when nothing is left: the finest;
                                  CT_EFFECTS_CHORD_NM when a level or rising
                                  ray reaches the tile: no such bound); with
                                  curvature chosen, radius_nm 0 and a UTM
                                  package (the true Earth) never below
                                  CT_EFFECTS_CHORD_NM, the finest its pieces
                                  prove everywhere (see ct_effects)      */
    int64_t bound_nm[4];       /* bound with [0] nothing simulated (c = 1 -
                                  k), [1] curvature only (c = k), [2]
                                  refraction only (c = 1), [3] both (0);
                                  2^62: unbounded                           */
    int64_t range_nm;          /* the largest rho of a sampled ray           */
    int64_t tan_min_q30;       /* the least tan(depression) of a sampled ray
                                  that reaches the tile (Q30, 2^62: none)    */
    uint32_t samples;          /* pixels that unprojected                   */
} ct_effects_choice;

/* The least set of effects a camera's pixels need for a tolerance (see
 * ct_effects_choice above): the camera's rays sampled over the image.
 *   [in]  pkg, cam, pose     an opened package, a camera, its pose.
 *   [in]  refraction_k_q16   k, Q16, in [-2, 2].
 *   [in]  radius_nm          R, nm: 0 (6371 km) or [2^40, 2^54].
 *   [in]  tol_nm             the ground error allowed, nm, >= 0.
 *   [out] out                the choice, its bounds and the samples.
 * Errors: CT_ERR_ARG (NULL, a camera or pose not set up), CT_ERR_EFFECTS
 * (k or R out of range), CT_ERR_UNPROJECT (no pixel unprojects).          */
ct_status ct_effects_for_tolerance(const ct_package *pkg, const ct_camera *cam, const ct_pose *pose,
                                   int32_t refraction_k_q16, int64_t radius_nm, int64_t tol_nm,
                                   ct_effects_choice *out);

/* Intervisibility (lib/src/los.c): is map point B (nm) visible from map
 * point A?  The segment A -> B against the package's surface, exact as
 * ct_trace (both points as ct_map_to_grid rounds them, Q16); with effects
 * as for geolocation: curvature with earth_radius_nm 0 on a UTM package is
 * the true Earth (the Earth-fixed line of sight from A aimed at B -- with
 * refraction at B raised by the path's drop k t^2 / 2R along the
 * direction the path bends: the vertical at A made perpendicular to the
 * line -- traced by earth.c, the
 * margin an Earth-fixed distance; earth_map / CT_EFFECT_EARTH_FIT honoured);
 * otherwise the sphere (c > 0; 0 = 6371 km): the line of sight from A
 * through B bent by c rho^2 / 2R, as ct_trace_bent's lowered walk.  CT_OK: nothing stands
 * between them (B visible); CT_HIT: the surface meets the line of sight
 * more than margin_nm (3D distance from A) before B -- *block is that
 * first point, as ct_trace's hit -- so a target on the ground, met at
 * itself, is visible; CT_BELOW: A under the surface.  Errors: CT_ERR_ARG
 * (NULL, margin < 0), CT_ERR_METHOD, CT_ERR_RAY (a point beyond
 * CT_MAX_ORIGIN_Q16 of the tile, A = B, or for the true Earth B where the
 * zone's projection cannot take it), CT_ERR_EFFECTS (effects that
 * ct_geolocate refuses -- unknown flags, |k| > 2, R or chord out of range,
 * another package's earth_map -- or, on the sphere, c < 0 or a bend the
 * lowered walk cannot take from A; for the true Earth, A where the zone's
 * projection cannot take it, e.g. far off the zone, or a piece of the line
 * of sight that cannot be proven within the chord), CT_ERR_RANGE (the true
 * Earth's line of sight needs more than 8192 pieces over the tile).
 *   [in]  pkg        an opened package.
 *   [in]  a_nm, b_nm the two map points (E, N, h), nm.
 *   [in]  effects    NULL or as ct_geolocate's.
 *   [in]  margin_nm  >= 0: how far before B a blocking point still counts
 *                    as B itself.
 *   [in]  method     CT_METHOD_*.
 *   [out] block      for CT_HIT, the first point where the surface meets
 *                    the line of sight (as ct_trace's hit).               */
ct_status ct_los(const ct_package *pkg, const int64_t a_nm[3], const int64_t b_nm[3], const ct_effects *effects,
                 int64_t margin_nm, ct_method method, ct_hit *block);

/* Inverse location with occlusion: where does the camera see the map point
 * G (nm), and does it see it?  The pixel (Q16) by ct_camera_project of the
 * direction from the camera centre to G -- with effects, to G lowered by
 * the line of sight's rise c rho^2 / 2R (the sphere model, as the tracer's
 * bent rays: the apparent point); on the true Earth (curvature, radius 0,
 * a UTM package) the Earth-fixed line of sight's direction, aimed as
 * ct_los aims it -- and *visible from ct_los between the
 * camera centre and G (the same effects and margin; *block the blocking
 * point when hidden).  CT_OK (pixel set, *visible 0 or 1); CT_BELOW (the
 * camera under the surface; pixel set, *visible 0); CT_ERR_UNPROJECT
 * (behind the camera or outside the valid field: no pixel), CT_ERR_LENS
 * (a grid camera), or ct_los's errors.  A pixel outside the image is still
 * given: the caller compares it with the imager size.
 *   [in]  pkg, cam, pose, effects, margin_nm  as ct_geolocate and ct_los.
 *   [in]  g_nm          the map point (E, N, h), nm.
 *   [out] u_q16, v_q16  the pixel, Q16.
 *   [out] visible       1 when nothing blocks the line of sight, else 0.
 *   [out] block         the blocking point when hidden (as ct_los).      */
ct_status ct_locate_inverse(const ct_package *pkg, const ct_camera *cam, const ct_pose *pose, const ct_effects *effects,
                            const int64_t g_nm[3], int64_t margin_nm, int64_t *u_q16, int64_t *v_q16,
                            uint32_t *visible, ct_hit *block);

/* Fit a ct_earth_map for `pkg` (on a UTM zone) over the cube of half-width
 * 2^q nm >= radius_nm (q = 44..47: 17.6 .. 141 km) around the map point
 * (e, n, h): (d + 1)^3 exact conversions, d = 4, 5, 6 for q = 44, 45..46, 47
 * (125 .. 343; 9.4M instructions at q = 44 on Cortex-M4).  CT_OK;
 * CT_ERR_ARG (NULL), CT_ERR_CRS (not UTM), CT_ERR_RANGE (radius beyond
 * 2^47 nm or not positive, the point off the zone or the grid's range, or
 * a cube point the projection cannot take).
 *   [in]  pkg               an opened package on a UTM zone.
 *   [in]  e_nm, n_nm, h_nm  the cube's centre, map frame, nm.
 *   [in]  radius_nm         the half-width needed, (0, 2^47] nm.
 *   [out] map               the fitted map, for ct_effects.earth_map.   */
ct_status ct_earth_map_init(const ct_package *pkg, int64_t e_nm, int64_t n_nm, int64_t h_nm, int64_t radius_nm,
                            ct_earth_map *map);

/* Result of geolocating one pixel.                                         */
typedef struct {
    ct_status status;          /* as returned by ct_geolocate               */
    uint32_t unproject_iters;  /* Newton iterations (0 for PINHOLE)         */
    int32_t ray_cam_q30[3];    /* unit ray, camera frame (valid if the pixel
                                  unprojected)                              */
    int64_t dir_map_q39[3];    /* the same ray in the map frame             */
    ct_hit hit;                /* the trace: hit.e_nm, n_nm, h_nm, steps    */
} ct_geo;

/* Validate *lens and find its valid field.
 *   [out] cam   the camera: the lens in the library's fixed-point form and
 *               its valid field (where the distortion is invertible).
 *   [in]  lens  model, focal lengths and centre (px), distortion
 *               coefficients (mrcal's / OpenCV's order and meaning).
 * Errors: CT_ERR_ARG (NULL), CT_ERR_LENS (unknown model, fx or fy outside
 * [1, 2^20] px, |cx|, |cy| > 2^20 px, a distortion coefficient beyond 2^10
 * or set but unused by the model, or no valid field at all).              */
ct_status ct_camera_init(ct_camera *cam, const ct_lens *lens);

/* A camera from an unprojection grid (the table stays in caller memory:
 * it must outlive cam).  ct_camera_project is not available for it
 * (CT_ERR_LENS).
 *   [out] cam   the camera.
 *   [in]  grid  the grid's geometry and nodes (ct_unproject_grid).
 * Errors: CT_ERR_ARG (NULL), CT_ERR_LENS (geometry out of range, or a node
 * that is neither a unit vector within 2^-20 nor (0, 0, 0)).              */
ct_status ct_camera_init_grid(ct_camera *cam, const ct_unproject_grid *grid);

/* Pixel (u, v) (Q16) to the unit ray in the camera frame (Q30).  CT_OK or
 * CT_ERR_UNPROJECT.  *iters (may be NULL) receives the Newton iterations.
 *   [in]  cam          from ct_camera_init / ct_camera_init_grid.
 *   [in]  u_q16, v_q16 pixel, Q16 px, mrcal's convention (the centre of the
 *                      top-left pixel is (0, 0)), |.| <= 2^20 px.
 *   [out] ray_cam_q30  unit vector, camera frame (x right, y down, z
 *                      forward), Q30, z > 0.
 *   [out] iters        Newton iterations used (<= CT_UNPROJECT_MAX_ITERS).
 * Scaling and overflow: normalised coordinates in Q32 (x^2 + y^2 <= 64),
 * the distortion's Horner sums in Q44/Q38 (camera.c beside each product).
 * A grid: Catmull-Rom weights in Q30 times Q30 nodes, sums in Q60 below
 * 2^63 in 64-bit, normalised by one reciprocal (grid_unproject).          */
ct_status ct_camera_unproject(const ct_camera *cam, int64_t u_q16,
                              int64_t v_q16, int32_t ray_cam_q30[3],
                              uint32_t *iters);

/* Camera-frame direction to the pixel that sees it (the lens model forward).
 *   [in]  cam          from ct_camera_init.
 *   [in]  ray_cam      any int32 vector with z > 0 (not necessarily unit),
 *                      camera frame.
 *   [out] u_q16, v_q16 the pixel, Q16, rounded.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_UNPROJECT (behind the camera or outside
 * the valid field), CT_ERR_LENS (a grid camera).                          */
ct_status ct_camera_project(const ct_camera *cam, const int32_t ray_cam[3],
                            int64_t *u_q16, int64_t *v_q16);

/* Validate and store a pose.
 *   [out] pose            the pose.
 *   [in]  R_map_cam_q30   camera-to-map rotation, row-major, Q30:
 *                         orthonormal within 2^-20 per entry of R^T R - I,
 *                         det > 0 (map frame: east, north, up).
 *   [in]  e_nm, n_nm, h_nm  the camera centre in the map frame, |.| <= 2^61.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_POSE (R not a rotation, a position out
 * of range).                                                               */
ct_status ct_pose_init(ct_pose *pose, const int32_t R_map_cam_q30[9],
                       int64_t e_nm, int64_t n_nm, int64_t h_nm);

/* dir_map = R_map_cam * ray_cam, Q39 (rounded).
 *   [in]  pose         from ct_pose_init / ct_pose_from_map / _wgs84.
 *   [in]  ray_cam_q30  camera-frame vector, Q30 (|.| <= 2^30 per axis).
 *   [out] dir_map_q39  map-frame (E, N, h) direction, Q39 (|.| < 2^40); for
 *                      a geodetic pose the horizontal components scaled by
 *                      the map's point scale (pose->hscale_q30).
 * CT_ERR_ARG for NULL or a pose not set up.  Scaling and overflow: R (Q30)
 * times the ray (Q30), three products summed and rounded to Q39; the point
 * scale applied in 128 bits (< 2^70), the results < 2^40.                  */
ct_status ct_pose_rotate(const ct_pose *pose, const int32_t ray_cam_q30[3],
                         int64_t dir_map_q39[3]);

/* Geolocate pixel (u, v): unproject, rotate into the map frame, trace from
 * the camera centre with `method`, bent by `effects` (NULL or flags 0: a
 * straight ray; see ct_effects).
 *   [in]  pkg           an opened package (the camera may be off the tile).
 *   [in]  cam, pose     the lens and the camera centre (map nm) and
 *                       attitude.
 *   [in]  method        CT_METHOD_*.
 *   [in]  effects       NULL, or the scene effects.
 *   [in]  u_q16, v_q16  the pixel, Q16 px.
 *   [out] out           status, camera-frame ray (Q30), map-frame direction
 *                       (Q39) and the trace's hit (grid Q16 and map nm).
 * The straight grid ray is ct_ray_from_map's from the pose centre along
 * out->dir_map_q39, so it can be formed again from the pose and *out.
 * Returns (and stores in out->status)
 * CT_HIT or CT_HIT_VOID (out->hit.e_nm, n_nm, h_nm valid), CT_MISS,
 * CT_BELOW (the ray's first point over the tile below the surface; on the
 * true Earth, where the line of sight is traced in pieces, only when the
 * camera is over the tile and under its surface -- a line of sight from
 * off the tile entering its side below the surface hits the side there),
 * or an error: CT_ERR_UNPROJECT for the pixel; CT_ERR_ARG /
 * CT_ERR_METHOD / CT_ERR_EFFECTS for the arguments, and CT_ERR_EFFECTS
 * for a pixel on the true Earth whose line of sight holds a piece that
 * cannot be proven within the chord (ct_effects.chord_nm); CT_ERR_RAY when
 * the camera centre is beyond CT_MAX_ORIGIN_Q16 of the tile; CT_ERR_RANGE
 * when a bent ray would need more than CT_BEND_MAX_SEGMENTS segments, the
 * true Earth's line of sight more than 8192 pieces over the tile, or the
 * camera is more than 2^52 nm (4500 km) from the tile.  With effects,
 * out->hit.t_q26 is the parameter on the prepared straight ray (lowered
 * walk) or on the polyline segment holding the hit, and steps/iters are
 * summed over segments (ct_trace_bent).                                    */
ct_status ct_geolocate(const ct_package *pkg, const ct_camera *cam,
                       const ct_pose *pose, ct_method method,
                       const ct_effects *effects, int64_t u_q16,
                       int64_t v_q16, ct_geo *out);

/* Many pixels, each result bit-identical to ct_geolocate's but for
 * hit.steps and hit.iters where runs apply (below); the per-call set-up
 * (argument checks, the camera centre in the grid frame, the bend's or the
 * true Earth's set-up) is done once.
 * Runs: with straight rays or the lowered model (effects off, or c > 0
 * on a sphere; not the true Earth nor the polyline) and every method but
 * CT_METHOD_INCREMENTAL (the plain reference walk), the pixels go in runs
 * of up to 8 consecutive ones.  Where the run's rays share a horizontal
 * axis and direction, each crosses the tile's relief over at least 16
 * cells, none parts from the first by more than 8 cells over 512 (or the
 * tile's width) nor lies more than 4 cells from it across its origin's
 * cell, one max-mipmap walk over bounds holding all their paths shows a
 * first stretch free of the surface for all of them (at most 2 w + levels
 * + 2 iterations, w the tile's cells along that axis; when it shows
 * nothing or the rays part too fast, the same for each half of the run),
 * and each pixel's walk starts where that stretch ends.  Over a tile set
 * (ct_geolocate_batch_tiles) the same on the tile every ray of the run
 * starts on, when each would fetch it anyway (a ray shown clear through
 * it skips it); later tiles ray by ray.  Every status and
 * hit is as ct_geolocate's; hit.steps and hit.iters count the pixel's own
 * walk only.  Consecutive pixels of an image row (or column) make good
 * runs; in any order the results are the same.
 *   [in]  pkg .. effects  as ct_geolocate.
 *   [in]  uv_q16          pixel k at uv_q16[2k], uv_q16[2k + 1], Q16 px.
 *   [in]  count           pixels.
 *   [out] out             out[0..count): each pixel's ct_geo, its own
 *                         status in out[k].status.
 *   [in]  out_len         entries available in out, >= count.
 * Returns CT_OK when every pixel was processed, or the set-up's error
 * (ct_geolocate's argument, camera, pose and effects errors; CT_ERR_ARG
 * for NULL arrays or out_len < count), with nothing written.              */
ct_status ct_geolocate_batch(const ct_package *pkg, const ct_camera *cam,
                             const ct_pose *pose, ct_method method,
                             const ct_effects *effects,
                             const int64_t *uv_q16,
                             size_t count, ct_geo *out, size_t out_len);
/* ======================== end of camera and geolocation ================= */

/* ------------------------------------------------------------------------ */
/* WGS84 geodetic <-> UTM (lib/src/geodesy.c): transverse Mercator by
 * Krueger's series to order n^6 (Karney 2011), in integers.  Geodetic
 * angles are radians in Q61 (int64: value * 2^61; 2^-61 rad is 3 pm on the
 * ground); map coordinates are nm with UTM's false easting (500 km) and,
 * south, false northing (10,000 km).  Accuracy (tests/test_geodesy.cpp,
 * against PROJ): see docs/geolocation.md, "Geodesy".  Domain: |lat| <=
 * 84.5 deg and |lon - the zone's central meridian| <= CT_UTM_MAX_DLON_DEG;
 * outside, CT_ERR_RANGE.                                                   */
typedef struct {
    int32_t zone;   /* 1..60 */
    int32_t south;  /* 0: north (EPSG 326zz), 1: south (EPSG 327zz) */
} ct_utm;

#define CT_PI_Q61 INT64_C(7244019458077122842)       /* pi, Q61 (rounded) */
#define CT_UTM_MAX_LAT_Q61 INT64_C(3400664690041760445) /* 84.5 deg, Q61 */
#define CT_UTM_MAX_DLON_DEG 9

/* The UTM zone of an EPSG code.
 *   [in]  epsg  32601..32660 (north) or 32701..32760 (south).
 *   [out] zone  the zone number and hemisphere.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_CRS (any other code).                 */
ct_status ct_utm_zone_of_epsg(int32_t epsg, ct_utm *zone);

/* Geodetic (lat, lon: Q61 radians) to UTM (E, N: nm, rounded).
 *   [in]  zone              the zone (and hemisphere).
 *   [in]  lat_q61, lon_q61  WGS84 latitude and longitude, Q61 radians.
 *   [out] e_nm, n_nm        UTM easting and northing, nm, false easting
 *                           and (south) northing included.
 * Errors: CT_ERR_ARG (NULL, zone outside 1..60), CT_ERR_RANGE (outside the
 * domain above).  Scaling: Q59 internals (|value| < 16) with 128-bit
 * products and quotients (geodesy.c); within 7 nm of PROJ's result.       */
ct_status ct_utm_forward(const ct_utm *zone, int64_t lat_q61, int64_t lon_q61,
                         int64_t *e_nm, int64_t *n_nm);

/* The meridian convergence and the point scale at a geodetic point: what
 * turns a north-east-down attitude into the map frame, and ground distances
 * into map distances.
 *   [in]  zone              the zone (and hemisphere).
 *   [in]  lat_q61, lon_q61  WGS84 latitude and longitude, Q61 radians.
 *   [out] gamma_q61         the angle from true north to grid north, Q61
 *                           radians, clockwise positive (as PROJ's).
 *   [out] k_q61             the point scale, Q61 (0.9996 on the central
 *                           meridian).
 * Errors and scaling: as ct_utm_forward (the same series and its
 * derivative, Karney 2011 eqs. 27-28).                                     */
ct_status ct_utm_factors(const ct_utm *zone, int64_t lat_q61, int64_t lon_q61,
                         int64_t *gamma_q61, int64_t *k_q61);

/* A camera pose from the navigation solution: the camera centre in WGS84
 * (lat, lon: Q61 radians; h_nm: ellipsoidal height, which is the package's
 * height frame when its source datum is known, pkg->vdatum) and its attitude
 * w.r.t. local north-east-down as a unit quaternion q = (w, x, y, z), Q30,
 * rotating camera-frame vectors into NED.  The map frame's axes at the
 * camera are grid east, grid north and up: NED turned by the meridian
 * convergence, and horizontal lengths scaled by k R / (R + h) (the point
 * scale and the elevation factor, R the Gaussian mean radius there) into
 * pose->hscale_q30.
 *   [out] pose            the pose (ct_pose_init's checks applied).
 *   [in]  zone            the package's UTM zone.
 *   [in]  lat_q61, lon_q61, h_nm  the camera centre (Q61 radians, nm).
 *   [in]  q_ned_cam_q30   (w, x, y, z), Q30, |q| = 1 within 2^-20.
 * Errors: CT_ERR_ARG (NULL, a zone outside 1..60), CT_ERR_RANGE (outside
 * the zone's domain), CT_ERR_POSE (q off unit length, a position beyond
 * ct_pose_init's range).                                                   */
ct_status ct_pose_from_wgs84(ct_pose *pose, const ct_utm *zone, int64_t lat_q61,
                             int64_t lon_q61, int64_t h_nm, const int32_t q_ned_cam_q30[4]);

/* A pose in the map frame with an attitude quaternion w.r.t. grid north,
 * grid east and down (no convergence, no scale: hscale 2^30).
 *   [out] pose            the pose.
 *   [in]  e_nm, n_nm, h_nm  the camera centre, map frame, |.| <= 2^61.
 *   [in]  q_ned_cam_q30   (w, x, y, z), Q30, |q| = 1 within 2^-20,
 *                         rotating camera-frame vectors into (grid north,
 *                         grid east, down).
 * Errors: CT_ERR_ARG (NULL), CT_ERR_POSE (q off unit length, a position
 * out of range).                                                           */
ct_status ct_pose_from_map(ct_pose *pose, int64_t e_nm, int64_t n_nm, int64_t h_nm,
                           const int32_t q_ned_cam_q30[4]);

/* The attitude quaternion of aerospace yaw, pitch, roll (Z-Y-X) for a
 * camera whose mrcal axes x right, y down, z forward point east, down,
 * north at zero; yaw turns it clockwise seen from above, pitch raises its
 * forward axis, roll turns it about that axis.
 *   [in]  yaw_q61, pitch_q61, roll_q61  Q61 radians, |.| <= pi.
 *   [out] q_ned_cam_q30  (w, x, y, z), Q30, rotating camera-frame vectors
 *                        into north-east-down (ct_pose_from_wgs84's input).
 * Errors: CT_ERR_ARG (NULL), CT_ERR_RANGE (an angle beyond pi).
 * Scaling: Q59 sines and cosines; products of Q30 values < 2^60, sums of
 * four < 2^62, rounded to Q30.                                             */
ct_status ct_quat_from_ypr(int64_t yaw_q61, int64_t pitch_q61, int64_t roll_q61,
                           int32_t q_ned_cam_q30[4]);

/* The geoid undulation N (h_ellipsoid = h_geoid + N) at a geodetic point,
 * bilinear in latitude and longitude between the grid's nodes (longitude
 * wraps at +-pi).
 *   [in]  grid              the geoid grid (a package's pkg->geoid).
 *   [in]  lat_q61, lon_q61  Q61 radians.
 *   [out] n_geoid_nm        N, nm.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_RANGE (outside the grid, its last row
 * and column included, or no grid).
 * Scaling: the position within a cell is a Q19 fraction of the step (at
 * EGM96's 15', < 0.06 m on the ground; times the geoid's slope < 1e-3:
 * < 0.06 mm); the first interpolation is rounded to nm (|N| < 2^31 um:
 * < 2^41 nm), so every product stays below 2^61.                          */
ct_status ct_geoid_at(const ct_geoid_grid *grid, int64_t lat_q61, int64_t lon_q61,
                      int64_t *n_geoid_nm);

/* The same at a map point of a package (ct_utm_inverse, then
 * ct_geoid_at on pkg->geoid): what turns the ellipsoidal heights of a
 * package with a known source datum into orthometric ones (h - N).
 *   [in]  pkg         an opened package.
 *   [in]  e_nm, n_nm  the map point, nm.
 *   [out] n_geoid_nm  N there, nm.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_CRS (not on a UTM zone), CT_ERR_RANGE
 * (as ct_utm_inverse and ct_geoid_at).                                     */
ct_status ct_package_geoid(const ct_package *pkg, int64_t e_nm, int64_t n_nm,
                           int64_t *n_geoid_nm);

/* WGS84 geodetic to Earth-centred, Earth-fixed Cartesian coordinates
 * (EPSG:4978).
 *   [in]  lat_q61, lon_q61  Q61 radians, |lat| <= pi/2, |lon| <= pi.
 *   [in]  h_nm              ellipsoidal height, [-2^52, 2^54] nm (-4,500 km
 *                           .. 18,000 km).
 *   [out] xyz_nm            x, y, z, nm, rounded.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_RANGE (outside the domain).            */
ct_status ct_ecef_from_wgs84(int64_t lat_q61, int64_t lon_q61, int64_t h_nm, int64_t xyz_nm[3]);

/* Earth-fixed to WGS84 geodetic.  On the polar axis lon = 0.
 *   [in]  xyz_nm            x, y, z, nm: |.| <= 2^55 and at least 2^50 nm
 *                           (1,100 km) from the Earth's centre.
 *   [out] lat_q61, lon_q61  Q61 radians.
 *   [out] h_nm              ellipsoidal height, nm.
 * Errors: CT_ERR_ARG (NULL), CT_ERR_RANGE (outside the domain).            */
ct_status ct_wgs84_from_ecef(const int64_t xyz_nm[3], int64_t *lat_q61, int64_t *lon_q61, int64_t *h_nm);

/* UTM to geodetic: the inverse of ct_utm_forward (Krueger's series).
 *   [in]  zone              the zone (and hemisphere).
 *   [in]  e_nm, n_nm        easting and northing, nm (false easting and,
 *                           south, northing included).
 *   [out] lat_q61, lon_q61  WGS84 latitude and longitude, Q61 radians.
 * Errors: CT_ERR_ARG (NULL, zone outside 1..60), CT_ERR_RANGE (more than
 * 1,100 km east or west of the central meridian or 9,500 km north or south
 * of the equator, a pole, or a point outside the zone's domain above).  */
ct_status ct_utm_inverse(const ct_utm *zone, int64_t e_nm, int64_t n_nm,
                         int64_t *lat_q61, int64_t *lon_q61);

/* ------------------------------------------------------------------------ */
/* Tile sets (lib/src/tiles.c): terrain larger than one package.             */
/*                                                                          */
/* `conetrace build DEM -o DIR --tile-size P` cuts the DEM's posts into a   */
/* grid of tiles of P posts per side that share their edge posts (tile      */
/* (col, row) holds posts col (P - 1) .. col (P - 1) + P - 1, and rows      */
/* alike; the last column and row of tiles may be narrower), each a normal   */
/* package with the set's height offset and scale, and a manifest.  The     */
/* library traces a ray over the set as over the one package built from    */
/* the merged DEM: the ray is prepared against the set's whole extent (its  */
/* "frame"), and walked tile by tile in order, each tile's walk starting    */
/* where the ray crosses onto it; the exact cell tests are the same, so a   */
/* hit is the merged package's bit for bit (steps and iters differ).  A     */
/* tile's cones promise empty space only inside its own box, which is all   */
/* its walk uses.  Tiles stay in caller memory: an array of slots (a cache, */
/* least recently used first out) filled through the caller's loader.  A    */
/* tile the ray passes over higher than its tallest post (the manifest      */
/* says) is not loaded.  A ray that reaches a tile the set does not have,  */
/* that the loader cannot give, or whose bytes fail their checks (CRC, the  */
/* manifest's size and CRC, its place in the grid) ends with CT_NO_DATA:    */
/* hit.t_q26 and the position are where the ray entered that tile -- never  */
/* a hit on terrain the set does not hold.                                  */
/*                                                                          */
/* The manifest (little-endian; CRC-32 as a package's):                     */
/*   0  char[4] "CTTS"      4  u16 version (1)     6  u16 header size (96)   */
/*   8  u32 total size     12  u32 CRC-32 (over the whole, these 4 bytes 0)  */
/*  16  u16 tiles_x        18  u16 tiles_y        20  u16 tile posts P      */
/*  22  u8  reduce r       23  u8  sectors N                                */
/*  24  u16 width W        26  u16 height H  (merged posts: W <= tiles_x    */
/*      (P - 1) + 1 < W + P - 1, rows alike; W, H <= CT_MAX_POSTS)          */
/*  28  u16 hmin code      30  u16 hmax code  (over every tile)             */
/*  32  i64 origin_e_nm    40  i64 origin_n_nm  (the merged grid's corner)  */
/*  48  i64 posting_e_nm   56  i64 posting_n_nm                             */
/*  64  i64 height_offset_nm 72 i64 height_scale_nm                          */
/*  80  u32 EPSG           84  u16 source vertical datum (CT_VDATUM_*)      */
/*  86  u16 reserved (0)   88  u32 flags (0)      92  u32 reserved (0)       */
/*  96  tiles_x * tiles_y entries of 16 bytes, row-major (row 0 north):     */
/*      u32 package size, u32 package CRC (its header's), u16 hmin, u16     */
/*      hmax (its codes' range), u8 present (1; 0: no tile, no data there), */
/*      u8[3] reserved (0).                                                 */
/* On the host the tiles are files "tile_<col>_<row>.ctp" beside the        */
/* manifest (docs/package-format.md).                                       */
enum {
    CT_NO_DATA = 5 /* result: the ray reached a tile the set does not hold
                      (missing, not loadable, or failing its checks); the
                      hit's t_q26, position and cell are where it entered */
};

#define CT_SET_MAGIC "CTTS"
#define CT_SET_VERSION 1u
#define CT_SET_HEADER_SIZE 96u
#define CT_SET_ENTRY_SIZE 16u
#define CT_SET_MAX_TILES 4096u     /* tiles_x * tiles_y                     */
#define CT_SET_HDR_TILES_X 16u
#define CT_SET_HDR_TILES_Y 18u
#define CT_SET_HDR_TILE_POSTS 20u
#define CT_SET_HDR_REDUCE 22u
#define CT_SET_HDR_SECTORS 23u
#define CT_SET_HDR_WIDTH 24u
#define CT_SET_HDR_HEIGHT 26u
#define CT_SET_HDR_HMIN 28u
#define CT_SET_HDR_HMAX 30u
#define CT_SET_HDR_GEOREF 32u      /* six i64, in a package header's order */
#define CT_SET_HDR_EPSG 80u
#define CT_SET_HDR_VDATUM 84u
#define CT_SET_HDR_FLAGS 88u

/* Worst-case iterations of a trace over a tile set: the tiles a ray
 * crosses (at most tiles_x + tiles_y - 1) times the method's bound for a
 * full tile, CT_WCET_CELL_ITERS(P - 1, P - 1) or CT_WCET_HIER_ITERS(P - 1,
 * P - 1, levels); each tile's walk enforces its own bound.                */
#define CT_WCET_SET_ITERS(tiles_x, tiles_y, tile_bound) \
    (((uint32_t)(tiles_x) + (uint32_t)(tiles_y)) * (uint32_t)(tile_bound))

/* The caller's loader: put tile (col, row) in reach and say where its
 * bytes are: fill buf[0..cap) (the slot's memory) and set *bytes = buf, or
 * point *bytes at memory of its own (flash, a mapped file) that stays
 * valid until the slot is reused; *len the bytes available.  Return CT_OK,
 * or anything else for "not available" (the trace then ends CT_NO_DATA).  */
typedef ct_status (*ct_tile_loader)(void *user, uint32_t col, uint32_t row, uint8_t *buf, size_t cap,
                                    const uint8_t **bytes, size_t *len);

/* One cache slot: caller memory.  Set buf and cap (or NULL, 0 when the
 * loader hands out its own memory) before ct_tileset_open.  Which tile a
 * slot holds is kept in the set (compactly: the lookup touches one or two
 * cache lines, not one per slot).                                          */
typedef struct {
    ct_package pkg;     /* the tile held, opened                           */
    uint8_t *buf;       /* memory the loader may fill                      */
    size_t cap;
} ct_tile_slot;

#define CT_SET_MAX_SLOTS 64u       /* slots per set                         */
#define CT_SET_HINTS 64u           /* slot guesses, by tile number mod 64   */

/* A tile set over caller memory.  Fill with ct_tileset_open.  The
 * manifest's bytes are kept by reference (zero copy).  Not reentrant: a
 * trace updates the cache (one set per thread).                           */
typedef struct {
    ct_package frame;          /* the merged grid: its size, heights' range
                                  and georeference (no sections: base is
                                  NULL): use it for ct_map_to_grid,
                                  ct_ray_from_map, ...; what reads terrain
                                  (ct_trace, ct_ray_prepare*, ct_trace_*,
                                  ct_surface_height, ct_los,
                                  ct_locate_inverse, ct_geolocate*,
                                  ct_package_verify) refuses it: CT_ERR_ARG */
    uint32_t tiles_x, tiles_y; /* the tile grid                             */
    uint32_t tile_posts;       /* P                                         */
    uint32_t tile_recip;       /* floor(2^32 / (P - 1)) + 1 (0 for P = 2):
                                  a cell's tile without a division          */
    const uint8_t *entries;    /* the manifest's tile table                 */
    ct_tile_slot *slots;
    uint32_t nslots;           /* 1..CT_SET_MAX_SLOTS                       */
    ct_tile_loader load;
    void *user;
    int16_t held[CT_SET_MAX_SLOTS]; /* tile (row * tiles_x + col) in slot k;
                                  -1: empty                                 */
    uint32_t used[CT_SET_MAX_SLOTS]; /* the clock at slot k's last use      */
    uint32_t clock;            /* uses so far (the cache's order)           */
    uint8_t hint[CT_SET_HINTS]; /* the slot tile k was last found in, at
                                  k mod CT_SET_HINTS (checked against held) */
    uint32_t loads;            /* tiles loaded and accepted                 */
    uint32_t refused;          /* loads that failed or were refused         */
    uint32_t ready;            /* CT_SET_READY once ct_tileset_open
                                  succeeded (0 from its start): the _tiles
                                  functions refuse any other set with
                                  CT_ERR_ARG                               */
} ct_tileset;

#define CT_SET_READY 0x52544553u /* "SETR" */

/* Validate a tile set's manifest and set up *ts over the caller's slots.
 *   [out] ts        the set (kept by reference: manifest, slots, user).
 *   [in]  manifest  the manifest's bytes (package-format.md), len of them;
 *                   they must outlive ts.
 *   [in]  slots     nslots cache slots, 1 <= nslots <= CT_SET_MAX_SLOTS,
 *                   each with its buf and cap set (or NULL, 0).
 *   [in]  load      the caller's loader; user is passed to it.
 * Errors: as ct_package_open's for a package (CT_ERR_TRUNCATED, _MAGIC,
 * _VERSION, _HEADER, _CRC; _SECTORS, _REDUCE, _GEOREF, _FLAGS), CT_ERR_DIMS
 * (a tile grid that does not fit W x H, or more than CT_SET_MAX_TILES
 * tiles), CT_ERR_RANGE (hmin > hmax, a tile's range outside the set's),
 * CT_ERR_ARG (NULL, nslots out of range).  On any error the set is not
 * ready (ts->ready 0): tracing it is refused, not undefined.              */
ct_status ct_tileset_open(ct_tileset *ts, const uint8_t *manifest, size_t len, ct_tile_slot *slots, uint32_t nslots,
                          ct_tile_loader load, void *user);

/* ct_trace over the set.
 *   [in,out] ts      the set (its cache is updated: one set per thread).
 *   [in]  ray        grid frame of the set (ts->frame), ct_trace's ranges.
 *   [in]  method     CT_METHOD_*.
 *   [out] hit        as ct_trace's, in the set's grid and map frames,
 *                    bit-identical to the merged package's; steps and iters
 *                    add up over the tiles walked.
 * Returns as ct_trace, or CT_NO_DATA (the ray reached a tile the set does
 * not have, the loader could not give, or whose bytes failed their checks;
 * hit: where it entered that tile); CT_ERR_ARG for a set that
 * ct_tileset_open did not make ready (as the other _tiles functions).     */
ct_status ct_tileset_trace(ct_tileset *ts, const ct_ray *ray, ct_method method, ct_hit *hit);

/* ct_geolocate / ct_geolocate_batch over a tile set (ts->frame is the
 * package for every georeference question, e.g. ct_earth_map_init).
 * Every effect ct_geolocate takes -- straight, the sphere's lowered walk
 * or polyline, the true Earth -- with the same results bit for bit, and
 * CT_NO_DATA where the line of sight reaches a tile the set does not hold.
 *   [in,out] ts  the set (its cache is updated).
 *   [in]  cam .. out_len  as ct_geolocate and ct_geolocate_batch.
 * Errors: theirs.                                                          */
ct_status ct_geolocate_tiles(ct_tileset *ts, const ct_camera *cam, const ct_pose *pose, ct_method method,
                             const ct_effects *effects, int64_t u_q16, int64_t v_q16, ct_geo *out);
ct_status ct_geolocate_batch_tiles(ct_tileset *ts, const ct_camera *cam, const ct_pose *pose, ct_method method,
                                   const ct_effects *effects, const int64_t *uv_q16, size_t count, ct_geo *out,
                                   size_t out_len);

/* ct_los over a tile set: the same answers as on the merged package (the
 * segment, or the true Earth's pieces, walked tile by tile), and
 * CT_NO_DATA when the line of sight reaches a tile the set does not hold
 * before anything blocks it (*block: where it entered that tile).
 *   [in,out] ts  the set (its cache is updated).
 *   [in]  a_nm .. method  as ct_los, in the set's map frame (ts->frame).
 *   [out] block  as ct_los's, or where the line of sight entered a tile
 *                the set does not hold (CT_NO_DATA).
 * Errors: ct_los's.                                                        */
ct_status ct_los_tiles(ct_tileset *ts, const int64_t a_nm[3], const int64_t b_nm[3], const ct_effects *effects,
                       int64_t margin_nm, ct_method method, ct_hit *block);

#ifdef __cplusplus
}
#endif

#endif /* CONETRACE_H */
