// package_build.cpp -- builds a terrain package (format: lib/include/
// conetrace.h) and streams it to a sink in file order: header, heights,
// max-mipmap, apexes, angle planes, voids, then one patch of the CRC field.
//
// Memory: the caller's DEM, the angle planes (the only package section held
// whole), one 16-bit array per coarse cell (apex levels) and, while the
// builder runs, its working arrays (builder_slices.cpp: one more array per
// coarse cell and one slice's bitsets).  The heights are written from the
// DEM, the mipmap level by level before the cones are built, the voids in
// chunks: none of them is held whole while the angle planes are.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>
#include <thread>

#include "builder_common.hpp"
#include "builder_slices.hpp"
#include "cells.hpp"
#include "conetrace.h"
#include "host_io.hpp"
#include "le.hpp"
#include "terrain.hpp"

namespace ct_host {
namespace {

using namespace bld;

// Sequential writes through a staging buffer, with the running CRC.
class Writer {
public:
    explicit Writer(PackageSink &s) : sink_(s) { buf_.reserve(kBuf); }
    void byte(uint8_t v)
    {
        buf_.push_back(v);
        if (buf_.size() >= kBuf) flush();
    }
    void u16(uint32_t v)
    {
        uint8_t b[2];
        put16(b, v);
        byte(b[0]);
        byte(b[1]);
    }
    void bytes(const uint8_t *p, size_t n)
    {
        flush();
        ct_crc32(crc_, p, n, &crc_);
        sink_.write(p, n);
        pos_ += n;
    }
    // zero padding up to a section's offset
    void pad_to(size_t off)
    {
        if (position() > off) throw Error("package writer: section overlap (internal error)");
        while (position() < off) byte(0);
    }
    size_t position() const { return pos_ + buf_.size(); }
    void flush()
    {
        if (buf_.empty()) return;
        ct_crc32(crc_, buf_.data(), buf_.size(), &crc_);
        sink_.write(buf_.data(), buf_.size());
        pos_ += buf_.size();
        buf_.clear();
    }
    uint32_t crc() const { return crc_; }

private:
    static constexpr size_t kBuf = 1 << 16;
    PackageSink &sink_;
    std::vector<uint8_t> buf_;
    size_t pos_ = 0;
    uint32_t crc_ = 0;
};

// The mipmap levels 1..levels of the fine cells' max pyramid (level l: 2x2
// maxima of level l-1; level 0 = fine cells, not stored), one level in memory
// besides the one being made.
void write_mipmap(Writer &w, const Terrain &t, int cx, int cy, uint32_t levels)
{
    std::vector<uint16_t> prev, cur;
    int pw = cx, ph = cy;
    for (uint32_t l = 1; l <= levels; ++l) {
        if (l == 1)
            cur = max_pyramid_step(pw, ph, [&](int i, int j) { return fine_max(t, i, j); });
        else
            cur = max_pyramid_step(pw, ph, [&](int i, int j) { return prev[(size_t)j * pw + i]; });
        for (uint16_t v : cur) w.u16(v);
        prev.swap(cur);
        pw = (pw + 1) / 2;
        ph = (ph + 1) / 2;
    }
}

class VectorSink : public PackageSink {
public:
    explicit VectorSink(std::vector<uint8_t> &b) : b_(b) {}
    void write(const uint8_t *p, size_t n) override { b_.insert(b_.end(), p, p + n); }
    void patch(size_t off, const uint8_t *p, size_t n) override { std::memcpy(&b_[off], p, n); }
    // one allocation: growing by doubling copies and pages in about twice the
    // package (measured on 45 MB packages: memmove and page faults ~15% of a build)
    void size_hint(size_t n) override { b_.reserve(n); }

private:
    std::vector<uint8_t> &b_;
};

class FileSink : public PackageSink {
public:
    explicit FileSink(AtomicFile &f) : f_(f) {}
    void write(const uint8_t *p, size_t n) override { f_.write(p, n); }
    void patch(size_t off, const uint8_t *p, size_t n) override { f_.patch(off, p, n); }

private:
    AtomicFile &f_;
};

// The slice builder's levels (codes): L_k = ceil(hmin + k (hmax - hmin) /
// K), duplicates removed, or the given ones (metres, rounded up to codes)
// plus the extremes; *slices_header: the count the header records.  No
// levels for the other builders.
std::vector<int> slice_levels(const Terrain &t, const BuildOptions &opt, uint16_t hmin, uint16_t hmax,
                              int *slices_header)
{
    *slices_header = opt.builder == PptBuilder::Degenerate ? 0 : opt.slices;
    std::vector<int> lv;
    if (opt.builder == PptBuilder::Slices) {
        const int K = opt.slices > 0 ? opt.slices : BuildOptions::DEFAULT_SLICES;
        *slices_header = K;
        if (!opt.levels_m.empty()) {
            // given levels in metres -> codes (rounded up: a level is only a
            // height at which a slice is cut), plus the extremes
            lv.push_back(hmin);
            lv.push_back(hmax);
            for (double m : opt.levels_m) {
                if (!std::isfinite(m)) throw Error("slice level is not a number");
                double code = std::ceil((m - t.height_offset_m) / t.height_scale_m - 1e-9);
                if (code > hmin && code < hmax) lv.push_back((int)code);
            }
            std::sort(lv.begin(), lv.end());
            lv.erase(std::unique(lv.begin(), lv.end()), lv.end());
            *slices_header = (int)lv.size() - 1;
        } else {
            for (int k = 0; k <= K; ++k) {
                const int l = slice_level(hmin, hmax, K, k);
                if (lv.empty() || l > lv.back()) lv.push_back(l);
            }
        }
    }
    return lv;
}

// The header's fields besides the layout's offsets and sizes.
struct HeaderFields {
    uint32_t total = 0, levels = 0, datum_off = 0;
    bool voids = false, datum = false;
    uint16_t hmin = 0, hmax = 0;
    int slices = 0;
    int64_t pe = 0, pn = 0, sc = 0;  // postings and height scale, nm
};

// The header, CRC field zero: the bytes before the heights section.
void write_header(Writer &w, const Terrain &t, const Ctx &c, const HeaderFields &f, const uint32_t so[CT_SEC_COUNT],
                  const uint32_t ss[CT_SEC_COUNT])
{
    std::vector<uint8_t> h(so[CT_SEC_HEIGHTS], 0);
    if (h.size() < (size_t)CT_HDR_SECTION_TABLE + 8 * CT_SEC_COUNT) throw Error("package layout: short header");
    std::memcpy(&h[CT_HDR_MAGIC], CT_PKG_MAGIC, 4);
    put16(h, CT_HDR_VERSION, CT_PKG_VERSION);
    put16(h, CT_HDR_HEADER_SIZE, CT_PKG_HEADER_SIZE);
    put32(h, CT_HDR_TOTAL, f.total);
    put16(h, CT_HDR_WIDTH, (uint32_t)t.width);
    put16(h, CT_HDR_HEIGHT, (uint32_t)t.height);
    h[CT_HDR_REDUCE] = (uint8_t)c.r;
    h[CT_HDR_SECTORS] = (uint8_t)c.n;
    h[CT_HDR_LEVELS] = (uint8_t)f.levels;
    h[CT_HDR_FLAGS] = (uint8_t)((f.voids ? CT_PKG_FLAG_VOIDS : 0u) | (f.datum ? CT_PKG_FLAG_DATUM : 0u));
    put16(h, CT_HDR_HMIN, f.hmin);
    put16(h, CT_HDR_HMAX, f.hmax);
    put32(h, CT_HDR_SLICES, (uint32_t)f.slices);
    put64(h, CT_HDR_ORIGIN_E, t.geo.origin_nm_set ? t.geo.origin_e_nm : metres_to_nm(t.geo.origin_e));
    put64(h, CT_HDR_ORIGIN_N, t.geo.origin_nm_set ? t.geo.origin_n_nm : metres_to_nm(t.geo.origin_n));
    put64(h, CT_HDR_POSTING_E, f.pe);
    put64(h, CT_HDR_POSTING_N, f.pn);
    put64(h, CT_HDR_HEIGHT_OFFSET, metres_to_nm(t.height_offset_m));
    put64(h, CT_HDR_HEIGHT_SCALE, f.sc);
    put32(h, CT_HDR_EPSG, (uint32_t)std::max(0, t.geo.epsg));
    put32(h, CT_HDR_DATUM, f.datum ? f.datum_off : 0u);
    for (int k = 0; k < CT_SEC_COUNT; ++k) {
        put32(h, CT_HDR_SECTION_TABLE + 8 * k, so[k]);
        put32(h, CT_HDR_SECTION_TABLE + 8 * k + 4, ss[k]);
    }
    w.bytes(h.data(), h.size());
}

// The PPT: *apex per coarse cell and *codes, the N sector planes of angle
// codes (sector-major), from the builder opt chooses.
void build_ppt(Ctx &c, const Terrain &t, const BuildOptions &opt, const std::vector<int> &lv, uint16_t hmin,
               uint16_t hmax, int nthreads, BuildStats *stats, std::vector<uint16_t> *apex_out,
               std::vector<uint8_t> *codes_out)
{
    std::vector<uint16_t> &apex = *apex_out;
    std::vector<uint8_t> &codes = *codes_out;
    const size_t plane = codes.size() / (size_t)c.n;
    // coarse heights: the tallest post of the coarse cell's fine cells
    int wct, hct;
    std::vector<uint16_t> hcm = cell_tops(t, c.r, wct, hct);
    if (opt.builder == PptBuilder::Slices) {
        std::vector<uint16_t> k0(plane);  // apex levels, < lv.size() <= 65536
        // the paper's apex: the lowest level not below the cell's top
        // (measured: 7% fewer steps than exact apexes with K = 64)
        for (size_t f = 0; f < plane; ++f)
            k0[f] = (uint16_t)(std::lower_bound(lv.begin(), lv.end(), (int)hcm[f]) - lv.begin());
        SliceInput in;
        in.levels = &lv;
        in.apex_level = &k0;
        in.coarse_max = &hcm;  // taken over
        in.window = opt.window;
        in.full_dt_rows = opt.full_dt_rows;
        in.threads = nthreads;
        in.progress = opt.progress;
        SliceStats sst;
        slice_angles(c, in, codes.data(), &sst);
        apex.resize(plane);
        for (size_t f = 0; f < plane; ++f) apex[f] = (uint16_t)lv[k0[f]];
        if (stats) {
            stats->slices = (int)lv.size() - 1;
            stats->slices_transformed = sst.slices;
            stats->seconds_local = sst.seconds_local;
            stats->far_narrowed = sst.far_narrowed;
            stats->dt_queries = sst.queries;
            stats->dt_query_rows = sst.query_rows;
            stats->full_dts = sst.full_dts;
            stats->seconds_dt = sst.seconds_dt;
        }
    } else if (opt.builder == PptBuilder::Degenerate) {
        apex.swap(hcm);  // the angle codes stay 0
    } else {
        apex.swap(hcm);
        if (opt.slices > 0 && hmax > hmin) {
            for (uint16_t &am : apex) {
                int m = am;
                // smallest level hmin + k*(hmax-hmin)/K >= m, as an integer code
                double step = (double)(hmax - hmin) / opt.slices;
                int k = (int)std::ceil((m - hmin) / step - 1e-12);
                int lvl = slice_level(hmin, hmax, opt.slices, k);
                am = (uint16_t)std::min<int>(hmax, std::max(m, lvl));
            }
        }
        c.fm.resize((size_t)c.cx * c.cy);
        for (int j = 0; j < c.cy; ++j)
            for (int i = 0; i < c.cx; ++i) c.fm[(size_t)j * c.cx + i] = fine_max(t, i, j);
        c.pyr = make_pyramid(c.fm, c.cx, c.cy);
        brute_angles(c, apex, codes.data(), nthreads, opt.progress);
        c.pyr = Pyramid();
        c.fm = std::vector<uint16_t>();
    }
}

// The voids section: bit k = fine cell k (row-major) touches a void post.
void write_voids(Writer &w, const Ctx &c, const Terrain &t)
{
    const size_t cells = (size_t)c.cx * c.cy;
    for (size_t k0 = 0; k0 < cells; k0 += 8) {
        uint8_t byte = 0;
        for (size_t k = k0; k < std::min(cells, k0 + 8); ++k) {
            const size_t i = k % (size_t)c.cx, j = k / (size_t)c.cx, p00 = j * (size_t)t.width + i;
            if (t.void_post[p00] || t.void_post[p00 + 1] || t.void_post[p00 + t.width] ||
                t.void_post[p00 + t.width + 1])
                byte |= (uint8_t)(1u << (k - k0));
        }
        w.byte(byte);
    }
}

// The datum section (conetrace.h): vertical datum, source CRS, geoid grid.
void write_datum(Writer &w, const Terrain &t)
{
    std::vector<uint8_t> d(CT_DATUM_HEADER_SIZE, 0);
    put16(d, 0, (uint32_t)t.vdatum);
    put16(d, 2, (uint32_t)t.geoid.w);
    put16(d, 4, (uint32_t)t.geoid.h);
    put32(d, 8, (uint32_t)std::max(0, t.geo.source_epsg));
    put64(d, 16, t.geoid.lat0_q61);
    put64(d, 24, t.geoid.lon0_q61);
    put64(d, 32, t.geoid.step_q61);
    w.bytes(d.data(), d.size());
    for (int32_t v : t.geoid.um) {
        uint8_t b[4];
        put32(b, (uint32_t)v);
        w.bytes(b, 4);
    }
}

}  // namespace

void build_package_to(const Terrain &t, const BuildOptions &opt, PackageSink &sink, BuildStats *stats)
{
    auto t0 = std::chrono::steady_clock::now();
    if (opt.sectors < 1 || opt.sectors > CT_MAX_SECTORS) throw Error("sectors must be in 1..64");
    if (opt.reduce < 1 || opt.reduce > CT_MAX_REDUCE) throw Error("reduce must be in 1..8");
    if (opt.slices < 0) throw Error("slices must be >= 0");
    if (t.width < 2 || t.height < 2 || t.width > CT_MAX_POSTS || t.height > CT_MAX_POSTS)
        throw Error("DEM dimensions outside 2..32768 posts");
    if ((size_t)t.width * t.height != t.codes.size()) throw Error("terrain codes size mismatch");

    Ctx c;
    c.t = &t;
    c.cx = t.width - 1;
    c.cy = t.height - 1;
    c.r = opt.reduce;
    c.n = opt.sectors;
    c.wedge = make_wedge(opt.sectors);

    // georeference as stored
    int64_t pe = metres_to_nm(t.geo.posting_e), pn = metres_to_nm(t.geo.posting_n);
    int64_t sc = metres_to_nm(t.height_scale_m);
    if (pe == 0 || pn == 0 || std::llabs(pe) != std::llabs(pn)) {
        std::ostringstream os;
        os << "non-square posting (" << t.geo.posting_e << " x " << t.geo.posting_n << " m)";
        throw Error(os.str());
    }
    if (sc <= 0) throw Error("height scale must be positive");
    if (ct_cot_table(pe, sc, c.cot_q16, c.cot_ok) != CT_OK) throw Error("posting or height scale out of range");
    prepare_codes(c);

    const bool voids = !t.void_post.empty();
    uint32_t so[CT_SEC_COUNT], ss[CT_SEC_COUNT], levels, total;
    if (ct_package_layout((uint32_t)t.width, (uint32_t)t.height, (uint32_t)c.r, (uint32_t)c.n, voids ? 1u : 0u, so, ss,
                          &levels, &total) != CT_OK)
        throw Error("package layout failed (size limits)");
    // the datum section (conetrace.h), after the fixed sections
    const bool datum = t.vdatum != CT_VDATUM_UNKNOWN || t.geo.source_epsg != 0 || t.geoid.w > 0;
    const uint32_t datum_off = total;
    if (datum) {
        if (t.geoid.um.size() != (size_t)t.geoid.w * (size_t)t.geoid.h) throw Error("geoid grid size mismatch");
        uint64_t end = (uint64_t)total + CT_DATUM_HEADER_SIZE + 4u * (uint64_t)t.geoid.um.size();
        end = (end + 7u) & ~(uint64_t)7u;
        if (end > 0xffffffffu) throw Error("package layout failed (size limits)");
        total = (uint32_t)end;
    }
    uint16_t hmin = 65535, hmax = 0;
    for (uint16_t v : t.codes) {
        hmin = std::min(hmin, v);
        hmax = std::max(hmax, v);
    }
    const int wc = (c.cx + c.r - 1) / c.r, hc = (c.cy + c.r - 1) / c.r;
    const size_t plane = (size_t)wc * hc;
    const int nthreads = opt.threads > 0 ? opt.threads : (int)std::max(1u, std::thread::hardware_concurrency());

    int slices_header = 0;
    const std::vector<int> lv = slice_levels(t, opt, hmin, hmax, &slices_header);

    // ---- header (CRC field zero), heights, mipmap: from the DEM alone
    sink.size_hint(total);
    Writer w(sink);
    HeaderFields f;
    f.total = total, f.levels = levels, f.datum_off = datum_off, f.voids = voids, f.datum = datum;
    f.hmin = hmin, f.hmax = hmax, f.slices = slices_header, f.pe = pe, f.pn = pn, f.sc = sc;
    write_header(w, t, c, f, so, ss);
    w.pad_to(so[CT_SEC_HEIGHTS]);
    for (uint16_t v : t.codes) w.u16(v);
    w.pad_to(so[CT_SEC_MIPMAP]);
    write_mipmap(w, t, c.cx, c.cy, levels);
    w.flush();

    // ---- the PPT: apexes and the angle planes (sector-major, then the
    // omnidirectional plane when N > 1, made while it is written)
    std::vector<uint8_t> codes(plane * (size_t)c.n, 0);
    std::vector<uint16_t> apex;  // per coarse cell: apex height code
    build_ppt(c, t, opt, lv, hmin, hmax, nthreads, stats, &apex, &codes);
    if (stats) stats->cones = plane * (size_t)c.n;
    size_t degenerate = 0;
    for (size_t k = 0; k < plane * (size_t)c.n; ++k) degenerate += codes[k] == 0;

    // ---- apexes, angles, voids
    w.pad_to(so[CT_SEC_APEX]);
    for (uint16_t v : apex) w.u16(v);
    w.pad_to(so[CT_SEC_ANGLES]);
    w.bytes(codes.data(), codes.size());
    if (c.n > 1) {
        for (size_t k = 0; k < plane; ++k) {
            uint8_t m = 255;
            for (int s = 0; s < c.n; ++s) m = std::min(m, codes[(size_t)s * plane + k]);
            w.byte(m);
        }
    }
    if (voids) {
        w.pad_to(so[CT_SEC_VOIDS]);
        write_voids(w, c, t);
    }
    if (datum) {
        w.pad_to(datum_off);
        write_datum(w, t);
    }
    w.pad_to(total);
    w.flush();
    uint8_t crc[4];
    put32(crc, w.crc());
    sink.patch(CT_HDR_CRC, crc, 4);
    if (stats) {
        stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        stats->degenerate_cones = degenerate;
        stats->bytes = total;
    }
}

std::vector<uint8_t> build_package(const Terrain &t, const BuildOptions &opt, BuildStats *stats)
{
    std::vector<uint8_t> b;
    VectorSink s(b);
    build_package_to(t, opt, s, stats);
    return b;
}

void build_package_file(const Terrain &t, const BuildOptions &opt, const std::string &path, BuildStats *stats)
{
    AtomicFile f(path);
    FileSink s(f);
    build_package_to(t, opt, s, stats);
    f.commit();
}

}  // namespace ct_host
