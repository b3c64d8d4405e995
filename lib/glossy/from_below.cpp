// The fit from below: lobe k fitted alone to what lobes 1..k-1 leave of the kernel, with a one-sided weight
// against overshoot (glossy.h, GlossyOptions::fromBelow; glossy_internal.h, fromBelowFit).
#include "glossy.h"
#include "glossy_internal.h"

#include <algorithm>
#include <cmath>

namespace prt::glossy {

double fromBelowSharpnessMax(const GlossyOptions& options) {
    const double resolution = options.gridResolution;
    return std::min(options.bounds.lambdaMax, std::max(resolution * resolution, options.phong.exponent));
}

std::vector<float> fromBelowFit(const DirectionGrid& grid, Chunk& tabulated, const GlossyOptions& options,
                                bool coherence) {
    FitBatch& batch = tabulated.batch;
    const int lobes = batch.lobes, width = lobes * kLobeParams;
    const size_t problems = batch.problems, count = grid.count();
    const std::vector<float> kernel = batch.kernel;
    GlossyOptions stage = options;
    stage.weights.overshoot = options.fromBelowOvershoot;
    stage.bounds.lambdaMax = fromBelowSharpnessMax(options);
    std::vector<float> lobesOut(problems * width);
    for (int k = 0; k < lobes; ++k) {
        batch.lobes = 1;
        batch.prior.clear();
        batch.hasPrior.clear();
        batch.params.assign(problems * kLobeParams, 0.0f);
        for (size_t p = 0; p < problems; ++p)
            initialise(grid, &batch.kernel[p * count], 1, options.phong.exponent, stage.bounds,
                       &batch.params[p * kLobeParams]);
        solve(grid, batch, FitWeights{0.0, 0.0, 0.0, stage.weights.overshoot}, stage);
        std::vector<float> fitted = coherencePass(grid, tabulated, stage, coherence);
        for (size_t p = 0; p < problems; ++p) {
            const float* lobe = &fitted[p * kLobeParams];
            std::copy_n(lobe, kLobeParams, &lobesOut[p * width + size_t(k) * kLobeParams]);
            float* residual = &batch.kernel[p * count];
            for (size_t i = 0; i < count; ++i) {
                const float* w = &grid.directions[i * 3];
                double cosine = double(lobe[1]) * w[0] + double(lobe[2]) * w[1] + double(lobe[3]) * w[2];
                residual[i] = float(residual[i] - double(lobe[0]) * std::exp(double(lobe[4]) * (cosine - 1.0)));
            }
        }
    }
    batch.lobes = lobes;
    batch.kernel = kernel;
    batch.params.resize(problems * width);
    for (size_t p = 0; p < problems; ++p) {
        toSolver(&lobesOut[p * width], &batch.params[p * width], lobes);
        batch.cost[p] = float(dataCost(grid, &kernel[p * count], lobes, &batch.params[p * width]));
    }
    return lobesOut;
}

} // namespace prt::glossy
