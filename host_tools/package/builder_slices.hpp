// builder_slices.hpp -- the PPT builders called by build_package
// (package_build.cpp): the slice-by-slice directional-DT builder
// (builder_slices.cpp, PptBuilder::Slices) and the brute-force one
// (builder_brute.cpp, PptBuilder::Brute).
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
    std::vector<uint16_t> *coarse_max = nullptr;        // per coarse cell: Hc, taken over (emptied)
    const std::vector<uint16_t> *apex_level = nullptr;  // per coarse cell: k0, the lowest k with L_k >= Hc;
                                                        // the apex is a = L_k0
    int window = 12;                               // Rw, coarse cells (>= 1)
    double full_dt_rows = 12.0;  // see BuildOptions::full_dt_rows
    int threads = 1;
    std::function<void(size_t, size_t)> progress;
};

struct SliceStats {
    int slices = 0;           // slices transformed (non-empty cross-sections)
    size_t far_narrowed = 0;  // (cell, sector) codes narrowed by a far (DT) term
    size_t queries = 0;       // capped directional DT queries (cell, slice, sector)
    uint64_t query_rows = 0;  // rows those queries visited
    size_t full_dts = 0;      // (slice, sector) pairs finished with a full line-traversal DT
    double seconds_local = 0.0;   // near + window terms
    double seconds_dt = 0.0;      // the slices' DTs and far terms
};

// The brute-force builder (builder_brute.cpp): angle codes for the given
// apexes (height codes per coarse cell); needs c.fm and c.pyr.
void brute_angles(const Ctx &c, const std::vector<uint16_t> &apex, uint8_t *codes, int threads,
                  const std::function<void(size_t, size_t)> &progress);

// Angle codes (N planes of coarse cells, sector-major) for ctx c, into
// codes[0 .. N * planes).
void slice_angles(const Ctx &c, const SliceInput &in, uint8_t *codes, SliceStats *st);

}  // namespace bld
}  // namespace ct_host
