// The FIV figures of docs/results.md, measured in one run and printed as JSON (not a test: it takes minutes).
//   fiv_figures BUNNY.ply ENV_DIR OUT_DIR [--quick] [--grids 32x17x15,...] [--scenes "one bunny,self-shadow"]
//               [--maps sunrise,courtyard] [--sources] [--self-vertices] [--source-grid NTxNPxNR [--sharpen K,...]]
// --sources --source-grid G [--sharpen K,...] (K default 2; --sharpen alone: G the main grid): the sources' own grid
// (fiv::sampleSourceGrid, docs/fiv.md decision 13) through the bundle layers, one bundle per K, every scene.
// Scenes (receiver 8x8 plane of 65x65 vertices unless said): the bunny scaled to 2 units hovering 0.5 above the
// plane; two bunnies with overlapping shadows; three; one straddling the plane; one 0.05 above it (close); one
// low beside the plane (grazing); the bunny as its own receiver. Maps: courtyard, sunrise (sharp sun), constant.
// Error: S = L_unoccluded - L_occluded per vertex in luminance, NRMSE = RMS(S - S_ref) / (max S_ref - min S_ref),
// against the brute-force direct sum over the full-resolution map (prt reference --occluder); also against the
// same sum over the 6x32x32 cube, which isolates the grid's error from the cube's.
#include "fiv.h"

#include "core.h"
#include "luminance.h"
#include "image.h"
#include "mesh.h"
#include "reference.h"
#include "runtime.h"
#include "scene.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <fstream>
#include <iostream>
#include <map>
#include <numbers>
#include <string>

using namespace prt;
using nlohmann::json;

namespace {

struct SceneSpec {
    std::string name;
    bool self = false;
    std::vector<std::array<float, 3>> placements; // bunny translations
    bool failureOnly = false;                     // measured under courtyard only (the failure map)
};

std::vector<double> luminance(const std::vector<float>& rgb) {
    std::vector<double> out(rgb.size() / 3);
    for (size_t v = 0; v < out.size(); ++v)
        out[v] = kLuminance[0] * rgb[3 * v] + kLuminance[1] * rgb[3 * v + 1] + kLuminance[2] * rgb[3 * v + 2];
    return out;
}

struct Errors {
    double nrmse = 0, relativeRmse = 0, shadowRange = 0;
};

Errors errors(const std::vector<float>& freeA, const std::vector<float>& shadedA, const std::vector<float>& freeRef,
              const std::vector<float>& shadedRef) {
    std::vector<double> fa = luminance(freeA), sa = luminance(shadedA), fr = luminance(freeRef), sr = luminance(shadedRef);
    double lo = 1e300, hi = -1e300, sum = 0;
    for (size_t v = 0; v < fa.size(); ++v) {
        double s = fa[v] - sa[v], r = fr[v] - sr[v];
        lo = std::min(lo, r), hi = std::max(hi, r);
        sum += (s - r) * (s - r);
    }
    Errors e;
    e.shadowRange = hi - lo;
    e.nrmse = hi > lo ? std::sqrt(sum / double(fa.size())) / (hi - lo) : 0.0;
    double num = 0, den = 0;
    for (size_t i = 0; i < shadedA.size(); ++i) num += std::pow(double(shadedA[i]) - shadedRef[i], 2), den += std::pow(double(shadedRef[i]), 2);
    e.relativeRmse = std::sqrt(num / den);
    return e;
}

std::vector<float> shadeFiv(const TriMesh& receiver, const FivLighting& lighting, const FivOccluder* occluder,
                            const std::vector<std::array<float, 3>>& placements, bool self, FivShadeOptions options) {
    std::vector<FivInstance> instances;
    for (const auto& p : placements) instances.push_back({occluder, {p[0], p[1], p[2]}});
    FivInstance selfInstance{occluder, {0, 0, 0}};
    // The exact per-vertex self-shadowing (--self-vertices) when the grid's bundle carries it.
    if (self && !occluder->selfIrradiance.empty()) selfInstance.selfIrradiance = occluder->selfIrradiance.data();
    std::vector<float> out(receiver.positions.size());
    fivIrradiance(lighting, instances.data(), instances.size(), self ? &selfInstance : nullptr, receiver.positions.data(),
                  receiver.normals.data(), receiver.vertexCount(), options, out.data());
    for (float& v : out) v = float(v / std::numbers::pi); // albedo 1
    return out;
}

// Shadow image S of a plane receiver (65 x 65) as a PNG: reference, FIV, and 10 x |difference|.
void writeShadowPng(const std::string& path, const std::vector<float>& freeA, const std::vector<float>& shadedA,
                    const std::vector<float>& freeRef, const std::vector<float>& shadedRef, int side) {
    std::vector<double> fa = luminance(freeA), sa = luminance(shadedA), fr = luminance(freeRef), sr = luminance(shadedRef);
    double hi = 1e-12;
    for (size_t v = 0; v < fa.size(); ++v) hi = std::max(hi, fr[v] - sr[v]);
    int width = 3 * side + 2;
    std::vector<float> pixels(size_t(width) * side * 3, 1.0f);
    for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
            size_t v = size_t(y) * side + x;
            double values[3] = {(fr[v] - sr[v]) / hi, (fa[v] - sa[v]) / hi, 10.0 * std::abs((fa[v] - sa[v]) - (fr[v] - sr[v])) / hi};
            for (int panel = 0; panel < 3; ++panel)
                for (int c = 0; c < 3; ++c)
                    pixels[3 * (size_t(y) * width + panel * (side + 1) + x) + c] = float(std::clamp(1.0 - values[panel], 0.0, 1.0));
        }
    writeImagePixels(path, width, side, {"R", "G", "B"}, pixels.data(), PixelStorage::U8);
}

