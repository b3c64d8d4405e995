// Closed forms of the FIV precompute (seed notes section 7): cube solid angles, DifMap and FIV(Env) of constant
// and random maps, the hemisphere identity, linearity and complement, rotation covariance, a sphere occluder's
// exact FIV, inside flags, open meshes, shards and threads, storage per sample.
#include "fiv.h"
#include "fiv_test_util.h"

#include "core.h"
#include "scene.h"
#include "sh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

using namespace prt;
using namespace prt::fiv;
using prt::fivtest::cubeFrom;
using prt::fivtest::makeBox;

namespace {

constexpr double kPi = std::numbers::pi;

std::array<double, 3> constant(const double*) { return {1.0, 2.0, 0.5}; }

// Index of the texel whose centre is -direction of texel t.
size_t antipode(const CubeTexels& cube, size_t t) {
    size_t best = 0;
    double bestDot = 2.0;
    for (size_t u = 0; u < cube.solidAngle.size(); ++u) {
        double dot = 0.0;
        for (int c = 0; c < 3; ++c) dot += cube.direction[3 * t + c] * cube.direction[3 * u + c];
        if (dot < bestDot) bestDot = dot, best = u;
    }
    return best;
}

VisibilityOptions smallGrid(int supersample = 1) {
    VisibilityOptions options;
    options.grid.azimuth = 8;
    options.grid.polar = 5;
    options.grid.shells = 4;
    options.grid.shellMin = 0.5;
    options.grid.shellMax = 6.0;
    options.cube = 16;
    options.supersample = supersample;
    return options;
}

} // namespace

TEST(FivCube, SolidAnglesSumToFourPiAndCentresMatchTheConvention) {
    CubeTexels cube = cubeTexels(32);
    double sum = 0.0, lo = 1e9, hi = 0.0;
    for (double w : cube.solidAngle) sum += w, lo = std::min(lo, w), hi = std::max(hi, w);
    EXPECT_NEAR(sum, 4.0 * kPi, 1e-12);
    EXPECT_NEAR(hi / lo, 4.86, 0.02);
    for (size_t t = 0; t < cube.solidAngle.size(); t += 97) {
        double d[3];
        sh::cubeStripDirection(32, double(t % 32), double(t / 32), d);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(cube.direction[3 * t + c], d[c], 1e-12);
    }
}

TEST(FivCube, ConstantMapGivesPiLIrradianceAndZeroFiv) {
    CubeEnvironment env = cubeFrom(32, constant);
    std::vector<float> dif = difMap(env, 8);
    for (size_t n = 0; n < dif.size() / 3; ++n)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(dif[3 * n + c], kPi * constant(nullptr)[size_t(c)], 4e-4 * kPi * 2);
    for (double v : environmentFiv(env)) EXPECT_NEAR(v, 0.0, 1e-12);
}

TEST(FivCube, HemisphereIdentityHoldsForARandomMap) {
    std::mt19937 random(7);
    std::uniform_real_distribution<double> u(0.0, 5.0);
    CubeEnvironment env = cubeFrom(8, [&](const double*) { return std::array<double, 3>{u(random), u(random), u(random)}; });
    std::vector<float> dif = difMap(env, 8);
    std::array<double, 9> fiv = environmentFiv(env);
    CubeTexels cube = cubeTexels(8);
    for (size_t t = 0; t < cube.solidAngle.size(); t += 5) {
        size_t a = antipode(cube, t);
        const double* n = &cube.direction[3 * t];
        for (int c = 0; c < 3; ++c) {
            double fi = n[0] * fiv[size_t(3 * c)] + n[1] * fiv[size_t(3 * c + 1)] + n[2] * fiv[size_t(3 * c + 2)];
            EXPECT_NEAR(double(dif[3 * t + c]) - dif[3 * a + c], fi, 1e-4 * std::abs(dif[3 * t + c]) + 1e-5);
            EXPECT_GE(dif[3 * t + c], fi - 1e-4);
        }
    }
}

