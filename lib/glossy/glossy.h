// Glossy view-dependent transfer (Green 2005): per vertex and per view of a fixed global view set, the glossy
// kernel T(wi) = f_phong V cos (docs/conventions.md, "Glossy BRDF") tabulated on a solid-angle-weighted cube
// grid and replaced by N spherical Gaussians a exp(lambda (mu . w - 1)) (docs/conventions.md, "Spherical
// Gaussians"), fitted by a batched Levenberg-Marquardt in OpenCL kernels (PoCL's CPU device) or, as the
// reference solver, by Ceres on the identical objective. docs/glossy.md records the choices and measurements.
//
// Parameters of one fit problem (one vertex, one view), kLobeParams per lobe, lobe-major:
//   [0] a        amplitude, in [0, amplitudeMax]
//   [1..3] m     unnormalised mean; the model uses mu = m / |m| and a gauge residual keeps |m| near 1
//   [4] s        log sharpness, lambda = exp(s), s in [log lambdaMin, log lambdaMax]
// Objective (sum of squared residuals, E = sum_i dw_i T_i^2 the problem's data energy):
//   data     sqrt(dw_i) (F(w_i) - T_i) o_i                   every grid direction i; o_i = sqrt(1 + rho) where
//                                                            F(w_i) > T_i, else 1 (rho = FitWeights::overshoot)
//   gauge    sqrt(E) (|m_k|^2 - 1)                           every lobe
//   mean     sqrt(beta E) (mu_k - priorMean_k)               3 per lobe, when the problem has a prior
//   width    sqrt(gamma E) (s_k - priorLogSharpness_k)       per lobe, with a prior
//   no-flip  sqrt(delta E) max(0, -(mu_k1 - mu_k2) . (p_k1 - p_k2))^(3/2), k1 < k2, p the prior means
#pragma once

#include "bundle.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {
struct EnvironmentMap; // image.h
}