struct GridChoice {
    int nt, np, nr;
};

struct Args {
    std::string bunnyPath, envDir, outDir;
    bool quick = false;
    bool sources = false;        // --sources: the map's small sources shadowed from their own texels (extractSmallSources)
    std::string sourceGrid;      // --source-grid NTxNPxNR: with --sources, the sources' own grid (fiv::sampleSourceGrid)
    std::vector<double> sharpen; // --sharpen K,...: its K values (default 2), one bundle each
    bool selfVertices = false;   // --self-vertices: the bunny's own self-shadowing at its vertices (fiv::selfIrradiance)
    std::string gridList, sceneList, mapList;
};

std::vector<std::string> splitList(const std::string& list) {
    std::vector<std::string> items;
    for (size_t start = 0; start <= list.size();) {
        size_t end = std::min(list.find(',', start), list.size());
        if (end > start) items.push_back(list.substr(start, end - start));
        start = end + 1;
    }
    return items;
}

// The command line; false (after a message) on an unknown option.
bool parseArgs(int argc, char** argv, Args& args) {
    args.bunnyPath = argv[1], args.envDir = argv[2], args.outDir = argv[3];
    for (int a = 4; a < argc; ++a) {
        std::string flag = argv[a];
        if (flag == "--quick") args.quick = true;
        else if (flag == "--grids" && a + 1 < argc) args.gridList = argv[++a];
        else if (flag == "--scenes" && a + 1 < argc) args.sceneList = argv[++a];
        else if (flag == "--maps" && a + 1 < argc) args.mapList = argv[++a];
        else if (flag == "--sources") args.sources = true;
        else if (flag == "--self-vertices") args.selfVertices = true;
        else if (flag == "--source-grid" && a + 1 < argc) args.sourceGrid = argv[++a];
        else if (flag == "--sharpen" && a + 1 < argc)
            for (const std::string& item : splitList(argv[++a])) args.sharpen.push_back(std::stod(item));
        else {
            std::fprintf(stderr, "fiv_figures: unknown option %s\n", flag.c_str());
            return false;
        }
    }
    return true;
}

// What every measurement shares: the bunny 2 units across (normals from lib/mesh), the 8x8 receiver plane, the
// scenes, the maps and the references over the full map and over the 32^2 cube, keyed by "scene|map".
struct Figures {
    TriMesh bunny, plane;
    float scale = 1;
    std::vector<SceneSpec> scenes;
    std::vector<std::string> maps;
    std::map<std::string, EnvironmentMap> envs;
    std::map<std::string, std::vector<float>> refShadowed, refFree, cubeShadowed, cubeFree;
    json results = json::array();
};

