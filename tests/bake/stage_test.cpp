// The `prt bake` stage end to end on small inputs: outputs and their references, and bad input that must leave
// nothing behind.
#include "bake.h"

#include "core.h"
#include "runtime.h"
#include "scene.h"
#include "scene_gltf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace prt {
namespace {

namespace fs = std::filesystem;

// A fresh folder per test; its files are the stage's outputs.
struct Folder {
    fs::path path;
    explicit Folder(const std::string& name)
        : path(fs::temp_directory_path() / ("prt_bake_stage_" + std::to_string(::getpid()) + "_" + name)) {
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~Folder() { fs::remove_all(path); }
    std::string operator/(const std::string& file) const { return (path / file).string(); }
    size_t files() const { return size_t(std::distance(fs::directory_iterator(path), fs::directory_iterator())); }
};

std::string writeMesh(const Folder& folder, const std::string& name, const TriMesh& mesh) {
    Bundle bundle;
    bundle.mesh = mesh;
    std::string path = folder / name;
    writeBundle(path, bundle);
    return path;
}

BakeOptions smallBake(const std::string& input, const std::string& output) {
    BakeOptions options;
    options.input = input;
    options.output = output;
    options.resolution = 32;
    options.order = 2;
    options.samples = 32;
    options.toolVersion = "test";
    return options;
}

// Runs the bake expecting prt::Error; returns it after checking that only the inputs remain in the folder.
Error expectFailureWithoutOutput(const BakeOptions& options, const Folder& folder, size_t inputs) {
    try {
        runBake(options);
    } catch (const Error& e) {
        EXPECT_EQ(folder.files(), inputs) << "the failed bake left files behind: " << e.what();
        return e;
    }
    ADD_FAILURE() << "expected an error";
    return Error("", "", "");
}

TEST(BakeStage, UvsOutsideTheUnitSquareWithoutAWrapMode) {
    Folder folder("outside");
    TriMesh plane = makePlane(1.0f, 2);
    plane.texcoords[0] = 1.5f;
    BakeOptions options = smallBake(writeMesh(folder, "low.glb", plane), folder / "out.glb");
    Error e = expectFailureWithoutOutput(options, folder, 1);
    EXPECT_NE(e.problem().find("outside [0, 1]"), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), options.input);
}

TEST(BakeStage, OverlappingUvs) {
    Folder folder("overlap");
    TriMesh plane = makePlane(1.0f, 2);
    for (size_t v = 0; v < plane.vertexCount(); ++v) plane.texcoords[2 * v] = 0.5f * plane.texcoords[2 * v] + 0.25f;
    TriMesh twice = mergeMeshes({plane, makePlane(1.0f, 2, 1.0f)}); // the second copy keeps UVs [0, 1]^2
    Error e = expectFailureWithoutOutput(smallBake(writeMesh(folder, "low.glb", twice), folder / "out.glb"), folder, 1);
    EXPECT_NE(e.problem().find("overlap"), std::string::npos) << e.what();
}

// Texcoords that all meet in one point (assimp's WusonOBJ.obj has a single `vt`) cover no texel: refused, naming
// the zero-area triangles and --generate-atlas, which bakes into a generated atlas instead.
TEST(BakeStage, DegenerateUvsAreRefusedAndGenerateAtlasBakesThem) {
    Folder folder("degenerate");
    TriMesh plane = makePlane(1.0f, 2);
    for (float& t : plane.texcoords) t = 0.5f;
    BakeOptions options = smallBake(writeMesh(folder, "low.glb", plane), folder / "out.glb");
    Error e = expectFailureWithoutOutput(options, folder, 1);
    EXPECT_NE(e.problem().find("8 of 8 triangles have zero UV area"), std::string::npos) << e.what();
    EXPECT_NE(e.problem().find("--generate-atlas"), std::string::npos) << e.what();
    options.generateAtlas = true;
    runBake(options);
    Bundle bundle = readBundle(options.output);
    const Layer* transfer = findLayer(bundle, "texel_transfer");
    ASSERT_TRUE(transfer);
    EXPECT_EQ(transfer->params["atlas"]["generated"], true);
    ASSERT_EQ(bundle.mesh.texcoords.size(), 2 * bundle.mesh.vertexCount());
    EXPECT_TRUE(std::any_of(bundle.mesh.texcoords.begin(), bundle.mesh.texcoords.end(),
                            [](float t) { return t != 0.5f; })); // the generated atlas, not the collapsed UVs
    options.uvSet = 0; // both at once are a usage error
    EXPECT_EQ(expectFailureWithoutOutput(options, folder, folder.files()).exitCode(), kExitUsage);
}

TEST(BakeStage, ResolutionOutOfRange) {
    Folder folder("resolution");
    std::string input = writeMesh(folder, "low.glb", makePlane(1.0f, 2));
    for (int resolution : {0, kMaxBakeResolution + 1}) {
        BakeOptions options = smallBake(input, folder / "out.glb");
        options.resolution = resolution;
        Error e = expectFailureWithoutOutput(options, folder, 1);
        EXPECT_EQ(e.exitCode(), kExitUsage);
        EXPECT_EQ(e.place(), "--resolution");
    }
}

TEST(BakeStage, HighMeshThatDoesNotCoverTheLowOne) {
    Folder folder("cover");
    BakeOptions options = smallBake(writeMesh(folder, "low.glb", makePlane(1.0f, 2)), folder / "out.glb");
    options.high = writeMesh(folder, "high.glb", makePlane(0.4f, 8, 0.001f)); // covers the middle only
    Error e = expectFailureWithoutOutput(options, folder, 2);
    EXPECT_EQ(e.file(), options.high);
    EXPECT_NE(e.problem().find("does not cover"), std::string::npos) << e.what();
}

TEST(BakeStage, PlaneUnderAHighPlaneWritesReferencedTexturesAndAFlatNormalMap) {
    Folder folder("plane");
    BakeOptions options = smallBake(writeMesh(folder, "low.glb", makePlane(1.0f, 2)), folder / "out.glb");
    options.high = writeMesh(folder, "high.glb", makePlane(1.2f, 10, 0.002f));
    options.format = TexelFormat::Float;
    runBake(options);
    Bundle bundle = readBundle(options.output);
    const Layer* transfer = findLayer(bundle, "texel_transfer");
    const Layer* normal = findLayer(bundle, "normal_map");
    ASSERT_TRUE(transfer && normal);
    EXPECT_EQ(transfer->domain, "texel");
    EXPECT_EQ(transfer->shape, (std::vector<uint64_t>{32 * 32, 4, 3}));
    std::string exr = folder / transfer->params["uri"].get<std::string>();
    EXPECT_EQ(transfer->params["hash"], hashFile(exr));
    int width = 32, height = 32, coefficients = 4;
    std::vector<float> texels = readCoefficientExr(exr, width, height, coefficients);
    // An open plane sees the whole upper hemisphere: every texel is the clamped-cosine transfer about +Y,
    // T_00 = A_0 Y_00 / pi = 0.5 / sqrt(pi) (gutters too, as push-pull fills them from covered texels).
    for (size_t t = 0; t < size_t(width) * height; ++t)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(texels[t * 12 + c], 0.5 / std::sqrt(M_PI), 1e-5) << "texel " << t;
    std::vector<uint8_t> normals = readImage8(folder / normal->params["uri"].get<std::string>(), width, height, 3);
    for (size_t t = 0; t < normals.size() / 3; ++t) {
        EXPECT_NEAR(normals[3 * t], 127.5, 0.5);
        EXPECT_NEAR(normals[3 * t + 1], 127.5, 0.5);
        EXPECT_EQ(normals[3 * t + 2], 255);
    }
    EXPECT_EQ(folder.files(), 6u); // low, high, bundle, transfer EXR, surface EXR, normal map
}

TEST(BakeStage, BoxRoomWithoutUvsGetsAGeneratedAtlasAndU8Layers) {
    Folder folder("room");
    TriMesh room = makeBoxRoom(2.0f, 2);
    BakeOptions options = smallBake(writeMesh(folder, "room.glb", room), folder / "room_baked.glb");
    options.format = TexelFormat::U8;
    runBake(options);
    Bundle bundle = readBundle(options.output);
    ASSERT_EQ(bundle.mesh.texcoords.size(), 2 * bundle.mesh.vertexCount());
    const Layer* transfer = findLayer(bundle, "texel_transfer");
    ASSERT_TRUE(transfer);
    EXPECT_EQ(transfer->params["atlas"]["generated"], true);
    EXPECT_EQ(transfer->params["atlas"]["charts"], 6);
    std::ifstream in(folder / transfer->params["uri"].get<std::string>());
    nlohmann::json sidecar = nlohmann::json::parse(in);
    ASSERT_EQ(sidecar["layers"].size(), 4u);
    for (const auto& layer : sidecar["layers"]) {
        EXPECT_TRUE(fs::exists(folder / layer["uri"].get<std::string>()));
        // A closed room admits no distant light: transfer is the exact unshadowed part minus an estimate of all
        // of it, zero up to the quadrature error of 32 directions.
        EXPECT_LT(std::abs(layer["min"].get<double>()), 0.01);
        EXPECT_LT(std::abs(layer["max"].get<double>()), 0.01);
    }
}

// A plane in the shadow and bounce light of a ball whose UVs are collapsed into one corner (it covers no texel);
// `detail` refines both, `lift` raises the plane (a high mesh for the plane of detail 1).
TriMesh planeUnderABall(int detail, float lift = 0.0f) {
    TriMesh ball = makeSphere(0.3f, 8 * detail, 16 * detail);
    for (size_t v = 0; v < ball.vertexCount(); ++v) ball.positions[3 * v + 1] += 0.5f;
    ball.texcoords.assign(2 * ball.vertexCount(), 1.0f);
    return mergeMeshes({makePlane(2.0f, 4 * detail, lift), ball});
}

// Same inputs and seed, any thread count: the same bits, bounces included.
TEST(BakeStage, ResultDoesNotDependOnTheThreadCount) {
    Folder folder("threads");
    BakeOptions options = smallBake(writeMesh(folder, "scene.glb", planeUnderABall(1)), folder / "unused.glb");
    options.bounces = 2;
    options.albedo = {0.8f, 0.7f, 0.6f};
    options.albedoOverride = true;
    options.seed = 5;
    options.threads = 1;
    BakedAtlas one = bakeAtlas(options);
    options.threads = 2;
    BakedAtlas two = bakeAtlas(options);
    ASSERT_EQ(one.transfer.size(), two.transfer.size());
    EXPECT_EQ(std::memcmp(one.transfer.data(), two.transfer.data(), one.transfer.size() * sizeof(float)), 0);
    EXPECT_EQ(one.normals, two.normals);
    float lo = 1e9f, hi = -1e9f; // not trivially constant: shadow and bounce light vary over the plane
    for (size_t t = 0; t < one.transfer.size(); t += 12) {
        lo = std::min(lo, one.transfer[t]);
        hi = std::max(hi, one.transfer[t]);
    }
    EXPECT_GT(hi - lo, 0.01f);
}

// The bounce layer is what the bounces add: transfer minus it is the shadowed bake of the same seed (fill and
// stitching are linear), so a hybrid relight can send cone lights through it without counting direct light twice.
TEST(BakeStage, TransferMinusItsBouncePartIsTheShadowedBake) {
    Folder folder("bounce_part");
    BakeOptions options = smallBake(writeMesh(folder, "scene.glb", planeUnderABall(1)), folder / "unused.glb");
    options.albedo = {0.8f, 0.7f, 0.6f};
    options.albedoOverride = true;
    options.seed = 3;
    options.bounces = 2;
    BakedAtlas interreflected = bakeAtlas(options);
    options.bounces = 0;
    BakedAtlas shadowed = bakeAtlas(options);
    EXPECT_TRUE(shadowed.bounce.empty());
    ASSERT_EQ(interreflected.bounce.size(), shadowed.transfer.size());
    double largest = 0.0, bounced = 0.0;
    for (size_t i = 0; i < shadowed.transfer.size(); ++i) {
        largest = std::max(largest, std::abs(double(interreflected.transfer[i]) - interreflected.bounce[i] -
                                             shadowed.transfer[i]));
        bounced = std::max(bounced, std::abs(double(interreflected.bounce[i])));
    }
    EXPECT_LT(largest, 1e-5);
    EXPECT_GT(bounced, 0.01) << "the ball and the plane light each other";
    // The surface layer: unit normals everywhere, coverage exactly the covered texels.
    size_t covered = 0;
    for (size_t t = 0; t < interreflected.surface.size() / kTexelSurfaceChannels; ++t) {
        const float* row = &interreflected.surface[t * kTexelSurfaceChannels];
        EXPECT_NEAR(std::sqrt(row[3] * row[3] + row[4] * row[4] + row[5] * row[5]), 1.0f, 1e-5f);
        covered += row[9] == 1.0f;
    }
    EXPECT_EQ(covered, interreflected.samples.texel.size());
}

// ---- shards ------------------------------------------------------------------------------------------------------

// Bakes `options` as `count` texel-range shards into their own folder; returns the shard files.
std::vector<std::string> bakeShards(BakeOptions options, const Folder& folder, int count) {
    std::vector<std::string> files;
    options.shardCount = count;
    for (int i = 0; i < count; ++i) {
        options.shardIndex = i;
        options.output = folder / ("shard-" + std::to_string(i) + ".glb");
        runBake(options);
        files.push_back(options.output);
    }
    EXPECT_EQ(folder.files(), size_t(count)) << "shards write their bundle only, no textures";
    return files;
}

// The unsharded bake and the merge of 3 shards (given out of order) write the same files, bit for bit.
void expectMergedShardsEqualTheWholeBake(BakeOptions options, const std::string& name) {
    Folder whole(name + "_whole"), parts(name + "_parts"), merged(name + "_merged");
    options.output = whole / "baked.glb";
    runBake(options);
    std::vector<std::string> shards = bakeShards(options, parts, 3);
    options.output = merged / "baked.glb";
    options.shardFiles = {shards[2], shards[0], shards[1]};
    runBake(options);
    ASSERT_EQ(merged.files(), whole.files());
    for (const fs::directory_entry& file : fs::directory_iterator(whole.path))
        EXPECT_EQ(readFileBytes(merged / file.path().filename().string()), readFileBytes(file.path().string()))
            << file.path().filename() << " differs after the merge";
}

TEST(BakeShards, MergedShardsEqualTheUnshardedBakeInHalf) {
    Folder inputs("shards_half_in");
    BakeOptions options = smallBake(writeMesh(inputs, "scene.glb", planeUnderABall(1)), "");
    expectMergedShardsEqualTheWholeBake(options, "shards_half");
}

TEST(BakeShards, AScenesMergedShardsEqualItsUnshardedBake) {
    // A glTF scene: a floor and a ball placed twice, once mirrored (Embree instances), with a coloured material,
    // interreflected, its atlas generated over every placement.
    Folder inputs("shards_scene_in");
    test::TestScene scene;
    scene.meshes = {{test::TestPrimitive{makePlane(4.0f, 4, -0.5f), 0, {}, {}}},
                    {test::TestPrimitive{makeSphere(0.4f, 8, 12), 1, {}, {}}}};
    scene.nodes = nlohmann::json::array({{{"mesh", 0}}, {{"mesh", 1}, {"translation", {-0.6, 0.0, 0.0}}},
                                         {{"mesh", 1}, {"translation", {0.6, 0.0, 0.0}}, {"scale", {-1.0, 1.0, 1.0}}}});
    scene.roots = {0, 1, 2};
    scene.materials = nlohmann::json::array(
        {{{"pbrMetallicRoughness", {{"baseColorFactor", {0.9, 0.9, 0.9, 1.0}}, {"metallicFactor", 0.0}}}},
         {{"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.2, 0.1, 1.0}}, {"metallicFactor", 0.0}}}}});
    test::writeSceneGltf(inputs / "scene.gltf", scene);
    BakeOptions options = smallBake(inputs / "scene.gltf", "");
    options.resolution = 64;
    options.bounces = 1;
    expectMergedShardsEqualTheWholeBake(options, "shards_scene");
}

TEST(BakeShards, MergedShardsEqualTheUnshardedBakeInU8WithAGeneratedAtlas) {
    Folder inputs("shards_u8_in");
    BakeOptions options = smallBake(writeMesh(inputs, "room.glb", makeBoxRoom(2.0f, 2)), "");
    options.format = TexelFormat::U8;
    expectMergedShardsEqualTheWholeBake(options, "shards_u8");
}

TEST(BakeShards, MergedShardsEqualTheUnshardedBakeWithAHighMeshAndABounce) {
    Folder inputs("shards_high_in");
    BakeOptions options = smallBake(writeMesh(inputs, "low.glb", planeUnderABall(1)), "");
    options.high = writeMesh(inputs, "high.glb", planeUnderABall(2, 0.002f));
    options.bounces = 1;
    options.samples = 16;
    expectMergedShardsEqualTheWholeBake(options, "shards_high");
}

class BakeShardMerge : public testing::Test {
protected:
    Folder inputs{"merge_in"}, parts{"merge_parts"}, merged{"merge_out"};
    BakeOptions options = smallBake(writeMesh(inputs, "scene.glb", planeUnderABall(1)), "");
    std::vector<std::string> shards;

    void SetUp() override { shards = bakeShards(options, parts, 3); }

    // The merge of `files` fails naming `file` and `problem`, and writes nothing.
    void expectRefused(const std::vector<std::string>& files, const std::string& file, const std::string& problem) {
        BakeOptions merge = options;
        merge.output = merged / "baked.glb";
        merge.shardFiles = files;
        Error e = expectFailureWithoutOutput(merge, merged, 0);
        EXPECT_EQ(e.file(), file) << e.what();
        EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
    }
};

TEST_F(BakeShardMerge, RefusesAMissingShard) {
    expectRefused({shards[0], shards[2]}, shards[0], "is shard 0 of 3, but 2 shards were given");
}

TEST_F(BakeShardMerge, RefusesAShardOfAnotherBake) {
    BakeOptions other = options;
    other.seed = 7;
    other.shardIndex = 1;
    other.shardCount = 3;
    other.output = inputs / "seed7.glb";
    runBake(other);
    expectRefused({shards[0], other.output, shards[2]}, other.output, "params.seed: is 7, but this bake has 0");
    options.samples = 64; // the merge's own options must match the shards' too
    expectRefused(shards, shards[0], "params.samples");
}

TEST_F(BakeShardMerge, RefusesOverlappingShards) {
    expectRefused({shards[0], shards[1], shards[1]}, shards[1], "shard 1 is given twice");
    Bundle bundle = readBundle(shards[1]); // shard 1 claims one texel of shard 0 as well
    Layer& layer = bundle.layers[0];
    layer.params["row_begin"] = layer.params["row_begin"].get<uint64_t>() - 1;
    layer.shape[0] += 1;
    layer.data.insert(layer.data.begin(), layer.data.begin(), layer.data.begin() + 12);
    std::string overlapping = inputs / "overlapping.glb";
    writeBundle(overlapping, bundle);
    expectRefused({shards[0], overlapping, shards[2]}, overlapping, "overlap or leave a gap");
}

TEST_F(BakeShardMerge, RefusesShardAndMergeTogether) {
    BakeOptions both = options;
    both.output = merged / "baked.glb";
    both.shardFiles = shards;
    both.shardCount = 3;
    Error e = expectFailureWithoutOutput(both, merged, 0);
    EXPECT_EQ(e.exitCode(), kExitUsage);
    EXPECT_EQ(e.place(), "--merge");
}

} // namespace
} // namespace prt
