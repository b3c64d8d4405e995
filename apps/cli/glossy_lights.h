// What `prt relight --lights` and `prt render --lights` share for a glossy bundle (docs/glossy.md, "Lights through
// the glossy path"): the bundle's lobes and diffuse transfer, the prt-lights file, each light's per-sample
// visibility by Embree, the residual map the lobes integrate, and the diffuse hybrid relight. The formulas are in
// lib/runtime (glossy_lights.cpp, hybrid.cpp) and lib/envlight (residual_map.cpp, visibility.cpp).
#pragma once

#include "bundle.h"
#include "envlight.h"
#include "image.h"
#include "runtime.h"

#include <string>
#include <vector>

namespace prt::cli {

struct GlossyHybridOptions {
    std::string bundle, env, lights;
    int lightSamples = 64;          // per light and vertex, for both the diffuse and the glossy visibility
    std::string bounceWindow = "hann";
    std::string window = "none";    // on the diffuse hybrid's SH residual
    std::string residualNegatives;  // "keep" or "clamp" (envlight::subtractConeLights)
};

struct GlossyHybrid {
    TriMesh mesh;
    GlossyModel glossy;
    HybridModel diffuse;
    HybridLighting lighting;
    GlossyConeLights cones;           // the lights with their sample directions and per-sample visibility
    std::vector<float> coneVisibility; // [V][lights], cosine weighted, for the diffuse hybrid
    EnvironmentMap residual;          // the map minus the cones: what the lobes integrate
    envlight::ResidualMapStats residualStats;
    uint64_t rays = 0;
};

// Reads and checks everything; refuses (kExitUsage or kExitInput, by flag or file name) a bundle without glossy
// lobes, a lights file of another order or another map, a map that is not 2:1 equirectangular, and bad option
// values.
GlossyHybrid prepareGlossyHybrid(const GlossyHybridOptions& options);

// The diffuse part per vertex ([V][3]): the hybrid relight (residual SH through the transfer, the lights in closed
// form with their cone visibility).
std::vector<float> glossyHybridDiffuse(const GlossyHybrid& hybrid);

// The lobes of `glossy` per vertex toward `eye` ([V][3]) under the equirectangular `map`, turned by `rotation`
// (row-major, as sh::rotationY; null: none) through the lookup: the stack over the lobes' range, or exact sums for
// a pass below the break-even (choosePrefilterRange), its rows on TBB. What `prt relight --eye` adds, with or
// without lights.
std::vector<float> glossyLobesTowardEye(const GlossyModel& glossy, const Image& map, const double* rotation,
                                        const float eye[3]);

// The glossy part per vertex toward `eye` ([V][3]): the lobes against the residual map plus the lights' exact lobe.
std::vector<float> glossyHybridGlossy(const GlossyHybrid& hybrid, const float eye[3]);

} // namespace prt::cli
