// The Slurm executor on a real single-node Slurm that the test starts (scripts/slurm_local.sh: munge, slurmctld
// and slurmd with private ports and folders) and stops. Starting daemons needs root: without it the tests skip,
// saying so loudly. CI runs as root, so there they run.
#include "pipeline_test_util.h"

#include <unistd.h>

namespace prt {
namespace {

const std::string kScript = PRT_SOURCE_DIR "/scripts/slurm_local.sh";

class Slurm : public testing::Test {
protected:
    static inline test::TempDir* daemons = nullptr;
    static inline std::string startLog;

    static void SetUpTestSuite() {
        if (geteuid() != 0) return;
        daemons = new test::TempDir;
        std::string conf;
        if (test::shell(kScript + " start " + daemons->path, &conf) != 0) {
            startLog = conf;
            return;
        }
        conf.erase(conf.find_last_not_of("\n") + 1);
        setenv("SLURM_CONF", conf.substr(conf.rfind('\n') + 1).c_str(), 1);
    }
    static void TearDownTestSuite() {
        if (!daemons) return;
        test::shell(kScript + " stop " + daemons->path);
        delete daemons;
        daemons = nullptr;
        unsetenv("SLURM_CONF");
    }
    void SetUp() override {
        if (geteuid() != 0) {
            std::fprintf(stderr, "\n*** SKIPPED: the Slurm executor test starts munge and Slurm daemons, which needs "
                                 "root. Run the test suite as root (CI does) to run it. ***\n\n");
            GTEST_SKIP() << "not root: cannot start a private Slurm";
        }
        ASSERT_NE(getenv("SLURM_CONF"), nullptr) << "the private Slurm did not start:\n" << startLog;
        test::writeSkyExr(dir / "sky.exr", 1.0f);
    }

    test::TempDir dir;
    // The two-spheres pipeline in two shards, writing into DIR/out-RUN.
    std::string pipelineText(const std::string& run) const {
        return test::twoSpheresPipeline(dir.path, 64, 2, dir / ("out-" + run));
    }
    Pipeline pipeline(const std::string& run) const { return parsePipeline(pipelineText(run), dir / (run + ".toml")); }
    RunOptions slurm(const std::string& cache) const {
        RunOptions options = test::testOptions(cache);
        options.executor = Executor::Slurm;
        options.slurmPollSeconds = 0.2;
        return options;
    }
};

TEST_F(Slurm, ShardedPipelineMatchesTheLocalRunBitForBit) {
    Pipeline local = pipeline("local");
    std::string file = dir / "farm.toml";
    test::writeText(file, pipelineText("farm"));
    Pipeline farm = loadPipeline(file); // jobs reread the file, so it must exist
    nlohmann::json localReport = test::runQuietly(local, test::testOptions(dir / "local-cache"));
    nlohmann::json farmReport = test::runQuietly(farm, slurm(dir / "farm-cache"));

    EXPECT_EQ(farmReport["executor"], "slurm");
    EXPECT_EQ(test::ranStages(farmReport), (std::set<std::string>{"ball", "transfer", "relight"}));
    EXPECT_EQ(test::outputHashes(farmReport), test::outputHashes(localReport));
    const nlohmann::json& transfer = farmReport["stages"][1];
    ASSERT_EQ(transfer["shard_jobs"].size(), 3u); // a job array of two, then the merge job
    std::string array = transfer["shard_jobs"][0]["slurm_job"];
    EXPECT_EQ(array.substr(array.find('_')), "_0");
    EXPECT_EQ(transfer["shard_jobs"][1]["slurm_job"], array.substr(0, array.find('_')) + "_1");

    // Everything is cached now: no job is submitted.
    nlohmann::json again = test::runQuietly(farm, slurm(dir / "farm-cache"));
    EXPECT_EQ(test::ranStages(again), std::set<std::string>{});
    EXPECT_EQ(again["cache_hits"], 3);
}

// Interreflected bounces: each pass a job array after the previous pass's gather job; the same bytes as locally.
TEST_F(Slurm, InterreflectedPassesRunAsDependentJobArrays) {
    std::string file = dir / "passes.toml";
    test::writeText(file, test::interreflectedPipeline(dir.path, 48, 2, dir / "out-passes", 2));
    Pipeline farm = loadPipeline(file);
    nlohmann::json local = test::runQuietly(
        parsePipeline(test::interreflectedPipeline(dir.path, 48, 1, dir / "out-whole", 2), dir / "whole.toml"),
        test::testOptions(dir / "local-cache"));
    nlohmann::json report = test::runQuietly(farm, slurm(dir / "farm-cache"));
    EXPECT_EQ(test::outputHashes(report), test::outputHashes(local));
    const nlohmann::json& jobs = report["stages"][1]["shard_jobs"];
    ASSERT_EQ(jobs.size(), 9u); // 3 passes of 2 shards, 2 gathers, the merge
    std::set<std::string> arrays;
    for (const nlohmann::json& job : jobs)
        if (job["shard"].is_array()) arrays.insert(job["slurm_job"].get<std::string>().substr(0, job["slurm_job"].get<std::string>().find('_')));
    EXPECT_EQ(arrays.size(), 3u); // one array per pass
    EXPECT_EQ(jobs[2]["shard"], "gather");
    EXPECT_EQ(jobs[8]["shard"], "merge");
}

TEST_F(Slurm, FailingJobFailsTheRunWithItsLog) {
    // `prt transfer` cannot read an OBJ: its job fails, and the relight job that waits on it never runs.
    test::writeTwoSpheresObj(dir / "shape.obj");
    std::string file = dir / "broken.toml";
    test::writeText(file, test::withDir(R"(
[inputs]
shape = { mesh = "@DIR@/shape.obj" }
sky = { env = "@DIR@/sky.exr" }
[stages.transfer]
run = "transfer"
inputs = { mesh = "shape" }
[stages.relight]
run = "relight"
inputs = { bundle = "transfer", env = "sky" }
[outputs]
radiance = { from = "relight", path = "@DIR@/out-broken/radiance.npy" }
)", dir.path));
    try {
        test::runQuietly(loadPipeline(file), slurm(dir / "cache"));
        FAIL() << "the failed job went unnoticed";
    } catch (const Error& e) {
        std::string message = e.what();
        EXPECT_NE(message.find("(transfer): FAILED"), std::string::npos) << message;
        EXPECT_NE(message.find("`prt transfer` exited with status"), std::string::npos) << message; // from its log
        EXPECT_TRUE(std::filesystem::is_regular_file(e.file())) << "the job's log: " << e.file();
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "out-broken/radiance.npy"));
    test::expectStoreConsistent(dir / "cache/store");
}

} // namespace
} // namespace prt
