// Cone lights through the glossy path (docs/glossy.md, "Lights through the glossy path"): the lights' exact Phong
// lobe against closed forms and the exact direct-light oracle, shadowed lights, the residual map, and the CLI.
#include "envlight.h"
#include "glossy.h"
#include "raycast.h"
#include "reference.h"
#include "runtime.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

namespace {

constexpr double kPi = std::numbers::pi;

// A glossy model of `mesh` with no lobe data (only what the lights' shading reads: positions, normals, the BRDF).
prt::GlossyModel lightsOnlyModel(const prt::TriMesh& mesh, double exponent, double ks) {
    prt::GlossyModel model;
    model.vertexCount = uint32_t(mesh.vertexCount());
    model.lobes = 1;
    model.positions = mesh.positions;
    model.normals = mesh.normals;
    model.exponent = exponent;
    model.ks = ks;
    return model;
}

prt::GlossyConeLights withSamples(const std::vector<prt::envlight::ConeLight>& cones, int samples) {
    prt::GlossyConeLights lights;
    lights.samples = samples;
    for (const prt::envlight::ConeLight& cone : cones) {
        prt::HybridConeLight light;
        for (int c = 0; c < 3; ++c) light.direction[c] = float(cone.direction[c]), light.radiance[c] = float(cone.radiance[c]);
        light.angularRadius = float(cone.angularRadius);
        lights.lights.push_back(light);
        std::vector<float> d = prt::envlight::coneSampleDirections(cone, samples);
        lights.directions.insert(lights.directions.end(), d.begin(), d.end());
    }
    return lights;
}

std::array<double, 3> unit(double x, double y, double z) {
    double l = std::sqrt(x * x + y * y + z * z);
    return {x / l, y / l, z / l};
}

} // namespace

// An open plane (normal +Y) under one 0.5-degree cone at 40 degrees from the normal, radiance 1000: toward the
// light's mirror direction the glossy radiance is radiance * solid angle * ks (n + 2) / (2 pi) * cos(40 deg), up to
// the lobe's and the cosine's variation inside the cone (n = 32: under 0.3%); Embree finds every sample visible.
TEST(GlossyLights, ClosedFormTowardTheMirrorDirectionOfOneSmallCone) {
    const prt::TriMesh plane = prt::makePlane(2.0f, 2, 0.0f);
    const double exponent = 32.0, ks = 0.5, radius = 0.5 * kPi / 180.0, angle = 40.0 * kPi / 180.0;
    prt::envlight::ConeLight cone{unit(std::sin(angle), std::cos(angle), 0.0), {1000.0, 500.0, 250.0}, radius};
    prt::GlossyConeLights lights = withSamples({cone}, 64);
    const std::vector<float> spawn = prt::spawnNormals(plane);
    uint64_t rays = 0;
    lights.visible = prt::envlight::coneSampleVisibility(plane, plane.positions.data(), plane.normals.data(),
                                                         spawn.data(), plane.vertexCount(), {cone}, 64, &rays);
    EXPECT_EQ(rays, plane.vertexCount() * 64u);
    for (uint8_t v : lights.visible) EXPECT_EQ(v, 1);
    const prt::GlossyModel model = lightsOnlyModel(plane, exponent, ks);
    ASSERT_NO_THROW(prt::checkGlossyConeLights(model, lights, "test"));
    const float mirror[3] = {float(-std::sin(angle)), float(std::cos(angle)), 0.0f}; // the light mirrored about +Y
    const double solidAngle = 2.0 * kPi * (1.0 - std::cos(radius));
    for (uint32_t v = 0; v < model.vertexCount; ++v) {
        float radiance[3];
        prt::glossyConeLightsToward(model, lights, v, mirror, radiance);
        for (int c = 0; c < 3; ++c) {
            const double expected = cone.radiance[c] * solidAngle * ks * (exponent + 2.0) / (2.0 * kPi) * std::cos(angle);
            EXPECT_NEAR(radiance[c], expected, 0.003 * expected) << v << " " << c;
        }
    }
    // Below the surface the lobe sends nothing; away from the mirror direction far less.
    const float below[3] = {0.0f, -1.0f, 0.0f}, normal[3] = {0.0f, 1.0f, 0.0f};
    float radiance[3];
    prt::glossyConeLightsToward(model, lights, 0, below, radiance);
    EXPECT_EQ(radiance[0], 0.0f);
    prt::glossyConeLightsToward(model, lights, 0, normal, radiance);
    const double atNormal = cone.radiance[0] * solidAngle * ks * (exponent + 2.0) / (2.0 * kPi) *
                            std::pow(std::cos(angle), exponent) * std::cos(angle);
    EXPECT_NEAR(radiance[0], atNormal, 0.05 * atNormal);
}

