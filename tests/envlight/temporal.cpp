// Temporal stability of the hybrid under a turning environment, run by scripts/envlight_figures.py (not a ctest
// test): the map turns about +Y in `step`-degree steps; each frame is decomposed afresh (envlight::decompose with
// the rotation, so detection, elbow and fit all see the turned map) and relit, hybrid and plain order-L SH.
//   envlight_temporal BUNDLE ENV ORDER MAX_LIGHTS FRAMES STEP_DEGREES [LIGHT_SAMPLES] [coherent|fresh]
// `coherent` decomposes through envlight::decomposeCoherent (hysteresis, matched slots, cross-fades), carrying its
// state from frame to frame; `fresh` (the default) decomposes each frame afresh.
// Prints one JSON object: light counts per frame, the largest light-direction jump between frames (raw, and
// against the light carried along by the turn), the number of light-count changes, and the largest frame-to-frame
// change of relit radiance (RMS over vertices and max over vertices, over the mean radiance) for both methods.
#include "envlight.h"
#include "raycast.h"
#include "runtime.h"

#include "core.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <cstdio>
#include <cstdlib>
#include <iostream>

namespace {

double angleDegrees(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI;
}

struct Change {
    double rms = 0.0, max = 0.0;
};

Change change(const std::vector<float>& a, const std::vector<float>& b, double meanRadiance) {
    double sum = 0.0, largest = 0.0;
    for (size_t v = 0; v < a.size() / 3; ++v) {
        double d = 0.0;
        for (int c = 0; c < 3; ++c) d += prt::envlight::kLuminance[c] * (a[v * 3 + c] - b[v * 3 + c]);
        sum += d * d;
        largest = std::max(largest, std::abs(d));
    }
    return {std::sqrt(sum / double(a.size() / 3)) / meanRadiance, largest / meanRadiance};
}

} // namespace

