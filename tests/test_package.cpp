// test_package.cpp -- the package format: good packages open and verify;
// every kind of corruption gets its own status code ("evil" inputs, in the
// spirit of littlefs's test_evil); random corruption never crashes, and a
// corrupted package that still opens never makes the tracer read outside
// the buffer (run under AddressSanitizer + UBSan as test_package_san).
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "builder_common.hpp"
#include "conetrace.h"
#include "dem_cases.hpp"
#include "harness.h"
#include "le.hpp"
#include "terrain.hpp"

namespace {

std::vector<uint8_t> base_package(int sectors = 8, int reduce = 2)
{
    auto z = dem_cases::smooth(29, 23, 5, 100, 9000);
    ct_host::Terrain t = dem_cases::make_terrain(29, 23, z, 0.5);
    ct_host::BuildOptions o;
    o.sectors = sectors;
    o.reduce = reduce;
    return ct_host::build_package(t, o);
}

using ct_host::get32;
using ct_host::put16;
using ct_host::put32;
using ct_host::put64;

// Recompute the CRC so a mutation reaches the check after the CRC.
void fix_crc(std::vector<uint8_t> &b)
{
    if (b.size() < 16) return;
    uint32_t total = get32(b, 8);
    if (total > b.size() || total < 16) return;
    put32(b, 12, 0);
    uint32_t c = 0;
    ct_crc32(0, b.data(), total, &c);
    put32(b, 12, c);
}

ct_status open_bytes(const std::vector<uint8_t> &b, size_t len)
{
    // copy into an exactly-sized heap buffer so ASan sees any overread
    std::vector<uint8_t> exact(b.begin(), b.begin() + (long)std::min(len, b.size()));
    ct_package p;
    uint8_t dummy = 0;
    return ct_package_open(&p, exact.empty() ? &dummy : exact.data(), exact.size());
}

void test_good_packages_open_and_verify()
{
    const int cfg[][2] = {{1, 1}, {2, 1}, {3, 2}, {8, 2}, {24, 3}, {64, 8}};
    for (auto &c : cfg) {
        std::vector<uint8_t> b = base_package(c[0], c[1]);
        ct_package p;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, b.data(), b.size()));
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_verify(&p));
        TEST_ASSERT_EQUAL_INT(c[0], p.sectors);
        TEST_ASSERT_EQUAL_INT(c[1], p.reduce);
        uint32_t sz = 0;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_size(29, 23, (uint32_t)c[1], (uint32_t)c[0], 0, &sz));
        TEST_ASSERT_EQUAL_INT(b.size(), sz);
        // a longer buffer is fine (the header's total size rules)
        std::vector<uint8_t> longer = b;
        longer.resize(b.size() + 100, 0xAB);
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, longer.data(), longer.size()));
    }
}

struct Evil {
    const char *name;
    ct_status expect;
    bool fixcrc;
    std::function<void(std::vector<uint8_t> &)> mutate;
    size_t len = 0;  // 0: the mutated buffer's size
};

