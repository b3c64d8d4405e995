// libFuzzer harness: adaptive bundles (`prt adapt`: ragged float, half, u16/u8 per-band codes with per-vertex or
// per-cluster scales, clustered PCA) through their layer readers. The input is a whole GLB; when its JSON parses,
// the harness recomputes the PRT_bundle checksum (fuzz_glb.h), reads the bundle and its adaptive layers
// (relightModel, which calls adaptiveRelightModel), then runs what `prt relight` runs: relight() of every row under
// a fixed lighting, relightBytes, and decodedTransfer. Oracle besides the sanitizers: for float and half rows,
// relight() must give the bits of the plain kernel on each row's decoded coefficients; for u8 / u16 codes (the
// fused kernel) it must agree with it within (gamma_{n+2} + gamma_{n+1})(1 + gamma_1) sum_j |decoded_j L_j|, and
// for blocked u8 codes (relit against the lighting quantised to steps s_c = max |L_c| / 32767) within 0.51 s_c
// sum_j |x_j| (1 + gamma_{b+3}) + (gamma_{b+4} + gamma_{n+1})(1 + gamma_1) sum_j |decoded_j L_j| (b bands; |x_j| <=
// |decoded_j| (1 + gamma_1), and gamma_{b+4} - gamma_{b+3} > u covers the decoded rows' own rounding), times the
// albedo and its rounding (prt/relight.h).
// Seeds: tests/fuzz/corpus/adaptive/ (a small sphere adapted as float, half, u16, u8 per-vertex and per-cluster,
// and CPCA).
#include "bundle.h"
#include "fuzz_glb.h"
#include "fuzz_util.h"
#include "runtime.h"

#include <algorithm>
#include <cmath>
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
            const bool coded = model.storage == prt::TransferStorage::Uint8 || model.storage == prt::TransferStorage::Uint16;
            const bool quantisedLighting = model.rowsBlocked && model.storage == prt::TransferStorage::Uint8;
            const double u = std::ldexp(1.0, -24), bands = std::round(std::sqrt(double(count)));
            auto gamma = [&](double n) { return n * u / (1 - n * u); };
            for (int c = 0; c < 3; ++c) {
                const double a = model.albedo.empty() ? 1.0 : std::fabs(double(model.albedo[size_t(v) * 3 + c]));
                double magnitude = 0, sumDecoded = 0, step = 0;
                for (uint32_t j = 0; j < count; ++j) {
                    const double x = std::fabs(double(rows[(size_t(model.offsets[v]) + j) * 3 + c]));
                    magnitude += x * std::fabs(lighting[j * 3 + c]);
                    sumDecoded += x;
                }
                for (size_t j = 0; j < coefficients; ++j)
                    step = std::max(step, std::fabs(double(lighting[j * 3 + c])) / 32767);
                const double bound =
                    quantisedLighting
                        ? 0.51 * step * sumDecoded * (1 + gamma(1)) * (1 + gamma(bands + 3)) +
                              (gamma(bands + 4) + gamma(count + 1.0)) * (1 + gamma(1)) * magnitude
                        : (gamma(count + 2.0) + gamma(count + 1.0)) * (1 + gamma(1)) * magnitude;
                const double raw = expected[c];
                if (!model.albedo.empty()) expected[c] *= model.albedo[size_t(v) * 3 + c];
                if (!coded) {
                    if (std::memcmp(&expected[c], &got[c], sizeof(float)) != 0) std::abort();
                } else if (!(std::fabs(double(got[c]) - expected[c]) <= a * bound + u * a * (2 * std::fabs(raw) + bound))) {
                    std::abort();
                }
            }
        }
    });
    return 0;
}
