// The bare-Embree yardstick: the shadowed direct pass's rays with nothing but rtcOccluded1 around them.
#include "transfer.h"

#include "core.h"
#include "rays.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <ctime>

namespace prt {

namespace {

// Casts every receiver's shadowed-mode rays with rtcOccluded1, in the direct pass's blocks.
RayThroughput castBare(const TriMesh& geometry, const Receivers& receivers, const TransferOptions& options) {
    if (options.samples < 1 || options.samples > kMaxTransferSamples)
        throw Error("", "samples", std::to_string(options.samples) + " outside 1.." +
                                       std::to_string(kMaxTransferSamples), kExitUsage);
    int samples = options.samples;
    float offset = rayOffset(geometry);
    rays::Hemisphere directions = rays::hemisphere(samples);
    size_t blockCount = (receivers.count + rays::kBlockVertices - 1) / rays::kBlockVertices;

    RayThroughput result;
    std::atomic<uint64_t> occluded{0};
    tbb::task_arena arena(arenaConcurrency(options.threads));
    arena.execute([&] {
        EmbreeScene scene(geometry);
        double start = nowSeconds();
        std::clock_t cpuStart = std::clock();
        tbb::parallel_for(tbb::blocked_range<size_t>(0, blockCount, 1), [&](const tbb::blocked_range<size_t>& blocks) {
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            uint64_t blocked = 0;
            for (size_t block = blocks.begin(); block != blocks.end(); ++block) {
                size_t first = block * rays::kBlockVertices;
                size_t last = std::min(first + rays::kBlockVertices, receivers.count);
                for (size_t v = first; v < last; ++v) {
                    rays::Fan fan = rays::fan(receivers, v, options.seed, offset);
                    for (int k = 0; k < samples; ++k) {
                        RTCRay ray;
                        rays::setRay(fan, directions, k, offset, ray);
                        rtcOccluded1(scene.scene, &context, &ray);
                        blocked += ray.tfar < 0.0f;
                    }
                }
            }
            occluded += blocked;
        });
        result.cpuSeconds = double(std::clock() - cpuStart) / CLOCKS_PER_SEC;
        result.seconds = nowSeconds() - start;
    });
    result.rays = uint64_t(receivers.count) * samples;
    result.occluded = occluded;
    return result;
}

} // namespace

RayThroughput castBareOcclusionRays(const TriMesh& mesh, const TransferOptions& options) {
    rays::validateMesh(mesh);
    size_t begin, end;
    rays::clipRange(mesh, options, begin, end);
    const std::vector<float> spawn = spawnNormals(mesh, begin, end);
    return castBare(mesh, rays::vertexReceivers(mesh, options, begin, end, spawn.data()), options);
}

RayThroughput castBareOcclusionRaysAt(const TriMesh& geometry, const Receivers& receivers,
                                      const TransferOptions& options) {
    rays::validateMesh(geometry);
    rays::validateReceivers(receivers);
    return castBare(geometry, receivers, options);
}

} // namespace prt
