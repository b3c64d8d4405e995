// Declarative pipelines: a TOML file names inputs, stages (prt subcommands with parameters) and outputs; `prt run`
// turns it into a DAG, runs each stage whose cache key changed, and keeps every result in a content-addressed
// store. docs/pipelines.md is the reference for the file format, the cache and the executors.
//
// Cache key of a stage = XXH3-128 of a canonical JSON of: the stage's name, its code version (kStage table in
// stages.cpp), its parameters as given, the options the stage resolves them to (defaults included, resolved in
// the `prt run` process by the stage's own option definitions), the prt build (version, build type, compiler,
// content hash of the prt-driver executable the stages run as) and the library versions it was compiled against
// and links (each library's real file name and size), and the content hashes of the files it reads (memoised by
// stat, hashFileMemo). A shard's key adds [index, count]. So a changed default, a rebuilt prt or an upgraded
// library never serves old bytes, and no process is started to compute a key.
// Store layout: STORE/<key hex>/ holds the stage's outputs under fixed names, its log and
// manifest.json. An entry is built in STORE/.tmp-<key hex>-<host>-<pid>/ and renamed into place as a whole, so
// an entry exists completely or not at all, whenever the process is killed.
#pragma once

#include "bundle.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace prt {

// ---- the stage catalogue --------------------------------------------------------------------------------------

// What a file between stages holds. An output feeds an input of the same kind; a bundle also feeds a mesh input.
enum class FileKind { Mesh, Bundle, Env, Sh, Radiance, Metrics, Report };
const char* fileKindName(FileKind kind);

struct PortSpec {
    std::string name;      // key under a stage's `inputs` table, or the part after "." in "stage.port"
    FileKind kind;
    std::string flag = {}; // "" for a positional argument, else "--env", "-o", ...
    std::string extension = {}; // outputs: the file the stage writes in its store entry is "<name>.<extension>"
    bool optional = false; // inputs only
};

enum class ParamType { Integer, Number, Boolean, String, Color };

struct ParamSpec {
    std::string name; // the TOML key, and the stage's flag "--<name>"
    ParamType type;
    double min = 0.0, max = 0.0;      // Integer, Number and each Color channel: inclusive range
    std::vector<std::string> choices = {}; // String: allowed values
    bool positional = false;          // passed as a positional argument rather than a flag
    bool required = false;
};

struct StageSpec {
    std::string name;      // the prt subcommand
    int version;           // bumped whenever the stage's output bytes change for the same inputs and parameters
    std::string summary;
    std::vector<PortSpec> inputs = {}, outputs = {};
    std::vector<ParamSpec> params = {};
    std::vector<std::string> exactlyOneInput = {}; // input ports of which exactly one must be wired (relight env | sh)
    // Pairs of exactlyOneInput's ports that may also be wired together (relight: env with lights, for a glossy
    // bundle's lobes under the map minus the lights).
    std::vector<std::pair<std::string, std::string>> alsoTogether = {};
    // Why these parameters do not go together, or "" when they do.
    std::string (*paramsRefusal)(const nlohmann::json& params) = nullptr;
    bool takesThreads = false;                // takes --threads; outputs do not depend on it, so keys ignore it
    bool shardable = false;                   // takes --shard I/N and writes one bundle of "..._range" layers
    // How the merge job joins the shards: "" by mergeShards ("vertex_range" layers); else by running the stage
    // again with its inputs and parameters plus "<mergeFlag> SHARD..." (`prt bake --merge`: its finishing needs them).
    std::string mergeFlag = {};
    // Why these parameters cannot be sharded, or "" when they can (shardable stages only).
    std::string (*shardRefusal)(const nlohmann::json& params) = nullptr;
    // Sharded, these parameters need this many passes (null: 1), each a job per shard whose rows feed the next
    // pass through a gather job (interreflected transfer: the direct pass, then one pass per bounce). The pass
    // protocol: shard job `--shard I/N --pass P`, writing "rows.bin" (pass 0 also "rows.bin.hits") before the last
    // pass and the shard bundle in the last; passes P > 0 also get `--previous` (the shard's rows of pass P-1),
    // `--hits` (its pass-0 hit records) and `--exitant` (pass P-1's gathered array); the gather job runs the stage
    // with `--gather ROWS...` (every shard's rows of pass P) and writes "exitant.bin". The last pass's shards merge
    // as single-pass shards do.
    int (*passes)(const nlohmann::json& params) = nullptr;
};

