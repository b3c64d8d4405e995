// Pictures of scenes (renderVertexRadiance with a Surface): under a constant sky every pixel of an unoccluded
// textured plane is its texel's albedo times the sky's radiance, and a cut-out lets the ray through.
#include "material.h"
#include "render.h"
#include "scene.h"
#include "scene_gltf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

using namespace prt;
using namespace prt::test;
using nlohmann::json;

namespace {

// A 2 x 2 textured plane (the plane y = 0, seen from above), and a cut-out square above its +X half.
Bundle texturedScene(bool withCutout) {
    TestScene scene;
    scene.meshes = {{{makePlane(2.0f, 4, 0.0f), 0}}};
    scene.nodes = json::array({{{"mesh", 0}}});
    scene.roots = {0};
    scene.materials = json::array(
        {{{"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"baseColorTexture", {{"index", 0}}}}}},
         {{"alphaMode", "MASK"}, {"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"baseColorFactor", {0.0, 0.0, 1.0, 0.2}}}}}});
    scene.textures = json::array({{{"source", 0}, {"sampler", 0}}});
    scene.samplers = json::array({{{"magFilter", 9728}}});
    // Texel (x, y): red, green / blue, 50% grey (sRGB 188 is linear ~0.5).
    scene.images = json::array({{{"uri", pngDataUri(pngBytes(2, 2, {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 188, 188, 188, 255}))}}});
    if (withCutout) {
        scene.meshes.push_back({{makePlane(1.0f, 1, 0.5f), 1}});
        scene.nodes.push_back({{"mesh", 1}, {"translation", {0.5, 0.0, 0.0}}});
        scene.roots.push_back(1);
    }
    std::filesystem::path dir = std::filesystem::temp_directory_path() / (withCutout ? "prt_scene_render_cut" : "prt_scene_render");
    std::filesystem::create_directories(dir);
    writeSceneGltf((dir / "scene.gltf").string(), scene);
    return readBundle((dir / "scene.gltf").string());
}

PinholeCamera topCamera() {
    PinholeCamera camera;
    camera.eye = {0, 4, 0};
    camera.target = {0, 0, 0};
    camera.up = {0, 0, -1};
    camera.fovyDegrees = 30.0f;
    camera.width = camera.height = 40;
    return camera;
}

} // namespace

TEST(SceneRender, EveryPixelIsItsTexelsAlbedoTimesTheSky) {
    Bundle bundle = texturedScene(false);
    Surface surface = decodeSurface(bundle, "scene.gltf");
    const float sky = 2.0f;
    // Unoccluded under a constant sky, a white surface reflects the sky's radiance: the relit rows (E / pi).
    std::vector<float> rows(bundle.mesh.vertexCount() * 3, sky);
    RenderedImage image = renderVertexRadiance(bundle.mesh, rows, topCamera(), &surface);
    const float grey = srgbToLinear(188.0f / 255.0f);
    // Expected per quadrant of the plane: u along +X, v along +Z; seen from above with up = -Z, +X is right and
    // +Z is down in the picture, so the picture's quadrants are the texture's.
    const float expected[2][2][3] = {{{1, 0, 0}, {0, 1, 0}}, {{0, 0, 1}, {grey, grey, grey}}};
    int checked = 0;
    for (int y : {12, 27})
        for (int x : {12, 27}) {
            const float* pixel = &image.radiance.rgb[3 * (size_t(y) * 40 + x)];
            const float* want = expected[y > 20][x > 20];
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(pixel[c], want[c] * sky, 1e-5f) << x << "," << y << " channel " << c;
            ++checked;
        }
    EXPECT_EQ(checked, 4);
}

TEST(SceneRender, PrimaryRaysPassThroughCutOuts) {
    Bundle bundle = texturedScene(true);
    Surface surface = decodeSurface(bundle, "scene.gltf");
    std::vector<float> rows(bundle.mesh.vertexCount() * 3, 1.0f);
    RenderedImage image = renderVertexRadiance(bundle.mesh, rows, topCamera(), &surface);
    // The square's alpha 0.2 is below the cutoff 0.5: the plane's texels show through, not its blue.
    const float* pixel = &image.radiance.rgb[3 * (size_t(27) * 40 + 27)];
    const float grey = srgbToLinear(188.0f / 255.0f);
    EXPECT_NEAR(pixel[0], grey, 1e-5f);
    EXPECT_NEAR(pixel[2], grey, 1e-5f);
}

TEST(SceneRender, ASceneBakeIsLookedUpThroughItsCornerUvsAndTimesTheAlbedo) {
    Bundle bundle = texturedScene(false);
    Surface surface = decodeSurface(bundle, "scene.gltf");
    // A 2 x 1 relit atlas, E / pi = 1 on its left texel and 3 on its right, addressed through corner uvs that
    // mirror u: so the plane's +X half (the picture's right) reads the left texel. TEXCOORD_0 would read the other.
    Image atlas;
    atlas.width = 2;
    atlas.height = 1;
    atlas.rgb = {1, 1, 1, 3, 3, 3};
    std::vector<float> cornerUv(2 * bundle.mesh.indices.size());
    for (size_t c = 0; c < bundle.mesh.indices.size(); ++c) {
        cornerUv[2 * c] = 1.0f - bundle.mesh.texcoords[2 * bundle.mesh.indices[c]];
        cornerUv[2 * c + 1] = 0.5f;
    }
    RenderedImage image = renderTexelRadiance(bundle.mesh, atlas, topCamera(), cornerUv.data(), &surface);
    const float* left = &image.radiance.rgb[3 * (size_t(12) * 40 + 12)];  // texture red, atlas 3
    const float* right = &image.radiance.rgb[3 * (size_t(12) * 40 + 27)]; // texture green, atlas 1
    EXPECT_NEAR(left[0], 3.0f, 1e-5f);
    EXPECT_NEAR(left[1], 0.0f, 1e-5f);
    EXPECT_NEAR(right[0], 0.0f, 1e-5f);
    EXPECT_NEAR(right[1], 1.0f, 1e-5f);
}

TEST(SceneRender, AMirroredInstanceInterpolatesLikeTheMirroredCopy) {
    // One mesh placed twice, the second mirrored: Embree instances it; its hits must name the flattened triangle's
    // corners in the flattened (flipped) order. Radiance linear in world position then renders the same as two
    // plain copies.
    TriMesh plane = makePlane(1.0f, 2, 0.0f);
    TriMesh mirrored = plane;
    for (size_t v = 0; v < mirrored.vertexCount(); ++v) mirrored.positions[3 * v] *= -1.0f;
    for (size_t t = 0; t < mirrored.triangleCount(); ++t) std::swap(mirrored.indices[3 * t + 1], mirrored.indices[3 * t + 2]);
    auto write = [](const TestScene& scene, const char* name) {
        std::filesystem::path dir = std::filesystem::temp_directory_path() / name;
        std::filesystem::create_directories(dir);
        writeSceneGltf((dir / "scene.gltf").string(), scene);
        return readBundle((dir / "scene.gltf").string());
    };
    TestScene instanced;
    instanced.meshes = {{{plane, -1}}};
    instanced.nodes = json::array({{{"mesh", 0}, {"translation", {-0.6, 0.0, 0.0}}},
                                   {{"mesh", 0}, {"translation", {0.6, 0.0, 0.0}}, {"scale", {-1.0, 1.0, 1.0}}}});
    instanced.roots = {0, 1};
    TestScene copies;
    copies.meshes = {{{plane, -1}}, {{mirrored, -1}}};
    copies.nodes = json::array({{{"mesh", 0}, {"translation", {-0.6, 0.0, 0.0}}},
                                {{"mesh", 1}, {"translation", {0.6, 0.0, 0.0}}}});
    copies.roots = {0, 1};
    Bundle a = write(instanced, "prt_scene_render_mirror_instance"), b = write(copies, "prt_scene_render_mirror_copy");
    ASSERT_EQ(a.mesh.positions, b.mesh.positions);
    ASSERT_EQ(a.mesh.indices, b.mesh.indices);
    Surface surfaceA = decodeSurface(a, "instanced"), surfaceB = decodeSurface(b, "copies");
    ASSERT_TRUE(surfaceA.instancing);
    std::vector<float> rows(a.mesh.vertexCount() * 3);
    for (size_t v = 0; v < a.mesh.vertexCount(); ++v) {
        rows[3 * v] = 2.0f + a.mesh.positions[3 * v];
        rows[3 * v + 1] = 2.0f + a.mesh.positions[3 * v + 2];
        rows[3 * v + 2] = 1.0f;
    }
    RenderedImage ia = renderVertexRadiance(a.mesh, rows, topCamera(), &surfaceA);
    RenderedImage ib = renderVertexRadiance(b.mesh, rows, topCamera(), &surfaceB);
    size_t covered = 0;
    for (size_t p = 0; p < ia.coverage.size(); ++p) {
        ASSERT_EQ(ia.coverage[p], ib.coverage[p]) << p;
        covered += ia.coverage[p] > 0.5f;
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(ia.radiance.rgb[3 * p + c], ib.radiance.rgb[3 * p + c], 1e-4f) << p;
    }
    EXPECT_GT(covered, 400u);
}
