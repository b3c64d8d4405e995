// Mesh preparation: load a triangle mesh from OBJ, PLY, OFF, STL, glTF or GLB, validate it, weld it, give it
// normals, optionally decimate it, and measure its boundary. `prt meshprep` is runMeshprep().
//
// Free functions over prt::TriMesh (bundle.h). Each states what it needs and what it guarantees; the stage calls
// them in this order: loadMesh, validateMesh, weldVertices, removeDegenerateFaces + removeUnusedVertices (for
// what welding collapsed), decimate, computeNormals, analyzeTopology.
//
// Vertex order is part of the contract, because every later stage writes per-vertex arrays in it: each function
// that changes the vertex set returns `sourceVertex`, the input vertex each output vertex comes from, and keeps
// output vertices in increasing order of that index. Composed, they give the report's `source_vertex`, which maps
// every vertex of the prepared mesh back to a vertex of the input file.
#pragma once

#include "bundle.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {

// ---- loading ---------------------------------------------------------------------------------------------------

// What loadMesh learned about the file besides the mesh.
struct MeshFileInfo {
    std::string format;                 // "obj", "ply", "off", "stl", "gltf" or "glb"
    std::string hash;                   // content hash of the file (core.h hashBytes)
    size_t fileVertices = 0;            // vertices as the file lists them
    size_t filePolygons = 0;            // faces as the file lists them
    size_t polygonsTriangulated = 0;    // faces with more than three corners, fan-triangulated
    size_t degenerateFacesDropped = 0;  // faces with fewer than three distinct corners, which make no triangle
    std::vector<uint32_t> sourceVertex; // for each mesh vertex, the file vertex it comes from (see loadMesh)
};

// Reads a mesh file, chosen by extension. OBJ, PLY (ascii and binary), OFF (ascii) and STL (ascii and binary) go
// through OpenMesh's readers; glTF and GLB through readBundle (its layers are dropped).
// OpenMesh's readers return success on broken input: they skip OBJ lines they cannot parse (shifting every later
// index), repeat the last face of a truncated OFF or ascii PLY, read OFF comments as data, and loop forever on a
// PLY header they cannot tokenize. So each file is first checked against its own format (declared counts against
// the data present, every number parsed, text being text); OpenMesh then reads the checked bytes (OFF without
// comments, PLY with its header rewritten in the plain form its parser needs), and its result is checked against
// the declared counts.
// Needs: nothing; the file may be anything.
// Guarantees: the mesh as the file states it, not yet validated: indices may be out of range and coordinates
// non-finite (validateMesh decides). Polygons are fanned from their first corner. Attributes: normals, texcoords
// (v flipped to glTF's v-down) and vertex colours (8-bit colours decoded from sRGB, float colours taken as linear)
// become albedo, each kept only when every vertex a triangle uses has it. An OBJ corner whose texcoord or normal
// differs from an earlier corner at the same `v` gets a copy of that vertex, appended after the file's vertices;
// `info->sourceVertex` names the file vertex of every mesh vertex. OpenMesh's STL reader shares vertices at
// exactly equal positions, so STL's fileVertices counts distinct positions.
// Throws Error naming `path` and the place (line, element, byte offset) for a missing or unreadable file, an
// unknown extension, malformed or truncated content, non-finite numbers in a text format, and an empty mesh.
TriMesh loadMesh(const std::string& path, MeshFileInfo* info = nullptr);

// ---- validation and cleanup ------------------------------------------------------------------------------------

struct FaceCleanup {
    size_t degenerateFaces = 0; // removed: a repeated index, or zero area
    size_t duplicateFaces = 0;  // removed: the same three vertices as an earlier triangle
};

// Checks a mesh against the TriMesh invariants and removes triangles that carry no area.
// Needs: any TriMesh; `source` names it in errors.
// Guarantees: on return every index is in range, every float finite, normals (if any) unit length, at least one
// triangle left, and removeDegenerateFaces has run. Authored normals with a zero-length entry are dropped (with a
// warning) so that they get computed.
// Throws Error(source, "vertex V", ...) for a non-finite position, normal, texcoord or albedo; Error(source,
// "triangle T", ...) for an index out of range, naming the index; Error(source, "", "empty mesh") when there are
// no vertices or no triangles; Error(source, "", "all N triangles are degenerate"); Error for per-vertex arrays of
// the wrong size.
FaceCleanup validateMesh(TriMesh& mesh, const std::string& source);

