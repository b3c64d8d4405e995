// The thesis's 8-bit storage: each layer mapped linearly from its own [min, max] onto 0..255.
#include "bake.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace prt {

RangeCompressed rangeCompress(const float* texels, size_t texelCount, int layers, int channelsPerLayer) {
    int channels = layers * channelsPerLayer;
    RangeCompressed out;
    out.range.resize(2 * size_t(layers));
    out.values.resize(texelCount * channels);
    for (int layer = 0; layer < layers; ++layer) {
        float lo = std::numeric_limits<float>::infinity(), hi = -lo;
        for (size_t t = 0; t < texelCount; ++t)
            for (int c = 0; c < channelsPerLayer; ++c) {
                float value = texels[t * channels + layer * channelsPerLayer + c];
                lo = std::min(lo, value);
                hi = std::max(hi, value);
            }
        if (texelCount == 0) lo = hi = 0.0f;
        out.range[2 * layer] = lo;
        out.range[2 * layer + 1] = hi;
        double scale = hi > lo ? 255.0 / (double(hi) - lo) : 0.0;
        for (size_t t = 0; t < texelCount; ++t)
            for (int c = 0; c < channelsPerLayer; ++c) {
                size_t i = t * channels + layer * channelsPerLayer + c;
                out.values[i] = uint8_t(std::lround(std::clamp((double(texels[i]) - lo) * scale, 0.0, 255.0)));
            }
    }
    return out;
}

std::vector<float> rangeExpand(const RangeCompressed& compressed, size_t texelCount, int layers,
                               int channelsPerLayer) {
    int channels = layers * channelsPerLayer;
    std::vector<float> texels(texelCount * channels);
    for (int layer = 0; layer < layers; ++layer) {
        double lo = compressed.range[2 * layer], step = (compressed.range[2 * layer + 1] - lo) / 255.0;
        for (size_t t = 0; t < texelCount; ++t)
            for (int c = 0; c < channelsPerLayer; ++c) {
                size_t i = t * channels + layer * channelsPerLayer + c;
                texels[i] = float(lo + compressed.values[i] * step);
            }
    }
    return texels;
}

} // namespace prt
