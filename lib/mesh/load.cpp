#include "mesh.h"

#include "core.h"
#include "file_check.h"
#include "quiet_openmesh.h"

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <tuple>

namespace prt {
namespace {

using OpenMesh::EdgeHandle;
using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::Vec2f;
using OpenMesh::Vec3d;
using OpenMesh::Vec3f;
using OpenMesh::Vec3uc;
using OpenMesh::Vec4f;
using OpenMesh::Vec4uc;
using OpenMesh::VertexHandle;
using OpenMesh::Attributes::StatusInfo;

// 8-bit colours in mesh files are display-referred by convention, so they are sRGB-encoded.
float decodeSrgb(unsigned char encoded) {
    float c = encoded / 255.0f;
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// A per-vertex attribute of `width` floats that only some vertices may have.
struct OptionalAttribute {
    int width;
    std::vector<float> values;
    std::vector<uint8_t> present;

    void grow(size_t vertices) {
        values.resize(vertices * width);
        present.resize(vertices);
    }
    void set(size_t v, const float* x) {
        if (v >= present.size()) return; // a reader naming a vertex that does not exist: validation reports the face
        std::copy(x, x + width, values.begin() + v * width);
        present[v] = 1;
    }
    // Whether vertex v carries exactly `x` (nullptr: carries nothing).
    bool holds(size_t v, const float* x) const {
        if (!x) return !present[v];
        return present[v] && std::memcmp(&values[v * width], x, width * sizeof(float)) == 0;
    }
};

// Collects what an OpenMesh reader emits, as it emits it. OpenMesh's own mesh kernels refuse non-manifold faces
// and duplicate vertices to fit them in, but validation must see the file's own indices.
// OBJ gives texcoords and normals per corner (the reader calls set_texcoord / set_normal for each corner of a
// face just before add_face), so in corner mode they are held until add_face and a corner that disagrees with an
// earlier corner at the same vertex gets a copy of the vertex.
class TriMeshImporter final : public OpenMesh::IO::BaseImporter {
public:
    explicit TriMeshImporter(bool cornerAttributes) : cornerAttributes_(cornerAttributes) {}

    VertexHandle add_vertex(const Vec3f& point) override {
        VertexHandle handle = add_vertex();
        set_point(handle, point);
        return handle;
    }
    VertexHandle add_vertex() override {
        size_t v = vertexCount();
        positions_.resize(positions_.size() + 3);
        grow(v + 1);
        sourceVertex_.push_back(uint32_t(v));
        ++fileVertices_;
        return VertexHandle(int(v));
    }
    void set_point(VertexHandle v, const Vec3f& point) override {
        if (v.idx() >= 0 && size_t(v.idx()) < vertexCount()) std::copy(point.data(), point.data() + 3, &positions_[3 * v.idx()]);
    }

    FaceHandle add_face(const VHandles& corners) override {
        corners_.clear();
        for (VertexHandle corner : corners)
            corners_.push_back(cornerAttributes_ ? splitCorner(corner.idx()) : uint32_t(corner.idx()));
        pendingTexcoords_.clear();
        pendingNormals_.clear();
        if (corners_.size() < 3) ++polygonsWithoutTriangle_;
        if (corners_.size() > 3) ++polygonsTriangulated_;
        for (size_t k = 1; k + 1 < corners_.size(); ++k)
            indices_.insert(indices_.end(), {corners_[0], corners_[k], corners_[k + 1]});
        return FaceHandle(int(polygons_++));
    }

    void set_normal(VertexHandle v, const Vec3f& normal) override {
        if (cornerAttributes_) pendingNormals_.push_back({v.idx(), {normal[0], normal[1], normal[2]}});
        else normals_.set(size_t(v.idx()), normal.data());
    }
    void set_normal(VertexHandle v, const Vec3d& normal) override { set_normal(v, Vec3f(normal)); }
    void set_texcoord(VertexHandle v, const Vec2f& texcoord) override {
        if (cornerAttributes_) pendingTexcoords_.push_back({v.idx(), {texcoord[0], texcoord[1], 0.0f}});
        else texcoords_.set(size_t(v.idx()), texcoord.data());
    }
    void set_color(VertexHandle v, const Vec3uc& c) override {
        setAlbedo(v, {decodeSrgb(c[0]), decodeSrgb(c[1]), decodeSrgb(c[2])});
    }
    void set_color(VertexHandle v, const Vec4uc& c) override {
        setAlbedo(v, {decodeSrgb(c[0]), decodeSrgb(c[1]), decodeSrgb(c[2])});
    }
    void set_color(VertexHandle v, const Vec3f& c) override { setAlbedo(v, {c[0], c[1], c[2]}); }
    void set_color(VertexHandle v, const Vec4f& c) override { setAlbedo(v, {c[0], c[1], c[2]}); }

    // What the readers may call but a triangle soup does not keep: halfedge structure, status bits, face and edge
    // attributes, per-face texcoords (OBJ sends the same data per vertex too), 3D texcoords, materials.
    HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }
    FaceHandle add_face(HalfedgeHandle) override { return FaceHandle(); }
    void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<Vec2f>&) override {}
    void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<Vec3f>&) override {}
    void set_face_texindex(FaceHandle, int) override {}
    void set_halfedge(VertexHandle, HalfedgeHandle) override {}
    void set_status(VertexHandle, const StatusInfo&) override {}
    void set_next(HalfedgeHandle, HalfedgeHandle) override {}
    void set_face(HalfedgeHandle, FaceHandle) override {}
    void request_face_texcoords2D() override {}
    void set_texcoord(HalfedgeHandle, const Vec2f&) override {}
    void set_texcoord(VertexHandle, const Vec3f&) override {}
    void set_texcoord(HalfedgeHandle, const Vec3f&) override {}
    void set_status(HalfedgeHandle, const StatusInfo&) override {}
    void set_color(EdgeHandle, const Vec3uc&) override {}
    void set_color(EdgeHandle, const Vec4uc&) override {}
    void set_color(EdgeHandle, const Vec3f&) override {}
    void set_color(EdgeHandle, const Vec4f&) override {}
    void set_status(EdgeHandle, const StatusInfo&) override {}
    void set_normal(FaceHandle, const Vec3f&) override {}
    void set_normal(FaceHandle, const Vec3d&) override {}
    void set_color(FaceHandle, const Vec3uc&) override {}
    void set_color(FaceHandle, const Vec4uc&) override {}
    void set_color(FaceHandle, const Vec3f&) override {}
    void set_color(FaceHandle, const Vec4f&) override {}
    void set_status(FaceHandle, const StatusInfo&) override {}
    void add_texture_information(int, std::string) override {}

