// Version 2 of the bundle format: objects, instances, compact component types, and reading version 1.
#include "bundle.h"
#include "bundle_internal.h"

#include "core.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <bit>
#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

fs::path scratch(const std::string& name) {
    fs::path dir = fs::temp_directory_path() / ("prt_bundle_v2_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    return dir / name;
}

prt::TriMesh triangle(float offset) {
    prt::TriMesh mesh;
    mesh.positions = {offset, 0, 0, offset + 1, 0, 0, offset, 1, 0};
    mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    mesh.indices = {0, 1, 2};
    return mesh;
}

prt::TriMesh quad() {
    prt::TriMesh mesh;
    mesh.positions = {0, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 1};
    mesh.indices = {0, 2, 1, 0, 3, 2};
    return mesh;
}

prt::Layer floatLayer(std::string name, std::string type, std::vector<uint64_t> shape, std::vector<float> data, uint32_t object) {
    prt::Layer layer;
    layer.name = std::move(name);
    layer.domain = "vertex";
    layer.semantic = "test_values";
    layer.shape = std::move(shape);
    layer.componentType = std::move(type);
    layer.data = std::move(data);
    layer.object = object;
    return layer;
}

prt::Layer integerLayer(std::string name, std::string type, std::vector<uint32_t> values, uint32_t object) {
    prt::Layer layer;
    layer.name = std::move(name);
    layer.domain = "grid";
    layer.semantic = "test_integers";
    layer.shape = {values.size()};
    layer.componentType = std::move(type);
    layer.integers = std::move(values);
    layer.object = object;
    layer.params = {{"resolution", {values.size()}}};
    return layer;
}

// A receiver, two occluder types, three instances, and one layer of every component type, on several objects.
prt::Bundle sceneBundle() {
    prt::Bundle bundle;
    bundle.mesh = quad();
    bundle.meshName = "floor";
    bundle.objects.push_back({"small", "occluder", triangle(0)});
    bundle.objects.push_back({"large", "occluder", triangle(5)});
    bundle.instances.push_back({"floor", 0, {0, 0, 0}});
    bundle.instances.push_back({"small#0", 1, {0.5f, 2, -1}});
    bundle.instances.push_back({"small#1", 1, {-3, 2.25f, 0}});
    bundle.instances.push_back({"", 2, {0, 4, 0}});
    bundle.producer = {{"tool", "prt"}, {"stage", "test"}};
    bundle.layers.push_back(floatLayer("f32", "float32", {4, 2}, {1, 2, 3, 4, 5, 6, 7, 8.5f}, 0));
    // Three values that float16 holds exactly and one that it rounds (0.1 -> 0.0999755859375).
    bundle.layers.push_back(floatLayer("f16", "float16", {3}, {0.5f, -65504.0f, 0.1f}, 2));
    bundle.layers.push_back(integerLayer("u8", "uint8", {0, 1, 255}, 1));
    bundle.layers.push_back(integerLayer("u16", "uint16", {65535, 7}, 1));
    bundle.layers.push_back(integerLayer("u32", "uint32", {4294967295u, 0, 12345}, 2));
    return bundle;
}

// PRT_BUNDLE_TEST_KEEP names a folder where the bundles also go, for the glTF validator test to check.
void keepCopy(const std::string& path) {
    if (const char* keep = std::getenv("PRT_BUNDLE_TEST_KEEP"))
        fs::copy_file(path, fs::path(keep) / ("v2test-" + fs::path(path).filename().string()), fs::copy_options::overwrite_existing);
}

std::string writeScene(const std::string& name) {
    std::string path = scratch(name).string();
    prt::writeBundle(path, sceneBundle());
    keepCopy(path);
    return path;
}

void expectWriteError(const prt::Bundle& bundle, const std::string& fragment, int version = prt::kBundleVersion) {
    std::string path = scratch("refused.glb").string();
    try {
        prt::writeBundle(path, bundle, version);
        FAIL() << "expected an error containing: " << fragment;
    } catch (const prt::Error& e) {
        EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(path));
}

} // namespace

