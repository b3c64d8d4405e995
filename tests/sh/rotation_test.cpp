// SH rotation: group properties, the closed-form z rotation, and agreement with projecting a rotated function.
#include "helpers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace prt::sh;
using namespace prt::sh::test;

namespace {

std::vector<double> rotated(const Rotation& rotation, const std::vector<double>& c) {
    std::vector<double> out(c.size());
    rotate(rotation, c.data(), out.data(), 1);
    return out;
}

void transpose(const double R[9], double T[9]) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) T[j * 3 + i] = R[i * 3 + j];
}

double maxDifference(const std::vector<double>& a, const std::vector<double>& b) {
    double worst = 0.0;
    for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
    return worst;
}

} // namespace

TEST(ShRotation, IdentityMatrixGivesIdentity) {
    const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    Rotation rotation = prt::sh::rotation(kMaxOrder, I);
    size_t offset = 0;
    for (int l = 0; l < kMaxOrder; ++l) {
        int size = 2 * l + 1;
        for (int r = 0; r < size; ++r)
            for (int c = 0; c < size; ++c)
                ASSERT_NEAR(rotation.blocks[offset + r * size + c], r == c ? 1.0 : 0.0, 1e-13) << l;
        offset += size_t(size) * size;
    }
    EXPECT_EQ(offset, rotation.blocks.size());
}

TEST(ShRotation, BlocksAreOrthogonalAtMaxOrder) {
    std::mt19937 rng(7);
    double R[9];
    randomRotation(rng, R);
    Rotation rotation = prt::sh::rotation(kMaxOrder, R);
    size_t offset = 0;
    for (int l = 0; l < kMaxOrder; ++l) {
        int size = 2 * l + 1;
        const double* B = &rotation.blocks[offset];
        double worst = 0.0;
        for (int a = 0; a < size; ++a)
            for (int b = 0; b < size; ++b) {
                double dot = 0.0;
                for (int k = 0; k < size; ++k) dot += B[a * size + k] * B[b * size + k];
                worst = std::max(worst, std::abs(dot - (a == b ? 1.0 : 0.0)));
            }
        EXPECT_LT(worst, 1e-10) << "band " << l;
        offset += size_t(size) * size;
    }
}

TEST(ShRotation, InverseUndoesAndNormIsKeptPerBand) {
    std::mt19937 rng(11);
    for (int order : {2, 3, 5, 8, 15, kMaxOrder}) {
        double R[9], Rt[9];
        randomRotation(rng, R);
        transpose(R, Rt);
        std::vector<double> c = randomCoefficients(rng, coefficientCount(order));
        std::vector<double> there = rotated(prt::sh::rotation(order, R), c);
        std::vector<double> back = rotated(prt::sh::rotation(order, Rt), there);
        EXPECT_LT(maxDifference(back, c), 1e-10) << order;
        for (int l = 0; l < order; ++l) {
            double before = 0.0, after = 0.0;
            for (int i = l * l; i < (l + 1) * (l + 1); ++i) before += c[i] * c[i], after += there[i] * there[i];
            EXPECT_NEAR(after, before, 1e-10 * before) << "order " << order << " band " << l;
        }
    }
}

TEST(ShRotation, ComposesLikeMatrices) {
    std::mt19937 rng(13);
    for (int order : {3, 9, kMaxOrder}) {
        double A[9], B[9], AB[9] = {};
        randomRotation(rng, A);
        randomRotation(rng, B);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                for (int k = 0; k < 3; ++k) AB[i * 3 + j] += A[i * 3 + k] * B[k * 3 + j];
        std::vector<double> c = randomCoefficients(rng, coefficientCount(order));
        std::vector<double> stepwise = rotated(prt::sh::rotation(order, A), rotated(prt::sh::rotation(order, B), c));
        std::vector<double> direct = rotated(prt::sh::rotation(order, AB), c);
        EXPECT_LT(maxDifference(stepwise, direct), 1e-10) << order;
    }
}

