// The pilot, held-out and final check vertex subsets: stratified along a Morton curve so that each covers the whole
// mesh.
#include "autoconfig.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace prt::autoconfig {

namespace {

// 10 bits of x spread to every third bit.
uint32_t spreadBits(uint32_t x) {
    x &= 0x3ff;
    x = (x | (x << 16)) & 0x030000ff;
    x = (x | (x << 8)) & 0x0300f00f;
    x = (x | (x << 4)) & 0x030c30c3;
    x = (x | (x << 2)) & 0x09249249;
    return x;
}

uint64_t mix(uint64_t x) { // splitmix64's finaliser
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

} // namespace

void splitVertices(const TriMesh& mesh, size_t count, uint64_t seed, std::vector<uint32_t>& pilot,
                   std::vector<uint32_t>& heldOut, std::vector<uint32_t>& check) {
    const size_t V = mesh.vertexCount();
    if (V < 3)
        throw Error("", "mesh", "needs at least 3 vertices for a pilot, a held-out and a check vertex", kExitInput);
    count = std::clamp<size_t>(count, 1, V / 3);
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < V; ++v)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], mesh.positions[v * 3 + a]);
            hi[a] = std::max(hi[a], mesh.positions[v * 3 + a]);
        }
    std::vector<uint32_t> code(V);
    for (size_t v = 0; v < V; ++v) {
        uint32_t cell[3];
        for (int a = 0; a < 3; ++a) {
            float extent = hi[a] - lo[a];
            float t = extent > 0.0f ? (mesh.positions[v * 3 + a] - lo[a]) / extent : 0.0f;
            cell[a] = uint32_t(std::clamp(t * 1023.0f, 0.0f, 1023.0f));
        }
        code[v] = spreadBits(cell[0]) | (spreadBits(cell[1]) << 1) | (spreadBits(cell[2]) << 2);
    }
    std::vector<uint32_t> order(V);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return code[a] != code[b] ? code[a] < code[b] : a < b;
    });
    pilot.clear();
    heldOut.clear();
    check.clear();
    for (size_t run = 0; run < count; ++run) {
        const size_t begin = run * V / count, end = (run + 1) * V / count; // >= 3 vertices, as count <= V / 3
        const size_t length = end - begin;
        const uint64_t h = mix(seed ^ mix(run));
        const size_t a = size_t(h % length);
        const size_t b = (a + 1 + size_t((h >> 32) % (length - 1))) % length; // any other vertex of the run
        // The k-th vertex of the run that is neither a nor b.
        size_t k = size_t(mix(h) % (length - 2)), c = 0;
        for (;; ++c)
            if (c != a && c != b && k-- == 0) break;
        pilot.push_back(order[begin + a]);
        heldOut.push_back(order[begin + b]);
        check.push_back(order[begin + c]);
    }
    std::sort(pilot.begin(), pilot.end());
    std::sort(heldOut.begin(), heldOut.end());
    std::sort(check.begin(), check.end());
}

} // namespace prt::autoconfig
