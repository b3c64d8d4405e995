// The one place prt builds Embree 3 scenes: every stage that casts rays (transfer, bake, reference) traces the
// same triangles with the same setup, and offsets ray origins by the same model-relative distance.
#pragma once

#include "bundle.h"

#include <embree3/rtcore.h>

#include <array>
#include <cstddef>

namespace prt {

// An Embree device and committed scene over a mesh's triangles (geometry 0, primitive i = triangle i), build
// quality high; both released on destruction.
// Needs indices in range (lib/mesh validation guarantees them). `robust` sets RTC_SCENE_FLAG_ROBUST, so no ray
// slips between adjacent triangles (closed cavities never leak), at some cost in speed.
// Throws prt::Error(kExitFailure) when Embree fails, naming the step.
struct EmbreeScene {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;

    explicit EmbreeScene(const TriMesh& mesh, bool robust = false);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;
};

// Throws prt::Error(kExitFailure) naming `step` when `device` holds an error.
void throwIfEmbreeFailed(RTCDevice device, const char* step);

// Where rays leave a surface point: this far along its normal, with tnear the same, so that they clear float
// error at any model scale. It is 1e-4 times the bounding-box diagonal (0 for an empty mesh).
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

} // namespace prt
