#include "scene.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace prt {

TriMesh makeSphereInCavity(int rings, int segments) {
    return mergeMeshes({makeSphere(kInnerSphereRadius, rings, segments), makeOpenCavity(1.0f, kCavityOpeningHalfAngle, rings, segments)});
}

TriMesh makeTwoSpheres(int rings, int segments) {
    const float left[3] = {-1.0f, 0.0f, 0.0f}, right[3] = {1.0f, 0.0f, 0.0f};
    return mergeMeshes({makeSphere(0.5f, rings, segments, left), makeSphere(0.5f, rings, segments, right)});
}

std::vector<std::string> sceneNames() { return {"sphere", "plane", "box-room", "cavity", "sphere-in-cavity", "two-spheres"}; }

TriMesh makeScene(const std::string& name) {
    // Default resolutions: about 2000 vertices per sphere, enough for smooth transfer, quick to precompute.
    if (name == "sphere") return makeSphere(1.0f, 32, 64);
    if (name == "plane") return makePlane(2.0f, 16);
    if (name == "box-room") return makeBoxRoom(2.0f, 16);
    if (name == "cavity") return makeOpenCavity(1.0f, kCavityOpeningHalfAngle, 32, 64);
    if (name == "sphere-in-cavity") return makeSphereInCavity(32, 64);
    if (name == "two-spheres") return makeTwoSpheres(32, 64);
    std::string known;
    for (const std::string& candidate : sceneNames()) known += (known.empty() ? "" : ", ") + candidate;
    throw Error("", "scene", "unknown scene '" + name + "' (known: " + known + ")", kExitUsage);
}

TriMesh makeSceneWithVertices(const std::string& name, uint64_t vertices) {
    auto build = [&](int rings) {
        int segments = 2 * rings;
        if (name == "sphere") return makeSphere(1.0f, rings, segments);
        if (name == "cavity") return makeOpenCavity(1.0f, kCavityOpeningHalfAngle, rings, segments);
        if (name == "sphere-in-cavity") return makeSphereInCavity(rings, segments);
        if (name == "two-spheres") return makeTwoSpheres(rings, segments);
        throw Error("", "--vertices", "scene '" + name + "' cannot be grown; use sphere, cavity, sphere-in-cavity "
                                      "or two-spheres", kExitUsage);
    };
    int rings = 8;
    TriMesh mesh = build(rings);
    while (mesh.vertexCount() < vertices) {
        double grow = std::sqrt(double(vertices) / double(mesh.vertexCount()));
        rings = std::max(rings + 1, int(std::ceil(rings * grow)));
        mesh = build(rings);
    }
    return mesh;
}


} // namespace prt
