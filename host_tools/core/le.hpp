// le.hpp -- little-endian stores and loads on byte buffers (host): the one
// writer of the package format's multi-byte fields (lib/include/conetrace.h)
// for the builder, the vertical-datum code, the MCU vector generator and the
// tests.  The flight library's loads are ct_ld16 / ct_ld32 / ct_ld64s in
// lib/src/fixed.h.  No bounds checks: the caller sizes the buffer.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace ct_host {

// v's low 2 / 4 / 8 bytes at p, least significant first.
inline void put16(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
inline void put32(uint8_t *p, uint32_t v)
{
    for (int k = 0; k < 4; ++k) p[k] = (uint8_t)(v >> (8 * k));
}
inline void put64(uint8_t *p, int64_t v)
{
    for (int k = 0; k < 8; ++k) p[k] = (uint8_t)((uint64_t)v >> (8 * k));
}

// The same at offset off of a buffer (off + width <= b.size()).
inline void put16(std::vector<uint8_t> &b, size_t off, uint32_t v) { put16(&b[off], v); }
inline void put32(std::vector<uint8_t> &b, size_t off, uint32_t v) { put32(&b[off], v); }
inline void put64(std::vector<uint8_t> &b, size_t off, int64_t v) { put64(&b[off], v); }

// The 16-bit field at p.
inline uint16_t get16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }

// The 32-bit field at offset off (off + 4 <= b.size()).
inline uint32_t get32(const std::vector<uint8_t> &b, size_t off)
{
    return (uint32_t)b[off] | ((uint32_t)b[off + 1] << 8) | ((uint32_t)b[off + 2] << 16) |
           ((uint32_t)b[off + 3] << 24);
}

}  // namespace ct_host
