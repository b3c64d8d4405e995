// prt/glossy.h: glossy spherical-Gaussian lobes (bundles from `prt glossy`; docs/glossy.md "Runtime").
#pragma once

#include "hybrid.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "jobs.h"

namespace prt {

struct Bundle; // bundle.h


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
    // The view triangles around each view, ascending (indexViewTriangles; glossyModel fills them): viewWeights
    // then tests the few around the nearest view instead of all. Empty: viewWeights scans every triangle.
    std::vector<uint32_t> viewTriangleOffsets; // [viewCount + 1]
    std::vector<uint32_t> viewTriangles;       // [3 triangleCount]
    double exponent = 0.0, ks = 0.0;   // the fitted Phong lobe (params.brdf); 0, 0 when the layer records none
    size_t viewCount() const { return views.size() / 3; }
};

// Fills model.viewTriangleOffsets and viewTriangles from model.views and model.triangles (indices < viewCount).
void indexViewTriangles(GlossyModel& model);

// Reads the lobes of `bundle`. Needs a vertex-domain "glossy_lobes" layer of semantic "sg_lobes" whose second
// axis equals the number of params.views, params.view_triangles indexing those views, N in 1..4, five values
// per lobe, V the mesh's vertex count, finite values; and mesh normals. Throws prt::Error naming `source`.
GlossyModel glossyModel(const Bundle& bundle, const std::string& source);

// The view triangle containing unit direction d and its barycentric weights (>= 0, summing to 1), by central
// projection onto the triangle's plane: among the triangles around the nearest view when the model is indexed
// (indexViewTriangles), else (or when rounding hides it there) the first of all that holds d.
void viewWeights(const GlossyModel& model, const float d[3], uint32_t views[3], float weights[3]);

// Lobe k of vertex v toward unit direction d: the 3 enclosing views' lobes blended with the barycentric weights,
// amplitude linearly, mean linearly then normalised, sharpness linearly in log. Writes (a, mu xyz, lambda).
void interpolateLobe(const GlossyModel& model, uint32_t vertex, int lobe, const uint32_t views[3],
                     const float weights[3], float out[5]);

