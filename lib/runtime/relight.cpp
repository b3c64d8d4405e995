// The relighting kernel: per vertex, a dot product of its transfer row with the lighting, per channel.
#include "runtime.h"

#include "core.h"

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace prt {

namespace {

// Accumulator lanes: a multiple of 3, so lane i always holds channel i % 3 of [coefficient][3] rows, and of 4,
// so they fill whole SSE registers. 12 measured faster than 24 at orders 3 and 5 (fewer lanes to reduce per
// vertex) and equal at order 8, where the kernel runs at the memory bandwidth (tests/runtime/bench_runtime).
constexpr int kLanes = 12;

// `kValues` (coefficients * 3) known at compile time lets the compiler unroll the common orders completely;
// 0 means take it from `values`. Every instantiation adds in the same order, so they agree bit for bit.
template <int kValues>
void relightRows(const float* transfer, size_t vertexCount, int values, const float* lighting, float* radiance) {
    if constexpr (kValues != 0) values = kValues;
    for (size_t v = 0; v < vertexCount; ++v) {
        const float* row = transfer + v * size_t(values);
        float sum[kLanes] = {};
        int k = 0;
        for (; k + kLanes <= values; k += kLanes)
            for (int i = 0; i < kLanes; ++i) sum[i] += row[k + i] * lighting[k + i];
        for (int i = 0; k + i < values; ++i) sum[i] += row[k + i] * lighting[k + i];
        // Fold the lanes in halves, which keeps each lane's channel: 12 -> 6 -> 3.
        for (int i = 0; i < 6; ++i) sum[i] += sum[i + 6];
        for (int c = 0; c < 3; ++c) radiance[v * 3 + c] = sum[c] + sum[c + 3];
    }
}

} // namespace

void relight(const float* transfer, size_t vertexCount, int coefficientCount, const float* lighting,
             float* radiance) {
    switch (coefficientCount) {
    case 9: return relightRows<27>(transfer, vertexCount, 27, lighting, radiance);
    case 16: return relightRows<48>(transfer, vertexCount, 48, lighting, radiance);
    case 25: return relightRows<75>(transfer, vertexCount, 75, lighting, radiance);
    case 36: return relightRows<108>(transfer, vertexCount, 108, lighting, radiance);
    case 49: return relightRows<147>(transfer, vertexCount, 147, lighting, radiance);
    case 64: return relightRows<192>(transfer, vertexCount, 192, lighting, radiance);
    default: return relightRows<0>(transfer, vertexCount, coefficientCount * 3, lighting, radiance);
    }
}

void relight(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance) {
    if (begin > end || end > model.vertexCount)
        throw Error("", "relight", "vertex range [" + std::to_string(begin) + ", " + std::to_string(end) +
                                       ") outside the model's " + std::to_string(model.vertexCount) + " vertices",
                    kExitFailure);
    if (!model.offsets.empty()) return relightAdaptive(model, lighting, begin, end, radiance);
    const int coefficients = sh::coefficientCount(model.order);
    const size_t rowValues = size_t(coefficients) * 3;
    // Blocks of a few thousand vertices keep the scheduling overhead far below the memory traffic; std::threads
    // rather than TBB keep the installed runtime free of it.
    constexpr size_t kBlock = 4096;
    const size_t count = end - begin, blocks = (count + kBlock - 1) / kBlock;
    std::atomic<size_t> nextBlock{0};
    auto relightBlocks = [&] {
        for (size_t block; (block = nextBlock.fetch_add(1)) < blocks;) {
            size_t first = begin + block * kBlock, last = std::min(end, first + kBlock);
            float* out = radiance + (first - begin) * 3;
            relight(model.transfer.data() + first * rowValues, last - first, coefficients, lighting, out);
            if (!model.albedo.empty())
                for (size_t i = 0; i < (last - first) * 3; ++i) out[i] *= model.albedo[first * 3 + i];
        }
    };
    size_t workers = std::min<size_t>(blocks, std::max(1u, std::thread::hardware_concurrency()));
    std::vector<std::thread> pool;
    for (size_t i = 1; i < workers; ++i) pool.emplace_back(relightBlocks);
    relightBlocks();
    for (std::thread& thread : pool) thread.join();
}

} // namespace prt