// A point under a blocker sees none of the cone: every sample is occluded, the lights add nothing, so the glossy
// radiance is the lobes' of the residual alone. Samples below the horizon are 0 and cast no ray.
TEST(GlossyLights, AFullyBlockedLightGivesNothing) {
    const prt::TriMesh floor = prt::makePlane(1.0f, 1, 0.0f), roof = prt::makePlane(50.0f, 1, 1.0f);
    prt::TriMesh scene = prt::mergeMeshes({floor, roof});
    const float point[3] = {0.0f, 0.01f, 0.0f}, up[3] = {0.0f, 1.0f, 0.0f};
    prt::envlight::ConeLight overhead{unit(0.2, 1.0, 0.1), {100.0, 100.0, 100.0}, 0.05};
    prt::envlight::ConeLight below{unit(0.0, -1.0, 0.0), {100.0, 100.0, 100.0}, 0.05};
    uint64_t rays = 0;
    std::vector<uint8_t> visible =
        prt::envlight::coneSampleVisibility(scene, point, up, nullptr, 1, {overhead, below}, 32, &rays);
    ASSERT_EQ(visible.size(), 64u);
    EXPECT_EQ(rays, 32u); // the light below the horizon casts nothing
    for (uint8_t v : visible) EXPECT_EQ(v, 0);
    prt::TriMesh one;
    one.positions = {point[0], point[1], point[2]};
    one.normals = {0.0f, 1.0f, 0.0f};
    const prt::GlossyModel model = lightsOnlyModel(one, 32.0, 0.5);
    prt::GlossyConeLights lights = withSamples({overhead, below}, 32);
    lights.visible = visible;
    const float eye[3] = {-0.2f * 10.0f, 10.0f, -0.1f * 10.0f};
    float radiance[3];
    prt::glossyConeLightRadiance(model, lights, eye, radiance);
    EXPECT_EQ(radiance[0], 0.0f);
    // The same light unblocked (the roof gone) lights the point.
    visible = prt::envlight::coneSampleVisibility(floor, point, up, nullptr, 1, {overhead, below}, 32);
    lights.visible = visible;
    prt::glossyConeLightRadiance(model, lights, eye, radiance);
    EXPECT_GT(radiance[0], 1.0f);
}

// The lights' glossy part against the exact oracle of the cones alone: `prt reference --brute-force --brdf` over
// the cones rendered into a map (what `prt reference --lights` does with a zero residual), albedo 0 so only the
// lobe is left, on a convex sphere from an eye outside it. 64 stratified samples per 4-degree cone against
// every texel of a 1024 x 512 map: within 0.5% relative RMSE (measured 0.15%).
TEST(GlossyLights, LightsPartMatchesTheExactOracleOfTheConesAlone) {
    const prt::TriMesh sphere = prt::makeSphere(1.0f, 16, 32);
    const std::vector<prt::envlight::ConeLight> cones = {{unit(0.3, 0.8, 0.5), {40.0, 30.0, 20.0}, 4.0 * kPi / 180.0},
                                                         {unit(-0.7, 0.2, 0.6), {10.0, 10.0, 30.0}, 2.5 * kPi / 180.0}};
    const prt::EnvironmentMap map = prt::envlight::renderLighting(cones, std::vector<double>(3, 0.0), 1, 1024, 8);
    prt::DirectOptions options;
    options.albedo = std::array<float, 3>{0.0f, 0.0f, 0.0f};
    options.phong = prt::PhongBrdf{32.0, 0.5};
    options.eye = std::array<float, 3>{0.5f, 1.0f, 6.0f};
    options.threads = 2;
    options.shadows = false; // a convex sphere shadows nothing but its own back, which the cosine removes
    const prt::ReferenceRadiance oracle = prt::referenceDirectRadiance(sphere, {}, map, options);

    const prt::GlossyModel model = lightsOnlyModel(sphere, 32.0, 0.5);
    prt::GlossyConeLights lights = withSamples(cones, 64);
    const std::vector<float> spawn = prt::spawnNormals(sphere);
    lights.visible = prt::envlight::coneSampleVisibility(sphere, sphere.positions.data(), sphere.normals.data(),
                                                         spawn.data(), sphere.vertexCount(), cones, 64);
    std::vector<float> radiance(sphere.vertexCount() * 3);
    prt::glossyConeLightRadiance(model, lights, options.eye->data(), radiance.data());
    double error = 0.0, energy = 0.0;
    for (size_t i = 0; i < radiance.size(); ++i) {
        error += std::pow(double(radiance[i]) - oracle.radiance[i], 2);
        energy += std::pow(double(oracle.radiance[i]), 2);
    }
    ASSERT_GT(energy, 0.0);
    std::printf("lights part against the oracle of the cones: relative RMSE %.4f\n", std::sqrt(error / energy));
    EXPECT_LT(std::sqrt(error / energy), 0.005);
}

