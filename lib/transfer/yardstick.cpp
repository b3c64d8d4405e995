// The bare-Embree yardstick: the shadowed direct pass's rays with nothing but rtcOccluded1 around them.
#include "transfer.h"

#include "core.h"
#include "rays.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <ctime>

namespace prt {

RayThroughput castBareOcclusionRays(const TriMesh& mesh, const TransferOptions& options) {
    rays::validateMesh(mesh);
    size_t begin, end;
    rays::clipRange(mesh, options, begin, end);
    if (options.samples < 1 || options.samples > kMaxTransferSamples)
        throw Error("", "samples", std::to_string(options.samples) + " outside 1.." +
                                       std::to_string(kMaxTransferSamples), kExitUsage);
    int samples = options.samples;
    float offset = rayOffset(mesh);
    rays::Hemisphere directions = rays::hemisphere(samples);
    size_t blockCount = (end - begin + rays::kBlockVertices - 1) / rays::kBlockVertices;

    RayThroughput result;
    std::atomic<uint64_t> occluded{0};
    tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        rays::Scene scene(mesh);
        double start = nowSeconds();
        std::clock_t cpuStart = std::clock();
        tbb::parallel_for(tbb::blocked_range<size_t>(0, blockCount, 1), [&](const tbb::blocked_range<size_t>& blocks) {
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            uint64_t blocked = 0;
            for (size_t block = blocks.begin(); block != blocks.end(); ++block) {
                size_t first = begin + block * rays::kBlockVertices;
                size_t last = std::min(first + rays::kBlockVertices, end);
                for (size_t v = first; v < last; ++v) {
                    rays::Fan fan = rays::fan(mesh, v, options.seed, offset);
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
    result.rays = uint64_t(end - begin) * samples;
    result.occluded = occluded;
    return result;
}

} // namespace prt
