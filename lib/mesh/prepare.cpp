#include "mesh.h"

#include "core.h"

#include <cmath>

namespace prt {
namespace {

constexpr const char* kVertexOrder =
    "output vertex k comes from input vertex source_vertex[k]. Vertices keep the input's order: a weld group is "
    "represented by its lowest-index vertex, and decimation keeps a subsequence. OBJ corners whose texcoord or "
    "normal differs from an earlier corner of the same vertex use copies of it, which come after the file's "
    "vertices in order of first use and name the file vertex they copy.";

// `toInput` maps the current vertices to input vertices; a step then made new vertices from current ones
// (`fromCurrent`). Afterwards `toInput` maps the new vertices to input vertices.
void chainSource(std::vector<uint32_t>& toInput, const std::vector<uint32_t>& fromCurrent) {
    std::vector<uint32_t> chained(fromCurrent.size());
    for (size_t k = 0; k < fromCurrent.size(); ++k) chained[k] = toInput[fromCurrent[k]];
    toInput = std::move(chained);
}

size_t usedVertexCount(const TriMesh& mesh) {
    std::vector<uint8_t> used(mesh.vertexCount());
    for (uint32_t v : mesh.indices) used[v] = 1;
    size_t count = 0;
    for (uint8_t u : used) count += u;
    return count;
}

} // namespace

PreparedMesh prepareMesh(const MeshprepOptions& options) {
    if (!std::isfinite(options.weldTolerance) || options.weldTolerance < 0)
        throw Error("", "--weld-tolerance", "must be a finite number >= 0", kExitUsage);
    if (!std::isfinite(options.scale) || options.scale <= 0)
        throw Error("", "--scale", "must be a finite number > 0", kExitUsage);

    MeshFileInfo file;
    TriMesh mesh = loadMesh(options.input, &file);
    const size_t verticesLoaded = mesh.vertexCount();
    const size_t trianglesLoaded = mesh.triangleCount();
    if (options.scale != 1.0)
        for (float& x : mesh.positions) x = float(x * options.scale);

    FaceCleanup cleanup = validateMesh(mesh, options.input);
    cleanup.degenerateFaces += file.degenerateFacesDropped;
    if (options.recomputeNormals) mesh.normals.clear();
    const bool normalsKept = !mesh.normals.empty();

    const size_t verticesUsed = usedVertexCount(mesh);
    const float tolerance = float(options.weldTolerance * computeBounds(mesh).diagonal);
    std::vector<uint32_t> sourceVertex = weldVertices(mesh, tolerance, !options.weldIgnoreAttributes);
    const size_t weldedVertices = verticesUsed - mesh.vertexCount();
    FaceCleanup collapsed = removeDegenerateFaces(mesh);
    if (mesh.indices.empty())
        throw Error(options.input, "", "no triangles left after welding vertices closer than " + std::to_string(tolerance));
    if (collapsed.degenerateFaces + collapsed.duplicateFaces > 0) chainSource(sourceVertex, removeUnusedVertices(mesh));
    cleanup.degenerateFaces += collapsed.degenerateFaces;
    cleanup.duplicateFaces += collapsed.duplicateFaces;

    nlohmann::json decimation = nullptr;
    if (options.decimateTo > 0) {
        size_t before = mesh.triangleCount();
        chainSource(sourceVertex, decimate(mesh, options.decimateTo));
        decimation = {
            {"target_faces", options.decimateTo},
            {"faces_before", before},
            {"faces_after", mesh.triangleCount()},
            {"method",
             "OpenMesh DecimaterT: halfedge collapses by ModQuadricT error; ModNormalFlippingT 60 degrees, ModAspectRatioT 5"}};
    }
    if (!normalsKept) computeNormals(mesh);
    const MeshTopology topology = analyzeTopology(mesh);
    const Bounds bounds = computeBounds(mesh);
    for (uint32_t& v : sourceVertex) v = file.sourceVertex[v];

    PreparedMesh prepared;
    prepared.report = {
        {"input", {{"path", options.input}, {"hash", file.hash}, {"format", file.format}}},
        {"counts",
         {{"vertices_in", file.fileVertices},
          {"faces_in", file.filePolygons},
          {"triangles_in", trianglesLoaded},
          {"vertices_out", mesh.vertexCount()},
          {"faces_out", mesh.triangleCount()}}},
        {"bounds", {{"min", bounds.min}, {"max", bounds.max}, {"diagonal", bounds.diagonal}}},
        {"boundary", {{"edges", topology.boundaryEdges}, {"loops", topology.boundaryLoops}}},
        {"non_manifold_edges", topology.nonManifoldEdges},
        {"fixed",
         {{"welded_vertices", weldedVertices},
          {"unused_vertices_removed", verticesLoaded - verticesUsed},
          {"vertices_split_at_corners", verticesLoaded - file.fileVertices},
          {"degenerate_faces_removed", cleanup.degenerateFaces},
          {"duplicate_faces_removed", cleanup.duplicateFaces},
          {"polygons_triangulated", file.polygonsTriangulated},
          {"normals", normalsKept ? "kept" : "computed"}}},
        {"weld",
         {{"tolerance", tolerance},
          {"relative_tolerance", options.weldTolerance},
          {"attributes", options.weldIgnoreAttributes ? "ignored" : "compared"}}},
        {"scale", options.scale},
        {"decimation", decimation},
        {"vertex_order", kVertexOrder},
        {"source_vertex", sourceVertex},
    };
    prepared.mesh = std::move(mesh);
    return prepared;
}

void runMeshprep(const MeshprepOptions& options) {
    if (options.input.empty() || options.output.empty())
        throw Error("", "meshprep", "needs an input mesh and -o OUT.glb", kExitUsage);
    if (fileExtension(options.output) != "glb") throw Error(options.output, "-o", "output must be a .glb file", kExitUsage);
    const double start = nowSeconds();

    Bundle bundle;
    nlohmann::json report;
    // A glTF input that is a scene (not a bundle of prt's own meshes), or an OBJ with materials, is kept as the
    // asset, unless --flatten.
    const std::string format = fileExtension(options.input);
    if (!options.flatten && (format == "gltf" || format == "glb")) bundle = readBundle(options.input);
    if (!options.flatten && objHasMaterials(options.input)) bundle = readObjScene(options.input);
    if (bundle.asset) {
        PreparedScene prepared = prepareScene(options, std::move(bundle));
        bundle = std::move(prepared.bundle);
        report = std::move(prepared.report);
    } else {
        PreparedMesh prepared = prepareMesh(options);
        report = std::move(prepared.report);
        bundle = Bundle();
        bundle.mesh = std::move(prepared.mesh);
        bundle.producer = {{"tool", "prt"}, {"version", options.toolVersion}, {"stage", "meshprep"}};
        bundle.inputs = {{"mesh", report["input"]["hash"]}};
        bundle.convention = conventionRecord();
    }
    if (options.report.empty()) {
        writeBundle(options.output, bundle);
    } else {
        // The report is renamed into place only after the bundle has been: an error in either leaves neither.
        writeFileAtomic(options.report, [&](const std::string& reportTmp) {
            writeBytesAtomic(reportTmp, report.dump(2) + "\n");
            writeBundle(options.output, bundle);
        });
    }

    const nlohmann::json& counts = report["counts"];
    if (report.contains("scene")) {
        const nlohmann::json& scene = report["scene"];
        logInfo("meshprep: " + options.input + ": scene of " + scene["receivers"].dump() + " receivers (" +
                scene["meshes"].dump() + " meshes, " + scene["instances"].dump() + " instances), " +
                scene["materials"].dump() + " materials (" + scene["textured_materials"].dump() + " textured, " +
                scene["cutout_materials"].dump() + " cut-out), " + counts["vertices_out"].dump() + " vertices, " +
                counts["faces_out"].dump() + " triangles; normals computed for " +
                scene["normals_computed_for_primitives"].dump() + " primitives; wrote " + options.output);
    } else {
        const nlohmann::json& fixed = report["fixed"];
        logInfo("meshprep: " + options.input + ": " + counts["vertices_in"].dump() + " vertices, " + counts["faces_in"].dump() +
                " faces -> " + counts["vertices_out"].dump() + " vertices, " + counts["faces_out"].dump() + " triangles; welded " +
                fixed["welded_vertices"].dump() + " vertices, removed " + fixed["degenerate_faces_removed"].dump() +
                " degenerate and " + fixed["duplicate_faces_removed"].dump() + " duplicate faces; " +
                report["boundary"]["edges"].dump() + " boundary edges in " + report["boundary"]["loops"].dump() + " loops, " +
                report["non_manifold_edges"].dump() + " non-manifold edges; normals " + fixed["normals"].get<std::string>() +
                "; wrote " + options.output);
    }

    StageCost cost;
    cost.stage = "meshprep";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace prt
