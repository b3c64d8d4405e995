// Store garbage collection: the policy that says which entries a store keeps, and their crash-safe removal.
// docs/pipelines.md ("Store garbage collection") states the policy for users.
#include "pipeline_internal.h"

#include "core.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>

namespace fs = std::filesystem;

namespace prt {

namespace {

// Bytes of the regular files under `dir` (0 when it cannot be read).
uint64_t folderBytes(const fs::path& dir) {
    uint64_t bytes = 0;
    std::error_code error;
    for (fs::recursive_directory_iterator item(dir, error), end; !error && item != end; item.increment(error))
        if (item->is_regular_file(error)) bytes += item->file_size(error);
    return bytes;
}

bool isEntryName(const std::string& name) {
    return name.size() == 32 && name.find_first_not_of("0123456789abcdef") == std::string::npos;
}

} // namespace

// Removes the entry STORE/<hex> as a whole: one rename takes it out of the store (from then its key is simply
// absent, which a reader or a later run treats as "not stored"), then its files go. A kill after the rename
// leaves a .old- folder whose writer is dead, which sweepStore removes; a kill before it leaves the entry intact.
// Returns the bytes it held, or 0 when there was no such entry.
uint64_t removeStoreEntry(const std::string& store, const std::string& hex) {
    std::error_code error;
    fs::path entry = fs::path(store) / hex;
    if (!fs::is_directory(entry, error)) return 0;
    uint64_t bytes = folderBytes(entry);
    std::string old = privateEntryPath(store, ".old-", "xxh128:" + hex);
    checkpoint("before store removal");
    if (std::rename(entry.c_str(), old.c_str()) != 0) {
        if (errno == ENOENT) return 0; // another collector took it first
        throw Error(entry.string(), "", std::string("cannot remove store entry: ") + std::strerror(errno), kExitOutput);
    }
    syncFolder(store);
    checkpoint("after store removal");
    fs::remove_all(old, error);
    return bytes;
}

nlohmann::json collectIntermediates(const std::string& store, const std::vector<std::string>& finalKeys,
                                    const std::vector<std::string>& jobKeys) {
    std::set<std::string> keep(finalKeys.begin(), finalKeys.end());
    nlohmann::json removed = nlohmann::json::array();
    uint64_t bytes = 0;
    for (const std::string& key : std::set<std::string>(jobKeys.begin(), jobKeys.end())) {
        if (keep.count(key)) continue;
        uint64_t freed = removeStoreEntry(store, keyHex(key));
        if (freed == 0) continue;
        removed.push_back(key);
        bytes += freed;
    }
    return {{"removed", removed.size()}, {"removed_bytes", bytes}, {"store_bytes", folderBytes(store)}};
}

nlohmann::json collectStore(const RunOptions& options, bool dryRun) {
    std::string store = storeDir(options);
    // What the recorded runs need: the entry of every stage of each pipeline's last run (CACHE/runs/NAME.last.json
    // holds their key ingredients).
    std::set<std::string> keep;
    std::error_code error;
    for (const fs::directory_entry& item : fs::directory_iterator(options.cacheDir + "/runs", error)) {
        std::string name = item.path().filename().string();
        if (name.size() < 10 || name.compare(name.size() - 10, 10, ".last.json") != 0) continue;
        nlohmann::json last = nlohmann::json::parse(readFileBytes(item.path().string()), nullptr, false);
        if (!last.is_object())
            throw Error(item.path().string(), "", "is not a run record (JSON object): refusing to collect the store "
                                                  "without knowing what it needs", kExitInput);
        for (auto& [stage, ingredients] : last.items()) keep.insert(keyHex(keyOf(ingredients)));
    }
    if (!dryRun) sweepStore(store);
    nlohmann::json removed = nlohmann::json::array();
    uint64_t removedBytes = 0, keptBytes = 0;
    size_t kept = 0;
    std::vector<std::string> names;
    for (const fs::directory_entry& item : fs::directory_iterator(store, error)) names.push_back(item.path().filename().string());
    std::sort(names.begin(), names.end());
    for (const std::string& name : names) {
        if (!isEntryName(name)) continue; // .tmp-/.old- folders belong to their writers (sweepStore)
        uint64_t bytes = folderBytes(fs::path(store) / name);
        if (keep.count(name)) {
            keptBytes += bytes;
            ++kept;
            continue;
        }
        if (!dryRun) bytes = removeStoreEntry(store, name);
        removed.push_back({{"key", "xxh128:" + name}, {"bytes", bytes}});
        removedBytes += bytes;
    }
    return {{"store", store}, {"dry_run", dryRun}, {"kept", kept}, {"kept_bytes", keptBytes},
            {"removed", removed}, {"removed_bytes", removedBytes}};
}

} // namespace prt
