// families.hpp -- the benchmark's ray families (ct_bench, and the rays
// ct_bench_m4_data bakes for the Cortex-M4 instruction counts): nadir,
// oblique 30 deg, grazing 3 deg, horizontal and the paper's long horizontal
// rays (400-600 incremental steps), from random points of the tile.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
#include "terrain.hpp"

namespace {

struct FamilyRays {
    std::string name;
    std::vector<ct_ray> rays;
};

double elev_deg_rand(ct_rng *r, double lo, double hi) { return lo + (hi - lo) * ct_rng_unit(r); }

// Ray families in the paper's spirit, in the metric frame of the terrain;
// azimuth_deg >= 0 puts every ray (within 1e-3 rad) in that direction.
std::vector<FamilyRays> make_families(const ct_host::Terrain &t, const ct_package &p, int n, uint64_t seed,
                                      double azimuth_deg = -1)
{
    ct_rng r;
    ct_rng_seed(&r, seed);
    double lo, hi;
    dem_cases::minmax(t, &lo, &hi);
    double cw = t.width - 1, ch = t.height - 1;
    std::vector<FamilyRays> fam = {{"nadir", {}}, {"oblique30", {}}, {"grazing3", {}}, {"horizontal", {}},
                                   {"paper_long", {}}};
    auto start_above = [&](double x, double y, double el_deg, double az) {
        double d[3];
        dem_cases::metric_dir(t, az, el_deg * M_PI / 180, d);
        if (el_deg <= -89.999) d[0] = d[1] = 0;
        return dem_cases::to_ray(x, y, hi + 10, d);
    };
    for (int k = 0; k < n; ++k) {
        double x = ct_rng_unit(&r) * cw, y = ct_rng_unit(&r) * ch, az = ct_rng_unit(&r) * 2 * M_PI;
        if (azimuth_deg >= 0) az = azimuth_deg * M_PI / 180 + 1e-3 * ct_rng_unit(&r);
        fam[0].rays.push_back(start_above(x, y, -90 + elev_deg_rand(&r, 0, 0.0), az));
        fam[1].rays.push_back(start_above(x, y, -30, az));
        fam[2].rays.push_back(start_above(x, y, -3, az));
        {
            double d[3];
            dem_cases::metric_dir(t, az, 0, d);
            d[2] = 0;
            double s = dem_cases::surf(t, x, y);
            fam[3].rays.push_back(dem_cases::to_ray(x, y, s + ct_rng_unit(&r) * (hi - s), d));
        }
    }
    // paper-like long rays: horizontal rays that need 400..600 incremental steps
    int tries = 0;
    while ((int)fam[4].rays.size() < n && tries < 400 * n) {
        ++tries;
        double x = ct_rng_unit(&r) * cw, y = ct_rng_unit(&r) * ch, az = ct_rng_unit(&r) * 2 * M_PI;
        if (azimuth_deg >= 0) az = azimuth_deg * M_PI / 180 + 1e-3 * ct_rng_unit(&r);
        double d[3];
        dem_cases::metric_dir(t, az, 0, d);
        d[2] = 0;
        double s = dem_cases::surf(t, x, y);
        ct_ray ray = dem_cases::to_ray(x, y, s + 0.3 * (hi - s) * ct_rng_unit(&r), d);
        ct_hit h;
        ct_status st = ct_trace(&p, &ray, CT_METHOD_INCREMENTAL, &h);
        if ((st == CT_HIT || st == CT_MISS) && h.steps >= 400 && h.steps <= 600) fam[4].rays.push_back(ray);
    }
    return fam;
}

}  // namespace
