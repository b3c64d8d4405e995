// Evaluation of the real SH basis and the clamped-cosine factors.
#include "sh.h"

#include "core.h"

#include <cmath>
#include <numbers>

namespace prt::sh {

namespace {

// Coefficients of the normalized associated-Legendre recurrences, where N_l^m(z) = P_l^m(z) / sin^m(theta)
// times the orthonormalization constant. Dividing out sin^m(theta) leaves polynomials in z, and the sin^m(theta)
// cos(m phi), sin^m(theta) sin(m phi) factors are Re and Im of (x + i y)^m, so no trigonometry is needed.
struct Recurrence {
    double diagonal[kMaxOrder];           // N_m^m = N_{m-1}^{m-1} * diagonal[m]
    double a[kMaxOrder][kMaxOrder];       // N_l^m = a[l][m] z N_{l-1}^m - b[l][m] N_{l-2}^m
    double b[kMaxOrder][kMaxOrder];
};

Recurrence buildRecurrence() {
    Recurrence r{};
    r.diagonal[0] = 0.5 / std::sqrt(std::numbers::pi);
    for (int m = 1; m < kMaxOrder; ++m) r.diagonal[m] = std::sqrt((2.0 * m + 1.0) / (2.0 * m));
    for (int l = 1; l < kMaxOrder; ++l)
        for (int m = 0; m < l; ++m) {
            double l2 = double(l) * l, m2 = double(m) * m, lm1 = double(l - 1) * (l - 1);
            r.a[l][m] = std::sqrt((4.0 * l2 - 1.0) / (l2 - m2));
            r.b[l][m] = r.a[l][m] * std::sqrt((lm1 - m2) / (4.0 * lm1 - 1.0));
        }
    return r;
}

const Recurrence& recurrence() {
    static const Recurrence r = buildRecurrence();
    return r;
}

template <typename T>
void evaluateBasis(int order, double x, double y, double z, T* out) {
    if (order < 1 || order > kMaxOrder)
        throw Error("", "sh::evaluate", "order " + std::to_string(order) + " outside 1.." + std::to_string(kMaxOrder),
                    kExitFailure);
    const Recurrence& r = recurrence();
    double diagonal = r.diagonal[0];
    double cosine = 1.0, sine = 0.0; // Re and Im of (x + i y)^m
    for (int m = 0; m < order; ++m) {
        if (m > 0) {
            diagonal *= r.diagonal[m];
            double c = x * cosine - y * sine;
            sine = x * sine + y * cosine;
            cosine = c;
        }
        // Real SH for m != 0 carry a factor sqrt(2); m = 0 has only the cosine part.
        double previous = 0.0, current = m > 0 ? std::numbers::sqrt2 * diagonal : diagonal;
        for (int l = m; l < order; ++l) {
            if (l > m) {
                double next = r.a[l][m] * z * current - r.b[l][m] * previous;
                previous = current;
                current = next;
            }
            out[index(l, m)] = T(current * cosine);
            if (m > 0) out[index(l, -m)] = T(current * sine);
        }
    }
}

} // namespace

void evaluate(int order, double x, double y, double z, double* out) { evaluateBasis(order, x, y, z, out); }
void evaluate(int order, float x, float y, float z, float* out) { evaluateBasis(order, x, y, z, out); }

double clampedCosine(int l) {
    if (l == 0) return std::numbers::pi;
    if (l == 1) return 2.0 * std::numbers::pi / 3.0;
    if (l % 2 == 1) return 0.0;
    // Ramamoorthi-Hanrahan: 2 pi (-1)^(l/2 - 1) / ((l + 2)(l - 1)) * l! / (2^l ((l/2)!)^2).
    double centralBinomial = 1.0; // l! / (2^l ((l/2)!)^2), built from k = 0 by the ratio (k + 1) / (k + 2)
    for (int k = 0; k < l; k += 2) centralBinomial *= double(k + 1) / double(k + 2);
    double sign = (l / 2) % 2 == 1 ? 1.0 : -1.0;
    return 2.0 * std::numbers::pi * sign / (double(l + 2) * double(l - 1)) * centralBinomial;
}

} // namespace prt::sh
