// Bundles: glTF 2.0 binaries (.glb) that any viewer opens as the mesh, carrying precomputed layers under the
// versioned extension PRT_bundle. docs/bundle.md is the format's reference; this header is its C++ face.
// Every stage reads and writes meshes through this header, so the triangle mesh type lives here too.
#pragma once

#include "asset.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <memory>
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

// One precomputed array in a bundle. `domain` says what the first axis runs over (docs/bundle.md, "Layer domains"):
//   "vertex"  : one row per vertex of the layer's object, in its vertex order
//   "texel"   : one row per atlas texel (row-major, y down), `params` holds width/height
//   "grid"    : one row per sample of a regular grid around the object (FIV grids); params name the axes
//   "vertex_range", "texel_range": a shard's rows of a vertex or texel layer
// `shape` is the full array shape, first axis = rows, C order (last axis fastest).
// Values: float layers ("float32", "float16") keep them in `data` (float16 is rounded to nearest-even half on write
// and widened on read, so `data` always holds what a reader gets back); integer layers ("uint8", "uint16",
// "uint32") keep them in `integers`. Exactly one of the two is filled, with the product of `shape` elements.
struct Layer {
    std::string name;     // unique within a bundle, e.g. "transfer"
    std::string domain;   // see above
    std::string semantic; // what a row means, e.g. "sh_transfer_rgb" ([coefficient][3] per vertex)
    std::vector<uint64_t> shape;
    std::string componentType = "float32"; // "float32" | "float16" | "uint8" | "uint16" | "uint32"
    std::vector<float> data;               // float32 and float16 layers
    std::vector<uint32_t> integers;        // uint8, uint16 and uint32 layers (each value must fit the type)
    uint32_t object = 0;                   // the bundle object the rows belong to: 0 is Bundle::mesh, k is objects[k-1]
    nlohmann::json params = nlohmann::json::object(); // order, mode, samples, ... as the producing stage set them
};

// A further mesh of a bundle (version 2): an occluder type, a second receiver, ... Object k >= 1 of a bundle is
// objects[k - 1]; object 0 is always Bundle::mesh. Each object is its own glTF mesh and node.
struct BundleObject {
    std::string name; // unique within the bundle, not empty
    std::string role; // "receiver", "occluder", or another word the producing stage documents
    TriMesh mesh;
};

// A placement of an object (version 2): its vertex p sits at p + translation, in world units. Written as a glTF
// node with that translation, so viewers show every instance.
struct Instance {
    std::string name;   // may be empty
    uint32_t object = 0; // 0 is Bundle::mesh, k is objects[k-1]
    std::array<float, 3> translation{0, 0, 0};
};

// What a bundle holds, with its provenance.
struct Bundle {
    TriMesh mesh;                      // object 0
    std::string meshName;              // object 0's name ("" reads as "mesh")
    std::string meshRole = "receiver"; // object 0's role
    std::vector<BundleObject> objects; // objects 1..N (version 2)
    std::vector<Instance> instances;   // (version 2); empty means every object once, untranslated
    std::vector<Layer> layers;
    // A scene bundle (version 3, asset.h): the glTF asset it carries intact, of which `mesh` is the flattened
    // world-space receiver mesh; null for a bundle of prt's own meshes (objects and instances above). Shared and
    // immutable, so stages pass it from the bundle they read to the one they write.
    std::shared_ptr<const SceneAsset> asset;
    nlohmann::json producer = nlohmann::json::object(); // {"tool":"prt","version":..,"stage":..}
    nlohmann::json inputs = nlohmann::json::object();   // {"mesh": "xxh128:..", "env": ..}
    nlohmann::json convention = nlohmann::json::object();
};

// The mesh of object `object` (0: bundle.mesh, k: objects[k-1]). Throws prt::Error (kExitFailure) when absent.
const TriMesh& objectMesh(const Bundle& bundle, uint32_t object);

// The version prt writes; readBundle reads this one and every earlier one (docs/bundle.md, "Versioning").
inline constexpr int kBundleVersion = 3;
inline constexpr int kOldestBundleVersion = 1;
inline constexpr const char* kBundleExtension = "PRT_bundle";

// Writes `bundle` as a .glb atomically. Each object is a standard glTF mesh (POSITION, NORMAL, TEXCOORD_0,
// COLOR_0 when present) with its node; layers go into buffer views referenced only from the PRT_bundle extension,
// with a checksum of the binary chunk so readers detect truncation and tampering.
// Needs: meshes with at least one triangle and per-vertex arrays of matching sizes; unique non-empty object names;
// layers with unique non-empty names, a known componentType whose value array (data or integers) holds the product
// of shape elements (or nothing when that product is 0 or params.uri names an external file), integer values that
// fit their type, an existing object, and vertex-domain layers with that object's vertex count of rows; instances
// of existing objects with finite translations. `version` may be 1 for readers that predate version 2: then the
// bundle must use nothing of version 2 (objects, instances, non-float32 layers). JSON (producer, inputs,
// convention, params) is stored as glTF stores it: null members and empty arrays or objects are left out,
// integers beyond 32 bits become doubles; NaN, infinities and integers beyond 2^53 are refused. Throws prt::Error
// (kExitFailure) when these needs are not met and prt::Error (kExitOutput) when the file cannot be written;
// either way `path` is untouched.
void writeBundle(const std::string& path, const Bundle& bundle, int version = kBundleVersion);

