// libFuzzer harness: adaptive bundles (`prt adapt`: ragged float, half, u16/u8 per-band codes with per-vertex or
// per-cluster scales, clustered PCA) through their layer readers. The input is a whole GLB; when its JSON parses,
// the harness recomputes the PRT_bundle checksum (fuzz_glb.h), reads the bundle and its adaptive layers
// (relightModel, which calls adaptiveRelightModel), then runs what `prt relight` runs: relight() of every row under
// a fixed lighting, relightBytes, and decodedTransfer. Oracle besides the sanitizers: for every storage but CPCA,
// relight() must give the bits of the plain kernel on each row's decoded coefficients (prt/relight.h).
// Seeds: tests/fuzz/corpus/adaptive/ (a small sphere adapted as float, half, u16, u8 per-vertex and per-cluster,
// and CPCA).
#include "bundle.h"
#include "fuzz_glb.h"
#include "fuzz_util.h"
#include "runtime.h"

#include <cstring>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    prt::fuzz::capElements();
    std::string file = prt::fuzz::withChecksum(data, size);
    std::string path = prt::fuzz::writeInput(reinterpret_cast<const uint8_t*>(file.data()), file.size(), "glb");
    prt::fuzz::expectOnlyErrors([&] {
        prt::Bundle bundle = prt::readBundle(path);
        if (!prt::hasAdaptiveTransfer(bundle)) return;
        prt::RelightModel model = prt::relightModel(std::move(bundle), path);
        const size_t coefficients = size_t(model.order) * model.order;
        std::vector<float> lighting(coefficients * 3);
        for (size_t i = 0; i < lighting.size(); ++i) lighting[i] = 1.0f / float(1 + i % 5);
        std::vector<float> radiance(size_t(model.vertexCount) * 3);
        prt::relight(model, lighting.data(), 0, model.vertexCount, radiance.data());
        (void)prt::relightBytes(model);
        std::vector<float> rows = prt::decodedTransfer(model);
        if (model.storage == prt::TransferStorage::Cpca || model.offsets.empty()) return;
        if (rows.size() != size_t(model.offsets.back()) * 3) std::abort();
        for (uint32_t v = 0; v < model.vertexCount; ++v) {
            const uint32_t count = model.offsets[v + 1] - model.offsets[v];
            float expected[3];
            prt::relight(rows.data() + size_t(model.offsets[v]) * 3, 1, int(count), lighting.data(), expected);
            float got[3] = {radiance[v * 3], radiance[v * 3 + 1], radiance[v * 3 + 2]};
            if (!model.albedo.empty())
                for (int c = 0; c < 3; ++c) expected[c] *= model.albedo[size_t(v) * 3 + c];
            if (std::memcmp(expected, got, sizeof got) != 0) std::abort();
        }
    });
    return 0;
}
