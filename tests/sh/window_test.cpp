// Band windows, band energy and window names.
#include "sh.h"

#include "core.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace prt::sh;

TEST(ShWindow, WeightsFollowTheirFormulas) {
    const int order = 5;
    for (int l = 0; l < order; ++l) {
        double angle = std::numbers::pi * l / order;
        EXPECT_EQ(windowWeight(Window::None, l, order), 1.0);
        EXPECT_NEAR(windowWeight(Window::Hann, l, order), 0.5 * (1 + std::cos(angle)), 1e-15);
        EXPECT_NEAR(windowWeight(Window::Lanczos, l, order), l == 0 ? 1.0 : std::sin(angle) / angle, 1e-15);
    }
    EXPECT_EQ(windowWeight(Window::Hann, 0, order), 1.0);
    EXPECT_NEAR(windowWeight(Window::Hann, order, order), 0.0, 1e-15);
}

TEST(ShWindow, ApplyScalesEachBandAndEnergySumsIt) {
    const int order = 3;
    std::vector<float> coeffs(coefficientCount(order) * 3, 1.0f);
    coeffs[index(1, 0) * 3 + 2] = 2.0f;
    applyWindow(Window::Hann, order, coeffs.data(), 3);
    float w1 = float(windowWeight(Window::Hann, 1, order)), w2 = float(windowWeight(Window::Hann, 2, order));
    EXPECT_EQ(coeffs[0], 1.0f);
    EXPECT_EQ(coeffs[index(1, -1) * 3], w1);
    EXPECT_EQ(coeffs[index(1, 0) * 3 + 2], 2.0f * w1);
    EXPECT_EQ(coeffs[index(2, 2) * 3 + 1], w2);

    std::vector<double> energy = bandEnergy(order, coeffs.data(), 3);
    ASSERT_EQ(energy.size(), 3u);
    EXPECT_NEAR(energy[0], 3.0, 1e-12);
    EXPECT_NEAR(energy[1], (8.0 + 4.0) * double(w1) * w1, 1e-6);
    EXPECT_NEAR(energy[2], 15.0 * double(w2) * w2, 1e-6);
}

TEST(ShWindow, NamesRoundTripAndUnknownIsAUsageError) {
    for (Window window : {Window::None, Window::Hann, Window::Lanczos})
        EXPECT_EQ(parseWindow(windowName(window)), window);
    try {
        parseWindow("gauss");
        FAIL() << "no error";
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.exitCode(), prt::kExitUsage);
        EXPECT_NE(std::string(e.what()).find("gauss"), std::string::npos);
    }
}
