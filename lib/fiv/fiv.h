// Occluder FIV sampling (Fullsphere Irradiance Factorization, Michael & Chrysanthou): the precomputed shadow of
// one rigid occluder type, for receivers anywhere around it, under one distant environment. docs/fiv.md is the
// method's page (choices, measurements); docs/bundle.md documents the layers.
//
// The work is split in two:
//   (a) sampleVisibility: for every sample of a spherical grid of receiver positions around the occluder, which
//       texels of an environment cube the occluder hides (a coverage mask). Environment-independent, cacheable,
//       shardable over grid samples. Only rays that can hit the occluder's bounding sphere are cast.
//   (b) reduceVisibility + difMap + environmentFiv: the cheap environment reduction of every mask into the FIV
//       (9 floats per sample: the occluded radiance's vector irradiance, xyz per colour), plus the occluded power
//       (3 floats, for the partial-occluder correction), the unoccluded irradiance cube (DifMap) and FIV(Env).
//
// Grid (docs/bundle.md "FIV grids"): sample (i, j, k), i < azimuth, j < polar, k < shells, has row
// (k * polar + j) * azimuth + i. It places the occluder's bounding-sphere centre at c = p + rho_k R d(theta_j,
// phi_i) from the receiver point p, with phi_i = 2 pi i / azimuth (periodic), theta_j = pi j / (polar - 1) (both
// poles included) and d = (sin theta sin phi, cos theta, -sin theta cos phi), the world's equirectangular
// convention (docs/conventions.md). rho_k are the shell radii in units of the bounding-sphere radius R.
// Radiance is per steradian, irradiance per unit area; every sum over texels carries the texel's exact solid angle.
#pragma once

#include "bundle.h"
#include "image.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt::fiv {

// ---- limits (refused before anything is allocated) ---------------------------------------------------------
inline constexpr int kMaxAzimuth = 4096, kMaxPolar = 2049, kMaxShells = 1024, kMaxCube = 256, kMaxSupersample = 8;
inline constexpr uint64_t kMaxSamples = uint64_t(1) << 26;

// ---- the grid ------------------------------------------------------------------------------------------------
struct GridSpec {
    int azimuth = 128, polar = 65, shells = 30;
    double shellMin = 0.25, shellMax = 8.0; // in units of R; shells spaced evenly in log(rho) between them
    std::string spacing = "log";             // "log" | "linear"
    size_t sampleCount() const { return size_t(azimuth) * polar * shells; }
};

// Throws prt::Error(source, place, problem, exitCode) for a zero, negative or absurd dimension, a sample count
// above kMaxSamples, shellMin <= 0, shellMax <= shellMin, or an unknown spacing.
void checkGrid(const GridSpec& grid, const std::string& source, int exitCode);

// The cap on work and memory (not only on samples): the naive ray count samples x 6 cube^2 x supersample^2 bounds
// both the rays (visibility casts at most that many; about 28% in practice) and the mask bits (at most one bit
// per ray), and the reduction visits samples x 6 cube^2 texels. It may not exceed 16 x prt::maxElements(), 2^34 by
// default (11x the default grid's 1.5e9; PRT_MAX_ELEMENTS raises it). Throws prt::Error(source, "--grid", ...,
// exitCode) naming the count and the limit. 4096 x 2048 x 8 at cube 32 (4.1e11) is refused.
void checkWork(const GridSpec& grid, int cube, int supersample, const std::string& source, int exitCode);

// The shell radii rho_k (units of R), ascending: shellMin .. shellMax, `shells` of them (one shell: shellMin).
std::vector<double> shellRadii(const GridSpec& grid);

// Unit direction d of grid direction (i, j): exactly (0, +-1, 0) on the pole rows.
void gridDirection(const GridSpec& grid, int i, int j, double d[3]);

// Centre: middle of the axis-aligned bounds; radius: largest distance of a vertex from it (so every vertex lies
// in the sphere). Needs a non-empty mesh.
struct BoundingSphere {
    std::array<double, 3> centre{0, 0, 0};
    double radius = 0.0;
};
BoundingSphere boundingSphere(const TriMesh& mesh);

