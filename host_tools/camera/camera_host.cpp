// camera_host.cpp -- see camera_host.hpp.
#include "camera_host.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

extern "C" {
#include <mrcal/mrcal.h>
}

#include "host_io.hpp"  // status_name, read_number_csv
#include "terrain.hpp"  // ct_host::Error

namespace ct_host {

typedef long double ld;

namespace {

// Run f with stderr redirected to a temporary file; return the last message
// mrcal wrote there, without its "source.c(123): " prefix ("" if none), as
// one line: a message may run over several lines (mrcal quotes the text it
// could not parse), and control characters are blanked (a '\r' in the
// file would overwrite the terminal's line); cut to 300 characters.
template <class F>
std::string quiet_mrcal(F f)
{
    std::fflush(stderr);
    std::FILE *cap = std::tmpfile();
    int saved = dup(2);
    if (cap && saved >= 0) dup2(fileno(cap), 2);
    f();
    std::fflush(stderr);
    if (cap && saved >= 0) dup2(saved, 2);
    if (saved >= 0) close(saved);
    std::string why;
    if (cap) {
        std::rewind(cap);
        char buf[512];
        bool at_line_start = true;
        while (std::fgets(buf, sizeof buf, cap)) {
            std::string s(buf);
            const bool whole = !s.empty() && s.back() == '\n';
            size_t k = s.find("): ");
            if (at_line_start && k != std::string::npos && k < 60) {
                why = s.substr(k + 3);  // a new message
            } else if (why.size() < 400) {
                why += ' ';  // the message goes on
                why += s;
            }
            at_line_start = whole;
        }
        std::fclose(cap);
        for (char &c : why)
            if ((unsigned char)c < 0x20 || c == 0x7f) c = ' ';
        std::string one;  // blanks collapsed, ends trimmed
        for (char c : why)
            if (c != ' ' || (!one.empty() && one.back() != ' ')) one += c;
        while (!one.empty() && one.back() == ' ') one.pop_back();
        if (one.size() > 300) one = one.substr(0, 300) + " ...";
        why = one;
    }
    return why;
}

}  // namespace

void rotation_from_r(const ld r[3], ld R[9])
{
    ld t2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    ld t = std::sqrt(t2);
    // R = I + a [r]x + b [r]x^2, a = sin t / t, b = (1 - cos t) / t^2
    ld a, b;
    if (t < 1e-4L) {
        a = 1 - t2 / 6 + t2 * t2 / 120;
        b = 0.5L - t2 / 24 + t2 * t2 / 720;
    } else {
        a = std::sin(t) / t;
        b = (1 - std::cos(t)) / t2;
    }
    const ld x = r[0], y = r[1], z = r[2];
    // [r]x^2 = r r^T - t2 I
    R[0] = 1 + b * (x * x - t2);
    R[1] = -a * z + b * x * y;
    R[2] = a * y + b * x * z;
    R[3] = a * z + b * x * y;
    R[4] = 1 + b * (y * y - t2);
    R[5] = -a * x + b * y * z;
    R[6] = -a * y + b * x * z;
    R[7] = a * x + b * y * z;
    R[8] = 1 + b * (z * z - t2);
}

HostPose pose_from_rt_cam_ref(const double rt[6])
{
    HostPose p;
    ld r[3] = {rt[0], rt[1], rt[2]}, R_cam_map[9];
    for (int k = 0; k < 6; ++k)
        if (!std::isfinite(rt[k])) throw Error("extrinsics rt_cam_ref are not finite");
    rotation_from_r(r, R_cam_map);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) p.R_map_cam[3 * i + j] = R_cam_map[3 * j + i];
    // c = -R_cam_map^T t = -R_map_cam t
    for (int i = 0; i < 3; ++i) {
        ld s = 0;
        for (int j = 0; j < 3; ++j) s -= p.R_map_cam[3 * i + j] * (ld)rt[3 + j];
        p.centre_m[i] = s;
        ld nm = std::nearbyint(s * 1e9L);
        if (!(std::fabs(nm) <= 2305843009213693952.0L)) throw Error("camera centre beyond 2^61 nm");
        p.centre_nm[i] = (int64_t)nm;
    }
    for (int k = 0; k < 9; ++k) p.R_map_cam_q30[k] = (int32_t)std::llround(p.R_map_cam[k] * 1073741824.0L);
    return p;
}

