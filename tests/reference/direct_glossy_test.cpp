// The exact glossy oracle (referenceDirectRadiance with a Phong lobe, `prt reference --brute-force --brdf`):
// against the normalised lobe's closed form on an unoccluded sphere, and against the Monte Carlo glossy
// reference within its quoted noise where the mesh shadows itself.
#include "reference.h"

#include "core.h"
#include "scene.h"
#include "sh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace {

using prt::EnvironmentMap;
const std::vector<prt::DirectOccluder> kNone;

// An equirectangular map of width x width/2 texels whose radiance at texel-centre direction d is radiance(d).
template <typename Radiance>
EnvironmentMap equirectMap(int width, const Radiance& radiance) {
    EnvironmentMap env;
    env.layout = prt::EnvLayout::Equirectangular;
    env.radiance.width = width;
    env.radiance.height = width / 2;
    for (int y = 0; y < env.radiance.height; ++y)
        for (int x = 0; x < width; ++x) {
            double d[3];
            prt::sh::equirectDirection(width, width / 2, x, y, d);
            std::array<float, 3> rgb = radiance(d);
            env.radiance.rgb.insert(env.radiance.rgb.end(), rgb.begin(), rgb.end());
        }
    return env;
}

double cosineToEye(const prt::TriMesh& mesh, size_t v, const std::array<float, 3>& eye) {
    double o[3], length = 0.0, dot = 0.0;
    for (int c = 0; c < 3; ++c) o[c] = eye[size_t(c)] - mesh.positions[v * 3 + c], length += o[c] * o[c];
    double n = std::sqrt(mesh.normals[v * 3] * mesh.normals[v * 3] + mesh.normals[v * 3 + 1] * mesh.normals[v * 3 + 1] +
                         mesh.normals[v * 3 + 2] * mesh.normals[v * 3 + 2]);
    for (int c = 0; c < 3; ++c) dot += o[c] * mesh.normals[v * 3 + c];
    return dot / std::sqrt(length) / n;
}

// Constant radiance L on a convex sphere, nothing blocked. The normalised lobe integrates to
// ks (n + 2) / (2 pi) int cos^n(r . w) (N . w) dw = ks (N . r) = ks cos(theta_o) wherever the horizon clips none of
// it (theta_o <= 30 deg leaves cos^33(60 deg) < 1e-9 of it below), so each such vertex returns
// L (albedo + ks cos theta_o); a vertex that faces away from the eye returns L albedo.
TEST(ReferenceDirectGlossy, UnoccludedSphereMatchesTheNormalisedLobesClosedForm) {
    const std::array<float, 3> radiance = {1.0f, 0.5f, 0.25f};
    EnvironmentMap env = equirectMap(256, [&](const double*) { return radiance; });
    prt::TriMesh sphere = prt::makeSphere(1.0f, 12, 24);
    prt::DirectOptions options;
    options.albedo = std::array<float, 3>{0.5f, 0.5f, 0.5f};
    options.phong = prt::PhongBrdf{32.0, 0.5};
    options.eye = std::array<float, 3>{0.0f, 20.0f, 0.0f};
    prt::ReferenceRadiance result = prt::referenceDirectRadiance(sphere, kNone, env, options);
    ASSERT_EQ(result.radiance.size(), 3 * sphere.vertexCount());
    int inside = 0, away = 0;
    for (size_t v = 0; v < sphere.vertexCount(); ++v) {
        double cosOut = cosineToEye(sphere, v, *options.eye);
        double lobe = 0.0;
        if (cosOut >= std::cos(30.0 * 3.14159265358979 / 180.0)) lobe = 0.5 * cosOut, ++inside;
        else if (cosOut <= 0.0) ++away;
        else continue;
        for (int c = 0; c < 3; ++c) {
            double expected = radiance[size_t(c)] * (0.5 + lobe);
            EXPECT_NEAR(result.radiance[v * 3 + c], expected, 3e-3 * expected) << v << " " << c;
            EXPECT_EQ(result.standardError[v * 3 + c], 0.0f);
        }
    }
    EXPECT_GT(inside, 20);
    EXPECT_GT(away, 100);
    // The glossy part alone (albedo 0) at the north pole, which faces the eye: exactly ks L.
    options.albedo = std::array<float, 3>{0.0f, 0.0f, 0.0f};
    prt::ReferenceRadiance glossy = prt::referenceDirectRadiance(sphere, kNone, env, options);
    EXPECT_NEAR(glossy.radiance[0], 0.5, 1e-3);
    // A glossy BRDF needs the eye.
    options.eye.reset();
    EXPECT_THROW(prt::referenceDirectRadiance(sphere, kNone, env, options), prt::Error);
}