// ---- cubes -------------------------------------------------------------------------------------------------
// An environment cube of `size` texels per face edge, texel t = face * size^2 + row * size + column in the cube
// strip order of docs/conventions.md (faces +X, -X, +Y, -Y, +Z, -Z).
struct CubeTexels {
    int size = 0;
    std::vector<double> direction;   // [t][3], unit texel-centre directions
    std::vector<double> solidAngle;  // [t], exact; sums to 4 pi
    std::vector<double> cosRadius;   // [t], cosine of the largest angle between the centre and a corner
    std::vector<double> sinRadius;   // [t]
};
// Needs 1 <= size <= kMaxCube.
CubeTexels cubeTexels(int size);

// Unit direction of subsample (sx, sy) of `supersample` x `supersample` in texel t (stratum centres).
void subsampleDirection(const CubeTexels& cube, size_t t, int sx, int sy, int supersample, double d[3]);

// Radiance on a cube, area-weighted: every map texel (equirectangular or cube strip) is split among the cube
// texels it overlaps by solid angle: whole where it lies in one, cut by the boundary where one crosses it (as if
// straight in it), halved down to 1/64 of the texel per side near cube-texel corners, face seams and poles. Each
// cube texel's radiance is the power it received over its own exact solid angle. So the cube's power
// sum_t L_t dw_t equals the map's sum L dw to rounding, for every source however small (a sun of one map texel
// keeps its power, in the cube texels it overlaps), and a constant map comes out constant within 2e-4 (tests/fiv).
// Needs a map whose size matches its layout; deterministic for any thread count.
struct CubeEnvironment {
    int size = 0;
    std::vector<double> radiance; // [t][3]
};
CubeEnvironment resampleToCube(const EnvironmentMap& env, int size);

// The cube as an EnvironmentMap (cube strip layout), so the brute-force reference can integrate it exactly.
EnvironmentMap cubeAsEnvironmentMap(const CubeEnvironment& cube);

// The DifMap: unoccluded irradiance sum_t L_t max(0, n . w_t) dw_t at the centre direction n of every texel of
// a cube of `size` ([t][3]). Deterministic (fixed summation order), parallel over output texels.
std::vector<float> difMap(const CubeEnvironment& env, int size);

// FIV(Env) = sum_t L_t w_t dw_t over the whole sphere: [channel][xyz].
std::array<double, 9> environmentFiv(const CubeEnvironment& env);

// ---- (a) visibility ------------------------------------------------------------------------------------------
struct VisibilityOptions {
    GridSpec grid;
    int cube = 32;       // environment cube face size the masks are sampled on
    int supersample = 1; // rays per texel edge: coverage in steps of 1 / supersample^2
    bool allowOpen = false;
    int threads = 0;        // 0 = all
    int shardIndex = 0, shardCount = 1; // rows shardRows(sampleCount, index, count)
};

// The masks of grid rows [rowBegin, rowEnd). A row's candidate texels are those whose cone (centre, radius)
// reaches the bounding sphere seen from the receiver (all texels when rho < 1), in ascending texel order; its
// mask stores, per candidate, the count of subsample rays that hit the occluder (bitsPerTexel bits each, LSB
// first, the row starting on a byte boundary). Invalid rows (receiver inside the occluder) store no bits.
struct Visibility {
    GridSpec grid;
    int cube = 0, supersample = 1, bitsPerTexel = 1;
    BoundingSphere sphere;
    size_t rowBegin = 0, rowEnd = 0;
    int shardIndex = 0, shardCount = 1;
    std::vector<uint32_t> offsets; // rowEnd - rowBegin + 1 byte offsets into bits
    std::vector<uint8_t> bits;
    std::vector<uint8_t> valid;    // per row: 1 usable, 0 receiver inside the closed occluder
    uint64_t rays = 0;             // rays cast (inside votes included)
    uint64_t naiveRays = 0;        // rays of the naive method: cube texels x supersample^2 per sample
    bool closed = true;            // the mesh had no boundary edges
    size_t boundaryEdges = 0;
};

// Needs a validated mesh (lib/mesh) with at least one triangle. Throws prt::Error(source, ...): kExitInput for an
// open or non-manifold occluder without allowOpen (the inside test needs a closed surface; with allowOpen a
// sample is inside when most of 26 fixed rays first hit a back face), kExitUsage for bad options.
// Same inputs give bit-identical masks for any thread count and any sharding.
Visibility sampleVisibility(const TriMesh& occluder, const VisibilityOptions& options, const std::string& source);

