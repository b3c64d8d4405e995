// The 92-view set, the direction grid and the Phong kernel: closed-form properties.
#include "glossy.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace {

using namespace prt::glossy;

double angleDegrees(const float* a, const float* b) {
    double d = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
    return std::acos(std::clamp(d, -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

TEST(GlossyViews, FrequencyThreeIcosahedron) {
    const ViewSet& views = viewSet();
    ASSERT_EQ(views.directions.size(), 92u);
    EXPECT_EQ(views.triangles.size(), 180u);
    int valence5 = 0, valence6 = 0;
    for (const auto& ring : views.neighbours) valence5 += ring.size() == 5, valence6 += ring.size() == 6;
    EXPECT_EQ(valence5, 12);
    EXPECT_EQ(valence6, 80);
    size_t edges = 0;
    double shortest = 180, longest = 0;
    for (size_t v = 0; v < 92; ++v) {
        EXPECT_NEAR(std::sqrt(views.directions[v][0] * views.directions[v][0] + views.directions[v][1] * views.directions[v][1] +
                              views.directions[v][2] * views.directions[v][2]), 1.0, 1e-6);
        for (uint32_t n : views.neighbours[v]) {
            edges += n > v;
            double a = angleDegrees(views.directions[v].data(), views.directions[n].data());
            shortest = std::min(shortest, a), longest = std::max(longest, a);
        }
    }
    EXPECT_EQ(edges, 270u);
    EXPECT_NEAR(shortest, 20.08, 0.01);
    EXPECT_NEAR(longest, 23.80, 0.01);
    // Antipodal symmetry: every view's opposite is a view.
    for (const auto& d : views.directions) {
        float opposite[3] = {-d[0], -d[1], -d[2]};
        double nearest = 180;
        for (const auto& e : views.directions) nearest = std::min(nearest, angleDegrees(opposite, e.data()));
        EXPECT_LT(nearest, 0.05); // acos near 1 in float
    }
}

TEST(GlossyViews, FortySixInEveryOpenHemisphereAndCoveringRadius) {
    const ViewSet& views = viewSet();
    std::mt19937 random(7);
    std::normal_distribution<float> normal;
    double covering = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        float d[3] = {normal(random), normal(random), normal(random)};
        float length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (float& c : d) c /= length;
        int above = 0;
        double nearest = 180;
        for (const auto& v : views.directions) {
            above += d[0] * v[0] + d[1] * v[1] + d[2] * v[2] > 0;
            nearest = std::min(nearest, angleDegrees(d, v.data()));
        }
        if (trial < 2000) {
            EXPECT_EQ(above, 46) << trial;
        }
        covering = std::max(covering, nearest);
    }
    EXPECT_LE(covering, 13.65);
    // Exactly: the deepest hole of a triangle is its circumcentre when that lies inside, else the middle of its
    // longest edge.
    double deepest = 0;
    for (const auto& t : views.triangles) {
        const float *a = views.directions[t[0]].data(), *b = views.directions[t[1]].data(), *c = views.directions[t[2]].data();
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) e1[k] = b[k] - a[k], e2[k] = c[k] - a[k];
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        float centre[3] = {float(n[0] / length), float(n[1] / length), float(n[2] / length)};
        auto triple = [](const float* x, const float* y, const float* z) {
            return x[0] * (y[1] * z[2] - y[2] * z[1]) - x[1] * (y[0] * z[2] - y[2] * z[0]) + x[2] * (y[0] * z[1] - y[1] * z[0]);
        };
        bool inside = triple(centre, b, c) >= 0 && triple(a, centre, c) >= 0 && triple(a, b, centre) >= 0;
        double hole = angleDegrees(centre, a);
        if (!inside) {
            hole = 0;
            for (int e = 0; e < 3; ++e) {
                const float* p = views.directions[t[e]].data();
                const float* q = views.directions[t[(e + 1) % 3]].data();
                hole = std::max(hole, angleDegrees(p, q) / 2);
            }
        }
        deepest = std::max(deepest, hole);
    }
    // 13.676 deg: the seed notes' 13.65 deg is what sampling finds (as above), an underestimate (docs/glossy.md).
    EXPECT_NEAR(deepest, 13.676, 0.001);
}

TEST(GlossyGrid, SolidAnglesSumToTheSphere) {
    for (int resolution : {2, 8, 16}) {
        DirectionGrid grid = cubeGrid(resolution);
        ASSERT_EQ(grid.count(), size_t(6 * resolution * resolution));
        double sum = 0;
        for (float w : grid.solidAngle) sum += w;
        EXPECT_NEAR(sum, 4 * std::numbers::pi, 1e-4);
    }
}

TEST(GlossyKernel, WhiteFurnaceEnergyOfThePhongLobe) {
    // Integral of T over the sphere is the lobe's directional albedo: ks at normal incidence, less elsewhere.
    DirectionGrid grid = cubeGrid(48);
    std::vector<float> kernel(grid.count());
    const float normal[3] = {0, 0, 1};
    for (double exponent : {4.0, 16.0}) {
        Phong phong{exponent, 0.7};
        double previous = 1e9;
        for (double degrees : {0.0, 30.0, 60.0, 80.0}) {
            double t = degrees * std::numbers::pi / 180;
            const float outgoing[3] = {float(std::sin(t)), 0.0f, float(std::cos(t))};
            tabulateKernel(grid, normal, outgoing, phong, nullptr, kernel.data());
            double energy = 0;
            for (size_t i = 0; i < grid.count(); ++i) energy += kernel[i] * grid.solidAngle[i];
            if (degrees == 0.0) {
                EXPECT_NEAR(energy, 0.7, 0.7 * 0.01) << exponent;
            }
            EXPECT_LE(energy, 0.7 * 1.005);
            EXPECT_LT(energy, previous + 1e-6);
            previous = energy;
        }
    }
    // Below the horizon the kernel is zero.
    const float below[3] = {0, 0.6f, -0.8f};
    tabulateKernel(grid, normal, below, Phong{8, 1}, nullptr, kernel.data());
    for (float k : kernel) EXPECT_EQ(k, 0.0f);
}

TEST(GlossySg, ProductAndConvolutionIdentities) {
    // Product: a1 G(mu1, l1) a2 G(mu2, l2) = a1 a2 exp(|l1 mu1 + l2 mu2| - l1 - l2) G(mu_m, |l1 mu1 + l2 mu2|).
    // Integral of one SG: 2 pi a (1 - exp(-2 l)) / l; so the inner product of two SGs has a closed form.
    DirectionGrid grid = cubeGrid(64);
    const double mu1[3] = {0, 0, 1}, l1 = 20;
    const double mu2[3] = {0.6, 0, 0.8}, l2 = 35;
    double um[3], lm = 0;
    for (int c = 0; c < 3; ++c) um[c] = l1 * mu1[c] + l2 * mu2[c], lm += um[c] * um[c];
    lm = std::sqrt(lm);
    double numeric = 0, maxProductError = 0;
    for (size_t i = 0; i < grid.count(); ++i) {
        const float* w = &grid.directions[i * 3];
        double g1 = std::exp(l1 * (mu1[0] * w[0] + mu1[1] * w[1] + mu1[2] * w[2] - 1));
        double g2 = std::exp(l2 * (mu2[0] * w[0] + mu2[1] * w[1] + mu2[2] * w[2] - 1));
        double gm = std::exp(lm - l1 - l2) * std::exp((um[0] * w[0] + um[1] * w[1] + um[2] * w[2]) - lm);
        maxProductError = std::max(maxProductError, std::abs(g1 * g2 - gm));
        numeric += g1 * g2 * grid.solidAngle[i];
    }
    double closed = std::exp(lm - l1 - l2) * 2 * std::numbers::pi * (1 - std::exp(-2 * lm)) / lm;
    EXPECT_LT(maxProductError, 1e-12);
    EXPECT_NEAR(numeric, closed, 2e-3 * closed);
    // Single-lobe integral.
    double single = 0;
    for (size_t i = 0; i < grid.count(); ++i) {
        const float* w = &grid.directions[i * 3];
        single += std::exp(l1 * (w[2] - 1)) * grid.solidAngle[i];
    }
    EXPECT_NEAR(single, 2 * std::numbers::pi * (1 - std::exp(-2 * l1)) / l1, 1e-3 * single);
}

} // namespace
