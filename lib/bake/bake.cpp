// The bake's computation: validate everything, bake per-texel transfer (all texels, or one shard's range), fill and
// stitch. stage.cpp writes the results.
#include "bake.h"

#include "core.h"
#include "image.h"
#include "material.h"
#include "runtime.h"
#include "sh.h"
#include "transfer.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace prt {

namespace {

Error usage(const std::string& flag, const std::string& problem) { return Error("", flag, problem, kExitUsage); }

void checkOptions(const BakeOptions& options) {
    if (options.resolution < 1 || options.resolution > kMaxBakeResolution)
        throw usage("--resolution", std::to_string(options.resolution) + " outside 1.." +
                                        std::to_string(kMaxBakeResolution));
    if (options.order < 1 || options.order > sh::kMaxOrder)
        throw usage("--order", std::to_string(options.order) + " outside 1.." + std::to_string(sh::kMaxOrder));
    if (options.samples < 1 || options.samples > kMaxTransferSamples)
        throw usage("--samples", std::to_string(options.samples) + " outside 1.." +
                                     std::to_string(kMaxTransferSamples));
    if (options.bounces < 0) throw usage("--bounces", "must be >= 0");
    if (options.uvSet < -1) throw usage("--uv-set", "must be >= 0 (or -1: the default choice)");
    if (options.generateAtlas && options.uvSet >= 0)
        throw usage("--generate-atlas", "bakes into a generated atlas, not into the --uv-set given");
    if (!(options.cage > 0.0 && options.cage < 1.0)) throw usage("--cage", "must lie in (0, 1)");
    if (!(options.maxMissFraction >= 0.0 && options.maxMissFraction <= 1.0))
        throw usage("--max-miss", "must lie in [0, 1]");
    if (options.padding < 2) throw usage("--padding", "must be at least 2 texels");
    if (options.seed > (uint64_t(1) << 53)) throw usage("--seed", "must be a whole number from 0 to 2^53");
    if (options.threads < 0) throw usage("--threads", "must be >= 0 (0: all cores)");
}

Bundle readBundleWithNormals(const std::string& path, const char* role) {
    Bundle bundle = readBundle(path);
    const TriMesh& mesh = bundle.mesh;
    if (mesh.normals.size() != mesh.positions.size())
        throw Error(path, "mesh", std::string("the ") + role + " mesh has no normals: run `prt meshprep` on it first");
    for (uint32_t v : mesh.indices)
        if (v >= mesh.vertexCount()) throw Error(path, "mesh", "index " + std::to_string(v) + " is out of range");
    return bundle;
}

// A scene's input: the bundle kept whole (its asset and materials serve the rays and the output), refusing what
// belongs to single meshes. Returns the flattened mesh with the atlas's source texcoords (empty: generate).
TriMesh sceneBakeMesh(Bundle input, const BakeOptions& options, BakeSurface& surface, int& chosenSet) {
    if (!options.high.empty())
        throw usage("--high", "is for a single low mesh; a scene (" + options.input + ") bakes its own surfaces");
    if (options.albedoOverride)
        throw usage("--albedo", "a scene (" + options.input + ") takes its albedo from its materials");
    TriMesh mesh = input.mesh;
    if (options.generateAtlas) chosenSet = -1;
    else mesh.texcoords = sceneAtlasTexcoords(input, options.uvSet, options.input, chosenSet);
    input.layers.clear();
    auto scene = std::make_shared<const Bundle>(std::move(input));
    surface.materials = std::make_shared<const Surface>(decodeSurface(*scene, options.input));
    surface.scene = std::move(scene);
    return mesh;
}

double boundingDiagonal(const TriMesh& mesh) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        lo[i % 3] = std::min(lo[i % 3], double(mesh.positions[i]));
        hi[i % 3] = std::max(hi[i % 3], double(mesh.positions[i]));
    }
    return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

