// Temporal coherence for a turning (or otherwise changing) environment: the decomposition of this frame, made
// consistent with the previous frame's lights. Hysteresis on K and on the elbow threshold, lights matched by
// direction into fixed slots, and a cross-fade of an entering or leaving light through the residual.
#include "envlight.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace prt::envlight {

namespace {

double angleBetween(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return std::acos(std::clamp(a[0] * b[0] + a[1] * b[1] + a[2] * b[2], -1.0, 1.0));
}

double powerOf(const ConeLight& l) {
    return (kLuminance[0] * l.radiance[0] + kLuminance[1] * l.radiance[1] + kLuminance[2] * l.radiance[2]) *
           coneSolidAngle(l.angularRadius);
}

} // namespace

Decomposition decomposeCoherent(const EnvironmentMap& env, const Options& options, const CoherenceOptions& coherence,
                                CoherenceState& state) {
    if (!(coherence.keepFraction > 0.0 && coherence.keepFraction <= 1.0))
        throw Error("", "keep fraction", "outside (0, 1]", kExitUsage);
    if (coherence.fadeFrames < 1) throw Error("", "fade frames", "must be >= 1", kExitUsage);
    if (coherence.spareLights < 0) throw Error("", "spare lights", "must be >= 0", kExitUsage);
    if (!(coherence.matchRadius > 0.0)) throw Error("", "match radius", "must be > 0", kExitUsage);
    if (state.lights.size() != state.weights.size() || state.lights.size() > size_t(options.maxLights))
        throw Error("", "coherence state", "lights and weights differ in size, or exceed K", kExitUsage);

    // The keep set: this frame's lights at the lower (keeping) threshold and K + spare, fitted together.
    Options inner = options;
    inner.maxLights = options.maxLights == 0 ? 0 : options.maxLights + coherence.spareLights;
    inner.minLights = 0;
    inner.elbowThreshold = options.elbowThreshold * coherence.keepFraction;
    Decomposition frame = decompose(env, inner);
    // The enter set: the lead lights the strict threshold and K keep.
    std::vector<double> powers;
    for (const ConeLight& l : frame.lights) powers.push_back(powerOf(l));
    const size_t enter = std::min(elbowCount(powers.data(), powers.size(), options.elbowThreshold),
                                  size_t(options.maxLights));

    // Match slots to this frame's lights by direction: the closest pairs first (ties by slot, then light index),
    // each slot and light at most once, only within the match radius.
    std::vector<std::tuple<double, size_t, size_t>> pairs;
    for (size_t s = 0; s < state.lights.size(); ++s)
        for (size_t k = 0; k < frame.lights.size(); ++k) {
            double angle = angleBetween(state.lights[s].direction, frame.lights[k].direction);
            if (angle <= coherence.matchRadius) pairs.emplace_back(angle, s, k);
        }
    std::sort(pairs.begin(), pairs.end());
    std::vector<int> slotMatch(state.lights.size(), -1), lightMatched(frame.lights.size(), 0);
    for (const auto& [angle, s, k] : pairs)
        if (slotMatch[s] < 0 && !lightMatched[k]) slotMatch[s] = int(k), lightMatched[k] = 1;

    // Matched slots follow their light and fade in towards full weight; unmatched slots keep their last light and
    // fade out; a slot whose weight reaches 0 is freed (the others keep their order).
    const double step = 1.0 / coherence.fadeFrames;
    CoherenceState next;
    for (size_t s = 0; s < state.lights.size(); ++s) {
        double weight = state.weights[s];
        ConeLight light = state.lights[s];
        if (slotMatch[s] >= 0) {
            light = frame.lights[size_t(slotMatch[s])];
            weight = std::min(1.0, weight + step);
        } else {
            weight -= step;
        }
        if (weight > 1e-12) {
            next.lights.push_back(light);
            next.weights.push_back(weight);
        }
    }
    // Unmatched lights of the enter set take free slots, strongest first, once they were in the enter set the
    // frame before too (pending; on the first frame at once, at full weight). The others wait as pending.
    for (size_t k = 0; k < enter; ++k) {
        if (lightMatched[k]) continue;
        bool waited = !state.started;
        for (const auto& p : state.pending)
            if (angleBetween(p, frame.lights[k].direction) <= coherence.matchRadius) waited = true;
        if (waited && next.lights.size() < size_t(options.maxLights)) {
            next.lights.push_back(frame.lights[k]);
            next.weights.push_back(state.started ? step : 1.0);
        } else {
            next.pending.push_back(frame.lights[k].direction);
        }
    }
    next.started = true;

    // The lights as emitted: each slot's light at its weight. The residual is the map's projection minus exactly
    // these lights, so a fading light's remainder lives in the residual and the total never jumps.
    Decomposition result = std::move(frame);
    std::vector<double> projection = result.residual, lit = lightsProjection(result.lights, options.order);
    for (size_t j = 0; j < projection.size(); ++j) projection[j] += lit[j];
    result.lights.clear();
    for (size_t s = 0; s < next.lights.size(); ++s) {
        ConeLight l = next.lights[s];
        for (double& r : l.radiance) r *= next.weights[s];
        result.lights.push_back(l);
    }
    result.weights = next.weights;
    std::vector<double> emitted = lightsProjection(result.lights, options.order);
    result.residual.assign(projection.size(), 0.0);
    for (size_t j = 0; j < projection.size(); ++j) result.residual[j] = projection[j] - emitted[j];
    result.projection = std::move(projection);
    state = std::move(next);
    if (int(result.lights.size()) < options.minLights)
        throw Error("", "lights", "found " + std::to_string(result.lights.size()) + " lights, fewer than the " +
                                      std::to_string(options.minLights) + " that --min-lights asks for");
    return result;
}

} // namespace prt::envlight
