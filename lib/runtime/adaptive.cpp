// Adaptive transfer in the runtime: loading the ragged, quantised and clustered-PCA layers of `prt adapt`
// (docs/bundle.md, "Adaptive transfer") and relighting each vertex with only its own bands.
#include "runtime.h"

#include "core.h"
#include "runtime_internal.h"

#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace prt {

namespace {

const Layer& requireLayer(const Bundle& bundle, const nlohmann::json& params, const char* member,
                          const std::string& source, const std::string& place) {
    if (!params.contains(member) || !params[member].is_string())
        throw Error(source, place, std::string("params.") + member + " does not name a layer");
    const std::string name = params[member].get<std::string>();
    const Layer* layer = findLayer(bundle, name);
    if (!layer) throw Error(source, place, "names layer \"" + name + "\" in params." + member + ", which is absent");
    return *layer;
}

// The layer's shape is `shape` and its component type `type`: an exact type ("uint32"), "float" (float16 or
// float32, values in data) or "uint" (uint8, uint16 or uint32, values in integers), so no reader reads the storage
// a layer of another type leaves empty; and that storage holds exactly the shape's values.
void requireShape(const Layer& layer, const std::vector<uint64_t>& shape, const std::string& type,
                  const std::string& source) {
    const std::string place = "layer \"" + layer.name + "\"";
    if (layer.shape != shape) {
        std::string expected;
        for (uint64_t axis : shape) expected += (expected.empty() ? "" : ", ") + std::to_string(axis);
        throw Error(source, place, "shape does not match [" + expected + "]");
    }
    const std::string& held = layer.componentType;
    bool typed = type == "float"  ? held == "float16" || held == "float32"
                 : type == "uint" ? held == "uint8" || held == "uint16" || held == "uint32"
                                  : held == type;
    if (!typed)
        throw Error(source, place, "is " + held + ", expected " +
                                       (type == "float" ? "float16 or float32" : type == "uint" ? "uint8, uint16 or uint32" : type));
    uint64_t count = 1;
    for (uint64_t axis : shape) count *= axis;
    bool integer = layer.componentType.rfind("uint", 0) == 0;
    if ((integer ? layer.integers.size() : layer.data.size()) != count)
        throw Error(source, place, "holds the wrong number of values for its shape");
}

int layerOrder(const Layer& layer, const std::string& source) {
    const std::string place = "layer \"" + layer.name + "\"";
    if (!layer.params.contains("order") || !layer.params["order"].is_number_integer())
        throw Error(source, place, "params.order is missing");
    int64_t order = layer.params["order"].get<int64_t>();
    if (order > kMaxRuntimeOrder)
        throw Error(source, place, "asks for " + std::to_string(order) + " SH bands; this runtime evaluates at most " +
                                       std::to_string(kMaxRuntimeOrder) + " (a newer prt, or `prt adapt` at a lower order)");
    if (order < 1) throw Error(source, place, "params.order " + std::to_string(order) + " is not a band count");
    return int(order);
}

// The rows of adaptive layers of `domain` (vertex: the mesh's vertices; texel: params width x height of `layer`).
size_t adaptiveRows(const Bundle& bundle, const Layer& layer, const std::string& domain, const std::string& source) {
    if (domain == "vertex") return bundle.mesh.vertexCount();
    const std::string place = "layer \"" + layer.name + "\"";
    uint64_t rows = 1;
    for (const char* key : {"width", "height"}) {
        const nlohmann::json& value = layer.params.contains(key) ? layer.params[key] : nlohmann::json();
        if (!value.is_number_integer() || value.get<int64_t>() < 1 || value.get<int64_t>() > 65536)
            throw Error(source, place + ", params." + key, "is missing or not a size in 1..65536");
        rows *= value.get<uint64_t>();
    }
    if (rows > std::numeric_limits<uint32_t>::max()) throw Error(source, place, "too many texels");
    return size_t(rows);
}

RelightModel raggedModel(Bundle& bundle, const std::string& source) {
    Layer& data = const_cast<Layer&>(*findLayer(bundle, "transfer_ragged"));
    const std::string place = "layer \"transfer_ragged\"";
    if (data.domain != "vertex_ragged" && data.domain != "texel_ragged")
        throw Error(source, place, "domain \"" + data.domain + "\", expected vertex_ragged or texel_ragged");
    const std::string domain = data.domain.substr(0, data.domain.find('_')); // vertex or texel
    const size_t V = adaptiveRows(bundle, data, domain, source);
    const int order = layerOrder(data, source);
    const Layer& offsetsLayer = requireLayer(bundle, data.params, "offsets", source, place);
    if (offsetsLayer.domain != domain + "_offsets")
        throw Error(source, "layer \"" + offsetsLayer.name + "\"", "domain \"" + offsetsLayer.domain + "\", expected " +
                                                                   domain + "_offsets");
    requireShape(offsetsLayer, {V + 1}, "uint32", source);
    const std::vector<uint32_t>& offsets = offsetsLayer.integers;
    if (offsets[0] != 0) throw Error(source, "layer \"" + offsetsLayer.name + "\"", "does not start at 0");
    for (size_t v = 0; v < V; ++v) {
        if (offsets[v + 1] < offsets[v])
            throw Error(source, "layer \"" + offsetsLayer.name + "\", vertex " + std::to_string(v), "offsets descend");
        uint32_t count = offsets[v + 1] - offsets[v];
        int n = int(std::lround(std::sqrt(double(count))));
        if (n < 1 || uint32_t(n) * uint32_t(n) != count)
            throw Error(source, place + ", vertex " + std::to_string(v),
                        std::to_string(count) + " coefficients is not a whole number of bands (n^2, n >= 1)");
        if (n > kMaxRuntimeOrder)
            throw Error(source, place + ", vertex " + std::to_string(v),
                        "asks for " + std::to_string(n) + " SH bands; this runtime evaluates at most " +
                            std::to_string(kMaxRuntimeOrder));
        if (n > order)
            throw Error(source, place + ", vertex " + std::to_string(v),
                        "has " + std::to_string(n) + " bands, more than the layer's order " + std::to_string(order));
    }
    const uint64_t rows = offsets[V];
    RelightModel model;
    model.vertexCount = uint32_t(V);
    model.order = order;
    const std::string& type = data.componentType;
    if (type == "float32" || type == "float16") {
        if (data.semantic != "sh_transfer_rgb")
            throw Error(source, place, "semantic \"" + data.semantic + "\", expected sh_transfer_rgb");
        requireShape(data, {rows, 3}, "float", source);
        checkFiniteRows(data.data, 3, source, place, "row");
        if (type == "float32") {
            model.transfer = std::move(data.data);
        } else { // kept as the halves the file stores (the reader widened them exactly, so this is exact too)
            model.storage = TransferStorage::Float16;
            model.halves.resize(data.data.size());
            for (size_t i = 0; i < data.data.size(); ++i) model.halves[i] = floatToHalf(data.data[i]);
        }
    } else if (type == "uint8" || type == "uint16") {
        if (data.semantic != "sh_transfer_rgb_quantised")
            throw Error(source, place, "semantic \"" + data.semantic + "\", expected sh_transfer_rgb_quantised");
        requireShape(data, {rows, 3}, type, source);
        const int bits = type == "uint8" ? 8 : 16;
        const uint32_t centre = (1u << (bits - 1)) - 1;
        const Layer& scales = requireLayer(bundle, data.params, "scale_layer", source, place);
        const std::vector<uint32_t>* cluster = nullptr;
        size_t clusterCount = 0;
        if (scales.domain == "cluster") {
            const Layer& clusterLayer = requireLayer(bundle, data.params, "cluster_layer", source, place);
            if (scales.shape.size() != 2) throw Error(source, "layer \"" + scales.name + "\"", "shape is not [clusters, order]");
            clusterCount = scales.shape[0];
            requireShape(scales, {clusterCount, uint64_t(order)}, "float", source);
            requireShape(clusterLayer, {V}, "uint", source);
            for (size_t v = 0; v < V; ++v)
                if (clusterLayer.integers[v] >= clusterCount)
                    throw Error(source, "layer \"" + clusterLayer.name + "\", vertex " + std::to_string(v),
                                "cluster index out of range");
            cluster = &clusterLayer.integers;
        } else if (scales.domain == domain + "_bands") {
            uint64_t bands = 0;
            for (size_t v = 0; v < V; ++v) bands += uint64_t(std::lround(std::sqrt(double(offsets[v + 1] - offsets[v]))));
            requireShape(scales, {bands}, "float", source);
        } else {
            throw Error(source, "layer \"" + scales.name + "\"", "domain \"" + scales.domain + "\", expected " + domain +
                                                              "_bands or cluster");
        }
        checkFiniteRows(scales.data, 1, source, "layer \"" + scales.name + "\"", "scale");
        // Codes stay codes (1 or 2 bytes each); the scales become sigma = scale / C, as relight() uses them.
        for (size_t i = 0; i < data.integers.size(); ++i)
            if (data.integers[i] > 2 * centre)
                throw Error(source, place + ", row " + std::to_string(i / 3), "code above " + std::to_string(2 * centre));
        model.storage = bits == 8 ? TransferStorage::Uint8 : TransferStorage::Uint16;
        if (bits == 8) model.codes8.assign(data.integers.begin(), data.integers.end());
        else model.codes16.assign(data.integers.begin(), data.integers.end());
        model.bandScales.resize(scales.data.size());
        for (size_t i = 0; i < scales.data.size(); ++i) model.bandScales[i] = scales.data[i] / float(centre);
        if (cluster) {
            model.scaleCluster = *cluster;
        } else {
            uint32_t band = 0;
            for (size_t v = 0; v < V; ++v) {
                if (v % kRelightBlock == 0) model.bandBlockStarts.push_back(band);
                band += uint32_t(std::lround(std::sqrt(double(offsets[v + 1] - offsets[v]))));
            }
            model.bandBlockStarts.push_back(band);
        }
    } else {
        throw Error(source, place, "component type " + type + " is not one this runtime decodes");
    }
    model.offsets = offsets;
    return model;
}

RelightModel cpcaModel(Bundle& bundle, const std::string& source) {
    const Layer& basis = *findLayer(bundle, "transfer_cpca_basis");
    const std::string place = "layer \"transfer_cpca_basis\"";
    const bool texels = basis.params.contains("width");
    const size_t V = adaptiveRows(bundle, basis, texels ? "texel" : "vertex", source);
    const int order = layerOrder(basis, source);
    if (basis.semantic != "cpca_mean_basis" || basis.shape.size() != 4)
        throw Error(source, place, "is not a cpca_mean_basis layer [clusters, components + 1, L*L, 3]");
    const uint64_t clusters = basis.shape[0], components = basis.shape[1] - 1, dim = uint64_t(order) * order * 3;
    if (basis.shape[1] < 1) throw Error(source, place, "has no mean row");
    requireShape(basis, {clusters, components + 1, uint64_t(order) * order, 3}, "float32", source);
    const Layer& weights = requireLayer(bundle, basis.params, "weights_layer", source, place);
    const Layer& cluster = requireLayer(bundle, basis.params, "cluster_layer", source, place);
    requireShape(weights, {V, components}, "float32", source);
    requireShape(cluster, {V}, "uint", source);
    for (const Layer* layer : {&weights, &cluster})
        if (layer->domain != (texels ? "texel" : "vertex"))
            throw Error(source, "layer \"" + layer->name + "\"", "domain \"" + layer->domain + "\" is not the basis's");
    checkFiniteRows(basis.data, dim, source, place, "row");
    checkFiniteRows(weights.data, components ? components : 1, source, "layer \"" + weights.name + "\"", "vertex");
    for (size_t v = 0; v < V; ++v)
        if (cluster.integers[v] >= clusters)
            throw Error(source, "layer \"" + cluster.name + "\", vertex " + std::to_string(v), "cluster index out of range");
    if (clusters > std::numeric_limits<uint32_t>::max() || components > uint64_t(std::numeric_limits<int>::max()))
        throw Error(source, place, "too many clusters or components");
    // Kept in the basis: relight() projects each cluster on the lighting once and sums M weights per vertex.
    RelightModel model;
    model.vertexCount = uint32_t(V);
    model.order = order;
    model.storage = TransferStorage::Cpca;
    model.cpcaComponents = int(components);
    model.cpcaClusters = uint32_t(clusters);
    model.cpcaBasis = basis.data;
    model.cpcaWeights = weights.data;
    model.cpcaCluster = cluster.integers;
    return model;
}

} // namespace

