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
#include <array>
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

// The subset's rows: pilot rows first, then the held-out ones, then the check set.
struct Rows {
    std::vector<uint32_t> all;
    size_t pilot = 0, heldOut = 0, check = 0;
};

// The reference at every subset row under every map: a first pass measures the noise, then paths are added until
// it is options.noiseFraction of the target (refused when even --max-reference-samples could not get it below
// 1 / kNoiseRefusalRatio of it). Fills result's reference fields.
std::vector<ReferenceRadiance> measureReference(const TriMesh& mesh, const std::vector<EnvironmentMap>& envs,
                                                const std::vector<std::string>& envNames, const Rows& rows,
                                                const Options& options, Result& result) {
    const double t0 = nowSeconds();
    const size_t n = rows.all.size();
    const double E = options.targetError;
    auto nameOf = [&](size_t m) { return m < envNames.size() ? envNames[m] : "map " + std::to_string(m); };
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
        reference.push_back(referenceVertexRadianceAt(mesh, envs[m], rows.all, ref));
        result.rays += reference.back().rays;
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
        for (size_t m = 0; m < envs.size(); ++m) {
            reference[m] = referenceVertexRadianceAt(mesh, envs[m], rows.all, ref);
            result.rays += reference[m].rays;
        }
    }
    result.referenceSamples = ref.samples;
    for (size_t m = 0; m < envs.size(); ++m) result.referenceNoise.push_back(relativeNoise(reference[m], 0, n));
    result.referenceSeconds = nowSeconds() - t0;
    char text[200];
    std::snprintf(text, sizeof text, "autoconfig: reference at %d paths on %zu pilot + %zu held-out + %zu check "
                  "vertices, largest relative noise %.4g, %.1f s", ref.samples, rows.pilot, rows.heldOut, rows.check,
                  *std::max_element(result.referenceNoise.begin(), result.referenceNoise.end()), result.referenceSeconds);
    logInfo(text);
    return reference;
}

// The pilot transfers at the largest order, one per (samples, bounces), at the subset's rows.
struct Pilots {
    int maxOrder = 0;
    std::vector<float> positions, normals, spawn; // the subset rows' [n][3]
    std::vector<int> samplesAxis, bouncesAxis, ordersAxis; // sorted, unique
    std::vector<std::vector<float>> rows;   // [samples][bounces] -> [n][maxOrder^2][3]
    std::vector<std::vector<float>> bounce; // the same for the bounces' part (empty without bounces)
    double hitFraction = 0.0;    // front-face hits per ray at the pilot rows (bounces gather there)
    double secondsPerCost = 0.0; // measured, for the report's seconds only
    uint64_t rays = 0;           // the pilot transfers cast
};

Pilots runPilots(const TriMesh& mesh, const Rows& subset, const Options& options) {
    Pilots pilots;
    const size_t n = subset.all.size();
    pilots.maxOrder = *std::max_element(options.orders.begin(), options.orders.end());
    const int maxOrder = pilots.maxOrder;
    pilots.positions.resize(n * 3), pilots.normals.resize(n * 3), pilots.spawn.resize(n * 3);
    std::vector<uint64_t> keys(subset.all.begin(), subset.all.end());
    const std::vector<float> meshSpawn = spawnNormals(mesh);
    for (size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) {
            const size_t from = size_t(subset.all[i]) * 3 + a;
            pilots.positions[i * 3 + a] = mesh.positions[from];
            pilots.normals[i * 3 + a] = mesh.normals[from];
            pilots.spawn[i * 3 + a] = meshSpawn[from];
        }
    Receivers receivers;
    receivers.positions = pilots.positions.data();
    receivers.normals = pilots.normals.data();
    receivers.spawnNormals = pilots.spawn.data();
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
    pilots.samplesAxis = options.samples, pilots.bouncesAxis = options.bounces, pilots.ordersAxis = options.orders;
    for (std::vector<int>* axis : {&pilots.samplesAxis, &pilots.bouncesAxis, &pilots.ordersAxis}) {
        std::sort(axis->begin(), axis->end());
        axis->erase(std::unique(axis->begin(), axis->end()), axis->end());
    }
    for (int s : pilots.samplesAxis)
        for (int b : pilots.bouncesAxis) {
            Transfer t = computeTransferAt(mesh, receivers, transferOptions(maxOrder, s, b));
            pilots.rays += t.stats.rays;
            if (b > 0 && s == pilots.samplesAxis.back()) pilots.hitFraction = double(t.stats.hits) / (double(n) * s);
            if (b == 0 && s == pilots.samplesAxis.back())
                pilots.secondsPerCost =
                    t.stats.directSeconds / (double(n) * s * (1.0 + kCoefficientCost * maxOrder * maxOrder));
            for (size_t i = 0; i < t.direct.size(); ++i) t.direct[i] = t.coefficients[i] - t.direct[i];
            pilots.bounce.push_back(std::move(t.direct));
            pilots.rows.push_back(std::move(t.coefficients));
        }
    return pilots;
}

