// prt/fiv.h: shadows of moving rigid occluders from FIV grids (bundles from `prt fiv` and `prt fivscene`;
// docs/fiv.md). std only and single-threaded. The loaders throw prt::Error (a std::runtime_error).
#pragma once

#include "bundle.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {

// Irradiance at receiver points (position, unit normal; any mesh, deforming or not) under a distant environment
// with rigid occluders that translate: I = DifMap(N) - sum_j I_occ,j (overlap-corrected), clamped to
// 0 <= I <= DifMap(N). I_occ,j = N . FIV_j(c_j - p) from occluder j's grid (trilinear over azimuth, polar angle and
// shell, periodic in azimuth, samples inside the occluder skipped and the weights renormalised), by the seed's
// cases: A (bounding sphere wholly above the tangent plane) exact, B (straddling) corrected, C (below) ignored.
// A receiver that is its own occluder (`self`) uses I = N . FIV(Env) - N . FIV_self - sum_j I_occ,j, or, when the
// self instance carries per-point self-shadowed irradiance E_self (layer fiv_self), I = E_self - sum_j I_occ,j.
// Everything here is std only and single-threaded; outgoing radiance is albedo / pi times I.

// The sources' own grid (optional layers fiv_source_grid, fiv_source_valid of `prt fiv --sources --source-grid`;
// docs/fiv.md decision 13): per sample the hidden fraction f of the map's small sources (a sun), on a grid of its
// own with the occluder's centre and radius. When an occluder has one, its main grid holds the rest of the map and
// the sources' hidden irradiance is g max(0, N . fiv[channel]), g = clamp(0.5 + sharpen (f - 0.5), 0, 1).
struct FivSourceGrid {
    int azimuth = 0, polar = 0, shells = 0; // 0: none
    std::vector<float> shellRadii;          // world units, ascending
    std::vector<float> fraction;            // [row] in [0, 1], row (k * polar + j) * azimuth + i
    std::vector<uint8_t> valid;             // [row]
    float sharpen = 2.0f;                   // K, 1..100
    float power[3] = {0, 0, 0};             // the sources' power [channel]
    float fiv[9] = {0};                     // FIV_sources [channel][xyz]
};

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
    // Optional layer fiv_self (`prt fiv --self-vertices`, object 0 only): [vertex][3] the irradiance each vertex of
    // the bundle's own mesh receives with the mesh itself as the only occluder; empty when the bundle has none.
    std::vector<float> selfIrradiance;
    // Optional: the sources' own grid (sources.azimuth 0 when the bundle has none; then fiv holds the whole map).
    FivSourceGrid sources;
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
// fivOccluder reads the optional source grid of object `object` the same way: both layers or neither, its own
// dimensions and ascending shells, a centre and radius equal to the main grid's, f in [0, 1], valid 0 or 1,
// sharpen in 1..100, source_power [3] finite and >= 0, source_fiv [3][3] finite with |fiv[c]| <= power[c] (1e-3).
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
    // For the `self` instance only, or null: [count][3] the points' own self-shadowed irradiance (the occluder's
    // selfIrradiance for the points passed), used instead of N . FIV(Env) - N . FIV_self. Set it only when the
    // receiver points are the vertices of the mesh the layer was computed for, unmoved relative to each other.
    const float* selfIrradiance = nullptr;
};

// The sources' term (occluders with a source grid): per instance in cases A and B (case C hides nothing; the
// source term needs no partial correction: its rays decide, whatever the tangent plane), g_j from fivSourceLookup
// (1 when the point is inside the occluder), combined over instances as 1 - prod_j (1 - g_j) (overlap None: the
// sum, clamped to 1), times max(0, N . FIV_sources), the largest over the instances' types. A `self` grid with a
// source grid, when no selfIrradiance is given, adds its sources back signed: unoccluded = N . FIV(Env) -
// N . FIV_self - g_self N . FIV_sources (the grid path of --sources, on the finer grid).
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
    FivInstance self;                   // then: object 0's grid, untranslated (with its fiv_self when it has one)
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
// The source grid's hidden fraction f at `offset` (as fivLookup: trilinear with r_k^2 weights between shells and
// 1 / rho^2 after, invalid samples dropped and the rest renormalised, stepping outwards when all are inside),
// clamped to [0, 1]. Returns false when the grid has no usable sample along the way out (or none at all).
bool fivSourceLookup(const FivSourceGrid& grid, const float offset[3], float* fraction);
// Area of the lens where discs of radii r1 and r2 with centres s apart overlap (0 when apart).
double discOverlap(double r1, double r2, double s);
// Irradiance of a uniform cap of half-angle sigma (sin^2 sigma given) at angle theta (cos given) from the normal,
// clipped by the tangent plane, per unit radiance: integral over the cap of max(0, N . w) dw.
double clippedCapIrradiance(double cosTheta, double sinSigmaSquared);


} // namespace prt
