// Exact SH projection of a spherical cap: zonal about its axis, so each band is one Legendre integral.
#include "sh.h"

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

} // namespace prt::sh
