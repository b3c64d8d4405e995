// prt run: runs a pipeline file (docs/pipelines.md) locally or on Slurm, from the content-addressed cache.
#include "build_info.h"
#include "cli.h"

#include "core.h"
#include "pipeline.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

namespace prt::cli {

namespace {

struct RunArgs {
    std::string pipeline;
    RunOptions options;
    std::string executor = "local";
    std::string job, jobPart, runDir; // a Slurm job's own invocation
    int jobPass = 0;
    bool allowOutputsAnywhere = false;
};

// The `prt` next to this program: stages run as `prt STAGE`, also when this is the standalone prt-run.
std::string prtBinary() {
    std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe");
    std::string prt = (self.parent_path() / "prt").string();
    if (!std::filesystem::exists(prt)) throw Error(prt, "", "the prt binary the stages run as is missing", kExitFailure);
    return prt;
}

// "all", "I/N", "merge/N" or "gather/N", as the Slurm executor writes them into its job scripts.
void parseJobPart(const std::string& text, int& shardIndex, int& shardCount) {
    shardIndex = 0;
    shardCount = 1;
    if (text == "all") return;
    size_t slash = text.find('/');
    std::string index = text.substr(0, slash);
    std::istringstream count(slash == std::string::npos ? "" : text.substr(slash + 1));
    if (!(count >> shardCount) || shardCount < 2) throw Error("", "--job-part", "'" + text + "' is not all, I/N, merge/N or gather/N", kExitUsage);
    bool join = index == "merge" || index == "gather";
    shardIndex = index == "merge" ? kMergeJob : index == "gather" ? kGatherJob : std::atoi(index.c_str());
    if (!join && (index.empty() || index.find_first_not_of("0123456789") != std::string::npos || shardIndex >= shardCount))
        throw Error("", "--job-part", "'" + text + "' is not all, I/N, merge/N or gather/N", kExitUsage);
}

void runRun(RunArgs& args) {
    args.options.prt = prtBinary();
    // The cache key's questions are answered in this process, by the option definitions the stages parse with.
    args.options.askPrt = inProcessAnswers(hashMemoFile(args.options));
    args.options.executor = args.executor == "slurm" ? Executor::Slurm : Executor::Local;
    Pipeline pipeline = loadPipeline(args.pipeline);
    if (args.job.empty() && !args.allowOutputsAnywhere) checkOutputsInside(pipeline); // jobs copy no outputs
    if (args.job.empty()) {
        nlohmann::json report = runPipeline(pipeline, args.options);
        // The metrics are the run's answer: print them.
        const nlohmann::json outputs = report.value("outputs", nlohmann::json::object());
        for (auto& [name, output] : outputs.items())
            if (output["kind"] == "metrics") std::fputs(readFileBytes(output["path"]).c_str(), stdout);
        return;
    }
    if (args.runDir.empty()) throw Error("", "--job", "needs --run-dir", kExitUsage);
    int shardIndex, shardCount;
    parseJobPart(args.jobPart, shardIndex, shardCount);
    const PipelineStage& stage = pipeline.stages[findStage(pipeline, args.job)];
    nlohmann::json record =
        runStageJob(pipeline, stage, args.options, shardIndex, shardCount, args.options.force, args.jobPass);
    writeBytesAtomic(jobRecordPath(args.runDir, stage.id, shardIndex, shardCount, args.jobPass), record.dump(2) + "\n");
}

} // namespace

void addRunCommand(CLI::App& app) {
    auto args = std::make_shared<RunArgs>();
    RunOptions& options = args->options;
    CLI::App* command = app.add_subcommand(
        "run", "Run a pipeline file: every stage whose cache key changed, the rest from the cache");
    command->add_option("pipeline", args->pipeline, "Pipeline file (.toml); its relative paths start at the current "
                                                    "directory")->required();
    command->add_flag("--plan", options.plan, "Print what would run and why; run nothing");
    command->add_flag("--allow-outputs-anywhere", args->allowOutputsAnywhere,
                      "Write outputs outside the current directory and the pipeline file's folder too");
    command->add_flag("--force", options.force, "Ignore the cache: rerun every stage");
    command->add_flag("--keep-intermediates", options.keepIntermediates,
                      "Keep sharded stages' shard, pass and gather entries in the store after a successful run");
    command->add_option("--only", options.only, "Rerun only this stage, its inputs from the cache");
    command->add_option("--from", options.from, "Rerun this stage and everything downstream of it");
    command->add_option("--executor", args->executor, "local (default) or slurm")
        ->check(CLI::IsMember({"local", "slurm"}));
    command->add_option("--shards", options.shards, "Split every stage that can be sharded into N shards")
        ->check(CLI::Range(1, 4096));
    command->add_option("--threads", options.threads, "Worker threads per stage, local executor (default 0: all cores)")
        ->check(CLI::NonNegativeNumber);
    command->add_option("--cache-dir", options.cacheDir, "Store in DIR/store, run reports in DIR/runs (default .cache)");
    outputFile(command->add_option("--report", options.reportPath, "Also write the run report (JSON) here"));
    command->add_option("--slurm-partition", options.slurmPartition, "Slurm partition (default: the cluster's)");
    command->add_option("--slurm-cpus-per-task", options.slurmCpusPerTask, "CPUs, and stage threads, per job (default 1)")
        ->check(CLI::Range(1, 4096));
    command->add_option("--slurm-poll", options.slurmPollSeconds, "Seconds between squeue polls (default 0.5)")
        ->check(CLI::Range(0.05, 600.0));
    command->add_option("--slurm-arg", options.slurmArgs, "Extra sbatch argument, e.g. --slurm-arg=--time=60 (repeatable)")
        ->allow_extra_args(false);
    const char* internal = "Internal (the Slurm executor's jobs)";
    command->add_option("--job", args->job, "Run one stage job of the pipeline and record it")->group(internal);
    command->add_option("--job-part", args->jobPart, "all, I/N (shard), merge/N or gather/N")->default_val("all")->group(internal);
    command->add_option("--job-pass", args->jobPass, "The pass of a multi-pass stage's job (default 0)")
        ->check(CLI::NonNegativeNumber)->group(internal);
    command->add_option("--run-dir", args->runDir, "Run folder the job records go to")->group(internal);
    command->callback([args] { runRun(*args); });

    // `prt gc` lives with `prt run`: it collects the store that runs fill.
    auto gc = std::make_shared<std::pair<RunOptions, bool>>();
    CLI::App* collect = app.add_subcommand(
        "gc", "Remove every store entry that no pipeline's last run needs (each stays fully cached)");
    collect->add_flag("--dry-run", gc->second, "Print what would be removed; remove nothing");
    collect->add_option("--cache-dir", gc->first.cacheDir, "The cache whose store to collect (default .cache)");
    collect->callback([gc, collect] {
        std::error_code error;
        // A mistyped --cache-dir would report an empty store; the default may not exist yet (no run so far).
        if (collect->get_option("--cache-dir")->count() > 0 && !std::filesystem::is_directory(gc->first.cacheDir, error))
            throw Error(gc->first.cacheDir, "--cache-dir", "is not a folder: no cache to collect", kExitInput);
        nlohmann::json result = collectStore(gc->first, gc->second);
        std::printf("%s %zu entries (%.1f MiB), kept %zu entries (%.1f MiB) in %s\n",
                    gc->second ? "would remove" : "removed", result["removed"].size(),
                    result["removed_bytes"].get<uint64_t>() / 1048576.0, result["kept"].get<size_t>(),
                    result["kept_bytes"].get<uint64_t>() / 1048576.0, result["store"].get<std::string>().c_str());
    });
}

} // namespace prt::cli
