// prt render --background: where the primary ray escapes, the map's radiance along the pixel's ray, turned with the
// lighting, bilinear between texel centres; checked against the conventions' closed form on a ramp map.
#include "render.h"

#include "core.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

// A W x H map whose texel (x, y) holds R = x, G = y, B = 1: bilinear between texel centres gives R = u and G = v
// exactly, (u, v) the continuous texel coordinates of the direction (away from the u seam and the poles).
prt::EnvironmentMap rampMap(int width, int height) {
    prt::EnvironmentMap map;
    map.radiance.width = width;
    map.radiance.height = height;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) map.radiance.rgb.insert(map.radiance.rgb.end(), {float(x), float(y), 1.0f});
    return map;
}

// A unit square at z = 0 facing +Z, seen from (0, 0, 2): the centre of the picture is covered, the corners are not.
prt::TriMesh square() {
    prt::TriMesh mesh;
    mesh.positions = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    return mesh;
}

prt::PinholeCamera camera(std::array<float, 3> target) {
    prt::PinholeCamera c;
    c.eye = {0, 0, 2};
    c.target = target;
    c.fovyDegrees = 60.0f;
    c.width = 40;
    c.height = 30;
    return c;
}

// docs/conventions.md: d = (sin t sin p, cos t, -sin t cos p), u = W (p + pi) / (2 pi), v = H t / pi; texel centres
// at integer + 0.5, so the ramp's bilinear value is u - 0.5 and v - 0.5.
void expectedRamp(const double e[3], int width, int height, double& r, double& g) {
    const double pi = std::numbers::pi;
    double theta = std::acos(e[1]), phi = std::atan2(e[0], -e[2]);
    r = (phi + pi) / (2 * pi) * width - 0.5;
    g = theta / pi * height - 0.5;
}

} // namespace

// Unturned and turned by 90 and -35 degrees: every escaping pixel is the map at R^T d (R about +Y, 90 degrees takes
// +Z to +X); covered pixels and the coverage are untouched.
TEST(RenderBackground, EscapingRaysSeeTheTurnedMapBilinearly) {
    const int W = 64, H = 32;
    prt::EnvironmentMap map = rampMap(W, H);
    for (double degrees : {0.0, 90.0, -35.0}) {
        prt::PinholeCamera c = camera({0.3f, 0.2f, 0.0f});
        std::vector<float> radiance(12, 0.25f);
        prt::RenderedImage image = prt::renderVertexRadiance(square(), radiance, c);
        std::vector<float> coverage = image.coverage;
        prt::drawEnvironmentBackground(image, map, "ramp.exr", c, degrees);
        EXPECT_EQ(image.coverage, coverage);
        prt::PinholeRays rays = prt::pinholeRays(c);
        const double t = degrees * std::numbers::pi / 180.0, cs = std::cos(t), sn = std::sin(t);
        int checked = 0;
        for (size_t p = 0; p < size_t(c.width) * c.height; ++p) {
            const float* rgb = &image.radiance.rgb[p * 3];
            if (coverage[p] != 0.0f) {
                EXPECT_NEAR(rgb[0], 0.25f, 1e-6f); // the surface, as renderVertexRadiance left it
                continue;
            }
            float d[3];
            prt::pinholeRayDirection(rays, p, d);
            // R^T d for R = [[c, 0, s], [0, 1, 0], [-s, 0, c]].
            const double e[3] = {cs * d[0] - sn * d[2], d[1], sn * d[0] + cs * d[2]};
            double r, g;
            expectedRamp(e, W, H, r, g);
            if (r < 0.0 || r > W - 1.0 || g < 0.0 || g > H - 1.0) continue; // across the seam or at a pole
            EXPECT_NEAR(rgb[0], r, 2e-4) << "pixel " << p << " turned " << degrees;
            EXPECT_NEAR(rgb[1], g, 2e-4) << "pixel " << p << " turned " << degrees;
            EXPECT_EQ(rgb[2], 1.0f);
            ++checked;
        }
        EXPECT_GT(checked, 600) << degrees;
    }
}

// Looking straight along -Z at the picture's centre (no mesh): the map's centre column (u = W/2), turned by 90
// degrees the +X direction (u = 3W/4), as conventions.md places them.
TEST(RenderBackground, TheTurnMovesTheMapAsTheLightingTurns) {
    const int W = 64, H = 32;
    prt::EnvironmentMap map = rampMap(W, H);
    prt::TriMesh far = square();
    for (size_t i = 0; i < far.positions.size(); i += 3) far.positions[i + 2] = 50.0f; // behind the eye
    prt::PinholeCamera c = camera({0, 0, 0});
    c.width = c.height = 2; // the four pixels sit symmetrically around -Z
    for (auto [degrees, u] : {std::pair{0.0, 0.5 * W}, std::pair{90.0, 0.75 * W}, std::pair{-90.0, 0.25 * W}}) {
        prt::RenderedImage image = prt::renderVertexRadiance(far, std::vector<float>(12, 0.0f), c);
        prt::drawEnvironmentBackground(image, map, "ramp.exr", c, degrees);
        double mean = 0;
        for (int p = 0; p < 4; ++p) mean += image.radiance.rgb[p * 3] / 4.0;
        EXPECT_NEAR(mean, u - 0.5, 1e-3) << degrees;
    }
}

TEST(RenderBackground, RefusesACubeStrip) {
    prt::EnvironmentMap map = rampMap(8, 48);
    map.layout = prt::EnvLayout::CubeStrip;
    prt::PinholeCamera c = camera({0, 0, 0});
    prt::RenderedImage image = prt::renderVertexRadiance(square(), std::vector<float>(12, 0.0f), c);
    EXPECT_THROW(prt::drawEnvironmentBackground(image, map, "cube.exr", c, 0.0), prt::Error);
}
