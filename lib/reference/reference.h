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

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace prt {

struct ReferenceOptions {
    int bounces = 0;   // extra diffuse vertices per path: 0 = direct lighting only (shadowed)
    int samples = 256; // paths per vertex or pixel, >= 2 (the standard error needs two)
    uint64_t seed = 0;
    // Diffuse albedo: this constant if set, else the mesh's per-vertex albedo if it has one, else white.
    std::optional<std::array<float, 3>> albedo;
    int threads = 0; // worker threads; 0 = all hardware threads. Results do not depend on it.
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

// A pinhole camera. Pixel (x, y), row 0 at the top, looks through its centre: with f = forward (target - eye),
// r = f x up and u = r x f normalised, the ray is f + (2 (x + 0.5) / width - 1) tan(fovy / 2) aspect r
// + (1 - 2 (y + 0.5) / height) tan(fovy / 2) u, aspect = width / height.
struct PinholeCamera {
    std::array<float, 3> eye{0, 0, 1};
    std::array<float, 3> target{0, 0, 0};
    std::array<float, 3> up{0, 1, 0};
    float fovyDegrees = 40.0f;
    int width = 0;
    int height = 0;
};

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
};
// Outgoing radiance at every receiver vertex from direct light only, as the exact sum over every texel of the map
// at its full resolution: albedo / pi * sum_t L_t max(0, N . w_t) V_t dw_t, texel-centre directions, exact texel
// solid angles, V_t one Embree shadow ray from the vertex (pushed off along its normal) against the receiver and
// every occluder. A flat receiver cannot shadow itself, so there only the rays that meet an occluder's bounding
// sphere are cast. Deterministic; standardError is zero. Needs receiver normals; throws prt::Error otherwise.
ReferenceRadiance referenceDirectRadiance(const TriMesh& receiver, const std::vector<DirectOccluder>& occluders,
                                          const EnvironmentMap& env, const DirectOptions& options);

} // namespace prt
