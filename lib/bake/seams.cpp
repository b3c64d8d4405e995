// UV seams: finding them, making the texels on their two sides agree, and measuring the jump that remains.
#include "bake.h"

#include "core.h"
#include "position_groups.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

namespace prt {

namespace {

bool sameTexcoord(const TriMesh& mesh, uint32_t v, uint32_t w) {
    return mesh.texcoords[2 * size_t(v)] == mesh.texcoords[2 * size_t(w)] &&
           mesh.texcoords[2 * size_t(v) + 1] == mesh.texcoords[2 * size_t(w) + 1];
}

// Whether vertices v and w carry the same shading normal (within about 2.6 degrees), or the mesh has none: where
// they do not, the edge is a crease (a floor meeting a wall), across which irradiance really jumps.
bool sameNormal(const TriMesh& mesh, uint32_t v, uint32_t w) {
    if (mesh.normals.empty()) return true;
    const float* n = &mesh.normals[3 * size_t(v)];
    const float* m = &mesh.normals[3 * size_t(w)];
    return n[0] * m[0] + n[1] * m[1] + n[2] * m[2] > 0.999f;
}

} // namespace

std::vector<SeamEdge> findSeams(const TriMesh& mesh) {
    // One id per position (-0 and +0 alike), as spawn normals group them.
    const std::vector<int32_t> ids = groupPositions(mesh, 0, mesh.vertexCount()).group;
    // Undirected position edge -> the (triangle, corner) of each triangle using it, in triangle order.
    std::map<std::pair<uint32_t, uint32_t>, std::vector<std::pair<uint32_t, int>>> uses;
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t p = uint32_t(ids[mesh.indices[3 * t + k]]);
            const uint32_t q = uint32_t(ids[mesh.indices[3 * t + (k + 1) % 3]]);
            if (p != q) uses[{std::min(p, q), std::max(p, q)}].push_back({uint32_t(t), k});
        }
    std::vector<SeamEdge> seams;
    for (const auto& [edge, list] : uses) {
        if (list.size() != 2) continue; // boundaries have no other side; non-manifold edges no single one
        SeamEdge seam;
        seam.first = list[0].first;
        seam.second = list[1].first;
        const uint32_t* f = &mesh.indices[3 * size_t(seam.first)];
        const uint32_t* s = &mesh.indices[3 * size_t(seam.second)];
        seam.a = f[list[0].second];
        seam.b = f[(list[0].second + 1) % 3];
        uint32_t c = s[list[1].second], d = s[(list[1].second + 1) % 3];
        if (ids[c] != ids[seam.a]) std::swap(c, d);
        seam.c = c, seam.d = d;
        if (sameTexcoord(mesh, seam.a, seam.c) && sameTexcoord(mesh, seam.b, seam.d)) continue;
        if (!sameNormal(mesh, seam.a, seam.c) || !sameNormal(mesh, seam.b, seam.d)) continue; // a crease
        seams.push_back(seam);
    }
    std::sort(seams.begin(), seams.end(), [](const SeamEdge& x, const SeamEdge& y) {
        return std::tie(x.first, x.a, x.b) < std::tie(y.first, y.a, y.b);
    });
    return seams;
}

namespace {

// The four texels a bilinear lookup at (u, v) reads and their weights (texel centres at (x + 0.5) / width;
// clamped at the borders, where a texel may appear twice).
void bilinearFootprint(int width, int height, double u, double v, uint32_t texel[4], double weight[4]) {
    double x = u * width - 0.5, y = v * height - 0.5;
    double fx = x - std::floor(x), fy = y - std::floor(y);
    int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    int xa = std::clamp(x0, 0, width - 1), xb = std::clamp(x0 + 1, 0, width - 1);
    int ya = std::clamp(y0, 0, height - 1), yb = std::clamp(y0 + 1, 0, height - 1);
    texel[0] = uint32_t(ya * width + xa), weight[0] = (1 - fx) * (1 - fy);
    texel[1] = uint32_t(ya * width + xb), weight[1] = fx * (1 - fy);
    texel[2] = uint32_t(yb * width + xa), weight[2] = (1 - fx) * fy;
    texel[3] = uint32_t(yb * width + xb), weight[3] = fx * fy;
}

// Where parameter s of a seam's side lies in the atlas.
void seamPoint(const TriMesh& mesh, uint32_t from, uint32_t to, double s, double& u, double& v) {
    u = (1 - s) * mesh.texcoords[2 * size_t(from)] + s * mesh.texcoords[2 * size_t(to)];
    v = (1 - s) * mesh.texcoords[2 * size_t(from) + 1] + s * mesh.texcoords[2 * size_t(to) + 1];
}

} // namespace

