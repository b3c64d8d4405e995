// The thin runtime: relights a bundle's precomputed transfer under new distant lighting, per vertex or per texel.
// It needs no ray tracer or solver, only the bundle reader (tinygltf) and SH; an engine links prt::runtime (see
// tests/runtime/consumer for a complete find_package(prt) project). prt::runtime needs the C++ standard library and
// tinygltf alone: no OpenImageIO, TBB, Embree, Ceres or OpenCL, and its threads are std::threads. The one function
// that reads image files, loadTexelRelightModel, lives in the optional target prt::runtime_images (CMake component
// runtime_images), which adds lib/image (OpenImageIO). image.h is included for its data types only.
//
// Outgoing radiance of vertex v in channel c is radiance[v][c] = sum_j transfer[v][j][c] * lighting[j][c]
// (docs/conventions.md), with lighting as RGB SH radiance coefficients [coefficient][3].
#pragma once

#include "bundle.h"
#include "core.h" // prt::Error, thrown by the loaders
#include "image.h"
#include "sh.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace prt {

// Per-vertex transfer ready to relight: the "transfer" layer of a bundle (semantic "sh_transfer_rgb").
struct RelightModel {
    uint32_t vertexCount = 0;
    int order = 0;               // SH bands; order * order coefficients per vertex
    std::vector<float> transfer; // [vertexCount][order * order][3], the mesh's vertex order
    // Adaptive models (`prt adapt`, below): when not empty, vertex v has its own order n_v <= order and its
    // n_v^2 coefficients are rows offsets[v] .. offsets[v+1] - 1 of transfer ([offsets[vertexCount]][3]).
    std::vector<uint32_t> offsets;
    // A scene's transfer is irradiance transfer (params.albedo "excluded", docs/bundle.md "Scene bundles"): the
    // rows give what a white surface reflects, E / pi. Then albedo holds each vertex's diffuse albedo ([vertexCount]
    // [3], layer "diffuse_albedo") and relight() multiplies by it, so it returns outgoing radiance for every bundle;
    // clear it to get E / pi (an engine multiplies by its base colour per pixel instead).
    bool albedoExcluded = false;
    std::vector<float> albedo;
};

// Takes the "transfer" layer out of `bundle` (pass it with std::move to avoid copying), or, in a bundle without
// one, the adaptive layers `prt adapt` writes (adaptiveRelightModel, below). `source` names the bundle in errors.
// Needs a vertex-domain layer of semantic "sh_transfer_rgb", shape [V, L*L, 3] with L = params.order when that
// is set, V equal to the mesh's vertex count, finite values. Throws prt::Error naming `source` otherwise.
RelightModel relightModel(Bundle bundle, const std::string& source);

// Reads a bundle file and takes its transfer layer, as relightModel does.
RelightModel loadRelightModel(const std::string& bundlePath);

// ---- per-texel transfer (bundles from `prt bake`) -------------------------------------------------------------
// Per-texel transfer ready to relight: the "texel_transfer" layer of a bundle and the coefficient texture it
// references. Rows are texels, row-major with row 0 at the top of the atlas (docs/bundle.md, "Texel layers"), so
// the per-vertex kernel relights them unchanged.
struct TexelRelightModel {
    int width = 0, height = 0;
    RelightModel rows; // rows.vertexCount = width * height texels
};

// Takes the "texel_transfer" layer out of `bundle` when its rows are stored in the bundle's own buffers (layer data
// present, no params.uri). Part of the thin prt::runtime. Needs: domain "texel", semantic "sh_transfer_rgb", shape
// [W*H, L*L, 3] with params width W and height H (and params.order = L when set), W*H*L*L*3 finite values.
// Throws prt::Error naming `source` otherwise, and for a layer whose texels live in a texture (params.uri), which
// loadTexelRelightModel reads.
TexelRelightModel texelRelightModel(Bundle bundle, const std::string& source);

