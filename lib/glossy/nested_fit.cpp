// The nested fit: lobes added one stage at a time, each problem keeping a stage only where the held-out error
// says it helps (glossy_internal.h, nestedFit and keepStage).
#include "glossy.h"
#include "glossy_internal.h"

#include <algorithm>
#include <cmath>

namespace prt::glossy {

std::vector<uint8_t> keepStage(const std::vector<size_t>& first, const std::vector<double>& held,
                               const std::vector<double>& previous, int k, const GlossyOptions& options) {
    const size_t problems = held.size();
    std::vector<uint8_t> keep(problems, 1);
    if (k == 1) return keep;
    const double factor = 1.0 - options.nestedMargin;
    if (!options.nestedPerVertex) {
        for (size_t p = 0; p < problems; ++p) keep[p] = held[p] < factor * previous[p];
        return keep;
    }
    for (size_t i = 0; i + 1 < first.size(); ++i) {
        double now = 0.0, before = 0.0;
        for (size_t p = first[i]; p < first[i + 1]; ++p) now += held[p], before += previous[p];
        for (size_t p = first[i]; p < first[i + 1]; ++p) keep[p] = now < factor * before;
    }
    return keep;
}

std::vector<float> nestedFit(const DirectionGrid& grid, const DirectionGrid& heldOut, Chunk& tabulated,
                             const GlossyOptions& options, bool coherence, std::vector<double>& heldCost,
                             std::vector<uint64_t>& keptStage) {
    FitBatch& batch = tabulated.batch;
    const int lobes = batch.lobes;
    const size_t problems = batch.problems, heldCount = heldOut.count();
    std::vector<float> kept, keptCost; // output form [problems][(k - 1) * kLobeParams], and its costs
    std::vector<int> keptIterations;
    heldCost.assign(problems, 0.0);
    std::vector<double> keptScore(problems, 0.0); // the kept fit's keep score: litCost, or without lighting heldCost
    const size_t rows = options.nestedLighting.size() / std::max<size_t>(heldCount, 1);
    if (keptStage.size() < size_t(lobes)) keptStage.resize(size_t(lobes), 0);
    const float zeroSharpness = float(std::clamp(options.phong.exponent, options.bounds.lambdaMin, options.bounds.lambdaMax));
    for (int k = 1; k <= lobes; ++k) {
        const size_t width = size_t(k) * kLobeParams, before = width - kLobeParams;
        batch.lobes = k;
        batch.prior.clear();
        batch.hasPrior.clear();
        batch.params.assign(problems * width, 0.0f);
        for (size_t p = 0; p < problems; ++p) {
            float* x = &batch.params[p * width];
            toSolver(&kept[p * before], x, k - 1);
            initialiseFrom(grid, &batch.kernel[p * grid.count()], k - 1, k, options.phong.exponent, options.bounds, x);
        }
        solve(grid, batch, FitWeights{}, options);
        std::vector<float> fitted = coherencePass(grid, tabulated, options, coherence);
        std::vector<double> held(problems), score(problems);
        for (size_t p = 0; p < problems; ++p) {
            const float* kernel = &tabulated.heldKernel[p * heldCount];
            held[p] = dataCost(heldOut, kernel, k, &batch.params[p * width]);
            score[p] = rows ? litCost(heldOut, kernel, k, &batch.params[p * width], options.nestedLighting.data(), rows)
                       : options.nestedMaxNorm ? maxResidual(heldOut, kernel, k, &batch.params[p * width])
                                               : held[p];
        }
        std::vector<uint8_t> keep = keepStage(tabulated.first, score, keptScore, k, options);
        for (size_t p = 0; p < problems; ++p) {
            if (keep[p]) {
                heldCost[p] = held[p];
                keptScore[p] = score[p];
                ++keptStage[size_t(k) - 1];
                continue;
            }
            float* row = &fitted[p * width];
            std::copy_n(&kept[p * before], before, row);
            float* extra = row + before;
            extra[0] = 0.0f;
            std::copy_n(row + 1, 3, extra + 1);
            extra[4] = zeroSharpness;
            toSolver(row, &batch.params[p * width], k);
            batch.cost[p] = keptCost[p];
            batch.iterations[p] = keptIterations[p];
        }
        kept = std::move(fitted);
        keptCost = batch.cost;
        keptIterations = batch.iterations;
    }
    return kept;
}

} // namespace prt::glossy
