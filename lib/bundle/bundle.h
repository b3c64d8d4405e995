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
// Needs: a mesh with at least one triangle and per-vertex arrays of matching sizes; layers with unique non-empty
// names, data.size() equal to the product of shape (or no data when that product is 0 or params.uri names an
// external file), vertex-domain layers with vertexCount() rows. JSON (producer, inputs, convention, params) is
// stored as glTF stores it: null members and empty arrays or objects are left out, integers beyond 32 bits become
// doubles; NaN, infinities and integers beyond 2^53 are refused. Throws prt::Error (kExitFailure) when these
// needs are not met and prt::Error (kExitOutput) when the file cannot be written; either way `path` is untouched.
void writeBundle(const std::string& path, const Bundle& bundle);

// The "convention" record stages write into their bundles: the choices of docs/conventions.md, by name.
nlohmann::json conventionRecord();

// Reads a .glb or .gltf. Throws prt::Error naming the file and the problem for: a missing file, a truncated or
// malformed glTF, a PRT_bundle of an unsupported version, a checksum mismatch. A plain glTF without the extension
// reads as a bundle with no layers.
// The mesh merges every TRIANGLES primitive reachable from the default scene (or every mesh when the file has no
// scene), with node transforms applied (winding kept counter-clockwise under mirroring transforms). NORMAL and
// TEXCOORD_0 are kept when every primitive has them. Albedo is COLOR_0 times the material's baseColorFactor, or
// the factor alone, and stays empty when it would be 1 everywhere. Indices are not range-checked here (lib/mesh
// validation reports them); an index outside its own primitive reads as 0xFFFFFFFF so merging cannot hide it.
// Every accessor is bounds-checked against its buffer, so a malformed file cannot cause an out-of-bounds read.
Bundle readBundle(const std::string& path);

// Finds a layer by name; nullptr if absent.
const Layer* findLayer(const Bundle& bundle, const std::string& name);

// The order of shard bundles of one `--shard I/N` run, given their sharded layers (null where a bundle has none):
// result[I] is the position of shard I. Needs every layer's params.shard = [I, N] with N the number of layers and
// each I once. Throws prt::Error(files[s], "", problem, kExitInput) naming the first bundle that is no shard, of
// another N, out of range or given twice.
std::vector<size_t> orderShards(const std::vector<const Layer*>& layers, const std::vector<std::string>& files);

} // namespace prt
