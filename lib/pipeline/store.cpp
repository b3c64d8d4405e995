// Cache keys and the content-addressed store. An entry is a folder named by its key that appears by one rename,
// complete with manifest.json, so a reader never sees half of one.
#include "pipeline_internal.h"

#include "core.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <unistd.h>

namespace fs = std::filesystem;

namespace prt {

nlohmann::json keyIngredients(const PipelineStage& stage, const std::map<std::string, std::string>& inputHashes,
                              int shardIndex, int shardCount, int pass) {
    nlohmann::json ingredients = {{"stage", stage.spec->name},
                                  {"version", stage.version},
                                  {"params", stage.params},
                                  {"inputs", inputHashes}};
    if (shardCount > 0) ingredients["shard"] = {shardIndex, shardCount};
    if (pass >= 0) ingredients["pass"] = pass;
    if (!stage.resolved.is_null()) ingredients["resolved"] = stage.resolved;
    if (!stage.build.is_null()) ingredients["build"] = stage.build;
    return ingredients;
}

namespace {

// Asks options.askPrt, once per question and process. There is no fallback to running the binary: a key is
// never computed by starting a process (a fresh prt-driver loads about 270 shared libraries).
nlohmann::json askPrt(const std::vector<std::string>& args, const RunOptions& options) {
    static std::mutex mutex;
    static std::map<std::vector<std::string>, nlohmann::json> answers;
    std::lock_guard<std::mutex> lock(mutex);
    auto known = answers.find(args);
    if (known != answers.end()) return known->second;
    if (!options.askPrt)
        throw Error("", "cache key", "RunOptions::askPrt is not set: the stages' options are resolved in process "
                                     "(prt::cli::inProcessAnswers)", kExitFailure);
    nlohmann::json answer = options.askPrt(args);
    if (!answer.is_object()) {
        std::string command;
        for (const std::string& arg : args) command += (command.empty() ? "" : " ") + arg;
        throw Error("", "cache key", "`" + command + "` has no JSON answer", kExitFailure);
    }
    return answers[args] = answer;
}

} // namespace

void resolveStageOptions(Pipeline& pipeline, const RunOptions& options) {
    nlohmann::json build = askPrt({options.prt, "--build-info"}, options);
    for (PipelineStage& stage : pipeline.stages) {
        std::vector<std::string> args = stageArguments(stage);
        args.insert(args.begin(), {options.prt, "--resolved-options"});
        stage.resolved = askPrt(args, options);
        stage.build = build;
    }
}

// nlohmann::json keeps object keys sorted, so dump() is canonical.
std::string keyOf(const nlohmann::json& ingredients) {
    std::string text = ingredients.dump();
    return hashBytes(text.data(), text.size());
}

std::string keyHex(const std::string& key) {
    size_t colon = key.find(':');
    return colon == std::string::npos ? key : key.substr(colon + 1);
}

std::string privateEntryPath(const std::string& store, const std::string& prefix, const std::string& key) {
    return store + "/" + prefix + keyHex(key) + "-" + hostName() + "-" + std::to_string(getpid());
}

std::optional<StoreEntry> findStoreEntry(const std::string& store, const std::string& key, const std::string& memoFile) {
    StoreEntry entry;
    entry.dir = store + "/" + keyHex(key);
    std::error_code error;
    if (!fs::is_directory(entry.dir, error)) return std::nullopt;
    const std::string manifest = entry.dir + "/manifest.json";
    if (fs::is_regular_file(manifest, error))
        entry.manifest = nlohmann::json::parse(readFileBytes(manifest), nullptr, false);
    bool intact = entry.manifest.is_object() && entry.manifest.value("key", "") == key &&
                  entry.manifest.contains("outputs") && entry.manifest["outputs"].is_object();
    for (auto& [port, output] : intact ? entry.manifest["outputs"].items() : nlohmann::json::object().items()) {
        if (!output.is_object() || !output.contains("file") || !output["file"].is_string()) {
            intact = false;
            break;
        }
        const std::string file = entry.dir + "/" + output["file"].get<std::string>();
        uintmax_t bytes = fs::file_size(file, error);
        if (error || bytes != output.value("bytes", uintmax_t(0))) intact = false;
        else if (output.contains("hash") && output["hash"].is_string() && hashFileMemo(file, memoFile) != output["hash"])
            intact = false;
        if (!intact) break;
    }
    if (!intact) {
        // Out of the way (an entry is renamed as a whole, so readers see it or nothing), so the rebuilt one can be
        // committed under the key; a kill during the removal leaves an .old- folder that sweepStore removes.
        logWarn("store entry " + entry.dir + " does not match its manifest (a file cut, overwritten or missing): "
                "removed, and the stage runs again");
        const std::string aside = privateEntryPath(store, ".old-", key);
        if (std::rename(entry.dir.c_str(), aside.c_str()) == 0) fs::remove_all(aside, error);
        return std::nullopt;
    }
    return entry;
}

void commitStoreEntry(const std::string& store, const std::string& key, const std::string& tmpDir, bool replace) {
    std::string final = store + "/" + keyHex(key);
    syncFolder(tmpDir);
    checkpoint("before store commit");
    if (std::rename(tmpDir.c_str(), final.c_str()) == 0) {
        syncFolder(store);
        checkpoint("after store commit");
        return;
    }
    if (errno != EEXIST && errno != ENOTEMPTY)
        throw Error(final, "", std::string("cannot commit store entry: ") + std::strerror(errno), kExitOutput);
    if (!replace) { // another run stored the same key first; readers may be using its files
        fs::remove_all(tmpDir);
        return;
    }
    // A forced rerun replaces the entry: between the two renames the key is simply absent, which is consistent.
    std::string old = privateEntryPath(store, ".old-", key);
    if (std::rename(final.c_str(), old.c_str()) != 0 || std::rename(tmpDir.c_str(), final.c_str()) != 0)
        throw Error(final, "", std::string("cannot replace store entry: ") + std::strerror(errno), kExitOutput);
    syncFolder(store);
    fs::remove_all(old);
}

void sweepStore(const std::string& store) {
    std::error_code error;
    if (!fs::is_directory(store, error)) return;
    std::string host = hostName();
    for (const fs::directory_entry& item : fs::directory_iterator(store, error)) {
        std::string name = item.path().filename().string();
        if (name.rfind(".tmp-", 0) != 0 && name.rfind(".old-", 0) != 0) continue;
        // .tmp-<32 hex>-<host>-<pid>: host names may hold '-', pids may not.
        size_t dash = name.rfind('-');
        if (name.size() < 5 + 32 + 2 || dash == std::string::npos) continue;
        std::string owner = name.substr(5 + 32 + 1, dash - (5 + 32 + 1));
        const long pid = std::atol(name.c_str() + dash + 1);
        // Only this host can tell whether the writer lives; another node's writer may still be at work.
        if (owner != host || !processHasEnded(pid)) continue;
        fs::remove_all(item.path(), error);
    }
}

} // namespace prt
