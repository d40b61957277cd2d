// temp_output.cpp -- see temp_output.hpp.
#include "temp_output.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

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

// the registry of temporaries (see temp_output.hpp)
struct Temporary {
    std::string temp, output;
    bool is_dir;
};
std::recursive_mutex &registry_mutex()
{
    static std::recursive_mutex m;
    return m;
}
std::vector<Temporary> &registry()
{
    static std::vector<Temporary> v;
    return v;
}

const int kInterruptSignals[] = {SIGINT, SIGTERM, SIGHUP};

// The watcher: waits for one of `set`, removes what is registered (holding
// the lock to the end: nothing is created or renamed meanwhile), says so and
// ends the process by that signal.
void watch_interrupts(sigset_t set, std::string program, std::string declared)
{
    int sig = 0;
    while (sigwait(&set, &sig) != 0) {
    }
    registry_mutex().lock();
    std::vector<std::string> outputs;
    for (const Temporary &t : registry()) {
        bool inner = false;  // a file in a registered directory: that directory's output counts
        for (const Temporary &d : registry())
            inner = inner || (d.is_dir && t.temp.compare(0, d.temp.size() + 1, d.temp + "/") == 0);
        bool seen = inner;
        for (const std::string &o : outputs) seen = seen || o == t.output;
        if (!seen) outputs.push_back(t.output);
    }
    for (const Temporary &t : registry()) {
        std::error_code ec;
        if (!t.is_dir)
            ::unlink(t.temp.c_str());
        else
            for (int k = 0; k < 10 && std::filesystem::exists(t.temp, ec); ++k)
                std::filesystem::remove_all(t.temp, ec);  // a writer may add an entry meanwhile: again
    }
    const bool removed = !outputs.empty();
    if (outputs.empty() && !declared.empty()) outputs.push_back(declared);
    std::string names;
    for (const std::string &o : outputs) names += (names.empty() ? "" : ", ") + o;
    const char *sname = sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "a signal";
    const char *nl = ::isatty(2) ? "\n" : "";  // after a progress bar or the terminal's ^C
    if (names.empty())
        std::fprintf(stderr, "%s%s: interrupted by %s\n", nl, program.c_str(), sname);
    else
        std::fprintf(stderr, "%s%s: interrupted by %s: %s not written%s\n", nl, program.c_str(), sname, names.c_str(),
                     removed ? " (its temporaries removed)" : "");
    std::fflush(stderr);
    // the same signal, now with its default action (the process ends)
    ::signal(sig, SIG_DFL);
    sigset_t one;
    sigemptyset(&one);
    sigaddset(&one, sig);
    pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
    ::raise(sig);
    ::_exit(128 + sig);
}
}  // namespace

void remove_temporaries_on_interrupt(const char *program, const std::string &output)
{
    sigset_t set;
    sigemptyset(&set);
    for (int sig : kInterruptSignals) {
        struct sigaction old;
        if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler != SIG_IGN) sigaddset(&set, sig);
    }
    // blocked here, so in every thread started from now on (the watcher too)
    if (pthread_sigmask(SIG_BLOCK, &set, nullptr) != 0) return;
    std::thread(watch_interrupts, set, std::string(program), output).detach();
}

InterruptLock::InterruptLock() { registry_mutex().lock(); }
InterruptLock::~InterruptLock() { registry_mutex().unlock(); }

void register_temporary(const std::string &temp, const std::string &output, bool is_dir)
{
    std::lock_guard<std::recursive_mutex> lock(registry_mutex());
    registry().push_back(Temporary{temp, output, is_dir});
}

void unregister_temporary(const std::string &temp)
{
    std::lock_guard<std::recursive_mutex> lock(registry_mutex());
    std::vector<Temporary> &r = registry();
    for (size_t k = r.size(); k-- > 0;)
        if (r[k].temp == temp) {
            r.erase(r.begin() + (std::ptrdiff_t)k);
            return;
        }
}

void create_registered_dir(const std::string &temp, const std::string &output)
{
    std::lock_guard<std::recursive_mutex> lock(registry_mutex());
    std::error_code ec;
    if (!std::filesystem::create_directories(temp, ec))
        throw Error(temp + ": cannot create (" + (ec ? ec.message() : std::string("it exists")) + ")");
    register_temporary(temp, output, true);
}

TempOutput::TempOutput(const std::string &path) : path_(path)
{
    std::lock_guard<std::recursive_mutex> lock(registry_mutex());  // created and registered at once
    for (int attempt = 0; attempt < 100 && fd_ < 0; attempt++) {  // a clash: another suffix
        tmp_ = path + ".tmp-" + random_suffix();
        fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd_ < 0 && errno != EEXIST)
            throw Error(path + ": cannot create a temporary file next to it (" + std::strerror(errno) + ")");
    }
    if (fd_ < 0) throw Error(path + ": cannot create a temporary file next to it (100 names taken)");
    register_temporary(tmp_, path_, false);
}

TempOutput::~TempOutput()
{
    if (fd_ >= 0) ::close(fd_);
    if (!done_) {
        std::lock_guard<std::recursive_mutex> lock(registry_mutex());
        ::unlink(tmp_.c_str());
        unregister_temporary(tmp_);
    }
}

void TempOutput::fail(int err) const { throw Error(path_ + ": cannot write (" + std::strerror(err) + ")"); }

void TempOutput::commit()
{
    // EINVAL / EROFS: a file system that cannot sync (the data is written)
    if (::fsync(fd_) != 0 && errno != EINVAL && errno != EROFS) fail(errno);
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail(errno);
    std::lock_guard<std::recursive_mutex> lock(registry_mutex());  // renamed and unregistered at once
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0)
        throw Error(path_ + ": cannot rename the temporary file '" + tmp_ + "' onto it (" + std::strerror(errno) + ")");
    unregister_temporary(tmp_);
    done_ = true;
}

}  // namespace ct_host
