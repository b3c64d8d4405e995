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

// The relit error of lobes `params` (solver form, as dataCost) summed over lightings: sum over rows r of
// (sum_i lighting[r][i] (model_i - kernel_i))^2, with lighting [rows][grid.count()] radiance x solid angle at
// grid's directions (GlossyOptions::nestedLighting). In double; >= 0.
double litCost(const DirectionGrid& grid, const float* kernel, int lobes, const float* params, const float* lighting,
               size_t rows);

// The largest |model_i - kernel_i| over grid's directions (the relit error's bound under one small source of unit
// irradiance, GlossyOptions::nestedMaxNorm), in double; >= 0.
double maxResidual(const DirectionGrid& grid, const float* kernel, int lobes, const float* params);

// The nested fit's keep decision of stage k (compute.cpp): keep[p] = 1 for every p at k = 1; else, per problem,
// held[p] < (1 - options.nestedMargin) previous[p], or with options.nestedPerVertex the same test on the sums over
// each vertex's problems first[i] .. first[i + 1] (first.back() == held.size()), applied to all of them.
std::vector<uint8_t> keepStage(const std::vector<size_t>& first, const std::vector<double>& held,
                               const std::vector<double>& previous, int k, const GlossyOptions& options);

// Counts the lobe-order flips of result (flips.cpp) into result.stats: viewPairs / viewFlips over neighbouring
// views of each vertex, vertexPairs / vertexFlips over the edges of mesh inside [vertexBegin, vertexEnd) at each
// view. Needs result.values for its vertex range; does nothing below 2 lobes.
void countFlips(const TriMesh& mesh, GlossyLobes& result);

} // namespace prt::glossy
