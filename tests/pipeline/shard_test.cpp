// Sharding: N contiguous vertex ranges merged give the unsharded bundle bit for bit, through the pipeline and
// through `prt merge`; shards that do not belong together are refused.
#include "pipeline_test_util.h"

#include "bundle.h"
#include "core.h"
#include "../scene_gltf.h"

namespace prt {
namespace {

Pipeline shardedPipeline(const test::TempDir& dir, int shards) {
    std::string text = test::twoSpheresPipeline(dir.path, 64, shards, dir / ("out-" + std::to_string(shards)));
    return parsePipeline(text, dir / "sharded.toml");
}

TEST(Shards, PipelineMergeEqualsTheUnshardedRunBitForBit) {
    test::TempDir dir;
    test::writeSkyExr(dir / "sky.exr", 1.0f);
    nlohmann::json whole = test::runQuietly(shardedPipeline(dir, 1), test::testOptions(dir / "cache-1"));
    nlohmann::json sharded = test::runQuietly(shardedPipeline(dir, 3), test::testOptions(dir / "cache-3"));
    EXPECT_EQ(test::outputHashes(sharded), test::outputHashes(whole));
    ASSERT_EQ(readFileBytes(dir / "out-3/bundle.glb"), readFileBytes(dir / "out-1/bundle.glb"));

    const nlohmann::json& transfer = sharded["stages"][1];
    ASSERT_EQ(transfer["id"], "transfer");
    EXPECT_EQ(transfer["shards"], 3);
    ASSERT_EQ(transfer["shard_jobs"].size(), 4u); // three shards and the merge
    EXPECT_EQ(transfer["shard_jobs"][3]["shard"], "merge");
    EXPECT_EQ(transfer["key"], whole["stages"][1]["key"]); // the merged product shares the unsharded key

    // The run-wide override shards a stage the file leaves whole; the product is the same again.
    RunOptions four = test::testOptions(dir / "cache-4");
    four.shards = 4;
    nlohmann::json overridden = test::runQuietly(shardedPipeline(dir, 1), four);
    EXPECT_EQ(overridden["stages"][1]["shard_jobs"].size(), 5u);
    EXPECT_EQ(test::outputHashes(overridden), test::outputHashes(whole));
}

// A stored shard bundle with one flipped byte (its size unchanged, so the entry looks whole) is found by its content
// hash before the merge reads it: the entry is removed, the shard runs again, and the merged bundle is the first
// run's, byte for byte. (Before, the merge refused it by name, exit 3, and every later run did the same.)
TEST(Shards, ACorruptedShardEntryIsRebuiltBeforeTheMerge) {
    test::TempDir dir;
    test::writeSkyExr(dir / "sky.exr", 1.0f);
    RunOptions options = test::testOptions(dir / "cache");
    options.keepIntermediates = true; // the shard entries this test corrupts
    nlohmann::json report = test::runQuietly(shardedPipeline(dir, 3), options);
    const std::map<std::string, std::string> outputs = test::outputHashes(report);
    std::string store = options.cacheDir + "/store";
    std::string mergedKey = report["stages"][1]["key"];
    std::string shardFile;
    for (const auto& item : std::filesystem::directory_iterator(store)) {
        if (item.path().filename().string()[0] == '.') continue;
        nlohmann::json manifest = nlohmann::json::parse(readFileBytes(item.path().string() + "/manifest.json"));
        if (manifest["ingredients"].contains("shard") && manifest["ingredients"]["shard"][0] == 1)
            shardFile = item.path().string() + "/" + manifest["outputs"]["bundle"]["file"].get<std::string>();
    }
    ASSERT_FALSE(shardFile.empty());
    std::string bytes = readFileBytes(shardFile);
    bytes[bytes.size() - 5] ^= 0x01;
    writeBytesAtomic(shardFile, bytes);
    std::filesystem::remove_all(store + "/" + mergedKey.substr(7)); // the merge must run again
    nlohmann::json again = test::runQuietly(shardedPipeline(dir, 3), options);
    const nlohmann::json& jobs = again["stages"][1]["shard_jobs"];
    ASSERT_EQ(jobs.size(), 4u);
    EXPECT_EQ(jobs[0]["status"], "cached");
    EXPECT_EQ(jobs[1]["status"], "ran"); // the corrupted one
    EXPECT_EQ(jobs[2]["status"], "cached");
    EXPECT_EQ(test::outputHashes(again), outputs);
    test::expectStoreConsistent(store);
}

// Interreflected transfer with bounces runs sharded as passes: the direct pass and each bounce an array of shard
// jobs, a gather between passes, the merge after the last; the product is the unsharded one, key included.
TEST(Shards, InterreflectedPassesMergeIntoTheUnshardedRunBitForBit) {
    test::TempDir dir;
    test::writeSkyExr(dir / "sky.exr", 1.0f);
    auto pipeline = [&](int shards, int bounces, const std::string& run) {
        return parsePipeline(test::interreflectedPipeline(dir.path, 48, shards, dir / ("out-" + run), bounces),
                             dir / (run + ".toml"));
    };
    nlohmann::json whole = test::runQuietly(pipeline(1, 2, "whole"), test::testOptions(dir / "cache-whole"));
    nlohmann::json sharded = test::runQuietly(pipeline(3, 2, "sharded"), test::testOptions(dir / "cache-sharded"));
    EXPECT_EQ(test::outputHashes(sharded), test::outputHashes(whole));
    ASSERT_EQ(readFileBytes(dir / "out-sharded/bundle.glb"), readFileBytes(dir / "out-whole/bundle.glb"));

    const nlohmann::json& transfer = sharded["stages"][1];
    ASSERT_EQ(transfer["id"], "transfer");
    EXPECT_EQ(transfer["key"], whole["stages"][1]["key"]);
    const nlohmann::json& jobs = transfer["shard_jobs"];
    ASSERT_EQ(jobs.size(), 12u); // 3 passes (direct, 2 bounces) of 3 shards, 2 gathers and the merge
    EXPECT_EQ(jobs[0]["pass"], 0);
    EXPECT_EQ(jobs[3]["shard"], "gather");
    EXPECT_EQ(jobs[4]["pass"], 1);
    EXPECT_EQ(jobs[7]["shard"], "gather");
    EXPECT_EQ(jobs[7]["pass"], 1);
    EXPECT_EQ(jobs[11]["shard"], "merge");
    EXPECT_GT(jobs[0]["rays"].get<uint64_t>(), 0u); // the direct pass casts the rays, bounces none
    EXPECT_EQ(jobs[4]["rays"].get<uint64_t>(), 0u);

    // Cached on the second run, every job.
    nlohmann::json again = test::runQuietly(pipeline(3, 2, "sharded"), test::testOptions(dir / "cache-sharded"));
    EXPECT_EQ(test::ranStages(again), std::set<std::string>{});

    // The run-wide override, the default bounce count (2) and another shard count: the same product.
    RunOptions four = test::testOptions(dir / "cache-four");
    four.shards = 4;
    nlohmann::json overridden = test::runQuietly(pipeline(1, -1, "four"), four);
    EXPECT_EQ(overridden["stages"][1]["shard_jobs"].size(), 15u);
    EXPECT_EQ(test::outputHashes(overridden), test::outputHashes(whole));

    // One bounce more is another product, under another key.
    nlohmann::json three = test::runQuietly(pipeline(3, 3, "three"), test::testOptions(dir / "cache-sharded"));
    EXPECT_NE(three["stages"][1]["key"], transfer["key"]);
    EXPECT_NE(readFileBytes(dir / "out-three/bundle.glb"), readFileBytes(dir / "out-whole/bundle.glb"));
}

class Merge : public testing::Test {
protected:
    test::TempDir dir;
    std::string transfer = test::kPrt + " --quiet transfer " + (dir / "ball.glb") + " --mode shadowed --samples 32";

