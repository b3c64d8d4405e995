// Cache invalidation: change an input byte, a parameter or a stage's code version, and exactly the affected
// subgraph reruns. Also --plan, --only, --from and --force.
#include "pipeline_test_util.h"

#include <filesystem>
#include <functional>

namespace prt {
namespace {

// Two branches joined at the end:  shape -> prep -> transfer -+-> relight ----+-> compare
//                                  sky ---------------------- +-> relight-sh -+
//                                  sky -> envsh ------------------^
const char* kPipeline = R"(
[inputs]
shape = { mesh = "@DIR@/shape.obj" }
sky = { env = "@DIR@/sky.exr" }

[stages.prep]
run = "meshprep"
inputs = { mesh = "shape" }

[stages.transfer]
run = "transfer"
inputs = { mesh = "prep" }
mode = "shadowed"
order = 3
samples = 16

[stages.envsh]
run = "envsh"
inputs = { env = "sky" }
order = 3

[stages.relight]
run = "relight"
inputs = { bundle = "transfer", env = "sky" }

[stages.relight-sh]
run = "relight"
inputs = { bundle = "transfer", sh = "envsh" }

[stages.compare]
run = "compare"
inputs = { result = "relight-sh", reference = "relight" }

[outputs]
bundle = { from = "transfer", path = "@DIR@/out/bundle.glb" }
metrics = { from = "compare", path = "@DIR@/out/metrics.json" }
)";

using Names = std::set<std::string>;
const Names kAll = {"prep", "transfer", "envsh", "relight", "relight-sh", "compare"};

class Cache : public testing::Test {
protected:
    test::TempDir dir;
    RunOptions options = test::testOptions(dir / "cache");

