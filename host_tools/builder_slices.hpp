// builder_slices.hpp -- the slice-by-slice directional-DT PPT builder
// (builder_slices.cpp), called by build_package for PptBuilder::Slices.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "builder_common.hpp"

namespace ct_host {
namespace bld {

struct SliceInput {
    const std::vector<int> *levels = nullptr;      // L_0 < ... < L_K, height codes
    const std::vector<uint16_t> *apex = nullptr;        // per coarse cell: apex height code a >= Hc
    const std::vector<uint16_t> *apex_level = nullptr;  // per coarse cell: k0, the largest k with L_k <= a
    int window = 12;                               // Rw, coarse cells (>= 1)
    double full_dt_rows = 12.0;  // see BuildOptions::full_dt_rows
    int threads = 1;
    std::function<void(size_t, size_t)> progress;
};

struct SliceStats {
    int slices = 0;           // slices transformed (non-empty cross-sections)
    size_t far_narrowed = 0;  // (cell, sector) codes narrowed by a far (DT) term
    size_t dts_skipped = 0;   // (slice, sector) pairs where no cone could narrow: no query
    size_t queries = 0;       // capped directional DT queries (cell, slice, sector)
    uint64_t query_rows = 0;  // rows those queries visited
    size_t full_dts = 0;      // (slice, sector) pairs finished with a full line-traversal DT
    double seconds_local = 0.0;   // near + window terms
    double seconds_dt = 0.0;      // the slices' DTs and far terms
};

// Angle codes (N planes of coarse cells, sector-major) for ctx c, into
// codes[0 .. N * planes).
void slice_angles(const Ctx &c, const SliceInput &in, uint8_t *codes, SliceStats *st);

}  // namespace bld
}  // namespace ct_host
