// Lobe-order flips of a fit (GlossyLobes::stats): between neighbouring views of each vertex and between mesh
// neighbours at each view, counted by lobesFlipped over the pairs whose lobes are all lit.
#include "glossy.h"
#include "glossy_internal.h"

namespace prt::glossy {

namespace {

bool allLobesLit(const float* lobes, int count) {
    for (int k = 0; k < count; ++k)
        if (!(lobes[k * kLobeParams] > 0.0f)) return false;
    return true;
}

} // namespace

// Lobe-order flips between neighbouring views of each vertex and between mesh neighbours at each view.
void countFlips(const TriMesh& mesh, GlossyLobes& result) {
    if (result.lobes < 2) return;
    const ViewSet& views = viewSet();
    const size_t width = size_t(result.lobes) * kLobeParams;
    auto lobesOf = [&](size_t vertex, int view) {
        return &result.values[((vertex - result.vertexBegin) * kViewCount + size_t(view)) * width];
    };
    for (size_t v = result.vertexBegin; v < result.vertexEnd; ++v)
        for (int a = 0; a < kViewCount; ++a)
            for (uint32_t b : views.neighbours[a]) {
                if (int(b) <= a || !allLobesLit(lobesOf(v, a), result.lobes) || !allLobesLit(lobesOf(v, int(b)), result.lobes))
                    continue;
                ++result.stats.viewPairs;
                result.stats.viewFlips += lobesFlipped(lobesOf(v, a), lobesOf(v, int(b)), result.lobes);
            }
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        for (int e = 0; e < 3; ++e) {
            size_t p = mesh.indices[t * 3 + e], q = mesh.indices[t * 3 + (e + 1) % 3];
            // Each undirected edge once: from its smaller end, in the triangle that lists it ascending.
            if (p >= q || p < result.vertexBegin || q >= result.vertexEnd) continue;
            for (int view = 0; view < kViewCount; ++view) {
                if (!allLobesLit(lobesOf(p, view), result.lobes) || !allLobesLit(lobesOf(q, view), result.lobes)) continue;
                ++result.stats.vertexPairs;
                result.stats.vertexFlips += lobesFlipped(lobesOf(p, view), lobesOf(q, view), result.lobes);
            }
        }
}

} // namespace prt::glossy
