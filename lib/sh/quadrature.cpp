// Gauss-Legendre and sphere product quadrature, the exact integrators behind triple products and the tests.
#include "sh.h"

#include "core.h"

#include <cmath>
#include <numbers>

namespace prt::sh {

void gaussLegendre(int n, double* nodes, double* weights) {
    if (n < 1) throw Error("", "sh::gaussLegendre", "need at least one node", kExitFailure);
    // Newton on P_n from the Tricomi estimate of each root; roots are symmetric, so solve half.
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double x = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
        double derivative = 1.0;
        for (int iteration = 0; iteration < 100; ++iteration) {
            double p0 = 1.0, p1 = x;
            for (int k = 2; k <= n; ++k) {
                double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            derivative = n * (x * p1 - p0) / (x * x - 1.0);
            double step = p1 / derivative;
            x -= step;
            if (std::abs(step) < 1e-15) break;
        }
        double weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
        nodes[i] = -x;
        nodes[n - 1 - i] = x;
        weights[i] = weights[n - 1 - i] = weight;
    }
}

SphereQuadrature sphereQuadrature(int degree) {
    if (degree < 0) throw Error("", "sh::sphereQuadrature", "negative degree", kExitFailure);
    // n Gauss nodes integrate z^(2n-1) exactly; `degree + 1` uniform azimuths integrate cos(k phi), k <= degree.
    int zCount = degree / 2 + 1;
    int phiCount = degree + 1;
    std::vector<double> z(zCount), zWeight(zCount);
    gaussLegendre(zCount, z.data(), zWeight.data());

    SphereQuadrature q;
    q.directions.reserve(size_t(zCount) * phiCount * 3);
    q.weights.reserve(size_t(zCount) * phiCount);
    for (int i = 0; i < zCount; ++i) {
        double sinTheta = std::sqrt(std::max(0.0, 1.0 - z[i] * z[i]));
        for (int j = 0; j < phiCount; ++j) {
            double phi = 2.0 * std::numbers::pi * j / phiCount;
            q.directions.insert(q.directions.end(), {sinTheta * std::cos(phi), sinTheta * std::sin(phi), z[i]});
            q.weights.push_back(zWeight[i] * 2.0 * std::numbers::pi / phiCount);
        }
    }
    return q;
}

} // namespace prt::sh
