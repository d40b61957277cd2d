// bench_ddt.cpp -- directional distance transforms (host_tools/ddt.hpp) on
// cross-sections of the real DEM (fixtures/jacksboro_fault_dem.tif): bitmaps
// with 1 where height >= a slice level, at the native 403 x 344 and at
// 2048 x 2048 (mirror-tiled).  For N = 24 sectors (squared Euclidean) it
// reports the time of a full directional DT (all sectors), ns per pixel per
// sector, candidate comparisons per pixel per sector with and without the
// pruning rules, and the unconstrained DT time.  It writes the bitmaps (PGM)
// and our unconstrained Euclidean DT (raw float32) to the output directory
// and runs scripts/bench_ddt_opencv.py on them (OpenCV's exact
// distanceTransform, DIST_L2 + DIST_MASK_PRECISE) for the per-pixel ratio.
// Nothing here is a pass/fail test.
//
// Options: --quick (native size only, 2 levels), --no-2048, --no-opencv,
//          --threads N (default 2), --out DIR (default ./ddt_bench_out),
//          --dem PATH, --python PATH (default /usr/bin/python3).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <sys/stat.h>
#include <vector>

#include "ddt.hpp"
#include "dem_io.hpp"

using namespace ct_host::ddt;
using clk = std::chrono::steady_clock;

namespace {

double secs_since(clk::time_point t0) { return std::chrono::duration<double>(clk::now() - t0).count(); }

struct Slice {
    std::string name;
    int w, h;
    double level, density;
    std::vector<uint8_t> bits;
};

void write_pgm(const std::string &path, const Slice &s)
{
    FILE *f = fopen(path.c_str(), "wb");
    if (!f) {
        fprintf(stderr, "cannot write %s\n", path.c_str());
        exit(1);
    }
    fprintf(f, "P5\n%d %d\n255\n", s.w, s.h);
    std::vector<uint8_t> row((size_t)s.w);
    for (int y = 0; y < s.h; ++y) {
        for (int x = 0; x < s.w; ++x)
            row[(size_t)x] = s.bits[(size_t)y * s.w + x] ? 255 : 0;
        fwrite(row.data(), 1, row.size(), f);
    }
    fclose(f);
}

void write_f32(const std::string &path, const std::vector<int64_t> &dt2)
{
    FILE *f = fopen(path.c_str(), "wb");
    if (!f)
        return;
    std::vector<float> v(dt2.size());
    for (size_t i = 0; i < dt2.size(); ++i)
        v[i] = dt2[i] == Inf<int64_t>::value ? INFINITY : (float)std::sqrt((double)dt2[i]);
    fwrite(v.data(), sizeof(float), v.size(), f);
    fclose(f);
}

struct Row {
    std::string name;
    int w, h;
    double density;
    double full_ms_1t, full_ms, ns_pix_sector_1t, ns_pix_sector, prep_ms;
    double ops_rules, ops_none, ops_r1, ops_r2, walk_per_pix, cand_per_pix;
    double unc_ms_1t, unc_ms, unc_ns_pix_1t;
    double cv_ns_1t = -1, cv_ns_nt = -1, cv_diff = -1;
};

// Full N-sector directional DT; returns seconds (best of reps).
double time_full(const Prepared &bm, int n, const Options &o, Stats *st, int reps)
{
    std::vector<int64_t> dt;
    std::vector<Point> ft;
    double best = 1e30;
    for (int r = 0; r < reps; ++r) {  // timed without counting
        const auto t0 = clk::now();
        for (int k = 0; k < n; ++k)
            directional(bm, (uint32_t)n, (uint32_t)k, EuclideanSq(), dt, ft, o, nullptr);
        best = std::min(best, secs_since(t0));
    }
    if (st) {  // counts from one more run
        Stats s;
        for (int k = 0; k < n; ++k)
            directional(bm, (uint32_t)n, (uint32_t)k, EuclideanSq(), dt, ft, o, &s);
        *st = s;
    }
    return best;
}

}  // namespace

