// OBJ with MTL read as a scene (readObjScene): Kd as the base colour factor, and the MTL found next to the OBJ,
// or next to its target when the OBJ is a symbolic link, as `prt run` links inputs into a job's folder.
#include "mesh.h"
#include "mesh_test_util.h"

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

// Old MTL files write names in Latin-1 (assimp's regr01.mtl has "Terraind\xe6k"); glTF stores UTF-8 only, so the
// name is transcoded and the scene writes (it failed with nlohmann's "invalid UTF-8 byte" as an internal error).
class ObjSceneFiles : public test::ScratchTest {};

TEST_F(ObjSceneFiles, Latin1NamesBecomeUtf8AndTheSceneWrites) {
    write("m.mtl", "newmtl Terraind\xe6k\nKd 0.2 0.6 0.1\n");
    const std::string obj = write("m\xe6.obj", "\xef\xbb\xbfmtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                                "usemtl Terraind\xe6k\nf 1 2 3\n");
    ASSERT_TRUE(objHasMaterials(obj)); // the UTF-8 byte order mark before `mtllib` is skipped
    Bundle scene = readObjScene(obj);
    ASSERT_TRUE(scene.asset);
    ASSERT_GE(scene.asset->materials.size(), 1u);
    EXPECT_EQ(scene.asset->materials[0].name, "Terraind\xc3\xa6k");
    EXPECT_FLOAT_EQ(scene.asset->materials[0].baseColorFactor[1], 0.6f);
    EXPECT_NO_THROW(writeBundle(path("m.glb"), scene));
    EXPECT_NE(read("m.glb").find("Terraind\xc3\xa6k"), std::string::npos);
}

// An MTL that is not there (assimp's cube_mtllib_after_g.obj names a .mat that does not exist) costs the
// materials, not the geometry; one outside the OBJ's folder is still refused.
TEST_F(ObjSceneFiles, AMissingMtlIsReadWithoutMaterialsAndOneOutsideIsRefused) {
    const std::string missing = write("a.obj", "mtllib nothere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_FALSE(objHasMaterials(missing));
    EXPECT_EQ(loadMesh(missing).triangleCount(), 1u);
    const std::string outside = write("b.obj", "mtllib ../elsewhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write("../elsewhere.mtl", "newmtl x\n");
    try {
        objHasMaterials(outside);
        ADD_FAILURE() << "an MTL outside the folder was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("outside the OBJ file's folder"), std::string::npos) << e.what();
    }
    std::filesystem::remove(path("../elsewhere.mtl"));
}

} // namespace prt
