// The map-to-cube resampling keeps every source's power: a sun of one map texel, smaller than the cube's texels,
// placed anywhere, and a constant map stays constant; the shared cube geometry (lib/sh/cube.cpp) round-trips.
#include "fiv.h"

#include "sh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace prt;
using namespace prt::fiv;

namespace {

constexpr double kPi = std::numbers::pi;

EnvironmentMap equirect(int width, float r, float g, float b) {
    EnvironmentMap env;
    env.radiance.width = width;
    env.radiance.height = width / 2;
    env.radiance.rgb.resize(size_t(width) * (width / 2) * 3);
    for (size_t i = 0; i < env.radiance.rgb.size(); i += 3)
        env.radiance.rgb[i] = r, env.radiance.rgb[i + 1] = g, env.radiance.rgb[i + 2] = b;
    return env;
}

// sum_t L_t dw_t per channel.
std::array<double, 3> cubePower(const CubeEnvironment& env) {
    CubeTexels cube = cubeTexels(env.size);
    std::array<double, 3> power{0, 0, 0};
    for (size_t t = 0; t < cube.solidAngle.size(); ++t)
        for (int c = 0; c < 3; ++c) power[size_t(c)] += env.radiance[3 * t + c] * cube.solidAngle[t];
    return power;
}

} // namespace

TEST(FivResample, OneHotTexelKeepsItsPowerAndItsPlaceWhereverItLies) {
    // A 5.6 degree sun on 22.5 (4^2) and 11.25 degree (8^2) cube texels: point samples would miss it or count it
    // several times over; area weighting keeps its power exactly and puts it where it is.
    const int width = 64, height = 32;
    std::vector<double> solidAngle = sh::texelSolidAngles(equirect(width, 0, 0, 0));
    // Texels at a face centre, on face edges and corners (45 degrees, the cube's corner latitude), near a pole,
    // on the pole row, and at odd places.
    const int places[][2] = {{0, 16}, {8, 16}, {7, 8}, {40, 9}, {56, 6}, {5, 0}, {38, 31}, {32, 1},
                             {50, 25}, {15, 22}, {63, 15}};
    for (int size : {4, 8})
        for (const auto& place : places) {
            EnvironmentMap env = equirect(width, 0, 0, 0);
            size_t texel = size_t(place[1]) * width + place[0];
            env.radiance.rgb[3 * texel] = 1000.0f, env.radiance.rgb[3 * texel + 1] = 10.0f;
            CubeEnvironment cube = resampleToCube(env, size);
            std::array<double, 3> power = cubePower(cube);
            double expected = 1000.0 * solidAngle[texel];
            EXPECT_NEAR(power[0], expected, 1e-10 * expected) << "size " << size << " at " << place[0] << "," << place[1];
            EXPECT_NEAR(power[1], expected / 100.0, 1e-10 * expected);
            EXPECT_EQ(power[2], 0.0);
            // Every cube texel that got some of it overlaps the hot texel: its centre lies within its own radius
            // plus the hot texel's from the hot texel's centre.
            double d[3];
            sh::equirectDirection(width, height, place[0], place[1], d);
            double hotRadius = kPi / height * std::sqrt(2.0); // a bound on the texel's half-diagonal angle
            CubeTexels texels = cubeTexels(size);
            for (size_t t = 0; t < texels.solidAngle.size(); ++t) {
                if (cube.radiance[3 * t] == 0.0) continue;
                const double* w = &texels.direction[3 * t];
                double angle = std::acos(std::clamp(d[0] * w[0] + d[1] * w[1] + d[2] * w[2], -1.0, 1.0));
                EXPECT_LE(angle, std::acos(texels.cosRadius[t]) + hotRadius) << "texel " << t;
            }
        }
}

TEST(FivResample, ConstantMapStaysConstantAndTotalPowerIsTheMaps) {
    EnvironmentMap env = equirect(256, 1.0f, 2.0f, 0.5f);
    for (int size : {4, 16}) {
        CubeEnvironment cube = resampleToCube(env, size);
        double worst = 0.0;
        for (size_t t = 0; t < cube.radiance.size() / 3; ++t)
            worst = std::max(worst, std::abs(cube.radiance[3 * t + 1] / 2.0 - 1.0));
        // Cells are cut by the boundary as if it were straight in them, and leaves at cube-texel corners go
        // whole to one side: a small error (1e-4 to 2e-4 measured from 128 x 64 to 1024 x 512 maps).
        EXPECT_LT(worst, 3e-4) << "size " << size;
        std::array<double, 3> power = cubePower(cube);
        EXPECT_NEAR(power[0], 4.0 * kPi, 1e-12 * 4.0 * kPi);
        EXPECT_NEAR(power[1], 8.0 * kPi, 1e-12 * 8.0 * kPi);
    }
}

