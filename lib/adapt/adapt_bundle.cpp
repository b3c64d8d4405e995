// `prt adapt`'s library half: a bundle's full-order "transfer" layer replaced by adaptive, compact layers
// (docs/bundle.md, "Adaptive transfer").
#include "adapt.h"

#include "core.h"
#include "sh.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

namespace prt::adapt {

Format parseFormat(const std::string& name) {
    if (name == "float") return Format::Float;
    if (name == "half") return Format::Half;
    if (name == "u16") return Format::U16;
    if (name == "u8") return Format::U8;
    if (name == "cpca") return Format::Cpca;
    throw Error("", "--format", "\"" + name + "\" is not one of float, half, u16, u8, cpca", kExitUsage);
}

const char* formatName(Format format) {
    switch (format) {
    case Format::Float: return "float";
    case Format::Half: return "half";
    case Format::U16: return "u16";
    case Format::U8: return "u8";
    case Format::Cpca: return "cpca";
    }
    return "?";
}

namespace {

uint64_t componentBytes(const std::string& type) {
    if (type == "float16" || type == "uint16") return 2;
    if (type == "uint8") return 1;
    return 4;
}

uint64_t layerBytes(const Layer& layer) {
    uint64_t count = 1;
    for (uint64_t axis : layer.shape) count *= axis;
    return count * componentBytes(layer.componentType);
}

Layer makeLayer(std::string name, std::string domain, std::string semantic, std::vector<uint64_t> shape,
                std::string type) {
    Layer layer;
    layer.name = std::move(name);
    layer.domain = std::move(domain);
    layer.semantic = std::move(semantic);
    layer.shape = std::move(shape);
    layer.componentType = std::move(type);
    return layer;
}

const char* priorName(Prior prior) { return prior == Prior::Maps ? "maps" : "worst"; }

} // namespace

std::vector<uint32_t> gridTriangles(int width, int height) {
    std::vector<uint32_t> triangles;
    for (int y = 0; y + 1 < height; ++y)
        for (int x = 0; x + 1 < width; ++x) {
            const uint32_t i = uint32_t(y) * width + x, right = i + 1, below = i + width;
            triangles.insert(triangles.end(), {i, right, below, right, below + 1, below});
        }
    return triangles;
}

namespace {

// The layer adaptBundle works on, taken out of the bundle and checked: a per-vertex "transfer" or a bake's
// "texel_transfer" [rows, L*L, 3] of finite floats held in the bundle.
struct TransferInput {
    Layer layer;
    bool texels = false;     // rows are texels of a width x height grid, else the mesh's vertices
    std::string domain;      // "vertex" or "texel"
    int width = 0, height = 0;
    size_t rows = 0;
    int order = 0;
    std::vector<uint32_t> triangles; // the rows' neighbourhood: the mesh's triangles, or the texel grid's
};

TransferInput takeTransferInput(Bundle& bundle, const std::string& source) {
    auto found = std::find_if(bundle.layers.begin(), bundle.layers.end(), [](const Layer& l) { return l.name == "transfer"; });
    if (found == bundle.layers.end())
        found = std::find_if(bundle.layers.begin(), bundle.layers.end(),
                             [](const Layer& l) { return l.name == "texel_transfer"; });
    if (found == bundle.layers.end())
        throw Error(source, "PRT_bundle", "no full-order \"transfer\" (or \"texel_transfer\") layer to adapt (run `prt "
                                          "transfer` or `prt bake` to make one)");
    TransferInput in;
    in.layer = std::move(*found);
    bundle.layers.erase(found);
    const Layer& input = in.layer;
    // Rows are vertices, whose neighbours are the mesh's edges, or texels of a bake, neighbours on the texel grid.
    in.texels = input.name == "texel_transfer";
    in.domain = in.texels ? "texel" : "vertex";
    const std::string place = "layer \"" + input.name + "\"";
    // The bounce part of the full-order transfer (hybrid lighting's) no longer matches what is stored: dropped.
    const char* bounceLayer = in.texels ? "texel_transfer_bounce" : "transfer_bounce";
    std::erase_if(bundle.layers, [&](const Layer& l) { return l.name == bounceLayer; });
    if (in.texels) {
        auto side = [&](const char* key) {
            const nlohmann::json& value = input.params.contains(key) ? input.params[key] : nlohmann::json();
            if (!value.is_number_integer() || value.get<int64_t>() < 1 || value.get<int64_t>() > 65536)
                throw Error(source, place + ", params." + key, "is missing or not a size in 1..65536");
            return int(value.get<int64_t>());
        };
        in.width = side("width"), in.height = side("height");
    }
    const size_t V = in.texels ? size_t(in.width) * in.height : bundle.mesh.vertexCount();
    in.rows = V;
    in.triangles = in.texels ? gridTriangles(in.width, in.height) : bundle.mesh.indices;
    const int order = input.shape.size() == 3 ? int(std::lround(std::sqrt(double(input.shape[1])))) : 0;
    if (input.domain != in.domain || input.semantic != "sh_transfer_rgb" || input.shape.size() != 3 ||
        input.shape[0] != V || input.shape[2] != 3 || order < 1 || order > sh::kMaxOrder ||
        uint64_t(order) * order != input.shape[1] || input.data.size() != V * input.shape[1] * 3)
        throw Error(source, place, "is not a " + in.domain + " sh_transfer_rgb layer [rows, L*L, 3] of float values "
                                   "held in the bundle (a bake's texture must be read into it first)");
    for (float value : input.data)
        if (!std::isfinite(value)) throw Error(source, place, "holds a value that is not finite");
    in.order = order;
    return in;
}

// Relative RMSE under the prior `lightings` (of inputOrder) of `dense` rows at `order` <= inputOrder against the
// input rows `inputFull` at inputOrder; the bands past `order` count as zero.
double errorAgainstInput(const std::vector<float>& dense, int order, const std::vector<float>& inputFull, int inputOrder,
                         size_t V, const std::vector<std::vector<float>>& lightings) {
    std::vector<float> padded(inputFull.size(), 0.0f);
    const size_t from = size_t(order) * order * 3, to = size_t(inputOrder) * inputOrder * 3;
    for (size_t v = 0; v < V; ++v) std::copy_n(dense.begin() + v * from, from, padded.begin() + v * to);
    return priorRelativeRmse(padded.data(), inputFull.data(), V, inputOrder, lightings);
}

// The CPCA layers of rows `full` [V][order^2][3]: options.components, or with none the fewest (doubling) whose
// error against the input is within options.maxError. `error(dense)` is that error; fills the stats' error and
// order fields and params' CPCA keys (basis layer's params are params).
std::vector<Layer> cpcaLayers(const std::vector<float>& full, size_t V, int order, const std::string& domain,
                              const AdaptOptions& options, const std::function<double(const std::vector<float>&)>& error,
                              nlohmann::json& params, AdaptStats& stats) {
    const size_t dim = size_t(order) * order * 3;
    const int clusters = std::clamp<int>(options.clusters, 1, int(V));
    Cpca cpca;
    if (options.components > 0) {
        cpca = clusteredPca(full.data(), V, dim, clusters, std::min<int>(options.components, int(dim)));
    } else { // the fewest components (doubling) whose relative RMSE under the prior is within max_error
        for (int m = 1;; m = std::min<int>(m * 2, int(dim))) {
            cpca = clusteredPca(full.data(), V, dim, clusters, m);
            if (m == int(dim) || error(reconstruct(cpca)) <= options.maxError) break;
        }
    }
    stats.relativeRmse = error(reconstruct(cpca));
    stats.components = cpca.components;
    stats.meanOrder = order;
    stats.meanCoefficients = double(order) * order;
    stats.orderHistogram[order] = int(V);
    params["clusters"] = clusters;
    params["components"] = cpca.components;
    params["cluster_layer"] = "transfer_cpca_cluster";
    params["weights_layer"] = "transfer_cpca_weights";
    Layer cluster = makeLayer("transfer_cpca_cluster", domain, "cluster_index", {V},
                              clusters <= 65536 ? "uint16" : "uint32");
    cluster.integers = cpca.cluster;
    Layer weights = makeLayer("transfer_cpca_weights", domain, "cpca_weights", {V, uint64_t(cpca.components)},
                              "float32");
    weights.data = std::move(cpca.weights);
    Layer basis = makeLayer("transfer_cpca_basis", "cluster", "cpca_mean_basis",
                            {uint64_t(clusters), uint64_t(cpca.components) + 1, uint64_t(order) * order, 3},
                            "float32");
    basis.data = std::move(cpca.basis);
    basis.params = params;
    std::vector<Layer> layers;
    layers.push_back(std::move(cluster));
    layers.push_back(std::move(weights));
    layers.push_back(std::move(basis));
    return layers;
}

// Each row's order under the prior `lightings`: options.perVertexBudget's per-row bound, else the rms budget,
// graded across `triangles` to options.maxStep; counts the rows the grading raised into the stats.
std::vector<uint8_t> adaptiveOrders(const std::vector<float>& full, size_t V, int order,
                                    const std::vector<uint32_t>& triangles,
                                    const std::vector<std::vector<float>>& lightings, const AdaptOptions& options,
                                    AdaptStats& stats) {
    std::vector<uint8_t> orders;
    if (options.perVertexBudget) {
        std::vector<float> error = truncationError(full.data(), V, order, lightings, options.prior);
        orders = selectOrders(error, V, order, options.maxError);
        stats.raisedBySmoothing = smoothOrdersWithinBound(triangles, orders, error, order, options.maxError, options.maxStep);
        return orders;
    }
    // Truncation error is not monotone in the order (bands can cancel), so grading can overshoot the budget: then
    // spend a smaller one until the graded field fits (at worst the full order, exact).
    std::vector<double> error = truncationErrorSquared(full.data(), V, order, lightings, options.prior);
    for (double budget = options.maxError;; budget *= 0.9) {
        orders = budgetOrders(error, lightings.size(), V, order, budget < 1e-4 * options.maxError ? 0.0 : budget);
        stats.raisedBySmoothing = smoothOrders(triangles, orders, options.maxStep);
        std::vector<float> truncated = denseTransfer(raggedTransfer(full.data(), V, order, orders));
        if (budget < 1e-4 * options.maxError ||
            priorRelativeRmse(truncated.data(), full.data(), V, order, lightings) <= options.maxError)
            break;
    }
    return orders;
}

// The stored layers of ragged rows (offsets, then the values as float or half, or codes and band scales, with
// per-cluster scales their cluster layer); `stored` receives the values as the runtime reads them back. The data
// layer's params are params plus the storage's keys.
std::vector<Layer> raggedLayers(const RaggedTransfer& ragged, const std::vector<float>& full, size_t V, int order,
                                const std::string& domain, const AdaptOptions& options, nlohmann::json& params,
                                std::vector<float>& stored) {
    params["offsets"] = "transfer_offsets";
    params["max_step"] = options.maxStep;
    Layer offsets = makeLayer("transfer_offsets", domain + "_offsets", "sh_coefficient_offsets", {V + 1}, "uint32");
    offsets.integers = ragged.offsets;
    const uint64_t rows = ragged.offsets[V];
    std::vector<Layer> layers;
    if (options.format == Format::Float || options.format == Format::Half) {
        Layer data = makeLayer("transfer_ragged", domain + "_ragged", "sh_transfer_rgb", {rows, 3},
                               options.format == Format::Float ? "float32" : "float16");
        data.data = ragged.values;
        if (options.format == Format::Half)
            for (float& value : data.data) value = halfToFloat(floatToHalf(value));
        stored = data.data;
        data.params = params;
        layers.push_back(std::move(offsets));
        layers.push_back(std::move(data));
        return layers;
    }
    const int bits = options.format == Format::U8 ? 8 : 16;
    std::vector<uint32_t> cluster;
    int clusters = 0;
    if (options.perClusterScales) {
        clusters = std::clamp<int>(options.clusters, 1, int(V));
        // Clusters of similar transfer magnitude share scales: k-means on the per-band norms.
        std::vector<float> norms(V * order);
        for (size_t v = 0; v < V; ++v) {
            std::vector<double> energy = sh::bandEnergy(order, full.data() + v * order * order * 3, 3);
            for (int l = 0; l < order; ++l) norms[v * order + l] = float(std::sqrt(energy[l]));
        }
        cluster = kMeans(norms.data(), V, order, clusters, 12);
    }
    QuantisedTransfer q = quantise(ragged, bits, cluster, clusters);
    stored = dequantise(ragged, q);
    params["bits"] = bits;
    params["scales"] = options.perClusterScales ? "per-cluster" : "per-vertex";
    params["scale_layer"] = "transfer_band_scales";
    Layer data = makeLayer("transfer_ragged", domain + "_ragged", "sh_transfer_rgb_quantised", {rows, 3},
                           bits == 8 ? "uint8" : "uint16");
    data.integers = std::move(q.codes);
    Layer scales = options.perClusterScales
                       ? makeLayer("transfer_band_scales", "cluster", "sh_band_scales",
                                   {uint64_t(clusters), uint64_t(order)}, "float16")
                       : makeLayer("transfer_band_scales", domain + "_bands", "sh_band_scales",
                                   {uint64_t(q.scales.size())}, "float16");
    scales.data = std::move(q.scales);
    if (options.perClusterScales) {
        params["cluster_layer"] = "transfer_scale_cluster";
        params["clusters"] = clusters;
        Layer clusterLayer = makeLayer("transfer_scale_cluster", domain, "cluster_index", {V},
                                       clusters <= 65536 ? "uint16" : "uint32");
        clusterLayer.integers = std::move(cluster);
        layers.push_back(std::move(clusterLayer));
    }
    data.params = params;
    layers.push_back(std::move(offsets));
    layers.push_back(std::move(scales));
    layers.push_back(std::move(data));
    return layers;
}

// The seam measure of the stored rows `dense` against the full rows under one lighting (both [V][order^2][3]).
SeamMeasure seamUnder(const std::vector<uint32_t>& triangles, const std::vector<uint8_t>& orders,
                    const std::vector<float>& dense, const std::vector<float>& full, size_t V, int order,
                    const std::vector<float>& lighting) {
    const size_t coefficients = size_t(order) * order;
    std::vector<float> a(V * 3, 0.0f), f(V * 3, 0.0f);
    for (size_t v = 0; v < V; ++v)
        for (int c = 0; c < 3; ++c) {
            double sa = 0.0, sf = 0.0;
            for (size_t j = 0; j < coefficients; ++j) {
                sa += double(dense[(v * coefficients + j) * 3 + c]) * lighting[j * 3 + c];
                sf += double(full[(v * coefficients + j) * 3 + c]) * lighting[j * 3 + c];
            }
            a[v * 3 + c] = float(sa), f[v * 3 + c] = float(sf);
        }
    return seamMeasure(triangles, orders, a.data(), f.data());
}

} // namespace

AdaptStats adaptBundle(Bundle& bundle, const std::vector<std::vector<float>>& inputLightings, const AdaptOptions& options,
                       const std::string& source) {
    TransferInput in = takeTransferInput(bundle, source);
    Layer& input = in.layer;
    const size_t V = in.rows;
    int order = in.order;
    const uint64_t inputBytes = uint64_t(input.data.size()) * 4;
    const std::vector<float> inputFull = input.data;
    const int inputOrder = order;
    if (options.order > 0 && options.order < order) { // uniform truncation first; everything below sees order N
        const size_t from = size_t(order) * order * 3, to = size_t(options.order) * options.order * 3;
        for (size_t v = 0; v < V; ++v) std::copy_n(input.data.begin() + v * from, to, input.data.begin() + v * to);
        input.data.resize(V * to);
        order = options.order;
    }
    const bool adaptive = options.order <= 0;
    if (inputLightings.empty() && (adaptive || (options.format == Format::Cpca && options.components <= 0)))
        throw Error(source, "--env", "the lighting prior needs at least one map", kExitUsage);
    for (const std::vector<float>& lighting : inputLightings)
        if (lighting.size() != size_t(inputOrder) * inputOrder * 3)
            throw Error(source, "--env", "lighting of the wrong order for the transfer", kExitFailure);
    // The prior at the working order (its first bands), and the error of what is stored against the input itself.
    std::vector<std::vector<float>> lightings;
    for (const std::vector<float>& lighting : inputLightings)
        lightings.push_back(std::vector<float>(lighting.begin(), lighting.begin() + size_t(order) * order * 3));
    auto error = [&](const std::vector<float>& dense) {
        return errorAgainstInput(dense, order, inputFull, inputOrder, V, inputLightings);
    };

    AdaptStats stats;
    stats.vertexCount = V;
    stats.fullOrder = inputOrder;
    stats.fullLayerBytes = inputBytes;
    stats.orderHistogram.assign(inputOrder + 1, 0);
    const std::vector<float>& full = input.data;

    nlohmann::json params = {{"order", order},
                             {"format", formatName(options.format)},
                             {"max_error", adaptive ? nlohmann::json(options.maxError) : nlohmann::json()},
                             {"uniform_order", adaptive ? nlohmann::json() : nlohmann::json(order)},
                             {"prior", priorName(options.prior)},
                             {"budget", options.perVertexBudget ? "vertex" : "rms"},
                             {"lightings", options.lightingNames},
                             {"transfer", input.params}};
    if (in.texels) params["width"] = in.width, params["height"] = in.height;
    std::vector<Layer> added;
    if (options.format == Format::Cpca) {
        added = cpcaLayers(full, V, order, in.domain, options, error, params, stats);
    } else {
        std::vector<uint8_t> orders =
            adaptive ? adaptiveOrders(full, V, order, in.triangles, lightings, options, stats)
                     : std::vector<uint8_t>(V, uint8_t(order));
        RaggedTransfer ragged = raggedTransfer(full.data(), V, order, orders);
        double orderSum = 0.0;
        for (uint8_t n : orders) ++stats.orderHistogram[n], orderSum += n;
        stats.meanOrder = V ? orderSum / double(V) : 0.0;
        stats.meanCoefficients = V ? double(ragged.offsets[V]) / double(V) : 0.0;
        std::vector<float> stored;
        added = raggedLayers(ragged, full, V, order, in.domain, options, params, stored);
        std::vector<float> dense = denseTransfer(ragged, &stored);
        stats.relativeRmse = error(dense);
        for (const std::vector<float>& lighting : lightings)
            stats.seams.push_back(seamUnder(in.triangles, orders, dense, full, V, order, lighting));
    }
    for (Layer& layer : added) {
        stats.layerBytes += layerBytes(layer);
        bundle.layers.push_back(std::move(layer));
    }
    bundle.producer["stage"] = "adapt";
    return stats;
}

} // namespace prt::adapt
