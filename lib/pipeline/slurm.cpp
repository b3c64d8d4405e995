// The Slurm executor: every stage that must run becomes a job running `prt run SNAPSHOT --job STAGE`, a sharded
// stage a job array plus a merge job, chained with --dependency=afterok. Each job computes its own key when it
// starts, from the store its upstream jobs filled, so the waiting `prt run` needs no shared state but the
// folders (store and run folder must be on a file system every node mounts).
#include "pipeline_internal.h"

#include "core.h"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;

namespace prt {

namespace {

volatile std::sig_atomic_t gInterrupted = 0;
void onInterrupt(int) { gInterrupted = 1; }

struct Job {
    std::string slurmId; // "12" or "12_3" for a task of array 12
    std::string baseId;  // "12"
    size_t stage;
    int shardIndex, shardCount; // as runStageJob takes them
    int pass;
    std::string label, logPath;
    std::string state = "SUBMITTED";
    bool finished = false;
};

std::string submit(std::vector<std::string> args) {
    int status = 0;
    std::string output = captureCommand(args, true, status);
    // --parsable prints "JOBID" or "JOBID;CLUSTER".
    std::string id = output.substr(0, output.find_first_of(";\n"));
    if (status != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
        throw Error("", "sbatch", "submission failed (status " + std::to_string(status) + "): " + output, kExitFailure);
    return id;
}

bool stillGoing(const std::string& state) {
    static const std::set<std::string> waiting = {"SUBMITTED", "PENDING", "CONFIGURING", "RUNNING", "COMPLETING",
                                                  "SUSPENDED", "REQUEUED", "RESIZING", "SIGNALING", "STAGE_OUT"};
    return waiting.count(state) > 0;
}

// squeue's "ID|STATE|REASON" for the tasks of the given base ids. Returns false when squeue fails (it does when
// any id was already purged, after MinJobAge).
bool queryStates(const std::set<std::string>& baseIds, std::map<std::string, std::pair<std::string, std::string>>& states) {
    std::string ids;
    for (const std::string& id : baseIds) ids += (ids.empty() ? "" : ",") + id;
    int status = 0;
    std::string output = captureCommand({"squeue", "--noheader", "--array", "--states=all", "--jobs=" + ids,
                                         "--format=%i|%T|%r"}, true, status);
    if (status != 0) return false;
    size_t start = 0;
    while (start < output.size()) {
        size_t end = output.find('\n', start);
        if (end == std::string::npos) end = output.size();
        std::string line = output.substr(start, end - start);
        start = end + 1;
        size_t first = line.find('|'), second = line.find('|', first + 1);
        if (first == std::string::npos || second == std::string::npos) continue;
        states[line.substr(0, first)] = {line.substr(first + 1, second - first - 1), line.substr(second + 1)};
    }
    return true;
}

void cancel(const std::vector<Job>& jobs) {
    std::set<std::string> ids;
    for (const Job& job : jobs)
        if (!job.finished) ids.insert(job.baseId);
    if (ids.empty()) return;
    std::vector<std::string> args = {"scancel"};
    args.insert(args.end(), ids.begin(), ids.end());
    int status = 0;
    captureCommand(args, true, status);
}

// While alive: Ctrl-C and SIGTERM set gInterrupted instead of ending the process. When it goes, for whatever
// reason, it cancels the jobs that have not finished, so an error never leaves jobs queued behind it.
struct JobsGuard {
    std::vector<Job>& jobs;
    struct sigaction previousInt {}, previousTerm {};

    explicit JobsGuard(std::vector<Job>& jobs) : jobs(jobs) {
        struct sigaction interrupt {};
        interrupt.sa_handler = onInterrupt;
        sigaction(SIGINT, &interrupt, &previousInt);
        sigaction(SIGTERM, &interrupt, &previousTerm);
    }
    ~JobsGuard() {
        cancel(jobs);
        sigaction(SIGINT, &previousInt, nullptr);
        sigaction(SIGTERM, &previousTerm, nullptr);
        gInterrupted = 0;
    }
};

} // namespace

std::map<std::string, std::vector<nlohmann::json>> runOnSlurm(const Pipeline& pipeline, const RunOptions& options,
                                                               const std::vector<SlurmStage>& stages,
                                                               const std::string& runDir) {
    std::string run = absolutePath(runDir);
    fs::create_directories(run + "/slurm");
    fs::create_directories(run + "/jobs");
    // Jobs read a snapshot, so editing the pipeline while they wait changes nothing. Same stem, same default name.
    std::string snapshot = run + "/" + fs::path(pipeline.file).filename().string();
    writeBytesAtomic(snapshot, readFileBytes(pipeline.file));
    std::string cwd = fs::current_path().string();

    std::vector<Job> jobs;
    JobsGuard guard(jobs);
    std::map<std::string, std::string> finalJob; // stage id -> the job whose success means the stage is stored
    for (const SlurmStage& item : stages) {
        const PipelineStage& stage = pipeline.stages[item.stage];
        std::set<std::string> after;
        for (const StageInput& input : stage.inputs)
            if (finalJob.count(input.source)) after.insert(finalJob[input.source]);

        auto sbatch = [&](const std::string& name, const std::string& part, const std::string& logPattern,
                          const std::set<std::string>& deps, int arraySize, int pass) {
            std::string script = run + "/slurm/" + stage.id + "." + name + ".sh";
            std::string body = "#!/bin/bash\n# prt pipeline " + pipeline.name + ", stage " + stage.id + "\nexec " +
                               shellQuote(absolutePath(options.prt)) + " --log-json run " + shellQuote(snapshot) +
                               " --job " + shellQuote(stage.id) + " --job-part " + part +
                               (pass > 0 ? " --job-pass " + std::to_string(pass) : "") + " --cache-dir " +
                               shellQuote(absolutePath(options.cacheDir)) + " --run-dir " + shellQuote(run) +
                               " --threads " + std::to_string(options.slurmCpusPerTask) + (item.force ? " --force" : "") + "\n";
            writeBytesAtomic(script, body);
            std::vector<std::string> args = {"sbatch", "--parsable", "--job-name=prt-" + pipeline.name + "-" + stage.id,
                                             "--output=" + run + "/slurm/" + logPattern, "--chdir=" + cwd,
                                             "--cpus-per-task=" + std::to_string(options.slurmCpusPerTask)};
            if (!options.slurmPartition.empty()) args.push_back("--partition=" + options.slurmPartition);
            if (arraySize > 0) args.push_back("--array=0-" + std::to_string(arraySize - 1));
            if (!deps.empty()) {
                std::string list = "afterok";
                for (const std::string& dep : deps) list += ":" + dep;
                args.insert(args.end(), {"--dependency=" + list, "--kill-on-invalid-dep=yes"});
            }
            args.insert(args.end(), options.slurmArgs.begin(), options.slurmArgs.end());
            args.push_back(script);
            return submit(args);
        };

        int passes = stagePasses(stage, item.shards);
        if (item.shards > 1) {
            // Pass by pass: an array of shards after the previous pass's gather, then this pass's gather (or, after
            // the last pass, the merge) after the array.
            std::string n = std::to_string(item.shards);
            std::set<std::string> deps = after;
            for (int pass = 0; pass < passes; ++pass) {
                bool last = pass + 1 == passes;
                std::string tag = passes > 1 ? "p" + std::to_string(pass) + "-" : "";
                std::string passName = passes > 1 ? " pass " + std::to_string(pass) : "";
                std::string array = sbatch(tag + "shards", "\"$SLURM_ARRAY_TASK_ID/" + n + "\"",
                                           stage.id + "-" + tag + "%A_%a.log", deps, item.shards, pass);
                for (int s = 0; s < item.shards; ++s)
                    jobs.push_back({array + "_" + std::to_string(s), array, item.stage, s, item.shards, pass,
                                    stage.id + passName + " shard " + std::to_string(s + 1) + "/" + n,
                                    run + "/slurm/" + stage.id + "-" + tag + array + "_" + std::to_string(s) + ".log"});
                std::string what = last ? "merge" : "gather";
                std::string join = sbatch(tag + what, what + "/" + n, stage.id + "-" + tag + what + "-%j.log", {array},
                                          0, pass);
                jobs.push_back({join, join, item.stage, last ? kMergeJob : kGatherJob, item.shards, pass,
                                stage.id + passName + " " + what,
                                run + "/slurm/" + stage.id + "-" + tag + what + "-" + join + ".log"});
                deps = {join};
            }
            finalJob[stage.id] = *deps.begin();
        } else {
            std::string id = sbatch("all", "all", stage.id + "-%j.log", after, 0, 0);
            jobs.push_back({id, id, item.stage, 0, 1, 0, stage.id, run + "/slurm/" + stage.id + "-" + id + ".log"});
            finalJob[stage.id] = id;
        }
        std::string waits;
        for (const std::string& dep : after) waits += (waits.empty() ? ", after job " : ",") + dep;
        logInfo("slurm: submitted " + stage.id +
                (item.shards > 1 ? " as " + std::to_string(item.shards) + " shards and a merge" : "") +
                (passes > 1 ? " in each of " + std::to_string(passes) + " passes (gathers between them)" : "") +
                " (job " + finalJob[stage.id] + waits + ")");
    }

    size_t finished = 0;
    while (finished < jobs.size()) {
        std::this_thread::sleep_for(std::chrono::duration<double>(options.slurmPollSeconds));
        if (gInterrupted) throw Error("", "slurm", "interrupted: cancelled the pipeline's jobs", kExitInterrupted);
        std::set<std::string> open;
        for (const Job& job : jobs)
            if (!job.finished) open.insert(job.baseId);
        std::map<std::string, std::pair<std::string, std::string>> states;
        std::set<std::string> gone; // base ids squeue no longer knows
        if (!queryStates(open, states)) {
            for (const std::string& id : open)
                if (!queryStates({id}, states)) gone.insert(id);
            if (gone.size() == open.size()) continue; // the controller itself did not answer: ask again
        }
        const Job* failed = nullptr;
        std::string failedReason;
        for (Job& job : jobs) {
            if (job.finished) continue;
            auto found = states.find(job.slurmId);
            std::string state = job.state, reason;
            if (found != states.end()) {
                state = found->second.first;
                reason = found->second.second;
            } else if (gone.count(job.baseId)) {
                // Slurm forgot the job: its record tells whether it succeeded.
                bool recorded = fs::exists(jobRecordPath(run, pipeline.stages[job.stage].id, job.shardIndex, job.shardCount, job.pass));
                state = recorded ? "COMPLETED" : "FAILED";
                reason = recorded ? "" : "gone from squeue without a record";
            }
            if (state != job.state) {
                job.state = state;
                logInfo("slurm: " + job.label + " (job " + job.slurmId + ") " + state);
            }
            bool neverRuns = state == "PENDING" && reason == "DependencyNeverSatisfied";
            if (state == "COMPLETED") {
                job.finished = true;
                ++finished;
                logInfo("slurm: " + std::to_string(finished) + "/" + std::to_string(jobs.size()) + " jobs done");
            } else if (neverRuns || !stillGoing(state)) {
                // Report the job that broke, not the dependents Slurm cancelled because of it.
                bool dependent = reason == "DependencyNeverSatisfied";
                if (!failed || (failedReason == "DependencyNeverSatisfied" && !dependent)) {
                    failed = &job;
                    failedReason = reason;
                }
            }
        }
        if (failed)
            throw Error(failed->logPath, "slurm job " + failed->slurmId + " (" + failed->label + ")",
                        failed->state + (failedReason.empty() || failedReason == "None" ? "" : " (" + failedReason + ")") +
                            "; its log ends:" + readableLogTail(failed->logPath, 25),
                        kExitFailure);
    }

    std::map<std::string, std::vector<nlohmann::json>> records;
    for (const Job& job : jobs) {
        const std::string& id = pipeline.stages[job.stage].id;
        std::string path = jobRecordPath(run, id, job.shardIndex, job.shardCount, job.pass);
        nlohmann::json record = nlohmann::json::parse(readFileBytes(path), nullptr, false);
        if (!record.is_object()) throw Error(path, job.label, "job completed but left no readable record", kExitFailure);
        record["slurm_job"] = job.slurmId;
        records[id].push_back(record);
    }
    return records;
}

} // namespace prt