void makeScenes(const Args& args, Figures& f) {
    MeshprepOptions prep;
    prep.input = args.bunnyPath;
    f.bunny = prepareMesh(prep).mesh;
    Bounds bounds = computeBounds(f.bunny);
    float extent = 0;
    for (int c = 0; c < 3; ++c) extent = std::max(extent, bounds.max[size_t(c)] - bounds.min[size_t(c)]);
    f.scale = 2.0f / extent;
    for (float& p : f.bunny.positions) p *= f.scale;
    bounds = computeBounds(f.bunny);
    float cx = 0.5f * (bounds.min[0] + bounds.max[0]), cz = 0.5f * (bounds.min[2] + bounds.max[2]);
    float cy = 0.5f * (bounds.min[1] + bounds.max[1]);
    std::array<float, 3> hover{-cx, 0.5f - bounds.min[1], -cz};
    auto shifted = [&](float x, float y, float z) { return std::array<float, 3>{hover[0] + x, hover[1] + y, hover[2] + z}; };
    f.plane = makePlane(8.0f, 64);
    f.scenes = {
        {"one bunny", false, {hover}},
        {"two bunnies", false, {shifted(-1.1f, 0, 0), shifted(1.1f, 0.6f, 0.4f)}},
        {"three bunnies", false, {shifted(-1.1f, 0, 0), shifted(1.1f, 0.6f, 0.4f), shifted(0.0f, 1.4f, -0.9f)}, true},
        {"straddling", false, {{-cx, -cy, -cz}}},
        {"close (0.05 above)", false, {shifted(0, -0.45f, 0)}, true},
        {"grazing (beside the plane)", false, {{-cx + 5.5f, -cy + 0.3f, -cz}}, true},
        {"self-shadow", true, {}},
    };
    if (!args.sceneList.empty()) {
        std::vector<std::string> keep = splitList(args.sceneList);
        std::erase_if(f.scenes, [&](const SceneSpec& s) { return std::find(keep.begin(), keep.end(), s.name) == keep.end(); });
        for (SceneSpec& s : f.scenes) s.failureOnly = false;
    }
    f.maps = {"courtyard", "sunrise", "constant"};
    if (!args.mapList.empty()) f.maps = splitList(args.mapList);
    for (const std::string& m : f.maps) {
        if (m == "constant") {
            EnvironmentMap env;
            env.radiance.width = 64, env.radiance.height = 32;
            env.radiance.rgb.assign(64 * 32 * 3, 1.0f);
            f.envs[m] = env;
        } else {
            f.envs[m] = readEnvironmentMap(args.envDir + "/" + m + ".exr");
        }
    }
}

// References: brute-force over the full map, shadowed and unshadowed, and over the 32^2 cube. The shadowed full-map
// reference is cached next to the figures: it costs minutes and does not depend on the grid. Returns their cost.
json computeReferences(const Args& args, Figures& f) {
    json referenceCost = json::array();
    for (const SceneSpec& s : f.scenes)
        for (const std::string& m : f.maps) {
            if (s.failureOnly && m != "courtyard") continue;
            const TriMesh& receiver = s.self ? f.bunny : f.plane;
            std::vector<DirectOccluder> occluders;
            for (const auto& p : s.placements) occluders.push_back({f.bunny, p});
            DirectOptions shadowed, unshadowed;
            shadowed.threads = unshadowed.threads = 2;
            unshadowed.shadows = false;
            shadowed.albedo = unshadowed.albedo = std::array<float, 3>{1, 1, 1};
            std::string key = s.name + "|" + m;
            double t0 = nowSeconds();
            const EnvironmentMap& referenceMap = f.envs[m]; // the full map, as prt reference uses it
            std::string cache = args.outDir + "/reference-" + std::to_string(std::hash<std::string>()(key)) + ".npy";
            ReferenceRadiance r;
            if (std::filesystem::exists(cache)) {
                std::vector<size_t> shape;
                r.radiance = readNpy(cache, &shape);
            } else {
                r = referenceDirectRadiance(receiver, occluders, referenceMap, shadowed);
                writeNpy(cache, r.radiance, {receiver.vertexCount(), 3});
            }
            double seconds = nowSeconds() - t0;
            f.refShadowed[key] = r.radiance;
            f.refFree[key] = referenceDirectRadiance(receiver, {}, referenceMap, unshadowed).radiance;
            EnvironmentMap cube = fiv::cubeAsEnvironmentMap(fiv::resampleToCube(f.envs[m], 32));
            f.cubeShadowed[key] = referenceDirectRadiance(receiver, occluders, cube, shadowed).radiance;
            f.cubeFree[key] = referenceDirectRadiance(receiver, {}, cube, unshadowed).radiance;
            referenceCost.push_back({{"scene", s.name}, {"map", m}, {"seconds", seconds}, {"rays", r.rays},
                                     {"map_texels", {referenceMap.radiance.width, referenceMap.radiance.height}}});
            std::fprintf(stderr, "reference %s: %.1f s, %llu rays\n", key.c_str(), seconds, (unsigned long long)r.rays);
        }
    return referenceCost;
}

