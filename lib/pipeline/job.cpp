// One stage job: run `prt STAGE ...` (or merge shards) into a private folder of the store, then commit it.
// The stage runs with that folder as its current directory and sees its inputs as symlinks there, so the
// command line, and anything the stage records from it, is the same whichever store or run it belongs to.
#include "pipeline_internal.h"

#include "core.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <memory>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace prt {

double epochSeconds() {
    using namespace std::chrono;
    return duration<double>(system_clock::now().time_since_epoch()).count();
}

void syncFolder(const std::string& path) {
    int fd = open(path.c_str(), O_RDONLY | O_DIRECTORY);
    if (fd < 0) return;
    fsync(fd);
    close(fd);
}

std::string storeDir(const RunOptions& options) { return options.cacheDir + "/store"; }

std::string absolutePath(const std::string& path) { return fs::absolute(path).lexically_normal().string(); }

std::string shellQuote(const std::string& text) {
    std::string quoted = "'";
    for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

std::string captureCommand(const std::vector<std::string>& args, bool withStderr, int& status) {
    std::string command;
    for (const std::string& arg : args) command += shellQuote(arg) + " ";
    command += withStderr ? "2>&1" : "2>/dev/null";
    std::FILE* pipe = popen(command.c_str(), "r");
    if (!pipe) throw Error("", args[0], "cannot run", kExitFailure);
    std::string output;
    char buffer[4096];
    size_t got;
    while ((got = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) output.append(buffer, got);
    int wait = pclose(pipe);
    status = WIFEXITED(wait) ? WEXITSTATUS(wait) : 128;
    return output;
}

std::map<std::string, std::string> inputHashes(const StageInputs& inputs) {
    std::map<std::string, std::string> hashes;
    for (const auto& [port, file] : inputs) hashes[port] = file.hash;
    return hashes;
}

std::string jobRecordPath(const std::string& runDir, const std::string& stageId, int shardIndex, int shardCount,
                          int pass) {
    std::string part = shardCount <= 1             ? "all"
                       : shardIndex == kMergeJob   ? "merge"
                       : shardIndex == kGatherJob ? "gather"
                                                   : std::to_string(shardIndex) + "of" + std::to_string(shardCount);
    if (pass > 0 || (shardIndex == kGatherJob)) part = "p" + std::to_string(pass) + "." + part;
    return runDir + "/jobs/" + stageId + "." + part + ".json";
}

int stagePasses(const PipelineStage& stage, int shardCount) {
    return shardCount > 1 && stage.spec->passes ? std::max(1, stage.spec->passes(stage.params)) : 1;
}

std::string readableLogTail(const std::string& logPath, size_t lines) {
    std::string text;
    try {
        text = readFileBytes(logPath);
    } catch (const Error&) {
        return "(no log)";
    }
    std::vector<std::string> kept;
    size_t start = 0;
    while (start < text.size()) {
        size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        std::string line = text.substr(start, end - start);
        start = end + 1;
        nlohmann::json record = nlohmann::json::parse(line, nullptr, false);
        if (record.is_object() && record.contains("event")) continue;
        if (record.is_object() && record.contains("msg"))
            line = record.value("level", "") + ": " + record["msg"].get<std::string>();
        if (!line.empty()) kept.push_back(line);
    }
    std::string tail;
    for (size_t i = kept.size() > lines ? kept.size() - lines : 0; i < kept.size(); ++i) tail += "\n  | " + kept[i];
    return tail.empty() ? "(empty log)" : tail;
}

namespace {

struct ChildResult {
    int status = 0;
    uint64_t peakMemoryBytes = 0;
    uint64_t rays = 0;
};

// Runs `args` in `dir` with stdout and stderr appended to `logPath`. The stage logs JSON lines: its progress is
// shown here under `label` and its cost record read for the ray count. The child dies with this process.
ChildResult runLogged(const std::vector<std::string>& args, const std::string& dir, const std::string& logPath,
                      const std::string& label) {
    int log = open(logPath.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    int pipeFds[2];
    if (log < 0 || pipe2(pipeFds, O_CLOEXEC) != 0)
        throw Error(logPath, "", std::string("cannot create the stage log: ") + std::strerror(errno), kExitOutput);
    std::vector<char*> argv;
    for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
    argv.push_back(nullptr);
    std::fflush(nullptr);
    pid_t parent = getpid();
    pid_t pid = fork();
    if (pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent) _exit(127);
        if (chdir(dir.c_str()) != 0 || dup2(log, 1) < 0 || dup2(pipeFds[1], 2) < 0) _exit(127);
        execv(argv[0], argv.data());
        dprintf(2, "{\"level\":\"error\",\"msg\":\"cannot run %s: %s\"}\n", argv[0], std::strerror(errno));
        _exit(127);
    }
    close(pipeFds[1]);
    if (pid < 0) {
        close(pipeFds[0]);
        close(log);
        throw Error("", "", std::string("cannot start a stage: ") + std::strerror(errno), kExitFailure);
    }

    ChildResult result;
    std::map<std::string, std::pair<std::unique_ptr<Progress>, uint64_t>> progress;
    std::string pending;
    char buffer[4096];
    ssize_t got;
    while ((got = read(pipeFds[0], buffer, sizeof(buffer))) != 0) {
        if (got < 0) {
            if (errno == EINTR) continue;
            break;
        }
        if (write(log, buffer, size_t(got)) != got) logWarn("could not write all of " + logPath);
        pending.append(buffer, size_t(got));
        size_t newline;
        while ((newline = pending.find('\n')) != std::string::npos) {
            nlohmann::json line = nlohmann::json::parse(pending.substr(0, newline), nullptr, false);
            pending.erase(0, newline + 1);
            if (!line.is_object()) continue;
            std::string event = line.value("event", "");
            if (event == "cost") result.rays += line.value("rays", uint64_t(0));
            if (event != "progress") continue;
            auto& [bar, done] = progress[line.value("label", "")];
            if (!bar) {
                std::string what = line.value("label", "");
                bar = std::make_unique<Progress>(what.empty() || label.rfind(what, 0) == 0 ? label : label + ": " + what,
                                                 line.value("total", uint64_t(0)));
            }
            uint64_t now = line.value("done", uint64_t(0));
            if (now > done) bar->add(now - done);
            done = std::max(done, now);
        }
    }
    close(pipeFds[0]);
    close(log);
    struct rusage usage {};
    while (wait4(pid, &result.status, 0, &usage) < 0 && errno == EINTR) {
    }
    result.peakMemoryBytes = uint64_t(usage.ru_maxrss) * 1024;
    return result;
}

std::string exitText(int status) {
    if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
    if (WIFSIGNALED(status))
        return "was killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
    return "ended with wait status " + std::to_string(status);
}

std::string paramText(const nlohmann::json& value) {
    char text[32];
    if (value.is_number_integer()) return std::to_string(value.get<int64_t>());
    if (value.is_number()) {
        std::snprintf(text, sizeof(text), "%.17g", value.get<double>());
        return text;
    }
    if (value.is_array()) {
        std::string list;
        for (const nlohmann::json& item : value) list += (list.empty() ? "" : ",") + paramText(item);
        return list;
    }
    return value.get<std::string>();
}

// What a job of a sharded stage changes on the stage's command line (the pass protocol in pipeline.h).
struct JobExtras {
    std::vector<std::pair<std::string, std::string>> outputs; // (flag, file) in place of the spec's outputs, if any
    std::vector<std::string> args;                            // appended as they are ("--pass", "1")
    std::vector<std::pair<std::string, std::string>> files;   // (flag, stored file), linked as "in-<flag>.<ext>"
    std::string listFlag;                                     // then "<listFlag> shard-<I>.<ext>..." (merge, gather)
    std::vector<std::string> listFiles;
};

// The command line of a stage run in its entry folder; inputs are symlinked there as "input-<port>.<ext>", and
// the files of `extras` as named there.
std::vector<std::string> stageCommand(const PipelineStage& stage, const StageInputs& inputs, const RunOptions& options,
                                      const std::string& dir, int shardIndex, int shardCount,
                                      const JobExtras& extras) {
    const StageSpec& spec = *stage.spec;
    std::vector<std::string> args = {options.prt, "--log-json", spec.name};
    for (const ParamSpec& param : spec.params)
        if (param.positional && stage.params.contains(param.name)) args.push_back(paramText(stage.params[param.name]));
    std::vector<std::string> flagged;
    for (const PortSpec& port : spec.inputs) {
        auto input = inputs.find(port.name);
        if (input == inputs.end()) continue;
        std::string link = "input-" + port.name;
        if (!dir.empty()) { // else only the arguments are wanted (stageArguments)
            link += "." + fileExtension(input->second.path);
            fs::create_symlink(absolutePath(input->second.path), dir + "/" + link);
        }
        if (port.flag.empty()) args.push_back(link);
        else flagged.insert(flagged.end(), {port.flag, link});
    }
    args.insert(args.end(), flagged.begin(), flagged.end());
    if (extras.outputs.empty())
        for (const PortSpec& port : spec.outputs) args.insert(args.end(), {port.flag, port.name + "." + port.extension});
    for (const auto& [flag, file] : extras.outputs) args.insert(args.end(), {flag, file});
    for (const ParamSpec& param : spec.params) {
        if (param.positional || !stage.params.contains(param.name)) continue;
        const nlohmann::json& value = stage.params[param.name];
        if (value.is_boolean()) {
            if (value.get<bool>()) args.push_back("--" + param.name);
        } else {
            args.insert(args.end(), {"--" + param.name, paramText(value)});
        }
    }
    if (spec.takesThreads && options.threads > 0) args.insert(args.end(), {"--threads", std::to_string(options.threads)});
    if (shardCount > 1 && shardIndex >= 0)
        args.insert(args.end(), {"--shard", std::to_string(shardIndex) + "/" + std::to_string(shardCount)});
    args.insert(args.end(), extras.args.begin(), extras.args.end());
    for (const auto& [flag, file] : extras.files) {
        std::string link = "in-" + flag.substr(flag.find_first_not_of('-')) + "." + fileExtension(file);
        fs::create_symlink(absolutePath(file), dir + "/" + link);
        args.insert(args.end(), {flag, link});
    }
    if (!extras.listFiles.empty()) {
        args.push_back(extras.listFlag);
        for (size_t i = 0; i < extras.listFiles.size(); ++i) {
            std::string link = "shard-" + std::to_string(i) + "." + fileExtension(extras.listFiles[i]);
            fs::create_symlink(absolutePath(extras.listFiles[i]), dir + "/" + link);
            args.push_back(link);
        }
    }
    return args;
}

} // namespace

std::vector<std::string> stageArguments(const PipelineStage& stage) {
    StageInputs placeholders;
    for (const StageInput& input : stage.inputs) placeholders[input.port] = {"", ""};
    RunOptions noThreads;
    std::vector<std::string> args = stageCommand(stage, placeholders, noThreads, "", 0, 1, JobExtras{});
    args.erase(args.begin(), args.begin() + 2); // prt --log-json
    return args;
}

namespace {

// The files a job leaves, by port: the spec's outputs, or for a pass job or a gather what the pass protocol names.
std::vector<std::pair<std::string, std::string>> jobOutputs(const StageSpec& spec, int shardIndex, int pass,
                                                            int passes) {
    if (shardIndex == kGatherJob) return {{"exitant", "exitant.bin"}};
    if (shardIndex >= 0 && pass < passes - 1) {
        if (pass == 0) return {{"rows", "rows.bin"}, {"hits", "rows.bin.hits"}};
        return {{"rows", "rows.bin"}};
    }
    std::vector<std::pair<std::string, std::string>> outputs;
    for (const PortSpec& port : spec.outputs) outputs.emplace_back(port.name, port.name + "." + port.extension);
    return outputs;
}

nlohmann::json describeOutputs(const std::vector<std::pair<std::string, std::string>>& files, const std::string& dir,
                               const std::string& label) {
    nlohmann::json outputs = nlohmann::json::object();
    for (const auto& [name, file] : files) {
        std::error_code error;
        uintmax_t bytes = fs::file_size(dir + "/" + file, error);
        if (error) throw Error(dir + "/" + file, label, "the stage succeeded but wrote no '" + name + "' output", kExitFailure);
        outputs[name] = {{"file", file}, {"hash", hashFile(dir + "/" + file)}, {"bytes", bytes}};
    }
    return outputs;
}

// Runs `prt STAGE` with `dir` as its current directory; returns its cost and command line.
nlohmann::json runStageIn(const std::string& dir, const PipelineStage& stage, const StageInputs& inputs,
                          const RunOptions& options, int shardIndex, int shardCount, const std::string& label,
                          const JobExtras& extras = {}) {
    double start = nowSeconds();
    std::vector<std::string> args = stageCommand(stage, inputs, options, dir, shardIndex, shardCount, extras);
    logInfo(label + ": running " + stage.spec->name);
    ChildResult child = runLogged(args, dir, dir + "/stage.log", label);
    if (!WIFEXITED(child.status) || WEXITSTATUS(child.status) != 0)
        throw Error("", label, "`prt " + stage.spec->name + "` " + exitText(child.status) + "; its log ends:" +
                                   readableLogTail(dir + "/stage.log", 20),
                    WIFEXITED(child.status) ? WEXITSTATUS(child.status) : kExitInterrupted); // the stage's own code
    for (const fs::directory_entry& item : fs::directory_iterator(dir))
        if (item.is_symlink()) fs::remove(item.path()); // the entry holds outputs, not links to its inputs
    args[0] = "prt";
    return {{"seconds", nowSeconds() - start}, {"rays", child.rays}, {"peak_memory_bytes", child.peakMemoryBytes},
            {"command", args}};
}

// The key of one job of `stage` (the whole stage's key for its merge and for unsharded runs).
nlohmann::json jobIngredients(const PipelineStage& stage, const std::map<std::string, std::string>& hashes,
                              int shardIndex, int shardCount, int pass) {
    if (shardCount <= 1 || shardIndex == kMergeJob) return keyIngredients(stage, hashes);
    int passes = stagePasses(stage, shardCount);
    if (shardIndex == kGatherJob) return keyIngredients(stage, hashes, -1, shardCount, pass);
    return keyIngredients(stage, hashes, shardIndex, shardCount, passes > 1 ? pass : -1);
}

// The file `port` of an earlier job of the stage, from its store entry, whose content findStoreEntry checked against
// the hash the entry's manifest recorded (shard bundles carry no checksum of their own; pass files do).
std::string storedFile(const PipelineStage& stage, const std::map<std::string, std::string>& hashes,
                       const RunOptions& options, int shardIndex, int shardCount, int pass, const std::string& port,
                       const std::string& label) {
    std::string store = storeDir(options);
    std::string key = keyOf(jobIngredients(stage, hashes, shardIndex, shardCount, pass));
    std::optional<StoreEntry> entry = findStoreEntry(store, key, hashMemoFile(options));
    std::string what = shardIndex == kGatherJob ? "the gather" : "shard " + std::to_string(shardIndex + 1) + "/" + std::to_string(shardCount);
    if (stagePasses(stage, shardCount) > 1) what += " of pass " + std::to_string(pass);
    if (!entry || !entry->manifest["outputs"].contains(port))
        throw Error(store, label, what + " (" + key + ") is not in the store", kExitFailure);
    const nlohmann::json& output = entry->manifest["outputs"][port];
    return entry->dir + "/" + output["file"].get<std::string>();
}

// Joins the stored shards of `stage`'s last pass into `dir`, by mergeShardFiles (streamed) or by the stage itself
// (spec.mergeFlag); returns the merge's cost.
nlohmann::json mergeInto(const std::string& dir, const PipelineStage& stage, const StageInputs& inputs,
                         const RunOptions& options, int shardCount, const std::string& label) {
    double start = nowSeconds();
    std::map<std::string, std::string> hashes = inputHashes(inputs);
    const PortSpec& port = stage.spec->outputs.front(); // shardable stages write one bundle
    int last = stagePasses(stage, shardCount) - 1;
    std::vector<std::string> files;
    for (int i = 0; i < shardCount; ++i)
        files.push_back(storedFile(stage, hashes, options, i, shardCount, last, port.name, label));
    if (!stage.spec->mergeFlag.empty()) {
        JobExtras extras;
        extras.listFlag = stage.spec->mergeFlag;
        extras.listFiles = files;
        return runStageIn(dir, stage, inputs, options, kMergeJob, shardCount, label, extras);
    }
    mergeShardFiles(files, dir + "/" + port.name + "." + port.extension);
    writeBytesAtomic(dir + "/stage.log", "merged " + std::to_string(shardCount) + " shards\n");
    return {{"seconds", nowSeconds() - start}, {"rays", 0}, {"peak_memory_bytes", peakMemoryBytes()}};
}

// What a shard job of pass `pass`, or the gather of that pass, adds to the stage's command line.
JobExtras passExtras(const PipelineStage& stage, const std::map<std::string, std::string>& hashes,
                     const RunOptions& options, int shardIndex, int shardCount, int pass, const std::string& label) {
    JobExtras extras;
    int passes = stagePasses(stage, shardCount);
    if (passes <= 1) return extras;
    for (const auto& [port, file] : jobOutputs(*stage.spec, shardIndex, pass, passes))
        if (port != "hits") extras.outputs.emplace_back("-o", file); // hits land next to the rows
    extras.args = {"--pass", std::to_string(pass)};
    if (shardIndex == kGatherJob) {
        extras.listFlag = "--gather";
        for (int i = 0; i < shardCount; ++i)
            extras.listFiles.push_back(storedFile(stage, hashes, options, i, shardCount, pass, "rows", label));
        extras.args.clear(); // the rows name their pass
    } else if (pass > 0) {
        extras.files = {{"--previous", storedFile(stage, hashes, options, shardIndex, shardCount, pass - 1, "rows", label)},
                        {"--hits", storedFile(stage, hashes, options, shardIndex, shardCount, 0, "hits", label)},
                        {"--exitant", storedFile(stage, hashes, options, kGatherJob, shardCount, pass - 1, "exitant", label)}};
    }
    if (shardIndex >= 0 && pass == passes - 1) extras.outputs.clear(); // the last pass writes the shard bundle
    return extras;
}

} // namespace

nlohmann::json runJob(const PipelineStage& stage, const StageInputs& inputs, const RunOptions& options, int shardIndex,
                      int shardCount, bool force, int pass) {
    bool sharded = shardCount > 1;
    bool merge = sharded && shardIndex == kMergeJob, gather = sharded && shardIndex == kGatherJob;
    int passes = stagePasses(stage, shardCount);
    if (!sharded) shardIndex = 0;
    if (merge || !sharded) pass = passes - 1;
    std::string store = storeDir(options);
    std::map<std::string, std::string> hashes = inputHashes(inputs);
    std::string stageKey = keyOf(keyIngredients(stage, hashes));
    nlohmann::json ingredients = jobIngredients(stage, hashes, shardIndex, shardCount, pass);
    std::string key = keyOf(ingredients);
    std::string passLabel = passes > 1 && !merge ? " pass " + std::to_string(pass) : "";
    std::string label = stage.id + passLabel +
                        (merge ? " merge"
                         : gather ? " gather"
                         : sharded ? " shard " + std::to_string(shardIndex + 1) + "/" + std::to_string(shardCount)
                                   : "");

    nlohmann::json record = {{"id", stage.id}, {"stage", stage.spec->name}, {"key", key}, {"host", hostName()},
                             {"start", epochSeconds()}, {"rays", 0}, {"peak_memory_bytes", 0}};
    if (sharded)
        record["shard"] = merge ? nlohmann::json("merge") : gather ? nlohmann::json("gather") : nlohmann::json{shardIndex, shardCount};
    if (passes > 1 && !merge) record["pass"] = pass;
    std::optional<StoreEntry> existing = findStoreEntry(store, key, hashMemoFile(options));
    // A shard (or a pass's gather) whose merged stage is already stored has nothing to add.
    if (!existing && sharded && !merge && !force) existing = findStoreEntry(store, stageKey, hashMemoFile(options));
    if (existing && !force) {
        record.update({{"status", "cached"}, {"end", epochSeconds()}, {"seconds", 0.0},
                       {"outputs", existing->manifest["outputs"]}});
        return record;
    }

    fs::create_directories(store);
    std::string dir = privateEntryPath(store, ".tmp-", key);
    fs::remove_all(dir);
    fs::create_directories(dir);
    try {
        nlohmann::json cost =
            merge ? mergeInto(dir, stage, inputs, options, shardCount, label)
                  : runStageIn(dir, stage, inputs, options, shardIndex, shardCount, label,
                               passExtras(stage, hashes, options, shardIndex, shardCount, pass, label));
        nlohmann::json outputs = describeOutputs(jobOutputs(*stage.spec, merge ? kMergeJob : shardIndex, pass, passes),
                                                 dir, label);
        // A bundle's companion files (a bake's textures), so that copying it out needs no read of the bundle.
        for (const PortSpec& port : stage.spec->outputs)
            if (port.kind == FileKind::Bundle && outputs.contains(port.name) && (merge || !sharded))
                outputs[port.name]["files"] = bundleCompanionNames(dir + "/" + outputs[port.name]["file"].get<std::string>());
        auto hashes = [](const nlohmann::json& described) {
            std::map<std::string, std::string> result;
            for (auto& [name, output] : described.items()) result[name] = output.value("hash", "");
            return result;
        };
        if (existing && hashes(existing->manifest["outputs"]) != hashes(outputs))
            logWarn(label + ": output differs from the stored result of the same key: the stage is not deterministic");
        nlohmann::json manifest = {{"key", key}, {"ingredients", ingredients}, {"outputs", outputs}, {"cost", cost}};
        writeBytesAtomic(dir + "/manifest.json", manifest.dump(2) + "\n");
        commitStoreEntry(store, key, dir, force);
        record.update({{"status", "ran"}, {"end", epochSeconds()}, {"seconds", cost["seconds"]}, {"rays", cost["rays"]},
                       {"peak_memory_bytes", cost["peak_memory_bytes"]}, {"outputs", outputs}});
        return record;
    } catch (Error& e) {
        // Keep the log where a person finds it; the half-built entry goes.
        std::string kept = options.cacheDir + "/failed/" + stage.id + "-" + keyHex(key).substr(0, 12) + ".log";
        std::error_code error;
        fs::create_directories(options.cacheDir + "/failed", error);
        fs::rename(dir + "/stage.log", kept, error);
        fs::remove_all(dir, error);
        throw Error(e.file().empty() ? kept : e.file(), e.place(), e.problem(), e.exitCode());
    } catch (...) {
        std::error_code error;
        fs::remove_all(dir, error);
        throw;
    }
}

nlohmann::json runStageJob(const Pipeline& given, const PipelineStage& givenStage, const RunOptions& options,
                           int shardIndex, int shardCount, bool force, int pass) {
    Pipeline pipeline = given;
    resolveStageOptions(pipeline, options); // the keys must be the ones the planner computed
    auto same = std::find_if(pipeline.stages.begin(), pipeline.stages.end(),
                             [&](const PipelineStage& s) { return s.id == givenStage.id; });
    if (same == pipeline.stages.end()) throw Error(given.file, givenStage.id, "is not a stage of this pipeline", kExitFailure);
    const PipelineStage& stage = *same;
    std::map<std::string, InputFile> pipelineInputs = hashPipelineInputs(pipeline, options);
    std::map<std::string, StoreEntry> entries;
    for (const PipelineStage& upstream : pipeline.stages) {
        if (upstream.id == stage.id) break;
        std::optional<StageInputs> inputs = resolveInputs(upstream, pipelineInputs, entries);
        if (!inputs) continue;
        if (std::optional<StoreEntry> entry = findStoreEntry(storeDir(options), keyOf(keyIngredients(upstream, inputHashes(*inputs))), hashMemoFile(options)))
            entries[upstream.id] = *entry;
    }
    std::optional<StageInputs> inputs = resolveInputs(stage, pipelineInputs, entries);
    if (!inputs) {
        std::string missing;
        for (const StageInput& input : stage.inputs)
            if (!input.sourcePort.empty() && !entries.count(input.source)) missing += (missing.empty() ? "" : ", ") + input.source;
        throw Error(pipeline.file, "stage " + stage.id, "its upstream stages " + missing + " are not in the store", kExitFailure);
    }
    return runJob(stage, *inputs, options, shardIndex, shardCount, force, pass);
}

} // namespace prt