TEST(FivCube, RotatingTheMapRotatesFivAndDifMap) {
    // 90 degrees about +Y permutes the cube's texel centres, so the discrete sums permute exactly.
    auto f = [](const double* d) { return std::array<double, 3>{1.0 + d[0] + 0.5 * d[2] * d[2], 2.0 + d[1] * d[2], 1.5 + d[2]}; };
    auto rotated = [&](const double* d) { double back[3] = {-d[2], d[1], d[0]}; return f(back); }; // f(Q^T d)
    CubeEnvironment a = cubeFrom(8, f), b = cubeFrom(8, rotated);
    std::array<double, 9> fa = environmentFiv(a), fb = environmentFiv(b);
    for (int c = 0; c < 3; ++c) { // Q (x, y, z) = (z, y, -x)
        EXPECT_NEAR(fb[size_t(3 * c)], fa[size_t(3 * c + 2)], 1e-10);
        EXPECT_NEAR(fb[size_t(3 * c + 1)], fa[size_t(3 * c + 1)], 1e-10);
        EXPECT_NEAR(fb[size_t(3 * c + 2)], -fa[size_t(3 * c)], 1e-10);
    }
    std::vector<float> da = difMap(a, 8), db = difMap(b, 8);
    CubeTexels cube = cubeTexels(8);
    for (size_t t = 0; t < cube.solidAngle.size(); t += 7) { // DifMap_b(N) = DifMap_a(Q^T N)
        const double* n = &cube.direction[3 * t];
        double back[3] = {-n[2], n[1], n[0]};
        size_t u = 0;
        for (; u < cube.solidAngle.size(); ++u)
            if (std::abs(cube.direction[3 * u] - back[0]) + std::abs(cube.direction[3 * u + 1] - back[1]) +
                    std::abs(cube.direction[3 * u + 2] - back[2]) < 1e-9)
                break;
        ASSERT_LT(u, cube.solidAngle.size());
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(db[3 * t + c], da[3 * u + c], 1e-4 * da[3 * u + c]);
    }
}

TEST(FivGrid, RefusesZeroAndAbsurdDimensions) {
    GridSpec grid;
    grid.polar = 0;
    EXPECT_THROW(checkGrid(grid, "x", kExitUsage), Error);
    grid = GridSpec();
    grid.azimuth = 4096, grid.polar = 2049, grid.shells = 1000;
    try {
        checkGrid(grid, "x", kExitUsage);
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("samples"), std::string::npos);
    }
    grid = GridSpec();
    grid.shellMin = 2.0, grid.shellMax = 1.0;
    EXPECT_THROW(checkGrid(grid, "x", kExitUsage), Error);
    std::vector<double> radii = shellRadii(GridSpec());
    EXPECT_DOUBLE_EQ(radii.front(), 0.25);
    EXPECT_NEAR(radii.back(), 8.0, 1e-12);
}

TEST(FivVisibility, SphereOccluderHasTheExactFiv) {
    // A sphere of radius R at distance D hides a cap with sin(alpha) = R / D: FIV = pi L (R / D)^2 a.
    TriMesh sphere = makeSphere(1.0f, 48, 96);
    VisibilityOptions options = smallGrid(2);
    options.cube = 32;
    options.grid.azimuth = 4, options.grid.polar = 3, options.grid.shells = 4;
    options.grid.shellMin = 1.5, options.grid.shellMax = 5.0;
    Visibility vis = sampleVisibility(sphere, options, "sphere");
    EXPECT_LT(vis.rays, vis.naiveRays / 3);
    CubeEnvironment env = cubeFrom(32, [](const double*) { return std::array<double, 3>{1, 1, 1}; });
    FivGrid grid = reduceVisibility(vis, env);
    std::vector<double> radii = shellRadii(options.grid);
    double R = vis.sphere.radius; // ~1: the mesh's vertices lie on the unit sphere
    for (size_t row = 0; row < grid.valid.size(); ++row) {
        ASSERT_TRUE(grid.valid[row]);
        int i = int(row % 4), j = int(row / 4 % 3), k = int(row / 12);
        double d[3];
        gridDirection(options.grid, i, j, d);
        double D = radii[size_t(k)] * R, sinAlpha = 1.0 / D; // the true sphere has radius 1
        double exact = kPi * sinAlpha * sinAlpha;
        double tolerance = sinAlpha > 0.4 ? 0.02 : 0.06;
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(grid.fiv[9 * row + a], exact * d[a], tolerance * exact) << row;
        double cap = 2.0 * kPi * (1.0 - std::sqrt(1.0 - sinAlpha * sinAlpha));
        EXPECT_NEAR(grid.power[3 * row], cap, tolerance * cap);
    }
}

