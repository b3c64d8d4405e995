// The fused code kernels: u8 / u16 transfer codes of 1..8 bands relit straight from the codes, with no decoded row
// in memory, row by row or, for vertex-blocked codes, 8 vertices at a time (relight_encoded.cpp keeps the decode
// tile for other band counts).
#include "runtime.h"

#include "runtime_internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>

#include <emmintrin.h>
#if PRT_HAVE_AVX2_CLONE
#include <immintrin.h>
#endif

// The kernel's vectors are passed only between inlined functions, never across an ABI boundary.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace prt {

namespace {

// Eight-wide GCC vectors: the baseline build lowers each operation to two SSE2 instructions, the AVX2 clone to one,
// lane for lane the same operations in the same order, so both give the same bits.
typedef float V8f __attribute__((vector_size(32)));
typedef float V4f __attribute__((vector_size(16)));

// Where value j (= coefficient j / 3, channel j % 3) of a row of kN bands takes its band scale from, per chunk of 8
// values: the band of coefficient j / 3, floor(sqrt(j / 3)); lanes past the row (padding) take band 0, which they
// multiply by a zero lighting value.
template <int kN>
struct CodeLayout {
    static constexpr int kValues = 3 * kN * kN, kChunks = (kValues + 7) / 8, kPadded = kChunks * 8;
    static constexpr std::array<std::array<int, 8>, kChunks> bands = [] {
        std::array<std::array<int, 8>, kChunks> out{};
        for (int k = 0; k < kChunks; ++k)
            for (int i = 0; i < 8; ++i) {
                const int j = 8 * k + i;
                int l = 0;
                while (j < kValues && (l + 1) * (l + 1) <= j / 3) ++l;
                out[k][i] = l;
            }
        return out;
    }();
};

// The first of band l's pair constants in U8Lighting::pairs: 3 (0 + 1 + ... + (l - 1)).
constexpr int pairStart(int l) { return 3 * l * (l - 1) / 2; }

namespace codes_base {
#define PRT_CODES_AVX2 0
#include "relight_codes_kernel.inc"
#undef PRT_CODES_AVX2
} // namespace codes_base

#if PRT_HAVE_AVX2_CLONE
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2")
#endif
namespace codes_avx2 {
#define PRT_CODES_AVX2 1
#include "relight_codes_kernel.inc"
#undef PRT_CODES_AVX2
} // namespace codes_avx2
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif
#endif

#if PRT_HAVE_AVX2_CLONE
#define PRT_CODES(N) \
    (processorHasAvx2() ? codes_avx2::relightCodesKernel<Code, N> : codes_base::relightCodesKernel<Code, N>)
#define PRT_BLOCKED(N) \
    (processorHasAvx2() ? codes_avx2::relightBlockedKernel<Code, N> : codes_base::relightBlockedKernel<Code, N>)
#define PRT_BLOCKED_U8(N) \
    (processorHasAvx2() ? codes_avx2::relightBlockedU8Kernel<N> : codes_base::relightBlockedU8Kernel<N>)
#else
#define PRT_CODES(N) codes_base::relightCodesKernel<Code, N>
#define PRT_BLOCKED(N) codes_base::relightBlockedKernel<Code, N>
#define PRT_BLOCKED_U8(N) codes_base::relightBlockedU8Kernel<N>
#endif

// Every n in 1..8: n = 1..3 took the decode tile until the fused kernel (with prefetch) measured 1.4-3.6x its rate
// at 1, 2 and 3 bands (docs/results.md, issue 21; in 12 lanes and without prefetch it had been 0.75x float at order
// 3 against the tile's 1.13x).
template <class Code>
bool relightCodesOf(const RelightModel& model, const std::vector<Code>& codes, int n, size_t first, size_t last,
                    size_t band, const float* lighting, float* radiance) {
    return withBands(n, [&](auto bands) {
        PRT_CODES(decltype(bands)::value)(model, codes.data(), codes.size(), first, last, band, lighting, radiance);
    });
}

// u8: the integer kernel. u16 codes (up to 65535) times int16 lighting would overflow its int32 pair sums, so they
// keep the float kernel below.
void relightBlockedU8(const RelightModel& model, size_t first, size_t last, const U8Lighting& q, float* radiance) {
    forEachBlockRun(model, first, last, [&](int n, size_t value, size_t scale, size_t blocks, size_t base,
                                            const uint16_t* lanes) {
        const uint8_t* codes = model.codes8.data() + value;
        const float* scales = model.bandScales.data() + scale;
        withBands(n, [&](auto bands) {
            PRT_BLOCKED_U8(decltype(bands)::value)(codes, scales, blocks, base, lanes, first, last, q, radiance);
        });
    });
}

template <class Code>
void relightBlockedOf(const RelightModel& model, const std::vector<Code>& codeArray, size_t first, size_t last,
                      const float* lighting, float* radiance) {
    forEachBlockRun(model, first, last, [&](int n, size_t value, size_t scale, size_t blocks, size_t base,
                                            const uint16_t* lanes) {
        const Code* codes = codeArray.data() + value;
        const float* scales = model.bandScales.data() + scale;
        withBands(n, [&](auto bands) {
            PRT_BLOCKED(decltype(bands)::value)(codes, scales, blocks, base, lanes, first, last, lighting, radiance);
        });
    });
}

} // namespace

