// Shared between the pipeline library's files; not part of its interface.
#pragma once

#include "pipeline.h"

#include <map>
#include <optional>
#include <string>

namespace prt {

// A file a stage reads: where it is and its content hash.
struct InputFile {
    std::string path;
    std::string hash;
};
using StageInputs = std::map<std::string, InputFile>; // by input port

std::string keyHex(const std::string& key); // the key without its "xxh128:" prefix: the entry's folder name
// STORE/<prefix><key hex>-<host>-<pid>: a folder only this process writes.
std::string privateEntryPath(const std::string& store, const std::string& prefix, const std::string& key);
// Renames a finished temporary folder into place as the entry for `key`. An entry already there (another run's)
// is kept unless `replace`.
void commitStoreEntry(const std::string& store, const std::string& key, const std::string& tmpDir, bool replace);
void syncFolder(const std::string& path);
double epochSeconds(); // wall-clock seconds since 1970: comparable between processes and hosts
std::string storeDir(const RunOptions& options);
std::string absolutePath(const std::string& path);
std::string shellQuote(const std::string& text); // for /bin/sh, whatever the text holds
// Runs `args` (each quoted by shellQuote) and returns its stdout, with its stderr too when `withStderr` (else
// dropped); `status` gets its exit status, 128 when a signal ended it. Throws prt::Error when it cannot start.
std::string captureCommand(const std::vector<std::string>& args, bool withStderr, int& status);

// `stage`'s command line after `prt` (subcommand, parameters, inputs as "input-PORT", outputs), as stageCommand
// builds it, without --log-json, --threads or --shard: what --resolved-options is asked about.
std::vector<std::string> stageArguments(const PipelineStage& stage);

// The last `lines` lines of a log a person wants to read: messages of JSON log lines, no progress records;
// each on its own line, indented.
std::string readableLogTail(const std::string& path, size_t lines);

// The pipeline's input files with their content hashes (hashFileMemo, in the run's memo).
std::map<std::string, InputFile> hashPipelineInputs(const Pipeline& pipeline, const RunOptions& options);
// The files `stage` reads, or nothing when an upstream stage has no entry in `entries` (by stage id).
std::optional<StageInputs> resolveInputs(const PipelineStage& stage, const std::map<std::string, InputFile>& pipelineInputs,
                                         const std::map<std::string, StoreEntry>& entries);
std::map<std::string, std::string> inputHashes(const StageInputs& inputs);

// The external files a bundle's layers reference (params.files: plain names next to the bundle, docs/bundle.md),
// read from the bundle's header (readBundleHeader: no layer values are held). Throws prt::Error for a name that
// is not a plain file name.
std::vector<std::string> bundleCompanionNames(const std::string& bundleFile);

// Removes the store entry STORE/<hex> crash-safely (gc.cpp: one rename takes it out, then its files go); returns
// the bytes it held, 0 when absent.
uint64_t removeStoreEntry(const std::string& store, const std::string& hex);
// The automatic collection at the end of a successful run: removes the entries of `jobKeys` (a sharded stage's
// shard, pass and gather jobs) that are not among `finalKeys` (the stages' own entries, which stay). Returns
// {"removed": count, "removed_bytes", "store_bytes": what the store holds after}.
nlohmann::json collectIntermediates(const std::string& store, const std::vector<std::string>& finalKeys,
                                    const std::vector<std::string>& jobKeys);

// runStageJob with the inputs already resolved.
nlohmann::json runJob(const PipelineStage& stage, const StageInputs& inputs, const RunOptions& options, int shardIndex,
                      int shardCount, bool force, int pass = 0);

// One stage for the Slurm executor: index into pipeline.stages, its shard count, and whether it must rerun.
struct SlurmStage {
    size_t stage;
    int shards;
    bool force;
};
// Submits the stages as Slurm jobs (an array and a merge job for sharded ones, afterok dependencies along the
// DAG), waits for them, and returns the jobs' records by stage id. Cancels the rest and throws prt::Error with
// the failing job's log when a job fails.
std::map<std::string, std::vector<nlohmann::json>> runOnSlurm(const Pipeline& pipeline, const RunOptions& options,
                                                               const std::vector<SlurmStage>& stages,
                                                               const std::string& runDir);

} // namespace prt
