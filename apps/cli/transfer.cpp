// prt transfer: per-vertex diffuse SH transfer of a mesh, written as the "transfer" layer of a bundle; sharded
// interreflected transfer runs as passes (--shard I/N --pass P, --gather), the work in lib/transfer.
#include "cli.h"

#include "bundle.h"
#include "core.h"
#include "material.h"
#include "sh.h"
#include "transfer.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <limits>
#include <memory>
#include <optional>

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
    // Sharded interreflected passes (transfer.h): -1 not given
    int pass = -1;
    std::string previous, exitant, hits;
    std::vector<std::string> gather;
    bool noInstancing = false;
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
    if (args.seed > (uint64_t(1) << 53)) throw usage("--seed", "must be a whole number from 0 to 2^53");
    options.seed = args.seed;
    options.threads = resolveThreads(args.threads);
    return options;
}

// The bundle `prt transfer` writes: the mesh, the "transfer" layer of rows [rowBegin, rowEnd) (a "vertex_range"
// layer for a shard), and with `direct` (interreflected with bounces) the "transfer_bounce" layer, total minus direct.
struct Rows {
    std::vector<float> total;
    const std::vector<float>* direct = nullptr;
    size_t begin = 0, end = 0;
    uint64_t rays = 0, backFaceHits = 0;
    float rayOffset = 0.0f;
};

// `input` is the bundle the stage read: its mesh and, for a scene, its asset move on into the result (after every
// use of options.surface, which borrows input.mesh); its layers do not.
Bundle transferBundle(const TransferArgs& args, const TransferOptions& options, Bundle& input, Rows rows,
                      int shardIndex, int shardCount, const std::string& meshHash) {
    const TriMesh& mesh = input.mesh;
    bool perVertexAlbedo = !mesh.albedo.empty() && !options.albedoOverride;
    Layer layer;
    layer.name = "transfer";
    layer.semantic = "sh_transfer_rgb";
    uint64_t coefficients = uint64_t(options.order) * options.order;
    layer.shape = {rows.end - rows.begin, coefficients, 3};
    layer.data = std::move(rows.total);
    // A scene's transfer excludes the receiver's albedo (irradiance transfer, docs/bundle.md "Scene bundles").
    nlohmann::json albedo = options.surface ? nlohmann::json("excluded") : nlohmann::json("per-vertex");
    if (!perVertexAlbedo && !options.surface)
        albedo = args.albedo.empty() ? std::array<double, 3>{1.0, 1.0, 1.0} : parseAlbedo(args.albedo);
    layer.params = {{"mode", args.mode},
                    {"order", options.order},
                    {"samples", options.mode == TransferMode::Unshadowed ? 0 : options.samples},
                    {"bounces", options.bounces},
                    {"albedo", albedo},
                    {"seed", options.seed},
                    {"direction_set", kTransferDirectionSet},
                    {"ray_offset", rows.rayOffset},
                    {"rays", rows.rays},
                    {"back_face_hits", rows.backFaceHits}};
    markVertexShard(layer, rows.begin, rows.end, mesh.vertexCount(), shardIndex, shardCount);

    // The bounce part travels as its own layer, so a hybrid relight can send cone lights through it.
    Layer bounceLayer;
    if (rows.direct) {
        bounceLayer.name = "transfer_bounce";
        bounceLayer.domain = layer.domain;
        bounceLayer.semantic = "sh_transfer_bounce_rgb";
        bounceLayer.shape = layer.shape;
        bounceLayer.data.resize(layer.data.size());
        for (size_t i = 0; i < layer.data.size(); ++i) bounceLayer.data[i] = layer.data[i] - (*rows.direct)[i];
        bounceLayer.params = layer.params;
        bounceLayer.params["part"] = "bounces 1..B: transfer minus its direct (shadowed) pass";
    }

    // What a scene's rows are multiplied by for outgoing radiance: the diffuse albedo at each vertex.
    Layer albedoLayer;
    // A shard holds its rows of it, so that the merge gives the unsharded layer.
    if (options.surface) {
        albedoLayer.name = "diffuse_albedo";
        albedoLayer.semantic = "diffuse_albedo_rgb";
        std::vector<float> albedo = vertexDiffuseAlbedo(*options.surface);
        albedoLayer.data.assign(albedo.begin() + 3 * rows.begin, albedo.begin() + 3 * rows.end);
        albedoLayer.shape = {rows.end - rows.begin, 3};
        albedoLayer.params = {{"rule", "base colour factor * texture at the vertex's texcoord * COLOR_0 * (1 - metallic)"}};
        markVertexShard(albedoLayer, rows.begin, rows.end, mesh.vertexCount(), shardIndex, shardCount);
    }

    Bundle output = std::move(input);
    output.layers.clear();
    output.layers.push_back(std::move(layer));
    if (!bounceLayer.name.empty()) output.layers.push_back(std::move(bounceLayer));
    if (!albedoLayer.name.empty()) output.layers.push_back(std::move(albedoLayer));
    output.producer = {{"tool", "prt"}, {"version", PRT_VERSION}, {"stage", "transfer"}};
    output.inputs = {{"mesh", meshHash}};
    output.convention = conventionRecord();
    return output;
}

