// Internal to prt_glossy: one problem's view of a batch, and the residuals both solvers share.
#pragma once

#include "glossy.h"

namespace prt::glossy {

struct ProblemView {
    int lobes = 1;
    const float* kernel = nullptr; // [grid.count()]
    double energy = 0.0;           // dataEnergy
    double amplitudeMax = 0.0;
    const float* prior = nullptr;  // [lobes][4] or null
};

ProblemView problemView(const DirectionGrid& grid, const FitBatch& batch, size_t p);

// Residuals of the objective in glossy.h: grid.count() data, lobes gauge, 3 lobes mean, lobes width and
// lobes (lobes - 1) / 2 no-flip (zero without a prior), in that order.
int residualCount(size_t gridCount, int lobes);

// Fills residuals[residualCount] and, when not null, jacobian[residualCount][lobes * kLobeParams] (row-major).
void evaluateResiduals(const DirectionGrid& grid, const ProblemView& problem, const FitWeights& weights,
                       const double* params, double* residuals, double* jacobian);

// The OpenCL kernel's own normal equations at batch.params (projected onto the bounds), for the tests: per
// problem 1 + w + w^2 doubles (w = lobes * kLobeParams): the objective, g = J^T r, then J^T J row-major.
std::vector<double> openClNormalEquations(const DirectionGrid& grid, const FitBatch& batch, const FitWeights& weights,
                                          const FitBounds& bounds);

} // namespace prt::glossy
