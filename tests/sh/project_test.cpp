// Environment projection: texel directions and solid angles, constant and band-limited environments,
// determinism across thread counts, irradiance.
#include "helpers.h"

#include <OpenEXR/ImfEnvmap.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

using namespace prt::sh;
using namespace prt::sh::test;

namespace {

const double kPi = std::numbers::pi;

prt::EnvironmentMap makeEnvironment(prt::EnvLayout layout, int width, int height) {
    prt::EnvironmentMap env;
    env.layout = layout;
    env.radiance.width = width;
    env.radiance.height = height;
    env.radiance.rgb.assign(size_t(width) * height * 3, 0.0f);
    return env;
}

void direction(const prt::EnvironmentMap& env, int x, int y, double d[3]) {
    if (env.layout == prt::EnvLayout::Equirectangular)
        equirectDirection(env.radiance.width, env.radiance.height, x, y, d);
    else
        cubeStripDirection(env.radiance.width, x, y, d);
}

// Fills every texel with sum_i c[i][channel] Y_i(d) at the texel's direction.
void fillFromCoefficients(prt::EnvironmentMap& env, int order, const std::vector<double>& rgbCoeffs) {
    std::vector<double> basis(coefficientCount(order));
    for (int y = 0; y < env.radiance.height; ++y)
        for (int x = 0; x < env.radiance.width; ++x) {
            double d[3];
            direction(env, x, y, d);
            evaluate(order, d[0], d[1], d[2], basis.data());
            for (int c = 0; c < 3; ++c) {
                double value = 0.0;
                for (int i = 0; i < coefficientCount(order); ++i) value += rgbCoeffs[i * 3 + c] * basis[i];
                env.radiance.rgb[(size_t(y) * env.radiance.width + x) * 3 + c] = float(value);
            }
        }
}

void expectNear(const double* d, double x, double y, double z) {
    EXPECT_NEAR(d[0], x, 1e-12);
    EXPECT_NEAR(d[1], y, 1e-12);
    EXPECT_NEAR(d[2], z, 1e-12);
}

} // namespace

TEST(ShProject, EquirectDirectionsFollowTheConvention) {
    const int W = 8, H = 4; // pixel centres sit exactly on the axes at these positions
    double d[3];
    equirectDirection(W, H, W / 2 - 0.5, H / 2 - 0.5, d); // image centre
    expectNear(d, 0, 0, -1);
    equirectDirection(W, H, 3 * W / 4 - 0.5, H / 2 - 0.5, d); // right half
    expectNear(d, 1, 0, 0);
    equirectDirection(W, H, W / 4 - 0.5, H / 2 - 0.5, d);
    expectNear(d, -1, 0, 0);
    equirectDirection(W, H, -0.5, H / 2 - 0.5, d); // left edge
    expectNear(d, 0, 0, 1);
    equirectDirection(W, H, 0, -0.5, d); // top edge
    expectNear(d, 0, 1, 0);
}

// OpenEXR's own cube-map functions must find every texel of our strip where we put it. OpenEXR spreads texel
// centres from edge to edge (scale (S-1)/S), so positions agree to within half a texel; a flipped axis would not.
TEST(ShProject, CubeStripDirectionsMatchOpenExrLayout) {
    const int S = 8;
    IMATH_NAMESPACE::Box2i window(IMATH_NAMESPACE::V2i(0, 0), IMATH_NAMESPACE::V2i(S - 1, 6 * S - 1));
    for (int y = 0; y < 6 * S; ++y)
        for (int x = 0; x < S; ++x) {
            double d[3];
            cubeStripDirection(S, x, y, d);
            EXPECT_NEAR(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], 1.0, 1e-14);
            Imf::CubeMapFace face;
            IMATH_NAMESPACE::V2f inFace;
            Imf::CubeMap::faceAndPixelPosition(IMATH_NAMESPACE::V3f(float(d[0]), float(d[1]), float(d[2])), window,
                                               face, inFace);
            IMATH_NAMESPACE::V2f position = Imf::CubeMap::pixelPosition(face, window, inFace);
            EXPECT_EQ(int(face), y / S) << x << " " << y;
            EXPECT_LE(std::abs(position.x - x), 0.5f + 1e-4f) << x << " " << y;
            EXPECT_LE(std::abs(position.y - y), 0.5f + 1e-4f) << x << " " << y;
        }
}

// Sub-texel positions stay in their texel's face: half a texel above face 1's first row is still face 1 (-X).
TEST(ShProject, CubeStripSubTexelPositionsKeepTheirFace) {
    const int S = 4;
    double d[3];
    cubeStripDirection(S, 1.0, S - 0.45, d);
    EXPECT_LT(d[0], 0.0);
    EXPECT_GT(std::abs(d[0]), std::abs(d[1]));
    EXPECT_GT(std::abs(d[0]), std::abs(d[2]));
    cubeStripDirection(S, 1.0, S - 0.55, d); // last row of face 0 (+X)
    EXPECT_GT(d[0], 0.0);
}

