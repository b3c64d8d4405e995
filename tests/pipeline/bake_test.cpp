// A bake stage in a pipeline: its bundle's textures travel with it, to the declared output and to stages that read
// the bundle from the store; sharded, it writes the same files as unsharded.
#include "pipeline_test_util.h"

#include "runtime.h"

namespace prt {
namespace {

const char* kPipeline = R"(
[inputs]
shape = { mesh = "@DIR@/shape.obj" }

[stages.prep]
run = "meshprep"
inputs = { mesh = "shape" }

[stages.bake]
run = "bake"
inputs = { mesh = "prep" }
resolution = 32
order = 2
samples = 16
format = "@FORMAT@"
shards = @SHARDS@

[outputs]
baked = { from = "bake", path = "@DIR@/out/baked.glb" }
)";

// The bake pipeline in `dir` (which holds shape.obj), its output under OUT.
Pipeline bakePipeline(const test::TempDir& dir, const std::string& format, int shards, const std::string& out) {
    std::string text = test::replaceAll(test::replaceAll(kPipeline, "@FORMAT@", format), "@SHARDS@",
                                        std::to_string(shards));
    text = test::replaceAll(test::withDir(text, dir.path), dir.path + "/out/", out + "/");
    std::string file = dir / ("bake-" + format + "-" + std::to_string(shards) + ".toml");
    test::writeText(file, text);
    return loadPipeline(file);
}

TEST(PipelineBake, OutputBundleArrivesWithItsTexturesAndRelights) {
    for (const char* format : {"half", "u8"}) {
        test::TempDir dir;
        test::writeTwoSpheresObj(dir / "shape.obj");
        Pipeline pipeline = bakePipeline(dir, format, 1, dir / "out");
        nlohmann::json report = runPipeline(pipeline, test::testOptions(dir / "cache"));
        const nlohmann::json& output = report["outputs"]["baked"];
        ASSERT_TRUE(output.contains("files")) << output.dump();
        EXPECT_GE(output["files"].size(), 2u) << output.dump(); // coefficients (EXR or sidecar + PNGs), normal map
        for (const auto& file : output["files"]) EXPECT_TRUE(std::filesystem::exists(file.get<std::string>())) << file;
        TexelRelightModel model = loadTexelRelightModel(dir / "out/baked.glb"); // hashes checked on the way
        EXPECT_EQ(model.width, 32);
        EXPECT_EQ(model.rows.order, 2);
        EXPECT_EQ(model.rows.transfer.size(), 32u * 32u * 4u * 3u);
    }
}

// Three texel-range shards and the stage's own merge (`prt bake --merge`) give the unsharded bake's files.
TEST(PipelineBake, ShardedBakeWritesTheUnshardedFiles) {
    test::TempDir dir;
    test::writeTwoSpheresObj(dir / "shape.obj");
    nlohmann::json whole = test::runQuietly(bakePipeline(dir, "u8", 1, dir / "out-1"), test::testOptions(dir / "c1"));
    nlohmann::json sharded = test::runQuietly(bakePipeline(dir, "u8", 3, dir / "out-3"), test::testOptions(dir / "c3"));
    EXPECT_EQ(test::outputHashes(sharded), test::outputHashes(whole));
    const nlohmann::json& bake = sharded["stages"][1];
    ASSERT_EQ(bake["id"], "bake");
    EXPECT_EQ(bake["shards"], 3);
    ASSERT_EQ(bake["shard_jobs"].size(), 4u); // three shards and the merge
    EXPECT_EQ(bake["key"], whole["stages"][1]["key"]);
    const nlohmann::json& files = whole["outputs"]["baked"]["files"];
    ASSERT_GE(files.size(), 2u);
    for (const auto& file : files) {
        std::string name = std::filesystem::path(file.get<std::string>()).filename().string();
        EXPECT_EQ(readFileBytes(dir / ("out-3/" + name)), readFileBytes(file.get<std::string>())) << name;
    }
}

// Two baked bundles declared into one folder would share texture names: the run says so instead of letting the
// second overwrite the first's textures.
TEST(PipelineBake, TwoBakedOutputsInOneFolderAreAnError) {
    test::TempDir dir;
    test::writeTwoSpheresObj(dir / "shape.obj");
    std::string text = test::replaceAll(test::replaceAll(kPipeline, "@FORMAT@", "u8"), "@SHARDS@", "1");
    text = test::withDir(text, dir.path) + "other = { from = \"bake\", path = \"" + dir.path + "/out/other.glb\" }\n";
    Pipeline pipeline = parsePipeline(text, dir / "clash.toml");
    try {
        test::runQuietly(pipeline, test::testOptions(dir / "cache"));
        FAIL() << "expected an error";
    } catch (const Error& e) {
        std::string message = e.what();
        EXPECT_NE(message.find("outputs.other"), std::string::npos) << message;
        EXPECT_NE(message.find("'baked'"), std::string::npos) << message;
        EXPECT_NE(message.find("different folders"), std::string::npos) << message;
    }
    // Refused before anything was copied: neither bundle nor any texture is there.
    EXPECT_FALSE(std::filesystem::exists(dir / "out")) << "partial outputs left";
}

} // namespace
} // namespace prt
