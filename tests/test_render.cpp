// test_render.cpp -- `conetrace render` end to end: runs the real binary,
// reads the PNGs back with OpenImageIO and checks what they show against
// independent references computed here from the raw DEM samples (read_dem)
// and the raw package bytes:
//  - sizes and the documented panel layout;
//  - bitmap: exactly the cells whose tallest corner (max over r x r cells)
//    is at or above the level, from the metres in the file;
//  - dt / ddt on small generated DEMs vs a brute-force Euclidean (directional)
//    DT: infinity <=> the "none" colour, distance 0 <=> the palette's first
//    colour, pixels in the same colour bin (index round(255 d / R)) share a
//    colour, different bins differ, and luminance grows with the distance;
//  - on the real fixture: features have the zero colour in dt and in every
//    ddt panel, no dt pixel is "none", and every ddt pixel is "none" exactly
//    when the sector's rays leave the tile without meeting a feature
//    (checked on a sample of pixels by brute force);
//  - angles: code 0 <=> "none", equal codes share a colour, luminance grows
//    with the code; apex: grey, linear in the apex code from 0 to 255;
//  - errors: one line naming the file, non-zero exit, no output file and no
//    temporary left behind, an existing output untouched.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "conetrace.h"
#include "dem_io.hpp"
#include "harness.h"

namespace fs = std::filesystem;

static std::string g_dir;
static const std::string kFixture = std::string(CT_FIXTURES_DIR) + "/jacksboro_fault_dem.tif";
static const int GAP = 8, STRIP = 28;  // documented in cmd_render.cpp

struct Rgb {
    int r = 0, g = 0, b = 0;
    bool operator==(const Rgb &o) const { return r == o.r && g == o.g && b == o.b; }
    bool operator!=(const Rgb &o) const { return !(*this == o); }
    bool operator<(const Rgb &o) const { return r != o.r ? r < o.r : g != o.g ? g < o.g : b < o.b; }
    double lum() const { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }
};
static const Rgb kNone{200, 200, 200}, kZero{68, 1, 84}, kTop{253, 231, 37}, kFeature{38, 38, 46},
    kWhite{255, 255, 255};

struct Png {
    int w = 0, h = 0, ch = 0;
    std::vector<uint8_t> px;
    Rgb at(int x, int y) const
    {
        const uint8_t *p = &px[((size_t)y * w + x) * ch];
        return Rgb{p[0], p[1], p[2]};
    }
};

static bool read_png(const std::string &path, Png &out)
{
    auto in = OIIO::ImageInput::open(path);
    if (!in) return false;
    const OIIO::ImageSpec &s = in->spec();
    out.w = s.width, out.h = s.height, out.ch = s.nchannels;
    out.px.resize((size_t)out.w * out.h * out.ch);
    bool ok = s.nchannels >= 3 && in->read_image(0, 0, 0, -1, OIIO::TypeDesc::UINT8, out.px.data());
    in->close();
    return ok && std::string(in->format_name()) == "png";
}

struct Run {
    int code = -1;
    std::string out, err;
};

static std::string quote(const std::string &s)
{
    std::string r = "'";
    for (char c : s) r += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return r + "'";
}