    size_t n_vertices() const override { return vertexCount(); }
    size_t n_faces() const override { return polygons_; }
    size_t n_edges() const override { return 0; }

    size_t vertexCount() const { return positions_.size() / 3; }
    size_t fileVertices() const { return fileVertices_; }
    size_t polygons() const { return polygons_; }

    // The collected mesh. An attribute is kept when every vertex a triangle uses has it.
    TriMesh assemble(const std::string& path, MeshFileInfo& info) {
        TriMesh mesh;
        mesh.positions = std::move(positions_);
        mesh.indices = std::move(indices_);
        auto keep = [&](OptionalAttribute& attribute, std::vector<float>& out, const char* name) {
            size_t have = 0, used = 0;
            for (uint32_t v : mesh.indices)
                if (v < attribute.present.size()) ++used, have += attribute.present[v];
            if (have == used && used > 0) out = std::move(attribute.values);
            else if (have > 0) logWarn(path + ": only some vertices have " + name + "; ignoring them");
        };
        keep(normals_, mesh.normals, "normals");
        keep(texcoords_, mesh.texcoords, "texcoords");
        keep(albedo_, mesh.albedo, "colours");
        for (size_t i = 1; i < mesh.texcoords.size(); i += 2)
            mesh.texcoords[i] = 1.0f - mesh.texcoords[i]; // glTF's v points down
        info.fileVertices = fileVertices_;
        info.polygonsTriangulated = polygonsTriangulated_;
        info.degenerateFacesDropped += polygonsWithoutTriangle_;
        info.sourceVertex = std::move(sourceVertex_);
        return mesh;
    }

private:
    struct PendingCorner {
        int vertex;
        std::array<float, 3> value;
    };

