// Encoded models for the runtime tests (encoded_test.cpp, encoded_reader_test.cpp, blocked_codes_test.cpp):
// ragged quantised and clustered-PCA bundles as `prt adapt` writes them, random lighting, a scrambled job system,
// and the rounding bound gamma_n = n u / (1 - n u), u = 2^-24 (Higham, "Accuracy and Stability of Numerical
// Algorithms", 3.1).
#pragma once

#include "bundle.h"
#include "core.h"
#include "prt/runtime.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace prt_test {

using namespace prt;

inline double roundingGamma(double n) {
    const double u = std::ldexp(1.0, -24);
    return n * u / (1.0 - n * u);
}

inline std::vector<float> randomLighting(int order, uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> uniform(-2.0f, 2.0f);
    std::vector<float> lighting(size_t(order) * order * 3);
    for (float& value : lighting) value = uniform(random);
    return lighting;
}

// A bundle of V vertices (positions only; relightModel needs the count) and no layers.
inline Bundle vertexBundle(size_t V) {
    Bundle bundle;
    bundle.mesh.positions.assign(V * 3, 0.0f);
    bundle.mesh.indices = {0, 1, 2};
    return bundle;
}

inline Layer layer(const std::string& name, const std::string& domain, const std::string& semantic,
            std::vector<uint64_t> shape, const std::string& type) {
    Layer out;
    out.name = name;
    out.domain = domain;
    out.semantic = semantic;
    out.shape = std::move(shape);
    out.componentType = type;
    return out;
}

// Ragged orders 1..order (vertex v has 1 + (v / patch * 7) % order bands: with patch > 1 in runs of `patch`
// vertices, as graded orders come over a mesh) as `prt adapt` stores them, quantised to `bits`
// with per-vertex or per-cluster half scales. `original` receives the float rows the codes stand for.
struct Quantised {
    Bundle bundle;
    std::vector<float> original;          // [offsets[V]][3]
    std::vector<double> scaleOfValue;     // s of each value's band, [offsets[V] * 3]
    std::vector<double> exact;            // what each code stands for, (q - C) sigma exactly, sigma = fl(s / C)
    std::vector<uint32_t> offsets;
};

inline Quantised quantisedBundle(size_t V, int order, int bits, bool perCluster, uint32_t seed, size_t patch = 1) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    const uint32_t C = (1u << (bits - 1)) - 1, K = 3;
    Quantised q;
    q.bundle = vertexBundle(V);
    q.offsets.push_back(0);
    std::vector<int> bands(V);
    for (size_t v = 0; v < V; ++v) {
        bands[v] = 1 + int((v / patch * 7) % order);
        q.offsets.push_back(q.offsets.back() + uint32_t(bands[v] * bands[v]));
    }
    // Scales: exact halves in [0.25, 4), per (vertex, band) or per (cluster, band).
    auto halfScale = [&] { return halfToFloat(floatToHalf(std::ldexp(1.0f + 0.5f * (unit(random) + 1.0f), int(random() % 4) - 2))); };
    std::vector<float> scales;
    std::vector<uint32_t> clusterOf(V);
    if (perCluster) {
        for (uint32_t i = 0; i < K * order; ++i) scales.push_back(halfScale());
        for (size_t v = 0; v < V; ++v) clusterOf[v] = uint32_t(random() % K);
    } else {
        for (size_t v = 0; v < V; ++v)
            for (int l = 0; l < bands[v]; ++l) scales.push_back(halfScale());
    }
    Layer data = layer("transfer_ragged", "vertex_ragged", "sh_transfer_rgb_quantised", {q.offsets[V], 3},
                       bits == 8 ? "uint8" : "uint16");
    size_t band = 0;
    for (size_t v = 0; v < V; ++v) {
        for (int l = 0; l < bands[v]; ++l) {
            const double s = perCluster ? scales[clusterOf[v] * order + l] : scales[band + l];
            for (size_t i = (q.offsets[v] + size_t(l) * l) * 3; i < (q.offsets[v] + size_t(l + 1) * (l + 1)) * 3; ++i) {
                const float t = float(s) * unit(random); // |t| <= s, so the code is in 0 .. 2C
                const uint32_t code = uint32_t(std::lround(double(t) * C / s) + C);
                q.original.push_back(t);
                q.scaleOfValue.push_back(s);
                q.exact.push_back((double(code) - C) * double(float(s) / float(C)));
                data.integers.push_back(code);
            }
        }
        band += bands[v];
    }
    data.params = {{"order", order}, {"offsets", "transfer_offsets"}, {"format", bits == 8 ? "u8" : "u16"},
                   {"bits", bits}, {"scale_layer", "transfer_band_scales"}};
    Layer offsets = layer("transfer_offsets", "vertex_offsets", "sh_coefficient_offsets", {V + 1}, "uint32");
    offsets.integers = q.offsets;
    Layer scaleLayer = perCluster ? layer("transfer_band_scales", "cluster", "sh_band_scales", {K, uint64_t(order)}, "float16")
                                  : layer("transfer_band_scales", "vertex_bands", "sh_band_scales", {scales.size()}, "float16");
    scaleLayer.data = scales;
    q.bundle.layers = {data, offsets, scaleLayer};
    if (perCluster) {
        q.bundle.layers[0].params["cluster_layer"] = "transfer_scale_cluster";
        Layer cluster = layer("transfer_scale_cluster", "vertex", "cluster_index", {V}, "uint16");
        cluster.integers = clusterOf;
        q.bundle.layers.push_back(cluster);
    }
    return q;
}