TEST(BundleVersion2, HalfConversionIsExactForEveryHalf) {
    for (uint32_t bits = 0; bits < 0x10000u; ++bits) {
        uint16_t half = uint16_t(bits);
        bool nan = (half & 0x7c00u) == 0x7c00u && (half & 0x3ffu) != 0;
        if (nan) {
            EXPECT_TRUE(std::isnan(prt::halfToFloat(half)));
            continue;
        }
        ASSERT_EQ(prt::floatToHalf(prt::halfToFloat(half)), half) << bits;
    }
}

TEST(BundleVersion2, HalfConversionRoundsToNearestEven) {
    EXPECT_EQ(prt::floatToHalf(1.0f), 0x3c00u);
    EXPECT_EQ(prt::floatToHalf(65504.0f), 0x7bffu);
    EXPECT_EQ(prt::floatToHalf(65519.0f), 0x7bffu); // below the midpoint to 65536
    EXPECT_EQ(prt::floatToHalf(65520.0f), 0x7c00u); // the midpoint rounds to even: infinity
    EXPECT_EQ(prt::floatToHalf(-1e9f), 0xfc00u);
    // 1 + 2^-11 is halfway between 1 and the next half, 1 + 2^-10: to even, 1. Just above it rounds up.
    EXPECT_EQ(prt::floatToHalf(1.0f + 0x1p-11f), 0x3c00u);
    EXPECT_EQ(prt::floatToHalf(1.0f + 0x1p-11f + 0x1p-20f), 0x3c01u);
    EXPECT_EQ(prt::floatToHalf(1.0f + 3 * 0x1p-11f), 0x3c02u); // halfway between odd 0x3c01 and 0x3c02: even
    // Subnormals: the smallest is 2^-24; 2^-25 is halfway to zero and rounds to even (zero); above it, up.
    EXPECT_EQ(prt::floatToHalf(0x1p-24f), 0x0001u);
    EXPECT_EQ(prt::floatToHalf(0x1p-25f), 0x0000u);
    EXPECT_EQ(prt::floatToHalf(0x1.01p-25f), 0x0001u);
    EXPECT_EQ(prt::floatToHalf(-0.0f), 0x8000u);
    EXPECT_EQ(prt::floatToHalf(0x1.ff8p-15f), 0x03ffu); // the largest subnormal
    EXPECT_EQ(prt::floatToHalf(0x1.ffcp-15f), 0x0400u); // halfway above it rounds to even: the smallest normal
    EXPECT_EQ(prt::halfToFloat(0x0001u), 0x1p-24f);
}

TEST(BundleVersion2, ObjectsInstancesAndComponentTypesRoundTrip) {
    prt::Bundle written = sceneBundle();
    prt::Bundle read = prt::readBundle(writeScene("scene.glb"));
    EXPECT_EQ(read.meshName, "floor");
    EXPECT_EQ(read.meshRole, "receiver");
    EXPECT_EQ(read.mesh.positions, written.mesh.positions);
    EXPECT_EQ(read.mesh.indices, written.mesh.indices);
    ASSERT_EQ(read.objects.size(), 2u);
    for (size_t k = 0; k < 2; ++k) {
        EXPECT_EQ(read.objects[k].name, written.objects[k].name);
        EXPECT_EQ(read.objects[k].role, "occluder");
        EXPECT_EQ(read.objects[k].mesh.positions, written.objects[k].mesh.positions); // untransformed
        EXPECT_EQ(read.objects[k].mesh.normals, written.objects[k].mesh.normals);
        EXPECT_EQ(read.objects[k].mesh.indices, written.objects[k].mesh.indices);
    }
    ASSERT_EQ(read.instances.size(), 4u);
    for (size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(read.instances[i].name, written.instances[i].name);
        EXPECT_EQ(read.instances[i].object, written.instances[i].object);
        EXPECT_EQ(read.instances[i].translation, written.instances[i].translation);
    }
    ASSERT_EQ(read.layers.size(), 5u);
    EXPECT_EQ(read.layers[0].data, written.layers[0].data);
    EXPECT_EQ(read.layers[1].componentType, "float16");
    EXPECT_EQ(read.layers[1].object, 2u);
    EXPECT_EQ(read.layers[1].data, (std::vector<float>{0.5f, -65504.0f, 0.0999755859375f}));
    for (size_t i = 2; i < 5; ++i) {
        EXPECT_EQ(read.layers[i].componentType, written.layers[i].componentType);
        EXPECT_EQ(read.layers[i].integers, written.layers[i].integers);
        EXPECT_EQ(read.layers[i].object, written.layers[i].object);
        EXPECT_TRUE(read.layers[i].data.empty());
    }
    EXPECT_EQ(&prt::objectMesh(read, 2), &read.objects[1].mesh);
}

