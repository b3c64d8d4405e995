// `prt glossy` and `prt relight --eye` end to end: a small fit, the view-dependent radiance against the
// reference, and every bad input refused with no output.
#include "bundle.h"
#include "compare.h"
#include "core.h"
#include "image.h"
#include "render.h"

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

namespace {

struct PrtRun {
    int exitCode;
    std::string text;
};

PrtRun prt(const std::string& arguments, const fs::path& dir, const std::string& environment = "") {
    fs::path log = dir / "stderr.txt";
    std::string command = environment + " " + PRT_EXECUTABLE + " " + arguments + " 2> " + log.string();
    int status = std::system(command.c_str());
    std::stringstream text;
    text << std::ifstream(log).rdbuf();
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}

class GlossyCli : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("prt_glossy_cli_" + std::to_string(getpid()));
        fs::create_directories(dir);
        ASSERT_EQ(prt("scene sphere -o " + path("sphere.glb") + " --quiet", dir).exitCode, 0);
    }
    void TearDown() override { fs::remove_all(dir); }
    std::string path(const std::string& name) const { return (dir / name).string(); }
    fs::path dir;
};

TEST_F(GlossyCli, BadInputsFailWithoutOutput) {
    const std::string base = "glossy " + path("sphere.glb") + " -o " + path("out.glb") + " --grid 4 --quiet ";
    PrtRun exponent = prt(base + "--brdf phong:0,0.5", dir);
    EXPECT_EQ(exponent.exitCode, 2);
    EXPECT_NE(exponent.text.find("exponent must be > 0"), std::string::npos) << exponent.text;
    PrtRun lobes = prt(base + "--brdf phong:8,0.5 --lobes 5", dir);
    EXPECT_EQ(lobes.exitCode, 2);
    EXPECT_NE(lobes.text.find("--lobes"), std::string::npos) << lobes.text;
    PrtRun solver = prt(base + "--brdf phong:8,0.5 --solver cuda", dir);
    EXPECT_EQ(solver.exitCode, 2);
    PrtRun colour = prt(base + "--brdf phong:8,0.5 --indirect-glossy --albedo 0.5,0.4,0.3", dir);
    EXPECT_EQ(colour.exitCode, 2);
    EXPECT_NE(colour.text.find("grey"), std::string::npos) << colour.text;
    PrtRun nestedWarm = prt(base + "--brdf phong:8,0.5 --lobes 2 --nested --warm-start", dir);
    EXPECT_EQ(nestedWarm.exitCode, 2);
    EXPECT_NE(nestedWarm.text.find("--nested"), std::string::npos) << nestedWarm.text;
    PrtRun heldOut = prt(base + "--brdf phong:8,0.5 --lobes 2 --nested --held-out-grid 1", dir);
    EXPECT_EQ(heldOut.exitCode, 2);
    EXPECT_NE(heldOut.text.find("--held-out-grid"), std::string::npos) << heldOut.text;
    // The keep criteria: only with --nested, a margin in [0, 1), the max norm not with a lighting prior.
    for (const char* flags : {"--nested-margin 0.1", "--nested --nested-margin 1", "--nested-per-vertex",
                              "--nested --nested-max --nested-lighting x.exr"}) {
        PrtRun keep = prt(base + "--brdf phong:8,0.5 --lobes 2 " + flags, dir);
        EXPECT_EQ(keep.exitCode, 2) << flags;
        EXPECT_NE(keep.text.find("--nested"), std::string::npos) << flags << ": " << keep.text;
    }
    // The fit from below: not with the staged fits that refit earlier lobes, and a one-sided weight in (0, 1e6].
    for (const char* flags : {"--from-below --nested", "--from-below --warm-start"}) {
        PrtRun below = prt(base + "--brdf phong:8,0.5 --lobes 2 " + flags, dir);
        EXPECT_EQ(below.exitCode, 2) << flags;
        EXPECT_NE(below.text.find("--from-below"), std::string::npos) << flags << ": " << below.text;
    }
    for (const char* weight : {"0", "-1", "1e7", "nan"}) {
        PrtRun over = prt(base + "--brdf phong:8,0.5 --lobes 2 --from-below --overshoot " + weight, dir);
        EXPECT_EQ(over.exitCode, 2) << weight;
        EXPECT_NE(over.text.find("--overshoot"), std::string::npos) << weight << ": " << over.text;
    }
    // No OpenCL platform: an empty ICD vendor folder.
    fs::create_directories(dir / "no_vendors");
    PrtRun platform = prt(base + "--brdf phong:8,0.5", dir, "OCL_ICD_VENDORS=" + path("no_vendors"));
    EXPECT_NE(platform.exitCode, 0);
    EXPECT_NE(platform.text.find("--solver ceres"), std::string::npos) << platform.text;
    EXPECT_FALSE(fs::exists(dir / "out.glb"));
}

