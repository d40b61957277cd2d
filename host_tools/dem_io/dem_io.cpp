// dem_io.cpp -- DEM rasters: pixels through OpenImageIO (dem_pixels.cpp; read
// in the file's native sample type, never rescaled), georeference through
// libtiff + libgeotiff, GeoTIFF writing through libtiff + libgeotiff.
//
// Diagnostics: libtiff messages produced on our handles go to per-handle
// handlers (libtiff >= 4.5, TIFFOpenOptions) and end up in the exception
// text; warnings are dropped.  Process-wide handlers (TIFFSetErrorHandler /
// TIFFSetWarningHandler) are installed once as a backstop for messages that
// carry no handle: while one of our calls is active on the thread they are
// captured, otherwise they are forwarded to whatever handler was installed
// before ours (OpenImageIO installs its own silent ones too).

#include "dem_io.hpp"
#include "temp_output.hpp"

#include <geotiffio.h>
#include <geovalues.h>
#include <tiffio.h>
#include <xtiffio.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <type_traits>

namespace ct_host {
namespace {

// ---------------------------------------------------------------------------
// message capture

std::string vformat(const char *fmt, va_list ap)
{
    if (!fmt) return std::string();
    char small[512];
    va_list ap2;
    va_copy(ap2, ap);
    int n = std::vsnprintf(small, sizeof small, fmt, ap2);
    va_end(ap2);
    if (n < 0) return std::string(fmt);
    if ((size_t)n < sizeof small) return std::string(small, (size_t)n);
    std::string big((size_t)n + 1, '\0');
    va_copy(ap2, ap);
    std::vsnprintf(&big[0], big.size(), fmt, ap2);
    va_end(ap2);
    big.resize((size_t)n);
    return big;
}

struct MsgSink {
    std::string errors;  // "module: message; module: message"
    void add(const char *module, const char *fmt, va_list ap)
    {
        std::string m = one_line(vformat(fmt, ap));
        if (module && *module) m = std::string(module) + ": " + m;
        if (!errors.empty()) {
            if (errors.size() > 600) return;  // enough detail already
            errors += "; ";
        }
        errors += m;
    }
    std::string text(const char *fallback) const { return errors.empty() ? fallback : errors; }
};

thread_local MsgSink *t_sink = nullptr;

struct SinkScope {
    MsgSink *prev;
    explicit SinkScope(MsgSink *s) : prev(t_sink) { t_sink = s; }
    ~SinkScope() { t_sink = prev; }
    SinkScope(const SinkScope &) = delete;
    SinkScope &operator=(const SinkScope &) = delete;
};

TIFFErrorHandler g_prev_error_handler = nullptr;
TIFFErrorHandler g_prev_warning_handler = nullptr;
TIFFExtendProc g_prev_extender = nullptr;

void global_tiff_error(const char *module, const char *fmt, va_list ap)
{
    if (t_sink)
        t_sink->add(module, fmt, ap);
    else if (g_prev_error_handler)
        g_prev_error_handler(module, fmt, ap);
}

void global_tiff_warning(const char *module, const char *fmt, va_list ap)
{
    if (t_sink) return;  // our own warnings are dropped
    if (g_prev_warning_handler) g_prev_warning_handler(module, fmt, ap);
}

#if TIFFLIB_VERSION >= 20221213  // libtiff 4.5.0: per-handle handlers
int handle_tiff_error(TIFF *, void *user, const char *module, const char *fmt, va_list ap)
{
    static_cast<MsgSink *>(user)->add(module, fmt, ap);
    return 1;  // handled: do not call the process-wide handlers
}
int handle_tiff_warning(TIFF *, void *, const char *, const char *, va_list) { return 1; }
#define CT_HAVE_TIFF_OPEN_OPTIONS 1
#endif

// libgeotiff diagnostics: errors captured, warnings dropped.
void geotiff_message(GTIF *gt, int level, const char *fmt, ...)
{
    if (level != LIBGEOTIFF_ERROR) return;
    MsgSink *sink = gt ? static_cast<MsgSink *>(GTIFGetUserData(gt)) : nullptr;
    if (!sink) sink = t_sink;
    if (!sink) return;
    va_list ap;
    va_start(ap, fmt);
    sink->add("libgeotiff", fmt, ap);
    va_end(ap);
}

// ---------------------------------------------------------------------------
// libtiff set-up: GeoTIFF tags (XTIFFInitialize), the GDAL_NODATA tag, and
// the backstop handlers.

constexpr uint32_t kTagGdalNodata = 42113;

void gdal_tag_extender(TIFF *tif)
{
    static char name[] = "GDALNoDataValue";
    static const TIFFFieldInfo info[] = {
        {kTagGdalNodata, TIFF_VARIABLE, TIFF_VARIABLE, TIFF_ASCII, FIELD_CUSTOM, 1, 0, name},
    };
    TIFFMergeFieldInfo(tif, info, 1);
    if (g_prev_extender) g_prev_extender(tif);
}

void tiff_init_once()
{
    static std::once_flag once;
    std::call_once(once, [] {
        XTIFFInitialize();  // registers the GeoTIFF tags (what XTIFFOpen does first)
        g_prev_extender = TIFFSetTagExtender(gdal_tag_extender);
        g_prev_error_handler = TIFFSetErrorHandler(global_tiff_error);
        g_prev_warning_handler = TIFFSetWarningHandler(global_tiff_warning);
    });
}

struct TiffCloser {
    void operator()(TIFF *t) const
    {
        if (t) XTIFFClose(t);
    }
};
using TiffPtr = std::unique_ptr<TIFF, TiffCloser>;

struct GtifFreer {
    void operator()(GTIF *g) const
    {
        if (g) GTIFFree(g);
    }
};
using GtifPtr = std::unique_ptr<GTIF, GtifFreer>;

// Open a TIFF with the GeoTIFF tags registered (equivalent to XTIFFOpen /
// XTIFFFdOpen) and errors routed to `sink` (which must outlive the handle).
TIFF *open_tiff(const std::string &name, const char *mode, MsgSink &sink, int fd = -1)
{
    tiff_init_once();
#ifdef CT_HAVE_TIFF_OPEN_OPTIONS
    TIFFOpenOptions *opts = TIFFOpenOptionsAlloc();
    if (!opts) return nullptr;
    TIFFOpenOptionsSetErrorHandlerExtR(opts, handle_tiff_error, &sink);
    TIFFOpenOptionsSetWarningHandlerExtR(opts, handle_tiff_warning, nullptr);
    TIFF *t = fd >= 0 ? TIFFFdOpenExt(fd, name.c_str(), mode, opts)
                      : TIFFOpenExt(name.c_str(), mode, opts);
    TIFFOpenOptionsFree(opts);
    return t;
#else
    (void)sink;  // messages reach it through t_sink and the global handlers
    return fd >= 0 ? XTIFFFdOpen(fd, name.c_str(), mode) : XTIFFOpen(name.c_str(), mode);
#endif
}

// A double-array tag (ModelPixelScale, ModelTiepoint, ModelTransformation).
std::vector<double> get_doubles(TIFF *tif, uint32_t tag)
{
    const TIFFField *f = TIFFFindField(tif, tag, TIFF_ANY);
    if (!f || !TIFFFieldPassCount(f)) return {};
    double *p = nullptr;
    uint32_t n = 0;
    int ok;
    if (TIFFFieldReadCount(f) == TIFF_VARIABLE2) {
        uint32_t c = 0;
        ok = TIFFGetField(tif, tag, &c, &p);
        n = c;
    } else {
        uint16_t c = 0;
        ok = TIFFGetField(tif, tag, &c, &p);
        n = c;
    }
    if (!ok || !p) return {};
    return std::vector<double>(p, p + n);
}

std::string num(double v)
{
    std::ostringstream o;
    o.precision(12);
    o << v;
    return o.str();
}

// ---------------------------------------------------------------------------
// reading

void read_georef(const std::string &path, DemRaster &r)
{
    auto fail = [&](const std::string &why) { return Error(path + ": " + why); };

    MsgSink sink;
    SinkScope scope(&sink);
    TiffPtr tif(open_tiff(path, "r", sink));
    if (!tif) throw fail("cannot open as TIFF: " + sink.text("unknown libtiff error"));

    {
        uint32_t rows = 0;
        if (TIFFIsTiled(tif.get()) ? TIFFGetField(tif.get(), TIFFTAG_TILELENGTH, &rows) == 1
                                   : TIFFGetField(tif.get(), TIFFTAG_ROWSPERSTRIP, &rows) == 1)
            r.block_rows = (int)std::min<uint32_t>(rows, 1u << 20);
    }
    // GDAL_NODATA
    char *nd = nullptr;
    if (TIFFGetField(tif.get(), kTagGdalNodata, &nd) == 1 && nd) {
        std::string s = one_line(nd);
        char *end = nullptr;
        errno = 0;
        double v = std::strtod(s.c_str(), &end);
        if (s.empty() || end == s.c_str() || *end != '\0')
            throw fail("unparsable GDAL_NODATA value '" + clipped(s, 60) + "'");
        r.has_nodata = true;
        r.nodata = v;
    }

    std::vector<double> scale = get_doubles(tif.get(), TIFFTAG_GEOPIXELSCALE);
    std::vector<double> ties = get_doubles(tif.get(), TIFFTAG_GEOTIEPOINTS);
    std::vector<double> xform = get_doubles(tif.get(), TIFFTAG_GEOTRANSMATRIX);

    GtifPtr gt(GTIFNewEx(tif.get(), geotiff_message, &sink));
    if (!gt) throw fail("invalid GeoTIFF key directory: " + sink.text("GTIFNew failed"));

    unsigned short v = 0;
    int raster_type = RasterPixelIsArea;
    if (GTIFKeyGetSHORT(gt.get(), GTRasterTypeGeoKey, &v, 0, 1) == 1) raster_type = v;
    int epsg = 0;
    if (GTIFKeyGetSHORT(gt.get(), ProjectedCSTypeGeoKey, &v, 0, 1) == 1 && v != 0 &&
        v != KvUserDefined)
        epsg = v;
    else if (GTIFKeyGetSHORT(gt.get(), GeographicTypeGeoKey, &v, 0, 1) == 1 && v != 0 &&
             v != KvUserDefined)
        epsg = v;
    r.geo.epsg = epsg;

    double pe, pn, oe, on;
    if (!scale.empty() || ties.size() >= 6) {
        if (scale.size() < 2) {
            if (xform.size() < 16)
                throw fail("ModelTiepoint without ModelPixelScale (ground control points) "
                           "is not supported");
        } else if (ties.size() < 6) {
            throw fail("ModelPixelScale without ModelTiepoint");
        }
    }
    if (scale.size() >= 2 && ties.size() >= 6) {
        const double sx = scale[0], sy = scale[1];
        const double ti = ties[0], tj = ties[1], tx = ties[3], ty = ties[4];
        pe = sx;
        pn = -sy;
        oe = tx - ti * sx;
        on = ty + tj * sy;
    } else if (xform.size() >= 16) {
        const double a = xform[0], b = xform[1], d = xform[3];
        const double e = xform[4], f = xform[5], h = xform[7];
        const double mag = std::max(std::fabs(a), std::fabs(f));
        if (std::fabs(b) > 1e-12 * mag || std::fabs(e) > 1e-12 * mag)
            throw fail("rotated or sheared model transformation is not supported");
        pe = a;
        pn = f;
        oe = d;
        on = h;
    } else {
        r.has_georef = false;
        return;
    }
    if (!(std::isfinite(pe) && std::isfinite(pn) && std::isfinite(oe) && std::isfinite(on)) ||
        pe == 0.0 || pn == 0.0)
        throw fail("invalid pixel scale or model transformation (" + num(pe) + ", " + num(pn) + ")");
    const double ape = std::fabs(pe), apn = std::fabs(pn);
    if (std::fabs(ape - apn) > 1e-9 * std::max(ape, apn))
        throw fail("non-square posting (" + num(ape) + " x " + num(apn) + ")");
    if (raster_type == RasterPixelIsPoint) {
        // the model point is the centre of the referenced pixel
        oe -= 0.5 * pe;
        on -= 0.5 * pn;
    }
    r.has_georef = true;
    r.geo.origin_e = oe;
    r.geo.origin_n = on;
    r.geo.posting_e = pe;
    r.geo.posting_n = pn;
}

// The nodata rule of read_dem: NaN, or equal to GDAL_NODATA compared in the
// sample type (as GDAL does).
struct NodataRule {
    bool can_match = false;
    double cmp = 0.0;
    explicit NodataRule(const DemRaster &r)
    {
        if (r.has_nodata && !std::isnan(r.nodata)) {
            const double nd = r.nodata;
            const std::string &t = r.sample_type;
            if (t == "float64") {
                can_match = true;
                cmp = nd;
            } else if (t == "float32") {
                if (std::isinf(nd) || std::fabs(nd) <= (double)FLT_MAX) {
                    can_match = true;
                    cmp = (double)(float)nd;
                }
            } else if (std::isfinite(nd) && nd == std::floor(nd)) {
                double lo = 0, hi = 0;
                if (t == "int8") lo = INT8_MIN, hi = INT8_MAX;
                else if (t == "uint8") lo = 0, hi = UINT8_MAX;
                else if (t == "int16") lo = INT16_MIN, hi = INT16_MAX;
                else if (t == "uint16") lo = 0, hi = UINT16_MAX;
                else if (t == "int32") lo = INT32_MIN, hi = INT32_MAX;
                else if (t == "uint32") lo = 0, hi = UINT32_MAX;
                can_match = nd >= lo && nd <= hi;
                cmp = nd;
            }
        }
    }
    void apply(const std::vector<double> &h, std::vector<uint8_t> &valid) const
    {
        valid.assign(h.size(), 1);
        for (size_t k = 0; k < h.size(); k++) {
            const double v = h[k];
            if (std::isnan(v) || (can_match && v == cmp)) valid[k] = 0;
        }
    }
};

void mark_valid(DemRaster &r) { NodataRule(r).apply(r.h, r.valid); }

// ---------------------------------------------------------------------------
// writing

template <typename T>
void to_integer(const std::string &path, const std::vector<double> &values, bool has_nodata,
                double nodata, const char *tname, std::vector<unsigned char> &out)
{
    const double lo = (double)std::numeric_limits<T>::min();
    const double hi = (double)std::numeric_limits<T>::max();
    if (has_nodata && !(std::isfinite(nodata) && nodata == std::floor(nodata) && nodata >= lo &&
                        nodata <= hi))
        throw Error(path + ": nodata value " + num(nodata) + " is not representable as " + tname);
    out.resize(values.size() * sizeof(T));
    for (size_t k = 0; k < values.size(); k++) {
        double v = values[k];
        if (std::isnan(v)) {
            if (!has_nodata)
                throw Error(path + ": NaN sample at index " + std::to_string(k) + " cannot be stored as " +
                            tname + " without a nodata value");
            v = nodata;
        }
        const double rv = std::round(v);  // nearest, halves away from zero
        if (!(rv >= lo && rv <= hi))
            throw Error(path + ": sample " + num(v) + " at index " + std::to_string(k) +
                        " is out of range for " + tname);
        const T t = (T)rv;
        std::memcpy(out.data() + k * sizeof(T), &t, sizeof(T));
    }
}

void to_float32(const std::string &path, const std::vector<double> &values,
                std::vector<unsigned char> &out)
{
    out.resize(values.size() * sizeof(float));
    for (size_t k = 0; k < values.size(); k++) {
        const double v = values[k];
        if (std::isfinite(v) && std::fabs(v) > (double)FLT_MAX)
            throw Error(path + ": sample " + num(v) + " at index " + std::to_string(k) +
                        " is out of range for float32");
        const float f = (float)v;
        std::memcpy(out.data() + k * sizeof(float), &f, sizeof(float));
    }
}

// The samples `data` (bits, sample format and predictor as TIFF tags) as a
// single-band TIFF at `path`, written through a TempOutput (host_io.hpp); GeoTIFF tags when geo is given (and GDAL_NODATA when nodata_text
// is), an ImageDescription when desc is not empty.
void write_tiff(const std::string &path, int width, int height, const std::vector<unsigned char> &data,
                uint16_t bits, uint16_t sfmt, uint16_t predictor, const Georef *geo, const std::string *nodata_text,
                const std::string &desc)
{
    auto fail = [&](const std::string &why) { return Error(path + ": " + why); };
    tiff_init_once();
    MsgSink sink;  // must outlive the TIFF handle
    SinkScope scope(&sink);
    TempOutput tmp(path);
    // TIFFClose closes the descriptor it was given: a duplicate, so that tmp
    // syncs, closes and renames the file itself on commit
    const int fd = ::dup(tmp.fd());
    const bool big = data.size() > 0xE0000000ull;
    TiffPtr tif(fd < 0 ? nullptr : open_tiff(tmp.temp_path(), big ? "w8" : "w", sink, fd));
    if (!tif) {
        if (fd >= 0) ::close(fd);
        throw fail("cannot open for writing: " + sink.text(fd < 0 ? std::strerror(errno) : "unknown libtiff error"));
    }
    TIFF *t = tif.get();
    auto check = [&](bool ok, const char *what) {
        if (!ok || !sink.errors.empty())
            throw fail(std::string(what) + " failed" +
                       (sink.errors.empty() ? std::string() : ": " + sink.errors));
    };

    const uint16_t compression =
        TIFFIsCODECConfigured(COMPRESSION_ADOBE_DEFLATE) ? COMPRESSION_ADOBE_DEFLATE : COMPRESSION_NONE;
    const size_t row_bytes = (size_t)width * (bits / 8);
    const uint32_t rows_per_strip =
        (uint32_t)std::max<size_t>(1, std::min<size_t>((size_t)height, 65536 / std::max<size_t>(1, row_bytes)));
    bool ok = TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)width) &&
              TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)height) &&
              TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1) &&
              TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, bits) &&
              TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, sfmt) &&
              TIFFSetField(t, TIFFTAG_PHOTOMETRIC, (uint16_t)PHOTOMETRIC_MINISBLACK) &&
              TIFFSetField(t, TIFFTAG_PLANARCONFIG, (uint16_t)PLANARCONFIG_CONTIG) &&
              TIFFSetField(t, TIFFTAG_COMPRESSION, compression) &&
              TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, rows_per_strip);
    if (ok && compression != COMPRESSION_NONE) ok = TIFFSetField(t, TIFFTAG_PREDICTOR, predictor);
    check(ok, "setting TIFF tags");

    if (!desc.empty()) check(TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, desc.c_str()) == 1, "setting TIFF tags");
    if (geo) {
        // Georeference: PixelIsArea tiepoint at the corner of pixel (0,0).
        double pixel_scale[3] = {std::fabs(geo->posting_e), std::fabs(geo->posting_n), 0.0};
        double tiepoint[6] = {0.0, 0.0, 0.0, geo->origin_e, geo->origin_n, 0.0};
        ok = TIFFSetField(t, TIFFTAG_GEOPIXELSCALE, (uint16_t)3, pixel_scale) &&
             TIFFSetField(t, TIFFTAG_GEOTIEPOINTS, (uint16_t)6, tiepoint);
        if (ok && nodata_text) ok = TIFFSetField(t, kTagGdalNodata, nodata_text->c_str());
        check(ok, "setting GeoTIFF tags");
        GtifPtr gt(GTIFNewEx(t, geotiff_message, &sink));
        check(gt != nullptr, "creating GeoTIFF keys");
        ok = GTIFKeySet(gt.get(), GTModelTypeGeoKey, TYPE_SHORT, 1, (int)ModelTypeProjected) &&
             GTIFKeySet(gt.get(), GTRasterTypeGeoKey, TYPE_SHORT, 1, (int)RasterPixelIsArea);
        if (ok && geo->epsg != 0)
            ok = GTIFKeySet(gt.get(), ProjectedCSTypeGeoKey, TYPE_SHORT, 1, geo->epsg);
        else if (ok)
            ok = GTIFKeySet(gt.get(), ProjLinearUnitsGeoKey, TYPE_SHORT, 1, (int)Linear_Meter);
        check(ok, "setting GeoTIFF keys");
        check(GTIFWriteKeys(gt.get()) != 0, "writing GeoTIFF keys");
    }

    for (uint32_t row = 0, strip = 0; row < (uint32_t)height; row += rows_per_strip, strip++) {
        const uint32_t nrows = std::min<uint32_t>(rows_per_strip, (uint32_t)height - row);
        const tmsize_t bytes = (tmsize_t)(nrows * row_bytes);
        // libtiff may modify the buffer in place (predictor), so hand it a copy
        std::vector<unsigned char> chunk(data.begin() + (ptrdiff_t)(row * row_bytes),
                                         data.begin() + (ptrdiff_t)(row * row_bytes + (size_t)bytes));
        check(TIFFWriteEncodedStrip(t, strip, chunk.data(), bytes) == bytes, "writing pixel data");
    }
    check(TIFFFlush(t) == 1, "writing TIFF directory");
    tif.reset();  // closes the duplicate
    check(true, "closing TIFF");
    tmp.commit();  // fsync, close, rename
}

}  // namespace

