// `prt run`: plan which stages run and why, run them with an executor, copy the declared outputs, and write the
// run report.
#include "pipeline_internal.h"

#include "bundle_stream.h"
#include "core.h"
#include "json_input.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <set>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace prt {

namespace {

// The files a mesh input reads besides itself, which its cache key must cover too: a .gltf's external buffers and
// images (URIs that are not data: URIs), an OBJ's MTL file and the texture maps the MTL names. Names are resolved
// next to the input; ones that do not exist are left out (the stage reports them). A .glb is self-contained.
std::vector<std::string> meshCompanions(const std::string& path) {
    std::vector<std::string> files;
    const fs::path folder = fs::path(path).parent_path();
    auto add = [&](std::string name) {
        for (char& c : name)
            if (c == '\\') c = '/';
        std::error_code error;
        fs::path file = folder / name;
        if (!name.empty() && fs::is_regular_file(file, error)) files.push_back(file.string());
    };
    const std::string extension = fileExtension(path);
    if (extension == "gltf") {
        nlohmann::json gltf = readJsonFile(path, size_t(1) << 30);
        for (const char* array : {"buffers", "images"})
            if (gltf.contains(array) && gltf[array].is_array())
                for (const nlohmann::json& item : gltf[array])
                    if (item.is_object() && item.contains("uri") && item["uri"].is_string() &&
                        item["uri"].get<std::string>().rfind("data:", 0) != 0)
                        add(item["uri"].get<std::string>());
    } else if (extension == "obj") {
        // The last word of every line that starts with `keyword` (map_Kd options come before the file name).
        auto lastWords = [](const std::string& text, const std::string& keyword) {
            std::vector<std::string> words;
            std::istringstream lines(text);
            for (std::string line; std::getline(lines, line);) {
                std::istringstream tokens(line);
                std::string first, word, last;
                if (!(tokens >> first) || first.rfind(keyword, 0) != 0) continue;
                while (tokens >> word) last = word;
                if (!last.empty()) words.push_back(last);
            }
            return words;
        };
        for (const std::string& library : lastWords(readFileBytes(path), "mtllib")) {
            size_t before = files.size();
            add(library);
            if (files.size() == before) continue;
            for (const std::string& map : lastWords(readFileBytes(files.back()), "map_")) add(map);
        }
    }
    return files;
}

} // namespace

std::map<std::string, InputFile> hashPipelineInputs(const Pipeline& pipeline, const RunOptions& options) {
    std::map<std::string, InputFile> files;
    std::string memo = hashMemoFile(options);
    for (const PipelineInput& input : pipeline.inputs) {
        std::string hash = hashFileMemo(input.path, memo);
        // A mesh that reads other files (a .gltf's buffers and images, an OBJ's MTL and textures): its hash is that
        // of the list of all their hashes, so that a changed texture reruns meshprep.
        std::vector<std::string> companions =
            input.kind == FileKind::Mesh ? meshCompanions(input.path) : std::vector<std::string>();
        if (!companions.empty()) {
            std::string all = hash;
            for (const std::string& file : companions) all += "\n" + file + " " + hashFileMemo(file, memo);
            hash = hashBytes(all.data(), all.size());
        }
        files[input.name] = {input.path, hash};
    }
    return files;
}

std::optional<StageInputs> resolveInputs(const PipelineStage& stage, const std::map<std::string, InputFile>& pipelineInputs,
                                         const std::map<std::string, StoreEntry>& entries) {
    StageInputs inputs;
    for (const StageInput& wire : stage.inputs) {
        if (wire.sourcePort.empty()) {
            inputs[wire.port] = pipelineInputs.at(wire.source);
            continue;
        }
        auto entry = entries.find(wire.source);
        if (entry == entries.end()) return std::nullopt;
        const nlohmann::json& output = entry->second.manifest["outputs"][wire.sourcePort];
        inputs[wire.port] = {entry->second.dir + "/" + output["file"].get<std::string>(), output["hash"].get<std::string>()};
    }
    return inputs;
}

