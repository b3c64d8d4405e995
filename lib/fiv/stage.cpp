// `prt fiv`: the two halves of the precompute behind one command, with their cost.
#include "fiv.h"

#include "core.h"

#include <cstdio>

namespace prt::fiv {

namespace {

// The flag checks that need no input read: usage errors (kExitUsage) for what cannot go together.
void checkFivOptions(const FivStageOptions& options) {
    if (options.inputs.empty() && options.merge.empty())
        throw Error("", "input", "is required: an occluder mesh, or visibility bundles (or --merge SHARD...)", kExitUsage);
    if (fileExtension(options.output) != "glb") throw Error(options.output, "-o", "needs a .glb file", kExitUsage);
    bool sharded = options.visibility.shardCount > 1;
    if (sharded && !options.visibilityOnly)
        throw Error("", "--shard", "shards hold visibility only: add --visibility-only, then reduce all shards", kExitUsage);
    if (!options.visibilityOnly && options.env.empty())
        throw Error("", "--env", "is needed to reduce the visibility (or give --visibility-only)", kExitUsage);
    if (options.difmapSize < 1 || options.difmapSize > kMaxCube)
        throw Error("", "--difmap", "must lie in 1.." + std::to_string(kMaxCube), kExitUsage);

    if (options.sourceGrid.azimuth > 0) {
        if (!options.sources) throw Error("", "--source-grid", "needs --sources (it is the sources' own grid)", kExitUsage);
        if (options.visibilityOnly)
            throw Error("", "--source-grid", "belongs to the reduction (the sources come from --env), not --visibility-only",
                        kExitUsage);
        checkSourceGrid(options.sourceGrid, 0, "", kExitUsage);
        if (!(options.sourceSharpen >= kMinSourceSharpen && options.sourceSharpen <= kMaxSourceSharpen))
            throw Error("", "--source-sharpen", "must lie in " + std::to_string(int(kMinSourceSharpen)) + ".." +
                                                    std::to_string(int(kMaxSourceSharpen)), kExitUsage);
    }
}

// The occluder's visibility: joined from visibility bundles (options.inputs, as their shards), or sampled from one occluder
// mesh. Gives the occluder mesh and the bundle inputs to record.
Visibility occluderVisibility(const FivStageOptions& options, TriMesh& occluder, nlohmann::json& inputs) {
    Bundle first = readBundle(options.inputs[0]);
    bool fromVisibility = findLayer(first, "fiv_mask_offsets") != nullptr;
    Visibility vis;
    if (fromVisibility) {
        if (options.visibilityOnly) throw Error(options.inputs[0], "--visibility-only", "input is visibility already", kExitUsage);
        std::vector<Visibility> parts;
        parts.push_back(readVisibility(first, options.inputs[0]));
        occluder = std::move(first.mesh);
        inputs = first.inputs;
        for (size_t i = 1; i < options.inputs.size(); ++i) {
            Bundle other = readBundle(options.inputs[i]);
            if (!findLayer(other, "fiv_mask_offsets"))
                throw Error(options.inputs[i], "fiv_mask_offsets", "is not a visibility bundle like " + options.inputs[0]);
            parts.push_back(readVisibility(other, options.inputs[i]));
        }
        vis = parts.size() == 1 && parts[0].shardCount == 1 ? std::move(parts[0]) : joinShards(std::move(parts), options.inputs);
        if (vis.rowBegin != 0 || vis.rowEnd != vis.grid.sampleCount())
            throw Error(options.inputs[0], "fiv_mask_offsets", "covers rows " + std::to_string(vis.rowBegin) + ".." +
                                                                  std::to_string(vis.rowEnd) + " only: give every shard");
        logInfo("fiv: reducing the visibility of " + options.inputs[0] + " (" + std::to_string(vis.grid.sampleCount()) +
                " samples)");
    } else {
        if (options.inputs.size() != 1) throw Error(options.inputs[1], "fiv", "one occluder mesh at a time", kExitUsage);
        occluder = std::move(first.mesh);
        inputs = {{"mesh", hashFile(options.inputs[0])}};
        const GridSpec& g = options.visibility.grid;
        logInfo("fiv: " + options.inputs[0] + " (" + std::to_string(occluder.triangleCount()) + " triangles), grid " +
                std::to_string(g.azimuth) + "x" + std::to_string(g.polar) + "x" + std::to_string(g.shells) + ", cube 6x" +
                std::to_string(options.visibility.cube) + "^2, supersample " + std::to_string(options.visibility.supersample));
        double t0 = nowSeconds();
        vis = sampleVisibility(occluder, options.visibility, options.inputs[0]);
        const double visibilitySeconds = nowSeconds() - t0;
        char line[200];
        std::snprintf(line, sizeof line, "fiv: visibility in %.2f s, %llu rays (%.2f%% of the naive %llu)",
                      visibilitySeconds, (unsigned long long)vis.rays, 100.0 * double(vis.rays) / double(std::max<uint64_t>(vis.naiveRays, 1)),
                      (unsigned long long)vis.naiveRays);
        logInfo(line);
    }

    return vis;
}

} // namespace

void runFiv(const FivStageOptions& options) {
    double start = nowSeconds();
    checkFivOptions(options);
    const bool withSourceGrid = options.sourceGrid.azimuth > 0;

    if (!options.merge.empty()) {
        if (!options.visibilityOnly) throw Error("", "--merge", "joins visibility shards only", kExitUsage);
        std::vector<Visibility> parts;
        Bundle shard = readBundle(options.merge[0]);
        for (size_t i = 0; i < options.merge.size(); ++i) {
            if (i > 0) shard = readBundle(options.merge[i]);
            parts.push_back(readVisibility(shard, options.merge[i]));
        }
        Visibility joined = joinShards(std::move(parts), options.merge);
        Bundle firstShard = readBundle(options.merge[0]);
        writeBundle(options.output, visibilityBundle(firstShard.mesh, joined, firstShard.inputs));
        logInfo("fiv: joined " + std::to_string(options.merge.size()) + " visibility shards into " + options.output);
        return;
    }
    TriMesh occluder;
    nlohmann::json inputs;
    uint64_t extraRays = 0; // the source grid's rays
    Visibility vis = occluderVisibility(options, occluder, inputs);

    if (options.visibilityOnly) {
        writeBundle(options.output, visibilityBundle(occluder, vis, inputs));
    } else {
        double t0 = nowSeconds();
        EnvironmentMap env = readEnvironmentMap(options.env);
        std::string envHash = hashFile(options.env);
        CubeEnvironment cube = resampleToCube(env, vis.cube);
        FivGrid grid;
        uint64_t sourceRays = 0, selfRays = 0;
        SmallSources sources;
        SourceGrid sourceGrid; // with a source grid and a map with sources: its samples (else empty)
        CubeEnvironment residualCube; // the cube of the map without its small sources (with options.sources)
        if (options.sources) { // the masks see the map without its small sources; those get rays of their own
            EnvironmentMap residual = env;
            sources = extractSmallSources(residual);
            residualCube = resampleToCube(residual, vis.cube);
            grid = reduceVisibility(vis, residualCube, options.inputs[0]);
            if (withSourceGrid && !sources.direction.empty()) { // the grid keeps the rest; the sources get their own
                const GridSpec& g = options.sourceGrid;
                SourceGridOptions so; // sampleSourceGrid checks the grid against the sources' texel count
                so.grid = g;
                so.sharpen = options.sourceSharpen;
                so.threads = options.visibility.threads;
                double s0 = nowSeconds();
                sourceGrid = sampleSourceGrid(occluder, sources, so, options.inputs[0]);
                char line[240];
                std::snprintf(line, sizeof line,
                              "fiv: source grid %dx%dx%d (%zu samples, K %g): %llu source rays + %llu inside-vote rays in %.2f s",
                              g.azimuth, g.polar, g.shells, g.sampleCount(), so.sharpen,
                              (unsigned long long)sourceGrid.sourceRays, (unsigned long long)sourceGrid.insideRays,
                              nowSeconds() - s0);
                logInfo(line);
            } else {
                if (withSourceGrid) logInfo("fiv: the map has no small source: no source grid (the bundle is the one without it)");
                sourceRays = addSourceShadows(occluder, vis, sources, grid, options.visibility.threads);
            }
            std::string shares;
            for (double f : sources.powerFraction) shares += (shares.empty() ? "" : ", ") + std::to_string(f);
            logInfo("fiv: " + std::to_string(sources.powerFraction.size()) + " small sources (" +
                    std::to_string(sources.direction.size() / 3) + " texels, power shares " + (shares.empty() ? "-" : shares) +
                    ") shadowed by " + std::to_string(sourceRays + sourceGrid.sourceRays) + " rays of their own" +
                    (sourceGrid.fraction.empty() ? "" : " on their own grid"));
        } else {
            grid = reduceVisibility(vis, cube, options.inputs[0]);
        }
        std::vector<float> self;
        if (options.selfVertices) {
            if (occluder.normals.size() != occluder.positions.size())
                throw Error(options.inputs[0], "--self-vertices", "the occluder mesh has no vertex normals (prt meshprep adds them)",
                            kExitInput);
            double s0 = nowSeconds();
            self = selfIrradiance(occluder, options.sources ? residualCube : cube, sources, options.visibility.threads, &selfRays);
            char line[160];
            std::snprintf(line, sizeof line, "fiv: self-shadowing at %zu vertices, %llu rays in %.2f s", occluder.vertexCount(),
                          (unsigned long long)selfRays, nowSeconds() - s0);
            logInfo(line);
        }
        std::vector<float> difmap = difMap(cube, options.difmapSize);
        std::array<double, 9> fivEnv = environmentFiv(cube);
        inputs["env"] = envHash;
        FivBundleOptions bundleOptions;
        bundleOptions.half = options.half;
        bundleOptions.difmapSize = options.difmapSize;
        bundleOptions.envHash = envHash;
        bundleOptions.selfIrradiance = std::move(self);
        if (!sourceGrid.fraction.empty()) bundleOptions.sourceGrid = &sourceGrid;
        extraRays = sourceGrid.sourceRays + sourceGrid.insideRays;
        Bundle bundle = fivBundle(occluder, grid, difmap, fivEnv, bundleOptions, inputs);
        for (Layer& layer : bundle.layers)
            if (layer.name == "fiv") {
                layer.params["rays"] = vis.rays, layer.params["naive_rays"] = vis.naiveRays;
                if (sourceRays > 0) layer.params["source_rays"] = sourceRays; // a map without sources: same bytes
                if (options.selfVertices) layer.params["self_rays"] = selfRays;
            }
        writeBundle(options.output, bundle);
        char line[160];
        std::snprintf(line, sizeof line, "fiv: reduction in %.2f s, %d bytes per sample", nowSeconds() - t0,
                      options.half ? 25 : 49);
        logInfo(line);
    }
    StageCost cost;
    cost.stage = "fiv";
    cost.seconds = nowSeconds() - start;
    cost.rays = vis.rays + extraRays;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace prt::fiv