// prt::runtime_images only (links OpenImageIO). Reads the bundle's "texel_transfer" layer and its texture:
// params.uri, relative to the bundle file (symlinks resolved), is an OpenEXR with channels T000.R, T000.G, ...
// (params.format "half" or "float") or the JSON sidecar of 8-bit PNG layers (format "u8": value = min + q * (max -
// min) / 255 per coefficient layer); a layer with no params.uri is read from the bundle as texelRelightModel does.
// Needs what texelRelightModel needs, texture files whose xxh128 equals the recorded hash and of W x H texels,
// finite values. Throws prt::Error naming the bundle or the texture file, the place and the problem otherwise.
TexelRelightModel loadTexelRelightModel(const std::string& bundlePath);

// Channel name of coefficient j, colour c (0..2) in coefficient textures: "T000.R", "T012.B".
std::string texelCoefficientChannel(int coefficient, int colour);

// ---- lighting ------------------------------------------------------------------------------------------------
// Lighting of `coefficientCount` RGB coefficients from lighting of another count: their common prefix, with
// missing coefficients set to zero. Both counts are squares, so this is projecting both onto their common bands.
std::vector<float> fitLighting(const float* lighting, int lightingCoefficientCount, int coefficientCount);

// Reads prt-sh JSON as `prt envsh` writes it ({"format":"prt-sh","order":L,"coefficients":[[r,g,b],...]}).
// Returns [L*L][3] and sets *order to L. Throws prt::Error naming the file and the bad member.
std::vector<float> readLightingJson(const std::string& path, int* order);

// Lighting for `order` bands from an environment map: projected with exact texel solid angles, then rotated so
// the environment turns by `rotation` (row-major 3x3, d' = R d; null for none), then windowed against ringing.
std::vector<float> environmentLighting(const EnvironmentMap& env, int order, const double* rotation,
                                       sh::Window window);

// Rotates RGB lighting of `order` bands so the environment it describes turns by `rotation` (d' = R d).
std::vector<float> rotateLighting(const float* lighting, int order, const double rotation[9]);

// ---- relighting ----------------------------------------------------------------------------------------------
// The real-time kernel: radiance[v][c] = sum_j transfer[v][j][c] * lighting[j][c] for v < vertexCount.
// transfer is [vertexCount][coefficientCount][3], lighting [coefficientCount][3], radiance [vertexCount][3].
// Single-threaded and allocation-free; sums in float in a fixed order, so results do not depend on how callers
// split the vertices. To stream a range [begin, end), pass transfer + begin * coefficientCount * 3 and
// end - begin vertices.
void relight(const float* transfer, size_t vertexCount, int coefficientCount, const float* lighting,
             float* radiance);

// Relights vertices [begin, end) of `model` across the hardware's std::threads (blocks of 4096), bit-identical to
// the kernel on that range, times model.albedo per vertex when that is not empty.
// Needs lighting of model.order * model.order RGB coefficients (see fitLighting), end <= model.vertexCount and
// radiance sized (end - begin) * 3: row 0 of radiance is vertex `begin`. Throws prt::Error for a range outside
// the model.
void relight(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance);

// ---- FIV shadows of moving occluders (bundles from `prt fiv`; docs/fiv.md) ----------------------------------
// Irradiance at receiver points (position, unit normal; any mesh, deforming or not) under a distant environment
// with rigid occluders that translate: I = DifMap(N) - sum_j I_occ,j (overlap-corrected), clamped to
// 0 <= I <= DifMap(N). I_occ,j = N . FIV_j(c_j - p) from occluder j's grid (trilinear over azimuth, polar angle and
// shell, periodic in azimuth, samples inside the occluder skipped and the weights renormalised), by the seed's
// cases: A (bounding sphere wholly above the tangent plane) exact, B (straddling) corrected, C (below) ignored.
// A receiver that is its own occluder (`self`) uses I = N . FIV(Env) - N . FIV_self - sum_j I_occ,j.
// Everything here is std only and single-threaded; outgoing radiance is albedo / pi times I.

