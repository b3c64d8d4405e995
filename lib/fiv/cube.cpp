// Environment cubes: texel directions and exact solid angles, resampling a map onto a cube, the DifMap and FIV(Env).
#include "fiv.h"

#include "core.h"
#include "sh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace prt::fiv {

namespace {

// The cube strip's faces as docs/conventions.md (OpenEXR's ImfEnvmap.h) lays them out: axis, the direction of
// increasing column, the direction of decreasing row. Same table as lib/sh's cubeStripDirection.
struct Face {
    double axis[3], right[3], up[3];
};
constexpr Face kFaces[6] = {
    {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}},   {{-1, 0, 0}, {0, 0, -1}, {0, 1, 0}}, {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},
    {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}}, {{0, 0, 1}, {-1, 0, 0}, {0, 1, 0}}, {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}},
};

// Direction of face coordinates (a, b) in [-1, 1]^2 on `face`, unit.
void faceDirection(int face, double a, double b, double d[3]) {
    const Face& f = kFaces[face];
    double length = 0.0;
    for (int c = 0; c < 3; ++c) {
        d[c] = f.axis[c] + a * f.right[c] + b * f.up[c];
        length += d[c] * d[c];
    }
    length = std::sqrt(length);
    for (int c = 0; c < 3; ++c) d[c] /= length;
}

double cornerSolidAngle(double a, double b) { return std::atan2(a * b, std::sqrt(a * a + b * b + 1.0)); }

// The texel of a cube of `size` that direction d falls in.
size_t cubeTexelOf(int size, const double d[3]) {
    int axis = 0;
    for (int c = 1; c < 3; ++c)
        if (std::abs(d[c]) > std::abs(d[axis])) axis = c;
    int face = 2 * axis + (d[axis] < 0.0 ? 1 : 0);
    const Face& f = kFaces[face];
    double depth = std::abs(d[axis]);
    double a = (f.right[0] * d[0] + f.right[1] * d[1] + f.right[2] * d[2]) / depth;
    double b = (f.up[0] * d[0] + f.up[1] * d[1] + f.up[2] * d[2]) / depth;
    int column = std::clamp(int(std::floor((a + 1.0) * 0.5 * size)), 0, size - 1);
    int row = std::clamp(int(std::floor((1.0 - b) * 0.5 * size)), 0, size - 1);
    return (size_t(face) * size + size_t(row)) * size + size_t(column);
}

size_t equirectTexelOf(int width, int height, const double d[3]) {
    double theta = std::acos(std::clamp(d[1], -1.0, 1.0));
    double phi = std::atan2(d[0], -d[2]);
    int x = int(std::floor((phi + std::numbers::pi) / (2.0 * std::numbers::pi) * width));
    int y = int(std::floor(theta / std::numbers::pi * height));
    return size_t(std::clamp(y, 0, height - 1)) * width + size_t(std::clamp(x, 0, width - 1));
}

} // namespace

CubeTexels cubeTexels(int size) {
    if (size < 1 || size > kMaxCube)
        throw Error("", "--cube", "face size " + std::to_string(size) + " is outside 1.." + std::to_string(kMaxCube),
                    kExitUsage);
    CubeTexels cube;
    cube.size = size;
    size_t count = 6 * size_t(size) * size;
    cube.direction.resize(3 * count);
    cube.solidAngle.resize(count);
    cube.cosRadius.resize(count);
    cube.sinRadius.resize(count);
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < size; ++row)
            for (int column = 0; column < size; ++column) {
                size_t t = (size_t(face) * size + row) * size + column;
                double a0 = 2.0 * column / size - 1.0, a1 = 2.0 * (column + 1) / size - 1.0;
                double b0 = 1.0 - 2.0 * (row + 1) / size, b1 = 1.0 - 2.0 * row / size;
                double* d = &cube.direction[3 * t];
                faceDirection(face, 0.5 * (a0 + a1), 0.5 * (b0 + b1), d);
                cube.solidAngle[t] = cornerSolidAngle(a0, b0) - cornerSolidAngle(a0, b1) - cornerSolidAngle(a1, b0) +
                                     cornerSolidAngle(a1, b1);
                double minCos = 1.0;
                for (double a : {a0, a1})
                    for (double b : {b0, b1}) {
                        double corner[3];
                        faceDirection(face, a, b, corner);
                        minCos = std::min(minCos, d[0] * corner[0] + d[1] * corner[1] + d[2] * corner[2]);
                    }
                // Widened a little so float error never drops a texel whose corner touches the sphere.
                double angle = std::acos(std::clamp(minCos, -1.0, 1.0)) * (1.0 + 1e-6) + 1e-9;
                cube.cosRadius[t] = std::cos(angle);
                cube.sinRadius[t] = std::sin(angle);
            }
    return cube;
}

