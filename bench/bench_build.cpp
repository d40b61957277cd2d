// bench_build.cpp -- the full PPT build (issue 3's benchmark): wall time,
// peak working memory and package size, per builder and reduction r.
//
// DEMs: the fixture (fixtures/jacksboro_fault_dem.tif, 403 x 344) and a
// 2048 x 2048 DEM made by mirror-tiling it (... 0 1 .. W-1 W-1 .. 1 0 0 1 ..).
// Build: BuildOptions{sectors = 24, slices = 80, threads = 2}, r in {1, 3}.
// Each build runs in a forked child: the child resets its peak-RSS counter
// (/proc/self/clear_refs = 5), reads VmRSS as the baseline (the DEM and the
// program are already resident), builds, and reports the wall time of
// build_package, VmHWM - baseline (peak working memory: everything the
// build allocated and touched, the package included) and the package size
// through a pipe.  Both are compared with the DEM's 16-bit size (W*H*2).
// A build that takes longer than --timeout seconds is killed and reported.
//
// Options: --builder NAME|all (default all), --size S (tiled DEM side,
//   default 2048; 0 = fixture only), --reduce LIST (default 1,3),
//   --big-r1 (also r = 1 on the tiled DEM for builders that skip it by
//   default), --threads T (default 2), --timeout S (default 1800),
//   --quick (fixture only, r = 3).
// Nothing here is a pass/fail test.
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include "conetrace.h"
#include "dem_io.hpp"
#include "terrain.hpp"

using namespace ct_host;