// One occluder type's grid (layers fiv, fiv_power, fiv_valid of a FIV bundle).
struct FivOccluder {
    int azimuth = 0, polar = 0, shells = 0;
    std::vector<float> shellRadii; // world units (rho_k R), ascending
    float centre[3] = {0, 0, 0};   // bounding-sphere centre in the occluder's own coordinates
    float radius = 0.0f;           // bounding-sphere radius
    std::vector<float> fiv;        // [row][channel][xyz], row (k * polar + j) * azimuth + i
    std::vector<float> power;      // [row][channel]: occluded radiance times solid angle
    std::vector<uint8_t> valid;    // [row]: 0 where the receiver would sit inside the occluder
    std::string envHash;           // the environment the grid was reduced with
};

// The unoccluded environment as the shading needs it (layers difmap and fiv_env).
struct FivLighting {
    int difmapSize = 0;
    std::vector<float> difmap; // [6 * size^2][3] irradiance by normal, cube strip order
    float fivEnv[9] = {0};     // FIV(Env) [channel][xyz]
    std::string envHash;
};

// Take the layers of object `object` out of a FIV bundle (`prt fiv`: object 0) or a FIV scene bundle (`prt
// fivscene`). Need: layer shapes that agree with the grid header in params (rows = azimuth * polar * shells,
// shell_radii of `shells` ascending positive values, radius > 0), finite values. Throw prt::Error(source, layer,
// problem) otherwise.
// They check every layer through fivLayer, and the params with typed access: a value of the wrong JSON type, or a
// centre, radius or shell radius whose float is not finite or beyond kFivMaxCoordinate, is refused (kExitInput).
FivOccluder fivOccluder(const Bundle& bundle, const std::string& source, uint32_t object = 0);
FivLighting fivLighting(const Bundle& bundle, const std::string& source, uint32_t object = 0);

// The one layer check every FIV reader runs (fivOccluder, fivLighting, fivScene, and lib/fiv's visibility and
// scene readers): layer `name` of object `object` exists, its semantic is `semantic` (unless null), its component
// type fits `storage` (Float: float16 or float32 in data; Uint8 / Uint32: that type in integers), its storage holds
// exactly as many values as its shape, floats are finite, and the shape is `shape` (empty: any one axis). Throws
// prt::Error(source, layer, problem, kExitInput) naming what is wrong, so no reader reads the other storage.
enum class FivStorage { Float, Uint8, Uint32 };
const Layer& fivLayer(const Bundle& bundle, const std::string& name, uint32_t object, const char* semantic,
                      FivStorage storage, const std::vector<uint64_t>& shape, const std::string& source);
// The largest |coordinate| (world units) FIV accepts for centres, radii, translations and receiver points: float32
// spacing there is already 64 units, and squared distances stay far inside the float range.
inline constexpr double kFivMaxCoordinate = 1e9;
// Refuses receiver points ([count][3]) that are not finite or lie beyond kFivMaxCoordinate: prt::Error(source,
// "vertex V", problem, kExitInput).
void checkFivPoints(const std::vector<float>& positions, const std::string& source);


enum class FivPartial {
    None,    // case B like case A: max(0, N . FIV)
    Literal, // the seed as printed: max(0, (d + R) / (2R) N . FIV)
    Cap,     // the occluded light as one uniform cap of the same power and mean direction, clipped by the tangent
             // plane (exact for a uniformly lit sphere; equals case A when the cap lies wholly above the plane)
};
enum class FivOverlap {
    None,   // sum of the occluders
    Paper,  // the seed's Eq. 13-14 pairwise: sum I_j - sum_pairs O_jk (I_j + I_k), O_jk = lens / (disc_j + disc_k),
            // discs of angular radius asin(R / |v|) around each direction; never below the largest single I_j
    Shared, // each occluder weighted by 1 / (1 + sum_k lens_jk / disc_j): coverage shared evenly, any count
    Cap,    // Paper's pairwise rule on the discs of the hidden light itself: the cap of the partial correction
            // (half-angle from |FIV| / power, around FIV's direction, green channel) instead of the bounding sphere
};
struct FivShadeOptions {
    FivPartial partial = FivPartial::Cap;
    FivOverlap overlap = FivOverlap::Cap; // the lowest measured error (docs/results.md)
};

