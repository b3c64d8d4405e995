// OBJ with MTL materials as a glTF scene: one mesh with a primitive per material, each material's Kd as base
// colour and its map_Kd as base colour texture, read through tinyobjloader after prt's own OBJ check.
#include "mesh.h"

#include "core.h"
#include "file_check.h"
#include "utf8.h"

#include <tiny_gltf.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <sstream>
#include <tuple>

namespace prt {
namespace {

// A file an OBJ or MTL names, resolved inside the OBJ's folder: backslashes read as separators (Windows
// exporters write `.\\file.jpg`), links resolved, and nothing outside the folder followed (Error naming `file` and
// `place`). Whether the file exists is not checked.
std::filesystem::path resolveInFolder(const std::filesystem::path& folder, std::string name, const std::string& file,
                                      const std::string& place) {
    for (char& c : name)
        if (c == '\\') c = '/';
    const std::string resolved = resolvedInside((folder / name).string(), folder.string());
    if (resolved.empty())
        throw Error(file, place, "'" + name.substr(0, 80) + "' lies outside the OBJ file's folder; prt follows no path out of it");
    return resolved;
}

// resolveInFolder's file, which must exist.
std::filesystem::path insideFolder(const std::filesystem::path& folder, const std::string& name, const std::string& file,
                                   const std::string& place) {
    std::filesystem::path resolved = resolveInFolder(folder, name, file, place);
    std::error_code error;
    if (!std::filesystem::is_regular_file(resolved, error))
        throw Error(file, place, "'" + name.substr(0, 80) + "' is not a file next to the OBJ file");
    return resolved;
}

// The folder an OBJ's MTL and maps lie in: the OBJ's, or, when it is a symbolic link (as `prt run` links inputs into
// a job's folder), its target's.
std::filesystem::path objFolder(const std::string& path) {
    std::error_code error;
    return std::filesystem::weakly_canonical(std::filesystem::absolute(path), error).parent_path();
}

// The first `mtllib NAME` of the OBJ text, or "".
std::string mtllibName(const std::string& text) {
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
        size_t start = line.find_first_not_of(" \t");
        if (start == std::string::npos || line.compare(start, 7, "mtllib ") != 0) continue;
        std::string name = line.substr(start + 7);
        while (!name.empty() && std::isspace(static_cast<unsigned char>(name.back()))) name.pop_back();
        size_t first = name.find_first_not_of(" \t");
        return first == std::string::npos ? "" : name.substr(first);
    }
    return "";
}

int addView(tinygltf::Model& model, const void* data, size_t bytes) {
    std::vector<unsigned char>& buffer = model.buffers[0].data;
    buffer.resize((buffer.size() + 3) / 4 * 4, 0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.size();
    view.byteLength = bytes;
    const unsigned char* begin = static_cast<const unsigned char*>(data);
    buffer.insert(buffer.end(), begin, begin + bytes);
    model.bufferViews.push_back(view);
    return int(model.bufferViews.size()) - 1;
}

int addAccessor(tinygltf::Model& model, const std::vector<float>& values, int type, int width, bool bounds) {
    tinygltf::Accessor accessor;
    accessor.bufferView = addView(model, values.data(), values.size() * sizeof(float));
    accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    accessor.type = type;
    accessor.count = values.size() / size_t(width);
    if (bounds) { // POSITION's, as glTF requires
        accessor.minValues.assign(3, 1e300);
        accessor.maxValues.assign(3, -1e300);
        for (size_t i = 0; i < values.size(); ++i) {
            accessor.minValues[i % 3] = std::min(accessor.minValues[i % 3], double(values[i]));
            accessor.maxValues[i % 3] = std::max(accessor.maxValues[i % 3], double(values[i]));
        }
    }
    model.accessors.push_back(accessor);
    return int(model.accessors.size()) - 1;
}

} // namespace

bool objHasMaterials(const std::string& path) {
    if (fileExtension(path) != "obj") return false;
    std::string text = readFileBytes(path);
    detail::dropUtf8Bom(text);
    const std::string name = mtllibName(text);
    if (name.empty()) return false;
    // A missing MTL (exporters write names that do not match the file, or leave it behind) costs the materials,
    // not the geometry, as in other importers; one outside the folder is refused.
    std::error_code error;
    if (!std::filesystem::is_regular_file(resolveInFolder(objFolder(path), name, path, "mtllib"), error)) {
        logWarn(path + ": mtllib: '" + name.substr(0, 80) + "' is not a file next to the OBJ file: it is read without " +
                "its materials (every face takes the default one)");
        return false;
    }
    return true;
}

Bundle readObjScene(const std::string& path) {
    std::string text = readFileBytes(path);
    detail::dropUtf8Bom(text);
    detail::checkObj(text, path); // counts, numbers and text checked before tinyobjloader sees the bytes
    const std::filesystem::path folder = objFolder(path);
    const std::string mtlName = mtllibName(text);
    const std::filesystem::path mtlPath = insideFolder(folder, mtlName, path, "mtllib");
    if (std::filesystem::file_size(mtlPath) > (uint64_t(64) << 20))
        throw Error(mtlPath.string(), "", "larger than 64 MiB, more than an MTL file prt reads");
    std::string mtlText = readFileBytes(mtlPath.string());
    detail::dropUtf8Bom(mtlText);

    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    tinyobj::ObjReader reader;
    if (!reader.ParseFromString(text, mtlText, config))
        throw Error(path, "", "tinyobjloader cannot read it: " + reader.Error().substr(0, 200));
    const tinyobj::attrib_t& attrib = reader.GetAttrib();
    const std::vector<tinyobj::material_t>& materials = reader.GetMaterials();

    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "prt meshprep (OBJ + MTL)";
    model.buffers.resize(1);
    // Materials: Kd as base colour, map_Kd as its texture; the OBJ's diffuse surfaces are not metallic.
    std::map<std::string, int> imageOf;
    for (size_t m = 0; m < materials.size(); ++m) {
        const tinyobj::material_t& source = materials[m];
        const std::string place = mtlPath.filename().string() + ": newmtl " + source.name.substr(0, 80);
        tinygltf::Material material;
        material.name = utf8FromLatin1(source.name); // glTF names are UTF-8; old MTL files write Latin-1
        material.pbrMetallicRoughness.baseColorFactor = {std::clamp(double(source.diffuse[0]), 0.0, 1.0),
                                                         std::clamp(double(source.diffuse[1]), 0.0, 1.0),
                                                         std::clamp(double(source.diffuse[2]), 0.0, 1.0), 1.0};
        material.pbrMetallicRoughness.metallicFactor = 0.0;
        if (!source.diffuse_texname.empty()) {
            std::filesystem::path texture = insideFolder(folder, source.diffuse_texname, mtlPath.string(), place + ", map_Kd");
            auto found = imageOf.find(texture.string());
            if (found == imageOf.end()) {
                tinygltf::Image image;
                image.name = utf8FromLatin1(texture.filename().string());
                std::string bytes = readFileBytes(texture.string());
                image.image.assign(bytes.begin(), bytes.end());
                image.as_is = true;
                std::string extension = fileExtension(texture.string());
                image.mimeType = extension == "png" ? "image/png" : "image/jpeg";
                model.images.push_back(image);
                tinygltf::Texture gltfTexture;
                gltfTexture.source = int(model.images.size()) - 1;
                model.textures.push_back(gltfTexture);
                found = imageOf.emplace(texture.string(), int(model.textures.size()) - 1).first;
            }
            material.pbrMetallicRoughness.baseColorTexture.index = found->second;
        }
        model.materials.push_back(material);
    }

    // One primitive per material (and one for faces without), its vertices the distinct corners (v, vt, vn).
    struct Corner {
        int v, t, n;
        bool operator<(const Corner& o) const { return std::tie(v, t, n) < std::tie(o.v, o.t, o.n); }
    };
    std::map<int, std::vector<Corner>> cornersOf; // material -> triangle corners
    for (const tinyobj::shape_t& shape : reader.GetShapes())
        for (size_t f = 0; f < shape.mesh.material_ids.size(); ++f) {
            int material = shape.mesh.material_ids[f];
            if (material < -1 || material >= int(materials.size())) material = -1;
            for (int k = 0; k < 3; ++k) {
                const tinyobj::index_t& index = shape.mesh.indices[3 * f + k];
                cornersOf[material].push_back({index.vertex_index, index.texcoord_index, index.normal_index});
            }
        }
    tinygltf::Mesh mesh;
    mesh.name = utf8FromLatin1(std::filesystem::path(path).stem().string());
    for (const auto& [material, corners] : cornersOf) {
        std::map<Corner, uint32_t> vertexOf;
        std::vector<float> positions, normals, texcoords;
        std::vector<uint32_t> indices;
        bool allNormals = true, allTexcoords = true;
        for (const Corner& c : corners) {
            allNormals = allNormals && c.n >= 0 && 3 * size_t(c.n) + 2 < attrib.normals.size();
            allTexcoords = allTexcoords && c.t >= 0 && 2 * size_t(c.t) + 1 < attrib.texcoords.size();
            // A zero or non-finite authored normal (exporters write `vn 0 0 0`) drops the set: meshprep computes it.
            if (allNormals) {
                const float* n = &attrib.normals[3 * size_t(c.n)];
                float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                allNormals = std::isfinite(length) && length > 1e-6f;
            }
        }
        for (const Corner& c : corners) {
            if (c.v < 0 || 3 * size_t(c.v) + 2 >= attrib.vertices.size())
                throw Error(path, "face", "names vertex " + std::to_string(c.v + 1) + ", which the file does not have");
            auto [found, added] = vertexOf.emplace(c, uint32_t(positions.size() / 3));
            if (added) {
                for (int a = 0; a < 3; ++a) positions.push_back(attrib.vertices[3 * size_t(c.v) + a]);
                if (allNormals) {
                    const float* n = &attrib.normals[3 * size_t(c.n)];
                    float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                    for (int a = 0; a < 3; ++a) normals.push_back(n[a] / length); // glTF requires unit normals
                }
                if (allTexcoords) { // OBJ's v runs up, glTF's down
                    texcoords.push_back(attrib.texcoords[2 * size_t(c.t)]);
                    texcoords.push_back(1.0f - attrib.texcoords[2 * size_t(c.t) + 1]);
                }
            }
            indices.push_back(found->second);
        }
        tinygltf::Primitive primitive;
        primitive.mode = TINYGLTF_MODE_TRIANGLES;
        primitive.material = material;
        primitive.attributes["POSITION"] = addAccessor(model, positions, TINYGLTF_TYPE_VEC3, 3, true);
        if (allNormals) primitive.attributes["NORMAL"] = addAccessor(model, normals, TINYGLTF_TYPE_VEC3, 3, false);
        if (allTexcoords) primitive.attributes["TEXCOORD_0"] = addAccessor(model, texcoords, TINYGLTF_TYPE_VEC2, 2, false);
        tinygltf::Accessor accessor;
        accessor.bufferView = addView(model, indices.data(), indices.size() * sizeof(uint32_t));
        accessor.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
        accessor.type = TINYGLTF_TYPE_SCALAR;
        accessor.count = indices.size();
        model.accessors.push_back(accessor);
        primitive.indices = int(model.accessors.size()) - 1;
        mesh.primitives.push_back(primitive);
    }
    if (mesh.primitives.empty()) throw Error(path, "", "empty mesh (no faces)");
    model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.name = mesh.name;
    node.mesh = 0;
    model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    model.scenes.push_back(scene);
    model.defaultScene = 0;
    return sceneFromModel(std::move(model), path);
}

} // namespace prt
