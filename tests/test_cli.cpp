// test_cli.cpp -- the `conetrace` command line tool, end to end.
//
// Runs the real binary (CT_CLI) through system() inside a fresh scratch
// directory (mkdtemp under /tmp), capturing stdout, stderr and the exit
// code, and checks: build + info on the bundled real DEM; trace with every
// method against heights read independently from the fixture; the nodata
// policy (void posts -> "voids yes", status hit_void; all-nodata is an
// error); bad inputs (one "conetrace: " line naming the file, no output
// and no leftover temporary); an existing output survives a failed run.
//
// CT_TEST_VERBOSE=1 prints every command and its stderr; CT_TEST_KEEP=1
// keeps the scratch directory.  Independent invocations run a few at a
// time (each start of the binary costs ~0.4 s of dynamic linking).

#include "dem_io.hpp"
#include "harness.h"
#include "tiff_bytes.hpp"

#include <geotiffio.h>
#include <geovalues.h>
#include <tiffio.h>
#include <xtiffio.h>
#include <zlib.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#ifndef CT_CLI
#error "CT_CLI must be defined (path of the conetrace binary)"
#endif
#ifndef CT_FIXTURES_DIR
#error "CT_FIXTURES_DIR must be defined"
#endif

namespace fs = std::filesystem;
using ct_host::Georef;
using ct_host::SampleType;

// ---------------------------------------------------------------------------
// scratch directories, files, running the CLI

static std::string g_root;  // mkdtemp directory; captures live directly in it
static int g_dirs = 0;

static bool verbose() { return getenv("CT_TEST_VERBOSE") != nullptr; }

static std::string fixture_dem() { return std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif"; }

// A fresh, empty working directory under g_root.
static std::string new_dir(const char *tag)
{
    std::string d = g_root + "/" + std::to_string(++g_dirs) + "_" + tag;
    fs::create_directory(d);
    return d;
}

static std::string slurp(const std::string &path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

static void spit(const std::string &path, const std::string &text)
{
    std::ofstream o(path, std::ios::binary | std::ios::trunc);
    o << text;
}

static std::set<std::string> listing(const std::string &dir)
{
    std::set<std::string> s;
    for (const auto &e : fs::directory_iterator(dir)) s.insert(e.path().filename().string());
    return s;
}

static std::string join(const std::set<std::string> &s)
{
    std::string r;
    for (const auto &x : s) r += (r.empty() ? "" : " ") + x;
    return r.empty() ? "(empty)" : r;
}

static std::vector<std::string> lines_of(const std::string &text)
{
    std::vector<std::string> v;
    std::istringstream in(text);
    std::string l;
    while (std::getline(in, l)) v.push_back(l);
    return v;
}

static std::string quote(const std::string &s)
{
    std::string r = "'";
    for (char c : s) r += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return r + "'";
}

struct Run {
    int code = -1;  // exit code; >= 128: killed by a signal
    std::string out, err, cmd;
    std::vector<std::string> err_lines;
};

// One invocation: `conetrace ARGS...` with `dir` as working directory.
struct Job {
    std::string dir;
    std::vector<std::string> args;
    std::string shell = "";  // run before the binary (e.g. a file-size limit)
};

static Run run_job(const Job &j, int slot)
{
    Run r;
    std::string cmd = "cd " + quote(j.dir) + " && " + j.shell + "exec " + quote(CT_CLI);
    r.cmd = "conetrace";
    for (const auto &a : j.args) {
        cmd += " " + quote(a);
        r.cmd += " " + a;
    }
    // captures live in g_root itself, never in a checked directory
    const std::string fo = g_root + "/stdout." + std::to_string(slot), fe = g_root + "/stderr." + std::to_string(slot);
    cmd += " </dev/null >" + quote(fo) + " 2>" + quote(fe);
    int st = std::system(cmd.c_str());
    if (st == -1)
        r.code = -1;
    else if (WIFEXITED(st))
        r.code = WEXITSTATUS(st);
    else
        r.code = 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
    r.out = slurp(fo);
    r.err = slurp(fe);
    // the coverage build's instrumentation (libgcov) reports its own write
    // failures at exit (e.g. under the full-disk case's file-size limit):
    // not the tool's output
    for (const std::string &l : lines_of(r.err))
        if (l.compare(0, 24, "libgcov profiling error:") != 0) r.err_lines.push_back(l);
    return r;
}

static void print_run(const Run &r)
{
    if (verbose()) printf("  $ %s  -> %d\n%s", r.cmd.c_str(), r.code, r.err.c_str());
}

static Run run_cli(const std::string &dir, const std::vector<std::string> &args)
{
    Run r = run_job(Job{dir, args}, 0);
    print_run(r);
    return r;
}

// Independent jobs (each in its own directory) run a few at a time.
static std::vector<Run> run_all(const std::vector<Job> &jobs)
{
    std::vector<Run> runs(jobs.size());
    std::atomic<size_t> next{0};
    unsigned nt = std::max(2u, std::min(4u, std::thread::hardware_concurrency()));
    std::vector<std::thread> pool;
    for (unsigned w = 0; w < nt; ++w)
        pool.emplace_back([&, w] {
            for (size_t k; (k = next++) < jobs.size();) runs[k] = run_job(jobs[k], (int)w + 1);
        });
    for (auto &t : pool) t.join();
    for (const Run &r : runs) print_run(r);
    return runs;
}

static std::string first_err(const Run &r) { return r.err_lines.empty() ? "(no stderr)" : r.err_lines[0]; }

static bool starts_with(const std::string &s, const std::string &p) { return s.compare(0, p.size(), p) == 0; }
static bool contains(const std::string &s, const std::string &p) { return s.find(p) != std::string::npos; }

// The value of an `info` line "key<spaces>value" ("" if absent).
static std::string info_value(const std::string &text, const std::string &key)
{
    for (const std::string &l : lines_of(text)) {
        if (!starts_with(l, key) || l.size() <= key.size() || l[key.size()] != ' ') continue;
        size_t b = l.find_first_not_of(' ', key.size());
        return b == std::string::npos ? std::string() : l.substr(b);
    }
    return std::string();
}

// A failed run: non-zero exit (no crash), nothing on stdout, first stderr
// line "conetrace: ..." naming `name` and containing `needle`; exactly one
// stderr line unless `usage` (usage text may follow); directory unchanged.
// Returns "" or a description of what is wrong.
static std::string check_failure(const Run &r, const std::string &dir, const std::set<std::string> &before,
                                 const std::string &name, const std::string &needle = "", bool usage = false)
{
    std::string why;
    if (r.code == 0) why += "exit code 0; ";
    if (r.code < 0 || r.code >= 128) why += "crashed or killed (code " + std::to_string(r.code) + "); ";
    if (!r.out.empty()) why += "stdout not empty: '" + r.out + "'; ";
    if (r.err_lines.empty()) why += "nothing on stderr; ";
    if (!usage && r.err_lines.size() != 1) why += std::to_string(r.err_lines.size()) + " stderr lines; ";
    const std::string l = first_err(r);
    if (!starts_with(l, "conetrace: ")) why += "stderr does not start with 'conetrace: '; ";
    if (!name.empty() && !contains(l, name)) why += "message does not name '" + name + "'; ";
    if (!needle.empty()) {  // "a|b": either will do
        bool any = false;
        for (size_t b = 0, e; b <= needle.size(); b = e + 1) {
            e = std::min(needle.find('|', b), needle.size());
            any = any || contains(l, needle.substr(b, e - b));
        }
        if (!any) why += "message lacks '" + needle + "'; ";
    }
    std::set<std::string> after = listing(dir);
    if (after != before) why += "directory changed: before {" + join(before) + "}, after {" + join(after) + "}; ";
    if (why.empty()) return why;
    return "`" + r.cmd + "`: " + why + "stderr was: " + (r.err.empty() ? "(empty)" : r.err);
}

#define CHECK_FAILURE(...)                                                 \
    do {                                                                   \
        std::string why_ = check_failure(__VA_ARGS__);                     \
        TEST_ASSERT_MSG(why_.empty(), "%s", why_.c_str());                 \
    } while (0)

// ---------------------------------------------------------------------------
// the fixture (read independently with read_dem) and its package

static const int kW = 403, kH = 344;
static const double kOE = 195000.0, kON = 4071000.0, kPost = 30.0;

static ct_host::DemRaster g_dem;
static bool g_dem_ok = false;
static std::string g_pkg;  // absolute path of the fixture package (built by test 1 or on demand)

static double post_h(int i, int j) { return g_dem.h[(size_t)j * kW + (size_t)i]; }
static double post_e(double i) { return kOE + (i + 0.5) * kPost; }
static double post_n(double j) { return kON - (j + 0.5) * kPost; }

// Bilinear surface of the fixture at map (e, n); false outside the post box.
static bool surface(double e, double n, double *h)
{
    double x = (e - kOE) / kPost - 0.5, y = (kON - n) / kPost - 0.5;
    if (!(x >= 0 && y >= 0 && x <= kW - 1 && y <= kH - 1)) return false;
    int i = std::min((int)x, kW - 2), j = std::min((int)y, kH - 2);
    double fx = x - i, fy = y - j;
    *h = (1 - fy) * ((1 - fx) * post_h(i, j) + fx * post_h(i + 1, j)) +
         fy * ((1 - fx) * post_h(i, j + 1) + fx * post_h(i + 1, j + 1));
    return true;
}

static bool load_fixture()
{
    if (g_dem_ok) return true;
    try {
        g_dem = ct_host::read_dem(fixture_dem());
        g_dem_ok = g_dem.width == kW && g_dem.height == kH;
    } catch (const std::exception &e) {
        printf("  read_dem(%s): %s\n", fixture_dem().c_str(), e.what());
    }
    return g_dem_ok;
}

// Build the fixture package once (sectors 8, reduce 2); "" on failure.
static std::string fixture_package()
{
    if (!g_pkg.empty()) return g_pkg;
    std::string d = new_dir("pkg");
    Run r = run_cli(d, {"build", fixture_dem(), "-o", "X.ctp", "--sectors", "8", "--reduce", "2"});
    if (r.code == 0 && fs::exists(d + "/X.ctp")) g_pkg = d + "/X.ctp";
    else printf("  building the fixture package failed (%d): %s\n", r.code, r.err.c_str());
    return g_pkg;
}

// ---------------------------------------------------------------------------
// 1. build + info on the real DEM

// --help: the usage on stdout and exit 0 (for the program: every command's;
// `CMD --help`, anywhere on the line: that command's alone); a missing or
// unknown command: the usage on stderr and exit 2.
// The binary starts light: OpenImageIO and GDAL (~200 shared libraries
// between them) are loaded only from the plugin conetrace_heavy.so when a
// DEM is read (host_tools/cli/heavy_door.hpp), never by the dynamic linker at
// start-up; a binary without its plugin says so when it needs it and runs
// every other command.
static void test_light_start(void)
{
    std::string d = new_dir("light");
    Run r = run_job(Job{d, {}, "LD_TRACE_LOADED_OBJECTS=1 "}, 0);  // what ldd prints
    TEST_ASSERT_MSG(r.code == 0 && contains(r.out, "libtiff") && contains(r.out, "libc.so"), "no listing: %s",
                    r.out.c_str());
    TEST_ASSERT_MSG(!contains(r.out, "OpenImageIO") && !contains(r.out, "libgdal") && !contains(r.out, "opencv"),
                    "loaded at start-up:\n%s", r.out.c_str());
    // alone, without the plugin beside it
    fs::create_directories(d + "/bin");
    fs::copy_file(CT_CLI, d + "/bin/conetrace");
    fs::permissions(d + "/bin/conetrace", fs::perms::owner_all);
    const std::string dem = std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif";
    const std::string cmd = "cd " + quote(d) + " && ./bin/conetrace build " + quote(dem) + " -o p.ctp 2>err.txt";
    const int st = std::system(cmd.c_str());
    TEST_ASSERT(st != -1 && WIFEXITED(st) && WEXITSTATUS(st) == 1);
    const std::string err = slurp(d + "/err.txt");
    TEST_ASSERT_MSG(starts_with(err, "conetrace: cannot load the DEM reader ") && contains(err, "conetrace_heavy.so") &&
                        lines_of(err).size() == 1,
                    "stderr: %s", err.c_str());
    TEST_ASSERT(!fs::exists(d + "/p.ctp"));
    const int st2 = std::system(("cd " + quote(d) + " && ./bin/conetrace --help >/dev/null 2>&1").c_str());
    TEST_ASSERT(st2 != -1 && WIFEXITED(st2) && WEXITSTATUS(st2) == 0);
}

static void test_help(void)
{
    std::string d = new_dir("help");
    std::vector<Job> jobs;
    for (const char *c : {"build", "info", "trace", "demo", "geoloc", "render", "viewshed", "shadows", "view"})
        jobs.push_back(Job{d, {c, "--help"}});
    jobs.push_back(Job{d, {"--help"}});
    jobs.push_back(Job{d, {"-h"}});
    jobs.push_back(Job{d, {"help"}});
    jobs.push_back(Job{d, {"geoloc", "pkg.ctp", "-h"}});
    std::vector<Run> runs = run_all(jobs);
    const char *cmds[] = {"build", "info", "trace", "demo", "geoloc", "render", "viewshed", "shadows", "view"};
    for (size_t k = 0; k < runs.size(); ++k) {
        const Run &r = runs[k];
        TEST_ASSERT_MSG(r.code == 0, "%s exited %d", r.cmd.c_str(), r.code);
        TEST_ASSERT_MSG(r.err.empty(), "%s wrote to stderr: %s", r.cmd.c_str(), r.err.c_str());
        if (k < 9 || k == runs.size() - 1) {
            // CMD --help: that command's usage alone
            const char *c = k < 9 ? cmds[k] : "geoloc";
            TEST_ASSERT_MSG(starts_with(r.out, std::string("usage: conetrace ") + c), "%s: no usage of %s on stdout",
                            r.cmd.c_str(), c);
            for (const char *o : cmds)
                if (std::strcmp(o, c) != 0)
                    TEST_ASSERT_MSG(!contains(r.out, std::string("conetrace ") + o + " "), "%s: also %s's usage",
                                    r.cmd.c_str(), o);
        } else {
            TEST_ASSERT_MSG(starts_with(r.out, "usage: conetrace build") && contains(r.out, "conetrace geoloc PKG"),
                            "%s: no usage on stdout", r.cmd.c_str());
        }
    }
    TEST_ASSERT(contains(runs[4].out, "--pose-wgs84") && contains(runs[0].out, "--vdatum") &&
                contains(runs[0].out, "--utm"));
    Run bad = run_cli(d, {"frobnicate"});
    TEST_ASSERT(bad.code == 2 && bad.out.empty() && contains(bad.err, "unknown command 'frobnicate'") &&
                contains(bad.err, "usage: conetrace build"));
}

static void test_build_info_fixture(void)
{
    std::string d = new_dir("build");
    Run r = run_cli(d, {"build", fixture_dem(), "-o", "X.ctp", "--sectors", "8", "--reduce", "2"});
    TEST_ASSERT_MSG(r.code == 0, "build exited %d: %s", r.code, r.err.c_str());
    std::vector<std::string> out = lines_of(r.out);
    TEST_ASSERT_MSG(out.size() == 1, "build printed %zu lines on stdout, expected 1: '%s'", out.size(), r.out.c_str());
    TEST_ASSERT_MSG(contains(out[0], "X.ctp"), "summary does not name the output: '%s'", out[0].c_str());
    TEST_ASSERT_MSG(contains(out[0], "403x344"), "summary does not give the size: '%s'", out[0].c_str());
    TEST_ASSERT_MSG(fs::is_regular_file(d + "/X.ctp"), "no X.ctp after build");
    std::string pkg = slurp(d + "/X.ctp");
    TEST_ASSERT_MSG(pkg.size() > 128 && pkg.compare(0, 4, "CTPK") == 0, "X.ctp is not a package (%zu bytes)", pkg.size());
    std::set<std::string> files = listing(d);
    TEST_ASSERT_MSG(files == std::set<std::string>{"X.ctp"}, "build left {%s}", join(files).c_str());
    if (g_pkg.empty()) g_pkg = d + "/X.ctp";

    Run i = run_cli(d, {"info", "X.ctp"});
    TEST_ASSERT_MSG(i.code == 0, "info exited %d: %s", i.code, i.err.c_str());
    const std::string &t = i.out;
    TEST_ASSERT_MSG(info_value(t, "file") == "X.ctp", "info file: '%s'", info_value(t, "file").c_str());
    TEST_ASSERT_MSG(starts_with(info_value(t, "posts"), "403 x 344"), "info posts: '%s'", info_value(t, "posts").c_str());
    TEST_ASSERT_MSG(info_value(t, "sectors") == "8", "info sectors: '%s'", info_value(t, "sectors").c_str());
    TEST_ASSERT_MSG(info_value(t, "reduce") == "2" || starts_with(info_value(t, "reduce"), "2 "), "info reduce: '%s'",
                    info_value(t, "reduce").c_str());
    TEST_ASSERT_MSG(info_value(t, "epsg") == "32617", "info epsg: '%s'", info_value(t, "epsg").c_str());
    TEST_ASSERT_MSG(info_value(t, "voids") == "no", "info voids: '%s'", info_value(t, "voids").c_str());
    TEST_ASSERT_MSG(contains(t, "\nverify        ok\n"), "info lacks 'verify        ok':\n%s", t.c_str());
    // the origin and posting of fixtures/README.md
    double oe = 0, on = 0;
    TEST_ASSERT_MSG(std::sscanf(info_value(t, "origin").c_str(), "E %lf N %lf", &oe, &on) == 2, "info origin: '%s'",
                    info_value(t, "origin").c_str());
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, kOE, oe);
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, kON, on);
    double pe = 0, pn = 0;
    TEST_ASSERT_MSG(std::sscanf(info_value(t, "posting").c_str(), "%lf x %lf", &pe, &pn) == 2, "info posting: '%s'",
                    info_value(t, "posting").c_str());
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, kPost, pe);
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, -kPost, pn);
    TEST_ASSERT_MSG(listing(d) == files, "info changed the directory: {%s}", join(listing(d)).c_str());
}