TEST_F(GlossyCli, FitRelightsAndRefusesATamperedViewSet) {
    PrtRun fit = prt("glossy " + path("sphere.glb") + " -o " + path("g.glb") +
                  " --brdf phong:8,0.5 --albedo 0.3 --grid 4 --samples 64 --quiet", dir);
    ASSERT_EQ(fit.exitCode, 0) << fit.text;
    prt::Bundle bundle = prt::readBundle(path("g.glb"));
    const prt::Layer* lobes = prt::findLayer(bundle, "glossy_lobes");
    ASSERT_NE(lobes, nullptr);
    EXPECT_EQ(lobes->componentType, "float16");
    EXPECT_EQ(lobes->shape[1], 92u);
    ASSERT_NE(prt::findLayer(bundle, "transfer"), nullptr);
    // A view set of 91 directions for 92 views per vertex.
    for (prt::Layer& layer : bundle.layers)
        if (layer.name == "glossy_lobes") layer.params["views"].erase(0);
    prt::writeBundle(path("bad.glb"), bundle);
    std::string env = std::string(PRT_DATA_DIR) + "/env/courtyard.exr";
    if (!fs::exists(env)) GTEST_SKIP() << "no " << env;
    PrtRun bad = prt("relight " + path("bad.glb") + " --env " + env + " --eye 0,0,4 -o " + path("bad.npy"), dir);
    EXPECT_EQ(bad.exitCode, 3);
    EXPECT_NE(bad.text.find("disagrees"), std::string::npos) << bad.text;
    EXPECT_FALSE(fs::exists(dir / "bad.npy"));
    PrtRun relit = prt("relight " + path("g.glb") + " --env " + env + " --eye 0,0,4 -o " + path("fit.npy") + " --quiet", dir);
    ASSERT_EQ(relit.exitCode, 0) << relit.text;
    PrtRun reference = prt("reference " + path("sphere.glb") + " --env " + env +
                        " --brdf phong:8,0.5 --albedo 0.3 --eye 0,0,4 --samples 64 -o " + path("ref.npy") + " --quiet",
                        dir);
    ASSERT_EQ(reference.exitCode, 0) << reference.text;
    PrtRun compare = prt("compare " + path("fit.npy") + " " + path("ref.npy") + " > " + path("c.json"), dir);
    ASSERT_EQ(compare.exitCode, 0);
    nlohmann::json metrics = nlohmann::json::parse(std::ifstream(path("c.json")));
    EXPECT_LT(metrics["relative_rmse"].get<double>(), 0.25) << metrics.dump();
}

