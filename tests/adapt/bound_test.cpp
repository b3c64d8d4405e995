// `--budget vertex` keeps its bound at every vertex after grading, where the truncation error is not monotone in
// the order (bands that cancel): a hand-built case that plain grading breaks, a random one, and the bundle path.
#include "adapt.h"
#include "core.h"
#include "sh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace prt;

namespace {

constexpr int kOrder = 4;

// Three vertices, one triangle. Lighting: 1 on coefficient (l, 0) of every band, every channel. Vertex 0 needs
// order 3 (its band 2 is large, band 3 empty); vertex 1's bands 1 and 2 cancel, so order 1 (tail 0) and order 3
// (tail 0) are within any bound but order 2 (tail -0.5) is not; vertex 2 needs order 1.
struct Case {
    std::vector<float> transfer = std::vector<float>(3 * kOrder * kOrder * 3, 0.0f);
    std::vector<std::vector<float>> lightings{std::vector<float>(kOrder * kOrder * 3, 0.0f)};
    std::vector<uint32_t> indices{0, 1, 2};
    Case() {
        auto set = [&](size_t v, int j, float value) {
            for (int c = 0; c < 3; ++c) transfer[(v * kOrder * kOrder + size_t(j)) * 3 + c] = value;
        };
        set(0, 0, 1.0f), set(0, sh::index(2, 0), 1.0f);
        set(1, 0, 1.0f), set(1, sh::index(1, 0), 0.5f), set(1, sh::index(2, 0), -0.5f);
        set(2, 0, 1.0f);
        for (int l = 0; l < kOrder; ++l)
            for (int c = 0; c < 3; ++c) lightings[0][size_t(sh::index(l, 0)) * 3 + c] = 1.0f;
    }
};

void expectGradedAndWithinBound(const std::vector<uint32_t>& indices, const std::vector<uint8_t>& orders,
                                const std::vector<float>& error, int order, double maxError, int maxStep) {
    for (size_t v = 0; v < orders.size(); ++v)
        EXPECT_LE(error[v * order + orders[v] - 1], maxError) << "vertex " << v << " at order " << int(orders[v]);
    for (size_t t = 0; t + 2 < indices.size(); t += 3)
        for (int e = 0; e < 3; ++e)
            EXPECT_LE(std::abs(int(orders[indices[t + e]]) - int(orders[indices[t + (e + 1) % 3]])), maxStep);
}

} // namespace

TEST(AdaptBound, GradingIntoANonMonotoneErrorIsRepairedAtEveryVertex) {
    Case c;
    const double maxError = 0.1;
    std::vector<float> error = adapt::truncationError(c.transfer.data(), 3, kOrder, c.lightings, adapt::Prior::Maps);
    // The case is what it claims: vertex 1 within the bound at 1 and 3, outside it at 2.
    EXPECT_LE(error[1 * kOrder + 0], maxError);
    EXPECT_GT(error[1 * kOrder + 1], maxError);
    EXPECT_LE(error[1 * kOrder + 2], maxError);
    std::vector<uint8_t> selected = adapt::selectOrders(error, 3, kOrder, maxError);
    EXPECT_EQ(selected, (std::vector<uint8_t>{3, 1, 1}));
    // Plain grading raises vertex 1 to 2, out of its bound: the failure this repairs.
    std::vector<uint8_t> plain = selected;
    adapt::smoothOrders(c.indices, plain, 1);
    EXPECT_EQ(plain[1], 2);
    EXPECT_GT(error[1 * kOrder + plain[1] - 1], maxError);
    std::vector<uint8_t> orders = selected;
    size_t raised = adapt::smoothOrdersWithinBound(c.indices, orders, error, kOrder, maxError, 1);
    expectGradedAndWithinBound(c.indices, orders, error, kOrder, maxError, 1);
    // The smallest repair: vertex 1 to 3 (its next order within the bound), vertex 2 to 2 for the grading.
    EXPECT_EQ(orders, (std::vector<uint8_t>{3, 3, 2}));
    EXPECT_EQ(raised, 2u);
}