size_t stitchSeams(const TriMesh& mesh, const std::vector<SeamEdge>& seams, int width, int height, float* texels,
                   int channels, double weight) {
    // One row per seam point: bilinear lookup on the first side minus the one on the second.
    std::map<uint32_t, int> unknownOf; // texel -> unknown, in texel order so the system does not depend on seams' order
    std::vector<std::array<std::pair<uint32_t, double>, 8>> rows;
    for (const SeamEdge& seam : seams) {
        double u[4], v[4];
        seamPoint(mesh, seam.a, seam.b, 0.0, u[0], v[0]);
        seamPoint(mesh, seam.a, seam.b, 1.0, u[1], v[1]);
        seamPoint(mesh, seam.c, seam.d, 0.0, u[2], v[2]);
        seamPoint(mesh, seam.c, seam.d, 1.0, u[3], v[3]);
        double texelLength = std::max(std::hypot((u[1] - u[0]) * width, (v[1] - v[0]) * height),
                                      std::hypot((u[3] - u[2]) * width, (v[3] - v[2]) * height));
        int points = std::max(2, int(std::ceil(3.0 * texelLength)));
        for (int i = 0; i < points; ++i) {
            double s = (i + 0.5) / points, pu, pv;
            std::array<std::pair<uint32_t, double>, 8> row;
            uint32_t texel[4];
            double w[4];
            seamPoint(mesh, seam.a, seam.b, s, pu, pv);
            bilinearFootprint(width, height, pu, pv, texel, w);
            for (int k = 0; k < 4; ++k) row[k] = {texel[k], w[k]};
            seamPoint(mesh, seam.c, seam.d, s, pu, pv);
            bilinearFootprint(width, height, pu, pv, texel, w);
            for (int k = 0; k < 4; ++k) row[4 + k] = {texel[k], -w[k]};
            for (const auto& [t, unused] : row) unknownOf.emplace(t, 0);
            rows.push_back(row);
        }
    }
    if (rows.empty()) return 0;
    std::vector<uint32_t> texelOf;
    for (auto& [texel, unknown] : unknownOf) {
        unknown = int(texelOf.size());
        texelOf.push_back(texel);
    }

    // Normal equations of min |x - x0|^2 + weight |C x|^2: (I + weight C^T C) x = x0, symmetric positive definite.
    int n = int(texelOf.size());
    std::vector<Eigen::Triplet<double>> entries;
    for (int i = 0; i < n; ++i) entries.emplace_back(i, i, 1.0);
    for (const auto& row : rows)
        for (const auto& [ti, wi] : row)
            for (const auto& [tj, wj] : row)
                if (wi != 0.0 && wj != 0.0) entries.emplace_back(unknownOf[ti], unknownOf[tj], weight * wi * wj);
    Eigen::SparseMatrix<double> system(n, n);
    system.setFromTriplets(entries.begin(), entries.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(system);
    if (solver.info() != Eigen::Success) throw Error("", "seam stitching", "factorisation failed", kExitFailure);
    Eigen::MatrixXd original(n, channels);
    for (int i = 0; i < n; ++i)
        for (int c = 0; c < channels; ++c) original(i, c) = texels[size_t(texelOf[i]) * channels + c];
    Eigen::MatrixXd stitched = solver.solve(original);
    size_t changed = 0;
    for (int i = 0; i < n; ++i) {
        bool differs = false;
        for (int c = 0; c < channels; ++c) {
            float value = float(stitched(i, c));
            float& target = texels[size_t(texelOf[i]) * channels + c];
            differs |= value != target;
            target = value;
        }
        changed += differs;
    }
    return changed;
}

void sampleBilinear(const float* texels, int width, int height, int channels, float u, float v, float* out) {
    uint32_t texel[4];
    double weight[4];
    bilinearFootprint(width, height, u, v, texel, weight);
    for (int c = 0; c < channels; ++c) {
        double sum = 0.0;
        for (int k = 0; k < 4; ++k) sum += weight[k] * texels[size_t(texel[k]) * channels + c];
        out[c] = float(sum);
    }
}

namespace {

// Accumulates the jump between two radiance lookups along every seam; `lookup(side, seam, s, rgb)` gives side
// 0's or side 1's radiance at parameter s from (a, c) to (b, d).
template <class Lookup> SeamJump seamJump(const std::vector<SeamEdge>& seams, int pointsPerEdge, Lookup lookup) {
    SeamJump jump;
    double squares = 0.0, sum = 0.0;
    for (const SeamEdge& seam : seams)
        for (int i = 0; i < pointsPerEdge; ++i) {
            float s = (i + 0.5f) / pointsPerEdge, one[3], two[3];
            lookup(0, seam, s, one);
            lookup(1, seam, s, two);
            for (int c = 0; c < 3; ++c) {
                squares += double(one[c] - two[c]) * (one[c] - two[c]);
                sum += 0.5 * (double(one[c]) + two[c]);
            }
            ++jump.points;
        }
    if (jump.points > 0) {
        jump.rms = std::sqrt(squares / (3.0 * jump.points));
        jump.meanRadiance = sum / (3.0 * jump.points);
    }
    return jump;
}

} // namespace

SeamJump texelSeamJump(const TriMesh& mesh, const std::vector<SeamEdge>& seams, const float* radiance,
                       int width, int height, int pointsPerEdge) {
    return seamJump(seams, pointsPerEdge, [&](int side, const SeamEdge& seam, float s, float* rgb) {
        uint32_t from = side == 0 ? seam.a : seam.c, to = side == 0 ? seam.b : seam.d;
        float u = (1 - s) * mesh.texcoords[2 * size_t(from)] + s * mesh.texcoords[2 * size_t(to)];
        float v = (1 - s) * mesh.texcoords[2 * size_t(from) + 1] + s * mesh.texcoords[2 * size_t(to) + 1];
        sampleBilinear(radiance, width, height, 3, u, v, rgb);
    });
}

SeamJump vertexSeamJump(const TriMesh& mesh, const std::vector<SeamEdge>& seams, const float* radiance,
                        int pointsPerEdge) {
    return seamJump(seams, pointsPerEdge, [&](int side, const SeamEdge& seam, float s, float* rgb) {
        uint32_t from = side == 0 ? seam.a : seam.c, to = side == 0 ? seam.b : seam.d;
        for (int c = 0; c < 3; ++c)
            rgb[c] = (1 - s) * radiance[3 * size_t(from) + c] + s * radiance[3 * size_t(to) + c];
    });
}

} // namespace prt
