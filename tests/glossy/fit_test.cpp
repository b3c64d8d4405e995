// The fit: a synthetic Gaussian is recovered by both solvers, the OpenCL batch is deterministic, kernel build
// failures carry their log, lobe matching, and the stage's results do not depend on chunking or ranges.
#include "glossy.h"
#include "glossy_internal.h"

#include "core.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace {

using namespace prt::glossy;

// A batch of `copies` problems whose kernel is exactly a exp(l (mu . w - 1)), started from a perturbed guess.
FitBatch syntheticBatch(const DirectionGrid& grid, size_t copies, const float truth[5], const float start[5]) {
    FitBatch batch;
    batch.lobes = 1;
    batch.problems = copies;
    for (size_t p = 0; p < copies; ++p) {
        for (size_t i = 0; i < grid.count(); ++i) {
            const float* w = &grid.directions[i * 3];
            double c = truth[1] * w[0] + truth[2] * w[1] + truth[3] * w[2];
            batch.kernel.push_back(float(truth[0] * std::exp(truth[4] * (c - 1.0))));
        }
        batch.params.insert(batch.params.end(), start, start + 5);
        batch.amplitudeMax.push_back(4 * truth[0]);
    }
    return batch;
}

void expectRecovered(const FitBatch& batch, size_t p, const float truth[5], double energy) {
    const float* x = &batch.params[p * 5];
    double length = std::sqrt(x[1] * x[1] + x[2] * x[2] + x[3] * x[3]);
    double dot = (x[1] * truth[1] + x[2] * truth[2] + x[3] * truth[3]) / length;
    EXPECT_LT(std::acos(std::min(1.0, dot)) * 180 / std::numbers::pi, 0.05);
    EXPECT_NEAR(x[0], truth[0], 2e-3 * truth[0]);
    EXPECT_NEAR(std::exp(x[4]), truth[4], 2e-3 * truth[4]);
    EXPECT_LT(batch.cost[p], 1e-6 * energy);
}

TEST(GlossyFit, SingleGaussianRecoveredByBothSolvers) {
    DirectionGrid grid = cubeGrid(16);
    const float truth[5] = {3.0f, 0.48f, 0.6f, 0.64f, 40.0f};
    const float start[5] = {1.5f, 0.3f, 0.7f, 0.65f, std::log(20.0f)};
    FitBatch batch = syntheticBatch(grid, 1, truth, start);
    double energy = dataEnergy(grid, batch.kernel.data());
    FitBatch ceres = batch, opencl = batch;
    solveCeres(grid, ceres, FitWeights{}, FitBounds{}, SolverOptions{});
    expectRecovered(ceres, 0, truth, energy);
    solveOpenCl(grid, opencl, FitWeights{}, FitBounds{}, SolverOptions{});
    expectRecovered(opencl, 0, truth, energy);
    // The kernel reports its own objective at its double end point; the host's objective at the returned float
    // parameters agrees up to their rounding.
    EXPECT_NEAR(opencl.cost[0], objective(grid, opencl, 0, FitWeights{}, FitBounds{}, opencl.params.data()),
                1e-9 * energy);
}

TEST(GlossyFit, OpenClBatchIsBitIdenticalWhereverAProblemSits) {
    DirectionGrid grid = cubeGrid(8);
    const float truth[5] = {2.0f, 0.0f, 0.8f, 0.6f, 12.0f};
    const float start[5] = {1.0f, 0.2f, 0.7f, 0.6f, std::log(8.0f)};
    FitBatch one = syntheticBatch(grid, 1, truth, start);
    FitBatch many = syntheticBatch(grid, 37, truth, start);
    // Vary the others so the batch is not uniform.
    for (size_t p = 1; p < many.problems; ++p) many.params[p * 5] = 0.5f + 0.05f * float(p);
    solveOpenCl(grid, one, FitWeights{}, FitBounds{}, SolverOptions{});
    solveOpenCl(grid, many, FitWeights{}, FitBounds{}, SolverOptions{});
    for (int i = 0; i < 5; ++i) EXPECT_EQ(one.params[i], many.params[i]);
    EXPECT_EQ(one.iterations[0], many.iterations[0]);
}

