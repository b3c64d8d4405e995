// Materials at surface points (lib/material): texture sampling with glTF's wrap modes and filters, sRGB decoding,
// KHR_texture_transform, the diffuse albedo rule (factor * texture * COLOR_0 * (1 - metallic)) and cut-outs.
#include "core.h"
#include "material.h"
#include "scene.h"
#include "scene_gltf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

using namespace prt;
using namespace prt::test;

namespace {

std::filesystem::path scratch(const std::string& name) {
    std::filesystem::path dir = std::filesystem::temp_directory_path() / ("prt_material_test_" + name);
    std::filesystem::create_directories(dir);
    return dir;
}

// A unit plane (two triangles, uv 0..1) with `material`, in a scene of its own.
Bundle texturedPlane(const std::string& name, nlohmann::json material, nlohmann::json textures = nlohmann::json::array(),
                     nlohmann::json images = nlohmann::json::array(), nlohmann::json samplers = nlohmann::json::array()) {
    TestScene scene;
    scene.meshes = {{{makePlane(1.0f, 1), 0}}};
    scene.nodes = nlohmann::json::array({{{"mesh", 0}}});
    scene.roots = {0};
    scene.materials = nlohmann::json::array({material});
    scene.textures = textures;
    scene.images = images;
    scene.samplers = samplers;
    if (material.dump().find("KHR_texture_transform") != std::string::npos) scene.top["extensionsUsed"] = {"KHR_texture_transform"};
    std::filesystem::path path = scratch(name) / "plane.gltf";
    writeSceneGltf(path.string(), scene);
    return readBundle(path.string());
}

// 2 x 1 texels: left red (255, 0, 0), right grey 128 with alpha 64.
std::string twoTexelPng() { return pngBytes(2, 1, {255, 0, 0, 255, 128, 128, 128, 64}); }

} // namespace

TEST(Material, SrgbDecodesToLinear) {
    EXPECT_FLOAT_EQ(srgbToLinear(0.0f), 0.0f);
    EXPECT_FLOAT_EQ(srgbToLinear(1.0f), 1.0f);
    EXPECT_NEAR(srgbToLinear(128.0f / 255.0f), 0.2158605f, 1e-6f); // the sRGB curve at 128
    EXPECT_NEAR(srgbToLinear(0.04f), 0.04f / 12.92f, 1e-9f);       // linear segment
}

TEST(Material, WrapModesAndBilinearFilter) {
    SurfaceImage image;
    image.width = 2;
    image.height = 1;
    image.rgba = {0, 0, 0, 1, 1, 1, 1, 1}; // black | white
    TextureRecord repeat, clamp, mirror, nearest;
    clamp.wrapS = clamp.wrapT = 33071;
    mirror.wrapS = mirror.wrapT = 33648;
    nearest.magFilter = 9728;
    // Texel centres at u = 0.25 and 0.75; halfway between is their mean.
    EXPECT_FLOAT_EQ(sampleTexture(image, repeat, 0.25f, 0.5f)[0], 0.0f);
    EXPECT_FLOAT_EQ(sampleTexture(image, repeat, 0.75f, 0.5f)[0], 1.0f);
    EXPECT_FLOAT_EQ(sampleTexture(image, repeat, 0.5f, 0.5f)[0], 0.5f);
    // At u = 1.0 repeat blends the white texel with the black one it wraps to; clamp stays white.
    EXPECT_FLOAT_EQ(sampleTexture(image, repeat, 1.0f, 0.5f)[0], 0.5f);
    EXPECT_FLOAT_EQ(sampleTexture(image, clamp, 1.0f, 0.5f)[0], 1.0f);
    // Mirrored repeat: u = 1.25 is the mirror of 0.75 (white); repeat gives 0.25 (black).
    EXPECT_FLOAT_EQ(sampleTexture(image, mirror, 1.25f, 0.5f)[0], 1.0f);
    EXPECT_FLOAT_EQ(sampleTexture(image, repeat, 1.25f, 0.5f)[0], 0.0f);
    EXPECT_FLOAT_EQ(sampleTexture(image, repeat, -0.75f, 0.5f)[0], 0.0f);
    EXPECT_FLOAT_EQ(sampleTexture(image, nearest, 0.6f, 0.5f)[0], 1.0f);
}