std::vector<std::string> bundleCompanionNames(const std::string& bundleFile) {
    std::vector<std::string> names;
    // The header alone (its checksum checked as readBundle checks it): the layers' values are never needed here.
    for (const Layer& layer : readBundleHeader(bundleFile).bundle.layers) {
        if (!layer.params.contains("files") || !layer.params["files"].is_array()) continue;
        for (const nlohmann::json& name : layer.params["files"]) {
            if (!name.is_string())
                throw Error(bundleFile, "layer \"" + layer.name + "\" params.files", "holds a " +
                            std::string(name.type_name()) + ", not a file name", kExitInput);
            fs::path relative = name.get<std::string>();
            if (relative.is_absolute() || relative.filename() != relative)
                throw Error(bundleFile, "layer \"" + layer.name + "\" params.files",
                            "'" + relative.string() + "' is not a plain file name next to the bundle", kExitFailure);
            names.push_back(relative.string());
        }
    }
    return names;
}

namespace {

enum class Action { Cached, Run, Skip };

const char* actionName(Action action) {
    return action == Action::Cached ? "cached" : action == Action::Run ? "run" : "skip";
}

struct StagePlan {
    Action action = Action::Skip;
    std::string key;    // empty while an upstream stage has yet to run
    std::string reason;
    int shards = 1;
    bool selected = true; // --only/--from may leave a stage out: it is then never executed
    bool force = false;   // rerun whatever the store holds
};

// Why a stage's key differs from the one it had at the pipeline's last run, as "parameter samples 256 -> 512; ...".
// `hashes` is null while upstream stages have yet to run.
std::string changeReason(const nlohmann::json& last, const PipelineStage& stage,
                         const std::map<std::string, std::string>* hashes) {
    if (!last.is_object()) return "never run";
    std::vector<std::string> changes;
    if (last.value("version", 0) != stage.version)
        changes.push_back("code version " + std::to_string(last.value("version", 0)) + " -> " + std::to_string(stage.version));
    const nlohmann::json& before = last.contains("params") ? last["params"] : nlohmann::json::object();
    std::set<std::string> names;
    for (auto& [name, value] : before.items()) names.insert(name);
    for (auto& [name, value] : stage.params.items()) names.insert(name);
    for (const std::string& name : names) {
        if (!before.contains(name)) changes.push_back("parameter " + name + " added (" + stage.params[name].dump() + ")");
        else if (!stage.params.contains(name)) changes.push_back("parameter " + name + " removed");
        else if (before[name] != stage.params[name])
            changes.push_back("parameter " + name + " " + before[name].dump() + " -> " + stage.params[name].dump());
    }
    if (hashes) {
        const nlohmann::json& inputs = last.contains("inputs") ? last["inputs"] : nlohmann::json::object();
        for (auto& [port, hash] : *hashes)
            if (inputs.value(port, "") != hash) changes.push_back("input " + port + " changed");
    }
    if (changes.empty()) return hashes ? "not in the store (removed, or its run was interrupted)" : "";
    std::string text;
    for (const std::string& change : changes) text += (text.empty() ? "" : "; ") + change;
    return text;
}

// What each stage will do and why. Keys are known down to the first stages that must run; below them they
// wait on those stages' outputs. `entries` receives the stored results the plan relies on.
std::vector<StagePlan> planStages(const Pipeline& pipeline, const RunOptions& options,
                                  const std::map<std::string, InputFile>& pipelineInputs, const nlohmann::json& last,
                                  std::map<std::string, StoreEntry>& entries) {
    if (!options.only.empty() && !options.from.empty())
        throw Error("", "--only/--from", "give one of them, not both", kExitUsage);
    std::string chosen = !options.only.empty() ? options.only : options.from;
    size_t chosenIndex = chosen.empty() ? 0 : findStage(pipeline, chosen);
    std::string forcedBy = options.force          ? "forced (--force)"
                           : !options.only.empty() ? "forced (--only " + options.only + ")"
                                                   : "forced (--from " + options.from + ")";

    std::vector<StagePlan> plans(pipeline.stages.size());
    for (size_t i = 0; i < plans.size(); ++i) {
        const PipelineStage& stage = pipeline.stages[i];
        StagePlan& plan = plans[i];
        // --only takes one stage, --from it and everything downstream (stages are in topological order).
        plan.selected = chosen.empty() || i == chosenIndex;
        if (!options.from.empty() && i > chosenIndex)
            for (const StageInput& input : stage.inputs)
                if (!input.sourcePort.empty() && plans[findStage(pipeline, input.source)].selected) plan.selected = true;
        plan.force = options.force || (!chosen.empty() && plan.selected);
        plan.shards = stage.shards;
        std::string refusal = stage.spec->shardRefusal ? stage.spec->shardRefusal(stage.params) : "";
        if (options.shards > 0 && stage.spec->shardable && refusal.empty()) plan.shards = options.shards;

        std::optional<StageInputs> inputs = resolveInputs(stage, pipelineInputs, entries);
        std::map<std::string, std::string> hashes = inputs ? inputHashes(*inputs) : std::map<std::string, std::string>();
        std::optional<StoreEntry> entry;
        if (inputs) {
            plan.key = keyOf(keyIngredients(stage, hashes));
            entry = findStoreEntry(storeDir(options), plan.key, hashMemoFile(options));
        }
        if (entry && !plan.force) {
            plan.action = Action::Cached;
            plan.reason = plan.key;
            entries[stage.id] = *entry;
            continue;
        }
        if (!plan.selected) {
            plan.action = Action::Skip;
            plan.reason = "outside --" + std::string(options.only.empty() ? "from " : "only ") + chosen + ", not cached";
            continue;
        }
        plan.action = Action::Run;
        std::vector<std::string> waits;
        for (const StageInput& input : stage.inputs) {
            if (input.sourcePort.empty() || entries.count(input.source)) continue;
            if (plans[findStage(pipeline, input.source)].action == Action::Skip)
                throw Error(pipeline.file, "stage " + stage.id,
                            "its input " + input.port + " comes from stage " + input.source +
                                ", which is not in the store: run the pipeline without --only/--from first",
                            kExitUsage);
            waits.push_back(input.source);
        }
        std::string change = changeReason(last.value(stage.id, nlohmann::json()), stage, inputs ? &hashes : nullptr);
        if (plan.force) {
            plan.reason = forcedBy;
        } else if (change.empty()) { // only an upstream stage changed
            plan.reason = "after ";
            for (size_t w = 0; w < waits.size(); ++w) plan.reason += (w ? ", " : "") + waits[w];
            plan.reason += ": reruns if their output changes";
        } else {
            plan.reason = change;
        }
    }
    return plans;
}

void printPlan(const Pipeline& pipeline, const std::vector<StagePlan>& plans, bool toStdout) {
    size_t width = 5;
    for (const PipelineStage& stage : pipeline.stages) width = std::max(width, stage.id.size());
    int running = 0;
    for (const StagePlan& plan : plans) running += plan.action == Action::Run;
    std::string text = "plan for " + pipeline.file + " (" + pipeline.name + "): " + std::to_string(plans.size()) +
                       " stages, " + std::to_string(running) + " to run\n";
    for (size_t i = 0; i < plans.size(); ++i) {
        const PipelineStage& stage = pipeline.stages[i];
        const StagePlan& plan = plans[i];
        char line[256];
        std::snprintf(line, sizeof(line), "  %-*s %-10s %-6s ", int(width), stage.id.c_str(), stage.spec->name.c_str(),
                      actionName(plan.action));
        text += line;
        if (plan.shards > 1) text += std::to_string(plan.shards) + " shards, ";
        text += plan.reason;
        text += '\n';
    }
    if (toStdout) std::fputs(text.c_str(), stdout);
    else logInfo(text.substr(0, text.size() - 1));
}

// Runs the planned stages with the chosen executor and records their jobs by stage id; `entries` gains each
// stage's stored result. On a failure, `failed` names the stage that was running (if one can be named).
void executeStages(const Pipeline& pipeline, const RunOptions& options, const std::string& runDir,
                   const std::map<std::string, InputFile>& pipelineInputs, std::vector<StagePlan>& plans,
                   std::map<std::string, StoreEntry>& entries, std::map<std::string, std::vector<nlohmann::json>>& jobs,
                   std::string& failed) {
    if (options.executor == Executor::Slurm) {
        std::vector<SlurmStage> submit;
        for (size_t i = 0; i < plans.size(); ++i)
            if (plans[i].action == Action::Run) submit.push_back({i, plans[i].shards, plans[i].force});
        if (!submit.empty()) jobs = runOnSlurm(pipeline, options, submit, runDir);
    }
    for (size_t i = 0; i < plans.size(); ++i) {
        const PipelineStage& stage = pipeline.stages[i];
        StagePlan& plan = plans[i];
        std::optional<StageInputs> inputs = resolveInputs(stage, pipelineInputs, entries);
        if (plan.action == Action::Cached && !plan.selected &&
            (!inputs || keyOf(keyIngredients(stage, inputHashes(*inputs))) != plan.key)) {
            // Downstream of --only: the stored result belongs to the inputs before the rerun.
            entries.erase(stage.id);
            plan.action = Action::Skip;
            plan.reason = "outside --only " + options.only + "; its inputs changed, so its stored result is stale";
        }
        if (plan.action != Action::Run) continue;
        failed = stage.id;
        if (options.executor == Executor::Local) {
            // Pass by pass (one for most stages): its shards, then its gather, or after the last the merge.
            std::vector<nlohmann::json>& records = jobs[stage.id];
            int passes = stagePasses(stage, plan.shards);
            for (int pass = 0; pass < passes; ++pass) {
                for (int s = 0; s < std::max(plan.shards, 1); ++s)
                    records.push_back(runJob(stage, *inputs, options, s, plan.shards, plan.force, pass));
                if (plan.shards > 1)
                    records.push_back(runJob(stage, *inputs, options, pass + 1 < passes ? kGatherJob : kMergeJob,
                                             plan.shards, plan.force, pass));
            }
        }
        plan.key = keyOf(keyIngredients(stage, inputHashes(*inputs)));
        std::optional<StoreEntry> entry = findStoreEntry(storeDir(options), plan.key, hashMemoFile(options));
        if (!entry) throw Error(storeDir(options), "stage " + stage.id, "finished but its entry " + plan.key + " is missing", kExitFailure);
        entries[stage.id] = *entry;
        if (plan.reason.rfind("after ", 0) == 0 && jobs[stage.id].back()["status"] == "cached")
            plan.reason = "cached: the upstream output came out unchanged";
    }
    failed.clear();
}

std::string timestamp() {
    std::time_t now = std::time(nullptr);
    char text[32];
    std::strftime(text, sizeof(text), "%Y%m%dT%H%M%SZ", std::gmtime(&now));
    return text;
}

nlohmann::json readJsonOr(const std::string& path, nlohmann::json fallback) {
    std::error_code error;
    if (!fs::is_regular_file(path, error)) return fallback;
    nlohmann::json value = nlohmann::json::parse(readFileBytes(path), nullptr, false);
    return value.is_discarded() ? fallback : value;
}

// The stage's record for the report from its jobs' records (one, or one per shard plus the merge).
nlohmann::json stageRecord(const PipelineStage& stage, const StagePlan& plan, const std::vector<nlohmann::json>& jobs,
                           double runStart) {
    nlohmann::json record = {{"id", stage.id}, {"stage", stage.spec->name}, {"version", stage.version},
                             {"reason", plan.reason}, {"shards", plan.shards}, {"key", plan.key}};
    if (jobs.empty()) {
        record["status"] = plan.action == Action::Cached ? "cached" : "not run";
        return record;
    }
    double start = jobs.front()["start"], end = jobs.front()["end"];
    uint64_t rays = 0, peak = 0;
    bool ran = false;
    nlohmann::json shards = nlohmann::json::array();
    for (const nlohmann::json& job : jobs) {
        start = std::min(start, job["start"].get<double>());
        end = std::max(end, job["end"].get<double>());
        rays += job.value("rays", uint64_t(0));
        peak = std::max(peak, job.value("peak_memory_bytes", uint64_t(0)));
        ran = ran || job["status"] == "ran";
        if (job.contains("shard")) {
            nlohmann::json shard = job;
            shard["start"] = job["start"].get<double>() - runStart;
            shard["end"] = job["end"].get<double>() - runStart;
            shard.erase("outputs");
            shards.push_back(shard);
        }
    }
    record.update({{"status", ran ? "ran" : "cached"}, {"start", start - runStart}, {"end", end - runStart},
                   {"seconds", end - start}, {"rays", rays}, {"peak_memory_bytes", peak},
                   {"outputs", jobs.back()["outputs"]}});
    if (!shards.empty()) record["shard_jobs"] = shards;
    return record;
}

// One line of the run's cost table: "  transfer   ran      3.21 s   12.3 M rays   peak 120 MiB".
std::string costLine(const nlohmann::json& record) {
    char line[160];
    std::string status = record["status"];
    if (status != "ran") {
        std::snprintf(line, sizeof line, "  %-12s %-8s", record["id"].get<std::string>().c_str(), status.c_str());
        return line;
    }
    std::snprintf(line, sizeof line, "  %-12s %-8s %8.2f s %9.1f M rays   peak %6.0f MiB",
                  record["id"].get<std::string>().c_str(), status.c_str(), record["seconds"].get<double>(),
                  record["rays"].get<uint64_t>() * 1e-6, record["peak_memory_bytes"].get<uint64_t>() / 1048576.0);
    return line;
}

// Copies `file` atomically to `path` unless that already holds the same bytes (by the run's hash memo). The copy
// is the file system's (copy_file), so no output is held in memory whatever its size.
void copyIfChanged(const std::string& file, const std::string& path, const std::string& hash, const std::string& memo) {
    std::error_code error;
    if (fs::is_regular_file(path, error) && hashFileMemo(path, memo) == hash) return;
    writeFileAtomic(path, [&](const std::string& tmp) {
        std::error_code copyError;
        if (!fs::copy_file(file, tmp, fs::copy_options::overwrite_existing, copyError))
            throw Error(path, "", "cannot copy " + file + ": " + copyError.message(), kExitOutput);
    });
}

// (source, target) pairs for the companion files `names` of the bundle `bundleFile`: each goes next to the
// bundle's copy at `destination` under the same name, so the references hold.
std::vector<std::pair<std::string, std::string>> companionPairs(const std::vector<std::string>& names,
                                                                const std::string& bundleFile,
                                                                const std::string& destination) {
    std::vector<std::pair<std::string, std::string>> files;
    fs::path from = fs::path(bundleFile).parent_path(), to = fs::path(destination).parent_path();
    for (const std::string& name : names) {
        fs::path relative = name;
        if (relative.empty() || relative.is_absolute() || relative.filename() != relative)
            throw Error(bundleFile, "companion files", "'" + name + "' is not a plain file name next to the bundle",
                        kExitFailure);
        files.emplace_back((from / name).string(), (to / name).lexically_normal().string());
    }
    return files;
}

std::vector<std::pair<std::string, std::string>> companionFiles(const std::string& bundleFile,
                                                                const std::string& destination) {
    return companionPairs(bundleCompanionNames(bundleFile), bundleFile, destination);
}

// One declared output to copy out of the store, with a bundle's companion files.
struct OutputCopy {
    const PipelineOutput* output = nullptr;
    std::string file, hash;
    FileKind kind = FileKind::Mesh;
    std::vector<std::pair<std::string, std::string>> companions; // (source, target)
};

// Copies each declared output whose stage has a result atomically into place, unless it already holds it; a
// bundle's companion files (external textures) go next to it. Two outputs whose files would land on one path
// (two bundles' textures in one folder) are an error naming both, raised before anything is copied.
nlohmann::json copyOutputs(const Pipeline& pipeline, const std::map<std::string, StoreEntry>& entries,
                           const std::string& memo) {
    std::map<std::string, std::string> claimed; // destination path -> output name
    for (const PipelineOutput& output : pipeline.outputs)
        claimed.emplace(fs::path(output.path).lexically_normal().string(), output.name);
    std::vector<OutputCopy> copies;
    for (const PipelineOutput& output : pipeline.outputs) {
        auto entry = entries.find(output.stage);
        if (entry == entries.end()) {
            logInfo("output " + output.name + " (" + output.path + ") not updated: stage " + output.stage + " did not run");
            continue;
        }
        const nlohmann::json& product = entry->second.manifest["outputs"][output.port];
        OutputCopy copy;
        copy.output = &output;
        copy.file = entry->second.dir + "/" + product["file"].get<std::string>();
        copy.hash = product["hash"];
        const StageSpec& spec = *pipeline.stages[findStage(pipeline, output.stage)].spec;
        copy.kind = std::find_if(spec.outputs.begin(), spec.outputs.end(), [&](const PortSpec& port) {
                        return port.name == output.port;
                    })->kind;
        // The store's manifest lists a bundle's companions (entries written before it did: read the bundle).
        if (copy.kind == FileKind::Bundle)
            copy.companions = product.contains("files") && product["files"].is_array()
                                  ? companionPairs(product["files"].get<std::vector<std::string>>(), copy.file, output.path)
                                  : companionFiles(copy.file, output.path);
        for (const auto& [source, target] : copy.companions) {
            auto [owner, fresh] = claimed.emplace(target, output.name);
            if (!fresh && owner->second != output.name)
                throw Error(pipeline.file, "outputs." + output.name,
                            "its bundle's texture " + target + " would overwrite the file of output '" +
                                owner->second + "': put the two outputs in different folders",
                            kExitInput);
        }
        copies.push_back(std::move(copy));
    }

    nlohmann::json copied = nlohmann::json::object();
    for (const OutputCopy& copy : copies) {
        const PipelineOutput& output = *copy.output;
        std::error_code error;
        fs::path parent = fs::path(output.path).parent_path();
        if (!parent.empty()) fs::create_directories(parent, error);
        // Textures first, the bundle last: a kill in between leaves the old bundle, whose textures (named by
        // content) are still there, never a bundle naming a texture that is not.
        nlohmann::json files = nlohmann::json::array();
        std::vector<std::string> previous; // the textures of the bundle about to be replaced
        if (copy.kind == FileKind::Bundle && fs::is_regular_file(output.path, error)) {
            try {
                if (hashFileMemo(output.path, memo) == copy.hash) { // the same bundle: the same companions
                    for (const auto& [source, target] : copy.companions) previous.push_back(target);
                } else {
                    for (const auto& [old, target] : companionFiles(output.path, output.path)) previous.push_back(target);
                }
            } catch (const Error&) {
                // not a bundle we wrote: leave what lies next to it alone
            }
        }
        for (const auto& [source, target] : copy.companions) {
            copyIfChanged(source, target, hashFileMemo(source, memo), memo);
            files.push_back(target);
        }
        copyIfChanged(copy.file, output.path, copy.hash, memo);
        // Only what a bake names its textures by: a bundle found at the path may list any file beside it.
        const std::string stem = fs::path(output.path).stem().string();
        for (const std::string& old : previous)
            if (std::find(files.begin(), files.end(), old) == files.end() &&
                isBakeTextureName(fs::path(old).filename().string(), stem))
                fs::remove(old, error);
        copied[output.name] = {{"path", output.path}, {"hash", copy.hash}, {"kind", fileKindName(copy.kind)},
                               {"from", output.stage + "." + output.port}};
        if (!files.empty()) copied[output.name]["files"] = files;
    }
    return copied;
}

void writeJson(const std::string& path, const nlohmann::json& value) {
    fs::path parent = fs::path(path).parent_path();
    if (!parent.empty()) fs::create_directories(parent);
    writeBytesAtomic(path, value.dump(2) + "\n");
}

} // namespace

