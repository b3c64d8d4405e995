// The `prt bake` stage: validate everything, bake per-texel transfer (all texels, or one shard's range), fill,
// stitch, write textures then the bundle; or join shards and finish as the unsharded bake does.
#include "bake.h"

#include "core.h"
#include "image.h"
#include "sh.h"
#include "transfer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <unistd.h>

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
    if (options.uvSet < 0) throw usage("--uv-set", "must be >= 0");
    if (!(options.cage > 0.0 && options.cage < 1.0)) throw usage("--cage", "must lie in (0, 1)");
    if (!(options.maxMissFraction >= 0.0 && options.maxMissFraction <= 1.0))
        throw usage("--max-miss", "must lie in [0, 1]");
    if (options.padding < 2) throw usage("--padding", "must be at least 2 texels");
    if (options.seed > (uint64_t(1) << 53)) throw usage("--seed", "must be at most 2^53");
    if (options.threads < 0) throw usage("--threads", "must be >= 0 (0: all cores)");
}

TriMesh readMeshWithNormals(const std::string& path, const char* role) {
    TriMesh mesh = readBundle(path).mesh;
    if (mesh.normals.size() != mesh.positions.size())
        throw Error(path, "mesh", std::string("the ") + role + " mesh has no normals: run `prt meshprep` on it first");
    for (uint32_t v : mesh.indices)
        if (v >= mesh.vertexCount()) throw Error(path, "mesh", "index " + std::to_string(v) + " is out of range");
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

// Per sample: the low mesh's albedo interpolated, or empty when the mesh has none or `skip` is set.
std::vector<float> sampleAlbedo(const TriMesh& mesh, const TexelSamples& samples, bool skip) {
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

// The textures of one bake. Each is named by its content (NAME.KIND.<16 hex>.EXT), so a new bake never
// overwrites a file the previous bundle references: until the new bundle replaces it, the last good result stays
// whole, and a failure removes only the files this bake created. Once committed, the previous bundle's textures
// that the new one does not use are removed.
struct WrittenFiles {
    std::vector<std::string> paths;   // every texture the new bundle references
    std::vector<std::string> created; // those that did not exist before
    std::vector<std::string> previous; // the textures of the bundle being replaced
    bool committed = false;
    ~WrittenFiles() {
        if (committed) {
            for (const std::string& path : previous)
                if (std::find(paths.begin(), paths.end(), path) == paths.end()) std::remove(path.c_str());
            return;
        }
        for (const std::string& path : created) std::remove(path.c_str());
    }
};

// Writes a texture through `write` (into a hidden temporary file with the right extension, which the writer needs)
// and moves it to BASE.KIND.<first 16 hex digits of its content hash>.EXTENSION; returns that path.
std::string writeContentAddressed(const std::string& base, const std::string& kind, const std::string& extension,
                                  WrittenFiles& written, const std::function<void(const std::string&)>& write) {
    std::filesystem::path stem(base);
    std::string tmp = (stem.parent_path() / ("." + stem.filename().string() + "." + kind + ".tmp-" +
                                             std::to_string(getpid()) + "." + extension)).string();
    write(tmp);
    std::string hash = hashFile(tmp);
    std::string path = base + "." + kind + "." + hash.substr(hash.find(':') + 1, 16) + "." + extension;
    std::error_code error;
    if (std::filesystem::exists(path, error)) {
        std::remove(tmp.c_str()); // the same name holds the same bytes
    } else {
        std::filesystem::rename(tmp, path);
        written.created.push_back(path);
    }
    written.paths.push_back(path);
    return path;
}

// The external files of the bundle at `path` (params.files of its layers), if it is a readable bundle.
std::vector<std::string> bundleTextures(const std::string& path) {
    std::vector<std::string> files;
    std::error_code error;
    if (!std::filesystem::exists(path, error)) return files;
    try {
        std::filesystem::path folder = std::filesystem::path(path).parent_path();
        for (const Layer& layer : readBundle(path).layers)
            if (layer.params.contains("files") && layer.params["files"].is_array())
                for (const nlohmann::json& name : layer.params["files"])
                    if (name.is_string() && std::filesystem::path(name.get<std::string>()).filename() == name.get<std::string>())
                        files.push_back((folder / name.get<std::string>()).string());
    } catch (const Error&) {
        // Not a bundle we can read: nothing of it to clean up.
    }
    return files;
}

std::string fileName(const std::string& path) { return std::filesystem::path(path).filename().string(); }

} // namespace

BakeSurface bakeSurface(const BakeOptions& options) {
    checkOptions(options);
    const int size = options.resolution;
    BakeSurface surface;
    TriMesh& mesh = surface.mesh;
    mesh = readMeshWithNormals(options.input, "low");
    if (options.uvSet > 0) mesh.texcoords = readTexcoordSet(options.input, options.uvSet);
    bool generated = mesh.texcoords.empty();
    nlohmann::json& atlasRecord = surface.atlasRecord;
    atlasRecord = {{"generated", generated}, {"source_uv_set", options.uvSet}};
    if (generated) {
        AtlasOptions atlasOptions;
        atlasOptions.width = atlasOptions.height = size;
        atlasOptions.padding = options.padding;
        GeneratedAtlas atlas = generateAtlas(mesh, atlasOptions);
        mesh = std::move(atlas.mesh);
        logWarn("bake: " + options.input + " has no UVs: GENERATED a lightmap atlas of " +
                std::to_string(atlas.charts) + " charts (" + std::to_string(options.padding) + " texels padding, " +
                std::to_string(atlas.texelsPerUnit) + " texels per unit); the bundle's TEXCOORD_0 is that atlas");
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
    if (count == 0) throw Error(options.input, "texcoords", "cover no texel of the atlas");
    if (samples.overlappingTexels > 0)
        logWarn("bake: " + std::to_string(samples.overlappingTexels) +
                " texels lie under overlapping UV triangles; the lowest triangle keeps each");
    std::vector<float>& positions = surface.positions;
    std::vector<float>& normals = surface.normals;
    texelSurface(mesh, samples, positions, normals);

    surface.detailNormals = normals;
    if (!options.high.empty()) {
        TriMesh& high = surface.high;
        high = readMeshWithNormals(options.high, "high");
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
        surface.highRecord = {{"mesh", fileName(options.high)}, {"hash", hashFile(options.high)},
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
    const TriMesh& geometry = options.high.empty() ? surface.mesh : surface.high;
    TexelTransferRows result;
    result.begin = begin;
    result.end = end;
    BakeStats& stats = result.stats;
    stats.texels = end - begin;

    // Transfer per texel: the per-vertex integrator with texels as receivers.
    std::vector<float> albedo = sampleAlbedo(surface.mesh, samples, options.albedoOverride);
    std::vector<uint64_t> keys(samples.texel.begin() + begin, samples.texel.begin() + end); // rotations follow texels
    Receivers receivers;
    receivers.positions = surface.positions.data() + 3 * begin;
    receivers.normals = surface.normals.data() + 3 * begin;
    receivers.albedo = albedo.empty() ? nullptr : albedo.data() + 3 * begin;
    receivers.keys = keys.data();
    receivers.count = end - begin;
    TransferOptions transferOptions = texelTransferOptions(options);
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
    result.rayOffset = transfer.stats.rayOffset;
    return result;
}

BakedAtlas finishBake(BakeSurface surface, const BakeOptions& options, std::vector<float> rows, float rayOffset,
                      BakeStats stats) {
    const int size = options.resolution;
    const int channels = 3 * options.order * options.order;
    BakedAtlas baked;
    baked.mesh = std::move(surface.mesh);
    baked.samples = std::move(surface.samples);
    const TriMesh& mesh = baked.mesh;
    const TexelSamples& samples = baked.samples;
    const size_t count = samples.texel.size();
    if (rows.size() != count * channels)
        throw Error("", "bake", "finishing needs the rows of all " + std::to_string(count) + " covered texels",
                    kExitFailure);
    stats.texels = count;

    // Atlas images: fill the gutters, then make seams agree (lookups on chart borders read the gutters).
    baked.transfer = scatter(samples, rows.data(), channels);
    rows = {};
    std::vector<uint8_t> covered = coverageMask(samples);
    double fillStart = nowSeconds();
    if (options.dilateOnly)
        dilateOneRing(baked.transfer.data(), size, size, channels, covered.data());
    else
        pushPull(baked.transfer.data(), size, size, channels, covered.data());
    stats.fillSeconds = nowSeconds() - fillStart;
    std::vector<SeamEdge> seams = findSeams(mesh);
    stats.seamEdges = seams.size();
    if (options.seamStitch)
        stats.stitchedTexels = stitchSeams(mesh, seams, size, size, baked.transfer.data(), channels);

    std::vector<float> tangentNormals =
        tangentSpaceNormals(mesh, vertexTangents(mesh), samples, surface.detailNormals);
    baked.normals = scatter(samples, tangentNormals.data(), 3);
    pushPull(baked.normals.data(), size, size, 3, covered.data());
    for (size_t t = 0; t < baked.normals.size() / 3; ++t) {
        float* n = &baked.normals[3 * t];
        double length = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
        if (length > 1e-6)
            for (int a = 0; a < 3; ++a) n[a] = float(n[a] / length);
        else
            n[0] = n[1] = 0.0f, n[2] = 1.0f; // far from every chart: flat
    }

    baked.params = {{"width", size},
                    {"height", size},
                    {"uv_set", 0},
                    {"atlas", surface.atlasRecord},
                    {"order", options.order},
                    {"mode", transferModeName(texelTransferOptions(options).mode)},
                    {"samples", options.samples},
                    {"bounces", options.bounces},
                    {"albedo", mesh.albedo.empty() || options.albedoOverride
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
    return finishBake(std::move(surface), options, std::move(rows.rows), rows.rayOffset, rows.stats);
}

namespace {

void reportBakeCost(double start, const BakeStats& stats) {
    StageCost cost;
    cost.stage = "bake";
    cost.seconds = nowSeconds() - start;
    cost.rays = stats.rays + stats.cageRays;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

// One shard: the transfer of its range of covered texels, written as a texel_range bundle.
void runBakeShard(const BakeOptions& options, double start) {
    BakeSurface surface = bakeSurface(options);
    RowRange range = shardRows(surface.samples.texel.size(), options.shardIndex, options.shardCount);
    TexelTransferRows rows = bakeTexelTransfer(surface, options, range.begin, range.end);
    writeTexelShard(options, surface, rows);
    logInfo("bake: wrote shard " + std::to_string(options.shardIndex) + "/" + std::to_string(options.shardCount) +
            " (covered texels " + std::to_string(range.begin) + ".." + std::to_string(range.end) + ") to " +
            options.output);
    reportBakeCost(start, rows.stats);
}

// The merge: every shard's rows joined, then the unsharded bake's finishing.
BakedAtlas bakeFromShards(const BakeOptions& options) {
    BakeSurface surface = bakeSurface(options);
    float rayOffset = 0.0f;
    std::vector<float> rows = joinTexelShards(options, surface, rayOffset);
    BakeStats stats;
    stats.cageRays = surface.cageRays;
    logInfo("bake: joined " + std::to_string(options.shardFiles.size()) + " shards");
    return finishBake(std::move(surface), options, std::move(rows), rayOffset, stats);
}

} // namespace

void runBake(const BakeOptions& options) {
    double start = nowSeconds();
    if (fileExtension(options.output) != "glb") throw usage("-o", "the output bundle must end in .glb");
    if (options.shardCount < 1 || options.shardIndex < 0 || options.shardIndex >= options.shardCount)
        throw usage("--shard", std::to_string(options.shardIndex) + "/" + std::to_string(options.shardCount) +
                                   " is not I/N with 0 <= I < N");
    if (options.shardCount > 1 && !options.shardFiles.empty())
        throw usage("--merge", "joins the shards of a bake; it does not go with --shard");
    if (options.shardCount > 1) return runBakeShard(options, start);
    BakedAtlas baked = options.shardFiles.empty() ? bakeAtlas(options) : bakeFromShards(options);
    const BakeStats& stats = baked.stats;
    const int size = options.resolution;
    const int coefficients = options.order * options.order;
    const int channels = 3 * coefficients;
    const size_t texelCount = size_t(size) * size;

    // Textures first, the bundle that references them last.
    std::string base = options.output.substr(0, options.output.size() - 4);
    WrittenFiles written;
    written.previous = bundleTextures(options.output);
    Layer layer;
    layer.name = "texel_transfer";
    layer.domain = "texel";
    layer.semantic = "sh_transfer_rgb";
    layer.shape = {texelCount, uint64_t(coefficients), 3};
    layer.params = baked.params;
    layer.params["format"] = texelFormatName(options.format);
    uint64_t storedBytes = 0;
    std::string transferPath;
    if (options.format == TexelFormat::Bundle) {
        // The rows in the bundle's own buffer: the thin runtime (texelRelightModel) and the viewer read them.
        layer.data = baked.transfer;
        storedBytes = layer.data.size() * sizeof(float);
    } else {
        if (options.format == TexelFormat::U8) {
            RangeCompressed compressed = rangeCompress(baked.transfer.data(), texelCount, coefficients, 3);
            nlohmann::json layers = nlohmann::json::array();
            std::vector<uint8_t> plane(texelCount * 3);
            for (int j = 0; j < coefficients; ++j) {
                for (size_t t = 0; t < texelCount; ++t)
                    for (int c = 0; c < 3; ++c) plane[3 * t + c] = compressed.values[t * channels + 3 * j + c];
                char kind[32];
                std::snprintf(kind, sizeof kind, "transfer.T%03d", j);
                std::string path = writeContentAddressed(base, kind, "png", written, [&](const std::string& tmp) {
                    writeImagePixels(tmp, size, size, {"R", "G", "B"}, plane.data());
                });
                storedBytes += std::filesystem::file_size(path);
                layers.push_back({{"coefficient", j}, {"uri", fileName(path)}, {"hash", hashFile(path)},
                                  {"min", compressed.range[2 * j]}, {"max", compressed.range[2 * j + 1]}});
            }
            nlohmann::json sidecar = {{"format", "prt-texel-u8"}, {"version", 1}, {"width", size}, {"height", size},
                                      {"order", options.order},
                                      {"decode", "value = min + q * (max - min) / 255, per coefficient layer"},
                                      {"layers", layers}};
            transferPath = writeContentAddressed(base, "transfer", "json", written, [&](const std::string& tmp) {
                writeBytesAtomic(tmp, sidecar.dump(2) + "\n");
            });
        } else {
            transferPath = writeContentAddressed(base, "transfer", "exr", written, [&](const std::string& tmp) {
                writeCoefficientExr(tmp, baked.transfer.data(), size, size, coefficients, options.format == TexelFormat::Half);
            });
            layer.params["channels"] = "T{j:03d}.{R,G,B} for coefficient j";
        }
        storedBytes += std::filesystem::file_size(transferPath);
        layer.params["files"] = nlohmann::json::array();
        for (const std::string& path : written.paths) layer.params["files"].push_back(fileName(path));
        layer.params["uri"] = fileName(transferPath);
        layer.params["hash"] = hashFile(transferPath);
    }

    std::vector<uint8_t> normalBytes(baked.normals.size());
    for (size_t i = 0; i < normalBytes.size(); ++i)
        normalBytes[i] = uint8_t(std::lround(std::clamp((double(baked.normals[i]) + 1.0) * 127.5, 0.0, 255.0)));
    std::string normalPath = writeContentAddressed(base, "normal", "png", written, [&](const std::string& tmp) {
        writeImagePixels(tmp, size, size, {"R", "G", "B"}, normalBytes.data());
    });
    Layer normalLayer;
    normalLayer.name = "normal_map";
    normalLayer.domain = "texel";
    normalLayer.semantic = "tangent_normal";
    normalLayer.shape = {texelCount, 3};
    normalLayer.params = {{"uri", fileName(normalPath)},
                          {"files", {fileName(normalPath)}},
                          {"hash", hashFile(normalPath)},
                          {"width", size},
                          {"height", size},
                          {"uv_set", 0},
                          {"encoding", "rgb8 = round((n + 1) * 127.5)"},
                          {"frame", "x along +u, y along -v (image up), z the interpolated vertex normal"},
                          {"source", options.high.empty() ? "low mesh normals" : "high mesh normals"}};

    Bundle bundle;
    bundle.mesh = std::move(baked.mesh);
    bundle.layers.push_back(std::move(layer));
    bundle.layers.push_back(std::move(normalLayer));
    bundle.producer = {{"tool", "prt"}, {"version", options.toolVersion}, {"stage", "bake"}};
    bundle.inputs = {{"mesh", hashFile(options.input)}};
    if (!options.high.empty()) bundle.inputs["high"] = hashFile(options.high);
    bundle.convention = conventionRecord();
    writeBundle(options.output, bundle); // atomic: on failure neither it nor (below) the textures remain
    written.committed = true;

    double texelsPerSecond = stats.transferSeconds > 0.0 ? stats.texels / stats.transferSeconds : 0.0;
    double raysPerSecond = stats.directSeconds > 0.0 ? stats.rays / stats.directSeconds : 0.0;
    logInfo("bake: wrote " + options.output + " and " + std::to_string(written.paths.size()) + " texture files (" +
            std::to_string(storedBytes) + " bytes of " + texelFormatName(options.format) + " coefficients); " +
            std::to_string(texelsPerSecond) + " texels/s, " + std::to_string(raysPerSecond / 1e6) +
            " Mrays/s, fill " + std::to_string(stats.fillSeconds) + " s, " + std::to_string(stats.seamEdges) +
            " seam edges, " + std::to_string(stats.stitchedTexels) + " texels stitched");
    bool yardstick = options.yardstick && options.shardFiles.empty(); // a merge casts no transfer rays
    if (yardstick)
        logInfo("bake: bare Embree over the same rays: " + std::to_string(stats.bareRaysPerSecond / 1e6) +
                " Mrays/s; the bake reached " + std::to_string(raysPerSecond / stats.bareRaysPerSecond) + " of it");
    nlohmann::json record = {{"texels", stats.texels},
                             {"texels_per_second", texelsPerSecond},
                             {"rays", stats.rays},
                             {"rays_per_second", raysPerSecond},
                             {"transfer_seconds", stats.transferSeconds},
                             {"fill_seconds", stats.fillSeconds},
                             {"seam_edges", stats.seamEdges},
                             {"stitched_texels", stats.stitchedTexels},
                             {"stored_bytes", storedBytes}};
    if (yardstick) record["bare_rays_per_second"] = stats.bareRaysPerSecond;
    logEvent("bake_stats", record.dump());

    reportBakeCost(start, stats);
}

} // namespace prt