// An occluder placed in the world: its vertex p sits at p + translation.
struct FivInstance {
    const FivOccluder* occluder = nullptr;
    float translation[3] = {0, 0, 0};
};

// Irradiance [count][3] at `count` points (positions and unit normals [count][3], world). `self` (or null) is the
// receiver's own grid, placed like an instance. Needs instances with occluders, lighting with its DifMap. Results
// do not depend on how callers split the points.
void fivIrradiance(const FivLighting& lighting, const FivInstance* instances, size_t instanceCount,
                   const FivInstance* self, const float* positions, const float* normals, size_t count,
                   const FivShadeOptions& options, float* irradiance);

// A FIV scene (docs/fiv.md "Scene bundles"): the receiver (object 0), the occluder types (objects with a grid)
// and their instances, ready for fivIrradiance. `instances` and `self` point into `grids`, which holds one entry
// per bundle object (empty where an object has no grid), so a FivScene may be moved but not copied.
struct FivScene {
    std::vector<FivOccluder> grids;     // [object]
    FivLighting lighting;
    std::vector<FivInstance> instances; // every placed occluder (instances of objects >= 1 with a grid)
    bool selfShadowing = false;         // object 0 carries its own grid
    FivInstance self;                   // then: object 0's grid, untranslated
    FivScene() = default;
    FivScene(FivScene&&) = default;
    FivScene& operator=(FivScene&&) = default;
    FivScene(const FivScene&) = delete;
};

// Reads a scene bundle. Needs: the lighting layers (difmap, fiv_env) on some object, every object other than 0
// that an instance places with its grid, every grid reduced under the lighting's environment, at least one
// instance or object 0's own grid. Throws prt::Error(source, place, problem) otherwise.
FivScene fivScene(const Bundle& bundle, const std::string& source);

// True when the bundle is a FIV scene: some object other than 0 carries a grid (layer fiv.k, bundle.h
// objectLayerName), or object 0 is a receiver (role) with its own grid.
bool isFivScene(const Bundle& bundle);

// Building blocks, exposed for tests and tools.
// DifMap(n), bilinear within a face, for a unit n.
void fivDifmap(const FivLighting& lighting, const float n[3], float out[3]);
// The grid's FIV and power at offset = bounding-sphere centre - receiver point (world): trilinear, weights of
// samples inside the occluder dropped and the rest renormalised; when all eight are inside, the nearest shells
// further out are used. Beyond the outermost shell the value falls off as (rho_max / rho)^2. Returns false when no
// usable sample exists along the way out.
bool fivLookup(const FivOccluder& occluder, const float offset[3], float fiv[9], float power[3]);
// Area of the lens where discs of radii r1 and r2 with centres s apart overlap (0 when apart).
double discOverlap(double r1, double r2, double s);
// Irradiance of a uniform cap of half-angle sigma (sin^2 sigma given) at angle theta (cos given) from the normal,
// clipped by the tangent plane, per unit radiance: integral over the cap of max(0, N . w) dw.
double clippedCapIrradiance(double cosTheta, double sinSigmaSquared);

// ---- adaptive transfer (bundles from `prt adapt`; docs/bundle.md "Adaptive transfer", docs/adapt.md) ---------
// The highest order this runtime evaluates; a bundle asking for more bands is refused with an error saying so.
inline constexpr int kMaxRuntimeOrder = sh::kMaxOrder;

