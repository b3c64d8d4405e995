// The occluder's own self-shadowed irradiance at its vertices (issue 20, "FIV self-shadowing"): a receiver vertex
// lies on the surface, between grid samples inside the mesh (skipped) and outside it, so the grid's FIV_self is an
// interpolation across the surface; rays from the vertex itself give the exact visibility of the cube's texels.
#include "fiv.h"

#include "core.h"
#include "raycast.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <cmath>

namespace prt::fiv {

std::vector<float> selfIrradiance(const TriMesh& mesh, const CubeEnvironment& env, const SmallSources& sources,
                                  int threads, uint64_t* raysCast) {
    const size_t vertices = mesh.vertexCount();
    if (mesh.normals.size() != mesh.positions.size())
        throw Error("", "fiv_self", "the occluder mesh has no vertex normals (prt meshprep adds them)", kExitInput);
    const CubeTexels cube = cubeTexels(env.size);
    const size_t texels = cube.solidAngle.size(), sourceTexels = sources.direction.size() / 3;
    // Each direction's radiance x solid angle: the cube's texels, then the sources' own map texels.
    std::vector<float> direction(3 * (texels + sourceTexels));
    std::vector<double> power(3 * (texels + sourceTexels));
    for (size_t t = 0; t < texels; ++t)
        for (int c = 0; c < 3; ++c) {
            direction[3 * t + size_t(c)] = float(cube.direction[3 * t + size_t(c)]);
            power[3 * t + size_t(c)] = env.radiance[3 * t + size_t(c)] * cube.solidAngle[t];
        }
    for (size_t s = 0; s < sourceTexels; ++s)
        for (int c = 0; c < 3; ++c) {
            direction[3 * (texels + s) + size_t(c)] = float(sources.direction[3 * s + size_t(c)]);
            power[3 * (texels + s) + size_t(c)] = sources.power[3 * s + size_t(c)];
        }
    const size_t directions = texels + sourceTexels;
    const std::vector<float> spawn = spawnNormals(mesh);
    const float offset = rayOffset(mesh);
    std::vector<float> out(3 * vertices, 0.0f);
    std::atomic<uint64_t> rays{0};
    tbb::task_arena arena(arenaConcurrency(threads));
    arena.execute([&] {
        EmbreeScene embree(mesh);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, vertices, 16), [&](const tbb::blocked_range<size_t>& range) {
            std::vector<RTCRay> batch;
            std::vector<uint32_t> directionOf;
            std::vector<float> cosineOf;
            uint64_t cast = 0;
            for (size_t v = range.begin(); v < range.end(); ++v) {
                const float* m = &mesh.normals[3 * v];
                float length = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
                if (!(length > 0.0f)) continue; // no normal: no irradiance to speak of
                const float n[3] = {m[0] / length, m[1] / length, m[2] / length};
                float origin[3];
                spawnOrigin(&mesh.positions[3 * v], &spawn[3 * v], offset, origin);
                batch.clear(), directionOf.clear(), cosineOf.clear();
                for (size_t t = 0; t < directions; ++t) {
                    const float* w = &direction[3 * t];
                    float cosine = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
                    if (!(cosine > 0.0f) || (t < texels && power[3 * t] == 0.0 && power[3 * t + 1] == 0.0 && power[3 * t + 2] == 0.0))
                        continue;
                    RTCRay ray;
                    spawnRay(ray, origin, w[0], w[1], w[2]);
                    batch.push_back(ray), directionOf.push_back(uint32_t(t)), cosineOf.push_back(cosine);
                }
                if (batch.empty()) continue;
                RTCIntersectContext context;
                rtcInitIntersectContext(&context);
                context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
                rtcOccluded1M(embree.scene, &context, batch.data(), unsigned(batch.size()), sizeof(RTCRay));
                cast += batch.size();
                double sum[3] = {0, 0, 0}; // in ray order: ascending directions, so the same for any thread count
                for (size_t r = 0; r < batch.size(); ++r) {
                    if (batch[r].tfar < 0.0f) continue; // hidden by the mesh itself
                    for (int c = 0; c < 3; ++c) sum[c] += power[3 * directionOf[r] + size_t(c)] * cosineOf[r];
                }
                for (int c = 0; c < 3; ++c) out[3 * v + size_t(c)] = float(sum[c]);
            }
            rays += cast;
        });
    });
    if (raysCast) *raysCast = rays;
    return out;
}

} // namespace prt::fiv
