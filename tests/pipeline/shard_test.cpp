// Sharding: N contiguous vertex ranges merged give the unsharded bundle bit for bit, through the pipeline and
// through `prt merge`; shards that do not belong together are refused.
#include "pipeline_test_util.h"

#include "bundle.h"

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

} // namespace
} // namespace prt
