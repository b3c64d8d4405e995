// Relighting throughput at orders 3, 5 and 8 (or those of --orders) for every storage the runtime relights from
// (float32, half, u16 and u8 codes, vertex-blocked and row by row, clustered PCA), each next to two memory
// yardsticks measured in the same run: a plain read (64-bit word sum) of exactly the bytes that relight reads
// (relightBytes), and that read plus the radiance writes. The table at the end gives bytes per vertex, Mvert/s,
// each storage against float32, each relight against both yardsticks, and the second yardstick against the first
// ("write bound": about the most a relight that writes its radiance can reach against the read alone; not a strict
// bound where the data sit in cache). Single-threaded: relight()
// runs on the calling thread without a job system. Run by hand:
// build/tests/runtime/bench_runtime [--vertices N] [--orders 1,2,3].
#include "prt/relight.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

size_t gVertices = 1000000;

// half / u16 / u8: vertex-blocked rows, as the loader holds them (blockRows); "-rows": the same rows row by row;
// "-ragged": graded orders as `prt adapt` stores them, blocked by band count as the loader holds them, or with "-rows"
// row by row: runs of 1..3 vertices at the order or one to three bands fewer (the bunny's u8 bundle at --max-error
// 0.005, order 8: bands 5..8, runs of 1.75 vertices on average).
constexpr const char* kStorages[] = {"float32", "half",      "half-rows", "half-ragged", "half-ragged-rows",
                                     "u16",     "u16-rows",  "u16-ragged", "u16-ragged-rows",
                                     "u8",      "u8-rows",   "u8-ragged", "u8-ragged-rows", "cpca"};

// A fast deterministic fill (the values do not matter to the speed, only that they are not all alike).
struct Lcg {
    uint64_t state;
    uint32_t next() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return uint32_t(state >> 33);
    }
    float unit() { return float(next() & 0xffffff) / float(0x800000) - 1.0f; }
};

prt::RelightModel makeModel(const std::string& storage, int order) {
    Lcg random{uint64_t(order) * 977 + storage.size()};
    prt::RelightModel model;
    model.vertexCount = uint32_t(gVertices);
    model.order = order;
    const size_t n = size_t(order) * order, values = gVertices * n * 3;
    if (storage == "float32") {
        model.transfer.resize(values);
        for (float& value : model.transfer) value = random.unit();
        return model;
    }
    if (storage == "cpca") { // 64 clusters of 8 directions, as `prt adapt --format cpca` might choose
        const uint32_t K = 64, M = 8;
        model.storage = prt::TransferStorage::Cpca;
        model.cpcaClusters = K;
        model.cpcaComponents = M;
        model.cpcaBasis.resize(size_t(K) * (M + 1) * n * 3);
        for (float& value : model.cpcaBasis) value = random.unit();
        model.cpcaWeights.resize(gVertices * M);
        for (float& value : model.cpcaWeights) value = random.unit();
        model.cpcaCluster.resize(gVertices);
        for (uint32_t& k : model.cpcaCluster) k = random.next() % K;
        return model;
    }
    // The adaptive layout: offsets (one uniform order, or graded), and for codes one scale per (vertex, band).
    const bool ragged = storage.find("-ragged") != std::string::npos;
    std::vector<int> bands(gVertices, order);
    for (size_t v = 0; ragged && v < gVertices;) {
        const int patchBands = std::max(1, order - int(random.next() % 4));
        const size_t patch = 1 + random.next() % 3;
        for (size_t i = v; i < std::min(gVertices, v + patch); ++i) bands[i] = patchBands;
        v += patch;
    }
    model.offsets.resize(gVertices + 1);
    for (size_t v = 0; v < gVertices; ++v) model.offsets[v + 1] = model.offsets[v] + uint32_t(bands[v] * bands[v]);
    const size_t rows = model.offsets[gVertices];
    if (storage.rfind("half", 0) == 0) {
        model.storage = prt::TransferStorage::Float16;
        model.halves.resize(rows * 3);
        for (uint16_t& half : model.halves) half = uint16_t(random.next() & 0xbbff); // finite, mixed signs
        if (storage.find("-rows") == std::string::npos) prt::blockRows(model);
        return model;
    }
    const bool u8 = storage.rfind("u8", 0) == 0;
    const uint32_t C = u8 ? 127 : 32767;
    model.storage = u8 ? prt::TransferStorage::Uint8 : prt::TransferStorage::Uint16;
    if (u8) {
        model.codes8.resize(rows * 3);
        for (uint8_t& code : model.codes8) code = uint8_t(random.next() % (2 * C + 1));
    } else {
        model.codes16.resize(rows * 3);
        for (uint16_t& code : model.codes16) code = uint16_t(random.next() % (2 * C + 1));
    }
    for (size_t v = 0; v < gVertices; ++v) {
        if (v % prt::kRelightBlock == 0) model.bandBlockStarts.push_back(uint32_t(model.bandScales.size()));
        for (int l = 0; l < bands[v]; ++l) model.bandScales.push_back((1.0f + random.unit()) / float(C));
    }
    model.bandBlockStarts.push_back(uint32_t(model.bandScales.size()));
    if (storage.find("-rows") == std::string::npos) prt::blockRows(model);
    return model;
}

