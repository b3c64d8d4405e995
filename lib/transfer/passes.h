// Internal to lib/transfer: the passes computeTransfer chains, shared with the sharded interreflected passes
// (shards.cpp) so that both run the same code on each vertex and agree bit for bit.
#pragma once

#include "core.h"
#include "raycast.h"
#include "rays.h"
#include "transfer.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

namespace prt::passes {

// The direct pass's front-face hits for one block of rays::kBlockVertices receivers, in receiver then sample
// order: 10 bytes per hit.
struct HitBlock {
    std::vector<uint32_t> end;         // per receiver of the block: one past its last hit
    std::vector<uint32_t> triangle;
    std::vector<uint32_t> barycentric; // u | v << 16, each quantised to 1/65535
    std::vector<uint16_t> sample;
};

// What every pass reads.
struct Context {
    const TriMesh& mesh;    // the geometry rays hit and bounces gather from
    const TransferOptions& options;
    Receivers receivers;    // the rows the direct pass writes, in order: mesh vertices or other points
    int coefficients;       // order^2
    int stride;             // floats per vertex row: order^2 * 3
    float offset;
    rays::Hemisphere directions;
    std::vector<float> weightedBasis; // [sample][coefficient]: cos(theta_k) * Y_j(s_k) in the local frame
    std::vector<float> cosines;       // [sample]
    std::vector<double> lambert;      // [coefficient]: A_l / pi, the unshadowed transfer's band factor

    // The albedo folded into a receiver's rows: 1 for a scene's irradiance transfer (options.surface).
    std::array<float, 3> albedo(size_t receiver) const {
        if (options.surface) return {1.0f, 1.0f, 1.0f};
        if (!receivers.albedo || options.albedoOverride) return options.albedo;
        const float* a = &receivers.albedo[3 * receiver];
        return {a[0], a[1], a[2]};
    }
};

// Checks the options and the mesh's own albedo (the vertex range is the caller's business). Throws prt::Error
// (kExitUsage for options, kExitInput for the mesh).
void checkOptions(const TriMesh& mesh, const TransferOptions& options);

// Needs checked options; `receivers` must outlive the context.
Context makeContext(const TriMesh& mesh, const TransferOptions& options, const Receivers& receivers);

// Bounces run on one channel (unit-albedo rows) when one albedo covers the mesh, else on RGB rows.
inline int bounceChannels(const TriMesh& mesh, const TransferOptions& options) {
    if (options.surface) return 3; // albedo at every hit point
    return mesh.albedo.empty() || options.albedoOverride ? 1 : 3;
}

struct DirectCounts {
    std::atomic<uint64_t> rays{0}, hits{0}, backFaceHits{0};
};

// Shadowed and interreflected direct pass over the context's receivers into `out` (row i for receiver i) and,
// when not null, unit-albedo single-channel rows into `unitOut`. With `hitBlocks` (one per block of receivers,
// empty) rays find their nearest hits and front-face hits are recorded there; otherwise they are occlusion rays.
// Each receiver's row and hits depend only on the receiver (its key), never on the block or thread it lands in.
void directPass(const Context& context, const EmbreeScene& scene, float* out, float* unitOut,
                std::vector<HitBlock>* hitBlocks, DirectCounts& counts, Progress* progress);

// directPass with the Embree scene of context.mesh built before and freed after it (so the bounces that follow
// do not hold the BVH), progress shown when the options ask; fills the stats' build and direct times, rays, hits,
// back-face hits and hit-record bytes.
void runDirectPass(const Context& context, float* out, float* unitOut, std::vector<HitBlock>* hitBlocks,
                   TransferStats& stats);

// One Jacobi bounce, number `number` (1-based). Every receiver gathers `previous` (rows of the mesh's vertices) at
// its recorded hits, each hit weighted by its cosine and interpolated with its barycentrics, and scales the sum by
// 2/N; the result goes to `next` (when not null) and is added to `total` ([order^2][3] rows, one per receiver).
// Rows of `next` and `total` are the context's receivers (block b of hitBlocks is receivers
// [b * kBlockVertices, ...)); rows of `previous` are mesh vertices, all of them.
// With `channels` 3 the rows are RGB and the scale includes the vertex's albedo; with options.surface each hit's
// interpolated row is multiplied by the material's diffuse albedo at the hit instead (the rows are irradiance
// transfer, so that is the light the hit point reflects). With `channels` 1 (one albedo
// for the whole mesh) the rows are unit-albedo G_b, a third of the bytes to gather, and `total` receives
// albedo^(number+1) * G_b per channel, since bounce b of uniform albedo rho is rho^(b+1) G_b.
// `previous` is only read, so each vertex's gather order (its hits in sample order) fixes every bit; the
// per-vertex work is one function whoever calls (the whole mesh or a shard). Corner k of triangle t gathers row
// cornerRows[3 t + k] of `previous`: mesh.indices where `previous` holds every vertex, a bounce shard's own table
// where it holds only the rows its hits name (shards.cpp).
void bounce(const Context& context, const std::vector<HitBlock>& hitBlocks, int channels, const float* previous,
            const uint32_t* cornerRows, float* next, float* total, int number, Progress* progress);

// What hit records take (the layout in transfer.h): 4 bytes per receiver, 10 per hit.
uint64_t hitRecordBytes(const std::vector<HitBlock>& blocks);

// The number of hit blocks for `receivers` receivers.
inline size_t hitBlockCount(size_t receivers) { return (receivers + rays::kBlockVertices - 1) / rays::kBlockVertices; }

// The shard files (shard_files.cpp; their layout is written there). Writers are atomic; readers check the header
// against `run` (and the shard), the payload's length against the header, and every index and value, and throw
// prt::Error(kExitInput) naming the file and the problem.
void writeHitRecords(const std::string& path, const ShardRun& run, const std::vector<HitBlock>& blocks);
std::vector<HitBlock> readHitRecords(const std::string& path, const ShardRun& run);
// The exitant array of pass `pass` (gatherExitant's file), only the rows of the vertices that `needed` marks
// ([run.vertexCount] flags), packed in vertex order. Checks the payload's length and the chunk digest table against
// the header's checksum, then reads only the 1 MiB chunks that hold a marked row, each checked against its digest
// and for finite values: memory and bytes read are the marked rows' chunks, plus one chunk.
std::vector<float> readExitant(const std::string& path, const ShardRun& run, int pass,
                               const std::vector<uint8_t>& needed);

} // namespace prt::passes
