#include "reference.h"

#include "core.h"
#include "path_tracer.h"
#include "scene.h"
#include "sh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <vector>

namespace {

using prt::EnvironmentMap;
using prt::EnvLayout;

EnvironmentMap constantEnvironment(const float radiance[3], int width = 64,
                                   EnvLayout layout = EnvLayout::Equirectangular) {
    EnvironmentMap env;
    env.layout = layout;
    env.radiance.width = width;
    env.radiance.height = layout == EnvLayout::Equirectangular ? width / 2 : 6 * width;
    size_t texels = size_t(env.radiance.width) * env.radiance.height;
    for (size_t i = 0; i < texels; ++i) env.radiance.rgb.insert(env.radiance.rgb.end(), radiance, radiance + 3);
    return env;
}

// A smooth, everywhere-positive order-3 radiance function, different per channel: [9][3].
const std::vector<float> kShRadiance = {
    2.0f,  1.5f,  1.0f,   // l=0
    0.3f,  -0.2f, 0.1f,   // Y_1,-1 ~ y
    0.5f,  0.3f,  -0.2f,  // Y_1,0 ~ z
    -0.4f, 0.2f,  0.3f,   // Y_1,1 ~ x
    0.1f,  0.05f, -0.1f,  // l=2
    -0.1f, 0.1f,  0.05f, 0.2f, -0.1f, 0.1f, 0.05f, 0.1f, -0.05f, -0.15f, 0.05f, 0.1f,
};

// The SH function sampled at every texel centre of an equirect or cube-strip image (sh's own texel directions).
EnvironmentMap shEnvironment(int width, EnvLayout layout) {
    EnvironmentMap env;
    env.layout = layout;
    env.radiance.width = width;
    env.radiance.height = layout == EnvLayout::Equirectangular ? width / 2 : 6 * width;
    for (int y = 0; y < env.radiance.height; ++y)
        for (int x = 0; x < width; ++x) {
            double d[3], basis[9];
            if (layout == EnvLayout::Equirectangular)
                prt::sh::equirectDirection(width, env.radiance.height, x, y, d);
            else
                prt::sh::cubeStripDirection(width, x, y, d);
            prt::sh::evaluate(3, d[0], d[1], d[2], basis);
            for (int c = 0; c < 3; ++c) {
                double radiance = 0.0;
                for (int i = 0; i < 9; ++i) radiance += basis[i] * kShRadiance[i * 3 + c];
                env.radiance.rgb.push_back(float(radiance));
            }
        }
    return env;
}

// Unshadowed diffuse radiance under kShRadiance: (albedo / pi) sum_l A_l L_lm Y_lm(n).
void shClosedForm(const float n[3], const float albedo[3], double out[3]) {
    double basis[9];
    prt::sh::evaluate(3, double(n[0]), double(n[1]), double(n[2]), basis);
    for (int c = 0; c < 3; ++c) {
        double irradiance = 0.0;
        for (int l = 0; l < 3; ++l)
            for (int i = l * l; i < (l + 1) * (l + 1); ++i)
                irradiance += prt::sh::clampedCosine(l) * kShRadiance[i * 3 + c] * basis[i];
        out[c] = albedo[c] / std::numbers::pi * irradiance;
    }
}

// How far estimates sit from the truth in units of their standard error, plus a relative tolerance for what the
// estimator does not see (the map's texels, the mesh's facets). Unbiased estimates with honest errors give a
// mean square near 1 and, over a few thousand values, no |z| beyond about 4.5. The summed error per channel
// (channels share their paths, so they are not summed together) catches small systematic biases that hide in
// per-value noise.
struct ZScores {
    double meanSquare = 0.0;
    double maxAbs = 0.0;
    double sum = 0.0; // max over channels of |sum of errors| / (sqrt(sum of variances) + tolerance sum |expected|)
};
ZScores zScores(const std::vector<float>& estimate, const std::vector<float>& standardError,
                const std::vector<double>& expected, double tolerance) {
    ZScores z;
    double errorSum[3] = {0, 0, 0}, varianceSum[3] = {0, 0, 0}, expectedSum[3] = {0, 0, 0};
    for (size_t i = 0; i < estimate.size(); ++i) {
        double error = estimate[i] - expected[i];
        double score = error == 0.0 ? 0.0 : error / (standardError[i] + tolerance * std::abs(expected[i]));
        z.meanSquare += score * score / double(estimate.size());
        z.maxAbs = std::max(z.maxAbs, std::abs(score));
        errorSum[i % 3] += error;
        varianceSum[i % 3] += double(standardError[i]) * standardError[i];
        expectedSum[i % 3] += std::abs(expected[i]);
    }
    for (int c = 0; c < 3; ++c)
        z.sum = std::max(z.sum, std::abs(errorSum[c]) / (std::sqrt(varianceSum[c]) + tolerance * expectedSum[c]));
    return z;
}

// The estimate agrees with `expected` as its own standard error says it should: z-scores of unit mean square,
// none beyond 4.5 sigma, and no bias in the per-channel sums (`tolerance`: relative slack for float rounding).
void expectUnbiasedWithinItsStandardError(const prt::ReferenceRadiance& result, const std::vector<double>& expected,
                                          double tolerance) {
    ZScores z = zScores(result.radiance, result.standardError, expected, tolerance);
    EXPECT_GT(z.meanSquare, 0.5);
    EXPECT_LT(z.meanSquare, 1.5);
    EXPECT_LT(z.maxAbs, 4.5);
    EXPECT_LT(z.sum, 4.0);
}

double meanOf(const std::vector<float>& values) {
    double sum = 0.0;
    for (float v : values) sum += v;
    return sum / double(values.size());
}

TEST(Reference, WhiteFurnaceSphereReturnsTheEnvironment) {
    const float radiance[3] = {0.5f, 1.0f, 2.0f};
    EnvironmentMap env = constantEnvironment(radiance);
    prt::TriMesh sphere = prt::makeSphere(1.0f, 8, 16);
    prt::ReferenceOptions options;
    options.samples = 512;
    options.albedo = std::array<float, 3>{1.0f, 1.0f, 1.0f};
    prt::ReferenceRadiance result = prt::referenceVertexRadiance(sphere, env, options);
    ASSERT_EQ(result.radiance.size(), sphere.vertexCount() * 3);

    std::vector<double> expected(result.radiance.size());
    for (size_t i = 0; i < expected.size(); ++i) expected[i] = radiance[i % 3];
    expectUnbiasedWithinItsStandardError(result, expected, 0.0);
    for (size_t i = 0; i < expected.size(); ++i) EXPECT_LT(result.standardError[i], 0.02 * expected[i]) << i;
    // One bounce ray per sample, plus a shadow ray whenever the light sample is above the horizon (about half).
    double raysPerSample = double(result.rays) / double(sphere.vertexCount() * options.samples);
    EXPECT_GT(raysPerSample, 1.4);
    EXPECT_LT(raysPerSample, 1.6);
}

TEST(Reference, UniformSkyLightsATiltedNormalByItsViewFactor) {
    // Radiance L above the horizon, black below (whole rows of zero weight): an unoccluded surface with normal n
    // receives pi L (1 + n_y) / 2, so it returns albedo L (1 + n_y) / 2.
    const float sky[3] = {1.0f, 0.8f, 0.6f};
    EnvironmentMap env = constantEnvironment(sky);
    std::fill(env.radiance.rgb.begin() + env.radiance.rgb.size() / 2, env.radiance.rgb.end(), 0.0f);
    prt::TriMesh sphere = prt::makeSphere(1.0f, 8, 16);
    prt::ReferenceOptions options;
    options.samples = 256;
    options.albedo = std::array<float, 3>{0.5f, 0.5f, 0.5f};
    prt::ReferenceRadiance result = prt::referenceVertexRadiance(sphere, env, options);
    std::vector<double> expected(result.radiance.size());
    for (size_t i = 0; i < expected.size(); ++i)
        expected[i] = 0.5 * sky[i % 3] * (1.0 + sphere.normals[i / 3 * 3 + 1]) / 2.0;
    ZScores z = zScores(result.radiance, result.standardError, expected, 1e-4);
    EXPECT_LT(z.meanSquare, 1.5);
    EXPECT_LT(z.maxAbs, 4.5);
    EXPECT_LT(z.sum, 4.0);
    // The south pole sees only black ground.
    size_t south = sphere.vertexCount() - 1;
    ASSERT_FLOAT_EQ(sphere.normals[south * 3 + 1], -1.0f);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(result.radiance[south * 3 + c], 0.0f);
}

TEST(Reference, BlackEnvironmentGivesBlack) {
    const float black[3] = {0.0f, 0.0f, 0.0f};
    prt::ReferenceOptions options;
    options.samples = 4;
    options.bounces = 2;
    prt::ReferenceRadiance result =
        prt::referenceVertexRadiance(prt::makeOpenCavity(1.0f, 1.0f, 6, 12), constantEnvironment(black), options);
    for (size_t i = 0; i < result.radiance.size(); ++i) {
        EXPECT_EQ(result.radiance[i], 0.0f);
        EXPECT_EQ(result.standardError[i], 0.0f);
    }
}

TEST(Reference, ConvexSphereMatchesTheShClosedForm) {
    EnvironmentMap env = shEnvironment(128, EnvLayout::Equirectangular);
    prt::TriMesh sphere = prt::makeSphere(1.0f, 12, 24);
    // Per-vertex albedo varying with height exercises the mesh-albedo path.
    for (size_t v = 0; v < sphere.vertexCount(); ++v) {
        float y = sphere.positions[v * 3 + 1];
        sphere.albedo.insert(sphere.albedo.end(), {0.6f + 0.3f * y, 0.5f, 0.4f - 0.2f * y});
    }
    prt::ReferenceOptions options;
    options.samples = 256;
    options.bounces = 1; // every bounce ray of a convex object escapes: same answer as direct lighting
    prt::ReferenceRadiance result = prt::referenceVertexRadiance(sphere, env, options);

    std::vector<double> expected(result.radiance.size());
    for (size_t v = 0; v < sphere.vertexCount(); ++v)
        shClosedForm(&sphere.normals[v * 3], &sphere.albedo[v * 3], &expected[v * 3]);
    expectUnbiasedWithinItsStandardError(result, expected, 1e-3);
}

// Signed radiance (what `prt reference --lights` renders where the SH residual dips below zero): light transport is
// linear, so the sphere under the SH map minus a constant s returns the closed form minus albedo * s, negative where
// the map is, within the estimate's own standard error (sampling follows |radiance|).
TEST(Reference, SignedEnvironmentIsTransportedLinearly) {
    EnvironmentMap env = shEnvironment(128, EnvLayout::Equirectangular);
    const float shift = 0.5f;
    size_t negative = 0;
    for (float& value : env.radiance.rgb) negative += (value -= shift) < 0.0f;
    ASSERT_GT(negative, env.radiance.rgb.size() / 10) << "the map must be negative in places";
    prt::TriMesh sphere = prt::makeSphere(1.0f, 12, 24);
    prt::ReferenceOptions options;
    options.samples = 256;
    options.bounces = 1;
    options.albedo = std::array<float, 3>{0.8f, 0.8f, 0.8f};
    prt::ReferenceRadiance result = prt::referenceVertexRadiance(sphere, env, options);
    std::vector<double> expected(result.radiance.size());
    const float albedo[3] = {0.8f, 0.8f, 0.8f};
    size_t negativeVertices = 0;
    for (size_t v = 0; v < sphere.vertexCount(); ++v) {
        shClosedForm(&sphere.normals[v * 3], albedo, &expected[v * 3]);
        for (int c = 0; c < 3; ++c) negativeVertices += (expected[v * 3 + c] -= albedo[c] * shift) < 0.0;
    }
    EXPECT_GT(negativeVertices, 0u);
    expectUnbiasedWithinItsStandardError(result, expected, 1e-3);
}

TEST(Reference, CubeStripEnvironmentMatchesTheShClosedForm) {
    EnvironmentMap env = shEnvironment(48, EnvLayout::CubeStrip);
    prt::TriMesh sphere = prt::makeSphere(1.0f, 12, 24);
    prt::ReferenceOptions options;
    options.samples = 256;
    options.albedo = std::array<float, 3>{0.9f, 0.7f, 0.5f};
    prt::ReferenceRadiance result = prt::referenceVertexRadiance(sphere, env, options);

    std::vector<double> expected(result.radiance.size());
    for (size_t v = 0; v < sphere.vertexCount(); ++v)
        shClosedForm(&sphere.normals[v * 3], options.albedo->data(), &expected[v * 3]);
    expectUnbiasedWithinItsStandardError(result, expected, 1e-3);
}

TEST(Reference, CubeStripLookupFindsEveryTexelCentre) {
    const float radiance[3] = {1.0f, 1.0f, 1.0f};
    for (int faceSize : {1, 2, 7}) {
        EnvironmentMap env = constantEnvironment(radiance, faceSize, EnvLayout::CubeStrip);
        prt::pathtrace::EnvironmentSampler sampler = prt::pathtrace::makeEnvironmentSampler(env);
        for (int y = 0; y < 6 * faceSize; ++y)
            for (int x = 0; x < faceSize; ++x) {
                double d[3];
                prt::sh::cubeStripDirection(faceSize, x, y, d);
                float direction[3] = {float(d[0]), float(d[1]), float(d[2])};
                EXPECT_EQ(prt::pathtrace::environmentTexel(sampler, direction), size_t(y) * faceSize + x)
                    << faceSize << ": " << x << "," << y;
            }
    }
}

TEST(Reference, OpenCavityFollowsTheNeumannSeries) {
    const float radiance[3] = {1.0f, 1.0f, 1.0f};
    EnvironmentMap env = constantEnvironment(radiance);
    double alpha = std::numbers::pi / 3.0, f = (1.0 - std::cos(alpha)) / 2.0, rho = 0.8;
    prt::TriMesh cavity = prt::makeOpenCavity(1.0f, float(alpha), 24, 48);
    prt::ReferenceOptions options;
    options.samples = 128;
    options.albedo = std::array<float, 3>{float(rho), float(rho), float(rho)};
    double expected = 0.0, term = rho * f;
    for (int bounces = 0; bounces <= 3; ++bounces) {
        expected += term;
        term *= rho * (1.0 - f);
        options.bounces = bounces;
        prt::ReferenceRadiance result = prt::referenceVertexRadiance(cavity, env, options);
        // The facets make the opening a 48-gon, 0.3% smaller than the circle: allow 0.4%.
        std::vector<double> uniform(result.radiance.size(), expected);
        ZScores z = zScores(result.radiance, result.standardError, uniform, 0.004);
        EXPECT_LT(z.maxAbs, 4.5) << bounces << " bounces";
        EXPECT_LT(z.sum, 4.0) << bounces << " bounces";
    }
}

TEST(Reference, StandardErrorShrinksAsOneOverSqrtSamples) {
    EnvironmentMap env = shEnvironment(64, EnvLayout::Equirectangular);
    prt::TriMesh sphere = prt::makeSphere(1.0f, 8, 16);
    prt::ReferenceOptions options;
    options.samples = 64;
    double few = meanOf(prt::referenceVertexRadiance(sphere, env, options).standardError);
    options.samples = 1024;
    double many = meanOf(prt::referenceVertexRadiance(sphere, env, options).standardError);
    EXPECT_NEAR(few / many, 4.0, 0.4);
}

TEST(Reference, OutputDoesNotDependOnThreadCount) {
    EnvironmentMap env = shEnvironment(64, EnvLayout::Equirectangular);
    prt::TriMesh cavity = prt::makeOpenCavity(1.0f, 1.0f, 8, 16);
    prt::ReferenceOptions options;
    options.samples = 32;
    options.bounces = 2;
    options.seed = 7;
    options.threads = 1;
    prt::ReferenceRadiance one = prt::referenceVertexRadiance(cavity, env, options);
    options.threads = 3;
    prt::ReferenceRadiance three = prt::referenceVertexRadiance(cavity, env, options);
    EXPECT_EQ(one.radiance, three.radiance);
    EXPECT_EQ(one.standardError, three.standardError);
    EXPECT_EQ(one.rays, three.rays);
    options.seed = 8;
    EXPECT_NE(prt::referenceVertexRadiance(cavity, env, options).radiance, one.radiance);
}

TEST(Reference, ImageShowsTheEnvironmentBehindTheObject) {
    EnvironmentMap env = shEnvironment(32, EnvLayout::Equirectangular);
    prt::TriMesh sphere = prt::makeSphere(0.5f, 16, 32);
    prt::PinholeCamera camera;
    camera.eye = {0.0f, 0.0f, 3.0f};
    camera.target = {0.0f, 0.0f, 0.0f};
    camera.up = {0.0f, 1.0f, 0.0f};
    camera.fovyDegrees = 40.0f;
    camera.width = 33;
    camera.height = 21;
    prt::ReferenceOptions options;
    options.samples = 256;
    prt::ReferenceImage image = prt::referenceImage(sphere, env, camera, options);
    std::filesystem::path folder = std::filesystem::temp_directory_path() / "prt_test_reference";
    std::filesystem::create_directories(folder);
    std::string path = (folder / "image.exr").string();
    prt::writeImage(path, image.radiance);
    prt::Image read = prt::readImage(path);
    ASSERT_EQ(read.width, camera.width);
    ASSERT_EQ(read.height, camera.height);

    // Top-left pixel misses the sphere: its ray, by the camera model in reference.h, picks the nearest texel.
    double tanHalf = std::tan(20.0 * std::numbers::pi / 180.0), aspect = 33.0 / 21.0;
    double sx = (2.0 * 0.5 / 33.0 - 1.0) * tanHalf * aspect, sy = (1.0 - 2.0 * 0.5 / 21.0) * tanHalf;
    double d[3] = {sx, sy, -1.0}, length = std::sqrt(sx * sx + sy * sy + 1.0);
    for (double& c : d) c /= length;
    double theta = std::acos(d[1]), phi = std::atan2(d[0], -d[2]);
    int tx = int((phi + std::numbers::pi) / (2.0 * std::numbers::pi) * 32), ty = int(theta / std::numbers::pi * 16);
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(read.rgb[c], env.radiance.rgb[(size_t(ty) * 32 + tx) * 3 + c]);
        EXPECT_EQ(image.standardError.rgb[c], 0.0f);
    }

