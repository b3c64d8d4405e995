// lib/envlight's coherence (decomposeCoherent) and K choice (decomposeChoosingLights) on closed-form maps.
#include "envlight_maps.h"

#include "core.h"

#include <gtest/gtest.h>

#include <cstdio>

using namespace envlight_test;
namespace el = prt::envlight;

namespace {

el::Options smallOptions() {
    el::Options options;
    options.icosphereLevel = 5; // ~2 degrees apart: enough for 3-degree discs, and fast
    return options;
}

// Asserts residual + lights == the map's projection: against the projection decomposeCoherent reports (one
// rounding), and that projection against an independent projection of the turned texels.
void expectEnergyIdentity(const el::Decomposition& d, const prt::EnvironmentMap& env, const double* R, int order) {
    std::vector<double> lit = el::lightsProjection(d.lights, order);
    std::vector<double> direct = el::projectTexels(el::environmentTexels(env, R), order);
    ASSERT_EQ(d.projection.size(), direct.size());
    double scale = std::abs(direct[0]);
    for (size_t j = 0; j < direct.size(); ++j) {
        EXPECT_NEAR(d.residual[j] + lit[j], d.projection[j], 1e-13 * scale) << j;
        EXPECT_NEAR(d.projection[j], direct[j], 1e-9 * scale) << j;
    }
}

} // namespace

TEST(Coherence, TwoComparableSunsNearTheThresholdDoNotFlicker) {
    // Two suns of nearly equal power and a weak disc at the elbow threshold (its share of the running total is
    // about 0.05), turned in 1-degree steps while their radiances flicker every other frame (one sun by 10-30%, the weak disc by 15%) every other frame (as a
    // captured sky's would): decomposed afresh, the lead light swaps between the suns (K = 1) and the weak disc
    // comes and goes (K = 3). The coherent decomposition keeps its count, its slots and their suns every frame.
    auto frameMap = [](int frame, double sunFlicker) {
        double flicker = frame % 2 ? -1.0 : 1.0; // bright on even frames, from the first
        Disc a{unit(0.6, 0.5, -0.6), 3.0, {60.0, 60.0, 60.0}};
        Disc b{unit(-0.6, 0.45, 0.6), 3.0, {60.0 * (1.0 + sunFlicker * flicker), 60.0 * (1.0 + sunFlicker * flicker), 60.0 * (1.0 + sunFlicker * flicker)}};
        double weak = 6.3 * (1.0 + 0.15 * flicker);
        Disc c{unit(0.1, -0.3, 0.9), 3.0, {weak, weak, weak}};
        return discMap(256, 0.5, {a, b, c});
    };
    const int frames = 8;
    for (int K : {1, 3}) {
        // K = 1: the suns flicker by 30%, so that afresh the lead light swaps; K = 3: by 10%, so that the weak
        // disc's share crosses the threshold while the suns stay ahead of it.
        const double sunFlicker = K == 1 ? 0.3 : 0.1;
        const prt::EnvironmentMap maps[2] = {frameMap(0, sunFlicker), frameMap(1, sunFlicker)};
        el::Options options = smallOptions();
        options.maxLights = K;
        el::CoherenceState state;
        int freshChanges = 0;
        size_t count = 0;
        el::Decomposition previousFresh;
        std::vector<std::array<double, 3>> previous;
        for (int frame = 0; frame < frames; ++frame) {
            double R[9];
            prt::sh::rotationY(frame * 1.0, R);
            options.rotation = R;
            const prt::EnvironmentMap& env = maps[frame % 2];
            el::Decomposition fresh = el::decompose(env, options);
            if (frame > 0 && (fresh.lights.size() != previousFresh.lights.size() ||
                              angleDegrees(fresh.lights[0].direction, previousFresh.lights[0].direction) > 1.5))
                ++freshChanges;
            previousFresh = fresh;

            el::Decomposition d = el::decomposeCoherent(env, options, el::CoherenceOptions{}, state);
            if (frame == 0) count = d.lights.size();
            ASSERT_EQ(d.lights.size(), count) << "K " << K << " frame " << frame; // K never flickers
            ASSERT_EQ(d.weights.size(), count);
            EXPECT_LE(count, size_t(K));
            EXPECT_GE(count, 1u);
            for (size_t s = 0; s < count; ++s) {
                EXPECT_EQ(d.weights[s], 1.0);
                // Slot s follows one sun: a 1-degree turn moves it by at most 1 degree.
                if (frame > 0) {
                    EXPECT_LT(angleDegrees(d.lights[s].direction, previous[s]), 1.5) << s << " " << frame;
                }
            }
            expectEnergyIdentity(d, env, R, options.order);
            previous.clear();
            for (const auto& l : d.lights) previous.push_back(l.direction);
        }
        // The case is hard: afresh, the count or the lead light changes (else this test would prove nothing).
        EXPECT_GT(freshChanges, 0) << "K " << K;
    }
}

