#include "bundle_internal.h"

#include "bundle_stream.h"
#include "core.h"
#include "stream_hash.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace prt {

using nlohmann::json;

// Raw little-endian floats and indices are copied into the GLB as they lie in memory.
static_assert(std::endian::native == std::endian::little, "GLB buffers are little-endian");

static void checkMesh(const std::string& path, const std::string& place, const TriMesh& mesh) {
    auto refuse = [&](const std::string& problem) { throw Error(path, place, problem, kExitFailure); };
    size_t vertexCount = mesh.vertexCount();
    if (mesh.positions.size() % 3 != 0) refuse("positions are not xyz triples");
    // POSITION bounds go into the JSON, which has no NaN or infinity.
    for (float p : mesh.positions)
        if (!std::isfinite(p)) refuse("positions are not finite");
    if (mesh.indices.empty() || mesh.indices.size() % 3 != 0) refuse("no triangles, or indices are not triples");
    if (!mesh.normals.empty() && mesh.normals.size() != vertexCount * 3) refuse("normals do not match the vertex count");
    if (!mesh.texcoords.empty() && mesh.texcoords.size() != vertexCount * 2) refuse("texcoords do not match the vertex count");
    if (!mesh.albedo.empty() && mesh.albedo.size() != vertexCount * 3) refuse("albedo does not match the vertex count");
    // An index past the vertices would make the glTF invalid for every viewer.
    for (size_t i = 0; i < mesh.indices.size(); ++i)
        if (mesh.indices[i] >= vertexCount) refuse("index " + std::to_string(i) + " is out of range");
}

// The product of the shape, saturating instead of wrapping so that no absurd shape matches a small data size.
static uint64_t elementCount(const Layer& layer) {
    uint64_t count = 1;
    for (uint64_t extent : layer.shape) {
        if (extent != 0 && count > std::numeric_limits<uint64_t>::max() / extent) return std::numeric_limits<uint64_t>::max();
        count *= extent;
    }
    return count;
}

static bool hasExternalData(const Layer& layer) {
    return layer.params.is_object() && layer.params.contains("uri") && layer.params["uri"].is_string();
}

static std::string objectName(const Bundle& bundle, uint32_t object) {
    if (object == 0) return bundle.meshName.empty() ? "mesh" : bundle.meshName;
    return bundle.objects[object - 1].name;
}

static void checkObjects(const std::string& path, const Bundle& bundle, int version) {
    auto refuse = [&](const std::string& place, const std::string& problem) { throw Error(path, place, problem, kExitFailure); };
    if (version < kOldestBundleVersion || version > kBundleVersion)
        refuse("", "cannot write bundle version " + std::to_string(version) + "; this build writes " +
                       std::to_string(kOldestBundleVersion) + " to " + std::to_string(kBundleVersion));
    if (version == 1 && (!bundle.objects.empty() || !bundle.instances.empty()))
        refuse("", "version 1 holds one mesh: objects and instances need version 2");
    if (bundle.asset) {
        if (version < 3) refuse("", "a scene bundle (a glTF asset with its transfer) needs version 3");
        if (!bundle.objects.empty() || !bundle.instances.empty())
            refuse("", "a scene bundle places its meshes by its own node tree: it takes no objects or instances");
        const SceneAsset& asset = *bundle.asset;
        if (!asset.source || asset.source->buffers.size() != 1 || !asset.source->buffers[0].uri.empty())
            refuse("", "the scene asset is not self-contained (selfContainedModel)");
        uint64_t vertices = 0;
        for (const SceneReceiver& receiver : asset.receivers) vertices += receiver.vertexCount;
        if (vertices != bundle.mesh.vertexCount() || asset.triangleReceiver.size() != bundle.mesh.triangleCount())
            refuse("mesh", "is not the flattened mesh of the scene asset");
    }
    checkMesh(path, "mesh", bundle.mesh);
    std::set<std::string> names = {objectName(bundle, 0)};
    for (size_t k = 0; k < bundle.objects.size(); ++k) {
        std::string place = "objects[" + std::to_string(k + 1) + "]";
        const BundleObject& object = bundle.objects[k];
        if (object.name.empty()) refuse(place, "object has no name");
        if (!names.insert(object.name).second) refuse(place, "duplicate object name '" + object.name + "'");
        if (object.role.empty()) refuse(place, "object has no role");
        checkMesh(path, place, object.mesh);
    }
    for (size_t i = 0; i < bundle.instances.size(); ++i) {
        const Instance& instance = bundle.instances[i];
        std::string place = "instances[" + std::to_string(i) + "]";
        if (instance.object > bundle.objects.size()) refuse(place, "object " + std::to_string(instance.object) + " does not exist");
        for (float t : instance.translation)
            if (!std::isfinite(t)) refuse(place, "translation is not finite");
    }
}

