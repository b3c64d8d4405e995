// Texture-space bake: diffuse SH transfer per atlas texel, optionally with detail (normals, positions and shadows)
// from a high-resolution mesh, gutters filled by push-pull, written as multi-channel OpenEXR or range-compressed
// 8-bit layers next to a bundle that references them. `prt bake` is runBake().
//
// Texel space (docs/conventions.md, glTF): texel (x, y) of a W x H atlas, row 0 at the top, has its centre at
// uv = ((x + 0.5) / W, (y + 0.5) / H) in TEXCOORD_0's v-down convention, so no flip happens anywhere.
// Texel arrays are row-major, linear index y * W + x, with `channels` interleaved floats per texel.
// A coefficient texture holds the per-texel transfer [order^2][3] as channels "T000.R", "T000.G", "T000.B",
// "T001.R", ... (coefficient j as three decimal digits, docs/bundle.md "Texel layers").
#pragma once

#include "bundle.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace prt {

struct Surface; // lib/material: a scene's materials at surface points

// Largest atlas side: a 16384^2 atlas of order-3 float transfer already takes 29 GB.
inline constexpr int kMaxBakeResolution = 16384;

// TEXCOORD_<set> of a .glb / .gltf file, per vertex in the order readBundle gives the merged mesh.
// Throws prt::Error naming the file and the primitive that lacks the set.
std::vector<float> readTexcoordSet(const std::string& path, int set);

// ---- rasterisation ----------------------------------------------------------------------------------------------

// How texcoords outside [0, 1] are treated: refused, or wrapped onto the atlas (texel coordinates modulo size).
enum class UvWrap { None, Repeat };
// Parses "none" | "repeat"; throws prt::Error(kExitUsage) otherwise.
UvWrap parseUvWrap(const std::string& name);

// The covered texels of an atlas and where on the surface each one samples.
struct TexelSamples {
    int width = 0, height = 0;
    std::vector<uint32_t> texel;       // covered texels in ascending linear index y * width + x
    std::vector<uint32_t> triangle;    // per covered texel: the triangle its sample point lies on
    std::vector<float> barycentric;    // per covered texel: weights of that triangle's corners, >= 0, summing to 1
    std::vector<uint8_t> centreInside; // per covered texel: 1 if its centre lies in the triangle, else 0
    size_t degenerateTriangles = 0;    // triangles of zero UV area: they cover no texel
    size_t overlappingTexels = 0;      // texel centres strictly inside two triangles (only with allowOverlap)
};

struct RasterOptions {
    int width = 0, height = 0;
    UvWrap wrap = UvWrap::None;
    bool allowOverlap = false; // otherwise overlapping UVs are an error: transfer needs a unique atlas
};

// Rasterises every UV triangle conservatively: a texel is covered when its square overlaps the triangle with
// positive area. Its sample point is the texel centre when the centre lies in the triangle, else the point of
// the triangle nearest to the centre (in UV space). A texel several triangles cover takes, in this order, a
// triangle containing its centre, the nearest triangle, the lowest triangle index; so edges shared inside a chart
// never disagree and the result does not depend on triangle order beyond that last tie.
// Needs: mesh.texcoords per vertex, indices in range, 1 <= width, height <= kMaxBakeResolution.
// Throws prt::Error(source, ...) naming the vertex for a non-finite texcoord or, without wrap, one outside
// [0, 1]; naming both triangles and the texel when two triangles contain one texel centre strictly inside (UVs
// overlap) unless options.allowOverlap, in which case the lower triangle keeps the texel and it is counted.
TexelSamples rasteriseAtlas(const TriMesh& mesh, const RasterOptions& options, const std::string& source);

// The atlas's coverage: 1 for covered texels, 0 elsewhere; width * height bytes.
std::vector<uint8_t> coverageMask(const TexelSamples& samples);