inline std::vector<float> relightAll(const RelightModel& model, const float* lighting, const JobSystem& jobs = {}) {
    std::vector<float> radiance(size_t(model.vertexCount) * 3);
    relight(model, lighting, 0, model.vertexCount, radiance.data(), jobs);
    return radiance;
}

inline bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

inline Bundle cpcaBundle(size_t V, int order, uint64_t K, uint64_t M, uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    const uint64_t dim = uint64_t(order) * order * 3;
    Bundle bundle = vertexBundle(V);
    Layer basis = layer("transfer_cpca_basis", "cluster", "cpca_mean_basis", {K, M + 1, uint64_t(order) * order, 3}, "float32");
    for (uint64_t i = 0; i < K * (M + 1) * dim; ++i) basis.data.push_back(unit(random));
    basis.params = {{"order", order}, {"weights_layer", "transfer_cpca_weights"}, {"cluster_layer", "transfer_cpca_cluster"}};
    Layer weights = layer("transfer_cpca_weights", "vertex", "cpca_weights", {V, M}, "float32");
    for (uint64_t i = 0; i < V * M; ++i) weights.data.push_back(unit(random));
    Layer cluster = layer("transfer_cpca_cluster", "vertex", "cluster_index", {V}, "uint16");
    for (size_t v = 0; v < V; ++v) cluster.integers.push_back(uint32_t(random() % K));
    bundle.layers = {basis, weights, cluster};
    return bundle;
}

// A job system that runs the tasks backwards, spread over three std::threads: as unlike the serial order as it gets.
inline void scrambledParallelFor(void* context, size_t count, TaskFunction task, void* data) {
    ++*static_cast<size_t*>(context);
    std::vector<std::thread> threads;
    for (size_t t = 0; t < 3; ++t)
        threads.emplace_back([=] {
            for (size_t i = count; i-- > 0;)
                if (i % 3 == t) task(data, i);
        });
    for (std::thread& thread : threads) thread.join();
}

// The bound prt/relight.h gives relight() on codes, around the exact E = sum_j x_j L_j over the values the codes
// stand for (exact: [rows][3], x_j = (q_j - C) sigma_l, rows offsets[v] .. offsets[v + 1] - 1 for vertex v): per
// channel of a row of n coefficients and b bands, gamma_{n+2} sum_j |x_j L_j|, or, for codes relit against the
// lighting quantised per channel (`quantisedLighting`: blocked u8), 0.51 s_c sum_j |x_j| + gamma_{b+3} sum_j |x_j|
// (|L_j| + 0.51 s_c), s_c = max |L_c| / 32767 over all `lighting` (the model's order); plus 2^-45 sum_j |x_j L_j|
// for the sums here in double (at most 64 exact products per channel). Counts the channels of vertices [begin,
// end) (row 0 of `radiance` is vertex begin) outside it; `exact`, when given, receives how many equal E.
inline size_t outsideExactCodeBound(const std::vector<double>& x, const std::vector<uint32_t>& offsets,
                                    const std::vector<float>& lighting, bool quantisedLighting, const float* radiance,
                                    size_t begin, size_t end, size_t* exact = nullptr) {
    double step[3] = {};
    for (size_t k = 0; k < lighting.size(); ++k)
        step[k % 3] = std::max(step[k % 3], std::fabs(double(lighting[k])) / 32767);
    size_t failures = 0;
    if (exact) *exact = 0;
    for (size_t v = begin; v < end; ++v) {
        const size_t n = offsets[v + 1] - offsets[v];
        const double bands = std::round(std::sqrt(double(n)));
        for (size_t c = 0; c < 3; ++c) {
            double E = 0, magnitude = 0, sumX = 0;
            for (size_t j = 0; j < n; ++j) {
                const double xj = x[(offsets[v] + j) * 3 + c], L = double(lighting[j * 3 + c]);
                E += xj * L;
                magnitude += std::fabs(xj * L);
                sumX += std::fabs(xj);
            }
            const double error = std::fabs(double(radiance[(v - begin) * 3 + c]) - E);
            const double quantisation = 0.51 * step[c] * sumX, rounding = std::ldexp(1.0, -45) * magnitude;
            const double bound = quantisedLighting
                                     ? quantisation + roundingGamma(bands + 3) * (magnitude + quantisation) + rounding
                                     : roundingGamma(double(n + 2)) * magnitude + rounding;
            if (error > bound) ++failures;
            if (exact && error == 0) ++*exact;
        }
    }
    return failures;
}

} // namespace prt_test