// The error of the 32^2 cube's own direct sum against the full map's: what no grid can remove.
json cubeOnlyError(const Figures& f) {
    json cubeError = json::array();
    for (const SceneSpec& s : f.scenes)
        for (const std::string& m : f.maps) {
            if (s.failureOnly && m != "courtyard") continue;
            std::string key = s.name + "|" + m;
            Errors e = errors(f.cubeFree.at(key), f.cubeShadowed.at(key), f.refFree.at(key), f.refShadowed.at(key));
            cubeError.push_back({{"scene", s.name}, {"map", m}, {"nrmse", e.nrmse}, {"relative_rmse", e.relativeRmse}});
        }
    return cubeError;
}

// What a reader gets back from a float16 layer.
void roundHalfLayers(Bundle& bundle) {
    for (Layer& layer : bundle.layers)
        if (layer.componentType == "float16")
            for (float& v : layer.data) v = halfToFloat(floatToHalf(v));
}

// One map's source-grid measurement (--source-grid NTxNPxNR [--sharpen K,...]): the sources' own grid
// (fiv::sampleSourceGrid, docs/fiv.md decision 13) through the real layer path: the bundle of `prt fiv --sources
// --source-grid` (float16, the rest of the map on the main grid), written, read back by fivOccluder and shaded by
// fivIrradiance. --sharpen without --source-grid: the source grid at the main grid's resolution (the experiment's
// "main grid" row of docs/results.md). False on a bad grid name.
bool measureSourceGrid(const Args& args, Figures& f, const std::string& m, const fiv::VisibilityOptions& options,
                       const std::string& gridName, const fiv::Visibility& vis, const fiv::SmallSources& found,
                       const fiv::CubeEnvironment& residualCube, const std::vector<float>& difmap,
                       const std::array<double, 9>& fivEnv, const std::vector<float>& self) {
    const std::string sourceGridName = args.sourceGrid.empty() ? gridName : args.sourceGrid;
    fiv::FivGrid rest = fiv::reduceVisibility(vis, residualCube);
    fiv::SourceGridOptions so;
    so.grid = options.grid;
    if (std::sscanf(sourceGridName.c_str(), "%dx%dx%d", &so.grid.azimuth, &so.grid.polar, &so.grid.shells) != 3)
        return false;
    so.threads = 2;
    double sourceSeconds = nowSeconds();
    fiv::SourceGrid sg = fiv::sampleSourceGrid(f.bunny, found, so, "bunny");
    sourceSeconds = nowSeconds() - sourceSeconds;
    std::fprintf(stderr, "source grid %s: %zu samples, %.1f s, %llu source rays, %llu inside-vote rays\n",
                 sourceGridName.c_str(), sg.fraction.size(), sourceSeconds, (unsigned long long)sg.sourceRays,
                 (unsigned long long)sg.insideRays);
    for (double k : args.sharpen.empty() ? std::vector<double>{2.0} : args.sharpen) {
        sg.sharpen = k;
        fiv::FivBundleOptions bundleOptions;
        bundleOptions.selfIrradiance = self;
        bundleOptions.sourceGrid = &sg;
        std::string file = args.outDir + "/source_grid-" + m + "-" + gridName + ".fiv.glb";
        writeBundle(file, fiv::fivBundle(f.bunny, rest, difmap, fivEnv, bundleOptions, {}));
        Bundle bundle = readBundle(file);
        size_t layerBytes = 0;
        for (const Layer& layer : bundle.layers)
            if (layer.name == "fiv_source_grid") layerBytes += 2 * layer.data.size();
            else if (layer.name == "fiv_source_valid") layerBytes += layer.integers.size();
        FivOccluder occluder = fivOccluder(bundle, file);
        FivLighting lighting = fivLighting(bundle, file);
        for (const SceneSpec& s : f.scenes) {
            if (s.failureOnly && m != "courtyard") continue;
            std::string key = s.name + "|" + m;
            const TriMesh& receiver = s.self ? f.bunny : f.plane;
            std::vector<float> free = shadeFiv(receiver, lighting, &occluder, {}, false, {});
            FivShadeOptions mode{FivPartial::Cap, FivOverlap::Paper};
            std::vector<float> shaded = shadeFiv(receiver, lighting, &occluder, s.placements, s.self, mode);
            Errors full = errors(free, shaded, f.refFree[key], f.refShadowed[key]);
            f.results.push_back({{"grid", gridName}, {"samples", options.grid.sampleCount()}, {"map", m},
                                 {"scene", s.name}, {"mode", "cap+paper, source grid K " + std::to_string(k)},
                                 {"source_grid", sourceGridName}, {"source_samples", sg.fraction.size()},
                                 {"source_seconds", sourceSeconds}, {"source_rays", sg.sourceRays},
                                 {"inside_rays", sg.insideRays}, {"source_layer_bytes", layerBytes},
                                 {"storage", "float16"}, {"nrmse", full.nrmse}, {"relative_rmse", full.relativeRmse}});
            std::fprintf(stderr, "source grid %s K %g: %s %s NRMSE %.4f\n", sourceGridName.c_str(), k, s.name.c_str(),
                         m.c_str(), full.nrmse);
        }
    }
    return true;
}

