// The prt-lights JSON document that `prt envlight` writes and the runtime reads (readHybridLightingJson).
#include "envlight.h"

#include "core.h"
#include "json_input.h"

#include <cmath>

namespace prt::envlight {

nlohmann::ordered_json lightsDocument(const Decomposition& decomposition, const Options& options,
                                      const std::string& inputPath, const std::string& inputHash) {
    nlohmann::ordered_json lights = nlohmann::ordered_json::array();
    double lightPower = 0.0;
    for (const ConeLight& light : decomposition.lights) {
        double solidAngle = coneSolidAngle(light.angularRadius);
        std::array<double, 3> power;
        for (int c = 0; c < 3; ++c) power[c] = light.radiance[c] * solidAngle;
        lightPower += kLuminance[0] * power[0] + kLuminance[1] * power[1] + kLuminance[2] * power[2];
        lights.push_back({{"direction", light.direction},
                          {"radiance", light.radiance},
                          {"angular_radius", light.angularRadius},
                          {"angular_radius_degrees", light.angularRadius * 180.0 / M_PI},
                          {"solid_angle", solidAngle},
                          {"power", power}});
    }
    nlohmann::ordered_json residual = nlohmann::ordered_json::array();
    for (size_t j = 0; j < decomposition.residual.size(); j += 3)
        residual.push_back({decomposition.residual[j], decomposition.residual[j + 1], decomposition.residual[j + 2]});
    return {
        {"format", "prt-lights"},
        {"version", 1},
        {"order", decomposition.order},
        {"lights", lights},
        {"residual", residual},
        {"convention",
         {{"direction", "unit vector from the scene towards the light, world right-handed Y-up"},
          {"radiance", "RGB radiance, uniform inside the cone, in the environment map's units"},
          {"angular_radius", "half-angle of the cone in radians; solid angle = 2 pi (1 - cos r)"},
          {"power", "radiance * solid angle: irradiance at normal incidence from the whole cone"},
          {"residual", "real orthonormal SH radiance coefficients [coefficient][channel], index l*l + l + m, no "
                       "Condon-Shortley phase: projection of the map minus the lights' exact projections"},
          {"luminance", "Rec.709 0.2126 R + 0.7152 G + 0.0722 B"}}},
        {"input", {{"path", inputPath}, {"hash", inputHash}}},
        {"options",
         {{"max_lights", options.maxLights},
          {"min_lights", options.minLights},
          {"icosphere_level", options.icosphereLevel},
          {"smoothing_fwhm_degrees", options.smoothingFwhm * 180.0 / M_PI},
          {"detection_window", sh::windowName(options.detectionWindow)},
          {"elbow_threshold", options.elbowThreshold},
          {"min_contrast", options.minContrast},
          {"radius_bounds_degrees", {options.minRadius * 180.0 / M_PI, options.maxRadius * 180.0 / M_PI}},
          {"refine", options.refine},
          {"outer_iterations", options.outerIterations}}},
        {"diagnostics",
         {{"candidates", decomposition.candidates.size()},
          {"elbow", decomposition.elbow},
          {"mean_luminance", decomposition.meanLuminance},
          {"environment_power", decomposition.environmentPower},
          {"light_power_fraction", lightPower / decomposition.environmentPower},
          {"ceres_iterations", decomposition.fit.ceresIterations},
          {"ceres_initial_cost", decomposition.fit.initialCost},
          {"ceres_final_cost", decomposition.fit.finalCost},
          {"ceres_termination", decomposition.fit.termination},
          {"dropped_lights", decomposition.fit.droppedLights}}},
    };
}

void checkLightsInput(const std::string& lightsPath, const std::string& envPath) {
    nlohmann::json document = readJsonFile(lightsPath, kMaxLightsJsonBytes);
    const std::string actual = hashFile(envPath);
    const nlohmann::json* found = document.is_object() && document.contains("input") ? &document["input"] : nullptr;
    if (!found || (found->is_object() && !found->contains("hash")))
        throw Error(lightsPath, "input.hash",
                    "records no input hash, so it cannot be checked against --env " + envPath + " (" + actual +
                        "); write the lights again with `prt envlight`, or leave out --env");
    const nlohmann::json& input = *found;
    const std::string recorded = jsonString(input, "hash", lightsPath, "input"); // typed: an object with a string
    if (recorded == actual) return;
    std::string from = input.contains("path") && input["path"].is_string()
                           ? jsonExcerpt(input["path"]) + " (" + jsonExcerpt(input["hash"]) + ")"
                           : jsonExcerpt(input["hash"]);
    throw Error(lightsPath, "input.hash",
                "the lights were made from " + from + ", not from " + envPath + " (" + actual + ")");
}

} // namespace prt::envlight
