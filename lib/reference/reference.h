// Ground truth: a Monte Carlo path tracer (Embree 3) for the outgoing radiance of diffuse surfaces under a
// distant environment map, the answer every precomputed method is compared against.
//
// Each sample is one path. At every diffuse vertex it combines two strategies with the power heuristic:
// next-event estimation that picks an environment texel with probability proportional to luminance times solid
// angle (then a direction uniformly inside it), and a cosine-weighted direction about the shading normal.
// Environment lookups are nearest-texel, the same piecewise-constant function the sampler integrates, so the
// estimate is unbiased for the map as stored. Shading normals are vertex normals (interpolated at hit points);
// a path that hits a back face ends with zero.
#pragma once

#include "bundle.h"
#include "image.h"
#include "raycast.h"

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace prt {

struct Surface; // lib/material

// The normalised Phong lobe on top of the diffuse albedo (docs/conventions.md, "Glossy BRDF"):
// f = albedo / pi + ks (n + 2) / (2 pi) max(0, r . wi)^n, r the mirror of the outgoing direction about the
// shading normal, the lobe zero when the outgoing direction is below the surface.
struct PhongBrdf {
    double exponent = 32.0; // n > 0
    double ks = 0.0;        // specular albedo in [0, 1]
};

struct ReferenceOptions {
    int bounces = 0;   // extra diffuse vertices per path: 0 = direct lighting only (shadowed)
    int samples = 256; // paths per vertex or pixel, >= 2 (the standard error needs two)
    uint64_t seed = 0;
    // Diffuse albedo: this constant if set, else the mesh's per-vertex albedo if it has one, else white.
    std::optional<std::array<float, 3>> albedo;
    // A scene's materials (lib/material; the mesh must be its flattened mesh), borrowed: every path vertex takes
    // the diffuse albedo of the material at its point (vertices: vertexDiffuseAlbedo), and rays pass through
    // cut-outs, exactly as transfer sees the scene. Not with `albedo`.
    const Surface* surface = nullptr;
    int threads = 0; // worker threads; 0 = all hardware threads. Results do not depend on it.
    // Glossy surfaces: the Phong lobe at every path vertex. Vertex mode then needs `eye`: each vertex's radiance
    // is the radiance it sends toward that point (view-dependent); images use the camera ray.
    std::optional<PhongBrdf> phong;
    std::optional<std::array<float, 3>> eye;
};

struct ReferenceRadiance {
    std::vector<float> radiance;      // rgb per vertex, mesh vertex order
    std::vector<float> standardError; // rgb per vertex: standard error of `radiance` (sample std-dev / sqrt(N))
    uint64_t rays = 0;                // rays cast, shadow rays included
};

// Outgoing radiance at every vertex of `mesh`, seen from its normal's side.
// Needs: mesh.normals for every vertex, mesh.albedo empty or rgb per vertex, options.samples >= 2,
// an environment whose size matches its layout. Same inputs and seed give bit-identical output for any thread count.
// Shows Progress. Throws prt::Error for an unusable environment (wrong size) or an Embree failure.
ReferenceRadiance referenceVertexRadiance(const TriMesh& mesh, const EnvironmentMap& env,
                                          const ReferenceOptions& options);

// The same at the listed vertices only (a pilot subset): row i is vertex vertices[i], bit for bit that vertex's
// row of referenceVertexRadiance (each vertex's paths come from its own random streams). Needs every index below
// the vertex count (throws prt::Error(kExitUsage) otherwise); repeats are allowed.
ReferenceRadiance referenceVertexRadianceAt(const TriMesh& mesh, const EnvironmentMap& env,
                                            const std::vector<uint32_t>& vertices, const ReferenceOptions& options);

// PinholeCamera (lib/raycast) is the camera of referenceImage, shared with `prt render`.

struct ReferenceImage {
    Image radiance;      // the first hit's outgoing radiance, or the environment's radiance where the ray escapes
    Image standardError; // per pixel, zero where the ray escapes
    uint64_t rays = 0;
};

// Renders `mesh` with one primary ray per pixel and `options.samples` paths at each hit, shaded exactly as
// referenceVertexRadiance shades vertices but with the interpolated normal and albedo at the hit point.
// Needs what referenceVertexRadiance needs, width and height > 0, eye != target and up not parallel to the view.
ReferenceImage referenceImage(const TriMesh& mesh, const EnvironmentMap& env, const PinholeCamera& camera,
                              const ReferenceOptions& options);

// ---- brute-force direct lighting (bounces 0), for FIV shadows -------------------------------------------------
// An occluder placed in the world: it blocks light but is not shaded; its vertex p sits at p + translation.
struct DirectOccluder {
    TriMesh mesh;
    std::array<float, 3> translation{0, 0, 0};
};
struct DirectOptions {
    std::optional<std::array<float, 3>> albedo; // as ReferenceOptions::albedo
    bool shadows = true; // false: unshadowed irradiance (no rays at all)
    int threads = 0;
    // Glossy: the Phong lobe of `phong` on top of the albedo (as ReferenceOptions::phong), toward the eye point
    // `eye`, which it then needs.
    std::optional<PhongBrdf> phong;
    std::optional<std::array<float, 3>> eye;
};
// Outgoing radiance at every receiver vertex from direct light only, as the exact sum over every texel of the map
// at its full resolution: albedo / pi * sum_t L_t max(0, N . w_t) V_t dw_t, texel-centre directions, exact texel
// solid angles, V_t one Embree shadow ray from the vertex (pushed off along its normal) against the receiver and
// every occluder. A flat receiver cannot shadow itself, so there only the rays that meet an occluder's bounding
// sphere are cast. With options.phong the sum is sum_t L_t f(w_t, w_o) max(0, N . w_t) V_t dw_t, f the diffuse
// plus Phong BRDF (docs/conventions.md, "Glossy BRDF") evaluated at texel centres, w_o the unit direction from the
// vertex to options.eye: the exact direct glossy radiance, the oracle of prt glossy (docs/glossy.md).
// Deterministic; standardError is zero. Needs receiver normals, and the eye with phong; throws prt::Error otherwise.
ReferenceRadiance referenceDirectRadiance(const TriMesh& receiver, const std::vector<DirectOccluder>& occluders,
                                          const EnvironmentMap& env, const DirectOptions& options);

} // namespace prt