TEST(GlossyFit, KernelBuildFailureShowsTheBuildLog) {
    try {
        buildOpenClProgram("__kernel void broken(__global float* x) { x[0] = undefinedName; }", "");
        FAIL() << "expected a build failure";
    } catch (const prt::Error& e) {
        EXPECT_NE(e.problem().find("build log"), std::string::npos) << e.what();
        EXPECT_NE(e.problem().find("undefinedName"), std::string::npos) << e.what();
        EXPECT_EQ(e.exitCode(), prt::kExitFailure);
    }
}

TEST(GlossyFit, LobeMatching) {
    // Output form (a, mu, lambda): b is a with its two lobes swapped.
    float a[10] = {1, 1, 0, 0, 10, 2, 0, 1, 0, 50};
    float b[10] = {2, 0, 1, 0, 50, 1, 1, 0, 0, 10};
    EXPECT_TRUE(lobesFlipped(a, b, 2));
    EXPECT_FALSE(lobesFlipped(a, a, 2));
    alignLobes(a, b, 2);
    for (int i = 0; i < 10; ++i) EXPECT_EQ(a[i], b[i]);
}

TEST(GlossyStage, ChunksAndRangesGiveTheSameRowsAndSolversAgree) {
    prt::TriMesh sphere = prt::makeSphere(1.0f, 5, 8);
    GlossyOptions options;
    options.phong = {16.0, 0.5};
    options.lobes = 1;
    options.gridResolution = 6;
    options.progress = false;
    options.chunkVertices = 64;
    GlossyLobes whole = computeGlossyLobes(sphere, options);
    options.chunkVertices = 5;
    options.vertexBegin = 7;
    options.vertexEnd = 19;
    GlossyLobes part = computeGlossyLobes(sphere, options);
    const size_t row = kViewCount * kLobeParams;
    ASSERT_EQ(part.values.size(), 12 * row);
    for (size_t i = 0; i < part.values.size(); ++i) ASSERT_EQ(part.values[i], whole.values[7 * row + i]) << i;
    // An unoccluded convex sphere: every fitted lobe points near its view's mirror direction.
    EXPECT_GT(whole.stats.problems, 0u);
    EXPECT_LT(whole.stats.meanRelativeError, 0.3);
    options.solver = Solver::Ceres;
    GlossyLobes ceres = computeGlossyLobes(sphere, options);
    double worst = 0;
    for (size_t i = 0; i < ceres.values.size(); i += kLobeParams)
        worst = std::max(worst, double(std::abs(ceres.values[i] - part.values[i])) / (1e-3 + part.values[i]));
    EXPECT_LT(worst, 0.02);
    // Bad options.
    options.lobes = 5;
    EXPECT_THROW(computeGlossyLobes(sphere, options), prt::Error);
    options.lobes = 1;
    options.phong.exponent = 0;
    EXPECT_THROW(computeGlossyLobes(sphere, options), prt::Error);
}

} // namespace

