// Error metrics of a result against a reference.
#include "compare.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace prt {

namespace {

// A normalised error with a zero denominator: no error is still no error, any error is unbounded.
double normalised(double error, double scale) {
    if (scale > 0.0) return error / scale;
    return error == 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
}

double luminance(const float* rgb) {
    return kLuminance[0] * rgb[0] + kLuminance[1] * rgb[1] + kLuminance[2] * rgb[2];
}

} // namespace

ErrorMetrics compareRadiance(const float* result, const float* reference, size_t rows) {
    ErrorMetrics metrics;
    metrics.count = rows;
    if (rows == 0) return metrics;

    double squaredError = 0.0, squaredReference = 0.0, absLuminance = 0.0, signedLuminance = 0.0;
    double referenceMin = reference[0], referenceMax = reference[0];
    for (size_t i = 0; i < rows * 3; ++i) {
        double error = double(result[i]) - double(reference[i]);
        squaredError += error * error;
        squaredReference += double(reference[i]) * reference[i];
        metrics.maxAbsError = std::max(metrics.maxAbsError, std::abs(error));
        referenceMin = std::min(referenceMin, double(reference[i]));
        referenceMax = std::max(referenceMax, double(reference[i]));
    }
    for (size_t row = 0; row < rows; ++row) {
        double error = luminance(&result[row * 3]) - luminance(&reference[row * 3]);
        absLuminance += std::abs(error);
        signedLuminance += error;
    }

    double values = double(rows * 3);
    metrics.rmse = std::sqrt(squaredError / values);
    metrics.relativeRmse = normalised(metrics.rmse, std::sqrt(squaredReference / values));
    metrics.nrmse = normalised(metrics.rmse, referenceMax - referenceMin);
    metrics.meanAbsLuminanceError = absLuminance / double(rows);
    metrics.meanLuminanceBias = signedLuminance / double(rows);
    return metrics;
}

ErrorMetrics compareFiles(const std::string& resultPath, const std::string& referencePath) {
    std::vector<float> result = readVertexRadiance(resultPath);
    std::vector<float> reference = readVertexRadiance(referencePath);
    if (result.size() != reference.size())
        throw Error(resultPath, "",
                    std::to_string(result.size() / 3) + " rows, but the reference " + referencePath + " has " +
                        std::to_string(reference.size() / 3));
    if (result.empty()) throw Error(resultPath, "", "has no rows: nothing to compare");
    return compareRadiance(result.data(), reference.data(), result.size() / 3);
}

} // namespace prt
