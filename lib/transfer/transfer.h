// Per-vertex diffuse SH transfer by quasi-Monte Carlo over Embree 3 rays: unshadowed, shadowed, and
// interreflected as a truncated Neumann series (Jacobi bounces that reuse the direct pass's hits).
//
// Output convention (docs/conventions.md): transfer[v][j][c] maps the RGB radiance SH coefficients of distant
// lighting to exitant radiance, radiance_out(v, c) = sum_j transfer[v][j][c] * lighting[j][c], with albedo/pi
// folded in. The layout is always [vertex][order^2][3], whatever the mode, so the runtime has one path.
//
// Estimator (written once here; the stage records it in the bundle as "direction_set"):
//   One shared set of N uniform-hemisphere Hammersley directions about +z: cos(theta_k) = (k + 0.5) / N,
//   phi_k = 2 pi * radicalInverse2(k), weight 2 pi / N each. Vertex v uses it in a frame about its normal turned
//   about the normal by an angle from a hash of (seed, v), so neighbouring vertices do not alias together and the
//   result for v depends only on (mesh, options, v), never on the thread count or the vertex range.
//   Shadowed transfer is the exact unshadowed integral (rho/pi) A_l Y_lm(n) minus the estimate of the occluded
//   part: unoccluded vertices are exact (a white furnace returns L to float precision) and bounces on a convex
//   mesh add exactly zero.
//   Rays follow the shared spawn rule (lib/raycast: spawnOrigin, spawnRay), offset = 1e-4 * bounding-box diagonal.
//   A ray whose nearest hit is a back face (geometric normal . direction > 0, with counter-clockwise front faces)
//   is occluded but carries no bounce light; such hits are counted, as they signal open or inverted meshes.
//
// Memory (interreflected), linear in the vertex count: hit records take 10 bytes per front-face hit (triangle,
// two 16-bit barycentrics, 16-bit sample index) plus 4 bytes per vertex; the result takes 12 * order^2 bytes per
// vertex, and bounces one more array (one bounce) or two (more) of 4 * order^2 bytes per vertex when one albedo
// covers the mesh, 12 * order^2 with per-vertex albedo. The Embree BVH is freed before the bounces. Measured:
// 1.06 M vertices, order 5, 128 samples, 2 bounces: peak 1768 bytes per vertex, of which hits 1004, transfer 500.
// Everything else is O(vertices * order^2) or O(samples * order^2).
// Sharded (computeDirectShard, computeBounceShard below) a job holds its range's hits and rows plus the mesh and
// either the BVH (direct pass) or the previous pass's exitant array (4 * order^2 * channels bytes per vertex);
// measured on that mesh in 4 shards: at most 1.1 GiB per job against 3.8 GiB for the unsharded stage.
#pragma once

#include "bundle.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {

enum class TransferMode { Unshadowed, Shadowed, Interreflected };

// Parses "unshadowed" | "shadowed" | "interreflected"; throws prt::Error(kExitUsage) otherwise.
TransferMode parseTransferMode(const std::string& name);
const char* transferModeName(TransferMode mode);

// Hit records store the sample index in 16 bits.
inline constexpr int kMaxTransferSamples = 65536;

// Short description of the direction set and estimator above, recorded with every transfer layer.
inline constexpr const char* kTransferDirectionSet =
    "hammersley-uniform-hemisphere: cos(theta)=(k+0.5)/N, phi=2pi*radinv2(k), per-vertex rotation about the "
    "normal by hash(seed,vertex); shadowed = exact unshadowed - occluded estimate";

struct Surface; // lib/material: a scene's materials at surface points

struct TransferOptions {
    TransferMode mode = TransferMode::Shadowed;
    int order = 3;       // bands, 1..sh::kMaxOrder
    int samples = 1024;  // directions per vertex, 1..kMaxTransferSamples (unused when unshadowed)
    int bounces = 0;     // interreflected only
    std::array<float, 3> albedo = {1.0f, 1.0f, 1.0f}; // linear RGB in [0, 1]
    bool albedoOverride = false; // use `albedo` even where the mesh carries per-vertex albedo
    uint64_t seed = 0;
    int threads = 0;     // 0: all hardware threads
    size_t vertexBegin = 0;            // the vertex range [begin, end) to compute, clipped to the mesh
    size_t vertexEnd = SIZE_MAX;
    bool progress = true;
    bool keepDirect = false; // interreflected with bounces: also return the direct pass's rows (Transfer::direct)
    // A scene's materials (lib/material), borrowed: rays pass through cut-outs, every bounce takes the diffuse
    // albedo of the material at its hit point (texture, factor, COLOR_0, 1 - metallic), and the rows are
    // irradiance transfer: the receiver's own albedo is excluded (radiance_out = albedo(receiver) * sum_j T L),
    // so a runtime multiplies by the albedo per vertex or per pixel. Null: per-vertex or uniform albedo as above.
    // Not with albedoOverride. The mesh must be the surface's flattened mesh.
    const Surface* surface = nullptr;
};

