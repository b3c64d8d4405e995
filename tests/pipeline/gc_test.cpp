// Store garbage collection: after a sharded interreflected run the store keeps the stages' own entries only (no
// hit records, pass rows, gathered arrays or shard bundles), a rerun is fully cached, the store stays within 1.5x
// the outputs, `prt gc` removes what no recorded run needs, and a collector killed at any checkpoint leaves a
// consistent store.
#include "pipeline_test_util.h"

namespace prt {
namespace {

namespace fs = std::filesystem;

uint64_t bytesUnder(const std::string& dir) {
    uint64_t bytes = 0;
    for (const auto& item : fs::recursive_directory_iterator(dir))
        if (item.is_regular_file()) bytes += item.file_size();
    return bytes;
}

// The ingredients of every entry in the store (hidden writer folders left out).
std::vector<nlohmann::json> entryIngredients(const std::string& store) {
    std::vector<nlohmann::json> result;
    for (const auto& item : fs::directory_iterator(store)) {
        if (item.path().filename().string()[0] == '.') continue;
        result.push_back(nlohmann::json::parse(readFileBytes(item.path().string() + "/manifest.json"))["ingredients"]);
    }
    return result;
}

size_t jobEntries(const std::string& store) {
    size_t count = 0;
    for (const nlohmann::json& ingredients : entryIngredients(store))
        count += ingredients.contains("shard") || ingredients.contains("pass");
    return count;
}

class Gc : public testing::Test {
protected:
    test::TempDir dir;
    void SetUp() override { test::writeSkyExr(dir / "sky.exr", 1.0f); }
    Pipeline pipeline(int samples, const std::string& run) const {
        std::string text = test::interreflectedPipeline(dir.path, samples, 3, dir / ("out-" + run), 2);
        test::writeText(dir / (run + ".toml"), text);
        return parsePipeline(text, dir / (run + ".toml"));
    }
    uint64_t outputBytes(const std::string& run) const { return bytesUnder(dir / ("out-" + run)); }
};

TEST_F(Gc, ASuccessfulShardedRunKeepsNoPassRowsAndRerunsFullyCached) {
    RunOptions options = test::testOptions(dir / "cache");
    nlohmann::json first = test::runQuietly(pipeline(48, "a"), options);
    std::string store = dir / "cache/store";
    // 3 passes of 3 shards, 2 gathers: 11 job entries, all gone; the three stages' entries stay.
    EXPECT_EQ(first["gc"]["removed"], 11);
    EXPECT_EQ(jobEntries(store), 0u);
    EXPECT_EQ(entryIngredients(store).size(), 3u);
    test::expectStoreConsistent(store);

    uint64_t storeBytes = bytesUnder(store), outputs = outputBytes("a");
    std::printf("store %llu bytes, outputs %llu bytes: %.3fx\n", (unsigned long long)storeBytes,
                (unsigned long long)outputs, double(storeBytes) / double(outputs));
    EXPECT_LE(double(storeBytes), 1.5 * double(outputs));
    EXPECT_EQ(first["gc"]["store_bytes"].get<uint64_t>(), storeBytes);

    // Nothing recomputes, whatever was collected; the outputs are the same bytes.
    std::map<std::string, std::string> hashes = test::outputHashes(first);
    fs::remove_all(dir / "out-a");
    nlohmann::json again = test::runQuietly(pipeline(48, "a"), options);
    EXPECT_EQ(test::ranStages(again), std::set<std::string>{});
    EXPECT_EQ(test::outputHashes(again), hashes);
}

TEST_F(Gc, CollectRemovesWhatNoRecordedRunNeedsAndKeepsRunsCached) {
    RunOptions options = test::testOptions(dir / "cache");
    options.keepIntermediates = true;
    test::runQuietly(pipeline(48, "a"), options);
    std::string store = dir / "cache/store";
    EXPECT_EQ(jobEntries(store), 11u);
    // The same pipeline with other samples: its last run no longer needs the 48-sample transfer and relight.
    test::runQuietly(pipeline(32, "a"), options);
    size_t before = entryIngredients(store).size();
    EXPECT_EQ(before, 3u + 11u + 2u + 11u); // the scene is shared

    nlohmann::json dry = collectStore(options, true);
    EXPECT_EQ(dry["removed"].size(), 2u + 22u);
    EXPECT_EQ(entryIngredients(store).size(), before); // a dry run removes nothing

    nlohmann::json done = collectStore(options, false);
    EXPECT_EQ(done["removed"], dry["removed"]);
    EXPECT_EQ(done["kept"], 3);
    EXPECT_EQ(jobEntries(store), 0u);
    test::expectStoreConsistent(store);
    for (const nlohmann::json& ingredients : entryIngredients(store))
        if (ingredients["stage"] == "transfer") {
            EXPECT_EQ(ingredients["params"]["samples"], 32);
        }

    options.keepIntermediates = false;
    EXPECT_EQ(test::ranStages(test::runQuietly(pipeline(32, "a"), options)), std::set<std::string>{});
}

// `prt gc` killed at each of its checkpoints in turn (before and after each entry's removal rename): every time
// the store is consistent, the next collection finishes the work, and the run stays cached.
TEST_F(Gc, KilledCollectorLeavesAConsistentStore) {
    RunOptions options = test::testOptions(dir / "cache");
    options.keepIntermediates = true;
    Pipeline p = pipeline(32, "a");
    std::map<std::string, std::string> hashes = test::outputHashes(test::runQuietly(p, options));
    std::string store = dir / "cache/store";
    std::string gc = test::kPrt + " --quiet gc --cache-dir " + (dir / "cache");
    int killed = 0;
    for (int point = 1; point < 100; ++point) {
        int status = test::shell("PRT_KILL_AT=" + std::to_string(point) + " " + gc);
        test::expectStoreConsistent(store);
        if (status == 0) break;
        ++killed;
    }
    EXPECT_GE(killed, 2); // killed before and after a removal at least
    EXPECT_EQ(test::shell(gc), 0);
    EXPECT_EQ(jobEntries(store), 0u);
    size_t hidden = 0;
    for (const auto& item : fs::directory_iterator(store)) hidden += item.path().filename().string()[0] == '.';
    EXPECT_EQ(hidden, 0u); // the killed collectors' .old- folders are swept
    options.keepIntermediates = false;
    nlohmann::json again = test::runQuietly(p, options);
    EXPECT_EQ(test::ranStages(again), std::set<std::string>{});
    EXPECT_EQ(test::outputHashes(again), hashes);
}

} // namespace
} // namespace prt