// About +Z, f(R^T d) shifts phi by alpha: c'_lm = cos(m a) c_lm - sin(m a) c_l-m and
// c'_l-m = sin(m a) c_lm + cos(m a) c_l-m.
TEST(ShRotation, EqualsClosedFormZRotation) {
    const int order = 12;
    const double alpha = 0.7;
    const double axis[3] = {0, 0, 1};
    double R[9];
    axisAngle(axis, alpha, R);
    std::mt19937 rng(17);
    std::vector<double> c = randomCoefficients(rng, coefficientCount(order));
    std::vector<double> out = rotated(prt::sh::rotation(order, R), c);
    for (int l = 0; l < order; ++l) {
        EXPECT_NEAR(out[index(l, 0)], c[index(l, 0)], 1e-12);
        for (int m = 1; m <= l; ++m) {
            double cm = c[index(l, m)], cn = c[index(l, -m)];
            EXPECT_NEAR(out[index(l, m)], std::cos(m * alpha) * cm - std::sin(m * alpha) * cn, 1e-12) << l << m;
            EXPECT_NEAR(out[index(l, -m)], std::sin(m * alpha) * cm + std::cos(m * alpha) * cn, 1e-12) << l << m;
        }
    }
}

// coeffs(f o R^T) computed by exact quadrature must equal rotate(coeffs(f)).
TEST(ShRotation, EqualsProjectionOfTheRotatedFunction) {
    std::mt19937 rng(19);
    for (int order : {2, 3, 4, 7, 15, kMaxOrder}) {
        double R[9];
        randomRotation(rng, R);
        int count = coefficientCount(order);
        std::vector<double> c = randomCoefficients(rng, count);
        SphereQuadrature q = sphereQuadrature(2 * (order - 1));
        std::vector<double> projected(count, 0.0), basis(count);
        for (size_t p = 0; p < q.weights.size(); ++p) {
            const double* d = &q.directions[p * 3];
            double source[3] = {}; // R^T d
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) source[i] += R[j * 3 + i] * d[j];
            double value = reconstruct(order, c.data(), source);
            evaluate(order, d[0], d[1], d[2], basis.data());
            for (int i = 0; i < count; ++i) projected[i] += q.weights[p] * value * basis[i];
        }
        EXPECT_LT(maxDifference(rotated(prt::sh::rotation(order, R), c), projected), 1e-9) << "order " << order;
    }
}

TEST(ShRotation, FloatMatchesDoubleForInterleavedChannels) {
    std::mt19937 rng(23);
    double R[9];
    randomRotation(rng, R);
    const int order = 6, count = coefficientCount(order);
    Rotation rotation = prt::sh::rotation(order, R);
    std::vector<double> rgb = randomCoefficients(rng, count * 3), rgbOut(count * 3);
    std::vector<float> single(rgb.begin(), rgb.end()), singleOut(count * 3);
    rotate(rotation, rgb.data(), rgbOut.data(), 3);
    rotate(rotation, single.data(), singleOut.data(), 3);
    for (int c = 0; c < 3; ++c) {
        std::vector<double> channel(count), channelOut;
        for (int i = 0; i < count; ++i) channel[i] = rgb[i * 3 + c];
        channelOut = rotated(rotation, channel);
        for (int i = 0; i < count; ++i) {
            EXPECT_NEAR(rgbOut[i * 3 + c], channelOut[i], 1e-14);
            EXPECT_NEAR(singleOut[i * 3 + c], channelOut[i], 1e-5);
        }
    }
}

TEST(ShRotation, RotationYTurnsZTowardX) {
    double R[9];
    rotationY(90.0, R);
    const double z[3] = {0, 0, 1};
    double d[3] = {};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) d[i] += R[i * 3 + j] * z[j];
    EXPECT_NEAR(d[0], 1.0, 1e-15);
    EXPECT_NEAR(d[1], 0.0, 1e-15);
    EXPECT_NEAR(d[2], 0.0, 1e-15);
}