    void grow(size_t vertices) {
        normals_.grow(vertices);
        texcoords_.grow(vertices);
        albedo_.grow(vertices);
        cornerAssigned_.resize(vertices);
    }

    void setAlbedo(VertexHandle v, std::array<float, 3> rgb) { albedo_.set(size_t(v.idx()), rgb.data()); }

    static const float* pendingValue(const std::vector<PendingCorner>& pending, int vertex) {
        for (auto it = pending.rbegin(); it != pending.rend(); ++it)
            if (it->vertex == vertex) return it->value.data();
        return nullptr;
    }

    // The vertex a corner ends up using: the file's vertex if its attributes agree, else a copy that carries them.
    uint32_t splitCorner(int vertex) {
        if (vertex < 0 || size_t(vertex) >= fileVertices_) return uint32_t(vertex); // out of range: validation reports it
        const float* texcoord = pendingValue(pendingTexcoords_, vertex);
        const float* normal = pendingValue(pendingNormals_, vertex);
        auto assign = [&](size_t v) {
            if (texcoord) texcoords_.set(v, texcoord);
            if (normal) normals_.set(v, normal);
            cornerAssigned_[v] = 1;
        };
        if (!cornerAssigned_[vertex]) {
            assign(size_t(vertex));
            return uint32_t(vertex);
        }
        if (texcoords_.holds(vertex, texcoord) && normals_.holds(vertex, normal)) return uint32_t(vertex);

        CopyKey key{uint32_t(vertex), uint8_t((texcoord ? 1 : 0) | (normal ? 2 : 0)), {}};
        if (texcoord) std::memcpy(&key.bits[0], texcoord, 2 * sizeof(float));
        if (normal) std::memcpy(&key.bits[2], normal, 3 * sizeof(float));
        auto found = copies_.find(key);
        if (found != copies_.end()) return found->second;
        uint32_t copy = uint32_t(vertexCount());
        positions_.insert(positions_.end(), positions_.begin() + 3 * vertex, positions_.begin() + 3 * vertex + 3);
        grow(copy + 1);
        if (albedo_.present[vertex]) albedo_.set(copy, &albedo_.values[3 * vertex]);
        assign(copy);
        sourceVertex_.push_back(uint32_t(vertex));
        copies_.emplace(key, copy);
        return copy;
    }

    struct CopyKey {
        uint32_t vertex;
        uint8_t which;
        std::array<uint32_t, 5> bits; // texcoord then normal, as bit patterns
        bool operator<(const CopyKey& o) const { return std::tie(vertex, which, bits) < std::tie(o.vertex, o.which, o.bits); }
    };

    bool cornerAttributes_;
    std::vector<float> positions_;
    OptionalAttribute normals_{3, {}, {}};
    OptionalAttribute texcoords_{2, {}, {}};
    OptionalAttribute albedo_{3, {}, {}};
    std::vector<uint32_t> indices_;
    std::vector<uint32_t> sourceVertex_;
    size_t fileVertices_ = 0;
    size_t polygons_ = 0;
    size_t polygonsTriangulated_ = 0;
    size_t polygonsWithoutTriangle_ = 0;
    std::vector<uint32_t> corners_;
    std::vector<PendingCorner> pendingTexcoords_;
    std::vector<PendingCorner> pendingNormals_;
    std::vector<uint8_t> cornerAssigned_;
    std::map<CopyKey, uint32_t> copies_;
};