// The adaptive transfer of a bundle as a RelightModel: the ragged layer "transfer_ragged" (float32, float16, or
// uint8/uint16 codes with per-band scales, decoded here) with its offsets, or the clustered-PCA layers
// "transfer_cpca_*" (reconstructed here to full order). Needs the layers and params docs/bundle.md lists, offsets
// ascending from 0 whose every difference is n^2 with 1 <= n <= params.order <= kMaxRuntimeOrder, codes and
// cluster indices in range, finite values. Throws prt::Error naming `source`, the layer and the problem
// otherwise (for a vertex asking for more bands than the runtime has, naming the vertex and both orders).
RelightModel adaptiveRelightModel(Bundle& bundle, const std::string& source);

// True when the bundle holds adaptive transfer layers (and so relightModel reads them).
bool hasAdaptiveTransfer(const Bundle& bundle);

// Relights vertices [begin, end) of an adaptive model (model.offsets not empty): each vertex with its own bands,
// the lighting's first n_v^2 coefficients. Runs of equal order go through the same kernel as full-order rows, so
// a model whose every vertex has the full order relights bit for bit like the full-order model. Single-threaded.
// relight(model, ...) above calls it for adaptive models.
void relightAdaptive(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance);

} // namespace prt

// ---- hybrid relighting: cone lights plus an SH residual (lib/runtime/hybrid.cpp, docs/envlight.md) ------------
// `prt envlight` splits an environment into a few cone lights (uniform radiance inside a cone) and the SH
// projection of the rest. The hybrid relights the residual through the whole transfer, each light's direct light
// in closed form with the caller's visibility (an engine's shadow maps), and each light's interreflected light
// through the bounce part of the transfer (the "transfer_bounce" layer: transfer minus its direct pass):
//   radiance = T . residual + B . sum_k proj(light_k) + sum_k (albedo / pi) radiance_k visibility_k C_k(n)
// with C_k(n) = integral over cone k of max(0, n . w) dw (coneCosineIntegral).
namespace prt {

struct HybridConeLight {
    std::array<float, 3> direction{0, 1, 0}; // unit, towards the light
    std::array<float, 3> radiance{0, 0, 0};  // RGB, >= 0
    float angularRadius = 0.0f;             // radians, in (0, pi/2)
};

struct HybridLighting {
    int order = 0;
    std::vector<float> residual; // [order^2][3] RGB SH radiance
    std::vector<HybridConeLight> lights;
    // Window on the lights' projection where it meets the bounce part (B . proj(light)): a small bright cone rings
    // at low order, and B truncated to L bands rings too, so their product can go negative at vertices that see
    // the light directly (docs/envlight.md, "Hybrid relight"). Hann removed 86% of such vertices on sunrise at no
    // measurable error.
    sh::Window bounceWindow = sh::Window::Hann;
};

// Reads prt-lights JSON as `prt envlight` writes it. Throws prt::Error naming the file and the member for a wrong
// format, an order outside 1..sh::kMaxOrder, a residual of the wrong size, and any light value that is not
// finite, a direction that is not unit length (to 1e-3), negative radiance or a radius outside (0, pi/2).
HybridLighting readHybridLightingJson(const std::string& path);

// The lighting turned by `rotation` (row-major 3x3, d' = R d): directions rotated, residual rotated in SH.
HybridLighting rotateHybridLighting(const HybridLighting& lighting, const double rotation[9]);

// Integral over the cone of half-angle `angularRadius` about a direction at cosine `cosAngle` from the normal
// of max(0, n . w) dw: pi sin^2(r) cosAngle when the cone is above the horizon, 0 below it, and the exact
// horizon-clipped spherical-cap form in between (Snyder 1996, as in Frostbite's sphere lights).
double coneCosineIntegral(double cosAngle, double angularRadius);

// Exact SH projection of the cone lights onto `order` bands, [order^2][3] (sh::capProjection times radiance).
std::vector<float> coneLightsProjection(const std::vector<HybridConeLight>& lights, int order);

// What the hybrid needs per row (vertex or texel): the full transfer, its bounce part (empty: no bounces, the
// lights then light only directly), the shading normal and the diffuse albedo.
struct HybridModel {
    RelightModel total;          // "transfer" (or "texel_transfer" rows)
    std::vector<float> bounce;   // [rows][order^2][3], or empty
    std::vector<float> normals;  // [rows][3], unit
    std::vector<float> albedo;   // [rows][3]
};

// From a bundle of `prt transfer` (the "transfer" layer, its optional "transfer_bounce" layer of the same shape,
// the mesh's normals, and the albedo in the transfer's params.albedo or, for "per-vertex", the mesh's).
// Throws prt::Error naming `source` for a missing or malformed layer, missing normals or albedo.
HybridModel hybridModel(Bundle bundle, const std::string& source);
HybridModel loadHybridModel(const std::string& bundlePath);

// ---- the texel hybrid (bundles from `prt bake`) ------------------------------------------------------------------
// Channels of a bake's "texel_surface" layer (docs/bundle.md): per texel in object space, the receiver's position
// and unit normal (the high mesh's with --high), its diffuse albedo, and coverage (1 for covered texels, 0 in
// gutters, whose other channels push-pull fills from the covered ones; normals renormalised).
inline constexpr int kTexelSurfaceChannels = 10;
inline constexpr const char* kTexelSurfaceChannelNames[kTexelSurfaceChannels] = {
    "P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z", "albedo.R", "albedo.G", "albedo.B", "coverage"};

// The hybrid's rows for every texel of a bake, and where each texel lies, so that a caller can sample each cone
// light's visibility there (or look it up in its shadow maps).
struct TexelHybridModel {
    int width = 0, height = 0;
    HybridModel rows;             // rows = texels, row-major from the top: total, bounce, normals, albedo
    std::vector<float> positions; // [texels][3], object space
    std::vector<uint8_t> covered; // [texels]: 1 where the bake sampled the surface, 0 in gutters
};

// prt::runtime_images only. Reads a bake bundle's "texel_transfer", its "texel_transfer_bounce" (present when the
// bake had bounces; without it the rows' bounce stays empty and cone lights light only directly) and
// "texel_surface", from their textures or inline (format "bundle").
// Throws prt::Error naming the bundle or texture, the place and the problem: a missing or malformed layer (bakes
// written before the texel hybrid lack "texel_surface" and must be baked again), sizes that disagree, texture hashes
// that differ from the recorded ones, non-finite values.
TexelHybridModel loadTexelHybridModel(const std::string& bundlePath);
// The same on a bundle already read from bundlePath (texture uris resolve against it).
TexelHybridModel texelHybridModel(Bundle bundle, const std::string& bundlePath);

// Throws prt::Error(lightsSource, "order", ...) unless the lighting's order equals the model's.
void checkHybridOrder(const HybridModel& model, const HybridLighting& lighting, const std::string& lightsSource);

// Relights rows [begin, end) of `model` into radiance ([end - begin][3]). visibility is [rows][lights] (row-major,
// the model's rows, not offset by begin): for row v and light k, the cosine-weighted visible fraction of cone k,
// in [0, 1] (1 = unshadowed; a shadow map's filtered lookup at the light's direction is a fine stand-in).
// Needs the same order in model and lighting (checkHybridOrder). Sums in a fixed order: results do not depend on
// how callers split the rows.
void relightHybrid(const HybridModel& model, const HybridLighting& lighting, const float* visibility, size_t begin,
                   size_t end, float* radiance);
// The same with visibility from a callback, called once per (row, light) in row order.
using ConeVisibility = std::function<float(size_t row, size_t light)>;
void relightHybrid(const HybridModel& model, const HybridLighting& lighting, const ConeVisibility& visibility,
                   size_t begin, size_t end, float* radiance);

} // namespace prt

