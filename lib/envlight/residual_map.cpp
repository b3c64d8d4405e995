// The map minus its cone lights, as a map: the smooth part of the lighting that the glossy lobes integrate when the
// lights themselves are shaded exactly (docs/glossy.md, "Lights through the glossy path").
#include "envlight.h"

#include "core.h"

#include <algorithm>
#include <cmath>

namespace prt::envlight {

EnvironmentMap subtractConeLights(const EnvironmentMap& env, const std::vector<ConeLight>& lights, int supersample,
                                  bool clampNegative, ResidualMapStats* stats) {
    const int width = env.radiance.width, height = env.radiance.height;
    if (env.layout != EnvLayout::Equirectangular || width < 4 || width != 2 * height ||
        env.radiance.rgb.size() != size_t(width) * height * 3)
        throw Error("", "--env", "the residual map needs a 2:1 equirectangular map", kExitInput);
    if (supersample < 1) throw Error("", "subtractConeLights", "supersample must be >= 1", kExitFailure);
    // The cones exactly as `prt reference --lights` renders them: renderLighting with a zero residual.
    const EnvironmentMap cones = renderLighting(lights, std::vector<double>(3, 0.0), 1, width, supersample);
    const std::vector<double> solidAngle = sh::texelSolidAngles(env);
    EnvironmentMap residual = env;
    double negative = 0.0, lit = 0.0, total = 0.0;
    for (size_t t = 0; t < solidAngle.size(); ++t)
        for (int c = 0; c < 3; ++c) {
            const size_t i = t * 3 + c;
            const double value = double(env.radiance.rgb[i]) - double(cones.radiance.rgb[i]);
            total += kLuminance[c] * double(env.radiance.rgb[i]) * solidAngle[t];
            lit += kLuminance[c] * double(cones.radiance.rgb[i]) * solidAngle[t];
            if (value < 0.0) negative -= kLuminance[c] * value * solidAngle[t];
            residual.radiance.rgb[i] = float(clampNegative ? std::max(0.0, value) : value);
        }
    if (stats) {
        stats->negativeEnergy = total > 0.0 ? negative / total : 0.0;
        stats->lightsEnergy = total > 0.0 ? lit / total : 0.0;
    }
    return residual;
}

} // namespace prt::envlight
