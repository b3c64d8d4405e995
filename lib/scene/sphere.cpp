#include "scene.h"

#include <cmath>
#include <numbers>

namespace prt {

// Rings of `segments` vertices at the polar angles `thetas` (ascending from +Y), closed by a pole vertex at +Y
// (when `northPole`) and at -Y. Triangles wind counter-clockwise seen from outside, or from inside if `inward`,
// and the normals point the same way.
static TriMesh latitudeMesh(double radius, const float center[3], const std::vector<double>& thetas, int segments,
                            bool northPole, bool inward) {
    TriMesh mesh;
    double c[3] = {center ? center[0] : 0.0, center ? center[1] : 0.0, center ? center[2] : 0.0};
    double side = inward ? -1.0 : 1.0;
    auto addVertex = [&](double x, double y, double z) {
        mesh.positions.insert(mesh.positions.end(), {float(c[0] + radius * x), float(c[1] + radius * y), float(c[2] + radius * z)});
        mesh.normals.insert(mesh.normals.end(), {float(side * x), float(side * y), float(side * z)});
    };
    auto addTriangle = [&](uint32_t a, uint32_t b, uint32_t c) {
        if (inward) std::swap(b, c);
        mesh.indices.insert(mesh.indices.end(), {a, b, c});
    };

    uint32_t north = 0;
    if (northPole) addVertex(0.0, 1.0, 0.0);
    uint32_t firstRing = uint32_t(mesh.vertexCount());
    for (double theta : thetas)
        for (int j = 0; j < segments; ++j) {
            double phi = 2.0 * std::numbers::pi * j / segments - std::numbers::pi;
            addVertex(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
        }
    uint32_t south = uint32_t(mesh.vertexCount());
    addVertex(0.0, -1.0, 0.0);

    auto ring = [&](size_t i, int j) { return firstRing + uint32_t(i * segments + (j % segments)); };
    if (northPole)
        for (int j = 0; j < segments; ++j) addTriangle(north, ring(0, j + 1), ring(0, j));
    for (size_t i = 0; i + 1 < thetas.size(); ++i)
        for (int j = 0; j < segments; ++j) {
            addTriangle(ring(i, j), ring(i + 1, j + 1), ring(i + 1, j));
            addTriangle(ring(i, j), ring(i, j + 1), ring(i + 1, j + 1));
        }
    size_t last = thetas.size() - 1;
    for (int j = 0; j < segments; ++j) addTriangle(ring(last, j), ring(last, j + 1), south);
    return mesh;
}

TriMesh makeSphere(float radius, int rings, int segments, const float center[3]) {
    std::vector<double> thetas;
    for (int i = 1; i < rings; ++i) thetas.push_back(std::numbers::pi * i / rings);
    return latitudeMesh(radius, center, thetas, segments, true, false);
}

TriMesh makeOpenCavity(float radius, float openingHalfAngle, int rings, int segments) {
    std::vector<double> thetas;
    for (int i = 0; i < rings; ++i) thetas.push_back(openingHalfAngle + (std::numbers::pi - openingHalfAngle) * i / rings);
    return latitudeMesh(radius, nullptr, thetas, segments, false, true);
}

} // namespace prt