int main(int argc, char **argv)
{
    bool quick = false, no2048 = false, noocv = false;
    int threads = 2;
    std::string out = "ddt_bench_out", dem = std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif";
    std::string python = "/usr/bin/python3";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--quick")
            quick = true;
        else if (a == "--no-2048")
            no2048 = true;
        else if (a == "--no-opencv")
            noocv = true;
        else if (a == "--threads" && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (a == "--out" && i + 1 < argc)
            out = argv[++i];
        else if (a == "--dem" && i + 1 < argc)
            dem = argv[++i];
        else if (a == "--python" && i + 1 < argc)
            python = argv[++i];
        else {
            fprintf(stderr, "usage: %s [--quick] [--no-2048] [--no-opencv] [--threads N] [--out DIR] [--dem PATH]\n",
                    argv[0]);
            return 2;
        }
    }
    const int N = 24;
    mkdir(out.c_str(), 0755);
    ct_host::DemRaster r;
    try {
        r = ct_host::read_dem(dem);
    } catch (const std::exception &e) {
        fprintf(stderr, "%s\n", e.what());
        return 1;
    }
    // slice levels: height percentiles
    std::vector<double> hs = r.h;
    std::sort(hs.begin(), hs.end());
    std::vector<int> pct = quick ? std::vector<int>{30, 90} : std::vector<int>{10, 30, 50, 70, 90, 98};
    std::vector<Slice> slices;
    std::vector<int> sizes = {0};
    if (!quick && !no2048)
        sizes.push_back(2048);
    for (int sz : sizes) {
        const int w = sz ? sz : r.width, h = sz ? sz : r.height;
        for (int p : pct) {
            Slice s;
            s.w = w;
            s.h = h;
            s.level = hs[(size_t)((hs.size() - 1) * p / 100)];
            s.bits.resize((size_t)w * h);
            size_t ones = 0;
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    // mirror tiling: ... 0 1 .. W-1 W-1 .. 1 0 0 1 ...
                    int sx = x % (2 * r.width), sy = y % (2 * r.height);
                    if (sx >= r.width)
                        sx = 2 * r.width - 1 - sx;
                    if (sy >= r.height)
                        sy = 2 * r.height - 1 - sy;
                    const uint8_t b = r.h[(size_t)sy * r.width + sx] >= s.level ? 1 : 0;
                    s.bits[(size_t)y * w + x] = b;
                    ones += b;
                }
            s.density = (double)ones / ((double)w * h);
            char nm[96];
            snprintf(nm, sizeof nm, "slice_%dx%d_p%02d", w, h, p);
            s.name = nm;
            slices.push_back(std::move(s));
        }
    }

    printf("ct_bench_ddt: %s, N = %d sectors, squared Euclidean, %d thread(s) (and 1)\n", dem.c_str(), N, threads);
    printf("bitmaps: 1 where height >= level (height percentiles %s); outputs in %s/\n\n",
           quick ? "30, 90" : "10, 30, 50, 70, 90, 98", out.c_str());
    std::vector<Row> rows;
    for (const Slice &s : slices) {
        Row row{};
        row.name = s.name;
        row.w = s.w;
        row.h = s.h;
        row.density = s.density;
        const double npix = (double)s.w * s.h;
        const bool big = npix > 1e6;
        auto t0 = clk::now();
        const Prepared bm(s.w, s.h, s.bits.data());
        row.prep_ms = secs_since(t0) * 1e3;
        Options o1, on;
        o1.threads = 1;
        on.threads = threads;
        Stats st;
        const int reps = big ? 1 : 3;
        row.full_ms_1t = time_full(bm, N, o1, &st, reps) * 1e3;
        row.full_ms = time_full(bm, N, on, nullptr, reps) * 1e3;
        row.ns_pix_sector_1t = row.full_ms_1t * 1e6 / (npix * N);
        row.ns_pix_sector = row.full_ms * 1e6 / (npix * N);
        row.ops_rules = (double)st.comparisons / (npix * N);
        row.walk_per_pix = (double)st.walk_steps / (npix * N);
        row.cand_per_pix = (double)st.candidates / (npix * N);
        row.ops_none = row.ops_r1 = row.ops_r2 = -1;
        if (!big) {  // without rules the scan is quadratic per line
            Options o = on;
            Stats s0, s1, s2;
            o.rule1 = o.rule2 = false;
            time_full(bm, N, o, &s0, 0);
            o.rule1 = true;
            time_full(bm, N, o, &s1, 0);
            o.rule1 = false;
            o.rule2 = true;
            time_full(bm, N, o, &s2, 0);
            row.ops_none = (double)s0.comparisons / (npix * N);
            row.ops_r1 = (double)s1.comparisons / (npix * N);
            row.ops_r2 = (double)s2.comparisons / (npix * N);
        }
        std::vector<int64_t> dt;
        std::vector<Point> ft;
        double b1 = 1e30, bn = 1e30;
        for (int k = 0; k < reps; ++k) {
            t0 = clk::now();
            unconstrained(bm, EuclideanSq(), dt, ft, o1);
            b1 = std::min(b1, secs_since(t0));
            t0 = clk::now();
            unconstrained(bm, EuclideanSq(), dt, ft, on);
            bn = std::min(bn, secs_since(t0));
        }
        row.unc_ms_1t = b1 * 1e3;
        row.unc_ms = bn * 1e3;
        row.unc_ns_pix_1t = b1 * 1e9 / npix;
        write_pgm(out + "/" + s.name + ".pgm", s);
        write_f32(out + "/" + s.name + ".dt.f32", dt);
        rows.push_back(row);
        fprintf(stderr, "  %s done\n", s.name.c_str());
    }

    // OpenCV on the same bitmaps
    std::string cvnote;
    if (!noocv) {
        std::string cmd = python + " " + CT_SCRIPTS_DIR + "/bench_ddt_opencv.py --threads " + std::to_string(threads);
        for (const Slice &s : slices)
            cmd += " " + out + "/" + s.name + ".pgm";
        cmd += " 2>&1";
        FILE *p = popen(cmd.c_str(), "r");
        char line[512];
        std::map<std::string, std::array<double, 3>> cv;
        while (p && fgets(line, sizeof line, p)) {
            char nm[256];
            double a, b, diff;
            if (sscanf(line, "RESULT %255s %lf %lf %lf", nm, &a, &b, &diff) == 4) {
                std::string n = nm;
                const size_t sl = n.find_last_of('/');
                n = n.substr(sl == std::string::npos ? 0 : sl + 1);
                n = n.substr(0, n.size() - 4);
                cv[n] = {a, b, diff};
                if (diff > 1e-3)
                    cvnote += "  WARNING: " + n + ": our unconstrained DT differs from OpenCV's by " +
                              std::to_string(diff) + " px\n";
            } else {
                cvnote += std::string("  opencv: ") + line;
            }
        }
        const int rc = p ? pclose(p) : -1;
        if (rc != 0)
            cvnote += "  (OpenCV comparison unavailable: exit status " + std::to_string(rc) +
                      "; apt-get install -y python3-opencv)\n";
        for (Row &row : rows)
            if (cv.count(row.name)) {
                row.cv_ns_1t = cv[row.name][0];
                row.cv_ns_nt = cv[row.name][1];
                row.cv_diff = cv[row.name][2];
            }
    }

    printf("%-22s %6s | %9s %9s | %7s %7s | %6s %6s %6s %6s | %7s %6s | %9s %9s | %7s %7s\n", "bitmap", "ones",
           "N=24 ms", "(1 thr)", "ns/px/s", "(1 thr)", "ops", "none", "r1", "r2", "walk", "cand", "unc ms",
           "(1 thr)", "cv ns/px", "ratio");
    for (const Row &r0 : rows) {
        char none[16], o1[16], o2[16], cvs[16], ratio[16];
        snprintf(none, sizeof none, r0.ops_none < 0 ? "n/a" : "%.1f", r0.ops_none);
        snprintf(o1, sizeof o1, r0.ops_r1 < 0 ? "n/a" : "%.2f", r0.ops_r1);
        snprintf(o2, sizeof o2, r0.ops_r2 < 0 ? "n/a" : "%.1f", r0.ops_r2);
        snprintf(cvs, sizeof cvs, r0.cv_ns_1t < 0 ? "n/a" : "%.2f", r0.cv_ns_1t);
        snprintf(ratio, sizeof ratio, r0.cv_ns_1t < 0 ? "n/a" : "%.2f", r0.ns_pix_sector_1t / r0.cv_ns_1t);
        printf("%-22s %5.1f%% | %9.1f %9.1f | %7.2f %7.2f | %6.2f %6s %6s %6s | %7.2f %6.2f | %9.2f %9.2f | %8s %7s\n",
               r0.name.c_str(), 100.0 * r0.density, r0.full_ms, r0.full_ms_1t, r0.ns_pix_sector, r0.ns_pix_sector_1t,
               r0.ops_rules, none, o1, o2, r0.walk_per_pix, r0.cand_per_pix, r0.unc_ms, r0.unc_ms_1t, cvs, ratio);
    }
    printf("\ncolumns: ones = feature density; N=24 ms = all 24 directional DTs (%d threads, then 1 thread);\n"
           "ns/px/s = ns per pixel per sector; ops = candidate comparisons per pixel per sector with both rules,\n"
           "none / r1 / r2 = without rules / rule 1 only / rule 2 only (native size only: quadratic without\n"
           "rules); walk = activation-walk steps, cand = candidates created per pixel per sector;\n"
           "unc ms = unconstrained DT (4 quadrants); cv ns/px = OpenCV distanceTransform(DIST_L2,\n"
           "DIST_MASK_PRECISE) per pixel, 1 thread; ratio = ours per sector (1 thread) / OpenCV (1 thread).\n",
           threads);
    for (const Row &r0 : rows)
        if (r0.cv_ns_nt >= 0)
            printf("  %-22s unconstrained ours %.2f ns/px (1 thr) vs OpenCV %.2f (1 thr), %.2f (%d thr): ratio %.2f;"
                   " max |ours - OpenCV| %.2g px\n",
                   r0.name.c_str(), r0.unc_ns_pix_1t, r0.cv_ns_1t, r0.cv_ns_nt, threads, r0.unc_ns_pix_1t / r0.cv_ns_1t,
                   r0.cv_diff);
    if (!cvnote.empty())
        printf("%s", cvnote.c_str());
    return 0;
}