void test_evil_packages()
{
    const std::vector<uint8_t> good = base_package();
    const size_t T = CT_HDR_SECTION_TABLE;
    std::vector<Evil> cases = {
        {"empty buffer", CT_ERR_TRUNCATED, false, [](std::vector<uint8_t> &) {}, 1},
        {"shorter than the header", CT_ERR_TRUNCATED, false, [](std::vector<uint8_t> &) {}, 100},
        {"truncated by one byte", CT_ERR_TRUNCATED, false, [](std::vector<uint8_t> &) {}, good.size() - 1},
        {"wrong magic", CT_ERR_MAGIC, true, [](std::vector<uint8_t> &b) { b[0] = 'X'; }},
        {"wrong version", CT_ERR_VERSION, true, [](std::vector<uint8_t> &b) { put16(b, 4, 2); }},
        {"wrong header size", CT_ERR_HEADER, true, [](std::vector<uint8_t> &b) { put16(b, 6, 64); }},
        {"total size past the buffer", CT_ERR_TRUNCATED, false,
         [](std::vector<uint8_t> &b) { put32(b, 8, (uint32_t)b.size() + 8); }},
        {"total size overflowing", CT_ERR_TRUNCATED, false, [](std::vector<uint8_t> &b) { put32(b, 8, 0xFFFFFFFFu); }},
        {"wrong CRC", CT_ERR_CRC, false, [](std::vector<uint8_t> &b) { b[b.size() / 2] ^= 0x10; }},
        {"CRC field flipped", CT_ERR_CRC, false, [](std::vector<uint8_t> &b) { b[12] ^= 1; }},
        {"width 1", CT_ERR_DIMS, true, [](std::vector<uint8_t> &b) { put16(b, 16, 1); }},
        {"width above the limit", CT_ERR_DIMS, true, [](std::vector<uint8_t> &b) { put16(b, 16, 40000); }},
        {"height 0", CT_ERR_DIMS, true, [](std::vector<uint8_t> &b) { put16(b, 18, 0); }},
        {"N = 0", CT_ERR_SECTORS, true, [](std::vector<uint8_t> &b) { b[21] = 0; }},
        {"N = 65", CT_ERR_SECTORS, true, [](std::vector<uint8_t> &b) { b[21] = 65; }},
        {"r = 0", CT_ERR_REDUCE, true, [](std::vector<uint8_t> &b) { b[20] = 0; }},
        {"r = 9", CT_ERR_REDUCE, true, [](std::vector<uint8_t> &b) { b[20] = 9; }},
        {"unknown flag", CT_ERR_FLAGS, true, [](std::vector<uint8_t> &b) { b[23] |= 0x80; }},
        {"sizes imply a different layout (more posts)", CT_ERR_SIZE, true, [](std::vector<uint8_t> &b) { put16(b, 16, 30); }},
        {"levels wrong", CT_ERR_LEVELS, true, [](std::vector<uint8_t> &b) { b[22] += 1; }},
        {"heights section size wrong", CT_ERR_SIZE, true, [T](std::vector<uint8_t> &b) { put32(b, T + 4, get32(b, T + 4) + 2); }},
        {"angles section size overflowing", CT_ERR_SIZE, true,
         [T](std::vector<uint8_t> &b) { put32(b, T + 8 * CT_SEC_ANGLES + 4, 0xFFFFFFF8u); }},
        {"offset past the end", CT_ERR_OFFSET, true,
         [T](std::vector<uint8_t> &b) { put32(b, T + 8 * CT_SEC_ANGLES, (uint32_t)b.size()); }},
        {"offset + size wrapping 32 bits", CT_ERR_OFFSET, true,
         [T](std::vector<uint8_t> &b) { put32(b, T + 8 * CT_SEC_APEX, 0xFFFFFF00u); }},
        {"offset misaligned", CT_ERR_OFFSET, true,
         [T](std::vector<uint8_t> &b) { put32(b, T + 8 * CT_SEC_MIPMAP, get32(b, T + 8 * CT_SEC_MIPMAP) + 2); }},
        {"offset inside the header", CT_ERR_OFFSET, true, [T](std::vector<uint8_t> &b) { put32(b, T, 64); }},
        {"sections overlapping", CT_ERR_OFFSET, true,
         [T](std::vector<uint8_t> &b) { put32(b, T + 8 * CT_SEC_APEX, get32(b, T + 8 * CT_SEC_MIPMAP)); }},
        {"hmin > hmax", CT_ERR_RANGE, true, [](std::vector<uint8_t> &b) { put16(b, 24, 60000); put16(b, 26, 10); }},
        {"zero posting", CT_ERR_GEOREF, true, [](std::vector<uint8_t> &b) { put64(b, 48, 0); }},
        {"non-square posting", CT_ERR_GEOREF, true, [](std::vector<uint8_t> &b) { put64(b, 56, -31000000000ll); }},
        {"negative height scale", CT_ERR_GEOREF, true, [](std::vector<uint8_t> &b) { put64(b, 72, -1); }},
        {"reserved field set", CT_ERR_FLAGS, true, [](std::vector<uint8_t> &b) { put32(b, 84, 7); }},
        {"32768 x 32768 posts, r 1, N 64: over 4 GB", CT_ERR_SIZE, true,
         [](std::vector<uint8_t> &b) { put16(b, 16, 32768); put16(b, 18, 32768); b[20] = 1; b[21] = 64; }},
        {"total size below the header", CT_ERR_TRUNCATED, false, [](std::vector<uint8_t> &b) { put32(b, 8, 64); }},
        {"zero posting north", CT_ERR_GEOREF, true, [](std::vector<uint8_t> &b) { put64(b, 56, 0); }},
        {"posting beyond 2^50 nm", CT_ERR_GEOREF, true,
         [](std::vector<uint8_t> &b) { put64(b, 48, (1ll << 50) + 1); put64(b, 56, -(1ll << 50) - 1); }},
        {"height scale beyond 2^46 nm", CT_ERR_GEOREF, true, [](std::vector<uint8_t> &b) { put64(b, 72, (1ll << 46) + 1); }},
        {"height scale 0", CT_ERR_GEOREF, true, [](std::vector<uint8_t> &b) { put64(b, 72, 0); }},
        {"origin east beyond 2^61 nm", CT_ERR_GEOREF, true, [](std::vector<uint8_t> &b) { put64(b, 32, (1ll << 61) + 1); }},
        {"origin north beyond 2^61 nm", CT_ERR_GEOREF, true, [](std::vector<uint8_t> &b) { put64(b, 40, -(1ll << 61) - 1); }},
        {"height offset beyond 2^61 nm", CT_ERR_GEOREF, true, [](std::vector<uint8_t> &b) { put64(b, 64, (1ll << 61) + 1); }},
    };
    for (auto &c : cases) {
        std::vector<uint8_t> b = good;
        c.mutate(b);
        if (c.fixcrc) fix_crc(b);
        size_t len = c.len ? c.len : b.size();
        ct_status st = open_bytes(b, len);
        TEST_ASSERT_MSG(st == c.expect, "%s: expected %d, got %d", c.name, c.expect, st);
    }
    // a height scale so fine against the posting (0.1 mm codes, 30 m
    // posts) that the prepared z unit reaches its coarsest, 2^CT_ZSHIFT_MAX
    // Q16 LSB; the package opens and traces as ever (a hit from above)
    {
        std::vector<uint8_t> b = good;
        put64(b, 72, 100000);
        fix_crc(b);
        ct_package q;
        TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&q, b.data(), b.size()));
        TEST_ASSERT_EQUAL_INT(CT_ZSHIFT_MAX, (int)q.zshift_max);
        const ct_ray down = {(int64_t)q.cells_x << 15, (int64_t)q.cells_y << 15, ((int64_t)q.hmax + 10) << 16, 3, 1, -(1 << 20)};
        ct_hit h;
        TEST_ASSERT_EQUAL_INT(CT_HIT, ct_trace(&q, &down, CT_METHOD_DIRECTIONAL, &h));
    }
    // NULL arguments
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_package_open(&p, nullptr, 100));
    TEST_ASSERT_EQUAL_INT(CT_ERR_ARG, ct_package_open(nullptr, good.data(), good.size()));
}

