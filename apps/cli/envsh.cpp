// prt envsh: project an environment map onto SH radiance coefficients, written as prt-sh JSON.
#include "cli.h"

#include "core.h"
#include "image.h"
#include "sh.h"

#include <nlohmann/json.hpp>

#include <memory>

namespace prt::cli {

namespace {

struct EnvshOptions {
    std::string input;
    std::string output;
    int order = 3;
    double rotateYDegrees = 0.0;
    std::string window = "none";
};

void runEnvsh(const EnvshOptions& options) {
    double start = nowSeconds();
    if (options.order < 1 || options.order > sh::kMaxOrder)
        throw Error("", "--order", "order " + std::to_string(options.order) + " outside 1.." +
                                       std::to_string(sh::kMaxOrder), kExitUsage);
    sh::Window window = sh::parseWindow(options.window);

    EnvironmentMap env = readEnvironmentMap(options.input);
    logInfo("envsh: " + options.input + " (" + std::to_string(env.radiance.width) + "x" +
            std::to_string(env.radiance.height) + ") to order " + std::to_string(options.order));
    std::vector<float> coeffs = sh::projectEnvironment(env, options.order);
    if (options.rotateYDegrees != 0.0) {
        double R[9];
        sh::rotationY(options.rotateYDegrees, R);
        std::vector<float> rotated(coeffs.size());
        sh::rotate(sh::rotation(options.order, R), coeffs.data(), rotated.data(), 3);
        coeffs.swap(rotated);
    }
    sh::applyWindow(window, options.order, coeffs.data(), 3);
    requireFiniteResult(coeffs.data(), coeffs.size(), 3, options.output);

    nlohmann::ordered_json coefficients = nlohmann::ordered_json::array();
    for (size_t i = 0; i < coeffs.size(); i += 3) coefficients.push_back({coeffs[i], coeffs[i + 1], coeffs[i + 2]});
    nlohmann::ordered_json document = {
        {"format", "prt-sh"},
        {"version", 1},
        {"order", options.order},
        {"coefficients", coefficients},
        {"convention",
         {{"basis", "real orthonormal spherical harmonics, RGB radiance, [coefficient][channel]"},
          {"index", "i = l*l + l + m, m from -l to l"},
          {"condon_shortley", false},
          {"axes", "Y_1,-1 ~ y, Y_1,0 ~ z, Y_1,1 ~ x"},
          {"world", "right-handed Y-up"},
          {"equirect", "pixel (x, y) of W x H: theta = pi (y + 0.5) / H from +Y, phi = 2 pi (x + 0.5) / W - pi, "
                       "d = (sin theta sin phi, cos theta, -sin theta cos phi)"}}},
        {"layout", env.layout == EnvLayout::Equirectangular ? "equirectangular" : "cube strip"},
        {"window", sh::windowName(window)},
        {"rotate_y_degrees", options.rotateYDegrees},
        {"input", {{"path", options.input}, {"hash", hashFile(options.input)}}},
        {"band_energy", sh::bandEnergy(options.order, coeffs.data(), 3)},
    };
    writeBytesAtomic(options.output, document.dump(2) + "\n");
    logInfo("envsh: wrote " + options.output);

    StageCost cost;
    cost.stage = "envsh";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addEnvshCommand(CLI::App& app) {
    auto options = std::make_shared<EnvshOptions>();
    CLI::App* command = app.add_subcommand("envsh", "Project an environment map (EXR) onto SH radiance coefficients");
    command->add_option("env", options->input, "Environment map: 2:1 equirectangular or 1:6 cube strip")
        ->required();
    command->add_option("--order", options->order, "Number of SH bands L (L*L coefficients), 1.." +
                                                       std::to_string(sh::kMaxOrder))
        ->required();
    command->add_option("-o,--output", options->output, "Output prt-sh JSON")->required();
    command->add_option("--rotate-y", options->rotateYDegrees,
                        "Rotate the lighting by this many degrees about +Y (right-handed) before writing")
        ->check(CLI::Range(-360.0, 360.0));
    command->add_option("--window", options->window, "Band window against ringing: none, hann or lanczos");
    command->callback([options] { runEnvsh(*options); });
}

} // namespace prt::cli
