// fuzz_host.cpp -- libFuzzer harness over the host tools' file readers (built
// with clang, ASan + UBSan, by tests/fuzz/fuzz_host.sh).  The first byte
// chooses the reader, the rest is the file's content, written to a
// per-process temporary file ($CT_FUZZ_TMPDIR or /tmp; removed after each
// input):
//   0  rays CSV            ct_host::read_rays_csv     (host_io.hpp)
//   1  pixels CSV          ct_host::read_pixels_csv   (camera_host.hpp)
//   2  DEM raster          ct_host::DemRows, read_dem (dem_io.hpp; OpenImageIO,
//                          libtiff + libgeotiff)
//   3  .cameramodel        ct_host::read_cameramodel  (libmrcal's reader), then
//                          lib_camera as the CLI does
//   4  geolocation scene   scene::read_scene          (tests/kit/scene.hpp)
// The contract: a call returns a result or throws ct_host::Error whose text
// is one line starting with the file's path; any other exception, a crash,
// a hang or a sanitizer report is a finding (abort).  Results are checked
// against what the readers promise (finite numbers, consistent sizes, a
// square nonzero posting, the nodata rule, ...).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <typeinfo>
#include <vector>

#include "camera_host.hpp"
#include "dem_io.hpp"
#include "host_io.hpp"
#include "scene.hpp"

