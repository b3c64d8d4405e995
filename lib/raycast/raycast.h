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
// With a scene's `surface` (lib/material) whose materials have cut-outs, hits where the surface is absent
// (presentAt false) are ignored by every query, nearest-hit and occlusion alike, through Embree filter functions;
// the surface must outlive the scene.
// Instancing: with a surface whose `instancing` is set, a glTF mesh that several nodes place is built once, as an
// Embree scene of its primitives in its first placement's world space, and every other placement is an Embree
// instance of it (transform: the placement's world matrix times the first's inverse), so the BVH holds each such
// mesh's triangles once. Receivers placed once share one triangle geometry. Hits then name a geometry of an
// instance: flatTriangle() maps every hit to its triangle of the flattened mesh, which all callers index with, and
// callers take facing from that triangle's world positions (Embree's Ng is in the instanced object's space).
// Barycentrics are those of the flattened triangle. Without instancing, flatTriangle(hit) is hit.primID.
struct Surface;
struct EmbreeScene {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;

    explicit EmbreeScene(const TriMesh& mesh, const Surface* surface = nullptr);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    // Whether some geometry is an instance (then Ng of a hit is not in world space).
    bool instanced() const { return !prototypes.empty(); }
    uint32_t flatTriangle(unsigned instID, unsigned geomID, unsigned primID) const {
        if (topReceiver.empty()) return primID;
        uint32_t receiver = instID == RTC_INVALID_GEOMETRY_ID ? topReceiver[geomID] : topReceiver[instID] + geomID;
        return receiverTriangles[receiver] + primID;
    }
    uint32_t flatTriangle(const RTCHit& hit) const { return flatTriangle(hit.instID[0], hit.geomID, hit.primID); }

    // The mapping behind flatTriangle (empty without instancing): per top-level geometry, the receiver it holds
    // (a receiver placed once) or the first receiver of the placement it instances (an instance, whose prototype
    // holds the placement's receivers in order as its geometries); per receiver, its first flattened triangle.
    std::vector<uint32_t> topReceiver;
    std::vector<uint32_t> receiverTriangles;
    std::vector<RTCScene> prototypes;
    struct FilterData {
        const Surface* surface;
        const EmbreeScene* scene;
    } filterData{nullptr, nullptr};
};

// The unnormalised geometric normal (p1 - p0) x (p2 - p0) of `triangle`, on its counter-clockwise front side.
inline void triangleNormal(const TriMesh& mesh, uint32_t triangle, float n[3]) {
    const uint32_t* corner = &mesh.indices[3 * size_t(triangle)];
    const float *p0 = &mesh.positions[3 * size_t(corner[0])], *p1 = &mesh.positions[3 * size_t(corner[1])],
                *p2 = &mesh.positions[3 * size_t(corner[2])];
    const float e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

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
// triangle: the vertex normal (normalised), else +z. Memory: 4 bytes per vertex, and at most about 40 per vertex of
// the range (a table of its distinct positions, their sums).
std::vector<float> spawnNormals(const TriMesh& mesh);
// The same rows for vertices [begin, end) only ([end - begin][3], bit for bit those of spawnNormals(mesh)): a shard's
// receivers. Its table holds the range's positions alone; every vertex and triangle is still visited once.
std::vector<float> spawnNormals(const TriMesh& mesh, size_t begin, size_t end);

} // namespace prt
