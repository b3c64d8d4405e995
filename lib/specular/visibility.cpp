// The per-vertex cosine-weighted visibility O = V max(0, n . w) in SH, and its bundle layer.
#include "specular.h"

#include "core.h"
#include "json_input.h"
#include "transfer.h"

#include <cmath>
#include <numbers>
#include <string>

namespace prt::specular {

Visibility computeVisibility(const TriMesh& mesh, const VisibilityOptions& options) {
    if (options.order < 1 || options.order > sh::kMaxOrder)
        throw Error("", "--order", "must lie in 1.." + std::to_string(sh::kMaxOrder), kExitUsage);
    if (options.samples < 1 || options.samples > kMaxTransferSamples)
        throw Error("", "--samples", "must lie in 1.." + std::to_string(kMaxTransferSamples), kExitUsage);
    double start = nowSeconds();
    // The shadowed diffuse transfer at unit albedo is (1 / pi) integral V max(0, n . w) Y_j: the same integrand up to
    // pi, with the same rays, seeds and exact unoccluded part as every other transfer prt computes.
    TransferOptions transfer;
    transfer.mode = TransferMode::Shadowed;
    transfer.order = options.order;
    transfer.samples = options.samples;
    transfer.albedo = {1.0f, 1.0f, 1.0f};
    transfer.albedoOverride = true;
    transfer.seed = options.seed;
    transfer.threads = options.threads;
    transfer.progress = options.progress;
    Transfer computed = computeTransfer(mesh, transfer);

    Visibility visibility;
    visibility.order = options.order;
    const size_t count = computed.coefficients.size() / 3;
    visibility.coefficients.resize(count);
    for (size_t i = 0; i < count; ++i)
        visibility.coefficients[i] = float(std::numbers::pi * double(computed.coefficients[3 * i]));
    visibility.rays = computed.stats.rays;
    visibility.rayOffset = computed.stats.rayOffset;
    visibility.seconds = nowSeconds() - start;
    return visibility;
}

Layer visibilityLayer(const Visibility& visibility, const VisibilityOptions& options) {
    Layer layer;
    layer.name = kVisibilityLayer;
    layer.domain = "vertex";
    layer.semantic = "sh_cosine_visibility";
    const uint64_t coefficients = uint64_t(visibility.order) * visibility.order;
    layer.shape = {visibility.coefficients.size() / coefficients, coefficients};
    layer.data = visibility.coefficients;
    layer.params = {{"order", visibility.order},           {"samples", options.samples},
                    {"seed", options.seed},                {"direction_set", kTransferDirectionSet},
                    {"ray_offset", visibility.rayOffset}, {"rays", visibility.rays}};
    return layer;
}

Visibility readVisibility(const Bundle& bundle, const std::string& source) {
    const Layer* layer = findLayer(bundle, kVisibilityLayer);
    if (!layer)
        throw Error(source, "layers",
                    std::string("has no \"") + kVisibilityLayer + "\" layer (prt specular writes one)");
    const std::string place = std::string("layer ") + kVisibilityLayer;
    if (layer->domain != "vertex" || layer->semantic != "sh_cosine_visibility")
        throw Error(source, place, "is not a per-vertex \"sh_cosine_visibility\" layer");
    // Typed and range-checked before narrowing: 2^32 + 3 must not read as 3.
    const int order = int(jsonInteger(layer->params, "order", source, place + " params", 1, sh::kMaxOrder));
    const uint64_t vertices = bundle.mesh.vertexCount();
    if (layer->shape.size() != 2 || layer->shape[0] != vertices || layer->shape[1] != uint64_t(order) * order)
        throw Error(source, place + " shape",
                    "must be [" + std::to_string(vertices) + ", " + std::to_string(order * order) +
                        "] for the mesh's vertices and order " + std::to_string(order));
    if (layer->data.size() != vertices * order * order)
        throw Error(source, place, "is not a float layer of its shape");
    for (size_t i = 0; i < layer->data.size(); ++i)
        if (!std::isfinite(layer->data[i]))
            throw Error(source, place, "value " + std::to_string(i) + " is not finite");
    Visibility visibility;
    visibility.order = order;
    visibility.coefficients = layer->data;
    return visibility;
}

} // namespace prt::specular