bool hasAdaptiveTransfer(const Bundle& bundle) {
    return findLayer(bundle, "transfer_ragged") || findLayer(bundle, "transfer_cpca_basis");
}

RelightModel adaptiveRelightModel(Bundle& bundle, const std::string& source) {
    if (bundle.mesh.vertexCount() > std::numeric_limits<uint32_t>::max())
        throw Error(source, "mesh", "too many vertices");
    const Layer* data = findLayer(bundle, "transfer_ragged");
    if (!data) data = findLayer(bundle, "transfer_cpca_basis");
    if (!data) throw Error(source, "PRT_bundle", "no adaptive transfer layers (transfer_ragged or transfer_cpca_basis)");
    // The adapted layer's params.transfer holds the full-order layer's params, albedo rule included.
    Layer input;
    if (data->params.contains("transfer") && data->params["transfer"].is_object()) input.params = data->params["transfer"];
    RelightModel model = data->name == "transfer_ragged" ? raggedModel(bundle, source) : cpcaModel(bundle, source);
    readExcludedAlbedo(bundle, input, source, model);
    blockRows(model); // codes with per-vertex scales, and halves: the blocked kernels' layout, in place
    return model;
}

void relightAdaptive(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance) {
    checkRelightCall(model, begin, end, "relightAdaptive");
    if (model.offsets.empty() || model.storage == TransferStorage::Cpca)
        throw Error("", "relightAdaptive", "needs a model with per-vertex orders (offsets), not clustered PCA; relight() "
                                           "takes every model", kExitFailure);
    if (begin == end) return;
    relightRaggedRange(model, lighting, begin, end, radiance);
    if (!model.albedo.empty())
        for (size_t i = 0; i < (end - begin) * 3; ++i) radiance[i] *= model.albedo[begin * 3 + i];
}

} // namespace prt
