// Texel-range shards of the bake: what a shard records so that a merge can check it belongs, writing one, and
// joining all of them back into the transfer rows of every covered texel (docs/bundle.md "texel_range").
#include "bake.h"

#include "bundle_stream.h"
#include "core.h"
#include "json_input.h"

#include <limits>
#include <string>

namespace prt {

namespace {

const char* const kShardLayer = "texel_transfer";
const char* const kShardBounceLayer = "texel_transfer_bounce";

// A shard's params member as text for messages ("(none)" when absent).
std::string memberText(const nlohmann::json& params, const std::string& key) {
    return params.contains(key) ? jsonExcerpt(params[key]) : "(none)";
}

uint64_t rowParam(const nlohmann::json& params, const char* key, const std::string& file) {
    return uint64_t(jsonInteger(params, key, file, std::string("layer ") + kShardLayer + ", params", 0,
                                std::numeric_limits<int64_t>::max()));
}

} // namespace

nlohmann::json texelShardIdentity(const BakeOptions& options, const BakeSurface& surface) {
    nlohmann::json inputs = {{"mesh", hashFile(options.input)}};
    if (!options.high.empty()) inputs["high"] = hashFile(options.high);
    return {{"width", surface.samples.width},
            {"height", surface.samples.height},
            {"texel_count", surface.samples.texel.size()},
            {"uv_set", options.uvSet},
            {"generate_atlas", options.generateAtlas},
            {"wrap", options.wrap == UvWrap::Repeat ? "repeat" : "none"},
            {"allow_overlap", options.allowOverlap},
            {"padding", options.padding},
            {"high_position", options.highPosition},
            {"cage", options.cage},
            {"order", options.order},
            {"samples", options.samples},
            {"bounces", options.bounces},
            {"albedo", options.albedo},
            {"albedo_override", options.albedoOverride},
            {"seed", options.seed},
            {"inputs", inputs}};
}

void writeTexelShard(const BakeOptions& options, const BakeSurface& surface, const TexelTransferRows& rows) {
    Layer layer;
    layer.name = kShardLayer;
    layer.domain = "texel_range";
    layer.semantic = "sh_transfer_rgb";
    layer.shape = {uint64_t(rows.end - rows.begin), uint64_t(options.order) * options.order, 3};
    layer.data = rows.rows;
    layer.params = texelShardIdentity(options, surface);
    layer.params["shard"] = {options.shardIndex, options.shardCount};
    layer.params["row_begin"] = rows.begin;
    layer.params["row_end"] = rows.end;
    layer.params["ray_offset"] = rows.rayOffset;

    Bundle bundle;
    bundle.mesh = surface.mesh;
    bundle.inputs = layer.params["inputs"];
    Layer bounce;
    bounce.name = kShardBounceLayer;
    bounce.domain = "texel_range";
    bounce.semantic = "sh_transfer_bounce_rgb";
    bounce.shape = layer.shape;
    bounce.data = rows.bounce;
    bounce.params = {{"row_begin", rows.begin}, {"row_end", rows.end}};
    bundle.layers.push_back(std::move(layer));
    if (!rows.bounce.empty()) bundle.layers.push_back(std::move(bounce));
    bundle.producer = {{"tool", "prt"}, {"version", options.toolVersion}, {"stage", "bake"}};
    bundle.convention = conventionRecord();
    writeBundle(options.output, bundle);
}

// Streams: each shard's header is read once (readBundleHeader, its checksum checked, its mesh dropped), and once
// every shard is placed its rows are read by ranges straight into the joined arrays (readLayerFloats), so besides
// them it holds one shard's mesh at a time and every shard's layer descriptions.
std::vector<float> joinTexelShards(const BakeOptions& options, const BakeSurface& surface, float& rayOffset,
                                   std::vector<float>& bounce) {
    const std::vector<std::string>& files = options.shardFiles;
    std::vector<BundleHeader> shards;
    std::vector<const Layer*> layers;
    shards.reserve(files.size());
    for (const std::string& file : files) {
        shards.push_back(readBundleHeader(file));
        shards.back().bundle.mesh = {};
        shards.back().bundle.objects.clear();
        shards.back().bundle.asset.reset();
        const Layer* layer = findLayer(shards.back().bundle, kShardLayer);
        if (!layer || layer->domain != "texel_range")
            throw Error(file, "", std::string("not a bake shard: no '") + kShardLayer +
                                      "' layer of domain texel_range (`prt bake --shard I/N` writes them)",
                        kExitInput);
        layers.push_back(layer);
    }
    std::vector<size_t> order = orderShards(layers, files);

    // Every shard must come from this bake: the same inputs, atlas and transfer options, hence the same rows.
    const nlohmann::json identity = texelShardIdentity(options, surface);
    for (size_t s = 0; s < files.size(); ++s)
        for (const auto& [key, value] : identity.items())
            if (!layers[s]->params.contains(key) || layers[s]->params[key] != value)
                throw Error(files[s], std::string("layer ") + kShardLayer + ", params." + key,
                            "is " + memberText(layers[s]->params, key) + ", but this bake has " + jsonExcerpt(value) +
                                ": the shard belongs to another bake (other inputs or options)",
                            kExitInput);

    // A shard layer's index in its bundle, once its rows are checked to be `count` floats in the file.
    auto rowsOf = [&](const BundleHeader& shard, const Layer& layer, uint64_t count) {
        size_t index = size_t(&layer - shard.bundle.layers.data());
        uint64_t bytes = layer.componentType == "float32" ? 4 : layer.componentType == "float16" ? 2 : 0;
        return bytes != 0 && shard.extents[index].byteLength == count * bytes ? index : shard.bundle.layers.size();
    };
    const size_t texels = surface.samples.texel.size();
    const size_t rowWidth = size_t(3) * options.order * options.order;
    std::vector<float> rows(checkedProduct({texels, rowWidth}, "texel transfer values", files[0], kShardLayer));
    bounce.assign(options.bounces > 0 ? rows.size() : 0, 0.0f);
    uint64_t next = 0;
    for (size_t index = 0; index < order.size(); ++index) {
        const BundleHeader& shard = shards[order[index]];
        const std::string& file = files[order[index]];
        const Layer& layer = *layers[order[index]];
        uint64_t begin = rowParam(layer.params, "row_begin", file), end = rowParam(layer.params, "row_end", file);
        if (begin != next || end < begin || end > texels)
            throw Error(file, std::string("layer ") + kShardLayer,
                        "covered texels [" + std::to_string(begin) + ", " + std::to_string(end) + ") of shard " +
                            std::to_string(index) + " overlap or leave a gap: shard " + std::to_string(index) +
                            " must start at texel " + std::to_string(next) + " and end by " +
                            std::to_string(texels),
                        kExitInput);
        const uint64_t count = (end - begin) * rowWidth;
        size_t rowsIndex = rowsOf(shard, layer, count);
        if (layer.shape.size() != 3 || layer.shape[0] != end - begin || layer.shape[1] * layer.shape[2] != rowWidth ||
            rowsIndex == shard.bundle.layers.size())
            throw Error(file, std::string("layer ") + kShardLayer,
                        "holds no [" + std::to_string(end - begin) + ", " + std::to_string(rowWidth / 3) +
                            ", 3] rows for its range",
                        kExitInput);
        float offset = layer.params.contains("ray_offset")
                           ? jsonFloat(layer.params, "ray_offset", file, std::string("layer ") + kShardLayer + ", params")
                           : 0.0f;
        if (index > 0 && offset != rayOffset)
            throw Error(file, std::string("layer ") + kShardLayer + ", params.ray_offset",
                        "differs from shard 0's: the shards traced other geometry", kExitInput);
        rayOffset = offset;
        readLayerFloats(shard, rowsIndex, rows.data() + begin * rowWidth);
        if (options.bounces > 0) {
            const Layer* bounceLayer = findLayer(shard.bundle, kShardBounceLayer);
            size_t bounceIndex = bounceLayer ? rowsOf(shard, *bounceLayer, count) : shard.bundle.layers.size();
            if (!bounceLayer || bounceLayer->domain != "texel_range" || bounceLayer->shape != layer.shape ||
                bounceIndex == shard.bundle.layers.size())
                throw Error(file, std::string("layer ") + kShardBounceLayer,
                            "is missing or not shaped like the shard's transfer rows (a bake with bounces keeps "
                            "their part apart)",
                            kExitInput);
            readLayerFloats(shard, bounceIndex, bounce.data() + begin * rowWidth);
        }
        next = end;
    }
    if (next != texels)
        throw Error(files[order.back()], std::string("layer ") + kShardLayer,
                    "the shards end at covered texel " + std::to_string(next) + " of " + std::to_string(texels) +
                        ": a shard is missing",
                    kExitInput);
    return rows;
}

} // namespace prt
