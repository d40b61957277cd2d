// test_dem_io.cpp -- read_dem() / write_geotiff(): round trips, native sample
// formats, PixelIsPoint, non-TIFF input, error handling, the real-DEM fixture.

#include "dem_io.hpp"
#include "harness.h"
#include "tiff_bytes.hpp"

#include <OpenImageIO/imageio.h>
#include <geotiffio.h>
#include <geovalues.h>
#include <tiffio.h>
#include <xtiffio.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#ifndef CT_FIXTURES_DIR
#error "CT_FIXTURES_DIR must be defined"
#endif

namespace fs = std::filesystem;
using ct_host::DemRaster;
using ct_host::Error;
using ct_host::Georef;
using ct_host::SampleType;

static std::string g_dir;  // per-run scratch directory

static std::string tmp_path(const char *name) { return g_dir + "/" + name; }

static bool verbose() { return getenv("CT_TEST_VERBOSE") != nullptr; }

// Count leftover temporaries of write_geotiff in a directory.
static int count_temporaries(const std::string &dir)
{
    int n = 0;
    for (const auto &e : fs::directory_iterator(dir))
        if (e.path().filename().string().find(".tmp-") != std::string::npos) n++;
    return n;
}

// Expect `expr` to throw ct_host::Error whose one-line message starts with
// "<path>: " and contains `needle` (may be "").
#define EXPECT_DEM_ERROR(expr, path, needle)                                                   \
    do {                                                                                       \
        std::string msg_;                                                                      \
        bool threw_ = false;                                                                   \
        try {                                                                                  \
            expr;                                                                              \
        } catch (const Error &ex_) {                                                           \
            threw_ = true;                                                                     \
            msg_ = ex_.what();                                                                 \
        } catch (const std::exception &ex_) {                                                  \
            TEST_FAIL_MSG("%s threw a non-ct_host::Error: %s", #expr, ex_.what());             \
        }                                                                                      \
        TEST_ASSERT_MSG(threw_, "%s did not throw", #expr);                                    \
        if (verbose()) printf("  [message] %s\n", msg_.c_str());                               \
        const std::string pfx_ = std::string(path) + ": ";                                     \
        TEST_ASSERT_MSG(msg_.compare(0, pfx_.size(), pfx_) == 0,                               \
                        "message does not start with the path: '%s'", msg_.c_str());           \
        TEST_ASSERT_MSG(msg_.find('\n') == std::string::npos, "multi-line message: '%s'",      \
                        msg_.c_str());                                                         \
        TEST_ASSERT_MSG(msg_.find(needle) != std::string::npos, "message '%s' lacks '%s'",     \
                        msg_.c_str(), needle);                                                 \
    } while (0)

// Redirect fd 2 to a file while alive; finish() restores it and returns what
// was written.
struct StderrCapture {
    int saved = -1;
    std::string file;
    explicit StderrCapture(const std::string &f) : file(f)
    {
        fflush(stderr);
        saved = dup(2);
        int fd = open(f.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
        dup2(fd, 2);
        close(fd);
    }
    std::string finish()
    {
        if (saved < 0) return std::string();
        fflush(stderr);
        dup2(saved, 2);
        close(saved);
        saved = -1;
        std::ifstream in(file);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    }
    ~StderrCapture() { finish(); }
};

// ---------------------------------------------------------------------------
// A TIFF written directly with libtiff + libgeotiff, for the cases
// write_geotiff() deliberately cannot produce.

struct RawTiff {
    int width = 0, height = 0;
    uint16_t bits = 16, sample_format = SAMPLEFORMAT_INT, spp = 1;
    std::vector<unsigned char> data;  // native order, row-major, contiguous
    std::vector<double> scale, ties, xform;
    int raster_type = 0;  // 0: key not written
    int projected_epsg = 0, geographic_epsg = 0;
    const char *nodata = nullptr;
};

static bool write_raw_tiff(const std::string &path, const RawTiff &r)
{
    TIFF *t = XTIFFOpen(path.c_str(), "w");
    if (!t) return false;
    bool ok = TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)r.width) &&
              TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)r.height) &&
              TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, r.spp) &&
              TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, r.bits) &&
              TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, r.sample_format) &&
              TIFFSetField(t, TIFFTAG_PHOTOMETRIC,
                           (uint16_t)(r.spp == 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK)) &&
              TIFFSetField(t, TIFFTAG_PLANARCONFIG, (uint16_t)PLANARCONFIG_CONTIG) &&
              TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, (uint32_t)r.height);
    if (ok && !r.scale.empty())
        ok = TIFFSetField(t, TIFFTAG_GEOPIXELSCALE, (uint16_t)r.scale.size(), r.scale.data());
    if (ok && !r.ties.empty())
        ok = TIFFSetField(t, TIFFTAG_GEOTIEPOINTS, (uint16_t)r.ties.size(), r.ties.data());
    if (ok && !r.xform.empty())
        ok = TIFFSetField(t, TIFFTAG_GEOTRANSMATRIX, (uint16_t)r.xform.size(), r.xform.data());
    if (ok && r.nodata) {
        // GDAL_NODATA is not a libtiff/libgeotiff tag; register it here.
        static char name[] = "GDALNoDataValue";
        static const TIFFFieldInfo info[] = {
            {42113, TIFF_VARIABLE, TIFF_VARIABLE, TIFF_ASCII, FIELD_CUSTOM, 1, 0, name}};
        TIFFMergeFieldInfo(t, info, 1);
        ok = TIFFSetField(t, 42113, r.nodata);
    }
    if (ok && (r.raster_type || r.projected_epsg || r.geographic_epsg)) {
        GTIF *g = GTIFNew(t);
        ok = g != nullptr;
        if (ok && r.raster_type)
            ok = GTIFKeySet(g, GTRasterTypeGeoKey, TYPE_SHORT, 1, r.raster_type);
        if (ok && r.projected_epsg)
            ok = GTIFKeySet(g, GTModelTypeGeoKey, TYPE_SHORT, 1, (int)ModelTypeProjected) &&
                 GTIFKeySet(g, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, r.projected_epsg);
        if (ok && r.geographic_epsg)
            ok = GTIFKeySet(g, GTModelTypeGeoKey, TYPE_SHORT, 1, (int)ModelTypeGeographic) &&
                 GTIFKeySet(g, GeographicTypeGeoKey, TYPE_SHORT, 1, r.geographic_epsg);
        if (ok) ok = GTIFWriteKeys(g);
        if (g) GTIFFree(g);
    }
    if (ok)
        ok = TIFFWriteEncodedStrip(t, 0, (void *)r.data.data(), (tmsize_t)r.data.size()) ==
             (tmsize_t)r.data.size();
    XTIFFClose(t);
    return ok;
}

