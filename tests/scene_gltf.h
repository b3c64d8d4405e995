// Hand-made glTF 2.0 scenes for tests: meshes from TriMeshes, a node tree, materials, textures and PNG images,
// written as one .gltf with an embedded data-URI buffer. Also a minimal PNG encoder (stored deflate), so tests can
// make textures, and hostile headers, without an image library.
#pragma once

#include "bundle.h"
#include "gltf_data_uri.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace prt::test {

struct TestPrimitive {
    // A constructor rather than aggregate initialisation, so that {mesh, material} leaves the rest empty without
    // -Wmissing-field-initializers.
    TestPrimitive(TriMesh mesh_ = {}, int material_ = -1, std::vector<float> uv1_ = {}, std::vector<float> colors_ = {})
        : mesh(std::move(mesh_)), material(material_), uv1(std::move(uv1_)), colors(std::move(colors_)) {}
    TriMesh mesh;              // POSITION, NORMAL, TEXCOORD_0 (mesh.texcoords) as present; indices
    int material = -1;
    std::vector<float> uv1;    // TEXCOORD_1 per vertex, or empty
    std::vector<float> colors; // COLOR_0 RGBA per vertex, or empty
};

struct TestScene {
    std::vector<std::vector<TestPrimitive>> meshes;
    nlohmann::json nodes = nlohmann::json::array(); // glTF node objects
    nlohmann::json roots = nlohmann::json::array(); // the scene's root nodes
    nlohmann::json materials = nlohmann::json::array();
    nlohmann::json textures = nlohmann::json::array();
    nlohmann::json samplers = nlohmann::json::array();
    nlohmann::json images = nlohmann::json::array();
    nlohmann::json top = nlohmann::json::object(); // merged into the top level (extensionsUsed, cameras, extras, ...)
};

// The scene's glTF JSON, its buffer embedded as a data URI.
inline nlohmann::json sceneJson(const TestScene& scene) {
    using nlohmann::json;
    std::string buffer;
    json views = json::array(), accessors = json::array(), meshes = json::array();
    auto addAccessor = [&](const void* data, size_t bytes, int componentType, const char* type, size_t count,
                           const std::vector<float>* minMaxOf) {
        while (buffer.size() % 4) buffer.push_back('\0');
        views.push_back({{"buffer", 0}, {"byteOffset", buffer.size()}, {"byteLength", bytes}});
        buffer.append(static_cast<const char*>(data), bytes);
        json accessor = {{"bufferView", views.size() - 1}, {"componentType", componentType}, {"type", type}, {"count", count}};
        if (minMaxOf) {
            std::vector<float> lo(3, 1e30f), hi(3, -1e30f);
            for (size_t i = 0; i < minMaxOf->size(); ++i) {
                lo[i % 3] = std::min(lo[i % 3], (*minMaxOf)[i]);
                hi[i % 3] = std::max(hi[i % 3], (*minMaxOf)[i]);
            }
            accessor["min"] = lo;
            accessor["max"] = hi;
        }
        accessors.push_back(accessor);
        return accessors.size() - 1;
    };
    for (const std::vector<TestPrimitive>& primitives : scene.meshes) {
        json mesh = {{"primitives", json::array()}};
        for (const TestPrimitive& p : primitives) {
            const TriMesh& m = p.mesh;
            json attributes;
            attributes["POSITION"] = addAccessor(m.positions.data(), m.positions.size() * 4, 5126, "VEC3", m.vertexCount(), &m.positions);
            if (!m.normals.empty()) attributes["NORMAL"] = addAccessor(m.normals.data(), m.normals.size() * 4, 5126, "VEC3", m.vertexCount(), nullptr);
            if (!m.texcoords.empty())
                attributes["TEXCOORD_0"] = addAccessor(m.texcoords.data(), m.texcoords.size() * 4, 5126, "VEC2", m.vertexCount(), nullptr);
            if (!p.uv1.empty()) attributes["TEXCOORD_1"] = addAccessor(p.uv1.data(), p.uv1.size() * 4, 5126, "VEC2", m.vertexCount(), nullptr);
            if (!p.colors.empty()) attributes["COLOR_0"] = addAccessor(p.colors.data(), p.colors.size() * 4, 5126, "VEC4", m.vertexCount(), nullptr);
            json primitive = {{"attributes", attributes},
                              {"indices", addAccessor(m.indices.data(), m.indices.size() * 4, 5125, "SCALAR", m.indices.size(), nullptr)}};
            if (p.material >= 0) primitive["material"] = p.material;
            mesh["primitives"].push_back(primitive);
        }
        meshes.push_back(mesh);
    }
    json gltf = {{"asset", {{"version", "2.0"}}},
                 {"scene", 0},
                 {"scenes", json::array({{{"nodes", scene.roots}}})},
                 {"nodes", scene.nodes},
                 {"meshes", meshes},
                 {"accessors", accessors},
                 {"bufferViews", views},
                 {"buffers", json::array({{{"byteLength", buffer.size()}, {"uri", dataUri(buffer)}}})}};
    if (!scene.materials.empty()) gltf["materials"] = scene.materials;
    if (!scene.textures.empty()) gltf["textures"] = scene.textures;
    if (!scene.samplers.empty()) gltf["samplers"] = scene.samplers;
    if (!scene.images.empty()) gltf["images"] = scene.images;
    for (const auto& [key, value] : scene.top.items()) gltf[key] = value;
    return gltf;
}

