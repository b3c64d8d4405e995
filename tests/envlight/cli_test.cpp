// `prt envlight` end to end: a disc map gives its light in prt-lights JSON; bad inputs exit non-zero with no output.
#include "cli_util.h"
#include "envlight_maps.h"

#include "core.h"
#include "runtime.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace envlight_test;

namespace {

using prt::test::CliRun;

class EnvlightCli : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("prt_envlight_cli_" + std::to_string(getpid()));
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }

    CliRun run(const std::string& arguments) { return prt::test::runPrt(arguments, dir); }
    std::string writeMap(const std::string& name, const prt::EnvironmentMap& env) {
        std::string path = (dir / name).string();
        prt::writeImage(path, env.radiance);
        return path;
    }
    fs::path dir;
};

} // namespace

TEST_F(EnvlightCli, WritesTheLightAndTheResidual) {
    Disc disc{unit(-0.3, 0.7, 0.6), 6.0, {30.0, 30.0, 30.0}};
    std::string map = writeMap("disc.exr", discMap(256, 1.0, {disc}));
    std::string out = (dir / "lights.json").string();
    CliRun r = run("envlight " + map + " -o " + out + " --order 3 --max-lights 2 --icosphere-level 5");
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    nlohmann::json doc = nlohmann::json::parse(std::ifstream(out));
    EXPECT_EQ(doc["format"], "prt-lights");
    EXPECT_EQ(doc["order"], 3);
    EXPECT_EQ(doc["residual"].size(), 9u);
    ASSERT_EQ(doc["lights"].size(), 1u);
    std::array<double, 3> d = doc["lights"][0]["direction"].get<std::array<double, 3>>();
    EXPECT_LT(angleDegrees(d, disc.direction), 0.3);
    EXPECT_NEAR(doc["lights"][0]["angular_radius_degrees"].get<double>(), 6.0, 0.5);
    EXPECT_EQ(doc["input"]["hash"], prt::hashFile(map));
}

TEST_F(EnvlightCli, BadInputsExitNonZeroWithNoOutput) {
    std::string out = (dir / "lights.json").string();
    std::string zero = writeMap("zero.exr", discMap(64, 0.0, {}));
    CliRun r = run("envlight " + zero + " -o " + out);
    EXPECT_EQ(r.exitCode, 3) << r.stderrText;
    EXPECT_NE(r.stderrText.find("zero everywhere"), std::string::npos) << r.stderrText;
    EXPECT_FALSE(fs::exists(out));

    std::string negative = writeMap("negative.exr", discMap(64, -1.0, {}));
    r = run("envlight " + negative + " -o " + out);
    EXPECT_EQ(r.exitCode, 3) << r.stderrText;
    EXPECT_NE(r.stderrText.find("negative"), std::string::npos) << r.stderrText;
    EXPECT_FALSE(fs::exists(out));

    std::string constant = writeMap("constant.exr", discMap(64, 1.0, {}));
    r = run("envlight " + constant + " -o " + out + " --max-lights 0 --min-lights 1");
    EXPECT_EQ(r.exitCode, 2) << r.stderrText;
    EXPECT_NE(r.stderrText.find("--max-lights"), std::string::npos) << r.stderrText;
    EXPECT_FALSE(fs::exists(out));

    r = run("envlight " + constant + " -o " + out + " --min-lights 1 --icosphere-level 4");
    EXPECT_EQ(r.exitCode, 3) << r.stderrText;
    EXPECT_FALSE(fs::exists(out));
}

namespace {

double relativeRmse(const std::vector<float>& a, const std::vector<float>& reference) {
    double error = 0.0, norm = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        error += (a[i] - reference[i]) * (a[i] - reference[i]);
        norm += reference[i] * reference[i];
    }
    return std::sqrt(error / norm);
}

} // namespace

