// warp_options.cpp -- the parts of warp.hpp that need no GDAL: the --utm
// zone's parser and the one-line summary of a resampling (warp.cpp holds
// the warper itself).
#include "warp.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace ct_host {

void parse_utm_zone(const std::string &s, WarpOptions *o)
{
    size_t k = 0;
    while (k < s.size() && std::isdigit((unsigned char)s[k])) k++;
    const bool shape = k >= 1 && k <= 2 && k + 1 == s.size() &&
                       std::strchr("NnSs", s[k]) != nullptr;
    const int zone = shape ? std::atoi(s.substr(0, k).c_str()) : 0;
    if (!shape || zone < 1 || zone > 60)
        throw Error("'" + s + "' is not a UTM zone (expected 1..60 followed by N or S, e.g. 17N)");
    o->utm_zone = zone;
    o->south = s[k] == 'S' || s[k] == 's';
}

std::string warp_summary(const DemRaster &r)
{
    const std::string from = r.geo.source_epsg ? "EPSG:" + std::to_string(r.geo.source_epsg) : "a non-EPSG CRS";
    char b[160];
    std::snprintf(b, sizeof b, "resampled from %s onto EPSG:%d at %g m, bilinear", from.c_str(), r.geo.epsg,
                  std::fabs(r.geo.posting_e));
    return b;
}

}  // namespace ct_host
