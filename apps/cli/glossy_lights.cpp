// The shared set-up of the glossy path with cone lights, for prt relight and prt render.
#include "glossy_lights.h"

#include "core.h"
#include "raycast.h"
#include "tbb_jobs.h"

#include <algorithm>

namespace prt::cli {

GlossyHybrid prepareGlossyHybrid(const GlossyHybridOptions& options) {
    if (options.env.empty())
        throw Error("", "--env",
                    "the glossy path with --lights needs --env, the map the lights were made from (the lobes integrate "
                    "the map minus the lights)",
                    kExitUsage);
    if (options.lightSamples < 1 || options.lightSamples > 65536)
        throw Error("", "--light-samples", "with glossy lobes must lie in 1..65536", kExitUsage);
    if (options.residualNegatives != "keep" && options.residualNegatives != "clamp")
        throw Error("", "--residual-negatives", "must be keep or clamp, not \"" + options.residualNegatives + "\"",
                    kExitUsage);
    const sh::Window window = sh::parseWindow(options.window);
    GlossyHybrid hybrid;
    Bundle bundle = readBundle(options.bundle);
    if (!findLayer(bundle, "glossy_lobes"))
        throw Error(options.bundle, "layers",
                    "has no \"glossy_lobes\" layer: --lights with --eye, --image or --glossy-only needs a `prt glossy` "
                    "bundle",
                    kExitInput);
    if (bundle.asset) throw Error(options.bundle, "layers", "glossy lobes of a scene are not supported", kExitInput);
    hybrid.mesh = bundle.mesh;
    hybrid.glossy = glossyModel(bundle, options.bundle);
    hybrid.diffuse = hybridModel(std::move(bundle), options.bundle);
    hybrid.lighting = readHybridLightingJson(options.lights);
    checkHybridOrder(hybrid.diffuse, hybrid.lighting, options.lights);
    envlight::checkLightsInput(options.lights, options.env);
    sh::applyWindow(window, hybrid.lighting.order, hybrid.lighting.residual.data(), 3);
    if (options.bounceWindow == "off")
        hybrid.diffuse.bounce.clear();
    else
        hybrid.lighting.bounceWindow = sh::parseWindow(options.bounceWindow, "--bounce-window");

    const EnvironmentMap map = readEnvironmentMap(options.env);
    if (map.layout != EnvLayout::Equirectangular)
        throw Error(options.env, "--env", "the glossy runtime needs an equirectangular (2:1) map", kExitInput);
    std::vector<envlight::ConeLight> cones;
    for (const HybridConeLight& light : hybrid.lighting.lights)
        cones.push_back({{light.direction[0], light.direction[1], light.direction[2]},
                         {light.radiance[0], light.radiance[1], light.radiance[2]},
                         light.angularRadius});
    // The cones as `prt reference --lights` renders them (8 x 8 coverage points per rim texel).
    hybrid.residual = envlight::subtractConeLights(map, cones, 8, options.residualNegatives == "clamp",
                                                   &hybrid.residualStats);

    hybrid.cones.lights = hybrid.lighting.lights;
    hybrid.cones.samples = options.lightSamples;
    for (const envlight::ConeLight& cone : cones) {
        std::vector<float> directions = envlight::coneSampleDirections(cone, options.lightSamples);
        hybrid.cones.directions.insert(hybrid.cones.directions.end(), directions.begin(), directions.end());
    }
    const std::vector<float> spawn = spawnNormals(hybrid.mesh);
    const size_t vertices = hybrid.mesh.vertexCount();
    uint64_t rays = 0;
    hybrid.cones.visible = envlight::coneSampleVisibility(hybrid.mesh, hybrid.mesh.positions.data(),
                                                          hybrid.diffuse.normals.data(), spawn.data(), vertices, cones,
                                                          options.lightSamples, &rays);
    hybrid.rays += rays;
    checkGlossyConeLights(hybrid.glossy, hybrid.cones, options.bundle);
    // The diffuse hybrid's cosine-weighted visible fraction, from the same rays.
    hybrid.coneVisibility =
        envlight::coneVisibilityFromSamples(hybrid.diffuse.normals.data(), vertices, cones.size(), options.lightSamples,
                                            hybrid.cones.directions.data(), hybrid.cones.visible.data());
    return hybrid;
}

std::vector<float> glossyHybridDiffuse(const GlossyHybrid& hybrid) {
    std::vector<float> radiance(size_t(hybrid.diffuse.total.vertexCount) * 3);
    relightHybrid(hybrid.diffuse, hybrid.lighting, hybrid.coneVisibility.data(), 0, hybrid.diffuse.total.vertexCount,
                  radiance.data());
    return radiance;
}

std::vector<float> glossyLobesTowardEye(const GlossyModel& glossy, const Image& map, const double* rotation,
                                        const float eye[3]) {
    PrefilterOptions prefilter;
    choosePrefilterRange(glossy, size_t(3) * glossy.lobes * glossy.vertexCount, prefilter);
    const JobSystem jobs = tbbJobs();
    prefilter.jobs = &jobs;
    PrefilteredEnvironment prefiltered = prefilterEnvironment(map.rgb.data(), map.width, map.height, prefilter);
    if (rotation) std::copy_n(rotation, 9, prefiltered.rotation);
    std::vector<float> lobes(size_t(glossy.vertexCount) * 3);
    glossyRadiance(glossy, prefiltered, eye, lobes.data());
    return lobes;
}

std::vector<float> glossyHybridGlossy(const GlossyHybrid& hybrid, const float eye[3]) {
    const size_t values = size_t(hybrid.glossy.vertexCount) * 3;
    std::vector<float> lobes = glossyLobesTowardEye(hybrid.glossy, hybrid.residual.radiance, nullptr, eye);
    std::vector<float> lights(values);
    glossyConeLightRadiance(hybrid.glossy, hybrid.cones, eye, lights.data());
    for (size_t i = 0; i < values; ++i) lobes[i] += lights[i];
    return lobes;
}

} // namespace prt::cli
