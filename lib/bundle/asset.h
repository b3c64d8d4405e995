// Scene assets: a glTF 2.0 scene (node tree, instanced meshes, materials, textures) that a version 3 bundle
// carries intact beside its PRT layers (docs/bundle.md, "Scene bundles"). bundle.h includes this header; the
// types are plain records of what the file says, read and checked once by readBundle. Decoding the textures and
// evaluating albedo and cut-outs at surface points is lib/material's.
//
// The scene's rows. A scene is flattened, for every stage, into one world-space TriMesh (Bundle::mesh): its
// receivers, each one primitive placed by one node, in node order (the default scene's roots in order, each node
// before its children, children in order) and then primitive order, their vertices in accessor order. Every
// vertex-domain layer of a scene bundle has a row per vertex of that mesh, so an instance is its own receiver with
// its own rows.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace prt {

enum class AlphaMode : uint8_t {
    Opaque, // alpha ignored
    Mask,   // a surface point exists where alpha >= alphaCutoff, and is absent (no occlusion, no reflection) elsewhere
    Blend,  // prt treats blended surfaces as Mask with the material's cutoff (0.5 by default): transfer has no
            // partial occlusion, so a point is either there or not (docs/bundle.md "Materials")
};

// One glTF material as prt uses it (pbrMetallicRoughness). The diffuse albedo at a surface point is
// baseColorFactor.rgb * texture.rgb (at the point's texcoord) * COLOR_0.rgb * (1 - metallic), written once in
// lib/material; alpha is the product of the same factors' alpha channels.
struct MaterialRecord {
    std::string name;
    std::array<float, 4> baseColorFactor{1, 1, 1, 1}; // linear RGBA
    float metallic = 0.0f;     // a glTF material's metallicFactor (glTF's default 1); a primitive without material: 0
    int baseColorTexture = -1; // index into SceneAsset::textures, or -1
    int texCoord = 0;          // 0 or 1: TEXCOORD_n the texture is read with (after KHR_texture_transform's override)
    // KHR_texture_transform as a 2x3 affine map, uv' = (m[0] u + m[1] v + m[2], m[3] u + m[4] v + m[5]):
    // translation * rotation * scale as that extension defines them. Identity without the extension.
    std::array<float, 6> uvTransform{1, 0, 0, 0, 1, 0};
    AlphaMode alphaMode = AlphaMode::Opaque;
    float alphaCutoff = 0.5f;
    bool doubleSided = false;
};

// A glTF texture: an image and how it is sampled. Wrap and filter values are glTF's enums (10497 REPEAT, 33071
// CLAMP_TO_EDGE, 33648 MIRRORED_REPEAT; 9728 NEAREST, 9729 LINEAR, ...), checked on reading.
struct TextureRecord {
    int image = -1; // index into SceneAsset::images
    int wrapS = 10497, wrapT = 10497;
    int magFilter = -1, minFilter = -1; // -1: not given (prt samples bilinearly)
};

// A glTF image's encoded bytes (PNG or JPEG), from a buffer view, a data URI or a file next to the glTF file.
struct ImageRecord {
    std::string name;
    std::string mimeType; // "image/png" or "image/jpeg"
    std::vector<unsigned char> bytes;
};

// One placed primitive: rows [firstVertex, firstVertex + vertexCount) and triangles [firstTriangle, ...) of the
// flattened mesh.
struct SceneReceiver {
    int node = -1, mesh = -1, primitive = -1;
    int material = 0; // index into SceneAsset::materials (the default material when the primitive names none)
    uint32_t firstVertex = 0, vertexCount = 0;
    uint32_t firstTriangle = 0, triangleCount = 0;
    std::array<double, 16> world{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; // column-major node-to-world
    bool mirrored = false; // negative determinant: the winding was flipped to stay counter-clockwise
};

// What a scene bundle carries besides the flattened mesh.
struct SceneAsset {
    // The asset as read, with every buffer merged into buffer 0 and every image in a buffer view, so that it
    // writes as one self-contained .glb; writeBundle adds the PRT layers to a copy.
    std::shared_ptr<const tinygltf::Model> source;
    // The asset's glTF JSON as the file wrote it: what writeBundle writes back, object for object, so that nothing
    // tinygltf would normalise (defaults it adds, members it reads into other types) changes. Empty for an asset
    // built in memory (an OBJ), which is written as tinygltf serialises `source`.
    std::string sourceJson;
    std::vector<SceneReceiver> receivers;
    std::vector<MaterialRecord> materials; // the asset's, in order, then the default material (white, metallic 0)
    std::vector<TextureRecord> textures;
    std::vector<ImageRecord> images;
    std::vector<uint32_t> triangleReceiver; // per flattened triangle: its receiver
    // Per flattened vertex: TEXCOORD_0 and TEXCOORD_1 (u, v; zeros where a primitive lacks the set, or empty when
    // no primitive has it) and COLOR_0 as linear RGBA (1 where a primitive has none, or empty when none has it).
    std::vector<float> texcoords[2];
    std::vector<float> colors;

    const MaterialRecord& triangleMaterial(size_t triangle) const {
        return materials[size_t(receivers[triangleReceiver[triangle]].material)];
    }
};

} // namespace prt
