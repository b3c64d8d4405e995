// The Embree scene, the ray offset and the spawn rule every ray-casting stage shares.
#include "raycast.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace prt {

void throwIfEmbreeFailed(RTCDevice device, const char* step) {
    RTCError error = rtcGetDeviceError(device);
    if (error != RTC_ERROR_NONE)
        throw Error("", std::string("embree ") + step, "failed with error code " + std::to_string(int(error)),
                    kExitFailure);
}

EmbreeScene::EmbreeScene(const TriMesh& mesh) {
    device = rtcNewDevice(nullptr);
    if (!device)
        throw Error("", "embree device",
                    "cannot create (error code " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")", kExitFailure);
    try {
        scene = rtcNewScene(device);
        rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
        if (mesh.triangleCount() > 0) {
            RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
            rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_HIGH);
            // Embree-owned buffers: Embree reads vertex buffers 16 bytes at a time, past a tight float3 array's end.
            auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
                geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertexCount()));
            auto* triangles = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
                geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), mesh.triangleCount()));
            if (!vertices || !triangles) {
                rtcReleaseGeometry(geometry);
                throwIfEmbreeFailed(device, "buffers");
                throw Error("", "embree buffers", "cannot allocate", kExitFailure);
            }
            std::copy(mesh.positions.begin(), mesh.positions.end(), vertices);
            std::copy(mesh.indices.begin(), mesh.indices.end(), triangles);
            rtcCommitGeometry(geometry);
            rtcAttachGeometry(scene, geometry);
            rtcReleaseGeometry(geometry);
        }
        rtcCommitScene(scene);
        throwIfEmbreeFailed(device, "scene build");
    } catch (...) {
        if (scene) rtcReleaseScene(scene);
        rtcReleaseDevice(device);
        throw;
    }
}

EmbreeScene::~EmbreeScene() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
}

float rayOffset(const TriMesh& mesh) {
    if (mesh.positions.empty()) return 0.0f;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        lo[i % 3] = std::min(lo[i % 3], mesh.positions[i]);
        hi[i % 3] = std::max(hi[i % 3], mesh.positions[i]);
    }
    double diagonal = 0.0;
    for (int a = 0; a < 3; ++a) diagonal += double(hi[a] - lo[a]) * (hi[a] - lo[a]);
    return float(1e-4 * std::sqrt(diagonal));
}

} // namespace prt
