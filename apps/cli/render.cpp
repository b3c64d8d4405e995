// prt render: a picture of a relit bundle from a pinhole camera, per vertex or per texel.
#include "cli.h"

#include "bundle.h"
#include "compare.h"
#include "core.h"
#include "image.h"
#include "material.h"
#include "raycast.h"
#include "render.h"
#include "runtime.h"
#include "runtime_jobs.h"

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
};

void runRender(const RenderOptions& options) {
    double start = nowSeconds();
    std::string extension = fileExtension(options.output);
    if (extension != "exr" && extension != "png")
        throw Error(options.output, "-o", "the image must end in .exr (linear) or .png (tone mapped)", kExitUsage);
    PinholeCamera camera;
    parsePinholeCamera(options.size, "--size", options.camera, camera);
    sh::Window window = sh::parseWindow(options.window);

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
        if (options.rotateYDegrees != 0.0)
            throw Error("", "--rotate-y", "does not combine with glossy lobes (they are fitted to the map as it is)",
                        kExitUsage);
        glossy = glossyModel(bundle, options.bundle);
    }
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
    relight(model, lighting.data(), 0, model.vertexCount, radiance.data(), cli::tbbJobs());

    RenderedImage image;
    if (options.texels) {
        Image relit;
        relit.width = atlas.width;
        relit.height = atlas.height;
        relit.rgb = std::move(radiance);
        image = renderTexelRadiance(mesh, relit, camera, cornerUv.empty() ? nullptr : cornerUv.data(),
                                    surface ? &*surface : nullptr);
    } else {
        image = glossy ? renderGlossyRadiance(mesh, radiance, *glossy, environment, options.env, camera, false)
                       : renderVertexRadiance(mesh, radiance, camera, surface ? &*surface : nullptr);
    }
    // The map behind the mesh, turned with the lighting, as the viewer's sky (its tone map is the surface's).
    if (options.background) drawEnvironmentBackground(image, environment, options.env, camera, options.rotateYDegrees);
    writeRenderedPicture(options.output, image, options.exposure);
    logInfo("render: wrote " + options.output + " (" + std::to_string(camera.width) + "x" +
            std::to_string(camera.height) + ", " + (options.texels ? "per texel" : "per vertex") + ")");

    StageCost cost;
    cost.stage = "render";
    cost.seconds = nowSeconds() - start;
    cost.rays = image.rays;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addRenderCommand(CLI::App& app) {
    auto options = std::make_shared<RenderOptions>();
    CLI::App* command = app.add_subcommand(
        "render", "Picture of a relit bundle from a pinhole camera (the camera of `prt reference --image`)");
    command->add_option("bundle", options->bundle, "Bundle (.glb) with a \"transfer\" layer (or, with --texels, a bake)")
        ->required();
    command->add_option("--env", options->env, "Environment map: 2:1 equirect or 1:6 cube strip")->required();
    command->add_option("--camera", options->camera, "EYEX,EYEY,EYEZ,TARGETX,TARGETY,TARGETZ,UPX,UPY,UPZ,FOVY (degrees)")
        ->required();
    command->add_option("--size", options->size, "Image W,H in pixels, e.g. 640,480")->required();
    command->add_option("-o,--output", options->output,
                        "Image: .exr (linear float RGBA, A = coverage) or .png (tone mapped, see --exposure)")
        ->required();
    command->add_option("--rotate-y", options->rotateYDegrees,
                        "Turn the lighting by this many degrees about +Y (right-handed)");
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
    command->callback([options] { runRender(*options); });
}

} // namespace prt::cli