// `prt glossy --nested` (one shard of the sphere's vertices, for time): the layer records it with its held-out grid,
// the stats count the views that kept each stage's lobe, and a view that dropped its second lobe holds it with
// amplitude 0 (no format change).
TEST_F(GlossyCli, NestedFitRecordsItsHeldOutGridAndZeroLobes) {
    PrtRun fit = prt("glossy " + path("sphere.glb") + " -o " + path("n.glb") + " --brdf phong:64,0.5 --lobes 2 --grid 4 " +
                         "--samples 16 --nested --shard 0/40 --stats " + path("n.json") + " --quiet",
                     dir);
    ASSERT_EQ(fit.exitCode, 0) << fit.text;
    prt::Bundle bundle = prt::readBundle(path("n.glb"));
    const prt::Layer* lobes = prt::findLayer(bundle, "glossy_lobes");
    ASSERT_NE(lobes, nullptr);
    EXPECT_EQ(lobes->params["nested"]["resolution"].get<int>(), 8);
    nlohmann::json stats = nlohmann::json::parse(std::ifstream(path("n.json")));
    ASSERT_EQ(stats["nested_kept_stage"].size(), 2u);
    const uint64_t problems = stats["problems"].get<uint64_t>(), kept = stats["nested_kept_stage"][1].get<uint64_t>();
    EXPECT_EQ(stats["nested_kept_stage"][0].get<uint64_t>(), problems);
    EXPECT_LE(kept, problems);
    // Views with a fitted first lobe and a zero second lobe: every dropped stage-2 lobe (and kept fits whose second
    // amplitude ended on its bound of 0).
    uint64_t dropped = 0;
    for (size_t row = 0; row + 10 <= lobes->data.size(); row += 10)
        dropped += lobes->data[row] > 0.0f && lobes->data[row + 5] == 0.0f;
    EXPECT_GE(dropped, problems - kept);
    EXPECT_GT(dropped, 0u);
}

// `--from-below` records its one-sided weight and sharpness bound in the lobe layer, and no lobe is sharper than
// the bound (grid 4: max(4^2, exponent 8) = 16).
TEST_F(GlossyCli, FitFromBelowRecordsItsWeightAndBoundsItsLobes) {
    PrtRun fit = prt("glossy " + path("sphere.glb") + " -o " + path("b.glb") + " --brdf phong:8,0.5 --lobes 2 --grid 4 " +
                         "--samples 16 --from-below --overshoot 20 --shard 0/40 --quiet",
                     dir);
    ASSERT_EQ(fit.exitCode, 0) << fit.text;
    prt::Bundle bundle = prt::readBundle(path("b.glb"));
    const prt::Layer* lobes = prt::findLayer(bundle, "glossy_lobes");
    ASSERT_NE(lobes, nullptr);
    EXPECT_EQ(lobes->params["from_below"]["overshoot"].get<double>(), 20.0);
    EXPECT_EQ(lobes->params["from_below"]["lambda_max"].get<double>(), 16.0);
    size_t lit = 0;
    for (size_t lobe = 0; lobe + 5 <= lobes->data.size(); lobe += 5) {
        if (lobes->data[lobe] == 0.0f) continue; // no fit (below the horizon): the exponent
        ++lit;
        EXPECT_LE(lobes->data[lobe + 4], 16.0f * (1 + 1e-3f)) << lobe; // float16 rounding
    }
    EXPECT_GT(lit, 0u);
}

