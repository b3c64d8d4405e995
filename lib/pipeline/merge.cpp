// Joins shard bundles (contiguous vertex ranges of one stage run) into the bundle the unsharded run writes: one
// validator (checkShard, joinLayers) for the join in memory (mergeShards) and the streamed one (mergeShardFiles).
#include "pipeline.h"

#include "bundle_stream.h"
#include "core.h"

#include <algorithm>
#include <cmath>
#include <functional>
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

// A shard layer's whole-number parameter `key`: a number in [0, 2^53] (what a bundle's JSON stores exactly).
uint64_t rowParam(const Layer& layer, const char* key, const std::string& file) {
    const nlohmann::json& value = layer.params.contains(key) ? layer.params[key] : nlohmann::json();
    if (!value.is_number() || !(value.get<double>() >= 0) || value.get<double>() > 9007199254740992.0 ||
        value.get<double>() != std::floor(value.get<double>()))
        throw Error(file, "layer " + layer.name, std::string("shard layer has no valid '") + key +
                                                     "' (a whole number from 0 to 2^53)", kExitInput);
    return uint64_t(value.get<double>());
}

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

// The index of the layer named `name` in `bundle`, or bundle.layers.size() when it has none.
size_t layerIndex(const Bundle& bundle, const std::string& name) {
    for (size_t i = 0; i < bundle.layers.size(); ++i)
        if (bundle.layers[i].name == name) return i;
    return bundle.layers.size();
}

// Whether a layer that every shard holds whole holds the same values in shard `other` as in the first.
using SameValues = std::function<bool(const Layer& first, size_t firstIndex, const Layer& other, size_t otherIndex)>;

// Checks that shard `other` (from `file`) belongs to the run of `first` (from `firstFile`): the same meshes, inputs,
// producer and convention, as many layers, and every layer the first holds whole held alike (domain, params and
// values). Throws prt::Error(file, ..., kExitInput) naming the difference.
void checkShard(const Bundle& first, const std::string& firstFile, const Bundle& other, const std::string& file,
                const SameValues& sameValues) {
    const TriMesh &a = first.mesh, &b = other.mesh;
    if (a.positions != b.positions || a.indices != b.indices || a.normals != b.normals || a.texcoords != b.texcoords ||
        a.albedo != b.albedo)
        throw Error(file, "mesh", "differs from the mesh of " + firstFile + ": shards of different inputs", kExitInput);
    if (other.inputs != first.inputs || other.producer != first.producer || other.convention != first.convention)
        throw Error(file, "", "was produced from other inputs or by another producer than " + firstFile, kExitInput);
    if (other.layers.size() != first.layers.size())
        throw Error(file, "", "has " + std::to_string(other.layers.size()) + " layers, " + firstFile + " has " +
                                  std::to_string(first.layers.size()), kExitInput);
    for (size_t k = 0; k < first.layers.size(); ++k) {
        const Layer& layer = first.layers[k];
        if (layer.domain == "vertex_range") continue;
        size_t index = layerIndex(other, layer.name);
        const Layer* same = index < other.layers.size() ? &other.layers[index] : nullptr;
        if (!same || same->domain != layer.domain || same->params != layer.params || !sameValues(layer, k, *same, index))
            throw Error(file, "layer " + layer.name, "differs from " + firstFile + "'s, but is not sharded", kExitInput);
    }
}

// For each layer of `first`, the description (no values) of the layer of that name in `shard`, or a layer with no
// name where it has none.
std::vector<Layer> describeLike(const Bundle& first, const Bundle& shard) {
    std::vector<Layer> parts(first.layers.size());
    for (size_t k = 0; k < first.layers.size(); ++k) {
        size_t index = layerIndex(shard, first.layers[k].name);
        if (index < shard.layers.size()) parts[k] = describe(shard.layers[index]);
    }
    return parts;
}

// How the layers of the shards join.
struct JoinPlan {
    std::vector<size_t> order;  // order[I]: the position of shard I among the files
    std::vector<Layer> layers;  // the first shard's layers, without values; sharded ones as the joined layer
    std::vector<bool> sharded;  // per layer: joined from every shard's rows (else kept from the first)
};

