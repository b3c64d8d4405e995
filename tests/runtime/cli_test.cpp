// `prt relight` end to end: the binary reads a bundle and lighting, writes radiance, or fails with no output.
#include "cli_util.h"
#include "compare.h"
#include "core.h"
#include "image.h"
#include "runtime.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using prt::test::CliRun;
using prt::test::runPrt;

class RelightCli : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("prt_relight_cli_" + std::to_string(getpid()));
        fs::create_directories(dir);
        // Unoccluded white sphere points at order 2: transfer = A_l Y_lm(n) / pi, so constant radiance L gives L.
        prt::Bundle bundle;
        bundle.mesh.positions = {1, 0, 0, 0, 1, 0, 0, 0, -1, -0.6f, 0.8f, 0};
        bundle.mesh.indices = {0, 1, 2, 0, 2, 3};
        prt::Layer layer;
        layer.name = "transfer";
        layer.domain = "vertex";
        layer.semantic = "sh_transfer_rgb";
        layer.shape = {4, 4, 3};
        layer.params = {{"order", 2}};
        for (size_t v = 0; v < 4; ++v) {
            const float* n = &bundle.mesh.positions[v * 3];
            float basis[4];
            prt::sh::evaluate(2, n[0], n[1], n[2], basis);
            for (int j = 0; j < 4; ++j)
                for (int c = 0; c < 3; ++c)
                    layer.data.push_back(float(prt::sh::clampedCosine(j == 0 ? 0 : 1) * basis[j] / std::numbers::pi));
        }
        bundle.layers.push_back(layer);
        prt::writeBundle((dir / "sphere.glb").string(), bundle);
        bundle.layers[0].name = "ambient_occlusion";
        prt::writeBundle((dir / "no_transfer.glb").string(), bundle);
    }
    void TearDown() override { fs::remove_all(dir); }

    fs::path dir;
};

} // namespace

TEST_F(RelightCli, ShLightingOfHigherOrderGivesTheFurnaceRadiance) {
    // Constant radiance (1, 2, 3): its only coefficient is L sqrt(4 pi). The order-3 file also holds a band-2
    // coefficient, beyond the transfer's two bands, which must be dropped rather than change the result.
    const double y0 = 2.0 * std::sqrt(std::numbers::pi);
    std::ofstream(dir / "light.json") << "{\"format\":\"prt-sh\",\"order\":3,\"coefficients\":[[" << y0 << ","
                                      << 2 * y0 << "," << 3 * y0 << "],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],"
                                      << "[0,0,0],[0,0,0],[5,5,5]]}";
    for (const char* rotate : {"", "--rotate-y 360"}) {
        CliRun run = runPrt("relight " + (dir / "sphere.glb").string() + " --sh " + (dir / "light.json").string() +
                                " " + rotate + " -o " + (dir / "out.npy").string(),
                            dir);
        ASSERT_EQ(run.exitCode, 0) << run.stderrText;
        std::vector<float> radiance = prt::readVertexRadiance((dir / "out.npy").string());
        ASSERT_EQ(radiance.size(), 12u);
        for (int v = 0; v < 4; ++v)
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(radiance[v * 3 + c], c + 1.0f, 1e-5f) << rotate << v << c;
    }
}

TEST_F(RelightCli, EnvironmentMapRotatedWritesCsv) {
    // Brighter toward +X than -X: a quarter turn about +Y (+X goes to -Z) makes the vertex facing -Z the bright one.
    prt::Image image;
    image.width = 32;
    image.height = 16;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x) {
            double d[3];
            prt::sh::equirectDirection(32, 16, x, y, d);
            for (int c = 0; c < 3; ++c) image.rgb.push_back(float(1.0 + 0.5 * d[0]));
        }
    prt::writeImage((dir / "env.exr").string(), image);

    CliRun run = runPrt("relight " + (dir / "sphere.glb").string() + " --env " + (dir / "env.exr").string() +
                            " --rotate-y 90 --window none -o " + (dir / "out.csv").string(),
                        dir);
    ASSERT_EQ(run.exitCode, 0) << run.stderrText;
    std::vector<float> radiance = prt::readVertexRadiance((dir / "out.csv").string());
    ASSERT_EQ(radiance.size(), 12u);
    // Lighting 1 + 0.5 d.a reflects off a white Lambertian point with normal n as 1 + 0.5 (A_1 / A_0) n.a
    // = 1 + n.a / 3. The turn takes a from +X to -Z.
    const float expected[4] = {1.0f, 1.0f, 1.0f + 1.0f / 3.0f, 1.0f};
    for (int v = 0; v < 4; ++v)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(radiance[v * 3 + c], expected[v], 2e-3f) << v << " " << c;
}

TEST_F(RelightCli, ErrorsLeaveNoOutput) {
    std::ofstream(dir / "light.json") << R"({"format":"prt-sh","order":1,"coefficients":[[1,1,1]]})";
    prt::Image wide;
    wide.width = 30;
    wide.height = 10;
    wide.rgb.assign(300 * 3, 1.0f);
    prt::writeImage((dir / "wide.exr").string(), wide);
    const std::string out = (dir / "out.npy").string();

    CliRun noTransfer = runPrt("relight " + (dir / "no_transfer.glb").string() + " --sh " +
                                   (dir / "light.json").string() + " -o " + out,
                               dir);
    EXPECT_EQ(noTransfer.exitCode, prt::kExitInput);
    EXPECT_NE(noTransfer.stderrText.find("no_transfer.glb"), std::string::npos) << noTransfer.stderrText;
    EXPECT_NE(noTransfer.stderrText.find("transfer"), std::string::npos) << noTransfer.stderrText;

    CliRun badEnv = runPrt("relight " + (dir / "sphere.glb").string() + " --env " + (dir / "wide.exr").string() +
                               " -o " + out,
                           dir);
    EXPECT_EQ(badEnv.exitCode, prt::kExitInput);
    EXPECT_NE(badEnv.stderrText.find("wide.exr"), std::string::npos) << badEnv.stderrText;

    CliRun both = runPrt("relight " + (dir / "sphere.glb").string() + " --sh " + (dir / "light.json").string() +
                             " --env " + (dir / "wide.exr").string() + " -o " + out,
                         dir);
    EXPECT_NE(both.exitCode, 0);

    CliRun badWindow = runPrt("relight " + (dir / "sphere.glb").string() + " --sh " +
                                  (dir / "light.json").string() + " --window box -o " + out,
                              dir);
    EXPECT_EQ(badWindow.exitCode, prt::kExitUsage);
    EXPECT_FALSE(fs::exists(out));
}
