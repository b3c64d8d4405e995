// prt adapt: a full-order transfer bundle rewritten with no more bands per vertex than a target error needs, in a
// compact storage format; `prt relight` reads the result like any other bundle.
#include "cli.h"

#include "adapt.h"
#include "core.h"
#include "runtime.h"

#include <cstdio>
#include <memory>

namespace prt::cli {

namespace {

struct AdaptArgs {
    std::string bundle, output;
    double maxError = 0.0;
    int order = 0;
    std::vector<std::string> envs, shFiles;
    std::string prior = "maps", format = "float", scales = "per-vertex", budget = "rms";
    int clusters = 64, components = 0, maxStep = 1;
};

// A bake's per-texel transfer read from its texture into the layer (adapted texels live in the bundle's own
// buffers); the other layers whose data lie in files next to the input are left out, so the output never names a
// file that is not next to it.
void readBakeIntoBundle(Bundle& bundle, const std::string& path, const std::string& output) {
    TexelRelightModel rows = loadTexelRelightModel(path);
    std::vector<std::string> dropped;
    std::vector<Layer> kept;
    for (Layer& layer : bundle.layers) {
        if (layer.name == "texel_transfer") {
            for (const char* key : {"uri", "hash", "files", "channels"}) layer.params.erase(key);
            layer.params["format"] = "bundle";
            layer.data = std::move(rows.rows.transfer);
        } else if (layer.params.contains("uri")) {
            dropped.push_back(layer.name);
            continue;
        }
        kept.push_back(std::move(layer));
    }
    bundle.layers = std::move(kept);
    if (!dropped.empty()) {
        std::string names;
        for (const std::string& name : dropped) names += (names.empty() ? "" : ", ") + name;
        logWarn("adapt: " + output + " leaves out the layers whose data lie in files next to " + path + " (" + names +
                "): bake with --format bundle to keep them inline");
    }
}

void runAdapt(const AdaptArgs& args, const CLI::App& command) {
    double start = nowSeconds();
    const bool haveError = command.count("--max-error") > 0, haveOrder = command.count("--order") > 0;
    if (haveError && haveOrder)
        throw Error("", "--order", "conflicts with --max-error: --order truncates every vertex to one order, "
                    "--max-error chooses each vertex's order; give one", kExitUsage);
    if (!haveError && !haveOrder) throw Error("", "--max-error", "is needed (or --order for a uniform order)", kExitUsage);
    if (haveError && !(args.maxError > 0.0))
        throw Error("", "--max-error", "must be > 0 (it is a relative error; 0 would keep every band: use "
                    "--order with the transfer's order for lossless storage)", kExitUsage);
    if (haveOrder && (args.order < 1 || args.order > sh::kMaxOrder))
        throw Error("", "--order", "must be in 1.." + std::to_string(sh::kMaxOrder), kExitUsage);
    if (args.maxStep < 1) throw Error("", "--max-step", "must be >= 1", kExitUsage);
    if (args.clusters < 1) throw Error("", "--clusters", "must be >= 1", kExitUsage);
    if (args.components < 0) throw Error("", "--components", "must be >= 0", kExitUsage);
    if (args.prior != "maps" && args.prior != "worst")
        throw Error("", "--prior", "\"" + args.prior + "\" is not maps or worst", kExitUsage);
    if (args.budget != "rms" && args.budget != "vertex")
        throw Error("", "--budget", "\"" + args.budget + "\" is not rms or vertex", kExitUsage);
    if (args.scales != "per-vertex" && args.scales != "per-cluster")
        throw Error("", "--scales", "\"" + args.scales + "\" is not per-vertex or per-cluster", kExitUsage);
    // Given with another format they would be ignored.
    if (args.components != 0 && args.format != "cpca")
        throw Error("", "--components", "counts CPCA components: it goes with --format cpca", kExitUsage);
    if (args.scales == "per-cluster" && args.format != "u8" && args.format != "u16")
        throw Error("", "--scales", "per-cluster scales are those of --format u8 or u16 codes", kExitUsage);
    if (haveError && args.envs.empty() && args.shFiles.empty())
        throw Error("", "--env", "--max-error needs a lighting prior: one or more --env maps (or --sh files)", kExitUsage);
    if (fileExtension(args.output) != "glb") throw Error(args.output, "-o", "output must end in .glb", kExitUsage);

    adapt::AdaptOptions options;
    options.maxError = haveError ? args.maxError : 0.0;
    options.order = haveOrder ? args.order : 0;
    options.perVertexBudget = args.budget == "vertex";
    options.prior = args.prior == "worst" ? adapt::Prior::Worst : adapt::Prior::Maps;
    options.format = adapt::parseFormat(args.format);
    options.perClusterScales = args.scales == "per-cluster";
    options.clusters = args.clusters;
    options.components = args.components;
    options.maxStep = args.maxStep;

    Bundle bundle = readBundle(args.bundle);
    const bool texels = findLayer(bundle, "texel_transfer") != nullptr;
    if (texels) readBakeIntoBundle(bundle, args.bundle, args.output);
    const Layer* transfer = findLayer(bundle, "transfer");
    if (!transfer) transfer = findLayer(bundle, "texel_transfer");
    if (!transfer || transfer->shape.size() != 3)
        throw Error(args.bundle, "PRT_bundle", "no full-order \"transfer\" layer to adapt (run `prt transfer`, or "
                                               "`prt bake` for texels)");
    int order = 1;
    while (uint64_t(order) * order < transfer->shape[1] && order < sh::kMaxOrder) ++order;
    if (haveOrder && args.order > order)
        throw Error(args.bundle, "--order", std::to_string(args.order) + " is above the transfer's order " +
                    std::to_string(order), kExitUsage);

    std::vector<std::vector<float>> lightings;
    for (const std::string& env : args.envs) {
        lightings.push_back(environmentLighting(readEnvironmentMap(env), order, nullptr, sh::Window::None));
        options.lightingNames.push_back(hashFile(env));
    }
    for (const std::string& file : args.shFiles) {
        int lightingOrder = 0;
        std::vector<float> read = readLightingJson(file, &lightingOrder);
        if (lightingOrder < order)
            throw Error(file, "order", "the lighting has " + std::to_string(lightingOrder) +
                        " bands, fewer than the transfer's " + std::to_string(order) + ": its error would go unseen");
        lightings.push_back(fitLighting(read.data(), lightingOrder * lightingOrder, order * order));
        options.lightingNames.push_back(hashFile(file));
    }
    adapt::AdaptStats stats = adapt::adaptBundle(bundle, lightings, options, args.bundle);
    bundle.producer = {{"tool", "prt"}, {"version", PRT_VERSION}, {"stage", "adapt"}};
    writeBundle(args.output, bundle);

    char line[320];
    std::snprintf(line, sizeof line,
                  "adapt: %zu %s, mean order %.2f of %d (%.1f coefficients), %zu raised by smoothing; "
                  "%s: %.1f bytes per row (float order %d: %.1f), relative RMSE under the prior %.4g",
                  stats.vertexCount, texels ? "texels" : "vertices", stats.meanOrder, stats.fullOrder, stats.meanCoefficients, stats.raisedBySmoothing,
                  args.format.c_str(), double(stats.layerBytes) / double(stats.vertexCount), stats.fullOrder,
                  double(stats.fullLayerBytes) / double(stats.vertexCount), stats.relativeRmse);
    logInfo(line);
    logInfo("adapt: wrote " + args.output);
    nlohmann::json record = {{"vertices", stats.vertexCount},
                             {"full_order", stats.fullOrder},
                             {"mean_order", stats.meanOrder},
                             {"mean_coefficients", stats.meanCoefficients},
                             {"raised_by_smoothing", stats.raisedBySmoothing},
                             {"order_histogram", stats.orderHistogram},
                             {"format", args.format},
                             {"components", stats.components},
                             {"layer_bytes", stats.layerBytes},
                             {"full_layer_bytes", stats.fullLayerBytes},
                             {"relative_rmse", stats.relativeRmse}};
    nlohmann::json seams = nlohmann::json::array();
    for (const adapt::SeamMeasure& seam : stats.seams)
        seams.push_back({{"boundary_edges", seam.boundaryEdges},
                         {"other_edges", seam.otherEdges},
                         {"largest_boundary_excess", seam.largestBoundaryExcess},
                         {"mean_boundary_excess", seam.meanBoundaryExcess},
                         {"largest_other_jump", seam.largestOtherJump},
                         {"mean_other_jump", seam.meanOtherJump}});
    record["seams"] = seams;
    logEvent("adapt_stats", record.dump());

    StageCost cost;
    cost.stage = "adapt";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addAdaptCommand(CLI::App& app) {
    auto args = std::make_shared<AdaptArgs>();
    CLI::App* command = app.add_subcommand(
        "adapt", "Rewrite a transfer bundle with per-vertex adaptive SH order and compact storage");
    command->add_option("bundle", args->bundle, "Bundle (.glb) with a full-order \"transfer\" layer")->required();
    command->add_option("-o,--output", args->output, "Adaptive bundle (.glb)")->required();
    command->add_option("--max-error", args->maxError,
                        "Relative error truncation may add (> 0): with --budget rms the relight's relative RMSE under "
                        "every prior map, with --budget vertex each vertex's error over the map's RMS radiance");
    command->add_option("--budget", args->budget,
                        "rms (default): fewest coefficients overall; vertex: each vertex within --max-error");
    command->add_option("--order", args->order, "Instead of --max-error: every vertex truncated to this order");
    command->add_option("--env", args->envs, "Lighting prior: environment maps (repeat; e.g. all eight)");
    command->add_option("--sh", args->shFiles, "Lighting prior as prt-sh JSON from `prt envsh` (repeat; at least the "
                        "transfer's order)");
    command->add_option("--prior", args->prior,
                        "maps: the maps as they are; worst: any rotation of them (per-band Cauchy-Schwarz bound)");
    command->add_option("--format", args->format, "Storage: float, half, u16, u8 (per-band codes) or cpca");
    command->add_option("--scales", args->scales, "u8/u16 band scales: per-vertex or per-cluster");
    command->add_option("--clusters", args->clusters, "Clusters for per-cluster scales and CPCA (default 64)");
    command->add_option("--components", args->components,
                        "CPCA components per cluster (default: the fewest whose error is within --max-error)");
    command->add_option("--max-step", args->maxStep, "Largest order difference along a mesh edge (default 1)");
    command->callback([args, command] { runAdapt(*args, *command); });
}

} // namespace prt::cli
