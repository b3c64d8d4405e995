// What autoconfig hands on: the chosen configuration as a pipeline file `prt run` executes, and the search as JSON.
#include "autoconfig.h"

#include "core.h"

#include <nlohmann/json.hpp>

#include <cctype>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <set>
#include <cstring>

namespace prt::autoconfig {

namespace {

std::string quoted(const std::string& text) { return nlohmann::json(text).dump(); } // a TOML basic string

// The shortest text that reads back as the same double.
std::string number(double value) {
    char text[64];
    auto [end, ec] = std::to_chars(text, text + sizeof text, value);
    std::string s(text, end);
    if (s.find_first_of(".eE") == std::string::npos) s += ".0"; // a TOML float, not an integer
    return s;
}

// A TOML bare key from a file stem: letters, digits, '-' and '_' kept, anything else as '-'.
std::string bareKey(const std::string& text) {
    std::string key;
    for (char c : text) key += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '-';
    return key.empty() ? "map" : key;
}

nlohmann::json candidateJson(const Candidate& c) {
    nlohmann::json j = {{"order", c.config.order},
                        {"samples", c.config.samples},
                        {"bounces", c.config.bounces},
                        {"format", adapt::formatName(c.config.format)},
                        {"adaptive_error", c.config.adaptiveError},
                        {"lights", c.config.lights},
                        {"bake_cost", c.bakeCost},
                        {"bake_seconds", c.bakeSeconds},
                        {"bundle_bytes", c.bundleBytes},
                        {"pilot_error", c.pilotError}};
    if (c.heldOutError >= 0.0) j["held_out_error"] = c.heldOutError;
    if (c.checkError >= 0.0) j["check_error"] = c.checkError;
    return j;
}

} // namespace

std::string pipelineToml(const Result& result, const Options& options, const std::string& meshPath,
                         const std::vector<std::string>& envPaths, const std::string& bundlePath,
                         const std::string& name) {
    const Config& c = result.chosen.config;
    std::string noise;
    for (size_t m = 0; m < result.referenceNoise.size() && m < envPaths.size(); ++m) {
        char text[64];
        // The map by its key's name: a file stem may hold a newline, which would end the comment.
        std::snprintf(text, sizeof text, "%s%s %.4g", m ? ", " : "",
                      bareKey(std::filesystem::path(envPaths[m]).stem().string()).c_str(), result.referenceNoise[m]);
        noise += text;
    }
    char head[1600];
    std::snprintf(head, sizeof head,
                  "# Written by `prt autoconfig`: the cheapest bake and smallest bundle whose relative error against\n"
                  "# `prt reference` (%d bounces, albedo %s,%s,%s; reference noise taken out) is under the target.\n"
                  "#   target error           %.6g\n"
                  "#   chosen                 order %d, %d samples, %d bounces, %s storage, adaptive budget %.4g, "
                  "lights %d\n"
                  "#   predicted (pilot)      %.6g on %zu vertices\n"
                  "#   verified (held out)    %.6g on %zu other vertices\n"
                  "#   final check            %.6g on %zu vertices no choice looked at\n"
                  "#   reference              %d paths per vertex; relative noise %s\n"
                  "#   modelled cost          bake %.4g Mray equivalents, transfer layers %llu bytes\n"
                  "#   searched               %zu configurations, %zu on the Pareto front, %zu verified\n"
                  "# Run it with: prt run THIS_FILE (paths are relative to the directory prt run starts in)\n\n",
                  options.referenceBounces, number(options.albedo[0]).c_str(), number(options.albedo[1]).c_str(),
                  number(options.albedo[2]).c_str(), options.targetError, c.order, c.samples, c.bounces,
                  adapt::formatName(c.format), c.adaptiveError, c.lights, result.chosen.pilotError, result.pilot.size(),
                  result.chosen.heldOutError, result.heldOut.size(), result.chosen.checkError, result.check.size(),
                  result.referenceSamples, noise.c_str(),
                  result.chosen.bakeCost * 1e-6, (unsigned long long)result.chosen.bundleBytes, result.candidates.size(),
                  result.pareto.size(), result.tried.size());
    std::string t = head;
    t += "[pipeline]\nname = " + quoted(bareKey(name)) + "\n";
    t += "description = " + quoted("autoconfig to relative error " + number(options.targetError)) + "\n\n";
    t += "[inputs]\nmesh = { mesh = " + quoted(meshPath) + " }\n";
    std::vector<std::string> envKeys;
    std::set<std::string> used = {"mesh"};
    for (size_t m = 0; m < envPaths.size(); ++m) {
        std::string key = "env-";
        key += bareKey(std::filesystem::path(envPaths[m]).stem().string());
        while (used.count(key)) key.append(1, '-').append(std::to_string(m));
        used.insert(key);
        envKeys.push_back(key);
        t += key + " = { env = " + quoted(envPaths[m]) + " }\n";
    }
    t += "\n[stages.transfer]\nrun = \"transfer\"\ninputs = { mesh = \"mesh\" }\n";
    t += c.bounces > 0 ? "mode = \"interreflected\"\n" : "mode = \"shadowed\"\n";
    t += "order = " + std::to_string(c.order) + "\nsamples = " + std::to_string(c.samples) + "\n";
    if (c.bounces > 0) t += "bounces = " + std::to_string(c.bounces) + "\n";
    t += "albedo = [" + number(options.albedo[0]) + ", " + number(options.albedo[1]) + ", " +
         number(options.albedo[2]) + "]\nseed = " + std::to_string(options.seed) + "\n";
    std::string bundleStage = "transfer";
    // Adaptive: `prt adapt`'s graded orders (max-step 1, its default), re-checked against the per-vertex bound. The
    // pilot predicted the ungraded orders; grading only raises orders where the bound allows, so the error stays
    // within the budget and the bytes are at least the predicted ones.
    if (c.adaptiveError > 0.0) {
        bundleStage = "adapt";
        t += "\n[stages.adapt]\nrun = \"adapt\"\ninputs = { bundle = \"transfer\", env = \"" + envKeys[0] +
             "\" }\nmax-error = " + number(c.adaptiveError) + "\nformat = " + quoted(adapt::formatName(c.format)) +
             "\n";
    } else if (c.lights == 0 && (c.format != adapt::Format::Float || c.bounces > 0)) { // drops transfer_bounce
        bundleStage = "adapt";
        t += "\n[stages.adapt]\nrun = \"adapt\"\ninputs = { bundle = \"transfer\" }\norder = " +
             std::to_string(c.order) + "\nformat = " + quoted(adapt::formatName(c.format)) + "\n";
    }
    for (size_t m = 0; m < envKeys.size(); ++m) {
        const std::string map = envKeys[m].substr(4);
        if (c.lights > 0) { // the hybrid: each map's cone lights and residual feed its relight
            t += "\n[stages.lights-" + map + "]\nrun = \"envlight\"\ninputs = { env = \"" + envKeys[m] +
                 "\" }\norder = " + std::to_string(c.order) + "\nmax-lights = " + std::to_string(c.lights) + "\n";
            t += "\n[stages.relight-" + map + "]\nrun = \"relight\"\ninputs = { bundle = \"" + bundleStage +
                 "\", lights = \"lights-" + map + "\" }\nlight-samples = " + std::to_string(options.lightSamples) + "\n";
        } else {
            t += "\n[stages.relight-" + map + "]\nrun = \"relight\"\ninputs = { bundle = \"" + bundleStage +
                 "\", env = \"" + envKeys[m] + "\" }\n";
        }
    }
    std::filesystem::path bundle(bundlePath);
    std::string stem = bundle.filename().string();
    for (const char* suffix : {".glb", ".prt"})
        if (stem.size() > std::strlen(suffix) && stem.ends_with(suffix)) stem.resize(stem.size() - std::strlen(suffix));
    t += "\n[outputs]\nbundle = { from = \"" + bundleStage + "\", path = " + quoted(bundlePath) + " }\n";
    for (size_t m = 0; m < envKeys.size(); ++m) {
        std::string map = envKeys[m].substr(4);
        t += "radiance-" + map + " = { from = \"relight-" + map + "\", path = " +
             quoted((bundle.parent_path() / (stem + "." + map + ".npy")).string()) + " }\n";
    }
    return t;
}

std::string reportJson(const Result& result, const Options& options) {
    nlohmann::json pareto = nlohmann::json::array(), tried = nlohmann::json::array();
    for (size_t i : result.pareto) pareto.push_back(candidateJson(result.candidates[i]));
    for (size_t i : result.tried) tried.push_back(candidateJson(result.candidates[i]));
    nlohmann::json report = {{"target_error", options.targetError},
                             {"margin", options.margin},
                             {"chosen", candidateJson(result.chosen)},
                             {"tried", tried},
                             {"pareto", pareto},
                             {"configurations", result.candidates.size()},
                             {"pilot_vertices", result.pilot.size()},
                             {"held_out_vertices", result.heldOut.size()},
                             {"check_vertices", result.check.size()},
                             {"reference_samples", result.referenceSamples},
                             {"reference_bounces", options.referenceBounces},
                             {"reference_noise", result.referenceNoise},
                             {"reference_seconds", result.referenceSeconds},
                             {"pilot_transfer_seconds", result.pilotTransferSeconds},
                             {"seconds", result.seconds}};
    return report.dump(1) + "\n";
}

} // namespace prt::autoconfig
