#include "position_groups.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace prt {
namespace {

TriMesh pointsAt(const std::vector<float>& positions) {
    TriMesh mesh;
    mesh.positions = positions;
    return mesh;
}

TEST(PositionGroups, EqualPositionsShareAGroupNumberedByFirstVertexAndSignedZerosAreOne) {
    const float next = std::nextafter(1.0f, 2.0f);
    // 0: (1,2,3); 1: (0,0,0); 2: (1,2,3) again; 3: (-0,0,-0), the same point as 1; 4: one ulp past vertex 0 in x;
    // 5: (0,-0,0).
    const TriMesh mesh = pointsAt({1, 2, 3, 0, 0, 0, 1, 2, 3, -0.0f, 0, -0.0f, next, 2, 3, 0, -0.0f, 0});
    const PositionGroups groups = groupPositions(mesh, 0, mesh.vertexCount());
    EXPECT_EQ(groups.groupCount, 3u);
    EXPECT_EQ(groups.group, (std::vector<int32_t>{0, 1, 0, 1, 2, 1}));
}

TEST(PositionGroups, ARangeNumbersItsOwnGroupsAndFindsThemOutsideIt) {
    // Positions a b a c b d: the range [2, 5) holds a, c, b.
    const TriMesh mesh = pointsAt({1, 0, 0, 2, 0, 0, 1, 0, 0, 3, 0, 0, 2, 0, 0, 4, 0, 0});
    const PositionGroups groups = groupPositions(mesh, 2, 5);
    EXPECT_EQ(groups.groupCount, 3u);
    // a is group 0 (vertex 2), c group 1 (vertex 3), b group 2 (vertex 4); d is in no group of the range.
    EXPECT_EQ(groups.group, (std::vector<int32_t>{0, 2, 0, 1, 2, -1}));
    // Past the end: clamped; an empty range has no groups.
    EXPECT_EQ(groupPositions(mesh, 4, 100).group, (std::vector<int32_t>{-1, 0, -1, -1, 0, 1}));
    const PositionGroups none = groupPositions(mesh, 3, 3);
    EXPECT_EQ(none.groupCount, 0u);
    EXPECT_EQ(none.group, std::vector<int32_t>(6, -1));
}

TEST(PositionGroups, ManyPositionsWithCollisionsGroupAsAMapWould) {
    // 20,000 vertices over 1,000 positions on a grid (many hash neighbours), each position's first vertex in order.
    TriMesh mesh;
    for (size_t v = 0; v < 20000; ++v) {
        const size_t p = (v * 7919) % 1000;
        mesh.positions.insert(mesh.positions.end(), {float(p % 10), float(p / 10 % 10), float(p / 100)});
    }
    const PositionGroups groups = groupPositions(mesh, 0, mesh.vertexCount());
    ASSERT_EQ(groups.groupCount, 1000u);
    // Vertices 0..999 are the 1,000 positions once each (7919 is prime to 1000), so vertex v < 1000 opens group v.
    for (size_t v = 0; v < 20000; ++v) ASSERT_EQ(groups.group[v], int32_t(v % 1000)) << v;
}

} // namespace
} // namespace prt