// Bitstream helpers shared by (a) and (b).
int bitsPerTexel(int supersample);
// The candidate texels of grid direction d at radius rho (units of R), ascending, appended to `out`.
void candidateTexels(const CubeTexels& cube, const double d[3], double rho, std::vector<uint32_t>& out);

// Joins shards (any order) into the unsharded visibility. Throws prt::Error(files[s], ...) for shards of other
// runs, missing or repeated shards.
Visibility joinShards(std::vector<Visibility> shards, const std::vector<std::string>& files);

// ---- (b) reduction -----------------------------------------------------------------------------------------
struct FivGrid {
    GridSpec grid;
    BoundingSphere sphere;
    int cube = 0, supersample = 1;
    std::vector<float> fiv;   // [sample][channel][xyz], 0 for invalid samples
    std::vector<float> power; // [sample][channel]: sum of L dw over the occluded texels
    std::vector<uint8_t> valid;
};
// Needs the whole grid (rowBegin 0, rowEnd sampleCount) and env.size == vis.cube. Fixed summation order, so the
// result does not depend on threads or on how the visibility was sharded.
// Errors (a row with fewer bits than its candidates) name `source`, the visibility's file.
FivGrid reduceVisibility(const Visibility& vis, const CubeEnvironment& env, const std::string& source = "");

// ---- small sources, shadowed from their own texels --------------------------------------------------------
// A sun smaller than a cube texel is smeared over it, and its shadow comes from the texel centre's mask bit. So
// the map's dominant small sources can be taken out of the cube (the reduction then sees the rest) and shadowed
// by rays toward each of their own map texels (addSourceShadows).
struct SmallSourceOptions {
    int maxSources = 4;            // at most this many sources, brightest first
    double radiusDegrees = 5.0;    // a source: texels within this angle of its peak texel ...
    double floorFraction = 0.01;   // ... whose luminance is at least this fraction of the peak's ...
    double minPowerFraction = 0.1; // ... taken only when together they hold this fraction of the map's power
};
struct SmallSources {
    std::vector<double> direction; // [texel][3], unit map-texel centres
    std::vector<double> power;     // [texel][3], radiance x exact solid angle
    std::vector<double> powerFraction; // per source: its share of the map's luminance power
    std::vector<size_t> texelCount;    // per source: its texels
};
// Finds the sources (repeatedly the brightest remaining texel; the texels of its cone above the floor; kept when
// they hold minPowerFraction of the whole map's power, otherwise the search ends), copies their texels out and sets
// them to 0 in `env`, so env + sources is the map again, power for power. A map without such a source (courtyard,
// a constant map) gives no texels and is left as it was. Deterministic.
SmallSources extractSmallSources(EnvironmentMap& env, const SmallSourceOptions& options = {});

// Adds to every valid sample of `grid` the sources' light the occluder hides from its receiver point: one ray per
// source texel from the point (as sampleVisibility places it), traced only when it can meet the bounding sphere;
// a hit adds the texel's power to grid.power and power x direction to grid.fiv. Needs `grid` reduced from `vis`
// of this `occluder`. Deterministic for any thread count (`threads` 0: all). Returns the rays cast.
uint64_t addSourceShadows(const TriMesh& occluder, const Visibility& vis, const SmallSources& sources, FivGrid& grid,
                          int threads = 0);

