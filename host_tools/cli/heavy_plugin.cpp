// heavy_plugin.cpp -- conetrace_heavy.so: the DEM pixel reader (OpenImageIO)
// and the warper (GDAL) behind the door of heavy_door.hpp.  Built with hidden
// visibility: conetrace_heavy_door is its only exported symbol.
#include "heavy_door.hpp"

#include <exception>

namespace {

template <typename F>
int guarded(std::string *why, F f)
{
    try {
        f();
        return 0;
    } catch (const ct_host::Error &e) {
        *why = e.what();
        return 1;
    } catch (const std::exception &e) {
        *why = e.what();
        return 2;
    }
}

int read_pixels(const std::string &path, ct_host::DemRaster *r, bool *is_tiff, std::string *why)
{
    return guarded(why, [&] { ct_host::read_dem_pixels(path, *r, *is_tiff); });
}

int needs_warp(const std::string &path, const ct_host::WarpOptions &o, bool *needs, std::string *why)
{
    return guarded(why, [&] { *needs = ct_host::dem_needs_warp(path, o); });
}

int warp(const std::string &path, const ct_host::WarpOptions &o, ct_host::DemRaster *r, std::string *why)
{
    return guarded(why, [&] { *r = ct_host::warp_dem(path, o); });
}

int open_rows(const std::string &path, ct_host::DemRaster *r, bool *is_tiff, void **handle, std::string *why)
{
    return guarded(why, [&] { *handle = ct_host::open_dem_pixel_rows(path, *r, *is_tiff); });
}

int read_rows(void *handle, int y0, int n, std::vector<double> *h, std::string *why)
{
    return guarded(why, [&] { ct_host::read_dem_pixel_rows(handle, y0, n, *h); });
}

void close_rows(void *handle) { ct_host::close_dem_pixel_rows(handle); }

const ct_host::HeavyDoor kDoor = {ct_host::kHeavyDoorVersion, read_pixels, needs_warp, warp, open_rows, read_rows,
                                  close_rows};

}  // namespace

extern "C" __attribute__((visibility("default"))) const ct_host::HeavyDoor *conetrace_heavy_door(void)
{
    return &kDoor;
}
