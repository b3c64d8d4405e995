// Scene bundles (version 3, asset.h): a glTF scene read as its receivers in node order, with transforms composed,
// instances as receivers of their own, mirrored winding flipped; written back as the same asset plus layers, and
// hostile scene inputs refused with the place named.
#include "bundle.h"
#include "core.h"
#include "scene_gltf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace prt;
using namespace prt::test;
using nlohmann::json;

namespace {

std::filesystem::path scratch(const std::string& name) {
    std::filesystem::path dir = std::filesystem::temp_directory_path() / ("prt_scene_test_" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

// One triangle in the XY plane facing +Z, with normals.
TriMesh triangle() {
    TriMesh mesh;
    mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    mesh.texcoords = {0, 0, 1, 0, 0, 1};
    mesh.indices = {0, 1, 2};
    return mesh;
}

// The JSON chunk of a .glb.
json glbJson(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    return json::parse(bytes.substr(20, length));
}

void expectRefused(const TestScene& scene, const std::string& name, const std::string& place, const std::string& fragment) {
    std::filesystem::path path = scratch(name) / "scene.gltf";
    writeSceneGltf(path.string(), scene);
    try {
        readBundle(path.string());
        ADD_FAILURE() << name << ": read without error";
    } catch (const Error& e) {
        EXPECT_EQ(e.exitCode(), kExitInput) << e.what();
        EXPECT_NE(e.place().find(place), std::string::npos) << name << ": " << e.what();
        EXPECT_NE(e.problem().find(fragment), std::string::npos) << name << ": " << e.what();
    }
}

TestScene oneTriangleScene() {
    TestScene scene;
    scene.meshes = {{{triangle(), -1}}};
    scene.nodes = json::array({{{"mesh", 0}}});
    scene.roots = {0};
    return scene;
}

} // namespace

TEST(SceneBundle, ReceiversFollowNodeOrderWithComposedTransformsAndInstances) {
    // Root 0 translates by (10, 0, 0) and has children 1 (mesh 0, scaled by 2) and 2 (mesh 0 again, mirrored).
    TestScene scene;
    scene.meshes = {{{triangle(), -1}}};
    scene.nodes = json::array({{{"children", {1, 2}}, {"translation", {10.0, 0.0, 0.0}}},
                               {{"mesh", 0}, {"scale", {2.0, 2.0, 2.0}}},
                               {{"mesh", 0}, {"scale", {-1.0, 1.0, 1.0}}}});
    scene.roots = {0};
    std::filesystem::path path = scratch("order") / "scene.gltf";
    writeSceneGltf(path.string(), scene);
    Bundle bundle = readBundle(path.string());
    ASSERT_TRUE(bundle.asset);
    const SceneAsset& asset = *bundle.asset;
    ASSERT_EQ(asset.receivers.size(), 2u); // an instance is its own receiver
    EXPECT_EQ(asset.receivers[0].node, 1);
    EXPECT_EQ(asset.receivers[1].node, 2);
    EXPECT_EQ(asset.receivers[1].firstVertex, 3u);
    EXPECT_FALSE(asset.receivers[0].mirrored);
    EXPECT_TRUE(asset.receivers[1].mirrored);
    const TriMesh& mesh = bundle.mesh;
    ASSERT_EQ(mesh.vertexCount(), 6u);
    // Node 1: 2 p + (10, 0, 0); node 2: (-x, y, z) + (10, 0, 0).
    EXPECT_FLOAT_EQ(mesh.positions[3 * 1 + 0], 12.0f);
    EXPECT_FLOAT_EQ(mesh.positions[3 * 2 + 1], 2.0f);
    EXPECT_FLOAT_EQ(mesh.positions[3 * 4 + 0], 9.0f);
    // Both triangles stay counter-clockwise seen from their normal's side: (p1 - p0) x (p2 - p0) . n > 0.
    for (size_t t = 0; t < 2; ++t) {
        const uint32_t* c = &mesh.indices[3 * t];
        float e1[3], e2[3];
        for (int a = 0; a < 3; ++a)
            e1[a] = mesh.positions[3 * c[1] + a] - mesh.positions[3 * c[0] + a],
            e2[a] = mesh.positions[3 * c[2] + a] - mesh.positions[3 * c[0] + a];
        float z = e1[0] * e2[1] - e1[1] * e2[0];
        EXPECT_GT(z * mesh.normals[3 * c[0] + 2], 0.0f) << "triangle " << t;
        EXPECT_GE(c[0], 3 * t);
        EXPECT_LT(c[0], 3 * t + 3);
    }
}

TEST(SceneBundle, EveryObjectOfTheAssetSurvivesTheRoundTripFieldForField) {
    TestScene scene;
    TestPrimitive textured{triangle(), 0};
    textured.uv1 = {0, 0, 0.5f, 0, 0, 0.5f};
    textured.colors = {1, 0.5f, 0.25f, 1, 1, 1, 1, 1, 1, 1, 1, 1};
    scene.meshes = {{textured}, {{triangle(), 1}}};
    scene.nodes = json::array({{{"name", "root"}, {"children", {1, 2}}, {"extras", {{"studio", {{"tag", 7}}}}}},
                               {{"name", "crate"}, {"mesh", 0}, {"rotation", {0.0, 0.7071067811865476, 0.0, 0.7071067811865476}}},
                               {{"name", "fence"}, {"mesh", 1}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 3, 1}}},
                               {{"name", "camera"}, {"camera", 0}}});
    scene.roots = {0, 3};
    scene.materials = json::array(
        {{{"name", "wood"},
          {"pbrMetallicRoughness",
           {{"baseColorFactor", {0.9, 0.8, 0.7, 1.0}},
            {"metallicFactor", 0.0},
            {"roughnessFactor", 0.6},
            {"baseColorTexture",
             {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"offset", {0.25, 0.0}}, {"scale", {2.0, 2.0}}}}}}}}}},
          {"extras", {{"source", "scan"}}}},
         {{"name", "leaves"}, {"alphaMode", "MASK"}, {"alphaCutoff", 0.4}, {"doubleSided", true},
          {"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"baseColorTexture", {{"index", 0}, {"texCoord", 1}}}}}}});
    scene.textures = json::array({{{"source", 0}, {"sampler", 0}, {"name", "grain"}}});
    scene.samplers = json::array({{{"magFilter", 9728}, {"minFilter", 9987}, {"wrapS", 33071}, {"wrapT", 33648}}});
    scene.images = json::array({{{"name", "grain.png"}, {"uri", pngDataUri(pngBytes(1, 1, {200, 100, 50, 255}))}}});
    scene.top["extensionsUsed"] = {"KHR_texture_transform", "KHR_materials_variants_demo"};
    scene.top["cameras"] = json::array({{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}});
    scene.top["extras"] = {{"pipeline", "studio-7"}};
    scene.top["extensions"] = {{"KHR_materials_variants_demo", {{"variants", json::array({{{"name", "red"}}})}}}};
    std::filesystem::path dir = scratch("roundtrip");
    writeSceneGltf((dir / "scene.gltf").string(), scene);
    json input = sceneJson(scene);

    Bundle bundle = readBundle((dir / "scene.gltf").string());
    Layer layer;
    layer.name = "transfer";
    layer.domain = "vertex";
    layer.semantic = "sh_transfer_rgb";
    layer.shape = {bundle.mesh.vertexCount(), 1, 3};
    layer.data.assign(bundle.mesh.vertexCount() * 3, 0.5f);
    bundle.layers.push_back(layer);
    writeBundle((dir / "out.glb").string(), bundle);
    json output = glbJson((dir / "out.glb").string());

    for (const char* key : {"asset", "scene", "scenes", "nodes", "meshes", "accessors", "materials", "textures", "samplers", "cameras", "extras"})
        EXPECT_EQ(output[key], input[key]) << key << "\n input: " << input[key].dump() << "\noutput: " << output[key].dump();
    ASSERT_EQ(output["images"].size(), 1u);
    EXPECT_EQ(output["images"][0]["name"], "grain.png");
    EXPECT_EQ(output["images"][0]["mimeType"], "image/png");
    EXPECT_TRUE(output["images"][0].contains("bufferView")); // embedded: a bundle is one self-contained file
    EXPECT_EQ(output["extensions"]["KHR_materials_variants_demo"], input["extensions"]["KHR_materials_variants_demo"]);
    for (const json& name : input["extensionsUsed"])
        EXPECT_NE(std::find(output["extensionsUsed"].begin(), output["extensionsUsed"].end(), name), output["extensionsUsed"].end())
            << name;
    EXPECT_EQ(output["buffers"].size(), 1u);

    // And it reads back as the same scene with its layer, twice over (layers do not pile up).
    Bundle again = readBundle((dir / "out.glb").string());
    ASSERT_TRUE(again.asset);
    EXPECT_EQ(again.mesh.positions, bundle.mesh.positions);
    EXPECT_EQ(again.asset->receivers.size(), 2u);
    ASSERT_NE(findLayer(again, "transfer"), nullptr);
    writeBundle((dir / "again.glb").string(), again);
    EXPECT_EQ(std::filesystem::file_size(dir / "again.glb"), std::filesystem::file_size(dir / "out.glb"));
    EXPECT_EQ(again.asset->materials[1].alphaMode, AlphaMode::Mask);
    EXPECT_TRUE(again.asset->materials[1].doubleSided);
    EXPECT_EQ(again.asset->materials[1].texCoord, 1);
    EXPECT_EQ(again.asset->images[0].bytes, bundle.asset->images[0].bytes);
}

TEST(SceneBundle, HostileScenesAreRefusedNamingThePlace) {
    TestScene scene = oneTriangleScene();
    scene.meshes[0][0].material = 0;
    scene.materials = json::array({{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 3}}}}}}});
    expectRefused(scene, "texture_index", "materials[0].pbrMetallicRoughness.baseColorTexture.index", "does not exist");

    scene = oneTriangleScene();
    scene.meshes[0][0].material = 0;
    scene.materials = json::array({{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}});
    scene.textures = json::array({{{"source", 0}, {"sampler", 0}}});
    scene.samplers = json::array({{{"wrapS", 12345}}});
    scene.images = json::array({{{"uri", pngDataUri(pngBytes(1, 1, {1, 2, 3, 255}))}}});
    expectRefused(scene, "sampler_enum", "samplers[0].wrapS", "12345 is not a glTF wrap mode");

    scene = oneTriangleScene();
    scene.top["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    scene.top["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    expectRefused(scene, "draco", "extensionsRequired", "KHR_draco_mesh_compression");

    scene = oneTriangleScene();
    scene.meshes[0][0].material = 0;
    scene.materials = json::array({{{"alphaMode", "CUTOUT"}}});
    expectRefused(scene, "alpha_mode", "materials[0].alphaMode", "not OPAQUE, MASK or BLEND");

    scene = oneTriangleScene();
    scene.meshes[0][0].material = 0;
    scene.materials = json::array({{{"pbrMetallicRoughness", {{"metallicFactor", 1.5}}}}});
    expectRefused(scene, "metallic", "metallicFactor", "[0, 1]");

    scene = oneTriangleScene();
    scene.nodes = json::array({{{"mesh", 0}, {"children", {1}}}, {{"children", {0}}}});
    expectRefused(scene, "cycle", "nodes", "parent");

    scene = oneTriangleScene();
    scene.nodes = json::array({{{"children", {2}}}, {{"children", {2}}}, {{"mesh", 0}}});
    scene.roots = {0, 1};
    expectRefused(scene, "two_parents", "nodes[1].children", "at most one parent");
}

TEST(SceneBundle, MissingAndEscapingImageFilesAreRefused) {
    TestScene scene = oneTriangleScene();
    scene.meshes[0][0].material = 0;
    scene.materials = json::array({{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}});
    scene.textures = json::array({{{"source", 0}}});
    scene.images = json::array({{{"uri", "missing.png"}}});
    std::filesystem::path dir = scratch("missing_image");
    writeSceneGltf((dir / "scene.gltf").string(), scene);
    EXPECT_THROW(readBundle((dir / "scene.gltf").string()), Error);

    std::filesystem::path outside = scratch("escaping_image");
    std::filesystem::create_directories(outside / "asset");
    std::ofstream(outside / "secret.png", std::ios::binary) << pngBytes(1, 1, {1, 2, 3, 255});
    scene.images = json::array({{{"uri", "../secret.png"}}});
    writeSceneGltf((outside / "asset" / "scene.gltf").string(), scene);
    try {
        readBundle((outside / "asset" / "scene.gltf").string());
        ADD_FAILURE() << "an image outside the glTF file's folder was read";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("outside"), std::string::npos) << e.what();
    }
}