struct TransferStats {
    uint64_t rays = 0;          // rays cast (all in the direct pass; bounces cast none)
    uint64_t hits = 0;          // front-face hits recorded for bounces (interreflected)
    uint64_t backFaceHits = 0;  // nearest hits on back faces (interreflected; occlusion rays do not say)
    float rayOffset = 0.0f;     // the spawn rule's offset (lib/raycast), in mesh units
    double buildSeconds = 0.0;  // Embree BVH build
    double directSeconds = 0.0; // direct pass: rays plus accumulation, wall clock
    double directCpuSeconds = 0.0; // the same in process CPU time, which other processes' load does not inflate
    std::vector<double> bounceSeconds;
    uint64_t hitRecordBytes = 0;
    uint64_t exitantRows = 0;      // a bounce shard's rows of the previous pass's exitant array: those its hits name
    uint64_t transferBytes = 0;    // transfer arrays alive at the peak
    uint64_t peakMemoryBytes = 0;  // process peak resident set after the computation
};

struct Transfer {
    int order = 0;
    size_t vertexBegin = 0, vertexEnd = 0;
    std::vector<float> coefficients; // [vertexEnd - vertexBegin][order^2][3]
    // With options.keepDirect, interreflected and bounces > 0: the direct (shadowed) part alone, same layout, so
    // coefficients - direct is what the bounces add (what a hybrid relight sends the cone lights through).
    std::vector<float> direct;
    TransferStats stats;
};

// Computes transfer for the vertices in the options' range.
// Needs: a mesh with unit-length (or at least nonzero) normals per vertex and indices in range; options within
// the ranges above; interreflected with bounces > 0 needs the whole vertex range, because every bounce gathers
// from every vertex (the sharded passes below split it). Throws prt::Error (kExitInput for the mesh, kExitUsage
// for options) otherwise.
// Guarantees: bit-identical coefficients for the same mesh and options whatever `threads`, and for any range the
// rows equal the same rows of the whole-mesh result.
Transfer computeTransfer(const TriMesh& mesh, const TransferOptions& options);

// ---- sharded interreflected transfer ----------------------------------------------------------------------------
// Interreflected transfer with B > 0 bounces split over N contiguous vertex ranges (shardRows), as B + 1 passes of
// N jobs each (docs/pipelines.md "Shards"):
//   pass 0, per shard: the direct pass of its rows (computeDirectShard), its hit records kept in a file;
//   pass b = 1..B, per shard: bounce b of its rows (computeBounceShard), gathering at its own hits the exitant rows
//   of pass b - 1 of every vertex, which gatherExitant joins from that pass's shards.
// Pass B's rows are bit-identical to the same rows of computeTransfer (same direct pass per vertex, same hits,
// same per-vertex bounce function), so concatenated they give the unsharded result.
// Files between passes (shard_files.cpp) carry a header naming the run (ShardRun) and are refused, exit 3 with
// the file and the mismatch named, when read by a job of another run; every size they claim is checked against
// the file's length and the element cap before anything is allocated.

// Which run a file belongs to: written in every header, compared on reading.
struct ShardRun {
    std::string meshHash;        // content hash of the mesh file (hashFile)
    uint64_t vertexCount = 0, triangleCount = 0;
    TransferOptions options;     // interreflected, bounces > 0; range and threads play no part in the identity
    int channels = 1;            // rows of the exitant arrays: 1 (one albedo, unit-albedo rows) or 3 (RGB)
    int shardIndex = 0, shardCount = 1;
    size_t rowBegin = 0, rowEnd = 0; // shardRows(vertexCount, shardIndex, shardCount)
};
// Needs options with mode interreflected and bounces > 0 (else throws prt::Error(kExitUsage)).
ShardRun makeShardRun(const TriMesh& mesh, const TransferOptions& options, const std::string& meshHash,
                      int shardIndex, int shardCount);

// One shard's rows after pass `pass`. Row r is vertex rowBegin + r.
struct ShardRows {
    int pass = 0;
    size_t rowBegin = 0, rowEnd = 0;
    std::vector<float> total;    // [rows][order^2][3]: direct plus bounces 1..pass, what computeTransfer returns
    std::vector<float> direct;   // [rows][order^2][3]: the direct (shadowed) pass alone (computeTransfer's keepDirect)
    std::vector<float> exitant;  // [rows][order^2 * channels]: what pass `pass` alone sends on (empty after pass B)
    uint64_t rays = 0, hits = 0, backFaceHits = 0; // of the shard's direct pass, carried to the last pass's bundle
    float rayOffset = 0.0f;
};

// Pass 0 of the run's shard: the direct pass of its rows, and its hit records written atomically to `hitsPath`.
// Needs a mesh as computeTransfer needs it, equal to the one run was made from. Fills `stats` (rays, times, hit
// bytes, peak memory). Rows are computeTransfer's direct rows, bit for bit.
ShardRows computeDirectShard(const TriMesh& mesh, const ShardRun& run, const std::string& hitsPath,
                             TransferStats& stats);