namespace {

// The indirect kernel of a vertex whose upper hemisphere is all blocked by surfaces of constant diffuse radiance
// c L_0 (transfer c in the first SH coefficient): under a constant unit environment it adds ks c L_0 at normal
// incidence, ks being the normalised lobe's directional albedo there (docs/conventions.md), L_0 = sqrt(4 pi).
TEST(GlossyIndirect, KernelOfAFullyBlockedHemisphereReflectsItsHitRadiance) {
    const prt::glossy::DirectionGrid grid = prt::glossy::cubeGrid(16);
    const int order = 3;
    const std::vector<float> basis = prt::glossy::gridBasis(grid, order);
    const float up[3] = {0.0f, 1.0f, 0.0f};
    const prt::glossy::Phong phong{8.0, 0.5};
    std::vector<uint8_t> visibility(grid.count(), 0);
    std::vector<float> hits(grid.count() * 9, 0.0f);
    const double c = 0.3;
    for (size_t t = 0; t < grid.count(); ++t) hits[t * 9] = float(c);
    std::vector<float> kernel(grid.count(), 0.0f);
    prt::glossy::addIndirectKernel(grid, basis.data(), order, up, up, phong, visibility.data(), hits.data(),
                                   kernel.data());
    double integral = 0.0;
    for (size_t t = 0; t < grid.count(); ++t) integral += kernel[t] * grid.solidAngle[t];
    const double expected = phong.ks * c * std::sqrt(4.0 * std::numbers::pi);
    EXPECT_NEAR(integral, expected, 0.02 * expected);
    // Nothing blocked: nothing added.
    std::fill(visibility.begin(), visibility.end(), 1);
    std::vector<float> none(grid.count(), 0.0f);
    prt::glossy::addIndirectKernel(grid, basis.data(), order, up, up, phong, visibility.data(), hits.data(), none.data());
    EXPECT_EQ(*std::max_element(none.begin(), none.end()), 0.0f);
}

// On a convex sphere nothing is blocked, so indirect glossy changes no lobe; inside an open cavity it adds light:
// the fitted lobes carry more energy at every vertex that sees the cavity wall.
TEST(GlossyIndirect, ConvexMeshUnchangedCavityGainsLight) {
    using namespace prt::glossy;
    GlossyOptions options;
    options.phong = {8.0, 0.5};
    options.gridResolution = 4;
    options.progress = false;
    options.weights = FitWeights{};
    prt::TriMesh sphere = prt::makeSphere(1.0f, 5, 8);
    GlossyLobes plain = computeGlossyLobes(sphere, options);
    options.indirectOrder = 2;
    options.indirectTransfer.assign(sphere.vertexCount() * 4, 0.2f);
    GlossyLobes indirect = computeGlossyLobes(sphere, options);
    EXPECT_EQ(indirect.values, plain.values);
    // Per-vertex statistics: a convex sphere sees its whole upper hemisphere.
    for (size_t v = 0; v < sphere.vertexCount(); ++v)
        ASSERT_FLOAT_EQ(plain.vertexStats[v * kVertexStatColumns + 3], 1.0f) << v;

    prt::TriMesh cavity = prt::makeOpenCavity(1.0f, 0.8f, 6, 10);
    options.indirectTransfer.clear();
    plain = computeGlossyLobes(cavity, options);
    options.indirectTransfer.assign(cavity.vertexCount() * 4, 0.0f);
    for (size_t v = 0; v < cavity.vertexCount(); ++v) options.indirectTransfer[v * 4] = 0.2f; // constant radiance
    indirect = computeGlossyLobes(cavity, options);
    double plainSum = 0.0, indirectSum = 0.0;
    for (size_t i = 0; i < plain.values.size(); i += kLobeParams) {
        // Energy of a lobe a exp(lambda (mu.w - 1)): 2 pi a (1 - exp(-2 lambda)) / lambda.
        auto energy = [](const float* lobe) { return lobe[0] * (1.0 - std::exp(-2.0 * lobe[4])) / lobe[4]; };
        plainSum += energy(&plain.values[i]);
        indirectSum += energy(&indirect.values[i]);
    }
    EXPECT_GT(indirectSum, 1.05 * plainSum);
    // Inside the cavity the wall hides part of every hemisphere.
    EXPECT_LT(plain.vertexStats[(cavity.vertexCount() - 1) * kVertexStatColumns + 3], 0.9f);
}

} // namespace