static std::string slurp(const std::string &p)
{
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

static Run run(const std::vector<std::string> &args, const std::string &dir = g_dir)
{
    // `conetrace render ARGS`, or `conetrace build ...` when args[0] is "build"
    std::string cmd = "cd " + quote(dir) + " && exec " + quote(CT_CLI) + (args[0] == "build" ? "" : " render");
    for (const auto &a : args) cmd += " " + quote(a);
    cmd += " </dev/null >" + quote(g_dir + "/../out.txt") + " 2>" + quote(g_dir + "/../err.txt");
    Run r;
    int st = std::system(cmd.c_str());
    r.code = st != -1 && WIFEXITED(st) ? WEXITSTATUS(st) : 128;
    r.out = slurp(g_dir + "/../out.txt");
    r.err = slurp(g_dir + "/../err.txt");
    if (getenv("CT_TEST_VERBOSE")) printf("  $ conetrace ... -> %d\n%s%s", r.code, r.out.c_str(), r.err.c_str());
    return r;
}

static std::set<std::string> listing(const std::string &d)
{
    std::set<std::string> s;
    for (const auto &e : fs::directory_iterator(d)) s.insert(e.path().filename().string());
    return s;
}

// ------------------------------------------------------------ references
struct Dem {
    int w = 0, h = 0;      // posts
    std::vector<double> z;  // metres
    double at(int i, int j) const { return z[(size_t)j * w + i]; }
};

static Dem load(const std::string &path)
{
    ct_host::DemRaster r = ct_host::read_dem(path);
    return Dem{r.width, r.height, r.h};
}

// Coarse cells: top = max of the posts of its r x r fine cells; feature iff
// top >= level (metres).
static std::vector<uint8_t> ref_bitmap(const Dem &d, int r, double level, int &wc, int &hc)
{
    int cx = d.w - 1, cy = d.h - 1;
    wc = (cx + r - 1) / r, hc = (cy + r - 1) / r;
    std::vector<uint8_t> b((size_t)wc * hc, 0);
    for (int cj = 0; cj < hc; ++cj)
        for (int ci = 0; ci < wc; ++ci) {
            double top = -1e300;
            for (int j = cj * r; j <= std::min(cy, (cj + 1) * r); ++j)
                for (int i = ci * r; i <= std::min(cx, (ci + 1) * r); ++i) top = std::max(top, d.at(i, j));
            b[(size_t)cj * wc + ci] = top >= level;
        }
    return b;
}

// Sector s of N as the closed wedge between boundary vectors (the library's
// documented convention), tested with exact 128-bit cross products.
static bool in_sector(int n, int s, long dx, long dy)
{
    if (n == 1 || (dx == 0 && dy == 0)) return true;
    int32_t ax, ay, bx, by;
    ct_sector_boundary((uint32_t)n, (uint32_t)s, &ax, &ay);
    ct_sector_boundary((uint32_t)n, (uint32_t)s + 1, &bx, &by);
    __int128 c0 = (__int128)ax * dy - (__int128)ay * dx, c1 = (__int128)dx * by - (__int128)dy * bx;
    return c0 >= 0 && c1 >= 0;
}

// Brute-force DT: squared Euclidean distance to the nearest feature (in the
// sector if n > 0), -1 = none.
static std::vector<long> brute_dt(const std::vector<uint8_t> &b, int w, int h, int n, int s)
{
    std::vector<long> d((size_t)w * h, -1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            long best = -1;
            for (int v = 0; v < h; ++v)
                for (int u = 0; u < w; ++u)
                    if (b[(size_t)v * w + u] && (n == 0 || in_sector(n, s, u - x, v - y))) {
                        long q = (long)(u - x) * (u - x) + (long)(v - y) * (v - y);
                        if (best < 0 || q < best) best = q;
                    }
            d[(size_t)y * w + x] = best;
        }
    return d;
}

// A panel of a PNG against reference distances (squared, -1 = none) with the
// colour scale 0..R: see the header comment.
static void check_distance_panel(const Png &p, int x0, int y0, int w, int h, const std::vector<long> &d2, double R,
                                 const char *what)
{
    std::map<int, Rgb> bin_colour;
    std::map<Rgb, int> colour_bin;
    std::vector<std::pair<double, double>> dl;  // (distance, luminance)
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            long q = d2[(size_t)y * w + x];
            Rgb c = p.at(x0 + x, y0 + y);
            if (q < 0) {
                TEST_ASSERT_MSG(c == kNone, "%s: pixel (%d,%d) has no feature but colour (%d,%d,%d)", what, x, y, c.r,
                                c.g, c.b);
                continue;
            }
            TEST_ASSERT_MSG(c != kNone, "%s: pixel (%d,%d) at distance^2 %ld shows 'none'", what, x, y, q);
            if (q == 0)
                TEST_ASSERT_MSG(c == kZero, "%s: feature pixel (%d,%d) colour (%d,%d,%d)", what, x, y, c.r, c.g, c.b);
            double dist = std::sqrt((double)q);
            int bin = (int)std::lround(std::min(1.0, dist / R) * 255.0);
            if (bin >= 255) TEST_ASSERT_MSG(c == kTop, "%s: pixel (%d,%d) beyond the range is not the top colour", what, x, y);
            auto it = bin_colour.find(bin);
            if (it == bin_colour.end()) {
                bin_colour[bin] = c;
                auto jt = colour_bin.find(c);
                TEST_ASSERT_MSG(jt == colour_bin.end(), "%s: bins %d and %d share a colour", what, bin,
                                jt == colour_bin.end() ? -1 : jt->second);
                colour_bin[c] = bin;
            } else {
                TEST_ASSERT_MSG(it->second == c, "%s: pixel (%d,%d) distance %.3f: colour differs within bin %d", what,
                                x, y, dist, bin);
            }
            dl.push_back({dist, c.lum()});
        }
    // luminance nondecreasing with the distance (1 unit of rounding slack)
    std::sort(dl.begin(), dl.end());
    double run_max = -1;
    for (auto &e : dl) {
        TEST_ASSERT_MSG(e.second >= run_max - 1.0, "%s: luminance falls at distance %.3f", what, e.first);
        run_max = std::max(run_max, e.second);
    }
    TEST_ASSERT_MSG(bin_colour.size() >= 3, "%s: only %zu distinct distance bins (test too weak)", what,
                    bin_colour.size());
}

