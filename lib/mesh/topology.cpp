#include "mesh.h"

#include <algorithm>
#include <numeric>

namespace prt {

MeshTopology analyzeTopology(const TriMesh& mesh) {
    // Seams and hard edges split vertices that are one point of the surface: join them by position.
    TriMesh surface;
    surface.positions = mesh.positions;
    surface.indices = mesh.indices;
    weldVertices(surface, 0.0f, false);

    // Undirected edges as (low, high) pairs packed in 64 bits; sorting groups the uses of each edge.
    std::vector<uint64_t> edges;
    edges.reserve(surface.indices.size());
    for (size_t t = 0; t < surface.triangleCount(); ++t)
        for (int k = 0; k < 3; ++k) {
            uint32_t a = surface.indices[3 * t + k], b = surface.indices[3 * t + (k + 1) % 3];
            if (a != b) edges.push_back(uint64_t(std::min(a, b)) << 32 | std::max(a, b));
        }
    std::sort(edges.begin(), edges.end());

    MeshTopology topology;
    std::vector<uint32_t> parent(surface.vertexCount());
    std::iota(parent.begin(), parent.end(), 0u);
    auto root = [&](uint32_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    };
    std::vector<uint32_t> rimVertices;
    for (size_t first = 0; first < edges.size();) {
        size_t last = first;
        while (last < edges.size() && edges[last] == edges[first]) ++last;
        size_t uses = last - first;
        if (uses >= 3) ++topology.nonManifoldEdges;
        if (uses == 1) {
            ++topology.boundaryEdges;
            uint32_t a = uint32_t(edges[first] >> 32), b = uint32_t(edges[first]);
            parent[root(a)] = root(b);
            rimVertices.push_back(a);
        }
        first = last;
    }
    std::vector<uint32_t> loops;
    for (uint32_t v : rimVertices) loops.push_back(root(v));
    std::sort(loops.begin(), loops.end());
    topology.boundaryLoops = size_t(std::unique(loops.begin(), loops.end()) - loops.begin());
    return topology;
}

} // namespace prt
