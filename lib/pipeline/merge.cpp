// Joins shard bundles (contiguous vertex ranges of one stage run) into the bundle the unsharded run writes.
#include "pipeline.h"

#include "core.h"

#include <algorithm>
#include <functional>
#include <map>
#include <numeric>

namespace prt {

namespace {

// Shard bookkeeping, absent from the unsharded layer.
const char* const kShardParams[] = {"shard", "row_begin", "row_end", "vertex_count"};
// Per-shard counts that the unsharded layer holds as totals.
const char* const kCounterParams[] = {"rays", "back_face_hits"};

nlohmann::json withoutShardParams(nlohmann::json params) {
    for (const char* key : kShardParams) params.erase(key);
    for (const char* key : kCounterParams) params.erase(key);
    return params;
}

uint64_t rowParam(const Layer& layer, const char* key, const std::string& file) {
    const nlohmann::json& value = layer.params.contains(key) ? layer.params[key] : nlohmann::json();
    if (!value.is_number() || value.get<double>() < 0)
        throw Error(file, "layer " + layer.name, std::string("shard layer has no valid '") + key + "'");
    return uint64_t(value.get<double>());
}

} // namespace

namespace {

// One shard's rows of one sharded layer, moved out of the shard bundle, with the layer's description.
struct LayerPart {
    Layer meta; // the layer without its data
    std::vector<float> data;
};

Layer describe(const Layer& layer) {
    Layer meta;
    meta.name = layer.name;
    meta.domain = layer.domain;
    meta.semantic = layer.semantic;
    meta.shape = layer.shape;
    meta.componentType = layer.componentType;
    meta.object = layer.object;
    meta.params = layer.params;
    return meta;
}

// Joins shards that `load(s)` gives one at a time (s in 0..count-1, each loaded once, in order), so that at most
// one shard bundle besides the first is held at once: the others' meshes and whole layers are compared with the
// first's and dropped, their sharded rows kept until they are joined.
Bundle mergeShardsFrom(size_t count, const std::function<Bundle(size_t)>& load, const std::vector<std::string>& files) {
    if (count == 0 || count != files.size()) throw Error("", "merge", "no shards to merge", kExitUsage);
    Bundle merged = load(0);
    const Bundle& first = merged;
    std::vector<Layer> keyLayers(count); // each shard's layer named as the first's first layer, without data
    std::vector<bool> hasKey(count, false);
    std::map<std::string, std::vector<LayerPart>> parts; // by layer name, in load order
    // Moves shard s's rows of every layer the first shard holds sharded into `parts`; keeps descriptions.
    auto stash = [&](Bundle& shard, size_t s) {
        if (!first.layers.empty())
            if (const Layer* key = findLayer(shard, first.layers[0].name)) {
                keyLayers[s] = describe(*key);
                hasKey[s] = true;
            }
        for (const Layer& layer : first.layers) {
            if (layer.domain != "vertex_range") continue;
            LayerPart piece;
            if (Layer* part = const_cast<Layer*>(findLayer(shard, layer.name))) {
                piece.meta = describe(*part);
                piece.data = std::move(part->data);
                part->data = {};
            } else {
                piece.meta.name = ""; // missing: reported when the layer is joined
            }
            parts[layer.name].push_back(std::move(piece));
        }
    };
    stash(merged, 0);
    for (size_t s = 1; s < count; ++s) {
        Bundle other = load(s);
        const TriMesh &a = first.mesh, &b = other.mesh;
        if (a.positions != b.positions || a.indices != b.indices || a.normals != b.normals ||
            a.texcoords != b.texcoords || a.albedo != b.albedo)
            throw Error(files[s], "mesh", "differs from the mesh of " + files[0] + ": shards of different inputs", kExitInput);
        if (other.inputs != first.inputs || other.producer != first.producer || other.convention != first.convention)
            throw Error(files[s], "", "was produced from other inputs or by another producer than " + files[0], kExitInput);
        if (other.layers.size() != first.layers.size())
            throw Error(files[s], "", "has " + std::to_string(other.layers.size()) + " layers, " + files[0] + " has " +
                                          std::to_string(first.layers.size()), kExitInput);
        for (const Layer& layer : first.layers) {
            const Layer* same = findLayer(other, layer.name);
            if (layer.domain != "vertex_range" &&
                (!same || same->domain != layer.domain || same->params != layer.params || same->data != layer.data))
                throw Error(files[s], "layer " + layer.name, "differs from " + files[0] + "'s, but is not sharded",
                            kExitInput);
        }
        stash(other, s);
    }
    std::vector<const Layer*> sharded(count);
    for (size_t s = 0; s < count; ++s) sharded[s] = hasKey[s] ? &keyLayers[s] : nullptr;
    std::vector<size_t> order = orderShards(sharded, files);
    for (const Layer& layer : first.layers)
        if (layer.domain == "texel_range")
            throw Error(files[0], "layer " + layer.name,
                        "is a bake shard: its merge redoes the bake's finishing, so run `prt bake MESH -o OUT.glb "
                        "--merge SHARD...` with the shards' options instead",
                        kExitUsage);

    for (Layer& layer : merged.layers) {
        if (layer.domain != "vertex_range") continue; // layers every shard holds whole are kept as they are
        uint64_t vertices = rowParam(layer, "vertex_count", files[0]);
        if (vertices != first.mesh.vertexCount())
            throw Error(files[0], "layer " + layer.name, "vertex_count " + std::to_string(vertices) +
                                                             " does not match the mesh's " +
                                                             std::to_string(first.mesh.vertexCount()) + " vertices", kExitInput);
        uint64_t rowWidth = std::accumulate(layer.shape.begin() + 1, layer.shape.end(), uint64_t(1), std::multiplies<>());
        nlohmann::json common = withoutShardParams(layer.params);
        std::vector<float> data;
        data.reserve(vertices * rowWidth);
        nlohmann::json counters = nlohmann::json::object();
        uint64_t nextRow = 0;
        std::vector<LayerPart>& pieces = parts[layer.name];
        for (size_t index = 0; index < count; ++index) {
            size_t s = order[index];
            LayerPart& piece = pieces[s];
            const Layer* part = piece.meta.name.empty() ? nullptr : &piece.meta;
            if (!part || part->domain != "vertex_range" || part->semantic != layer.semantic ||
                !std::equal(part->shape.begin() + 1, part->shape.end(), layer.shape.begin() + 1, layer.shape.end()) ||
                part->shape.size() != layer.shape.size())
                throw Error(files[s], "layer " + layer.name, "missing or of another domain, semantic or row shape", kExitInput);
            if (withoutShardParams(part->params) != common)
                throw Error(files[s], "layer " + layer.name, "parameters differ from " + files[0] + "'s", kExitInput);
            uint64_t begin = rowParam(*part, "row_begin", files[s]), end = rowParam(*part, "row_end", files[s]);
            if (begin != nextRow || end < begin || end > vertices || part->shape[0] != end - begin)
                throw Error(files[s], "layer " + layer.name, "rows [" + std::to_string(begin) + ", " + std::to_string(end) +
                                                                 ") do not continue at row " + std::to_string(nextRow), kExitInput);
            nextRow = end;
            data.insert(data.end(), piece.data.begin(), piece.data.end());
            piece.data = {}; // held once: joined rows grow as shard rows go
            for (const char* key : kCounterParams)
                if (part->params.contains(key)) counters[key] = counters.value(key, uint64_t(0)) + part->params[key].get<uint64_t>();
        }
        if (nextRow != vertices)
            throw Error(files[order[count - 1]], "layer " + layer.name, "shards end at row " + std::to_string(nextRow) +
                                                                            " of " + std::to_string(vertices), kExitInput);
        layer.domain = "vertex";
        layer.shape[0] = vertices;
        layer.data = std::move(data);
        layer.params = common;
        layer.params.update(counters);
    }
    return merged;
}

} // namespace

Bundle mergeShards(const std::vector<Bundle>& shards, const std::vector<std::string>& files) {
    if (shards.size() != files.size()) throw Error("", "merge", "no shards to merge", kExitUsage);
    return mergeShardsFrom(shards.size(), [&](size_t s) { return shards[s]; }, files);
}

Bundle mergeShardFiles(const std::vector<std::string>& files) {
    return mergeShardsFrom(files.size(), [&](size_t s) { return readBundle(files[s]); }, files);
}

} // namespace prt
