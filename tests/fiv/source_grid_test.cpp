// The sources' own grid (sampleSourceGrid, layers fiv_source_grid / fiv_source_valid, the runtime's source term):
// a sphere hides a sun texel exactly where the ray meets it, a sphere's shadow on a plane under a one-texel sun
// sits and measures where ray casts say and is closer to them than the main grid's, the lookup is exact at nodes,
// the occluders' fractions combine as written, and the reader refuses malformed layers.
#include "fiv.h"

#include "core.h"
#include "runtime.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

using namespace prt;
using namespace prt::fiv;

namespace {

// Whether the ray from p along unit s meets the sphere (centre c, radius r); `margin` receives how far the ray's
// closest approach lies from the surface, relative to r (small: grazing).
bool rayMeetsSphere(const double p[3], const double s[3], const double c[3], double r, double* margin) {
    double v[3] = {c[0] - p[0], c[1] - p[1], c[2] - p[2]};
    double along = v[0] * s[0] + v[1] * s[1] + v[2] * s[2];
    double d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - along * along;
    *margin = std::abs(std::sqrt(std::max(d2, 0.0)) - r) / r;
    return along > 0 && d2 < r * r;
}

// An equirectangular map, black but for one texel (the sun) of radiance `sun`.
EnvironmentMap sunMap(int width, int x, int y, float sun) {
    EnvironmentMap env;
    env.radiance.width = width, env.radiance.height = width / 2;
    env.radiance.rgb.assign(size_t(width) * (width / 2) * 3, 0.0f);
    for (int c = 0; c < 3; ++c) env.radiance.rgb[3 * (size_t(y) * width + x) + size_t(c)] = sun * float(c + 1);
    return env;
}

GridSpec gridOf(int azimuth, int polar, int shells, double shellMin, double shellMax) {
    GridSpec g;
    g.azimuth = azimuth, g.polar = polar, g.shells = shells, g.shellMin = shellMin, g.shellMax = shellMax;
    return g;
}

// A FivOccluder with an empty rest (all valid, hiding nothing) and a source grid of constant fraction f.
FivOccluder constantSourceOccluder(float f, float sharpen) {
    FivOccluder o;
    o.azimuth = 4, o.polar = 3, o.shells = 2, o.radius = 1.0f;
    o.shellRadii = {2.0f, 4.0f};
    o.fiv.assign(9 * 24, 0.0f), o.power.assign(3 * 24, 0.0f), o.valid.assign(24, 1);
    FivSourceGrid& g = o.sources;
    g.azimuth = 4, g.polar = 3, g.shells = 2, g.shellRadii = {2.0f, 4.0f};
    g.fraction.assign(24, f), g.valid.assign(24, 1), g.sharpen = sharpen;
    g.power[0] = g.power[1] = g.power[2] = 1.0f;
    g.fiv[1] = g.fiv[4] = g.fiv[7] = 1.0f; // a sun straight up, power 1 per channel
    return o;
}

} // namespace

