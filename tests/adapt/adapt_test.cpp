// lib/adapt and the runtime's adaptive half: order selection, grading, ragged relighting (bit for bit at full
// order), per-band quantisation bounds, CPCA exactness, and the runtime's refusals.
#include "adapt.h"
#include "core.h"
#include "runtime.h"
#include "sh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace prt;

namespace {

// A strip of triangles over vertices 0..n-1 in a row (pairs), so the mesh has edges (v, v+1) and (v, v+2).
TriMesh stripMesh(size_t n) {
    TriMesh mesh;
    for (size_t v = 0; v < n; ++v) mesh.positions.insert(mesh.positions.end(), {float(v / 2), float(v % 2), 0.0f});
    for (size_t v = 0; v + 2 < n; ++v) {
        if (v % 2 == 0) mesh.indices.insert(mesh.indices.end(), {uint32_t(v), uint32_t(v + 2), uint32_t(v + 1)});
        else mesh.indices.insert(mesh.indices.end(), {uint32_t(v), uint32_t(v + 1), uint32_t(v + 2)});
    }
    return mesh;
}

// Transfer whose band l has magnitude decay^l, so low-decay vertices need few bands, and a positive DC term.
std::vector<float> decayingTransfer(size_t vertices, int order, uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    std::vector<float> transfer(vertices * order * order * 3);
    for (size_t v = 0; v < vertices; ++v) {
        float decay = 0.1f + 0.8f * float(v % 7) / 6.0f;
        for (int l = 0; l < order; ++l)
            for (int j = l * l; j < (l + 1) * (l + 1); ++j)
                for (int c = 0; c < 3; ++c)
                    transfer[(v * order * order + j) * 3 + c] =
                        (l == 0 ? 1.0f : uniform(random)) * std::pow(decay, float(l));
    }
    return transfer;
}

std::vector<float> randomLighting(int order, uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    std::vector<float> lighting(size_t(order) * order * 3);
    for (float& value : lighting) value = uniform(random);
    for (int c = 0; c < 3; ++c) lighting[c] = 3.0f;
    return lighting;
}

Bundle transferBundle(size_t vertices, int order, uint32_t seed) {
    Bundle bundle;
    bundle.mesh = stripMesh(vertices);
    Layer layer;
    layer.name = "transfer";
    layer.domain = "vertex";
    layer.semantic = "sh_transfer_rgb";
    layer.shape = {vertices, uint64_t(order) * order, 3};
    layer.params = {{"order", order}};
    layer.data = decayingTransfer(vertices, order, seed);
    bundle.layers.push_back(layer);
    return bundle;
}

std::vector<float> relightAll(const RelightModel& model, const std::vector<float>& lighting) {
    std::vector<float> radiance(size_t(model.vertexCount) * 3);
    relight(model, lighting.data(), 0, model.vertexCount, radiance.data());
    return radiance;
}

} // namespace

TEST(Adapt, ThresholdZeroRelightsBitForBitLikeFullOrder) {
    for (int order : {3, 8}) {
        Bundle bundle = transferBundle(101, order, 7);
        RelightModel full = relightModel(bundle, "full");
        std::vector<float> lighting = randomLighting(order, 3);
        adapt::AdaptOptions options; // maxError 0: lossless
        adapt::adaptBundle(bundle, {lighting}, options, "test");
        ASSERT_EQ(findLayer(bundle, "transfer"), nullptr);
        RelightModel adaptive = relightModel(bundle, "adaptive");
        ASSERT_FALSE(adaptive.offsets.empty());
        std::vector<float> a = relightAll(adaptive, lighting), b = relightAll(full, lighting);
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << "order " << order;
    }
}

// A bake's per-texel transfer, inline (format bundle), over a width x height atlas.
Bundle texelBundle(int width, int height, int order, uint32_t seed) {
    Bundle bundle;
    bundle.mesh = stripMesh(4);
    Layer layer;
    layer.name = "texel_transfer";
    layer.domain = "texel";
    layer.semantic = "sh_transfer_rgb";
    const size_t texels = size_t(width) * height;
    layer.shape = {texels, uint64_t(order) * order, 3};
    layer.params = {{"order", order}, {"width", width}, {"height", height}, {"format", "bundle"}};
    layer.data = decayingTransfer(texels, order, seed);
    bundle.layers.push_back(layer);
    return bundle;
}