TEST(ShProject, SolidAnglesSumToFourPi) {
    for (auto [layout, width, height] : {std::tuple{prt::EnvLayout::Equirectangular, 2, 1},
                                         std::tuple{prt::EnvLayout::Equirectangular, 1024, 512},
                                         std::tuple{prt::EnvLayout::CubeStrip, 1, 6},
                                         std::tuple{prt::EnvLayout::CubeStrip, 33, 198}}) {
        std::vector<double> solidAngle = texelSolidAngles(makeEnvironment(layout, width, height));
        ASSERT_EQ(solidAngle.size(), size_t(width) * height);
        double sum = 0.0;
        for (double omega : solidAngle) {
            EXPECT_GT(omega, 0.0);
            sum += omega;
        }
        EXPECT_NEAR(sum, 4 * kPi, 1e-10) << width << "x" << height;
    }
    // A one-texel face sees a sixth of the sphere; a 2x1 equirect pixel sees a hemisphere.
    EXPECT_NEAR(texelSolidAngles(makeEnvironment(prt::EnvLayout::CubeStrip, 1, 6))[3], 4 * kPi / 6, 1e-14);
    EXPECT_NEAR(texelSolidAngles(makeEnvironment(prt::EnvLayout::Equirectangular, 2, 1))[0], 2 * kPi, 1e-14);
}

// Exact solid angles make the DC term exact; higher terms are off only by the texel-centre rule's O(texel^2)
// error, which the cube's l=4 harmonic (cubic symmetry) shows most.
TEST(ShProject, ConstantRadianceGivesOnlyTheDcTerm) {
    const float radiance[3] = {1.5f, 0.25f, 3.0f};
    const int order = 6;
    for (auto [layout, width, height, tolerance] : {std::tuple{prt::EnvLayout::Equirectangular, 1024, 512, 1e-5},
                                                    std::tuple{prt::EnvLayout::CubeStrip, 128, 768, 1e-4}}) {
        prt::EnvironmentMap env = makeEnvironment(layout, width, height);
        for (size_t t = 0; t < env.radiance.rgb.size(); ++t) env.radiance.rgb[t] = radiance[t % 3];
        std::vector<float> coeffs = projectEnvironment(env, order);
        ASSERT_EQ(coeffs.size(), size_t(coefficientCount(order)) * 3);
        for (int c = 0; c < 3; ++c) {
            double dc = radiance[c] * std::sqrt(4 * kPi);
            EXPECT_NEAR(coeffs[c], dc, 1e-6 * dc);
            for (int i = 1; i < coefficientCount(order); ++i) EXPECT_NEAR(coeffs[i * 3 + c], 0.0, tolerance * dc) << i;
        }
    }
}

TEST(ShProject, BandLimitedEnvironmentProjectsBackToItsCoefficients) {
    const int order = 5, count = coefficientCount(order);
    std::mt19937 rng(31);
    std::vector<double> rgbCoeffs = randomCoefficients(rng, count * 3);
    for (int c = 0; c < 3; ++c) rgbCoeffs[c] = 4.0; // keeps the function mostly positive; sign does not matter here
    for (auto [layout, width, height] : {std::tuple{prt::EnvLayout::Equirectangular, 1024, 512},
                                         std::tuple{prt::EnvLayout::CubeStrip, 128, 768}}) {
        prt::EnvironmentMap env = makeEnvironment(layout, width, height);
        fillFromCoefficients(env, order, rgbCoeffs);
        std::vector<float> coeffs = projectEnvironment(env, order);
        for (int i = 0; i < count * 3; ++i) EXPECT_NEAR(coeffs[i], rgbCoeffs[i], 2e-4) << i;
    }
}

TEST(ShProject, IdenticalBitsForAnyThreadCount) {
    const int order = 8;
    prt::EnvironmentMap env = makeEnvironment(prt::EnvLayout::Equirectangular, 256, 128);
    std::mt19937 rng(37);
    std::uniform_real_distribution<float> uniform(0.0f, 10.0f);
    for (float& v : env.radiance.rgb) v = uniform(rng);
    std::vector<float> single, many;
    single = projectEnvironment(env, order, 1);
    many = projectEnvironment(env, order, 8);
    ASSERT_EQ(single.size(), many.size());
    EXPECT_EQ(std::memcmp(single.data(), many.data(), single.size() * sizeof(float)), 0);
}

// Constant radiance L gives irradiance pi L for every normal; a pure l=1 lighting gives (2 pi / 3) L_1m Y_1m(n).
TEST(ShProject, IrradianceAppliesClampedCosine) {
    const int order = 3;
    std::vector<float> coeffs(coefficientCount(order) * 3, 0.0f);
    for (int c = 0; c < 3; ++c) coeffs[c] = float((c + 1) * std::sqrt(4 * kPi));
    std::mt19937 rng(41);
    for (int trial = 0; trial < 10; ++trial) {
        double n[3], E[3];
        randomUnit(rng, n);
        irradiance(order, coeffs.data(), n, E);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(E[c], kPi * (c + 1), 1e-5);
    }
    std::fill(coeffs.begin(), coeffs.end(), 0.0f);
    coeffs[index(1, 0) * 3] = 1.0f;
    const double up[3] = {0, 0, 1};
    double E[3];
    irradiance(order, coeffs.data(), up, E);
    EXPECT_NEAR(E[0], 2 * kPi / 3 * std::sqrt(3 / (4 * kPi)), 1e-6);
}
