// Procedural scenes with known answers, generated in code (no shipped files).
// Every mesh is consistently wound (counter-clockwise seen from the side the normal points to) and carries exact
// analytic normals. Directions on spheres follow docs/conventions.md: polar angle theta from +Y, azimuth phi,
// d = (sin theta sin phi, cos theta, -sin theta cos phi). Same arguments give bit-identical meshes.
#pragma once

#include "bundle.h"

#include <cstdint>
#include <string>
#include <vector>

namespace prt {

// Closed UV sphere of `radius` centred at `center` (origin if null), outward normals. Needs rings >= 2 latitude
// bands and segments >= 3. One shared vertex at each pole and no seam duplicates, so every edge joins exactly two
// triangles: 2 + (rings - 1) * segments vertices, 2 * segments * (rings - 1) triangles.
TriMesh makeSphere(float radius, int rings, int segments, const float center[3] = nullptr);

// Open square in the XZ plane at height y, side `size`, centred on the Y axis, normal +Y, n x n quads (n >= 1),
// texcoords u along +X and v along +Z in [0, 1].
TriMesh makePlane(float size, int n, float y = 0.0f);

// Closed cube room [-size/2, size/2]^3 seen from inside: floor, ceiling and four walls of n x n quads each, flat
// normals pointing inward. Faces have their own vertices (flat normals) but identical positions along shared
// edges, so the surface is watertight.
TriMesh makeBoxRoom(float size, int n);

// Sphere of `radius` at the origin with inward normals and the polar cap of half-angle `openingHalfAngle`
// (radians, in (0, pi)) around +Y removed: the "open spherical cavity" of the interreflection closed form.
// The first of `rings` rings lies exactly on the opening (theta = openingHalfAngle), the others evenly down to
// a shared vertex at the -Y pole: rings * segments + 1 vertices, segments * (2 * rings - 1) triangles.
TriMesh makeOpenCavity(float radius, float openingHalfAngle, int rings, int segments);

// A sphere of radius kInnerSphereRadius (outward normals) at the centre of an open cavity of radius 1 with
// opening half-angle kCavityOpeningHalfAngle, both at `rings` x `segments`.
inline constexpr float kInnerSphereRadius = 0.3f;
inline constexpr float kCavityOpeningHalfAngle = 1.04719755f; // 60 degrees
TriMesh makeSphereInCavity(int rings, int segments);

// Two spheres of radius 0.5 centred at x = -1 and x = +1 (a gap of 1 between them).
TriMesh makeTwoSpheres(int rings, int segments);

// Names accepted by makeScene: "sphere", "plane", "box-room", "cavity", "sphere-in-cavity", "two-spheres".
std::vector<std::string> sceneNames();
// Builds a named scene at its default resolution; throws prt::Error (kExitUsage) naming the known scenes for an
// unknown name.
TriMesh makeScene(const std::string& name);
// A growable scene (sphere, cavity, sphere-in-cavity, two-spheres) with rings and segments raised together until
// it has at least `vertices` vertices: how the benchmarks and big-mesh measurements get a mesh of a given size
// (sphere-in-cavity at 1000000 gives 1,055,759). Throws prt::Error(kExitUsage) for other names.
TriMesh makeSceneWithVertices(const std::string& name, uint64_t vertices);

// Concatenates meshes, offsetting indices. A per-vertex attribute is kept only when every part has it.
TriMesh mergeMeshes(const std::vector<TriMesh>& parts);

} // namespace prt