// The residual map: a map that is a constant plus a rendered cone gives the constant back; the constant alone
// gives negative texels inside the cone (kept: the map is exactly residual + cones), or zeros (clamped).
TEST(GlossyLights, ResidualMapIsTheMapMinusTheCones) {
    const std::vector<prt::envlight::ConeLight> cones = {{unit(0.0, 0.6, 0.8), {5.0, 4.0, 3.0}, 6.0 * kPi / 180.0}};
    prt::EnvironmentMap map = prt::envlight::renderLighting(cones, std::vector<double>(3, 0.0), 1, 128, 8);
    for (float& x : map.radiance.rgb) x += 1.5f;
    prt::envlight::ResidualMapStats stats;
    const prt::EnvironmentMap residual = prt::envlight::subtractConeLights(map, cones, 8, false, &stats);
    for (float x : residual.radiance.rgb) EXPECT_NEAR(x, 1.5f, 1e-5f);
    EXPECT_GT(stats.lightsEnergy, 0.0);
    EXPECT_EQ(stats.negativeEnergy, 0.0);
    // No lights: the map itself, bit for bit.
    const prt::EnvironmentMap same = prt::envlight::subtractConeLights(map, {}, 8, false);
    EXPECT_EQ(same.radiance.rgb, map.radiance.rgb);

    for (float& x : map.radiance.rgb) x = 1.5f;
    const prt::EnvironmentMap kept = prt::envlight::subtractConeLights(map, cones, 8, false, &stats);
    EXPECT_GT(stats.negativeEnergy, 0.0);
    float lowest = 0.0f;
    for (float x : kept.radiance.rgb) lowest = std::min(lowest, x);
    EXPECT_NEAR(lowest, 1.5f - 5.0f, 1e-5f);
    const prt::EnvironmentMap clamped = prt::envlight::subtractConeLights(map, cones, 8, true);
    for (float x : clamped.radiance.rgb) EXPECT_GE(x, 0.0f);
    prt::EnvironmentMap strip = map;
    strip.layout = prt::EnvLayout::CubeStrip;
    EXPECT_THROW(prt::envlight::subtractConeLights(strip, cones, 8, false), prt::Error);
}

// The per-sample bits give coneVisibility's cosine-weighted visible fractions bit for bit, on a mesh that shadows
// itself (an open spherical cavity, normals inward) under wide cones that the rim cuts part way.
TEST(GlossyLights, SampleBitsGiveTheConeVisibilityFractions) {
    const prt::TriMesh mesh = prt::makeOpenCavity(1.0f, 1.0f, 12, 24);
    const std::vector<prt::envlight::ConeLight> cones = {{unit(0.4, 0.9, 0.1), {1.0, 1.0, 1.0}, 15.0 * kPi / 180.0},
                                                         {unit(-0.8, 0.3, 0.5), {1.0, 1.0, 1.0}, 25.0 * kPi / 180.0}};
    const std::vector<float> spawn = prt::spawnNormals(mesh);
    const std::vector<uint8_t> bits = prt::envlight::coneSampleVisibility(
        mesh, mesh.positions.data(), mesh.normals.data(), spawn.data(), mesh.vertexCount(), cones, 32);
    std::vector<float> directions;
    for (const auto& cone : cones) {
        std::vector<float> d = prt::envlight::coneSampleDirections(cone, 32);
        directions.insert(directions.end(), d.begin(), d.end());
    }
    const std::vector<float> fractions = prt::envlight::coneVisibilityFromSamples(
        mesh.normals.data(), mesh.vertexCount(), cones.size(), 32, directions.data(), bits.data());
    const std::vector<float> expected = prt::envlight::coneVisibility(mesh, mesh.positions.data(), mesh.normals.data(),
                                                                      spawn.data(), mesh.vertexCount(), cones, 32);
    EXPECT_EQ(fractions, expected);
    size_t partial = 0;
    for (float f : expected) partial += f > 0.0f && f < 1.0f;
    EXPECT_GT(partial, 0u);
}
