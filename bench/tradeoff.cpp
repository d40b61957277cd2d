// tradeoff.cpp -- `make tradeoff`: what each knob buys and costs.
//
// On the bundled DEM and the scenes of fixtures/scenes/ (tests/kit/scene.hpp:
// ground truth by mrcal and the independent reference tracer), every knob
// that trades accuracy, memory or build time against tracing time, one at a
// time from the defaults (N = 24, r = 3, slice builder, directional, the
// scene's effects, chord 1 mm, closed-form lens):
//   package  N in {1, 4, 8, 16, 24, 32, 64} x r in {1, 2, 3, 4} (slice
//            builder), slices K in {16, 32, 128}, the brute-force builder;
//            on the four scenes over the plain DEM (one build per setting);
//   method   incremental, hierarchical, cone, directional;
//   effects  none, curvature, refraction, both (the sphere of the scene's
//            radius; the world has the scene's own effects), and the true
//            Earth (exact, fitted per call) for time (its error against the
//            scenes' sphere-model truth is not comparable: NaN);
//   chord    the true Earth's piece tolerance 0.5 mm .. 10 m, error against
//            the same pixels at 0.5 mm (err_ref = "finest chord": the finest
//            whose pieces every scene proves; a finer one refuses pixels,
//            docs/geolocation.md);
//   grid     the lens baked into an unprojection grid, step 4 .. 64 px.
// Per setting and scene: steps and ns per pixel (ct_geolocate_batch over
// every 16th pixel of the 1024 x 768 image, best of 3 rounds), package
// bytes and build time, and the horizontal error against the scene's
// ground truth over its samples (RMS, p99, max; wrong surface = a miss or
// an error beyond a posting).  Writes OUT/tradeoff.csv (default
// build/tradeoff); scripts/plot_tradeoff.py draws the plots.
//
//   ct_tradeoff [--out DIR] [--samples N] [--quick]
//   ct_tradeoff --smoke --out DIR   the smallest sweep (nadir; N in {8,
//                                   24}; two methods), then re-reads the CSV
//                                   and checks every deterministic column
//                                   against direct ct_geolocate calls (the
//                                   ctest `tradeoff_smoke`); exit 1 on a
//                                   mismatch.
// Host figures only; Cortex-M4 instruction counts are bench_m4's
// (docs/benchmarks.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "scene.hpp"

