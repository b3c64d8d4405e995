// The Embree scene, the ray offset and the spawn rule every ray-casting stage shares.
#include "raycast.h"

#include "core.h"
#include "material.h"
#include "position_groups.h"

#include <algorithm>
#include <array>
#include <atomic>
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

namespace {

// Embree filter for cut-out materials: a hit where the surface is absent is no hit, so the ray goes on.
void cutoutFilter(const RTCFilterFunctionNArguments* args) {
    const EmbreeScene::FilterData& data = *static_cast<const EmbreeScene::FilterData*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        uint32_t triangle = data.scene->flatTriangle(RTCHitN_instID(args->hit, args->N, i, 0),
                                                     RTCHitN_geomID(args->hit, args->N, i),
                                                     RTCHitN_primID(args->hit, args->N, i));
        if (!presentAt(*data.surface, triangle, RTCHitN_u(args->hit, args->N, i), RTCHitN_v(args->hit, args->N, i)))
            args->valid[i] = 0;
    }
}

// A triangle geometry of `triangles` (flattened triangle indices) with the vertices they use, committed and
// attached to `scene`. Embree-owned buffers: Embree reads vertex buffers 16 bytes at a time, past a tight float3
// array's end.
void attachTriangles(RTCDevice device, RTCScene scene, const TriMesh& mesh, const uint32_t* triangles, size_t count,
                     uint32_t firstVertex, uint32_t vertexCount, EmbreeScene::FilterData* filter) {
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_HIGH);
    auto* vertices = static_cast<float*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertexCount));
    auto* indices = static_cast<uint32_t*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), count));
    if (!vertices || !indices) {
        rtcReleaseGeometry(geometry);
        throwIfEmbreeFailed(device, "buffers");
        throw Error("", "embree buffers", "cannot allocate", kExitFailure);
    }
    std::copy_n(mesh.positions.begin() + 3 * size_t(firstVertex), 3 * size_t(vertexCount), vertices);
    for (size_t t = 0; t < count; ++t)
        for (int k = 0; k < 3; ++k) indices[3 * t + k] = mesh.indices[3 * size_t(triangles ? triangles[t] : t) + k] - firstVertex;
    if (filter) {
        rtcSetGeometryUserData(geometry, filter);
        rtcSetGeometryIntersectFilterFunction(geometry, cutoutFilter);
        rtcSetGeometryOccludedFilterFunction(geometry, cutoutFilter);
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene, geometry);
    rtcReleaseGeometry(geometry);
}

using Matrix = std::array<double, 16>; // column-major, glTF's

Matrix inverseAffine(const Matrix& m) {
    // The linear part's inverse by cofactors, then the translation.
    const double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
    const double A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
    const double det = a * A + b * B + c * C;
    Matrix inv{};
    const double r[3][3] = {{A / det, -(b * i - c * h) / det, (b * f - c * e) / det},
                            {B / det, (a * i - c * g) / det, -(a * f - c * d) / det},
                            {C / det, -(a * h - b * g) / det, (a * e - b * d) / det}};
    for (int row = 0; row < 3; ++row)
        for (int column = 0; column < 3; ++column) inv[column * 4 + row] = r[row][column];
    for (int row = 0; row < 3; ++row)
        inv[12 + row] = -(r[row][0] * m[12] + r[row][1] * m[13] + r[row][2] * m[14]);
    inv[15] = 1.0;
    return inv;
}

Matrix multiply(const Matrix& x, const Matrix& y) {
    Matrix out{};
    for (int column = 0; column < 4; ++column)
        for (int row = 0; row < 4; ++row)
            for (int k = 0; k < 4; ++k) out[column * 4 + row] += x[k * 4 + row] * y[column * 4 + k];
    return out;
}

