// Conservative UV rasterisation with exact sample points: texel centres inside, nearest points at the borders.
#include "bake.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace prt {

UvWrap parseUvWrap(const std::string& name) {
    if (name == "none") return UvWrap::None;
    if (name == "repeat") return UvWrap::Repeat;
    throw Error("", "--wrap", "'" + name + "' is not one of none, repeat", kExitUsage);
}

namespace {

// Barycentric weights of point p in the 2D triangle (a, b, c) of signed doubled area `area`.
void barycentric2d(const double a[2], const double b[2], const double c[2], double area, const double p[2],
                   double w[3]) {
    w[0] = ((b[0] - p[0]) * (c[1] - p[1]) - (b[1] - p[1]) * (c[0] - p[0])) / area;
    w[1] = ((c[0] - p[0]) * (a[1] - p[1]) - (c[1] - p[1]) * (a[0] - p[0])) / area;
    w[2] = 1.0 - w[0] - w[1];
}

// The point of segment (a, b) nearest to p, as the parameter t along it.
double nearestOnSegment(const double a[2], const double b[2], const double p[2]) {
    double dx = b[0] - a[0], dy = b[1] - a[1];
    double length2 = dx * dx + dy * dy;
    if (length2 <= 0.0) return 0.0;
    return std::clamp(((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2, 0.0, 1.0);
}

// Squared distance from p to the triangle and the barycentrics of the nearest point, for p outside it.
double nearestInTriangle(const double* corner[3], const double p[2], double w[3]) {
    double best = std::numeric_limits<double>::infinity();
    for (int e = 0; e < 3; ++e) {
        const double* a = corner[e];
        const double* b = corner[(e + 1) % 3];
        double t = nearestOnSegment(a, b, p);
        double q[2] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])};
        double d2 = (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]);
        if (d2 < best) {
            best = d2;
            w[e] = 1.0 - t;
            w[(e + 1) % 3] = t;
            w[(e + 2) % 3] = 0.0;
        }
    }
    return best;
}

// Whether the open square [x, x+1] x [y, y+1] and the counter-clockwise triangle overlap with positive area:
// the box axes are settled by the caller's bounding-box loop, so only the three edge axes remain.
bool squareOverlapsTriangle(const double* corner[3], double x, double y) {
    for (int e = 0; e < 3; ++e) {
        const double* a = corner[e];
        const double* b = corner[(e + 1) % 3];
        // Outward normal of a counter-clockwise edge: (dy, -dx); the triangle lies where n . (q - a) <= 0.
        double nx = b[1] - a[1], ny = -(b[0] - a[0]);
        double cornerX = nx < 0.0 ? x + 1.0 : x; // the square's corner deepest into the triangle's side
        double cornerY = ny < 0.0 ? y + 1.0 : y;
        if (nx * (cornerX - a[0]) + ny * (cornerY - a[1]) >= 0.0) return false;
    }
    return true;
}

// A texel centre counts as strictly inside two triangles (an overlap) only beyond this barycentric margin, so
// centres on shared edges never do.
constexpr double kInsideMargin = 1e-6;

} // namespace

