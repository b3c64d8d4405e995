#include "bake.h"

#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>

namespace prt {
namespace {

RasterOptions square(int size) {
    RasterOptions options;
    options.width = options.height = size;
    return options;
}

TEST(VertexTangents, FollowUAndPutTheBitangentAlongMinusV) {
    TriMesh plane = makePlane(2.0f, 2); // u along +X, v along +Z, normal +Y
    std::vector<float> frames = vertexTangents(plane);
    for (size_t v = 0; v < plane.vertexCount(); ++v) {
        EXPECT_NEAR(frames[4 * v], 1.0f, 1e-6f);
        EXPECT_NEAR(frames[4 * v + 1], 0.0f, 1e-6f);
        EXPECT_NEAR(frames[4 * v + 2], 0.0f, 1e-6f);
        EXPECT_EQ(frames[4 * v + 3], 1.0f); // cross(+Y, +X) = -Z, the direction of decreasing v
    }
    for (size_t v = 0; v < plane.vertexCount(); ++v) plane.texcoords[2 * v] = 1.0f - plane.texcoords[2 * v];
    frames = vertexTangents(plane); // mirrored in u: the tangent turns round, the handedness flips
    for (size_t v = 0; v < plane.vertexCount(); ++v) {
        EXPECT_NEAR(frames[4 * v], -1.0f, 1e-6f);
        EXPECT_EQ(frames[4 * v + 3], -1.0f);
    }
}

TEST(NormalMap, FlatHighMeshOverFlatLowMeshIsUpEverywhere) {
    TriMesh low = makePlane(1.0f, 2);
    TriMesh high = makePlane(1.2f, 16, 0.01f); // finer, slightly above, a little larger so the borders hit
    TexelSamples samples = rasteriseAtlas(low, square(32), "low");
    std::vector<float> positions, normals;
    texelSurface(low, samples, positions, normals);
    CageProjection projection = projectOntoHigh(high, positions, normals, 0.05f);
    EXPECT_EQ(projection.misses, 0u);
    for (size_t i = 0; i < samples.texel.size(); ++i) EXPECT_NEAR(projection.positions[3 * i + 1], 0.01f, 1e-7f);
    std::vector<float> tangentNormals =
        tangentSpaceNormals(low, vertexTangents(low), samples, projection.normals);
    ASSERT_EQ(tangentNormals.size(), 3 * size_t(32 * 32));
    for (size_t i = 0; i < samples.texel.size(); ++i) {
        EXPECT_NEAR(tangentNormals[3 * i], 0.0f, 1e-6f);
        EXPECT_NEAR(tangentNormals[3 * i + 1], 0.0f, 1e-6f);
        EXPECT_NEAR(tangentNormals[3 * i + 2], 1.0f, 1e-6f);
    }
}

TEST(NormalMap, TiltsTowardUAndTowardImageUpHaveTheirSigns) {
    TriMesh low = makePlane(1.0f, 1);
    TexelSamples samples = rasteriseAtlas(low, square(8), "low");
    std::vector<float> positions, normals;
    texelSurface(low, samples, positions, normals);
    // Detail normal leaning toward +X (= +u) and toward -Z (= -v, up in the image).
    double length = std::sqrt(0.3 * 0.3 + 1.0 + 0.2 * 0.2);
    std::vector<float> detail;
    for (size_t i = 0; i < samples.texel.size(); ++i)
        detail.insert(detail.end(), {float(0.3 / length), float(1.0 / length), float(-0.2 / length)});
    std::vector<float> tangentNormals = tangentSpaceNormals(low, vertexTangents(low), samples, detail);
    for (size_t i = 0; i < samples.texel.size(); ++i) {
        EXPECT_NEAR(tangentNormals[3 * i], 0.3 / length, 1e-6);
        EXPECT_NEAR(tangentNormals[3 * i + 1], 0.2 / length, 1e-6);
        EXPECT_NEAR(tangentNormals[3 * i + 2], 1.0 / length, 1e-6);
    }
}

TEST(CageProjection, MissesWhereTheHighMeshDoesNotReach) {
    TriMesh low = makePlane(1.0f, 2);
    TriMesh high = makePlane(0.5f, 4, 0.01f); // covers only the middle quarter
    TexelSamples samples = rasteriseAtlas(low, square(16), "low");
    std::vector<float> positions, normals;
    texelSurface(low, samples, positions, normals);
    CageProjection projection = projectOntoHigh(high, positions, normals, 0.05f);
    EXPECT_EQ(projection.misses, samples.texel.size() - 64); // the middle 8x8 texels hit
    for (size_t i = 0; i < samples.texel.size(); ++i)
        if (!projection.hit[i]) {
            EXPECT_EQ(projection.positions[3 * i + 1], 0.0f); // misses keep the low point
        }
}

} // namespace
} // namespace prt
