// prt fivshade: per-vertex radiance of a receiver under translated occluders from their FIV bundles (docs/fiv.md).
#include "cli.h"

#include "bundle.h"
#include "compare.h"
#include "core.h"
#include "runtime.h"

#include <cmath>
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

void runFivshade(const FivshadeArgs& args) {
    double start = nowSeconds();
    FivShadeOptions options;
    options.partial = parsePartial(args.partial);
    options.overlap = parseOverlap(args.overlap);
    if (args.occluders.size() != args.at.size())
        throw Error("", "--at", "give one --at X,Y,Z per --occluder (" + std::to_string(args.occluders.size()) +
                                    " occluders, " + std::to_string(args.at.size()) + " placements)", kExitUsage);
    std::vector<std::array<float, 3>> placements;
    for (const std::string& at : args.at) placements.push_back(parsePoint(at, "--at"));
    if (args.occluders.empty() && args.self.empty())
        throw Error("", "--occluder", "needs at least one --occluder or --self", kExitUsage);
    std::string extension = fileExtension(args.output);
    if (extension != "npy" && extension != "csv") throw Error(args.output, "-o", "needs a .npy or .csv file", kExitUsage);
    std::array<double, 3> albedo{1, 1, 1};
    if (!args.albedo.empty()) albedo = parseAlbedo(args.albedo);

    Bundle receiverBundle = readBundle(args.receiver);
    const TriMesh& receiver = receiverBundle.mesh;
    if (receiver.normals.size() != receiver.positions.size() || receiver.positions.empty())
        throw Error(args.receiver, "mesh", "has no vertex normals (prt meshprep adds them)");
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
    if (!args.self.empty()) self.occluder = load(args.self);

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
    fivIrradiance(lighting, instances.data(), instances.size(), args.self.empty() ? nullptr : &self,
                  receiver.positions.data(), normals.data(), count, options, radiance.data());
    double shadeSeconds = nowSeconds() - shadeStart;
    for (size_t v = 0; v < count; ++v)
        for (int c = 0; c < 3; ++c) {
            double a = args.albedo.empty() && !receiver.albedo.empty() ? receiver.albedo[3 * v + c] : albedo[size_t(c)];
            radiance[3 * v + c] = float(a / std::numbers::pi * radiance[3 * v + c]);
        }
    writeVertexRadiance(args.output, radiance);
    logInfo("fivshade: " + std::to_string(count) + " points, " + std::to_string(instances.size()) + " occluders" +
            (args.self.empty() ? "" : " and self-shadowing") + ", " +
            std::to_string(shadeSeconds > 0 ? int(double(count) / shadeSeconds) : 0) + " points/s");
    StageCost cost;
    cost.stage = "fivshade";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addFivshadeCommand(CLI::App& app) {
    auto args = std::make_shared<FivshadeArgs>();
    CLI::App* command = app.add_subcommand(
        "fivshade", "Direct-light radiance per receiver vertex under translated occluders, from their FIV grids "
                    "(diffuse, distant environment, no interreflection)");
    command->add_option("receiver", args->receiver, "Receiver mesh (.glb) with vertex normals")->required();
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
