// The stat-keyed memo of file content hashes (hashFileMemo in pipeline.h): a cached `prt run` stats its inputs
// and its driver instead of reading them.
//
// The rule. A memo entry is (absolute path, size, mtime ns, ctime ns, inode, device) -> hash. It is used only when
// all six match the file now, and it is recorded only when
//   - the file's stat is the same before and after it was hashed (nobody wrote it meanwhile), and
//   - its mtime and its ctime are at least kRacyNanoseconds older than the moment the hash began.
// Any write changes ctime, and ctime cannot be set back (utimensat sets mtime, and moves ctime to now), so a
// rewritten file, whatever its size and mtime, no longer matches its entry. The second condition is git's "racy"
// rule: a file written in the same timestamp tick as it was hashed could change again without changing its
// times, so such a hash is answered to this call only, never recorded, and taken again when next asked.
// Timestamps are at most one second coarse on the filesystems prt runs on; a coarser one (FAT: 2 s) defeats the
// rule.
#include "pipeline_internal.h"

#include "core.h"

#include <chrono>
#include <filesystem>
#include <map>
#include <mutex>
#include <sys/stat.h>

namespace prt {

namespace {

constexpr int64_t kRacyNanoseconds = 2'000'000'000;
constexpr size_t kMaxEntries = 4096; // the memo file stays small: the oldest hashes go first

struct FileStat {
    int64_t size = -1, mtime = 0, ctime = 0;
    uint64_t inode = 0, device = 0;
    bool operator==(const FileStat&) const = default;
};

bool statFile(const std::string& path, FileStat& stat) {
    struct stat s {};
    if (::stat(path.c_str(), &s) != 0) return false;
    stat = {int64_t(s.st_size), int64_t(s.st_mtim.tv_sec) * 1'000'000'000 + s.st_mtim.tv_nsec,
            int64_t(s.st_ctim.tv_sec) * 1'000'000'000 + s.st_ctim.tv_nsec, uint64_t(s.st_ino), uint64_t(s.st_dev)};
    return true;
}

int64_t nowNanoseconds() {
    using namespace std::chrono;
    return duration_cast<nanoseconds>(system_clock::now().time_since_epoch()).count();
}

nlohmann::json statJson(const FileStat& s) {
    return {{"size", s.size}, {"mtime_ns", s.mtime}, {"ctime_ns", s.ctime}, {"inode", s.inode}, {"device", s.device}};
}

struct Memo {
    bool loaded = false;
    nlohmann::json entries = nlohmann::json::object(); // absolute path -> stat fields, "hash", "hashed_at"
};

std::mutex memoMutex;
std::map<std::string, Memo> memos; // by memo file; "" is this process's only

void saveMemo(const std::string& memoFile, Memo& memo) {
    while (memo.entries.size() > kMaxEntries) {
        auto oldest = memo.entries.begin();
        for (auto it = memo.entries.begin(); it != memo.entries.end(); ++it)
            if (it.value().value("hashed_at", int64_t(0)) < oldest.value().value("hashed_at", int64_t(0))) oldest = it;
        memo.entries.erase(oldest);
    }
    try {
        std::error_code error;
        std::filesystem::create_directories(std::filesystem::path(memoFile).parent_path(), error);
        writeBytesAtomic(memoFile, memo.entries.dump() + "\n");
    } catch (const Error& e) {
        logWarn("cannot save the hash memo: " + std::string(e.what())); // a memo: the next run hashes again
    }
}

} // namespace

std::string hashFileMemo(const std::string& path, const std::string& memoFile) {
    std::string absolute = absolutePath(path);
    FileStat before;
    if (!statFile(absolute, before)) return hashFile(path); // throws, naming the file
    {
        std::lock_guard<std::mutex> lock(memoMutex);
        Memo& memo = memos[memoFile];
        if (!memo.loaded && !memoFile.empty()) {
            std::error_code error;
            if (std::filesystem::is_regular_file(memoFile, error)) {
                nlohmann::json read = nlohmann::json::parse(readFileBytes(memoFile), nullptr, false);
                if (read.is_object()) memo.entries = std::move(read);
            }
        }
        memo.loaded = true;
        auto entry = memo.entries.find(absolute);
        if (entry != memo.entries.end() && entry->is_object() && entry->contains("hash") &&
            entry->value("size", int64_t(-2)) == before.size && entry->value("mtime_ns", int64_t(0)) == before.mtime &&
            entry->value("ctime_ns", int64_t(0)) == before.ctime && entry->value("inode", uint64_t(0)) == before.inode &&
            entry->value("device", uint64_t(0)) == before.device && (*entry)["hash"].is_string())
            return (*entry)["hash"].get<std::string>();
    }
    int64_t start = nowNanoseconds();
    std::string hash = hashFile(path);
    FileStat after;
    bool settled = statFile(absolute, after) && after == before && before.mtime <= start - kRacyNanoseconds &&
                   before.ctime <= start - kRacyNanoseconds;
    std::lock_guard<std::mutex> lock(memoMutex);
    Memo& memo = memos[memoFile];
    if (!settled) {
        memo.entries.erase(absolute);
        return hash;
    }
    nlohmann::json entry = statJson(before);
    entry["hash"] = hash;
    entry["hashed_at"] = start;
    memo.entries[absolute] = entry;
    if (!memoFile.empty()) saveMemo(memoFile, memo);
    return hash;
}

std::string hashMemoFile(const RunOptions& options) { return options.cacheDir + "/hash-memo.json"; }

} // namespace prt