// A small DEM: smooth hills plus a few spikes, int16 metres, 30 m posting.
static std::string write_small_dem(const std::string &name, int w, int h, uint64_t seed)
{
    ct_rng r;
    ct_rng_seed(&r, seed);
    double ph[4], fx[4], fy[4];
    for (int k = 0; k < 4; ++k)
        ph[k] = ct_rng_unit(&r) * 6.28, fx[k] = (ct_rng_unit(&r) - 0.5) * 0.8, fy[k] = (ct_rng_unit(&r) - 0.5) * 0.8;
    std::vector<double> z((size_t)w * h);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += std::sin(fx[k] * i + fy[k] * j + ph[k]) / (k + 1);
            z[(size_t)j * w + i] = std::round(500 + 100 * s);
        }
    for (int k = 0; k < 5; ++k) z[(size_t)ct_rng_range(&r, 0, h - 1) * w + ct_rng_range(&r, 0, w - 1)] = 800;
    ct_host::Georef g;
    g.origin_e = 500000, g.origin_n = 4000000, g.posting_e = 30, g.posting_n = -30, g.epsg = 32616;
    std::string path = g_dir + "/" + name;
    ct_host::write_geotiff(path, w, h, z, ct_host::SampleType::Int16, g);
    return path;
}

// ------------------------------------------------------------ tests
static void test_bitmap_fixture(void)
{
    Dem d = load(kFixture);
    for (int r : {1, 3}) {
        const double level = 656.5;  // int16 metres: no cell top equals it
        std::string out = "bitmap_r" + std::to_string(r) + ".png";
        Run k = run({kFixture, "--what", "bitmap", "--slice", "656.5", "--reduce", std::to_string(r), "-o", out,
                     "--no-legend"});
        TEST_ASSERT_MSG(k.code == 0, "render bitmap failed: %s", k.err.c_str());
        Png p;
        TEST_ASSERT(read_png(g_dir + "/" + out, p));
        int wc, hc;
        std::vector<uint8_t> b = ref_bitmap(d, r, level, wc, hc);
        TEST_ASSERT_EQUAL_INT(wc, p.w);
        TEST_ASSERT_EQUAL_INT(hc, p.h);
        size_t nf = 0;
        for (int y = 0; y < hc; ++y)
            for (int x = 0; x < wc; ++x) {
                Rgb c = p.at(x, y);
                bool f = b[(size_t)y * wc + x];
                nf += f;
                TEST_ASSERT_MSG(c == (f ? kFeature : kWhite), "r=%d cell (%d,%d): expected %s", r, x, y,
                                f ? "feature" : "free");
            }
        TEST_ASSERT(nf > 100 && nf < b.size() - 100);  // a real cross-section
    }
    // --level k --slices K: level k of K evenly spaced between the DEM's extremes
    Run k = run({kFixture, "--what", "bitmap", "--level", "40", "--slices", "80", "-o", "lvl.png", "--no-legend"});
    TEST_ASSERT_MSG(k.code == 0, "%s", k.err.c_str());
    double lo = *std::min_element(d.z.begin(), d.z.end()), hi = *std::max_element(d.z.begin(), d.z.end());
    double level = lo + 40.0 * (hi - lo) / 80.0;
    int wc, hc;
    std::vector<uint8_t> b = ref_bitmap(d, 1, level - 1e-6, wc, hc);
    Png p;
    TEST_ASSERT(read_png(g_dir + "/lvl.png", p));
    size_t bad = 0;
    for (int y = 0; y < hc; ++y)
        for (int x = 0; x < wc; ++x) bad += p.at(x, y) != (b[(size_t)y * wc + x] ? kFeature : kWhite);
    TEST_ASSERT_MSG(bad == 0, "--level 40 --slices 80 (%.3f m): %zu cells differ", level, bad);
}

