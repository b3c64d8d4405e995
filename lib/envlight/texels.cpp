// The environment as a list of (direction, solid angle, radiance) samples, and its SH projection.
#include "envlight.h"

#include <cmath>

namespace prt::envlight {

double coneSolidAngle(double angularRadius) { return sh::capSolidAngle(std::cos(angularRadius)); }

Texels environmentTexels(const EnvironmentMap& env, const double* rotation) {
    const Image& image = env.radiance;
    Texels texels;
    texels.solidAngles = sh::texelSolidAngles(env); // also checks the size against the layout
    texels.rgb = image.rgb;
    texels.directions.resize(texels.solidAngles.size() * 3);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            double d[3];
            if (env.layout == EnvLayout::Equirectangular)
                sh::equirectDirection(image.width, image.height, x, y, d);
            else
                sh::cubeStripDirection(image.width, x, y, d);
            double* out = &texels.directions[(size_t(y) * image.width + x) * 3];
            for (int r = 0; r < 3; ++r)
                out[r] = rotation ? rotation[3 * r] * d[0] + rotation[3 * r + 1] * d[1] + rotation[3 * r + 2] * d[2]
                                  : d[r];
        }
    return texels;
}

std::vector<double> projectTexels(const Texels& texels, int order) {
    const int coefficients = sh::coefficientCount(order);
    std::vector<double> projection(size_t(coefficients) * 3, 0.0), basis(coefficients);
    for (size_t i = 0; i < texels.count(); ++i) {
        const float* rgb = &texels.rgb[i * 3];
        if (rgb[0] == 0.0f && rgb[1] == 0.0f && rgb[2] == 0.0f) continue;
        const double* d = &texels.directions[i * 3];
        sh::evaluate(order, d[0], d[1], d[2], basis.data());
        for (int j = 0; j < coefficients; ++j)
            for (int c = 0; c < 3; ++c) projection[j * 3 + c] += texels.solidAngles[i] * basis[j] * rgb[c];
    }
    return projection;
}

} // namespace prt::envlight
