// The one place prt builds Embree 3 scenes: every stage that casts rays (transfer, bake, reference) traces the
// same triangles with the same setup, and offsets ray origins by the same model-relative distance.
#pragma once

#include "bundle.h"

#include <embree3/rtcore.h>

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

} // namespace prt
