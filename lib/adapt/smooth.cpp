// Grading the order across the mesh, and the seam measure that checks it.
#include "adapt.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace prt::adapt {

namespace {

// Each undirected edge once, (smaller, larger), sorted: the same list whatever the triangle order.
std::vector<std::pair<uint32_t, uint32_t>> meshEdges(const std::vector<uint32_t>& indices) {
    std::vector<std::pair<uint32_t, uint32_t>> edges;
    edges.reserve(indices.size());
    for (size_t t = 0; t + 2 < indices.size(); t += 3)
        for (int e = 0; e < 3; ++e) {
            uint32_t a = indices[t + e], b = indices[t + (e + 1) % 3];
            if (a != b) edges.emplace_back(std::min(a, b), std::max(a, b));
        }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    return edges;
}

} // namespace

size_t smoothOrders(const std::vector<uint32_t>& indices, std::vector<uint8_t>& orders, int maxStep) {
    std::vector<uint8_t> original = orders;
    auto edges = meshEdges(indices);
    // Raising to (neighbour - maxStep) until nothing changes: the smallest graded field above the input. Each
    // pass can only raise, and orders are bounded, so it ends; at most (largest order) passes are needed.
    for (bool changed = true; changed;) {
        changed = false;
        for (auto [a, b] : edges) {
            int lowest = std::max(int(orders[a]), int(orders[b])) - maxStep;
            if (orders[a] < lowest) orders[a] = uint8_t(lowest), changed = true;
            if (orders[b] < lowest) orders[b] = uint8_t(lowest), changed = true;
        }
    }
    size_t raised = 0;
    for (size_t v = 0; v < orders.size(); ++v) raised += orders[v] != original[v];
    return raised;
}

size_t smoothOrdersWithinBound(const std::vector<uint32_t>& indices, std::vector<uint8_t>& orders,
                               const std::vector<float>& error, int order, double maxError, int maxStep) {
    std::vector<uint8_t> original = orders;
    if (error.size() != orders.size() * size_t(order))
        throw Error("", "smoothOrdersWithinBound", "error table does not hold `order` values per vertex", kExitFailure);
    // Both steps only raise, and each maps a field below the smallest admissible graded field G (one that is graded
    // and within the bound everywhere) to one still below G: grading because G is graded, the bound step because
    // G[v] is an order within the bound at or above the current one. Order `order` has error 0, so G exists, and
    // the loop ends at G itself: nothing is raised more than the bound and the grading need.
    for (bool violated = true; violated;) {
        smoothOrders(indices, orders, maxStep);
        violated = false;
        for (size_t v = 0; v < orders.size(); ++v) {
            int n = std::max(1, int(orders[v]));
            while (n < order && !(error[v * order + size_t(n - 1)] <= maxError)) ++n;
            if (n != orders[v]) orders[v] = uint8_t(n), violated = true;
        }
    }
    size_t raised = 0;
    for (size_t v = 0; v < orders.size(); ++v) raised += orders[v] != original[v];
    return raised;
}

SeamMeasure seamMeasure(const std::vector<uint32_t>& indices, const std::vector<uint8_t>& orders,
                        const float* adaptiveRadiance, const float* fullRadiance) {
    SeamMeasure measure;
    double boundarySum = 0.0, otherSum = 0.0;
    for (auto [a, b] : meshEdges(indices)) {
        double excess = 0.0, jump = 0.0;
        for (int c = 0; c < 3; ++c) {
            double full = double(fullRadiance[a * 3 + c]) - fullRadiance[b * 3 + c];
            double adaptive = double(adaptiveRadiance[a * 3 + c]) - adaptiveRadiance[b * 3 + c];
            excess = std::max(excess, std::fabs(adaptive - full));
            jump = std::max(jump, std::fabs(full));
        }
        if (orders[a] != orders[b]) {
            ++measure.boundaryEdges;
            measure.largestBoundaryExcess = std::max(measure.largestBoundaryExcess, excess);
            boundarySum += excess;
        } else {
            ++measure.otherEdges;
            measure.largestOtherJump = std::max(measure.largestOtherJump, jump);
            otherSum += jump;
        }
    }
    if (measure.boundaryEdges) measure.meanBoundaryExcess = boundarySum / double(measure.boundaryEdges);
    if (measure.otherEdges) measure.meanOtherJump = otherSum / double(measure.otherEdges);
    return measure;
}

} // namespace prt::adapt