TEST(AdaptTexels, ThresholdZeroRelightsBitForBitLikeTheBake) {
    Bundle bundle = texelBundle(9, 7, 5, 11);
    TexelRelightModel full = texelRelightModel(bundle, "full");
    std::vector<float> lighting = randomLighting(5, 4);
    adapt::adaptBundle(bundle, {lighting}, adapt::AdaptOptions{}, "test");
    ASSERT_EQ(findLayer(bundle, "texel_transfer"), nullptr);
    ASSERT_NE(findLayer(bundle, "transfer_ragged"), nullptr);
    EXPECT_EQ(findLayer(bundle, "transfer_ragged")->domain, "texel_ragged");
    EXPECT_EQ(findLayer(bundle, "transfer_offsets")->domain, "texel_offsets");
    TexelRelightModel adaptive = texelRelightModel(bundle, "adaptive");
    EXPECT_EQ(adaptive.width, 9);
    EXPECT_EQ(adaptive.height, 7);
    std::vector<float> a = relightAll(adaptive.rows, lighting), b = relightAll(full.rows, lighting);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
}

TEST(AdaptTexels, OrdersStayWithinTheBoundAndGradedOverTheTexelGrid) {
    const int width = 12, height = 10, order = 6;
    Bundle bundle = texelBundle(width, height, order, 5);
    std::vector<float> full = bundle.layers[0].data, lighting = randomLighting(order, 9);
    adapt::AdaptOptions options;
    options.maxError = 0.02;
    adapt::AdaptStats stats = adapt::adaptBundle(bundle, {lighting}, options, "test");
    EXPECT_LE(stats.relativeRmse, 0.02);
    EXPECT_LT(stats.meanCoefficients, double(order * order)) << "some texels need fewer bands";
    TexelRelightModel model = texelRelightModel(bundle, "adaptive");
    auto orderOf = [&](size_t t) { return int(std::lround(std::sqrt(model.rows.offsets[t + 1] - model.rows.offsets[t]))); };
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            size_t t = size_t(y) * width + x;
            if (x + 1 < width) {
                EXPECT_LE(std::abs(orderOf(t) - orderOf(t + 1)), 1) << "texel " << t;
            }
            if (y + 1 < height) {
                EXPECT_LE(std::abs(orderOf(t) - orderOf(t + width)), 1) << "texel " << t;
            }
        }
    // A per-vertex runtime call on texel layers is refused rather than misread.
    Bundle vertexBundle = transferBundle(10, 3, 1);
    adapt::AdaptOptions lossless;
    adapt::adaptBundle(vertexBundle, {randomLighting(3, 1)}, lossless, "vertex");
    EXPECT_THROW(texelRelightModel(vertexBundle, "vertex"), Error);
}

TEST(Adapt, EveryVertexStaysWithinTheBoundAndSmoothVerticesGetFewBands) {
    const int order = 6;
    const size_t V = 70;
    std::vector<float> transfer = decayingTransfer(V, order, 1);
    std::vector<float> lighting = randomLighting(order, 2);
    std::vector<float> error = adapt::truncationError(transfer.data(), V, order, {lighting}, adapt::Prior::Maps);
    const double maxError = 0.01;
    std::vector<uint8_t> orders = adapt::selectOrders(error, V, order, maxError);
    // The scale: RMS full radiance.
    std::vector<double> full(V * 3);
    double sumSquares = 0.0;
    for (size_t v = 0; v < V; ++v)
        for (int c = 0; c < 3; ++c) {
            for (int j = 0; j < order * order; ++j) full[v * 3 + c] += double(transfer[(v * order * order + j) * 3 + c]) * lighting[j * 3 + c];
            sumSquares += full[v * 3 + c] * full[v * 3 + c];
        }
    const double scale = std::sqrt(sumSquares / double(V * 3));
    for (size_t v = 0; v < V; ++v) {
        for (int c = 0; c < 3; ++c) {
            double truncated = 0.0;
            for (int j = 0; j < orders[v] * orders[v]; ++j)
                truncated += double(transfer[(v * order * order + j) * 3 + c]) * lighting[j * 3 + c];
            EXPECT_LE(std::fabs(truncated - full[v * 3 + c]) / scale, maxError * (1 + 1e-5)) << v;
        }
        if (orders[v] > 1) { // one band fewer would break the bound: the order is the smallest
            EXPECT_GT(error[v * order + orders[v] - 2], maxError) << v;
        }
    }
    EXPECT_LE(orders[0], 3); // decay 0.1: bands fall by 10x each
    EXPECT_EQ(orders[6], order); // decay 0.9
}

