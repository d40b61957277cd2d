// temp_output.cpp -- see temp_output.hpp.
#include "temp_output.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <random>

#include "terrain.hpp"  // Error

namespace ct_host {

namespace {
std::string random_suffix()
{
    static std::mutex m;
    static std::mt19937_64 rng{std::random_device{}() ^ ((uint64_t)::getpid() << 32)};
    std::lock_guard<std::mutex> lock(m);
    char s[17];
    std::snprintf(s, sizeof s, "%08x", (unsigned)(rng() & 0xffffffffu));
    return s;
}
}  // namespace

TempOutput::TempOutput(const std::string &path) : path_(path)
{
    for (int attempt = 0; attempt < 100 && fd_ < 0; attempt++) {  // a clash: another suffix
        tmp_ = path + ".tmp-" + random_suffix();
        fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd_ < 0 && errno != EEXIST)
            throw Error(path + ": cannot create a temporary file next to it (" + std::strerror(errno) + ")");
    }
    if (fd_ < 0) throw Error(path + ": cannot create a temporary file next to it (100 names taken)");
}

TempOutput::~TempOutput()
{
    if (fd_ >= 0) ::close(fd_);
    if (!done_) ::unlink(tmp_.c_str());
}

void TempOutput::fail(int err) const { throw Error(path_ + ": cannot write (" + std::strerror(err) + ")"); }

void TempOutput::commit()
{
    // EINVAL / EROFS: a file system that cannot sync (the data is written)
    if (::fsync(fd_) != 0 && errno != EINVAL && errno != EROFS) fail(errno);
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail(errno);
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0)
        throw Error(path_ + ": cannot rename the temporary file '" + tmp_ + "' onto it (" + std::strerror(errno) + ")");
    done_ = true;
}

}  // namespace ct_host
