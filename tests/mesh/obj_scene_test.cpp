// OBJ with MTL read as a scene (readObjScene): Kd as the base colour factor, and the MTL found next to the OBJ,
// or next to its target when the OBJ is a symbolic link, as `prt run` links inputs into a job's folder.
#include "mesh.h"

#include "core.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace prt {
namespace {

namespace fs = std::filesystem;

void writeText(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

} // namespace

TEST(ObjScene, ReadsTheMtlNextToTheTargetOfASymbolicLink) {
    fs::path root = fs::temp_directory_path() / ("prt_obj_scene_" + std::to_string(::getpid()));
    fs::remove_all(root);
    fs::create_directories(root / "asset");
    fs::create_directories(root / "job");
    writeText(root / "asset/m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
    writeText(root / "asset/m.mtl", "newmtl red\nKd 0.8 0.2 0.1\n");
    fs::create_symlink(root / "asset/m.obj", root / "job/input-mesh.obj");
    for (const fs::path& path : {root / "asset/m.obj", root / "job/input-mesh.obj"}) {
        Bundle scene = readObjScene(path.string());
        ASSERT_TRUE(scene.asset) << path;
        ASSERT_GE(scene.asset->materials.size(), 1u);
        const MaterialRecord& red = scene.asset->materials[0];
        EXPECT_FLOAT_EQ(red.baseColorFactor[0], 0.8f) << path;
        EXPECT_FLOAT_EQ(red.baseColorFactor[1], 0.2f) << path;
        EXPECT_FLOAT_EQ(red.baseColorFactor[2], 0.1f) << path;
        EXPECT_EQ(scene.mesh.triangleCount(), 1u);
    }
    // A link whose target's folder lacks the MTL still fails, naming the link.
    fs::remove(root / "asset/m.mtl");
    try {
        readObjScene((root / "job/input-mesh.obj").string());
        ADD_FAILURE() << "a missing MTL was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.exitCode(), kExitInput);
        EXPECT_NE(std::string(e.what()).find("input-mesh.obj"), std::string::npos) << e.what();
    }
    fs::remove_all(root);
}

} // namespace prt