// Two spheres that shadow and light each other under a constant sky plus a 4-degree sun: the hybrid (order 3 plus
// the sun as a cone) against plain order 3, both against the path tracer.
TEST_F(EnvlightCli, HybridRelightBeatsPlainSh) {
    std::string scene = (dir / "two.glb").string(), bundle = (dir / "two_t.glb").string();
    ASSERT_EQ(run("scene two-spheres -o " + scene).exitCode, 0);
    CliRun r = run("transfer " + scene + " -o " + bundle +
                   " --mode interreflected --bounces 2 --samples 256 --order 3 --albedo 0.8");
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    prt::Bundle read = prt::readBundle(bundle);
    const prt::Layer* bounce = prt::findLayer(read, "transfer_bounce");
    ASSERT_NE(bounce, nullptr);
    EXPECT_EQ(bounce->semantic, "sh_transfer_bounce_rgb");

    Disc sun{unit(0.3, 0.8, -0.5), 4.0, {200.0, 200.0, 200.0}};
    std::string map = writeMap("sun.exr", discMap(256, 0.5, {sun}));
    std::string lights = (dir / "lights.json").string();
    ASSERT_EQ(run("envlight " + map + " -o " + lights + " --order 3").exitCode, 0);
    std::string hybrid = (dir / "hybrid.npy").string(), plain = (dir / "plain.npy").string();
    std::string reference = (dir / "reference.npy").string();
    r = run("relight " + bundle + " --env " + map + " --lights " + lights + " -o " + hybrid);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    ASSERT_EQ(run("relight " + bundle + " --env " + map + " -o " + plain).exitCode, 0);
    ASSERT_EQ(run("reference " + scene + " --env " + map + " --bounces 2 --albedo 0.8 --samples 512 -o " + reference)
                  .exitCode,
              0);
    std::vector<size_t> shape;
    std::vector<float> ref = prt::readNpy(reference, &shape);
    double hybridError = relativeRmse(prt::readNpy(hybrid, &shape), ref);
    double plainError = relativeRmse(prt::readNpy(plain, &shape), ref);
    EXPECT_LT(hybridError, 0.85 * plainError) << hybridError << " against " << plainError;

    // A lights file of another order than the bundle, a non-finite light, lights with --sh, lights from another map.
    std::string wrongOrder = (dir / "order2.json").string(), out = (dir / "bad.npy").string();
    ASSERT_EQ(run("envlight " + map + " -o " + wrongOrder + " --order 2").exitCode, 0);
    r = run("relight " + bundle + " --lights " + wrongOrder + " -o " + out);
    EXPECT_EQ(r.exitCode, 3) << r.stderrText;
    EXPECT_NE(r.stderrText.find("order"), std::string::npos) << r.stderrText;
    EXPECT_FALSE(fs::exists(out));

    nlohmann::json document = nlohmann::json::parse(std::ifstream(lights));
    document["lights"][0]["radiance"][1] = "nan";
    std::string nonFinite = (dir / "nan.json").string();
    std::ofstream(nonFinite) << document.dump();
    r = run("relight " + bundle + " --lights " + nonFinite + " -o " + out);
    EXPECT_EQ(r.exitCode, 3) << r.stderrText;
    EXPECT_NE(r.stderrText.find("lights[0].radiance"), std::string::npos) << r.stderrText;
    EXPECT_FALSE(fs::exists(out));

    r = run("relight " + bundle + " --lights " + lights + " --sh " + wrongOrder + " -o " + out);
    EXPECT_EQ(r.exitCode, 2) << r.stderrText;
    EXPECT_FALSE(fs::exists(out));

    std::string other = writeMap("other.exr", discMap(64, 1.0, {}));
    r = run("relight " + bundle + " --env " + other + " --lights " + lights + " -o " + out);
    EXPECT_EQ(r.exitCode, 3) << r.stderrText;
    EXPECT_FALSE(fs::exists(out));
}

