// Receiver points shaded per second by the FIV runtime with 1, 2 and 8 occluders (Google Benchmark; run by hand:
// build/tests/fiv/bench_fiv). The grid is a sphere's at 64x33x15; the cost does not depend on the mesh.
#include "fiv.h"
#include "fiv_test_util.h"

#include "runtime.h"
#include "scene.h"

#include <benchmark/benchmark.h>

using namespace prt;

namespace {

struct Setup {
    Bundle bundle;
    FivOccluder occluder;
    FivLighting lighting;
    std::vector<float> positions, normals;
};

const Setup& setup() {
    static Setup s = [] {
        Setup s;
        fiv::VisibilityOptions options;
        options.grid.azimuth = 64, options.grid.polar = 33, options.grid.shells = 15;
        options.cube = 16;
        TriMesh sphere = makeSphere(1.0f, 16, 32);
        fiv::Visibility vis = fiv::sampleVisibility(sphere, options, "sphere");
        fiv::CubeEnvironment env = fivtest::cubeFrom(16, [](const double* d) {
            return std::array<double, 3>{1.0 + d[1], 1.0, 0.5 + 0.5 * d[0]};
        });
        fiv::FivBundleOptions bundleOptions;
        bundleOptions.difmapSize = 16;
        s.bundle = fiv::fivBundle(sphere, fiv::reduceVisibility(vis, env), fiv::difMap(env, 16),
                                  fiv::environmentFiv(env), bundleOptions, {});
        s.occluder = fivOccluder(s.bundle, "sphere");
        s.lighting = fivLighting(s.bundle, "sphere");
        TriMesh plane = makePlane(8.0f, 64); // 65 x 65 points
        s.positions = plane.positions;
        s.normals = plane.normals;
        return s;
    }();
    return s;
}

void shadePoints(benchmark::State& state) {
    const Setup& s = setup();
    int occluders = int(state.range(0));
    std::vector<FivInstance> instances;
    for (int j = 0; j < occluders; ++j)
        instances.push_back({&s.occluder, {float(j % 4) - 1.5f, 1.5f + 0.1f * float(j), float(j / 4) - 0.5f}});
    size_t count = s.positions.size() / 3;
    std::vector<float> irradiance(3 * count);
    for (auto _ : state) {
        fivIrradiance(s.lighting, instances.data(), instances.size(), nullptr, s.positions.data(), s.normals.data(),
                      count, {}, irradiance.data());
        benchmark::DoNotOptimize(irradiance.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(count));
    state.counters["points_per_second"] = benchmark::Counter(double(state.iterations()) * double(count), benchmark::Counter::kIsRate);
}

} // namespace

BENCHMARK(shadePoints)->Arg(1)->Arg(2)->Arg(8)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
