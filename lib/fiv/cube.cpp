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

// A map texel as a rectangle of parameters (u, v) in [0, 1]^2 over which the solid angle is (nearly) uniform, with
// the direction and the exact solid angle of any sub-rectangle: equirectangular texels in (phi, cos theta), where
// the solid angle dphi dz is exactly uniform; cube-strip texels in face coordinates (a, b).
struct SourceTexel {
    const EnvironmentMap* env;
    int x = 0, y = 0;
    double zTop = 1.0, zBottom = -1.0; // equirectangular: cos theta at the texel's top and bottom edges
    double bend = 0.0;                  // equirectangular: (zTop - zBottom) / (the smaller 1 - z^2 of the row)

    void setRow(int row) {
        y = row;
        if (env->layout == EnvLayout::Equirectangular) {
            zTop = std::cos(std::numbers::pi * row / env->radiance.height);
            zBottom = std::cos(std::numbers::pi * (row + 1) / env->radiance.height);
            double r2 = std::min(1.0 - zTop * zTop, 1.0 - zBottom * zBottom);
            bend = r2 > 0.0 ? (zTop - zBottom) / r2 : INFINITY;
        }
    }
    void direction(double u, double v, double d[3]) const {
        const Image& image = env->radiance;
        if (env->layout == EnvLayout::Equirectangular) {
            double z = std::clamp(zTop + v * (zBottom - zTop), -1.0, 1.0), s = std::sqrt(std::max(0.0, 1.0 - z * z));
            double phi = 2.0 * std::numbers::pi * (x + u) / image.width - std::numbers::pi;
            d[0] = s * std::sin(phi), d[1] = z, d[2] = -s * std::cos(phi);
        } else {
            int size = image.width, face = y / size, row = y % size;
            sh::cubeFaceDirection(face, 2.0 * (x + u) / size - 1.0, 1.0 - 2.0 * (row + v) / size, d);
        }
    }
    double solidAngle(double u0, double u1, double v0, double v1) const {
        const Image& image = env->radiance;
        if (env->layout == EnvLayout::Equirectangular)
            return 2.0 * std::numbers::pi * (u1 - u0) / image.width * (v1 - v0) * (zTop - zBottom);
        int size = image.width, row = y % size;
        return sh::cubeRectangleSolidAngle(2.0 * (x + u0) / size - 1.0, 2.0 * (x + u1) / size - 1.0,
                                           1.0 - 2.0 * (row + v1) / size, 1.0 - 2.0 * (row + v0) / size);
    }
};

struct Splat {
    uint32_t target;
    double solidAngle;
};

void addSplat(std::vector<Splat>& out, size_t first, uint32_t target, double solidAngle) {
    for (size_t i = first; i < out.size(); ++i)
        if (out[i].target == target) {
            out[i].solidAngle += solidAngle;
            return;
        }
    out.push_back({target, solidAngle});
}

// Where direction d falls on a cube of `size`: face, column, row, and the face coordinates.
struct CubePoint {
    int face, column, row;
    double a, b;
    uint32_t texel(int size) const { return uint32_t((size_t(face) * size + size_t(row)) * size + size_t(column)); }
};
CubePoint cubePoint(int size, const double d[3]) {
    CubePoint p;
    p.face = sh::cubeFaceOf(d, p.a, p.b);
    p.column = std::clamp(int(std::floor((p.a + 1.0) * 0.5 * size)), 0, size - 1);
    p.row = std::clamp(int(std::floor((1.0 - p.b) * 0.5 * size)), 0, size - 1);
    return p;
}

// The fraction of a triangle's area where the linear function with vertex values p, q, r is negative.
double negativeFraction(double p, double q, double r) {
    int negative = (p < 0) + (q < 0) + (r < 0);
    if (negative == 0) return 0.0;
    if (negative == 3) return 1.0;
    // The vertex alone on its side: a corner triangle of area fraction lone^2 / ((lone - o1)(lone - o2)).
    double lone, o1, o2;
    bool loneNegative = negative == 1;
    if ((p < 0) == loneNegative) lone = p, o1 = q, o2 = r;
    else if ((q < 0) == loneNegative) lone = q, o1 = p, o2 = r;
    else lone = r, o1 = p, o2 = q;
    double corner = lone * lone / ((lone - o1) * (lone - o2));
    return loneNegative ? corner : 1.0 - corner;
}

// Deepest halving of a map texel's cells: leaves are 1/64 of the texel (or of its first split) per side. Only
// cells near a cube-texel corner or a face seam (two boundaries) get that deep.
constexpr int kMaxDepth = 6;

