// Vertices at one position: the grouping that spawn normals (lib/raycast) and UV seams (lib/bake) share, so that
// both see the same corners as one point.
#pragma once

#include "bundle.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace prt {

// The position groups of vertices [begin, end) of `mesh` (clamped to its vertices), numbered 0, 1, ... in order of
// each group's first vertex. group[v], for every vertex v of the mesh, is the group of v's position, or -1 where no
// vertex of the range has it (only outside the range). Two positions are one exactly when their coordinates' bits
// are, with -0 and +0 one value (a mirrored copy of a vertex on the mirror plane is the same point). groupCount is
// the number of groups. Linear in the vertices: a flat open-addressing table of 4 bytes per slot, at most 70% full.
struct PositionGroups {
    std::vector<int32_t> group;
    size_t groupCount = 0;
};
PositionGroups groupPositions(const TriMesh& mesh, size_t begin, size_t end);

} // namespace prt
