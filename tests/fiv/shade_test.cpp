// The runtime's FIV shading: the seed's cases against a sphere occluder's closed form, interpolation at nodes,
// across the azimuth seam and at the poles, the partial and overlap corrections' invariants, self-shadowing of a
// flat top face, clamping, translation invariance, and grids whose size disagrees with their header.
#include "fiv.h"
#include "fiv_test_util.h"

#include "core.h"
#include "runtime.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

using namespace prt;
using prt::fivtest::cubeFrom;
using prt::fivtest::makeBox;

namespace {

constexpr double kPi = std::numbers::pi;

struct Scene {
    Bundle bundle;
    FivOccluder occluder;
    FivLighting lighting;
};

// A FIV bundle in memory (no file) of `mesh` under a constant white map.
Scene build(const TriMesh& mesh, fiv::GridSpec grid, int supersample = 1) {
    fiv::VisibilityOptions options;
    options.grid = grid;
    options.cube = 32;
    options.supersample = supersample;
    fiv::Visibility vis = fiv::sampleVisibility(mesh, options, "test");
    fiv::CubeEnvironment env = cubeFrom(32, [](const double*) { return std::array<double, 3>{1, 1, 1}; });
    fiv::FivGrid fivGrid = fiv::reduceVisibility(vis, env);
    fiv::FivBundleOptions bundleOptions;
    bundleOptions.difmapSize = 16;
    Scene s;
    s.bundle = fiv::fivBundle(mesh, fivGrid, fiv::difMap(env, 16), fiv::environmentFiv(env), bundleOptions, {});
    s.occluder = fivOccluder(s.bundle, "test");
    s.lighting = fivLighting(s.bundle, "test");
    return s;
}

fiv::GridSpec sphereGrid() {
    fiv::GridSpec grid;
    grid.azimuth = 16, grid.polar = 9, grid.shells = 6, grid.shellMin = 0.5, grid.shellMax = 6.0;
    return grid;
}

const Scene& sphereScene() {
    static Scene scene = build(makeSphere(1.0f, 32, 64), sphereGrid(), 2);
    return scene;
}

float shade(const Scene& s, const std::vector<FivInstance>& instances, const float p[3], const float n[3],
            FivShadeOptions options = {}, const FivInstance* self = nullptr) {
    float out[3];
    fivIrradiance(s.lighting, instances.data(), instances.size(), self, p, n, 1, options, out);
    return out[0];
}

} // namespace

TEST(FivShade, CaseAMatchesTheSphereClosedFormAndCaseCIgnoresTheOccluder) {
    const Scene& s = sphereScene();
    float up[3] = {0, 1, 0}, origin[3] = {0, 0, 0};
    std::vector<double> radii = fiv::shellRadii(sphereGrid());
    double R = s.occluder.radius;
    for (int k : {2, 3, 4}) { // centres straight above, on the pole row, at a shell: case A
        double D = radii[size_t(k)] * R;
        FivInstance instance{&s.occluder, {0.0f, float(D), 0.0f}};
        float I = shade(s, {instance}, origin, up);
        double exact = kPi - kPi / (D * D);
        EXPECT_NEAR(I, exact, 0.02 * kPi) << D;
    }
    // Below the tangent plane by more than R: case C, the DifMap alone.
    FivInstance below{&s.occluder, {0.0f, -1.5f * float(R), 0.0f}};
    float total[3];
    fivDifmap(s.lighting, up, total);
    EXPECT_EQ(shade(s, {below}, origin, up), total[0]);
    EXPECT_NEAR(total[0], kPi, 1e-3 * kPi);
}

TEST(FivShade, InterpolationIsExactAtNodesPeriodicInAzimuthAndConsistentAtPoles) {
    const Scene& s = sphereScene();
    const FivOccluder& o = s.occluder;
    float fiv[9], power[3];
    size_t row = (size_t(3) * o.polar + 3) * o.azimuth + 5;
    double theta = kPi * 3 / (o.polar - 1), phi = 2 * kPi * 5 / o.azimuth, rho = o.shellRadii[3];
    float offset[3] = {float(rho * std::sin(theta) * std::sin(phi)), float(rho * std::cos(theta)),
                       float(-rho * std::sin(theta) * std::cos(phi))};
    ASSERT_TRUE(fivLookup(o, offset, fiv, power));
    for (int e = 0; e < 9; ++e) EXPECT_NEAR(fiv[e], o.fiv[9 * row + e], 1e-4 * std::abs(o.fiv[9 * row + e]) + 1e-7);

    // Just either side of the azimuth seam (phi = 0 = 2 pi): nearly the same value.
    auto at = [&](double t, double p, float out[9]) {
        float v[3] = {float(rho * std::sin(t) * std::sin(p)), float(rho * std::cos(t)), float(-rho * std::sin(t) * std::cos(p))};
        fivLookup(o, v, out, power);
    };
    float left[9], right[9], pole[9], pole2[9];
    at(theta, 1e-4, right);
    at(theta, 2 * kPi - 1e-4, left);
    float largest = 0.0f;
    for (int e = 0; e < 9; ++e) largest = std::max(largest, std::abs(right[e]));
    for (int e = 0; e < 9; ++e) EXPECT_NEAR(left[e], right[e], 1e-3 * largest);
    at(1e-6, 0.3, pole);
    at(1e-6, 4.0, pole2);
    for (int e = 0; e < 9; ++e) EXPECT_NEAR(pole[e], pole2[e], 1e-4 * (std::abs(pole[e]) + 1e-3));
}

