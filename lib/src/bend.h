/*
 * bend.h -- bent-ray helpers shared by bend.c and geoloc.c (private).
 */
#ifndef CT_BEND_H
#define CT_BEND_H

#include "conetrace.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Check *bd's ranges (ct_bend) and compute the polyline's segment length
 * Delta = sqrt(8 chord R / |c|) in Q16 fine cells of pkg (0 when c = 0).
 * CT_OK, or CT_ERR_ARG for a parameter out of range or Delta < 1/64 cell. */
ct_status ct_bend_segment(const ct_package *pkg, const ct_bend *bd, int64_t *delta_q16);

/* ct_trace_prepared for a ray this library prepared itself (skips the
 * re-validation of the caller-visible struct). */
ct_status ct_trace_prepared_own(const ct_package *pkg, const ct_prepared *ray, ct_method method, ct_hit *hit);

#ifdef __cplusplus
}
#endif

#endif /* CT_BEND_H */