static void test_dt_ddt_small_vs_brute(void)
{
    struct Case {
        int w, h, r;
        uint64_t seed;
        double level;
    };
    const Case cases[] = {{37, 29, 1, 11, 560.5}, {41, 23, 2, 12, 520.5}, {25, 33, 1, 13, 790.5}};
    for (const Case &c : cases) {
        std::string dem = write_small_dem("small" + std::to_string(c.seed) + ".tif", c.w, c.h, c.seed);
        Dem d = load(dem);
        int wc, hc;
        std::vector<uint8_t> b = ref_bitmap(d, c.r, c.level, wc, hc);
        const double R = 12.75;  // bins of 1/20 cell
        char lv[32];
        std::snprintf(lv, sizeof lv, "%.1f", c.level);
        // unconstrained
        Run k = run({dem, "--what", "dt", "--slice", lv, "--reduce", std::to_string(c.r), "--range", "0,12.75",
                     "--no-legend", "-o", "dt.png"});
        TEST_ASSERT_MSG(k.code == 0, "%s", k.err.c_str());
        Png p;
        TEST_ASSERT(read_png(g_dir + "/dt.png", p));
        TEST_ASSERT_EQUAL_INT(wc, p.w);
        TEST_ASSERT_EQUAL_INT(hc, p.h);
        char what[64];
        std::snprintf(what, sizeof what, "dt seed %llu", (unsigned long long)c.seed);
        check_distance_panel(p, 0, 0, wc, hc, brute_dt(b, wc, hc, 0, 0), R, what);
        // directional: all 8 sectors, and three of 24
        for (int n : {8, 24}) {
            std::vector<int> secs = n == 8 ? std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7} : std::vector<int>{0, 7, 17};
            std::string list;
            for (int s : secs) list += (list.empty() ? "" : ",") + std::to_string(s);
            Run q = run({dem, "--what", "ddt", "--slice", lv, "--reduce", std::to_string(c.r), "--sectors",
                         std::to_string(n), "--sector", list, "--columns", "3", "--range", "0,12.75", "--no-legend",
                         "-o", "ddt.png"});
            TEST_ASSERT_MSG(q.code == 0, "%s", q.err.c_str());
            Png pp;
            TEST_ASSERT(read_png(g_dir + "/ddt.png", pp));
            int np = (int)secs.size(), cols = 3, rows = (np + 2) / 3;
            TEST_ASSERT_EQUAL_INT(cols * wc + (cols - 1) * GAP, pp.w);
            TEST_ASSERT_EQUAL_INT(rows * (STRIP + hc) + (rows - 1) * GAP, pp.h);
            for (int k2 = 0; k2 < np; ++k2) {
                int x0 = (k2 % cols) * (wc + GAP), y0 = (k2 / cols) * (STRIP + hc + GAP) + STRIP;
                std::snprintf(what, sizeof what, "ddt seed %llu N=%d s=%d", (unsigned long long)c.seed, n, secs[(size_t)k2]);
                check_distance_panel(pp, x0, y0, wc, hc, brute_dt(b, wc, hc, n, secs[(size_t)k2]), R, what);
            }
        }
    }
}