TEST(FivSourceGrid, ASphereHidesTheSunExactlyWhereTheRayMeetsItForAnyThreadCount) {
    TriMesh sphere = makeSphere(1.0f, 48, 96);
    SmallSources sources;
    const double s[3] = {0.48, 0.6, 0.64};
    sources.direction = {s[0], s[1], s[2], 0.0, 1.0, 0.0};
    sources.power = {1.0, 2.0, 3.0, 0.5, 0.5, 0.5};
    SourceGridOptions options;
    options.grid = gridOf(16, 9, 5, 0.5, 6.0);
    options.threads = 1;
    SourceGrid grid = sampleSourceGrid(sphere, sources, options, "sphere");
    options.threads = 2;
    SourceGrid again = sampleSourceGrid(sphere, sources, options, "sphere");
    EXPECT_EQ(grid.fraction, again.fraction);
    EXPECT_EQ(grid.valid, again.valid);
    for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(grid.power[size_t(c)], (c + 1) + 0.5);
    EXPECT_DOUBLE_EQ(grid.fiv[3 * 1 + 1], 2.0 * s[1] + 0.5); // green, y
    const double lum[2] = {0.2126 * 1 + 0.7152 * 2 + 0.0722 * 3, 0.5}; // the two texels' luminance power
    std::vector<double> radii = shellRadii(options.grid);
    size_t hidden = 0, invalid = 0;
    for (size_t row = 0; row < grid.fraction.size(); ++row) {
        int i = int(row % 16), j = int(row / 16 % 9), k = int(row / (16 * 9));
        double d[3];
        gridDirection(options.grid, i, j, d);
        double rho = radii[size_t(k)] * grid.sphere.radius;
        if (rho < 0.99) { // inside the unit sphere (the tessellation lies within 1e-3 of it)
            EXPECT_EQ(grid.valid[row], 0) << row;
            EXPECT_EQ(grid.fraction[row], 0.0f);
            ++invalid;
            continue;
        }
        if (rho < 1.01) continue; // on the surface: either answer
        ASSERT_EQ(grid.valid[row], 1) << row;
        double p[3] = {-rho * d[0], -rho * d[1], -rho * d[2]}, c[3] = {0, 0, 0}, m0, m1;
        bool hit0 = rayMeetsSphere(p, s, c, 1.0, &m0), hit1 = rayMeetsSphere(p, &sources.direction[3], c, 1.0, &m1);
        if (m0 < 0.01 || m1 < 0.01) continue; // grazing
        double expected = (hit0 * lum[0] + hit1 * lum[1]) / (lum[0] + lum[1]);
        EXPECT_NEAR(grid.fraction[row], expected, 1e-6) << row;
        hidden += hit0 || hit1;
    }
    EXPECT_GT(hidden, 40u);
    EXPECT_GT(invalid, 100u);
    EXPECT_GT(grid.sourceRays, 0u);
    EXPECT_GT(grid.insideRays, 0u);

    // Refused: no sources, a grid out of range, K out of range.
    EXPECT_THROW(sampleSourceGrid(sphere, {}, options, "sphere"), Error);
    SourceGridOptions bad = options;
    bad.grid.azimuth = 2;
    EXPECT_THROW(sampleSourceGrid(sphere, sources, bad, "sphere"), Error);
    bad = options;
    bad.sharpen = 0.5;
    EXPECT_THROW(sampleSourceGrid(sphere, sources, bad, "sphere"), Error);
}