// One map's FIV bundle in float16 and float32, every scene, the partial and overlap modes that matter for it; a
// shadow picture per scene at the last grid.
void measureStorages(const Args& args, Figures& f, const std::string& m, const fiv::VisibilityOptions& options,
                     const std::string& gridName, bool lastGrid, double visibilitySeconds, const fiv::FivGrid& grid,
                     const std::vector<float>& difmap, const std::array<double, 9>& fivEnv,
                     const std::vector<float>& self) {
    for (bool half : {true, false}) {
        fiv::FivBundleOptions bundleOptions;
        bundleOptions.half = half;
        bundleOptions.selfIrradiance = self;
        Bundle bundle = fiv::fivBundle(f.bunny, grid, difmap, fivEnv, bundleOptions, {});
        if (half) roundHalfLayers(bundle);
        FivOccluder occluder = fivOccluder(bundle, "bunny");
        FivLighting lighting = fivLighting(bundle, "bunny");
        for (const SceneSpec& s : f.scenes) {
            if (s.failureOnly && m != "courtyard") continue;
            std::string key = s.name + "|" + m;
            const TriMesh& receiver = s.self ? f.bunny : f.plane;
            std::vector<float> free = shadeFiv(receiver, lighting, &occluder, {}, false, {});
            struct Mode { std::string name; FivShadeOptions options; };
            std::vector<Mode> modes = {{"cap+paper", {FivPartial::Cap, FivOverlap::Paper}}};
            if (half && (s.name == "straddling" || s.name == "grazing (beside the plane)" || s.name == "one bunny"))
                modes.push_back({"literal+paper", {FivPartial::Literal, FivOverlap::Paper}}),
                    modes.push_back({"none+paper", {FivPartial::None, FivOverlap::Paper}});
            if (half && s.placements.size() > 1)
                modes.push_back({"cap+none", {FivPartial::Cap, FivOverlap::None}}),
                    modes.push_back({"cap+shared", {FivPartial::Cap, FivOverlap::Shared}}),
                    modes.push_back({"cap+cap", {FivPartial::Cap, FivOverlap::Cap}});
            for (const Mode& mode : modes) {
                std::vector<float> shaded = shadeFiv(receiver, lighting, &occluder, s.placements, s.self, mode.options);
                Errors full = errors(free, shaded, f.refFree[key], f.refShadowed[key]);
                Errors grid32 = errors(free, shaded, f.cubeFree[key], f.cubeShadowed[key]);
                f.results.push_back({{"grid", gridName}, {"samples", options.grid.sampleCount()}, {"map", m},
                                     {"scene", s.name}, {"mode", mode.name}, {"storage", half ? "float16" : "float32"},
                                     {"nrmse", full.nrmse}, {"relative_rmse", full.relativeRmse},
                                     {"nrmse_vs_cube_reference", grid32.nrmse}, {"shadow_range", full.shadowRange},
                                     {"visibility_seconds", visibilitySeconds}});
                if (half && mode.name == "cap+paper" && !s.self && lastGrid) {
                    std::string file = s.name.substr(0, s.name.find(' ')) + "-" + m + "-" + gridName + ".png";
                    writeShadowPng(args.outDir + "/fiv_shadow_" + file, free, shaded, f.refFree[key], f.refShadowed[key], 65);
                }
            }
        }
    }
}