namespace {

// Every PptBuilder that exists: adding a builder is one line here.
// big_r1: run r = 1 on the 2048^2 DEM by default (the brute-force builder
// takes ~10 min there; --big-r1 forces it).
struct BuilderEntry {
    PptBuilder id;
    const char *name;
    bool big_r1;
};
const BuilderEntry kBuilders[] = {
    {PptBuilder::Brute, "brute", false},
};

long proc_status_kb(const char *key)
{
    FILE *f = std::fopen("/proc/self/status", "r");
    if (!f) return -1;
    char line[256];
    long v = -1;
    const size_t n = std::strlen(key);
    while (std::fgets(line, sizeof line, f))
        if (!std::strncmp(line, key, n) && line[n] == ':') v = std::atol(line + n + 1);
    std::fclose(f);
    return v;
}

struct Result {
    int ok = 0;                 // 1 = built, 0 = failed/killed
    double seconds = 0;
    long base_kb = 0, hwm_kb = 0;
    uint64_t pkg_bytes = 0;
    uint64_t ppt_bytes = 0;     // apex + angle sections
    double degenerate = 0;      // fraction of (cell, sector) cones with code 0
    char err[160] = {0};
};

// Runs job() in a forked child with a fresh peak-RSS counter; job fills
// everything but base_kb / hwm_kb.
Result run_child(const std::function<void(Result &)> &job, double timeout_s)
{
    int fd[2];
    Result r;
    if (pipe(fd) != 0) {
        std::snprintf(r.err, sizeof r.err, "pipe failed");
        return r;
    }
    std::fflush(stdout);
    pid_t pid = fork();
    if (pid < 0) {
        std::snprintf(r.err, sizeof r.err, "fork failed");
        return r;
    }
    if (pid == 0) {
        close(fd[0]);
        Result c;
        if (FILE *f = std::fopen("/proc/self/clear_refs", "w")) {  // reset VmHWM to VmRSS
            std::fputs("5", f);
            std::fclose(f);
        }
        c.base_kb = proc_status_kb("VmRSS");
        try {
            job(c);
        } catch (const std::exception &e) {
            c.ok = 0;
            std::snprintf(c.err, sizeof c.err, "%s", e.what());
        }
        c.hwm_kb = proc_status_kb("VmHWM");
        ssize_t w = write(fd[1], &c, sizeof c);
        _exit(w == (ssize_t)sizeof c ? 0 : 1);
    }
    close(fd[1]);
    struct pollfd pf = {fd[0], POLLIN, 0};
    int pr = poll(&pf, 1, (int)std::min(timeout_s * 1000.0, 2e9));
    if (pr == 1 && read(fd[0], &r, sizeof r) == (ssize_t)sizeof r) {
        waitpid(pid, nullptr, 0);
    } else {
        kill(pid, SIGKILL);
        waitpid(pid, nullptr, 0);
        r = Result();
        std::snprintf(r.err, sizeof r.err, pr == 0 ? "killed after the %.0f s timeout" : "child died", timeout_s);
    }
    close(fd[0]);
    return r;
}

Result run_build(const Terrain &t, const BuildOptions &o, double timeout_s)
{
    return run_child(
        [&](Result &c) {
            BuildStats st;
            auto t0 = std::chrono::steady_clock::now();
            std::vector<uint8_t> pkg = build_package(t, o, &st);
            c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            c.pkg_bytes = pkg.size();
            c.degenerate = st.cones ? (double)st.degenerate_cones / (double)st.cones : 0.0;
            ct_package p;
            if (ct_package_open(&p, pkg.data(), pkg.size()) != CT_OK) {
                std::snprintf(c.err, sizeof c.err, "package does not open");
                return;
            }
            uint32_t so[CT_SEC_COUNT], ss[CT_SEC_COUNT], lv, tot;
            ct_package_layout(p.width, p.height, p.reduce, p.sectors, p.voids ? 1u : 0u, so, ss, &lv, &tot);
            c.ppt_bytes = (uint64_t)ss[CT_SEC_APEX] + ss[CT_SEC_ANGLES];
            c.ok = 1;
        },
        timeout_s);
}

// The method itself: a child that allocates and touches 32 MiB should
// report about 32 MiB.
double calibrate_mib()
{
    Result r = run_child(
        [](Result &c) {
            std::vector<uint8_t> v((size_t)32 << 20);
            for (size_t k = 0; k < v.size(); k += 4096) v[k] = (uint8_t)(k >> 12 | 1);
            volatile uint8_t sink = v[v.size() / 2];  // keep v alive and used
            c.ok = sink != 0;
        },
        60);
    return r.ok ? (r.hwm_kb - r.base_kb) / 1024.0 : -1.0;
}

Terrain mirror_tile(const Terrain &t, int n)
{
    Terrain b = t;
    b.width = b.height = n;
    b.codes.assign((size_t)n * n, 0);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            int pi = i % (2 * t.width), pj = j % (2 * t.height);
            if (pi >= t.width) pi = 2 * t.width - 1 - pi;
            if (pj >= t.height) pj = 2 * t.height - 1 - pj;
            b.codes[(size_t)j * n + i] = t.at(pi, pj);
        }
    return b;
}

}  // namespace

