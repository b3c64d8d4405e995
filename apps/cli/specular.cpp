// prt specular: the per-vertex cosine-weighted visibility SH layer that specular through SH triple products
// relights (lib/specular), added to a mesh or bundle.
#include "cli.h"

#include "bundle.h"
#include "core.h"
#include "specular.h"

#include <nlohmann/json.hpp>

#include <memory>

#ifndef PRT_VERSION
#define PRT_VERSION "0.0.0"
#endif

namespace prt::cli {

namespace {

struct SpecularArgs {
    std::string input;
    std::string output;
    int order = 6;
    int samples = 1024;
    uint64_t seed = 0;
    int threads = 0;
    std::string stats;
};

void runSpecular(const SpecularArgs& args) {
    double start = nowSeconds();
    if (fileExtension(args.output) != "glb") throw Error(args.output, "-o", "must end in .glb", kExitUsage);
    specular::VisibilityOptions options;
    options.order = args.order;
    options.samples = args.samples;
    options.seed = args.seed;
    options.threads = resolveThreads(args.threads);
    options.progress = !logOptions().quiet;

    Bundle bundle = readBundle(args.input);
    if (bundle.mesh.normals.empty()) throw Error(args.input, "mesh", "has no normals: run `prt meshprep` on it first");
    logInfo("specular: " + args.input + " (" + std::to_string(bundle.mesh.vertexCount()) + " vertices), order " +
            std::to_string(args.order) + ", " + std::to_string(args.samples) + " rays per vertex");
    specular::Visibility visibility = specular::computeVisibility(bundle.mesh, options);

    // The input's layers stay (a transfer layer gives relight its diffuse part); an older visibility is replaced.
    std::erase_if(bundle.layers, [](const Layer& layer) { return layer.name == specular::kVisibilityLayer; });
    bundle.layers.push_back(specular::visibilityLayer(visibility, options));
    bundle.producer = {{"tool", "prt"}, {"version", PRT_VERSION}, {"stage", "specular"}};
    bundle.inputs["mesh"] = hashFile(args.input);
    bundle.convention = conventionRecord();
    writeBundle(args.output, bundle);
    logInfo("specular: wrote " + args.output);

    nlohmann::json record = {{"vertices", bundle.mesh.vertexCount()},
                             {"order", args.order},
                             {"samples", args.samples},
                             {"rays", visibility.rays},
                             {"visibility_seconds", visibility.seconds},
                             {"seconds", nowSeconds() - start},
                             {"bytes_per_vertex", 4 * args.order * args.order},
                             {"peak_memory_bytes", peakMemoryBytes()}};
    logEvent("specular_stats", record.dump());
    if (!args.stats.empty()) writeBytesAtomic(args.stats, record.dump(2) + "\n");

    StageCost cost;
    cost.stage = "specular";
    cost.seconds = nowSeconds() - start;
    cost.rays = visibility.rays;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addSpecularCommand(CLI::App& app) {
    auto args = std::make_shared<SpecularArgs>();
    CLI::App* command = app.add_subcommand(
        "specular", "Cosine-weighted visibility SH per vertex, for specular through SH triple products (relight "
                    "--brdf phong:N,KS --eye)");
    command->add_option("input", args->input, "Mesh with normals (from `prt meshprep`) or bundle")->required();
    command->add_option("-o,--output", args->output, "Output bundle (.glb): the input plus specular_visibility")
        ->required();
    command->add_option("--order", args->order, "SH bands of the visibility (default 6)");
    command->add_option("--samples", args->samples, "Rays per vertex (default 1024)");
    command->add_option("--seed", args->seed, "Seed of the per-vertex direction-set rotation (default 0)");
    command->add_option("--threads", args->threads, "Worker threads (default: all cores)");
    outputFile(command->add_option("--stats", args->stats, "Also write the stage's statistics as JSON to this file"));
    command->callback([args] { runSpecular(*args); });
}

} // namespace prt::cli
