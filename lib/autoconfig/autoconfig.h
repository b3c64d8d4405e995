// Auto-configuration to a target error (`prt autoconfig`, issue 12): the cheapest bake and the smallest bundle
// whose relative error against the path-traced reference stays under a target, chosen from cheap pilot runs on a
// vertex subset, verified on held-out vertices, and reported on a final check set that no choice ever looked at.
// docs/autoconfig.md has the decisions; results.md the figures.
//
// A configuration is (SH order L, transfer samples S, bounces B, storage format, extracted lights K). Its error is the relative RMSE
// `prt compare` reports (RMS over vertices and RGB channels of relit - reference, over the reference's RMS), with
// the reference's own noise taken out: e^2 = (mean (x - r)^2 - mean se^2) / (mean r^2 - mean se^2), se the
// reference's per-vertex standard error, because noise adds in quadrature and would otherwise be charged to the
// configuration. Under several maps the error of a configuration is the largest over them.
//
// Why the pilot predicts the bake: transfer at a receiver with a vertex's key is that vertex's row of the full
// bake (bit for bit without bounces, to float rounding with them: lib/transfer computeTransferAt), and lower SH
// orders are the first coefficients of the same Monte Carlo run (the estimator does not depend on the order), so
// one run at the largest order per (S, B) gives every order's rows. The quantised formats are emulated with
// lib/adapt's own code. What the pilot cannot know is the vertices it did not see: hence the held-out check.
#pragma once

#include "adapt.h"
#include "bundle.h"
#include "image.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace prt::autoconfig {

struct Config {
    int order = 0;    // bands
    int samples = 0;  // transfer directions per vertex
    int bounces = 0;  // 0: shadowed transfer; > 0: interreflected
    adapt::Format format = adapt::Format::Float; // Float: the transfer stage's own layer; others through `prt adapt`
    // > 0: adaptive order, `prt adapt --max-error` (rms budget, one map as the prior, no grading): each vertex keeps
    // the bands the budget gives it, up to `order`. 0: every vertex at `order`.
    double adaptiveError = 0.0;
    // > 0: the hybrid relight (docs/envlight.md) with up to this many cone lights per map from `prt envlight
    // --order L --max-lights K` and their order-L residual; float storage with the transfer's bounce layer, which
    // the lights' interreflection goes through. 0: plain SH.
    int lights = 0;
};

// One configuration with its modelled costs and its errors on the pilot, held-out and check vertices.
struct Candidate {
    Config config;
    double bakeCost = 0.0;      // modelled work of the bake on the whole mesh, in ray equivalents (kCoefficientCost)
    double bakeSeconds = 0.0;   // the same in seconds at the pilot's measured rate (the report's; not used to choose)
    uint64_t bundleBytes = 0;   // bytes of the transfer layers the bundle stores (bundleLayerBytes)
    double pilotError = 0.0;    // largest over the maps, noise-corrected, on the pilot vertices
    double heldOutError = -1.0; // the same on the held-out vertices; < 0 until verified
    // The same on the final check vertices, measured once for the chosen configuration only: the held-out set
    // stops being unseen once a candidate has failed on it and the next is tried, so this is the unbiased figure.
    double checkError = -1.0;
};

struct Options {
    double targetError = 0.0;                  // relative, > 0
    std::vector<int> orders = {2, 3, 4, 5, 6, 7, 8};
    std::vector<int> samples = {64, 128, 256, 512, 1024};
    std::vector<int> bounces = {0, 1, 2, 3};
    std::vector<adapt::Format> formats = {adapt::Format::Float, adapt::Format::Half, adapt::Format::U16,
                                          adapt::Format::U8};
    std::vector<int> lights = {0, 4};          // extracted cone lights (max per map); 0: plain SH only
    int lightSamples = 64;                     // cone visibility rays per vertex and light, as `prt relight`'s
    std::array<double, 3> albedo = {0.8, 0.8, 0.8}; // transfer and reference (overrides per-vertex albedo), as typed
    uint64_t seed = 0;                         // transfer directions, reference paths and the vertex subsets
    size_t pilotVertices = 256;                // and as many held out and as many for the check (at most a third each)
    int referenceBounces = 3;                  // the ground truth the error is measured against
    int referenceMinSamples = 1024;            // the first reference pass, which measures the noise
    int referenceMaxSamples = 16384;           // the most paths per vertex autoconfig may spend on its reference
    double noiseFraction = 1.0 / 3.0;          // paths are added until the reference noise is under this x target
    double margin = 0.9;                       // a configuration is chosen only if its pilot error <= margin x target
    int threads = 0;
};

// The bake's cost model, in work counts so that the choice is the same on any machine load and thread count: a
// direction cast costs 1 plus kCoefficientCost per SH coefficient it accumulates, and each bounce costs
// kGatherCost per coefficient at each front-face hit (the pilot counts the hits per direction). Calibrated on this
// project's measurements (results.md: order 1 to 12 at 16384 samples 1.44 to 1.86 s, order 3 to 8 at 1024 samples
// 0.110 to 0.140 s; one bounce 0.011 of the direct pass on the bunny at order 5, 0.104 hits per direction).
inline constexpr double kCoefficientCost = 0.004;
inline constexpr double kGatherCost = 0.005;
// A hybrid candidate also pays, per map and extracted light, for the decomposition (`prt envlight`: kEnvlightTexelCost
// per map texel) and for its cone visibility (`prt relight --lights`: lightSamples rays at every vertex).
inline constexpr double kEnvlightTexelCost = 1.0;

