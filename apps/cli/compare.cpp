// prt compare: error metrics of a per-vertex result against a reference, as JSON.
#include "cli.h"

#include "compare.h"
#include "core.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>

namespace prt::cli {

namespace {

struct CompareOptions {
    std::string result;
    std::string reference;
    std::string output;
};

void runCompare(const CompareOptions& options) {
    ErrorMetrics metrics = compareFiles(options.result, options.reference);
    // Non-finite metrics (a flat reference) print as null.
    nlohmann::ordered_json document = {
        {"result", options.result},
        {"reference", options.reference},
        {"count", metrics.count},
        {"rmse", metrics.rmse},
        {"relative_rmse", metrics.relativeRmse},
        {"nrmse", metrics.nrmse},
        {"max_abs_error", metrics.maxAbsError},
        {"mean_abs_luminance_error", metrics.meanAbsLuminanceError},
        {"mean_luminance_bias", metrics.meanLuminanceBias},
        {"luminance_weights", kLuminanceWeights},
    };
    std::string text = document.dump(2) + "\n";
    if (!options.output.empty()) writeBytesAtomic(options.output, text);
    std::fputs(text.c_str(), stdout);
}

} // namespace

void addCompareCommand(CLI::App& app) {
    auto options = std::make_shared<CompareOptions>();
    CLI::App* command =
        app.add_subcommand("compare", "Error metrics of per-vertex radiance A against a reference B, as JSON");
    command->add_option("result", options->result, "Result A: .npy [V,3] or .csv rows r,g,b")->required();
    command->add_option("reference", options->reference, "Reference B, same format and vertex order")->required();
    command->add_option("-o,--output", options->output, "Also write the metrics JSON here");
    command->callback([options] { runCompare(*options); });
}

} // namespace prt::cli