template <typename T>
static std::vector<unsigned char> bytes_of(const std::vector<T> &v)
{
    std::vector<unsigned char> b(v.size() * sizeof(T));
    memcpy(b.data(), v.data(), b.size());
    return b;
}

// A small int16 raster with square 5 m posting and no georeference yet.
static RawTiff small_int16(int w, int h)
{
    RawTiff r;
    r.width = w, r.height = h;
    std::vector<int16_t> v((size_t)w * h);
    for (size_t k = 0; k < v.size(); k++) v[k] = (int16_t)(100 + 7 * (int)k);
    r.data = bytes_of(v);
    return r;
}

// ---------------------------------------------------------------------------
// write/read round trips

static void test_roundtrip_int16(void)
{
    const int w = 13, h = 7;
    std::vector<double> v((size_t)w * h);
    for (size_t k = 0; k < v.size(); k++) v[k] = (double)((int)(k * 2749 % 65535) - 32767) + 0.25;
    v[0] = -32768, v[1] = 32767, v[2] = 2.5, v[3] = -2.5, v[4] = NAN, v[5] = -9999, v[6] = 1.49;
    v[7] = -9998.6;  // rounds onto nodata
    Georef g;
    g.origin_e = 500010.5, g.origin_n = 4100020.25, g.posting_e = 10, g.posting_n = -10;
    g.epsg = 32633;
    const std::string p = tmp_path("rt_int16.tif");
    try {
        ct_host::write_geotiff(p, w, h, v, SampleType::Int16, g, true, -9999);
    } catch (const Error &e) {
        TEST_FAIL_MSG("write_geotiff: %s", e.what());
    }
    DemRaster r;
    try {
        r = ct_host::read_dem(p);
    } catch (const Error &e) {
        TEST_FAIL_MSG("read_dem: %s", e.what());
    }
    TEST_ASSERT_EQUAL_INT(w, r.width);
    TEST_ASSERT_EQUAL_INT(h, r.height);
    TEST_ASSERT(r.sample_type == "int16");
    TEST_ASSERT(r.has_georef);
    TEST_ASSERT(r.has_nodata);
    TEST_ASSERT_DOUBLE_WITHIN(0, -9999, r.nodata);
    TEST_ASSERT_DOUBLE_WITHIN(0, 500010.5, r.geo.origin_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, 4100020.25, r.geo.origin_n);
    TEST_ASSERT_DOUBLE_WITHIN(0, 10, r.geo.posting_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, -10, r.geo.posting_n);
    TEST_ASSERT_EQUAL_INT(32633, r.geo.epsg);
    TEST_ASSERT_EQUAL_UINT64(v.size(), r.h.size());
    TEST_ASSERT_EQUAL_UINT64(v.size(), r.valid.size());
    TEST_ASSERT_DOUBLE_WITHIN(0, 3, r.h[2]);
    TEST_ASSERT_DOUBLE_WITHIN(0, -3, r.h[3]);
    TEST_ASSERT_DOUBLE_WITHIN(0, 1, r.h[6]);
    for (size_t k = 0; k < v.size(); k++) {
        const double e = std::isnan(v[k]) ? -9999.0 : std::round(v[k]);
        TEST_ASSERT_MSG(r.h[k] == e, "sample %zu: expected %g, got %g", k, e, r.h[k]);
        TEST_ASSERT_MSG(r.valid[k] == (e != -9999.0 ? 1 : 0), "valid[%zu] = %d", k, r.valid[k]);
    }
    TEST_ASSERT_EQUAL_INT(0, r.valid[4]);
    TEST_ASSERT_EQUAL_INT(0, r.valid[5]);
    TEST_ASSERT_EQUAL_INT(0, r.valid[7]);
    TEST_ASSERT_EQUAL_INT(0, count_temporaries(g_dir));
}