namespace {

using clk = std::chrono::steady_clock;
double now_s() { return std::chrono::duration<double>(clk::now().time_since_epoch()).count(); }

struct Setting {
    std::string knob, value;
    int sectors = 24, reduce = 3, slices = 0;
    bool brute = false;
    ct_method method = CT_METHOD_DIRECTIONAL;
    std::string effects = "scene";  // scene | none | curvature | refraction | both | earth | earth_fit
    double chord_m = 0;             // 0: default
    double grid_px = 0;             // 0: closed-form lens
};

struct Row {
    Setting s;
    std::string scene;
    size_t pixels = 0, samples = 0;
    double steps = 0, ns = 0, err_rms = NAN, err_p99 = NAN, err_max = NAN;
    long wrong = 0;
    size_t bytes = 0;
    double x_dem = 0, build_s = 0;
    std::string err_ref = "truth";
};

struct Pkg {
    std::vector<uint8_t> bytes;
    ct_package p;
    double build_s = 0;
};

// the package of a setting over a world's terrain (cached per terrain and
// package knobs)
Pkg *package_for(scene::World &w, const Setting &s)
{
    static std::map<std::string, Pkg *> cache;
    char key[160];
    std::snprintf(key, sizeof key, "%p/%d/%d/%d/%d", (void *)&w.t, s.sectors, s.reduce, s.slices, (int)s.brute);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    ct_host::BuildOptions o;
    o.sectors = s.sectors;
    o.reduce = s.reduce;
    o.slices = s.slices;
    o.builder = s.brute ? ct_host::PptBuilder::Brute : ct_host::PptBuilder::Slices;
    ct_host::BuildStats st;
    Pkg *pk = new Pkg;
    pk->bytes = ct_host::build_package(w.t, o, &st);
    pk->build_s = st.seconds;
    if (ct_package_open(&pk->p, pk->bytes.data(), pk->bytes.size()) != CT_OK)
        throw ct_host::Error("tradeoff: a package does not open");
    cache[key] = pk;
    return pk;
}

ct_effects effects_for(const scene::World &w, const Setting &s)
{
    using namespace scene;
    unsigned fx = w.s.effects & (FX_CURVATURE | FX_REFRACTION);
    if (s.effects == "none") fx = 0;
    if (s.effects == "curvature") fx = FX_CURVATURE;
    if (s.effects == "refraction") fx = FX_REFRACTION;
    if (s.effects == "both") fx = FX_CURVATURE | FX_REFRACTION;
    ct_effects e = lib_effects(w.s, fx);
    if (s.effects == "earth" || s.effects == "earth_fit") {
        e = lib_effects(w.s, FX_CURVATURE | FX_REFRACTION);
        e.earth_radius_nm = 0;
        if (s.effects == "earth_fit") e.flags |= CT_EFFECT_EARTH_FIT;
    }
    if (s.chord_m > 0) e.chord_nm = std::llround(s.chord_m * 1e9);
    return e;
}

struct Cam {
    ct_camera cam;
    ct_pose pose;
    ct_host::BakedGrid baked;
};

Cam camera_for(const scene::World &w, const Setting &s)
{
    Cam c{w.cam.cam, w.cam.pose, {}};
    if (s.grid_px > 0) {
        c.baked = ct_host::bake_grid(w.file_model, s.grid_px);
        if (ct_camera_init_grid(&c.cam, &c.baked.grid) != CT_OK) throw ct_host::Error("tradeoff: grid camera");
    }
    return c;
}

std::vector<int64_t> pixel_grid(const scene::World &w) { return dem_cases::pixel_grid(w.s.width, w.s.height, 16); }

// Errors of geolocated samples against their truth (or against ref hits).
void error_stats(const std::vector<scene::Sample> &smp, const std::vector<ct_geo> &g,
                 const std::vector<ct_geo> *ref, double posting, Row *r)
{
    std::vector<double> e;
    long wrong = 0;
    for (size_t k = 0; k < smp.size(); ++k) {
        const bool hit = g[k].status == CT_HIT || g[k].status == CT_HIT_VOID;
        double te = 0, tn = 0;
        if (ref) {
            if ((*ref)[k].status != g[k].status) {
                wrong++;
                continue;
            }
            if (!hit) continue;
            te = (*ref)[k].hit.e_nm * 1e-9;
            tn = (*ref)[k].hit.n_nm * 1e-9;
        } else {
            if (!hit) {
                wrong++;
                continue;
            }
            te = (double)smp[k].first[0];
            tn = (double)smp[k].first[1];
        }
        const double d = std::hypot(g[k].hit.e_nm * 1e-9 - te, g[k].hit.n_nm * 1e-9 - tn);
        if (!ref && d > posting) wrong++;
        e.push_back(d);
    }
    r->wrong = wrong;
    r->samples = smp.size();
    if (e.empty()) return;
    double s2 = 0;
    for (double x : e) s2 += x * x;
    std::sort(e.begin(), e.end());
    r->err_rms = std::sqrt(s2 / (double)e.size());
    r->err_p99 = e[std::min(e.size() - 1, (size_t)std::ceil(0.99 * (double)e.size()) - 1)];
    r->err_max = e.back();
}

std::vector<ct_geo> locate(const ct_package &p, const Cam &c, ct_method m, const ct_effects &fx,
                           const std::vector<int64_t> &uv)
{
    const size_t n = uv.size() / 2;
    std::vector<ct_geo> g(n);
    if (ct_geolocate_batch(&p, &c.cam, &c.pose, m, &fx, uv.data(), n, g.data(), n) != CT_OK)
        throw ct_host::Error("tradeoff: ct_geolocate_batch failed");
    return g;
}

std::vector<int64_t> sample_uv(const std::vector<scene::Sample> &smp)
{
    std::vector<int64_t> uv;
    for (const scene::Sample &s : smp) {
        uv.push_back(s.uq);
        uv.push_back(s.vq);
    }
    return uv;
}

Row measure(scene::World &w, const std::vector<scene::Sample> &smp, const Setting &s, int rounds)
{
    Row r;
    r.s = s;
    r.scene = w.s.name;
    Pkg *pk = package_for(w, s);
    r.bytes = pk->bytes.size();
    r.x_dem = (double)pk->bytes.size() / (2.0 * w.t.width * w.t.height);
    r.build_s = pk->build_s;
    const Cam c = camera_for(w, s);
    const ct_effects fx = effects_for(w, s);
    const std::vector<int64_t> uv = pixel_grid(w);
    r.pixels = uv.size() / 2;
    double best = 1e300;
    std::vector<ct_geo> g;
    for (int k = 0; k < rounds; ++k) {
        const double t0 = now_s();
        g = locate(pk->p, c, s.method, fx, uv);
        best = std::min(best, (now_s() - t0) / (double)r.pixels);
    }
    r.ns = best * 1e9;
    for (const ct_geo &x : g) r.steps += x.hit.steps;
    r.steps /= (double)r.pixels;
    const std::vector<int64_t> su = sample_uv(smp);
    const std::vector<ct_geo> gs = locate(pk->p, c, s.method, fx, su);
    const double posting = std::fabs(w.t.geo.posting_e);
    if (s.knob == "chord") {
        Setting fine = s;
        fine.chord_m = 5e-4;
        const std::vector<ct_geo> gr = locate(pk->p, c, s.method, effects_for(w, fine), su);
        error_stats(smp, gs, &gr, posting, &r);
        r.err_ref = "finest chord";
    } else if (s.effects == "earth" || s.effects == "earth_fit") {
        r.samples = smp.size();
        r.err_ref = "not comparable";
    } else {
        error_stats(smp, gs, nullptr, posting, &r);
    }
    return r;
}

std::string csv_header()
{
    return "knob,value,scene,sectors,reduce,slices,builder,method,effects,chord_m,grid_px,pixels,steps_per_px,"
           "ns_per_px,package_bytes,package_x_dem,build_s,samples,err_rms_m,err_p99_m,err_max_m,wrong_surface,err_ref\n";
}

std::string csv_row(const Row &r)
{
    static const char *mn[4] = {"incremental", "hierarchical", "cone", "directional"};
    char b[640];
    std::snprintf(b, sizeof b, "%s,%s,%s,%d,%d,%d,%s,%s,%s,%.6g,%g,%zu,%.4f,%.1f,%zu,%.4f,%.3f,%zu,%.6g,%.6g,%.6g,%ld,%s\n",
                  r.s.knob.c_str(), r.s.value.c_str(), r.scene.c_str(), r.s.sectors, r.s.reduce, r.s.slices,
                  r.s.brute ? "brute" : "slices", mn[r.s.method], r.s.effects.c_str(),
                  r.s.chord_m > 0 ? r.s.chord_m : 1e-3, r.s.grid_px, r.pixels, r.steps, r.ns, r.bytes, r.x_dem,
                  r.build_s, r.samples, r.err_rms, r.err_p99, r.err_max, r.wrong, r.err_ref.c_str());
    return b;
}

std::vector<std::string> split(const std::string &s)
{
    std::vector<std::string> f;
    std::stringstream ss(s);
    std::string t;
    while (std::getline(ss, t, ',')) f.push_back(t);
    return f;
}

}  // namespace

