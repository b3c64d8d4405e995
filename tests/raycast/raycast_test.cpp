#include "raycast.h"

#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

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
    for (bool robust : {false, true}) {
        EmbreeScene scene(makeSphere(1.0f, 32, 64), robust);
        const float outside[3] = {0.0f, 0.0f, 5.0f}, towards[3] = {0.0f, 0.0f, -1.0f}, away[3] = {0.0f, 0.0f, 1.0f};
        EXPECT_NEAR(nearestHit(scene, outside, towards), 4.0f, 2e-3f); // the tessellation lies inside the sphere
        EXPECT_TRUE(std::isinf(nearestHit(scene, outside, away)));
        const float centre[3] = {0.0f, 0.0f, 0.0f};
        EXPECT_NEAR(nearestHit(scene, centre, away), 1.0f, 2e-3f);
    }
}

TEST(Raycast, AnEmptyMeshIsASceneWithNothingToHit) {
    EmbreeScene scene{TriMesh{}};
    const float origin[3] = {0, 0, 0}, d[3] = {1, 0, 0};
    EXPECT_TRUE(std::isinf(nearestHit(scene, origin, d)));
}

} // namespace
} // namespace prt
