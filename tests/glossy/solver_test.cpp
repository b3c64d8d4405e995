// The two solvers against each other and against finite differences: the analytic Jacobian of every term of the
// objective (data, plain and one-sided, gauge, mean and width coherence, no-flip) against central differences, the
// OpenCL kernel's own normal equations against the host's (also with sharp lobes, where the kernel skips
// negligible directions), and
// 2- and 3-lobe problems, with and without priors, solved by both to the same cost within 1%.
#include "glossy.h"
#include "glossy_internal.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace prt::glossy;

// A glossy kernel with a shadow: the Phong lobe toward `view` at normal `normal`, with every grid direction on the
// far side of the plane through the origin with normal `cut` blocked (a wall across part of the lobe).
std::vector<float> shadowedKernel(const DirectionGrid& grid, const float normal[3], const float view[3],
                                  const float cut[3], double exponent) {
    std::vector<uint8_t> visible(grid.count());
    for (size_t i = 0; i < grid.count(); ++i) {
        const float* w = &grid.directions[i * 3];
        visible[i] = w[0] * cut[0] + w[1] * cut[1] + w[2] * cut[2] > 0.0f;
    }
    std::vector<float> kernel(grid.count());
    tabulateKernel(grid, normal, view, Phong{exponent, 0.5}, visible.data(), kernel.data());
    return kernel;
}

void normalise(float v[3]) {
    float l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int c = 0; c < 3; ++c) v[c] /= l;
}

// `count` problems with `lobes` lobes: shadowed kernels of varied views and walls, started from initialise().
FitBatch shadowedBatch(const DirectionGrid& grid, int lobes, size_t count, double exponent) {
    FitBatch batch;
    batch.lobes = lobes;
    batch.problems = count;
    const int width = lobes * kLobeParams;
    const float normal[3] = {0.0f, 1.0f, 0.0f};
    for (size_t p = 0; p < count; ++p) {
        double t = double(p) / double(count);
        float view[3] = {float(0.7 * std::cos(6.3 * t)), 1.0f, float(0.7 * std::sin(6.3 * t))};
        float cut[3] = {float(std::cos(2.0 + 11.0 * t)), float(0.3 - 0.6 * t), float(std::sin(2.0 + 11.0 * t))};
        normalise(view), normalise(cut);
        std::vector<float> kernel = shadowedKernel(grid, normal, view, cut, exponent);
        batch.kernel.insert(batch.kernel.end(), kernel.begin(), kernel.end());
        batch.amplitudeMax.push_back(4.0f * *std::max_element(kernel.begin(), kernel.end()));
        batch.params.resize((p + 1) * width);
        initialise(grid, kernel.data(), lobes, exponent, FitBounds{}, &batch.params[p * width]);
    }
    return batch;
}

// Priors that pull every lobe's mean toward the next lobe's start (so lobe pairs are crossed against their priors
// and the no-flip term is active) and its log sharpness half a unit up.
void crossedPriors(FitBatch& batch) {
    const int lobes = batch.lobes, width = lobes * kLobeParams;
    batch.prior.assign(batch.problems * lobes * 4, 0.0f);
    batch.hasPrior.assign(batch.problems, 1);
    for (size_t p = 0; p < batch.problems; ++p)
        for (int k = 0; k < lobes; ++k) {
            const float* from = &batch.params[p * width + ((k + 1) % lobes) * kLobeParams];
            float mean[3] = {from[1], from[2], from[3]};
            mean[0] += 0.2f; // not exactly another lobe's start
            normalise(mean);
            float* prior = &batch.prior[(p * lobes + k) * 4];
            std::copy_n(mean, 3, prior);
            prior[3] = batch.params[p * width + k * kLobeParams + 4] + 0.5f;
        }
}

