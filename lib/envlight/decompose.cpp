// The whole chain: smoothing, icosphere, detection SH, maxima, elbow, the bounded fit alternated with the residual
// projection, and the residual SH: the projection of what the lights do not explain, so energy is counted once.
#include "envlight.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace prt::envlight {

namespace {

constexpr double kDegree = M_PI / 180.0;
constexpr size_t kFitTexels = 6000; // at most this many texels per light fit

double luminanceOf(const double* rgb) { return kLuminance[0] * rgb[0] + kLuminance[1] * rgb[1] + kLuminance[2] * rgb[2]; }
double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

void checkOptions(const Options& options) {
    auto usage = [](const std::string& place, const std::string& problem) {
        return Error("", place, problem, kExitUsage);
    };
    if (options.order < 1 || options.order > sh::kMaxOrder)
        throw usage("--order", std::to_string(options.order) + " outside 1.." + std::to_string(sh::kMaxOrder));
    if (options.maxLights < 0) throw usage("--max-lights", "must be >= 0");
    if (options.minLights < 0) throw usage("--min-lights", "must be >= 0");
    if (options.minLights > options.maxLights)
        throw usage("--max-lights", std::to_string(options.maxLights) + " lights allowed but --min-lights asks for " +
                                        std::to_string(options.minLights));
    if (!(options.minRadius > 0.0 && options.minRadius <= options.maxRadius && options.maxRadius < M_PI / 2))
        throw usage("--max-radius", "need 0 < min radius <= max radius < 90 degrees");
    if (!(options.elbowThreshold >= 0.0 && options.elbowThreshold < 1.0)) throw usage("--elbow", "outside [0, 1)");
    if (!(options.fixedRadius > 0.0 && options.fixedRadius < M_PI / 2)) throw usage("--fixed-radius", "outside (0, 90) degrees");
    if (!(options.minContrast >= 0.0)) throw usage("--min-contrast", "must be >= 0");
    if (options.outerIterations < 1) throw usage("outer iterations", "must be >= 1");
}

// Value of RGB SH coefficients ([n][3], double) at direction d, using scratch for the basis.
void evaluateRgb(int order, const std::vector<double>& coefficients, const double* d, std::vector<double>& basis,
                 double out[3]) {
    sh::evaluate(order, d[0], d[1], d[2], basis.data());
    out[0] = out[1] = out[2] = 0.0;
    for (size_t j = 0; j < basis.size(); ++j)
        for (int c = 0; c < 3; ++c) out[c] += coefficients[j * 3 + c] * basis[j];
}

// Soft-edged coverage, as the fit models a cone (fit.cpp).
double cover(const ConeLight& light, const double* w, double edge) {
    const double* d = light.direction.data();
    double chord = std::sqrt((d[0] - w[0]) * (d[0] - w[0]) + (d[1] - w[1]) * (d[1] - w[1]) + (d[2] - w[2]) * (d[2] - w[2]));
    return 0.5 * std::erfc((chord - 2.0 * std::sin(0.5 * light.angularRadius)) / (std::sqrt(2.0) * edge));
}

// The detection SH P: the map's projection smoothed as S is and windowed against ringing.
std::vector<double> detectionProjection(const std::vector<double>& projection, const Options& options) {
    const int order = options.order;
    std::vector<double> factors = gaussianBandFactors(options.smoothingFwhm, order);
    std::vector<double> detection(projection.size());
    for (int l = 0; l < order; ++l)
        for (int j = l * l; j < (l + 1) * (l + 1); ++j)
            for (int c = 0; c < 3; ++c)
                detection[j * 3 + c] =
                    projection[j * 3 + c] * factors[l] * sh::windowWeight(options.detectionWindow, l, order);
    return detection;
}

// A local maximum of the smoothed luminance and how far it stands above the detection SH there.
struct Peak {
    uint32_t vertex;
    double residual;
};

// Detection: smoothed luminance S at the icosphere vertices against the detection SH P. Guarantees the maxima of S
// whose residual S - P (what P cannot represent) is positive and at least minContrast times the mean luminance,
// strongest first, at most 4 maxLights + 8 of them.
std::vector<Peak> detectPeaks(const Icosphere& sphere, const std::vector<double>& smoothed,
                              const std::vector<double>& detection, const Options& options, double meanLuminance) {
    std::vector<double> basis(sh::coefficientCount(options.order));
    std::vector<Peak> peaks;
    for (uint32_t v : localMaxima(sphere, smoothed)) {
        double p[3];
        evaluateRgb(options.order, detection, &sphere.vertices[v * 3], basis, p);
        double residual = smoothed[v] - luminanceOf(p);
        if (residual > 0.0 && residual >= options.minContrast * meanLuminance) peaks.push_back({v, residual});
    }
    std::stable_sort(peaks.begin(), peaks.end(), [](const Peak& a, const Peak& b) { return a.residual > b.residual; });
    peaks.resize(std::min(peaks.size(), size_t(4 * options.maxLights + 8)));
    return peaks;
}

// A candidate's first guess from the raw texels near candidate.direction: the half-maximum region of the residual
// E - P gives a radius (clamped to the options' range), a mean radiance and a power. Without options.refine, the
// thesis's light instead: fixed radius, radiance E - P at the centre texel (it over-brightens). Guarantees false,
// and the candidate unset, when no texel near it stands above the projection.
bool firstGuess(const Texels& texels, const std::vector<double>& projection, const std::vector<double>& detection,
                const Options& options, Candidate& candidate) {
    const int order = options.order;
    const double cosSearch = std::cos(options.maxRadius + 1.0 * kDegree), cosPeak = std::cos(options.smoothingFwhm);
    std::vector<double> basis(sh::coefficientCount(order));
    std::vector<size_t> near;
    std::vector<double> residualRgb;
    double peakResidual = 0.0, bestDot = -2.0;
    size_t centreTexel = 0;
    for (size_t i = 0; i < texels.count(); ++i) {
        const double* w = &texels.directions[i * 3];
        double cosine = dot3(w, candidate.direction.data());
        if (cosine < cosSearch) continue;
        double p[3];
        evaluateRgb(order, projection, w, basis, p);
        double r[3];
        for (int c = 0; c < 3; ++c) r[c] = texels.rgb[i * 3 + c] - p[c];
        near.push_back(i);
        residualRgb.insert(residualRgb.end(), r, r + 3);
        if (cosine >= cosPeak) peakResidual = std::max(peakResidual, luminanceOf(r));
        if (cosine > bestDot) bestDot = cosine, centreTexel = i;
    }
    double halfArea = 0.0, sum[3] = {0, 0, 0};
    for (size_t k = 0; k < near.size(); ++k)
        if (luminanceOf(&residualRgb[k * 3]) >= 0.5 * peakResidual) {
            double omega = texels.solidAngles[near[k]];
            halfArea += omega;
            for (int c = 0; c < 3; ++c) sum[c] += residualRgb[k * 3 + c] * omega;
        }
    if (!(peakResidual > 0.0) || !(halfArea > 0.0)) return false;
    double radius = std::acos(std::clamp(1.0 - halfArea / (2.0 * M_PI), -1.0, 1.0));
    candidate.initialRadius = std::clamp(radius, options.minRadius, options.maxRadius);
    for (int c = 0; c < 3; ++c) candidate.initialRadiance[c] = std::max(0.0, sum[c] / halfArea);
    candidate.power = luminanceOf(candidate.initialRadiance.data()) * halfArea;
    if (!options.refine) {
        double p[3];
        evaluateRgb(order, detection, candidate.direction.data(), basis, p);
        for (int c = 0; c < 3; ++c)
            candidate.initialRadiance[c] = std::max(0.0, double(texels.rgb[centreTexel * 3 + c]) - p[c]);
        candidate.initialRadius = options.fixedRadius;
        candidate.power = luminanceOf(candidate.initialRadiance.data()) * coneSolidAngle(options.fixedRadius);
    }
    return true;
}

// Non-maximum suppression: a flat-topped source has many maxima of nearly equal height on its plateau. Needs the
// candidates strongest first; guarantees the strongest of those within a source radius (plus the smoothing width)
// of each other, in the same order.
std::vector<Candidate> distinctCandidates(const std::vector<Candidate>& candidates, double smoothingFwhm) {
    std::vector<Candidate> distinct;
    for (const Candidate& c : candidates) {
        bool covered = false;
        for (const Candidate& kept : distinct)
            if (std::acos(std::clamp(dot3(c.direction.data(), kept.direction.data()), -1.0, 1.0)) <
                std::max(kept.initialRadius, c.initialRadius) + smoothingFwhm)
                covered = true;
        if (!covered) distinct.push_back(c);
    }
    return distinct;
}

// The texels light k is fitted to: those within `window` of it, each with the map minus the residual SH and the
// other lights' soft coverage. Large windows (a big soft source near a pole) are thinned to about kFitTexels
// texels, each standing for `stride` of them: every stride-th in texel order, so the fit stays deterministic.
// Also returns the texel nearest light k, whose size sets the fit's edge.
FitTexels fitTexelsOf(const Texels& texels, const std::vector<ConeLight>& lights, size_t k,
                      const std::vector<double>& residual, int order, double window, size_t& centre) {
    const ConeLight& light = lights[k];
    std::vector<double> basis(sh::coefficientCount(order));
    double best = -2.0;
    centre = 0;
    FitTexels fitTexels;
    for (size_t i = 0; i < texels.count(); ++i) {
        const double* w = &texels.directions[i * 3];
        double cosine = dot3(w, light.direction.data());
        if (cosine > best) best = cosine, centre = i;
        if (cosine < std::cos(window)) continue;
        double background[3];
        evaluateRgb(order, residual, w, basis, background);
        for (size_t j = 0; j < lights.size(); ++j)
            if (j != k) {
                double coverage = cover(lights[j], w, 0.3 * std::sqrt(texels.solidAngles[i]));
                for (int c = 0; c < 3; ++c) background[c] += lights[j].radiance[c] * coverage;
            }
        fitTexels.directions.insert(fitTexels.directions.end(), w, w + 3);
        fitTexels.solidAngles.push_back(texels.solidAngles[i]);
        for (int c = 0; c < 3; ++c) fitTexels.target.push_back(texels.rgb[i * 3 + c] - background[c]);
    }
    const size_t stride = (fitTexels.solidAngles.size() + kFitTexels - 1) / kFitTexels;
    if (stride <= 1) return fitTexels;
    FitTexels thinned;
    for (size_t i = 0; i < fitTexels.solidAngles.size(); i += stride) {
        thinned.directions.insert(thinned.directions.end(), &fitTexels.directions[i * 3], &fitTexels.directions[i * 3] + 3);
        thinned.solidAngles.push_back(fitTexels.solidAngles[i] * double(stride));
        thinned.target.insert(thinned.target.end(), &fitTexels.target[i * 3], &fitTexels.target[i * 3] + 3);
    }
    return thinned;
}

double lightPower(const ConeLight& light) {
    return luminanceOf(light.radiance.data()) * coneSolidAngle(light.angularRadius);
}

// The bounded fit alternated with the residual projection: each outer iteration projects what the current lights
// leave, then fits each light in turn against it and the other lights. Then lights the fit drove to nothing
// (below 1e-6 of the total power) and lights that converged onto a stronger one are dropped. Records the costs,
// iterations and drops in `fit`.
void refineLights(const Texels& texels, const std::vector<double>& projection, const Options& options,
                  const std::vector<double>& upperRadius, std::vector<ConeLight>& lights, FitReport& fit) {
    const int order = options.order;
    for (int iteration = 0; iteration < options.outerIterations; ++iteration) {
        std::vector<double> residual = projection, lit = lightsProjection(lights, order);
        for (size_t j = 0; j < residual.size(); ++j) residual[j] -= lit[j];
        fit.initialCost = fit.finalCost = 0.0;
        for (size_t k = 0; k < lights.size(); ++k) {
            size_t centre = 0;
            FitTexels fitTexels = fitTexelsOf(texels, lights, k, residual, order, upperRadius[k] + 1.0 * kDegree, centre);
            // Edge: a third of the texel size at the light.
            double edge = 0.3 * std::sqrt(texels.solidAngles[centre]);
            LightFit lightFit = fitLight(fitTexels, lights[k], options.minRadius, upperRadius[k], edge);
            lights[k] = lightFit.light;
            fit.initialCost += lightFit.initialCost;
            fit.finalCost += lightFit.finalCost;
            fit.ceresIterations += lightFit.iterations;
            fit.termination = lightFit.termination;
        }
    }
    double total = 0.0;
    for (const ConeLight& l : lights) total += lightPower(l);
    std::vector<size_t> rank(lights.size());
    std::iota(rank.begin(), rank.end(), 0);
    std::stable_sort(rank.begin(), rank.end(), [&](size_t a, size_t b) { return lightPower(lights[a]) > lightPower(lights[b]); });
    std::vector<ConeLight> kept;
    for (size_t k : rank) {
        const ConeLight& l = lights[k];
        bool duplicate = false;
        for (const ConeLight& other : kept)
            if (std::acos(std::clamp(dot3(l.direction.data(), other.direction.data()), -1.0, 1.0)) <
                l.angularRadius + other.angularRadius)
                duplicate = true;
        if (duplicate || !(lightPower(l) > 1e-6 * total)) {
            ++fit.droppedLights;
            continue;
        }
        kept.push_back(l);
    }
    lights.swap(kept);
}

} // namespace

