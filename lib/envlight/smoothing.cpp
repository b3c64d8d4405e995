// Spherical-Gaussian pre-smoothing of the environment's luminance (thesis 4.3.3): removes single-texel outliers
// and makes the function smooth enough for hill climbing and quadric fits.
#include "envlight.h"

#include "core.h"

#include <algorithm>
#include <cmath>

namespace prt::envlight {

namespace {

constexpr double kTruncation = 1e-3;

double kappaOf(double fwhm) { return std::log(2.0) / (1.0 - std::cos(0.5 * fwhm)); }
double supportCosine(double kappa) { return std::max(-1.0, 1.0 + std::log(kTruncation) / kappa); }

// Texel indices bucketed by polar angle from +Y and azimuth on a regular grid, so a query visits only the cells
// its support can reach.
struct Buckets {
    int rows = 0, columns = 0;
    double cell = 0.0;
    std::vector<uint32_t> offsets, texels;
};

void polarAzimuth(const double* d, double& theta, double& phi) {
    theta = std::acos(std::clamp(d[1], -1.0, 1.0));
    phi = std::atan2(d[0], -d[2]) + M_PI; // [0, 2 pi]
}

Buckets bucket(const Texels& texels, double cell) {
    Buckets b;
    b.rows = std::max(1, int(std::ceil(M_PI / cell)));
    b.columns = std::max(1, int(std::ceil(2.0 * M_PI / cell)));
    b.cell = cell;
    auto cellOf = [&](size_t i) {
        double theta, phi;
        polarAzimuth(&texels.directions[i * 3], theta, phi);
        int row = std::min(b.rows - 1, int(theta / cell)), column = std::min(b.columns - 1, int(phi / cell));
        return size_t(row) * b.columns + column;
    };
    b.offsets.assign(size_t(b.rows) * b.columns + 1, 0);
    for (size_t i = 0; i < texels.count(); ++i) ++b.offsets[cellOf(i) + 1];
    for (size_t c = 1; c < b.offsets.size(); ++c) b.offsets[c] += b.offsets[c - 1];
    b.texels.resize(texels.count());
    std::vector<uint32_t> fill(b.offsets.begin(), b.offsets.end() - 1);
    for (size_t i = 0; i < texels.count(); ++i) b.texels[fill[cellOf(i)]++] = uint32_t(i);
    return b;
}

} // namespace

std::vector<double> smoothLuminance(const Texels& texels, const double* directions, size_t count, double fwhm) {
    if (!(fwhm > 0.0 && fwhm <= 0.5)) throw Error("", "smoothing", "FWHM outside (0, 0.5] radians", kExitUsage);
    const double kappa = kappaOf(fwhm), cosSupport = supportCosine(kappa), support = std::acos(cosSupport);
    Buckets buckets = bucket(texels, std::max(support / 2.0, M_PI / 720.0));
    std::vector<double> luminance(texels.count());
    for (size_t i = 0; i < texels.count(); ++i)
        luminance[i] = kLuminance[0] * texels.rgb[i * 3] + kLuminance[1] * texels.rgb[i * 3 + 1] +
                       kLuminance[2] * texels.rgb[i * 3 + 2];

    std::vector<double> smoothed(count, 0.0);
    for (size_t q = 0; q < count; ++q) {
        const double* x = &directions[q * 3];
        double theta, phi;
        polarAzimuth(x, theta, phi);
        int rowBegin = std::max(0, int((theta - support) / buckets.cell));
        int rowEnd = std::min(buckets.rows - 1, int((theta + support) / buckets.cell));
        double weighted = 0.0, weights = 0.0;
        for (int row = rowBegin; row <= rowEnd; ++row) {
            // Azimuth half-range of the support: asin(sin s / sin theta) at the centre's polar angle, widened to
            // the row edge nearest a pole (conservative).
            double nearPole = std::min({std::sin(theta), std::sin(row * buckets.cell),
                                        std::sin(std::min(M_PI, (row + 1) * buckets.cell))});
            int columnBegin = 0, columnEnd = buckets.columns - 1;
            if (nearPole > std::sin(support) && support < M_PI / 2) {
                double half = std::asin(std::min(1.0, std::sin(support) / nearPole)) + buckets.cell;
                columnBegin = int(std::floor((phi - half) / buckets.cell));
                columnEnd = int(std::floor((phi + half) / buckets.cell));
                if (columnEnd - columnBegin + 1 >= buckets.columns) columnBegin = 0, columnEnd = buckets.columns - 1;
            }
            for (int c = columnBegin; c <= columnEnd; ++c) {
                int column = ((c % buckets.columns) + buckets.columns) % buckets.columns;
                size_t cell = size_t(row) * buckets.columns + column;
                for (uint32_t k = buckets.offsets[cell]; k < buckets.offsets[cell + 1]; ++k) {
                    uint32_t i = buckets.texels[k];
                    const double* d = &texels.directions[i * 3];
                    double dot = d[0] * x[0] + d[1] * x[1] + d[2] * x[2];
                    if (dot < cosSupport) continue;
                    double w = std::exp(kappa * (dot - 1.0)) * texels.solidAngles[i];
                    weighted += w * luminance[i];
                    weights += w;
                }
            }
        }
        smoothed[q] = weights > 0.0 ? weighted / weights : 0.0;
    }
    return smoothed;
}

std::vector<double> gaussianBandFactors(double fwhm, int order) {
    const double kappa = kappaOf(fwhm), a = supportCosine(kappa);
    const int n = 64;
    std::vector<double> nodes(n), weights(n), factors(order, 0.0);
    sh::gaussLegendre(n, nodes.data(), weights.data());
    double norm = 0.0;
    std::vector<double> legendre(size_t(order) + 1);
    for (int k = 0; k < n; ++k) {
        double t = a + (1.0 - a) * 0.5 * (nodes[k] + 1.0), w = weights[k] * std::exp(kappa * (t - 1.0));
        legendre[0] = 1.0;
        if (order >= 1) legendre[1] = t;
        for (int l = 1; l < order; ++l) legendre[l + 1] = ((2 * l + 1) * t * legendre[l] - l * legendre[l - 1]) / (l + 1);
        norm += w;
        for (int l = 0; l < order; ++l) factors[l] += w * legendre[l];
    }
    for (double& f : factors) f /= norm;
    return factors;
}

} // namespace prt::envlight
