#include "mesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace prt {

void computeNormals(TriMesh& mesh) {
    const size_t vertexCount = mesh.vertexCount();
    std::vector<Eigen::Vector3d> sum(vertexCount, Eigen::Vector3d::Zero());
    std::vector<Eigen::Vector3d> firstFaceNormal(vertexCount, Eigen::Vector3d::Zero());
    auto position = [&](uint32_t v) {
        return Eigen::Vector3d(mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]);
    };

    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t* corner = &mesh.indices[3 * t];
        Eigen::Vector3d p[3] = {position(corner[0]), position(corner[1]), position(corner[2])};
        Eigen::Vector3d faceNormal = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
        for (int k = 0; k < 3; ++k) {
            Eigen::Vector3d toNext = p[(k + 1) % 3] - p[k];
            Eigen::Vector3d toPrevious = p[(k + 2) % 3] - p[k];
            // atan2 of |cross| and dot stays accurate for angles near 0 and pi, where acos of a cosine does not.
            double angle = std::atan2(toNext.cross(toPrevious).norm(), toNext.dot(toPrevious));
            sum[corner[k]] += angle * faceNormal;
            if (firstFaceNormal[corner[k]].isZero()) firstFaceNormal[corner[k]] = faceNormal;
        }
    }

    mesh.normals.resize(3 * vertexCount);
    for (size_t v = 0; v < vertexCount; ++v) {
        double length = sum[v].norm();
        // A sum this short means the faces around the vertex cancel (back-to-back sheets): it has no direction.
        Eigen::Vector3d normal = length > 1e-9 ? Eigen::Vector3d(sum[v] / length) : firstFaceNormal[v];
        for (int c = 0; c < 3; ++c) mesh.normals[3 * v + c] = float(normal[c]);
    }
}

} // namespace prt