TEST(Adapt, WorstCaseBoundsEveryRotationOfTheMap) {
    const int order = 5;
    const size_t V = 40;
    std::vector<float> transfer = decayingTransfer(V, order, 5);
    std::vector<float> lighting = randomLighting(order, 6);
    std::vector<float> worst = adapt::truncationError(transfer.data(), V, order, {lighting}, adapt::Prior::Worst);
    std::vector<float> maps = adapt::truncationError(transfer.data(), V, order, {lighting}, adapt::Prior::Maps);
    for (size_t i = 0; i < worst.size(); ++i) EXPECT_GE(worst[i] * (1 + 1e-5) + 1e-7, maps[i]) << i;
    // A rotated map: its own exact errors, measured against its own scale, stay under the bound measured against
    // the unrotated map's scale times the ratio of scales; compare absolute tails instead.
    double R[9];
    sh::rotationY(73.0, R);
    std::vector<float> rotated = rotateLighting(lighting.data(), order, R);
    for (size_t v = 0; v < V; ++v)
        for (int n = 1; n < order; ++n)
            for (int c = 0; c < 3; ++c) {
                double tail = 0.0, bound = 0.0;
                for (int l = n; l < order; ++l) {
                    double tn = 0.0, ln = 0.0;
                    for (int j = l * l; j < (l + 1) * (l + 1); ++j) {
                        tail += double(transfer[(v * order * order + j) * 3 + c]) * rotated[j * 3 + c];
                        tn += double(transfer[(v * order * order + j) * 3 + c]) * transfer[(v * order * order + j) * 3 + c];
                        ln += double(lighting[j * 3 + c]) * lighting[j * 3 + c];
                    }
                    bound += std::sqrt(tn * ln);
                }
                EXPECT_LE(std::fabs(tail), bound * (1 + 1e-4) + 1e-6);
            }
}

TEST(Adapt, SmoothingGradesTheOrderByOneBandPerEdgeAndOnlyRaises) {
    TriMesh mesh = stripMesh(12); // edges (v, v+1) and (v, v+2)
    std::vector<uint8_t> orders(12, 1);
    orders[0] = 8;
    std::vector<uint8_t> before = orders;
    size_t raised = adapt::smoothOrders(mesh.indices, orders, 1);
    for (size_t v = 0; v < 12; ++v) EXPECT_GE(orders[v], before[v]);
    for (size_t t = 0; t < mesh.indices.size(); t += 3)
        for (int e = 0; e < 3; ++e)
            EXPECT_LE(std::abs(int(orders[mesh.indices[t + e]]) - int(orders[mesh.indices[t + (e + 1) % 3]])), 1);
    // Graph distance from vertex 0 along (v, v+1), (v, v+2): vertex v is ceil(v / 2) steps away.
    for (size_t v = 0; v < 12; ++v) EXPECT_EQ(orders[v], std::max(1, 8 - int((v + 1) / 2))) << v;
    EXPECT_EQ(raised, 11u); // every vertex but 0
}

