// The brute-force direct-lighting reference: every texel of the full-resolution map, one shadow ray each; diffuse,
// or diffuse plus the Phong lobe toward an eye point (the exact glossy oracle).
#include "reference.h"

#include "core.h"
#include "path_tracer.h"
#include "raycast.h"
#include "sh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

namespace prt {

namespace {

struct Sphere {
    double centre[3];
    double radius2;
};

// True when every vertex lies on the plane of vertex 0 with one normal: then no ray leaving the receiver's
// front can meet the receiver again.
bool isFlat(const TriMesh& mesh) {
    const float* n0 = &mesh.normals[0];
    const float* p0 = &mesh.positions[0];
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        lo[i % 3] = std::min(lo[i % 3], mesh.positions[i]), hi[i % 3] = std::max(hi[i % 3], mesh.positions[i]);
    double diagonal = std::sqrt(double(hi[0] - lo[0]) * (hi[0] - lo[0]) + double(hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                double(hi[2] - lo[2]) * (hi[2] - lo[2]));
    for (size_t v = 0; v < mesh.vertexCount(); ++v) {
        const float* n = &mesh.normals[3 * v];
        const float* p = &mesh.positions[3 * v];
        if (n[0] * n0[0] + n[1] * n0[1] + n[2] * n0[2] < 0.99999f) return false;
        double height = (p[0] - p0[0]) * n0[0] + (p[1] - p0[1]) * n0[1] + (p[2] - p0[2]) * n0[2];
        if (std::abs(height) > 1e-6 * diagonal) return false;
    }
    return true;
}

} // namespace

ReferenceRadiance referenceDirectRadiance(const TriMesh& receiver, const std::vector<DirectOccluder>& occluders,
                                          const EnvironmentMap& env, const DirectOptions& options) {
    if (receiver.normals.size() != receiver.positions.size() || receiver.positions.empty())
        throw Error("", "receiver", "has no vertex normals");
    if (options.phong) {
        if (!options.eye) throw Error("", "--eye", "a glossy BRDF's per-vertex radiance needs the eye point", kExitUsage);
        if (!(options.phong->exponent > 0.0 && std::isfinite(options.phong->exponent)))
            throw Error("", "--brdf", "the Phong exponent must be > 0", kExitUsage);
        if (!(options.phong->ks >= 0.0 && options.phong->ks <= 1.0))
            throw Error("", "--brdf", "the Phong specular albedo must lie in [0, 1]", kExitUsage);
    }
    std::vector<double> solidAngle = sh::texelSolidAngles(env); // checks the size against the layout
    int width = env.radiance.width, height = env.radiance.height;
    size_t texels = solidAngle.size();
    std::vector<float> direction(3 * texels);
    std::vector<double> weighted(3 * texels);
    for (size_t t = 0; t < texels; ++t) {
        double d[3];
        int x = int(t % size_t(width)), y = int(t / size_t(width));
        if (env.layout == EnvLayout::Equirectangular) sh::equirectDirection(width, height, x, y, d);
        else sh::cubeStripDirection(width, x, y, d);
        for (int c = 0; c < 3; ++c) {
            direction[3 * t + c] = float(d[c]);
            weighted[3 * t + c] = double(env.radiance.rgb[3 * t + c]) * solidAngle[t];
        }
    }

    bool flat = isFlat(receiver);
    TriMesh scene;
    if (!flat) scene = receiver;
    std::vector<Sphere> spheres;
    for (const DirectOccluder& o : occluders) {
        uint32_t base = uint32_t(scene.vertexCount());
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t i = 0; i < o.mesh.positions.size(); ++i) {
            float p = o.mesh.positions[i] + o.translation[i % 3];
            scene.positions.push_back(p);
            lo[i % 3] = std::min(lo[i % 3], double(p)), hi[i % 3] = std::max(hi[i % 3], double(p));
        }
        for (uint32_t index : o.mesh.indices) scene.indices.push_back(base + index);
        Sphere s{{0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])}, 0.0};
        for (size_t v = 0; v < o.mesh.vertexCount(); ++v) {
            double r2 = 0.0;
            for (int c = 0; c < 3; ++c) r2 += std::pow(o.mesh.positions[3 * v + c] + o.translation[size_t(c)] - s.centre[c], 2);
            s.radius2 = std::max(s.radius2, r2 * (1.0 + 1e-5));
        }
        spheres.push_back(s);
    }
    TriMesh both = receiver;
    for (float p : scene.positions) both.positions.push_back(p);
    float offset = rayOffset(both);

    ReferenceRadiance result;
    size_t vertices = receiver.vertexCount();
    result.radiance.assign(3 * vertices, 0.0f);
    result.standardError.assign(3 * vertices, 0.0f);
    std::atomic<uint64_t> rays{0};
    tbb::task_arena arena(arenaConcurrency(options.threads));
    arena.execute([&] {
        bool trace = options.shadows && scene.triangleCount() > 0;
        std::unique_ptr<EmbreeScene> embree = trace ? std::make_unique<EmbreeScene>(scene) : nullptr;
        Progress progress("reference direct", vertices);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, vertices, 4), [&](const tbb::blocked_range<size_t>& range) {
            uint64_t blockRays = 0;
            for (size_t v = range.begin(); v < range.end(); ++v) {
                const float* n = &receiver.normals[3 * v];
                float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                float normal[3] = {n[0] / length, n[1] / length, n[2] / length};
                float origin[3];
                for (int c = 0; c < 3; ++c) origin[c] = receiver.positions[3 * v + c] + offset * normal[c];
                // The Phong lobe's mirror direction toward the eye; no lobe when the eye is below the surface.
                float mirror[3] = {0, 0, 0};
                bool glossy = false;
                if (options.phong && options.phong->ks > 0.0) {
                    float out[3];
                    for (int c = 0; c < 3; ++c) out[c] = (*options.eye)[size_t(c)] - receiver.positions[3 * v + c];
                    float toEye = std::sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
                    float cosOut = toEye > 0.0f ? (out[0] * normal[0] + out[1] * normal[1] + out[2] * normal[2]) / toEye : 0.0f;
                    glossy = cosOut > 0.0f;
                    for (int c = 0; c < 3; ++c) mirror[c] = 2.0f * cosOut * normal[c] - out[c] / toEye;
                }
                double sum[3] = {0, 0, 0}, glossySum[3] = {0, 0, 0};
                for (size_t t = 0; t < texels; ++t) {
                    const float* w = &direction[3 * t];
                    float cosine = normal[0] * w[0] + normal[1] * w[1] + normal[2] * w[2];
                    if (cosine <= 0.0f) continue;
                    bool visible = true;
                    if (trace) {
                        bool mayHit = !flat;
                        for (size_t s = 0; s < spheres.size() && !mayHit; ++s) {
                            double to[3] = {spheres[s].centre[0] - origin[0], spheres[s].centre[1] - origin[1],
                                            spheres[s].centre[2] - origin[2]};
                            double along = to[0] * w[0] + to[1] * w[1] + to[2] * w[2];
                            double distance2 = to[0] * to[0] + to[1] * to[1] + to[2] * to[2];
                            if (distance2 <= spheres[s].radius2 ||
                                (along > 0.0 && distance2 - along * along <= spheres[s].radius2))
                                mayHit = true;
                        }
                        if (mayHit) {
                            RTCIntersectContext context;
                            rtcInitIntersectContext(&context);
                            RTCRay ray{};
                            ray.org_x = origin[0], ray.org_y = origin[1], ray.org_z = origin[2];
                            ray.dir_x = w[0], ray.dir_y = w[1], ray.dir_z = w[2];
                            ray.tnear = offset;
                            ray.tfar = std::numeric_limits<float>::infinity();
                            ray.mask = ~0u;
                            rtcOccluded1(embree->scene, &context, &ray);
                            ++blockRays;
                            visible = ray.tfar >= 0.0f;
                        }
                    }
                    if (!visible) continue;
                    for (int c = 0; c < 3; ++c) sum[c] += weighted[3 * t + c] * cosine;
                    if (!glossy) continue;
                    double lobe = pathtrace::phongLobe(mirror, w, options.phong->exponent, options.phong->ks);
                    for (int c = 0; c < 3; ++c) glossySum[c] += weighted[3 * t + c] * cosine * lobe;
                }
                for (int c = 0; c < 3; ++c) {
                    float albedo = options.albedo ? (*options.albedo)[size_t(c)]
                                   : receiver.albedo.empty() ? 1.0f : receiver.albedo[3 * v + c];
                    result.radiance[3 * v + c] = float(albedo / std::numbers::pi * sum[c] + glossySum[c]);
                }
            }
            rays += blockRays;
            progress.add(range.size());
        });
        progress.finish();
    });
    result.rays = rays;
    return result;
}

} // namespace prt