// Removes degenerate triangles and duplicates, keeping the order of the others.
// Degenerate: two equal indices, or zero area to float precision, |e1 x e2| <= FLT_EPSILON * (longest edge)^2.
// Duplicate: the same three vertices as an earlier triangle in either winding (a back-to-back pair would shadow
// itself at distance zero); the first survives.
// Needs: indices in range. Guarantees: vertices untouched (some may become unused: see removeUnusedVertices).
FaceCleanup removeDegenerateFaces(TriMesh& mesh);

// Drops vertices no triangle uses. Needs: indices in range.
// Guarantees: the survivors keep their order; returns sourceVertex (output vertex -> input vertex).
std::vector<uint32_t> removeUnusedVertices(TriMesh& mesh);

// ---- welding ---------------------------------------------------------------------------------------------------

// Merges vertices closer than `tolerance` (Euclidean, in the mesh's units; 0 merges equal positions only).
// The rule is greedy in input order: vertex i joins the lowest-index earlier representative within tolerance, or
// becomes a representative itself; there is no chaining, so a group spans at most `tolerance` from its
// representative. A grid of cells of size `tolerance` finds candidates; taking the lowest index among them makes
// the result independent of hashing order.
// With `compareAttributes`, vertices also need bitwise-equal normals, texcoords and albedo to merge, so texture
// seams and hard edges stay; without, a group takes its representative's attributes.
// Needs: a valid mesh (validateMesh). Guarantees: triangles keep their order and winding; unused vertices are
// dropped; output vertices are the representatives in increasing input index, and the function returns
// sourceVertex (output vertex -> its representative's input index). Triangles may become degenerate or duplicate.
std::vector<uint32_t> weldVertices(TriMesh& mesh, float tolerance, bool compareAttributes);

// ---- normals ---------------------------------------------------------------------------------------------------

// Angle-weighted vertex normals (Thürmer and Wüthrich 1998): each triangle adds its unit normal times its
// interior angle at the corner, so the result does not depend on how a surface is triangulated.
// Needs: a valid mesh without degenerate triangles or unused vertices. Guarantees: mesh.normals holds one unit,
// finite normal per vertex; a vertex whose weighted sum vanishes (opposite faces cancelling) takes its first
// triangle's normal.
void computeNormals(TriMesh& mesh);

// ---- decimation ------------------------------------------------------------------------------------------------

// Reduces the mesh to `targetTriangles` by halfedge collapses in OpenMesh's Decimater, ordered by quadric error
// (ModQuadricT), refusing collapses that turn a face normal by more than 60 degrees (ModNormalFlippingT) or leave
// a triangle with an aspect ratio above 5 that was not already worse (ModAspectRatioT).
// OpenMesh's legality checks keep boundaries: a boundary vertex never collapses into an interior one. Texture
// seams are boundaries of the welded mesh, so they survive too. Edges used by more than two triangles cannot be
// represented in OpenMesh's halfedge mesh: the triangles that do not fit get their own copies of the vertices.
// Needs: a valid mesh without degenerate triangles; targetTriangles >= 1.
// Guarantees: at most targetTriangles triangles (targetTriangles - 1 when the last collapse removes two), unless
// no legal collapse remains; vertices are never moved, so the survivors keep their positions and attributes and
// stay in increasing input order; returns sourceVertex (output vertex -> input vertex; a copy names its original).
// Deterministic for the same input.
std::vector<uint32_t> decimate(TriMesh& mesh, size_t targetTriangles);

// ---- measurements ----------------------------------------------------------------------------------------------

struct Bounds {
    std::array<float, 3> min{};
    std::array<float, 3> max{};
    double diagonal = 0.0;
};

// Axis-aligned bounds of the vertices that triangles use. Needs: indices in range.
Bounds computeBounds(const TriMesh& mesh);

