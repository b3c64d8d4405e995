// The occluder's own self-shadowing at its vertices (selfIrradiance, layer fiv_self): a point-like source over a
// floor with a sphere above it lights exactly the floor vertices whose ray toward it misses the sphere; a lone
// plane under a constant cube receives the cube's hemisphere; the runtime uses the layer as it is written, and the
// reader refuses a fiv_self layer of the wrong shape, type or values through fivLayer.
#include "fiv.h"
#include "fiv_test_util.h"

#include "core.h"
#include "reference.h"
#include "runtime.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace prt;
using namespace prt::fiv;

namespace {

// `b` appended to `a` (positions, normals, indices).
TriMesh joined(TriMesh a, const TriMesh& b) {
    uint32_t base = uint32_t(a.vertexCount());
    a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
    a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
    for (uint32_t i : b.indices) a.indices.push_back(base + i);
    a.texcoords.clear();
    return a;
}

CubeEnvironment black(int size) {
    CubeEnvironment env;
    env.size = size;
    env.radiance.assign(3 * 6 * size_t(size) * size, 0.0);
    return env;
}

} // namespace

TEST(FivSelf, APointSourceLightsExactlyTheFloorVerticesWhoseRayMissesTheSphere) {
    const float centre[3] = {0.0f, 2.0f, 0.0f};
    TriMesh floor = makePlane(8.0f, 40);
    const size_t floorVertices = floor.vertexCount();
    TriMesh mesh = joined(floor, makeSphere(1.0f, 48, 96, centre));
    SmallSources sources;
    const double s[3] = {0.48, 0.6, 0.64}; // unit, above the floor
    sources.direction = {s[0], s[1], s[2]};
    sources.power = {1.0, 2.0, 3.0};
    uint64_t rays = 0;
    std::vector<float> e = selfIrradiance(mesh, black(4), sources, 2, &rays);
    ASSERT_EQ(e.size(), 3 * mesh.vertexCount());
    size_t shadowed = 0, lit = 0;
    for (size_t v = 0; v < floorVertices; ++v) {
        // The ray p + t s passes the sphere's centre at distance |(c - p) x s|; the tessellation lies within 2e-3
        // of the unit sphere, so grazing rays may go either way.
        const float* p = &mesh.positions[3 * v];
        double q[3] = {centre[0] - p[0], centre[1] - p[1], centre[2] - p[2]};
        double cross[3] = {q[1] * s[2] - q[2] * s[1], q[2] * s[0] - q[0] * s[2], q[0] * s[1] - q[1] * s[0]};
        double miss = std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
        if (std::abs(miss - 1.0) < 0.01) continue;
        bool hidden = miss < 1.0;
        (hidden ? shadowed : lit) += 1;
        for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(e[3 * v + c], hidden ? 0.0f : float((c + 1) * s[1])) << v;
    }
    EXPECT_GT(shadowed, 20u);
    EXPECT_GT(lit, 1000u);
    EXPECT_GT(rays, floorVertices / 2); // one ray per vertex with the source above its tangent plane (none black)
    // Bit-identical for any thread count.
    EXPECT_EQ(selfIrradiance(mesh, black(4), sources, 1), e);
}

TEST(FivSelf, ALonePlaneReceivesTheConstantCubesCosineWeightedHemisphere) {
    TriMesh plane = makePlane(2.0f, 4);
    CubeEnvironment env = fivtest::cubeFrom(16, [](const double*) { return std::array<double, 3>{1.0, 2.0, 0.5}; });
    std::vector<float> e = selfIrradiance(plane, env, {}, 2);
    // Nothing occludes an open plane's upper side: E = pi L, to the cube's texel-centre cosine rule.
    for (size_t v = 0; v < plane.vertexCount(); ++v)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(e[3 * v + c], std::numbers::pi * (c == 0 ? 1.0 : c == 1 ? 2.0 : 0.5), 2e-2 * std::numbers::pi);
    TriMesh noNormals = plane;
    noNormals.normals.clear();
    EXPECT_THROW(selfIrradiance(noNormals, env, {}, 1), Error);
}

