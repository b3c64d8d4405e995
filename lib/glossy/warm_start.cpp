// The warm-started independent pass: 1, 2, ..., N lobes, each fit started from the one before it plus a greedy
// lobe, never ending above the fit before it (glossy_internal.h, warmStartFit).
#include "glossy.h"
#include "glossy_internal.h"

#include <algorithm>
#include <cmath>

namespace prt::glossy {

void warmStartFit(const DirectionGrid& grid, FitBatch& batch, const GlossyOptions& options) {
    const int lobes = batch.lobes;
    FitBatch step;
    step.problems = batch.problems;
    step.kernel = std::move(batch.kernel);
    step.amplitudeMax = batch.amplitudeMax;
    std::vector<float> previous, previousCost; // the last fit, [problems][(k - 1) * kLobeParams], and its costs
    for (int k = 1; k <= lobes; ++k) {
        const size_t width = size_t(k) * kLobeParams, before = width - kLobeParams;
        step.lobes = k;
        step.params.assign(step.problems * width, 0.0f);
        for (size_t p = 0; p < step.problems; ++p) {
            float* x = &step.params[p * width];
            std::copy_n(previous.begin() + std::ptrdiff_t(p * before), before, x);
            initialiseFrom(grid, &step.kernel[p * grid.count()], k - 1, k, options.phong.exponent, options.bounds, x);
        }
        solve(grid, step, FitWeights{}, options);
        for (size_t p = 0; k > 1 && p < step.problems; ++p) {
            if (!(step.cost[p] > previousCost[p])) continue;
            float* x = &step.params[p * width];
            std::copy_n(previous.begin() + std::ptrdiff_t(p * before), before, x);
            float* extra = x + before; // a zero lobe along the first lobe, at the exponent
            extra[0] = 0.0f;
            double length = std::sqrt(double(x[1]) * x[1] + double(x[2]) * x[2] + double(x[3]) * x[3]);
            for (int c = 0; c < 3; ++c) extra[1 + c] = float(x[1 + c] / length);
            extra[4] = float(std::log(std::clamp(options.phong.exponent, options.bounds.lambdaMin, options.bounds.lambdaMax)));
            step.cost[p] = previousCost[p];
        }
        previous = step.params;
        previousCost = step.cost;
    }
    batch.kernel = std::move(step.kernel);
    batch.params = std::move(step.params);
    batch.cost = std::move(step.cost);
    batch.iterations = std::move(step.iterations);
}

} // namespace prt::glossy
