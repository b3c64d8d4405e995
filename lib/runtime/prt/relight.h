// prt/relight.h: per-vertex relighting of a bundle's precomputed transfer under new distant lighting. std only:
// prt::runtime needs the C++ standard library and tinygltf alone (no OpenImageIO, TBB, Embree, Ceres, OpenCL), and
// starts no threads of its own (prt/jobs.h). Loaders throw prt::Error (prt/status.h); prt/nothrow.h has the same
// functions returning status codes.
//
// Outgoing radiance of vertex v in channel c is radiance[v][c] = sum_j transfer[v][j][c] * lighting[j][c]
// (docs/conventions.md), with lighting as RGB SH radiance coefficients [coefficient][3].
#pragma once

#include "jobs.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {

struct Bundle; // bundle.h

// How a model's transfer rows are held in memory. Float32 rows are in RelightModel::transfer; the others stay as
// the bundle stores them (docs/bundle.md, "Adaptive transfer") and relight() reads them as they are.
enum class TransferStorage : uint8_t {
    Float32, // transfer
    Float16, // halves: IEEE binary16 bits, [rows][3]
    Uint16,  // codes16 [rows][3] with bandScales
    Uint8,   // codes8 [rows][3] with bandScales
    Cpca,    // cpcaBasis, cpcaWeights, cpcaCluster: every vertex at the full order
};

// Where a run of groups of ragged vertex-blocked rows starts (RelightModel::blockedRuns): the group, the index of
// its first value in the codes or halves, and of its first band scale (codes).
struct BlockedRun {
    uint64_t group = 0, value = 0, scale = 0;
};

// Per-vertex transfer ready to relight: the "transfer" layer of a bundle (semantic "sh_transfer_rgb"), or the
// adaptive layers of `prt adapt`.
struct RelightModel {
    uint32_t vertexCount = 0;
    int order = 0;               // SH bands; order * order coefficients per vertex (the most any vertex has)
    TransferStorage storage = TransferStorage::Float32;
    std::vector<float> transfer; // Float32: [vertexCount][order * order][3], the mesh's vertex order
    // Adaptive models (`prt adapt`, prt/adaptive.h): when not empty, vertex v has its own order n_v <= order and its
    // n_v^2 coefficients are rows offsets[v] .. offsets[v+1] - 1 of the rows ([offsets[vertexCount]][3]).
    std::vector<uint32_t> offsets;
    // Float16 rows.
    std::vector<uint16_t> halves;
    // Uint8 / Uint16 codes: band l of vertex v decodes q to float(int(q) - C) * sigma, C = 127 or 32767, sigma =
    // the band's scale / C (float). Per-vertex scales: sigma = bandScales[bandStart(v) + l], bandStart(v) = n_0 +
    // ... + n_{v-1}, with bandBlockStarts[b] = bandStart(b * kRelightBlock). Per-cluster scales (scaleCluster
    // not empty): sigma = bandScales[scaleCluster[v] * order + l].
    std::vector<uint8_t> codes8;
    std::vector<uint16_t> codes16;
    std::vector<float> bandScales;
    std::vector<uint32_t> bandBlockStarts;
    std::vector<uint32_t> scaleCluster;
    // Vertex-blocked rows (blockRows; codes and halves): blocks of kCodeBlock vertices, block b holding the 3
    // order^2 values of its vertices, value j (= 3 coefficient + channel) of vertex b kCodeBlock + i at codes[b 3
    // order^2 kCodeBlock + position] (or halves[...]). u16 and halves: position j kCodeBlock + i (value j of the 8
    // side by side). u8, which the integer kernel reads 16 codes at a time: band l and channel c own (2l + 1)
    // kCodeBlock positions from kCodeBlock (3 l^2 + (2l + 1) c), coefficients l^2 + 2p and l^2 + 2p + 1 (p < l) at 2
    // kCodeBlock p + 2i and + 1 within them, the band's last coefficient at 2 kCodeBlock l + i. Codes' sigma_l at
    // bandScales[(b order + l) kCodeBlock + i]; the last block padded with code C and sigma 0 (halves: +0).
    // offsets and bandBlockStarts are kept; the rows are the same values in another order.
    bool rowsBlocked = false;
    // Ragged vertex-blocked rows (blockRows of a model whose vertices have orders of their own; empty for one
    // order): each task block of kRelightBlock vertices (from vertex t kRelightBlock) holds its vertices grouped by
    // their band count n, kCodeBlock of one n per group in vertex order (each n's last group padded as above), and
    // the groups of n bands laid out as the blocks above at order n. blockedRuns[8 t + n - 1] is where task block
    // t's groups of n bands start, blockedRuns[8 T] ends the last of T task blocks; blockedLanes[g kCodeBlock + i]
    // is the vertex in lane i of group g, counted from its task block's first vertex, or kPaddingLane.
    std::vector<BlockedRun> blockedRuns;
    std::vector<uint16_t> blockedLanes;
    // Cpca: T[v] = mean[k] + sum_i cpcaWeights[v][i] basis[k][i], k = cpcaCluster[v]; cpcaBasis is [K][M + 1]
    // [order^2][3] (row 0 the mean), cpcaWeights [vertexCount][M].
    int cpcaComponents = 0;
    uint32_t cpcaClusters = 0;
    std::vector<float> cpcaBasis, cpcaWeights;
    std::vector<uint32_t> cpcaCluster;
    // A scene's transfer is irradiance transfer (params.albedo "excluded", docs/bundle.md "Scene bundles"): the
    // rows give what a white surface reflects, E / pi. Then albedo holds each vertex's diffuse albedo ([vertexCount]
    // [3], layer "diffuse_albedo") and relight() multiplies by it, so it returns outgoing radiance for every bundle;
    // clear it to get E / pi (an engine multiplies by its base colour per pixel instead).
    bool albedoExcluded = false;
    std::vector<float> albedo;
};

