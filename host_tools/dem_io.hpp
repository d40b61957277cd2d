// dem_io.hpp -- reading DEM rasters (pixels via OpenImageIO, georeference via
// libgeotiff/libtiff) and writing GeoTIFFs (libtiff + libgeotiff).
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

}  // namespace ct_host
