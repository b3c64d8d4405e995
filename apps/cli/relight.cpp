// prt relight: per-vertex (or, with --texels, per-texel) outgoing radiance of a bundle's transfer under an
// environment map or SH lighting.
#include "cli.h"

#include "bake.h"
#include "compare.h"
#include "core.h"
#include "envlight.h"
#include "glossy_lights.h"
#include "material.h"
#include "raycast.h"
#include "render.h"
#include "runtime.h"
#include "tbb_jobs.h"

#include <nlohmann/json.hpp>

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
    std::string lights;
    int lightSamples = 64;
    std::string bounceWindow = "hann";
    std::string residualNegatives = "keep"; // glossy bundles with --lights: the residual map's negative texels
    std::string eye; // "X,Y,Z": add the glossy lobes' radiance toward this point
    bool glossyOnly = false;
    std::string imageSize; // "W,H": a picture through --camera instead of per-vertex radiance
    std::string camera;    // "EYE,TARGET,UP,FOVY", as `prt render` and `prt reference --image`
    float exposure = 0.0f;
    bool irradiance = false; // rows of irradiance E instead of outgoing radiance
    int visibilityTurns = -1; // --visibility-turns N: a table of N turns instead of one (-1: not given)
    std::string positions;   // also write each row's world-space position, [V,3] .npy
    std::string visibilityOut; // --lights: also write each row's cone visibility, [rows, lights] .npy
    SpecularRelightArgs specular; // --brdf: relight_specular.cpp
};

// Per vertex [V][3], what outgoing radiance is divided by to give irradiance E = pi * radiance / albedo:
// `albedo` (the transfer layer's params.albedo) when uniform, else `meshAlbedo` per vertex (1 when empty); 1 / pi
// alone for a scene's irradiance transfer, whose model then leaves its albedo out. Throws prt::Error where an
// albedo of 0 leaves E unknown.
std::vector<float> irradianceDivisors(const nlohmann::json& albedo, const std::vector<float>& meshAlbedo,
                                      RelightModel& model, const std::string& source) {
    const float pi = 3.14159265358979323846f;
    std::vector<float> divisors(size_t(model.vertexCount) * 3, 1.0f / pi);
    if (model.albedoExcluded) {
        model.albedo.clear();
        return divisors;
    }
    const bool uniform = albedo.is_array() && albedo.size() == 3;
    for (size_t v = 0; v < model.vertexCount; ++v)
        for (int c = 0; c < 3; ++c) {
            float rho = uniform && albedo[c].is_number() ? albedo[c].get<float>()
                        : meshAlbedo.empty()               ? 1.0f
                                                           : meshAlbedo[3 * v + c];
            if (!(rho > 0.0f))
                throw Error(source, "vertex " + std::to_string(v),
                            "has albedo 0, so its irradiance is unknown (--irradiance)", kExitInput);
            divisors[3 * v + c] = rho / pi;
        }
    return divisors;
}

// Relit rows to `path`: with texels a width x height float EXR atlas, else per-vertex radiance (.npy or .csv).
// Atomic either way.
void writeRelit(const std::string& path, bool texels, int width, int height, std::vector<float> radiance) {
    if (!texels) return writeVertexRadiance(path, radiance);
    Image image;
    image.width = width;
    image.height = height;
    image.rgb = std::move(radiance);
    writeImage(path, image);
}

// What the hybrid relights: rows (vertices, or texels of a bake) and, for the cone visibility, where each row lies
// and the mesh whose shadows fall on it.
struct HybridRows {
    HybridModel model;
    TriMesh mesh;
    std::vector<float> points, spawn; // [rows][3]; spawn empty: the normals (points inside triangles)
    int width = 0, height = 0;        // texels: the atlas
    std::vector<uint8_t> covered;     // texels: 1 where the bake sampled the surface
    bool scene = false;               // a scene bundle
    std::optional<Surface> surface;   // a scene's materials, for a picture or cut-outs (surface->mesh: the caller's)
    std::vector<float> cornerUv;      // a picture of a scene bake: its atlas (layer "lightmap_uv")
};

