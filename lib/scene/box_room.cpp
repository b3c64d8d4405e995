#include "scene.h"

namespace prt {

TriMesh makeBoxRoom(float size, int n) {
    TriMesh mesh;
    // Every coordinate comes from this one function of a grid index, so edges shared by two faces have
    // bit-identical positions.
    auto coordinate = [&](int i) { return float(size * (double(i) / n - 0.5)); };
    for (int axis = 0; axis < 3; ++axis)
        for (int side : {0, n}) {
            // Grid axes b, c with e_b x e_c = e_axis. The wall at index 0 faces +axis (inward), the one at n faces -axis.
            int b = (axis + 1) % 3, c = (axis + 2) % 3;
            float inward = side == 0 ? 1.0f : -1.0f;
            uint32_t first = uint32_t(mesh.vertexCount());
            for (int k = 0; k <= n; ++k)
                for (int i = 0; i <= n; ++i) {
                    float position[3], normal[3] = {0.0f, 0.0f, 0.0f};
                    position[axis] = coordinate(side);
                    position[b] = coordinate(i);
                    position[c] = coordinate(k);
                    normal[axis] = inward;
                    mesh.positions.insert(mesh.positions.end(), position, position + 3);
                    mesh.normals.insert(mesh.normals.end(), normal, normal + 3);
                }
            auto vertex = [&](int i, int k) { return first + uint32_t(k * (n + 1) + i); };
            for (int k = 0; k < n; ++k)
                for (int i = 0; i < n; ++i) {
                    uint32_t quad[4] = {vertex(i, k), vertex(i + 1, k), vertex(i + 1, k + 1), vertex(i, k + 1)};
                    if (inward < 0) std::swap(quad[1], quad[3]); // counter-clockwise seen from -axis
                    mesh.indices.insert(mesh.indices.end(), {quad[0], quad[1], quad[2], quad[0], quad[2], quad[3]});
                }
        }
    return mesh;
}

} // namespace prt
