// prt render: closed-form pictures of a square in front of the camera, per vertex and per texel, and the camera
// shared with prt reference --image.
#include "render.h"

#include "compare.h"

#include "core.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

// A unit square in the z = 0 plane facing +Z, corners (-0.5,-0.5) .. (0.5,0.5), uv (0,0) at the top left.
prt::TriMesh square() {
    prt::TriMesh mesh;
    mesh.positions = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
    mesh.texcoords = {0, 1, 1, 1, 1, 0, 0, 0};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    return mesh;
}

prt::PinholeCamera frontCamera(int width, int height) {
    prt::PinholeCamera camera;
    camera.eye = {0, 0, 2};
    camera.target = {0, 0, 0};
    camera.fovyDegrees = 40.0f;
    camera.width = width;
    camera.height = height;
    return camera;
}

} // namespace

// Equal radiance at every vertex: every covered pixel holds exactly it, the rest is black with coverage 0. The
// square spans 2 atan(0.25) of the 40 degree view: about 0.687 of the image height.
TEST(Render, ConstantVertexRadianceFillsTheSquareExactly) {
    prt::TriMesh mesh = square();
    std::vector<float> radiance(12);
    for (size_t v = 0; v < 4; ++v) radiance[v * 3] = 0.25f, radiance[v * 3 + 1] = 0.5f, radiance[v * 3 + 2] = 2.0f;
    prt::RenderedImage image = prt::renderVertexRadiance(mesh, radiance, frontCamera(64, 64));
    double covered = 0;
    for (size_t p = 0; p < 64 * 64; ++p) {
        covered += image.coverage[p];
        if (image.coverage[p] == 1.0f) {
            EXPECT_NEAR(image.radiance.rgb[p * 3], 0.25f, 1e-6f);
            EXPECT_NEAR(image.radiance.rgb[p * 3 + 2], 2.0f, 1e-6f);
        } else {
            EXPECT_EQ(image.radiance.rgb[p * 3 + 1], 0.0f);
        }
    }
    double side = 0.25 / std::tan(20.0 * M_PI / 180.0) * 64; // pixels
    EXPECT_NEAR(covered, side * side, 4 * side);              // within a one-pixel border
    EXPECT_EQ(image.coverage[0], 0.0f);
    EXPECT_EQ(image.coverage[32 * 64 + 32], 1.0f);
}

// A linear radiance ramp in x interpolates exactly: pixel radiance = that of the surface point it sees.
TEST(Render, VertexRadianceIsInterpolatedBarycentrically) {
    prt::TriMesh mesh = square();
    std::vector<float> radiance = {0, 0, 0, 1, 1, 1, 1, 1, 1, 0, 0, 0}; // x + 0.5
    prt::PinholeCamera camera = frontCamera(33, 33);
    prt::RenderedImage image = prt::renderVertexRadiance(mesh, radiance, camera);
    prt::PinholeRays rays = prt::pinholeRays(camera);
    for (size_t p : {size_t(16 * 33 + 16), size_t(10 * 33 + 12), size_t(20 * 33 + 22)}) {
        float d[3];
        prt::pinholeRayDirection(rays, p, d);
        float x = camera.eye[0] + d[0] * (-camera.eye[2] / d[2]);
        EXPECT_NEAR(image.radiance.rgb[p * 3], x + 0.5f, 1e-5f) << "pixel " << p;
    }
}

// Per texel: a 2x2 atlas with a different colour per texel shows the texel under each image quadrant; texel row 0 is
// the top of the atlas (v down), which is the top of the square.
TEST(Render, TexelsAreLookedUpAtTexcoordNearest) {
    prt::TriMesh mesh = square();
    prt::Image atlas;
    atlas.width = atlas.height = 2;
    atlas.rgb = {1, 0, 0, 2, 0, 0, 3, 0, 0, 4, 0, 0}; // (0,0) (1,0) (0,1) (1,1)
    prt::RenderedImage image = prt::renderTexelRadiance(mesh, atlas, frontCamera(40, 40));
    auto at = [&](int x, int y) { return image.radiance.rgb[(size_t(y) * 40 + x) * 3]; };
    EXPECT_EQ(at(15, 15), 1.0f); // top left
    EXPECT_EQ(at(25, 15), 2.0f);
    EXPECT_EQ(at(15, 25), 3.0f);
    EXPECT_EQ(at(25, 25), 4.0f);
}

// Seen from behind, the square is a back face: black, but covered.
TEST(Render, BackFacesAreBlack) {
    prt::TriMesh mesh = square();
    std::vector<float> radiance(12, 1.0f);
    prt::PinholeCamera camera = frontCamera(16, 16);
    camera.eye = {0, 0, -2};
    prt::RenderedImage image = prt::renderVertexRadiance(mesh, radiance, camera);
    EXPECT_EQ(image.coverage[8 * 16 + 8], 1.0f);
    EXPECT_EQ(image.radiance.rgb[(8 * 16 + 8) * 3], 0.0f);
}

TEST(Render, RejectsMismatchedInputs) {
    prt::TriMesh mesh = square();
    EXPECT_THROW(prt::renderVertexRadiance(mesh, std::vector<float>(9), frontCamera(8, 8)), prt::Error);
    mesh.texcoords.clear();
    prt::Image atlas;
    atlas.width = atlas.height = 1;
    atlas.rgb = {1, 1, 1};
    EXPECT_THROW(prt::renderTexelRadiance(mesh, atlas, frontCamera(8, 8)), prt::Error);
    prt::PinholeCamera bad = frontCamera(8, 8);
    bad.up = {0, 0, 1}; // along the view
    EXPECT_THROW(prt::renderVertexRadiance(square(), std::vector<float>(12), bad), prt::Error);
}

// The tone map of compare.h: 0 stays 0, x = 1 is Reinhard 0.5 in sRGB (188), exposure doubles before the curve.
TEST(Render, ToneMapIsReinhardThenSrgb) {
    EXPECT_EQ(prt::toneMap(0.0f, 0.0f), 0);
    EXPECT_EQ(prt::toneMap(-1.0f, 0.0f), 0);
    EXPECT_EQ(prt::toneMap(1.0f, 0.0f), 188);
    EXPECT_EQ(prt::toneMap(0.5f, 1.0f), 188);
    EXPECT_EQ(prt::toneMap(1e9f, 0.0f), 255);
}
