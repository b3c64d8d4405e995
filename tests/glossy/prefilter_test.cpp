// The glossy runtime's prefiltered stack (lib/runtime/glossy_prefilter.cpp): lookupLobe against the exact texel
// sum integrateLobe, against closed forms (a constant map, a Gaussian light), at the poles and the +-pi seam, a
// rotated map as a rotated lookup, and the stack's independence of its range and of the job system.
#include "glossy.h"
#include "runtime.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace {

constexpr double kPi = std::numbers::pi;

double kernelIntegral(double sharpness) { return 2.0 * kPi / sharpness * (1.0 - std::exp(-2.0 * sharpness)); }

void directionOf(double theta, double phi, float d[3]) {
    d[0] = float(std::sin(theta) * std::sin(phi)), d[1] = float(std::cos(theta)), d[2] = float(-std::sin(theta) * std::cos(phi));
}

// A map with structure at every scale: a smooth sky gradient, a band of texel noise, and a small bright sun
// (a few texels, 200 times the sky) near the +-pi seam at 30 degrees from the top pole.
std::vector<float> structuredMap(int width, int height) {
    std::vector<float> rgb(size_t(width) * height * 3);
    std::mt19937 random(7);
    std::uniform_real_distribution<float> noise(0.0f, 1.0f);
    float sun[3];
    directionOf(kPi / 6, kPi - 0.05, sun);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            float w[3];
            directionOf(kPi * (y + 0.5) / height, 2 * kPi * (x + 0.5) / width - kPi, w);
            float sky = 0.3f + 0.5f * std::max(0.0f, w[1]) + 0.2f * w[0];
            float grain = (y > height / 2 && y < 3 * height / 4) ? noise(random) : 0.0f;
            float c = w[0] * sun[0] + w[1] * sun[1] + w[2] * sun[2];
            float bright = c > std::cos(0.04f) ? 200.0f : 0.0f;
            float* t = &rgb[(size_t(y) * width + x) * 3];
            t[0] = sky + grain + bright, t[1] = 0.8f * sky + bright, t[2] = 0.5f + 0.3f * grain + 0.5f * bright;
        }
    return rgb;
}

// Unit directions: random ones, the poles, on and beside the +-pi seam (+Z), and beside the poles.
std::vector<std::array<float, 3>> testDirections() {
    std::vector<std::array<float, 3>> out;
    std::mt19937 random(3);
    std::normal_distribution<float> normal;
    for (int i = 0; i < 40; ++i) {
        float d[3] = {normal(random), normal(random), normal(random)};
        float l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        out.push_back({d[0] / l, d[1] / l, d[2] / l});
    }
    for (double theta : {0.0, 0.004, 0.03, kPi / 6, kPi / 2, kPi - 0.01, kPi})
        for (double phi : {kPi, -kPi + 1e-4, kPi - 0.02, kPi - 0.05, 0.7}) {
            float d[3];
            directionOf(theta, phi, d);
            out.push_back({d[0], d[1], d[2]});
        }
    return out;
}

std::vector<double> testSharpness() {
    std::vector<double> out;
    for (double s = 0.5; s <= 8192.0; s *= 2.7) out.push_back(s);
    out.push_back(8192.0);
    out.push_back(0.5);
    return out;
}

TEST(GlossyPrefilter, ConstantMapGivesTheKernelIntegralTimesTheRadiance) {
    const int width = 128, height = 64;
    std::vector<float> rgb(size_t(width) * height * 3);
    for (size_t i = 0; i < rgb.size(); i += 3) rgb[i] = 1.5f, rgb[i + 1] = 0.25f, rgb[i + 2] = 4.0f;
    const prt::PrefilteredEnvironment env = prt::prefilterEnvironment(rgb.data(), width, height);
    ASSERT_GE(env.sharpnessLevels.size(), 2u);
    for (double sharpness : testSharpness())
        for (const auto& d : testDirections()) {
            const float lobe[5] = {0.7f, d[0], d[1], d[2], float(sharpness)};
            float radiance[3];
            prt::lookupLobe(env, lobe, radiance);
            const double integral = 0.7 * kernelIntegral(float(sharpness));
            EXPECT_NEAR(radiance[0], 1.5 * integral, 1e-5 * 1.5 * integral) << sharpness;
            EXPECT_NEAR(radiance[1], 0.25 * integral, 1e-5 * 0.25 * integral) << sharpness;
            EXPECT_NEAR(radiance[2], 4.0 * integral, 1e-5 * 4.0 * integral) << sharpness;
        }
}