TEST(Adapt, PerBandQuantisationStaysWithinHalfAStep) {
    const int order = 5;
    const size_t V = 60;
    std::vector<float> transfer = decayingTransfer(V, order, 9);
    std::vector<uint8_t> orders(V);
    for (size_t v = 0; v < V; ++v) orders[v] = uint8_t(1 + v % order);
    adapt::RaggedTransfer ragged = adapt::raggedTransfer(transfer.data(), V, order, orders);
    std::vector<uint32_t> cluster(V);
    for (size_t v = 0; v < V; ++v) cluster[v] = uint32_t(v % 4);
    for (int bits : {8, 16})
        for (bool perCluster : {false, true}) {
            adapt::QuantisedTransfer q = adapt::quantise(ragged, bits, perCluster ? cluster : std::vector<uint32_t>{}, 4);
            std::vector<float> decoded = adapt::dequantise(ragged, q);
            const double c = double((1u << (bits - 1)) - 1);
            size_t bandOffset = 0;
            for (size_t v = 0; v < V; ++v) {
                for (int l = 0; l < orders[v]; ++l) {
                    double scale = perCluster ? q.scales[cluster[v] * order + l] : q.scales[bandOffset + l];
                    for (int j = l * l; j < (l + 1) * (l + 1); ++j)
                        for (int ch = 0; ch < 3; ++ch) {
                            size_t i = (ragged.offsets[v] + j) * 3 + ch;
                            EXPECT_LE(q.codes[i], uint32_t(2 * c));
                            EXPECT_LE(std::fabs(decoded[i] - ragged.values[i]), scale / (2 * c) * (1 + 1e-5) + 1e-12)
                                << bits << " " << perCluster << " " << i;
                        }
                }
                bandOffset += orders[v];
            }
        }
}

TEST(Adapt, QuantisedBundlesDecodeInTheRuntimeAsInTheLibrary) {
    fs::path dir = fs::temp_directory_path() / ("prt_adapt_q_" + std::to_string(getpid()));
    fs::create_directories(dir);
    const int order = 4;
    for (auto format : {adapt::Format::U8, adapt::Format::U16, adapt::Format::Half})
        for (bool perCluster : {false, true}) {
            Bundle bundle = transferBundle(50, order, 11);
            std::vector<float> full = bundle.layers[0].data;
            std::vector<float> lighting = randomLighting(order, 4);
            adapt::AdaptOptions options;
            options.maxError = 0.02;
            options.format = format;
            options.perClusterScales = perCluster;
            options.clusters = 5;
            adapt::AdaptStats stats = adapt::adaptBundle(bundle, {lighting}, options, "test");
            std::string path = (dir / "q.glb").string();
            writeBundle(path, bundle);
            RelightModel model = loadRelightModel(path);
            // The runtime's relight matches the relative RMSE the library computed from its own decode.
            std::vector<float> radiance = relightAll(model, lighting);
            double error = 0.0, reference = 0.0;
            for (size_t v = 0; v < 50; ++v)
                for (int c = 0; c < 3; ++c) {
                    double f = 0.0;
                    for (int j = 0; j < order * order; ++j) f += double(full[(v * order * order + j) * 3 + c]) * lighting[j * 3 + c];
                    error += (radiance[v * 3 + c] - f) * (radiance[v * 3 + c] - f);
                    reference += f * f;
                }
            EXPECT_NEAR(std::sqrt(error / reference), stats.relativeRmse, 1e-5 + 1e-3 * stats.relativeRmse);
            EXPECT_LT(stats.relativeRmse, 0.03);
        }
    fs::remove_all(dir);
}

TEST(Adapt, CpcaWithAllComponentsReconstructsExactly) {
    const size_t rows = 200, dim = 12; // order 2
    std::vector<float> data = decayingTransfer(rows, 2, 13);
    adapt::Cpca cpca = adapt::clusteredPca(data.data(), rows, dim, 4, int(dim));
    std::vector<float> back = adapt::reconstruct(cpca);
    for (size_t i = 0; i < data.size(); ++i) EXPECT_NEAR(back[i], data[i], 1e-5f) << i;
    // Fewer components: a real approximation, and more components never worse.
    double previous = 1e30;
    for (int m : {1, 3, 6, 12}) {
        adapt::Cpca fewer = adapt::clusteredPca(data.data(), rows, dim, 4, m);
        std::vector<float> approx = adapt::reconstruct(fewer);
        double error = 0.0;
        for (size_t i = 0; i < data.size(); ++i) error += double(approx[i] - data[i]) * (approx[i] - data[i]);
        EXPECT_LE(error, previous * (1 + 1e-6) + 1e-9);
        previous = error;
    }
}

