// meshprep on a glTF scene whose NORMAL holds zero vectors (exporters write them at degenerate corners): those
// vertices get normals computed from their triangles, every authored normal is kept, and transfer accepts the result.
#include "mesh.h"

#include "scene.h"
#include "scene_gltf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace prt {
namespace {

using nlohmann::json;
using namespace prt::test;

TEST(SceneNormals, ZeroAuthoredNormalsAreComputedAndTheOthersKept) {
    TriMesh plane = makePlane(2.0f, 2, 0.0f); // 9 vertices, normals +Y
    // Tilt every authored normal a little, so that a kept one is told from a computed one (+Y exactly), and zero
    // two of them.
    for (size_t v = 0; v < plane.vertexCount(); ++v) {
        plane.normals[3 * v] = 0.6f, plane.normals[3 * v + 1] = 0.8f, plane.normals[3 * v + 2] = 0.0f;
    }
    for (size_t v : {size_t(0), size_t(4)}) plane.normals[3 * v] = plane.normals[3 * v + 1] = plane.normals[3 * v + 2] = 0.0f;
    TestScene scene;
    scene.meshes = {{{plane, -1}}};
    scene.nodes = json::array({{{"mesh", 0}}});
    scene.roots = {0};
    std::filesystem::path dir = std::filesystem::temp_directory_path() / ("prt_scene_normals_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "plane.gltf").string();
    writeSceneGltf(path, scene);
    MeshprepOptions options;
    options.input = path;
    PreparedScene prepared = prepareScene(options, readBundle(path));
    const TriMesh& mesh = prepared.bundle.mesh;
    ASSERT_EQ(mesh.vertexCount(), plane.vertexCount());
    for (size_t v = 0; v < mesh.vertexCount(); ++v) {
        const float* n = &mesh.normals[3 * v];
        if (v == 0 || v == 4) { // computed from the flat plane's triangles
            EXPECT_NEAR(n[0], 0.0f, 1e-6f) << v;
            EXPECT_NEAR(n[1], 1.0f, 1e-6f) << v;
        } else { // authored, kept
            EXPECT_FLOAT_EQ(n[0], 0.6f) << v;
            EXPECT_FLOAT_EQ(n[1], 0.8f) << v;
        }
    }
    EXPECT_EQ(prepared.report["scene"]["zero_normals_repaired"], 2);
    std::filesystem::remove_all(dir);
}

} // namespace
} // namespace prt