// A sphere (radius 0.5, centre 1 above the plane) under a one-texel sun, nothing else in the map: the shadow S on
// the plane against the exact one from ray-sphere tests, through the real bundle path (fivBundle, fivOccluder,
// fivIrradiance), with the main grid alone (`--sources`) and with the sources' own grid, four times finer.
TEST(FivSourceGrid, ASpheresShadowUnderOneTexelSunSitsWhereTheRaysSayAndTheFinerGridIsCloserThanTheMainOne) {
    TriMesh sphere = makeSphere(0.5f, 48, 96);
    for (size_t v = 0; v < sphere.vertexCount(); ++v) sphere.positions[3 * v + 1] += 1.0f;
    EnvironmentMap env = sunMap(128, 70, 20, 2000.0f);
    EnvironmentMap residual = env;
    SmallSources sources = extractSmallSources(residual);
    ASSERT_EQ(sources.direction.size(), 3u);
    const double* s = sources.direction.data();
    ASSERT_GT(s[1], 0.3); // above the plane, tilted

    VisibilityOptions options;
    options.grid = gridOf(16, 9, 8, 0.25, 16.0);
    options.cube = 8;
    options.threads = 2;
    Visibility vis = sampleVisibility(sphere, options, "sphere");
    CubeEnvironment cube = resampleToCube(env, 32), rest = resampleToCube(residual, 8);
    std::vector<float> difmap = difMap(cube, 8);
    std::array<double, 9> fivEnv = environmentFiv(cube);
    FivGrid mainOnly = reduceVisibility(vis, rest);
    addSourceShadows(sphere, vis, sources, mainOnly, 2);
    FivGrid restGrid = reduceVisibility(vis, rest);
    SourceGridOptions so;
    so.grid = gridOf(64, 33, 32, 0.25, 16.0);
    so.threads = 2;
    SourceGrid sg = sampleSourceGrid(sphere, sources, so, "sphere");

    FivBundleOptions plain;
    plain.half = false;
    plain.difmapSize = 8;
    FivBundleOptions withGrid = plain;
    withGrid.sourceGrid = &sg;
    Bundle a = fivBundle(sphere, mainOnly, difmap, fivEnv, plain, {});
    Bundle b = fivBundle(sphere, restGrid, difmap, fivEnv, withGrid, {});
    FivOccluder oa = fivOccluder(a, "a"), ob = fivOccluder(b, "b");
    ASSERT_EQ(oa.sources.azimuth, 0);
    ASSERT_EQ(ob.sources.azimuth, 64);
    FivLighting lighting = fivLighting(a, "a");

    TriMesh plane = makePlane(4.0f, 64);
    const size_t count = plane.vertexCount();
    auto shadow = [&](const FivOccluder& o) {
        FivInstance instance{&o, {0, 0, 0}};
        std::vector<float> free(3 * count), shaded(3 * count);
        fivIrradiance(lighting, nullptr, 0, nullptr, plane.positions.data(), plane.normals.data(), count, {}, free.data());
        fivIrradiance(lighting, &instance, 1, nullptr, plane.positions.data(), plane.normals.data(), count, {}, shaded.data());
        std::vector<double> out(count);
        for (size_t v = 0; v < count; ++v) out[v] = double(free[3 * v + 1]) - shaded[3 * v + 1]; // green
        return out;
    };
    std::vector<double> sa = shadow(oa), sb = shadow(ob);
    // Exact: the sun's green irradiance 2 P max(0, N . s) where the ray toward it meets the sphere.
    // The runtime clamps at the DifMap (the cube's sun, smeared over a 2.8-degree texel): the full shadow is that.
    float freeGreen[3];
    fivDifmap(lighting, &plane.normals[0], freeGreen);
    const double sunIrradiance = std::min(sources.power[1] * s[1], double(freeGreen[1]));
    EXPECT_NEAR(sunIrradiance, sources.power[1] * s[1], 0.03 * sources.power[1] * s[1]);
    const double centre[3] = {0, 1, 0};
    double errorA = 0, errorB = 0, areaExact = 0, areaB = 0;
    size_t compared = 0, wrongB = 0;
    for (size_t v = 0; v < count; ++v) {
        double p[3] = {plane.positions[3 * v], plane.positions[3 * v + 1], plane.positions[3 * v + 2]}, margin;
        bool hit = rayMeetsSphere(p, s, centre, 0.5, &margin);
        double exact = hit ? sunIrradiance : 0.0;
        errorA += std::pow(sa[v] - exact, 2), errorB += std::pow(sb[v] - exact, 2);
        areaExact += hit, areaB += sb[v] / sunIrradiance;
        if (margin < 0.15) continue; // within a source-grid cell of the edge
        ++compared;
        wrongB += (sb[v] > 0.5 * sunIrradiance) != hit;
    }
    EXPECT_GT(areaExact, 100); // the shadow covers a few hundred of the 4,225 vertices
    EXPECT_LT(wrongB, compared / 200 + 1) << compared;           // in and out where the rays say, off the edge
    EXPECT_NEAR(areaB, areaExact, 0.08 * areaExact);              // and of the right size
    EXPECT_LT(std::sqrt(errorB), 0.6 * std::sqrt(errorA)) << std::sqrt(errorA); // closer than the main grid alone
}

TEST(FivSourceGrid, TheLookupIsExactAtNodesAndSkipsInvalidSamples) {
    TriMesh sphere = makeSphere(1.0f, 16, 32);
    SmallSources sources;
    sources.direction = {0.0, 1.0, 0.0};
    sources.power = {1.0, 1.0, 1.0};
    SourceGridOptions so;
    so.grid = gridOf(8, 5, 4, 1.5, 6.0);
    so.threads = 1;
    SourceGrid sg = sampleSourceGrid(sphere, sources, so, "s");
    std::mt19937 random(7);
    for (float& f : sg.fraction) f = std::uniform_real_distribution<float>(0, 1)(random);
    sg.valid[9] = 0;
    VisibilityOptions vo;
    vo.grid = so.grid;
    vo.cube = 2;
    FivGrid rest = reduceVisibility(sampleVisibility(sphere, vo, "s"), resampleToCube(sunMap(16, 3, 3, 0.0f), 2));
    FivBundleOptions options;
    options.half = false;
    options.difmapSize = 2;
    options.sourceGrid = &sg;
    Bundle bundle = fivBundle(sphere, rest, std::vector<float>(6 * 4 * 3, 1.0f), {}, options, {});
    FivOccluder o = fivOccluder(bundle, "b");
    ASSERT_EQ(o.sources.fraction, sg.fraction);
    std::vector<double> radii = shellRadii(so.grid);
    for (size_t row = 0; row < sg.fraction.size(); ++row) {
        int i = int(row % 8), j = int(row / 8 % 5), k = int(row / 40);
        if (j == 0 || j == 4 || !sg.valid[row]) continue; // a pole's azimuths hold different random values here
        double d[3];
        gridDirection(so.grid, i, j, d);
        float offset[3];
        for (int c = 0; c < 3; ++c) offset[c] = float(radii[size_t(k)] * sg.sphere.radius * d[c]);
        float f = -1.0f;
        ASSERT_TRUE(fivSourceLookup(o.sources, offset, &f));
        EXPECT_NEAR(f, sg.fraction[row], 2e-5f) << row;
    }
    // The invalid sample's weight goes to its neighbours: at its node the value is theirs, not its own.
    int i = 1, j = 1;
    double d[3];
    gridDirection(so.grid, i, j, d);
    float offset[3], f = -1.0f;
    for (int c = 0; c < 3; ++c) offset[c] = float(radii[0] * sg.sphere.radius * d[c]);
    ASSERT_TRUE(fivSourceLookup(o.sources, offset, &f));
    EXPECT_NE(f, sg.fraction[9]);
    EXPECT_GE(f, 0.0f);
    EXPECT_LE(f, 1.0f);
}