static void checkLayers(const std::string& path, const Bundle& bundle, int version, const std::vector<LayerStream>& streams) {
    if (!streams.empty() && streams.size() != bundle.layers.size())
        throw Error(path, "", std::to_string(streams.size()) + " layer streams for " + std::to_string(bundle.layers.size()) +
                                  " layers", kExitFailure);
    std::set<std::string> names;
    for (size_t index = 0; index < bundle.layers.size(); ++index) {
        const Layer& layer = bundle.layers[index];
        const bool streamed = !streams.empty() && streams[index].write;
        std::string place = "layer '" + layer.name + "'";
        auto refuse = [&](const std::string& problem) { throw Error(path, place, problem, kExitFailure); };
        if (layer.name.empty()) refuse("layer has no name");
        if (!names.insert(layer.name).second) refuse("duplicate layer name");
        if (layer.domain.empty() || layer.semantic.empty()) refuse("domain and semantic are required");
        if (layer.shape.empty()) refuse("shape is empty");
        if (!layer.params.is_object()) refuse("params is not a JSON object");
        size_t size = detail::componentSize(layer.componentType);
        if (size == 0) refuse("unknown componentType '" + layer.componentType + "'");
        if (version == 1 && layer.componentType != "float32") refuse("version 1 stores float32 only");
        if (layer.object > bundle.objects.size()) refuse("object " + std::to_string(layer.object) + " does not exist");
        if (version == 1 && layer.object != 0) refuse("version 1 holds one object");
        bool floats = detail::isFloatComponent(layer.componentType);
        const size_t values = floats ? layer.data.size() : layer.integers.size();
        if (floats ? !layer.integers.empty() : !layer.data.empty())
            refuse(std::string(floats ? "a float layer holds integers" : "an integer layer holds floats"));
        uint64_t count = elementCount(layer);
        bool dataless = count == 0 || hasExternalData(layer);
        if (streamed) { // its values pass through the writer, which checks what needs checking as they go
            if (values != 0) refuse("is streamed but also holds values");
            if (count > std::numeric_limits<uint64_t>::max() / size || streams[index].byteLength != count * size)
                refuse("stream gives " + std::to_string(streams[index].byteLength) + " bytes, shape needs " +
                       std::to_string(count) + " " + layer.componentType);
        } else if (!(values == count || (dataless && values == 0))) {
            refuse("holds " + std::to_string(values) + " values, shape needs " + std::to_string(count));
        }
        if (layer.componentType == "float16")
            for (float value : layer.data)
                if (!std::isfinite(value) || std::fabs(value) > 65504.0f) refuse("a value does not fit float16");
        if (!floats && layer.componentType != "uint32") {
            uint32_t limit = layer.componentType == "uint8" ? 0xffu : 0xffffu;
            for (uint32_t value : layer.integers)
                if (value > limit) refuse("value " + std::to_string(value) + " does not fit " + layer.componentType);
        }
        size_t vertexCount = objectMesh(bundle, layer.object).vertexCount();
        if (layer.domain == "vertex" && layer.shape[0] != vertexCount)
            refuse("vertex layer has " + std::to_string(layer.shape[0]) + " rows for " + std::to_string(vertexCount) +
                   " vertices of object '" + objectName(bundle, layer.object) + "'");
        size_t cornerCount = objectMesh(bundle, layer.object).indices.size();
        if (layer.domain == "corner" && layer.shape[0] != cornerCount)
            refuse("corner layer has " + std::to_string(layer.shape[0]) + " rows for " + std::to_string(cornerCount) +
                   " triangle corners of object '" + objectName(bundle, layer.object) + "'");
    }
}

