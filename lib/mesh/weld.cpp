#include "mesh.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

namespace prt {
namespace {

constexpr uint32_t kNone = ~0u;
constexpr size_t kProgressStep = 1 << 16;

struct CellKey {
    int64_t x, y, z;
    bool operator==(const CellKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellKeyHash {
    size_t operator()(const CellKey& k) const {
        uint64_t h = uint64_t(k.x) * 0x9E3779B97F4A7C15ull;
        h = (h ^ uint64_t(k.y)) * 0xC2B2AE3D27D4EB4Full;
        h = (h ^ uint64_t(k.z)) * 0x165667B19E3779F9ull;
        return size_t(h ^ (h >> 32));
    }
};

bool sameValues(const std::vector<float>& values, size_t width, size_t a, size_t b) {
    return values.empty() || std::memcmp(&values[a * width], &values[b * width], width * sizeof(float)) == 0;
}

bool sameAttributes(const TriMesh& mesh, size_t a, size_t b) {
    return sameValues(mesh.normals, 3, a, b) && sameValues(mesh.texcoords, 2, a, b) && sameValues(mesh.albedo, 3, a, b);
}

} // namespace

std::vector<uint32_t> weldVertices(TriMesh& mesh, float tolerance, bool compareAttributes) {
    const size_t vertexCount = mesh.vertexCount();
    std::vector<uint8_t> used(vertexCount);
    for (uint32_t v : mesh.indices) used[v] = 1;

    // Cells of the tolerance's size put every vertex within tolerance into the 27 cells around a vertex. With no
    // tolerance a cell is one exact position (+0 and -0 alike), and only that cell is searched.
    const bool exact = !(tolerance > 0.0f);
    const int reach = exact ? 0 : 1;
    const double toleranceSquared = double(tolerance) * double(tolerance);
    auto cellOf = [&](const float* p) {
        int64_t key[3];
        for (int c = 0; c < 3; ++c) {
            if (exact) {
                float x = p[c] + 0.0f;
                uint32_t bits;
                std::memcpy(&bits, &x, sizeof(bits));
                key[c] = bits;
            } else {
                key[c] = int64_t(std::clamp(std::floor(double(p[c]) / tolerance), -4e18, 4e18));
            }
        }
        return CellKey{key[0], key[1], key[2]};
    };

    // Representatives per cell as linked lists through nextInCell.
    std::unordered_map<CellKey, uint32_t, CellKeyHash> cellHead;
    std::vector<uint32_t> nextInCell(vertexCount, kNone);
    std::vector<uint32_t> representative(vertexCount, kNone);
    Progress progress("weld", vertexCount);
    for (size_t i = 0; i < vertexCount; ++i) {
        if (i % kProgressStep == kProgressStep - 1) progress.add(kProgressStep);
        if (!used[i]) continue;
        const float* p = &mesh.positions[3 * i];
        CellKey cell = cellOf(p);
        uint32_t best = kNone;
        for (int dx = -reach; dx <= reach; ++dx)
            for (int dy = -reach; dy <= reach; ++dy)
                for (int dz = -reach; dz <= reach; ++dz) {
                    auto found = cellHead.find({cell.x + dx, cell.y + dy, cell.z + dz});
                    if (found == cellHead.end()) continue;
                    for (uint32_t r = found->second; r != kNone; r = nextInCell[r]) {
                        if (r >= best) continue;
                        const float* q = &mesh.positions[3 * r];
                        double dx2 = double(p[0]) - q[0], dy2 = double(p[1]) - q[1], dz2 = double(p[2]) - q[2];
                        if (dx2 * dx2 + dy2 * dy2 + dz2 * dz2 <= toleranceSquared &&
                            (!compareAttributes || sameAttributes(mesh, i, r)))
                            best = r;
                    }
                }
        if (best != kNone) {
            representative[i] = best;
            continue;
        }
        representative[i] = uint32_t(i);
        auto [head, inserted] = cellHead.try_emplace(cell, uint32_t(i));
        if (!inserted) {
            nextInCell[i] = head->second;
            head->second = uint32_t(i);
        }
    }
    progress.finish();

    for (uint32_t& v : mesh.indices) v = representative[v];
    return removeUnusedVertices(mesh);
}

} // namespace prt
