// The reference drivers: per-vertex radiance and pinhole images, parallel over points, each point's samples
// run in a fixed order from its own random streams.
#include "reference.h"

#include "core.h"
#include "path_tracer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <cmath>
#include <numbers>

namespace prt {

namespace {

using namespace pathtrace;

void checkInputs(const TriMesh& mesh, const ReferenceOptions& options) {
    if (options.samples < 2) throw Error("", "reference", "need at least 2 samples for a standard error", kExitUsage);
    if (options.bounces < 0) throw Error("", "reference", "bounces must be >= 0", kExitUsage);
    if (mesh.normals.size() != mesh.positions.size()) throw Error("", "mesh", "has no vertex normals");
    if (!mesh.albedo.empty() && mesh.albedo.size() != mesh.positions.size())
        throw Error("", "mesh", "albedo is not rgb per vertex");
    if (options.surface && options.albedo)
        throw Error("", "--albedo", "a scene takes its albedo from its materials", kExitUsage);
    if (options.phong && !(options.phong->exponent > 0.0 && std::isfinite(options.phong->exponent)))
        throw Error("", "--brdf", "the Phong exponent must be > 0", kExitUsage);
    if (options.phong && !(options.phong->ks >= 0.0 && options.phong->ks <= 1.0))
        throw Error("", "--brdf", "the Phong specular albedo must lie in [0, 1]", kExitUsage);
}

// Mean of `samples` path estimates from `point` and its standard error (Welford's running variance, which
// stays accurate when the mean is large against the spread).
void estimatePoint(const SceneTracer& scene, const EnvironmentSampler& environment, const ShadingPoint& point,
                   uint64_t pointIndex, const ReferenceOptions& options, float mean[3], float standardError[3],
                   uint64_t& rays, const float* outgoing = nullptr) {
    double running[3] = {0, 0, 0}, squares[3] = {0, 0, 0};
    for (int sample = 0; sample < options.samples; ++sample) {
        Pcg32 random = sampleGenerator(options.seed, pointIndex, uint64_t(sample));
        double radiance[3];
        if (options.phong && outgoing)
            estimateGlossyRadiance(scene, environment, point, outgoing, options.phong->exponent, options.phong->ks,
                                   options.bounces, random, radiance, rays);
        else
            estimateRadiance(scene, environment, point, options.bounces, random, radiance, rays);
        for (int c = 0; c < 3; ++c) {
            double delta = radiance[c] - running[c];
            running[c] += delta / (sample + 1);
            squares[c] += delta * (radiance[c] - running[c]);
        }
    }
    double n = options.samples;
    for (int c = 0; c < 3; ++c) {
        mean[c] = float(running[c]);
        standardError[c] = float(std::sqrt(squares[c] / (n - 1.0) / n));
    }
}

// Runs body(begin, end, rays) over [0, count) in blocks, with Progress; returns the rays counted.
template <typename Body>
uint64_t parallelOverPoints(const char* label, size_t count, const Body& body) {
    std::atomic<uint64_t> rays{0};
    Progress progress(label, count);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16), [&](const tbb::blocked_range<size_t>& range) {
        uint64_t blockRays = 0;
        body(range.begin(), range.end(), blockRays);
        rays += blockRays;
        progress.add(range.size());
    });
    progress.finish();
    return rays;
}

// Runs `work` with at most `threads` workers (0: all), Embree's scene build included.
template <typename Work>
auto withThreads(int threads, const Work& work) {
    tbb::task_arena arena(arenaConcurrency(threads));
    return arena.execute(work);
}