U8Lighting quantiseU8Lighting(const float* lighting, int order) {
    U8Lighting q;
    if (order < 1 || order > 8) return q; // no blocked kernel takes it (relightBlockedU8)
    const int n = order * order;
    int32_t codes[3 * 64] = {}; // Lq of value 3 m + c, each rounded once
    for (int c = 0; c < 3; ++c) {
        float largest = 0.0f;
        bool finite = true;
        for (int m = 0; m < n; ++m) {
            finite = finite && std::isfinite(lighting[m * 3 + c]);
            largest = std::max(largest, std::fabs(lighting[m * 3 + c]));
        }
        q.scale[c] = finite ? largest / 32767.0f : std::numeric_limits<float>::quiet_NaN();
        if (!(q.scale[c] > 0.0f)) continue; // zero lighting, or not finite: codes 0
        for (int m = 0; m < n; ++m)
            codes[m * 3 + c] = int32_t(std::clamp(std::lrint(lighting[m * 3 + c] / q.scale[c]), -32767L, 32767L));
    }
    auto pack = [](int32_t low, int32_t high) {
        return int32_t(uint32_t(uint16_t(low)) | (uint32_t(uint16_t(high)) << 16));
    };
    for (int l = 0; l < order; ++l)
        for (int c = 0; c < 3; ++c) {
            int32_t sum = 0;
            for (int p = 0; p < l; ++p) {
                const int m = l * l + 2 * p;
                q.pairs[pairStart(l) + c * l + p] = pack(codes[m * 3 + c], codes[(m + 1) * 3 + c]);
                sum += codes[m * 3 + c] + codes[(m + 1) * 3 + c];
            }
            const int last = l * l + 2 * l;
            q.single[3 * l + c] = pack(codes[last * 3 + c], 0);
            sum += codes[last * 3 + c];
            q.offset[3 * l + c] = -127 * sum;
        }
    return q;
}

bool relightBlockedCodes(const RelightModel& model, size_t first, size_t last, const float* lighting,
                         const U8Lighting* quantised, float* radiance) {
    if (!model.rowsBlocked) return false; // blocked models have orders 1..8 (blockRows)
    if (model.storage == TransferStorage::Uint8)
        relightBlockedU8(model, first, last, quantised ? *quantised : quantiseU8Lighting(lighting, model.order),
                         radiance);
    else if (model.storage == TransferStorage::Uint16)
        relightBlockedOf(model, model.codes16, first, last, lighting, radiance);
    else
        return false;
    return true;
}

bool relightCodes(const RelightModel& model, int n, size_t first, size_t last, size_t band, const float* lighting,
                  float* radiance) {
    if (model.storage == TransferStorage::Uint8)
        return relightCodesOf(model, model.codes8, n, first, last, band, lighting, radiance);
    if (model.storage == TransferStorage::Uint16)
        return relightCodesOf(model, model.codes16, n, first, last, band, lighting, radiance);
    return false;
}

} // namespace prt