    void SetUp() override {
        ASSERT_EQ(test::shell(test::kPrt + " --quiet scene two-spheres -o " + (dir / "ball.glb")), 0);
        ASSERT_EQ(test::shell(transfer + " -o " + (dir / "whole.glb")), 0);
        for (int i = 0; i < 3; ++i)
            ASSERT_EQ(test::shell(transfer + " --shard " + std::to_string(i) + "/3 -o " + shard(i)), 0);
    }
    std::string shard(int i) const { return dir / ("shard-" + std::to_string(i) + ".glb"); }
    void expectRefused(const std::vector<std::string>& files, const std::string& problem) {
        std::vector<Bundle> bundles;
        for (const std::string& file : files) bundles.push_back(readBundle(file));
        try {
            mergeShards(bundles, files);
            FAIL() << "merged shards that do not belong together";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
        }
    }
};

TEST_F(Merge, CommandJoinsShardsInAnyOrderIntoTheUnshardedBundle) {
    std::string output;
    ASSERT_EQ(test::shell(test::kPrt + " --quiet merge " + shard(2) + " " + shard(0) + " " + shard(1) + " -o " +
                              (dir / "merged.glb"), &output), 0) << output;
    EXPECT_EQ(readFileBytes(dir / "merged.glb"), readFileBytes(dir / "whole.glb"));
}

TEST_F(Merge, RefusesShardsThatDoNotTileOneRun) {
    expectRefused({shard(0), shard(1)}, "is shard 0 of 3, but 2 shards were given");
    expectRefused({shard(0), shard(1), shard(1)}, "shard 1 is given twice");

    ASSERT_EQ(test::shell(transfer + " --seed 7 --shard 1/3 -o " + (dir / "seed.glb")), 0);
    expectRefused({shard(0), dir / "seed.glb", shard(2)}, "parameters differ");

    ASSERT_EQ(test::shell(test::kPrt + " --quiet scene sphere -o " + (dir / "sphere.glb")), 0);
    ASSERT_EQ(test::shell(test::kPrt + " --quiet transfer " + (dir / "sphere.glb") + " --mode shadowed --samples 32 "
                                                                                   "--shard 2/3 -o " + (dir / "other.glb")), 0);
    expectRefused({shard(0), shard(1), dir / "other.glb"}, "differs from the mesh");

    expectRefused({dir / "whole.glb"}, "not a shard bundle");
}

// The streamed merge (`prt merge`, the pipeline's merge job) writes the bytes of the in-memory one,
// writeBundle(mergeShards(...)), for every kind of sharded layer: float32 transfer and transfer_bounce rows, float16
// glossy lobes, uint8 and uint16 rows, and a layer every shard holds whole.
TEST_F(Merge, StreamedMergeIsTheInMemoryMergeByteForByte) {
    Bundle whole = readBundle(dir / "whole.glb");
    const uint64_t vertices = whole.mesh.vertexCount();
    auto add = [&](const std::string& name, const std::string& type, std::vector<uint64_t> shape, const std::string& domain) {
        Layer layer;
        layer.name = name;
        layer.domain = domain;
        layer.semantic = name == "glossy_lobes" ? "sg_lobes" : "test_" + name;
        layer.componentType = type;
        layer.shape = shape;
        layer.params = {{"order", 3}, {"rays", 1000}};
        uint64_t count = 1;
        for (uint64_t extent : shape) count *= extent;
        for (uint64_t i = 0; i < count; ++i) {
            if (type == "float32") layer.data.push_back(float(i % 977) * 0.125f - 3.0f);
            else if (type == "float16") layer.data.push_back(halfToFloat(floatToHalf(float(i % 1013) * 0.01f)));
            else layer.integers.push_back(uint32_t(i * 37 % (type == "uint8" ? 256 : 65536)));
        }
        whole.layers.push_back(std::move(layer));
    };
    add("transfer_bounce", "float32", {vertices, 9, 3}, "vertex");
    add("glossy_lobes", "float16", {vertices, 92, 2, 5}, "vertex");
    add("codes", "uint8", {vertices, 3}, "vertex");
    add("cluster_index", "uint16", {vertices}, "vertex");
    add("diffuse", "float32", {vertices, 9, 3}, "vertex"); // held whole by every shard
    std::vector<std::string> files;
    std::vector<Bundle> shards;
    for (int i = 0; i < 3; ++i) {
        uint64_t begin = vertices * i / 3, end = vertices * (i + 1) / 3;
        Bundle part = whole;
        for (Layer& layer : part.layers) {
            if (layer.name == "diffuse") continue;
            uint64_t width = (layer.data.empty() ? layer.integers.size() : layer.data.size()) / vertices;
            if (!layer.data.empty()) layer.data = std::vector<float>(layer.data.begin() + begin * width, layer.data.begin() + end * width);
            else layer.integers = std::vector<uint32_t>(layer.integers.begin() + begin * width, layer.integers.begin() + end * width);
            layer.shape[0] = end - begin;
            markVertexShard(layer, begin, end, vertices, i, 3);
            layer.params["rays"] = 1000 + i;
        }
        files.push_back(dir / ("kinds-" + std::to_string(i) + ".glb"));
        writeBundle(files.back(), part);
        shards.push_back(readBundle(files.back()));
    }
    writeBundle(dir / "in-memory.glb", mergeShards(shards, files));
    mergeShardFiles({files[1], files[2], files[0]}, dir / "streamed.glb");
    const std::string inMemory = readFileBytes(dir / "in-memory.glb");
    EXPECT_EQ(readFileBytes(dir / "streamed.glb"), inMemory);
    std::string output;
    ASSERT_EQ(test::shell(test::kPrt + " --quiet merge " + files[2] + " " + files[0] + " " + files[1] + " -o " +
                              (dir / "command.glb"), &output), 0) << output;
    EXPECT_EQ(readFileBytes(dir / "command.glb"), inMemory);

    // What the merge joined is the rows of the whole run, in vertex order, its counters summed.
    Bundle merged = readBundle(dir / "streamed.glb");
    for (const Layer& layer : whole.layers) {
        const Layer* joined = findLayer(merged, layer.name);
        ASSERT_NE(joined, nullptr) << layer.name;
        EXPECT_EQ(joined->domain, "vertex");
        EXPECT_EQ(joined->data, layer.data) << layer.name;
        EXPECT_EQ(joined->integers, layer.integers) << layer.name;
        if (layer.name != "diffuse") {
            EXPECT_EQ(joined->params["rays"], 3003) << layer.name;
        }
    }
}

// `prt merge` checks every shard's checksum while it streams: a flipped byte in a shard's rows is refused by the
// shard's name, exit 3, and no merged file is left.
TEST_F(Merge, CommandRefusesACorruptedShardByName) {
    std::string bytes = readFileBytes(shard(1));
    bytes[bytes.size() - 9] ^= 0x01;
    writeBytesAtomic(shard(1), bytes);
    std::string output;
    EXPECT_EQ(test::shell(test::kPrt + " merge " + shard(0) + " " + shard(1) + " " + shard(2) + " -o " + (dir / "merged.glb"),
                          &output), kExitInput) << output;
    EXPECT_NE(output.find(shard(1)), std::string::npos) << output;
    EXPECT_NE(output.find("checksum mismatch"), std::string::npos) << output;
    EXPECT_FALSE(std::filesystem::exists(dir / "merged.glb"));
}

} // namespace
} // namespace prt

