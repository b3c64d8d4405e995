#include "scene.h"

namespace prt {

TriMesh makePlane(float size, int n, float y) {
    TriMesh mesh;
    for (int k = 0; k <= n; ++k)
        for (int i = 0; i <= n; ++i) {
            double u = double(i) / n, v = double(k) / n;
            mesh.positions.insert(mesh.positions.end(), {float(size * (u - 0.5)), y, float(size * (v - 0.5))});
            mesh.normals.insert(mesh.normals.end(), {0.0f, 1.0f, 0.0f});
            mesh.texcoords.insert(mesh.texcoords.end(), {float(u), float(v)});
        }
    auto vertex = [n](int i, int k) { return uint32_t(k * (n + 1) + i); };
    // Seen from +Y, +Z then +X turns counter-clockwise.
    for (int k = 0; k < n; ++k)
        for (int i = 0; i < n; ++i) {
            mesh.indices.insert(mesh.indices.end(), {vertex(i, k), vertex(i, k + 1), vertex(i + 1, k + 1)});
            mesh.indices.insert(mesh.indices.end(), {vertex(i, k), vertex(i + 1, k + 1), vertex(i + 1, k)});
        }
    return mesh;
}

} // namespace prt
