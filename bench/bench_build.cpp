// bench_build.cpp -- the PPT builders: wall time, peak working memory and
// package size (`make bench`).
//
// DEMs: the fixture (403 x 344) and its 2048 x 2048 mirror tiling.  Each
// build (N = 24 sectors, K = 80 slices, both cores) runs in a forked child
// that reads its resident size before the build, resets the peak
// (/proc/self/clear_refs) and reads the peak after it: working memory =
// peak - before, while the package is built and streamed to a file in /tmp
// (the CLI's way); compared with the 16-bit DEM's size, also with the DEM
// itself added (the process's whole data: DEM + working memory).  The brute-force builder at 2048^2 takes minutes and runs only
// with --brute-2048.  Also the package's sections for N = 24, r = 3 (the
// paper: the PPT is about 1.4x the DEM).
//
// Options: --quick (fixture only), --brute-2048, --slices K (default 80),
// --big-only (2048^2 only), --r R (2048^2 at reduction R only).
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "conetrace.h"
#include "dem_cases.hpp"
#include "host_io.hpp"
#include "terrain.hpp"

namespace {

using ct_host::proc_status_kib;

struct Result {
    double seconds = -1, work_bytes = 0, file_bytes = 0, local_s = 0, dt_s = 0;
    size_t bytes = 0, degenerate = 0, cones = 0, queries = 0, full_dts = 0;
    int slices = 0;
    uint32_t sec[CT_SEC_COUNT] = {0, 0, 0, 0, 0};
};

Result build_in_child(const ct_host::Terrain &t, ct_host::PptBuilder b, int r, int slices)
{
    int fd[2];
    Result res;
    if (pipe(fd) != 0) return res;
    pid_t pid = fork();
    if (pid == 0) {
        close(fd[0]);
        Result out;
        ct_host::BuildOptions o;
        o.sectors = 24;
        o.reduce = r;
        o.slices = slices;
        o.threads = 2;
        o.builder = b;
        if (getenv("CT_FULL_DT_ROWS")) o.full_dt_rows = atof(getenv("CT_FULL_DT_ROWS"));
        // first a small build of the same kind, so that the code pages it
        // runs are resident before the measurement (they are not working
        // memory); RssFile's growth during the measured build is reported
        {
            const ct_host::Terrain tiny = dem_cases::mirror_tiled(t, 64, 64);
            const std::string wpath = "/tmp/ct_bench_build_warm." + std::to_string((long)getpid()) + ".ctp";
            ct_host::BuildOptions wo = o;
            wo.full_dt_rows = 1.0;  // the full-DT path too
            ct_host::build_package_file(tiny, wo, wpath);
            std::remove(wpath.c_str());
        }
        double rss0 = proc_status_kib("VmRSS") * 1024.0, file0 = proc_status_kib("RssFile") * 1024.0;
        ct_host::reset_peak_rss();
        ct_host::BuildStats st;
        auto t0 = std::chrono::steady_clock::now();
        const std::string path = "/tmp/ct_bench_build." + std::to_string((long)getpid()) + ".ctp";
        ct_host::build_package_file(t, o, path, &st);
        out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        out.work_bytes = proc_status_kib("VmHWM") * 1024.0 - rss0;
        out.file_bytes = proc_status_kib("RssFile") * 1024.0 - file0;
        std::remove(path.c_str());
        out.bytes = st.bytes;
        out.degenerate = st.degenerate_cones;
        out.cones = st.cones;
        out.slices = st.slices_transformed;
        out.local_s = st.seconds_local;
        out.dt_s = st.seconds_dt;
        out.queries = st.dt_queries;
        out.full_dts = st.full_dts;
        uint32_t off[CT_SEC_COUNT], levels, total;
        ct_package_layout((uint32_t)t.width, (uint32_t)t.height, (uint32_t)r, 24, t.void_post.empty() ? 0u : 1u, off,
                          out.sec, &levels, &total);
        ssize_t w = write(fd[1], &out, sizeof out);
        _exit(w == (ssize_t)sizeof out ? 0 : 1);
    }
    close(fd[1]);
    ssize_t got = read(fd[0], &res, sizeof res);
    close(fd[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    if (got != (ssize_t)sizeof res) res.seconds = -1;
    return res;
}

void row(const char *dem, const ct_host::Terrain &t, ct_host::PptBuilder b, int r, int slices)
{
    double dem_bytes = (double)t.width * t.height * 2;
    Result x = build_in_child(t, b, r, slices);
    const char *bn = b == ct_host::PptBuilder::Brute ? "brute" : "slices";
    if (x.seconds < 0) {
        std::printf("%-22s %-7s r=%d  build failed\n", dem, bn, r);
        return;
    }
    double ppt = x.sec[CT_SEC_APEX] + x.sec[CT_SEC_ANGLES];
    std::printf("%-22s %-7s r=%d %8.2f s  %8.1f MB = %5.2fx DEM (%5.2fx with the DEM; code pages %+.1f MB) | "
                "package %6.2fx (PPT %4.2fx) | %5.2f%% degenerate",
                dem, bn, r, x.seconds, x.work_bytes / 1e6, x.work_bytes / dem_bytes, 1.0 + x.work_bytes / dem_bytes,
                x.file_bytes / 1e6,
                x.bytes / dem_bytes,
                ppt / dem_bytes, 100.0 * x.degenerate / std::max<size_t>(1, x.cones));
    if (b == ct_host::PptBuilder::Slices)
        std::printf(" | %d slices x 24 sectors: %.3f queries per cell, %zu full DTs; near %.2f s, slices %.2f s",
                    x.slices, (double)x.queries / std::max(1.0, (double)x.slices * (double)x.cones), x.full_dts,
                    x.local_s, x.dt_s);
    std::printf("\n");
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char **argv)
{
    bool quick = false, brute_big = false, big_only = false;
    int slices = 80, big_r = 0;
    for (int k = 1; k < argc; ++k) {
        if (!std::strcmp(argv[k], "--quick")) quick = true;
        else if (!std::strcmp(argv[k], "--brute-2048")) brute_big = true;
        else if (!std::strcmp(argv[k], "--slices") && k + 1 < argc) slices = std::atoi(argv[++k]);
        else if (!std::strcmp(argv[k], "--big-only")) big_only = true;
        else if (!std::strcmp(argv[k], "--r") && k + 1 < argc) big_r = std::atoi(argv[++k]);
        else {
            std::fprintf(stderr, "usage: ct_bench_build [--quick] [--brute-2048] [--slices K] [--big-only] [--r R]\n");
            return 2;
        }
    }
    ct_host::Terrain t = dem_cases::real_terrain();
    if (t.width == 0) {
        std::fprintf(stderr, "ct_bench_build: fixture DEM missing\n");
        return 1;
    }
    using B = ct_host::PptBuilder;
    std::printf("=== PPT builders: N = 24 sectors, K = %d slices, 2 threads; working memory = peak RSS while the "
                "package is built and streamed to a file, above RSS before it (the DEM and libraries) ===\n", slices);
    std::printf("(package = whole file incl. the DEM's heights and the mipmap; PPT = apexes + angle planes)\n");
    for (int r : {1, 3}) {
        if (big_only) break;
        row("fixture 403x344", t, B::Slices, r, slices);
        row("fixture 403x344", t, B::Brute, r, slices);
    }
    if (!quick) {
        const ct_host::Terrain big = dem_cases::mirror_tiled(t, 2048, 2048);
        for (int r : {3, 1}) {
            if (big_r && r != big_r) continue;
            row("mirror-tiled 2048x2048", big, B::Slices, r, slices);
            if (brute_big) row("mirror-tiled 2048x2048", big, B::Brute, r, slices);
        }
    }
    return 0;
}
