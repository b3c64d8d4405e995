#include "bake.h"

#include "scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

namespace prt {
namespace {

TEST(FindSeams, PlaneHasNoneAndAnAtlasOfASphereHasThemWherePositionsMeet) {
    EXPECT_TRUE(findSeams(makePlane(1.0f, 4)).empty());
    AtlasOptions options;
    options.width = options.height = 128;
    GeneratedAtlas atlas = generateAtlas(makeSphere(1.0f, 8, 16), options);
    std::vector<SeamEdge> seams = findSeams(atlas.mesh);
    ASSERT_FALSE(seams.empty());
    const TriMesh& mesh = atlas.mesh;
    for (const SeamEdge& seam : seams) {
        EXPECT_NE(atlas.chart[seam.first], atlas.chart[seam.second]);
        for (int a = 0; a < 3; ++a) {
            EXPECT_EQ(mesh.positions[3 * size_t(seam.a) + a], mesh.positions[3 * size_t(seam.c) + a]);
            EXPECT_EQ(mesh.positions[3 * size_t(seam.b) + a], mesh.positions[3 * size_t(seam.d) + a]);
        }
    }
}

// A quad split along x = 0 into two charts, the seam's two vertices duplicated with their own texcoords, one copy
// at x = -0 (what mirroring a half mesh leaves): the two triangles still meet there, so it is one seam edge.
TEST(FindSeams, SignedZeroCopiesOfAVertexAreOnePosition) {
    TriMesh mesh;
    mesh.positions = {-1, 0, 0, 0, 0, 0, 0, 1, 0,        // left chart: its seam side at x = +0
                      -0.0f, 0, 0, 1, 0, 0, -0.0f, 1, 0}; // right chart: the same corners at x = -0
    mesh.texcoords = {0.0f, 0.0f, 0.4f, 0.0f, 0.4f, 0.4f, 0.6f, 0.0f, 1.0f, 0.0f, 0.6f, 0.4f};
    mesh.indices = {0, 1, 2, 3, 4, 5};
    const std::vector<SeamEdge> seams = findSeams(mesh);
    ASSERT_EQ(seams.size(), 1u);
    EXPECT_EQ(seams[0].first, 0u);
    EXPECT_EQ(seams[0].second, 1u);
    // The edge from vertex 1 to 2 of the first triangle meets the edge 3..5 of the second, corner to corner.
    EXPECT_EQ(seams[0].a, 1u);
    EXPECT_EQ(seams[0].b, 2u);
    EXPECT_EQ(seams[0].c, 3u);
    EXPECT_EQ(seams[0].d, 5u);
}

// A smooth function of position plus per-texel noise (what Monte Carlo leaves), over an atlas of a sphere,
// with gutters filled: the raw material of the seam measurements.
struct NoisyAtlas {
    TriMesh mesh;
    TexelSamples samples;
    std::vector<float> texels; // rgb
    std::vector<uint8_t> covered;
};

NoisyAtlas noisyAtlas(float noise) {
    NoisyAtlas out;
    AtlasOptions options;
    options.width = options.height = 128;
    out.mesh = generateAtlas(makeSphere(1.0f, 10, 20), options).mesh;
    RasterOptions raster;
    raster.width = raster.height = 128;
    out.samples = rasteriseAtlas(out.mesh, raster, "sphere");
    std::vector<float> positions, normals;
    texelSurface(out.mesh, out.samples, positions, normals);
    out.texels.assign(128 * 128 * 3, 0.0f);
    std::mt19937 random(11);
    std::uniform_real_distribution<float> jitter(-noise, noise);
    for (size_t i = 0; i < out.samples.texel.size(); ++i) {
        const float* p = &positions[3 * i];
        float value = 1.0f + 0.3f * p[0] + 0.2f * p[1] - 0.1f * p[2];
        for (int c = 0; c < 3; ++c) out.texels[3 * size_t(out.samples.texel[i]) + c] = value + jitter(random);
    }
    out.covered = coverageMask(out.samples);
    return out;
}

TEST(StitchSeams, TexelsOnBothSidesOfASeamAgreeAndTexelsAwayFromSeamsKeepTheirBits) {
    NoisyAtlas atlas = noisyAtlas(0.05f);
    pushPull(atlas.texels.data(), 128, 128, 3, atlas.covered.data());
    std::vector<SeamEdge> seams = findSeams(atlas.mesh);
    std::vector<float> stitched = atlas.texels;
    size_t changed = stitchSeams(atlas.mesh, seams, 128, 128, stitched.data(), 3);
    EXPECT_GT(changed, 0u);
    // Only texels that bilinear lookups on seams read, whose centres lie within a texel's diagonal of a seam.
    auto distanceToSeams = [&](double x, double y) {
        double best = INFINITY;
        const TriMesh& mesh = atlas.mesh;
        for (const SeamEdge& seam : seams)
            for (auto [from, to] : {std::pair{seam.a, seam.b}, std::pair{seam.c, seam.d}}) {
                double ax = mesh.texcoords[2 * from] * 128.0, ay = mesh.texcoords[2 * from + 1] * 128.0;
                double bx = mesh.texcoords[2 * to] * 128.0, by = mesh.texcoords[2 * to + 1] * 128.0;
                double length2 = (bx - ax) * (bx - ax) + (by - ay) * (by - ay);
                double s = std::clamp(((x - ax) * (bx - ax) + (y - ay) * (by - ay)) / length2, 0.0, 1.0);
                best = std::min(best, std::hypot(ax + s * (bx - ax) - x, ay + s * (by - ay) - y));
            }
        return best;
    };
    size_t differing = 0;
    for (size_t t = 0; t < stitched.size() / 3; ++t)
        if (std::memcmp(&stitched[3 * t], &atlas.texels[3 * t], 3 * sizeof(float)) != 0) {
            ++differing;
            EXPECT_LE(distanceToSeams(t % 128 + 0.5, t / 128 + 0.5), std::sqrt(2.0) + 1e-9) << "texel " << t;
        }
    EXPECT_EQ(differing, changed);
    SeamJump before = texelSeamJump(atlas.mesh, seams, atlas.texels.data(), 128, 128, 8);
    SeamJump after = texelSeamJump(atlas.mesh, seams, stitched.data(), 128, 128, 8);
    EXPECT_GT(before.points, 0u);
    EXPECT_LT(after.rms, 0.2 * before.rms);
    // Without noise the function is smooth: what is left is far below the radiance itself.
    NoisyAtlas smooth = noisyAtlas(0.0f);
    pushPull(smooth.texels.data(), 128, 128, 3, smooth.covered.data());
    stitchSeams(smooth.mesh, seams, 128, 128, smooth.texels.data(), 3);
    SeamJump exact = texelSeamJump(smooth.mesh, seams, smooth.texels.data(), 128, 128, 8);
    EXPECT_LT(exact.rms, 1e-3 * exact.meanRadiance);
}

TEST(SeamJump, VertexJumpIsTheDifferenceOfTheTwoSidesVertices) {
    AtlasOptions options;
    options.width = options.height = 64;
    GeneratedAtlas atlas = generateAtlas(makeSphere(1.0f, 6, 12), options);
    std::vector<SeamEdge> seams = findSeams(atlas.mesh);
    ASSERT_FALSE(seams.empty());
    std::vector<float> radiance(3 * atlas.mesh.vertexCount(), 1.0f);
    SeamJump none = vertexSeamJump(atlas.mesh, seams, radiance.data(), 4);
    EXPECT_EQ(none.rms, 0.0);
    EXPECT_EQ(none.meanRadiance, 1.0);
    // Radiance 0.1 * chart on every vertex (each belongs to one chart): each seam jumps by 0.1 * the charts' gap.
    for (size_t t = 0; t < atlas.mesh.triangleCount(); ++t)
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) radiance[3 * size_t(atlas.mesh.indices[3 * t + k]) + c] = 0.1f * atlas.chart[t];
    double squares = 0.0;
    for (const SeamEdge& seam : seams)
        squares += std::pow(0.1 * (double(atlas.chart[seam.first]) - atlas.chart[seam.second]), 2);
    SeamJump jump = vertexSeamJump(atlas.mesh, seams, radiance.data(), 4);
    EXPECT_NEAR(jump.rms, std::sqrt(squares / seams.size()), 1e-6);
}

} // namespace
} // namespace prt
