// The nested fit's lighting prior (lib/glossy/lighting_prior.cpp): where a training map's light lands on the
// held-out directions, and what it refuses.
#include "glossy.h"

#include "core.h"
#include "image.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

using namespace prt;

namespace {

EnvironmentMap equirect(int width, int height, float value) {
    EnvironmentMap env;
    env.radiance.width = width, env.radiance.height = height;
    env.radiance.rgb.assign(size_t(width) * height * 3, value);
    return env;
}

} // namespace

// A constant map spreads over every direction: each turn's row sums to 1 and each direction's share is about its
// cell's solid angle over 4 pi (the held-out cube grid's cells differ by at most a few times in size).
TEST(GlossyLightingPrior, ConstantMapRowsSumToOneAndCoverTheSphere) {
    const glossy::DirectionGrid held = glossy::heldOutGrid(8);
    std::vector<float> rows = glossy::lightingPrior(equirect(256, 128, 2.0f), "constant", held, 3);
    ASSERT_EQ(rows.size(), 3 * held.count());
    for (int r = 0; r < 3; ++r) {
        const float* row = &rows[r * held.count()];
        EXPECT_NEAR(std::accumulate(row, row + held.count(), 0.0), 1.0, 1e-5);
        for (size_t i = 0; i < held.count(); ++i) {
            EXPECT_GT(row[i], 0.1 / double(held.count())) << "direction " << i;
            EXPECT_LT(row[i], 10.0 / double(held.count())) << "direction " << i;
        }
    }
}

// Light only in the top texel row (within 0.7 degree of +y) lands only on held-out directions near +y, at every
// turn about y (which leaves +y where it is).
TEST(GlossyLightingPrior, LightAtThePoleStaysAtThePoleUnderEveryTurn) {
    const glossy::DirectionGrid held = glossy::heldOutGrid(8);
    EnvironmentMap env = equirect(256, 128, 0.0f);
    for (int x = 0; x < 256; ++x) env.radiance.rgb[size_t(x) * 3 + 1] = 5.0f;
    std::vector<float> rows = glossy::lightingPrior(env, "pole", held, 4);
    for (int r = 0; r < 4; ++r)
        for (size_t i = 0; i < held.count(); ++i)
            if (rows[r * held.count() + i] > 0.0f) {
                EXPECT_GT(held.directions[i * 3 + 1], 0.9f) << "turn " << r << ", direction " << i;
            }
}

TEST(GlossyLightingPrior, RefusesBlackAndNarrowMapsNamingTheFile) {
    const glossy::DirectionGrid held = glossy::heldOutGrid(4);
    try {
        glossy::lightingPrior(equirect(256, 128, 0.0f), "black.exr", held, 1);
        FAIL() << "a black map was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("black.exr"), std::string::npos) << e.what();
    }
    EXPECT_THROW(glossy::lightingPrior(equirect(64, 32, 1.0f), "narrow.exr", held, 1), Error);
}
