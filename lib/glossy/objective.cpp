// The fit objective of glossy.h in double (Ceres's residuals and the reported costs), the shared greedy start,
// and lobe-order matching.
#include "glossy.h"
#include "glossy_internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

namespace prt::glossy {

double dataEnergy(const DirectionGrid& grid, const float* kernel) {
    double energy = 0.0;
    for (size_t i = 0; i < grid.count(); ++i) energy += double(grid.solidAngle[i]) * kernel[i] * kernel[i];
    return energy;
}

namespace {

// The lobes' model minus the kernel at every direction of `grid` (dataCost's residuals), in double.
std::vector<double> dataResiduals(const DirectionGrid& grid, const float* kernel, int lobes, const float* params) {
    double mean[kMaxLobes][3], sharpness[kMaxLobes];
    for (int k = 0; k < lobes; ++k) {
        const float* p = params + k * kLobeParams;
        double length = std::sqrt(double(p[1]) * p[1] + double(p[2]) * p[2] + double(p[3]) * p[3]);
        for (int c = 0; c < 3; ++c) mean[k][c] = length > 0.0 ? p[1 + c] / length : 0.0;
        sharpness[k] = std::exp(double(p[4]));
    }
    std::vector<double> residuals(grid.count());
    for (size_t i = 0; i < grid.count(); ++i) {
        const float* w = &grid.directions[i * 3];
        double model = 0.0;
        for (int k = 0; k < lobes; ++k) {
            double cosine = mean[k][0] * w[0] + mean[k][1] * w[1] + mean[k][2] * w[2];
            model += double(params[k * kLobeParams]) * std::exp(sharpness[k] * (cosine - 1.0));
        }
        residuals[i] = model - double(kernel[i]);
    }
    return residuals;
}

} // namespace

double dataCost(const DirectionGrid& grid, const float* kernel, int lobes, const float* params) {
    const std::vector<double> residuals = dataResiduals(grid, kernel, lobes, params);
    double cost = 0.0;
    for (size_t i = 0; i < grid.count(); ++i) cost += double(grid.solidAngle[i]) * residuals[i] * residuals[i];
    return cost;
}

double maxResidual(const DirectionGrid& grid, const float* kernel, int lobes, const float* params) {
    double worst = 0.0;
    for (double r : dataResiduals(grid, kernel, lobes, params)) worst = std::max(worst, std::abs(r));
    return worst;
}

double litCost(const DirectionGrid& grid, const float* kernel, int lobes, const float* params, const float* lighting,
               size_t rows) {
    const std::vector<double> residuals = dataResiduals(grid, kernel, lobes, params);
    double cost = 0.0;
    for (size_t r = 0; r < rows; ++r) {
        double lit = 0.0;
        for (size_t i = 0; i < grid.count(); ++i) lit += double(lighting[r * grid.count() + i]) * residuals[i];
        cost += lit * lit;
    }
    return cost;
}

int residualCount(size_t gridCount, int lobes) {
    return int(gridCount) + lobes + 4 * lobes + lobes * (lobes - 1) / 2;
}

void evaluateResiduals(const DirectionGrid& grid, const ProblemView& problem, const FitWeights& weights,
                       const double* params, double* residuals, double* jacobian) {
    const int lobes = problem.lobes, width = lobes * kLobeParams;
    const size_t count = grid.count();
    if (jacobian) std::fill(jacobian, jacobian + size_t(residualCount(count, lobes)) * width, 0.0);
    double mean[kMaxLobes][3], length[kMaxLobes], sharpness[kMaxLobes];
    for (int k = 0; k < lobes; ++k) {
        const double* p = params + k * kLobeParams;
        length[k] = std::sqrt(p[1] * p[1] + p[2] * p[2] + p[3] * p[3]);
        for (int c = 0; c < 3; ++c) mean[k][c] = p[1 + c] / length[k];
        sharpness[k] = std::exp(p[4]);
    }
    const double rootOver = std::sqrt(1.0 + weights.overshoot);
    for (size_t i = 0; i < count; ++i) {
        const float* w = &grid.directions[i * 3];
        double model = 0.0;
        double e[kMaxLobes], cosine[kMaxLobes];
        for (int k = 0; k < lobes; ++k) {
            cosine[k] = mean[k][0] * w[0] + mean[k][1] * w[1] + mean[k][2] * w[2];
            e[k] = std::exp(sharpness[k] * (cosine[k] - 1.0));
            model += params[k * kLobeParams] * e[k];
        }
        // The one-sided data weight (FitWeights::overshoot) where the model lies above the kernel.
        const double difference = model - double(problem.kernel[i]);
        const double root = std::sqrt(double(grid.solidAngle[i])) * (difference > 0.0 ? rootOver : 1.0);
        residuals[i] = root * difference;
        double* row = jacobian ? jacobian + i * width : nullptr;
        for (int k = 0; row && k < lobes; ++k) {
            double g = params[k * kLobeParams] * e[k];
            double* r = row + k * kLobeParams;
            r[0] = root * e[k];
            double along = root * g * sharpness[k] / length[k];
            for (int c = 0; c < 3; ++c) r[1 + c] = along * (w[c] - cosine[k] * mean[k][c]);
            r[4] = root * g * sharpness[k] * (cosine[k] - 1.0);
        }
    }
    size_t next = count;
    const double rootEnergy = std::sqrt(problem.energy);
    for (int k = 0; k < lobes; ++k, ++next) { // gauge
        const double* p = params + k * kLobeParams;
        residuals[next] = rootEnergy * (length[k] * length[k] - 1.0);
        if (jacobian)
            for (int c = 0; c < 3; ++c) jacobian[next * width + k * kLobeParams + 1 + c] = rootEnergy * 2.0 * p[1 + c];
    }
    const bool prior = problem.prior != nullptr;
    const double rootBeta = prior ? std::sqrt(weights.beta * problem.energy) : 0.0;
    const double rootGamma = prior ? std::sqrt(weights.gamma * problem.energy) : 0.0;
    const double rootDelta = prior ? std::sqrt(weights.delta * problem.energy) : 0.0;
    // d mu_c / d m_j = (delta_cj - mu_c mu_j) / |m|
    auto meanJacobian = [&](int k, int c, int j) { return ((c == j) - mean[k][c] * mean[k][j]) / length[k]; };
    for (int k = 0; k < lobes; ++k)
        for (int c = 0; c < 3; ++c, ++next) {
            residuals[next] = prior ? rootBeta * (mean[k][c] - problem.prior[k * 4 + c]) : 0.0;
            if (jacobian && prior)
                for (int j = 0; j < 3; ++j) jacobian[next * width + k * kLobeParams + 1 + j] = rootBeta * meanJacobian(k, c, j);
        }
    for (int k = 0; k < lobes; ++k, ++next) {
        residuals[next] = prior ? rootGamma * (params[k * kLobeParams + 4] - problem.prior[k * 4 + 3]) : 0.0;
        if (jacobian && prior) jacobian[next * width + k * kLobeParams + 4] = rootGamma;
    }
    for (int k1 = 0; k1 < lobes; ++k1)
        for (int k2 = k1 + 1; k2 < lobes; ++k2, ++next) {
            residuals[next] = 0.0;
            if (!prior) continue;
            double q[3], x = 0.0;
            for (int c = 0; c < 3; ++c) {
                q[c] = problem.prior[k1 * 4 + c] - problem.prior[k2 * 4 + c];
                x -= (mean[k1][c] - mean[k2][c]) * q[c];
            }
            if (x <= 0.0) continue;
            residuals[next] = rootDelta * x * std::sqrt(x);
            if (!jacobian) continue;
            double slope = 1.5 * rootDelta * std::sqrt(x); // d r / d x; d x / d mu1 = -q, d x / d mu2 = q
            for (int j = 0; j < 3; ++j) {
                double d1 = 0.0, d2 = 0.0;
                for (int c = 0; c < 3; ++c) d1 -= q[c] * meanJacobian(k1, c, j), d2 += q[c] * meanJacobian(k2, c, j);
                jacobian[next * width + k1 * kLobeParams + 1 + j] = slope * d1;
                jacobian[next * width + k2 * kLobeParams + 1 + j] = slope * d2;
            }
        }
}

ProblemView problemView(const DirectionGrid& grid, const FitBatch& batch, size_t p) {
    ProblemView view;
    view.lobes = batch.lobes;
    view.kernel = &batch.kernel[p * grid.count()];
    view.energy = dataEnergy(grid, view.kernel);
    view.amplitudeMax = batch.amplitudeMax[p];
    if (!batch.hasPrior.empty() && batch.hasPrior[p]) view.prior = &batch.prior[p * batch.lobes * 4];
    return view;
}

double objective(const DirectionGrid& grid, const FitBatch& batch, size_t p, const FitWeights& weights,
                 const FitBounds&, const float* params) {
    ProblemView view = problemView(grid, batch, p);
    std::vector<double> x(params, params + batch.lobes * kLobeParams);
    std::vector<double> residuals(residualCount(grid.count(), batch.lobes));
    evaluateResiduals(grid, view, weights, x.data(), residuals.data(), nullptr);
    double cost = 0.0;
    for (double r : residuals) cost += r * r;
    return cost;
}

void initialiseFrom(const DirectionGrid& grid, const float* kernel, int given, int lobes, double exponent,
                    const FitBounds& bounds, float* params) {
    std::vector<double> residual(kernel, kernel + grid.count());
    for (int k = 0; k < lobes; ++k) {
        float* p = params + k * kLobeParams;
        double mean[3], sharpness, amplitude;
        if (k < given) { // a lobe of the given fit, as it stands
            double length = std::sqrt(double(p[1]) * p[1] + double(p[2]) * p[2] + double(p[3]) * p[3]);
            for (int c = 0; c < 3; ++c) mean[c] = p[1 + c] / length;
            sharpness = std::exp(double(p[4]));
            amplitude = p[0];
        } else {
            size_t peak = size_t(std::max_element(residual.begin(), residual.end()) - residual.begin());
            sharpness = std::clamp(exponent * double(1 << k), bounds.lambdaMin, bounds.lambdaMax);
            amplitude = std::max(0.0, residual[peak]) * (k == 0 ? 1.0 : 0.5);
            const float* direction = &grid.directions[peak * 3];
            p[0] = float(amplitude);
            for (int c = 0; c < 3; ++c) p[1 + c] = direction[c], mean[c] = direction[c];
            p[4] = float(std::log(sharpness));
        }
        for (size_t i = 0; i < grid.count(); ++i) {
            const float* w = &grid.directions[i * 3];
            double cosine = mean[0] * w[0] + mean[1] * w[1] + mean[2] * w[2];
            residual[i] -= amplitude * std::exp(sharpness * (cosine - 1.0));
        }
    }
}

void initialise(const DirectionGrid& grid, const float* kernel, int lobes, double exponent, const FitBounds& bounds,
                float* params) {
    initialiseFrom(grid, kernel, 0, lobes, exponent, bounds, params);
}

namespace {

double lobeDistance(const float* a, const float* b) {
    double dot = 0.0, la = 0.0, lb = 0.0;
    for (int c = 1; c <= 3; ++c) dot += double(a[c]) * b[c], la += double(a[c]) * a[c], lb += double(b[c]) * b[c];
    double angle = std::acos(std::clamp(dot / std::sqrt(la * lb), -1.0, 1.0));
    return angle + std::abs(std::log(double(a[4])) - std::log(double(b[4])));
}

// Cost of matching lobe k of a with lobe permutation[k] of b; lobes with a zero amplitude match anything.
double permutationCost(const float* a, const float* b, const int* permutation, int lobes) {
    double cost = 0.0;
    for (int k = 0; k < lobes; ++k) {
        const float* la = a + k * kLobeParams;
        const float* lb = b + permutation[k] * kLobeParams;
        if (la[0] > 0.0f && lb[0] > 0.0f) cost += lobeDistance(la, lb);
    }
    return cost;
}

} // namespace

// Lobe records here are the output form (a, mu, lambda), not the solver's (a, m, log lambda).
void alignLobes(const float* a, float* b, int lobes) {
    std::array<int, kMaxLobes> permutation, best;
    std::iota(permutation.begin(), permutation.begin() + lobes, 0);
    best = permutation;
    double bestCost = permutationCost(a, b, permutation.data(), lobes);
    while (std::next_permutation(permutation.begin(), permutation.begin() + lobes)) {
        double cost = permutationCost(a, b, permutation.data(), lobes);
        if (cost < bestCost - 1e-9) bestCost = cost, best = permutation;
    }
    std::vector<float> copy(b, b + lobes * kLobeParams);
    for (int k = 0; k < lobes; ++k)
        std::copy_n(&copy[best[k] * kLobeParams], kLobeParams, b + k * kLobeParams);
}

bool lobesFlipped(const float* a, const float* b, int lobes, double margin) {
    std::array<int, kMaxLobes> permutation;
    std::iota(permutation.begin(), permutation.begin() + lobes, 0);
    double identity = permutationCost(a, b, permutation.data(), lobes);
    while (std::next_permutation(permutation.begin(), permutation.begin() + lobes))
        if (permutationCost(a, b, permutation.data(), lobes) < identity - margin) return true;
    return false;
}

} // namespace prt::glossy