// Error of a configuration on a range of the subset's rows, and (adaptive) the coefficients and bands its rows
// keep there.
struct Prediction {
    double error = 0.0;
    uint64_t coefficients = 0, bands = 0;
    int largestOrder = 0; // the most bands any of the rows keeps
};

// Predicts configurations from the pilots: relights the pilot rows as the configuration stores them (or through
// the hybrid's lights, extracted once per map, order and light count) against the reference.
struct Predictor {
    const TriMesh& mesh;
    const std::vector<EnvironmentMap>& envs;
    const Options& options;
    const Pilots& pilots;
    const std::vector<ReferenceRadiance>& reference;
    std::vector<std::vector<float>> lightings; // each map's SH at pilots.maxOrder

    // Extracted lights per (map, order, K), and their cone visibility at every subset row ([n][lights]).
    struct MapLights {
        HybridLighting lighting;
        std::vector<float> visibility;
    };
    std::map<std::array<int, 3>, MapLights> mapLights;
    uint64_t rays = 0; // the cone visibility cast

    const MapLights& lightsOf(size_t m, int order, int k);
    std::vector<float> hybridRadiance(const Config& c, size_t run, size_t m, size_t first, size_t count);
    // The error of c from pilot run `run` on rows [first, first + count): the largest over the maps.
    Prediction predict(const Config& c, size_t run, size_t first, size_t count);
};

const Predictor::MapLights& Predictor::lightsOf(size_t m, int order, int k) {
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
    const size_t n = pilots.positions.size() / 3;
    uint64_t cast = 0;
    lights.visibility = envlight::coneVisibility(mesh, pilots.positions.data(), pilots.normals.data(),
                                                 pilots.spawn.data(), n, d.lights, options.lightSamples, &cast);
    rays += cast;
    return mapLights.emplace(std::array<int, 3>{int(m), order, k}, std::move(lights)).first->second;
}

// The hybrid's radiance at rows [first, first + count) of run `run` under map m.
std::vector<float> Predictor::hybridRadiance(const Config& c, size_t run, size_t m, size_t first, size_t count) {
    const MapLights& lights = lightsOf(m, c.order, c.lights);
    const int maxOrder = pilots.maxOrder;
    const size_t stride = size_t(maxOrder) * maxOrder * 3;
    HybridModel model;
    model.total.vertexCount = uint32_t(count);
    model.total.order = c.order;
    model.total.transfer =
        storedRows(pilots.rows[run].data() + first * stride, count, maxOrder, c.order, adapt::Format::Float);
    if (!pilots.bounce[run].empty())
        model.bounce =
            storedRows(pilots.bounce[run].data() + first * stride, count, maxOrder, c.order, adapt::Format::Float);
    model.normals.assign(pilots.normals.begin() + first * 3, pilots.normals.begin() + (first + count) * 3);
    model.albedo.resize(count * 3);
    for (size_t i = 0; i < count; ++i)
        for (int a = 0; a < 3; ++a) model.albedo[i * 3 + a] = float(options.albedo[a]);
    std::vector<float> radiance(count * 3);
    relightHybrid(model, lights.lighting, lights.visibility.data() + first * lights.lighting.lights.size(), 0, count,
                  radiance.data());
    return radiance;
}

