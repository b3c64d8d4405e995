// Vertices at one position, grouped in a flat hash table (position_groups.h).
#include "position_groups.h"

#include <algorithm>
#include <array>
#include <cstring>

namespace prt {

namespace {

// A position's coordinates as bits, -0 as +0.
std::array<uint32_t, 3> positionKey(const float* positions, size_t v) {
    std::array<uint32_t, 3> bits;
    std::memcpy(bits.data(), positions + 3 * v, sizeof bits);
    for (uint32_t& b : bits) b = b == 0x80000000u ? 0u : b;
    return bits;
}

} // namespace

PositionGroups groupPositions(const TriMesh& mesh, size_t begin, size_t end) {
    const size_t count = mesh.vertexCount();
    end = std::min(end, count);
    begin = std::min(begin, end);
    const float* positions = mesh.positions.data();
    size_t capacity = 16;
    while (capacity * 7 < (end - begin) * 10) capacity *= 2;
    const size_t mask = capacity - 1;
    std::vector<int32_t> slots(capacity, -1); // a group, or -1: empty
    std::vector<uint32_t> firstVertex;        // per group
    // The slot of vertex v's position: the one holding its group, or the empty one where it belongs.
    auto slot = [&](size_t v) {
        const std::array<uint32_t, 3> bits = positionKey(positions, v);
        const uint64_t h = (uint64_t(bits[0]) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(bits[1]) * 0xC2B2AE3D27D4EB4Full) ^
                           (uint64_t(bits[2]) * 0x165667B19E3779F9ull);
        size_t at = size_t(h ^ (h >> 29)) & mask;
        while (slots[at] >= 0 && positionKey(positions, firstVertex[size_t(slots[at])]) != bits) at = (at + 1) & mask;
        return at;
    };
    PositionGroups groups;
    groups.group.assign(count, -1);
    for (size_t v = begin; v < end; ++v) {
        const size_t at = slot(v);
        if (slots[at] < 0) {
            slots[at] = int32_t(firstVertex.size());
            firstVertex.push_back(uint32_t(v));
        }
        groups.group[v] = slots[at];
    }
    if (end - begin < count)
        for (size_t v = 0; v < count; ++v)
            if (v < begin || v >= end) groups.group[v] = slots[slot(v)];
    groups.groupCount = firstVertex.size();
    return groups;
}

} // namespace prt
