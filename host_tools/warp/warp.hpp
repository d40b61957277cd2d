// warp.hpp -- resampling a DEM on another CRS (geographic lat/lon grids such
// as SRTM or Copernicus GLO-30, or any projected CRS other than a WGS84 UTM
// zone) onto a square metric grid in a WGS84 UTM zone, with GDAL's warper
// (bilinear, exact coordinate transformation).
//
// Voids: a destination post whose bilinear footprint (the source posts with
// a non-zero weight in GDAL's kernel) touches a nodata / masked / NaN source
// post is a void; nodata is never averaged into valid heights.  Posts
// outside the source raster are voids too.
#pragma once

#include <string>

#include "dem_io.hpp"
#include "terrain.hpp"

namespace ct_host {

struct WarpOptions {
    int utm_zone = 0;       // 1..60; 0: the zone of the DEM's centre (standard 6-degree zones)
    bool south = false;     // utm_zone != 0: southern hemisphere (EPSG:327zz); else from the centre
    double posting_m = 0;   // output posting; 0: the source posting in metres at the DEM's centre
                            // (geometric mean of the two axes), rounded to 2 significant digits
};

// "17N", "17s", "5S": zone 1..60 and a hemisphere letter into o->utm_zone /
// o->south.  Throws Error("'<s>' is not a UTM zone ...").
void parse_utm_zone(const std::string &s, WarpOptions *o);

// Does `path` need warping?  With o.utm_zone == 0: true when GDAL reads the
// file and its horizontal CRS is geographic or anything other than a WGS84
// UTM zone; false for a file without a CRS or that GDAL cannot read (the
// plain reader reports those).  With o.utm_zone != 0: true unless the file
// is already on that zone; throws Error("<path>: ...") when the file has no
// georeference or cannot be read.
bool dem_needs_warp(const std::string &path, const WarpOptions &o = WarpOptions());

// Resample the single-band DEM `path` onto a UTM grid (GDAL's output extent
// for `gdalwarp -t_srs EPSG:326zz -tr P P`): metres row-major, `valid` mask,
// geo.epsg = 326zz/327zz, geo.source_epsg = the source CRS's EPSG code (0 if
// it has none), sample_type "float64".  Throws Error("<path>: <reason>").
DemRaster warp_dem(const std::string &path, const WarpOptions &o = WarpOptions());

// "resampled from EPSG:4326 onto EPSG:32617 at 30 m, bilinear"
std::string warp_summary(const DemRaster &r);

}  // namespace ct_host
