// Internal to prt_reference: the environment sampler, the Embree scene and the one-path estimator that
// vertex mode and image mode share.
#pragma once

#include "bundle.h"
#include "image.h"

#include "raycast.h"

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace prt::pathtrace {

// ---- random numbers -----------------------------------------------------------------------------------------
// PCG32 (O'Neill, XSH-RR). Each (seed, point, sample) gets its own generator, so a sample's numbers do not
// depend on which thread runs it or in which order.
struct Pcg32 {
    uint64_t state = 0;
    uint64_t increment = 1;

    uint32_t next();
    // Uniform in [0, 1) with 24 bits, and with 53 bits for choices among many texels.
    float uniform();
    double uniformDouble();
};
Pcg32 sampleGenerator(uint64_t seed, uint64_t point, uint64_t sample);

// ---- environment --------------------------------------------------------------------------------------------
// Importance sampling of an environment map by texel luminance times texel solid angle: a marginal
// distribution over image rows, then a conditional one over the chosen row's texels.
struct EnvironmentTexel {
    float radiance[3];
    float density; // equirect: pdf per steradian; cube strip: pdf per unit area of the face plane
};
struct EnvironmentSampler {
    EnvLayout layout = EnvLayout::Equirectangular;
    int width = 0, height = 0;
    std::vector<EnvironmentTexel> texels; // row-major, radiance and density side by side for one memory access
    std::vector<double> rowCdf;           // running row probability, ending at 1; empty if the map is black
    std::vector<double> columnCdf;        // per row, running conditional probability of its texels
    std::vector<double> rowCosine;        // equirect: cos of each row's upper polar bound, height + 1 values
};
// Throws prt::Error when the image size does not match the layout.
EnvironmentSampler makeEnvironmentSampler(const EnvironmentMap& env);

// The texel (row-major pixel index) that direction d (unit) falls in.
size_t environmentTexel(const EnvironmentSampler& sampler, const float d[3]);
// Solid-angle pdf with which sampleEnvironment produces direction d, given d lies in `texel`.
float environmentPdf(const EnvironmentSampler& sampler, size_t texel, const float d[3]);

struct EnvironmentSample {
    float direction[3];
    size_t texel;
    float pdf; // per steradian
};
// Picks a row with uRow, a texel in it with uColumn, and a point inside the texel with u1, u2. Needs a
// non-empty rowCdf.
EnvironmentSample sampleEnvironment(const EnvironmentSampler& sampler, double uRow, double uColumn, float u1,
                                    float u2);

// ---- scene --------------------------------------------------------------------------------------------------
// Where a path scatters: position, unit shading normal, the unit normal ray origins are pushed along (to the
// side the shading normal faces), and the diffuse albedo.
struct ShadingPoint {
    float position[3];
    float normal[3];
    float offsetNormal[3];
    float albedo[3];
};

enum class HitKind { Miss, BackFace, FrontFace };

// The mesh in an Embree scene, with its normals and albedo for shading hit points.
class SceneTracer {
public:
    // Needs mesh.normals per vertex; keeps references to `mesh`, which must outlive the tracer.
    // With a scene's `surface` (borrowed, outliving the tracer) albedo comes from its materials and rays pass
    // through its cut-outs.
    SceneTracer(const TriMesh& mesh, const std::optional<std::array<float, 3>>& constantAlbedo,
                const Surface* surface = nullptr);

    ShadingPoint vertexPoint(uint32_t vertex) const;
    // Casts origin + t d, t > 0. On a front-face hit fills `point`.
    HitKind intersect(const float origin[3], const float d[3], ShadingPoint* point) const;
    bool occluded(const float origin[3], const float d[3]) const;
    // Ray origins leave a shading point this far along its offset normal: far enough to clear float error,
    // small against the model.
    float rayOffset() const { return rayOffset_; }

private:
    void albedoAt(const uint32_t* triangle, float u, float v, float out[3]) const;

    const TriMesh& mesh_;
    std::optional<std::array<float, 3>> constantAlbedo_;
    const Surface* surface_ = nullptr;
    std::vector<float> vertexAlbedo_; // with a surface: vertexDiffuseAlbedo
    EmbreeScene embree_;
    float rayOffset_ = 0.0f;
};

// ---- estimator ----------------------------------------------------------------------------------------------
// One path's estimate of the radiance leaving `point` along its shading normal's side, with up to `bounces`
// further diffuse vertices. Adds the rays it casts to `rays`.
void estimateRadiance(const SceneTracer& scene, const EnvironmentSampler& environment, const ShadingPoint& point,
                      int bounces, Pcg32& random, double radiance[3], uint64_t& rays);

// The same for a glossy surface (diffuse albedo plus the Phong lobe of `phong`), seen from unit direction
// `outgoing` (away from the point). BRDF sampling is a mixture of the cosine and Phong lobes, combined with
// next-event estimation by the power heuristic; every further vertex is glossy too, seen along the path.
void estimateGlossyRadiance(const SceneTracer& scene, const EnvironmentSampler& environment,
                            const ShadingPoint& point, const float outgoing[3], double exponent, double ks,
                            int bounces, Pcg32& random, double radiance[3], uint64_t& rays);

// The Phong lobe value ks (n + 2) / (2 pi) max(0, r . wi)^n for unit r and wi (docs/conventions.md).
float phongLobe(const float mirror[3], const float incoming[3], double exponent, double ks);

} // namespace prt::pathtrace
