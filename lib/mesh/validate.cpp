#include "mesh.h"

#include "core.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <unordered_set>

namespace prt {
namespace {

void requireArraySize(const std::vector<float>& values, size_t width, size_t vertices, const char* name,
                      const std::string& source) {
    if (!values.empty() && values.size() != width * vertices)
        throw Error(source, name,
                    std::to_string(values.size()) + " floats for " + std::to_string(vertices) + " vertices (expected " +
                        std::to_string(width * vertices) + ")");
}

void requireFinite(const std::vector<float>& values, size_t width, const char* name, const std::string& source) {
    for (size_t i = 0; i < values.size(); ++i)
        if (!std::isfinite(values[i]))
            throw Error(source, "vertex " + std::to_string(i / width),
                        std::string("non-finite ") + name + " (" + std::to_string(values[i]) + ")");
}

bool isDegenerate(const TriMesh& mesh, const uint32_t* t) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
    const float* p[3] = {&mesh.positions[3 * t[0]], &mesh.positions[3 * t[1]], &mesh.positions[3 * t[2]]};
    double e[3][3];
    double longest = 0;
    for (int k = 0; k < 3; ++k) {
        const float* a = p[k];
        const float* b = p[(k + 1) % 3];
        for (int c = 0; c < 3; ++c) e[k][c] = double(b[c]) - double(a[c]);
        longest = std::max(longest, e[k][0] * e[k][0] + e[k][1] * e[k][1] + e[k][2] * e[k][2]);
    }
    double cross[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                       e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    double twiceArea = std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
    return twiceArea <= FLT_EPSILON * longest;
}

// A triangle's vertices in ascending order: equal for both windings and all rotations.
struct TriangleKey {
    uint32_t v[3];
    bool operator==(const TriangleKey& o) const { return v[0] == o.v[0] && v[1] == o.v[1] && v[2] == o.v[2]; }
};
struct TriangleKeyHash {
    size_t operator()(const TriangleKey& k) const {
        uint64_t h = k.v[0];
        h = h * 0x9E3779B97F4A7C15ull ^ k.v[1];
        h = h * 0x9E3779B97F4A7C15ull ^ k.v[2];
        return size_t(h ^ (h >> 29));
    }
};

} // namespace

FaceCleanup removeDegenerateFaces(TriMesh& mesh) {
    FaceCleanup removed;
    std::unordered_set<TriangleKey, TriangleKeyHash> seen;
    seen.reserve(mesh.triangleCount());
    size_t kept = 0;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t* corners = &mesh.indices[3 * t];
        if (isDegenerate(mesh, corners)) {
            ++removed.degenerateFaces;
            continue;
        }
        TriangleKey key{{corners[0], corners[1], corners[2]}};
        std::sort(key.v, key.v + 3);
        if (!seen.insert(key).second) {
            ++removed.duplicateFaces;
            continue;
        }
        std::copy(corners, corners + 3, &mesh.indices[3 * kept++]);
    }
    mesh.indices.resize(3 * kept);
    return removed;
}

std::vector<uint32_t> removeUnusedVertices(TriMesh& mesh) {
    constexpr uint32_t kUnused = ~0u;
    std::vector<uint32_t> newIndex(mesh.vertexCount(), kUnused);
    for (uint32_t v : mesh.indices) newIndex[v] = 0;
    std::vector<uint32_t> sourceVertex;
    for (size_t v = 0; v < newIndex.size(); ++v)
        if (newIndex[v] != kUnused) {
            newIndex[v] = uint32_t(sourceVertex.size());
            sourceVertex.push_back(uint32_t(v));
        }
    auto gather = [&](std::vector<float>& values, size_t width) {
        if (values.empty()) return;
        std::vector<float> kept(sourceVertex.size() * width);
        for (size_t k = 0; k < sourceVertex.size(); ++k) std::copy_n(&values[sourceVertex[k] * width], width, &kept[k * width]);
        values = std::move(kept);
    };
    gather(mesh.positions, 3);
    gather(mesh.normals, 3);
    gather(mesh.texcoords, 2);
    gather(mesh.albedo, 3);
    for (uint32_t& v : mesh.indices) v = newIndex[v];
    return sourceVertex;
}

FaceCleanup validateMesh(TriMesh& mesh, const std::string& source) {
    size_t vertices = mesh.vertexCount();
    if (mesh.positions.size() % 3 != 0) throw Error(source, "positions", "not a multiple of 3 floats");
    if (mesh.indices.size() % 3 != 0) throw Error(source, "indices", "not a multiple of 3");
    if (vertices == 0 || mesh.indices.empty())
        throw Error(source, "",
                    "empty mesh (" + std::to_string(vertices) + " vertices, " + std::to_string(mesh.triangleCount()) +
                        " triangles)");
    requireArraySize(mesh.normals, 3, vertices, "normals", source);
    requireArraySize(mesh.texcoords, 2, vertices, "texcoords", source);
    requireArraySize(mesh.albedo, 3, vertices, "albedo", source);
    requireFinite(mesh.positions, 3, "position", source);
    requireFinite(mesh.normals, 3, "normal", source);
    requireFinite(mesh.texcoords, 2, "texcoord", source);
    requireFinite(mesh.albedo, 3, "albedo", source);
    for (size_t i = 0; i < mesh.indices.size(); ++i)
        if (mesh.indices[i] >= vertices)
            throw Error(source, "triangle " + std::to_string(i / 3),
                        "vertex index " + std::to_string(mesh.indices[i]) + " out of range (" + std::to_string(vertices) +
                            " vertices)");

    for (size_t v = 0; v < vertices && !mesh.normals.empty(); ++v) {
        float* n = &mesh.normals[3 * v];
        double length = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
        if (length == 0.0) {
            logWarn(source + ": vertex " + std::to_string(v) +
                    " has a zero normal; computing normals instead of keeping the file's");
            mesh.normals.clear();
            break;
        }
        for (int c = 0; c < 3; ++c) n[c] = float(n[c] / length);
    }

    size_t triangles = mesh.triangleCount();
    FaceCleanup removed = removeDegenerateFaces(mesh);
    if (mesh.indices.empty()) throw Error(source, "", "all " + std::to_string(triangles) + " triangles are degenerate");
    return removed;
}

Bounds computeBounds(const TriMesh& mesh) {
    Bounds bounds;
    bounds.min.fill(INFINITY);
    bounds.max.fill(-INFINITY);
    for (uint32_t v : mesh.indices)
        for (int c = 0; c < 3; ++c) {
            bounds.min[c] = std::min(bounds.min[c], mesh.positions[3 * v + c]);
            bounds.max[c] = std::max(bounds.max[c], mesh.positions[3 * v + c]);
        }
    if (mesh.indices.empty()) return Bounds();
    double squared = 0;
    for (int c = 0; c < 3; ++c) squared += (double(bounds.max[c]) - bounds.min[c]) * (double(bounds.max[c]) - bounds.min[c]);
    bounds.diagonal = std::sqrt(squared);
    return bounds;
}

} // namespace prt
