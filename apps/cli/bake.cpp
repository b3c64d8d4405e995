// prt bake: per-texel diffuse SH transfer of a mesh's atlas, written as textures next to a bundle that references
// them (lib/bake runBake).
#include "cli.h"

#include "bake.h"
#include "core.h"
#include "runtime.h"
#include "sh.h"
#include "transfer.h"

#include <memory>

#ifndef PRT_VERSION
#define PRT_VERSION "0.0.0"
#endif

namespace prt::cli {

namespace {

struct BakeArgs {
    BakeOptions options;
    std::string format = "half";
    std::string wrap = "none";
    std::string albedo;
    bool noSeamStitch = false;
    bool lowPosition = false;
    std::string shard;
};

void runBakeCommand(BakeArgs args) {
    BakeOptions& options = args.options;
    options.format = parseTexelFormat(args.format);
    options.wrap = parseUvWrap(args.wrap);
    options.seamStitch = !args.noSeamStitch;
    options.highPosition = !args.lowPosition;
    if (!args.albedo.empty()) {
        std::array<double, 3> albedo = parseAlbedo(args.albedo);
        options.albedo = {float(albedo[0]), float(albedo[1]), float(albedo[2])};
        options.albedoOverride = true;
    }
    if (options.threads < 0) throw Error("", "--threads", "must be >= 0 (0: all cores)", kExitUsage);
    options.threads = resolveThreads(options.threads);
    options.toolVersion = PRT_VERSION;
    if (!args.shard.empty()) parseShard(args.shard, options.shardIndex, options.shardCount);
    // The atlas's floats (transfer RGB per coefficient, surface and normal channels per texel), refused by the
    // element cap before anything is allocated; runBake checks the ranges themselves.
    if (options.resolution >= 1 && options.resolution <= kMaxBakeResolution && options.order >= 1 &&
        options.order <= sh::kMaxOrder)
        checkCommandLineSize({uint64_t(options.resolution), uint64_t(options.resolution),
                              uint64_t(3 * options.order * options.order + kTexelSurfaceChannels + 3)},
                             "atlas values (resolution^2 texels x (3 order^2 + 13) floats)", "--resolution");
    runBake(options);
}

} // namespace

void addBakeCommand(CLI::App& app) {
    auto args = std::make_shared<BakeArgs>();
    BakeOptions& o = args->options;
    CLI::App* command = app.add_subcommand(
        "bake", "Per-texel SH transfer into atlas textures (optionally with detail from a high-resolution mesh)");
    command->add_option("mesh", o.input, "Low mesh with normals (.glb from `prt meshprep`); its UVs, or a generated "
                                         "lightmap atlas when it has none")
        ->required();
    command->add_option("-o,--output", o.output,
                        "Output bundle (.glb); the textures go next to it as NAME.transfer.HASH.exr (or NAME.transfer.HASH.json "
                        "and NAME.transfer.TJJJ.HASH.png with --format u8) and NAME.normal.HASH.png, HASH from their content")
        ->required();
    command->add_option("--high", o.high, "High-resolution mesh with normals: normals, positions and shadows come "
                                          "from it (cage projection along the low normals)");
    command->add_option("--resolution", o.resolution,
                        "Atlas side in texels, 1.." + std::to_string(kMaxBakeResolution) + " (default 512)");
    command->add_option("--order", o.order, "Number of SH bands L (L*L coefficients), 1.." +
                                                std::to_string(sh::kMaxOrder) + " (default 3)");
    command->add_option("--samples", o.samples,
                        "Hemisphere directions per texel, 1.." + std::to_string(kMaxTransferSamples) +
                            " (default 1024)");
    command->add_option("--bounces", o.bounces, "Interreflection bounces (default 0: shadowed)");
    command->add_option("--albedo", args->albedo,
                        "Diffuse albedo R,G,B (or one grey value) in [0,1]; overrides the mesh's per-vertex albedo "
                        "(default: the mesh's, else 1)");
    command->add_option("--uv-set", o.uvSet,
                        "Bake into TEXCOORD_K of the input (default: TEXCOORD_0 of a mesh; a scene's TEXCOORD_1 when it "
                        "is unique, else an atlas generated over every instance)")
        ->check(CLI::Range(0, 7));
    command->add_flag("--generate-atlas", o.generateAtlas,
                      "Bake into a generated lightmap atlas whatever texcoords the input has (texcoords shared by "
                      "instances, overlapping or of zero area are no lightmap)");
    command->add_option("--format", args->format,
                        "Coefficient storage: half or float (one multi-channel OpenEXR) or u8 (8-bit PNG per "
                        "coefficient with a per-layer [min, max] JSON sidecar) or bundle (float32 rows in the bundle's own "
                        "buffer, no texture: what the thin runtime and the viewer read); default half");
    command->add_option("--wrap", args->wrap, "UVs outside [0, 1]: none (an error, default) or repeat");
    command->add_flag("--allow-overlap", o.allowOverlap,
                      "Accept overlapping UVs (the lowest triangle keeps a shared texel) instead of failing");
    command->add_flag("--dilate-only", o.dilateOnly,
                      "Fill gutters by one ring of dilation (the thesis's fill) instead of push-pull");
    command->add_flag("--no-seam-stitch", args->noSeamStitch, "Leave the two sides of UV seams as baked");
    command->add_flag("--low-position", args->lowPosition,
                      "With --high: shade at the low surface's point (normals and shadows still from the high mesh)");
    command->add_option("--cage", o.cage, "Cage distance for --high, relative to the low mesh's bounding-box "
                                          "diagonal (default 0.02)");
    command->add_option("--max-miss", o.maxMissFraction,
                        "With --high: the largest fraction of texels allowed to miss the high mesh (default 0.01)");
    command->add_option("--padding", o.padding, "Texels between charts of a generated atlas (default 4)");
    command->add_option("--seed", o.seed, "Seed of the per-texel direction rotations (default 0)");
    command->add_option("--threads", o.threads, "Worker threads (default 0: all cores)");
    command->add_flag("--yardstick", o.yardstick,
                      "Also cast the direct pass's rays with bare Embree and log both throughputs");
    CLI::Option* shard = command->add_option(
        "--shard", args->shard,
        "I/N: compute only the I-th of N contiguous ranges of covered texels, written to -o as a 'texel_range' "
        "bundle (no textures) for a later --merge");
    command->add_option("--merge", o.shardFiles,
                        "Join these shard bundles (every --shard I/N of one bake, any order, baked with the same "
                        "options as given here), then fill, stitch and write as the unsharded bake does")
        ->excludes(shard);
    optionNeeds(command, "--cage", "--high");
    optionNeeds(command, "--low-position", "--high");
    command->callback([args] { runBakeCommand(*args); });
}

} // namespace prt::cli
