// host_io.cpp -- see host_io.hpp.
#include "host_io.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <atomic>
#include <sstream>
#include <thread>

#include <unistd.h>

namespace ct_host {

std::vector<uint8_t> read_file(const std::string &path)
{
    std::FILE *f = std::fopen(path.c_str(), "rb");
    if (!f) throw Error(path + ": " + std::strerror(errno));
    std::vector<uint8_t> b;
    uint8_t buf[1 << 16];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) b.insert(b.end(), buf, buf + n);
    bool bad = std::ferror(f);
    std::fclose(f);
    if (bad) throw Error(path + ": read error");
    return b;
}

void open_package_file(const std::string &path, std::vector<uint8_t> *bytes, ct_package *pkg)
{
    *bytes = read_file(path);
    const ct_status st = ct_package_open(pkg, bytes->data(), bytes->size());
    if (st != CT_OK) throw Error(path + ": not a valid package (" + status_name(st) + ")");
}

AtomicFile::AtomicFile(const std::string &path) : tmp_(path)
{
    const int fd = ::dup(tmp_.fd());  // the stream closes its own
    f_ = fd < 0 ? nullptr : ::fdopen(fd, "wb");
    if (!f_) {
        const int err = errno;
        if (fd >= 0) ::close(fd);
        tmp_.fail(err);
    }
}

AtomicFile::~AtomicFile()
{
    if (f_) std::fclose(f_);
}

void AtomicFile::write(const void *p, size_t n)
{
    if (std::fwrite(p, 1, n, f_) != n) tmp_.fail(errno);
}

void AtomicFile::patch(size_t offset, const void *p, size_t n)
{
    const long here = std::ftell(f_);
    if (here < 0 || std::fseek(f_, (long)offset, SEEK_SET) != 0 || std::fwrite(p, 1, n, f_) != n ||
        std::fseek(f_, here, SEEK_SET) != 0)
        tmp_.fail(errno);
}

void AtomicFile::commit()
{
    std::FILE *f = f_;
    f_ = nullptr;
    const bool flushed = std::fflush(f) == 0;
    const int err = errno;
    if (std::fclose(f) != 0 || !flushed) tmp_.fail(flushed ? errno : err);
    tmp_.commit();  // fsync, close, rename
}

void write_file_atomic(const std::string &path, const std::vector<uint8_t> &bytes)
{
    AtomicFile f(path);
    f.write(bytes.data(), bytes.size());
    f.commit();
}

void write_file_atomic(const std::string &path, const std::string &head, const std::vector<std::string> &parts)
{
    AtomicFile f(path);
    f.write(head.data(), head.size());
    for (const std::string &part : parts) f.write(part.data(), part.size());
    f.commit();
}

double proc_status_kib(const char *key)
{
    std::ifstream f("/proc/self/status");
    std::string line;
    const size_t n = std::strlen(key);
    while (std::getline(f, line))
        if (line.compare(0, n, key) == 0 && line.size() > n && line[n] == ':') return std::atof(line.c_str() + n + 1);
    return 0.0;
}

void reset_peak_rss()
{
    std::ofstream f("/proc/self/clear_refs");
    f << "5";
}

std::string status_name(ct_status s)
{
    const char *n = "unknown";
    ct_status_name(s, &n);
    return n;
}

std::string parse_cmdline(int argc, char **argv, int first, const std::vector<std::string> &valued,
                          const std::vector<std::string> &flags, bool once, CmdLine *out)
{
    auto in = [](const std::vector<std::string> &v, const std::string &s) {
        for (const std::string &x : v)
            if (x == s) return true;
        return false;
    };
    for (int k = first; k < argc; ++k) {
        std::string s = argv[k];
        if (in(flags, s)) {
            out->flag.insert(s);
        } else if (s.size() > 1 && s[0] == '-') {
            if (!in(valued, s)) return "unknown option " + s;
            if (k + 1 >= argc) return "option " + s + " needs a value";
            if (once && out->opt.count(s)) return "option " + s + " given twice";
            out->opt[s] = argv[++k];
        } else {
            out->pos.push_back(s);
        }
    }
    return "";
}