// Buffer 0 as the writer streams it: each part's bytes in order. A view's part is followed by zeros to the next
// multiple of 4 (so every view starts 4-aligned whatever its element size); a scene's asset bytes, the first part,
// are not.
struct BinaryPart {
    uint64_t byteLength = 0;
    uint64_t padding = 0;
    std::function<void(const ByteSink&)> write;
};
struct Binary {
    std::vector<BinaryPart> parts;
    uint64_t size = 0;
};

// Adds a buffer view over the next byteLength bytes of buffer 0, which `write` gives when the file is written.
static int addView(tinygltf::Model& model, Binary& binary, uint64_t byteLength, std::function<void(const ByteSink&)> write,
                   int target) {
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = binary.size;
    view.byteLength = byteLength;
    view.target = target;
    uint64_t padding = (4 - byteLength % 4) % 4;
    binary.parts.push_back({byteLength, padding, std::move(write)});
    binary.size += byteLength + padding;
    model.bufferViews.push_back(view);
    return int(model.bufferViews.size()) - 1;
}

// A part that passes `size` bytes lying in memory at `data` (which must outlive the write).
static std::function<void(const ByteSink&)> bytesAt(const void* data, uint64_t size) {
    return [data, size](const ByteSink& sink) { sink(data, size); };
}

static int addFloatAttribute(tinygltf::Model& model, Binary& binary, const std::vector<float>& values, int width) {
    tinygltf::Accessor accessor;
    accessor.bufferView = addView(model, binary, values.size() * sizeof(float), bytesAt(values.data(), values.size() * sizeof(float)),
                                  TINYGLTF_TARGET_ARRAY_BUFFER);
    accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    accessor.type = width == 2 ? TINYGLTF_TYPE_VEC2 : TINYGLTF_TYPE_VEC3;
    accessor.count = values.size() / width;
    model.accessors.push_back(accessor);
    return int(model.accessors.size()) - 1;
}

// Adds `mesh` as glTF mesh number model.meshes.size() with material 0, and a node without transform showing it.
static void addMesh(tinygltf::Model& model, Binary& binary, const TriMesh& mesh, const std::string& name) {
    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.attributes["POSITION"] = addFloatAttribute(model, binary, mesh.positions, 3);
    // glTF requires POSITION bounds.
    tinygltf::Accessor& position = model.accessors.back();
    position.minValues.assign(3, std::numeric_limits<double>::infinity());
    position.maxValues.assign(3, -std::numeric_limits<double>::infinity());
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        position.minValues[i % 3] = std::min(position.minValues[i % 3], double(mesh.positions[i]));
        position.maxValues[i % 3] = std::max(position.maxValues[i % 3], double(mesh.positions[i]));
    }
    if (!mesh.normals.empty()) primitive.attributes["NORMAL"] = addFloatAttribute(model, binary, mesh.normals, 3);
    if (!mesh.texcoords.empty()) primitive.attributes["TEXCOORD_0"] = addFloatAttribute(model, binary, mesh.texcoords, 2);
    if (!mesh.albedo.empty()) primitive.attributes["COLOR_0"] = addFloatAttribute(model, binary, mesh.albedo, 3);

    tinygltf::Accessor indices;
    uint64_t indexBytes = mesh.indices.size() * sizeof(uint32_t);
    indices.bufferView = addView(model, binary, indexBytes, bytesAt(mesh.indices.data(), indexBytes),
                                 TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    indices.type = TINYGLTF_TYPE_SCALAR;
    indices.count = mesh.indices.size();
    model.accessors.push_back(indices);
    primitive.indices = int(model.accessors.size()) - 1;
    primitive.material = 0;

    tinygltf::Mesh gltfMesh;
    gltfMesh.name = name;
    gltfMesh.primitives.push_back(primitive);
    model.meshes.push_back(gltfMesh);
    tinygltf::Node node;
    node.name = name;
    node.mesh = int(model.meshes.size()) - 1;
    model.nodes.push_back(node);
}

static void addMaterial(tinygltf::Model& model) {
    // A white dielectric, so viewers show the albedo (COLOR_0) as a diffuse surface and readers multiply it by 1.
    tinygltf::Material material;
    material.name = "prt_diffuse";
    material.pbrMetallicRoughness.baseColorFactor = {1.0, 1.0, 1.0, 1.0};
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 1.0;
    model.materials.push_back(material);
}

