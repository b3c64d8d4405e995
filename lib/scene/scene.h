// Procedural scenes with known answers, generated in code (no shipped files).
// All are closed, consistently wound (counter-clockwise from the side the normal points to) and carry exact
// analytic normals.
#pragma once

#include "bundle.h"

#include <string>
#include <vector>

namespace prt {

// Unit-radius-scaled UV sphere centred at `center`, outward normals. rings >= 2, segments >= 3.
TriMesh makeSphere(float radius, int rings, int segments, const float center[3] = nullptr);

// Square in the XZ plane at height y, side `size`, normal +Y, subdivided `n` x `n`.
TriMesh makePlane(float size, int n, float y = 0.0f);

// Closed box room seen from inside: floor, ceiling, four walls, normals pointing inward; `n` subdivisions per side.
TriMesh makeBoxRoom(float size, int n);

// Sphere of radius `radius` at the origin with inward normals and a polar cap opening of half-angle
// `openingHalfAngle` (radians) around +Y removed: the "open spherical cavity" of the interreflection closed form.
TriMesh makeOpenCavity(float radius, float openingHalfAngle, int rings, int segments);

// The sphere inside an open cavity: a small sphere (outward normals) at the centre of an open cavity.
TriMesh makeSphereInCavity(int rings, int segments);

// Two spheres side by side along X, touching neither.
TriMesh makeTwoSpheres(int rings, int segments);

// Names accepted by makeScene: "sphere", "plane", "box-room", "cavity", "sphere-in-cavity", "two-spheres".
std::vector<std::string> sceneNames();
// Builds a named scene at its default resolution; throws prt::Error for an unknown name.
TriMesh makeScene(const std::string& name);

// Concatenates meshes, offsetting indices.
TriMesh mergeMeshes(const std::vector<TriMesh>& parts);

} // namespace prt
