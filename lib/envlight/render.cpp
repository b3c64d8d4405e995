// The decomposed lighting as a map again, so the path tracer can render exactly what the hybrid approximates and
// decomposition error separates from transfer error.
#include "envlight.h"

#include "core.h"

#include <algorithm>
#include <cmath>

namespace prt::envlight {

EnvironmentMap renderLighting(const std::vector<ConeLight>& lights, const std::vector<double>& residual, int order,
                              int width, int supersample, double* negativeEnergy) {
    if (width < 4 || width % 2 != 0 || supersample < 1 ||
        residual.size() != size_t(sh::coefficientCount(order)) * 3)
        throw Error("", "renderLighting", "bad size", kExitFailure);
    const int height = width / 2;
    EnvironmentMap env;
    env.layout = EnvLayout::Equirectangular;
    env.radiance.width = width;
    env.radiance.height = height;
    env.radiance.rgb.assign(size_t(width) * height * 3, 0.0f);
    std::vector<double> solidAngle = sh::texelSolidAngles(env), basis(sh::coefficientCount(order));
    double negative = 0.0, total = 0.0;
    const double texelAngle = M_PI / height;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            double d[3], value[3] = {0, 0, 0};
            sh::equirectDirection(width, height, x, y, d);
            sh::evaluate(order, d[0], d[1], d[2], basis.data());
            for (size_t j = 0; j < basis.size(); ++j)
                for (int c = 0; c < 3; ++c) value[c] += residual[j * 3 + c] * basis[j];
            for (const ConeLight& light : lights) {
                double cosine = d[0] * light.direction[0] + d[1] * light.direction[1] + d[2] * light.direction[2];
                // Only texels within a texel diagonal of the rim can be partly covered.
                double angle = std::acos(std::clamp(cosine, -1.0, 1.0));
                if (angle > light.angularRadius + 2.0 * texelAngle / std::max(0.05, std::sin(M_PI * (y + 0.5) / height)))
                    continue;
                const double cosRadius = std::cos(light.angularRadius);
                int inside = 0;
                for (int sy = 0; sy < supersample; ++sy)
                    for (int sx = 0; sx < supersample; ++sx) {
                        double s[3];
                        // Stratified points inside the texel, uniform in its (x, cos theta) so in solid angle.
                        double u = (sx + 0.5) / supersample, v = (sy + 0.5) / supersample;
                        double cosTop = std::cos(M_PI * y / height), cosBottom = std::cos(M_PI * (y + 1) / height);
                        double cosTheta = cosTop + v * (cosBottom - cosTop);
                        double theta = std::acos(std::clamp(cosTheta, -1.0, 1.0));
                        sh::equirectDirection(width, height, x - 0.5 + u, theta / M_PI * height - 0.5, s);
                        if (s[0] * light.direction[0] + s[1] * light.direction[1] + s[2] * light.direction[2] >= cosRadius)
                            ++inside;
                    }
                double coverage = double(inside) / (supersample * supersample);
                for (int c = 0; c < 3; ++c) value[c] += coverage * light.radiance[c];
            }
            size_t texel = size_t(y) * width + x;
            double luminance = kLuminance[0] * value[0] + kLuminance[1] * value[1] + kLuminance[2] * value[2];
            total += std::abs(luminance) * solidAngle[texel];
            for (int c = 0; c < 3; ++c) {
                if (value[c] < 0.0) negative += -value[c] * kLuminance[c] * solidAngle[texel];
                env.radiance.rgb[texel * 3 + c] = float(value[c]);
            }
        }
    if (negativeEnergy) *negativeEnergy = total > 0.0 ? negative / total : 0.0;
    return env;
}

} // namespace prt::envlight
