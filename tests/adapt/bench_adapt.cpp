// Relight speed, full order against adaptive: the same mesh's transfer relit at full order and with each vertex's
// own bands. `bench_adapt FULL.glb ADAPTIVE.glb [benchmark flags]` times two bundles (`prt adapt` output); without
// bundles it times a synthetic 100,000-vertex order-8 transfer whose orders spread over 2..8. Prints the ratio.
#include "runtime.h"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstring>
#include <random>
#include <string>

namespace {

struct Workload {
    prt::RelightModel model;
    std::vector<float> lighting, radiance;
    double bytesPerRelight = 0.0;
};

Workload prepare(prt::RelightModel model) {
    Workload w;
    w.model = std::move(model);
    std::mt19937 random(1);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    w.lighting.resize(size_t(w.model.order) * w.model.order * 3);
    for (float& value : w.lighting) value = uniform(random);
    w.radiance.resize(size_t(w.model.vertexCount) * 3);
    w.bytesPerRelight = double(prt::relightBytes(w.model));
    return w;
}

prt::RelightModel synthetic(bool adaptive) {
    const uint32_t V = 100000;
    const int order = 8;
    std::mt19937 random(2);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    prt::RelightModel model;
    model.vertexCount = V;
    model.order = order;
    if (!adaptive) {
        model.transfer.resize(size_t(V) * order * order * 3);
    } else { // patches of 64 vertices of one order, as graded meshes have
        model.offsets.resize(V + 1, 0);
        for (uint32_t v = 0; v < V; ++v) {
            uint32_t n = 2 + (v / 64 * 2654435761u >> 7) % 7;
            model.offsets[v + 1] = model.offsets[v] + n * n;
        }
        model.transfer.resize(size_t(model.offsets[V]) * 3);
    }
    for (float& value : model.transfer) value = uniform(random);
    return model;
}

Workload full, adaptive;

void relightOne(benchmark::State& state, Workload* w) {
    for (auto _ : state) {
        prt::relight(w->model, w->lighting.data(), 0, w->model.vertexCount, w->radiance.data());
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * w->model.vertexCount);
    state.SetBytesProcessed(int64_t(state.iterations() * w->bytesPerRelight));
}

// Collects the mean real time per iteration of each run, for the ratio.
class RatioReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        for (const Run& run : runs)
            if (run.run_type == Run::RT_Iteration) {
                seconds[run.benchmark_name()] = run.GetAdjustedRealTime();
                cpuSeconds[run.benchmark_name()] = run.GetAdjustedCPUTime();
            }
        ConsoleReporter::ReportRuns(runs);
    }
    std::map<std::string, double> seconds, cpuSeconds;
};

} // namespace

int main(int argc, char** argv) {
    int first = 1;
    if (argc >= 3 && std::strncmp(argv[1], "--", 2) != 0 && std::strncmp(argv[2], "--", 2) != 0) {
        full = prepare(prt::loadRelightModel(argv[1]));
        adaptive = prepare(prt::loadRelightModel(argv[2]));
        first = 3;
    } else {
        full = prepare(synthetic(false));
        adaptive = prepare(synthetic(true));
    }
    // The kernel is single-threaded for adaptive models; time the full model single-threaded too, through the
    // same kernel, so the ratio is per core.
    prt::RelightModel& fullModel = full.model;
    benchmark::RegisterBenchmark("relight/full", [&](benchmark::State& state) {
        const int coefficients = fullModel.order * fullModel.order;
        for (auto _ : state) {
            prt::relight(fullModel.transfer.data(), fullModel.vertexCount, coefficients, full.lighting.data(),
                         full.radiance.data());
            benchmark::ClobberMemory();
        }
        state.SetItemsProcessed(int64_t(state.iterations()) * fullModel.vertexCount);
        state.SetBytesProcessed(int64_t(state.iterations() * full.bytesPerRelight));
    });
    benchmark::RegisterBenchmark("relight/adaptive", relightOne, &adaptive);
    std::vector<char*> args = {argv[0]};
    for (int i = first; i < argc; ++i) args.push_back(argv[i]);
    int count = int(args.size());
    benchmark::Initialize(&count, args.data());
    RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    double fullTime = reporter.seconds["relight/full"], adaptiveTime = reporter.seconds["relight/adaptive"];
    std::printf("vertices %u, bytes read per relight: full %.0f, adaptive %.0f (%.2fx fewer)\n", full.model.vertexCount,
                full.bytesPerRelight, adaptive.bytesPerRelight, full.bytesPerRelight / adaptive.bytesPerRelight);
    if (adaptiveTime > 0.0) std::printf("speedup adaptive over full: %.2fx\n", fullTime / adaptiveTime);
    double fullCpu = reporter.cpuSeconds["relight/full"], adaptiveCpu = reporter.cpuSeconds["relight/adaptive"];
    if (adaptiveCpu > 0.0) std::printf("speedup by CPU time (steadier on a loaded machine): %.2fx\n", fullCpu / adaptiveCpu);
    return 0;
}
