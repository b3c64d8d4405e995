// The solver comparison: the same fit problems (the first views of a mesh's first vertices, as the stage
// builds them) solved by the OpenCL batch and by Ceres, timed in steady state.
#include "glossy.h"

#include "core.h"
#include "raycast.h"

#include <algorithm>
#include <cmath>

#include <sys/resource.h>

namespace prt::glossy {

// compute.cpp: the mesh's first `problems` fit problems (vertex by vertex, view by view), and the rays that tabulated
// their radiance.
FitBatch stageProblems(const TriMesh& mesh, const GlossyOptions& options, size_t problems, uint64_t& rays);

namespace {

// User plus system CPU time of the whole process (every thread, PoCL's device threads included), in seconds.
// On a shared machine it moves less with the load than the wall clock.
double processCpuSeconds() {
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
           1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

} // namespace

SolverComparison compareSolvers(const TriMesh& mesh, const GlossyOptions& options, size_t problems) {
    const DirectionGrid grid = cubeGrid(options.gridResolution);
    SolverComparison result;
    FitBatch start = stageProblems(mesh, options, problems, result.rays);
    result.problems = start.problems;
    const int width = start.lobes * kLobeParams;
    // Warm-up: compiles (or loads from PoCL's cache) the kernel, outside the timing.
    FitBatch warm = start;
    warm.problems = std::min<size_t>(warm.problems, 16);
    solveOpenCl(grid, warm, FitWeights{}, options.bounds, options.solverOptions);
    FitBatch opencl = start, ceres = start;
    double t0 = nowSeconds(), c0 = processCpuSeconds();
    solveOpenCl(grid, opencl, FitWeights{}, options.bounds, options.solverOptions);
    double t1 = nowSeconds(), c1 = processCpuSeconds();
    solveCeres(grid, ceres, FitWeights{}, options.bounds, options.solverOptions);
    double t2 = nowSeconds(), c2 = processCpuSeconds();
    result.openClSeconds = t1 - t0;
    result.ceresSeconds = t2 - t1;
    result.openClCpuSeconds = c1 - c0;
    result.ceresCpuSeconds = c2 - c1;
    size_t within = 0, agreeing = 0;
    double openClIterations = 0, ceresIterations = 0;
    for (size_t p = 0; p < start.problems; ++p) {
        double initial = objective(grid, start, p, FitWeights{}, options.bounds, &start.params[p * width]);
        result.initialCost += initial;
        result.openClCost += opencl.cost[p];
        result.ceresCost += ceres.cost[p];
        double energy = dataEnergy(grid, &start.kernel[p * grid.count()]);
        // Within 1% of Ceres's cost, or both at the float noise floor of the problem's energy.
        if (opencl.cost[p] <= 1.01 * ceres.cost[p] || opencl.cost[p] <= 1e-7 * energy) ++within;
        if (std::abs(opencl.cost[p] - ceres.cost[p]) <= 0.01 * ceres.cost[p] + 1e-7 * energy) ++agreeing;
        openClIterations += opencl.iterations[p];
        ceresIterations += ceres.iterations[p];
        result.openClCosts.push_back(opencl.cost[p]);
        result.ceresCosts.push_back(ceres.cost[p]);
    }
    result.shareWithinOnePercent = start.problems ? double(within) / double(start.problems) : 0.0;
    result.shareAgreeing = start.problems ? double(agreeing) / double(start.problems) : 0.0;
    result.openClMeanIterations = start.problems ? openClIterations / double(start.problems) : 0.0;
    result.ceresMeanIterations = start.problems ? ceresIterations / double(start.problems) : 0.0;
    return result;
}

} // namespace prt::glossy
