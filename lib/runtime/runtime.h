// The thin runtime: relights a bundle's precomputed transfer under new distant lighting, per vertex or per texel.
// It needs no ray tracer or solver, only the bundle reader and SH; an engine links prt::runtime (see
// tests/runtime/consumer for a complete find_package(prt) project).
//
// Outgoing radiance of vertex v in channel c is radiance[v][c] = sum_j transfer[v][j][c] * lighting[j][c]
// (docs/conventions.md), with lighting as RGB SH radiance coefficients [coefficient][3].
#pragma once

#include "bundle.h"
#include "core.h" // prt::Error, thrown by the loaders
#include "image.h"
#include "sh.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {

// Per-vertex transfer ready to relight: the "transfer" layer of a bundle (semantic "sh_transfer_rgb").
struct RelightModel {
    uint32_t vertexCount = 0;
    int order = 0;               // SH bands; order * order coefficients per vertex
    std::vector<float> transfer; // [vertexCount][order * order][3], the mesh's vertex order
    // Adaptive models (`prt adapt`, below): when not empty, vertex v has its own order n_v <= order and its
    // n_v^2 coefficients are rows offsets[v] .. offsets[v+1] - 1 of transfer ([offsets[vertexCount]][3]).
    std::vector<uint32_t> offsets;
};

// Takes the "transfer" layer out of `bundle` (pass it with std::move to avoid copying), or, in a bundle without
// one, the adaptive layers `prt adapt` writes (adaptiveRelightModel, below). `source` names the bundle in errors.
// Needs a vertex-domain layer of semantic "sh_transfer_rgb", shape [V, L*L, 3] with L = params.order when that
// is set, V equal to the mesh's vertex count, finite values. Throws prt::Error naming `source` otherwise.
RelightModel relightModel(Bundle bundle, const std::string& source);

// Reads a bundle file and takes its transfer layer, as relightModel does.
RelightModel loadRelightModel(const std::string& bundlePath);

// ---- per-texel transfer (bundles from `prt bake`) -------------------------------------------------------------
// Per-texel transfer ready to relight: the "texel_transfer" layer of a bundle and the coefficient texture it
// references. Rows are texels, row-major with row 0 at the top of the atlas (docs/bundle.md, "Texel layers"), so
// the per-vertex kernel relights them unchanged.
struct TexelRelightModel {
    int width = 0, height = 0;
    RelightModel rows; // rows.vertexCount = width * height texels
};

// Reads the bundle's "texel_transfer" layer and its texture: params.uri, relative to the bundle file (symlinks
// resolved), is an OpenEXR with channels T000.R, T000.G, ... (params.format "half" or "float") or the JSON
// sidecar of 8-bit PNG layers (format "u8": value = min + q * (max - min) / 255 per coefficient layer).
// Needs: domain "texel", semantic "sh_transfer_rgb", shape [W*H, L*L, 3] with params width W and height H (and
// params.order = L when set), texture files whose xxh128 equals the recorded hash and of W x H texels, finite
// values. Throws prt::Error naming the bundle or the texture file, the place and the problem otherwise.
TexelRelightModel loadTexelRelightModel(const std::string& bundlePath);

// Channel name of coefficient j, colour c (0..2) in coefficient textures: "T000.R", "T012.B".
std::string texelCoefficientChannel(int coefficient, int colour);

// ---- lighting ------------------------------------------------------------------------------------------------
// Lighting of `coefficientCount` RGB coefficients from lighting of another count: their common prefix, with
// missing coefficients set to zero. Both counts are squares, so this is projecting both onto their common bands.
std::vector<float> fitLighting(const float* lighting, int lightingCoefficientCount, int coefficientCount);

// Reads prt-sh JSON as `prt envsh` writes it ({"format":"prt-sh","order":L,"coefficients":[[r,g,b],...]}).
// Returns [L*L][3] and sets *order to L. Throws prt::Error naming the file and the bad member.
std::vector<float> readLightingJson(const std::string& path, int* order);