// Content that breaks an invariant but keeps the structure: opens, fails
// the deep check, and tracing stays in bounds.
void test_verify_catches_bad_content()
{
    std::vector<uint8_t> b = base_package();
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, b.data(), b.size()));
    size_t apex_off = (size_t)(p.apex - b.data());
    put16(b, apex_off, 0);  // apex below its cell
    fix_crc(b);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, b.data(), b.size()));
    TEST_ASSERT_EQUAL_INT(CT_ERR_VERIFY, ct_package_verify(&p));
    std::vector<uint8_t> c = base_package();
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, c.data(), c.size()));
    size_t mip_off = (size_t)(p.mip[1] - c.data());
    put16(c, mip_off, 0);
    fix_crc(c);
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, c.data(), c.size()));
    TEST_ASSERT_EQUAL_INT(CT_ERR_VERIFY, ct_package_verify(&p));
}

// Random corruption (with the CRC fixed so the structure checks are reached):
// open never crashes; if it opens, every method traces rays without reading
// outside the buffer (the sanitizer build checks the reads).
void test_random_corruption()
{
    const std::vector<uint8_t> good = base_package(5, 3);
    ct_rng r;
    ct_rng_seed(&r, ct_test_seed() + 99);
    int opened = 0;
    int iters = (int)(3000 * ct_test_scale());
    auto t = dem_cases::make_terrain(29, 23, dem_cases::smooth(29, 23, 5, 100, 9000), 0.5);
    for (int k = 0; k < iters; ++k) {
        std::vector<uint8_t> b = good;
        int flips = (int)ct_rng_range(&r, 1, 8);
        for (int f = 0; f < flips; ++f) {
            size_t pos = (size_t)ct_rng_range(&r, 0, (int64_t)b.size() - 1);
            if (k % 2) pos = (size_t)ct_rng_range(&r, 0, 127);  // half the time: the header
            b[pos] = (uint8_t)ct_rng_u64(&r);
        }
        if (k % 4 != 3) fix_crc(b);
        size_t len = b.size() - (k % 7 == 0 ? (size_t)ct_rng_range(&r, 0, 64) : 0);
        std::vector<uint8_t> exact(b.begin(), b.begin() + (long)len);
        ct_package p;
        ct_status st = ct_package_open(&p, exact.data(), exact.size());
        TEST_ASSERT(st <= 0);
        if (st != CT_OK) continue;
        opened++;
        ct_package_verify(&p);
        for (int q = 0; q < 20; ++q) {
            ct_ray ray = dem_cases::make_ray(t, (dem_cases::Family)(q % dem_cases::FAMILY_COUNT), &r);
            for (int m = 0; m < 4; ++m) {
                ct_hit h;
                ct_status s = ct_trace(&p, &ray, (ct_method)m, &h);
                TEST_ASSERT_MSG(s >= CT_ERR_RAY || s == CT_ERR_INTERNAL || s == CT_ERR_GEOREF || s == CT_ERR_RANGE,
                                "unexpected status %d", s);
            }
        }
    }
    std::printf("  %d of %d corrupted packages still opened (content damage); all traced in bounds\n", opened, iters);
}