    // The centre pixel sees the sphere's point facing the camera, normal +Z, lit by the SH environment.
    size_t centre = (size_t(10) * 33 + 16) * 3;
    const float normal[3] = {0.0f, 0.0f, 1.0f}, white[3] = {1.0f, 1.0f, 1.0f};
    double expected[3];
    shClosedForm(normal, white, expected);
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(read.rgb[centre + c], expected[c], 4.0 * image.standardError.rgb[centre + c] + 0.01 * expected[c]);
}

TEST(Reference, BadInputsThrow) {
    const float radiance[3] = {1.0f, 1.0f, 1.0f};
    EnvironmentMap env = constantEnvironment(radiance);
    prt::TriMesh sphere = prt::makeSphere(1.0f, 4, 8);
    prt::ReferenceOptions options;
    options.samples = 1;
    EXPECT_THROW(prt::referenceVertexRadiance(sphere, env, options), prt::Error);
    options.samples = 8;
    prt::TriMesh noNormals = sphere;
    noNormals.normals.clear();
    EXPECT_THROW(prt::referenceVertexRadiance(noNormals, env, options), prt::Error);
    EnvironmentMap wrongSize = env;
    wrongSize.radiance.height += 1;
    wrongSize.radiance.rgb.resize(size_t(wrongSize.radiance.width) * wrongSize.radiance.height * 3, 1.0f);
    EXPECT_THROW(prt::referenceVertexRadiance(sphere, wrongSize, options), prt::Error);
    prt::PinholeCamera camera;
    camera.width = camera.height = 4;
    camera.target = camera.eye;
    EXPECT_THROW(prt::referenceImage(sphere, env, camera, options), prt::Error);
}

} // namespace