    void SetUp() override {
        test::writeTwoSpheresObj(dir / "shape.obj");
        test::writeSkyExr(dir / "sky.exr", 1.0f);
    }
    Pipeline pipeline(const std::string& from = "", const std::string& to = "") const {
        std::string text = test::withDir(kPipeline, dir.path);
        if (!from.empty()) text.replace(text.find(from), from.size(), to);
        return parsePipeline(text, dir / "p.toml");
    }
    Names run(const Pipeline& p) { return test::ranStages(test::runQuietly(p, options)); }
};

TEST_F(Cache, RerunsExactlyTheAffectedSubgraph) {
    nlohmann::json first = test::runQuietly(pipeline(), options);
    EXPECT_EQ(test::ranStages(first), kAll);
    std::map<std::string, std::string> outputs = test::outputHashes(first);

    nlohmann::json second = test::runQuietly(pipeline(), options);
    EXPECT_EQ(test::ranStages(second), Names{});
    EXPECT_EQ(second["cache_hits"], 6);
    EXPECT_EQ(test::outputHashes(second), outputs);

    // One byte of the mesh: a coordinate's last digit.
    std::string obj = readFileBytes(dir / "shape.obj");
    size_t digit = obj.find('\n') - 1;
    obj[digit] = obj[digit] == '1' ? '2' : '1';
    test::writeText(dir / "shape.obj", obj);
    EXPECT_EQ(run(pipeline()), (Names{"prep", "transfer", "relight", "relight-sh", "compare"}));

    test::writeSkyExr(dir / "sky.exr", 2.0f);
    EXPECT_EQ(run(pipeline()), (Names{"envsh", "relight", "relight-sh", "compare"}));

    Pipeline moreSamples = pipeline("samples = 16", "samples = 17");
    EXPECT_EQ(run(moreSamples), (Names{"transfer", "relight", "relight-sh", "compare"}));

    // A parameter of a last stage: only it and what it feeds.
    Pipeline turned = pipeline("env = \"sky\" }\n\n[stages.relight-sh]", "env = \"sky\" }\nrotate-y = 30\n\n[stages.relight-sh]");
    EXPECT_EQ(run(turned), (Names{"relight", "compare"}));
    EXPECT_EQ(run(turned), Names{});
    EXPECT_EQ(run(pipeline()), Names{}); // the earlier results are still stored
}

// A damaged store entry (found by a session that damaged the store as a farm's disks and people do): a file cut
// short, overwritten in place at the same size, deleted, or a manifest that is not JSON. The run removes the entry,
// reruns its stage and what it feeds, and gives the first run's outputs; before, a cut file made every later run
// fail ("finished but its entry ... is missing", exit 1) and an overwritten one was copied out as the result.
TEST_F(Cache, ADamagedStoreEntryIsRebuiltAndItsOutputsAreTheFirstRunsAgain) {
    nlohmann::json first = test::runQuietly(pipeline(), options);
    const std::map<std::string, std::string> outputs = test::outputHashes(first);
    const std::string store = options.cacheDir + "/store";
    auto entryOf = [&](const std::string& stage) {
        for (const nlohmann::json& record : first["stages"])
            if (record["id"] == stage) return store + "/" + record["key"].get<std::string>().substr(7);
        return std::string();
    };
    auto fileOf = [&](const std::string& entry) {
        for (const auto& item : std::filesystem::directory_iterator(entry))
            if (item.path().filename() != "manifest.json" && item.path().filename() != "stage.log") return item.path().string();
        return std::string();
    };
    const std::string transfer = entryOf("transfer"), relight = entryOf("relight");
    ASSERT_TRUE(std::filesystem::is_directory(transfer)) << transfer;
    const std::vector<std::pair<std::string, std::function<void()>>> damages = {
        {"cut", [&] { std::filesystem::resize_file(fileOf(relight), std::filesystem::file_size(fileOf(relight)) - 10); }},
        {"overwritten", [&] {
             std::string bytes = readFileBytes(fileOf(transfer));
             bytes[bytes.size() / 2] ^= 0x5a;
             test::writeText(fileOf(transfer), bytes);
         }},
        {"deleted", [&] { std::filesystem::remove(fileOf(relight)); }},
        {"manifest", [&] { test::writeText(transfer + "/manifest.json", "{"); }},
    };
    for (const auto& [name, damage] : damages) {
        SCOPED_TRACE(name);
        damage();
        nlohmann::json again = test::runQuietly(pipeline(), options);
        EXPECT_FALSE(test::ranStages(again).empty());
        EXPECT_EQ(test::outputHashes(again), outputs);
        EXPECT_EQ(run(pipeline()), Names{}); // and stored whole again
    }
}

// A code version bump reruns every stage of that kind. Their outputs come out identical (the code did not
// really change), so the keys downstream, which hash content, stay the same: nothing else reruns.
TEST_F(Cache, VersionBumpRerunsTheStageAndStopsWhereOutputsAgree) {
    run(pipeline());
    Pipeline bumped = pipeline();
    for (PipelineStage& stage : bumped.stages)
        if (stage.spec->name == "relight") stage.version += 1;
    nlohmann::json report = test::runQuietly(bumped, options);
    EXPECT_EQ(test::ranStages(report), (Names{"relight", "relight-sh"}));
    for (const nlohmann::json& stage : report["stages"]) {
        if (stage["stage"] != "relight") continue;
        EXPECT_NE(stage["reason"].get<std::string>().find("code version 2 -> 3"), std::string::npos) << stage["reason"];
    }
    EXPECT_EQ(test::statuses(report)["compare"], "cached");

    Pipeline envshBumped = pipeline();
    envshBumped.stages[findStage(envshBumped, "envsh")].version += 1;
    EXPECT_EQ(run(envshBumped), (Names{"envsh"}));
}

TEST_F(Cache, PlanRunsNothingAndSaysWhy) {
    run(pipeline());
    std::string store = options.cacheDir + "/store";
    size_t entries = std::distance(std::filesystem::directory_iterator(store), std::filesystem::directory_iterator());

    RunOptions plan = options;
    plan.plan = true;
    nlohmann::json report = test::runQuietly(pipeline("samples = 16", "samples = 32"), plan);
    std::map<std::string, nlohmann::json> byId;
    for (const nlohmann::json& stage : report["plan"]) byId[stage["id"]] = stage;
    EXPECT_EQ(byId["prep"]["action"], "cached");
    EXPECT_EQ(byId["envsh"]["action"], "cached");
    EXPECT_EQ(byId["transfer"]["action"], "run");
    EXPECT_EQ(byId["transfer"]["reason"], "parameter samples 16 -> 32");
    EXPECT_EQ(byId["relight"]["action"], "run");
    EXPECT_EQ(byId["relight"]["reason"], "after transfer: reruns if their output changes");
    EXPECT_EQ(byId["relight"]["key"], ""); // unknown until transfer has run
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(store), std::filesystem::directory_iterator()),
              std::ptrdiff_t(entries));
}