// Per sample: the diffuse albedo of a scene's material at the sample point, or the low mesh's albedo
// interpolated; empty when the mesh has none or `skip` is set.
std::vector<float> sampleAlbedo(const TriMesh& mesh, const TexelSamples& samples, bool skip,
                                const Surface* materials = nullptr) {
    if (materials) {
        std::vector<float> albedo(3 * samples.texel.size());
        for (size_t i = 0; i < samples.texel.size(); ++i) {
            std::array<float, 3> rho = diffuseAlbedoAt(*materials, samples.triangle[i], samples.barycentric[3 * i + 1],
                                                       samples.barycentric[3 * i + 2]);
            std::copy(rho.begin(), rho.end(), albedo.begin() + 3 * i);
        }
        return albedo;
    }
    if (mesh.albedo.empty() || skip) return {};
    std::vector<float> albedo(3 * samples.texel.size());
    for (size_t i = 0; i < samples.texel.size(); ++i) {
        const uint32_t* corner = &mesh.indices[3 * size_t(samples.triangle[i])];
        for (int c = 0; c < 3; ++c) {
            double sum = 0.0;
            for (int k = 0; k < 3; ++k) sum += samples.barycentric[3 * i + k] * mesh.albedo[3 * size_t(corner[k]) + c];
            albedo[3 * i + c] = float(std::clamp(sum, 0.0, 1.0));
        }
    }
    return albedo;
}

// Spreads per-sample rows over a zeroed atlas: [width * height][channels].
std::vector<float> scatter(const TexelSamples& samples, const float* rows, int channels) {
    std::vector<float> atlas(size_t(samples.width) * samples.height * channels, 0.0f);
    for (size_t i = 0; i < samples.texel.size(); ++i)
        std::copy(rows + i * channels, rows + (i + 1) * channels, atlas.begin() + size_t(samples.texel[i]) * channels);
    return atlas;
}

} // namespace

BakeSurface bakeSurface(const BakeOptions& options) {
    checkOptions(options);
    const int size = options.resolution;
    BakeSurface surface;
    TriMesh& mesh = surface.mesh;
    Bundle input = readBundleWithNormals(options.input, "low");
    int sourceSet = std::max(options.uvSet, 0);
    if (input.asset) {
        mesh = sceneBakeMesh(std::move(input), options, surface, sourceSet);
    } else {
        mesh = std::move(input.mesh);
        if (options.uvSet > 0) mesh.texcoords = readTexcoordSet(options.input, options.uvSet);
        if (options.generateAtlas) mesh.texcoords.clear();
    }
    bool generated = mesh.texcoords.empty();
    nlohmann::json& atlasRecord = surface.atlasRecord;
    atlasRecord = {{"generated", generated}};
    if (!generated || !surface.scene) atlasRecord["source_uv_set"] = sourceSet;
    if (generated) {
        AtlasOptions atlasOptions;
        atlasOptions.width = atlasOptions.height = size;
        atlasOptions.padding = options.padding;
        GeneratedAtlas atlas = generateAtlas(mesh, atlasOptions);
        mesh = std::move(atlas.mesh);
        std::string layout = std::to_string(atlas.charts) + " charts (" + std::to_string(options.padding) +
                             " texels padding, " + std::to_string(atlas.texelsPerUnit) + " texels per unit)";
        if (surface.scene)
            logInfo("bake: generated a lightmap atlas of " + layout + " over every placed primitive of " +
                    options.input + "; the bundle's layer lightmap_uv is that atlas");
        else
            logWarn("bake: " + options.input + " has no UVs: GENERATED a lightmap atlas of " + layout +
                    "; the bundle's TEXCOORD_0 is that atlas");
        atlasRecord["charts"] = atlas.charts;
        atlasRecord["texels_per_unit"] = atlas.texelsPerUnit;
        atlasRecord["padding"] = options.padding;
    }
    RasterOptions raster;
    raster.width = raster.height = size;
    raster.wrap = options.wrap;
    raster.allowOverlap = options.allowOverlap;
    TexelSamples& samples = surface.samples;
    samples = rasteriseAtlas(mesh, raster, options.input);
    const size_t count = samples.texel.size();
    if (count == 0)
        throw Error(options.input, "texcoords",
                    "cover no texel of the atlas (" + std::to_string(samples.degenerateTriangles) + " of " +
                        std::to_string(mesh.triangleCount()) + " triangles have zero UV area): these texcoords are "
                        "no lightmap: bake into a generated atlas with --generate-atlas");
    if (samples.overlappingTexels > 0)
        logWarn("bake: " + std::to_string(samples.overlappingTexels) +
                " texels lie under overlapping UV triangles; the lowest triangle keeps each");
    std::vector<float>& positions = surface.positions;
    std::vector<float>& normals = surface.normals;
    texelSurface(mesh, samples, positions, normals);

    surface.detailNormals = normals;
    if (!options.high.empty()) {
        TriMesh& high = surface.high;
        high = readBundleWithNormals(options.high, "high").mesh;
        float cage = float(options.cage * boundingDiagonal(mesh));
        CageProjection projection = projectOntoHigh(high, positions, normals, cage);
        surface.cageRays = count;
        double missed = double(projection.misses) / double(count);
        if (missed > options.maxMissFraction)
            throw Error(options.high, "",
                        "does not cover the low mesh " + options.input + ": " + std::to_string(projection.misses) +
                            " of " + std::to_string(count) + " texels found no surface within the cage (" +
                            std::to_string(cage) + " units either side along the low normal); allowed " +
                            std::to_string(options.maxMissFraction * 100.0) + "% (--max-miss), cage --cage");
        if (projection.misses > 0)
            logWarn("bake: " + std::to_string(projection.misses) + " of " + std::to_string(count) +
                    " texels missed the high mesh; they keep the low surface's point and normal");
        surface.detailNormals = projection.normals;
        if (options.highPosition) positions = std::move(projection.positions);
        normals = std::move(projection.normals);
        surface.highRecord = {{"mesh", std::filesystem::path(options.high).filename().string()},
                              {"hash", hashFile(options.high)},
                              {"cage", cage}, {"position", options.highPosition ? "high" : "low"},
                              {"misses", projection.misses}};
    }
    return surface;
}