static void test_dt_ddt_fixture(void)
{
    Dem d = load(kFixture);
    int wc, hc;
    std::vector<uint8_t> b = ref_bitmap(d, 1, 700.5, wc, hc);
    Run k = run({kFixture, "--what", "dt", "--slice", "700.5", "-o", "fdt.png"});
    TEST_ASSERT_MSG(k.code == 0, "%s", k.err.c_str());
    Png p;
    TEST_ASSERT(read_png(g_dir + "/fdt.png", p));
    TEST_ASSERT_EQUAL_INT(wc, p.w);
    TEST_ASSERT_EQUAL_INT(hc + 26, p.h);  // + the legend
    for (int y = 0; y < hc; ++y)
        for (int x = 0; x < wc; ++x) {
            Rgb c = p.at(x, y);
            TEST_ASSERT_MSG(c != kNone, "dt pixel (%d,%d) is 'none' but the section has features", x, y);
            TEST_ASSERT_MSG((c == kZero) == (bool)b[(size_t)y * wc + x], "dt pixel (%d,%d): zero colour iff feature",
                            x, y);
        }
    // ddt, 8 sectors, the paper's Fig. 11 style
    const int secs[3] = {0, 2, 5};
    Run q = run({kFixture, "--what", "ddt", "--slice", "700.5", "--sectors", "8", "--sector", "0,2,5", "--hillshade",
                 "-o", "fddt.png"});
    Run q2 = run({kFixture, "--what", "ddt", "--slice", "700.5", "--sectors", "8", "--sector", "0,2,5", "-o",
                  "fddt_plain.png"});
    TEST_ASSERT_MSG(q.code == 0 && q2.code == 0, "%s %s", q.err.c_str(), q2.err.c_str());
    Png h, pl;
    TEST_ASSERT(read_png(g_dir + "/fddt.png", h) && read_png(g_dir + "/fddt_plain.png", pl));
    TEST_ASSERT_EQUAL_INT(3 * wc + 2 * GAP, pl.w);
    TEST_ASSERT_EQUAL_INT(STRIP + hc + 26, pl.h);
    TEST_ASSERT(h.w == pl.w && h.h == pl.h);
    ct_rng rng;
    ct_rng_seed(&rng, 7);
    size_t shaded = 0, none = 0;
    for (int k2 = 0; k2 < 3; ++k2) {
        const int x0 = k2 * (wc + GAP), y0 = STRIP;
        for (int y = 0; y < hc; ++y)
            for (int x = 0; x < wc; ++x) {
                Rgb c = pl.at(x0 + x, y0 + y), cs = h.at(x0 + x, y0 + y);
                const bool f = b[(size_t)y * wc + x];
                TEST_ASSERT_MSG((c == kZero) == f, "ddt s=%d pixel (%d,%d): zero colour iff feature", secs[k2], x, y);
                // hillshade only darkens, by at most the documented 0.45 factor
                TEST_ASSERT(cs.r <= c.r && cs.g <= c.g && cs.b <= c.b);
                TEST_ASSERT(cs.r >= (int)(0.45 * c.r) - 1 && cs.g >= (int)(0.45 * c.g) - 1);
                shaded += cs != c;
                none += c == kNone;
            }
        // "none" exactly where no feature lies in the sector: brute force on a sample
        for (int t = 0; t < 300; ++t) {
            int x = (int)ct_rng_range(&rng, 0, wc - 1), y = (int)ct_rng_range(&rng, 0, hc - 1);
            bool any = false;
            for (int v = 0; v < hc && !any; ++v)
                for (int u = 0; u < wc && !any; ++u) any = b[(size_t)v * wc + u] && in_sector(8, secs[k2], u - x, v - y);
            TEST_ASSERT_MSG((pl.at(x0 + x, y0 + y) == kNone) == !any, "ddt s=%d pixel (%d,%d): 'none' iff no feature",
                            secs[k2], x, y);
        }
    }
    TEST_ASSERT(shaded > (size_t)wc * hc);
    TEST_ASSERT(none > 1000);  // Fig. 11's blank regions exist
}

static uint32_t rd32(const std::vector<uint8_t> &b, size_t o)
{
    return (uint32_t)b[o] | (uint32_t)b[o + 1] << 8 | (uint32_t)b[o + 2] << 16 | (uint32_t)b[o + 3] << 24;
}

