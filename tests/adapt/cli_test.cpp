// `prt adapt` end to end: an adaptive bundle that `prt relight` reads, and the refusals (exit code, message, no
// output file).
#include "bundle.h"
#include "cli_util.h"
#include "compare.h"
#include "image.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using prt::test::CliRun;
using prt::test::runPrt;

class AdaptCli : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("prt_adapt_cli_" + std::to_string(getpid()));
        fs::create_directories(dir);
        // A grid of 6 x 6 vertices with random, decaying order-4 transfer.
        prt::Bundle bundle;
        const int n = 6, order = 4;
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) bundle.mesh.positions.insert(bundle.mesh.positions.end(), {float(x), float(y), 0});
        for (int y = 0; y + 1 < n; ++y)
            for (int x = 0; x + 1 < n; ++x) {
                uint32_t a = y * n + x, b = a + 1, c = a + n, d = c + 1;
                bundle.mesh.indices.insert(bundle.mesh.indices.end(), {a, b, d, a, d, c});
            }
        prt::Layer layer;
        layer.name = "transfer";
        layer.domain = "vertex";
        layer.semantic = "sh_transfer_rgb";
        layer.shape = {uint64_t(n * n), uint64_t(order * order), 3};
        layer.params = {{"order", order}};
        std::mt19937 random(1);
        std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
        for (int v = 0; v < n * n; ++v)
            for (int j = 0; j < order * order; ++j)
                for (int c = 0; c < 3; ++c) {
                    int l = int(std::sqrt(double(j)));
                    layer.data.push_back(j == 0 ? 0.5f : uniform(random) * std::pow(0.3f + 0.1f * (v % 6), float(l)));
                }
        bundle.layers.push_back(layer);
        prt::writeBundle((dir / "full.glb").string(), bundle);
        // A small sky: brighter towards the top.
        prt::Image sky;
        sky.width = 32;
        sky.height = 16;
        for (int y = 0; y < sky.height; ++y)
            for (int x = 0; x < sky.width; ++x)
                sky.rgb.insert(sky.rgb.end(), {2.0f - y / 8.0f + (x == 3 ? 5.0f : 0.0f), 1.0f, 0.5f});
        prt::writeImage((dir / "sky.exr").string(), sky);
    }
    void TearDown() override { fs::remove_all(dir); }

    std::string path(const char* name) const { return (dir / name).string(); }
    fs::path dir;
};

} // namespace

TEST_F(AdaptCli, AdaptiveBundleRelightsCloseToFullOrder) {
    ASSERT_EQ(runPrt("relight " + path("full.glb") + " --env " + path("sky.exr") + " -o " + path("f.npy"), dir).exitCode, 0);
    for (const char* format : {"float", "half", "u16", "u8", "cpca"}) {
        CliRun run = runPrt("adapt " + path("full.glb") + " -o " + path("adaptive.glb") + " --max-error 0.02 --env " +
                                path("sky.exr") + " --format " + format + " --clusters 4",
                            dir);
        ASSERT_EQ(run.exitCode, 0) << format << ": " << run.stderrText;
        ASSERT_EQ(runPrt("relight " + path("adaptive.glb") + " --env " + path("sky.exr") + " -o " + path("a.npy"), dir).exitCode, 0);
        prt::ErrorMetrics metrics = prt::compareFiles(path("a.npy"), path("f.npy"));
        EXPECT_LT(metrics.relativeRmse, 0.03) << format; // 0.02 per vertex from truncation, plus rounding
        EXPECT_GT(metrics.relativeRmse, 0.0) << format;
    }
}

// A bake's texture is read into the adaptive texel layers; the output relights like the bake within the bound and
// names no file next to the input.
TEST_F(AdaptCli, ABakeAdaptsPerTexel) {
    ASSERT_EQ(runPrt("scene sphere -o " + path("sphere.glb"), dir).exitCode, 0);
    ASSERT_EQ(runPrt("bake " + path("sphere.glb") + " -o " + path("bake.glb") +
                         " --resolution 64 --order 4 --samples 16 --quiet",
                     dir)
                  .exitCode,
              0);
    CliRun run = runPrt("adapt " + path("bake.glb") + " -o " + path("texels.glb") + " --max-error 0.02 --env " +
                            path("sky.exr"),
                        dir);
    ASSERT_EQ(run.exitCode, 0) << run.stderrText;
    EXPECT_NE(run.stderrText.find("leaves out the layers"), std::string::npos) << run.stderrText;
    prt::Bundle adapted = prt::readBundle(path("texels.glb"));
    for (const prt::Layer& layer : adapted.layers) EXPECT_FALSE(layer.params.contains("uri")) << layer.name;
    for (const char* bundle : {"bake.glb", "texels.glb"})
        ASSERT_EQ(runPrt(std::string("relight ") + path(bundle) + " --texels --env " + path("sky.exr") + " -o " +
                             path(bundle) + ".exr --quiet",
                         dir)
                      .exitCode,
                  0);
    prt::Image bake = prt::readImage(path("bake.glb") + ".exr"), texels = prt::readImage(path("texels.glb") + ".exr");
    ASSERT_EQ(bake.rgb.size(), texels.rgb.size());
    double error = 0.0, energy = 0.0;
    for (size_t i = 0; i < bake.rgb.size(); ++i) {
        error += (texels.rgb[i] - bake.rgb[i]) * (texels.rgb[i] - bake.rgb[i]);
        energy += bake.rgb[i] * bake.rgb[i];
    }
    EXPECT_LE(std::sqrt(error / energy), 0.0201);
}

TEST_F(AdaptCli, RefusesBadOptionsWithNoOutput) {
    const std::string base = "adapt " + path("full.glb") + " -o " + path("out.glb") + " --env " + path("sky.exr");
    struct Case {
        std::string arguments;
        int exitCode;
        const char* message;
    };
    for (const Case& c : {Case{base + " --max-error 0.01 --order 2", 2, "conflicts with --max-error"},
                          Case{base + " --max-error 0", 2, "must be > 0"},
                          Case{base + " --max-error -0.5", 2, "must be > 0"},
                          Case{base, 2, "--max-error"},
                          Case{base + " --max-error 0.01 --format u4", 2, "is not one of"},
                          Case{base + " --order 9", 2, "above the transfer's order"},
                          Case{"adapt " + path("missing.glb") + " -o " + path("out.glb") + " --max-error 0.1 --env " +
                                   path("sky.exr"), 3, "missing.glb"},
                          Case{"adapt " + path("full.glb") + " -o " + path("out.glb") + " --max-error 0.1", 2, "--env"}}) {
        CliRun run = runPrt(c.arguments, dir);
        EXPECT_EQ(run.exitCode, c.exitCode) << c.arguments << "\n" << run.stderrText;
        EXPECT_NE(run.stderrText.find(c.message), std::string::npos) << c.arguments << "\n" << run.stderrText;
        EXPECT_FALSE(fs::exists(dir / "out.glb")) << c.arguments;
    }
}