TEST(FivSelf, TheLayerIsReadBackUsedAsWrittenAndRefusedWhenMalformed) {
    TriMesh sphere = makeSphere(0.5f, 8, 16);
    VisibilityOptions options;
    options.grid.azimuth = 8, options.grid.polar = 5, options.grid.shells = 3;
    options.cube = 4;
    Visibility vis = sampleVisibility(sphere, options, "sphere");
    CubeEnvironment env = fivtest::cubeFrom(4, [](const double* d) { return std::array<double, 3>{1.0 + d[1], 1.0, 1.0}; });
    FivGrid grid = reduceVisibility(vis, env);
    FivBundleOptions bundleOptions;
    bundleOptions.half = false;
    bundleOptions.difmapSize = 4;
    bundleOptions.selfIrradiance = selfIrradiance(sphere, env, {}, 1);
    Bundle bundle = fivBundle(sphere, grid, difMap(env, 4), environmentFiv(env), bundleOptions, {});
    FivOccluder occluder = fivOccluder(bundle, "b.glb");
    ASSERT_EQ(occluder.selfIrradiance, bundleOptions.selfIrradiance);
    // The runtime takes E_self as the self-shadowed unoccluded irradiance (clamped to DifMap(N) only).
    FivLighting lighting = fivLighting(bundle, "b.glb");
    for (float& v : lighting.difmap) v = 1e6f;
    FivInstance self{&occluder, {0, 0, 0}, occluder.selfIrradiance.data()};
    std::vector<float> out(sphere.positions.size());
    fivIrradiance(lighting, nullptr, 0, &self, sphere.positions.data(), sphere.normals.data(), sphere.vertexCount(), {},
                  out.data());
    EXPECT_EQ(out, occluder.selfIrradiance);
    // Without the layer nothing changes for older bundles: no selfIrradiance.
    Bundle plain = bundle;
    plain.layers.pop_back();
    EXPECT_TRUE(fivOccluder(plain, "p.glb").selfIrradiance.empty());

    auto refused = [&](const std::function<void(Layer&)>& mutate, const std::string& expected) {
        Bundle bad = bundle;
        mutate(bad.layers.back());
        ASSERT_EQ(bad.layers.back().name, "fiv_self");
        try {
            fivOccluder(bad, "bad.glb");
            ADD_FAILURE() << "accepted: " << expected;
        } catch (const Error& e) {
            EXPECT_EQ(e.exitCode(), kExitInput);
            EXPECT_NE(std::string(e.what()).find("fiv_self"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
        }
    };
    refused([](Layer& l) { l.shape[0] += 1, l.data.resize(l.data.size() + 3, 0.0f); }, "shape");
    refused([](Layer& l) { l.shape = {l.shape[0] * 3}; }, "shape");
    refused([](Layer& l) { l.componentType = "uint8", l.integers.assign(l.data.size(), 0), l.data.clear(); }, "component type");
    refused([](Layer& l) { l.data.pop_back(); }, "values");
    refused([](Layer& l) { l.data[4] = std::nanf(""); }, "non-finite");
    refused([](Layer& l) { l.data[4] = -1.0f; }, "negative");
    refused([](Layer& l) { l.semantic = "fiv_occluded_rgb"; }, "semantic");
}

TEST(FivSelf, MatchesTheBruteForceReferenceOverTheSameCube) {
    // A floor with a sphere resting above it (a concave scene, shadows both ways) under a sky with a bright patch:
    // the brute-force direct sum of lib/reference (its own rays, its own spawn rule) over the same cube, at every
    // vertex, within the spawn rules' difference at grazing texels.
    const float centre[3] = {0.3f, 0.8f, -0.2f};
    TriMesh mesh = joined(makePlane(4.0f, 16), makeSphere(0.6f, 16, 32, centre));
    CubeEnvironment env = fivtest::cubeFrom(8, [](const double* d) {
        double sky = d[1] > 0 ? 1.0 + d[1] : 0.2, patch = d[0] > 0.7 && d[1] > 0.3 ? 20.0 : 0.0;
        return std::array<double, 3>{sky + patch, sky, 0.5 * sky};
    });
    std::vector<float> e = selfIrradiance(mesh, env, {}, 2);
    DirectOptions options;
    options.threads = 2;
    options.albedo = std::array<float, 3>{1, 1, 1};
    ReferenceRadiance reference = referenceDirectRadiance(mesh, {}, cubeAsEnvironmentMap(env), options);
    double worst = 0, sum = 0, peak = 0;
    for (size_t i = 0; i < e.size(); ++i) {
        double r = reference.radiance[i] * std::numbers::pi;
        peak = std::max(peak, r);
        worst = std::max(worst, std::abs(e[i] - r));
        sum += (e[i] - r) * (e[i] - r);
    }
    EXPECT_LT(std::sqrt(sum / double(e.size())), 0.01 * peak);
    EXPECT_LT(worst, 0.1 * peak);
}
