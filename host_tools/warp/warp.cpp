// warp.cpp -- DEMs on a geographic (or other non-UTM) CRS resampled onto a
// WGS84 UTM grid with GDAL's warper (gdal_utils.h GDALWarp).
//
// The source is copied into a two-band in-memory dataset: band 1 the
// heights (0 at invalid posts), band 2 the validity (1 valid, 0 invalid),
// neither with a nodata value, and both are warped bilinearly in one pass
// with the exact coordinate transformation (-et 0).  A destination post is
// valid when its warped validity is 1 (every source post with a non-zero
// kernel weight valid); there the warped height is the plain bilinear
// interpolation of valid heights, the value gdalwarp gives.  gdalwarp
// itself renormalises the weights over the valid posts of a footprint that
// touches nodata (a value from fewer posts): those posts are voids here.
// Posts outside the source raster keep the INIT_DEST validity 0.
//
// GDAL diagnostics are captured by a pushed error handler (never printed)
// and the first failure message ends up in the Error text.

#include "warp.hpp"

#include <gdal.h>
#include <gdal_alg.h>
#include <gdal_utils.h>
#include <ogr_srs_api.h>
#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <vector>

namespace ct_host {
namespace {

void register_gdal()
{
    static std::once_flag once;
    std::call_once(once, [] { GDALAllRegister(); });
}

// GDAL messages of this thread while alive: failures are kept, the rest
// (warnings, debug) dropped.
class GdalErrors {
public:
    GdalErrors() { CPLPushErrorHandlerEx(&GdalErrors::handler, this); }
    ~GdalErrors() { CPLPopErrorHandler(); }
    GdalErrors(const GdalErrors &) = delete;
    GdalErrors &operator=(const GdalErrors &) = delete;
    std::string text(const std::string &fallback) const { return first_.empty() ? fallback : first_; }

private:
    std::string first_;
    static void CPL_STDCALL handler(CPLErr cls, CPLErrorNum, const char *msg)
    {
        auto *self = static_cast<GdalErrors *>(CPLGetErrorHandlerUserData());
        if (!self || cls < CE_Failure || !self->first_.empty() || !msg) return;
        std::string m = msg;
        for (char &c : m)
            if (c == '\n' || c == '\r') c = ' ';
        self->first_ = m;
    }
};

struct DsClose {
    void operator()(void *p) const { GDALClose((GDALDatasetH)p); }
};
using DsPtr = std::unique_ptr<void, DsClose>;
struct SrsFree {
    void operator()(void *p) const { OSRDestroySpatialReference((OGRSpatialReferenceH)p); }
};
using SrsPtr = std::unique_ptr<void, SrsFree>;
struct CtFree {
    void operator()(void *p) const { OCTDestroyCoordinateTransformation((OGRCoordinateTransformationH)p); }
};
using CtPtr = std::unique_ptr<void, CtFree>;

std::string num(double v)
{
    char b[64];
    std::snprintf(b, sizeof b, "%.10g", v);
    return b;
}

SrsPtr epsg_srs(int code)
{
    SrsPtr s(OSRNewSpatialReference(nullptr));
    if (!s || OSRImportFromEPSG((OGRSpatialReferenceH)s.get(), code) != OGRERR_NONE) return SrsPtr();
    OSRSetAxisMappingStrategy((OGRSpatialReferenceH)s.get(), OAMS_TRADITIONAL_GIS_ORDER);
    return s;
}

// What a file is, as GDAL sees it.
struct Source {
    DsPtr ds;
    bool has_gt = false;
    double gt[6] = {0, 1, 0, 0, 0, 1};
    SrsPtr srs;          // horizontal CRS (vertical part of a compound CRS stripped); null: none
    int epsg = 0;        // its EPSG code, 0 if none
    int utm_epsg = 0;    // 326zz / 327zz when it is a WGS84 UTM zone
};

int epsg_code(OGRSpatialReferenceH h)
{
    const char *auth = OSRGetAuthorityName(h, nullptr);
    const char *code = OSRGetAuthorityCode(h, nullptr);
    if (auth && code && std::strcmp(auth, "EPSG") == 0) return std::atoi(code);
    SrsPtr c(OSRClone(h));
    if (c && OSRAutoIdentifyEPSG((OGRSpatialReferenceH)c.get()) == OGRERR_NONE) {
        auth = OSRGetAuthorityName((OGRSpatialReferenceH)c.get(), nullptr);
        code = OSRGetAuthorityCode((OGRSpatialReferenceH)c.get(), nullptr);
        if (auth && code && std::strcmp(auth, "EPSG") == 0) return std::atoi(code);
    }
    return 0;
}

// Open `path`; fills everything GDAL can tell.  Returns false (no throw)
// when GDAL cannot open it; *why gets the reason.
bool open_source(const std::string &path, Source *s, std::string *why)
{
    register_gdal();
    GdalErrors errs;
    s->ds.reset(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY | GDAL_OF_VERBOSE_ERROR, nullptr,
                           nullptr, nullptr));
    if (!s->ds) {
        *why = errs.text("not a raster GDAL can read");
        return false;
    }
    GDALDatasetH ds = (GDALDatasetH)s->ds.get();
    s->has_gt = GDALGetGeoTransform(ds, s->gt) == CE_None;
    OGRSpatialReferenceH ref = GDALGetSpatialRef(ds);
    if (ref && !OSRIsLocal(ref) && (OSRIsGeographic(ref) || OSRIsProjected(ref))) {
        s->srs.reset(OSRClone(ref));
        OGRSpatialReferenceH h = (OGRSpatialReferenceH)s->srs.get();
        if (OSRIsCompound(h)) OSRStripVertical(h);
        OSRSetAxisMappingStrategy(h, OAMS_TRADITIONAL_GIS_ORDER);
        s->epsg = epsg_code(h);
        if ((s->epsg >= 32601 && s->epsg <= 32660) || (s->epsg >= 32701 && s->epsg <= 32760)) {
            s->utm_epsg = s->epsg;
        } else if (OSRIsProjected(h)) {
            int north = 0, zone = OSRGetUTMZone(h, &north);
            SrsPtr wgs84 = epsg_srs(4326);
            if (zone >= 1 && zone <= 60 && wgs84 && OSRIsSameGeogCS(h, (OGRSpatialReferenceH)wgs84.get()))
                s->utm_epsg = (north ? 32600 : 32700) + zone;
        }
    }
    return true;
}

bool georeferenced(const Source &s) { return s.has_gt && s.srs; }

// Source pixel/line (x, y) -> the CRS of `ct`'s target.
bool pixel_to(const Source &s, OGRCoordinateTransformationH ct, double x, double y, double *e, double *n)
{
    double X = s.gt[0] + x * s.gt[1] + y * s.gt[2], Y = s.gt[3] + x * s.gt[4] + y * s.gt[5], Z = 0;
    if (!OCTTransform(ct, 1, &X, &Y, &Z) || !std::isfinite(X) || !std::isfinite(Y)) return false;
    *e = X;
    *n = Y;
    return true;
}

double round_2_digits(double p)
{
    const int e = (int)std::floor(std::log10(p)) - 1;  // keep 2 significant digits
    if (e >= 0) {
        const double k = std::pow(10.0, e);
        return std::round(p / k) * k;
    }
    const double k = std::pow(10.0, -e);
    return std::round(p * k) / k;
}

}  // namespace

