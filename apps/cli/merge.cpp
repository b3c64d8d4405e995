// prt merge: joins the shard bundles of a sharded stage into the bundle the unsharded stage writes, bit for bit.
#include "cli.h"

#include "bundle.h"
#include "core.h"
#include "pipeline.h"

#include <memory>

namespace prt::cli {

namespace {

struct MergeArgs {
    std::vector<std::string> shards;
    std::string output;
};

void runMerge(const MergeArgs& args) {
    double start = nowSeconds();
    mergeShardFiles(args.shards, args.output); // streamed: no layer is held whole
    logInfo("merge: joined " + std::to_string(args.shards.size()) + " shards into " + args.output);
    StageCost cost;
    cost.stage = "merge";
    cost.seconds = nowSeconds() - start;
    cost.peakMemoryBytes = peakMemoryBytes();
    reportCost(cost);
}

} // namespace

void addMergeCommand(CLI::App& app) {
    auto args = std::make_shared<MergeArgs>();
    CLI::App* command = app.add_subcommand("merge", "Join shard bundles (--shard I/N outputs) into one bundle");
    command->add_option("shards", args->shards, "Every shard bundle of one run, in any order")->required();
    command->add_option("-o,--output", args->output, "Merged bundle (.glb)")->required();
    command->callback([args] { runMerge(*args); });
}

} // namespace prt::cli
