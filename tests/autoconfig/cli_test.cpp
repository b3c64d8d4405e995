// `prt autoconfig` end to end on a scene with a known answer: an unoccluded sphere under order-2 lighting
// L(d) = a + b d_y, whose exact radiance is albedo (a + 2/3 b n_y). There order 2 has no truncation error, shadowed
// transfer on a convex mesh is exact at any sample count and bounces add nothing, so the cheapest configuration
// under any target is order 2 (or fewer bands where the target allows), the fewest samples and no bounces; the
// written pipeline must run and its radiance be within the target of the closed form. Then the refusals.
#include "bundle.h"
#include "cli_util.h"
#include "core.h"
#include "image.h"
#include "sh.h"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using prt::test::CliRun;
using prt::test::runPrt;

constexpr float kA[3] = {1.0f, 0.8f, 0.6f}, kB[3] = {0.8f, -0.5f, 0.3f};
constexpr float kAlbedo = 0.8f;

class AutoconfigCli : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("prt_autoconfig_cli_" + std::to_string(getpid()));
        fs::create_directories(dir);
        ASSERT_EQ(runPrt("scene sphere -o " + path("sphere.glb"), dir).exitCode, 0);
        prt::Image sky;
        sky.width = 64;
        sky.height = 32;
        for (int y = 0; y < sky.height; ++y)
            for (int x = 0; x < sky.width; ++x) {
                double d[3];
                prt::sh::equirectDirection(sky.width, sky.height, x, y, d);
                for (int c = 0; c < 3; ++c) sky.rgb.push_back(float(kA[c] + kB[c] * d[1]));
            }
        prt::writeImage(path("sky.exr"), sky);
    }
    void TearDown() override { fs::remove_all(dir); }
    std::string path(const char* name) const { return (dir / name).string(); }
    std::string base() const {
        return "autoconfig " + path("sphere.glb") + " --env " + path("sky.exr") +
               " --orders 1,2,3,4 --samples 16,64 --bounces 0,1 --formats float,half,u8 --pilot-vertices 64 "
               "--albedo 0.8";
    }
    fs::path dir;
};

std::string readText(const std::string& file) {
    std::stringstream text;
    text << std::ifstream(file).rdbuf();
    return text.str();
}

} // namespace

TEST_F(AutoconfigCli, PicksOrderTwoTheFewestSamplesAndNoBouncesAndItsPipelineMeetsTheTarget) {
    const double target = 0.05;
    CliRun run = runPrt(base() + " --threads 2 --target-error 0.05 -o " + path("auto.toml") + " --report " + path("report.json") +
                            " --bundle " + path("out/sphere.prt.glb"),
                        dir);
    ASSERT_EQ(run.exitCode, 0) << run.stderrText;
    nlohmann::json report = nlohmann::json::parse(readText(path("report.json")));
    const nlohmann::json& chosen = report["chosen"];
    EXPECT_EQ(chosen["order"], 2) << report.dump(1); // order 1 misses the linear term; more buys nothing
    EXPECT_EQ(chosen["samples"], 16);
    EXPECT_EQ(chosen["bounces"], 0);
    EXPECT_LE(chosen["pilot_error"].get<double>(), 0.9 * target);
    EXPECT_LE(chosen["held_out_error"].get<double>(), target);
    // The final check is measured once on vertices no choice looked at, and reported.
    ASSERT_TRUE(chosen.contains("check_error"));
    EXPECT_GE(chosen["check_error"].get<double>(), 0.0);
    EXPECT_LE(chosen["check_error"].get<double>(), target);
    EXPECT_GT(report["pareto"].size(), 1u);
    // The pipeline parses and runs, and its radiance is within the target of the closed form.
    CliRun pipeline = runPrt("run " + path("auto.toml") + " --cache-dir " + path("cache"), dir);
    ASSERT_EQ(pipeline.exitCode, 0) << pipeline.stderrText << "\n" << readText(path("auto.toml"));
    std::vector<size_t> shape;
    std::vector<float> radiance = prt::readNpy(path("out/sphere.sky.npy"), &shape);
    prt::Bundle sphere = prt::readBundle(path("sphere.glb"));
    ASSERT_EQ(radiance.size(), sphere.mesh.vertexCount() * 3);
    double difference = 0.0, signal = 0.0;
    for (size_t v = 0; v < sphere.mesh.vertexCount(); ++v)
        for (int c = 0; c < 3; ++c) {
            double exact = kAlbedo * (kA[c] + 2.0 / 3.0 * kB[c] * sphere.mesh.normals[v * 3 + 1]);
            difference += std::pow(radiance[v * 3 + c] - exact, 2.0);
            signal += exact * exact;
        }
    double achieved = std::sqrt(difference / signal);
    EXPECT_LE(achieved, target);
    // The comment block states what was predicted and verified.
    std::string toml = readText(path("auto.toml"));
    // Same inputs and seed, another thread count: the same pipeline, byte for byte (the costs are work counts).
    ASSERT_EQ(runPrt(base() + " --threads 1 --target-error 0.05 --name auto -o " + path("again.toml") + " --bundle " +
                         path("out/sphere.prt.glb"), dir).exitCode, 0);
    EXPECT_EQ(readText(path("again.toml")), toml);
    EXPECT_NE(toml.find("predicted (pilot)"), std::string::npos);
    EXPECT_NE(toml.find("verified (held out)"), std::string::npos);
}

