// Relighting throughput in vertices per second at orders 3, 5 and 8, next to a memory-bandwidth yardstick: a
// plain sum over the same transfer array in the same run. The kernel reads each transfer value once, so the sum
// is the speed it can at best approach; the table at the end gives the ratio.
#include "runtime.h"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <random>

namespace {

constexpr size_t kVertices = 100000;

struct Workload {
    prt::RelightModel model;
    std::vector<float> lighting;
    std::vector<float> radiance;
};

Workload& workload(int order) {
    static std::map<int, Workload> workloads;
    Workload& w = workloads[order];
    if (w.model.order == 0) {
        std::mt19937 random(order);
        std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
        w.model.vertexCount = kVertices;
        w.model.order = order;
        w.model.transfer.resize(kVertices * order * order * 3);
        for (float& value : w.model.transfer) value = uniform(random);
        w.lighting.resize(size_t(order) * order * 3);
        for (float& value : w.lighting) value = uniform(random);
        w.radiance.resize(kVertices * 3);
    }
    return w;
}

void setCounters(benchmark::State& state, int order) {
    state.SetItemsProcessed(int64_t(state.iterations()) * kVertices);
    state.SetBytesProcessed(int64_t(state.iterations()) * kVertices * order * order * 3 * sizeof(float));
}

void relightKernel(benchmark::State& state) {
    int order = int(state.range(0));
    Workload& w = workload(order);
    for (auto _ : state) {
        prt::relight(w.model.transfer.data(), kVertices, order * order, w.lighting.data(), w.radiance.data());
        benchmark::ClobberMemory();
    }
    setCounters(state, order);
}

void relightParallel(benchmark::State& state) {
    int order = int(state.range(0));
    Workload& w = workload(order);
    for (auto _ : state) {
        prt::relight(w.model, w.lighting.data(), 0, kVertices, w.radiance.data());
        benchmark::ClobberMemory();
    }
    setCounters(state, order);
}

// The yardstick: every transfer value read once and added, in independent lanes so it vectorises.
void sumTransfer(benchmark::State& state) {
    int order = int(state.range(0));
    const std::vector<float>& transfer = workload(order).model.transfer;
    for (auto _ : state) {
        benchmark::ClobberMemory(); // the array may have changed, so the sum cannot be hoisted out of the loop
        const float* values = transfer.data();
        float lanes[16] = {};
        for (size_t i = 0; i + 16 <= transfer.size(); i += 16) // 100000 rows: no remainder
            for (int k = 0; k < 16; ++k) lanes[k] += values[i + k];
        float sum = 0.0f;
        for (float lane : lanes) sum += lane;
        benchmark::DoNotOptimize(sum);
    }
    setCounters(state, order);
}

// Console output as usual, plus vertices/s per benchmark kept for the ratio table.
class RatioReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& run : runs)
            if (run.run_type == Run::RT_Iteration) verticesPerSecond[run.benchmark_name()] = run.counters.at("items_per_second");
    }
    std::map<std::string, double> verticesPerSecond;
};

} // namespace

int main(int argc, char** argv) {
    // Per order, kernel and yardstick run back to back, so both see the same machine load.
    for (int order : {3, 5, 8}) {
        benchmark::RegisterBenchmark("relightKernel", relightKernel)->Arg(order)->Unit(benchmark::kMicrosecond);
        benchmark::RegisterBenchmark("relightParallel", relightParallel)
            ->Arg(order)
            ->Unit(benchmark::kMicrosecond)
            ->UseRealTime();
        benchmark::RegisterBenchmark("sumTransfer", sumTransfer)->Arg(order)->Unit(benchmark::kMicrosecond);
    }
    benchmark::Initialize(&argc, argv);
    RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    std::printf("\n%-6s %16s %16s %16s %10s\n", "order", "kernel Mvert/s", "parallel Mvert/s", "sum Mvert/s",
                "kernel/sum");
    for (int order : {3, 5, 8}) {
        std::string arg = std::to_string(order);
        auto rate = [&](const std::string& name) {
            auto found = reporter.verticesPerSecond.find(name);
            return found == reporter.verticesPerSecond.end() ? 0.0 : found->second;
        };
        double kernel = rate("relightKernel/" + arg), parallel = rate("relightParallel/" + arg + "/real_time"),
               sum = rate("sumTransfer/" + arg);
        std::printf("%-6d %16.1f %16.1f %16.1f %10.2f\n", order, kernel / 1e6, parallel / 1e6, sum / 1e6,
                    sum > 0.0 ? kernel / sum : 0.0);
    }
    benchmark::Shutdown();
    return 0;
}
