// temp_output.hpp -- the temporary file behind every output file the host
// tools write (host_io.hpp's AtomicFile, dem_io's GeoTIFF writer).
#pragma once

#include <string>

namespace ct_host {

// The temporary file behind every output (AtomicFile, the GeoTIFF writer):
// created next to the destination as "<path>.tmp-<8 hex digits>" (O_EXCL,
// a fresh random suffix on a clash), renamed onto the destination only by
// commit(), after the data reached the disk (fsync); removed when destroyed
// uncommitted (an error on the way), or by the interrupt watcher below when
// the run is interrupted.  Never a partial output file.  Fails
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

// Interrupted runs.  A program's main calls remove_temporaries_on_interrupt
// first (before any thread starts): SIGINT, SIGTERM and SIGHUP (each one not
// ignored when the program started, e.g. by nohup) are then blocked in every
// thread and taken by a watcher thread, which removes every registered
// temporary (a file, or a directory and its contents), prints one line on
// stderr, "<program>: interrupted by SIGINT: <output> not written (its
// temporaries removed)" -- the outputs of the registered temporaries; when
// none is registered, "... <output> not written" with `output` (the command
// line's -o), or just "<program>: interrupted by SIGINT" -- and ends the
// process by the same signal (the parent sees it killed by SIGINT).  An
// output already in place (one being replaced) is left as it was.
// Without the call, registering costs a lock and nothing else happens.
void remove_temporaries_on_interrupt(const char *program, const std::string &output);

// The registry of temporaries.  A temporary is registered, under the lock,
// as it is created (TempOutput does; directories with
// create_registered_dir) and unregistered as it is renamed into place, so
// the watcher never sees one half made or half renamed.  The mutex is
// recursive: hold an InterruptLock around a sequence of renames (the
// watcher waits for it).
class InterruptLock {
public:
    InterruptLock();
    ~InterruptLock();
    InterruptLock(const InterruptLock &) = delete;
    InterruptLock &operator=(const InterruptLock &) = delete;
};
void register_temporary(const std::string &temp, const std::string &output, bool is_dir);
void unregister_temporary(const std::string &temp);
// create_directories(temp) and register it, under the lock; throws
// Error("<temp>: cannot create (<reason>)").
void create_registered_dir(const std::string &temp, const std::string &output);

// A finished output (or a file that goes with others, e.g. a package and
// its C array) removed if the run is interrupted while this lives: "all
// outputs or none".
class RemovedIfInterrupted {
public:
    explicit RemovedIfInterrupted(const std::string &path) : path_(path) { register_temporary(path, path, false); }
    ~RemovedIfInterrupted() { unregister_temporary(path_); }
    RemovedIfInterrupted(const RemovedIfInterrupted &) = delete;
    RemovedIfInterrupted &operator=(const RemovedIfInterrupted &) = delete;

private:
    std::string path_;
};

}  // namespace ct_host