// Object-space sample points and unit normals (the interpolated vertex normal, or the face normal where the
// interpolation vanishes), [sample][3] each. Needs mesh.normals and samples from this mesh.
void texelSurface(const TriMesh& mesh, const TexelSamples& samples, std::vector<float>& positions,
                  std::vector<float>& normals);

// ---- detail from a high-resolution mesh (the cage approach) ----------------------------------------------------

struct CageProjection {
    std::vector<float> positions; // [sample][3]: the high mesh's surface point, or the low point on a miss
    std::vector<float> normals;   // [sample][3]: the high mesh's interpolated unit normal, or the low one on a miss
    std::vector<uint8_t> hit;     // [sample]
    std::vector<uint32_t> triangle; // [sample]: the high triangle hit (UINT32_MAX on a miss)
    std::vector<float> barycentric; // [sample][3]: where on it, weights of its corners
    size_t misses = 0;
};

// For every low-mesh sample (point p, unit normal n) casts a ray from the cage point p + cage * n along -n and
// takes the first surface of `high` within 2 * cage: the high-resolution surface the low one stands in for.
// Needs: high with normals per vertex, cage > 0 and finite. Deterministic and independent of thread count.
CageProjection projectOntoHigh(const TriMesh& high, const std::vector<float>& positions,
                               const std::vector<float>& normals, float cage);

// ---- gutters ----------------------------------------------------------------------------------------------------

// Push-pull hole filling. Pull: a pyramid down to 1 x 1 whose texels average their 2 x 2 children over those that
// hold a value (binary coverage weights). Push: from the coarsest level back to the finest, every empty texel takes
// the bilinear interpolation of its parent level, already filled. Covered texels keep their bits; with any texel
// covered, every texel ends with a value, a convex combination of covered ones, and a constant image stays exactly
// constant. Works on 16 channels at a time, so its memory beyond the image is about 1.4 floats per texel and channel
// chunk. Needs covered of width * height bytes; texels [width * height][channels].
void pushPull(float* texels, int width, int height, int channels, const uint8_t* covered);

// The thesis's fill, kept for comparison: one pass in which every empty texel with covered 8-neighbours takes
// their average (from a snapshot, so scan order does not matter). Texels further out keep their values.
void dilateOneRing(float* texels, int width, int height, int channels, const uint8_t* covered);

// ---- 8-bit range compression (the thesis's storage) ------------------------------------------------------------

// Per layer (a group of channelsPerLayer consecutive channels, e.g. one SH coefficient's RGB), its [min, max]
// over all texels and q = round(255 * (value - min) / (max - min)); a constant layer stores q = 0.
struct RangeCompressed {
    std::vector<uint8_t> values; // [texel][layers * channelsPerLayer], like the input
    std::vector<float> range;    // [layer][2]: min, max
};
// Needs finite texels. Guarantees: rangeExpand(...) differs from the input by at most (max - min) / 510 per
// layer, plus float rounding.
RangeCompressed rangeCompress(const float* texels, size_t texelCount, int layers, int channelsPerLayer);
// value = min + q * (max - min) / 255.
std::vector<float> rangeExpand(const RangeCompressed& compressed, size_t texelCount, int layers,
                               int channelsPerLayer);

// ---- tangent-space normal maps ----------------------------------------------------------------------------------

// Per-vertex tangent frames from the UV parameterisation: xyz the unit tangent along +u, orthogonal to the vertex
// normal, w = +1 or -1 the handedness, so the bitangent is w * cross(normal, tangent) and points along -v (up in
// the image, glTF's convention for normal textures). Area-weighted over the triangles around each vertex; a vertex
// with no usable UV gradient gets any tangent orthogonal to its normal, w = +1. Needs normals and texcoords.
std::vector<float> vertexTangents(const TriMesh& mesh);

// Each sample's normal `objectNormals` ([sample][3], unit) in the tangent frame interpolated at the sample
// (tangent, bitangent, interpolated normal, re-orthonormalised): [sample][3], unit. A normal equal to the low
// mesh's own interpolated normal gives (0, 0, 1).
std::vector<float> tangentSpaceNormals(const TriMesh& mesh, const std::vector<float>& tangents,
                                       const TexelSamples& samples, const std::vector<float>& objectNormals);

