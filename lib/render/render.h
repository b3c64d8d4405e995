// Pictures of relit bundles (`prt render`): one Embree primary ray per pixel through the pinhole camera that
// `prt reference --image` uses (lib/raycast), so a render and a reference line up pixel for pixel. At a front-face
// hit the pixel takes the relit radiance interpolated there: per vertex with the hit's barycentrics (what a
// rasteriser does with a per-vertex colour), or per texel as the nearest texel of the relit atlas at the hit's
// interpolated TEXCOORD_0 (glTF's u right, v down; texel row 0 at the top). A back-face hit is black, as it ends a
// reference path; a ray that hits nothing is black with coverage 0.
#pragma once

#include "bundle.h"
#include "image.h"
#include "raycast.h"

#include <cstdint>
#include <string>
#include <vector>

namespace prt {

struct GlossyModel;      // prt/glossy.h
struct GlossyConeLights; // prt/glossy.h
struct PrefilteredEnvironment; // prt/glossy.h

struct RenderedImage {
    Image radiance;              // linear RGB, row 0 at the top
    std::vector<float> coverage; // per pixel: 1 where the ray hits the mesh (front or back face), 0 where it escapes
    uint64_t rays = 0;
};

// Renders per-vertex radiance ([vertexCount][3], the mesh's vertex order, e.g. what the runtime relights).
// Needs radiance sized mesh.vertexCount() * 3 and a camera pinholeRays accepts. Throws prt::Error otherwise
// (kExitInput for a wrong radiance size, kExitUsage for a bad camera, kExitFailure for Embree).
// With a scene's `surface` (lib/material; mesh must be its flattened mesh), `radiance` is what a white surface
// reflects (a scene's irradiance transfer relit without its albedo, E / pi) and each pixel multiplies it by the
// material's diffuse albedo at the hit (texture, factor, COLOR_0, 1 - metallic), as an engine does with a
// lightmap; primary rays pass through cut-outs. Back faces stay black, double-sided or not, as in the reference.
RenderedImage renderVertexRadiance(const TriMesh& mesh, const std::vector<float>& radiance, const PinholeCamera& camera,
                                   const Surface* surface = nullptr);

// Renders per-vertex diffuse radiance ([V][3], as renderVertexRadiance interpolates it) plus glossy lobes evaluated
// per pixel: at each hit the view direction from the hit point to the camera's eye, each corner's lobes toward that
// one direction (glossyRadianceToward, prt/glossy.h) blended with the hit's barycentrics. So a highlight moves
// across a triangle as the camera does, where per-vertex glossy radiance would cross-fade between its corners.
// With glossyOnly the diffuse radiance is left out (it may then be empty). Needs a model of this mesh's vertices and
// an equirectangular map (prefiltered here once); throws prt::Error(envSource, "--env", ...) for another layout.
// With `lights` (docs/glossy.md "Lights through the glossy path"; `environment` is then the residual map) each
// corner also adds its cone lights' glossy radiance toward the pixel's direction (glossyConeLightsToward, with that
// corner's per-sample visibility), blended the same way. With `rotation` (row-major 3x3, as sh::rotationY; null for
// none) the lobes see the map turned by it, L'(d) = L(R^T d): the lookup turns, the stack is the same. With
// `prefiltered` (glossyRenderEnvironment of this model and map, e.g. one also written by writeSharpnessStack) that
// stack is used instead of building it again.
RenderedImage renderGlossyRadiance(const TriMesh& mesh, const std::vector<float>& diffuse, const GlossyModel& glossy,
                                   const EnvironmentMap& environment, const std::string& envSource,
                                   const PinholeCamera& camera, bool glossyOnly,
                                   const GlossyConeLights* lights = nullptr, const double* rotation = nullptr,
                                   const PrefilteredEnvironment* prefiltered = nullptr);

// The prefiltered environment renderGlossyRadiance evaluates `glossy`'s lobes against (lib/render/glossy_stack.cpp):
// the stack over the lobes' own sharpness range (glossySharpnessRange), rows on TBB, rotation identity. Needs an
// equirectangular map; throws prt::Error(envSource, "--env", ...) for another layout.
PrefilteredEnvironment glossyRenderEnvironment(const GlossyModel& glossy, const EnvironmentMap& environment,
                                               const std::string& envSource);

// `prt render --glossy-stack`: writes env's sharpness stack (env.sharpnessLevels, what lookupLobe reads) atomically
// as a "prt-sg-stack" file for the browser viewer (docs/glossy.md "The stack file"), little-endian:
//   "PRTSGSTK", uint32 version 1, levelsPerOctave, firstSharpnessIndex, levelCount,
//   then per level uint32 width, height, float64 sharpness, float32 rgb [height][width][3].
// Needs at least two levels (a stack lookupLobe uses); throws prt::Error(path, "--glossy-stack") otherwise.
void writeSharpnessStack(const std::string& path, const PrefilteredEnvironment& env);

// Renders a relit atlas (width x height texels, e.g. `prt relight --texels`) through the mesh's TEXCOORD_0, or
// through `cornerUv` ([3 T][2], a scene bake's layer "lightmap_uv": corner k of triangle t at 3 t + k) when given.
// With a scene's `surface` the atlas holds E / pi (a scene bake's irradiance transfer) and each pixel multiplies it
// by the material's diffuse albedo at the hit, as renderVertexRadiance does; primary rays pass through cut-outs.
// Needs texcoords for every vertex (or cornerUv for every corner), atlas.rgb sized width * height * 3. Throws
// prt::Error otherwise.
RenderedImage renderTexelRadiance(const TriMesh& mesh, const Image& atlas, const PinholeCamera& camera,
                                  const float* cornerUv = nullptr, const Surface* surface = nullptr);

// The atlas of a scene bake, its layer "lightmap_uv": [3 T][2], uv per triangle corner of bundle.mesh. Throws
// prt::Error(source, ...) when the layer is absent, not a float32 corner layer of that shape, or not finite.
std::vector<float> lightmapCorners(const Bundle& bundle, const std::string& source);

// `prt render --background`: every pixel whose ray escapes (coverage 0) takes the environment's radiance along the
// pixel's pinhole ray, turned with the lighting (the lighting turned by rotateYDegrees about +Y, R, shows the map at
// R^T d), looked up bilinearly between texel centres (u repeats, v clamps), as the browser viewer's sky
// (viewer/sky.js) does; coverage stays 0 there, so `prt compare --image` still measures the surface only. Pixels
// that hit the mesh, back faces included, are left as they are. Needs an equirectangular map (throws
// prt::Error(envSource, "--background", kExitUsage) for a cube strip) and an image of the camera's size.
void drawEnvironmentBackground(RenderedImage& image, const EnvironmentMap& environment, const std::string& envSource,
                               const PinholeCamera& camera, double rotateYDegrees);

// Writes `image` atomically as a linear float RGBA OpenEXR, A = coverage (empty coverage: 1). For a tone-mapped
// PNG, `prt render` passes the radiance through compare.h's toneMap, the one tone map of prt's pictures.
void writeRenderedExr(const std::string& path, const Image& image, const std::vector<float>& coverage);

// Writes a render by the extension of `path`, atomically: .exr as writeRenderedExr, .png tone mapped by compare.h's
// tonemappedPicture at `exposure` stops. Throws prt::Error(kExitUsage) naming -o for any other extension.
void writeRenderedPicture(const std::string& path, const RenderedImage& image, float exposure);

} // namespace prt
