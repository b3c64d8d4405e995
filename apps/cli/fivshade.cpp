// prt fivshade: per-vertex radiance of a receiver under translated occluders from their FIV bundles, or from one
// FIV scene bundle; prt fivscene: that scene bundle (docs/fiv.md).
#include "cli.h"

#include "bundle.h"
#include "compare.h"
#include "core.h"
#include "fiv.h"
#include "runtime.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>

namespace prt::cli {

namespace {

struct FivshadeArgs {
    std::string receiver, env, output, self, albedo, partial = "cap", overlap = "cap";
    std::vector<std::string> occluders, at;
};

FivPartial parsePartial(const std::string& text) {
    if (text == "none") return FivPartial::None;
    if (text == "literal") return FivPartial::Literal;
    if (text == "cap") return FivPartial::Cap;
    throw Error("", "--partial", "'" + text + "' is not none, literal or cap", kExitUsage);
}

FivOverlap parseOverlap(const std::string& text) {
    if (text == "none") return FivOverlap::None;
    if (text == "paper") return FivOverlap::Paper;
    if (text == "shared") return FivOverlap::Shared;
    if (text == "cap") return FivOverlap::Cap;
    throw Error("", "--overlap", "'" + text + "' is not none, paper, shared or cap", kExitUsage);
}

// One --at per --occluder, each three finite numbers.
std::vector<std::array<float, 3>> parsePlacements(const std::vector<std::string>& occluders,
                                                  const std::vector<std::string>& at) {
    if (occluders.size() != at.size())
        throw Error("", "--at", "give one --at X,Y,Z per --occluder (" + std::to_string(occluders.size()) +
                                    " occluders, " + std::to_string(at.size()) + " placements)", kExitUsage);
    std::vector<std::array<float, 3>> placements;
    for (const std::string& text : at) {
        placements.push_back(parsePoint(text, "--at"));
        for (float x : placements.back())
            if (std::abs(double(x)) > kFivMaxCoordinate)
                throw Error("", "--at", "'" + text + "' lies beyond +-" + std::to_string(int64_t(kFivMaxCoordinate)) +
                                            " (FIV bounds coordinates: float32 spacing there is 64 units)", kExitUsage);
    }
    return placements;
}

void runFivshade(const FivshadeArgs& args) {
    double start = nowSeconds();
    FivShadeOptions options;
    options.partial = parsePartial(args.partial);
    options.overlap = parseOverlap(args.overlap);
    std::vector<std::array<float, 3>> placements = parsePlacements(args.occluders, args.at);
    std::string extension = fileExtension(args.output);
    if (extension != "npy" && extension != "csv") throw Error(args.output, "-o", "needs a .npy or .csv file", kExitUsage);
    std::array<double, 3> albedo{1, 1, 1};
    if (!args.albedo.empty()) albedo = parseAlbedo(args.albedo);

    Bundle receiverBundle = readBundle(args.receiver);
    const TriMesh& receiver = receiverBundle.mesh;
    bool fromScene = isFivScene(receiverBundle);
    if (fromScene && (!args.occluders.empty() || !args.self.empty()))
        throw Error("", "--occluder", args.receiver + " is a FIV scene bundle, which places its own occluders: give "
                                      "no --occluder or --self with it", kExitUsage);
    if (!fromScene && args.occluders.empty() && args.self.empty())
        throw Error("", "--occluder", "needs at least one --occluder or --self, or a FIV scene bundle", kExitUsage);
    if (receiver.normals.size() != receiver.positions.size() || receiver.positions.empty())
        throw Error(args.receiver, "mesh", "has no vertex normals (prt meshprep adds them)");
    checkFivPoints(receiver.positions, args.receiver);
    std::string envHash = hashFile(args.env);

    // Each distinct file is loaded once: instances of one type share its grid.
    std::vector<std::string> files = args.occluders;
    if (!args.self.empty()) files.push_back(args.self);
    std::vector<std::unique_ptr<FivOccluder>> types;
    std::vector<std::string> typeFiles;
    FivLighting lighting;
    auto load = [&](const std::string& file) -> const FivOccluder* {
        for (size_t t = 0; t < typeFiles.size(); ++t)
            if (typeFiles[t] == file) return types[t].get();
        Bundle bundle = readBundle(file);
        auto occluder = std::make_unique<FivOccluder>(fivOccluder(bundle, file));
        if (occluder->envHash != envHash)
            throw Error(file, "fiv", "was reduced under another environment than " + args.env +
                                         " (run `prt fiv` with this --env)");
        if (typeFiles.empty()) lighting = fivLighting(bundle, file);
        typeFiles.push_back(file);
        types.push_back(std::move(occluder));
        return types.back().get();
    };
    std::vector<FivInstance> instances;
    for (size_t j = 0; j < args.occluders.size(); ++j) {
        FivInstance instance;
        instance.occluder = load(args.occluders[j]);
        for (int c = 0; c < 3; ++c) instance.translation[c] = placements[j][size_t(c)];
        instances.push_back(instance);
    }
    FivInstance self;
    if (!args.self.empty()) {
        self.occluder = load(args.self);
        // The exact per-vertex self-shadowing (layer fiv_self) holds for the mesh it was computed on: use it when
        // the receiver is that mesh, vertex for vertex; otherwise the grid's FIV_self, as before.
        if (!self.occluder->selfIrradiance.empty()) {
            const TriMesh& own = readBundle(args.self).mesh;
            if (own.positions == receiver.positions && own.normals == receiver.normals)
                self.selfIrradiance = self.occluder->selfIrradiance.data();
            else
                logInfo("fivshade: " + args.self + " has fiv_self for another mesh than " + args.receiver +
                        "; using its grid");
        }
    }
    FivScene scene;
    bool selfShadowing = !args.self.empty();
    if (fromScene) {
        scene = fivScene(receiverBundle, args.receiver);
        if (scene.lighting.envHash != envHash)
            throw Error(args.receiver, "difmap", "was reduced under another environment than " + args.env +
                                                     " (run `prt fiv` with this --env, then `prt fivscene`)");
        lighting = scene.lighting;
        instances = scene.instances;
        self = scene.self;
        selfShadowing = scene.selfShadowing;
    }

    // What the sources' own grids (decision 13) do here, said once per run.
    for (const FivInstance& instance : instances)
        if (instance.occluder->sources.azimuth > 0) {
            const FivSourceGrid& g = instance.occluder->sources;
            logInfo("fivshade: the small sources' shadow comes from their own grid " + std::to_string(g.azimuth) + "x" +
                    std::to_string(g.polar) + "x" + std::to_string(g.shells) + " (sharpened, K " +
                    std::to_string(g.sharpen) + "); --partial does not apply to it, and it combines over occluders as "
                    "1 - prod(1 - g)" + (options.overlap == FivOverlap::None ? " (--overlap none: the sum)" : ""));
            break;
        }
    if (selfShadowing && self.occluder && self.occluder->sources.azimuth > 0)
        logInfo(self.selfIrradiance ? "fivshade: self-shadowing from fiv_self, which holds the sources exactly"
                                    : "fivshade: self-shadowing through the grid: its sources' hidden part comes back from "
                                      "the source grid, signed (N . FIV_sources, as FIV_self held it with --sources alone)");

    size_t count = receiver.vertexCount();
    std::vector<float> normals(receiver.normals);
    for (size_t v = 0; v < count; ++v) {
        float* n = &normals[3 * v];
        float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(length > 0.0f)) throw Error(args.receiver, "normal " + std::to_string(v), "is zero");
        for (int c = 0; c < 3; ++c) n[c] /= length;
    }
    std::vector<float> radiance(3 * count);
    double shadeStart = nowSeconds();
    fivIrradiance(lighting, instances.data(), instances.size(), selfShadowing ? &self : nullptr,
                  receiver.positions.data(), normals.data(), count, options, radiance.data());
    double shadeSeconds = nowSeconds() - shadeStart;
    for (size_t v = 0; v < count; ++v)
        for (int c = 0; c < 3; ++c) {
            double a = args.albedo.empty() && !receiver.albedo.empty() ? receiver.albedo[3 * v + c] : albedo[size_t(c)];
            radiance[3 * v + c] = float(a / std::numbers::pi * radiance[3 * v + c]);
        }
    writeVertexRadiance(args.output, radiance);
    logInfo("fivshade: " + std::to_string(count) + " points, " + std::to_string(instances.size()) + " occluders" +
            (selfShadowing ? " and self-shadowing" : "") + ", " +
            std::to_string(shadeSeconds > 0 ? int(double(count) / shadeSeconds) : 0) + " points/s");
    StageCost cost;
    cost.stage = "fivshade";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

struct FivsceneArgs {
    std::string receiver, output, self;
    std::vector<std::string> occluders, at;
};

void runFivscene(const FivsceneArgs& args) {
    double start = nowSeconds();
    std::vector<std::array<float, 3>> at = parsePlacements(args.occluders, args.at);
    if (fileExtension(args.output) != "glb") throw Error(args.output, "-o", "needs a .glb file", kExitUsage);
    Bundle receiver = readBundle(args.receiver);
    // Each distinct file is one occluder type; its placements are instances of it.
    std::vector<std::string> files;
    std::vector<Bundle> bundles;
    std::vector<fiv::ScenePlacement> placements;
    for (size_t j = 0; j < args.occluders.size(); ++j) {
        size_t type = std::find(files.begin(), files.end(), args.occluders[j]) - files.begin();
        if (type == files.size()) {
            files.push_back(args.occluders[j]);
            bundles.push_back(readBundle(args.occluders[j]));
        }
        placements.push_back({type, at[j]});
    }
    std::vector<fiv::SceneType> types;
    for (size_t t = 0; t < files.size(); ++t) {
        std::string stem = std::filesystem::path(files[t]).filename().string();
        types.push_back({&bundles[t], files[t], stem.substr(0, stem.find('.'))});
    }
    Bundle self;
    if (!args.self.empty()) self = readBundle(args.self);
    Bundle scene = fiv::fivSceneBundle(receiver, args.receiver, types, placements, args.self.empty() ? nullptr : &self,
                                       args.self);
    writeBundle(args.output, scene);
    logInfo("fivscene: " + args.output + ": " + std::to_string(types.size()) + " occluder types, " +
            std::to_string(placements.size()) + " instances" + (args.self.empty() ? "" : ", self-shadowing"));
    StageCost cost;
    cost.stage = "fivscene";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addFivsceneCommand(CLI::App& app) {
    auto args = std::make_shared<FivsceneArgs>();
    CLI::App* command = app.add_subcommand(
        "fivscene", "One bundle (version 2) with a receiver, occluder types with their FIV grids and their instances, "
                    "for `prt fivshade SCENE.glb` and engines");
    command->add_option("receiver", args->receiver, "Receiver mesh (.glb) with vertex normals")->required();
    command->add_option("--occluder", args->occluders, "FIV bundle of an occluder type (repeatable, one per --at)");
    command->add_option("--at", args->at,
                        "X,Y,Z: the occluder's translation; its vertex p sits at p + (X,Y,Z) (repeatable)");
    command->add_option("--self", args->self, "FIV bundle of the receiver itself, for self-shadowing");
    command->add_option("-o,--output", args->output, "Scene bundle (.glb)")->required();
    command->callback([args] { runFivscene(*args); });
}

void addFivshadeCommand(CLI::App& app) {
    auto args = std::make_shared<FivshadeArgs>();
    CLI::App* command = app.add_subcommand(
        "fivshade", "Direct-light radiance per receiver vertex under translated occluders, from their FIV grids "
                    "(diffuse, distant environment, no interreflection)");
    command->add_option("receiver", args->receiver,
                        "Receiver mesh (.glb) with vertex normals, or a FIV scene bundle (`prt fivscene`)")->required();
    command->add_option("--env", args->env, "The environment map the FIV bundles were reduced with")->required();
    command->add_option("--occluder", args->occluders, "FIV bundle of an occluder type (repeatable, one per --at)");
    command->add_option("--at", args->at,
                        "X,Y,Z: the occluder's translation; its vertex p sits at p + (X,Y,Z) (repeatable)");
    command->add_option("--self", args->self, "FIV bundle of the receiver itself, for self-shadowing");
    command->add_option("--albedo", args->albedo, "Diffuse albedo R,G,B or one grey value (default: COLOR_0, else 1)");
    command->add_option("--partial", args->partial, "Straddling occluders (case B): none, literal or cap")->capture_default_str();
    command->add_option("--overlap", args->overlap, "Overlapping occluders: none, paper, shared or cap")->capture_default_str();
    command->add_option("-o,--output", args->output, "Radiance per vertex (.npy [V,3] or .csv)")->required();
    command->callback([args] { runFivshade(*args); });
}

} // namespace prt::cli
