// prt relight: per-vertex (or, with --texels, per-texel) outgoing radiance of a bundle's transfer under an
// environment map or SH lighting.
#include "cli.h"

#include "compare.h"
#include "core.h"
#include "runtime.h"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>

namespace prt::cli {

namespace {

struct RelightOptions {
    std::string bundle;
    std::string env;
    std::string shJson;
    double rotateYDegrees = 0.0;
    std::string window = "none";
    std::string output;
    bool texels = false;
    std::string eye; // "X,Y,Z": add the glossy lobes' radiance toward this point
    bool glossyOnly = false;
};

void runRelight(const RelightOptions& options) {
    double start = nowSeconds();
    sh::Window window = sh::parseWindow(options.window);
    // writeVertexRadiance checks this too, but only after the work; a typo should fail at once.
    std::string outputExtension = fileExtension(options.output);
    if (options.texels && outputExtension != "exr")
        throw Error(options.output, "-o", "with --texels the output is an atlas image and must end in .exr",
                    kExitUsage);
    if (!options.texels && outputExtension != "npy" && outputExtension != "csv")
        throw Error(options.output, "-o", "output must end in .npy or .csv", kExitUsage);

    if (!options.eye.empty() && (options.texels || options.env.empty()))
        throw Error("", "--eye", "needs --env (an equirectangular map) and per-vertex output", kExitUsage);
    if (!options.eye.empty() && options.rotateYDegrees != 0.0)
        throw Error("", "--eye", "does not combine with --rotate-y", kExitUsage);
    TexelRelightModel texelModel;
    std::optional<GlossyModel> glossy;
    RelightModel model;
    if (options.texels) {
        texelModel = loadTexelRelightModel(options.bundle);
        model = std::move(texelModel.rows);
    } else if (!options.eye.empty()) {
        Bundle bundle = readBundle(options.bundle);
        glossy = glossyModel(bundle, options.bundle);
        model = relightModel(std::move(bundle), options.bundle);
    } else {
        model = loadRelightModel(options.bundle);
    }
    const int coefficients = sh::coefficientCount(model.order);
    double R[9];
    sh::rotationY(options.rotateYDegrees, R);
    const double* rotation = options.rotateYDegrees != 0.0 ? R : nullptr;

    // Same order of operations as `prt envsh`: project, rotate, window; windowed over the transfer's bands.
    std::vector<float> lighting;
    EnvironmentMap environment;
    if (!options.env.empty()) {
        environment = readEnvironmentMap(options.env);
        lighting = environmentLighting(environment, model.order, rotation, window);
    } else {
        int lightingOrder = 0;
        std::vector<float> read = readLightingJson(options.shJson, &lightingOrder);
        if (lightingOrder != model.order)
            logInfo("relight: lighting has order " + std::to_string(lightingOrder) + ", transfer order " +
                    std::to_string(model.order) + "; using their common " +
                    std::to_string(std::min(lightingOrder, model.order)) + " bands");
        lighting = fitLighting(read.data(), sh::coefficientCount(lightingOrder), coefficients);
        if (rotation) lighting = rotateLighting(lighting.data(), model.order, rotation);
        sh::applyWindow(window, model.order, lighting.data(), 3);
    }

    double relightStart = nowSeconds();
    std::vector<float> radiance(size_t(model.vertexCount) * 3);
    relight(model, lighting.data(), 0, model.vertexCount, radiance.data());
    double relightSeconds = nowSeconds() - relightStart;
    char rate[160];
    const char* rows = options.texels ? "texels" : "vertices";
    std::snprintf(rate, sizeof rate, "relight: %u %s at order %d in %.3f ms (%.1f M%s/s)", model.vertexCount, rows,
                  model.order, relightSeconds * 1e3,
                  relightSeconds > 0.0 ? model.vertexCount / relightSeconds / 1e6 : 0.0, rows);
    logInfo(rate);

    if (glossy) {
        if (environment.layout != EnvLayout::Equirectangular)
            throw Error(options.env, "--env", "the glossy runtime needs an equirectangular (2:1) map");
        std::array<float, 3> eye = parsePoint(options.eye, "--eye");
        double glossyStart = nowSeconds();
        PrefilteredEnvironment prefiltered = prefilterEnvironment(
            environment.radiance.rgb.data(), environment.radiance.width, environment.radiance.height);
        std::vector<float> glossyPart(radiance.size());
        glossyRadiance(*glossy, prefiltered, eye.data(), glossyPart.data());
        for (size_t i = 0; i < radiance.size(); ++i) radiance[i] = (options.glossyOnly ? 0.0f : radiance[i]) + glossyPart[i];
        char line[160];
        std::snprintf(line, sizeof line, "relight: glossy lobes (%d per view) toward the eye in %.3f ms", glossy->lobes,
                      (nowSeconds() - glossyStart) * 1e3);
        logInfo(line);
    }

    if (options.texels) {
        Image image;
        image.width = texelModel.width;
        image.height = texelModel.height;
        image.rgb = std::move(radiance);
        writeImage(options.output, image); // float EXR, atomic
    } else {
        writeVertexRadiance(options.output, radiance);
    }
    logInfo("relight: wrote " + options.output);

    StageCost cost;
    cost.stage = "relight";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addRelightCommand(CLI::App& app) {
    auto options = std::make_shared<RelightOptions>();
    CLI::App* command =
        app.add_subcommand("relight", "Per-vertex (or per-texel) radiance of a bundle's transfer under new lighting");
    command->add_option("bundle", options->bundle, "Bundle (.glb) with a \"transfer\" layer")->required();
    CLI::Option_group* lighting = command->add_option_group("lighting", "Where the lighting comes from");
    lighting->add_option("--env", options->env, "Environment map: 2:1 equirect or 1:6 cube strip");
    lighting->add_option("--sh", options->shJson, "SH lighting as `prt envsh` writes it (prt-sh JSON), any order: the bands it shares with the "
                         "transfer are used");
    lighting->require_option(1);
    command->add_option("--rotate-y", options->rotateYDegrees,
                        "Turn the lighting by this many degrees about +Y (right-handed)");
    command->add_option("--window", options->window, "Band window against ringing: none, hann or lanczos");
    command->add_flag("--texels", options->texels,
                      "Relight the bundle's per-texel transfer (\"texel_transfer\", from `prt bake`) into an atlas "
                      "image");
    command->add_option("-o,--output", options->output,
                        "Per-vertex radiance [V,3]: .npy (float32) or .csv; with --texels an RGB float .exr atlas")
        ->required();
    command->add_option("--eye", options->eye,
                        "Eye point X,Y,Z: add the bundle's glossy lobes (from `prt glossy`), radiance toward it");
    command->add_flag("--glossy-only", options->glossyOnly, "With --eye: the glossy part alone, without the diffuse SH");
    command->callback([options] { runRelight(*options); });
}

} // namespace prt::cli
