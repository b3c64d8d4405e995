#include "core.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <sys/resource.h>

namespace prt {

static LogOptions gOptions;
static std::mutex gLogMutex;

void setLogOptions(const LogOptions& options) { gOptions = options; }
const LogOptions& logOptions() { return gOptions; }

double nowSeconds() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

// A log line as JSON; bytes of a message that are not UTF-8 (a file name, a name from an input file) are written as
// U+FFFD rather than failing the line.
static std::string dumpLine(const nlohmann::json& line) {
    return line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

static void emit(const char* level, const std::string& message) {
    std::lock_guard<std::mutex> lock(gLogMutex);
    if (gOptions.json) {
        nlohmann::json record = {{"level", level}, {"msg", message}};
        std::fprintf(stderr, "%s\n", dumpLine(record).c_str());
    } else if (std::string(level) == "info") {
        std::fprintf(stderr, "%s\n", message.c_str());
    } else {
        std::fprintf(stderr, "prt: %s: %s\n", level, message.c_str());
    }
}

void logInfo(const std::string& message) {
    if (!gOptions.quiet) emit("info", message);
}
void logWarn(const std::string& message) { emit("warning", message); }
void logError(const std::string& message) { emit("error", message); }

void logEvent(const std::string& event, const std::string& jsonObject) {
    if (gOptions.quiet && !gOptions.json) return;
    nlohmann::json record = nlohmann::json::parse(jsonObject, nullptr, false);
    if (!record.is_object()) record = nlohmann::json{{"value", jsonObject}};
    std::lock_guard<std::mutex> lock(gLogMutex);
    if (gOptions.json) {
        nlohmann::json line = {{"event", event}};
        line.update(record);
        std::fprintf(stderr, "%s\n", dumpLine(line).c_str());
    } else {
        std::string text = event + ":";
        for (auto& [key, value] : record.items()) text += " " + key + "=" + (value.is_string() ? value.get<std::string>() : dumpLine(value));
        std::fprintf(stderr, "%s\n", text.c_str());
    }
}

// ---- progress ------------------------------------------------------------------------------------------------

struct Progress::State {
    std::string label;
    uint64_t total = 0;
    uint64_t done = 0;
    double start = 0.0;
    double lastPrint = 0.0;
    bool finished = false;
    std::mutex mutex;
};

static std::string formatDuration(double seconds) {
    if (!std::isfinite(seconds) || seconds < 0) return "?";
    char text[32];
    if (seconds < 60) std::snprintf(text, sizeof(text), "%.1fs", seconds);
    else if (seconds < 3600) std::snprintf(text, sizeof(text), "%dm%02ds", int(seconds) / 60, int(seconds) % 60);
    else std::snprintf(text, sizeof(text), "%dh%02dm", int(seconds) / 3600, int(seconds) % 3600 / 60);
    return text;
}

static void printProgress(Progress::State& s, double now, bool final) {
    double elapsed = now - s.start;
    double fraction = s.total ? double(s.done) / double(s.total) : 1.0;
    double eta = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : NAN;
    std::lock_guard<std::mutex> lock(gLogMutex);
    if (gOptions.json) {
        nlohmann::json line = {{"event", "progress"}, {"label", s.label}, {"done", s.done}, {"total", s.total},
                               {"elapsed_s", elapsed}, {"eta_s", final ? 0.0 : (std::isfinite(eta) ? eta : -1.0)}};
        std::fprintf(stderr, "%s\n", dumpLine(line).c_str());
    } else {
        std::fprintf(stderr, "\r%s: %5.1f%% (%llu/%llu) elapsed %s eta %s%s", s.label.c_str(), 100.0 * fraction,
                     (unsigned long long)s.done, (unsigned long long)s.total, formatDuration(elapsed).c_str(),
                     final ? "0s" : formatDuration(eta).c_str(), final ? "\n" : "   ");
    }
    std::fflush(stderr);
}

Progress::Progress(std::string label, uint64_t total) : state_(new State) {
    state_->label = std::move(label);
    state_->total = total;
    state_->start = state_->lastPrint = nowSeconds();
}

Progress::~Progress() {
    finish();
    delete state_;
}

void Progress::add(uint64_t done) {
    checkpoint("progress");
    std::lock_guard<std::mutex> lock(state_->mutex);
    state_->done += done;
    if (gOptions.quiet) return;
    double now = nowSeconds();
    // Text redraws 4 times a second; JSON lines once a second keep logs small.
    double interval = gOptions.json ? 1.0 : 0.25;
    if (now - state_->lastPrint < interval) return;
    state_->lastPrint = now;
    printProgress(*state_, now, false);
}

void Progress::finish() {
    std::lock_guard<std::mutex> lock(state_->mutex);
    if (state_->finished) return;
    state_->finished = true;
    // Short jobs that never printed stay silent.
    if (gOptions.quiet || state_->lastPrint == state_->start) return;
    printProgress(*state_, nowSeconds(), true);
}

// ---- cost ----------------------------------------------------------------------------------------------------

uint64_t peakMemoryBytes() {
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    return uint64_t(usage.ru_maxrss) * 1024; // Linux reports kilobytes
}

void reportCost(const StageCost& cost) {
    nlohmann::json record = {{"stage", cost.stage}, {"seconds", cost.seconds}, {"rays", cost.rays},
                             {"peak_memory_bytes", cost.peakMemoryBytes}};
    if (gOptions.json) {
        logEvent("cost", dumpLine(record));
        return;
    }
    if (gOptions.quiet) return;
    char text[256];
    double megaRaysPerSecond = cost.seconds > 0 ? cost.rays / cost.seconds / 1e6 : 0.0;
    std::snprintf(text, sizeof(text), "%s: %.3f s, %llu rays (%.2f Mrays/s), peak memory %.1f MiB", cost.stage.c_str(),
                  cost.seconds, (unsigned long long)cost.rays, megaRaysPerSecond, cost.peakMemoryBytes / 1048576.0);
    emit("info", text);
}

void reportCost(const std::string& stage, double start, uint64_t rays) {
    StageCost cost;
    cost.stage = stage;
    cost.seconds = nowSeconds() - start;
    cost.rays = rays;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace prt