// With overshoot > 0 the data rows of directions where the model lies above the kernel carry sqrt(1 + rho): the
// test point has rows on both sides, and no data residual within the difference step of its kink at zero.
void expectJacobianMatchesFiniteDifferences(double overshoot) {
    const DirectionGrid grid = cubeGrid(6);
    const int lobes = 3, width = lobes * kLobeParams;
    FitBatch batch = shadowedBatch(grid, lobes, 1, 16.0);
    crossedPriors(batch);
    // A point off the start: means not unit (the gauge term is nonzero), amplitudes and widths moved.
    std::vector<double> x(batch.params.begin(), batch.params.end());
    for (int k = 0; k < lobes; ++k) {
        // One-sided: lower amplitudes, so that the model lies under the kernel near its peak and above it elsewhere.
        x[k * kLobeParams] = (overshoot > 0 ? 0.1 : 0.5) * batch.amplitudeMax[0] / (k + 1.0);
        x[k * kLobeParams + 1] *= 1.1, x[k * kLobeParams + 2] *= 0.95, x[k * kLobeParams + 3] += 0.05;
        x[k * kLobeParams + 4] -= 0.3 * k;
    }
    const FitWeights weights{0.2, 0.3, 0.5, overshoot};
    ProblemView view = problemView(grid, batch, 0);
    const int rows = residualCount(grid.count(), lobes);
    std::vector<double> r(rows), jacobian(size_t(rows) * width), plus(rows), minus(rows);
    evaluateResiduals(grid, view, weights, x.data(), r.data(), jacobian.data());
    // Row blocks: data, gauge, mean, width, no-flip.
    const int count = int(grid.count());
    const int blocks[6] = {0, count, count + lobes, count + 4 * lobes, count + 5 * lobes, rows};
    double blockNorm[5] = {}, blockError[5] = {};
    int crossings = 0; // data rows whose side of the kernel a difference step changes
    for (int j = 0; j < width; ++j) {
        const double h = 1e-6 * std::max(1.0, std::abs(x[j]));
        std::vector<double> y = x;
        y[j] = x[j] + h;
        evaluateResiduals(grid, view, weights, y.data(), plus.data(), nullptr);
        y[j] = x[j] - h;
        evaluateResiduals(grid, view, weights, y.data(), minus.data(), nullptr);
        for (int i = 0; i < count; ++i) crossings += (plus[i] > 0) != (r[i] > 0) || (minus[i] > 0) != (r[i] > 0);
        for (int b = 0; b < 5; ++b)
            for (int i = blocks[b]; i < blocks[b + 1]; ++i) {
                double numeric = (plus[i] - minus[i]) / (2 * h), analytic = jacobian[size_t(i) * width + j];
                if (b == 4 && r[i] == 0.0) { // an inactive pair: zero slope (its kink may lie within h)
                    EXPECT_EQ(analytic, 0.0);
                    continue;
                }
                blockNorm[b] = std::max(blockNorm[b], std::abs(analytic));
                blockError[b] = std::max(blockError[b], std::abs(numeric - analytic));
            }
    }
    const char* names[5] = {"data", "gauge", "mean", "width", "no-flip"};
    for (int b = 0; b < 5; ++b) {
        EXPECT_GT(blockNorm[b], 0.0) << names[b] << " is not exercised";
        EXPECT_LT(blockError[b], 1e-6 * blockNorm[b]) << names[b];
    }
    // Some lobe pair is crossed against its priors, so the no-flip term has a residual.
    EXPECT_GT(*std::max_element(r.begin() + blocks[4], r.end()), 0.0);
    if (overshoot > 0) {
        // Data rows above and below the kernel, none crossing the kink within a difference step.
        int above = 0, below = 0;
        for (int i = 0; i < count; ++i) above += r[i] > 0, below += r[i] < 0;
        EXPECT_EQ(crossings, 0);
        EXPECT_GT(above, 10);
        EXPECT_GT(below, 10);
        // The one-sided weight acts: an above-kernel row is sqrt(1 + rho) times the plain residual.
        std::vector<double> plain(rows);
        evaluateResiduals(grid, view, FitWeights{0.2, 0.3, 0.5}, x.data(), plain.data(), nullptr);
        for (int i = 0; i < count; ++i)
            EXPECT_NEAR(r[i], plain[i] * (plain[i] > 0 ? std::sqrt(1 + overshoot) : 1.0), 1e-12 * std::abs(r[i])) << i;
    }
}

TEST(GlossySolvers, AnalyticJacobianMatchesFiniteDifferencesForEveryTerm) {
    expectJacobianMatchesFiniteDifferences(0.0);
}

