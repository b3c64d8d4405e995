// Cube-strip geometry shared by every cube map in prt: face directions, exact texel solid angles, and the face a
// direction falls on (docs/conventions.md).
#include "sh.h"

#include <cmath>

namespace prt::sh {

void cubeFaceDirection(int face, double a, double b, double d[3]) {
    const CubeFace& f = kCubeFaces[face];
    double length = 0.0;
    for (int c = 0; c < 3; ++c) {
        d[c] = f.axis[c] + a * f.right[c] + b * f.up[c];
        length += d[c] * d[c];
    }
    length = std::sqrt(length);
    for (int c = 0; c < 3; ++c) d[c] /= length;
}

double cubeRectangleSolidAngle(double a0, double a1, double b0, double b1) {
    // The solid angle of [0, a] x [0, b] at unit distance, signed by a and b; the rectangle's by inclusion-exclusion.
    auto corner = [](double a, double b) { return std::atan2(a * b, std::sqrt(a * a + b * b + 1.0)); };
    return corner(a1, b1) - corner(a0, b1) - corner(a1, b0) + corner(a0, b0);
}

int cubeFaceOf(const double d[3], double& a, double& b) {
    int axis = 0;
    for (int c = 1; c < 3; ++c)
        if (std::abs(d[c]) > std::abs(d[axis])) axis = c;
    const int face = 2 * axis + (d[axis] < 0.0 ? 1 : 0);
    const CubeFace& f = kCubeFaces[face];
    const double depth = std::abs(d[axis]);
    a = (f.right[0] * d[0] + f.right[1] * d[1] + f.right[2] * d[2]) / depth;
    b = (f.up[0] * d[0] + f.up[1] * d[1] + f.up[2] * d[2]) / depth;
    return face;
}

} // namespace prt::sh
