#include "scene.h"

#include "core.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <numbers>

namespace {

using Vec = std::array<double, 3>;

Vec vertex(const std::vector<float>& xyz, uint32_t i) { return {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]}; }
Vec sub(Vec a, Vec b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(Vec a, Vec b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec cross(Vec a, Vec b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
double length(Vec a) { return std::sqrt(dot(a, a)); }

// Directed edges keyed by exact positions, so faces with their own vertices along a shared edge still count as
// joined. A closed, consistently wound surface uses every directed edge once and its reverse once.
std::map<std::pair<Vec, Vec>, int> directedEdges(const prt::TriMesh& mesh) {
    std::map<std::pair<Vec, Vec>, int> edges;
    for (size_t t = 0; t < mesh.indices.size(); t += 3)
        for (int k = 0; k < 3; ++k)
            ++edges[{vertex(mesh.positions, mesh.indices[t + k]), vertex(mesh.positions, mesh.indices[t + (k + 1) % 3])}];
    return edges;
}

// Edges without a reverse partner: the boundary. Fails the test on any edge used twice in the same direction.
std::vector<std::pair<Vec, Vec>> boundaryEdges(const prt::TriMesh& mesh) {
    std::vector<std::pair<Vec, Vec>> boundary;
    auto edges = directedEdges(mesh);
    for (const auto& [edge, count] : edges) {
        EXPECT_EQ(count, 1) << "edge used twice in one direction: winding is inconsistent";
        if (!edges.count({edge.second, edge.first})) boundary.push_back(edge);
    }
    return boundary;
}

void expectConsistentNormals(const prt::TriMesh& mesh) {
    ASSERT_EQ(mesh.normals.size(), mesh.positions.size());
    for (size_t v = 0; v < mesh.vertexCount(); ++v) EXPECT_NEAR(length(vertex(mesh.normals, uint32_t(v))), 1.0, 1e-6);
    for (size_t t = 0; t < mesh.indices.size(); t += 3) {
        for (int k = 0; k < 3; ++k) ASSERT_LT(mesh.indices[t + k], mesh.vertexCount());
        Vec a = vertex(mesh.positions, mesh.indices[t]), b = vertex(mesh.positions, mesh.indices[t + 1]),
            c = vertex(mesh.positions, mesh.indices[t + 2]);
        Vec face = cross(sub(b, a), sub(c, a));
        ASSERT_GT(length(face), 0.0) << "degenerate triangle " << t / 3;
        for (int k = 0; k < 3; ++k)
            ASSERT_GT(dot(face, vertex(mesh.normals, mesh.indices[t + k])), 0.0) << "triangle " << t / 3 << " winds against its normals";
    }
}

double polarAngle(Vec p) { return std::acos(std::clamp(p[1] / length(p), -1.0, 1.0)); }

} // namespace

TEST(Scene, EveryNamedSceneWindsWithItsNormals) {
    for (const std::string& name : prt::sceneNames()) {
        SCOPED_TRACE(name);
        expectConsistentNormals(prt::makeScene(name));
    }
}

TEST(Scene, SphereIsClosedWithExactCounts) {
    const float center[3] = {0.5f, -2.0f, 3.0f};
    prt::TriMesh sphere = prt::makeSphere(2.0f, 5, 7, center);
    EXPECT_EQ(sphere.vertexCount(), 2u + 4u * 7u);
    EXPECT_EQ(sphere.triangleCount(), 2u * 7u * 4u);
    EXPECT_TRUE(boundaryEdges(sphere).empty());
    expectConsistentNormals(sphere);
    for (size_t v = 0; v < sphere.vertexCount(); ++v) {
        Vec offset = sub(vertex(sphere.positions, uint32_t(v)), {center[0], center[1], center[2]});
        EXPECT_NEAR(length(offset), 2.0, 1e-5);
        EXPECT_GT(dot(offset, vertex(sphere.normals, uint32_t(v))), 0.0); // outward
    }
    // The smallest sphere still closes: two bands, three segments.
    EXPECT_TRUE(boundaryEdges(prt::makeSphere(1.0f, 2, 3)).empty());
}

TEST(Scene, SphereFollowsTheEquirectDirectionConvention) {
    // Ring 1 of 2 lies on the equator; its first vertex is phi = -pi: d = (0, 0, +1).
    prt::TriMesh sphere = prt::makeSphere(1.0f, 2, 4);
    Vec first = vertex(sphere.positions, 1);
    EXPECT_NEAR(first[0], 0.0, 1e-6);
    EXPECT_NEAR(first[1], 0.0, 1e-6);
    EXPECT_NEAR(first[2], 1.0, 1e-6);
    EXPECT_EQ(vertex(sphere.positions, 0), (Vec{0.0, 1.0, 0.0}));
}

TEST(Scene, BoxRoomIsClosedAndFacesInward) {
    prt::TriMesh room = prt::makeBoxRoom(2.0f, 3);
    EXPECT_EQ(room.vertexCount(), 6u * 16u);
    EXPECT_EQ(room.triangleCount(), 6u * 2u * 9u);
    EXPECT_TRUE(boundaryEdges(room).empty());
    expectConsistentNormals(room);
    for (size_t v = 0; v < room.vertexCount(); ++v) {
        Vec p = vertex(room.positions, uint32_t(v)), n = vertex(room.normals, uint32_t(v));
        for (double coordinate : p) EXPECT_LE(std::fabs(coordinate), 1.0);
        EXPECT_GT(dot(n, p), -1.0 - 1e-9); // n . (centre - p) = 1 on every face
        EXPECT_DOUBLE_EQ(dot(n, p), -1.0);
    }
}

TEST(Scene, CavityOpensExactlyAtItsAngle) {
    const float opening = 0.7f;
    const int rings = 6, segments = 9;
    prt::TriMesh cavity = prt::makeOpenCavity(1.5f, opening, rings, segments);
    EXPECT_EQ(cavity.vertexCount(), size_t(rings * segments + 1));
    EXPECT_EQ(cavity.triangleCount(), size_t(segments * (2 * rings - 1)));
    expectConsistentNormals(cavity);
    double smallestPolar = std::numbers::pi;
    for (size_t v = 0; v < cavity.vertexCount(); ++v) {
        Vec p = vertex(cavity.positions, uint32_t(v));
        smallestPolar = std::min(smallestPolar, polarAngle(p));
        EXPECT_NEAR(length(p), 1.5, 1e-5);
        EXPECT_LT(dot(p, vertex(cavity.normals, uint32_t(v))), 0.0); // inward
    }
    EXPECT_NEAR(smallestPolar, opening, 1e-6);
    // The only boundary is the rim: one ring of `segments` edges at the opening angle.
    auto rim = boundaryEdges(cavity);
    EXPECT_EQ(rim.size(), size_t(segments));
    for (const auto& [from, to] : rim) {
        EXPECT_NEAR(polarAngle(from), opening, 1e-6);
        EXPECT_NEAR(polarAngle(to), opening, 1e-6);
    }
}

TEST(Scene, SphereInCavityHasBothParts) {
    prt::TriMesh scene = prt::makeSphereInCavity(4, 6);
    size_t sphereVertices = 2 + 3 * 6, cavityVertices = 4 * 6 + 1;
    ASSERT_EQ(scene.vertexCount(), sphereVertices + cavityVertices);
    for (size_t v = 0; v < scene.vertexCount(); ++v)
        EXPECT_NEAR(length(vertex(scene.positions, uint32_t(v))), v < sphereVertices ? prt::kInnerSphereRadius : 1.0, 1e-5);
    EXPECT_EQ(boundaryEdges(scene).size(), 6u); // the cavity's rim; the inner sphere is closed
}

TEST(Scene, TwoSpheresAreSeparateAndClosed) {
    prt::TriMesh scene = prt::makeTwoSpheres(4, 6);
    EXPECT_TRUE(boundaryEdges(scene).empty());
    size_t half = scene.vertexCount() / 2;
    for (size_t v = 0; v < scene.vertexCount(); ++v) {
        Vec p = vertex(scene.positions, uint32_t(v));
        EXPECT_NEAR(length(sub(p, {v < half ? -1.0 : 1.0, 0.0, 0.0})), 0.5, 1e-6);
    }
}

TEST(Scene, PlaneFacesUpWithTexcoords) {
    prt::TriMesh plane = prt::makePlane(4.0f, 2, 1.5f);
    EXPECT_EQ(plane.vertexCount(), 9u);
    EXPECT_EQ(plane.triangleCount(), 8u);
    EXPECT_EQ(boundaryEdges(plane).size(), 8u);
    expectConsistentNormals(plane);
    ASSERT_EQ(plane.texcoords.size(), 18u);
    EXPECT_EQ(vertex(plane.positions, 8), (Vec{2.0, 1.5, 2.0}));
    EXPECT_EQ(plane.texcoords[16], 1.0f);
    EXPECT_EQ(plane.texcoords[17], 1.0f);
}

TEST(Scene, MergeOffsetsIndicesAndKeepsSharedAttributes) {
    prt::TriMesh plane = prt::makePlane(1.0f, 1), sphere = prt::makeSphere(1.0f, 2, 3);
    prt::TriMesh merged = prt::mergeMeshes({plane, sphere});
    EXPECT_EQ(merged.vertexCount(), plane.vertexCount() + sphere.vertexCount());
    EXPECT_EQ(merged.indices[plane.indices.size()], sphere.indices[0] + plane.vertexCount());
    EXPECT_EQ(merged.normals.size(), merged.positions.size());
    EXPECT_TRUE(merged.texcoords.empty()); // the sphere has none
}

TEST(Scene, UnknownNameIsAUsageErrorListingTheNames) {
    try {
        prt::makeScene("teapot");
        ADD_FAILURE() << "no error";
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.exitCode(), prt::kExitUsage);
        for (const std::string& name : prt::sceneNames()) EXPECT_NE(std::string(e.what()).find(name), std::string::npos);
    }
}

TEST(Scene, DefaultScenesRoundTripThroughBundles) {
    for (const std::string& name : prt::sceneNames()) {
        SCOPED_TRACE(name);
        prt::Bundle bundle;
        bundle.mesh = prt::makeScene(name);
        std::string path = std::string(PRT_BINARY_DIR) + "/test_scene_" + name + ".glb";
        prt::writeBundle(path, bundle);
        prt::TriMesh read = prt::readBundle(path).mesh;
        EXPECT_EQ(read.positions, bundle.mesh.positions);
        EXPECT_EQ(read.normals, bundle.mesh.normals);
        EXPECT_EQ(read.indices, bundle.mesh.indices);
    }
}
