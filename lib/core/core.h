// prt core: errors, atomic artifact writes, content hashes, logging with progress, and stage cost.
//
// Every stage reports failures as prt::Error, which names the file, the place inside it and the problem.
// The driver turns an Error into one line on stderr and its exit code; see README "Exit codes".
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace prt {

// Process exit codes, documented in the README.
enum ExitCode : int {
    kExitOk = 0,
    kExitFailure = 1,     // internal error (a bug)
    kExitUsage = 2,       // bad command line
    kExitInput = 3,       // bad or missing input file
    kExitOutput = 4,      // output could not be written
    kExitInterrupted = 5, // stopped by a signal
};

// An error the user can act on. what() reads "FILE: PLACE: PROBLEM" (empty parts are skipped).
class Error : public std::runtime_error {
public:
    Error(std::string file, std::string place, std::string problem, int exitCode = kExitInput);
    const std::string& file() const { return file_; }
    const std::string& place() const { return place_; }
    const std::string& problem() const { return problem_; }
    int exitCode() const { return exitCode_; }

private:
    std::string file_, place_, problem_;
    int exitCode_;
};

// `path` with its links resolved (std::filesystem::weakly_canonical, so it need not exist) when that lies strictly
// inside `folder`, whose links are resolved too; "" when it does not, or when either cannot be resolved. What every
// reader that follows a name found in a file (a URI, an MTL, a texture) asks before it opens it.
std::string resolvedInside(const std::string& path, const std::string& folder);

// Reads a whole file. Throws Error naming the path when it is missing or unreadable.
std::string readFileBytes(const std::string& path);

// Writes an artifact atomically: `write` receives a temporary path in the same folder, fills it, and returns;
// the temporary file is then fsynced and renamed onto `path`. If `write` throws, the temporary file is removed
// and the exception propagates, so `path` never exists half-written and an older `path` is left untouched.
// Temporary names are ".NAME.tmp-HOST-PID-N-R" (freshTemporaryPath), so a SIGKILLed stage leaves at most such a
// file, never `path`; the next write of `path` on that host removes those of processes that no longer exist (a
// scan of path's folder).
void writeFileAtomic(const std::string& path, const std::function<void(const std::string& tmpPath)>& write);

// A new, empty temporary file for `path`, in its folder, and its name: ".NAME.tmp-HOST-PID-N-R" (R 16 random hex
// digits) followed by `suffix` (an extension, for writers that choose a format by it). It is created as a new
// regular file (O_EXCL, O_NOFOLLOW), so a link or a file planted at the name is never written through. First
// removes the temporaries of `path` that writers on this host left when they were killed (those of processes that
// no longer exist). For writers that rename the file themselves, as the bake does to name a texture by its
// content; writeFileAtomic takes its temporaries from here. Throws prt::Error(kExitOutput) naming `path`.
std::string freshTemporaryPath(const std::string& path, const std::string& suffix = "");

// A point where a SIGKILL must leave no corrupt artifact: before and after every rename into place, at the
// start of every command, at each progress step, around store commits. Environment (tests only):
// PRT_KILL_AT=N makes the process SIGKILL itself at the Nth checkpoint (N <= 0 or unset: never);
// PRT_KILL_COUNTER=FILE counts checkpoints across every process sharing FILE (a `prt run` and its stages), else
// each process counts its own; PRT_KILL_TRACE=FILE appends "PID N NAME" per checkpoint, so a test learns how
// many points a clean run passes.
void checkpoint(const char* name);

// The concurrency of a stage's TBB task arena for its --threads: -1 (tbb::task_arena::automatic, every processor)
// for 0 or less, else `threads` but no more than the machine's processors (TBB prints a warning of its own on stderr,
// outside prt's log, when asked for more). Outputs never depend on it: every stage gives the same bits for any
// thread count.
int arenaConcurrency(int threads);

// This host's name (gethostname): what temporary names and store folders say of their writer.
std::string hostName();
// Whether process `pid` of this host has ended (kill(pid, 0) says it does not exist): a writer whose temporary files
// or folders may be removed. False for pid <= 0 and for processes that exist, whoever's.
bool processHasEnded(long pid);

// Convenience over writeFileAtomic for an in-memory buffer.
void writeBytesAtomic(const std::string& path, std::string_view bytes);

// Content hash (XXH3-128) as 32 lowercase hex digits, prefixed "xxh128:". Stable across machines and runs.
std::string hashBytes(const void* data, size_t size);
std::string hashFile(const std::string& path);

// ---- logging and progress ----------------------------------------------------------------------------------
// One process-wide log sink on stderr. Human text by default; with json, one JSON object per line
// ({"level":..,"msg":..} or {"event":"progress",..}). quiet suppresses info and progress, not warnings or errors.
struct LogOptions {
    bool quiet = false;
    bool json = false;
};
void setLogOptions(const LogOptions& options);
const LogOptions& logOptions();
void logInfo(const std::string& message);
void logWarn(const std::string& message);
void logError(const std::string& message);
// Emits a structured record (JSON mode: as-is plus "event"; text mode: "event: k=v ...").
void logEvent(const std::string& event, const std::string& jsonObject);

// Progress over a known amount of work, printed at most a few times per second with rate and ETA.
// Thread-safe: add() may be called from worker threads.
class Progress {
public:
    Progress(std::string label, uint64_t total);
    ~Progress();
    void add(uint64_t done);
    void finish();

    struct State;

private:
    State* state_;
};

// ---- cost ---------------------------------------------------------------------------------------------------
// What a stage spent. Every stage fills one and prints it (text) or logs it (JSON) when it ends.
struct StageCost {
    std::string stage;
    double seconds = 0.0;
    uint64_t rays = 0;
    uint64_t peakMemoryBytes = 0; // process peak resident set size
};
uint64_t peakMemoryBytes();
void reportCost(const StageCost& cost);
// reportCost for `stage` begun at `start` (nowSeconds), having cast `rays`: the time to now, this process's peak.
void reportCost(const std::string& stage, double start, uint64_t rays);

// Monotonic wall clock in seconds.
double nowSeconds();

// Lower-case file extension without the dot ("glb", "obj"); empty if none.
std::string fileExtension(const std::string& path);

// ---- shards -------------------------------------------------------------------------------------------------
// Rows [begin, end) of shard `index` of `count` over `rows` rows (0 <= index < count): contiguous, in shard order,
// sizes differing by at most one, the shards tiling [0, rows) exactly. Every `--shard I/N` stage splits by this.
struct RowRange {
    size_t begin = 0, end = 0;
};
inline RowRange shardRows(size_t rows, int index, int count) {
    return {rows * size_t(index) / size_t(count), rows * size_t(index + 1) / size_t(count)};
}

// ---- memory caps ------------------------------------------------------------------------------------------
// Every count read from a file (vertices, faces, texels, grid samples, array elements) is checked against one cap
// before anything is allocated for it. The cap is kDefaultMaxElements unless the environment variable
// PRT_MAX_ELEMENTS holds another positive integer (a bad value is a command-line error, exit 2).
inline constexpr uint64_t kDefaultMaxElements = uint64_t(1) << 30;
uint64_t maxElements();
// Throws Error(file, place, "claims COUNT WHAT, above the limit of N (PRT_MAX_ELEMENTS ...)") above the cap.
void checkElementCount(uint64_t count, const std::string& what, const std::string& file, const std::string& place);
// The product of `factors` (a shape), after the same check; an overflowing product is refused the same way.
uint64_t checkedProduct(const std::vector<uint64_t>& factors, const std::string& what, const std::string& file,
                        const std::string& place);

// Before a result is written to `path`: every one of `count` values is finite, else prt::Error (kExitInput) naming
// `path`, the first value that is not (its row of `rowLength` values, and its column) and the likely cause, inputs
// whose values overflow float on the way (a map texel or a light of 3e38). JSON would write such a value as null,
// .npy as itself, and the next stage would refuse or propagate it.
void requireFiniteResult(const float* values, size_t count, size_t rowLength, const std::string& path);

// ---- .npy arrays --------------------------------------------------------------------------------------------
// float32, C order. Used for per-vertex radiance [V,3] and other per-element outputs.
void writeNpy(const std::string& path, const std::vector<float>& data, const std::vector<size_t>& shape);
std::vector<float> readNpy(const std::string& path, std::vector<size_t>* shape);
// uint8 ('|u1'), C order, atomic: quantised tables (the hybrid's cone visibility per turn).
void writeNpyU8(const std::string& path, const std::vector<uint8_t>& data, const std::vector<size_t>& shape);

} // namespace prt
