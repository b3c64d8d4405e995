// prt envlight: split an environment map into cone lights plus an SH residual, written as prt-lights JSON.
#include "cli.h"

#include "core.h"
#include "envlight.h"
#include "image.h"

#include <cmath>
#include <memory>
#include <vector>

namespace prt::cli {

namespace {

struct EnvlightArgs {
    std::string input;
    std::string output;
    int order = 5;
    int maxLights = 4;
    int minLights = 0;
    double rotateYDegrees = 0.0;
    double elbow = 0.05;
    double minContrast = 1.0;
    int icosphereLevel = 6;
    double smoothingDegrees = 2.0;
    double minRadiusDegrees = 0.1;
    double maxRadiusDegrees = 20.0;
    std::string detectionWindow = "hann";
    bool thesisLights = false;
    double fixedRadiusDegrees = 3.0;
    bool chooseLights = false;
    int plainOrder = 8;
    std::vector<int> residualOrders;
};

void runEnvlight(const EnvlightArgs& args) {
    double start = nowSeconds();
    constexpr double kDegree = M_PI / 180.0;
    if (fileExtension(args.output) != "json") throw Error(args.output, "-o", "output must end in .json", kExitUsage);
    if (args.icosphereLevel < 3 || args.icosphereLevel > 8)
        throw Error("", "--icosphere-level", std::to_string(args.icosphereLevel) + " outside 3..8", kExitUsage);
    if (!(args.smoothingDegrees > 0.0 && args.smoothingDegrees <= 20.0))
        throw Error("", "--smoothing", "FWHM outside (0, 20] degrees", kExitUsage);
    envlight::Options options;
    options.order = args.order;
    options.maxLights = args.maxLights;
    options.minLights = args.minLights;
    options.elbowThreshold = args.elbow;
    options.minContrast = args.minContrast;
    options.icosphereLevel = args.icosphereLevel;
    options.smoothingFwhm = args.smoothingDegrees * kDegree;
    options.minRadius = args.minRadiusDegrees * kDegree;
    options.maxRadius = args.maxRadiusDegrees * kDegree;
    options.detectionWindow = sh::parseWindow(args.detectionWindow, "--detection-window");
    options.refine = !args.thesisLights;
    options.fixedRadius = args.fixedRadiusDegrees * kDegree;
    double R[9];
    sh::rotationY(args.rotateYDegrees, R);
    if (args.rotateYDegrees != 0.0) options.rotation = R;

    EnvironmentMap env = readEnvironmentMap(args.input);
    logInfo("envlight: " + args.input + " (" + std::to_string(env.radiance.width) + "x" +
            std::to_string(env.radiance.height) + "), order " + std::to_string(args.order) + ", at most " +
            std::to_string(args.maxLights) + " lights");
    envlight::Decomposition decomposition;
    envlight::LightChoice choice;
    envlight::ChoiceOptions choiceOptions;
    choiceOptions.plainOrder = args.plainOrder;
    choiceOptions.residualOrders = args.residualOrders;
    if (!args.residualOrders.empty() && !args.chooseLights)
        throw Error("", "--residual-orders", "needs --choose-lights", kExitUsage);
    for (int order : args.residualOrders)
        if (order < 1 || order >= choiceOptions.errorOrder)
            throw Error("", "--residual-orders", std::to_string(order) + " outside 1.." +
                                                     std::to_string(choiceOptions.errorOrder - 1), kExitUsage);
    try {
        decomposition = args.chooseLights ? envlight::decomposeChoosingLights(env, options, choiceOptions, &choice)
                                          : envlight::decompose(env, options);
    } catch (const Error& e) {
        if (!e.file().empty() || e.exitCode() != kExitInput) throw;
        throw Error(args.input, e.place(), e.problem(), e.exitCode());
    }
    nlohmann::ordered_json document = envlight::lightsDocument(decomposition, options, args.input, hashFile(args.input));
    document["rotate_y_degrees"] = args.rotateYDegrees;
    if (args.chooseLights) {
        document["choice"] = {{"lights", choice.lights},
                              {"residual_order", choice.order},
                              {"plain_sh", choice.plainSh},
                              {"plain_order", args.plainOrder},
                              {"errors", choice.errors},
                              {"orders_tried", choice.orders},
                              {"errors_by_order", choice.errorsByOrder},
                              {"plain_error", choice.plainError},
                              {"band_width", choiceOptions.bandWidth},
                              {"bands", choice.bands},
                              {"plain_bands", choice.plainBands},
                              {"reason", choice.reason}};
        logInfo("envlight: " + choice.reason);
    }
    writeBytesAtomic(args.output, document.dump(2) + "\n");
    for (const envlight::ConeLight& light : decomposition.lights) {
        char line[200];
        std::snprintf(line, sizeof line, "envlight: light towards (%.4f, %.4f, %.4f), radius %.3f deg, radiance (%.4g, %.4g, %.4g)",
                      light.direction[0], light.direction[1], light.direction[2], light.angularRadius / kDegree,
                      light.radiance[0], light.radiance[1], light.radiance[2]);
        logInfo(line);
    }
    logInfo("envlight: wrote " + args.output + " (" + std::to_string(decomposition.lights.size()) + " lights)");

    StageCost cost;
    cost.stage = "envlight";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addEnvlightCommand(CLI::App& app) {
    auto args = std::make_shared<EnvlightArgs>();
    CLI::App* command = app.add_subcommand(
        "envlight", "Split an environment map into cone lights plus an SH residual (prt-lights JSON)");
    command->add_option("env", args->input, "Environment map: 2:1 equirectangular or 1:6 cube strip")->required();
    command->add_option("-o,--output", args->output, "Output prt-lights JSON")->required();
    command->add_option("--order", args->order, "SH bands L of the residual (L*L coefficients; default 5)");
    command->add_option("--max-lights", args->maxLights, "At most this many lights K (default 4)");
    command->add_option("--min-lights", args->minLights, "Fail (exit 3) unless at least this many lights are found");
    command->add_option("--rotate-y", args->rotateYDegrees, "Turn the environment by this many degrees about +Y first")
        ->check(CLI::Range(-360.0, 360.0));
    command->add_option("--elbow", args->elbow, "Weber-law elbow threshold in [0, 1) (default 0.05)");
    command->add_option("--min-contrast", args->minContrast,
                        "A peak's smoothed residual must reach this times the mean luminance (default 1)");
    command->add_option("--icosphere-level", args->icosphereLevel, "Detection icosphere level 3..8 (default 6)");
    command->add_option("--smoothing", args->smoothingDegrees, "Detection spherical-Gaussian FWHM in degrees (default 2)");
    command->add_option("--min-radius", args->minRadiusDegrees, "Smallest cone half-angle in degrees (default 0.1)");
    command->add_option("--max-radius", args->maxRadiusDegrees, "Largest cone half-angle in degrees (default 20)");
    command->add_option("--detection-window", args->detectionWindow, "Window of the detection SH: none, hann, lanczos");
    command->add_flag("--thesis-lights", args->thesisLights,
                      "The thesis's lights instead of the bounded fit: fixed radius, peak residual radiance");
    command->add_option("--fixed-radius", args->fixedRadiusDegrees, "Cone half-angle of --thesis-lights, degrees (default 3)");
    command->add_flag("--choose-lights", args->chooseLights,
                      "Choose K per map (at most --max-lights; up to 16 is sensible) from the decomposition's own "
                      "band-weighted error, and the residual order among --residual-orders; 0 lights and a 'plain "
                      "SH' verdict (residual at --plain-order) when no configuration beats plain SH at --plain-order");
    command->add_option("--plain-order", args->plainOrder, "The plain SH order --choose-lights compares with (default 8)");
    command->add_option("--residual-orders", args->residualOrders,
                        "Residual orders --choose-lights tries with the lights (default: --order and --plain-order); "
                        "it keeps the (order, K) of least predicted error")
        ->delimiter(',');
    optionNeeds(command, "--fixed-radius", "--thesis-lights");
    optionNeeds(command, "--plain-order", "--choose-lights");
    command->callback([args] { runEnvlight(*args); });
}

} // namespace prt::cli