// --visibility-out: the cone visibility the hybrid used, [V, lights] in [0, 1] (the sun overhead: the spheres' lower
// halves dark, their tops open); relighting the bundle's model with it in the runtime gives the CLI's radiance. It goes with
// --lights only.
TEST_F(EnvlightCli, VisibilityOutIsTheVisibilityTheHybridUsed) {
    std::string scene = (dir / "two.glb").string(), bundle = (dir / "two_t.glb").string();
    ASSERT_EQ(run("scene two-spheres -o " + scene).exitCode, 0);
    ASSERT_EQ(run("transfer " + scene + " -o " + bundle + " --mode interreflected --bounces 1 --samples 64 --order 3 "
                  "--albedo 0.8").exitCode, 0);
    Disc sun{unit(0.0, 1.0, 0.0), 4.0, {200.0, 200.0, 200.0}};
    std::string map = writeMap("sun.exr", discMap(256, 0.5, {sun}));
    std::string lights = (dir / "lights.json").string(), hybrid = (dir / "hybrid.npy").string();
    std::string visibility = (dir / "visibility.npy").string();
    ASSERT_EQ(run("envlight " + map + " -o " + lights + " --order 3").exitCode, 0);
    CliRun r = run("relight " + bundle + " --lights " + lights + " --visibility-out " + visibility + " -o " + hybrid);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    prt::HybridModel model = prt::loadHybridModel(bundle);
    prt::HybridLighting lighting = prt::readHybridLightingJson(lights);
    ASSERT_GE(lighting.lights.size(), 1u);
    std::vector<size_t> shape;
    std::vector<float> visible = prt::readNpy(visibility, &shape);
    ASSERT_EQ(shape, (std::vector<size_t>{model.total.vertexCount, lighting.lights.size()}));
    size_t shadowed = 0, open = 0;
    for (float v : visible) {
        EXPECT_GE(v, 0.0f);
        EXPECT_LE(v, 1.0f);
        shadowed += v < 0.5f;
        open += v == 1.0f;
    }
    EXPECT_GT(shadowed, 0u);
    EXPECT_GT(open, 0u);
    std::vector<float> expected(size_t(model.total.vertexCount) * 3);
    prt::relightHybrid(model, lighting, visible.data(), 0, model.total.vertexCount, expected.data());
    std::vector<float> written = prt::readNpy(hybrid, &shape);
    ASSERT_EQ(written.size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(written[i], expected[i], 1e-5f * (1.0f + expected[i])) << i;

    // --image with --lights: the picture of those rows (the upper sphere's top, lit by the sun, is bright).
    std::string picture = (dir / "hybrid.exr").string();
    r = run("relight " + bundle + " --lights " + lights + " --image 32,24 --camera 1,3,0,1,0,0,0,0,-1,20 -o " + picture);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    prt::Image image = prt::readImage(picture);
    ASSERT_EQ(image.width, 32);
    EXPECT_GT(image.rgb[(12 * 32 + 16) * 3], 0.5f);

    std::string out = (dir / "bad.npy").string();
    EXPECT_EQ(run("relight " + bundle + " --env " + map + " --visibility-out " + out + " -o " + hybrid).exitCode, 2);
    EXPECT_EQ(run("relight " + bundle + " --lights " + lights + " --visibility-out " + (dir / "v.csv").string() +
                  " -o " + hybrid).exitCode, 2);
    EXPECT_FALSE(fs::exists(out));
}

// --visibility-turns N: entry t of the uint8 table [N, rows, lights] is exactly round(255 V) of the visibility
// `--rotate-y t*360/N --visibility-out` casts; bad turn counts and combinations exit 2 with no output.
TEST_F(EnvlightCli, VisibilityTurnsTableEqualsRotateYCasts) {
    std::string scene = (dir / "two.glb").string(), bundle = (dir / "two_t.glb").string();
    ASSERT_EQ(run("scene two-spheres -o " + scene).exitCode, 0);
    ASSERT_EQ(run("transfer " + scene + " -o " + bundle + " --samples 16 --order 3 --albedo 0.8").exitCode, 0);
    Disc sun{unit(0.7, 0.5, 0.0), 6.0, {200.0, 200.0, 200.0}};
    std::string map = writeMap("sun.exr", discMap(128, 0.5, {sun}));
    std::string lights = (dir / "lights.json").string(), out = (dir / "r.npy").string();
    std::string table = (dir / "table.npy").string();
    ASSERT_EQ(run("envlight " + map + " -o " + lights + " --order 3").exitCode, 0);
    const int turns = 8;
    CliRun r = run("relight " + bundle + " --lights " + lights + " --light-samples 16 --visibility-out " + table +
                   " --visibility-turns " + std::to_string(turns) + " -o " + out);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    std::ifstream file(table, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 10u);
    size_t headerLength = (unsigned char)bytes[8] | (unsigned char)bytes[9] << 8;
    std::string header = bytes.substr(10, headerLength);
    EXPECT_NE(header.find("'|u1'"), std::string::npos) << header;
    const uint8_t* data = reinterpret_cast<const uint8_t*>(bytes.data() + 10 + headerLength);
    size_t tableSize = bytes.size() - 10 - headerLength;
    size_t differing = 0;
    for (int t = 0; t < turns; ++t) {
        std::string name = "v"; // appended, not "v" + ...: GCC 12's -Wrestrict misfires on literal + string here
        name += std::to_string(t) + ".npy";
        std::string single = (dir / name).string();
        r = run("relight " + bundle + " --lights " + lights + " --light-samples 16 --rotate-y " +
                std::to_string(t * 360 / turns) + " --visibility-out " + single + " -o " + out);
        ASSERT_EQ(r.exitCode, 0) << r.stderrText;
        std::vector<size_t> shape;
        std::vector<float> visible = prt::readNpy(single, &shape);
        std::string tableShape = "(";
        tableShape += std::to_string(turns) + "," + std::to_string(shape[0]) + "," + std::to_string(shape[1]) + ")";
        ASSERT_EQ(header.find(tableShape) != std::string::npos, true) << header;
        ASSERT_EQ(tableSize, turns * visible.size());
        for (size_t i = 0; i < visible.size(); ++i) {
            uint8_t expected = uint8_t(std::lround(255.0f * std::clamp(visible[i], 0.0f, 1.0f)));
            ASSERT_EQ(data[t * visible.size() + i], expected) << "turn " << t << " entry " << i;
            differing += data[t * visible.size() + i] != data[i];
        }
    }
    EXPECT_GT(differing, 0u); // the shadows move with the turn

    std::string bad = (dir / "bad.npy").string();
    for (const std::string flags : {" --visibility-turns 0", " --visibility-turns 721", " --visibility-turns 4 --rotate-y 10"}) {
        r = run("relight " + bundle + " --lights " + lights + " --visibility-out " + bad + flags + " -o " + out + ".x.npy");
        EXPECT_EQ(r.exitCode, 2) << flags;
        EXPECT_NE(r.stderrText.find("--visibility-turns"), std::string::npos) << r.stderrText;
    }
    r = run("relight " + bundle + " --lights " + lights + " --visibility-turns 4 -o " + bad);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.stderrText.find("--visibility-out"), std::string::npos) << r.stderrText;
    EXPECT_FALSE(fs::exists(bad));
}