// `prt relight --image`: the glossy bundle's radiance toward the camera's eye, per vertex, drawn by the renderer of
// `prt render` (so pixel for pixel what renderVertexRadiance makes of `relight --eye EYE`), and close to the
// path-traced `prt reference --image` of the same camera.
TEST_F(GlossyCli, RelightImageRendersTheLobesTowardTheCamera) {
    std::string env = std::string(PRT_DATA_DIR) + "/env/courtyard.exr";
    if (!fs::exists(env)) GTEST_SKIP() << "no " << env;
    ASSERT_EQ(prt("glossy " + path("sphere.glb") + " -o " + path("g.glb") +
                      " --brdf phong:8,0.5 --albedo 0.3 --grid 4 --samples 64 --quiet", dir).exitCode, 0);
    const std::string camera = " --image 24,20 --camera 0,0.5,4,0,0,0,0,1,0,35";
    PrtRun picture = prt("relight " + path("g.glb") + " --env " + env + camera + " -o " + path("pic.exr") + " --quiet", dir);
    ASSERT_EQ(picture.exitCode, 0) << picture.text;
    ASSERT_EQ(prt("relight " + path("g.glb") + " --env " + env + " --eye 0,0.5,4 -o " + path("eye.npy") + " --quiet",
                  dir).exitCode, 0);
    prt::PinholeCamera pinhole;
    pinhole.eye = {0.0f, 0.5f, 4.0f};
    pinhole.fovyDegrees = 35.0f;
    pinhole.width = 24;
    pinhole.height = 20;
    // The picture evaluates the lobes per pixel, toward each pixel's own view direction; the per-vertex radiance
    // toward the eye, interpolated, is what it replaces. Both see the same highlights on average (the lobes are
    // smooth at this sharpness), but not pixel for pixel.
    prt::RenderedImage expected = prt::renderVertexRadiance(prt::readBundle(path("g.glb")).mesh,
                                                            prt::readVertexRadiance(path("eye.npy")), pinhole);
    prt::Image image = prt::readImage(path("pic.exr"));
    ASSERT_EQ(image.rgb.size(), expected.radiance.rgb.size());
    double pictureSum = 0.0, vertexSum = 0.0, largest = 0.0;
    for (size_t i = 0; i < image.rgb.size(); ++i) {
        pictureSum += image.rgb[i], vertexSum += expected.radiance.rgb[i];
        largest = std::max(largest, std::fabs(double(image.rgb[i]) - expected.radiance.rgb[i]));
    }
    EXPECT_NEAR(pictureSum, vertexSum, 0.05 * vertexSum);
    EXPECT_GT(largest, 1e-4); // per pixel is not per vertex
    // `prt render` of the glossy bundle draws the same picture as `prt relight --image`.
    ASSERT_EQ(prt("render " + path("g.glb") + " --env " + env + " --size 24,20 --camera 0,0.5,4,0,0,0,0,1,0,35 -o " +
                      path("render.exr") + " --quiet", dir).exitCode, 0);
    prt::Image rendered = prt::readImage(path("render.exr"));
    ASSERT_EQ(rendered.rgb.size(), image.rgb.size());
    for (size_t i = 0; i < image.rgb.size(); ++i) ASSERT_EQ(rendered.rgb[i], image.rgb[i]) << i;

    PrtRun glossyOnly = prt("relight " + path("g.glb") + " --env " + env + camera + " --glossy-only -o " +
                                path("lobes.png") + " --quiet", dir);
    ASSERT_EQ(glossyOnly.exitCode, 0) << glossyOnly.text;
    EXPECT_TRUE(fs::exists(dir / "lobes.png"));

    ASSERT_EQ(prt("reference " + path("sphere.glb") + " --env " + env + " --brdf phong:8,0.5 --albedo 0.3" + camera +
                      " --samples 64 -o " + path("ref.exr") + " --quiet", dir).exitCode, 0);
    prt::Image reference = prt::readImage(path("ref.exr"));
    // Over the sphere's pixels (the reference shows the map where rays escape).
    prt::ImageComparison comparison = prt::compareImages(image.rgb.data(), reference.rgb.data(),
                                                         expected.coverage.data(), 24, 20);
    EXPECT_GT(comparison.maskPixels, 50u);
    EXPECT_LT(comparison.metrics.relativeRmse, 0.3);

    // Bad combinations: exit 2, no picture.
    for (const std::string& bad : {std::string(" --image 24,20 -o ") + path("bad.exr"),
                                   camera + " --eye 0,0,4 -o " + path("bad.exr"), camera + " -o " + path("bad.npy")}) {
        PrtRun refused = prt("relight " + path("g.glb") + " --env " + env + bad, dir);
        EXPECT_EQ(refused.exitCode, 2) << bad << ": " << refused.text;
    }
    EXPECT_FALSE(fs::exists(dir / "bad.exr"));
    EXPECT_FALSE(fs::exists(dir / "bad.npy"));
}

