// Error metrics between a result and a reference, and the per-vertex radiance files every stage exchanges.
// Radiance arrays are flat rgb rows ([N][3], row-major), in the mesh's vertex order or an image's pixel order.
#pragma once

#include "luminance.h" // kLuminance, the weights of every luminance metric

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt {

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
// Throws prt::Error(kExitUsage) for any other extension, and (requireFiniteResult) for a value that is not finite.
void writeVertexRadiance(const std::string& path, const std::vector<float>& rgb);

// Reads rgb rows from .npy (float32 [N,3]) or .csv (N lines "r,g,b", an optional header line first).
// Throws prt::Error naming the file, and the line for csv, for a missing file, a wrong shape or column count,
// or a value that is not a finite number.
std::vector<float> readVertexRadiance(const std::string& path);

// ---- images (`prt compare --image`) ----------------------------------------------------------------------------
// Two linear RGB images ([pixel][3], row 0 at the top) compared over a mask: `metrics` as compareRadiance over the
// mask's pixels, and per pixel the relative luminance error |Y(a) - Y(b)| / max(Y(b), relativeFloor), where the
// floor is 1e-3 of the reference's mean luminance over the mask (so near-black pixels do not dominate).
struct ImageComparison {
    int width = 0, height = 0;
    uint64_t maskPixels = 0;
    ErrorMetrics metrics;
    double relativeFloor = 0.0;
    double meanRelativeError = 0.0, p95RelativeError = 0.0, maxRelativeError = 0.0; // over the mask
    std::vector<float> relativeError; // per pixel; -1 outside the mask
};
// Needs result and reference of width * height * 3 values, finite (a NaN pixel's error is NaN; the percentile
// then has no order); mask of width * height values (> 0.5 is inside), or null for every pixel.
ImageComparison compareImages(const float* result, const float* reference, const float* mask, int width, int height);

// An 8-bit RGB picture, row 0 at the top.
struct Picture {
    int width = 0, height = 0;
    std::vector<uint8_t> rgb;
};
// The relative error in false colour (viridis from 0 to `scaleTop`, saturated above; grey outside the mask) with a
// legend bar and its end labels under the image. Needs scaleTop > 0.
Picture relativeErrorPicture(const ImageComparison& comparison, double scaleTop);
// The tone map of every 8-bit picture prt writes (`prt render` PNGs, `prt compare --image` strips) and of the browser
// viewer (viewer/): x = radiance * 2^exposure per channel, then Reinhard x / (1 + x), then the sRGB transfer
// function (x <= 0.0031308: 12.92 x, else 1.055 x^(1/2.4) - 0.055), rounded to the nearest of 256 levels.
// Negative and NaN radiance map to 0. Linear outputs (EXR) are never tone mapped.
uint8_t toneMap(float radiance, float exposure);
// Linear radiance (width * height * 3 values) through toneMap, `exposure` in stops.
Picture tonemappedPicture(const float* radiance, int width, int height, float exposure);
// result | reference | error side by side, 4 pixels apart, each labelled at its top.
Picture comparisonStrip(const Picture& result, const Picture& reference, const Picture& error);

} // namespace prt