void test_prepared_ray_tampering()
{
    std::vector<uint8_t> b = base_package();
    ct_package p;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, b.data(), b.size()));
    ct_ray ray = {10 * 65536, 10 * 65536, ((int64_t)p.hmax + 1) * 65536 - 1, 1 << 20, 3 << 18, -(1 << 22)};
    ct_prepared pr, bad;
    ct_hit h;
    TEST_ASSERT_EQUAL_INT(CT_OK, ct_ray_prepare(&p, &ray, &pr));
    bad = pr;
    bad.dx = 0;
    bad.dy = 0;
    bad.dz = 5;  // below 2^25
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_DIRECTIONAL, &h));
    bad = pr;
    bad.ox = -1;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_INCREMENTAL, &h));
    bad = pr;
    bad.sector = (int32_t)p.sectors;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_DIRECTIONAL, &h));
    bad = pr;
    bad.sector = (pr.sector + 3) % (int32_t)p.sectors;  // a sector that does not hold the direction
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_DIRECTIONAL, &h));
    bad = pr;
    bad.len_hi += 5;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_CONE, &h));
    bad = pr;
    bad.tend_d = 0;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_HIERARCHICAL, &h));
    bad = pr;
    bad.zshift = CT_ZSHIFT_MAX + 1;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_DIRECTIONAL, &h));
    bad = pr;
    bad.zshift = -1;
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_INCREMENTAL, &h));
    bad = pr;
    bad.dx = bad.dy = 0;
    bad.dz = -(1 << 26);
    bad.sector = -1;
    bad.len_lo = bad.len_hi = 0;
    bad.zshift = 1;  // a vertical ray is traced in Q16 only
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_INCREMENTAL, &h));
    bad.zshift = 0;
    bad.oz = pr.oz * ((int64_t)1 << pr.zshift);
    TEST_ASSERT(ct_trace_prepared(&p, &bad, CT_METHOD_INCREMENTAL, &h) >= 0);  // the same ray, well formed
    bad = pr;
    bad.tend_n = pr.tend_n + pr.tend_d;  // one unit of t past where the ray leaves the box
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_DIRECTIONAL, &h));
    bad = pr;
    bad.oz = ((int64_t)p.hmin - 1) * (65536 >> pr.zshift);  // a traceable ray must start above the box's floor
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_CONE, &h));
    bad = pr;
    bad.oz = ((int64_t)p.hmax + 1) * (65536 >> pr.zshift) + 1;  // above the box in the ray's z units
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace_prepared(&p, &bad, CT_METHOD_INCREMENTAL, &h));
    TEST_ASSERT_EQUAL_INT(CT_ERR_METHOD, ct_trace_prepared(&p, &pr, (ct_method)7, &h));
    ct_ray zero = {0, 0, 0, 0, 0, 0};
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace(&p, &zero, CT_METHOD_INCREMENTAL, &h));
    ct_ray far = {(int64_t)1 << 50, 0, 0, 1, 0, 0};
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace(&p, &far, CT_METHOD_INCREMENTAL, &h));
    ct_ray huge = {0, 0, 0, INT64_MAX, 0, 0};
    TEST_ASSERT_EQUAL_INT(CT_ERR_RAY, ct_trace(&p, &huge, CT_METHOD_INCREMENTAL, &h));
}

