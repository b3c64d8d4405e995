// Small sources shadowed from their own texels (extractSmallSources, addSourceShadows): what is taken out of the
// map is put back power for power, maps without a dominant small source are left alone, and a sphere occluder
// hides a source texel exactly when the ray toward it meets the sphere.
#include "fiv.h"

#include "scene.h"
#include "sh.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace prt;
using namespace prt::fiv;

namespace {

EnvironmentMap constantMap(int width, float value) {
    EnvironmentMap env;
    env.radiance.width = width, env.radiance.height = width / 2;
    env.radiance.rgb.assign(size_t(width) * (width / 2) * 3, value);
    return env;
}

} // namespace

TEST(FivSources, ASunIsTakenOutWholeAndAConstantMapKeepsEverything) {
    EnvironmentMap env = constantMap(64, 0.1f);
    const size_t sun = 9 * 64 + 40;
    for (int c = 0; c < 3; ++c) env.radiance.rgb[3 * sun + c] = 1e4f * float(c + 1);
    const EnvironmentMap original = env;
    SmallSources sources = extractSmallSources(env);
    ASSERT_EQ(sources.texelCount.size(), 1u);
    EXPECT_EQ(sources.texelCount[0], 1u); // its neighbours are far below 1% of the peak
    EXPECT_GT(sources.powerFraction[0], 0.9);
    std::vector<double> solidAngle = sh::texelSolidAngles(original);
    double d[3];
    sh::equirectDirection(64, 32, 40, 9, d);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(sources.direction[size_t(a)], d[a], 1e-12);
    for (int c = 0; c < 3; ++c) {
        EXPECT_DOUBLE_EQ(sources.power[size_t(c)], 1e4 * (c + 1) * solidAngle[sun]);
        EXPECT_EQ(env.radiance.rgb[3 * sun + c], 0.0f);
    }
    for (size_t t = 0; t < solidAngle.size(); ++t) {
        if (t == sun) continue;
        for (int c = 0; c < 3; ++c) ASSERT_EQ(env.radiance.rgb[3 * t + c], original.radiance.rgb[3 * t + c]);
    }

    EnvironmentMap flat = constantMap(64, 2.0f);
    EXPECT_TRUE(extractSmallSources(flat).direction.empty());
    EXPECT_EQ(flat.radiance.rgb, constantMap(64, 2.0f).radiance.rgb);
}

TEST(FivSources, ASphereHidesASourceTexelExactlyWhenTheRayMeetsIt) {
    TriMesh sphere = makeSphere(1.0f, 48, 96);
    VisibilityOptions options;
    options.grid.azimuth = 16, options.grid.polar = 9, options.grid.shells = 4;
    options.grid.shellMin = 1.2, options.grid.shellMax = 6.0;
    options.cube = 8;
    Visibility vis = sampleVisibility(sphere, options, "sphere");
    CubeEnvironment black;
    black.size = 8;
    black.radiance.assign(3 * 6 * 64, 0.0);
    FivGrid grid = reduceVisibility(vis, black);
    SmallSources sources;
    const double s[3] = {0.48, 0.6, 0.64}; // unit
    sources.direction = {s[0], s[1], s[2]};
    sources.power = {1.0, 2.0, 3.0};
    EXPECT_GT(addSourceShadows(sphere, vis, sources, grid, 2), 0u);
    std::vector<double> radii = shellRadii(options.grid);
    size_t hidden = 0;
    for (size_t row = 0; row < grid.valid.size(); ++row) {
        ASSERT_TRUE(grid.valid[row]);
        int i = int(row % 16), j = int(row / 16 % 9), k = int(row / (16 * 9));
        double d[3];
        gridDirection(options.grid, i, j, d);
        // The receiver point is at -rho R d from the centre; the ray toward s passes the centre at distance
        // |p x s| when it points at it. The tessellated sphere lies within 1e-3 of the unit sphere.
        double rho = radii[size_t(k)] * vis.sphere.radius, p[3] = {-rho * d[0], -rho * d[1], -rho * d[2]};
        double along = -(p[0] * s[0] + p[1] * s[1] + p[2] * s[2]);
        double cross[3] = {p[1] * s[2] - p[2] * s[1], p[2] * s[0] - p[0] * s[2], p[0] * s[1] - p[1] * s[0]};
        double miss = std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
        if (along > 0 && std::abs(miss - 1.0) < 0.01) continue; // grazing: either answer
        bool hit = along > 0 && miss < 1.0;
        hidden += hit;
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(grid.power[3 * row + c], hit ? float(c + 1) : 0.0f) << row;
            for (int a = 0; a < 3; ++a) EXPECT_FLOAT_EQ(grid.fiv[9 * row + 3 * c + a], hit ? float((c + 1) * s[a]) : 0.0f);
        }
    }
    EXPECT_GT(hidden, 20u);
}
