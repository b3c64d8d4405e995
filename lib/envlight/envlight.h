// Environment lighting as a few cone lights plus a low-order SH residual (thesis chapter 4, with its errata fixed;
// docs/envlight.md records every choice and measurement).
//
// The chain, one source file per step:
//   texels.cpp     the map as (direction, solid angle, RGB radiance) samples, optionally rotated
//   icosphere.cpp  a subdivided icosahedron (the thesis's spherical quadtree) with vertex neighbours
//   smoothing.cpp  spherical-Gaussian pre-smoothing of the luminance, sampled at the icosphere vertices
//   maxima.cpp     hill-climbing local maxima and their quadric (tangent-plane) refinement
//   elbow.cpp      the Weber-law elbow threshold on the sorted candidates
//   fit.cpp        bounded Ceres refinement of each light's direction, radiance and angular radius
//   decompose.cpp  the whole chain, and the residual SH: the projection of what the lights do not explain
//   coherence.cpp  the chain frame after frame: hysteresis on K and the elbow, lights matched into stable slots,
//                  entering and leaving lights cross-faded through the residual
//   choose.cpp     K per map from the decomposition's own (band-weighted) error, or plain SH when lights do not pay
//   document.cpp   the prt-lights JSON document
//   render.cpp     the decomposed lighting back as an equirectangular map (for `prt reference --lights`)
//   residual_map.cpp  the map minus the cone lights, as a map (the smooth part the glossy lobes integrate)
//   visibility.cpp each light's soft (cone-sampled) visibility at surface points, by Embree rays (lib/raycast):
//                  what `prt relight --lights` uses in place of an engine's shadow maps
//
// Conventions (docs/conventions.md): world right-handed Y-up; a light's direction points from the scene TOWARDS
// the light; radiance is RGB W/(sr m^2) (the map's units), uniform inside the cone of half-angle angularRadius
// (radians) about the direction, so its solid angle is 2 pi (1 - cos r) and its power per unit area at normal
// incidence is radiance * solid angle. Luminance is Rec.709 (0.2126, 0.7152, 0.0722).
#pragma once

#include "bundle.h"
#include "image.h"
#include "luminance.h"
#include "sh.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {
struct Surface; // lib/material: a scene's materials, for cut-outs in the cone visibility
}