// build_package_file streams the same bytes as build_package (voids and
// both builders included); a path that cannot be written throws and leaves
// neither the file nor its temporary behind.
void test_streamed_file_same_bytes()
{
    auto z = dem_cases::smooth(41, 37, 5, 100, 9000);
    ct_host::Terrain t = dem_cases::make_terrain(41, 37, z, 0.5);
    t.void_post.assign(z.size(), 0);
    t.void_post[5 * 41 + 7] = 1;
    const std::string path = "/tmp/ct_test_stream." + std::to_string((long)getpid()) + ".ctp";
    for (ct_host::PptBuilder b : {ct_host::PptBuilder::Slices, ct_host::PptBuilder::Brute})
        for (int n : {1, 8, 24}) {
            ct_host::BuildOptions o;
            o.sectors = n;
            o.reduce = 2;
            o.builder = b;
            const std::vector<uint8_t> mem = ct_host::build_package(t, o);
            ct_host::BuildStats st;
            ct_host::build_package_file(t, o, path, &st);
            FILE *f = fopen(path.c_str(), "rb");
            TEST_ASSERT(f != nullptr);
            std::vector<uint8_t> disk(mem.size() + 16);
            size_t got = fread(disk.data(), 1, disk.size(), f);
            fclose(f);
            disk.resize(got);
            std::remove(path.c_str());
            TEST_ASSERT_MSG(disk == mem, "N=%d: file (%zu bytes) differs from memory (%zu bytes)", n, got, mem.size());
            TEST_ASSERT_EQUAL_INT((int)mem.size(), (int)st.bytes);
            ct_package p;
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_open(&p, mem.data(), mem.size()));
            TEST_ASSERT_EQUAL_INT(CT_OK, ct_package_verify(&p));
            TEST_ASSERT(p.voids != 0);
        }
    const std::string bad = "/tmp/ct_no_such_dir_" + std::to_string((long)getpid()) + "/x.ctp";
    bool threw = false;
    try {
        ct_host::build_package_file(t, ct_host::BuildOptions(), bad);
    } catch (const ct_host::Error &e) {
        threw = std::string(e.what()).find(bad) != std::string::npos;
    }
    TEST_ASSERT_MSG(threw, "an unwritable path did not throw an error naming it");
    // a build that fails after the file was opened leaves nothing behind
    ct_host::Terrain broken = t;
    broken.geo.posting_n = 2 * broken.geo.posting_e;  // non-square posting
    threw = false;
    try {
        ct_host::build_package_file(broken, ct_host::BuildOptions(), path);
    } catch (const ct_host::Error &) {
        threw = true;
    }
    TEST_ASSERT(threw);
    FILE *f = fopen(path.c_str(), "rb");
    TEST_ASSERT_MSG(f == nullptr, "a failed build left %s", path.c_str());
    if (f) fclose(f);
    const std::string cmd = "ls " + path + ".tmp-* >/dev/null 2>&1";
    TEST_ASSERT_MSG(std::system(cmd.c_str()) != 0, "a failed build left a temporary file");
}

}  // namespace