TEST(FivSourceGrid, OccludersFractionsCombineAsTheUnionAndSelfShadowingAddsTheSourcesBackSigned) {
    FivLighting lighting;
    lighting.difmapSize = 1;
    lighting.difmap.assign(6 * 3, 10.0f);
    lighting.fivEnv[1] = lighting.fivEnv[4] = lighting.fivEnv[7] = 3.0f;
    const float p[3] = {0, 0, 0}, n[3] = {0, 1, 0}; // occluders at shell 0 (2 above): f as stored
    auto irradiance = [&](const std::vector<FivInstance>& instances, FivOverlap overlap, const FivInstance* self = nullptr) {
        float out[3];
        fivIrradiance(lighting, instances.data(), instances.size(), self, p, n, 1, {FivPartial::Cap, overlap}, out);
        return out[1];
    };
    // f 0.75 sharpened by K 2: g = 1; by K 1: 0.75. The sun gives N . FIV_sources = 1.
    FivOccluder full = constantSourceOccluder(0.75f, 2.0f), part = constantSourceOccluder(0.75f, 1.0f);
    FivInstance above{&full, {0, 2, 0}}, partAbove{&part, {0, 2, 0}}, below{&full, {0, -2, 0}};
    EXPECT_FLOAT_EQ(irradiance({above}, FivOverlap::Cap), 9.0f);
    EXPECT_FLOAT_EQ(irradiance({partAbove}, FivOverlap::Cap), 9.25f);
    EXPECT_FLOAT_EQ(irradiance({above, above}, FivOverlap::Cap), 9.0f);             // the sun is hidden once
    EXPECT_FLOAT_EQ(irradiance({partAbove, partAbove}, FivOverlap::Paper), 10.0f - 0.9375f); // 1 - 0.25^2
    EXPECT_FLOAT_EQ(irradiance({partAbove, partAbove}, FivOverlap::None), 9.0f);   // the sum, clamped to 1
    EXPECT_FLOAT_EQ(irradiance({below}, FivOverlap::Cap), 10.0f);                  // case C hides nothing
    // Self through the grid: N . FIV(Env) - N . FIV_self (0 here) - g N . FIV_sources.
    FivInstance self{&part, {0, 2, 0}};
    EXPECT_FLOAT_EQ(irradiance({}, FivOverlap::Cap, &self), 3.0f - 0.75f);
}