// ---- the sources' own grid ------------------------------------------------------------------------------------
// A sun's shadow is a step, and the main grid's trilinear interpolant spreads it over a cell (2.8 degrees and one
// shell at 128x65x30). The sources' hidden fraction f gets a grid of its own, finer and cheap (one ray per source
// texel per sample, no cube), which the runtime interpolates as the main grid (trilinear, rho^2 between shells),
// sharpens to g = clamp(0.5 + K (f - 0.5), 0, 1) and subtracts as g max(0, N . FIV_sources); the main grid then
// holds the rest of the map (layers fiv_source_grid, fiv_source_valid; docs/fiv.md decision 13).
inline constexpr double kMinSourceSharpen = 1.0, kMaxSourceSharpen = 100.0;
struct SourceGridOptions {
    GridSpec grid;        // the source grid's own dimensions and shells (prt fiv: the main grid's shells)
    double sharpen = 2.0; // K, in kMinSourceSharpen..kMaxSourceSharpen; recorded for the runtime
    int threads = 0;      // 0 = all
};
struct SourceGrid {
    GridSpec grid;
    BoundingSphere sphere;         // the occluder's (boundingSphere), the main grid's too
    double sharpen = 2.0;
    size_t texels = 0;             // source texels
    std::array<double, 3> power{}; // the sources' power sum L dw [channel]
    std::array<double, 9> fiv{};   // FIV_sources = sum L w dw [channel][xyz]
    std::vector<float> fraction;   // [row]: hidden share of the sources' luminance power in [0, 1]; 0 when invalid
    std::vector<uint8_t> valid;    // [row]: 1 usable, 0 receiver inside the occluder
    uint64_t sourceRays = 0, insideRays = 0;
};
// Refuses (prt::Error(source, "--source-grid", ..., exitCode)) a grid that checkGrid refuses, or one whose rays,
// samples x (sourceTexels + 26), exceed 16 x prt::maxElements() (the bound checkWork puts on the main grid).
void checkSourceGrid(const GridSpec& grid, size_t sourceTexels, const std::string& source, int exitCode);
// Needs a mesh with triangles and at least one source texel of positive power (extractSmallSources' output);
// throws prt::Error(source, ..., kExitUsage) for a grid checkSourceGrid refuses, K out of range or no sources.
// Each sample's receiver point is placed as sampleVisibility places it (rows, shells, poles alike); samples with
// rho < 1 get sampleVisibility's inside vote (26 rays; exact for a closed mesh, a majority for an open one); a
// valid sample casts one ray per source texel that can meet the bounding sphere (traced once per pole row).
// f = luminance of the hidden texels' power / luminance of all of it. Deterministic for any thread count.
SourceGrid sampleSourceGrid(const TriMesh& occluder, const SmallSources& sources, const SourceGridOptions& options,
                            const std::string& source);

// ---- self-shadowing at the mesh's own vertices ---------------------------------------------------------------
// The irradiance each vertex of `mesh` receives with the mesh itself as the only occluder:
// E_v = sum_t L_t dw_t V(p_v, w_t) max(0, n_v . w_t) over the texels of `env` and the texels of `sources` (their
// radiance x solid angle; pass the cube of the map without them, as extractSmallSources leaves it, or no sources),
// one ray per direction above the vertex's tangent plane from the spawn rule of lib/raycast (spawnOrigin,
// spawnNormals, rayOffset), texels of zero radiance skipped. [vertex][3]. Needs vertex normals (else
// prt::Error(kExitInput)); a zero normal gives 0. Deterministic for any thread count (`threads` 0: all).
// `raysCast` (or null) receives the rays cast. The runtime uses it instead of the grid's FIV_self when the
// receiver is this mesh (layer fiv_self, docs/fiv.md decision 14).
std::vector<float> selfIrradiance(const TriMesh& mesh, const CubeEnvironment& env, const SmallSources& sources,
                                  int threads = 0, uint64_t* raysCast = nullptr);

// ---- bundles -------------------------------------------------------------------------------------------------
// The visibility bundle (object 0 the occluder mesh, layers fiv_mask_offsets, fiv_mask_bits, fiv_valid) and its
// reader. readVisibility throws prt::Error(path, layer, problem) when a layer is missing, its size disagrees with
// the grid in its params, or an offset runs past the bits.
Bundle visibilityBundle(const TriMesh& occluder, const Visibility& vis, const nlohmann::json& inputs);
Visibility readVisibility(const Bundle& bundle, const std::string& path);

