#include "mesh.h"

#include "core.h"
#include "quiet_openmesh.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <OpenMesh/Tools/Decimater/Observer.hh>

#include <algorithm>
#include <numeric>

namespace prt {
namespace {

using HalfedgeMesh = OpenMesh::TriMesh_ArrayKernelT<>;
constexpr double kMaxNormalTurnDegrees = 60.0;
// Where the quadric error is zero everywhere (flat regions) any collapse is free, and without a shape limit the
// decimater piles collapses onto one vertex: fans of ever higher valence, each collapse slower than the last.
constexpr float kMaxAspectRatio = 5.0f;
constexpr size_t kProgressInterval = 1024;

class DecimationProgress final : public OpenMesh::Decimater::Observer {
public:
    explicit DecimationProgress(Progress& progress) : Observer(kProgressInterval), progress_(progress) {}
    void notify(size_t) override { progress_.add(kProgressInterval); }

private:
    Progress& progress_;
};

} // namespace

std::vector<uint32_t> decimate(TriMesh& mesh, size_t targetTriangles) {
    if (mesh.triangleCount() <= targetTriangles) {
        std::vector<uint32_t> identity(mesh.vertexCount());
        std::iota(identity.begin(), identity.end(), 0u);
        return identity;
    }
    detail::QuietOpenMesh quiet; // add_face prints for every triangle it refuses; those are handled below

    HalfedgeMesh halfedges;
    OpenMesh::VPropHandleT<uint32_t> source;
    halfedges.add_property(source);
    auto addVertex = [&](uint32_t v) {
        const float* p = &mesh.positions[3 * v];
        OpenMesh::VertexHandle handle = halfedges.add_vertex(HalfedgeMesh::Point(p[0], p[1], p[2]));
        halfedges.property(source, handle) = v;
        return handle;
    };
    std::vector<OpenMesh::VertexHandle> handle(mesh.vertexCount());
    for (uint32_t v = 0; v < mesh.vertexCount(); ++v) handle[v] = addVertex(v);
    size_t separated = 0;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t* corner = &mesh.indices[3 * t];
        if (halfedges.add_face(handle[corner[0]], handle[corner[1]], handle[corner[2]]).is_valid()) continue;
        // A non-manifold edge or vertex: the triangle stands apart on copies of its vertices.
        halfedges.add_face(addVertex(corner[0]), addVertex(corner[1]), addVertex(corner[2]));
        ++separated;
    }
    if (separated > 0)
        logWarn("decimate: " + std::to_string(separated) +
                " triangle(s) on non-manifold edges or vertices stand apart on copies of their vertices");

    halfedges.request_vertex_status();
    halfedges.request_edge_status();
    halfedges.request_face_status();
    halfedges.request_face_normals();
    halfedges.update_face_normals();
    OpenMesh::Decimater::DecimaterT<HalfedgeMesh> decimater(halfedges);
    OpenMesh::Decimater::ModQuadricT<HalfedgeMesh>::Handle quadric;
    OpenMesh::Decimater::ModNormalFlippingT<HalfedgeMesh>::Handle flipping;
    OpenMesh::Decimater::ModAspectRatioT<HalfedgeMesh>::Handle aspect;
    decimater.add(quadric);
    decimater.add(flipping);
    decimater.add(aspect);
    decimater.module(quadric).unset_max_err();
    decimater.module(flipping).set_max_normal_deviation(kMaxNormalTurnDegrees);
    decimater.module(aspect).set_aspect_ratio(kMaxAspectRatio);
    if (!decimater.initialize()) throw Error("", "decimate", "OpenMesh's decimater did not initialize", kExitFailure);
    // Each interior collapse removes two triangles.
    Progress progress("decimate", (mesh.triangleCount() - targetTriangles) / 2);
    DecimationProgress observer(progress);
    decimater.set_observer(&observer);
    decimater.decimate_to_faces(0, targetTriangles);
    decimater.set_observer(nullptr);
    progress.finish();
    halfedges.garbage_collection();

    // garbage_collection fills holes from the end, so order the survivors by input vertex again.
    std::vector<OpenMesh::VertexHandle> survivors(halfedges.vertices_begin(), halfedges.vertices_end());
    std::stable_sort(survivors.begin(), survivors.end(), [&](OpenMesh::VertexHandle a, OpenMesh::VertexHandle b) {
        return halfedges.property(source, a) < halfedges.property(source, b);
    });
    std::vector<uint32_t> sourceVertex(survivors.size());
    std::vector<uint32_t> outputIndex(halfedges.n_vertices());
    for (size_t k = 0; k < survivors.size(); ++k) {
        sourceVertex[k] = halfedges.property(source, survivors[k]);
        outputIndex[survivors[k].idx()] = uint32_t(k);
    }

    TriMesh decimated;
    auto gather = [&](const std::vector<float>& values, std::vector<float>& out, size_t width) {
        if (values.empty()) return;
        out.resize(sourceVertex.size() * width);
        for (size_t k = 0; k < sourceVertex.size(); ++k) std::copy_n(&values[sourceVertex[k] * width], width, &out[k * width]);
    };
    gather(mesh.positions, decimated.positions, 3);
    gather(mesh.normals, decimated.normals, 3);
    gather(mesh.texcoords, decimated.texcoords, 2);
    gather(mesh.albedo, decimated.albedo, 3);
    decimated.indices.reserve(3 * halfedges.n_faces());
    for (OpenMesh::FaceHandle face : halfedges.faces())
        for (OpenMesh::VertexHandle v : halfedges.fv_range(face)) decimated.indices.push_back(outputIndex[v.idx()]);
    mesh = std::move(decimated);

    // Collapses never leave a vertex without triangles, but an isolated one would have no normal: drop any.
    std::vector<uint32_t> used = removeUnusedVertices(mesh);
    for (uint32_t& v : used) v = sourceVertex[v];
    return used;
}

} // namespace prt