TEST(FivResample, ACubeStripMapOfTheSameSizeComesBackExactlyAndASmallerOneKeepsItsPower) {
    // A cube-strip map of 16^2 faces whose texel t holds t: resampling it to 16^2 is the identity.
    EnvironmentMap strip;
    strip.layout = EnvLayout::CubeStrip;
    strip.radiance.width = 16, strip.radiance.height = 96;
    for (int t = 0; t < 16 * 96; ++t) strip.radiance.rgb.insert(strip.radiance.rgb.end(), {float(t), 1.0f, 0.0f});
    CubeEnvironment same = resampleToCube(strip, 16);
    for (int t = 0; t < 16 * 96; ++t) {
        EXPECT_NEAR(same.radiance[3 * size_t(t)], double(t), 1e-9 * t);
        EXPECT_NEAR(same.radiance[3 * size_t(t) + 1], 1.0, 1e-12);
    }
    // Onto 6 x 5^2 (boundaries that cut the source texels): the power is kept, the constant channel stays 1.
    CubeEnvironment coarse = resampleToCube(strip, 5);
    std::vector<double> solidAngle = sh::texelSolidAngles(strip);
    double expected = 0.0;
    for (int t = 0; t < 16 * 96; ++t) expected += double(t) * solidAngle[size_t(t)];
    EXPECT_NEAR(cubePower(coarse)[0], expected, 1e-12 * expected);
    for (size_t t = 0; t < coarse.radiance.size() / 3; ++t) EXPECT_NEAR(coarse.radiance[3 * t + 1], 1.0, 3e-4);
}

TEST(FivResample, SharedCubeGeometryRoundTripsAndItsSolidAnglesAreTheCornerFormulas) {
    for (int face = 0; face < 6; ++face)
        for (double a : {-0.9, -0.2, 0.0, 0.6})
            for (double b : {-0.7, 0.1, 0.95}) {
                double d[3], a2, b2;
                sh::cubeFaceDirection(face, a, b, d);
                EXPECT_NEAR(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], 1.0, 1e-14);
                EXPECT_EQ(sh::cubeFaceOf(d, a2, b2), face);
                EXPECT_NEAR(a2, a, 1e-14);
                EXPECT_NEAR(b2, b, 1e-14);
            }
    // A whole face is 4 pi / 6; a quarter face [0, 1]^2 is 4 pi / 24.
    EXPECT_NEAR(sh::cubeRectangleSolidAngle(-1, 1, -1, 1), 4.0 * kPi / 6.0, 1e-14);
    EXPECT_NEAR(sh::cubeRectangleSolidAngle(0, 1, 0, 1), 4.0 * kPi / 24.0, 1e-14);
}

TEST(FivResample, CapCosineIntegralMatchesQuadrature) {
    // The one Snyder formula (sh::capCosineIntegral), against a midpoint rule over the cap.
    for (double sigma : {0.05, 0.4, 1.2})
        for (double cosTheta : {0.99, 0.5, 0.1, -0.05, -0.3}) {
            double sinTheta = std::sqrt(1.0 - cosTheta * cosTheta), axis[3] = {sinTheta, 0.0, cosTheta};
            // Normal +Z; cap about `axis`: integrate max(0, w_z) over the cap in its own polar coordinates.
            const int n = 600;
            double sum = 0.0;
            for (int i = 0; i < n; ++i) {
                double t = sigma * (i + 0.5) / n, st = std::sin(t), ct = std::cos(t);
                for (int j = 0; j < n; ++j) {
                    double p = 2.0 * kPi * (j + 0.5) / n;
                    // w = ct axis + st (cos p e1 + sin p e2), e1 = (cosTheta, 0, -sinTheta), e2 = (0, 1, 0)
                    double wz = ct * axis[2] + st * std::cos(p) * (-sinTheta);
                    sum += std::max(0.0, wz) * st * (sigma / n) * (2.0 * kPi / n);
                }
            }
            double s = std::sin(sigma);
            EXPECT_NEAR(sh::capCosineIntegral(cosTheta, s * s), sum, 2e-4 * std::max(sum, 1e-3))
                << "sigma " << sigma << " cos " << cosTheta;
        }
}