// Supersampled masks (variant 0) and a 64^2 cube (variant 1, at the 64-wide grid) against the binary mask, under
// the sharp sun and courtyard, for the one-bunny and self-shadow scenes.
void measureMaskVariants(Figures& f, const fiv::VisibilityOptions& options, const GridChoice& g,
                         const std::string& gridName) {
    for (int variant = 0; variant < 2; ++variant) {
        fiv::VisibilityOptions ss = options;
        if (variant == 0) ss.supersample = 2;
        else ss.cube = 64;
        if (variant == 1 && g.nt != 64) continue;
        std::string variantName = variant == 0 ? "cap+paper, supersample 2" : "cap+paper, cube 64";
        double s0 = nowSeconds();
        fiv::Visibility vis2 = fiv::sampleVisibility(f.bunny, ss, "bunny");
        double ssSeconds = nowSeconds() - s0;
        for (const std::string& m : {std::string("sunrise"), std::string("courtyard")}) {
            if (f.envs.count(m) == 0 || f.envs[m].radiance.rgb.empty()) continue; // not among --maps
            fiv::CubeEnvironment cube = fiv::resampleToCube(f.envs[m], ss.cube);
            Bundle bundle = fiv::fivBundle(f.bunny, fiv::reduceVisibility(vis2, cube), fiv::difMap(cube, 32),
                                           fiv::environmentFiv(cube), {}, {});
            roundHalfLayers(bundle);
            FivOccluder occluder = fivOccluder(bundle, "bunny");
            FivLighting lighting = fivLighting(bundle, "bunny");
            for (const SceneSpec& s : f.scenes) {
                if (s.name != "one bunny" && s.name != "self-shadow") continue;
                std::string key = s.name + "|" + m;
                const TriMesh& receiver = s.self ? f.bunny : f.plane;
                std::vector<float> free = shadeFiv(receiver, lighting, &occluder, {}, false, {});
                std::vector<float> shaded = shadeFiv(receiver, lighting, &occluder, s.placements, s.self, {});
                Errors full = errors(free, shaded, f.refFree[key], f.refShadowed[key]);
                Errors grid32 = errors(free, shaded, f.cubeFree[key], f.cubeShadowed[key]);
                f.results.push_back({{"grid", gridName}, {"samples", options.grid.sampleCount()}, {"map", m},
                                     {"scene", s.name}, {"mode", variantName}, {"storage", "float16"},
                                     {"nrmse", full.nrmse}, {"relative_rmse", full.relativeRmse},
                                     {"nrmse_vs_cube_reference", grid32.nrmse}, {"shadow_range", full.shadowRange},
                                     {"visibility_seconds", ssSeconds}});
            }
        }
    }
}