namespace prt {
namespace {

// A glTF scene's transfer excludes the albedo and carries it as a "diffuse_albedo" layer; sharded, each shard
// holds its rows of it, so the merged bundle is the unsharded one and relight takes it.
TEST(Shards, ASceneShardedKeepsItsAlbedoLayerAndMergesBitForBit) {
    test::TempDir dir;
    test::writeSkyExr(dir / "sky.exr", 1.0f);
    test::TestScene scene;
    scene.meshes.push_back({test::TestPrimitive{makeSphere(0.5f, 12, 16), 0, {}, {}}});
    scene.meshes.push_back({test::TestPrimitive{makePlane(4.0f, 4, -0.5f), 0, {}, {}}});
    scene.nodes = nlohmann::json::array({{{"mesh", 0}}, {{"mesh", 1}}});
    scene.roots = {0, 1};
    scene.materials = nlohmann::json::array({{{"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.3, 0.2, 1.0}}, {"metallicFactor", 0.0}}}}});
    test::writeSceneGltf(dir / "scene.gltf", scene);
    auto pipeline = [&](int shards, const std::string& run) {
        std::string text = test::withDir(R"(
[inputs]
scene = { mesh = "@DIR@/scene.gltf" }
sky = { env = "@DIR@/sky.exr" }
[stages.prep]
run = "meshprep"
inputs = { mesh = "scene" }
[stages.transfer]
run = "transfer"
inputs = { mesh = "prep" }
mode = "interreflected"
samples = 16
bounces = 2
shards = )" + std::to_string(shards) + R"(
[stages.relight]
run = "relight"
inputs = { bundle = "transfer", env = "sky" }
[outputs]
bundle = { from = "transfer", path = "@DIR@/out-)" + run + R"(/bundle.glb" }
radiance = { from = "relight", path = "@DIR@/out-)" + run + R"(/radiance.npy" }
)", dir.path);
        return parsePipeline(text, dir / (run + ".toml"));
    };
    nlohmann::json whole = test::runQuietly(pipeline(1, "whole"), test::testOptions(dir / "cache-whole"));
    nlohmann::json sharded = test::runQuietly(pipeline(3, "sharded"), test::testOptions(dir / "cache-sharded"));
    ASSERT_EQ(readFileBytes(dir / "out-sharded/bundle.glb"), readFileBytes(dir / "out-whole/bundle.glb"));
    EXPECT_EQ(test::outputHashes(sharded), test::outputHashes(whole));
    const Layer* albedo = nullptr;
    Bundle bundle = readBundle(dir / "out-sharded/bundle.glb");
    for (const Layer& layer : bundle.layers)
        if (layer.name == "diffuse_albedo") albedo = &layer;
    ASSERT_NE(albedo, nullptr);
    EXPECT_EQ(albedo->domain, "vertex");
    EXPECT_FLOAT_EQ(albedo->data[0], 0.8f);
}

} // namespace
} // namespace prt
