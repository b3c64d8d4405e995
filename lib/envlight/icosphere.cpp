// The thesis's spherical quadtree: a regular icosahedron, each triangle split 1 -> 4 per level, vertices pushed
// onto the unit sphere. Uniform in solid angle to within ~20%, with no seams (unlike cube maps).
#include "envlight.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace prt::envlight {

Icosphere icosphere(int level) {
    if (level < 0 || level > 8)
        throw Error("", "icosphere level", std::to_string(level) + " outside 0..8", kExitUsage);
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    Icosphere sphere;
    sphere.vertices = {-1, t, 0, 1, t, 0, -1, -t, 0, 1, -t, 0, 0, -1, t, 0, 1, t,
                       0, -1, -t, 0, 1, -t, t, 0, -1, t, 0, 1, -t, 0, -1, -t, 0, 1};
    sphere.triangles = {0, 11, 5, 0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11, 4,  11, 10, 2,  10, 7, 6,
                        7, 1,  8, 3, 9,  4, 3, 4, 2, 3, 2,  6,  3, 6,  8,  3, 8, 9, 4, 9,  5,  2,  4,  11, 6,  2, 10,
                        8, 6,  7, 9, 8,  1};
    auto normalise = [&](size_t v) {
        double* p = &sphere.vertices[v * 3];
        double length = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (int c = 0; c < 3; ++c) p[c] /= length;
    };
    for (size_t v = 0; v < 12; ++v) normalise(v);
    for (int l = 0; l < level; ++l) {
        std::unordered_map<uint64_t, uint32_t> midpoints;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
            auto found = midpoints.find(key);
            if (found != midpoints.end()) return found->second;
            uint32_t index = uint32_t(sphere.vertexCount());
            for (int c = 0; c < 3; ++c)
                sphere.vertices.push_back(0.5 * (sphere.vertices[a * 3 + c] + sphere.vertices[b * 3 + c]));
            normalise(index);
            midpoints.emplace(key, index);
            return index;
        };
        std::vector<uint32_t> next;
        next.reserve(sphere.triangles.size() * 4);
        for (size_t f = 0; f < sphere.triangles.size(); f += 3) {
            uint32_t a = sphere.triangles[f], b = sphere.triangles[f + 1], c = sphere.triangles[f + 2];
            uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        sphere.triangles.swap(next);
    }
    // Neighbours from the triangles' edges, each list sorted and unique.
    std::vector<std::vector<uint32_t>> lists(sphere.vertexCount());
    for (size_t f = 0; f < sphere.triangles.size(); f += 3)
        for (int e = 0; e < 3; ++e) {
            uint32_t a = sphere.triangles[f + e], b = sphere.triangles[f + (e + 1) % 3];
            lists[a].push_back(b);
            lists[b].push_back(a);
        }
    sphere.neighbourOffsets.push_back(0);
    for (auto& list : lists) {
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
        sphere.neighbours.insert(sphere.neighbours.end(), list.begin(), list.end());
        sphere.neighbourOffsets.push_back(uint32_t(sphere.neighbours.size()));
    }
    return sphere;
}

} // namespace prt::envlight