TEST(FivVisibility, SamplesInsideAClosedMeshAreInvalidAndOpenMeshesAreRefused) {
    TriMesh box = makeBox(-1.0f, 1.0f); // R = sqrt(3): rho < 1 / sqrt(3) lies inside the box on every axis
    VisibilityOptions options = smallGrid();
    options.grid.shellMin = 0.3, options.grid.shellMax = 3.0, options.grid.shells = 3;
    Visibility vis = sampleVisibility(box, options, "box");
    size_t perShell = size_t(options.grid.azimuth) * options.grid.polar;
    for (size_t row = 0; row < perShell; ++row) EXPECT_EQ(vis.valid[row], 0) << row;          // rho 0.3: inside
    for (size_t row = 2 * perShell; row < 3 * perShell; ++row) EXPECT_EQ(vis.valid[row], 1); // rho 3: outside
    // Masks shrink as the occluder moves away.
    CubeEnvironment env = cubeFrom(16, [](const double*) { return std::array<double, 3>{1, 1, 1}; });
    FivGrid grid = reduceVisibility(vis, env);
    EXPECT_GT(grid.power[3 * perShell], grid.power[3 * 2 * perShell]);

    TriMesh plane = makePlane(2.0f, 2);
    try {
        sampleVisibility(plane, options, "plane.glb");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.exitCode(), kExitInput);
        EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos);
    }
    options.allowOpen = true;
    EXPECT_NO_THROW(sampleVisibility(plane, options, "plane.glb"));
}

TEST(FivVisibility, ShardsAndThreadCountsGiveIdenticalMasks) {
    TriMesh box = makeBox(-1.0f, 0.5f);
    VisibilityOptions options = smallGrid(2);
    options.threads = 1;
    Visibility whole = sampleVisibility(box, options, "box");
    options.threads = 2;
    std::vector<Visibility> shards;
    for (int s = 2; s >= 0; --s) {
        options.shardIndex = s, options.shardCount = 3;
        shards.push_back(sampleVisibility(box, options, "box"));
    }
    Visibility joined = joinShards(std::move(shards), {"a", "b", "c"});
    EXPECT_EQ(joined.offsets, whole.offsets);
    EXPECT_EQ(joined.bits, whole.bits);
    EXPECT_EQ(joined.valid, whole.valid);
    EXPECT_EQ(joined.rays, whole.rays);
    EXPECT_EQ(joined.naiveRays, whole.naiveRays);
    // Every azimuth of a pole row holds the same mask.
    for (int k = 0; k < options.grid.shells; ++k)
        for (int j : {0, options.grid.polar - 1}) {
            size_t first = (size_t(k) * options.grid.polar + j) * options.grid.azimuth;
            for (int i = 1; i < options.grid.azimuth; ++i)
                EXPECT_EQ(whole.offsets[first + i + 1] - whole.offsets[first + i],
                          whole.offsets[first + 1] - whole.offsets[first]);
        }
}

TEST(FivReduce, IsLinearInTheMapAndMaskAndComplementSumToFivEnv) {
    TriMesh box = makeBox(-0.5f, 1.0f);
    VisibilityOptions options = smallGrid();
    Visibility vis = sampleVisibility(box, options, "box");
    std::mt19937 random(3);
    std::uniform_real_distribution<double> u(0.0, 2.0);
    CubeEnvironment a = cubeFrom(16, [&](const double*) { return std::array<double, 3>{u(random), u(random), u(random)}; });
    CubeEnvironment b = cubeFrom(16, [&](const double*) { return std::array<double, 3>{u(random), u(random), u(random)}; });
    CubeEnvironment sum = a;
    for (size_t e = 0; e < sum.radiance.size(); ++e) sum.radiance[e] += 3.0 * b.radiance[e];
    FivGrid fa = reduceVisibility(vis, a), fb = reduceVisibility(vis, b), fs = reduceVisibility(vis, sum);
    for (size_t e = 0; e < fa.fiv.size(); ++e) EXPECT_NEAR(fs.fiv[e], fa.fiv[e] + 3.0f * fb.fiv[e], 1e-4 + 1e-5 * std::abs(fs.fiv[e]));

    // Complement: on an inner shell every texel is a candidate; inverting the bits gives the unoccluded part.
    Visibility inverted = vis;
    std::array<double, 9> total = environmentFiv(a);
    size_t perShell = size_t(options.grid.azimuth) * options.grid.polar;
    for (size_t row = 0; row < perShell; ++row) {
        if (!vis.valid[row]) continue;
        for (uint32_t byte = vis.offsets[row]; byte < vis.offsets[row + 1]; ++byte) inverted.bits[byte] = uint8_t(~vis.bits[byte]);
    }
    FivGrid fi = reduceVisibility(inverted, a);
    for (size_t row = 0; row < perShell; ++row) {
        if (!vis.valid[row]) continue;
        for (int e = 0; e < 9; ++e) EXPECT_NEAR(fa.fiv[9 * row + e] + fi.fiv[9 * row + e], total[size_t(e)], 1e-4);
    }
}

