// prt/glossy.h: glossy spherical-Gaussian lobes (bundles from `prt glossy`; docs/glossy.md "Runtime").
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

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

// Glossy radiance of vertex `vertex` toward unit direction d (from the surface to the viewer): for each of the 3
// views around d, that view's lobes turned onto d's mirror direction about the vertex normal (turnViewLobes) and
// integrated against the environment, the three blended with the barycentric weights; zero where d is below the
// vertex's tangent plane. What glossyRadiance does per vertex, and a per-pixel renderer per triangle corner.
// Needs model.lobes in 1..4 (as glossyModel guarantees; more are not read).
void glossyRadianceToward(const GlossyModel& model, const PrefilteredEnvironment& env, uint32_t vertex,
                          const float d[3], float radiance[3]);

// Glossy radiance of every vertex toward the point `eye`: for each of the 3 views around the eye direction, that
// view's lobes turned onto the eye's mirror direction (turnViewLobes) and integrated against the environment, the
// three radiances blended with the barycentric weights (docs/glossy.md, "Runtime": lobes are never paired across
// views); zero where the eye is below a vertex's tangent plane. radiance [V][3].
void glossyRadiance(const GlossyModel& model, const PrefilteredEnvironment& env, const float eye[3],
                    float* radiance);


} // namespace prt
