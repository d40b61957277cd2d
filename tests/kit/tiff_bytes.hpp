// tiff_bytes.hpp -- a little-endian TIFF written byte by byte, for the DEM
// readers' refusals of headers that libtiff would not write (a strip that
// promises more bytes than the file holds, tiles far larger than the
// image): one IFD of single-valued entries at offset 8, then the data.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace tiff_bytes {

struct Entry {
    uint16_t tag, type;  // type 3: SHORT, 4: LONG
    uint32_t value;      // kData: the data's offset
};

constexpr uint32_t kData = 0xffffffffu;

inline std::string make(const std::vector<Entry> &entries, const std::string &data)
{
    std::string b;
    auto put = [&b](uint32_t v, int bytes) {
        for (int k = 0; k < bytes; ++k) b += (char)((v >> (8 * k)) & 255);
    };
    const uint32_t at = 8 + 2 + 12 * (uint32_t)entries.size() + 4;
    put(0x4949, 2);
    put(42, 2);
    put(8, 4);
    put((uint32_t)entries.size(), 2);
    for (const Entry &e : entries) {
        put(e.tag, 2);
        put(e.type, 2);
        put(1, 4);
        put(e.value == kData ? at : e.value, e.type == 3 ? 2 : 4);
        if (e.type == 3) put(0, 2);
    }
    put(0, 4);
    return b + data;
}

}  // namespace tiff_bytes