// ---- lightmap atlas generation ----------------------------------------------------------------------------------

struct AtlasOptions {
    int width = 0, height = 0;
    int padding = 4;            // texels between charts' covered texels (and half of it at the atlas border)
    double chartAngle = 60.0;   // degrees: a face joins a chart when its normal is this close to the chart's seed
};

struct GeneratedAtlas {
    TriMesh mesh;                      // the input with texcoords; vertices split where charts meet
    std::vector<uint32_t> sourceVertex; // output vertex -> input vertex
    std::vector<uint32_t> chart;        // per triangle: its chart
    size_t charts = 0;
    double texelsPerUnit = 0.0;         // atlas texels per mesh unit of length, the same for every chart
};

// A unique UV atlas for a mesh without one. Charts grow over OpenMesh's face adjacency from seed faces (lowest
// unassigned index first, nearest normals first) while face normals stay within chartAngle of the seed's; a chart
// whose projection onto its seed's plane folds over itself is grown again from its own faces with half the cone,
// down to single faces. Each chart is projected onto the plane of its seed normal and turned to its minimal-area
// bounding rectangle; all are packed (skyline, bottom-left) at one common texel density, the largest that fits,
// with `padding` texels between charts.
// Needs: indices in range, at least one triangle; 8 <= width, height <= kMaxBakeResolution; padding >= 2;
// 0 < chartAngle < 90. Guarantees: texcoords in [0, 1]; rasteriseAtlas on the result finds no overlap; every face
// within chartAngle of its chart's projection direction; same input, same output.
// Throws prt::Error(kExitInput) when the charts do not fit at any density (too many for the padding).
GeneratedAtlas generateAtlas(const TriMesh& mesh, const AtlasOptions& options);

// ---- seams ------------------------------------------------------------------------------------------------------

// An edge of the surface (vertices at equal positions count as one) whose two triangles map it to different
// places in the atlas, on a smooth surface: where the vertex normals of the two sides differ (a crease, such as a
// floor meeting a wall, across which irradiance really jumps) the edge is no seam. Corners a, b of `first` and c, d of `second` lie at the same two positions: a with c,
// b with d.
struct SeamEdge {
    uint32_t first = 0, second = 0; // triangles
    uint32_t a = 0, b = 0, c = 0, d = 0;
};
// Needs texcoords and indices in range. Deterministic order (by first triangle, then edge).
std::vector<SeamEdge> findSeams(const TriMesh& mesh);

// Makes the two sides of every seam agree under bilinear filtering (after the gutters are filled, since lookups
// on a chart's border read them): the texels that lookups along seams touch move to the x minimising
// |x - x0|^2 + weight * sum over seam points p of |bilinear_first(p) - bilinear_second(p)|^2, with points a third of
// a texel apart along each edge (sparse Cholesky, Eigen). Larger weights close the jump further and move texels
// more; all other texels keep their bits. texels [width * height][channels].
// Returns the number of texels changed. Deterministic.
size_t stitchSeams(const TriMesh& mesh, const std::vector<SeamEdge>& seams, int width, int height, float* texels,
                   int channels, double weight = 16.0);

// Radiance jump across seams: at `pointsPerEdge` points along each seam edge, the bilinear lookups of `radiance`
// (an RGB atlas, [width * height][3]) through either side's texcoords, and their difference.
struct SeamJump {
    double rms = 0.0;       // RMS over points and channels of the difference
    double meanRadiance = 0.0; // mean over the same points and channels of the two sides' average
    size_t points = 0;
};
SeamJump texelSeamJump(const TriMesh& mesh, const std::vector<SeamEdge>& seams, const float* radiance,
                       int width, int height, int pointsPerEdge);