TEST(AdaptBound, RandomCancellingBandsStayWithinTheBoundGradedAndMinimal) {
    // Bands of random sign and no decay under two random lightings: errors far from monotone.
    const int order = 6;
    const size_t V = 80;
    std::mt19937 random(11);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    std::vector<float> transfer(V * order * order * 3);
    for (float& value : transfer) value = uniform(random);
    for (size_t v = 0; v < V; ++v)
        for (int c = 0; c < 3; ++c) transfer[v * order * order * 3 + c] = 3.0f;
    std::vector<std::vector<float>> lightings(2, std::vector<float>(order * order * 3));
    for (auto& lighting : lightings)
        for (float& value : lighting) value = uniform(random);
    // A strip: edges (v, v+1) and (v, v+2).
    std::vector<uint32_t> indices;
    for (uint32_t v = 0; v + 2 < V; ++v) indices.insert(indices.end(), {v, v + 1, v + 2});
    std::vector<float> error = adapt::truncationError(transfer.data(), V, order, lightings, adapt::Prior::Maps);
    size_t nonMonotone = 0;
    for (size_t v = 0; v < V; ++v)
        for (int n = 1; n + 1 < order; ++n) nonMonotone += error[v * order + n] > error[v * order + n - 1];
    ASSERT_GT(nonMonotone, V / 4); // the case is what it claims
    for (double maxError : {0.05, 0.15, 0.3})
        for (int maxStep : {1, 2}) {
            std::vector<uint8_t> selected = adapt::selectOrders(error, V, order, maxError);
            std::vector<uint8_t> orders = selected;
            adapt::smoothOrdersWithinBound(indices, orders, error, order, maxError, maxStep);
            expectGradedAndWithinBound(indices, orders, error, order, maxError, maxStep);
            // Minimal: no vertex can come down to any lower order that keeps its bound and its edges graded.
            for (size_t v = 0; v < V; ++v) {
                EXPECT_GE(orders[v], selected[v]);
                for (int n = 1; n < orders[v]; ++n) {
                    if (!(error[v * order + n - 1] <= maxError)) continue;
                    bool graded = true;
                    for (size_t t = 0; t < indices.size(); t += 3)
                        for (int e = 0; e < 3; ++e) {
                            uint32_t a = indices[t + e], b = indices[t + (e + 1) % 3];
                            if (a == v) graded = graded && std::abs(n - int(orders[b])) <= maxStep;
                            if (b == v) graded = graded && std::abs(n - int(orders[a])) <= maxStep;
                        }
                    EXPECT_FALSE(graded) << "vertex " << v << " could keep order " << n;
                }
            }
        }
}

TEST(AdaptBound, VertexBudgetBundleKeepsTheBoundAtEveryVertex) {
    Case c;
    Bundle bundle;
    bundle.mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    bundle.mesh.indices = c.indices;
    Layer layer;
    layer.name = "transfer";
    layer.domain = "vertex";
    layer.semantic = "sh_transfer_rgb";
    layer.shape = {3, kOrder * kOrder, 3};
    layer.data = c.transfer;
    bundle.layers.push_back(layer);
    adapt::AdaptOptions options;
    options.maxError = 0.1;
    options.perVertexBudget = true;
    adapt::AdaptStats stats = adapt::adaptBundle(bundle, c.lightings, options, "case");
    const Layer* offsets = findLayer(bundle, "transfer_offsets");
    ASSERT_NE(offsets, nullptr);
    std::vector<float> error = adapt::truncationError(c.transfer.data(), 3, kOrder, c.lightings, adapt::Prior::Maps);
    std::vector<uint8_t> orders;
    for (size_t v = 0; v < 3; ++v)
        orders.push_back(uint8_t(std::lround(std::sqrt(double(offsets->integers[v + 1] - offsets->integers[v])))));
    expectGradedAndWithinBound(c.indices, orders, error, kOrder, options.maxError, 1);
    EXPECT_EQ(orders, (std::vector<uint8_t>{3, 3, 2}));
    EXPECT_EQ(stats.raisedBySmoothing, 2u);
}
