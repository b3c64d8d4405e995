// Error metrics between a result and a reference, and the per-vertex radiance files every stage exchanges.
// Radiance arrays are flat rgb rows ([N][3], row-major), in the mesh's vertex order or an image's pixel order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {

// Rec.709 luminance weights, used for every luminance metric.
inline constexpr double kLuminanceWeights[3] = {0.2126, 0.7152, 0.0722};

// How far a result is from a reference. Every error is result minus reference; the RMS-type metrics run over
// all values (rows times channels), the luminance metrics over rows.
struct ErrorMetrics {
    uint64_t count = 0;                  // rows compared
    double rmse = 0.0;                   // sqrt(mean (a - b)^2)
    double relativeRmse = 0.0;           // rmse / sqrt(mean b^2)
    double nrmse = 0.0;                  // rmse / (max b - min b)
    double maxAbsError = 0.0;            // max |a - b|
    double meanAbsLuminanceError = 0.0;  // mean |Y(a) - Y(b)|
    double meanLuminanceBias = 0.0;      // mean (Y(a) - Y(b)): positive when the result is too bright
};

// Compares `result` against `reference`, both `rows` rgb rows. A normalised metric whose denominator is zero
// (a black or flat reference) is 0 when rmse is 0 and +infinity otherwise.
ErrorMetrics compareRadiance(const float* result, const float* reference, size_t rows);

// Reads both files with readVertexRadiance and compares them. Throws prt::Error naming both files when their
// row counts differ.
ErrorMetrics compareFiles(const std::string& resultPath, const std::string& referencePath);

// Writes rgb rows (rgb.size() a multiple of 3) atomically, by extension: .npy (float32 [N,3]) or .csv (header
// "r,g,b", then one row "r,g,b" per line, printed so every float reads back bit-exact).
// Throws prt::Error(kExitUsage) for any other extension.
void writeVertexRadiance(const std::string& path, const std::vector<float>& rgb);

// Reads rgb rows from .npy (float32 [N,3]) or .csv (N lines "r,g,b", an optional header line first).
// Throws prt::Error naming the file, and the line for csv, for a missing file, a wrong shape or column count,
// or a value that is not a finite number.
std::vector<float> readVertexRadiance(const std::string& path);

} // namespace prt