// Every stage a pipeline may run, in the order they usually chain.
const std::vector<StageSpec>& stageCatalogue();
const StageSpec* findStageSpec(const std::string& name); // nullptr when unknown

// ---- pipeline files -------------------------------------------------------------------------------------------

struct PipelineInput {
    std::string name; // [inputs] key
    FileKind kind;    // mesh or env (or bundle, radiance)
    std::string path; // as written: relative paths resolve against the current directory
    int line = 0;
};

struct StageInput {
    std::string port;       // the consuming stage's input port
    std::string source;     // a pipeline input name or a stage id
    std::string sourcePort; // the producing stage's output port; empty when `source` is a pipeline input
    int line = 0;
};

struct PipelineStage {
    std::string id;           // [stages.<id>]
    const StageSpec* spec = nullptr;
    int version = 0;          // spec->version, copied so that a caller can model a code change
    nlohmann::json params;    // given parameters only, canonical: integers int64, numbers double, colors [r,g,b]
    std::vector<StageInput> inputs; // in the spec's port order, wired ports only
    int shards = 1;
    int line = 0;
    // Filled by `prt run` before any key is computed (null until then, and then left out of keys): what
    // `prt --resolved-options STAGE ...` prints for this stage's command line (every option, defaults included),
    // and what `prt --build-info` prints (prt's version, build, executable hash and library versions), both
    // answered in process (RunOptions::askPrt).
    nlohmann::json resolved = nullptr;
    nlohmann::json build = nullptr;
};

struct PipelineOutput {
    std::string name;  // [outputs] key
    std::string stage; // producing stage id
    std::string port;  // its output port
    std::string path;  // where the run copies the product
    int line = 0;
};

struct Pipeline {
    std::string file;        // as given to loadPipeline / parsePipeline
    std::string name;        // [pipeline] name, else the file's stem
    std::string description;
    std::vector<PipelineInput> inputs;
    std::vector<PipelineStage> stages; // topologically sorted, ties in file order
    std::vector<PipelineOutput> outputs;
};

// Parses and validates a pipeline. Throws prt::Error(file, "line N, KEY", problem, kExitInput) for TOML syntax,
// unknown keys, wrong types, out-of-range values, unknown stages or ports, wiring of the wrong file kind,
// missing required inputs and parameters, cycles, duplicate names or outputs, and shards a stage cannot take.
// Does not touch the file system: loadPipeline also checks that input files exist.
Pipeline parsePipeline(std::string_view text, const std::string& file);
Pipeline loadPipeline(const std::string& file);
// Throws prt::Error(file, "line N, outputs.NAME.path", ..., kExitInput) for an output that, resolved (against the
// current directory, symlinks in its existing parents followed), lies neither inside the current directory nor
// inside the pipeline file's folder: `../../etc/x` never escapes unless `prt run --allow-outputs-anywhere`.
void checkOutputsInside(const Pipeline& pipeline);

// Index of a stage in pipeline.stages; throws prt::Error(kExitUsage) naming the known stages when absent.
size_t findStage(const Pipeline& pipeline, const std::string& id);

// ---- cache keys and the store ---------------------------------------------------------------------------------

// The canonical JSON a stage key hashes. `inputHashes` maps each wired input port to its file's content hash;
// shard is {index, count} for one shard, or {0, 0} for the whole stage (sharded or not: the merged product of
// N shards is bit-identical to the unsharded one, so they share a key). `pass` >= 0 adds the pass of a
// multi-pass stage's job (its shards' and gathers' keys; a gather's shard is {-1, count}).
nlohmann::json keyIngredients(const PipelineStage& stage, const std::map<std::string, std::string>& inputHashes,
                              int shardIndex = 0, int shardCount = 0, int pass = -1);