TEST(FivVisibility, RotatingOccluderAndMapTogetherRotatesTheGrid) {
    // Q = 90 degrees about +Y maps azimuth i to i + azimuth / 4, cube texels to cube texels and the mesh exactly.
    TriMesh box = makeBox(-0.3f, 1.0f);
    for (size_t v = 0; v < box.positions.size(); v += 3) box.positions[v + 1] *= 0.5f; // not symmetric in y
    TriMesh turned = box;
    for (size_t v = 0; v < box.positions.size(); v += 3) { // Q (x, y, z) = (z, y, -x)
        turned.positions[v] = box.positions[v + 2];
        turned.positions[v + 2] = -box.positions[v];
    }
    auto f = [](const double* d) { return std::array<double, 3>{1.0 + d[0], 1.0 + 0.5 * d[2], 2.0 + d[1]}; };
    auto g = [&](const double* d) { double back[3] = {-d[2], d[1], d[0]}; return f(back); };
    VisibilityOptions options = smallGrid();
    FivGrid a = reduceVisibility(sampleVisibility(box, options, "a"), cubeFrom(16, f));
    FivGrid b = reduceVisibility(sampleVisibility(turned, options, "b"), cubeFrom(16, g));
    // The bounding-sphere centres differ by Q as well, so sample (i, j, k) of a matches (i - azimuth / 4, j, k) of b.
    int az = options.grid.azimuth;
    for (size_t row = 0; row < a.valid.size(); ++row) {
        int i = int(row % size_t(az));
        size_t other = row - size_t(i) + size_t((i + 3 * az / 4) % az); // phi - pi / 2
        ASSERT_EQ(a.valid[row], b.valid[other]);
        for (int c = 0; c < 3; ++c) {
            const float* fa = &a.fiv[9 * row + 3 * c];
            const float* fb = &b.fiv[9 * other + 3 * c];
            float scale = 1e-3f * (std::abs(fa[0]) + std::abs(fa[1]) + std::abs(fa[2])) + 1e-4f;
            EXPECT_NEAR(fb[0], fa[2], scale);
            EXPECT_NEAR(fb[1], fa[1], scale);
            EXPECT_NEAR(fb[2], -fa[0], scale);
        }
    }
}

TEST(FivBundle, StoresAtMost36BytesPerSample) {
    // Table 1 of the seed: 36 B per sample (9 float32), MiB truncated to 2 decimals.
    struct Row { int nt, np, nr; double mib; };
    for (Row r : {Row{256, 129, 30, 34.01}, Row{128, 65, 30, 8.56}, Row{64, 33, 30, 2.17}, Row{64, 33, 15, 1.08},
                  Row{32, 17, 15, 0.28}}) {
        double mib = 36.0 * r.nt * r.np * r.nr / (1 << 20);
        EXPECT_DOUBLE_EQ(std::floor(mib * 100) / 100, r.mib);
    }
    TriMesh box = makeBox(-1.0f, 1.0f);
    VisibilityOptions options = smallGrid();
    FivGrid grid = reduceVisibility(sampleVisibility(box, options, "box"), cubeFrom(16, constant));
    Bundle bundle = fivBundle(box, grid, std::vector<float>(6 * 32 * 32 * 3, 1.0f), {}, {}, {});
    double bytes = 0.0;
    for (const Layer& layer : bundle.layers) {
        if (layer.name != "fiv" && layer.name != "fiv_power" && layer.name != "fiv_valid") continue;
        double elements = 1.0;
        for (uint64_t s : layer.shape) elements *= double(s);
        bytes += elements * (layer.componentType == "float16" ? 2 : layer.componentType == "uint8" ? 1 : 4);
    }
    EXPECT_EQ(bytes / double(options.grid.sampleCount()), 25.0);
}
