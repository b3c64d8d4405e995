// Small meshes with known structure and a scratch folder, for the lib/mesh tests.
#pragma once

#include "bundle.h"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace prt::test {

namespace fs = std::filesystem;

// Flips triangles whose normal points toward the origin: makes a convex shape around it wind outward.
inline void orientOutward(TriMesh& mesh) {
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        uint32_t* c = &mesh.indices[3 * t];
        const float* p[3] = {&mesh.positions[3 * c[0]], &mesh.positions[3 * c[1]], &mesh.positions[3 * c[2]]};
        double e1[3], e2[3], centroid[3];
        for (int k = 0; k < 3; ++k)
            e1[k] = p[1][k] - p[0][k], e2[k] = p[2][k] - p[0][k], centroid[k] = p[0][k] + p[1][k] + p[2][k];
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        if (n[0] * centroid[0] + n[1] * centroid[1] + n[2] * centroid[2] < 0) std::swap(c[1], c[2]);
    }
}

// Unit cube centred at the origin: 8 vertices, 6 faces of 2 triangles. `skipFaces` lists faces to leave out
// (0..5: -X +X -Y +Y -Z +Z). Each face is split along the diagonal from its first corner, so corners sit in one
// or two triangles of a face depending on the face.
inline TriMesh makeCube(std::vector<int> skipFaces = {}) {
    TriMesh mesh;
    for (int i = 0; i < 8; ++i)
        mesh.positions.insert(mesh.positions.end(), {i & 1 ? 0.5f : -0.5f, i & 2 ? 0.5f : -0.5f, i & 4 ? 0.5f : -0.5f});
    const uint32_t faces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
    for (int f = 0; f < 6; ++f) {
        if (std::find(skipFaces.begin(), skipFaces.end(), f) != skipFaces.end()) continue;
        const uint32_t* q = faces[f];
        mesh.indices.insert(mesh.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    }
    orientOutward(mesh);
    return mesh;
}

// Square of side 1 in the XZ plane at y = 0, n x n quads, normal +Y (counter-clockwise seen from above).
inline TriMesh makeGrid(int n) {
    TriMesh mesh;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j)
            mesh.positions.insert(mesh.positions.end(), {float(j) / n - 0.5f, 0.0f, float(i) / n - 0.5f});
    auto at = [n](int i, int j) { return uint32_t(i * (n + 1) + j); };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            mesh.indices.insert(mesh.indices.end(),
                                {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    return mesh;
}

// Unit sphere with single pole vertices: 2 + (rings - 1) * segments vertices, 2 * segments * (rings - 1) triangles.
inline TriMesh makeSphere(int rings, int segments) {
    TriMesh mesh;
    mesh.positions = {0, 1, 0};
    for (int r = 1; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            double theta = M_PI * r / rings, phi = 2 * M_PI * s / segments;
            mesh.positions.insert(mesh.positions.end(), {float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)),
                                                         float(std::sin(theta) * std::sin(phi))});
        }
    mesh.positions.insert(mesh.positions.end(), {0, -1, 0});
    uint32_t south = uint32_t(mesh.vertexCount() - 1);
    auto ring = [segments](int r, int s) { return uint32_t(1 + (r - 1) * segments + (s % segments)); };
    for (int s = 0; s < segments; ++s) {
        mesh.indices.insert(mesh.indices.end(), {0, ring(1, s), ring(1, s + 1)});
        mesh.indices.insert(mesh.indices.end(), {south, ring(rings - 1, s), ring(rings - 1, s + 1)});
        for (int r = 1; r + 1 < rings; ++r)
            mesh.indices.insert(mesh.indices.end(),
                                {ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)});
    }
    orientOutward(mesh);
    return mesh;
}

// Every triangle on its own three vertices, as STL stores meshes.
inline TriMesh makeSoup(const TriMesh& mesh) {
    TriMesh soup;
    for (uint32_t v : mesh.indices) {
        soup.positions.insert(soup.positions.end(), &mesh.positions[3 * v], &mesh.positions[3 * v] + 3);
        soup.indices.push_back(uint32_t(soup.indices.size()));
    }
    return soup;
}

// Writes the mesh with OpenMesh's own writer (binary where the format has one): round trips check our side of its
// readers, and binary files give the byte layout the truncation and NaN tests aim at.
inline void writeWithOpenMesh(const TriMesh& mesh, const std::string& file, bool binary) {
    OpenMesh::TriMesh_ArrayKernelT<> out;
    std::vector<OpenMesh::VertexHandle> handles;
    for (size_t v = 0; v < mesh.vertexCount(); ++v)
        handles.push_back(out.add_vertex({mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]}));
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        out.add_face(handles[mesh.indices[3 * t]], handles[mesh.indices[3 * t + 1]], handles[mesh.indices[3 * t + 2]]);
    OpenMesh::IO::Options options;
    if (binary) options += OpenMesh::IO::Options::Binary;
    ASSERT_TRUE(OpenMesh::IO::write_mesh(out, file, options));
}

// An OBJ listing of the mesh's positions and triangles.
inline std::string toObj(const TriMesh& mesh) {
    std::string text;
    char line[128];
    for (size_t v = 0; v < mesh.vertexCount(); ++v) {
        std::snprintf(line, sizeof(line), "v %.9g %.9g %.9g\n", mesh.positions[3 * v], mesh.positions[3 * v + 1],
                      mesh.positions[3 * v + 2]);
        text += line;
    }
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        std::snprintf(line, sizeof(line), "f %u %u %u\n", mesh.indices[3 * t] + 1, mesh.indices[3 * t + 1] + 1,
                      mesh.indices[3 * t + 2] + 1);
        text += line;
    }
    return text;
}

// A fresh folder per test, removed afterwards.
class ScratchTest : public ::testing::Test {
protected:
    void SetUp() override {
        const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("prt_mesh_test_" + std::to_string(getpid()) + "_" + info->test_suite_name() + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    std::string write(const std::string& name, const std::string& bytes) const {
        std::ofstream(path(name), std::ios::binary) << bytes;
        return path(name);
    }

    std::string read(const std::string& name) const {
        std::ifstream in(path(name), std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    }

    size_t fileCount() const { return size_t(std::distance(fs::directory_iterator(dir_), fs::directory_iterator())); }

    fs::path dir_;
};

} // namespace prt::test
