// Per-vertex order selection: the truncation error of each order under a lighting prior, and the smallest order
// within a bound.
#include "adapt.h"

#include "core.h"
#include "sh.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace prt::adapt {

namespace {

// What one lighting of the prior needs, computed once per lighting: its band norms per channel (the worst case
// bounds band l of a row by |row_l| |lighting_l|) and the sum of the squared full-order radiance over every vertex
// and channel (the error scale). Throws prt::Error naming lighting k when that sum is 0: a black relight has no
// relative error.
struct LightingPrior {
    std::vector<double> bandNorm; // [order][3]
    double sumSquares = 0.0;
};

LightingPrior lightingPrior(const float* transfer, size_t vertexCount, int order, const std::vector<float>& lighting,
                            size_t k) {
    const size_t coefficients = size_t(order) * order;
    LightingPrior p;
    p.bandNorm.assign(size_t(order) * 3, 0.0);
    for (int l = 0; l < order; ++l)
        for (int j = l * l; j < (l + 1) * (l + 1); ++j)
            for (int c = 0; c < 3; ++c) p.bandNorm[l * 3 + c] += double(lighting[j * 3 + c]) * lighting[j * 3 + c];
    for (double& value : p.bandNorm) value = std::sqrt(value);
    for (size_t v = 0; v < vertexCount; ++v)
        for (int c = 0; c < 3; ++c) {
            double radiance = 0.0;
            for (size_t j = 0; j < coefficients; ++j)
                radiance += double(transfer[(v * coefficients + j) * 3 + c]) * lighting[j * 3 + c];
            p.sumSquares += radiance * radiance;
        }
    if (!(p.sumSquares > 0.0))
        throw Error("", "lighting " + std::to_string(k), "relights the mesh to black at full order, so no "
                    "relative error can be measured under it", kExitInput);
    return p;
}

// Band l's part of one vertex row's radiance, per channel, into partial[l * 3 + c]: the exact value under the
// lighting (Prior::Maps) or its Cauchy-Schwarz bound (Prior::Worst).
void bandParts(const float* row, const std::vector<float>& lighting, const LightingPrior& p, int order, Prior prior,
               double* partial) {
    for (int l = 0; l < order; ++l)
        for (int c = 0; c < 3; ++c) {
            double value = 0.0;
            if (prior == Prior::Maps) {
                for (int j = l * l; j < (l + 1) * (l + 1); ++j) value += double(row[j * 3 + c]) * lighting[j * 3 + c];
            } else {
                double norm = 0.0;
                for (int j = l * l; j < (l + 1) * (l + 1); ++j) norm += double(row[j * 3 + c]) * row[j * 3 + c];
                value = std::sqrt(norm) * p.bandNorm[l * 3 + c];
            }
            partial[l * 3 + c] = value;
        }
}

} // namespace

std::vector<float> truncationError(const float* transfer, size_t vertexCount, int order,
                                   const std::vector<std::vector<float>>& lightings, Prior prior) {
    if (order < 1 || order > sh::kMaxOrder)
        throw Error("", "truncationError", "order " + std::to_string(order) + " outside 1.." +
                                               std::to_string(sh::kMaxOrder), kExitFailure);
    const size_t coefficients = size_t(order) * order;
    std::vector<float> error(vertexCount * order, 0.0f);
    std::vector<double> partial(size_t(order) * 3); // per vertex: radiance (Maps) or tail bound (Worst) per band
    for (size_t k = 0; k < lightings.size(); ++k) {
        const std::vector<float>& lighting = lightings[k];
        if (lighting.size() != coefficients * 3)
            throw Error("", "truncationError", "lighting " + std::to_string(k) + " has " +
                                                   std::to_string(lighting.size()) + " values, not " +
                                                   std::to_string(coefficients * 3), kExitFailure);
        const LightingPrior p = lightingPrior(transfer, vertexCount, order, lighting, k);
        // The scale: RMS full-order radiance over the mesh.
        double scale = std::sqrt(p.sumSquares / double(std::max<size_t>(1, vertexCount * 3)));
        for (size_t v = 0; v < vertexCount; ++v) {
            bandParts(transfer + v * coefficients * 3, lighting, p, order, prior, partial.data());
            // Tail from band n on: what order n leaves out.
            for (int c = 0; c < 3; ++c) {
                double tail = 0.0;
                for (int n = order; n >= 1; --n) {
                    float relative = float(std::fabs(tail) / scale);
                    float& slot = error[v * order + (n - 1)];
                    slot = std::max(slot, relative);
                    tail += partial[(n - 1) * 3 + c];
                }
            }
        }
    }
    return error;
}

std::vector<uint8_t> selectOrders(const std::vector<float>& error, size_t vertexCount, int order, double maxError) {
    std::vector<uint8_t> orders(vertexCount, uint8_t(order));
    if (!(maxError > 0.0)) return orders;
    for (size_t v = 0; v < vertexCount; ++v)
        for (int n = 1; n <= order; ++n)
            if (error[v * order + (n - 1)] <= maxError) {
                orders[v] = uint8_t(n);
                break;
            }
    return orders;
}