// ---------------------------------------------------------------------------
// 2. trace

struct TRay {
    double e, n, h, de, dn, dh;
    const char *kind;  // "nadir", "below", "miss", "hit", "any"
    int pi, pj;        // nadir: the post under the ray
};

struct Row {
    std::string status, e, n, h, t, steps;
    double E = NAN, N = NAN, Hh = NAN, T = NAN;
};

static bool parse_hits(const std::string &text, std::vector<Row> *rows, std::string *why)
{
    std::vector<std::string> ls = lines_of(text);
    if (ls.empty() || ls[0] != "status,E,N,h,t,steps") {
        *why = "header is '" + (ls.empty() ? std::string("(none)") : ls[0]) + "'";
        return false;
    }
    rows->clear();
    for (size_t k = 1; k < ls.size(); ++k) {
        std::vector<std::string> f;
        std::string cur;
        for (char c : ls[k]) {
            if (c == ',') {
                f.push_back(cur);
                cur.clear();
            } else {
                cur += c;
            }
        }
        f.push_back(cur);
        if (f.size() != 6) {
            *why = "line " + std::to_string(k + 1) + " has " + std::to_string(f.size()) + " fields: '" + ls[k] + "'";
            return false;
        }
        Row r;
        r.status = f[0], r.e = f[1], r.n = f[2], r.h = f[3], r.t = f[4], r.steps = f[5];
        r.E = std::strtod(f[1].c_str(), nullptr);
        r.N = std::strtod(f[2].c_str(), nullptr);
        r.Hh = std::strtod(f[3].c_str(), nullptr);
        r.T = std::strtod(f[4].c_str(), nullptr);
        if (f[5].empty() || f[5].find_first_not_of("0123456789") != std::string::npos) {
            *why = "line " + std::to_string(k + 1) + ": steps '" + f[5] + "' is not an unsigned integer";
            return false;
        }
        rows->push_back(r);
    }
    return true;
}

static std::string fmt(double v)
{
    char b[64];
    std::snprintf(b, sizeof b, "%.17g", v);
    return b;
}

