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
#include <functional>
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

// Writes DIR/flat.exr, a uniform 32x16 map of radiance 1, and DIR/sunny.exr, the same with one texel of 4000: a
// sun holding most of the map's power, which `prt fiv --sources` extracts as one small source.
void writeFlatAndSunnyMaps(const TempDir& dir) {
    Image flat;
    flat.width = 32, flat.height = 16;
    flat.rgb.assign(32 * 16 * 3, 1.0f);
    writeImage(dir / "flat.exr", flat);
    Image sunny = flat;
    for (int c = 0; c < 3; ++c) sunny.rgb[3 * (5 * 32 + 20) + size_t(c)] = 4000.0f;
    writeImage(dir / "sunny.exr", sunny);
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

// The classes the crafted-input battery found (issue 20, "Hardening, round 2"), one case each: a layer typed as the
// other storage, wrong JSON types, values whose float overflows, a visibility row short of bits, a grid whose work
// sits at the sample cap, and coordinates whose squares overflow. fivshade and fivscene refuse the same files.
TEST(FivCli, HardenedReadersRefuseEveryCrashClassWithoutOutput) {
    const Files& f = files();
    TempDir out;
    std::string npy = out / "out.npy", glb = out / "out.glb", message;
    auto edited = [&](const std::string& name, const std::function<void(Bundle&)>& edit) {
        Bundle bundle = readBundle(f / "sphere.fiv.glb");
        edit(bundle);
        writeBundle(out / name, bundle);
        return out / name;
    };
    auto layer = [](Bundle& bundle, const char* name) -> Layer& {
        for (Layer& l : bundle.layers)
            if (l.name == name) return l;
        throw std::runtime_error(name);
    };
    struct Case {
        std::string file, says;
    };
    std::vector<Case> cases = {
        {edited("valid-float.glb",
                [&](Bundle& b) {
                    Layer& valid = layer(b, "fiv_valid");
                    valid.componentType = "float32";
                    valid.data.assign(valid.integers.begin(), valid.integers.end());
                    valid.integers.clear();
                }),
         "component type is float32, not uint8"},
        {edited("fiv-uint.glb",
                [&](Bundle& b) {
                    Layer& fiv = layer(b, "fiv");
                    fiv.componentType = "uint32";
                    fiv.integers.assign(fiv.data.size(), 0u);
                    fiv.data.clear();
                }),
         "component type is uint32"},
        {edited("centre-string.glb", [&](Bundle& b) { layer(b, "fiv").params["centre"][1] = "up"; }),
         "centre[1]"},
        {edited("radii-object.glb", [&](Bundle& b) { layer(b, "fiv").params["shell_radii"][2] = false; }),
         "shell_radii[2]"},
        {edited("radius-bool.glb", [&](Bundle& b) { layer(b, "fiv").params["radius"] = true; }), "not a number"},
        {edited("centre-huge.glb", [&](Bundle& b) { layer(b, "fiv").params["centre"][0] = 1e39; }), "centre[0]"},
        {edited("radius-huge.glb", [&](Bundle& b) { layer(b, "fiv").params["radius"] = 1e300; }), "radius"},
        {edited("radii-huge.glb", [&](Bundle& b) { layer(b, "fiv").params["shell_radii"][5] = 1e38; }), "shell_radii[5]"},
        {edited("radii-descending.glb", [&](Bundle& b) { layer(b, "fiv").params["shell_radii"][5] = 0.1; }), "ascending"},
        {edited("azimuth-wraps.glb", [&](Bundle& b) { layer(b, "fiv").params["azimuth"] = 4294967312ull; }), "azimuth"},
    };
    for (const Case& c : cases) {
        // fivshade and fivscene run the one validator (runtime.h fivLayer, fivOccluder, fivLighting).
        EXPECT_EQ(run("fivshade " + f / "plane.glb --env " + f / "env.exr --occluder " + c.file + " --at 0,1,0 -o " + npy,
                      &message), 3) << c.file << "\n" << message;
        EXPECT_NE(message.find(c.says), std::string::npos) << message;
        EXPECT_NE(message.find(c.file), std::string::npos) << message;
        EXPECT_EQ(run("fivscene " + f / "plane.glb --occluder " + c.file + " --at 0,1,0 -o " + glb, &message), 3)
            << c.file << "\n" << message;
        EXPECT_NE(message.find(c.says), std::string::npos) << message;
        EXPECT_FALSE(std::filesystem::exists(npy) || std::filesystem::exists(glb)) << c.file;
    }

    // The sources' own grid (decision 13) goes through the same validator in both commands.
    Image sunny;
    sunny.width = 32, sunny.height = 16;
    sunny.rgb.assign(32 * 16 * 3, 1.0f);
    for (int c = 0; c < 3; ++c) sunny.rgb[3 * (5 * 32 + 20) + size_t(c)] = 4000.0f;
    writeImage(out / "sunny.exr", sunny);
    ASSERT_EQ(run("fiv " + f / "sphere.glb --env " + out / "sunny.exr --grid 16,9,6 --cube 8 --sources --source-grid 16,9,6 -o " +
                  out / "sg.glb"), 0);
    auto sourceEdited = [&](const std::string& name, const std::function<void(Bundle&)>& edit) {
        Bundle bundle = readBundle(out / "sg.glb");
        edit(bundle);
        writeBundle(out / name, bundle);
        return out / name;
    };
    const std::vector<Case> sourceCases = {
        {sourceEdited("sg-above-one.glb", [&](Bundle& b) { layer(b, "fiv_source_grid").data[7] = 1.5f; }), "outside 0..1"},
        {sourceEdited("sg-uint8.glb",
                      [&](Bundle& b) {
                          Layer& l = layer(b, "fiv_source_grid");
                          l.componentType = "uint8", l.integers.assign(l.data.size(), 0u), l.data.clear();
                      }),
         "component type is uint8"},
        {sourceEdited("sg-radius.glb", [&](Bundle& b) { layer(b, "fiv_source_grid").params["radius"] = 0.25; }),
         "differs from the main grid"},
        {sourceEdited("sg-no-valid.glb",
                      [&](Bundle& b) { std::erase_if(b.layers, [](const Layer& l) { return l.name == "fiv_source_valid"; }); }),
         "come together"},
    };
    for (const Case& c : sourceCases) {
        EXPECT_EQ(run("fivshade " + f / "plane.glb --env " + out / "sunny.exr --occluder " + c.file + " --at 0,1,0 -o " + npy,
                      &message), 3) << c.file << "\n" << message;
        EXPECT_NE(message.find(c.says), std::string::npos) << message;
        EXPECT_EQ(run("fivscene " + f / "plane.glb --occluder " + c.file + " --at 0,1,0 -o " + glb, &message), 3)
            << c.file << "\n" << message;
        EXPECT_NE(message.find(c.says), std::string::npos) << message;
        EXPECT_FALSE(std::filesystem::exists(npy) || std::filesystem::exists(glb)) << c.file;
    }

    // Visibility bundles: a mask layer typed as floats, a centre of the wrong type, a row short of bits (the
    // reduction's error names the file).
    ASSERT_EQ(run("fiv-visibility " + f / "sphere.glb --grid 16,9,6 --cube 8 -o " + out / "vis.glb"), 0);
    auto visibility = [&](const std::string& name, const std::function<void(Bundle&)>& edit) {
        Bundle bundle = readBundle(out / "vis.glb");
        edit(bundle);
        writeBundle(out / name, bundle);
        return out / name;
    };
    std::vector<Case> masks = {
        {visibility("bits-float.glb",
                    [&](Bundle& b) {
                        Layer& bits = layer(b, "fiv_mask_bits");
                        bits.componentType = "float32";
                        bits.data.assign(bits.integers.begin(), bits.integers.end());
                        bits.integers.clear();
                    }),
         "component type is float32, not uint8"},
        {visibility("vis-centre.glb", [&](Bundle& b) { layer(b, "fiv_mask_offsets").params["centre"][0] = "x"; }),
         "centre"},
        {visibility("vis-short.glb",
                    [&](Bundle& b) {
                        // A valid row's bytes given to the next row: offsets still run 0..size in order.
                        Layer& offsets = layer(b, "fiv_mask_offsets");
                        const Layer& valid = layer(b, "fiv_mask_valid");
                        size_t r = 0;
                        while (r + 1 < offsets.integers.size() &&
                               !(valid.integers[r] && offsets.integers[r + 1] > offsets.integers[r]))
                            ++r;
                        ASSERT_LT(r + 2, offsets.integers.size());
                        offsets.integers[r + 1] = offsets.integers[r];
                    }),
         "fewer than its"},
    };
    for (const Case& c : masks) {
        EXPECT_EQ(run("fiv " + c.file + " --env " + f / "env.exr -o " + glb, &message), 3) << c.file << "\n" << message;
        EXPECT_NE(message.find(c.says), std::string::npos) << message;
        EXPECT_NE(message.find(c.file), std::string::npos) << message;
        EXPECT_FALSE(std::filesystem::exists(glb)) << c.file;
    }

    // Command-line values (exit 2, as every bad flag): a grid at the sample cap whose rays and masks the work cap
    // refuses before anything is read, and a placement whose squared distance overflows a float.
    EXPECT_EQ(run("fiv " + f / "sphere.glb --env " + f / "env.exr --grid 4096,2048,8 -o " + glb, &message), 2) << message;
    EXPECT_NE(message.find("ray-texel pairs"), std::string::npos) << message;
    EXPECT_EQ(run("fivshade " + f / "plane.glb --env " + f / "env.exr --occluder " + f / "sphere.fiv.glb --at 1e30,0,0 -o " +
                  npy, &message), 2) << message;
    EXPECT_NE(message.find("lies beyond"), std::string::npos) << message;
    EXPECT_EQ(run("fivscene " + f / "plane.glb --occluder " + f / "sphere.fiv.glb --at 0,-1e30,0 -o " + glb, &message), 2);
    EXPECT_FALSE(std::filesystem::exists(npy) || std::filesystem::exists(glb));
}

// `prt fiv --sources`: a map with a one-texel sun holding most of its power gets rays toward the sun of its own (the
// bundle records them and its grid differs); a map without a small source comes out byte for byte as without it.
TEST(FivCli, SourcesShadowASunByItsOwnRaysAndLeaveAMapWithoutOneAlone) {
    const Files& f = files();
    TempDir dir;
    writeFlatAndSunnyMaps(dir);
    const std::string common = f / "sphere.glb --grid 16,9,6 --cube 8 --threads 1 ";
    for (const char* map : {"flat", "sunny"}) {
        ASSERT_EQ(run("fiv " + common + "--env " + dir / (std::string(map) + ".exr") + " -o " + dir / (std::string(map) + ".glb")), 0);
        ASSERT_EQ(run("fiv " + common + "--sources --env " + dir / (std::string(map) + ".exr") + " -o " +
                      dir / (std::string(map) + ".sources.glb")), 0);
    }
    EXPECT_EQ(readFileBytes(dir / "flat.glb"), readFileBytes(dir / "flat.sources.glb"));
    Bundle plain = readBundle(dir / "sunny.glb"), sources = readBundle(dir / "sunny.sources.glb");
    const Layer* a = findLayer(plain, "fiv");
    const Layer* b = findLayer(sources, "fiv");
    ASSERT_TRUE(a && b);
    EXPECT_FALSE(a->params.contains("source_rays"));
    ASSERT_TRUE(b->params.contains("source_rays"));
    EXPECT_GT(b->params["source_rays"].get<uint64_t>(), 0u);
    EXPECT_NE(a->data, b->data);
}

TEST(FivCli, SelfVerticesStoreTheMeshsOwnShadowingAndFivshadeUsesItOnThatMeshOnly) {
    const Files& f = files();
    TempDir dir;
    const std::string common = f / "sphere.glb --env " + f / "env.exr --grid 16,9,6 --cube 8 --threads 1 ";
    ASSERT_EQ(run("fiv " + common + "--self-vertices -o " + dir / "self.fiv.glb"), 0);
    Bundle plain = readBundle(f / "sphere.fiv.glb"), self = readBundle(dir / "self.fiv.glb");
    EXPECT_EQ(findLayer(plain, "fiv_self"), nullptr); // off by default: the bundle as before
    const Layer* layer = findLayer(self, "fiv_self");
    ASSERT_NE(layer, nullptr);
    EXPECT_EQ(layer->shape, (std::vector<uint64_t>{self.mesh.vertexCount(), 3}));
    EXPECT_EQ(findLayer(self, "fiv")->data, findLayer(plain, "fiv")->data); // the grid itself is unchanged
    // A convex sphere hides nothing above a vertex's tangent plane: E_self is the unshadowed irradiance, so the
    // shading is the DifMap's (grid: N . FIV(Env) - N . FIV_self, which differs).
    ASSERT_EQ(run("fivshade " + f / "sphere.glb --env " + f / "env.exr --self " + dir / "self.fiv.glb -o " + dir / "a.npy"), 0);
    ASSERT_EQ(run("fivshade " + f / "sphere.glb --env " + f / "env.exr --self " + f / "sphere.fiv.glb -o " + dir / "b.npy"), 0);
    std::vector<size_t> shape;
    std::vector<float> a = readNpy(dir / "a.npy", &shape), b = readNpy(dir / "b.npy", &shape);
    ASSERT_EQ(a.size(), 3 * self.mesh.vertexCount());
    EXPECT_NE(a, b);
    // Radiance albedo / pi E_self (albedo 1), E_self clamped to DifMap(N) only.
    size_t equal = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        double e = layer->data[i] / 3.14159265358979;
        EXPECT_LE(a[i], e * (1 + 1e-6) + 1e-7) << i;
        equal += std::abs(a[i] - e) <= 1e-6 * e + 1e-7;
    }
    EXPECT_GT(equal, a.size() / 4); // the rest clamped to the bilinear DifMap, below the exact cube sum
    // Another receiver: the layer does not apply, the grid does (same bytes as without the layer).
    ASSERT_EQ(run("fivshade " + f / "plane.glb --env " + f / "env.exr --self " + dir / "self.fiv.glb -o " + dir / "c.npy"), 0);
    ASSERT_EQ(run("fivshade " + f / "plane.glb --env " + f / "env.exr --self " + f / "sphere.fiv.glb -o " + dir / "d.npy"), 0);
    EXPECT_EQ(readFileBytes(dir / "c.npy"), readFileBytes(dir / "d.npy"));
}

