// Internal to lib/runtime: checks the per-vertex and per-texel loaders share.
#pragma once

#include "bundle.h"
#include "runtime.h"

#include <cstddef>
#include <string>
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

// Relight kernels of the encoded storages (relight_encoded.cpp), vertices [first, last) into out ([last - first][3]),
// without the albedo. relightRaggedRange: a model with offsets, any storage but Cpca, each row bit-identical to
// the float kernel on decodedTransfer. cpcaProjections: [clusters][components + 1][3], each cluster's mean and
// directions dotted with the lighting by the float kernel; relightCpcaRange sums them with the vertex's weights.
void relightRaggedRange(const RelightModel& model, const float* lighting, size_t first, size_t last, float* out);
std::vector<float> cpcaProjections(const RelightModel& model, const float* lighting);
void relightCpcaRange(const RelightModel& model, const float* projections, size_t first, size_t last, float* out);
// The fused code kernel (relight_codes.cpp): vertices [first, last) of a u8 / u16 model, all of n bands, relit from
// their codes into out; `band` is `first`'s band-0 scale index (per-vertex scales). False, with nothing written,
// for other storages or n outside 4..8 (those take the decode tile).
bool relightCodes(const RelightModel& model, int n, size_t first, size_t last, size_t band, const float* lighting,
                  float* out);

// The u8 kernel's fixed-point lighting for one band count n (relight_codes_u8.cpp), made from the lighting alone on
// first use in a task: per group g = (band l, channel c), e_g = 13 - ilogb(M_g) with M_g = max |L_j| over the
// group (e_g = 0 when M_g = 0), weights w_j = round(L_j 2^e_g) (|w| <= 2^14), scale[g] = 2^-e_g.
struct CodeLighting {
    bool ready = false, usable = false; // usable: the lighting is finite
    alignas(64) int16_t weights[13][32] = {}; // per slice, per 16-bit slot (U8Layout)
    int16_t rowWeights[192] = {};             // the same in row order, for the portable loop
    alignas(64) int32_t centring[32] = {};    // per lane, 127 sum w
    alignas(64) double scale[32] = {};         // per flat lane, 2^-e_g (0 where no group)
};
struct CodeLightingCache {
    CodeLighting byBands[5]; // n = 4..8
};
// Vertices [first, last) of a u8 model, all of n bands (4..8), relit from their codes into out. Per channel c:
// S_lc = sum_{j in band l, channel c} (q_j - 127) w_j exactly in int32, then r_c = float(sum_l S_lc sigma_l 2^-e_lc)
// with each term exact in double and the sum in double by a fixed tree of depth 4. Bound, with x_j = (q_j - 127)
// sigma_l the value the code stands for, E = sum_j x_j L_j (exact), u = 2^-24, g_d = 4 2^-53 / (1 - 4 2^-53):
//   |r - E| <= u |E| + (1 + u) (2^-14 sum_j |x_j| M_g(j) + g_d sum_j |x_j| (|L_j| + 2^-14 M_g(j))),
// since |L_j - w_j 2^-e| <= 2^(-e-1) <= 2^-14 M_g (M_g 2^e >= 2^13), the integer sums and the terms are exact, the
// double sum is within g_d sum |terms| and the conversion to float within u of its value.
// Taken on processors with AVX-512 VBMI (u8IntegerKernel()); elsewhere it declines and u8 codes go through the
// fused float kernel (relightCodes, within its own tighter bound), so u8 results differ between those two kinds of
// processor, though never with the thread count. False, with nothing written, for other storages, n outside 4..8,
// non-finite lighting or no VBMI.
bool relightU8Codes(const RelightModel& model, int n, size_t first, size_t last, size_t band, const float* lighting,
                    CodeLightingCache& cache, float* out);
bool u8IntegerKernel();
// The same integers and double operations through a portable loop, whatever the processor: for tests, the bits
// relightU8Codes gives where it is taken.
bool relightU8CodesPortable(const RelightModel& model, int n, size_t first, size_t last, size_t band,
                            const float* lighting, float* out);

} // namespace prt