ct_lens lens_from_intrinsics(const std::string &model, const std::vector<double> &in, unsigned width,
                             unsigned height)
{
    ct_lens l;
    std::memset(&l, 0, sizeof l);
    size_t n;
    if (model == "LENSMODEL_PINHOLE") {
        l.model = CT_LENS_PINHOLE;
        n = 4;
    } else if (model == "LENSMODEL_OPENCV4") {
        l.model = CT_LENS_OPENCV4;
        n = 8;
    } else if (model == "LENSMODEL_OPENCV5") {
        l.model = CT_LENS_OPENCV5;
        n = 9;
    } else if (model == "LENSMODEL_OPENCV8") {
        l.model = CT_LENS_OPENCV8;
        n = 12;
    } else {
        throw Error("lens model " + model +
                    " is not supported (supported: LENSMODEL_PINHOLE, LENSMODEL_OPENCV4, LENSMODEL_OPENCV5, "
                    "LENSMODEL_OPENCV8)");
    }
    if (in.size() != n)
        throw Error(model + " needs " + std::to_string(n) + " intrinsics, got " + std::to_string(in.size()));
    for (double v : in)
        if (!std::isfinite(v)) throw Error("intrinsics are not finite");
    const double pmax = (double)CT_CAM_MAX_PIXEL;
    if (!(in[0] >= 1 && in[0] <= pmax && in[1] >= 1 && in[1] <= pmax))
        throw Error("focal lengths must be in [1, 2^20] pixels");
    if (!(std::fabs(in[2]) <= pmax && std::fabs(in[3]) <= pmax))
        throw Error("principal point beyond 2^20 pixels");
    const long double q32 = 4294967296.0L;
    l.fx_q32 = std::llround(in[0] * q32);
    l.fy_q32 = std::llround(in[1] * q32);
    l.cx_q32 = std::llround(in[2] * q32);
    l.cy_q32 = std::llround(in[3] * q32);
    for (size_t k = 4; k < n; ++k) {
        if (!(std::fabs(in[k]) <= 1024.0))
            throw Error("distortion coefficient " + std::to_string(k - 4) + " = " + std::to_string(in[k]) +
                        " beyond the library's range (|k| <= 1024)");
        l.dist_q48[k - 4] = std::llround(in[k] * 281474976710656.0L);  // Q48
    }
    l.width = width;
    l.height = height;
    return l;
}

namespace {

// libmrcal 2.2's parser (Debian 12) scans a quoted string to its closing
// quote and a '#' comment to its newline without stopping at the end of
// the text, and copies the lens model's name and each number into arrays
// on the stack: an unterminated string or a last comment line without a
// newline read past the end of the file's bytes (found by fuzz_host), a
// 10 MB number would overflow the stack.  What it is given is checked
// first (strings and comments found as its lexer finds them: a comment
// outside strings, strings closed by either quote); "" if acceptable.
std::string mrcal_unsafe(const std::string &t)
{
    if (t.find('\0') != std::string::npos) return "a NUL byte (not a text file)";
    size_t run = 0;  // characters of one number so far
    std::string last;  // the string before this one (a key: "lensmodel"?)
    for (size_t k = 0; k < t.size(); ++k) {
        const char c = t[k];
        if (c == '#') {
            k = t.find('\n', k);  // the caller appended a newline
            run = 0;
        } else if (c == '\'' || c == '"') {
            const size_t e = t.find_first_of("'\"", k + 1);
            if (e == std::string::npos) return "a string not closed (from byte " + std::to_string(k) + ")";
            if (last == "lensmodel" && e - k > 1000) return "a lens model name of over 1000 characters";
            last = t.substr(k + 1, std::min<size_t>(e - k - 1, 16));
            k = e;
            run = 0;
        } else if ((c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E') {
            if (++run > 1000) return "a number of over 1000 characters";
        } else {
            run = 0;
        }
    }
    return "";
}

}  // namespace

CameraModel read_cameramodel(const std::string &path)
{
    std::string text;
    {
        std::FILE *f = std::fopen(path.c_str(), "rb");
        if (!f) throw Error(path + ": " + std::strerror(errno));
        char buf[65536];
        size_t n;
        while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
            text.append(buf, n);
            if (text.size() > ((size_t)1 << 30)) {
                std::fclose(f);
                throw Error(path + ": over 1 GB: not a .cameramodel");
            }
        }
        const bool bad = std::ferror(f) != 0;
        std::fclose(f);
        if (bad) throw Error(path + ": cannot read");
    }
    text += '\n';  // a last comment line ends
    const std::string unsafe = mrcal_unsafe(text);
    if (!unsafe.empty()) throw Error(path + ": not a valid mrcal .cameramodel (" + unsafe + ")");
    // mrcal reports parse errors on stderr: capture them into one line
    mrcal_cameramodel_t *m = nullptr;
    std::string why = quiet_mrcal([&] { m = mrcal_read_cameramodel_string(text.c_str(), (int)text.size()); });
    if (!m) throw Error(path + ": not a valid mrcal .cameramodel" + (why.empty() ? "" : " (" + why + ")"));
    CameraModel c;
    char name[256];
    if (!mrcal_lensmodel_name(name, sizeof name, &m->lensmodel)) {
        mrcal_free_cameramodel(&m);
        throw Error(path + ": unknown lens model");
    }
    c.model = name;
    int n = mrcal_lensmodel_num_params(&m->lensmodel);
    c.intrinsics.assign(m->intrinsics, m->intrinsics + (n > 0 ? n : 0));
    for (int k = 0; k < 6; ++k) c.rt_cam_ref[k] = m->rt_cam_ref[k];
    c.width = m->imagersize[0];
    c.height = m->imagersize[1];
    mrcal_free_cameramodel(&m);
    return c;
}