namespace {
// A field of a file quoted in a message: control characters (a NUL would
// end the message, a '\r' overwrite the line) as '?', cut to 60 characters.
std::string printable(const std::string &s)
{
    std::string o = s.substr(0, 60);
    for (char &c : o)
        if ((unsigned char)c < 0x20 || c == 0x7f) c = '?';
    return s.size() > 60 ? o + "..." : o;
}
}  // namespace

void read_number_csv(const std::string &path, const std::vector<std::string> &names,
                     const std::function<void(const double *v, const std::vector<std::string> &text)> &row,
                     const std::function<void(size_t rows)> &expect)
{
    std::string need;
    for (const std::string &n : names) need += (need.empty() ? "" : ",") + n;
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path + ": " + std::strerror(errno));
    // the whole file, then its lines ('\n'; the last one may lack it)
    std::string buf;
    {
        std::vector<char> tmp((size_t)1 << 16);
        while (in.read(tmp.data(), (std::streamsize)tmp.size()) || in.gcount() > 0)
            buf.append(tmp.data(), (size_t)in.gcount());
    }
    if (buf.empty()) throw Error(path + ": empty file (expected a header " + need + ")");
    const char *p = buf.data(), *const end = buf.data() + buf.size();
    auto next_line = [&](const char **b, const char **e) {
        const char *nl = static_cast<const char *>(std::memchr(p, '\n', (size_t)(end - p)));
        *b = p;
        *e = nl != nullptr ? nl : end;
        p = nl != nullptr ? nl + 1 : end;
    };
    auto blank = [](char ch) { return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\f' || ch == '\v'; };
    // fields into v (reused from line to line): blanks of every kind
    // dropped (strtod would skip them, the text keep them)
    auto split = [&blank](const char *b, const char *e, std::vector<std::string> &v) {
        size_t k = 0;
        if (v.empty()) v.emplace_back();
        v[0].clear();
        for (; b < e; ++b) {
            const char ch = *b;
            if (ch == ',') {
                if (++k == v.size()) v.emplace_back();
                v[k].clear();
            } else if (!blank(ch)) {
                v[k] += ch;
            }
        }
        v.resize(k + 1);
    };
    const size_t n = names.size();
    const char *lb, *le;
    next_line(&lb, &le);
    std::vector<std::string> hdr;
    split(lb, le, hdr);
    std::vector<int> col(n);
    for (size_t k = 0; k < n; ++k) {
        col[k] = -1;
        for (size_t c = 0; c < hdr.size(); ++c) {
            if (hdr[c] != names[k]) continue;
            if (col[k] >= 0) throw Error(path + ":1: column '" + names[k] + "' appears twice in the header");
            col[k] = (int)c;
        }
        if (col[k] < 0) throw Error(path + ":1: header lacks column '" + names[k] + "' (need " + need + ")");
    }
    if (expect) {
        // at most one row per remaining line
        size_t lines = (size_t)std::count(p, end, '\n') + (end > p && end[-1] != '\n' ? 1u : 0u);
        expect(lines);
    }
    std::vector<double> v(n);
    std::vector<std::string> text(n), f;
    int lineno = 1;
    while (p < end) {
        next_line(&lb, &le);
        ++lineno;
        if (std::all_of(lb, le, blank)) continue;
        split(lb, le, f);
        for (size_t k = 0; k < n; ++k) {
            if ((size_t)col[k] >= f.size()) throw Error(path + ":" + std::to_string(lineno) + ": too few columns");
            char *endp = nullptr;
            const std::string &t = f[col[k]];
            v[k] = std::strtod(t.c_str(), &endp);
            // the whole field a number (a NUL in it would end strtod's text)
            if (t.empty() || endp != t.c_str() + t.size() || !std::isfinite(v[k]))
                throw Error(path + ":" + std::to_string(lineno) + ": bad number '" + printable(f[col[k]]) +
                            "' in column " + names[k]);
            text[k] = f[col[k]];
        }
        row(v.data(), text);
    }
}