// ---- glossy lobes (bundles from `prt glossy`) -----------------------------------------------------------------
namespace prt {

// Per-vertex spherical-Gaussian lobes for each view of a global view set (docs/bundle.md, "Glossy lobes"):
// the "glossy_lobes" layer, semantic "sg_lobes", shape [V, views, N, 5] of (a, mu xyz, lambda), with the view
// directions and their triangles in params.
struct GlossyModel {
    uint32_t vertexCount = 0;
    int lobes = 0;
    std::vector<float> views;          // [viewCount][3], unit
    std::vector<uint32_t> triangles;   // [triangleCount][3], counter-clockwise from outside
    std::vector<float> values;         // [V][viewCount][N][5]
    std::vector<float> positions;      // [V][3], the mesh's, for the direction toward the eye
    std::vector<float> normals;        // [V][3]
    size_t viewCount() const { return views.size() / 3; }
};

// Reads the lobes of `bundle`. Needs a vertex-domain "glossy_lobes" layer of semantic "sg_lobes" whose second
// axis equals the number of params.views, params.view_triangles indexing those views, N in 1..4, five values
// per lobe, V the mesh's vertex count, finite values; and mesh normals. Throws prt::Error naming `source`.
GlossyModel glossyModel(const Bundle& bundle, const std::string& source);

// The view triangle containing unit direction d and its barycentric weights (>= 0, summing to 1), by central
// projection onto the triangle's plane.
void viewWeights(const GlossyModel& model, const float d[3], uint32_t views[3], float weights[3]);

// Lobe k of vertex v toward unit direction d: the 3 enclosing views' lobes blended with the barycentric weights,
// amplitude linearly, mean linearly then normalised, sharpness linearly in log. Writes (a, mu xyz, lambda).
void interpolateLobe(const GlossyModel& model, uint32_t vertex, int lobe, const uint32_t views[3],
                     const float weights[3], float out[5]);

// An equirectangular environment (docs/conventions.md) as a chain of 2x2 box-filtered levels, each texel with
// its solid angle, so a lobe of any width integrates over a level whose texels are narrower than the lobe.
struct PrefilteredEnvironment {
    struct Level {
        int width = 0, height = 0;
        std::vector<float> rgb;        // [height][width][3] radiance
        std::vector<float> solidAngle; // [height], per texel of the row
    };
    std::vector<Level> levels; // finest first
};
// Needs width = 2 height, both >= 2 (a 2:1 map), rgb [height][width][3] finite. Throws prt::Error otherwise.
PrefilteredEnvironment prefilterEnvironment(const float* rgb, int width, int height);

// Integral of a exp(lambda (mu . w - 1)) L(w) over the sphere, per channel, for unit mu: summed over the texels
// within 5.5 / sqrt(lambda) rad of mu (all of them for wide lobes) of the coarsest level whose texel spacing is
// at most a quarter of the lobe's width 1 / sqrt(lambda).
void integrateLobe(const PrefilteredEnvironment& env, const float lobe[5], float radiance[3]);

// The lobes of vertex `vertex` at view `view`, each mean turned by the rotation that takes the view's mirror
// direction about the vertex normal to unit `mirror` (amplitude and sharpness kept): out [lobes][5].
void turnViewLobes(const GlossyModel& model, uint32_t vertex, uint32_t view, const float mirror[3], float* out);

// Glossy radiance of every vertex toward the point `eye`: for each of the 3 views around the eye direction, that
// view's lobes turned onto the eye's mirror direction (turnViewLobes) and integrated against the environment, the
// three radiances blended with the barycentric weights (docs/glossy.md, "Runtime": lobes are never paired across
// views); zero where the eye is below a vertex's tangent plane. radiance [V][3].
void glossyRadiance(const GlossyModel& model, const PrefilteredEnvironment& env, const float eye[3],
                    float* radiance);

} // namespace prt