// The join of shards whose layers `parts` describes (parts[s] = describeLike(first, shard s), parts[0] the first's
// own), after checkShard passed for every other shard: the shards' order, and each "vertex_range" layer joined into
// a "vertex" layer of the mesh's vertex count (shard bookkeeping dropped, counters summed). Throws prt::Error naming
// the offending file for shards that are no shards of one run, for bake shards, and for ranges that do not tile
// [0, vertex_count) exactly once in shard order.
JoinPlan joinLayers(const Bundle& first, const std::vector<std::vector<Layer>>& parts, const std::vector<std::string>& files) {
    const size_t count = parts.size();
    JoinPlan plan;
    std::vector<const Layer*> keys(count, nullptr); // each shard's layer named as the first's first layer
    for (size_t s = 0; s < count; ++s)
        if (!parts[s].empty() && !parts[s][0].name.empty()) keys[s] = &parts[s][0];
    plan.order = orderShards(keys, files);
    for (const Layer& layer : first.layers)
        if (layer.domain == "texel_range")
            throw Error(files[0], "layer " + layer.name,
                        "is a bake shard: its merge redoes the bake's finishing, so run `prt bake MESH -o OUT.glb "
                        "--merge SHARD...` with the shards' options instead",
                        kExitUsage);

    for (size_t k = 0; k < first.layers.size(); ++k) {
        Layer layer = describe(first.layers[k]);
        plan.sharded.push_back(layer.domain == "vertex_range");
        if (!plan.sharded.back()) { // layers every shard holds whole are kept as they are
            plan.layers.push_back(std::move(layer));
            continue;
        }
        uint64_t vertices = rowParam(layer, "vertex_count", files[0]);
        if (vertices != first.mesh.vertexCount())
            throw Error(files[0], "layer " + layer.name, "vertex_count " + std::to_string(vertices) +
                                                             " does not match the mesh's " +
                                                             std::to_string(first.mesh.vertexCount()) + " vertices", kExitInput);
        nlohmann::json common = withoutShardParams(layer.params);
        nlohmann::json counters = nlohmann::json::object();
        uint64_t nextRow = 0;
        for (size_t index = 0; index < count; ++index) {
            size_t s = plan.order[index];
            const Layer* part = parts[s][k].name.empty() ? nullptr : &parts[s][k];
            if (!part || part->domain != "vertex_range" || part->semantic != layer.semantic ||
                part->componentType != layer.componentType ||
                !std::equal(part->shape.begin() + 1, part->shape.end(), layer.shape.begin() + 1, layer.shape.end()) ||
                part->shape.size() != layer.shape.size())
                throw Error(files[s], "layer " + layer.name, "missing or of another domain, semantic, type or row shape",
                            kExitInput);
            if (withoutShardParams(part->params) != common)
                throw Error(files[s], "layer " + layer.name, "parameters differ from " + files[0] + "'s", kExitInput);
            uint64_t begin = rowParam(*part, "row_begin", files[s]), end = rowParam(*part, "row_end", files[s]);
            if (begin != nextRow || end < begin || end > vertices || part->shape[0] != end - begin)
                throw Error(files[s], "layer " + layer.name, "rows [" + std::to_string(begin) + ", " + std::to_string(end) +
                                                                 ") do not continue at row " + std::to_string(nextRow), kExitInput);
            if (rowParam(*part, "vertex_count", files[s]) != vertices)
                throw Error(files[s], "layer " + layer.name, "vertex_count differs from " + files[0] + "'s", kExitInput);
            nextRow = end;
            for (const char* key : kCounterParams) {
                if (!part->params.contains(key)) continue;
                const uint64_t sum = counters.value(key, uint64_t(0)) + rowParam(*part, key, files[s]);
                if (sum > (uint64_t(1) << 53))
                    throw Error(files[s], "layer " + layer.name, std::string("the shards' '") + key +
                                                                     "' sum past 2^53", kExitInput);
                counters[key] = sum;
            }
        }
        if (nextRow != vertices)
            throw Error(files[plan.order[count - 1]], "layer " + layer.name, "shards end at row " + std::to_string(nextRow) +
                                                                                 " of " + std::to_string(vertices), kExitInput);
        layer.domain = "vertex";
        layer.shape[0] = vertices;
        layer.params = common;
        layer.params.update(counters);
        plan.layers.push_back(std::move(layer));
    }
    return plan;
}

} // namespace