// The same for per-vertex radiance ([vertex][3]) linearly interpolated along the edges.
SeamJump vertexSeamJump(const TriMesh& mesh, const std::vector<SeamEdge>& seams, const float* radiance,
                        int pointsPerEdge);

// Bilinear lookup of an atlas at uv (texel centres at (x + 0.5) / W; clamped at the borders): channels floats.
void sampleBilinear(const float* texels, int width, int height, int channels, float u, float v, float* out);

// ---- texture files ----------------------------------------------------------------------------------------------

// Storage of coefficient textures: one multi-channel OpenEXR (half or float), or one 8-bit RGB PNG per
// coefficient with the per-layer [min, max] in a JSON sidecar; or none: "bundle" keeps the float32 rows in the
// bundle's own buffer, which the thin runtime (texelRelightModel) and the browser viewer read without images.
enum class TexelFormat { Half, Float, U8, Bundle }; // Bundle: float32 rows in the bundle's own buffer, no texture
// Parses "half" | "float" | "u8" | "bundle"; throws prt::Error(kExitUsage) otherwise.
TexelFormat parseTexelFormat(const std::string& name);
const char* texelFormatName(TexelFormat format);

// Writes [width * height][coefficients][3] transfer atomically as one OpenEXR with ZIP compression and channels
// named by texelCoefficientChannel (runtime.h: "T000.R"), as the runtime reads them. Throws prt::Error(path, ..., kExitOutput) when it cannot be written.
void writeCoefficientExr(const std::string& path, const float* texels, int width, int height, int coefficients,
                         bool half);

// Reads a coefficient EXR back, finding channels by name: [width * height][coefficients][3].
// Throws prt::Error naming the file for a missing file, a missing channel or a size other than expected
// (expected sizes of 0 accept any).
std::vector<float> readCoefficientExr(const std::string& path, int& width, int& height, int& coefficients);

// Reads the first `channels` channels of an 8-bit image (expected sizes of 0 accept any).
std::vector<uint8_t> readImage8(const std::string& path, int& width, int& height, int channels);

// ---- scenes (scene_atlas.cpp) ------------------------------------------------------------------------------------

// The texcoords a scene bakes into, per flattened vertex: TEXCOORD_<uvSet> (0 or 1), or with uvSet -1 TEXCOORD_1
// when every primitive has it and no mesh is placed twice; empty when the atlas is to be generated (logged why).
// chosenSet receives the set taken, or -1. Throws prt::Error(path, ...) for a set some primitive lacks, a set
// above 1 (kExitUsage), and an explicit set on a mesh placed by several nodes, whose instances it would overlap.
std::vector<float> sceneAtlasTexcoords(const Bundle& scene, int uvSet, const std::string& path, int& chosenSet);

// The atlas of a scene bake as the layer "lightmap_uv" (domain "corner", semantic "lightmap_uv", [3 T][2]): row
// 3 t + k is corner k of triangle t of the flattened mesh, its atlas uv. Corners, not vertices, because a generated
// atlas splits vertices where charts meet and the scene keeps its own vertices. Needs texcoords on atlasMesh.
Layer lightmapUvLayer(const TriMesh& atlasMesh);

// ---- the stage --------------------------------------------------------------------------------------------------

