// prt glossy: view-dependent glossy transfer as spherical-Gaussian lobes per vertex and view (lib/glossy), plus
// the diffuse SH transfer (lib/transfer, or copied from --diffuse), in one bundle.
#include "cli.h"

#include "bundle.h"
#include "core.h"
#include "glossy.h"
#include "image.h"
#include "sh.h"
#include "transfer.h"

#include <nlohmann/json.hpp>

#include <memory>

#ifndef PRT_VERSION
#define PRT_VERSION "0.0.0"
#endif

namespace prt::cli {

namespace {

struct GlossyArgs {
    std::string input;
    std::string output;
    std::string brdf;
    std::string albedo = "0.5";
    int lobes = 1;
    std::string solver = "pocl";
    int bounces = 0;
    std::string diffuse;
    int order = 6; // measured against the exact oracle (docs/glossy.md, "Defaults")
    int samples = 1024;
    int grid = 16;
    double beta = 0.001, gamma = 0.001, delta = 0.001; // chosen by measurement (docs/results.md)
    bool noCoherence = false;
    bool warmStart = false;
    bool nested = false;
    int heldOutGrid = 0;
    double nestedMargin = 0.0;
    bool nestedPerVertex = false;
    std::vector<std::string> nestedLighting;
    int nestedRotations = 8;
    bool nestedMax = false;
    bool fromBelow = false;
    double overshoot = 10.0; // docs/glossy.md, "Fit from below"
    int threads = 0;
    int iterations = 100;
    std::string stats;
    size_t compareSolvers = 0;
    std::string vertexStats;
    std::string lobeType = "float16";
    std::string shard;
    bool indirectGlossy = false;
};

Error usage(const std::string& flag, const std::string& problem) { return Error("", flag, problem, kExitUsage); }

// The diffuse part for the rows `range` (shard shardIndex of shardCount). A --diffuse layer is copied whole into
// every shard (the merge keeps layers that every shard holds identically); a computed one covers the range.
Layer diffuseLayer(const GlossyArgs& args, const TriMesh& mesh, const std::array<double, 3>& albedo, int threads,
                   RowRange range, int shardIndex, int shardCount) {
    if (!args.diffuse.empty()) {
        Bundle diffuse = readBundle(args.diffuse);
        const Layer* layer = findLayer(diffuse, "transfer");
        if (!layer || layer->domain != "vertex" || layer->semantic != "sh_transfer_rgb")
            throw Error(args.diffuse, "layers", "has no per-vertex \"transfer\" layer (prt transfer writes one)");
        if (layer->shape.empty() || layer->shape[0] != mesh.vertexCount())
            throw Error(args.diffuse, "layer transfer", "has another vertex count than " + args.input);
        return *layer;
    }
    TransferOptions options;
    options.mode = args.bounces > 0 ? TransferMode::Interreflected : TransferMode::Shadowed;
    options.bounces = args.bounces;
    options.order = args.order;
    options.samples = args.samples;
    options.albedo = {float(albedo[0]), float(albedo[1]), float(albedo[2])};
    options.albedoOverride = true;
    options.threads = threads;
    options.vertexBegin = range.begin;
    options.vertexEnd = range.end;
    Transfer transfer = computeTransfer(mesh, options);
    Layer layer;
    layer.name = "transfer";
    layer.semantic = "sh_transfer_rgb";
    layer.shape = {transfer.vertexEnd - transfer.vertexBegin, uint64_t(args.order) * args.order, 3};
    layer.data = std::move(transfer.coefficients);
    layer.params = {{"mode", transferModeName(options.mode)}, {"order", args.order}, {"samples", args.samples},
                    {"bounces", args.bounces}, {"albedo", albedo}, {"seed", 0},
                    {"direction_set", kTransferDirectionSet}, {"ray_offset", transfer.stats.rayOffset},
                    {"rays", transfer.stats.rays}, {"back_face_hits", transfer.stats.backFaceHits}};
    markVertexShard(layer, transfer.vertexBegin, transfer.vertexEnd, mesh.vertexCount(), shardIndex, shardCount);
    return layer;
}

// The grey per-vertex shadowed transfer of the whole mesh that indirect glossy reads at its hit points (every shard
// computes all of it: hits land anywhere). Needs a grey albedo (checked by runGlossy): the kernel has one channel.
void indirectTransfer(const GlossyArgs& args, const TriMesh& mesh, const std::array<double, 3>& albedo, int threads,
                      glossy::GlossyOptions& options) {
    TransferOptions transfer;
    transfer.mode = TransferMode::Shadowed;
    transfer.order = args.order;
    transfer.samples = args.samples;
    transfer.albedo = {float(albedo[0]), float(albedo[1]), float(albedo[2])};
    transfer.albedoOverride = true;
    transfer.threads = threads;
    Transfer whole = computeTransfer(mesh, transfer);
    const size_t coefficients = size_t(args.order) * args.order;
    options.indirectTransfer.resize(mesh.vertexCount() * coefficients);
    for (size_t i = 0; i < options.indirectTransfer.size(); ++i) options.indirectTransfer[i] = whole.coefficients[i * 3];
    options.indirectOrder = args.order;
    options.indirectSamples = args.samples;
}

// The fit's options from the flags, each checked for range and for combinations that do not go together.
glossy::GlossyOptions glossyOptions(const GlossyArgs& args) {
    glossy::GlossyOptions options;
    if (args.brdf.empty()) throw usage("--brdf", "is required: phong:EXPONENT,KS");
    parsePhongBrdf(args.brdf, options.phong.exponent, options.phong.ks);
    if (args.lobes < 1 || args.lobes > glossy::kMaxLobes)
        throw usage("--lobes", "must lie in 1.." + std::to_string(glossy::kMaxLobes) + ", got " +
                                   std::to_string(args.lobes));
    options.lobes = args.lobes;
    options.solver = glossy::parseSolver(args.solver);
    if (args.bounces < 0) throw usage("--bounces", "must be >= 0");
    if (args.order < 1 || args.order > sh::kMaxOrder) throw usage("--order", "outside 1.." + std::to_string(sh::kMaxOrder));
    if (args.samples < 1 || args.samples > kMaxTransferSamples) throw usage("--samples", "out of range");
    if (args.grid < 2 || args.grid > 64) throw usage("--grid", "cube resolution must lie in 2..64");
    if (!(args.beta >= 0 && args.gamma >= 0 && args.delta >= 0)) throw usage("--coherence", "weights must be >= 0");
    if (args.iterations < 1) throw usage("--iterations", "must be >= 1");
    if (args.compareSolvers == 0 && args.output.empty()) throw usage("-o", "is required");
    if (args.compareSolvers > 0 && !args.output.empty())
        throw usage("-o", "--compare-solvers writes no bundle: its figures go to the log and --stats");
    if (args.compareSolvers == 0 && fileExtension(args.output) != "glb")
        throw Error(args.output, "-o", "must end in .glb", kExitUsage);
    options.gridResolution = args.grid;
    options.weights = args.noCoherence ? glossy::FitWeights{} : glossy::FitWeights{args.beta, args.gamma, args.delta};
    options.warmStart = args.warmStart;
    options.nested = args.nested;
    options.heldOutResolution = args.heldOutGrid;
    if (!(args.nestedMargin >= 0.0 && args.nestedMargin < 1.0)) throw usage("--nested-margin", "must lie in [0, 1)");
    if (!args.nested && (args.nestedMargin > 0.0 || args.nestedPerVertex || args.nestedMax))
        throw usage(args.nestedPerVertex ? "--nested-per-vertex" : args.nestedMax ? "--nested-max" : "--nested-margin",
                    "needs --nested");
    if (args.nestedMax && !args.nestedLighting.empty())
        throw usage("--nested-max", "and --nested-lighting are two scores: pick one");
    options.nestedMargin = args.nestedMargin;
    options.nestedPerVertex = args.nestedPerVertex;
    options.nestedMaxNorm = args.nestedMax;
    if (!args.nestedLighting.empty()) {
        if (!args.nested) throw usage("--nested-lighting", "needs --nested");
        if (args.nestedRotations < 1 || args.nestedRotations > 64) throw usage("--nested-rotations", "must lie in 1..64");
        const glossy::DirectionGrid held = glossy::heldOutGrid(glossy::heldOutResolution(options));
        for (const std::string& path : args.nestedLighting) {
            std::vector<float> rows = glossy::lightingPrior(readEnvironmentMap(path), path, held, args.nestedRotations);
            options.nestedLighting.insert(options.nestedLighting.end(), rows.begin(), rows.end());
        }
    }
    if (args.nested && args.warmStart)
        throw Error("", "--nested", "already starts each stage from the previous one: drop --warm-start", kExitUsage);
    if (args.fromBelow && (args.nested || args.warmStart))
        throw usage("--from-below", "fits each lobe on what the earlier ones leave: not with --nested or --warm-start");
    if (!(args.overshoot > 0.0 && args.overshoot <= 1e6)) throw usage("--overshoot", "must lie in (0, 1e6]");
    options.fromBelow = args.fromBelow;
    options.fromBelowOvershoot = args.overshoot;
    options.solverOptions.threads = resolveThreads(args.threads);
    options.solverOptions.maxIterations = args.iterations;
    options.progress = !logOptions().quiet;
    if (args.lobeType != "float16" && args.lobeType != "float32")
        throw usage("--lobe-type", "must be float16 or float32");
    options.lobeType = args.lobeType;
    return options;
}

// `--compare-solvers N`: both solvers on the first N problems of the mesh, reported as an event and to --stats.
void reportSolverComparison(const GlossyArgs& args, const TriMesh& mesh, const glossy::GlossyOptions& options,
                            double start) {
    glossy::SolverComparison c = glossy::compareSolvers(mesh, options, args.compareSolvers);
    nlohmann::json record = {{"problems", c.problems}, {"lobes", args.lobes}, {"grid", args.grid},
                             {"brdf", args.brdf}, {"threads", options.solverOptions.threads},
                             {"pocl_seconds", c.openClSeconds}, {"ceres_seconds", c.ceresSeconds},
                             {"pocl_ms_per_fit", 1e3 * c.openClSeconds / double(c.problems)},
                             {"ceres_ms_per_fit", 1e3 * c.ceresSeconds / double(c.problems)},
                             {"speed_ratio", c.ceresSeconds / c.openClSeconds},
                             {"pocl_cpu_seconds", c.openClCpuSeconds}, {"ceres_cpu_seconds", c.ceresCpuSeconds},
                             {"cpu_time_ratio", c.ceresCpuSeconds / c.openClCpuSeconds},
                             {"initial_cost", c.initialCost}, {"pocl_cost", c.openClCost},
                             {"ceres_cost", c.ceresCost}, {"share_within_1pct", c.shareWithinOnePercent},
                             {"share_agreeing_1pct", c.shareAgreeing},
                             {"pocl_mean_iterations", c.openClMeanIterations},
                             {"ceres_mean_iterations", c.ceresMeanIterations},
                             {"pocl_costs", c.openClCosts}, {"ceres_costs", c.ceresCosts}};
    nlohmann::json summary = record;
    summary.erase("pocl_costs"), summary.erase("ceres_costs");
    logEvent("glossy_solver_comparison", summary.dump());
    if (!args.stats.empty()) writeBytesAtomic(args.stats, record.dump(2) + "\n");
    reportCost("glossy", start, c.rays);
}

void runGlossy(const GlossyArgs& args) {
    double start = nowSeconds();
    glossy::GlossyOptions options = glossyOptions(args);
    std::array<double, 3> albedo = parseAlbedo(args.albedo);
    if (args.indirectGlossy && (albedo[0] != albedo[1] || albedo[1] != albedo[2]))
        throw usage("--indirect-glossy", "needs a grey --albedo: the glossy kernel has one channel");
    int shardIndex = 0, shardCount = 1;
    if (!args.shard.empty()) {
        parseShard(args.shard, shardIndex, shardCount);
        if (args.bounces > 0 && args.diffuse.empty())
            throw usage("--shard", "diffuse interreflection (--bounces) gathers from every vertex; run it unsharded, "
                                   "or give its transfer as --diffuse BUNDLE.glb");
        if (args.compareSolvers > 0) throw usage("--shard", "does not combine with --compare-solvers");
    }
    if (options.solver == glossy::Solver::OpenCl) logInfo("glossy: OpenCL device " + glossy::openClDeviceName());

    Bundle input = readBundle(args.input);
    TriMesh& mesh = input.mesh;
    if (mesh.normals.empty()) throw Error(args.input, "mesh", "has no normals: run `prt meshprep` on it first");
    logInfo("glossy: " + args.input + " (" + std::to_string(mesh.vertexCount()) + " vertices), " + args.brdf + ", " +
            std::to_string(args.lobes) + " lobes, " + args.solver + ", grid 6x" + std::to_string(args.grid) + "^2");
    if (args.compareSolvers > 0) return reportSolverComparison(args, mesh, options, start);
    // Shards are vertex ranges: every row is computed as the whole run computes it (lib/glossy and lib/transfer
    // guarantee rows independent of the range), so `prt merge` joins them bit for bit.
    RowRange range = shardRows(mesh.vertexCount(), shardIndex, shardCount);
    options.vertexBegin = range.begin;
    options.vertexEnd = range.end;
    Layer diffuse = diffuseLayer(args, mesh, albedo, options.solverOptions.threads, range, shardIndex, shardCount);
    if (args.indirectGlossy) indirectTransfer(args, mesh, albedo, options.solverOptions.threads, options);
    glossy::GlossyLobes lobes = glossy::computeGlossyLobes(mesh, options);

    Bundle output;
    output.layers.push_back(glossy::lobeLayer(lobes, options, mesh.vertexCount(), shardIndex, shardCount));
    output.layers.push_back(std::move(diffuse));
    output.mesh = std::move(mesh);
    output.producer = {{"tool", "prt"}, {"version", PRT_VERSION}, {"stage", "glossy"}};
    output.inputs = {{"mesh", hashFile(args.input)}};
    if (!args.diffuse.empty()) output.inputs["diffuse"] = hashFile(args.diffuse);
    output.convention = conventionRecord();
    writeBundle(args.output, output);
    logInfo("glossy: wrote " + args.output);

    const glossy::GlossyStats& stats = lobes.stats;
    nlohmann::json record = {{"problems", stats.problems},
                             {"rays", stats.rays},
                             {"tabulate_seconds", stats.tabulateSeconds},
                             {"fit_seconds", stats.fitSeconds},
                             {"mean_cost", stats.meanCost},
                             {"mean_relative_error", stats.meanRelativeError},
                             {"solver", args.solver},
                             {"lobes", args.lobes},
                             {"grid", args.grid},
                             {"brdf", args.brdf},
                             {"coherence", !args.noCoherence},
                             {"view_pairs", stats.viewPairs},
                             {"view_flips", stats.viewFlips},
                             {"vertex_pairs", stats.vertexPairs},
                             {"vertex_flips", stats.vertexFlips},
                             {"seconds", nowSeconds() - start},
                             {"peak_memory_bytes", peakMemoryBytes()},
                             {"vertices", output.mesh.vertexCount()},
                             {"lobe_layer_bytes_per_vertex",
                              double(output.layers[0].shape[1] * output.layers[0].shape[2] * output.layers[0].shape[3]) *
                                  (args.lobeType == "float16" ? 2.0 : 4.0)}};
    if (args.nested) {
        double sum = 0.0;
        size_t fitted = 0;
        for (float e : lobes.heldOutError)
            if (e >= 0.0f) sum += std::sqrt(double(e)), ++fitted;
        record["nested_kept_stage"] = lobes.keptStage;
        record["held_out_mean_relative_error"] = fitted ? sum / double(fitted) : 0.0;
    }
    if (!args.vertexStats.empty())
        writeNpy(args.vertexStats, lobes.vertexStats, {lobes.vertexEnd - lobes.vertexBegin, size_t(glossy::kVertexStatColumns)});
    logEvent("glossy_stats", record.dump());
    if (!args.stats.empty()) writeBytesAtomic(args.stats, record.dump(2) + "\n");

    reportCost("glossy", start, stats.rays);
}

} // namespace

void addGlossyCommand(CLI::App& app) {
    auto args = std::make_shared<GlossyArgs>();
    CLI::App* command = app.add_subcommand(
        "glossy", "View-dependent glossy transfer: spherical-Gaussian lobes per vertex and view (OpenCL LM or Ceres) "
                  "plus diffuse SH transfer");
    command->add_option("mesh", args->input, "Input mesh with normals (from `prt meshprep`)")->required();
    command->add_option("-o,--output", args->output, "Output bundle (.glb): glossy_lobes and transfer layers");
    command->add_option("--brdf", args->brdf, "phong:EXPONENT,KS (docs/conventions.md)")->required();
    command->add_option("--albedo", args->albedo, "Diffuse albedo R,G,B or grey, in [0,1] (default 0.5)");
    command->add_option("--lobes", args->lobes, "Spherical Gaussians per vertex and view, 1..4 (default 1)");
    command->add_option("--solver", args->solver, "pocl (batched OpenCL LM, default) or ceres (reference)");
    command->add_option("--bounces", args->bounces, "Diffuse interreflection bounces of the SH part (default 0)");
    command->add_option("--diffuse", args->diffuse, "Take the diffuse transfer layer from this bundle instead");
    command->add_option("--order", args->order, "SH bands of the diffuse part (default 6: docs/glossy.md, \"Defaults\")");
    command->add_option("--samples", args->samples, "Rays per vertex of the diffuse part (default 1024)");
    command->add_option("--grid", args->grid, "Cube face resolution of the kernel grid (default 16: 6x16x16)");
    command->add_option("--beta", args->beta, "Weight of the mean-coherence term (default 0.001)");
    command->add_option("--gamma", args->gamma, "Weight of the width-coherence term (default 0.001)");
    command->add_option("--delta", args->delta, "Weight of the no-flip term (default 0.001)");
    command->add_flag("--no-coherence", args->noCoherence, "Independent fits only, no coherence pass");
    command->add_flag("--warm-start", args->warmStart,
                      "Fit 1, 2, ..., N lobes in turn, each from the previous fit plus one lobe (never a higher cost)");
    command->add_flag("--nested", args->nested,
                      "Fit 1, 2, ..., N lobes in turn, each from the previous plus one lobe; a view keeps a lobe only "
                      "where it lowers the error on held-out directions (so more lobes never fit worse there)");
    command->add_option("--held-out-grid", args->heldOutGrid,
                        "With --nested: cube face resolution of the held-out directions (default 0: twice --grid)");
    command->add_option("--nested-margin", args->nestedMargin,
                        "With --nested: keep a lobe only where it lowers the held-out error by this fraction (default 0)");
    command->add_flag("--nested-per-vertex", args->nestedPerVertex,
                      "With --nested: keep a lobe for all views of a vertex or none, by their summed held-out error");
    command->add_option("--nested-lighting", args->nestedLighting,
                        "With --nested: training maps (comma-separated); a lobe is kept where it lowers the relit "
                        "held-out error under them, each turned about y (--nested-rotations), instead of the L2 one")
        ->delimiter(',');
    command->add_flag("--nested-max", args->nestedMax,
                      "With --nested: keep a lobe where it lowers the largest held-out residual (a sun's worst case)");
    command->add_option("--nested-rotations", args->nestedRotations,
                        "With --nested-lighting: turns of each map about y, 1..64 (default 8)");
    command->add_flag("--from-below", args->fromBelow,
                      "Fit lobe 1, 2, ..., N one at a time on what the earlier lobes leave, each from below (an "
                      "overshoot costs --overshoot times more), so more lobes never relight darker and, under the "
                      "kernel, never worse");
    command->add_option("--overshoot", args->overshoot,
                        "With --from-below: the one-sided weight rho, (0, 1e6] (default 10)");
    command->add_option("--iterations", args->iterations, "LM iteration limit per fit (default 100)");
    command->add_option("--threads", args->threads, "Worker threads (default: all cores)");
    outputFile(command->add_option("--stats", args->stats, "Also write the fit statistics as JSON to this file"));
    command->add_option("--compare-solvers", args->compareSolvers,
                        "Instead of a bundle: solve the first N fit problems with both solvers and report time, "
                        "cost and agreement (JSON on stderr and in --stats)");
    outputFile(command->add_option("--vertex-stats", args->vertexStats,
                        "Also write per-vertex diagnostics [V,6] (.npy): normal, visible share, mean and worst "
                        "relative fit error"));
    command->add_option("--lobe-type", args->lobeType, "Lobe layer storage: float16 (default) or float32");
    command->add_flag("--indirect-glossy", args->indirectGlossy,
                      "Also fit the glossy reflection of light that bounced once diffusely off the mesh (grey "
                      "--albedo; docs/glossy.md)");
    command->add_option("--shard", args->shard,
                        "Compute only vertex range I of N (0-based) into a shard bundle; `prt merge` joins the N "
                        "shards into the unsharded bundle, bit for bit");
    optionNeeds(command, "--overshoot", "--from-below");
    command->callback([args] { runGlossy(*args); });
}

} // namespace prt::cli
