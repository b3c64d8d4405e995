// Relighting straight from encoded transfer (u8 / u16 codes, halves, clustered PCA), the job-system hook and the
// no-throw API. Oracles: the float kernel on the decoded rows, exact sums in double, and closed-form float rounding
// bounds (gamma_n = n u / (1 - n u), u = 2^-24; Higham, "Accuracy and Stability of Numerical Algorithms", 3.1).
#include "core.h"
#include "prt/nothrow.h"
#include "prt/runtime.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <thread>
#include <tuple>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace prt;

namespace {

double roundingGamma(double n) {
    const double u = std::ldexp(1.0, -24);
    return n * u / (1.0 - n * u);
}

std::vector<float> randomLighting(int order, uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> uniform(-2.0f, 2.0f);
    std::vector<float> lighting(size_t(order) * order * 3);
    for (float& value : lighting) value = uniform(random);
    return lighting;
}

// A bundle of V vertices (positions only; relightModel needs the count) and no layers.
Bundle vertexBundle(size_t V) {
    Bundle bundle;
    bundle.mesh.positions.assign(V * 3, 0.0f);
    bundle.mesh.indices = {0, 1, 2};
    return bundle;
}

Layer layer(const std::string& name, const std::string& domain, const std::string& semantic,
            std::vector<uint64_t> shape, const std::string& type) {
    Layer out;
    out.name = name;
    out.domain = domain;
    out.semantic = semantic;
    out.shape = std::move(shape);
    out.componentType = type;
    return out;
}

// Ragged orders 1..order (vertex v has 1 + (v * 7) % order bands) as `prt adapt` stores them, quantised to `bits`
// with per-vertex or per-cluster half scales. `original` receives the float rows the codes stand for.
struct Quantised {
    Bundle bundle;
    std::vector<float> original;          // [offsets[V]][3]
    std::vector<double> scaleOfValue;     // s of each value's band, [offsets[V] * 3]
    std::vector<uint32_t> offsets;
};

Quantised quantisedBundle(size_t V, int order, int bits, bool perCluster, uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    const uint32_t C = (1u << (bits - 1)) - 1, K = 3;
    Quantised q;
    q.bundle = vertexBundle(V);
    q.offsets.push_back(0);
    std::vector<int> bands(V);
    for (size_t v = 0; v < V; ++v) {
        bands[v] = 1 + int((v * 7) % order);
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

std::vector<float> relightAll(const RelightModel& model, const float* lighting, const JobSystem& jobs = {}) {
    std::vector<float> radiance(size_t(model.vertexCount) * 3);
    relight(model, lighting, 0, model.vertexCount, radiance.data(), jobs);
    return radiance;
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// The fused code kernel sums q'_j * fl(sigma_l L_j) (q' = q - C exact), so each channel is within gamma_{n+2}
// sum_j |x_j L_j| of the exact sum over x_j = q'_j sigma_l; the float kernel on the decoded rows (fl(q' sigma_l))
// within gamma_{n+1} of it; and |x_j| <= |decoded_j| (1 + gamma_1). Counts the channels of vertices [begin, end)
// (row 0 of `radiance` and `viaDecode` is vertex begin) where the two differ by more.
size_t outsideCodeKernelBound(const float* radiance, const float* viaDecode, const std::vector<float>& decoded,
                              const std::vector<uint32_t>& offsets, const std::vector<float>& lighting, size_t begin,
                              size_t end) {
    size_t failures = 0;
    for (size_t v = begin; v < end; ++v) {
        const size_t n = offsets[v + 1] - offsets[v];
        for (int c = 0; c < 3; ++c) {
            double magnitude = 0;
            for (size_t j = 0; j < n; ++j)
                magnitude += std::fabs(double(decoded[(offsets[v] + j) * 3 + c])) * std::fabs(lighting[j * 3 + c]);
            const double bound =
                (roundingGamma(double(n + 2)) + roundingGamma(double(n + 1))) * (1 + roundingGamma(1)) * magnitude;
            const size_t i = (v - begin) * 3 + c;
            if (std::fabs(double(radiance[i]) - viaDecode[i]) > bound) ++failures;
        }
    }
    return failures;
}

} // namespace

TEST(EncodedRelight, CodesRelightLikeTheirDecodeAndWithinTheQuantisationBound) {
    const int order = 5;
    const size_t V = 9001; // more than two relight blocks, so band scales cross block starts
    for (int bits : {8, 16})
        for (bool perCluster : {false, true}) {
            SCOPED_TRACE(std::to_string(bits) + " bits, " + (perCluster ? "per-cluster" : "per-vertex") + " scales");
            Quantised q = quantisedBundle(V, order, bits, perCluster, 17 + bits + perCluster);
            RelightModel model = relightModel(q.bundle, "q.glb");
            ASSERT_EQ(model.storage, bits == 8 ? TransferStorage::Uint8 : TransferStorage::Uint16);
            ASSERT_TRUE(model.transfer.empty()) << "codes stay codes";
            EXPECT_EQ(relightBytes(model) < q.original.size() * sizeof(float) * (bits == 8 ? 0.5 : 0.75), true);
            std::vector<float> lighting = randomLighting(order, 3);
            std::vector<float> radiance = relightAll(model, lighting.data());

            // 1. Within rounding of the float kernel on the decoded rows (codeKernelBound).
            std::vector<float> decoded = decodedTransfer(model);
            ASSERT_EQ(decoded.size(), q.original.size());
            std::vector<float> viaDecode(V * 3), viaOriginal(V * 3);
            for (size_t v = 0; v < V; ++v) {
                const int count = int(q.offsets[v + 1] - q.offsets[v]);
                relight(decoded.data() + size_t(q.offsets[v]) * 3, 1, count, lighting.data(), &viaDecode[v * 3]);
                relight(q.original.data() + size_t(q.offsets[v]) * 3, 1, count, lighting.data(), &viaOriginal[v * 3]);
            }
            EXPECT_EQ(outsideCodeKernelBound(radiance.data(), viaDecode.data(), decoded, q.offsets, lighting, 0, V), 0u);

            // 2. Within the analytic bound of the float relight of the values the codes stand for: per value
            // |t - x| <= s / 2C (x = (q - C) s / C, exact; the test's rounding in double adds at most 2^-50
            // relatively), |decoded - x| <= gamma_2 |x| (s / C and the product rounded), and each float dot product
            // of n terms within gamma_n sum |a_j b_j| of its exact value.
            const double C = (1u << (bits - 1)) - 1;
            size_t failures = 0;
            for (size_t v = 0; v < V; ++v) {
                const size_t n = q.offsets[v + 1] - q.offsets[v];
                for (int c = 0; c < 3; ++c) {
                    double dotDecoded = 0, dotOriginal = 0, quantisation = 0;
                    for (size_t j = 0; j < n; ++j) {
                        const size_t i = (q.offsets[v] + j) * 3 + c;
                        const double L = std::fabs(lighting[j * 3 + c]), s = q.scaleOfValue[i];
                        const double x = std::round(double(q.original[i]) * C / s) * s / C;
                        dotDecoded += std::fabs(decoded[i]) * L;
                        dotOriginal += std::fabs(q.original[i]) * L;
                        quantisation += L * (s / (2 * C) * (1 + std::ldexp(1.0, -50)) + roundingGamma(2) * std::fabs(x));
                    }
                    const double bound = roundingGamma(double(n)) * (dotDecoded + dotOriginal) + quantisation;
                    if (std::fabs(double(radiance[v * 3 + c]) - viaOriginal[v * 3 + c]) > bound) ++failures;
                }
            }
            EXPECT_EQ(failures, 0u);
        }
}

TEST(EncodedRelight, HalfRowsRelightBitForBitLikeTheirFloats) {
    Quantised shape = quantisedBundle(5000, 4, 8, false, 5); // only its offsets
    Bundle bundle = vertexBundle(5000);
    std::mt19937 random(9);
    Layer data = layer("transfer_ragged", "vertex_ragged", "sh_transfer_rgb", {shape.offsets.back(), 3}, "float16");
    for (size_t i = 0; i < size_t(shape.offsets.back()) * 3; ++i) // every half pattern but infinities and NaNs
        data.data.push_back(halfToFloat(uint16_t(random() % 0x10000u & 0xfbffu)));
    data.data[0] = halfToFloat(0x0001); // the smallest subnormal
    data.data[1] = halfToFloat(0x83ff); // a negative subnormal
    data.params = {{"order", 4}, {"offsets", "transfer_offsets"}, {"format", "half"}};
    bundle.layers = {data, shape.bundle.layers[1]};
    RelightModel model = relightModel(bundle, "h.glb");
    ASSERT_EQ(model.storage, TransferStorage::Float16);
    EXPECT_TRUE(sameBits(decodedTransfer(model), data.data)) << "halves widen exactly";
    RelightModel floats = model;
    floats.storage = TransferStorage::Float32;
    floats.transfer = data.data;
    floats.halves.clear();
    std::vector<float> lighting = randomLighting(4, 2);
    EXPECT_TRUE(sameBits(relightAll(model, lighting.data()), relightAll(floats, lighting.data())));
}

namespace {

Bundle cpcaBundle(size_t V, int order, uint64_t K, uint64_t M, uint32_t seed) {
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

} // namespace

TEST(EncodedRelight, CpcaRelightsInItsBasisWithinRoundingOfItsReconstruction) {
    const int order = 5;
    const size_t V = 5000, K = 4, M = 6;
    Bundle bundle = cpcaBundle(V, order, K, M, 21);
    RelightModel model = relightModel(bundle, "cpca.glb");
    ASSERT_EQ(model.storage, TransferStorage::Cpca);
    EXPECT_LT(relightBytes(model), V * order * order * 3 * sizeof(float) / 2);
    std::vector<float> lighting = randomLighting(order, 4);
    std::vector<float> radiance = relightAll(model, lighting.data());
    std::vector<float> decoded = decodedTransfer(model), viaDecode(V * 3);
    relight(decoded.data(), V, order * order, lighting.data(), viaDecode.data());
    // Both agree with the exact sum_j L_j (mean_j + sum_i w_i b_ij) within gamma_{n + M + 1} S, S = sum_j |L_j|
    // (|mean_j| + sum_i |w_i b_ij|), n = L^2: the projections are n-term dot products, the weighted sum M + 1
    // terms, and the reconstruction M + 1 terms then an n-term dot product. So they differ by at most twice that.
    const std::vector<float>& b = bundle.layers[0].data;
    const std::vector<float>& w = bundle.layers[1].data;
    const std::vector<uint32_t>& k = bundle.layers[2].integers;
    const size_t n = size_t(order) * order, dim = n * 3;
    size_t failures = 0;
    for (size_t v = 0; v < V; ++v)
        for (int c = 0; c < 3; ++c) {
            double S = 0;
            for (size_t j = 0; j < n; ++j) {
                const float* block = b.data() + k[v] * (M + 1) * dim;
                double row = std::fabs(block[j * 3 + c]);
                for (size_t i = 0; i < M; ++i) row += std::fabs(w[v * M + i] * block[(i + 1) * dim + j * 3 + c]);
                S += std::fabs(lighting[j * 3 + c]) * row;
            }
            if (std::fabs(double(radiance[v * 3 + c]) - viaDecode[v * 3 + c]) > 2 * roundingGamma(double(n + M + 1)) * S) ++failures;
        }
    EXPECT_EQ(failures, 0u);
    // And bit for bit the documented order (runtime_internal.h, relightCpcaRange): each basis row projected by the
    // float kernel, then per channel an even sum, the mean's projection + w_0 p_0 + w_2 p_2 + ..., and an odd one,
    // 0 + w_1 p_1 + w_3 p_3 + ... (+ 0 * 0 after an odd M's last even term), in float, then even + odd: scalar sums
    // here (the runtime sums in vector lanes), for the whole buffer and a range ending at its end. M = 6 and 5 take
    // the kernel for any M; a second basis of 16 directions, cut to 16, 8, 4 and 15, the kernels for M = 16, 8, 4
    // and an odd M again.
    const Bundle wide = cpcaBundle(V, order, K, 16, 22);
    for (auto [source, full, used] : {std::tuple<const Bundle*, size_t, size_t>{&bundle, M, M}, {&bundle, M, M - 1},
                                      {&wide, 16, 16}, {&wide, 16, 8}, {&wide, 16, 4}, {&wide, 16, 15}}) {
        SCOPED_TRACE(std::to_string(used) + " of " + std::to_string(full) + " components");
        const std::vector<float>& basis = source->layers[0].data;
        const std::vector<float>& weights = source->layers[1].data;
        const std::vector<uint32_t>& clusters = source->layers[2].integers;
        RelightModel cut = relightModel(*source, "cpca.glb");
        cut.cpcaComponents = int(used); // the same basis with its last full - used directions dropped
        cut.cpcaBasis.clear();
        for (size_t cluster = 0; cluster < K; ++cluster)
            cut.cpcaBasis.insert(cut.cpcaBasis.end(), basis.begin() + std::ptrdiff_t(cluster * (full + 1) * dim),
                                 basis.begin() + std::ptrdiff_t((cluster * (full + 1) + used + 1) * dim));
        cut.cpcaWeights.clear();
        for (size_t v = 0; v < V; ++v)
            cut.cpcaWeights.insert(cut.cpcaWeights.end(), weights.begin() + std::ptrdiff_t(v * full),
                                   weights.begin() + std::ptrdiff_t(v * full + used));
        std::vector<float> projections(K * (used + 1) * 3);
        relight(cut.cpcaBasis.data(), K * (used + 1), int(n), lighting.data(), projections.data());
        std::vector<float> expected(V * 3);
        for (size_t v = 0; v < V; ++v)
            for (int c = 0; c < 3; ++c) {
                const float* p = projections.data() + clusters[v] * (used + 1) * 3;
                const float* x = cut.cpcaWeights.data() + v * used;
                float even = p[c], odd = 0.0f;
                size_t i = 0;
                for (; i + 1 < used; i += 2) {
                    even += x[i] * p[(i + 1) * 3 + c];
                    odd += x[i + 1] * p[(i + 2) * 3 + c];
                }
                if (i < used) even += x[i] * p[(i + 1) * 3 + c], odd += 0.0f * 0.0f;
                expected[v * 3 + c] = even + odd;
            }
        EXPECT_TRUE(sameBits(relightAll(cut, lighting.data()), expected));
        std::vector<float> tail(7 * 3);
        relight(cut, lighting.data(), V - 7, V, tail.data());
        EXPECT_EQ(std::memcmp(tail.data(), expected.data() + (V - 7) * 3, tail.size() * sizeof(float)), 0);
    }
}

namespace {

// A job system that runs the tasks backwards, spread over three std::threads: as unlike the serial order as it gets.
void scrambledParallelFor(void* context, size_t count, TaskFunction task, void* data) {
    ++*static_cast<size_t*>(context);
    std::vector<std::thread> threads;
    for (size_t t = 0; t < 3; ++t)
        threads.emplace_back([=] {
            for (size_t i = count; i-- > 0;)
                if (i % 3 == t) task(data, i);
        });
    for (std::thread& thread : threads) thread.join();
}

} // namespace

TEST(EncodedRelight, JobHookGivesTheSerialResultBitForBit) {
    size_t calls = 0;
    JobSystem jobs{scrambledParallelFor, &calls};
    std::vector<float> lighting = randomLighting(5, 8);
    RelightModel floats;
    floats.vertexCount = 20000;
    floats.order = 5;
    floats.transfer.resize(size_t(20000) * 75);
    std::mt19937 random(1);
    for (float& value : floats.transfer) value = std::uniform_real_distribution<float>(-1, 1)(random);
    floats.albedo.assign(size_t(20000) * 3, 0.75f);
    std::vector<RelightModel> models;
    models.push_back(floats);
    models.push_back(relightModel(quantisedBundle(20000, 5, 8, false, 3).bundle, "q"));
    models.push_back(relightModel(cpcaBundle(20000, 5, 3, 4, 2), "c"));
    for (const RelightModel& model : models) {
        // A range that starts and ends inside blocks.
        const size_t begin = 1234, end = 19000;
        std::vector<float> serial((end - begin) * 3), hooked((end - begin) * 3);
        relight(model, lighting.data(), begin, end, serial.data());
        relight(model, lighting.data(), begin, end, hooked.data(), jobs);
        EXPECT_TRUE(sameBits(serial, hooked)) << int(model.storage);
        // And each part of it is the same rows of the whole.
        std::vector<float> whole = relightAll(model, lighting.data());
        EXPECT_EQ(std::memcmp(serial.data(), whole.data() + begin * 3, serial.size() * sizeof(float)), 0);
    }
    EXPECT_EQ(calls, models.size());
}

// Uniform orders 1..8 built directly, so the fused half kernel (relight_vector.cpp, where the processor has F16C)
// runs long runs that end at the array's last row, whose odd-order tail load it leaves to the decode tile. Halves of
// every finite pattern, a third of them +-0, against lighting with exact zeros, so products of -0 reach every lane:
// the relit radiance is the float kernel's on the decoded rows bit for bit, for the whole buffer, ranges that start
// and end inside blocks or end at the buffer's end, single vertices, and through the job hook.
TEST(EncodedRelight, HalfRowsOfEveryOrderRelightBitForBitLikeTheFloatKernel) {
    const size_t V = 4099; // a block and 3 vertices
    size_t calls = 0;
    JobSystem jobs{scrambledParallelFor, &calls};
    for (int n = 1; n <= 8; ++n) {
        SCOPED_TRACE(std::to_string(n) + " bands");
        std::mt19937 random(uint32_t(n * 13));
        RelightModel model;
        model.vertexCount = uint32_t(V);
        model.order = n;
        model.storage = TransferStorage::Float16;
        for (size_t v = 0; v <= V; ++v) model.offsets.push_back(uint32_t(v * n * n));
        model.halves.resize(V * n * n * 3);
        for (uint16_t& half : model.halves) {
            const uint32_t r = random();
            half = r % 3 == 0 ? uint16_t(r & 0x8000u) : uint16_t(r >> 8 & 0xfbffu); // +-0, else finite
        }
        model.halves[1] = 0x0001, model.halves[2] = 0x83ff, model.halves.back() = 0x7bff; // subnormals, the largest
        std::vector<float> lighting = randomLighting(n, uint32_t(n + 40));
        for (size_t i = 0; i < lighting.size(); i += 5) lighting[i] = i % 2 ? -0.0f : 0.0f;
        RelightModel floats = model;
        floats.storage = TransferStorage::Float32;
        floats.transfer = decodedTransfer(model);
        floats.halves.clear();
        const std::vector<float> whole = relightAll(model, lighting.data()), expected = relightAll(floats, lighting.data());
        EXPECT_TRUE(sameBits(whole, expected)) << "the whole buffer";
        size_t negativeZeros = 0;
        for (float r : whole) negativeZeros += r == 0 && std::signbit(r);
        EXPECT_EQ(negativeZeros, 0u) << "the float kernel's lanes start at +0";
        for (auto [begin, end] : {std::pair<size_t, size_t>{1237, 4090}, {1, V}, {V - 1, V}, {4095, 4097}}) {
            std::vector<float> range((end - begin) * 3), hooked((end - begin) * 3);
            relight(model, lighting.data(), begin, end, range.data());
            EXPECT_EQ(std::memcmp(range.data(), expected.data() + begin * 3, range.size() * sizeof(float)), 0)
                << "range [" << begin << ", " << end << ")";
            relight(model, lighting.data(), begin, end, hooked.data(), jobs);
            EXPECT_TRUE(sameBits(range, hooked)) << "job hook, range [" << begin << ", " << end << ")";
        }
    }
    EXPECT_EQ(calls, 8u * 4);
}

TEST(EncodedRelight, CodesAtEveryOrderOddCountsAndMidBufferRangesWithinBoundOfTheirDecode) {
    const size_t V = 8195; // odd, two whole relight blocks and a tail
    const size_t begin = 1237, end = 8190; // starts and ends inside blocks
    size_t calls = 0;
    JobSystem jobs{scrambledParallelFor, &calls};
    for (int order = 1; order <= 8; ++order)
        for (int bits : {8, 16})
            for (bool perCluster : {false, true}) {
                SCOPED_TRACE("order " + std::to_string(order) + ", " + std::to_string(bits) + " bits" +
                             (perCluster ? ", per-cluster" : ""));
                Quantised q = quantisedBundle(V, order, bits, perCluster, uint32_t(order * 31 + bits + perCluster));
                RelightModel model = relightModel(q.bundle, "q.glb");
                std::vector<float> lighting = randomLighting(order, uint32_t(order));
                std::vector<float> decoded = decodedTransfer(model), viaDecode((end - begin) * 3);
                for (size_t v = begin; v < end; ++v)
                    relight(decoded.data() + size_t(q.offsets[v]) * 3, 1, int(q.offsets[v + 1] - q.offsets[v]),
                            lighting.data(), &viaDecode[(v - begin) * 3]);
                std::vector<float> range((end - begin) * 3), hooked((end - begin) * 3);
                relight(model, lighting.data(), begin, end, range.data());
                EXPECT_EQ(outsideCodeKernelBound(range.data(), viaDecode.data(), decoded, q.offsets, lighting, begin, end), 0u);
                relight(model, lighting.data(), begin, end, hooked.data(), jobs);
                EXPECT_TRUE(sameBits(range, hooked)) << "job hook";
                std::vector<float> whole = relightAll(model, lighting.data());
                EXPECT_EQ(std::memcmp(range.data(), whole.data() + begin * 3, range.size() * sizeof(float)), 0)
                    << "a range is the same rows of the whole";
                // A one-vertex range at an odd place.
                float one[3];
                relight(model, lighting.data(), 4097, 4098, one);
                EXPECT_EQ(std::memcmp(one, whole.data() + 4097 * 3, sizeof one), 0);
            }
}

// Uniform orders 1..8 built directly, so the fused kernel runs long runs of vertices and a run ends at the codes'
// last row (read through its zero-padded copy), then with per-vertex scales the same codes vertex-blocked (blockCodes:
// 4099 vertices end in a padded block; ranges and the job hook), under lighting spanning many magnitudes (bands falling 16x each,
// one (band, channel) all zero, one at 1e-30). Each channel is within gamma_{n+2} sum_j |x_j L_j| of the exact
// E = sum_j x_j L_j, x_j = (q_j - C) sigma_l (in double: q - C and sigma are exact there; the products and their
// sum of at most 64 terms per channel stay within 2^-45 sum |x L| of it, which the check allows); blocked u8 codes
// within the bound of their quantised lighting (prt/relight.h, relight), which fails with a pair's two lighting
// values swapped or the codes centred on 128.
TEST(EncodedRelight, FusedCodesOfLongRunsWithinRoundingOfTheExactSum) {
    const size_t V = 4099; // a block and 3 vertices
    for (int n = 1; n <= 8; ++n)
        for (int bits : {8, 16})
            for (bool perCluster : {false, true}) {
                SCOPED_TRACE(std::to_string(n) + " bands, " + std::to_string(bits) + " bits" + (perCluster ? ", per-cluster" : ""));
                std::mt19937 random(uint32_t(n * 7 + bits + perCluster));
                const uint32_t C = bits == 8 ? 127 : 32767;
                RelightModel model;
                model.vertexCount = uint32_t(V);
                model.order = n;
                model.storage = bits == 8 ? TransferStorage::Uint8 : TransferStorage::Uint16;
                const size_t values = size_t(n) * n * 3;
                for (size_t v = 0; v <= V; ++v) model.offsets.push_back(uint32_t(v * n * n));
                std::vector<uint32_t> codes(V * values);
                for (uint32_t& q : codes) q = random() % (2 * C + 1);
                codes[7] = 0, codes[8] = 2 * C, codes.back() = 2 * C; // the extreme codes, one in the last row
                if (bits == 8) model.codes8.assign(codes.begin(), codes.end());
                else model.codes16.assign(codes.begin(), codes.end());
                const size_t scaleRows = perCluster ? 5 : V;
                for (size_t i = 0; i < scaleRows * n; ++i)
                    model.bandScales.push_back(std::ldexp(1.0f + float(random() % 1000) / 1000.0f, int(random() % 9) - 12));
                if (perCluster)
                    for (size_t v = 0; v < V; ++v) model.scaleCluster.push_back(uint32_t(random() % 5));
                for (size_t v = 0; v <= V; v += kRelightBlock) model.bandBlockStarts.push_back(uint32_t(v * n));
                std::vector<float> lighting = randomLighting(n, uint32_t(n));
                for (int k = 0; k < n * n; ++k)
                    for (int c = 0; c < 3; ++c) {
                        const int l = int(std::sqrt(double(k)));
                        lighting[k * 3 + c] *= std::ldexp(1.0f, -4 * l);
                        if (l == 2 && c == 1) lighting[k * 3 + c] = 0;
                        if (l == 3 && c == 2) lighting[k * 3 + c] *= 1e-30f;
                    }
                const std::vector<float> sigmas = model.bandScales;
                // The row kernel, then (per-vertex scales) the same codes vertex-blocked, each against the exact sum.
                for (bool blocked : {false, true}) {
                    if (blocked) {
                        const std::vector<float> rows = decodedTransfer(model);
                        ASSERT_EQ(blockCodes(model), !perCluster);
                        if (perCluster) continue;
                        ASSERT_TRUE(model.codesBlocked);
                        EXPECT_TRUE(sameBits(decodedTransfer(model), rows)) << "the blocked rows decode as the rows did";
                    }
                    SCOPED_TRACE(blocked ? "blocked" : "rows");
                    std::vector<float> radiance = relightAll(model, lighting.data());
                    // Blocked u8 codes go through the lighting quantised per channel to steps of s_c = max |L_c| /
                    // 32767 (relightBlockedU8Kernel): that adds 0.51 s_c sum |x_j|, and its rounding is
                    // gamma_{n + 3} sum |x_j| (|L_j| + 0.51 s_c).
                    const bool quantised = blocked && bits == 8;
                    double step[3] = {};
                    for (int k = 0; k < n * n; ++k)
                        for (int c = 0; c < 3; ++c)
                            step[c] = std::max(step[c], std::fabs(double(lighting[k * 3 + c])) / 32767);
                    size_t failures = 0, exact = 0;
                    for (size_t v = 0; v < V; ++v) {
                        const float* sigma = sigmas.data() + (perCluster ? model.scaleCluster[v] * n : v * n);
                        for (int c = 0; c < 3; ++c) {
                            double E = 0, magnitude = 0, sumX = 0;
                            for (int k = 0; k < n * n; ++k) {
                                const double x = (double(codes[v * values + k * 3 + c]) - C) *
                                                 double(sigma[int(std::sqrt(double(k)))]);
                                E += x * double(lighting[k * 3 + c]);
                                magnitude += std::fabs(x * double(lighting[k * 3 + c]));
                                sumX += std::fabs(x);
                            }
                            const double error = std::fabs(double(radiance[v * 3 + c]) - E);
                            const double rounding = std::ldexp(1.0, -45) * magnitude;
                            const double quantisation = 0.51 * step[c] * sumX;
                            const double bound =
                                quantised ? quantisation + roundingGamma(double(n + 3)) * (magnitude + quantisation) +
                                                rounding
                                          : roundingGamma(double(n * n + 2)) * magnitude + rounding;
                            if (error > bound) ++failures;
                            if (error == 0) ++exact;
                        }
                    }
                    EXPECT_EQ(failures, 0u);
                    EXPECT_LT(exact, V * 3) << "float rounding shows: the check is not vacuous";
                    if (!blocked) continue;
                    // Ranges that start and end inside blocks, one inside a single block, and the scrambled job
                    // hook: each vertex's bits as in the whole call.
                    for (auto [begin, end] : {std::pair<size_t, size_t>{1237, 4090}, {3, 6}, {4093, V}, {0, 1}}) {
                        std::vector<float> part((end - begin) * 3);
                        relight(model, lighting.data(), begin, end, part.data());
                        EXPECT_TRUE(sameBits(part, std::vector<float>(radiance.begin() + std::ptrdiff_t(begin * 3),
                                                                      radiance.begin() + std::ptrdiff_t(end * 3))))
                            << begin << ".." << end;
                    }
                    size_t calls = 0;
                    EXPECT_TRUE(sameBits(relightAll(model, lighting.data(), JobSystem{scrambledParallelFor, &calls}),
                                         radiance));
                    EXPECT_EQ(calls, 1u);
                    // Lighting that is not finite in one channel (NaN, or infinity) is not quantised into finite
                    // garbage: that channel is not finite, the others are as before.
                    for (float bad :
                         {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
                        std::vector<float> broken = lighting;
                        broken[(n * n - 1) * 3 + 1] = bad;
                        std::vector<float> out = relightAll(model, broken.data());
                        size_t finiteGreen = 0, changedOthers = 0;
                        for (size_t v = 0; v < V; ++v) {
                            finiteGreen += std::isfinite(out[v * 3 + 1]) ? 1 : 0;
                            changedOthers += std::memcmp(&out[v * 3], &radiance[v * 3], 4) != 0 ||
                                             std::memcmp(&out[v * 3 + 2], &radiance[v * 3 + 2], 4) != 0;
                        }
                        EXPECT_EQ(finiteGreen, 0u) << bad;
                        EXPECT_EQ(changedOthers, 0u) << bad;
                    }
                }
            }
}

TEST(NoThrow, StatusForMissingCorruptAndGoodFilesAndBadRanges) {
    fs::path dir = fs::temp_directory_path() / ("prt_nothrow_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    Bundle bundle = vertexBundle(3);
    bundle.mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    Layer transfer = layer("transfer", "vertex", "sh_transfer_rgb", {3, 1, 3}, "float32");
    transfer.data = {1, 1, 1, 2, 2, 2, 3, 3, 3};
    transfer.params = {{"order", 1}};
    bundle.layers.push_back(transfer);
    const std::string good = (dir / "good.glb").string(), bad = (dir / "bad.glb").string();
    writeBundle(good, bundle);

    Expected<RelightModel> missing = tryLoadRelightModel((dir / "absent.glb").string());
    EXPECT_EQ(missing.status().code, StatusCode::NotFound);
    EXPECT_NE(missing.status().message.find("absent.glb"), std::string::npos);

    // The same file with one byte of its binary chunk flipped: the checksum refuses it.
    std::string bytes;
    {
        std::ifstream in(good, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    bytes[bytes.size() - 5] ^= 0x40;
    std::ofstream(bad, std::ios::binary) << bytes;
    Expected<RelightModel> corrupt = tryLoadRelightModel(bad);
    EXPECT_EQ(corrupt.status().code, StatusCode::Corrupt) << corrupt.status().message;
    EXPECT_NE(corrupt.status().message.find("bad.glb"), std::string::npos);
    std::ofstream(bad, std::ios::binary) << bytes.substr(0, bytes.size() / 2); // truncated
    EXPECT_EQ(tryLoadRelightModel(bad).status().code, StatusCode::Corrupt);

    Expected<RelightModel> loaded = tryLoadRelightModel(good);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message;
    const float lighting[3] = {1, 2, 3};
    float radiance[9];
    EXPECT_TRUE(tryRelight(loaded.value(), lighting, 0, 3, radiance).ok());
    EXPECT_EQ(radiance[8], 9.0f);
    EXPECT_EQ(tryRelight(loaded.value(), lighting, 2, 4, radiance).code, StatusCode::InvalidInput);
    EXPECT_EQ(tryRelight(loaded.value(), nullptr, 0, 3, radiance).code, StatusCode::InvalidInput);
    int order = 0;
    EXPECT_EQ(tryReadLightingJson(good, &order).status().code, StatusCode::Corrupt);
    EXPECT_STREQ(statusName(StatusCode::Corrupt), "corrupt");
    fs::remove_all(dir);
}

// Crash classes of untrusted adaptive bundles (issue 20, layer type confusion): band scales or cluster indices of
// the other storage kind passed the shape check, and relight then read the empty storage (SIGSEGV). Every adaptive
// layer's component type is checked with its shape: each swap is refused (exit 3) naming the layer.
TEST(EncodedRelight, LayersOfTheWrongStorageKindAreRefusedNamingTheLayer) {
    auto refused = [](Bundle bundle, const std::string& layerName) {
        try {
            relightModel(std::move(bundle), "q.glb");
            ADD_FAILURE() << "accepted " << layerName << " of the wrong type";
        } catch (const Error& e) {
            EXPECT_EQ(e.exitCode(), kExitInput);
            EXPECT_NE(std::string(e.what()).find(layerName), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("expected"), std::string::npos) << e.what();
        }
    };
    auto swapStorage = [](Layer& l, const std::string& type) {
        if (type.rfind("uint", 0) == 0) {
            for (float v : l.data) l.integers.push_back(uint32_t(std::max(0.0f, v)));
            l.data.clear();
        } else {
            for (uint32_t v : l.integers) l.data.push_back(float(v));
            l.integers.clear();
        }
        l.componentType = type;
    };
    for (bool perCluster : {false, true}) {
        Quantised q = quantisedBundle(300, 4, 8, perCluster, 5);
        ASSERT_NO_THROW(relightModel(q.bundle, "q.glb"));
        for (Layer& l : q.bundle.layers) {
            Bundle bad = q.bundle;
            Layer& target = *std::find_if(bad.layers.begin(), bad.layers.end(), [&](const Layer& x) { return x.name == l.name; });
            swapStorage(target, target.componentType.rfind("uint", 0) == 0 ? "float32" : "uint32");
            refused(bad, l.name);
        }
    }
    Bundle cpca = cpcaBundle(200, 3, 2, 2, 9);
    ASSERT_NO_THROW(relightModel(cpca, "c.glb"));
    for (const Layer& l : cpca.layers) {
        Bundle bad = cpca;
        Layer& target = *std::find_if(bad.layers.begin(), bad.layers.end(), [&](const Layer& x) { return x.name == l.name; });
        swapStorage(target, target.componentType.rfind("uint", 0) == 0 ? "float32" : "uint32");
        refused(bad, l.name);
    }
}