void subsampleDirection(const CubeTexels& cube, size_t t, int sx, int sy, int supersample, double d[3]) {
    int size = cube.size;
    int face = int(t / (size_t(size) * size));
    int row = int(t / size % size), column = int(t % size);
    double a = 2.0 * (column + (sx + 0.5) / supersample) / size - 1.0;
    double b = 1.0 - 2.0 * (row + (sy + 0.5) / supersample) / size;
    faceDirection(face, a, b, d);
}

CubeEnvironment resampleToCube(const EnvironmentMap& env, int size) {
    CubeTexels cube = cubeTexels(size);
    const Image& image = env.radiance;
    CubeEnvironment out;
    out.size = size;
    size_t count = cube.solidAngle.size();
    out.radiance.assign(3 * count, 0.0);
    constexpr int kStrata = 4;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 256), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t t = range.begin(); t < range.end(); ++t) {
            double sum[3] = {0, 0, 0};
            for (int sy = 0; sy < kStrata; ++sy)
                for (int sx = 0; sx < kStrata; ++sx) {
                    double d[3];
                    subsampleDirection(cube, t, sx, sy, kStrata, d);
                    size_t texel = env.layout == EnvLayout::Equirectangular
                                       ? equirectTexelOf(image.width, image.height, d)
                                       : cubeTexelOf(image.width, d);
                    for (int c = 0; c < 3; ++c) sum[c] += image.rgb[3 * texel + c];
                }
            for (int c = 0; c < 3; ++c) out.radiance[3 * t + c] = sum[c] / (kStrata * kStrata);
        }
    });
    return out;
}

EnvironmentMap cubeAsEnvironmentMap(const CubeEnvironment& cube) {
    EnvironmentMap env;
    env.layout = EnvLayout::CubeStrip;
    env.radiance.width = cube.size;
    env.radiance.height = 6 * cube.size;
    env.radiance.rgb.assign(cube.radiance.begin(), cube.radiance.end());
    return env;
}

std::vector<float> difMap(const CubeEnvironment& env, int size) {
    CubeTexels source = cubeTexels(env.size);
    CubeTexels target = cubeTexels(size);
    size_t sources = source.solidAngle.size(), targets = target.solidAngle.size();
    std::vector<double> weighted(3 * sources); // L dw per texel
    for (size_t t = 0; t < sources; ++t)
        for (int c = 0; c < 3; ++c) weighted[3 * t + c] = env.radiance[3 * t + c] * source.solidAngle[t];
    std::vector<float> out(3 * targets);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, targets, 64), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t n = range.begin(); n < range.end(); ++n) {
            const double* normal = &target.direction[3 * n];
            double sum[3] = {0, 0, 0};
            for (size_t t = 0; t < sources; ++t) {
                const double* w = &source.direction[3 * t];
                double cosine = normal[0] * w[0] + normal[1] * w[1] + normal[2] * w[2];
                if (cosine <= 0.0) continue;
                for (int c = 0; c < 3; ++c) sum[c] += weighted[3 * t + c] * cosine;
            }
            for (int c = 0; c < 3; ++c) out[3 * n + c] = float(sum[c]);
        }
    });
    return out;
}

std::array<double, 9> environmentFiv(const CubeEnvironment& env) {
    CubeTexels cube = cubeTexels(env.size);
    std::array<double, 9> fiv{};
    for (size_t t = 0; t < cube.solidAngle.size(); ++t)
        for (int c = 0; c < 3; ++c)
            for (int a = 0; a < 3; ++a)
                fiv[size_t(3 * c + a)] += env.radiance[3 * t + c] * cube.solidAngle[t] * cube.direction[3 * t + a];
    return fiv;
}

} // namespace prt::fiv
