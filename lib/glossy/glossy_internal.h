// Internal to prt_glossy: one problem's view of a batch, the residuals both solvers share, and the per-chunk fit's
// pieces that the fits adding lobes one at a time (warm start, nested, from below) build on.
#pragma once

#include "glossy.h"

#include <array>
#include <vector>

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

// ---- The per-chunk fit (compute.cpp), shared with the fits that add lobes one at a time ----

// One chunk's problems: kernels of every view above each vertex's horizon with a nonzero kernel, started from
// the shared initialisation. slot[i][view] is the problem's index among vertex i's, or -1.
struct Chunk {
    FitBatch batch;
    std::vector<std::vector<int>> slot;
    std::vector<size_t> first; // [chunk + 1]: vertex i's problems are first[i] .. first[i + 1]
    std::vector<std::array<float, 3>> normals;
    std::vector<float> visibleShare; // [chunk]: visible solid angle over the upper hemisphere's
    std::vector<float> heldKernel;   // [problems][heldOut.count()] in batch order, nested fits only
};

// Solver form (a, m, log lambda) of `lobes` lobes to output form (a, unit mu, lambda), and back.
void toOutput(const float* solver, float* out, int lobes);
void toSolver(const float* out, float* solver, int lobes);

// Fits batch from batch.params with options.solver under weights and options.bounds; nothing for no problems.
void solve(const DirectionGrid& grid, FitBatch& batch, const FitWeights& weights, const GlossyOptions& options);

// The fit after pass 1 (batch.params hold its result, solver form): with `coherence`, lobe order aligned across
// each vertex's views, priors from the aligned neighbours, and pass 2 from there. Returns the output form
// [problems][batch.lobes * kLobeParams]; batch.params, cost and iterations hold the final fit.
std::vector<float> coherencePass(const DirectionGrid& grid, Chunk& tabulated, const GlossyOptions& options,
                                 bool coherence);

// The independent pass with a warm start (warm_start.cpp, GlossyOptions::warmStart): fits of 1, 2, ...,
// batch.lobes lobes, each from the previous fit plus one greedy lobe (initialiseFrom); where a fit ends above the
// previous fit's cost, the previous fit plus a zero-amplitude lobe is kept. Leaves batch.params, cost and
// iterations as solve() does.
void warmStartFit(const DirectionGrid& grid, FitBatch& batch, const GlossyOptions& options);

// The nested fit of one chunk (nested_fit.cpp, GlossyOptions::nested): stages 1..lobes, stage k from stage
// k - 1's kept fit plus one greedy lobe on its residual (initialiseFrom), pass 1 and the coherence pass as the
// plain fit; a problem keeps stage k where keepStage says (its held-out data cost, dataCost on `heldOut`,
// tabulated.heldKernel, against stage k - 1's: by options.nestedMargin, per view or per vertex), else stage
// k - 1's lobes and a zero lobe (amplitude 0, along the first lobe, the exponent's sharpness). Returns the output
// form as coherencePass; heldCost[p] is the kept fit's held-out data cost; keptStage[k - 1] counts the problems
// that kept stage k.
std::vector<float> nestedFit(const DirectionGrid& grid, const DirectionGrid& heldOut, Chunk& tabulated,
                             const GlossyOptions& options, bool coherence, std::vector<double>& heldCost,
                             std::vector<uint64_t>& keptStage);

// The fit from below of one chunk (from_below.cpp, GlossyOptions::fromBelow): for k = 1..lobes a 1-lobe batch on
// the residual kernel (the kernel minus lobes < k, on the grid), started by the shared greedy start, pass 1 and
// the coherence pass with the one-sided data weight and sharpness at most fromBelowSharpnessMax; lobe k is then
// subtracted from the residual. Returns the output form as coherencePass does (lobe k of problem p at
// (p lobes + k) kLobeParams); leaves batch with the whole kernel, the solver-form lobes, and as cost the plain
// data cost (dataCost) of all lobes on the grid.
std::vector<float> fromBelowFit(const DirectionGrid& grid, Chunk& tabulated, const GlossyOptions& options,
                                bool coherence);

// The nested fit's keep decision of stage k (nested_fit.cpp): keep[p] = 1 for every p at k = 1; else, per problem,
// held[p] < (1 - options.nestedMargin) previous[p], or with options.nestedPerVertex the same test on the sums over
// each vertex's problems first[i] .. first[i + 1] (first.back() == held.size()), applied to all of them.
std::vector<uint8_t> keepStage(const std::vector<size_t>& first, const std::vector<double>& held,
                               const std::vector<double>& previous, int k, const GlossyOptions& options);

// Counts the lobe-order flips of result (flips.cpp) into result.stats: viewPairs / viewFlips over neighbouring
// views of each vertex, vertexPairs / vertexFlips over the edges of mesh inside [vertexBegin, vertexEnd) at each
// view. Needs result.values for its vertex range; does nothing below 2 lobes.
void countFlips(const TriMesh& mesh, GlossyLobes& result);

} // namespace prt::glossy