nlohmann::json runPipeline(const Pipeline& given, const RunOptions& options) {
    Pipeline pipeline = given;
    resolveStageOptions(pipeline, options); // before any key: they are part of every key
    sweepStore(storeDir(options));
    double runStart = epochSeconds();
    std::string lastPath = options.cacheDir + "/runs/" + pipeline.name + ".last.json";
    nlohmann::json last = readJsonOr(lastPath, nlohmann::json::object());
    std::map<std::string, InputFile> pipelineInputs = hashPipelineInputs(pipeline, options);
    std::map<std::string, StoreEntry> entries;
    std::vector<StagePlan> plans = planStages(pipeline, options, pipelineInputs, last, entries);
    printPlan(pipeline, plans, options.plan);
    if (options.plan) {
        nlohmann::json planned = nlohmann::json::array();
        for (size_t i = 0; i < plans.size(); ++i)
            planned.push_back({{"id", pipeline.stages[i].id}, {"action", actionName(plans[i].action)},
                               {"key", plans[i].key}, {"reason", plans[i].reason}, {"shards", plans[i].shards}});
        return {{"pipeline", pipeline.name}, {"file", pipeline.file}, {"plan", planned}};
    }

    std::string runDir = options.cacheDir + "/runs/" + pipeline.name + "-" + timestamp() + "-" + std::to_string(getpid());
    fs::create_directories(runDir);
    std::map<std::string, std::vector<nlohmann::json>> jobs;
    std::optional<Error> failure;
    std::string failed;
    try {
        executeStages(pipeline, options, runDir, pipelineInputs, plans, entries, jobs, failed);
    } catch (const Error& e) {
        failure = e;
    }

    nlohmann::json report = {{"pipeline", pipeline.name}, {"file", pipeline.file},
                             {"executor", options.executor == Executor::Slurm ? "slurm" : "local"},
                             {"host", hostName()}, {"run_dir", runDir}, {"stages", nlohmann::json::array()}};
    int hits = 0, ran = 0;
    uint64_t peak = 0;
    for (size_t i = 0; i < plans.size(); ++i) {
        const PipelineStage& stage = pipeline.stages[i];
        nlohmann::json record = stageRecord(stage, plans[i], jobs[stage.id], runStart);
        if (failure && stage.id == failed) record["status"] = "failed";
        hits += record["status"] == "cached";
        ran += record["status"] == "ran";
        peak = std::max(peak, record.value("peak_memory_bytes", uint64_t(0)));
        report["stages"].push_back(record);
        // For the next run's reasons: the ingredients of each stored result.
        auto entry = entries.find(stage.id);
        if (entry != entries.end()) last[stage.id] = entry->second.manifest["ingredients"];
    }
    report["outputs"] = nlohmann::json::object();
    if (!failure) {
        try {
            report["outputs"] = copyOutputs(pipeline, entries, hashMemoFile(options));
            if (!options.keepIntermediates) {
                // The store's policy: a sharded stage's job entries go once its merged entry is stored.
                std::vector<std::string> finalKeys, jobKeys;
                for (const auto& [id, entry] : entries) finalKeys.push_back(entry.manifest.value("key", ""));
                for (const auto& [id, records] : jobs)
                    for (const nlohmann::json& job : records)
                        if (job.contains("shard") && entries.count(id)) jobKeys.push_back(job.value("key", ""));
                report["gc"] = collectIntermediates(storeDir(options), finalKeys, jobKeys);
            }
        } catch (const Error& e) {
            failure = e; // the report still records what ran
        }
    }
    report.update({{"ok", !failure}, {"seconds", epochSeconds() - runStart}, {"cache_hits", hits},
                   {"stages_run", ran}, {"peak_memory_bytes", peak}});
    if (failure) report["error"] = failure->what();
    writeJson(runDir + "/report.json", report);
    writeJson(lastPath, last);
    if (!options.reportPath.empty()) writeJson(options.reportPath, report);
    logInfo("run " + pipeline.name + ": " + std::to_string(ran) + " stages ran, " + std::to_string(hits) + " cached, " +
            std::to_string(report["seconds"].get<double>()) + " s; report " + runDir + "/report.json");
    for (const nlohmann::json& record : report["stages"]) logInfo(costLine(record));
    if (failure) throw *failure;
    return report;
}

} // namespace prt