TEST(FivSourceGrid, TheLayersAreReadBackAndRefusedWhenMalformed) {
    TriMesh sphere = makeSphere(0.5f, 8, 16);
    SmallSources sources;
    sources.direction = {0.6, 0.8, 0.0};
    sources.power = {1.0, 2.0, 3.0};
    SourceGridOptions so;
    so.grid = gridOf(8, 5, 3, 0.25, 8.0);
    so.threads = 1;
    SourceGrid sg = sampleSourceGrid(sphere, sources, so, "s");
    VisibilityOptions vo;
    vo.grid = gridOf(4, 3, 2, 0.25, 8.0);
    vo.cube = 2;
    FivGrid rest = reduceVisibility(sampleVisibility(sphere, vo, "s"), resampleToCube(sunMap(16, 3, 3, 0.0f), 2));
    FivBundleOptions options;
    options.half = false;
    options.difmapSize = 2;
    options.sourceGrid = &sg;
    Bundle bundle = fivBundle(sphere, rest, std::vector<float>(6 * 4 * 3, 1.0f), {}, options, {});
    FivOccluder o = fivOccluder(bundle, "b.glb");
    EXPECT_EQ(o.sources.fraction, sg.fraction);
    EXPECT_EQ(o.sources.valid, sg.valid);
    EXPECT_EQ(o.sources.azimuth, 8);
    EXPECT_FLOAT_EQ(o.sources.fiv[3 * 2 + 0], 3.0f * 0.6f);
    EXPECT_FLOAT_EQ(o.sources.power[1], 2.0f);
    EXPECT_EQ(findLayer(bundle, "fiv")->params.at("sources"), "fiv_source_grid");
    Bundle older = bundle; // without the layers: read as before
    older.layers.resize(older.layers.size() - 2);
    EXPECT_EQ(fivOccluder(older, "o.glb").sources.azimuth, 0);

    auto refused = [&](const std::function<void(Bundle&, Layer&)>& mutate, const std::string& expected) {
        Bundle bad = bundle;
        Layer* layer = nullptr;
        for (Layer& l : bad.layers)
            if (l.name == "fiv_source_grid") layer = &l;
        mutate(bad, *layer);
        try {
            fivOccluder(bad, "bad.glb");
            ADD_FAILURE() << "accepted: " << expected;
        } catch (const Error& e) {
            EXPECT_EQ(e.exitCode(), kExitInput);
            EXPECT_NE(std::string(e.what()).find("fiv_source_"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
        }
    };
    refused([](Bundle&, Layer& l) { l.shape[0] += 1, l.data.push_back(0.0f); }, "shape");
    refused([](Bundle&, Layer& l) { l.shape = {l.shape[0], 1}; }, "shape");
    refused([](Bundle&, Layer& l) { l.componentType = "uint8", l.integers.assign(l.data.size(), 0), l.data.clear(); },
            "component type");
    refused([](Bundle&, Layer& l) { l.data.pop_back(); }, "values");
    refused([](Bundle&, Layer& l) { l.data[3] = std::nanf(""); }, "non-finite");
    refused([](Bundle&, Layer& l) { l.data[3] = 1.5f; }, "outside 0..1");
    refused([](Bundle&, Layer& l) { l.data[3] = -0.25f; }, "outside 0..1");
    refused([](Bundle&, Layer& l) { l.semantic = "fiv_occluded_rgb"; }, "semantic");
    refused([](Bundle&, Layer& l) { l.params["azimuth"] = 9; }, "shape");
    refused([](Bundle&, Layer& l) { l.params["azimuth"] = "8"; }, "azimuth");
    refused([](Bundle&, Layer& l) { l.params["radius"] = 0.75; }, "radius");
    refused([](Bundle&, Layer& l) { l.params["centre"][1] = 0.5; }, "centre");
    refused([](Bundle&, Layer& l) { l.params["shell_radii"][1] = 0.1; }, "ascending");
    refused([](Bundle&, Layer& l) { l.params["sharpen"] = 0.5; }, "sharpen");
    refused([](Bundle&, Layer& l) { l.params.erase("sharpen"); }, "sharpen");
    refused([](Bundle&, Layer& l) { l.params["source_power"][0] = -1.0; }, "negative");
    refused([](Bundle&, Layer& l) { l.params["source_fiv"][2][0] = 10.0; }, "longer than source_power");
    refused([](Bundle&, Layer& l) { l.params["source_fiv"][2] = 1.0; }, "source_fiv");
    refused([](Bundle&, Layer& l) { l.params["env"] = "another"; }, "environment");
    refused([](Bundle& b, Layer&) {
        for (Layer& l : b.layers)
            if (l.name == "fiv_source_valid") l.integers[2] = 2;
    }, "0 and 1");
    refused([](Bundle& b, Layer&) {
        for (Layer& l : b.layers)
            if (l.name == "fiv_source_valid") l.shape = {l.shape[0] - 1}, l.integers.pop_back();
    }, "shape");
    refused([](Bundle& b, Layer&) { std::erase_if(b.layers, [](const Layer& l) { return l.name == "fiv_source_valid"; }); },
            "come together");
}