// Vertices per task of relight(model, ...): the split is fixed, so results never depend on the job system.
inline constexpr size_t kRelightBlock = 4096;

// Vertices per block of vertex-blocked rows (RelightModel::rowsBlocked): one per lane of an 8-float vector.
inline constexpr size_t kCodeBlock = 8;
// The lane of a group of ragged blocked rows that holds no vertex (RelightModel::blockedLanes).
inline constexpr uint16_t kPaddingLane = 0xffff;
static_assert(kRelightBlock < kPaddingLane, "a lane names a vertex of its task block in 16 bits");

// Puts a model whose vertices have 1..8 bands (at most model.order) into the vertex-blocked layout
// (RelightModel::rowsBlocked; with blockedRuns and blockedLanes where the vertices' band counts differ, as `prt
// adapt` stores them), which relight() reads 8 vertices per vector instruction, each vertex in its own lane: u8 /
// u16 codes with per-vertex scales (per band and channel sum_j (q_j - C) L_j over the band's values, times sigma_l,
// summed over the bands, with no per-value scale; for u8 exact integer sums against the lighting quantised per
// channel to int16, see relight), and half rows where the processor has AVX2 and F16C (each lane's products added
// in the float kernel's 12 lanes and fold, so the bits stay the float kernel's). docs/results.md, issue 21, gives
// the rates. Returns whether it did; other models (per-cluster scales, float rows, halves without F16C) are left as
// they are. decodedTransfer gives the same rows bit for bit. Memory: the rows and scales are rearranged (a second
// copy while it runs), plus at most 7 padded vertices per band count and task block, and for ragged models 2 bytes
// per vertex of lanes.
bool blockRows(RelightModel& model);

// Takes the "transfer" layer out of `bundle` (pass it with std::move to avoid copying), or, in a bundle without
// one, the adaptive layers `prt adapt` writes (adaptiveRelightModel, prt/adaptive.h), kept encoded. `source` names
// the bundle in errors. Needs a vertex-domain layer of semantic "sh_transfer_rgb", shape [V, L*L, 3] with L =
// params.order when that is set, V equal to the mesh's vertex count, finite values. Throws prt::Error naming
// `source` otherwise.
RelightModel relightModel(Bundle bundle, const std::string& source);