static std::vector<TRay> fixture_rays()
{
    std::vector<TRay> v;
    auto nadir = [&](int i, int j, double dh) { v.push_back({post_e(i), post_n(j), 1500.0, 0, 0, dh, "nadir", i, j}); };
    // the four corners (values of fixtures/README.md are checked separately)
    nadir(0, 0, -1);
    nadir(kW - 1, 0, -1);
    nadir(0, kH - 1, -1);
    nadir(kW - 1, kH - 1, -1);
    // interior posts, the highest and the lowest post, and one with |d| != 1
    int imax = 0, imin = 0;
    for (size_t k = 0; k < g_dem.h.size(); ++k) {
        if (g_dem.h[k] > g_dem.h[(size_t)imax]) imax = (int)k;
        if (g_dem.h[k] < g_dem.h[(size_t)imin]) imin = (int)k;
    }
    nadir(100, 50, -1);
    nadir(200, 171, -1);
    nadir(37, 300, -1);
    nadir(imax % kW, imax / kW, -1);
    nadir(imin % kW, imin / kW, -1);
    nadir(250, 100, -3);
    // starts below the surface: just under a post; horizontal under the lowest terrain
    v.push_back({post_e(120), post_n(120), post_h(120, 120) - 1.0, 0, 0, -1, "below", 0, 0});
    v.push_back({post_e(150), post_n(200), 200.0, 1, 0.25, 0, "below", 0, 0});
    // misses: outside heading away; horizontal overflight; rising into the sky
    v.push_back({190000.0, 4066000.0, 800.0, -1, 0.2, -0.1, "miss", 0, 0});
    v.push_back({194000.0, 4065000.0, 1200.0, 1, 0.3, 0, "miss", 0, 0});
    v.push_back({post_e(200), post_n(170), 1100.0, 0.6, -0.7, 0.2, "miss", 0, 0});
    // oblique rays that must hit: from high above the middle, and from outside
    v.push_back({post_e(200), post_n(170), 1500.0, 0.6, -0.8, -0.5, "hit", 0, 0});
    v.push_back({post_e(180), post_n(160), 1400.0, -0.3, 0.2, -1.0, "hit", 0, 0});
    v.push_back({post_e(220), post_n(150), 1300.0, -0.5, -0.5, -0.3, "hit", 0, 0});
    v.push_back({194000.0, 4066000.0, 1200.0, 1, 0.1, -0.08, "hit", 0, 0});
    // a grazing ray: whatever it does, all methods must agree
    v.push_back({195100.0, 4068000.0, 900.0, 1, -0.05, -0.02, "any", 0, 0});
    return v;
}

static void write_rays(const std::string &path, const std::vector<TRay> &rays, bool reversed)
{
    std::string t = reversed ? "dh,dN,dE,h,N,E\n" : "E,N,h,dE,dN,dh\n";
    for (const TRay &r : rays) {
        if (reversed)
            t += fmt(r.dh) + "," + fmt(r.dn) + "," + fmt(r.de) + "," + fmt(r.h) + "," + fmt(r.n) + "," + fmt(r.e) + "\n";
        else
            t += fmt(r.e) + "," + fmt(r.n) + "," + fmt(r.h) + "," + fmt(r.de) + "," + fmt(r.dn) + "," + fmt(r.dh) + "\n";
    }
    spit(path, t);
}

// Independent checks of one row against the ray; "" if fine.
static std::string check_row(const TRay &ray, const Row &row)
{
    std::ostringstream w;
    const std::string kind = ray.kind;
    const bool hit = row.status == "hit";
    if (kind == "below" || kind == "miss") {
        if (row.status != kind) w << "status " << row.status << ", expected " << kind;
        else if (row.e != "nan" || row.n != "nan" || row.h != "nan" || row.t != "nan")
            w << "E,N,h,t are '" << row.e << "," << row.n << "," << row.h << "," << row.t << "', expected nan";
        return w.str();
    }
    if (kind == "any" && !hit) {
        if (row.status != "miss") w << "status " << row.status << ", expected hit or miss";
        else if (row.e != "nan" || row.t != "nan") w << "a miss with E/t not nan";
        return w.str();
    }
    if (!hit) {
        w << "status " << row.status << ", expected hit";
        return w.str();
    }
    if (!(std::isfinite(row.E) && std::isfinite(row.N) && std::isfinite(row.Hh) && std::isfinite(row.T)))
        return "a hit with non-finite fields";
    // hit = origin + t * d
    const double pe = ray.e + row.T * ray.de, pn = ray.n + row.T * ray.dn, ph = ray.h + row.T * ray.dh;
    if (!(row.T > 0) || std::fabs(pe - row.E) > 0.001 || std::fabs(pn - row.N) > 0.001 || std::fabs(ph - row.Hh) > 0.001)
        w << "origin + t*d = (" << fmt(pe) << ", " << fmt(pn) << ", " << fmt(ph) << ") for t=" << row.t
          << ", hit is (" << row.e << ", " << row.n << ", " << row.h << "); ";
    if (kind == "nadir") {
        double want = post_h(ray.pi, ray.pj);
        if (std::fabs(row.Hh - want) > 0.01) w << "nadir over post (" << ray.pi << "," << ray.pj << ") hit h=" << row.h << ", post is " << want << "; ";
        if (std::fabs(row.E - ray.e) > 0.001 || std::fabs(row.N - ray.n) > 0.001)
            w << "nadir hit at (" << row.e << ", " << row.n << "), post centre (" << fmt(ray.e) << ", " << fmt(ray.n) << "); ";
    }
    // the hit lies on the bilinear surface of the fixture ...
    double s = 0;
    if (!surface(row.E, row.N, &s)) {
        w << "hit (" << row.e << ", " << row.n << ") outside the post box; ";
    } else if (std::fabs(s - row.Hh) > 0.05) {
        w << "hit h=" << row.h << " but the surface there is " << fmt(s) << "; ";
    }
    // ... and is the first one: the ray stays above the surface before it
    const double len = std::sqrt(ray.de * ray.de + ray.dn * ray.dn + ray.dh * ray.dh);
    const int n = std::max(100, (int)(row.T * len / 2.0));
    for (int k = 0; k < n; ++k) {
        double t = row.T * k / n;
        double hs = 0;
        if (!surface(ray.e + t * ray.de, ray.n + t * ray.dn, &hs)) continue;
        if (ray.h + t * ray.dh < hs - 0.05) {
            w << "not the first hit: at t=" << fmt(t) << " the ray is at h=" << fmt(ray.h + t * ray.dh)
              << ", below the surface " << fmt(hs) << "; ";
            break;
        }
    }
    return w.str();
}

static void test_trace_methods(void)
{
    TEST_ASSERT_MSG(load_fixture(), "cannot read the fixture DEM");
    // fixtures/README.md's corner posts
    TEST_ASSERT_DOUBLE_WITHIN(0, 483, post_h(0, 0));
    TEST_ASSERT_DOUBLE_WITHIN(0, 444, post_h(kW - 1, 0));
    TEST_ASSERT_DOUBLE_WITHIN(0, 545, post_h(0, kH - 1));
    TEST_ASSERT_DOUBLE_WITHIN(0, 272, post_h(kW - 1, kH - 1));
    const std::string pkg = fixture_package();
    TEST_ASSERT_MSG(!pkg.empty(), "no fixture package");

    std::string d = new_dir("trace");
    const std::vector<TRay> rays = fixture_rays();
    write_rays(d + "/rays.csv", rays, false);
    write_rays(d + "/rays_rev.csv", rays, true);

    // every method, the default, and the default on reordered columns; each
    // writes its own hits file, so they run side by side
    const char *methods[] = {"incremental", "hierarchical", "cone", "directional", nullptr};
    std::vector<Job> jobs;
    for (int m = 0; m < 5; ++m) {
        std::string hits = std::string("hits_") + (methods[m] ? methods[m] : "default") + ".csv";
        std::vector<std::string> args = {"trace", pkg, "--rays", "rays.csv", "-o", hits};
        if (methods[m]) {
            args.push_back("--method");
            args.push_back(methods[m]);
        }
        jobs.push_back(Job{d, args});
    }
    jobs.push_back(Job{d, {"trace", pkg, "--rays", "rays_rev.csv", "-o", "hits_rev.csv"}});
    // --threads: the rays 60 times over (several 1,024-ray chunks), on one
    // and on three threads
    {
        std::vector<TRay> many;
        for (int k = 0; k < 60; ++k) many.insert(many.end(), rays.begin(), rays.end());
        write_rays(d + "/rays_many.csv", many, false);
    }
    jobs.push_back(Job{d, {"trace", pkg, "--rays", "rays_many.csv", "-o", "hits_t1.csv", "--threads", "1"}});
    jobs.push_back(Job{d, {"trace", pkg, "--rays", "rays_many.csv", "-o", "hits_t3.csv", "--threads", "3"}});
    std::vector<Run> runs = run_all(jobs);

    std::vector<std::vector<Row>> all;
    std::vector<std::string> texts;
    for (int m = 0; m < 5; ++m) {
        const char *mname = methods[m] ? methods[m] : "(default)";
        const Run &r = runs[(size_t)m];
        TEST_ASSERT_MSG(r.code == 0, "trace %s exited %d: %s", mname, r.code, r.err.c_str());
        TEST_ASSERT_MSG(r.err.empty(), "trace %s wrote to stderr: %s", mname, r.err.c_str());
        TEST_ASSERT_MSG(r.out.empty(), "trace %s wrote to stdout: %s", mname, r.out.c_str());
        std::string text = slurp(d + "/" + jobs[(size_t)m].args[5]);
        std::vector<Row> rows;
        std::string why;
        TEST_ASSERT_MSG(parse_hits(text, &rows, &why), "trace %s: hits.csv: %s", mname, why.c_str());
        TEST_ASSERT_MSG(rows.size() == rays.size(), "trace %s: %zu rows for %zu rays", mname, rows.size(), rays.size());
        for (size_t k = 0; k < rays.size(); ++k) {
            std::string bad = check_row(rays[k], rows[k]);
            TEST_ASSERT_MSG(bad.empty(), "trace %s, ray %zu (%s, %s,%s,%s dir %s,%s,%s): %s", mname, k + 1, rays[k].kind,
                            fmt(rays[k].e).c_str(), fmt(rays[k].n).c_str(), fmt(rays[k].h).c_str(),
                            fmt(rays[k].de).c_str(), fmt(rays[k].dn).c_str(), fmt(rays[k].dh).c_str(), bad.c_str());
        }
        all.push_back(rows);
        texts.push_back(text);
    }
    // identical status, E, N, h, t for every method
    for (size_t m = 1; m < all.size(); ++m)
        for (size_t k = 0; k < rays.size(); ++k) {
            const Row &a = all[0][k], &b = all[m][k];
            TEST_ASSERT_MSG(a.status == b.status && a.e == b.e && a.n == b.n && a.h == b.h && a.t == b.t,
                            "ray %zu: %s gives %s,%s,%s,%s,%s but %s gives %s,%s,%s,%s,%s", k + 1, methods[0],
                            a.status.c_str(), a.e.c_str(), a.n.c_str(), a.h.c_str(), a.t.c_str(),
                            methods[m] ? methods[m] : "(default)", b.status.c_str(), b.e.c_str(), b.n.c_str(),
                            b.h.c_str(), b.t.c_str());
        }
    TEST_ASSERT_MSG(texts[4] == texts[3], "the default method's output differs from --method directional");

    // columns in another order: the very same output
    const Run &rr = runs[5];
    TEST_ASSERT_MSG(rr.code == 0, "trace with reordered columns exited %d: %s", rr.code, rr.err.c_str());
    std::string rev = slurp(d + "/hits_rev.csv");
    TEST_ASSERT_MSG(rev == texts[4], "reordered columns give different hits:\n%s\nvs\n%s", rev.c_str(), texts[4].c_str());
    // --threads 1 and 3: the same file, and the one-ray-set output 60 times
    {
        TEST_ASSERT_MSG(runs[6].code == 0 && runs[7].code == 0, "trace --threads exited %d / %d: %s%s", runs[6].code,
                        runs[7].code, runs[6].err.c_str(), runs[7].err.c_str());
        std::string t1 = slurp(d + "/hits_t1.csv"), t3 = slurp(d + "/hits_t3.csv");
        TEST_ASSERT_MSG(t1 == t3, "trace --threads 3 differs from --threads 1");
        std::string body = texts[4].substr(texts[4].find('\n') + 1), want_many = texts[4].substr(0, texts[4].find('\n') + 1);
        for (int k = 0; k < 60; ++k) want_many += body;
        TEST_ASSERT_MSG(t1 == want_many, "trace --threads: rows not the single run's, in input order");
    }
    std::set<std::string> files = listing(d), want = {"rays.csv", "rays_rev.csv", "hits_rev.csv", "rays_many.csv"};
    for (const Job &j : jobs) want.insert(j.args[5]);
    TEST_ASSERT_MSG(files == want, "trace left {%s}", join(files).c_str());
}

