// proj_pair.hpp -- PROJ for the tests: a transformation between two CRSs,
// normalised for visualisation (longitude before latitude, degrees and
// metres), owning its context.
#pragma once

#include <proj.h>

// proj_create_crs_to_crs(a, b) normalised; nullptr when PROJ cannot make it
inline PJ *proj_normalized(PJ_CONTEXT *ctx, const char *a, const char *b)
{
    PJ *p = proj_create_crs_to_crs(ctx, a, b, nullptr);
    if (!p) return nullptr;
    PJ *n = proj_normalize_for_visualization(ctx, p);
    proj_destroy(p);
    return n;
}

struct ProjPair {
    PJ_CONTEXT *ctx = nullptr;
    PJ *pj = nullptr;  // nullptr when PROJ cannot make the transformation
    ProjPair(const char *src, const char *dst) : ctx(proj_context_create()), pj(proj_normalized(ctx, src, dst)) {}
    ~ProjPair()
    {
        if (pj) proj_destroy(pj);
        proj_context_destroy(ctx);
    }
    ProjPair(const ProjPair &) = delete;
    ProjPair &operator=(const ProjPair &) = delete;
};
