// Transfer against closed forms: white furnace, clamped-cosine transfer of a convex sphere, the occluding cone,
// the open spherical cavity's Neumann series; plus determinism, convergence rate and back-face accounting.
#include "transfer.h"

#include "core.h"
#include "scene.h"
#include "sh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numbers>

using namespace prt;

namespace {

constexpr double kPi = std::numbers::pi;

TransferOptions quietOptions(TransferMode mode, int order, int samples) {
    TransferOptions options;
    options.mode = mode;
    options.order = order;
    options.samples = samples;
    options.progress = false;
    return options;
}

// Exitant radiance of vertex row `row` under constant radiance L: only the DC lighting coefficient L sqrt(4 pi).
double furnaceRadiance(const Transfer& transfer, size_t row, int channel, double radiance) {
    size_t stride = size_t(transfer.order) * transfer.order * 3;
    return transfer.coefficients[row * stride + channel] * radiance * std::sqrt(4.0 * kPi);
}

bool bitIdentical(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// Receivers at the origin under an occluding disk of angular radius `coneHalfAngle` centred on +Y, one unit up
// (a 1024-gon facing down). The receivers are unreferenced vertices with normals tilted from +Y by up to
// `maxTilt`, so the cone lies inside every receiver's hemisphere.
constexpr int kReceivers = 64;
TriMesh coneScene(double coneHalfAngle, double maxTilt) {
    TriMesh mesh;
    const int sides = 1024;
    double radius = std::tan(coneHalfAngle);
    mesh.positions = {0.0f, 1.0f, 0.0f};
    mesh.normals = {0.0f, -1.0f, 0.0f};
    for (int i = 0; i < sides; ++i) {
        double phi = 2.0 * kPi * i / sides;
        mesh.positions.insert(mesh.positions.end(),
                              {float(radius * std::cos(phi)), 1.0f, float(radius * std::sin(phi))});
        mesh.normals.insert(mesh.normals.end(), {0.0f, -1.0f, 0.0f});
        // Counter-clockwise seen from below (-Y).
        mesh.indices.insert(mesh.indices.end(), {0u, uint32_t(1 + i), uint32_t(1 + (i + 1) % sides)});
    }
    for (int r = 0; r < kReceivers; ++r) {
        double tilt = maxTilt * std::sqrt((r + 0.5) / kReceivers);
        double azimuth = 2.399963 * r; // golden angle
        mesh.positions.insert(mesh.positions.end(), {0.0f, 0.0f, 0.0f});
        mesh.normals.insert(mesh.normals.end(), {float(std::sin(tilt) * std::cos(azimuth)), float(std::cos(tilt)),
                                                 float(std::sin(tilt) * std::sin(azimuth))});
    }
    return mesh;
}

// Exact per-unit-albedo shadowed transfer of a receiver with normal n under the cone: (1/pi) times
// [A_l Y_j(n) - integral over the cone of (n.d) Y_j(d)], the cone integral by a fine midpoint rule in the polar
// angle and the trapezoid rule in azimuth (exact for these trigonometric polynomials).
std::vector<double> coneTransfer(int order, const double n[3], double coneHalfAngle) {
    int count = order * order;
    std::vector<double> result(count, 0.0), basis(count);
    const int thetaSteps = 2000, phiSteps = 64;
    double dTheta = coneHalfAngle / thetaSteps, dPhi = 2.0 * kPi / phiSteps;
    for (int i = 0; i < thetaSteps; ++i) {
        double theta = (i + 0.5) * dTheta;
        for (int k = 0; k < phiSteps; ++k) {
            double phi = k * dPhi;
            double d[3] = {std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)};
            double weight = (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) * std::sin(theta) * dTheta * dPhi;
            sh::evaluate(order, d[0], d[1], d[2], basis.data());
            for (int j = 0; j < count; ++j) result[j] -= weight * basis[j];
        }
    }
    sh::evaluate(order, n[0], n[1], n[2], basis.data());
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m) {
            int j = sh::index(l, m);
            result[j] = (sh::clampedCosine(l) * basis[j] + result[j]) / kPi;
        }
    return result;
}

} // namespace

TEST(Transfer, WhiteFurnaceReturnsTheEnvironmentRadiance) {
    TriMesh sphere = makeSphere(1.0f, 16, 32);
    for (TransferMode mode : {TransferMode::Unshadowed, TransferMode::Shadowed}) {
        Transfer transfer = computeTransfer(sphere, quietOptions(mode, 3, 256));
        for (size_t v = 0; v < sphere.vertexCount(); ++v)
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(furnaceRadiance(transfer, v, c, 2.5), 2.5, 2.5 * 1e-6) << v;
    }
}