// The scene of a flattened glTF scene with repeated meshes as instances (raycast.h). Returns false, building
// nothing, when no mesh is placed twice.
bool buildInstanced(EmbreeScene& embree, const TriMesh& mesh, const SceneAsset& asset, EmbreeScene::FilterData* filter) {
    struct Placement {
        uint32_t firstReceiver, receivers; // the consecutive receivers one node gives one mesh
    };
    std::vector<Placement> placements;
    std::vector<std::vector<uint32_t>> placementsOfMesh;
    for (uint32_t r = 0; r < asset.receivers.size(); ++r) {
        const SceneReceiver& receiver = asset.receivers[r];
        if (r > 0 && asset.receivers[r - 1].node == receiver.node && asset.receivers[r - 1].mesh == receiver.mesh) {
            ++placements.back().receivers;
            continue;
        }
        placements.push_back({r, 1});
        // Mirrored placements get a prototype of their own: their flattened triangles have the winding flipped, so
        // a hit's barycentrics on the unmirrored prototype would name their corners in the wrong order.
        const size_t group = 2 * size_t(receiver.mesh) + (receiver.mirrored ? 1 : 0);
        if (placementsOfMesh.size() <= group) placementsOfMesh.resize(group + 1);
        placementsOfMesh[group].push_back(uint32_t(placements.size() - 1));
    }
    bool repeated = false;
    for (const std::vector<uint32_t>& list : placementsOfMesh) repeated = repeated || list.size() > 1;
    if (!repeated) return false;

    for (const SceneReceiver& receiver : asset.receivers) embree.receiverTriangles.push_back(receiver.firstTriangle);
    auto receiverTriangles = [&](uint32_t r) {
        const SceneReceiver& receiver = asset.receivers[r];
        std::vector<uint32_t> triangles(receiver.triangleCount);
        for (uint32_t t = 0; t < receiver.triangleCount; ++t) triangles[t] = receiver.firstTriangle + t;
        return triangles;
    };
    for (const std::vector<uint32_t>& list : placementsOfMesh) {
        if (list.empty()) continue;
        const Placement& first = placements[list[0]];
        // A prototype's geometry p is its placement's receiver p, so every receiver needs triangles of its own.
        bool instanceable = list.size() > 1;
        for (uint32_t r = first.firstReceiver; r < first.firstReceiver + first.receivers; ++r)
            instanceable = instanceable && asset.receivers[r].triangleCount > 0;
        if (!instanceable) {
            // Placed once (or not instanceable): each receiver is a world-space geometry of the top-level scene.
            for (uint32_t k : list) {
                const Placement& placement = placements[k];
                for (uint32_t r = placement.firstReceiver; r < placement.firstReceiver + placement.receivers; ++r) {
                    const SceneReceiver& receiver = asset.receivers[r];
                    if (receiver.triangleCount == 0) continue;
                    std::vector<uint32_t> triangles = receiverTriangles(r);
                    attachTriangles(embree.device, embree.scene, mesh, triangles.data(), triangles.size(),
                                    receiver.firstVertex, receiver.vertexCount, filter);
                    embree.topReceiver.push_back(r);
                }
            }
            continue;
        }
        // The prototype: the first placement's receivers in its world space, geometry p = its receiver p.
        RTCScene prototype = rtcNewScene(embree.device);
        embree.prototypes.push_back(prototype);
        rtcSetSceneFlags(prototype, RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(prototype, RTC_BUILD_QUALITY_HIGH);
        for (uint32_t r = first.firstReceiver; r < first.firstReceiver + first.receivers; ++r) {
            const SceneReceiver& receiver = asset.receivers[r];
            std::vector<uint32_t> triangles = receiverTriangles(r);
            attachTriangles(embree.device, prototype, mesh, triangles.data(), triangles.size(), receiver.firstVertex,
                            receiver.vertexCount, filter);
        }
        rtcCommitScene(prototype);
        const Matrix toFirst = inverseAffine(asset.receivers[first.firstReceiver].world);
        for (uint32_t k : list) {
            const Placement& placement = placements[k];
            Matrix transform = multiply(asset.receivers[placement.firstReceiver].world, toFirst);
            float columns[12];
            for (int column = 0; column < 4; ++column)
                for (int row = 0; row < 3; ++row) columns[column * 3 + row] = float(transform[column * 4 + row]);
            RTCGeometry instance = rtcNewGeometry(embree.device, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(instance, prototype);
            rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, columns);
            rtcCommitGeometry(instance);
            rtcAttachGeometry(embree.scene, instance);
            rtcReleaseGeometry(instance);
            embree.topReceiver.push_back(placement.firstReceiver);
        }
    }
    return true;
}

// Bytes Embree holds on this process's devices, from its memory monitor: what a scene's log reports as the size
// of its ray-tracing structures (BVH and geometry), instanced or not.
std::atomic<int64_t> embreeBytes{0};

bool countEmbreeBytes(void*, ssize_t bytes, bool) {
    embreeBytes += int64_t(bytes);
    return true;
}

} // namespace

