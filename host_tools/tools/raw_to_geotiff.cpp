// raw_to_geotiff -- wrap a headerless little-endian sample file as a GeoTIFF
// through ct_host::write_geotiff().  Used to build test fixtures reproducibly.
//
//   ct_raw_to_geotiff --in F.raw --width W --height H --type int16|uint16|float32
//                     --origin-e E --origin-n N --posting P [--epsg CODE]
//                     [--nodata V] --out F.tif
//
// Row 0 of the raw file is the top (northernmost) row.  The posting P is
// the square post spacing in metres (written as posting_e = P, posting_n = -P).

#include "dem_io.hpp"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

[[noreturn]] void usage(const char *why)
{
    std::fprintf(stderr,
                 "ct_raw_to_geotiff: %s\n"
                 "usage: ct_raw_to_geotiff --in F.raw --width W --height H "
                 "--type int16|uint16|float32 --origin-e E --origin-n N --posting P "
                 "[--epsg CODE] [--nodata V] --out F.tif\n",
                 why);
    std::exit(2);
}

double parse_double(const char *opt, const char *s)
{
    char *end = nullptr;
    double v = std::strtod(s, &end);
    if (end == s || *end) usage((std::string("bad number for ") + opt).c_str());
    return v;
}

long parse_long(const char *opt, const char *s)
{
    char *end = nullptr;
    long v = std::strtol(s, &end, 10);
    if (end == s || *end) usage((std::string("bad integer for ") + opt).c_str());
    return v;
}

template <typename T, typename U>
std::vector<double> decode(const std::vector<unsigned char> &raw)
{
    static_assert(sizeof(T) == sizeof(U), "size");
    std::vector<double> out(raw.size() / sizeof(T));
    for (size_t k = 0; k < out.size(); k++) {
        U u = 0;  // assemble little-endian bytes, whatever the host order
        for (size_t i = 0; i < sizeof(U); i++) u |= (U)((U)raw[k * sizeof(U) + i] << (8 * i));
        T v;
        std::memcpy(&v, &u, sizeof(T));
        out[k] = (double)v;
    }
    return out;
}

}  // namespace

int main(int argc, char **argv)
{
    std::string in, out, type;
    long width = -1, height = -1;
    ct_host::Georef geo;
    bool have_e = false, have_n = false, have_p = false, has_nodata = false;
    double nodata = 0.0;
    geo.epsg = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (i + 1 >= argc) usage((std::string("missing value for ") + a).c_str());
        const char *v = argv[++i];
        if (!std::strcmp(a, "--in")) in = v;
        else if (!std::strcmp(a, "--out")) out = v;
        else if (!std::strcmp(a, "--type")) type = v;
        else if (!std::strcmp(a, "--width")) width = parse_long(a, v);
        else if (!std::strcmp(a, "--height")) height = parse_long(a, v);
        else if (!std::strcmp(a, "--origin-e")) geo.origin_e = parse_double(a, v), have_e = true;
        else if (!std::strcmp(a, "--origin-n")) geo.origin_n = parse_double(a, v), have_n = true;
        else if (!std::strcmp(a, "--posting")) {
            double p = parse_double(a, v);
            if (!(p > 0)) usage("--posting must be > 0");
            geo.posting_e = p, geo.posting_n = -p, have_p = true;
        } else if (!std::strcmp(a, "--epsg")) geo.epsg = (int)parse_long(a, v);
        else if (!std::strcmp(a, "--nodata")) nodata = parse_double(a, v), has_nodata = true;
        else usage((std::string("unknown option ") + a).c_str());
    }
    if (in.empty() || out.empty() || type.empty() || width <= 0 || height <= 0 || !have_e ||
        !have_n || !have_p)
        usage("missing required option");

    ct_host::SampleType st;
    size_t bytes_per_sample;
    if (type == "int16") st = ct_host::SampleType::Int16, bytes_per_sample = 2;
    else if (type == "uint16") st = ct_host::SampleType::UInt16, bytes_per_sample = 2;
    else if (type == "float32") st = ct_host::SampleType::Float32, bytes_per_sample = 4;
    else usage("--type must be int16, uint16 or float32");

    std::ifstream f(in, std::ios::binary);
    if (!f) {
        std::fprintf(stderr, "ct_raw_to_geotiff: %s: cannot open\n", in.c_str());
        return 1;
    }
    std::vector<unsigned char> raw((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    const size_t expect = (size_t)width * (size_t)height * bytes_per_sample;
    if (raw.size() != expect) {
        std::fprintf(stderr, "ct_raw_to_geotiff: %s: %zu bytes, expected %zu (%ld x %ld %s)\n",
                     in.c_str(), raw.size(), expect, width, height, type.c_str());
        return 1;
    }
    std::vector<double> values = type == "int16"    ? decode<int16_t, uint16_t>(raw)
                                 : type == "uint16" ? decode<uint16_t, uint16_t>(raw)
                                                    : decode<float, uint32_t>(raw);
    try {
        ct_host::write_geotiff(out, (int)width, (int)height, values, st, geo, has_nodata, nodata);
    } catch (const ct_host::Error &e) {
        std::fprintf(stderr, "ct_raw_to_geotiff: %s\n", e.what());
        return 1;
    }
    return 0;
}
