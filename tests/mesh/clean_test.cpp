// validateMesh, removeDegenerateFaces, weldVertices, computeNormals, decimate, analyzeTopology on meshes built in
// memory.
#include "mesh.h"
#include "mesh_test_util.h"

#include "core.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <random>

namespace prt::test {
namespace {

std::string errorOf(const std::function<void()>& run) {
    try {
        run();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

// ---- validation ----

TEST(Validate, RemovesDegenerateAndDuplicateFacesAndCountsThem) {
    TriMesh mesh = makeCube();
    mesh.positions.insert(mesh.positions.end(), {2, 0, 0, 3, 0, 0, 4, 0, 0});                     // collinear: zero area
    mesh.indices.insert(mesh.indices.end(), {8, 9, 10, 0, 0, 1});                                 // zero area, repeated index
    mesh.indices.insert(mesh.indices.end(), {mesh.indices[1], mesh.indices[2], mesh.indices[0]}); // rotation of triangle 0
    mesh.indices.insert(mesh.indices.end(), {mesh.indices[3], mesh.indices[5], mesh.indices[4]}); // triangle 1, other winding
    std::vector<uint32_t> cubeIndices = makeCube().indices;

    FaceCleanup cleanup = validateMesh(mesh, "cube");
    EXPECT_EQ(cleanup.degenerateFaces, 2u);
    EXPECT_EQ(cleanup.duplicateFaces, 2u);
    EXPECT_EQ(mesh.indices, cubeIndices); // the first of each duplicate set survives, in order
}

TEST(Validate, NamesTheVertexWithANonFinitePosition) {
    TriMesh mesh = makeCube();
    mesh.positions[3 * 5 + 1] = NAN;
    std::string message = errorOf([&] { validateMesh(mesh, "cube.obj"); });
    EXPECT_NE(message.find("cube.obj: vertex 5: non-finite position"), std::string::npos) << message;
}

TEST(Validate, NamesTheTriangleAndIndexOutOfRange) {
    TriMesh mesh = makeCube();
    mesh.indices[3 * 7 + 2] = 8;
    std::string message = errorOf([&] { validateMesh(mesh, "cube.obj"); });
    EXPECT_NE(message.find("cube.obj: triangle 7: vertex index 8 out of range (8 vertices)"), std::string::npos) << message;
}

TEST(Validate, RefusesEmptyAndAllDegenerateMeshes) {
    TriMesh empty;
    EXPECT_NE(errorOf([&] { validateMesh(empty, "e.obj"); }).find("empty mesh"), std::string::npos);
    TriMesh flat;
    flat.positions = {0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3};
    flat.indices = {0, 1, 2, 1, 2, 3, 0, 0, 3};
    EXPECT_NE(errorOf([&] { validateMesh(flat, "f.obj"); }).find("all 3 triangles are degenerate"), std::string::npos);
}

TEST(Validate, NormalizesAuthoredNormalsAndDropsZeroOnes) {
    TriMesh mesh = makeGrid(1);
    mesh.normals = {0, 2, 0, 0, 3, 0, 0, 0.5f, 0, 0, 1, 0};
    validateMesh(mesh, "grid");
    EXPECT_EQ(mesh.normals, (std::vector<float>{0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0}));
    mesh.normals[4] = 0;
    validateMesh(mesh, "grid");
    EXPECT_TRUE(mesh.normals.empty());
}

// ---- welding ----

TEST(Weld, SoupOfACubeWeldsToItsEightCornersInFirstAppearanceOrder) {
    TriMesh cube = makeCube();
    TriMesh soup = makeSoup(cube);
    ASSERT_EQ(soup.vertexCount(), 36u);
    std::vector<uint32_t> source = weldVertices(soup, 1e-6f, true);

    ASSERT_EQ(soup.vertexCount(), 8u);
    EXPECT_EQ(soup.triangleCount(), 12u);
    // Representatives are each corner's first appearance in the soup, in increasing order.
    std::vector<uint32_t> firstAppearance;
    std::vector<bool> seen(8);
    for (size_t k = 0; k < cube.indices.size(); ++k)
        if (!seen[cube.indices[k]]) seen[cube.indices[k]] = true, firstAppearance.push_back(uint32_t(k));
    EXPECT_EQ(source, firstAppearance);
    for (size_t k = 0; k < soup.indices.size(); ++k)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(soup.positions[3 * soup.indices[k] + c], cube.positions[3 * cube.indices[k] + c]);
}

TEST(Weld, ToleranceIsARadiusAroundTheRepresentativeWithoutChaining) {
    // Points along x at 0, 0.8, 1.6, 2.4 (tolerance 1): 1 joins 0; 2 is 0.8 from 1 but 1.6 from representative 0,
    // so it starts a group that 3 joins.
    TriMesh mesh;
    mesh.positions = {0, 0, 0, 0.8f, 0, 0, 1.6f, 0, 0, 2.4f, 0, 0, 0, 5, 0};
    mesh.indices = {0, 1, 4, 1, 2, 4, 2, 3, 4};
    std::vector<uint32_t> source = weldVertices(mesh, 1.0f, true);
    EXPECT_EQ(source, (std::vector<uint32_t>{0, 2, 4}));
    EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 0, 2, 0, 1, 2, 1, 1, 2}));
}

TEST(Weld, KeepsTextureSeamsUnlessToldToIgnoreAttributes) {
    TriMesh mesh = makeGrid(1);
    mesh.positions.insert(mesh.positions.end(), mesh.positions.begin(), mesh.positions.begin() + 3); // vertex 4 = vertex 0
    mesh.texcoords = {0, 0, 1, 0, 0, 1, 1, 1, 0.5f, 0.5f};
    mesh.indices[3] = 4; // the second triangle uses the copy
    TriMesh ignoring = mesh;
    EXPECT_EQ(weldVertices(mesh, 1e-3f, true).size(), 5u);
    EXPECT_EQ(weldVertices(ignoring, 1e-3f, false), (std::vector<uint32_t>{0, 1, 2, 3}));
    EXPECT_FLOAT_EQ(ignoring.texcoords[0], 0.0f); // the representative's
}

// The rule written the slow way: vertex i joins the lowest earlier representative within tolerance.
std::vector<uint32_t> bruteForceRepresentatives(const TriMesh& mesh, float tolerance) {
    std::vector<uint32_t> representatives;
    for (uint32_t i = 0; i < mesh.vertexCount(); ++i) {
        bool joined = false;
        for (uint32_t r : representatives) {
            double d2 = 0;
            for (int c = 0; c < 3; ++c) d2 += std::pow(double(mesh.positions[3 * i + c]) - mesh.positions[3 * r + c], 2);
            if (d2 <= double(tolerance) * tolerance) {
                joined = true;
                break;
            }
        }
        if (!joined) representatives.push_back(i);
    }
    return representatives;
}

TEST(Weld, FollowsTheGreedyRuleExactlyOnClusteredPoints) {
    std::mt19937 random(7);
    std::uniform_real_distribution<float> centre(-1, 1), jitter(-0.004f, 0.004f);
    // Clusters wider than the tolerance, so some split; shuffled so that members are far apart in the input.
    std::vector<std::array<float, 3>> points;
    for (int cluster = 0; cluster < 200; ++cluster) {
        float c[3] = {centre(random), centre(random), centre(random)};
        for (int k = 0; k < 3; ++k) points.push_back({c[0] + jitter(random), c[1] + jitter(random), c[2] + jitter(random)});
    }
    std::shuffle(points.begin(), points.end(), random);
    TriMesh mesh;
    for (const auto& p : points) mesh.positions.insert(mesh.positions.end(), p.begin(), p.end());
    for (uint32_t v = 0; v + 2 < mesh.vertexCount(); v += 3) mesh.indices.insert(mesh.indices.end(), {v, v + 1, v + 2});
    const float tolerance = 0.01f;
    std::vector<uint32_t> expected = bruteForceRepresentatives(mesh, tolerance);
    TriMesh again = mesh;
    EXPECT_EQ(weldVertices(mesh, tolerance, true), expected);
    EXPECT_EQ(weldVertices(again, tolerance, true), expected);
    EXPECT_EQ(mesh.indices, again.indices);
}

// ---- normals ----

TEST(Normals, CubeCornersPointAlongTheDiagonalWhateverTheTriangulation) {
    TriMesh cube = makeCube();
    // The split diagonals put some corners in two triangles of a face and in one of another: only the angle
    // weighting sees each face as 90 degrees.
    std::vector<int> uses(8);
    for (uint32_t v : cube.indices) ++uses[v];
    ASSERT_NE(*std::min_element(uses.begin(), uses.end()), *std::max_element(uses.begin(), uses.end()));
    computeNormals(cube);
    for (size_t v = 0; v < 8; ++v)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(cube.normals[3 * v + c], std::copysign(1.0 / std::sqrt(3.0), cube.positions[3 * v + c]), 1e-6)
                << "vertex " << v;
}

// Largest angle in degrees between a vertex normal and the radial direction of the unit sphere.
double worstNormalErrorDegrees(int rings, int segments) {
    TriMesh sphere = makeSphere(rings, segments);
    computeNormals(sphere);
    double worst = 0;
    for (size_t v = 0; v < sphere.vertexCount(); ++v) {
        double dot = 0, radius = 0, length = 0;
        for (int c = 0; c < 3; ++c) {
            dot += sphere.normals[3 * v + c] * sphere.positions[3 * v + c];
            radius += sphere.positions[3 * v + c] * sphere.positions[3 * v + c];
            length += sphere.normals[3 * v + c] * sphere.normals[3 * v + c];
        }
        EXPECT_NEAR(length, 1.0, 1e-6);
        worst = std::max(worst, std::acos(std::min(1.0, dot / std::sqrt(radius * length))) * 180 / M_PI);
    }
    return worst;
}

TEST(Normals, SphereNormalsConvergeToTheRadialDirection) {
    // Rings of different radii above and below a vertex tilt its normal by O(h^2): halving h quarters the error.
    double coarse = worstNormalErrorDegrees(12, 24), medium = worstNormalErrorDegrees(24, 48),
           fine = worstNormalErrorDegrees(48, 96);
    std::cout << "worst normal error: " << coarse << " " << medium << " " << fine << " degrees\n";
    EXPECT_LT(medium, 0.2);
    EXPECT_GT(coarse / medium, 3.5);
    EXPECT_GT(medium / fine, 3.5);
}

// ---- decimation ----

TEST(Decimate, SphereReachesTheTargetAndStaysAValidClosedSurface) {
    TriMesh sphere = makeSphere(32, 64);
    const TriMesh original = sphere;
    ASSERT_EQ(sphere.triangleCount(), 3968u);
    std::vector<uint32_t> source = decimate(sphere, 1000);

    EXPECT_GE(sphere.triangleCount(), 990u);
    EXPECT_LE(sphere.triangleCount(), 1000u);
    TriMesh check = sphere;
    FaceCleanup cleanup = validateMesh(check, "decimated");
    EXPECT_EQ(cleanup.degenerateFaces + cleanup.duplicateFaces, 0u);
    MeshTopology topology = analyzeTopology(sphere);
    EXPECT_EQ(topology.boundaryEdges, 0u);
    EXPECT_EQ(topology.nonManifoldEdges, 0u);
    EXPECT_EQ(sphere.vertexCount() * 2 - 4, sphere.triangleCount()); // Euler: a closed genus-0 surface
    ASSERT_EQ(source.size(), sphere.vertexCount());
    EXPECT_TRUE(std::is_sorted(source.begin(), source.end()));
    for (size_t k = 0; k < source.size(); ++k)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(sphere.positions[3 * k + c], original.positions[3 * source[k] + c]);
    // Still outward: every triangle faces away from the centre.
    orientOutward(check);
    EXPECT_EQ(check.indices, sphere.indices);
}

TEST(Decimate, PlaneKeepsItsRim) {
    TriMesh plane = makeGrid(20);
    decimate(plane, 200);
    EXPECT_GE(plane.triangleCount(), 198u);
    EXPECT_LE(plane.triangleCount(), 200u);
    MeshTopology topology = analyzeTopology(plane);
    EXPECT_EQ(topology.boundaryLoops, 1u);
    Bounds bounds = computeBounds(plane);
    EXPECT_EQ(bounds.min, (std::array<float, 3>{-0.5f, 0.0f, -0.5f}));
    EXPECT_EQ(bounds.max, (std::array<float, 3>{0.5f, 0.0f, 0.5f}));
}

TEST(Decimate, KeepsATriangleOnANonManifoldEdgeOnCopiesOfItsVertices) {
    TriMesh sphere = makeSphere(16, 32);
    uint32_t a = sphere.indices[0], b = sphere.indices[1]; // an edge already used by two triangles
    sphere.positions.insert(sphere.positions.end(), {0, 3, 0});
    sphere.indices.insert(sphere.indices.end(), {a, b, uint32_t(sphere.vertexCount() - 1)});
    ASSERT_EQ(analyzeTopology(sphere).nonManifoldEdges, 1u);

    std::vector<uint32_t> source = decimate(sphere, 300);
    EXPECT_LE(sphere.triangleCount(), 300u);
    EXPECT_GE(sphere.triangleCount(), 297u);
    TriMesh check = sphere;
    EXPECT_EQ(validateMesh(check, "decimated").degenerateFaces, 0u);
    EXPECT_TRUE(std::is_sorted(source.begin(), source.end()));
    // The fin stands apart, untouched: its tip (the last input vertex) is the last output vertex, on a triangle
    // with copies of a and b.
    ASSERT_EQ(source.back(), 16u * 32u - 32u + 2u);
    uint32_t tip = uint32_t(sphere.vertexCount() - 1);
    auto fin = std::find(sphere.indices.begin(), sphere.indices.end(), tip);
    ASSERT_NE(fin, sphere.indices.end());
    size_t corner = size_t(fin - sphere.indices.begin());
    const uint32_t* triangle = &sphere.indices[corner - corner % 3];
    std::vector<uint32_t> corners = {source[triangle[0]], source[triangle[1]], source[triangle[2]]};
    std::sort(corners.begin(), corners.end());
    std::vector<uint32_t> expected = {std::min(a, b), std::max(a, b), 16u * 32u - 32u + 2u};
    EXPECT_EQ(corners, expected);
}

TEST(Decimate, IsDeterministic) {
    TriMesh a = makeSphere(16, 32), b = a;
    EXPECT_EQ(decimate(a, 300), decimate(b, 300));
    EXPECT_EQ(a.indices, b.indices);
}

// ---- topology ----

TEST(Topology, PlaneHasOneLoopAroundItsRim) {
    MeshTopology topology = analyzeTopology(makeGrid(5));
    EXPECT_EQ(topology.boundaryEdges, 20u);
    EXPECT_EQ(topology.boundaryLoops, 1u);
    EXPECT_EQ(topology.nonManifoldEdges, 0u);
}

TEST(Topology, CubeWithFacesRemoved) {
    EXPECT_EQ(analyzeTopology(makeCube()).boundaryLoops, 0u);
    MeshTopology adjacent = analyzeTopology(makeCube({1, 3})); // +X and +Y share an edge: one hole
    EXPECT_EQ(adjacent.boundaryLoops, 1u);
    EXPECT_EQ(adjacent.boundaryEdges, 6u);
    MeshTopology opposite = analyzeTopology(makeCube({0, 1})); // -X and +X: a tube with two rims
    EXPECT_EQ(opposite.boundaryLoops, 2u);
    EXPECT_EQ(opposite.boundaryEdges, 8u);
}

TEST(Topology, CountsEdgesSharedByThreeTriangles) {
    TriMesh fin;
    fin.positions = {0, 0, 0, 0, 1, 0, 1, 0, 0, -1, 0, 0, 0, 0, 1};
    fin.indices = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    MeshTopology topology = analyzeTopology(fin);
    EXPECT_EQ(topology.nonManifoldEdges, 1u);
    EXPECT_EQ(topology.boundaryEdges, 6u);
}

TEST(Topology, TextureSeamIsNotABoundary) {
    TriMesh mesh = makeCube();
    // Give face -X its own copies of its corners, as a UV seam would.
    for (size_t t = 0; t < 2; ++t)
        for (int k = 0; k < 3; ++k) {
            uint32_t& v = mesh.indices[3 * t + k];
            mesh.positions.insert(mesh.positions.end(), &mesh.positions[3 * v], &mesh.positions[3 * v] + 3);
            v = uint32_t(mesh.vertexCount() - 1);
        }
    EXPECT_EQ(analyzeTopology(mesh).boundaryEdges, 0u);
}

} // namespace
} // namespace prt::test
