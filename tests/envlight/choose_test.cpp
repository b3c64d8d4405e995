// lib/envlight/choose.cpp (decomposeChoosingLights): the chooser's decision, K and residual order, on synthetic maps
// whose answer is known.
#include "envlight_maps.h"

#include "core.h"

#include <gtest/gtest.h>

using namespace envlight_test;
namespace el = prt::envlight;

namespace {

el::Options fastOptions() {
    el::Options options;
    options.icosphereLevel = 5; // ~2 degrees apart: enough for 1.5-degree discs, and fast
    options.maxLights = 16;
    return options;
}

// The share of the map's luminance power inside the disc around `direction` of half-angle `radiusDegrees`.
double powerShare(const prt::EnvironmentMap& env, const std::array<double, 3>& direction, double radiusDegrees) {
    el::Texels texels = el::environmentTexels(env, nullptr);
    double inside = 0.0, total = 0.0, cosRadius = std::cos(radiusDegrees * M_PI / 180.0);
    for (size_t i = 0; i < texels.count(); ++i) {
        const float* c = &texels.rgb[i * 3];
        double power = (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) * texels.solidAngles[i];
        const double* d = &texels.directions[i * 3];
        if (d[0] * direction[0] + d[1] * direction[1] + d[2] * direction[2] >= cosRadius) inside += power;
        total += power;
    }
    return inside / total;
}

// A unit background and one 1.5-degree disc holding about half the power (4 pi / solid angle of the disc).
prt::EnvironmentMap halfPowerSun() {
    return discMap(256, 1.0, {{unit(0.3, 0.7, -0.5), 1.5, {5800.0, 5800.0, 5800.0}}});
}

} // namespace

TEST(ChooseConfiguration, ATinyDiscHoldingHalfThePowerGetsLightsAndTheOrder8Residual) {
    prt::EnvironmentMap sun = halfPowerSun();
    double share = powerShare(sun, unit(0.3, 0.7, -0.5), 2.5);
    ASSERT_GT(share, 0.4);
    ASSERT_LT(share, 0.6);
    el::Options options = fastOptions();
    options.order = 5;
    el::LightChoice choice;
    el::Decomposition d = el::decomposeChoosingLights(sun, options, el::ChoiceOptions{}, &choice);
    EXPECT_FALSE(choice.plainSh) << choice.reason;
    EXPECT_GE(choice.lights, 1);
    EXPECT_EQ(d.lights.size(), size_t(choice.lights));
    // Tried: the asked order and the plain order. The light leaves the same high bands either way, and the order-8
    // residual says bands 5..7 exactly, so order 8 leaves less.
    ASSERT_EQ(choice.orders, (std::vector<int>{5, 8}));
    EXPECT_EQ(choice.order, 8);
    EXPECT_EQ(d.order, 8);
    EXPECT_EQ(d.residual.size(), size_t(64 * 3));
    EXPECT_LT(choice.errorsByOrder[1][1], choice.errorsByOrder[0][1]);
    EXPECT_LT(choice.errors[size_t(choice.lights)], 0.5 * choice.plainError);
    // The choice is the least error over every (order, k >= 1).
    for (const std::vector<double>& errors : choice.errorsByOrder)
        for (size_t k = 1; k < errors.size(); ++k) EXPECT_LE(choice.errors[size_t(choice.lights)], errors[k]);
    // The brightest light is the disc.
    const el::ConeLight& light = d.lights[0];
    std::array<double, 3> u = unit(0.3, 0.7, -0.5);
    EXPECT_GT(light.direction[0] * u[0] + light.direction[1] * u[1] + light.direction[2] * u[2], std::cos(M_PI / 90.0));
}

TEST(ChooseConfiguration, OnlyTheAskedResidualOrderWhenTold) {
    el::Options options = fastOptions();
    options.order = 5;
    el::ChoiceOptions only5;
    only5.residualOrders = {5};
    el::LightChoice choice;
    el::Decomposition d = el::decomposeChoosingLights(halfPowerSun(), options, only5, &choice);
    EXPECT_FALSE(choice.plainSh) << choice.reason;
    EXPECT_EQ(choice.orders, (std::vector<int>{5}));
    EXPECT_EQ(choice.order, 5);
    EXPECT_EQ(d.order, 5);
    EXPECT_EQ(d.residual.size(), size_t(25 * 3));
}

TEST(ChooseConfiguration, ASmoothMapFallsBackToPlainSHAtThePlainOrder) {
    // A constant plus a gentle 40-degree disc: no light is found at either order, so plain order 8.
    prt::EnvironmentMap smooth = discMap(256, 1.0, {{unit(0.2, 0.9, 0.1), 40.0, {0.3, 0.3, 0.3}}});
    el::Options options = fastOptions();
    options.order = 5;
    el::LightChoice choice;
    el::Decomposition d = el::decomposeChoosingLights(smooth, options, el::ChoiceOptions{}, &choice);
    EXPECT_TRUE(choice.plainSh) << choice.reason;
    EXPECT_EQ(choice.lights, 0);
    EXPECT_EQ(choice.order, 8);
    EXPECT_TRUE(d.lights.empty());
    EXPECT_EQ(d.order, 8);
    // With no lights the residual is the plain projection at order 8.
    std::vector<double> plain = el::projectTexels(el::environmentTexels(smooth, nullptr), 8);
    ASSERT_EQ(d.residual.size(), plain.size());
    for (size_t j = 0; j < plain.size(); ++j) EXPECT_NEAR(d.residual[j], plain[j], 1e-9 * std::abs(plain[0]));
    EXPECT_NE(choice.reason.find("do not pay"), std::string::npos);
}

TEST(ChooseConfiguration, RejectsResidualOrdersOutsideTheErrorOrder) {
    el::ChoiceOptions bad;
    bad.residualOrders = {5, 32};
    EXPECT_THROW(el::decomposeChoosingLights(halfPowerSun(), fastOptions(), bad, nullptr), prt::Error);
    bad.residualOrders = {0};
    EXPECT_THROW(el::decomposeChoosingLights(halfPowerSun(), fastOptions(), bad, nullptr), prt::Error);
}
