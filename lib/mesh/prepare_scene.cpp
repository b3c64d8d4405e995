// Mesh preparation of a scene (a glTF asset): validated receiver by receiver, given normals where a primitive has
// none, and otherwise kept as it is, so that the bundle is the asset.
#include "mesh.h"

#include "core.h"
#include "material.h"

#include <cmath>
#include <set>

namespace prt {
namespace {

std::string receiverPlace(const SceneReceiver& receiver) {
    return "meshes[" + std::to_string(receiver.mesh) + "].primitives[" + std::to_string(receiver.primitive) + "] (node " +
           std::to_string(receiver.node) + ")";
}

// Every receiver's indices inside its own vertices and every value finite, albedo and colours in [0, 1]; named
// by the primitive and node, which is where a user can find the fault in the asset.
void validateScene(const Bundle& bundle, const std::string& file) {
    const TriMesh& mesh = bundle.mesh;
    const SceneAsset& asset = *bundle.asset;
    for (const SceneReceiver& receiver : asset.receivers) {
        const std::string place = receiverPlace(receiver);
        const uint32_t first = receiver.firstVertex, end = receiver.firstVertex + receiver.vertexCount;
        for (size_t t = receiver.firstTriangle; t < size_t(receiver.firstTriangle) + receiver.triangleCount; ++t)
            for (int k = 0; k < 3; ++k) {
                uint32_t index = mesh.indices[3 * t + k];
                if (index < first || index >= end)
                    throw Error(file, place + ".indices", "triangle " + std::to_string(t - receiver.firstTriangle) +
                                                              " names a vertex the primitive does not have");
            }
        auto checkFinite = [&](const std::vector<float>& values, int width, const char* what, bool unit) {
            if (values.empty()) return;
            for (size_t v = first; v < end; ++v)
                for (int c = 0; c < width; ++c) {
                    float x = values[width * v + c];
                    if (!std::isfinite(x) || (unit && (x < 0.0f || x > 1.0f)))
                        throw Error(file, place + "." + what, "vertex " + std::to_string(v - first) + " is " +
                                                                  (unit ? "not in [0, 1]" : "not finite"));
                }
        };
        checkFinite(mesh.positions, 3, "POSITION", false);
        checkFinite(mesh.normals, 3, "NORMAL", false);
        checkFinite(asset.texcoords[0], 2, "TEXCOORD_0", false);
        checkFinite(asset.texcoords[1], 2, "TEXCOORD_1", false);
        checkFinite(asset.colors, 4, "COLOR_0", true);
    }
}

} // namespace

PreparedScene prepareScene(const MeshprepOptions& options, Bundle bundle) {
    auto refuse = [&](const char* flag) {
        throw Error("", flag, "does not apply to a scene (a glTF file, or an OBJ with its MTL materials), which "
                              "meshprep keeps as it is; add --flatten to merge the scene into one welded mesh first",
                    kExitUsage);
    };
    if (options.decimateTo > 0) refuse("--decimate-to");
    if (options.scale != 1.0) refuse("--scale");
    if (options.recomputeNormals) refuse("--recompute-normals");
    if (options.weldIgnoreAttributes) refuse("--weld-ignore-attributes");

    if (!bundle.asset) throw Error(options.input, "", "is a bundle of prt meshes, not a glTF scene", kExitFailure);
    validateScene(bundle, options.input);
    decodeSurface(bundle, options.input); // every texture decodes, within the size limits

    // Primitives without NORMAL get angle-weighted normals in their own space, stored in the asset; in primitives
    // whose NORMAL holds zero vectors (exporters write them for degenerate corners), those vertices get them and
    // every authored normal is kept.
    std::vector<PrimitiveTriangles> missing = primitivesWithoutNormals(bundle, options.input);
    size_t repairedVertices = 0;
    for (PrimitiveTriangles& p : missing) {
        TriMesh& triangles = p.triangles;
        const std::vector<float> authored = triangles.normals;
        for (uint32_t& index : triangles.indices)
            if (index >= triangles.vertexCount()) index = 0; // validateScene has refused these already
        removeDegenerateFaces(triangles);
        computeNormals(triangles);
        for (size_t v = 0; v < triangles.vertexCount(); ++v) {
            float* n = &triangles.normals[3 * v];
            const float* a = authored.empty() ? nullptr : &authored[3 * v];
            if (a && (a[0] != 0.0f || a[1] != 0.0f || a[2] != 0.0f)) {
                std::copy(a, a + 3, n);
                continue;
            }
            repairedVertices += a != nullptr;
            if (!(std::fabs(n[0]) + std::fabs(n[1]) + std::fabs(n[2]) > 0.0f) || !std::isfinite(n[0] + n[1] + n[2]))
                n[0] = 0.0f, n[1] = 1.0f, n[2] = 0.0f; // a vertex on no triangle
        }
    }
    if (repairedVertices > 0)
        logWarn("meshprep: " + options.input + ": " + std::to_string(repairedVertices) +
                " authored normals were zero vectors; computed from their triangles instead");
    if (!missing.empty()) bundle = withPrimitiveNormals(bundle, missing, options.input);

    const SceneAsset& asset = *bundle.asset;
    const TriMesh& mesh = bundle.mesh;
    // Instances: placements (a node placing a mesh) of a mesh that an earlier node placed already.
    std::set<int> meshes;
    std::set<std::pair<int, int>> placements;
    size_t instanced = 0;
    for (const SceneReceiver& receiver : asset.receivers)
        if (placements.insert({receiver.node, receiver.mesh}).second) instanced += !meshes.insert(receiver.mesh).second;
    size_t textured = 0, cutout = 0;
    for (const MaterialRecord& material : asset.materials) {
        textured += material.baseColorTexture >= 0;
        cutout += material.alphaMode != AlphaMode::Opaque;
    }
    const MeshTopology topology = analyzeTopology(mesh);
    const Bounds bounds = computeBounds(mesh);
    PreparedScene prepared;
    prepared.report = {
        {"input", {{"path", options.input}, {"hash", hashFile(options.input)}, {"format", fileExtension(options.input)}}},
        {"scene",
         {{"receivers", asset.receivers.size()},
          {"meshes", meshes.size()},
          {"instances", instanced},
          {"materials", asset.materials.size() - 1},
          {"textured_materials", textured},
          {"cutout_materials", cutout},
          {"textures", asset.textures.size()},
          {"images", asset.images.size()},
          {"normals_computed_for_primitives", missing.size()},
          {"zero_normals_repaired", repairedVertices}}},
        {"counts",
         {{"vertices_in", mesh.vertexCount()},
          {"faces_in", mesh.triangleCount()},
          {"triangles_in", mesh.triangleCount()},
          {"vertices_out", mesh.vertexCount()},
          {"faces_out", mesh.triangleCount()}}},
        {"bounds", {{"min", bounds.min}, {"max", bounds.max}, {"diagonal", bounds.diagonal}}},
        {"boundary", {{"edges", topology.boundaryEdges}, {"loops", topology.boundaryLoops}}},
        {"non_manifold_edges", topology.nonManifoldEdges},
        {"vertex_order", "the scene's rows: receivers in node order, then vertices in accessor order (docs/bundle.md "
                         "\"Scene bundles\"); nothing is welded, removed or reordered"},
    };
    bundle.producer = {{"tool", "prt"}, {"version", options.toolVersion}, {"stage", "meshprep"}};
    bundle.inputs = {{"mesh", prepared.report["input"]["hash"]}};
    bundle.convention = conventionRecord();
    prepared.bundle = std::move(bundle);
    return prepared;
}

} // namespace prt