TEST(GlossySolvers, OneSidedDataWeightHasItsJacobianOnBothSidesOfTheKernel) {
    expectJacobianMatchesFiniteDifferences(50.0);
}

// The kernel's normal equations of one problem ([cost, J^T r (width), J^T J (width^2)]) against the host's double
// residuals and Jacobian at x: the cost within costTolerance relative, J^T r and J^T J within 1e-9 of their scale.
void expectNormalsMatchHost(const DirectionGrid& grid, const ProblemView& view, const FitWeights& weights,
                            const std::vector<double>& x, const double* kernel, double costTolerance) {
    const int width = int(x.size()), rows = residualCount(grid.count(), width / kLobeParams);
    std::vector<double> r(rows), jacobian(size_t(rows) * width);
    evaluateResiduals(grid, view, weights, x.data(), r.data(), jacobian.data());
    double cost = 0.0, scale = 0.0;
    for (double v : r) cost += v * v;
    EXPECT_NEAR(kernel[0], cost, costTolerance * cost);
    std::vector<double> g(width, 0.0), jtj(size_t(width) * width, 0.0);
    for (int i = 0; i < rows; ++i)
        for (int a = 0; a < width; ++a) {
            g[a] += jacobian[size_t(i) * width + a] * r[i];
            for (int b = 0; b < width; ++b)
                jtj[size_t(a) * width + b] += jacobian[size_t(i) * width + a] * jacobian[size_t(i) * width + b];
        }
    for (double v : jtj) scale = std::max(scale, std::abs(v));
    for (int a = 0; a < width; ++a) EXPECT_NEAR(kernel[1 + a], g[a], 1e-9 * std::sqrt(scale * cost)) << a;
    for (int a = 0; a < width * width; ++a) EXPECT_NEAR(kernel[1 + width + a], jtj[a], 1e-9 * scale) << a;
}

TEST(GlossySolvers, KernelNormalEquationsMatchTheHostJacobian) {
    const DirectionGrid grid = cubeGrid(6);
    for (int lobes : {1, 2, 3}) {
        const int width = lobes * kLobeParams;
        FitBatch batch = shadowedBatch(grid, lobes, 5, 16.0);
        crossedPriors(batch);
        batch.hasPrior[1] = 0; // one problem without a prior
        for (size_t i = 1; i < batch.params.size(); i += kLobeParams) batch.params[i] *= 1.05f; // gauge active
        for (double overshoot : {0.0, 30.0}) { // the plain data term, and one-sided (the kernel's select)
            const FitWeights weights{0.2, 0.3, 0.5, overshoot};
            std::vector<double> normals = openClNormalEquations(grid, batch, weights, FitBounds{});
            ASSERT_EQ(normals.size(), batch.problems * size_t(1 + width + width * width));
            for (size_t p = 0; p < batch.problems; ++p) {
                ProblemView view = problemView(grid, batch, p);
                std::vector<double> x(batch.params.begin() + p * width, batch.params.begin() + (p + 1) * width);
                SCOPED_TRACE(std::to_string(lobes) + " lobes, problem " + std::to_string(p) + ", overshoot " +
                             std::to_string(overshoot));
                expectNormalsMatchHost(grid, view, weights, x, &normals[p * (1 + width + width * width)], 1e-9);
            }
        }
    }
}

// The residuals of problem p of `batch` at its params, in double.
std::vector<double> problemResiduals(const DirectionGrid& grid, const FitBatch& batch, size_t p,
                                     const FitWeights& weights) {
    const size_t width = size_t(batch.lobes) * kLobeParams;
    std::vector<double> x(&batch.params[p * width], &batch.params[p * width] + width);
    std::vector<double> r(residualCount(grid.count(), batch.lobes));
    evaluateResiduals(grid, problemView(grid, batch, p), weights, x.data(), r.data(), nullptr);
    return r;
}