inline void writeSceneGltf(const std::string& path, const TestScene& scene) {
    std::ofstream(path, std::ios::binary) << sceneJson(scene).dump(1);
}

// ---- PNG ------------------------------------------------------------------------------------------------------

inline uint32_t crc32Bytes(const unsigned char* data, size_t size, uint32_t crc = 0) {
    crc = ~crc;
    for (size_t i = 0; i < size; ++i) {
        crc ^= data[i];
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

inline void appendBigEndian(std::string& out, uint32_t value) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(char((value >> shift) & 0xFF));
}

inline void appendChunk(std::string& out, const char* type, const std::string& data) {
    appendBigEndian(out, uint32_t(data.size()));
    std::string body = std::string(type, 4) + data;
    out += body;
    appendBigEndian(out, crc32Bytes(reinterpret_cast<const unsigned char*>(body.data()), body.size()));
}

// An 8-bit RGBA PNG of `width` x `height` (rgba row-major, row 0 at the top), zlib with stored blocks.
// `claimedWidth` / `claimedHeight` (when non-zero) go into the header instead: a hostile file.
inline std::string pngBytes(int width, int height, const std::vector<uint8_t>& rgba, uint32_t claimedWidth = 0,
                            uint32_t claimedHeight = 0) {
    std::string raw;
    for (int y = 0; y < height; ++y) {
        raw.push_back('\0'); // filter: none
        raw.append(reinterpret_cast<const char*>(&rgba[size_t(y) * width * 4]), size_t(width) * 4);
    }
    std::string zlib = {char(0x78), char(0x01)};
    for (size_t at = 0; at < raw.size() || at == 0; at += 65535) {
        size_t n = std::min<size_t>(65535, raw.size() - at);
        bool last = at + n >= raw.size();
        zlib.push_back(char(last ? 1 : 0));
        zlib.push_back(char(n & 0xFF));
        zlib.push_back(char(n >> 8));
        zlib.push_back(char(~n & 0xFF));
        zlib.push_back(char((~n >> 8) & 0xFF));
        zlib.append(raw, at, n);
        if (last) break;
    }
    uint32_t a = 1, b = 0;
    for (unsigned char c : raw) a = (a + c) % 65521, b = (b + a) % 65521;
    appendBigEndian(zlib, (b << 16) | a);
    std::string png = "\x89PNG\r\n\x1a\n";
    std::string header;
    appendBigEndian(header, claimedWidth ? claimedWidth : uint32_t(width));
    appendBigEndian(header, claimedHeight ? claimedHeight : uint32_t(height));
    header += {char(8), char(6), char(0), char(0), char(0)}; // 8 bits, RGBA
    appendChunk(png, "IHDR", header);
    appendChunk(png, "IDAT", zlib);
    appendChunk(png, "IEND", "");
    return png;
}

inline std::string pngDataUri(const std::string& png) {
    std::string uri = dataUri(png);
    return "data:image/png;base64," + uri.substr(uri.find(',') + 1);
}

} // namespace prt::test