namespace {

TransferOptions texelTransferOptions(const BakeOptions& options) {
    TransferOptions transferOptions;
    transferOptions.mode = options.bounces > 0 ? TransferMode::Interreflected : TransferMode::Shadowed;
    transferOptions.order = options.order;
    transferOptions.samples = options.samples;
    transferOptions.bounces = options.bounces;
    transferOptions.albedo = options.albedo;
    transferOptions.albedoOverride = options.albedoOverride;
    transferOptions.seed = options.seed;
    transferOptions.threads = options.threads;
    transferOptions.keepDirect = options.bounces > 0; // the bounce layer: what the hybrid sends cone lights through
    return transferOptions;
}

} // namespace

TexelTransferRows bakeTexelTransfer(const BakeSurface& surface, const BakeOptions& options, size_t begin,
                                    size_t end) {
    const TexelSamples& samples = surface.samples;
    const size_t count = samples.texel.size();
    const int size = options.resolution;
    end = std::min(end, count);
    begin = std::min(begin, end);
    // A scene's rays see its own flattened mesh (the same triangles as the atlas mesh, its vertices unsplit, which
    // its materials address) with its materials; a plain bake's, the low mesh or the high one.
    const TriMesh& geometry = surface.scene ? surface.scene->mesh : options.high.empty() ? surface.mesh : surface.high;
    TexelTransferRows result;
    result.begin = begin;
    result.end = end;
    BakeStats& stats = result.stats;
    stats.texels = end - begin;

    // Transfer per texel: the per-vertex integrator with texels as receivers.
    // A scene's rows are irradiance transfer: its materials' albedo is applied at bounces, never at the receiver.
    std::vector<float> albedo = surface.scene ? std::vector<float>() : sampleAlbedo(surface.mesh, samples, options.albedoOverride);
    std::vector<uint64_t> keys(samples.texel.begin() + begin, samples.texel.begin() + end); // rotations follow texels
    Receivers receivers;
    receivers.positions = surface.positions.data() + 3 * begin;
    receivers.normals = surface.normals.data() + 3 * begin;
    receivers.albedo = albedo.empty() ? nullptr : albedo.data() + 3 * begin;
    receivers.keys = keys.data();
    receivers.count = end - begin;
    TransferOptions transferOptions = texelTransferOptions(options);
    transferOptions.surface = surface.materials.get();
    std::string range = end - begin == count ? "" : " (texels " + std::to_string(begin) + ".." + std::to_string(end) +
                                                        " of them)";
    logInfo("bake: " + std::to_string(count) + " texels of " + std::to_string(size) + "x" + std::to_string(size) +
            " (" + std::to_string(100.0 * count / (double(size) * size)) + "% covered)" + range + ", order " +
            std::to_string(options.order) + ", " + std::to_string(options.samples) + " samples" +
            (options.bounces > 0 ? ", " + std::to_string(options.bounces) + " bounces" : "") + ", rays against " +
            (options.high.empty() ? "the low mesh"
                                  : "the high mesh (" + std::to_string(surface.high.triangleCount()) + " triangles)"));
    double transferStart = nowSeconds();
    Transfer transfer;
    try {
        transfer = computeTransferAt(geometry, receivers, transferOptions);
    } catch (const Error& e) {
        if (!e.file().empty() || e.exitCode() != kExitInput) throw;
        throw Error(options.high.empty() ? options.input : options.high, e.place(), e.problem(), e.exitCode());
    }
    stats.transferSeconds = nowSeconds() - transferStart;
    stats.directSeconds = transfer.stats.directSeconds;
    stats.rays = transfer.stats.rays;
    stats.cageRays = surface.cageRays;
    if (options.yardstick) {
        RayThroughput bare = castBareOcclusionRaysAt(geometry, receivers, transferOptions);
        stats.bareRaysPerSecond = bare.seconds > 0.0 ? bare.rays / bare.seconds : 0.0;
    }
    result.rows = std::move(transfer.coefficients);
    if (!transfer.direct.empty()) {
        result.bounce = std::move(transfer.direct);
        for (size_t i = 0; i < result.bounce.size(); ++i) result.bounce[i] = result.rows[i] - result.bounce[i];
    }
    result.rayOffset = transfer.stats.rayOffset;
    return result;
}