// ---------------------------------------------------------------------------
// 3. nodata policy

static const int sW = 20, sH = 15;
static const double sOE = 600000.0, sON = 4500000.0, sNodata = -9999.0;

// multiples of 1/8 m: exact at the package's 1/16 m LSB
static double small_h(int i, int j) { return 200.0 + 1.5 * i + 2.25 * j + 0.125 * ((i * j) % 7); }
static bool small_void(int i, int j) { return i >= 6 && i <= 9 && j >= 5 && j <= 8; }

static Georef small_geo(double posting_n = -30.0)
{
    Georef g;
    g.origin_e = sOE;
    g.origin_n = sON;
    g.posting_e = 30.0;
    g.posting_n = posting_n;
    g.epsg = 32617;
    return g;
}

// write_geotiff; "" or the error text
static std::string write_small(const std::string &path, bool voids, bool all_nodata, double posting_n = -30.0)
{
    std::vector<double> v((size_t)sW * sH);
    for (int j = 0; j < sH; ++j)
        for (int i = 0; i < sW; ++i)
            v[(size_t)j * sW + i] = all_nodata || (voids && small_void(i, j)) ? sNodata : small_h(i, j);
    try {
        ct_host::write_geotiff(path, sW, sH, v, SampleType::Float32, small_geo(posting_n), true, sNodata);
    } catch (const std::exception &e) {
        return e.what();
    }
    return "";
}

static void test_nodata_policy(void)
{
    std::string d = new_dir("nodata");
    std::string w = write_small(d + "/void.tif", true, false);
    TEST_ASSERT_MSG(w.empty(), "write_geotiff: %s", w.c_str());
    Run b = run_cli(d, {"build", "void.tif", "-o", "void.ctp", "--sectors", "8", "--reduce", "2"});
    TEST_ASSERT_MSG(b.code == 0, "build of a DEM with voids exited %d: %s", b.code, b.err.c_str());
    TEST_ASSERT_MSG(lines_of(b.out).size() == 1 && contains(b.out, "void.ctp"), "build summary: '%s'", b.out.c_str());

    // nadir over the middle of the void block (grid x 7.5, y 6.5: cell (7,6),
    // all four corners void); nadir over a valid post far from the voids
    const double ve = sOE + (7.5 + 0.5) * 30, vn = sON - (6.5 + 0.5) * 30;
    const double ge = sOE + (17 + 0.5) * 30, gn = sON - (12 + 0.5) * 30;
    spit(d + "/rays.csv", "E,N,h,dE,dN,dh\n" + fmt(ve) + "," + fmt(vn) + ",1000,0,0,-1\n" + fmt(ge) + "," + fmt(gn) +
                              ",1000,0,0,-1\n");
    // every post nodata: an error naming the file, no output
    std::string d2 = new_dir("allnodata");
    w = write_small(d2 + "/allnd.tif", false, true);
    TEST_ASSERT_MSG(w.empty(), "write_geotiff: %s", w.c_str());
    const std::set<std::string> before2 = listing(d2);

    const char *methods[] = {"incremental", "hierarchical", "cone", "directional"};
    std::vector<Job> jobs = {Job{d, {"info", "void.ctp"}}, Job{d2, {"build", "allnd.tif", "-o", "allnd.ctp"}}};
    for (const char *m : methods)
        jobs.push_back(Job{d, {"trace", "void.ctp", "--rays", "rays.csv", "--method", m, "-o", std::string("hits_") + m + ".csv"}});
    std::vector<Run> runs = run_all(jobs);

    const Run &i = runs[0];
    TEST_ASSERT_MSG(i.code == 0, "info exited %d: %s", i.code, i.err.c_str());
    TEST_ASSERT_MSG(contains(i.out, "\nvoids         yes\n"), "info lacks 'voids         yes':\n%s", i.out.c_str());
    TEST_ASSERT_MSG(contains(i.out, "\nverify        ok\n"), "info lacks 'verify        ok':\n%s", i.out.c_str());
    TEST_ASSERT_MSG(starts_with(info_value(i.out, "posts"), "20 x 15"), "info posts: '%s'", info_value(i.out, "posts").c_str());
    TEST_ASSERT_MSG(info_value(i.out, "epsg") == "32617", "info epsg: '%s'", info_value(i.out, "epsg").c_str());

    CHECK_FAILURE(runs[1], d2, before2, "allnd.tif");

    for (size_t k = 0; k < 4; ++k) {
        const char *m = methods[k];
        const Run &t = runs[k + 2];
        TEST_ASSERT_MSG(t.code == 0, "trace %s exited %d: %s", m, t.code, t.err.c_str());
        std::vector<Row> rows;
        std::string why;
        TEST_ASSERT_MSG(parse_hits(slurp(d + "/hits_" + m + ".csv"), &rows, &why), "trace %s: %s", m, why.c_str());
        TEST_ASSERT_MSG(rows.size() == 2, "trace %s: %zu rows", m, rows.size());
        TEST_ASSERT_MSG(rows[0].status == "hit_void", "trace %s: nadir into the void block: status %s, expected hit_void",
                        m, rows[0].status.c_str());
        // the void floor is the lowest valid height (post (0,0) = 200 m)
        TEST_ASSERT_MSG(std::fabs(rows[0].Hh - 200.0) <= 0.01, "trace %s: void floor at h=%s, expected 200 (lowest valid)",
                        m, rows[0].h.c_str());
        TEST_ASSERT_MSG(std::fabs(rows[0].E - ve) <= 0.001 && std::fabs(rows[0].N - vn) <= 0.001,
                        "trace %s: void hit at %s,%s", m, rows[0].e.c_str(), rows[0].n.c_str());
        TEST_ASSERT_MSG(rows[1].status == "hit", "trace %s: nadir over valid post (17,12): status %s", m,
                        rows[1].status.c_str());
        TEST_ASSERT_MSG(std::fabs(rows[1].Hh - small_h(17, 12)) <= 0.01, "trace %s: post (17,12) hit at h=%s, post is %g",
                        m, rows[1].h.c_str(), small_h(17, 12));
        TEST_ASSERT_MSG(std::fabs(rows[1].E - ge) <= 0.001 && std::fabs(rows[1].N - gn) <= 0.001,
                        "trace %s: valid hit at %s,%s", m, rows[1].e.c_str(), rows[1].n.c_str());
        TEST_ASSERT_MSG(std::fabs(rows[1].T - (1000.0 - small_h(17, 12))) <= 0.001, "trace %s: t=%s", m, rows[1].t.c_str());
    }
}

// ---------------------------------------------------------------------------
// 4. bad inputs: each case runs in its own empty directory (read-only inputs
// come from a shared one), so "no output, no temporary" is a listing check.

struct BadCase {
    const char *tag;
    std::vector<std::string> args;  // "@x" = the shared input file x
    std::string name, needle;       // the message must contain name and needle ("a|b": a or b)
    bool usage;                     // usage text may follow the first line
    std::string rays;               // if set: written to rays.csv in the case directory
};

// A little-endian TIFF whose header promises w x h uncompressed int16 posts
// in one strip but holds 64 bytes of pixels.
static std::string lying_tiff(uint32_t w, uint32_t h)
{
    return tiff_bytes::make({{256, 4, w}, {257, 4, h}, {258, 3, 16}, {259, 3, 1}, {262, 3, 1},
                             {273, 4, tiff_bytes::kData}, {277, 3, 1}, {278, 4, h}, {279, 4, w * h * 2}, {339, 3, 2}},
                            std::string(64, '\0'));
}

