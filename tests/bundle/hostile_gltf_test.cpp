// Crafted glTF files: node DAGs, cycles, deep trees, URIs that leave the file's folder, strips and fans,
// glTF 1.0 and claimed sizes over the element cap. Each test failed (or hung) before its fix.
#include "bundle.h"
#include "bundle_stream.h"

#include "core.h"
#include "gltf_data_uri.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

fs::path scratch(const std::string& name) {
    fs::path dir = fs::temp_directory_path() / ("prt_hostile_gltf_" + std::to_string(getpid()));
    fs::create_directories(dir / "sub");
    return dir / name;
}

// Four vertices of a unit square in z = 0 (0,0) (1,0) (1,1) (0,1), then six uint16 indices 0 1 2 0 2 3.
std::string squareBytes() {
    const float positions[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
    std::string bytes(reinterpret_cast<const char*>(positions), sizeof positions);
    bytes.append(reinterpret_cast<const char*>(indices), sizeof indices);
    return bytes;
}

// A glTF with the square's buffer (embedded unless `uri` is given), one mesh whose primitive has `mode` and, when
// `indexed`, the index accessor; nodes and scenes are left to the caller.
json squareGltf(int mode = 4, bool indexed = true, const std::string& uri = "") {
    std::string bytes = squareBytes();
    json gltf = {{"asset", {{"version", "2.0"}}},
                 {"buffers", {{{"byteLength", bytes.size()},
                               {"uri", uri.empty() ? prt::test::dataUri(bytes) : uri}}}},
                 {"bufferViews", {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
                                  {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 12}}}},
                 {"accessors", {{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"},
                                 {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
                                {{"bufferView", 1}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}}};
    json primitive = {{"attributes", {{"POSITION", 0}}}, {"mode", mode}};
    if (indexed) primitive["indices"] = 1;
    gltf["meshes"] = {{{"primitives", {primitive}}}};
    return gltf;
}

std::string writeGltf(const json& gltf, const std::string& name) {
    std::string path = scratch(name).string();
    std::ofstream(path) << gltf.dump();
    return path;
}

std::string refusal(const std::string& path) {
    try {
        prt::readBundle(path);
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.exitCode(), prt::kExitInput);
        return e.what();
    }
    return "";
}

struct ScopedEnv {
    ScopedEnv(const char* name, const char* value) : name(name) { setenv(name, value, 1); }
    ~ScopedEnv() { unsetenv(name); }
    const char* name;
};

} // namespace

// 40 nodes each listing the next twice expand to 2^40 paths; the single-parent rule refuses the file at once.
TEST(HostileGltf, NodeDagIsRefusedBeforeItExpands) {
    json gltf = squareGltf();
    const int depth = 40;
    for (int n = 0; n < depth; ++n) gltf["nodes"].push_back({{"children", {n + 1, n + 1}}});
    gltf["nodes"].push_back({{"mesh", 0}});
    gltf["scenes"] = {{{"nodes", {0}}}};
    std::string message = refusal(writeGltf(gltf, "dag.gltf"));
    EXPECT_NE(message.find("already has parent"), std::string::npos) << message;
}

TEST(HostileGltf, NodeWithTwoParentsIsRefused) {
    json gltf = squareGltf();
    gltf["nodes"] = {{{"children", {2}}}, {{"children", {2}}}, {{"mesh", 0}}};
    gltf["scenes"] = {{{"nodes", {0, 1}}}};
    std::string message = refusal(writeGltf(gltf, "two_parents.gltf"));
    EXPECT_NE(message.find("nodes[1].children: node 2 already has parent 0"), std::string::npos) << message;
}

TEST(HostileGltf, CyclesAndRepeatedRootsAreRefused) {
    json gltf = squareGltf();
    gltf["nodes"] = {{{"children", {1}}, {"mesh", 0}}, {{"children", {0}}}};
    gltf["scenes"] = {{{"nodes", {0}}}};
    EXPECT_NE(refusal(writeGltf(gltf, "cycle.gltf")).find("is a root but has parent 1"), std::string::npos);

    gltf["nodes"] = {{{"mesh", 0}}, {{"children", {2}}}, {{"children", {1}}}}; // a cycle no root reaches
    EXPECT_NE(refusal(writeGltf(gltf, "unreached_cycle.gltf")).find("is its own ancestor"), std::string::npos);

    gltf["nodes"] = {{{"mesh", 0}}};
    gltf["scenes"] = {{{"nodes", {0, 0}}}};
    EXPECT_NE(refusal(writeGltf(gltf, "repeated_root.gltf")).find("is reached twice"), std::string::npos);
}

// A chain deeper than any call stack: the traversal is iterative, so it reads (and composes every translation).
TEST(HostileGltf, DeepNodeChainReadsWithoutRecursion) {
    json gltf = squareGltf();
    const int depth = 100000;
    json nodes = json::array();
    for (int n = 0; n < depth; ++n) nodes.push_back({{"children", {n + 1}}, {"translation", {0.0, 0.0, 1.0}}});
    nodes.push_back({{"mesh", 0}});
    gltf["nodes"] = nodes;
    gltf["scenes"] = {{{"nodes", {0}}}};
    prt::Bundle bundle = prt::readBundle(writeGltf(gltf, "deep.gltf"));
    ASSERT_EQ(bundle.mesh.vertexCount(), 4u);
    EXPECT_FLOAT_EQ(bundle.mesh.positions[2], float(depth));
}

TEST(HostileGltf, RelativeUriLeavingTheFolderIsRefused) {
    std::string bytes = squareBytes();
    std::ofstream(scratch("secret.bin"), std::ios::binary) << bytes;
    std::ofstream(scratch("sub/inside.bin"), std::ios::binary) << bytes;
    json gltf = squareGltf(4, true, "../secret.bin");
    std::string message = refusal(writeGltf(gltf, "sub/escape.gltf"));
    EXPECT_NE(message.find("outside the file's folder"), std::string::npos) << message;

    gltf["buffers"][0]["uri"] = "%2E%2E/secret.bin"; // percent-encoded: decoded by tinygltf, then checked
    message = refusal(writeGltf(gltf, "sub/escape_encoded.gltf"));
    EXPECT_NE(message.find("outside the file's folder"), std::string::npos) << message;

    gltf["buffers"][0]["uri"] = scratch("secret.bin").string(); // absolute
    message = refusal(writeGltf(gltf, "sub/absolute.gltf"));
    EXPECT_FALSE(message.empty());

    fs::remove(scratch("sub/link.bin"));
    fs::create_symlink(scratch("secret.bin"), scratch("sub/link.bin")); // a link inside pointing outside
    gltf["buffers"][0]["uri"] = "link.bin";
    message = refusal(writeGltf(gltf, "sub/link.gltf"));
    EXPECT_NE(message.find("outside the file's folder"), std::string::npos) << message;

    gltf["buffers"][0]["uri"] = "inside.bin"; // inside the folder: read
    EXPECT_EQ(prt::readBundle(writeGltf(gltf, "sub/inside.gltf")).mesh.triangleCount(), 2u);
}

// Strips and fans, indexed or not, become triangle lists that keep the first triangle's winding.
TEST(HostileGltf, TriangleStripsAndFansAreRead) {
    // Strip 0 1 3 2 over the square: triangles (0,1,3), (1,2,3) by the glTF rule, both facing +z.
    json strip = squareGltf(5, true);
    strip["accessors"][1]["count"] = 4;
    std::string bytes = squareBytes();
    const uint16_t stripCorners[6] = {0, 1, 3, 2, 0, 0}; // 4 used; the last two pad the view
    std::memcpy(bytes.data() + 48, stripCorners, sizeof stripCorners);
    strip["buffers"][0]["uri"] = prt::test::dataUri(bytes);
    prt::TriMesh mesh = prt::readBundle(writeGltf(strip, "strip.gltf")).mesh;
    ASSERT_EQ(mesh.triangleCount(), 2u);
    EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 3, 1, 2, 3}));

    json fan = squareGltf(6, false); // 0 1 2 3 unindexed: triangles (1,2,0), (2,3,0)
    mesh = prt::readBundle(writeGltf(fan, "fan.gltf")).mesh;
    EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{1, 2, 0, 2, 3, 0}));

    json unindexedStrip = squareGltf(5, false); // 0 1 2 3: (0,1,2) and (1,3,2)
    mesh = prt::readBundle(writeGltf(unindexedStrip, "strip_plain.gltf")).mesh;
    EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2}));
}