// The glTF scene: object k is mesh k and node k. Without instances the scene shows every object once; with
// instances it shows one translated node per instance (nodes N+1..), and the object nodes stay out of it.
static json addScene(tinygltf::Model& model, const Bundle& bundle) {
    tinygltf::Scene scene;
    json instances = json::array();
    size_t objectCount = bundle.objects.size() + 1;
    if (bundle.instances.empty()) {
        for (size_t k = 0; k < objectCount; ++k) scene.nodes.push_back(int(k));
    } else {
        for (const Instance& instance : bundle.instances) {
            tinygltf::Node node;
            node.name = instance.name;
            node.mesh = int(instance.object);
            node.translation = {instance.translation[0], instance.translation[1], instance.translation[2]};
            model.nodes.push_back(node);
            scene.nodes.push_back(int(model.nodes.size()) - 1);
            json record = {{"object", instance.object},
                           {"translation", {instance.translation[0], instance.translation[1], instance.translation[2]}},
                           {"node", model.nodes.size() - 1}};
            if (!instance.name.empty()) record["name"] = instance.name;
            instances.push_back(record);
        }
    }
    model.scenes.push_back(scene);
    model.defaultScene = 0;
    return instances;
}

// An in-memory layer's stored bytes, converted to its component type in pieces of kPiece values.
static std::function<void(const ByteSink&)> layerBytes(const Layer& layer) {
    static constexpr size_t kPiece = 1 << 16;
    const std::string& type = layer.componentType;
    if (type == "float32") return bytesAt(layer.data.data(), layer.data.size() * sizeof(float));
    if (type == "uint32") return bytesAt(layer.integers.data(), layer.integers.size() * sizeof(uint32_t));
    return [&layer, type](const ByteSink& sink) {
        size_t count = type == "float16" ? layer.data.size() : layer.integers.size();
        std::vector<uint16_t> wide(type == "uint8" ? 0 : std::min(count, kPiece));
        std::vector<uint8_t> narrow(type == "uint8" ? std::min(count, kPiece) : 0);
        for (size_t begin = 0; begin < count; begin += kPiece) {
            size_t end = std::min(count, begin + kPiece);
            for (size_t i = begin; i < end; ++i) {
                if (type == "float16") wide[i - begin] = floatToHalf(layer.data[i]);
                else if (type == "uint16") wide[i - begin] = uint16_t(layer.integers[i]);
                else narrow[i - begin] = uint8_t(layer.integers[i]);
            }
            if (type == "uint8") sink(narrow.data(), end - begin);
            else sink(wide.data(), (end - begin) * 2);
        }
    };
}

// The layer's record, with a view over its stored bytes when it has any: `stream` when set, else its values.
static json layerRecord(tinygltf::Model& model, Binary& binary, const Layer& layer, const LayerStream* stream) {
    json record = {{"name", layer.name}, {"domain", layer.domain}, {"semantic", layer.semantic},
                   {"shape", layer.shape}, {"params", layer.params}};
    if (layer.object != 0) record["object"] = layer.object;
    if (stream) {
        if (stream->byteLength == 0) return record;
        record["bufferView"] = addView(model, binary, stream->byteLength, stream->write, 0);
    } else {
        if (layer.data.empty() && layer.integers.empty()) return record;
        uint64_t count = layer.data.empty() ? layer.integers.size() : layer.data.size();
        record["bufferView"] = addView(model, binary, count * detail::componentSize(layer.componentType), layerBytes(layer), 0);
    }
    record["componentType"] = layer.componentType;
    return record;
}

