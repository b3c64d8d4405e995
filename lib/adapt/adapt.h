// Model no more than a scene needs: per-vertex adaptive SH order chosen offline from a transfer's band energies
// under a lighting prior, graded across the mesh so no seam shows, stored ragged, optionally quantised per band
// (8 or 16 bit) or compressed by clustered PCA (Sloan et al. 2003). docs/adapt.md has the decisions and figures;
// docs/bundle.md the layers. The runtime half (reading and relighting these layers) is in lib/runtime.
//
// Transfer arrays are [V][L*L][3] (coefficient j = l*l + l + m, RGB), lighting [L*L][3] SH radiance
// coefficients, as docs/conventions.md defines them. "Order" n means n bands, n*n coefficients.
#pragma once

#include "bundle.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt::adapt {

// ---- order selection ----------------------------------------------------------------------------------------
// What lighting the error is measured under.
//   Maps:  the given lightings as they are (the error each vertex has under each of them, exactly).
//   Worst: any rotation of the given lightings: per band, |T_l . L_l| <= |T_l| |L_l| (Cauchy-Schwarz), and band
//          norms do not change under rotation, so the absolute tail bound holds for every orientation of every
//          given map. The relative error divides it by the given orientation's RMS radiance s; a rotated map
//          whose own RMS is s' has a relative error of at most (the bound) * s / s', not the bound itself.
enum class Prior { Maps, Worst };

// Per-vertex truncation error for each order n = 1..order: error[v * order + (n - 1)] is the largest, over the
// lightings and the three channels, of |radiance at full order - radiance at order n| divided by that lighting's
// RMS full-order radiance over all vertices and channels (so a bound E on it bounds the relative RMSE by E).
// Needs transfer [vertexCount][order*order][3], each lighting [order*order][3] with a non-zero full-order
// radiance somewhere, 1 <= order <= sh::kMaxOrder. error[.. + order - 1] is 0.
std::vector<float> truncationError(const float* transfer, size_t vertexCount, int order,
                                   const std::vector<std::vector<float>>& lightings, Prior prior);

// The smallest order per vertex whose error (from truncationError) is <= maxError; maxError <= 0 gives `order`
// everywhere (lossless: relighting equals the full order bit for bit).
std::vector<uint8_t> selectOrders(const std::vector<float>& error, size_t vertexCount, int order, double maxError);

// Per map k, vertex v and order n = 1..order: the squared truncation error of vertex v at order n, summed over the
// three channels and divided by 3 V s_k^2 (s_k the map's RMS full-order radiance), so that summing over vertices
// gives the squared relative RMSE of the whole relight under map k. [maps][V][order]; Worst uses the bound.
std::vector<double> truncationErrorSquared(const float* transfer, size_t vertexCount, int order,
                                           const std::vector<std::vector<float>>& lightings, Prior prior);

// The fewest coefficients overall whose relight keeps the relative RMSE under every map within maxRmse: each
// vertex takes the order minimising (its summed weighted squared error) + lambda * n^2, with lambda the largest
// (found by bisection on log lambda) that keeps every map's total within maxRmse^2. maxRmse <= 0 gives `order`.
std::vector<uint8_t> budgetOrders(const std::vector<double>& errorSquared, size_t mapCount, size_t vertexCount,
                                  int order, double maxRmse);

// Grades the orders so that the ends of every mesh edge differ by at most `maxStep` bands, only ever raising an
// order (so every vertex stays within its error bound). Needs indices < orders.size(). Deterministic.
// Returns the number of vertices raised.
size_t smoothOrders(const std::vector<uint32_t>& indices, std::vector<uint8_t>& orders, int maxStep = 1);

