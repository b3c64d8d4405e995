// Texcoord sets other than TEXCOORD_0, which readBundle does not keep: the same merged mesh with another set.
#include "bake.h"

#include "bundle_internal.h"
#include "core.h"

#include <cstring>

namespace prt {

namespace {

bool skipImage(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
    return true;
}

} // namespace

std::vector<float> readTexcoordSet(const std::string& path, int set) {
    if (set < 0) throw Error("", "--uv-set", "must be >= 0", kExitUsage);
    std::string bytes = readFileBytes(path);
    size_t slash = path.find_last_of('/');
    std::string folder = slash == std::string::npos ? "." : path.substr(0, slash);
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skipImage, nullptr);
    tinygltf::Model model;
    std::string error, warning;
    bool binary = bytes.compare(0, 4, "glTF") == 0;
    bool loaded = binary ? loader.LoadBinaryFromMemory(&model, &error, &warning,
                                                       reinterpret_cast<const unsigned char*>(bytes.data()),
                                                       unsigned(bytes.size()), folder)
                         : loader.LoadASCIIFromString(&model, &error, &warning, bytes.data(), unsigned(bytes.size()),
                                                      folder);
    if (!loaded) throw Error(path, "glTF", error.empty() ? "not a glTF file" : error);
    // readGltfMesh keeps TEXCOORD_0: hand it the requested set under that name, so vertex order and merging are
    // exactly readBundle's.
    const std::string name = "TEXCOORD_" + std::to_string(set);
    for (size_t m = 0; m < model.meshes.size(); ++m)
        for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
            tinygltf::Primitive& primitive = model.meshes[m].primitives[p];
            if (primitive.mode != TINYGLTF_MODE_TRIANGLES && primitive.mode != -1) continue;
            auto found = primitive.attributes.find(name);
            if (found == primitive.attributes.end())
                throw Error(path, "meshes[" + std::to_string(m) + "].primitives[" + std::to_string(p) + "]",
                            "has no " + name + " (--uv-set " + std::to_string(set) + ")");
            primitive.attributes["TEXCOORD_0"] = found->second;
        }
    std::vector<float> texcoords = detail::readGltfMesh(model, path).texcoords;
    if (texcoords.empty()) throw Error(path, "", "has no " + name);
    return texcoords;
}

} // namespace prt
