// The vector kernels (AVX2): float rows of 1..5 bands and half rows of 1..8, the halves converted by F16C inside the
// dot product with no decoded row in memory, two vertices folded at a time; and vertex-blocked half rows
// (blockRows), 8 vertices at a time. Both are bit for bit the float kernel (relight.cpp) on the same (decoded) rows.
// Processors without AVX2 (and F16C, for halves) take relight.cpp's lane loop for floats and relight_encoded.cpp's
// decode tile for halves (which blockRows then leaves row by row).
#include "runtime.h"

#include "runtime_internal.h"

#include <cstring>

#if PRT_HAVE_AVX2_CLONE
#include <cpuid.h>
#include <immintrin.h>
#endif

// The kernel's vectors are passed only between inlined functions, never across an ABI boundary.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace prt {

#if PRT_HAVE_AVX2_CLONE

namespace {

typedef float V8f __attribute__((vector_size(32)));
typedef float V4f __attribute__((vector_size(16)));
typedef int V4i __attribute__((vector_size(16)));

#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2,f16c"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2,f16c")
#endif

// 8 and 4 consecutive row values as floats: halves converted (exactly), floats as they are.
PRT_ALWAYS_INLINE inline V8f load8(const uint16_t* h) {
    return V8f(_mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(h))));
}
PRT_ALWAYS_INLINE inline V4f load4(const uint16_t* h) {
    return V4f(_mm_cvtph_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(h))));
}
PRT_ALWAYS_INLINE inline float load1(const uint16_t* h) { return _cvtsh_ss(*h); }
PRT_ALWAYS_INLINE inline float load1(const float* f) { return *f; }
PRT_ALWAYS_INLINE inline V8f load8(const float* f) {
    V8f x;
    std::memcpy(&x, f, sizeof x);
    return x;
}
PRT_ALWAYS_INLINE inline V4f load4(const float* f) {
    V4f x;
    std::memcpy(&x, f, sizeof x);
    return x;
}

#include "relight_blocks.inc"

// The float kernel's 12 accumulator lanes (relight.cpp: lane i sums values i, i + 12, i + 24, ... of the row, from
// +0, each product rounded, then added) held as lanes 0..7 in `a` and 8..11 in `b`: the same products and the same
// additions, lane for lane in the same order, and half->float is exact, so every lane has the float kernel's bits.
// Odd n leave 3 values (3 n^2 = 3 mod 12) for lanes 0..2: a 4-value load (one value past the row) whose fourth
// product is masked to +0 (whatever it was, NaN included), and lanes 3..7 add +0, which leaves them as they are: a
// lane that starts at +0 is never -0 (x + y is -0 only when both are), and x + (+0) = x for every other x.
template <typename T, int kValues>
struct Rows {
    static constexpr int kFull = kValues / 12, kTail = kValues % 12;
    static_assert(kTail == 0 || kTail == 3, "rows of 3 n^2 values");
    V8f lightA[kFull > 0 ? kFull : 1];
    V4f lightB[kFull > 0 ? kFull : 1], lightTail = {};

    explicit Rows(const float* lighting) {
        for (int k = 0; k < kFull; ++k) {
            std::memcpy(&lightA[k], lighting + 12 * k, sizeof(V8f));
            std::memcpy(&lightB[k], lighting + 12 * k + 8, sizeof(V4f));
        }
        std::memcpy(&lightTail, lighting + 12 * kFull, sizeof(float) * kTail);
    }
    PRT_ALWAYS_INLINE void accumulate(const T* row, V8f& a, V4f& b) const {
        a = V8f{};
        b = V4f{};
#pragma GCC unroll 16
        for (int k = 0; k < kFull; ++k) {
            a += load8(row + 12 * k) * lightA[k];
            b += load4(row + 12 * k + 8) * lightB[k];
        }
        if constexpr (kTail != 0) {
            const V4i tailMask = {-1, -1, -1, 0};
            const V4f t = V4f(V4i(load4(row + 12 * kFull) * lightTail) & tailMask);
            a += __builtin_shufflevector(t, V4f{}, 0, 1, 2, 3, 4, 5, 6, 7);
        }
    }
};

