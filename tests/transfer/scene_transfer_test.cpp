// Transfer over glTF scenes (TransferOptions::surface): irradiance transfer with the albedo of the material at
// every hit. Closed forms: the open cavity's Neumann series per colour channel, instances against copies,
// mirrored instances against mirrored meshes, cut-out shadows, metallic surfaces that bounce nothing.
#include "material.h"
#include "scene.h"
#include "corner_scene.h"
#include "scene_gltf.h"
#include "transfer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <numbers>

using namespace prt;
using namespace prt::test;
using nlohmann::json;

namespace {

constexpr double kPi = std::numbers::pi;

TransferOptions quietOptions(TransferMode mode, int order, int samples, int bounces = 0) {
    TransferOptions options;
    options.mode = mode;
    options.order = order;
    options.samples = samples;
    options.bounces = bounces;
    options.progress = false;
    return options;
}

Bundle readScene(const TestScene& scene, const std::string& name) {
    std::filesystem::path dir = std::filesystem::temp_directory_path() / ("prt_scene_transfer_" + name);
    std::filesystem::create_directories(dir);
    writeSceneGltf((dir / "scene.gltf").string(), scene);
    return readBundle((dir / "scene.gltf").string());
}

// Transfer of a scene with its materials.
Transfer sceneTransfer(const Bundle& bundle, TransferOptions options) {
    Surface surface = decodeSurface(bundle, "scene");
    options.surface = &surface;
    return computeTransfer(bundle.mesh, options);
}

json diffuse(double r, double g, double b, double metallic = 0.0) {
    return {{"pbrMetallicRoughness", {{"baseColorFactor", {r, g, b, 1.0}}, {"metallicFactor", metallic}}}};
}

// The DC row under constant radiance 1 (L_00 = sqrt(4 pi)): what a white surface reflects.
double whiteRadiance(const Transfer& transfer, size_t row, int channel) {
    size_t stride = size_t(transfer.order) * transfer.order * 3;
    return transfer.coefficients[row * stride + channel] * std::sqrt(4.0 * kPi);
}

TriMesh translated(TriMesh mesh, float dx) {
    for (size_t v = 0; v < mesh.vertexCount(); ++v) mesh.positions[3 * v] += dx;
    return mesh;
}

} // namespace

TEST(SceneTransfer, ColouredCavityFollowsTheNeumannSeriesPerChannel) {
    const double opening = 60.0 * kPi / 180.0;
    const double rho[3] = {0.8, 0.6, 0.3};
    TestScene scene;
    scene.meshes = {{{makeOpenCavity(1.0f, float(opening), 24, 48), 0}}};
    scene.nodes = json::array({{{"mesh", 0}}});
    scene.roots = {0};
    scene.materials = json::array({diffuse(rho[0], rho[1], rho[2])});
    Bundle bundle = readScene(scene, "cavity");
    const double formFactor = (1.0 - std::cos(opening)) / 2.0;
    for (int bounces = 0; bounces <= 3; ++bounces) {
        Transfer transfer = sceneTransfer(bundle, quietOptions(TransferMode::Interreflected, 3, 1024, bounces));
        for (int c = 0; c < 3; ++c) {
            // Outgoing radiance is the receiver's albedo times its irradiance transfer: rho f sum_k (rho (1 - f))^k.
            double expected = 0.0;
            for (int k = 0; k <= bounces; ++k) expected += rho[c] * formFactor * std::pow(rho[c] * (1.0 - formFactor), k);
            double sum = 0.0;
            int count = 0;
            for (size_t v = 0; v < bundle.mesh.vertexCount(); ++v) {
                double polar = std::acos(std::clamp(double(bundle.mesh.positions[3 * v + 1]), -1.0, 1.0));
                if (polar < opening + 20.0 * kPi / 180.0) continue; // away from the rim
                sum += bundle.mesh.albedo[3 * v + c] * whiteRadiance(transfer, v, c);
                ++count;
            }
            ASSERT_GT(count, 100);
            EXPECT_NEAR(sum / count, expected, 0.01 * expected) << bounces << " bounces, channel " << c;
        }
    }
}