// Where the mesh shadows itself (an open cavity) under a non-constant map, the oracle agrees with the unbiased
// Monte Carlo glossy reference (bounces 0) within the reference's quoted standard error: z-scores of about unit
// mean square and none past 5. The two differ only in that the oracle evaluates the BRDF at texel centres
// (relative bias about (texel / lobe width)^2 / 24, 0.2% here), so a slack of 0.5% of the value is allowed.
TEST(ReferenceDirectGlossy, AgreesWithTheMonteCarloReferenceWithinItsNoise) {
    const double sun[3] = {0.3, 0.9, 0.3};
    const double sunLength = std::sqrt(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2]);
    EnvironmentMap env = equirectMap(128, [&](const double* d) {
        double c = std::max(0.0, (d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2]) / sunLength);
        float value = float(0.3 + 0.4 * (d[1] + 1.0) + 4.0 * std::pow(c, 8.0));
        return std::array<float, 3>{value, 0.8f * value, 0.6f * value};
    });
    prt::TriMesh cavity = prt::makeOpenCavity(1.0f, 0.9f, 6, 12);
    const std::array<float, 3> eye = {0.5f, 6.0f, 1.0f};
    prt::DirectOptions direct;
    direct.albedo = std::array<float, 3>{0.3f, 0.3f, 0.3f};
    direct.phong = prt::PhongBrdf{16.0, 0.5};
    direct.eye = eye;
    prt::ReferenceRadiance exact = prt::referenceDirectRadiance(cavity, kNone, env, direct);
    prt::ReferenceOptions mc;
    mc.samples = 512;
    mc.albedo = direct.albedo;
    mc.phong = direct.phong;
    mc.eye = eye;
    prt::ReferenceRadiance noisy = prt::referenceVertexRadiance(cavity, env, mc);
    double meanSquare = 0.0, worst = 0.0, glossyShare = 0.0;
    size_t lit = 0;
    direct.albedo = std::array<float, 3>{0.0f, 0.0f, 0.0f};
    prt::ReferenceRadiance glossyOnly = prt::referenceDirectRadiance(cavity, kNone, env, direct);
    for (size_t i = 0; i < exact.radiance.size(); ++i) {
        if (!(noisy.standardError[i] > 0.0f)) {
            EXPECT_NEAR(exact.radiance[i], noisy.radiance[i], 1e-6) << i;
            continue;
        }
        double z = (noisy.radiance[i] - exact.radiance[i]) / (noisy.standardError[i] + 5e-3 * exact.radiance[i]);
        meanSquare += z * z, worst = std::max(worst, std::abs(z)), ++lit;
        glossyShare += glossyOnly.radiance[i] / std::max(1e-12f, exact.radiance[i]);
    }
    ASSERT_GT(lit, 100u);
    meanSquare /= double(lit);
    EXPECT_LT(meanSquare, 1.5);
    EXPECT_GT(meanSquare, 0.3);
    EXPECT_LT(worst, 5.0);
    // The case exercises the lobe: on average it carries a good share of the light.
    EXPECT_GT(glossyShare / double(lit), 0.1);
}

} // namespace
