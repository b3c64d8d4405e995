// Small shared pieces of the SH tests: seeded random inputs and reconstruction.
#pragma once

#include "sh.h"

#include <cmath>
#include <random>
#include <vector>

namespace prt::sh::test {

inline void randomUnit(std::mt19937& rng, double d[3]) {
    std::normal_distribution<double> normal;
    double length;
    do {
        for (int c = 0; c < 3; ++c) d[c] = normal(rng);
        length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    } while (length < 1e-6);
    for (int c = 0; c < 3; ++c) d[c] /= length;
}

// Rotation by `angle` radians about the unit `axis` (Rodrigues), row-major.
inline void axisAngle(const double axis[3], double angle, double R[9]) {
    double c = std::cos(angle), s = std::sin(angle), t = 1.0 - c;
    double x = axis[0], y = axis[1], z = axis[2];
    const double m[9] = {t * x * x + c,     t * x * y - s * z, t * x * z + s * y, t * x * y + s * z, t * y * y + c,
                         t * y * z - s * x, t * x * z - s * y, t * y * z + s * x, t * z * z + c};
    for (int i = 0; i < 9; ++i) R[i] = m[i];
}

inline void randomRotation(std::mt19937& rng, double R[9]) {
    double axis[3];
    randomUnit(rng, axis);
    axisAngle(axis, std::uniform_real_distribution<double>(0.1, 3.0)(rng), R);
}

inline std::vector<double> randomCoefficients(std::mt19937& rng, int count) {
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    std::vector<double> c(count);
    for (double& v : c) v = uniform(rng);
    return c;
}

// f(d) = sum_i c_i Y_i(d) for one channel.
inline double reconstruct(int order, const double* c, const double d[3]) {
    std::vector<double> basis(coefficientCount(order));
    evaluate(order, d[0], d[1], d[2], basis.data());
    double sum = 0.0;
    for (int i = 0; i < coefficientCount(order); ++i) sum += c[i] * basis[i];
    return sum;
}

} // namespace prt::sh::test
