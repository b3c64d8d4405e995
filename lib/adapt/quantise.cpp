// Per-band quantisation of a ragged transfer to 8 or 16 bit codes with per-vertex or per-cluster scales.
#include "adapt.h"

#include "core.h"

#include <algorithm>
#include <cmath>

namespace prt::adapt {

namespace {

// The smallest float16 value >= value (value >= 0, below the half range).
float halfAtLeast(float value) {
    float rounded = halfToFloat(floatToHalf(value));
    if (rounded >= value) return rounded;
    return halfToFloat(uint16_t(floatToHalf(value) + 1)); // positive halves are ordered like their bits
}

} // namespace

QuantisedTransfer quantise(const RaggedTransfer& ragged, int bits, const std::vector<uint32_t>& cluster,
                           int clusterCount) {
    if (bits != 8 && bits != 16) throw Error("", "quantise", "bits must be 8 or 16", kExitFailure);
    const size_t vertexCount = ragged.offsets.size() - 1;
    const bool perCluster = !cluster.empty();
    QuantisedTransfer q;
    q.bits = bits;
    q.cluster = cluster;
    q.clusterCount = perCluster ? clusterCount : 0;
    const int order = ragged.order;

    // Band offsets of the per-vertex scales.
    std::vector<size_t> bandOffset(vertexCount + 1, 0);
    for (size_t v = 0; v < vertexCount; ++v) bandOffset[v + 1] = bandOffset[v] + vertexOrder(ragged, v);
    q.scales.assign(perCluster ? size_t(clusterCount) * order : bandOffset[vertexCount], 0.0f);
    auto scaleIndex = [&](size_t v, int l) { return perCluster ? size_t(cluster[v]) * order + l : bandOffset[v] + l; };

    for (size_t v = 0; v < vertexCount; ++v) {
        const float* row = ragged.values.data() + size_t(ragged.offsets[v]) * 3;
        for (int l = 0; l < vertexOrder(ragged, v); ++l) {
            float& scale = q.scales[scaleIndex(v, l)];
            for (int j = l * l; j < (l + 1) * (l + 1); ++j)
                for (int c = 0; c < 3; ++c) scale = std::max(scale, std::fabs(row[j * 3 + c]));
        }
    }
    for (float& scale : q.scales) scale = halfAtLeast(scale);

    const double centre = double((1u << (bits - 1)) - 1);
    q.codes.resize(ragged.values.size());
    for (size_t v = 0; v < vertexCount; ++v) {
        const size_t base = size_t(ragged.offsets[v]) * 3;
        for (int l = 0; l < vertexOrder(ragged, v); ++l) {
            double scale = q.scales[scaleIndex(v, l)];
            for (int j = l * l; j < (l + 1) * (l + 1); ++j)
                for (int c = 0; c < 3; ++c) {
                    double x = ragged.values[base + j * 3 + c];
                    double code = scale > 0.0 ? std::nearbyint(x / scale * centre) + centre : centre;
                    q.codes[base + j * 3 + c] = uint32_t(std::clamp(code, 0.0, 2.0 * centre));
                }
        }
    }
    return q;
}

std::vector<float> dequantise(const RaggedTransfer& layout, const QuantisedTransfer& q) {
    const size_t vertexCount = layout.offsets.size() - 1;
    const float centre = float((1u << (q.bits - 1)) - 1);
    std::vector<float> values(q.codes.size());
    size_t bandOffset = 0;
    for (size_t v = 0; v < vertexCount; ++v) {
        const size_t base = size_t(layout.offsets[v]) * 3;
        const int order = vertexOrder(layout, v);
        for (int l = 0; l < order; ++l) {
            float scale = q.cluster.empty() ? q.scales[bandOffset + l] : q.scales[size_t(q.cluster[v]) * layout.order + l];
            for (int j = l * l; j < (l + 1) * (l + 1); ++j)
                for (int c = 0; c < 3; ++c)
                    values[base + j * 3 + c] = (float(q.codes[base + j * 3 + c]) - centre) * scale / centre;
        }
        bandOffset += order;
    }
    return values;
}

} // namespace prt::adapt