// Bundles of prt's own meshes (versions 1 and 2 layout): object k is mesh k and node k.
static void addPrtMeshes(tinygltf::Model& model, Binary& binary, const Bundle& bundle, int version, json& extension) {
    model.asset.version = "2.0";
    model.asset.generator = "prt";
    model.buffers.resize(1);
    addMaterial(model);
    addMesh(model, binary, bundle.mesh, version == 1 ? "" : objectName(bundle, 0));
    json objects = json::array();
    objects.push_back({{"name", objectName(bundle, 0)}, {"role", bundle.meshRole}, {"mesh", 0}, {"node", 0}});
    for (size_t k = 0; k < bundle.objects.size(); ++k) {
        addMesh(model, binary, bundle.objects[k].mesh, bundle.objects[k].name);
        objects.push_back({{"name", bundle.objects[k].name}, {"role", bundle.objects[k].role}, {"mesh", k + 1}, {"node", k + 1}});
    }
    json instances = addScene(model, bundle);
    if (version >= 2) {
        extension["objects"] = objects;
        extension["instances"] = instances;
    }
}

// The `scene` record of a scene bundle's extension: its receivers in row order (docs/bundle.md "Scene bundles").
static json sceneRecord(const SceneAsset& asset, const TriMesh& mesh) {
    json receivers = json::array();
    for (const SceneReceiver& r : asset.receivers)
        receivers.push_back({{"node", r.node}, {"mesh", r.mesh}, {"primitive", r.primitive}, {"material", r.material},
                             {"first_row", r.firstVertex}, {"rows", r.vertexCount}, {"first_triangle", r.firstTriangle},
                             {"triangles", r.triangleCount}, {"mirrored", r.mirrored}});
    return {{"rows", mesh.vertexCount()},
            {"triangles", mesh.triangleCount()},
            {"row_order", "receivers in node order (default scene, depth first, children in order), then primitive "
                          "order; each receiver's vertices in accessor order"},
            {"receivers", receivers}};
}

// The JSON of a scene bundle: what tinygltf wrote for what prt changes (the one buffer, the buffer views, the
// accessors and NORMAL attributes meshprep added, images moved into views, the PRT_bundle extension) and the
// asset's own JSON for everything else, object for object, so that nothing tinygltf normalises on the way
// (defaults it writes out, zfar 0 for an infinite camera, ...) changes the asset.
static json sceneJson(const json& written, const std::string& sourceJson) {
    json out = json::parse(sourceJson);
    const json kNone = json::array();
    for (const char* key : {"buffers", "bufferViews"}) out[key] = written.value(key, kNone);
    json accessors = written.value("accessors", kNone);
    for (size_t i = 0; i < accessors.size() && i < out.value("accessors", kNone).size(); ++i)
        accessors[i] = out["accessors"][i];
    out["accessors"] = accessors;
    if (out.contains("images"))
        for (size_t i = 0; i < out["images"].size(); ++i) {
            json& image = out["images"][i];
            image.erase("uri");
            image["bufferView"] = written["images"][i]["bufferView"];
            image["mimeType"] = written["images"][i]["mimeType"];
        }
    if (out.contains("meshes"))
        for (size_t m = 0; m < out["meshes"].size(); ++m)
            for (size_t p = 0; p < out["meshes"][m]["primitives"].size(); ++p)
                out["meshes"][m]["primitives"][p]["attributes"] = written["meshes"][m]["primitives"][p]["attributes"];
    json used = json::array();
    for (const json& name : out.value("extensionsUsed", kNone))
        if (name != kBundleExtension) used.push_back(name);
    used.push_back(kBundleExtension);
    out["extensionsUsed"] = used;
    if (out.contains("extensionsRequired")) {
        json required = json::array();
        for (const json& name : out["extensionsRequired"])
            if (name != kBundleExtension) required.push_back(name);
        out["extensionsRequired"] = required;
        if (required.empty()) out.erase("extensionsRequired");
    }
    if (!out.contains("extensions") || !out["extensions"].is_object()) out["extensions"] = json::object();
    out["extensions"][kBundleExtension] = written["extensions"][kBundleExtension];
    return out;
}

// The JSON tinygltf writes for `model` (whose buffer 0 holds no bytes: they are streamed), with buffer 0's
// byteLength set to `bufferLength`; for a scene, merged into its asset's own JSON (sceneJson).
static std::string glbJson(const tinygltf::Model& model, const Bundle& bundle, uint64_t bufferLength, const std::string& path) {
    tinygltf::TinyGLTF writer;
    std::ostringstream glb;
    if (!writer.WriteGltfSceneToStream(&model, glb, false, true)) throw Error(path, "", "write failed", kExitOutput);
    std::string bytes = glb.str();
    uint32_t jsonLength = 0;
    if (bytes.size() >= 20) std::memcpy(&jsonLength, bytes.data() + 12, 4);
    if (bytes.size() < 20 + uint64_t(jsonLength)) throw Error(path, "", "tinygltf wrote no JSON chunk", kExitFailure);
    json written = json::parse(bytes.substr(20, jsonLength));
    written["buffers"][0]["byteLength"] = bufferLength;
    if (bundle.asset && !bundle.asset->sourceJson.empty()) return sceneJson(written, bundle.asset->sourceJson).dump();
    return written.dump();
}

