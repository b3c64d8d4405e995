// A wall beside a floor, for the scene tests that need a corner (transfer, reference).
#pragma once

#include "bundle.h"
#include "scene.h"

namespace prt::test {

// makePlane(size, n) turned to stand on the plane y = 0 at x = 1, facing -X (toward a floor at x < 1):
// (x, 0, z) -> (1, x + 1, z), which maps makePlane's +Y-facing triangles to -X-facing ones.
inline TriMesh wallAtXOne(float size, int n) {
    TriMesh wall = makePlane(size, n, 0.0f);
    for (size_t v = 0; v < wall.vertexCount(); ++v) {
        float x = wall.positions[3 * v];
        wall.positions[3 * v] = 1.0f, wall.positions[3 * v + 1] = x + 1.0f;
        wall.normals[3 * v] = -1.0f, wall.normals[3 * v + 1] = 0.0f, wall.normals[3 * v + 2] = 0.0f;
    }
    return wall;
}

} // namespace prt::test
