// vdatum.cpp -- see vdatum.hpp.
#include "vdatum.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <proj.h>

#include "conetrace.h"
#include "le.hpp"

namespace ct_host {

namespace {

const long double kQ61 = 2305843009213693952.0L;  // 2^61
int64_t q61_of_deg(long double deg) { return (int64_t)std::llround(deg * M_PIl / 180 * kQ61); }
long double deg_of_q61(int64_t q) { return (long double)q / kQ61 * 180 / M_PIl; }
const int kPerDegree = 4;  // EGM96 (egm96_15.gtx): nodes every 15', at multiples of 0.25 deg

ct_utm utm_of(int epsg)
{
    ct_utm z;
    if (ct_utm_zone_of_epsg(epsg, &z) != CT_OK)
        throw Error("a vertical datum needs a UTM CRS (EPSG 326zz or 327zz), not EPSG:" + std::to_string(epsg));
    return z;
}

// the library's view of a grid (little-endian values)
struct GridView {
    std::vector<uint8_t> le;
    ct_geoid_grid g{};
    explicit GridView(const GeoidGrid &grid) : le(grid.um.size() * 4)
    {
        for (size_t k = 0; k < grid.um.size(); ++k) put32(le, 4 * k, (uint32_t)grid.um[k]);
        g = ct_geoid_grid{(uint32_t)grid.w, (uint32_t)grid.h, grid.lat0_q61, grid.lon0_q61, grid.step_q61, le.data()};
    }
    // N in nm at a map point, or false
    bool at(const ct_utm &z, int64_t e_nm, int64_t n_nm, int64_t *n) const
    {
        int64_t lat = 0, lon = 0;
        return ct_utm_inverse(&z, e_nm, n_nm, &lat, &lon) == CT_OK && ct_geoid_at(&g, lat, lon, n) == CT_OK;
    }
};

}  // namespace

int parse_vdatum(const std::string &s)
{
    if (s == "unknown") return CT_VDATUM_UNKNOWN;
    if (s == "ellipsoid" || s == "wgs84") return CT_VDATUM_WGS84;
    if (s == "egm96") return CT_VDATUM_EGM96;
    throw Error("unknown vertical datum '" + s + "' (expected egm96, ellipsoid or unknown)");
}

Egm96::Egm96()
{
    PJ_CONTEXT *ctx = proj_context_create();
    PJ *pj = proj_create(ctx, "+proj=vgridshift +grids=egm96_15.gtx +multiplier=1");
    if (!pj) {
        std::string why = proj_context_errno_string(ctx, proj_context_errno(ctx));
        proj_context_destroy(ctx);
        throw Error("PROJ cannot read the EGM96 geoid egm96_15.gtx (" + why + "; Debian: proj-data)");
    }
    ctx_ = ctx;
    pj_ = pj;
    if (!std::isfinite(at(0.0, 0.0))) {
        proj_destroy(pj);
        proj_context_destroy(ctx);
        throw Error("PROJ's EGM96 grid egm96_15.gtx is not available (Debian: proj-data)");
    }
}

Egm96::~Egm96()
{
    proj_destroy(static_cast<PJ *>(pj_));
    proj_context_destroy(static_cast<PJ_CONTEXT *>(ctx_));
}

double Egm96::at(double lat_deg, double lon_deg) const
{
    PJ *pj = static_cast<PJ *>(pj_);
    proj_errno_reset(pj);
    PJ_COORD c = proj_trans(pj, PJ_FWD, proj_coord(proj_torad(lon_deg), proj_torad(lat_deg), 0.0, 0.0));
    if (proj_errno(pj) != 0 || !std::isfinite(c.xyz.z) || std::fabs(c.xyz.z) > 1000.0) return NAN;
    return c.xyz.z;
}

GeoidGrid make_geoid_grid(const Egm96 &egm, const Georef &geo, int width, int height)
{
    const ct_utm z = utm_of(geo.epsg);
    // the latitude and longitude range of the tile's boundary posts (the
    // projection is smooth and monotone enough over a tile that its
    // extremes lie on the boundary)
    const int64_t oe = metres_to_nm(geo.origin_e), on = metres_to_nm(geo.origin_n);
    const int64_t pe = metres_to_nm(geo.posting_e), pn = metres_to_nm(geo.posting_n);
    long double la0 = 1e9L, la1 = -1e9L, lo0 = 1e9L, lo1 = -1e9L;
    auto visit = [&](int i, int j) {
        int64_t lat = 0, lon = 0;
        if (ct_utm_inverse(&z, oe + pe / 2 + i * pe, on + pn / 2 + j * pn, &lat, &lon) != CT_OK)
            throw Error("the tile lies outside its UTM zone's domain");
        la0 = std::min(la0, deg_of_q61(lat));
        la1 = std::max(la1, deg_of_q61(lat));
        lo0 = std::min(lo0, deg_of_q61(lon));
        lo1 = std::max(lo1, deg_of_q61(lon));
    };
    for (int i = 0; i < width; ++i) {
        visit(i, 0);
        visit(i, height - 1);
    }
    for (int j = 0; j < height; ++j) {
        visit(0, j);
        visit(width - 1, j);
    }
    // nodes: multiples of 15', one beyond the range on each side
    const long k_la0 = (long)std::floor(la0 * kPerDegree) - 1, k_la1 = (long)std::ceil(la1 * kPerDegree) + 1;
    const long k_lo0 = (long)std::floor(lo0 * kPerDegree) - 1, k_lo1 = (long)std::ceil(lo1 * kPerDegree) + 1;
    GeoidGrid g;
    g.w = (int)(k_lo1 - k_lo0 + 1);
    g.h = (int)(std::min<long>(k_la1, 90 * kPerDegree) - std::max<long>(k_la0, -90 * kPerDegree) + 1);
    if (g.w > (int)CT_GEOID_MAX_NODES || g.h > (int)CT_GEOID_MAX_NODES) throw Error("the tile is too large for a geoid grid");
    const long top = std::min<long>(k_la1, 90 * kPerDegree);
    g.lat0_q61 = q61_of_deg((long double)top / kPerDegree);
    long lo_first = k_lo0;
    if (lo_first < -180 * kPerDegree) lo_first += 360 * kPerDegree;  // lon0 within +-180
    g.lon0_q61 = q61_of_deg((long double)lo_first / kPerDegree);
    g.step_q61 = q61_of_deg(1.0L / kPerDegree);
    g.um.resize((size_t)g.w * g.h);
    for (int j = 0; j < g.h; ++j)
        for (int i = 0; i < g.w; ++i) {
            const double lat = (double)(top - j) / kPerDegree, lon = (double)(k_lo0 + i) / kPerDegree;
            const double n = egm.at(lat, lon);
            if (!std::isfinite(n)) throw Error("PROJ has no EGM96 undulation at the tile");
            g.um[(size_t)j * g.w + i] = (int32_t)std::lround(n * 1e6);
        }
    return g;
}

double geoid_at(const GeoidGrid &grid, int epsg, double e_m, double n_m)
{
    ct_utm z;
    int64_t n = 0;
    if (grid.w < 2 || ct_utm_zone_of_epsg(epsg, &z) != CT_OK) return NAN;
    return GridView(grid).at(z, metres_to_nm(e_m), metres_to_nm(n_m), &n) ? (double)n * 1e-9 : NAN;
}

GeoidGrid vdatum_grid(const Georef &geo, int width, int height, int vdatum)
{
    if (vdatum == CT_VDATUM_UNKNOWN) return GeoidGrid();
    (void)utm_of(geo.epsg);  // a UTM CRS, or Error
    Egm96 egm;
    return make_geoid_grid(egm, geo, width, height);
}

void apply_vdatum_rows(std::vector<double> &h_m, const std::vector<uint8_t> &valid, int width, int y0, int n,
                       const Georef &geo, int vdatum, const GeoidGrid &geoid)
{
    if (vdatum != CT_VDATUM_EGM96) return;  // unknown, or ellipsoidal heights: as they are
    const ct_utm z = utm_of(geo.epsg);
    GridView v(geoid);
    const int64_t oe = metres_to_nm(geo.origin_e), on = metres_to_nm(geo.origin_n);
    const int64_t pe = metres_to_nm(geo.posting_e), pn = metres_to_nm(geo.posting_n);
    for (int jj = 0; jj < n; ++jj)
        for (int i = 0; i < width; ++i) {
            const size_t k = (size_t)jj * width + i;
            const int64_t j = (int64_t)y0 + jj;
            if (!valid.empty() && !valid[k]) continue;
            int64_t u = 0;
            if (!v.at(z, oe + pe / 2 + i * pe, on + pn / 2 + j * pn, &u))
                throw Error("a post lies outside its own geoid grid");
            h_m[k] += (double)u * 1e-9;
        }
}

void apply_vdatum(std::vector<double> &h_m, const std::vector<uint8_t> &valid, int width, int height,
                  const Georef &geo, int vdatum, GeoidGrid &geoid)
{
    geoid = vdatum_grid(geo, width, height, vdatum);
    apply_vdatum_rows(h_m, valid, width, 0, height, geo, vdatum, geoid);
}

}  // namespace ct_host