bool dem_needs_warp(const std::string &path, const WarpOptions &o)
{
    Source s;
    std::string why;
    const bool forced = o.utm_zone != 0;
    if (!open_source(path, &s, &why)) {
        if (forced) throw Error(path + ": " + why);
        return false;
    }
    if (!forced) return georeferenced(s) && s.utm_epsg == 0;
    if (!s.has_gt) throw Error(path + ": no georeference in the file; --utm needs a georeferenced DEM");
    if (!s.srs) throw Error(path + ": no coordinate reference system in the file; --utm needs a georeferenced DEM");
    return s.utm_epsg != (o.south ? 32700 : 32600) + o.utm_zone;
}

namespace {

// What warp_dem's steps share: the source, its CRS, the GDAL error text.
struct Warp {
    const std::string &path;
    Source &s;
    GdalErrors &errs;
    Error fail(const std::string &why) const { return Error(path + ": " + why); }
};

// The UTM zone: given, or that of the DEM's centre (*south set).
int utm_zone_for(const Warp &w, OGRSpatialReferenceH ssrs, const WarpOptions &opt, bool *south)
{
    *south = opt.south;
    if (opt.utm_zone != 0) return opt.utm_zone;
    const int W = GDALGetRasterXSize((GDALDatasetH)w.s.ds.get()), H = GDALGetRasterYSize((GDALDatasetH)w.s.ds.get());
    SrsPtr wgs84 = epsg_srs(4326);
    CtPtr ct(wgs84 ? OCTNewCoordinateTransformation(ssrs, (OGRSpatialReferenceH)wgs84.get()) : nullptr);
    double lon, lat;
    if (!ct || !pixel_to(w.s, (OGRCoordinateTransformationH)ct.get(), 0.5 * W, 0.5 * H, &lon, &lat))
        throw w.fail("cannot locate the DEM's centre in WGS84 (" + w.errs.text("no transformation") + ")");
    if (!(lat >= -90 && lat <= 90 && lon >= -540 && lon <= 540))
        throw w.fail("the DEM's centre (" + num(lat) + ", " + num(lon) + ") is not on the earth");
    lon = std::fmod(lon + 180.0, 360.0);
    if (lon < 0) lon += 360.0;
    *south = lat < 0;
    return std::min(60, std::max(1, (int)std::floor(lon / 6.0) + 1));
}

// The posting: given, or the source posting at the centre in UTM metres
// (rounded to two significant digits).
double posting_for(const Warp &w, OGRCoordinateTransformationH to_utm, int epsg, double given)
{
    if (given != 0) return given;
    const int W = GDALGetRasterXSize((GDALDatasetH)w.s.ds.get()), H = GDALGetRasterYSize((GDALDatasetH)w.s.ds.get());
    const double cx = std::floor(0.5 * W) + 0.5, cy = std::floor(0.5 * H) + 0.5;
    double e0, n0, e1, n1, e2, n2;
    if (!pixel_to(w.s, to_utm, cx, cy, &e0, &n0) || !pixel_to(w.s, to_utm, cx + 1, cy, &e1, &n1) ||
        !pixel_to(w.s, to_utm, cx, cy + 1, &e2, &n2))
        throw w.fail("cannot transform the DEM's centre onto EPSG:" + std::to_string(epsg));
    const double dx = std::hypot(e1 - e0, n1 - n0), dy = std::hypot(e2 - e0, n2 - n0);
    const double p = std::sqrt(dx * dy);
    if (!(p > 1e-6 && p < 1e6)) throw w.fail("source posting of " + num(p) + " m at the centre is not usable; give --posting");
    return round_2_digits(p);
}

std::string wkt_of(OGRSpatialReferenceH srs)
{
    char *wkt = nullptr;
    OSRExportToWkt(srs, &wkt);
    const std::string out = wkt ? wkt : "";
    CPLFree(wkt);
    return out;
}

// The output size GDAL will choose (as gdalwarp -tr): oversized grids are
// refused before any pixel is read.
void check_output_size(const Warp &w, const std::string &swkt, const std::string &dwkt, double posting)
{
    const std::string so = "SRC_SRS=" + swkt, dso = "DST_SRS=" + dwkt;
    const char *topts[] = {so.c_str(), dso.c_str(), nullptr};
    GDALDatasetH src = (GDALDatasetH)w.s.ds.get();
    void *tr = GDALCreateGenImgProjTransformer2(src, nullptr, (char **)topts);
    if (!tr) throw w.fail("cannot set up the transformation (" + w.errs.text("?") + ")");
    double sgt[6], ext[4];
    int npx = 0, nln = 0;
    CPLErr e = GDALSuggestedWarpOutput2(src, GDALGenImgProjTransform, tr, sgt, &npx, &nln, ext, 0);
    GDALDestroyGenImgProjTransformer(tr);
    if (e != CE_None) throw w.fail("cannot compute the output extent (" + w.errs.text("?") + ")");
    const double nx = (npx * std::fabs(sgt[1]) + posting / 2) / posting;
    const double ny = (nln * std::fabs(sgt[5]) + posting / 2) / posting;
    if (nx > 32768 || ny > 32768)
        throw w.fail("resampled at " + num(posting) + " m it would be " + num(std::floor(nx)) + " x " +
                     num(std::floor(ny)) + " posts, over the package limit of 32768 per side; give a coarser --posting");
}

// The heights (0 where invalid) and their validity as two float64 bands of
// an in-memory dataset with the source's georeference.
DsPtr in_memory_copy(const Warp &w, GDALRasterBandH band, OGRSpatialReferenceH ssrs)
{
    GDALDatasetH src = (GDALDatasetH)w.s.ds.get();
    const int W = GDALGetRasterXSize(src), H = GDALGetRasterYSize(src);
    std::vector<double> h((size_t)W * H);
    std::vector<uint8_t> m((size_t)W * H);
    if (GDALRasterIO(band, GF_Read, 0, 0, W, H, h.data(), W, H, GDT_Float64, 0, 0) != CE_None)
        throw w.fail("cannot read the heights (" + w.errs.text("read error") + ")");
    if (GDALRasterIO(GDALGetMaskBand(band), GF_Read, 0, 0, W, H, m.data(), W, H, GDT_Byte, 0, 0) != CE_None)
        throw w.fail("cannot read the nodata mask (" + w.errs.text("read error") + ")");
    GDALDriverH drv = GDALGetDriverByName("MEM");
    if (!drv) throw w.fail("GDAL has no MEM driver");
    DsPtr mem(GDALCreate(drv, "", W, H, 2, GDT_Float64, nullptr));
    if (!mem) throw w.fail("cannot allocate " + std::to_string(W) + " x " + std::to_string(H) + " in memory");
    GDALDatasetH md = (GDALDatasetH)mem.get();
    GDALSetGeoTransform(md, w.s.gt);
    GDALSetSpatialRef(md, ssrs);
    std::vector<double> v((size_t)W * H);
    for (size_t k = 0; k < v.size(); ++k) {
        const bool ok = m[k] != 0 && std::isfinite(h[k]);
        v[k] = ok ? 1.0 : 0.0;
        if (!ok) h[k] = 0.0;
    }
    if (GDALRasterIO(GDALGetRasterBand(md, 1), GF_Write, 0, 0, W, H, h.data(), W, H, GDT_Float64, 0, 0) != CE_None ||
        GDALRasterIO(GDALGetRasterBand(md, 2), GF_Write, 0, 0, W, H, v.data(), W, H, GDT_Float64, 0, 0) != CE_None)
        throw w.fail("cannot fill the in-memory copy (" + w.errs.text("write error") + ")");
    return mem;
}

// gdalwarp -of MEM -s_srs SRC -t_srs EPSG:326zz -tr P P -r bilinear -et 0
// -ot Float64 -wo INIT_DEST=0 over the in-memory copy (released here).
DsPtr warped(const Warp &w, DsPtr mem, const std::string &swkt, const std::string &dwkt, double posting)
{
    const std::string tr = num(posting);
    std::vector<std::string> args = {"-of", "MEM", "-s_srs", swkt, "-t_srs", dwkt, "-tr", tr, tr,
                                     "-r", "bilinear", "-et", "0", "-ot", "Float64", "-wo", "INIT_DEST=0",
                                     "-wo", "NUM_THREADS=ALL_CPUS"};
    std::vector<char *> argv;
    for (std::string &a : args) argv.push_back(&a[0]);
    argv.push_back(nullptr);
    GDALWarpAppOptions *wo = GDALWarpAppOptionsNew(argv.data(), nullptr);
    if (!wo) throw w.fail("bad warp options (" + w.errs.text("?") + ")");
    GDALDatasetH srcs[1] = {(GDALDatasetH)mem.get()};
    int usage_error = 0;
    DsPtr out(GDALWarp("", nullptr, 1, srcs, wo, &usage_error));
    GDALWarpAppOptionsFree(wo);
    mem.reset();
    if (!out) throw w.fail("resampling failed (" + w.errs.text("GDALWarp failed") + ")");
    return out;
}

// The warped dataset as a DemRaster (heights NaN where not every source
// post under them was valid).
DemRaster raster_of(const Warp &w, GDALDatasetH od, int epsg)
{
    DemRaster r;
    r.width = GDALGetRasterXSize(od);
    r.height = GDALGetRasterYSize(od);
    double ogt[6];
    if (GDALGetGeoTransform(od, ogt) != CE_None || ogt[2] != 0 || ogt[4] != 0)
        throw w.fail("resampling produced no north-up grid");
    const size_t n = (size_t)r.width * r.height;
    r.h.resize(n);
    r.valid.resize(n);
    std::vector<double> v(n);
    if (GDALRasterIO(GDALGetRasterBand(od, 1), GF_Read, 0, 0, r.width, r.height, r.h.data(), r.width, r.height,
                     GDT_Float64, 0, 0) != CE_None ||
        GDALRasterIO(GDALGetRasterBand(od, 2), GF_Read, 0, 0, r.width, r.height, v.data(), r.width, r.height,
                     GDT_Float64, 0, 0) != CE_None)
        throw w.fail("cannot read the resampled grid (" + w.errs.text("read error") + ")");
    for (size_t k = 0; k < n; ++k) {
        // validity 1 up to rounding: every source post with a weight above
        // 1e-9 was valid (the height error from the rest is below 1e-9 h)
        r.valid[k] = v[k] >= 1.0 - 1e-9 && std::isfinite(r.h[k]);
        if (!r.valid[k]) r.h[k] = std::nan("");
    }
    r.sample_type = "float64";
    r.has_georef = true;
    r.geo.origin_e = ogt[0];
    r.geo.origin_n = ogt[3];
    r.geo.posting_e = ogt[1];
    r.geo.posting_n = ogt[5];
    r.geo.epsg = epsg;
    r.geo.source_epsg = w.s.epsg;
    return r;
}

}  // namespace