// A small bright sun on a dim constant sky: plain SH at order 1 misses the sun's shape by far (16%), while one cone
// light plus the order-1 residual is exact on the unoccluded sphere up to the fit. So autoconfig must take the
// extracted lights at the lowest order, and its pipeline (envlight feeding relight) must meet the target.
TEST_F(AutoconfigCli, TakesExtractedLightsForASmallSunAndItsPipelineMeetsTheTarget) {
    prt::Image sky;
    sky.width = 256;
    sky.height = 128;
    const double sun[3] = {0.3, 0.8, 0.52}, length = std::sqrt(0.09 + 0.64 + 0.2704);
    for (int y = 0; y < sky.height; ++y)
        for (int x = 0; x < sky.width; ++x) {
            double d[3];
            prt::sh::equirectDirection(sky.width, sky.height, x, y, d);
            bool inSun = (d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2]) / length > std::cos(5.0 * M_PI / 180.0);
            sky.rgb.insert(sky.rgb.end(), {0.5f + (inSun ? 40.0f : 0.0f), 0.5f + (inSun ? 36.0f : 0.0f),
                                           0.6f + (inSun ? 30.0f : 0.0f)});
        }
    prt::writeImage(path("sun.exr"), sky);
    const double target = 0.02;
    CliRun run = runPrt("autoconfig " + path("sphere.glb") + " --env " + path("sun.exr") +
                            " --orders 1,2 --samples 16 --bounces 0 --formats float --lights 0,2 --pilot-vertices 64 "
                            "--target-error 0.02 -o " + path("sun.toml") + " --report " + path("sun.json") +
                            " --bundle " + path("out/sun.prt.glb"),
                        dir);
    ASSERT_EQ(run.exitCode, 0) << run.stderrText;
    nlohmann::json report = nlohmann::json::parse(readText(path("sun.json")));
    EXPECT_EQ(report["chosen"]["lights"], 2) << report.dump(1);
    EXPECT_EQ(report["chosen"]["order"], 1) << report.dump(1);
    EXPECT_NE(readText(path("sun.toml")).find("run = \"envlight\""), std::string::npos);
    ASSERT_EQ(runPrt("run " + path("sun.toml") + " --cache-dir " + path("cache"), dir).exitCode, 0);
    ASSERT_EQ(runPrt("reference " + path("sphere.glb") + " --env " + path("sun.exr") +
                         " --bounces 0 --albedo 0.8,0.8,0.8 --samples 256 -o " + path("sun-ref.npy"),
                     dir)
                  .exitCode,
              0);
    ASSERT_EQ(runPrt("compare " + path("out/sun.sun.npy") + " " + path("sun-ref.npy") + " -o " + path("m.json"), dir)
                  .exitCode,
              0);
    nlohmann::json metrics = nlohmann::json::parse(readText(path("m.json")));
    EXPECT_LE(metrics["relative_rmse"].get<double>(), target + 0.02) << metrics.dump(1); // plus 256-path noise
}

TEST_F(AutoconfigCli, RefusesTargetsAtOrBelowZeroAndBelowTheReferenceNoiseWithNoOutput) {
    struct Case {
        std::string arguments;
        const char* message;
    };
    for (const Case& c : {Case{" --target-error 0", "must be > 0"}, Case{" --target-error -0.01", "must be > 0"},
                          Case{"", "--target-error"},
                          Case{" --target-error 0.002 --max-reference-samples 64", "reference's own noise"},
                          Case{" --target-error 0.05 --formats cpca", "cpca"}}) {
        CliRun run = runPrt(base() + c.arguments + " -o " + path("refused.toml"), dir);
        EXPECT_EQ(run.exitCode, 2) << c.arguments << "\n" << run.stderrText;
        EXPECT_NE(run.stderrText.find(c.message), std::string::npos) << c.arguments << "\n" << run.stderrText;
        EXPECT_FALSE(fs::exists(dir / "refused.toml")) << c.arguments;
    }
}
