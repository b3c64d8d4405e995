// Relighting straight from encoded transfer (u8 / u16 codes, halves, clustered PCA) and the job-system hook.
// Oracles: the float kernel on the decoded rows, exact sums in double, and closed-form float rounding bounds
// (roundingGamma, encoded_fixtures.h).
#include "encoded_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <tuple>

using namespace prt_test;

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

            // 1. The rows decode to what the codes stand for, fl((q - C) sigma), and the radiance is within the
            // documented bound of the exact sum over those values (per-vertex scales: blocked at load, so u8 goes
            // through the quantised lighting).
            EXPECT_EQ(model.rowsBlocked, !perCluster);
            const bool quantisedLighting = model.rowsBlocked && bits == 8;
            std::vector<float> decoded = decodedTransfer(model);
            ASSERT_EQ(decoded.size(), q.original.size());
            size_t undecoded = 0;
            for (size_t i = 0; i < decoded.size(); ++i) undecoded += decoded[i] != float(q.exact[i]);
            EXPECT_EQ(undecoded, 0u);
            EXPECT_EQ(outsideExactCodeBound(q.exact, q.offsets, lighting, quantisedLighting, radiance.data(), 0, V), 0u);
            std::vector<float> viaOriginal(V * 3);
            for (size_t v = 0; v < V; ++v)
                relight(q.original.data() + size_t(q.offsets[v]) * 3, 1, int(q.offsets[v + 1] - q.offsets[v]),
                        lighting.data(), &viaOriginal[v * 3]);

            // 2. Within the analytic bound of the float relight of the values the codes stand for: per value
            // |t - x| <= s / 2C (x = (q - C) s / C, exact; the test's rounding in double adds at most 2^-50
            // relatively), |decoded - x| <= gamma_2 |x| (s / C and the product rounded), and each float dot product
            // of n terms within gamma_n sum |a_j b_j| of its exact value; with the quantised lighting, its
            // allowance as outsideExactCodeBound gives it (steps s_c = max |L_c| / 32767).
            const double C = (1u << (bits - 1)) - 1;
            double step[3] = {};
            for (size_t k = 0; k < lighting.size(); ++k)
                step[k % 3] = std::max(step[k % 3], std::fabs(double(lighting[k])) / 32767);
            size_t failures = 0;
            for (size_t v = 0; v < V; ++v) {
                const size_t n = q.offsets[v + 1] - q.offsets[v];
                for (int c = 0; c < 3; ++c) {
                    double dotDecoded = 0, dotOriginal = 0, quantisation = 0, sumX = 0;
                    for (size_t j = 0; j < n; ++j) {
                        const size_t i = (q.offsets[v] + j) * 3 + c;
                        const double L = std::fabs(lighting[j * 3 + c]), s = q.scaleOfValue[i];
                        const double x = std::round(double(q.original[i]) * C / s) * s / C;
                        dotDecoded += std::fabs(decoded[i]) * L;
                        dotOriginal += std::fabs(q.original[i]) * L;
                        sumX += std::fabs(q.exact[i]);
                        quantisation += L * (s / (2 * C) * (1 + std::ldexp(1.0, -50)) + roundingGamma(2) * std::fabs(x));
                    }
                    const double gamma = roundingGamma(order + 3), lightingSteps = 0.51 * step[c] * sumX;
                    const double steps =
                        quantisedLighting ? lightingSteps * (1 + gamma) + gamma * dotDecoded * (1 + roundingGamma(1)) : 0;
                    const double bound = roundingGamma(double(n)) * (dotDecoded + dotOriginal) + quantisation + steps;
                    if (std::fabs(double(radiance[v * 3 + c]) - viaOriginal[v * 3 + c]) > bound) ++failures;
                }
            }
            EXPECT_EQ(failures, 0u);
        }
}

