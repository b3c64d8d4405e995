// `prt render` and `prt compare --image` through the binary: a square of known radiance under a constant sky.
#include "bundle.h"
#include "compare.h"
#include "core.h"
#include "image.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include <unistd.h>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {

int runPrt(const std::string& arguments) {
    int status = std::system((std::string(PRT_EXECUTABLE) + " --quiet " + arguments + " 2>/dev/null >/dev/null").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class RenderCli : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("prt_render_cli_" + std::to_string(getpid()));
        fs::create_directories(dir);
        // A square facing +Z with transfer Y_00 at order 1: under constant radiance E the runtime gives E.
        prt::Bundle bundle;
        bundle.mesh.positions = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
        bundle.mesh.indices = {0, 1, 2, 0, 2, 3};
        prt::Layer layer;
        layer.name = "transfer";
        layer.domain = "vertex";
        layer.semantic = "sh_transfer_rgb";
        layer.shape = {4, 1, 3};
        layer.params = {{"order", 1}};
        layer.data.assign(12, float(0.5 / std::sqrt(std::numbers::pi)));
        bundle.layers.push_back(layer);
        prt::writeBundle((dir / "square.glb").string(), bundle);
        prt::Image sky;
        sky.width = 64;
        sky.height = 32;
        sky.rgb.assign(64 * 32 * 3, 0.5f);
        prt::writeImage((dir / "sky.exr").string(), sky);
        camera = "--camera 0,0,2,0,0,0,0,1,0,40 --size 48,32";
    }
    void TearDown() override { fs::remove_all(dir); }
    std::string path(const char* name) const { return (dir / name).string(); }
    fs::path dir;
    std::string camera;
};

} // namespace

TEST_F(RenderCli, RendersLinearExrWithCoverageAndTonemappedPng) {
    ASSERT_EQ(runPrt("render " + path("square.glb") + " --env " + path("sky.exr") + " " + camera + " -o " +
                     path("r.exr")),
              0);
    ASSERT_EQ(runPrt("render " + path("square.glb") + " --env " + path("sky.exr") + " " + camera + " -o " +
                     path("r.png") + " --exposure 1"),
              0);
    prt::Image image = prt::readImage(path("r.exr"));
    ASSERT_EQ(image.width, 48);
    ASSERT_EQ(image.height, 32);
    std::vector<float> coverage = prt::readImageChannels(path("r.exr"), {"A"}).values;
    size_t centre = 16 * 48 + 24;
    EXPECT_EQ(coverage[centre], 1.0f);
    EXPECT_EQ(coverage[0], 0.0f);
    EXPECT_NEAR(image.rgb[centre * 3 + 1], 0.5f, 1e-4f); // the projection of a constant sky is exact to rounding
    prt::ImageChannels png = prt::readImageChannels(path("r.png"), {"R", "G", "B"});
    EXPECT_NEAR(png.values[centre * 3] * 255.0f, float(prt::toneMap(image.rgb[centre * 3], 1.0f)), 1e-3f);
    EXPECT_EQ(png.values[0], 0.0f);
}

// --background: the constant sky (0.5) where rays escape, in the EXR and the PNG's tone map, coverage kept.
TEST_F(RenderCli, BackgroundDrawsTheMapWhereRaysEscape) {
    ASSERT_EQ(runPrt("render " + path("square.glb") + " --env " + path("sky.exr") + " " + camera +
                     " --background --rotate-y 30 -o " + path("b.exr")),
              0);
    ASSERT_EQ(runPrt("render " + path("square.glb") + " --env " + path("sky.exr") + " " + camera +
                     " --background -o " + path("b.png")),
              0);
    prt::Image image = prt::readImage(path("b.exr"));
    std::vector<float> coverage = prt::readImageChannels(path("b.exr"), {"A"}).values;
    size_t centre = 16 * 48 + 24;
    EXPECT_EQ(coverage[centre], 1.0f);
    EXPECT_EQ(coverage[0], 0.0f);
    EXPECT_NEAR(image.rgb[0], 0.5f, 1e-6f);
    EXPECT_NEAR(image.rgb[centre * 3 + 1], 0.5f, 1e-4f);
    prt::ImageChannels png = prt::readImageChannels(path("b.png"), {"R", "G", "B"});
    EXPECT_NEAR(png.values[0] * 255.0f, float(prt::toneMap(0.5f, 0.0f)), 1e-3f);
}

