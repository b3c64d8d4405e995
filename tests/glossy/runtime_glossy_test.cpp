// The glossy runtime: view weights, lobe interpolation, lobe integration against closed forms, and the loader's
// checks.
#include "glossy.h"
#include "runtime.h"
#include "render.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace {

prt::GlossyModel modelOf(int lobes, const std::vector<float>& values) {
    const prt::glossy::ViewSet& views = prt::glossy::viewSet();
    prt::GlossyModel model;
    model.vertexCount = 1;
    model.lobes = lobes;
    for (const auto& d : views.directions) model.views.insert(model.views.end(), d.begin(), d.end());
    for (const auto& t : views.triangles) model.triangles.insert(model.triangles.end(), t.begin(), t.end());
    model.values = values;
    model.positions = {0, 0, 0};
    model.normals = {0, 0, 1};
    return model;
}

std::vector<float> constantEquirect(int width, float value) {
    return std::vector<float>(size_t(width) * (width / 2) * 3, value);
}

TEST(GlossyRuntime, ViewWeightsAreBarycentricAndReproduceViews) {
    prt::GlossyModel model = modelOf(1, std::vector<float>(92 * 5, 0.0f));
    for (int v = 0; v < 92; v += 7) {
        uint32_t views[3];
        float weights[3];
        viewWeights(model, &model.views[v * 3], views, weights);
        float at = 0;
        for (int j = 0; j < 3; ++j) at += views[j] == uint32_t(v) ? weights[j] : 0.0f;
        EXPECT_NEAR(at, 1.0f, 1e-5f) << v;
    }
    const float d[3] = {0.3f, 0.5f, std::sqrt(1 - 0.34f)};
    uint32_t views[3];
    float weights[3];
    viewWeights(model, d, views, weights);
    float sum = 0;
    for (float w : weights) {
        EXPECT_GE(w, 0.0f);
        sum += w;
    }
    EXPECT_NEAR(sum, 1.0f, 1e-6f);
}

// The index (the triangles around the nearest view) finds the triangle the full scan finds: the same views with
// the same weights, for directions everywhere including on views and near edges.
TEST(GlossyRuntime, IndexedViewWeightsEqualTheFullScan) {
    prt::GlossyModel plain = modelOf(1, std::vector<float>(92 * 5, 0.0f));
    prt::GlossyModel indexed = plain;
    prt::indexViewTriangles(indexed);
    ASSERT_EQ(indexed.viewTriangleOffsets.size(), 93u);
    std::vector<std::array<float, 3>> directions;
    for (int v = 0; v < 92; ++v) directions.push_back({plain.views[v * 3], plain.views[v * 3 + 1], plain.views[v * 3 + 2]});
    for (int i = 0; i < 4000; ++i) { // a spiral over the sphere
        float z = 1.0f - 2.0f * (i + 0.5f) / 4000.0f, r = std::sqrt(1.0f - z * z), phi = 2.39996323f * i;
        directions.push_back({r * std::cos(phi), r * std::sin(phi), z});
    }
    for (size_t t = 0; t < plain.triangles.size(); t += 3) { // edge midpoints
        const float* a = &plain.views[plain.triangles[t] * 3];
        const float* b = &plain.views[plain.triangles[t + 1] * 3];
        float m[3] = {a[0] + b[0], a[1] + b[1], a[2] + b[2]}, l = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        directions.push_back({m[0] / l, m[1] / l, m[2] / l});
    }
    for (const auto& d : directions) {
        uint32_t va[3], vb[3];
        float wa[3], wb[3];
        viewWeights(plain, d.data(), va, wa);
        viewWeights(indexed, d.data(), vb, wb);
        // The same weight per view (a view of weight 0 may differ between two triangles sharing an edge).
        for (int j = 0; j < 3; ++j) {
            float other = 0.0f;
            for (int k = 0; k < 3; ++k) other += vb[k] == va[j] ? wb[k] : 0.0f;
            EXPECT_NEAR(other, wa[j], 1e-6f);
        }
    }
}

