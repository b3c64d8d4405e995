// The nested fit's lighting prior (GlossyOptions::nestedLighting, `prt glossy --nested-lighting`): a training map
// as rows of luminance x solid angle at the held-out directions, one row per turn about y.
#include "glossy.h"

#include "core.h"
#include "image.h"
#include "luminance.h"
#include "sh.h"

#include <cmath>
#include <numbers>

namespace prt::glossy {

std::vector<float> lightingPrior(const EnvironmentMap& env, const std::string& path, const DirectionGrid& held,
                                 int rotations) {
    constexpr int kWidth = 128, kHeight = 64;
    std::vector<float> rows;
    const int width = env.radiance.width, height = env.radiance.height;
    if (env.layout != EnvLayout::Equirectangular || width < kWidth)
        throw Error(path, "--nested-lighting", "must be an equirectangular map at least 128 texels wide", kExitUsage);
    const std::vector<double> solidAngle = sh::texelSolidAngles(env);
    std::vector<double> bins(size_t(kWidth) * kHeight, 0.0);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t t = size_t(y) * width + size_t(x);
            const float* c = &env.radiance.rgb[3 * t];
            bins[size_t(y * kHeight / height) * kWidth + size_t(x * kWidth / width)] +=
                solidAngle[t] * (kLuminance[0] * c[0] + kLuminance[1] * c[1] + kLuminance[2] * c[2]);
        }
    for (int r = 0; r < rotations; ++r) {
        const double angle = 2.0 * std::numbers::pi * r / rotations, cs = std::cos(angle), sn = std::sin(angle);
        std::vector<double> row(held.count(), 0.0);
        double total = 0.0;
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x) {
                double d[3];
                sh::equirectDirection(kWidth, kHeight, x, y, d);
                const double turned[3] = {cs * d[0] + sn * d[2], d[1], -sn * d[0] + cs * d[2]};
                size_t best = 0;
                double bestDot = -2.0;
                for (size_t i = 0; i < held.count(); ++i) {
                    const float* h = &held.directions[i * 3];
                    const double dot = turned[0] * h[0] + turned[1] * h[1] + turned[2] * h[2];
                    if (dot > bestDot) bestDot = dot, best = i;
                }
                const double value = bins[size_t(y) * kWidth + size_t(x)];
                row[best] += value, total += value;
            }
        if (!(total > 0.0)) throw Error(path, "--nested-lighting", "is black", kExitUsage);
        for (double v : row) rows.push_back(float(v / total));
    }
    return rows;
}

} // namespace prt::glossy
