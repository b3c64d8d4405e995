// The Gaunt (triple-product) tensor of the real SH basis, by exact quadrature.
#include "sh.h"

#include "core.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace prt::sh {

namespace {

// The azimuthal factor of Y_lm: cos(m phi) for m > 0, sin(|m| phi) for m < 0, 1 for m = 0.
double azimuthal(int m, double phi) {
    return m > 0 ? std::cos(m * phi) : m < 0 ? std::sin(-m * phi) : 1.0;
}

// The real-SH m rule: an integral of three azimuthal factors is nonzero only if an even number of them are sines
// and one |m| is the sum of the other two.
bool azimuthAllowed(int m1, int m2, int m3) {
    int sines = (m1 < 0) + (m2 < 0) + (m3 < 0);
    int a = std::abs(m1), b = std::abs(m2), c = std::abs(m3);
    return sines % 2 == 0 && (a == b + c || b == a + c || c == a + b);
}

} // namespace

TripleProduct tripleProduct(int order) {
    if (order < 1 || order > kMaxOrder)
        throw Error("", "sh::tripleProduct",
                    "order " + std::to_string(order) + " outside 1.." + std::to_string(kMaxOrder), kExitFailure);
    // Y_lm(z, phi) = Theta_l|m|(z) * azimuthal(m, phi), and the product rule (Gauss-Legendre in z times uniform
    // phi) factors the same way, so G is exactly (z rule over three Thetas) * (phi rule over three azimuthals).
    // A product of three bands up to order-1 has degree 3 (order-1): both rules are exact for it.
    int degree = 3 * (order - 1);
    int zCount = degree / 2 + 1, phiCount = degree + 1;
    std::vector<double> z(zCount), zWeight(zCount);
    gaussLegendre(zCount, z.data(), zWeight.data());

    int count = coefficientCount(order);
    // Theta at each z node: Y_l|m| at azimuth 0, where the azimuthal factor is 1.
    std::vector<double> theta(size_t(zCount) * count);
    for (int q = 0; q < zCount; ++q)
        evaluate(order, std::sqrt(std::max(0.0, 1.0 - z[q] * z[q])), 0.0, z[q], &theta[size_t(q) * count]);

    int mSpan = 2 * order - 1;
    auto azimuthIndex = [&](int m1, int m2, int m3) {
        return (size_t(m1 + order - 1) * mSpan + (m2 + order - 1)) * mSpan + (m3 + order - 1);
    };
    std::vector<double> azimuthIntegral(size_t(mSpan) * mSpan * mSpan, 0.0);
    for (int m1 = 1 - order; m1 < order; ++m1)
        for (int m2 = 1 - order; m2 < order; ++m2)
            for (int m3 = 1 - order; m3 < order; ++m3) {
                if (!azimuthAllowed(m1, m2, m3)) continue;
                double sum = 0.0;
                for (int p = 0; p < phiCount; ++p) {
                    double phi = 2.0 * std::numbers::pi * p / phiCount;
                    sum += azimuthal(m1, phi) * azimuthal(m2, phi) * azimuthal(m3, phi);
                }
                azimuthIntegral[azimuthIndex(m1, m2, m3)] = sum * 2.0 * std::numbers::pi / phiCount;
            }

    TripleProduct tensor;
    tensor.order = order;
    for (int l1 = 0; l1 < order; ++l1)
        for (int m1 = -l1; m1 <= l1; ++m1)
            for (int l2 = 0; l2 < order; ++l2)
                for (int m2 = -l2; m2 <= l2; ++m2) {
                    // l3 runs over the triangle |l1 - l2| .. l1 + l2 with l1 + l2 + l3 even.
                    int l3Last = std::min(l1 + l2, order - 1);
                    for (int l3 = std::abs(l1 - l2); l3 <= l3Last; l3 += 2)
                        for (int m3 = -l3; m3 <= l3; ++m3) {
                            if (!azimuthAllowed(m1, m2, m3)) continue;
                            // Factors in sorted order, so every permutation of (i, j, k) gets the same bits.
                            std::array<int, 3> t = {index(l1, std::abs(m1)), index(l2, std::abs(m2)),
                                                    index(l3, std::abs(m3))};
                            std::array<int, 3> m = {m1, m2, m3};
                            std::sort(t.begin(), t.end());
                            std::sort(m.begin(), m.end());
                            double polar = 0.0;
                            for (int q = 0; q < zCount; ++q) {
                                const double* node = &theta[size_t(q) * count];
                                polar += zWeight[q] * node[t[0]] * node[t[1]] * node[t[2]];
                            }
                            double value = polar * azimuthIntegral[azimuthIndex(m[0], m[1], m[2])];
                            if (std::abs(value) <= 1e-12) continue;
                            tensor.i.push_back(uint32_t(index(l1, m1)));
                            tensor.j.push_back(uint32_t(index(l2, m2)));
                            tensor.k.push_back(uint32_t(index(l3, m3)));
                            tensor.value.push_back(value);
                        }
                }
    return tensor;
}

void multiply(const TripleProduct& tensor, const float* a, const float* b, float* out) {
    std::vector<double> sum(coefficientCount(tensor.order), 0.0);
    for (size_t e = 0; e < tensor.value.size(); ++e)
        sum[tensor.i[e]] += tensor.value[e] * double(a[tensor.j[e]]) * double(b[tensor.k[e]]);
    for (size_t i = 0; i < sum.size(); ++i) out[i] = float(sum[i]);
}

} // namespace prt::sh