EmbreeScene::EmbreeScene(const TriMesh& mesh, const Surface* surface) {
    device = rtcNewDevice(nullptr);
    if (!device)
        throw Error("", "embree device",
                    "cannot create (error code " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")", kExitFailure);
    // Only a scene logs its structures' size, so only a scene's device pays for the monitor on every allocation.
    const bool sceneAsset = surface && surface->asset;
    if (sceneAsset) rtcSetDeviceMemoryMonitorFunction(device, countEmbreeBytes, nullptr);
    const int64_t bytesBefore = embreeBytes;
    try {
        scene = rtcNewScene(device);
        rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
        filterData = {surface, this};
        FilterData* filter = surface && surface->cutouts ? &filterData : nullptr;
        bool instances = surface && surface->instancing && surface->asset &&
                         buildInstanced(*this, mesh, *surface->asset, filter);
        if (!instances && mesh.triangleCount() > 0)
            attachTriangles(device, scene, mesh, nullptr, mesh.triangleCount(), 0, uint32_t(mesh.vertexCount()), filter);
        rtcCommitScene(scene);
        throwIfEmbreeFailed(device, "scene build");
        if (sceneAsset)
            logInfo("ray tracing: " + std::to_string(surface->asset->receivers.size()) + " receivers, " +
                    (instances ? std::to_string(prototypes.size()) + " meshes built once and placed as instances"
                               : std::string("every triangle in one BVH")) +
                    ": " + std::to_string(double(embreeBytes - bytesBefore) / (1024.0 * 1024.0)) +
                    " MiB of Embree structures");
    } catch (...) {
        if (scene) rtcReleaseScene(scene);
        for (RTCScene prototype : prototypes) rtcReleaseScene(prototype);
        rtcReleaseDevice(device);
        throw;
    }
}

EmbreeScene::~EmbreeScene() {
    rtcReleaseScene(scene);
    for (RTCScene prototype : prototypes) rtcReleaseScene(prototype);
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

std::vector<float> spawnNormals(const TriMesh& mesh) { return spawnNormals(mesh, 0, mesh.vertexCount()); }

std::vector<float> spawnNormals(const TriMesh& mesh, size_t begin, size_t end) {
    const size_t count = mesh.vertexCount();
    end = std::min(end, count);
    begin = std::min(begin, end);
    // The groups of the range's positions; every vertex at one of them belongs to its group.
    const PositionGroups groups = groupPositions(mesh, begin, end);
    const std::vector<int32_t>& group = groups.group;
    // Each group's sum over its triangles in triangle order, corner by corner, whatever the range.
    std::vector<double> sum(3 * groups.groupCount, 0.0);
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t* corner = &mesh.indices[3 * t];
        if (group[corner[0]] < 0 && group[corner[1]] < 0 && group[corner[2]] < 0) continue;
        const float* p0 = &mesh.positions[3 * corner[0]];
        const float* p1 = &mesh.positions[3 * corner[1]];
        const float* p2 = &mesh.positions[3 * corner[2]];
        double e1[3], e2[3];
        for (int c = 0; c < 3; ++c) e1[c] = double(p1[c]) - p0[c], e2[c] = double(p2[c]) - p0[c];
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; ++k)
            if (group[corner[k]] >= 0)
                for (int c = 0; c < 3; ++c) sum[3 * size_t(group[corner[k]]) + c] += n[c];
    }
    std::vector<float> normals(3 * (end - begin));
    const bool haveNormal = mesh.normals.size() == mesh.positions.size();
    for (size_t v = begin; v < end; ++v) {
        const double* s = &sum[3 * size_t(group[v])];
        double length = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        double fallback[3] = {0.0, 0.0, 1.0};
        if (haveNormal) {
            const float* n = &mesh.normals[3 * v];
            double nl = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
            if (nl > 0) fallback[0] = n[0] / nl, fallback[1] = n[1] / nl, fallback[2] = n[2] / nl;
        }
        // Summed normals that (nearly) cancel say nothing about the side; nor does a vertex on no triangle.
        double scale = 0.0;
        for (int c = 0; c < 3; ++c) scale += std::fabs(s[c]);
        bool usable = length > 1e-6 * scale && length > 0.0;
        // On the side the rays leave: the shading normal's (an inside-out mesh keeps its rays inside).
        double side = usable && haveNormal ? (s[0] * fallback[0] + s[1] * fallback[1] + s[2] * fallback[2]) / length : 1.0;
        if (std::fabs(side) < 1e-3) usable = false;
        double sign = side < 0.0 ? -1.0 : 1.0;
        for (int c = 0; c < 3; ++c) normals[3 * (v - begin) + c] = float(usable ? sign * s[c] / length : fallback[c]);
    }
    return normals;
}

} // namespace prt