// Both solvers from one start reach the same cost within 1% on every problem (or both lie at the float floor,
// 1e-7 of the problem's energy), without priors and with crossed priors, and each reports its own objective.
void expectSameCosts(const DirectionGrid& grid, const FitBatch& start, const FitWeights& weights) {
    FitBatch opencl = start, ceres = start;
    solveOpenCl(grid, opencl, weights, FitBounds{}, SolverOptions{});
    solveCeres(grid, ceres, weights, FitBounds{}, SolverOptions{});
    const int width = start.lobes * kLobeParams;
    double openClTotal = 0.0, ceresTotal = 0.0, initialTotal = 0.0;
    for (size_t p = 0; p < start.problems; ++p) {
        double energy = dataEnergy(grid, &start.kernel[p * grid.count()]);
        double floor = 1e-7 * energy;
        EXPECT_NEAR(opencl.cost[p], ceres.cost[p], 0.01 * ceres.cost[p] + floor) << start.lobes << " lobes, problem " << p;
        // The reported costs are each solver's own objective at its end point (double), which the float
        // parameters it returns reproduce up to their rounding.
        double again = objective(grid, opencl, p, weights, FitBounds{}, &opencl.params[p * width]);
        EXPECT_NEAR(opencl.cost[p], again, 1e-4 * again + floor) << p;
        openClTotal += opencl.cost[p], ceresTotal += ceres.cost[p];
        initialTotal += objective(grid, start, p, weights, FitBounds{}, &start.params[p * width]);
    }
    EXPECT_LE(openClTotal, 1.001 * ceresTotal);
    EXPECT_LT(ceresTotal, 0.8 * initialTotal); // the fits did something
}

