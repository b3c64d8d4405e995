#include "raycast.h"

#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <cstdio>
#include <limits>
#include <utility>

namespace prt {
namespace {

// A ray from `origin` along `d`: the distance to the nearest hit, or infinity.
float nearestHit(const EmbreeScene& scene, const float origin[3], const float d[3]) {
    RTCRayHit rayHit{};
    RTCRay& ray = rayHit.ray;
    ray.org_x = origin[0], ray.org_y = origin[1], ray.org_z = origin[2];
    ray.dir_x = d[0], ray.dir_y = d[1], ray.dir_z = d[2];
    ray.tfar = std::numeric_limits<float>::infinity();
    ray.mask = ~0u;
    rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcIntersect1(scene.scene, &context, &rayHit);
    return rayHit.hit.geomID == RTC_INVALID_GEOMETRY_ID ? std::numeric_limits<float>::infinity() : ray.tfar;
}

TEST(Raycast, OffsetIsATenThousandthOfTheDiagonal) {
    TriMesh plane = makePlane(2.0f, 2); // 2 x 0 x 2: diagonal 2 sqrt 2
    EXPECT_NEAR(rayOffset(plane), 1e-4f * 2.0f * std::sqrt(2.0f), 1e-9f);
    EXPECT_EQ(rayOffset(TriMesh{}), 0.0f);
}

TEST(Raycast, RaysHitTheMeshWhereItIs) {
    {
        EmbreeScene scene(makeSphere(1.0f, 32, 64));
        const float outside[3] = {0.0f, 0.0f, 5.0f}, towards[3] = {0.0f, 0.0f, -1.0f}, away[3] = {0.0f, 0.0f, 1.0f};
        EXPECT_NEAR(nearestHit(scene, outside, towards), 4.0f, 2e-3f); // the tessellation lies inside the sphere
        EXPECT_TRUE(std::isinf(nearestHit(scene, outside, away)));
        const float centre[3] = {0.0f, 0.0f, 0.0f};
        EXPECT_NEAR(nearestHit(scene, centre, away), 1.0f, 2e-3f);
    }
}

// Rays spawned by the shared rule from every vertex of a closed box room (corners and edges included, where a
// wall's vertex lies in the neighbouring wall's plane), over a dense hemisphere about its flat normal, and from
// points just beside the creases: none may escape. With the old transfer rule (origin along the vertex normal,
// tnear = offset) the rays from an edge towards the neighbouring wall skipped it and left the room.
TEST(Raycast, SpawnedRaysNeverLeakFromAClosedBoxRoom) {
    TriMesh room = makeBoxRoom(2.0f, 4);
    EmbreeScene scene(room);
    const float offset = rayOffset(room);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    size_t rays = 0, escaped = 0, escapedOldRule = 0;
    const std::vector<float> spawn = spawnNormals(room);
    auto cast = [&](const float position[3], const float normal[3], const float spawnNormal[3]) {
        float origin[3];
        spawnOrigin(position, spawnNormal, offset, origin);
        // Directions on a 24 x 48 grid of the hemisphere about the normal, grazing ones included.
        float t[3], b[3];
        const float* n = normal;
        float helper[3] = {std::fabs(n[0]) < 0.9f ? 1.0f : 0.0f, std::fabs(n[0]) < 0.9f ? 0.0f : 1.0f, 0.0f};
        t[0] = helper[1] * n[2] - helper[2] * n[1], t[1] = helper[2] * n[0] - helper[0] * n[2], t[2] = helper[0] * n[1] - helper[1] * n[0];
        float tl = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
        for (float& c : t) c /= tl;
        b[0] = n[1] * t[2] - n[2] * t[1], b[1] = n[2] * t[0] - n[0] * t[2], b[2] = n[0] * t[1] - n[1] * t[0];
        for (int i = 0; i < 24; ++i) {
            double theta = (i + 0.5) / 24.0 * 0.5 * 3.14159265358979; // up to 89.6 degrees from the normal
            for (int j = 0; j < 48; ++j) {
                double phi = j / 48.0 * 2.0 * 3.14159265358979;
                float d[3];
                for (int c = 0; c < 3; ++c)
                    d[c] = float(std::sin(theta) * (std::cos(phi) * t[c] + std::sin(phi) * b[c]) + std::cos(theta) * n[c]);
                RTCRayHit rayHit{};
                spawnRay(rayHit.ray, origin, d[0], d[1], d[2]);
                rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                rtcIntersect1(scene.scene, &context, &rayHit);
                ++rays;
                if (rayHit.hit.geomID == RTC_INVALID_GEOMETRY_ID) ++escaped;
                RTCRayHit old{};
                // The old transfer rule, for contrast: origin along the vertex normal, tnear = offset as well.
                float oldOrigin[3];
                spawnOrigin(position, normal, offset, oldOrigin);
                spawnRay(old.ray, oldOrigin, d[0], d[1], d[2]);
                old.ray.tnear = offset;
                old.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                rtcIntersect1(scene.scene, &context, &old);
                if (old.hit.geomID == RTC_INVALID_GEOMETRY_ID) ++escapedOldRule;
            }
        }
    };
    for (size_t v = 0; v < room.vertexCount(); ++v) cast(&room.positions[3 * v], &room.normals[3 * v], &spawn[3 * v]);
    // Beside the creases: points of each triangle at barycentric (1 - 2e, e, e) and its permutations.
    for (size_t f = 0; f < room.triangleCount(); ++f) {
        const uint32_t* corner = &room.indices[3 * f];
        for (int k = 0; k < 3; ++k) {
            const float e = 1e-6f;
            float w[3] = {e, e, e};
            w[k] = 1.0f - 2.0f * e;
            float p[3];
            for (int c = 0; c < 3; ++c)
                p[c] = w[0] * room.positions[3 * corner[0] + c] + w[1] * room.positions[3 * corner[1] + c] +
                       w[2] * room.positions[3 * corner[2] + c];
            cast(p, &room.normals[3 * corner[0]], &room.normals[3 * corner[0]]); // inside the face: its normal
        }
    }
    EXPECT_GT(rays, 100000u);
    EXPECT_EQ(escaped, 0u) << "of " << rays << " rays";
    EXPECT_GT(escapedOldRule, 0u) << "the test no longer tells the old rule from the new one";
    std::printf("box room: %zu rays, %zu escaped by the shared rule, %zu by the old transfer rule\n", rays, escaped,
                escapedOldRule);
}

// A shard's receivers get the rows of the whole mesh's spawn normals bit for bit, though their positions' groups
// reach outside the range: the box room's corners and edges are split vertices (one per wall), and its copy lies
// over it at the same positions, so every group spans both halves.
TEST(Raycast, SpawnNormalsOfARangeAreTheWholeMeshsRows) {
    const TriMesh room = makeBoxRoom(2.0f, 4);
    TriMesh twice = mergeMeshes({room, room});
    for (size_t i = 0; i < room.normals.size(); ++i) twice.normals[room.normals.size() + i] *= -1.0f; // other side
    const std::vector<float> whole = spawnNormals(twice);
    ASSERT_EQ(whole.size(), twice.positions.size());
    const size_t V = twice.vertexCount();
    const std::pair<size_t, size_t> ranges[] = {{0, V}, {0, 7}, {5, V / 2 + 3}, {V / 2, V}, {V - 1, V}, {9, 9}};
    for (auto [begin, end] : ranges) {
        const std::vector<float> rows = spawnNormals(twice, begin, end);
        ASSERT_EQ(rows.size(), 3 * (end - begin));
        if (rows.empty()) continue; // (memcmp may not take the null pointer of an empty vector)
        EXPECT_EQ(0, std::memcmp(rows.data(), whole.data() + 3 * begin, rows.size() * sizeof(float)))
            << "[" << begin << ", " << end << ")";
    }
    // The groups matter: a corner vertex's spawn normal leaves all three walls, unlike its own wall's normal.
    size_t corner = 0;
    while (corner < room.vertexCount() &&
           !(std::fabs(whole[3 * corner]) > 0.3f && std::fabs(whole[3 * corner + 1]) > 0.3f &&
             std::fabs(whole[3 * corner + 2]) > 0.3f))
        ++corner;
    EXPECT_LT(corner, room.vertexCount()) << "no vertex of the room has a corner's spawn normal";
}

TEST(Raycast, AnEmptyMeshIsASceneWithNothingToHit) {
    EmbreeScene scene{TriMesh{}};
    const float origin[3] = {0, 0, 0}, d[3] = {1, 0, 0};
    EXPECT_TRUE(std::isinf(nearestHit(scene, origin, d)));
}

} // namespace
} // namespace prt