TEST(HostileGltf, Gltf1IsNamedAsUnsupported) {
    json gltf = squareGltf();
    gltf["asset"]["version"] = "1.0";
    std::string message = refusal(writeGltf(gltf, "v1.gltf"));
    EXPECT_NE(message.find("glTF 1.0 is not supported"), std::string::npos) << message;
}

// A Draco primitive's accessors have no buffer view (the data is in the extension's), and tinygltf refuses an index
// accessor without one before prt sees extensionsRequired: the refusal still names the extension, with what to do.
TEST(HostileGltf, DracoIsNamedEvenWhereItsAccessorsHaveNoBufferView) {
    json gltf = squareGltf();
    gltf["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    gltf["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    gltf["accessors"][0].erase("bufferView");
    gltf["accessors"][1].erase("bufferView");
    std::string message = refusal(writeGltf(gltf, "draco.gltf"));
    EXPECT_NE(message.find("extensionsRequired: requires KHR_draco_mesh_compression"), std::string::npos) << message;
    EXPECT_NE(message.find("decompress"), std::string::npos) << message;
}

// A glTF 1.0 binary (header version 1) is named as such, not as truncated or unreadable.
TEST(HostileGltf, Gltf1BinaryIsNamedByItsHeaderVersion) {
    std::string json = R"({"asset":{"version":"1.0"}})";
    std::string glb = "glTF";
    const uint32_t header[4] = {1, uint32_t(20 + json.size() + 100), uint32_t(json.size()), 0};
    glb.append(reinterpret_cast<const char*>(header), sizeof header);
    glb += json;
    std::string path = scratch("v1.glb").string();
    std::ofstream(path, std::ios::binary) << glb;
    std::string message = refusal(path);
    EXPECT_NE(message.find("glTF binary: version 1 is not supported"), std::string::npos) << message;
}

// Properties of the wrong JSON type, as in assimp's glTF2/wrongTypes: tinygltf reads them as absent (a material
// whose pbrMetallicRoughness is an array became black and fully metallic) and a scene bundle carried them on. Each
// is refused naming the property; without the check every one of them loads.
TEST(HostileGltf, CorePropertiesOfTheWrongJsonTypeAreRefusedByPlace) {
    json textured = squareGltf();
    textured["materials"] = {{{"pbrMetallicRoughness", {{"metallicFactor", 0}}}}};
    textured["meshes"][0]["primitives"][0]["material"] = 0;
    const std::pair<std::function<void(json&)>, std::string> cases[] = {
        {[](json& g) { g["meshes"][0]["name"] = 42; }, "meshes[0].name: expected a string"},
        {[](json& g) { g["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", -1}}; },
         "materials[0].pbrMetallicRoughness.baseColorTexture.index: expected an integer in 0.."},
        {[](json& g) { g["materials"][0]["normalTexture"] = {{"index", 0}, {"scale", "not a number"}}; },
         "materials[0].normalTexture.scale: expected a number"},
        {[](json& g) { g["materials"][0]["pbrMetallicRoughness"] = {"not an object"}; },
         "materials[0].pbrMetallicRoughness: expected an object"},
        {[](json& g) {
             g["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}, {"extensions", {{"KHR_texture_transform", "x"}}}};
         },
         "baseColorTexture.extensions.KHR_texture_transform: expected an object"},
        {[](json& g) { g["meshes"][0]["primitives"] = g["meshes"][0]["primitives"][0]; },
         "meshes[0].primitives: expected an array of objects"},
        {[](json& g) { g["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = "0"; },
         "meshes[0].primitives[0].attributes.POSITION: expected an integer"},
        {[](json& g) { g["accessors"][1]["count"] = 0; }, "accessors[1].count: expected an integer in 1..9007199254740992"},
        {[](json& g) { g["extensionsUsed"] = {"KHR_texture_transform", 3}; }, "extensionsUsed[1]: expected a string"},
    };
    for (const auto& [edit, expected] : cases) {
        json gltf = textured;
        edit(gltf);
        const std::string message = refusal(writeGltf(gltf, "types.gltf"));
        EXPECT_NE(message.find(expected), std::string::npos) << expected << "\n" << message;
    }
    EXPECT_EQ(refusal(writeGltf(textured, "types.gltf")), ""); // the file they were made from is read
}

// Bytes after the length a .glb's header declares (two files joined, a copy appended to an old one) are refused by
// both readers of a .glb, as a cut-off file is; before, they were read as if absent.
TEST(HostileGltf, BytesPastTheDeclaredLengthAreRefusedByBothGlbReaders) {
    prt::Bundle bundle;
    bundle.mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    bundle.mesh.indices = {0, 1, 2};
    const std::string path = scratch("joined.glb").string();
    prt::writeBundle(path, bundle);
    EXPECT_NO_THROW(prt::readBundle(path));
    EXPECT_NO_THROW(prt::readBundleHeader(path));
    std::ofstream(path, std::ios::binary | std::ios::app) << "glTF";
    std::string message = refusal(path);
    EXPECT_NE(message.find("glTF binary: 4 bytes past the"), std::string::npos) << message;
    try {
        prt::readBundleHeader(path);
        ADD_FAILURE() << "readBundleHeader read past the declared length";
    } catch (const prt::Error& e) {
        EXPECT_NE(std::string(e.what()).find("4 bytes past the"), std::string::npos) << e.what();
    }
}

TEST(HostileGltf, ClaimedVertexCountAboveTheCapIsRefusedNamingTheLimit) {
    json gltf = squareGltf();
    gltf["accessors"][0]["count"] = 1000000000000ull;
    std::string message = refusal(writeGltf(gltf, "huge.gltf"));
    EXPECT_NE(message.find("above the limit of"), std::string::npos) << message;
    EXPECT_NE(message.find("PRT_MAX_ELEMENTS"), std::string::npos) << message;

    ScopedEnv cap("PRT_MAX_ELEMENTS", "3");
    message = refusal(writeGltf(squareGltf(), "capped.gltf"));
    EXPECT_NE(message.find("claims 4 vertices, above the limit of 3"), std::string::npos) << message;
}
