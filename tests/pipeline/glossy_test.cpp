// The glossy stage in a pipeline: sharded over vertices it stores the unsharded bundle byte for byte under the
// unsharded key, its key follows every option it resolves, and its bundle relights toward an eye point.
#include "pipeline_test_util.h"

#include "bundle.h"

namespace prt {
namespace {

// The sphere scene, a small glossy fit in `shards` shards (lobes 2, grid 4, 32 diffuse samples, 15 LM iterations), and its relight
// under DIR/sky.exr toward the eye (0, 0, 4), into the folder `out`.
std::string glossyPipeline(const test::TempDir& dir, int shards, const std::string& out, const std::string& extra = "") {
    std::string text = R"(
[inputs]
sky = { env = "@DIR@/sky.exr" }

[stages.ball]
run = "scene"
name = "sphere"

[stages.glossy]
run = "glossy"
inputs = { mesh = "ball" }
brdf = "phong:16,0.5"
albedo = [0.4, 0.4, 0.4]
lobes = 2
grid = 4
samples = 32
iterations = 15
shards = @SHARDS@
@EXTRA@
[stages.relight]
run = "relight"
inputs = { bundle = "glossy", env = "sky" }
eye = "0,0,4"

[outputs]
bundle = { from = "glossy", path = "@OUT@/glossy.glb" }
radiance = { from = "relight", path = "@OUT@/radiance.npy" }
)";
    text = test::replaceAll(test::replaceAll(text, "@SHARDS@", std::to_string(shards)), "@EXTRA@", extra);
    return test::withDir(test::replaceAll(text, "@OUT@", out), dir.path);
}

TEST(PipelineGlossy, ThreeShardsStoreTheUnshardedBundleAndItRelights) {
    test::TempDir dir;
    test::writeSkyExr(dir / "sky.exr", 1.0f);
    nlohmann::json whole = test::runQuietly(parsePipeline(glossyPipeline(dir, 1, dir / "out-1"), dir / "g1.toml"),
                                            test::testOptions(dir / "cache-1"));
    nlohmann::json sharded = test::runQuietly(parsePipeline(glossyPipeline(dir, 3, dir / "out-3"), dir / "g3.toml"),
                                              test::testOptions(dir / "cache-3"));
    ASSERT_EQ(readFileBytes(dir / "out-3/glossy.glb"), readFileBytes(dir / "out-1/glossy.glb"));
    EXPECT_EQ(test::outputHashes(sharded), test::outputHashes(whole));
    const nlohmann::json& stage = sharded["stages"][1];
    ASSERT_EQ(stage["id"], "glossy");
    EXPECT_EQ(stage["shard_jobs"].size(), 4u); // three shards and the merge
    EXPECT_EQ(stage["key"], whole["stages"][1]["key"]);

    // The product relit toward the eye: one finite, non-negative RGB value per vertex.
    Bundle bundle = readBundle(dir / "out-1/glossy.glb");
    ASSERT_NE(findLayer(bundle, "glossy_lobes"), nullptr);
    std::vector<size_t> shape;
    std::vector<float> radiance = readNpy(dir / "out-1/radiance.npy", &shape);
    ASSERT_EQ(shape.size(), 2u);
    EXPECT_EQ(shape[0], bundle.mesh.vertexCount());
    for (float value : radiance) ASSERT_TRUE(std::isfinite(value) && value >= 0.0f);

    // Every resolved option is in the key: a changed weight reruns the stage (and the relight), a second run of
    // the same file is served from the cache.
    nlohmann::json again = test::runQuietly(parsePipeline(glossyPipeline(dir, 1, dir / "out-1"), dir / "g1.toml"),
                                            test::testOptions(dir / "cache-1"));
    EXPECT_EQ(test::statuses(again)["glossy"], "cached");
    nlohmann::json changed = test::runQuietly(
        parsePipeline(glossyPipeline(dir, 1, dir / "out-b", "beta = 0.1\n"), dir / "gb.toml"),
        test::testOptions(dir / "cache-1"));
    EXPECT_EQ(test::statuses(changed)["glossy"], "ran");
    EXPECT_NE(changed["stages"][1]["key"], whole["stages"][1]["key"]);
}

TEST(PipelineGlossy, ShardedInterreflectionIsRefusedWhenParsed) {
    test::TempDir dir;
    try {
        parsePipeline(glossyPipeline(dir, 3, dir / "out", "bounces = 1\n"), dir / "g.toml");
        FAIL() << "sharded interreflection accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("cannot be sharded"), std::string::npos) << e.what();
    }
}

} // namespace
} // namespace prt