// One main grid: its visibility, then per map the reduction (with --sources, the small sources apart; with
// --self-vertices, the exact self term), the source grid, both storages; the mask variants at the small grids.
// Returns the grid's precompute cost; false in `ok` on a bad grid name.
json measureGrid(const Args& args, Figures& f, const GridChoice& g, bool lastGrid, bool& ok) {
    fiv::VisibilityOptions options;
    options.grid.azimuth = g.nt, options.grid.polar = g.np, options.grid.shells = g.nr;
    options.cube = 32;
    options.allowOpen = true; // the npm bunny has holes in its base
    options.threads = 2;
    double t0 = nowSeconds();
    fiv::Visibility vis = fiv::sampleVisibility(f.bunny, options, "bunny");
    double visibilitySeconds = nowSeconds() - t0;
    std::string gridName = std::to_string(g.nt) + "x" + std::to_string(g.np) + "x" + std::to_string(g.nr);
    size_t invalid = 0;
    for (uint8_t v : vis.valid) invalid += v == 0;
    json cost = {{"grid", gridName}, {"samples", options.grid.sampleCount()}, {"visibility_seconds", visibilitySeconds},
                 {"rays", vis.rays}, {"naive_rays", vis.naiveRays},
                 {"rays_per_sample", double(vis.rays) / double(options.grid.sampleCount())},
                 {"mask_bytes", vis.bits.size()}, {"invalid_samples", invalid}, {"threads", 2}};
    std::fprintf(stderr, "visibility %s: %.1f s, %.0f rays/sample\n", gridName.c_str(), visibilitySeconds,
                 double(vis.rays) / double(options.grid.sampleCount()));
    json reductions = json::array();
    for (const std::string& m : f.maps) {
        double r0 = nowSeconds();
        fiv::CubeEnvironment cube = fiv::resampleToCube(f.envs[m], 32);
        fiv::FivGrid grid;
        json sourceReport, selfReport;
        fiv::SmallSources found;
        fiv::CubeEnvironment residualCube;
        if (args.sources) {
            EnvironmentMap residual = f.envs[m];
            found = fiv::extractSmallSources(residual);
            residualCube = fiv::resampleToCube(residual, 32);
            grid = fiv::reduceVisibility(vis, residualCube);
            uint64_t sourceRays = fiv::addSourceShadows(f.bunny, vis, found, grid, 2);
            sourceReport = {{"texels", found.texelCount}, {"power_fraction", found.powerFraction}, {"rays", sourceRays}};
            std::fprintf(stderr, "sources %s: %zu texels, %llu rays\n", m.c_str(), found.direction.size() / 3,
                         (unsigned long long)sourceRays);
        } else {
            grid = fiv::reduceVisibility(vis, cube);
        }
        std::vector<float> self;
        if (args.selfVertices) {
            double s0 = nowSeconds();
            uint64_t selfRays = 0;
            self = fiv::selfIrradiance(f.bunny, args.sources ? residualCube : cube, found, 2, &selfRays);
            selfReport = {{"vertices", f.bunny.vertexCount()}, {"rays", selfRays}, {"seconds", nowSeconds() - s0},
                          {"bytes_float16", 6 * f.bunny.vertexCount()}};
            std::fprintf(stderr, "self %s: %llu rays, %.2f s\n", m.c_str(), (unsigned long long)selfRays, nowSeconds() - s0);
        }
        std::vector<float> difmap = fiv::difMap(cube, 32);
        std::array<double, 9> fivEnv = fiv::environmentFiv(cube);
        reductions.push_back({{"map", m}, {"seconds", nowSeconds() - r0}, {"sources", sourceReport}, {"self_vertices", selfReport}});
        if (args.sources && (!args.sourceGrid.empty() || !args.sharpen.empty()) && !found.direction.empty() &&
            !measureSourceGrid(args, f, m, options, gridName, vis, found, residualCube, difmap, fivEnv, self)) {
            ok = false;
            return cost;
        }
        measureStorages(args, f, m, options, gridName, lastGrid, visibilitySeconds, grid, difmap, fivEnv, self);
    }
    cost["reductions"] = reductions;
    if (g.nt <= 64 && g.nr == 15) measureMaskVariants(f, options, g, gridName);
    return cost;
}

} // namespace

int main(int argc, char** argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: fiv_figures BUNNY.ply ENV_DIR OUT_DIR [--quick]\n");
        return 2;
    }
    Args args;
    if (!parseArgs(argc, argv, args)) return 2;
    setLogOptions({true, false});
    try {
        Figures f;
        makeScenes(args, f);
        std::vector<GridChoice> grids = {{32, 17, 15}, {64, 33, 15}, {64, 33, 30}, {128, 65, 30}};
        if (args.quick) grids = {{32, 17, 15}, {64, 33, 15}};
        if (!args.gridList.empty()) {
            grids.clear();
            for (const std::string& g : splitList(args.gridList)) {
                GridChoice choice{};
                if (std::sscanf(g.c_str(), "%dx%dx%d", &choice.nt, &choice.np, &choice.nr) != 3) return 2;
                grids.push_back(choice);
            }
        }
        json report;
        report["bunny"] = {{"vertices", f.bunny.vertexCount()}, {"triangles", f.bunny.triangleCount()}, {"scale", f.scale}};
        report["reference_cost"] = computeReferences(args, f);
        report["cube_only_error"] = cubeOnlyError(f);
        json precompute = json::array();
        for (const GridChoice& g : grids) {
            bool ok = true;
            const bool lastGrid = g.nt == grids.back().nt && g.nr == grids.back().nr;
            precompute.push_back(measureGrid(args, f, g, lastGrid, ok));
            if (!ok) return 2;
        }
        report["precompute"] = precompute;
        report["results"] = f.results;
        report["bytes_per_sample"] = {{"float16", 25}, {"float32", 49}, {"seed", 36}};
        std::ofstream(args.outDir + "/fiv_figures.json") << report.dump(1) << "\n";
        std::cout << report.dump(1) << "\n";
    } catch (const Error& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return e.exitCode();
    }
    return 0;
}