TexelSamples rasteriseAtlas(const TriMesh& mesh, const RasterOptions& options, const std::string& source) {
    const int width = options.width, height = options.height;
    if (width < 1 || height < 1 || width > kMaxBakeResolution || height > kMaxBakeResolution)
        throw Error("", "--resolution",
                    std::to_string(width) + "x" + std::to_string(height) + " outside 1.." +
                        std::to_string(kMaxBakeResolution),
                    kExitUsage);
    if (mesh.texcoords.size() != 2 * mesh.vertexCount()) throw Error(source, "mesh", "has no texcoords");
    for (uint32_t v : mesh.indices) {
        float u = mesh.texcoords[2 * size_t(v)], t = mesh.texcoords[2 * size_t(v) + 1];
        auto where = [&] {
            return "texcoord (" + std::to_string(u) + ", " + std::to_string(t) + ")";
        };
        if (!std::isfinite(u) || !std::isfinite(t))
            throw Error(source, "vertex " + std::to_string(v), where() + " is not finite");
        if (options.wrap == UvWrap::None && !(u >= 0.0f && u <= 1.0f && t >= 0.0f && t <= 1.0f))
            throw Error(source, "vertex " + std::to_string(v),
                        where() + " lies outside [0, 1] and no wrap mode is set (--wrap repeat tiles it)");
    }

    const size_t texelCount = size_t(width) * height;
    constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
    std::vector<uint32_t> owner(texelCount, kNone);
    std::vector<float> ownerDistance(texelCount, std::numeric_limits<float>::infinity()); // 0: centre inside
    std::vector<uint8_t> strictlyInside(texelCount, 0);
    TexelSamples samples;
    samples.width = width;
    samples.height = height;

    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        double uv[3][2];
        for (int k = 0; k < 3; ++k) {
            uint32_t v = mesh.indices[3 * t + k];
            uv[k][0] = double(mesh.texcoords[2 * size_t(v)]) * width;
            uv[k][1] = double(mesh.texcoords[2 * size_t(v) + 1]) * height;
        }
        double area = (uv[1][0] - uv[0][0]) * (uv[2][1] - uv[0][1]) - (uv[1][1] - uv[0][1]) * (uv[2][0] - uv[0][0]);
        if (area == 0.0) {
            ++samples.degenerateTriangles;
            continue;
        }
        // Counter-clockwise in the (u, v) plane for the edge test; mirrored charts are as valid as any.
        const double* corner[3] = {uv[0], uv[1], uv[2]};
        if (area < 0.0) std::swap(corner[1], corner[2]);
        double lo[2] = {std::min({uv[0][0], uv[1][0], uv[2][0]}), std::min({uv[0][1], uv[1][1], uv[2][1]})};
        double hi[2] = {std::max({uv[0][0], uv[1][0], uv[2][0]}), std::max({uv[0][1], uv[1][1], uv[2][1]})};
        long x0 = long(std::floor(lo[0])), x1 = long(std::ceil(hi[0])) - 1;
        long y0 = long(std::floor(lo[1])), y1 = long(std::ceil(hi[1])) - 1;
        if (options.wrap == UvWrap::None) {
            // UVs in [0, 1] can only reach past the last texel at exactly 1.
            x0 = std::max(x0, 0L), y0 = std::max(y0, 0L);
            x1 = std::min(x1, long(width) - 1), y1 = std::min(y1, long(height) - 1);
        }
        for (long y = y0; y <= y1; ++y)
            for (long x = x0; x <= x1; ++x) {
                if (!squareOverlapsTriangle(corner, double(x), double(y))) continue;
                double centre[2] = {x + 0.5, y + 0.5}, w[3];
                barycentric2d(uv[0], uv[1], uv[2], area, centre, w);
                bool inside = w[0] >= 0.0 && w[1] >= 0.0 && w[2] >= 0.0;
                double distance2 = 0.0;
                if (!inside) {
                    const double* ordered[3] = {uv[0], uv[1], uv[2]};
                    distance2 = nearestInTriangle(ordered, centre, w);
                }
                long wx = ((x % width) + width) % width, wy = ((y % height) + height) % height;
                size_t texel = size_t(wy) * width + size_t(wx);
                bool strict = std::min({w[0], w[1], w[2]}) > kInsideMargin;
                if (strict && strictlyInside[texel]) {
                    if (!options.allowOverlap)
                        throw Error(source, "triangles " + std::to_string(owner[texel]) + " and " + std::to_string(t),
                                    "overlap in UV space at texel (" + std::to_string(wx) + ", " +
                                        std::to_string(wy) + ") of the " + std::to_string(width) + "x" +
                                        std::to_string(height) +
                                        " atlas; baked transfer needs a unique atlas (give a UV set without "
                                        "overlaps, or none to have one generated)");
                    ++samples.overlappingTexels;
                    continue;
                }
                if (float(distance2) < ownerDistance[texel]) {
                    owner[texel] = uint32_t(t);
                    ownerDistance[texel] = float(distance2);
                }
                if (strict) strictlyInside[texel] = 1;
            }
    }

    // Second pass: sample points of the winners, in texel order.
    for (size_t texel = 0; texel < texelCount; ++texel) {
        uint32_t t = owner[texel];
        if (t == kNone) continue;
        double uv[3][2];
        for (int k = 0; k < 3; ++k) {
            uint32_t v = mesh.indices[3 * size_t(t) + k];
            uv[k][0] = double(mesh.texcoords[2 * size_t(v)]) * width;
            uv[k][1] = double(mesh.texcoords[2 * size_t(v) + 1]) * height;
        }
        double area = (uv[1][0] - uv[0][0]) * (uv[2][1] - uv[0][1]) - (uv[1][1] - uv[0][1]) * (uv[2][0] - uv[0][0]);
        // The texel's centre in the triangle's own (unwrapped) copy of the plane.
        long x = long(texel % width), y = long(texel / width);
        double cu = (uv[0][0] + uv[1][0] + uv[2][0]) / 3.0, cv = (uv[0][1] + uv[1][1] + uv[2][1]) / 3.0;
        double centre[2] = {x + 0.5 + width * std::round((cu - x - 0.5) / width),
                            y + 0.5 + height * std::round((cv - y - 0.5) / height)};
        if (options.wrap == UvWrap::None) centre[0] = x + 0.5, centre[1] = y + 0.5;
        double w[3];
        barycentric2d(uv[0], uv[1], uv[2], area, centre, w);
        bool inside = ownerDistance[texel] == 0.0f && w[0] >= 0.0 && w[1] >= 0.0 && w[2] >= 0.0;
        if (!inside) {
            const double* ordered[3] = {uv[0], uv[1], uv[2]};
            nearestInTriangle(ordered, centre, w);
        }
        double sum = 0.0;
        for (double& weight : w) sum += weight = std::max(weight, 0.0);
        samples.texel.push_back(uint32_t(texel));
        samples.triangle.push_back(t);
        for (double weight : w) samples.barycentric.push_back(float(weight / sum));
        samples.centreInside.push_back(inside ? 1 : 0);
    }
    return samples;
}