// The FIV bundle: the occluder mesh, fiv (float16 [S,3,3] or float32), fiv_power, fiv_valid, difmap, fiv_env, and
// the optional fiv_self ([V,3]) and fiv_source_grid ([S'], float16 unless !half) with fiv_source_valid ([S'] u8),
// whose params carry the source grid's header (gridParams), sharpen, source_power [3] and source_fiv [3][3]; the
// grid's `fiv` params then say sources "fiv_source_grid" (the grid holds the rest of the map).
struct FivBundleOptions {
    bool half = true;
    int difmapSize = 32;
    std::string envHash;
    std::vector<float> selfIrradiance; // [vertex][3] (selfIrradiance) or empty: then no fiv_self layer
    const SourceGrid* sourceGrid = nullptr; // or null: then no fiv_source_grid / fiv_source_valid layers
};
Bundle fivBundle(const TriMesh& occluder, const FivGrid& grid, const std::vector<float>& difmap,
                 const std::array<double, 9>& fivEnv, const FivBundleOptions& options, const nlohmann::json& inputs);

// A FIV scene bundle (version 2, docs/fiv.md "Scene bundles"): object 0 the receiver (role receiver), object t + 1
// occluder type t (role occluder, the type's mesh) with its grid layers renamed fiv.k, fiv_power.k, fiv_valid.k
// (bundle.h objectLayerName), difmap and fiv_env once, from the first grid, and instances: the receiver, then one
// per placement. With `self` (the receiver's own FIV bundle), object 0 carries its grid too (self-shadowing).
// Needs FIV bundles from `prt fiv` reduced under one environment, a receiver with normals, a self grid of the
// receiver's own mesh, placements of existing types, files at the sources (their hashes become the inputs).
// Throws prt::Error naming the source and the problem otherwise. The runtime reads the result with fivScene.
struct SceneType {
    const Bundle* bundle = nullptr; // a FIV bundle
    std::string source;             // its path
    std::string name;               // the object's name (made unique with -2, -3, ...), "" for "occluder"
};
struct ScenePlacement {
    size_t type = 0;                        // index into the types
    std::array<float, 3> translation{0, 0, 0}; // the type's vertex p sits at p + translation
};
Bundle fivSceneBundle(const Bundle& receiver, const std::string& receiverSource, const std::vector<SceneType>& types,
                      const std::vector<ScenePlacement>& placements, const Bundle* self, const std::string& selfSource);

// Params every grid layer carries (dimensions, axes, shell radii, sphere).
nlohmann::json gridParams(const GridSpec& grid, const BoundingSphere& sphere);

} // namespace prt::fiv

namespace prt::fiv {

// ---- the stage -----------------------------------------------------------------------------------------------
struct FivStageOptions {
    std::vector<std::string> inputs; // one occluder mesh (.glb), or visibility bundles (one whole, or every shard)
    std::string output;              // .glb: the FIV bundle, or with visibilityOnly the visibility bundle
    std::string env;                 // environment map; needed unless visibilityOnly
    VisibilityOptions visibility;    // grid, cube, supersample, allowOpen, threads, shard (mesh input only)
    bool visibilityOnly = false;     // (a) only
    std::vector<std::string> merge;  // with visibilityOnly: visibility shards to join instead of sampling
    int difmapSize = 32;
    bool half = true;                // FIV layers as float16 (else float32)
    bool sources = false;            // the map's dominant small sources shadowed from their own texels
    bool selfVertices = false;       // the mesh's own self-shadowed irradiance at its vertices (layer fiv_self)
    // With sources: the sources' own grid (sampleSourceGrid; azimuth 0 = none), its K. A map without a small source
    // gets none (the bundle is then the one without the option).
    GridSpec sourceGrid{0, 0, 0};
    double sourceSharpen = 2.0;
};
// `prt fiv`: (a) from a mesh input, unless the input is a visibility bundle already; then (b) unless
// visibilityOnly. With visibilityOnly and `merge`, joins those visibility shards into one visibility bundle. Writes one bundle atomically, logs rays against the naive count, reports its cost.
// With sourceGrid (needs sources), the grid's layers hold the rest of the map and the sources' shadow is the
// source grid's (layers fiv_source_grid, fiv_source_valid).
// Throws prt::Error: kExitUsage for bad options (a shard without visibilityOnly, no env, several meshes,
// a source grid without sources or one checkSourceGrid refuses),
// kExitInput for bad inputs (see sampleVisibility, readVisibility, joinShards).
void runFiv(const FivStageOptions& options);

} // namespace prt::fiv
