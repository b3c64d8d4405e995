// The 92-view set: a frequency-3 (edge-trisected) geodesic icosahedron, built once.
#include "glossy.h"

#include "sh.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace prt::glossy {

namespace {

ViewSet buildViewSet() {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    const double corners[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                   {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    const int faces[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                              {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                              {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    ViewSet set;
    // Points are keyed by their barycentric multiset over corner indices, so shared edge points merge exactly.
    std::map<std::vector<std::pair<int, int>>, uint32_t> index;
    auto point = [&](const int face[3], int i, int j, int k) {
        std::vector<std::pair<int, int>> key;
        const int weights[3] = {i, j, k};
        for (int c = 0; c < 3; ++c)
            if (weights[c] > 0) key.push_back({face[c], weights[c]});
        std::sort(key.begin(), key.end());
        auto [it, inserted] = index.emplace(key, uint32_t(set.directions.size()));
        if (inserted) {
            double d[3] = {0, 0, 0};
            for (auto [corner, weight] : key)
                for (int c = 0; c < 3; ++c) d[c] += weight * corners[corner][c];
            double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            set.directions.push_back({float(d[0] / length), float(d[1] / length), float(d[2] / length)});
        }
        return it->second;
    };
    // Corners first, so views 0..11 are the icosahedron's.
    for (int c = 0; c < 12; ++c) {
        int face[3] = {c, c, c};
        point(face, 3, 0, 0);
    }
    for (const auto& face : faces) {
        // Rows of the trisected face: point (i, j, k) with i + j + k = 3 weights the corners.
        auto p = [&](int i, int j) { return point(face, i, j, 3 - i - j); };
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3 - i; ++j) {
                set.triangles.push_back({p(i + 1, j), p(i, j + 1), p(i, j)});
                if (i + j < 2) set.triangles.push_back({p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)});
            }
    }
    // Wind every triangle counter-clockwise seen from outside.
    for (auto& tri : set.triangles) {
        const auto &a = set.directions[tri[0]], &b = set.directions[tri[1]], &c = set.directions[tri[2]];
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) e1[k] = b[k] - a[k], e2[k] = c[k] - a[k];
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        if (n[0] * a[0] + n[1] * a[1] + n[2] * a[2] < 0) std::swap(tri[1], tri[2]);
    }
    set.neighbours.resize(set.directions.size());
    for (const auto& tri : set.triangles)
        for (int e = 0; e < 3; ++e) {
            set.neighbours[tri[e]].push_back(tri[(e + 1) % 3]);
            set.neighbours[tri[(e + 1) % 3]].push_back(tri[e]);
        }
    for (auto& ring : set.neighbours) {
        std::sort(ring.begin(), ring.end());
        ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    }
    return set;
}

} // namespace

const ViewSet& viewSet() {
    static const ViewSet set = buildViewSet();
    return set;
}

DirectionGrid cubeGrid(int resolution) {
    DirectionGrid grid;
    grid.resolution = resolution;
    // The texel centres of a cube strip of faces `resolution` texels wide, in strip order, and their exact solid
    // angles: prt's one cube layout (sh::kCubeFaces, docs/conventions.md "Cube maps").
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < resolution; ++row)
            for (int column = 0; column < resolution; ++column) {
                double d[3];
                sh::cubeStripDirection(resolution, column, face * resolution + row, d);
                for (int c = 0; c < 3; ++c) grid.directions.push_back(float(d[c]));
                const double a0 = -1.0 + 2.0 * column / resolution, a1 = -1.0 + 2.0 * (column + 1) / resolution;
                const double b0 = 1.0 - 2.0 * (row + 1) / resolution, b1 = 1.0 - 2.0 * row / resolution;
                grid.solidAngle.push_back(float(sh::cubeRectangleSolidAngle(a0, a1, b0, b1)));
            }
    return grid;
}

DirectionGrid heldOutGrid(int resolution) {
    DirectionGrid grid = cubeGrid(resolution);
    // Rodrigues' rotation about the unit axis (1, 2, 3) / sqrt(14) by 0.5 rad: a generic turn, so no direction of
    // the turned grid lands on the unturned one (the nearest pair is tested) and no face is aligned with the axes.
    const double angle = 0.5, c = std::cos(angle), s = std::sin(angle), n = std::sqrt(14.0);
    const double k[3] = {1.0 / n, 2.0 / n, 3.0 / n};
    for (size_t i = 0; i < grid.count(); ++i) {
        float* d = &grid.directions[i * 3];
        const double v[3] = {d[0], d[1], d[2]};
        const double along = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
        const double cross[3] = {k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]};
        double r[3], length = 0.0;
        for (int a = 0; a < 3; ++a) r[a] = v[a] * c + cross[a] * s + k[a] * along * (1.0 - c), length += r[a] * r[a];
        for (int a = 0; a < 3; ++a) d[a] = float(r[a] / std::sqrt(length));
    }
    return grid;
}

void tabulateKernel(const DirectionGrid& grid, const float normal[3], const float outgoing[3], const Phong& phong,
                    const uint8_t* visibility, float* kernel) {
    double cosOut = double(normal[0]) * outgoing[0] + double(normal[1]) * outgoing[1] + double(normal[2]) * outgoing[2];
    double mirror[3];
    for (int c = 0; c < 3; ++c) mirror[c] = 2.0 * cosOut * normal[c] - outgoing[c];
    const double scale = phong.ks * (phong.exponent + 2.0) / (2.0 * 3.14159265358979323846);
    for (size_t i = 0; i < grid.count(); ++i) {
        const float* w = &grid.directions[i * 3];
        double cosine = normal[0] * double(w[0]) + normal[1] * double(w[1]) + normal[2] * double(w[2]);
        double lobe = mirror[0] * w[0] + mirror[1] * w[1] + mirror[2] * w[2];
        bool seen = cosOut > 0.0 && cosine > 0.0 && lobe > 0.0 && (!visibility || visibility[i]);
        kernel[i] = seen ? float(scale * std::pow(lobe, phong.exponent) * cosine) : 0.0f;
    }
}

} // namespace prt::glossy