Bundle mergeShards(const std::vector<Bundle>& shards, const std::vector<std::string>& files) {
    if (shards.empty() || shards.size() != files.size()) throw Error("", "merge", "no shards to merge", kExitUsage);
    const Bundle& first = shards[0];
    std::vector<std::vector<Layer>> parts = {describeLike(first, first)};
    SameValues sameValues = [](const Layer& a, size_t, const Layer& b, size_t) {
        return a.componentType == b.componentType && a.data == b.data && a.integers == b.integers;
    };
    for (size_t s = 1; s < shards.size(); ++s) {
        checkShard(first, files[0], shards[s], files[s], sameValues);
        parts.push_back(describeLike(first, shards[s]));
    }
    JoinPlan plan = joinLayers(first, parts, files);
    Bundle merged = first;
    for (size_t k = 0; k < merged.layers.size(); ++k) {
        if (!plan.sharded[k]) continue;
        Layer joined = plan.layers[k];
        for (size_t s : plan.order) {
            const Layer& part = shards[s].layers[layerIndex(shards[s], joined.name)];
            joined.data.insert(joined.data.end(), part.data.begin(), part.data.end());
            joined.integers.insert(joined.integers.end(), part.integers.begin(), part.integers.end());
        }
        merged.layers[k] = std::move(joined);
    }
    return merged;
}

void mergeShardFiles(const std::vector<std::string>& files, const std::string& output) {
    if (files.empty()) throw Error("", "merge", "no shards to merge", kExitUsage);
    // Every shard's header is read (and its checksum checked) once, its mesh compared with the first's and
    // dropped; what stays per shard is its layers' descriptions and where their bytes lie.
    std::vector<BundleHeader> headers;
    headers.reserve(files.size()); // `first` and the streams point into it
    headers.push_back(readBundleHeader(files[0]));
    const Bundle& first = headers[0].bundle;
    std::vector<std::vector<Layer>> parts = {describeLike(first, first)};
    for (size_t s = 1; s < files.size(); ++s) {
        BundleHeader header = readBundleHeader(files[s]);
        checkShard(first, files[0], header.bundle, files[s], [&](const Layer& a, size_t ai, const Layer& b, size_t bi) {
            const LayerExtent &x = headers[0].extents[ai], &y = header.extents[bi];
            return a.componentType == b.componentType && x.byteLength == y.byteLength && x.hash == y.hash;
        });
        parts.push_back(describeLike(first, header.bundle));
        header.bundle.mesh = {};
        header.bundle.objects.clear();
        header.bundle.asset.reset();
        headers.push_back(std::move(header));
    }
    JoinPlan plan = joinLayers(first, parts, files);

    Bundle merged = std::move(headers[0].bundle); // the first's meshes and records, not copied
    headers[0].bundle.layers = merged.layers;      // streamLayerBytes names them
    merged.layers = plan.layers;
    std::vector<LayerStream> streams(merged.layers.size());
    for (size_t k = 0; k < merged.layers.size(); ++k) {
        // The rows of shard I, in shard order, for a joined layer; the first shard's bytes for a whole one.
        std::vector<std::pair<const BundleHeader*, size_t>> pieces;
        if (!plan.sharded[k]) pieces.emplace_back(&headers[0], k);
        else
            for (size_t s : plan.order) pieces.emplace_back(&headers[s], layerIndex(headers[s].bundle, merged.layers[k].name));
        for (const auto& [header, index] : pieces) streams[k].byteLength += header->extents[index].byteLength;
        streams[k].write = [pieces](const ByteSink& sink) {
            for (const auto& [header, index] : pieces) streamLayerBytes(*header, index, sink);
        };
    }
    writeBundleStreamed(output, merged, streams);
}

} // namespace prt
