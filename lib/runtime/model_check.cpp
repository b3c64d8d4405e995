// What relight() and relightAdaptive() check on every call (checkRelightCall): the range, and the sizes of the
// model's arrays against its counts, storage and layout, so that a model an engine built by hand, or moved from, is
// refused instead of read past.
#include "runtime.h"

#include "runtime_internal.h"

#include <string>

namespace prt {

namespace {

[[noreturn]] void refuse(const char* place, const std::string& problem) {
    throw Error("", place, "the model's " + problem, kExitFailure);
}

void requireSize(size_t size, size_t expected, const char* place, const char* array) {
    if (size != expected)
        refuse(place, std::string(array) + " holds " + std::to_string(size) + " values where its counts and layout "
                      "say " + std::to_string(expected) + " (a model moved from, or arrays changed after loading?)");
}

// The arrays' sizes against the model's counts, storage and layout.
void checkModelArrays(const RelightModel& model, const char* place) {
    const size_t V = model.vertexCount;
    if (model.order < 1 || model.order > sh::kMaxOrder)
        refuse(place, "order " + std::to_string(model.order) + " is outside 1.." + std::to_string(sh::kMaxOrder));
    const size_t n = size_t(model.order), values = 3 * n * n;
    if (!model.albedo.empty()) requireSize(model.albedo.size(), 3 * V, place, "albedo");
    if (model.storage == TransferStorage::Cpca) {
        if (model.cpcaComponents < 0 || (V > 0 && model.cpcaClusters == 0))
            refuse(place, "clustered PCA has " + std::to_string(model.cpcaComponents) + " components and " +
                              std::to_string(model.cpcaClusters) + " clusters");
        const size_t M = size_t(model.cpcaComponents);
        requireSize(model.cpcaWeights.size(), V * M, place, "cpcaWeights");
        requireSize(model.cpcaCluster.size(), V, place, "cpcaCluster");
        requireSize(model.cpcaBasis.size(), size_t(model.cpcaClusters) * (M + 1) * values, place, "cpcaBasis");
        return;
    }
    // Rows: V * n^2, or with offsets (every storage but float32 has them) offsets[V].
    if (model.offsets.empty() && model.storage != TransferStorage::Float32)
        refuse(place, "encoded rows have no offsets");
    if (!model.offsets.empty()) requireSize(model.offsets.size(), V + 1, place, "offsets");
    const size_t rows = model.offsets.empty() ? V * n * n : size_t(model.offsets[V]);
    if (!model.offsets.empty() && (model.offsets[0] != 0 || rows > V * n * n))
        refuse(place, "offsets run from " + std::to_string(model.offsets[0]) + " to " + std::to_string(rows) +
                          ", not from 0 to at most " + std::to_string(V * n * n) + " rows");
    if (model.storage == TransferStorage::Float32) return requireSize(model.transfer.size(), 3 * rows, place, "transfer");
    const size_t stored = model.storage == TransferStorage::Float16 ? model.halves.size()
                          : model.storage == TransferStorage::Uint8 ? model.codes8.size()
                                                                    : model.codes16.size();
    const char* array = model.storage == TransferStorage::Float16 ? "halves"
                        : model.storage == TransferStorage::Uint8 ? "codes8"
                                                                  : "codes16";
    const bool coded = model.storage != TransferStorage::Float16;
    if (!model.rowsBlocked) {
        requireSize(stored, 3 * rows, place, array);
        if (coded && !model.scaleCluster.empty()) {
            requireSize(model.scaleCluster.size(), V, place, "scaleCluster");
            if (model.bandScales.size() % n != 0) refuse(place, "bandScales are not whole clusters of order bands");
        } else if (coded) { // one start per task block, and (as the loader writes it) the end after the last
            const size_t tasks = (V + kRelightBlock - 1) / kRelightBlock;
            if (model.bandBlockStarts.size() != tasks)
                requireSize(model.bandBlockStarts.size(), tasks + 1, place, "bandBlockStarts");
            if (model.bandBlockStarts.size() == tasks + 1)
                requireSize(model.bandScales.size(), model.bandBlockStarts.back(), place, "bandScales");
            else if (tasks > 0 && model.bandScales.size() < model.bandBlockStarts.back())
                refuse(place, "bandScales end before the last task block's first scale");
        }
        return;
    }
    // Vertex-blocked (blockRows): blocks of one order, or ragged groups described by blockedRuns.
    if (!model.blockedRuns.empty()) {
        requireSize(model.blockedRuns.size(), (V + kRelightBlock - 1) / kRelightBlock * 8 + 1, place, "blockedRuns");
        requireSize(model.blockedLanes.size(), size_t(model.blockedRuns.back().group) * kCodeBlock, place,
                    "blockedLanes");
    }
    const BlockedSizes blocked = blockedSizes(model, model.blockedRuns);
    requireSize(stored, blocked.values, place, array);
    if (coded) requireSize(model.bandScales.size(), blocked.scales, place, "bandScales");
}

} // namespace

void checkRelightCall(const RelightModel& model, size_t begin, size_t end, const char* place) {
    if (begin > end || end > model.vertexCount)
        throw Error("", place, "vertex range [" + std::to_string(begin) + ", " + std::to_string(end) +
                                   ") outside the model's " + std::to_string(model.vertexCount) + " vertices",
                    kExitFailure);
    checkModelArrays(model, place);
}

} // namespace prt