namespace {

using namespace prt::glossy;

TEST(GlossyNested, HeldOutGridLiesMostlyBetweenTheFitGrid) {
    for (int resolution : {6, 8, 16}) {
        const DirectionGrid grid = cubeGrid(resolution), held = heldOutGrid(resolution);
        ASSERT_EQ(held.count(), grid.count());
        double total = 0;
        std::vector<double> nearest; // per held-out direction, the angle to the nearest fit-grid direction
        for (size_t i = 0; i < held.count(); ++i) {
            const float* h = &held.directions[i * 3];
            total += held.solidAngle[i];
            EXPECT_NEAR(std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]), 1.0, 1e-6);
            double best = -1;
            for (size_t j = 0; j < grid.count(); ++j) {
                const float* g = &grid.directions[j * 3];
                best = std::max(best, double(h[0] * g[0] + h[1] * g[1] + h[2] * g[2]));
            }
            nearest.push_back(std::acos(std::min(1.0, best)));
        }
        EXPECT_NEAR(total, 4 * std::numbers::pi, 1e-4);
        // The fit grid's spacing is about 2 / resolution rad at a face centre, its cells' half-diagonal about
        // 0.7 of that: the median held-out direction lies at least a quarter spacing from every grid direction.
        std::sort(nearest.begin(), nearest.end());
        EXPECT_GT(nearest[nearest.size() / 2], 0.25 * 2.0 / resolution) << resolution;
        EXPECT_LT(nearest[nearest.size() / 2], 0.75 * 2.0 / resolution) << resolution;
    }
}

// Held-out data cost of every fitted (vertex, view) of a sphere (convex: V = 1 above the tangent plane, so the
// kernel is known without rays), recomputed here from the output lobes; -1 where the view has no fit.
// With options.nestedMaxNorm the score is maxResidual, with options.nestedLighting litCost (the nested gate's).
std::vector<double> sphereHeldOutCosts(const prt::TriMesh& sphere, const GlossyOptions& options,
                                       const GlossyLobes& lobes) {
    const DirectionGrid held = heldOutGrid(heldOutResolution(options));
    const ViewSet& views = viewSet();
    const int width = lobes.lobes * kLobeParams;
    std::vector<double> costs;
    std::vector<float> kernel(held.count()), solver(static_cast<size_t>(width), 0.0f);
    for (size_t v = 0; v < sphere.vertexCount(); ++v) {
        float n[3];
        const float* nn = &sphere.normals[v * 3];
        float length = std::sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
        for (int c = 0; c < 3; ++c) n[c] = nn[c] / length;
        for (int view = 0; view < kViewCount; ++view) {
            const float* row = &lobes.values[(v * kViewCount + size_t(view)) * size_t(width)];
            const float* w = views.directions[size_t(view)].data();
            tabulateKernel(held, n, w, options.phong, nullptr, kernel.data());
            bool fitted = n[0] * w[0] + n[1] * w[1] + n[2] * w[2] > 0.0f && row[0] > 0.0f;
            for (int k = 0; k < lobes.lobes; ++k) {
                std::copy_n(row + k * kLobeParams, 4, &solver[size_t(k) * kLobeParams]);
                solver[size_t(k) * kLobeParams + 4] = std::log(row[k * kLobeParams + 4]);
            }
            const size_t rows = options.nestedLighting.size() / held.count();
            double score = rows ? litCost(held, kernel.data(), lobes.lobes, solver.data(), options.nestedLighting.data(), rows)
                           : options.nestedMaxNorm ? maxResidual(held, kernel.data(), lobes.lobes, solver.data())
                                                   : dataCost(held, kernel.data(), lobes.lobes, solver.data());
            costs.push_back(fitted ? score : -1.0);
        }
    }
    return costs;
}

