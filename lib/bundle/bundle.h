// Bundles: glTF 2.0 binaries (.glb) that any viewer opens as the mesh, carrying precomputed layers under the
// versioned extension PRT_bundle. docs/bundle.md is the format's reference; this header is its C++ face.
// Every stage reads and writes meshes through this header, so the triangle mesh type lives here too.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {

// An indexed triangle mesh with flat arrays. Units and orientation: docs/conventions.md.
// Invariants after validation (lib/mesh): every index < vertexCount(); per-vertex arrays are empty or sized
// to vertexCount() times their width; all floats finite.
struct TriMesh {
    std::vector<float> positions;  // xyz per vertex
    std::vector<float> normals;    // unit xyz per vertex, or empty
    std::vector<float> texcoords;  // uv per vertex (glTF TEXCOORD_0, v down), or empty
    std::vector<float> albedo;     // linear rgb diffuse albedo per vertex (glTF COLOR_0 times baseColorFactor), or empty
    std::vector<uint32_t> indices; // 3 per triangle, counter-clockwise front faces

    size_t vertexCount() const { return positions.size() / 3; }
    size_t triangleCount() const { return indices.size() / 3; }
};

// One precomputed array in a bundle. `domain` says what the first axis runs over:
//   "vertex"  : one row per mesh vertex, in the mesh's vertex order
//   "texel"   : one row per atlas texel (row-major, y down), `params` holds width/height
//   "occluder": one row per grid cell of an occluder's FIV grid
//   "lobe"    : one row per (vertex, lobe) of a view-dependent fit
// `shape` is the full array shape, first axis = rows; data is float32, C order.
struct Layer {
    std::string name;     // unique within a bundle, e.g. "transfer"
    std::string domain;   // see above
    std::string semantic; // what a row means, e.g. "sh_transfer_rgb" ([coefficient][3] per vertex)
    std::vector<uint64_t> shape;
    std::vector<float> data;
    nlohmann::json params = nlohmann::json::object(); // order, mode, samples, ... as the producing stage set them
};

// Provenance of a bundle: who produced it from what.
struct Bundle {
    TriMesh mesh;
    std::vector<Layer> layers;
    nlohmann::json producer = nlohmann::json::object(); // {"tool":"prt","version":..,"stage":..}
    nlohmann::json inputs = nlohmann::json::object();   // {"mesh": "xxh128:..", "env": ..}
    nlohmann::json convention = nlohmann::json::object();
};

inline constexpr int kBundleVersion = 1;
inline constexpr const char* kBundleExtension = "PRT_bundle";

// Writes `bundle` as a .glb atomically. The mesh is a standard glTF primitive (POSITION, NORMAL, TEXCOORD_0,
// COLOR_0 when present); layers go into buffer views referenced only from the PRT_bundle extension, with a
// checksum of the binary chunk so readers detect truncation and tampering.
void writeBundle(const std::string& path, const Bundle& bundle);

// Reads a .glb or .gltf. Throws prt::Error naming the file and the problem for: a missing file, a truncated or
// malformed glTF, a PRT_bundle of an unsupported version, a checksum mismatch. A plain glTF without the extension
// reads as a bundle with no layers.
Bundle readBundle(const std::string& path);

// Finds a layer by name; nullptr if absent.
const Layer* findLayer(const Bundle& bundle, const std::string& name);

} // namespace prt
