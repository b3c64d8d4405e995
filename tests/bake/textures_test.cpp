#include "bake.h"

#include "core.h"
#include "runtime.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

namespace prt {
namespace {

std::string tempPath(const std::string& name) {
    std::string file = "prt_bake_test_" + std::to_string(::getpid()) + "_" + name;
    return (std::filesystem::temp_directory_path() / file).string();
}

TEST(CoefficientExr, ChannelNamesFollowTheDocumentedPattern) {
    EXPECT_EQ(texelCoefficientChannel(0, 0), "T000.R");
    EXPECT_EQ(texelCoefficientChannel(8, 2), "T008.B");
    EXPECT_EQ(texelCoefficientChannel(123, 1), "T123.G");
}

TEST(CoefficientExr, FloatRoundTripsExactlyAndHalfToHalfPrecision) {
    const int width = 13, height = 7, coefficients = 9;
    std::vector<float> texels(size_t(width) * height * coefficients * 3);
    std::mt19937 random(5);
    for (float& value : texels) value = std::normal_distribution<float>(0.0f, 2.0f)(random);
    for (bool half : {false, true}) {
        std::string path = tempPath(half ? "half.exr" : "float.exr");
        writeCoefficientExr(path, texels.data(), width, height, coefficients, half);
        int w = 0, h = 0, n = 0;
        std::vector<float> read = readCoefficientExr(path, w, h, n);
        EXPECT_EQ(w, width);
        EXPECT_EQ(h, height);
        EXPECT_EQ(n, coefficients);
        ASSERT_EQ(read.size(), texels.size());
        for (size_t i = 0; i < texels.size(); ++i) {
            if (half)
                EXPECT_NEAR(read[i], texels[i], std::abs(texels[i]) * 4.9e-4 + 6e-8);
            else
                EXPECT_EQ(read[i], texels[i]);
        }
        std::filesystem::remove(path);
    }
}

TEST(CoefficientExr, WrongSizeOrMissingFileIsAnError) {
    std::vector<float> texels(4 * 4 * 3, 1.0f);
    std::string path = tempPath("small.exr");
    writeCoefficientExr(path, texels.data(), 4, 4, 1, true);
    int w = 8, h = 4, n = 0;
    EXPECT_THROW(readCoefficientExr(path, w, h, n), Error);
    w = 4, n = 2; // asks for a coefficient the file does not have
    try {
        readCoefficientExr(path, w, h, n);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(e.place().find("T001.R"), std::string::npos) << e.what();
    }
    std::filesystem::remove(path);
    w = h = n = 0;
    EXPECT_THROW(readCoefficientExr(path, w, h, n), Error);
}

} // namespace
} // namespace prt
