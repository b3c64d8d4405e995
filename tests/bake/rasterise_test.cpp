#include "bake.h"

#include "core.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>

namespace prt {
namespace {

// One triangle in the XZ plane whose UVs are its (x, z) coordinates, normal +Y.
TriMesh uvTriangle(float u0, float v0, float u1, float v1, float u2, float v2) {
    TriMesh mesh;
    mesh.positions = {u0, 0, v0, u1, 0, v1, u2, 0, v2};
    mesh.normals = {0, 1, 0, 0, 1, 0, 0, 1, 0};
    mesh.texcoords = {u0, v0, u1, v1, u2, v2};
    mesh.indices = {0, 1, 2};
    return mesh;
}

RasterOptions square(int size) {
    RasterOptions options;
    options.width = options.height = size;
    return options;
}

TEST(Rasterise, UnitSquareSamplesEveryTexelCentreOnce) {
    TriMesh plane = makePlane(1.0f, 3); // UV [0,1]^2 in 18 triangles; x = u - 0.5, z = v - 0.5
    TexelSamples samples = rasteriseAtlas(plane, square(16), "plane");
    ASSERT_EQ(samples.texel.size(), 256u);
    std::vector<float> positions, normals;
    texelSurface(plane, samples, positions, normals);
    for (size_t i = 0; i < samples.texel.size(); ++i) {
        EXPECT_EQ(samples.texel[i], i);
        EXPECT_EQ(samples.centreInside[i], 1);
        float u = (i % 16 + 0.5f) / 16, v = (i / 16 + 0.5f) / 16;
        EXPECT_NEAR(positions[3 * i], u - 0.5f, 1e-6f);
        EXPECT_EQ(positions[3 * i + 1], 0.0f);
        EXPECT_NEAR(positions[3 * i + 2], v - 0.5f, 1e-6f);
        EXPECT_FLOAT_EQ(normals[3 * i + 1], 1.0f);
        const float* w = &samples.barycentric[3 * i];
        EXPECT_NEAR(w[0] + w[1] + w[2], 1.0f, 1e-6f);
    }
}

TEST(Rasterise, SliverThinnerThanATexelIsStillCovered) {
    // 0.2 texels high: the centres of only the two texels under its apex lie inside it; the other texels it
    // crosses are covered only because rasterisation is conservative.
    TriMesh sliver = uvTriangle(0.1f, 0.51f, 0.9f, 0.51f, 0.5f, 0.51f + 0.2f / 32);
    TexelSamples samples = rasteriseAtlas(sliver, square(32), "sliver");
    ASSERT_GE(samples.texel.size(), 25u);
    std::vector<float> positions, normals;
    texelSurface(sliver, samples, positions, normals);
    size_t centresInside = 0;
    for (size_t i = 0; i < samples.texel.size(); ++i) {
        EXPECT_EQ(samples.texel[i] / 32, 16u); // row 16 spans v in [0.5, 0.53125)
        centresInside += samples.centreInside[i];
        for (int k = 0; k < 3; ++k) EXPECT_GE(samples.barycentric[3 * i + k], 0.0f);
        // Every sample lies on the sliver.
        EXPECT_GE(positions[3 * i + 2], 0.51f - 1e-6f);
        EXPECT_LE(positions[3 * i + 2], 0.51f + 0.2f / 32 + 1e-6f);
    }
    EXPECT_EQ(centresInside, 2u);
}

TEST(Rasterise, PartlyCoveredTexelSamplesTheNearestPoint) {
    // Hypotenuse u + v = 0.45. Texel (1, 2) of an 8x8 atlas, [0.125, 0.25] x [0.25, 0.375], reaches into the
    // triangle, but its centre (0.1875, 0.3125) lies outside: its sample is the centre's projection onto the
    // hypotenuse, (0.1625, 0.2875). Texel (2, 2) starts at u + v = 0.5 and is not covered.
    TriMesh triangle = uvTriangle(0.0f, 0.0f, 0.0f, 0.45f, 0.45f, 0.0f);
    TexelSamples samples = rasteriseAtlas(triangle, square(8), "triangle");
    std::vector<float> positions, normals;
    texelSurface(triangle, samples, positions, normals);
    bool found = false;
    for (size_t i = 0; i < samples.texel.size(); ++i) {
        EXPECT_NE(samples.texel[i], 2u * 8 + 2);
        if (samples.texel[i] != 2 * 8 + 1) continue;
        found = true;
        EXPECT_EQ(samples.centreInside[i], 0);
        EXPECT_NEAR(positions[3 * i], 0.1625f, 1e-6f);
        EXPECT_NEAR(positions[3 * i + 2], 0.2875f, 1e-6f);
    }
    EXPECT_TRUE(found);
}

TEST(Rasterise, DegenerateTriangleCoversNothing) {
    TriMesh line = uvTriangle(0.1f, 0.1f, 0.5f, 0.5f, 0.9f, 0.9f);
    TexelSamples samples = rasteriseAtlas(line, square(16), "line");
    EXPECT_EQ(samples.degenerateTriangles, 1u);
    EXPECT_TRUE(samples.texel.empty());
}

TEST(Rasterise, UvsOutsideTheUnitSquareNeedAWrapMode) {
    TriMesh outside = uvTriangle(0.8f, 0.1f, 1.2f, 0.1f, 1.0f, 0.4f);
    try {
        rasteriseAtlas(outside, square(16), "outside.glb");
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_EQ(e.file(), "outside.glb");
        EXPECT_NE(e.problem().find("outside [0, 1]"), std::string::npos) << e.what();
    }
    RasterOptions repeat = square(16);
    repeat.wrap = UvWrap::Repeat;
    TexelSamples samples = rasteriseAtlas(outside, repeat, "outside.glb");
    bool left = false, right = false;
    for (uint32_t texel : samples.texel) left |= texel % 16 < 4, right |= texel % 16 >= 12;
    EXPECT_TRUE(left && right); // the part beyond u = 1 wraps to the left edge
}

TEST(Rasterise, OverlappingUvsAreRefusedUnlessAllowed) {
    TriMesh twice = uvTriangle(0.1f, 0.1f, 0.1f, 0.9f, 0.9f, 0.1f);
    twice.positions.insert(twice.positions.end(), {0, 1, 0, 0, 1, 1, 1, 1, 0});
    twice.normals.insert(twice.normals.end(), {0, 1, 0, 0, 1, 0, 0, 1, 0});
    twice.texcoords.insert(twice.texcoords.end(), {0.2f, 0.2f, 0.2f, 0.6f, 0.6f, 0.2f});
    twice.indices.insert(twice.indices.end(), {3, 4, 5});
    try {
        rasteriseAtlas(twice, square(16), "twice.glb");
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(e.place().find("triangles 0 and 1"), std::string::npos) << e.what();
        EXPECT_NE(e.problem().find("overlap"), std::string::npos) << e.what();
    }
    RasterOptions allow = square(16);
    allow.allowOverlap = true;
    TexelSamples samples = rasteriseAtlas(twice, allow, "twice.glb");
    EXPECT_GT(samples.overlappingTexels, 0u);
    for (uint32_t t : samples.triangle) EXPECT_EQ(t, 0u); // the lower triangle keeps every shared texel
}

TEST(Rasterise, ResolutionOutsideItsRangeIsAUsageError) {
    TriMesh plane = makePlane(1.0f, 1);
    for (int size : {0, kMaxBakeResolution + 1}) {
        try {
            rasteriseAtlas(plane, square(size), "plane");
            FAIL() << "expected an error for " << size;
        } catch (const Error& e) {
            EXPECT_EQ(e.exitCode(), kExitUsage);
        }
    }
}

} // namespace
} // namespace prt
