// The Phong lobe's zonal multipliers against numeric quadrature and closed forms, and the adaptive band count.
#include "core.h"
#include "sh.h"
#include "specular.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace {

// lambda_l = 2 pi integral_0^1 ((n + 2) / (2 pi)) t^n P_l(t) dt by Gauss-Legendre on [0, 1] (exact for integer n
// up to degree 2 * 200 - 1; for non-integer n the integrand is smooth on (0, 1] and converges fast).
double quadratureMultiplier(double exponent, int l) {
    const int nodes = 200;
    std::vector<double> x(nodes), w(nodes);
    prt::sh::gaussLegendre(nodes, x.data(), w.data());
    double sum = 0.0;
    for (int q = 0; q < nodes; ++q) {
        double t = 0.5 * (x[q] + 1.0);
        double p0 = 1.0, p1 = t, pl = l == 0 ? 1.0 : t;
        for (int k = 1; k < l; ++k) {
            double p2 = ((2 * k + 1) * t * p1 - k * p0) / (k + 1);
            p0 = p1, p1 = p2, pl = p2;
        }
        sum += 0.5 * w[q] * std::pow(t, exponent) * pl;
    }
    return (exponent + 2.0) * sum;
}

TEST(PhongZonal, MultipliersMatchQuadrature) {
    for (double exponent : {1.0, 8.0, 10.5, 32.0, 128.0}) {
        std::vector<double> m = prt::specular::phongMultipliers(exponent, 20);
        for (int l = 0; l < 20; ++l)
            EXPECT_NEAR(m[l], quadratureMultiplier(exponent, l), 1e-9 * std::max(1.0, std::abs(m[l])))
                << "n " << exponent << " l " << l;
    }
}

TEST(PhongZonal, ClosedForms) {
    // n = 1 is 3 / (2 pi) times the clamped cosine, whose multipliers lib/sh has.
    std::vector<double> one = prt::specular::phongMultipliers(1.0, 8);
    for (int l = 0; l < 8; ++l) EXPECT_NEAR(one[l], 3.0 / (2.0 * std::numbers::pi) * prt::sh::clampedCosine(l), 1e-12);
    // Band 0 is the lobe's integral over its hemisphere, (n + 2) / (n + 1); band 1 is (n + 2) / (n + 2) = 1.
    std::vector<double> m = prt::specular::phongMultipliers(32.0, 12);
    EXPECT_DOUBLE_EQ(m[0], 34.0 / 33.0);
    EXPECT_DOUBLE_EQ(m[1], 1.0);
    // An even integer n: even bands above n + 1 vanish exactly.
    std::vector<double> eight = prt::specular::phongMultipliers(8.0, 16);
    EXPECT_EQ(eight[10], 0.0);
    EXPECT_EQ(eight[12], 0.0);
    EXPECT_NE(eight[11], 0.0);
}

TEST(PhongZonal, AdaptiveBands) {
    // n = 8: lambda_7 / lambda_0 = 0.0352 >= 0.02 > lambda_8 / lambda_0 = 0.0105.
    EXPECT_EQ(prt::specular::adaptiveBands(8.0, 16), 8);
    EXPECT_EQ(prt::specular::adaptiveBands(8.0, 16, 0.01), 9);
    EXPECT_EQ(prt::specular::adaptiveBands(8.0, 5), 5);      // capped by what the product holds
    EXPECT_EQ(prt::specular::adaptiveBands(8.0, 16, 0.0), 16); // tolerance 0 keeps every band
    int previous = 0;
    for (double exponent : {2.0, 8.0, 32.0, 128.0}) {
        int bands = prt::specular::adaptiveBands(exponent, 32);
        EXPECT_GT(bands, previous) << exponent; // sharper lobes need more bands, about 2.8 sqrt(n)
        EXPECT_NEAR(bands, 2.8 * std::sqrt(exponent), 0.25 * bands + 1.0) << exponent;
        previous = bands;
    }
}

TEST(PhongZonal, BadInputIsRefused) {
    for (double exponent : {0.0, -1.0, std::nan("")}) {
        try {
            prt::specular::phongMultipliers(exponent, 4);
            FAIL() << exponent;
        } catch (const prt::Error& e) {
            EXPECT_EQ(e.exitCode(), prt::kExitUsage);
            EXPECT_NE(std::string(e.what()).find("exponent"), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(prt::specular::phongMultipliers(8.0, 0), prt::Error);
    EXPECT_THROW(prt::specular::adaptiveBands(8.0, 4, -0.1), prt::Error);
}

} // namespace
