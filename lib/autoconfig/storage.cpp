// What a configuration's bundle stores: its transfer layers' bytes and the rows the runtime decodes from them,
// by lib/adapt's own layout and quantiser, so the pilot's error includes the format's.
#include "autoconfig.h"

#include "core.h"

#include <algorithm>

namespace prt::autoconfig {

uint64_t bundleLayerBytes(size_t vertexCount, int order, adapt::Format format) {
    const uint64_t V = vertexCount, values = V * uint64_t(order) * order * 3;
    const uint64_t offsets = (V + 1) * 4, scales = V * uint64_t(order) * 2; // uint32; float16 per vertex and band
    switch (format) {
    case adapt::Format::Float: return values * 4;           // the transfer stage's "transfer" layer
    case adapt::Format::Half: return offsets + values * 2;
    case adapt::Format::U16: return offsets + scales + values * 2;
    case adapt::Format::U8: return offsets + scales + values;
    case adapt::Format::Cpca: break;
    }
    throw Error("", "--formats", "cpca is not modelled by autoconfig (its error depends on the whole mesh's clusters)",
                kExitUsage);
}

std::vector<float> storedRows(const float* rows, size_t count, int strideOrder, int order, adapt::Format format) {
    const size_t from = size_t(strideOrder) * strideOrder * 3, to = size_t(order) * order * 3;
    std::vector<float> truncated(count * to);
    for (size_t v = 0; v < count; ++v) std::copy_n(rows + v * from, to, truncated.begin() + v * to);
    switch (format) {
    case adapt::Format::Float: return truncated;
    case adapt::Format::Half:
        for (float& value : truncated) value = halfToFloat(floatToHalf(value));
        return truncated;
    case adapt::Format::U16:
    case adapt::Format::U8: {
        const std::vector<uint8_t> orders(count, uint8_t(order));
        adapt::RaggedTransfer ragged = adapt::raggedTransfer(truncated.data(), count, order, orders);
        adapt::QuantisedTransfer q = adapt::quantise(ragged, format == adapt::Format::U8 ? 8 : 16, {}, 0);
        const std::vector<float> decoded = adapt::dequantise(ragged, q);
        return adapt::denseTransfer(ragged, &decoded);
    }
    case adapt::Format::Cpca: break;
    }
    throw Error("", "--formats", "cpca is not modelled by autoconfig", kExitUsage);
}

} // namespace prt::autoconfig
