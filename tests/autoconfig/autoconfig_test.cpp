// lib/autoconfig's pieces: the vertex subsets, the stored rows and bytes of each format, the noise-corrected error,
// and the property the pilot rests on (a lower order is the first coefficients of the same transfer run).
#include "autoconfig.h"

#include "core.h"
#include "scene.h"
#include "transfer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

namespace prt::autoconfig {
namespace {

TEST(Autoconfig, SubsetsAreDisjointDeterministicAndCoverTheMesh) {
    TriMesh sphere = makeSphere(1.0f, 16, 32);
    std::vector<uint32_t> pilot, heldOut, check, again, againHeld, againCheck;
    splitVertices(sphere, 40, 7, pilot, heldOut, check);
    splitVertices(sphere, 40, 7, again, againHeld, againCheck);
    EXPECT_EQ(pilot, again);
    EXPECT_EQ(heldOut, againHeld);
    EXPECT_EQ(check, againCheck);
    ASSERT_EQ(pilot.size(), 40u);
    ASSERT_EQ(heldOut.size(), 40u);
    ASSERT_EQ(check.size(), 40u);
    std::set<uint32_t> all(pilot.begin(), pilot.end());
    all.insert(heldOut.begin(), heldOut.end());
    all.insert(check.begin(), check.end());
    EXPECT_EQ(all.size(), 120u); // disjoint, no repeats
    // Stratified: every set reaches both hemispheres.
    for (const std::vector<uint32_t>* set : {&pilot, &heldOut, &check}) {
        int up = 0;
        for (uint32_t v : *set) up += sphere.positions[v * 3 + 1] > 0.0f;
        EXPECT_GT(up, 10);
        EXPECT_LT(up, 30);
    }
    // Asking for more than a third of the mesh gives a third.
    TriMesh tiny = makeSphere(1.0f, 2, 3); // 5 vertices
    splitVertices(tiny, 100, 0, pilot, heldOut, check);
    EXPECT_EQ(pilot.size(), 1u);
    EXPECT_EQ(heldOut.size(), 1u);
    EXPECT_EQ(check.size(), 1u);
    EXPECT_NE(pilot[0], check[0]);
    EXPECT_NE(heldOut[0], check[0]);
}

TEST(Autoconfig, StoredRowsKeepEachFormatsPrecisionAndTheBytesMatchItsLayers) {
    const int order = 3, stride = 4;
    const size_t count = 20;
    std::mt19937 random(3);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    std::vector<float> rows(count * stride * stride * 3);
    for (float& x : rows) x = uniform(random);
    for (adapt::Format format : {adapt::Format::Float, adapt::Format::Half, adapt::Format::U16, adapt::Format::U8}) {
        std::vector<float> stored = storedRows(rows.data(), count, stride, order, format);
        ASSERT_EQ(stored.size(), count * order * order * 3);
        double worst = 0.0;
        for (size_t v = 0; v < count; ++v)
            for (int j = 0; j < order * order * 3; ++j)
                worst = std::max(worst, double(std::abs(stored[v * order * order * 3 + j] - rows[v * stride * stride * 3 + j])));
        // Float exact; half within 2^-11 relative of |x| <= 1; codes within half a step of the band's scale (<= 1).
        const double bound = format == adapt::Format::Float ? 0.0
                             : format == adapt::Format::Half ? 1.0 / 2048
                             : format == adapt::Format::U16 ? 0.5 / 32767 * 1.001
                                                            : 0.5 / 127 * 1.001;
        EXPECT_LE(worst, bound) << adapt::formatName(format);
        if (format != adapt::Format::Float) {
            EXPECT_GT(worst, 0.0) << adapt::formatName(format);
        }
    }
    // Per-vertex orders: the coefficients beyond a vertex's order are zero.
    std::vector<uint8_t> orders(count, 3);
    orders[0] = 1;
    std::vector<float> ragged = storedRows(rows.data(), count, stride, order, adapt::Format::Float, &orders);
    EXPECT_EQ(ragged[0], rows[0]);
    for (int j = 3; j < order * order * 3; ++j) EXPECT_EQ(ragged[j], 0.0f);
    // Bytes: 1000 vertices at order 3.
    EXPECT_EQ(bundleLayerBytes(1000, 3, adapt::Format::Float, 0), 1000u * 9 * 3 * 4);
    EXPECT_EQ(bundleLayerBytes(1000, 3, adapt::Format::Float, 2), 1001u * 4 + 1000u * 9 * 3 * 4);
    EXPECT_EQ(bundleLayerBytes(1000, 3, adapt::Format::Half, 0), 1001u * 4 + 1000u * 9 * 3 * 2);
    EXPECT_EQ(bundleLayerBytes(1000, 3, adapt::Format::U8, 0), 1001u * 4 + 1000u * 3 * 2 + 1000u * 9 * 3);
    EXPECT_EQ(raggedLayerBytes(1000, 9000, 3000, adapt::Format::U8), bundleLayerBytes(1000, 3, adapt::Format::U8, 1));
    EXPECT_THROW(bundleLayerBytes(10, 3, adapt::Format::Cpca, 0), prt::Error);
}

TEST(Autoconfig, NoiseCorrectedErrorTakesOutTheReferencesNoise) {
    const size_t count = 4000;
    std::mt19937 random(5);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    std::vector<float> truth(count * 3), reference(count * 3), se(count * 3), relit(count * 3);
    for (size_t i = 0; i < count * 3; ++i) {
        truth[i] = 1.0f + 0.5f * float(i % 7) / 7.0f;
        se[i] = 0.02f * truth[i];
        reference[i] = truth[i] + se[i] * gauss(random);
        relit[i] = truth[i] * 1.03f; // a 3% error against the truth
    }
    double measured = noiseCorrectedError(relit.data(), reference.data(), se.data(), count);
    EXPECT_NEAR(measured, 0.03, 0.002);
    // Without the correction the noise would be charged: sqrt(0.03^2 + 0.02^2) = 0.036.
    std::vector<float> zero(count * 3, 0.0f);
    EXPECT_NEAR(noiseCorrectedError(relit.data(), reference.data(), zero.data(), count), 0.036, 0.002);
    // A relight equal to the truth measures (about) zero.
    EXPECT_LT(noiseCorrectedError(truth.data(), reference.data(), se.data(), count), 0.004);
}

// What lets one pilot run serve every order: the estimator does not depend on the order.
TEST(Autoconfig, LowerOrdersAreTheFirstCoefficientsOfTheSameRun) {
    TriMesh mesh = makeSphereInCavity(6, 12);
    for (int bounces : {0, 2}) {
        TransferOptions options;
        options.mode = bounces ? TransferMode::Interreflected : TransferMode::Shadowed;
        options.bounces = bounces;
        options.samples = 64;
        options.albedo = {0.7f, 0.7f, 0.7f};
        options.progress = false;
        options.order = 6;
        Transfer high = computeTransfer(mesh, options);
        options.order = 3;
        Transfer low = computeTransfer(mesh, options);
        double worst = 0.0, scale = 0.0;
        for (size_t v = 0; v < mesh.vertexCount(); ++v)
            for (int j = 0; j < 27; ++j) {
                worst = std::max(worst, double(std::abs(low.coefficients[v * 27 + j] - high.coefficients[v * 108 + j])));
                scale = std::max(scale, double(std::abs(high.coefficients[v * 108 + j])));
            }
        EXPECT_LE(worst, 1e-5 * scale) << bounces << " bounces";
    }
}

// A map's file name is the user's: one holding a newline and a TOML table must not end the comment it is quoted in
// and add an output to the pipeline (a stem gives the map's key and the noise line its name, both as bare keys).
TEST(Autoconfig, AMapsFileNameCannotAddTomlToThePipeline) {
    Result result;
    result.chosen.config.order = 3;
    result.chosen.config.samples = 64;
    result.referenceNoise = {0.01};
    Options options;
    const std::string hostile = "maps/x\n[outputs.e]\nfrom=\"transfer\"\npath=\"pwn\"\n#.exr";
    const std::string toml = pipelineToml(result, options, "mesh.glb", {hostile}, "out/bundle.glb", "p");
    size_t tables = 0;
    for (size_t begin = 0; begin < toml.size();) {
        size_t end = toml.find('\n', begin);
        if (end == std::string::npos) end = toml.size();
        const std::string line = toml.substr(begin, end - begin);
        EXPECT_NE(line.rfind("[outputs.", 0), 0u) << line;
        EXPECT_NE(line.rfind("path=", 0), 0u) << line;
        tables += line.rfind("[", 0) == 0;
        begin = end + 1;
    }
    EXPECT_GE(tables, 4u); // pipeline, inputs, the stages, outputs
    EXPECT_NE(toml.find("env-x--outputs-e--from--transfer--path--pwn---"), std::string::npos) << toml;
}

} // namespace
} // namespace prt::autoconfig