static void test_bad_inputs(void)
{
    std::string in = new_dir("inputs");
    std::string w = write_small(in + "/ok.tif", false, false);
    TEST_ASSERT_MSG(w.empty(), "write_geotiff: %s", w.c_str());
    spit(in + "/garbage.tif", "this is not a TIFF file at all\n");
    spit(in + "/gif.tif", "GIF89a not a tiff\n");
    // write_geotiff writes ModelPixelScale (|posting_e|, |posting_n|) as given
    w = write_small(in + "/nonsq.tif", false, false, -20.0);
    TEST_ASSERT_MSG(w.empty(), "write_geotiff (non-square): %s", w.c_str());
    try {  // one post wider than the package format allows (CT_MAX_POSTS = 32768)
        std::vector<double> wide((size_t)(32768 + 1) * 2, 100.0);
        ct_host::write_geotiff(in + "/wide.tif", 32768 + 1, 2, wide, SampleType::Int16, small_geo(-30.0), false, 0);
    } catch (const std::exception &e) {
        TEST_FAIL_MSG("write_geotiff (wide): %s", e.what());
    }
    try {  // one post: no cell to trace
        ct_host::write_geotiff(in + "/one.tif", 1, 1, std::vector<double>(1, 100.0), SampleType::Int16,
                               small_geo(-30.0), false, 0);
    } catch (const std::exception &e) {
        TEST_FAIL_MSG("write_geotiff (1 x 1): %s", e.what());
    }
    spit(in + "/empty.csv", "");
    spit(in + "/lie.tif", lying_tiff(30000, 30000));  // 1.8 GB promised, 64 bytes there
    {
        // fuzz_host's finding as it found it (less its first byte, the
        // harness's choice of reader): 8 x 8 posts in tiles of 28,944 x
        // 65,521, a 7.6 GB tile for OpenImageIO to allocate
        const std::string seed = slurp(std::string(CT_FIXTURES_DIR) + "/../tests/fuzz/corpus_host/dem_huge_tiles");
        TEST_ASSERT_MSG(seed.size() > 100, "no corpus_host/dem_huge_tiles");
        spit(in + "/tiles.tif", seed.substr(1));
    }
    const std::string pkg = fixture_package();
    TEST_ASSERT_MSG(!pkg.empty(), "no fixture package");
    std::string bytes = slurp(pkg);
    TEST_ASSERT_MSG(bytes.size() > 4096, "fixture package too small (%zu)", bytes.size());
    spit(in + "/trunc.ctp", bytes.substr(0, 100));
    std::string flipped = bytes;
    flipped[flipped.size() / 2] = (char)(flipped[flipped.size() / 2] ^ 0x10);
    spit(in + "/flip.ctp", flipped);
    const std::set<std::string> inputs = listing(in);

    const std::string good = "E,N,h,dE,dN,dh\n195600,4068000,1500,0,0,-1\n";
    const std::string fix = fixture_dem();
    const std::vector<BadCase> cases = {
        // DEM problems
        {"missing", {"build", "missing.tif", "-o", "X.ctp"}, "missing.tif", "", false, ""},
        {"garbage", {"build", "@garbage.tif", "-o", "X.ctp"}, "garbage.tif", "", false, ""},
        // a .tif that starts like a GIF: OpenImageIO's GIF reader takes it
        {"gif", {"build", "@gif.tif", "-o", "X.ctp"}, "gif.tif", "", false, ""},
        {"nonsquare", {"build", "@nonsq.tif", "-o", "X.ctp"}, "nonsq.tif", "non-square", false, ""},
        {"onepost", {"build", "@one.tif", "-o", "X.ctp"}, "one.tif", "", false, ""},
        {"lie", {"build", "@lie.tif", "-o", "X.ctp", "--posting", "30"}, "lie.tif", "promises", false, ""},
        {"hugetiles", {"build", "@tiles.tif", "-o", "X.ctp", "--posting", "30"}, "tiles.tif", "tiles of 28944 x 65521",
         false, ""},
        // output problems
        {"nodir", {"build", "@ok.tif", "-o", "nodir/X.ctp"}, "nodir/X.ctp", "", false, ""},
        {"outisdir", {"build", "@ok.tif", "-o", "adir"}, "adir", "", false, ""},
        // not writable even for root
        {"readonly", {"build", "@ok.tif", "-o", "/proc/conetrace-test.ctp"}, "/proc/conetrace-test.ctp", "", false,
         ""},
        // damaged packages
        {"trunc", {"info", "@trunc.ctp"}, "trunc.ctp", "err_truncated", false, ""},
        {"flip", {"info", "@flip.ctp"}, "flip.ctp", "err_crc", false, ""},
        // bad rays.csv: file and line
        {"nodh", {"trace", pkg, "--rays", "rays.csv", "-o", "hits.csv"}, "rays.csv:1:", "dh", false,
         "E,N,h,dE,dN\n195600,4068000,1500,0,0\n"},
        {"badnum", {"trace", pkg, "--rays", "rays.csv", "-o", "hits.csv"}, "rays.csv:3:", "15x0", false,
         good + "195600,4068000,15x0,0,0,-1\n"},
        {"emptycsv", {"trace", pkg, "--rays", "@empty.csv", "-o", "hits.csv"}, "empty.csv", "empty file", false, ""},
        {"inf", {"trace", pkg, "--rays", "rays.csv", "-o", "hits.csv"}, "rays.csv:3:", "inf", false,
         good + "195600,4068000,inf,0,0,-1\n"},
        {"nan", {"trace", pkg, "--rays", "rays.csv", "-o", "hits.csv"}, "rays.csv:2:", "nan", false,
         "E,N,h,dE,dN,dh\n195600,4068000,1500,nan,0,-1\n"},
        // a NUL ended strtod's text: "-1\0x" was read as -1 (found by fuzz_host)
        {"nulbyte", {"trace", pkg, "--rays", "rays.csv", "-o", "hits.csv"}, "rays.csv:2:", "bad number '-1?x' in column dh",
         false, std::string("E,N,h,dE,dN,dh\n195600,4068000,1500,0,0,-1\0x\n", 44)},
        {"dupcol", {"trace", pkg, "--rays", "rays.csv", "-o", "hits.csv"}, "rays.csv:1:", "twice", false,
         "E,N,h,dE,dN,dh,dh\n195600,4068000,1500,0,0,-1,-1\n"},
        {"short", {"trace", pkg, "--rays", "rays.csv", "-o", "hits.csv"}, "rays.csv:3:", "too few", false,
         good + "195600,4068000,1500,0,0\n"},
        // usage errors
        {"method", {"trace", pkg, "--rays", "rays.csv", "--method", "bogus", "-o", "hits.csv"}, "", "bogus", true, good},
        {"threads", {"trace", pkg, "--rays", "rays.csv", "--threads", "x", "-o", "hits.csv"}, "", "--threads", false,
         good},
        {"threads257", {"trace", pkg, "--rays", "rays.csv", "--threads", "257", "-o", "hits.csv"}, "", "--threads",
         false, good},
        {"option", {"build", fix, "-o", "X.ctp", "--frobnicate", "1"}, "", "--frobnicate", true, ""},
        {"command", {"frobnicate"}, "", "frobnicate", true, ""},
        {"noargs", {"trace", pkg}, "", "--rays|-o", true, ""},
        {"sectors0", {"build", fix, "-o", "X.ctp", "--sectors", "0"}, "", "--sectors", true, ""},
        {"sectors65", {"build", fix, "-o", "X.ctp", "--sectors", "65"}, "", "--sectors", true, ""},
        {"reduce9", {"build", fix, "-o", "X.ctp", "--reduce", "9"}, "", "--reduce", true, ""},
        // out-of-range option values must not be truncated or ignored
        {"sectors2^32+8", {"build", "@ok.tif", "-o", "X.ctp", "--sectors", "4294967304"}, "", "--sectors", true, ""},
        {"hscale_nan", {"build", "@ok.tif", "-o", "X.ctp", "--height-scale", "nan"}, "", "--height-scale|ok.tif", true, ""},
        {"posting_nan", {"build", "@ok.tif", "-o", "X.ctp", "--posting", "nan"}, "", "--posting|ok.tif", true, ""},
        {"toolarge", {"build", "@wide.tif", "-o", "X.ctp"}, "wide.tif", "exceeds the package limit", false, ""},
        {"builder", {"build", "@ok.tif", "-o", "X.ctp", "--builder", "magic"}, "", "--builder", true, ""},
        {"window0", {"build", "@ok.tif", "-o", "X.ctp", "--window", "0"}, "", "--window", true, ""},
    };
    std::vector<Job> jobs;
    std::vector<std::string> dirs;
    std::vector<std::set<std::string>> befores;
    for (const BadCase &c : cases) {
        std::string d = new_dir(c.tag);
        if (!c.rays.empty()) spit(d + "/rays.csv", c.rays);
        if (std::string(c.tag) == "outisdir") fs::create_directory(d + "/adir");
        Job j{d, c.args};
        for (auto &a : j.args)
            if (!a.empty() && a[0] == '@') a = in + "/" + a.substr(1);
        jobs.push_back(j);
        dirs.push_back(d);
        befores.push_back(listing(d));
    }
    std::vector<Run> runs = run_all(jobs);
    // every case is checked; all failures are reported together
    std::string bad;
    int nbad = 0;
    for (size_t k = 0; k < cases.size(); ++k) {
        const BadCase &c = cases[k];
        std::string why = check_failure(runs[k], dirs[k], befores[k], c.name, c.needle, c.usage);
        if (!why.empty()) {
            bad += "\n    case " + std::string(c.tag) + ": " + why;
            nbad++;
        }
    }
    TEST_ASSERT_MSG(bad.empty(), "%d of %zu bad-input cases wrong:%s", nbad, cases.size(), bad.c_str());
    for (size_t k = 0; k < cases.size(); ++k)
        if (std::string(cases[k].tag) == "outisdir")
            TEST_ASSERT_MSG(fs::is_empty(dirs[k] + "/adir"), "case outisdir: something was written into adir");
    TEST_ASSERT_MSG(!fs::exists("/proc/conetrace-test.ctp"), "case readonly: a file appeared");
    TEST_ASSERT_MSG(listing(in) == inputs, "the input directory changed: {%s}", join(listing(in)).c_str());
}

// Rows the library answers with a status of their own: the run succeeds and
// says so per row (docs/cli.md, "Bad input").
static void test_bad_rows(void)
{
    const std::string pkg = fixture_package();
    TEST_ASSERT_MSG(!pkg.empty(), "no fixture package");
    const std::string hdr = "E,N,h,dE,dN,dh\n", ok = "195600,4068000,1500,0,0,-1\n";
    struct R {
        const char *tag;
        std::string rays;
        std::vector<std::string> extra;  // more options
        std::vector<std::string> rows;   // expected status column, in order
    };
    const std::vector<R> cases = {
        {"header only", hdr, {}, {}},
        {"huge origin", hdr + ok + "195600,4068000,1e300,0,0,-1\n", {}, {"hit", "err_ray"}},
        {"zero direction", hdr + "195600,4068000,1500,0,0,0\n" + ok, {}, {"err_ray", "hit"}},
        // only a direction's ratios count: 1e300 east is due east (above the terrain here)
        {"huge direction", hdr + "195600,4068000,1500,1e300,0,-1\n", {}, {"miss"}},
        {"threads 0 (all cores)", hdr + ok + ok, {"--threads", "0"}, {"hit", "hit"}},
    };
    std::vector<Job> jobs;
    for (const R &c : cases) {
        const std::string d = new_dir("rows");
        spit(d + "/rays.csv", c.rays);
        Job j{d, {"trace", pkg, "--rays", "rays.csv", "-o", "hits.csv"}};
        j.args.insert(j.args.end(), c.extra.begin(), c.extra.end());
        jobs.push_back(j);
    }
    const std::vector<Run> runs = run_all(jobs);
    for (size_t k = 0; k < cases.size(); ++k) {
        TEST_ASSERT_MSG(runs[k].code == 0, "case %s: `%s` exit %d: %s", cases[k].tag, runs[k].cmd.c_str(), runs[k].code,
                        runs[k].err.c_str());
        const std::vector<std::string> l = lines_of(slurp(jobs[k].dir + "/hits.csv"));
        TEST_ASSERT_MSG(!l.empty() && starts_with(l[0], "status,"), "case %s: no header", cases[k].tag);
        std::vector<std::string> st;
        for (size_t r = 1; r < l.size(); ++r) st.push_back(l[r].substr(0, l[r].find(',')));
        TEST_ASSERT_MSG(st == cases[k].rows, "case %s: statuses {%s}, expected {%s}", cases[k].tag, join({st.begin(), st.end()}).c_str(),
                        join({cases[k].rows.begin(), cases[k].rows.end()}).c_str());
    }
}

// ---------------------------------------------------------------------------
// 5. an existing output survives a failed run

