// SH basis evaluation: known values, poles, closed forms and orthonormality at every supported order.
#include "sh.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace prt::sh;

namespace {

const double kPi = std::numbers::pi;

std::vector<double> basisAt(int order, double x, double y, double z) {
    std::vector<double> basis(coefficientCount(order));
    evaluate(order, x, y, z, basis.data());
    return basis;
}

} // namespace

TEST(ShEvaluate, IndexCountsBandsAndOrdersMAscending) {
    EXPECT_EQ(coefficientCount(3), 9);
    EXPECT_EQ(index(0, 0), 0);
    EXPECT_EQ(index(1, -1), 1);
    EXPECT_EQ(index(1, 1), 3);
    EXPECT_EQ(index(2, -2), 4);
    EXPECT_EQ(index(31, 31), coefficientCount(kMaxOrder) - 1);
}

TEST(ShEvaluate, MatchesTheTabulatedBandsZeroToTwo) {
    double x = 0.3, y = -0.5, z = 0.8;
    double length = std::sqrt(x * x + y * y + z * z);
    x /= length, y /= length, z /= length;
    std::vector<double> Y = basisAt(3, x, y, z);
    const double tolerance = 2e-6; // the table has 6 to 7 digits
    EXPECT_NEAR(Y[index(0, 0)], 0.282095, tolerance);
    EXPECT_NEAR(Y[index(1, -1)], 0.488603 * y, tolerance);
    EXPECT_NEAR(Y[index(1, 0)], 0.488603 * z, tolerance);
    EXPECT_NEAR(Y[index(1, 1)], 0.488603 * x, tolerance);
    EXPECT_NEAR(Y[index(2, -2)], 1.092548 * x * y, tolerance);
    EXPECT_NEAR(Y[index(2, -1)], 1.092548 * y * z, tolerance);
    EXPECT_NEAR(Y[index(2, 0)], 0.315392 * (3 * z * z - 1), tolerance);
    EXPECT_NEAR(Y[index(2, 1)], 1.092548 * x * z, tolerance);
    EXPECT_NEAR(Y[index(2, 2)], 0.546274 * (x * x - y * y), tolerance);
}

TEST(ShEvaluate, PolesHaveOnlyZonalTermsAtEveryOrder) {
    for (double pole : {1.0, -1.0}) {
        std::vector<double> Y = basisAt(kMaxOrder, 0.0, 0.0, pole);
        for (int l = 0; l < kMaxOrder; ++l)
            for (int m = -l; m <= l; ++m) {
                double expected = m != 0 ? 0.0 : std::pow(pole, l) * std::sqrt((2 * l + 1) / (4 * kPi));
                EXPECT_NEAR(Y[index(l, m)], expected, 1e-12 * std::sqrt(2 * l + 1.0)) << "l=" << l << " m=" << m;
            }
    }
}

// Independent closed form: Y_lm = sqrt(2) K_lm P_l^m(z) {cos, sin}(m phi), with std::assoc_legendre (which has
// no Condon-Shortley phase) and K_lm from lgamma.
TEST(ShEvaluate, MatchesAssociatedLegendreClosedFormUpToMaxOrder) {
    const double theta = 1.1, phi = -2.3;
    double x = std::sin(theta) * std::cos(phi), y = std::sin(theta) * std::sin(phi), z = std::cos(theta);
    std::vector<double> Y = basisAt(kMaxOrder, x, y, z);
    for (int l = 0; l < kMaxOrder; ++l) {
        EXPECT_NEAR(Y[index(l, 0)], std::sqrt((2 * l + 1) / (4 * kPi)) * std::legendre(l, z), 1e-12) << l;
        for (int m = 1; m <= l; ++m) {
            double factorials = std::exp(std::lgamma(l - m + 1.0) - std::lgamma(l + m + 1.0)); // (l-m)! / (l+m)!
            double K = std::sqrt((2 * l + 1) / (4 * kPi) * factorials);
            double legendre = std::numbers::sqrt2 * K * std::assoc_legendre(l, m, z);
            EXPECT_NEAR(Y[index(l, m)], legendre * std::cos(m * phi), 1e-10) << l << " " << m;
            EXPECT_NEAR(Y[index(l, -m)], legendre * std::sin(m * phi), 1e-10) << l << " " << -m;
        }
    }
}

