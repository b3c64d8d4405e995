// Closed-form test environments: a constant background plus uniform discs (cones) of known size and radiance,
// rasterised into an equirectangular map with 4x4 supersampling per texel.
#pragma once

#include "envlight.h"
#include "image.h"
#include "sh.h"

#include <array>
#include <cmath>
#include <vector>

namespace envlight_test {

struct Disc {
    std::array<double, 3> direction; // unit
    double radiusDegrees;
    std::array<double, 3> radiance;  // added on top of the background
};

inline std::array<double, 3> unit(double x, double y, double z) {
    double n = std::sqrt(x * x + y * y + z * z);
    return {x / n, y / n, z / n};
}

inline prt::EnvironmentMap discMap(int width, double background, const std::vector<Disc>& discs) {
    prt::EnvironmentMap env;
    env.layout = prt::EnvLayout::Equirectangular;
    env.radiance.width = width;
    env.radiance.height = width / 2;
    env.radiance.rgb.assign(size_t(width) * (width / 2) * 3, float(background));
    const int sub = 4;
    for (int y = 0; y < width / 2; ++y)
        for (int x = 0; x < width; ++x)
            for (const Disc& disc : discs) {
                double cosRadius = std::cos(disc.radiusDegrees * M_PI / 180.0), covered = 0.0;
                for (int sy = 0; sy < sub; ++sy)
                    for (int sx = 0; sx < sub; ++sx) {
                        double d[3];
                        prt::sh::equirectDirection(width, width / 2, x - 0.5 + (sx + 0.5) / sub, y - 0.5 + (sy + 0.5) / sub, d);
                        if (d[0] * disc.direction[0] + d[1] * disc.direction[1] + d[2] * disc.direction[2] >= cosRadius)
                            covered += 1.0 / (sub * sub);
                    }
                for (int c = 0; c < 3; ++c)
                    env.radiance.rgb[(size_t(y) * width + x) * 3 + c] += float(covered * disc.radiance[c]);
            }
    return env;
}

inline double angleDegrees(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    return std::acos(std::min(1.0, std::max(-1.0, c))) * 180.0 / M_PI;
}

} // namespace envlight_test