TEST(BundleVersion2, ViewersSeeEveryInstanceAtItsTranslation) {
    std::string path = writeScene("viewer.glb");
    tinygltf::TinyGLTF loader;
    tinygltf::Model model;
    std::string error, warning;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, path)) << error;
    ASSERT_EQ(model.meshes.size(), 3u);
    ASSERT_EQ(model.scenes.size(), 1u);
    ASSERT_EQ(model.scenes[0].nodes.size(), 4u);
    const tinygltf::Node& second = model.nodes[model.scenes[0].nodes[2]];
    EXPECT_EQ(second.mesh, 1);
    EXPECT_EQ(second.translation, (std::vector<double>{-3.0, 2.25, 0.0}));
    // Every buffer view starts 4-aligned, whatever the element size of the view before it.
    for (const tinygltf::BufferView& view : model.bufferViews) EXPECT_EQ(view.byteOffset % 4, 0u);
    // Through the scene, the plain-glTF reading merges all instances: 4 + 3 * 3 vertices.
    EXPECT_EQ(prt::detail::readGltfMesh(model, path).vertexCount(), 13u);
}

TEST(BundleVersion2, WithoutInstancesTheSceneShowsEveryObjectOnce) {
    prt::Bundle bundle = sceneBundle();
    bundle.instances.clear();
    std::string path = scratch("objects.glb").string();
    prt::writeBundle(path, bundle);
    tinygltf::TinyGLTF loader;
    tinygltf::Model model;
    std::string error, warning;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, path)) << error;
    EXPECT_EQ(model.scenes[0].nodes, (std::vector<int>{0, 1, 2}));
    EXPECT_TRUE(prt::readBundle(path).instances.empty());
}

TEST(BundleVersion2, VersionOneIsStillWrittenAndRead) {
    prt::Bundle bundle;
    bundle.mesh = quad();
    bundle.layers.push_back(floatLayer("transfer", "float32", {4, 1, 3}, std::vector<float>(12, 0.25f), 0));
    std::string path = scratch("v1.glb").string();
    prt::writeBundle(path, bundle, 1);
    keepCopy(path);
    std::string bytes = prt::readFileBytes(path);
    EXPECT_NE(bytes.find("\"version\":1"), std::string::npos);
    EXPECT_EQ(bytes.find("\"objects\""), std::string::npos);
    prt::Bundle read = prt::readBundle(path);
    EXPECT_EQ(read.mesh.positions, bundle.mesh.positions);
    EXPECT_EQ(read.layers[0].data, bundle.layers[0].data);
    EXPECT_EQ(read.layers[0].componentType, "float32");
    EXPECT_TRUE(read.objects.empty());
}

TEST(BundleVersion2, VersionOneRefusesWhatOnlyVersionTwoHolds) {
    expectWriteError(sceneBundle(), "objects and instances need version 2", 1);
    prt::Bundle bundle;
    bundle.mesh = quad();
    bundle.layers.push_back(floatLayer("half", "float16", {4}, {1, 2, 3, 4}, 0));
    expectWriteError(bundle, "version 1 stores float32 only", 1);
    expectWriteError(bundle, "cannot write bundle version 4", 4);
}

