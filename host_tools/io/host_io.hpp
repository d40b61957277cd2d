// host_io.hpp -- files, command lines, CSVs of numbers (rays, pixels), progress,
// map <-> grid conversion (host).
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "conetrace.h"
#include "temp_output.hpp"
#include "terrain.hpp"

namespace ct_host {

// Whole-file read; throws Error("<path>: <reason>").
std::vector<uint8_t> read_file(const std::string &path);

// A package file read whole into *bytes and opened as *pkg (a view of
// *bytes: keep them together); throws Error("<path>: not a valid package
// (<status>)") or read_file's.
void open_package_file(const std::string &path, std::vector<uint8_t> *bytes, ct_package *pkg);

// An output file written atomically through a TempOutput: commit() flushes,
// syncs and renames it onto path; destroyed without commit() (an error on
// the way), the temporary is removed.  Every failure throws Error("<path>:
// cannot write (<reason>)").
class AtomicFile {
public:
    explicit AtomicFile(const std::string &path);
    ~AtomicFile();
    AtomicFile(const AtomicFile &) = delete;
    AtomicFile &operator=(const AtomicFile &) = delete;
    void write(const void *p, size_t n);
    void patch(size_t offset, const void *p, size_t n);  // overwrite bytes already written
    void commit();

private:
    TempOutput tmp_;
    std::FILE *f_ = nullptr;
};
// The whole file at once, through AtomicFile.
void write_file_atomic(const std::string &path, const std::vector<uint8_t> &bytes);
// The same from a head and parts written one after another (text made in
// chunks, never joined in memory).
void write_file_atomic(const std::string &path, const std::string &head, const std::vector<std::string> &parts);

// A field of /proc/self/status in KiB (0 when unavailable), e.g. "VmHWM".
double proc_status_kib(const char *key);
// Reset VmHWM to the current resident size (Linux >= 4.0; harmless elsewhere).
void reset_peak_rss();

std::string status_name(ct_status s);

// Run work(begin, end) over [0, n) in chunks of `chunk` items on `threads`
// threads (0: all cores; never more threads than chunks), each chunk once;
// the calling thread takes part.  Outputs indexed by item keep input order.
void parallel_chunks(size_t n, int threads, size_t chunk, const std::function<void(size_t, size_t)> &work);

// An option's number: text parsed whole (strtod) and within [lo, hi]
// (NaN never is).  Throws Error("<name> needs <what>, got '<text>'").
double number_in(const std::string &name, const std::string &text, double lo, double hi, const char *what);

// --method NAME: incremental, hierarchical, cone or directional.  Throws
// Error("unknown method 'x' (incremental, hierarchical, cone, directional)").
ct_method method_named(const std::string &name);

// --threads T: a number of threads in [0, 256] (0 = all cores).
int threads_option(const std::string &text, const std::string &cmd);

// A command's arguments from argv[first]: "NAME VALUE" for the names in
// `valued`, bare switches in `flags`, the rest positional (an argument
// starting with '-' and longer than one character is an option).  Returns
// "" or the error: "unknown option X", "option X needs a value" and, with
// once, "option X given twice" (else the last value wins).
struct CmdLine {
    std::vector<std::string> pos;
    std::map<std::string, std::string> opt;
    std::set<std::string> flag;
};
std::string parse_cmdline(int argc, char **argv, int first, const std::vector<std::string> &valued,
                          const std::vector<std::string> &flags, bool once, CmdLine *out);

// A CSV of numbers whose header names the columns (any order, others
// ignored; blanks and CR dropped from every field; blank lines skipped):
// row(v, text) for each data row, v[k] and text[k] the value and field of
// column names[k].  Throws Error "<path>: empty file (expected a header
// A,B,..)", "<path>:1: header lacks column 'A' (need A,B,..)" / ": column
// 'A' appears twice in the header",
// "<path>:<line>: too few columns" / ": bad number 'x' in column A".
// expect (if given) hears once, before the first row, how many rows there
// can be at most (the lines after the header).
void read_number_csv(const std::string &path, const std::vector<std::string> &names,
                     const std::function<void(const double *v, const std::vector<std::string> &text)> &row,
                     const std::function<void(size_t rows)> &expect = nullptr);

// A ray in the map frame (metres): origin (e, n, h), direction (de, dn, dh).
struct MapRay {
    double e, n, h, de, dn, dh;
};
// rays.csv: header naming E,N,h,dE,dN,dh (any order); throws Error with
// "<path>:<line>: <reason>" on bad input.
std::vector<MapRay> read_rays_csv(const std::string &path);

// Map-frame ray (double metres) to a grid ray for the package with the
// flight library's ct_ray_from_map: origin rounded to nm, direction scaled to
// |max| = 2^40.  CT_ERR_RAY if degenerate or out of range.
ct_status map_ray_to_grid(const ct_package &p, const MapRay &r, ct_ray *out);

// A progress bar on stderr, shown only once the work has taken > 1 s.
class Progress {
  public:
    explicit Progress(std::string what);
    void update(size_t done, size_t total);
    void finish();

  private:
    std::string what_;
    std::chrono::steady_clock::time_point t0_;
    bool shown_ = false;
};

}  // namespace ct_host
