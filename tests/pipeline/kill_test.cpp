// SIGKILL at any point leaves the store consistent, and the next run redoes only what was cut short, ending
// with outputs identical to an uninterrupted run.
#include "pipeline_test_util.h"

#include <chrono>
#include <csignal>
#include <fcntl.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace prt {
namespace {

namespace fs = std::filesystem;

// `prt run` in a process group of its own, so that one kill takes it and its stage.
pid_t spawnRun(const std::string& pipeline, const std::string& cache, const std::string& log,
               const std::map<std::string, std::string>& environment = {}) {
    pid_t pid = fork();
    if (pid == 0) {
        setpgid(0, 0);
        for (const auto& [name, value] : environment) setenv(name.c_str(), value.c_str(), 1);
        int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(fd, 1);
        dup2(fd, 2);
        execl(test::kPrt.c_str(), "prt", "run", pipeline.c_str(), "--cache-dir", cache.c_str(), "--threads", "2",
              (char*)nullptr);
        _exit(127);
    }
    setpgid(pid, pid);
    return pid;
}

// Polls `ready` every millisecond while `pid` runs; true once it holds, false if the process ended first.
template <class Ready>
bool waitWhileRunning(pid_t pid, Ready ready) {
    for (;;) {
        if (ready()) return true;
        if (waitpid(pid, nullptr, WNOHANG) == pid) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
}

// True while a temporary store entry of the transfer stage (the one that links an input mesh) exists.
bool transferRunning(const std::string& store) {
    std::error_code error;
    for (const auto& item : fs::directory_iterator(store, error))
        if (item.path().filename().string().rfind(".tmp-", 0) == 0 && fs::is_symlink(item.path() / "input-mesh.glb", error))
            return true;
    return false;
}

size_t entryCount(const std::string& store) {
    size_t count = 0;
    std::error_code error;
    for (const auto& item : fs::directory_iterator(store, error)) count += item.path().filename().string()[0] != '.';
    return count;
}

int waitStatus(pid_t pid) {
    int status = 0;
    waitpid(pid, &status, 0);
    return status;
}

class Kill : public testing::Test {
protected:
    test::TempDir dir;
    std::map<std::string, std::string> expected; // output hashes of an uninterrupted run

    void SetUp() override {
        test::writeSkyExr(dir / "sky.exr", 1.0f);
        expected = test::outputHashes(test::runQuietly(pipeline("reference"), test::testOptions(dir / "reference-cache")));
    }
    // The pipeline writing its outputs to DIR/out-NAME, also as a file for `prt run`.
    Pipeline pipeline(const std::string& name) const {
        // Slow enough to be caught in the middle: the transfer casts a few million rays.
        std::string text = test::twoSpheresPipeline(dir.path, name == "hooked" ? 64 : 1024, 1, dir / ("out-" + name));
        test::writeText(dir / (name + ".toml"), text);
        return parsePipeline(text, dir / (name + ".toml"));
    }
    void expectResumesToTheSameOutputs(const Pipeline& p, const std::string& cache) {
        test::expectStoreConsistent(cache + "/store");
        nlohmann::json report = test::runQuietly(p, test::testOptions(cache));
        EXPECT_EQ(test::outputHashes(report), expected);
        test::expectStoreConsistent(cache + "/store");
    }
};

TEST_F(Kill, WholeRunKilledDuringAStageResumesWithOnlyThatStageAndAfter) {
    Pipeline p = pipeline("mid-stage");
    std::string cache = dir / "cache";
    pid_t pid = spawnRun(p.file, cache, dir / "run.log");
    ASSERT_TRUE(waitWhileRunning(pid, [&] { return transferRunning(cache + "/store"); })) << readFileBytes(dir / "run.log");
    kill(-pid, SIGKILL);
    EXPECT_TRUE(WIFSIGNALED(waitStatus(pid)));

    test::expectStoreConsistent(cache + "/store");
    EXPECT_EQ(entryCount(cache + "/store"), 1u); // the scene only
    EXPECT_FALSE(fs::exists(dir / "out-mid-stage/bundle.glb"));

    nlohmann::json report = test::runQuietly(p, test::testOptions(cache));
    EXPECT_EQ(test::statuses(report), (std::map<std::string, std::string>{{"ball", "cached"}, {"transfer", "ran"}, {"relight", "ran"}}));
    EXPECT_EQ(test::outputHashes(report), expected);
    for (const auto& item : fs::directory_iterator(cache + "/store"))
        EXPECT_NE(item.path().filename().string()[0], '.') << "the dead run's temporary entry was swept: " << item.path();
}

// Kill anywhere, by the hook (core.h, checkpoint) rather than by sleeping: a clean run counts the checkpoints that
// `prt run` and its stages pass together (PRT_KILL_COUNTER); then runs die by SIGKILL at points spread over all
// of them (renames, store commits, command starts, progress steps; the stage or `prt run` itself, whichever
// reaches it), and each resumes to outputs bit-identical to the uninterrupted run's.
TEST_F(Kill, KilledAtEveryKindOfCheckpointTheStoreStaysConsistentAndResumes) {
    Pipeline p = pipeline("hooked");
    std::string counter = dir / "clean.count";
    {
        std::string cache = dir / "cache-clean";
        pid_t pid = spawnRun(p.file, cache, dir / "clean.log", {{"PRT_KILL_COUNTER", counter}});
        int status = waitStatus(pid);
        ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << readFileBytes(dir / "clean.log");
        expected = test::outputHashes(test::runQuietly(p, test::testOptions(cache))); // all cached: the clean outputs
    }
    const long total = long(fs::file_size(counter));
    ASSERT_GT(total, 10);
    // The first points (the run's own start, the first stage's start), then spread to the last renames (the
    // outputs copied out of the store). Counts vary by a few between runs (`prt run`'s own progress lines follow
    // its stages' timing), so a late point may lie past a run's end.
    std::vector<long> points = {1, 2, 3};
    for (int k = 1; k <= 6; ++k) points.push_back(std::max(4L, (total - 2) * k / 6));
    std::printf("kill test: %ld checkpoints in a clean run; killing at", total);
    for (long point : points) std::printf(" %ld", point);
    std::printf("\n");
    size_t killed = 0;
    for (long point : points) {
        std::string name = "at-" + std::to_string(point);
        SCOPED_TRACE(name);
        std::string cache = dir / ("cache-" + name);
        pid_t pid = spawnRun(p.file, cache, dir / (name + ".log"),
                             {{"PRT_KILL_AT", std::to_string(point)}, {"PRT_KILL_COUNTER", dir / (name + ".count")}});
        int status = waitStatus(pid);
        killed += !(WIFEXITED(status) && WEXITSTATUS(status) == 0);
        // What was copied out is whole or absent: a bundle there reads.
        if (fs::exists(dir / "out-hooked/bundle.glb")) {
            EXPECT_NO_THROW(readBundle(dir / "out-hooked/bundle.glb"));
        }
        expectResumesToTheSameOutputs(p, cache);
    }
    EXPECT_GE(killed + 1, points.size()) << "runs were not killed where the clean run's count says";
}

// The stage alone dies: the run fails naming it, keeps what finished, and the next run redoes only the stage.
TEST_F(Kill, StageKilledAloneFailsTheRunAndResumes) {
    Pipeline p = pipeline("stage-only");
    std::string cache = dir / "cache";
    pid_t pid = spawnRun(p.file, cache, dir / "run.log");
    pid_t stage = 0;
    auto findStage = [&] {
        if (!transferRunning(cache + "/store")) return false;
        for (const auto& item : fs::directory_iterator("/proc")) {
            std::string stat;
            try {
                stat = readFileBytes(item.path().string() + "/stat");
            } catch (const Error&) {
                continue;
            }
            // pid (comm) state ppid ...
            size_t close = stat.rfind(')');
            if (close == std::string::npos || std::atoi(stat.c_str() + close + 4) != pid) continue;
            stage = std::atoi(stat.c_str());
            return true;
        }
        return false;
    };
    ASSERT_TRUE(waitWhileRunning(pid, findStage)) << readFileBytes(dir / "run.log");
    kill(stage, SIGKILL);
    int status = waitStatus(pid);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), kExitInterrupted);
    std::string log = readFileBytes(dir / "run.log");
    EXPECT_NE(log.find("was killed by signal 9"), std::string::npos) << log;
    test::expectStoreConsistent(cache + "/store");

    nlohmann::json report = test::runQuietly(p, test::testOptions(cache));
    EXPECT_EQ(test::statuses(report)["ball"], "cached");
    EXPECT_EQ(test::statuses(report)["transfer"], "ran");
    EXPECT_EQ(test::outputHashes(report), expected);
}

} // namespace
} // namespace prt
