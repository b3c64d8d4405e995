// The cage projection: from just outside the low surface, along its normal, onto the high-resolution surface.
#include "bake.h"

#include "core.h"
#include "raycast.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace prt {

CageProjection projectOntoHigh(const TriMesh& high, const std::vector<float>& positions,
                               const std::vector<float>& normals, float cage) {
    if (!(cage > 0.0f) || !std::isfinite(cage)) throw Error("", "--cage", "must be positive and finite", kExitUsage);
    if (high.normals.size() != high.positions.size()) throw Error("", "high mesh", "has no per-vertex normals");
    size_t count = positions.size() / 3;
    CageProjection out;
    out.positions = positions;
    out.normals = normals;
    out.hit.assign(count, 0);
    out.triangle.assign(count, UINT32_MAX);
    out.barycentric.assign(3 * count, 0.0f);
    EmbreeScene scene(high);
    std::atomic<size_t> misses{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1024), [&](const tbb::blocked_range<size_t>& range) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        size_t blockMisses = 0;
        for (size_t i = range.begin(); i != range.end(); ++i) {
            const float* p = &positions[3 * i];
            const float* n = &normals[3 * i];
            RTCRayHit rayHit;
            RTCRay& ray = rayHit.ray;
            ray.org_x = p[0] + cage * n[0], ray.org_y = p[1] + cage * n[1], ray.org_z = p[2] + cage * n[2];
            ray.dir_x = -n[0], ray.dir_y = -n[1], ray.dir_z = -n[2];
            ray.tnear = 0.0f;
            ray.tfar = 2.0f * cage;
            ray.time = 0.0f;
            ray.mask = 0xFFFFFFFFu;
            ray.id = 0;
            ray.flags = 0;
            rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(scene.scene, &context, &rayHit);
            if (rayHit.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
                ++blockMisses;
                continue;
            }
            const uint32_t* corner = &high.indices[3 * size_t(rayHit.hit.primID)];
            double w[3] = {1.0 - rayHit.hit.u - rayHit.hit.v, rayHit.hit.u, rayHit.hit.v};
            double q[3] = {0, 0, 0}, m[3] = {0, 0, 0};
            for (int k = 0; k < 3; ++k)
                for (int a = 0; a < 3; ++a) {
                    q[a] += w[k] * high.positions[3 * size_t(corner[k]) + a];
                    m[a] += w[k] * high.normals[3 * size_t(corner[k]) + a];
                }
            double length = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
            if (!(length > 1e-12)) {
                // Opposite vertex normals cancel; keep the low normal, which faces the same way.
                m[0] = n[0], m[1] = n[1], m[2] = n[2], length = 1.0;
            }
            for (int a = 0; a < 3; ++a) {
                out.positions[3 * i + a] = float(q[a]);
                out.normals[3 * i + a] = float(m[a] / length);
            }
            out.hit[i] = 1;
            out.triangle[i] = rayHit.hit.primID;
            for (int k = 0; k < 3; ++k) out.barycentric[3 * i + k] = float(w[k]);
        }
        misses += blockMisses;
    });
    out.misses = misses;
    return out;
}

} // namespace prt
