// prt autoconfig: the cheapest bake and smallest bundle under a target error against the reference, written as a
// pipeline file for `prt run` (lib/autoconfig does the search).
#include "cli.h"

#include "autoconfig.h"
#include "core.h"
#include "image.h"

#include <cstdio>
#include <filesystem>
#include <memory>

namespace prt::cli {

namespace {

struct AutoconfigArgs {
    std::string mesh, output, bundle, report, name, albedo = "0.8";
    std::vector<std::string> envs;
    double targetError = 0.0, margin = 0.9;
    std::vector<int> orders = {2, 3, 4, 5, 6, 7, 8}, samples = {64, 128, 256, 512, 1024}, bounces = {0, 1, 2, 3};
    std::vector<std::string> formats = {"float", "half", "u16", "u8"};
    std::vector<int> lights = {0, 4};
    int pilotVertices = 256, referenceBounces = 3, maxReferenceSamples = 65536, threads = 0;
    uint64_t seed = 0;
};

void runAutoconfig(const AutoconfigArgs& args, const CLI::App& command) {
    double start = nowSeconds();
    if (command.count("--target-error") == 0) throw Error("", "--target-error", "is needed", kExitUsage);
    if (!(args.targetError > 0.0))
        throw Error("", "--target-error", "must be > 0 (a relative RMSE, e.g. 0.02 for 2%)", kExitUsage);
    if (fileExtension(args.output) != "toml") throw Error(args.output, "-o", "output must end in .toml", kExitUsage);
    if (args.envs.empty()) throw Error("", "--env", "needs at least one environment map", kExitUsage);
    if (args.pilotVertices < 1) throw Error("", "--pilot-vertices", "must be >= 1", kExitUsage);
    if (args.seed > (uint64_t(1) << 53)) throw Error("", "--seed", "must be a whole number from 0 to 2^53", kExitUsage);

    autoconfig::Options options;
    options.targetError = args.targetError;
    options.orders = args.orders;
    options.samples = args.samples;
    options.lights = args.lights;
    options.bounces = args.bounces;
    options.formats.clear();
    for (const std::string& format : args.formats) options.formats.push_back(adapt::parseFormat(format));
    options.albedo = parseAlbedo(args.albedo);
    options.seed = args.seed;
    options.pilotVertices = size_t(args.pilotVertices);
    options.referenceBounces = args.referenceBounces;
    options.referenceMaxSamples = args.maxReferenceSamples;
    options.referenceMinSamples = std::min(1024, args.maxReferenceSamples);
    options.margin = args.margin;
    options.threads = resolveThreads(args.threads);

    TriMesh mesh = readBundle(args.mesh).mesh;
    if (mesh.normals.size() != mesh.positions.size())
        throw Error(args.mesh, "", "mesh has no vertex normals (prt meshprep adds them)");
    std::vector<EnvironmentMap> envs;
    std::vector<std::string> names;
    for (const std::string& env : args.envs) {
        envs.push_back(readEnvironmentMap(env));
        names.push_back(std::filesystem::path(env).stem().string());
    }
    logInfo("autoconfig: " + args.mesh + " (" + std::to_string(mesh.vertexCount()) + " vertices), target " +
            std::to_string(args.targetError) + " under " + std::to_string(envs.size()) + " map(s)");
    autoconfig::Result result = autoconfig::autoconfigure(mesh, envs, names, options);

    // The Pareto front on stderr: cost against predicted error.
    logInfo("autoconfig: Pareto front (modelled bake Mray equivalents and seconds, transfer-layer bytes, predicted error):");
    for (size_t i : result.pareto) {
        const autoconfig::Candidate& c = result.candidates[i];
        char line[200];
        std::snprintf(line, sizeof line, "  order %d  samples %5d  bounces %d  %-5s  adaptive %-8.4g  lights %d  %9.4g M  "
                      "%8.3g s  %10llu B  %.4g", c.config.order, c.config.samples, c.config.bounces,
                      adapt::formatName(c.config.format), c.config.adaptiveError, c.config.lights, c.bakeCost * 1e-6,
                      c.bakeSeconds,
                      (unsigned long long)c.bundleBytes, c.pilotError);
        logInfo(line);
    }
    const std::string bundle = args.bundle.empty()
                                   ? "out/autoconfig/" + std::filesystem::path(args.mesh).stem().string() + ".prt.glb"
                                   : args.bundle;
    const std::string name = args.name.empty() ? std::filesystem::path(args.output).stem().string() : args.name;
    const std::string toml = autoconfig::pipelineToml(result, options, args.mesh, args.envs, bundle, name);
    const std::string report = autoconfig::reportJson(result, options);
    if (!args.report.empty()) writeBytesAtomic(args.report, report);
    writeBytesAtomic(args.output, toml);
    const autoconfig::Candidate& c = result.chosen;
    char line[320];
    std::snprintf(line, sizeof line,
                  "autoconfig: chose order %d, %d samples, %d bounces, %s, %d lights: predicted %.4g, held out %.4g, "
                  "final check %.4g (target %.4g); wrote %s in %.1f s",
                  c.config.order, c.config.samples, c.config.bounces, adapt::formatName(c.config.format), c.config.lights,
                  c.pilotError, c.heldOutError, c.checkError, args.targetError, args.output.c_str(),
                  nowSeconds() - start);
    logInfo(line);

    reportCost("autoconfig", start, result.rays);
}

} // namespace

void addAutoconfigCommand(CLI::App& app) {
    auto args = std::make_shared<AutoconfigArgs>();
    CLI::App* command = app.add_subcommand(
        "autoconfig", "Choose order, samples, bounces and storage format for a target error; write a pipeline");
    command->add_option("mesh", args->mesh, "Mesh (.glb/.gltf) with vertex normals")->required();
    command->add_option("--env", args->envs, "Environment maps the error is measured under (repeat)")->required();
    command->add_option("--target-error", args->targetError,
                        "Relative RMSE against `prt reference` to stay under, noise-corrected (> 0)");
    command->add_option("-o,--output", args->output, "Pipeline file (.toml) for `prt run`")->required();
    command->add_option("--bundle", args->bundle,
                        "Where the pipeline puts the bundle (default out/autoconfig/MESH.prt.glb)");
    outputFile(command->add_option("--report", args->report, "Also write the search (Pareto front, choice, times) as JSON"));
    command->add_option("--name", args->name, "Pipeline name (default: the output's stem)");
    command->add_option("--albedo", args->albedo, "Diffuse albedo R,G,B or one grey value (default 0.8)");
    command->add_option("--seed", args->seed, "Seed of transfer directions, reference paths and subsets (default 0)");
    command->add_option("--orders", args->orders, "SH orders to search (comma list)")->delimiter(',');
    command->add_option("--samples", args->samples, "Transfer samples to search (comma list)")->delimiter(',');
    command->add_option("--bounces", args->bounces, "Bounces to search (comma list; 0 = shadowed)")->delimiter(',');
    command->add_option("--formats", args->formats, "Storage formats to search: float, half, u16, u8")->delimiter(',');
    command->add_option("--lights", args->lights,
                        "Extracted cone lights to search, the most per map (comma list; 0: plain SH; default 0,4)")
        ->delimiter(',');
    command->add_option("--pilot-vertices", args->pilotVertices,
                        "Pilot vertices, and as many held out and as many for the final check (default 256, at most a third "
                        "of the mesh each)");
    command->add_option("--reference-bounces", args->referenceBounces, "Bounces of the reference (default 3)");
    command->add_option("--max-reference-samples", args->maxReferenceSamples,
                        "Most paths per vertex of the pilot reference (default 65536)");
    command->add_option("--margin", args->margin,
                        "Choose only configurations predicted at or under margin x target (default 0.9)");
    command->add_option("--threads", args->threads, "Worker threads (0: all cores)");
    command->callback([args, command] { runAutoconfig(*args, *command); });
}

} // namespace prt::cli