TEST(GlossyRuntime, InterpolationBlendsLinearlyNormalisedAndInLog) {
    std::vector<float> values(92 * 5, 0.0f);
    for (int v = 0; v < 92; ++v) {
        float* lobe = &values[v * 5];
        lobe[0] = 2.0f, lobe[1] = 0.0f, lobe[2] = 0.0f, lobe[3] = 1.0f, lobe[4] = 30.0f;
    }
    values[1 * 5 + 0] = 4.0f, values[1 * 5 + 4] = 120.0f, values[1 * 5 + 1] = 1.0f, values[1 * 5 + 3] = 0.0f;
    prt::GlossyModel model = modelOf(1, values);
    const uint32_t views[3] = {0, 1, 2};
    const float weights[3] = {0.5f, 0.5f, 0.0f};
    float lobe[5];
    interpolateLobe(model, 0, 0, views, weights, lobe);
    EXPECT_FLOAT_EQ(lobe[0], 3.0f);
    EXPECT_NEAR(lobe[4], 60.0f, 1e-3f); // geometric mean of 30 and 120
    EXPECT_NEAR(lobe[1] * lobe[1] + lobe[2] * lobe[2] + lobe[3] * lobe[3], 1.0f, 1e-6f);
    EXPECT_NEAR(lobe[1], std::sqrt(0.5f), 1e-6f);
    const uint32_t same[3] = {3, 4, 5};
    const float third[3] = {0.2f, 0.3f, 0.5f};
    interpolateLobe(model, 0, 0, same, third, lobe);
    EXPECT_FLOAT_EQ(lobe[0], 2.0f);
    EXPECT_NEAR(lobe[4], 30.0f, 1e-4f);
    EXPECT_FLOAT_EQ(lobe[3], 1.0f);
}

// A lobe on its view's mirror direction is turned onto the eye's mirror direction; amplitude and sharpness stay.
TEST(GlossyRuntime, TurnedLobesFollowTheMirrorDirection) {
    const prt::glossy::ViewSet& views = prt::glossy::viewSet();
    std::vector<float> values(92 * 2 * 5, 0.0f);
    for (int v = 0; v < 92; ++v) {
        const auto& w = views.directions[v];
        float mirror[3] = {-w[0], -w[1], w[2]}; // about the normal (0, 0, 1)
        float* lobe = &values[v * 10];
        lobe[0] = 2.0f, lobe[1] = mirror[0], lobe[2] = mirror[1], lobe[3] = mirror[2], lobe[4] = 40.0f;
        lobe[5] = 1.0f, lobe[6] = 0.0f, lobe[7] = 0.0f, lobe[8] = 1.0f, lobe[9] = 8.0f; // along the normal
    }
    prt::GlossyModel model = modelOf(2, values);
    const float length = std::sqrt(0.36f * 0.36f + 0.933f * 0.933f);
    const float target[3] = {0.36f / length, 0.0f, 0.933f / length};
    float turned[10];
    for (uint32_t v : {0u, 17u, 50u}) {
        if (views.directions[v][2] <= 0.0f) continue;
        prt::turnViewLobes(model, 0, v, target, turned);
        EXPECT_NEAR(turned[1], target[0], 1e-5f) << v;
        EXPECT_NEAR(turned[3], target[2], 1e-5f) << v;
        EXPECT_EQ(turned[0], 2.0f);
        EXPECT_EQ(turned[4], 40.0f);
        EXPECT_NEAR(turned[5 + 1] * turned[5 + 1] + turned[5 + 2] * turned[5 + 2] + turned[5 + 3] * turned[5 + 3], 1.0f, 1e-5f);
    }
}

