// prt/adaptive.h: adaptive transfer (bundles from `prt adapt`; docs/bundle.md "Adaptive transfer", docs/adapt.md):
// ragged per-vertex orders, u8/u16/half codes and clustered PCA, kept encoded in memory and relit from there.
#pragma once

#include "relight.h"
#include "sh.h"

#include <cstddef>
#include <string>

namespace prt {

// The highest order this runtime evaluates; a bundle asking for more bands is refused with an error saying so.
inline constexpr int kMaxRuntimeOrder = sh::kMaxOrder;

// The adaptive transfer of a bundle as a RelightModel, kept as stored so relight() reads the compressed bytes: the
// ragged layer "transfer_ragged" (float32 into transfer, float16 into halves, uint8/uint16 codes into codes8 /
// codes16 with their band scales as sigma = scale / C; codes with per-vertex scales, and halves where the processor
// has F16C, put in the vertex-blocked layout by blockRows) with its offsets, or the clustered-PCA layers
// "transfer_cpca_*" (storage Cpca; decodedTransfer reconstructs the rows to full order). Needs the layers and params docs/bundle.md lists, offsets
// ascending from 0 whose every difference is n^2 with 1 <= n <= params.order <= kMaxRuntimeOrder, codes and
// cluster indices in range, finite values. Throws prt::Error naming `source`, the layer and the problem
// otherwise (for a vertex asking for more bands than the runtime has, naming the vertex and both orders).
RelightModel adaptiveRelightModel(Bundle& bundle, const std::string& source);

// True when the bundle holds adaptive transfer layers (and so relightModel reads them).
bool hasAdaptiveTransfer(const Bundle& bundle);

// Relights vertices [begin, end) of an adaptive model (model.offsets not empty) on the calling thread, with the bits
// relight(model, ...) gives them: each vertex with its own bands, the lighting's first n_v^2 coefficients. Float
// and half rows go in runs of equal order through the same kernel as full-order rows, so a model whose every vertex
// has the full order relights bit for bit like the full-order model; blocked codes (blockRows) through the blocked
// kernel. Every storage but Cpca (whose rows have no offsets). Throws prt::Error for a range outside the model, for
// a model without offsets or of storage Cpca, and for one relight() refuses.
void relightAdaptive(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance);


} // namespace prt