// Writes the .glb of `text` (the JSON, holding `placeholder` once as its checksum) and buffer 0 as `binary`'s parts
// give it, as glTF 2.0 lays a .glb out, to `file`; then writes over the placeholder the checksum of the buffer
// followed by `canonical` (the extension's canonical text, docs/bundle.md "Checksum"). Streamed float16 layers
// (float16Parts) are checked finite as they pass.
static void writeGlbStreamed(std::FILE* file, const std::string& path, std::string text, const std::string& placeholder,
                             const Binary& binary, const std::vector<bool>& float16Parts, const std::string& canonical,
                             bool binaryChunk) {
    auto put = [&](const void* bytes, size_t size) {
        if (size > 0 && std::fwrite(bytes, 1, size, file) != size)
            throw Error(path, "", std::string("write failed: ") + std::strerror(errno), kExitOutput);
    };
    const std::string member = "\"checksum\":\"";
    size_t at = text.find(placeholder);
    if (at == std::string::npos || at < member.size() || text.compare(at - member.size(), member.size(), member) != 0 ||
        text.find(placeholder, at + 1) != std::string::npos)
        throw Error(path, "", "the checksum's place in the JSON is not unique", kExitFailure);
    const uint64_t checksumOffset = 20 + at;
    text.resize((text.size() + 3) / 4 * 4, ' ');
    const uint64_t binaryLength = (binary.size + 3) / 4 * 4;
    const uint32_t header[3] = {0x46546C67u, 2u, uint32_t(12 + 8 + text.size() + (binaryChunk ? 8 + binaryLength : 0))};
    const uint32_t jsonChunk[2] = {uint32_t(text.size()), 0x4E4F534Au};
    const uint32_t binaryHeader[2] = {uint32_t(binaryLength), 0x004E4942u};
    put(header, sizeof header);
    put(jsonChunk, sizeof jsonChunk);
    put(text.data(), text.size());
    if (binaryChunk) put(binaryHeader, sizeof binaryHeader);

    StreamHash hash; // over buffer 0, then the canonical extension text
    const unsigned char zeros[4] = {0, 0, 0, 0};
    for (size_t p = 0; p < binary.parts.size(); ++p) {
        const BinaryPart& part = binary.parts[p];
        uint64_t given = 0;
        bool half = float16Parts[p];
        unsigned char carry = 0; // a float16 value split between two pieces: its first byte
        part.write([&](const void* bytes, size_t size) {
            if (half) {
                const unsigned char* b = static_cast<const unsigned char*>(bytes);
                for (size_t i = 0; i < size; ++i) {
                    if ((given + i) % 2 == 0) { carry = b[i]; continue; }
                    uint16_t value = uint16_t(carry | (b[i] << 8));
                    if ((value & 0x7C00u) == 0x7C00u)
                        throw Error(path, "", "a streamed float16 value is not finite", kExitFailure);
                }
            }
            given += size;
            if (given > part.byteLength)
                throw Error(path, "", "a layer stream gives more than its " + std::to_string(part.byteLength) + " bytes", kExitFailure);
            put(bytes, size);
            hash.add(bytes, size);
        });
        if (given != part.byteLength)
            throw Error(path, "", "a layer stream gave " + std::to_string(given) + " of its " +
                                      std::to_string(part.byteLength) + " bytes", kExitFailure);
        put(zeros, part.padding);
        hash.add(zeros, part.padding);
    }
    if (binaryChunk) put(zeros, binaryLength - binary.size);
    hash.add(canonical.data(), canonical.size());
    std::string checksum = hash.digest();
    if (checksum.size() != placeholder.size()) throw Error(path, "", "checksum length changed", kExitFailure);
    if (std::fseek(file, long(checksumOffset), SEEK_SET) != 0)
        throw Error(path, "", std::string("seek failed: ") + std::strerror(errno), kExitOutput);
    put(checksum.data(), checksum.size());
}