TEST_F(RenderCli, CompareImageMeasuresOverTheMaskAndDrawsPictures) {
    ASSERT_EQ(runPrt("render " + path("square.glb") + " --env " + path("sky.exr") + " " + camera + " -o " +
                     path("r.exr")),
              0);
    // A reference 10% brighter everywhere, with a background the mask must exclude.
    prt::Image reference = prt::readImage(path("r.exr"));
    for (float& v : reference.rgb) v = v == 0.0f ? 7.0f : v * 1.1f;
    prt::writeImage(path("ref.exr"), reference);
    ASSERT_EQ(runPrt("compare --image " + path("r.exr") + " " + path("ref.exr") + " -o " + path("diff.png") +
                     " --strip " + path("strip.png") + " --metrics " + path("m.json")),
              0);
    nlohmann::json metrics = nlohmann::json::parse(std::ifstream(path("m.json")));
    std::vector<float> coverage = prt::readImageChannels(path("r.exr"), {"A"}).values;
    double covered = 0;
    for (float c : coverage) covered += c;
    EXPECT_EQ(metrics["count"].get<double>(), covered);
    EXPECT_NEAR(metrics["mean_relative_luminance_error"].get<double>(), 0.1 / 1.1, 1e-4);
    EXPECT_NEAR(metrics["max_relative_luminance_error"].get<double>(), 0.1 / 1.1, 1e-4);
    prt::ImageChannels diff = prt::readImageChannels(path("diff.png"), {"R", "G", "B"});
    EXPECT_EQ(diff.width, 48);
    EXPECT_GT(diff.height, 32); // the legend
    prt::ImageChannels strip = prt::readImageChannels(path("strip.png"), {"R", "G", "B"});
    EXPECT_EQ(strip.width, 3 * 48 + 8);
    // Same image: no error at all.
    ASSERT_EQ(runPrt("compare --image " + path("r.exr") + " " + path("r.exr") + " -o " + path("same.png") +
                     " --metrics " + path("same.json")),
              0);
    EXPECT_EQ(nlohmann::json::parse(std::ifstream(path("same.json")))["rmse"].get<double>(), 0.0);
}

TEST_F(RenderCli, BadInputsFailWithNoOutput) {
    // A camera looking along its up vector, an unknown extension, and images of two sizes.
    EXPECT_EQ(runPrt("render " + path("square.glb") + " --env " + path("sky.exr") +
                     " --camera 0,0,2,0,0,0,0,0,1,40 --size 8,8 -o " + path("bad.exr")),
              2);
    EXPECT_EQ(runPrt("render " + path("square.glb") + " --env " + path("sky.exr") + " " + camera + " -o " +
                     path("bad.jpg")),
              2);
    prt::writeImage(path("small.exr"), prt::Image{2, 2, std::vector<float>(12, 1.0f)});
    ASSERT_EQ(runPrt("render " + path("square.glb") + " --env " + path("sky.exr") + " " + camera + " -o " +
                     path("r.exr")),
              0);
    EXPECT_EQ(runPrt("compare --image " + path("r.exr") + " " + path("small.exr") + " -o " + path("bad.png")), 3);
    EXPECT_FALSE(fs::exists(path("bad.exr")));
    EXPECT_FALSE(fs::exists(path("bad.jpg")));
    EXPECT_FALSE(fs::exists(path("bad.png")));
}

// --glossy-stack needs a glossy bundle: a plain one is refused (kExitInput) and neither file is written; with
// --lights or --texels it is a usage error.
TEST_F(RenderCli, GlossyStackNeedsAGlossyBundleAndWritesNothingOtherwise) {
    EXPECT_EQ(runPrt("render " + path("square.glb") + " --env " + path("sky.exr") + " " + camera + " -o " +
                     path("p.png") + " --glossy-stack " + path("s.stack")),
              prt::kExitInput);
    EXPECT_FALSE(fs::exists(dir / "s.stack"));
    EXPECT_FALSE(fs::exists(dir / "p.png"));
    EXPECT_EQ(runPrt("render " + path("square.glb") + " --env " + path("sky.exr") + " " + camera + " -o " +
                     path("p.png") + " --texels --glossy-stack " + path("s.stack")),
              prt::kExitUsage);
    EXPECT_FALSE(fs::exists(dir / "s.stack"));
}
