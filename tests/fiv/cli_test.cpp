// `prt fiv`, `prt fiv-visibility`, `prt fivshade` and `prt reference --occluder` through the binary: the split and
// shards give the same bytes, the shading matches the brute-force reference, bad inputs fail cleanly.
#include "bundle.h"
#include "compare.h"
#include "core.h"
#include "image.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

using namespace prt;

namespace {

const std::string kPrt = PRT_EXECUTABLE;

struct TempDir {
    std::string path;
    TempDir() {
        std::string pattern = (std::filesystem::temp_directory_path() / "prt-fiv-XXXXXX").string();
        path = mkdtemp(pattern.data());
    }
    ~TempDir() { std::filesystem::remove_all(path); }
    std::string operator/(const std::string& name) const { return path + "/" + name; }
};

int run(const std::string& args, std::string* output = nullptr) {
    std::FILE* pipe = popen((kPrt + " --quiet " + args + " 2>&1").c_str(), "r");
    std::string text;
    char buffer[4096];
    size_t got;
    while ((got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) text.append(buffer, got);
    int status = pclose(pipe);
    if (output) *output = text;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

// A sphere occluder, a plane receiver and a sky brighter above than below, written once.
struct Files {
    TempDir dir;
    Files() {
        TriMesh sphere = makeSphere(0.5f, 12, 24);
        Bundle b;
        b.mesh = sphere;
        writeBundle(dir / "sphere.glb", b);
        b.mesh = makePlane(4.0f, 8);
        writeBundle(dir / "plane.glb", b);
        b.mesh.normals.clear();
        writeBundle(dir / "no-normals.glb", b);
        b.mesh = makePlane(1.0f, 2);
        b.mesh.normals.clear();
        writeBundle(dir / "open.glb", b);
        Image env;
        env.width = 32, env.height = 16;
        env.rgb.assign(32 * 16 * 3, 1.0f);
        for (int i = 0; i < 32 * 8 * 3; ++i) env.rgb[size_t(i)] = 3.0f;
        env.rgb[3 * (3 * 32 + 20)] = 400.0f; // a small bright "sun"
        writeImage(dir / "env.exr", env);
        EXPECT_EQ(run("fiv " + dir / "sphere.glb --env " + dir / "env.exr --grid 16,9,6 --cube 8 -o " +
                      dir / "sphere.fiv.glb"), 0);
    }
    std::string operator/(const std::string& name) const { return dir / name; }
};

const Files& files() {
    static Files f;
    return f;
}

} // namespace

TEST(FivCli, SplitAndShardsGiveTheSameBundleBytes) {
    const Files& f = files();
    TempDir out;
    std::string common = " --grid 16,9,6 --cube 8";
    ASSERT_EQ(run("fiv-visibility " + f / "sphere.glb" + common + " -o " + out / "vis.glb"), 0);
    ASSERT_EQ(run("fiv " + out / "vis.glb --env " + f / "env.exr -o " + out / "split.fiv.glb"), 0);
    for (int s = 0; s < 3; ++s)
        ASSERT_EQ(run("fiv-visibility " + f / "sphere.glb" + common + " --threads 1 --shard " + std::to_string(s) +
                      "/3 -o " + out / ("shard" + std::to_string(s) + ".glb")), 0);
    ASSERT_EQ(run("fiv " + out / "shard2.glb " + out / "shard0.glb " + out / "shard1.glb --env " + f / "env.exr -o " +
                  out / "sharded.fiv.glb"), 0);
    ASSERT_EQ(run("fiv-visibility " + f / "sphere.glb" + common + " --merge " + out / "shard0.glb " +
                  out / "shard1.glb " + out / "shard2.glb -o " + out / "merged.glb"), 0);
    std::string whole = readFileBytes(f / "sphere.fiv.glb");
    EXPECT_EQ(readFileBytes(out / "split.fiv.glb"), whole);
    EXPECT_EQ(readFileBytes(out / "sharded.fiv.glb"), whole);
    EXPECT_EQ(readFileBytes(out / "merged.glb"), readFileBytes(out / "vis.glb"));
    // A missing shard is refused.
    EXPECT_EQ(run("fiv " + out / "shard0.glb " + out / "shard1.glb --env " + f / "env.exr -o " + out / "x.glb"), 3);
    EXPECT_FALSE(std::filesystem::exists(out / "x.glb"));
    // Every layer reads back as written, float16 rounded.
    Bundle bundle = readBundle(f / "sphere.fiv.glb");
    const Layer* fiv = findLayer(bundle, "fiv");
    ASSERT_NE(fiv, nullptr);
    EXPECT_EQ(fiv->componentType, "float16");
    EXPECT_EQ(fiv->shape, (std::vector<uint64_t>{16 * 9 * 6, 3, 3}));
    EXPECT_EQ(fiv->params["env"], hashFile(f / "env.exr"));
}

TEST(FivCli, ShadingMatchesTheBruteForceReference) {
    const Files& f = files();
    TempDir out;
    ASSERT_EQ(run("fivshade " + f / "plane.glb --env " + f / "env.exr --occluder " + f / "sphere.fiv.glb --at 0.3,1,0 " +
                  "--occluder " + f / "sphere.fiv.glb --at -0.4,1.2,0.2 --albedo 0.8 -o " + out / "fiv.npy"), 0);
    ASSERT_EQ(run("reference " + f / "plane.glb --env " + f / "env.exr --occluder " + f / "sphere.glb --at 0.3,1,0 " +
                  "--occluder " + f / "sphere.glb --at -0.4,1.2,0.2 --albedo 0.8 --bounces 0 -o " + out / "ref.npy"), 0);
    ASSERT_EQ(run("reference " + f / "plane.glb --env " + f / "env.exr --unshadowed --albedo 0.8 --bounces 0 -o " +
                  out / "free.npy"), 0);
    std::vector<float> shaded = readVertexRadiance(out / "fiv.npy"), reference = readVertexRadiance(out / "ref.npy");
    std::vector<float> free = readVertexRadiance(out / "free.npy");
    ASSERT_EQ(shaded.size(), reference.size());
    double error = 0.0, lo = 1e30, hi = -1e30;
    for (size_t v = 0; v < shaded.size() / 3; ++v) {
        double s = free[3 * v + 1] - shaded[3 * v + 1], r = free[3 * v + 1] - reference[3 * v + 1];
        error += (s - r) * (s - r);
        lo = std::min(lo, r), hi = std::max(hi, r);
    }
    double nrmse = std::sqrt(error / double(shaded.size() / 3)) / (hi - lo);
    EXPECT_GT(hi - lo, 0.1); // there is a shadow to get right
    EXPECT_LT(nrmse, 0.08);  // a coarse 16x9x6 grid on an 8^2 cube
}

// A scene bundle (prt fivscene) holds the receiver, two occluder types and three instances; fivshade of it equals
// fivshade of the separate files byte for byte, and so does self-shadowing. The Khronos validator accepts it.
TEST(FivCli, SceneBundleShadesLikeSeparateFiles) {
    const Files& f = files();
    TempDir out;
    Bundle small;
    small.mesh = makeSphere(0.3f, 10, 20);
    writeBundle(out / "small.glb", small);
    ASSERT_EQ(run("fiv " + out / "small.glb --env " + f / "env.exr --grid 16,9,6 --cube 8 -o " + out / "small.fiv.glb"), 0);
    std::string placed = " --occluder " + f / "sphere.fiv.glb --at 0.3,1,0 --occluder " + out / "small.fiv.glb" +
                         " --at -0.5,0.8,0.2 --occluder " + f / "sphere.fiv.glb --at -0.2,1.4,-0.6";
    ASSERT_EQ(run("fivscene " + f / "plane.glb" + placed + " -o " + out / "scene.glb"), 0);
    ASSERT_EQ(run("fivshade " + f / "plane.glb --env " + f / "env.exr" + placed + " --albedo 0.8 -o " + out / "files.npy"), 0);
    ASSERT_EQ(run("fivshade " + out / "scene.glb --env " + f / "env.exr --albedo 0.8 -o " + out / "scene.npy"), 0);
    EXPECT_EQ(readFileBytes(out / "scene.npy"), readFileBytes(out / "files.npy"));

    Bundle scene = readBundle(out / "scene.glb");
    ASSERT_EQ(scene.objects.size(), 2u); // two types, one object each
    EXPECT_EQ(scene.objects[0].role, "occluder");
    EXPECT_EQ(scene.instances.size(), 4u); // the receiver and three occluders
    EXPECT_EQ(scene.instances[3].object, 1u);
    EXPECT_FLOAT_EQ(scene.instances[3].translation[2], -0.6f);
    EXPECT_NE(findObjectLayer(scene, "fiv", 2), nullptr);
    EXPECT_EQ(findObjectLayer(scene, "fiv", 2)->name, "fiv.2");

    ASSERT_EQ(run("fivscene " + f / "sphere.glb --self " + f / "sphere.fiv.glb -o " + out / "self.glb"), 0);
    ASSERT_EQ(run("fivshade " + f / "sphere.glb --env " + f / "env.exr --self " + f / "sphere.fiv.glb -o " + out / "a.npy"), 0);
    ASSERT_EQ(run("fivshade " + out / "self.glb --env " + f / "env.exr -o " + out / "b.npy"), 0);
    EXPECT_EQ(readFileBytes(out / "a.npy"), readFileBytes(out / "b.npy"));

    std::string message;
    EXPECT_EQ(run("fivshade " + out / "scene.glb --env " + f / "env.exr --occluder " + f / "sphere.fiv.glb --at 0,1,0 -o " +
                  out / "c.npy", &message), 2);
    EXPECT_NE(message.find("places its own occluders"), std::string::npos) << message;
    EXPECT_EQ(run("fivscene " + f / "plane.glb --self " + f / "sphere.fiv.glb -o " + out / "d.glb", &message), 3);
    EXPECT_NE(message.find("not the receiver's mesh"), std::string::npos) << message;
    Image other;
    other.width = 32, other.height = 16;
    other.rgb.assign(32 * 16 * 3, 0.5f);
    writeImage(out / "other.exr", other);
    ASSERT_EQ(run("fiv " + out / "small.glb --env " + out / "other.exr --grid 16,9,6 --cube 8 -o " + out / "other.fiv.glb"), 0);
    EXPECT_EQ(run("fivscene " + f / "plane.glb --occluder " + f / "sphere.fiv.glb --at 0,1,0 --occluder " +
                  out / "other.fiv.glb --at 1,1,0 -o " + out / "e.glb", &message), 3);
    EXPECT_NE(message.find("another environment"), std::string::npos) << message;
    EXPECT_EQ(run("fivshade " + out / "scene.glb --env " + out / "other.exr -o " + out / "f.npy", &message), 3);
    EXPECT_NE(message.find("another environment"), std::string::npos) << message;
    for (const char* name : {"c.npy", "d.glb", "e.glb", "f.npy"}) EXPECT_FALSE(std::filesystem::exists(out / name)) << name;

    std::string validator = PRT_SOURCE_DIR "/tests/bundle/gltf_validator";
    if (!std::filesystem::exists(validator + "/node_modules/gltf-validator"))
        GTEST_SKIP() << "npm ci --prefix tests/bundle/gltf_validator (scripts/bootstrap.sh) installs the validator";
    std::string output;
    std::FILE* pipe = popen(("node " + validator + "/validate.mjs " + out / "scene.glb " + out / "self.glb 2>&1").c_str(), "r");
    char buffer[4096];
    size_t got;
    while ((got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, got);
    EXPECT_EQ(WEXITSTATUS(pclose(pipe)), 0) << output;
    EXPECT_NE(output.find("\"errors\":0"), std::string::npos) << output;
}

TEST(FivCli, BadInputsFailCleanlyWithoutOutput) {
    const Files& f = files();
    TempDir out;
    std::string o = out / "out.glb", npy = out / "out.npy", message;
    struct Case {
        std::string args;
        int code;
        std::string says;
    };
    for (const Case& c : std::vector<Case>{
             {"fiv " + f / "open.glb --env " + f / "env.exr --grid 8,5,3 -o " + o, 3, "not closed"},
             {"fiv " + f / "sphere.glb --env " + f / "env.exr --grid 0,17,15 -o " + o, 2, "azimuth"},
             {"fiv " + f / "sphere.glb --env " + f / "env.exr --grid 4096,2049,1000 -o " + o, 2, "samples"},
             {"fiv " + f / "sphere.glb --grid 8,5,3 -o " + o, 2, "--env"},
             {"fivshade " + f / "no-normals.glb --env " + f / "env.exr --occluder " + f / "sphere.fiv.glb --at 0,1,0 -o " + npy, 3, "normals"},
             {"fivshade " + f / "plane.glb --env " + f / "env.exr --occluder " + f / "sphere.fiv.glb --at 0,1 -o " + npy, 2, "three finite"},
             {"fivshade " + f / "plane.glb --env " + f / "env.exr --occluder " + f / "sphere.fiv.glb --at 0,nan,1 -o " + npy, 2, "three finite"},
             {"fivshade " + f / "plane.glb --env " + f / "env.exr --occluder " + f / "sphere.fiv.glb --at 0,1,2,3 -o " + npy, 2, "three finite"},
             {"fivshade " + f / "plane.glb --env " + f / "plane.glb --occluder " + f / "sphere.fiv.glb --at 0,1,0 -o " + npy, 3, "another environment"},
             {"reference " + f / "plane.glb --env " + f / "env.exr --occluder " + f / "sphere.glb --at 0,1,0 --bounces 1 -o " + npy, 2, "--bounces 0"},
         }) {
        EXPECT_EQ(run(c.args, &message), c.code) << c.args << "\n" << message;
        EXPECT_NE(message.find(c.says), std::string::npos) << message;
        EXPECT_FALSE(std::filesystem::exists(o) || std::filesystem::exists(npy)) << c.args;
    }
    // A bundle whose grid disagrees with its header.
    Bundle bundle = readBundle(f / "sphere.fiv.glb");
    for (Layer& layer : bundle.layers)
        if (layer.name == "fiv") layer.params["polar"] = 10;
    writeBundle(out / "bad.fiv.glb", bundle);
    EXPECT_EQ(run("fivshade " + f / "plane.glb --env " + f / "env.exr --occluder " + out / "bad.fiv.glb --at 0,1,0 -o " + npy, &message), 3);
    EXPECT_NE(message.find("disagrees with the grid header"), std::string::npos) << message;
    EXPECT_FALSE(std::filesystem::exists(npy));
}

TEST(FivCli, KhronosValidatorReportsNoErrors) {
    const Files& f = files();
    std::string validator = PRT_SOURCE_DIR "/tests/bundle/gltf_validator";
    if (!std::filesystem::exists(validator + "/node_modules/gltf-validator"))
        GTEST_SKIP() << "npm ci --prefix tests/bundle/gltf_validator (scripts/bootstrap.sh) installs the validator";
    TempDir out;
    ASSERT_EQ(run("fiv-visibility " + f / "sphere.glb --grid 16,9,6 --cube 8 -o " + out / "vis.glb"), 0);
    std::string output;
    std::string command = "node " + validator + "/validate.mjs " + f / "sphere.fiv.glb " + out / "vis.glb 2>&1";
    std::FILE* pipe = popen(command.c_str(), "r");
    char buffer[4096];
    size_t got;
    while ((got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, got);
    int status = pclose(pipe);
    EXPECT_EQ(WEXITSTATUS(status), 0) << output;
    EXPECT_NE(output.find("\"errors\":0"), std::string::npos) << output;
}

TEST(FivCli, PipelineRerunsOnlyTheReductionWhenTheEnvironmentChanges) {
    const Files& f = files();
    TempDir out;
    Image other;
    other.width = 32, other.height = 16;
    other.rgb.assign(32 * 16 * 3, 0.5f);
    writeImage(out / "other.exr", other);
    auto pipeline = [&](const std::string& env) {
        std::string text = "[pipeline]\nname = \"fiv\"\n[inputs]\nsphere = { mesh = \"" + f / "sphere.glb" +
                           "\" }\nsky = { env = \"" + env + "\" }\n[stages.masks]\nrun = \"fiv-visibility\"\n"
                           "inputs = { mesh = \"sphere\" }\ngrid = \"16,9,6\"\ncube = 8\nshards = 2\n"
                           "[stages.grid]\nrun = \"fiv\"\ninputs = { visibility = \"masks\", env = \"sky\" }\n"
                           "[outputs]\nfiv = { from = \"grid\", path = \"" + out / "sphere.fiv.glb" + "\" }\n";
        writeBytesAtomic(out / "fiv.toml", text);
    };
    pipeline(f / "env.exr");
    std::string text;
    ASSERT_EQ(std::system(("cd " + out.path + " && " + kPrt + " --quiet run fiv.toml >/dev/null 2>&1").c_str()), 0);
    EXPECT_EQ(readFileBytes(out / "sphere.fiv.glb"), readFileBytes(f / "sphere.fiv.glb")); // 2 shards = 1 run
    pipeline(out / "other.exr");
    std::FILE* pipe = popen(("cd " + out.path + " && " + kPrt + " run fiv.toml --plan 2>&1").c_str(), "r");
    char buffer[4096];
    size_t got;
    while ((got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) text.append(buffer, got);
    pclose(pipe);
    EXPECT_NE(text.find("masks fiv-visibility cached"), std::string::npos) << text;
    EXPECT_NE(text.find("fiv        run"), std::string::npos) << text;
}