bool is_parametric(const std::string &model)
{
    return model == "LENSMODEL_PINHOLE" || model == "LENSMODEL_OPENCV4" || model == "LENSMODEL_OPENCV5" ||
           model == "LENSMODEL_OPENCV8";
}

BakedGrid bake_grid(const CameraModel &m, double step_px)
{
    mrcal_lensmodel_t lm;
    if (!mrcal_lensmodel_from_name(&lm, m.model.c_str())) throw Error("unknown lens model " + m.model);
    if ((int)m.intrinsics.size() != mrcal_lensmodel_num_params(&lm))
        throw Error(m.model + ": wrong number of intrinsics");
    if (!(step_px >= 1 && step_px <= 4096)) throw Error("grid step must be in [1, 4096] pixels");
    if (m.width == 0 || m.height == 0) throw Error("the camera model has no imager size");
    BakedGrid b;
    ct_unproject_grid &g = b.grid;
    g.step_q16 = std::llround(step_px * 65536.0);
    const double step = g.step_q16 / 65536.0;
    const double u0 = -0.5 - step, v0 = -0.5 - step;
    g.u0_q16 = std::llround(u0 * 65536.0);
    g.v0_q16 = std::llround(v0 * 65536.0);
    const double su = g.u0_q16 / 65536.0, sv = g.v0_q16 / 65536.0;
    long nu = (long)std::floor((m.width - 0.5 - su) / step) + 3, nv = (long)std::floor((m.height - 0.5 - sv) / step) + 3;
    if (nu > (long)CT_GRID_MAX_NODES || nv > (long)CT_GRID_MAX_NODES)
        throw Error("grid of " + std::to_string(nu) + " x " + std::to_string(nv) + " nodes exceeds the library's " +
                    std::to_string(CT_GRID_MAX_NODES) + " per side; use a larger step");
    g.nu = (uint32_t)nu;
    g.nv = (uint32_t)nv;
    std::vector<mrcal_point2_t> q((size_t)nu * nv);
    for (long j = 0; j < nv; ++j)
        for (long i = 0; i < nu; ++i) {
            q[(size_t)j * nu + i].x = su + i * step;
            q[(size_t)j * nu + i].y = sv + j * step;
        }
    std::vector<mrcal_point3_t> v(q.size());
    bool ok = false;
    std::string why = quiet_mrcal([&] { ok = mrcal_unproject(v.data(), q.data(), (int)q.size(), &lm, m.intrinsics.data()); });
    if (!ok) throw Error(m.model + ": mrcal cannot unproject this model" + (why.empty() ? "" : " (" + why + ")"));
    b.rays = std::make_shared<std::vector<int32_t>>(3 * q.size(), 0);
    for (size_t k = 0; k < q.size(); ++k) {
        ld x = v[k].x, y = v[k].y, z = v[k].z, n = std::sqrt(x * x + y * y + z * z);
        if (!std::isfinite((double)n) || !(n > 0)) {
            ++b.missing;
            continue;
        }
        (*b.rays)[3 * k] = (int32_t)std::llround(x / n * 1073741824.0L);
        (*b.rays)[3 * k + 1] = (int32_t)std::llround(y / n * 1073741824.0L);
        (*b.rays)[3 * k + 2] = (int32_t)std::llround(z / n * 1073741824.0L);
    }
    g.rays_q30 = b.rays->data();
    g.rays_len = b.rays->size();
    return b;
}

