#include "core.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <signal.h>
#include <fstream>
#include <sstream>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

namespace prt {

std::string readFileBytes(const std::string& path) {
    struct stat info;
    if (stat(path.c_str(), &info) != 0) throw Error(path, "", std::string("cannot open: ") + std::strerror(errno));
    if (S_ISDIR(info.st_mode)) throw Error(path, "", "is a folder, not a file");
    if (!S_ISREG(info.st_mode)) throw Error(path, "", "is not a regular file (a device, a FIFO or a socket)");
    // Whole-file reads are bounded with the elements a file may claim: 4 GiB, or 4 bytes per element of a cap
    // raised past 2^30.
    const uint64_t limit = std::max<uint64_t>(uint64_t(1) << 32, 4 * maxElements());
    if (uint64_t(info.st_size) > limit)
        throw Error(path, "", "is " + std::to_string(uint64_t(info.st_size)) + " bytes, above the limit of " +
                                  std::to_string(limit) + " bytes for a file read whole (4 bytes per element of "
                                  "PRT_MAX_ELEMENTS, at least 4 GiB; set PRT_MAX_ELEMENTS=N in the environment to raise it)");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path, "", std::string("cannot open: ") + std::strerror(errno));
    std::ostringstream bytes;
    bytes << in.rdbuf();
    if (in.bad()) throw Error(path, "", "read failed");
    return bytes.str();
}

std::string resolvedInside(const std::string& path, const std::string& folder) {
    std::error_code error;
    const std::filesystem::path base = std::filesystem::weakly_canonical(std::filesystem::absolute(folder, error), error);
    if (error) return "";
    const std::filesystem::path resolved = std::filesystem::weakly_canonical(std::filesystem::absolute(path, error), error);
    if (error) return "";
    // Element by element (a trailing "/" on the base is an empty last element).
    auto mismatch = std::mismatch(base.begin(), base.end(), resolved.begin(), resolved.end());
    const bool inside = (mismatch.first == base.end() || (std::next(mismatch.first) == base.end() && mismatch.first->empty())) &&
                        resolved != base && mismatch.second != resolved.end();
    return inside ? resolved.string() : "";
}

std::string hostName() {
    char name[256] = {};
    gethostname(name, sizeof name - 1);
    return name;
}

bool processHasEnded(long pid) { return pid > 0 && kill(pid_t(pid), 0) != 0 && errno == ESRCH; }

// ".NAME.tmp-HOST-" for `path`'s name (an output folder may be shared by a farm's hosts): what every temporary name
// of `path` written on this host starts with.
static std::string temporaryPrefix(const std::string& path) {
    const std::string name = std::filesystem::path(path).filename().string();
    return "." + name + ".tmp-" + hostName() + "-";
}

// Removes what writers of `path` on this host left when they were killed: ".NAME.tmp-HOST-PID-..." files of
// processes that no longer exist. Another host's, and a live process's, are left alone.
static void sweepTemporaryFiles(const std::string& path) {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    const std::string prefix = temporaryPrefix(path);
    std::error_code error;
    for (const auto& item : std::filesystem::directory_iterator(parent.empty() ? "." : parent, error)) {
        const std::string name = item.path().filename().string();
        if (name.compare(0, prefix.size(), prefix) != 0) continue;
        const long pid = std::atol(name.c_str() + prefix.size());
        if (!processHasEnded(pid)) continue;
        std::filesystem::remove(item.path(), error);
    }
}

std::string freshTemporaryPath(const std::string& path, const std::string& suffix) {
    static std::atomic<unsigned> counter{0};
    sweepTemporaryFiles(path);
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    for (int attempt = 0;; ++attempt) {
        // 64 random bits: nobody can plant a link at the name before it is made (kernel entropy, not the seed of
        // any output, so outputs stay bit-identical).
        uint64_t random = 0;
        if (getrandom(&random, sizeof random, 0) != ssize_t(sizeof random))
            random = uint64_t(std::chrono::steady_clock::now().time_since_epoch().count()) * 0x9e3779b97f4a7c15ull;
        char hex[17];
        std::snprintf(hex, sizeof hex, "%016llx", (unsigned long long)random);
        const std::string tmp = (parent / temporaryPrefix(path)).string() + std::to_string(getpid()) + "-" +
                                std::to_string(counter++) + "-" + hex + suffix;
        // Made here, as a new regular file: never through a link or over a file already there.
        const int fd = open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
        if (fd >= 0) {
            close(fd);
            return tmp;
        }
        if (errno != EEXIST || attempt >= 8)
            throw Error(path, "", std::string("cannot create a temporary file beside it: ") + std::strerror(errno),
                        kExitOutput);
    }
}

// fsync the file and its folder so a crash after rename never exposes an empty or partial artifact.
static void syncPath(const std::string& path, bool directory) {
    int fd = open(path.c_str(), directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
    if (fd < 0) return;
    fsync(fd);
    close(fd);
}

void writeFileAtomic(const std::string& path, const std::function<void(const std::string& tmpPath)>& write) {
    std::string tmp = freshTemporaryPath(path);
    try {
        write(tmp);
        struct stat info;
        if (stat(tmp.c_str(), &info) != 0) throw Error(path, "", "writer produced no file", kExitOutput);
        syncPath(tmp, false);
        checkpoint("before rename");
        if (std::rename(tmp.c_str(), path.c_str()) != 0)
            throw Error(path, "", std::string("cannot rename into place: ") + std::strerror(errno), kExitOutput);
    } catch (...) {
        std::remove(tmp.c_str());
        throw;
    }
    size_t slash = path.find_last_of('/');
    syncPath(slash == std::string::npos ? "." : path.substr(0, slash + 1), true);
    checkpoint("after rename");
}

void writeBytesAtomic(const std::string& path, std::string_view bytes) {
    writeFileAtomic(path, [&](const std::string& tmp) {
        std::FILE* file = std::fopen(tmp.c_str(), "wb");
        if (!file) throw Error(path, "", std::string("cannot create: ") + std::strerror(errno), kExitOutput);
        size_t written = std::fwrite(bytes.data(), 1, bytes.size(), file);
        bool ok = written == bytes.size() && std::fflush(file) == 0;
        ok = std::fclose(file) == 0 && ok;
        if (!ok) throw Error(path, "", std::string("write failed: ") + std::strerror(errno), kExitOutput);
    });
}

} // namespace prt