// The reference noise that makes a target untestable: below kNoiseRefusalRatio times the noise the reference
// would have at referenceMaxSamples paths the pilot cannot tell a configuration's error from the noise.
inline constexpr double kNoiseRefusalRatio = 2.0;

struct Result {
    Candidate chosen;
    std::vector<Candidate> candidates;  // every configuration, pilot errors and costs
    std::vector<size_t> pareto;         // indices into candidates: not dominated in (seconds, bytes, pilot error)
    std::vector<size_t> tried;          // indices verified on held-out vertices, in order (the last is chosen)
    std::vector<uint32_t> pilot, heldOut, check; // the vertex subsets
    int referenceSamples = 0;           // paths per vertex of the pilot reference
    std::vector<double> referenceNoise; // per map: RMS standard error over RMS radiance on all three subsets' rows
    double pilotTransferSeconds = 0.0, referenceSeconds = 0.0, seconds = 0.0;
    uint64_t rays = 0; // cast in all: the references, the pilot transfers and the lights' cone visibility
};

// ---- the pieces (each in its own file) ------------------------------------------------------------------------

// Three disjoint deterministic vertex subsets of `count` vertices each (count clipped to V / 3): vertices sorted
// along a Morton curve over the bounding box, cut into `count` runs of equal length, and from each run one vertex
// for the pilot, another for the held-out set and a third for the final check, picked by a hash of (seed, run).
// So every set covers the mesh evenly. Needs V >= 3. All returned sorted.
void splitVertices(const TriMesh& mesh, size_t count, uint64_t seed, std::vector<uint32_t>& pilot,
                   std::vector<uint32_t>& heldOut, std::vector<uint32_t>& check);

// Bytes of the transfer layers a bundle of V vertices at uniform order L stores in `format` (the mesh's own bytes,
// the same for every configuration, left out). Float without bounces is the transfer stage's [V][L^2][3] float32
// layer; everything else goes through `prt adapt --order L`, which drops the transfer stage's "transfer_bounce"
// layer (hybrid lighting's, as large again) and writes ragged layers: the offsets, then the values in the format
// (float32, float16, uint16, uint8), and for u16/u8 one float16 scale per vertex and band. CPCA is not modelled
// (throws prt::Error(kExitUsage)).
uint64_t bundleLayerBytes(size_t vertexCount, int order, adapt::Format format, int bounces);
// The same for ragged (adaptive) layers holding `coefficients` coefficient rows and `bands` bands in all: offsets,
// the values in the format (float32 for float), and for u16/u8 one float16 scale per band.
uint64_t raggedLayerBytes(size_t vertexCount, uint64_t coefficients, uint64_t bands, adapt::Format format);

// The rows a bundle in `format` stores for `rows` transfer rows [count][order^2][3] (the first order^2
// coefficients of a larger run may be passed with stride `strideOrder`), decoded back to float as the runtime
// reads them: float as is, half rounded to float16, u16/u8 through adapt::quantise / dequantise with per-vertex
// scales. With `orders` (per row, each <= order) only each row's first orders[i]^2 coefficients are kept, the
// rest zero, as a ragged bundle stores them. Result [count][order^2][3].
std::vector<float> storedRows(const float* rows, size_t count, int strideOrder, int order, adapt::Format format,
                              const std::vector<uint8_t>* orders = nullptr);

// Noise-corrected relative RMSE of radiance against a reference, both [count][3], with the reference's standard
// error se [count][3] (see the top of this file); 0 where the noise exceeds the measured difference.
double noiseCorrectedError(const float* radiance, const float* reference, const float* standardError, size_t count);

// Runs the whole search (pilot reference, pilot transfers, prediction, Pareto front, choice, held-out check, final
// check). A chosen configuration over the target on the final check is still returned, with a warning: choosing
// again on that set would make it a selection set too.
// Needs a mesh with normals, at least one map, options.targetError > 0. Throws prt::Error(kExitUsage) for a
// target <= 0 or below kNoiseRefusalRatio x the reference's noise (saying so and what would be needed), and for
// a target no configuration reaches (naming the best one found); nothing is written either way.
Result autoconfigure(const TriMesh& mesh, const std::vector<EnvironmentMap>& envs,
                     const std::vector<std::string>& envNames, const Options& options);

// The pipeline `prt run` executes for the chosen configuration: the mesh input, the transfer stage (with the
// albedo and seed the pilot used, so the bake's rows are the pilot's), `prt adapt --order L --format F` for the
// compact formats, and a relight per map; outputs the bundle at bundlePath and each map's radiance next to it.
// A comment block records the target, the predicted and verified errors and the reference noise. `name` is
// made a pipeline name (characters other than letters, digits, '-' and '_' become '-').
std::string pipelineToml(const Result& result, const Options& options, const std::string& meshPath,
                         const std::vector<std::string>& envPaths, const std::string& bundlePath,
                         const std::string& name);

// The report as JSON: options, subsets' sizes, reference samples and noise, every Pareto candidate, the tried
// and chosen ones, and times.
std::string reportJson(const Result& result, const Options& options);

} // namespace prt::autoconfig
