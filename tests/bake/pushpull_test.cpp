#include "bake.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace prt {
namespace {

constexpr float kEmpty = std::numeric_limits<float>::quiet_NaN();

// Coverage of two discs and a one-texel island, like charts in an atlas; an odd size exercises the pyramid's
// ceil-halving.
std::vector<uint8_t> chartCoverage(int width, int height) {
    std::vector<uint8_t> covered(size_t(width) * height, 0);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            double a = std::hypot(x - 0.3 * width, y - 0.35 * height);
            double b = std::hypot(x - 0.75 * width, y - 0.7 * height);
            covered[size_t(y) * width + x] = a < 0.2 * width || b < 0.12 * width || (x == 3 && y == height - 4);
        }
    return covered;
}

// Random values in covered texels, NaN (nothing) elsewhere.
std::vector<float> randomTexels(const std::vector<uint8_t>& covered, int channels, unsigned seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> value(-3.0f, 5.0f);
    std::vector<float> texels(covered.size() * channels, kEmpty);
    for (size_t t = 0; t < covered.size(); ++t)
        if (covered[t])
            for (int c = 0; c < channels; ++c) texels[t * channels + c] = value(random);
    return texels;
}

TEST(PushPull, KeepsCoveredTexelsAndFillsEveryOtherWithinTheCoveredRange) {
    const int width = 97, height = 61, channels = 5;
    std::vector<uint8_t> covered = chartCoverage(width, height);
    std::vector<float> before = randomTexels(covered, channels, 7), after = before;
    pushPull(after.data(), width, height, channels, covered.data());
    std::vector<float> lo(channels, INFINITY), hi(channels, -INFINITY);
    for (size_t t = 0; t < covered.size(); ++t)
        if (covered[t])
            for (int c = 0; c < channels; ++c)
                lo[c] = std::min(lo[c], before[t * channels + c]), hi[c] = std::max(hi[c], before[t * channels + c]);
    for (size_t t = 0; t < covered.size(); ++t)
        for (int c = 0; c < channels; ++c) {
            float value = after[t * channels + c];
            if (covered[t]) {
                EXPECT_EQ(std::memcmp(&value, &before[t * channels + c], sizeof value), 0) << "texel " << t;
            } else {
                ASSERT_TRUE(std::isfinite(value)) << "texel " << t << " left empty";
                EXPECT_GE(value, lo[c] - 1e-5f);
                EXPECT_LE(value, hi[c] + 1e-5f);
            }
        }
}

TEST(PushPull, GutterNextToAChartTakesValuesCloseToTheChart) {
    // Left half 1, right half 3 (separate charts), a gutter column between them: each side's near texels keep
    // nearer to their own chart than to the other.
    const int width = 64, height = 64;
    std::vector<uint8_t> covered(size_t(width) * height, 0);
    std::vector<float> texels(covered.size(), kEmpty);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            if (x < 28 || x >= 36) {
                covered[size_t(y) * width + x] = 1;
                texels[size_t(y) * width + x] = x < 28 ? 1.0f : 3.0f;
            }
    pushPull(texels.data(), width, height, 1, covered.data());
    for (int y = 0; y < height; ++y) {
        EXPECT_LT(texels[size_t(y) * width + 28], 2.0f);
        EXPECT_GT(texels[size_t(y) * width + 35], 2.0f);
        for (int x = 28; x < 35; ++x) EXPECT_LE(texels[size_t(y) * width + x], texels[size_t(y) * width + x + 1]);
    }
}

TEST(PushPull, ConstantImageStaysExactlyConstant) {
    const int width = 130, height = 77;
    std::vector<uint8_t> covered = chartCoverage(width, height);
    const float constant[3] = {0.1f, -7.3e-3f, 1234.567f}; // none is a short binary fraction
    std::vector<float> texels(covered.size() * 3, kEmpty);
    for (size_t t = 0; t < covered.size(); ++t)
        if (covered[t])
            for (int c = 0; c < 3; ++c) texels[t * 3 + c] = constant[c];
    pushPull(texels.data(), width, height, 3, covered.data());
    for (size_t t = 0; t < covered.size(); ++t)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(texels[t * 3 + c], constant[c]) << "texel " << t;
}

TEST(PushPull, NothingCoveredLeavesTheImageAlone) {
    std::vector<uint8_t> covered(16 * 16, 0);
    std::vector<float> texels(16 * 16, 2.5f);
    pushPull(texels.data(), 16, 16, 1, covered.data());
    for (float value : texels) EXPECT_EQ(value, 2.5f);
}

TEST(DilateOneRing, FillsExactlyTheFirstRingWithItsCoveredNeighboursMean) {
    const int width = 9, height = 9;
    std::vector<uint8_t> covered(size_t(width) * height, 0);
    std::vector<float> texels(covered.size(), 0.0f);
    // A 2x2 block at (3..4, 3..4) with values 1, 2, 3, 4.
    for (int y = 3; y <= 4; ++y)
        for (int x = 3; x <= 4; ++x) {
            covered[size_t(y) * width + x] = 1;
            texels[size_t(y) * width + x] = float(1 + (x - 3) + 2 * (y - 3));
        }
    dilateOneRing(texels.data(), width, height, 1, covered.data());
    auto at = [&](int x, int y) { return texels[size_t(y) * width + x]; };
    EXPECT_FLOAT_EQ(at(2, 2), 1.0f);               // one neighbour
    EXPECT_FLOAT_EQ(at(3, 2), 1.5f);               // (1 + 2) / 2
    EXPECT_FLOAT_EQ(at(2, 3), 2.0f);               // (1 + 3) / 2
    EXPECT_FLOAT_EQ(at(5, 5), 4.0f);
    EXPECT_FLOAT_EQ(at(5, 3), 3.0f);               // (2 + 4) / 2
    EXPECT_FLOAT_EQ(at(3, 3), 1.0f);               // covered, unchanged
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            if (x < 2 || x > 5 || y < 2 || y > 5) {
                EXPECT_EQ(at(x, y), 0.0f) << x << "," << y; // second ring and beyond
            }
}

} // namespace
} // namespace prt