// `prt fiv --sources --source-grid`: under a map with a sun the bundle carries the sources' own grid (its grid the
// rest of the map), `prt fivshade` reads it and says so, `prt fivscene` carries it (and fiv_self) and shades the
// same bytes; a map without a small source gives the bundle without the option, byte for byte; bad values are
// usage errors that write nothing.
TEST(FivCli, SourceGridIsWrittenAsLayersReadByFivshadeAndCarriedByFivscene) {
    const Files& f = files();
    TempDir dir;
    writeFlatAndSunnyMaps(dir);
    const std::string common = f / "sphere.glb --grid 16,9,6 --cube 8 --threads 1 --sources ";
    ASSERT_EQ(run("fiv " + common + "--env " + dir / "flat.exr -o " + dir / "flat.glb"), 0);
    std::string log;
    ASSERT_EQ(run("fiv " + common + "--source-grid 32,17,12 --env " + dir / "flat.exr -o " + dir / "flat.grid.glb", &log), 0);
    EXPECT_EQ(readFileBytes(dir / "flat.glb"), readFileBytes(dir / "flat.grid.glb"));
    ASSERT_EQ(run("fiv " + common + "--env " + dir / "sunny.exr -o " + dir / "sunny.glb"), 0);
    ASSERT_EQ(run("fiv " + common + "--source-grid auto --source-sharpen 3 --self-vertices --env " + dir / "sunny.exr -o " +
                  dir / "sunny.grid.glb"), 0); // auto: 2 NT, 2 NP - 1, 2 NR = 32, 17, 12
    Bundle sources = readBundle(dir / "sunny.glb"), grid = readBundle(dir / "sunny.grid.glb");
    const Layer* fraction = findLayer(grid, "fiv_source_grid");
    const Layer* valid = findLayer(grid, "fiv_source_valid");
    ASSERT_TRUE(fraction && valid);
    EXPECT_EQ(findLayer(sources, "fiv_source_grid"), nullptr);
    EXPECT_EQ(fraction->componentType, "float16");
    EXPECT_EQ(fraction->shape, (std::vector<uint64_t>{32 * 17 * 12}));
    EXPECT_EQ(valid->componentType, "uint8");
    EXPECT_EQ(fraction->params["sharpen"], 3.0);
    EXPECT_EQ(fraction->params["azimuth"], 32);
    EXPECT_EQ(fraction->params["centre"], findLayer(grid, "fiv")->params["centre"]);
    EXPECT_GT(fraction->params["source_rays"].get<uint64_t>(), 0u);
    EXPECT_EQ(findLayer(grid, "fiv")->params["sources"], "fiv_source_grid");
    EXPECT_FALSE(findLayer(grid, "fiv")->params.contains("source_rays")); // the grid holds the rest of the map
    EXPECT_NE(findLayer(grid, "fiv")->data, findLayer(sources, "fiv")->data);
    size_t hidden = 0;
    for (float v : fraction->data) hidden += v > 0.5f;
    EXPECT_GT(hidden, 50u);

    // fivshade reads it; the sun's shadow is closer to the brute-force reference's than --sources alone gives it.
    const std::string shade = "fivshade " + f / "plane.glb --env " + dir / "sunny.exr --at 0.3,1,0 --occluder ";
    ASSERT_EQ(run(shade + dir / "sunny.grid.glb -o " + dir / "grid.npy", &log), 0);
    ASSERT_EQ(run(shade + dir / "sunny.glb -o " + dir / "sources.npy"), 0);
    ASSERT_EQ(run("reference " + f / "plane.glb --env " + dir / "sunny.exr --occluder " + f / "sphere.glb --at 0.3,1,0 " +
                  "--bounces 0 -o " + dir / "ref.npy"), 0);
    ASSERT_EQ(run("reference " + f / "plane.glb --env " + dir / "sunny.exr --unshadowed --bounces 0 -o " + dir / "free.npy"), 0);
    std::vector<float> g = readVertexRadiance(dir / "grid.npy"), s = readVertexRadiance(dir / "sources.npy"),
                       ref = readVertexRadiance(dir / "ref.npy"), free = readVertexRadiance(dir / "free.npy");
    ASSERT_EQ(g.size(), ref.size());
    double errorGrid = 0, errorSources = 0, shadow = 0;
    for (size_t i = 1; i < g.size(); i += 3) {
        errorGrid += std::pow(double(g[i]) - ref[i], 2), errorSources += std::pow(double(s[i]) - ref[i], 2);
        shadow = std::max(shadow, double(free[i]) - ref[i]);
    }
    EXPECT_GT(shadow, 1.0); // the sun's shadow is there to get right
    EXPECT_LT(errorGrid, 0.8 * errorSources) << errorGrid << " " << errorSources; // measured 722 against 1221
    // fivscene carries the layers, and fiv_self for the receiver; the scene shades like the separate files.
    const std::string placed = " --occluder " + dir / "sunny.grid.glb --at 0.3,1,0";
    ASSERT_EQ(run("fivscene " + f / "plane.glb" + placed + " -o " + dir / "scene.glb"), 0);
    Bundle scene = readBundle(dir / "scene.glb");
    EXPECT_NE(findObjectLayer(scene, "fiv_source_grid", 1), nullptr);
    EXPECT_NE(findObjectLayer(scene, "fiv_source_valid", 1), nullptr);
    ASSERT_EQ(run("fivshade " + dir / "scene.glb --env " + dir / "sunny.exr -o " + dir / "scene.npy"), 0);
    EXPECT_EQ(readFileBytes(dir / "scene.npy"), readFileBytes(dir / "grid.npy"));
    ASSERT_EQ(run("fivscene " + f / "sphere.glb --self " + dir / "sunny.grid.glb -o " + dir / "self.glb"), 0);
    EXPECT_NE(findObjectLayer(readBundle(dir / "self.glb"), "fiv_self", 0), nullptr);
    ASSERT_EQ(run("fivshade " + dir / "self.glb --env " + dir / "sunny.exr -o " + dir / "self-scene.npy"), 0);
    ASSERT_EQ(run("fivshade " + f / "sphere.glb --env " + dir / "sunny.exr --self " + dir / "sunny.grid.glb -o " +
                  dir / "self-files.npy", &log), 0);
    EXPECT_EQ(readFileBytes(dir / "self-scene.npy"), readFileBytes(dir / "self-files.npy"));
    std::string validator = PRT_SOURCE_DIR "/tests/bundle/gltf_validator";
    if (std::filesystem::exists(validator + "/node_modules/gltf-validator")) { // the Khronos validator accepts both
        std::string output;
        std::FILE* pipe = popen(("node " + validator + "/validate.mjs " + dir / "scene.glb " + dir / "self.glb 2>&1").c_str(), "r");
        char buffer[4096];
        size_t got;
        while ((got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, got);
        EXPECT_EQ(WEXITSTATUS(pclose(pipe)), 0) << output;
        size_t clean = 0;
        for (size_t at = output.find("\"errors\":0"); at != std::string::npos; at = output.find("\"errors\":0", at + 1)) ++clean;
        EXPECT_EQ(clean, 2u) << output; // no error in either file
    }

    // Usage errors (exit 2), nothing written.
    std::string message;
    const std::string out = " -o " + dir / "bad.glb";
    EXPECT_EQ(run("fiv " + f / "sphere.glb --grid 16,9,6 --cube 8 --source-grid 32,17,12 --env " + dir / "sunny.exr" + out,
                  &message), 2);
    EXPECT_NE(message.find("needs --sources"), std::string::npos) << message;
    for (const char* bad : {"--source-grid 2,17,12", "--source-grid 32,17", "--source-grid 32,1.5,4", "--source-grid Auto",
                            "--source-grid 4096,2049,1024", "--source-grid 32,17,12 --source-sharpen 0.5",
                            "--source-sharpen 2"}) {
        EXPECT_EQ(run("fiv " + common + bad + " --env " + dir / "sunny.exr" + out, &message), 2) << bad;
        EXPECT_NE(message.find("--source-"), std::string::npos) << bad << ": " << message;
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.glb"));
}
