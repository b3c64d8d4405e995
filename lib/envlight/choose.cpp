// K per map from the decomposition's own error: the lighting error each configuration leaves (what K cones and an
// order-L residual do not say, against what plain order-P SH does not say), per SH band up to order 32, weighted by
// a Gaussian band window standing for a shadowed diffuse transfer's spectrum; the smallest-error K, or plain SH
// when no K beats it.
#include "envlight.h"

#include "core.h"

#include <algorithm>
#include <cmath>

namespace prt::envlight {

namespace {

double luminanceOf(const double* rgb) { return kLuminance[0] * rgb[0] + kLuminance[1] * rgb[1] + kLuminance[2] * rgb[2]; }

// Energy per SH band of luminance coefficients `e` ([order^2]), bands from..order-1 (0 below from).
std::vector<double> bandEnergies(const std::vector<double>& e, int from, int order) {
    std::vector<double> bands(size_t(order), 0.0);
    for (int l = from; l < order; ++l)
        for (int j = l * l; j < (l + 1) * (l + 1); ++j) bands[size_t(l)] += e[j] * e[j];
    return bands;
}

// sqrt(sum_l exp(-(l / width)^2) bands[l] / energy).
double weightedError(const std::vector<double>& bands, double width, double energy) {
    double sum = 0.0;
    for (size_t l = 0; l < bands.size(); ++l) sum += std::exp(-(double(l) / width) * (double(l) / width)) * bands[l];
    return std::sqrt(sum / energy);
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
    double energy = 0.0;
    for (size_t i = 0; i < texels.count(); ++i) {
        double rgb[3] = {texels.rgb[i * 3], texels.rgb[i * 3 + 1], texels.rgb[i * 3 + 2]};
        energy += luminanceOf(rgb) * luminanceOf(rgb) * texels.solidAngles[i];
    }
    // Plain SH at plainOrder leaves the bands from plainOrder up.
    result.plainBands = bandEnergies(projection, choice.plainOrder, M);
    result.plainError = weightedError(result.plainBands, choice.bandWidth, energy);
    // Hybrid with the first k lights (by power): e = P(E) - P(lights), its bands from the residual's order up.
    std::vector<double> e = projection, cap(size_t(M) * M);
    for (size_t k = 0; k <= full.lights.size(); ++k) {
        if (k > 0) {
            const ConeLight& light = full.lights[k - 1];
            sh::capProjection(M, light.direction.data(), std::cos(light.angularRadius), cap.data());
            double lum = luminanceOf(light.radiance.data());
            for (size_t j = 0; j < e.size(); ++j) e[j] -= lum * cap[j];
        }
        result.bands.push_back(bandEnergies(e, options.order, M));
        result.errors.push_back(weightedError(result.bands.back(), choice.bandWidth, energy));
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
