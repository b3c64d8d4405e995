// The exhaustive grid search autoconfig is measured against, run by hand (scripts/autoconfig_figures.py; not a
// ctest test): every order x samples x bounces x format on ALL vertices, each transfer baked on the whole mesh and
// timed, its error under each map against a full reference (noise-corrected, as autoconfig measures it).
//   build/tests/autoconfig/autoconfig_grid MESH.glb OUT.csv ENV.exr REF.npy SE.npy [ENV REF SE ...]
// Columns: map, order, samples, bounces, format, bake_seconds (BVH build plus passes, best of five wall-clock runs, 2 threads),
// bake_cpu_seconds, bundle_bytes, error.
#include "autoconfig.h"

#include "core.h"
#include "runtime.h"
#include "transfer.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

using namespace prt;

int main(int argc, char** argv) {
    if (argc < 6 || (argc - 3) % 3 != 0) {
        std::fprintf(stderr, "usage: %s MESH.glb OUT.csv ENV.exr REF.npy SE.npy [ENV REF SE ...]\n", argv[0]);
        return 2;
    }
    try {
        TriMesh mesh = readBundle(argv[1]).mesh;
        const size_t V = mesh.vertexCount();
        struct Map {
            std::string name;
            std::vector<float> lighting, reference, standardError;
        };
        std::vector<Map> maps;
        const int maxOrder = 8;
        for (int i = 3; i + 2 < argc; i += 3) {
            Map map;
            map.name = std::filesystem::path(argv[i]).stem().string();
            map.lighting = environmentLighting(readEnvironmentMap(argv[i]), maxOrder, nullptr, sh::Window::None);
            std::vector<size_t> shape;
            map.reference = readNpy(argv[i + 1], &shape);
            map.standardError = readNpy(argv[i + 2], &shape);
            if (map.reference.size() != V * 3 || map.standardError.size() != V * 3)
                throw Error(argv[i + 1], "", "reference is not [V, 3] for this mesh");
            maps.push_back(std::move(map));
        }
        std::ofstream csv(argv[2]);
        csv << "map,order,samples,bounces,format,bake_seconds,bake_cpu_seconds,bundle_bytes,error\n";
        const adapt::Format formats[] = {adapt::Format::Float, adapt::Format::Half, adapt::Format::U16,
                                         adapt::Format::U8};
        std::vector<float> radiance(V * 3);
        for (int samples : {64, 128, 256, 512, 1024})
            for (int bounces : {0, 1, 2, 3})
                for (int order = 2; order <= maxOrder; ++order) {
                    TransferOptions options;
                    options.mode = bounces ? TransferMode::Interreflected : TransferMode::Shadowed;
                    options.order = order;
                    options.samples = samples;
                    options.bounces = bounces;
                    options.albedo = {0.8f, 0.8f, 0.8f};
                    options.albedoOverride = true;
                    options.threads = 2;
                    options.progress = false;
                    double best = 1e300, bestCpu = 1e300;
                    Transfer transfer;
                    for (int run = 0; run < 5; ++run) { // the bake's time: the passes, wall clock, best of five
                        transfer = computeTransfer(mesh, options);
                        double seconds = transfer.stats.buildSeconds + transfer.stats.directSeconds;
                        for (double b : transfer.stats.bounceSeconds) seconds += b;
                        best = std::min(best, seconds);
                        bestCpu = std::min(bestCpu, transfer.stats.directCpuSeconds);
                    }
                    for (adapt::Format format : formats) {
                        std::vector<float> stored =
                            autoconfig::storedRows(transfer.coefficients.data(), V, order, order, format);
                        const uint64_t bytes = autoconfig::bundleLayerBytes(V, order, format, bounces);
                        for (const Map& map : maps) {
                            relight(stored.data(), V, order * order, map.lighting.data(), radiance.data());
                            double error = autoconfig::noiseCorrectedError(radiance.data(), map.reference.data(),
                                                                           map.standardError.data(), V);
                            char line[256];
                            std::snprintf(line, sizeof line, "%s,%d,%d,%d,%s,%.6g,%.6g,%llu,%.6g\n", map.name.c_str(),
                                          order, samples, bounces, adapt::formatName(format), best, bestCpu,
                                          (unsigned long long)bytes, error);
                            csv << line;
                        }
                    }
                }
        std::fprintf(stderr, "wrote %s\n", argv[2]);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
    return 0;
}