// The runtime pairs no lobe of one view with a lobe of another: swapping the order of one view's lobes changes
// nothing (a parameter blend would pair lobe k of every view).
TEST(GlossyRuntime, GlossyRadianceDoesNotDependOnLobeOrder) {
    const prt::glossy::ViewSet& views = prt::glossy::viewSet();
    std::vector<float> values(92 * 2 * 5, 0.0f);
    for (int v = 0; v < 92; ++v) {
        const auto& w = views.directions[v];
        float* lobe = &values[v * 10];
        lobe[0] = 1.0f, lobe[1] = -w[0], lobe[2] = -w[1], lobe[3] = w[2], lobe[4] = 30.0f;
        lobe[5] = 0.3f, lobe[6] = 0.6f, lobe[7] = 0.0f, lobe[8] = 0.8f, lobe[9] = 5.0f;
    }
    std::vector<float> map(128 * 64 * 3);
    for (size_t i = 0; i < map.size(); ++i) map[i] = 0.5f + 0.5f * float(std::sin(0.01 * double(i)));
    prt::PrefilteredEnvironment env = prt::prefilterEnvironment(map.data(), 128, 64);
    const float eye[3] = {1.0f, 0.5f, 4.0f};
    prt::GlossyModel model = modelOf(2, values);
    float before[3], after[3];
    prt::glossyRadiance(model, env, eye, before);
    for (int v = 0; v < 92; v += 2) std::swap_ranges(&values[v * 10], &values[v * 10 + 5], &values[v * 10 + 5]);
    model = modelOf(2, values);
    prt::glossyRadiance(model, env, eye, after);
    EXPECT_GT(before[0], 0.0f);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(after[c], before[c], 1e-6f * before[c]) << c;
}

TEST(GlossyRuntime, LobeIntegralUnderConstantAndGaussianLight) {
    // Constant L: a L 2 pi (1 - exp(-2 l)) / l, for wide and sharp lobes.
    // integrateLobe reads only the box chain: no stack (prefilter_test.cpp tests the stack's lookups).
    prt::PrefilterOptions boxesOnly;
    boxesOnly.sharpnessMin = 2.0, boxesOnly.sharpnessMax = 1.0;
    prt::PrefilteredEnvironment constant =
        prt::prefilterEnvironment(constantEquirect(512, 1.5f).data(), 512, 256, boxesOnly);
    for (float sharpness : {2.0f, 30.0f, 400.0f, 3000.0f}) {
        const float lobe[5] = {2.0f, 0.6f, 0.0f, 0.8f, sharpness};
        float radiance[3];
        integrateLobe(constant, lobe, radiance);
        double expected = 2.0 * 1.5 * 2 * std::numbers::pi * (1 - std::exp(-2.0 * sharpness)) / sharpness;
        EXPECT_NEAR(radiance[1], expected, 0.01 * expected) << sharpness;
    }
    // A Gaussian environment exp(lL (d . w - 1)): the SG inner-product closed form.
    const int width = 1024, height = 512;
    std::vector<float> rgb(size_t(width) * height * 3);
    const double d[3] = {0.0, 0.6, -0.8}, lightSharpness = 50.0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            double t = std::numbers::pi * (y + 0.5) / height, p = 2 * std::numbers::pi * (x + 0.5) / width - std::numbers::pi;
            double w[3] = {std::sin(t) * std::sin(p), std::cos(t), -std::sin(t) * std::cos(p)};
            float value = float(std::exp(lightSharpness * (d[0] * w[0] + d[1] * w[1] + d[2] * w[2] - 1)));
            for (int c = 0; c < 3; ++c) rgb[(size_t(y) * width + x) * 3 + c] = value;
        }
    prt::PrefilteredEnvironment gaussian = prt::prefilterEnvironment(rgb.data(), width, height, boxesOnly);
    const double mu[3] = {0.0, 0.8, -0.6}, sharpness = 80.0;
    const float lobe[5] = {1.0f, float(mu[0]), float(mu[1]), float(mu[2]), float(sharpness)};
    float radiance[3];
    integrateLobe(gaussian, lobe, radiance);
    double m[3], lm = 0;
    for (int c = 0; c < 3; ++c) m[c] = sharpness * mu[c] + lightSharpness * d[c], lm += m[c] * m[c];
    lm = std::sqrt(lm);
    double expected = 2 * std::numbers::pi * std::exp(lm - sharpness - lightSharpness) * (1 - std::exp(-2 * lm)) / lm;
    EXPECT_NEAR(radiance[0], expected, 0.01 * expected);
}

