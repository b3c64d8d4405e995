#include "core.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <signal.h>
#include <fstream>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

namespace prt {

std::string readFileBytes(const std::string& path) {
    struct stat info;
    if (stat(path.c_str(), &info) != 0) throw Error(path, "", std::string("cannot open: ") + std::strerror(errno));
    if (S_ISDIR(info.st_mode)) throw Error(path, "", "is a folder, not a file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path, "", std::string("cannot open: ") + std::strerror(errno));
    std::ostringstream bytes;
    bytes << in.rdbuf();
    if (in.bad()) throw Error(path, "", "read failed");
    return bytes.str();
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

static std::string temporaryPath(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    return (parent / temporaryPrefix(path)).string() + std::to_string(getpid()) + "-" + std::to_string(counter++);
}

// Removes what writers of `path` on this host left when they were killed: ".NAME.tmp-HOST-PID-N" files of
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

// fsync the file and its folder so a crash after rename never exposes an empty or partial artifact.
static void syncPath(const std::string& path, bool directory) {
    int fd = open(path.c_str(), directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
    if (fd < 0) return;
    fsync(fd);
    close(fd);
}

void writeFileAtomic(const std::string& path, const std::function<void(const std::string& tmpPath)>& write) {
    sweepTemporaryFiles(path);
    std::string tmp = temporaryPath(path);
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