static void test_failed_run_keeps_output(void)
{
    std::string in = new_dir("keep_inputs");
    std::string w = write_small(in + "/allnd.tif", false, true);
    TEST_ASSERT_MSG(w.empty(), "write_geotiff: %s", w.c_str());
    spit(in + "/garbage.tif", std::string("II*\0\x08\0\0\0", 8) + "a truncated TIFF");
    spit(in + "/rays.csv", "E,N,h,dE,dN,dh\n195600,4068000,1500,0,0,-1\n195600,4068000,nan,0,0,-1\n");
    const std::string pkg = fixture_package();
    TEST_ASSERT_MSG(!pkg.empty(), "no fixture package");

    std::string many = "E,N,h,dE,dN,dh\n";
    for (int k = 0; k < 3000; ++k) many += "195600,4068000,1500,0,0,-1\n";
    spit(in + "/many.csv", many);
    // a full disk, as the process sees it: writes beyond 4 KB fail (EFBIG;
    // SIGXFSZ ignored so that write() reports it)
    const std::string full = "trap '' XFSZ; ulimit -f 8; ";
    struct K {
        std::vector<std::string> args;
        std::string kept, name;
        std::string shell = "";
    };
    const std::vector<K> cases = {
        {{"build", fixture_dem(), "-o", "out.ctp"}, "out.ctp", "out.ctp", full},
        {{"trace", pkg, "--rays", in + "/many.csv", "-o", "hits.csv"}, "hits.csv", "hits.csv", full},
        {{"build", "missing.tif", "-o", "out.ctp"}, "out.ctp", "missing.tif"},
        {{"build", in + "/garbage.tif", "-o", "out.ctp"}, "out.ctp", "garbage.tif"},
        {{"build", in + "/allnd.tif", "-o", "out.ctp"}, "out.ctp", "allnd.tif"},
        {{"build", fixture_dem(), "-o", "out.ctp", "--sectors", "65"}, "out.ctp", ""},
        {{"trace", pkg, "--rays", in + "/rays.csv", "-o", "hits.csv"}, "hits.csv", "rays.csv:3:"},
    };
    std::vector<Job> jobs;
    std::vector<std::set<std::string>> befores;
    for (const K &c : cases) {
        std::string d = new_dir("keep");
        spit(d + "/" + c.kept, "keep");
        jobs.push_back(Job{d, c.args, c.shell});
        befores.push_back(listing(d));
    }
    std::vector<Run> runs = run_all(jobs);
    for (size_t k = 0; k < cases.size(); ++k) {
        const Run &r = runs[k];
        TEST_ASSERT_MSG(r.code != 0, "`%s` succeeded", r.cmd.c_str());
        TEST_ASSERT_MSG(slurp(jobs[k].dir + "/" + cases[k].kept) == "keep", "`%s` damaged the existing %s", r.cmd.c_str(),
                        cases[k].kept.c_str());
        std::string why = check_failure(r, jobs[k].dir, befores[k], cases[k].name, "", cases[k].name.empty());
        TEST_ASSERT_MSG(why.empty(), "%s", why.c_str());
    }
}

// ---------------------------------------------------------------------------
// 6. tile sets: build --tile-size, info, trace over a set (the package's
// rows but the steps), a missing tile (no_data, the other rows unchanged),
// failures that leave nothing behind

// rows of a hits file without the steps column
static std::vector<std::string> rows_sans_steps(const std::string &text)
{
    std::vector<std::string> out;
    for (const std::string &l : lines_of(text)) out.push_back(l.substr(0, l.rfind(',')));
    return out;
}

static void test_tile_sets(void)
{
    TEST_ASSERT_MSG(load_fixture(), "cannot read the fixture DEM");
    std::string d = new_dir("tiles");
    // grazing and oblique rays across the whole DEM: many cross seams
    std::vector<TRay> rays = fixture_rays();
    ct_rng rng;
    ct_rng_seed(&rng, 9);
    for (int k = 0; k < 400; ++k) {
        const double e = kOE + ct_rng_unit(&rng) * kW * kPost, n = kON - ct_rng_unit(&rng) * kH * kPost;
        const double az = ct_rng_unit(&rng) * 6.283, el = (k % 2 ? 0.02 : 0.4) * ct_rng_unit(&rng) + 0.001;
        rays.push_back({e, n, 1100.0 + 300 * ct_rng_unit(&rng), std::cos(az), std::sin(az), -std::tan(el), "any", 0, 0});
    }
    write_rays(d + "/rays.csv", rays, false);
    std::vector<Run> runs = run_all({
        Job{d, {"build", fixture_dem(), "-o", "set", "--tile-size", "129", "--reduce", "3", "--sectors", "16"}},
        Job{d, {"build", fixture_dem(), "-o", "one.ctp", "--reduce", "3", "--sectors", "16"}},
    });
    TEST_ASSERT_MSG(runs[0].code == 0 && runs[1].code == 0, "build failed: %s %s", runs[0].err.c_str(),
                    runs[1].err.c_str());
    TEST_ASSERT_MSG(contains(runs[0].out, "4 x 3 tiles of 129 posts"), "build summary: %s", runs[0].out.c_str());
    const std::set<std::string> files = listing(d + "/set");
    TEST_ASSERT_EQUAL_INT(13, (int)files.size());  // 12 tiles and the manifest
    TEST_ASSERT(files.count("manifest.ctm") == 1 && files.count("tile_3_2.ctp") == 1);
    Run info = run_cli(d, {"info", "set"});
    TEST_ASSERT_EQUAL_INT(0, info.code);
    TEST_ASSERT_MSG(starts_with(info_value(info.out, "verify"), "ok"), "info: %s", info.out.c_str());
    TEST_ASSERT_MSG(starts_with(info_value(info.out, "tiles"), "4 x 3 of 129 posts"), "info: %s", info.out.c_str());
    TEST_ASSERT_MSG(starts_with(info_value(info.out, "posts"), "403 x 344"), "info: %s", info.out.c_str());

    // a copy without tile (1, 1)
    fs::copy(d + "/set", d + "/holed");
    fs::remove(d + "/holed/tile_1_1.ctp");
    runs = run_all({
        Job{d, {"trace", "one.ctp", "--rays", "rays.csv", "-o", "h_one.csv"}},
        Job{d, {"trace", "set", "--rays", "rays.csv", "--cache-tiles", "1", "-o", "h_set1.csv"}},
        Job{d, {"trace", "set/manifest.ctm", "--rays", "rays.csv", "--threads", "3", "-o", "h_set.csv"}},
        Job{d, {"trace", "holed", "--rays", "rays.csv", "-o", "h_holed.csv"}},
        Job{d, {"info", "holed"}},
    });
    for (int k = 0; k < 4; ++k) TEST_ASSERT_MSG(runs[k].code == 0, "`%s`: %s", runs[k].cmd.c_str(), runs[k].err.c_str());
    TEST_ASSERT_MSG(contains(runs[1].err, "tile loads"), "trace over a set reports its loads: %s", runs[1].err.c_str());
    const auto one = rows_sans_steps(slurp(d + "/h_one.csv"));
    TEST_ASSERT(one.size() == rays.size() + 1);
    TEST_ASSERT_MSG(rows_sans_steps(slurp(d + "/h_set1.csv")) == one, "a 1-slot cache changed the rows");
    TEST_ASSERT_MSG(rows_sans_steps(slurp(d + "/h_set.csv")) == one, "the tile set's rows differ from the package's");
    const auto holed = rows_sans_steps(slurp(d + "/h_holed.csv"));
    TEST_ASSERT(holed.size() == one.size());
    size_t nodata = 0, same = 0;
    for (size_t k = 1; k < holed.size() && k < one.size(); ++k) {
        if (starts_with(holed[k], "no_data,")) nodata++;
        else same += holed[k] == one[k];
    }
    TEST_ASSERT_MSG(nodata > 0 && nodata + same == holed.size() - 1, "holed set: %zu no_data, %zu as the package of %zu",
                    nodata, same, holed.size() - 1);
    TEST_ASSERT_MSG(runs[4].code != 0 && contains(runs[4].out, "tile_1_1.ctp"), "info on the holed set: %d %s",
                    runs[4].code, runs[4].out.c_str());

    // geoloc over the set: the package's rows but the steps (column 7), with
    // the true Earth (curvature and refraction on the UTM fixture)
    {
        std::string px = "u,v\n";
        for (int v = 0; v < 768; v += 48)
            for (int u = 0; u < 1024; u += 48) px += std::to_string(u) + "," + std::to_string(v) + "\n";
        spit(d + "/px.csv", px);
        const std::string cam = std::string(CT_FIXTURES_DIR) + "/scenes/oblique30.cameramodel";
        runs = run_all({
            Job{d, {"geoloc", "one.ctp", "--camera", cam, "--pixels", "px.csv", "--effects", "curvature,refraction",
                    "-o", "g_one.csv"}},
            Job{d, {"geoloc", "set", "--camera", cam, "--pixels", "px.csv", "--effects", "curvature,refraction",
                    "--cache-tiles", "2", "-o", "g_set.csv"}},
        });
        TEST_ASSERT_MSG(runs[0].code == 0 && runs[1].code == 0, "geoloc: %s %s", runs[0].err.c_str(), runs[1].err.c_str());
        auto sans_steps = [](const std::string &text) {
            std::vector<std::string> out;
            for (const std::string &l : lines_of(text)) {
                size_t c = 0, k = 0;
                for (; k < l.size() && c < 6; ++k) c += l[k] == ',';
                const size_t e = l.find(',', k);
                out.push_back(l.substr(0, k) + (e == std::string::npos ? "" : l.substr(e)));
            }
            return out;
        };
        const auto g1 = sans_steps(slurp(d + "/g_one.csv")), g2 = sans_steps(slurp(d + "/g_set.csv"));
        size_t hit = 0;
        for (const std::string &l : g1) hit += contains(l, ",hit,");
        TEST_ASSERT_MSG(g1 == g2 && g1.size() > 300 && hit > 100, "geoloc over the set: %zu rows (%zu hits) vs %zu",
                        g1.size(), hit, g2.size());
        fs::remove(d + "/px.csv");
        fs::remove(d + "/g_one.csv");
        fs::remove(d + "/g_set.csv");
    }

    // failures: nothing written, nothing left behind
    fs::create_directory(d + "/notaset");
    spit(d + "/notaset/keep.txt", "keep");
    const std::set<std::string> before = listing(d);
    runs = run_all({
        Job{d, {"build", "missing.tif", "-o", "set2", "--tile-size", "129"}},
        Job{d, {"build", fixture_dem(), "-o", "notaset", "--tile-size", "129"}},
        Job{d, {"build", fixture_dem(), "-o", "set3", "--tile-size", "1"}},
        Job{d, {"trace", "one.ctp", "--rays", "rays.csv", "--cache-tiles", "2", "-o", "x.csv"}},
        Job{d, {"trace", "set", "--rays", "rays.csv", "--cache-tiles", "0", "-o", "x.csv"}},
    });
    CHECK_FAILURE(runs[0], d, before, "missing.tif");
    CHECK_FAILURE(runs[1], d, before, "notaset", "not a tile set");
    CHECK_FAILURE(runs[2], d, before, "", "--tile-size", true);
    CHECK_FAILURE(runs[3], d, before, "", "--cache-tiles", true);
    CHECK_FAILURE(runs[4], d, before, "", "--cache-tiles", true);
    TEST_ASSERT(listing(d + "/notaset") == std::set<std::string>{"keep.txt"});
    // rebuilding over an existing set replaces it whole
    Run again = run_cli(d, {"build", fixture_dem(), "-o", "set", "--tile-size", "200", "--reduce", "3"});
    TEST_ASSERT_MSG(again.code == 0, "rebuild: %s", again.err.c_str());
    TEST_ASSERT_EQUAL_INT(7, (int)listing(d + "/set").size());  // 3 x 2 tiles and the manifest
    TEST_ASSERT_MSG(listing(d) == before, "scratch files left beside the set: {%s}", join(listing(d)).c_str());
}