struct Workload {
    prt::RelightModel model;
    std::vector<float> lighting, radiance;
    std::vector<std::pair<const void*, size_t>> buffers; // what relight reads, for the yardstick
};

// One workload at a time (the largest is about 0.8 GB), built on first use and dropped when the next is asked for.
Workload& workload(const std::string& storage, int order) {
    static std::unique_ptr<Workload> current;
    static std::string key;
    const std::string wanted = storage + "/" + std::to_string(order);
    if (!current || key != wanted) {
        current.reset();
        current = std::make_unique<Workload>();
        key = wanted;
        Workload& w = *current;
        w.model = makeModel(storage, order);
        Lcg random{7};
        w.lighting.resize(size_t(order) * order * 3);
        for (float& value : w.lighting) value = random.unit();
        w.radiance.resize(gVertices * 3);
        const prt::RelightModel& m = w.model;
        auto add = [&](const auto& array) {
            if (!array.empty()) w.buffers.push_back({array.data(), array.size() * sizeof(array[0])});
        };
        add(m.transfer), add(m.halves), add(m.codes8), add(m.codes16), add(m.bandScales), add(m.scaleCluster);
        add(m.blockedRuns), add(m.blockedLanes);
        if (!m.rowsBlocked) add(m.offsets), add(m.bandBlockStarts); // the blocked kernel reads neither
        add(m.cpcaBasis), add(m.cpcaWeights), add(m.cpcaCluster);
    }
    return *current;
}

void relightStorage(benchmark::State& state, std::string storage, int order) {
    Workload& w = workload(storage, order);
    for (auto _ : state) {
        prt::relight(w.model, w.lighting.data(), 0, w.model.vertexCount, w.radiance.data());
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(gVertices));
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(prt::relightBytes(w.model)));
    state.counters["bytes_per_vertex"] = double(prt::relightBytes(w.model)) / double(gVertices);
}

// The bytes of every buffer relight reads that vertices [first, last) own, read once as 64-bit words and summed
// into 8 independent lanes.
uint64_t sumBuffers(const Workload& w, size_t first, size_t last) {
    uint64_t lanes[8] = {}; // local, so that they live in registers
    for (const auto& [data, bytes] : w.buffers) {
        // The share of this buffer that vertices [first, last) own, in whole 64-byte lines.
        const size_t begin = bytes * first / gVertices / 64 * 64;
        const size_t end = last == gVertices ? bytes : bytes * last / gVertices / 64 * 64;
        const unsigned char* p = static_cast<const unsigned char*>(data);
        size_t i = begin;
        for (; i + 64 <= end; i += 64) {
            uint64_t words[8];
            std::memcpy(words, p + i, 64);
            for (int k = 0; k < 8; ++k) lanes[k] += words[k];
        }
        for (; i < end; ++i) lanes[0] += p[i];
    }
    uint64_t sum = 0;
    for (uint64_t lane : lanes) sum += lane;
    return sum;
}

// The yardstick of the goal: every byte relight reads, read once (sumBuffers).
void streamStorage(benchmark::State& state, std::string storage, int order) {
    Workload& w = workload(storage, order);
    for (auto _ : state) {
        benchmark::ClobberMemory(); // the arrays may have changed, so the sums cannot be hoisted
        benchmark::DoNotOptimize(sumBuffers(w, 0, gVertices));
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(gVertices));
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(prt::relightBytes(w.model)));
}

