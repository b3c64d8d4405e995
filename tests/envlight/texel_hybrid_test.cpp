// The texel hybrid end to end: `prt bake` writes what it needs ("texel_surface", and "texel_transfer_bounce" with
// bounces) and `prt relight --texels --lights` relights every texel, in closed form on an open plane.
#include "cli_util.h"

#include "bundle.h"
#include "core.h"
#include "image.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace fs = std::filesystem;

namespace {

class TexelHybrid : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("prt_texel_hybrid_" + std::to_string(getpid()));
        fs::create_directories(dir);
        ASSERT_EQ(run("scene plane -o " + path("plane.glb")).exitCode, 0);
    }
    void TearDown() override { fs::remove_all(dir); }

    prt::test::CliRun run(const std::string& arguments) { return prt::test::runPrt(arguments, dir); }
    std::string path(const std::string& name) const { return (dir / name).string(); }

    // One cone light of radiance `radiance` and radius `radius` toward `direction`, no residual, at `order`.
    std::string writeLights(const std::string& name, const std::array<double, 3>& direction,
                            const std::array<double, 3>& radiance, double radius, int order) {
        nlohmann::json residual = nlohmann::json::array();
        for (int j = 0; j < order * order; ++j) residual.push_back({0.0, 0.0, 0.0});
        nlohmann::json document = {{"format", "prt-lights"},
                                   {"order", order},
                                   {"residual", residual},
                                   {"lights", {{{"direction", direction}, {"radiance", radiance}, {"angular_radius", radius}}}}};
        std::ofstream(path(name)) << document.dump();
        return path(name);
    }
    fs::path dir;
};

} // namespace

// Unoccluded plane, light overhead: outgoing radiance = albedo / pi * L * pi sin^2(r), in every texel (gutters too:
// their filled normals and visibility are those of the plane).
TEST_F(TexelHybrid, OpenPlaneUnderOneConeIsAlbedoTimesRadianceTimesSinSquared) {
    ASSERT_EQ(run("bake " + path("plane.glb") + " -o " + path("bake.glb") +
                  " --resolution 16 --order 2 --samples 16 --albedo 0.5,0.6,0.7 --quiet")
                  .exitCode,
              0);
    const double radius = 0.2;
    std::string lights = writeLights("lights.json", {0.0, 1.0, 0.0}, {2.0, 3.0, 4.0}, radius, 2);
    prt::test::CliRun r = run("relight " + path("bake.glb") + " --texels --lights " + lights + " -o " +
                              path("radiance.exr") + " --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    prt::Image image = prt::readImage(path("radiance.exr"));
    ASSERT_EQ(image.width, 16);
    ASSERT_EQ(image.height, 16);
    const double albedo[3] = {0.5, 0.6, 0.7}, radiance[3] = {2.0, 3.0, 4.0};
    const double sin2 = std::sin(radius) * std::sin(radius);
    for (size_t t = 0; t < image.rgb.size() / 3; ++t)
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(image.rgb[3 * t + c], albedo[c] * radiance[c] * sin2, 1e-5) << "texel " << t << " colour " << c;

    // Below the horizon the cone gives nothing.
    lights = writeLights("below.json", {0.0, -1.0, 0.0}, {2.0, 3.0, 4.0}, radius, 2);
    ASSERT_EQ(run("relight " + path("bake.glb") + " --texels --lights " + lights + " -o " + path("below.exr") +
                  " --quiet")
                  .exitCode,
              0);
    for (float x : prt::readImage(path("below.exr")).rgb) ASSERT_EQ(x, 0.0f);
}

TEST_F(TexelHybrid, ABakeWithBouncesCarriesTheBounceLayerAndEveryBakeItsSurface) {
    ASSERT_EQ(run("bake " + path("plane.glb") + " -o " + path("bounced.glb") +
                  " --resolution 8 --order 2 --samples 8 --bounces 1 --format bundle --quiet")
                  .exitCode,
              0);
    prt::Bundle bundle = prt::readBundle(path("bounced.glb"));
    const prt::Layer* bounce = prt::findLayer(bundle, "texel_transfer_bounce");
    const prt::Layer* surface = prt::findLayer(bundle, "texel_surface");
    ASSERT_TRUE(bounce && surface);
    EXPECT_EQ(bounce->shape, (std::vector<uint64_t>{64, 4, 3}));
    EXPECT_EQ(surface->shape, (std::vector<uint64_t>{64, 10}));
    for (float x : bounce->data) EXPECT_EQ(x, 0.0f) << "an open plane sees no other surface";
    size_t covered = 0;
    for (size_t t = 0; t < 64; ++t) {
        const float* row = &surface->data[t * 10];
        EXPECT_NEAR(row[4], 1.0f, 1e-6f) << "the plane's normal is +Y";
        covered += row[9] == 1.0f;
    }
    EXPECT_EQ(covered, 64u) << "the plane's atlas covers every texel of an 8 x 8 bake";
}

TEST_F(TexelHybrid, ABakeWithoutTheSurfaceLayerIsRefusedWithoutOutput) {
    ASSERT_EQ(run("bake " + path("plane.glb") + " -o " + path("bake.glb") +
                  " --resolution 8 --order 2 --samples 8 --format bundle --quiet")
                  .exitCode,
              0);
    prt::Bundle bundle = prt::readBundle(path("bake.glb"));
    std::erase_if(bundle.layers, [](const prt::Layer& layer) { return layer.name == "texel_surface"; });
    prt::writeBundle(path("old.glb"), bundle);
    std::string lights = writeLights("lights.json", {0.0, 1.0, 0.0}, {1.0, 1.0, 1.0}, 0.1, 2);
    prt::test::CliRun r = run("relight " + path("old.glb") + " --texels --lights " + lights + " -o " + path("out.exr"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.stderrText.find("texel_surface"), std::string::npos) << r.stderrText;
    EXPECT_NE(r.stderrText.find("bake it again"), std::string::npos) << r.stderrText;
    EXPECT_FALSE(fs::exists(path("out.exr")));
}