// ---------------------------------------------------------------------------
// 7. a DEM beyond one tile set's frame (33,000 x 33,000 posts, 2.2 GB of
// int16 heights: past the one-package limit of 32,768 posts, and its last
// row and column of tiles partial): a plain build refuses it from the header; build
// --tile-size streams it into a mosaic of tile sets, read to its end, whose
// manifests and posts are checked

// The generated heights: TIFF tile (I, J) of 512 x 512 posts holds
// 100 + (u + 2 v) % 97 + 10 ((I + 3 J) % 7) at (u, v) in it -- seven
// distinct tiles, each deflated once and written as often as it occurs.
static const int kBigW = 33000, kWideW = 40000, kBigTile = 512;
static int big_height(int i, int j)
{
    const int u = i % kBigTile, v = j % kBigTile, I = i / kBigTile, J = j / kBigTile;
    return 100 + (u + 2 * v) % 97 + 10 * ((I + 3 * J) % 7);
}

static std::string write_big_tiff(const std::string &path, int width = kBigW, int height = kBigW)
{
    TIFF *t = XTIFFOpen(path.c_str(), "w");
    if (!t) return "cannot open " + path;
    const double scale[3] = {30.0, 30.0, 0.0}, tie[6] = {0, 0, 0, sOE, sON, 0};
    bool ok = TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)width) && TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)height) &&
              TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1) && TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, (uint16_t)16) &&
              TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, (uint16_t)SAMPLEFORMAT_INT) &&
              TIFFSetField(t, TIFFTAG_PHOTOMETRIC, (uint16_t)PHOTOMETRIC_MINISBLACK) &&
              TIFFSetField(t, TIFFTAG_PLANARCONFIG, (uint16_t)PLANARCONFIG_CONTIG) &&
              TIFFSetField(t, TIFFTAG_COMPRESSION, (uint16_t)COMPRESSION_ADOBE_DEFLATE) &&
              TIFFSetField(t, TIFFTAG_TILEWIDTH, (uint32_t)kBigTile) && TIFFSetField(t, TIFFTAG_TILELENGTH, (uint32_t)kBigTile) &&
              TIFFSetField(t, TIFFTAG_GEOPIXELSCALE, (uint16_t)3, scale) && TIFFSetField(t, TIFFTAG_GEOTIEPOINTS, (uint16_t)6, tie);
    GTIF *gt = ok ? GTIFNew(t) : nullptr;
    ok = gt && GTIFKeySet(gt, GTModelTypeGeoKey, TYPE_SHORT, 1, (int)ModelTypeProjected) &&
         GTIFKeySet(gt, GTRasterTypeGeoKey, TYPE_SHORT, 1, (int)RasterPixelIsArea) &&
         GTIFKeySet(gt, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, 32617) && GTIFWriteKeys(gt);
    if (gt) GTIFFree(gt);
    // the seven tiles, deflated
    std::vector<std::vector<unsigned char>> z(7);
    for (int k = 0; k < 7 && ok; ++k) {
        std::vector<int16_t> px((size_t)kBigTile * kBigTile);
        for (int v = 0; v < kBigTile; ++v)
            for (int u = 0; u < kBigTile; ++u) px[(size_t)v * kBigTile + u] = (int16_t)(100 + (u + 2 * v) % 97 + 10 * k);
        uLongf n = compressBound((uLong)(px.size() * 2));
        z[k].resize(n);
        ok = compress2(z[k].data(), &n, (const Bytef *)px.data(), (uLong)(px.size() * 2), 6) == Z_OK;
        z[k].resize(n);
    }
    const int ntx = (width + kBigTile - 1) / kBigTile, nty = (height + kBigTile - 1) / kBigTile;
    for (int J = 0; J < nty && ok; ++J)
        for (int I = 0; I < ntx && ok; ++I) {
            const std::vector<unsigned char> &b = z[(I + 3 * J) % 7];
            ok = TIFFWriteRawTile(t, TIFFComputeTile(t, (uint32_t)(I * kBigTile), (uint32_t)(J * kBigTile), 0, 0),
                                  (void *)b.data(), (tmsize_t)b.size()) == (tmsize_t)b.size();
        }
    XTIFFClose(t);
    return ok ? "" : "libtiff failed writing " + path;
}

static uint32_t le16(const std::string &b, size_t o) { return (uint8_t)b[o] | (uint32_t)(uint8_t)b[o + 1] << 8; }

static void test_big_dem(void)
{
    std::string d = new_dir("bigdem");
    auto t0 = std::chrono::steady_clock::now();
    const std::string w = write_big_tiff(d + "/big.tif");
    TEST_ASSERT_MSG(w.empty(), "%s", w.c_str());
    auto secs = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    printf("  big.tif: %d x %d posts, %.1f MB, written in %.1f s\n", kBigW, kBigW, fs::file_size(d + "/big.tif") / 1e6,
           secs());
    // one package: refused from the header, naming the DEM and the way out
    std::set<std::string> before = listing(d);
    Run r = run_cli(d, {"build", "big.tif", "-o", "X.ctp", "--sectors", "1", "--reduce", "8"});
    CHECK_FAILURE(r, d, before, "big.tif", "exceeds the package limit of 32768");
    TEST_ASSERT_MSG(contains(r.err, "--tile-size"), "the refusal suggests --tile-size: %s", r.err.c_str());
    // more memory than any machine has (a band of 32,768 rows, 64 tiles of 32,768^2 at once): refused first
    r = run_cli(d, {"build", "big.tif", "-o", "mosaic", "--tile-size", "32768", "--threads", "64"});
    CHECK_FAILURE(r, d, before, "big.tif", "available");
    // more disk than the output's file system has (none: /proc): refused first too
    r = run_cli(d, {"build", "big.tif", "-o", "/proc/ct_mosaic", "--tile-size", "4097", "--sectors", "1", "--reduce", "8"});
    CHECK_FAILURE(r, d, before, "/proc/ct_mosaic", "free");
    // tiles of 4,097 posts: 9 x 9 of them (the last of 232), in 2 x 2 tile
    // sets of at most 7 x 7
    t0 = std::chrono::steady_clock::now();
    r = run_cli(d, {"build", "big.tif", "-o", "mosaic", "--tile-size", "4097", "--sectors", "1", "--reduce", "8",
                    "--slices", "2", "--window", "1"});
    printf("  build --tile-size 4097: %.1f s; %s", secs(), r.out.c_str());
    TEST_ASSERT_MSG(r.code == 0, "build: %s", r.err.c_str());
    TEST_ASSERT_MSG(contains(r.out, "mosaic of 2 x 2 tile sets") && contains(r.out, "9 x 9 tiles of 4097 posts"),
                    "summary: %s", r.out.c_str());
    TEST_ASSERT_MSG(listing(d) == (std::set<std::string>{"big.tif", "mosaic"}), "left beside: {%s}", join(listing(d)).c_str());
    TEST_ASSERT_MSG(listing(d + "/mosaic") == (std::set<std::string>{"set_0_0", "set_0_1", "set_1_0", "set_1_1"}),
                    "mosaic: {%s}", join(listing(d + "/mosaic")).c_str());
    // each set's manifest: its grid and merged size (7 tiles of 4,096 cells, then 2 for the last 4,327)
    const int tiles[2] = {7, 2}, posts[2] = {7 * 4096 + 1, kBigW - 7 * 4096};
    for (int by = 0; by < 2; ++by)
        for (int bx = 0; bx < 2; ++bx) {
            const std::string sd = d + "/mosaic/set_" + std::to_string(bx) + "_" + std::to_string(by);
            const std::string m = slurp(sd + "/manifest.ctm");
            TEST_ASSERT_MSG(m.size() >= 96 && m.compare(0, 4, "CTTS") == 0, "%s: not a manifest", sd.c_str());
            TEST_ASSERT_EQUAL_INT(tiles[bx], (int)le16(m, 16));
            TEST_ASSERT_EQUAL_INT(tiles[by], (int)le16(m, 18));
            TEST_ASSERT_EQUAL_INT(4097, (int)le16(m, 20));
            TEST_ASSERT_EQUAL_INT(posts[bx], (int)le16(m, 24));
            TEST_ASSERT_EQUAL_INT(posts[by], (int)le16(m, 26));
            TEST_ASSERT_EQUAL_INT(tiles[bx] * tiles[by] + 1, (int)listing(sd).size());
        }
    // posts: vertical rays onto posts of every set (corners, seams, the
    // DEM's last row and column) hit the generated heights exactly
    ct_rng rng;
    ct_rng_seed(&rng, 40000);
    std::vector<std::pair<int, int>> pts = {{0, 0},         {32999, 32999}, {28672, 28672}, {28672, 0},
                                            {32999, 0},     {0, 32999},     {28671, 28673}, {4096, 4096},
                                            {12345, 32123}, {32123, 12345}};
    for (int k = 0; k < 30; ++k)
        pts.push_back({(int)(ct_rng_unit(&rng) * (kBigW - 1)), (int)(ct_rng_unit(&rng) * (kBigW - 1))});
    std::string rays[2][2];
    std::vector<std::pair<int, int>> in_set[2][2];
    for (const auto &p : pts) {
        const int bx = p.first > 28672 ? 1 : 0, by = p.second > 28672 ? 1 : 0;
        char line[200];
        snprintf(line, sizeof line, "%.3f,%.3f,2000,0,0,-1\n", sOE + (p.first + 0.5) * 30.0, sON - (p.second + 0.5) * 30.0);
        rays[bx][by] += line;
        in_set[bx][by].push_back(p);
    }
    std::vector<Job> jobs;
    for (int by = 0; by < 2; ++by)
        for (int bx = 0; bx < 2; ++bx) {
            const std::string n = std::to_string(bx) + "_" + std::to_string(by);
            spit(d + "/rays_" + n + ".csv", "E,N,h,dE,dN,dh\n" + rays[bx][by]);
            jobs.push_back(Job{d, {"trace", "mosaic/set_" + n, "--rays", "rays_" + n + ".csv", "-o", "hits_" + n + ".csv"}});
        }
    jobs.push_back(Job{d, {"info", "mosaic"}});
    jobs.push_back(Job{d, {"trace", "mosaic", "--rays", "rays_0_0.csv", "-o", "hits.csv"}});
    std::vector<Run> runs = run_all(jobs);
    size_t checked = 0;
    for (int by = 0; by < 2; ++by)
        for (int bx = 0; bx < 2; ++bx) {
            const Run &tr = runs[(size_t)by * 2 + bx];
            TEST_ASSERT_MSG(tr.code == 0, "`%s`: %s", tr.cmd.c_str(), tr.err.c_str());
            const std::string n = std::to_string(bx) + "_" + std::to_string(by);
            const std::vector<std::string> hl = lines_of(slurp(d + "/hits_" + n + ".csv"));
            TEST_ASSERT_EQUAL_INT((int)in_set[bx][by].size() + 1, (int)hl.size());
            for (size_t k = 0; k < in_set[bx][by].size(); ++k) {
                const auto &p = in_set[bx][by][k];
                double e = 0, nn = 0, h = 0;
                char status[32] = "";
                TEST_ASSERT_MSG(sscanf(hl[k + 1].c_str(), "%31[^,],%lf,%lf,%lf", status, &e, &nn, &h) == 4 &&
                                    std::string(status) == "hit" && std::fabs(h - big_height(p.first, p.second)) < 1e-6,
                                "post (%d, %d) in set %s: '%s', expected h %d", p.first, p.second, n.c_str(),
                                hl[k + 1].c_str(), big_height(p.first, p.second));
                checked++;
            }
        }
    TEST_ASSERT_EQUAL_INT((int)pts.size(), (int)checked);
    const Run &info = runs[4];
    TEST_ASSERT_MSG(info.code == 0 && contains(info.out, "2 x 2 tile sets"), "info: %d %s %s", info.code,
                    info.out.c_str(), info.err.c_str());
    size_t ok = 0, pos = 0;
    while ((pos = info.out.find("verify        ok", pos)) != std::string::npos) ok++, pos++;
    TEST_ASSERT_MSG(ok == 4, "info verifies every set: %s", info.out.c_str());
    TEST_ASSERT_MSG(runs[5].code != 0 && runs[5].err_lines.size() == 1 && contains(runs[5].err, "mosaic") &&
                        contains(runs[5].err, "set_0_0") && !fs::exists(d + "/hits.csv"),
                    "trace over the whole mosaic: %d %s", runs[5].code, runs[5].err.c_str());
    fs::remove_all(d);  // ~3 GB
}

