// temp_output.hpp -- the temporary file behind every output file the host
// tools write (host_io.hpp's AtomicFile, dem_io's GeoTIFF writer).
#pragma once

#include <string>

namespace ct_host {

// The temporary file behind every output (AtomicFile, the GeoTIFF writer):
// created next to the destination as "<path>.tmp-<8 hex digits>" (O_EXCL,
// a fresh random suffix on a clash), renamed onto the destination only by
// commit(), after the data reached the disk (fsync); removed when destroyed
// uncommitted (an error on the way).  Never a partial output file.  Fails
// with Error("<path>: cannot create a temporary file next to it (<reason>)"),
// Error("<path>: cannot write (<reason>)") or Error("<path>: cannot rename
// the temporary file '<tmp>' onto it (<reason>)").
class TempOutput {
public:
    explicit TempOutput(const std::string &path);
    ~TempOutput();
    TempOutput(const TempOutput &) = delete;
    TempOutput &operator=(const TempOutput &) = delete;
    // The descriptor stays TempOutput's: a writer that closes what it is
    // given (fclose of an fdopen'ed stream, TIFFClose) gets a dup of it.
    int fd() const { return fd_; }
    const std::string &temp_path() const { return tmp_; }
    // After the writer flushed: fsync, close, rename.
    void commit();
    [[noreturn]] void fail(int err) const;

private:
    std::string path_, tmp_;
    int fd_ = -1;
    bool done_ = false;
};

}  // namespace ct_host