// A scene's materials are decoded for a picture (`picture`: --image) and for cut-outs, which the cone visibility's
// rays pass through as the transfer's do.
HybridRows hybridRows(const RelightOptions& options, bool picture) {
    HybridRows rows;
    Bundle bundle = readBundle(options.bundle);
    if (bundle.asset) {
        Surface surface = decodeSurface(bundle, options.bundle);
        if (picture || surface.cutouts) rows.surface = std::move(surface);
    }
    if (!options.texels) {
        rows.scene = !!bundle.asset;
        rows.mesh = bundle.mesh;
        rows.model = hybridModel(std::move(bundle), options.bundle);
        rows.points = rows.mesh.positions;
        rows.spawn = spawnNormals(rows.mesh);
        return rows;
    }
    const Layer* transfer = findLayer(bundle, "texel_transfer");
    if (transfer && transfer->params.contains("high"))
        throw Error(options.bundle, "layer \"texel_transfer\", params.high",
                    "the bake sampled a high-resolution mesh, whose shadows the texel hybrid's cone visibility would "
                    "need; only bakes of one mesh are supported");
    if (picture && bundle.asset) {
        rows.scene = true;
        rows.cornerUv = lightmapCorners(bundle, options.bundle);
    }
    rows.mesh = std::move(bundle.mesh); // the texel layers do not need it
    TexelHybridModel texels = texelHybridModel(std::move(bundle), options.bundle);
    rows.model = std::move(texels.rows);
    rows.points = std::move(texels.positions);
    rows.width = texels.width;
    rows.height = texels.height;
    rows.covered = std::move(texels.covered);
    return rows;
}

// Each cone's visibility per row ([rows][lights]) by Embree. Texels: cast at covered texels, then gutters filled by
// push-pull as the bake fills the transfer's, so that filtered lookups across chart borders stay smooth.
std::vector<float> hybridVisibility(const HybridRows& rows, const std::vector<envlight::ConeLight>& cones, int samples,
                                    uint64_t* rays) {
    const size_t count = rows.model.total.vertexCount;
    const Surface* cutouts = rows.surface && rows.surface->cutouts ? &*rows.surface : nullptr;
    if (samples == 0 || cones.empty()) return std::vector<float>(count * cones.size(), 1.0f);
    const float* normals = rows.model.normals.data();
    if (rows.covered.empty())
        return envlight::coneVisibility(rows.mesh, rows.points.data(), normals, rows.spawn.data(), count, cones,
                                        samples, rays, cutouts);
    std::vector<size_t> texels;
    std::vector<float> points, coveredNormals;
    for (size_t t = 0; t < count; ++t)
        if (rows.covered[t]) {
            texels.push_back(t);
            points.insert(points.end(), &rows.points[3 * t], &rows.points[3 * t] + 3);
            coveredNormals.insert(coveredNormals.end(), normals + 3 * t, normals + 3 * t + 3);
        }
    std::vector<float> visible = envlight::coneVisibility(rows.mesh, points.data(), coveredNormals.data(), nullptr,
                                                          texels.size(), cones, samples, rays, cutouts);
    std::vector<float> visibility(count * cones.size(), 0.0f);
    for (size_t i = 0; i < texels.size(); ++i)
        std::copy(&visible[i * cones.size()], &visible[(i + 1) * cones.size()], &visibility[texels[i] * cones.size()]);
    pushPull(visibility.data(), rows.width, rows.height, int(cones.size()), rows.covered.data());
    return visibility;
}