void requireTriangles(const TriMesh& mesh, const MeshFileInfo& info, const std::string& path) {
    if (mesh.triangleCount() > 0 && mesh.vertexCount() > 0) return;
    if (info.degenerateFacesDropped > 0)
        throw Error(path, "", "all " + std::to_string(info.degenerateFacesDropped) + " faces are degenerate");
    throw Error(path, "", "empty mesh (" + std::to_string(mesh.vertexCount()) + " vertices, no faces)");
}

TriMesh loadGltf(const std::string& path, MeshFileInfo& info) {
    Bundle bundle = readBundle(path);
    if (!bundle.layers.empty())
        logWarn(path + ": dropping its " + std::to_string(bundle.layers.size()) +
                " layers: meshprep changes the vertices they describe");
    info.hash = hashFile(path);
    info.fileVertices = bundle.mesh.vertexCount();
    info.filePolygons = bundle.mesh.triangleCount();
    info.sourceVertex.resize(info.fileVertices);
    for (size_t v = 0; v < info.fileVertices; ++v) info.sourceVertex[v] = uint32_t(v);
    return std::move(bundle.mesh);
}

} // namespace

TriMesh loadMesh(const std::string& path, MeshFileInfo* info) {
    MeshFileInfo local;
    MeshFileInfo& out = info ? *info : local;
    out = MeshFileInfo();
    out.format = fileExtension(path);
    if (out.format == "gltf" || out.format == "glb") {
        TriMesh mesh = loadGltf(path, out);
        requireTriangles(mesh, out, path);
        return mesh;
    }
    detail::CheckedFile (*check)(std::string_view, const std::string&) = nullptr;
    if (out.format == "obj") check = detail::checkObj;
    else if (out.format == "off") check = detail::checkOff;
    else if (out.format == "ply") check = detail::checkPly;
    else if (out.format == "stl") check = detail::checkStl;
    else throw Error(path, "", "unknown mesh format '" + out.format + "' (expected obj, ply, off, stl, gltf or glb)");

    std::string bytes = readFileBytes(path);
    if (bytes.empty()) throw Error(path, "", "empty mesh (the file is empty)");
    out.hash = hashBytes(bytes.data(), bytes.size());
    if (out.format == "obj" || out.format == "off") detail::dropUtf8Bom(bytes);
    detail::CheckedFile declared = check(bytes, path);

    // The reader gets the bytes that were checked, not a second read of the file.
    std::istringstream stream(declared.readerInput.empty() ? std::move(bytes) : std::move(declared.readerInput));
    TriMeshImporter importer(out.format == "obj");
    OpenMesh::IO::Options options = OpenMesh::IO::Options::VertexNormal;
    options += OpenMesh::IO::Options::VertexTexCoord;
    options += OpenMesh::IO::Options::VertexColor;
    if (declared.binary) options += OpenMesh::IO::Options::Binary;
    bool read;
    {
        detail::QuietOpenMesh quiet;
        read = OpenMesh::IO::IOManager().read(stream, out.format, importer, options);
    }
    if (!read) throw Error(path, "", "OpenMesh's " + out.format + " reader refused the file");
    if (declared.vertices != detail::kUnknownCount && importer.fileVertices() != declared.vertices)
        throw Error(path, "",
                    "OpenMesh's reader returned " + std::to_string(importer.fileVertices()) + " of the " +
                        std::to_string(declared.vertices) + " vertices the file lists");
    if (importer.polygons() != declared.faces - declared.facesWithoutTriangle)
        throw Error(path, "",
                    "OpenMesh's reader returned " + std::to_string(importer.polygons()) + " of the " +
                        std::to_string(declared.faces - declared.facesWithoutTriangle) + " faces the file lists");

    out.filePolygons = declared.faces;
    out.degenerateFacesDropped = declared.facesWithoutTriangle;
    TriMesh mesh = importer.assemble(path, out);
    requireTriangles(mesh, out, path);
    return mesh;
}

} // namespace prt