namespace prt::glossy {

inline constexpr int kLobeParams = 5;
inline constexpr int kMaxLobes = 4;
inline constexpr int kViewCount = 92;

// ---- the view set ------------------------------------------------------------------------------------------
// The frequency-3 geodesic icosahedron: 92 unit directions (12 icosahedron corners, then edge and face points),
// 180 counter-clockwise triangles, each view's 1-ring neighbours. Antipodally symmetric, so every open
// hemisphere not bounded by a view holds exactly 46 views; every direction lies within 13.65 deg of a view.
struct ViewSet {
    std::vector<std::array<float, 3>> directions;  // [92]
    std::vector<std::array<uint32_t, 3>> triangles; // [180]
    std::vector<std::vector<uint32_t>> neighbours;  // [92], 5 or 6 each, ascending
};
const ViewSet& viewSet();

// ---- the direction grid ------------------------------------------------------------------------------------
// A cube grid of 6 x resolution^2 texel centres (a cube strip's, faces +X, -X, +Y, -Y, +Z, -Z as sh::kCubeFaces
// lays them out) with their exact solid angles, summing to 4 pi.
struct DirectionGrid {
    int resolution = 0;
    std::vector<float> directions; // [count][3], unit
    std::vector<float> solidAngle; // [count]
    size_t count() const { return solidAngle.size(); }
};
DirectionGrid cubeGrid(int resolution);

// The held-out directions of the nested fit (GlossyOptions::nested): cubeGrid(resolution) turned by a fixed
// generic rotation (0.5 rad about (1, 2, 3)), so its directions lie mostly between the fit grid's (at the same
// resolution; the stage uses twice it: heldOutResolution); same solid angles.
DirectionGrid heldOutGrid(int resolution);

// ---- the kernel --------------------------------------------------------------------------------------------
struct Phong {
    double exponent = 32.0; // > 0
    double ks = 1.0;        // [0, 1]
};

// T(w_i) for every grid direction at a point with unit shading normal `normal`, seen from unit `outgoing`,
// with visibility[i] (1 visible, 0 blocked; null: all visible). Writes grid.count() values; all zero when
// outgoing is below the surface.
void tabulateKernel(const DirectionGrid& grid, const float normal[3], const float outgoing[3], const Phong& phong,
                    const uint8_t* visibility, float* kernel);

// ---- indirect glossy (optional) -----------------------------------------------------------------------------
// SH basis (order bands, order^2 values) at every grid direction: [count][order^2].
std::vector<float> gridBasis(const DirectionGrid& grid, int order);
// The grey transfer [V][order^2] interpolated at Embree's hit (triangle, u, v) of `mesh`: order^2 values.
void hitTransfer(const TriMesh& mesh, const std::vector<float>& transfer, int order, uint32_t triangle, float u,
                 float v, float* out);
// Adds to `kernel` the indirect glossy kernel of one vertex and view (indirect.cpp): the Phong lobe over the
// directions visibility[i] == 0 blocks, each carrying the diffuse light of its hit point, hitTransfers[i]
// ([count][order^2], zero rows for back-face hits), as a kernel over environment directions, clamped >= 0. Needs
// basis = gridBasis(grid, order). Adds nothing when the lobe reaches no blocked direction.
void addIndirectKernel(const DirectionGrid& grid, const float* basis, int order, const float normal[3],
                       const float outgoing[3], const Phong& phong, const uint8_t* visibility,
                       const float* hitTransfers, float* kernel);

// ---- the fit -----------------------------------------------------------------------------------------------
struct FitWeights {
    double beta = 0.0;  // mean coherence
    double gamma = 0.0; // width coherence
    double delta = 0.0; // no-flip
    // One-sided data weight rho >= 0: a direction where the model lies above the kernel counts 1 + rho times, so a
    // large rho fits from below (GlossyOptions::fromBelow). 0: the plain least-squares data term.
    double overshoot = 0.0;
};

struct FitBounds {
    double lambdaMin = 0.5;
    double lambdaMax = 8192.0;
};

// A batch of independent problems on one grid, lobe count fixed. Arrays are problem-major.
struct FitBatch {
    int lobes = 1;
    size_t problems = 0;
    std::vector<float> kernel;      // [problems][grid.count()]  T_i
    std::vector<float> params;      // [problems][lobes * kLobeParams]: the start on input, the result on output
    std::vector<float> amplitudeMax; // [problems]
    std::vector<float> prior;       // [problems][lobes * 4]: prior mean xyz and log sharpness, or empty
    std::vector<uint8_t> hasPrior;  // [problems], or empty
    std::vector<float> cost;        // [problems], filled by the solvers: final objective
    std::vector<int> iterations;    // [problems], filled by the solvers
};

// Both solvers run Ceres 2.1's trust-region Levenberg-Marquardt rules (Ceres itself with its projected line
// search off; the OpenCL kernel re-implemented in double) and stop on the same three tests.
struct SolverOptions {
    int maxIterations = 100;
    double functionTolerance = 1e-9;  // |cost change| <= this x cost
    double parameterTolerance = 1e-10; // |step| <= this x (|x| + this)
    double gradientTolerance = 1e-14;  // max |x - project(x - J^T r)| <= this
    int threads = 0; // Ceres: worker threads over problems (0 all); PoCL uses its own device threads
};

// Data energy E = sum_i dw_i T_i^2 of problem p.
double dataEnergy(const DirectionGrid& grid, const float* kernel);

// The data term alone, sum_i dw_i (F(w_i) - T_i)^2, of `lobes` lobes in solver form (a, m, log lambda) on any
// direction set with `kernel` tabulated on it (the held-out error of the nested fit), in double.
double dataCost(const DirectionGrid& grid, const float* kernel, int lobes, const float* params);

// The objective above at `params` for problem p of `batch`, in double. Both solvers minimise exactly this.
double objective(const DirectionGrid& grid, const FitBatch& batch, size_t p, const FitWeights& weights,
                 const FitBounds& bounds, const float* params);

// The deterministic start both solvers share: greedy peak picking. Lobe k goes at the brightest grid direction of
// the kernel minus lobes < k, sharpness the Phong exponent (sharper for later lobes), amplitude the residual there.
// Writes lobes * kLobeParams floats.
void initialise(const DirectionGrid& grid, const float* kernel, int lobes, double exponent,
                const FitBounds& bounds, float* params);

// The same greedy start after `given` lobes already in params (solver form, a fit of `given` lobes): lobes
// given..lobes-1 go at the peaks of the kernel minus every earlier lobe. initialise is initialiseFrom(given = 0).
void initialiseFrom(const DirectionGrid& grid, const float* kernel, int given, int lobes, double exponent,
                    const FitBounds& bounds, float* params);

// Batched LM in OpenCL on the first platform's first device (PoCL's CPU device in CI). Kernels compile once per
// process per (lobes, grid size) and are reused. Deterministic: every problem is its own work item in full work
// groups, with contraction off. Throws prt::Error(kExitFailure) when no OpenCL platform exists (naming
// --solver ceres) or a kernel fails to build (with the build log).
void solveOpenCl(const DirectionGrid& grid, FitBatch& batch, const FitWeights& weights, const FitBounds& bounds,
                 const SolverOptions& options);

// The same problems, one Ceres solve each (analytic Jacobian, bounds on a and s), in parallel over problems.
void solveCeres(const DirectionGrid& grid, FitBatch& batch, const FitWeights& weights, const FitBounds& bounds,
                const SolverOptions& options);

// Builds `source` as an OpenCL program on the default device (exposed for the build-failure test). Throws
// prt::Error(kExitFailure) with the build log when it does not compile.
void buildOpenClProgram(const std::string& source, const std::string& buildOptions);

// Human name of the OpenCL device solveOpenCl uses; throws as solveOpenCl does when none exists.
std::string openClDeviceName();

// ---- lobe order --------------------------------------------------------------------------------------------
// Reorders the lobes of `b` (in place) to best match `a`: the permutation minimising the sum of angles between
// means plus |log sharpness difference| over lobes whose amplitudes are both > 0.
void alignLobes(const float* a, float* b, int lobes);
// Whether the lobes of b are flipped against a: some other permutation matches better than the identity by
// more than `margin` (same distance as alignLobes).
bool lobesFlipped(const float* a, const float* b, int lobes, double margin = 0.05);

// ---- the stage ---------------------------------------------------------------------------------------------
enum class Solver { OpenCl, Ceres };
Solver parseSolver(const std::string& name); // "pocl" | "ceres"; throws prt::Error(kExitUsage)

struct GlossyOptions {
    Phong phong;
    int lobes = 1;                // 1..kMaxLobes
    int gridResolution = 16;      // cube face resolution, 2..64
    Solver solver = Solver::OpenCl;
    FitWeights weights{0.001, 0.001, 0.001}; // coherence pass weights (measured, docs/results.md); all zero: no pass
    FitBounds bounds;
    SolverOptions solverOptions;
    size_t chunkVertices = 64;    // vertices tabulated and fitted together; results do not depend on it
    // Warm start: the independent pass fits 1, 2, ..., lobes lobes in turn, each started from the previous fit
    // plus one greedy lobe, and keeps the previous fit (with a zero lobe) where the new one is not better, so the
    // k + 1 lobe fit's cost is never above the k lobe fit's.
    bool warmStart = false;
    // Nested fit (issue 19): stages 1, 2, ..., lobes, each started from the previous stage's result plus one greedy
    // lobe on its residual and fitted as the plain fit is (pass 1, then the coherence pass when it is on); a
    // (vertex, view) keeps stage k's fit only where it lowers the data error on held-out directions
    // (heldOutGrid: the kernel tabulated there too, one ray per held-out direction), else stage k - 1's with a zero
    // lobe. So each view's held-out error never rises with the lobe count, and stage 1 is the plain 1-lobe fit.
    bool nested = false;
    int heldOutResolution = 0; // nested: the held-out grid is heldOutGrid(this), 0: twice gridResolution (max 64)
    // Nested keep criterion: stage k is kept only where its held-out cost is below (1 - nestedMargin) times stage
    // k - 1's (0: any decrease), in [0, 1). nestedPerVertex: one decision per vertex for all its views, by the
    // held-out costs summed over them (so the runtime's blend of neighbouring views never mixes k and k - 1 lobe
    // solutions of one vertex); the per-view bound then holds for the vertex's sum, not for each view.
    double nestedMargin = 0.0;
    bool nestedPerVertex = false;
    // Nested, lighting-aware: non-empty, [rows][heldOutGrid count] radiance x solid angle of training lightings at
    // the held-out directions; the keep criterion is then litCost (the relit error of a distant eye along the
    // view, summed over the rows) in place of the held-out data cost. The reported held-out error stays the L2 one.
    std::vector<float> nestedLighting;
    // Nested: the keep criterion is the largest held-out residual (maxResidual: the error under one small source,
    // such as a sun, in the worst direction) in place of the held-out data cost; not with nestedLighting.
    bool nestedMaxNorm = false;
    // Fit from below (issue 19, "N + 1 lobes never worse than N"): lobes 1, 2, ..., N fitted one at a time, lobe
    // k a 1-lobe fit (pass 1, then the coherence pass) of the kernel minus lobes < k, which stay as they are, with
    // the one-sided data weight FitWeights::overshoot = fromBelowOvershoot, so each lobe lies (nearly) under what
    // is left. Every lobe is >= 0, so the model and any relit radiance never fall as lobes are added; while the
    // model stays under the kernel, the relit error under any lighting >= 0 never grows. Not with nested or
    // warmStart.
    // Its lobes are no sharper than fromBelowSharpnessMax: a lobe narrower than the grid's spacing could sit between
    // its directions, where the one-sided weight does not see it.
    bool fromBelow = false;
    double fromBelowOvershoot = 10.0; // rho of the one-sided data weight, > 0 (chosen on training maps: docs/glossy.md)
    size_t vertexBegin = 0, vertexEnd = SIZE_MAX;
    bool progress = true;
    std::string lobeType = "float16"; // the bundle layer's componentType: "float16" or "float32"
    // Indirect glossy: the grey shadowed diffuse transfer of every vertex, [V][indirectOrder^2], albedo included
    // (lib/transfer). Non-empty: blocked kernel directions carry their hit point's diffuse light (indirect.cpp).
    std::vector<float> indirectTransfer;
    int indirectOrder = 0;
    int indirectSamples = 0; // recorded in the layer's params
};

// The sharpest lobe of a fit from below: min(bounds.lambdaMax, max(gridResolution^2, the Phong exponent)). At
// lambda = resolution^2 a lobe still holds e^-1 of its peak at the ~1.4 / resolution rad to the nearest grid
// direction; the exponent keeps the Phong lobe itself within reach on coarse grids.
double fromBelowSharpnessMax(const GlossyOptions& options);

// The held-out grid's resolution a nested stage uses: options.heldOutResolution, or 0: min(64, 2 x gridResolution).
int heldOutResolution(const GlossyOptions& options);

struct GlossyStats {
    uint64_t rays = 0;
    uint64_t problems = 0;       // fitted (vertex, view) pairs
    double tabulateSeconds = 0.0;
    double fitSeconds = 0.0;
    double meanCost = 0.0;       // mean final objective over fitted problems
    double meanRelativeError = 0.0; // mean over problems of sqrt(data cost / E)
    uint64_t peakMemoryBytes = 0;
    // Lobe-order flips (lobesFlipped, lobes >= 2): pairs of fitted neighbouring views of one vertex, and pairs of
    // mesh-edge neighbours at one view, both fitted with every lobe's amplitude > 0.
    uint64_t viewPairs = 0, viewFlips = 0, vertexPairs = 0, vertexFlips = 0;
};

// Per-vertex diagnostics of a fit, [rows][6]: unit normal xyz, the visible share of the upper hemisphere's grid
// solid angle, and the mean and the largest over fitted views of sqrt(cost / E), the relative fit error.
inline constexpr int kVertexStatColumns = 6;

// Per-vertex lobes for the vertex range: [vertexEnd - vertexBegin][kViewCount][lobes][kLobeParams] as
// (a, mu x, mu y, mu z, lambda) with unit mu and a in radiance per steradian of the lighting; views below a
// vertex's horizon and empty kernels get a = 0 with the mirror direction and the exponent.
struct GlossyLobes {
    int lobes = 0;
    size_t vertexBegin = 0, vertexEnd = 0;
    std::vector<float> values;
    GlossyStats stats;
    std::vector<float> vertexStats; // [rows][kVertexStatColumns]
    // Nested fits only: [rows][kViewCount] sum dw (F - T)^2 / E on the held-out grid (E the held-out energy) of the
    // kept fit, -1 where no view was fitted; and the count of (vertex, view) fits that kept each stage's lobe
    // (keptStage[k - 1] for stage k; stage 1 keeps every fit).
    std::vector<float> heldOutError;
    std::vector<uint64_t> keptStage;
};

// The nested fit's lighting prior from one training map (GlossyOptions::nestedLighting): the map box-filtered to
// 128x64 bins, turned about y by 2 pi r / rotations (r = 0 .. rotations - 1), its luminance x solid angle summed
// into the nearest direction of `held`, each row normalised to sum 1 (every map and turn weighs the same). Needs an
// equirectangular map at least 128 texels wide, not black, and rotations >= 1 (throws prt::Error naming `path`
// otherwise). Returns [rotations][held.count()].
std::vector<float> lightingPrior(const EnvironmentMap& env, const std::string& path, const DirectionGrid& held,
                                 int rotations);

// Needs normals per vertex and options in range (throws prt::Error kExitUsage / kExitInput otherwise).
// Streams: memory holds one chunk's kernels plus the output. Bit-identical for any thread count and any range.
GlossyLobes computeGlossyLobes(const TriMesh& mesh, const GlossyOptions& options);

// The bundle layer of the lobes ("glossy_lobes", semantic "sg_lobes", float16, shape [V, 92, N, 5]) and its
// params: view set (directions), lobes, brdf, grid. `semantic` rows as GlossyLobes.values. Needs the lobes of
// every vertex, or shardCount > 1: then the rows are shard shardIndex of a `--shard I/N` run (domain
// "vertex_range", markVertexShard), which mergeShards joins bit for bit into the whole run's layer.
Layer lobeLayer(const GlossyLobes& lobes, const GlossyOptions& options, size_t vertexCount, int shardIndex = 0,
                int shardCount = 1);

// ---- solver comparison -------------------------------------------------------------------------------------
struct SolverComparison {
    size_t problems = 0;
    uint64_t rays = 0; // cast to tabulate the problems' radiance
    double openClSeconds = 0.0, ceresSeconds = 0.0; // wall clock for all problems, after a warm-up launch
    double openClCpuSeconds = 0.0, ceresCpuSeconds = 0.0; // process CPU time (user + system, all threads) of each
    double initialCost = 0.0, openClCost = 0.0, ceresCost = 0.0; // summed final objectives
    double shareWithinOnePercent = 0.0; // OpenCL cost <= 1.01 x Ceres cost (or at the float floor, 1e-7 E)
    double shareAgreeing = 0.0;         // |OpenCL cost - Ceres cost| <= 1% of Ceres's (or both at that floor)
    double openClMeanIterations = 0.0, ceresMeanIterations = 0.0;
    std::vector<double> openClCosts, ceresCosts;
};
// The first `problems` fit problems of the stage on `mesh` (vertex order, views above the horizon), started from
// the shared initialisation and solved without priors by both solvers with options.solverOptions.
SolverComparison compareSolvers(const TriMesh& mesh, const GlossyOptions& options, size_t problems);

} // namespace prt::glossy
