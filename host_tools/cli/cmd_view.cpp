// cmd_view.cpp -- `conetrace view`: the image a camera would see.
//
//   conetrace view PKG --camera C.cameramodel [--effects LIST] [--threads T]
//                  -o view.png [--range range.tif]
//
// Every pixel of the camera's image (its extrinsics are the pose, as for
// geoloc) is geolocated by the flight library (ct_geolocate_batch,
// directional) and shaded by the terrain's slope there (the bilinear
// surface's normal against a light from the north-west, 45 degrees up), so
// a user can hold it next to a real frame to check a pose or a lens; sky
// and pixels outside the lens's field are light blue.  --range: the range
// from the camera centre to each pixel's hit in metres, a single-channel
// float32 TIFF of the image's size (NaN where nothing is hit).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "camera_host.hpp"
#include "conetrace.h"
#include "dem_io.hpp"
#include "host_io.hpp"
#include "picture.hpp"
#include "terrain.hpp"

using namespace ct_host;

int cmd_view(int argc, char **argv)
{
    CmdLine args;
    const std::string err =
        parse_cmdline(argc, argv, 2, {"--camera", "--effects", "--threads", "-o", "--range"}, {}, false, &args);
    if (!err.empty()) throw Error("view: " + err);
    std::map<std::string, std::string> &opt = args.opt;
    if (args.pos.size() != 1) throw Error("view needs exactly one package file");
    if (!opt.count("--camera")) throw Error("view needs --camera C.cameramodel");
    if (!opt.count("-o")) throw Error("view needs -o view.png");
    const int threads = opt.count("--threads") ? threads_option(opt["--threads"], "view") : 0;
    const std::string &path = args.pos[0];
    std::vector<uint8_t> bytes;
    ct_package p;
    open_package_file(path, &bytes, &p);
    const std::string cpath = opt["--camera"];
    const CameraModel cm = read_cameramodel(cpath);
    LibCamera cam = lib_camera(cm, cpath);
    const int W = (int)cm.width, H = (int)cm.height;
    if (W <= 0 || H <= 0 || (long)W * H > 64L * 1024 * 1024) throw Error(cpath + ": no usable image size");
    ct_effects fx = {0u, CT_REFRACTION_K_STD_Q16, 0, 0, nullptr};
    if (opt.count("--effects")) fx.flags = effects_from_list(opt["--effects"]);
    fx.flags |= CT_EFFECT_EARTH_FIT;
    // the camera against the package first (its status, as one call's)
    const int64_t uv0[2] = {0, 0};
    ct_geo none;
    const ct_status st = ct_geolocate_batch(&p, &cam.cam, &cam.pose, CT_METHOD_DIRECTIONAL, &fx, uv0, 0, &none, 0);
    if (st != CT_OK) throw Error(cpath + ": cannot geolocate from this camera (" + status_name(st) + ")");
    const size_t n = (size_t)W * H;
    // shading from the bilinear surface's normal at each hit
    const double post = std::fabs(p.posting_e_nm * 1e-9), hs = p.height_scale_nm * 1e-9;
    const Terrain t = terrain_from_package(p);
    auto code = [&](int i, int j) {
        return (double)t.at(std::max(0, std::min(t.width - 1, i)), std::max(0, std::min(t.height - 1, j)));
    };
    // light from the north-west, 45 degrees up, in (east, south, up) like the hillshade
    const double lx = -0.5, ly = -0.5, lz = std::sqrt(0.5);
    Image im(W, H);
    const bool want_range = opt.count("--range") != 0;
    std::vector<float> range(want_range ? n : 0, NAN);
    std::atomic<long> hits{0};
    // chunks of pixels geolocated and shaded where they are (the image and
    // the range are all that is kept: 3 and 4 bytes a pixel)
    parallel_chunks(n, threads, 16384, [&](size_t b, size_t e) {
        std::vector<int64_t> uv(2 * (e - b));
        for (size_t k = b; k < e; ++k) {
            uv[2 * (k - b)] = (int64_t)(k % (size_t)W) << 16;
            uv[2 * (k - b) + 1] = (int64_t)(k / (size_t)W) << 16;
        }
        std::vector<ct_geo> g(e - b);
        (void)ct_geolocate_batch(&p, &cam.cam, &cam.pose, CT_METHOD_DIRECTIONAL, &fx, uv.data(), e - b, g.data(),
                                 e - b);
        long h = 0;
        for (size_t k = b; k < e; ++k) {
            const ct_geo &q = g[k - b];
            const int u = (int)(k % (size_t)W), v = (int)(k / (size_t)W);
            if (q.status != CT_HIT && q.status != CT_HIT_VOID) {
                im.set(u, v, Rgb{200, 222, 245});
                continue;
            }
            h++;
            const double x = q.hit.x_q16 / 65536.0, y = q.hit.y_q16 / 65536.0;
            const int i = std::min((int)p.width - 2, std::max(0, (int)std::floor(x)));
            const int j = std::min((int)p.height - 2, std::max(0, (int)std::floor(y)));
            const double fu = x - i, fv = y - j;
            const double h00 = code(i, j), h10 = code(i + 1, j), h01 = code(i, j + 1), h11 = code(i + 1, j + 1);
            const double gx = ((h10 - h00) * (1 - fv) + (h11 - h01) * fv) * hs / post;
            const double gy = ((h01 - h00) * (1 - fu) + (h11 - h10) * fu) * hs / post;  // towards the south (grid y)
            const double nn = std::sqrt(gx * gx + gy * gy + 1);
            const double sh = std::max(0.0, (-gx * lx - gy * ly + lz) / nn);
            const double de = (q.hit.e_nm - cam.pose.e_nm) * 1e-9, dn = (q.hit.n_nm - cam.pose.n_nm) * 1e-9,
                         dh = (q.hit.h_nm - cam.pose.h_nm) * 1e-9;
            const double r = std::sqrt(de * de + dn * dn + dh * dh);
            if (want_range) range[k] = (float)r;
            // a little atmospheric fade with range (5 % per 10 km)
            const double fade = std::min(0.5, r / 200000.0);
            const double val = (0.2 + 0.75 * sh) * (1 - fade) + 0.85 * fade;
            im.set(u, v, Rgb{(uint8_t)std::lround(255 * val * 0.92), (uint8_t)std::lround(255 * val * 0.95),
                             (uint8_t)std::lround(255 * val * 0.85)});
        }
        hits += h;
    });
    write_png_atomic(opt["-o"], im, "conetrace view: " + cpath, "conetrace view");
    if (want_range) {
        write_float_tiff(opt["--range"], W, H, range,
                         "conetrace view: range from the camera centre, metres (NaN: no hit)");
    }
    std::fprintf(stderr, "view: %dx%d pixels, %ld hit the terrain\n", W, H, hits.load());
    return 0;
}