TEST(Transfer, AlbedoScalesPerVertexUnlessOverridden) {
    TriMesh sphere = makeSphere(1.0f, 8, 16);
    for (size_t v = 0; v < sphere.vertexCount(); ++v)
        sphere.albedo.insert(sphere.albedo.end(), {0.1f, 0.5f, float(v % 10) / 10.0f});
    TransferOptions options = quietOptions(TransferMode::Unshadowed, 2, 1);
    Transfer perVertex = computeTransfer(sphere, options);
    options.albedo = {0.25f, 0.25f, 0.25f};
    options.albedoOverride = true;
    Transfer overridden = computeTransfer(sphere, options);
    for (size_t v = 0; v < sphere.vertexCount(); ++v)
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(furnaceRadiance(perVertex, v, c, 1.0), sphere.albedo[3 * v + c], 1e-6);
            EXPECT_NEAR(furnaceRadiance(overridden, v, c, 1.0), 0.25, 1e-6);
        }
}

TEST(Transfer, ConvexSphereShadowedIsTheClampedCosineTransfer) {
    TriMesh sphere = makeSphere(1.0f, 16, 32);
    TransferOptions options = quietOptions(TransferMode::Shadowed, 5, 64);
    options.albedo = {0.8f, 0.5f, 0.2f};
    options.albedoOverride = true;
    Transfer transfer = computeTransfer(sphere, options);
    EXPECT_EQ(transfer.stats.rays, sphere.vertexCount() * 64);
    const double bandFactor[5] = {kPi, 2.0 * kPi / 3.0, kPi / 4.0, 0.0, -kPi / 24.0};
    double basis[25];
    for (size_t v = 0; v < sphere.vertexCount(); ++v) {
        const float* n = &sphere.normals[3 * v];
        sh::evaluate(5, double(n[0]), double(n[1]), double(n[2]), basis);
        for (int l = 0; l < 5; ++l)
            for (int m = -l; m <= l; ++m)
                for (int c = 0; c < 3; ++c) {
                    int j = sh::index(l, m);
                    double expected = options.albedo[c] / kPi * bandFactor[l] * basis[j];
                    ASSERT_NEAR(transfer.coefficients[(v * 25 + j) * 3 + c], expected, 2e-6) << v << " " << j;
                }
    }
}

TEST(Transfer, BouncesAddExactlyZeroOnAConvexMesh) {
    TriMesh sphere = makeSphere(1.0f, 12, 24);
    Transfer shadowed = computeTransfer(sphere, quietOptions(TransferMode::Shadowed, 4, 128));
    TransferOptions options = quietOptions(TransferMode::Interreflected, 4, 128);
    options.bounces = 3;
    Transfer interreflected = computeTransfer(sphere, options);
    EXPECT_EQ(interreflected.stats.hits, 0u);
    EXPECT_EQ(interreflected.stats.bounceSeconds.size(), 3u);
    EXPECT_TRUE(bitIdentical(shadowed.coefficients, interreflected.coefficients));
}

TEST(Transfer, OccludingConeMatchesQuadratureAndConvergesAtTheQmcRate) {
    const double cone = 30.0 * kPi / 180.0;
    TriMesh mesh = coneScene(cone, 30.0 * kPi / 180.0);
    size_t first = mesh.vertexCount() - kReceivers;
    const int order = 4, count = order * order;
    std::vector<std::vector<double>> exact;
    for (int r = 0; r < kReceivers; ++r) {
        const float* n = &mesh.normals[3 * (first + r)];
        double normal[3] = {n[0], n[1], n[2]};
        exact.push_back(coneTransfer(order, normal, cone));
    }

    std::vector<double> logSamples, logError;
    for (int samples : {16, 64, 256, 1024}) {
        TransferOptions options = quietOptions(TransferMode::Shadowed, order, samples);
        options.vertexBegin = first;
        Transfer transfer = computeTransfer(mesh, options);
        ASSERT_EQ(transfer.coefficients.size(), size_t(kReceivers) * count * 3);
        double squared = 0.0, worst = 0.0;
        for (int r = 0; r < kReceivers; ++r)
            for (int j = 0; j < count; ++j) {
                double error = transfer.coefficients[(size_t(r) * count + j) * 3] - exact[r][j];
                squared += error * error;
                worst = std::max(worst, std::abs(error));
            }
        double rms = std::sqrt(squared / (kReceivers * count));
        logSamples.push_back(std::log(double(samples)));
        logError.push_back(std::log(rms));
        if (samples == 1024) {
            // The occluded part is about a quarter of the DC transfer 0.2821.
            EXPECT_LT(rms, 1.5e-3);
            EXPECT_LT(worst, 6e-3);
        }
    }
    double meanX = 0.0, meanY = 0.0;
    for (size_t i = 0; i < logSamples.size(); ++i) {
        meanX += logSamples[i] / logSamples.size();
        meanY += logError[i] / logSamples.size();
    }
    double sxy = 0.0, sxx = 0.0;
    for (size_t i = 0; i < logSamples.size(); ++i) {
        sxy += (logSamples[i] - meanX) * (logError[i] - meanY);
        sxx += (logSamples[i] - meanX) * (logSamples[i] - meanX);
    }
    double slope = sxy / sxx;
    EXPECT_LE(slope, -0.4) << "RMS error against log samples";
}