// --rotate-y turns the map under the lobes (the lookup turns, the stack is the map's): relit with a quarter turn,
// a glossy bundle gives what the map shifted by a quarter of its columns gives unturned, per vertex (exact sums,
// and the diffuse part through the rotated SH) and per pixel (the prefiltered stack). Both are the same texels in
// another order, so they agree to rounding.
TEST_F(GlossyCli, RotateYTurnsTheMapUnderTheLobes) {
    std::string env = std::string(PRT_DATA_DIR) + "/env/courtyard.exr";
    if (!fs::exists(env)) GTEST_SKIP() << "no " << env;
    ASSERT_EQ(prt("glossy " + path("sphere.glb") + " -o " + path("g.glb") +
                      " --brdf phong:8,0.5 --albedo 0.3 --grid 4 --samples 64 --quiet", dir).exitCode, 0);
    prt::Image map = prt::readImage(env), shifted = map;
    const int quarter = map.width / 4;
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x)
            for (int c = 0; c < 3; ++c)
                shifted.rgb[(size_t(y) * map.width + (x + map.width - quarter) % map.width) * 3 + c] =
                    map.rgb[(size_t(y) * map.width + x) * 3 + c];
    prt::writeImage(path("shifted.exr"), shifted);
    const std::string eye = " --eye 1,0.5,3.5 --quiet";
    ASSERT_EQ(prt("relight " + path("g.glb") + " --env " + env + " --rotate-y 90" + eye + " -o " + path("turned.npy"),
                  dir).exitCode, 0);
    ASSERT_EQ(prt("relight " + path("g.glb") + " --env " + path("shifted.exr") + eye + " -o " + path("moved.npy"),
                  dir).exitCode, 0);
    ASSERT_EQ(prt("relight " + path("g.glb") + " --env " + env + eye + " -o " + path("still.npy"), dir).exitCode, 0);
    std::vector<float> turned = prt::readVertexRadiance(path("turned.npy"));
    std::vector<float> moved = prt::readVertexRadiance(path("moved.npy"));
    std::vector<float> still = prt::readVertexRadiance(path("still.npy"));
    ASSERT_EQ(turned.size(), moved.size());
    double difference = 0.0, change = 0.0, energy = 0.0;
    for (size_t i = 0; i < turned.size(); ++i) {
        difference += (double(turned[i]) - moved[i]) * (double(turned[i]) - moved[i]);
        change += (double(turned[i]) - still[i]) * (double(turned[i]) - still[i]);
        energy += double(moved[i]) * moved[i];
    }
    EXPECT_LT(std::sqrt(difference / energy), 1e-3);
    EXPECT_GT(std::sqrt(change / energy), 0.05); // the turn changes the radiance, so the test can fail
    const std::string camera = " --size 24,20 --camera 1,0.5,3.5,0,0,0,0,1,0,35 --quiet -o ";
    ASSERT_EQ(prt("render " + path("g.glb") + " --env " + env + " --rotate-y 90" + camera + path("turned.exr"), dir)
                  .exitCode, 0);
    ASSERT_EQ(prt("render " + path("g.glb") + " --env " + path("shifted.exr") + camera + path("moved.exr"), dir)
                  .exitCode, 0);
    prt::Image turnedPicture = prt::readImage(path("turned.exr")), movedPicture = prt::readImage(path("moved.exr"));
    ASSERT_EQ(turnedPicture.rgb.size(), movedPicture.rgb.size());
    difference = energy = 0.0;
    for (size_t i = 0; i < turnedPicture.rgb.size(); ++i) {
        double d = double(turnedPicture.rgb[i]) - movedPicture.rgb[i];
        difference += d * d, energy += double(movedPicture.rgb[i]) * movedPicture.rgb[i];
    }
    EXPECT_GT(energy, 0.0);
    EXPECT_LT(std::sqrt(difference / energy), 1e-3);
}

