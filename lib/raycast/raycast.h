// The one place prt builds Embree 3 scenes: every stage that casts rays (transfer, bake, reference) traces the
// same triangles with the same setup, and offsets ray origins by the same model-relative distance.
#pragma once

#include "bundle.h"

#include <embree3/rtcore.h>

#include <array>
#include <cstddef>
#include <vector>

namespace prt {

// An Embree device and committed scene over a mesh's triangles (geometry 0, primitive i = triangle i), build
// quality high, RTC_SCENE_FLAG_ROBUST (so no ray slips between adjacent triangles: closed rooms never leak);
// both released on destruction. Part of the spawn rule below, so there is no non-robust variant.
// Needs indices in range (lib/mesh validation guarantees them).
// Throws prt::Error(kExitFailure) when Embree fails, naming the step.
struct EmbreeScene {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;

    explicit EmbreeScene(const TriMesh& mesh);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;
};

// Throws prt::Error(kExitFailure) naming `step` when `device` holds an error.
void throwIfEmbreeFailed(RTCDevice device, const char* step);

// How far rays leave a surface point along its normal, so that they clear float error at any model scale:
// 1e-4 times the bounding-box diagonal (0 for an empty mesh).
float rayOffset(const TriMesh& mesh);

// ---- the pinhole camera ------------------------------------------------------------------------------------
// One camera for every image prt renders (`prt reference --image`, `prt render`), so their pixels line up.
// Pixel (x, y), row 0 at the top, looks through its centre: with f = forward (target - eye), r = f x up and
// u = r x f normalised, the ray is f + (2 (x + 0.5) / width - 1) tan(fovy / 2) aspect r
// + (1 - 2 (y + 0.5) / height) tan(fovy / 2) u, aspect = width / height. three.js's PerspectiveCamera with
// fov = fovy, aspect = width / height, placed at eye with up and lookAt(target) is the same projection.
struct PinholeCamera {
    std::array<float, 3> eye{0, 0, 1};
    std::array<float, 3> target{0, 0, 0};
    std::array<float, 3> up{0, 1, 0};
    float fovyDegrees = 40.0f;
    int width = 0;
    int height = 0;
};

// A camera's unit frame and image-plane half extents, ready to make rays.
struct PinholeRays {
    float forward[3], right[3], up[3];
    float halfWidth = 0, halfHeight = 0;
    int width = 0, height = 0;
};
// Throws prt::Error(kExitUsage) for a non-positive size, eye equal to target or up parallel to the view.
PinholeRays pinholeRays(const PinholeCamera& camera);
// The unit direction d of the ray through the centre of pixel index `pixel` (y * width + x), from camera.eye.
void pinholeRayDirection(const PinholeRays& rays, size_t pixel, float d[3]);
// ---- the one ray-spawn rule (transfer, bake and reference all use it) ----------------------------------------
// A ray leaving a surface point starts at position + offset * spawnNormal with tnear 0 and tfar infinity, in a
// robust EmbreeScene; offset = rayOffset(mesh). The offset is applied once: a tnear of `offset` as well (the old
// transfer rule) skips whatever is nearer than the offset, which at a crease is the neighbouring face, and rays
// leak out of closed rooms through their edges. spawnNormal is the geometric normal of the surface at the point:
// for a point inside a triangle, the triangle's; for a mesh vertex, spawnNormals() below, the mean over every
// triangle that touches its position, so that at a crease or corner (where the vertex lies in the other faces'
// planes) the origin leaves all of them, and a ray into a neighbouring face hits it at t > 0.
inline void spawnOrigin(const float position[3], const float spawnNormal[3], float offset, float origin[3]) {
    for (int c = 0; c < 3; ++c) origin[c] = float(double(position[c]) + double(offset) * double(spawnNormal[c]));
}

// Fills `ray` for direction (dx, dy, dz) from an origin spawnOrigin gave: tnear 0, tfar infinity, mask all, time 0.
inline void spawnRay(RTCRay& ray, const float origin[3], float dx, float dy, float dz) {
    ray.org_x = origin[0];
    ray.org_y = origin[1];
    ray.org_z = origin[2];
    ray.dir_x = dx;
    ray.dir_y = dy;
    ray.dir_z = dz;
    ray.tnear = 0.0f;
    ray.tfar = __builtin_inff();
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
}

// Per vertex [vertexCount][3]: the unit mean of the area-weighted geometric normals of every triangle that touches
// a vertex at exactly the same position, split vertices included, turned to the vertex normal's side (where the
// rays leave). Where they cancel (two-sided sheets), are perpendicular to the vertex normal, or the vertex is on no
// triangle: the vertex normal (normalised), else +z.
std::vector<float> spawnNormals(const TriMesh& mesh);

} // namespace prt
