// The one tone map of prt's 8-bit pictures (image.h).
#include "image.h"

#include <cmath>

namespace prt {

uint8_t toneMap(float radiance, float exposure) {
    double x = double(radiance) * std::exp2(double(exposure));
    if (!(x > 0.0)) return 0; // negative and NaN
    double display = x / (1.0 + x);
    double encoded = display <= 0.0031308 ? 12.92 * display : 1.055 * std::pow(display, 1.0 / 2.4) - 0.055;
    return uint8_t(std::lround(std::fmin(1.0, encoded) * 255.0));
}

} // namespace prt