// smoothOrders that keeps the per-vertex bound: under Prior::Maps the truncation error is not monotone in the
// order (bands can cancel), so a vertex raised by grading can leave its bound. Grades, raises every vertex whose
// error (truncationError's table, `order` values per vertex) exceeds maxError to its next order within it, and
// repeats until both hold. Needs orders within the bound (selectOrders') and indices < orders.size(). Guarantees:
// every edge differs by at most maxStep, every vertex's error <= maxError, and the result is the smallest such
// field above the input (no vertex higher than the bound and the grading together need). Deterministic. Returns
// the number of vertices raised.
size_t smoothOrdersWithinBound(const std::vector<uint32_t>& indices, std::vector<uint8_t>& orders,
                               const std::vector<float>& error, int order, double maxError, int maxStep = 1);

// Ragged storage: vertex v's coefficients are rows offsets[v] .. offsets[v+1] - 1 of values ([rows][3]), the
// first orders[v]^2 coefficients of its transfer.
struct RaggedTransfer {
    int order = 0;                 // the largest order any vertex may have
    std::vector<uint32_t> offsets; // [V + 1], ascending, offsets[0] = 0, in coefficients
    std::vector<float> values;     // [offsets[V]][3]
};
RaggedTransfer raggedTransfer(const float* transfer, size_t vertexCount, int order,
                              const std::vector<uint8_t>& orders);

// Order of vertex v in a ragged transfer: sqrt(offsets[v+1] - offsets[v]).
int vertexOrder(const RaggedTransfer& ragged, size_t v);

// The ragged transfer as [V][order*order][3] with zeros beyond each vertex's order; `values` replaces
// ragged.values when given (decoded quantised values of the same layout).
std::vector<float> denseTransfer(const RaggedTransfer& ragged, const std::vector<float>* values = nullptr);

// The largest, over the lightings, relative RMSE of the radiance of `approx` against that of `full` (both
// [V][order*order][3]): sqrt(mean (a - f)^2) / sqrt(mean f^2) over vertices and channels.
double priorRelativeRmse(const float* approx, const float* full, size_t vertexCount, int order,
                         const std::vector<std::vector<float>>& lightings);

// The seam measure: over mesh edges whose ends have different orders, the largest change that truncation adds to
// the radiance jump across the edge, |(a_u - a_v) - (f_u - f_v)| with a adaptive and f full-order radiance; and,
// for scale, the largest and the mean full-order jump |f_u - f_v| over the other edges. Radiance [V][3].
struct SeamMeasure {
    size_t boundaryEdges = 0, otherEdges = 0;
    double largestBoundaryExcess = 0.0; // the largest jump truncation adds across an order boundary
    double meanBoundaryExcess = 0.0;
    double largestOtherJump = 0.0;      // the largest full-order jump across edges elsewhere
    double meanOtherJump = 0.0;
};
SeamMeasure seamMeasure(const std::vector<uint32_t>& indices, const std::vector<uint8_t>& orders,
                        const float* adaptiveRadiance, const float* fullRadiance);

// ---- per-band quantisation ----------------------------------------------------------------------------------
// Codes q in [0, 2c] with c = 2^(bits-1) - 1 decode as (q - c) * scale / c, scale the largest |value| of the band
// (over its 2l+1 coefficients and 3 channels) rounded up to a float16, so zero is exact and every value is within
// scale / (2c) of what it encodes.
// Per vertex: vertex v's band l uses scales[bandOffset(v) + l] with bandOffset(v) = sum of orders of vertices < v.
// Per cluster: vertex v's band l uses scales[cluster[v] * order + l].
struct QuantisedTransfer {
    int bits = 8;                  // 8 or 16
    std::vector<uint32_t> codes;   // one per ragged value
    std::vector<float> scales;     // float16-representable
    std::vector<uint32_t> cluster; // per vertex; empty for per-vertex scales
    int clusterCount = 0;
};
QuantisedTransfer quantise(const RaggedTransfer& ragged, int bits, const std::vector<uint32_t>& cluster,
                           int clusterCount);
// The values the codes stand for, [offsets[V]][3].
std::vector<float> dequantise(const RaggedTransfer& layout, const QuantisedTransfer& quantised);

