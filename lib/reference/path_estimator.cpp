// One diffuse path: next-event estimation of the environment and cosine-weighted bounces, combined by multiple
// importance sampling (power heuristic), and the random numbers that drive it.
#include "path_tracer.h"

#include <cmath>
#include <numbers>

namespace prt::pathtrace {

namespace {

uint64_t mix64(uint64_t x) { // splitmix64's finaliser
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

float dot(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Cosine-weighted direction about the unit normal n, through the branchless orthonormal basis of
// Duff et al. 2017. Returns the cosine to n.
float sampleCosine(const float n[3], float u0, float u1, float d[3]) {
    float sign = std::copysign(1.0f, n[2]);
    float a = -1.0f / (sign + n[2]), b = n[0] * n[1] * a;
    float tangent[3] = {1.0f + sign * n[0] * n[0] * a, sign * b, -sign * n[0]};
    float bitangent[3] = {b, sign + n[1] * n[1] * a, -n[1]};
    float radius = std::sqrt(u0), phi = 2.0f * std::numbers::pi_v<float> * u1;
    float x = radius * std::cos(phi), y = radius * std::sin(phi), z = std::sqrt(std::max(0.0f, 1.0f - u0));
    for (int c = 0; c < 3; ++c) d[c] = x * tangent[c] + y * bitangent[c] + z * n[c];
    return z;
}

float powerHeuristic(float pdf, float otherPdf) { return pdf * pdf / (pdf * pdf + otherPdf * otherPdf); }

} // namespace

uint32_t Pcg32::next() {
    uint64_t old = state;
    state = old * 6364136223846793005ull + increment;
    uint32_t shifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    uint32_t rotation = uint32_t(old >> 59u);
    return (shifted >> rotation) | (shifted << ((-rotation) & 31u));
}

float Pcg32::uniform() { return float(next() >> 8) * 0x1p-24f; }

double Pcg32::uniformDouble() {
    uint64_t bits = (uint64_t(next()) << 21) ^ uint64_t(next()); // 53 random bits
    return double(bits) * 0x1p-53;
}

Pcg32 sampleGenerator(uint64_t seed, uint64_t point, uint64_t sample) {
    Pcg32 random;
    random.increment = (mix64(seed ^ 0x9e3779b97f4a7c15ull) << 1) | 1u;
    random.state = mix64(mix64(seed + mix64(point)) + sample) + random.increment;
    random.next();
    return random;
}

void estimateRadiance(const SceneTracer& scene, const EnvironmentSampler& environment, const ShadingPoint& start,
                      int bounces, Pcg32& random, double radiance[3], uint64_t& rays) {
    constexpr float kInvPi = std::numbers::inv_pi_v<float>;
    ShadingPoint point = start;
    float throughput[3] = {point.albedo[0], point.albedo[1], point.albedo[2]}; // product of albedos so far
    radiance[0] = radiance[1] = radiance[2] = 0.0;

    for (int depth = 0;; ++depth) {
        float origin[3];
        spawnOrigin(point.position, point.offsetNormal, scene.rayOffset(), origin);

        // Next-event estimation: f cos L / pdf with f = albedo / pi.
        if (!environment.rowCdf.empty()) {
            double uRow = random.uniformDouble(), uColumn = random.uniformDouble();
            float u1 = random.uniform(), u2 = random.uniform();
            EnvironmentSample light = sampleEnvironment(environment, uRow, uColumn, u1, u2);
            float cosine = dot(point.normal, light.direction);
            // A texel whose probability underflows float has no usable pdf; the bounce strategy covers it.
            if (cosine > 0.0f && light.pdf > 0.0f) {
                ++rays;
                if (!scene.occluded(origin, light.direction)) {
                    float weight = powerHeuristic(light.pdf, cosine * kInvPi) * cosine * kInvPi / light.pdf;
                    const float* emitted = environment.texels[light.texel].radiance;
                    for (int c = 0; c < 3; ++c) radiance[c] += double(throughput[c] * weight * emitted[c]);
                }
            }
        }

        // Cosine-weighted bounce: f cos / pdf = albedo, already in the throughput.
        float u0 = random.uniform(), u1 = random.uniform();
        float d[3];
        float cosine = sampleCosine(point.normal, u0, u1, d);
        ++rays;
        ShadingPoint hit;
        HitKind kind = scene.intersect(origin, d, &hit);
        if (kind == HitKind::Miss) {
            size_t texel = environmentTexel(environment, d);
            float weight = powerHeuristic(cosine * kInvPi, environmentPdf(environment, texel, d));
            const float* emitted = environment.texels[texel].radiance;
            for (int c = 0; c < 3; ++c) radiance[c] += double(throughput[c] * weight * emitted[c]);
            return;
        }
        if (kind == HitKind::BackFace || depth == bounces) return;
        point = hit;
        for (int c = 0; c < 3; ++c) throughput[c] *= point.albedo[c];
    }
}

} // namespace prt::pathtrace
