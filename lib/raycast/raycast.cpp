// The Embree scene, the ray offset and the spawn rule every ray-casting stage shares.
#include "raycast.h"

#include "core.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <cmath>
#include <numbers>
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

namespace {

void cross(const float a[3], const float b[3], float out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

float length(const float a[3]) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

void normalize(float a[3]) {
    float n = length(a);
    for (int c = 0; c < 3; ++c) a[c] /= n;
}

} // namespace

PinholeRays pinholeRays(const PinholeCamera& camera) {
    if (camera.width <= 0 || camera.height <= 0) throw Error("", "camera", "image size must be positive", kExitUsage);
    PinholeRays rays;
    for (int c = 0; c < 3; ++c) rays.forward[c] = camera.target[c] - camera.eye[c];
    cross(rays.forward, camera.up.data(), rays.right);
    cross(rays.right, rays.forward, rays.up);
    if (!(length(rays.right) > 0.0f))
        throw Error("", "camera", "eye equals target or up is parallel to the view direction", kExitUsage);
    normalize(rays.forward);
    normalize(rays.right);
    normalize(rays.up);
    rays.halfHeight = std::tan(camera.fovyDegrees * std::numbers::pi_v<float> / 360.0f);
    rays.halfWidth = rays.halfHeight * float(camera.width) / float(camera.height);
    rays.width = camera.width;
    rays.height = camera.height;
    return rays;
}

void pinholeRayDirection(const PinholeRays& rays, size_t pixel, float d[3]) {
    float sx = (2.0f * (float(pixel % rays.width) + 0.5f) / float(rays.width) - 1.0f) * rays.halfWidth;
    float sy = (1.0f - 2.0f * (float(pixel / rays.width) + 0.5f) / float(rays.height)) * rays.halfHeight;
    for (int c = 0; c < 3; ++c) d[c] = rays.forward[c] + sx * rays.right[c] + sy * rays.up[c];
    normalize(d);
}

std::vector<float> spawnNormals(const TriMesh& mesh) {
    const size_t count = mesh.vertexCount();
    // Vertices at the same position form one group: sort vertex indices by their position's bits.
    auto bits = [&](size_t v) {
        std::array<uint32_t, 3> key;
        std::memcpy(key.data(), &mesh.positions[3 * v], sizeof key);
        for (uint32_t& k : key) k = k == 0x80000000u ? 0u : k; // -0 and +0 are one position
        return key;
    };
    std::vector<uint32_t> order(count);
    for (size_t v = 0; v < count; ++v) order[v] = uint32_t(v);
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return bits(a) < bits(b); });
    std::vector<uint32_t> group(count);
    size_t groups = 0;
    for (size_t i = 0; i < count; ++i) {
        if (i > 0 && bits(order[i]) != bits(order[i - 1])) ++groups;
        group[order[i]] = uint32_t(groups);
    }
    std::vector<double> sum(3 * (count ? groups + 1 : 0), 0.0);
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t* corner = &mesh.indices[3 * t];
        const float* p0 = &mesh.positions[3 * corner[0]];
        const float* p1 = &mesh.positions[3 * corner[1]];
        const float* p2 = &mesh.positions[3 * corner[2]];
        double e1[3], e2[3];
        for (int c = 0; c < 3; ++c) e1[c] = double(p1[c]) - p0[c], e2[c] = double(p2[c]) - p0[c];
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) sum[3 * group[corner[k]] + c] += n[c];
    }
    std::vector<float> normals(3 * count);
    for (size_t v = 0; v < count; ++v) {
        const double* s = &sum[3 * group[v]];
        double length = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        double fallback[3] = {0.0, 0.0, 1.0};
        if (mesh.normals.size() == mesh.positions.size()) {
            const float* n = &mesh.normals[3 * v];
            double nl = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
            if (nl > 0) fallback[0] = n[0] / nl, fallback[1] = n[1] / nl, fallback[2] = n[2] / nl;
        }
        // Summed normals that (nearly) cancel say nothing about the side; nor does a vertex on no triangle.
        double scale = 0.0;
        for (int c = 0; c < 3; ++c) scale += std::fabs(s[c]);
        bool usable = length > 1e-6 * scale && length > 0.0;
        // On the side the rays leave: the shading normal's (an inside-out mesh keeps its rays inside).
        bool haveNormal = mesh.normals.size() == mesh.positions.size();
        double side = usable && haveNormal ? (s[0] * fallback[0] + s[1] * fallback[1] + s[2] * fallback[2]) / length : 1.0;
        if (std::fabs(side) < 1e-3) usable = false;
        double sign = side < 0.0 ? -1.0 : 1.0;
        for (int c = 0; c < 3; ++c) normals[3 * v + c] = float(usable ? sign * s[c] / length : fallback[c]);
    }
    return normals;
}

} // namespace prt
