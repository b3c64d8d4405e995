// `prt relight --lights` and `prt render --lights` of a glossy bundle end to end: zero lights give the plain lobes,
// the picture of relight and render agree, and every bad combination is refused by name with no output.
#include "bundle.h"
#include "cli_util.h"
#include "compare.h"
#include "core.h"
#include "image.h"
#include "render.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using prt::test::runPrt; // stderr captured in DIR/stderr.txt

// One fit and one lights file for the suite (the fit is most of its time).
class GlossyLightsCli : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        env = std::string(PRT_DATA_DIR) + "/env/sunrise.exr";
        if (!fs::exists(env)) return;
        dir = fs::temp_directory_path() / ("prt_glossy_lights_cli_" + std::to_string(getpid()));
        fs::create_directories(dir);
        ready = runPrt("scene sphere -o " + path("sphere.glb") + " --quiet", dir).exitCode == 0 &&
                runPrt("glossy " + path("sphere.glb") + " -o " + path("g.glb") +
                           " --brdf phong:16,0.5 --albedo 0.3 --order 3 --grid 4 --samples 64 --quiet", dir).exitCode == 0 &&
                runPrt("envlight " + env + " --order 3 --max-lights 2 -o " + path("l.json") + " --quiet", dir).exitCode == 0;
    }
    static void TearDownTestSuite() {
        if (!dir.empty()) fs::remove_all(dir);
    }
    void SetUp() override {
        if (!fs::exists(env)) GTEST_SKIP() << "no " << env;
        ASSERT_TRUE(ready) << "the sphere, its glossy fit or the lights failed";
    }
    static std::string path(const std::string& name) { return (dir / name).string(); }
    static inline std::string env;
    static inline fs::path dir;
    static inline bool ready = false;
};

std::vector<float> rows(const std::string& path) { return prt::readVertexRadiance(path); }

} // namespace

// A lights file with no lights: the residual map is the map, the lights add nothing, so the glossy part equals the
// plain lobes' bit for bit; with the lights the glossy part differs, and every value is finite.
TEST_F(GlossyLightsCli, ZeroLightsGiveThePlainLobesAndLightsChangeOnlyTheSplit) {
    nlohmann::json document = nlohmann::json::parse(std::ifstream(path("l.json")));
    ASSERT_GE(document["lights"].size(), 1u);
    document["lights"] = nlohmann::json::array();
    std::ofstream(path("none.json")) << document.dump();
    const std::string eye = " --eye 0.5,1,4";
    ASSERT_EQ(runPrt("relight " + path("g.glb") + " --env " + env + eye + " --glossy-only -o " + path("plain.npy") +
                      " --quiet", dir).exitCode, 0);
    prt::test::CliRun none = runPrt("relight " + path("g.glb") + " --env " + env + " --lights " + path("none.json") + eye +
                          " --glossy-only -o " + path("none.npy") + " --quiet", dir);
    ASSERT_EQ(none.exitCode, 0) << none.stderrText;
    EXPECT_EQ(rows(path("none.npy")), rows(path("plain.npy")));
    prt::test::CliRun lit = runPrt("relight " + path("g.glb") + " --env " + env + " --lights " + path("l.json") + eye + " -o " +
                         path("lit.npy") + " --quiet", dir);
    ASSERT_EQ(lit.exitCode, 0) << lit.stderrText;
    prt::test::CliRun glossy = runPrt("relight " + path("g.glb") + " --env " + env + " --lights " + path("l.json") + eye +
                            " --glossy-only -o " + path("lit_glossy.npy") + " --quiet", dir);
    ASSERT_EQ(glossy.exitCode, 0) << glossy.stderrText;
    const std::vector<float> total = rows(path("lit.npy")), part = rows(path("lit_glossy.npy"));
    ASSERT_EQ(total.size(), part.size());
    for (size_t i = 0; i < total.size(); ++i) {
        ASSERT_TRUE(std::isfinite(total[i]));
        EXPECT_GE(total[i] + 1e-6f, part[i]); // the diffuse hybrid adds light (this sphere has no negatives)
    }
    EXPECT_NE(part, rows(path("plain.npy")));
    // `prt render --vertex-radiance` draws those rows as renderVertexRadiance does.
    prt::test::CliRun drawn = runPrt("render " + path("g.glb") + " --vertex-radiance " + path("lit.npy") +
                              " --size 16,12 --camera 0,0.5,4,0,0,0,0,1,0,35 -o " + path("lit.exr") + " --quiet", dir);
    ASSERT_EQ(drawn.exitCode, 0) << drawn.stderrText;
    prt::PinholeCamera camera;
    camera.eye = {0.0f, 0.5f, 4.0f};
    camera.fovyDegrees = 35.0f;
    camera.width = 16;
    camera.height = 12;
    const prt::RenderedImage expected = prt::renderVertexRadiance(prt::readBundle(path("g.glb")).mesh, total, camera);
    EXPECT_EQ(prt::readImage(path("lit.exr")).rgb, expected.radiance.rgb);
}

