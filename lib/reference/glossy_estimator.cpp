// One glossy path: the diffuse-plus-Phong BRDF of docs/conventions.md, with next-event estimation of the
// environment and a mixture of cosine and Phong-lobe sampling, combined by the power heuristic.
#include "path_tracer.h"
#include "prt/glossy.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace prt::pathtrace {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

float dot(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// A direction with cosine `cosine` to the unit axis a and azimuth 2 pi u (Duff et al. 2017 basis).
void directionAbout(const float a[3], float cosine, float u, float d[3]) {
    float sign = std::copysign(1.0f, a[2]);
    float p = -1.0f / (sign + a[2]), q = a[0] * a[1] * p;
    float tangent[3] = {1.0f + sign * a[0] * a[0] * p, sign * q, -sign * a[0]};
    float bitangent[3] = {q, sign + a[1] * a[1] * p, -a[1]};
    float sine = std::sqrt(std::max(0.0f, 1.0f - cosine * cosine)), phi = 2.0f * kPi * u;
    float x = sine * std::cos(phi), y = sine * std::sin(phi);
    for (int c = 0; c < 3; ++c) d[c] = x * tangent[c] + y * bitangent[c] + cosine * a[c];
}

float powerHeuristic(float pdf, float otherPdf) { return pdf * pdf / (pdf * pdf + otherPdf * otherPdf); }

} // namespace

float phongLobe(const float mirror[3], const float incoming[3], double exponent, double ks) {
    return float(phongLobeValue(mirror, incoming, exponent, ks)); // the formula lives once, in the runtime
}

void estimateGlossyRadiance(const SceneTracer& scene, const EnvironmentSampler& environment,
                            const ShadingPoint& start, const float startOutgoing[3], double exponent, double ks,
                            int bounces, Pcg32& random, double radiance[3], uint64_t& rays) {
    ShadingPoint point = start;
    float outgoing[3] = {startOutgoing[0], startOutgoing[1], startOutgoing[2]};
    float throughput[3] = {1.0f, 1.0f, 1.0f};
    radiance[0] = radiance[1] = radiance[2] = 0.0;
    const float phongPdfScale = float((exponent + 1.0) / (2.0 * std::numbers::pi));

    for (int depth = 0;; ++depth) {
        float cosOut = dot(point.normal, outgoing);
        float surfaceKs = cosOut > 0.0f ? float(ks) : 0.0f; // no lobe toward a viewer below the surface
        float mirror[3];
        for (int c = 0; c < 3; ++c) mirror[c] = 2.0f * cosOut * point.normal[c] - outgoing[c];
        float diffuseWeight = (point.albedo[0] + point.albedo[1] + point.albedo[2]) / 3.0f;
        if (diffuseWeight + surfaceKs <= 0.0f) return;
        float specularChoice = surfaceKs / (diffuseWeight + surfaceKs);
        auto brdfPdf = [&](const float d[3], float cosine) {
            float lobe = dot(mirror, d);
            float specular = lobe > 0.0f ? phongPdfScale * std::pow(lobe, float(exponent)) : 0.0f;
            return (1.0f - specularChoice) * std::max(cosine, 0.0f) / kPi + specularChoice * specular;
        };
        auto brdf = [&](const float d[3], int c) {
            return point.albedo[c] / kPi + (surfaceKs > 0.0f ? phongLobe(mirror, d, exponent, surfaceKs) : 0.0f);
        };
        float origin[3];
        for (int c = 0; c < 3; ++c) origin[c] = point.position[c] + scene.rayOffset() * point.offsetNormal[c];

        if (!environment.rowCdf.empty()) {
            double uRow = random.uniformDouble(), uColumn = random.uniformDouble();
            float u1 = random.uniform(), u2 = random.uniform();
            EnvironmentSample light = sampleEnvironment(environment, uRow, uColumn, u1, u2);
            float cosine = dot(point.normal, light.direction);
            if (cosine > 0.0f && light.pdf > 0.0f) {
                ++rays;
                if (!scene.occluded(origin, light.direction)) {
                    float weight = powerHeuristic(light.pdf, brdfPdf(light.direction, cosine)) * cosine / light.pdf;
                    const float* emitted = environment.texels[light.texel].radiance;
                    for (int c = 0; c < 3; ++c)
                        radiance[c] += double(throughput[c] * brdf(light.direction, c) * weight * emitted[c]);
                }
            }
        }

        float choice = random.uniform(), u0 = random.uniform(), u1 = random.uniform();
        float d[3];
        if (choice < specularChoice)
            directionAbout(mirror, std::pow(u0, 1.0f / float(exponent + 1.0)), u1, d);
        else
            directionAbout(point.normal, std::sqrt(u0), u1, d);
        float cosine = dot(point.normal, d);
        if (cosine <= 0.0f) return; // a lobe sample below the surface carries nothing
        float pdf = brdfPdf(d, cosine);
        if (!(pdf > 0.0f)) return;
        ++rays;
        ShadingPoint hit;
        HitKind kind = scene.intersect(origin, d, &hit);
        float scale[3];
        for (int c = 0; c < 3; ++c) scale[c] = brdf(d, c) * cosine / pdf;
        if (kind == HitKind::Miss) {
            size_t texel = environmentTexel(environment, d);
            float weight = powerHeuristic(pdf, environmentPdf(environment, texel, d));
            const float* emitted = environment.texels[texel].radiance;
            for (int c = 0; c < 3; ++c) radiance[c] += double(throughput[c] * scale[c] * weight * emitted[c]);
            return;
        }
        if (kind == HitKind::BackFace || depth == bounces) return;
        for (int c = 0; c < 3; ++c) throughput[c] *= scale[c], outgoing[c] = -d[c];
        point = hit;
    }
}

} // namespace prt::pathtrace