TEST(BundleVersion2, InconsistentObjectsAndLayersAreRefusedOnWrite) {
    prt::Bundle bundle = sceneBundle();
    bundle.layers[0].object = 1; // 4 rows on a 3-vertex object
    expectWriteError(bundle, "vertex layer has 4 rows for 3 vertices of object 'small'");
    bundle = sceneBundle();
    bundle.layers[2].integers[0] = 256;
    expectWriteError(bundle, "value 256 does not fit uint8");
    bundle = sceneBundle();
    bundle.layers[3].componentType = "int8";
    expectWriteError(bundle, "unknown componentType 'int8'");
    bundle = sceneBundle();
    bundle.layers[4].object = 3;
    expectWriteError(bundle, "object 3 does not exist");
    bundle = sceneBundle();
    bundle.instances[1].object = 9;
    expectWriteError(bundle, "object 9 does not exist");
    bundle = sceneBundle();
    bundle.objects[1].name = "small";
    expectWriteError(bundle, "duplicate object name 'small'");
    bundle = sceneBundle();
    bundle.layers[1].data[0] = 70000.0f;
    expectWriteError(bundle, "does not fit float16");
    bundle = sceneBundle();
    bundle.layers[2].data = {1.0f};
    expectWriteError(bundle, "an integer layer holds floats");
}

// A reader refuses a structurally wrong extension even when its checksum was recomputed to match.
TEST(BundleVersion2, ForgedObjectReferencesAreRefusedOnRead) {
    std::string path = writeScene("forged.glb");
    std::string bytes = prt::readFileBytes(path);
    uint32_t jsonLength;
    std::memcpy(&jsonLength, bytes.data() + 12, 4);
    json document = json::parse(bytes.substr(20, jsonLength));
    std::string binary = bytes.substr(20 + jsonLength + 8);
    uint32_t bufferLength = document["buffers"][0]["byteLength"].get<uint32_t>();
    std::vector<unsigned char> buffer(binary.begin(), binary.begin() + bufferLength);
    auto forge = [&](auto edit, const std::string& fragment) {
        json changed = document;
        json& extension = changed["extensions"]["PRT_bundle"];
        edit(extension);
        extension.erase("checksum");
        extension["checksum"] = prt::detail::extensionChecksum(buffer, extension);
        std::string text = changed.dump();
        text.resize((text.size() + 3) / 4 * 4, ' ');
        std::string out = bytes.substr(0, 12);
        uint32_t length = uint32_t(text.size());
        out.append(reinterpret_cast<const char*>(&length), 4);
        out.append("JSON", 4);
        out += text;
        out += bytes.substr(20 + jsonLength);
        uint32_t total = uint32_t(out.size());
        std::memcpy(out.data() + 8, &total, 4);
        std::string forged = scratch("forged-edit.glb").string();
        prt::writeBytesAtomic(forged, out);
        try {
            prt::readBundle(forged);
            FAIL() << "expected: " << fragment;
        } catch (const prt::Error& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        }
    };
    forge([](json& e) { e["layers"][1]["object"] = 7; }, "object 7 does not exist");
    forge([](json& e) { e["instances"][0]["object"] = 3; }, "is not the index of an object");
    forge([](json& e) { e["objects"][1]["mesh"] = 9; }, "is not the index of a glTF mesh");
    forge([](json& e) { e["objects"][2]["name"] = "floor"; }, "name is empty or not unique");
    forge([](json& e) { e["layers"][2]["componentType"] = "uint16"; }, "bufferView holds 3 bytes, shape needs 3 uint16");
    forge([](json& e) { e["layers"][3]["componentType"] = "float64"; }, "componentType must be one of");
    forge([](json& e) { e["version"] = 4; }, "version 4 is not supported; this build reads versions 1 to 3");
    forge([](json& e) { e["instances"][1]["translation"] = {1, 2}; }, "is not three numbers");
}
