// The mesh in an Embree 3 scene: nearest hits with their shading frame, and shadow rays.
#include "path_tracer.h"

#include "core.h"
#include "material.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace prt::pathtrace {

namespace {

void normalize(float v[3]) {
    float length = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int c = 0; c < 3; ++c) v[c] /= length;
}

RTCRay makeRay(const float origin[3], const float d[3]) {
    RTCRay ray{};
    spawnRay(ray, origin, d[0], d[1], d[2]); // the shared spawn rule (lib/raycast)
    return ray;
}

} // namespace

SceneTracer::SceneTracer(const TriMesh& mesh, const std::optional<std::array<float, 3>>& constantAlbedo,
                         const Surface* surface)
    // EmbreeScene is robust: no rays slip between adjacent triangles, so closed cavities never leak light.
    : mesh_(mesh), constantAlbedo_(constantAlbedo), surface_(surface), embree_(mesh, surface),
      rayOffset_(prt::rayOffset(mesh)) {
    if (surface_) vertexAlbedo_ = vertexDiffuseAlbedo(*surface_);
}

void SceneTracer::albedoAt(const uint32_t* triangle, float u, float v, float out[3]) const {
    if (surface_ && triangle[0] == triangle[1] && triangle[1] == triangle[2]) {
        std::copy_n(&vertexAlbedo_[3 * size_t(triangle[0])], 3, out); // a vertex (vertexPoint)
    } else if (surface_) {
        std::array<float, 3> albedo = diffuseAlbedoAt(*surface_, size_t(triangle - mesh_.indices.data()) / 3, u, v);
        std::copy(albedo.begin(), albedo.end(), out);
    } else if (constantAlbedo_) {
        std::copy(constantAlbedo_->begin(), constantAlbedo_->end(), out);
    } else if (mesh_.albedo.empty()) {
        std::fill(out, out + 3, 1.0f);
    } else {
        const float* a0 = &mesh_.albedo[triangle[0] * 3];
        const float* a1 = &mesh_.albedo[triangle[1] * 3];
        const float* a2 = &mesh_.albedo[triangle[2] * 3];
        for (int c = 0; c < 3; ++c) out[c] = (1.0f - u - v) * a0[c] + u * a1[c] + v * a2[c];
    }
}

ShadingPoint SceneTracer::vertexPoint(uint32_t vertex) const {
    ShadingPoint point;
    for (int c = 0; c < 3; ++c) {
        point.position[c] = mesh_.positions[vertex * 3 + c];
        point.normal[c] = mesh_.normals[vertex * 3 + c];
    }
    normalize(point.normal);
    std::copy(point.normal, point.normal + 3, point.offsetNormal);
    // A vertex reads its own albedo: the first corner of a triangle made of it alone.
    uint32_t corners[3] = {vertex, vertex, vertex};
    albedoAt(corners, 0.0f, 0.0f, point.albedo);
    return point;
}

HitKind SceneTracer::intersect(const float origin[3], const float d[3], ShadingPoint* point) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rayHit{};
    rayHit.ray = makeRay(origin, d);
    rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(embree_.scene, &context, &rayHit);
    if (rayHit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return HitKind::Miss;

    const uint32_t triangleIndex = embree_.flatTriangle(rayHit.hit);
    const uint32_t* triangle = &mesh_.indices[size_t(triangleIndex) * 3];
    const float* p0 = &mesh_.positions[triangle[0] * 3];
    const float* p1 = &mesh_.positions[triangle[1] * 3];
    const float* p2 = &mesh_.positions[triangle[2] * 3];
    // The winding gives the front side (counter-clockwise seen from it, docs/conventions.md).
    float faceNormal[3];
    triangleNormal(mesh_, triangleIndex, faceNormal);
    if (faceNormal[0] * d[0] + faceNormal[1] * d[1] + faceNormal[2] * d[2] > 0.0f) return HitKind::BackFace;

    float u = rayHit.hit.u, v = rayHit.hit.v, w = 1.0f - u - v;
    const float* n0 = &mesh_.normals[triangle[0] * 3];
    const float* n1 = &mesh_.normals[triangle[1] * 3];
    const float* n2 = &mesh_.normals[triangle[2] * 3];
    for (int c = 0; c < 3; ++c) {
        point->position[c] = w * p0[c] + u * p1[c] + v * p2[c];
        point->normal[c] = w * n0[c] + u * n1[c] + v * n2[c];
        point->offsetNormal[c] = faceNormal[c];
    }
    normalize(point->normal);
    normalize(point->offsetNormal);
    albedoAt(triangle, u, v, point->albedo);
    return HitKind::FrontFace;
}

bool SceneTracer::occluded(const float origin[3], const float d[3]) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray = makeRay(origin, d);
    rtcOccluded1(embree_.scene, &context, &ray);
    return ray.tfar < 0.0f; // Embree marks an occluded ray with tfar = -inf
}

} // namespace prt::pathtrace