Prediction Predictor::predict(const Config& c, size_t run, size_t first, size_t count) {
    auto errorUnder = [&](size_t m, const std::vector<float>& radiance) {
        return noiseCorrectedError(radiance.data(), reference[m].radiance.data() + first * 3,
                                   reference[m].standardError.data() + first * 3, count);
    };
    Prediction p;
    if (c.lights > 0) {
        p.coefficients = uint64_t(count) * c.order * c.order, p.bands = uint64_t(count) * c.order;
        p.largestOrder = c.order;
        for (size_t m = 0; m < envs.size(); ++m) p.error = std::max(p.error, errorUnder(m, hybridRadiance(c, run, m, first, count)));
        return p;
    }
    const int maxOrder = pilots.maxOrder;
    const float* rowsHere = pilots.rows[run].data() + first * maxOrder * maxOrder * 3;
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
    for (uint8_t n : orders) p.coefficients += uint64_t(n) * n, p.bands += n, p.largestOrder = std::max<int>(p.largestOrder, n);
    for (size_t m = 0; m < envs.size(); ++m) {
        relight(stored.data(), count, c.order * c.order, lightings[m].data(), radiance.data());
        p.error = std::max(p.error, errorUnder(m, radiance));
    }
    return p;
}

// Every configuration of the search with its cost, bytes and pilot error, into result.candidates; rowsOf[i] is
// candidate i's pilot run. Hybrid candidates go beside each float one, adaptive ones beside each uniform one.
void enumerateCandidates(Predictor& predictor, size_t V, size_t np, const Options& options, Result& result,
                         std::vector<size_t>& rowsOf) {
    const Pilots& pilots = predictor.pilots;
    const std::vector<EnvironmentMap>& envs = predictor.envs;
    const double E = options.targetError;
    // Deterministic work counts, so the choice does not depend on the machine's load or the thread count.
    auto bakeCost = [&](const Config& c) {
        const double coefficients = double(c.order) * c.order;
        return double(V) * c.samples * (1.0 + kCoefficientCost * coefficients +
                                        c.bounces * pilots.hitFraction * kGatherCost * coefficients);
    };
    for (size_t si = 0; si < pilots.samplesAxis.size(); ++si)
        for (size_t bi = 0; bi < pilots.bouncesAxis.size(); ++bi)
            for (int order : pilots.ordersAxis)
                for (adapt::Format format : options.formats) {
                    const size_t run = si * pilots.bouncesAxis.size() + bi;
                    const int bounces = pilots.bouncesAxis[bi];
                    Candidate c;
                    c.config = {order, pilots.samplesAxis[si], bounces, format};
                    c.bakeCost = bakeCost(c.config);
                    c.bakeSeconds = c.bakeCost * pilots.secondsPerCost;
                    c.bundleBytes = bundleLayerBytes(V, order, format, bounces);
                    c.pilotError = predictor.predict(c.config, run, 0, np).error;
                    result.candidates.push_back(c);
                    rowsOf.push_back(run);
                    // The hybrid: float storage (the bounce layer stays), lights per map from `prt envlight`.
                    for (int k : options.lights) {
                        if (k <= 0 || format != adapt::Format::Float) continue;
                        Candidate h = c;
                        h.config.lights = k;
                        size_t found = 0;
                        for (size_t m = 0; m < envs.size(); ++m)
                            found += predictor.lightsOf(m, order, k).lighting.lights.size();
                        if (found == 0) continue; // no light in any map: plain SH
                        h.pilotError = predictor.predict(h.config, run, 0, np).error;
                        // What the lights cost besides the bake: each map's decomposition and the cone visibility
                        // `prt relight --lights` casts at every vertex for every light.
                        for (size_t m = 0; m < envs.size(); ++m) {
                            const double lights = double(predictor.lightsOf(m, order, k).lighting.lights.size());
                            h.bakeCost += lights * (double(envs[m].radiance.width) * envs[m].radiance.height *
                                                        kEnvlightTexelCost +
                                                    double(V) * options.lightSamples);
                        }
                        h.bakeSeconds = h.bakeCost * pilots.secondsPerCost;
                        // The transfer stage's float32 layers as they are: transfer, and with bounces its bounce
                        // part of the same size; plus each light's 7 floats.
                        h.bundleBytes =
                            bundleLayerBytes(V, order, adapt::Format::Float, 0) * (bounces > 0 ? 2 : 1) + 28 * found;
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
                        Prediction p = predictor.predict(a.config, run, 0, np);
                        a.pilotError = p.error;
                        a.bundleBytes = raggedLayerBytes(V, (p.coefficients * V + np / 2) / np,
                                                         (p.bands * V + np / 2) / np, format);
                        // Keeping every band is the uniform configuration; keeping none of band L is one from L - 1.
                        if (a.bundleBytes >= c.bundleBytes || p.largestOrder < order) continue;
                        result.candidates.push_back(a);
                        rowsOf.push_back(run);
                    }
                }
}

