// dem_cases_real.cpp -- the bundled real DEM as a test case.
#include <cstdio>

#include "dem_cases.hpp"
#include "dem_io.hpp"

namespace dem_cases {

ct_host::Terrain real_terrain()
{
    ct_host::DemRaster r = ct_host::read_dem(CT_FIXTURES_DIR "/jacksboro_fault_dem.tif");
    return ct_host::terrain_from_heights(r.width, r.height, r.h, r.valid, r.geo, 0.0);
}

std::vector<Case> real_cases()
{
    std::vector<Case> v;
    std::FILE *f = std::fopen(CT_FIXTURES_DIR "/jacksboro_fault_dem.tif", "rb");
    if (!f) return v;
    std::fclose(f);
    ct_host::Terrain t = real_terrain();
    v.push_back(make_case("jacksboro", t, 24, 1));
    v.push_back(make_case("jacksboro_r3", t, 24, 3));
    return v;
}

}  // namespace dem_cases
