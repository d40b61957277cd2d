// heavy_door.hpp -- the door between the `conetrace` binary and its two heavy
// libraries, OpenImageIO (DEM pixels of any format) and GDAL (warping).
//
// Linked into the binary, the two would be loaded on every start: with their
// ~270 shared libraries (OpenCV, FFmpeg, GStreamer, ... behind OpenImageIO)
// that costs ~0.15-0.25 s per run before `main`, more than a whole viewshed.
// So they live in a plugin, conetrace_heavy.so beside the binary
// (heavy_plugin.cpp: dem_pixels.cpp and warp.cpp), loaded with dlopen the
// first time a DEM is read; heavy_door.cpp, linked into the binary only,
// defines read_dem_pixels, the row reader, dem_needs_warp and warp_dem by
// calling through this table.  Tests and benchmarks link dem_pixels.cpp and warp.cpp directly.
#pragma once

#include <string>
#include <vector>

#include "dem_io.hpp"
#include "warp.hpp"

namespace ct_host {

// Each call returns 0 when it succeeded, 1 when it threw ct_host::Error
// (*why its text), 2 for any other exception (*why its what()).
struct HeavyDoor {
    int version;  // kHeavyDoorVersion
    int (*read_pixels)(const std::string &path, DemRaster *r, bool *is_tiff, std::string *why);
    int (*needs_warp)(const std::string &path, const WarpOptions &o, bool *needs, std::string *why);
    int (*warp)(const std::string &path, const WarpOptions &o, DemRaster *r, std::string *why);
    // dem_io.hpp's open/read/close_dem_pixel_rows (a DEM a band of rows at a time)
    int (*open_rows)(const std::string &path, DemRaster *r, bool *is_tiff, void **handle, std::string *why);
    int (*read_rows)(void *handle, int y0, int n, std::vector<double> *h, std::string *why);
    void (*close_rows)(void *handle);
};
constexpr int kHeavyDoorVersion = 2;

}  // namespace ct_host

// The plugin's only exported symbol.
extern "C" const ct_host::HeavyDoor *conetrace_heavy_door(void);
