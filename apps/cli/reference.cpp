// prt reference: ground-truth outgoing radiance by path tracing, per vertex or as a pinhole image.
#include "cli.h"

#include "bundle.h"
#include "compare.h"
#include "core.h"
#include "material.h"
#include "image.h"
#include "raycast.h"
#include "envlight.h"
#include "reference.h"
#include "runtime.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

namespace prt::cli {

namespace {

struct ReferenceCommandOptions {
    std::string mesh;
    std::string env;
    std::string output;
    std::string standardErrorOutput;
    int bounces = 0;
    int samples = 256;
    uint64_t seed = 0;
    int threads = 0;
    std::string albedo; // "R,G,B"
    std::string imageSize; // "W,H"
    std::string camera;    // "EYE,TARGET,UP,FOVY"
    std::string lights;    // prt-lights JSON: render the decomposed lighting instead of --env
    int lightsWidth = 2048;
    std::vector<std::string> occluders, at; // brute-force direct lighting with occluders (FIV ground truth)
    bool bruteForce = false, unshadowed = false;
    std::string brdf;      // "phong:N,KS"
    std::string eye;       // "X,Y,Z"
};

// Coverage samples per side of a texel near a cone light, when a prt-lights file is rendered into a map.
constexpr int kLightsSupersample = 8;

// The decomposed lighting of a prt-lights file (residual SH plus cones) as a map the path tracer samples.
EnvironmentMap lightsEnvironment(const std::string& path, int width) {
    HybridLighting lighting = readHybridLightingJson(path);
    std::vector<envlight::ConeLight> cones;
    for (const HybridConeLight& light : lighting.lights)
        cones.push_back({{light.direction[0], light.direction[1], light.direction[2]},
                         {light.radiance[0], light.radiance[1], light.radiance[2]},
                         light.angularRadius});
    std::vector<double> residual(lighting.residual.begin(), lighting.residual.end());
    double negative = 0.0;
    EnvironmentMap env = envlight::renderLighting(cones, residual, lighting.order, width, kLightsSupersample, &negative);
    char line[320];
    std::snprintf(line, sizeof line, "reference: %s rendered as a %dx%d map; the residual's negative radiance (kept, "
                                     "signed): %.3g%% of its luminance energy", path.c_str(), width, width / 2,
                  100.0 * negative);
    logInfo(line);
    return env;
}

void requireExtension(const std::string& path, const char* option, std::initializer_list<const char*> extensions) {
    std::string extension = fileExtension(path);
    std::string allowed;
    for (const char* e : extensions) {
        if (extension == e) return;
        allowed += std::string(allowed.empty() ? "." : " or .") + e;
    }
    throw Error(path, option, "needs a " + allowed + " file", kExitUsage);
}

// Mean standard error over mean radiance, over every value: the run's relative noise level.
double relativeNoise(const std::vector<float>& radiance, const std::vector<float>& standardError) {
    double radianceSum = 0.0, errorSum = 0.0;
    for (size_t i = 0; i < radiance.size(); ++i) radianceSum += radiance[i], errorSum += standardError[i];
    return radianceSum > 0.0 ? errorSum / radianceSum : 0.0;
}

void runReference(const ReferenceCommandOptions& options) {
    double start = nowSeconds();
    bool imageMode = !options.imageSize.empty();
    if (imageMode != !options.camera.empty())
        throw Error("", "--image", "--image and --camera go together", kExitUsage);
    if (options.samples < 2) throw Error("", "--samples", "need at least 2 for a standard error", kExitUsage);
    if (options.bounces < 0) throw Error("", "--bounces", "must be >= 0", kExitUsage);
    if (imageMode) {
        requireExtension(options.output, "-o", {"exr"});
        if (!options.standardErrorOutput.empty())
            requireExtension(options.standardErrorOutput, "--stderr-out", {"exr"});
    } else {
        requireExtension(options.output, "-o", {"npy", "csv"});
        if (!options.standardErrorOutput.empty())
            requireExtension(options.standardErrorOutput, "--stderr-out", {"npy", "csv"});
    }

    ReferenceOptions reference;
    reference.bounces = options.bounces;
    reference.samples = options.samples;
    reference.seed = options.seed;
    reference.threads = resolveThreads(options.threads);
    if (!options.albedo.empty()) {
        std::array<double, 3> albedo = parseAlbedo(options.albedo);
        reference.albedo = std::array<float, 3>{float(albedo[0]), float(albedo[1]), float(albedo[2])};
    }
    if (!options.brdf.empty()) {
        PhongBrdf phong;
        parsePhongBrdf(options.brdf, phong.exponent, phong.ks);
        reference.phong = phong;
        if (!imageMode && options.eye.empty())
            throw Error("", "--eye", "--brdf in vertex mode needs --eye X,Y,Z (radiance toward that point)",
                        kExitUsage);
    }
    if (!options.eye.empty()) reference.eye = parsePoint(options.eye, "--eye");
    PinholeCamera camera;
    if (imageMode) parsePinholeCamera(options.imageSize, "--image", options.camera, camera);

    bool direct = options.bruteForce || options.unshadowed || !options.occluders.empty();
    if (direct && (imageMode || options.bounces != 0))
        throw Error("", "--occluder", "--occluder, --brute-force and --unshadowed need --bounces 0 and no --image",
                    kExitUsage);
    if (options.occluders.size() != options.at.size())
        throw Error("", "--at", "give one --at X,Y,Z per --occluder", kExitUsage);
    std::vector<DirectOccluder> occluders;
    for (size_t j = 0; j < options.at.size(); ++j) occluders.push_back({TriMesh(), parsePoint(options.at[j], "--at")});

    Bundle bundle = readBundle(options.mesh);
    const TriMesh& mesh = bundle.mesh;
    if (mesh.normals.empty()) throw Error(options.mesh, "", "mesh has no vertex normals (prt meshprep adds them)");
    // A scene is traced with its materials, as transfer sees it.
    std::optional<Surface> surface;
    if (bundle.asset) {
        if (reference.albedo)
            throw Error("", "--albedo", "a scene (" + options.mesh + ") takes its albedo from its materials", kExitUsage);
        if (direct)
            throw Error("", "--brute-force", "the direct sum (--brute-force, --unshadowed, --occluder) does not read "
                                             "materials yet; path-trace the scene", kExitUsage);
        surface = decodeSurface(bundle, options.mesh);
        reference.surface = &*surface;
    }
    for (size_t j = 0; j < occluders.size(); ++j) occluders[j].mesh = readBundle(options.occluders[j]).mesh;
    if (options.env.empty() == options.lights.empty())
        throw Error("", "--env", "give --env or --lights (exactly one)", kExitUsage);
    if (options.lightsWidth < 4 || options.lightsWidth > 16384 || options.lightsWidth % 2 != 0)
        throw Error("", "--lights-width", "must be even, 4..16384", kExitUsage);
    // renderLighting's coverage samples (8 x 8 per texel near a light), refused by the element cap: it bounds the
    // time the map takes, not only its floats.
    if (!options.lights.empty())
        checkCommandLineSize({uint64_t(options.lightsWidth), uint64_t(options.lightsWidth / 2),
                              uint64_t(kLightsSupersample * kLightsSupersample)},
                             "coverage samples (W x W/2 texels x 8 x 8)", "--lights-width");
    EnvironmentMap env = options.lights.empty() ? readEnvironmentMap(options.env)
                                                : lightsEnvironment(options.lights, options.lightsWidth);
    if (direct) {
        DirectOptions directOptions;
        directOptions.albedo = reference.albedo;
        directOptions.shadows = !options.unshadowed;
        directOptions.threads = reference.threads;
        directOptions.phong = reference.phong; // glossy: the exact direct sum toward --eye (checked above)
        directOptions.eye = reference.eye;
        ReferenceRadiance radiance = referenceDirectRadiance(mesh, occluders, env, directOptions);
        writeVertexRadiance(options.output, radiance.radiance);
        if (!options.standardErrorOutput.empty()) writeVertexRadiance(options.standardErrorOutput, radiance.standardError);
        logInfo("reference: brute-force direct lighting over " + std::to_string(env.radiance.width) + "x" +
                std::to_string(env.radiance.height) + " texels, " + std::to_string(occluders.size()) + " occluders" +
                (reference.phong ? ", Phong " + options.brdf + " toward the eye" : ""));
        StageCost cost;
        cost.stage = "reference";
        cost.seconds = nowSeconds() - start;
        cost.rays = radiance.rays;
        cost.peakMemoryBytes = peakMemoryBytes();
        reportCost(cost);
        return;
    }
    std::string albedoSource = surface           ? "of the scene's materials"
                               : reference.albedo ? "constant"
                               : mesh.albedo.empty() ? "white"
                                                     : "per vertex";
    logInfo("reference: " + options.mesh + " (" + std::to_string(mesh.vertexCount()) + " vertices) under " +
            (options.lights.empty() ? options.env : options.lights) + ", " + std::to_string(options.samples) + " samples, " + std::to_string(options.bounces) +
            " bounces, albedo " + albedoSource + ", " + std::to_string(reference.threads) + " threads");

    uint64_t rays = 0;
    double noise = 0.0;
    if (imageMode) {
        ReferenceImage image = referenceImage(mesh, env, camera, reference);
        writeImage(options.output, image.radiance);
        if (!options.standardErrorOutput.empty()) writeImage(options.standardErrorOutput, image.standardError);
        rays = image.rays;
        noise = relativeNoise(image.radiance.rgb, image.standardError.rgb);
    } else {
        ReferenceRadiance radiance = referenceVertexRadiance(mesh, env, reference);
        writeVertexRadiance(options.output, radiance.radiance);
        if (!options.standardErrorOutput.empty())
            writeVertexRadiance(options.standardErrorOutput, radiance.standardError);
        rays = radiance.rays;
        noise = relativeNoise(radiance.radiance, radiance.standardError);
    }
    char summary[64];
    std::snprintf(summary, sizeof summary, "%.3g%%", 100.0 * noise);
    logInfo("reference: wrote " + options.output + "; mean standard error is " + summary + " of mean radiance");

    StageCost cost;
    cost.stage = "reference";
    cost.seconds = nowSeconds() - start;
    cost.rays = rays;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addReferenceCommand(CLI::App& app) {
    auto options = std::make_shared<ReferenceCommandOptions>();
    CLI::App* command = app.add_subcommand(
        "reference", "Ground-truth outgoing radiance by path tracing (diffuse, environment lighting), per vertex or "
                     "as an image");
    command->add_option("mesh", options->mesh, "Mesh (.glb/.gltf) with vertex normals")->required();
    command->add_option("--env", options->env, "Environment map: 2:1 equirectangular or 1:6 cube strip");
    command->add_option("--lights", options->lights,
                        "Instead of --env: the decomposed lighting of `prt envlight` (prt-lights JSON), its SH residual "
                        "plus its cones, rendered into an equirectangular map");
    command->add_option("--lights-width", options->lightsWidth, "Width of that map (default 2048)");
    command->add_option("-o,--output", options->output,
                        "Radiance per vertex (.npy [V,3] or .csv), in the mesh's vertex order; with --image an .exr")
        ->required();
    command->add_option("--bounces", options->bounces, "Extra diffuse bounces; 0 = direct lighting only (shadowed)")
        ->capture_default_str();
    command->add_option("--samples", options->samples, "Paths per vertex or pixel (>= 2)")->capture_default_str();
    command->add_option("--albedo", options->albedo,
                        "Constant diffuse albedo R,G,B or one grey value in [0,1], e.g. 0.8 "
                        "(default: the mesh's COLOR_0, else white)");
    command->add_option("--seed", options->seed, "Random seed; same seed, same output for any thread count")
        ->capture_default_str();
    command->add_option("--threads", options->threads, "Worker threads (default: all)");
    outputFile(command->add_option("--stderr-out", options->standardErrorOutput,
                        "Also write the standard error of each value, in the same format as -o"));
    command->add_option("--image", options->imageSize, "Render a W,H pinhole image instead, e.g. 640,480");
    command->add_option("--camera", options->camera,
                        "With --image: EYE,TARGET,UP,FOVY as 10 comma-separated numbers (three x,y,z triples, then "
                        "the vertical field of view in degrees), e.g. 0,1,3,0,0.5,0,0,1,0,40");
    command->add_option("--occluder", options->occluders,
                        "An occluder mesh (.glb) that blocks light but is not shaded (repeatable, one per --at); "
                        "implies the brute-force direct sum, needs --bounces 0");
    command->add_option("--at", options->at, "X,Y,Z: the occluder's translation; its vertex p sits at p + (X,Y,Z)");
    command->add_flag("--brute-force", options->bruteForce,
                      "Direct light (--bounces 0) as the exact sum over every texel of the map, one shadow ray each "
                      "(with --brdf and --eye: the exact glossy direct light)");
    command->add_flag("--unshadowed", options->unshadowed, "With the brute-force sum: no shadows at all");
    command->add_option("--brdf", options->brdf,
                        "Glossy surfaces: phong:EXPONENT,KS, normalised Phong on top of the diffuse albedo "
                        "(docs/conventions.md); vertex mode then needs --eye");
    command->add_option("--eye", options->eye,
                        "Eye point X,Y,Z: each vertex's radiance toward it (view-dependent with --brdf)");
    command->callback([options] { runReference(*options); });
}

} // namespace prt::cli