std::vector<uint8_t> coverageMask(const TexelSamples& samples) {
    std::vector<uint8_t> covered(size_t(samples.width) * samples.height, 0);
    for (uint32_t texel : samples.texel) covered[texel] = 1;
    return covered;
}

void texelSurface(const TriMesh& mesh, const TexelSamples& samples, std::vector<float>& positions,
                  std::vector<float>& normals) {
    size_t count = samples.texel.size();
    positions.resize(3 * count);
    normals.resize(3 * count);
    for (size_t i = 0; i < count; ++i) {
        const uint32_t* corner = &mesh.indices[3 * size_t(samples.triangle[i])];
        const float* w = &samples.barycentric[3 * i];
        double p[3] = {0, 0, 0}, n[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) {
                p[a] += w[k] * double(mesh.positions[3 * size_t(corner[k]) + a]);
                n[a] += w[k] * double(mesh.normals[3 * size_t(corner[k]) + a]);
            }
        double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(length > 1e-12)) {
            // Opposite vertex normals cancel: the face's own normal is the only meaningful one.
            const float* p0 = &mesh.positions[3 * size_t(corner[0])];
            const float* p1 = &mesh.positions[3 * size_t(corner[1])];
            const float* p2 = &mesh.positions[3 * size_t(corner[2])];
            double e1[3] = {double(p1[0]) - p0[0], double(p1[1]) - p0[1], double(p1[2]) - p0[2]};
            double e2[3] = {double(p2[0]) - p0[0], double(p2[1]) - p0[1], double(p2[2]) - p0[2]};
            n[0] = e1[1] * e2[2] - e1[2] * e2[1];
            n[1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        }
        for (int a = 0; a < 3; ++a) {
            positions[3 * i + a] = float(p[a]);
            normals[3 * i + a] = float(n[a] / length);
        }
    }
}

} // namespace prt
