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

std::vector<int> residualOrdersTried(const Options& options, const ChoiceOptions& choice) {
    std::vector<int> orders = choice.residualOrders;
    if (orders.empty()) orders = {options.order, choice.plainOrder};
    std::sort(orders.begin(), orders.end());
    orders.erase(std::unique(orders.begin(), orders.end()), orders.end());
    return orders;
}

Decomposition decomposeChoosingLights(const EnvironmentMap& env, const Options& options, const ChoiceOptions& choice,
                                      LightChoice* report) {
    const std::vector<int> orders = residualOrdersTried(options, choice);
    const int M = choice.errorOrder;
    if (choice.plainOrder < 1 || choice.plainOrder > sh::kMaxOrder || M <= choice.plainOrder || M > sh::kMaxOrder ||
        orders.front() < 1 || orders.back() >= M)
        throw Error("", "light choice", "need plain order and residual orders >= 1 and below the error order <= " +
                                            std::to_string(sh::kMaxOrder), kExitUsage);
    if (!(choice.margin > 0.0 && choice.margin <= 1.0)) throw Error("", "light choice", "margin outside (0, 1]", kExitUsage);
    LightChoice result;

    // The map's luminance: per texel, its energy, and its projection onto errorOrder bands.
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

    // Per residual order L: decompose at L (the fit depends on the residual it shares the map with), then score the
    // hybrid with the first k lights (by power): e = P(E) - P(lights), its bands from L up.
    std::vector<Decomposition> full(orders.size());
    std::vector<std::vector<std::vector<double>>> bandsByOrder(orders.size());
    size_t bestOrder = 0, bestK = 0;
    double bestError = 0.0;
    std::vector<double> cap(size_t(M) * M);
    for (size_t o = 0; o < orders.size(); ++o) {
        Options at = options;
        at.order = orders[o];
        full[o] = decompose(env, at); // up to options.maxLights lights, as the elbow keeps them
        std::vector<double> e = projection, errors;
        for (size_t k = 0; k <= full[o].lights.size(); ++k) {
            if (k > 0) {
                const ConeLight& light = full[o].lights[k - 1];
                sh::capProjection(M, light.direction.data(), std::cos(light.angularRadius), cap.data());
                double lum = luminanceOf(light.radiance.data());
                for (size_t j = 0; j < e.size(); ++j) e[j] -= lum * cap[j];
            }
            bandsByOrder[o].push_back(bandEnergies(e, orders[o], M));
            errors.push_back(weightedError(bandsByOrder[o].back(), choice.bandWidth, energy));
            // The least error with at least one light; ties keep the lower order and the fewer lights.
            if (k > 0 && (bestK == 0 || errors.back() < bestError)) bestOrder = o, bestK = k, bestError = errors.back();
        }
        result.orders.push_back(orders[o]);
        result.errorsByOrder.push_back(std::move(errors));
    }
    result.plainSh = bestK == 0 || !(bestError < choice.margin * result.plainError);
    result.order = result.plainSh ? choice.plainOrder : orders[bestOrder];
    result.lights = result.plainSh ? 0 : int(bestK);
    // The k = 0 .. found errors and bands of the order the choice rests on (the best hybrid's, also when declined).
    result.errors = result.errorsByOrder[bestOrder];
    result.bands = bandsByOrder[bestOrder];
    char line[300];
    if (result.plainSh) {
        if (bestK == 0)
            std::snprintf(line, sizeof line, "lights do not pay: no light found at residual orders %d..%d; use plain "
                          "order-%d SH", orders.front(), orders.back(), choice.plainOrder);
        else
            std::snprintf(line, sizeof line,
                          "lights do not pay: the best hybrid (order %d, %zu lights) leaves %.4g of the map's weighted "
                          "error against %.4g for plain order-%d SH; use plain SH",
                          orders[bestOrder], bestK, bestError, result.plainError, choice.plainOrder);
    } else {
        std::snprintf(line, sizeof line,
                      "%zu lights: the hybrid (order %d) leaves %.4g of the map's weighted error against %.4g for "
                      "plain order-%d SH",
                      bestK, orders[bestOrder], bestError, result.plainError, choice.plainOrder);
    }
    result.reason = line;

    // The decomposition with the chosen lights at the chosen order, refitted together (the fit of k lights depends
    // on which others are present), or none: then the residual is the plain projection at plainOrder.
    Decomposition chosen;
    if (!result.plainSh && result.lights == int(full[bestOrder].lights.size())) {
        chosen = std::move(full[bestOrder]);
    } else {
        Options again = options;
        again.order = result.order;
        again.maxLights = result.lights;
        again.minLights = std::min(again.minLights, result.lights);
        chosen = decompose(env, again);
    }
    if (report) *report = result;
    return chosen;
}

} // namespace prt::envlight
