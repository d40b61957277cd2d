// dem_io.hpp -- reading DEM rasters (pixels via OpenImageIO, georeference via
// libgeotiff/libtiff) and writing GeoTIFFs and plain float TIFFs (libtiff +
// libgeotiff).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "terrain.hpp"

namespace ct_host {

struct DemRaster {
    int width = 0, height = 0;
    std::vector<double> h;        // metres (sample value as stored), row-major
    std::vector<uint8_t> valid;   // 1 = valid sample, 0 = nodata / NaN
    std::string sample_type;      // "int16", "uint16", "float32", ...
    bool has_georef = false;      // GeoTIFF model tags found
    Georef geo;                   // GDAL-convention corner origin and posting
    bool has_nodata = false;
    double nodata = 0.0;
    int block_rows = 0;           // a TIFF's rows per tile or strip (0: not known)
};

// Read a single-band raster.  Throws ct_host::Error("<path>: <reason>") for
// an unreadable file, more than one channel, an unsupported sample format,
// a non-square posting or a rotated/sheared model transformation.
DemRaster read_dem(const std::string &path);

// Write a single-band GeoTIFF (int16, uint16 or float32 samples) with
// ModelPixelScale + ModelTiepoint (PixelIsArea), optional EPSG projected CRS
// and optional GDAL_NODATA.  Writes to a temporary file and renames it, so
// no partial output is left on failure.  Throws ct_host::Error.
enum class SampleType { Int16, UInt16, Float32 };
void write_geotiff(const std::string &path, int width, int height,
                   const std::vector<double> &values, SampleType type,
                   const Georef &geo, bool has_nodata = false, double nodata = 0.0);

// Write a single-band float32 TIFF without a georeference (an image's
// samples, e.g. the range per pixel of `conetrace view`; NaN allowed), its
// ImageDescription tag `desc`.  Atomic as write_geotiff.  Throws
// ct_host::Error("<path>: <reason>").
void write_float_tiff(const std::string &path, int width, int height, const std::vector<float> &values,
                      const std::string &desc);

// read_dem's first half: the pixels, sample type and size of `path` through
// OpenImageIO (dem_pixels.cpp); is_tiff: OpenImageIO read it as a TIFF (so
// read_dem looks for GeoTIFF tags).  The `conetrace` binary links a door to
// the plugin in its place (heavy_door.hpp).
void read_dem_pixels(const std::string &path, DemRaster &r, bool &is_tiff);

// The same a band of rows at a time (dem_pixels.cpp; the door in the
// binary): open checks the header as read_dem_pixels does and sets r's size
// and sample type; read puts rows y0 .. y0 + n - 1 in h (metres as stored);
// close ends it (also after an error).  Throw Error("<path>: ...").
void *open_dem_pixel_rows(const std::string &path, DemRaster &r, bool &is_tiff);
void read_dem_pixel_rows(void *handle, int y0, int n, std::vector<double> &h);
void close_dem_pixel_rows(void *handle);

// A DEM read by bands of rows, for DEMs too large to hold whole: header()
// is read_dem's result without the pixels (size, sample type,
// georeference, nodata); read() gives rows y0 .. y0 + n - 1 and their
// valid flags by read_dem's rules.  Throws Error("<path>: <reason>").
class DemRows {
public:
    explicit DemRows(const std::string &path);
    ~DemRows();
    DemRows(const DemRows &) = delete;
    DemRows &operator=(const DemRows &) = delete;
    const DemRaster &header() const { return hdr_; }
    void read(int y0, int n, std::vector<double> &h, std::vector<uint8_t> &valid);

private:
    DemRaster hdr_;
    void *handle_ = nullptr;
};

// A library's message on one line (line breaks and other control
// characters as spaces: a message may quote the file's bytes; ends trimmed).
inline std::string one_line(std::string s)
{
    for (char &c : s)
        if ((unsigned char)c < 0x20 || c == 0x7f) c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    size_t b = 0;
    while (b < s.size() && s[b] == ' ') b++;
    return s.substr(b);
}

// A library's error text cut to a readable length (OIIO records one message
// per failed strip: megabytes for a file that lies about its size).
inline std::string clipped(std::string s, size_t max = 300)
{
    if (s.size() > max) s = s.substr(0, max) + " ...";
    return s;
}

}  // namespace ct_host