// A second yardstick, for where the time goes: the same read, and the 12 bytes of radiance per vertex that relight
// writes, written through the cache as relight writes them, interleaved with the reads in runs of 1,024 vertices.
// The ratio of the two yardsticks is about the most a relight that writes its radiance can reach against the
// first; a relight well below the second is bound by its own instructions, not by memory.
void streamWriteStorage(benchmark::State& state, std::string storage, int order) {
    Workload& w = workload(storage, order);
    constexpr size_t kRun = 1024;
    for (auto _ : state) {
        benchmark::ClobberMemory();
        for (size_t first = 0; first < gVertices; first += kRun) {
            const size_t last = std::min(gVertices, first + kRun);
            const float value = float(sumBuffers(w, first, last) & 0xff);
            std::fill(w.radiance.begin() + first * 3, w.radiance.begin() + last * 3, value);
        }
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(gVertices));
}

// Console output as usual, plus vertices/s and bytes per vertex kept for the table.
class RatioReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& run : runs)
            if (run.run_type == Run::RT_Iteration) {
                const std::string name = run.benchmark_name().substr(0, run.benchmark_name().find("/min_time"));
                rate[name] = run.counters.at("items_per_second");
                auto found = run.counters.find("bytes_per_vertex");
                if (found != run.counters.end()) bytesPerVertex[name] = found->second;
            }
    }
    std::map<std::string, double> rate, bytesPerVertex;
};

} // namespace

int main(int argc, char** argv) {
    std::vector<int> orders = {3, 5, 8};
    for (int i = 1; i + 1 < argc;)
        if (std::strcmp(argv[i], "--vertices") == 0 || std::strcmp(argv[i], "--orders") == 0) {
            if (std::strcmp(argv[i], "--vertices") == 0) {
                gVertices = std::strtoull(argv[i + 1], nullptr, 10);
            } else { // a comma-separated list of orders in 1..8
                orders.clear();
                for (const char* p = argv[i + 1]; *p;) {
                    char* end = nullptr;
                    const long order = std::strtol(p, &end, 10);
                    if (end == p || order < 1 || order > 8) {
                        std::fprintf(stderr, "bench_runtime: --orders wants orders in 1..8, e.g. 1,2,3\n");
                        return 2;
                    }
                    orders.push_back(int(order));
                    p = *end == ',' ? end + 1 : end;
                }
            }
            for (int j = i; j + 2 <= argc; ++j) argv[j] = argv[j + 2];
            argc -= 2;
        } else {
            ++i;
        }
    // Per storage and order, relight and yardstick run back to back on one workload, so both see the same load.
    for (int order : orders)
        for (const char* storage : kStorages) {
            const std::string name = std::string(storage) + "/" + std::to_string(order);
            benchmark::RegisterBenchmark(("relight/" + name).c_str(), relightStorage, storage, order)
                ->Unit(benchmark::kMillisecond)
                ->MinTime(0.3);
            benchmark::RegisterBenchmark(("stream/" + name).c_str(), streamStorage, storage, order)
                ->Unit(benchmark::kMillisecond)
                ->MinTime(0.3);
            benchmark::RegisterBenchmark(("stream+write/" + name).c_str(), streamWriteStorage, storage, order)
                ->Unit(benchmark::kMillisecond)
                ->MinTime(0.3);
        }
    benchmark::Initialize(&argc, argv);
    RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    std::printf("\n%zu vertices, single thread\n%-6s %-8s %10s %12s %14s %14s %12s %14s %14s %12s\n", gVertices,
                "order", "storage", "B/vertex", "MB/relight", "relight Mv/s", "stream Mv/s", "vs float32",
                "relight/stream", "/stream+write", "write bound");
    for (int order : orders)
        for (const char* storage : kStorages) {
            const std::string name = std::string(storage) + "/" + std::to_string(order);
            auto get = [](const std::map<std::string, double>& table, const std::string& key) {
                auto found = table.find(key);
                return found == table.end() ? 0.0 : found->second;
            };
            const double relightRate = get(reporter.rate, "relight/" + name);
            const double streamRate = get(reporter.rate, "stream/" + name),
                         floatRate = get(reporter.rate, "relight/float32/" + std::to_string(order));
            const double bytesPerVertex = get(reporter.bytesPerVertex, "relight/" + name);
            const double writeRate = get(reporter.rate, "stream+write/" + name);
            std::printf("%-6d %-8s %10.1f %12.1f %14.1f %14.1f %12.2f %14.2f %14.2f %12.2f\n", order, storage,
                        bytesPerVertex, bytesPerVertex * double(gVertices) / 1e6, relightRate / 1e6, streamRate / 1e6,
                        floatRate > 0 ? relightRate / floatRate : 0.0, streamRate > 0 ? relightRate / streamRate : 0.0,
                        writeRate > 0 ? relightRate / writeRate : 0.0, streamRate > 0 ? writeRate / streamRate : 0.0);
        }
    benchmark::Shutdown();
    return 0;
}