// At a stack level's own sharpness and one of its texel centres the lookup reads one texel: integrateLobe's sum
// over the same texels, normalised by the kernel's sum there and scaled by its exact integral. So the stack holds
// exact sums and the lookup's only approximation is the interpolation.
TEST(GlossyPrefilter, StackTexelsAreTheExactSums) {
    const int width = 256, height = 128;
    const std::vector<float> rgb = structuredMap(width, height);
    const prt::PrefilteredEnvironment env = prt::prefilterEnvironment(rgb.data(), width, height);
    std::vector<float> ones(rgb.size(), 1.0f);
    const prt::PrefilteredEnvironment unit = prt::prefilterEnvironment(ones.data(), width, height);
    std::mt19937 random(11);
    for (const auto& level : env.sharpnessLevels) {
        std::uniform_int_distribution<int> row(0, level.height - 1), column(0, level.width - 1);
        for (int i = 0; i < 6; ++i) {
            int y = i == 0 ? 0 : i == 1 ? level.height - 1 : row(random), x = i == 2 ? 0 : column(random);
            float d[3];
            directionOf(kPi * (y + 0.5) / level.height, 2 * kPi * (x + 0.5) / level.width - kPi, d);
            const float lobe[5] = {1.0f, d[0], d[1], d[2], float(level.sharpness)};
            float looked[3], exact[3], kernel[3];
            prt::lookupLobe(env, lobe, looked);
            prt::integrateLobe(env, lobe, exact);
            prt::integrateLobe(unit, lobe, kernel); // the kernel's own texel sum
            for (int c = 0; c < 3; ++c) {
                const double expected = exact[c] / kernel[c] * kernelIntegral(lobe[4]);
                EXPECT_NEAR(looked[c], expected, 2e-4 * expected + 1e-6) << level.sharpness << " " << y << " " << x;
            }
        }
    }
}

// Between texels and between levels: the lookup against the exact sum for lobes of sharpness 0.5..8192 at
// random directions, the poles and the seam. The error is taken relative to the lobe's integral of half the sky's
// radiance plus the exact value, so a lobe that misses the sun is judged against the sky it sees. Lobes the map
// resolves (its texel spacing at most a quarter of 1 / sqrt(lambda), lambda <= 104 at 256 x 128) are held to the
// stack's interpolation error; sharper ones, where both sums see only a few texels, more loosely.
TEST(GlossyPrefilter, LookupAgreesWithTheExactSum) {
    const int width = 256, height = 128;
    const std::vector<float> rgb = structuredMap(width, height);
    const prt::PrefilteredEnvironment env = prt::prefilterEnvironment(rgb.data(), width, height);
    double worst[2] = {0, 0}, sumSquares[2] = {0, 0};
    size_t count[2] = {0, 0};
    for (double sharpness : testSharpness())
        for (const auto& d : testDirections())
            for (double jitter : {1.0, 1.13, 1.41}) {
                const float lobe[5] = {1.0f, d[0], d[1], d[2], float(std::min(8192.0, sharpness * jitter))};
                float looked[3], exact[3];
                prt::lookupLobe(env, lobe, looked);
                prt::integrateLobe(env, lobe, exact);
                const int sharp = 2 * kPi / width > 0.25 / std::sqrt(lobe[4]);
                for (int c = 0; c < 3; ++c) {
                    const double scale = 0.5 * kernelIntegral(lobe[4]) + exact[c];
                    const double error = std::fabs(double(looked[c]) - exact[c]) / scale;
                    worst[sharp] = std::max(worst[sharp], error);
                    sumSquares[sharp] += error * error;
                    ++count[sharp];
                }
            }
    const double rms[2] = {std::sqrt(sumSquares[0] / double(count[0])), std::sqrt(sumSquares[1] / double(count[1]))};
    std::printf("lookup against the exact sum, resolved lobes: rms %.4f, worst %.4f (%zu); sharper: rms %.4f, worst "
                "%.4f (%zu)\n", rms[0], worst[0], count[0], rms[1], worst[1], count[1]);
    EXPECT_LT(rms[0], 0.01);
    EXPECT_LT(worst[0], 0.04);
    EXPECT_LT(rms[1], 0.05);
    EXPECT_LT(worst[1], 0.3);
}

// A Gaussian light exp(lL (d . w - 1)): the SG inner-product closed form, through the lookup.
TEST(GlossyPrefilter, LookupOfAGaussianLightMatchesTheClosedForm) {
    const int width = 256, height = 128;
    std::vector<float> rgb(size_t(width) * height * 3);
    const double d[3] = {0.0, 0.6, -0.8}, lightSharpness = 50.0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            float w[3];
            directionOf(kPi * (y + 0.5) / height, 2 * kPi * (x + 0.5) / width - kPi, w);
            float value = float(std::exp(lightSharpness * (d[0] * w[0] + d[1] * w[1] + d[2] * w[2] - 1)));
            for (int c = 0; c < 3; ++c) rgb[(size_t(y) * width + x) * 3 + c] = value;
        }
    prt::PrefilterOptions options;
    options.sharpnessMin = 30, options.sharpnessMax = 100;
    const prt::PrefilteredEnvironment env = prt::prefilterEnvironment(rgb.data(), width, height, options);
    // On the light, 6 and 20 degrees from it.
    const double means[3][3] = {{0.0, 0.6, -0.8}, {0.1045, 0.5967, -0.7956}, {0.3420, 0.5638, -0.7518}};
    for (double sharpness : {35.0, 60.0, 95.0})
        for (const auto& raw : means) {
            const double length = std::sqrt(raw[0] * raw[0] + raw[1] * raw[1] + raw[2] * raw[2]);
            const double mu[3] = {raw[0] / length, raw[1] / length, raw[2] / length};
            const float lobe[5] = {1.0f, float(mu[0]), float(mu[1]), float(mu[2]), float(sharpness)};
            float radiance[3];
            prt::lookupLobe(env, lobe, radiance);
            double m[3], lm = 0;
            for (int c = 0; c < 3; ++c) m[c] = sharpness * mu[c] + lightSharpness * d[c], lm += m[c] * m[c];
            lm = std::sqrt(lm);
            double expected = 2 * kPi * std::exp(lm - sharpness - lightSharpness) * (1 - std::exp(-2 * lm)) / lm;
            EXPECT_NEAR(radiance[0], expected, 0.02 * expected) << sharpness << " " << mu[0];
        }
}