// The fold is the float kernel's: lanes 0..5 += 6..11, then channel c = lane c + lane c + 3; two vertices at a time
// (one in each 128-bit half), then the last one or two alone. Rows up to 256 bytes prefetch every line 24 rows
// ahead, as the code kernel does.
template <typename T, int kValues>
void relightRowsKernel(const T* __restrict rowValues, size_t vertexCount, const float* __restrict lighting,
                       float* __restrict radiance) {
    const Rows<T, kValues> rows(lighting);
    constexpr size_t kRowBytes = sizeof(T) * kValues;
    auto prefetch = [](const T* row) PRT_ALWAYS_INLINE {
        if constexpr (kRowBytes <= 256)
            for (size_t line = 0; line < kRowBytes; line += 64)
                __builtin_prefetch(reinterpret_cast<const char*>(uintptr_t(row) + 24 * kRowBytes + line));
    };
    size_t v = 0;
    for (; v + 2 < vertexCount; v += 2) { // a vertex follows the pair, so its 4-float stores stay inside radiance
        const T* row = rowValues + v * kValues;
        prefetch(row);
        prefetch(row + kValues);
        V8f a0, a1;
        V4f b0, b1;
        rows.accumulate(row, a0, b0);
        rows.accumulate(row + kValues, a1, b1);
        const V8f x = __builtin_shufflevector(a0, a1, 0, 1, 2, 3, 8, 9, 10, 11); // lanes 0..3 of each
        const V8f y = __builtin_shufflevector(a0, a1, 4, 5, 6, 7, 12, 13, 14, 15); // lanes 4..7
        const V8f z = __builtin_shufflevector(b0, b1, 0, 1, 2, 3, 4, 5, 6, 7); // lanes 8..11
        const V8f s03 = x + __builtin_shufflevector(y, z, 2, 3, 8, 9, 6, 7, 12, 13); // lanes 0..3 += 6..9
        const V8f s45 = y + __builtin_shufflevector(z, z, 2, 3, 2, 3, 6, 7, 6, 7);    // lanes 4, 5 += 10, 11
        const V8f out = s03 + __builtin_shufflevector(s03, s45, 3, 8, 9, 9, 7, 12, 13, 13);
        V4f lo = __builtin_shufflevector(out, out, 0, 1, 2, 3), hi = __builtin_shufflevector(out, out, 4, 5, 6, 7);
        std::memcpy(radiance + v * 3, &lo, sizeof lo); // its fourth float is overwritten next
        std::memcpy(radiance + v * 3 + 3, &hi, sizeof hi);
    }
    for (; v < vertexCount; ++v) {
        V8f a;
        V4f b;
        rows.accumulate(rowValues + v * kValues, a, b);
        const V4f lo = __builtin_shufflevector(a, a, 0, 1, 2, 3), hi = __builtin_shufflevector(a, a, 4, 5, 6, 7);
        const V4f s03 = lo + __builtin_shufflevector(hi, b, 2, 3, 4, 5);
        const V4f s45 = hi + __builtin_shufflevector(b, b, 2, 3, 2, 3);
        const V4f out = s03 + __builtin_shufflevector(s03, s45, 3, 4, 5, 5);
        radiance[v * 3] = out[0];
        radiance[v * 3 + 1] = out[1];
        radiance[v * 3 + 2] = out[2];
    }
}

// One band: the float kernel's ((0 + x_c L_c) + 0) + (0 + 0) is x_c L_c + 0 (+0 for -0, else x_c L_c), so the
// radiance is the values times the lighting repeated, plus +0, over the whole run as one contiguous array.
template <typename T>
void relightBand0(const T* __restrict values, size_t vertexCount, const float* __restrict lighting,
                  float* __restrict radiance) {
    const float L0 = lighting[0], L1 = lighting[1], L2 = lighting[2];
    const V8f l0 = {L0, L1, L2, L0, L1, L2, L0, L1}, l1 = {L2, L0, L1, L2, L0, L1, L2, L0},
              l2 = {L1, L2, L0, L1, L2, L0, L1, L2}, zero = {};
    const size_t total = vertexCount * 3;
    size_t i = 0;
    for (; i + 24 <= total; i += 24) {
        const V8f r0 = load8(values + i) * l0 + zero, r1 = load8(values + i + 8) * l1 + zero,
                  r2 = load8(values + i + 16) * l2 + zero;
        std::memcpy(radiance + i, &r0, sizeof r0);
        std::memcpy(radiance + i + 8, &r1, sizeof r1);
        std::memcpy(radiance + i + 16, &r2, sizeof r2);
    }
    for (; i < total; ++i) radiance[i] = load1(values + i) * lighting[i % 3] + 0.0f;
}

// Vertex-blocked half rows (RelightModel::rowsBlocked; value j of the block's 8 vertices side by side), a run as
// relightBlockRun takes it. Lane i is one vertex, and holds the float kernel's 12 accumulators (relight.cpp)
// in 12 vectors: acc[j % 12] += x_j * L_j for j in row order, from +0, each product rounded, then added; then
// lanes 0..5 += 6..11 and channel c = acc[c] + acc[c + 3]. Those are the float kernel's operations in its order, and
// half->float is exact, so every vertex has the float kernel's bits on its decoded row. Prefetch 2 KB ahead, as the
// u16 codes' blocked kernel.
template <int kN>
void relightBlockedHalvesKernel(const uint16_t* __restrict halves, size_t blocks, size_t base,
                                const uint16_t* __restrict lanes, size_t first, size_t last,
                                const float* __restrict lighting, float* __restrict radiance) {
    constexpr int kValues = 3 * kN * kN;
    V8f light[kValues];
    for (int j = 0; j < kValues; ++j) light[j] = V8f{} + lighting[j];
    auto sums = [&](const uint16_t* q, const float*, V8f* sum) PRT_ALWAYS_INLINE {
        V8f acc[12] = {};
        unrolled(std::make_index_sequence<kValues>{}, [&](auto jc) PRT_ALWAYS_INLINE {
            constexpr size_t j = decltype(jc)::value;
            acc[j % 12] += load8(q + j * kCodeBlock) * light[j];
        });
        for (int i = 0; i < 6; ++i) acc[i] += acc[i + 6];
        for (int c = 0; c < 3; ++c) sum[c] = acc[c] + acc[c + 3];
    };
    relightBlockRun<uint16_t, kN, 0, 2048>(halves, nullptr, blocks, base, lanes, first, last, sums, radiance);
}

