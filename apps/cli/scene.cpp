// prt scene: write a procedural scene with a known answer (lib/scene) as a bundle.
#include "cli.h"

#include "bundle.h"
#include "core.h"
#include "scene.h"

#include <cstdio>
#include <memory>

#ifndef PRT_VERSION
#define PRT_VERSION "0.0.0"
#endif

namespace prt::cli {

namespace {

struct SceneOptions {
    std::string name;
    std::string output;
    bool list = false;
    uint64_t vertices = 0; // 0: the scene's default resolution
};

void runScene(const SceneOptions& options) {
    if (options.list) {
        for (const std::string& name : sceneNames()) std::printf("%s\n", name.c_str());
        return;
    }
    if (options.name.empty() || options.output.empty())
        throw Error("", "scene", "needs a scene NAME and -o OUT.glb (--list shows the names)", kExitUsage);
    if (fileExtension(options.output) != "glb") throw Error(options.output, "-o", "output must be a .glb file", kExitUsage);
    double start = nowSeconds();

    Bundle bundle;
    bundle.mesh = options.vertices > 0 ? makeSceneWithVertices(options.name, options.vertices) : makeScene(options.name);
    bundle.producer = {{"tool", "prt"}, {"version", PRT_VERSION}, {"stage", "scene"}};
    bundle.inputs = {{"scene", options.name}};
    bundle.convention = conventionRecord();
    writeBundle(options.output, bundle);
    logInfo("scene: wrote " + options.name + " (" + std::to_string(bundle.mesh.vertexCount()) + " vertices, " +
            std::to_string(bundle.mesh.triangleCount()) + " triangles) to " + options.output);

    StageCost cost;
    cost.stage = "scene";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addSceneCommand(CLI::App& app) {
    auto options = std::make_shared<SceneOptions>();
    CLI::App* command = app.add_subcommand("scene", "Write a procedural scene with a known answer as a bundle (.glb)");
    command->add_option("name", options->name, "Scene name (see --list)");
    command->add_option("-o,--output", options->output, "Output bundle (.glb)");
    command->add_flag("--list", options->list, "Print the scene names and exit");
    command->add_option("--vertices", options->vertices,
                        "Grow sphere, cavity, sphere-in-cavity or two-spheres to at least N vertices (big-mesh runs)")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 30));
    command->callback([options] { runScene(*options); });
}

} // namespace prt::cli