void reportStats(const TransferStats& stats, double start) {
    nlohmann::json record = {{"rays", stats.rays},
                             {"hits", stats.hits},
                             {"back_face_hits", stats.backFaceHits},
                             {"build_seconds", stats.buildSeconds},
                             {"direct_seconds", stats.directSeconds},
                             {"direct_cpu_seconds", stats.directCpuSeconds},
                             {"bounce_seconds", stats.bounceSeconds},
                             {"hit_record_bytes", stats.hitRecordBytes},
                             {"exitant_rows", stats.exitantRows},
                             {"transfer_bytes", stats.transferBytes}};
    logEvent("transfer_stats", record.dump());
    StageCost cost;
    cost.stage = "transfer";
    cost.seconds = nowSeconds() - start;
    cost.rays = stats.rays;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

void warnBackFaces(const TransferStats& stats) {
    // A closed mesh still sees the odd grazing back-face hit from float error: warn only above 1 in 100000 rays.
    if (stats.backFaceHits > 0)
        (stats.backFaceHits * 100000 > stats.rays ? logWarn : logInfo)(
            "transfer: " + std::to_string(stats.backFaceHits) + " of " + std::to_string(stats.rays) +
            " rays hit back faces (open or inside-out mesh?); they count as occluded and reflect nothing");
}

// A mesh error without a file is the input mesh's.
template <class F>
auto namingInput(const std::string& input, F&& work) {
    try {
        return work();
    } catch (const Error& e) {
        if (!e.file().empty() || e.exitCode() != kExitInput) throw;
        throw Error(input, e.place(), e.problem(), e.exitCode());
    }
}

// A scene's materials, decoded, for the rows of `input`; none for a bundle of prt's own meshes. A scene takes its
// albedo from its materials, so --albedo is refused there.
std::optional<Surface> sceneSurface(const Bundle& input, const TransferArgs& args) {
    if (!input.asset) return std::nullopt;
    if (!args.albedo.empty())
        throw usage("--albedo", "a scene (" + args.input + ") takes its albedo from its materials; --albedo is for "
                                "bundles without them");
    Surface surface = decodeSurface(input, args.input);
    surface.instancing = !args.noInstancing;
    return surface;
}

void runTransferPassOn(const TransferArgs& args, const TransferOptions& options, Bundle& input, int shardIndex,
                       int shardCount, double start);

// One job of sharded interreflected transfer: pass 0 (direct, hit records to OUTPUT.hits), pass 1..B (a bounce;
// the last writes the shard bundle `prt merge` joins), or --gather (a pass's exitant array).
void runTransferPass(const TransferArgs& args, const TransferOptions& options, int shardIndex, int shardCount,
                     double start) {
    Bundle input = readBundle(args.input);
    TriMesh& mesh = input.mesh;
    if (mesh.normals.empty()) throw Error(args.input, "mesh", "has no normals: run `prt meshprep` on it first");
    std::optional<Surface> surface = sceneSurface(input, args);
    TransferOptions sceneOptions = options;
    sceneOptions.surface = surface ? &*surface : nullptr;
    runTransferPassOn(args, sceneOptions, input, shardIndex, shardCount, start);
}

void runTransferPassOn(const TransferArgs& args, const TransferOptions& options, Bundle& input, int shardIndex,
                       int shardCount, double start) {
    TriMesh& mesh = input.mesh;
    const std::string meshHash = hashFile(args.input);
    if (!args.gather.empty()) {
        ShardRun run = makeShardRun(mesh, options, meshHash, 0, int(args.gather.size()));
        int pass = gatherExitant(args.gather, run, args.output);
        logInfo("transfer: gathered pass " + std::to_string(pass) + " of " + std::to_string(args.gather.size()) +
                " shards into " + args.output);
        reportStats(TransferStats{}, start);
        return;
    }
    const int pass = std::max(args.pass, 0);
    ShardRun run = makeShardRun(mesh, options, meshHash, shardIndex, shardCount);
    logInfo("transfer: " + args.input + " (" + std::to_string(run.vertexCount) + " vertices) interreflected, order " +
            std::to_string(options.order) + ", " + std::to_string(options.samples) + " samples, shard " + args.shard +
            (pass == 0 ? ", direct pass" : ", bounce " + std::to_string(pass) + " of " + std::to_string(options.bounces)));
    TransferStats stats;
    ShardRows rows;
    const std::string hitsOut = args.output + ".hits";
    if (pass == 0) {
        rows = namingInput(args.input, [&] { return computeDirectShard(mesh, run, hitsOut, stats); });
        warnBackFaces(stats);
    } else {
        rows = namingInput(args.input, [&] {
            return computeBounceShard(mesh, run, pass, args.previous, args.hits, args.exitant, stats);
        });
    }
    try {
        if (pass < options.bounces) {
            writeShardRows(args.output, run, rows);
        } else {
            Rows layerRows{std::move(rows.total), &rows.direct, rows.rowBegin, rows.rowEnd, rows.rays,
                           rows.backFaceHits, rows.rayOffset};
            writeBundle(args.output, transferBundle(args, options, input, std::move(layerRows), shardIndex,
                                                    shardCount, meshHash));
        }
    } catch (...) {
        // The hit records are half of pass 0's output: without the rows they go too.
        std::error_code error;
        if (pass == 0) std::filesystem::remove(hitsOut, error);
        throw;
    }
    logInfo("transfer: wrote " + args.output + (pass == 0 ? " and " + hitsOut : ""));
    reportStats(stats, start);
}

void runTransfer(const TransferArgs& args) {
    double start = nowSeconds();
    TransferOptions options = resolveOptions(args);
    int shardIndex = 0, shardCount = 1;
    if (!args.shard.empty()) parseShard(args.shard, shardIndex, shardCount);
    bool passes = options.mode == TransferMode::Interreflected && options.bounces > 0 &&
                  (shardCount > 1 || !args.gather.empty());
    bool passFlags = args.pass >= 0 || !args.previous.empty() || !args.exitant.empty() || !args.hits.empty();
    if (!passes && (passFlags || !args.gather.empty()))
        throw usage(args.gather.empty() ? "--pass" : "--gather",
                    "only for sharded interreflected transfer with bounces (--shard I/N, N > 1)");
    if (passes) {
        if (!args.gather.empty() && (!args.shard.empty() || !args.previous.empty() || !args.exitant.empty() || !args.hits.empty()))
            throw usage("--gather", "joins one pass's shards: it takes no --shard, --previous, --exitant or --hits");
        if (args.gather.empty() && args.pass > options.bounces)
            throw usage("--pass", std::to_string(args.pass) + " outside 0.." + std::to_string(options.bounces));
        bool bouncePass = args.gather.empty() && args.pass > 0;
        if (bouncePass && (args.previous.empty() || args.exitant.empty() || args.hits.empty()))
            throw usage("--pass", "a bounce pass needs --previous (its shard's rows of the pass before), --exitant "
                                  "(that pass's gathered array) and --hits (its shard's hit records)");
        if (args.gather.empty() && !bouncePass && (!args.previous.empty() || !args.exitant.empty() || !args.hits.empty()))
            throw usage("--pass", "the direct pass (0) reads no --previous, --exitant or --hits");
        runTransferPass(args, options, shardIndex, shardCount, start);
        return;
    }

    Bundle input = readBundle(args.input);
    TriMesh& mesh = input.mesh;
    if (mesh.normals.empty()) throw Error(args.input, "mesh", "has no normals: run `prt meshprep` on it first");
    std::optional<Surface> surface = sceneSurface(input, args);
    options.surface = surface ? &*surface : nullptr;
    size_t vertexCount = mesh.vertexCount();
    RowRange range = shardRows(vertexCount, shardIndex, shardCount);
    options.vertexBegin = range.begin;
    options.vertexEnd = range.end;
    logInfo("transfer: " + args.input + " (" + std::to_string(vertexCount) + " vertices) " + args.mode + ", order " +
            std::to_string(options.order) + ", " + std::to_string(options.samples) + " samples" +
            (options.bounces > 0 ? ", " + std::to_string(options.bounces) + " bounces" : "") +
            (shardCount > 1 ? ", shard " + args.shard : ""));

    options.keepDirect = options.mode == TransferMode::Interreflected && options.bounces > 0;
    Transfer transfer = namingInput(args.input, [&] { return computeTransfer(mesh, options); });
    const TransferStats& stats = transfer.stats;
    warnBackFaces(stats);
    Rows rows{std::move(transfer.coefficients), options.keepDirect ? &transfer.direct : nullptr, transfer.vertexBegin, transfer.vertexEnd,
              stats.rays, stats.backFaceHits, stats.rayOffset};
    writeBundle(args.output, transferBundle(args, options, input, std::move(rows), shardIndex, shardCount,
                                            hashFile(args.input)));
    logInfo("transfer: wrote " + args.output);
    reportStats(stats, start);
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
                        "layer for a later merge; interreflected with bounces runs as passes (--pass)");
    command->add_option("--pass", args->pass,
                        "Sharded interreflected only: 0 (default) the direct pass, writing -o OUT (the shard's rows) "
                        "and OUT.hits (its hit records); P = 1..B bounce P, writing the rows (the shard bundle "
                        "after the last bounce)")
        ->check(CLI::Range(0, std::numeric_limits<int>::max())); // -1 is "not given" inside: refuse negatives
    command->add_option("--previous", args->previous, "Bounce pass P: this shard's rows of pass P-1");
    command->add_option("--exitant", args->exitant, "Bounce pass P: the exitant array of pass P-1 (--gather)");
    command->add_option("--hits", args->hits, "Bounce pass P: this shard's hit records (OUT.hits of pass 0)");
    command->add_option("--gather", args->gather,
                        "ROWS...: join one pass's shard rows (every shard, any order) into that pass's exitant "
                        "array, -o OUT, for the next bounce");
    command->add_flag("--no-instancing", args->noInstancing,
                      "A scene: build every placed mesh into the ray-tracing BVH as its own triangles instead of Embree "
                      "instances of meshes that several nodes place (same rows to float rounding; for memory figures)");
    command->callback([args] { runTransfer(*args); });
}

} // namespace prt::cli