TEST(ShEvaluate, LowerOrdersArePrefixesOfHigherOrders) {
    std::vector<double> full = basisAt(kMaxOrder, 0.48, -0.6, 0.64);
    for (int order = 1; order <= kMaxOrder; ++order) {
        std::vector<double> part = basisAt(order, 0.48, -0.6, 0.64);
        for (int i = 0; i < coefficientCount(order); ++i) ASSERT_EQ(part[i], full[i]) << order << " " << i;
    }
}

TEST(ShEvaluate, FloatMatchesDouble) {
    std::vector<float> single(coefficientCount(kMaxOrder));
    evaluate(kMaxOrder, 0.48f, -0.6f, 0.64f, single.data());
    std::vector<double> full = basisAt(kMaxOrder, 0.48, -0.6, 0.64);
    for (size_t i = 0; i < full.size(); ++i) EXPECT_NEAR(single[i], full[i], 1e-5) << i;
}

TEST(ShEvaluate, GaussLegendreIsExactToDegreeTwoNMinusOne) {
    for (int n = 1; n <= 40; ++n) {
        std::vector<double> nodes(n), weights(n);
        gaussLegendre(n, nodes.data(), weights.data());
        for (int k = 0; k <= 2 * n - 1; ++k) {
            double sum = 0.0;
            for (int i = 0; i < n; ++i) sum += weights[i] * std::pow(nodes[i], k);
            EXPECT_NEAR(sum, k % 2 ? 0.0 : 2.0 / (k + 1), 1e-14) << "n=" << n << " k=" << k;
        }
    }
}

// The Gram matrix of the basis under a quadrature exact for its products is the identity. Each order is checked
// with the smallest exact rule for it, so the quadrature (used by triple products) is checked as well.
TEST(ShEvaluate, OrthonormalAtEveryOrder) {
    for (int order = 1; order <= kMaxOrder; ++order) {
        SphereQuadrature q = sphereQuadrature(2 * (order - 1));
        int count = coefficientCount(order);
        Eigen::MatrixXd weighted(q.weights.size(), count);
        std::vector<double> basis(count);
        for (size_t p = 0; p < q.weights.size(); ++p) {
            const double* d = &q.directions[p * 3];
            evaluate(order, d[0], d[1], d[2], basis.data());
            for (int i = 0; i < count; ++i) weighted(Eigen::Index(p), i) = std::sqrt(q.weights[p]) * basis[i];
        }
        Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(count, count);
        gram.selfadjointView<Eigen::Lower>().rankUpdate(weighted.transpose());
        gram = gram.selfadjointView<Eigen::Lower>();
        double worst = (gram - Eigen::MatrixXd::Identity(count, count)).cwiseAbs().maxCoeff();
        EXPECT_LT(worst, 1e-11) << "order " << order;
    }
}

// Ramamoorthi-Hanrahan A_l = 2 pi * integral_0^1 z P_l(z) dz, integrated here by Gauss-Legendre on [0, 1].
TEST(ShEvaluate, ClampedCosineMatchesItsIntegral) {
    EXPECT_DOUBLE_EQ(clampedCosine(0), kPi);
    EXPECT_DOUBLE_EQ(clampedCosine(1), 2 * kPi / 3);
    EXPECT_DOUBLE_EQ(clampedCosine(2), kPi / 4);
    EXPECT_DOUBLE_EQ(clampedCosine(3), 0.0);
    EXPECT_NEAR(clampedCosine(4), -kPi / 24, 1e-15);
    const int n = 32;
    std::vector<double> nodes(n), weights(n);
    gaussLegendre(n, nodes.data(), weights.data());
    for (int l = 0; l < kMaxOrder; ++l) {
        double integral = 0.0;
        for (int i = 0; i < n; ++i) {
            double z = 0.5 * (nodes[i] + 1.0);
            integral += 0.5 * weights[i] * z * std::legendre(l, z);
        }
        EXPECT_NEAR(clampedCosine(l), 2 * kPi * integral, 1e-13) << l;
    }
}
