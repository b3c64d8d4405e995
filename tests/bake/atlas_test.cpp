#include "bake.h"

#include "core.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>

namespace prt {
namespace {

void expectValidAtlas(const TriMesh& input, const GeneratedAtlas& atlas, int size, int padding,
                      double chartAngle = AtlasOptions().chartAngle) {
    const TriMesh& mesh = atlas.mesh;
    ASSERT_EQ(mesh.vertexCount(), atlas.sourceVertex.size());
    ASSERT_EQ(mesh.indices.size(), input.indices.size());
    ASSERT_EQ(mesh.texcoords.size(), 2 * mesh.vertexCount());
    ASSERT_EQ(mesh.normals.size(), 3 * mesh.vertexCount());
    for (float t : mesh.texcoords) {
        EXPECT_GE(t, 0.0f);
        EXPECT_LE(t, 1.0f);
    }
    // Same triangles, corner by corner.
    for (size_t i = 0; i < mesh.indices.size(); ++i) {
        uint32_t source = atlas.sourceVertex[mesh.indices[i]];
        EXPECT_EQ(source, input.indices[i]);
        for (int a = 0; a < 3; ++a)
            EXPECT_EQ(mesh.positions[3 * size_t(mesh.indices[i]) + a], input.positions[3 * size_t(source) + a]);
    }
    // One texel density everywhere: UV area over surface area is (texelsPerUnit / size)^2.
    double expected = std::pow(atlas.texelsPerUnit / size, 2);
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t* c = &mesh.indices[3 * t];
        auto p = [&](int k, int a) { return double(mesh.positions[3 * size_t(c[k]) + a]); };
        auto uv = [&](int k, int a) { return double(mesh.texcoords[2 * size_t(c[k]) + a]); };
        double e1[3], e2[3];
        for (int a = 0; a < 3; ++a) e1[a] = p(1, a) - p(0, a), e2[a] = p(2, a) - p(0, a);
        double area3 = 0.5 * std::sqrt(std::pow(e1[1] * e2[2] - e1[2] * e2[1], 2) +
                                       std::pow(e1[2] * e2[0] - e1[0] * e2[2], 2) +
                                       std::pow(e1[0] * e2[1] - e1[1] * e2[0], 2));
        double area2 = 0.5 * std::abs((uv(1, 0) - uv(0, 0)) * (uv(2, 1) - uv(0, 1)) -
                                      (uv(1, 1) - uv(0, 1)) * (uv(2, 0) - uv(0, 0)));
        // A chart's projection shrinks faces tilted from its seed normal by at most cos(chartAngle).
        EXPECT_LE(area2, expected * area3 * (1 + 1e-4)) << "triangle " << t;
        EXPECT_GE(area2, expected * area3 * std::cos(chartAngle * M_PI / 180) * (1 - 1e-4)) << "triangle " << t;
    }
    // Unique, and charts keep `padding` empty texels between their covered texels.
    RasterOptions raster;
    raster.width = raster.height = size;
    TexelSamples samples = rasteriseAtlas(mesh, raster, "atlas"); // throws on overlap
    std::vector<int> chartAt(size_t(size) * size, -1);
    for (size_t i = 0; i < samples.texel.size(); ++i) chartAt[samples.texel[i]] = int(atlas.chart[samples.triangle[i]]);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            int chart = chartAt[size_t(y) * size + x];
            if (chart < 0) continue;
            for (int ny = std::max(0, y - padding); ny <= std::min(size - 1, y + padding); ++ny)
                for (int nx = std::max(0, x - padding); nx <= std::min(size - 1, x + padding); ++nx) {
                    int other = chartAt[size_t(ny) * size + nx];
                    ASSERT_TRUE(other < 0 || other == chart)
                        << "charts " << chart << " and " << other << " closer than " << padding << " texels at (" << x
                        << ", " << y << ")";
                }
        }
}

TEST(GenerateAtlas, BoxRoomGetsOneChartPerWall) {
    TriMesh room = makeBoxRoom(2.0f, 3);
    room.texcoords.clear();
    AtlasOptions options;
    options.width = options.height = 128;
    GeneratedAtlas atlas = generateAtlas(room, options);
    EXPECT_EQ(atlas.charts, 6u);
    EXPECT_EQ(atlas.mesh.vertexCount(), room.vertexCount()); // walls share no vertices, so nothing splits
    expectValidAtlas(room, atlas, 128, options.padding);
    // Six 2x2 walls in 128^2 texels: each wall takes at least a fifth of the side.
    EXPECT_GT(atlas.texelsPerUnit * 2.0, 128 / 5.0);
}

TEST(GenerateAtlas, SphereSplitsIntoChartsThatDoNotOverlap) {
    TriMesh sphere = makeSphere(1.0f, 12, 24);
    AtlasOptions options;
    options.width = options.height = 256;
    options.padding = 3;
    GeneratedAtlas atlas = generateAtlas(sphere, options);
    EXPECT_GE(atlas.charts, 4u);
    EXPECT_GT(atlas.mesh.vertexCount(), sphere.vertexCount()); // chart borders split vertices
    expectValidAtlas(sphere, atlas, 256, options.padding);
    // Same input, same atlas.
    GeneratedAtlas again = generateAtlas(sphere, options);
    EXPECT_EQ(again.mesh.texcoords, atlas.mesh.texcoords);
    EXPECT_EQ(again.mesh.indices, atlas.mesh.indices);
}

TEST(GenerateAtlas, NonManifoldEdgesAndRepeatedCornersDoNotBreakIt) {
    // Three triangles on one edge, and a triangle with a repeated corner.
    TriMesh mesh;
    mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1};
    mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    mesh.indices = {0, 1, 2, 1, 0, 3, 0, 1, 4, 2, 2, 1};
    AtlasOptions options;
    options.width = options.height = 64;
    GeneratedAtlas atlas = generateAtlas(mesh, options);
    expectValidAtlas(mesh, atlas, 64, options.padding);
}

TEST(GenerateAtlas, RefusesTooLittlePadding) {
    AtlasOptions options;
    options.width = options.height = 64;
    options.padding = 1;
    EXPECT_THROW(generateAtlas(makeSphere(1.0f, 4, 8), options), Error);
}

} // namespace
} // namespace prt