// A map turned by 90 degrees about +Y is its columns shifted by a quarter turn: the rotated lookup of the stored
// map reads what the stored lookup of the shifted map reads.
TEST(GlossyPrefilter, RotatedMapIsARotatedLookup) {
    const int width = 128, height = 64;
    const std::vector<float> rgb = structuredMap(width, height);
    std::vector<float> shifted(rgb.size());
    // L'(d) = L(R^T d) with R taking +Z to +X: phi' = phi + pi / 2, a quarter of the columns.
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c)
                shifted[(size_t(y) * width + x) * 3 + c] = rgb[(size_t(y) * width + (x + width / 4) % width) * 3 + c];
    prt::PrefilteredEnvironment turned = prt::prefilterEnvironment(rgb.data(), width, height);
    const double angle = kPi / 2;
    const double R[9] = {std::cos(angle), 0, std::sin(angle), 0, 1, 0, -std::sin(angle), 0, std::cos(angle)};
    std::copy(R, R + 9, turned.rotation);
    const prt::PrefilteredEnvironment moved = prt::prefilterEnvironment(shifted.data(), width, height);
    for (double sharpness : {0.7, 9.0, 150.0, 3000.0})
        for (const auto& d : testDirections()) {
            // At a pole the azimuth, and so the bilinear weights of the lookup, depend on rounding.
            if (std::fabs(d[1]) > 0.9999f) continue;
            const float lobe[5] = {1.0f, d[0], d[1], d[2], float(sharpness)};
            float a[3], b[3], ea[3], eb[3];
            prt::lookupLobe(turned, lobe, a);
            prt::lookupLobe(moved, lobe, b);
            prt::integrateLobe(turned, lobe, ea);
            prt::integrateLobe(moved, lobe, eb);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(a[c], b[c], 1e-4 * (std::fabs(b[c]) + 1e-3)) << sharpness;
                EXPECT_NEAR(ea[c], eb[c], 1e-4 * (std::fabs(eb[c]) + 1e-3)) << sharpness;
            }
        }
}

void reversed(void*, size_t count, prt::TaskFunction task, void* data) {
    for (size_t i = count; i-- > 0;) task(data, i);
}

// A stack built over a sub-range, or by a job system running the rows in another order, holds the same texels.
TEST(GlossyPrefilter, StackDoesNotDependOnItsRangeOrJobs) {
    const int width = 128, height = 64;
    const std::vector<float> rgb = structuredMap(width, height);
    const prt::PrefilteredEnvironment whole = prt::prefilterEnvironment(rgb.data(), width, height);
    prt::PrefilterOptions options;
    options.sharpnessMin = 3.0, options.sharpnessMax = 70.0;
    prt::JobSystem jobs;
    jobs.parallelFor = reversed;
    options.jobs = &jobs;
    const prt::PrefilteredEnvironment part = prt::prefilterEnvironment(rgb.data(), width, height, options);
    ASSERT_GE(part.sharpnessLevels.size(), 2u);
    EXPECT_LE(part.sharpnessLevels.front().sharpness, 3.0);
    EXPECT_GE(part.sharpnessLevels.back().sharpness, 70.0);
    EXPECT_LT(part.sharpnessLevels.size(), whole.sharpnessLevels.size());
    for (const auto& level : part.sharpnessLevels) {
        const auto& same = whole.sharpnessLevels[size_t(part.firstSharpnessIndex) + (&level - &part.sharpnessLevels[0])];
        EXPECT_EQ(level.sharpness, same.sharpness);
        EXPECT_EQ(level.rgb, same.rgb);
    }
    // Outside the built range the lookup is the exact sum.
    const float sharp[5] = {1.0f, 0.0f, 0.6f, 0.8f, 900.0f};
    float a[3], b[3];
    prt::lookupLobe(part, sharp, a);
    prt::integrateLobe(part, sharp, b);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(a[c], b[c]);
    options.sharpnessMin = 2.0, options.sharpnessMax = 1.0;
    EXPECT_TRUE(prt::prefilterEnvironment(rgb.data(), width, height, options).sharpnessLevels.empty());
}

} // namespace
