// prt/hybrid.h: hybrid relighting, cone lights plus an SH residual (lib/runtime/hybrid.cpp, docs/envlight.md).
#pragma once

#include "relight.h"
#include "sh.h"

#include <array>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace prt {

struct Bundle; // bundle.h

// `prt envlight` splits an environment into a few cone lights (uniform radiance inside a cone) and the SH
// projection of the rest. The hybrid relights the residual through the whole transfer, each light's direct light
// in closed form with the caller's visibility (an engine's shadow maps), and each light's interreflected light
// through the bounce part of the transfer (the "transfer_bounce" layer: transfer minus its direct pass):
//   radiance = T . residual + B . sum_k proj(light_k) + sum_k (albedo / pi) radiance_k visibility_k C_k(n)
// with C_k(n) = integral over cone k of max(0, n . w) dw (coneCosineIntegral).

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
