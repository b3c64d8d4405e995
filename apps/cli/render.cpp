// prt render: a picture of a relit bundle from a pinhole camera, per vertex or per texel.
#include "cli.h"

#include "bundle.h"
#include "compare.h"
#include "core.h"
#include "glossy_lights.h"
#include "image.h"
#include "material.h"
#include "raycast.h"
#include "render.h"
#include "runtime.h"
#include "tbb_jobs.h"

#include <memory>
#include <optional>

namespace prt::cli {

namespace {

struct RenderOptions {
    std::string bundle;
    std::string env;
    std::string camera; // "EYE,TARGET,UP,FOVY"
    std::string size;   // "W,H"
    std::string output;
    double rotateYDegrees = 0.0;
    std::string window = "none";
    int order = 0; // 0: the transfer's
    float exposure = 0.0f;
    bool texels = false;
    bool background = false; // the map behind the mesh where rays escape
    std::string lights; // prt-lights JSON: a glossy bundle through the glossy path with cone lights
    int lightSamples = 64;
    std::string bounceWindow = "hann";
    std::string residualNegatives = "keep";
    std::string vertexRadiance; // a [V,3] .npy to draw instead of relighting (e.g. a per-vertex reference)
    std::string glossyStack;    // also write the lobes' prefiltered stack here (prt-sg-stack, for the viewer)
};

// Writes the picture (atomically, by extension), says so, and reports the stage's time, rays and peak memory.
void finishPicture(const RenderOptions& options, const PinholeCamera& camera, const RenderedImage& image,
                   const std::string& what, double start) {
    writeRenderedPicture(options.output, image, options.exposure);
    logInfo("render: wrote " + options.output + " (" + std::to_string(camera.width) + "x" +
            std::to_string(camera.height) + ", " + what + ")");
    reportCost("render", start, image.rays);
}

// A glossy bundle under cone lights (docs/glossy.md, "Lights through the glossy path"): the diffuse hybrid per
// vertex, the lights' exact lobe and the lobes against the residual map per pixel; what `prt relight --lights
// --image` draws.
RenderedImage renderGlossyHybrid(const RenderOptions& options, const PinholeCamera& camera) {
    if (options.texels)
        throw Error("", "--lights", "goes with a glossy bundle's vertices, not --texels", kExitUsage);
    if (options.rotateYDegrees != 0.0)
        throw Error("", "--rotate-y", "does not combine with --lights on glossy lobes (the lights and their shadows are of the map as it is)",
                    kExitUsage);
    if (options.order != 0) throw Error("", "--order", "does not combine with --lights (the lights' order is the bundle's)", kExitUsage);
    GlossyHybridOptions setup{options.bundle, options.env, options.lights, options.lightSamples, options.bounceWindow,
                              options.window, options.residualNegatives};
    GlossyHybrid hybrid = prepareGlossyHybrid(setup);
    std::vector<float> diffuse = glossyHybridDiffuse(hybrid);
    RenderedImage image = renderGlossyRadiance(hybrid.mesh, diffuse, hybrid.glossy, hybrid.residual, options.env,
                                               camera, false, &hybrid.cones);
    image.rays += hybrid.rays;
    return image;
}

void runRender(const RenderOptions& options) {
    double start = nowSeconds();
    std::string extension = fileExtension(options.output);
    if (extension != "exr" && extension != "png")
        throw Error(options.output, "-o", "the image must end in .exr (linear) or .png (tone mapped)", kExitUsage);
    if (options.exposure != 0.0f && extension != "png")
        throw Error("", "--exposure", "tone-maps a .png; an .exr keeps linear radiance", kExitUsage);
    if (!options.vertexRadiance.empty() && options.rotateYDegrees != 0.0)
        throw Error("", "--rotate-y", "turns the lighting of a relight: --vertex-radiance draws given radiance", kExitUsage);
    PinholeCamera camera;
    parsePinholeCamera(options.size, "--size", options.camera, camera);
    sh::Window window = sh::parseWindow(options.window);
    if (!options.vertexRadiance.empty()) {
        // Given per-vertex radiance drawn as every relit bundle is (Gouraud): a per-vertex reference beside a relight.
        if (!options.env.empty() || !options.lights.empty() || options.texels)
            throw Error("", "--vertex-radiance", "draws the given radiance: no --env, --lights or --texels", kExitUsage);
        Bundle bundle = readBundle(options.bundle);
        if (bundle.asset)
            throw Error(options.bundle, "--vertex-radiance", "a scene's pictures need its materials; give a mesh",
                        kExitUsage);
        std::vector<float> radiance = readVertexRadiance(options.vertexRadiance);
        if (radiance.size() != bundle.mesh.vertexCount() * 3)
            throw Error(options.vertexRadiance, "--vertex-radiance",
                        std::to_string(radiance.size() / 3) + " rows for " + std::to_string(bundle.mesh.vertexCount()) +
                            " vertices of " + options.bundle,
                        kExitInput);
        RenderedImage image = renderVertexRadiance(bundle.mesh, radiance, camera);
        writeRenderedPicture(options.output, image, options.exposure);
        logInfo("render: wrote " + options.output + " (given per-vertex radiance)");
        return reportCost("render", start, image.rays);
    }
    if (options.env.empty()) throw Error("", "--env", "give --env (or --vertex-radiance)", kExitUsage);
    if (!options.glossyStack.empty() && (!options.lights.empty() || options.texels))
        throw Error("", "--glossy-stack", "goes with a glossy bundle's plain picture (no --lights or --texels)", kExitUsage);
    if (!options.lights.empty()) {
        RenderedImage image = renderGlossyHybrid(options, camera);
        if (options.background)
            drawEnvironmentBackground(image, readEnvironmentMap(options.env), options.env, camera, 0.0);
        finishPicture(options, camera, image, "glossy lobes and cone lights per pixel", start);
        return;
    }
    for (auto [given, flag] : {std::pair{options.residualNegatives != "keep", "--residual-negatives"},
                               std::pair{options.lightSamples != 64, "--light-samples"},
                               std::pair{options.bounceWindow != "hann", "--bounce-window"}})
        if (given) throw Error("", flag, "needs --lights", kExitUsage);

    // The runtime relights exactly as `prt relight` does; only the picture is new.
    Bundle bundle = readBundle(options.bundle);
    TriMesh mesh = bundle.mesh;
    // A scene is relit without its albedo and multiplied by its materials per pixel.
    std::optional<Surface> surface;
    std::vector<float> cornerUv; // a scene bake's atlas (layer "lightmap_uv")
    if (bundle.asset) {
        surface = decodeSurface(bundle, options.bundle);
        surface->mesh = &mesh;
        if (options.texels) cornerUv = lightmapCorners(bundle, options.bundle);
    }
    TexelRelightModel atlas;
    if (options.texels) atlas = loadTexelRelightModel(options.bundle);
    // A glossy bundle (`prt glossy`): its lobes are evaluated per pixel, toward each pixel's own view direction.
    std::optional<GlossyModel> glossy;
    if (!options.texels && findLayer(bundle, "glossy_lobes")) {
        if (bundle.asset) throw Error(options.bundle, "layers", "glossy lobes of a scene are not supported", kExitInput);
        glossy = glossyModel(bundle, options.bundle);
    }
    if (!options.glossyStack.empty() && !glossy)
        throw Error(options.bundle, "--glossy-stack", "has no \"glossy_lobes\" layer (prt glossy writes one)", kExitInput);
    RelightModel model = options.texels ? std::move(atlas.rows) : relightModel(std::move(bundle), options.bundle);
    if (surface) {
        if (!model.albedoExcluded)
            throw Error(options.bundle, "layer \"transfer\"", "a scene's transfer must exclude the albedo (params.albedo "
                                                               "\"excluded\"); run `prt transfer` on the scene again");
        model.albedo.clear();
    }
    if (options.order < 0 || options.order > model.order)
        throw Error("", "--order", "must lie in 1.." + std::to_string(model.order) + " (the transfer's order)",
                    kExitUsage);
    double R[9];
    sh::rotationY(options.rotateYDegrees, R);
    const EnvironmentMap environment = readEnvironmentMap(options.env);
    std::vector<float> lighting =
        environmentLighting(environment, model.order, options.rotateYDegrees != 0.0 ? R : nullptr, window);
    // A lower --order keeps the first order^2 coefficients of the lighting, as the viewer's order slider does.
    if (options.order > 0)
        for (size_t i = size_t(options.order) * options.order * 3; i < lighting.size(); ++i) lighting[i] = 0.0f;
    std::vector<float> radiance(size_t(model.vertexCount) * 3);
    relight(model, lighting.data(), 0, model.vertexCount, radiance.data(), tbbJobs());

    // The stack the lobes are looked up in, written for the viewer (unturned: the viewer turns the lookup as
    // renderGlossyRadiance does) and reused by the picture.
    std::optional<PrefilteredEnvironment> stack;
    if (!options.glossyStack.empty()) {
        stack = glossyRenderEnvironment(*glossy, environment, options.env);
        writeSharpnessStack(options.glossyStack, *stack);
        logInfo("render: wrote " + options.glossyStack + " (the glossy lobes' prefiltered stack)");
    }
    RenderedImage image;
    if (options.texels) {
        Image relit;
        relit.width = atlas.width;
        relit.height = atlas.height;
        relit.rgb = std::move(radiance);
        image = renderTexelRadiance(mesh, relit, camera, cornerUv.empty() ? nullptr : cornerUv.data(),
                                    surface ? &*surface : nullptr);
    } else {
        image = glossy ? renderGlossyRadiance(mesh, radiance, *glossy, environment, options.env, camera, false, nullptr,
                                              options.rotateYDegrees != 0.0 ? R : nullptr, stack ? &*stack : nullptr)
                       : renderVertexRadiance(mesh, radiance, camera, surface ? &*surface : nullptr);
    }
    // The map behind the mesh, turned with the lighting, as the viewer's sky (its tone map is the surface's).
    if (options.background) drawEnvironmentBackground(image, environment, options.env, camera, options.rotateYDegrees);
    finishPicture(options, camera, image, options.texels ? "per texel" : "per vertex", start);
}

} // namespace

void addRenderCommand(CLI::App& app) {
    auto options = std::make_shared<RenderOptions>();
    CLI::App* command = app.add_subcommand(
        "render", "Picture of a relit bundle from a pinhole camera (the camera of `prt reference --image`)");
    command->add_option("bundle", options->bundle, "Bundle (.glb) with a \"transfer\" layer (or, with --texels, a bake)")
        ->required();
    command->add_option("--env", options->env, "Environment map: 2:1 equirect or 1:6 cube strip");
    command->add_option("--vertex-radiance", options->vertexRadiance,
                        "Instead of --env: draw this per-vertex radiance ([V,3] .npy, the bundle's vertex order, e.g. "
                        "`prt reference` rows) interpolated per vertex, as a relit bundle is drawn");
    command->add_option("--camera", options->camera, "EYEX,EYEY,EYEZ,TARGETX,TARGETY,TARGETZ,UPX,UPY,UPZ,FOVY (degrees)")
        ->required();
    command->add_option("--size", options->size, "Image W,H in pixels, e.g. 640,480")->required();
    command->add_option("-o,--output", options->output,
                        "Image: .exr (linear float RGBA, A = coverage) or .png (tone mapped, see --exposure)")
        ->required();
    command->add_option("--rotate-y", options->rotateYDegrees,
                        "Turn the lighting by this many degrees about +Y (right-handed)")
        ->check(CLI::Range(-360.0, 360.0));
    command->add_option("--window", options->window, "Band window against ringing: none, hann or lanczos");
    command->add_option("--order", options->order, "Relight with only the first ORDER bands (default: all)");
    command->add_option("--exposure", options->exposure,
                        "PNG only: stops; x = radiance * 2^exposure, then x / (1 + x), then sRGB")
        ->capture_default_str();
    command->add_flag("--texels", options->texels,
                      "Relight the per-texel transfer (\"texel_transfer\") and look texels up at TEXCOORD_0");
    command->add_flag("--background", options->background,
                      "Draw the --env map where rays escape, turned by --rotate-y, bilinear between texel centres "
                      "(equirectangular maps; the EXR's A stays the coverage)");
    command->add_option("--lights", options->lights,
                        "Cone lights plus SH residual of `prt envlight` made from --env (prt-lights JSON, the bundle's "
                        "order), for a glossy bundle: the lights through the exact Phong lobe with their shadowed cone "
                        "visibility, the lobes against the map minus the lights, the diffuse part the hybrid relight");
    command->add_option("--light-samples", options->lightSamples,
                        "With --lights: occlusion rays per vertex and light over each cone (default 64)");
    command->add_option("--bounce-window", options->bounceWindow,
                        "With --lights: window on the lights' SH where they meet the bounce layer (hann, none, lanczos, off)");
    command->add_option("--residual-negatives", options->residualNegatives,
                        "With --lights: keep (default) or clamp the residual map's negative texels");
    outputFile(command->add_option("--glossy-stack", options->glossyStack,
                        "Glossy bundle: also write the prefiltered spherical-Gaussian stack its lobes are looked up in "
                        "(prt-sg-stack, docs/glossy.md; the browser viewer's glossy= input)"));
    command->callback([options] { runRender(*options); });
}

} // namespace prt::cli