TEST(Material, DiffuseAlbedoIsFactorTimesTextureTimesOneMinusMetallic) {
    nlohmann::json material = {{"pbrMetallicRoughness",
                                {{"baseColorFactor", {0.5, 1.0, 1.0, 1.0}}, {"metallicFactor", 0.25},
                                 {"baseColorTexture", {{"index", 0}}}}}};
    Bundle bundle = texturedPlane("albedo", material, nlohmann::json::array({{{"source", 0}, {"sampler", 0}}}),
                                  nlohmann::json::array({{{"uri", pngDataUri(twoTexelPng())}}}),
                                  nlohmann::json::array({{{"magFilter", 9728}}}));
    ASSERT_TRUE(bundle.asset);
    Surface surface = decodeSurface(bundle, "plane.gltf");
    // The plane's texcoords: u along +X. Find the triangle and barycentrics of a point at u = 0.25 and at 0.75.
    const TriMesh& mesh = bundle.mesh;
    auto albedoAtU = [&](float u) {
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const uint32_t* c = &mesh.indices[3 * t];
            const float* uv0 = &bundle.asset->texcoords[0][2 * c[0]];
            const float* uv1 = &bundle.asset->texcoords[0][2 * c[1]];
            const float* uv2 = &bundle.asset->texcoords[0][2 * c[2]];
            // Solve uv = uv0 + b1 (uv1 - uv0) + b2 (uv2 - uv0) for (u, 0.3).
            double a = uv1[0] - uv0[0], b = uv2[0] - uv0[0], cc = uv1[1] - uv0[1], d = uv2[1] - uv0[1];
            double det = a * d - b * cc, x = u - uv0[0], y = 0.3 - uv0[1];
            double b1 = (x * d - b * y) / det, b2 = (a * y - cc * x) / det;
            if (b1 >= 0 && b2 >= 0 && b1 + b2 <= 1) return diffuseAlbedoAt(surface, t, float(b1), float(b2));
        }
        ADD_FAILURE() << "no triangle at u = " << u;
        return std::array<float, 3>{};
    };
    std::array<float, 3> red = albedoAtU(0.25f), grey = albedoAtU(0.75f);
    EXPECT_FLOAT_EQ(red[0], 0.5f * 1.0f * 0.75f);
    EXPECT_FLOAT_EQ(red[1], 0.0f);
    // The grey texel has alpha 64/255: OpenImageIO associates alpha in 8 bits and material.h divides it out
    // again, which leaves the colour within 0.5 / 64 of an 8-bit step (kPartialAlphaTolerance, measured 1.8e-3).
    const float kPartialAlphaTolerance = 3e-3f;
    EXPECT_NEAR(grey[1], srgbToLinear(128.0f / 255.0f) * 0.75f, kPartialAlphaTolerance);
    EXPECT_NEAR(grey[0], 0.5f * srgbToLinear(128.0f / 255.0f) * 0.75f, kPartialAlphaTolerance);
}