TEST(GlossyRuntime, LoaderRefusesALobeLayerThatDisagreesWithItsViewSet) {
    prt::Bundle bundle;
    bundle.mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    bundle.mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    bundle.mesh.indices = {0, 1, 2};
    prt::glossy::GlossyLobes lobes;
    lobes.lobes = 1;
    lobes.vertexEnd = 3;
    lobes.values.assign(3 * 92 * 5, 1.0f);
    prt::Layer layer = prt::glossy::lobeLayer(lobes, prt::glossy::GlossyOptions{}, 3);
    bundle.layers.push_back(layer);
    EXPECT_NO_THROW(prt::glossyModel(bundle, "b.glb"));
    bundle.layers[0].params["views"].erase(91);
    try {
        prt::glossyModel(bundle, "b.glb");
        FAIL();
    } catch (const prt::Error& e) {
        EXPECT_NE(e.problem().find("disagrees"), std::string::npos) << e.what();
    }
    bundle.layers[0] = layer;
    bundle.layers[0].shape[2] = 5;
    EXPECT_THROW(prt::glossyModel(bundle, "b.glb"), prt::Error);
}

// Crash classes of untrusted glossy bundles (issue 20): view triangles that leave part of the sphere uncovered
// left viewWeights' outputs unset (SIGSEGV), and a lobe layer of an integer type left the float storage empty.
// Each must be refused by the loader with a message naming the layer.
TEST(GlossyRuntime, LoaderRefusesViewTrianglesThatDoNotTileTheSphereAndLobesOfAnIntegerType) {
    prt::Bundle bundle;
    bundle.mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    bundle.mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    bundle.mesh.indices = {0, 1, 2};
    prt::glossy::GlossyLobes lobes;
    lobes.lobes = 1;
    lobes.vertexEnd = 3;
    lobes.values.assign(3 * 92 * 5, 1.0f);
    const prt::Layer layer = prt::glossy::lobeLayer(lobes, prt::glossy::GlossyOptions{}, 3);
    auto refused = [&](const prt::Layer& bad, const std::string& words) {
        bundle.layers = {bad};
        try {
            prt::glossyModel(bundle, "b.glb");
            ADD_FAILURE() << "accepted: " << words;
        } catch (const prt::Error& e) {
            EXPECT_EQ(e.exitCode(), prt::kExitInput);
            EXPECT_NE(std::string(e.what()).find("glossy_lobes"), std::string::npos) << e.what();
            EXPECT_NE(e.problem().find(words), std::string::npos) << e.what();
        }
    };
    prt::Layer holed = layer; // one triangle fewer: a hole
    holed.params["view_triangles"].erase(holed.params["view_triangles"].size() - 1);
    refused(holed, "hole");
    prt::Layer twice = layer; // the first triangle twice, the last one gone: closed count, wrong cover
    twice.params["view_triangles"].back() = twice.params["view_triangles"][0];
    refused(twice, "view triangles");
    prt::Layer flipped = layer; // one triangle clockwise
    std::swap(flipped.params["view_triangles"][3][1], flipped.params["view_triangles"][3][2]);
    refused(flipped, "counter-clockwise");
    prt::Layer single = layer; // only one triangle, all three of its corners on valid views
    single.params["view_triangles"] = nlohmann::json::array({layer.params["view_triangles"][0]});
    refused(single, "hole");
    prt::Layer integers = layer; // the values in the integer storage, the float storage empty
    integers.componentType = "uint8";
    integers.data.clear();
    integers.integers.assign(3 * 92 * 5, 1u);
    refused(integers, "component type");
    bundle.layers = {layer};
    EXPECT_NO_THROW(prt::glossyModel(bundle, "b.glb"));
}

} // namespace

