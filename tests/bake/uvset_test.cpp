// --uv-set: a texcoord set other than TEXCOORD_0, in readBundle's vertex order.
#include "bake.h"

#include "core.h"
#include "scene.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cstring>
#include <filesystem>

namespace prt {
namespace {

// A plain glTF binary of `mesh` with a second texcoord set, TEXCOORD_1 = TEXCOORD_0 / 2.
std::string planeWithTwoSets(const std::string& path, const TriMesh& mesh) {
    Bundle bundle;
    bundle.mesh = mesh;
    writeBundle(path, bundle);
    tinygltf::TinyGLTF gltf;
    tinygltf::Model model;
    std::string error, warning;
    if (!gltf.LoadBinaryFromFile(&model, &error, &warning, path)) throw std::runtime_error(error);
    model.extensions.clear(); // its checksum covers the buffer this adds to
    model.extensionsUsed.clear();
    std::vector<float> half(mesh.texcoords);
    for (float& t : half) t *= 0.5f;
    std::vector<unsigned char>& buffer = model.buffers[0].data;
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.size();
    view.byteLength = half.size() * sizeof(float);
    buffer.resize(buffer.size() + view.byteLength);
    std::memcpy(buffer.data() + view.byteOffset, half.data(), view.byteLength);
    model.bufferViews.push_back(view);
    tinygltf::Accessor accessor;
    accessor.bufferView = int(model.bufferViews.size()) - 1;
    accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    accessor.type = TINYGLTF_TYPE_VEC2;
    accessor.count = half.size() / 2;
    model.accessors.push_back(accessor);
    model.meshes[0].primitives[0].attributes["TEXCOORD_1"] = int(model.accessors.size()) - 1;
    if (!gltf.WriteGltfSceneToFile(&model, path, true, true, false, true)) throw std::runtime_error("write failed");
    return path;
}

TEST(UvSet, ReadsTheRequestedSetAndBakesWithIt) {
    auto folder = std::filesystem::temp_directory_path() / ("prt_bake_uvset_" + std::to_string(::getpid()));
    std::filesystem::create_directories(folder);
    TriMesh plane = makePlane(1.0f, 2);
    std::string path = planeWithTwoSets((folder / "two_sets.glb").string(), plane);
    EXPECT_EQ(readTexcoordSet(path, 0), plane.texcoords);
    std::vector<float> second = readTexcoordSet(path, 1);
    ASSERT_EQ(second.size(), plane.texcoords.size());
    for (size_t i = 0; i < second.size(); ++i) EXPECT_EQ(second[i], 0.5f * plane.texcoords[i]);
    try {
        readTexcoordSet(path, 2);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(e.problem().find("TEXCOORD_2"), std::string::npos) << e.what();
    }

    BakeOptions options;
    options.input = path;
    options.output = (folder / "baked.glb").string();
    options.resolution = 16;
    options.order = 1;
    options.samples = 8;
    options.uvSet = 1;
    BakedAtlas baked = bakeAtlas(options);
    EXPECT_EQ(baked.mesh.texcoords, second);
    EXPECT_EQ(baked.samples.texel.size(), 8u * 8u); // [0, 0.5]^2 of a 16^2 atlas
    std::filesystem::remove_all(folder);
}

} // namespace
} // namespace prt
