// camera_host.hpp -- host side of the camera: mrcal .cameramodel files to
// the library's fixed-point lens (ct_lens) and pose (ct_pose), and the
// rotation helpers (long double).  See conetrace.h "Camera and geolocation".
//
// Where the pose conversion happens: mrcal's extrinsics rt_cam_ref (the
// Rodrigues vector r and translation t that map map-frame points p_map to
// camera-frame points p_cam = R(r) p_map + t) are turned here, in long
// double, into R_map_cam = R(r)^T (Q30) and the camera centre
// c = -R(r)^T t (integer nm).  The flight library only sees those.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "conetrace.h"
#include "terrain.hpp"  // ct_host::Error

namespace ct_host {

// Rodrigues: R = rotation by |r| about r/|r|, row-major; well conditioned
// for every angle (series for sin(t)/t and (1 - cos t)/t^2 near 0; exact
// at t = pi: no r_from_R involved anywhere).
void rotation_from_r(const long double r[3], long double R[9]);

struct HostPose {
    long double R_map_cam[9];      // row-major
    long double centre_m[3];       // camera centre, map frame, metres
    int32_t R_map_cam_q30[9];      // rounded to Q30
    int64_t centre_nm[3];          // rounded to nm
};
// From mrcal's rt_cam_ref (map frame = reference).  Throws Error when the
// centre is beyond +-2^61 nm or not finite.
HostPose pose_from_rt_cam_ref(const double rt_cam_ref[6]);

// A lens from mrcal's model name (LENSMODEL_PINHOLE, LENSMODEL_OPENCV4,
// LENSMODEL_OPENCV5, LENSMODEL_OPENCV8) and intrinsics (fx fy cx cy then
// the distortion), rounded to the library's formats (Q32 and Q48).  Throws Error
// naming the problem (unsupported model, wrong count, value out of range).
ct_lens lens_from_intrinsics(const std::string &model, const std::vector<double> &intrinsics,
                             unsigned width, unsigned height);

struct CameraModel {
    std::string model;              // e.g. "LENSMODEL_OPENCV8"
    std::vector<double> intrinsics; // as in the file
    double rt_cam_ref[6] = {0, 0, 0, 0, 0, 0};
    unsigned width = 0, height = 0;
};
// Read a .cameramodel with libmrcal's C reader (mrcal_read_cameramodel_file).
// Throws Error("<path>: <reason>") (mrcal's own messages on stderr are
// suppressed so a failure is one line).
CameraModel read_cameramodel(const std::string &path);

// Any mrcal lens model baked into an unprojection grid (ct_unproject_grid):
// unit rays from mrcal_unproject at pixels u0 + i * step covering the
// imager (pixel centres -0.5 .. width - 0.5) with the 4 x 4 Catmull-Rom
// support; nodes mrcal cannot unproject are (0, 0, 0).  The table is
// shared so copies of the grid stay valid.  Throws Error when the grid
// would exceed the library's limits.
struct BakedGrid {
    std::shared_ptr<std::vector<int32_t>> rays;
    ct_unproject_grid grid;
    long missing = 0;  // nodes without a ray
};
BakedGrid bake_grid(const CameraModel &m, double step_px);

// Default grid step for models the library has no closed form for (see
// docs/geolocation.md, "Unprojection grids": accuracy vs step).
constexpr double kDefaultGridStepPx = 16.0;

// A camera ready for the library: lens checked by ct_camera_init (PINHOLE,
// OPENCV4/5/8) or baked into a grid (any other model mrcal can unproject,
// step grid_step_px), pose by ct_pose_init.  Throws Error("<path>: ...")
// when either refuses.
struct LibCamera {
    ct_camera cam;
    ct_pose pose;
    HostPose host_pose;
    BakedGrid baked;  // grid cameras only
};
bool is_parametric(const std::string &model);
LibCamera lib_camera(const CameraModel &m, const std::string &path, double grid_step_px = kDefaultGridStepPx);

// pixels.csv: header naming columns u and v (any order, other columns
// ignored), one pixel per line (mrcal convention: (0,0) is the centre of
// the top-left pixel).  Returns the values and the text of each field as
// given.  Throws Error("<path>:<line>: <reason>").
struct PixelRow {
    double u, v;
    std::string u_text, v_text;  // the fields as given (blanks removed)
};
std::vector<PixelRow> read_pixels_csv(const std::string &path);

// Pixel to Q16 (rounded); false if beyond +-CT_CAM_MAX_PIXEL or not finite.
bool pixel_to_q16(double u, double v, int64_t *u_q16, int64_t *v_q16);

// Integer nanometres as exact decimal metres ("-123.000000456").
std::string nm_to_decimal(int64_t nm);
void append_nm_decimal(std::string &out, int64_t nm);  // the same, appended

// --effects LIST: comma-separated curvature, refraction (spaces around the
// names allowed; empty: none) to CT_EFFECT_* flags.  Throws Error naming
// the unknown effect.
uint32_t effects_from_list(const std::string &list);

}  // namespace ct_host
