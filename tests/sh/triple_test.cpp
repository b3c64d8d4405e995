// The Gaunt tensor: values, selection rules, symmetry, completeness against brute force, and products.
#include "helpers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <tuple>

using namespace prt::sh;
using namespace prt::sh::test;

namespace {

using Key = std::tuple<uint32_t, uint32_t, uint32_t>;

std::map<Key, double> asMap(const TripleProduct& tensor) {
    std::map<Key, double> entries;
    for (size_t e = 0; e < tensor.value.size(); ++e) entries[{tensor.i[e], tensor.j[e], tensor.k[e]}] = tensor.value[e];
    return entries;
}

void band(uint32_t i, int& l, int& m) {
    l = int(std::sqrt(double(i)));
    m = int(i) - l * l - l;
}

} // namespace

TEST(ShTriple, KnownValueAndConstantFunctionIsIdentity) {
    std::map<Key, double> entries = asMap(tripleProduct(4));
    uint32_t y11 = index(1, 1), y22 = index(2, 2);
    EXPECT_NEAR(entries.at({y11, y11, y22}), 0.2185097, 1e-7);
    for (uint32_t j = 0; j < 16; ++j)
        for (uint32_t k = 0; k < 16; ++k) {
            auto found = entries.find({0, j, k});
            double value = found == entries.end() ? 0.0 : found->second;
            EXPECT_NEAR(value, j == k ? 0.5 / std::sqrt(std::numbers::pi) : 0.0, 1e-14) << j << " " << k;
        }
}

TEST(ShTriple, EntriesObeySelectionRulesAndAllPermutations) {
    TripleProduct tensor = tripleProduct(6);
    std::map<Key, double> entries = asMap(tensor);
    ASSERT_FALSE(entries.empty());
    for (const auto& [key, value] : entries) {
        auto [i, j, k] = key;
        int l1, m1, l2, m2, l3, m3;
        band(i, l1, m1), band(j, l2, m2), band(k, l3, m3);
        EXPECT_EQ((l1 + l2 + l3) % 2, 0);
        EXPECT_LE(l3, l1 + l2);
        EXPECT_GE(l3, std::abs(l1 - l2));
        EXPECT_EQ(((m1 < 0) + (m2 < 0) + (m3 < 0)) % 2, 0);
        int a = std::abs(m1), b = std::abs(m2), c = std::abs(m3);
        EXPECT_TRUE(a == b + c || b == a + c || c == a + b);
        EXPECT_GT(std::abs(value), 1e-12);
        for (Key permuted : {Key{i, k, j}, Key{j, i, k}, Key{j, k, i}, Key{k, i, j}, Key{k, j, i}}) {
            auto found = entries.find(permuted);
            ASSERT_NE(found, entries.end());
            EXPECT_EQ(found->second, value);
        }
    }
}

// Every triple, nonzero or not, against a direct sphere quadrature of Y_i Y_j Y_k.
TEST(ShTriple, MatchesBruteForceQuadratureForEveryTriple) {
    const int order = 4, count = coefficientCount(order);
    std::map<Key, double> entries = asMap(tripleProduct(order));
    SphereQuadrature q = sphereQuadrature(3 * (order - 1));
    std::vector<double> basis(q.weights.size() * count);
    for (size_t p = 0; p < q.weights.size(); ++p)
        evaluate(order, q.directions[p * 3], q.directions[p * 3 + 1], q.directions[p * 3 + 2], &basis[p * count]);
    for (int i = 0; i < count; ++i)
        for (int j = 0; j < count; ++j)
            for (int k = 0; k < count; ++k) {
                double sum = 0.0;
                for (size_t p = 0; p < q.weights.size(); ++p)
                    sum += q.weights[p] * basis[p * count + i] * basis[p * count + j] * basis[p * count + k];
                auto found = entries.find({uint32_t(i), uint32_t(j), uint32_t(k)});
                ASSERT_NEAR(found == entries.end() ? 0.0 : found->second, sum, 1e-13) << i << " " << j << " " << k;
            }
}

// Two order-3 functions multiply into degree 4, which order 5 holds exactly: the product's coefficients must
// match quadrature and reconstruct f * g pointwise.
TEST(ShTriple, MultiplyMatchesQuadratureOfTheProduct) {
    const int order = 5, count = coefficientCount(order);
    std::mt19937 rng(29);
    std::vector<double> a(count, 0.0), b(count, 0.0);
    std::vector<double> low = randomCoefficients(rng, 9), other = randomCoefficients(rng, 9);
    std::copy(low.begin(), low.end(), a.begin());
    std::copy(other.begin(), other.end(), b.begin());
    std::vector<float> af(a.begin(), a.end()), bf(b.begin(), b.end()), product(count);
    multiply(tripleProduct(order), af.data(), bf.data(), product.data());

    SphereQuadrature q = sphereQuadrature(3 * (order - 1));
    std::vector<double> projected(count, 0.0), basis(count);
    for (size_t p = 0; p < q.weights.size(); ++p) {
        const double* d = &q.directions[p * 3];
        double value = reconstruct(order, a.data(), d) * reconstruct(order, b.data(), d);
        evaluate(order, d[0], d[1], d[2], basis.data());
        for (int i = 0; i < count; ++i) projected[i] += q.weights[p] * value * basis[i];
    }
    for (int i = 0; i < count; ++i) EXPECT_NEAR(product[i], projected[i], 1e-5) << i;

    std::vector<double> productDouble(product.begin(), product.end());
    for (int trial = 0; trial < 20; ++trial) {
        double d[3];
        randomUnit(rng, d);
        double expected = reconstruct(order, a.data(), d) * reconstruct(order, b.data(), d);
        EXPECT_NEAR(reconstruct(order, productDouble.data(), d), expected, 1e-4);
    }
}
