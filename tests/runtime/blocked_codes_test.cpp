// Ragged vertex-blocked codes: `prt adapt`'s graded orders with per-vertex scales, grouped at load by band count
// within each task block (blockRows, RelightModel::blockedRuns) so that the blocked kernels relight them 8 vertices
// at a time. Oracles: the codes' own definition, fl((q - C) sigma), the same vertex relit alone as a model of its
// own order, and the whole call's bits for every range and job system.
#include "encoded_fixtures.h"

#include "prt/adaptive.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

using namespace prt_test;

namespace {

// 10,000 vertices: two whole task blocks and a part of one; orders 1..8, vertex by vertex (vertex v has 1 + 7v mod 8
// bands, so no group of 8 holds consecutive vertices) or in patches of 13 (so most do, and some do not).
constexpr size_t kVertices = 10000;
constexpr int kOrder = 8;
constexpr size_t kPatches[] = {1, 13};

// Lighting whose largest magnitude per channel is band 0's, so that the u8 kernel's quantisation step, the
// largest |L_c| / 32767, is the same for the model's order and for any fewer bands.
std::vector<float> bandZeroLargest(uint32_t seed) {
    std::vector<float> lighting = randomLighting(kOrder, seed);
    for (int c = 0; c < 3; ++c) lighting[c] = c == 1 ? -3.0f : 3.0f;
    return lighting;
}

// Vertex v of q alone, as a model of its own band count n with per-vertex scales, blocked as blockRows lays out
// one order.
RelightModel vertexAlone(const Quantised& q, const RelightModel& ragged, size_t v, int bits) {
    const size_t first = size_t(q.offsets[v]) * 3, values = size_t(q.offsets[v + 1] - q.offsets[v]) * 3;
    const int n = int(std::lround(std::sqrt(double(values / 3))));
    const float C = float((1u << (bits - 1)) - 1);
    RelightModel alone;
    alone.vertexCount = 1;
    alone.order = n;
    alone.storage = ragged.storage;
    alone.offsets = {0, uint32_t(n * n)};
    alone.bandBlockStarts = {0, uint32_t(n)};
    const std::vector<uint32_t>& codes = q.bundle.layers[0].integers;
    const auto from = codes.begin() + std::ptrdiff_t(first), to = from + std::ptrdiff_t(values);
    if (bits == 8) alone.codes8.assign(from, to);
    else alone.codes16.assign(from, to);
    for (int l = 0; l < n; ++l) alone.bandScales.push_back(float(q.scaleOfValue[first + size_t(l * l) * 3]) / C);
    EXPECT_TRUE(blockRows(alone));
    return alone;
}

// Calls f(q, model, bits) for graded u8 and u16 codes, vertex by vertex and in patches, loaded (so blocked) as
// `prt relight` loads them.
template <class F>
void forEachRaggedModel(uint32_t seed, F&& f) {
    for (int bits : {8, 16})
        for (size_t patch : kPatches) {
            SCOPED_TRACE(std::to_string(bits) + " bits, patches of " + std::to_string(patch));
            const Quantised q = quantisedBundle(kVertices, kOrder, bits, false, seed + uint32_t(bits), patch);
            f(q, relightModel(q.bundle, "q.glb"), bits);
        }
}

} // namespace

TEST(BlockedCodes, RaggedCodesAreGroupedByBandCountAndDecodeToTheirRows) {
    forEachRaggedModel(41, [](const Quantised& q, const RelightModel& model, int bits) {
        ASSERT_TRUE(model.rowsBlocked) << "blocked at load";
        const size_t tasks = (kVertices + kRelightBlock - 1) / kRelightBlock;
        ASSERT_EQ(model.blockedRuns.size(), tasks * 8 + 1);
        ASSERT_EQ(model.blockedLanes.size(), model.blockedRuns.back().group * kCodeBlock);
        // Every vertex in exactly one lane, of a group of its own band count, in its own task block, in vertex
        // order.
        std::vector<int> seen(kVertices, 0);
        size_t padding = 0;
        for (size_t t = 0; t < tasks; ++t)
            for (size_t n = 1; n <= 8; ++n) {
                long previous = -1;
                const uint64_t groupEnd = model.blockedRuns[8 * t + n].group;
                for (uint64_t g = model.blockedRuns[8 * t + n - 1].group; g < groupEnd; ++g)
                    for (size_t i = 0; i < kCodeBlock; ++i) {
                        const uint16_t lane = model.blockedLanes[g * kCodeBlock + i];
                        if (lane == kPaddingLane) {
                            ++padding;
                            continue;
                        }
                        const size_t v = t * kRelightBlock + lane;
                        ASSERT_LT(v, kVertices);
                        ++seen[v];
                        EXPECT_EQ(q.offsets[v + 1] - q.offsets[v], n * n) << "vertex " << v;
                        EXPECT_GT(long(v), previous) << "vertex order within a run";
                        previous = long(v);
                    }
            }
        EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(kVertices));
        EXPECT_LE(padding, tasks * 8 * (kCodeBlock - 1)) << "at most 7 padded lanes per band count and task block";
        // The rows decode to what the codes stand for, bit for bit.
        const std::vector<float> decoded = decodedTransfer(model);
        ASSERT_EQ(decoded.size(), q.exact.size());
        size_t wrong = 0;
        for (size_t i = 0; i < decoded.size(); ++i) wrong += decoded[i] != float(q.exact[i]);
        EXPECT_EQ(wrong, 0u);
        // What relight reads: the codes and scales with their padding, the lanes and runs; no offsets.
        const size_t codeBytes = q.exact.size() * (bits / 8), lanes = model.blockedLanes.size() * sizeof(uint16_t);
        EXPECT_GT(relightBytes(model), codeBytes + lanes);
        EXPECT_LT(relightBytes(model), size_t(double(codeBytes) * 1.2) + lanes + kVertices * 8 * sizeof(float));
    });
}

