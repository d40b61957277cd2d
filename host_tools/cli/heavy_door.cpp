// heavy_door.cpp -- the `conetrace` binary's side of heavy_door.hpp: loads
// conetrace_heavy.so from the binary's own directory on first use and
// forwards read_dem_pixels, the row reader, dem_needs_warp and warp_dem to it.  Linked into
// the binary only (in place of dem_pixels.cpp and warp.cpp).
#include "heavy_door.hpp"

#include <dlfcn.h>
#include <limits.h>
#include <unistd.h>

#include <mutex>
#include <stdexcept>

namespace ct_host {
namespace {

std::string plugin_path()
{
    char buf[PATH_MAX];
    const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
    std::string dir = ".";
    if (n > 0) {
        dir.assign(buf, (size_t)n);
        const size_t slash = dir.rfind('/');
        dir = slash == std::string::npos ? "." : dir.substr(0, slash);
    }
    return dir + "/conetrace_heavy.so";
}

const HeavyDoor &door()
{
    static std::once_flag once;
    static const HeavyDoor *d = nullptr;
    static std::string failure;
    std::call_once(once, [] {
        const std::string path = plugin_path();
        void *h = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!h) {
            const char *e = ::dlerror();
            failure = "cannot load the DEM reader " + path + " (" + (e ? e : "unknown error") + ")";
            return;
        }
        using Entry = const HeavyDoor *(*)(void);
        Entry entry = reinterpret_cast<Entry>(::dlsym(h, "conetrace_heavy_door"));
        const HeavyDoor *cand = entry ? entry() : nullptr;
        if (!cand || cand->version != kHeavyDoorVersion) {
            failure = path + ": not this conetrace's DEM reader (rebuild it)";
            return;
        }
        d = cand;  // the plugin stays loaded for the process's life
    });
    if (!d) throw Error(failure);
    return *d;
}

void rethrow(int code, const std::string &why)
{
    if (code == 1) throw Error(why);
    if (code != 0) throw std::runtime_error(why);
}

}  // namespace

void read_dem_pixels(const std::string &path, DemRaster &r, bool &is_tiff)
{
    std::string why;
    rethrow(door().read_pixels(path, &r, &is_tiff, &why), why);
}

void *open_dem_pixel_rows(const std::string &path, DemRaster &r, bool &is_tiff)
{
    std::string why;
    void *h = nullptr;
    rethrow(door().open_rows(path, &r, &is_tiff, &h, &why), why);
    return h;
}

void read_dem_pixel_rows(void *handle, int y0, int n, std::vector<double> &h)
{
    std::string why;
    rethrow(door().read_rows(handle, y0, n, &h, &why), why);
}

void close_dem_pixel_rows(void *handle)
{
    if (handle) door().close_rows(handle);
}

bool dem_needs_warp(const std::string &path, const WarpOptions &o)
{
    std::string why;
    bool needs = false;
    rethrow(door().needs_warp(path, o, &needs, &why), why);
    return needs;
}

DemRaster warp_dem(const std::string &path, const WarpOptions &o)
{
    std::string why;
    DemRaster r;
    rethrow(door().warp(path, o, &r, &why), why);
    return r;
}

}  // namespace ct_host