// ---- clustered PCA (Sloan, Hall, Hart, Snyder 2003) ---------------------------------------------------------
// Deterministic k-means (Lloyd, `iterations` rounds, seeded with rows i*V/K) of the rows of data [rows][dim];
// returns each row's cluster in 0..clusterCount-1. Needs 1 <= clusterCount <= rows.
std::vector<uint32_t> kMeans(const float* data, size_t rows, size_t dim, int clusterCount, int iterations);

// Each cluster: its mean and its first `components` principal directions (Eigen's self-adjoint eigensolver on the
// cluster's covariance), and each row's weights: row ~ mean[k] + sum_i weight[i] * basis[k][i].
// With components = dim the reconstruction is exact up to rounding.
struct Cpca {
    int clusterCount = 0, components = 0;
    size_t dim = 0;
    std::vector<uint32_t> cluster; // [rows]
    std::vector<float> basis;      // [clusterCount][components + 1][dim]: the mean first, then the directions
    std::vector<float> weights;    // [rows][components]
};
Cpca clusteredPca(const float* data, size_t rows, size_t dim, int clusterCount, int components, int iterations = 12);
std::vector<float> reconstruct(const Cpca& cpca); // [rows][dim]

// ---- bundles ------------------------------------------------------------------------------------------------
enum class Format { Float, Half, U16, U8, Cpca };
Format parseFormat(const std::string& name); // throws prt::Error(kExitUsage) for an unknown name
const char* formatName(Format format);

struct AdaptOptions {
    double maxError = 0.0; // the bound (budget below); must be > 0 from the CLI
    bool perVertexBudget = false; // true: every vertex within maxError (truncationError); false: the relight's
                                  // relative RMSE under every prior map within maxError (budgetOrders)
    int order = 0;         // > 0: every vertex truncated to this order (no adaptivity; maxError unused)
    Prior prior = Prior::Maps;
    Format format = Format::Float;
    bool perClusterScales = false; // u8/u16: one scale per cluster and band instead of per vertex and band
    int clusters = 64;             // u8/u16 per-cluster scales, and CPCA
    int components = 8;            // CPCA
    int maxStep = 1;               // smoothing: largest order difference along an edge
    std::vector<std::string> lightingNames; // recorded in params
};

struct AdaptStats {
    size_t vertexCount = 0;
    int fullOrder = 0;
    double meanOrder = 0.0, meanCoefficients = 0.0;
    size_t raisedBySmoothing = 0;
    double relativeRmse = 0.0;     // priorRelativeRmse of what the bundle stores against the input (full order)
    int components = 0;            // CPCA: the components used
    uint64_t layerBytes = 0;       // bytes of the transfer layers written (what a relight reads, before decoding)
    uint64_t fullLayerBytes = 0;   // the input's float32 transfer layer
    std::vector<int> orderHistogram; // [fullOrder + 1]
    std::vector<SeamMeasure> seams;  // ragged formats, per lighting: the stored transfer against the input's
};

// The texel grid as triangles over texel indices (two per 2 x 2 block), so that smoothOrders and seamMeasure grade
// and measure texel neighbours as they do mesh edges.
std::vector<uint32_t> gridTriangles(int width, int height);

// Replaces the bundle's "transfer" layer (vertex, sh_transfer_rgb) by the adaptive layers of docs/bundle.md
// ("Adaptive transfer"); or a bake's "texel_transfer" (its rows held in the layer's data, params width and height)
// by the same layers of domains texel, texel_offsets, texel_ragged and texel_bands, graded over the texel grid. `lightings` is the prior ([L*L][3] each, L the transfer's order); it may be empty only
// with options.order (and, for CPCA, options.components) given. Errors in the stats are against the input. Throws prt::Error
// naming `source` for a bundle without a usable transfer layer. Returns what it did.
AdaptStats adaptBundle(Bundle& bundle, const std::vector<std::vector<float>>& lightings, const AdaptOptions& options,
                       const std::string& source);

} // namespace prt::adapt
