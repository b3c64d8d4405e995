// The relighting kernel: per vertex, a dot product of its transfer row with the lighting, per channel. The lane
// loop here defines the order of additions; where the processor has AVX2, orders 1..5 run relight_vector.cpp's
// kernel, which keeps that order lane for lane, and this loop relights the rest (orders past 5, an odd order's last
// row, processors without AVX2).
#include "runtime.h"

#include "core.h"
#include "runtime_internal.h"

#include <algorithm>
#include <vector>

namespace prt {

#if PRT_HAVE_AVX2_CLONE
bool processorHasAvx2() {
    static const bool yes = __builtin_cpu_supports("avx2");
    return yes;
}
#endif

namespace {

// Accumulator lanes: a multiple of 3, so lane i always holds channel i % 3 of [coefficient][3] rows, and of 4,
// so they fill whole SSE registers. 12 measured faster than 24 at orders 3 and 5 (fewer lanes to reduce per
// vertex) and equal at order 8, where the kernel runs at the memory bandwidth (tests/runtime/bench_runtime).
constexpr int kLanes = 12;
// Measured on this loop before the vector kernel took orders 1..5 on AVX2: rows of up to 48 values (orders 1..4)
// read 4 KB ahead: at order 3 the hardware prefetcher alone left the loop at 0.78-0.90 of the rate its bytes
// stream, one prefetch per row brings it to 1.1-1.5 (tests/runtime/bench_runtime); longer rows stream as fast
// without (a prefetch of one line per row of 5-12 lines measured slower). Calls of at most 4096 floats
// (relight_encoded.cpp's decode tiles, already in L1) do not prefetch.
constexpr uintptr_t kPrefetchBytes = 4096;

// `kValues` (coefficients * 3) known at compile time lets the compiler unroll the common orders completely;
// 0 means take it from `values`. Every instantiation adds in the same order, so they agree bit for bit.
template <int kValues>
PRT_ALWAYS_INLINE inline void relightRowsBody(const float* transfer, size_t vertexCount, int values,
                                              const float* lighting, float* radiance) {
    if constexpr (kValues != 0) values = kValues;
    const bool prefetch = kValues > 0 && kValues <= 48 && vertexCount * size_t(values) > 4096;
    for (size_t v = 0; v < vertexCount; ++v) {
        const float* row = transfer + v * size_t(values);
        if (prefetch)
            __builtin_prefetch(reinterpret_cast<const char*>(uintptr_t(row) + kPrefetchBytes));
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

// The kernel compiled for the baseline and, where the processor has it, for AVX2: wider registers over the same
// lanes, each lane the same multiplies and adds in the same order (AVX2 without FMA, so nothing is contracted), so
// both give the same bits on every input.
template <int kValues>
void relightRowsBase(const float* transfer, size_t vertexCount, int values, const float* lighting, float* radiance) {
    relightRowsBody<kValues>(transfer, vertexCount, values, lighting, radiance);
}
#if PRT_HAVE_AVX2_CLONE
template <int kValues>
__attribute__((target("avx2"))) void relightRowsAvx2(const float* transfer, size_t vertexCount, int values,
                                                     const float* lighting, float* radiance) {
    relightRowsBody<kValues>(transfer, vertexCount, values, lighting, radiance);
}
template <int kValues>
void relightRows(const float* transfer, size_t vertexCount, int values, const float* lighting, float* radiance) {
    (processorHasAvx2() ? relightRowsAvx2<kValues> : relightRowsBase<kValues>)(transfer, vertexCount, values,
                                                                                lighting, radiance);
}
#else
template <int kValues>
void relightRows(const float* transfer, size_t vertexCount, int values, const float* lighting, float* radiance) {
    relightRowsBase<kValues>(transfer, vertexCount, values, lighting, radiance);
}
#endif

} // namespace

void relight(const float* transfer, size_t vertexCount, int coefficientCount, const float* lighting,
             float* radiance) {
    if (coefficientCount < 1)
        throw Error("", "relight", std::to_string(coefficientCount) + " coefficients per row (at least 1)", kExitFailure);
    // Where the processor has AVX2, orders 1..5 take the vector kernel (the same bits), all but an odd order's
    // last row.
    const size_t done = relightFloatRows(transfer, vertexCount, coefficientCount, lighting, radiance);
    transfer += done * size_t(coefficientCount) * 3, radiance += done * 3, vertexCount -= done;
    if (vertexCount == 0) return;
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

namespace {

// What each task of relight(model, ...) needs: the same for every task, so tasks differ only by their block.
struct RelightTasks {
    const RelightModel* model;
    const float* lighting;
    const float* projections; // Cpca: [clusters][components + 1][4]
    const U8Lighting* quantised; // blocked u8 codes: the lighting quantised once (quantiseU8Lighting), else null
    size_t begin, end;
    float* radiance;
};

void relightTask(void* data, size_t index) {
    const RelightTasks& tasks = *static_cast<const RelightTasks*>(data);
    const RelightModel& model = *tasks.model;
    const size_t block = tasks.begin / kRelightBlock + index; // task `index`: the part of [begin, end) in this block
    const size_t first = std::max(tasks.begin, block * kRelightBlock);
    const size_t last = std::min(tasks.end, (block + 1) * kRelightBlock);
    float* out = tasks.radiance + (first - tasks.begin) * 3;
    if (model.storage == TransferStorage::Cpca)
        relightCpcaRange(model, tasks.projections, first, last, out);
    else if (!model.offsets.empty())
        relightRaggedRange(model, tasks.lighting, first, last, out, tasks.quantised);
    else
        relight(model.transfer.data() + first * size_t(model.order) * model.order * 3, last - first,
                model.order * model.order, tasks.lighting, out);
    if (!model.albedo.empty())
        for (size_t i = 0; i < (last - first) * 3; ++i) out[i] *= model.albedo[first * 3 + i];
}

} // namespace

void relight(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance,
             const JobSystem& jobs) {
    checkRelightCall(model, begin, end, "relight");
    if (begin == end) return; // nothing to relight: the lighting is not read
    // Cpca: each cluster's mean and directions projected on the lighting once, before any task runs; blocked u8
    // codes: the lighting quantised once.
    std::vector<float> projections;
    if (model.storage == TransferStorage::Cpca) projections = cpcaProjections(model, lighting);
    U8Lighting quantised;
    const bool u8Blocked = model.rowsBlocked && model.storage == TransferStorage::Uint8;
    if (u8Blocked) quantised = quantiseU8Lighting(lighting, model.order);
    RelightTasks tasks{&model, lighting, projections.data(), u8Blocked ? &quantised : nullptr, begin, end, radiance};
    // Blocks of kRelightBlock vertices keep the scheduling overhead far below the memory traffic; the caller's job
    // system (or the calling thread) runs them, so the runtime itself never starts a thread. A task is the part of
    // [begin, end) in one block counted from vertex 0, the unit of the graded blocked rows' layout.
    const size_t tasksCount = (end - 1) / kRelightBlock - begin / kRelightBlock + 1;
    runTasks(jobs, tasksCount, relightTask, &tasks);
}

} // namespace prt