// ---------------------------------------------------------------------------
// interrupted builds (SIGINT, SIGTERM): the temporaries removed, one line
// naming the output, the process ended by the signal

// `conetrace ARGS` started in `dir` (fork + exec: its pid), sent `sig` once
// ready(dir) holds (polled every 5 ms) and `delay_s` more have passed.
// *why: what went wrong ("" if the signal was sent while it ran).
static Run run_interrupted(const std::string &dir, const std::vector<std::string> &args, int sig,
                           const std::function<bool(const std::string &)> &ready, double delay_s, std::string *why)
{
    Run r;
    r.cmd = "conetrace";
    for (const auto &a : args) r.cmd += " " + a;
    const std::string fo = g_root + "/stdout.int", fe = g_root + "/stderr.int";
    std::vector<std::string> argv_s = {CT_CLI};
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    std::vector<char *> argv;
    for (auto &a : argv_s) argv.push_back(&a[0]);
    argv.push_back(nullptr);
    fflush(stdout);
    const pid_t pid = fork();
    if (pid == 0) {
        // as from a terminal: the signals' default actions, none blocked
        // (ctest or a shell may start us with SIGINT ignored)
        signal(SIGINT, SIG_DFL);
        signal(SIGTERM, SIG_DFL);
        sigset_t none;
        sigemptyset(&none);
        sigprocmask(SIG_SETMASK, &none, nullptr);
        const int o = open(fo.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), e = open(fe.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        const int in = open("/dev/null", O_RDONLY);
        if (o < 0 || e < 0 || in < 0 || chdir(dir.c_str()) != 0) _exit(126);
        dup2(in, 0);
        dup2(o, 1);
        dup2(e, 2);
        execv(CT_CLI, argv.data());
        _exit(127);
    }
    *why = pid < 0 ? "fork failed" : "";
    int st = 0;
    bool sent = false;
    const auto t0 = std::chrono::steady_clock::now();
    auto secs = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    while (pid > 0) {
        const pid_t w = waitpid(pid, &st, sent ? 0 : WNOHANG);
        if (w == pid) break;
        if (secs() > 120) {
            kill(pid, SIGKILL);
            waitpid(pid, &st, 0);
            *why = "not ready after 120 s";
            break;
        }
        if (!sent && ready(dir)) {
            std::this_thread::sleep_for(std::chrono::duration<double>(delay_s));
            kill(pid, sig);
            sent = true;
            continue;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (pid > 0 && !sent && why->empty()) *why = "ended before it was interrupted";
    r.code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
    r.out = slurp(fo);
    r.err = slurp(fe);
    for (const std::string &l : lines_of(r.err))
        if (l.compare(0, 24, "libgcov profiling error:") != 0) r.err_lines.push_back(l);
    if (verbose()) printf("  $ %s  (signal %d after %.2f s) -> %d\n%s", r.cmd.c_str(), sig, secs(), r.code, r.err.c_str());
    return r;
}

// An entry of `dir` whose name starts with `prefix`, "" if none.
static std::string entry_starting(const std::string &dir, const std::string &prefix)
{
    for (const std::string &n : listing(dir))
        if (starts_with(n, prefix)) return n;
    return "";
}

static void test_interrupt(void)
{
    std::string why;
    // a package (r = 1, 64 sectors, one thread: ~12 s) with an earlier one
    // in its place: SIGTERM once its temporary is being written
    std::string d = new_dir("interrupt_pkg");
    spit(d + "/X.ctp", "an earlier output");
    std::set<std::string> before = listing(d);
    Run r = run_interrupted(d, {"build", fixture_dem(), "-o", "X.ctp", "--reduce", "1", "--sectors", "64", "--threads", "1"},
                            SIGTERM, [](const std::string &dir) { return !entry_starting(dir, "X.ctp.tmp-").empty(); },
                            0.3, &why);
    TEST_ASSERT_MSG(why.empty(), "`%s`: %s", r.cmd.c_str(), why.c_str());
    TEST_ASSERT_MSG(r.code == 128 + SIGTERM, "`%s`: ended by SIGTERM, got code %d: %s", r.cmd.c_str(), r.code, r.err.c_str());
    TEST_ASSERT_MSG(listing(d) == before, "left: {%s}", join(listing(d)).c_str());
    TEST_ASSERT_MSG(slurp(d + "/X.ctp") == "an earlier output", "the earlier X.ctp changed");
    TEST_ASSERT_MSG(!r.err_lines.empty() && r.err_lines.back() == "conetrace: interrupted by SIGTERM: X.ctp not written "
                                                                  "(its temporaries removed)",
                    "stderr: %s", r.err.c_str());

    // a mosaic (a DEM of 40,000 x 1,024 posts, 79 x 2 tiles of 513, ~3 s):
    // SIGINT once its first tiles are written in "mosaic.tmp.<pid>/"
    d = new_dir("interrupt_mosaic");
    const std::string w = write_big_tiff(d + "/wide.tif", kWideW, 2 * kBigTile);
    TEST_ASSERT_MSG(w.empty(), "%s", w.c_str());
    before = listing(d);
    r = run_interrupted(d, {"build", "wide.tif", "-o", "mosaic", "--tile-size", "513", "--sectors", "1", "--reduce", "8",
                            "--slices", "2", "--window", "1", "--threads", "2"},
                        SIGINT,
                        [](const std::string &dir) {
                            const std::string tmp = entry_starting(dir, "mosaic.tmp.");
                            std::error_code ec;
                            if (tmp.empty()) return false;
                            for (const auto &e : fs::recursive_directory_iterator(dir + "/" + tmp, ec))
                                if (starts_with(e.path().filename().string(), "tile_")) return true;
                            return false;
                        },
                        0.2, &why);
    TEST_ASSERT_MSG(why.empty(), "`%s`: %s", r.cmd.c_str(), why.c_str());
    TEST_ASSERT_MSG(r.code == 128 + SIGINT, "`%s`: ended by SIGINT, got code %d: %s", r.cmd.c_str(), r.code, r.err.c_str());
    TEST_ASSERT_MSG(listing(d) == before, "left: {%s} (no mosaic, no mosaic.tmp.*)", join(listing(d)).c_str());
    TEST_ASSERT_MSG(!r.err_lines.empty() && r.err_lines.back() == "conetrace: interrupted by SIGINT: mosaic not written "
                                                                  "(its temporaries removed)",
                    "stderr: %s", r.err.c_str());
    if (!getenv("CT_TEST_KEEP")) fs::remove_all(d);
}

// ---------------------------------------------------------------------------

// `test_cli`: every test but the big DEM's and the interrupted builds';
// `test_cli bigdem`, `test_cli interrupt`: those (their own CTest entries,
// test_cli_bigdem with the label "bigdem").
int main(int argc, char **argv)
{
    const bool big = argc > 1 && std::strcmp(argv[1], "bigdem") == 0;
    const bool interrupt = argc > 1 && std::strcmp(argv[1], "interrupt") == 0;
    TEST_BEGIN(big ? "test_cli bigdem" : interrupt ? "test_cli interrupt" : "test_cli");
    char tmpl[] = "/tmp/ct_test_cli_XXXXXX";
    if (!mkdtemp(tmpl)) {
        printf("test_cli: mkdtemp failed\n");
        return 1;
    }
    g_root = tmpl;
    if (access(CT_CLI, X_OK) != 0) {
        printf("test_cli: %s is not executable\n", CT_CLI);
        return 1;
    }
    load_fixture();
    if (big) {
        RUN_TEST(test_big_dem);
    } else if (interrupt) {
        RUN_TEST(test_interrupt);
    } else {
        RUN_TEST(test_light_start);
        RUN_TEST(test_help);
        RUN_TEST(test_build_info_fixture);
        RUN_TEST(test_trace_methods);
        RUN_TEST(test_nodata_policy);
        RUN_TEST(test_bad_inputs);
        RUN_TEST(test_bad_rows);
        RUN_TEST(test_failed_run_keeps_output);
        RUN_TEST(test_tile_sets);
    }
    int rc = TEST_END();
    if (getenv("CT_TEST_KEEP"))
        printf("scratch directory kept: %s\n", g_root.c_str());
    else
        fs::remove_all(g_root);
    return rc;
}
