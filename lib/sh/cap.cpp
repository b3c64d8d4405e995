// Exact SH projection of a spherical cap: zonal about its axis, so each band is one Legendre integral.
#include "sh.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace prt::sh {

void capProjection(int order, const double d[3], double cosRadius, double* out) {
    // Legendre P_0 .. P_order at x = cosRadius; integral_x^1 P_l = (P_{l-1}(x) - P_{l+1}(x)) / (2l + 1), l >= 1.
    const double x = cosRadius;
    std::vector<double> legendre(size_t(order) + 1);
    legendre[0] = 1.0;
    if (order >= 1) legendre[1] = x;
    for (int l = 1; l < order; ++l) legendre[l + 1] = ((2 * l + 1) * x * legendre[l] - l * legendre[l - 1]) / (l + 1);
    evaluate(order, d[0], d[1], d[2], out);
    for (int l = 0; l < order; ++l) {
        double integral = l == 0 ? 1.0 - x : (legendre[l - 1] - legendre[l + 1]) / (2 * l + 1);
        for (int m = -l; m <= l; ++m) out[index(l, m)] *= 2.0 * std::numbers::pi * integral;
    }
}

void addCapRadiance(int order, const double d[3], double cosRadius, const double radiance[3], double* out) {
    std::vector<double> cap(size_t(order) * order);
    capProjection(order, d, cosRadius, cap.data());
    for (size_t j = 0; j < cap.size(); ++j)
        for (int c = 0; c < 3; ++c) out[j * 3 + c] += radiance[c] * cap[j];
}

double capSolidAngle(double cosRadius) { return 2.0 * std::numbers::pi * (1.0 - cosRadius); }

double capCosineIntegral(double cosTheta, double sinSigmaSquared) {
    cosTheta = std::clamp(cosTheta, -1.0, 1.0);
    sinSigmaSquared = std::clamp(sinSigmaSquared, 0.0, 1.0);
    // Wholly above or below the horizon (this also covers a cap of zero size).
    if (cosTheta * cosTheta >= sinSigmaSquared) return std::numbers::pi * sinSigmaSquared * std::max(0.0, cosTheta);
    // Straddling: sin^2 sigma > cos^2 theta >= 0, so sinTheta > 0.
    const double sinTheta = std::sqrt(1.0 - cosTheta * cosTheta);
    const double x = std::sqrt(std::max(1.0 / sinSigmaSquared - 1.0, 0.0));
    const double y = std::clamp(-x * cosTheta / sinTheta, -1.0, 1.0);
    const double sinThetaSqrtY = sinTheta * std::sqrt(std::max(0.0, 1.0 - y * y));
    const double value = (cosTheta * std::acos(y) - x * sinThetaSqrtY) * sinSigmaSquared +
                         (x > 0.0 ? std::atan(sinThetaSqrtY / x) : std::numbers::pi / 2.0);
    return std::max(0.0, value);
}

} // namespace prt::sh
