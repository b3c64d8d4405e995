// The one place prt builds Embree 3 scenes: every stage that casts rays (transfer, bake, reference) traces the
// same triangles with the same setup, and offsets ray origins by the same model-relative distance.
#pragma once

#include "bundle.h"

#include <embree3/rtcore.h>

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

// ---- the one ray-spawn rule (transfer, bake and reference all use it) ----------------------------------------
// A ray leaving surface point `position` starts at position + offset * normal (offset = rayOffset(mesh), normal
// unit and on the side the ray leaves), with tnear 0 and tfar infinity, traced in a robust EmbreeScene. The
// offset is applied once: a tnear as well would skip geometry nearer than the offset, which at a crease is the
// neighbouring face, and rays would leak out of closed rooms through their edges.
inline void spawnOrigin(const float position[3], const float normal[3], float offset, float origin[3]) {
    for (int c = 0; c < 3; ++c) origin[c] = float(double(position[c]) + double(offset) * double(normal[c]));
}

// Fills `ray` from an origin spawnOrigin gave and a direction: tnear 0, tfar infinity, mask all, time 0.
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

} // namespace prt