TEST(SceneTransfer, TwoInstancesOfAMeshGiveTheRowsOfTwoCopies) {
    TriMesh sphere = makeSphere(0.5f, 8, 16);
    TriMesh floor = makePlane(6.0f, 6, -0.6f);
    TestScene instanced, copies;
    instanced.meshes = {{{floor, 0}}, {{sphere, 1}}};
    instanced.nodes = json::array({{{"mesh", 0}}, {{"mesh", 1}, {"translation", {-1.0, 0.0, 0.0}}},
                                   {{"mesh", 1}, {"translation", {1.0, 0.0, 0.0}}}});
    instanced.roots = {0, 1, 2};
    instanced.materials = json::array({diffuse(0.8, 0.8, 0.8), diffuse(0.9, 0.2, 0.2)});
    copies = instanced;
    copies.meshes = {{{floor, 0}}, {{translated(sphere, -1.0f), 1}}, {{translated(sphere, 1.0f), 1}}};
    copies.nodes = json::array({{{"mesh", 0}}, {{"mesh", 1}}, {{"mesh", 2}}});
    Bundle a = readScene(instanced, "instances"), b = readScene(copies, "copies");
    ASSERT_EQ(a.mesh.vertexCount(), b.mesh.vertexCount());
    TransferOptions options = quietOptions(TransferMode::Interreflected, 3, 256, 2);
    Transfer ta = sceneTransfer(a, options), tb = sceneTransfer(b, options);
    ASSERT_EQ(ta.coefficients.size(), tb.coefficients.size());
    for (size_t i = 0; i < ta.coefficients.size(); ++i)
        ASSERT_NEAR(ta.coefficients[i], tb.coefficients[i], 1e-5f) << "value " << i;
    // Each instance sees the other one: the two spheres' rows are mirror images, not equal.
    size_t sphereRows = sphere.vertexCount(), first = floor.vertexCount();
    double difference = 0.0;
    for (size_t v = 0; v < sphereRows; ++v) difference += std::fabs(whiteRadiance(ta, first + v, 0) - whiteRadiance(ta, first + sphereRows + v, 0));
    EXPECT_GT(difference / double(sphereRows), 1e-3);
}

TEST(SceneTransfer, AMirroredInstanceEqualsTheMirroredMesh) {
    // An asymmetric corner: a floor and a wall on its +X side.
    TriMesh floor = makePlane(2.0f, 4, 0.0f);
    TriMesh wall = wallAtXOne(2.0f, 4);
    TestScene scene;
    scene.meshes = {{{floor, 0}, {wall, 0}}};
    scene.nodes = json::array({{{"mesh", 0}, {"scale", {-1.0, 1.0, 1.0}}}});
    scene.roots = {0};
    scene.materials = json::array({diffuse(0.7, 0.7, 0.7)});
    TestScene mirrored = scene;
    auto mirror = [](TriMesh mesh) {
        for (size_t v = 0; v < mesh.vertexCount(); ++v) mesh.positions[3 * v] *= -1.0f, mesh.normals[3 * v] *= -1.0f;
        for (size_t t = 0; t < mesh.triangleCount(); ++t) std::swap(mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]);
        return mesh;
    };
    mirrored.meshes = {{{mirror(floor), 0}, {mirror(wall), 0}}};
    mirrored.nodes = json::array({{{"mesh", 0}}});
    Bundle a = readScene(scene, "mirror_instance"), b = readScene(mirrored, "mirror_mesh");
    EXPECT_TRUE(a.asset->receivers[0].mirrored);
    EXPECT_EQ(a.mesh.indices, b.mesh.indices);
    TransferOptions options = quietOptions(TransferMode::Interreflected, 3, 256, 1);
    Transfer ta = sceneTransfer(a, options), tb = sceneTransfer(b, options);
    for (size_t i = 0; i < ta.coefficients.size(); ++i) ASSERT_NEAR(ta.coefficients[i], tb.coefficients[i], 1e-5f) << i;
    EXPECT_EQ(ta.stats.backFaceHits, tb.stats.backFaceHits);
}