std::vector<double> lightsProjection(const std::vector<ConeLight>& lights, int order) {
    std::vector<double> projection(size_t(sh::coefficientCount(order)) * 3, 0.0);
    for (const ConeLight& light : lights)
        sh::addCapRadiance(order, light.direction.data(), std::cos(light.angularRadius), light.radiance.data(),
                           projection.data());
    return projection;
}

Decomposition decompose(const EnvironmentMap& env, const Options& options) {
    checkOptions(options);
    const int order = options.order;
    Texels texels = environmentTexels(env, options.rotation);
    std::vector<double> projection = projectTexels(texels, order);

    Decomposition result;
    result.order = order;
    double power = 0.0;
    for (size_t i = 0; i < texels.count(); ++i) {
        double rgb[3] = {texels.rgb[i * 3], texels.rgb[i * 3 + 1], texels.rgb[i * 3 + 2]};
        power += luminanceOf(rgb) * texels.solidAngles[i];
    }
    if (!(power > 0.0))
        throw Error("", "radiance", "the environment is zero everywhere: there is no light to decompose");
    result.environmentPower = power;
    result.meanLuminance = power / (4.0 * M_PI);

    // Maxima of the smoothed luminance, ranked by what the SH cannot represent; each candidate's first guess.
    Icosphere sphere = icosphere(options.icosphereLevel);
    std::vector<double> smoothed = smoothLuminance(texels, sphere.vertices.data(), sphere.vertexCount(), options.smoothingFwhm);
    std::vector<double> detection = detectionProjection(projection, options);
    for (const Peak& peak : detectPeaks(sphere, smoothed, detection, options, result.meanLuminance)) {
        Candidate candidate;
        candidate.direction = refineMaximum(sphere, smoothed, peak.vertex);
        candidate.smoothedResidual = peak.residual;
        if (firstGuess(texels, projection, detection, options, candidate)) result.candidates.push_back(candidate);
    }
    std::stable_sort(result.candidates.begin(), result.candidates.end(),
                     [](const Candidate& a, const Candidate& b) { return a.power > b.power; });
    result.candidates = distinctCandidates(result.candidates, options.smoothingFwhm);

    // The elbow of the ranked powers says how many are lights.
    std::vector<double> powers;
    for (const Candidate& c : result.candidates) powers.push_back(c.power);
    result.elbow = elbowCount(powers.data(), powers.size(), options.elbowThreshold);
    const size_t lightCount = std::min(result.elbow, size_t(options.maxLights));
    std::vector<ConeLight> lights;
    std::vector<double> upperRadius;
    for (size_t k = 0; k < lightCount; ++k) {
        const Candidate& c = result.candidates[k];
        lights.push_back({c.direction, c.initialRadiance, c.initialRadius});
        upperRadius.push_back(std::min(options.maxRadius, std::max(3.0 * c.initialRadius, c.initialRadius + 2.0 * kDegree)));
    }
    if (options.refine && !lights.empty()) refineLights(texels, projection, options, upperRadius, lights, result.fit);
    std::stable_sort(lights.begin(), lights.end(), [](const ConeLight& a, const ConeLight& b) { return lightPower(a) > lightPower(b); });

    // The residual: the projection of what the lights do not explain, so energy is counted once.
    result.residual = projection;
    std::vector<double> lit = lightsProjection(lights, order);
    for (size_t j = 0; j < result.residual.size(); ++j) result.residual[j] -= lit[j];
    result.lights = std::move(lights);
    if (int(result.lights.size()) < options.minLights)
        throw Error("", "lights", "found " + std::to_string(result.lights.size()) + " lights, fewer than the " +
                                      std::to_string(options.minLights) + " that --min-lights asks for");
    return result;
}

} // namespace prt::envlight
