// bench_ddt.cpp -- directional distance transforms (host_tools/ddt/ddt.hpp) on
// cross-sections of the real DEM (fixtures/jacksboro_fault_dem.tif): bitmaps
// with 1 where height >= a slice level, at the native 403 x 344 and at
// 2048 x 2048 (mirror-tiled).  For N = 24 sectors (squared Euclidean) it
// reports the time of a full directional DT (all sectors; distances only, as
// OpenCV computes, and with the feature transform), ns per pixel per sector,
// candidate comparisons per pixel per sector with and without the pruning
// rules, and the unconstrained DT time.  OpenCV's exact distanceTransform
// (DIST_L2 + DIST_MASK_PRECISE) runs in a coprocess
// (scripts/bench_ddt_opencv.py --serve) and is timed in rounds alternating
// with ours on the same bitmap: each side's best over the rounds gives the
// ratio (this shared machine's speed drifts by tens of percent over seconds,
// so times from separate runs are not comparable).  The bitmaps (PGM) and our
// unconstrained Euclidean DT (raw float32) go to the output directory for
// OpenCV's cross-check.  Nothing here is a pass/fail test.
//
// Options: --quick (native size only, 2 levels), --no-2048, --no-opencv,
//          --threads N (default 2), --out DIR (default ./ddt_bench_out),
//          --dem PATH, --python PATH (default /usr/bin/python3).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <csignal>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
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
    double full_ms_1t, full_ft_ms_1t, full_ms, ns_pix_sector_1t, ns_pix_sector_ft_1t, ns_pix_sector, prep_ms;
    double ops_rules, ops_none, ops_r1, ops_r2, ops_r12, walk_per_pix, cand_per_pix;
    double unc_ms_1t, unc_ms, unc_ns_pix_1t;
    double cv_ns_1t = -1, cv_ns_nt = -1, cv_diff = -1;
};

// OpenCV in a coprocess (scripts/bench_ddt_opencv.py --serve): one command
// line out, one answer line back.
class CvServer {
public:
    ~CvServer() { stop(); }
    // false (and why) when it does not start, e.g. without python3-opencv
    bool start(const std::string &python, const std::string &script, std::string &why)
    {
        int to[2], from[2];
        if (pipe(to) != 0 || pipe(from) != 0) {
            why = "pipe failed";
            return false;
        }
        pid_ = fork();
        if (pid_ < 0) {
            why = "fork failed";
            return false;
        }
        if (pid_ == 0) {
            dup2(to[0], 0);
            dup2(from[1], 1);
            close(to[0]);
            close(to[1]);
            close(from[0]);
            close(from[1]);
            execl(python.c_str(), python.c_str(), script.c_str(), "--serve", (char *)nullptr);
            _exit(127);
        }
        close(to[0]);
        close(from[1]);
        to_ = fdopen(to[1], "w");
        from_ = fdopen(from[0], "r");
        std::string hello;
        if (!to_ || !from_ || !read_line(hello) || hello.compare(0, 7, "opencv ") != 0) {
            const int rc = stop();
            why = "exit status " + std::to_string(rc) + "; apt-get install -y python3-opencv";
            return false;
        }
        version = hello.substr(7);
        return true;
    }
    // The answer to one command ("" when the coprocess is gone).
    std::string ask(const std::string &cmd)
    {
        std::string reply;
        if (!to_ || fprintf(to_, "%s\n", cmd.c_str()) < 0 || fflush(to_) != 0 || !read_line(reply))
            return "";
        return reply;
    }
    std::string version;

private:
    bool read_line(std::string &out)
    {
        char buf[512];
        if (!fgets(buf, sizeof buf, from_))
            return false;
        out = buf;
        while (!out.empty() && (out.back() == '\n' || out.back() == '\r'))
            out.pop_back();
        return true;
    }
    int stop()
    {
        if (to_) {
            fputs("\n", to_);
            fclose(to_);
            to_ = nullptr;
        }
        if (from_) {
            fclose(from_);
            from_ = nullptr;
        }
        int status = 0;
        if (pid_ > 0 && waitpid(pid_, &status, 0) == pid_) {
            pid_ = -1;
            return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        }
        return -1;
    }
    pid_t pid_ = -1;
    FILE *to_ = nullptr, *from_ = nullptr;
};