static void test_angles_apex(void)
{
    Run bld = run({"build", kFixture, "-o", "p.ctp", "--sectors", "8", "--reduce", "4", "--slices", "40"});
    TEST_ASSERT_MSG(bld.code == 0, "%s", bld.err.c_str());
    std::vector<uint8_t> pkg;
    {
        std::ifstream f(g_dir + "/p.ctp", std::ios::binary);
        pkg.assign(std::istreambuf_iterator<char>(f), {});
    }
    TEST_ASSERT(pkg.size() > 128);
    // raw layout (conetrace.h): W, H at 16/18, r at 20, N at 21, section table at 88
    const int W = pkg[16] | pkg[17] << 8, H = pkg[18] | pkg[19] << 8, r = pkg[20], N = pkg[21];
    const int wc = (W - 1 + r - 1) / r, hc = (H - 1 + r - 1) / r;
    const size_t apex_off = rd32(pkg, 88 + 8 * 2), ang_off = rd32(pkg, 88 + 8 * 3), plane = (size_t)wc * hc;
    TEST_ASSERT_EQUAL_INT(8, N);
    // angles: planes 0, 5 and omni (= plane N)
    Run k = run({"p.ctp", "--what", "angles", "--sector", "0,5,omni", "--range", "0,180", "--zoom", "2",
                 "--no-legend", "-o", "ang.png"});
    TEST_ASSERT_MSG(k.code == 0, "%s", k.err.c_str());
    Png p;
    TEST_ASSERT(read_png(g_dir + "/ang.png", p));
    TEST_ASSERT_EQUAL_INT(3 * 2 * wc + 2 * GAP, p.w);
    TEST_ASSERT_EQUAL_INT(STRIP + 2 * hc, p.h);
    const int planes[3] = {0, 5, 8};
    std::map<int, Rgb> code_colour;
    std::vector<std::pair<int, double>> cl;
    size_t zeros = 0;
    for (int k2 = 0; k2 < 3; ++k2)
        for (int y = 0; y < hc; ++y)
            for (int x = 0; x < wc; ++x) {
                int code = pkg[ang_off + (size_t)planes[k2] * plane + (size_t)y * wc + x];
                for (int a = 0; a < 2; ++a)  // zoom 2: all four pixels of the cell
                    for (int bb = 0; bb < 2; ++bb) {
                        Rgb c = p.at(k2 * (2 * wc + GAP) + 2 * x + bb, STRIP + 2 * y + a);
                        TEST_ASSERT_MSG((c == kNone) == (code == 0), "angle plane %d cell (%d,%d) code %d", planes[k2],
                                        x, y, code);
                        if (code == 0) continue;
                        auto it = code_colour.find(code);
                        if (it == code_colour.end())
                            code_colour[code] = c;
                        else
                            TEST_ASSERT_MSG(it->second == c, "angle code %d shown in two colours", code);
                        cl.push_back({code, c.lum()});
                    }
                zeros += code == 0;
            }
    std::sort(cl.begin(), cl.end());
    for (size_t i = 1; i < cl.size(); ++i)
        TEST_ASSERT_MSG(cl[i].second >= cl[i - 1].second - 1.0, "angle luminance falls at code %d", cl[i].first);
    TEST_ASSERT(code_colour.size() >= 10);
    // apex: grey, linear from the lowest (0) to the highest apex (255)
    Run a = run({"p.ctp", "--what", "apex", "--no-legend", "-o", "apex.png"});
    TEST_ASSERT_MSG(a.code == 0, "%s", a.err.c_str());
    Png ap;
    TEST_ASSERT(read_png(g_dir + "/apex.png", ap));
    TEST_ASSERT_EQUAL_INT(wc, ap.w);
    TEST_ASSERT_EQUAL_INT(hc, ap.h);
    int amin = 65535, amax = 0;
    for (size_t i = 0; i < plane; ++i) {
        int v = pkg[apex_off + 2 * i] | pkg[apex_off + 2 * i + 1] << 8;
        amin = std::min(amin, v), amax = std::max(amax, v);
    }
    TEST_ASSERT(amax > amin);
    for (int y = 0; y < hc; ++y)
        for (int x = 0; x < wc; ++x) {
            size_t i = (size_t)y * wc + x;
            int v = pkg[apex_off + 2 * i] | pkg[apex_off + 2 * i + 1] << 8;
            Rgb c = ap.at(x, y);
            double expect = 255.0 * (v - amin) / (amax - amin);
            TEST_ASSERT_MSG(c.r == c.g && c.g == c.b && std::fabs(c.r - expect) <= 1.0,
                            "apex cell (%d,%d) code %d: grey %d, expected %.1f", x, y, v, c.r, expect);
        }
}