TEST_F(Cache, OnlyFromAndForceRerunWhatTheySay) {
    std::map<std::string, std::string> outputs = test::outputHashes(test::runQuietly(pipeline(), options));

    RunOptions only = options;
    only.only = "transfer";
    EXPECT_EQ(run(pipeline()), Names{});
    EXPECT_EQ(test::ranStages(test::runQuietly(pipeline(), only)), Names{"transfer"});

    // --only on a changed stage leaves what it feeds alone: their stored results are stale, not served.
    nlohmann::json changedOnly = test::runQuietly(pipeline("samples = 16", "samples = 24"), only);
    EXPECT_EQ(test::ranStages(changedOnly), Names{"transfer"});
    EXPECT_EQ(test::statuses(changedOnly)["relight"], "not run");
    EXPECT_EQ(test::statuses(changedOnly)["envsh"], "cached");
    EXPECT_FALSE(changedOnly["outputs"].contains("metrics"));

    RunOptions from = options;
    from.from = "transfer";
    EXPECT_EQ(test::ranStages(test::runQuietly(pipeline(), from)), (Names{"transfer", "relight", "relight-sh", "compare"}));

    RunOptions force = options;
    force.force = true;
    nlohmann::json forced = test::runQuietly(pipeline(), force);
    EXPECT_EQ(test::ranStages(forced), kAll);
    EXPECT_EQ(test::outputHashes(forced), outputs); // deterministic stages: same bytes again

    RunOptions missing = test::testOptions(dir / "empty-cache");
    missing.only = "relight";
    try {
        test::runQuietly(pipeline(), missing);
        FAIL() << "--only ran with its inputs missing from the store";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("not in the store"), std::string::npos) << e.what();
    }
}

TEST_F(Cache, FailingStageNamesItselfQuotesItsLogAndLeavesTheStoreConsistent) {
    // A mesh without normals makes `prt transfer` fail: wire the raw OBJ straight in.
    Pipeline broken = parsePipeline(test::withDir(R"(
[inputs]
shape = { mesh = "@DIR@/shape.obj" }
[stages.transfer]
run = "transfer"
inputs = { mesh = "shape" }
[outputs]
bundle = { from = "transfer", path = "@DIR@/out/broken.glb" }
)", dir.path), dir / "broken.toml");
    try {
        test::runQuietly(broken, options);
        FAIL() << "the failing stage went unnoticed";
    } catch (const Error& e) {
        std::string message = e.what();
        EXPECT_NE(message.find("transfer: `prt transfer` exited with status"), std::string::npos) << message;
        EXPECT_NE(message.find("error:"), std::string::npos) << message; // the stage's own message, quoted
        EXPECT_EQ(e.exitCode(), kExitInput);                                 // and its exit code
        EXPECT_TRUE(std::filesystem::exists(e.file())) << "the failed stage's log is kept: " << e.file();
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "out/broken.glb"));
    test::expectStoreConsistent(options.cacheDir + "/store");
}

} // namespace
} // namespace prt

