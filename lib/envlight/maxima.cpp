// Local maxima by hill climbing on the icosphere, and their sub-vertex refinement by a tangent-plane quadric:
// discrete maxima jump by a vertex spacing as a source moves, the quadric's extremum moves continuously.
#include "envlight.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace prt::envlight {

namespace {

// The neighbour with the largest value greater than v's (ties to the lower index), or v itself.
uint32_t uphill(const Icosphere& sphere, const std::vector<double>& values, uint32_t v) {
    uint32_t best = v;
    for (uint32_t k = sphere.neighbourOffsets[v]; k < sphere.neighbourOffsets[v + 1]; ++k) {
        uint32_t n = sphere.neighbours[k];
        if (values[n] > values[best] || (best != v && values[n] == values[best] && n < best)) best = n;
    }
    return best;
}

} // namespace

std::vector<uint32_t> localMaxima(const Icosphere& sphere, const std::vector<double>& values,
                                  std::vector<uint32_t>* basin) {
    const size_t count = sphere.vertexCount();
    std::vector<uint32_t> next(count), top(count);
    for (uint32_t v = 0; v < count; ++v) next[v] = uphill(sphere, values, v);
    std::vector<uint32_t> maxima;
    for (uint32_t v = 0; v < count; ++v) {
        uint32_t u = v;
        while (next[u] != u) u = next[u]; // strictly increasing values: always ends
        top[v] = u;
        if (u == v) maxima.push_back(v);
    }
    if (basin) basin->swap(top);
    return maxima;
}

std::array<double, 3> refineMaximum(const Icosphere& sphere, const std::vector<double>& values, uint32_t vertex) {
    const double* c = &sphere.vertices[vertex * 3];
    Eigen::Vector3d centre(c[0], c[1], c[2]);
    // Tangent frame at the vertex.
    Eigen::Vector3d helper = std::abs(centre.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    Eigen::Vector3d t1 = centre.cross(helper).normalized(), t2 = centre.cross(t1);

    // The vertex, its one-ring and its two-ring.
    std::vector<uint32_t> ring = {vertex};
    auto addRing = [&](uint32_t v) {
        for (uint32_t k = sphere.neighbourOffsets[v]; k < sphere.neighbourOffsets[v + 1]; ++k)
            if (std::find(ring.begin(), ring.end(), sphere.neighbours[k]) == ring.end())
                ring.push_back(sphere.neighbours[k]);
    };
    addRing(vertex);
    size_t oneRing = ring.size();
    for (size_t i = 1; i < oneRing; ++i) addRing(ring[i]);

    Eigen::MatrixXd A(ring.size(), 6);
    Eigen::VectorXd b(ring.size());
    double reach = 0.0; // the one-ring's radius in the tangent plane
    for (size_t i = 0; i < ring.size(); ++i) {
        const double* p = &sphere.vertices[ring[i] * 3];
        Eigen::Vector3d d(p[0], p[1], p[2]);
        Eigen::Vector3d projected = d / d.dot(centre); // gnomonic projection onto the tangent plane
        double u = projected.dot(t1), v = projected.dot(t2);
        if (i < oneRing) reach = std::max(reach, std::hypot(u, v));
        A.row(i) << u * u, u * v, v * v, u, v, 1.0;
        b(i) = values[ring[i]];
    }
    Eigen::VectorXd q = A.colPivHouseholderQr().solve(b);
    Eigen::Matrix2d hessian;
    hessian << 2 * q(0), q(1), q(1), 2 * q(2);
    std::array<double, 3> result = {c[0], c[1], c[2]};
    // Concave: both eigenvalues negative (determinant > 0 and trace < 0).
    if (!(hessian.determinant() > 0.0 && hessian.trace() < 0.0)) return result;
    Eigen::Vector2d offset = hessian.ldlt().solve(-Eigen::Vector2d(q(3), q(4)));
    if (!offset.allFinite() || offset.norm() > reach) return result;
    Eigen::Vector3d refined = (centre + offset(0) * t1 + offset(1) * t2).normalized();
    return {refined.x(), refined.y(), refined.z()};
}

} // namespace prt::envlight