// ---------------------------------------------------------------------------

DemRaster read_dem(const std::string &path)
{
    struct stat st;
    if (::stat(path.c_str(), &st) != 0)
        throw Error(path + ": cannot open: " + std::strerror(errno));
    if (S_ISDIR(st.st_mode)) throw Error(path + ": cannot open: is a directory");
    if (::access(path.c_str(), R_OK) != 0)
        throw Error(path + ": cannot open: " + std::strerror(errno));

    DemRaster r;
    bool is_tiff = false;
    try {
        read_dem_pixels(path, r, is_tiff);
    } catch (const Error &) {
        throw;
    } catch (const std::exception &e) {
        // OpenImageIO plugins can throw (e.g. a GIF disguised as .tif)
        throw Error(path + ": cannot read image (" + e.what() + ")");
    }
    if (is_tiff) read_georef(path, r);
    mark_valid(r);
    return r;
}

DemRows::DemRows(const std::string &path)
{
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) throw Error(path + ": cannot open: " + std::strerror(errno));
    if (S_ISDIR(st.st_mode)) throw Error(path + ": cannot open: is a directory");
    if (::access(path.c_str(), R_OK) != 0) throw Error(path + ": cannot open: " + std::strerror(errno));
    bool is_tiff = false;
    try {
        handle_ = open_dem_pixel_rows(path, hdr_, is_tiff);
        if (is_tiff) read_georef(path, hdr_);
    } catch (const Error &) {
        if (handle_) close_dem_pixel_rows(handle_);
        throw;
    } catch (const std::exception &e) {
        if (handle_) close_dem_pixel_rows(handle_);
        throw Error(path + ": cannot read image (" + e.what() + ")");
    }
}

