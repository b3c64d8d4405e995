// Shard bookkeeping common to every `--shard I/N` stage: which shard bundle is which, by its layer's params.shard.
#include "bundle.h"

#include "core.h"

namespace prt {

std::vector<size_t> orderShards(const std::vector<const Layer*>& layers, const std::vector<std::string>& files) {
    size_t count = layers.size();
    std::vector<size_t> order(count);
    std::vector<int> seen(count, -1);
    for (size_t s = 0; s < count; ++s) {
        const Layer* layer = layers[s];
        const nlohmann::json* shard = layer && layer->params.contains("shard") ? &layer->params["shard"] : nullptr;
        if (!shard || !shard->is_array() || shard->size() != 2 || !(*shard)[0].is_number_integer() ||
            !(*shard)[1].is_number_integer())
            throw Error(files[s], "", "not a shard bundle: no layer with params.shard = [I, N]", kExitInput);
        int64_t index = (*shard)[0], total = (*shard)[1];
        if (total != int64_t(count))
            throw Error(files[s], "",
                        "is shard " + std::to_string(index) + " of " + std::to_string(total) + ", but " +
                            std::to_string(count) + " shards were given",
                        kExitInput);
        if (index < 0 || index >= total)
            throw Error(files[s], "", "shard index " + std::to_string(index) + " is out of range", kExitInput);
        if (seen[index] >= 0)
            throw Error(files[s], "",
                        "shard " + std::to_string(index) + " is given twice (also " + files[seen[index]] + ")",
                        kExitInput);
        seen[index] = int(s);
        order[index] = s;
    }
    return order;
}

void markVertexShard(Layer& layer, uint64_t rowBegin, uint64_t rowEnd, uint64_t vertexCount, int index, int count) {
    if (count <= 1) {
        layer.domain = "vertex";
        return;
    }
    // A slice of the vertex rows; the merge concatenates the shards into one "vertex" layer.
    layer.domain = "vertex_range";
    layer.params["shard"] = {index, count};
    layer.params["row_begin"] = rowBegin;
    layer.params["row_end"] = rowEnd;
    layer.params["vertex_count"] = vertexCount;
}

} // namespace prt
