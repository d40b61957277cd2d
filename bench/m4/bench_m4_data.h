/* bench_m4_data.h -- the data ct_gen_m4_data bakes for bench_m4.c. */
#ifndef CT_BENCH_M4_DATA_H
#define CT_BENCH_M4_DATA_H
#include <stdint.h>

typedef struct {
    int64_t ray[6];      /* ct_ray: x, y, z (Q16), dx, dy, dz                */
    int32_t status[4];   /* the host's ct_trace status per method            */
    uint32_t steps[4];   /* the host's steps per method                      */
    int32_t bent_status; /* the host's ct_trace_bent (m4_bend), directional  */
    uint32_t bent_steps;
} m4_ray;

/* The bend of the "bent" lines: curvature and refraction, c = 1 - 0.13, R =
 * 6371 km, the polyline chord 1 mm (unused by the lowered walk).          */
#define M4_BEND_COEFF_Q16 57016
#define M4_BEND_RADIUS_NM INT64_C(6371000000000000)
#define M4_BEND_CHORD_NM INT64_C(1000000)

extern const uint32_t m4_pkg_size;
extern const uint8_t m4_pkg[];
extern const uint32_t m4_family_count;
extern const char *const m4_family_name[];
extern const uint32_t m4_family_start[];
extern const m4_ray m4_rays[];
#endif