// How many passes the stage runs as with `shardCount` shards: StageSpec::passes, 1 unsharded or without it.
int stagePasses(const PipelineStage& stage, int shardCount);

// The jobs of a stage, in the order they may run: shard jobs (shardIndex >= 0), the gather of a pass
// (kGatherJob; multi-pass stages, after every pass but the last) and the merge (kMergeJob).
inline constexpr int kMergeJob = -1, kGatherJob = -2;
std::string keyOf(const nlohmann::json& ingredients); // "xxh128:<32 hex>"

// A complete store entry: manifest.json read back and each output's size and content hash checked against it (the
// hash through hashFileMemo in `memoFile`, so a cached run stats the files instead of reading them). An entry that
// does not match its manifest (a file cut, overwritten or gone) is removed from the store with a warning, so the
// stage runs again and stores it afresh; nullopt then, as for a key never stored.
struct StoreEntry {
    std::string dir;
    nlohmann::json manifest; // {"key","ingredients","outputs":{port:{"file","hash","bytes"}},"cost":{...}}
};
std::optional<StoreEntry> findStoreEntry(const std::string& store, const std::string& key,
                                         const std::string& memoFile = "");

// Removes temporary entries whose writer process on this host has died, and leftovers of replaced entries.
void sweepStore(const std::string& store);

// ---- shards ---------------------------------------------------------------------------------------------------

// Joins the bundles of shards 0..N-1 (any order) into the bundle the unsharded stage writes, bit for bit once
// written: "vertex_range" layers become "vertex" layers, rows concatenated, shard bookkeeping removed from their
// params and the counters "rays" and "back_face_hits" summed. Needs the same mesh, producer, inputs, layer names
// and other params in every shard, and row ranges that tile [0, vertex_count) exactly once; throws prt::Error
// naming the offending shard file otherwise.
Bundle mergeShards(const std::vector<Bundle>& shards, const std::vector<std::string>& files);
// mergeShards over shard files, streamed into `output` (written atomically): each shard's header is read once
// (readBundleHeader, checksum checked) and its meshes compared with the first's and dropped; then the merged
// bundle's JSON is computed from the headers alone and every layer's bytes are copied shard by shard in 1 MiB
// pieces, each shard read by ranges (streamLayerBytes, which refuses bytes that changed since the check). The file
// is the one writeBundle(output, mergeShards(...)) writes, byte for byte. Memory: the first shard's meshes, one
// other shard's meshes at a time and every shard's layer descriptions, whatever the layers' sizes. Layers every
// shard holds whole are compared by their bytes' XXH3-128 hashes. Throws as mergeShards, naming the shard file.
void mergeShardFiles(const std::vector<std::string>& files, const std::string& output);

// ---- running --------------------------------------------------------------------------------------------------

enum class Executor { Local, Slurm };

struct RunOptions {
    std::string prt;           // the prt binary the stages run as (`prt STAGE ...`)
    std::string cacheDir = ".cache"; // store in CACHE/store, run folders in CACHE/runs
    Executor executor = Executor::Local;
    bool plan = false;         // print what would run and why; run nothing
    bool force = false;        // rerun every stage
    std::string only;          // rerun this stage alone, its inputs from the store
    std::string from;          // rerun this stage and everything downstream, the rest from the store
    int shards = 0;            // > 0: shard every stage that can take it into this many
    int threads = 0;           // per stage; 0 = all cores (Slurm: the job's CPUs)
    std::string reportPath;    // also copy the run report here
    // After a successful run the store drops the entries of sharded stages' shard, pass and gather jobs (hit
    // records, pass rows, gathered exitant arrays, shard bundles) whose stage's merged entry is stored; a cached
    // rerun needs only the merged entries. true keeps them (docs/pipelines.md, "Store garbage collection").
    bool keepIntermediates = false;
    // Slurm
    std::string slurmPartition;
    int slurmCpusPerTask = 1;
    double slurmPollSeconds = 0.5;
    std::vector<std::string> slurmArgs; // extra sbatch arguments, passed as given
    // Answers `prt ARGS` for `prt --build-info` and `prt --resolved-options STAGE ...` in this process, with the
    // option definitions the stage itself parses with (prt::cli::inProcessAnswers, apps/cli/cli.h). Required: no
    // key is ever computed by starting a process, so runPipeline and runStageJob throw without it.
    std::function<nlohmann::json(const std::vector<std::string>& args)> askPrt = nullptr;
};