std::string fileBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Shards are vertex ranges; `prt merge` joins three of them, in any order, into the unsharded bundle byte for byte,
// and neither the thread count nor the sharding changes a byte.
TEST_F(GlossyCli, ThreeShardsMergeIntoTheUnshardedBundleByteForByte) {
    const std::string base = "glossy " + path("sphere.glb") + " --brdf phong:16,0.5 --albedo 0.4 --lobes 2 "
                             "--grid 4 --samples 32 --iterations 15 --quiet ";
    ASSERT_EQ(prt(base + "-o " + path("whole.glb") + " --threads 2", dir).exitCode, 0);
    ASSERT_EQ(prt(base + "-o " + path("one.glb") + " --threads 1", dir).exitCode, 0);
    EXPECT_EQ(fileBytes(path("one.glb")), fileBytes(path("whole.glb")));
    for (int i = 0; i < 3; ++i) {
        PrtRun shard = prt(base + "--shard " + std::to_string(i) + "/3 --threads " + std::to_string(1 + i % 2) +
                               " -o " + path("shard" + std::to_string(i) + ".glb"), dir);
        ASSERT_EQ(shard.exitCode, 0) << shard.text;
    }
    prt::Bundle shard = prt::readBundle(path("shard1.glb"));
    ASSERT_NE(prt::findLayer(shard, "glossy_lobes"), nullptr);
    EXPECT_EQ(prt::findLayer(shard, "glossy_lobes")->domain, "vertex_range");
    EXPECT_EQ(prt::findLayer(shard, "transfer")->domain, "vertex_range");
    PrtRun merge = prt("merge " + path("shard2.glb") + " " + path("shard0.glb") + " " + path("shard1.glb") + " -o " +
                           path("merged.glb") + " --quiet", dir);
    ASSERT_EQ(merge.exitCode, 0) << merge.text;
    EXPECT_EQ(fileBytes(path("merged.glb")), fileBytes(path("whole.glb")));

    // A diffuse bundle given with --diffuse travels whole in every shard and merges as well.
    ASSERT_EQ(prt(base + "-o " + path("d_whole.glb") + " --diffuse " + path("whole.glb"), dir).exitCode, 0);
    for (int i = 0; i < 3; ++i)
        ASSERT_EQ(prt(base + "--diffuse " + path("whole.glb") + " --shard " + std::to_string(i) + "/3 -o " +
                          path("d" + std::to_string(i) + ".glb"), dir).exitCode, 0);
    ASSERT_EQ(prt("merge " + path("d0.glb") + " " + path("d1.glb") + " " + path("d2.glb") + " -o " +
                      path("d_merged.glb") + " --quiet", dir).exitCode, 0);
    EXPECT_EQ(fileBytes(path("d_merged.glb")), fileBytes(path("d_whole.glb")));

    // Indirect glossy reads the whole mesh's transfer in every shard: still byte for byte (in the open cavity,
    // where the wall blocks part of every lobe).
    ASSERT_EQ(prt("scene cavity -o " + path("cavity.glb") + " --quiet", dir).exitCode, 0);
    std::string indirect = base;
    indirect.replace(indirect.find(path("sphere.glb")), path("sphere.glb").size(), path("cavity.glb"));
    indirect += "--indirect-glossy ";
    ASSERT_EQ(prt(indirect + "-o " + path("i_whole.glb"), dir).exitCode, 0);
    for (int i = 0; i < 2; ++i)
        ASSERT_EQ(prt(indirect + "--shard " + std::to_string(i) + "/2 -o " + path("i" + std::to_string(i) + ".glb"),
                      dir).exitCode, 0);
    ASSERT_EQ(prt("merge " + path("i1.glb") + " " + path("i0.glb") + " -o " + path("i_merged.glb") + " --quiet", dir)
                  .exitCode, 0);
    EXPECT_EQ(fileBytes(path("i_merged.glb")), fileBytes(path("i_whole.glb")));

    // Interreflection gathers from every vertex: refused with a shard, nothing written.
    PrtRun bounces = prt(base + "--bounces 1 --shard 0/3 -o " + path("b.glb"), dir);
    EXPECT_EQ(bounces.exitCode, 2);
    EXPECT_NE(bounces.text.find("--shard"), std::string::npos) << bounces.text;
    EXPECT_FALSE(fs::exists(dir / "b.glb"));
    PrtRun badShard = prt(base + "--shard 3/3 -o " + path("b.glb"), dir);
    EXPECT_EQ(badShard.exitCode, 2);
    EXPECT_FALSE(fs::exists(dir / "b.glb"));
}

} // namespace