namespace prt::envlight {

using prt::kLuminance; // lib/core/luminance.h

struct ConeLight {
    std::array<double, 3> direction{0, 1, 0}; // unit, towards the light
    std::array<double, 3> radiance{0, 0, 0};  // RGB, >= 0
    double angularRadius = 0.0;              // radians, > 0
};
double coneSolidAngle(double angularRadius);

// ---- texels ---------------------------------------------------------------------------------------------------
// The environment as samples: texel i has the unit direction directions[3i..], exact solid angle solidAngles[i]
// and radiance rgb[3i..], in the map's row-major order. With `rotation` (row-major 3x3, d' = R d, as
// sh::rotation takes it) every direction is turned, which turns the environment exactly (no resampling).
struct Texels {
    std::vector<double> directions;
    std::vector<double> solidAngles;
    std::vector<float> rgb;
    size_t count() const { return solidAngles.size(); }
};
Texels environmentTexels(const EnvironmentMap& env, const double* rotation = nullptr);
// SH projection of the texels onto `order` bands, [order^2][3], accumulated in double in texel order.
std::vector<double> projectTexels(const Texels& texels, int order);

// ---- icosphere ------------------------------------------------------------------------------------------------
// Level k: 10 * 4^k + 2 unit vertices, 20 * 4^k triangles; the 12 original vertices have 5 neighbours, all others
// 6. neighbours of vertex v are neighbours[neighbourOffsets[v] .. neighbourOffsets[v + 1]).
struct Icosphere {
    std::vector<double> vertices; // [V][3]
    std::vector<uint32_t> triangles;
    std::vector<uint32_t> neighbourOffsets, neighbours;
    size_t vertexCount() const { return vertices.size() / 3; }
};
// Needs 0 <= level <= 8.
Icosphere icosphere(int level);

// ---- smoothing ------------------------------------------------------------------------------------------------
// Luminance of the texels convolved with the normalised spherical Gaussian exp(kappa (w . x - 1)) whose full width
// at half maximum is `fwhm` radians, truncated where the kernel falls below 1e-3 of its peak, at each of `count`
// unit directions. A constant map stays that constant. Needs fwhm in (0, 0.5].
std::vector<double> smoothLuminance(const Texels& texels, const double* directions, size_t count, double fwhm);
// The same kernel's Funk-Hecke factors g_0 .. g_{order-1} (g_0 = 1): smoothing multiplies band l by g_l.
std::vector<double> gaussianBandFactors(double fwhm, int order);

// ---- maxima ---------------------------------------------------------------------------------------------------
// Hill climbing: from every vertex, step to the largest larger neighbour until none is larger (ties broken by the
// lower index). Returns the local maxima reached, ascending; basin[v] (when not null, sized V) is the maximum
// vertex v climbs to, so every vertex belongs to exactly one basin.
std::vector<uint32_t> localMaxima(const Icosphere& sphere, const std::vector<double>& values,
                                  std::vector<uint32_t>* basin = nullptr);
// Sub-vertex position of the maximum at `vertex`: a least-squares quadric a u^2 + b uv + c v^2 + d u + e v + f
// over the vertex and its two-ring in the tangent plane, and the quadric's stationary point. Keeps the vertex when
// the quadric is not concave or the point leaves the one-ring. Returns a unit direction.
std::array<double, 3> refineMaximum(const Icosphere& sphere, const std::vector<double>& values, uint32_t vertex);

// ---- elbow ----------------------------------------------------------------------------------------------------
// The thesis's FIND-ELBOW-POINT, fixed: `values` sorted non-increasing and >= 0; keeps candidate k while its share
// of the running total values[0] + ... + values[k] exceeds `threshold`. Returns how many lead candidates to keep:
// 0 for an empty list, 1 for one candidate, never more than `count`, never reads past the end.
size_t elbowCount(const double* values, size_t count, double threshold);

// ---- the fit --------------------------------------------------------------------------------------------------
// What one light is fitted against: the texels near it, with the radiance that everything else (the residual SH
// and the other lights) puts there.
struct FitTexels {
    std::vector<double> directions;  // [n][3] unit
    std::vector<double> solidAngles; // [n]
    std::vector<double> target;      // [n][3]: E minus the background, per channel
};
struct LightFit {
    ConeLight light;
    double initialCost = 0.0, finalCost = 0.0;
    int iterations = 0;
    std::string termination;
};
// Bounded Ceres (Levenberg-Marquardt, one thread): minimises sum_i solidAngle_i |target_i - radiance cover_i|^2
// over the direction (on the sphere), radiance (>= 0 per channel) and angular radius (in [minRadius, maxRadius]),
// where cover_i = erfc((chord_i - 2 sin(r / 2)) / (sqrt 2 edge)) / 2 is the cone's soft-edged coverage of texel i
// (chord_i = |direction - w_i|, edge ~ a third of a texel). The returned radiance is rescaled so that radiance *
// coneSolidAngle(r) equals the fitted soft cone's energy sum_i radiance cover_i solidAngle_i: the light keeps the
// energy the fit gave it. Needs `initial` inside the bounds, edge > 0.
LightFit fitLight(const FitTexels& texels, const ConeLight& initial, double minRadius, double maxRadius, double edge);

// ---- the decomposition ----------------------------------------------------------------------------------------
struct Options {
    int order = 5;                      // residual SH bands
    int maxLights = 4;                  // K, >= 0
    int minLights = 0;                  // fail unless at least this many lights are found
    int icosphereLevel = 6;             // 40962 vertices, ~1.0 degree apart
    double smoothingFwhm = 0.0349;      // 2 degrees, for detection only; the fit uses the raw texels
    sh::Window detectionWindow = sh::Window::Hann; // window of the detection SH P in the ranking E - P
    double elbowThreshold = 0.05;       // Weber fraction
    double minContrast = 1.0;           // a candidate's smoothed residual E - P must reach this times mean luminance
    double minRadius = 0.00175;         // 0.1 degree
    double maxRadius = 0.349;           // 20 degrees
    int outerIterations = 3;            // alternations of the light fit and the residual projection
    bool refine = true;                 // false: the thesis's lights (fixed radius, peak residual), no Ceres
    double fixedRadius = 0.0524;        // 3 degrees, the thesis's common radius when refine is false
    const double* rotation = nullptr;   // turn the environment first (d' = R d, row-major 3x3)
};

// A detected peak, before the fit.
struct Candidate {
    std::array<double, 3> direction{};  // refined by the quadric
    double smoothedResidual = 0.0;      // luminance of (smoothed E) - P at the direction
    double power = 0.0;                 // estimated luminance power (residual radiance * solid angle), for ranking
    double initialRadius = 0.0;
    std::array<double, 3> initialRadiance{};
};

struct FitReport {
    int ceresIterations = 0;
    double initialCost = 0.0, finalCost = 0.0; // summed over lights and outer iterations' last pass
    std::string termination;                  // Ceres's, of the last solve
    int droppedLights = 0;                    // lights the fit drove to zero power
};

struct Decomposition {
    int order = 0;
    std::vector<ConeLight> lights;       // sorted by non-increasing luminance power
    std::vector<double> residual;        // [order^2][3]: projection of E minus the lights' exact projections
    std::vector<Candidate> candidates;   // every significant candidate, ranked
    size_t elbow = 0;                    // candidates the elbow kept (before maxLights)
    double meanLuminance = 0.0;          // of the map
    double environmentPower = 0.0;       // luminance integral of E over the sphere
    FitReport fit;
    // Set by decomposeCoherent only: each light's fade weight in (0, 1] (its radiance is already scaled by it),
    // and the map's projection [order^2][3], which residual + lightsProjection(lights) equals to rounding.
    std::vector<double> weights;
    std::vector<double> projection;
};

// Splits the environment into cone lights and an SH residual.
// Needs a map whose size matches its layout with finite radiance >= 0 (readEnvironmentMap guarantees it) and
// options in range. Throws prt::Error: kExitInput (file "", place "radiance") when the map is zero everywhere,
// kExitUsage for bad options (maxLights 0 with minLights > 0 among them), kExitInput when fewer than minLights
// lights are found. Guarantees: every light finite, radiance >= 0, radius within [minRadius, maxRadius];
// residual energy plus lights' energy equals the map's (sqrt(4 pi) residual_00 + sum radiance * solid angle =
// integral of E, per channel, to rounding); deterministic (same input, same bits; single-threaded Ceres).
Decomposition decompose(const EnvironmentMap& env, const Options& options);

// ---- temporal coherence --------------------------------------------------------------------------------------
// The previous frame's lights, in slots: a flat state the caller keeps between frames (start from {}).
struct CoherenceState {
    std::vector<ConeLight> lights; // at full radiance, in slot order
    std::vector<double> weights;   // fade weight per slot, in (0, 1]
    bool started = false;          // false before the first frame: lights then enter at full weight
    std::vector<std::array<double, 3>> pending; // enter-set lights of the last frame that took no slot
};
struct CoherenceOptions {
    double keepFraction = 0.5;     // a held light stays while it passes the elbow at threshold * keepFraction
    int spareLights = 2;           // ... and ranks within K + spareLights; a new light enters within K, threshold
    int fadeFrames = 8;            // an entering or leaving light crosses over in this many frames
    double matchRadius = 0.1745;   // 10 degrees: a slot follows this frame's nearest light within this angle
};
// decompose() frame after frame, coherent with `state` (updated in place). Each frame decomposes with K +
// spareLights lights at the lower (keeping) threshold; slots are matched to those lights by direction, closest
// pairs first; a matched slot follows its light and its weight rises by 1/fadeFrames to 1, an unmatched slot
// keeps its last light and its weight falls by 1/fadeFrames, and is freed at 0 (the other slots keep their order);
// a light of the enter set (the lead lights the strict elbow and K keep) that no slot holds takes a free slot
// when it was in the enter set the frame before too (within matchRadius of a pending direction), at weight
// 1/fadeFrames (1 on the first frame), so a one-frame candidate never blips in. Returns the lights in slot order (not sorted by power), each at
// its weight (Decomposition::weights), never more than options.maxLights, and the residual = the map's projection
// minus exactly these lights, so light + residual is the map's projection at every frame (energy conserved, to
// rounding), and a fading light's remainder is carried by the residual. Same needs and throws as decompose(), and
// kExitUsage for options out of range or a state that does not fit K. Deterministic.
Decomposition decomposeCoherent(const EnvironmentMap& env, const Options& options, const CoherenceOptions& coherence,
                                CoherenceState& state);

// ---- choosing K -----------------------------------------------------------------------------------------------
struct ChoiceOptions {
    int plainOrder = 8;            // the plain SH the hybrid has to beat
    int errorOrder = 32;           // the error is measured band by band below this order
    double bandWidth = 5.0;        // band l weighs exp(-(l / bandWidth)^2): the transfer's falling spectrum
    double margin = 0.95;          // lights pay when the hybrid's error is below margin * plain SH's
    std::vector<int> residualOrders; // the hybrid's residual orders to try; empty: options.order and plainOrder
};
struct LightChoice {
    int lights = 0;                // K chosen (0 with plainSh)
    int order = 0;                 // the residual order chosen (plainOrder with plainSh)
    bool plainSh = false;          // lights do not pay: relight with plain SH at plainOrder instead
    std::vector<double> errors;    // at the best hybrid's residual order: the error with the first k lights, k = 0 ..
                                   // lights found
    double plainError = 0.0;       // plain SH's error at plainOrder
    std::vector<std::vector<double>> bands; // per k, at that order: the hybrid's unweighted error energy per band
    std::vector<double> plainBands;         // plain SH's
    std::vector<int> orders;                // the residual orders tried, ascending
    std::vector<std::vector<double>> errorsByOrder; // per order tried: the error with the first k lights
    std::string reason;            // one line for the log and the document
};
// The residual orders decomposeChoosingLights tries: choice.residualOrders, or {options.order, choice.plainOrder}
// when empty; sorted, without repeats.
std::vector<int> residualOrdersTried(const Options& options, const ChoiceOptions& choice);
// K and the residual order per map, from the decomposition's own error. For each residual order L tried, decomposes
// at L with up to options.maxLights lights (the elbow's count); for each prefix of k lights (by power), the lighting
// error e = E - lights - residual is measured by its SH band energies |e_l|^2 (exact: the map's projection minus the
// cones' cap projections, bands from L up, below errorOrder) as sqrt(sum_l exp(-(l / bandWidth)^2) |e_l|^2 / |E|^2),
// and plain SH's the same way over bands from plainOrder; bands from errorOrder up are left out (weight below
// exp(-16) at the defaults). Picks the (L, k >= 1) of least error (ties: the lower L, the fewer k); when no light
// is found, or the least error is not below margin * plain's, lights do not pay: 0 lights, plainSh, and the
// residual is plain SH at plainOrder. Returns the decomposition with the chosen K at the chosen L (refitted when K
// differs from the count found) and the choice in *report. The caller writes the document at report->order. Needs
// what decompose() needs, and every order tried and plainOrder in 1 .. errorOrder - 1, errorOrder <= sh::kMaxOrder.
Decomposition decomposeChoosingLights(const EnvironmentMap& env, const Options& options, const ChoiceOptions& choice,
                                      LightChoice* report);

// The exact SH projection of uniform cone lights onto `order` bands (sh::capProjection), [order^2][3].
std::vector<double> lightsProjection(const std::vector<ConeLight>& lights, int order);

// The prt-lights JSON document (docs/envlight.md): lights, residual SH, conventions, options and the input's
// path and hash.
nlohmann::ordered_json lightsDocument(const Decomposition& decomposition, const Options& options,
                                      const std::string& inputPath, const std::string& inputHash);

// Checks that the prt-lights file `lightsPath` was made from the map `envPath`: its input.hash (a string) equals
// the map's content hash. Reads the file under the same size and nesting bounds as readHybridLightingJson. Throws
// Error(lightsPath, "input.hash", ...) naming both files and both hashes, or saying that no hash is recorded.
void checkLightsInput(const std::string& lightsPath, const std::string& envPath);

// ---- rendering the decomposition ------------------------------------------------------------------------------
// The lighting residual SH + cones as a width x width/2 equirectangular map: each texel the residual at its centre
// plus each cone's exact coverage of the texel, estimated with `supersample`^2 stratified points. The SH residual
// can dip below zero where the map had less light than the lights' cones; those texels stay negative (light
// transport is linear, and prt reference samples by |radiance| and keeps the sign), and *negativeEnergy (when not
// null) receives their luminance energy over the map's total |luminance| energy. Needs width even and >= 4,
// residual sized order^2 * 3.
EnvironmentMap renderLighting(const std::vector<ConeLight>& lights, const std::vector<double>& residual, int order,
                              int width, int supersample, double* negativeEnergy = nullptr);

// ---- the residual as a map (the glossy path, docs/glossy.md "Lights through the glossy path") -----------------
// What the glossy lobes integrate when the cone lights are shaded exactly: the map minus each cone's coverage of
// every texel times its radiance (the cones exactly as renderLighting renders them, `supersample`^2 stratified
// points per texel near a rim), per channel. Where a cone claims more than the texel holds the difference is
// negative: kept (clampNegative false: the map is exactly residual + cones) or set to 0 (true: no negative
// radiance, but residual + cones then exceed the map by the clamped part). Equirectangular maps only.
struct ResidualMapStats {
    double negativeEnergy = 0.0; // luminance energy of the negative texels over the map's luminance energy
    double lightsEnergy = 0.0;   // the cones' share of the map's luminance energy
};
// Needs a 2:1 equirectangular `env`, supersample >= 1. Throws Error(kExitInput) for another layout.
EnvironmentMap subtractConeLights(const EnvironmentMap& env, const std::vector<ConeLight>& lights, int supersample,
                                  bool clampNegative, ResidualMapStats* stats = nullptr);

// ---- visibility -----------------------------------------------------------------------------------------------
// For each point p_i with unit normal n_i and each light k: the cosine-weighted visible fraction of cone k,
//   sum_s V(p_i, w_s) max(0, n_i . w_s) / sum_s max(0, n_i . w_s)
// over `samples` directions w_s spread over the cone (a Hammersley set on the cap, uniform in solid angle, the same
// for every point), each an occlusion ray against `mesh` by lib/raycast's spawn rule: from p + offset s_i, with s_i
// the point's spawn normal (`spawnNormals` [count][3], or null: the normals; mesh vertices pass
// prt::spawnNormals(mesh)), tnear 0. 0 where the whole cone is below the horizon. Returns [points][lights].
// Deterministic for any thread count. Needs finite points and unit normals, samples >= 1, a mesh Embree accepts.
// *rays counts the rays cast. With a scene's `surface` (lib/material, its mesh `mesh`), rays pass through its
// cut-outs as the transfer's do (EmbreeScene's filter); null: every triangle occludes.
std::vector<float> coneVisibility(const TriMesh& mesh, const float* points, const float* normals,
                                  const float* spawnNormals, size_t count, const std::vector<ConeLight>& lights,
                                  int samples, uint64_t* rays = nullptr, const Surface* surface = nullptr);

// The sample directions coneVisibility casts toward `light`: `samples` unit vectors [samples][3], a Hammersley set
// on the cap uniform in solid angle (sample s at cos theta = 1 - (s + 0.5) / samples (1 - cos r), azimuth the
// base-2 radical inverse of s). The same for every point, so a runtime can shade with them.
std::vector<float> coneSampleDirections(const ConeLight& light, int samples);

// Per point, light and sample: 1 where the sample direction w_s (coneSampleDirections) is unoccluded from p_i and
// above its horizon (n_i . w_s > 0), else 0, by the same rays from the same origins as coneVisibility (which is
// the cosine-weighted mean of these). What the glossy path needs: the Phong lobe weights the samples unequally, so
// one visible fraction per light is not enough. Returns [points][lights][samples]. Same needs and guarantees as
// coneVisibility.
std::vector<uint8_t> coneSampleVisibility(const TriMesh& mesh, const float* points, const float* normals,
                                          const float* spawnNormals, size_t count, const std::vector<ConeLight>& lights,
                                          int samples, uint64_t* rays = nullptr);

// coneVisibility's cosine-weighted visible fraction from coneSampleVisibility's bits (`visible` [count][lights]
// [samples]) and the same directions (`directions` [lights][samples][3], coneSampleDirections), summed in the same
// order, so equal to coneVisibility bit for bit without casting its rays again. Returns [count][lights].
std::vector<float> coneVisibilityFromSamples(const float* normals, size_t count, size_t lights, int samples,
                                             const float* directions, const uint8_t* visible);

// ---- visibility turns ------------------------------------------------------------------------------------------
// The cone visibility of `lights` turned about +Y, for `turns` turns evenly over 360 degrees (turn t at t * 360 /
// turns degrees), quantised to bytes: table[(t * count + i) * lights + k] = quantizeVisibility(V_tik), where V_tik
// is coneVisibility (same points, normals, spawn normals, samples) for the lights turned by turnConeLightsY(lights,
// t * 360 / turns), exactly what `prt relight --lights --rotate-y DEG --visibility-out` casts at that angle. samples 0:
// unshadowed (all 255). Grows as turns x count x lights bytes; refuses (Error, kExitUsage) turns outside
// 1..kMaxVisibilityTurns and a table above kMaxVisibilityTableBytes, before allocating. *rays counts the rays.
// `surface` as coneVisibility's.
constexpr int kMaxVisibilityTurns = 720;
constexpr uint64_t kMaxVisibilityTableBytes = uint64_t(1) << 30;
std::vector<uint8_t> coneVisibilityTurns(const TriMesh& mesh, const float* points, const float* normals,
                                         const float* spawnNormals, size_t count, const std::vector<ConeLight>& lights,
                                         int samples, int turns, uint64_t* rays = nullptr,
                                         const Surface* surface = nullptr);
// `lights` turned by `degrees` about +Y (sh::rotationY) as rotateHybridLighting turns a prt-lights JSON's cones:
// each direction's float components rotated in double and rounded to float. 0 degrees: unchanged.
std::vector<ConeLight> turnConeLightsY(const std::vector<ConeLight>& lights, double degrees);
// round(255 v) for v clamped to [0, 1]: a visibility as a byte (the viewer reads it back as byte / 255).
uint8_t quantizeVisibility(float visibility);

} // namespace prt::envlight
