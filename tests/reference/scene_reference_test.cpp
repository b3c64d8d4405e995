// Scenes through the path tracer (ReferenceOptions::surface) against scene transfer: a white floor beside a red
// wall turns red by the wall's bounce, in both, by the same amount within the reference's noise.
#include "material.h"
#include "reference.h"
#include "scene.h"
#include "corner_scene.h"
#include "scene_gltf.h"
#include "transfer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>

using namespace prt;
using namespace prt::test;
using nlohmann::json;

TEST(SceneReference, AWhiteFloorBesideARedWallTurnsRedAsTransferSays) {
    TriMesh floor = makePlane(2.0f, 8, 0.0f);
    TriMesh wall = wallAtXOne(2.0f, 8);
    TestScene scene;
    scene.meshes = {{{floor, 0}}, {{wall, 1}}};
    scene.nodes = json::array({{{"mesh", 0}}, {{"mesh", 1}}});
    scene.roots = {0, 1};
    scene.materials = json::array({{{"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.8, 0.8, 1.0}}, {"metallicFactor", 0.0}}}},
                                   {{"pbrMetallicRoughness", {{"baseColorFactor", {0.9, 0.1, 0.1, 1.0}}, {"metallicFactor", 0.0}}}}});
    std::filesystem::path dir = std::filesystem::temp_directory_path() / "prt_scene_reference";
    std::filesystem::create_directories(dir);
    writeSceneGltf((dir / "scene.gltf").string(), scene);
    Bundle bundle = readBundle((dir / "scene.gltf").string());
    Surface surface = decodeSurface(bundle, "scene.gltf");

    // Floor vertices next to the wall (x > 0.5, away from the open edges in z).
    std::vector<uint32_t> rows;
    for (uint32_t v = 0; v < floor.vertexCount(); ++v)
        if (bundle.mesh.positions[3 * v] > 0.5f && bundle.mesh.positions[3 * v] < 0.9f && std::fabs(bundle.mesh.positions[3 * v + 2]) < 0.6f) rows.push_back(v);
    ASSERT_GE(rows.size(), 3u);

    EnvironmentMap sky;
    sky.radiance.width = 16;
    sky.radiance.height = 8;
    sky.radiance.rgb.assign(16 * 8 * 3, 1.0f);
    ReferenceOptions reference;
    reference.bounces = 1;
    reference.samples = 4096;
    reference.surface = &surface;
    ReferenceRadiance traced = referenceVertexRadianceAt(bundle.mesh, sky, rows, reference);

    TransferOptions options;
    options.mode = TransferMode::Interreflected;
    options.order = 1; // a constant sky is band 0 alone: no truncation error
    options.samples = 4096;
    options.bounces = 1;
    options.progress = false;
    options.surface = &surface;
    Transfer transfer = computeTransfer(bundle.mesh, options);
    double sumRed = 0.0, sumGreen = 0.0;
    for (size_t i = 0; i < rows.size(); ++i) {
        uint32_t v = rows[i];
        for (int c = 0; c < 3; ++c) {
            double relit = bundle.mesh.albedo[3 * v + c] * transfer.coefficients[3 * v + c] * std::sqrt(4.0 * std::numbers::pi);
            // The reference's noise (quoted by it) plus the transfer's own quasi-Monte Carlo error.
            double tolerance = 4.0 * traced.standardError[3 * i + c] + 0.01 * relit;
            EXPECT_NEAR(relit, traced.radiance[3 * i + c], tolerance) << "vertex " << v << " channel " << c;
        }
        sumRed += traced.radiance[3 * i];
        sumGreen += traced.radiance[3 * i + 1];
    }
    // The floor is white (0.8 in every channel); only the wall's red bounce makes red exceed green.
    EXPECT_GT(sumRed, 1.05 * sumGreen);
}
