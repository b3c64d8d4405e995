// The reference solver: one Ceres problem per fit, the objective of glossy.h with its analytic Jacobian, Ceres's
// Levenberg-Marquardt with dense QR, bounds on amplitude and log sharpness.
#include "glossy.h"
#include "glossy_internal.h"

#include "core.h"

#include <ceres/ceres.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cmath>

namespace prt::glossy {

namespace {

class FitCost : public ceres::CostFunction {
public:
    FitCost(const DirectionGrid& grid, const ProblemView& problem, const FitWeights& weights)
        : grid_(grid), problem_(problem), weights_(weights) {
        set_num_residuals(residualCount(grid.count(), problem.lobes));
        mutable_parameter_block_sizes()->push_back(problem.lobes * kLobeParams);
    }
    bool Evaluate(const double* const* parameters, double* residuals, double** jacobians) const override {
        evaluateResiduals(grid_, problem_, weights_, parameters[0], residuals, jacobians ? jacobians[0] : nullptr);
        return true;
    }

private:
    const DirectionGrid& grid_;
    ProblemView problem_;
    FitWeights weights_;
};

} // namespace

void solveCeres(const DirectionGrid& grid, FitBatch& batch, const FitWeights& weights, const FitBounds& bounds,
                const SolverOptions& options) {
    const int width = batch.lobes * kLobeParams;
    batch.cost.assign(batch.problems, 0.0f);
    batch.iterations.assign(batch.problems, 0);
    auto solveOne = [&](size_t p) {
        ProblemView view = problemView(grid, batch, p);
        std::vector<double> x(batch.params.begin() + p * width, batch.params.begin() + (p + 1) * width);
        ceres::Problem::Options problemOptions;
        problemOptions.cost_function_ownership = ceres::TAKE_OWNERSHIP;
        ceres::Problem problem(problemOptions);
        problem.AddResidualBlock(new FitCost(grid, view, weights), nullptr, x.data());
        for (int k = 0; k < batch.lobes; ++k) {
            problem.SetParameterLowerBound(x.data(), k * kLobeParams, 0.0);
            problem.SetParameterUpperBound(x.data(), k * kLobeParams, view.amplitudeMax);
            problem.SetParameterLowerBound(x.data(), k * kLobeParams + 4, std::log(bounds.lambdaMin));
            problem.SetParameterUpperBound(x.data(), k * kLobeParams + 4, std::log(bounds.lambdaMax));
        }
        ceres::Solver::Options solverOptions;
        solverOptions.linear_solver_type = ceres::DENSE_QR;
        solverOptions.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
        solverOptions.max_num_iterations = options.maxIterations;
        solverOptions.function_tolerance = options.functionTolerance;
        solverOptions.gradient_tolerance = options.gradientTolerance;
        solverOptions.parameter_tolerance = options.parameterTolerance;
        // No projected line search along the LM step (Ceres's own TODO calls it "not terribly effective"): plain
        // projected LM, the rules lm_kernel.cl follows, so both solvers take the same steps from one start.
        solverOptions.max_num_line_search_step_size_iterations = 0;
        solverOptions.num_threads = 1;
        solverOptions.logging_type = ceres::SILENT;
        ceres::Solver::Summary summary;
        ceres::Solve(solverOptions, &problem, &summary);
        for (int i = 0; i < width; ++i) batch.params[p * width + i] = float(x[i]);
        batch.cost[p] = float(2.0 * summary.final_cost); // Ceres's own cost at its end point: half the objective
        batch.iterations[p] = int(summary.iterations.size()) - 1; // iteration 0 is the start
    };
    tbb::task_arena arena(arenaConcurrency(options.threads));
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, batch.problems, 4), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t p = r.begin(); p < r.end(); ++p) solveOne(p);
        });
    });
}

} // namespace prt::glossy