int main(int argc, char** argv) {
    if (argc < 7) {
        std::fprintf(stderr, "usage: %s BUNDLE ENV ORDER MAX_LIGHTS FRAMES STEP_DEGREES [LIGHT_SAMPLES] [coherent|fresh]\n", argv[0]);
        return 2;
    }
    try {
        prt::setLogOptions({true, false});
        prt::Bundle bundle = prt::readBundle(argv[1]);
        prt::TriMesh mesh = bundle.mesh;
        prt::HybridModel model = prt::hybridModel(std::move(bundle), argv[1]);
        prt::EnvironmentMap env = prt::readEnvironmentMap(argv[2]);
        prt::envlight::Options options;
        options.order = std::atoi(argv[3]);
        options.maxLights = std::atoi(argv[4]);
        const int frames = std::atoi(argv[5]);
        const double step = std::atof(argv[6]);
        const int samples = argc > 7 ? std::atoi(argv[7]) : 64;
        const std::string mode = argc > 8 ? argv[8] : "fresh";
        if (mode != "coherent" && mode != "fresh") throw prt::Error("", "mode", "must be coherent or fresh");
        prt::envlight::CoherenceState state;
        prt::envlight::CoherenceOptions coherence;
        nlohmann::json hybridSeries = nlohmann::json::array(), plainSeries = nlohmann::json::array();
        if (options.order != model.total.order) throw prt::Error(argv[1], "order", "differs from ORDER");
        const size_t rows = model.total.vertexCount;
        std::vector<float> projection = prt::sh::projectEnvironment(env, options.order);

        nlohmann::json counts = nlohmann::json::array();
        double largestJump = 0.0, largestCarriedJump = 0.0, seconds = 0.0;
        int countChanges = 0;
        Change hybridChange, plainChange;
        std::vector<prt::envlight::ConeLight> previousLights;
        std::vector<float> previousHybrid, previousPlain;
        double meanRadiance = 0.0;
        for (int frame = 0; frame < frames; ++frame) {
            double R[9], stepR[9];
            prt::sh::rotationY(frame * step, R);
            prt::sh::rotationY(step, stepR);
            options.rotation = R;
            double start = prt::nowSeconds();
            prt::envlight::Decomposition d = mode == "coherent"
                                                 ? prt::envlight::decomposeCoherent(env, options, coherence, state)
                                                 : prt::envlight::decompose(env, options);
            seconds += prt::nowSeconds() - start;
            prt::HybridLighting lighting;
            lighting.order = options.order;
            lighting.residual.assign(d.residual.begin(), d.residual.end());
            for (const auto& l : d.lights)
                lighting.lights.push_back({{float(l.direction[0]), float(l.direction[1]), float(l.direction[2])},
                                           {float(l.radiance[0]), float(l.radiance[1]), float(l.radiance[2])},
                                           float(l.angularRadius)});
            std::vector<float> visibility =
                prt::envlight::coneVisibility(mesh, mesh.positions.data(), model.normals.data(),
                                              prt::spawnNormals(mesh).data(), rows, d.lights, samples);
            std::vector<float> hybrid(rows * 3), plain(rows * 3);
            prt::relightHybrid(model, lighting, visibility.data(), 0, rows, hybrid.data());
            std::vector<float> rotated = prt::rotateLighting(projection.data(), options.order, R);
            prt::relight(model.total, rotated.data(), 0, rows, plain.data());
            if (frame == 0) {
                for (size_t v = 0; v < rows; ++v)
                    for (int c = 0; c < 3; ++c) meanRadiance += prt::envlight::kLuminance[c] * plain[v * 3 + c];
                meanRadiance /= double(rows);
            }
            counts.push_back(d.lights.size());
            if (frame > 0) {
                if (d.lights.size() != previousLights.size()) ++countChanges;
                for (const auto& l : d.lights) {
                    double nearest = 1e9, carried = 1e9;
                    for (const auto& p : previousLights) {
                        std::array<double, 3> moved;
                        for (int r = 0; r < 3; ++r)
                            moved[r] = stepR[3 * r] * p.direction[0] + stepR[3 * r + 1] * p.direction[1] +
                                       stepR[3 * r + 2] * p.direction[2];
                        double a = angleDegrees(l.direction, p.direction);
                        if (a < nearest) nearest = a, carried = angleDegrees(l.direction, moved);
                    }
                    if (nearest < 1e9) {
                        largestJump = std::max(largestJump, nearest);
                        largestCarriedJump = std::max(largestCarriedJump, carried);
                    }
                }
                Change h = change(hybrid, previousHybrid, meanRadiance), p = change(plain, previousPlain, meanRadiance);
                hybridSeries.push_back(h.rms);
                plainSeries.push_back(p.rms);
                hybridChange.rms = std::max(hybridChange.rms, h.rms);
                hybridChange.max = std::max(hybridChange.max, h.max);
                plainChange.rms = std::max(plainChange.rms, p.rms);
                plainChange.max = std::max(plainChange.max, p.max);
            }
            previousLights = d.lights;
            previousHybrid.swap(hybrid);
            previousPlain.swap(plain);
        }
        auto median = [](nlohmann::json series) {
            std::vector<double> v = series.get<std::vector<double>>();
            if (v.empty()) return 0.0;
            std::sort(v.begin(), v.end());
            return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
        };
        double hybridMedian = median(hybridSeries), plainMedian = median(plainSeries);
        nlohmann::json out = {{"frames", frames},
                              {"mode", mode},
                              {"step_degrees", step},
                              {"order", options.order},
                              {"max_lights", options.maxLights},
                              {"light_counts", counts},
                              {"light_count_changes", countChanges},
                              {"largest_direction_jump_degrees", largestJump},
                              {"largest_jump_against_the_turn_degrees", largestCarriedJump},
                              {"hybrid_largest_change_rms", hybridChange.rms},
                              {"hybrid_largest_change_max", hybridChange.max},
                              {"plain_largest_change_rms", plainChange.rms},
                              {"plain_largest_change_max", plainChange.max},
                              {"hybrid_median_change_rms", hybridMedian},
                              {"plain_median_change_rms", plainMedian},
                              {"hybrid_largest_over_median", hybridMedian > 0 ? hybridChange.rms / hybridMedian : 0.0},
                              {"plain_largest_over_median", plainMedian > 0 ? plainChange.rms / plainMedian : 0.0},
                              {"hybrid_change_rms_per_frame", hybridSeries},
                              {"decompose_seconds_per_frame", seconds / frames}};
        std::cout << out.dump() << "\n";
    } catch (const std::exception& e) {
        std::fprintf(stderr, "envlight_temporal: %s\n", e.what());
        return 3;
    }
    return 0;
}
