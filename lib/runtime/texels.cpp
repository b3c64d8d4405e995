// Per-texel transfer held in the bundle's own buffers (the "texel_transfer" layer with its rows inline), and the
// layer checks the texture reader of prt::runtime_images shares. No image library here: the thin runtime.
#include "runtime.h"

#include "core.h"
#include "runtime_internal.h"

#include <cstdio>
#include <limits>
#include <utility>

namespace prt {

namespace {

int sizeParam(const nlohmann::json& object, const char* key, const std::string& source, const std::string& place) {
    if (!object.contains(key) || !object[key].is_number_integer() || object[key].get<int64_t>() < 1 ||
        object[key].get<int64_t>() > std::numeric_limits<int>::max())
        throw Error(source, place, std::string(key) + " is missing or not a positive integer");
    return int(object[key].get<int64_t>());
}

} // namespace

TexelLayerShape texelLayerShape(const Layer& layer, const std::string& source) {
    const std::string place = "layer \"texel_transfer\"";
    TexelLayerShape shape;
    shape.order = transferLayerOrder(layer, source, place);
    shape.width = sizeParam(layer.params, "width", source, place + ", params");
    shape.height = sizeParam(layer.params, "height", source, place + ", params");
    const nlohmann::json albedo = layer.params.value("albedo", nlohmann::json());
    shape.albedoExcluded = albedo.is_string() && albedo.get<std::string>() == "excluded";
    uint64_t texels = uint64_t(shape.width) * uint64_t(shape.height);
    if (layer.shape[0] != texels || texels > std::numeric_limits<uint32_t>::max())
        throw Error(source, place, "has " + std::to_string(layer.shape[0]) + " rows for a " +
                                       std::to_string(shape.width) + "x" + std::to_string(shape.height) + " atlas");
    return shape;
}

std::string texelCoefficientChannel(int coefficient, int colour) {
    char name[16];
    std::snprintf(name, sizeof name, "T%03d.%c", coefficient, "RGB"[colour]);
    return name;
}

TexelRelightModel adaptiveTexelModel(Bundle& bundle, const std::string& source) {
    const Layer* layer = findLayer(bundle, "transfer_ragged");
    if (!layer) layer = findLayer(bundle, "transfer_cpca_basis");
    const std::string place = "layer \"" + layer->name + "\"";
    if (!layer->params.contains("width"))
        throw Error(source, place, "holds per-vertex adaptive transfer: relight it without --texels");
    TexelRelightModel model;
    model.width = sizeParam(layer->params, "width", source, place + ", params");
    model.height = sizeParam(layer->params, "height", source, place + ", params");
    model.rows = adaptiveRelightModel(bundle, source);
    return model;
}

TexelRelightModel texelRelightModel(Bundle bundle, const std::string& source) {
    if (!findLayer(bundle, "texel_transfer") && hasAdaptiveTransfer(bundle)) return adaptiveTexelModel(bundle, source);
    Layer& layer = transferLayer(bundle, "texel_transfer", "texel", source, "bake");
    TexelLayerShape shape = texelLayerShape(layer, source);
    const size_t rowValues = 3 * size_t(shape.order) * shape.order;
    if (layer.data.size() != size_t(shape.width) * shape.height * rowValues)
        throw Error(source, "layer \"texel_transfer\"",
                    layer.params.contains("uri")
                        ? "keeps its texels in the texture params.uri: read it with loadTexelRelightModel "
                          "(prt::runtime_images)"
                        : "holds " + std::to_string(layer.data.size()) + " values, not its shape's " +
                              std::to_string(size_t(shape.width) * shape.height * rowValues));
    TexelRelightModel model;
    model.width = shape.width;
    model.height = shape.height;
    model.rows.vertexCount = uint32_t(size_t(shape.width) * shape.height);
    model.rows.order = shape.order;
    model.rows.albedoExcluded = shape.albedoExcluded;
    model.rows.transfer = std::move(layer.data);
    checkFiniteRows(model.rows.transfer, rowValues, source, "layer \"texel_transfer\"", "texel");
    return model;
}

} // namespace prt