namespace {

// stderr as the process started: read_cameramodel points fd 2 at a
// temporary file while mrcal parses (a report made then would be lost; the
// sanitizers' reports go to files, fuzz_host.sh's log_path)
int g_stderr = -1;

[[noreturn]] void finding(const std::string &what)
{
    const std::string m = "fuzz_host: FINDING: " + what + "\n";
    if (write(g_stderr >= 0 ? g_stderr : 2, m.data(), m.size()) < 0) {
    }
    std::abort();
}

void check(bool ok, const char *what)
{
    if (!ok) finding(std::string("broken promise: ") + what);
}

std::string g_dir;

std::string temp_path(const char *ext)
{
    if (g_dir.empty()) {
        const char *d = std::getenv("CT_FUZZ_TMPDIR");
        g_dir = d && *d ? d : "/tmp";
    }
    return g_dir + "/ct_fuzz_host." + std::to_string((long)getpid()) + ext;
}

// The clear error: one line naming the file.
void check_error(const ct_host::Error &e, const std::string &path)
{
    const std::string m = e.what();
    if (m.compare(0, path.size(), path) != 0 || m.size() <= path.size() || m[path.size()] != ':')
        finding("error text does not start with the path: '" + m.substr(0, 300) + "'");
    for (char c : m)
        if ((unsigned char)c < 0x20 || c == 0x7f)
            finding("error text is not one plain line (control character " + std::to_string((int)c) + "): '" +
                    m.substr(0, 300) + "'");
    if (m.size() > 2000) finding("error text of " + std::to_string(m.size()) + " characters");
}

// Lines after the header that hold something (read_number_csv's rule): each
// gives a row or an error.
size_t data_lines(const uint8_t *p, size_t n)
{
    size_t lines = 0, k = 0;
    while (k < n && p[k] != '\n') ++k;  // the header
    while (k < n) {
        ++k;  // past '\n'
        bool blank = true;
        size_t b = k;
        while (k < n && p[k] != '\n') {
            if (p[k] != ' ' && p[k] != '\t' && p[k] != '\r' && p[k] != '\f' && p[k] != '\v') blank = false;
            ++k;
        }
        if (b < n && !blank) ++lines;
        if (b == n) break;
    }
    return lines;
}

void rays(const std::string &path, const uint8_t *p, size_t n)
{
    std::vector<ct_host::MapRay> r = ct_host::read_rays_csv(path);
    check(r.size() == data_lines(p, n), "rays: one ray per non-blank line");
    for (const ct_host::MapRay &m : r) {
        const double v[6] = {m.e, m.n, m.h, m.de, m.dn, m.dh};
        for (double x : v) check(std::isfinite(x), "rays: finite numbers only (nan, inf refused)");
    }
}

void pixels(const std::string &path, const uint8_t *p, size_t n)
{
    std::vector<ct_host::PixelRow> r = ct_host::read_pixels_csv(path);
    check(r.size() == data_lines(p, n), "pixels: one row per non-blank line");
    for (const ct_host::PixelRow &q : r) {
        check(std::isfinite(q.u) && std::isfinite(q.v), "pixels: finite numbers only");
        check(!q.u_text.empty() && !q.v_text.empty(), "pixels: the fields' text kept");
        for (const std::string *t : {&q.u_text, &q.v_text})
            for (char c : *t)
                check(c != ' ' && c != ',' && (unsigned char)c >= 0x20 && c != 0x7f,
                      "pixels: the fields' text a number's, without blanks, commas or control characters");
        check(std::strtod(q.u_text.c_str(), nullptr) == q.u && std::strtod(q.v_text.c_str(), nullptr) == q.v,
              "pixels: the text is the value's");
        int64_t uq, vq;
        if (ct_host::pixel_to_q16(q.u, q.v, &uq, &vq))
            check(std::fabs(q.u) <= (double)CT_CAM_MAX_PIXEL && std::fabs(q.v) <= (double)CT_CAM_MAX_PIXEL,
                  "pixel_to_q16 within the limit");
    }
}

const char *const kSampleTypes[] = {"int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"};

void check_header(const ct_host::DemRaster &r)
{
    check(r.width > 0 && r.height > 0, "dem: a positive size");
    bool known = false;
    for (const char *t : kSampleTypes) known = known || r.sample_type == t;
    check(known, "dem: a documented sample type");
    if (r.has_georef) {
        const ct_host::Georef &g = r.geo;
        check(std::isfinite(g.origin_e) && std::isfinite(g.origin_n) && std::isfinite(g.posting_e) &&
                  std::isfinite(g.posting_n),
              "dem: a finite georeference");
        check(g.posting_e != 0 && g.posting_n != 0, "dem: a nonzero posting");
        const double a = std::fabs(g.posting_e), b = std::fabs(g.posting_n);
        check(std::fabs(a - b) <= 1e-9 * std::max(a, b), "dem: a square posting");
    }
    check(r.block_rows >= 0, "dem: block rows not negative");
}

void check_valid(const ct_host::DemRaster &hdr, const std::vector<double> &h, const std::vector<uint8_t> &valid)
{
    check(h.size() == valid.size(), "dem: as many flags as heights");
    for (size_t k = 0; k < h.size(); ++k) {
        if (!valid[k]) check(std::isnan(h[k]) || hdr.has_nodata, "dem: nodata only for NaN or GDAL_NODATA");
        if (std::isnan(h[k])) check(valid[k] == 0, "dem: NaN is nodata");
        else if (!hdr.has_nodata) check(valid[k] == 1, "dem: without GDAL_NODATA every number is valid");
        else if (hdr.sample_type == "float64")
            check(valid[k] == (h[k] != hdr.nodata), "dem: the nodata rule (float64)");
    }
}

void dem(const std::string &path)
{
    // as the CLI: the header first (DemRows), the whole raster only when it
    // is small (a header may promise 2^30 posts of compressed data)
    size_t posts;
    ct_host::DemRaster hdr;
    {
        ct_host::DemRows rows(path);
        hdr = rows.header();
        check_header(hdr);
        check(hdr.h.empty(), "dem: the header holds no pixels");
        posts = (size_t)hdr.width * (size_t)hdr.height;
        if ((size_t)hdr.width <= 4096) {
            // the first band as build_mosaic reads it
            std::vector<double> h;
            std::vector<uint8_t> valid;
            const int n = std::min(hdr.height, 4);
            if ((size_t)hdr.width * (size_t)std::max(n, std::min(hdr.block_rows, hdr.height)) <= ((size_t)1 << 22)) {
                rows.read(0, n, h, valid);
                check(h.size() == (size_t)hdr.width * n, "dem: a band's size");
                check_valid(hdr, h, valid);
            }
        }
    }
    if (posts > ((size_t)1 << 20)) return;
    ct_host::DemRaster r = ct_host::read_dem(path);
    check_header(r);
    check(r.width == hdr.width && r.height == hdr.height && r.sample_type == hdr.sample_type &&
              r.has_georef == hdr.has_georef && r.has_nodata == hdr.has_nodata,
          "dem: read_dem agrees with the header");
    check(r.h.size() == posts, "dem: width x height heights");
    check_valid(r, r.h, r.valid);
}

void cameramodel(const std::string &path)
{
    ct_host::CameraModel m = ct_host::read_cameramodel(path);
    check(!m.model.empty(), "cameramodel: a lens model name");
    mrcal_lensmodel_t lm;
    check(mrcal_lensmodel_from_name(&lm, m.model.c_str()), "cameramodel: a model mrcal knows");
    check((int)m.intrinsics.size() == mrcal_lensmodel_num_params(&lm), "cameramodel: the model's intrinsics");
    // what geoloc does next (a small imager: baking a big one's grid is slow)
    if ((uint64_t)m.width * m.height <= ((uint64_t)1 << 20)) {
        ct_host::LibCamera c = ct_host::lib_camera(m, path);
        (void)c;
    }
}

void read_scene_file(const std::string &path)
{
    scene::Scene s = scene::read_scene(path);
    check(!s.dem.empty() && !s.camera.empty() && !s.lens_model.empty(), "scene: dem, camera and lens given");
    check(s.tile_x >= 1 && s.tile_x <= 8 && s.tile_y >= 1 && s.tile_y <= 8, "scene: tile 1..8");
    check((s.effects & ~7u) == 0, "scene: known effects");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (g_stderr < 0) g_stderr = dup(2);
    if (size < 1) return 0;
    const int which = data[0] % 5;
    static const char *const ext[5] = {".csv", ".csv", ".tif", ".cameramodel", ".scene"};
    const std::string path = temp_path(ext[which]);
    {
        std::FILE *f = std::fopen(path.c_str(), "wb");
        if (!f) finding("cannot write " + path);
        if (size > 1 && std::fwrite(data + 1, 1, size - 1, f) != size - 1) finding("cannot write " + path);
        std::fclose(f);
    }
    const uint8_t *p = data + 1;
    const size_t n = size - 1;
    try {
        switch (which) {
        case 0: rays(path, p, n); break;
        case 1: pixels(path, p, n); break;
        case 2: dem(path); break;
        case 3: cameramodel(path); break;
        default: read_scene_file(path); break;
        }
    } catch (const ct_host::Error &e) {
        check_error(e, path);
    } catch (const std::exception &e) {
        finding(std::string("an undocumented exception: ") + typeid(e).name() + ": " + e.what());
    } catch (...) {
        finding("an undocumented exception (not a std::exception)");
    }
    std::remove(path.c_str());
    return 0;
}