// The choice: the cheapest candidate (bake cost and bundle bytes, each over its best) under margin x target on the
// pilot rows that also holds on the held-out rows, then measured once on the check rows (reported, not acted on).
void chooseAndCheck(Predictor& predictor, const std::vector<size_t>& rowsOf, const Rows& rows, const Options& options,
                    Result& result) {
    const double E = options.targetError;
    const size_t np = rows.pilot, nh = rows.heldOut, nc = rows.check;
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
        c.heldOutError = predictor.predict(c.config, rowsOf[i], np, nh).error;
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
    result.candidates[chosen].checkError = predictor.predict(result.chosen.config, rowsOf[chosen], np + nh, nc).error;
    result.chosen.checkError = result.candidates[chosen].checkError;
    char text[320];
    std::snprintf(text, sizeof text, "autoconfig: final check on %zu unseen vertices: %.4g%s", nc,
                  result.chosen.checkError,
                  result.chosen.checkError <= E ? ""
                                                : ", OVER the target: the pilot and held-out sets were not "
                                                  "representative; raise --pilot-vertices");
    if (result.chosen.checkError <= E) logInfo(text);
    else logWarn(text);
}

} // namespace

Result autoconfigure(const TriMesh& mesh, const std::vector<EnvironmentMap>& envs,
                     const std::vector<std::string>& envNames, const Options& options) {
    const double start = nowSeconds();
    checkOptions(mesh, envs, options);
    Result result;
    splitVertices(mesh, options.pilotVertices, options.seed, result.pilot, result.heldOut, result.check);
    Rows rows;
    rows.all = result.pilot;
    rows.all.insert(rows.all.end(), result.heldOut.begin(), result.heldOut.end());
    rows.all.insert(rows.all.end(), result.check.begin(), result.check.end());
    rows.pilot = result.pilot.size(), rows.heldOut = result.heldOut.size(), rows.check = result.check.size();

    const std::vector<ReferenceRadiance> reference = measureReference(mesh, envs, envNames, rows, options, result);
    const double t0 = nowSeconds();
    const Pilots pilots = runPilots(mesh, rows, options);
    result.pilotTransferSeconds = nowSeconds() - t0;

    Predictor predictor{mesh, envs, options, pilots, reference, {}, {}, 0};
    for (const EnvironmentMap& env : envs)
        predictor.lightings.push_back(environmentLighting(env, pilots.maxOrder, nullptr, sh::Window::None));
    std::vector<size_t> rowsOf; // candidate -> pilot run
    enumerateCandidates(predictor, mesh.vertexCount(), rows.pilot, options, result, rowsOf);
    result.pareto = paretoFront(result.candidates);
    chooseAndCheck(predictor, rowsOf, rows, options, result);
    result.rays += pilots.rays + predictor.rays;
    result.seconds = nowSeconds() - start;
    return result;
}

} // namespace prt::autoconfig