TEST(BlockedCodes, EachVertexRelightsAsItWouldAloneAtItsOwnOrder) {
    forEachRaggedModel(7, [](const Quantised& q, const RelightModel& model, int bits) {
        ASSERT_FALSE(model.blockedRuns.empty());
        const std::vector<float> lighting = bandZeroLargest(5);
        const std::vector<float> radiance = relightAll(model, lighting.data());
        size_t different = 0;
        for (size_t v = 0; v < kVertices; ++v) {
            const RelightModel alone = vertexAlone(q, model, v, bits);
            float one[3];
            relight(alone, lighting.data(), 0, 1, one); // lighting's first n^2 coefficients: the same steps
            different += std::memcmp(one, &radiance[v * 3], sizeof one) != 0;
        }
        EXPECT_EQ(different, 0u);
        EXPECT_EQ(outsideExactCodeBound(q.exact, q.offsets, lighting, bits == 8, radiance.data(), 0, kVertices),
                  0u);
    });
}

TEST(BlockedCodes, RangesAndJobSystemsGiveTheWholeCallsBits) {
    forEachRaggedModel(3, [](const Quantised& q, const RelightModel& model, int bits) {
        const std::vector<float> lighting = randomLighting(kOrder, 11);
        const std::vector<float> whole = relightAll(model, lighting.data());
        for (auto [begin, end] : {std::pair<size_t, size_t>{1, 2}, {4095, 4097}, {1237, 9000}, {8192, kVertices},
                                  {5000, 5001}, {3, 4090}, {0, kVertices}}) {
            std::vector<float> part((end - begin) * 3), adaptive((end - begin) * 3);
            relight(model, lighting.data(), begin, end, part.data());
            EXPECT_EQ(std::memcmp(part.data(), &whole[begin * 3], part.size() * sizeof(float)), 0)
                << begin << ".." << end;
            relightAdaptive(model, lighting.data(), begin, end, adaptive.data());
            EXPECT_TRUE(sameBits(adaptive, part)) << "relightAdaptive " << begin << ".." << end;
        }
        size_t calls = 0;
        EXPECT_TRUE(sameBits(relightAll(model, lighting.data(), JobSystem{scrambledParallelFor, &calls}), whole));
        EXPECT_EQ(calls, 1u);
    });
}

// blockRows leaves alone what it cannot block: per-cluster scales, a vertex with more bands than the model's
// order, and codes or scales of other sizes than the offsets say.
TEST(BlockedCodes, ModelsItCannotBlockAreLeftAsTheyAre) {
    Quantised perCluster = quantisedBundle(300, 4, 8, true, 2);
    RelightModel model = relightModel(perCluster.bundle, "q.glb");
    EXPECT_FALSE(model.rowsBlocked);
    EXPECT_FALSE(blockRows(model));

    Quantised q = quantisedBundle(300, 4, 16, false, 2);
    RelightModel rows = relightModel(q.bundle, "q.glb");
    ASSERT_TRUE(rows.rowsBlocked);
    RelightModel unblocked;
    unblocked.vertexCount = 300;
    unblocked.order = 4;
    unblocked.storage = TransferStorage::Uint16;
    unblocked.offsets = q.offsets;
    unblocked.codes16.assign(q.bundle.layers[0].integers.begin(), q.bundle.layers[0].integers.end());
    for (size_t v = 0; v < 300; ++v) {
        if (v % kRelightBlock == 0) unblocked.bandBlockStarts.push_back(uint32_t(unblocked.bandScales.size()));
        const size_t n = size_t(std::lround(std::sqrt(double(q.offsets[v + 1] - q.offsets[v]))));
        for (size_t l = 0; l < n; ++l)
            unblocked.bandScales.push_back(float(q.scaleOfValue[(q.offsets[v] + l * l) * 3]) / 32767.0f);
    }
    unblocked.bandBlockStarts.push_back(uint32_t(unblocked.bandScales.size()));
    RelightModel tooFewBands = unblocked;
    tooFewBands.order = 3; // some vertices have 4 bands
    EXPECT_FALSE(blockRows(tooFewBands));
    EXPECT_FALSE(tooFewBands.rowsBlocked);
    RelightModel shortScales = unblocked;
    shortScales.bandScales.pop_back();
    EXPECT_FALSE(blockRows(shortScales));
    RelightModel shortCodes = unblocked;
    shortCodes.codes16.pop_back();
    EXPECT_FALSE(blockRows(shortCodes));
    const std::vector<float> before = decodedTransfer(unblocked);
    ASSERT_TRUE(blockRows(unblocked));
    EXPECT_TRUE(sameBits(decodedTransfer(unblocked), before)) << "the same rows, blocked";
    EXPECT_TRUE(sameBits(decodedTransfer(unblocked), decodedTransfer(rows))) << "as the loader blocks them";
}
