// Tangent frames from the UV parameterisation and tangent-space normal maps of high-mesh detail.
#include "bake.h"

#include <cmath>

namespace prt {

namespace {

double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

void cross3(const double a[3], const double b[3], double out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

bool normalise3(double v[3]) {
    double length = std::sqrt(dot3(v, v));
    if (!(length > 1e-20)) return false;
    for (int a = 0; a < 3; ++a) v[a] /= length;
    return true;
}

// A unit tangent orthogonal to n (Duff et al. 2017), for vertices the UVs say nothing about.
void anyTangent(const double n[3], double t[3]) {
    double sign = std::copysign(1.0, n[2]);
    double a = -1.0 / (sign + n[2]);
    t[0] = 1.0 + sign * n[0] * n[0] * a;
    t[1] = sign * n[0] * n[1] * a;
    t[2] = -sign * n[0];
}

// t minus its component along unit n, normalised; false when t is (nearly) parallel to n.
bool orthogonalise(double t[3], const double n[3]) {
    double along = dot3(t, n);
    for (int a = 0; a < 3; ++a) t[a] -= along * n[a];
    return normalise3(t);
}

} // namespace

std::vector<float> vertexTangents(const TriMesh& mesh) {
    size_t vertexCount = mesh.vertexCount();
    std::vector<double> tangent(3 * vertexCount, 0.0), bitangent(3 * vertexCount, 0.0);
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t* corner = &mesh.indices[3 * t];
        double p[3][3], uv[3][2];
        for (int k = 0; k < 3; ++k) {
            for (int a = 0; a < 3; ++a) p[k][a] = mesh.positions[3 * size_t(corner[k]) + a];
            // Image-up second coordinate: the bitangent follows -v.
            uv[k][0] = mesh.texcoords[2 * size_t(corner[k])];
            uv[k][1] = -double(mesh.texcoords[2 * size_t(corner[k]) + 1]);
        }
        double e1[3], e2[3];
        for (int a = 0; a < 3; ++a) e1[a] = p[1][a] - p[0][a], e2[a] = p[2][a] - p[0][a];
        double du1 = uv[1][0] - uv[0][0], dv1 = uv[1][1] - uv[0][1];
        double du2 = uv[2][0] - uv[0][0], dv2 = uv[2][1] - uv[0][1];
        double det = du1 * dv2 - du2 * dv1;
        if (det == 0.0) continue;
        double faceTangent[3], faceBitangent[3], faceNormal[3];
        for (int a = 0; a < 3; ++a) {
            faceTangent[a] = (e1[a] * dv2 - e2[a] * dv1) / det;
            faceBitangent[a] = (e2[a] * du1 - e1[a] * du2) / det;
        }
        cross3(e1, e2, faceNormal);
        double area = 0.5 * std::sqrt(dot3(faceNormal, faceNormal));
        if (!normalise3(faceTangent) || !normalise3(faceBitangent)) continue;
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) {
                tangent[3 * size_t(corner[k]) + a] += area * faceTangent[a];
                bitangent[3 * size_t(corner[k]) + a] += area * faceBitangent[a];
            }
    }
    std::vector<float> frames(4 * vertexCount);
    for (size_t v = 0; v < vertexCount; ++v) {
        double n[3] = {mesh.normals[3 * v], mesh.normals[3 * v + 1], mesh.normals[3 * v + 2]};
        normalise3(n);
        double* t = &tangent[3 * v];
        double handedness = 1.0;
        if (orthogonalise(t, n)) {
            double expected[3];
            cross3(n, t, expected);
            handedness = dot3(expected, &bitangent[3 * v]) < 0.0 ? -1.0 : 1.0;
        } else {
            anyTangent(n, t);
        }
        for (int a = 0; a < 3; ++a) frames[4 * v + a] = float(t[a]);
        frames[4 * v + 3] = float(handedness);
    }
    return frames;
}

std::vector<float> tangentSpaceNormals(const TriMesh& mesh, const std::vector<float>& tangents,
                                       const TexelSamples& samples, const std::vector<float>& objectNormals) {
    size_t count = samples.texel.size();
    std::vector<float> out(3 * count);
    for (size_t i = 0; i < count; ++i) {
        const uint32_t* corner = &mesh.indices[3 * size_t(samples.triangle[i])];
        const float* w = &samples.barycentric[3 * i];
        double n[3] = {0, 0, 0}, t[3] = {0, 0, 0}, handedness = 0.0;
        for (int k = 0; k < 3; ++k) {
            for (int a = 0; a < 3; ++a) {
                n[a] += w[k] * double(mesh.normals[3 * size_t(corner[k]) + a]);
                t[a] += w[k] * double(tangents[4 * size_t(corner[k]) + a]);
            }
            handedness += w[k] * double(tangents[4 * size_t(corner[k]) + 3]);
        }
        if (!normalise3(n)) {
            out[3 * i + 2] = 1.0f;
            continue;
        }
        if (!orthogonalise(t, n)) anyTangent(n, t);
        double b[3];
        cross3(n, t, b);
        double sign = handedness < 0.0 ? -1.0 : 1.0;
        double detail[3] = {objectNormals[3 * i], objectNormals[3 * i + 1], objectNormals[3 * i + 2]};
        double local[3] = {dot3(detail, t), sign * dot3(detail, b), dot3(detail, n)};
        if (!normalise3(local)) local[0] = local[1] = 0.0, local[2] = 1.0;
        for (int a = 0; a < 3; ++a) out[3 * i + a] = float(local[a]);
    }
    return out;
}

} // namespace prt