struct BakeOptions {
    std::string input;        // the low mesh: .glb / .gltf with normals
    std::string output;       // .glb bundle; textures go next to it, named after it
    std::string high;         // optional high-resolution mesh (.glb / .gltf with normals)
    int resolution = 512;     // atlas side, 1..kMaxBakeResolution
    int order = 3;
    int samples = 1024;
    int bounces = 0;          // > 0: interreflected
    // The atlas: TEXCOORD_<uvSet> of the input, or with -1 (auto) the mesh's TEXCOORD_0 (a scene's TEXCOORD_1, its
    // lightmap set, when no mesh is placed twice), and a generated atlas where that set is absent. A scene's
    // TEXCOORD_0 addresses its textures, so a scene takes it only when asked.
    int uvSet = -1;
    // Bake into a generated lightmap atlas whatever texcoords the input has (for texcoords that are no lightmap:
    // shared between instances, overlapping or of zero area). Excludes uvSet >= 0.
    bool generateAtlas = false;
    std::array<float, 3> albedo = {1.0f, 1.0f, 1.0f}; // used where the low mesh has no albedo, or always with
    bool albedoOverride = false;                      // albedoOverride (linear RGB in [0, 1])
    TexelFormat format = TexelFormat::Half;
    UvWrap wrap = UvWrap::None;
    bool allowOverlap = false;
    bool dilateOnly = false;  // the thesis's one-ring dilation instead of push-pull
    bool seamStitch = true;
    bool highPosition = true; // with a high mesh: sample (and shade) at the projected high-mesh point
    double cage = 0.02;       // cage distance, relative to the low mesh's bounding-box diagonal
    double maxMissFraction = 0.01; // more texels than this missing the high mesh is an error
    int padding = 4;          // generated atlases
    uint64_t seed = 0;
    int threads = 0;
    bool yardstick = false;   // also cast the direct pass's rays with bare Embree, to compare rays/s in one run
    std::string toolVersion;
    // Sharding (docs/bundle.md "texel_range"): shardCount > 1 computes the transfer of covered texels
    // shardRows(covered, shardIndex, shardCount) only and writes them as a shard bundle, no textures; shardFiles
    // non-empty joins such shards (all of one bake with these options) and finishes as the unsharded bake does.
    int shardIndex = 0, shardCount = 1;
    std::vector<std::string> shardFiles;
};

struct BakeStats {
    size_t texels = 0;              // covered texels, each one receiver
    uint64_t rays = 0;              // transfer rays (all in the direct pass)
    uint64_t cageRays = 0;          // rays of the cage projection onto the high mesh
    double transferSeconds = 0.0;   // per-texel transfer, wall clock
    double directSeconds = 0.0;     // its direct pass: rays plus accumulation
    double fillSeconds = 0.0;       // push-pull or dilation of the coefficient atlas
    size_t seamEdges = 0;
    size_t stitchedTexels = 0;
    double bareRaysPerSecond = 0.0; // with options.yardstick: bare rtcOccluded1 over the same rays
};

// What a bake computed, before anything is written.
struct BakedAtlas {
    TriMesh mesh;                    // the low mesh with the atlas as texcoords (generated when it had none)
    TexelSamples samples;
    std::vector<float> transfer;     // [width * height][order^2][3]: filled and stitched
    std::vector<float> bounce;       // the same for what the bounces add (transfer minus the direct part);
                                     // empty without bounces. Filled and stitched alike (both are linear).
    std::vector<float> surface;      // [width * height][kTexelSurfaceChannels] (runtime.h, "texel_surface"), filled
    std::vector<float> normals;      // [width * height][3]: tangent-space unit normals, filled
    nlohmann::json params;           // what the texel layer records about the bake (docs/bundle.md)
    BakeStats stats;
    std::shared_ptr<const Bundle> scene; // BakeSurface::scene: the output keeps the asset, the atlas goes in a layer
};

