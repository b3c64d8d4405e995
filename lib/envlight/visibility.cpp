// Soft visibility of cone lights at surface points, standing in for an engine's filtered shadow maps: occlusion
// rays over a fixed sample set on each cone, weighted by the receiver's cosine.
#include "envlight.h"

#include "raycast.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace prt::envlight {

namespace {

double radicalInverse2(uint32_t k) {
    k = (k << 16) | (k >> 16);
    k = ((k & 0x00ff00ffu) << 8) | ((k & 0xff00ff00u) >> 8);
    k = ((k & 0x0f0f0f0fu) << 4) | ((k & 0xf0f0f0f0u) >> 4);
    k = ((k & 0x33333333u) << 2) | ((k & 0xccccccccu) >> 2);
    k = ((k & 0x55555555u) << 1) | ((k & 0xaaaaaaaau) >> 1);
    return double(k) * (1.0 / 4294967296.0);
}

} // namespace

std::vector<float> coneSampleDirections(const ConeLight& light, int samples) {
    const double* d = light.direction.data();
    double helper[3] = {std::abs(d[0]) < 0.9 ? 1.0 : 0.0, std::abs(d[0]) < 0.9 ? 0.0 : 1.0, 0.0};
    double t1[3] = {d[1] * helper[2] - d[2] * helper[1], d[2] * helper[0] - d[0] * helper[2],
                    d[0] * helper[1] - d[1] * helper[0]};
    double length = std::sqrt(t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]);
    for (double& x : t1) x /= length;
    double t2[3] = {d[1] * t1[2] - d[2] * t1[1], d[2] * t1[0] - d[0] * t1[2], d[0] * t1[1] - d[1] * t1[0]};
    const double cosRadius = std::cos(light.angularRadius);
    std::vector<float> out(size_t(samples) * 3);
    for (int s = 0; s < samples; ++s) {
        double cosTheta = 1.0 - (s + 0.5) / samples * (1.0 - cosRadius);
        double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
        double phi = 2.0 * M_PI * radicalInverse2(uint32_t(s));
        for (int c = 0; c < 3; ++c)
            out[s * 3 + c] = float(cosTheta * d[c] + sinTheta * (std::cos(phi) * t1[c] + std::sin(phi) * t2[c]));
    }
    return out;
}

namespace {

// Casts, for every point i < count, one occlusion ray toward each sample of each light that lies above the point's
// horizon (n_i . w > 0), from the point's spawn origin (lib/raycast's rule: spawnNormals, or normals when null),
// and hands the results to `store(i, hits)`, where hits is [lights][samples] with 1 visible, 0 occluded or below
// the horizon. With a scene's `surface` (its mesh `mesh`), rays pass through its cut-outs (EmbreeScene's filter);
// null: every triangle occludes. Needs: `directions` [lights][samples * 3] unit vectors. Guarantees: the same rays in the same order
// per point whatever the thread count, so every caller's reduction is deterministic; returns the rays cast.
template <class Store>
uint64_t castConeSamples(const TriMesh& mesh, const float* points, const float* normals, const float* spawnNormals,
                         size_t count, const std::vector<std::vector<float>>& directions, int samples,
                         const Surface* surface, Store store) {
    const size_t lights = directions.size(), perPoint = lights * size_t(samples);
    EmbreeScene scene(mesh, surface);
    const float offset = rayOffset(mesh);
    std::atomic<uint64_t> cast{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 256), [&](const tbb::blocked_range<size_t>& range) {
        uint64_t local = 0;
        std::vector<uint8_t> hits(perPoint);
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        for (size_t i = range.begin(); i != range.end(); ++i) {
            const float* n = normals + i * 3;
            float origin[3];
            spawnOrigin(points + i * 3, (spawnNormals ? spawnNormals : normals) + i * 3, offset, origin);
            for (size_t k = 0; k < lights; ++k)
                for (int s = 0; s < samples; ++s) {
                    const float* w = &directions[k][s * 3];
                    uint8_t& hit = hits[k * samples + s];
                    hit = 0;
                    if (n[0] * w[0] + n[1] * w[1] + n[2] * w[2] <= 0.0f) continue; // below the horizon: 0
                    RTCRay ray;
                    spawnRay(ray, origin, w[0], w[1], w[2]);
                    rtcOccluded1(scene.scene, &context, &ray);
                    ++local;
                    hit = ray.tfar >= 0.0f ? 1 : 0; // occluded rays come back with tfar = -inf
                }
            store(i, hits.data());
        }
        cast += local;
    });
    return cast.load();
}

// The cosine-weighted visible fraction of one light at one point: sum over samples above the horizon of
// (n . w) * hit, over the sum of (n . w); 0 when no sample is above it. `directions` [samples][3], `hits` [samples].
float visibleFraction(const float* n, const float* directions, int samples, const uint8_t* hits) {
    double seen = 0.0, total = 0.0;
    for (int s = 0; s < samples; ++s) {
        const float* w = directions + s * 3;
        float cosine = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
        if (cosine <= 0.0f) continue;
        total += cosine;
        if (hits[s]) seen += cosine;
    }
    return total > 0.0 ? float(seen / total) : 0.0f;
}

std::vector<std::vector<float>> sampleDirections(const std::vector<ConeLight>& lights, int samples) {
    std::vector<std::vector<float>> directions;
    for (const ConeLight& light : lights) directions.push_back(coneSampleDirections(light, samples));
    return directions;
}

} // namespace

std::vector<float> coneVisibility(const TriMesh& mesh, const float* points, const float* normals,
                                  const float* spawnNormals, size_t count, const std::vector<ConeLight>& lights,
                                  int samples, uint64_t* rays, const Surface* surface) {
    std::vector<float> visibility(count * lights.size(), 0.0f);
    if (lights.empty() || count == 0) return visibility;
    const std::vector<std::vector<float>> directions = sampleDirections(lights, samples);
    const size_t lightCount = lights.size();
    uint64_t cast = castConeSamples(mesh, points, normals, spawnNormals, count, directions, samples, surface,
                                    [&](size_t i, const uint8_t* hits) {
                                        for (size_t k = 0; k < lightCount; ++k)
                                            visibility[i * lightCount + k] = visibleFraction(
                                                normals + i * 3, directions[k].data(), samples, hits + k * samples);
                                    });
    if (rays) *rays = cast;
    return visibility;
}

std::vector<uint8_t> coneSampleVisibility(const TriMesh& mesh, const float* points, const float* normals,
                                          const float* spawnNormals, size_t count, const std::vector<ConeLight>& lights,
                                          int samples, uint64_t* rays) {
    const size_t perPoint = lights.size() * size_t(samples);
    std::vector<uint8_t> visible(count * perPoint, 0);
    if (lights.empty() || count == 0 || samples <= 0) return visible;
    uint64_t cast = castConeSamples(mesh, points, normals, spawnNormals, count, sampleDirections(lights, samples),
                                    samples, nullptr, [&](size_t i, const uint8_t* hits) {
                                        std::copy(hits, hits + perPoint, visible.begin() + i * perPoint);
                                    });
    if (rays) *rays = cast;
    return visible;
}

std::vector<float> coneVisibilityFromSamples(const float* normals, size_t count, size_t lights, int samples,
                                             const float* directions, const uint8_t* visible) {
    std::vector<float> fraction(count * lights, 0.0f);
    for (size_t i = 0; i < count; ++i)
        for (size_t k = 0; k < lights; ++k)
            fraction[i * lights + k] = visibleFraction(normals + i * 3, directions + k * samples * 3, samples,
                                                       visible + (i * lights + k) * samples);
    return fraction;
}

} // namespace prt::envlight