DemRows::~DemRows()
{
    if (handle_) close_dem_pixel_rows(handle_);
}

void DemRows::read(int y0, int n, std::vector<double> &h, std::vector<uint8_t> &valid)
{
    read_dem_pixel_rows(handle_, y0, n, h);
    NodataRule(hdr_).apply(h, valid);
}

void write_geotiff(const std::string &path, int width, int height,
                   const std::vector<double> &values, SampleType type, const Georef &geo,
                   bool has_nodata, double nodata)
{
    auto fail = [&](const std::string &why) { return Error(path + ": " + why); };

    if (width <= 0 || height <= 0)
        throw fail("invalid raster size " + std::to_string(width) + " x " + std::to_string(height));
    if (values.size() != (size_t)width * (size_t)height)
        throw fail("expected " + std::to_string((size_t)width * (size_t)height) + " samples, got " +
                   std::to_string(values.size()));
    if (!(geo.posting_e > 0.0 && geo.posting_n < 0.0 && std::isfinite(geo.posting_e) &&
          std::isfinite(geo.posting_n)))
        throw fail("only north-up rasters (posting_e > 0, posting_n < 0) can be written, got (" +
                   num(geo.posting_e) + ", " + num(geo.posting_n) + ")");
    if (!(std::isfinite(geo.origin_e) && std::isfinite(geo.origin_n)))
        throw fail("non-finite origin");
    if (geo.epsg < 0 || geo.epsg > 65535) throw fail("invalid EPSG code " + std::to_string(geo.epsg));

    // Convert (and range-check) everything before touching the file system.
    std::vector<unsigned char> data;
    uint16_t bits = 0, sfmt = 0, predictor = PREDICTOR_HORIZONTAL;
    switch (type) {
    case SampleType::Int16:
        to_integer<int16_t>(path, values, has_nodata, nodata, "int16", data);
        bits = 16, sfmt = SAMPLEFORMAT_INT;
        break;
    case SampleType::UInt16:
        to_integer<uint16_t>(path, values, has_nodata, nodata, "uint16", data);
        bits = 16, sfmt = SAMPLEFORMAT_UINT;
        break;
    case SampleType::Float32:
        to_float32(path, values, data);
        bits = 32, sfmt = SAMPLEFORMAT_IEEEFP, predictor = PREDICTOR_FLOATINGPOINT;
        break;
    default: throw fail("unsupported sample type");
    }
    std::string nodata_text;
    if (has_nodata) {
        char b[64];
        std::snprintf(b, sizeof b, "%.17g", nodata);
        nodata_text = b;
    }

    write_tiff(path, width, height, data, bits, sfmt, predictor, &geo, has_nodata ? &nodata_text : nullptr, "");
}

void write_float_tiff(const std::string &path, int width, int height, const std::vector<float> &values,
                      const std::string &desc)
{
    if (width <= 0 || height <= 0)
        throw Error(path + ": invalid raster size " + std::to_string(width) + " x " + std::to_string(height));
    if (values.size() != (size_t)width * (size_t)height)
        throw Error(path + ": expected " + std::to_string((size_t)width * (size_t)height) + " samples, got " +
                    std::to_string(values.size()));
    std::vector<unsigned char> data(values.size() * sizeof(float));
    std::memcpy(data.data(), values.data(), data.size());
    write_tiff(path, width, height, data, 32, SAMPLEFORMAT_IEEEFP, PREDICTOR_FLOATINGPOINT, nullptr, nullptr, desc);
}

}  // namespace ct_host