TEST(Material, MaskCutsOutBelowTheCutoff) {
    nlohmann::json material = {{"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"baseColorTexture", {{"index", 0}}}}},
                               {"alphaMode", "MASK"},
                               {"alphaCutoff", 0.5}};
    Bundle bundle = texturedPlane("mask", material, nlohmann::json::array({{{"source", 0}, {"sampler", 0}}}),
                                  nlohmann::json::array({{{"uri", pngDataUri(twoTexelPng())}}}),
                                  nlohmann::json::array({{{"magFilter", 9728}}}));
    Surface surface = decodeSurface(bundle, "plane.gltf");
    EXPECT_TRUE(surface.cutouts);
    size_t present = 0, absent = 0;
    const TriMesh& mesh = bundle.mesh;
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        for (float b1 : {0.1f, 0.3f, 0.6f})
            for (float b2 : {0.1f, 0.3f}) {
                const uint32_t* c = &mesh.indices[3 * t];
                float u = (1 - b1 - b2) * bundle.asset->texcoords[0][2 * c[0]] + b1 * bundle.asset->texcoords[0][2 * c[1]] +
                          b2 * bundle.asset->texcoords[0][2 * c[2]];
                bool expected = u < 0.5f; // the left texel is opaque, the right one has alpha 64/255 < 0.5
                EXPECT_EQ(presentAt(surface, t, b1, b2), expected) << "u " << u;
                (expected ? present : absent) += 1;
            }
    EXPECT_GT(present, 0u);
    EXPECT_GT(absent, 0u);
}

TEST(Material, TextureTransformOffsetsTheLookup) {
    // An offset of 0.5 in u swaps the two texels.
    nlohmann::json material = {
        {"pbrMetallicRoughness",
         {{"metallicFactor", 0.0},
          {"baseColorTexture", {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"offset", {0.5, 0.0}}}}}}}}}}};
    Bundle bundle = texturedPlane("transform", material, nlohmann::json::array({{{"source", 0}, {"sampler", 0}}}),
                                  nlohmann::json::array({{{"uri", pngDataUri(twoTexelPng())}}}),
                                  nlohmann::json::array({{{"magFilter", 9728}}}));
    const MaterialRecord& record = bundle.asset->materials[0];
    EXPECT_FLOAT_EQ(record.uvTransform[2], 0.5f);
    // Nearest texel at the plane's corners (u = 0 and 1): x = u' * 2 - 0.5 rounds to texel 0 (red) without the
    // offset and to texel 1 (grey) with it, at both corners (u = 1 wraps).
    Surface surface = decodeSurface(bundle, "plane.gltf");
    for (float value : [&] {
             std::vector<float> green;
             std::vector<float> albedo = vertexDiffuseAlbedo(surface);
             for (size_t v = 0; v < albedo.size() / 3; ++v) green.push_back(albedo[3 * v + 1]);
             return green;
         }())
        EXPECT_NEAR(value, srgbToLinear(128.0f / 255.0f), 3e-3f); // alpha 64/255: see the test above
    nlohmann::json plain = material;
    plain["pbrMetallicRoughness"]["baseColorTexture"].erase("extensions");
    Bundle control = texturedPlane("no_transform", plain, nlohmann::json::array({{{"source", 0}, {"sampler", 0}}}),
                                   nlohmann::json::array({{{"uri", pngDataUri(twoTexelPng())}}}),
                                   nlohmann::json::array({{{"magFilter", 9728}}}));
    Surface controlSurface = decodeSurface(control, "plane.gltf");
    std::vector<float> controlAlbedo = vertexDiffuseAlbedo(controlSurface);
    for (size_t v = 0; v < controlAlbedo.size() / 3; ++v) {
        EXPECT_FLOAT_EQ(controlAlbedo[3 * v], 1.0f);
        EXPECT_FLOAT_EQ(controlAlbedo[3 * v + 1], 0.0f);
    }
}

TEST(Material, MetallicOneHasNoDiffuseAlbedo) {
    nlohmann::json material = {{"pbrMetallicRoughness", {{"baseColorFactor", {0.9, 0.8, 0.7, 1.0}}, {"metallicFactor", 1.0}}}};
    Bundle bundle = texturedPlane("metal", material);
    Surface surface = decodeSurface(bundle, "plane.gltf");
    for (float value : vertexDiffuseAlbedo(surface)) EXPECT_EQ(value, 0.0f);
    for (float value : bundle.mesh.albedo) EXPECT_EQ(value, 0.0f);
}

TEST(Material, ImagesClaimingTooManyTexelsAreRefusedBeforeDecoding) {
    nlohmann::json material = {{"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"baseColorTexture", {{"index", 0}}}}}};
    std::string huge = pngBytes(2, 1, {0, 0, 0, 255, 0, 0, 0, 255}, 100000, 100000);
    Bundle bundle = texturedPlane("huge", material, nlohmann::json::array({{{"source", 0}}}),
                                  nlohmann::json::array({{{"uri", pngDataUri(huge)}}}));
    try {
        decodeSurface(bundle, "plane.gltf");
        FAIL() << "a 100000 x 100000 PNG was decoded";
    } catch (const Error& e) {
        EXPECT_EQ(e.exitCode(), kExitInput);
        EXPECT_EQ(e.place(), "images[0]");
        EXPECT_NE(e.problem().find("100000 x 100000"), std::string::npos) << e.what();
    }
}
