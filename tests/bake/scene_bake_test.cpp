// The bake over glTF scenes: one lightmap atlas over every placed primitive, irradiance transfer with the albedo of
// the material at every hit, the asset kept and the atlas as the corner layer "lightmap_uv". Closed forms: an open
// textured floor under a constant sky (white radiance 1 and the texture's albedo per texel), instances that get
// texels of their own, and the colour a red wall bounces onto a white floor.
#include "bake.h"

#include "core.h"
#include "corner_scene.h"
#include "material.h"
#include "runtime.h"
#include "scene.h"
#include "scene_gltf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>

namespace prt {
namespace {

using nlohmann::json;
using namespace prt::test;
namespace fs = std::filesystem;

struct Folder {
    fs::path path;
    explicit Folder(const std::string& name)
        : path(fs::temp_directory_path() / ("prt_scene_bake_" + std::to_string(::getpid()) + "_" + name)) {
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~Folder() { fs::remove_all(path); }
    std::string operator/(const std::string& file) const { return (path / file).string(); }
};

json diffuse(double r, double g, double b) {
    return {{"pbrMetallicRoughness", {{"baseColorFactor", {r, g, b, 1.0}}, {"metallicFactor", 0.0}}}};
}

BakeOptions sceneBake(const std::string& input, const std::string& output, int resolution) {
    BakeOptions options;
    options.input = input;
    options.output = output;
    options.resolution = resolution;
    options.order = 2;
    options.samples = 1024;
    options.format = TexelFormat::Bundle;
    options.toolVersion = "test";
    return options;
}

// A 2 x 2 texture of four colours, nearest filtering, over a floor whose TEXCOORD_1 repeats its TEXCOORD_0.
TestScene texturedFloor() {
    TriMesh floor = makePlane(2.0f, 4, 0.0f);
    TestScene scene;
    TestPrimitive primitive{floor, 0};
    primitive.uv1 = floor.texcoords;
    scene.meshes = {{primitive}};
    scene.nodes = json::array({{{"mesh", 0}}});
    scene.roots = {0};
    scene.materials = json::array(
        {{{"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"baseColorTexture", {{"index", 0}}}}}}});
    scene.textures = json::array({{{"source", 0}, {"sampler", 0}}});
    scene.samplers = json::array({{{"magFilter", 9728}, {"minFilter", 9728}}});
    scene.images = json::array({{{"uri", pngDataUri(pngBytes(2, 2, {255, 0, 0, 255, 0, 255, 0, 255,  //
                                                                    0, 0, 255, 255, 128, 128, 128, 255}))}}});
    return scene;
}

} // namespace

TEST(SceneBake, TexturedFloorBakesIrradianceTransferAndItsTextureAsAlbedo) {
    Folder folder("floor");
    writeSceneGltf(folder / "floor.gltf", texturedFloor());
    BakeOptions options = sceneBake(folder / "floor.gltf", folder / "floor.bake.glb", 16);
    runBake(options);
    Bundle baked = readBundle(options.output);

    // The asset is the input's, and the atlas is its TEXCOORD_1 (unique: no mesh is placed twice).
    ASSERT_TRUE(baked.asset);
    EXPECT_EQ(baked.asset->materials.size(), 2u); // the floor's and the default
    EXPECT_EQ(baked.asset->images.size(), 1u);
    const Layer* transfer = findLayer(baked, "texel_transfer");
    ASSERT_TRUE(transfer);
    EXPECT_EQ(transfer->params["albedo"], "excluded");
    EXPECT_EQ(transfer->params["atlas"]["source_uv_set"], 1);
    EXPECT_EQ(transfer->params["atlas"]["generated"], false);
    const Layer* corners = findLayer(baked, "lightmap_uv");
    ASSERT_TRUE(corners);
    EXPECT_EQ(corners->domain, "corner");
    ASSERT_EQ(corners->data.size(), 2 * baked.mesh.indices.size());
    for (size_t c = 0; c < baked.mesh.indices.size(); ++c)
        for (int a = 0; a < 2; ++a)
            ASSERT_EQ(corners->data[2 * c + a], baked.asset->texcoords[1][2 * baked.mesh.indices[c] + a]) << c;

    // Open to a constant sky of radiance 1, every texel reflects 1 as a white surface (E / pi = 1), and the
    // runtime relights a scene bake as that: it does not multiply by the albedo.
    TexelRelightModel model = texelRelightModel(baked, options.output);
    EXPECT_TRUE(model.rows.albedoExcluded);
    std::vector<float> lighting(4 * 3, 0.0f);
    for (int c = 0; c < 3; ++c) lighting[c] = float(std::sqrt(4.0 * std::numbers::pi));
    std::vector<float> radiance(size_t(model.rows.vertexCount) * 3);
    relight(model.rows, lighting.data(), 0, model.rows.vertexCount, radiance.data());
    const Layer* surface = findLayer(baked, "texel_surface");
    ASSERT_TRUE(surface);
    const float quadrant[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.5f, 0.5f, 0.5f}}; // sRGB, decoded below
    size_t covered = 0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            size_t t = size_t(y) * 16 + x;
            const float* row = &surface->data[t * kTexelSurfaceChannels];
            if (row[9] < 0.5f) continue;
            ++covered;
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(radiance[3 * t + c], 1.0, 0.02) << "texel " << x << "," << y;
            // The texel's albedo is the texture's at its centre: uv = texel centre, TEXCOORD_0 = TEXCOORD_1.
            const float* expected = quadrant[(y < 8 ? 0 : 2) + (x < 8 ? 0 : 1)];
            for (int c = 0; c < 3; ++c)
                EXPECT_FLOAT_EQ(row[6 + c], srgbToLinear(expected[c] == 0.5f ? 128.0f / 255.0f : expected[c]))
                    << "texel " << x << "," << y << " channel " << c;
        }
    EXPECT_EQ(covered, 256u); // the floor's TEXCOORD_1 spans the whole atlas
}

TEST(SceneBake, InstancesGetTexelsOfTheirOwnInAGeneratedAtlas) {
    Folder folder("instances");
    TriMesh floor = makePlane(6.0f, 6, -0.6f);
    TestScene scene;
    TestPrimitive ground{floor, 0}, ball{makeSphere(0.5f, 8, 16), 1};
    ground.uv1 = floor.texcoords;
    ball.uv1.assign(2 * ball.mesh.vertexCount(), 0.25f); // a TEXCOORD_1 the two instances would share
    scene.meshes = {{ground}, {ball}};
    scene.nodes = json::array({{{"mesh", 0}}, {{"mesh", 1}, {"translation", {-1.0, 0.0, 0.0}}},
                               {{"mesh", 1}, {"translation", {1.0, 0.0, 0.0}}}});
    scene.roots = {0, 1, 2};
    scene.materials = json::array({diffuse(0.8, 0.8, 0.8), diffuse(0.9, 0.2, 0.2)});
    writeSceneGltf(folder / "balls.gltf", scene);
    BakeOptions options = sceneBake(folder / "balls.gltf", folder / "balls.bake.glb", 128);
    options.samples = 16;

    // The ball is placed twice: the atlas is generated over every placement.
    BakedAtlas baked = bakeAtlas(options);
    ASSERT_TRUE(baked.scene);
    EXPECT_EQ(baked.params["atlas"]["generated"], true);
    const SceneAsset& asset = *baked.scene->asset;
    ASSERT_EQ(asset.receivers.size(), 3u);
    std::vector<size_t> texelsOf(asset.receivers.size(), 0);
    for (uint32_t triangle : baked.samples.triangle) ++texelsOf[asset.triangleReceiver[triangle]];
    for (size_t r = 0; r < texelsOf.size(); ++r) EXPECT_GT(texelsOf[r], 20u) << "receiver " << r;
    // Same mesh, same size, same texel density: the two balls cover about as many texels.
    EXPECT_NEAR(double(texelsOf[1]), double(texelsOf[2]), 0.2 * double(texelsOf[1]));

    // Asked for TEXCOORD_1 by name, the bake refuses it: both balls would land on the same texels.
    options.uvSet = 1;
    try {
        bakeSurface(options);
        ADD_FAILURE() << "a shared TEXCOORD_1 was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.exitCode(), kExitInput);
        EXPECT_EQ(e.place(), "meshes[1]");
    }
}

TEST(SceneBake, ABounceOffARedWallTurnsTheWhiteFloorRed) {
    Folder folder("corner");
    TestScene scene;
    scene.meshes = {{{makePlane(2.0f, 8, 0.0f), 0}}, {{wallAtXOne(2.0f, 8), 1}}};
    scene.nodes = json::array({{{"mesh", 0}}, {{"mesh", 1}}});
    scene.roots = {0, 1};
    scene.materials = json::array({diffuse(1.0, 1.0, 1.0), diffuse(0.9, 0.1, 0.1)});
    writeSceneGltf(folder / "corner.gltf", scene);
    BakeOptions options = sceneBake(folder / "corner.gltf", folder / "corner.bake.glb", 64);
    options.samples = 256;
    options.bounces = 1;
    BakedAtlas baked = bakeAtlas(options);
    ASSERT_FALSE(baked.bounce.empty());
    // What the wall bounces onto the floor texels near it, per channel (the DC coefficient): the wall's red.
    const int rowValues = 3 * options.order * options.order;
    double bounced[3] = {0, 0, 0};
    size_t count = 0;
    for (size_t t = 0; t < size_t(options.resolution) * options.resolution; ++t) {
        const float* surface = &baked.surface[t * kTexelSurfaceChannels];
        bool nearWallOnFloor =
            surface[9] > 0.5f && std::fabs(surface[1]) < 1e-4f && surface[4] > 0.9f && surface[0] > 0.5f;
        if (!nearWallOnFloor) continue;
        ++count;
        for (int c = 0; c < 3; ++c) bounced[c] += baked.bounce[t * rowValues + c];
        EXPECT_FLOAT_EQ(surface[6], 1.0f); // the texel's albedo is the white floor's
    }
    ASSERT_GT(count, 50u);
    EXPECT_GT(bounced[0], 0.0);
    // Albedo 0.9 against 0.1 at every hit, the same rays for every channel: exactly 9 times the green. (Seam
    // stitching must not blend the floor with the wall across their crease.)
    EXPECT_NEAR(bounced[0], 9.0 * bounced[1], 1e-4 * bounced[0]);
    EXPECT_NEAR(bounced[1], bounced[2], 0.2 * bounced[1] + 1e-6);
}

TEST(SceneBake, RefusesAHighMeshAndAnAlbedoForAScene) {
    Folder folder("refuse");
    writeSceneGltf(folder / "floor.gltf", texturedFloor());
    BakeOptions options = sceneBake(folder / "floor.gltf", folder / "floor.bake.glb", 16);
    options.high = folder / "floor.gltf";
    EXPECT_THROW(bakeSurface(options), Error);
    options.high.clear();
    options.albedoOverride = true;
    EXPECT_THROW(bakeSurface(options), Error);
    options.albedoOverride = false;
    options.uvSet = 2;
    EXPECT_THROW(bakeSurface(options), Error);
    EXPECT_FALSE(fs::exists(options.output));
}

} // namespace prt
