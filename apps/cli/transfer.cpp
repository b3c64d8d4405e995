// prt transfer: per-vertex diffuse SH transfer of a mesh, written as the "transfer" layer of a bundle.
#include "cli.h"

#include "bundle.h"
#include "core.h"
#include "sh.h"
#include "transfer.h"

#include <nlohmann/json.hpp>

#include <memory>

#ifndef PRT_VERSION
#define PRT_VERSION "0.0.0"
#endif

namespace prt::cli {

namespace {

struct TransferArgs {
    std::string input;
    std::string output;
    std::string mode = "shadowed";
    int order = 3;
    int samples = 1024;
    int bounces = -1; // -1: not given
    std::string albedo;
    uint64_t seed = 0;
    int threads = 0;
    std::string shard;
};

Error usage(const std::string& flag, const std::string& problem) { return Error("", flag, problem, kExitUsage); }

TransferOptions resolveOptions(const TransferArgs& args) {
    TransferOptions options;
    options.mode = parseTransferMode(args.mode);
    if (args.order < 1 || args.order > sh::kMaxOrder)
        throw usage("--order", std::to_string(args.order) + " outside 1.." + std::to_string(sh::kMaxOrder));
    options.order = args.order;
    if (args.samples < 1 || args.samples > kMaxTransferSamples)
        throw usage("--samples", std::to_string(args.samples) + " outside 1.." + std::to_string(kMaxTransferSamples));
    options.samples = args.samples;
    bool interreflected = options.mode == TransferMode::Interreflected;
    if (args.bounces >= 0 && !interreflected) throw usage("--bounces", "only applies to --mode interreflected");
    if (args.bounces < -1) throw usage("--bounces", "must be >= 0");
    options.bounces = interreflected ? (args.bounces >= 0 ? args.bounces : 2) : 0;
    if (!args.albedo.empty()) {
        std::array<double, 3> albedo = parseAlbedo(args.albedo);
        options.albedo = {float(albedo[0]), float(albedo[1]), float(albedo[2])};
        options.albedoOverride = true;
    }
    // Bundle JSON holds integers exactly up to 2^53.
    if (args.seed > (uint64_t(1) << 53)) throw usage("--seed", "must be at most 2^53");
    options.seed = args.seed;
    if (args.threads < 0) throw usage("--threads", "must be >= 0 (0: all cores)");
    options.threads = resolveThreads(args.threads);
    return options;
}

void runTransfer(const TransferArgs& args) {
    double start = nowSeconds();
    TransferOptions options = resolveOptions(args);
    int shardIndex = 0, shardCount = 1;
    if (!args.shard.empty()) {
        parseShard(args.shard, shardIndex, shardCount);
        if (options.bounces > 0)
            throw usage("--shard", "interreflected bounces gather from every vertex; run them unsharded");
    }

    Bundle input = readBundle(args.input);
    TriMesh& mesh = input.mesh;
    if (mesh.normals.empty()) throw Error(args.input, "mesh", "has no normals: run `prt meshprep` on it first");
    size_t vertexCount = mesh.vertexCount();
    RowRange range = shardRows(vertexCount, shardIndex, shardCount);
    options.vertexBegin = range.begin;
    options.vertexEnd = range.end;
    bool perVertexAlbedo = !mesh.albedo.empty() && !options.albedoOverride;
    logInfo("transfer: " + args.input + " (" + std::to_string(vertexCount) + " vertices) " + args.mode + ", order " +
            std::to_string(options.order) + ", " + std::to_string(options.samples) + " samples" +
            (options.bounces > 0 ? ", " + std::to_string(options.bounces) + " bounces" : "") +
            (shardCount > 1 ? ", shard " + args.shard : ""));

    // The bounce part travels as its own layer, so a hybrid relight can send cone lights through it.
    options.keepDirect = options.mode == TransferMode::Interreflected && options.bounces > 0;
    Transfer transfer;
    try {
        transfer = computeTransfer(mesh, options);
    } catch (const Error& e) {
        if (!e.file().empty() || e.exitCode() != kExitInput) throw;
        throw Error(args.input, e.place(), e.problem(), e.exitCode());
    }
    const TransferStats& stats = transfer.stats;
    // A closed mesh still sees the odd grazing back-face hit from float error: warn only above 1 in 100000 rays.
    if (stats.backFaceHits > 0)
        (stats.backFaceHits * 100000 > stats.rays ? logWarn : logInfo)("transfer: " + std::to_string(stats.backFaceHits) + " of " + std::to_string(stats.rays) +
                " rays hit back faces (open or inside-out mesh?); they count as occluded and reflect nothing");

    Layer layer;
    layer.name = "transfer";
    layer.semantic = "sh_transfer_rgb";
    uint64_t rows = transfer.vertexEnd - transfer.vertexBegin;
    uint64_t coefficients = uint64_t(options.order) * options.order;
    layer.shape = {rows, coefficients, 3};
    layer.data = std::move(transfer.coefficients);
    nlohmann::json albedo = "per-vertex";
    if (!perVertexAlbedo)
        albedo = args.albedo.empty() ? std::array<double, 3>{1.0, 1.0, 1.0} : parseAlbedo(args.albedo);
    layer.params = {{"mode", args.mode},
                    {"order", options.order},
                    {"samples", options.mode == TransferMode::Unshadowed ? 0 : options.samples},
                    {"bounces", options.bounces},
                    {"albedo", albedo},
                    {"seed", options.seed},
                    {"direction_set", kTransferDirectionSet},
                    {"ray_offset", stats.rayOffset},
                    {"rays", stats.rays},
                    {"back_face_hits", stats.backFaceHits}};
    markVertexShard(layer, transfer.vertexBegin, transfer.vertexEnd, vertexCount, shardIndex, shardCount);

    Layer bounceLayer;
    if (!transfer.direct.empty()) {
        bounceLayer.name = "transfer_bounce";
        bounceLayer.domain = "vertex";
        bounceLayer.semantic = "sh_transfer_bounce_rgb";
        bounceLayer.shape = layer.shape;
        bounceLayer.data.resize(layer.data.size());
        for (size_t i = 0; i < layer.data.size(); ++i) bounceLayer.data[i] = layer.data[i] - transfer.direct[i];
        bounceLayer.params = layer.params;
        bounceLayer.params["part"] = "bounces 1..B: transfer minus its direct (shadowed) pass";
    }

    Bundle output;
    output.mesh = std::move(mesh);
    output.layers.push_back(std::move(layer));
    if (!bounceLayer.name.empty()) output.layers.push_back(std::move(bounceLayer));
    output.producer = {{"tool", "prt"}, {"version", PRT_VERSION}, {"stage", "transfer"}};
    output.inputs = {{"mesh", hashFile(args.input)}};
    output.convention = conventionRecord();
    writeBundle(args.output, output);
    logInfo("transfer: wrote " + args.output);

    nlohmann::json record = {{"rays", stats.rays},
                             {"hits", stats.hits},
                             {"back_face_hits", stats.backFaceHits},
                             {"build_seconds", stats.buildSeconds},
                             {"direct_seconds", stats.directSeconds},
                             {"direct_cpu_seconds", stats.directCpuSeconds},
                             {"bounce_seconds", stats.bounceSeconds},
                             {"hit_record_bytes", stats.hitRecordBytes},
                             {"transfer_bytes", stats.transferBytes}};
    logEvent("transfer_stats", record.dump());

    StageCost cost;
    cost.stage = "transfer";
    cost.seconds = nowSeconds() - start;
    cost.rays = stats.rays;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addTransferCommand(CLI::App& app) {
    auto args = std::make_shared<TransferArgs>();
    CLI::App* command = app.add_subcommand("transfer", "Per-vertex diffuse SH transfer by Monte Carlo ray casting");
    command->add_option("mesh", args->input, "Input mesh with normals: a bundle or glb from `prt meshprep`")
        ->required();
    command->add_option("-o,--output", args->output, "Output bundle (.glb) with the mesh and a 'transfer' layer")
        ->required();
    command->add_option("--mode", args->mode, "unshadowed, shadowed or interreflected (default shadowed)");
    command->add_option("--order", args->order, "Number of SH bands L (L*L coefficients), 1.." +
                                                    std::to_string(sh::kMaxOrder) + " (default 3)");
    command->add_option("--samples", args->samples, "Hemisphere directions per vertex, 1.." +
                                                        std::to_string(kMaxTransferSamples) + " (default 1024)");
    command->add_option("--bounces", args->bounces, "Interreflection bounces, interreflected only (default 2)");
    command->add_option("--albedo", args->albedo,
                        "Diffuse albedo R,G,B (or one grey value) in [0,1]; overrides the mesh's per-vertex "
                        "albedo (default: the mesh's, else 1)");
    command->add_option("--seed", args->seed, "Seed of the per-vertex direction rotations (default 0)");
    command->add_option("--threads", args->threads, "Worker threads (default 0: all cores)");
    command->add_option("--shard", args->shard,
                        "I/N: compute only the I-th of N contiguous vertex ranges, written as a 'vertex_range' "
                        "layer for a later merge");
    command->callback([args] { runTransfer(*args); });
}

} // namespace prt::cli