static void test_roundtrip_uint16(void)
{
    const int w = 31, h = 17;
    std::vector<double> v((size_t)w * h);
    for (size_t k = 0; k < v.size(); k++) v[k] = (double)(k * 40503 % 65536);
    v[0] = 0, v[1] = 65535, v[2] = 65534.6, v[3] = 0.4, v[4] = 300.5;
    Georef g;
    g.origin_e = 0.0, g.origin_n = 0.0, g.posting_e = 2, g.posting_n = -2;
    g.epsg = 3857;
    const std::string p = tmp_path("rt_uint16.tif");
    DemRaster r;
    try {
        ct_host::write_geotiff(p, w, h, v, SampleType::UInt16, g, true, 65535);
        r = ct_host::read_dem(p);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT_EQUAL_INT(w, r.width);
    TEST_ASSERT_EQUAL_INT(h, r.height);
    TEST_ASSERT(r.sample_type == "uint16");
    TEST_ASSERT(r.has_georef);
    TEST_ASSERT(r.has_nodata);
    TEST_ASSERT_DOUBLE_WITHIN(0, 65535, r.nodata);
    TEST_ASSERT_DOUBLE_WITHIN(0, 0, r.geo.origin_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, 0, r.geo.origin_n);
    TEST_ASSERT_DOUBLE_WITHIN(0, 2, r.geo.posting_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, -2, r.geo.posting_n);
    TEST_ASSERT_EQUAL_INT(3857, r.geo.epsg);
    for (size_t k = 0; k < v.size(); k++) {
        const double e = std::round(v[k]);
        TEST_ASSERT_MSG(r.h[k] == e, "sample %zu: expected %g, got %g", k, e, r.h[k]);
        TEST_ASSERT_MSG(r.valid[k] == (e != 65535.0 ? 1 : 0), "valid[%zu] = %d", k, r.valid[k]);
    }
    TEST_ASSERT_DOUBLE_WITHIN(0, 301, r.h[4]);
    TEST_ASSERT_EQUAL_INT(0, r.valid[1]);
    TEST_ASSERT_EQUAL_INT(0, r.valid[2]);
}

static void test_roundtrip_float32(void)
{
    const int w = 64, h = 33;  // several strips are not needed; odd sizes are
    std::vector<double> v((size_t)w * h);
    ct_rng rng;
    ct_rng_seed(&rng, ct_test_seed());
    for (size_t k = 0; k < v.size(); k++) v[k] = ct_rng_unit(&rng) * 4000.0 - 450.0;
    const double nd = -32767.25;
    v[0] = NAN, v[1] = nd, v[2] = 1e-30, v[3] = -(double)FLT_MAX, v[4] = 8848.86;
    v[5] = nd + 1e-9;  // rounds to the same float as the nodata value
    Georef g;
    g.origin_e = -12345.5, g.origin_n = 678.0, g.posting_e = 0.5, g.posting_n = -0.5;
    g.epsg = 0;
    const std::string p = tmp_path("rt_float32.tif");
    DemRaster r;
    try {
        ct_host::write_geotiff(p, w, h, v, SampleType::Float32, g, true, nd);
        r = ct_host::read_dem(p);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT_EQUAL_INT(w, r.width);
    TEST_ASSERT_EQUAL_INT(h, r.height);
    TEST_ASSERT(r.sample_type == "float32");
    TEST_ASSERT(r.has_georef);
    TEST_ASSERT(r.has_nodata);
    TEST_ASSERT_DOUBLE_WITHIN(0, nd, r.nodata);
    TEST_ASSERT_DOUBLE_WITHIN(0, -12345.5, r.geo.origin_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, 678.0, r.geo.origin_n);
    TEST_ASSERT_DOUBLE_WITHIN(0, 0.5, r.geo.posting_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, -0.5, r.geo.posting_n);
    TEST_ASSERT_EQUAL_INT(0, r.geo.epsg);
    TEST_ASSERT(std::isnan(r.h[0]));
    for (size_t k = 1; k < v.size(); k++) {
        const double e = (double)(float)v[k];
        TEST_ASSERT_MSG(r.h[k] == e, "sample %zu: expected %.9g, got %.9g", k, e, r.h[k]);
        const int ev = (float)v[k] == (float)nd ? 0 : 1;
        TEST_ASSERT_MSG(r.valid[k] == ev, "valid[%zu] = %d", k, r.valid[k]);
    }
    TEST_ASSERT_EQUAL_INT(0, r.valid[0]);
    TEST_ASSERT_EQUAL_INT(0, r.valid[1]);
    TEST_ASSERT_EQUAL_INT(0, r.valid[5]);
    TEST_ASSERT_EQUAL_INT(1, r.valid[3]);
}

static void test_roundtrip_without_nodata(void)
{
    const int w = 3, h = 2;
    std::vector<double> v = {1, 2, 3, 4, 5, 6};
    Georef g;
    g.origin_e = 100, g.origin_n = 200, g.posting_e = 1, g.posting_n = -1, g.epsg = 32617;
    const std::string p = tmp_path("rt_nonodata.tif");
    DemRaster r;
    try {
        ct_host::write_geotiff(p, w, h, v, SampleType::Int16, g);
        r = ct_host::read_dem(p);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT_FALSE(r.has_nodata);
    for (size_t k = 0; k < v.size(); k++) {
        TEST_ASSERT_DOUBLE_WITHIN(0, v[k], r.h[k]);
        TEST_ASSERT_EQUAL_INT(1, r.valid[k]);
    }
    // NaN cannot be stored in an integer raster without a nodata value
    v[3] = NAN;
    const std::string q = tmp_path("rt_nan_int.tif");
    EXPECT_DEM_ERROR(ct_host::write_geotiff(q, w, h, v, SampleType::Int16, g), q, "NaN");
    TEST_ASSERT_FALSE(fs::exists(q));
}

// ---------------------------------------------------------------------------
// georeference variants written with libgeotiff directly

static void test_pixel_is_point(void)
{
    RawTiff t = small_int16(4, 3);
    t.scale = {5, 5, 0};
    t.ties = {0, 0, 0, 1000, 2000, 0};
    t.raster_type = RasterPixelIsPoint;
    t.projected_epsg = 32633;
    const std::string p = tmp_path("point.tif");
    TEST_ASSERT(write_raw_tiff(p, t));
    DemRaster r;
    try {
        r = ct_host::read_dem(p);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT(r.has_georef);
    // tiepoint = centre of pixel (0,0): corner is half a post up and left
    TEST_ASSERT_DOUBLE_WITHIN(0, 997.5, r.geo.origin_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, 2002.5, r.geo.origin_n);
    TEST_ASSERT_DOUBLE_WITHIN(0, 5, r.geo.posting_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, -5, r.geo.posting_n);
    TEST_ASSERT_EQUAL_INT(32633, r.geo.epsg);
    TEST_ASSERT(r.sample_type == "int16");
    TEST_ASSERT_DOUBLE_WITHIN(0, 100 + 7 * 11, r.h[11]);

    // the same grid as PixelIsArea: no shift
    t.raster_type = RasterPixelIsArea;
    const std::string q = tmp_path("area.tif");
    TEST_ASSERT(write_raw_tiff(q, t));
    try {
        r = ct_host::read_dem(q);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT_DOUBLE_WITHIN(0, 1000, r.geo.origin_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, 2000, r.geo.origin_n);
}

static void test_georef_variants(void)
{
    DemRaster r;
    // tiepoint away from pixel (0,0), no GTRasterTypeGeoKey (defaults to area)
    RawTiff t = small_int16(6, 5);
    t.scale = {5, 5, 0};
    t.ties = {2, 3, 0, 1000, 2000, 0};
    const std::string p1 = tmp_path("tie23.tif");
    TEST_ASSERT(write_raw_tiff(p1, t));
    try {
        r = ct_host::read_dem(p1);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT(r.has_georef);
    TEST_ASSERT_DOUBLE_WITHIN(0, 1000 - 2 * 5, r.geo.origin_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, 2000 + 3 * 5, r.geo.origin_n);
    TEST_ASSERT_EQUAL_INT(0, r.geo.epsg);

    // axis-aligned ModelTransformation, PixelIsPoint
    t.scale.clear();
    t.ties.clear();
    t.xform = {5, 0, 0, 1000, 0, -5, 0, 2000, 0, 0, 0, 0, 0, 0, 0, 1};
    t.raster_type = RasterPixelIsPoint;
    const std::string p2 = tmp_path("xform_point.tif");
    TEST_ASSERT(write_raw_tiff(p2, t));
    try {
        r = ct_host::read_dem(p2);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT(r.has_georef);
    TEST_ASSERT_DOUBLE_WITHIN(0, 997.5, r.geo.origin_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, 2002.5, r.geo.origin_n);
    TEST_ASSERT_DOUBLE_WITHIN(0, 5, r.geo.posting_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, -5, r.geo.posting_n);

    // geographic CRS: the EPSG code comes from GeographicTypeGeoKey
    t.xform.clear();
    t.scale = {0.001, 0.001, 0};
    t.ties = {0, 0, 0, -84.4, 36.7, 0};
    t.raster_type = RasterPixelIsArea;
    t.geographic_epsg = 4326;
    const std::string p3 = tmp_path("geographic.tif");
    TEST_ASSERT(write_raw_tiff(p3, t));
    try {
        r = ct_host::read_dem(p3);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT_EQUAL_INT(4326, r.geo.epsg);
    TEST_ASSERT_DOUBLE_WITHIN(1e-12, -84.4, r.geo.origin_e);
    TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0.001, r.geo.posting_e);

    // a plain TIFF: pixels, no georeference, no error
    RawTiff plain = small_int16(3, 3);
    const std::string p4 = tmp_path("plain.tif");
    TEST_ASSERT(write_raw_tiff(p4, plain));
    try {
        r = ct_host::read_dem(p4);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT_FALSE(r.has_georef);
    TEST_ASSERT_FALSE(r.has_nodata);
    TEST_ASSERT_EQUAL_INT(0, r.geo.epsg);
    TEST_ASSERT_DOUBLE_WITHIN(0, 100 + 7 * 8, r.h[8]);
}

// Every supported native sample type is read without rescaling.
static void test_native_sample_types(void)
{
    struct Case {
        const char *name;
        uint16_t bits, fmt;
        std::vector<unsigned char> data;
        std::vector<double> expect;
        const char *nodata;
    };
    std::vector<Case> cases;
    cases.push_back({"int8", 8, SAMPLEFORMAT_INT, bytes_of(std::vector<int8_t>{-128, -1, 0, 127}),
                     {-128, -1, 0, 127}, "-128"});
    cases.push_back({"uint8", 8, SAMPLEFORMAT_UINT, bytes_of(std::vector<uint8_t>{0, 1, 200, 255}),
                     {0, 1, 200, 255}, "0"});
    cases.push_back({"int32", 32, SAMPLEFORMAT_INT,
                     bytes_of(std::vector<int32_t>{-2147483647 - 1, -2000000000, 70000, 2147483647}),
                     {-2147483648.0, -2000000000, 70000, 2147483647}, "-2147483648"});
    cases.push_back({"uint32", 32, SAMPLEFORMAT_UINT,
                     bytes_of(std::vector<uint32_t>{0, 65536, 4000000000u, 4294967295u}),
                     {0, 65536, 4000000000.0, 4294967295.0}, nullptr});
    cases.push_back({"float64", 64, SAMPLEFORMAT_IEEEFP,
                     bytes_of(std::vector<double>{1234.5678901234567, -1e300, NAN, -9999}),
                     {1234.5678901234567, -1e300, NAN, -9999}, "-9999"});
    for (const Case &c : cases) {
        RawTiff t;
        t.width = 2, t.height = 2, t.bits = c.bits, t.sample_format = c.fmt, t.data = c.data;
        t.scale = {1, 1, 0};
        t.ties = {0, 0, 0, 0, 0, 0};
        t.nodata = c.nodata;
        const std::string p = tmp_path((std::string("native_") + c.name + ".tif").c_str());
        TEST_ASSERT(write_raw_tiff(p, t));
        DemRaster r;
        try {
            r = ct_host::read_dem(p);
        } catch (const Error &e) {
            TEST_FAIL_MSG("%s: %s", c.name, e.what());
        }
        TEST_ASSERT_MSG(r.sample_type == c.name, "expected %s, got %s", c.name, r.sample_type.c_str());
        TEST_ASSERT_EQUAL_INT(c.nodata != nullptr, r.has_nodata);
        for (size_t k = 0; k < 4; k++) {
            const double e = c.expect[k];
            if (std::isnan(e)) {
                TEST_ASSERT_MSG(std::isnan(r.h[k]), "%s[%zu]: expected NaN", c.name, k);
                TEST_ASSERT_EQUAL_INT(0, r.valid[k]);
                continue;
            }
            TEST_ASSERT_MSG(r.h[k] == e, "%s[%zu]: expected %.17g, got %.17g", c.name, k, e, r.h[k]);
            const bool is_nd = c.nodata && e == atof(c.nodata);
            TEST_ASSERT_MSG(r.valid[k] == (is_nd ? 0 : 1), "%s: valid[%zu] = %d", c.name, k, r.valid[k]);
        }
    }
}

// A 16-bit PNG (written through OIIO): native uint16, values above 255 kept
// exactly, no georeference.
static void test_png16(void)
{
    const int w = 5, h = 4;
    std::vector<uint16_t> px((size_t)w * h);
    for (size_t k = 0; k < px.size(); k++) px[k] = (uint16_t)(k * 3271 + 17);
    px[0] = 0, px[1] = 255, px[2] = 256, px[3] = 1000, px[4] = 40000, px[5] = 65535;
    const std::string p = tmp_path("gray16.png");
    {
        auto out = OIIO::ImageOutput::create(p);
        TEST_ASSERT(out != nullptr);
        OIIO::ImageSpec spec(w, h, 1, OIIO::TypeDesc::UINT16);
        TEST_ASSERT(out->open(p, spec));
        TEST_ASSERT(out->write_image(OIIO::TypeDesc::UINT16, px.data()));
        TEST_ASSERT(out->close());
    }
    DemRaster r;
    try {
        r = ct_host::read_dem(p);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT_EQUAL_INT(w, r.width);
    TEST_ASSERT_EQUAL_INT(h, r.height);
    TEST_ASSERT(r.sample_type == "uint16");
    TEST_ASSERT_FALSE(r.has_georef);
    TEST_ASSERT_FALSE(r.has_nodata);
    for (size_t k = 0; k < px.size(); k++) {
        TEST_ASSERT_MSG(r.h[k] == (double)px[k], "sample %zu: expected %u, got %g", k,
                        (unsigned)px[k], r.h[k]);
        TEST_ASSERT_EQUAL_INT(1, r.valid[k]);
    }
}

// ---------------------------------------------------------------------------
// DemRows (a mosaic's reader) over tiled TIFFs: rows read tile by tile,
// partial tiles at the right and bottom edges, starts within a tile row

static void test_rows_tiled(void)
{
    const uint32_t W = 100, H = 75, T = 32;  // 4 x 3 tiles, the last column and row partial
    for (int deflate = 0; deflate < 2; ++deflate) {
        const std::string path = tmp_path(deflate ? "rows_tiled_z.tif" : "rows_tiled.tif");
        TIFF *t = XTIFFOpen(path.c_str(), "w");
        TEST_ASSERT(t != nullptr);
        TEST_ASSERT(TIFFSetField(t, TIFFTAG_IMAGEWIDTH, W) && TIFFSetField(t, TIFFTAG_IMAGELENGTH, H) &&
                    TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1) &&
                    TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, (uint16_t)16) &&
                    TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, (uint16_t)SAMPLEFORMAT_INT) &&
                    TIFFSetField(t, TIFFTAG_PHOTOMETRIC, (uint16_t)PHOTOMETRIC_MINISBLACK) &&
                    TIFFSetField(t, TIFFTAG_PLANARCONFIG, (uint16_t)PLANARCONFIG_CONTIG) &&
                    TIFFSetField(t, TIFFTAG_COMPRESSION,
                                 (uint16_t)(deflate ? COMPRESSION_ADOBE_DEFLATE : COMPRESSION_NONE)) &&
                    TIFFSetField(t, TIFFTAG_TILEWIDTH, T) && TIFFSetField(t, TIFFTAG_TILELENGTH, T));
        // post (i, j) = (37 i + 101 j) % 4001 - 2000; a tile's posts past the
        // image's edge hold 30000, which must never be read
        for (uint32_t ty = 0; ty < H; ty += T)
            for (uint32_t tx = 0; tx < W; tx += T) {
                std::vector<int16_t> px((size_t)T * T, (int16_t)30000);
                for (uint32_t v = 0; v < T && ty + v < H; ++v)
                    for (uint32_t u = 0; u < T && tx + u < W; ++u)
                        px[(size_t)v * T + u] = (int16_t)((37 * (tx + u) + 101 * (ty + v)) % 4001 - 2000);
                TEST_ASSERT(TIFFWriteTile(t, px.data(), tx, ty, 0, 0) > 0);
            }
        XTIFFClose(t);
        ct_host::DemRows rows(path);
        TEST_ASSERT_EQUAL_INT((int)W, rows.header().width);
        TEST_ASSERT_EQUAL_INT((int)H, rows.header().height);
        const int spans[][2] = {{0, 75}, {0, 1}, {31, 2}, {32, 32}, {33, 40}, {74, 1}, {10, 65}, {64, 11}};
        std::vector<double> h;
        std::vector<uint8_t> valid;
        for (const auto &sp : spans) {
            rows.read(sp[0], sp[1], h, valid);
            TEST_ASSERT_EQUAL_INT(sp[1] * (int)W, (int)h.size());
            for (int j = 0; j < sp[1]; ++j)
                for (int i = 0; i < (int)W; ++i) {
                    const double want = (double)((37 * i + 101 * (sp[0] + j)) % 4001 - 2000);
                    TEST_ASSERT_MSG(h[(size_t)j * W + i] == want, "%s rows %d+%d: post (%d, %d) = %g, expected %g",
                                    path.c_str(), sp[0], sp[1], i, sp[0] + j, h[(size_t)j * W + i], want);
                }
        }
    }
}

// ---------------------------------------------------------------------------
// errors

// A TIFF of w x h float32 posts, deflated, in tiles of tw x th posts (one
// tile: its offset and a 16-byte count).
static bool write_tiled_header(const std::string &path, uint32_t w, uint32_t h, uint32_t tw, uint32_t th)
{
    const std::string b = tiff_bytes::make({{256, 4, w}, {257, 4, h}, {258, 3, 32}, {259, 3, 8}, {262, 3, 1},
                                            {277, 3, 1}, {284, 3, 1}, {322, 4, tw}, {323, 4, th},
                                            {324, 4, tiff_bytes::kData}, {325, 4, 16}, {339, 3, 3}},
                                           std::string(16, '\x5a'));
    std::ofstream f(path, std::ios::binary);
    f.write(b.data(), (std::streamsize)b.size());
    return (bool)f;
}

static void test_read_errors(void)
{
    StderrCapture cap(tmp_path("stderr_read.txt"));

    const std::string missing = tmp_path("does_not_exist.tif");
    EXPECT_DEM_ERROR(ct_host::read_dem(missing), missing, "No such file");

    EXPECT_DEM_ERROR(ct_host::read_dem(g_dir), g_dir, "directory");

    // tiles far larger than the image (fuzz_host's finding: OpenImageIO
    // allocates a whole tile, 7.6 GB here, before reading a byte of it)
    const std::string huge_tiles = tmp_path("huge_tiles.tif");
    TEST_ASSERT(write_tiled_header(huge_tiles, 8, 8, 28944, 65520));
    EXPECT_DEM_ERROR(ct_host::read_dem(huge_tiles), huge_tiles, "tiles of 28944 x 65520 posts for a 8 x 8 image");
    EXPECT_DEM_ERROR(ct_host::DemRows rows(huge_tiles), huge_tiles, "tiles of 28944 x 65520 posts");
    // tiles of 256 x 256 for a 8 x 8 image are ordinary: read (the data
    // itself is garbage here, so the error is the decoder's, not the tiles')
    const std::string small_tiles = tmp_path("small_tiles.tif");
    TEST_ASSERT(write_tiled_header(small_tiles, 8, 8, 256, 256));
    try {
        (void)ct_host::read_dem(small_tiles);
    } catch (const Error &ex) {
        TEST_ASSERT_MSG(std::string(ex.what()).find("tiles of") == std::string::npos, "%s", ex.what());
    }

    const std::string garbage = tmp_path("garbage.tif");
    {
        std::ofstream f(garbage, std::ios::binary);
        ct_rng rng;
        ct_rng_seed(&rng, 7);
        for (int k = 0; k < 4096; k++) f.put((char)(ct_rng_u64(&rng) & 0xff));
    }
    EXPECT_DEM_ERROR(ct_host::read_dem(garbage), garbage, "");

    // a real GeoTIFF whose compressed pixel data is overwritten
    const std::string full = tmp_path("to_corrupt.tif");
    const std::string cut = tmp_path("corrupt.tif");
    {
        std::vector<double> v(200 * 100);
        for (size_t k = 0; k < v.size(); k++) v[k] = (double)(k % 5000);
        Georef g;
        ct_host::write_geotiff(full, 200, 100, v, SampleType::Float32, g);
        std::ifstream in(full, std::ios::binary);
        std::vector<char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        // keep the header and the directory (written at the end by libtiff) but
        // overwrite the first half of the deflate streams
        std::fill(b.begin() + 16, b.begin() + (ptrdiff_t)(b.size() / 2), (char)0x5a);
        std::ofstream out(cut, std::ios::binary);
        out.write(b.data(), (std::streamsize)b.size());
    }
    EXPECT_DEM_ERROR(ct_host::read_dem(cut), cut, "");

    // three channels (PNG via OIIO, and an RGB TIFF)
    const std::string rgb_png = tmp_path("rgb.png");
    {
        auto out = OIIO::ImageOutput::create(rgb_png);
        TEST_ASSERT(out != nullptr);
        OIIO::ImageSpec spec(4, 3, 3, OIIO::TypeDesc::UINT8);
        std::vector<uint8_t> px(4 * 3 * 3, 77);
        TEST_ASSERT(out->open(rgb_png, spec));
        TEST_ASSERT(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
        TEST_ASSERT(out->close());
    }
    EXPECT_DEM_ERROR(ct_host::read_dem(rgb_png), rgb_png, "3 channels");
    const std::string rgb_tif = tmp_path("rgb.tif");
    {
        RawTiff t;
        t.width = 2, t.height = 2, t.bits = 8, t.sample_format = SAMPLEFORMAT_UINT, t.spp = 3;
        t.data.assign(12, 9);
        TEST_ASSERT(write_raw_tiff(rgb_tif, t));
    }
    EXPECT_DEM_ERROR(ct_host::read_dem(rgb_tif), rgb_tif, "3 channels");

    // non-square posting
    const std::string nonsq = tmp_path("nonsquare.tif");
    {
        RawTiff t = small_int16(4, 4);
        t.scale = {30, 20, 0};
        t.ties = {0, 0, 0, 1000, 2000, 0};
        t.projected_epsg = 32617;
        TEST_ASSERT(write_raw_tiff(nonsq, t));
    }
    EXPECT_DEM_ERROR(ct_host::read_dem(nonsq), nonsq, "non-square posting (30 x 20)");

    // rotated model transformation
    const std::string rot = tmp_path("rotated.tif");
    {
        RawTiff t = small_int16(4, 4);
        const double c = 30 * std::cos(0.1), s = 30 * std::sin(0.1);
        t.xform = {c, -s, 0, 1000, s, c, 0, 2000, 0, 0, 0, 0, 0, 0, 0, 1};
        TEST_ASSERT(write_raw_tiff(rot, t));
    }
    EXPECT_DEM_ERROR(ct_host::read_dem(rot), rot,
                     "rotated or sheared model transformation is not supported");

    // tiepoints only (ground control points)
    const std::string gcp = tmp_path("gcps.tif");
    {
        RawTiff t = small_int16(4, 4);
        t.ties = {0, 0, 0, 1000, 2000, 0, 3, 3, 0, 1090, 1910, 0};
        TEST_ASSERT(write_raw_tiff(gcp, t));
    }
    EXPECT_DEM_ERROR(ct_host::read_dem(gcp), gcp, "not supported");

    // unsupported sample format: half float
    const std::string half = tmp_path("half.tif");
    {
        RawTiff t;
        t.width = 2, t.height = 2, t.bits = 16, t.sample_format = SAMPLEFORMAT_IEEEFP;
        t.data.assign(8, 0);
        TEST_ASSERT(write_raw_tiff(half, t));
    }
    EXPECT_DEM_ERROR(ct_host::read_dem(half), half, "unsupported sample format");

    // 12-bit samples: OIIO would widen *and rescale* them to 16 bits
    const std::string b12 = tmp_path("bits12.tif");
    {
        RawTiff t;
        t.width = 4, t.height = 2, t.bits = 12, t.sample_format = SAMPLEFORMAT_UINT;
        t.data.assign(12, 0x31);
        TEST_ASSERT(write_raw_tiff(b12, t));
    }
    EXPECT_DEM_ERROR(ct_host::read_dem(b12), b12, "unsupported bit depth 12");

    // bad GDAL_NODATA text
    const std::string badnd = tmp_path("bad_nodata.tif");
    {
        RawTiff t = small_int16(2, 2);
        t.nodata = "minus one";
        TEST_ASSERT(write_raw_tiff(badnd, t));
    }
    EXPECT_DEM_ERROR(ct_host::read_dem(badnd), badnd, "GDAL_NODATA");

    const std::string err = cap.finish();
    TEST_ASSERT_MSG(err.empty(), "libraries wrote to stderr: %s", err.c_str());
}

static void test_write_errors(void)
{
    StderrCapture cap(tmp_path("stderr_write.txt"));
    const int w = 4, h = 3;
    std::vector<double> v((size_t)w * h, 10.0);
    Georef g;
    g.origin_e = 1000, g.origin_n = 2000, g.posting_e = 30, g.posting_n = -30, g.epsg = 32617;

    // into a directory that does not exist
    const std::string nodir = tmp_path("no/such/dir/out.tif");
    EXPECT_DEM_ERROR(ct_host::write_geotiff(nodir, w, h, v, SampleType::Int16, g), nodir,
                     "No such file");
    TEST_ASSERT_FALSE(fs::exists(nodir));
    TEST_ASSERT_FALSE(fs::exists(tmp_path("no")));

    // out of range: nothing is created
    const std::string p = tmp_path("range.tif");
    std::vector<double> bad = v;
    bad[5] = 40000;
    EXPECT_DEM_ERROR(ct_host::write_geotiff(p, w, h, bad, SampleType::Int16, g), p, "out of range");
    TEST_ASSERT_FALSE(fs::exists(p));
    bad[5] = -1;
    EXPECT_DEM_ERROR(ct_host::write_geotiff(p, w, h, bad, SampleType::UInt16, g), p, "out of range");
    bad[5] = 1e39;
    EXPECT_DEM_ERROR(ct_host::write_geotiff(p, w, h, bad, SampleType::Float32, g), p, "out of range");
    EXPECT_DEM_ERROR(ct_host::write_geotiff(p, w, h, v, SampleType::Int16, g, true, 1e6), p,
                     "nodata");
    EXPECT_DEM_ERROR(ct_host::write_geotiff(p, w + 1, h, v, SampleType::Int16, g), p, "samples");
    TEST_ASSERT_FALSE(fs::exists(p));

    // a failed write leaves an existing file untouched
    try {
        ct_host::write_geotiff(p, w, h, v, SampleType::Int16, g);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    bad = v;
    bad[0] = 1e9;
    EXPECT_DEM_ERROR(ct_host::write_geotiff(p, w, h, bad, SampleType::Int16, g), p, "out of range");
    DemRaster r;
    try {
        r = ct_host::read_dem(p);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    TEST_ASSERT_DOUBLE_WITHIN(0, 10, r.h[0]);

    // a path that is a directory: the rename fails, the temporary is removed
    const std::string dirpath = tmp_path("a_directory");
    fs::create_directory(dirpath);
    EXPECT_DEM_ERROR(ct_host::write_geotiff(dirpath, w, h, v, SampleType::Int16, g), dirpath,
                     "rename");
    TEST_ASSERT(fs::is_directory(dirpath));
    TEST_ASSERT_EQUAL_INT(0, count_temporaries(g_dir));

    const std::string err = cap.finish();
    TEST_ASSERT_MSG(err.empty(), "libraries wrote to stderr: %s", err.c_str());
}

// ---------------------------------------------------------------------------
// the real-DEM fixture

static void test_fixture_jacksboro(void)
{
    const std::string p = std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif";
    DemRaster r;
    try {
        r = ct_host::read_dem(p);
    } catch (const Error &e) {
        TEST_FAIL_MSG("%s", e.what());
    }
    // numpy: elevation.shape == (344, 403): 344 rows (height), 403 columns (width)
    TEST_ASSERT_EQUAL_INT(403, r.width);
    TEST_ASSERT_EQUAL_INT(344, r.height);
    TEST_ASSERT(r.sample_type == "int16");
    TEST_ASSERT(r.has_georef);
    TEST_ASSERT_FALSE(r.has_nodata);
    TEST_ASSERT_DOUBLE_WITHIN(0, 30, r.geo.posting_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, -30, r.geo.posting_n);
    TEST_ASSERT_EQUAL_INT(32617, r.geo.epsg);
    TEST_ASSERT_DOUBLE_WITHIN(0, 195000, r.geo.origin_e);
    TEST_ASSERT_DOUBLE_WITHIN(0, 4071000, r.geo.origin_n);

    double lo = 1e300, hi = -1e300, sum = 0;
    for (size_t k = 0; k < r.h.size(); k++) {
        TEST_ASSERT_EQUAL_INT(1, r.valid[k]);
        lo = std::min(lo, r.h[k]);
        hi = std::max(hi, r.h[k]);
        sum += r.h[k];
    }
    // These numbers come from the npz (numpy: z.min(), z.max(), z.sum(),
    // z[0,0], z[0,-1], z[-1,0], z[-1,-1]; mean 531.0311688499048).
    TEST_ASSERT_DOUBLE_WITHIN(0, 236, lo);
    TEST_ASSERT_DOUBLE_WITHIN(0, 1076, hi);
    TEST_ASSERT_DOUBLE_WITHIN(0, 73617913, sum);
    TEST_ASSERT_DOUBLE_WITHIN(1e-9, 531.0311688499048, sum / (double)r.h.size());
    const size_t W = 403, H = 344;
    TEST_ASSERT_DOUBLE_WITHIN(0, 483, r.h[0]);
    TEST_ASSERT_DOUBLE_WITHIN(0, 444, r.h[W - 1]);
    TEST_ASSERT_DOUBLE_WITHIN(0, 545, r.h[(H - 1) * W]);
    TEST_ASSERT_DOUBLE_WITHIN(0, 272, r.h[H * W - 1]);
}

int main(void)
{
    char tmpl[4096];
    const char *base = getenv("TMPDIR");
    snprintf(tmpl, sizeof tmpl, "%s/ct_test_dem_io_XXXXXX", base && *base ? base : "/tmp");
    if (!mkdtemp(tmpl)) {
        perror("mkdtemp");
        return 1;
    }
    g_dir = tmpl;

    TEST_BEGIN("test_dem_io");
    RUN_TEST(test_roundtrip_int16);
    RUN_TEST(test_roundtrip_uint16);
    RUN_TEST(test_roundtrip_float32);
    RUN_TEST(test_roundtrip_without_nodata);
    RUN_TEST(test_pixel_is_point);
    RUN_TEST(test_georef_variants);
    RUN_TEST(test_native_sample_types);
    RUN_TEST(test_png16);
    RUN_TEST(test_rows_tiled);
    RUN_TEST(test_read_errors);
    RUN_TEST(test_write_errors);
    RUN_TEST(test_fixture_jacksboro);
    int rc = TEST_END();

    std::error_code ec;
    if (!getenv("CT_TEST_KEEP")) fs::remove_all(g_dir, ec);
    return rc;
}
