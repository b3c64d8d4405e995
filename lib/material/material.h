// Materials at surface points: the diffuse albedo and the cut-outs of a scene bundle's glTF materials (asset.h),
// with their base colour textures decoded. Transfer, bake, reference and render all evaluate a surface point
// through these functions, so every stage sees the same albedo and the same holes.
//
// Diffuse albedo (written once, here): albedo = baseColorFactor.rgb * texture.rgb * COLOR_0.rgb * (1 - metallic),
// alpha = baseColorFactor.a * texture.a * COLOR_0.a; a Mask or Blend material has no surface where alpha <
// alphaCutoff (asset.h). The texture is read at the point's TEXCOORD_n (the material's set), mapped by its
// KHR_texture_transform, wrapped by its sampler (repeat, mirrored repeat, clamp) and filtered bilinearly between
// texel centres, or by the nearest texel for a NEAREST magnification filter. Images are PNG or JPEG decoded from
// sRGB to linear RGB (alpha stays linear).
//
// A surface point is (triangle t of the flattened mesh, barycentrics b1 b2): the point (1 - b1 - b2) p0 + b1 p1 +
// b2 p2 of the triangle's corners, Embree's hit.u and hit.v.
#pragma once

#include "bundle.h"

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace prt {

// One decoded image: linear RGBA, row-major, row 0 at the top (glTF's v = 0).
struct SurfaceImage {
    int width = 0, height = 0;
    std::vector<float> rgba;
};

// A scene's materials ready to evaluate. Borrows `mesh` (the flattened mesh of the bundle it was made from),
// which must outlive it; holds the asset.
struct Surface {
    std::shared_ptr<const SceneAsset> asset;
    const TriMesh* mesh = nullptr;
    std::vector<SurfaceImage> images; // per asset image; those no material uses stay empty
    bool cutouts = false;             // some material is Mask or Blend
    bool instancing = true;           // ray casting builds meshes placed by several nodes as Embree instances
};

// The largest image prt decodes, per side and in texels (a 16k x 16k texture is 1 GiB of float RGBA).
inline constexpr int kMaxTextureSide = 16384;
inline constexpr uint64_t kMaxTextureTexels = uint64_t(1) << 26;

// Decodes every image a material uses as its base colour texture, each through OpenImageIO from its encoded
// bytes, its header's size checked against kMaxTextureSide, kMaxTextureTexels and the element cap before any
// pixel is decoded. Needs a bundle with an asset (bundle.asset) and bundle.mesh its flattened mesh; `file` names
// the bundle in errors. Throws prt::Error(file, "images[i]", problem, kExitInput) for an image that does not
// decode or is too large.
Surface decodeSurface(const Bundle& bundle, const std::string& file);

// Base colour (linear RGBA: factor * texture * COLOR_0) at a surface point. Needs triangle < the mesh's count.
std::array<float, 4> baseColorAt(const Surface& surface, size_t triangle, float b1, float b2);

// Diffuse albedo (linear RGB, in [0, 1]) at a surface point: the base colour times (1 - metallic).
std::array<float, 3> diffuseAlbedoAt(const Surface& surface, size_t triangle, float b1, float b2);

// Whether the surface exists at the point: false where a Mask or Blend material's alpha is below its cutoff.
bool presentAt(const Surface& surface, size_t triangle, float b1, float b2);

// The diffuse albedo at every vertex of the flattened mesh ([V][3]): its receiver's material evaluated at the
// vertex's own texcoord and colour, what a per-vertex result is multiplied by.
std::vector<float> vertexDiffuseAlbedo(const Surface& surface);

// Reads a texture at uv (glTF's: v down) with the record's wrap and filter: linear RGBA.
std::array<float, 4> sampleTexture(const SurfaceImage& image, const TextureRecord& texture, float u, float v);

// sRGB transfer function to linear, for 8-bit and 16-bit image values in [0, 1].
float srgbToLinear(float encoded);

} // namespace prt