// `prt relight --lights --image` and `prt render --lights` draw the same picture.
TEST_F(GlossyLightsCli, RelightImageAndRenderAgree) {
    const std::string camera = " --camera 0,0.5,4,0,0,0,0,1,0,35";
    prt::test::CliRun picture = runPrt("relight " + path("g.glb") + " --env " + env + " --lights " + path("l.json") +
                             " --image 24,20" + camera + " -o " + path("pic.exr") + " --quiet", dir);
    ASSERT_EQ(picture.exitCode, 0) << picture.stderrText;
    prt::test::CliRun render = runPrt("render " + path("g.glb") + " --env " + env + " --lights " + path("l.json") + " --size 24,20" +
                            camera + " -o " + path("render.exr") + " --quiet", dir);
    ASSERT_EQ(render.exitCode, 0) << render.stderrText;
    const prt::Image a = prt::readImage(path("pic.exr")), b = prt::readImage(path("render.exr"));
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    double sum = 0.0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
        ASSERT_EQ(a.rgb[i], b.rgb[i]) << i;
        sum += a.rgb[i];
    }
    EXPECT_GT(sum, 0.0);
}

// Bad combinations: refused by name (exit 2 for the command line, 3 for a file), no output.
TEST_F(GlossyLightsCli, BadCombinationsAreRefusedByName) {
    ASSERT_EQ(runPrt("transfer " + path("sphere.glb") + " --order 3 --samples 16 -o " + path("diffuse.glb") + " --quiet",
                  dir).exitCode, 0);
    const std::string lights = " --lights " + path("l.json");
    const std::string relight = "relight " + path("g.glb") + " --env " + env + lights;
    struct Case {
        std::string arguments;
        int exitCode;
        std::string names;
    };
    const std::vector<Case> cases = {
        {"relight " + path("diffuse.glb") + " --env " + env + lights + " --eye 0,0,4 -o " + path("bad.npy"), 3,
         "glossy_lobes"},
        {"relight " + path("g.glb") + lights + " --eye 0,0,4 -o " + path("bad.npy"), 2, "--env"},
        {relight + " --eye 0,0,4 --texels -o " + path("bad.exr"), 2, "--texels"},
        {relight + " --eye 0,0,4 --rotate-y 30 -o " + path("bad.npy"), 2, "--rotate-y"},
        {relight + " --glossy-only -o " + path("bad.npy"), 2, "--glossy-only"},
        {relight + " --eye 0,0,4 --residual-negatives maybe -o " + path("bad.npy"), 2, "--residual-negatives"},
        {relight + " --eye 0,0,4 --light-samples 0 -o " + path("bad.npy"), 2, "--light-samples"},
        {"relight " + path("g.glb") + " --env " + env + " --eye 0,0,4 --residual-negatives clamp -o " + path("bad.npy"), 2,
         "--residual-negatives"},
        {"relight " + path("g.glb") + " --env " + std::string(PRT_DATA_DIR) + "/env/city.exr" + lights +
             " --eye 0,0,4 -o " + path("bad.npy"), 3, "input.hash"},
        {"render " + path("diffuse.glb") + " --env " + env + lights + " --size 8,8 --camera 0,0,4,0,0,0,0,1,0,35 -o " +
             path("bad.exr"), 3, "glossy_lobes"},
        {"render " + path("g.glb") + " --env " + env + lights + " --order 2 --size 8,8 --camera 0,0,4,0,0,0,0,1,0,35 -o " +
             path("bad.exr"), 2, "--order"},
        {"render " + path("g.glb") + " --env " + env + " --light-samples 8 --size 8,8 --camera 0,0,4,0,0,0,0,1,0,35 -o " +
             path("bad.exr"), 2, "--light-samples"},
        {"render " + path("g.glb") + " --env " + env + " --vertex-radiance " + path("sphere.glb") +
             " --size 8,8 --camera 0,0,4,0,0,0,0,1,0,35 -o " + path("bad.exr"), 2, "--vertex-radiance"},
        {"render " + path("g.glb") + " --size 8,8 --camera 0,0,4,0,0,0,0,1,0,35 -o " + path("bad.exr"), 2, "--env"},
    };
    for (const Case& c : cases) {
        prt::test::CliRun run = runPrt(c.arguments, dir);
        EXPECT_EQ(run.exitCode, c.exitCode) << c.arguments << "\n" << run.stderrText;
        EXPECT_NE(run.stderrText.find(c.names), std::string::npos) << c.arguments << "\n" << run.stderrText;
    }
    EXPECT_FALSE(fs::exists(dir / "bad.npy"));
    EXPECT_FALSE(fs::exists(dir / "bad.exr"));
}
