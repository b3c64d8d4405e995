// A texel is a receiver like any vertex: the per-vertex integrator gives it the same transfer as a vertex placed
// at its sample point with its normal and its rotation key.
#include "bake.h"

#include "scene.h"
#include "transfer.h"

#include <gtest/gtest.h>

#include <cstring>

namespace prt {
namespace {

// A ground plane with UVs under a sphere that shadows part of it.
TriMesh shadowedPlane() {
    TriMesh plane = makePlane(2.0f, 4);
    TriMesh ball = makeSphere(0.3f, 8, 16);
    for (size_t v = 0; v < ball.vertexCount(); ++v) ball.positions[3 * v + 1] += 0.5f;
    ball.texcoords.assign(2 * ball.vertexCount(), 1.0f); // one corner texel; only the plane is rasterised below
    return mergeMeshes({plane, ball});
}

TransferOptions options(TransferMode mode, int bounces) {
    TransferOptions o;
    o.mode = mode;
    o.order = 3;
    o.samples = 256;
    o.bounces = bounces;
    o.seed = 17;
    o.progress = false;
    return o;
}

// The mesh with vertex `index` placed at (p, n): vertices before it are copies of vertex 0, which no triangle
// uses twice over and which leave the bounding box (hence the ray offset) as it was.
TriMesh withVertexAt(const TriMesh& mesh, size_t index, const float p[3], const float n[3]) {
    TriMesh out = mesh;
    while (out.vertexCount() < index) {
        out.positions.insert(out.positions.end(), mesh.positions.begin(), mesh.positions.begin() + 3);
        out.normals.insert(out.normals.end(), mesh.normals.begin(), mesh.normals.begin() + 3);
    }
    out.positions.insert(out.positions.end(), p, p + 3);
    out.normals.insert(out.normals.end(), n, n + 3);
    out.texcoords.clear();
    return out;
}

TEST(TransferAt, TexelInsideATriangleMatchesAVertexAtTheSamePoint) {
    TriMesh scene = shadowedPlane();
    TriMesh plane = makePlane(2.0f, 4);
    RasterOptions raster;
    raster.width = raster.height = 32;
    TexelSamples samples = rasteriseAtlas(plane, raster, "plane");
    std::vector<float> positions, normals;
    texelSurface(plane, samples, positions, normals);
    // A texel in the sphere's penumbra, strictly inside its triangle, off every vertex.
    size_t i = 0;
    while (!(samples.centreInside[i] && std::abs(positions[3 * i]) > 0.2f && std::abs(positions[3 * i]) < 0.4f &&
             std::abs(positions[3 * i + 2]) < 0.1f))
        ++i;
    uint64_t key = samples.texel[i];
    ASSERT_GT(key, scene.vertexCount());

    Receivers receivers;
    receivers.positions = &positions[3 * i];
    receivers.normals = &normals[3 * i];
    receivers.keys = &key;
    receivers.count = 1;
    TriMesh placed = withVertexAt(scene, key, &positions[3 * i], &normals[3 * i]);
    std::vector<float> shadowed;
    for (auto [mode, bounces] : {std::pair{TransferMode::Shadowed, 0}, std::pair{TransferMode::Interreflected, 2}}) {
        Transfer texel = computeTransferAt(scene, receivers, options(mode, bounces));
        Transfer vertex = computeTransfer(placed, options(mode, bounces));
        const float* row = &vertex.coefficients[key * 27];
        ASSERT_EQ(texel.coefficients.size(), 27u);
        if (mode == TransferMode::Shadowed) {
            EXPECT_EQ(std::memcmp(texel.coefficients.data(), row, 27 * sizeof(float)), 0);
            shadowed = texel.coefficients;
        } else {
            // The same series, summed in another order: one gather of the (B-1)-bounce vertex transfer instead of B
            // Jacobi sweeps.
            for (int k = 0; k < 27; ++k) EXPECT_NEAR(texel.coefficients[k], row[k], 1e-5f) << "coefficient " << k;
            EXPECT_GT(texel.coefficients[0], shadowed[0] + 1e-3f); // the ball reflects light onto the texel
        }
    }
    // The texel really is in the ball's shadow: well below the unoccluded closed form.
    Transfer unshadowed = computeTransferAt(scene, receivers, options(TransferMode::Unshadowed, 0));
    EXPECT_LT(shadowed[0], 0.95f * unshadowed.coefficients[0]);
}

} // namespace
} // namespace prt
