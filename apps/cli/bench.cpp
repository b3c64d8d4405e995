// prt bench transfer: the transfer stage against its yardsticks, measured in one run.
//   - shadowed rays/s against bare Embree rtcOccluded1 over exactly the same rays (target ratio >= 0.9)
//   - interreflected: each bounce's time against the direct pass's (target ratio <= 0.15)
//   - 1-thread against 2-thread shadowed time
//   - optionally, peak memory of an order-5 interreflected run on a procedural scene grown to --vertices
#include "cli.h"

#include "bundle.h"
#include "core.h"
#include "scene.h"
#include "transfer.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

namespace prt::cli {

namespace {

struct BenchTransferArgs {
    std::string mesh = "sphere-in-cavity";
    int samples = 1024;
    int order = 3;
    int threads = 0;
    int bounces = 2;
    int repeats = 3;
    uint64_t vertices = 0;
    int memorySamples = 256;
};

bool isSceneName(const std::string& name) {
    std::vector<std::string> names = sceneNames();
    return std::find(names.begin(), names.end(), name) != names.end();
}

TriMesh loadBenchMesh(const std::string& source) {
    if (isSceneName(source)) return makeScene(source);
    if (!std::filesystem::exists(source))
        throw Error(source, "", "is neither a file nor a scene name (scenes: sphere, plane, box-room, cavity, "
                                "sphere-in-cavity, two-spheres)", kExitUsage);
    TriMesh mesh = readBundle(source).mesh;
    if (mesh.normals.empty()) throw Error(source, "mesh", "has no normals: run `prt meshprep` on it first");
    return mesh;
}

double raysPerSecond(uint64_t rays, double seconds) { return seconds > 0.0 ? double(rays) / seconds : 0.0; }

void runBenchTransfer(const BenchTransferArgs& args) {
    if (args.samples < 1 || args.samples > kMaxTransferSamples)
        throw Error("", "--samples", "outside 1.." + std::to_string(kMaxTransferSamples), kExitUsage);
    if (args.memorySamples < 1 || args.memorySamples > kMaxTransferSamples)
        throw Error("", "--memory-samples", "outside 1.." + std::to_string(kMaxTransferSamples), kExitUsage);
    if (args.bounces < 1) throw Error("", "--bounces", "must be >= 1 to time a bounce", kExitUsage);
    if (args.repeats < 1) throw Error("", "--repeats", "must be >= 1", kExitUsage);
    if (args.threads < 0) throw Error("", "--threads", "must be >= 0", kExitUsage);
    if (args.vertices > 0 && !isSceneName(args.mesh))
        throw Error("", "--vertices", "grows procedural scenes only; give a scene name", kExitUsage);
    double start = nowSeconds();
    TriMesh mesh = loadBenchMesh(args.mesh);

    TransferOptions options;
    options.order = args.order;
    options.samples = args.samples;
    options.threads = resolveThreads(args.threads);
    options.progress = false;

    // Bare and stage passes alternate, best of `repeats` each, so drifting machine load hits both alike. The
    // ratio is taken in process CPU time too: on a shared machine other processes stretch wall time, not CPU time.
    RayThroughput bare;
    double bareSeconds = INFINITY, bareCpu = INFINITY, shadowedSeconds = INFINITY, shadowedCpu = INFINITY;
    uint64_t shadowedRays = 0;
    for (int r = 0; r < args.repeats; ++r) {
        bare = castBareOcclusionRays(mesh, options);
        bareSeconds = std::min(bareSeconds, bare.seconds);
        bareCpu = std::min(bareCpu, bare.cpuSeconds);
        Transfer shadowed = computeTransfer(mesh, options);
        shadowedSeconds = std::min(shadowedSeconds, shadowed.stats.directSeconds);
        shadowedCpu = std::min(shadowedCpu, shadowed.stats.directCpuSeconds);
        shadowedRays = shadowed.stats.rays;
    }
    double bareRate = raysPerSecond(bare.rays, bareSeconds);
    double shadowedRate = raysPerSecond(shadowedRays, shadowedSeconds);
    double cpuRatio = raysPerSecond(shadowedRays, shadowedCpu) / raysPerSecond(bare.rays, bareCpu);

    TransferOptions interreflectedOptions = options;
    interreflectedOptions.mode = TransferMode::Interreflected;
    interreflectedOptions.bounces = args.bounces;
    TransferStats interreflected = computeTransfer(mesh, interreflectedOptions).stats;
    double meanBounce = 0.0;
    for (double seconds : interreflected.bounceSeconds) meanBounce += seconds / interreflected.bounceSeconds.size();

    double threadSeconds[2];
    for (int t = 1; t <= 2; ++t) {
        TransferOptions single = options;
        single.threads = t;
        threadSeconds[t - 1] = INFINITY;
        for (int r = 0; r < args.repeats; ++r)
            threadSeconds[t - 1] = std::min(threadSeconds[t - 1], computeTransfer(mesh, single).stats.directSeconds);
    }

    // Other processes on the machine skew wall-clock ratios and thread scaling; the report says how busy it was.
    double load[1] = {0.0};
    getloadavg(load, 1);
    nlohmann::json report = {
        {"mesh", args.mesh},
        {"load_average", load[0]},
        {"vertices", mesh.vertexCount()},
        {"triangles", mesh.triangleCount()},
        {"samples", args.samples},
        {"order", args.order},
        {"threads", options.threads},
        {"bare_rays_per_second", bareRate},
        {"bare_occluded_fraction", double(bare.occluded) / double(std::max<uint64_t>(bare.rays, 1))},
        {"shadowed_rays_per_second", shadowedRate},
        {"shadowed_over_bare", shadowedRate / bareRate},
        {"shadowed_over_bare_cpu_time", cpuRatio},
        {"interreflected",
         {{"bounces", args.bounces},
          {"direct_seconds", interreflected.directSeconds},
          {"bounce_seconds", interreflected.bounceSeconds},
          {"bounce_over_direct", meanBounce / interreflected.directSeconds},
          {"hits_per_vertex", double(interreflected.hits) / mesh.vertexCount()},
          {"back_face_hits", interreflected.backFaceHits},
          {"hit_record_bytes", interreflected.hitRecordBytes}}},
        {"scaling",
         {{"one_thread_seconds", threadSeconds[0]},
          {"two_thread_seconds", threadSeconds[1]},
          {"speedup", threadSeconds[0] / threadSeconds[1]}}},
    };

    if (args.vertices > 0) {
        TriMesh big = makeSceneWithVertices(args.mesh, args.vertices);
        mesh = TriMesh{}; // free the small scene before the peak
        TransferOptions memoryOptions = interreflectedOptions;
        memoryOptions.order = 5;
        memoryOptions.samples = args.memorySamples;
        memoryOptions.progress = true;
        TransferStats stats = computeTransfer(big, memoryOptions).stats;
        double perVertex = 1.0 / double(big.vertexCount());
        double bigBounce = 0.0;
        for (double seconds : stats.bounceSeconds) bigBounce += seconds / stats.bounceSeconds.size();
        report["memory"] = {{"vertices", big.vertexCount()},
                            {"order", 5},
                            {"samples", args.memorySamples},
                            {"bounces", args.bounces},
                            {"peak_bytes", stats.peakMemoryBytes},
                            {"peak_bytes_per_vertex", double(stats.peakMemoryBytes) * perVertex},
                            {"hit_record_bytes_per_vertex", double(stats.hitRecordBytes) * perVertex},
                            {"transfer_bytes_per_vertex", double(stats.transferBytes) * perVertex},
                            {"hits_per_vertex", double(stats.hits) * perVertex},
                            {"direct_seconds", stats.directSeconds},
                            {"bounce_seconds", stats.bounceSeconds},
                            {"bounce_over_direct", bigBounce / stats.directSeconds}};
    }

    if (logOptions().json) {
        std::printf("%s\n", report.dump().c_str());
    } else {
        std::printf("transfer bench: %s, %zu vertices, %d samples, order %d, %d threads (load average %.1f)\n",
                    args.mesh.c_str(), size_t(report["vertices"]), args.samples, args.order, options.threads, load[0]);
        std::printf("  bare rtcOccluded1      %8.2f Mrays/s (%.1f%% occluded)\n", bareRate * 1e-6,
                    100.0 * double(report["bare_occluded_fraction"]));
        std::printf("  transfer shadowed      %8.2f Mrays/s  ratio %.3f wall, %.3f CPU time (target >= 0.9)\n",
                    shadowedRate * 1e-6, shadowedRate / bareRate, cpuRatio);
        std::printf("  interreflected direct  %8.3f s, bounce mean %.3f s  ratio %.3f (target <= 0.15), "
                    "%.1f hits/vertex\n",
                    interreflected.directSeconds, meanBounce, meanBounce / interreflected.directSeconds,
                    double(interreflected.hits) / double(report["vertices"]));
        std::printf("  scaling                1 thread %.3f s, 2 threads %.3f s, speedup %.2f\n", threadSeconds[0],
                    threadSeconds[1], threadSeconds[0] / threadSeconds[1]);
        if (report.contains("memory")) {
            const nlohmann::json& m = report["memory"];
            std::printf("  memory (order 5, %d samples, %d bounces, %zu vertices): peak %.0f MiB = %.0f B/vertex "
                        "(hits %.0f B, transfer arrays %.0f B per vertex)\n",
                        args.memorySamples, args.bounces, size_t(m["vertices"]),
                        double(m["peak_bytes"]) / (1 << 20), double(m["peak_bytes_per_vertex"]),
                        double(m["hit_record_bytes_per_vertex"]), double(m["transfer_bytes_per_vertex"]));
            std::printf("    direct %.2f s, bounce mean %.2f s  ratio %.3f, %.1f hits/vertex\n",
                        double(m["direct_seconds"]), double(m["bounce_over_direct"]) * double(m["direct_seconds"]),
                        double(m["bounce_over_direct"]),
                        double(m["hits_per_vertex"]));
        }
    }
    std::fflush(stdout);

    StageCost cost;
    cost.stage = "bench transfer";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addBenchCommand(CLI::App& app) {
    CLI::App* bench = app.add_subcommand("bench", "Measure stages against their yardsticks");
    bench->require_subcommand(1);

    auto args = std::make_shared<BenchTransferArgs>();
    CLI::App* transfer = bench->add_subcommand("transfer", "Transfer ray throughput, bounce cost, scaling, memory");
    transfer->add_option("mesh", args->mesh,
                         "A bundle/glb with normals, or a procedural scene name (default sphere-in-cavity)");
    transfer->add_option("--samples", args->samples, "Directions per vertex (default 1024)");
    transfer->add_option("--order", args->order, "SH bands (default 3)");
    transfer->add_option("--threads", args->threads, "Worker threads (default 0: all cores)");
    transfer->add_option("--bounces", args->bounces, "Bounces of the interreflected runs (default 2)");
    transfer->add_option("--repeats", args->repeats, "Timed repeats, best kept (default 3)");
    transfer->add_option("--vertices", args->vertices,
                         "Also grow the procedural scene to this many vertices and measure order-5 interreflected "
                         "peak memory");
    transfer->add_option("--memory-samples", args->memorySamples,
                         "Directions per vertex of the --vertices run (default 256)");
    transfer->callback([args] { runBenchTransfer(*args); });
}

} // namespace prt::cli
