// prt compare: error metrics of a per-vertex result against a reference, as JSON; with --image, of two images over
// the result's coverage mask, with a false-colour error picture and a result | reference | error strip.
#include "cli.h"

#include "compare.h"
#include "core.h"
#include "image.h"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>

namespace prt::cli {

namespace {

struct CompareOptions {
    std::string result;
    std::string reference;
    std::string output;
    bool image = false;
    std::string strip;
    std::string metricsOutput;
    double scaleTop = 0.2;
    float exposure = 0.0f;
};

// Writes a picture atomically as an 8-bit PNG.
void writePicture(const std::string& path, const Picture& picture) {
    writeImagePixels(path, picture.width, picture.height, {"R", "G", "B"}, picture.rgb.data());
}

// The coverage mask of an image: its A channel when it has one (`prt render` writes it), else empty (every pixel).
std::vector<float> coverageMask(const std::string& path) {
    std::vector<std::string> names = imageChannelNames(path);
    if (std::find(names.begin(), names.end(), "A") == names.end()) return {};
    return readImageChannels(path, {"A"}).values;
}

// The metrics every comparison reports, appended to `document` in this order.
void addMetrics(nlohmann::ordered_json& document, const ErrorMetrics& metrics) {
    document["count"] = metrics.count;
    document["rmse"] = metrics.rmse;
    document["relative_rmse"] = metrics.relativeRmse;
    document["nrmse"] = metrics.nrmse;
    document["max_abs_error"] = metrics.maxAbsError;
    document["mean_abs_luminance_error"] = metrics.meanAbsLuminanceError;
    document["mean_luminance_bias"] = metrics.meanLuminanceBias;
}

// Ends the report with the luminance weights, prints it, and writes it to `path` too unless that is empty.
void report(nlohmann::ordered_json& document, const std::string& path) {
    document["luminance_weights"] = kLuminance;
    std::string text = document.dump(2) + "\n";
    if (!path.empty()) writeBytesAtomic(path, text);
    std::fputs(text.c_str(), stdout);
}

// Reads an image to compare: every pixel finite (a NaN would order no error and index no colour), naming the first
// that is not.
Image readComparedImage(const std::string& path) {
    Image image = readImage(path);
    for (size_t i = 0; i < image.rgb.size(); ++i)
        if (!std::isfinite(image.rgb[i])) {
            const size_t pixel = i / 3;
            throw Error(path, "pixel (" + std::to_string(pixel % size_t(image.width)) + ", " +
                                  std::to_string(pixel / size_t(image.width)) + "), channel " + "RGB"[i % 3],
                        "value is not finite");
        }
    return image;
}

void runCompareImages(const CompareOptions& options) {
    if (fileExtension(options.output) != "png")
        throw Error(options.output, "-o", "with --image the output is the error picture and must end in .png",
                    kExitUsage);
    if (!options.strip.empty() && fileExtension(options.strip) != "png")
        throw Error(options.strip, "--strip", "must end in .png", kExitUsage);
    if (!(options.scaleTop > 0.0)) throw Error("", "--scale", "must be positive", kExitUsage);
    Image result = readComparedImage(options.result), reference = readComparedImage(options.reference);
    if (result.width != reference.width || result.height != reference.height)
        throw Error(options.result, "", std::to_string(result.width) + "x" + std::to_string(result.height) +
                                            " pixels, but " + options.reference + " has " +
                                            std::to_string(reference.width) + "x" + std::to_string(reference.height));
    std::vector<float> mask = coverageMask(options.result);
    ImageComparison comparison = compareImages(result.rgb.data(), reference.rgb.data(),
                                               mask.empty() ? nullptr : mask.data(), result.width, result.height);
    if (comparison.maskPixels == 0)
        throw Error(options.result, "A channel", "covers no pixel (none above 0.5): nothing to compare");
    Picture error = relativeErrorPicture(comparison, options.scaleTop);
    writePicture(options.output, error);
    if (!options.strip.empty())
        writePicture(options.strip,
                     comparisonStrip(tonemappedPicture(result.rgb.data(), result.width, result.height, options.exposure),
                                     tonemappedPicture(reference.rgb.data(), reference.width, reference.height,
                                                       options.exposure),
                                     error));
    const ErrorMetrics& metrics = comparison.metrics;
    nlohmann::ordered_json document = {
        {"result", options.result},
        {"reference", options.reference},
        {"width", result.width},
        {"height", result.height},
        {"mask", mask.empty() ? "every pixel" : "the result's A channel > 0.5"},
    };
    addMetrics(document, metrics);
    document["mean_relative_luminance_error"] = comparison.meanRelativeError;
    document["p95_relative_luminance_error"] = comparison.p95RelativeError;
    document["max_relative_luminance_error"] = comparison.maxRelativeError;
    document["relative_floor"] = comparison.relativeFloor;
    document["picture_scale_top"] = options.scaleTop;
    report(document, options.metricsOutput);
}

void runCompare(const CompareOptions& options) {
    const double start = nowSeconds();
    if (options.image) {
        runCompareImages(options);
        return reportCost("compare", start, 0);
    }
    if (!options.strip.empty()) throw Error("", "--strip", "goes with --image", kExitUsage);
    ErrorMetrics metrics = compareFiles(options.result, options.reference);
    // Non-finite metrics (a flat reference) print as null.
    nlohmann::ordered_json document = {
        {"result", options.result},
        {"reference", options.reference},
    };
    addMetrics(document, metrics);
    report(document, options.output);
    reportCost("compare", start, 0);
}

} // namespace

void addCompareCommand(CLI::App& app) {
    auto options = std::make_shared<CompareOptions>();
    CLI::App* command =
        app.add_subcommand("compare", "Error metrics of per-vertex radiance A against a reference B, as JSON");
    command->add_option("result", options->result, "Result A: .npy [V,3] or .csv rows r,g,b")->required();
    command->add_option("reference", options->reference, "Reference B, same format and vertex order")->required();
    command->add_option("-o,--output", options->output,
                        "Also write the metrics JSON here; with --image, the false-colour error picture (.png)");
    command->add_flag("--image", options->image,
                      "A and B are images (.exr) of one camera: metrics over A's A channel (coverage; every pixel "
                      "without one), -o DIFF.png the relative luminance error in false colour with a legend");
    outputFile(command->add_option("--strip", options->strip, "With --image: also write result | reference | error (.png)"));
    outputFile(command->add_option("--metrics", options->metricsOutput, "With --image: also write the metrics JSON here"));
    command->add_option("--scale", options->scaleTop, "With --image: relative error at the top of the colour scale")
        ->capture_default_str();
    command->add_option("--exposure", options->exposure, "With --image: stops for the strip's tone map (compare.h toneMap)")
        ->capture_default_str();
    optionNeeds(command, "--scale", "--image");
    optionNeeds(command, "--exposure", "--image");
    command->callback([options] { runCompare(*options); });
}

} // namespace prt::cli