// The nested fit: stage 1 is the plain 1-lobe fit bit for bit, each added lobe never raises a view's error on the
// held-out directions (recomputed from the output, not read from the fit's own report), the gate keeps some and
// drops some stage-2 lobes, and Ceres and PoCL agree on the nested fits.
TEST(GlossyNested, MoreLobesNeverRaiseTheHeldOutErrorAndSolversAgree) {
    prt::TriMesh sphere = prt::makeSphere(1.0f, 5, 8);
    GlossyOptions options;
    options.phong = {64.0, 0.5}; // a lobe about as narrow as the 6x6 grid's spacing: extra lobes can overfit
    options.gridResolution = 6;
    options.progress = false;
    options.lobes = 1;
    const GlossyLobes plain = computeGlossyLobes(sphere, options);
    options.nested = true;
    std::vector<std::vector<double>> costs[2];
    for (Solver solver : {Solver::OpenCl, Solver::Ceres}) {
        options.solver = solver;
        for (int lobes = 1; lobes <= 3; ++lobes) {
            options.lobes = lobes;
            GlossyLobes nested = computeGlossyLobes(sphere, options);
            if (lobes == 1 && solver == Solver::OpenCl) {
                ASSERT_EQ(nested.values, plain.values);
            }
            if (lobes == 2) {
                ASSERT_EQ(nested.keptStage.size(), 2u);
                EXPECT_EQ(nested.keptStage[0], nested.stats.problems);
                EXPECT_GT(nested.keptStage[1], 0u);
                EXPECT_LT(nested.keptStage[1], nested.stats.problems);
            }
            costs[solver == Solver::Ceres].push_back(sphereHeldOutCosts(sphere, options, nested));
        }
    }
    for (int s = 0; s < 2; ++s)
        for (int lobes = 2; lobes <= 3; ++lobes) {
            const auto &fewer = costs[s][size_t(lobes) - 2], &more = costs[s][size_t(lobes) - 1];
            ASSERT_EQ(fewer.size(), more.size());
            size_t fitted = 0;
            for (size_t p = 0; p < fewer.size(); ++p) {
                if (fewer[p] < 0) continue;
                ++fitted;
                // float rounding of the output lobes only
                EXPECT_LE(more[p], fewer[p] * (1 + 1e-4) + 1e-12) << "solver " << s << ", " << lobes << " lobes, " << p;
            }
            EXPECT_GT(fitted, 100u);
        }
    // Both solvers reach the same held-out error in total within 3% at every lobe count (their fits agree within
    // 1%, tests/glossy/solver_test.cpp; near-ties of the gate then go either way).
    for (int lobes = 1; lobes <= 3; ++lobes) {
        double sum[2] = {0, 0};
        for (int s = 0; s < 2; ++s)
            for (double c : costs[s][size_t(lobes) - 1]) sum[s] += std::max(0.0, c);
        EXPECT_NEAR(sum[1], sum[0], 0.03 * sum[0]) << lobes << " lobes";
    }
}

// The keep criterion in closed form: with a 10% margin a lobe that lowers a view's held-out cost by 5% (it fits
// a sample, not the kernel between samples) is dropped and one that halves it is kept; without a margin any
// decrease is kept; per vertex one decision by the summed costs covers all the vertex's views, also one that
// rises; stage 1 is always kept.
TEST(GlossyNested, KeepStageMarginDropsASmallGainAndKeepsAHalving) {
    const std::vector<size_t> first = {0, 2, 3}; // vertex 0: problems 0, 1; vertex 1: problem 2
    const std::vector<double> previous = {1.0, 1.0, 1.0}, held = {0.95, 0.5, 0.99}, rising = {1.2, 0.5, 1.1};
    GlossyOptions options;
    EXPECT_EQ(keepStage(first, held, previous, 1, options), (std::vector<uint8_t>{1, 1, 1}));
    EXPECT_EQ(keepStage(first, held, previous, 2, options), (std::vector<uint8_t>{1, 1, 1}));
    options.nestedMargin = 0.1;
    EXPECT_EQ(keepStage(first, held, previous, 1, options), (std::vector<uint8_t>{1, 1, 1}));
    EXPECT_EQ(keepStage(first, held, previous, 2, options), (std::vector<uint8_t>{0, 1, 0}));
    options.nestedPerVertex = true; // vertex 0: 1.45 < 0.9 x 2; vertex 1: 0.99 > 0.9
    EXPECT_EQ(keepStage(first, held, previous, 2, options), (std::vector<uint8_t>{1, 1, 0}));
    options.nestedMargin = 0.0; // vertex 0: 1.7 < 2 although its view 0 rises; vertex 1: 1.1 > 1
    EXPECT_EQ(keepStage(first, rising, previous, 3, options), (std::vector<uint8_t>{1, 1, 0}));
    options.nestedMargin = 0.2; // vertex 0: 1.7 > 0.8 x 2
    EXPECT_EQ(keepStage(first, rising, previous, 3, options), (std::vector<uint8_t>{0, 0, 0}));
}