// Pass `pass` (1..bounces) of the run's shard: bounce `pass` of its rows. Reads and checks `previousPath` (this
// shard's rows of pass - 1, writeShardRows), `hitsPath` (this shard's hit records) and `exitantPath` (the exitant
// array of pass - 1, gatherExitant); throws prt::Error(kExitInput) naming the file when one belongs to another run,
// shard or pass, or is malformed. Peak memory: the mesh, the rows of that array that its hits gather from (the
// corners of its hit triangles, order^2 * channels floats each: around a shard of a large scene, a fraction of the
// vertices; at most all of them), a row index per triangle corner, and this shard's hits and rows. After the last
// pass the rows' totals equal computeTransfer's rows bit for bit.
ShardRows computeBounceShard(const TriMesh& mesh, const ShardRun& run, int pass, const std::string& previousPath,
                             const std::string& hitsPath, const std::string& exitantPath, TransferStats& stats);

// Writes a shard's rows (atomically: temporary name, then rename) for the next pass.
void writeShardRows(const std::string& path, const ShardRun& run, const ShardRows& rows);
// Reads back their total and direct sections, checked against the run, the shard and the pass; `exitant` stays
// empty. A bounce gathers from the pass's joined exitant array instead; gatherExitant reads that section.
ShardRows readShardRows(const std::string& path, const ShardRun& run, int pass);

// Joins the exitant rows of one pass's shards (files in any order, one per shard of run.shardCount, each checked
// against the run) into the whole array, written atomically to `output` for the next pass. Returns the pass.
// Streams: copies each shard's rows in 1 MiB pieces, so it holds neither the array nor a shard's rows.
int gatherExitant(const std::vector<std::string>& parts, const ShardRun& run, const std::string& output);

// Receivers of transfer that are not the mesh's own vertices (atlas texels, probe points): each a point with a
// normal and a rotation key, the role the vertex index plays in the per-vertex direction-set rotation.
// Arrays are borrowed, not copied, and must outlive the call.
struct Receivers {
    const float* positions = nullptr; // [count][3], finite
    const float* normals = nullptr;   // [count][3], nonzero and finite (normalised inside)
    const float* albedo = nullptr;    // [count][3] linear RGB in [0, 1], or null: options.albedo for every receiver
    const uint64_t* keys = nullptr;   // [count] rotation keys, or null: receiver i has key firstKey + i
    // [count][3] unit geometric normals the ray origins step along (lib/raycast's spawn rule), or null: the
    // normals. Per-vertex passes give spawnNormals(mesh); points inside triangles may leave it null.
    const float* spawnNormals = nullptr;
    uint64_t firstKey = 0;
    size_t count = 0;
};

// Transfer at `receivers` with rays against `geometry`: the per-vertex integrator of computeTransfer (same
// direction set, frames, ray offset rayOffset(geometry), estimator and blocks), with receiver i standing where a
// vertex with index keys[i] would. Rows follow the receivers: coefficients [count][order^2][3]; vertexBegin 0,
// vertexEnd count. options.vertexBegin / vertexEnd are ignored; options.albedoOverride applies to receivers too;
// options.keepDirect fills Transfer::direct with each receiver's direct pass, as computeTransfer does.
// Unshadowed and shadowed: bit-identical to the row of a vertex of `geometry` with that index at (p, n) (a
// vertex on no triangle), whatever `threads`. Interreflected with B > 0 bounces: computes the (B - 1)-bounce
// per-vertex transfer of `geometry` first, then each receiver's direct pass gathers it once at its front-face
// hits (barycentric interpolation, cosine weighted, times the receiver's albedo): the same truncated series as
// the vertex result, summed in another order (equal to float rounding). Receivers are traced in chunks of fixed
// size so the hit records stay small; results do not depend on the chunking or the thread count.
// Needs: geometry as computeTransfer needs it; receivers as above (throws prt::Error(kExitInput) naming
// "receiver i" otherwise); options as for computeTransfer.
Transfer computeTransferAt(const TriMesh& geometry, const Receivers& receivers, const TransferOptions& options);

// The yardstick for the stage's ray throughput: casts exactly the occlusion rays that computeTransfer casts in
// shadowed mode (same origins, directions, blocks and threads) with rtcOccluded1 and nothing else.
struct RayThroughput {
    uint64_t rays = 0;
    uint64_t occluded = 0;
    double seconds = 0.0;    // excluding the BVH build, wall clock
    double cpuSeconds = 0.0; // the same in process CPU time
};
RayThroughput castBareOcclusionRays(const TriMesh& mesh, const TransferOptions& options);
// The same for receivers: exactly the occlusion rays computeTransferAt casts in shadowed mode.
RayThroughput castBareOcclusionRaysAt(const TriMesh& geometry, const Receivers& receivers,
                                      const TransferOptions& options);

} // namespace prt