// The pipeline stage: envlight's lights feed relight; a second run is served from the cache with the same bytes.
TEST_F(EnvlightCli, PipelineStageFeedsRelight) {
    ASSERT_EQ(run("scene two-spheres -o " + (dir / "two.glb").string()).exitCode, 0);
    writeMap("sun.exr", discMap(128, 0.5, {Disc{unit(0.3, 0.8, -0.5), 6.0, {100.0, 100.0, 100.0}}}));
    std::ofstream(dir / "hybrid.toml") << R"([pipeline]
name = "hybrid"
[inputs]
scene = { mesh = "two.glb" }
sun = { env = "sun.exr" }
[stages.transfer]
run = "transfer"
inputs = { mesh = "scene" }
mode = "interreflected"
order = 3
samples = 64
bounces = 1
albedo = [0.8, 0.8, 0.8]
[stages.lights]
run = "envlight"
inputs = { env = "sun" }
order = 3
max-lights = 2
icosphere-level = 5
[stages.relight]
run = "relight"
inputs = { bundle = "transfer", lights = "lights" }
light-samples = 16
[outputs]
radiance = { from = "relight", path = "out/radiance.npy" }
lights = { from = "lights", path = "out/lights.json" }
)";
    std::string cd = "cd " + dir.string() + " && ";
    auto runIn = [&](const std::string& arguments) {
        int status = std::system((cd + PRT_EXECUTABLE + " " + arguments + " 2> " + (dir / "run.txt").string()).c_str());
        std::stringstream text;
        text << std::ifstream(dir / "run.txt").rdbuf();
        return CliRun{WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
    };
    CliRun first = runIn("run hybrid.toml");
    ASSERT_EQ(first.exitCode, 0) << first.stderrText;
    nlohmann::json lights = nlohmann::json::parse(std::ifstream(dir / "out" / "lights.json"));
    EXPECT_EQ(lights["lights"].size(), 1u);
    std::string radiance = prt::hashFile((dir / "out" / "radiance.npy").string());
    CliRun second = runIn("run hybrid.toml --plan");
    EXPECT_EQ(second.exitCode, 0) << second.stderrText;
    CliRun third = runIn("run hybrid.toml");
    ASSERT_EQ(third.exitCode, 0) << third.stderrText;
    EXPECT_EQ(prt::hashFile((dir / "out" / "radiance.npy").string()), radiance);
}

