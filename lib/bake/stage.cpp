// The `prt bake` stage: bake (or join shards and finish as the unsharded bake does), then write the textures and
// last the bundle that references them, so that a failure leaves the previous result whole.
#include "bake.h"

#include "core.h"
#include "image.h"
#include "runtime.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>

namespace prt {

namespace {

Error usage(const std::string& flag, const std::string& problem) { return Error("", flag, problem, kExitUsage); }

// The textures of one bake. Each is named by its content (NAME.KIND.<16 hex>.EXT, isBakeTextureName), so a new
// bake never overwrites a file the previous bundle references: until the new bundle replaces it, the last good
// result stays whole, and a failure removes only the files this bake created. Once committed, the files in the
// folder with this bundle's texture names that the new bundle does not use and that were last written before this
// bake began are removed: the previous bundle's, and what a bake killed between its textures and its bundle left.
// Newer ones may be a concurrent bake's of the same output, still under way; files of any other name are never
// touched, whatever a bundle found at the output path lists.
struct WrittenFiles {
    std::string output;                    // NAME.glb
    std::filesystem::file_time_type began; // when this bake began
    std::vector<std::string> paths;        // every texture the new bundle references
    std::vector<std::string> created;      // those that did not exist before
    bool committed = false;
    ~WrittenFiles() {
        if (!committed) {
            for (const std::string& path : created) std::remove(path.c_str());
            return;
        }
        const std::filesystem::path out(output);
        const std::filesystem::path folder = out.parent_path().empty() ? std::filesystem::path(".") : out.parent_path();
        const std::string stem = out.stem().string();
        std::error_code error;
        for (const auto& item : std::filesystem::directory_iterator(folder, error)) {
            const std::string name = item.path().filename().string();
            const std::string path = (out.parent_path() / name).string();
            if (!isBakeTextureName(name, stem) ||
                std::find(paths.begin(), paths.end(), path) != paths.end())
                continue;
            std::error_code timeError;
            const auto written = std::filesystem::last_write_time(item.path(), timeError);
            if (!timeError && written < began) std::filesystem::remove(item.path(), timeError);
        }
    }
};

// Writes a texture through `write` (into a hidden temporary file with the right extension, which the writer needs)
// and moves it to BASE.KIND.<first 16 hex digits of its content hash>.EXTENSION; returns that path.
std::string writeContentAddressed(const std::string& base, const std::string& kind, const std::string& extension,
                                  WrittenFiles& written, const std::function<void(const std::string&)>& write) {
    // .BASE.KIND.EXT.tmp-HOST-PID-N-R.EXT: the next bake on this host removes it if this one is killed.
    std::string tmp = freshTemporaryPath(base + "." + kind + "." + extension, "." + extension);
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

std::string fileName(const std::string& path) { return std::filesystem::path(path).filename().string(); }

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
    std::vector<float> bounce;
    std::vector<float> rows = joinTexelShards(options, surface, rayOffset, bounce);
    BakeStats stats;
    stats.cageRays = surface.cageRays;
    logInfo("bake: joined " + std::to_string(options.shardFiles.size()) + " shards");
    return finishBake(std::move(surface), options, std::move(rows), std::move(bounce), rayOffset, stats);
}


// A coefficient atlas ([texels][order^2][3]) as layer `name`: inline rows (format bundle), one OpenEXR, or 8-bit
// PNG layers with a JSON sidecar; its files are named BASE.KIND.<hash>.EXT and listed in params.files.
Layer coefficientLayer(const std::string& name, const std::string& semantic, const std::string& kind,
                       const std::vector<float>& atlas, const nlohmann::json& params, const BakeOptions& options,
                       const std::string& base, WrittenFiles& written, uint64_t& storedBytes) {
    const int size = options.resolution;
    const int coefficients = options.order * options.order, channels = 3 * coefficients;
    const size_t texelCount = size_t(size) * size;
    Layer layer;
    layer.name = name;
    layer.domain = "texel";
    layer.semantic = semantic;
    layer.shape = {texelCount, uint64_t(coefficients), 3};
    layer.params = params;
    layer.params["format"] = texelFormatName(options.format);
    if (options.format == TexelFormat::Bundle) {
        // The rows in the bundle's own buffer: the thin runtime (texelRelightModel) and the viewer read them.
        layer.data = atlas;
        storedBytes += layer.data.size() * sizeof(float);
        return layer;
    }
    const size_t firstFile = written.paths.size();
    std::string path;
    if (options.format == TexelFormat::U8) {
        RangeCompressed compressed = rangeCompress(atlas.data(), texelCount, coefficients, 3);
        nlohmann::json layers = nlohmann::json::array();
        std::vector<uint8_t> plane(texelCount * 3);
        for (int j = 0; j < coefficients; ++j) {
            for (size_t t = 0; t < texelCount; ++t)
                for (int c = 0; c < 3; ++c) plane[3 * t + c] = compressed.values[t * channels + 3 * j + c];
            char coefficientKind[48];
            std::snprintf(coefficientKind, sizeof coefficientKind, "%s.T%03d", kind.c_str(), j);
            std::string png = writeContentAddressed(base, coefficientKind, "png", written, [&](const std::string& tmp) {
                writeImagePixels(tmp, size, size, {"R", "G", "B"}, plane.data());
            });
            storedBytes += std::filesystem::file_size(png);
            layers.push_back({{"coefficient", j}, {"uri", fileName(png)}, {"hash", hashFile(png)},
                              {"min", compressed.range[2 * j]}, {"max", compressed.range[2 * j + 1]}});
        }
        nlohmann::json sidecar = {{"format", "prt-texel-u8"}, {"version", 1}, {"width", size}, {"height", size},
                                  {"order", options.order},
                                  {"decode", "value = min + q * (max - min) / 255, per coefficient layer"},
                                  {"layers", layers}};
        path = writeContentAddressed(base, kind, "json", written, [&](const std::string& tmp) {
            writeBytesAtomic(tmp, sidecar.dump(2) + "\n");
        });
    } else {
        path = writeContentAddressed(base, kind, "exr", written, [&](const std::string& tmp) {
            writeCoefficientExr(tmp, atlas.data(), size, size, coefficients, options.format == TexelFormat::Half);
        });
        layer.params["channels"] = "T{j:03d}.{R,G,B} for coefficient j";
    }
    storedBytes += std::filesystem::file_size(path);
    layer.params["files"] = nlohmann::json::array();
    for (size_t i = firstFile; i < written.paths.size(); ++i) layer.params["files"].push_back(fileName(written.paths[i]));
    layer.params["uri"] = fileName(path);
    layer.params["hash"] = hashFile(path);
    return layer;
}

// The "texel_surface" layer: inline (format bundle) or one float OpenEXR with kTexelSurfaceChannelNames.
Layer texelSurfaceLayer(const std::vector<float>& atlas, int size, const BakeOptions& options, const std::string& base,
                        WrittenFiles& written, uint64_t& storedBytes) {
    Layer layer;
    layer.name = "texel_surface";
    layer.domain = "texel";
    layer.semantic = "texel_surface";
    layer.shape = {uint64_t(size) * size, uint64_t(kTexelSurfaceChannels)};
    layer.params = {{"width", size},
                    {"height", size},
                    {"channels", std::vector<std::string>(kTexelSurfaceChannelNames,
                                                          kTexelSurfaceChannelNames + kTexelSurfaceChannels)},
                    {"frame", "object space; N unit; albedo linear RGB"},
                    {"coverage", "1 for covered texels, 0 in gutters (whose other channels push-pull fills)"},
                    {"source", options.high.empty() || !options.highPosition ? "low mesh" : "high mesh"}};
    if (options.format == TexelFormat::Bundle) {
        layer.data = atlas;
        storedBytes += atlas.size() * sizeof(float);
        return layer;
    }
    std::string path = writeContentAddressed(base, "surface", "exr", written, [&](const std::string& tmp) {
        writeImagePixels(tmp, size, size,
                         std::vector<std::string>(kTexelSurfaceChannelNames,
                                                  kTexelSurfaceChannelNames + kTexelSurfaceChannels),
                         atlas.data(), PixelStorage::Float);
    });
    storedBytes += std::filesystem::file_size(path);
    layer.params["files"] = {fileName(path)};
    layer.params["uri"] = fileName(path);
    layer.params["hash"] = hashFile(path);
    return layer;
}

} // namespace

void runBake(const BakeOptions& options) {
    double start = nowSeconds();
    const std::filesystem::file_time_type began = std::filesystem::file_time_type::clock::now();
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
    const size_t texelCount = size_t(size) * size;

    // Textures first, the bundle that references them last.
    std::string base = options.output.substr(0, options.output.size() - 4);
    WrittenFiles written;
    written.output = options.output;
    written.began = began;
    uint64_t storedBytes = 0;
    Layer layer = coefficientLayer("texel_transfer", "sh_transfer_rgb", "transfer", baked.transfer, baked.params,
                                   options, base, written, storedBytes);
    Layer bounceLayer;
    if (!baked.bounce.empty()) {
        nlohmann::json params = {{"width", size}, {"height", size}, {"order", options.order},
                                 {"part", "texel_transfer minus its direct (shadowed) pass: bounces 1..B"}};
        bounceLayer = coefficientLayer("texel_transfer_bounce", "sh_transfer_bounce_rgb", "bounce", baked.bounce,
                                       params, options, base, written, storedBytes);
    }
    const uint64_t coefficientBytes = storedBytes; // the transfer and, with bounces, its bounce part
    Layer surfaceLayer = texelSurfaceLayer(baked.surface, size, options, base, written, storedBytes);

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
                          {"uv_set", baked.scene ? nlohmann::json("lightmap_uv") : nlohmann::json(0)},
                          {"encoding", "rgb8 = round((n + 1) * 127.5)"},
                          {"frame", "x along +u, y along -v (image up), z the interpolated vertex normal"},
                          {"source", options.high.empty() ? "low mesh normals" : "high mesh normals"}};

    // A scene keeps its asset and its own rows; the atlas, whose generated charts split vertices, is a corner layer.
    Bundle bundle;
    if (baked.scene) {
        bundle = *baked.scene;
        bundle.layers.push_back(lightmapUvLayer(baked.mesh));
    } else {
        bundle.mesh = std::move(baked.mesh);
    }
    bundle.layers.push_back(std::move(layer));
    if (!baked.bounce.empty()) bundle.layers.push_back(std::move(bounceLayer));
    bundle.layers.push_back(std::move(surfaceLayer));
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
            std::to_string(coefficientBytes) + " bytes of " + texelFormatName(options.format) + " coefficients, " +
            std::to_string(storedBytes - coefficientBytes) + " of surface); " +
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
                             {"stored_bytes", storedBytes},
                             {"coefficient_bytes", coefficientBytes}};
    if (yardstick) record["bare_rays_per_second"] = stats.bareRaysPerSecond;
    logEvent("bake_stats", record.dump());

    reportBakeCost(start, stats);
}

} // namespace prt
