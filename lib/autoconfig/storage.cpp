// What a configuration's bundle stores: its transfer layers' bytes and the rows the runtime decodes from them,
// by lib/adapt's own layout and quantiser, so the pilot's error includes the format's.
#include "autoconfig.h"

#include "core.h"

#include <algorithm>

namespace prt::autoconfig {

uint64_t bundleLayerBytes(size_t vertexCount, int order, adapt::Format format, int bounces) {
    const uint64_t V = vertexCount, values = V * uint64_t(order) * order * 3;
    const uint64_t offsets = (V + 1) * 4, scales = V * uint64_t(order) * 2; // uint32; float16 per vertex and band
    switch (format) {
    case adapt::Format::Float: return bounces > 0 ? offsets + values * 4 : values * 4;
    case adapt::Format::Half: return offsets + values * 2;
    case adapt::Format::U16: return offsets + scales + values * 2;
    case adapt::Format::U8: return offsets + scales + values;
    case adapt::Format::Cpca: break;
    }
    throw Error("", "--formats", "cpca is not modelled by autoconfig (its error depends on the whole mesh's clusters)",
                kExitUsage);
}

uint64_t raggedLayerBytes(size_t vertexCount, uint64_t coefficients, uint64_t bands, adapt::Format format) {
    const uint64_t offsets = (uint64_t(vertexCount) + 1) * 4, values = coefficients * 3;
    switch (format) {
    case adapt::Format::Float: return offsets + values * 4;
    case adapt::Format::Half: return offsets + values * 2;
    case adapt::Format::U16: return offsets + bands * 2 + values * 2;
    case adapt::Format::U8: return offsets + bands * 2 + values;
    case adapt::Format::Cpca: break;
    }
    throw Error("", "--formats", "cpca is not modelled by autoconfig", kExitUsage);
}

std::vector<float> storedRows(const float* rows, size_t count, int strideOrder, int order, adapt::Format format,
                              const std::vector<uint8_t>* orders) {
    const size_t from = size_t(strideOrder) * strideOrder * 3, to = size_t(order) * order * 3;
    std::vector<float> truncated(count * to);
    for (size_t v = 0; v < count; ++v) std::copy_n(rows + v * from, to, truncated.begin() + v * to);
    if (format == adapt::Format::Cpca) throw Error("", "--formats", "cpca is not modelled by autoconfig", kExitUsage);
    const std::vector<uint8_t> uniform(orders ? 0 : count, uint8_t(order));
    adapt::RaggedTransfer ragged = adapt::raggedTransfer(truncated.data(), count, order, orders ? *orders : uniform);
    std::vector<float> decoded;
    if (format == adapt::Format::Float) return adapt::denseTransfer(ragged);
    if (format == adapt::Format::Half) {
        decoded = ragged.values;
        for (float& value : decoded) value = halfToFloat(floatToHalf(value));
    } else {
        adapt::QuantisedTransfer q = adapt::quantise(ragged, format == adapt::Format::U8 ? 8 : 16, {}, 0);
        decoded = adapt::dequantise(ragged, q);
    }
    return adapt::denseTransfer(ragged, &decoded);
}

} // namespace prt::autoconfig