// Vertices [0, vertexCount) of rows of `count` coefficients (n^2, n in 1..8); false, with nothing written, for
// other counts.
template <typename T>
bool relightRowsVector(const T* values, size_t vertexCount, int count, const float* lighting, float* radiance) {
    switch (count) {
    case 1: relightBand0(values, vertexCount, lighting, radiance); return true;
    case 4: relightRowsKernel<T, 12>(values, vertexCount, lighting, radiance); return true;
    case 9: relightRowsKernel<T, 27>(values, vertexCount, lighting, radiance); return true;
    case 16: relightRowsKernel<T, 48>(values, vertexCount, lighting, radiance); return true;
    case 25: relightRowsKernel<T, 75>(values, vertexCount, lighting, radiance); return true;
    case 36: relightRowsKernel<T, 108>(values, vertexCount, lighting, radiance); return true;
    case 49: relightRowsKernel<T, 147>(values, vertexCount, lighting, radiance); return true;
    case 64: relightRowsKernel<T, 192>(values, vertexCount, lighting, radiance); return true;
    default: return false;
    }
}

#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

// AVX2 (which includes the OS saving the YMM state) and F16C, CPUID leaf 1 ECX bit 29 (bit_F16C; clang's
// __builtin_cpu_supports does not know "f16c").
bool haveF16c() {
    static const bool yes = [] {
        unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
        return processorHasAvx2() && __get_cpuid(1, &eax, &ebx, &ecx, &edx) && (ecx & bit_F16C) != 0;
    }();
    return yes;
}

} // namespace

bool processorHasF16c() { return haveF16c(); }

bool relightBlockedHalves(const RelightModel& model, size_t first, size_t last, const float* lighting,
                          float* radiance) {
    if (!model.rowsBlocked || model.storage != TransferStorage::Float16 || !haveF16c()) return false;
    forEachBlockRun(model, first, last, [&](int n, size_t value, size_t, size_t blocks, size_t base,
                                            const uint16_t* lanes) {
        const uint16_t* halves = model.halves.data() + value;
        withBands(n, [&](auto bands) {
            constexpr int kN = decltype(bands)::value;
            relightBlockedHalvesKernel<kN>(halves, blocks, base, lanes, first, last, lighting, radiance);
        });
    });
    return true;
}

size_t relightHalves(const RelightModel& model, size_t first, size_t last, int count, const float* lighting,
                     float* out) {
    if (!haveF16c() || first >= last) return 0;
    const size_t start = size_t(model.offsets[first]) * 3, values = size_t(count) * 3;
    // Odd n > 1 read 2 bytes past each row: the array's last row is left to the caller.
    size_t vertices = last - first;
    if (count % 2 == 1 && count > 1 && start + vertices * values + 1 > model.halves.size()) --vertices;
    return relightRowsVector(model.halves.data() + start, vertices, count, lighting, out) ? vertices : 0;
}

size_t relightFloatRows(const float* transfer, size_t vertexCount, int count, const float* lighting,
                        float* radiance) {
    // Orders 6..8 stay with relight.cpp's lane loop, which streams their long rows from memory faster (1M vertices,
    // three alternating rounds: order 6 at 1.12 of the stream rate against 0.86 here, 7 at 1.20 against 1.06).
    if (!processorHasAvx2() || vertexCount == 0 || count > 25) return 0;
    // Odd n > 1 read one float past each row, and nothing is known of the memory after the last.
    const size_t vertices = count % 2 == 1 && count > 1 ? vertexCount - 1 : vertexCount;
    return relightRowsVector(transfer, vertices, count, lighting, radiance) ? vertices : 0;
}

#else

bool processorHasF16c() { return false; }
bool relightBlockedHalves(const RelightModel&, size_t, size_t, const float*, float*) { return false; }
size_t relightHalves(const RelightModel&, size_t, size_t, int, const float*, float*) { return 0; }
size_t relightFloatRows(const float*, size_t, int, const float*, float*) { return 0; }

#endif

} // namespace prt
