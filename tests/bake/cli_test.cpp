// `prt bake` and `prt relight --texels` end to end through the binary: bad input exits non-zero naming the problem
// and leaves no output file; a good bake relights into an atlas image.
#include "bake.h"

#include "core.h"
#include "image.h"
#include "runtime.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace prt {
namespace {

struct CliRun {
    int exitCode;
    std::string stderrText;
};

class BakeCli : public ::testing::Test {
protected:
    fs::path dir, out;

    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir = fs::temp_directory_path() / ("prt_bake_cli_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir);
        fs::create_directories(dir / "out");
        out = dir / "out";
    }
    void TearDown() override { fs::remove_all(dir); }

    CliRun run(const std::string& arguments) {
        fs::path log = dir / "stderr.txt";
        int status = std::system((std::string(PRT_EXECUTABLE) + " " + arguments + " 2> " + log.string()).c_str());
        std::stringstream text;
        text << std::ifstream(log).rdbuf();
        return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
    }

    std::string mesh(const std::string& name, const TriMesh& mesh) {
        Bundle bundle;
        bundle.mesh = mesh;
        std::string path = (dir / name).string();
        writeBundle(path, bundle);
        return path;
    }

    // Bakes `input` (plus `extra` flags) into out/baked.glb, expecting failure with `code` and a message that
    // contains `needle`, and nothing at all in out/.
    void expectRefused(const std::string& input, const std::string& extra, int code, const std::string& needle) {
        CliRun result = run("bake " + input + " -o " + (out / "baked.glb").string() +
                            " --resolution 32 --order 2 --samples 16 " + extra);
        EXPECT_EQ(result.exitCode, code) << result.stderrText;
        EXPECT_NE(result.stderrText.find(needle), std::string::npos) << result.stderrText;
        EXPECT_TRUE(fs::is_empty(out)) << "a refused bake left files in " << out;
    }
};

TEST_F(BakeCli, UvsOutsideTheUnitSquareWithoutWrap) {
    TriMesh plane = makePlane(1.0f, 2);
    plane.texcoords[0] = 1.5f;
    std::string input = mesh("outside.glb", plane);
    expectRefused(input, "", kExitInput, "outside [0, 1]");
    expectRefused(input, "", kExitInput, input);
}

TEST_F(BakeCli, OverlappingUvs) {
    TriMesh plane = makePlane(1.0f, 2);
    TriMesh twice = mergeMeshes({plane, makePlane(1.0f, 2, 1.0f)});
    expectRefused(mesh("overlap.glb", twice), "", kExitInput, "overlap");
}

TEST_F(BakeCli, ResolutionZeroOrAboveTheLimit) {
    std::string input = mesh("plane.glb", makePlane(1.0f, 2));
    expectRefused(input, "--resolution 0", kExitUsage, "--resolution");
    expectRefused(input, "--resolution " + std::to_string(kMaxBakeResolution + 1), kExitUsage, "--resolution");
}

TEST_F(BakeCli, HighMeshThatDoesNotCoverTheLowOne) {
    std::string input = mesh("low.glb", makePlane(1.0f, 2));
    std::string high = mesh("high.glb", makePlane(0.4f, 8, 0.001f));
    expectRefused(input, "--high " + high, kExitInput, "does not cover");
}

// An open plane under constant radiance L: every texel's transfer is the clamped cosine about +Y, so relit
// radiance is L everywhere (gutters included, push-pull fills them from covered texels).
TEST_F(BakeCli, RelightTexelsWritesTheRadianceAtlas) {
    Image env;
    env.width = 256; // fine enough that projecting the constant onto order 3 is exact to float precision
    env.height = 128;
    env.rgb.assign(256 * 128 * 3, 0.0f);
    const float radiance[3] = {0.25f, 0.5f, 1.0f};
    for (size_t p = 0; p < 256 * 128; ++p)
        for (int c = 0; c < 3; ++c) env.rgb[3 * p + c] = radiance[c];
    std::string envPath = (dir / "constant.exr").string();
    writeImage(envPath, env);
    std::string input = mesh("plane.glb", makePlane(1.0f, 2));

    for (const char* format : {"half", "u8"}) {
        std::string bundle = (out / (std::string(format) + ".glb")).string();
        CliRun bake =
            run("bake " + input + " -o " + bundle + " --resolution 16 --order 3 --samples 16 --format " + format);
        ASSERT_EQ(bake.exitCode, 0) << bake.stderrText;
        std::string atlas = (out / (std::string(format) + "_radiance.exr")).string();
        CliRun relit = run("relight " + bundle + " --texels --env " + envPath + " -o " + atlas);
        ASSERT_EQ(relit.exitCode, 0) << relit.stderrText;
        Image image = readImage(atlas);
        ASSERT_EQ(image.width, 16);
        ASSERT_EQ(image.height, 16);
        for (size_t p = 0; p < 16 * 16; ++p)
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(image.rgb[3 * p + c], radiance[c], 2e-3 * radiance[c]) << format << " texel " << p;
    }

    // A per-vertex output name, or a bundle without texel transfer, is refused without output.
    std::string bad = (out / "radiance.npy").string();
    EXPECT_EQ(run("relight " + (out / "half.glb").string() + " --texels --env " + envPath + " -o " + bad).exitCode,
              kExitUsage);
    EXPECT_FALSE(fs::exists(bad));
    std::string none = (out / "none.exr").string();
    CliRun missing = run("relight " + input + " --texels --env " + envPath + " -o " + none);
    EXPECT_EQ(missing.exitCode, kExitInput);
    EXPECT_NE(missing.stderrText.find("texel_transfer"), std::string::npos) << missing.stderrText;
    EXPECT_FALSE(fs::exists(none));

    // A texture changed after the bake is caught by its hash.
    {
        // Texture names carry their content hash: the one the bundle names.
        std::string texture = findLayer(readBundle((out / "half.glb").string()), "texel_transfer")->params["uri"];
        std::ofstream tamper((out / texture).string(), std::ios::app | std::ios::binary);
        tamper << "x";
    }
    CliRun tampered = run("relight " + (out / "half.glb").string() + " --texels --env " + envPath + " -o " + none);
    EXPECT_EQ(tampered.exitCode, kExitInput);
    EXPECT_NE(tampered.stderrText.find("hash"), std::string::npos) << tampered.stderrText;
    EXPECT_FALSE(fs::exists(none));
}

// A bake killed anywhere (the kill hook, core.h checkpoint) never breaks the last good result: textures are named
// by content, written before the bundle, and only this bake's new files are ever removed. After each kill the
// bundle at the output path relights with every texture hash intact: the old bake's or, past the final rename,
// the new one's.
TEST_F(BakeCli, KilledBakeNeverBreaksTheLastGoodResult) {
    std::string input = mesh("plane.glb", makePlane(1.0f, 2));
    std::string output = (out / "baked.glb").string();
    const std::string flags = " --resolution 16 --order 2 --samples 16 --format u8";
    ASSERT_EQ(run("bake " + input + " -o " + output + flags + " --seed 1").exitCode, 0);
    std::string good = hashFile(output);
    std::string counter = (dir / "count").string();
    ASSERT_EQ(run("bake " + input + " -o " + (dir / "probe.glb").string() + flags + " --seed 2").exitCode, 0);
    fs::remove(counter);
    ASSERT_EQ(std::system(("PRT_KILL_COUNTER=" + counter + " " + PRT_EXECUTABLE + " --quiet bake " + input + " -o " +
                           (dir / "probe.glb").string() + flags + " --seed 2").c_str()), 0);
    long total = long(fs::file_size(counter));
    ASSERT_GT(total, 3);
    auto bakeFiles = [&] {
        std::vector<std::string> names;
        for (const auto& item : fs::directory_iterator(out)) {
            const std::string name = item.path().filename().string();
            if (name.rfind("baked.", 0) == 0 || name.rfind(".baked.", 0) == 0) names.push_back(name);
        }
        std::sort(names.begin(), names.end());
        return names;
    };
    int killed = 0;
    long messiest = 1; // the kill point that left the most files
    size_t mostLeft = 0;
    for (long point = 1; point <= total; ++point) {
        SCOPED_TRACE("kill point " + std::to_string(point) + " of " + std::to_string(total));
        int status = std::system(("PRT_KILL_AT=" + std::to_string(point) + " " + PRT_EXECUTABLE + " --quiet bake " + input +
                                  " -o " + output + flags + " --seed 2 2>/dev/null").c_str());
        killed += !(WIFEXITED(status) && WEXITSTATUS(status) == 0);
        EXPECT_NO_THROW(loadTexelRelightModel(output));
        std::string now = hashFile(output);
        if (now != good) { // the new bake landed: later kills leave it (same content, same names)
            good = now;
        }
        if (bakeFiles().size() > mostLeft) mostLeft = bakeFiles().size(), messiest = point;
    }
    EXPECT_EQ(killed, total);
    std::printf("bake kill test: %ld kill points, each left a loadable bundle\n", total);

    // What the kills left (hidden temporaries, textures written before a bundle that never landed) goes with the
    // next bake of the output: the folder then holds the bundle and exactly the textures it names.
    std::system(("PRT_KILL_AT=" + std::to_string(messiest) + " " + PRT_EXECUTABLE + " --quiet bake " + input + " -o " +
                 output + flags + " --seed 3 2>/dev/null").c_str());
    const size_t leftByKills = bakeFiles().size();
    ASSERT_EQ(run("bake " + input + " -o " + output + flags + " --seed 4").exitCode, 0);
    std::vector<std::string> named = {"baked.glb"};
    for (const Layer& layer : readBundle(output).layers)
        if (layer.params.contains("files"))
            for (const nlohmann::json& file : layer.params["files"]) named.push_back(file.get<std::string>());
    std::sort(named.begin(), named.end());
    EXPECT_EQ(bakeFiles(), named);
    EXPECT_GT(leftByKills, named.size()) << "the kills left nothing to clean, so this proves nothing";
}

} // namespace
} // namespace prt