TEST(Transfer, OpenCavityFollowsTheNeumannSeries) {
    const double opening = 60.0 * kPi / 180.0;
    const std::array<float, 3> albedo = {0.8f, 0.6f, 0.3f};
    TriMesh cavity = makeOpenCavity(1.0f, float(opening), 24, 48);
    double formFactor = (1.0 - std::cos(opening)) / 2.0; // of the opening, from any wall point
    for (int bounces = 0; bounces <= 3; ++bounces) {
        TransferOptions options = quietOptions(TransferMode::Interreflected, 3, 1024);
        options.bounces = bounces;
        options.albedo = albedo;
        Transfer transfer = computeTransfer(cavity, options);
        EXPECT_EQ(transfer.stats.backFaceHits, 0u);
        for (int c = 0; c < 3; ++c) {
            double expected = 0.0;
            for (int k = 0; k <= bounces; ++k)
                expected += albedo[c] * formFactor * std::pow(albedo[c] * (1.0 - formFactor), k);
            double sum = 0.0;
            int count = 0;
            for (size_t v = 0; v < cavity.vertexCount(); ++v) {
                double polar = std::acos(std::clamp(double(cavity.positions[3 * v + 1]), -1.0, 1.0));
                if (polar < opening + 20.0 * kPi / 180.0) continue; // away from the rim
                sum += furnaceRadiance(transfer, v, c, 1.0);
                ++count;
            }
            ASSERT_GT(count, 100);
            EXPECT_NEAR(sum / count, expected, 0.01 * expected) << bounces << " bounces, channel " << c;
        }
    }
}

TEST(Transfer, PerVertexAlbedoBouncesAgreeWithUniformAlbedo) {
    // Per-vertex albedo gathers RGB rows; one albedo for the mesh gathers a single channel. Same light either way.
    TriMesh cavity = makeOpenCavity(1.0f, 1.0f, 12, 24);
    TransferOptions options = quietOptions(TransferMode::Interreflected, 3, 256);
    options.bounces = 3;
    options.albedo = {0.9f, 0.5f, 0.2f};
    options.albedoOverride = true;
    Transfer uniform = computeTransfer(cavity, options);
    for (size_t v = 0; v < cavity.vertexCount(); ++v) cavity.albedo.insert(cavity.albedo.end(), {0.9f, 0.5f, 0.2f});
    options.albedoOverride = false;
    options.albedo = {1.0f, 1.0f, 1.0f};
    Transfer perVertex = computeTransfer(cavity, options);
    ASSERT_EQ(uniform.coefficients.size(), perVertex.coefficients.size());
    for (size_t i = 0; i < uniform.coefficients.size(); ++i)
        ASSERT_NEAR(perVertex.coefficients[i], uniform.coefficients[i], 1e-6 + 1e-5 * std::abs(uniform.coefficients[i]))
            << i;
}

