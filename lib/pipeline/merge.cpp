// Joins shard bundles (contiguous vertex ranges of one stage run) into the bundle the unsharded run writes.
#include "pipeline.h"

#include "core.h"

#include <algorithm>
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

Bundle mergeShards(const std::vector<Bundle>& shards, const std::vector<std::string>& files) {
    if (shards.empty() || shards.size() != files.size()) throw Error("", "merge", "no shards to merge", kExitUsage);
    const Bundle& first = shards[0];
    size_t count = shards.size();

    std::vector<const Layer*> sharded(count);
    for (size_t s = 0; s < count; ++s)
        sharded[s] = first.layers.empty() ? nullptr : findLayer(shards[s], first.layers[0].name);
    std::vector<size_t> order = orderShards(sharded, files);
    for (const Layer& layer : first.layers)
        if (layer.domain == "texel_range")
            throw Error(files[0], "layer " + layer.name,
                        "is a bake shard: its merge redoes the bake's finishing, so run `prt bake MESH -o OUT.glb "
                        "--merge SHARD...` with the shards' options instead",
                        kExitUsage);

    Bundle merged = first;
    for (size_t s = 1; s < count; ++s) {
        const Bundle& other = shards[s];
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
    }

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
        for (size_t index = 0; index < count; ++index) {
            size_t s = order[index];
            const Layer* part = findLayer(shards[s], layer.name);
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
            data.insert(data.end(), part->data.begin(), part->data.end());
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

} // namespace prt
