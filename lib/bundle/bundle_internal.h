// Shared by prt_bundle's sources only: the PRT_bundle extension as glTF stores it, and the mesh reader.
#pragma once

#include "bundle.h"
#include "bundle_stream.h"
#include "core.h"
#include "stream_hash.h"

#include <tiny_gltf.h>

#include <string>
#include <vector>

namespace prt::detail {

// `value` in the form that reads back unchanged through tinygltf, whose Value type has no null, no empty array or
// object (it writes them as null) and no integer wider than 32 bits: null members and empty containers are left
// out of objects and wide integers become doubles. Throws Error(file, place + the JSON path) for what has no such
// form: NaN, infinities, integers beyond 2^53, null or empty array elements.
nlohmann::json storableJson(const nlohmann::json& value, const std::string& file, const std::string& place);

// The tinygltf::Value holding `storable` (a result of storableJson) exactly.
tinygltf::Value toGltfValue(const nlohmann::json& storable);

// Appends the canonical text of `value` (docs/bundle.md, "Checksum"): what Python's
// json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=False) writes, so engines in any language
// can reproduce it. nlohmann's dump is not used because its float digits are not always the shortest.
void appendCanonicalJson(const nlohmann::json& value, std::string& out);

// The bundle checksum (docs/bundle.md, "Checksum"): hashBytes over the bytes of buffer 0 followed by the
// canonical text of the extension object with its "checksum" member removed.
// canonicalExtensionText is that text alone, for a checksum computed while the buffer streams (StreamHash).
std::string extensionChecksum(const std::vector<unsigned char>& buffer, const nlohmann::json& extension);
std::string canonicalExtensionText(nlohmann::json extension);

// tinygltf's model of a glTF file's bytes (`path` names it in messages), with the checks readBundle makes before
// tinygltf parses (truncation, JSON nesting); `jsonText` receives the glTF JSON as the bytes hold it.
tinygltf::Model loadModelFromBytes(const std::string& path, const std::string& bytes, std::string& jsonText);
// A .glb's header against the file: version 2, and a declared length that is the file's. Throws Error(path, "glTF
// binary", ...) naming what differs. Every reader of a .glb checks its header here (loadModelFromBytes,
// readBundleHeader).
void checkGlbHeader(const std::string& path, uint32_t version, uint64_t declaredLength, uint64_t fileSize);

// What readBundleHeader streamed of buffer 0, which its model holds only up to the first layer view.
struct StreamedBuffer {
    uint64_t length = 0;              // buffer 0's byteLength
    StreamHash* hash = nullptr;       // fed with all of buffer 0; bundleFromModel adds the extension and checks it
    std::vector<LayerExtent>* extents = nullptr; // receives each layer's view (byteOffset in buffer 0, byteLength)
};

// The bundle of a loaded model (readBundle after loading). With `streamed`, layers keep no values: their views go
// to streamed->extents, and the checksum is the one streamed->hash completes.
Bundle bundleFromModel(tinygltf::Model model, std::string jsonText, const std::string& path, StreamedBuffer* streamed);

// The triangle mesh of a loaded glTF model, as readBundle describes. Throws Error(file, ...) for accessors that
// reach outside their buffers, unsupported accessor kinds, malformed node trees and files without triangles.
TriMesh readGltfMesh(const tinygltf::Model& model, const std::string& file);

// The scene of a loaded glTF model (asset.h): the flattened world-space mesh as readGltfMesh merges it, but with
// the diffuse albedo rule of scenes (base colour times 1 - metallic), and in `scene` its receivers, materials,
// textures, images, texcoord sets and colours. scene.source is left to the caller. Throws as readGltfMesh, and
// Error(file, place) for a material, texture, sampler or image that is malformed, out of range or of an
// unsupported kind, and for a required extension prt cannot honour.
TriMesh readGltfScene(const tinygltf::Model& model, const std::string& file, SceneAsset& scene);

// The asset's materials, textures, samplers and images into `scene` (materials then the default one), checked;
// refuses required extensions prt cannot honour (checkRequiredExtensions).
void readMaterials(const tinygltf::Model& model, const std::string& file, SceneAsset& scene);
// Throws Error(file, PLACE, "expected TYPE (glTF 2.0 schema), got ...") for the first core property of the glTF
// JSON `root` whose JSON type the glTF 2.0 schema does not allow (a name that is not a string, an index that is not an
// integer >= 0, an object that is an array, an extension that is not an object, ...); properties the schema does
// not define, and extras, are not checked. gltf_types.cpp.
void checkGltfTypes(const nlohmann::json& root, const std::string& file);
// Refuses, by name and with advice, the first of `required` (a file's extensionsRequired) that prt cannot honour.
void checkRequiredExtensions(const std::vector<std::string>& required, const std::string& file);
// Refuses an asset.version of glTF 1.0 (which parses far enough to find no glTF 2.0 meshes) by saying what it is.
void requireGltf2(const std::string& version, const std::string& file);

// `model` made self-contained for writing as one .glb: every buffer merged into buffer 0 (each at an 8-byte
// aligned offset, views rebased), every image moved into a buffer view of its encoded bytes (uri cleared), the
// PRT_bundle extension removed. Nothing else changes.
std::shared_ptr<const tinygltf::Model> selfContainedModel(tinygltf::Model model);

// One primitive's vertices (accessor order) and triangles, untransformed (object space).
TriMesh readGltfPrimitive(const tinygltf::Model& model, int meshIndex, int primitiveIndex, const std::string& file);

// The triangles of glTF mesh `meshIndex` alone, untransformed: a version 2 bundle's object. Throws as readGltfMesh.
TriMesh readGltfMeshAt(const tinygltf::Model& model, int meshIndex, const std::string& file);

// Bytes per element of a layer component type ("float32" 4, "float16" 2, "uint8" 1, "uint16" 2, "uint32" 4), 0
// for an unknown name.
size_t componentSize(const std::string& componentType);
bool isFloatComponent(const std::string& componentType);

// `count` stored values of `size` bytes each (1, 2 or 4: uint8, uint16, uint32, little-endian) widened into `out`,
// as Layer::integers holds them. readBundle and readLayerValues decode through it.
void decodeIntegers(const unsigned char* bytes, size_t count, size_t size, uint32_t* out);

} // namespace prt::detail
