// The fused half kernel: half rows of 1..8 bands relit straight from their binary16 bits, converted by F16C inside
// the dot product, with no decoded row in memory; bit for bit the float kernel (relight.cpp) on the decoded rows.
// Processors without AVX2 and F16C, and other row lengths, take relight_encoded.cpp's decode tile.
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

PRT_ALWAYS_INLINE inline V8f halves8(const uint16_t* h) {
    return V8f(_mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(h))));
}
PRT_ALWAYS_INLINE inline V4f halves4(const uint16_t* h) {
    return V4f(_mm_cvtph_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(h))));
}

// The float kernel's 12 accumulator lanes (relight.cpp: lane i sums values i, i + 12, i + 24, ... of the row, from
// +0, each product rounded, then added) held as lanes 0..7 in `a` and 8..11 in `b`: the same products and the same
// additions, lane for lane in the same order, and half->float is exact, so every lane has the float kernel's bits.
// Odd n leave 3 values (3 n^2 = 3 mod 12) for lanes 0..2: a 4-half load (2 bytes past the row) whose fourth
// product is masked to +0, and lanes 3..7 add +0, which leaves them as they are: a lane that starts at +0 is never
// -0 (x + y is -0 only when both are), and x + (+0) = x for every other x.
template <int kValues>
struct HalfRows {
    static constexpr int kFull = kValues / 12, kTail = kValues % 12;
    static_assert(kTail == 0 || kTail == 3, "rows of 3 n^2 values");
    V8f lightA[kFull > 0 ? kFull : 1];
    V4f lightB[kFull > 0 ? kFull : 1], lightTail = {};

    explicit HalfRows(const float* lighting) {
        for (int k = 0; k < kFull; ++k) {
            std::memcpy(&lightA[k], lighting + 12 * k, sizeof(V8f));
            std::memcpy(&lightB[k], lighting + 12 * k + 8, sizeof(V4f));
        }
        std::memcpy(&lightTail, lighting + 12 * kFull, sizeof(float) * kTail);
    }
    PRT_ALWAYS_INLINE void accumulate(const uint16_t* row, V8f& a, V4f& b) const {
        a = V8f{};
        b = V4f{};
#pragma GCC unroll 16
        for (int k = 0; k < kFull; ++k) {
            a += halves8(row + 12 * k) * lightA[k];
            b += halves4(row + 12 * k + 8) * lightB[k];
        }
        if constexpr (kTail != 0) {
            const V4i tailMask = {-1, -1, -1, 0};
            const V4f t = V4f(V4i(halves4(row + 12 * kFull) * lightTail) & tailMask);
            a += __builtin_shufflevector(t, V4f{}, 0, 1, 2, 3, 4, 5, 6, 7);
        }
    }
};

// The fold is the float kernel's: lanes 0..5 += 6..11, then channel c = lane c + lane c + 3; two vertices at a time
// (one in each 128-bit half), then the last one or two alone. Rows up to 256 bytes prefetch every line 24 rows
// ahead, as the code kernel does.
template <int kValues>
void relightHalfRowsKernel(const uint16_t* __restrict halves, size_t vertexCount, const float* __restrict lighting,
                           float* __restrict radiance) {
    const HalfRows<kValues> rows(lighting);
    constexpr size_t kRowBytes = sizeof(uint16_t) * kValues;
    auto prefetch = [](const uint16_t* row) PRT_ALWAYS_INLINE {
        if constexpr (kRowBytes <= 256)
            for (size_t line = 0; line < kRowBytes; line += 64)
                __builtin_prefetch(reinterpret_cast<const char*>(uintptr_t(row) + 24 * kRowBytes + line));
    };
    size_t v = 0;
    for (; v + 2 < vertexCount; v += 2) { // a vertex follows the pair, so its 4-float stores stay inside radiance
        const uint16_t* row = halves + v * kValues;
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
        rows.accumulate(halves + v * kValues, a, b);
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
// radiance is the halves times the lighting repeated, plus +0, over the whole run as one contiguous array.
void relightHalfBand0(const uint16_t* __restrict halves, size_t vertexCount, const float* __restrict lighting,
                      float* __restrict radiance) {
    const float L0 = lighting[0], L1 = lighting[1], L2 = lighting[2];
    const V8f l0 = {L0, L1, L2, L0, L1, L2, L0, L1}, l1 = {L2, L0, L1, L2, L0, L1, L2, L0},
              l2 = {L1, L2, L0, L1, L2, L0, L1, L2}, zero = {};
    const size_t total = vertexCount * 3;
    size_t i = 0;
    for (; i + 24 <= total; i += 24) {
        const V8f r0 = halves8(halves + i) * l0 + zero, r1 = halves8(halves + i + 8) * l1 + zero,
                  r2 = halves8(halves + i + 16) * l2 + zero;
        std::memcpy(radiance + i, &r0, sizeof r0);
        std::memcpy(radiance + i + 8, &r1, sizeof r1);
        std::memcpy(radiance + i + 16, &r2, sizeof r2);
    }
    for (; i < total; ++i) radiance[i] = _cvtsh_ss(halves[i]) * lighting[i % 3] + 0.0f;
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
        return __builtin_cpu_supports("avx2") && __get_cpuid(1, &eax, &ebx, &ecx, &edx) && (ecx & bit_F16C) != 0;
    }();
    return yes;
}

} // namespace

size_t relightHalves(const RelightModel& model, size_t first, size_t last, int count, const float* lighting,
                     float* out) {
    if (!haveF16c() || first >= last) return 0;
    const size_t start = size_t(model.offsets[first]) * 3, values = size_t(count) * 3;
    // Odd n > 1 read 2 bytes past each row: the array's last row is left to the caller.
    size_t vertices = last - first;
    if (count % 2 == 1 && count > 1 && start + vertices * values + 1 > model.halves.size()) --vertices;
    const uint16_t* halves = model.halves.data() + start;
    switch (count) {
    case 1: relightHalfBand0(halves, vertices, lighting, out); break;
    case 4: relightHalfRowsKernel<12>(halves, vertices, lighting, out); break;
    case 9: relightHalfRowsKernel<27>(halves, vertices, lighting, out); break;
    case 16: relightHalfRowsKernel<48>(halves, vertices, lighting, out); break;
    case 25: relightHalfRowsKernel<75>(halves, vertices, lighting, out); break;
    case 36: relightHalfRowsKernel<108>(halves, vertices, lighting, out); break;
    case 49: relightHalfRowsKernel<147>(halves, vertices, lighting, out); break;
    case 64: relightHalfRowsKernel<192>(halves, vertices, lighting, out); break;
    default: return 0;
    }
    return vertices;
}

#else

size_t relightHalves(const RelightModel&, size_t, size_t, int, const float*, float*) { return 0; }

#endif

} // namespace prt
