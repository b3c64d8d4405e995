#include "bundle_internal.h"

#include "core.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>

namespace prt {

using nlohmann::json;

// Raw little-endian floats and indices are copied into the GLB as they lie in memory.
static_assert(std::endian::native == std::endian::little, "GLB buffers are little-endian");

static void checkMesh(const std::string& path, const TriMesh& mesh) {
    auto refuse = [&](const std::string& problem) { throw Error(path, "mesh", problem, kExitFailure); };
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

static void checkLayers(const std::string& path, const Bundle& bundle) {
    std::set<std::string> names;
    for (const Layer& layer : bundle.layers) {
        std::string place = "layer '" + layer.name + "'";
        auto refuse = [&](const std::string& problem) { throw Error(path, place, problem, kExitFailure); };
        if (layer.name.empty()) refuse("layer has no name");
        if (!names.insert(layer.name).second) refuse("duplicate layer name");
        if (layer.domain.empty() || layer.semantic.empty()) refuse("domain and semantic are required");
        if (layer.shape.empty()) refuse("shape is empty");
        if (!layer.params.is_object()) refuse("params is not a JSON object");
        uint64_t count = elementCount(layer);
        bool dataless = count == 0 || hasExternalData(layer);
        if (!(layer.data.size() == count || (dataless && layer.data.empty())))
            refuse("data holds " + std::to_string(layer.data.size()) + " floats, shape needs " + std::to_string(count));
        if (layer.domain == "vertex" && layer.shape[0] != bundle.mesh.vertexCount())
            refuse("vertex layer has " + std::to_string(layer.shape[0]) + " rows for " +
                   std::to_string(bundle.mesh.vertexCount()) + " vertices");
    }
}

// Appends bytes to buffer 0 as a new buffer view; every element prt stores is 4 bytes, so views stay 4-aligned.
static int addView(tinygltf::Model& model, const void* data, size_t byteLength, int target) {
    std::vector<unsigned char>& buffer = model.buffers[0].data;
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.size();
    view.byteLength = byteLength;
    view.target = target;
    const unsigned char* bytes = static_cast<const unsigned char*>(data);
    buffer.insert(buffer.end(), bytes, bytes + byteLength);
    model.bufferViews.push_back(view);
    return int(model.bufferViews.size()) - 1;
}

static int addFloatAttribute(tinygltf::Model& model, const std::vector<float>& values, int width) {
    tinygltf::Accessor accessor;
    accessor.bufferView = addView(model, values.data(), values.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
    accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    accessor.type = width == 2 ? TINYGLTF_TYPE_VEC2 : TINYGLTF_TYPE_VEC3;
    accessor.count = values.size() / width;
    model.accessors.push_back(accessor);
    return int(model.accessors.size()) - 1;
}

static void addMesh(tinygltf::Model& model, const TriMesh& mesh) {
    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.attributes["POSITION"] = addFloatAttribute(model, mesh.positions, 3);
    // glTF requires POSITION bounds.
    tinygltf::Accessor& position = model.accessors.back();
    position.minValues.assign(3, std::numeric_limits<double>::infinity());
    position.maxValues.assign(3, -std::numeric_limits<double>::infinity());
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        position.minValues[i % 3] = std::min(position.minValues[i % 3], double(mesh.positions[i]));
        position.maxValues[i % 3] = std::max(position.maxValues[i % 3], double(mesh.positions[i]));
    }
    if (!mesh.normals.empty()) primitive.attributes["NORMAL"] = addFloatAttribute(model, mesh.normals, 3);
    if (!mesh.texcoords.empty()) primitive.attributes["TEXCOORD_0"] = addFloatAttribute(model, mesh.texcoords, 2);
    if (!mesh.albedo.empty()) primitive.attributes["COLOR_0"] = addFloatAttribute(model, mesh.albedo, 3);

    tinygltf::Accessor indices;
    indices.bufferView = addView(model, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t),
                                 TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    indices.type = TINYGLTF_TYPE_SCALAR;
    indices.count = mesh.indices.size();
    model.accessors.push_back(indices);
    primitive.indices = int(model.accessors.size()) - 1;

    // A white dielectric, so viewers show the albedo (COLOR_0) as a diffuse surface and readers multiply it by 1.
    tinygltf::Material material;
    material.name = "prt_diffuse";
    material.pbrMetallicRoughness.baseColorFactor = {1.0, 1.0, 1.0, 1.0};
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 1.0;
    model.materials.push_back(material);
    primitive.material = 0;

    tinygltf::Mesh gltfMesh;
    gltfMesh.primitives.push_back(primitive);
    model.meshes.push_back(gltfMesh);
    tinygltf::Node node;
    node.mesh = 0;
    model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes.push_back(0);
    model.scenes.push_back(scene);
    model.defaultScene = 0;
}

static json layerRecord(tinygltf::Model& model, const Layer& layer) {
    json record = {{"name", layer.name}, {"domain", layer.domain}, {"semantic", layer.semantic},
                   {"shape", layer.shape}, {"params", layer.params}};
    if (!layer.data.empty()) {
        record["bufferView"] = addView(model, layer.data.data(), layer.data.size() * sizeof(float), 0);
        record["componentType"] = "float32";
    }
    return record;
}

void writeBundle(const std::string& path, const Bundle& bundle) {
    checkMesh(path, bundle.mesh);
    checkLayers(path, bundle);

    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "prt";
    model.buffers.resize(1);
    addMesh(model, bundle.mesh);

    json extension = {{"version", kBundleVersion}, {"producer", bundle.producer}, {"inputs", bundle.inputs},
                      {"convention", bundle.convention}, {"layers", json::array()}};
    for (const Layer& layer : bundle.layers) extension["layers"].push_back(layerRecord(model, layer));
    extension = detail::storableJson(extension, path, kBundleExtension);
    extension["checksum"] = detail::extensionChecksum(model.buffers[0].data, extension);
    model.extensions[kBundleExtension] = detail::toGltfValue(extension);
    model.extensionsUsed.push_back(kBundleExtension);

    // The GLB header stores the file length as a 32-bit integer; 16 MiB are left for the JSON chunk.
    if (model.buffers[0].data.size() > std::numeric_limits<uint32_t>::max() - (uint64_t(1) << 24))
        throw Error(path, "", "bundle exceeds the 4 GiB limit of a glTF binary", kExitOutput);

    writeFileAtomic(path, [&](const std::string& tmpPath) {
        std::ofstream out(tmpPath, std::ios::binary);
        if (!out) throw Error(path, "", std::string("cannot create: ") + std::strerror(errno), kExitOutput);
        tinygltf::TinyGLTF writer;
        bool written = writer.WriteGltfSceneToStream(&model, out, false, true);
        out.close();
        if (!written || !out) throw Error(path, "", "write failed", kExitOutput);
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