namespace {

// Directional albedo of the Phong lobe, integral of ks (n+2)/(2 pi) max(0, r.wi)^n cos(theta_i) over the
// hemisphere, for an outgoing direction at polar angle thetaOut: midpoint rule, fine enough for 1e-4.
double phongDirectionalAlbedo(double thetaOut, double exponent, double ks) {
    const int rows = 300, columns = 600;
    double r[3] = {-std::sin(thetaOut), 0.0, std::cos(thetaOut)}; // mirror of wo = (sin, 0, cos)
    double sum = 0.0;
    for (int i = 0; i < rows; ++i) {
        double theta = (i + 0.5) * std::numbers::pi / 2 / rows;
        for (int j = 0; j < columns; ++j) {
            double phi = (j + 0.5) * 2 * std::numbers::pi / columns;
            double w[3] = {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
            double lobe = std::max(0.0, r[0] * w[0] + r[1] * w[1] + r[2] * w[2]);
            sum += std::pow(lobe, exponent) * std::cos(theta) * std::sin(theta);
        }
    }
    double cell = (std::numbers::pi / 2 / rows) * (2 * std::numbers::pi / columns);
    return ks * (exponent + 2.0) / (2.0 * std::numbers::pi) * sum * cell;
}

} // namespace

TEST(Reference, PhongWhiteFurnaceReturnsTheDirectionalAlbedo) {
    // Constant radiance L on an unoccluded sphere: each vertex returns L (rho + E(theta_o)), E the lobe's
    // directional albedo, which is ks at normal incidence and never more.
    const float radiance[3] = {1.0f, 1.0f, 1.0f};
    EnvironmentMap env = constantEnvironment(radiance);
    prt::TriMesh sphere = prt::makeSphere(1.0f, 8, 16);
    prt::ReferenceOptions options;
    options.samples = 512;
    options.albedo = std::array<float, 3>{0.3f, 0.3f, 0.3f};
    options.phong = prt::PhongBrdf{16.0, 0.6};
    options.eye = std::array<float, 3>{0.0f, 3.0f, 0.0f};
    EXPECT_NEAR(phongDirectionalAlbedo(0.0, 16.0, 0.6), 0.6, 1e-4);
    prt::ReferenceRadiance result = prt::referenceVertexRadiance(sphere, env, options);
    std::vector<double> expected(result.radiance.size());
    for (size_t v = 0; v < sphere.vertexCount(); ++v) {
        const float* p = &sphere.positions[v * 3];
        double toEye[3] = {-p[0], 3.0 - p[1], -p[2]};
        double length = std::sqrt(toEye[0] * toEye[0] + toEye[1] * toEye[1] + toEye[2] * toEye[2]);
        double cosOut = (toEye[0] * sphere.normals[v * 3] + toEye[1] * sphere.normals[v * 3 + 1] +
                         toEye[2] * sphere.normals[v * 3 + 2]) / length;
        static std::map<float, double> albedoByCosine; // rings share their cosine
        if (!albedoByCosine.count(float(cosOut)))
            albedoByCosine[float(cosOut)] =
                cosOut > 0.0 ? phongDirectionalAlbedo(std::acos(std::min(1.0, cosOut)), 16.0, 0.6) : 0.0;
        double lobe = albedoByCosine[float(cosOut)];
        for (int c = 0; c < 3; ++c) expected[v * 3 + c] = 0.3 + lobe;
    }
    expectUnbiasedWithinItsStandardError(result, expected, 1e-3);
    // The north pole faces the eye: rho + ks.
    EXPECT_NEAR(result.radiance[0 * 3 + 1], 0.9, 4.5 * result.standardError[1] + 1e-3);
}
