// Internal to lib/runtime: checks the per-vertex and per-texel loaders share.
#pragma once

#include "bundle.h"
#include "runtime.h"

#include <cstddef>
#include <string>
#include <type_traits>
#include <vector>

// The relighting kernels (relight.cpp, relight_encoded.cpp) are also compiled for AVX2 and chosen at run time on
// GCC / x86-64 (the same bits: no FMA, the same per-lane order); their bodies are inlined into both versions.
#if defined(__GNUC__) && defined(__x86_64__)
#define PRT_HAVE_AVX2_CLONE 1
#define PRT_ALWAYS_INLINE __attribute__((always_inline))
#else
#define PRT_HAVE_AVX2_CLONE 0
#define PRT_ALWAYS_INLINE
#endif

namespace prt {

#if PRT_HAVE_AVX2_CLONE
// Whether this processor runs AVX2 code (the instructions and the OS saving the YMM state), asked once; every
// kernel that dispatches to an AVX2 version asks here (relight.cpp).
bool processorHasAvx2();
#endif

// The unit direction d from vertex `vertex` of `model` toward the point `eye`; false (d untouched) at the eye
// itself. What glossyRadiance and glossyConeLightRadiance shade each vertex toward.
bool directionToEye(const GlossyModel& model, uint32_t vertex, const float eye[3], float d[3]);

// The layer called `name` of `bundle`, of semantic "sh_transfer_rgb" in `domain`. `stage` names the prt stage that
// makes such a layer, for the message when there is none. Throws prt::Error(source, ...) otherwise.
Layer& transferLayer(Bundle& bundle, const std::string& name, const std::string& domain, const std::string& source,
                     const char* stage);

// The SH order L of a transfer layer of shape [rows, L*L, 3] (params.order, when set, must agree).
// Throws prt::Error(source, place, ...) naming the shape otherwise.
int transferLayerOrder(const Layer& layer, const std::string& source, const std::string& place);

// Throws prt::Error(source, "PLACE, ROW i", ...) for the first non-finite value; rows of rowValues floats.
void checkFiniteRows(const std::vector<float>& data, size_t rowValues, const std::string& source,
                     const std::string& place, const char* row);

// The atlas size and SH order of a "texel_transfer" layer: params width and height, shape [W*H, L*L, 3].
// Throws prt::Error(source, ...) naming the bad param or the row count otherwise.
struct TexelLayerShape {
    int width = 0, height = 0, order = 0;
    bool albedoExcluded = false; // params.albedo "excluded": a scene bake's irradiance transfer, relit as E / pi
};
TexelLayerShape texelLayerShape(const Layer& layer, const std::string& source);
// The texel-domain adaptive layers of an adapted bake (`prt adapt` of a `prt bake` bundle) as a texel model.
// Needs hasAdaptiveTransfer(bundle).
TexelRelightModel adaptiveTexelModel(Bundle& bundle, const std::string& source);

// Fills model.albedoExcluded and model.albedo from a transfer layer whose params.albedo is "excluded" (a scene's
// irradiance transfer) and the bundle's "diffuse_albedo" layer, checked: [vertexCount, 3], values in [0, 1].
void readExcludedAlbedo(const Bundle& bundle, const Layer& transfer, const std::string& source, RelightModel& model);

// What relight() and relightAdaptive() check on every call (model_check.cpp), throwing prt::Error("", place, ...):
// the range [begin, end) inside the model's vertices, and the model's arrays of the sizes its vertex count, order,
// storage and layout say (a model moved from, arrays changed after loading, a hand-built model): O(1), the sizes
// only. The values (offsets' steps, codes, cluster indices, lanes) are as a loader or blockRows left them, which
// check them.
void checkRelightCall(const RelightModel& model, size_t begin, size_t end, const char* place);

// The sizes of the arrays blockRows lays out: values (codes or halves) and band scales (0 for halves), for blocks of
// one order when `runs` is empty, else as the ragged runs' end says (RelightModel::blockedRuns).
struct BlockedSizes {
    size_t values = 0, scales = 0;
};
BlockedSizes blockedSizes(const RelightModel& model, const std::vector<BlockedRun>& runs);

// The lighting of the u8 blocked kernel (relight_codes_kernel.inc, relightBlockedU8Kernel): per channel c one
// scale s_c = max_j |L_jc| / 32767 and each value as an int16 Lq_j = round(L_j / s_c), |s_c Lq_j - L_j| <= 0.51
// s_c. Per band l and channel c (index 3 l + c): the band's coefficients m = l^2 .. l^2 + 2l taken in pairs (l^2 +
// 2p, l^2 + 2p + 1), p < l, each pair as one int32 (Lq of the first in its low 16 bits, of the second in its high
// 16), then the last coefficient alone (Lq in the low 16 bits, 0 in the high), and the offset -C sum_m Lq_m (C =
// 127) that centres the codes. A channel with a value that is not finite gets scale NaN and zero codes, so its
// radiance is NaN, as the float kernels' would be (or infinite).
struct U8Lighting {
    float scale[3] = {};
    int32_t pairs[3 * 28] = {}; // band l, channel c from 3 l (l - 1) / 2 + c l: at most 3 (0 + 1 + ... + 7)
    int32_t single[3 * 8] = {}; // [3 l + c]
    int32_t offset[3 * 8] = {}; // [3 l + c]
};
// lighting [order^2][3]; all zero for an order outside 1..8. relight() quantises once per call, before its tasks run.
U8Lighting quantiseU8Lighting(const float* lighting, int order);

// Relight kernels of the encoded storages (relight_encoded.cpp), vertices [first, last) into out ([last - first][3]),
// without the albedo. relightRaggedRange: a model with offsets, any storage but Cpca, each row bit-identical to
// the float kernel on decodedTransfer (blocked u8 codes: within relight()'s bound, against `quantised`, the
// lighting as quantiseU8Lighting gives it, or quantised here when null). cpcaProjections: [clusters][components +
// 1][4] (RGB, then 0), each cluster's mean and directions dotted with the lighting by the float kernel;
// relightCpcaRange sums them with the vertex's weights, per channel in two sums, each in order: the mean + w_0 p_0
// + w_2 p_2 + ... and 0 + w_1 p_1 + w_3 p_3 + ... (+ 0 * 0 after an odd M's last even term), then the first + the
// second.
void relightRaggedRange(const RelightModel& model, const float* lighting, size_t first, size_t last, float* out,
                        const U8Lighting* quantised = nullptr);
std::vector<float> cpcaProjections(const RelightModel& model, const float* lighting);
void relightCpcaRange(const RelightModel& model, const float* projections, size_t first, size_t last, float* out);
// The fused code kernel (relight_codes.cpp): vertices [first, last) of a u8 / u16 model, all of n bands, relit from
// their codes into out; `band` is `first`'s band-0 scale index (per-vertex scales). False, with nothing written,
// for other storages or n outside 1..8 (those take the decode tile).
bool relightCodes(const RelightModel& model, int n, size_t first, size_t last, size_t band, const float* lighting,
                  float* out);
// Where value j (= 3 coefficient + channel) of vertex i of a block of vertex-blocked rows (RelightModel::
// rowsBlocked) lies, counted from the block's start. u16 codes and halves: j kCodeBlock + i. u8, laid out for the
// integer kernel: band l and channel c own (2l + 1) kCodeBlock codes from kCodeBlock (3 l^2 + (2l + 1) c), the band's
// coefficients l^2 + 2p and l^2 + 2p + 1 (p < l) as 2 kCodeBlock codes from 2 kCodeBlock p with vertex i's two side
// by side at 2i, 2i + 1, then its last coefficient's at 2 kCodeBlock l + i.
inline size_t blockedCodeIndex(bool u8, size_t j, size_t i) {
    if (!u8) return j * kCodeBlock + i;
    const size_t m = j / 3, c = j % 3;
    size_t l = 0;
    while ((l + 1) * (l + 1) <= m) ++l;
    const size_t k = m - l * l, base = kCodeBlock * (3 * l * l + (2 * l + 1) * c);
    return k < 2 * l ? base + 2 * kCodeBlock * (k / 2) + 2 * i + k % 2 : base + 2 * kCodeBlock * l + i;
}

// Calls f(std::integral_constant<int, n>{}) for a band count n in 1..8, so that f can pick the kernel compiled for
// n bands; returns false, calling nothing, for other n.
template <class F>
bool withBands(int n, F&& f) {
    switch (n) {
    case 1: f(std::integral_constant<int, 1>{}); return true;
    case 2: f(std::integral_constant<int, 2>{}); return true;
    case 3: f(std::integral_constant<int, 3>{}); return true;
    case 4: f(std::integral_constant<int, 4>{}); return true;
    case 5: f(std::integral_constant<int, 5>{}); return true;
    case 6: f(std::integral_constant<int, 6>{}); return true;
    case 7: f(std::integral_constant<int, 7>{}); return true;
    case 8: f(std::integral_constant<int, 8>{}); return true;
    default: return false;
    }
}

// Calls run(n, value, scale, blocks, base, lanes) for each run of blocks of a model with rowsBlocked that vertices
// [first, last) lie in: `blocks` blocks of n bands from value index `value` of the codes or halves and band-scale
// index `scale` (codes), lane i of block k being vertex base + k kCodeBlock + i, or, with lanes, base + lanes[k
// kCodeBlock + i] (RelightModel::blockedRuns): one run for a model of one order, at most 8 per task block for a
// ragged one.
template <class Run>
void forEachBlockRun(const RelightModel& model, size_t first, size_t last, Run&& run) {
    if (first >= last) return;
    if (model.blockedRuns.empty()) {
        const size_t n = size_t(model.order), b0 = first / kCodeBlock, b1 = (last + kCodeBlock - 1) / kCodeBlock;
        const size_t scales = model.storage == TransferStorage::Float16 ? 0 : n;
        run(int(n), b0 * 3 * n * n * kCodeBlock, b0 * scales * kCodeBlock, b1 - b0, b0 * kCodeBlock, nullptr);
        return;
    }
    for (size_t t = first / kRelightBlock; t * kRelightBlock < last; ++t)
        for (int n = 1; n <= 8; ++n) {
            const BlockedRun& begin = model.blockedRuns[8 * t + size_t(n) - 1];
            const BlockedRun& end = model.blockedRuns[8 * t + size_t(n)];
            if (end.group > begin.group)
                run(n, begin.value, begin.scale, end.group - begin.group, t * kRelightBlock,
                    model.blockedLanes.data() + begin.group * kCodeBlock);
        }
}

// The blocked code kernel (relight_codes.cpp): vertices [first, last) of a model with rowsBlocked, relit from its
// blocks into out; u8 models against `quantised`, or, when that is null, against the lighting quantised here. False,
// with nothing written, for other models.
bool relightBlockedCodes(const RelightModel& model, size_t first, size_t last, const float* lighting,
                         const U8Lighting* quantised, float* out);
// The blocked half kernel (relight_vector.cpp): vertices [first, last) of a Float16 model with rowsBlocked, relit
// from its blocks into out, bit for bit the float kernel on decodedTransfer's rows. False, with nothing written,
// for other models or where the processor lacks F16C (blockRows blocks halves only where processorHasF16c()).
bool relightBlockedHalves(const RelightModel& model, size_t first, size_t last, const float* lighting, float* out);
// Whether this processor runs the F16C half conversions (and AVX2) that the half kernels use, asked once.
bool processorHasF16c();
// The fused half kernel (relight_vector.cpp): vertices [first, last) of a Float16 model, all of `count` coefficients
// (count = n^2, n in 1..8), relit from their halves into out, bit for bit the float kernel on decodedTransfer's
// rows. Returns how many leading vertices it relit: 0 (nothing written) where the processor lacks AVX2 or F16C or
// for other counts, else last - first, less the array's last row for odd n (whose last 4-half load would pass the
// array's end; n > 1). The caller relights the rest.
size_t relightHalves(const RelightModel& model, size_t first, size_t last, int count, const float* lighting,
                     float* out);
// The same kernel on float rows (relight_vector.cpp): vertices [0, vertexCount) of `count` coefficients (n^2, n in
// 1..5), bit for bit relight.cpp's lane loop. Returns how many leading vertices it relit: 0 (nothing written)
// where the processor lacks AVX2 or for other counts (orders 6..8 measured faster in the lane loop), else
// vertexCount, less the last row for odd n > 1 (whose last 4-float load would pass the row). The caller relights
// the rest.
size_t relightFloatRows(const float* transfer, size_t vertexCount, int count, const float* lighting,
                        float* radiance);

} // namespace prt
