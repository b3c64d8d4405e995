// The glossy runtime's cost per vertex and lobe: glossyRadiance with every lobe summed exactly over the map's
// texels (integrateLobe, the runtime before issue 19 item 5) against the prefiltered stack (lookupLobe), the same
// bundle, map and eye in one run, single-threaded, best of several repetitions of thread CPU time; plus the prefilter's own time and
// memory and the two paths' agreement. Run by hand (not a ctest test):
//   build/tests/glossy/bench_glossy_runtime GLOSSY.glb ENV.exr [EYE_X,EYE_Y,EYE_Z]
// (docs/results.md, issue 19). Without arguments: a synthetic 1-lobe model on a sphere under a synthetic map.
#include "bundle.h"
#include "glossy.h"
#include "image.h"
#include "runtime.h"
#include "scene.h"

#include <algorithm>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

// This thread's CPU time: the machine the figures come from is shared, and wall time would count other loads.
double seconds() {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// Best wall time of `repeats` calls of f.
template <class F> double best(int repeats, F&& f) {
    double out = 1e30;
    for (int i = 0; i < repeats; ++i) {
        double start = seconds();
        f();
        out = std::min(out, seconds() - start);
    }
    return out;
}

size_t stackBytes(const prt::PrefilteredEnvironment& env) {
    size_t bytes = 0;
    for (const auto& level : env.sharpnessLevels) bytes += level.rgb.size() * sizeof(float);
    return bytes;
}

prt::GlossyModel syntheticModel() {
    const prt::glossy::ViewSet& views = prt::glossy::viewSet();
    prt::TriMesh sphere = prt::makeSphere(1.0f, 16, 32);
    prt::GlossyModel model;
    model.vertexCount = uint32_t(sphere.vertexCount());
    model.lobes = 1;
    for (const auto& d : views.directions) model.views.insert(model.views.end(), d.begin(), d.end());
    for (const auto& t : views.triangles) model.triangles.insert(model.triangles.end(), t.begin(), t.end());
    model.positions = sphere.positions;
    model.normals = sphere.normals;
    for (uint32_t v = 0; v < model.vertexCount; ++v) {
        const float* n = &sphere.normals[size_t(v) * 3];
        for (const auto& w : views.directions) {
            float c = 2.0f * (w[0] * n[0] + w[1] * n[1] + w[2] * n[2]);
            model.values.insert(model.values.end(), {0.05f, c * n[0] - w[0], c * n[1] - w[1], c * n[2] - w[2], 64.0f});
        }
    }
    prt::indexViewTriangles(model);
    return model;
}

} // namespace