// Reads a bundle file and takes its transfer layer, as relightModel does, with the file read as readRelightBundle
// reads it.
RelightModel loadRelightModel(const std::string& bundlePath);

// A bundle file as relight needs it. In a layout readBundleHeader reads (every bundle prt writes), the whole file
// is checked as readBundle checks it, and with a "transfer" layer only the values of "transfer" and
// "diffuse_albedo" are kept: the other layers keep their descriptions with no values, so a bundle's bounce layer,
// lobes or grids cost no memory. Without one (adaptive layers) every layer has its values, and in another layout
// it is readBundle's bundle. Throws prt::Error naming `bundlePath` as readBundle does.
Bundle readRelightBundle(const std::string& bundlePath);

// The real-time kernel: radiance[v][c] = sum_j transfer[v][j][c] * lighting[j][c] for v < vertexCount.
// transfer is [vertexCount][coefficientCount][3], lighting [coefficientCount][3], radiance [vertexCount][3].
// Single-threaded and allocation-free; sums in float in a fixed order, so results do not depend on how callers
// split the vertices. To stream a range [begin, end), pass transfer + begin * coefficientCount * 3 and
// end - begin vertices. Throws prt::Error for coefficientCount < 1.
void relight(const float* transfer, size_t vertexCount, int coefficientCount, const float* lighting,
             float* radiance);

// Relights vertices [begin, end) of `model`, whatever its storage, times model.albedo per vertex when that is not
// empty, in tasks run through `jobs` (default: in order on the calling thread), one per block of kRelightBlock
// vertices counted from vertex 0 that the range overlaps.
// Float32 and Float16 rows are bit-identical to the kernel on decodedTransfer(model); u8 / u16 codes of 1..8
// bands are relit by a fused kernel straight from the codes (q - C times sigma_l L_j), within (gamma_{n+2} +
// gamma_{n+1})(1 + gamma_1) sum_j |decoded_j L_j| of the kernel on the decoded rows (tests/runtime), blocked u16
// codes (blockRows) by the blocked kernel within the same bound, blocked u8 codes against the lighting quantised
// per channel c to steps of s_c = max_j |L_jc| / 32767, within 0.51 s_c sum_j |x_j| + gamma_{n+3} sum_j |x_j|
// (|L_j| + 0.51 s_c) of the exact sum over the decoded values x_j (n bands; the same bits on every x86-64 build,
// the sums being exact integers; a channel whose lighting is not finite gives NaN); Cpca projects each
// cluster's mean and directions on the lighting once per call, then sums M weights per vertex, which agrees
// with the kernel on the decoded rows within float rounding (tests/runtime). Bit-identical for every job system.
// Needs lighting of model.order * model.order RGB coefficients (see fitLighting), end <= model.vertexCount and
// radiance sized (end - begin) * 3: row 0 of radiance is vertex `begin`; an empty range reads neither (they may be
// null). Throws prt::Error for a range outside the model, and for a model whose arrays do not have the sizes its
// vertex count, order, storage and layout say (checked on every call, O(1): a model moved from, or whose arrays
// were changed after loading); the arrays' values (offsets, codes, cluster indices) are trusted as the loaders and
// blockRows checked them. Allocates only for Cpca (the per-call projections).
// Cost per call: a ragged blocked model computes every task block the range touches whole, and Cpca projects every
// cluster on the lighting, so streaming a model in small ranges costs those again per range (graded u8 codes of
// 29,394 vertices in calls of 16 vertices: 235x the time of one call): stream in ranges of whole kRelightBlock
// blocks. Lighting that is not finite gives infinities or NaN (u8 codes and Cpca: NaN, from the quantisation or from
// products of infinity and zero).
void relight(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance,
             const JobSystem& jobs = {});

// The model's rows as float32 ([offsets[V] or V * order^2][3]), decoded exactly as relight() decodes them.
std::vector<float> decodedTransfer(const RelightModel& model);

// Bytes relight() reads from the model to relight all its vertices once (rows, codes, scales, offsets, weights,
// cluster indices, albedo, the lanes and runs of ragged blocked rows; not the lighting).
size_t relightBytes(const RelightModel& model);

} // namespace prt