struct MeshTopology {
    size_t boundaryEdges = 0;    // edges used by exactly one triangle
    size_t boundaryLoops = 0;    // connected components of the boundary edges: holes and outer rims
    size_t nonManifoldEdges = 0; // edges used by three or more triangles
};

// Edge statistics of the surface. Vertices at equal positions count as one, so texture seams and hard edges are
// not boundaries. Needs: indices in range.
MeshTopology analyzeTopology(const TriMesh& mesh);

// ---- the stage -------------------------------------------------------------------------------------------------

struct MeshprepOptions {
    std::string input;
    std::string output;          // .glb
    std::string report;          // JSON report; empty: none
    double weldTolerance = 1e-6; // relative to the bounding box diagonal
    bool weldIgnoreAttributes = false;
    bool recomputeNormals = false; // otherwise authored normals are kept when the file has them
    size_t decimateTo = 0;         // target triangle count; 0: no decimation
    double scale = 1.0;            // uniform scale applied to positions before anything else
    std::string toolVersion;       // recorded as the bundle's producer version
    bool flatten = false;          // a glTF scene: merge it into one mesh (the steps above) instead of keeping it
};

struct PreparedMesh {
    TriMesh mesh;
    nlohmann::json report; // see prepareMesh
};

// Runs the whole preparation in memory: load, scale, validate, weld, clean what welding collapsed, decimate,
// normals, topology. Writes nothing.
// Needs: options.input; weldTolerance >= 0; scale finite and > 0.
// Guarantees: a valid mesh and the report {"input":{path,hash,format}, "counts":{vertices_in, faces_in,
// vertices_out, faces_out}, "bounds":{min,max,diagonal}, "boundary":{edges,loops}, "non_manifold_edges",
// "fixed":{...}, "weld":{...}, "decimation":{...} or null, "vertex_order", "source_vertex":[...]}, where
// source_vertex[k] is the file vertex of output vertex k.
// Throws Error naming the input file for any bad input (see loadMesh and validateMesh).
PreparedMesh prepareMesh(const MeshprepOptions& options);

// Scenes. A glTF or GLB input is kept as the asset it is (a version 3 scene bundle, asset.h), unless
// options.flatten: every receiver is validated (indices inside its own vertices, finite values, colours in
// [0, 1]), primitives without NORMAL (or vertices whose NORMAL is a zero vector) get angle-weighted normals in a
// new NORMAL accessor (computeNormals, own space), and nothing is welded or reordered: rows stay the asset's.
struct PreparedScene {
    Bundle bundle;         // the scene, no layers
    nlohmann::json report; // input, scene counts, counts, bounds, boundary, vertex_order
};
// Whether `path` is an OBJ that names an MTL file (mtllib) that exists: meshprep then reads it as a scene
// (readObjScene). An MTL it names but that is missing is logged as a warning (false: the geometry is read without
// materials, as other importers do); one outside the OBJ's folder is refused (Error).
bool objHasMaterials(const std::string& path);
// An OBJ with its MTL as a scene bundle (no layers): one mesh, one primitive per material (its distinct corners as
// vertices, texcoords flipped to glTF's v down), Kd as base colour factor, map_Kd as base colour texture, not
// metallic. The OBJ is checked as loadMesh checks it first; the MTL and the textures must lie inside the OBJ's
// folder (backslashes read as separators). Throws Error naming the file and the place otherwise.
Bundle readObjScene(const std::string& path);

// Needs `scene`, options.input read by readBundle, to be a scene (scene.asset). Throws Error(kExitUsage) for the
// options that reshape a mesh (--decimate-to, --scale, --recompute-normals, --weld-ignore-attributes), naming
// --flatten; Error(input, place) for bad input, textures that do not decode included.
PreparedScene prepareScene(const MeshprepOptions& options, Bundle scene);

// The `prt meshprep` stage: prepareMesh (or prepareScene), then writes the bundle and the report (if asked) so that any error
// leaves neither file behind, logs a summary and reports its cost.
// Needs: options.output ending in .glb. Throws Error (kExitUsage for bad options).
void runMeshprep(const MeshprepOptions& options);

} // namespace prt