TEST(Adapt, CpcaBundleRelightsLikeItsReconstruction) {
    const int order = 3;
    Bundle bundle = transferBundle(80, order, 17);
    std::vector<float> lighting = randomLighting(order, 8);
    adapt::AdaptOptions options;
    options.order = order;
    options.format = adapt::Format::Cpca;
    options.clusters = 3;
    options.components = order * order * 3;
    std::vector<float> full = bundle.layers[0].data;
    adapt::adaptBundle(bundle, {lighting}, options, "test");
    RelightModel model = relightModel(bundle, "cpca");
    EXPECT_EQ(model.storage, TransferStorage::Cpca) << "kept in its basis, not decoded at load";
    std::vector<float> rows = decodedTransfer(model);
    ASSERT_EQ(rows.size(), full.size());
    for (size_t i = 0; i < full.size(); ++i) EXPECT_NEAR(rows[i], full[i], 1e-5f);
}

TEST(Adapt, RuntimeRefusesBandsItLacks) {
    Bundle bundle = transferBundle(10, 3, 1);
    adapt::AdaptOptions options;
    adapt::adaptBundle(bundle, {randomLighting(3, 1)}, options, "test");
    Layer* data = nullptr;
    for (Layer& layer : bundle.layers)
        if (layer.name == "transfer_ragged") data = &layer;
    ASSERT_NE(data, nullptr);
    data->params["order"] = kMaxRuntimeOrder + 8;
    try {
        relightModel(bundle, "big.glb");
        FAIL() << "accepted an order above the runtime's";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("this runtime evaluates at most " + std::to_string(kMaxRuntimeOrder)),
                  std::string::npos) << e.what();
        EXPECT_EQ(e.exitCode(), kExitInput);
    }
    // A vertex with more bands than the layer's order, and one with a count that is not n^2.
    data->params["order"] = 2;
    EXPECT_THROW(relightModel(bundle, "b.glb"), Error);
    data->params["order"] = 3;
    for (Layer& layer : bundle.layers)
        if (layer.name == "transfer_offsets") layer.integers[1] = 5;
    EXPECT_THROW(relightModel(bundle, "c.glb"), Error);
}

TEST(Adapt, RmsBudgetKeepsEveryMapWithinTheBoundWithFewerCoefficients) {
    const int order = 6;
    const size_t V = 140;
    std::vector<float> transfer = decayingTransfer(V, order, 21);
    std::vector<std::vector<float>> lightings = {randomLighting(order, 1), randomLighting(order, 2)};
    const double maxError = 0.01;
    std::vector<double> squared = adapt::truncationErrorSquared(transfer.data(), V, order, lightings, adapt::Prior::Maps);
    std::vector<uint8_t> orders = adapt::budgetOrders(squared, lightings.size(), V, order, maxError);
    std::vector<uint8_t> perVertex = adapt::selectOrders(
        adapt::truncationError(transfer.data(), V, order, lightings, adapt::Prior::Maps), V, order, maxError);
    adapt::RaggedTransfer ragged = adapt::raggedTransfer(transfer.data(), V, order, orders);
    std::vector<float> dense = adapt::denseTransfer(ragged);
    double worst = 0.0;
    for (const auto& lighting : lightings) { // each map on its own, as prt compare would score it
        double rmse = adapt::priorRelativeRmse(dense.data(), transfer.data(), V, order, {lighting});
        EXPECT_LE(rmse, maxError * (1 + 1e-6));
        worst = std::max(worst, rmse);
    }
    EXPECT_GT(worst, 0.5 * maxError); // it spends the budget rather than keep every band
    size_t budgetCoefficients = 0, vertexCoefficients = 0;
    for (size_t v = 0; v < V; ++v) budgetCoefficients += orders[v] * orders[v], vertexCoefficients += perVertex[v] * perVertex[v];
    EXPECT_LT(budgetCoefficients, vertexCoefficients);
    EXPECT_EQ(adapt::budgetOrders(squared, lightings.size(), V, order, 0.0), std::vector<uint8_t>(V, uint8_t(order)));
}