// A failed run: exit non-zero, one line naming `names`, nothing new in the
// directory (no output, no temporary), an existing output untouched.
static void expect_failure(const std::vector<std::string> &args, const std::string &names)
{
    auto before = listing(g_dir);
    std::string keep = slurp(g_dir + "/keep.png");
    Run k = run(args);
    TEST_ASSERT_MSG(k.code != 0, "expected failure for ... %s", names.c_str());
    TEST_ASSERT_MSG(std::count(k.err.begin(), k.err.end(), '\n') >= 1 && k.err.find("conetrace: ") == 0,
                    "stderr: %s", k.err.c_str());
    TEST_ASSERT_MSG(k.err.find(names) != std::string::npos, "error '%s' does not name '%s'", k.err.c_str(),
                    names.c_str());
    TEST_ASSERT_MSG(k.err.find("usage") != std::string::npos || std::count(k.err.begin(), k.err.end(), '\n') == 1,
                    "more than one line: %s", k.err.c_str());
    TEST_ASSERT_MSG(listing(g_dir) == before, "the directory changed after a failed run");
    TEST_ASSERT(slurp(g_dir + "/keep.png") == keep);
}

static void test_errors(void)
{
    Run k = run({kFixture, "--what", "bitmap", "--slice", "600", "-o", "keep.png"});
    TEST_ASSERT_MSG(k.code == 0, "%s", k.err.c_str());
    expect_failure({"nope.tif", "--what", "dt", "--slice", "600", "-o", "keep.png"}, "nope.tif");
    expect_failure({kFixture, "--what", "angles", "-o", "keep.png"}, "needs a package");
    expect_failure({kFixture, "--what", "ddt", "--slice", "600", "--sectors", "8", "--sector", "8", "-o", "keep.png"},
                   "--sector");
    expect_failure({kFixture, "--what", "dt", "-o", "keep.png"}, "--slice");
    expect_failure({kFixture, "--what", "dt", "--slice", "600", "--level", "3", "-o", "keep.png"}, "--level");
    expect_failure({kFixture, "--what", "heat", "--slice", "600", "-o", "keep.png"}, "heat");
    expect_failure({kFixture, "--what", "dt", "--slice", "600", "-o", "keep.jpg"}, "keep.jpg");
    expect_failure({kFixture, "--what", "dt", "--slice", "600", "--range", "5,5", "-o", "keep.png"}, "--range");
    expect_failure({kFixture, "--what", "apex", "--slice", "600", "-o", "keep.png"}, "--slice");
    expect_failure({kFixture, "--what", "dt", "--slice", "600", "-o", "no/such/dir/x.png"}, "no/such/dir/x.png");
    // a file that is not a DEM, a truncated package
    {
        std::ofstream(g_dir + "/junk.ctp") << "CTPK garbage";
    }
    expect_failure({"junk.ctp", "--what", "apex", "-o", "keep.png"}, "junk.ctp");
    // a DEM wider than a package may be (40,000 x 2 posts): refused from its
    // header, as build refuses it
    {
        ct_host::Georef g;  // 30 m posts by default
        g.origin_e = 500000, g.origin_n = 4000000, g.epsg = 32617;
        ct_host::write_geotiff(g_dir + "/wide.tif", 40000, 2, std::vector<double>(80000, 100.0),
                               ct_host::SampleType::Int16, g);
    }
    expect_failure({"wide.tif", "--what", "bitmap", "--slice", "100", "-o", "keep.png"}, "posts per side");
}

int main(void)
{
    TEST_BEGIN("test_render");
    char tmpl[] = "/tmp/ct_test_render_XXXXXX";
    if (!mkdtemp(tmpl)) {
        perror("mkdtemp");
        return 1;
    }
    g_dir = std::string(tmpl) + "/w";
    fs::create_directory(g_dir);
    RUN_TEST(test_bitmap_fixture);
    RUN_TEST(test_dt_ddt_small_vs_brute);
    RUN_TEST(test_dt_ddt_fixture);
    RUN_TEST(test_angles_apex);
    RUN_TEST(test_errors);
    if (!getenv("CT_TEST_KEEP")) fs::remove_all(tmpl);
    return TEST_END();
}