// The bake in three steps, so that shards compute step 2 for a range and a merge does step 3 once:
// 1. bakeSurface: reads the inputs and validates everything (options, UVs, high-mesh coverage): the atlas, its
//    covered texels (the row order of the transfer) and the receivers, cage-projected onto the high mesh if given.
//    A scene bakes one atlas over every placed primitive in world space, so each instance has texels of its own
//    (a generated atlas, unless the scene's TEXCOORD_1 is unique), and refuses --high and --albedo.
// 2. bakeTexelTransfer: the per-vertex transfer integrator with covered texels [begin, end) as receivers (rays
//    against the high mesh when given). Rows depend only on the surface and the options, never on the range.
// 3. finishBake: from the rows of every covered texel, scatter, gutter fill, seam stitching, tangent-space normals.
// bakeAtlas is the three over all texels. None writes anything; they log progress.
// Throw prt::Error (kExitUsage for bad options, kExitInput for bad inputs).
struct BakeSurface {
    TriMesh mesh;                 // the low mesh with the atlas as texcoords (generated when it had none)
    TexelSamples samples;
    std::vector<float> positions; // receivers [covered texel][3]: sample points (high-mesh points with --high)
    std::vector<float> normals;   // receivers' normals (the high mesh's with --high)
    std::vector<float> detailNormals; // what the normal map encodes, [covered texel][3]
    TriMesh high;                 // empty without --high
    nlohmann::json atlasRecord, highRecord; // recorded in the texel layer's params
    uint64_t cageRays = 0;
    // A scene (docs/bundle.md "Scene bundles"): the input bundle (its asset and flattened mesh, whose triangles are
    // `mesh`'s in the same order) and its decoded materials, which give every bounce its albedo and every texel its
    // diffuse albedo; the transfer is then irradiance transfer (params.albedo "excluded"). Null for a plain mesh.
    std::shared_ptr<const Bundle> scene;
    std::shared_ptr<const Surface> materials;
};
BakeSurface bakeSurface(const BakeOptions& options);

struct TexelTransferRows {
    size_t begin = 0, end = 0; // covered texels
    std::vector<float> rows;   // [end - begin][order^2][3]
    std::vector<float> bounce; // the same for the bounces' part (rows minus the direct pass); empty without bounces
    float rayOffset = 0.0f;
    BakeStats stats;           // rays, transferSeconds, directSeconds, bareRaysPerSecond
};
TexelTransferRows bakeTexelTransfer(const BakeSurface& surface, const BakeOptions& options, size_t begin,
                                    size_t end);

// Needs rows of every covered texel ([covered][order^2][3]) from bakeTexelTransfer with these options, and their
// bounce rows (empty without bounces).
BakedAtlas finishBake(BakeSurface surface, const BakeOptions& options, std::vector<float> rows,
                      std::vector<float> bounce, float rayOffset, BakeStats stats);

BakedAtlas bakeAtlas(const BakeOptions& options);

// The stage. Unsharded: bakeAtlas, then the textures and last the bundle that references them. With shardCount > 1:
// writeTexelShard. With shardFiles: joinTexelShards, finishBake, then the same files as unsharded, bit for bit.
// Each file is written atomically; when a later write fails the earlier files are removed, so an error leaves no
// output. Logs a summary and the stage cost.
// Throws prt::Error (kExitUsage, kExitInput as bakeAtlas and joinTexelShards; kExitOutput for write failures).
void runBake(const BakeOptions& options);

// ---- shards (shards.cpp) ----------------------------------------------------------------------------------------

// What a shard records so that a merge can tell whether it belongs to its bake: every option that changes the
// rows (atlas, rasterisation, high mesh and cage, transfer parameters), the inputs' content hashes and the atlas's
// size and covered texel count.
nlohmann::json texelShardIdentity(const BakeOptions& options, const BakeSurface& surface);

// Writes the shard bundle of options.output: the mesh with its atlas and one layer "texel_transfer" of domain
// "texel_range" holding the rows, params = identity + {shard: [I, N], row_begin, row_end, ray_offset}.
void writeTexelShard(const BakeOptions& options, const BakeSurface& surface, const TexelTransferRows& rows);

// Reads options.shardFiles and joins their rows: [covered][order^2][3], their bounce rows (the shards' layer
// "texel_transfer_bounce", present with bounces > 0) into `bounce`, and the ray offset they record.
// Needs shards 0..N-1 of one N, each once (any order), every identity member equal to this bake's, rows tiling
// [0, covered) exactly. Throws prt::Error(shard file, place, problem, kExitInput) naming the first shard and
// member that does not fit.
std::vector<float> joinTexelShards(const BakeOptions& options, const BakeSurface& surface, float& rayOffset,
                                   std::vector<float>& bounce);

} // namespace prt