namespace {

// Scales each texel's 3 channels starting at `first` to unit length; (0, 0, 1) where they vanish (far from every
// chart, where nothing reads them).
void normaliseTexels(float* texels, size_t count, int channels, int first) {
    for (size_t t = 0; t < count; ++t) {
        float* n = texels + t * channels + first;
        double length = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
        if (length > 1e-6)
            for (int a = 0; a < 3; ++a) n[a] = float(n[a] / length);
        else
            n[0] = n[1] = 0.0f, n[2] = 1.0f;
    }
}

// The "texel_surface" atlas: receivers' positions, normals and albedo, gutters filled, coverage exact.
// Needs the bake's mesh and samples and its receivers' positions and normals ([covered texel][3]).
std::vector<float> surfaceAtlas(const TriMesh& mesh, const TexelSamples& samples, const std::vector<float>& positions,
                                const std::vector<float>& normals, const BakeOptions& options, const uint8_t* covered,
                                const Surface* materials) {
    const size_t count = samples.texel.size();
    std::vector<float> albedo = sampleAlbedo(mesh, samples, options.albedoOverride, materials);
    std::vector<float> rows(count * kTexelSurfaceChannels);
    for (size_t i = 0; i < count; ++i) {
        float* row = &rows[i * kTexelSurfaceChannels];
        for (int a = 0; a < 3; ++a) {
            row[a] = positions[3 * i + a];
            row[3 + a] = normals[3 * i + a];
            row[6 + a] = albedo.empty() ? options.albedo[a] : albedo[3 * i + a];
        }
    }
    std::vector<float> atlas = scatter(samples, rows.data(), kTexelSurfaceChannels);
    const size_t texels = size_t(samples.width) * samples.height;
    pushPull(atlas.data(), samples.width, samples.height, kTexelSurfaceChannels, covered);
    normaliseTexels(atlas.data(), texels, kTexelSurfaceChannels, 3);
    for (size_t t = 0; t < texels; ++t) atlas[t * kTexelSurfaceChannels + 9] = covered[t] ? 1.0f : 0.0f;
    return atlas;
}

} // namespace