std::vector<MapRay> read_rays_csv(const std::string &path)
{
    std::vector<MapRay> rays;
    read_number_csv(
        path, {"E", "N", "h", "dE", "dN", "dh"},
        [&](const double *v, const std::vector<std::string> &) {
            rays.push_back(MapRay{v[0], v[1], v[2], v[3], v[4], v[5]});
        },
        [&](size_t n) { rays.reserve(n); });
    return rays;
}

ct_status map_ray_to_grid(const ct_package &p, const MapRay &r, ct_ray *out)
{
    // the flight library's conversion (ct_ray_from_map): origin in nm, the
    // direction scaled so its largest component is 2^40 (its range)
    const double lim = 2305843009213693952.0; /* 2^61 nm, ct_map_to_grid's range */
    const double o[3] = {r.e * 1e9, r.n * 1e9, r.h * 1e9};
    for (double v : o)
        if (!(std::fabs(v) <= lim)) return CT_ERR_RAY;
    double m = std::max(std::fabs(r.de), std::max(std::fabs(r.dn), std::fabs(r.dh)));
    if (!(m > 0) || !std::isfinite(m)) return CT_ERR_RAY;
    auto q40 = [m](double v) { return std::llround(v / m * 1099511627776.0); }; /* 2^40 */
    return ct_ray_from_map(&p, std::llround(o[0]), std::llround(o[1]), std::llround(o[2]), q40(r.de), q40(r.dn),
                           q40(r.dh), out);
}

Progress::Progress(std::string what) : what_(std::move(what)), t0_(std::chrono::steady_clock::now()) {}

void Progress::update(size_t done, size_t total)
{
    double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    if (el < 1.0 || total == 0 || !isatty(2)) {
        if (el >= 1.0 && total && !isatty(2) && !shown_) {
            std::fprintf(stderr, "%s ...\n", what_.c_str());
            shown_ = true;
        }
        return;
    }
    shown_ = true;
    int w = 30, k = (int)(w * done / total);
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%% %.0f s", what_.c_str(), k, "##############################", w - k, "",
                 (int)(100 * done / total), el);
}

void Progress::finish()
{
    if (shown_ && isatty(2)) std::fprintf(stderr, "\n");
}

}  // namespace ct_host

namespace ct_host {

void parallel_chunks(size_t n, int threads, size_t chunk, const std::function<void(size_t, size_t)> &work)
{
    if (chunk == 0) chunk = 1;
    size_t chunks = (n + chunk - 1) / chunk;
    size_t t = threads > 0 ? (size_t)threads : std::max(1u, std::thread::hardware_concurrency());
    t = std::min(t, std::max<size_t>(chunks, 1));
    std::atomic<size_t> next{0};
    auto run = [&]() {
        for (size_t c; (c = next.fetch_add(1)) < chunks;) work(c * chunk, std::min(n, (c + 1) * chunk));
    };
    std::vector<std::thread> pool;
    for (size_t k = 1; k < t; ++k) pool.emplace_back(run);
    run();
    for (auto &th : pool) th.join();
}

double number_in(const std::string &name, const std::string &text, double lo, double hi, const char *what)
{
    char *end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || !end || *end || !(v >= lo && v <= hi))
        throw Error(name + " needs " + what + ", got '" + text + "'");
    return v;
}

ct_method method_named(const std::string &name)
{
    if (name == "incremental") return CT_METHOD_INCREMENTAL;
    if (name == "hierarchical") return CT_METHOD_HIERARCHICAL;
    if (name == "cone") return CT_METHOD_CONE;
    if (name == "directional") return CT_METHOD_DIRECTIONAL;
    throw Error("unknown method '" + name + "' (incremental, hierarchical, cone, directional)");
}

int threads_option(const std::string &text, const std::string &cmd)
{
    char *end = nullptr;
    long v = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || !end || *end || v < 0 || v > 256)
        throw Error(cmd + ": --threads needs a number of threads in [0, 256] (0 = all cores), got '" + text + "'");
    return (int)v;
}

}  // namespace ct_host