// litCost in closed form: lobes of amplitude 0 leave residual -kernel, so under one row of lighting w_i the cost is
// (sum_i w_i kernel_i)^2, two rows add; exact lobes cost 0 under any lighting. The same for maxResidual.
TEST(GlossyNested, LitCostIsTheSquaredRelitErrorSummedOverLightings) {
    const DirectionGrid grid = cubeGrid(4);
    const float lobe[kLobeParams] = {0.7f, 0.0f, 0.6f, 0.8f, std::log(20.0f)};
    std::vector<float> kernel(grid.count()), lighting(2 * grid.count());
    double first = 0, second = 0;
    for (size_t i = 0; i < grid.count(); ++i) {
        const float* w = &grid.directions[i * 3];
        kernel[i] = 0.7f * std::exp(20.0f * (0.6f * w[1] + 0.8f * w[2] - 1.0f));
        lighting[i] = grid.solidAngle[i];
        lighting[grid.count() + i] = grid.solidAngle[i] * (w[1] > 0 ? 2.0f : 0.0f);
        first += double(lighting[i]) * kernel[i], second += double(lighting[grid.count() + i]) * kernel[i];
    }
    float zero[kLobeParams] = {0.0f, 0.0f, 0.6f, 0.8f, std::log(20.0f)};
    EXPECT_NEAR(litCost(grid, kernel.data(), 1, zero, lighting.data(), 1), first * first, 1e-9 * first * first);
    EXPECT_NEAR(litCost(grid, kernel.data(), 1, zero, lighting.data(), 2), first * first + second * second,
                1e-9 * (first * first + second * second));
    EXPECT_NEAR(litCost(grid, kernel.data(), 1, lobe, lighting.data(), 2), 0.0, 1e-9 * first * first);
    // maxResidual: the kernel's peak for zero lobes, 0 for the exact lobe.
    const float peak = *std::max_element(kernel.begin(), kernel.end());
    EXPECT_NEAR(maxResidual(grid, kernel.data(), 1, zero), peak, 1e-7 * peak);
    EXPECT_NEAR(maxResidual(grid, kernel.data(), 1, lobe), 0.0, 1e-5 * peak);
}

// The nested fit's options on the small test sphere: Phong 64, grid 6, quiet.
GlossyOptions nestedSphereOptions() {
    GlossyOptions options;
    options.phong = {64.0, 0.5};
    options.gridResolution = 6;
    options.progress = false;
    options.nested = true;
    return options;
}