BakedAtlas finishBake(BakeSurface surface, const BakeOptions& options, std::vector<float> rows,
                      std::vector<float> bounce, float rayOffset, BakeStats stats) {
    const int size = options.resolution;
    const int channels = 3 * options.order * options.order;
    BakedAtlas baked;
    baked.mesh = std::move(surface.mesh);
    baked.samples = std::move(surface.samples);
    const TriMesh& mesh = baked.mesh;
    const TexelSamples& samples = baked.samples;
    const size_t count = samples.texel.size();
    if (rows.size() != count * channels || (options.bounces > 0 && bounce.size() != rows.size()))
        throw Error("", "bake", "finishing needs the rows of all " + std::to_string(count) + " covered texels",
                    kExitFailure);
    stats.texels = count;

    // Atlas images: fill the gutters, then make seams agree (lookups on chart borders read the gutters).
    std::vector<uint8_t> covered = coverageMask(samples);
    std::vector<SeamEdge> seams = findSeams(mesh);
    stats.seamEdges = seams.size();
    auto atlasOf = [&](std::vector<float>& part) {
        std::vector<float> atlas = scatter(samples, part.data(), channels);
        part = {};
        double fillStart = nowSeconds();
        if (options.dilateOnly)
            dilateOneRing(atlas.data(), size, size, channels, covered.data());
        else
            pushPull(atlas.data(), size, size, channels, covered.data());
        stats.fillSeconds += nowSeconds() - fillStart;
        if (options.seamStitch) stats.stitchedTexels = stitchSeams(mesh, seams, size, size, atlas.data(), channels);
        return atlas;
    };
    baked.transfer = atlasOf(rows);
    if (!bounce.empty()) baked.bounce = atlasOf(bounce);
    baked.surface =
        surfaceAtlas(mesh, samples, surface.positions, surface.normals, options, covered.data(), surface.materials.get());
    baked.scene = surface.scene;

    std::vector<float> tangentNormals =
        tangentSpaceNormals(mesh, vertexTangents(mesh), samples, surface.detailNormals);
    baked.normals = scatter(samples, tangentNormals.data(), 3);
    pushPull(baked.normals.data(), size, size, 3, covered.data());
    normaliseTexels(baked.normals.data(), baked.normals.size() / 3, 3, 0);

    baked.params = {{"width", size},
                    {"height", size},
                    {"uv_set", surface.scene ? nlohmann::json("lightmap_uv") : nlohmann::json(0)},
                    {"atlas", surface.atlasRecord},
                    {"order", options.order},
                    {"mode", transferModeName(texelTransferOptions(options).mode)},
                    {"samples", options.samples},
                    {"bounces", options.bounces},
                    {"albedo", surface.scene ? nlohmann::json("excluded")
                               : mesh.albedo.empty() || options.albedoOverride
                                   ? nlohmann::json(options.albedo)
                                   : nlohmann::json("per-vertex")},
                    {"seed", options.seed},
                    {"direction_set", kTransferDirectionSet},
                    {"rotation_key", "texel index y * width + x"},
                    {"ray_offset", rayOffset},
                    {"covered_texels", count},
                    {"sample_point", "texel centre, or the triangle's point nearest to it for partly covered texels"},
                    {"fill", options.dilateOnly ? "dilate-one-ring" : "push-pull"},
                    {"seam_stitch", options.seamStitch},
                    {"wrap", options.wrap == UvWrap::Repeat ? "repeat" : "none"}};
    if (!surface.highRecord.is_null()) baked.params["high"] = surface.highRecord;
    baked.stats = stats;
    return baked;
}

BakedAtlas bakeAtlas(const BakeOptions& options) {
    BakeSurface surface = bakeSurface(options);
    TexelTransferRows rows = bakeTexelTransfer(surface, options, 0, surface.samples.texel.size());
    return finishBake(std::move(surface), options, std::move(rows.rows), std::move(rows.bounce), rows.rayOffset,
                      rows.stats);
}

} // namespace prt