// The hybrid: cone lights from `prt envlight` plus their SH residual, with Embree cone visibility standing in for
// an engine's shadow maps.
// With `camera` (--image), a picture of the per-vertex hybrid radiance as `prt render` draws per-vertex radiance;
// of a scene, the hybrid at albedo 1 per vertex (its irradiance over pi) times the materials' base colour per pixel,
// as `prt render` draws a scene's SH relight.
void runHybridRelight(const RelightOptions& options, double start, const PinholeCamera* camera) {
    if (!options.shJson.empty()) throw Error("", "--lights", "give --lights or --sh, not both", kExitUsage);
    if (options.lightSamples < 0 || options.lightSamples > 65536)
        throw Error("", "--light-samples", "outside 0..65536", kExitUsage);
    sh::Window window = sh::parseWindow(options.window);
    HybridRows rows = hybridRows(options, camera != nullptr);
    HybridModel& model = rows.model;
    if (rows.surface) rows.surface->mesh = &rows.mesh;
    if (camera && rows.surface && !options.texels) {
        // The picture multiplies by the materials per pixel: the rows are relit at albedo 1 (texelHybridModel
        // already relights a scene bake's texels so).
        model.total.albedo.clear();
        std::fill(model.albedo.begin(), model.albedo.end(), 1.0f);
    }
    HybridLighting lighting = readHybridLightingJson(options.lights);
    checkHybridOrder(model, lighting, options.lights);
    if (!options.env.empty()) {
        // --env names the map the lights were made from: refuse lights made from another.
        envlight::checkLightsInput(options.lights, options.env);
    }
    if (options.rotateYDegrees != 0.0) {
        double R[9];
        sh::rotationY(options.rotateYDegrees, R);
        lighting = rotateHybridLighting(lighting, R);
    }
    sh::applyWindow(window, lighting.order, lighting.residual.data(), 3);
    if (options.bounceWindow == "off")
        model.bounce.clear();
    else
        lighting.bounceWindow = sh::parseWindow(options.bounceWindow, "--bounce-window");

    double visibilityStart = nowSeconds();
    std::vector<envlight::ConeLight> cones;
    for (const HybridConeLight& light : lighting.lights)
        cones.push_back({{light.direction[0], light.direction[1], light.direction[2]},
                         {light.radiance[0], light.radiance[1], light.radiance[2]},
                         light.angularRadius});
    uint64_t rays = 0;
    std::vector<uint8_t> turnTable; // --visibility-turns: [turns][rows][lights] bytes
    if (options.visibilityTurns != -1) {
        turnTable = envlight::coneVisibilityTurns(rows.mesh, rows.points.data(), rows.model.normals.data(),
                                                  rows.spawn.data(), rows.model.total.vertexCount, cones,
                                                  options.lightSamples, options.visibilityTurns, &rays,
                                                  rows.surface && rows.surface->cutouts ? &*rows.surface : nullptr);
        char turnsLine[160];
        std::snprintf(turnsLine, sizeof turnsLine, "relight: cone visibility for %d turns in %.1f ms (%zu bytes)",
                      options.visibilityTurns, (nowSeconds() - visibilityStart) * 1e3, turnTable.size());
        logInfo(turnsLine);
    }
    std::vector<float> visibility = hybridVisibility(rows, cones, options.lightSamples, &rays);
    double visibilitySeconds = nowSeconds() - visibilityStart;

    double relightStart = nowSeconds();
    std::vector<float> radiance(size_t(model.total.vertexCount) * 3);
    relightHybrid(model, lighting, visibility.data(), 0, model.total.vertexCount, radiance.data());
    double relightSeconds = nowSeconds() - relightStart;
    char line[240];
    std::snprintf(line, sizeof line,
                  "relight: hybrid, %u %s, order %d, %zu lights, %s bounce layer: relight %.3f ms, cone "
                  "visibility %.1f ms (%llu rays)",
                  model.total.vertexCount, options.texels ? "texels" : "vertices", model.total.order, cones.size(),
                  model.bounce.empty() ? "no" : "with", relightSeconds * 1e3, visibilitySeconds * 1e3,
                  (unsigned long long)rays);
    logInfo(line);
    if (model.bounce.empty() && !cones.empty() && options.bounceWindow != "off")
        logWarn(options.texels
                    ? "relight: the bake has no \"texel_transfer_bounce\" layer, so the lights light only directly "
                      "(their interreflected light is lost); bake with --bounces"
                    : "relight: the bundle has no \"transfer_bounce\" layer, so the lights light only directly "
                      "(their interreflected light is lost); make it with `prt transfer --mode interreflected`");
    // The visibility first: a failure to write it leaves no radiance behind either.
    if (options.visibilityTurns != -1) {
        writeNpyU8(options.visibilityOut, turnTable,
                   {size_t(options.visibilityTurns), size_t(model.total.vertexCount), cones.size()});
        logInfo("relight: wrote " + options.visibilityOut + " (cone visibility per turn, row and light, bytes)");
    } else if (!options.visibilityOut.empty()) {
        writeNpy(options.visibilityOut, visibility, {size_t(model.total.vertexCount), cones.size()});
        logInfo("relight: wrote " + options.visibilityOut + " (cone visibility per row and light)");
    }
    const Surface* surface = camera && rows.surface ? &*rows.surface : nullptr;
    if (camera && options.texels) {
        // The relit atlas looked up at the nearest texel of each hit, as `prt render --texels` draws a bake.
        Image atlas;
        atlas.width = rows.width;
        atlas.height = rows.height;
        atlas.rgb = std::move(radiance);
        writeRenderedPicture(options.output,
                             renderTexelRadiance(rows.mesh, atlas, *camera,
                                                 rows.cornerUv.empty() ? nullptr : rows.cornerUv.data(), surface),
                             options.exposure);
    } else if (camera)
        writeRenderedPicture(options.output, renderVertexRadiance(rows.mesh, radiance, *camera, surface),
                             options.exposure);
    else
        writeRelit(options.output, options.texels, rows.width, rows.height, std::move(radiance));
    logInfo("relight: wrote " + options.output);
    nlohmann::json record = {{"relight_seconds", relightSeconds}, {"visibility_seconds", visibilitySeconds},
                             {"visibility_rays", rays}, {"lights", cones.size()}};
    logEvent("relight_stats", record.dump());

    StageCost cost;
    cost.stage = "relight";
    cost.seconds = nowSeconds() - start;
    cost.rays = rays;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

// A glossy bundle under cone lights (docs/glossy.md, "Lights through the glossy path"): the diffuse hybrid, the
// lights' exact Phong lobe with their per-sample visibility, and the lobes against the map minus the lights; per
// vertex toward --eye, or a picture through --camera with the glossy part per pixel.
void runGlossyHybridRelight(const RelightOptions& options, bool imageMode, const PinholeCamera& camera, double start) {
    if (!options.shJson.empty()) throw Error("", "--lights", "give --lights or --sh, not both", kExitUsage);
    if (options.texels)
        throw Error("", "--texels", "glossy lobes are per vertex: --texels does not combine with --eye or --image",
                    kExitUsage);
    if (options.rotateYDegrees != 0.0)
        throw Error("", "--rotate-y", "does not combine with --lights on glossy lobes (the lights and their shadows are of the map as it is)",
                    kExitUsage);
    if (imageMode && !options.eye.empty())
        throw Error("", "--eye", "with --image the eye is the camera's (--camera)", kExitUsage);
    if (!imageMode && options.eye.empty()) throw Error("", "--glossy-only", "needs --eye or --image", kExitUsage);
    if (!options.visibilityOut.empty())
        throw Error("", "--visibility-out", "does not combine with glossy lobes (--eye or --image of a glossy bundle)",
                    kExitUsage);
    GlossyHybridOptions setup{options.bundle, options.env, options.lights, options.lightSamples, options.bounceWindow,
                              options.window, options.residualNegatives};
    GlossyHybrid hybrid = prepareGlossyHybrid(setup);
    std::vector<float> diffuse;
    if (!options.glossyOnly) diffuse = glossyHybridDiffuse(hybrid);
    char line[320];
    std::snprintf(line, sizeof line,
                  "relight: glossy hybrid, %u vertices, %zu lights (%d samples each, %llu rays), residual map: lights "
                  "%.1f%% of the map's energy, negative texels %.3f%% (%s)",
                  hybrid.glossy.vertexCount, hybrid.cones.lights.size(), hybrid.cones.samples,
                  (unsigned long long)hybrid.rays, 100.0 * hybrid.residualStats.lightsEnergy,
                  100.0 * hybrid.residualStats.negativeEnergy, options.residualNegatives.c_str());
    logInfo(line);
    if (imageMode) {
        RenderedImage picture = renderGlossyRadiance(hybrid.mesh, diffuse, hybrid.glossy, hybrid.residual, options.env,
                                                     camera, options.glossyOnly, &hybrid.cones);
        writeRenderedPicture(options.output, picture, options.exposure);
    } else {
        std::array<float, 3> eye = parsePoint(options.eye, "--eye");
        std::vector<float> radiance = glossyHybridGlossy(hybrid, eye.data());
        if (!options.glossyOnly)
            for (size_t i = 0; i < radiance.size(); ++i) radiance[i] += diffuse[i];
        writeVertexRadiance(options.output, radiance);
    }
    logInfo("relight: wrote " + options.output);
    StageCost cost;
    cost.stage = "relight";
    cost.seconds = nowSeconds() - start;
    cost.rays = hybrid.rays;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

// The SH lighting of a relight, in the order of operations of `prt envsh` (project, rotate, window), windowed over
// the transfer's `order` bands: from `environment` when --env is given (read by the caller), else from --sh, whose
// bands are fitted to the transfer's (a common lower order is said).
std::vector<float> relightLighting(const RelightOptions& options, const EnvironmentMap& environment, int order,
                                   const double* rotation, sh::Window window) {
    if (!options.env.empty()) return environmentLighting(environment, order, rotation, window);
    int lightingOrder = 0;
    std::vector<float> read = readLightingJson(options.shJson, &lightingOrder);
    if (lightingOrder != order)
        logInfo("relight: lighting has order " + std::to_string(lightingOrder) + ", transfer order " +
                std::to_string(order) + "; using their common " + std::to_string(std::min(lightingOrder, order)) +
                " bands");
    std::vector<float> lighting = fitLighting(read.data(), sh::coefficientCount(lightingOrder), sh::coefficientCount(order));
    if (rotation) lighting = rotateLighting(lighting.data(), order, rotation);
    sh::applyWindow(window, order, lighting.data(), 3);
    return lighting;
}

// Adds the glossy lobes' radiance toward `eye` to `radiance` [V][3] (replaces it with glossyOnly), as
// glossyLobesTowardEye evaluates it, and says how long it took.
void addGlossyTowardEye(const GlossyModel& glossy, const EnvironmentMap& environment, const double* rotation,
                        const float eye[3], bool glossyOnly, std::vector<float>& radiance) {
    double glossyStart = nowSeconds();
    const std::vector<float> glossyPart = glossyLobesTowardEye(glossy, environment.radiance, rotation, eye);
    for (size_t i = 0; i < radiance.size(); ++i) radiance[i] = (glossyOnly ? 0.0f : radiance[i]) + glossyPart[i];
    char line[160];
    std::snprintf(line, sizeof line, "relight: glossy lobes (%d per view) toward the eye in %.3f ms", glossy.lobes,
                  (nowSeconds() - glossyStart) * 1e3);
    logInfo(line);
}

// The flag checks of `prt relight` that need no input read (kExitUsage for what cannot go together), and with
// --image the camera parsed into `camera`. `imageMode`: whether --image was given.
void checkRelightFlags(const RelightOptions& options, bool imageMode, PinholeCamera& camera) {
    // writeVertexRadiance checks this too, but only after the work; a typo should fail at once.
    std::string outputExtension = fileExtension(options.output);
    if (options.exposure != 0.0f && outputExtension != "png")
        throw Error("", "--exposure", "tone-maps a .png picture (--image); other outputs keep linear radiance", kExitUsage);
    if (imageMode != !options.camera.empty())
        throw Error("", "--image", "--image and --camera go together", kExitUsage);
    if (imageMode) {
        if (options.texels && options.lights.empty())
            throw Error("", "--image", "pictures of a bake's texels are `prt render --texels`'s (or give --lights)",
                        kExitUsage);
        if (!options.eye.empty())
            throw Error("", "--eye", "with --image the eye is the camera's (--camera)", kExitUsage);
        if (outputExtension != "exr" && outputExtension != "png")
            throw Error(options.output, "-o", "with --image the picture must end in .exr or .png", kExitUsage);
        parsePinholeCamera(options.imageSize, "--image", options.camera, camera);
    } else if (options.texels && outputExtension != "exr")
        throw Error(options.output, "-o", "with --texels the output is an atlas image and must end in .exr",
                    kExitUsage);
    else if (!options.texels && outputExtension != "npy" && outputExtension != "csv")
        throw Error(options.output, "-o", "output must end in .npy or .csv", kExitUsage);
    if ((options.irradiance || !options.positions.empty()) &&
        (options.texels || imageMode || !options.lights.empty() || !options.eye.empty()))
        throw Error("", options.irradiance ? "--irradiance" : "--positions",
                    "applies to per-vertex rows of diffuse transfer (not --texels, --image, --lights or --eye)", kExitUsage);
    if (!options.positions.empty() && fileExtension(options.positions) != "npy")
        throw Error(options.positions, "--positions", "must end in .npy", kExitUsage);
    if (!options.visibilityOut.empty() && (options.lights.empty() || fileExtension(options.visibilityOut) != "npy"))
        throw Error(options.visibilityOut, "--visibility-out", "goes with --lights and must end in .npy", kExitUsage);
    if (options.visibilityTurns != -1) {
        if (options.visibilityOut.empty())
            throw Error("", "--visibility-turns", "goes with --lights and --visibility-out", kExitUsage);
        if (options.visibilityTurns < 1 || options.visibilityTurns > envlight::kMaxVisibilityTurns)
            throw Error("", "--visibility-turns",
                        std::to_string(options.visibilityTurns) + " is outside 1.." +
                            std::to_string(envlight::kMaxVisibilityTurns), kExitUsage);
        if (options.texels) throw Error("", "--visibility-turns", "is per vertex (not --texels)", kExitUsage);
        if (options.rotateYDegrees != 0.0)
            throw Error("", "--visibility-turns",
                        "casts the turns 0, 360/N, ... itself: give --rotate-y to the runs that draw", kExitUsage);
    }
}

void runRelight(const RelightOptions& options) {
    if (!options.specular.brdf.empty())
        return runSpecularRelight(options.specular, options.bundle, options.env, options.eye, options.output,
                                  options.glossyOnly);
    double start = nowSeconds();
    sh::Window window = sh::parseWindow(options.window);
    bool imageMode = !options.imageSize.empty();
    PinholeCamera camera;
    checkRelightFlags(options, imageMode, camera);
    // A glossy bundle under lights goes through the glossy path (--eye, --glossy-only, or a picture of one).
    if (!options.lights.empty() &&
        (!options.eye.empty() || options.glossyOnly ||
         (imageMode && findLayer(readBundle(options.bundle), "glossy_lobes") != nullptr)))
        return runGlossyHybridRelight(options, imageMode, camera, start);
    if (options.residualNegatives != "keep")
        throw Error("", "--residual-negatives", "applies to glossy bundles with --lights and --eye or --image",
                    kExitUsage);
    if (!options.lights.empty()) return runHybridRelight(options, start, imageMode ? &camera : nullptr);
    if (options.env.empty() && options.shJson.empty()) throw Error("", "--env", "give --env, --sh or --lights", kExitUsage);
    if (!options.env.empty() && !options.shJson.empty()) throw Error("", "--env", "give --env or --sh, not both", kExitUsage);

    if (!options.eye.empty() && (options.texels || options.env.empty()))
        throw Error("", "--eye", "needs --env (an equirectangular map) and per-vertex output", kExitUsage);
    if (options.glossyOnly && options.eye.empty() && !imageMode)
        throw Error("", "--glossy-only", "needs --eye or --image", kExitUsage);
    TexelRelightModel texelModel;
    std::optional<GlossyModel> glossy;
    RelightModel model;
    TriMesh mesh; // --image: the mesh the picture is rendered from; --positions: its positions
    std::vector<float> irradiance; // --irradiance: what radiance is divided by, per row
    std::optional<Surface> surface; // --image of a scene: its materials
    std::array<float, 3> eye{};
    if (!options.eye.empty()) eye = parsePoint(options.eye, "--eye");
    if (imageMode) eye = {camera.eye[0], camera.eye[1], camera.eye[2]};
    if (options.texels) {
        texelModel = loadTexelRelightModel(options.bundle);
        model = std::move(texelModel.rows);
    } else if (!options.eye.empty() || imageMode) {
        Bundle bundle = readBundle(options.bundle);
        // A picture of a glossy bundle is view dependent (toward the camera); of any other, the diffuse relight.
        if (!options.eye.empty() || findLayer(bundle, "glossy_lobes")) {
            if (options.env.empty())
                throw Error("", "--env", "the glossy lobes of " + options.bundle + " need --env (an equirectangular map)",
                            kExitUsage);
            glossy = glossyModel(bundle, options.bundle);
        } else if (options.glossyOnly) {
            throw Error(options.bundle, "layers", "has no \"glossy_lobes\" layer for --glossy-only (prt glossy writes one)");
        }
        if (imageMode) mesh = bundle.mesh;
        if (imageMode && bundle.asset) {
            if (glossy) throw Error(options.bundle, "layers", "glossy lobes of a scene are not supported", kExitInput);
            surface = decodeSurface(bundle, options.bundle);
            surface->mesh = &mesh;
        }
        model = relightModel(std::move(bundle), options.bundle);
        if (surface) model.albedo.clear(); // the picture multiplies by the materials per pixel
    } else {
        Bundle bundle = readRelightBundle(options.bundle); // the layers relight reads, not the bounce layer's values
        if (!options.positions.empty()) mesh.positions = bundle.mesh.positions;
        const Layer* transfer = findLayer(bundle, "transfer");
        nlohmann::json albedo = transfer ? transfer->params.value("albedo", nlohmann::json()) : nlohmann::json();
        std::vector<float> meshAlbedo = options.irradiance ? bundle.mesh.albedo : std::vector<float>();
        model = relightModel(std::move(bundle), options.bundle);
        if (options.irradiance) irradiance = irradianceDivisors(albedo, meshAlbedo, model, options.bundle);
    }
    double R[9];
    sh::rotationY(options.rotateYDegrees, R);
    const double* rotation = options.rotateYDegrees != 0.0 ? R : nullptr;

    EnvironmentMap environment;
    if (!options.env.empty()) environment = readEnvironmentMap(options.env);
    std::vector<float> lighting = relightLighting(options, environment, model.order, rotation, window);

    double relightStart = nowSeconds();
    std::vector<float> radiance(size_t(model.vertexCount) * 3);
    relight(model, lighting.data(), 0, model.vertexCount, radiance.data(), tbbJobs());
    double relightSeconds = nowSeconds() - relightStart;
    char rate[160];
    const char* rows = options.texels ? "texels" : "vertices";
    std::snprintf(rate, sizeof rate, "relight: %u %s at order %d in %.3f ms (%.1f M%s/s)", model.vertexCount, rows,
                  model.order, relightSeconds * 1e3,
                  relightSeconds > 0.0 ? model.vertexCount / relightSeconds / 1e6 : 0.0, rows);
    logInfo(rate);

    if (glossy && environment.layout != EnvLayout::Equirectangular)
        throw Error(options.env, "--env", "the glossy runtime needs an equirectangular (2:1) map");
    if (glossy && !imageMode) // a picture evaluates the lobes per pixel instead (below)
        addGlossyTowardEye(*glossy, environment, rotation, eye.data(), options.glossyOnly, radiance);

    for (size_t i = 0; i < irradiance.size(); ++i) radiance[i] /= irradiance[i];
    if (!options.positions.empty()) writeVertexRadiance(options.positions, mesh.positions);
    if (imageMode) {
        // Diffuse radiance interpolated over each hit triangle as `prt render` does; glossy lobes per pixel, toward
        // the pixel's own view direction.
        double pictureStart = nowSeconds();
        RenderedImage picture = glossy ? renderGlossyRadiance(mesh, radiance, *glossy, environment, options.env, camera,
                                                              options.glossyOnly, nullptr, rotation)
                                       : renderVertexRadiance(mesh, radiance, camera, surface ? &*surface : nullptr);
        if (glossy) {
            char line[160];
            std::snprintf(line, sizeof line, "relight: glossy lobes (%d per view) per pixel in %.3f ms", glossy->lobes,
                          (nowSeconds() - pictureStart) * 1e3);
            logInfo(line);
        }
        writeRenderedPicture(options.output, picture, options.exposure);
    } else {
        writeRelit(options.output, options.texels, texelModel.width, texelModel.height, std::move(radiance));
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
    lighting->add_option("--lights", options->lights,
                         "Cone lights plus SH residual as `prt envlight` writes them (prt-lights JSON, the bundle's "
                         "order): the hybrid relight. With --env, the lights must have been made from that map");
    lighting->require_option(1, 2);
    command->add_option("--rotate-y", options->rotateYDegrees,
                        "Turn the lighting by this many degrees about +Y (right-handed)")
        ->check(CLI::Range(-360.0, 360.0));
    command->add_option("--window", options->window, "Band window against ringing: none, hann or lanczos");
    command->add_flag("--texels", options->texels,
                      "Relight the bundle's per-texel transfer (\"texel_transfer\", from `prt bake`) into an atlas "
                      "image");
    command->add_option("--light-samples", options->lightSamples,
                        "Occlusion rays per vertex and light over each cone, for --lights (default 64; 0: unshadowed)");
    command->add_option("--bounce-window", options->bounceWindow,
                        "With --lights: window on the lights' SH where they meet the bounce layer: none, hann (default), "
                        "lanczos; or off: the lights light only directly (to measure what their bounce adds)");
    command->add_option("--residual-negatives", options->residualNegatives,
                        "Glossy bundle with --lights and --eye or --image: the lobes integrate the map minus the lights; "
                        "where a light claims more than a texel holds, keep the negative difference (keep, default: "
                        "lights + residual = the map) or clamp it to 0 (clamp)");
    command->add_option("-o,--output", options->output,
                        "Per-vertex radiance [V,3]: .npy (float32) or .csv; with --texels an RGB float .exr atlas")
        ->required();
    command->add_option("--eye", options->eye,
                        "Eye point X,Y,Z: add the bundle's glossy lobes (from `prt glossy`), radiance toward it");
    command->add_flag("--glossy-only", options->glossyOnly,
                      "With --eye or --image: the glossy part alone, without the diffuse SH");
    command->add_option("--image", options->imageSize,
                        "A W,H picture through --camera instead of per-vertex radiance (-o .exr linear RGBA or .png "
                        "tone mapped); a glossy bundle's lobes are evaluated toward the camera's eye; with --lights the "
                        "hybrid's per-vertex radiance as `prt render` draws it (a scene's times its materials per "
                        "pixel), and with --lights --texels the hybrid's relit atlas as `prt render --texels` draws a "
                        "bake");
    command->add_option("--camera", options->camera,
                        "With --image: EYEX,EYEY,EYEZ,TARGETX,TARGETY,TARGETZ,UPX,UPY,UPZ,FOVY (degrees), the camera of "
                        "`prt render` and `prt reference --image`");
    command->add_option("--exposure", options->exposure,
                        "With --image and a .png: stops; x = radiance * 2^exposure, then x / (1 + x), then sRGB")
        ->capture_default_str();
    command->add_flag("--irradiance", options->irradiance,
                      "Rows of irradiance E (W/m^2 per unit radiance of the map) instead of outgoing radiance: for a "
                      "scene, pi times its irradiance transfer; else pi * radiance / albedo");
    outputFile(command->add_option("--positions", options->positions,
                        "Also write each row's world-space position as [V,3] float32 .npy (rows: a scene's receivers in "
                        "node order, then their vertices), so other tools can match rows by position"));
    outputFile(command->add_option("--visibility-out", options->visibilityOut,
                        "With --lights: also write the cone visibility the relight used, float32 .npy [rows, lights] "
                        "(the lights as turned by --rotate-y), e.g. for the browser viewer's hybrid"));
    command->add_option("--visibility-turns", options->visibilityTurns,
                        "With --lights and --visibility-out: cast the cone visibility for N turns about +Y evenly over "
                        "360 degrees (turn t at t*360/N, as --rotate-y casts it) and write them as one uint8 .npy "
                        "[N, rows, lights] (round(255 V)), so the viewer turns the lights freely with their shadows");
    addSpecularRelightOptions(command, options->specular);
    optionNeeds(command, "--light-samples", "--lights");
    command->callback([options] { runRelight(*options); });
}

} // namespace prt::cli