LibCamera lib_camera(const CameraModel &m, const std::string &path, double grid_step_px)
{
    LibCamera c;
    ct_status st;
    try {
        c.host_pose = pose_from_rt_cam_ref(m.rt_cam_ref);
        if (is_parametric(m.model)) {
            ct_lens l = lens_from_intrinsics(m.model, m.intrinsics, m.width, m.height);
            st = ct_camera_init(&c.cam, &l);
        } else {
            c.baked = bake_grid(m, grid_step_px);
            st = ct_camera_init_grid(&c.cam, &c.baked.grid);
        }
    } catch (const Error &e) {
        throw Error(path + ": " + e.what());
    }
    if (st != CT_OK) throw Error(path + ": the library refuses the lens (" + status_name(st) + ")");
    st = ct_pose_init(&c.pose, c.host_pose.R_map_cam_q30, c.host_pose.centre_nm[0], c.host_pose.centre_nm[1],
                      c.host_pose.centre_nm[2]);
    if (st != CT_OK) throw Error(path + ": the library refuses the pose (" + status_name(st) + ")");
    return c;
}

std::vector<PixelRow> read_pixels_csv(const std::string &path)
{
    std::vector<PixelRow> rows;
    read_number_csv(
        path, {"u", "v"},
        [&](const double *v, const std::vector<std::string> &text) {
            rows.push_back(PixelRow{v[0], v[1], text[0], text[1]});
        },
        [&](size_t n) { rows.reserve(n); });
    return rows;
}

bool pixel_to_q16(double u, double v, int64_t *uq, int64_t *vq)
{
    const double lim = (double)CT_CAM_MAX_PIXEL;
    if (!(std::fabs(u) <= lim && std::fabs(v) <= lim)) return false;
    *uq = std::llround(u * 65536.0);
    *vq = std::llround(v * 65536.0);
    return true;
}

void append_nm_decimal(std::string &out, int64_t nm)
{
    // metres with nine decimals, exact: the digits of |nm| with a point
    // before the last nine (no printf: this runs once per output value),
    // written backwards into buf and appended at once
    uint64_t a = nm < 0 ? (uint64_t)0 - (uint64_t)nm : (uint64_t)nm;
    char buf[32];
    int n = 32, d = 0;
    while (d < 10 || a != 0) {  // at least "0.000000000"
        if (d == 9) buf[--n] = '.';
        buf[--n] = (char)('0' + (int)(a % 10u));
        a /= 10u;
        ++d;
    }
    if (nm < 0) buf[--n] = '-';
    out.append(buf + n, (size_t)(32 - n));
}

std::string nm_to_decimal(int64_t nm)
{
    std::string s;
    append_nm_decimal(s, nm);
    return s;
}

uint32_t effects_from_list(const std::string &list)
{
    uint32_t flags = 0u;
    std::stringstream ss(list);
    std::string tok;
    while (std::getline(ss, tok, ',')) {
        tok.erase(0, tok.find_first_not_of(' '));
        tok.erase(tok.find_last_not_of(' ') + 1);
        if (tok.empty()) continue;
        if (tok == "curvature") flags |= CT_EFFECT_CURVATURE;
        else if (tok == "refraction") flags |= CT_EFFECT_REFRACTION;
        else throw Error("--effects '" + list + "': unknown effect '" + tok + "' (curvature, refraction)");
    }
    return flags;
}

}  // namespace ct_host