int main(int argc, char **argv)
{
    std::string out = "build/tradeoff";
    int samples = 300, rounds = 3;
    bool quick = false, smoke = false;
    for (int k = 1; k < argc; ++k) {
        if (!std::strcmp(argv[k], "--out") && k + 1 < argc) out = argv[++k];
        else if (!std::strcmp(argv[k], "--samples") && k + 1 < argc) samples = std::atoi(argv[++k]);
        else if (!std::strcmp(argv[k], "--quick")) quick = true;
        else if (!std::strcmp(argv[k], "--smoke")) smoke = true;
        else {
            std::fprintf(stderr, "usage: ct_tradeoff [--out DIR] [--samples N] [--quick] [--smoke]\n");
            return 2;
        }
    }
    if (quick) samples = 100, rounds = 2;
    if (smoke) samples = 40, rounds = 1;
    std::filesystem::create_directories(out);
    const std::vector<std::string> names =
        smoke ? std::vector<std::string>{"nadir"}
              : std::vector<std::string>{"nadir", "oblique30", "grazing3", "long30km", "wide_opencv8"};
    std::vector<scene::World *> worlds;
    std::vector<std::vector<scene::Sample>> smps;
    for (const std::string &n : names) {
        scene::World *w = scene::load_world(std::string(CT_SCENES_DIR) + "/" + n + ".scene");
        scene::SimOptions o;
        o.effects = w->s.effects;
        o.n = samples;
        o.seed = 777 + n.size();
        scene::SimStats ss;
        smps.push_back(scene::simulate(*w, o, &ss));
        worlds.push_back(w);
    }
    std::vector<Setting> sweep;
    auto add = [&](Setting s) { sweep.push_back(s); };
    const std::vector<int> Ns = smoke ? std::vector<int>{8, 24} : std::vector<int>{1, 4, 8, 16, 24, 32, 64};
    const std::vector<int> rs = smoke ? std::vector<int>{3} : std::vector<int>{1, 2, 3, 4};
    for (int r : rs)
        for (int n : Ns) {
            Setting s;
            s.knob = "package";
            s.value = "N" + std::to_string(n) + " r" + std::to_string(r);
            s.sectors = n;
            s.reduce = r;
            add(s);
        }
    if (!smoke) {
        for (int k : {16, 32, 128}) {
            Setting s;
            s.knob = "slices";
            s.value = "K" + std::to_string(k);
            s.slices = k;
            add(s);
        }
        Setting b;
        b.knob = "builder";
        b.value = "brute";
        b.brute = true;
        add(b);
    }
    for (int m = 0; m < CT_METHOD_COUNT; ++m) {
        if (smoke && m != 0 && m != 3) continue;
        static const char *mn[4] = {"incremental", "hierarchical", "cone", "directional"};
        Setting s;
        s.knob = "method";
        s.value = mn[m];
        s.method = (ct_method)m;
        add(s);
    }
    if (!smoke) {
        for (const char *e : {"none", "curvature", "refraction", "both", "earth", "earth_fit"}) {
            Setting s;
            s.knob = "effects";
            s.value = e;
            s.effects = e;
            add(s);
        }
        for (double c : {5e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0}) {
            Setting s;
            s.knob = "chord";
            char v[32];
            std::snprintf(v, sizeof v, "%g m", c);
            s.value = v;
            s.effects = "earth_fit";
            s.chord_m = c;
            add(s);
        }
        for (double g : {4.0, 8.0, 16.0, 32.0, 64.0}) {
            Setting s;
            s.knob = "grid";
            s.value = std::to_string((int)g) + " px";
            s.grid_px = g;
            add(s);
        }
    }
    std::string csv = csv_header();
    std::vector<Row> rows;
    const double t0 = now_s();
    size_t done = 0;
    for (const Setting &s : sweep) {
        for (size_t k = 0; k < worlds.size(); ++k) {
            scene::World &w = *worlds[k];
            // package knobs on the plain DEM only (long30km's 3 x 3 tiling
            // would make the r = 1 builds minutes long)
            if ((s.knob == "package" || s.knob == "slices" || s.knob == "builder") && (w.s.tile_x != 1 || w.s.tile_y != 1))
                continue;
            Setting s2 = s;
            if (s.knob != "package" && s.knob != "slices" && s.knob != "builder") {
                s2.sectors = w.s.sectors;  // the scene's own package
                s2.reduce = w.s.reduce;
            }
            const Row r = measure(w, smps[k], s2, rounds);
            rows.push_back(r);
            csv += csv_row(r);
        }
        ++done;
        std::fprintf(stderr, "\rtradeoff: %zu / %zu settings (%.0f s)", done, sweep.size(), now_s() - t0);
    }
    std::fprintf(stderr, "\n");
    const std::string path = out + "/tradeoff.csv";
    {
        std::ofstream f(path);
        f << csv;
        if (!f) {
            std::fprintf(stderr, "tradeoff: cannot write %s\n", path.c_str());
            return 1;
        }
    }
    std::printf("tradeoff: %zu rows in %s (%.0f s)\n", rows.size(), path.c_str(), now_s() - t0);
    if (!smoke) return 0;
    // --smoke: the CSV's deterministic columns against direct calls, one
    // pixel and one sample at a time
    std::ifstream f(path);
    std::string line;
    std::getline(f, line);
    size_t checked = 0;
    for (size_t k = 0; std::getline(f, line); ++k) {
        const std::vector<std::string> c = split(line);
        const Row &r = rows.at(k);
        scene::World &w = *worlds[0];
        Pkg *pk = package_for(w, r.s);
        const Cam cam = camera_for(w, r.s);
        const ct_effects fx = effects_for(w, r.s);
        const std::vector<int64_t> uv = pixel_grid(w);
        double steps = 0;
        for (size_t i = 0; i < uv.size() / 2; ++i) {
            ct_geo g;
            ct_geolocate(&pk->p, &cam.cam, &cam.pose, r.s.method, &fx, uv[2 * i], uv[2 * i + 1], &g);
            steps += g.hit.steps;
        }
        std::vector<ct_geo> gs;
        for (const scene::Sample &s : smps[0]) {
            ct_geo g;
            ct_geolocate(&pk->p, &cam.cam, &cam.pose, r.s.method, &fx, s.uq, s.vq, &g);
            gs.push_back(g);
        }
        Row d;
        error_stats(smps[0], gs, nullptr, std::fabs(w.t.geo.posting_e), &d);
        char want[160];
        std::snprintf(want, sizeof want, "%.4f|%zu|%.6g|%.6g|%.6g|%ld", steps / (double)(uv.size() / 2),
                      pk->bytes.size(), d.err_rms, d.err_p99, d.err_max, d.wrong);
        const std::string got = c.at(12) + "|" + c.at(14) + "|" + c.at(18) + "|" + c.at(19) + "|" + c.at(20) + "|" + c.at(21);
        if (got != want) {
            std::fprintf(stderr, "tradeoff --smoke: row %zu (%s %s): CSV %s, direct calls %s\n", k + 1,
                         r.s.knob.c_str(), r.s.value.c_str(), got.c_str(), want);
            return 1;
        }
        ++checked;
    }
    if (checked != rows.size() || checked < 3) {
        std::fprintf(stderr, "tradeoff --smoke: %zu of %zu rows read back\n", checked, rows.size());
        return 1;
    }
    std::printf("tradeoff --smoke: %zu rows equal to direct ct_geolocate calls (steps, package bytes, errors)\n",
                checked);
    return 0;
}