void writeBundle(const std::string& path, const Bundle& bundle, int version) { writeBundleStreamed(path, bundle, {}, version); }

void writeBundleStreamed(const std::string& path, const Bundle& bundle, const std::vector<LayerStream>& streams, int version) {
    checkObjects(path, bundle, version);
    checkLayers(path, bundle, version, streams);

    tinygltf::Model model;
    Binary binary;
    json extension = {{"version", version}, {"producer", bundle.producer}, {"inputs", bundle.inputs},
                      {"convention", bundle.convention}, {"layers", json::array()}};
    if (bundle.asset) {
        // The asset as it came, with the layers appended to its buffer (its bytes streamed from the asset itself).
        model = *bundle.asset->source;
        const std::vector<unsigned char>& assetBytes = bundle.asset->source->buffers[0].data;
        model.buffers[0].data = {};
        binary.parts.push_back({assetBytes.size(), 0, bytesAt(assetBytes.data(), assetBytes.size())});
        binary.size = assetBytes.size();
        extension["scene"] = sceneRecord(*bundle.asset, bundle.mesh);
    } else {
        addPrtMeshes(model, binary, bundle, version, extension);
    }
    size_t meshParts = binary.parts.size();
    for (size_t i = 0; i < bundle.layers.size(); ++i) {
        const LayerStream* stream = !streams.empty() && streams[i].write ? &streams[i] : nullptr;
        extension["layers"].push_back(layerRecord(model, binary, bundle.layers[i], stream));
    }
    std::vector<bool> float16Parts(binary.parts.size(), false); // streamed float16 layers, checked as they pass
    for (size_t i = 0, part = meshParts; i < bundle.layers.size(); ++i) {
        if (!extension["layers"][i].contains("bufferView")) continue;
        float16Parts[part++] = !streams.empty() && streams[i].write && bundle.layers[i].componentType == "float16";
    }
    extension = detail::storableJson(extension, path, kBundleExtension);
    const std::string canonical = detail::canonicalExtensionText(extension);
    const std::string placeholder = "xxh128:" + std::string(32, '?'); // a checksum's length; never a hash
    extension["checksum"] = placeholder;
    model.extensions[kBundleExtension] = detail::toGltfValue(extension);
    model.extensionsUsed.push_back(kBundleExtension);

    // The GLB header stores the file length as a 32-bit integer; 16 MiB are left for the JSON chunk.
    if (binary.size > std::numeric_limits<uint32_t>::max() - (uint64_t(1) << 24))
        throw Error(path, "", "bundle exceeds the 4 GiB limit of a glTF binary", kExitOutput);
    std::string text = glbJson(model, bundle, binary.size, path);
    model = {};

    writeFileAtomic(path, [&](const std::string& tmpPath) {
        std::vector<char> buffer(1 << 20); // outlives the file, which may be closed by the unique_ptr on a throw
        std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(tmpPath.c_str(), "wb"), std::fclose);
        if (!file) throw Error(path, "", std::string("cannot create: ") + std::strerror(errno), kExitOutput);
        std::setvbuf(file.get(), buffer.data(), _IOFBF, buffer.size());
        writeGlbStreamed(file.get(), path, text, placeholder, binary, float16Parts, canonical,
                         bundle.asset || binary.size > 0);
        if (std::fflush(file.get()) != 0 || std::fclose(file.release()) != 0)
            throw Error(path, "", std::string("write failed: ") + std::strerror(errno), kExitOutput);
    });
}

json conventionRecord() {
    return {{"reference", "docs/conventions.md"},
            {"up", "+Y"},
            {"handedness", "right"},
            {"frontFace", "counter-clockwise"},
            {"sh", {{"basis", "real orthonormal"}, {"condonShortleyPhase", false}, {"index", "l*l+l+m"}}},
            {"rgbLayout", "[coefficient][3]"},
            {"transfer", "radiance_out = sum_j transfer[v][j][c] * lighting[j][c], albedo and 1/pi folded in"}};
}

} // namespace prt