TEST(Coherence, ALeavingLightFadesIntoTheResidual) {
    // A held light where the map has none: no slot match, so it keeps its place and loses 1/fadeFrames of its
    // weight per frame, then frees the slot; the residual takes exactly what it loses.
    prt::EnvironmentMap env = discMap(128, 2.0, {});
    el::Options options = smallOptions();
    el::CoherenceOptions coherence;
    coherence.fadeFrames = 4;
    el::CoherenceState state;
    state.started = true;
    state.lights.push_back({unit(0, 1, 0), {10.0, 20.0, 30.0}, 0.05});
    state.weights.push_back(1.0);
    for (int frame = 1; frame <= 4; ++frame) {
        el::Decomposition d = el::decomposeCoherent(env, options, coherence, state);
        if (frame < 4) {
            ASSERT_EQ(d.lights.size(), 1u);
            EXPECT_DOUBLE_EQ(d.weights[0], 1.0 - 0.25 * frame);
            EXPECT_DOUBLE_EQ(d.lights[0].radiance[1], 20.0 * (1.0 - 0.25 * frame));
        } else {
            EXPECT_TRUE(d.lights.empty());
            EXPECT_TRUE(state.lights.empty());
        }
        expectEnergyIdentity(d, env, nullptr, options.order);
        // The DC carries the constant map minus the fading light's energy, per channel.
        double solidAngle = el::coneSolidAngle(0.05);
        for (int c = 0; c < 3; ++c) {
            double lightEnergy = d.lights.empty() ? 0.0 : d.lights[0].radiance[c] * solidAngle;
            EXPECT_NEAR(d.residual[c] * std::sqrt(4.0 * M_PI) + lightEnergy, 2.0 * 4.0 * M_PI, 1e-6);
        }
    }
}

TEST(Coherence, BadOptionsAreUsageErrors) {
    prt::EnvironmentMap env = discMap(64, 1.0, {});
    el::CoherenceState state;
    el::CoherenceOptions bad;
    bad.fadeFrames = 0;
    EXPECT_THROW(el::decomposeCoherent(env, smallOptions(), bad, state), prt::Error);
    state.lights.resize(1); // weights missing
    EXPECT_THROW(el::decomposeCoherent(env, smallOptions(), el::CoherenceOptions{}, state), prt::Error);
}

TEST(ChooseLights, NoLightOnASmoothMapAtLeastOneOnASunMap) {
    el::Options options = smallOptions();
    options.maxLights = 16;
    // Smooth: a constant plus a broad 10-degree disc of low contrast; a cone buys nothing plain order 8 lacks.
    prt::EnvironmentMap smooth = discMap(256, 1.0, {{unit(0.2, 0.9, 0.1), 40.0, {0.3, 0.3, 0.3}}});
    el::LightChoice choice;
    el::Decomposition d = el::decomposeChoosingLights(smooth, options, el::ChoiceOptions{}, &choice);
    EXPECT_TRUE(choice.plainSh) << choice.reason;
    EXPECT_EQ(choice.lights, 0);
    EXPECT_TRUE(d.lights.empty());
    EXPECT_NE(choice.reason.find("do not pay"), std::string::npos);
    // Sun: a 1.5-degree disc holding most of the power.
    prt::EnvironmentMap sun = discMap(256, 0.5, {{unit(0.5, 0.6, -0.6), 1.5, {3000.0, 2800.0, 2500.0}}});
    d = el::decomposeChoosingLights(sun, options, el::ChoiceOptions{}, &choice);
    EXPECT_FALSE(choice.plainSh) << choice.reason;
    EXPECT_GE(choice.lights, 1);
    EXPECT_EQ(d.lights.size(), size_t(choice.lights));
    EXPECT_LT(choice.errors[size_t(choice.lights)], 0.5 * choice.plainError);
    EXPECT_EQ(choice.errors.size(), 2u); // k = 0 and the one light found
}