// The share of the kernel's 8-direction chunks (grid order, the last one padded) in which lobe k of x lies below
// lm_kernel.cl's cutoff, lambda (cos - 1) < -50, in every direction: the chunks the kernel takes as zero.
double cutChunkShare(const DirectionGrid& grid, const float* x, int lobes) {
    size_t cut = 0, chunks = 0;
    for (int k = 0; k < lobes; ++k) {
        const float* q = x + k * kLobeParams;
        double length = std::sqrt(double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
        for (size_t i0 = 0; i0 < grid.count(); i0 += 8, ++chunks) {
            bool below = true;
            for (size_t i = i0; i < std::min(i0 + 8, grid.count()); ++i) {
                const float* w = &grid.directions[i * 3];
                double cosine = (q[1] * w[0] + q[2] * w[1] + q[3] * w[2]) / length;
                below = below && std::exp(double(q[4])) * (cosine - 1.0) < -50.0;
            }
            cut += below;
        }
    }
    return double(cut) / double(chunks);
}

// Sharp lobes, where the kernel skips most of the grid (lobe values below e^-50 = 2e-22 of the amplitude): its
// cost, J^T r and J^T J still match the host's full double sums, and both solvers still agree. Grid 16 lies
// wholly in the kernel's cache of lobe values (192 x 8 directions), grid 24 mostly past it (values recomputed).
void expectSharpLobesMatch(int resolution) {
    const DirectionGrid grid = cubeGrid(resolution);
    const int lobes = 2, width = lobes * kLobeParams;
    FitBatch all = shadowedBatch(grid, lobes, 12, 256.0), batch = all;
    batch.problems = 0, batch.kernel.clear(), batch.amplitudeMax.clear(), batch.params.clear();
    for (size_t p = 0; p < all.problems; ++p) { // the problems whose lobe the wall leaves lit (energy >= 1e-3)
        if (dataEnergy(grid, &all.kernel[p * grid.count()]) < 1e-3) continue;
        ++batch.problems;
        batch.kernel.insert(batch.kernel.end(), &all.kernel[p * grid.count()], &all.kernel[(p + 1) * grid.count()]);
        batch.amplitudeMax.push_back(all.amplitudeMax[p]);
        batch.params.insert(batch.params.end(), &all.params[p * width], &all.params[(p + 1) * width]);
    }
    ASSERT_GE(batch.problems, 6u);
    for (size_t p = 0; p < batch.problems; ++p)
        EXPECT_GT(cutChunkShare(grid, &batch.params[p * width], lobes), 0.5) << p; // the cutoff is exercised
    std::vector<double> normals = openClNormalEquations(grid, batch, FitWeights{}, FitBounds{});
    for (size_t p = 0; p < batch.problems; ++p) {
        ProblemView view = problemView(grid, batch, p);
        std::vector<double> x(batch.params.begin() + p * width, batch.params.begin() + (p + 1) * width);
        SCOPED_TRACE("problem " + std::to_string(p));
        expectNormalsMatchHost(grid, view, FitWeights{}, x, &normals[p * (1 + width + width * width)], 1e-12);
    }
    expectSameCosts(grid, batch, FitWeights{});
}

TEST(GlossySolvers, SharpLobesSkipOnlyNegligibleDirections) {
    for (int resolution : {16, 24}) {
        SCOPED_TRACE(resolution);
        expectSharpLobesMatch(resolution);
    }
}

TEST(GlossySolvers, TwoAndThreeLobeProblemsReachTheSameCostWithBothSolvers) {
    const DirectionGrid grid = cubeGrid(8);
    for (int lobes : {2, 3}) {
        FitBatch batch = shadowedBatch(grid, lobes, 24, 32.0);
        expectSameCosts(grid, batch, FitWeights{});
    }
}

// The fit from below's objective (GlossyOptions::fromBelow: one lobe at a time, rho 100) and a milder rho at two
// lobes: both solvers reach the same cost, and the one-sided fits end with less of the kernel overshot than the
// plain ones.
TEST(GlossySolvers, OneSidedProblemsReachTheSameCostWithBothSolvers) {
    const DirectionGrid grid = cubeGrid(8);
    for (auto [lobes, overshoot] : {std::pair{1, 100.0}, std::pair{2, 3.0}}) {
        SCOPED_TRACE(std::to_string(lobes) + " lobes, overshoot " + std::to_string(overshoot));
        FitBatch batch = shadowedBatch(grid, lobes, 24, 32.0);
        expectSameCosts(grid, batch, FitWeights{0.0, 0.0, 0.0, overshoot});
        FitBatch plain = batch, below = batch;
        solveOpenCl(grid, plain, FitWeights{}, FitBounds{}, SolverOptions{});
        solveOpenCl(grid, below, FitWeights{0.0, 0.0, 0.0, overshoot}, FitBounds{}, SolverOptions{});
        auto overshot = [&](const FitBatch& fit) { // sum over problems of sum_i dw_i max(0, F_i - T_i)^2
            double sum = 0.0;
            for (size_t p = 0; p < fit.problems; ++p) {
                const std::vector<double> r = problemResiduals(grid, fit, p, FitWeights{});
                for (size_t i = 0; i < grid.count(); ++i) sum += r[i] > 0 ? r[i] * r[i] : 0.0;
            }
            return sum;
        };
        EXPECT_LT(overshot(below), (lobes == 1 ? 0.05 : 0.5) * overshot(plain));
    }
}

TEST(GlossySolvers, PriorAndNoFlipTermsSolvedAlikeByBothSolvers) {
    const DirectionGrid grid = cubeGrid(8);
    for (int lobes : {2, 3}) {
        FitBatch batch = shadowedBatch(grid, lobes, 16, 32.0);
        crossedPriors(batch);
        const FitWeights weights{0.01, 0.01, 0.05};
        // The terms are live: the no-flip term has a residual at the start of some problem, and at the fitted
        // point the prior terms carry a share of the objective.
        double startFlip = 0.0;
        for (size_t p = 0; p < batch.problems; ++p) {
            const std::vector<double> r = problemResiduals(grid, batch, p, weights);
            for (size_t i = grid.count() + 5 * lobes; i < r.size(); ++i) startFlip = std::max(startFlip, r[i]);
        }
        EXPECT_GT(startFlip, 0.0);
        FitBatch pulled = batch;
        solveCeres(grid, pulled, weights, FitBounds{}, SolverOptions{});
        double total = 0.0, priorPart = 0.0;
        for (size_t p = 0; p < batch.problems; ++p) {
            const float* x = &pulled.params[p * lobes * kLobeParams];
            double all = objective(grid, pulled, p, weights, FitBounds{}, x);
            total += all, priorPart += all - objective(grid, pulled, p, FitWeights{}, FitBounds{}, x);
        }
        EXPECT_GT(priorPart, 0.01 * total);
        expectSameCosts(grid, batch, weights);
    }
}

} // namespace