// An equirectangular environment (docs/conventions.md) prepared for the glossy runtime (docs/glossy.md, "Runtime"):
// - `levels`, a chain of 2x2 solid-angle-weighted box-filtered levels, each texel with its solid angle, over which
//   integrateLobe sums a lobe exactly (the reference path);
// - `sharpnessLevels`, the map convolved with normalised spherical Gaussians at sharpness
//   kStackSharpnessMin 2^(k / levelsPerOctave): texel (y, x) of a level holds the kernel-weighted mean radiance
//   sum(G L dOmega) / sum(G dOmega) of integrateLobe's texel sum for a lobe of that sharpness at the texel's centre,
//   so lookupLobe evaluates a lobe in O(1) (two bilinear lookups) where integrateLobe sums thousands of texels;
// - `rotation`, the map as the runtime sees it: L'(d) = L(R^T d) for the stored L (row-major, d' = R d, as
//   sh::rotationY), identity by default; both lookupLobe and integrateLobe turn the lobe mean by R^T, so a rotated
//   map (`--rotate-y`) costs no new prefilter.
struct PrefilteredEnvironment {
    struct Level {
        int width = 0, height = 0;
        std::vector<float> rgb;        // [height][width][3] radiance
        std::vector<float> solidAngle; // [height], per texel of the row
    };
    struct SharpnessLevel {
        double sharpness = 0.0;        // lambda of the normalised kernel
        int width = 0, height = 0;     // one of `levels`' sizes, texel spacing <= 1 / (texelsPerWidth sqrt(lambda))
        std::vector<float> rgb;        // [height][width][3] kernel-weighted mean radiance
    };
    std::vector<Level> levels;                   // finest first
    std::vector<SharpnessLevel> sharpnessLevels; // ascending sharpness, consecutive on the global grid; may be empty
    int firstSharpnessIndex = 0;                 // k of sharpnessLevels[0]
    int levelsPerOctave = 0;
    double rotation[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
};

// The sharpness grid of the stack: lambda_k = kStackSharpnessMin 2^(k / levelsPerOctave), k >= 0, up to
// kStackSharpnessMax (the fit's bounds, glossy::FitBounds).
constexpr double kStackSharpnessMin = 0.5;
constexpr double kStackSharpnessMax = 8192.0;

// What prefilterEnvironment builds. Every level on the grid whose interval touches [sharpnessMin, sharpnessMax] is
// built (so a lobe inside the range always has both neighbours); levels are a function of the map, their index
// and these two integers alone, so a range that holds them yields the same texels. sharpnessMax < sharpnessMin:
// no stack (lookupLobe then sums exactly).
struct PrefilterOptions {
    double sharpnessMin = kStackSharpnessMin;
    double sharpnessMax = kStackSharpnessMax;
    int levelsPerOctave = 2;      // 1..8
    int texelsPerWidth = 4;       // a level's texel spacing is at most 1 / (this sqrt(lambda)) (or the map's), 1..8
    const JobSystem* jobs = nullptr; // the rows of the stack as tasks (serial when null); results do not depend on it
};

// Needs width = 2 height, both >= 2 (a 2:1 map), rgb [height][width][3] finite, options in range. Throws
// prt::Error otherwise. The stack costs about what integrateLobe costs per texel it holds; see docs/glossy.md
// "Runtime" for time and memory.
PrefilteredEnvironment prefilterEnvironment(const float* rgb, int width, int height,
                                            const PrefilterOptions& options);
// The same with the default options: the whole sharpness range.
PrefilteredEnvironment prefilterEnvironment(const float* rgb, int width, int height);

// Integral of a exp(lambda (mu . w - 1)) L(w) over the sphere, per channel, for unit mu: summed over the texels
// within 5.5 / sqrt(lambda) rad of mu (all of them for wide lobes) of the coarsest level whose texel spacing is
// at most a quarter of the lobe's width 1 / sqrt(lambda). The exact reference path (O(lambda^0) but thousands of
// texels per lobe); the runtime uses lookupLobe.
void integrateLobe(const PrefilteredEnvironment& env, const float lobe[5], float radiance[3]);

// The same integral in O(1): a times the kernel's exact integral 2 pi / lambda (1 - exp(-2 lambda)) times the
// kernel-weighted mean radiance, bilinear at mu (across the poles and the +-pi seam) in the two stack levels around
// lambda, linear in log lambda between them. Exact for a constant map; otherwise within the interpolation error of
// integrateLobe (docs/glossy.md "Runtime" and the tests). Falls back to integrateLobe for a lambda outside the
// stack. Needs unit mu.
void lookupLobe(const PrefilteredEnvironment& env, const float lobe[5], float radiance[3]);

// The smallest and largest sharpness of the model's lobes with a > 0 ({1, 0} when none is lit): the range to
// prefilter for it.
void glossySharpnessRange(const GlossyModel& model, double& sharpnessMin, double& sharpnessMax);

// Below this many lobe evaluations per map, summing each lobe exactly costs less than building the stack (measured
// on 1024x512 maps, docs/glossy.md "Runtime"; both costs grow alike with the map's size).
constexpr size_t kStackBreakEvenLobes = 32768;

// Sets options' sharpness range for a pass of `lobeEvaluations` lobe integrations of `model` against one map: the
// lobes' own range (glossySharpnessRange) when the pass reaches kStackBreakEvenLobes, else no stack, so that
// lookupLobe sums every lobe exactly (integrateLobe). Either way within about 1% of the other (docs/glossy.md).
void choosePrefilterRange(const GlossyModel& model, size_t lobeEvaluations, PrefilterOptions& options);

// How the runtime evaluates each lobe against the environment.
enum class LobeEvaluation { Prefiltered, ExactSum }; // lookupLobe | integrateLobe

// The lobes of vertex `vertex` at view `view`, each mean turned by the rotation that takes the view's mirror
// direction about the vertex normal to unit `mirror` (amplitude and sharpness kept): out [lobes][5].
void turnViewLobes(const GlossyModel& model, uint32_t vertex, uint32_t view, const float mirror[3], float* out);

// Glossy radiance of vertex `vertex` toward unit direction d (from the surface to the viewer): for each of the 3
// views around d, that view's lobes turned onto d's mirror direction about the vertex normal (turnViewLobes) and
// integrated against the environment, the three blended with the barycentric weights; zero where d is below the
// vertex's tangent plane. What glossyRadiance does per vertex, and a per-pixel renderer per triangle corner.
// Needs model.lobes in 1..4 (as glossyModel guarantees; more are not read).
void glossyRadianceToward(const GlossyModel& model, const PrefilteredEnvironment& env, uint32_t vertex,
                          const float d[3], float radiance[3]);
// The same with each lobe evaluated as `evaluation` says (the default above is Prefiltered).
void glossyRadianceToward(const GlossyModel& model, const PrefilteredEnvironment& env, uint32_t vertex,
                          const float d[3], float radiance[3], LobeEvaluation evaluation);

// Glossy radiance of every vertex toward the point `eye`: for each of the 3 views around the eye direction, that
// view's lobes turned onto the eye's mirror direction (turnViewLobes) and integrated against the environment, the
// three radiances blended with the barycentric weights (docs/glossy.md, "Runtime": lobes are never paired across
// views); zero where the eye is below a vertex's tangent plane. radiance [V][3]. Lobes by lookupLobe unless
// `evaluation` says ExactSum.
void glossyRadiance(const GlossyModel& model, const PrefilteredEnvironment& env, const float eye[3],
                    float* radiance, LobeEvaluation evaluation = LobeEvaluation::Prefiltered);

// ---- cone lights through the glossy path (lib/runtime/glossy_lights.cpp, docs/glossy.md "Lights through the
// glossy path") ----------------------------------------------------------------------------------------------------
// The cone lights of `prt envlight`, shaded with the exact Phong lobe over sample directions of each cone and the
// caller's visibility of each sample (Embree rays in prt, an engine's shadow-map lookups), while the lobes
// integrate only the residual map (the map minus the cones). Per row v, light k and sample s:
//   directions [k][s][3] (uniform in solid angle over cone k; envlight::coneSampleDirections),
//   visible [v][k][s] in {0, 1} (0 also below the horizon).
struct GlossyConeLights {
    std::vector<HybridConeLight> lights;
    int samples = 0;               // per light
    std::vector<float> directions; // [lights][samples][3]
    std::vector<uint8_t> visible;  // [rows][lights][samples]
};

// The normalised Phong lobe of docs/conventions.md ("Glossy BRDF"), ks (n + 2) / (2 pi) max(0, r . w)^n, for unit
// mirror direction r and incoming w.
double phongLobeValue(const float mirror[3], const float incoming[3], double exponent, double ks);

// The lights' glossy radiance at vertex `vertex` toward unit direction d (surface to viewer):
//   sum_k radiance_k solidAngle_k / S sum_s f(w_ks, d) max(0, n . w_ks) visible[v][k][s]
// with f the model's Phong lobe (phongLobeValue about d's mirror direction) and n the vertex normal; zero where d is
// below the tangent plane. The Monte Carlo (stratified) estimate of the lobe times the shadowed cone, converging to
// the exact integral as S grows. Needs lights.visible sized model.vertexCount * lights * samples and
// lights.directions lights * samples * 3 (checkGlossyConeLights).
void glossyConeLightsToward(const GlossyModel& model, const GlossyConeLights& lights, uint32_t vertex, const float d[3],
                            float radiance[3]);

// The same for every vertex toward the point `eye`: radiance [V][3].
void glossyConeLightRadiance(const GlossyModel& model, const GlossyConeLights& lights, const float eye[3],
                             float* radiance);

// Throws prt::Error naming `source` unless lights' arrays fit the model's vertices (kExitFailure) and the model
// records its Phong lobe (exponent > 0, kExitInput: bundles written before params.brdf must be refitted).
void checkGlossyConeLights(const GlossyModel& model, const GlossyConeLights& lights, const std::string& source);


} // namespace prt