RaggedTransfer raggedTransfer(const float* transfer, size_t vertexCount, int order,
                              const std::vector<uint8_t>& orders) {
    RaggedTransfer ragged;
    ragged.order = order;
    ragged.offsets.resize(vertexCount + 1, 0);
    const size_t coefficients = size_t(order) * order;
    for (size_t v = 0; v < vertexCount; ++v) ragged.offsets[v + 1] = ragged.offsets[v] + uint32_t(orders[v]) * orders[v];
    ragged.values.resize(size_t(ragged.offsets[vertexCount]) * 3);
    for (size_t v = 0; v < vertexCount; ++v) {
        const float* row = transfer + v * coefficients * 3;
        std::copy(row, row + size_t(orders[v]) * orders[v] * 3, ragged.values.begin() + size_t(ragged.offsets[v]) * 3);
    }
    return ragged;
}

int vertexOrder(const RaggedTransfer& ragged, size_t v) {
    return int(std::lround(std::sqrt(double(ragged.offsets[v + 1] - ragged.offsets[v]))));
}

} // namespace prt::adapt

namespace prt::adapt {

std::vector<float> denseTransfer(const RaggedTransfer& ragged, const std::vector<float>* values) {
    const std::vector<float>& source = values ? *values : ragged.values;
    const size_t vertexCount = ragged.offsets.size() - 1, coefficients = size_t(ragged.order) * ragged.order;
    std::vector<float> dense(vertexCount * coefficients * 3, 0.0f);
    for (size_t v = 0; v < vertexCount; ++v)
        std::copy(source.begin() + size_t(ragged.offsets[v]) * 3, source.begin() + size_t(ragged.offsets[v + 1]) * 3,
                  dense.begin() + v * coefficients * 3);
    return dense;
}

double priorRelativeRmse(const float* approx, const float* full, size_t vertexCount, int order,
                         const std::vector<std::vector<float>>& lightings) {
    const size_t coefficients = size_t(order) * order;
    double worst = 0.0;
    for (const std::vector<float>& lighting : lightings) {
        double error = 0.0, reference = 0.0;
        for (size_t v = 0; v < vertexCount; ++v)
            for (int c = 0; c < 3; ++c) {
                double a = 0.0, f = 0.0;
                for (size_t j = 0; j < coefficients; ++j) {
                    a += double(approx[(v * coefficients + j) * 3 + c]) * lighting[j * 3 + c];
                    f += double(full[(v * coefficients + j) * 3 + c]) * lighting[j * 3 + c];
                }
                error += (a - f) * (a - f);
                reference += f * f;
            }
        worst = std::max(worst, reference > 0.0 ? std::sqrt(error / reference) : 0.0);
    }
    return worst;
}

} // namespace prt::adapt

namespace prt::adapt {

std::vector<double> truncationErrorSquared(const float* transfer, size_t vertexCount, int order,
                                           const std::vector<std::vector<float>>& lightings, Prior prior) {
    const size_t coefficients = size_t(order) * order;
    std::vector<double> out(lightings.size() * vertexCount * order, 0.0);
    std::vector<double> partial(size_t(order) * 3);
    for (size_t k = 0; k < lightings.size(); ++k) {
        const std::vector<float>& lighting = lightings[k];
        const LightingPrior p = lightingPrior(transfer, vertexCount, order, lighting, k);
        const double sumSquares = p.sumSquares;
        for (size_t v = 0; v < vertexCount; ++v) {
            bandParts(transfer + v * coefficients * 3, lighting, p, order, prior, partial.data());
            double* slots = out.data() + (k * vertexCount + v) * order;
            for (int c = 0; c < 3; ++c) {
                double tail = 0.0;
                for (int n = order; n >= 1; --n) {
                    slots[n - 1] += tail * tail / sumSquares; // sumSquares = 3 V s^2
                    tail += partial[(n - 1) * 3 + c];
                }
            }
        }
    }
    return out;
}

std::vector<uint8_t> budgetOrders(const std::vector<double>& errorSquared, size_t mapCount, size_t vertexCount,
                                  int order, double maxRmse) {
    std::vector<uint8_t> orders(vertexCount, uint8_t(order));
    if (!(maxRmse > 0.0) || mapCount == 0) return orders;
    const double budget = maxRmse * maxRmse;
    std::vector<uint8_t> trial(vertexCount);
    auto choose = [&](double lambda) { // returns the worst map's squared relative RMSE
        std::vector<double> total(mapCount, 0.0);
        for (size_t v = 0; v < vertexCount; ++v) {
            double best = std::numeric_limits<double>::infinity();
            int bestOrder = order;
            for (int n = 1; n <= order; ++n) {
                double cost = lambda * double(n) * n;
                for (size_t k = 0; k < mapCount; ++k) cost += errorSquared[(k * vertexCount + v) * order + n - 1];
                if (cost < best) best = cost, bestOrder = n;
            }
            trial[v] = uint8_t(bestOrder);
            for (size_t k = 0; k < mapCount; ++k) total[k] += errorSquared[(k * vertexCount + v) * order + bestOrder - 1];
        }
        return *std::max_element(total.begin(), total.end());
    };
    // lambda is in squared relative error per coefficient; the feasible ones form an interval [0, lambda*].
    double low = -40.0, high = 5.0; // log10 lambda
    if (choose(std::pow(10.0, high)) <= budget) return trial;
    for (int iteration = 0; iteration < 60; ++iteration) {
        double middle = 0.5 * (low + high);
        if (choose(std::pow(10.0, middle)) <= budget) low = middle;
        else high = middle;
    }
    choose(std::pow(10.0, low));
    return trial;
}

} // namespace prt::adapt
