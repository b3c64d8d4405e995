// Cone lights through the glossy path: the exact Phong lobe over each cone's sample directions, with the caller's
// per-sample visibility (docs/glossy.md, "Lights through the glossy path"). Needs only the standard library.
#include "runtime.h"
#include "runtime_internal.h"
#include "sh.h"

#include <cmath>
#include <numbers>

namespace prt {

double phongLobeValue(const float mirror[3], const float incoming[3], double exponent, double ks) {
    const double c = double(mirror[0]) * incoming[0] + double(mirror[1]) * incoming[1] + double(mirror[2]) * incoming[2];
    if (!(c > 0.0)) return 0.0;
    return ks * (exponent + 2.0) / (2.0 * std::numbers::pi) * std::pow(c, exponent);
}

void checkGlossyConeLights(const GlossyModel& model, const GlossyConeLights& lights, const std::string& source) {
    const size_t perRow = lights.lights.size() * size_t(std::max(0, lights.samples));
    if (lights.samples < 0 || lights.directions.size() != perRow * 3 ||
        lights.visible.size() != size_t(model.vertexCount) * perRow)
        throw Error(source, "glossy cone lights", "sample directions or visibility do not fit " +
                                                     std::to_string(model.vertexCount) + " vertices and " +
                                                     std::to_string(lights.lights.size()) + " lights",
                    kExitFailure);
    if (!lights.lights.empty() && !(model.exponent > 0.0))
        throw Error(source, "layer glossy_lobes, params.brdf",
                    "records no Phong lobe, which the cone lights are shaded with (refit with `prt glossy`)",
                    kExitInput);
}

void glossyConeLightsToward(const GlossyModel& model, const GlossyConeLights& lights, uint32_t vertex, const float d[3],
                            float radiance[3]) {
    radiance[0] = radiance[1] = radiance[2] = 0.0f;
    if (lights.lights.empty() || lights.samples <= 0) return;
    const float* raw = &model.normals[size_t(vertex) * 3];
    const double length = std::sqrt(double(raw[0]) * raw[0] + double(raw[1]) * raw[1] + double(raw[2]) * raw[2]);
    if (!(length > 0.0)) return;
    const float n[3] = {float(raw[0] / length), float(raw[1] / length), float(raw[2] / length)};
    const double cosOut = double(n[0]) * d[0] + double(n[1]) * d[1] + double(n[2]) * d[2];
    if (!(cosOut > 0.0)) return; // the lobe sends nothing below the surface, as in the reference
    float mirror[3];
    for (int i = 0; i < 3; ++i) mirror[i] = float(2.0 * cosOut * n[i] - d[i]);
    const size_t samples = size_t(lights.samples);
    const uint8_t* visible = &lights.visible[size_t(vertex) * lights.lights.size() * samples];
    double sum[3] = {0, 0, 0};
    for (size_t k = 0; k < lights.lights.size(); ++k) {
        double lit = 0.0; // sum over samples of f cos V
        for (size_t s = 0; s < samples; ++s) {
            if (!visible[k * samples + s]) continue;
            const float* w = &lights.directions[(k * samples + s) * 3];
            const double cosine = double(n[0]) * w[0] + double(n[1]) * w[1] + double(n[2]) * w[2];
            if (!(cosine > 0.0)) continue;
            lit += phongLobeValue(mirror, w, model.exponent, model.ks) * cosine;
        }
        const HybridConeLight& light = lights.lights[k];
        const double solidAngle = sh::capSolidAngle(std::cos(double(light.angularRadius)));
        for (int c = 0; c < 3; ++c) sum[c] += light.radiance[c] * solidAngle / double(samples) * lit;
    }
    for (int c = 0; c < 3; ++c) radiance[c] = float(sum[c]);
}

void glossyConeLightRadiance(const GlossyModel& model, const GlossyConeLights& lights, const float eye[3],
                             float* radiance) {
    for (uint32_t v = 0; v < model.vertexCount; ++v) {
        float* out = radiance + size_t(v) * 3;
        out[0] = out[1] = out[2] = 0.0f;
        float d[3];
        if (directionToEye(model, v, eye, d)) glossyConeLightsToward(model, lights, v, d, out);
    }
}

} // namespace prt