double cv_time(CvServer *cv, const std::string &pgm, int reps, int threads)
{
    if (!cv)
        return -1;
    const std::string r = cv->ask("T " + pgm + " " + std::to_string(reps) + " " + std::to_string(threads));
    double ns = -1;
    return sscanf(r.c_str(), "T %lf", &ns) == 1 ? ns : -1;
}

// Full N-sector directional DT; returns seconds (best of reps).
double time_full(const Prepared &bm, int n, const Options &o, Stats *st, int reps)
{
    // outputs kept across calls, as a caller transforming slice after slice
    // would (fresh pages would add page faults to the first sector's time)
    static std::vector<int64_t> dt;
    static std::vector<Point> ft;
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

    signal(SIGPIPE, SIG_IGN);  // a dead coprocess is an answer of "", not a signal
    CvServer server;
    CvServer *cv = nullptr;
    std::string cvnote;
    if (!noocv) {
        std::string why;
        if (server.start(python, std::string(CT_SCRIPTS_DIR) + "/bench_ddt_opencv.py", why))
            cv = &server;
        else
            cvnote = "  (OpenCV comparison unavailable: " + why + ")\n";
    }
    printf("ct_bench_ddt: %s, N = %d sectors, squared Euclidean, %d thread(s) (and 1)%s%s\n", dem.c_str(), N,
           threads, cv ? "; OpenCV " : "", cv ? cv->version.c_str() : "");
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
        const std::string pgm = out + "/" + s.name + ".pgm";
        write_pgm(pgm, s);
        auto t0 = clk::now();
        const Prepared bm(s.w, s.h, s.bits.data());
        row.prep_ms = secs_since(t0) * 1e3;
        Options o1, on;
        o1.threads = 1;
        o1.feature_transform = false;  // distances only, as OpenCV
        on.threads = threads;
        on.feature_transform = false;
        // alternating rounds: ours (one full run, then one with the feature
        // transform), then OpenCV (cvreps runs); each side's best
        Options oft = o1;
        oft.feature_transform = true;
        const int rounds = big ? 3 : 9, cvreps = big ? 3 : 10, reps = big ? 1 : 3;
        double ours = 1e30, ours_ft = 1e30, cv1 = 1e30;
        for (int k = 0; k < rounds; ++k) {
            ours = std::min(ours, time_full(bm, N, o1, nullptr, 1));
            ours_ft = std::min(ours_ft, time_full(bm, N, oft, nullptr, 1));
            const double c = cv_time(cv, pgm, cvreps, 1);
            cv1 = c < 0 ? -1 : std::min(cv1, c);
        }
        row.cv_ns_1t = cv1;
        row.cv_ns_nt = cv_time(cv, pgm, cvreps, threads);
        Stats st;
        time_full(bm, N, oft, &st, 0);
        row.full_ms_1t = ours * 1e3;
        row.full_ft_ms_1t = ours_ft * 1e3;
        row.full_ms = time_full(bm, N, on, nullptr, reps) * 1e3;
        row.ns_pix_sector_1t = row.full_ms_1t * 1e6 / (npix * N);
        row.ns_pix_sector_ft_1t = row.full_ft_ms_1t * 1e6 / (npix * N);
        row.ns_pix_sector = row.full_ms * 1e6 / (npix * N);
        row.ops_rules = (double)st.comparisons / (npix * N);
        row.walk_per_pix = (double)st.walk_steps / (npix * N);
        row.cand_per_pix = (double)st.candidates / (npix * N);
        row.ops_none = row.ops_r1 = row.ops_r2 = -1;
        {  // both rules without the Euclidean pruning (linear: every size)
            Options o = on;
            Stats s12;
            o.euclid = false;
            time_full(bm, N, o, &s12, 0);
            row.ops_r12 = (double)s12.comparisons / (npix * N);
        }
        if (!big) {  // without rules the scan is quadratic per line
            Options o = on;
            Stats s0, s1, s2;
            o.rule1 = o.rule2 = false;
            o.euclid = false;
            time_full(bm, N, o, &s0, 0);
            o.rule1 = true;
            time_full(bm, N, o, &s1, 0);
            o.rule1 = false;
            o.rule2 = true;
            o.euclid = false;
            time_full(bm, N, o, &s2, 0);
            row.ops_none = (double)s0.comparisons / (npix * N);
            row.ops_r1 = (double)s1.comparisons / (npix * N);
            row.ops_r2 = (double)s2.comparisons / (npix * N);
        }
        std::vector<int64_t> dt;
        std::vector<Point> ft;
        Options u1 = o1, un = on;
        u1.feature_transform = un.feature_transform = true;  // as before: DT and FT
        double b1 = 1e30, bn = 1e30;
        for (int k = 0; k < reps; ++k) {
            t0 = clk::now();
            unconstrained(bm, EuclideanSq(), dt, ft, u1);
            b1 = std::min(b1, secs_since(t0));
            t0 = clk::now();
            unconstrained(bm, EuclideanSq(), dt, ft, un);
            bn = std::min(bn, secs_since(t0));
        }
        row.unc_ms_1t = b1 * 1e3;
        row.unc_ms = bn * 1e3;
        row.unc_ns_pix_1t = b1 * 1e9 / npix;
        write_f32(out + "/" + s.name + ".dt.f32", dt);
        if (cv) {
            double diff = -1;
            if (sscanf(cv->ask("D " + pgm).c_str(), "D %lf", &diff) == 1) {
                row.cv_diff = diff;
                if (diff > 1e-3)
                    cvnote += "  WARNING: " + s.name + ": our unconstrained DT differs from OpenCV's by " +
                              std::to_string(diff) + " px\n";
            }
        }
        rows.push_back(row);
        fprintf(stderr, "  %s done\n", s.name.c_str());
    }

    printf("%-22s %6s | %9s %9s | %7s %7s %7s | %6s %6s %6s %6s %6s | %7s %6s | %9s %9s | %8s %6s %6s\n", "bitmap",
           "ones", "N=24 ms", "(1 thr)", "ns/px/s", "(1 thr)", "+FT", "ops", "r1+r2", "none", "r1", "r2", "walk", "cand",
           "unc ms",
           "(1 thr)", "cv ns/px", "ratio", "+FT");
    for (const Row &r0 : rows) {
        char none[16], o1[16], o2[16], cvs[16], ratio[16], ratio_ft[16];
        snprintf(none, sizeof none, r0.ops_none < 0 ? "n/a" : "%.1f", r0.ops_none);
        snprintf(o1, sizeof o1, r0.ops_r1 < 0 ? "n/a" : "%.2f", r0.ops_r1);
        snprintf(o2, sizeof o2, r0.ops_r2 < 0 ? "n/a" : "%.1f", r0.ops_r2);
        snprintf(cvs, sizeof cvs, r0.cv_ns_1t < 0 ? "n/a" : "%.2f", r0.cv_ns_1t);
        snprintf(ratio, sizeof ratio, r0.cv_ns_1t < 0 ? "n/a" : "%.2f", r0.ns_pix_sector_1t / r0.cv_ns_1t);
        snprintf(ratio_ft, sizeof ratio_ft, r0.cv_ns_1t < 0 ? "n/a" : "%.2f", r0.ns_pix_sector_ft_1t / r0.cv_ns_1t);
        printf("%-22s %5.1f%% | %9.1f %9.1f | %7.2f %7.2f %7.2f | %6.2f %6.2f %6s %6s %6s | %7.2f %6.2f | %9.2f %9.2f | %8s "
               "%6s %6s\n",
               r0.name.c_str(), 100.0 * r0.density, r0.full_ms, r0.full_ms_1t, r0.ns_pix_sector, r0.ns_pix_sector_1t,
               r0.ns_pix_sector_ft_1t, r0.ops_rules, r0.ops_r12, none, o1, o2, r0.walk_per_pix, r0.cand_per_pix, r0.unc_ms,
               r0.unc_ms_1t, cvs, ratio, ratio_ft);
    }
    printf("\ncolumns: ones = feature density; N=24 ms = all 24 directional DTs, distances only (%d threads, then\n"
           "1 thread); ns/px/s = ns per pixel per sector (distances only; +FT: with the feature transform,\n"
           "1 thread); ops = candidate comparisons per pixel per sector with both rules and the Euclidean\n"
           "pruning; r1+r2 = both rules without the pruning; none / r1 / r2 = without rules / rule 1 only /\n"
           "rule 2 only, no pruning (native size only: quadratic without rules); walk =\n"
           "activation-walk steps, cand = candidates created per pixel per sector; unc ms = unconstrained DT\n"
           "and FT (4 quadrants); cv ns/px = OpenCV distanceTransform(DIST_L2, DIST_MASK_PRECISE) per pixel,\n"
           "1 thread; ratio = ours per sector (1 thread) / OpenCV (1 thread), each the best of rounds that\n"
           "alternate between the two (+FT: ours with the feature transform, in the same rounds).\n",
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
