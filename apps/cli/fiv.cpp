// prt fiv: an occluder type's FIV grid (visibility masks, then the environment reduction); docs/fiv.md.
#include "cli.h"

#include "core.h"
#include "fiv.h"

#include <memory>
#include <sstream>

namespace prt::cli {

namespace {

struct FivArgs {
    fiv::FivStageOptions stage;
    std::string grid = "128,65,30";
    std::string shells = "0.25,8";
    std::string shard;
    std::string sourceGrid;    // --source-grid NT,NP,NR ("" none)
    std::string sourceSharpen; // --source-sharpen K ("" the default)
    bool float32 = false;
};

std::vector<double> parseList(const std::string& text, size_t count, const char* option) {
    std::vector<double> values;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        size_t used = 0;
        double v = 0.0;
        try {
            v = std::stod(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != item.size()) throw Error("", option, "'" + text + "' is not a comma-separated list of numbers", kExitUsage);
        values.push_back(v);
    }
    if (values.size() != count)
        throw Error("", option, "'" + text + "' needs " + std::to_string(count) + " comma-separated numbers", kExitUsage);
    return values;
}

void runFivCommand(FivArgs args) {
    std::vector<double> grid = parseList(args.grid, 3, "--grid");
    for (double g : grid)
        if (g != std::floor(g) || g < 0 || g > 1e9) throw Error("", "--grid", "'" + args.grid + "' needs three whole numbers", kExitUsage);
    args.stage.visibility.grid.azimuth = int(grid[0]);
    args.stage.visibility.grid.polar = int(grid[1]);
    args.stage.visibility.grid.shells = int(grid[2]);
    std::vector<double> shells = parseList(args.shells, 2, "--shells");
    args.stage.visibility.grid.shellMin = shells[0];
    args.stage.visibility.grid.shellMax = shells[1];
    fiv::checkGrid(args.stage.visibility.grid, "", kExitUsage); // before anything is read or allocated
    fiv::checkWork(args.stage.visibility.grid, args.stage.visibility.cube, args.stage.visibility.supersample, "",
                   kExitUsage);
    if (args.sourceGrid == "auto") { // twice the main grid's resolution: 2 NT, 2 NP - 1 (the poles kept), 2 NR
        const fiv::GridSpec& g = args.stage.visibility.grid;
        args.sourceGrid = std::to_string(2 * g.azimuth) + "," + std::to_string(2 * g.polar - 1) + "," + std::to_string(2 * g.shells);
    }
    if (!args.sourceGrid.empty()) {
        std::vector<double> sg = parseList(args.sourceGrid, 3, "--source-grid");
        for (double g : sg)
            if (g != std::floor(g) || g < 1 || g > 1e9)
                throw Error("", "--source-grid", "'" + args.sourceGrid + "' needs three whole numbers", kExitUsage);
        fiv::GridSpec& g = args.stage.sourceGrid;
        g = args.stage.visibility.grid; // the main grid's shells and spacing
        g.azimuth = int(sg[0]), g.polar = int(sg[1]), g.shells = int(sg[2]);
        fiv::checkSourceGrid(g, 0, "", kExitUsage); // before anything is read or allocated
    }
    if (!args.sourceSharpen.empty()) {
        if (args.sourceGrid.empty()) throw Error("", "--source-sharpen", "needs --source-grid", kExitUsage);
        double k = parseList(args.sourceSharpen, 1, "--source-sharpen")[0];
        if (!(k >= fiv::kMinSourceSharpen && k <= fiv::kMaxSourceSharpen))
            throw Error("", "--source-sharpen", "'" + args.sourceSharpen + "' is outside 1..100", kExitUsage);
        args.stage.sourceSharpen = k;
    }
    if (!args.shard.empty()) parseShard(args.shard, args.stage.visibility.shardIndex, args.stage.visibility.shardCount);
    args.stage.visibility.threads = resolveThreads(args.stage.visibility.threads);
    args.stage.half = !args.float32;
    fiv::runFiv(args.stage);
}

} // namespace

// The options both subcommands share: `prt fiv-visibility` is `prt fiv --visibility-only`, a stage of its own
// so that pipelines cache and shard the environment-independent half apart from the reduction.
static void addFivOptions(CLI::App* command, const std::shared_ptr<FivArgs>& args, bool visibilityStage) {
    // Not required by CLI11: --merge SHARD... takes the words after it, and then needs no mesh (checkFivOptions).
    command->add_option("input", args->stage.inputs,
                        "Occluder mesh (.glb, closed), or the visibility bundle(s) of `--visibility-only` (all shards)");
    command->add_option("-o,--output", args->stage.output, "Output bundle (.glb)")->required();
    if (!visibilityStage)
        command->add_option("--env", args->stage.env, "Environment map (2:1 equirectangular or 1:6 cube strip)");
    command->add_option("--grid", args->grid, "Samples NT,NP,NR: azimuth, polar (poles included), shells")->capture_default_str();
    command->add_option("--shells", args->shells,
                        "Innermost and outermost shell radius MIN,MAX in bounding-sphere radii (log spaced)")
        ->capture_default_str();
    command->add_option("--spacing", args->stage.visibility.grid.spacing, "Shell spacing: log or linear")->capture_default_str();
    command->add_option("--cube", args->stage.visibility.cube, "Environment cube face size N (6 x N x N texels)")->capture_default_str();
    command->add_option("--supersample", args->stage.visibility.supersample,
                        "S x S rays per cube texel: fractional coverage against the binary mask's aliasing")
        ->capture_default_str();
    command->add_option("--difmap", args->stage.difmapSize, "DifMap (irradiance cube) face size")->capture_default_str();
    if (!visibilityStage)
        command->add_flag("--visibility-only", args->stage.visibilityOnly,
                          "Write the environment-independent visibility (part a) only; reduce it later with --env");
    command->add_option("--shard", args->shard, "With --visibility-only: grid rows of shard I/N");
    command->add_option("--merge", args->stage.merge, "With --visibility-only: join these visibility shards");
    command->add_flag("--allow-open", args->stage.visibility.allowOpen,
                      "Accept an open occluder: samples count as inside when most of 26 rays first hit a back face");
    command->add_flag("--float32", args->float32, "Store the grid as float32 (default float16)");
    if (!visibilityStage)
        command->add_flag("--sources", args->stage.sources,
                          "Shadow the map's dominant small sources (a sun) by rays toward their own texels, not "
                          "through the cube (docs/fiv.md, decision 13)");
    if (!visibilityStage) {
        command->add_option("--source-grid", args->sourceGrid,
                            "With --sources: the sources' own grid NT,NP,NR, or auto (2 NT, 2 NP - 1, 2 NR of --grid: "
                            "256,129,60 for the default), "
                            "interpolated and sharpened on its own; the main grid keeps the rest (docs/fiv.md, decision 13)");
        command->add_option("--source-sharpen", args->sourceSharpen,
                            "With --source-grid: K of the sharpened fraction clamp(0.5 + K (f - 0.5), 0, 1), 1..100 "
                            "(default 2)");
    }
    if (!visibilityStage)
        command->add_flag("--self-vertices", args->stage.selfVertices,
                          "Store the mesh's own self-shadowed irradiance at its vertices (layer fiv_self), which "
                          "fivshade --self uses when the receiver is this mesh (docs/fiv.md, decision 14)");
    command->add_option("--threads", args->stage.visibility.threads, "Worker threads (default: all)");
    command->callback([args, visibilityStage] {
        if (visibilityStage) args->stage.visibilityOnly = true;
        runFivCommand(*args);
    });
}

void addFivCommand(CLI::App& app) {
    auto args = std::make_shared<FivArgs>();
    CLI::App* command = app.add_subcommand(
        "fiv", "FIV grid of an occluder type: which environment texels it hides from receivers all around it (Embree "
               "rays), reduced under an environment into 9 floats per sample, the DifMap and FIV(Env)");
    addFivOptions(command, args, false);
}

void addFivVisibilityCommand(CLI::App& app) {
    auto args = std::make_shared<FivArgs>();
    CLI::App* command = app.add_subcommand(
        "fiv-visibility", "The environment-independent half of `prt fiv` (= prt fiv --visibility-only): the masks");
    addFivOptions(command, args, true);
}

} // namespace prt::cli
