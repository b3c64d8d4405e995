// The u8 code kernel for 4..8 bands: exact integer sums of the codes against a per-call fixed-point copy of the
// lighting, one per (band, channel), then each scaled by its band scale in double (docs/adapt.md, "Relighting
// encoded transfer"; the bound is in runtime_internal.h at relightU8Codes).
#include "runtime.h"

#include "runtime_internal.h"

#include <array>
#include <cmath>
#include <cstring>

// Vectors pass only between inlined functions, never across an ABI boundary.
#pragma GCC diagnostic ignored "-Wpsabi"
#if !defined(__clang__) // GCC 12 flags its own AVX-512 headers (_mm512_undefined_*) when they inline here.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#if PRT_HAVE_AVX2_CLONE
#include <immintrin.h>
#endif

namespace prt {

namespace {

constexpr int kCodeCentre = 127;
constexpr uintptr_t kPrefetchRows = 24; // rows read ahead of the one relit

// Where each value of a row of kN bands goes. Value j is coefficient k = j / 3 of band l = floor(sqrt(k)),
// channel c = j % 3, m = k - l^2 its place in the group (l, c) of 2l + 1 values. Groups of bands 0..4 take lanes
// 3l + c of lane set 0, bands 5..7 lanes 3(l - 5) + c of lane set 1 (16 lanes each, lane 16 s + i flat). A slice is
// 32 16-bit slots, two per lane: value m of a group sits in slice m / 2 of its lane set, slot 2 lane + m % 2; lane
// set 0 reads its codes from row bytes [0, 75), set 1 from [75, 3 kN^2) (so each set's bytes fit two 64-byte
// registers).
template <int kN>
struct U8Layout {
    static constexpr int kValues = 3 * kN * kN;
    static constexpr int kSlices0 = kN < 5 ? kN : 5, kSlices1 = kN > 5 ? kN : 0, kSlices = kSlices0 + kSlices1;
    static constexpr int kBytes0 = kValues < 75 ? kValues : 75, kBytes1 = kValues - kBytes0;
    struct Place {
        int lane, slice, slot, source; // flat lane 0..31, slice 0..kSlices-1, slot 0..31, byte in its set's window
    };
    static constexpr int band(int k) {
        int l = 0;
        while ((l + 1) * (l + 1) <= k) ++l;
        return l;
    }
    static constexpr std::array<Place, kValues> places = [] {
        std::array<Place, kValues> out{};
        for (int j = 0; j < kValues; ++j) {
            const int k = j / 3, c = j % 3, l = band(k), m = k - l * l, set = l >= 5 ? 1 : 0;
            const int lane = 3 * (l - 5 * set) + c;
            out[j] = {16 * set + lane, (set ? kSlices0 : 0) + m / 2, 2 * lane + m % 2, j - 75 * set};
        }
        return out;
    }();
    // Byte permutations: byte 2 slot of slice s takes source byte index[s][2 slot] of its set's window (bytes 0..63
    // of the first register, 64..127 of the second); the odd bytes (and unused slots) are zeroed by the mask or
    // meet a zero weight.
    static constexpr std::array<std::array<uint8_t, 64>, kSlices> index = [] {
        std::array<std::array<uint8_t, 64>, kSlices> out{};
        for (const Place& p : places) out[p.slice][2 * p.slot] = uint8_t(p.source);
        return out;
    }();
};

template <int kN>
void prepare(const float* lighting, CodeLighting& prepared) {
    using Layout = U8Layout<kN>;
    prepared = CodeLighting{};
    prepared.ready = true;
    int exponent[24] = {};
    for (int l = 0; l < kN; ++l)
        for (int c = 0; c < 3; ++c) {
            float most = 0;
            for (int k = l * l; k < (l + 1) * (l + 1); ++k) most = std::fmax(most, std::fabs(lighting[k * 3 + c]));
            if (!std::isfinite(most)) return; // not usable: the caller takes the float path
            // most * 2^e in [2^13, 2^14), so every |round(L 2^e)| <= 2^14 fits 16 bits.
            exponent[3 * l + c] = most > 0 ? 13 - std::ilogb(most) : 0;
            prepared.scale[l >= 5 ? 16 + 3 * (l - 5) + c : 3 * l + c] = std::ldexp(1.0, -exponent[3 * l + c]);
        }
    for (int j = 0; j < Layout::kValues; ++j) {
        const auto& p = Layout::places[j];
        const int l = Layout::band(j / 3), g = 3 * l + j % 3;
        const long weight = std::lround(std::ldexp(double(lighting[j]), exponent[g]));
        prepared.weights[p.slice][p.slot] = prepared.rowWeights[j] = int16_t(weight);
        prepared.centring[p.lane] += kCodeCentre * int32_t(weight);
    }
    prepared.usable = true;
}

// The band of each flat lane (0 for lanes no group uses, whose sums and scales are 0).
template <int kN>
constexpr std::array<int, 32> laneBands = [] {
    std::array<int, 32> out{};
    for (int l = 0; l < kN; ++l)
        for (int c = 0; c < 3; ++c) out[l >= 5 ? 16 + 3 * (l - 5) + c : 3 * l + c] = l;
    return out;
}();

// radiance_c from the lane sums: t_g = double(S_g) double(sigma_l) 2^-e_g per lane (exact: |S| < 2^25 times a
// 24-bit scale, then a power of two), then a fixed tree that keeps each lane's channel (lane i holds channel i % 3):
// U_i = t_i + t_{i+16} (only past 5 bands), V_i = U_i + U_{i+9} (i < 7; V_7 = U_7 + 0, V_8 = U_8), r_c =
// (V_c + V_{c+3}) + V_{c+6}, rounded to float. Each term meets at most 4 double additions. The portable version;
// relightU8Vbmi does the same operations lane for lane.
template <int kN>
PRT_ALWAYS_INLINE inline void scaleAndSum(const int32_t* sums, const float* sigma, const CodeLighting& prepared,
                                          float* out) {
    double t[32], u[16], v[9];
    for (int i = 0; i < 32; ++i) t[i] = double(sums[i]) * double(sigma[laneBands<kN>[i]]) * prepared.scale[i];
    for (int i = 0; i < 16; ++i) u[i] = kN > 5 ? t[i] + t[i + 16] : t[i];
    for (int i = 0; i < 7; ++i) v[i] = u[i] + u[i + 9];
    v[7] = u[7] + 0.0, v[8] = u[8];
    for (int c = 0; c < 3; ++c) out[c] = float((v[c] + v[c + 3]) + v[c + 6]);
}

PRT_ALWAYS_INLINE inline const float* scalesOf(const RelightModel& model, size_t v, size_t band) {
    return model.scaleCluster.empty() ? model.bandScales.data() + band
                                       : model.bandScales.data() + size_t(model.scaleCluster[v]) * model.order;
}

// The portable path: S_lc = sum_m (q_j - C) w_j over the group's values j = 3 (l^2 + m) + c, in a register per group
// (exact in int32: |q - C| <= 128, |w| <= 2^14, at most 15 terms).
template <int kN>
void relightU8Base(const RelightModel& model, size_t first, size_t last, size_t band, const CodeLighting& prepared,
                   float* radiance) {
    using Layout = U8Layout<kN>;
    const uint8_t* q = model.codes8.data() + size_t(model.offsets[first]) * 3;
    const int16_t* w = prepared.rowWeights;
    for (size_t v = first; v < last; ++v, band += kN, q += Layout::kValues) {
        __builtin_prefetch(reinterpret_cast<const char*>(uintptr_t(q) + kPrefetchRows * Layout::kValues));
        int32_t sums[32] = {};
        for (int l = 0; l < kN; ++l)
            for (int c = 0; c < 3; ++c) {
                int32_t sum = 0;
                for (int j = 3 * l * l + c; j < 3 * (l + 1) * (l + 1); j += 3) sum += (int32_t(q[j]) - kCodeCentre) * w[j];
                sums[l >= 5 ? 16 + 3 * (l - 5) + c : 3 * l + c] = sum;
            }
        scaleAndSum<kN>(sums, scalesOf(model, v, band), prepared, radiance + (v - first) * 3);
    }
}

#if PRT_HAVE_AVX2_CLONE
#define PRT_VBMI_TARGET __attribute__((target("avx512f,avx512bw,avx512vl,avx512vbmi")))
// t = double(S) double(sigma_l) 2^-e for 8 lanes (scaleAndSum's first step).
PRT_VBMI_TARGET PRT_ALWAYS_INLINE inline __m512d laneTerms(__m256i sums, __m512i bands, __m512d sigma, __m512d scale) {
    return _mm512_mul_pd(_mm512_mul_pd(_mm512_cvtepi32_pd(sums), _mm512_permutexvar_pd(bands, sigma)), scale);
}

// AVX-512 VBMI: per slice one byte permutation puts each code in the low byte of its 16-bit slot (odd bytes zeroed),
// one multiply-add against the slice's weights adds the slot pair into its lane; the centring C sum w comes off
// once per lane. The same integers as the portable path, so the same bits. Masked loads read only the row's bytes.
template <int kN>
PRT_VBMI_TARGET void relightU8Vbmi(const RelightModel& model, size_t first,
                                                                          size_t last, size_t band,
                                                                          const CodeLighting& prepared,
                                                                          float* radiance) {
    using Layout = U8Layout<kN>;
    constexpr int kBytes0 = Layout::kBytes0, kBytes1 = Layout::kBytes1;
    auto maskOf = [](int bytes) { return bytes >= 64 ? ~__mmask64(0) : bytes <= 0 ? 0 : (__mmask64(1) << bytes) - 1; };
    const __mmask64 low0 = maskOf(kBytes0), high0 = maskOf(kBytes0 - 64), low1 = maskOf(kBytes1),
                    high1 = maskOf(kBytes1 - 64), even = 0x5555555555555555ull;
    __m512i index[Layout::kSlices], weights[Layout::kSlices];
    for (int s = 0; s < Layout::kSlices; ++s) {
        index[s] = _mm512_loadu_si512(Layout::index[s].data());
        weights[s] = _mm512_load_si512(prepared.weights[s]);
    }
    const __m512i centring0 = _mm512_load_si512(prepared.centring), centring1 = _mm512_load_si512(prepared.centring + 16);
    __m512i bandIndex[4];
    __m512d scale[4];
    for (int r = 0; r < 4; ++r) {
        alignas(64) int64_t lanes[8];
        for (int i = 0; i < 8; ++i) lanes[i] = laneBands<kN>[8 * r + i];
        bandIndex[r] = _mm512_load_si512(lanes);
        scale[r] = _mm512_loadu_pd(prepared.scale + 8 * r);
    }
    const __m512i shiftDown = _mm512_set_epi64(0, 7, 6, 5, 4, 3, 2, 1), from3 = _mm512_set_epi64(0, 0, 0, 0, 0, 5, 4, 3),
                  from6 = _mm512_set_epi64(0, 0, 0, 0, 0, 8, 7, 6); // permutex2var: 8 = the second source's lane 0
    const uint8_t* q = model.codes8.data() + size_t(model.offsets[first]) * 3;
    for (size_t v = first; v < last; ++v, band += kN, q += Layout::kValues) {
        // The hardware prefetcher alone left this loop at 0.64 of the rate its bytes stream at order 5
        // (tests/runtime/bench_runtime); 24 rows ahead (1.8 KB at order 5, 4.6 KB at 8) brings it to about 1.
        // A prefetch never faults, so running past the buffer's end is harmless.
        __builtin_prefetch(reinterpret_cast<const char*>(uintptr_t(q) + kPrefetchRows * Layout::kValues));
        __m512i sums0, sums1 = _mm512_setzero_si512();
        {
            const __m512i a = _mm512_maskz_loadu_epi8(low0, q);
            const __m512i b = kBytes0 > 64 ? _mm512_maskz_loadu_epi8(high0, q + 64) : _mm512_setzero_si512();
            __m512i sum = _mm512_madd_epi16(_mm512_maskz_permutex2var_epi8(even, a, index[0], b), weights[0]);
            for (int s = 1; s < Layout::kSlices0; ++s)
                sum = _mm512_add_epi32(sum, _mm512_madd_epi16(_mm512_maskz_permutex2var_epi8(even, a, index[s], b), weights[s]));
            sums0 = _mm512_sub_epi32(sum, centring0);
        }
        if constexpr (Layout::kSlices1 > 0) {
            const __m512i a = _mm512_maskz_loadu_epi8(low1, q + 75);
            const __m512i b = kBytes1 > 64 ? _mm512_maskz_loadu_epi8(high1, q + 139) : _mm512_setzero_si512();
            constexpr int s0 = Layout::kSlices0;
            __m512i sum = _mm512_madd_epi16(_mm512_maskz_permutex2var_epi8(even, a, index[s0], b), weights[s0]);
            for (int s = s0 + 1; s < Layout::kSlices; ++s)
                sum = _mm512_add_epi32(sum, _mm512_madd_epi16(_mm512_maskz_permutex2var_epi8(even, a, index[s], b), weights[s]));
            sums1 = _mm512_sub_epi32(sum, centring1);
        }
        // scaleAndSum, lane for lane: 8 doubles per register, t0..t3 = lanes 0-7, 8-15, 16-23, 24-31.
        const __m512d sigma = _mm512_cvtps_pd(_mm256_maskz_loadu_ps(__mmask8((1u << kN) - 1), scalesOf(model, v, band)));
        __m512d u0 = laneTerms(_mm512_castsi512_si256(sums0), bandIndex[0], sigma, scale[0]), u1 = laneTerms(_mm512_extracti64x4_epi64(sums0, 1), bandIndex[1], sigma, scale[1]);
        if constexpr (kN > 5) {
            u0 = _mm512_add_pd(u0, laneTerms(_mm512_castsi512_si256(sums1), bandIndex[2], sigma, scale[2]));
            u1 = _mm512_add_pd(u1, laneTerms(_mm512_extracti64x4_epi64(sums1, 1), bandIndex[3], sigma, scale[3]));
        }
        // v_i = u_i + u_{i+9} for i < 7, v_7 = u_7 + 0 (u1 shifted down one lane, zero in), v_8 = u_8 = u1 lane 0.
        const __m512d v0 = _mm512_add_pd(u0, _mm512_maskz_permutexvar_pd(0x7f, shiftDown, u1));
        // (v_c + v_{c+3}) + v_{c+6}: lanes 0..2 of v0 + v0 lanes 3..5, then + {v0 lanes 6, 7, u1 lane 0}.
        const __m512d w = _mm512_add_pd(v0, _mm512_permutexvar_pd(from3, v0));
        const __m512d r = _mm512_add_pd(w, _mm512_permutex2var_pd(v0, from6, u1));
        _mm256_mask_storeu_ps(radiance + (v - first) * 3, 0x7, _mm512_cvtpd_ps(r));
    }
}
bool hasVbmi() {
    static const bool yes = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
                            __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512vbmi");
    return yes;
}
#define PRT_U8(N) relightU8Vbmi<N>
#else
bool hasVbmi() { return false; }
#define PRT_U8(N) relightU8Base<N> // never taken: relightU8Codes declines without VBMI
#endif

template <int kN>
bool relightU8Bands(const RelightModel& model, size_t first, size_t last, size_t band, const float* lighting,
                    CodeLighting& prepared, float* radiance) {
    if (!prepared.ready) prepare<kN>(lighting, prepared);
    if (!prepared.usable) return false;
    PRT_U8(kN)(model, first, last, band, prepared, radiance);
    return true;
}

} // namespace

bool relightU8CodesPortable(const RelightModel& model, int n, size_t first, size_t last, size_t band,
                            const float* lighting, float* out) {
    if (model.storage != TransferStorage::Uint8 || n < 4 || n > 8) return false;
    CodeLightingCache cache;
    CodeLighting& prepared = cache.byBands[n - 4];
    switch (n) {
    case 4: prepare<4>(lighting, prepared); break;
    case 5: prepare<5>(lighting, prepared); break;
    case 6: prepare<6>(lighting, prepared); break;
    case 7: prepare<7>(lighting, prepared); break;
    default: prepare<8>(lighting, prepared); break;
    }
    if (!prepared.usable) return false;
    switch (n) {
    case 4: relightU8Base<4>(model, first, last, band, prepared, out); break;
    case 5: relightU8Base<5>(model, first, last, band, prepared, out); break;
    case 6: relightU8Base<6>(model, first, last, band, prepared, out); break;
    case 7: relightU8Base<7>(model, first, last, band, prepared, out); break;
    default: relightU8Base<8>(model, first, last, band, prepared, out); break;
    }
    return true;
}

bool u8IntegerKernel() { return hasVbmi(); }

bool relightU8Codes(const RelightModel& model, int n, size_t first, size_t last, size_t band, const float* lighting,
                    CodeLightingCache& cache, float* out) {
    // Without VBMI the portable loop measured 17 M vertices/s at order 5 against the fused float kernel's 40-50
    // (tests/runtime/bench_runtime), so those processors take the float kernel.
    if (!u8IntegerKernel() || model.storage != TransferStorage::Uint8 || n < 4 || n > 8) return false;
    CodeLighting& prepared = cache.byBands[n - 4];
    switch (n) {
    case 4: return relightU8Bands<4>(model, first, last, band, lighting, prepared, out);
    case 5: return relightU8Bands<5>(model, first, last, band, lighting, prepared, out);
    case 6: return relightU8Bands<6>(model, first, last, band, lighting, prepared, out);
    case 7: return relightU8Bands<7>(model, first, last, band, lighting, prepared, out);
    default: return relightU8Bands<8>(model, first, last, band, lighting, prepared, out);
    }
}

} // namespace prt