// The "convention" record stages write into their bundles: the choices of docs/conventions.md, by name.
nlohmann::json conventionRecord();

// Reads a .glb or .gltf. Throws prt::Error naming the file and the problem for: a missing file, a truncated or
// malformed glTF, a PRT_bundle of an unsupported version, a checksum mismatch. A plain glTF without the extension
// reads as a bundle with no layers. Version 1 and 2 bundles read alike (version 1 has one object and float32
// layers only); a version 2 bundle's objects are read from their own glTF meshes, untransformed.
// The mesh merges every TRIANGLES primitive reachable from the default scene (or every mesh when the file has no
// scene), with node transforms applied (winding kept counter-clockwise under mirroring transforms). NORMAL and
// TEXCOORD_0 are kept when every primitive has them. Albedo is COLOR_0 times the material's baseColorFactor, or
// the factor alone, and stays empty when it would be 1 everywhere. Indices are not range-checked here (lib/mesh
// validation reports them); an index outside its own primitive reads as 0xFFFFFFFF so merging cannot hide it.
// Every accessor is bounds-checked against its buffer, so a malformed file cannot cause an out-of-bounds read.
Bundle readBundle(const std::string& path);

// Whether `name` (a plain file name) is one a bake names its external textures by for the bundle BUNDLE_STEM.glb:
// BUNDLE_STEM.KIND.<16 lower-case hex digits of the content hash>.EXT, with KIND transfer, bounce, surface or normal
// (transfer.T000 and bounce.T000, any three digits, for u8 planes) and EXT exr, png or json (docs/bundle.md,
// "Texel layers"). The files a writer may remove when it replaces that bundle: never any other file beside it.
bool isBakeTextureName(const std::string& name, const std::string& bundleStem);

// ---- scene assets (version 3; asset.h) --------------------------------------------------------------------------

// A scene bundle (no layers) of a glTF model built in memory, e.g. from another format (lib/mesh reads OBJ with
// MTL this way): read and checked exactly as readBundle reads a glTF file named `file`.
Bundle sceneFromModel(tinygltf::Model model, const std::string& file);

// The object-space vertices and triangles of a primitive of a scene's asset.
struct PrimitiveTriangles {
    int mesh = -1, primitive = -1;
    TriMesh triangles; // accessor order; normals, when filled by the caller, one per vertex
};

// Every primitive the scene's receivers use whose NORMAL is absent or holds a zero vector (then kept in normals),
// each once however many nodes place it. Needs bundle.asset. Throws as readBundle for malformed accessors.
std::vector<PrimitiveTriangles> primitivesWithoutNormals(const Bundle& bundle, const std::string& file);

// The scene with a NORMAL accessor (float VEC3) added to each listed primitive, holding its triangles' normals
// (object space, one per vertex), and re-flattened, so that bundle.mesh carries them in world space. Everything
// else of the asset and of `bundle` is kept. Needs bundle.asset and normals sized to each primitive's vertices.
Bundle withPrimitiveNormals(const Bundle& bundle, const std::vector<PrimitiveTriangles>& normals, const std::string& file);

// IEEE 754 binary16 conversions, as float16 layers store values: round to nearest even, overflow to infinity
// (writeBundle refuses non-finite values), subnormals kept. Exact for every half value both ways.
uint16_t floatToHalf(float value);
float halfToFloat(uint16_t half);

// Finds a layer by name; nullptr if absent.
const Layer* findLayer(const Bundle& bundle, const std::string& name);

// Layer names are unique within a bundle, so a bundle holding one kind of layer for several objects names object
// k's copy BASE.k, and object 0's BASE (docs/bundle.md "Objects"). objectLayerName gives that name;
// findObjectLayer finds the layer of `object` named BASE or BASE.k, or returns nullptr.
std::string objectLayerName(const std::string& base, uint32_t object);
const Layer* findObjectLayer(const Bundle& bundle, const std::string& base, uint32_t object);

// The order of shard bundles of one `--shard I/N` run, given their sharded layers (null where a bundle has none):
// result[I] is the position of shard I. Needs every layer's params.shard = [I, N] with N the number of layers and
// each I once. Throws prt::Error(files[s], "", problem, kExitInput) naming the first bundle that is no shard, of
// another N, out of range or given twice.
std::vector<size_t> orderShards(const std::vector<const Layer*>& layers, const std::vector<std::string>& files);

// Marks `layer` (rows [rowBegin, rowEnd) of a per-vertex layer, shape[0] already rowEnd - rowBegin) as shard
// `index` of `count`: domain "vertex_range" and params shard [I, N], row_begin, row_end, vertex_count, the
// bookkeeping mergeShards (lib/pipeline) removes again. With count <= 1 it only sets domain "vertex".
void markVertexShard(Layer& layer, uint64_t rowBegin, uint64_t rowEnd, uint64_t vertexCount, int index, int count);

} // namespace prt
