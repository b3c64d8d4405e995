// The stack file `prt render --glossy-stack` writes for the browser viewer (docs/glossy.md "The stack file"), read
// back by its documented layout.
#include "render.h"
#include "core.h"
#include "prt/glossy.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>

#include <unistd.h>

namespace {

uint32_t u32(const std::string& bytes, size_t at) {
    uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
}

// A constant map: every stack texel is the kernel-weighted mean of a constant, the constant itself (closed form).
TEST(GlossyStack, FileHoldsEveryLevelOfAConstantMapAsItsRadiance) {
    const int width = 64, height = 32;
    std::vector<float> rgb(size_t(width) * height * 3);
    for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = i % 3 == 0 ? 2.0f : i % 3 == 1 ? 0.5f : 1.0f;
    prt::PrefilterOptions options;
    options.sharpnessMin = 4.0, options.sharpnessMax = 64.0;
    prt::PrefilteredEnvironment env = prt::prefilterEnvironment(rgb.data(), width, height, options);
    ASSERT_GE(env.sharpnessLevels.size(), 2u);
    const std::string path =
        (std::filesystem::temp_directory_path() / ("prt_stack_" + std::to_string(getpid()) + ".stack")).string();
    prt::writeSharpnessStack(path, env);
    const std::string bytes = prt::readFileBytes(path);
    std::filesystem::remove(path);
    ASSERT_GE(bytes.size(), 24u);
    EXPECT_EQ(bytes.substr(0, 8), "PRTSGSTK");
    EXPECT_EQ(u32(bytes, 8), 1u);
    EXPECT_EQ(u32(bytes, 12), 2u); // levels per octave
    EXPECT_EQ(u32(bytes, 16), 6u); // lambda 4 = 0.5 2^(6 / 2)
    ASSERT_EQ(u32(bytes, 20), env.sharpnessLevels.size());
    size_t at = 24;
    for (uint32_t l = 0; l < u32(bytes, 20); ++l) {
        ASSERT_LE(at + 16, bytes.size());
        const uint32_t w = u32(bytes, at), h = u32(bytes, at + 4);
        double sharpness;
        std::memcpy(&sharpness, bytes.data() + at + 8, 8);
        EXPECT_DOUBLE_EQ(sharpness, 0.5 * std::exp2((6.0 + l) / 2.0));
        EXPECT_EQ(w, 2 * h);
        ASSERT_LE(at + 16 + size_t(w) * h * 12, bytes.size());
        for (size_t i = 0; i < size_t(w) * h * 3; ++i) {
            float value;
            std::memcpy(&value, bytes.data() + at + 16 + i * 4, 4);
            ASSERT_NEAR(value, rgb[i % 3], 1e-5f) << "level " << l << " value " << i;
        }
        at += 16 + size_t(w) * h * 12;
    }
    EXPECT_EQ(at, bytes.size());
}

TEST(GlossyStack, RefusesAnEnvironmentWithoutAStack) {
    std::vector<float> rgb(16 * 8 * 3, 1.0f);
    prt::PrefilterOptions options;
    options.sharpnessMin = 1.0, options.sharpnessMax = 0.0; // no stack
    prt::PrefilteredEnvironment env = prt::prefilterEnvironment(rgb.data(), 16, 8, options);
    EXPECT_THROW(prt::writeSharpnessStack("/nonexistent/never.stack", env), prt::Error);
}

} // namespace