int main(int argc, char **argv)
{
    std::string builder = "all", dem = std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif";
    int size = 2048, threads = 2;
    double timeout = 1800;
    bool big_r1 = false;
    std::vector<int> reduces = {1, 3};
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "%s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--builder")
            builder = next();
        else if (a == "--size")
            size = std::atoi(next().c_str());
        else if (a == "--threads")
            threads = std::atoi(next().c_str());
        else if (a == "--timeout")
            timeout = std::atof(next().c_str());
        else if (a == "--big-r1")
            big_r1 = true;
        else if (a == "--quick")
            size = 0, reduces = {3};
        else if (a == "--reduce") {
            reduces.clear();
            std::stringstream ss(next());
            std::string it;
            while (std::getline(ss, it, ',')) reduces.push_back(std::atoi(it.c_str()));
        } else if (a == "--dem")
            dem = next();
        else {
            std::fprintf(stderr,
                         "usage: %s [--builder NAME|all] [--size S] [--reduce LIST] [--big-r1] [--threads T] "
                         "[--timeout S] [--quick] [--dem PATH]\nbuilders:",
                         argv[0]);
            for (const auto &b : kBuilders) std::fprintf(stderr, " %s", b.name);
            std::fprintf(stderr, "\n");
            return 2;
        }
    }
    std::vector<BuilderEntry> chosen;
    for (const auto &b : kBuilders)
        if (builder == "all" || builder == b.name) chosen.push_back(b);
    if (chosen.empty()) {
        std::fprintf(stderr, "unknown builder '%s'\n", builder.c_str());
        return 2;
    }
    for (int r : reduces)
        if (r < 1 || r > 8) {
            std::fprintf(stderr, "--reduce: %d is not in 1..8\n", r);
            return 2;
        }
    if (size != 0 && (size < 16 || size > 32768)) {
        std::fprintf(stderr, "--size must be 0 or in 16..32768\n");
        return 2;
    }

    Terrain fx;
    try {
        DemRaster r = read_dem(dem);
        fx = terrain_from_heights(r.width, r.height, r.h, r.valid, r.geo, 0.0);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
    struct Dem {
        std::string name;
        Terrain t;
        bool big;
    };
    std::vector<Dem> dems;
    dems.push_back({"fixture", fx, false});
    if (size > 0) dems.push_back({"tiled", mirror_tile(fx, size), true});

    std::printf("full PPT build: N = 24 sectors, K = 80 slices, %d thread%s; peak working memory = VmHWM - VmRSS "
                "before the build (forked child); DEM = 16-bit posts\n\n",
                threads, threads == 1 ? "" : "s");
    std::printf("calibration: a child touching 32 MiB measures %.1f MiB\n\n", calibrate_mib());
    std::printf("%-8s %-9s %11s %2s | %9s | %9s %6s %9s | %10s %7s %8s | %s\n", "builder", "DEM", "size", "r", "time s",
                "peak MiB", "xDEM", "-pkg xDEM", "pkg MiB", "xDEM", "PPT xDEM", "degenerate");
    for (const BuilderEntry &b : chosen)
        for (const Dem &d : dems)
            for (int r : reduces) {
                char sz[32];
                std::snprintf(sz, sizeof sz, "%dx%d", d.t.width, d.t.height);
                if (d.big && r == 1 && !b.big_r1 && !big_r1) {
                    std::printf("%-8s %-9s %11s %2d | skipped (slow for this builder; --big-r1 runs it)\n", b.name,
                                d.name.c_str(), sz, r);
                    continue;
                }
                BuildOptions o;
                o.sectors = 24;
                o.slices = 80;
                o.reduce = r;
                o.threads = threads;
                o.builder = b.id;
                Result res = run_build(d.t, o, timeout);
                const double dem_b = 2.0 * d.t.width * d.t.height;
                if (!res.ok) {
                    std::printf("%-8s %-9s %11s %2d | failed: %s\n", b.name, d.name.c_str(), sz, r, res.err);
                    continue;
                }
                const double peak = (double)(res.hwm_kb - res.base_kb) * 1024.0;
                std::printf("%-8s %-9s %11s %2d | %9.2f | %9.1f %6.2f %9.2f | %10.2f %7.2f %8.2f | %.2f%%\n", b.name,
                            d.name.c_str(), sz, r, res.seconds, peak / 1048576.0, peak / dem_b,
                            (peak - (double)res.pkg_bytes) / dem_b,
                            res.pkg_bytes / 1048576.0, res.pkg_bytes / dem_b, res.ppt_bytes / dem_b,
                            100.0 * res.degenerate);
                std::fflush(stdout);
            }
    std::printf("\npeak: VmHWM - VmRSS before the build, the package included; -pkg: the same without the package;\n"
                "package xDEM: the whole package (heights 1x + mipmap + apexes + N+1 angle planes) over the "
                "DEM;\nPPT xDEM: the apex and angle sections alone (the paper's ~1.4x for N = 24, r = 3).\n"
                "Targets (issue 3): 2048^2 build < 10 s, peak working memory < 3x the DEM.\n");
    return 0;
}
