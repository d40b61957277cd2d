// vdatum.hpp -- the vertical datum of a package: a DEM's heights above the
// EGM96 geoid turned into WGS84 ellipsoidal heights at build time, and the
// geoid grid the package carries so the library can give orthometric
// heights back (ct_package_geoid).  The grid is EGM96's own 15' nodes over
// the tile, read through PROJ (proj-data's egm96_15.gtx), so the library's
// bilinear interpolation is PROJ's.
#pragma once

#include <string>
#include <vector>

#include "terrain.hpp"

namespace ct_host {

// "unknown", "ellipsoid" (or "wgs84"), "egm96"; throws Error otherwise.
int parse_vdatum(const std::string &s);

// EGM96 undulation N (metres, h_ellipsoid = h_geoid + N) through PROJ at
// a geodetic point.  Throws Error when PROJ or its grid is missing.
class Egm96 {
public:
    Egm96();
    ~Egm96();
    Egm96(const Egm96 &) = delete;
    Egm96 &operator=(const Egm96 &) = delete;
    double at(double lat_deg, double lon_deg) const;

private:
    void *ctx_ = nullptr, *pj_ = nullptr;
};

// EGM96's nodes (every 15') around the posts of a DEM on a UTM CRS, one
// node of margin beyond the posts' latitude and longitude range.  Throws
// Error for a CRS that is not UTM.
GeoidGrid make_geoid_grid(const Egm96 &egm, const Georef &g, int width, int height);

// N (metres) at a map point of a UTM CRS by the flight library
// (ct_utm_inverse, ct_geoid_at); NaN outside the grid.
double geoid_at(const GeoidGrid &grid, int epsg, double e_m, double n_m);

// Turn the heights of a DEM in `vdatum` into ellipsoidal ones (EGM96:
// h + N(post) by the library's interpolation of the grid, so that the
// library's h - N gives the source height back) and make the grid the
// package carries (EGM96 and ellipsoidal sources; none for unknown).
// Throws Error (without a path) for a CRS that is not UTM.
void apply_vdatum(std::vector<double> &h_m, const std::vector<uint8_t> &valid, int width,
                  int height, const Georef &g, int vdatum, GeoidGrid &geoid);

// apply_vdatum in two halves, for a DEM read by bands of rows: the grid
// over the whole DEM (empty for unknown), then the heights of rows y0 ..
// y0 + n - 1 (h_m and valid hold those rows) turned as apply_vdatum turns
// them -- the same sums, post by post.
GeoidGrid vdatum_grid(const Georef &g, int width, int height, int vdatum);
void apply_vdatum_rows(std::vector<double> &h_m, const std::vector<uint8_t> &valid, int width, int y0, int n,
                       const Georef &g, int vdatum, const GeoidGrid &geoid);

}  // namespace ct_host