// Splits the cell [u0, u1] x [v0, v1] of a map texel among the cube texels it overlaps, appending (target, solid
// angle) to out from index `first` on. Probes: the centre and the four corners (pulled in by 1e-9 of the cell).
// All in one cube texel: the cell goes to it whole. Split by one boundary (corners in two neighbouring columns,
// or rows, of one face): the boundary is linear in face coordinates, which are nearly linear over a map texel, so
// the cell is cut by the plane through the corners' signed distances on its two triangles, exactly for a straight
// boundary, and the two parts go to the two texels (their solid angles summing to the cell's). Otherwise the cell
// is halved both ways down to kMaxDepth, where a leaf goes whole to the texel of its centre.
void splatCell(const SourceTexel& source, int cubeSize, double u0, double u1, double v0, double v1, int depth,
               std::vector<Splat>& out, size_t first) {
    constexpr double kInset = 1e-9;
    double d[3];
    source.direction(0.5 * (u0 + u1), 0.5 * (v0 + v1), d);
    const CubePoint centre = cubePoint(cubeSize, d);
    CubePoint corners[4]; // (u0, v0), (u1, v0), (u0, v1), (u1, v1)
    bool single = true, sameFace = true, sameRow = true, sameColumn = true;
    int loColumn = centre.column, hiColumn = centre.column, loRow = centre.row, hiRow = centre.row;
    for (int corner = 0; corner < 4; ++corner) {
        double u = corner & 1 ? u1 - kInset * (u1 - u0) : u0 + kInset * (u1 - u0);
        double v = corner & 2 ? v1 - kInset * (v1 - v0) : v0 + kInset * (v1 - v0);
        source.direction(u, v, d);
        const CubePoint& p = corners[corner] = cubePoint(cubeSize, d);
        sameFace = sameFace && p.face == centre.face;
        sameRow = sameRow && p.row == centre.row;
        sameColumn = sameColumn && p.column == centre.column;
        loColumn = std::min(loColumn, p.column), hiColumn = std::max(hiColumn, p.column);
        loRow = std::min(loRow, p.row), hiRow = std::max(hiRow, p.row);
    }
    single = sameFace && sameRow && sameColumn;
    const double solidAngle = source.solidAngle(u0, u1, v0, v1);
    if (single) {
        addSplat(out, first, centre.texel(cubeSize), solidAngle);
        return;
    }
    // Face coordinates are nearly linear over the cell, unless it is large against its distance from a pole:
    // along a meridian the distance from the pole r = sqrt(1 - z^2) bends by about dz / r^2 over a cell dz tall
    // (a bias, always the same way), so such cells are halved first (down to kMaxDepth, then cut anyway).
    const bool linear = source.env->layout != EnvLayout::Equirectangular || depth >= kMaxDepth ||
                        (v1 - v0) * source.bend < 4e-3;
    const bool columnCut = linear && sameFace && sameRow && hiColumn == loColumn + 1;
    const bool rowCut = linear && sameFace && sameColumn && hiRow == loRow + 1;
    if (columnCut || rowCut) {
        // Signed distance to the boundary, negative on the low column (or the low row, whose b is larger).
        double boundary = columnCut ? 2.0 * hiColumn / cubeSize - 1.0 : 1.0 - 2.0 * hiRow / cubeSize;
        double g[4];
        for (int c = 0; c < 4; ++c) g[c] = columnCut ? corners[c].a - boundary : boundary - corners[c].b;
        CubePoint lowPoint = centre, highPoint = centre;
        if (columnCut) lowPoint.column = loColumn, highPoint.column = hiColumn;
        else lowPoint.row = loRow, highPoint.row = hiRow;
        double lowAngle;
        if (source.env->layout == EnvLayout::CubeStrip) {
            // A cube-strip texel lies on the same face: a is linear in u and b in v, so the boundary is the line
            // u = cut (or v = cut) and the parts are rectangles with exact solid angles.
            double g0 = g[0], g1 = columnCut ? g[1] : g[2];
            double lo = columnCut ? u0 : v0, hi = columnCut ? u1 : v1;
            double p0 = lo + kInset * (hi - lo), p1 = hi - kInset * (hi - lo);
            double cut = g0 != g1 ? std::clamp(p0 + (p1 - p0) * g0 / (g0 - g1), lo, hi) : 0.5 * (lo + hi);
            double part = columnCut ? source.solidAngle(u0, cut, v0, v1) : source.solidAngle(u0, u1, v0, cut);
            lowAngle = g0 < 0.0 ? part : solidAngle - part; // the low texel holds the cell's first edge or its last
        } else {
            // (phi, cos theta): the solid angle is uniform over the cell, so the area fraction is the solid angle's.
            lowAngle = solidAngle * 0.5 * (negativeFraction(g[0], g[1], g[3]) + negativeFraction(g[0], g[3], g[2]));
        }
        if (lowAngle > 0.0) addSplat(out, first, lowPoint.texel(cubeSize), lowAngle);
        if (lowAngle < solidAngle) addSplat(out, first, highPoint.texel(cubeSize), solidAngle - lowAngle);
        return;
    }
    if (depth >= kMaxDepth) {
        addSplat(out, first, centre.texel(cubeSize), solidAngle);
        return;
    }
    const double um = 0.5 * (u0 + u1), vm = 0.5 * (v0 + v1);
    splatCell(source, cubeSize, u0, um, v0, vm, depth + 1, out, first);
    splatCell(source, cubeSize, um, u1, v0, vm, depth + 1, out, first);
    splatCell(source, cubeSize, u0, um, vm, v1, depth + 1, out, first);
    splatCell(source, cubeSize, um, u1, vm, v1, depth + 1, out, first);
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
                sh::cubeFaceDirection(face, 0.5 * (a0 + a1), 0.5 * (b0 + b1), d);
                cube.solidAngle[t] = sh::cubeRectangleSolidAngle(a0, a1, b0, b1);
                double minCos = 1.0;
                for (double a : {a0, a1})
                    for (double b : {b0, b1}) {
                        double corner[3];
                        sh::cubeFaceDirection(face, a, b, corner);
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
    sh::cubeFaceDirection(face, a, b, d);
}

CubeEnvironment resampleToCube(const EnvironmentMap& env, int size) {
    CubeTexels cube = cubeTexels(size);
    const Image& image = env.radiance;
    const bool equirect = env.layout == EnvLayout::Equirectangular;
    if (image.width < 1 || image.height != (equirect ? image.width / 2 : 6 * image.width) ||
        (equirect && image.width % 2) || image.rgb.size() != size_t(image.width) * image.height * 3)
        throw Error("", "fiv::resampleToCube", "environment image size does not match its layout", kExitFailure);
    // Map texels wider than 0.15 pi / size (under half the smallest cube texel, a face corner's) are split evenly
    // first, so no cube texel lies inside a cell between its probes.
    const double texelAngle = equirect ? std::numbers::pi / image.height : 0.5 * std::numbers::pi / image.width;
    const int split = std::max(1, int(std::ceil(texelAngle / (0.15 * std::numbers::pi / size))));
    std::vector<double> power(3 * cube.solidAngle.size(), 0.0); // sum of L dw per cube texel
    // Rows in fixed blocks: splats in parallel, then added in row order, so the sums do not depend on threads.
    constexpr int kRowsPerBlock = 16;
    std::vector<std::vector<Splat>> splats(kRowsPerBlock);
    std::vector<std::vector<size_t>> texelStart(kRowsPerBlock);
    for (int block = 0; block < image.height; block += kRowsPerBlock) {
        int rows = std::min(kRowsPerBlock, image.height - block);
        tbb::parallel_for(0, rows, [&](int r) {
            std::vector<Splat>& out = splats[size_t(r)];
            std::vector<size_t>& begin = texelStart[size_t(r)];
            out.clear(), begin.clear();
            SourceTexel source{&env};
            source.setRow(block + r);
            for (int x = 0; x < image.width; ++x) {
                source.x = x;
                size_t first = out.size();
                begin.push_back(first);
                for (int i = 0; i < split; ++i)
                    for (int j = 0; j < split; ++j)
                        splatCell(source, size, double(i) / split, double(i + 1) / split, double(j) / split,
                                  double(j + 1) / split, 0, out, first);
            }
            begin.push_back(out.size());
        });
        for (int r = 0; r < rows; ++r)
            for (int x = 0; x < image.width; ++x) {
                const float* radiance = &image.rgb[3 * (size_t(block + r) * image.width + x)];
                for (size_t i = texelStart[size_t(r)][size_t(x)]; i < texelStart[size_t(r)][size_t(x) + 1]; ++i) {
                    const Splat& splat = splats[size_t(r)][i];
                    for (int c = 0; c < 3; ++c) power[3 * splat.target + c] += double(radiance[c]) * splat.solidAngle;
                }
            }
    }
    CubeEnvironment out;
    out.size = size;
    out.radiance.resize(power.size());
    for (size_t t = 0; t < cube.solidAngle.size(); ++t)
        for (int c = 0; c < 3; ++c) out.radiance[3 * t + c] = power[3 * t + c] / cube.solidAngle[t];
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