// The nested fit with a margin and per vertex: with the margin every view's held-out cost still never rises with
// the lobe count and fewer (but some) views keep stage 2; per vertex every vertex keeps stage k in all its fitted
// views or in none, and the vertex's summed held-out cost never rises.
TEST(GlossyNested, MarginAndPerVertexKeepCriteriaNeverRaiseTheHeldOutError) {
    prt::TriMesh sphere = prt::makeSphere(1.0f, 5, 8);
    GlossyOptions options = nestedSphereOptions();
    options.lobes = 2;
    const uint64_t anyGain = computeGlossyLobes(sphere, options).keptStage[1];
    options.nestedMargin = 0.1;
    std::vector<std::vector<double>> costs;
    for (int lobes = 1; lobes <= 2; ++lobes) {
        options.lobes = lobes;
        GlossyLobes nested = computeGlossyLobes(sphere, options);
        if (lobes == 2) {
            EXPECT_GT(nested.keptStage[1], 0u);
            EXPECT_LT(nested.keptStage[1], anyGain);
        }
        costs.push_back(sphereHeldOutCosts(sphere, options, nested));
    }
    // Each view either keeps stage 2 (held-out cost at most 0.9 of stage 1's) or stage 1's cost (float rounding).
    for (size_t p = 0; p < costs[0].size(); ++p) {
        if (costs[0][p] < 0) continue;
        const double before = costs[0][p], after = costs[1][p];
        EXPECT_TRUE(after <= 0.9 * before * (1 + 1e-4) + 1e-12 || std::abs(after - before) <= 1e-4 * before + 1e-12)
            << p << ": " << before << " -> " << after;
    }

    options.nestedMargin = 0.0;
    options.nestedPerVertex = true;
    costs.clear();
    for (int lobes = 1; lobes <= 3; ++lobes) {
        options.lobes = lobes;
        GlossyLobes nested = computeGlossyLobes(sphere, options);
        costs.push_back(sphereHeldOutCosts(sphere, options, nested));
        if (lobes < 2) continue;
        size_t keeping = 0, dropping = 0;
        const int width = lobes * kLobeParams;
        for (size_t v = 0; v < sphere.vertexCount(); ++v) {
            size_t kept = 0, fitted = 0;
            for (int view = 0; view < kViewCount; ++view) {
                if (costs.back()[v * kViewCount + size_t(view)] < 0) continue;
                ++fitted;
                kept += nested.values[(v * kViewCount + size_t(view)) * size_t(width) + size_t(lobes - 1) * kLobeParams] != 0.0f;
            }
            EXPECT_TRUE(kept == 0 || kept == fitted) << "vertex " << v << ": " << kept << " of " << fitted;
            keeping += kept > 0, dropping += kept == 0 && fitted > 0;
        }
        // On the sphere every vertex sees the same kernels turned, and summed over its views stage 2 does not
        // lower the held-out error (the per-view gate keeps it in some views): no vertex keeps it.
        if (lobes == 2) {
            EXPECT_EQ(keeping > 0, nested.keptStage[1] > 0);
            EXPECT_GT(dropping, 0u);
        }
        const auto &fewer = costs[size_t(lobes) - 2], &more = costs[size_t(lobes) - 1];
        for (size_t v = 0; v < sphere.vertexCount(); ++v) {
            double before = 0, after = 0;
            for (int view = 0; view < kViewCount; ++view) {
                size_t p = v * kViewCount + size_t(view);
                if (fewer[p] >= 0) before += fewer[p], after += more[p];
            }
            EXPECT_LE(after, before * (1 + 1e-4) + 1e-12) << "vertex " << v << ", " << lobes << " lobes";
        }
    }
}

// The max-norm and lighting-aware scores through the nested fit: recomputed from the output, each view's score
// never rises with stage 2, and the gate keeps some views' stage 2 and drops others'.
TEST(GlossyNested, MaxNormAndLightingScoresNeverRiseWithTheLobeCount) {
    prt::TriMesh sphere = prt::makeSphere(1.0f, 5, 8);
    GlossyOptions options = nestedSphereOptions();
    const DirectionGrid held = heldOutGrid(heldOutResolution(options));
    for (int score = 0; score < 2; ++score) {
        options.nestedMaxNorm = score == 0;
        options.nestedLighting.clear();
        if (score == 1) // two lightings: uniform, and the upper half twice as bright
            for (int row = 0; row < 2; ++row)
                for (size_t i = 0; i < held.count(); ++i)
                    options.nestedLighting.push_back(held.solidAngle[i] * (row == 0 ? 1.0f : held.directions[i * 3 + 1] > 0 ? 2.0f : 0.0f));
        std::vector<std::vector<double>> costs;
        for (int lobes = 1; lobes <= 2; ++lobes) {
            options.lobes = lobes;
            GlossyLobes nested = computeGlossyLobes(sphere, options);
            if (lobes == 2) {
                EXPECT_GT(nested.keptStage[1], 0u) << score;
                EXPECT_LT(nested.keptStage[1], nested.stats.problems) << score;
            }
            costs.push_back(sphereHeldOutCosts(sphere, options, nested));
        }
        for (size_t p = 0; p < costs[0].size(); ++p)
            if (costs[0][p] >= 0) {
                EXPECT_LE(costs[1][p], costs[0][p] * (1 + 1e-3) + 1e-9) << "score " << score << ", " << p;
            }
    }
}

} // namespace
