// make_scene_cameras.cpp -- writes the .cameramodel of each scene
// (fixtures/scenes/*.scene) from its `lens`, `imager` and `pose` lines with
// full precision, then reads it back with mrcal's reader
// (mrcal_read_cameramodel_file) and checks every value is kept.  Usage (from the repository root):
//   build/tests/ct_make_scene_cameras fixtures/scenes/*.scene
// test_scenes checks every committed .cameramodel still matches its scene.
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "scene.hpp"

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: ct_make_scene_cameras SCENE...\n");
        return 2;
    }
    try {
        for (int a = 1; a < argc; ++a) {
            scene::Scene s = scene::read_scene(argv[a]);
            ct_host::CameraModel m = scene::model_of(s);
            mrcal_lensmodel_t lm;
            if (!mrcal_lensmodel_from_name(&lm, m.model.c_str())) throw ct_host::Error(s.path + ": unknown lens model");
            int n = mrcal_lensmodel_num_params(&lm);
            if (n != (int)m.intrinsics.size())
                throw ct_host::Error(s.path + ": " + m.model + " needs " + std::to_string(n) + " intrinsics");
            // the text is written here, not by mrcal_write_cameramodel_file:
            // libmrcal 2.2's C writer prints "%f" (6 decimals: 1e-6 rad,
            // 1e-6 m); "%.17g" keeps every bit, and mrcal's reader reads it
            std::string out = s.dir + "/" + s.camera;
            std::FILE *f = std::fopen(out.c_str(), "w");
            if (!f) throw ct_host::Error(out + ": cannot write");
            std::fprintf(f, "# written by ct_make_scene_cameras from %s (full precision)\n{\n", s.path.c_str());
            std::fprintf(f, "  'lensmodel':  '%s',\n  'intrinsics': [", m.model.c_str());
            for (int k = 0; k < n; ++k) std::fprintf(f, " %.17g,", m.intrinsics[(size_t)k]);
            std::fprintf(f, " ],\n  'imagersize': [ %u, %u ],\n  'extrinsics': [", m.width, m.height);
            for (int k = 0; k < 6; ++k) std::fprintf(f, " %.17g,", m.rt_cam_ref[k]);
            std::fprintf(f, " ]\n}\n");
            if (std::fclose(f) != 0) throw ct_host::Error(out + ": cannot write");
            ct_host::CameraModel back = ct_host::read_cameramodel(out);
            double worst = 0;
            for (int k = 0; k < 6; ++k) worst = std::max(worst, std::fabs(back.rt_cam_ref[k] - m.rt_cam_ref[k]));
            if (worst != 0 || back.intrinsics != m.intrinsics || back.model != m.model)
                throw ct_host::Error(out + ": mrcal reads back a different model");
            std::printf("%s: %s, %s %ux%u, rt read back within %.3g\n", s.path.c_str(), out.c_str(), m.model.c_str(),
                        m.width, m.height, worst);
        }
    } catch (const std::exception &e) {
        std::fprintf(stderr, "ct_make_scene_cameras: %s\n", e.what());
        return 1;
    }
    return 0;
}