namespace prt {
namespace {

// ---- the key never goes stale: one test per ingredient the issue named ----
// The transfer stage of kPipeline, with what `prt run` fills in from the real prt binary.
struct ResolvedStage {
    PipelineStage stage;
    std::map<std::string, std::string> hashes = {{"mesh", "xxh128:0"}};
    ResolvedStage() {
        Pipeline p = parsePipeline(test::withDir(kPipeline, "/nowhere"), "p.toml");
        test::TempDir cache;
        resolveStageOptions(p, test::testOptions(cache.path));
        stage = p.stages[findStage(p, "transfer")];
    }
    std::string key(const PipelineStage& s) const { return keyOf(keyIngredients(s, hashes)); }
};

TEST(KeyIngredients, ResolvedOptionsHoldTheDefaultsAndAChangedDefaultChangesTheKey) {
    ResolvedStage r;
    // `bounces` and `seed` are not in the TOML: their defaults are in the key all the same.
    ASSERT_TRUE(r.stage.resolved.is_object());
    EXPECT_EQ(r.stage.resolved["--samples"], nlohmann::json({"16"}));
    EXPECT_EQ(r.stage.resolved["--seed"], "0");
    PipelineStage changedDefault = r.stage;
    changedDefault.resolved["--seed"] = "1"; // what a new default would print
    EXPECT_NE(r.key(r.stage), r.key(changedDefault));
    EXPECT_EQ(r.key(r.stage), r.key(ResolvedStage().stage)); // and the same prt says the same
}

TEST(KeyIngredients, PrtVersionIsInTheKey) {
    ResolvedStage r;
    EXPECT_FALSE(r.stage.build.value("prt", "").empty());
    PipelineStage other = r.stage;
    other.build["prt"] = "99.0.0";
    EXPECT_NE(r.key(r.stage), r.key(other));
}

TEST(KeyIngredients, BuildIdentityIsTheExecutableContentAndIsInTheKey) {
    ResolvedStage r;
    // `prt` is a launcher that execs prt-driver, which holds every stage's code: the driver is what is hashed.
    EXPECT_EQ(r.stage.build["executable"], hashFile(std::string(PRT_BINARY_DIR) + "/prt-driver"));
    EXPECT_FALSE(r.stage.build.value("compiler", "").empty());
    PipelineStage rebuilt = r.stage;
    rebuilt.build["executable"] = "xxh128:00000000000000000000000000000000";
    EXPECT_NE(r.key(r.stage), r.key(rebuilt));
    PipelineStage otherType = r.stage;
    otherType.build["build_type"] = "Debug";
    EXPECT_NE(r.key(r.stage), r.key(otherType));
}

TEST(KeyIngredients, LibraryVersionsAreInTheKey) {
    ResolvedStage r;
    const nlohmann::json& libraries = r.stage.build["libraries"];
    EXPECT_EQ(libraries["compiled"]["embree"], "3.13.5");
    bool embreeLoaded = false;
    for (const nlohmann::json& name : libraries["loaded"]) embreeLoaded = embreeLoaded || name.get<std::string>().find("libembree3.so") == 0;
    EXPECT_TRUE(embreeLoaded) << libraries.dump();
    PipelineStage upgraded = r.stage;
    upgraded.build["libraries"]["compiled"]["openimageio"] = "9.9.9";
    EXPECT_NE(r.key(r.stage), r.key(upgraded));
    PipelineStage relinked = r.stage;
    relinked.build["libraries"]["loaded"].push_back("libm.so.7 1 bytes");
    EXPECT_NE(r.key(r.stage), r.key(relinked));
}

// The store's manifests record the new ingredients, so a person can see why a key changed.
TEST_F(Cache, ManifestsRecordResolvedOptionsAndBuild) {
    nlohmann::json report = test::runQuietly(pipeline(), options);
    for (const nlohmann::json& stage : report["stages"]) {
        std::string key = stage["key"];
        nlohmann::json manifest = nlohmann::json::parse(readFileBytes(options.cacheDir + "/store/" + key.substr(7) + "/manifest.json"));
        EXPECT_TRUE(manifest["ingredients"].contains("resolved")) << stage["id"];
        EXPECT_TRUE(manifest["ingredients"].contains("build")) << stage["id"];
    }
}

} // namespace
} // namespace prt