// The content hash of a file (hashFile), memoised in `memoFile` (JSON; "" keeps the memo in this process only)
// by the file's absolute path and stat identity: size, mtime and ctime in nanoseconds, inode and device. A memo
// entry is used only when all of these match, and recorded only when the file did not change while it was hashed
// and its mtime and ctime are more than 2 s old; since any write moves ctime, which no call can set back, every
// change of content defeats the memo (hash_memo.cpp states the rule). Throws prt::Error when the file cannot be
// read.
std::string hashFileMemo(const std::string& path, const std::string& memoFile);
// CACHE/hash-memo.json: the memo a run with these options keeps.
std::string hashMemoFile(const RunOptions& options);

// Runs a pipeline and returns its report (also written to CACHE/runs/<name>-<time>-<pid>/report.json):
// {"pipeline","file","executor","ok","seconds","cache_hits","stages_run","peak_memory_bytes",
//  "stages":[{"id","stage","version","key","status":"cached|ran|failed|not run","reason","start","end",
//             "seconds","rays","peak_memory_bytes","outputs":{port:{"hash","bytes"}},"shards":[...]}],
//  "outputs":{name:{"path","hash","kind","from"}}}
// Times are seconds from the run's start. Declared outputs are copied atomically once every stage succeeded.
// Throws prt::Error for a stage that fails (naming it and quoting its log), after writing the report.
nlohmann::json runPipeline(const Pipeline& pipeline, const RunOptions& options);

// `prt gc`: removes every store entry that no stage of any pipeline's last recorded run (CACHE/runs/NAME.last.json)
// needs, so each of those runs stays fully cached; with `dryRun` only reports. Each removal is crash-safe (one
// rename takes an entry out whole, sweepStore clears what a killed collector leaves). Returns {"store",
// "dry_run","kept","kept_bytes","removed":[{"key","bytes"}],"removed_bytes"}. Throws prt::Error for a run record
// that is not JSON. Not to be run while a run writes to the same store.
nlohmann::json collectStore(const RunOptions& options, bool dryRun);

// Fills every stage's `resolved` and `build` (above) through options.askPrt, in this process (each distinct
// question once per process). Throws prt::Error when askPrt is unset or cannot say.
void resolveStageOptions(Pipeline& pipeline, const RunOptions& options);

// One stage job, the unit both executors run: resolves the stage's inputs from the store (its upstream stages
// must be complete), and unless `force` is set and if the entry is missing, runs the stage (or one shard of it
// in pass `pass`, the gather of pass `pass` when shardIndex == kGatherJob, or the merge of its shards when
// shardIndex == kMergeJob and the stage is sharded) and commits the entry. A job of a later pass needs the
// earlier passes' jobs stored. Returns the job's record for the report: {"id","shard","pass"?,"key",
// "status":"cached|ran","start","end","seconds","rays","peak_memory_bytes","outputs"} with epoch-second times.
// Throws prt::Error quoting the stage's log.
nlohmann::json runStageJob(const Pipeline& pipeline, const PipelineStage& stage, const RunOptions& options,
                           int shardIndex, int shardCount, bool force, int pass = 0);

// Where a Slurm job leaves its record for the waiting `prt run`: RUN_DIR/jobs/<stage id>.<part>.json, part being
// "all", "<index>of<count>", "merge", or with a pass "p<pass>.<index>of<count>" and "p<pass>.gather".
std::string jobRecordPath(const std::string& runDir, const std::string& stageId, int shardIndex, int shardCount,
                          int pass = 0);

} // namespace prt