// Lighting for `order` bands from an environment map: projected with exact texel solid angles, then rotated so
// the environment turns by `rotation` (row-major 3x3, d' = R d; null for none), then windowed against ringing.
std::vector<float> environmentLighting(const EnvironmentMap& env, int order, const double* rotation,
                                       sh::Window window);

// Rotates RGB lighting of `order` bands so the environment it describes turns by `rotation` (d' = R d).
std::vector<float> rotateLighting(const float* lighting, int order, const double rotation[9]);

// ---- relighting ----------------------------------------------------------------------------------------------
// The real-time kernel: radiance[v][c] = sum_j transfer[v][j][c] * lighting[j][c] for v < vertexCount.
// transfer is [vertexCount][coefficientCount][3], lighting [coefficientCount][3], radiance [vertexCount][3].
// Single-threaded and allocation-free; sums in float in a fixed order, so results do not depend on how callers
// split the vertices. To stream a range [begin, end), pass transfer + begin * coefficientCount * 3 and
// end - begin vertices.
void relight(const float* transfer, size_t vertexCount, int coefficientCount, const float* lighting,
             float* radiance);

// Relights vertices [begin, end) of `model` across TBB's threads, bit-identical to the kernel on that range.
// Needs lighting of model.order * model.order RGB coefficients (see fitLighting), end <= model.vertexCount and
// radiance sized (end - begin) * 3: row 0 of radiance is vertex `begin`. Throws prt::Error for a range outside
// the model.
void relight(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance);

// ---- FIV shadows of moving occluders (bundles from `prt fiv`; docs/fiv.md) ----------------------------------
// Irradiance at receiver points (position, unit normal; any mesh, deforming or not) under a distant environment
// with rigid occluders that translate: I = DifMap(N) - sum_j I_occ,j (overlap-corrected), clamped to
// 0 <= I <= DifMap(N). I_occ,j = N . FIV_j(c_j - p) from occluder j's grid (trilinear over azimuth, polar angle and
// shell, periodic in azimuth, samples inside the occluder skipped and the weights renormalised), by the seed's
// cases: A (bounding sphere wholly above the tangent plane) exact, B (straddling) corrected, C (below) ignored.
// A receiver that is its own occluder (`self`) uses I = N . FIV(Env) - N . FIV_self - sum_j I_occ,j.
// Everything here is std only and single-threaded; outgoing radiance is albedo / pi times I.

// One occluder type's grid (layers fiv, fiv_power, fiv_valid of a FIV bundle).
struct FivOccluder {
    int azimuth = 0, polar = 0, shells = 0;
    std::vector<float> shellRadii; // world units (rho_k R), ascending
    float centre[3] = {0, 0, 0};   // bounding-sphere centre in the occluder's own coordinates
    float radius = 0.0f;           // bounding-sphere radius
    std::vector<float> fiv;        // [row][channel][xyz], row (k * polar + j) * azimuth + i
    std::vector<float> power;      // [row][channel]: occluded radiance times solid angle
    std::vector<uint8_t> valid;    // [row]: 0 where the receiver would sit inside the occluder
    std::string envHash;           // the environment the grid was reduced with
};

// The unoccluded environment as the shading needs it (layers difmap and fiv_env).
struct FivLighting {
    int difmapSize = 0;
    std::vector<float> difmap; // [6 * size^2][3] irradiance by normal, cube strip order
    float fivEnv[9] = {0};     // FIV(Env) [channel][xyz]
    std::string envHash;
};

// Take the layers out of a FIV bundle. Need: layer shapes that agree with the grid header in params (rows =
// azimuth * polar * shells, shell_radii of `shells` ascending positive values, radius > 0), finite values.
// Throw prt::Error(source, layer, problem) otherwise.
FivOccluder fivOccluder(const Bundle& bundle, const std::string& source);
FivLighting fivLighting(const Bundle& bundle, const std::string& source);

