// A bake stage in a pipeline: its bundle's textures travel with it, to the declared output and to stages that read
// the bundle from the store.
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

[outputs]
baked = { from = "bake", path = "@DIR@/out/baked.glb" }
)";

TEST(PipelineBake, OutputBundleArrivesWithItsTexturesAndRelights) {
    for (const char* format : {"half", "u8"}) {
        test::TempDir dir;
        test::writeTwoSpheresObj(dir / "shape.obj");
        std::string text = test::replaceAll(test::replaceAll(kPipeline, "@DIR@", dir.path), "@FORMAT@", format);
        test::writeText(dir / "bake.toml", text);
        Pipeline pipeline = loadPipeline(dir / "bake.toml");
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

} // namespace
} // namespace prt