TEST(FivShade, PartialCorrectionsAreContinuousAndClampingHolds) {
    const Scene& s = sphereScene();
    float origin[3] = {0, 0, 0};
    double R = s.occluder.radius;
    // The centre 2R away, its tangent-plane height d swept through (-R, R): every mode stays in [0, I_tot], and
    // literal and cap meet case A at d = R and the DifMap at d = -R.
    for (FivPartial partial : {FivPartial::None, FivPartial::Literal, FivPartial::Cap}) {
        FivShadeOptions options;
        options.partial = partial;
        for (double d = -1.0; d <= 1.0; d += 0.125) {
            double angle = std::asin(d / 2.0);
            float n[3] = {0, 1, 0};
            FivInstance instance{&s.occluder, {float(2 * R * std::cos(angle)), float(2 * R * std::sin(angle)), 0.0f}};
            float I = shade(s, {instance}, origin, n, options);
            EXPECT_GE(I, 0.0f);
            EXPECT_LE(I, float(kPi) * 1.001f);
            if (d == 1.0 || d == -1.0) {
                FivShadeOptions none;
                none.partial = FivPartial::None;
                EXPECT_NEAR(I, shade(s, {instance}, origin, n, none), 1e-3) << int(partial) << " " << d;
            }
        }
    }
    EXPECT_NEAR(clippedCapIrradiance(0.8, 0.25), kPi * 0.25 * 0.8, 1e-12); // wholly above
    EXPECT_NEAR(clippedCapIrradiance(0.3, 1.0), kPi / 2 * 1.3, 1e-9);     // hemisphere cap
    EXPECT_NEAR(clippedCapIrradiance(-0.9, 0.1), 0.0, 1e-12);             // wholly below
}

