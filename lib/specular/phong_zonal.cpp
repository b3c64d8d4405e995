// The Funk-Hecke multipliers of the normalised Phong lobe, exactly, and the adaptive band count they give.
#include "specular.h"

#include "core.h"

#include <cmath>
#include <string>

namespace prt::specular {

namespace {

void checkExponent(double exponent) {
    if (!(exponent > 0.0) || !std::isfinite(exponent))
        throw Error("", "phong exponent", "must be a finite number > 0, got " + std::to_string(exponent), kExitUsage);
}

void checkBands(int bands, const char* what) {
    if (bands < 1 || bands > sh::kMaxOrder)
        throw Error("", what, "must lie in 1.." + std::to_string(sh::kMaxOrder) + ", got " + std::to_string(bands),
                    kExitUsage);
}

} // namespace

std::vector<double> phongMultipliers(double exponent, int bands) {
    checkExponent(exponent);
    checkBands(bands, "bands");
    // I_l = integral_0^1 t^n P_l(t) dt; the two-step recurrence follows from Bonnet's recurrence and integration by
    // parts, and is exact for non-integer n too (I_l vanishes for even l > n + 1 when n is an even integer).
    std::vector<double> integral(bands);
    for (int l = 0; l < bands; ++l)
        integral[l] = l == 0 ? 1.0 / (exponent + 1.0)
                    : l == 1 ? 1.0 / (exponent + 2.0)
                             : (exponent - l + 2.0) / (exponent + l + 1.0) * integral[l - 2];
    std::vector<double> multiplier(bands);
    for (int l = 0; l < bands; ++l) multiplier[l] = (exponent + 2.0) * integral[l];
    return multiplier;
}

int adaptiveBands(double exponent, int maxBands, double tolerance) {
    checkBands(maxBands, "bands");
    if (!(tolerance >= 0.0)) throw Error("", "band tolerance", "must be >= 0", kExitUsage);
    std::vector<double> multiplier = phongMultipliers(exponent, maxBands);
    int bands = 1;
    for (int l = 1; l < maxBands; ++l)
        if (std::abs(multiplier[l] / multiplier[0]) >= tolerance) bands = l + 1;
    return bands;
}

} // namespace prt::specular