// Shades the vertices vertices[0..count) (or 0..count when `vertices` is null) into rows 0..count of the result.
ReferenceRadiance shadeVertexRows(const TriMesh& mesh, const EnvironmentMap& env, const uint32_t* vertices,
                                  size_t count, const ReferenceOptions& options) {
    checkInputs(mesh, options);
    if (options.phong && !options.eye)
        throw Error("", "--eye", "a glossy BRDF's per-vertex radiance needs the eye point", kExitUsage);
    for (size_t i = 0; vertices && i < count; ++i)
        if (vertices[i] >= mesh.vertexCount())
            throw Error("", "reference", "vertex " + std::to_string(vertices[i]) + " is not in the mesh's " +
                        std::to_string(mesh.vertexCount()) + " vertices", kExitUsage);
    EnvironmentSampler environment = makeEnvironmentSampler(env);
    return withThreads(options.threads, [&] {
        SceneTracer scene(mesh, options.albedo, options.surface);
        ReferenceRadiance result;
        result.radiance.resize(count * 3);
        result.standardError.resize(count * 3);
        auto shadeVertices = [&](size_t begin, size_t end, uint64_t& rays) {
            for (size_t row = begin; row < end; ++row) {
                const uint32_t v = vertices ? vertices[row] : uint32_t(row);
                ShadingPoint point = scene.vertexPoint(v);
                float outgoing[3] = {0, 0, 1};
                if (options.eye) {
                    for (int c = 0; c < 3; ++c) outgoing[c] = (*options.eye)[c] - point.position[c];
                    float length = std::sqrt(outgoing[0] * outgoing[0] + outgoing[1] * outgoing[1] +
                                             outgoing[2] * outgoing[2]);
                    for (float& c : outgoing) c /= length;
                }
                estimatePoint(scene, environment, point, v, options, &result.radiance[row * 3],
                              &result.standardError[row * 3], rays, options.eye ? outgoing : nullptr);
            }
        };
        result.rays = parallelOverPoints("reference", count, shadeVertices);
        return result;
    });
}

} // namespace

ReferenceRadiance referenceVertexRadiance(const TriMesh& mesh, const EnvironmentMap& env,
                                          const ReferenceOptions& options) {
    return shadeVertexRows(mesh, env, nullptr, mesh.vertexCount(), options);
}

ReferenceRadiance referenceVertexRadianceAt(const TriMesh& mesh, const EnvironmentMap& env,
                                            const std::vector<uint32_t>& vertices, const ReferenceOptions& options) {
    return shadeVertexRows(mesh, env, vertices.data(), vertices.size(), options);
}

ReferenceImage referenceImage(const TriMesh& mesh, const EnvironmentMap& env, const PinholeCamera& camera,
                              const ReferenceOptions& options) {
    checkInputs(mesh, options);
    const PinholeRays pinhole = pinholeRays(camera);

    EnvironmentSampler environment = makeEnvironmentSampler(env);
    return withThreads(options.threads, [&] {
        SceneTracer scene(mesh, options.albedo, options.surface);
        ReferenceImage result;
        for (Image* image : {&result.radiance, &result.standardError}) {
            image->width = camera.width;
            image->height = camera.height;
            image->rgb.assign(size_t(camera.width) * camera.height * 3, 0.0f);
        }
        auto shadePixels = [&](size_t begin, size_t end, uint64_t& rays) {
            for (size_t pixel = begin; pixel < end; ++pixel) {
                float d[3];
                pinholeRayDirection(pinhole, pixel, d);
                ++rays;
                ShadingPoint hit;
                HitKind kind = scene.intersect(camera.eye.data(), d, &hit);
                float* radiance = &result.radiance.rgb[pixel * 3];
                if (kind == HitKind::Miss) {
                    const float* emitted = environment.texels[environmentTexel(environment, d)].radiance;
                    std::copy(emitted, emitted + 3, radiance);
                } else if (kind == HitKind::FrontFace) {
                    float outgoing[3] = {-d[0], -d[1], -d[2]};
                    estimatePoint(scene, environment, hit, pixel, options, radiance,
                                  &result.standardError.rgb[pixel * 3], rays, outgoing);
                } // a back face stays black, as it ends a path
            }
        };
        result.rays = parallelOverPoints("reference image", size_t(camera.width) * camera.height, shadePixels);
        return result;
    });
}

} // namespace prt
