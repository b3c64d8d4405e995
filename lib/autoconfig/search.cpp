// The search: pilot reference and transfers on a vertex subset, every configuration's error predicted by relighting
// the subset, the Pareto front, the cheapest configuration under the target, its check on held-out vertices, and
// its error on a final check set that nothing is chosen by.
#include "autoconfig.h"

#include "core.h"
#include "envlight.h"
#include "raycast.h"
#include "reference.h"
#include "runtime.h"
#include "sh.h"
#include "transfer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>

namespace prt::autoconfig {

namespace {

std::string describe(const Config& c) {
    char text[200];
    std::snprintf(text, sizeof text, "order %d, %d samples, %d bounce%s, %s", c.order, c.samples, c.bounces,
                  c.bounces == 1 ? "" : "s", adapt::formatName(c.format));
    std::string s = text;
    if (c.adaptiveError > 0.0) {
        std::snprintf(text, sizeof text, ", adaptive to %.4g", c.adaptiveError);
        s += text;
    }
    if (c.lights > 0) s += ", up to " + std::to_string(c.lights) + " cone lights";
    return s;
}

// Relative noise of a reference: RMS standard error over RMS radiance, over `count` rows from `first`.
double relativeNoise(const ReferenceRadiance& r, size_t first, size_t count) {
    double noise = 0.0, signal = 0.0;
    for (size_t i = first * 3; i < (first + count) * 3; ++i) {
        noise += double(r.standardError[i]) * r.standardError[i];
        signal += double(r.radiance[i]) * r.radiance[i];
    }
    return signal > 0.0 ? std::sqrt(noise / signal) : INFINITY;
}

void checkOptions(const TriMesh& mesh, const std::vector<EnvironmentMap>& envs, const Options& o) {
    auto usage = [](const char* place, const std::string& problem) { return Error("", place, problem, kExitUsage); };
    if (!(o.targetError > 0.0) || !std::isfinite(o.targetError))
        throw usage("--target-error", "must be > 0 (a relative RMSE, e.g. 0.02 for 2%)");
    if (envs.empty()) throw usage("--env", "needs at least one environment map to measure the error under");
    if (mesh.normals.size() != mesh.positions.size())
        throw Error("", "mesh", "has no vertex normals (prt meshprep adds them)", kExitInput);
    if (o.orders.empty() || o.samples.empty() || o.bounces.empty() || o.formats.empty())
        throw usage("--orders", "every axis of the search needs at least one value");
    for (int order : o.orders)
        if (order < 1 || order > sh::kMaxOrder) throw usage("--orders", "each order must be in 1..32");
    for (int samples : o.samples)
        if (samples < 1 || samples > kMaxTransferSamples) throw usage("--samples", "each must be in 1..65536");
    for (int bounces : o.bounces)
        if (bounces < 0 || bounces > 64) throw usage("--bounces", "each must be in 0..64");
    for (adapt::Format format : o.formats) bundleLayerBytes(1, 1, format, 0); // refuses cpca
    for (int lights : o.lights)
        if (lights < 0 || lights > 64) throw usage("--lights", "each must be in 0..64");
    if (o.lightSamples < 1 || o.lightSamples > 65536) throw usage("--light-samples", "must be in 1..65536");
    if (o.referenceBounces < 0) throw usage("--reference-bounces", "must be >= 0");
    if (o.referenceMinSamples < 2 || o.referenceMaxSamples < o.referenceMinSamples)
        throw usage("--max-reference-samples", "needs 2 <= first pass <= maximum");
    if (!(o.margin > 0.0 && o.margin <= 1.0)) throw usage("--margin", "must be in (0, 1]");
    if (o.pilotVertices < 1) throw usage("--pilot-vertices", "must be >= 1");
    for (double a : o.albedo)
        if (!(a >= 0.0 && a <= 1.0)) throw usage("--albedo", "each channel must be in [0, 1]");
}

// Pareto front of (bake cost, bytes, pilot error): indices of the candidates no other is at least as good on all
// three and better on one.
std::vector<size_t> paretoFront(const std::vector<Candidate>& c) {
    std::vector<size_t> front;
    for (size_t i = 0; i < c.size(); ++i) {
        bool dominated = false;
        for (size_t j = 0; j < c.size() && !dominated; ++j) {
            if (j == i) continue;
            bool noWorse = c[j].bakeCost <= c[i].bakeCost && c[j].bundleBytes <= c[i].bundleBytes &&
                           c[j].pilotError <= c[i].pilotError;
            bool better = c[j].bakeCost < c[i].bakeCost || c[j].bundleBytes < c[i].bundleBytes ||
                          c[j].pilotError < c[i].pilotError;
            dominated = noWorse && better;
        }
        if (!dominated) front.push_back(i);
    }
    std::sort(front.begin(), front.end(), [&](size_t a, size_t b) {
        return c[a].bakeCost != c[b].bakeCost ? c[a].bakeCost < c[b].bakeCost : a < b;
    });
    return front;
}

} // namespace

Result autoconfigure(const TriMesh& mesh, const std::vector<EnvironmentMap>& envs,
                     const std::vector<std::string>& envNames, const Options& options) {
    const double start = nowSeconds();
    checkOptions(mesh, envs, options);
    Result result;
    splitVertices(mesh, options.pilotVertices, options.seed, result.pilot, result.heldOut, result.check);
    std::vector<uint32_t> rows = result.pilot; // pilot rows first, then the held-out ones, then the check set
    rows.insert(rows.end(), result.heldOut.begin(), result.heldOut.end());
    rows.insert(rows.end(), result.check.begin(), result.check.end());
    const size_t n = rows.size(), np = result.pilot.size(), nh = result.heldOut.size(), nc = result.check.size();
    const size_t V = mesh.vertexCount();
    const double E = options.targetError;
    auto nameOf = [&](size_t m) { return m < envNames.size() ? envNames[m] : "map " + std::to_string(m); };

    // ---- reference: a first pass measures the noise; paths are added until it is a fraction of the target ----
    double t0 = nowSeconds();
    ReferenceOptions ref;
    ref.bounces = options.referenceBounces;
    ref.seed = options.seed;
    ref.albedo = std::array<float, 3>{float(options.albedo[0]), float(options.albedo[1]), float(options.albedo[2])};
    ref.threads = options.threads;
    ref.samples = options.referenceMinSamples;
    std::vector<ReferenceRadiance> reference;
    double worstNoise = 0.0;
    size_t worstMap = 0;
    for (size_t m = 0; m < envs.size(); ++m) {
        reference.push_back(referenceVertexRadianceAt(mesh, envs[m], rows, ref));
        double noise = relativeNoise(reference[m], 0, n);
        if (noise > worstNoise) worstNoise = noise, worstMap = m;
    }
    // Noise falls as 1 / sqrt(paths).
    const double noiseAtMax = worstNoise * std::sqrt(double(ref.samples) / options.referenceMaxSamples);
    if (E < kNoiseRefusalRatio * noiseAtMax) {
        double needed = ref.samples * std::pow(kNoiseRefusalRatio * worstNoise / E, 2.0);
        char text[480];
        std::snprintf(text, sizeof text,
                      "%.4g is below %.0fx the reference's own noise: under %s its relative noise (RMS standard "
                      "error / RMS radiance) is %.4g at %d paths per vertex and would be %.4g at the %d paths "
                      "--max-reference-samples allows, so no configuration's error could be told from the noise; "
                      "raise the target or --max-reference-samples to at least %.0f",
                      E, kNoiseRefusalRatio, nameOf(worstMap).c_str(), worstNoise, ref.samples, noiseAtMax,
                      options.referenceMaxSamples, std::ceil(needed));
        throw Error("", "--target-error", text, kExitUsage);
    }
    const double wanted = ref.samples * std::pow(worstNoise / (options.noiseFraction * E), 2.0);
    const int samples = int(std::clamp(std::ceil(wanted), double(ref.samples), double(options.referenceMaxSamples)));
    if (samples > ref.samples) {
        ref.samples = samples;
        for (size_t m = 0; m < envs.size(); ++m) reference[m] = referenceVertexRadianceAt(mesh, envs[m], rows, ref);
    }
    result.referenceSamples = ref.samples;
    for (size_t m = 0; m < envs.size(); ++m) result.referenceNoise.push_back(relativeNoise(reference[m], 0, n));
    result.referenceSeconds = nowSeconds() - t0;
    {
        char text[200];
        std::snprintf(text, sizeof text, "autoconfig: reference at %d paths on %zu pilot + %zu held-out + %zu check "
                      "vertices, largest relative noise %.4g, %.1f s", ref.samples, np, nh, nc,
                      *std::max_element(result.referenceNoise.begin(), result.referenceNoise.end()),
                      result.referenceSeconds);
        logInfo(text);
    }

    // ---- pilot transfers at the largest order, one per (samples, bounces), at the subset's vertices ----------
    t0 = nowSeconds();
    const int maxOrder = *std::max_element(options.orders.begin(), options.orders.end());
    std::vector<float> positions(n * 3), normals(n * 3), spawn(n * 3);
    std::vector<uint64_t> keys(rows.begin(), rows.end());
    const std::vector<float> meshSpawn = spawnNormals(mesh);
    for (size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) {
            positions[i * 3 + a] = mesh.positions[size_t(rows[i]) * 3 + a];
            normals[i * 3 + a] = mesh.normals[size_t(rows[i]) * 3 + a];
            spawn[i * 3 + a] = meshSpawn[size_t(rows[i]) * 3 + a];
        }
    Receivers receivers;
    receivers.positions = positions.data();
    receivers.normals = normals.data();
    receivers.spawnNormals = spawn.data();
    receivers.keys = keys.data();
    receivers.count = n;
    auto transferOptions = [&](int order, int samples, int bounces) {
        TransferOptions t;
        t.mode = bounces == 0 ? TransferMode::Shadowed : TransferMode::Interreflected;
        t.order = order;
        t.samples = samples;
        t.bounces = bounces;
        t.albedo = {float(options.albedo[0]), float(options.albedo[1]), float(options.albedo[2])};
        t.albedoOverride = true;
        t.seed = options.seed;
        t.threads = options.threads;
        t.progress = false;
        t.keepDirect = bounces > 0; // the hybrid's lights bounce through total - direct
        return t;
    };
    std::vector<int> samplesAxis = options.samples, bouncesAxis = options.bounces, ordersAxis = options.orders;
    for (std::vector<int>* axis : {&samplesAxis, &bouncesAxis, &ordersAxis}) {
        std::sort(axis->begin(), axis->end());
        axis->erase(std::unique(axis->begin(), axis->end()), axis->end());
    }
    std::vector<std::vector<float>> pilotRows; // [samples][bounces] -> [n][maxOrder^2][3]
    std::vector<std::vector<float>> pilotBounce; // the same for the bounces' part (empty without bounces)
    double hitFraction = 0.0;                  // front-face hits per ray at the pilot vertices (bounces gather there)
    double secondsPerCost = 0.0;               // measured, for the report's seconds only
    for (int s : samplesAxis)
        for (int b : bouncesAxis) {
            Transfer t = computeTransferAt(mesh, receivers, transferOptions(maxOrder, s, b));
            if (b > 0 && s == samplesAxis.back()) hitFraction = double(t.stats.hits) / (double(n) * s);
            if (b == 0 && s == samplesAxis.back())
                secondsPerCost = t.stats.directSeconds / (double(n) * s * (1.0 + kCoefficientCost * maxOrder * maxOrder));
            for (size_t i = 0; i < t.direct.size(); ++i) t.direct[i] = t.coefficients[i] - t.direct[i];
            pilotBounce.push_back(std::move(t.direct));
            pilotRows.push_back(std::move(t.coefficients));
        }
    result.pilotTransferSeconds = nowSeconds() - t0;
    // Deterministic work counts, so the choice does not depend on the machine's load or the thread count.
    auto bakeCost = [&](const Config& c) {
        const double coefficients = double(c.order) * c.order;
        return double(V) * c.samples * (1.0 + kCoefficientCost * coefficients +
                                        c.bounces * hitFraction * kGatherCost * coefficients);
    };

    // ---- every configuration's error on the pilot vertices --------------------------------------------------
    std::vector<std::vector<float>> lightings;
    for (const EnvironmentMap& env : envs) lightings.push_back(environmentLighting(env, maxOrder, nullptr, sh::Window::None));
    // Error of a configuration on rows [first, first + count) of the pilot run, and (adaptive) the coefficients and
    // bands its vertices keep there.
    struct Prediction {
        double error = 0.0;
        uint64_t coefficients = 0, bands = 0;
        int largestOrder = 0; // the most bands any of the rows keeps
    };
    // Extracted lights per (map, order, K), and their cone visibility at every subset row ([n][lights]).
    struct MapLights {
        HybridLighting lighting;
        std::vector<float> visibility;
    };
    std::map<std::array<int, 3>, MapLights> mapLights;
    auto lightsOf = [&](size_t m, int order, int k) -> const MapLights& {
        auto found = mapLights.find({int(m), order, k});
        if (found != mapLights.end()) return found->second;
        envlight::Options o;
        o.order = order;
        o.maxLights = k;
        envlight::Decomposition d = envlight::decompose(envs[m], o);
        MapLights lights;
        lights.lighting.order = order;
        lights.lighting.residual.assign(d.residual.begin(), d.residual.end());
        lights.lighting.bounceWindow = sh::Window::Hann; // `prt relight`'s default
        for (const envlight::ConeLight& l : d.lights)
            lights.lighting.lights.push_back({{float(l.direction[0]), float(l.direction[1]), float(l.direction[2])},
                                              {float(l.radiance[0]), float(l.radiance[1]), float(l.radiance[2])},
                                              float(l.angularRadius)});
        lights.visibility = envlight::coneVisibility(mesh, positions.data(), normals.data(), spawn.data(), n, d.lights,
                                                     options.lightSamples);
        return mapLights.emplace(std::array<int, 3>{int(m), order, k}, std::move(lights)).first->second;
    };
    // The hybrid's radiance at rows [first, first + count) of run `run` under map m.
    auto hybridRadiance = [&](const Config& c, size_t run, size_t m, size_t first, size_t count) {
        const MapLights& lights = lightsOf(m, c.order, c.lights);
        const size_t stride = size_t(maxOrder) * maxOrder * 3;
        HybridModel model;
        model.total.vertexCount = uint32_t(count);
        model.total.order = c.order;
        model.total.transfer = storedRows(pilotRows[run].data() + first * stride, count, maxOrder, c.order,
                                          adapt::Format::Float);
        if (!pilotBounce[run].empty())
            model.bounce = storedRows(pilotBounce[run].data() + first * stride, count, maxOrder, c.order,
                                      adapt::Format::Float);
        model.normals.assign(normals.begin() + first * 3, normals.begin() + (first + count) * 3);
        model.albedo.resize(count * 3);
        for (size_t i = 0; i < count; ++i)
            for (int a = 0; a < 3; ++a) model.albedo[i * 3 + a] = float(options.albedo[a]);
        std::vector<float> radiance(count * 3);
        relightHybrid(model, lights.lighting, lights.visibility.data() + first * lights.lighting.lights.size(), 0,
                      count, radiance.data());
        return radiance;
    };
    auto predict = [&](const Config& c, size_t run, size_t first, size_t count) {
        if (c.lights > 0) {
            Prediction p;
            p.coefficients = uint64_t(count) * c.order * c.order, p.bands = uint64_t(count) * c.order;
            p.largestOrder = c.order;
            for (size_t m = 0; m < envs.size(); ++m) {
                std::vector<float> radiance = hybridRadiance(c, run, m, first, count);
                p.error = std::max(p.error, noiseCorrectedError(radiance.data(), reference[m].radiance.data() + first * 3,
                                                                reference[m].standardError.data() + first * 3, count));
            }
            return p;
        }
        const std::vector<float>& rowsAtMax = pilotRows[run];
        const float* rowsHere = rowsAtMax.data() + first * maxOrder * maxOrder * 3;
        std::vector<uint8_t> orders(count, uint8_t(c.order));
        if (c.adaptiveError > 0.0) { // prt adapt's rms budget over these rows, without grading
            std::vector<float> dense = storedRows(rowsHere, count, maxOrder, c.order, adapt::Format::Float);
            std::vector<std::vector<float>> prior;
            for (const std::vector<float>& lighting : lightings)
                prior.emplace_back(lighting.begin(), lighting.begin() + c.order * c.order * 3);
            orders = adapt::budgetOrders(
                adapt::truncationErrorSquared(dense.data(), count, c.order, prior, adapt::Prior::Maps), prior.size(),
                count, c.order, c.adaptiveError);
        }
        std::vector<float> stored = storedRows(rowsHere, count, maxOrder, c.order, c.format, &orders);
        std::vector<float> radiance(count * 3);
        Prediction p;
        for (uint8_t n : orders) p.coefficients += uint64_t(n) * n, p.bands += n, p.largestOrder = std::max<int>(p.largestOrder, n);
        for (size_t m = 0; m < envs.size(); ++m) {
            relight(stored.data(), count, c.order * c.order, lightings[m].data(), radiance.data());
            p.error = std::max(p.error, noiseCorrectedError(radiance.data(), reference[m].radiance.data() + first * 3,
                                                            reference[m].standardError.data() + first * 3, count));
        }
        return p;
    };
    std::vector<size_t> rowsOf; // candidate -> pilotRows index
    for (size_t si = 0; si < samplesAxis.size(); ++si)
        for (size_t bi = 0; bi < bouncesAxis.size(); ++bi)
            for (int order : ordersAxis)
                for (adapt::Format format : options.formats) {
                    const size_t run = si * bouncesAxis.size() + bi;
                    Candidate c;
                    c.config = {order, samplesAxis[si], bouncesAxis[bi], format};
                    c.bakeCost = bakeCost(c.config);
                    c.bakeSeconds = c.bakeCost * secondsPerCost;
                    c.bundleBytes = bundleLayerBytes(V, order, format, bouncesAxis[bi]);
                    c.pilotError = predict(c.config, run, 0, np).error;
                    result.candidates.push_back(c);
                    rowsOf.push_back(run);
                    // The hybrid: float storage (the bounce layer stays), lights per map from `prt envlight`.
                    for (int k : options.lights) {
                        if (k <= 0 || format != adapt::Format::Float) continue;
                        Candidate h = c;
                        h.config.lights = k;
                        size_t found = 0;
                        for (size_t m = 0; m < envs.size(); ++m) found += lightsOf(m, order, k).lighting.lights.size();
                        if (found == 0) continue; // no light in any map: plain SH
                        h.pilotError = predict(h.config, run, 0, np).error;
                        // What the lights cost besides the bake: each map's decomposition and the cone visibility
                        // `prt relight --lights` casts at every vertex for every light.
                        for (size_t m = 0; m < envs.size(); ++m) {
                            const double lights = double(lightsOf(m, order, k).lighting.lights.size());
                            h.bakeCost += lights * (double(envs[m].radiance.width) * envs[m].radiance.height * kEnvlightTexelCost +
                                                    double(V) * options.lightSamples);
                        }
                        h.bakeSeconds = h.bakeCost * secondsPerCost;
                        // The transfer stage's float32 layers as they are: transfer, and with bounces its bounce
                        // part of the same size; plus each light's 7 floats.
                        h.bundleBytes = bundleLayerBytes(V, order, adapt::Format::Float, 0) * (bouncesAxis[bi] > 0 ? 2 : 1) +
                                        28 * found;
                        result.candidates.push_back(h);
                        rowsOf.push_back(run);
                    }
                    // Adaptive order spends what is left of the target: truncation adds about in quadrature, so
                    // budgets up to sqrt((margin E)^2 - e^2). The adapt stage takes one map as its prior.
                    const double room = std::pow(options.margin * E, 2.0) - c.pilotError * c.pilotError;
                    if (envs.size() != 1 || order < 2 || !(room > 0.0)) continue;
                    for (double fraction : {1.0, 0.85, 0.7, 0.5}) {
                        Candidate a = c;
                        a.config.adaptiveError = fraction * std::sqrt(room);
                        Prediction p = predict(a.config, run, 0, np);
                        a.pilotError = p.error;
                        a.bundleBytes = raggedLayerBytes(V, (p.coefficients * V + np / 2) / np, (p.bands * V + np / 2) / np,
                                                         format);
                        // Keeping every band is the uniform configuration; keeping none of band L is one from L - 1.
                        if (a.bundleBytes >= c.bundleBytes || p.largestOrder < order) continue;
                        result.candidates.push_back(a);
                        rowsOf.push_back(run);
                    }
                }
    result.pareto = paretoFront(result.candidates);

    // ---- the choice: cheapest (bake time and bundle bytes, each over its best) under margin x target ---------
    std::vector<size_t> feasible;
    for (size_t i = 0; i < result.candidates.size(); ++i)
        if (result.candidates[i].pilotError <= options.margin * E) feasible.push_back(i);
    if (feasible.empty()) {
        size_t best = 0;
        for (size_t i = 1; i < result.candidates.size(); ++i)
            if (result.candidates[i].pilotError < result.candidates[best].pilotError) best = i;
        throw Error("", "--target-error",
                    "no configuration in the search reaches " + std::to_string(E) + " (with the margin " +
                    std::to_string(options.margin) + "): the best, " + describe(result.candidates[best].config) +
                    ", has a predicted error of " + std::to_string(result.candidates[best].pilotError) +
                    " on the pilot vertices; raise the target or widen --orders / --samples / --bounces",
                    kExitUsage);
    }
    double costMin = INFINITY, bytesMin = INFINITY;
    for (size_t i : feasible) {
        costMin = std::min(costMin, result.candidates[i].bakeCost);
        bytesMin = std::min(bytesMin, double(result.candidates[i].bundleBytes));
    }
    auto score = [&](size_t i) {
        return result.candidates[i].bakeCost / costMin + double(result.candidates[i].bundleBytes) / bytesMin;
    };
    std::stable_sort(feasible.begin(), feasible.end(), [&](size_t a, size_t b) {
        double sa = score(a), sb = score(b);
        if (sa != sb) return sa < sb;
        return result.candidates[a].pilotError < result.candidates[b].pilotError;
    });
    bool verified = false;
    for (size_t i : feasible) {
        Candidate& c = result.candidates[i];
        c.heldOutError = predict(c.config, rowsOf[i], np, nh).error;
        result.tried.push_back(i);
        char text[240];
        std::snprintf(text, sizeof text, "autoconfig: %s: predicted %.4g, held out %.4g%s", describe(c.config).c_str(),
                      c.pilotError, c.heldOutError, c.heldOutError <= E ? "" : ": over the target, next");
        logInfo(text);
        if (c.heldOutError <= E) {
            result.chosen = c;
            verified = true;
            break;
        }
    }
    if (!verified)
        throw Error("", "--target-error",
                    "every configuration predicted under " + std::to_string(E) +
                    " failed the held-out check (the pilot vertices are not representative: raise --pilot-vertices)",
                    kExitUsage);
    // The final check: vertices no choice looked at, measured once. Over the target it is reported, not acted on.
    size_t chosen = result.tried.back();
    result.candidates[chosen].checkError = predict(result.chosen.config, rowsOf[chosen], np + nh, nc).error;
    result.chosen.checkError = result.candidates[chosen].checkError;
    {
        char text[320];
        std::snprintf(text, sizeof text, "autoconfig: final check on %zu unseen vertices: %.4g%s", nc,
                      result.chosen.checkError,
                      result.chosen.checkError <= E ? ""
                                                    : ", OVER the target: the pilot and held-out sets were not "
                                                      "representative; raise --pilot-vertices");
        if (result.chosen.checkError <= E) logInfo(text);
        else logWarn(text);
    }
    result.seconds = nowSeconds() - start;
    return result;
}

} // namespace prt::autoconfig
