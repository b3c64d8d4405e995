#include "bake.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace prt {
namespace {

TEST(RangeCompress, RoundTripErrorStaysWithinRangeOver510PerLayer) {
    const size_t texels = 4096;
    const int layers = 9, perLayer = 3;
    std::mt19937 random(3);
    std::vector<float> values(texels * layers * perLayer);
    for (size_t t = 0; t < texels; ++t)
        for (int j = 0; j < layers; ++j)
            for (int c = 0; c < perLayer; ++c) {
                // Layers of very different ranges and offsets, like SH bands.
                double scale = std::pow(10.0, j - 4), offset = (j % 3 - 1) * 2.0 * scale;
                double value = offset + scale * std::normal_distribution<>(0, 1)(random);
                values[(t * layers + j) * perLayer + c] = float(value);
            }
    RangeCompressed compressed = rangeCompress(values.data(), texels, layers, perLayer);
    ASSERT_EQ(compressed.range.size(), size_t(2 * layers));
    std::vector<float> expanded = rangeExpand(compressed, texels, layers, perLayer);
    for (int j = 0; j < layers; ++j) {
        double lo = compressed.range[2 * j], hi = compressed.range[2 * j + 1];
        double bound = (hi - lo) / 510.0, worst = 0.0;
        bool hasZero = false, hasFull = false;
        for (size_t t = 0; t < texels; ++t)
            for (int c = 0; c < perLayer; ++c) {
                size_t i = (t * layers + j) * perLayer + c;
                EXPECT_GE(values[i], lo);
                EXPECT_LE(values[i], hi);
                worst = std::max(worst, std::abs(double(expanded[i]) - values[i]));
                hasZero |= compressed.values[i] == 0;
                hasFull |= compressed.values[i] == 255;
            }
        // The bound plus the float rounding of the expanded value.
        double rounding = 4 * std::numeric_limits<float>::epsilon() * std::max(std::abs(lo), std::abs(hi));
        EXPECT_LE(worst, bound * (1 + 1e-6) + rounding)
            << "layer " << j;
        EXPECT_GT(worst, 0.5 * bound) << "layer " << j; // 8 bits really are lossy: the bound is tight
        EXPECT_TRUE(hasZero && hasFull) << "layer " << j; // min maps to 0, max to 255
    }
}

TEST(RangeCompress, ConstantLayerRoundTripsExactly) {
    std::vector<float> values = {0.25f, -1.0f, 0.25f, 2.0f, 0.25f, 3.0f};
    RangeCompressed compressed = rangeCompress(values.data(), 3, 2, 1);
    EXPECT_EQ(compressed.range[0], 0.25f);
    EXPECT_EQ(compressed.range[1], 0.25f);
    std::vector<float> expanded = rangeExpand(compressed, 3, 2, 1);
    for (size_t t = 0; t < 3; ++t) EXPECT_EQ(expanded[2 * t], 0.25f);
    EXPECT_EQ(expanded[1], -1.0f);
    EXPECT_EQ(expanded[5], 3.0f);
}

} // namespace
} // namespace prt