TEST_F(EnvlightCli, ChooseLightsWritesTheChosenResidualOrder) {
    // A unit background and a 1.5-degree disc holding about half the power: lights pay, and at the order-8
    // residual (the default tries --order and --plain-order).
    std::string map = writeMap("sun.exr", discMap(256, 1.0, {{unit(0.3, 0.7, -0.5), 1.5, {5800.0, 5800.0, 5800.0}}}));
    std::string out = (dir / "lights.json").string();
    CliRun r = run("envlight " + map + " -o " + out + " --order 5 --max-lights 16 --icosphere-level 5 --choose-lights");
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    nlohmann::json doc = nlohmann::json::parse(std::ifstream(out));
    EXPECT_EQ(doc["order"], 8);
    EXPECT_EQ(doc["residual"].size(), 64u);
    EXPECT_EQ(doc["choice"]["residual_order"], 8);
    EXPECT_EQ(doc["choice"]["orders_tried"], nlohmann::json::array({5, 8}));
    EXPECT_FALSE(doc["choice"]["plain_sh"].get<bool>());
    EXPECT_EQ(doc["lights"].size(), doc["choice"]["lights"].get<size_t>());
    // Told to keep order 5.
    r = run("envlight " + map + " -o " + out + " --order 5 --max-lights 16 --icosphere-level 5 --choose-lights "
            "--residual-orders 5");
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    doc = nlohmann::json::parse(std::ifstream(out));
    EXPECT_EQ(doc["order"], 5);
    EXPECT_EQ(doc["residual"].size(), 25u);
    // Orders outside 1..31, or without --choose-lights: usage errors, no output.
    fs::remove(out);
    r = run("envlight " + map + " -o " + out + " --choose-lights --residual-orders 5,40");
    EXPECT_EQ(r.exitCode, 2) << r.stderrText;
    EXPECT_NE(r.stderrText.find("--residual-orders"), std::string::npos) << r.stderrText;
    r = run("envlight " + map + " -o " + out + " --residual-orders 8");
    EXPECT_EQ(r.exitCode, 2) << r.stderrText;
    EXPECT_FALSE(fs::exists(out));
}