int main(int argc, char** argv) {
    prt::GlossyModel model;
    prt::EnvironmentMap map;
    float eye[3] = {0.0f, 5.0f, 25.0f};
    if (argc >= 3) {
        model = prt::glossyModel(prt::readBundle(argv[1]), argv[1]);
        map = prt::readEnvironmentMap(argv[2]);
        if (argc >= 4 && std::sscanf(argv[3], "%f,%f,%f", &eye[0], &eye[1], &eye[2]) != 3) {
            std::fprintf(stderr, "bad eye %s\n", argv[3]);
            return 2;
        }
    } else {
        model = syntheticModel();
        const int width = 1024, height = 512;
        map.radiance = {width, height, std::vector<float>(size_t(width) * height * 3)};
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c)
                    map.radiance.rgb[(size_t(y) * width + x) * 3 + c] =
                        0.2f + float(y) / height + (x / 16 + y / 16) % 2 * 0.5f + ((x - 300) * (x - 300) + (y - 100) * (y - 100) < 9 ? 500.0f : 0.0f);
    }
    const int width = map.radiance.width, height = map.radiance.height;
    const float* rgb = map.radiance.rgb.data();

    // The prefilter: the box chain alone (what the runtime built before), the stack over the model's sharpness
    // range (what relight and render build), and the whole stack 0.5..8192.
    prt::PrefilterOptions none, ranged, whole;
    none.sharpnessMin = 2.0, none.sharpnessMax = 1.0;
    prt::glossySharpnessRange(model, ranged.sharpnessMin, ranged.sharpnessMax);
    // PRT_BENCH_STACK=LEVELS_PER_OCTAVE,TEXELS_PER_WIDTH tries another stack (the defaults are 2,4).
    if (const char* stack = std::getenv("PRT_BENCH_STACK")) {
        if (std::sscanf(stack, "%d,%d", &ranged.levelsPerOctave, &ranged.texelsPerWidth) != 2) return 2;
        whole.levelsPerOctave = ranged.levelsPerOctave, whole.texelsPerWidth = ranged.texelsPerWidth;
    }
    prt::PrefilteredEnvironment boxes, env, full;
    const double boxSeconds = best(3, [&] { boxes = prt::prefilterEnvironment(rgb, width, height, none); });
    const double rangedSeconds = best(1, [&] { env = prt::prefilterEnvironment(rgb, width, height, ranged); });
    const double fullSeconds = best(1, [&] { full = prt::prefilterEnvironment(rgb, width, height, whole); });

    const size_t V = model.vertexCount, lobes = size_t(model.lobes);
    std::vector<float> exact(V * 3), looked(V * 3);
    const double exactSeconds =
        best(3, [&] { prt::glossyRadiance(model, env, eye, exact.data(), prt::LobeEvaluation::ExactSum); });
    const double lookupSeconds =
        best(20, [&] { prt::glossyRadiance(model, env, eye, looked.data(), prt::LobeEvaluation::Prefiltered); });
    // The same with no lobe evaluated at all (a = 0 everywhere): view weights and turning, the fixed part.
    prt::GlossyModel dark = model;
    for (size_t i = 0; i < dark.values.size(); i += 5) dark.values[i] = 0.0f;
    std::vector<float> zero(V * 3);
    const double fixedSeconds =
        best(20, [&] { prt::glossyRadiance(dark, env, eye, zero.data(), prt::LobeEvaluation::Prefiltered); });

    prt::GlossyModel scan = dark;
    scan.viewTriangleOffsets.clear(), scan.viewTriangles.clear();
    const double scanSeconds =
        best(5, [&] { prt::glossyRadiance(scan, env, eye, zero.data(), prt::LobeEvaluation::Prefiltered); });
    double squares = 0.0, reference = 0.0;
    for (size_t i = 0; i < exact.size(); ++i) {
        squares += (double(looked[i]) - exact[i]) * (double(looked[i]) - exact[i]);
        reference += double(exact[i]) * exact[i];
    }
    const double perUnit = 1e9 / double(V * lobes);
    std::printf("model: %zu vertices, %zu lobes per view, sharpness %.3g..%.3g; map %dx%d; eye %g,%g,%g\n", V, lobes,
                ranged.sharpnessMin, ranged.sharpnessMax, width, height, eye[0], eye[1], eye[2]);
    std::printf("prefilter: box chain %.1f ms; stack over the model's range %.1f ms (%zu levels, %.1f MB); whole "
                "stack 0.5..8192 %.1f ms (%zu levels, %.1f MB)\n",
                boxSeconds * 1e3, rangedSeconds * 1e3, env.sharpnessLevels.size(), stackBytes(env) / 1e6,
                fullSeconds * 1e3, full.sharpnessLevels.size(), stackBytes(full) / 1e6);
    std::printf("glossyRadiance ns per vertex and lobe (3 views each): exact sum %.0f, prefiltered %.0f, ratio %.1fx; "
                "without lobe evaluations %.0f ns per vertex (%.0f scanning every view triangle)\n",
                exactSeconds * perUnit, lookupSeconds * perUnit, exactSeconds / lookupSeconds, fixedSeconds * 1e9 / V, scanSeconds * 1e9 / V);
    std::printf("prefiltered against exact: relative RMSE %.4f%%\n", 100.0 * std::sqrt(squares / std::max(reference, 1e-30)));
    return 0;
}
