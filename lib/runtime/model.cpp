// Loading a bundle's transfer layer into a RelightModel, validated so the kernel can trust its sizes.
#include "runtime.h"

#include "bundle_stream.h"
#include "core.h"
#include "json_input.h"
#include "runtime_internal.h"

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>

namespace prt {

namespace {

std::string shapeText(const std::vector<uint64_t>& shape) {
    std::string text = "[";
    for (size_t i = 0; i < shape.size(); ++i) text += (i ? ", " : "") + std::to_string(shape[i]);
    return text + "]";
}

} // namespace

Layer& transferLayer(Bundle& bundle, const std::string& name, const std::string& domain, const std::string& source,
                     const char* stage) {
    Layer* layer = nullptr;
    for (Layer& candidate : bundle.layers)
        if (candidate.name == name) layer = &candidate;
    if (!layer)
        throw Error(source, "PRT_bundle", "no \"" + name + "\" layer to relight (run `prt " + stage + "` to make one)");
    if (layer->domain != domain || layer->semantic != "sh_transfer_rgb")
        throw Error(source, "layer \"" + name + "\"",
                    "domain \"" + layer->domain + "\", semantic \"" + layer->semantic + "\"; expected domain \"" +
                        domain + "\", semantic \"sh_transfer_rgb\"");
    return *layer;
}

int transferLayerOrder(const Layer& layer, const std::string& source, const std::string& place) {
    const std::vector<uint64_t>& shape = layer.shape;
    int order = int(std::lround(std::sqrt(shape.size() == 3 ? double(shape[1]) : 0.0)));
    if (shape.size() != 3 || shape[2] != 3 || order < 1 || order > sh::kMaxOrder ||
        uint64_t(order) * order != shape[1])
        throw Error(source, place, "shape " + shapeText(shape) + " is not [rows, L*L, 3] for an order L in 1.." +
                                       std::to_string(sh::kMaxOrder));
    const nlohmann::json& paramOrder = layer.params.contains("order") ? layer.params["order"] : nlohmann::json();
    if (!paramOrder.is_null() && !(paramOrder.is_number_integer() && paramOrder.get<int64_t>() == order))
        throw Error(source, place, "params.order " + jsonExcerpt(paramOrder) + " does not match shape " + shapeText(shape));
    return order;
}

void checkFiniteRows(const std::vector<float>& data, size_t rowValues, const std::string& source,
                     const std::string& place, const char* row) {
    for (size_t i = 0; i < data.size(); ++i)
        if (!std::isfinite(data[i]))
            throw Error(source, place + ", " + row + " " + std::to_string(i / rowValues),
                        "transfer value is not finite");
}

RelightModel relightModel(Bundle bundle, const std::string& source) {
    if (!findLayer(bundle, "transfer") && hasAdaptiveTransfer(bundle)) return adaptiveRelightModel(bundle, source);
    Layer* layer = &transferLayer(bundle, "transfer", "vertex", source, "transfer");
    const std::string place = "layer \"transfer\"";

    const std::vector<uint64_t>& shape = layer->shape;
    int order = transferLayerOrder(*layer, source, place);
    if (shape[0] != bundle.mesh.vertexCount() || shape[0] > std::numeric_limits<uint32_t>::max())
        throw Error(source, place, "has " + std::to_string(shape[0]) + " rows for a mesh of " +
                                       std::to_string(bundle.mesh.vertexCount()) + " vertices");
    if (layer->data.size() != shape[0] * shape[1] * 3)
        throw Error(source, place, "holds " + std::to_string(layer->data.size()) + " floats, shape " +
                                       shapeText(shape) + " needs " + std::to_string(shape[0] * shape[1] * 3));
    checkFiniteRows(layer->data, shape[1] * 3, source, place, "vertex");

    RelightModel model;
    model.vertexCount = uint32_t(shape[0]);
    model.order = order;
    model.transfer = std::move(layer->data);
    readExcludedAlbedo(bundle, *layer, source, model);
    return model;
}

void readExcludedAlbedo(const Bundle& bundle, const Layer& transfer, const std::string& source, RelightModel& model) {
    const nlohmann::json albedo = transfer.params.value("albedo", nlohmann::json());
    if (!(albedo.is_string() && albedo.get<std::string>() == "excluded")) return;
    model.albedoExcluded = true;
    const Layer* layer = findLayer(bundle, "diffuse_albedo");
    const std::string place = "layer \"diffuse_albedo\"";
    if (!layer)
        throw Error(source, "PRT_bundle", "transfer excludes the albedo but the bundle has no \"diffuse_albedo\" layer");
    if (layer->domain != "vertex" || layer->semantic != "diffuse_albedo_rgb" || layer->shape.size() != 2 ||
        layer->shape[0] != model.vertexCount || layer->shape[1] != 3 || layer->data.size() != size_t(model.vertexCount) * 3)
        throw Error(source, place, "is not a vertex layer diffuse_albedo_rgb of shape [" + std::to_string(model.vertexCount) +
                                       ", 3]");
    for (size_t i = 0; i < layer->data.size(); ++i)
        if (!(layer->data[i] >= 0.0f && layer->data[i] <= 1.0f))
            throw Error(source, place + ", vertex " + std::to_string(i / 3), "albedo is not in [0, 1]");
    model.albedo = layer->data;
}

Bundle readRelightBundle(const std::string& bundlePath) {
    std::optional<BundleHeader> header;
    try {
        header = readBundleHeader(bundlePath);
    } catch (const Error&) {
        return readBundle(bundlePath); // another layout, or a file readBundle refuses with its own message
    }
    Bundle& bundle = header->bundle;
    // With a transfer layer, relightModel reads it and the albedo it may exclude; without one, the adaptive layers
    // (adaptiveRelightModel), so then every layer has its values, as readBundle gives them.
    const bool transfer = findLayer(bundle, "transfer") != nullptr;
    for (size_t i = 0; i < bundle.layers.size(); ++i)
        if (!transfer || bundle.layers[i].name == "transfer" || bundle.layers[i].name == "diffuse_albedo")
            readLayerValues(*header, i, bundle.layers[i]);
    return std::move(bundle);
}

RelightModel loadRelightModel(const std::string& bundlePath) {
    return relightModel(readRelightBundle(bundlePath), bundlePath);
}

} // namespace prt