DemRaster warp_dem(const std::string &path, const WarpOptions &opt)
{
    auto fail = [&](const std::string &why) { return Error(path + ": " + why); };
    Source s;
    std::string why;
    if (!open_source(path, &s, &why)) throw fail(why);
    GDALDatasetH src = (GDALDatasetH)s.ds.get();
    if (!s.has_gt) throw fail("no georeference in the file; cannot resample it onto UTM");
    if (!s.srs) throw fail("no coordinate reference system in the file; cannot resample it onto UTM");
    OGRSpatialReferenceH ssrs = (OGRSpatialReferenceH)s.srs.get();
    const int W = GDALGetRasterXSize(src), H = GDALGetRasterYSize(src);
    if (GDALGetRasterCount(src) != 1)
        throw fail(std::to_string(GDALGetRasterCount(src)) + " bands; a DEM has exactly one");
    GDALRasterBandH band = GDALGetRasterBand(src, 1);
    const GDALDataType st = GDALGetRasterDataType(band);
    if (GDALDataTypeIsComplex(st)) throw fail(std::string("complex samples (") + GDALGetDataTypeName(st) + ")");
    if (W < 1 || H < 1) throw fail("empty raster");
    if (opt.utm_zone < 0 || opt.utm_zone > 60) throw fail("UTM zone " + std::to_string(opt.utm_zone) + " is not in 1..60");
    if (!(opt.posting_m >= 0 && opt.posting_m <= 1e6)) throw fail("invalid posting " + num(opt.posting_m) + " m");

    GdalErrors errs;
    const Warp w{path, s, errs};
    bool south = false;
    const int zone = utm_zone_for(w, ssrs, opt, &south);
    const int epsg = (south ? 32700 : 32600) + zone;
    SrsPtr dsrs = epsg_srs(epsg);
    if (!dsrs) throw w.fail("EPSG:" + std::to_string(epsg) + " unknown to PROJ (" + errs.text("?") + ")");
    CtPtr to_utm(OCTNewCoordinateTransformation(ssrs, (OGRSpatialReferenceH)dsrs.get()));
    if (!to_utm) throw w.fail("no transformation onto EPSG:" + std::to_string(epsg) + " (" + errs.text("?") + ")");
    const double posting = posting_for(w, (OGRCoordinateTransformationH)to_utm.get(), epsg, opt.posting_m);
    const std::string dwkt = wkt_of((OGRSpatialReferenceH)dsrs.get()), swkt = wkt_of(ssrs);
    check_output_size(w, swkt, dwkt, posting);
    DsPtr out = warped(w, in_memory_copy(w, band, ssrs), swkt, dwkt, posting);
    return raster_of(w, (GDALDatasetH)out.get(), epsg);
}

}  // namespace ct_host
