// libFuzzer harness: the files between the passes of sharded interreflected transfer (hit records, a shard's
// rows, a pass's exitant array; layout in lib/transfer/shard_files.cpp), through the readers the passes use: hit
// records, rows (total and direct), the exitant array, and the gather (a rows file's exitant section). The first
// byte picks the reader, the rest is the file. The run they are checked against is fixed (below), so seeds written for it get past the identity
// check to the payload. PRT_FUZZ_WRITE_SEEDS=DIR writes those seeds (tests/fuzz/corpus/shard) and exits.
#include "fuzz_util.h"
#include "passes.h"
#include "transfer.h"

#include <cstdlib>
#include <filesystem>

namespace {

prt::ShardRun fuzzRun() {
    prt::ShardRun run;
    run.meshHash = "xxh128:00000000000000000000000000000000";
    run.vertexCount = 4;
    run.triangleCount = 4;
    run.options.mode = prt::TransferMode::Interreflected;
    run.options.order = 2;
    run.options.samples = 8;
    run.options.bounces = 2;
    run.channels = 1;
    run.shardIndex = 0;
    run.shardCount = 1;
    run.rowBegin = 0;
    run.rowEnd = 4;
    return run;
}

void writeSeeds(const std::string& dir) {
    namespace fs = std::filesystem;
    fs::create_directories(dir);
    const prt::ShardRun run = fuzzRun();
    const std::string work = prt::fuzz::folder();
    prt::passes::HitBlock block;
    block.end = {1, 2, 3, 4};
    block.triangle = {0, 1, 2, 3};
    block.barycentric = {0, 0x7fff7fffu, 0xffffu, 0xffff0000u};
    block.sample = {0, 1, 2, 7};
    prt::passes::writeHitRecords(work + "/hits", run, {block});
    prt::ShardRows rows;
    rows.pass = 1;
    rows.rowBegin = 0;
    rows.rowEnd = 4;
    rows.total.assign(4 * 4 * 3, 0.25f);
    rows.direct.assign(4 * 4 * 3, 0.125f);
    rows.exitant.assign(4 * 4 * 1, 0.5f);
    rows.rays = 32;
    rows.hits = 4;
    rows.rayOffset = 1e-4f;
    prt::writeShardRows(work + "/rows", run, rows);
    prt::gatherExitant({work + "/rows"}, run, work + "/exitant");
    // One seed per reader: the reader byte, then the file.
    const char* files[] = {"hits", "rows", "exitant", "rows"};
    for (int reader = 0; reader < 4; ++reader) {
        std::string bytes(1, char(reader));
        bytes += prt::readFileBytes(work + "/" + files[reader]);
        prt::writeBytesAtomic(dir + "/" + std::to_string(reader) + "-" + files[reader], bytes);
    }
}

} // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    if (const char* dir = std::getenv("PRT_FUZZ_WRITE_SEEDS")) {
        writeSeeds(dir);
        std::exit(0);
    }
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    prt::fuzz::capElements();
    const prt::ShardRun run = fuzzRun();
    std::string path = prt::fuzz::writeInput(data + 1, size - 1, "shard");
    prt::fuzz::expectOnlyErrors([&] {
        switch (data[0] % 4) {
        case 0: prt::passes::readHitRecords(path, run); break;
        case 1: prt::readShardRows(path, run, 1); break;
        case 2: prt::passes::readExitant(path, run, 1, {1, 0, 1, 1}); break; // rows 0, 2 and 3 kept
        default: prt::gatherExitant({path}, run, prt::fuzz::folder() + "/gathered"); break; // their exitant section
        }
    });
    return 0;
}
