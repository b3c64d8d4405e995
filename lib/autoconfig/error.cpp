// The error measure: relative RMSE against a path-traced reference with the reference's own noise taken out
// (noise adds in quadrature, so a configuration is not charged for it).
#include "autoconfig.h"

#include <algorithm>
#include <cmath>

namespace prt::autoconfig {

double noiseCorrectedError(const float* radiance, const float* reference, const float* standardError, size_t count) {
    double difference = 0.0, signal = 0.0, noise = 0.0;
    for (size_t i = 0; i < count * 3; ++i) {
        const double d = double(radiance[i]) - reference[i];
        difference += d * d;
        signal += double(reference[i]) * reference[i];
        noise += double(standardError[i]) * standardError[i];
    }
    const double truth = signal - noise; // E[r^2] = truth^2 + se^2
    if (!(truth > 0.0)) return difference > 0.0 ? INFINITY : 0.0;
    return std::sqrt(std::max(0.0, difference - noise) / truth);
}

} // namespace prt::autoconfig
