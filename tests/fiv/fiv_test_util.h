// Shared helpers of the FIV tests: closed occluders and environments with known answers.
#pragma once

#include "bundle.h"
#include "fiv.h"

#include <functional>

namespace prt::fivtest {

// Closed axis-aligned box [lo, hi]^3, outward counter-clockwise faces, 8 vertices, 12 triangles.
inline TriMesh makeBox(float lo, float hi) {
    TriMesh m;
    for (int v = 0; v < 8; ++v) {
        m.positions.push_back(v & 1 ? hi : lo);
        m.positions.push_back(v & 2 ? hi : lo);
        m.positions.push_back(v & 4 ? hi : lo);
    }
    m.indices = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                 2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
    return m;
}

// A cube environment whose texel t has radiance f(direction).
inline fiv::CubeEnvironment cubeFrom(int size, const std::function<std::array<double, 3>(const double*)>& f) {
    fiv::CubeTexels cube = fiv::cubeTexels(size);
    fiv::CubeEnvironment env;
    env.size = size;
    env.radiance.resize(3 * cube.solidAngle.size());
    for (size_t t = 0; t < cube.solidAngle.size(); ++t) {
        auto rgb = f(&cube.direction[3 * t]);
        for (int c = 0; c < 3; ++c) env.radiance[3 * t + c] = rgb[size_t(c)];
    }
    return env;
}

} // namespace prt::fivtest