TEST(FivShade, OverlapCorrectionCountsCoincidentOccludersOnceAndIsSymmetric) {
    EXPECT_EQ(discOverlap(1.0, 1.0, 2.5), 0.0);
    EXPECT_NEAR(discOverlap(0.5, 1.0, 0.2), kPi * 0.25, 1e-12);
    EXPECT_NEAR(discOverlap(0.7, 0.4, 0.8), discOverlap(0.4, 0.7, 0.8), 1e-12);
    const Scene& s = sphereScene();
    float origin[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    FivInstance a{&s.occluder, {0.3f, 3.0f, 0.0f}}, b{&s.occluder, {-0.4f, 3.2f, 0.2f}};
    float one = shade(s, {a}, origin, up);
    for (FivOverlap overlap : {FivOverlap::Paper, FivOverlap::Shared, FivOverlap::Cap}) {
        FivShadeOptions options;
        options.overlap = overlap;
        EXPECT_NEAR(shade(s, {a, a}, origin, up, options), one, 1e-5);
        EXPECT_NEAR(shade(s, {a, b}, origin, up, options), shade(s, {b, a}, origin, up, options), 1e-5);
    }
    FivShadeOptions none;
    none.overlap = FivOverlap::None;
    float total[3];
    fivDifmap(s.lighting, up, total);
    EXPECT_NEAR(total[0] - shade(s, {a, a}, origin, up, none), 2 * (total[0] - one), 1e-4);
    // Far apart (disjoint discs): the sum, with or without the correction.
    FivInstance c{&s.occluder, {6.0f, 3.0f, 0.0f}};
    EXPECT_NEAR(shade(s, {a, c}, origin, up), shade(s, {a, c}, origin, up, none), 1e-6);
}

TEST(FivShade, SelfShadowOfAFlatTopFaceSeesTheWholeUpperHemisphere) {
    // A point on the top face of a box: the box hides the lower hemisphere, so I = N . 0 - N . (-pi N) = pi.
    fiv::GridSpec grid;
    grid.azimuth = 16, grid.polar = 17, grid.shells = 8, grid.shellMin = 0.3, grid.shellMax = 4.0;
    Scene s = build(makeBox(-1.0f, 1.0f), grid);
    FivInstance self{&s.occluder, {0, 0, 0}};
    for (float x : {0.0f, 0.3f, -0.5f}) {
        float p[3] = {x, 1.0f, 0.2f}, n[3] = {0, 1, 0};
        float I = shade(s, {}, p, n, {}, &self);
        EXPECT_NEAR(I, kPi, 0.08 * kPi) << x; // samples just above the face see past its edges
        EXPECT_LE(I, kPi * 1.001);
    }
}

TEST(FivShade, TranslatingEverythingTogetherChangesNothing) {
    const Scene& s = sphereScene();
    std::mt19937 random(5);
    std::uniform_real_distribution<float> u(-3.0f, 3.0f);
    for (int trial = 0; trial < 20; ++trial) {
        float p[3] = {u(random), u(random), u(random)}, shift[3] = {1.0f, -2.0f, 0.5f};
        float n[3] = {u(random), u(random), u(random)};
        float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (float& v : n) v /= length;
        FivInstance a{&s.occluder, {u(random), u(random), u(random)}};
        FivInstance b = a;
        float q[3];
        for (int c = 0; c < 3; ++c) b.translation[c] += shift[c], q[c] = p[c] + shift[c];
        float I = shade(s, {a}, p, n), J = shade(s, {b}, q, n);
        EXPECT_NEAR(I, J, 1e-4);
        float total[3];
        fivDifmap(s.lighting, n, total);
        EXPECT_GE(I, 0.0f);
        EXPECT_LE(I, total[0]);
    }
}

TEST(FivShade, RefusesAGridWhoseSizeDisagreesWithItsHeader) {
    Bundle bundle = sphereScene().bundle;
    for (Layer& layer : bundle.layers)
        if (layer.name == "fiv") layer.params["shells"] = 7;
    try {
        fivOccluder(bundle, "bad.fiv.glb");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("disagrees with the grid header"), std::string::npos);
        EXPECT_EQ(e.exitCode(), kExitInput);
    }
}

TEST(FivShade, FarOccludersLookUpWithoutOverflowAndScenesRefuseTranslationsPastTheBound) {
    // An occluder 1e30 away: the float squared distance would be inf (the receiver went black); in double the
    // lookup is the far-field value, and the receiver keeps its unoccluded light.
    const Scene& s = sphereScene();
    float p[3] = {0, 0, 0}, n[3] = {0, 1, 0}, unoccluded[3];
    fivDifmap(s.lighting, n, unoccluded);
    float offset[3] = {0, 1e30f, 0}, fiv[9], power[3];
    ASSERT_TRUE(fivLookup(s.occluder, offset, fiv, power));
    for (float v : fiv) EXPECT_TRUE(std::isfinite(v));
    EXPECT_LT(std::abs(fiv[1]), 1e-20f);
    FivInstance far{&s.occluder, {0, 1e30f, 0}};
    EXPECT_NEAR(shade(s, {far}, p, n), unoccluded[0], 1e-6 * unoccluded[0]);
    // A scene whose instance translation is past kFivMaxCoordinate (or not finite) is refused.
    Bundle scene = s.bundle;
    scene.meshRole = "receiver";
    scene.objects.push_back({"occluder", "occluder", scene.mesh});
    for (Layer& layer : scene.layers)
        if (layer.name == "fiv" || layer.name == "fiv_power" || layer.name == "fiv_valid") {
            layer.object = 1;
            layer.name = objectLayerName(layer.name, 1);
        }
    scene.instances = {{"receiver", 0, {0, 0, 0}}, {"a", 1, {0, 2, 0}}};
    EXPECT_NO_THROW(fivScene(scene, "scene.glb"));
    for (float bad : {2e9f, INFINITY, NAN}) {
        scene.instances[1].translation = {0, bad, 0};
        try {
            fivScene(scene, "scene.glb");
            ADD_FAILURE() << bad;
        } catch (const Error& e) {
            EXPECT_EQ(e.exitCode(), kExitInput);
            EXPECT_EQ(e.file(), "scene.glb");
        }
    }
    scene.instances[1] = {"b", 7, {0, 2, 0}}; // an object the bundle does not hold
    EXPECT_THROW(fivScene(scene, "scene.glb"), Error);
}
