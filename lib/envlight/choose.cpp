// K per map from the decomposition's own error: the lighting error each configuration leaves (what K cones and an
// order-L residual do not say, against what plain order-P SH does not say), weighted per SH band by a diffuse
// transfer's falling spectrum, and the smallest-error K; plain SH when no K beats it.
#include "envlight.h"

#include "core.h"

#include <algorithm>
#include <cmath>

namespace prt::envlight {

namespace {

double luminanceOf(const double* rgb) { return kLuminance[0] * rgb[0] + kLuminance[1] * rgb[1] + kLuminance[2] * rgb[2]; }

// Band-weighted energy of luminance SH coefficients `e` ([order^2]) over bands from..order-1, plus `tail` (the
// energy above the last band) at the last band's weight + 1.
double weightedEnergy(const std::vector<double>& e, int from, int order, double tail, double exponent) {
    double sum = 0.0;
    for (int l = from; l < order; ++l) {
        double band = 0.0;
        for (int j = l * l; j < (l + 1) * (l + 1); ++j) band += e[j] * e[j];
        sum += band * std::pow(1.0 + l, -exponent);
    }
    return sum + std::max(0.0, tail) * std::pow(1.0 + order, -exponent);
}

} // namespace

Decomposition decomposeChoosingLights(const EnvironmentMap& env, const Options& options, const ChoiceOptions& choice,
                                      LightChoice* report) {
    if (choice.plainOrder < 1 || choice.plainOrder > sh::kMaxOrder || choice.errorOrder <= choice.plainOrder ||
        choice.errorOrder <= options.order || choice.errorOrder > sh::kMaxOrder)
        throw Error("", "light choice", "need plain order and residual order below the error order <= " +
                                            std::to_string(sh::kMaxOrder), kExitUsage);
    if (!(choice.margin > 0.0 && choice.margin <= 1.0)) throw Error("", "light choice", "margin outside (0, 1]", kExitUsage);
    Decomposition full = decompose(env, options); // up to options.maxLights lights, as the elbow keeps them
    LightChoice result;

    // The map's luminance: per texel, its energy, and its projection onto errorOrder bands.
    const int M = choice.errorOrder;
    Texels texels = environmentTexels(env, options.rotation);
    std::vector<double> rgbProjection = projectTexels(texels, M), projection(size_t(M) * M);
    for (size_t j = 0; j < projection.size(); ++j) projection[j] = luminanceOf(&rgbProjection[j * 3]);
    std::vector<double> remainder(texels.count()); // luminance of E minus the lights so far
    double energy = 0.0;
    for (size_t i = 0; i < texels.count(); ++i) {
        double rgb[3] = {texels.rgb[i * 3], texels.rgb[i * 3 + 1], texels.rgb[i * 3 + 2]};
        remainder[i] = luminanceOf(rgb);
        energy += remainder[i] * remainder[i] * texels.solidAngles[i];
    }
    auto projectedEnergy = [&](const std::vector<double>& e) {
        double s = 0.0;
        for (double v : e) s += v * v;
        return s;
    };
    // Plain SH at plainOrder: the bands from plainOrder up, and everything above M.
    result.plainError = std::sqrt(weightedEnergy(projection, choice.plainOrder, M, energy - projectedEnergy(projection),
                                                 choice.spectrumExponent) / energy);

    // Hybrid with the first k lights (by power): e = P(E) - P(lights), its bands from the residual's order up.
    std::vector<double> e = projection, basis(size_t(M) * M);
    for (size_t k = 0; k <= full.lights.size(); ++k) {
        if (k > 0) {
            const ConeLight& light = full.lights[k - 1];
            double lum = luminanceOf(light.radiance.data()), cosRadius = std::cos(light.angularRadius);
            std::vector<double> cap(basis.size());
            sh::capProjection(M, light.direction.data(), cosRadius, cap.data());
            for (size_t j = 0; j < e.size(); ++j) e[j] -= lum * cap[j];
            // The cone's coverage of each texel, by 4x4 points would be exact; a texel-centre test with the
            // texel's own size as edge is within a texel of it, which is what the weights below can see.
            for (size_t i = 0; i < texels.count(); ++i) {
                const double* w = &texels.directions[i * 3];
                double c = w[0] * light.direction[0] + w[1] * light.direction[1] + w[2] * light.direction[2];
                double halfTexel = 0.5 * std::sqrt(texels.solidAngles[i]);
                double angle = std::acos(std::clamp(c, -1.0, 1.0));
                if (angle > light.angularRadius + halfTexel) continue;
                double coverage = std::clamp((light.angularRadius + halfTexel - angle) / (2.0 * halfTexel), 0.0, 1.0);
                remainder[i] -= lum * coverage;
            }
        }
        double rest = 0.0;
        for (size_t i = 0; i < texels.count(); ++i) rest += remainder[i] * remainder[i] * texels.solidAngles[i];
        result.errors.push_back(
            std::sqrt(weightedEnergy(e, options.order, M, rest - projectedEnergy(e), choice.spectrumExponent) / energy));
    }
    size_t best = 0;
    for (size_t k = 1; k < result.errors.size(); ++k)
        if (result.errors[k] < result.errors[best]) best = k;
    result.lights = int(best);
    result.plainSh = best == 0 || !(result.errors[best] < choice.margin * result.plainError);
    char line[300];
    if (result.plainSh) {
        result.lights = 0;
        std::snprintf(line, sizeof line,
                      "lights do not pay: the best hybrid (order %d, %zu lights) leaves %.4g of the map's weighted "
                      "error against %.4g for plain order-%d SH; use plain SH",
                      options.order, best, result.errors[best], result.plainError, choice.plainOrder);
    } else {
        std::snprintf(line, sizeof line,
                      "%zu lights: the hybrid (order %d) leaves %.4g of the map's weighted error against %.4g for "
                      "plain order-%d SH",
                      best, options.order, result.errors[best], result.plainError, choice.plainOrder);
    }
    result.reason = line;

    // The decomposition with the chosen lights, refitted together (the fit of k lights depends on which others
    // are present), or none: then the residual is the plain projection at options.order.
    Decomposition chosen;
    if (result.lights == int(full.lights.size())) {
        chosen = std::move(full);
    } else {
        Options again = options;
        again.maxLights = result.lights;
        again.minLights = std::min(again.minLights, result.lights);
        chosen = decompose(env, again);
    }
    if (report) *report = result;
    return chosen;
}

} // namespace prt::envlight
