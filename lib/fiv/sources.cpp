// Small sources of a map, taken out of the cube and shadowed from their own texels (issue 20, "FIV under a sharp
// sun"): the cube smears a 0.5-degree sun over a 2.8-degree texel whose mask bit comes from the texel centre.
#include "fiv.h"

#include "core.h"
#include "luminance.h"
#include "sh.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace prt::fiv {

namespace {

double luminance(const float* rgb) { return kLuminance[0] * rgb[0] + kLuminance[1] * rgb[1] + kLuminance[2] * rgb[2]; }

void texelDirection(const EnvironmentMap& env, size_t texel, double d[3]) {
    const Image& image = env.radiance;
    int x = int(texel % size_t(image.width)), y = int(texel / size_t(image.width));
    if (env.layout == EnvLayout::Equirectangular) sh::equirectDirection(image.width, image.height, x, y, d);
    else sh::cubeStripDirection(image.width, x, y, d);
}

} // namespace

SmallSources extractSmallSources(EnvironmentMap& env, const SmallSourceOptions& options) {
    SmallSources out;
    Image& image = env.radiance;
    const size_t texels = size_t(image.width) * image.height;
    if (options.maxSources <= 0 || texels == 0) return out;
    const std::vector<double> solidAngle = sh::texelSolidAngles(env);
    double total = 0.0;
    for (size_t t = 0; t < texels; ++t) total += luminance(&image.rgb[3 * t]) * solidAngle[t];
    if (!(total > 0.0)) return out;
    const double cosRadius = std::cos(options.radiusDegrees * std::numbers::pi / 180.0);
    std::vector<size_t> members;
    for (int s = 0; s < options.maxSources; ++s) {
        size_t peak = 0;
        for (size_t t = 1; t < texels; ++t)
            if (luminance(&image.rgb[3 * t]) > luminance(&image.rgb[3 * peak])) peak = t;
        const double peakLuminance = luminance(&image.rgb[3 * peak]);
        if (!(peakLuminance > 0.0)) break;
        double centre[3];
        texelDirection(env, peak, centre);
        members.clear();
        double power = 0.0;
        for (size_t t = 0; t < texels; ++t) {
            double l = luminance(&image.rgb[3 * t]);
            if (l < options.floorFraction * peakLuminance) continue;
            double d[3];
            texelDirection(env, t, d);
            if (d[0] * centre[0] + d[1] * centre[1] + d[2] * centre[2] < cosRadius) continue;
            members.push_back(t);
            power += l * solidAngle[t];
        }
        if (power < options.minPowerFraction * total) break;
        for (size_t t : members) {
            double d[3];
            texelDirection(env, t, d);
            out.direction.insert(out.direction.end(), d, d + 3);
            for (int c = 0; c < 3; ++c) {
                out.power.push_back(double(image.rgb[3 * t + size_t(c)]) * solidAngle[t]);
                image.rgb[3 * t + size_t(c)] = 0.0f;
            }
        }
        out.powerFraction.push_back(power / total);
        out.texelCount.push_back(members.size());
    }
    return out;
}

} // namespace prt::fiv