TEST(EncodedRelight, HalfRowsRelightBitForBitLikeTheirFloats) {
    for (size_t patch : {1, 11}) { // orders vertex by vertex, or in runs of 11 (groups of 8 consecutive vertices)
        SCOPED_TRACE("patches of " + std::to_string(patch));
        Quantised shape = quantisedBundle(5000, 4, 8, false, 5, patch); // only its offsets
        Bundle bundle = vertexBundle(5000);
        std::mt19937 random(9);
        Layer data = layer("transfer_ragged", "vertex_ragged", "sh_transfer_rgb", {shape.offsets.back(), 3}, "float16");
        for (size_t i = 0; i < size_t(shape.offsets.back()) * 3; ++i) // every half pattern but infinities and NaNs
            data.data.push_back(halfToFloat(uint16_t(random() % 0x10000u & 0xfbffu)));
        data.data[0] = halfToFloat(0x0001); // the smallest subnormal
        data.data[1] = halfToFloat(0x83ff); // a negative subnormal
        data.params = {{"order", 4}, {"offsets", "transfer_offsets"}, {"format", "half"}};
        bundle.layers = {data, shape.bundle.layers[1]};
        RelightModel model = relightModel(bundle, "h.glb"); // blocked by band count where the processor has F16C
        ASSERT_EQ(model.storage, TransferStorage::Float16);
        EXPECT_EQ(model.rowsBlocked, !model.blockedRuns.empty()) << "orders 1..4: blocked as ragged, or not at all";
        EXPECT_TRUE(sameBits(decodedTransfer(model), data.data)) << "halves widen exactly";
        RelightModel floats;
        floats.vertexCount = model.vertexCount;
        floats.order = 4;
        floats.offsets = shape.offsets;
        floats.transfer = data.data;
        std::vector<float> lighting = randomLighting(4, 2);
        const std::vector<float> expected = relightAll(floats, lighting.data());
        EXPECT_TRUE(sameBits(relightAll(model, lighting.data()), expected));
        for (auto [begin, end] : {std::pair<size_t, size_t>{1, 2}, {4095, 4097}, {1237, 4999}}) {
            std::vector<float> range((end - begin) * 3);
            relight(model, lighting.data(), begin, end, range.data());
            EXPECT_EQ(std::memcmp(range.data(), expected.data() + begin * 3, range.size() * sizeof(float)), 0)
                << "range [" << begin << ", " << end << ")";
        }
    }
}


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
// and end inside blocks or end at the buffer's end, single vertices, and through the job hook; then the same halves
// vertex-blocked (blockRows; 4,099 vertices end in a padded block), whose lanes add in the float kernel's order.
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
        const std::vector<float> expected = relightAll(floats, lighting.data());
        // Row by row, then (where the processor has F16C) vertex-blocked as the loader holds them.
        for (bool blocked : {false, true}) {
            if (blocked && !blockRows(model)) continue;
            SCOPED_TRACE(blocked ? "blocked" : "rows");
            EXPECT_TRUE(sameBits(decodedTransfer(model), floats.transfer)) << "the same rows";
            const std::vector<float> whole = relightAll(model, lighting.data());
            EXPECT_TRUE(sameBits(whole, expected)) << "the whole buffer";
            size_t negativeZeros = 0;
            for (float r : whole) negativeZeros += r == 0 && std::signbit(r);
            EXPECT_EQ(negativeZeros, 0u) << "the float kernel's lanes start at +0";
            for (auto [begin, end] : {std::pair<size_t, size_t>{1237, 4090}, {1, V}, {V - 1, V}, {4095, 4097}}) {
                std::vector<float> range((end - begin) * 3), hooked((end - begin) * 3);
                const size_t before = calls;
                relight(model, lighting.data(), begin, end, range.data());
                EXPECT_EQ(std::memcmp(range.data(), expected.data() + begin * 3, range.size() * sizeof(float)), 0)
                    << "range [" << begin << ", " << end << ")";
                relight(model, lighting.data(), begin, end, hooked.data(), jobs);
                EXPECT_TRUE(sameBits(range, hooked)) << "job hook, range [" << begin << ", " << end << ")";
                EXPECT_EQ(calls, before + 1) << "one parallelFor per call";
            }
        }
    }
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
                std::vector<float> range((end - begin) * 3), hooked((end - begin) * 3);
                relight(model, lighting.data(), begin, end, range.data());
                EXPECT_EQ(outsideExactCodeBound(q.exact, q.offsets, lighting, model.rowsBlocked && bits == 8,
                                                range.data(), begin, end),
                          0u);
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
// last row (read through its zero-padded copy), then with per-vertex scales the same codes vertex-blocked (blockRows:
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
                std::vector<double> exactValues(V * values); // x_j = (q_j - C) sigma_l
                for (size_t v = 0; v < V; ++v)
                    for (size_t j = 0; j < values; ++j) {
                        const size_t scaleRow = perCluster ? model.scaleCluster[v] : v;
                        const double sigma = model.bandScales[scaleRow * size_t(n) + size_t(std::sqrt(double(j / 3)))];
                        exactValues[v * values + j] = (double(codes[v * values + j]) - C) * sigma;
                    }
                const std::vector<uint32_t> offsets = model.offsets;
                // The row kernel, then (per-vertex scales) the same codes vertex-blocked, each against the exact sum.
                for (bool blocked : {false, true}) {
                    if (blocked) {
                        const std::vector<float> rows = decodedTransfer(model);
                        ASSERT_EQ(blockRows(model), !perCluster);
                        if (perCluster) continue;
                        ASSERT_TRUE(model.rowsBlocked);
                        EXPECT_TRUE(model.blockedRuns.empty()) << "one order: blocks of consecutive vertices";
                        EXPECT_TRUE(sameBits(decodedTransfer(model), rows)) << "the blocked rows decode as the rows did";
                    }
                    SCOPED_TRACE(blocked ? "blocked" : "rows");
                    std::vector<float> radiance = relightAll(model, lighting.data());
                    // Blocked u8 codes go through the lighting quantised per channel (relightBlockedU8Kernel).
                    size_t exact = 0;
                    const size_t failures = outsideExactCodeBound(exactValues, offsets, lighting, blocked && bits == 8,
                                                                  radiance.data(), 0, V, &exact);
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