namespace {

// A square of two triangles in the plane y = 0 (normal +Y), every vertex and view with one lobe along the view's
// mirror direction: identical lobes everywhere, so the glossy radiance at a point depends only on its view direction.
prt::GlossyModel mirrorLobePlane(const prt::TriMesh& plane, float sharpness) {
    const prt::glossy::ViewSet& views = prt::glossy::viewSet();
    prt::GlossyModel model;
    model.vertexCount = uint32_t(plane.vertexCount());
    model.lobes = 1;
    for (const auto& d : views.directions) model.views.insert(model.views.end(), d.begin(), d.end());
    for (const auto& t : views.triangles) model.triangles.insert(model.triangles.end(), t.begin(), t.end());
    model.positions = plane.positions;
    model.normals = plane.normals;
    for (uint32_t v = 0; v < model.vertexCount; ++v)
        for (const auto& w : views.directions) {
            const float mirror[3] = {-w[0], w[1], -w[2]}; // about +Y
            model.values.insert(model.values.end(), {1.0f, mirror[0], mirror[1], mirror[2], sharpness});
        }
    return model;
}

} // namespace

TEST(GlossyRender, LobesAreEvaluatedPerPixelTowardEachPixelsOwnViewDirection) {
    prt::TriMesh plane = prt::makePlane(2.0f, 1, 0.0f);
    prt::GlossyModel model = mirrorLobePlane(plane, 60.0f);
    // A map whose radiance varies with direction: brighter toward +X and up.
    const int width = 64, height = 32;
    std::vector<float> rgb(size_t(width) * height * 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c) rgb[(size_t(y) * width + x) * 3 + c] = 0.2f + float(x) / width + 0.5f * float(height - y) / height;
    prt::PrefilteredEnvironment env = prt::prefilterEnvironment(rgb.data(), width, height);
    prt::EnvironmentMap map;
    map.radiance = {width, height, rgb};
    prt::PinholeCamera camera;
    camera.eye = {0.3f, 1.2f, 2.0f};
    camera.target = {0.0f, 0.0f, 0.0f};
    camera.fovyDegrees = 50.0f;
    camera.width = 32;
    camera.height = 24;
    prt::RenderedImage picture = prt::renderGlossyRadiance(plane, {}, model, map, "map", camera, true);
    // Per vertex toward the eye, interpolated: what the per-pixel picture replaces.
    std::vector<float> vertexGlossy(plane.vertexCount() * 3);
    prt::glossyRadiance(model, env, camera.eye.data(), vertexGlossy.data());
    prt::RenderedImage perVertex = prt::renderVertexRadiance(plane, vertexGlossy, camera);
    const prt::PinholeRays rays = prt::pinholeRays(camera);
    size_t covered = 0;
    double largestVertexDifference = 0.0;
    for (size_t pixel = 0; pixel < picture.coverage.size(); ++pixel) {
        if (picture.coverage[pixel] < 0.5f) continue;
        ++covered;
        // The hit point on y = 0 and the direction from it to the eye, by hand.
        float d[3];
        prt::pinholeRayDirection(rays, pixel, d);
        const float t = -camera.eye[1] / d[1];
        float view[3];
        for (int a = 0; a < 3; ++a) view[a] = -t * d[a];
        const float length = std::sqrt(view[0] * view[0] + view[1] * view[1] + view[2] * view[2]);
        for (float& a : view) a /= length;
        float expected[3];
        prt::glossyRadianceToward(model, env, 0, view, expected);
        for (int c = 0; c < 3; ++c) {
            const float got = picture.radiance.rgb[pixel * 3 + c];
            ASSERT_NEAR(got, expected[c], 1e-3f * std::max(1.0f, expected[c])) << "pixel " << pixel;
            largestVertexDifference =
                std::max(largestVertexDifference, std::fabs(double(perVertex.radiance.rgb[pixel * 3 + c]) - got) / got);
        }
    }
    EXPECT_GT(covered, 200u);
    // Interpolating the corners' radiance instead misses how the highlight moves inside the triangles.
    EXPECT_GT(largestVertexDifference, 0.02);
}