// The builders' inline closed-wedge test (bld::in_closed) is the flight
// library's ct_in_wedge: every sector count, every sector, seeded vectors
// (random up to 2^30, small, axis, the boundary rays and one unit beside them).
static void test_builder_wedge_is_ct_in_wedge(void)
{
    ct_rng r;
    ct_rng_seed(&r, ct_test_seed() + 20);
    long checked = 0, inside = 0;
    for (int n = 1; n <= (int)CT_MAX_SECTORS; ++n) {
        const ct_host::bld::Wedge w = ct_host::bld::make_wedge(n);
        for (int s = 0; s < n; ++s) {
            std::vector<int64_t> v;
            for (int k = 0; k < 300; ++k) {
                const int64_t lim = k % 3 == 0 ? (INT64_C(1) << 30) : k % 3 == 1 ? (INT64_C(1) << 20) : 4;
                v.push_back(ct_rng_range(&r, -lim, lim));
                v.push_back(ct_rng_range(&r, -lim, lim));
            }
            for (int64_t a : {INT64_C(0), INT64_C(1), INT64_C(-1), INT64_C(1) << 30, -(INT64_C(1) << 30)})
                for (int64_t b : {INT64_C(0), INT64_C(1), INT64_C(-1), INT64_C(1) << 30, -(INT64_C(1) << 30)}) {
                    v.push_back(a);
                    v.push_back(b);
                }
            for (int k = s; k <= s + 1; ++k)
                for (int64_t ex = -1; ex <= 1; ++ex)
                    for (int64_t ey = -1; ey <= 1; ++ey) {
                        // the boundary itself (|b| <= 2^30) and one unit beside it
                        v.push_back(std::max<int64_t>(-(INT64_C(1) << 30), std::min<int64_t>(INT64_C(1) << 30, w.bx[k] + ex)));
                        v.push_back(std::max<int64_t>(-(INT64_C(1) << 30), std::min<int64_t>(INT64_C(1) << 30, w.by[k] + ey)));
                        v.push_back(w.bx[k] / 1024 + ex);
                        v.push_back(w.by[k] / 1024 + ey);
                    }
            for (size_t k = 0; k + 1 < v.size(); k += 2) {
                uint32_t in = 2;
                TEST_ASSERT_EQUAL_INT(CT_OK, ct_in_wedge(w.bx.data(), w.by.data(), (uint32_t)n, (uint32_t)s, v[k], v[k + 1], &in));
                const bool host = ct_host::bld::in_closed(w, s, v[k], v[k + 1]);
                TEST_ASSERT_MSG(host == (in != 0), "N=%d s=%d (%lld, %lld): builder %d, ct_in_wedge %u", n, s,
                                (long long)v[k], (long long)v[k + 1], (int)host, in);
                ++checked;
                inside += host;
            }
        }
    }
    std::printf("  wedge test: %ld vectors, %ld inside, builder == ct_in_wedge\n", checked, inside);
}

int main()
{
    TEST_BEGIN("test_package");
    RUN_TEST(test_good_packages_open_and_verify);
    RUN_TEST(test_evil_packages);
    RUN_TEST(test_verify_catches_bad_content);
    RUN_TEST(test_random_corruption);
    RUN_TEST(test_prepared_ray_tampering);
    RUN_TEST(test_streamed_file_same_bytes);
    RUN_TEST(test_builder_wedge_is_ct_in_wedge);
    return TEST_END();
}