enum class FivPartial {
    None,    // case B like case A: max(0, N . FIV)
    Literal, // the seed as printed: max(0, (d + R) / (2R) N . FIV)
    Cap,     // the occluded light as one uniform cap of the same power and mean direction, clipped by the tangent
             // plane (exact for a uniformly lit sphere; equals case A when the cap lies wholly above the plane)
};
enum class FivOverlap {
    None,   // sum of the occluders
    Paper,  // the seed's Eq. 13-14 pairwise: sum I_j - sum_pairs O_jk (I_j + I_k), O_jk = lens / (disc_j + disc_k),
            // discs of angular radius asin(R / |v|) around each direction; never below the largest single I_j
    Shared, // each occluder weighted by 1 / (1 + sum_k lens_jk / disc_j): coverage shared evenly, any count
    Cap,    // Paper's pairwise rule on the discs of the hidden light itself: the cap of the partial correction
            // (half-angle from |FIV| / power, around FIV's direction, green channel) instead of the bounding sphere
};
struct FivShadeOptions {
    FivPartial partial = FivPartial::Cap;
    FivOverlap overlap = FivOverlap::Cap; // the lowest measured error (docs/results.md)
};

// An occluder placed in the world: its vertex p sits at p + translation.
struct FivInstance {
    const FivOccluder* occluder = nullptr;
    float translation[3] = {0, 0, 0};
};

// Irradiance [count][3] at `count` points (positions and unit normals [count][3], world). `self` (or null) is the
// receiver's own grid, placed like an instance. Needs instances with occluders, lighting with its DifMap. Results
// do not depend on how callers split the points.
void fivIrradiance(const FivLighting& lighting, const FivInstance* instances, size_t instanceCount,
                   const FivInstance* self, const float* positions, const float* normals, size_t count,
                   const FivShadeOptions& options, float* irradiance);

// Building blocks, exposed for tests and tools.
// DifMap(n), bilinear within a face, for a unit n.
void fivDifmap(const FivLighting& lighting, const float n[3], float out[3]);
// The grid's FIV and power at offset = bounding-sphere centre - receiver point (world): trilinear, weights of
// samples inside the occluder dropped and the rest renormalised; when all eight are inside, the nearest shells
// further out are used. Beyond the outermost shell the value falls off as (rho_max / rho)^2. Returns false when no
// usable sample exists along the way out.
bool fivLookup(const FivOccluder& occluder, const float offset[3], float fiv[9], float power[3]);
// Area of the lens where discs of radii r1 and r2 with centres s apart overlap (0 when apart).
double discOverlap(double r1, double r2, double s);
// Irradiance of a uniform cap of half-angle sigma (sin^2 sigma given) at angle theta (cos given) from the normal,
// clipped by the tangent plane, per unit radiance: integral over the cap of max(0, N . w) dw.
double clippedCapIrradiance(double cosTheta, double sinSigmaSquared);

// ---- adaptive transfer (bundles from `prt adapt`; docs/bundle.md "Adaptive transfer", docs/adapt.md) ---------
// The highest order this runtime evaluates; a bundle asking for more bands is refused with an error saying so.
inline constexpr int kMaxRuntimeOrder = sh::kMaxOrder;

// The adaptive transfer of a bundle as a RelightModel: the ragged layer "transfer_ragged" (float32, float16, or
// uint8/uint16 codes with per-band scales, decoded here) with its offsets, or the clustered-PCA layers
// "transfer_cpca_*" (reconstructed here to full order). Needs the layers and params docs/bundle.md lists, offsets
// ascending from 0 whose every difference is n^2 with 1 <= n <= params.order <= kMaxRuntimeOrder, codes and
// cluster indices in range, finite values. Throws prt::Error naming `source`, the layer and the problem
// otherwise (for a vertex asking for more bands than the runtime has, naming the vertex and both orders).
RelightModel adaptiveRelightModel(Bundle& bundle, const std::string& source);

// True when the bundle holds adaptive transfer layers (and so relightModel reads them).
bool hasAdaptiveTransfer(const Bundle& bundle);

// Relights vertices [begin, end) of an adaptive model (model.offsets not empty): each vertex with its own bands,
// the lighting's first n_v^2 coefficients. Runs of equal order go through the same kernel as full-order rows, so
// a model whose every vertex has the full order relights bit for bit like the full-order model. Single-threaded.
// relight(model, ...) above calls it for adaptive models.
void relightAdaptive(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance);

} // namespace prt