TEST(SceneTransfer, AMaskCutOutCastsTheShadowOfItsOpaqueTexelsOnly) {
    // A floor under a square whose texture is opaque for u < 0.5 (x < 0) and cut out for u > 0.5, against a floor
    // under only the opaque half as geometry: the same shadow.
    TriMesh floor = makePlane(4.0f, 16, 0.0f);
    TriMesh square = makePlane(2.0f, 1, 0.5f), half = makePlane(2.0f, 1, 0.5f);
    for (size_t v = 0; v < half.vertexCount(); ++v) half.positions[3 * v] = half.positions[3 * v] < 0 ? -1.0f : 0.0f;
    json mask = {{"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"baseColorTexture", {{"index", 0}}}}},
                 {"alphaMode", "MASK"}};
    TestScene cut;
    cut.meshes = {{{floor, 0}}, {{square, 1}}};
    cut.nodes = json::array({{{"mesh", 0}}, {{"mesh", 1}}});
    cut.roots = {0, 1};
    cut.materials = json::array({diffuse(1, 1, 1), mask});
    cut.textures = json::array({{{"source", 0}, {"sampler", 0}}});
    cut.samplers = json::array({{{"magFilter", 9728}, {"wrapS", 33071}}});
    cut.images = json::array({{{"uri", pngDataUri(pngBytes(2, 1, {255, 255, 255, 255, 255, 255, 255, 0}))}}});
    TestScene solid = cut;
    solid.meshes = {{{floor, 0}}, {{half, 1}}};
    solid.materials = json::array({diffuse(1, 1, 1), diffuse(1, 1, 1)});
    solid.textures = solid.samplers = solid.images = json::array();
    Bundle a = readScene(cut, "mask"), b = readScene(solid, "half");
    TransferOptions options = quietOptions(TransferMode::Shadowed, 2, 1024);
    Transfer ta = sceneTransfer(a, options), tb = sceneTransfer(b, options);
    size_t shadowed = 0;
    for (size_t v = 0; v < floor.vertexCount(); ++v) {
        double cutRadiance = whiteRadiance(ta, v, 0), solidRadiance = whiteRadiance(tb, v, 0);
        EXPECT_NEAR(cutRadiance, solidRadiance, 0.01) << "floor vertex " << v;
        shadowed += solidRadiance < 0.9;
    }
    EXPECT_GT(shadowed, 10u); // the opaque half does shadow the floor
}

TEST(SceneTransfer, MetallicSurfacesReflectNoDiffuseLight) {
    // A floor beside a wall: with a metallic wall the floor's bounces add exactly nothing.
    TriMesh floor = makePlane(2.0f, 6, 0.0f);
    TriMesh wall = wallAtXOne(2.0f, 6);
    TestScene scene;
    scene.meshes = {{{floor, 0}}, {{wall, 1}}};
    scene.nodes = json::array({{{"mesh", 0}}, {{"mesh", 1}}});
    scene.roots = {0, 1};
    scene.materials = json::array({diffuse(0.8, 0.8, 0.8), diffuse(0.9, 0.9, 0.9, 1.0)});
    Bundle metal = readScene(scene, "metal");
    Transfer direct = sceneTransfer(metal, quietOptions(TransferMode::Shadowed, 3, 512));
    Transfer bounced = sceneTransfer(metal, quietOptions(TransferMode::Interreflected, 3, 512, 2));
    for (size_t i = 0; i < floor.vertexCount() * 27; ++i) ASSERT_EQ(bounced.coefficients[i], direct.coefficients[i]) << i;
    scene.materials[1] = diffuse(0.9, 0.9, 0.9, 0.0); // the control: a white wall does bounce light
    Bundle white = readScene(scene, "white_wall");
    Transfer lit = sceneTransfer(white, quietOptions(TransferMode::Interreflected, 3, 512, 2));
    double added = 0.0;
    for (size_t v = 0; v < floor.vertexCount(); ++v) added += whiteRadiance(lit, v, 0) - whiteRadiance(direct, v, 0);
    EXPECT_GT(added / double(floor.vertexCount()), 0.01);
}