TEST(Transfer, BitIdenticalAcrossThreadsAndShards) {
    TriMesh scene = makeSphereInCavity(12, 24);
    TransferOptions options = quietOptions(TransferMode::Shadowed, 3, 128);
    options.threads = 1;
    Transfer whole = computeTransfer(scene, options);
    for (int threads : {2, 3}) {
        options.threads = threads;
        EXPECT_TRUE(bitIdentical(whole.coefficients, computeTransfer(scene, options).coefficients)) << threads;
    }

    std::vector<float> joined;
    size_t cuts[] = {0, 100, 333, scene.vertexCount()};
    for (int s = 0; s < 3; ++s) {
        options.vertexBegin = cuts[s];
        options.vertexEnd = cuts[s + 1];
        Transfer shard = computeTransfer(scene, options);
        EXPECT_EQ(shard.vertexBegin, cuts[s]);
        joined.insert(joined.end(), shard.coefficients.begin(), shard.coefficients.end());
    }
    EXPECT_TRUE(bitIdentical(whole.coefficients, joined));

    TransferOptions bounced = quietOptions(TransferMode::Interreflected, 3, 128);
    bounced.bounces = 2;
    bounced.threads = 1;
    Transfer one = computeTransfer(scene, bounced);
    bounced.threads = 3;
    Transfer three = computeTransfer(scene, bounced);
    EXPECT_GT(one.stats.hits, 0u);
    EXPECT_TRUE(bitIdentical(one.coefficients, three.coefficients));
    TriMesh coloured = scene;
    for (size_t v = 0; v < coloured.vertexCount(); ++v)
        coloured.albedo.insert(coloured.albedo.end(), {0.9f, float(v % 7) / 7.0f, 0.5f});
    bounced.threads = 1;
    Transfer rgbOne = computeTransfer(coloured, bounced);
    bounced.threads = 3;
    EXPECT_TRUE(bitIdentical(rgbOne.coefficients, computeTransfer(coloured, bounced).coefficients));

    options = quietOptions(TransferMode::Shadowed, 3, 128);
    options.seed = 7;
    EXPECT_FALSE(bitIdentical(whole.coefficients, computeTransfer(scene, options).coefficients));
}

TEST(Transfer, BackFaceHitsAreCountedAndReflectNothing) {
    // Normals flipped inward, winding left outward: every ray meets the far wall from behind.
    TriMesh insideOut = makeSphere(1.0f, 12, 24);
    for (float& component : insideOut.normals) component = -component;
    TransferOptions options = quietOptions(TransferMode::Interreflected, 3, 64);
    options.bounces = 1;
    Transfer transfer = computeTransfer(insideOut, options);
    EXPECT_EQ(transfer.stats.hits, 0u);
    EXPECT_GT(transfer.stats.backFaceHits, transfer.stats.rays * 99 / 100);
    for (size_t v = 0; v < insideOut.vertexCount(); ++v) EXPECT_NEAR(furnaceRadiance(transfer, v, 0, 1.0), 0.0, 1e-3);
}

TEST(Transfer, BareYardstickCastsTheSameRays) {
    TriMesh scene = makeSphereInCavity(8, 16);
    TransferOptions options = quietOptions(TransferMode::Shadowed, 3, 64);
    RayThroughput bare = castBareOcclusionRays(scene, options);
    EXPECT_EQ(bare.rays, computeTransfer(scene, options).stats.rays);
    EXPECT_GT(bare.occluded, 0u);
    EXPECT_LT(bare.occluded, bare.rays);
}

TEST(Transfer, RefusesBadMeshesAndOptions) {
    TriMesh sphere = makeSphere(1.0f, 4, 8);
    auto exitCodeOf = [](const TriMesh& mesh, const TransferOptions& options) {
        try {
            computeTransfer(mesh, options);
        } catch (const Error& e) {
            return e.exitCode();
        }
        return int(kExitOk);
    };
    TriMesh noNormals = sphere;
    noNormals.normals.clear();
    EXPECT_EQ(exitCodeOf(noNormals, quietOptions(TransferMode::Shadowed, 3, 16)), kExitInput);
    TriMesh badIndex = sphere;
    badIndex.indices[5] = 999;
    EXPECT_EQ(exitCodeOf(badIndex, quietOptions(TransferMode::Shadowed, 3, 16)), kExitInput);

    EXPECT_EQ(exitCodeOf(sphere, quietOptions(TransferMode::Shadowed, 0, 16)), kExitUsage);
    EXPECT_EQ(exitCodeOf(sphere, quietOptions(TransferMode::Shadowed, 3, 0)), kExitUsage);
    TransferOptions bouncesWithoutInterreflection = quietOptions(TransferMode::Shadowed, 3, 16);
    bouncesWithoutInterreflection.bounces = 1;
    EXPECT_EQ(exitCodeOf(sphere, bouncesWithoutInterreflection), kExitUsage);
    TransferOptions partialBounces = quietOptions(TransferMode::Interreflected, 3, 16);
    partialBounces.bounces = 1;
    partialBounces.vertexEnd = 5;
    EXPECT_EQ(exitCodeOf(sphere, partialBounces), kExitUsage);
    TransferOptions brightAlbedo = quietOptions(TransferMode::Shadowed, 3, 16);
    brightAlbedo.albedo = {1.5f, 0.5f, 0.5f};
    EXPECT_EQ(exitCodeOf(sphere, brightAlbedo), kExitUsage);
    EXPECT_THROW(parseTransferMode("ambient"), Error);
}
